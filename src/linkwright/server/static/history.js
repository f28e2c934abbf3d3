/* linkwright workbench: undo and redo of every edit, and the work kept across a reload.
 *
 * A step is a document the server accepted. Every edit (a typed value, a drag, a family or an
 * example, an assembly mode, a tool's result) reaches the page through the scene pipeline, so
 * the history watches that one place and no edit can slip past it. A drag is one step: the
 * scenes drawn while a joint is held are not steps, the document at its end is. Undo and redo
 * send a step's document back through the same pipeline.
 *
 * The work in progress (document, view, input angle) is kept in localStorage after every step
 * and when the page is left, so a reload finds it (share.js decides what a fresh page opens).
 * Leaving asks first only while the document differs from the one last loaded or saved. */

import { $, clone, finite } from "./util.js";
import { requestScene, state, status } from "./pipeline.js";
import { fieldIsBeingEdited, labelOf } from "./fields.js";
import { captureSession } from "./share.js";
import { restoreSketch } from "./builder.js";

// Enough for an afternoon of edits; a document is a few hundred bytes to a few kilobytes, but
// may be up to the server's 2 MB, so the steps' total size is bounded too.
const MOST_STEPS = 200;
const MOST_STEP_CHARS = 20_000_000;
const WORK_KEY = "linkwright.workbench.work";

const undoSteps = []; // {doc, key, exampleName, at, family, label}, oldest first
let undoIndex = -1; // the step on screen
let restoreCount = 0; // undo or redo requests not yet answered
let baselineKey = null; // the document last loaded or saved
let storageRefused = false;
let saveAtTimer = null;

/** A document's identity: its JSON with the keys of every object sorted. */
export function docKey(doc) {
  return JSON.stringify(doc, (_k, v) =>
    v && typeof v === "object" && !Array.isArray(v)
      ? Object.fromEntries(Object.keys(v).sort().map((n) => [n, v[n]]))
      : v,
  );
}

function flatten(x, prefix, out) {
  if (x && typeof x === "object") {
    for (const [k, v] of Object.entries(x)) flatten(v, prefix ? `${prefix}.${k}` : k, out);
  } else out.set(prefix, x);
  return out;
}

/** The identity of what is on screen: the document, and the sketch while one is being built
 * (a sketch that does not compile yet leaves the last document that did). */
export function sessionKey() {
  return keyOf(state.doc, state.sketch);
}

export function keyOf(doc, sketch) {
  const d = doc ? docKey(doc) : "";
  return sketch ? `${d}\u0000${docKey(sketch)}` : d;
}

/** What changed from one step to the next, in the fields' words ("crank", "point u, point v"). */
function changeLabel(prev, next) {
  if (prev.sketchKey !== next.sketchKey) {
    if (!next.sketch) return "leaving the builder";
    return `building: ${next.sketchLabel || "an edit"}`;
  }
  const fam = (s) => s.doc && s.doc.mechanism && s.doc.mechanism.family;
  if (fam(prev) !== fam(next) || prev.exampleName !== next.exampleName) {
    const title = next.doc.title || next.exampleName || fam(next) || "mechanism";
    return next.exampleName ? `example “${title}”` : `“${title}”`;
  }
  const a = flatten(prev.doc, "", new Map());
  const b = flatten(next.doc, "", new Map());
  const names = new Set();
  for (const k of new Set([...a.keys(), ...b.keys()])) {
    if (a.get(k) === b.get(k)) continue;
    names.add(k.startsWith("mechanism.") ? labelOf(k) : k);
  }
  if (!names.size) return "change";
  return names.size <= 2 ? [...names].join(", ") : `${names.size} values`;
}

/** Record the document on screen as a step if it differs from the current one. */
export function checkpoint() {
  const doc = state.doc;
  if (!doc || restoreCount) return;
  const key = sessionKey();
  const head = undoSteps[undoIndex];
  if (head && head.key === key) {
    head.exampleName = state.exampleName;
    return;
  }
  const step = {
    doc: clone(doc),
    key,
    exampleName: state.exampleName,
    at: state.at,
    family: state.scene ? state.scene.family : null,
    label: "",
    sketch: state.sketch ? clone(state.sketch) : null,
    sketchKey: state.sketch ? docKey(state.sketch) : null,
    sketchLabel: state.sketchLabel || "",
  };
  if (head) step.label = changeLabel(head, step);
  undoSteps.splice(undoIndex + 1);
  undoSteps.push(step);
  if (undoSteps.length > MOST_STEPS) undoSteps.splice(0, undoSteps.length - MOST_STEPS);
  let chars = undoSteps.reduce((n, s) => n + s.key.length, 0);
  while (undoSteps.length > 1 && chars > MOST_STEP_CHARS) chars -= undoSteps.shift().key.length;
  undoIndex = undoSteps.length - 1;
  // the page's first document is the one it loaded
  if (baselineKey === null) baselineKey = key;
  refreshButtons();
  saveWork();
}

function onScene() {
  const pipe = state.dragPipe;
  const jointHeld =
    (state.gesture && state.gesture.kind === "joint") || (pipe && (pipe.busy || !pipe.ended));
  if (jointHeld || restoreCount) return;
  checkpoint();
}

async function goToStep(i, verb) {
  if (i < 0 || i >= undoSteps.length || i === undoIndex) return;
  const from = undoSteps[undoIndex];
  const to = undoSteps[i];
  undoIndex = i;
  restoreCount += 1;
  refreshButtons();
  // another family's input angle means nothing here: go back to the one that step had
  const other = !state.scene || state.scene.family !== to.family;
  const at = other && finite(to.at) ? to.at : state.at;
  let sc = null;
  // the sketch first: the scene's listeners then see the step whole
  if (from.sketchKey !== to.sketchKey) restoreSketch(to.sketch);
  try {
    sc = await requestScene(clone(to.doc), at, { exampleName: to.exampleName });
  } finally {
    restoreCount -= 1;
  }
  if (restoreCount) return; // a later undo or redo is on its way and will settle the history
  const key = state.doc ? sessionKey() : null;
  if (key !== undoSteps[undoIndex].key) {
    // refused (the status line says why): the history follows what is on screen
    const j = undoSteps.findIndex((s) => s.key === key);
    if (j >= 0) undoIndex = j;
    else checkpoint();
  } else if (sc) {
    status(`${verb}: ${(verb === "Undone" ? from : to).label || "change"}`, "info");
  }
  refreshButtons();
  saveWork();
}

export function undoStep() {
  goToStep(undoIndex - 1, "Undone");
}
export function redoStep() {
  goToStep(undoIndex + 1, "Redone");
}

/** The history's size and whether the document differs from the one last loaded or saved. */
export function historyInfo() {
  const back = Math.max(0, undoIndex);
  return { undo: back, redo: Math.max(0, undoSteps.length - 1 - undoIndex), dirty: isDirty() };
}

export function isDirty() {
  return !!state.doc && baselineKey !== null && sessionKey() !== baselineKey;
}

/** The document on screen was just loaded (an example, a family, a link) or saved. */
export function markLoaded() {
  if (state.doc) baselineKey = sessionKey();
  saveWork();
}

/** The document last loaded or saved, as kept with the work of an earlier visit. */
export function setBaseline(key) {
  baselineKey = typeof key === "string" ? key : null;
  saveWork();
}

function refreshButtons() {
  const undo = $("undo");
  const redo = $("redo");
  if (!undo || !redo) return;
  const back = undoIndex > 0 ? undoSteps[undoIndex] : null;
  const fwd = undoIndex < undoSteps.length - 1 ? undoSteps[undoIndex + 1] : null;
  undo.disabled = !back;
  redo.disabled = !fwd;
  undo.title = back ? `Undo ${back.label || "the last change"} (Ctrl+Z)` : "Nothing to undo";
  redo.title = fwd ? `Redo ${fwd.label || "the change"} (Ctrl+Shift+Z or Ctrl+Y)` : "Nothing to redo";
  document.body.dataset.undo = String(Math.max(0, undoIndex));
  document.body.dataset.redo = String(Math.max(0, undoSteps.length - 1 - undoIndex));
}

// ------------------------------------------------------------------ the work kept for a reload
export function saveWork() {
  if (!state.doc) return;
  const work = { v: 1, session: captureSession(), baseline: baselineKey };
  try {
    localStorage.setItem(WORK_KEY, JSON.stringify(work));
  } catch (e) {
    if (!storageRefused) {
      storageRefused = true;
      status(`This browser keeps no work for a reload (${e.name || "storage refused"})`, "error");
    }
  }
}

/** The work kept by an earlier visit, or null. */
export function readWork() {
  let work = null;
  try {
    work = JSON.parse(localStorage.getItem(WORK_KEY) || "null");
  } catch (e) {
    return null;
  }
  const ok =
    work && work.v === 1 && work.session && typeof work.session === "object" &&
    work.session.d && typeof work.session.d === "object";
  return ok ? work : null;
}

/** A button beside the status line's message, gone with the next message. */
export function offerAction(text, fn) {
  const b = $("status-action");
  if (!b) return;
  b.textContent = text;
  b.hidden = false;
  b.onclick = () => {
    b.hidden = true;
    fn();
  };
}

// ------------------------------------------------------------------ keys and buttons
/** Whether Ctrl+Z in this element belongs to the browser's own undo of text being typed. */
function browserUndo(t) {
  if (!t) return false;
  if (t.isContentEditable || t.tagName === "TEXTAREA") return true;
  if (t.tagName !== "INPUT" || !/^(text|search|number|email|url|tel|password)$/.test(t.type)) return false;
  if (t.dataset.path) return fieldIsBeingEdited(t);
  if (t.id === "doc-title") {
    const head = undoSteps[undoIndex];
    return t.value.trim() !== ((head && head.doc.title) || "");
  }
  return true; // the tools' own text boxes
}

function onKeyDown(e) {
  if (!(e.ctrlKey || e.metaKey) || e.altKey) return;
  const k = (e.key || "").toLowerCase();
  const undo = k === "z" && !e.shiftKey;
  const redo = (k === "z" && e.shiftKey) || (k === "y" && !e.shiftKey);
  if ((!undo && !redo) || browserUndo(e.target)) return;
  e.preventDefault();
  if (undo) undoStep();
  else redoStep();
}

export function initHistory() {
  state.listeners.scene.push(onScene);
  state.listeners.at.push(() => {
    // the input angle changes many times a second while playing: keep it now and then
    if (saveAtTimer === null) saveAtTimer = setTimeout(() => {
      saveAtTimer = null;
      saveWork();
    }, 500);
  });
  document.addEventListener("keydown", onKeyDown);
  for (const [id, fn] of [["undo", undoStep], ["redo", redoStep]]) {
    const b = $(id);
    // keep the focus where it is: a click must not apply a half-typed field first
    b.addEventListener("mousedown", (e) => e.preventDefault());
    b.addEventListener("click", fn);
  }
  // a title is one step once typed (Enter or leaving the box), not one per keystroke
  $("doc-title").addEventListener("change", () => checkpoint());
  window.addEventListener("pagehide", saveWork);
  document.addEventListener("visibilitychange", () => {
    if (document.visibilityState === "hidden") saveWork();
  });
  window.addEventListener("beforeunload", (e) => {
    saveWork();
    if (isDirty()) {
      e.preventDefault();
      e.returnValue = "";
    }
  });
  refreshButtons();
}

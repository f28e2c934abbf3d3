/* linkwright workbench: the rule by which a typed parameter is applied, and the plain words of
 * an error.
 *
 * A typed value is applied when the person is done with it (Enter, or leaving the field), never
 * per keystroke: on the way to "1e12" the field holds "1e1", and drawing that would show a
 * linkage the field does not. A value that does not parse, an emptied field, or a value the
 * server refuses leaves the last valid document on screen and the field marked, with a message
 * that names the field by its label. The server speaks in document paths
 * (`document: mechanism.B0[0]: ...`); the field table that turns a path into a label lives
 * here, in the page, where the fields are. */

import { $, clone, fmtInput, getPath, setPath } from "./util.js";
import { requestScene, state, status } from "./pipeline.js";
import { markField } from "./panels.js";

// A decimal number as people write it: no hex, no "Infinity", no thousands separators.
const DECIMAL = /^[+-]?(?:\d+\.?\d*|\.\d+)(?:e[+-]?\d+)?$/i;
// The document's own keys a server message may begin with, beside paths under `mechanism`.
const TOP_KEYS = ["title", "units", "format", "mechanism"];
// A path as the server writes it: `mechanism.B0[0]`, `mechanism.joints[3].r1`, `mechanism.crank`.
const PATH_IN_TEXT = /\bmechanism((?:\.[A-Za-z_]\w*|\.\d+|\[\d+\])+)/g;

/** The number a person typed, or null when the text is not one. */
export function parseDecimal(text) {
  const t = String(text).trim().replace(/^\u2212/, "-");
  if (!DECIMAL.test(t)) return null;
  const v = Number(t);
  return Number.isFinite(v) ? v : null;
}

function quoted(text) {
  const t = String(text).trim();
  return `“${t.length > 24 ? `${t.slice(0, 23)}…` : t}”`;
}

/** The field's input on the page, if it is shown. */
export function fieldInput(path) {
  if (!path) return null;
  return $("fields").querySelector(`[data-path="${CSS.escape(path)}"]`);
}

/** Whether a parameter field holds text the person has typed and not yet applied (then
 * Ctrl+Z belongs to the browser's own undo of that text). */
export function fieldIsBeingEdited(el) {
  return !!el && el.tagName === "INPUT" && el.value !== (el.dataset.applied ?? el.value);
}

function refuse(input, f, message) {
  markField(f.path, message);
  status(message, "error");
  // The next scene that is drawn says "Ready" again.
  state.pipelineError = true;
  input.dataset.applied = fmtInput(getPath(state.doc, f.path));
}

/** Apply what a field holds, if it parses and differs from the document's value; the server
 * then judges it (pipeline.js reports a refusal through explainError). */
export function applyField(input, f) {
  const base = state.latestRequested || state.doc;
  if (!base) return;
  let value;
  if (input.tagName === "SELECT") value = JSON.parse(input.value);
  else {
    const text = input.value.trim();
    const now = getPath(state.doc, f.path);
    if (text === "") {
      refuse(input, f, `${f.label}: empty; type a number (Esc puts back ${fmtInput(now)})`);
      return;
    }
    value = parseDecimal(text);
    if (value === null) {
      const comma = /^[+-]?\d*,\d+$/.test(text) ? ` (write ${text.replace(",", ".")})` : "";
      refuse(input, f, `${f.label}: ${quoted(text)} is not a number${comma}`);
      return;
    }
    input.dataset.applied = input.value;
  }
  if (value === getPath(base, f.path)) {
    // Typed back to the value in force: nothing to send, nothing wrong any more.
    if (input.classList.contains("invalid")) {
      markField(null);
      if (state.pipelineError && !state.latestRequested) {
        state.pipelineError = false;
        status("Ready", "info");
      }
    }
    return;
  }
  const doc = clone(base);
  setPath(doc, f.path, value);
  requestScene(doc, state.at, { fieldPath: f.path });
}

/** Put back the document's value (Esc). */
function revertField(input, f) {
  const v = getPath(state.doc, f.path);
  input.value = input.tagName === "SELECT" ? JSON.stringify(v) : fmtInput(v);
  input.dataset.applied = input.value;
  if (input.classList.contains("invalid")) markField(null);
}

/** Wire one parameter field: Enter or leaving it applies, Esc puts the value back; a chooser
 * applies on change. */
export function wireField(input, f) {
  input.addEventListener("change", () => applyField(input, f));
  if (input.tagName === "SELECT") return;
  input.addEventListener("keydown", (e) => {
    if (e.key === "Enter") {
      e.preventDefault();
      applyField(input, f);
    } else if (e.key === "Escape") {
      e.preventDefault();
      revertField(input, f);
    }
  });
}

/** A refused field stays "being edited" with the text it holds, so a scene drawn meanwhile does
 * not overwrite the text that is being corrected. */
export function fieldRefused(path) {
  const el = fieldInput(path);
  if (el && el.tagName === "INPUT") el.dataset.applied = fmtInput(getPath(state.doc, path));
}

// ------------------------------------------------------------------ server paths in plain words
function normalPath(path) {
  return String(path).replace(/\[(\d+)\]/g, ".$1");
}

/** The label a person knows a document path by: a field's own label, the common start of the
 * labels under it (`mechanism.B0` → "B0"), a joint's name, else the path without
 * `mechanism.`. */
export function labelOf(path) {
  const p = normalPath(path);
  const fields = (state.scene && state.scene.fields) || [];
  const exact = fields.find((f) => f.path === p);
  if (exact) return exact.label;
  const tail = p.replace(/^mechanism\./, "");
  const joint = /^joints\.(\d+)(.*)$/.exec(tail);
  if (joint) {
    const j = getPath(state.doc, `mechanism.joints.${joint[1]}`);
    const name = j && typeof j.name === "string" ? j.name : `joint ${Number(joint[1]) + 1}`;
    return `${name}${joint[2].split(".").join(" ")}`.trim();
  }
  const under = fields.filter((f) => f.path.startsWith(`${p}.`)).map((f) => f.label.split(" "));
  if (under.length > 1) {
    const common = [];
    for (let k = 0; under.every((w) => w.length > k + 1 && w[k] === under[0][k]); k++) {
      common.push(under[0][k]);
    }
    if (common.length) return common.join(" ");
  }
  return p === "mechanism" ? "mechanism" : tail.split(".").join(" ");
}

function plainPaths(text) {
  return text.replace(PATH_IN_TEXT, (whole) => labelOf(whole));
}

/** A server's error in the page's words. With `fieldPath` (the field whose value was sent) the
 * message starts with that field's label, and says the value was not applied when the server
 * objected to something else the value made wrong. */
export function explainError(message, fieldPath = null, doc = null) {
  const text = String(message == null ? "" : message).replace(/^document: /, "");
  const m = /^([A-Za-z_][\w.[\]]*): ([\s\S]*)$/.exec(text);
  let subject = null;
  let rest = text;
  if (m && (TOP_KEYS.includes(m[1]) || /^mechanism[.[]/.test(m[1]))) {
    subject = normalPath(m[1]);
    rest = m[2];
  }
  rest = plainPaths(rest);
  if (!fieldPath) return subject ? `${labelOf(subject)}: ${rest}` : rest;
  const label = labelOf(fieldPath);
  if (subject === fieldPath) return `${label}: ${rest}`;
  const el = fieldInput(fieldPath);
  const sent = doc ? getPath(doc, fieldPath) : undefined;
  const typed = el && el.tagName === "INPUT" && el.value.trim() ? el.value.trim() : fmtInput(sent);
  const what = typed ? `${typed} not applied` : "not applied";
  return `${label}: ${what}: ${subject ? `${labelOf(subject)} ${rest}` : rest}`;
}

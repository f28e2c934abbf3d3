/* linkwright workbench: the builder. A linkage is drawn on the canvas, joint by joint, in the
 * plane or on the sphere: ground pivots, pins, binary links and plates (ternary and larger
 * links), pins held on guides (sliders), and drivers (the input crank, and cranks geared to it).
 *
 * The drawing is a "sketch" (state.sketch; its format is the server's, see
 * linkwright.io.sketch). Every edit sends it to POST /api/sketch, which counts its
 * degrees of freedom, says in one sentence what is missing, and, once it has exactly one and a
 * driver, compiles it to a linkage document through the one model. That document goes through
 * the page's scene pipeline like any other, so the history (history.js) records each edit as
 * one step holding both the sketch and the document, and a link or a reload (share.js) carries
 * the sketch with the document. */

import { $, clone, finite, niceStep } from "./util.js";
import { api, requestScene, state, status } from "./pipeline.js";
import {
  drawAll, drawing, fromScreenPlane, layoutStage, requestDraw, resetSphere, unprojectSphere,
} from "./draw.js";
import { drawSketch, hitSketchJoint, hitSketchLink, sketchSpace } from "./builder_draw.js";
import { checkpoint } from "./history.js";

const TOOLS = [
  ["move", "V", "Move", "drag a joint to move it; click a joint or a link to select it; drag empty space to pan or turn"],
  ["ground", "G", "Ground", "click to place a ground pivot (on a pin: make it a ground pivot)"],
  ["joint", "J", "Joint", "click to place a pin"],
  ["link", "L", "Link", "click joints (or empty space, for a new pin) in turn: each click adds a binary link; Esc ends"],
  ["plate", "P", "Plate", "click three or more joints, then Enter or the first joint again: one rigid link through them all"],
  ["slider", "S", "Slider", "click to place a pin held on a guide line (or click a pin to put it on one); set the guide's angle on the left"],
  ["driver", "D", "Driver", "click a ground pivot, then a joint on a link about it: the input crank (a second one is geared to it)"],
  ["delete", "X", "Delete", "click a joint or a link to remove it"],
];

const builderUi = {
  tool: "move",
  chain: [], // the joints the link, plate or driver tool has picked so far
  pointer: null,
  hover: null,
  selectedJoint: null,
  selectedLink: -1,
  drag: null,
  snap: false,
};
let compileSeq = 0;
const TOOLBAR_HEIGHT = 70;

export const isBuilding = () => !!state.sketch;

// ------------------------------------------------------------------ names and positions
function freshName(sk, ground) {
  const used = new Set(sk.joints.map((j) => j.name));
  for (let i = 0; i < 26; i++) {
    const name = String.fromCharCode(65 + i) + (ground ? "0" : "");
    if (!used.has(name)) return name;
  }
  for (let i = 1; ; i++) {
    const name = `${ground ? "G" : "J"}${i}`;
    if (!used.has(name)) return name;
  }
}

function snapStep() {
  return niceStep(90 / state.view.s, 1) / 2;
}

/** The model point under screen point q: on the sphere the point of the front hemisphere (the
 * rim, outside the disc); in the plane snapped to half the grid's step when snap is on. */
function modelPoint(q) {
  if (sketchSpace(state.sketch) === "sphere") return unprojectSphere(q[0], q[1]);
  const p = fromScreenPlane(q);
  if (!builderUi.snap) return p;
  const s = snapStep();
  return [Math.round(p[0] / s) * s, Math.round(p[1] / s) * s];
}

const linkKey = (link) => [...link].sort().join("\u0001");

// ------------------------------------------------------------------ edits
function addJoint(sk, at, ground, extra) {
  const name = freshName(sk, ground);
  const j = { name, at };
  if (ground) j.ground = true;
  Object.assign(j, extra || {});
  sk.joints.push(j);
  return name;
}

function removeJoint(sk, name) {
  sk.joints = sk.joints.filter((j) => j.name !== name);
  sk.links = sk.links.map((l) => l.filter((n) => n !== name)).filter((l) => l.length >= 2);
  sk.drivers = (sk.drivers || []).filter((d) => d.pivot !== name && d.joint !== name);
  if (Array.isArray(sk.traced)) sk.traced = sk.traced.filter((n) => n !== name);
}

function addBinaryLink(sk, a, b) {
  if (a === b) return false;
  const key = linkKey([a, b]);
  // a link already joining them (a binary one, or a plate holding both) makes it rigid already
  if (sk.links.some((l) => linkKey(l) === key || (l.includes(a) && l.includes(b)))) return false;
  sk.links.push([a, b]);
  return true;
}

function addPlate(sk, names) {
  const set = new Set(names);
  // a link whose joints all lie on the plate becomes part of it
  sk.links = sk.links.filter((l) => !l.every((n) => set.has(n)));
  sk.links.push([...set]);
}

function onOneLink(sk, a, b) {
  return sk.links.some((l) => l.includes(a) && l.includes(b));
}

function jointNamed(sk, name) {
  return sk.joints.find((j) => j.name === name) || null;
}

// ------------------------------------------------------------------ the server's word
function showReport(rep) {
  state.sketchReport = rep;
  const box = $("build-report");
  if (box) {
    box.dataset.status = rep ? rep.status : "";
    box.dataset.dof = rep && finite(rep.dof) ? String(rep.dof) : "";
    const dof = rep && finite(rep.dof) ? `${rep.dof} DOF · ` : "";
    box.textContent = rep ? `${dof}${rep.message}` : "";
    box.title = box.textContent;
  }
  // a drawing with no link yet is only begun, not faulty
  const started = state.sketch && state.sketch.links.length > 0;
  if (rep) status(rep.message, rep.status === "ok" || rep.status === "empty" || !started ? "info" : "error");
  requestDraw();
}

async function compile(sk) {
  const seq = ++compileSeq;
  let rep;
  try {
    rep = await api("/api/sketch", { sketch: sk });
  } catch (e) {
    if (seq === compileSeq) status(`The drawing: ${e.message}`, "error");
    return null;
  }
  return seq === compileSeq ? rep : null;
}

/** Make `next` the drawing: compile it, run it where it compiles, and record one step. */
async function commit(next, label) {
  state.sketch = next;
  state.sketchLabel = label;
  requestDraw();
  renderInspector();
  const rep = await compile(next);
  if (!rep || state.sketch !== next) return;
  showReport(rep);
  if (rep.document) {
    const doc = clone(rep.document);
    if (next.title) doc.title = next.title;
    await requestScene(doc, 0, { exampleName: null });
  }
  if (state.sketch === next) checkpoint();
}

function applyEdit(label, fn) {
  const next = clone(state.sketch);
  if (fn(next) === false) return;
  commit(next, label);
}

// ------------------------------------------------------------------ entering and leaving
function fitSketch(sk) {
  if (sketchSpace(sk) === "sphere") {
    const c = sk.joints.reduce((s, j) => s.map((v, i) => v + j.at[i]), [0, 0, 0]);
    resetSphere(sk.joints.length ? { map_center: c } : null);
    return;
  }
  // an empty sheet shows the same stretch of the plane every time: a few units about the origin
  const xs = sk.joints.length ? sk.joints.map((j) => j.at[0]) : [-3, 7];
  const ys = sk.joints.length ? sk.joints.map((j) => j.at[1]) : [-2, 6];
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const cv = drawing();
  // the tools and their report cover the top of the canvas
  const top = TOOLBAR_HEIGHT;
  const w = cv.clientWidth - 120;
  const h = cv.clientHeight - top - 60;
  const v = state.view;
  v.s = Math.min(w / Math.max(x1 - x0, 1e-6), h / Math.max(y1 - y0, 1e-6));
  if (!(v.s > 0) || !Number.isFinite(v.s)) v.s = 60;
  v.ox = cv.clientWidth / 2 - v.s * (x0 + x1) / 2;
  v.oy = top + h / 2 + 20 + v.s * (y0 + y1) / 2;
  v.fitted = true;
  v.moved = true;
}

/** Fit the view to the drawing (F, or the Fit button, while building). */
export function refitSketch() {
  if (state.sketch) fitSketch(state.sketch);
}

function showBuilderUI(on) {
  document.body.classList.toggle("building", on);
  $("build-tools").hidden = !on;
  $("fields").inert = on;
  $("build").setAttribute("aria-pressed", on ? "true" : "false");
  $("build").textContent = on ? "Done" : "Draw";
  $("build").title = on
    ? "Leave the builder and run the drawn linkage"
    : "Draw a linkage of your own on the canvas (or edit this one's drawing)";
  layoutStage();
}

/** Show a sketch as the history or a link restores it (no step of its own), or none. */
export function restoreSketch(sk) {
  const next = sk ? clone(sk) : null;
  const entering = !!next && !state.sketch;
  state.sketch = next;
  builderUi.chain = [];
  builderUi.selectedJoint = null;
  builderUi.selectedLink = -1;
  showBuilderUI(!!next);
  if (next) {
    if (entering) fitSketch(next);
    compile(next).then((rep) => {
      if (rep && state.sketch === next) showReport(rep);
    });
  } else state.sketchReport = null;
  renderInspector();
  drawAll();
}

function emptySketch(space) {
  return { space, joints: [], links: [], drivers: [] };
}

/** Start the builder with `sk` (a new drawing, or the drawing of the linkage on the page). */
export async function enterBuilder(sk, label) {
  builderUi.chain = [];
  builderUi.selectedJoint = null;
  builderUi.selectedLink = -1;
  state.sketch = sk;
  showBuilderUI(true);
  fitSketch(sk);
  setTool(sk.joints.length ? "move" : "ground");
  await commit(sk, label);
}

async function startBuilding() {
  const doc = state.doc;
  const mech = doc && doc.mechanism;
  const space = state.scene && state.scene.space === "sphere" ? "sphere" : "plane";
  if (mech) {
    try {
      const answer = await api("/api/sketch/from-document", { document: doc });
      const sk = answer.sketch || answer;
      if (doc.title) sk.title = doc.title;
      await enterBuilder(sk, "the drawing of this linkage");
      return;
    } catch (e) {
      status(`This linkage cannot be edited as a drawing (${e.message}); starting a new one`, "info");
    }
  }
  await enterBuilder(emptySketch(space), "a new drawing");
}

export function leaveBuilder() {
  if (!state.sketch) return;
  const rep = state.sketchReport;
  state.sketch = null;
  state.sketchReport = null;
  builderUi.chain = [];
  showBuilderUI(false);
  state.view.fitted = false;
  state.view.moved = false;
  if (state.scene && state.scene.space === "sphere") resetSphere(state.scene);
  renderInspector();
  drawAll();
  checkpoint();
  if (rep && rep.status === "ok") status("Running the drawn linkage: press play, or drag a joint", "info");
  else status("The drawing is not a linkage yet; the mechanism shown is the last one that ran", "error");
}

// ------------------------------------------------------------------ tools
export function setTool(name) {
  builderUi.tool = name;
  builderUi.chain = [];
  for (const b of document.querySelectorAll("#build-tools [data-tool]")) {
    b.setAttribute("aria-pressed", b.dataset.tool === name ? "true" : "false");
  }
  const t = TOOLS.find((x) => x[0] === name);
  const hint = $("hint");
  if (hint && t) hint.textContent = `${t[2]}: ${t[3]}`;
  requestDraw();
}

function pickOrCreate(sk, q, ground) {
  const hit = hitSketchJoint(sk, q);
  if (hit) return hit;
  return addJoint(sk, modelPoint(q), ground);
}

function clickLink(q) {
  const hit = hitSketchJoint(state.sketch, q);
  const last = builderUi.chain[builderUi.chain.length - 1];
  if (hit && hit === last) {
    builderUi.chain = [];
    requestDraw();
    return;
  }
  if (!last) {
    if (hit) {
      builderUi.chain = [hit];
      requestDraw();
    } else applyEdit("a pin", (sk) => {
      builderUi.chain = [addJoint(sk, modelPoint(q), false)];
    });
    return;
  }
  applyEdit("a link", (sk) => {
    const name = pickOrCreate(sk, q, false);
    const added = addBinaryLink(sk, last, name);
    builderUi.chain = [name];
    if (!added) {
      status(`${last} and ${name} are already on one link`, "info");
      return hit ? false : undefined;
    }
    return undefined;
  });
}

function closePlate() {
  const names = builderUi.chain.slice();
  builderUi.chain = [];
  if (names.length < 2) {
    requestDraw();
    return;
  }
  applyEdit(names.length > 2 ? "a plate" : "a link", (sk) => addPlate(sk, names));
}

function clickPlate(q) {
  const hit = hitSketchJoint(state.sketch, q);
  if (hit && builderUi.chain.length >= 3 && hit === builderUi.chain[0]) {
    closePlate();
    return;
  }
  if (hit) {
    if (!builderUi.chain.includes(hit)) builderUi.chain.push(hit);
    requestDraw();
    return;
  }
  // a new pin on the plate: placed now (one step), joined when the plate closes
  applyEdit("a pin", (sk) => {
    builderUi.chain = builderUi.chain.concat([addJoint(sk, modelPoint(q), false)]);
  });
}

function clickDriver(q) {
  const sk = state.sketch;
  const hit = hitSketchJoint(sk, q);
  if (!hit) return;
  if (!builderUi.chain.length) {
    builderUi.chain = [hit];
    requestDraw();
    return;
  }
  const a = jointNamed(sk, builderUi.chain[0]);
  const b = jointNamed(sk, hit);
  builderUi.chain = [];
  if (!a || !b || a.name === b.name) return requestDraw();
  const pivot = a.ground ? a : b;
  const joint = a.ground ? b : a;
  if (!pivot.ground || joint.ground) {
    status("A driver turns a link about a ground pivot: click a ground pivot and a pin on a link about it", "error");
    return requestDraw();
  }
  if (!onOneLink(sk, pivot.name, joint.name)) {
    status(`${pivot.name} and ${joint.name} are on no one link: draw the link first`, "error");
    return requestDraw();
  }
  applyEdit("a driver", (next) => {
    next.drivers = (next.drivers || []).filter((d) => d.joint !== joint.name);
    next.drivers.push({ pivot: pivot.name, joint: joint.name, ratio: next.drivers.length ? -1 : 1 });
  });
}

function clickDelete(q) {
  const sk = state.sketch;
  const hit = hitSketchJoint(sk, q);
  if (hit) {
    applyEdit(`removing ${hit}`, (next) => removeJoint(next, hit));
    return;
  }
  const k = hitSketchLink(sk, q);
  if (k >= 0) {
    applyEdit("removing a link", (next) => {
      const gone = next.links.splice(k, 1)[0];
      next.drivers = (next.drivers || []).filter((d) => onOneLink(next, d.pivot, d.joint) || !gone);
    });
  }
}

function clickSlider(q) {
  const hit = hitSketchJoint(state.sketch, q);
  if (sketchSpace(state.sketch) === "sphere") {
    status("A slider has no spherical counterpart: on the sphere, a pin on a great circle is a link of 90° about its pole", "error");
    return;
  }
  if (hit) {
    applyEdit(`${hit} on a guide`, (sk) => {
      const j = jointNamed(sk, hit);
      if (j.ground) return false;
      if (typeof j.slider === "number") delete j.slider;
      else j.slider = 0;
      return undefined;
    });
  } else applyEdit("a slider", (sk) => {
    builderUi.selectedJoint = addJoint(sk, modelPoint(q), false, { slider: 0 });
  });
}

// ------------------------------------------------------------------ pointer (called by app.js)
/** Handle a pointer press on the canvas while building; false leaves it to the page (pan or
 * turn the view). */
export function builderPointerDown(q) {
  const sk = state.sketch;
  const tool = builderUi.tool;
  if (tool === "move") {
    const hit = hitSketchJoint(sk, q);
    if (hit) {
      builderUi.drag = { joint: hit, moved: false };
      builderUi.selectedJoint = hit;
      builderUi.selectedLink = -1;
      renderInspector();
      requestDraw();
      return true;
    }
    const k = hitSketchLink(sk, q);
    if (k >= 0) {
      builderUi.selectedLink = k;
      builderUi.selectedJoint = null;
      renderInspector();
      requestDraw();
      return true;
    }
    builderUi.selectedJoint = null;
    builderUi.selectedLink = -1;
    renderInspector();
    return false;
  }
  if (tool === "ground" || tool === "joint") {
    const hit = hitSketchJoint(sk, q);
    if (hit && tool === "ground") {
      applyEdit(`${hit} grounded`, (next) => {
        const j = jointNamed(next, hit);
        j.ground = !j.ground;
        if (!j.ground) delete j.ground;
        else delete j.slider;
      });
    } else if (!hit) applyEdit(tool === "ground" ? "a ground pivot" : "a pin", (next) => {
      addJoint(next, modelPoint(q), tool === "ground");
    });
  } else if (tool === "link") clickLink(q);
  else if (tool === "plate") clickPlate(q);
  else if (tool === "driver") clickDriver(q);
  else if (tool === "delete") clickDelete(q);
  else if (tool === "slider") clickSlider(q);
  return true;
}

export function builderPointerMove(q, pressed) {
  const sk = state.sketch;
  builderUi.pointer = q;
  if (builderUi.drag && pressed) {
    const j = jointNamed(sk, builderUi.drag.joint);
    if (j) {
      j.at = modelPoint(q);
      builderUi.drag.moved = true;
    }
    requestDraw();
    return;
  }
  const h = hitSketchJoint(sk, q);
  if (h !== builderUi.hover || builderUi.chain.length) {
    builderUi.hover = h;
    requestDraw();
  }
  drawing().className = h ? (builderUi.tool === "move" ? "grab" : "picking") : builderUi.tool === "move" ? "" : "picking";
}

export function builderPointerUp() {
  const d = builderUi.drag;
  builderUi.drag = null;
  if (d && d.moved) {
    // the drag edited state.sketch in place while drawing; the step is the whole move
    const next = clone(state.sketch);
    commit(next, `moving ${d.joint}`);
  }
}

export function builderKey(e) {
  if (e.key === "Escape") {
    if (builderUi.chain.length) {
      builderUi.chain = [];
      requestDraw();
    } else setTool("move");
    return true;
  }
  if (e.key === "Enter" && builderUi.tool === "plate") {
    closePlate();
    return true;
  }
  if ((e.key === "Delete" || e.key === "Backspace") && (builderUi.selectedJoint || builderUi.selectedLink >= 0)) {
    const joint = builderUi.selectedJoint;
    const link = builderUi.selectedLink;
    builderUi.selectedJoint = null;
    builderUi.selectedLink = -1;
    if (joint) applyEdit(`removing ${joint}`, (sk) => removeJoint(sk, joint));
    else applyEdit("removing a link", (sk) => void sk.links.splice(link, 1));
    return true;
  }
  const t = TOOLS.find((x) => x[1] === e.key.toUpperCase());
  if (t) {
    setTool(t[0]);
    return true;
  }
  return false;
}

export function drawBuilder() {
  drawSketch(builderUi);
}

// ------------------------------------------------------------------ the panel on the left
function numberRow(box, label, value, apply, testid) {
  const row = document.createElement("label");
  row.className = "build-row";
  row.textContent = label;
  const input = document.createElement("input");
  input.type = "text";
  input.value = String(Math.round(value * 1e6) / 1e6);
  if (testid) input.dataset.testid = testid;
  const done = () => {
    const v = Number(input.value.trim());
    if (input.value.trim() === "" || !Number.isFinite(v)) {
      input.classList.add("invalid");
      status(`${label}: “${input.value}” is not a number`, "error");
      return;
    }
    if (v !== value) apply(v);
  };
  input.addEventListener("change", done);
  input.addEventListener("keydown", (e) => {
    if (e.key === "Enter") input.blur();
  });
  row.appendChild(input);
  box.appendChild(row);
}

function renderInspector() {
  const box = $("build-panel");
  if (!box) return;
  box.hidden = !state.sketch;
  box.replaceChildren();
  const sk = state.sketch;
  if (!sk) return;
  const head = document.createElement("h3");
  head.textContent = `Drawing (${sketchSpace(sk)})`;
  box.appendChild(head);
  const count = document.createElement("p");
  count.className = "build-count";
  count.textContent = `${sk.joints.length} joints · ${sk.links.length} links · ${(sk.drivers || []).length} drivers`;
  box.appendChild(count);
  const j = builderUi.selectedJoint ? jointNamed(sk, builderUi.selectedJoint) : null;
  if (j) {
    const sub = document.createElement("h4");
    sub.textContent = `${j.ground ? "ground pivot" : typeof j.slider === "number" ? "slider pin" : "pin"} ${j.name}`;
    box.appendChild(sub);
    const axes = sketchSpace(sk) === "sphere" ? ["x", "y", "z"] : ["x", "y"];
    axes.forEach((ax, i) =>
      numberRow(box, `${j.name} ${ax}`, j.at[i], (v) => applyEdit(`${j.name} ${ax}`, (next) => {
        jointNamed(next, j.name).at[i] = v;
      }), `build-${ax}`),
    );
    if (typeof j.slider === "number") {
      numberRow(box, "guide angle (°)", j.slider, (v) => applyEdit(`${j.name} guide angle`, (next) => {
        jointNamed(next, j.name).slider = v;
      }), "build-guide");
    }
  }
  (sk.drivers || []).forEach((d, i) => {
    if (i === 0) {
      const p = document.createElement("p");
      p.className = "build-count";
      p.textContent = `input crank ${d.pivot}–${d.joint}`;
      box.appendChild(p);
    } else {
      numberRow(box, `gear ratio ${d.pivot}–${d.joint}`, d.ratio, (v) => applyEdit("a gear ratio", (next) => {
        next.drivers[i].ratio = v;
      }), `build-ratio-${i}`);
    }
  });
}

// ------------------------------------------------------------------ the toolbar
export function initBuilder() {
  const top = document.createElement("button");
  top.id = "build";
  top.type = "button";
  top.className = "top-button";
  top.dataset.testid = "build";
  top.setAttribute("aria-pressed", "false");
  top.textContent = "Draw";
  top.title = "Draw a linkage of your own on the canvas (or edit this one's drawing)";
  top.addEventListener("mousedown", (e) => e.preventDefault());
  top.addEventListener("click", () => (state.sketch ? leaveBuilder() : startBuilding()));
  $("copy-link").before(top);

  const bar = document.createElement("div");
  bar.id = "build-tools";
  bar.className = "build-tools";
  bar.dataset.testid = "build-tools";
  bar.hidden = true;
  for (const [name, key, label, help] of TOOLS) {
    const b = document.createElement("button");
    b.type = "button";
    b.dataset.tool = name;
    b.dataset.testid = `tool-${name}`;
    b.textContent = label;
    b.title = `${help} (${key})`;
    b.addEventListener("mousedown", (e) => e.preventDefault());
    b.addEventListener("click", () => setTool(name));
    bar.appendChild(b);
  }
  const snap = document.createElement("label");
  snap.className = "build-snap";
  snap.title = "snap new and moved joints to half the grid's step (plane)";
  const box = document.createElement("input");
  box.type = "checkbox";
  box.dataset.testid = "build-snap";
  box.addEventListener("change", () => {
    builderUi.snap = box.checked;
  });
  snap.append(box, " snap");
  bar.appendChild(snap);
  for (const space of ["plane", "sphere"]) {
    const b = document.createElement("button");
    b.type = "button";
    b.dataset.testid = `new-${space}`;
    b.textContent = `New ${space}`;
    b.title = `Start an empty drawing ${space === "plane" ? "in the plane" : "on the sphere"} (undo brings the old one back)`;
    b.addEventListener("mousedown", (e) => e.preventDefault());
    b.addEventListener("click", () => enterBuilder(emptySketch(space), `a new ${space} drawing`));
    bar.appendChild(b);
  }
  const report = document.createElement("div");
  report.id = "build-report";
  report.className = "build-report";
  report.dataset.testid = "build-report";
  report.setAttribute("role", "status");
  bar.appendChild(report);
  $("drawing-wrap").appendChild(bar);

  const panel = document.createElement("section");
  panel.id = "build-panel";
  panel.className = "info-block build-panel";
  panel.dataset.testid = "build-panel";
  panel.hidden = true;
  $("fields").before(panel);
}

/* linkwright workbench: the page's state, the server calls, and the scene pipeline (one scene
 * request in flight, the newest pending; a scene applied to the page, the pose located on it). */

import { $, SAMPLES, finite, okPoint } from "./util.js";
import {
  markField, renderCircuits, renderFields, renderInfo, renderLegend, renderLimitsList,
  renderModes, renderTop, updateAtUI,
} from "./panels.js";
import { drawAll, layoutStage, resetSphere } from "./draw.js";
import { fitMapBasis } from "./sphere.js";
import { renderCharts } from "./charts.js";
import { explainError, fieldRefused } from "./fields.js";

// ------------------------------------------------------------------ state
export const state = {
  families: [],
  examples: [],
  exampleName: null,
  doc: null, // last document the server accepted (scene.document)
  scene: null,
  latestRequested: null, // document of the newest scene request not yet answered
  cur: null, // {mode, circuit, index}: the displayed sample of the own mode
  exact: null, // the scene's pose when the displayed input is exactly scene.at
  at: null,
  playing: false,
  speed: 1,
  phase: 0,
  view: { s: 60, ox: 300, oy: 300, fitted: false, moved: false },
  sphere: { R: [1, 0, 0, 0, 1, 0, 0, 0, 1], zoom: 1, moved: false },
  map: { zoom: 1, basis: null },
  overlays: new Map(),
  pick: null,
  gesture: null,
  hoverHandle: null,
  hoverLimit: null,
  limitMarks: [],
  listeners: { scene: [], at: [], document: [], units: [] },
  chartsPhysical: false, // the velocity and acceleration charts at the page's input speed
  sceneCount: 0,
  busy: 0,
  pipelineError: false,
  sceneError: null, // the last refused scene's message, in the page's words
  fieldSig: "",
  chartSig: "",
  plotKind: "angles",
  charts: [],
  dragPipe: null,
  dragGhost: null,
  sketch: null, // the sketch being built (builder.js), or null
  sketchReport: null, // the server's word on it: degrees of freedom, status, message
  sketchLabel: "", // the last building edit, in words, for the history
};

export function emit(name, arg) {
  for (const fn of state.listeners[name] || []) {
    try {
      fn(arg);
    } catch (e) {
      console.error(e);
    }
  }
}

// ------------------------------------------------------------------ server access
export function setBusy(delta) {
  state.busy = Math.max(0, state.busy + delta);
  document.body.dataset.busy = state.busy > 0 ? "1" : "0";
}

export async function api(path, body) {
  setBusy(+1);
  try {
    let resp;
    try {
      resp = await fetch(
        path,
        body === undefined
          ? { headers: { Accept: "application/json" } }
          : {
              method: "POST",
              headers: { "Content-Type": "application/json", Accept: "application/json" },
              body: JSON.stringify(body),
            },
      );
    } catch (e) {
      throw new Error(`the workbench server cannot be reached (${path})`);
    }
    const text = await resp.text();
    let data = null;
    try {
      data = text ? JSON.parse(text) : null;
    } catch (e) {
      if (resp.ok) throw new Error(`${path}: the server answered something that is not JSON`);
    }
    if (!resp.ok) {
      const msg = data && typeof data.error === "string" ? data.error : `${path}: HTTP ${resp.status}`;
      const err = new Error(msg);
      err.status = resp.status;
      throw err;
    }
    return data;
  } finally {
    setBusy(-1);
  }
}

export function status(text, kind) {
  const el = $("status");
  el.textContent = text == null ? "" : String(text);
  el.dataset.kind = kind || "info";
  el.title = el.textContent;
  // an action offered beside a message (history.js) belongs to that message only
  const action = $("status-action");
  if (action) action.hidden = true;
}

// ------------------------------------------------------------------ scene pipeline
// At most one scene request in flight; a newer request replaces any waiting one, and its
// answer settles every promise that was waiting (the latest document is what counts).
let sceneInFlight = false;
let scenePending = null;

export function requestScene(doc, at, opts = {}) {
  state.latestRequested = doc;
  return new Promise((resolve) => {
    if (scenePending) {
      scenePending.waiters.push(resolve);
      scenePending.doc = doc;
      scenePending.at = at;
      scenePending.fit = scenePending.fit || !!opts.fit;
      scenePending.fieldPath = opts.fieldPath || null;
      scenePending.exampleName = opts.exampleName !== undefined ? opts.exampleName : scenePending.exampleName;
    } else {
      scenePending = {
        doc,
        at,
        fit: !!opts.fit,
        fieldPath: opts.fieldPath || null,
        exampleName: opts.exampleName,
        waiters: [resolve],
      };
    }
    pumpScene();
  });
}

async function pumpScene() {
  if (sceneInFlight || !scenePending) return;
  const job = scenePending;
  scenePending = null;
  sceneInFlight = true;
  let result = null;
  try {
    const body = { document: job.doc, samples: SAMPLES, at: finite(job.at) ? job.at : null, diagrams: true, ...state.sceneFlags };
    const sc = await api("/api/scene", body);
    if (!scenePending) state.latestRequested = null;
    applyScene(sc, job);
    result = sc;
  } catch (e) {
    if (!scenePending) state.latestRequested = null;
    state.pipelineError = true;
    // the page's words: the edited field's label, not the server's document path
    const text = explainError(e.message, job.fieldPath, job.doc);
    state.sceneError = text;
    status(text, "error");
    markField(job.fieldPath, text);
    fieldRefused(job.fieldPath);
    if (!state.scene) drawAll();
  } finally {
    sceneInFlight = false;
    for (const w of job.waiters) w(result);
    pumpScene();
  }
}

export function ownModeIndex(sc) {
  if (!sc || !sc.modes) return -1;
  return sc.modes.findIndex((m) => m.own);
}

export function samplePose(sc, m, c, i) {
  const circ = sc.modes[m].circuits[c];
  const out = {};
  for (const [name, arr] of Object.entries(circ.positions)) out[name] = arr[i];
  return out;
}

function poseDistance(a, b) {
  let d = 0;
  let n = 0;
  for (const k of Object.keys(a)) {
    const p = a[k];
    const q = b[k];
    if (!Array.isArray(p) || !Array.isArray(q) || p[0] == null || q[0] == null) continue;
    let s = 0;
    for (let j = 0; j < Math.min(p.length, q.length); j++) s += (p[j] - q[j]) ** 2;
    d = Math.max(d, Math.sqrt(s));
    n++;
  }
  return n ? d : Infinity;
}

export const angDist = (a, b) => {
  const d = Math.abs((((a - b) % 360) + 540) % 360 - 180);
  return d;
};

/** The own-mode sample to display for input `at`: nearest in input, on the branch closest
 * to what was drawn before (so an edit never flips the linkage to the other branch). */
function locate(sc, at, previous) {
  const m = ownModeIndex(sc);
  if (m < 0 || !sc.modes[m].circuits.length) return null;
  const circuits = sc.modes[m].circuits;
  let best = Infinity;
  const cands = [];
  circuits.forEach((circ, c) => {
    circ.input.forEach((x, i) => {
      if (!finite(x)) return;
      const d = finite(at) ? angDist(x, at) : 0;
      cands.push([d, c, i]);
      if (d < best) best = d;
    });
  });
  if (!cands.length) return null;
  if (!finite(at)) return { mode: m, circuit: 0, index: 0 };
  const step = 360 / Math.max(8, SAMPLES);
  const near = cands.filter((k) => k[0] <= best + 0.75 * step);
  const ref = previous || sc.pose;
  let pick = near[0];
  if (ref && near.length > 1) {
    let bd = Infinity;
    for (const k of near) {
      const d = poseDistance(ref, samplePose(sc, m, k[1], k[2])) + k[0] * 1e-6;
      if (d < bd) {
        bd = d;
        pick = k;
      }
    }
  } else {
    pick = near.reduce((a, b) => (b[0] < a[0] ? b : a));
  }
  return { mode: m, circuit: pick[1], index: pick[2] };
}

export function sceneScale(sc) {
  let lo = [Infinity, Infinity];
  let hi = [-Infinity, -Infinity];
  const m = ownModeIndex(sc);
  if (m >= 0)
    for (const circ of sc.modes[m].circuits)
      for (const arr of Object.values(circ.positions))
        for (const p of arr)
          if (okPoint(p)) {
            lo = [Math.min(lo[0], p[0]), Math.min(lo[1], p[1])];
            hi = [Math.max(hi[0], p[0]), Math.max(hi[1], p[1])];
          }
  const s = Math.max(hi[0] - lo[0], hi[1] - lo[1]);
  return finite(s) && s > 0 ? s : 1;
}

function applyScene(sc, job) {
  const prevScene = state.scene;
  const previous = currentPose();
  const freshKind = !prevScene || prevScene.family !== sc.family || prevScene.space !== sc.space;
  state.scene = sc;
  state.doc = sc.document;
  if (job.exampleName !== undefined) state.exampleName = job.exampleName;
  if (state.pipelineError) {
    state.pipelineError = false;
    status("Ready", "info");
  }
  markField(null);
  placeCursor(sc, locate(sc, finite(sc.at) ? sc.at : job.at, freshKind || job.fit ? null : previous));
  state.map.basis = sc.space === "sphere" ? fitMapBasis(sc) : null;
  // while building, the view is the sketch's: a linkage compiled from it must not move it
  if ((freshKind || job.fit) && !state.sketch) {
    state.view.fitted = false;
    state.view.moved = false;
    if (sc.space === "sphere") resetSphere(sc);
    state.map.zoom = 1;
  }
  renderTop(sc);
  renderFields(sc);
  renderInfo(sc);
  renderModes(sc);
  renderCircuits(sc);
  renderLegend(sc);
  renderLimitsList(sc);
  renderCharts(sc);
  layoutStage();
  updateAtUI();
  drawAll();
  state.sceneCount += 1;
  document.body.dataset.sceneCount = String(state.sceneCount);
  emit("scene", sc);
}

/** Show sample `cur` ({mode, circuit, index}, or null) of scene `sc`: at the scene's exact pose
 * when that sample is the pose the server computed at `sc.at`. */
export function placeCursor(sc, cur) {
  state.cur = cur;
  state.exact = null;
  if (state.cur) {
    const circ = sc.modes[state.cur.mode].circuits[state.cur.circuit];
    state.at = circ.input[state.cur.index];
    if (sc.pose && finite(sc.at)) {
      const samp = samplePose(sc, state.cur.mode, state.cur.circuit, state.cur.index);
      const tol = 0.05 * sceneScale(sc) + 1e-9;
      if (poseDistance(sc.pose, samp) <= tol) {
        state.exact = sc.pose;
        state.at = sc.at;
      }
    }
  } else {
    state.at = finite(sc.at) ? sc.at : null;
  }
}

export function currentPose() {
  const sc = state.scene;
  if (!sc || !state.cur) return sc && sc.pose ? sc.pose : null;
  if (state.exact) return state.exact;
  return samplePose(sc, state.cur.mode, state.cur.circuit, state.cur.index);
}

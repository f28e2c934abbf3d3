/* linkwright workbench: the core page (drawing, parameters, animation, plots); the entry module.
 *
 * No build step and nothing fetched from outside: ES modules (`<script type="module">`),
 * canvas 2D. The server computes every number (POST /api/scene, /api/drag); these modules only
 * draw what a scene says and turn the user's gestures into documents. This one holds the
 * pointer and keyboard interaction and window.lw, the API that tools.js builds on (see the
 * contract in the server package), and starts the page. */

import { $, clamp, clone, finite, mulMM, orthonormal, rotX, rotY } from "./util.js";
import {
  angDist, api, currentPose, ownModeIndex, requestScene, setBusy, state, status,
} from "./pipeline.js";
import {
  currentCircuit, fillChoosers, loadExample, loadFamily, renderLegend, setAtIndex, setHoverLimit,
  setPlaying, stepSample,
} from "./panels.js";
import {
  drawAll, drawing, fitPlane, fromScreenPlane, layoutStage, projectSphere, requestDraw,
  resetSphere, sphereGeom, toScreen, toScreenPlane, unprojectSphere,
} from "./draw.js";
import { explainError } from "./fields.js";
import { checkpoint, historyInfo, initHistory, markLoaded, redoStep, undoStep } from "./history.js";
import { initShare, openFirst, shareLink } from "./share.js";
import { initOverlays } from "./overlays.js";
import { initForces } from "./forces.js";
import {
  builderKey, builderPointerDown, builderPointerMove, builderPointerUp, initBuilder, refitSketch,
} from "./builder.js";
import { sketchToScreen } from "./builder_draw.js";
import { initHelp } from "./help.js";

// ------------------------------------------------------------------ pointer interaction
function canvasPoint(e) {
  const r = drawing().getBoundingClientRect();
  return [e.clientX - r.left, e.clientY - r.top];
}

function hitHandle(q) {
  const sc = state.scene;
  const pose = currentPose();
  if (!sc || !pose) return null;
  const sphere = sc.space === "sphere";
  const g = sphere ? sphereGeom() : null;
  let best = null;
  let bd = 11;
  for (const name of sc.handles || []) {
    const p = pose[name];
    if (!p || p[0] == null) continue;
    let s;
    if (sphere) {
      s = projectSphere(p, g);
      if (s[2] < -0.05) continue;
    } else s = toScreenPlane(p);
    const d = Math.hypot(s[0] - q[0], s[1] - q[1]);
    if (d < bd || (d === bd && best && (sc.traced || []).includes(name))) {
      bd = d;
      best = name;
    }
  }
  return best;
}

function hitLimit(q) {
  for (const m of state.limitMarks) if (Math.hypot(m.x - q[0], m.y - q[1]) <= 8) return m.k;
  return null;
}

function modelAt(q) {
  const sc = state.scene;
  if (sc && sc.space === "sphere") return unprojectSphere(q[0], q[1]);
  return fromScreenPlane(q);
}

const viewSpace = () =>
  state.sketch ? (state.sketch.space === "sphere" ? "sphere" : "plane") : state.scene && state.scene.space;

// Two fingers on the canvas pinch: the view scales about their midpoint (the sphere zooms).
const touches = new Map();
let pinchLast = null;

function pinchSpan() {
  const [a, b] = [...touches.values()];
  return { d: Math.hypot(a[0] - b[0], a[1] - b[1]), mid: [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2] };
}

function trackTouch(e, phase) {
  if (e.pointerType !== "touch") return false;
  if (phase === "up") {
    touches.delete(e.pointerId);
    if (touches.size < 2) pinchLast = null;
    return false;
  }
  touches.set(e.pointerId, canvasPoint(e));
  if (touches.size !== 2) return false;
  const now = pinchSpan();
  if (phase === "down" || !pinchLast) {
    pinchLast = now;
    state.gesture = null;
    return true;
  }
  const f = clamp(now.d / Math.max(pinchLast.d, 1), 0.5, 2);
  zoomBy(f, now.mid);
  pinchLast = now;
  return true;
}

function zoomBy(f, q) {
  if (viewSpace() === "sphere") {
    state.sphere.zoom = clamp(state.sphere.zoom * f, 0.3, 6);
  } else {
    const m = fromScreenPlane(q);
    state.view.s = clamp(state.view.s * f, 1e-6, 1e9);
    state.view.ox = q[0] - state.view.s * m[0];
    state.view.oy = q[1] + state.view.s * m[1];
    state.view.moved = true;
  }
  requestDraw();
}

function onPointerDown(e) {
  if (trackTouch(e, "down")) return;
  if (e.button !== 0 || !(state.scene || state.sketch)) return;
  const cv = drawing();
  cv.focus({ preventScroll: true });
  const q = canvasPoint(e);
  cv.setPointerCapture(e.pointerId);
  if (state.sketch) {
    if (builderPointerDown(q)) state.gesture = { kind: "build" };
    else state.gesture = { kind: viewSpace() === "sphere" ? "turn" : "pan", last: q, start: q };
    e.preventDefault();
    return;
  }
  if (state.pick) {
    state.pick.points = [modelAt(q)];
    state.gesture = { kind: "pick", last: q };
    e.preventDefault();
    return;
  }
  const joint = hitHandle(q);
  if (joint) {
    if (state.playing) setPlaying(false);
    state.gesture = { kind: "joint", joint, mouse: q };
    state.dragPipe = { joint, latest: null, busy: false };
    cv.className = "grabbing";
    hideTooltip();
  } else {
    state.gesture = { kind: state.scene.space === "sphere" ? "turn" : "pan", last: q, start: q };
    cv.className = "pan";
  }
  e.preventDefault();
}

function onPointerMove(e) {
  if (trackTouch(e, "move")) return;
  const q = canvasPoint(e);
  const g = state.gesture;
  const cv = drawing();
  if (state.sketch && (!g || g.kind === "build")) {
    builderPointerMove(q, !!g);
    return;
  }
  if (!g) {
    const h = hitHandle(q);
    if (h !== state.hoverHandle) {
      state.hoverHandle = h;
      requestDraw();
    }
    const lim = hitLimit(q);
    if (lim != null) showTooltip(q, (state.scene.limits[lim] || {}).text || "");
    else hideTooltip();
    setHoverLimit(lim, true);
    cv.className = state.pick ? "picking" : h ? "grab" : "";
    return;
  }
  if (g.kind === "pick") {
    if (Math.hypot(q[0] - g.last[0], q[1] - g.last[1]) >= 2) {
      state.pick.points.push(modelAt(q));
      g.last = q;
      requestDraw();
    }
  } else if (g.kind === "joint") {
    g.mouse = q;
    state.dragPipe.latest = modelAt(q);
    pumpDrag();
    requestDraw();
  } else if (g.kind === "pan") {
    state.view.ox += q[0] - g.last[0];
    state.view.oy += q[1] - g.last[1];
    state.view.moved = true;
    g.last = q;
    requestDraw();
  } else if (g.kind === "turn") {
    const dx = q[0] - g.last[0];
    const dy = q[1] - g.last[1];
    const k = 1 / (sphereGeom().r || 200);
    state.sphere.R = orthonormal(mulMM(mulMM(rotY(dx * k), rotX(dy * k)), state.sphere.R));
    state.sphere.moved = true;
    g.last = q;
    requestDraw();
  }
}

function onPointerUp(e) {
  trackTouch(e, "up");
  const g = state.gesture;
  const cv = drawing();
  if (cv.hasPointerCapture && cv.hasPointerCapture(e.pointerId)) cv.releasePointerCapture(e.pointerId);
  state.gesture = null;
  cv.className = state.pick ? "picking" : "";
  if (!g) return;
  if (g.kind === "build") {
    builderPointerUp();
    return;
  }
  if (g.kind === "pick") {
    const pts = state.pick.points || [];
    const fn = state.pick.fn;
    state.pick = null;
    cv.className = "";
    requestDraw();
    if (pts.length < 2) {
      status("Draw by holding the mouse button down while moving", "error");
      return;
    }
    try {
      fn(pts);
    } catch (err) {
      console.error(err);
      status(err.message || String(err), "error");
    }
  } else if (g.kind === "joint") {
    if (state.dragPipe) state.dragPipe.ended = true;
    // one drag, one undo step: taken now, or when the drag's last answer is drawn (pumpDrag)
    if (!state.dragPipe || !state.dragPipe.busy) checkpoint();
    requestDraw();
  }
}

function pumpDrag() {
  const pipe = state.dragPipe;
  if (!pipe || pipe.busy || !pipe.latest) return;
  const to = pipe.latest;
  pipe.latest = null;
  pipe.busy = true;
  setBusy(+1);
  const doc = state.latestRequested || state.doc;
  api("/api/drag", { document: doc, joint: pipe.joint, to, at: finite(state.at) ? state.at : 0 })
    .then((r) => {
      if (r.exact === false) status(`${pipe.joint} cannot reach there: shown at the nearest position it can take`, "info");
      return requestScene(r.document, r.at);
    })
    .catch((err) => {
      state.pipelineError = true;
      status(`${pipe.joint}: ${explainError(err.message)}`, "error");
    })
    .finally(() => {
      pipe.busy = false;
      setBusy(-1);
      if (pipe.latest) pumpDrag();
      else if (pipe.ended && state.dragPipe === pipe) {
        state.dragPipe = null;
        checkpoint();
      }
    });
}

function onWheel(e) {
  if (!state.scene && !state.sketch) return;
  e.preventDefault();
  zoomBy(Math.exp(-clamp(e.deltaY, -200, 200) * 0.0015), canvasPoint(e));
}

function showTooltip(q, text) {
  const tip = $("tooltip");
  tip.textContent = text;
  tip.hidden = false;
  const wrap = $("drawing-wrap");
  const x = Math.min(q[0] + 14, wrap.clientWidth - tip.offsetWidth - 6);
  const y = q[1] + 14 + tip.offsetHeight > wrap.clientHeight ? q[1] - tip.offsetHeight - 10 : q[1] + 14;
  tip.style.left = `${Math.max(4, x)}px`;
  tip.style.top = `${Math.max(4, y)}px`;
}
export function hideTooltip() {
  $("tooltip").hidden = true;
}

function fit() {
  const sc = state.scene;
  if (state.sketch) {
    refitSketch();
    drawAll();
    return;
  }
  if (!sc) return;
  if (sc.space === "sphere") {
    resetSphere(sc);
    state.map.zoom = 1;
  } else fitPlane();
  drawAll();
}

// ------------------------------------------------------------------ keyboard, tabs, resize
function onKey(e) {
  const t = e.target;
  const tag = t && t.tagName;
  if (tag === "INPUT" || tag === "SELECT" || tag === "TEXTAREA" || (t && t.isContentEditable)) return;
  if (e.ctrlKey || e.metaKey || e.altKey) return;
  if (state.sketch && builderKey(e)) {
    e.preventDefault();
    return;
  }
  if (e.key === " " || e.code === "Space") {
    e.preventDefault();
    setPlaying(!state.playing);
  } else if (e.key === "ArrowRight" || e.key === "ArrowUp") {
    e.preventDefault();
    stepSample(+1);
  } else if (e.key === "ArrowLeft" || e.key === "ArrowDown") {
    e.preventDefault();
    stepSample(-1);
  } else if ((e.key === "f" || e.key === "F") && tag !== "BUTTON") {
    fit();
  } else if (e.key === "Escape" && state.pick) {
    cancelPick();
  }
}

function setupTabs() {
  const nav = document.querySelector("#side .tabs");
  const buttons = [...nav.querySelectorAll("button[data-tab]")];
  const show = (name) => {
    document.body.classList.remove("side-collapsed");
    for (const b of buttons) {
      const on = b.dataset.tab === name;
      b.setAttribute("aria-selected", on ? "true" : "false");
      $(`tab-${b.dataset.tab}`).hidden = !on;
    }
    requestDraw();
  };
  for (const b of buttons) b.addEventListener("click", () => show(b.dataset.tab));
  const collapse = document.createElement("button");
  collapse.type = "button";
  collapse.className = "collapse";
  collapse.title = "hide / show the tools panel";
  collapse.textContent = "⇥";
  collapse.addEventListener("click", () => {
    document.body.classList.toggle("side-collapsed");
    collapse.textContent = document.body.classList.contains("side-collapsed") ? "⇤" : "⇥";
  });
  nav.appendChild(collapse);
  // tools.js may ask for a tab by clicking it; a tab can also be shown from the address
  window.addEventListener("lw-show-tab", (ev) => show(ev.detail));
}

function onResize() {
  layoutStage();
  if (state.scene && state.scene.space !== "sphere" && !state.view.moved) state.view.fitted = false;
  for (const ch of state.charts) ch.cache = null;
  drawAll();
}

// ------------------------------------------------------------------ public API
function cancelPick() {
  if (!state.pick) return;
  state.pick = null;
  state.gesture = null;
  drawing().className = "";
  requestDraw();
}

const lw = {
  document: () => clone(state.doc),
  setDocument(doc, opts = {}) {
    const d = clone(doc);
    if (opts && typeof opts.title === "string") d.title = opts.title;
    return requestScene(d, opts && finite(opts.at) ? opts.at : null, {
      fit: !(opts && opts.fit === false),
      exampleName: opts && opts.example ? opts.example : null,
    });
  },
  scene: () => state.scene,
  at: () => state.at,
  setAt(deg) {
    // nearest sample of the shown circuit (tools may want to show a given input)
    const circ = currentCircuit();
    if (!circ) return;
    let best = 0;
    circ.input.forEach((x, i) => {
      if (angDist(x, deg) < angDist(circ.input[best], deg)) best = i;
    });
    setAtIndex(best);
  },
  pose: () => clone(currentPose()),
  on(name, fn) {
    if (!state.listeners[name]) state.listeners[name] = [];
    state.listeners[name].push(fn);
    return () => {
      state.listeners[name] = state.listeners[name].filter((f) => f !== fn);
    };
  },
  overlay(name, curves, style) {
    state.overlays.set(String(name), { curves: curves || [], style: style || {} });
    if (state.scene) renderLegend(state.scene);
    requestDraw();
  },
  clearOverlay(name) {
    if (name === undefined) state.overlays.clear();
    else state.overlays.delete(String(name));
    if (state.scene) renderLegend(state.scene);
    requestDraw();
  },
  pickPoints(fn) {
    if (typeof fn !== "function") throw new TypeError("lw.pickPoints needs a function");
    if (state.playing) setPlaying(false);
    state.pick = { fn, points: null };
    drawing().className = "picking";
    status("Draw the curve on the drawing: hold the mouse button down and move (Esc cancels)", "info");
  },
  cancelPick,
  status,
  api,
  toScreen: (p) => (state.sketch ? sketchToScreen(state.sketch, p).slice(0, 2) : toScreen(p)),
  fromScreen: (q) => modelAt(q),
  fit,
  play: () => setPlaying(true),
  pause: () => setPlaying(false),
  step: stepSample,
  view: () => ({
    space: state.scene ? state.scene.space : null,
    scale: state.view.s,
    origin: [state.view.ox, state.view.oy],
    rotation: state.sphere.R.slice(),
    zoom: state.sphere.zoom,
    disc: sphereGeom(),
  }),
  // builder.js: the drawing being built and the server's word on it (null when not building)
  sketch: () => clone(state.sketch),
  sketchReport: () => clone(state.sketchReport),
  refresh: () => requestScene(clone(state.latestRequested || state.doc), state.at),
  // history.js and share.js: undo, redo, the state of the history, a link to this state
  undo: undoStep,
  redo: redoStep,
  history: historyInfo,
  markSaved: markLoaded,
  shareLink,
};
window.lw = lw;

// ------------------------------------------------------------------ start
function wire() {
  const cv = drawing();
  cv.addEventListener("pointerdown", onPointerDown);
  cv.addEventListener("pointermove", onPointerMove);
  cv.addEventListener("pointerup", onPointerUp);
  cv.addEventListener("pointercancel", onPointerUp);
  cv.addEventListener("pointerleave", () => {
    if (!state.gesture) {
      hideTooltip();
      if (state.hoverHandle) {
        state.hoverHandle = null;
        requestDraw();
      }
      setHoverLimit(null, true);
    }
  });
  cv.addEventListener("wheel", onWheel, { passive: false });
  cv.addEventListener("dblclick", fit);
  $("map").addEventListener(
    "wheel",
    (e) => {
      e.preventDefault();
      state.map.zoom = clamp(state.map.zoom * Math.exp(-clamp(e.deltaY, -200, 200) * 0.0015), 0.5, 8);
      requestDraw();
    },
    { passive: false },
  );
  $("fit").addEventListener("click", fit);
  for (const id of ["play", "step-back", "step-fwd", "fit"]) $(id).addEventListener("mousedown", (e) => e.preventDefault());
  $("play").addEventListener("click", () => setPlaying(!state.playing));
  $("step-back").addEventListener("click", () => stepSample(-1));
  $("step-fwd").addEventListener("click", () => stepSample(+1));
  $("input-slider").addEventListener("input", (e) => {
    if (state.playing) setPlaying(false);
    setAtIndex(Number(e.target.value));
  });
  const speed = $("speed");
  const setSpeed = () => {
    state.speed = Math.pow(2, (Number(speed.value) - 50) / 20);
    $("speed-value").textContent = `${state.speed.toFixed(state.speed < 1 ? 2 : 1)}×`;
    speed.dataset.speed = String(state.speed);
  };
  speed.addEventListener("input", setSpeed);
  setSpeed();
  $("circuit-select").addEventListener("change", (e) => {
    const c = Number(e.target.value);
    const sc = state.scene;
    if (!sc || !state.cur) return;
    const circ = sc.modes[state.cur.mode].circuits[c];
    let best = 0;
    circ.input.forEach((x, i) => {
      if (angDist(x, state.at) < angDist(circ.input[best], state.at)) best = i;
    });
    state.cur.circuit = c;
    setAtIndex(best);
    // The document names the circuit it runs on by an input on it (its start), so that a save,
    // an export, a share link and the CLI all trace the one picked here.
    const at = circ.input[best];
    if (state.doc && state.doc.mechanism && finite(at) && state.cur.mode === ownModeIndex(sc)) {
      const doc = clone(state.doc);
      doc.mechanism.start = Math.round(at * 1e6) / 1e6;
      requestScene(doc, at);
    }
  });
  $("family-select").addEventListener("change", (e) => loadFamily(e.target.value));
  $("example-select").addEventListener("change", (e) => {
    if (e.target.value) loadExample(e.target.value);
  });
  $("doc-title").addEventListener("input", (e) => {
    const t = e.target.value.trim();
    for (const d of [state.doc, state.latestRequested]) {
      if (!d) continue;
      if (t) d.title = t;
      else delete d.title;
    }
  });
  $("doc-title").addEventListener("keydown", (e) => {
    if (e.key === "Enter") e.target.blur();
  });
  document.addEventListener("keydown", onKey);
  initHistory();
  initShare();
  initOverlays();
  initForces();
  initBuilder();
  initHelp();
  setupTabs();
  new ResizeObserver(() => onResize()).observe($("stage"));
}

async function start() {
  wire();
  try {
    const [families, examples] = await Promise.all([api("/api/families"), api("/api/examples")]);
    state.families = families || [];
    state.examples = examples || [];
    fillChoosers();
  } catch (e) {
    status(e.message, "error");
    return;
  }
  // a shared link, the work kept from a reload, the example the address names, or the default
  await openFirst();
}

if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
else start();

/* linkwright workbench: analysis on the drawing (issue 24, points 5 and 6).
 *
 * Toggles beside "Fit" draw each joint's velocity and acceleration (arrows, scaled so that a
 * typical one is 60 px whatever the zoom) and the instant centres (plane: I12 … with the ones
 * at infinity at the drawing's edge; sphere: the instantaneous axes, as points on the sphere),
 * and show the analysis summary in the parameters column. The server computes every number: a
 * scene carries them when the request asks (`overlays`, `summary`, set through
 * state.sceneFlags), per unit input speed; this module turns them into physical units with the
 * page's length unit (the document's `units`), mass unit and input speed in rpm:
 * v = dP/dθ·ω and a = d²P/dθ²·ω² (constant input speed ω). */

import { $, clone, finite, fmt, okPoint, sizeCanvas, unit3 } from "./util.js";
import { currentPose, emit, requestScene, state, status } from "./pipeline.js";
import { drawing, labelText, projectSphere, requestDraw, sphereGeom, toScreenPlane } from "./draw.js";

const OV_KEY = "linkwright.workbench.overlays";
const OV_LENGTH_UNITS = ["", "mm", "cm", "m", "in", "ft"];
const OV_MASS_UNITS = ["kg", "g", "lb"];
const OV_V_COLOUR = "#0c8599";
const OV_A_COLOUR = "#c2255c";
const OV_C_COLOUR = "#5f3dc4";
const OV_ARROW_PX = 60; // a typical vector's length on screen
const OV_MOST_PX = 180; // none longer: next to a limit position the rates grow without bound

const ovView = {
  velocity: false,
  acceleration: false,
  centres: false,
  summary: false,
  rpm: 60,
  mass: "kg",
  drawn: { velocity: 0, acceleration: 0, centres: 0, axes: 0 },
};

function ovLoad() {
  try {
    const saved = JSON.parse(localStorage.getItem(OV_KEY) || "{}");
    for (const k of ["velocity", "acceleration", "centres", "summary"]) if (typeof saved[k] === "boolean") ovView[k] = saved[k];
    if (finite(saved.rpm) && saved.rpm > 0) ovView.rpm = saved.rpm;
    if (OV_MASS_UNITS.includes(saved.mass)) ovView.mass = saved.mass;
  } catch (e) {
    // storage refused or damaged: the defaults stand
  }
}

function ovSave() {
  try {
    const { velocity, acceleration, centres, summary, rpm, mass } = ovView;
    localStorage.setItem(OV_KEY, JSON.stringify({ velocity, acceleration, centres, summary, rpm, mass }));
  } catch (e) {
    // a page without storage still draws
  }
}

/** What the next scene request asks of the server (read by the scene pipeline). */
function ovFlags() {
  state.sceneFlags = {
    overlays: ovView.velocity || ovView.acceleration || ovView.centres,
    // The analysis takes a few hundred ms: not for every step of a drag, only once it ends
    // (summaryAfterDrag asks again then).
    get summary() {
      return ovView.summary && !dragging();
    },
  };
}

/** A joint is held, or its last drag answer is still on its way. */
function dragging() {
  const pipe = state.dragPipe;
  return !!(state.gesture && state.gesture.kind === "joint") || !!(pipe && (pipe.busy || !pipe.ended));
}

let ovShownSummary = null; // the last summary drawn, kept (faded) while a drag runs
let ovSummaryTimer = null;

/** A scene drawn without the summary that is on (a drag's): ask again once the drag is over. */
function summaryAfterDrag(sc) {
  if (!ovView.summary || !sc || sc.summary || ovSummaryTimer) return;
  ovSummaryTimer = setInterval(() => {
    if (dragging()) return;
    clearInterval(ovSummaryTimer);
    ovSummaryTimer = null;
    if (state.scene && !state.scene.summary && ovView.summary) {
      requestScene(clone(state.latestRequested || state.doc), state.at);
    }
  }, 150);
}

// ------------------------------------------------------------------ units
const inputOmega = () => (ovView.rpm * 2 * Math.PI) / 60; // rad/s of the input

function ovLengthUnit(sc) {
  if (sc && sc.space === "sphere") return "°";
  return (sc && sc.units) || "";
}

/** The input speed the page is set to (rpm, and ω in rad/s) and the length unit of `sc`. */
export function pageSpeed(sc) {
  return { rpm: ovView.rpm, omega: inputOmega(), length: ovLengthUnit(sc) };
}

/** "mm/s" or "°/s" (the sphere: the arc a joint sweeps), or "/s" of the document's lengths. */
export function rateUnit(sc, power) {
  const u = ovLengthUnit(sc);
  const per = power === 2 ? "/s²" : "/s";
  return u ? `${u}${per}` : `length${per}`;
}

/** A vector per unit input speed (radians of input) in the page's physicalSize units. */
export function physicalSize(sc, vec, power) {
  const k = Math.pow(inputOmega(), power) * (sc && sc.space === "sphere" ? 180 / Math.PI : 1);
  let s = 0;
  for (const x of vec) s += x * x;
  return Math.sqrt(s) * k;
}

// ------------------------------------------------------------------ the sample on screen
/** Velocities, accelerations and centres of the pose drawn now (null when none). */
export function overlaySample() {
  const sc = state.scene;
  const ov = sc && sc.overlays;
  if (!ov) return null;
  if (state.exact && ov.pose) return ov.pose;
  if (!state.cur) return ov.pose || null;
  const c = ov.circuits[state.cur.circuit];
  if (!c) return null;
  const i = state.cur.index;
  const pick = (m) => Object.fromEntries(Object.entries(m).map(([k, v]) => [k, v[i]]));
  return {
    velocity: pick(c.velocity),
    acceleration: pick(c.acceleration),
    centres: c.centres[i],
    directions: c.directions ? c.directions[i] : null,
    omega: c.omega[i],
  };
}

// ------------------------------------------------------------------ drawing
/** An arrow from screen point `from` to `to`; false where it is too short to draw. */
export function drawArrow(ctx, from, to, colour, width) {
  const dx = to[0] - from[0];
  const dy = to[1] - from[1];
  const len = Math.hypot(dx, dy);
  if (!(len > 1)) return false;
  const ux = dx / len;
  const uy = dy / len;
  const head = Math.min(9, 0.4 * len);
  ctx.save();
  ctx.strokeStyle = colour;
  ctx.fillStyle = colour;
  ctx.lineWidth = width;
  ctx.lineCap = "round";
  ctx.beginPath();
  ctx.moveTo(from[0], from[1]);
  ctx.lineTo(to[0] - ux * head * 0.8, to[1] - uy * head * 0.8);
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(to[0], to[1]);
  ctx.lineTo(to[0] - ux * head - uy * head * 0.45, to[1] - uy * head + ux * head * 0.45);
  ctx.lineTo(to[0] - ux * head + uy * head * 0.45, to[1] - uy * head - ux * head * 0.45);
  ctx.closePath();
  ctx.fill();
  ctx.restore();
  return true;
}

/** Screen length of a vector of size `size`, given the typical size: OV_ARROW_PX for a typical
 * one, at most OV_MOST_PX. */
function arrowPixels(size, typical) {
  if (!(typical > 0) || !finite(size)) return 0;
  return Math.min(OV_MOST_PX, (OV_ARROW_PX * size) / typical);
}

function drawVectorsPlane(ctx, sc, pose, sample, kind, colour) {
  const typical = sc.overlays.scale[kind];
  const fixed = new Set(sc.fixed || []);
  let n = 0;
  for (const [name, vec] of Object.entries(sample[kind])) {
    const p = pose[name];
    if (fixed.has(name) || !okPoint(p) || !okPoint(vec)) continue;
    const size = Math.hypot(vec[0], vec[1]);
    const px = arrowPixels(size, typical);
    const s = toScreenPlane(p);
    if (drawArrow(ctx, s, [s[0] + (px * vec[0]) / size, s[1] - (px * vec[1]) / size], colour, 2)) n++;
  }
  return n;
}

function centreMark(ctx, x, y, label, primary) {
  ctx.save();
  ctx.strokeStyle = OV_C_COLOUR;
  ctx.lineWidth = 1.6;
  ctx.beginPath();
  ctx.arc(x, y, primary ? 8 : 5, 0, 2 * Math.PI);
  ctx.stroke();
  if (!primary) {
    ctx.beginPath();
    ctx.moveTo(x - 7, y);
    ctx.lineTo(x + 7, y);
    ctx.moveTo(x, y - 7);
    ctx.lineTo(x, y + 7);
    ctx.stroke();
  }
  ctx.restore();
  labelText(ctx, label, x + 9, y + (primary ? 12 : -9), OV_C_COLOUR);
}

/** Where the ray from the canvas's centre along (dx, dy) (screen) leaves it, inset a little. */
function edgePoint(w, h, dx, dy) {
  const cx = w / 2;
  const cy = h / 2;
  const inset = 22;
  const tx = dx ? (dx > 0 ? w - inset - cx : inset - cx) / dx : Infinity;
  const ty = dy ? (dy > 0 ? h - inset - cy : inset - cy) / dy : Infinity;
  const t = Math.min(tx, ty);
  return [cx + t * dx, cy + t * dy];
}

function drawCentresPlane(ctx, sc, sample, w, h) {
  const ov = sc.overlays;
  let n = 0;
  ov.pairs.forEach(([i, j], k) => {
    const label = ov.labels[k];
    const c = sample.centres[k];
    const d = sample.directions ? sample.directions[k] : null;
    const shared = ov.bodies[i].joints.some((x) => ov.bodies[j].joints.includes(x));
    if (okPoint(c)) {
      const s = toScreenPlane(c);
      if (s[0] >= 0 && s[0] <= w && s[1] >= 0 && s[1] <= h) {
        centreMark(ctx, s[0], s[1], label, shared);
      } else {
        // Off the drawing: a mark at its edge, towards it.
        const e = edgePoint(w, h, s[0] - w / 2, s[1] - h / 2);
        const dn = Math.hypot(s[0] - e[0], s[1] - e[1]) || 1;
        drawArrow(ctx, [e[0] - ((s[0] - e[0]) / dn) * 14, e[1] - ((s[1] - e[1]) / dn) * 14], e, OV_C_COLOUR, 1.6);
        labelText(ctx, `${label} (off the drawing)`, e[0], e[1] + (e[1] > h / 2 ? -12 : 12), OV_C_COLOUR, e[0] > w / 2 ? "right" : "left");
      }
      n++;
    } else if (okPoint(d)) {
      // At infinity, along d: marked at the drawing's edge.
      const e = edgePoint(w, h, d[0], -d[1]);
      drawArrow(ctx, [e[0] - d[0] * 14, e[1] + d[1] * 14], e, OV_C_COLOUR, 1.6);
      labelText(ctx, `${label} at ∞`, e[0], e[1] + (e[1] > h / 2 ? -12 : 12), OV_C_COLOUR, e[0] > w / 2 ? "right" : "left");
      n++;
    }
  });
  return n;
}

function drawVectorsSphere(ctx, sc, pose, sample, kind, colour, g) {
  const typical = sc.overlays.scale[kind];
  const fixed = new Set(sc.fixed || []);
  let n = 0;
  for (const [name, vec] of Object.entries(sample[kind])) {
    const p = pose[name];
    if (fixed.has(name) || !Array.isArray(p) || p[0] == null || !vec || vec[0] == null) continue;
    const size = Math.hypot(vec[0], vec[1], vec[2]);
    // Drawn as the tangent step that sweeps its share of a typical arc (0.3 rad).
    const k = typical > 0 ? (0.3 * Math.min(3, size / typical)) / size : 0;
    const a = projectSphere(p, g);
    if (a[2] < 0) continue;
    const b = projectSphere(unit3([p[0] + k * vec[0], p[1] + k * vec[1], p[2] + k * vec[2]]), g);
    if (drawArrow(ctx, a, b, colour, 2)) n++;
  }
  return n;
}

function drawAxesSphere(ctx, sc, sample, g) {
  const ov = sc.overlays;
  let n = 0;
  ov.pairs.forEach((_, k) => {
    const axis = sample.centres[k];
    if (!axis || axis[0] == null) return;
    // An axis meets the sphere at two antipodal points; the one in front is marked.
    let s = projectSphere(axis, g);
    if (s[2] < 0) s = projectSphere(axis.map((x) => -x), g);
    centreMark(ctx, s[0], s[1], ov.labels[k], false);
    n++;
  });
  return n;
}

// Other modules' drawings over the linkage (forces.js's arrows), drawn after these each time.
const ovLayers = [];
export function addOverlayLayer(fn) {
  ovLayers.push(fn);
}

/** Draw the toggled overlays over the drawing just drawn (called by draw.js's drawAll). */
export function drawMotionOverlays() {
  const sc = state.scene;
  const drawn = { velocity: 0, acceleration: 0, centres: 0, axes: 0 };
  const sample = overlaySample();
  const pose = currentPose();
  if (sc && sample && pose) {
    const cv = drawing();
    const { ctx, w, h } = sizeCanvas(cv);
    const sphere = sc.space === "sphere";
    const g = sphere ? sphereGeom() : null;
    if (ovView.centres) {
      if (sphere) drawn.axes = drawAxesSphere(ctx, sc, sample, g);
      else drawn.centres = drawCentresPlane(ctx, sc, sample, w, h);
    }
    for (const [kind, colour] of [["velocity", OV_V_COLOUR], ["acceleration", OV_A_COLOUR]]) {
      if (!ovView[kind]) continue;
      drawn[kind] = sphere
        ? drawVectorsSphere(ctx, sc, pose, sample, kind, colour, g)
        : drawVectorsPlane(ctx, sc, pose, sample, kind, colour);
    }
  }
  ovView.drawn = drawn;
  const cv = drawing();
  cv.dataset.arrows = String(drawn.velocity + drawn.acceleration);
  cv.dataset.centres = String(drawn.centres + drawn.axes);
  for (const layer of ovLayers) layer();
  renderReadout(sc, sample);
}

// ------------------------------------------------------------------ the panel
let ovReadoutSig = "";

function renderReadout(sc, sample) {
  const box = $("motion-readout");
  if (!box) return;
  const on = ovView.velocity || ovView.acceleration;
  const rows = [];
  if (on && sc && sample) {
    const fixed = new Set(sc.fixed || []);
    for (const name of sc.joints || []) {
      if (fixed.has(name)) continue;
      const v = sample.velocity[name];
      const a = sample.acceleration[name];
      const ok = (x) => Array.isArray(x) && x[0] != null;
      rows.push([name, ok(v) ? fmt(physicalSize(sc, v, 1)) : "—", ok(a) ? fmt(physicalSize(sc, a, 2)) : "—"]);
    }
  }
  const head = sc ? [rateUnit(sc, 1), rateUnit(sc, 2)] : ["", ""];
  // Which body each centre's numbers name (I13: bodies 1 and 3), the frame being 1.
  const bodies = ovView.centres && sc && sc.overlays
    ? sc.overlays.bodies.map((b, k) => `${k + 1} ${b.name}`).join(" · ")
    : "";
  const sig = JSON.stringify([on, rows, head, ovView.rpm, bodies]);
  if (sig === ovReadoutSig) return;
  ovReadoutSig = sig;
  box.hidden = !on && !bodies;
  box.replaceChildren();
  if (bodies) {
    const key = document.createElement("p");
    key.className = "note";
    key.dataset.testid = "centre-bodies";
    key.textContent = `${sc.space === "sphere" ? "Axes" : "Centres"} I of bodies ${bodies}`;
    box.append(key);
  }
  if (!on) return;
  const table = document.createElement("table");
  table.innerHTML = `<thead><tr><th>joint</th><th>|v| ${head[0]}</th><th>|a| ${head[1]}</th></tr></thead>`;
  const body = document.createElement("tbody");
  for (const [name, v, a] of rows) {
    const tr = document.createElement("tr");
    tr.dataset.joint = name;
    for (const text of [name, v, a]) {
      const td = document.createElement("td");
      td.textContent = text;
      tr.appendChild(td);
    }
    body.appendChild(tr);
  }
  table.appendChild(body);
  const note = document.createElement("p");
  note.className = "note";
  note.textContent = sc && sc.overlays
    ? `at ${fmt(ovView.rpm)} rpm, constant; a typical arrow (${OV_ARROW_PX} px) is ${fmt(physicalSize(sc, [sc.overlays.scale.velocity || 0], 1))} ${head[0]}`
    : "the velocities arrive with the next scene";
  box.append(table, note);
}

function renderSummary(sc) {
  const box = $("summary-list");
  if (!box) return;
  $("summary-block").hidden = !ovView.summary;
  box.replaceChildren();
  const fresh = sc && sc.summary;
  if (fresh) ovShownSummary = fresh;
  const s = fresh || (dragging() ? ovShownSummary : null);
  box.classList.toggle("stale", !fresh && !!s);
  const note = $("summary-note");
  note.textContent = s && s.note ? s.note : "";
  note.hidden = !(s && s.note);
  if (!s) {
    if (ovView.summary) {
      const dd = document.createElement("dd");
      dd.textContent = "arrives with the next scene";
      box.appendChild(dd);
    }
    return;
  }
  for (const row of s.rows) {
    const dt = document.createElement("dt");
    dt.textContent = row.label;
    const dd = document.createElement("dd");
    dd.textContent = row.text;
    dd.dataset.key = row.key;
    box.append(dt, dd);
  }
}

function renderUnits(sc) {
  const sel = $("length-unit");
  const cur = ovLengthUnit(sc);
  const sphere = !!sc && sc.space === "sphere";
  $("length-unit-label").hidden = sphere;
  const options = OV_LENGTH_UNITS.includes(cur) || sphere ? OV_LENGTH_UNITS : [...OV_LENGTH_UNITS, cur];
  if (sel.dataset.options !== options.join("|")) {
    sel.replaceChildren(
      ...options.map((u) => {
        const o = document.createElement("option");
        o.value = u;
        o.textContent = u || "none";
        return o;
      }),
    );
    sel.dataset.options = options.join("|");
  }
  if (!sphere) sel.value = cur;
  const hasMass = !!(sc && sc.document && sc.document.mechanism && sc.document.mechanism.mass);
  $("mass-unit-label").hidden = !hasMass;
}

function setLengthUnit(unit) {
  const doc = clone(state.latestRequested || state.doc);
  if (!doc) return;
  if (unit) doc.units = unit;
  else delete doc.units;
  // The document's numbers stay: they are in the unit it names, which only the display reads.
  requestScene(doc, state.at).then((sc) => {
    if (sc) status(unit ? `Lengths are in ${unit}` : "Lengths have no unit", "info");
  });
}

function overlayToggle(key, text, title) {
  const b = document.createElement("button");
  b.type = "button";
  b.textContent = text;
  b.title = title;
  b.dataset.overlay = key;
  b.dataset.testid = `toggle-${key}`;
  b.setAttribute("aria-pressed", String(ovView[key]));
  b.addEventListener("mousedown", (e) => e.preventDefault());
  b.addEventListener("click", () => setOverlays({ [key]: !ovView[key] }));
  return b;
}

/** Turn overlays on or off ({velocity, acceleration, centres, summary}); a scene is asked for
 * again where the one shown lacks what was turned on. */
/** The toggles and the input speed, as a link carries them (share.js). */
export function overlayState() {
  const { velocity, acceleration, centres, summary, rpm } = ovView;
  return { velocity, acceleration, centres, summary, rpm };
}

/** Show the toggles and the speed a link carries; anything not of the right kind is ignored. */
export function applyOverlayState(o) {
  if (!o || typeof o !== "object") return Promise.resolve(state.scene);
  if (finite(o.rpm) && o.rpm > 0 && o.rpm <= 1e6 && o.rpm !== ovView.rpm) {
    ovView.rpm = o.rpm;
    const box = $("input-rpm");
    if (box) box.value = String(o.rpm);
    ovReadoutSig = "";
    emit("units", o.rpm);
  }
  const flags = {};
  for (const k of ["velocity", "acceleration", "centres", "summary"]) {
    if (typeof o[k] === "boolean") flags[k] = o[k];
  }
  return setOverlays(flags);
}

export function setOverlays(opts) {
  for (const k of ["velocity", "acceleration", "centres", "summary"]) if (k in opts) ovView[k] = !!opts[k];
  ovSave();
  ovFlags();
  for (const b of document.querySelectorAll("[data-overlay]")) b.setAttribute("aria-pressed", String(ovView[b.dataset.overlay]));
  const sc = state.scene;
  const need = (state.sceneFlags.overlays && !(sc && "overlays" in sc)) || (ovView.summary && !(sc && sc.summary));
  renderSummary(sc);
  requestDraw();
  if (need && sc) return requestScene(clone(state.latestRequested || state.doc), state.at);
  return Promise.resolve(sc);
}

function buildOverlayPanel() {
  const tools = document.querySelector("#drawing-wrap .canvas-tools");
  const group = document.createElement("div");
  group.className = "overlay-toggles";
  group.append(
    overlayToggle("velocity", "v", "velocity of every joint (arrows)"),
    overlayToggle("acceleration", "a", "acceleration of every joint (arrows)"),
    overlayToggle("centres", "IC", "instant centres (on the sphere: the instantaneous axes)"),
    overlayToggle("summary", "Σ", "analysis summary (in the parameters column)"),
  );
  tools.prepend(group);

  const section = document.createElement("section");
  section.id = "overlay-panel";
  section.className = "info-block";
  section.innerHTML = `
    <h3>Units and speed</h3>
    <div class="units-row">
      <label id="length-unit-label">length <select id="length-unit" data-testid="length-unit" aria-label="length unit"></select></label>
      <label>speed <input id="input-rpm" data-testid="input-rpm" type="number" min="0" step="any" aria-label="input speed in rpm"> rpm</label>
      <label id="mass-unit-label" hidden>mass <select id="mass-unit" data-testid="mass-unit" aria-label="mass unit"></select></label>
    </div>
    <div id="motion-readout" data-testid="motion-readout" hidden></div>
    <div id="summary-block" hidden>
      <h3>Analysis</h3>
      <dl id="summary-list" data-testid="summary"></dl>
      <p id="summary-note" class="note" hidden></p>
    </div>`;
  const after = $("limits-block") || $("motion-info");
  after.insertAdjacentElement("afterend", section);
  const mass = $("mass-unit");
  for (const u of OV_MASS_UNITS) {
    const o = document.createElement("option");
    o.value = u;
    o.textContent = u;
    mass.appendChild(o);
  }
  mass.value = ovView.mass;
  mass.addEventListener("change", () => {
    ovView.mass = mass.value;
    ovSave();
  });
  const rpm = $("input-rpm");
  rpm.value = String(ovView.rpm);
  rpm.addEventListener("change", () => {
    const x = Number(rpm.value);
    if (!(finite(x) && x > 0 && x <= 1e6)) {
      rpm.value = String(ovView.rpm);
      status("Input speed: a number of rpm above 0 (at most 1,000,000)", "error");
      return;
    }
    ovView.rpm = x;
    ovSave();
    ovReadoutSig = "";
    emit("units", x);
    requestDraw();
  });
  $("length-unit").addEventListener("change", (e) => setLengthUnit(e.target.value));
}

/** Build the toggles and the panel, and follow the scenes (called once by app.js). */
export function initOverlays() {
  ovLoad();
  ovFlags();
  buildOverlayPanel();
  const hooks = {
    get: () => ({ velocity: ovView.velocity, acceleration: ovView.acceleration, centres: ovView.centres, summary: ovView.summary }),
    set: setOverlays,
    units: () => ({ length: ovLengthUnit(state.scene), mass: ovView.mass, rpm: ovView.rpm, omega: inputOmega() }),
    drawn: () => ({ ...ovView.drawn }),
    sample: () => clone(overlaySample()),
  };
  if (window.lw) window.lw.overlays = hooks;
  if (window.lw) {
    window.lw.on("scene", (sc) => {
      renderUnits(sc);
      renderSummary(sc);
      summaryAfterDrag(sc);
      ovReadoutSig = "";
    });
  }
  const sc = state.scene;
  if (sc) {
    renderUnits(sc);
    renderSummary(sc);
  }
  document.body.dataset.overlaysReady = "1";
  $("summary-block").hidden = !ovView.summary;
}

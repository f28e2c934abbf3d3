/* linkwright workbench: the forces panel (issue 25 point 5; issue 24 point 5's units).
 *
 * A "Forces" section in the parameters column plots the driving torque and each joint's
 * reaction magnitude against the input, with a cursor at the input shown, and an "F" toggle
 * beside "Fit" draws each joint's reaction as an arrow on the drawing (plane and sphere). The
 * server computes the numbers (POST /api/forces) only while the panel is open or the arrows are
 * on, after each scene, at the input speed of the overlays' rpm control (no second control):
 * a separate request, so that a plain edit's redraw costs what it did before. A document
 * without masses gets one line saying how to add them, and a button that gives every link one
 * mass unit through lw.setDocument (an edit like any other: undo takes it back).
 *
 * Units: the document's mass unit (the overlays' mass chooser, kg by default) and length unit;
 * where the length unit is known the numbers are shown in N and N·m. */

import { $, INK2, INK3, SAMPLES, clone, finite, fmt, fmtDeg, mulMV, okPoint, sizeCanvas, tickLabel, ticks } from "./util.js";
import { api, currentPose, state, status } from "./pipeline.js";
import { drawing, projectSphere, requestDraw, sphereGeom, toScreenPlane } from "./draw.js";
import { addOverlayLayer, drawArrow } from "./overlays.js";

const FC_KEY = "linkwright.workbench.forces";
const FC_COLOUR = "#e8590c";
const FC_SERIES = ["#1c7ed6", "#d9480f", "#2b8a3e", "#ae3ec9", "#e67700", "#0c8599", "#5f3dc4", "#c2255c"];
const FC_ARROW_PX = 60; // a typical reaction's arrow on screen
const FC_MOST_PX = 180; // none longer: by a limit position the forces grow without bound
const FC_LENGTH_M = { mm: 1e-3, cm: 1e-2, m: 1, in: 0.0254, ft: 0.3048 };
const FC_MASS_KG = { kg: 1, g: 1e-3, lb: 0.45359237 };

const fcView = {
  open: false,
  arrows: false,
  data: null, // the last answer
  key: "", // the request it answers
  error: null,
  inFlight: null, // the key of the request on its way
  pending: null,
  drawn: 0,
  chartSig: "",
  panelSig: "",
};

function fcLoad() {
  try {
    const saved = JSON.parse(localStorage.getItem(FC_KEY) || "{}");
    if (typeof saved.open === "boolean") fcView.open = saved.open;
    if (typeof saved.arrows === "boolean") fcView.arrows = saved.arrows;
  } catch (e) {
    // storage refused or damaged: closed, no arrows
  }
}

function fcSave() {
  try {
    localStorage.setItem(FC_KEY, JSON.stringify({ open: fcView.open, arrows: fcView.arrows }));
  } catch (e) {
    // a page without storage still works
  }
}

// ------------------------------------------------------------------ speed and units
/** The overlays' speed control and mass chooser (overlays.js owns them). */
function fcPageUnits() {
  const u = window.lw && window.lw.overlays ? window.lw.overlays.units() : null;
  return {
    rpm: u && finite(u.rpm) && u.rpm > 0 ? u.rpm : 60,
    mass: u && typeof u.mass === "string" ? u.mass : "kg",
  };
}

/** How the numbers are shown: N and N·m where the length unit is known, else the document's
 * own units (mass·length/s²), with the factors that turn the server's numbers into them. */
function fcUnits(data) {
  const { mass } = fcPageUnits();
  const len = data && data.units;
  const toM = FC_LENGTH_M[len];
  const toKg = FC_MASS_KG[mass] || 1;
  if (toM) return { force: "N", torque: "N·m", kf: toKg * toM, kt: toKg * toM * toM, known: true };
  return { force: `${mass}·len/s²`, torque: `${mass}·len²/s²`, kf: 1, kt: 1, known: false };
}

// ------------------------------------------------------------------ the server's numbers
const fcWanted = () => fcView.open || fcView.arrows;

// A scene's request, kept while the scene and the speed stay (asked several times a frame).
let fcKeyMemo = { sc: null, rpm: null, key: "" };
function fcRequestKey(sc) {
  const rpm = fcPageUnits().rpm;
  if (fcKeyMemo.sc !== sc || fcKeyMemo.rpm !== rpm) {
    fcKeyMemo = { sc, rpm, key: JSON.stringify([sc.document, rpm, finite(sc.at) ? sc.at : null]) };
  }
  return fcKeyMemo.key;
}

/** The answer, where it is the scene on screen's at the speed set now; else null. */
function fcCurrent() {
  const sc = state.scene;
  if (!sc || !fcView.data || fcView.error) return null;
  return fcView.key === fcRequestKey(sc) ? fcView.data : null;
}

/** Ask for the forces of the scene on screen, unless they are here or on their way. */
function fcRefresh() {
  const sc = state.scene;
  if (fcWanted() && sc && sc.document && sc.modes) {
    const key = fcRequestKey(sc);
    const known = key === fcView.key || key === fcView.inFlight || (fcView.pending && fcView.pending.key === key);
    if (!known) {
      const body = { document: sc.document, speed: fcPageUnits().rpm, samples: SAMPLES, at: finite(sc.at) ? sc.at : null };
      fcView.pending = { key, body };
      fcPump();
    }
  }
  fcRender();
}

// One request in flight, the newest waiting (a drag sends many scenes; only the last counts).
async function fcPump() {
  if (fcView.inFlight || !fcView.pending) return;
  const job = fcView.pending;
  fcView.pending = null;
  fcView.inFlight = job.key;
  fcRender();
  try {
    fcView.data = await api("/api/forces", job.body);
    fcView.error = null;
  } catch (e) {
    fcView.data = null;
    fcView.error = e.message;
  } finally {
    fcView.key = job.key;
    fcView.inFlight = null;
    fcView.chartSig = "";
    fcView.panelSig = "";
    fcRender();
    requestDraw();
    fcPump();
  }
}

// ------------------------------------------------------------------ the sample on screen
function fcPick(table, i) {
  return table ? Object.fromEntries(Object.entries(table).map(([k, v]) => [k, v[i]])) : null;
}

/** The forces at the pose drawn now (null when there are none). */
function fcSample() {
  const d = fcCurrent();
  if (!d || !d.circuits.length) return null;
  if (state.exact && d.pose) return d.pose;
  if (!state.cur) return d.pose || null;
  const c = d.circuits[state.cur.circuit];
  if (!c) return null;
  const i = state.cur.index;
  return {
    input: c.input[i],
    torque: c.torque[i],
    energy_torque: c.energy_torque[i],
    reactions: fcPick(c.reactions, i),
    moments: fcPick(c.moments, i),
  };
}

// ------------------------------------------------------------------ arrows on the drawing
function fcArrow(ctx, from, to) {
  return drawArrow(ctx, from, to, FC_COLOUR, 2.2);
}

const fcPixels = (size, typical) => (typical > 0 && finite(size) ? Math.min(FC_MOST_PX, (FC_ARROW_PX * size) / typical) : 0);

function fcArrows(ctx, d, sample, where) {
  const sphere = d.space === "sphere";
  const g = sphere ? sphereGeom() : null;
  let n = 0;
  for (const [name, vec] of Object.entries(sample.reactions || {})) {
    const p = where[d.where[name] || name];
    if (!Array.isArray(vec) || !vec.every(finite) || !Array.isArray(p) || !p.every(finite)) continue;
    const size = Math.hypot(...vec);
    if (!(size > 0)) continue;
    const px = fcPixels(size, d.scale.force);
    if (sphere) {
      // The force as seen: its component across the line of sight, foreshortened.
      const a = projectSphere(p, g);
      if (a[2] < 0) continue;
      const q = mulMV(state.sphere.R, vec);
      if (fcArrow(ctx, a, [a[0] + (px * q[0]) / size, a[1] - (px * q[1]) / size])) n++;
    } else if (okPoint(p)) {
      const s = toScreenPlane(p);
      if (fcArrow(ctx, s, [s[0] + (px * vec[0]) / size, s[1] - (px * vec[1]) / size])) n++;
    }
  }
  return n;
}

/** Drawn over the linkage after each drawing (overlays.js calls it). */
function fcLayer() {
  const cv = drawing();
  const sample = fcSample();
  let n = 0;
  if (fcView.arrows && sample && !state.sketch) {
    const where = currentPose();
    if (where) n = fcArrows(sizeCanvas(cv).ctx, fcCurrent(), sample, where);
  }
  fcView.drawn = n;
  cv.dataset.forceArrows = String(n);
  if (fcView.open) {
    fcCharts(sample);
    fcReadout(sample);
  }
}

// ------------------------------------------------------------------ charts
/** Series of one chart: {label, colour, dashed, values: per circuit, scale}. */
function fcSeries(d, units) {
  const torque = [
    { label: "Newton–Euler", colour: FC_COLOUR, values: d.circuits.map((c) => c.torque), k: units.kt },
    { label: "energy balance", colour: INK2, dashed: true, values: d.circuits.map((c) => c.energy_torque), k: units.kt },
  ];
  const names = d.circuits.length ? Object.keys(d.circuits[0].reactions) : [];
  const reactions = names.map((name, j) => ({
    label: name,
    colour: FC_SERIES[j % FC_SERIES.length],
    values: d.circuits.map((c) => c.reactions[name].map((v) => (Array.isArray(v) && v.every(finite) ? Math.hypot(...v) : null))),
    k: units.kf,
  }));
  return { torque, reactions };
}

/** The y range: the values' own, but no more than 3× their 95th percentile in size (a limit
 * position's spike would flatten the rest). */
function fcRange(series) {
  const all = [];
  for (const s of series) for (const vs of s.values) for (const v of vs) if (finite(v)) all.push(v * s.k);
  if (!all.length) return null;
  const sizes = all.map(Math.abs).sort((a, b) => a - b);
  const cap = 3 * sizes[Math.min(sizes.length - 1, Math.floor(0.95 * sizes.length))] || 1;
  let lo = Math.max(Math.min(...all), -cap);
  let hi = Math.min(Math.max(...all), cap);
  if (lo > 0) lo = 0;
  if (hi < 0) hi = 0;
  if (!(hi > lo)) {
    hi = lo + 1;
  }
  const pad = 0.06 * (hi - lo);
  return [lo - (lo < 0 ? pad : 0), hi + pad];
}

function fcChart(canvas, d, series, ylabel, cursor) {
  const { ctx, w, h } = sizeCanvas(canvas);
  ctx.clearRect(0, 0, w, h);
  const xs = d.circuits.flatMap((c) => c.input.filter(finite));
  const yr = fcRange(series);
  let points = 0;
  if (!xs.length || !yr) {
    canvas.dataset.points = "0";
    return;
  }
  const L = 46;
  const R = 8;
  const T = 14;
  const B = 18;
  const x0 = Math.min(...xs);
  const x1 = Math.max(...xs) > x0 ? Math.max(...xs) : x0 + 1;
  const X = (x) => L + ((x - x0) / (x1 - x0)) * (w - L - R);
  const Y = (y) => T + ((yr[1] - y) / (yr[1] - yr[0])) * (h - T - B);
  ctx.font = "10px system-ui, sans-serif";
  ctx.fillStyle = INK3;
  ctx.strokeStyle = "#e3e7ec";
  ctx.lineWidth = 1;
  const yt = ticks(yr[0], yr[1], 4);
  const ystep = yt.length > 1 ? yt[1] - yt[0] : 1;
  ctx.textAlign = "right";
  ctx.textBaseline = "middle";
  for (const t of yt) {
    ctx.beginPath();
    ctx.moveTo(L, Y(t));
    ctx.lineTo(w - R, Y(t));
    ctx.stroke();
    ctx.fillText(tickLabel(t, ystep).replace(/^-/, "−"), L - 4, Y(t));
  }
  const xt = ticks(x0, x1, 5, true);
  const xstep = xt.length > 1 ? xt[1] - xt[0] : 1;
  ctx.textAlign = "center";
  ctx.textBaseline = "top";
  for (const t of xt) ctx.fillText(`${tickLabel(t, xstep).replace(/^-/, "−")}°`, X(t), h - B + 4);
  ctx.textAlign = "left";
  ctx.fillText(ylabel, L, 2);
  ctx.save();
  ctx.beginPath();
  ctx.rect(L, T - 2, w - L - R, h - T - B + 4);
  ctx.clip();
  for (const s of series) {
    ctx.strokeStyle = s.colour;
    ctx.lineWidth = s.dashed ? 1 : 1.6;
    ctx.setLineDash(s.dashed ? [4, 3] : []);
    d.circuits.forEach((c, ci) => {
      const vs = s.values[ci];
      ctx.beginPath();
      let open = false;
      c.input.forEach((x, i) => {
        const v = vs[i];
        if (!finite(x) || !finite(v)) {
          open = false;
          return;
        }
        const q = [X(x), Y(v * s.k)];
        if (open) ctx.lineTo(q[0], q[1]);
        else ctx.moveTo(q[0], q[1]);
        open = true;
        if (!s.dashed) points++;
      });
      ctx.stroke();
    });
  }
  ctx.setLineDash([]);
  if (cursor && finite(cursor.x)) {
    ctx.strokeStyle = INK2;
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.moveTo(X(cursor.x), T);
    ctx.lineTo(X(cursor.x), h - B);
    ctx.stroke();
  }
  ctx.restore();
  canvas.dataset.points = String(points);
  canvas.dataset.series = String(series.filter((s) => !s.dashed).length);
}

function fcCharts(sample) {
  const d = fcCurrent() || (fcView.error ? null : fcView.data);
  const torque = $("forces-torque");
  const reactions = $("forces-reactions");
  const stale = !fcCurrent();
  const units = fcUnits(d);
  const cursor = sample && finite(sample.input) ? { x: sample.input } : null;
  const w = torque.clientWidth;
  const sig = JSON.stringify([fcView.key, stale, units.torque, units.kt, cursor, w, fcView.open]);
  if (sig === fcView.chartSig) return;
  fcView.chartSig = sig;
  $("forces-charts").classList.toggle("stale", stale && !!d);
  const has = !!(d && d.circuits && d.circuits.length);
  $("forces-charts").hidden = !has;
  if (!has) {
    torque.dataset.points = "0";
    reactions.dataset.points = "0";
    return;
  }
  const s = fcSeries(d, units);
  fcChart(torque, d, s.torque, `driving torque (${units.torque})`, cursor);
  fcChart(reactions, d, s.reactions, `|reaction| (${units.force})`, cursor);
  const legend = $("forces-legend");
  legend.replaceChildren(
    ...s.reactions.map((r) => {
      const item = document.createElement("span");
      item.style.setProperty("--swatch", r.colour);
      item.textContent = r.label;
      return item;
    }),
  );
}

// ------------------------------------------------------------------ the panel
function fcReadout(sample) {
  const box = $("forces-readout");
  const d = fcCurrent();
  const units = fcUnits(d);
  const rows = [];
  const size = (v, k) => (Array.isArray(v) && v.every(finite) ? fmt(Math.hypot(...v) * k) : "—");
  const moments = d && sample && sample.moments;
  if (d && sample) {
    for (const [name, v] of Object.entries(sample.reactions || {})) {
      rows.push(moments ? [name, size(v, units.kf), size(moments[name], units.kt)] : [name, size(v, units.kf)]);
    }
  }
  const torque = d && sample && finite(sample.torque) ? fmt(sample.torque * units.kt) : "—";
  const sig = JSON.stringify([rows, torque, units.force, sample && sample.input]);
  if (sig === box.dataset.sig) return;
  box.dataset.sig = sig;
  box.replaceChildren();
  if (!d || !sample) return;
  const head = document.createElement("p");
  head.dataset.testid = "forces-torque-now";
  head.dataset.value = String(finite(sample.torque) ? sample.torque * units.kt : "");
  head.textContent = `T = ${torque} ${units.torque} at θ = ${fmtDeg(sample.input)}`;
  const table = document.createElement("table");
  // On the sphere each revolute carries a moment too (the bearing forces are the least-norm set).
  const more = moments ? `<th>|M| ${units.torque}</th>` : "";
  table.innerHTML = `<thead><tr><th>joint</th><th>|R| ${units.force}</th>${more}</tr></thead>`;
  const body = document.createElement("tbody");
  for (const [name, ...text] of rows) {
    const tr = document.createElement("tr");
    tr.dataset.joint = name;
    for (const t of [name, ...text]) {
      const td = document.createElement("td");
      td.textContent = t;
      tr.appendChild(td);
    }
    body.appendChild(tr);
  }
  table.appendChild(body);
  box.append(head, table);
}

/** What the panel shows: closed, loading, no-masses, ready, empty (nothing to compute, or a
 * linkage forces cannot do yet: its message says which), or error. */
function fcStatus() {
  if (!fcView.open) return "closed";
  if (fcView.error && fcView.key === fcRequestKey(state.scene || {})) return "error";
  const d = fcCurrent();
  if (!d) return "loading";
  if (!d.masses && d.links.length && !d.circuits.length) return "no-masses";
  return d.circuits.length ? "ready" : "empty";
}

function fcRender() {
  const section = $("forces-panel");
  if (!section) return;
  const state_ = fcStatus();
  section.dataset.state = state_;
  $("forces-open").setAttribute("aria-expanded", String(fcView.open));
  $("forces-body").hidden = !fcView.open;
  const d = fcCurrent();
  const { mass, rpm } = fcPageUnits();
  const units = fcUnits(d);
  const sig = JSON.stringify([state_, fcView.key, fcView.error, mass, rpm, !!d]);
  if (sig !== fcView.panelSig) {
    fcView.panelSig = sig;
    const msg = $("forces-message");
    let text = "";
    if (state_ === "loading") text = "computing the forces…";
    else if (state_ === "error") text = fcView.error;
    else if (d && d.message) text = d.message;
    msg.textContent = text;
    msg.hidden = !text;
    msg.dataset.kind = state_ === "error" ? "error" : "info";
    const add = $("forces-add-masses");
    add.hidden = !(d && !d.masses && Object.keys(d.suggest || {}).length);
    add.textContent = `Make every link a uniform body of 1 ${mass}`;
    const note = $("forces-suggest-note");
    note.textContent = d && !d.masses && d.suggest_note ? d.suggest_note : "";
    note.hidden = !note.textContent;
    const about = [];
    if (d && d.circuits.length) {
      about.push(d.inertia ? `at ${fmt(rpm)} rpm, constant (the speed above)` : "static: the document has loads.inertia = false");
      if (d.inertia && finite(d.document_speed_rpm) && d.document_speed_rpm !== rpm) {
        about.push(`the document's loads.speed (${fmt(d.document_speed_rpm)} rpm) is replaced by it`);
      }
      if (!units.known) {
        about.push(d.space === "sphere"
          ? "len is the unit of the document's loads.radius (the sphere's radius, 1 unless given)"
          : "lengths have no unit: choose one above to read N and N·m");
      }
      if (d.note) about.push(d.note);
      if (finite(d.scale.force)) about.push(`a typical arrow (${FC_ARROW_PX} px) is ${fmt(d.scale.force * units.kf)} ${units.force}`);
      about.push("arrows: at a ground pivot the frame's force on its link, at a moving joint the force on the link placed later");
    }
    $("forces-note").textContent = about.join("; ");
  }
  fcView.chartSig = "";
  requestDraw();
}

function fcSetOpen(on) {
  fcView.open = !!on;
  fcSave();
  fcRefresh();
}

function fcSetArrows(on) {
  fcView.arrows = !!on;
  fcSave();
  const b = $("toggle-forces");
  if (b) b.setAttribute("aria-pressed", String(fcView.arrows));
  fcRefresh();
}

/** What a share link carries of the panel: whether it is open and the arrows are on. */
export function forcesState() {
  return { open: fcView.open, arrows: fcView.arrows };
}

/** Show a share link's panel state (anything else in `f` is ignored). */
export function applyForcesState(f) {
  if (!f || typeof f !== "object") return;
  if (typeof f.open === "boolean" && f.open !== fcView.open) fcSetOpen(f.open);
  if (typeof f.arrows === "boolean" && f.arrows !== fcView.arrows) fcSetArrows(f.arrows);
}

/** The edit the button makes: every link its suggested mass, through the scene pipeline. */
async function fcAddMasses() {
  const d = fcCurrent();
  const base = clone(state.latestRequested || state.doc);
  if (!d || !base || !base.mechanism) return;
  base.mechanism.mass = clone(d.suggest);
  const opts = { fit: false, at: state.at };
  if (state.exampleName) opts.example = state.exampleName;
  const sc = await window.lw.setDocument(base, opts);
  if (sc) status(`Every link is a uniform body of 1 ${fcPageUnits().mass} (undo takes the masses away)`, "info");
}

function fcBuild() {
  const toggles = document.querySelector("#drawing-wrap .canvas-tools .overlay-toggles");
  const b = document.createElement("button");
  b.type = "button";
  b.id = "toggle-forces";
  b.textContent = "F";
  b.title = "the joints' reaction forces (arrows; the numbers in the Forces panel)";
  b.dataset.testid = "toggle-forces";
  b.setAttribute("aria-pressed", String(fcView.arrows));
  b.addEventListener("mousedown", (e) => e.preventDefault());
  b.addEventListener("click", () => fcSetArrows(!fcView.arrows));
  if (toggles) toggles.appendChild(b);

  const section = document.createElement("section");
  section.id = "forces-panel";
  section.className = "info-block";
  section.dataset.testid = "forces-panel";
  section.innerHTML = `
    <h3><button id="forces-open" data-testid="forces-open" type="button" aria-expanded="false"
      aria-controls="forces-body">Forces</button></h3>
    <div id="forces-body" hidden>
      <p id="forces-message" class="note" data-testid="forces-message" hidden></p>
      <button id="forces-add-masses" data-testid="forces-add-masses" type="button" hidden></button>
      <p id="forces-suggest-note" class="note" hidden></p>
      <div id="forces-readout" data-testid="forces-readout"></div>
      <div id="forces-charts" hidden>
        <div class="forces-chart"><canvas id="forces-torque" data-testid="forces-torque"></canvas></div>
        <div class="forces-chart"><canvas id="forces-reactions" data-testid="forces-reactions"></canvas></div>
        <div id="forces-legend" class="forces-legend"></div>
      </div>
      <p id="forces-note" class="note"></p>
    </div>`;
  const after = $("overlay-panel") || $("limits-block") || $("motion-info");
  after.insertAdjacentElement("afterend", section);
  $("forces-open").addEventListener("click", () => fcSetOpen(!fcView.open));
  $("forces-add-masses").addEventListener("click", fcAddMasses);
  // The overlays' speed and mass unit (their handlers run first: they were added first).
  const rpm = $("input-rpm");
  if (rpm) rpm.addEventListener("change", fcRefresh);
  const mass = $("mass-unit");
  if (mass) mass.addEventListener("change", fcRender);
  new ResizeObserver(() => {
    fcView.chartSig = "";
    requestDraw();
  }).observe(section);
}

/** Build the panel and the toggle, and follow the scenes (called once by app.js). */
export function initForces() {
  fcLoad();
  fcBuild();
  addOverlayLayer(fcLayer);
  const page = window.lw;
  if (page) {
    page.on("scene", fcRefresh);
    page.forces = {
      get: () => ({ open: fcView.open, arrows: fcView.arrows, status: fcStatus() }),
      open: fcSetOpen,
      arrows: fcSetArrows,
      data: () => clone(fcCurrent()),
      sample: () => clone(fcSample()),
      units: () => fcUnits(fcCurrent()),
      drawn: () => fcView.drawn,
    };
  }
  fcRefresh();
  document.body.dataset.forcesReady = "1";
}

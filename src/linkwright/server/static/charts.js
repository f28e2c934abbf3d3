/* linkwright workbench: the motion diagrams (angles, velocity, acceleration) under the drawing,
 * their static layer and the cursor at the current input. */

import {
  $, INK2, INK3, LIMIT_COLOUR, finite, fmt, minus, sizeCanvas, tickLabel, ticks,
} from "./util.js";
import { ownModeIndex, state } from "./pipeline.js";
import { diamond, requestDraw, strokePoly } from "./draw.js";
import { breakJumps } from "./sphere.js";
import { pageSpeed } from "./overlays.js";

// ------------------------------------------------------------------ plots
const seriesColour = (s, k) => (typeof s.color === "string" && /^#[0-9a-fA-F]{3,8}$|^[a-z]+$/.test(s.color) ? s.color : SERIES_COLOURS[k % SERIES_COLOURS.length]);
const SERIES_COLOURS = ["#2f6bd8", "#d9480f", "#2b8a3e", "#ae3ec9", "#e67700", "#0c8599"];

const KIND_NAMES = { angles: "Angles", velocity: "Velocity", acceleration: "Acceleration" };
const RATE_ORDER = { velocity: 1, acceleration: 2 };
// "ω_out/ω_in = φ′ (rad/rad)", "x′ = dx/dθ (length/rad)", "|d²P/dθ²| (length/rad²)": a
// rate per radian of input, the ratio (before " = ") named without its "/ω_in"
const PER_RADIAN = /^(.*?)(?: = .*)? \((rad|length)\/rad²?\)$/;
const BY_INPUT = /\/ω_in²?$/;

/** A velocity or acceleration panel at the page's input speed: each value times ω (ω²), the
 * label in units per second. Panels of other kinds, or labels not per radian, stay as sent. */
function physicalPanel(panel, order, sc) {
  const m = PER_RADIAN.exec(panel.ylabel || "");
  if (!m) return panel;
  const name = BY_INPUT.test(m[1]) ? m[1].replace(BY_INPUT, "") : `${m[1]}·ω${order === 2 ? "²" : ""}`;
  const speed = pageSpeed(sc);
  const k = Math.pow(speed.omega, order);
  const length = speed.length && speed.length !== "°" ? speed.length : "length";
  const unit = `${m[2] === "rad" ? "rad" : length}/s${order === 2 ? "²" : ""}`;
  return {
    ...panel,
    ylabel: `${name} at ${fmt(speed.rpm)} rpm (${unit})`,
    ideal: finite(panel.ideal) ? panel.ideal * k : panel.ideal,
    series: panel.series.map((s) => ({
      ...s,
      values: (s.values || []).map((arr) => (arr || []).map((v) => (finite(v) ? v * k : v))),
    })),
  };
}

let followsSpeed = false;

export function renderCharts(sc) {
  if (!followsSpeed) {
    // a new input speed rescales the charts shown per second
    followsSpeed = true;
    state.listeners.units.push(() => {
      if (!state.chartsPhysical || !state.scene) return;
      renderCharts(state.scene);
      drawChartsCursor();
    });
  }
  const box = $("plots");
  const diags = sc.diagrams || null;
  const entries = [];
  const kinds = [];
  if (diags) {
    const order = ["angles", "velocity", "acceleration"];
    const keys = order.filter((k) => diags[k]).concat(Object.keys(diags).filter((k) => !order.includes(k)));
    for (const key of keys) {
      const d = diags[key];
      if (!d || !Array.isArray(d.panels)) continue;
      kinds.push(key);
      const order = state.chartsPhysical ? RATE_ORDER[key] : 0;
      d.panels.forEach((panel, p) =>
        entries.push({ key, p, x: d.x, panel: order ? physicalPanel(panel, order, sc) : panel }),
      );
    }
  }
  const sig =
    `${state.chartsPhysical}|` +
    entries.map((e) => `${e.key}/${e.p}/${e.panel.ylabel}/${e.panel.series.map((s) => s.label).join(",")}`).join("|");
  if (sig !== state.chartSig) {
    state.chartSig = sig;
    box.innerHTML = "";
    state.charts = [];
    if (!entries.length) {
      const empty = document.createElement("div");
      empty.className = "empty";
      empty.textContent = sc.message || (sc.modes && sc.modes.length ? "No diagrams for this mechanism." : "No diagrams: the linkage does not assemble.");
      box.appendChild(empty);
    } else {
      const bar = document.createElement("div");
      bar.className = "plot-kinds";
      bar.setAttribute("role", "tablist");
      for (const key of kinds) {
        const b = document.createElement("button");
        b.type = "button";
        b.dataset.kind = key;
        b.dataset.testid = `plot-kind-${key}`;
        b.textContent = KIND_NAMES[key] || key;
        b.addEventListener("click", () => showPlotKind(key));
        bar.appendChild(b);
      }
      if (kinds.some((k) => RATE_ORDER[k])) {
        const unit = document.createElement("button");
        unit.type = "button";
        unit.className = "plot-units";
        unit.dataset.testid = "plot-physical";
        unit.setAttribute("aria-pressed", state.chartsPhysical ? "true" : "false");
        unit.textContent = state.chartsPhysical ? "per second" : "per radian";
        unit.title = state.chartsPhysical
          ? "Velocities and accelerations at the input speed set beside the drawing; click for the ratios per radian of input"
          : "Velocities and accelerations as ratios per radian of input; click for physical units at the input speed";
        unit.addEventListener("click", () => {
          state.chartsPhysical = !state.chartsPhysical;
          if (state.scene) renderCharts(state.scene);
          drawChartsCursor();
        });
        bar.appendChild(unit);
      }
      box.appendChild(bar);
    }
    const describe = document.createElement("div");
    describe.className = "describe";
    describe.id = "plots-describe";
    for (const e of entries) {
      const wrap = document.createElement("div");
      wrap.className = "plot";
      wrap.dataset.testid = "plot";
      wrap.dataset.diagram = e.key;
      const title = document.createElement("div");
      title.className = "plot-title";
      const t1 = document.createElement("span");
      title.append(t1);
      const pb = document.createElement("div");
      pb.className = "plot-box";
      const canvas = document.createElement("canvas");
      canvas.id = `plot-${e.key}-${e.p}`;
      canvas.dataset.testid = "plot-canvas";
      pb.appendChild(canvas);
      const note = document.createElement("div");
      note.className = "note";
      wrap.append(title, pb, note);
      box.appendChild(wrap);
      state.charts.push({ canvas, title: t1, note, entry: e, cache: null });
      chartObserver.observe(pb);
    }
    if (entries.length) box.appendChild(describe);
    if (!kinds.includes(state.plotKind)) state.plotKind = kinds[0] || null;
    showPlotKind(state.plotKind, true);
  }
  state.charts.forEach((ch, k) => {
    ch.entry = entries[k];
    ch.cache = null;
    ch.title.textContent = ch.entry.panel.ylabel;
    ch.title.title = ch.entry.panel.ylabel;
    ch.note.textContent = ch.entry.panel.note || "";
    ch.note.hidden = !ch.entry.panel.note;
  });
  const describe = $("plots-describe");
  if (describe) {
    const d = diags && state.plotKind && diags[state.plotKind];
    describe.textContent = d && d.describe ? d.describe : "";
  }
}

function showPlotKind(key, quiet) {
  state.plotKind = key;
  for (const b of $("plots").querySelectorAll(".plot-kinds button")) b.setAttribute("aria-selected", b.dataset.kind === key ? "true" : "false");
  for (const ch of state.charts) ch.canvas.closest(".plot").hidden = ch.entry.key !== key;
  const describe = $("plots-describe");
  const sc = state.scene;
  if (describe && sc && sc.diagrams && sc.diagrams[key]) describe.textContent = sc.diagrams[key].describe || "";
  if (!quiet) drawChartsCursor();
}

/** What tells a panel's series apart, short enough for the cursor's readout. */
function shortLabels(series) {
  const words = series.map((s) => String(s.label || "").split(/\s+/).filter(Boolean));
  if (words.length < 2) return words.map(() => "");
  let common = 0;
  while (words.every((w) => w.length > common + 1 && w[common] === words[0][common])) common++;
  return words.map((w) => (w.join(" ").length <= 10 ? w.join(" ") : w.slice(common, common + 1).join(" ").slice(0, 12)));
}

function chartRange(values, ideal, clip) {
  const all = [];
  for (const arr of values) for (const v of arr) if (finite(v)) all.push(v);
  if (!all.length) return [0, 1];
  all.sort((a, b) => a - b);
  let lo = all[0];
  let hi = all[all.length - 1];
  const q = (f) => all[Math.min(all.length - 1, Math.max(0, Math.round(f * (all.length - 1))))];
  const q1 = q(0.01);
  const q9 = q(0.99);
  // near a limit position a rate runs off to infinity: keep the scale on the bulk
  if (q9 > q1 && hi - lo > 6 * (q9 - q1)) {
    lo = q1 - 0.15 * (q9 - q1);
    hi = q9 + 0.15 * (q9 - q1);
  }
  if (finite(clip) && clip > 0) {
    // the server's own scale for a rate that runs off to infinity at a limit position
    lo = Math.max(lo, -clip);
    hi = Math.min(hi, clip);
  }
  if (finite(ideal) && ideal >= lo - (hi - lo) && ideal <= hi + (hi - lo)) {
    lo = Math.min(lo, ideal);
    hi = Math.max(hi, ideal);
  }
  if (hi - lo < 1e-9 * Math.max(1, Math.abs(hi))) {
    const d = Math.max(1e-6, Math.abs(hi) * 0.1, 1);
    lo -= d;
    hi += d;
  }
  const pad = (hi - lo) * 0.06;
  return [lo - pad, hi + pad];
}

const PL = 46;
const PR = 10;
const PT = 8;
const PB = 22;

function chartGeometry(ch, w, h) {
  const e = ch.entry;
  const xs = [];
  for (const arr of e.x || []) for (const v of arr) if (finite(v)) xs.push(v);
  let x0 = xs.length ? Math.min(...xs) : 0;
  let x1 = xs.length ? Math.max(...xs) : 360;
  if (x1 - x0 < 1e-9) {
    x0 -= 1;
    x1 += 1;
  }
  const vals = [];
  for (const s of e.panel.series) for (const arr of s.values || []) vals.push(arr || []);
  const [y0, y1] = chartRange(vals, e.panel.ideal, e.panel.clip);
  const X = (x) => PL + ((x - x0) / (x1 - x0)) * (w - PL - PR);
  const Y = (y) => PT + ((y1 - y) / (y1 - y0)) * (h - PT - PB);
  return { x0, x1, y0, y1, X, Y };
}

function renderChartStatic(ch) {
  const canvas = ch.canvas;
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, canvas.clientWidth);
  const h = Math.max(1, canvas.clientHeight);
  const off = document.createElement("canvas");
  off.width = Math.round(w * dpr);
  off.height = Math.round(h * dpr);
  const ctx = off.getContext("2d");
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  const geo = chartGeometry(ch, w, h);
  const { x0, x1, y0, y1, X, Y } = geo;
  const e = ch.entry;
  ctx.font = "10px system-ui, sans-serif";
  // grid and ticks
  const xt = ticks(x0, x1, 6, true);
  const yt = ticks(y0, y1, 4, false);
  const ystep = yt.length > 1 ? yt[1] - yt[0] : 1;
  const xstep = xt.length > 1 ? xt[1] - xt[0] : 1;
  ctx.strokeStyle = "#eef1f5";
  ctx.lineWidth = 1;
  ctx.beginPath();
  for (const t of xt) {
    const x = Math.round(X(t)) + 0.5;
    ctx.moveTo(x, PT);
    ctx.lineTo(x, h - PB);
  }
  for (const t of yt) {
    const y = Math.round(Y(t)) + 0.5;
    ctx.moveTo(PL, y);
    ctx.lineTo(w - PR, y);
  }
  ctx.stroke();
  ctx.strokeStyle = "#aab6c4";
  ctx.beginPath();
  ctx.moveTo(PL + 0.5, PT);
  ctx.lineTo(PL + 0.5, h - PB + 0.5);
  ctx.lineTo(w - PR, h - PB + 0.5);
  ctx.stroke();
  ctx.fillStyle = INK3;
  ctx.textAlign = "center";
  ctx.textBaseline = "top";
  for (const t of xt) ctx.fillText(tickLabel(t, xstep), X(t), h - PB + 4);
  ctx.textAlign = "right";
  ctx.textBaseline = "middle";
  for (const t of yt) ctx.fillText(tickLabel(t, ystep), PL - 4, Y(t));
  ctx.textAlign = "right";
  ctx.textBaseline = "bottom";
  ctx.fillText("θ (°)", w - PR, h - PB - 2);
  // the ideal value and the limit positions
  if (finite(e.panel.ideal) && e.panel.ideal >= y0 && e.panel.ideal <= y1) {
    ctx.save();
    ctx.setLineDash([5, 4]);
    ctx.strokeStyle = "#8fb38f";
    ctx.beginPath();
    ctx.moveTo(PL, Y(e.panel.ideal));
    ctx.lineTo(w - PR, Y(e.panel.ideal));
    ctx.stroke();
    ctx.fillStyle = "#5c8a5c";
    ctx.textAlign = "left";
    ctx.textBaseline = "bottom";
    ctx.fillText(`ideal ${fmt(e.panel.ideal)}`, PL + 4, Y(e.panel.ideal) - 1);
    ctx.restore();
  }
  const sc = state.scene;
  const own = ownModeIndex(sc);
  ctx.save();
  ctx.setLineDash([2, 3]);
  ctx.strokeStyle = LIMIT_COLOUR;
  for (const lim of sc.limits || []) {
    if (lim.mode !== own || !finite(lim.input) || lim.input < x0 || lim.input > x1) continue;
    const x = X(lim.input);
    ctx.beginPath();
    ctx.moveTo(x, PT + 6);
    ctx.lineTo(x, h - PB);
    ctx.stroke();
    diamond(ctx, x, PT + 4, 3.5, LIMIT_COLOUR);
  }
  ctx.restore();
  // series
  ctx.save();
  ctx.beginPath();
  ctx.rect(PL, PT, w - PL - PR, h - PT - PB);
  ctx.clip();
  ctx.lineJoin = "round";
  e.panel.series.forEach((s, k) => {
    ctx.strokeStyle = seriesColour(s, k);
    (s.values || []).forEach((arr, c) => {
      const xs = (e.x || [])[c] || [];
      if (!arr) return;
      ctx.lineWidth = 1.6;
      ctx.globalAlpha = state.cur && state.cur.circuit === c ? 1 : 0.45;
      const pts = arr.map((v, i) => (finite(v) && finite(xs[i]) ? [X(xs[i]), Y(v)] : null));
      strokePoly(ctx, breakJumps(pts, (h - PT - PB) * 3));
    });
  });
  ctx.restore();
  // legend
  // with many series the cursor's readout (coloured like the lines) is the legend
  const labels = e.panel.series.map((s) => s.label).filter(Boolean);
  if ((labels.length > 1 && labels.length <= 3) || (labels.length === 1 && labels[0].length <= 24)) {
    ctx.font = "10px system-ui, sans-serif";
    let y = PT + 8;
    const right = w - PR - 4;
    e.panel.series.forEach((s, k) => {
      if (!s.label) return;
      const tw = ctx.measureText(s.label).width;
      ctx.fillStyle = "rgba(255,255,255,0.85)";
      ctx.fillRect(right - tw - 20, y - 6, tw + 22, 12);
      ctx.strokeStyle = seriesColour(s, k);
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.moveTo(right - tw - 18, y);
      ctx.lineTo(right - tw - 6, y);
      ctx.stroke();
      ctx.fillStyle = INK2;
      ctx.textAlign = "right";
      ctx.textBaseline = "middle";
      ctx.fillText(s.label, right, y);
      y += 12;
    });
  }
  ch.cache = { img: off, w, h, dpr, geo };
}

export function drawChartsCursor() {
  for (const ch of state.charts) {
    const canvas = ch.canvas;
    if (!ch.entry || canvas.clientWidth < 2) continue;
    const { ctx, w, h, dpr } = sizeCanvas(canvas);
    if (!ch.cache || ch.cache.w !== w || ch.cache.h !== h || ch.cache.dpr !== dpr) renderChartStatic(ch);
    ctx.clearRect(0, 0, w, h);
    ctx.drawImage(ch.cache.img, 0, 0, w, h);
    const { X, Y, x0, x1, y0, y1 } = ch.cache.geo;
    const c = state.cur ? state.cur.circuit : 0;
    const i = state.cur ? state.cur.index : -1;
    const xs = (ch.entry.x || [])[c] || [];
    let xc = state.exact && finite(state.at) ? state.at : xs[i];
    if (!finite(xc)) xc = state.at;
    if (!finite(xc) || xc < x0 - 1e-9 || xc > x1 + 1e-9) {
      canvas.dataset.cursor = "";
      canvas.dataset.readout = "";
      continue;
    }
    const px = X(xc);
    ctx.save();
    ctx.strokeStyle = "rgba(29,39,51,0.55)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.moveTo(Math.round(px) + 0.5, PT);
    ctx.lineTo(Math.round(px) + 0.5, h - PB);
    ctx.stroke();
    const read = [];
    const short = shortLabels(ch.entry.panel.series);
    ch.entry.panel.series.forEach((s, k) => {
      const v = ((s.values || [])[c] || [])[i];
      if (!finite(v)) return;
      read.push([`${short[k] ? short[k] + " " : ""}${minus(fmt(v, 4))}`, seriesColour(s, k)]);
      if (v < y0 || v > y1) return;
      ctx.beginPath();
      ctx.arc(px, Y(v), 3.2, 0, 2 * Math.PI);
      ctx.fillStyle = seriesColour(s, k);
      ctx.fill();
      ctx.strokeStyle = "#fff";
      ctx.lineWidth = 1;
      ctx.stroke();
    });
    // the values at the cursor, beside it just above the axis
    ctx.font = "600 10.5px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    const widths = read.map(([t]) => ctx.measureText(t).width);
    const cols = read.length > 3 ? 2 : 1;
    const rows = Math.ceil(read.length / cols);
    const colW = Math.max(0, ...widths) + 8;
    const boxW = cols * colW + 4;
    const boxH = rows * 13 + 4;
    const right = px + 8 + boxW <= w - PR;
    const bx = right ? px + 6 : Math.max(PL, px - 6 - boxW);
    const by = h - PB - 4 - boxH;
    if (read.length) {
      ctx.fillStyle = "rgba(255,255,255,0.88)";
      ctx.fillRect(bx, by, boxW, boxH);
      read.forEach(([t, col], k) => {
        ctx.fillStyle = col;
        ctx.textAlign = "left";
        ctx.fillText(t, bx + 5 + colW * Math.floor(k / rows), by + 9 + 13 * (k % rows));
      });
    }
    ctx.restore();
    canvas.dataset.cursor = px.toFixed(1);
    canvas.dataset.cursorInput = String(xc);
    canvas.dataset.readout = read.map(([t]) => t).join(" · ");
  }
}

const chartObserver = new ResizeObserver(() => {
  for (const ch of state.charts) ch.cache = null;
  requestDraw();
});

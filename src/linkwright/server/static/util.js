/* linkwright workbench: small helpers shared by every module (numbers and their text,
 * document paths, axis ticks, canvas sizing, 3×3 rotations). No state, no DOM beyond `$`. */

// ------------------------------------------------------------------ small helpers
export const $ = (id) => document.getElementById(id);
export const SAMPLES = 360;
export const DEG = Math.PI / 180;
export const TRACE_COLOURS = ["#d9480f", "#1c7ed6", "#2b8a3e", "#ae3ec9", "#e67700", "#0c8599"];
export const BODY_COLOURS = ["#3d5a80", "#2a9d8f", "#8d6cab", "#b5651d", "#5c7cfa", "#0b7285", "#c2255c"];
export const MODE_DASHES = [[7, 4], [2, 3], [9, 3, 2, 3], [4, 4], [1, 4]];
export const LIMIT_COLOUR = "#c2410c";
export const INK = "#1d2733";
export const INK2 = "#4a5868";
export const INK3 = "#7c8a9a";

export const clone = (x) => (x === undefined ? undefined : JSON.parse(JSON.stringify(x)));
export const clamp = (v, lo, hi) => Math.max(lo, Math.min(hi, v));
export const finite = (v) => typeof v === "number" && Number.isFinite(v);
export const okPoint = (p) => Array.isArray(p) && p.length >= 2 && finite(p[0]) && finite(p[1]);

/** A number for display: short, no float noise. */
export function fmt(v, digits = 4) {
  if (!finite(v)) return "—";
  if (v === 0) return "0";
  const a = Math.abs(v);
  if (a >= 1e6 || a < 1e-4) return v.toExponential(2);
  return String(parseFloat(v.toFixed(Math.max(0, digits - Math.floor(Math.log10(a)) - 1))));
}
/** A number for an input box: exact enough to round-trip what a person typed. */
export function fmtInput(v) {
  if (!finite(v)) return "";
  return String(parseFloat(v.toPrecision(10)));
}
export const minus = (t) => t.replace(/^-/, "−");
export function fmtDeg(v) {
  return finite(v) ? `${minus(v.toFixed(1))}°` : "—";
}
export const signLabel = (v) => (v > 0 ? "+1" : v < 0 ? "−1" : String(v));

export function getPath(obj, path) {
  let o = obj;
  for (const k of path.split(".")) {
    if (o == null) return undefined;
    o = Array.isArray(o) ? o[Number(k)] : o[k];
  }
  return o;
}
export function setPath(obj, path, value) {
  const keys = path.split(".");
  let o = obj;
  for (let i = 0; i < keys.length - 1; i++) {
    const k = Array.isArray(o) ? Number(keys[i]) : keys[i];
    if (o[k] == null || typeof o[k] !== "object") o[k] = /^\d+$/.test(keys[i + 1]) ? [] : {};
    o = o[k];
  }
  const last = keys[keys.length - 1];
  o[Array.isArray(o) ? Number(last) : last] = value;
}

export function niceStep(range, target) {
  const raw = range / Math.max(1, target);
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / mag;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}
export function ticks(lo, hi, target, angle) {
  if (!(hi > lo)) return [lo];
  let step;
  if (angle && hi - lo >= 20) {
    step = [5, 10, 15, 30, 45, 60, 90, 180, 360].find((s) => (hi - lo) / s <= target) || 360;
  } else step = niceStep(hi - lo, target);
  const out = [];
  for (let t = Math.ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) {
    out.push(Math.abs(t) < step * 1e-9 ? 0 : t);
  }
  return out;
}
export function tickLabel(t, step) {
  const d = step >= 1 ? 0 : Math.min(6, Math.ceil(-Math.log10(step) - 1e-9));
  return Math.abs(t) >= 1e5 ? t.toExponential(1) : t.toFixed(d);
}

/** Size a canvas to its CSS box at the device's pixel ratio; a context in CSS pixels. */
export function sizeCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(1, canvas.clientWidth);
  const h = Math.max(1, canvas.clientHeight);
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const ctx = canvas.getContext("2d");
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  return { ctx, w, h, dpr };
}

// 3-vectors and 3×3 matrices (row-major arrays of 9) for the sphere view
export const dot3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross3 = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm3 = (a) => Math.hypot(a[0], a[1], a[2]);
export const unit3 = (a) => {
  const n = norm3(a) || 1;
  return [a[0] / n, a[1] / n, a[2] / n];
};
export const mulMV = (m, v) => [
  m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
  m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
  m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
];
export const mulMtV = (m, v) => [
  m[0] * v[0] + m[3] * v[1] + m[6] * v[2],
  m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
  m[2] * v[0] + m[5] * v[1] + m[8] * v[2],
];
export function mulMM(a, b) {
  const r = new Array(9);
  for (let i = 0; i < 3; i++)
    for (let j = 0; j < 3; j++) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
  return r;
}
export const rotX = (a) => [1, 0, 0, 0, Math.cos(a), -Math.sin(a), 0, Math.sin(a), Math.cos(a)];
export const rotY = (a) => [Math.cos(a), 0, Math.sin(a), 0, 1, 0, -Math.sin(a), 0, Math.cos(a)];
/** Re-orthonormalise a rotation so that many small turns do not drift. */
export function orthonormal(m) {
  const x = unit3([m[0], m[1], m[2]]);
  const z = unit3(cross3(x, [m[3], m[4], m[5]]));
  const y = cross3(z, x);
  return [...x, ...y, ...z];
}
/** Points along the great-circle arc from a to b (both unit vectors). */
export function slerp(a, b, n) {
  const c = clamp(dot3(a, b), -1, 1);
  const w = Math.acos(c);
  const out = [];
  for (let k = 0; k <= n; k++) {
    const t = k / n;
    if (w < 1e-6) out.push(unit3([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]));
    else {
      const s = Math.sin(w);
      const p = Math.sin((1 - t) * w) / s;
      const q = Math.sin(t * w) / s;
      out.push([p * a[0] + q * b[0], p * a[1] + q * b[1], p * a[2] + q * b[2]]);
    }
  }
  return out;
}

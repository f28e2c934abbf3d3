/* linkwright workbench: the drawing's views (plane fit, sphere projection) and the planar
 * drawing: grid, guides, bodies, joints, curves and limit marks. */

import {
  $, BODY_COLOURS, INK, INK2, INK3, LIMIT_COLOUR, TRACE_COLOURS, cross3, dot3, finite, fmt, mulMM,
  mulMV, mulMtV, niceStep, okPoint, orthonormal, rotX, rotY, sizeCanvas, unit3,
} from "./util.js";
import { currentPose, ownModeIndex, samplePose, sceneScale, state } from "./pipeline.js";
import { modeStyle, ownLimits } from "./panels.js";
import { drawMap, drawSphere } from "./sphere.js";
import { drawChartsCursor } from "./charts.js";
import { drawMotionOverlays } from "./overlays.js";
import { drawBuilder } from "./builder.js";

// ------------------------------------------------------------------ views
export const drawing = () => $("drawing");

export function layoutStage() {
  const sc = state.scene;
  const building = !!state.sketch;
  const sphere = building ? state.sketch.space === "sphere" : !!sc && sc.space === "sphere";
  $("map-wrap").hidden = !sphere || building;
  const stage = $("stage");
  stage.classList.toggle("column", sphere && stage.clientHeight > stage.clientWidth * 0.95);
  drawing().dataset.view = sphere ? "sphere" : "plane";
  if (building) return; // the builder's hint names its tool
  $("hint").textContent = sphere
    ? "drag a joint to move it · drag the sphere to turn it · wheel: zoom"
    : "drag a joint to move it · drag empty space to pan · wheel: zoom";
}

function planeBounds(sc) {
  let x0 = Infinity;
  let y0 = Infinity;
  let x1 = -Infinity;
  let y1 = -Infinity;
  const add = (p) => {
    if (!okPoint(p)) return;
    x0 = Math.min(x0, p[0]);
    y0 = Math.min(y0, p[1]);
    x1 = Math.max(x1, p[0]);
    y1 = Math.max(y1, p[1]);
  };
  const own = ownModeIndex(sc);
  (sc.modes || []).forEach((mode, m) => {
    for (const circ of mode.circuits) {
      for (const [name, arr] of Object.entries(circ.positions)) {
        if (m !== own && !(sc.traced || []).includes(name)) continue;
        for (const p of arr) add(p);
      }
    }
  });
  if (sc.pose) for (const p of Object.values(sc.pose)) add(p);
  for (const g of sc.guides || []) if (okPoint(g.point)) add(g.point);
  if (!(x1 >= x0)) return [-1, -1, 1, 1];
  return [x0, y0, x1, y1];
}

export function fitPlane() {
  const sc = state.scene;
  const cv = drawing();
  const w = cv.clientWidth;
  const h = cv.clientHeight;
  if (!sc || w < 10 || h < 10) return;
  const [x0, y0, x1, y1] = planeBounds(sc);
  const bw = Math.max(x1 - x0, 1e-9);
  const bh = Math.max(y1 - y0, 1e-9);
  const padTop = 34;
  const padBottom = 40;
  const s = Math.min((w - 90) / bw, (h - 30 - padTop - padBottom) / bh);
  const v = state.view;
  v.s = finite(s) && s > 0 ? s : 50;
  v.ox = w / 2 - v.s * (x0 + x1) / 2;
  v.oy = (h + padTop - padBottom) / 2 + v.s * (y0 + y1) / 2;
  v.fitted = true;
  v.moved = false;
}

export const toScreenPlane = (p) => [state.view.ox + state.view.s * p[0], state.view.oy - state.view.s * p[1]];
export const fromScreenPlane = (q) => [(q[0] - state.view.ox) / state.view.s, (state.view.oy - q[1]) / state.view.s];

export function sphereGeom() {
  const cv = drawing();
  const w = cv.clientWidth;
  const h = cv.clientHeight;
  // Keep the sphere clear of the legend in the top-left corner: beside it when there is
  // room, else below it (a little smaller).
  const lg = $("legend");
  const lw_ = lg.childElementCount ? lg.offsetLeft + lg.offsetWidth : 0;
  const lb = lg.childElementCount ? lg.offsetTop + lg.offsetHeight : 0;
  let r = 0.42 * Math.min(w, h);
  let cx = w / 2;
  let cy = h / 2;
  if (lb && w - lw_ - 16 < 2 * r) {
    const below = (h - lb - 26) / 2;
    if (below >= 0.3 * Math.min(w, h)) {
      r = Math.min(r, below);
      cy = lb + 6 + r;
    }
  } else if (lb) cx = Math.max(w / 2, lw_ + 8 + r);
  return { cx, cy, r: r * state.sphere.zoom };
}
export function projectSphere(p, g) {
  const q = mulMV(state.sphere.R, unit3(p));
  return [g.cx + g.r * q[0], g.cy - g.r * q[1], q[2]];
}
export function unprojectSphere(px, py) {
  const g = sphereGeom();
  let x = (px - g.cx) / g.r;
  let y = -(py - g.cy) / g.r;
  const s = x * x + y * y;
  let z = 0;
  if (s > 1) {
    const n = Math.sqrt(s);
    x /= n;
    y /= n;
  } else z = Math.sqrt(1 - s);
  return unit3(mulMtV(state.sphere.R, [x, y, z]));
}

export function resetSphere(sc) {
  // Look at the map's centre (the mechanism) with the frame's +z up, then tilt a little
  // so that the sphere reads as a solid.
  let f = sc && Array.isArray(sc.map_center) ? unit3(sc.map_center) : [0.6, 0.5, 0.6];
  let up = [0, 0, 1];
  if (Math.abs(dot3(up, f)) > 0.95) up = [0, 1, 0];
  const right = unit3(cross3(up, f));
  const u = cross3(f, right);
  const base = [...right, ...u, ...f];
  state.sphere.R = orthonormal(mulMM(mulMM(rotX(0.32), rotY(-0.38)), base));
  state.sphere.zoom = 1;
}

export function toScreen(p) {
  const sc = state.scene;
  if (sc && sc.space === "sphere" && Array.isArray(p) && p.length >= 3) {
    const q = projectSphere(p, sphereGeom());
    return [q[0], q[1]];
  }
  return toScreenPlane(p);
}

// ------------------------------------------------------------------ drawing: common
let drawQueued = false;
export function requestDraw() {
  if (drawQueued) return;
  drawQueued = true;
  requestAnimationFrame(() => {
    drawQueued = false;
    drawAll();
  });
}

// The dashed ring under the pointer while a joint is dragged (plane and sphere alike).
export function drawDragPointer(ctx) {
  if (!(state.gesture && state.gesture.kind === "joint" && state.gesture.mouse)) return;
  const [x, y] = state.gesture.mouse;
  ctx.save();
  ctx.strokeStyle = "rgba(47,107,216,0.8)";
  ctx.setLineDash([3, 3]);
  ctx.beginPath();
  ctx.arc(x, y, 9, 0, 2 * Math.PI);
  ctx.stroke();
  ctx.restore();
}

export function drawAll() {
  const sc = state.scene;
  const msg = $("canvas-message");
  if (state.sketch) {
    msg.hidden = true;
    drawBuilder();
    drawChartsCursor();
    return;
  }
  if (sc && (!sc.modes || !sc.modes.length || (!state.cur && !sc.pose))) {
    msg.textContent = sc.message || "This linkage does not assemble at any input.";
    msg.hidden = false;
  } else msg.hidden = true;
  if (sc && sc.space === "sphere") {
    drawSphere();
    drawMap();
  } else drawPlane();
  drawMotionOverlays();
  drawChartsCursor();
}

export function strokePoly(ctx, pts) {
  // pts: screen points, null = a break
  let open = false;
  ctx.beginPath();
  for (const p of pts) {
    if (!p) {
      open = false;
      continue;
    }
    if (!open) {
      ctx.moveTo(p[0], p[1]);
      open = true;
    } else ctx.lineTo(p[0], p[1]);
  }
  ctx.stroke();
}

export function labelText(ctx, text, x, y, colour, align) {
  ctx.font = "600 12px system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif";
  ctx.textAlign = align || "left";
  ctx.textBaseline = "middle";
  ctx.lineWidth = 3.5;
  ctx.strokeStyle = "rgba(255,255,255,0.92)";
  ctx.lineJoin = "round";
  ctx.strokeText(text, x, y);
  ctx.fillStyle = colour || INK2;
  ctx.fillText(text, x, y);
}

export function diamond(ctx, x, y, r, fill, stroke) {
  ctx.beginPath();
  ctx.moveTo(x, y - r);
  ctx.lineTo(x + r, y);
  ctx.lineTo(x, y + r);
  ctx.lineTo(x - r, y);
  ctx.closePath();
  ctx.fillStyle = fill;
  ctx.fill();
  if (stroke) {
    ctx.strokeStyle = stroke;
    ctx.lineWidth = 1.2;
    ctx.stroke();
  }
}

function tracedCurve(circ, name) {
  return circ.positions[name] || null;
}

/** Where each limit position is marked: the first traced point (else the first moving joint). */
function limitAnchor(sc) {
  const fixed = new Set(sc.fixed || []);
  return (sc.traced || [])[0] || (sc.joints || []).find((j) => !fixed.has(j)) || null;
}

export function limitPose(sc, k) {
  const lim = (sc.limits || [])[k];
  if (!lim || !sc.modes[lim.mode] || !sc.modes[lim.mode].circuits[lim.circuit]) return null;
  return samplePose(sc, lim.mode, lim.circuit, lim.index);
}

// ------------------------------------------------------------------ drawing: plane
export function drawGrid(ctx, w, h) {
  const v = state.view;
  const step = niceStep(90 / v.s, 1);
  const [mx0, my1] = fromScreenPlane([0, 0]);
  const [mx1, my0] = fromScreenPlane([w, h]);
  ctx.lineWidth = 1;
  ctx.strokeStyle = "#eef1f5";
  ctx.beginPath();
  for (let x = Math.ceil(mx0 / step) * step; x <= mx1; x += step) {
    const sx = Math.round(toScreenPlane([x, 0])[0]) + 0.5;
    ctx.moveTo(sx, 0);
    ctx.lineTo(sx, h);
  }
  for (let y = Math.ceil(my0 / step) * step; y <= my1; y += step) {
    const sy = Math.round(toScreenPlane([0, y])[1]) + 0.5;
    ctx.moveTo(0, sy);
    ctx.lineTo(w, sy);
  }
  ctx.stroke();
  const o = toScreenPlane([0, 0]);
  ctx.strokeStyle = "#dfe5ec";
  ctx.beginPath();
  ctx.moveTo(0, Math.round(o[1]) + 0.5);
  ctx.lineTo(w, Math.round(o[1]) + 0.5);
  ctx.moveTo(Math.round(o[0]) + 0.5, 0);
  ctx.lineTo(Math.round(o[0]) + 0.5, h);
  ctx.stroke();
  // scale bar
  const units = (state.scene && state.scene.units) || "";
  const px = step * v.s;
  ctx.strokeStyle = INK3;
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  ctx.moveTo(w - 16 - px, h - 14);
  ctx.lineTo(w - 16, h - 14);
  ctx.moveTo(w - 16 - px, h - 18);
  ctx.lineTo(w - 16 - px, h - 10);
  ctx.moveTo(w - 16, h - 18);
  ctx.lineTo(w - 16, h - 10);
  ctx.stroke();
  ctx.fillStyle = INK3;
  ctx.font = "11px system-ui, sans-serif";
  ctx.textAlign = "center";
  ctx.textBaseline = "bottom";
  ctx.fillText(`${fmt(step)}${units ? " " + units : ""}`, w - 16 - px / 2, h - 17);
}

export function groundSymbol(ctx, x, y) {
  ctx.save();
  ctx.strokeStyle = "#5b6775";
  ctx.fillStyle = "#eef1f4";
  ctx.lineWidth = 1.3;
  ctx.beginPath();
  ctx.moveTo(x, y);
  ctx.lineTo(x - 8, y + 13);
  ctx.lineTo(x + 8, y + 13);
  ctx.closePath();
  ctx.fill();
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(x - 13, y + 13);
  ctx.lineTo(x + 13, y + 13);
  for (let k = -12; k <= 12; k += 5) {
    ctx.moveTo(x + k + 1, y + 13);
    ctx.lineTo(x + k - 4, y + 19);
  }
  ctx.stroke();
  ctx.restore();
}

function guidePoint(g, pose) {
  if (okPoint(g.point)) return g.point;
  const p = g.through && pose ? pose[g.through] : null;
  return okPoint(p) ? p : null;
}

function sliderJoints(sc, guide) {
  if (Array.isArray(guide.sliders)) return guide.sliders;
  // A joint that stays on the guide line for the whole own-mode motion slides on it.
  const m = ownModeIndex(sc);
  if (m < 0) return [];
  const d = guide.direction;
  const n = Math.hypot(d[0], d[1]) || 1;
  const nx = -d[1] / n;
  const ny = d[0] / n;
  const tol = 1e-6 * sceneScale(sc) + 1e-9;
  const fixed = new Set(sc.fixed || []);
  const out = [];
  for (const name of sc.joints || []) {
    if (fixed.has(name)) continue;
    let on = true;
    let seen = 0;
    for (const circ of sc.modes[m].circuits) {
      const arr = circ.positions[name] || [];
      for (let i = 0; i < arr.length && on; i += 7) {
        const p = arr[i];
        if (!okPoint(p)) continue;
        seen++;
        if (Math.abs((p[0] - guide._point[0]) * nx + (p[1] - guide._point[1]) * ny) > tol) on = false;
      }
    }
    if (on && seen) out.push(name);
  }
  return out;
}

function drawGuides(ctx, sc, pose) {
  const m = ownModeIndex(sc);
  for (const g of sc.guides || []) {
    g._point = guidePoint(g, pose);
    if (!g._point || !okPoint(g.direction)) continue;
    const dn = Math.hypot(g.direction[0], g.direction[1]) || 1;
    const d = [g.direction[0] / dn, g.direction[1] / dn];
    const sliders = sliderJoints(sc, g);
    g._sliders = sliders;
    let t0 = Infinity;
    let t1 = -Infinity;
    const proj = (p) => (p[0] - g._point[0]) * d[0] + (p[1] - g._point[1]) * d[1];
    if (m >= 0)
      for (const circ of sc.modes[m].circuits)
        for (const name of sliders)
          for (const p of circ.positions[name] || []) {
            if (!okPoint(p)) continue;
            const t = proj(p);
            t0 = Math.min(t0, t);
            t1 = Math.max(t1, t);
          }
    if (!(t1 >= t0)) {
      t0 = 0;
      t1 = 0;
    }
    const pad = Math.max(0.25 * (t1 - t0), 40 / state.view.s);
    t0 -= pad;
    t1 += pad;
    const a = toScreenPlane([g._point[0] + t0 * d[0], g._point[1] + t0 * d[1]]);
    const b = toScreenPlane([g._point[0] + t1 * d[0], g._point[1] + t1 * d[1]]);
    const len = Math.hypot(b[0] - a[0], b[1] - a[1]) || 1;
    const ux = (b[0] - a[0]) / len;
    const uy = (b[1] - a[1]) / len;
    // hatch below the line (screen normal pointing down-ish), offset past the slider block
    let nx = -uy;
    let ny = ux;
    if (ny < 0) {
      nx = -nx;
      ny = -ny;
    }
    ctx.save();
    ctx.strokeStyle = "#5b6775";
    ctx.lineWidth = 1.4;
    const off = 7;
    ctx.beginPath();
    ctx.moveTo(a[0] + nx * off, a[1] + ny * off);
    ctx.lineTo(b[0] + nx * off, b[1] + ny * off);
    ctx.stroke();
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let s = 0; s <= len; s += 8) {
      const x = a[0] + ux * s + nx * off;
      const y = a[1] + uy * s + ny * off;
      ctx.moveTo(x, y);
      ctx.lineTo(x + nx * 6 - ux * 5, y + ny * 6 - uy * 5);
    }
    ctx.stroke();
    ctx.setLineDash([4, 4]);
    ctx.strokeStyle = "#b0bac5";
    ctx.beginPath();
    ctx.moveTo(a[0], a[1]);
    ctx.lineTo(b[0], b[1]);
    ctx.stroke();
    ctx.restore();
  }
}

function drawSliderBlocks(ctx, sc, pose) {
  for (const g of sc.guides || []) {
    if (!g._sliders || !okPoint(g.direction)) continue;
    const ang = Math.atan2(-g.direction[1], g.direction[0]);
    for (const name of g._sliders) {
      const p = pose[name];
      if (!okPoint(p)) continue;
      const s = toScreenPlane(p);
      ctx.save();
      ctx.translate(s[0], s[1]);
      ctx.rotate(ang);
      ctx.fillStyle = "#e3e9f2";
      ctx.strokeStyle = "#3d5a80";
      ctx.lineWidth = 1.5;
      ctx.beginPath();
      ctx.rect(-15, -7, 30, 14);
      ctx.fill();
      ctx.stroke();
      ctx.restore();
    }
  }
}

function drawBodiesPlane(ctx, sc, pose, ghost) {
  const fixed = new Set(sc.fixed || []);
  (sc.bodies || []).forEach((body, k) => {
    const pts = body.joints.map((j) => pose[j]).filter(okPoint).map(toScreenPlane);
    if (pts.length < 2) return;
    const col = BODY_COLOURS[k % BODY_COLOURS.length];
    ctx.save();
    if (ghost) ctx.globalAlpha = 0.35;
    if (body.ground) {
      ctx.strokeStyle = "#9aa5b1";
      ctx.lineWidth = 1.2;
      ctx.setLineDash([6, 4]);
      ctx.beginPath();
      pts.forEach((p, i) => (i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      if (pts.length > 2) ctx.closePath();
      ctx.stroke();
    } else if (pts.length === 2) {
      ctx.lineCap = "round";
      ctx.strokeStyle = col;
      ctx.lineWidth = ghost ? 3 : 5;
      ctx.beginPath();
      ctx.moveTo(pts[0][0], pts[0][1]);
      ctx.lineTo(pts[1][0], pts[1][1]);
      ctx.stroke();
    } else {
      ctx.lineJoin = "round";
      ctx.fillStyle = col + "30";
      ctx.strokeStyle = col;
      ctx.lineWidth = ghost ? 2 : 3;
      ctx.beginPath();
      pts.forEach((p, i) => (i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      ctx.closePath();
      ctx.fill();
      ctx.stroke();
    }
    ctx.restore();
  });
  if (ghost) return;
  const inBody = bodyJoints(sc);
  for (const name of fixed) if (okPoint(pose[name]) && inBody.has(name)) groundSymbol(ctx, ...toScreenPlane(pose[name]));
}

function bodyJoints(sc) {
  const out = new Set();
  for (const b of sc.bodies || []) for (const j of b.joints) out.add(j);
  return out;
}

function jointCentroid(pose, project) {
  let sx = 0;
  let sy = 0;
  let n = 0;
  for (const p of Object.values(pose)) {
    if (!p || p[0] == null) continue;
    const s = project(p);
    sx += s[0];
    sy += s[1];
    n++;
  }
  return n ? [sx / n, sy / n] : [0, 0];
}

export function drawJoints(ctx, sc, pose, project, faded) {
  const fixed = new Set(sc.fixed || []);
  const traced = sc.traced || [];
  const handles = new Set(sc.handles || []);
  const c = jointCentroid(pose, project);
  const inBody = bodyJoints(sc);
  for (const name of sc.joints || Object.keys(pose)) {
    const p = pose[name];
    if (!p || p[0] == null) continue;
    const s = project(p);
    const back = faded && faded(p);
    const k = traced.indexOf(name);
    ctx.save();
    if (back) ctx.globalAlpha = 0.35;
    const hover = state.hoverHandle === name || (state.gesture && state.gesture.joint === name);
    if (hover && handles.has(name)) {
      ctx.beginPath();
      ctx.arc(s[0], s[1], 11, 0, 2 * Math.PI);
      ctx.fillStyle = "rgba(47,107,216,0.15)";
      ctx.fill();
    }
    ctx.beginPath();
    const loose = fixed.has(name) && !inBody.has(name) && k < 0;
    if (loose) ctx.rect(s[0] - 3.5, s[1] - 3.5, 7, 7);
    else ctx.arc(s[0], s[1], fixed.has(name) ? 5 : 4.5, 0, 2 * Math.PI);
    ctx.fillStyle = k >= 0 ? TRACE_COLOURS[k % TRACE_COLOURS.length] : "#fff";
    ctx.fill();
    ctx.lineWidth = loose ? 1.2 : 1.7;
    ctx.strokeStyle = k >= 0 ? "#fff" : loose ? INK3 : INK;
    ctx.stroke();
    if (k >= 0) {
      ctx.beginPath();
      ctx.arc(s[0], s[1], 6.2, 0, 2 * Math.PI);
      ctx.strokeStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
      ctx.lineWidth = 1.2;
      ctx.stroke();
    }
    let dx = s[0] - c[0];
    let dy = s[1] - c[1];
    const dn = Math.hypot(dx, dy);
    if (dn < 1e-6) {
      dx = 0.7;
      dy = -0.7;
    } else {
      dx /= dn;
      dy /= dn;
    }
    if (fixed.has(name) && dy > 0.2) dx = dx >= 0 ? 1 : -1; // keep clear of the ground hatch
    const lx = s[0] + dx * 13;
    const ly = s[1] + (fixed.has(name) && dy > 0 ? 0 : dy * 13);
    labelText(ctx, name, lx, ly, k >= 0 ? TRACE_COLOURS[k % TRACE_COLOURS.length] : INK2, dx < -0.3 ? "right" : dx > 0.3 ? "left" : "center");
    ctx.restore();
  }
}

function drawOverlaysPlane(ctx) {
  for (const ov of state.overlays.values()) {
    const st = ov.style || {};
    ctx.save();
    ctx.strokeStyle = st.color || "#868e96";
    ctx.lineWidth = st.width || 1.5;
    ctx.setLineDash(st.dash || []);
    ctx.globalAlpha = st.alpha == null ? 1 : st.alpha;
    for (const curve of ov.curves || []) {
      strokePoly(ctx, curve.map((p) => (okPoint(p) ? toScreenPlane(p) : null)));
    }
    ctx.restore();
  }
}

export function drawPick(ctx, project) {
  if (!state.pick || !state.pick.points || state.pick.points.length < 2) return;
  ctx.save();
  ctx.strokeStyle = "#212529";
  ctx.lineWidth = 2;
  ctx.setLineDash([5, 3]);
  strokePoly(ctx, state.pick.points.map(project));
  ctx.restore();
}

function drawPlane() {
  const cv = drawing();
  const { ctx, w, h } = sizeCanvas(cv);
  ctx.clearRect(0, 0, w, h);
  const sc = state.scene;
  if (!sc) return;
  if (!state.view.fitted) fitPlane();
  drawGrid(ctx, w, h);
  drawGuides(ctx, sc, currentPose());
  const own = ownModeIndex(sc);
  const traced = sc.traced || [];
  // the other modes first, thin and dashed
  (sc.modes || []).forEach((mode, m) => {
    if (m === own) return;
    const st = modeStyle(sc, m);
    ctx.save();
    ctx.setLineDash(st.dash);
    ctx.lineWidth = 1.2;
    ctx.globalAlpha = 0.75;
    traced.forEach((name, k) => {
      ctx.strokeStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
      for (const circ of mode.circuits) {
        const arr = tracedCurve(circ, name);
        if (arr) strokePoly(ctx, closeIf(circ, arr.map((p) => (okPoint(p) ? toScreenPlane(p) : null))));
      }
    });
    ctx.restore();
  });
  if (own >= 0) {
    ctx.save();
    ctx.lineJoin = "round";
    traced.forEach((name, k) => {
      ctx.strokeStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
      sc.modes[own].circuits.forEach((circ, c) => {
        const arr = tracedCurve(circ, name);
        if (!arr) return;
        ctx.lineWidth = 2.6;
        ctx.globalAlpha = state.cur && state.cur.circuit === c ? 1 : 0.45;
        strokePoly(ctx, closeIf(circ, arr.map((p) => (okPoint(p) ? toScreenPlane(p) : null))));
      });
    });
    ctx.restore();
  }
  drawOverlaysPlane(ctx);
  const pose = currentPose();
  if (state.hoverLimit != null) {
    const gp = limitPose(sc, state.hoverLimit);
    if (gp) drawBodiesPlane(ctx, sc, gp, true);
  }
  drawLimitMarks(ctx, sc, (p) => (okPoint(p) ? toScreenPlane(p) : null));
  if (pose) {
    drawBodiesPlane(ctx, sc, pose, false);
    drawSliderBlocks(ctx, sc, pose);
    drawJoints(ctx, sc, pose, toScreenPlane, null);
  }
  drawDragPointer(ctx);
  drawPick(ctx, toScreenPlane);
}

export function closeIf(circ, pts) {
  if (circ.full && pts.length > 2 && pts[0] && pts[pts.length - 1]) return pts.concat([pts[0]]);
  return pts;
}

export function drawLimitMarks(ctx, sc, project) {
  state.limitMarks = [];
  const anchor = limitAnchor(sc);
  if (!anchor) return;
  const own = ownModeIndex(sc);
  ownLimits(sc).forEach(([lim, k], n) => {
    const mode = sc.modes[lim.mode];
    if (!mode || !mode.circuits[lim.circuit]) return;
    const p = (mode.circuits[lim.circuit].positions[anchor] || [])[lim.index];
    const s = p ? project(p) : null;
    if (!s) return;
    const hot = state.hoverLimit === k;
    ctx.save();
    if (s[2] != null && s[2] < 0) ctx.globalAlpha = 0.4;
    diamond(ctx, s[0], s[1], hot ? 8 : 6, lim.mode === own ? LIMIT_COLOUR : "#f0a27a", "#fff");
    ctx.font = "700 10px system-ui, sans-serif";
    ctx.fillStyle = LIMIT_COLOUR;
    ctx.textAlign = "left";
    ctx.textBaseline = "bottom";
    ctx.fillText(String(n + 1), s[0] + 7, s[1] - 4);
    ctx.restore();
    state.limitMarks.push({ k, x: s[0], y: s[1] });
  });
}

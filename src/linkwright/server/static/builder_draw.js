/* linkwright workbench: the builder's drawing of a sketch (its joints, links, guides and
 * drivers) on the plane or the sphere, and the hit tests the builder's pointer asks of it.
 *
 * The sketch is what the user drew (state.sketch); builder.js owns its edits. Where the server
 * compiled it, the traced curves of the compiled linkage's scene are drawn under it, so a
 * drawing with one degree of freedom shows at once the curves it makes. */

import {
  BODY_COLOURS, DEG, INK, INK3, TRACE_COLOURS, clamp, okPoint, sizeCanvas, slerp, unit3,
} from "./util.js";
import { currentPose, ownModeIndex, state } from "./pipeline.js";
import {
  drawGrid, drawing, groundSymbol, labelText, projectSphere, sphereGeom, strokePoly, toScreenPlane,
} from "./draw.js";
import { GRATICULE, strokeSide } from "./sphere.js";

const JOINT_RADIUS = 6;
const HIT_JOINT = 11;
const HIT_LINK = 7;

export const sketchSpace = (sk) => (sk && sk.space === "sphere" ? "sphere" : "plane");

/** Screen point [x, y, depth] of a model point of the sketch (depth ≥ 0 faces the viewer). */
export function sketchToScreen(sk, p) {
  if (sketchSpace(sk) === "sphere") return projectSphere(p, sphereGeom());
  const q = toScreenPlane(p);
  return [q[0], q[1], 1];
}

function jointMap(sk) {
  const out = new Map();
  for (const j of sk.joints) out.set(j.name, j);
  return out;
}

/** A link's outline in screen points: a binary link's segment, a plate's polygon (its joints
 * in turn about their centre), on the sphere along great circles. */
function linkOutline(sk, link, byName) {
  const pts = link.map((n) => byName.get(n)).filter(Boolean).map((j) => j.at);
  if (pts.length < 2) return [];
  let order = pts;
  if (pts.length > 2) {
    const scr = pts.map((p) => sketchToScreen(sk, p));
    const cx = scr.reduce((s, q) => s + q[0], 0) / scr.length;
    const cy = scr.reduce((s, q) => s + q[1], 0) / scr.length;
    const idx = scr.map((q, i) => [Math.atan2(q[1] - cy, q[0] - cx), i]).sort((a, b) => a[0] - b[0]);
    order = idx.map(([, i]) => pts[i]);
    order = order.concat([order[0]]);
  }
  if (sketchSpace(sk) !== "sphere") return order.map((p) => sketchToScreen(sk, p));
  const out = [];
  for (let i = 0; i + 1 < order.length; i++) {
    const seg = slerp(unit3(order[i]), unit3(order[i + 1]), 24).map((p) => projectSphere(p, sphereGeom()));
    if (out.length) seg.shift();
    out.push(...seg);
  }
  return out;
}

function distToSegment(q, a, b) {
  const dx = b[0] - a[0];
  const dy = b[1] - a[1];
  const l2 = dx * dx + dy * dy;
  const t = l2 > 0 ? clamp(((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / l2, 0, 1) : 0;
  return Math.hypot(q[0] - a[0] - t * dx, q[1] - a[1] - t * dy);
}

/** The joint under screen point q (the nearest within reach, front of the sphere only). */
export function hitSketchJoint(sk, q) {
  let best = null;
  let bd = HIT_JOINT;
  for (const j of sk.joints) {
    const s = sketchToScreen(sk, j.at);
    if (s[2] < -0.02) continue;
    const d = Math.hypot(s[0] - q[0], s[1] - q[1]);
    if (d < bd) {
      bd = d;
      best = j.name;
    }
  }
  return best;
}

/** The index of the link under screen point q, or -1. */
export function hitSketchLink(sk, q) {
  const byName = jointMap(sk);
  let best = -1;
  let bd = HIT_LINK;
  sk.links.forEach((link, k) => {
    const outline = linkOutline(sk, link, byName);
    for (let i = 0; i + 1 < outline.length; i++) {
      const a = outline[i];
      const b = outline[i + 1];
      if (a[2] < -0.02 || b[2] < -0.02) continue;
      const d = distToSegment(q, a, b);
      if (d < bd) {
        bd = d;
        best = k;
      }
    }
  });
  return best;
}

function drawCompiledCurves(ctx, sk) {
  const sc = state.scene;
  const rep = state.sketchReport;
  if (!sc || !rep || rep.status !== "ok" || sc.family !== "linkage") return;
  const own = ownModeIndex(sc);
  if (own < 0) return;
  ctx.save();
  ctx.lineWidth = 2;
  ctx.globalAlpha = 0.55;
  (sc.traced || []).forEach((name, k) => {
    ctx.strokeStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
    for (const circ of sc.modes[own].circuits) {
      const arr = circ.positions[name];
      if (!arr) continue;
      if (sketchSpace(sk) === "sphere") strokeSide(ctx, arr.map((p) => (okPoint(p) ? sketchToScreen(sk, p) : null)), true);
      else strokePoly(ctx, arr.map((p) => (okPoint(p) ? toScreenPlane(p) : null)));
    }
  });
  ctx.restore();
}

/** The compiled linkage at the input shown, faint, when that is not the drawn pose (input 0):
 * play or the input slider run the drawing while it is being built. */
function drawRunningPose(ctx, sk) {
  const rep = state.sketchReport;
  const sc = state.scene;
  if (!rep || rep.status !== "ok" || !sc || sc.family !== "linkage") return;
  if (!state.playing && Math.abs(state.at || 0) < 1e-9) return;
  const pose = currentPose();
  if (!pose) return;
  ctx.save();
  ctx.globalAlpha = 0.35;
  ctx.lineWidth = 3;
  ctx.lineCap = "round";
  sk.links.forEach((link, k) => {
    const pts = link.map((n) => pose[n]).filter((p) => okPoint(p));
    if (pts.length < 2) return;
    ctx.strokeStyle = BODY_COLOURS[k % BODY_COLOURS.length];
    const scr = pts.map((p) => sketchToScreen(sk, p));
    if (scr.some((q) => q[2] < -0.02)) return;
    strokePoly(ctx, pts.length > 2 ? scr.concat([scr[0]]) : scr);
  });
  ctx.restore();
}

function drawGuide(ctx, sk, j) {
  const s = sketchToScreen(sk, j.at);
  const a = j.slider * DEG;
  const d = [Math.cos(a), -Math.sin(a)];
  ctx.save();
  ctx.strokeStyle = "#8795a5";
  ctx.setLineDash([6, 4]);
  ctx.lineWidth = 1.3;
  ctx.beginPath();
  ctx.moveTo(s[0] - 2000 * d[0], s[1] - 2000 * d[1]);
  ctx.lineTo(s[0] + 2000 * d[0], s[1] + 2000 * d[1]);
  ctx.stroke();
  ctx.setLineDash([]);
  ctx.translate(s[0], s[1]);
  ctx.rotate(-a);
  ctx.fillStyle = "#f1f3f5";
  ctx.strokeStyle = INK;
  ctx.fillRect(-13, -8, 26, 16);
  ctx.strokeRect(-13, -8, 26, 16);
  ctx.restore();
}

function drawDriver(ctx, sk, drv, byName, first) {
  const p = byName.get(drv.pivot);
  const j = byName.get(drv.joint);
  if (!p || !j) return;
  const s = sketchToScreen(sk, p.at);
  const t = sketchToScreen(sk, j.at);
  const a = Math.atan2(t[1] - s[1], t[0] - s[0]);
  ctx.save();
  ctx.strokeStyle = first ? "#c2410c" : "#e67700";
  ctx.fillStyle = ctx.strokeStyle;
  ctx.lineWidth = 2;
  const r = 20;
  ctx.beginPath();
  ctx.arc(s[0], s[1], r, a - 0.9, a - 0.15);
  ctx.stroke();
  // the arrow head points the way the input turns (counter-clockwise on the screen)
  const e = a - 0.9;
  const hx = s[0] + r * Math.cos(e);
  const hy = s[1] + r * Math.sin(e);
  ctx.beginPath();
  ctx.moveTo(hx, hy);
  ctx.lineTo(hx + 7 * Math.cos(e + 0.9), hy + 7 * Math.sin(e + 0.9));
  ctx.lineTo(hx + 7 * Math.cos(e - 1.9 + Math.PI), hy + 7 * Math.sin(e - 1.9 + Math.PI));
  ctx.closePath();
  ctx.fill();
  if (!first) labelText(ctx, "×" + String(drv.ratio), s[0] + r + 4, s[1] - r, ctx.strokeStyle, "left");
  ctx.restore();
}

function drawSphereBackground(ctx) {
  const g = sphereGeom();
  ctx.save();
  ctx.fillStyle = "#fbfcfd";
  ctx.strokeStyle = "#b9c4d0";
  ctx.lineWidth = 1.2;
  ctx.beginPath();
  ctx.arc(g.cx, g.cy, g.r, 0, 2 * Math.PI);
  ctx.fill();
  ctx.stroke();
  ctx.lineWidth = 1;
  for (const l of GRATICULE) {
    ctx.strokeStyle = l.major ? "#c5cfdb" : "#e1e7ee";
    strokeSide(ctx, l.pts.map((p) => projectSphere(p, g)), true);
  }
  ctx.restore();
}

/** Draw the sketch being built, with the builder's pending gesture (`ui`: the tool's chain of
 * joints, the pointer, the selection). */
export function drawSketch(ui) {
  const cv = drawing();
  const { ctx, w, h } = sizeCanvas(cv);
  ctx.clearRect(0, 0, w, h);
  const sk = state.sketch;
  if (!sk) return;
  const sphere = sketchSpace(sk) === "sphere";
  if (sphere) drawSphereBackground(ctx);
  else drawGrid(ctx, w, h);
  drawCompiledCurves(ctx, sk);
  drawRunningPose(ctx, sk);
  const byName = jointMap(sk);
  for (const j of sk.joints) if (!sphere && typeof j.slider === "number") drawGuide(ctx, sk, j);
  sk.links.forEach((link, k) => {
    const outline = linkOutline(sk, link, byName);
    if (outline.length < 2) return;
    const colour = BODY_COLOURS[k % BODY_COLOURS.length];
    const selected = ui.selectedLink === k;
    ctx.save();
    ctx.lineCap = "round";
    ctx.lineJoin = "round";
    if (link.length > 2 && !sphere) {
      ctx.fillStyle = colour + "30";
      ctx.beginPath();
      outline.forEach((p, i) => (i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      ctx.closePath();
      ctx.fill();
    }
    ctx.strokeStyle = selected ? "#fa5252" : colour;
    ctx.lineWidth = selected ? 6 : 4.5;
    if (sphere) strokeSide(ctx, outline, true);
    else strokePoly(ctx, outline);
    ctx.restore();
  });
  (sk.drivers || []).forEach((d, i) => drawDriver(ctx, sk, d, byName, i === 0));
  // the chain the link or plate tool is drawing, and the rubber band to the pointer
  if (ui.chain && ui.chain.length) {
    const pts = ui.chain.map((n) => byName.get(n)).filter(Boolean).map((j) => sketchToScreen(sk, j.at));
    if (ui.pointer) pts.push(ui.pointer);
    ctx.save();
    ctx.strokeStyle = "#2f6bd8";
    ctx.lineWidth = 2;
    ctx.setLineDash([6, 4]);
    strokePoly(ctx, pts);
    ctx.restore();
  }
  for (const j of sk.joints) {
    const s = sketchToScreen(sk, j.at);
    if (s[2] < -0.02) continue;
    if (j.ground) groundSymbol(ctx, s[0], s[1]);
    ctx.save();
    const picked = ui.selectedJoint === j.name || (ui.chain || []).includes(j.name);
    ctx.fillStyle = j.ground ? "#dee2e6" : "#fff";
    ctx.strokeStyle = picked ? "#2f6bd8" : ui.hover === j.name ? "#fa5252" : INK;
    ctx.lineWidth = picked || ui.hover === j.name ? 2.6 : 1.8;
    ctx.beginPath();
    ctx.arc(s[0], s[1], JOINT_RADIUS, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    ctx.restore();
    labelText(ctx, j.name, s[0] + 9, s[1] - 9, INK, "left");
  }
  if (!sk.joints.length) {
    ctx.save();
    ctx.fillStyle = INK3;
    ctx.font = "14px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.fillText("Pick a tool above, then click here to place the first joint", w / 2, h / 2);
    ctx.restore();
  }
}

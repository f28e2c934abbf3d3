/* linkwright workbench: the sphere drawing (front and back, graticule) and its equal-area map. */

import {
  $, BODY_COLOURS, DEG, INK3, TRACE_COLOURS, cross3, dot3, mulMV, okPoint, sizeCanvas, slerp,
  unit3,
} from "./util.js";
import { currentPose, ownModeIndex, state } from "./pipeline.js";
import { currentCircuit, modeStyle } from "./panels.js";
import {
  closeIf, drawDragPointer, drawJoints, drawLimitMarks, drawPick, drawing, groundSymbol,
  labelText, limitPose, projectSphere, sphereGeom, strokePoly,
} from "./draw.js";

// ------------------------------------------------------------------ drawing: sphere
/** Split a projected polyline into runs on the front (z ≥ 0) or back of the sphere. */
export function strokeSide(ctx, proj, front) {
  ctx.beginPath();
  let open = false;
  for (let i = 0; i + 1 < proj.length; i++) {
    const a = proj[i];
    const b = proj[i + 1];
    if (!a || !b) {
      open = false;
      continue;
    }
    const z = (a[2] + b[2]) / 2;
    if (z >= 0 === front) {
      if (!open) {
        ctx.moveTo(a[0], a[1]);
        open = true;
      }
      ctx.lineTo(b[0], b[1]);
    } else open = false;
  }
  ctx.stroke();
}

function graticule() {
  const lines = [];
  for (let lat = -60; lat <= 60; lat += 30) {
    const pts = [];
    for (let lon = 0; lon <= 360; lon += 6)
      pts.push([Math.cos(lat * DEG) * Math.cos(lon * DEG), Math.cos(lat * DEG) * Math.sin(lon * DEG), Math.sin(lat * DEG)]);
    lines.push({ pts, major: lat === 0 });
  }
  for (let lon = 0; lon < 180; lon += 30) {
    const pts = [];
    for (let t = 0; t <= 360; t += 6)
      pts.push([Math.cos(t * DEG) * Math.cos(lon * DEG), Math.cos(t * DEG) * Math.sin(lon * DEG), Math.sin(t * DEG)]);
    lines.push({ pts, major: lon === 0 });
  }
  return lines;
}
export const GRATICULE = graticule();

function sphereCurves(sc, g) {
  // [{proj, colour, width, dash, alpha}] for every traced curve of every mode
  const out = [];
  const own = ownModeIndex(sc);
  (sc.modes || []).forEach((mode, m) => {
    const st = modeStyle(sc, m);
    (sc.traced || []).forEach((name, k) => {
      mode.circuits.forEach((circ, c) => {
        const arr = circ.positions[name];
        if (!arr) return;
        const proj = closeIf(circ, arr.map((p) => (Array.isArray(p) && p.length >= 3 && p[0] != null ? projectSphere(p, g) : null)));
        out.push({
          proj,
          colour: TRACE_COLOURS[k % TRACE_COLOURS.length],
          width: m === own ? 2.4 : 1.2,
          dash: st.dash,
          alpha: m === own ? (state.cur && state.cur.circuit === c ? 1 : 0.5) : 0.75,
        });
      });
    });
  });
  for (const ov of state.overlays.values()) {
    const st = ov.style || {};
    for (const curve of ov.curves || []) {
      if (!curve.length || !Array.isArray(curve[0]) || curve[0].length < 3) continue;
      out.push({
        proj: curve.map((p) => (Array.isArray(p) && p.length >= 3 ? projectSphere(p, g) : null)),
        colour: st.color || "#868e96",
        width: st.width || 1.5,
        dash: st.dash || [],
        alpha: 1,
      });
    }
  }
  return out;
}

function sphereLinks(sc, pose, g) {
  const out = [];
  (sc.bodies || []).forEach((body, k) => {
    const pts = body.joints.map((j) => pose[j]).filter((p) => Array.isArray(p) && p.length >= 3 && p[0] != null);
    if (pts.length < 2) return;
    const edges = pts.length === 2 ? [[pts[0], pts[1]]] : pts.map((p, i) => [p, pts[(i + 1) % pts.length]]);
    const arc = [];
    for (const [a, b] of edges) {
      const seg = slerp(unit3(a), unit3(b), 32).map((p) => projectSphere(p, g));
      if (arc.length) seg.shift();
      arc.push(...seg);
    }
    out.push({ arc, body, colour: BODY_COLOURS[k % BODY_COLOURS.length], n: pts.length });
  });
  return out;
}

export function drawSphere() {
  const cv = drawing();
  const { ctx, w, h } = sizeCanvas(cv);
  ctx.clearRect(0, 0, w, h);
  const sc = state.scene;
  if (!sc) return;
  const g = sphereGeom();
  const pose = currentPose();
  const grat = GRATICULE.map((l) => ({ major: l.major, proj: l.pts.map((p) => projectSphere(p, g)) }));
  const curves = sphereCurves(sc, g);
  const links = pose ? sphereLinks(sc, pose, g) : [];
  const ghost = state.hoverLimit != null ? limitPose(sc, state.hoverLimit) : null;
  const ghostLinks = ghost ? sphereLinks(sc, ghost, g) : [];

  const pass = (front) => {
    ctx.save();
    ctx.lineWidth = 1;
    for (const l of grat) {
      ctx.strokeStyle = front ? (l.major ? "#c5cfdb" : "#dde4ec") : "#e4e9ef";
      strokeSide(ctx, l.proj, front);
    }
    ctx.restore();
    for (const cu of curves) {
      ctx.save();
      ctx.strokeStyle = cu.colour;
      ctx.lineWidth = front ? cu.width : Math.max(1, cu.width * 0.6);
      ctx.globalAlpha = front ? cu.alpha : cu.alpha * 0.3;
      ctx.setLineDash(cu.dash);
      ctx.lineJoin = "round";
      strokeSide(ctx, cu.proj, front);
      ctx.restore();
    }
    for (const L of ghostLinks) {
      ctx.save();
      ctx.strokeStyle = L.colour;
      ctx.globalAlpha = front ? 0.35 : 0.12;
      ctx.lineWidth = 2.5;
      if (!L.body.ground) strokeSide(ctx, L.arc, front);
      ctx.restore();
    }
    for (const L of links) {
      ctx.save();
      ctx.lineCap = "round";
      ctx.lineJoin = "round";
      if (L.body.ground) {
        ctx.strokeStyle = "#8795a5";
        ctx.setLineDash([6, 4]);
        ctx.lineWidth = 1.3;
      } else {
        ctx.strokeStyle = L.colour;
        ctx.lineWidth = front ? 4.5 : 2.5;
      }
      if (!front) ctx.globalAlpha = 0.3;
      strokeSide(ctx, L.arc, front);
      if (front && L.n >= 3 && !L.body.ground && L.arc.every((p) => p[2] >= 0)) {
        ctx.fillStyle = L.colour + "26";
        ctx.beginPath();
        L.arc.forEach((p, i) => (i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
        ctx.closePath();
        ctx.fill();
      }
      ctx.restore();
    }
  };

  // back half, faded by a veil; then the front
  pass(false);
  const grad = ctx.createRadialGradient(g.cx - g.r * 0.35, g.cy - g.r * 0.4, g.r * 0.1, g.cx, g.cy, g.r);
  grad.addColorStop(0, "rgba(255,255,255,0.86)");
  grad.addColorStop(1, "rgba(232,238,246,0.78)");
  ctx.beginPath();
  ctx.arc(g.cx, g.cy, g.r, 0, 2 * Math.PI);
  ctx.fillStyle = grad;
  ctx.fill();
  ctx.lineWidth = 1.5;
  ctx.strokeStyle = "#aab6c4";
  ctx.stroke();
  pass(true);

  // the axes of the ground pivots: from the centre O to each fixed joint
  if (pose) {
    ctx.save();
    ctx.setLineDash([2, 3]);
    ctx.strokeStyle = "#8795a5";
    ctx.lineWidth = 1;
    for (const name of sc.fixed || []) {
      const p = pose[name];
      if (!p || p[0] == null) continue;
      const s = projectSphere(p, g);
      if (s[2] < 0) continue;
      ctx.beginPath();
      ctx.moveTo(g.cx, g.cy);
      ctx.lineTo(s[0], s[1]);
      ctx.stroke();
    }
    ctx.restore();
    ctx.beginPath();
    ctx.arc(g.cx, g.cy, 2.5, 0, 2 * Math.PI);
    ctx.fillStyle = INK3;
    ctx.fill();
    labelText(ctx, "O", g.cx + 6, g.cy + 8, INK3);
  }
  drawLimitMarks(ctx, sc, (p) => (Array.isArray(p) && p.length >= 3 && p[0] != null ? projectSphere(p, g) : null));
  if (pose) {
    const fixed = new Set(sc.fixed || []);
    const project = (p) => projectSphere(p, g);
    drawJoints(ctx, sc, pose, project, (p) => project(p)[2] < 0);
    for (const name of fixed) {
      const p = pose[name];
      if (!p || p[0] == null) continue;
      const s = project(p);
      if (s[2] < 0) continue;
      groundSymbol(ctx, s[0], s[1] + 1);
      drawJoints(ctx, { ...sc, joints: [name] }, pose, project, null);
    }
  }
  drawDragPointer(ctx);
  drawPick(ctx, (p) => projectSphere(p, g));
  drawTriad(ctx, w, h);
}

function drawTriad(ctx, w, h) {
  const o = [w - 36, h - 36];
  const axes = [
    ["x", [1, 0, 0], "#c92a2a"],
    ["y", [0, 1, 0], "#2b8a3e"],
    ["z", [0, 0, 1], "#1c7ed6"],
  ];
  const proj = axes.map(([n, v, c]) => [n, mulMV(state.sphere.R, v), c]).sort((a, b) => a[1][2] - b[1][2]);
  for (const [n, q, c] of proj) {
    ctx.save();
    ctx.globalAlpha = q[2] < 0 ? 0.45 : 1;
    ctx.strokeStyle = c;
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(o[0], o[1]);
    ctx.lineTo(o[0] + 20 * q[0], o[1] - 20 * q[1]);
    ctx.stroke();
    labelText(ctx, n, o[0] + 27 * q[0], o[1] - 27 * q[1], c, "center");
    ctx.restore();
  }
}

// ------------------------------------------------------------------ drawing: map
/** The map's tangent basis (e1, e2), recovered from the scene's own samples so that the
 * page draws links and the graticule on exactly the map the server computed. */
export function fitMapBasis(sc) {
  if (!Array.isArray(sc.map_center)) return null;
  const c = unit3(sc.map_center);
  const pairs = [];
  for (const mode of sc.modes || [])
    for (const circ of mode.circuits) {
      if (!circ.map) continue;
      for (const [name, uvs] of Object.entries(circ.map)) {
        const ps = circ.positions[name];
        if (!ps || !uvs) continue;
        for (let i = 0; i < uvs.length && pairs.length < 40; i += 17) {
          const p = ps[i];
          const uv = uvs[i];
          if (!p || !uv || p[0] == null || uv[0] == null) continue;
          if (Math.hypot(uv[0], uv[1]) < 1e-3 || dot3(p, c) < -0.9) continue;
          pairs.push([unit3(p), uv]);
        }
      }
    }
  if (pairs.length < 2) return null;
  let b1 = cross3(c, Math.abs(c[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0]);
  b1 = unit3(b1);
  const b2 = cross3(c, b1);
  const tau = ([p]) => Math.atan2(dot3(p, b2), dot3(p, b1));
  const ups = ([, uv]) => Math.atan2(uv[1], uv[0]);
  let best = null;
  for (const sign of [1, -1]) {
    const alpha = tau(pairs[0]) - sign * ups(pairs[0]);
    const e1 = [0, 1, 2].map((i) => Math.cos(alpha) * b1[i] + Math.sin(alpha) * b2[i]);
    let e2 = cross3(c, e1);
    if (sign < 0) e2 = e2.map((v) => -v);
    let err = 0;
    for (const [p, uv] of pairs) {
      const k = Math.sqrt(2 / Math.max(1e-12, 1 + dot3(p, c)));
      err = Math.max(err, Math.hypot(k * dot3(p, e1) - uv[0], k * dot3(p, e2) - uv[1]));
    }
    if (!best || err < best.err) best = { c, e1, e2, err };
  }
  return best && best.err < 1e-3 ? best : null;
}

function laea(p, B) {
  const u = unit3(p);
  const k = Math.sqrt(2 / Math.max(1e-12, 1 + dot3(u, B.c)));
  return [k * dot3(u, B.e1), k * dot3(u, B.e2)];
}

export function drawMap() {
  const cv = $("map");
  if ($("map-wrap").hidden) return;
  const { ctx, w, h } = sizeCanvas(cv);
  ctx.clearRect(0, 0, w, h);
  const sc = state.scene;
  if (!sc) return;
  const R = (0.46 * Math.min(w, h - 20) * state.map.zoom) / 2; // pixels per map unit; the disc has radius 2
  const cx = w / 2;
  const cy = h / 2 + 8;
  const S = (uv) => [cx + R * uv[0], cy - R * uv[1]];
  const B = state.map.basis;
  // disc of the whole sphere and the hemisphere around the centre
  ctx.beginPath();
  ctx.arc(cx, cy, 2 * R, 0, 2 * Math.PI);
  ctx.fillStyle = "#ffffff";
  ctx.fill();
  ctx.lineWidth = 1.5;
  ctx.strokeStyle = "#aab6c4";
  ctx.stroke();
  ctx.save();
  ctx.setLineDash([4, 4]);
  ctx.strokeStyle = "#d0d8e2";
  ctx.beginPath();
  ctx.arc(cx, cy, Math.SQRT2 * R, 0, 2 * Math.PI);
  ctx.stroke();
  ctx.restore();
  if (B) {
    ctx.save();
    ctx.lineWidth = 1;
    for (const l of GRATICULE) {
      ctx.strokeStyle = l.major ? "#d5dde6" : "#e8edf2";
      const pts = l.pts.map((p) => (dot3(p, B.c) < -0.97 ? null : S(laea(p, B))));
      strokePoly(ctx, breakJumps(pts, R * 0.6));
    }
    ctx.restore();
  }
  const own = ownModeIndex(sc);
  (sc.modes || []).forEach((mode, m) => {
    const st = modeStyle(sc, m);
    (sc.traced || []).forEach((name, k) => {
      mode.circuits.forEach((circ, c) => {
        const arr = circ.map && circ.map[name];
        if (!arr) return;
        ctx.save();
        ctx.strokeStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
        ctx.lineWidth = m === own ? 2.2 : 1.1;
        ctx.setLineDash(st.dash);
        ctx.globalAlpha = m === own ? (state.cur && state.cur.circuit === c ? 1 : 0.5) : 0.75;
        strokePoly(ctx, breakJumps(closeIf(circ, arr.map((uv) => (okPoint(uv) ? S(uv) : null))), R * 0.6));
        ctx.restore();
      });
    });
  });
  // the linkage itself, when the map's frame could be read back from the samples
  const pose = currentPose();
  if (pose && B) {
    (sc.bodies || []).forEach((body, k) => {
      const pts = body.joints.map((j) => pose[j]).filter((p) => Array.isArray(p) && p.length >= 3 && p[0] != null);
      if (pts.length < 2) return;
      const edges = pts.length === 2 ? [[pts[0], pts[1]]] : pts.map((p, i) => [p, pts[(i + 1) % pts.length]]);
      ctx.save();
      ctx.lineCap = "round";
      if (body.ground) {
        ctx.strokeStyle = "#8795a5";
        ctx.setLineDash([6, 4]);
        ctx.lineWidth = 1.2;
      } else {
        ctx.strokeStyle = BODY_COLOURS[k % BODY_COLOURS.length];
        ctx.lineWidth = 3.2;
      }
      for (const [a, b] of edges) strokePoly(ctx, breakJumps(slerp(unit3(a), unit3(b), 24).map((p) => S(laea(p, B))), R * 0.6));
      ctx.restore();
    });
    drawJoints(ctx, sc, pose, (p) => S(laea(p, B)), null);
  } else if (state.cur) {
    // no frame: mark the traced points at the current sample only
    const circ = currentCircuit();
    (sc.traced || []).forEach((name, k) => {
      const uv = circ.map && circ.map[name] && circ.map[name][state.cur.index];
      if (!okPoint(uv)) return;
      const s = S(uv);
      ctx.beginPath();
      ctx.arc(s[0], s[1], 4.5, 0, 2 * Math.PI);
      ctx.fillStyle = TRACE_COLOURS[k % TRACE_COLOURS.length];
      ctx.fill();
    });
  }
  ctx.fillStyle = INK3;
  ctx.font = "11px system-ui, sans-serif";
  ctx.textAlign = "center";
  ctx.textBaseline = "top";
  ctx.fillText("antipode", cx, cy + 2 * R + 3);
}

export function breakJumps(pts, maxJump) {
  const out = [];
  for (let i = 0; i < pts.length; i++) {
    const p = pts[i];
    const q = out.length ? out[out.length - 1] : null;
    if (p && q && Math.hypot(p[0] - q[0], p[1] - q[1]) > maxJump) out.push(null);
    out.push(p);
  }
  return out;
}

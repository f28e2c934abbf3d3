/* linkwright workbench: the core page (drawing, parameters, animation, plots).
 *
 * No build step and nothing fetched from outside: plain script, canvas 2D. The server computes
 * every number (POST /api/scene, /api/drag); this file only draws what a scene says and turns
 * the user's gestures into documents. window.lw is the API that tools.js builds on
 * (see the contract in the server package).
 */
(function () {
  "use strict";

  // ------------------------------------------------------------------ small helpers
  const $ = (id) => document.getElementById(id);
  const SAMPLES = 360;
  const DEG = Math.PI / 180;
  const TRACE_COLOURS = ["#d9480f", "#1c7ed6", "#2b8a3e", "#ae3ec9", "#e67700", "#0c8599"];
  const BODY_COLOURS = ["#3d5a80", "#2a9d8f", "#8d6cab", "#b5651d", "#5c7cfa", "#0b7285", "#c2255c"];
  const MODE_DASHES = [[7, 4], [2, 3], [9, 3, 2, 3], [4, 4], [1, 4]];
  const LIMIT_COLOUR = "#c2410c";
  const INK = "#1d2733";
  const INK2 = "#4a5868";
  const INK3 = "#7c8a9a";

  const clone = (x) => (x === undefined ? undefined : JSON.parse(JSON.stringify(x)));
  const clamp = (v, lo, hi) => Math.max(lo, Math.min(hi, v));
  const finite = (v) => typeof v === "number" && Number.isFinite(v);
  const okPoint = (p) => Array.isArray(p) && p.length >= 2 && finite(p[0]) && finite(p[1]);

  /** A number for display: short, no float noise. */
  function fmt(v, digits = 4) {
    if (!finite(v)) return "—";
    if (v === 0) return "0";
    const a = Math.abs(v);
    if (a >= 1e6 || a < 1e-4) return v.toExponential(2);
    return String(parseFloat(v.toFixed(Math.max(0, digits - Math.floor(Math.log10(a)) - 1))));
  }
  /** A number for an input box: exact enough to round-trip what a person typed. */
  function fmtInput(v) {
    if (!finite(v)) return "";
    return String(parseFloat(v.toPrecision(10)));
  }
  const minus = (t) => t.replace(/^-/, "−");
  function fmtDeg(v) {
    return finite(v) ? `${minus(v.toFixed(1))}°` : "—";
  }
  const signLabel = (v) => (v > 0 ? "+1" : v < 0 ? "−1" : String(v));

  function getPath(obj, path) {
    let o = obj;
    for (const k of path.split(".")) {
      if (o == null) return undefined;
      o = Array.isArray(o) ? o[Number(k)] : o[k];
    }
    return o;
  }
  function setPath(obj, path, value) {
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

  function niceStep(range, target) {
    const raw = range / Math.max(1, target);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const f = raw / mag;
    return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
  }
  function ticks(lo, hi, target, angle) {
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
  function tickLabel(t, step) {
    const d = step >= 1 ? 0 : Math.min(6, Math.ceil(-Math.log10(step) - 1e-9));
    return Math.abs(t) >= 1e5 ? t.toExponential(1) : t.toFixed(d);
  }

  /** Size a canvas to its CSS box at the device's pixel ratio; a context in CSS pixels. */
  function sizeCanvas(canvas) {
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
  const dot3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross3 = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm3 = (a) => Math.hypot(a[0], a[1], a[2]);
  const unit3 = (a) => {
    const n = norm3(a) || 1;
    return [a[0] / n, a[1] / n, a[2] / n];
  };
  const mulMV = (m, v) => [
    m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
    m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
    m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
  ];
  const mulMtV = (m, v) => [
    m[0] * v[0] + m[3] * v[1] + m[6] * v[2],
    m[1] * v[0] + m[4] * v[1] + m[7] * v[2],
    m[2] * v[0] + m[5] * v[1] + m[8] * v[2],
  ];
  function mulMM(a, b) {
    const r = new Array(9);
    for (let i = 0; i < 3; i++)
      for (let j = 0; j < 3; j++) r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    return r;
  }
  const rotX = (a) => [1, 0, 0, 0, Math.cos(a), -Math.sin(a), 0, Math.sin(a), Math.cos(a)];
  const rotY = (a) => [Math.cos(a), 0, Math.sin(a), 0, 1, 0, -Math.sin(a), 0, Math.cos(a)];
  /** Re-orthonormalise a rotation so that many small turns do not drift. */
  function orthonormal(m) {
    const x = unit3([m[0], m[1], m[2]]);
    const z = unit3(cross3(x, [m[3], m[4], m[5]]));
    const y = cross3(z, x);
    return [...x, ...y, ...z];
  }
  /** Points along the great-circle arc from a to b (both unit vectors). */
  function slerp(a, b, n) {
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

  // ------------------------------------------------------------------ state
  const state = {
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
    listeners: { scene: [], at: [], document: [] },
    sceneCount: 0,
    busy: 0,
    pipelineError: false,
    fieldSig: "",
    chartSig: "",
    plotKind: "angles",
    charts: [],
    dragPipe: null,
    dragGhost: null,
  };

  function emit(name, arg) {
    for (const fn of state.listeners[name] || []) {
      try {
        fn(arg);
      } catch (e) {
        console.error(e);
      }
    }
  }

  // ------------------------------------------------------------------ server access
  function setBusy(delta) {
    state.busy = Math.max(0, state.busy + delta);
    document.body.dataset.busy = state.busy > 0 ? "1" : "0";
  }

  async function api(path, body) {
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

  function status(text, kind) {
    const el = $("status");
    el.textContent = text == null ? "" : String(text);
    el.dataset.kind = kind || "info";
    el.title = el.textContent;
  }

  // ------------------------------------------------------------------ scene pipeline
  // At most one scene request in flight; a newer request replaces any waiting one, and its
  // answer settles every promise that was waiting (the latest document is what counts).
  let sceneInFlight = false;
  let scenePending = null;

  function requestScene(doc, at, opts = {}) {
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
      const body = { document: job.doc, samples: SAMPLES, at: finite(job.at) ? job.at : null, diagrams: true };
      const sc = await api("/api/scene", body);
      if (!scenePending) state.latestRequested = null;
      applyScene(sc, job);
      result = sc;
    } catch (e) {
      if (!scenePending) state.latestRequested = null;
      state.pipelineError = true;
      status(e.message, "error");
      markField(job.fieldPath, e.message);
      if (!state.scene) drawAll();
    } finally {
      sceneInFlight = false;
      for (const w of job.waiters) w(result);
      pumpScene();
    }
  }

  function ownModeIndex(sc) {
    if (!sc || !sc.modes) return -1;
    return sc.modes.findIndex((m) => m.own);
  }

  function samplePose(sc, m, c, i) {
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

  const angDist = (a, b) => {
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

  function sceneScale(sc) {
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
    state.cur = locate(sc, finite(sc.at) ? sc.at : job.at, freshKind || job.fit ? null : previous);
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
    state.map.basis = sc.space === "sphere" ? fitMapBasis(sc) : null;
    if (freshKind || job.fit) {
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

  function currentPose() {
    const sc = state.scene;
    if (!sc || !state.cur) return sc && sc.pose ? sc.pose : null;
    if (state.exact) return state.exact;
    return samplePose(sc, state.cur.mode, state.cur.circuit, state.cur.index);
  }

  // ------------------------------------------------------------------ top bar, choosers
  function renderTop(sc) {
    const fam = $("family-select");
    if (fam.value !== sc.family) fam.value = sc.family;
    const ex = $("example-select");
    const want = state.exampleName || "";
    if (ex.value !== want) ex.value = want;
    const title = $("doc-title");
    if (document.activeElement !== title) title.value = sc.document.title || "";
    document.title = `${sc.document.title || sc.family_name || "untitled"} · linkwright`;
  }

  function fillChoosers() {
    const fam = $("family-select");
    fam.innerHTML = "";
    // Families come grouped and in order from the server's family registry.
    const byGroup = new Map();
    for (const f of state.families) {
      if (!byGroup.has(f.group)) {
        const og = document.createElement("optgroup");
        og.label = f.group;
        byGroup.set(f.group, og);
        fam.appendChild(og);
      }
      byGroup.get(f.group).appendChild(new Option(f.name, f.family));
    }

    const ex = $("example-select");
    ex.innerHTML = "";
    ex.appendChild(new Option("— choose an example —", ""));
    const famName = Object.fromEntries(state.families.map((f) => [f.family, f.name]));
    const famGroup = Object.fromEntries(state.families.map((f) => [f.family, f.group]));
    const groups = new Map();
    const isPaper = (e) => /^paper\d/.test(e.name) || /\bpaper\s*\d/i.test(e.title || "");
    const add = (g, e) => {
      if (!groups.has(g)) groups.set(g, []);
      groups.get(g).push(e);
    };
    for (const e of state.examples) {
      add(isPaper(e) ? "From the papers" : famGroup[e.family] || "Other", e);
    }
    const order = ["From the papers", ...new Set(state.families.map((f) => f.group))];
    for (const g of order.concat([...groups.keys()].filter((k) => !order.includes(k)))) {
      if (!groups.has(g)) continue;
      const og = document.createElement("optgroup");
      og.label = g;
      for (const e of groups.get(g)) {
        const o = new Option(e.title || e.name, e.name);
        o.title = `${e.name} · ${famName[e.family] || e.family}`;
        og.appendChild(o);
      }
      ex.appendChild(og);
    }
  }

  async function loadExample(name) {
    try {
      const doc = await api(`/api/examples/${encodeURIComponent(name)}`);
      status(`Loading ${name}…`, "busy");
      const sc = await requestScene(doc, null, { fit: true, exampleName: name });
      if (sc) {
        status(`Loaded example “${sc.document.title || name}”`, "info");
        try {
          history.replaceState(null, "", `#${encodeURIComponent(name)}`);
        } catch (e) {
          /* file:// or sandboxed: the address is only a convenience */
        }
      }
    } catch (e) {
      status(e.message, "error");
    }
  }

  async function loadFamily(family) {
    try {
      const doc = await api(`/api/families/${encodeURIComponent(family)}/default`);
      const f = state.families.find((x) => x.family === family);
      const sc = await requestScene(doc, null, { fit: true, exampleName: f ? f.example : null });
      if (sc) status(`${sc.family_name}: ${sc.document.title || "default mechanism"}`, "info");
    } catch (e) {
      status(e.message, "error");
    }
  }

  // ------------------------------------------------------------------ parameter fields

  function unitText(f) {
    if (f.unit === "deg") return "°";
    if (f.unit === "length") return (state.scene && state.scene.units) || "";
    return f.unit || "";
  }

  function groupOf(f, doc) {
    const parts = f.path.split(".");
    if (parts.length <= 2) return "";
    const inner = parts.slice(1, -1);
    if (inner[0] === "joints" && inner.length >= 2) {
      const j = getPath(doc, `mechanism.joints.${inner[1]}`);
      return j && j.name ? `joint ${j.name}${j.type ? ` · ${j.type}` : ""}` : `joint ${Number(inner[1]) + 1}`;
    }
    return inner.join(" ");
  }

  function renderFields(sc) {
    const form = $("fields");
    const fields = sc.fields || [];
    const sig = fields.map((f) => `${f.path}:${f.kind}:${(f.choices || []).join(",")}`).join("|");
    if (sig !== state.fieldSig) {
      state.fieldSig = sig;
      form.innerHTML = "";
      let group = null;
      for (const f of fields) {
        const g = groupOf(f, sc.document);
        if (g !== group) {
          group = g;
          if (g) {
            const h = document.createElement("div");
            h.className = "group";
            h.textContent = g;
            form.appendChild(h);
          }
        }
        const id = `f-${f.path.replace(/[^A-Za-z0-9_-]/g, "-")}`;
        const label = document.createElement("label");
        label.htmlFor = id;
        label.textContent = f.label;
        label.title = f.path;
        let input;
        if (f.kind === "choice" || f.kind === "sign" || Array.isArray(f.choices)) {
          input = document.createElement("select");
          for (const ch of f.choices || [1, -1]) {
            const o = new Option(f.kind === "sign" ? signLabel(ch) : String(ch), JSON.stringify(ch));
            input.appendChild(o);
          }
          input.addEventListener("change", () => onFieldEdit(input, f, true));
        } else {
          input = document.createElement("input");
          input.type = "number";
          input.step = f.kind === "angle" ? "1" : "0.1";
          input.inputMode = "decimal";
          input.addEventListener("input", () => onFieldEdit(input, f, false));
          input.addEventListener("keydown", (e) => {
            if (e.key === "Enter") onFieldEdit(input, f, true);
          });
        }
        input.id = id;
        input.dataset.path = f.path;
        input.dataset.kind = f.kind;
        input.dataset.testid = `field-${f.path}`;
        input.setAttribute("aria-label", f.label);
        const unit = document.createElement("span");
        unit.className = "unit";
        unit.textContent = unitText(f);
        form.append(label, input, unit);
      }
    }
    for (const f of fields) {
      const el = form.querySelector(`[data-path="${CSS.escape(f.path)}"]`);
      if (!el || document.activeElement === el) continue;
      if (el.tagName === "SELECT") el.value = JSON.stringify(f.value);
      else el.value = fmtInput(f.value);
      el.classList.remove("invalid");
    }
    $("family-name").textContent = sc.family_name || sc.family;
    $("space-badge").textContent = sc.space === "sphere" ? "sphere" : "plane";
  }

  function markField(path, message) {
    for (const el of $("fields").querySelectorAll(".invalid")) {
      el.classList.remove("invalid");
      el.removeAttribute("title");
    }
    if (!path) return;
    const el = $("fields").querySelector(`[data-path="${CSS.escape(path)}"]`);
    if (el) {
      el.classList.add("invalid");
      el.title = message || "";
    }
  }

  // No debounce: requestScene keeps at most one request in flight and sends the latest value
  // when it returns, so a burst of keystrokes costs one round trip, and a single change is
  // drawn as soon as the server answers (the redraw's latency target is 50 ms).
  function onFieldEdit(input, f, now) {
    let value;
    if (input.tagName === "SELECT") value = JSON.parse(input.value);
    else {
      const text = input.value.trim();
      if (text === "" && !now) return; // cleared to type a new number: wait for it
      value = Number(text);
      if (text === "" || !Number.isFinite(value)) {
        markField(f.path, "not a number");
        status(`${f.label}: enter a number`, "error");
        state.pipelineError = true;
        return;
      }
    }
    const base = clone(state.latestRequested || state.doc);
    if (!base) return;
    setPath(base, f.path, value);
    requestScene(base, state.at, { fieldPath: f.path });
  }

  function renderInfo(sc) {
    $("range-text").textContent = sc.range || (sc.full ? "every input" : "—");
    $("compute-ms").textContent = finite(sc.compute_ms) ? `${sc.compute_ms.toFixed(1)} ms` : "—";
  }

  // ------------------------------------------------------------------ modes, circuits, animation UI
  function modeStyle(sc, m) {
    // Own mode solid; the others dashed, each its own pattern, in legend order.
    let k = 0;
    for (let j = 0; j < m; j++) if (!sc.modes[j].own) k++;
    return { own: !!sc.modes[m].own, dash: sc.modes[m].own ? [] : MODE_DASHES[k % MODE_DASHES.length] };
  }

  function dashSwatch(colour, dash, width) {
    const svg = `<svg width="26" height="8" viewBox="0 0 26 8"><line x1="1" y1="4" x2="25" y2="4" stroke="${colour}" stroke-width="${width}" stroke-dasharray="${dash.join(" ")}"/></svg>`;
    return svg;
  }

  function renderModes(sc) {
    const box = $("modes");
    box.innerHTML = "";
    (sc.modes || []).forEach((mode, m) => {
      const b = document.createElement("button");
      b.type = "button";
      b.setAttribute("role", "radio");
      b.setAttribute("aria-checked", mode.own ? "true" : "false");
      b.dataset.testid = "mode-option";
      b.dataset.mode = String(m);
      const st = modeStyle(sc, m);
      b.innerHTML = dashSwatch(mode.own ? TRACE_COLOURS[0] : INK2, st.dash, mode.own ? 2.5 : 1.5) + " ";
      b.appendChild(document.createTextNode(mode.label));
      const full = mode.circuits.every((c) => c.full);
      b.title = `${mode.label}: ${mode.circuits.length} circuit${mode.circuits.length === 1 ? "" : "s"}, ${full ? "the input turns fully" : "the input rocks"}${mode.own ? " (this document's mode)" : " — click to switch to it"}`;
      b.addEventListener("mousedown", (e) => e.preventDefault());
      b.addEventListener("click", () => chooseMode(m));
      box.appendChild(b);
    });
    for (const label of sc.never || []) {
      const b = document.createElement("button");
      b.type = "button";
      b.disabled = true;
      b.dataset.testid = "mode-never";
      b.textContent = label;
      b.title = `${label} never assembles`;
      box.appendChild(b);
    }
    box.hidden = !(sc.modes || []).length && !(sc.never || []).length;
  }

  function chooseMode(m) {
    const sc = state.scene;
    if (!sc || !sc.modes[m] || sc.modes[m].own) return;
    const doc = clone(state.latestRequested || state.doc);
    for (const [key, value] of Object.entries(sc.modes[m].assembly || {})) {
      setPath(doc, key.startsWith("mechanism.") ? key : `mechanism.${key}`, value);
    }
    requestScene(doc, state.at).then((s) => {
      if (s) status(`Assembly mode: ${sc.modes[m].label}`, "info");
    });
  }

  function renderCircuits(sc) {
    const sel = $("circuit-select");
    const m = ownModeIndex(sc);
    const circuits = m >= 0 ? sc.modes[m].circuits : [];
    $("circuit-label").hidden = circuits.length < 2;
    sel.innerHTML = "";
    circuits.forEach((c, k) => {
      sel.appendChild(new Option(`${k + 1} of ${circuits.length}${c.full ? " (turns)" : " (rocks)"}`, String(k)));
    });
    if (state.cur) sel.value = String(state.cur.circuit);
    const disabled = !state.cur;
    for (const id of ["play", "step-back", "step-fwd", "input-slider"]) $(id).disabled = disabled;
    if (disabled && state.playing) setPlaying(false);
  }

  function currentCircuit() {
    const sc = state.scene;
    if (!sc || !state.cur) return null;
    return sc.modes[state.cur.mode].circuits[state.cur.circuit];
  }

  function updateAtUI() {
    const circ = currentCircuit();
    const slider = $("input-slider");
    if (circ) {
      slider.max = String(circ.input.length - 1);
      if (document.activeElement !== slider || state.playing) slider.value = String(state.cur.index);
      const branch = circ.full ? "" : branchText(circ, state.cur.index);
      $("at-value").textContent = `θ = ${fmtDeg(state.at)}${branch}`;
    } else {
      $("at-value").textContent = finite(state.at) ? `θ = ${fmtDeg(state.at)} (does not assemble)` : "θ = —";
    }
    $("at-value").dataset.at = finite(state.at) ? String(state.at) : "";
    $("circuit-select").value = state.cur ? String(state.cur.circuit) : "";
  }

  function branchText(circ, i) {
    const n = circ.input.length;
    const a = circ.input[Math.max(0, i - 1)];
    const b = circ.input[Math.min(n - 1, i + 1)];
    if (!finite(a) || !finite(b) || Math.abs(b - a) < 1e-12) return "";
    return b > a ? " ↑" : " ↓";
  }

  function setAtIndex(index, circuit) {
    const sc = state.scene;
    if (!sc || !state.cur) return;
    if (circuit !== undefined) state.cur.circuit = circuit;
    const circ = currentCircuit();
    const n = circ.input.length;
    state.cur.index = ((index % n) + n) % n;
    state.exact = null;
    state.at = circ.input[state.cur.index];
    updateAtUI();
    drawAll();
    emit("at", state.at);
  }

  function step(k) {
    if (!state.cur) return;
    setAtIndex(state.cur.index + k);
  }

  let lastFrame = null;
  function setPlaying(on) {
    state.playing = !!on && !!state.cur;
    const b = $("play");
    b.dataset.state = state.playing ? "playing" : "paused";
    b.setAttribute("aria-label", state.playing ? "pause" : "play");
    document.body.dataset.playing = state.playing ? "1" : "0";
    lastFrame = null;
    state.phase = 0;
    if (state.playing) requestAnimationFrame(tick);
  }
  function tick(t) {
    if (!state.playing) return;
    const circ = currentCircuit();
    if (!circ) {
      setPlaying(false);
      return;
    }
    if (lastFrame != null) {
      // One circuit in six seconds at 1×, whatever the sampling.
      state.phase += ((t - lastFrame) / 1000) * state.speed * (circ.input.length / 6);
      const whole = Math.floor(state.phase);
      if (whole > 0) {
        state.phase -= whole;
        setAtIndex(state.cur.index + whole);
      }
    }
    lastFrame = t;
    requestAnimationFrame(tick);
  }

  // ------------------------------------------------------------------ legend, limits list
  function renderLegend(sc) {
    const box = $("legend");
    box.innerHTML = "";
    const traced = sc.traced || [];
    const rows = [];
    (sc.modes || []).forEach((mode, m) => {
      const st = modeStyle(sc, m);
      if (mode.own) {
        traced.forEach((name, k) => {
          const col = TRACE_COLOURS[k % TRACE_COLOURS.length];
          rows.push(`<div class="row">${dashSwatch(col, [], 3)}<span>${esc(name)} · ${esc(mode.label)} <b>(this mode)</b></span></div>`);
        });
      } else {
        rows.push(`<div class="row">${dashSwatch(TRACE_COLOURS[0], st.dash, 1.4)}<span>${esc(mode.label)}</span></div>`);
      }
    });
    for (const label of sc.never || []) {
      rows.push(`<div class="row never">${dashSwatch("#b8c2cc", [1, 3], 1.2)}<span>${esc(label)}: never assembles</span></div>`);
    }
    if (ownLimits(sc).length) {
      rows.push(`<div class="row"><svg width="26" height="10" viewBox="0 0 26 10"><path d="M13 1 L17 5 L13 9 L9 5 Z" fill="${LIMIT_COLOUR}"/></svg><span>limit position (hover)</span></div>`);
    }
    for (const [name, ov] of state.overlays) {
      // an overlay is named in the legend when its style gives it a label
      if (!ov.style || !ov.style.label) continue;
      const col = (ov.style && ov.style.color) || "#868e96";
      rows.push(`<div class="row">${dashSwatch(col, (ov.style && ov.style.dash) || [], 2)}<span>${esc((ov.style && ov.style.label) || name)}</span></div>`);
    }
    box.innerHTML = rows.join("");
  }

  function esc(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
  }

  /** The limit positions of the document's own mode (the others' are theirs to show once
   * chosen), with their index into scene.limits. */
  function ownLimits(sc) {
    const own = ownModeIndex(sc);
    return (sc.limits || []).map((lim, k) => [lim, k]).filter(([lim]) => lim.mode === own);
  }

  function renderLimitsList(sc) {
    const list = $("limits-list");
    list.innerHTML = "";
    const limits = ownLimits(sc);
    $("limits-block").hidden = !limits.length;
    limits.forEach(([lim, k]) => {
      const li = document.createElement("li");
      li.textContent = lim.text;
      li.dataset.limit = String(k);
      li.dataset.testid = "limit-item";
      li.title = "click: show this position";
      li.addEventListener("mouseenter", () => setHoverLimit(k, false));
      li.addEventListener("mouseleave", () => setHoverLimit(null, false));
      li.addEventListener("click", () => {
        const own = ownModeIndex(sc);
        if (lim.mode === own && state.cur) setAtIndex(lim.index, lim.circuit);
      });
      list.appendChild(li);
    });
  }

  function setHoverLimit(k, fromCanvas) {
    if (state.hoverLimit === k) return;
    state.hoverLimit = k;
    for (const li of $("limits-list").children) li.classList.toggle("hover", String(k) === li.dataset.limit);
    if (!fromCanvas) hideTooltip();
    drawAll();
  }

  // ------------------------------------------------------------------ views
  const drawing = () => $("drawing");

  function layoutStage() {
    const sc = state.scene;
    const sphere = !!sc && sc.space === "sphere";
    $("map-wrap").hidden = !sphere;
    const stage = $("stage");
    stage.classList.toggle("column", sphere && stage.clientHeight > stage.clientWidth * 0.95);
    drawing().dataset.view = sphere ? "sphere" : "plane";
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

  function fitPlane() {
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

  const toScreenPlane = (p) => [state.view.ox + state.view.s * p[0], state.view.oy - state.view.s * p[1]];
  const fromScreenPlane = (q) => [(q[0] - state.view.ox) / state.view.s, (state.view.oy - q[1]) / state.view.s];

  function sphereGeom() {
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
  function projectSphere(p, g) {
    const q = mulMV(state.sphere.R, unit3(p));
    return [g.cx + g.r * q[0], g.cy - g.r * q[1], q[2]];
  }
  function unprojectSphere(px, py) {
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

  function resetSphere(sc) {
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

  function toScreen(p) {
    const sc = state.scene;
    if (sc && sc.space === "sphere" && Array.isArray(p) && p.length >= 3) {
      const q = projectSphere(p, sphereGeom());
      return [q[0], q[1]];
    }
    return toScreenPlane(p);
  }

  // ------------------------------------------------------------------ drawing: common
  let drawQueued = false;
  function requestDraw() {
    if (drawQueued) return;
    drawQueued = true;
    requestAnimationFrame(() => {
      drawQueued = false;
      drawAll();
    });
  }

  // The dashed ring under the pointer while a joint is dragged (plane and sphere alike).
  function drawDragPointer(ctx) {
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

  function drawAll() {
    const sc = state.scene;
    const msg = $("canvas-message");
    if (sc && (!sc.modes || !sc.modes.length || (!state.cur && !sc.pose))) {
      msg.textContent = sc.message || "This linkage does not assemble at any input.";
      msg.hidden = false;
    } else msg.hidden = true;
    if (sc && sc.space === "sphere") {
      drawSphere();
      drawMap();
    } else drawPlane();
    drawChartsCursor();
  }

  function strokePoly(ctx, pts) {
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

  function labelText(ctx, text, x, y, colour, align) {
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

  function diamond(ctx, x, y, r, fill, stroke) {
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

  function limitPose(sc, k) {
    const lim = (sc.limits || [])[k];
    if (!lim || !sc.modes[lim.mode] || !sc.modes[lim.mode].circuits[lim.circuit]) return null;
    return samplePose(sc, lim.mode, lim.circuit, lim.index);
  }

  // ------------------------------------------------------------------ drawing: plane
  function drawGrid(ctx, w, h) {
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

  function groundSymbol(ctx, x, y) {
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

  function drawJoints(ctx, sc, pose, project, faded) {
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

  function drawPick(ctx, project) {
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

  function closeIf(circ, pts) {
    if (circ.full && pts.length > 2 && pts[0] && pts[pts.length - 1]) return pts.concat([pts[0]]);
    return pts;
  }

  function drawLimitMarks(ctx, sc, project) {
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

  // ------------------------------------------------------------------ drawing: sphere
  /** Split a projected polyline into runs on the front (z ≥ 0) or back of the sphere. */
  function strokeSide(ctx, proj, front) {
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
  const GRATICULE = graticule();

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

  function drawSphere() {
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
  function fitMapBasis(sc) {
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

  function drawMap() {
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

  function breakJumps(pts, maxJump) {
    const out = [];
    for (let i = 0; i < pts.length; i++) {
      const p = pts[i];
      const q = out.length ? out[out.length - 1] : null;
      if (p && q && Math.hypot(p[0] - q[0], p[1] - q[1]) > maxJump) out.push(null);
      out.push(p);
    }
    return out;
  }

  // ------------------------------------------------------------------ plots
  const seriesColour = (s, k) => (typeof s.color === "string" && /^#[0-9a-fA-F]{3,8}$|^[a-z]+$/.test(s.color) ? s.color : SERIES_COLOURS[k % SERIES_COLOURS.length]);
  const SERIES_COLOURS = ["#2f6bd8", "#d9480f", "#2b8a3e", "#ae3ec9", "#e67700", "#0c8599"];

  const KIND_NAMES = { angles: "Angles", velocity: "Velocity", acceleration: "Acceleration" };

  function renderCharts(sc) {
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
        d.panels.forEach((panel, p) => entries.push({ key, p, x: d.x, panel }));
      }
    }
    const sig = entries.map((e) => `${e.key}/${e.p}/${e.panel.ylabel}/${e.panel.series.map((s) => s.label).join(",")}`).join("|");
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

  function drawChartsCursor() {
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

  function onPointerDown(e) {
    if (e.button !== 0 || !state.scene) return;
    const cv = drawing();
    cv.focus({ preventScroll: true });
    const q = canvasPoint(e);
    cv.setPointerCapture(e.pointerId);
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
    const q = canvasPoint(e);
    const g = state.gesture;
    const cv = drawing();
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
    const g = state.gesture;
    const cv = drawing();
    if (cv.hasPointerCapture && cv.hasPointerCapture(e.pointerId)) cv.releasePointerCapture(e.pointerId);
    state.gesture = null;
    cv.className = state.pick ? "picking" : "";
    if (!g) return;
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
        status(`${pipe.joint}: ${err.message}`, "error");
      })
      .finally(() => {
        pipe.busy = false;
        setBusy(-1);
        if (pipe.latest) pumpDrag();
        else if (pipe.ended && state.dragPipe === pipe) state.dragPipe = null;
      });
  }

  function onWheel(e) {
    if (!state.scene) return;
    e.preventDefault();
    const f = Math.exp(-clamp(e.deltaY, -200, 200) * 0.0015);
    if (state.scene.space === "sphere") {
      state.sphere.zoom = clamp(state.sphere.zoom * f, 0.3, 6);
    } else {
      const q = canvasPoint(e);
      const m = fromScreenPlane(q);
      state.view.s = clamp(state.view.s * f, 1e-6, 1e9);
      state.view.ox = q[0] - state.view.s * m[0];
      state.view.oy = q[1] + state.view.s * m[1];
      state.view.moved = true;
    }
    requestDraw();
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
  function hideTooltip() {
    $("tooltip").hidden = true;
  }

  function fit() {
    const sc = state.scene;
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
    if (e.key === " " || e.code === "Space") {
      e.preventDefault();
      setPlaying(!state.playing);
    } else if (e.key === "ArrowRight" || e.key === "ArrowUp") {
      e.preventDefault();
      step(+1);
    } else if (e.key === "ArrowLeft" || e.key === "ArrowDown") {
      e.preventDefault();
      step(-1);
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
    toScreen: (p) => toScreen(p),
    fromScreen: (q) => modelAt(q),
    fit,
    play: () => setPlaying(true),
    pause: () => setPlaying(false),
    step,
    view: () => ({
      space: state.scene ? state.scene.space : null,
      scale: state.view.s,
      origin: [state.view.ox, state.view.oy],
      rotation: state.sphere.R.slice(),
      zoom: state.sphere.zoom,
    }),
    refresh: () => requestScene(clone(state.latestRequested || state.doc), state.at),
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
    $("step-back").addEventListener("click", () => step(-1));
    $("step-fwd").addEventListener("click", () => step(+1));
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
    let name = decodeURIComponent((location.hash || "").replace(/^#/, ""));
    if (!state.examples.some((e) => e.name === name)) name = "";
    if (!name) name = state.examples.some((e) => e.name === "crank-rocker") ? "crank-rocker" : (state.examples[0] || {}).name;
    if (name) await loadExample(name);
    else if (state.families.length) await loadFamily(state.families[0].family);
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();

/* linkwright workbench: the side panels built from a scene: the top bar and choosers, the
 * parameter fields, the modes and circuits, the animation controls, the legend and the limits. */

import {
  $, INK2, LIMIT_COLOUR, MODE_DASHES, TRACE_COLOURS, clone, finite, fmtDeg, fmtInput, getPath,
  setPath, signLabel,
} from "./util.js";
import { api, emit, ownModeIndex, requestScene, state, status } from "./pipeline.js";
import { drawAll } from "./draw.js";
import { hideTooltip } from "./app.js";
import { wireField } from "./fields.js";
import { markLoaded } from "./history.js";

// ------------------------------------------------------------------ top bar, choosers
export function renderTop(sc) {
  const fam = $("family-select");
  if (fam.value !== sc.family) fam.value = sc.family;
  const ex = $("example-select");
  const want = state.exampleName || "";
  if (ex.value !== want) ex.value = want;
  const title = $("doc-title");
  if (document.activeElement !== title) title.value = sc.document.title || "";
  document.title = `${sc.document.title || sc.family_name || "untitled"} · linkwright`;
}

export function fillChoosers() {
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

export async function loadExample(name) {
  try {
    const doc = await api(`/api/examples/${encodeURIComponent(name)}`);
    status(`Loading ${name}…`, "busy");
    const sc = await requestScene(doc, null, { fit: true, exampleName: name });
    if (sc) {
      markLoaded();
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

export async function loadFamily(family) {
  try {
    const doc = await api(`/api/families/${encodeURIComponent(family)}/default`);
    const f = state.families.find((x) => x.family === family);
    const sc = await requestScene(doc, null, { fit: true, exampleName: f ? f.example : null });
    if (sc) {
      markLoaded();
      status(`${sc.family_name}: ${sc.document.title || "default mechanism"}`, "info");
    }
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

export function renderFields(sc) {
  const form = $("fields");
  const fields = sc.fields || [];
  // labels and groups too: two linkages with joints in the same slots may name them otherwise
  const sig = fields
    .map((f) => `${f.path}:${f.kind}:${f.label}:${groupOf(f, sc.document)}:${(f.choices || []).join(",")}`)
    .join("|");
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
      } else {
        // text, not number: the page parses what was typed (a number input hides "abc" and
        // "1e" behind an empty value) and applies it on Enter or on leaving (fields.js)
        input = document.createElement("input");
        input.type = "text";
        input.inputMode = "decimal";
        input.spellcheck = false;
      }
      wireField(input, f);
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
    // text being typed stays; a focused field that holds what was applied follows the document
    if (!el || (el.tagName === "INPUT" && document.activeElement === el && el.value !== el.dataset.applied)) {
      continue;
    }
    if (el.tagName === "SELECT") el.value = JSON.stringify(f.value);
    else el.value = fmtInput(f.value);
    el.dataset.applied = el.value;
    el.classList.remove("invalid");
  }
  $("family-name").textContent = sc.family_name || sc.family;
  $("space-badge").textContent = sc.space === "sphere" ? "sphere" : "plane";
}

export function markField(path, message) {
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

export function renderInfo(sc) {
  $("range-text").textContent = sc.range || (sc.full ? "every input" : "—");
  $("compute-ms").textContent = finite(sc.compute_ms) ? `${sc.compute_ms.toFixed(1)} ms` : "—";
}

// ------------------------------------------------------------------ modes, circuits, animation UI
export function modeStyle(sc, m) {
  // Own mode solid; the others dashed, each its own pattern, in legend order.
  let k = 0;
  for (let j = 0; j < m; j++) if (!sc.modes[j].own) k++;
  return { own: !!sc.modes[m].own, dash: sc.modes[m].own ? [] : MODE_DASHES[k % MODE_DASHES.length] };
}

function dashSwatch(colour, dash, width) {
  const svg = `<svg width="26" height="8" viewBox="0 0 26 8"><line x1="1" y1="4" x2="25" y2="4" stroke="${colour}" stroke-width="${width}" stroke-dasharray="${dash.join(" ")}"/></svg>`;
  return svg;
}

export function renderModes(sc) {
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

export function renderCircuits(sc) {
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

export function currentCircuit() {
  const sc = state.scene;
  if (!sc || !state.cur) return null;
  return sc.modes[state.cur.mode].circuits[state.cur.circuit];
}

export function updateAtUI() {
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

export function setAtIndex(index, circuit) {
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

export function stepSample(k) {
  if (!state.cur) return;
  setAtIndex(state.cur.index + k);
}

let lastFrame = null;
export function setPlaying(on) {
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
export function renderLegend(sc) {
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
export function ownLimits(sc) {
  const own = ownModeIndex(sc);
  return (sc.limits || []).map((lim, k) => [lim, k]).filter(([lim]) => lim.mode === own);
}

export function renderLimitsList(sc) {
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

export function setHoverLimit(k, fromCanvas) {
  if (state.hoverLimit === k) return;
  state.hoverLimit = k;
  for (const li of $("limits-list").children) li.classList.toggle("hover", String(k) === li.dataset.limit);
  if (!fromCanvas) hideTooltip();
  drawAll();
}

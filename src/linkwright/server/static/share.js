/* linkwright workbench: the whole state in a link, and what a fresh page opens first.
 *
 * A link carries the document (so the assembly mode, which is the document's), the view (the
 * plane's scale and the model point at the drawing's centre, or the sphere's rotation and
 * zoom), the input angle and the circuit shown, the drawing being built, the analysis toggles
 * on the drawing, the forces panel (open, arrows), the input speed and the charts' units: `#s=` then "z." and base64url of deflated
 * compact JSON where the browser has CompressionStream("deflate-raw"), else "j." and the JSON
 * itself. The fragment never reaches the server. A link that is damaged, foreign or too long
 * opens the default example with a one-line message, never a blank page.
 *
 * A fresh page opens, in this order: a link; else the work an earlier visit kept (history.js),
 * on a reload or when the address names no other example; else the example the address names;
 * else the default example. */

import { $, clamp, clone, finite, okPoint } from "./util.js";
import { angDist, emit, ownModeIndex, placeCursor, requestScene, state, status } from "./pipeline.js";
import { loadExample, loadFamily, updateAtUI } from "./panels.js";
import { drawAll, drawing, fromScreenPlane } from "./draw.js";
import { keyOf, markLoaded, offerAction, readWork, sessionKey, setBaseline } from "./history.js";
import { restoreSketch } from "./builder.js";
import { applyOverlayState, overlayState } from "./overlays.js";
import { applyForcesState, forcesState } from "./forces.js";
import { renderCharts } from "./charts.js";

const LINK_PREFIX = "#s=";
const STATE_VERSION = 1;
// A document the server takes is at most its body limit (2 MB): inflating stops there, and a
// link longer than that much base64 is not one this page made.
const MOST_JSON_BYTES = 2_000_000;
const MOST_LINK_CHARS = Math.ceil((MOST_JSON_BYTES * 4) / 3) + 8;
const DEFAULT_EXAMPLE = "crank-rocker";

// ------------------------------------------------------------------ the state and its restoring
/** The page's state as a link carries it (and as history.js keeps it for a reload). */
export function captureSession() {
  const out = { v: STATE_VERSION, d: clone(state.doc) };
  if (state.sketch) out.k = clone(state.sketch);
  out.o = overlayState();
  out.f = forcesState();
  if (state.chartsPhysical) out.p = true;
  if (state.exampleName) out.e = state.exampleName;
  if (finite(state.at)) out.a = state.at;
  if (state.cur) out.c = [state.cur.circuit, state.cur.index];
  const sc = state.scene;
  const sphereView = state.sketch ? state.sketch.space === "sphere" : sc && sc.space === "sphere";
  if (sphereView) {
    out.w = { r: state.sphere.R.slice(), z: state.sphere.zoom, m: state.map.zoom };
  } else if (state.view.moved) {
    // the centre, not the pixel origin: a window of another size shows the same place
    const cv = drawing();
    out.w = { s: state.view.s, c: fromScreenPlane([cv.clientWidth / 2, cv.clientHeight / 2]) };
  } // else the view was fitted, and is fitted again
  return out;
}

function isSketch(k) {
  return !!k && typeof k === "object" && !Array.isArray(k) && Array.isArray(k.joints) && Array.isArray(k.links);
}

function isRotation(r) {
  for (let i = 0; i < 3; i++) {
    for (let j = 0; j < 3; j++) {
      const d = r[3 * i] * r[3 * j] + r[3 * i + 1] * r[3 * j + 1] + r[3 * i + 2] * r[3 * j + 2];
      if (Math.abs(d - (i === j ? 1 : 0)) > 1e-6) return false;
    }
  }
  return true;
}

function applyView(w, sc) {
  if (!w || typeof w !== "object") return;
  if (sc.space === "sphere") {
    if (Array.isArray(w.r) && w.r.length === 9 && w.r.every(finite) && isRotation(w.r)) {
      state.sphere.R = w.r.slice();
      state.sphere.moved = true;
    }
    if (finite(w.z)) state.sphere.zoom = clamp(w.z, 0.3, 6);
    if (finite(w.m)) state.map.zoom = clamp(w.m, 0.5, 8);
  } else if (finite(w.s) && w.s > 0 && okPoint(w.c)) {
    const cv = drawing();
    const v = state.view;
    v.s = clamp(w.s, 1e-6, 1e9);
    v.ox = cv.clientWidth / 2 - v.s * w.c[0];
    v.oy = cv.clientHeight / 2 + v.s * w.c[1];
    v.fitted = true;
    v.moved = true;
  }
}

/** Show the circuit and sample the state names, where they still fit the input angle: a
 * rocking input meets most angles twice, once on each branch. */
function applyCircuit(c, at, sc) {
  const m = ownModeIndex(sc);
  if (!Array.isArray(c) || m < 0 || !finite(at)) return;
  const [k, i] = c;
  const circ = sc.modes[m].circuits[k];
  if (!circ || !Number.isInteger(i) || i < 0 || i >= circ.input.length) return;
  const n = circ.input.length;
  const x = circ.input[i];
  const gap = Math.max(angDist(x, circ.input[(i + 1) % n]), angDist(x, circ.input[(i + n - 1) % n]));
  if (!(angDist(x, at) <= gap + 1e-9)) return;
  if (state.cur && state.cur.circuit === k && state.cur.index === i) return;
  placeCursor(sc, { mode: m, circuit: k, index: i });
  updateAtUI();
  emit("at", state.at);
}

/** Show a captured state; false when the server refused its document (the status line and
 * state.sceneError say why). */
export async function restoreSession(snap) {
  const at = finite(snap.a) ? snap.a : null;
  const exampleName = typeof snap.e === "string" ? snap.e : null;
  const sketch = isSketch(snap.k) ? snap.k : null;
  // the drawing first: the history's first step then holds it with the document
  restoreSketch(sketch);
  const sc = await requestScene(clone(snap.d), at, { fit: true, exampleName });
  if (!sc) {
    restoreSketch(null);
    return false;
  }
  applyView(snap.w, sketch ? { space: sketch.space === "sphere" ? "sphere" : "plane" } : sc);
  // the analysis on the drawing and the charts' units, where the state carries them
  await applyOverlayState(snap.o);
  applyForcesState(snap.f);
  if (typeof snap.p === "boolean" && snap.p !== state.chartsPhysical) {
    state.chartsPhysical = snap.p;
    if (state.scene) renderCharts(state.scene);
  }
  applyCircuit(snap.c, at, sc);
  drawAll();
  return true;
}

// ------------------------------------------------------------------ link text
function toBase64Url(bytes) {
  let bin = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    bin += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(bin).replace(/\+/g, "-").replace(/\//g, "_").replace(/=+$/, "");
}

function fromBase64Url(text) {
  const b64 = text.replace(/-/g, "+").replace(/_/g, "/");
  const bin = atob(b64 + "===".slice((b64.length + 3) % 4));
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}

class TooLarge extends Error {}

async function throughStream(bytes, transform, most) {
  const reader = new Blob([bytes]).stream().pipeThrough(transform).getReader();
  const chunks = [];
  let n = 0;
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    n += value.length;
    if (n > most) {
      reader.cancel().catch(() => {});
      throw new TooLarge(`it holds more than ${most.toLocaleString("en")} bytes`);
    }
    chunks.push(value);
  }
  const out = new Uint8Array(n);
  let at = 0;
  for (const c of chunks) {
    out.set(c, at);
    at += c.length;
  }
  return out;
}

/** The text after `#s=` for a captured state. */
export async function encodeSession(snap) {
  const json = new TextEncoder().encode(JSON.stringify(snap));
  if (typeof CompressionStream === "function") {
    try {
      const z = await throughStream(json, new CompressionStream("deflate-raw"), Infinity);
      return `z.${toBase64Url(z)}`;
    } catch (e) {
      /* a browser without deflate-raw: the plain form below */
    }
  }
  return `j.${toBase64Url(json)}`;
}

const NOT_OURS = "it is not a linkwright state (damaged, cut short, or from elsewhere)";

/** The state a link's text carries; throws an Error whose message says plainly why not. */
export async function decodeSession(text) {
  if (text.length > MOST_LINK_CHARS) throw new Error("it is longer than any state this page makes");
  const m = /^([zj])\.([A-Za-z0-9_-]+)$/.exec(text);
  if (!m) throw new Error(NOT_OURS);
  let bytes;
  try {
    bytes = fromBase64Url(m[2]);
  } catch (e) {
    throw new Error(NOT_OURS);
  }
  if (m[1] === "z") {
    if (typeof DecompressionStream !== "function") {
      throw new Error("this browser cannot read compressed links");
    }
    try {
      bytes = await throughStream(bytes, new DecompressionStream("deflate-raw"), MOST_JSON_BYTES);
    } catch (e) {
      throw e instanceof TooLarge ? new Error(e.message) : new Error(NOT_OURS);
    }
  } else if (bytes.length > MOST_JSON_BYTES) {
    throw new Error(`it holds more than ${MOST_JSON_BYTES.toLocaleString("en")} bytes`);
  }
  let snap;
  try {
    snap = JSON.parse(new TextDecoder("utf-8", { fatal: true }).decode(bytes));
  } catch (e) {
    throw new Error(NOT_OURS);
  }
  if (!snap || typeof snap !== "object" || Array.isArray(snap)) throw new Error(NOT_OURS);
  if (snap.v !== STATE_VERSION) {
    throw new Error(
      finite(snap.v) ? `it was made by another version of linkwright (state format ${snap.v})` : NOT_OURS,
    );
  }
  const d = snap.d;
  if (!d || typeof d !== "object" || Array.isArray(d) || !d.mechanism || typeof d.mechanism !== "object") {
    throw new Error("it holds no mechanism");
  }
  return snap;
}

/** A link that opens exactly this state in a fresh page. The address's access token, if it
 * has one, is left out: a link is for passing on, and the token opens the whole library. */
export async function shareLink() {
  if (!state.doc) throw new Error("there is no mechanism on the page yet");
  const text = await encodeSession(captureSession());
  const query = new URLSearchParams(location.search);
  query.delete("token");
  const search = query.toString() ? `?${query}` : "";
  return `${location.origin}${location.pathname}${search}${LINK_PREFIX}${text}`;
}

async function copyLink() {
  const b = $("copy-link");
  let link;
  try {
    link = await shareLink();
  } catch (e) {
    status(`Copy link: ${e.message}`, "error");
    return;
  }
  b.dataset.link = link;
  const size = `${link.length.toLocaleString("en")} characters`;
  const said = `Link copied: it opens this mechanism, view and input angle (${size})`;
  try {
    await navigator.clipboard.writeText(link);
    status(said, "info");
    return;
  } catch (e) {
    /* no clipboard permission (an insecure address, a strict browser): the older way below */
  }
  const box = document.createElement("textarea");
  box.value = link;
  box.setAttribute("readonly", "");
  box.style.position = "fixed";
  box.style.opacity = "0";
  document.body.appendChild(box);
  box.select();
  let copied = false;
  try {
    copied = document.execCommand("copy");
  } catch (e) {
    copied = false;
  }
  box.remove();
  if (copied) {
    status(said, "info");
    return;
  }
  try {
    history.replaceState(null, "", link);
    status("The browser refused the clipboard: the address bar holds the link; copy it from there", "error");
  } catch (e) {
    status("The browser refused the clipboard, and the address bar cannot hold the link", "error");
  }
}

export function initShare() {
  const b = $("copy-link");
  b.addEventListener("mousedown", (e) => e.preventDefault());
  b.addEventListener("click", copyLink);
  // a link pasted into the address bar of this page changes only the fragment: no new page
  window.addEventListener("hashchange", () => {
    const hash = location.hash || "";
    if (hash.startsWith(LINK_PREFIX)) openLink(hash.slice(LINK_PREFIX.length), false);
  });
}

// ------------------------------------------------------------------ what a fresh page opens
function defaultExampleName() {
  if (state.examples.some((e) => e.name === DEFAULT_EXAMPLE)) return DEFAULT_EXAMPLE;
  return (state.examples[0] || {}).name || null;
}

async function openDefault() {
  const name = defaultExampleName();
  if (name) await loadExample(name);
  else if (state.families.length) await loadFamily(state.families[0].family);
}

function dropFragment() {
  try {
    history.replaceState(null, "", `${location.pathname}${location.search}`);
  } catch (e) {
    /* file:// or sandboxed: the address is only a convenience */
  }
}

function shortName(text) {
  const t = String(text);
  return t.length > 40 ? `${t.slice(0, 39)}…` : t;
}

/** Open a link's state; when it cannot be, a fresh page shows the default example and a page
 * already at work keeps its mechanism (`fresh` false: a link pasted into its address bar). */
async function openLink(text, fresh) {
  // once read, the link is spent: a reload then finds the work done since (history.js)
  dropFragment();
  const instead = fresh ? "; showing the default example" : "";
  let snap;
  try {
    snap = await decodeSession(text);
  } catch (e) {
    if (fresh) await openDefault();
    status(`This link cannot be opened: ${e.message}${instead}`, "error");
    return;
  }
  if (await restoreSession(snap)) {
    markLoaded();
    const title = state.doc.title || state.scene.family_name || "mechanism";
    status(`Opened a shared link: “${shortName(title)}”`, "info");
    return;
  }
  const why = state.sceneError || "the server refused it";
  if (fresh || !state.doc) await openDefault();
  status(`This link's mechanism cannot be opened (${why})${fresh ? instead : ""}`, "error");
}

async function restoreWork(work) {
  if (!(await restoreSession(work.session))) {
    const why = state.sceneError || "the server refused it";
    await openDefault();
    status(`The work of your last visit cannot be opened (${why}); showing the default example`, "error");
    return;
  }
  setBaseline(work.baseline);
  const unsaved = sessionKey() !== work.baseline;
  status(unsaved ? "Restored your unsaved work" : "Restored your last session", "info");
  const ex = work.session.e;
  const known = typeof ex === "string" && state.examples.some((e) => e.name === ex);
  offerAction(known ? "back to the example" : "open the default example", () =>
    known ? loadExample(ex) : openDefault(),
  );
}

/** Open the page's first mechanism (see the order at the top of this module). */
export async function openFirst() {
  const hash = location.hash || "";
  if (hash.startsWith(LINK_PREFIX)) {
    await openLink(hash.slice(LINK_PREFIX.length), true);
    return;
  }
  let name = "";
  try {
    name = decodeURIComponent(hash.replace(/^#/, ""));
  } catch (e) {
    name = hash.replace(/^#/, "");
  }
  const known = !!name && state.examples.some((e) => e.name === name);
  const work = readWork();
  const nav = (performance.getEntriesByType ? performance.getEntriesByType("navigation")[0] : null) || {};
  const again = nav.type === "reload" || nav.type === "back_forward";
  if (work && (again || !name || name === work.session.e)) {
    await restoreWork(work);
    return;
  }
  if (known) await loadExample(name);
  else await openDefault();
  if (name && !known) {
    status(`There is no example “${shortName(name)}”; showing the default example`, "error");
  } else if (work && keyOf(work.session.d, work.session.k) !== work.baseline) {
    // the address asked for another example: the earlier work is one click away, not lost
    offerAction("restore your unsaved work", () => restoreWork(work));
  }
}

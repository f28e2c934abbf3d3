/* linkwright workbench: the side panel's tools (library, paper 002's pivot study, synthesis,
 * exports). Uses the page API `window.lw` defined by app.js (see the workbench contract) and the
 * JSON routes under /api. Plain JavaScript, no build step, nothing fetched from elsewhere. */
(function () {
  "use strict";

  const FORMATS = [
    ["png", "PNG", "the picture: linkage at the current input, every curve"],
    ["svg", "SVG", "vector drawing: linkage, curves, labels"],
    ["dxf", "DXF", "CAD drawing (R2010): links, joints, curves on layers"],
    ["csv", "CSV", "every joint's path along the circuit"],
    ["gif", "GIF", "animation of one circuit (48 frames)"],
    ["toml", "TOML", "the document file"],
    ["json", "JSON", "the document as JSON"],
  ];
  const DIRECTIONS = [
    ["left", "left (−x)"],
    ["right", "right (+x)"],
    ["up", "up (+y)"],
    ["down", "down (−y)"],
    ["angle", "angle…"],
  ];

  // ------------------------------------------------------------------------------------------
  // Small helpers
  // ------------------------------------------------------------------------------------------

  /** An element: h("button", {id, testid, class, text, onclick, ...}, ...children). */
  function h(tag, props, ...kids) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(props || {})) {
      if (v === null || v === undefined || v === false) continue;
      if (k === "testid") e.dataset.testid = v;
      else if (k === "class") e.className = v;
      else if (k === "text") e.textContent = v;
      else if (k === "dataset") Object.assign(e.dataset, v);
      else if (k.startsWith("on") && typeof v === "function") e.addEventListener(k.slice(2), v);
      else if (k === "checked" || k === "value" || k === "disabled") e[k] = v;
      else e.setAttribute(k, v === true ? "" : String(v));
    }
    for (const kid of kids.flat()) {
      if (kid !== null && kid !== undefined && kid !== false) e.append(kid);
    }
    return e;
  }

  /** A number for people: up to 4 significant digits, no trailing zeros, true minus sign. */
  function fmt(x, digits = 4) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "—";
    if (x === 0) return "0";
    let s = Math.abs(x) >= 1e5 || Math.abs(x) < 1e-3 ? x.toExponential(digits - 1)
      : x.toPrecision(digits);
    if (s.includes(".") && !s.includes("e")) s = s.replace(/0+$/, "").replace(/\.$/, "");
    return s.replace("-", "−");
  }

  function pct(x) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "—";
    return x < 1e-4 ? "< 0.01 %" : `${fmt(100 * x, 3)} %`;
  }

  function when(t) {
    if (!Number.isFinite(t)) return "—";
    const d = new Date(t * 1000);
    const pad = (n) => String(n).padStart(2, "0");
    return `${d.getFullYear()}-${pad(d.getMonth() + 1)}-${pad(d.getDate())} `
      + `${pad(d.getHours())}:${pad(d.getMinutes())}`;
  }

  /** fetch with the API's error convention: rejects with Error(the {"error"} line). */
  async function call(method, path, body, { raw = false } = {}) {
    const init = { method, headers: {} };
    if (body instanceof FormData) {
      init.body = body;
    } else if (body !== undefined) {
      init.headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(body);
    }
    let res;
    try {
      res = await fetch(path, init);
    } catch (e) {
      throw new Error(`cannot reach the workbench server (${e.message})`);
    }
    if (!res.ok) {
      let message = `${res.status} ${res.statusText}`;
      try {
        const j = await res.json();
        if (j && j.error) message = j.error;
      } catch (_) { /* not JSON: keep the status line */ }
      const err = new Error(message);
      err.status = res.status;
      throw err;
    }
    return raw ? res : res.json();
  }

  function lwStatus(text, kind) {
    if (window.lw && typeof window.lw.status === "function") window.lw.status(text, kind || "info");
  }

  /** Marks a panel's state for people (CSS) and tests: idle | running | done | error. */
  function setState(el, state) {
    el.dataset.state = state;
  }

  /** The current document's title or a name for it. */
  function docTitle(doc) {
    if (doc && doc.title) return doc.title;
    return doc && doc.mechanism ? doc.mechanism.family : "mechanism";
  }

  /** Distinct colours for n curves: blue → violet → red → orange. */
  function palette(n) {
    const out = [];
    for (let i = 0; i < n; i++) {
      const t = n <= 1 ? 0 : i / (n - 1);
      out.push(`hsl(${Math.round(215 - 200 * t)}, 72%, ${Math.round(42 + 6 * Math.sin(Math.PI * t))}%)`);
    }
    return out;
  }

  /** A polyline list with nulls (breaks) as a list of runs of [x, y] points. */
  function runs(rows) {
    const out = [];
    let cur = [];
    for (const p of rows || []) {
      if (p && Number.isFinite(p[0]) && Number.isFinite(p[1])) cur.push(p);
      else if (cur.length) { out.push(cur); cur = []; }
    }
    if (cur.length) out.push(cur);
    return out;
  }

  /** The size of the current drawing (for sensible default steps). */
  function sceneSize(scene) {
    if (!scene || !scene.pose) return 1;
    let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    for (const p of Object.values(scene.pose)) {
      if (!p) continue;
      lo = [Math.min(lo[0], p[0]), Math.min(lo[1], p[1])];
      hi = [Math.max(hi[0], p[0]), Math.max(hi[1], p[1])];
    }
    const s = Math.max(hi[0] - lo[0], hi[1] - lo[1]);
    return Number.isFinite(s) && s > 0 ? s : 1;
  }

  /** A round number near x (1, 2, 2.5 or 5 times a power of ten). */
  function niceStep(x) {
    const p = Math.pow(10, Math.floor(Math.log10(x)));
    for (const m of [1, 2, 2.5, 5, 10]) if (m * p >= x) return m * p;
    return 10 * p;
  }

  /** Download bytes as a file the way a link would. */
  function saveBlob(blob, name) {
    const url = URL.createObjectURL(blob);
    const a = h("a", { href: url, download: name, style: "display:none" });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 30000);
  }

  function filenameOf(res, fallback) {
    const cd = res.headers.get("Content-Disposition") || "";
    const star = /filename\*=UTF-8''([^;]+)/i.exec(cd);
    if (star) {
      try { return decodeURIComponent(star[1]); } catch (_) { /* fall through */ }
    }
    const plain = /filename="?([^";]+)"?/i.exec(cd);
    return plain ? plain[1] : fallback;
  }

  /** Draw curves on a small canvas, fitted with a margin, y up. */
  function preview(canvas, layers) {
    const dpr = window.devicePixelRatio || 1;
    const w = canvas.clientWidth || Number(canvas.getAttribute("width")) || 80;
    const hgt = canvas.clientHeight || Number(canvas.getAttribute("height")) || 60;
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(hgt * dpr);
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, hgt);
    let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    for (const layer of layers) {
      for (const run of runs(layer.points)) {
        for (const p of run) {
          lo = [Math.min(lo[0], p[0]), Math.min(lo[1], p[1])];
          hi = [Math.max(hi[0], p[0]), Math.max(hi[1], p[1])];
        }
      }
    }
    if (!Number.isFinite(lo[0])) return;
    const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], 1e-12);
    const k = Math.min((w - 8) / Math.max(hi[0] - lo[0], span * 0.05),
      (hgt - 8) / Math.max(hi[1] - lo[1], span * 0.05));
    const cx = (lo[0] + hi[0]) / 2, cy = (lo[1] + hi[1]) / 2;
    for (const layer of layers) {
      ctx.strokeStyle = layer.color;
      ctx.lineWidth = layer.width || 1.5;
      ctx.setLineDash(layer.dash || []);
      for (const run of runs(layer.points)) {
        ctx.beginPath();
        run.forEach((p, i) => {
          const x = w / 2 + k * (p[0] - cx), y = hgt / 2 - k * (p[1] - cy);
          if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y);
        });
        ctx.stroke();
      }
    }
  }

  /** x, y rows from CSV text (or x, y, z rows: directions on the sphere): a header line and '#'
   * comments allowed; every other line has as many numbers as the first. Throws an Error naming
   * the line. */
  function parseCsv(text) {
    const points = [];
    const lines = String(text).split(/\r\n|\n|\r/);
    let seenData = false;
    for (let i = 0; i < lines.length; i++) {
      const line = lines[i].trim();
      if (!line || line.startsWith("#")) continue;
      const cells = line.split(/\s*[,;\t]\s*|\s+/).filter((c) => c !== "");
      const nums = cells.map(Number);
      const numeric = cells.every((c, j) => c !== "" && Number.isFinite(nums[j]));
      if (!numeric) {
        if (!seenData && points.length === 0 && (cells.length === 2 || cells.length === 3)
          && !cells.some((c) => Number.isFinite(Number(c)))) {
          seenData = true; // the header
          continue;
        }
        const bad = cells.find((c) => !Number.isFinite(Number(c)));
        throw new Error(`CSV line ${i + 1}: ${JSON.stringify(bad)} is not a number (expected x, y)`);
      }
      seenData = true;
      const width = points.length ? points[0].length : cells.length;
      if (cells.length !== width || (width !== 2 && width !== 3)) {
        const want = width === 3 ? "x, y, z (as the first line)" : "x, y (x, y, z on the sphere)";
        throw new Error(`CSV line ${i + 1}: ${cells.length} values; each line must be ${want}`);
      }
      points.push(nums);
    }
    if (points.length < 5) {
      throw new Error(`CSV: ${points.length} points; a curve needs at least 5 (8 to match)`);
    }
    return points;
  }

  // ------------------------------------------------------------------------------------------
  // The panels
  // ------------------------------------------------------------------------------------------

  function start(lw) {
    if (!document.querySelector('link[href="/static/tools.css"]')) {
      document.head.append(h("link", { rel: "stylesheet", href: "/static/tools.css" }));
    }
    const library = libraryPanel(lw, document.getElementById("tab-library"));
    const study = studyPanel(lw, document.getElementById("tab-study"));
    const synthesis = synthesisPanel(lw, document.getElementById("tab-synthesis"));
    exportPanel(lw, document.getElementById("tab-export"));
    // Refresh a panel when it is shown, however app.js shows it.
    const shown = { "tab-library": library.refresh, "tab-synthesis": synthesis.shown,
      "tab-study": study.shown };
    for (const [id, fn] of Object.entries(shown)) {
      const section = document.getElementById(id);
      if (!section || !fn) continue;
      new MutationObserver(() => { if (!section.hidden) fn(); })
        .observe(section, { attributes: true, attributeFilter: ["hidden", "class", "style"] });
      if (!section.hidden) fn();
    }
    window.lwTools = { library, study, synthesis, parseCsv };
  }

  // ---- Library ------------------------------------------------------------------------------

  function libraryPanel(lw, root) {
    if (!root) return { refresh() {} };
    root.replaceChildren();
    setState(root, "idle");
    const name = h("input", { id: "lib-name", testid: "lib-name", type: "text", placeholder: "name",
      "aria-label": "name to save as", spellcheck: "false" });
    const save = h("button", { id: "lib-save", testid: "lib-save", type: "button", class: "primary",
      text: "Save" });
    const conflict = h("div", { id: "lib-conflict", testid: "lib-conflict", class: "notice", hidden: true });
    const fileInput = h("input", { id: "lib-import-file", testid: "lib-import-file", type: "file",
      accept: ".toml,.json,application/json,application/toml", class: "visually-hidden" });
    const importBtn = h("button", { id: "lib-import", testid: "lib-import", type: "button",
      text: "Import file…", title: "import a .toml or .json document into the library" });
    const refreshBtn = h("button", { id: "lib-refresh", testid: "lib-refresh", type: "button",
      text: "↻", title: "reload the list", "aria-label": "reload the list" });
    const count = h("span", { id: "lib-count", testid: "lib-count", class: "muted" });
    const list = h("ul", { id: "lib-list", testid: "lib-list", class: "lib-list" });
    const empty = h("p", { id: "lib-empty", testid: "lib-empty", class: "muted", hidden: true,
      text: "Nothing saved yet: name the current mechanism and press Save." });

    root.append(
      h("h3", { text: "Save current" }),
      h("form", { class: "row", onsubmit: (e) => { e.preventDefault(); doSave(false); } }, name, save),
      conflict,
      h("div", { class: "row spread" }, h("h3", { text: "Saved mechanisms" }), h("span", {}, count, refreshBtn)),
      list,
      empty,
      h("div", { class: "row" }, importBtn, fileInput),
    );

    let entries = [];
    let current = null; // id of the entry last loaded or saved
    let nameTouched = false;
    name.addEventListener("input", () => { nameTouched = true; });
    save.addEventListener("click", () => doSave(false));
    lw.on("scene", (scene) => {
      if (!nameTouched && document.activeElement !== name) {
        name.value = (scene && scene.title) || "";
      }
    });

    async function refresh() {
      try {
        entries = await call("GET", "/api/library");
        render();
      } catch (e) {
        lwStatus(`library: ${e.message}`, "error");
        setState(root, "error");
      }
    }

    // A row showing a rename form or a delete question survives a refresh of the list (a save's,
    // an import's, the ↻ button's): what the person was typing, and where, stays theirs.
    let editing = null; // { id, li }

    function render() {
      if (editing && !entries.some((e) => e.id === editing.id)) editing = null;
      const focused = list.contains(document.activeElement) ? document.activeElement : null;
      const selection = focused && typeof focused.selectionStart === "number"
        ? [focused.selectionStart, focused.selectionEnd] : null;
      list.replaceChildren(...entries.map((e) => (editing && editing.id === e.id ? editing.li : row(e))));
      if (focused && focused.isConnected) {
        focused.focus();
        if (selection) focused.setSelectionRange(...selection);
      }
      empty.hidden = entries.length > 0;
      count.textContent = entries.length ? `${entries.length}` : "";
    }

    function closeEdit() {
      editing = null;
      render();
    }

    function openEdit(li, entry, content) {
      li.replaceChildren(content);
      editing = { id: entry.id, li };
      render(); // a row left open elsewhere goes back to its plain form
    }

    function row(entry) {
      const li = h("li", { class: "lib-entry" + (entry.id === current ? " current" : ""),
        testid: "lib-entry", dataset: { id: String(entry.id), name: entry.name } });
      const title = h("span", { class: "lib-title", testid: "lib-entry-name", text: entry.name,
        title: entry.title || entry.name });
      const meta = h("span", { class: "lib-meta", testid: "lib-entry-meta" },
        h("span", { class: "lib-family", text: entry.family || "" }), " · ",
        h("time", { text: when(entry.modified) }));
      const load = h("button", { type: "button", testid: "lib-load", text: "Load",
        title: `load ${entry.name}`, onclick: () => doLoad(entry) });
      const rename = h("button", { type: "button", testid: "lib-rename", text: "Rename",
        onclick: () => startRename(li, entry) });
      const del = h("button", { type: "button", testid: "lib-delete", class: "danger", text: "Delete",
        onclick: () => confirmDelete(li, entry) });
      const ex = h("span", { class: "lib-export" },
        h("a", { href: `/api/library/${entry.id}/export?format=toml`, download: "", testid: "lib-export-toml",
          text: "TOML", title: "download as TOML" }),
        h("a", { href: `/api/library/${entry.id}/export?format=json`, download: "", testid: "lib-export-json",
          text: "JSON", title: "download as JSON" }));
      li.append(h("div", { class: "lib-head" }, title, meta),
        h("div", { class: "lib-actions" }, load, rename, del, ex));
      return li;
    }

    async function doSave(overwrite) {
      const n = name.value.trim();
      if (!n) {
        lwStatus("library: give the mechanism a name to save it under", "error");
        name.focus();
        return;
      }
      setState(root, "running");
      conflict.hidden = true;
      try {
        const entry = await call("POST", "/api/library", { name: n, document: lw.document(), overwrite });
        current = entry.id;
        // What the library holds is saved work: leaving the page no longer asks.
        if (lw.markSaved) lw.markSaved();
        lwStatus(`saved “${entry.name}” in the library`, "info");
        await refresh();
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        if (e.status === 409) {
          conflict.replaceChildren(
            h("span", { text: `“${n}” is already in the library.` }),
            h("button", { type: "button", id: "lib-overwrite", testid: "lib-overwrite", class: "danger",
              text: "Replace it", onclick: () => doSave(true) }),
            h("button", { type: "button", testid: "lib-overwrite-cancel", text: "Cancel",
              onclick: () => { conflict.hidden = true; } }));
          conflict.hidden = false;
        }
        lwStatus(`library: ${e.message}`, "error");
      }
    }

    async function doLoad(entry) {
      setState(root, "running");
      try {
        const full = await call("GET", `/api/library/${entry.id}`);
        current = entry.id;
        if (!(await lw.setDocument(full.document, { title: full.document.title }))) {
          throw new Error(`“${entry.name}” could not be drawn`);
        }
        if (lw.markSaved) lw.markSaved();
        nameTouched = true;
        name.value = entry.name;
        render();
        lwStatus(`loaded “${entry.name}” from the library`, "info");
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`library: ${e.message}`, "error");
      }
    }

    function startRename(li, entry) {
      const input = h("input", { type: "text", testid: "lib-rename-input", value: entry.name,
        "aria-label": `new name for ${entry.name}` });
      const ok = h("button", { type: "button", testid: "lib-rename-ok", class: "primary", text: "OK" });
      const cancel = h("button", { type: "button", testid: "lib-rename-cancel", text: "Cancel", onclick: closeEdit });
      const form = h("form", { class: "row", onsubmit: async (e) => {
        e.preventDefault();
        const n = input.value.trim();
        if (!n || n === entry.name) { closeEdit(); return; }
        setState(root, "running");
        try {
          await call("PATCH", `/api/library/${entry.id}`, { name: n });
          editing = null;
          lwStatus(`renamed “${entry.name}” to “${n}”`, "info");
          await refresh();
          setState(root, "done");
        } catch (err) {
          setState(root, "error");
          lwStatus(`library: ${err.message}`, "error");
          input.focus();
        }
      } }, input, ok, cancel);
      ok.addEventListener("click", () => form.requestSubmit());
      input.addEventListener("keydown", (e) => { if (e.key === "Escape") closeEdit(); });
      openEdit(li, entry, form);
      input.focus();
      input.select();
    }

    function confirmDelete(li, entry) {
      const yes = h("button", { type: "button", testid: "lib-delete-confirm", class: "danger",
        text: "Delete", onclick: async () => {
          setState(root, "running");
          try {
            await call("DELETE", `/api/library/${entry.id}`);
            editing = null;
            if (current === entry.id) current = null;
            lwStatus(`deleted “${entry.name}” from the library`, "info");
            await refresh();
            setState(root, "done");
          } catch (e) {
            setState(root, "error");
            lwStatus(`library: ${e.message}`, "error");
          }
        } });
      const no = h("button", { type: "button", testid: "lib-delete-cancel", text: "Keep", onclick: closeEdit });
      openEdit(li, entry, h("div", { class: "confirm" },
        h("span", { text: `Delete “${entry.name}”? This cannot be undone.` }), h("div", { class: "row" }, yes, no)));
      no.focus();
    }

    importBtn.addEventListener("click", () => fileInput.click());
    fileInput.addEventListener("change", async () => {
      const file = fileInput.files && fileInput.files[0];
      if (!file) return;
      const form = new FormData();
      form.append("file", file, file.name);
      setState(root, "running");
      try {
        const entry = await call("POST", "/api/library/import", form);
        current = entry.id;
        lwStatus(`imported ${file.name} as “${entry.name}”`, "info");
        await refresh();
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`import: ${e.message}`, "error");
      } finally {
        fileInput.value = "";
      }
    });
    refreshBtn.addEventListener("click", refresh);
    return { refresh };
  }

  // ---- Paper 002's pivot study ----------------------------------------------------------------

  function studyPanel(lw, root) {
    if (!root) return {};
    root.replaceChildren();
    setState(root, "idle");
    const pivot = h("select", { id: "study-pivot", testid: "study-pivot", "aria-label": "pivot to move" });
    const direction = h("select", { id: "study-direction", testid: "study-direction", "aria-label": "direction" },
      DIRECTIONS.map(([v, t]) => h("option", { value: v, text: t })));
    const angle = h("input", { id: "study-angle", testid: "study-angle", type: "number", step: "any",
      value: "0", "aria-label": "direction angle (degrees from +x)", disabled: true });
    const step = h("input", { id: "study-step", testid: "study-step", type: "number", step: "any", min: "0",
      value: "0.5", "aria-label": "step length" });
    const count = h("input", { id: "study-count", testid: "study-count", type: "number", step: "1", min: "1",
      max: "50", value: "3", "aria-label": "number of steps" });
    const run = h("button", { id: "study-run", testid: "study-run", type: "button", class: "primary",
      text: "Run study" });
    const clear = h("button", { id: "study-clear", testid: "study-clear", type: "button", text: "Clear" });
    const note = h("p", { id: "study-note", testid: "study-note", class: "muted small" });
    const legend = h("ol", { id: "study-legend", testid: "study-legend", class: "study-legend" });
    const stale = h("p", { id: "study-stale", testid: "study-stale", class: "notice", hidden: true,
      text: "The mechanism has changed since this study; run it again to follow." });

    root.append(
      h("p", { class: "muted small",
        text: "Paper 002's study: move one fixed pivot step by step and compare the curves." }),
      h("div", { class: "grid2" },
        h("label", { for: "study-pivot", text: "pivot" }), pivot,
        h("label", { for: "study-direction", text: "direction" }), direction,
        h("label", { for: "study-angle", text: "angle (°)" }), angle,
        h("label", { for: "study-step", text: "step" }), step,
        h("label", { for: "study-count", text: "steps" }), count),
      h("div", { class: "row" }, run, clear),
      note, stale, legend);

    let overlays = [];
    let studied = null; // the document string the overlay belongs to
    let studiedFamily = null;
    let stepFamily = null;

    direction.addEventListener("change", () => { angle.disabled = direction.value !== "angle"; });

    function fillPivots(scene) {
      if (studied !== null) {
        // Another family's curves say nothing about this linkage: clear them; the same
        // family's (a step loaded, a field edited) stay, marked as out of date.
        if (scene && scene.family !== studiedFamily) clearStudy();
        else stale.hidden = JSON.stringify(scene && scene.document) === studied;
      }
      const fixed = (scene && scene.space === "plane" && scene.fixed) || [];
      const keep = pivot.value;
      pivot.replaceChildren(...fixed.map((j) => h("option", { value: j, text: j })));
      if (fixed.includes(keep)) pivot.value = keep;
      const usable = fixed.length > 0;
      run.disabled = !usable;
      if (!usable) {
        note.textContent = scene && scene.space === "sphere"
          ? "The pivot study moves pivots in the plane; this linkage is spherical."
          : "This linkage has no fixed pivot to move.";
      } else if (!overlays.length) {
        note.textContent = "";
      }
      // A step of about a tenth of the drawing, set again when the family changes.
      const fam = scene && scene.family;
      if (fam !== stepFamily && scene && scene.pose) {
        stepFamily = fam;
        step.value = String(niceStep(sceneSize(scene) / 10));
      }
    }
    lw.on("scene", fillPivots);
    if (lw.scene && lw.scene()) fillPivots(lw.scene());

    function clearStudy() {
      for (const n of overlays) lw.clearOverlay(n);
      overlays = [];
      studied = null;
      legend.replaceChildren();
      stale.hidden = true;
      note.textContent = "";
      setState(root, "idle");
    }
    clear.addEventListener("click", clearStudy);

    run.addEventListener("click", async () => {
      const scene = lw.scene();
      const doc = lw.document();
      const dir = direction.value === "angle" ? Number(angle.value) : direction.value;
      const body = { document: doc, pivot: pivot.value, direction: dir, step: Number(step.value),
        count: Math.round(Number(count.value)) };
      if (direction.value === "angle" && !Number.isFinite(dir)) {
        lwStatus("study: the angle must be a number of degrees", "error");
        return;
      }
      setState(root, "running");
      run.disabled = true;
      lwStatus(`studying pivot ${body.pivot}…`, "busy");
      try {
        const res = await call("POST", "/api/study", body);
        for (const n of overlays) lw.clearOverlay(n);
        overlays = [];
        studied = JSON.stringify(scene ? scene.document : doc);
        studiedFamily = scene ? scene.family : doc.mechanism.family;
        stale.hidden = true;
        const colours = palette(res.steps.length);
        const size = sceneSize(scene);
        const origin = scene && scene.pose ? scene.pose[res.pivot] : null;
        legend.replaceChildren();
        res.steps.forEach((s, i) => {
          const curves = [];
          for (const rows of Object.values(s.curves || {})) curves.push(...runs(rows));
          if (origin) { // a small cross where the pivot sits at this step
            const c = [origin[0] + s.offset[0], origin[1] + s.offset[1]], r = size / 60;
            curves.push([[c[0] - r, c[1] - r], [c[0] + r, c[1] + r]], [[c[0] - r, c[1] + r], [c[0] + r, c[1] - r]]);
          }
          const name = `study-${i}`;
          const label = `${s.steps === 0 ? "study: start" : `step ${s.steps}`} (${fmt(s.offset[0], 3)}, ${fmt(s.offset[1], 3)})`;
          const inLegend = res.steps.length <= 6 || i === 0 || i === res.steps.length - 1;
          lw.overlay(name, curves, { color: colours[i], width: i === 0 ? 2 : 1.5, dash: s.full ? null : [5, 4],
            label, legend: inLegend });
          overlays.push(name);
          const state = !s.assembles ? "cannot assemble" : s.full ? "turns fully" : "locks: rocks";
          const li = h("li", { testid: "study-row", dataset: { steps: String(s.steps), full: String(s.full),
            assembles: String(s.assembles) }, class: s.assembles ? "" : "dead" },
            h("span", { class: "swatch", style: `border-color:${colours[i]}` + (s.full ? "" : ";border-top-style:dashed") }),
            h("span", { class: "study-text", text: `${s.steps === 0 ? "start" : `step ${s.steps}`}: `
              + `(${fmt(s.offset[0])}, ${fmt(s.offset[1])})` }),
            h("span", { class: "study-state " + (s.full ? "ok" : "warn"), testid: "study-state", text: state,
              title: s.note || state }),
            s.document ? h("button", { type: "button", class: "link", testid: "study-load", text: "load",
              title: "load this step's mechanism", onclick: () => lw.setDocument(s.document, { title: s.document.title }) })
              : null);
          legend.append(li);
        });
        const locked = res.steps.filter((s) => !s.full).length;
        note.textContent = `${res.note}. ${res.steps.length} positions`
          + (locked ? `; ${locked} where the input no longer turns fully (dashed).` : "; the input turns fully at each.");
        lwStatus(`study of ${res.pivot}: ${res.steps.length} curves overlaid`, "info");
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`study: ${e.message}`, "error");
      } finally {
        run.disabled = !pivot.options.length;
      }
    });
    return { clear: clearStudy, shown() {} };
  }

  // ---- Synthesis ------------------------------------------------------------------------------

  function synthesisPanel(lw, root) {
    if (!root) return {};
    root.replaceChildren();
    setState(root, "idle");
    const draw = h("button", { id: "synth-draw", testid: "synth-draw", type: "button", class: "primary",
      text: "Draw target curve", title: "press, drag and release on the drawing" });
    const csvInput = h("input", { id: "synth-csv", testid: "synth-csv", type: "file", accept: ".csv,.txt,text/csv",
      class: "visually-hidden" });
    const csvBtn = h("button", { id: "synth-csv-button", testid: "synth-csv-button", type: "button",
      text: "Import CSV…", title: "x, y per line (a header line is allowed)" });
    const clearTarget = h("button", { id: "synth-clear", testid: "synth-clear", type: "button", text: "Clear" });
    const targetInfo = h("p", { id: "synth-target-info", testid: "synth-target-info", class: "muted small",
      text: "No target yet." });

    const top = h("select", { id: "synth-top", testid: "synth-top", "aria-label": "candidates" },
      [3, 5, 8].map((n) => h("option", { value: String(n), text: `${n} candidates` })));
    top.value = "5";
    const refine = h("input", { id: "synth-refine", testid: "synth-refine", type: "checkbox", checked: true });
    const openCurve = h("input", { id: "synth-open", testid: "synth-open", type: "checkbox" });
    const matchBtn = h("button", { id: "synth-match", testid: "synth-match", type: "button", class: "primary",
      text: "Match", disabled: true });
    const atlasInfo = h("p", { id: "synth-atlas", testid: "synth-atlas", class: "muted small" });
    const candidates = h("ol", { id: "synth-candidates", testid: "synth-candidates", class: "candidates" });

    const circle = h("select", { id: "synth-circle", testid: "synth-circle", "aria-label": "Cardan circle" },
      h("option", { value: "small", text: "small circle (a − b)/2" }),
      h("option", { value: "large", text: "large circle (a + b)/2" }));
    const fitBtn = h("button", { id: "synth-ellipse", testid: "synth-ellipse", type: "button", class: "primary",
      text: "Fit ellipse", disabled: true });
    const ellipseInfo = h("dl", { id: "synth-ellipse-info", testid: "synth-ellipse-info", class: "facts", hidden: true });
    const s1 = h("input", { id: "synth-s1", testid: "synth-s1", type: "range", min: "0", max: "179.5", step: "0.5",
      value: "90", "aria-label": "slider R's guide angle s1" });
    const s2 = h("input", { id: "synth-s2", testid: "synth-s2", type: "range", min: "0", max: "179.5", step: "0.5",
      value: "0", "aria-label": "slider Q's guide angle s2" });
    const s1v = h("output", { id: "synth-s1-value", testid: "synth-s1-value", text: "90°" });
    const s2v = h("output", { id: "synth-s2-value", testid: "synth-s2-value", text: "0°" });
    const trammelInfo = h("p", { id: "synth-trammel", testid: "synth-trammel", class: "muted small" });
    const members = h("div", { id: "synth-family", testid: "synth-family", class: "chips" });
    const family = h("div", { id: "synth-family-box", class: "family", hidden: true },
      h("div", { class: "grid3" },
        h("label", { for: "synth-s1", text: "s1 (R)" }), s1, s1v,
        h("label", { for: "synth-s2", text: "s2 (Q)" }), s2, s2v),
      trammelInfo,
      h("p", { class: "muted small", text: "Members of the family (slider angles from the major axis):" }),
      members);

    root.append(
      h("h3", { text: "Target curve" }),
      h("div", { class: "row" }, draw, csvBtn, clearTarget, csvInput),
      targetInfo,
      h("h3", { text: "Four-bar from the atlas" }),
      h("div", { class: "row" }, top,
        h("label", { class: "check", for: "synth-refine" }, refine, " refine"),
        h("label", { class: "check", for: "synth-open", title: "the target is a piece of the curve wanted" },
          openCurve, " open"), matchBtn),
      atlasInfo,
      candidates,
      h("h3", { text: "Ellipse → double sliders (paper 004)" }),
      h("div", { class: "row" }, circle, fitBtn),
      ellipseInfo,
      family);

    let target = null;
    let ellipse = null;
    let polling = null;
    const prepared = {}; // by space: the plane's four-bar atlas, the sphere's spherical one
    let atlasSpace = "plane"; // the atlas the status line speaks of
    let trammelSeq = 0;
    let trammelTimer = null;

    let targetSource = "";
    function showTarget() {
      const points = target;
      const open = openCurve.checked;
      lw.overlay("synth-target", [open ? points : points.concat([points[0]])], { color: "#111827", width: 2,
        dash: [6, 4], label: "target curve" });
      targetInfo.textContent = `${points.length} points (${targetSource}); the curve is taken as ${
        open ? "open, a piece of the curve wanted" : "closed"}.`;
    }

    function setTarget(points, source) {
      target = points;
      targetSource = source;
      showTarget();
      matchBtn.disabled = points.length < 8;
      fitBtn.disabled = points.length < 5 || points[0].length !== 2; // an ellipse is planar
      candidates.replaceChildren();
      root.dataset.target = String(points.length);
    }

    draw.addEventListener("click", () => {
      lwStatus("draw the target curve on the drawing: press, drag, release", "info");
      draw.classList.add("active");
      lw.pickPoints((points) => {
        draw.classList.remove("active");
        if (!points || points.length < 5) {
          lwStatus("synthesis: the drawn curve has too few points; draw a longer stroke", "error");
          return;
        }
        setTarget(points, "drawn");
        lwStatus(`target curve: ${points.length} points drawn`, "info");
      });
    });
    csvBtn.addEventListener("click", () => csvInput.click());
    csvInput.addEventListener("change", async () => {
      const file = csvInput.files && csvInput.files[0];
      if (!file) return;
      try {
        const points = parseCsv(await file.text());
        setTarget(points, file.name);
        lwStatus(`target curve: ${points.length} points from ${file.name}`, "info");
      } catch (e) {
        lwStatus(`import: ${e.message}`, "error");
        targetInfo.textContent = e.message;
        setState(root, "error");
      } finally {
        csvInput.value = "";
      }
    });
    clearTarget.addEventListener("click", () => {
      target = null;
      ellipse = null;
      for (const n of ["synth-target", "synth-ellipse", "synth-candidate"]) lw.clearOverlay(n);
      targetInfo.textContent = "No target yet.";
      candidates.replaceChildren();
      ellipseInfo.hidden = true;
      family.hidden = true;
      matchBtn.disabled = true;
      fitBtn.disabled = true;
      delete root.dataset.target;
      setState(root, "idle");
    });

    function showAtlas(st) {
      if (!st) return;
      root.dataset.atlas = st.state;
      root.dataset.atlasSpace = atlasSpace;
      const kind = atlasSpace === "sphere" ? "spherical four-bar" : "four-bar";
      if (st.state === "building") {
        atlasInfo.textContent = `Building the ${kind} atlas… ${Math.round(100 * (st.progress || 0))} %`
          + " (first use only)";
      } else if (st.state === "ready") {
        atlasInfo.textContent = `Atlas: ${(st.count || 0).toLocaleString("en")} ${kind}s.`;
      } else if (st.state === "error") {
        atlasInfo.textContent = st.error || "the atlas could not be built";
      } else {
        atlasInfo.textContent = "The atlas is built on first use (seconds).";
      }
    }

    async function poll() {
      try {
        const st = await call("GET", `/api/match/status?space=${atlasSpace}`);
        showAtlas(st);
        if (st.state === "building") {
          polling = setTimeout(poll, 500);
          return;
        }
      } catch (e) { /* the status line stays as it was */ }
      polling = null;
    }

    // The atlas of the drawing's space is prepared when the tab shows, and again on a new scene.
    lw.on("scene", (sc) => { if (!root.hidden && sc && !prepared[sc.space]) shown(); });
    async function shown() {
      const sc = lw.scene();
      const space = sc && sc.space === "sphere" ? "sphere" : "plane";
      if (prepared[space]) return;
      prepared[space] = true;
      atlasSpace = space;
      try {
        showAtlas(await call("POST", `/api/match/prepare?space=${space}`));
        if (!polling) poll();
      } catch (e) {
        atlasInfo.textContent = e.message;
      }
    }

    openCurve.addEventListener("change", () => {
      if (!target) return;
      showTarget();
      candidates.replaceChildren();
    });

    matchBtn.addEventListener("click", async () => {
      if (!target) return;
      setState(root, "running");
      matchBtn.disabled = true;
      candidates.replaceChildren();
      lwStatus("matching…", "busy");
      atlasSpace = target[0].length === 3 ? "sphere" : "plane"; // the rows choose the atlas
      if (!polling) polling = setTimeout(poll, 300);
      try {
        const res = await call("POST", "/api/match", { points: target, top: Number(top.value),
          refine: refine.checked, open: openCurve.checked });
        showAtlas({ state: "ready", count: res.atlas.count });
        res.candidates.forEach((c) => candidates.append(candidateRow(c)));
        if (!res.candidates.length) candidates.append(h("li", { class: "muted", text: "No candidate found." }));
        const best = res.candidates[0];
        lwStatus(best ? `${res.candidates.length} candidates; best off by ${pct(best.relative)} of the curve's size`
          : "no candidate", "info");
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`match: ${e.message}`, "error");
      } finally {
        matchBtn.disabled = !target || target.length < 8;
      }
    });

    function candidateRow(c) {
      const canvas = h("canvas", { class: "preview", width: "84", height: "62", testid: "synth-preview" });
      const li = h("li", { class: "candidate", testid: "synth-candidate", tabindex: "0",
        dataset: { rank: String(c.rank), error: String(c.relative) },
        title: "load this four-bar" },
        canvas,
        h("div", { class: "cand-text" },
          h("b", { text: `#${c.rank}` }),
          h("span", { testid: "synth-candidate-error", text: ` off by ${pct(c.relative)}` }),
          h("div", { class: "muted small", text: (c.refined ? "refined · " : "") + `atlas entry ${c.atlas_id}` })));
      const choose = async () => {
        for (const el of candidates.children) el.classList.toggle("chosen", el === li);
        lw.clearOverlay("synth-candidate");
        try {
          const shown = await lw.setDocument(c.document, { title: c.document.title });
          if (shown) {
            lwStatus(`loaded candidate #${c.rank}: off by ${pct(c.relative)} of the curve's size`, "info");
            root.dataset.chosen = String(c.rank);
          }
        } catch (e) {
          lwStatus(`candidate: ${e.message}`, "error");
        }
      };
      li.addEventListener("click", choose);
      li.addEventListener("keydown", (e) => { if (e.key === "Enter" || e.key === " ") { e.preventDefault(); choose(); } });
      li.addEventListener("mouseenter", () => lw.overlay("synth-candidate", runs(c.curve),
        { color: "#2f6bd8", width: 1.5, label: `candidate #${c.rank}` }));
      li.addEventListener("mouseleave", () => lw.clearOverlay("synth-candidate"));
      // Directions on the sphere are previewed as the drawing shows them (screen y is down).
      const up = (q) => [q[0], -q[1]];
      const flat = (rows) => rows.map((p) => (p && p.length === 3 ? up(lw.toScreen(p)) : p));
      requestAnimationFrame(() => preview(canvas, [
        { points: flat(target ? target.concat([target[0]]) : []), color: "#9aa5b1", width: 1, dash: [3, 2] },
        { points: flat(c.curve), color: "#2f6bd8", width: 1.6 }]));
      return li;
    }

    fitBtn.addEventListener("click", async () => {
      if (!target) return;
      setState(root, "running");
      lwStatus("fitting an ellipse…", "busy");
      try {
        const res = await call("POST", "/api/ellipse", { points: target, count: 12, circle: circle.value });
        ellipse = res;
        lw.overlay("synth-ellipse", [res.curve], { color: "#b45309", width: 2, label: "fitted ellipse" });
        ellipseInfo.replaceChildren(
          h("dt", { text: "centre" }), h("dd", { text: `(${fmt(res.center[0])}, ${fmt(res.center[1])})` }),
          h("dt", { text: "semi-axes" }), h("dd", { text: `${fmt(res.axes[0])}, ${fmt(res.axes[1])}` }),
          h("dt", { text: "major axis" }), h("dd", { text: `${fmt(res.angle)}°` }),
          h("dt", { text: "fit residual" }),
          h("dd", { testid: "synth-residual", text: `${fmt(res.residual)} RMS (${pct(res.residual_relative)} of a)` }));
        ellipseInfo.hidden = false;
        members.replaceChildren(...res.family.map((m, i) => h("button", { type: "button", class: "chip",
          testid: "synth-family-member", dataset: { s1: String(m.s1), s2: String(m.s2) },
          text: i === 0 ? "trammel 90°, 0°" : `${fmt(m.s1, 3)}°, ${fmt(m.s2, 3)}°`,
          onclick: () => { s1.value = String(m.s1); s2.value = String(m.s2); loadTrammel(m); } })));
        family.hidden = false;
        const first = res.family[0];
        if (first) {
          s1.value = String(first.s1);
          s2.value = String(first.s2);
          await loadTrammel(first);
        }
        lwStatus(`ellipse fitted: residual ${pct(res.residual_relative)} of a; ${res.family.length} double sliders`, "info");
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`ellipse: ${e.message}`, "error");
      }
    });
    circle.addEventListener("change", () => { if (ellipse) fitBtn.click(); });

    function showAngles() {
      s1v.textContent = `${fmt(Number(s1.value), 4)}°`;
      s2v.textContent = `${fmt(Number(s2.value), 4)}°`;
    }

    async function loadTrammel(member) {
      // The member's own angles (a chip's may fall between the sliders' half degrees).
      s1v.textContent = `${fmt(member.s1, 4)}°`;
      s2v.textContent = `${fmt(member.s2, 4)}°`;
      trammelInfo.textContent = `s1 = ${fmt(member.s1)}°, s2 = ${fmt(member.s2)}°: `
        + `traces the ellipse to ${member.deviation === null ? "—" : fmt(member.deviation, 2)} of a`;
      root.dataset.s1 = String(member.s1);
      root.dataset.s2 = String(member.s2);
      // The ellipse stays where it is, so the view does too while the family is browsed.
      await lw.setDocument(member.document, { title: member.document.title, fit: false });
    }

    async function browse() {
      showAngles();
      if (!ellipse) return;
      const seq = ++trammelSeq;
      const a = Number(s1.value), b = Number(s2.value);
      if (Math.abs(((a - b) % 180 + 180) % 180) < 1e-9) {
        trammelInfo.textContent = "s1 and s2 must differ: equal angles put both sliders on one line.";
        return;
      }
      try {
        const m = await call("POST", "/api/ellipse/trammel", { ellipse: { center: ellipse.center,
          axes: ellipse.axes, angle: ellipse.angle }, a, b, circle: ellipse.circle });
        if (seq !== trammelSeq) return; // a later slider position has been asked for
        await loadTrammel(m);
      } catch (e) {
        if (seq === trammelSeq) lwStatus(`double slider: ${e.message}`, "error");
      }
    }
    for (const s of [s1, s2]) {
      s.addEventListener("input", () => {
        showAngles();
        clearTimeout(trammelTimer);
        trammelTimer = setTimeout(browse, 40);
      });
      s.addEventListener("change", () => { clearTimeout(trammelTimer); browse(); });
    }

    return { shown, setTarget };
  }

  // ---- Export ---------------------------------------------------------------------------------

  function exportPanel(lw, root) {
    if (!root) return;
    root.replaceChildren();
    setState(root, "idle");
    const buttons = FORMATS.map(([fmtName, label, what]) => {
      const b = h("button", { id: `export-${fmtName}`, testid: `export-${fmtName}`, type: "button",
        class: "export-btn", title: what },
      h("b", { text: label }), h("span", { class: "muted small", text: what }));
      b.addEventListener("click", () => doExport(fmtName, label, b));
      return b;
    });
    const last = h("p", { id: "export-last", testid: "export-last", class: "muted small" });
    root.append(
      h("p", { class: "muted small", text: "Files of the current mechanism, drawn at the current input angle." }),
      h("div", { class: "export-grid" }, buttons),
      last);

    async function doExport(fmtName, label, button) {
      setState(root, "running");
      button.disabled = true;
      lwStatus(`exporting ${label}…`, "busy");
      try {
        const doc = lw.document();
        const at = typeof lw.at === "function" ? lw.at() : null;
        const res = await call("POST", `/api/export/${fmtName}`,
          { document: doc, at: Number.isFinite(at) ? at : null, samples: 360 }, { raw: true });
        const blob = await res.blob();
        const name = filenameOf(res, `${docTitle(doc)}.${fmtName}`);
        saveBlob(blob, name);
        last.textContent = `${name}: ${blob.size.toLocaleString("en")} bytes`;
        lwStatus(`exported ${name}`, "info");
        setState(root, "done");
      } catch (e) {
        setState(root, "error");
        lwStatus(`export ${label}: ${e.message}`, "error");
      } finally {
        button.disabled = false;
      }
    }
  }

  // ------------------------------------------------------------------------------------------
  // Start once the page's API exists (app.js is loaded first, but may define lw late).
  // ------------------------------------------------------------------------------------------

  let tries = 0;
  function boot() {
    const lw = window.lw;
    if (lw && typeof lw.on === "function") {
      start(lw);
      return;
    }
    if (++tries > 400) { // 20 s
      console.error("tools.js: window.lw never appeared; the tool panels stay empty");
      return;
    }
    setTimeout(boot, 50);
  }
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", boot);
  else boot();
})();

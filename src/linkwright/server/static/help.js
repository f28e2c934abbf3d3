/* linkwright workbench: the help overlay ("?" or the ? button) and its short guided tour.
 *
 * The overlay lists the gestures and keys; the tour walks through the page's parts one at a
 * time, outlining each and saying what it is for. Nothing here changes the mechanism. */

import { $ } from "./util.js";

const KEYS = [
  ["drag a joint", "move it: the linkage follows, on the same branch"],
  ["drag empty space", "pan the plane, or turn the sphere"],
  ["wheel, or pinch", "zoom"],
  ["Space, ← →", "play or pause, step the input"],
  ["F, or double-click", "fit the drawing to the view"],
  ["Ctrl+Z, Ctrl+Shift+Z", "undo, redo every edit"],
  ["Draw", "build a linkage of your own: tools V G J L P S D X, Enter closes a plate, Esc ends a chain"],
  ["?", "this help; Esc closes it"],
];

const TOUR = [
  ["#drawing-wrap", "The drawing: the linkage at the input shown, its traced curves, and every assembly mode. Drag a joint to change the linkage."],
  ["#params", "The parameters: type a value and press Enter. A value the linkage cannot take is refused, and the drawing stays as the fields say."],
  ["#anim", "The input: play, step, or drag the slider. The circuit and assembly mode pick the branch."],
  ["#plots", "The diagrams: angles, transmission angle and the paper 003 coefficients along the input."],
  ["#side", "The tools: the library (save, open), studies, synthesis from a drawn curve, and exports."],
  ["#build", "Draw: build a linkage of your own, joint by joint, in the plane or on the sphere. It runs as soon as it has one degree of freedom and a driver."],
  ["#copy-link", "Copy link: the whole state (mechanism, view, input angle, drawing) in one address."],
];

let tourStep = -1;

function helpBox() {
  let box = $("help");
  if (box) return box;
  box = document.createElement("div");
  box.id = "help";
  box.className = "help-overlay";
  box.dataset.testid = "help";
  box.setAttribute("role", "dialog");
  box.setAttribute("aria-label", "help");
  box.hidden = true;
  document.body.appendChild(box);
  return box;
}

function clearHighlight() {
  for (const el of document.querySelectorAll(".tour-target")) el.classList.remove("tour-target");
}

function helpButton(text, testid, fn) {
  const b = document.createElement("button");
  b.type = "button";
  b.textContent = text;
  b.dataset.testid = testid;
  b.addEventListener("click", fn);
  return b;
}

function renderKeys(box) {
  box.replaceChildren();
  const h = document.createElement("h2");
  h.textContent = "linkwright workbench";
  const table = document.createElement("dl");
  for (const [k, v] of KEYS) {
    const dt = document.createElement("dt");
    dt.textContent = k;
    const dd = document.createElement("dd");
    dd.textContent = v;
    table.append(dt, dd);
  }
  const row = document.createElement("div");
  row.className = "help-buttons";
  row.append(helpButton("Take the tour", "help-tour", () => showTourStep(0)), helpButton("Close", "help-close", closeHelp));
  box.append(h, table, row);
}

function showTourStep(i) {
  const box = helpBox();
  clearHighlight();
  tourStep = i;
  const [selector, text] = TOUR[i];
  const target = document.querySelector(selector);
  if (target) target.classList.add("tour-target");
  box.replaceChildren();
  box.classList.add("touring");
  const p = document.createElement("p");
  p.textContent = text;
  p.dataset.testid = "help-step";
  const count = document.createElement("span");
  count.className = "help-count";
  count.textContent = `${i + 1} / ${TOUR.length}`;
  const row = document.createElement("div");
  row.className = "help-buttons";
  if (i > 0) row.append(helpButton("Back", "help-back", () => showTourStep(i - 1)));
  if (i + 1 < TOUR.length) row.append(helpButton("Next", "help-next", () => showTourStep(i + 1)));
  row.append(helpButton(i + 1 < TOUR.length ? "End tour" : "Done", "help-close", closeHelp));
  box.append(count, p, row);
  box.hidden = false;
}

export function openHelp() {
  const box = helpBox();
  tourStep = -1;
  clearHighlight();
  box.classList.remove("touring");
  renderKeys(box);
  box.hidden = false;
}

export function closeHelp() {
  const box = helpBox();
  box.hidden = true;
  tourStep = -1;
  clearHighlight();
}

export const helpIsOpen = () => !helpBox().hidden;

export function initHelp() {
  const b = document.createElement("button");
  b.id = "help-button";
  b.type = "button";
  b.title = "help and a short tour (?)";
  b.textContent = "?";
  b.dataset.testid = "help-button";
  b.addEventListener("mousedown", (e) => e.preventDefault());
  b.addEventListener("click", () => (helpIsOpen() ? closeHelp() : openHelp()));
  document.querySelector("#drawing-wrap .canvas-tools").appendChild(b);
  document.addEventListener("keydown", (e) => {
    const t = e.target;
    const tag = t && t.tagName;
    if (tag === "INPUT" || tag === "SELECT" || tag === "TEXTAREA" || (t && t.isContentEditable)) return;
    if (e.key === "?") {
      e.preventDefault();
      if (helpIsOpen()) closeHelp();
      else openHelp();
    } else if (e.key === "Escape" && helpIsOpen()) {
      e.stopPropagation();
      closeHelp();
    } else if (tourStep >= 0 && e.key === "ArrowRight" && tourStep + 1 < TOUR.length) {
      e.stopPropagation();
      showTourStep(tourStep + 1);
    }
  }, true);
}

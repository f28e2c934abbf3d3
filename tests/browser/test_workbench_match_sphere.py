"""Sphere matching in the workbench (issue 24, point 7), used like a person would: open a
spherical linkage, draw a target curve on the sphere with the mouse (or import an x, y, z CSV),
press Match, see the candidates, pick one, and find a spherical four-bar on the page whose
curve runs along the drawing.

Assertions read what the page shows (the panel's rows and texts, the status line, the legend),
the request the page sent, and, for numbers, the page's own scene through ``window.lw``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .page_helpers import (
    draw_with_mouse,
    scene_count,
    show_tab,
    status,
    wait_scene_after,
    wait_state,
)

EXAMPLE = "paper000-fig6-crank-rocker"


def open_workbench(page, server_url: str) -> None:
    """The workbench on the spherical example."""
    page.goto(server_url)
    page.wait_for_function("window.lw && Number(document.body.dataset.sceneCount) >= 1")
    before = scene_count(page)
    page.select_option("#example-select", EXAMPLE)
    wait_scene_after(page, before)
    assert page.evaluate("lw.scene().space") == "sphere"


# The gap, as a fraction of the curve's size, between the drawn target and the loaded
# candidate's curve: the pointer lands on whole pixels (about 1/300 of the sphere's radius).
GAP = 0.05

# Largest great-circle distance from any of the target's directions to the page's curve of P,
# over the target's RMS chord from its mean direction.
_GAP_JS = """(target) => {
  const sc = lw.scene();
  const P = sc.modes.find((m) => m.own).circuits[0].positions.P.filter(Boolean);
  const unit = (p) => { const n = Math.hypot(p[0], p[1], p[2]); return p.map((c) => c / n); };
  const arc = (a, b) =>
    2 * Math.asin(Math.min(1, Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]) / 2));
  const T = target.map(unit);
  let worst = 0;
  for (const q of T) worst = Math.max(worst, Math.min(...P.map((p) => arc(unit(p), q))));
  const m = unit([0, 1, 2].map((k) => T.reduce((s, q) => s + q[k], 0)));
  const size = Math.sqrt(T.reduce((s, q) => s + (q[0] - m[0]) ** 2 + (q[1] - m[1]) ** 2
    + (q[2] - m[2]) ** 2, 0) / T.length);
  return worst / size;
}"""


# The page's curve of P, its mean direction in the view's frame (x right, y up, z towards the
# eye) and the least depth of any of its points: where it is negative, part is out of sight.
_SEEN_JS = """() => {
  const P = lw.scene().modes.find((m) => m.own).circuits[0].positions.P.filter(Boolean);
  const v = lw.view(), R = v.rotation;  // row-major
  const view = (p) => {
    const n = Math.hypot(p[0], p[1], p[2]);
    return [0, 3, 6].map((i) => (R[i] * p[0] + R[i + 1] * p[1] + R[i + 2] * p[2]) / n);
  };
  const mean = view([0, 1, 2].map((k) => P.reduce((s, p) => s + p[k], 0)));
  return { P, mean, front: Math.min(...P.map((p) => view(p)[2])), disc: v.disc };
}"""


def turn_to_face_the_curve(page) -> None:
    """Turn the sphere by one mouse drag (begun off the sphere, where no joint is) so that the
    curve's mean direction faces the viewer: the page turns the view by rotY(dx/r)·rotX(dy/r)
    for a drag of (dx, dy) pixels, so dy = r·atan2(y, z) brings the direction into the plane
    x–z and dx = r·atan2(−x, √(y² + z²)) then to the eye."""
    seen = page.evaluate(_SEEN_JS)
    x, y, z = seen["mean"]
    disc = seen["disc"]
    r = disc["r"]
    dy = r * math.atan2(y, z)
    dx = r * math.atan2(-x, math.hypot(y, z))
    box = page.locator("#drawing").bounding_box()
    # Off the disc by 20 pixels, on the side the drag leaves from.
    sx = disc["cx"] - math.copysign(r + 20, dx)
    page.mouse.move(box["x"] + sx, box["y"] + disc["cy"])
    page.mouse.down()
    page.mouse.move(box["x"] + sx + dx, box["y"] + disc["cy"] + dy, steps=1)
    page.mouse.up()
    mean = page.evaluate(_SEEN_JS)["mean"]
    assert mean[2] > 0.999, mean


def _pick_best_and_check(page, target: list[list[float]]) -> None:
    """Pick the first candidate: the page shows a spherical four-bar (a linkage on the sphere
    of two ground axes, a crank, a dyad and a coupler point) whose curve runs along ``target``."""
    cands = page.locator("[data-testid=synth-candidate]")
    before = scene_count(page)
    cands.first.click()
    wait_scene_after(page, before)
    assert "loaded candidate #1" in status(page)
    doc = page.evaluate("lw.document()")
    assert doc["title"].startswith("Atlas match 1")
    mech = doc["mechanism"]
    assert mech["family"] == "linkage" and mech["space"] == "sphere"
    kinds = {j["name"]: j["type"] for j in mech["joints"]}
    assert kinds == {"A0": "fixed", "B0": "fixed", "A": "crank", "B": "rrr", "P": "rigid"}
    assert page.evaluate("lw.scene().space") == "sphere"
    gap = page.evaluate(_GAP_JS, target)
    assert gap < GAP, gap


def test_draw_on_the_sphere_match_and_pick(page, server_url: str) -> None:
    """Trace paper 000's Fig. 6 coupler curve on the sphere with the mouse: the page sends
    directions (unit vectors), the spherical atlas answers, a candidate's curve is overlaid on
    hover, and the picked one is a spherical four-bar along the drawing."""
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    page.wait_for_selector("#tab-synthesis[data-atlas-space=sphere]", state="attached")
    turn_to_face_the_curve(page)
    seen = page.evaluate(_SEEN_JS)
    target = [p for i, p in enumerate(seen["P"]) if i % 6 == 0]
    assert seen["front"] > 0.05, "the whole curve faces the viewer, so it can be drawn"
    curve_px = page.evaluate("(pts) => pts.map((p) => lw.toScreen(p))", target)
    assert len(curve_px) >= 40
    page.click("#synth-draw")
    draw_with_mouse(page, curve_px)
    page.wait_for_selector("#tab-synthesis[data-target]")
    assert "points (drawn)" in page.inner_text("#synth-target-info")
    assert "target curve" in page.inner_text("#legend")
    assert page.is_disabled("#synth-ellipse")  # an ellipse is fitted in the plane only

    with page.expect_request("**/api/match") as sent:
        page.click("#synth-match")
    rows = np.array(sent.value.post_data_json["points"], dtype=float)
    assert rows.shape[1] == 3 and len(rows) >= 40
    assert np.allclose(np.linalg.norm(rows, axis=1), 1.0, atol=1e-9)
    wait_state(page, "synthesis", timeout=120_000)
    cands = page.locator("[data-testid=synth-candidate]")
    assert cands.count() >= 1
    assert "spherical four-bars" in page.inner_text("#synth-atlas")
    best = float(cands.first.get_attribute("data-error"))
    assert best < GAP, best
    assert "off by" in cands.first.inner_text()
    cands.first.hover()
    page.wait_for_function("document.querySelector('#legend').innerText.includes('candidate #1')")
    _pick_best_and_check(page, target)


def test_csv_of_directions_matches_on_the_sphere(page, server_url: str, tmp_path: Path) -> None:
    """An x, y, z CSV (a header, directions of any length) is a target on the sphere: matched
    against the spherical atlas, the picked candidate runs along it."""
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    P = page.evaluate("lw.scene().modes.find((m) => m.own).circuits[0].positions.P.filter(Boolean)")
    target = [p for i, p in enumerate(P) if i % 5 == 0]
    lengths = np.linspace(0.5, 3.0, len(target))  # only the direction of a row counts
    path = tmp_path / "directions.csv"
    rows = [",".join(repr(float(k * c)) for c in p) for k, p in zip(lengths, target, strict=True)]
    path.write_text("x,y,z\n" + "\n".join(rows) + "\n")
    page.set_input_files("#synth-csv", str(path))
    page.wait_for_selector(f"#tab-synthesis[data-target='{len(target)}']")
    assert f"{len(target)} points (directions.csv)" in page.inner_text("#synth-target-info")
    assert page.is_disabled("#synth-ellipse")
    page.click("#synth-match")
    wait_state(page, "synthesis", timeout=120_000)
    best = float(page.locator("[data-testid=synth-candidate]").first.get_attribute("data-error"))
    assert best < 0.01, best
    _pick_best_and_check(page, target)


def test_an_open_piece_matches_on_the_sphere(page, server_url: str, tmp_path: Path) -> None:
    """Half of the example's coupler curve, as directions, matched as an open curve: the
    target is drawn open, every entry is screened for a matching arc, and the picked
    candidate runs along the piece."""
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    P = page.evaluate("lw.scene().modes.find((m) => m.own).circuits[0].positions.P.filter(Boolean)")
    target = [p for i, p in enumerate(P[: len(P) // 2]) if i % 3 == 0]
    path = tmp_path / "piece.csv"
    path.write_text("x,y,z\n" + "\n".join(",".join(repr(float(c)) for c in p) for p in target))
    page.set_input_files("#synth-csv", str(path))
    page.wait_for_selector(f"#tab-synthesis[data-target='{len(target)}']")
    assert "taken as closed" in page.inner_text("#synth-target-info")
    page.check("#synth-open")
    assert "taken as open" in page.inner_text("#synth-target-info")
    page.click("#synth-match")
    wait_state(page, "synthesis", timeout=120_000)
    best = float(page.locator("[data-testid=synth-candidate]").first.get_attribute("data-error"))
    assert best < 0.01, best
    _pick_best_and_check(page, target)


def test_csv_rows_must_all_be_alike(page, server_url: str, tmp_path: Path) -> None:
    open_workbench(page, server_url)
    show_tab(page, "synthesis")
    path = tmp_path / "mixed.csv"
    c, s = math.cos(0.3), math.sin(0.3)
    path.write_text(f"x,y,z\n1,0,0\n{c},{s},0\n{c},0\n")
    page.set_input_files("#synth-csv", str(path))
    page.wait_for_selector("#status[data-kind=error]")
    assert "CSV line 4: 2 values; each line must be x, y, z (as the first line)" in status(page)
    assert page.is_disabled("#synth-match")

"""Issue 24's builder, used as a person uses it: a linkage drawn from an empty canvas by clicking.

Each test drives Debian's chromium (fixtures in ``conftest.py``). The drawn linkage is checked
against the drawing itself and against its own constraints, not against the page's code: the
pose the server computes at input 0 is the drawn one, and every link keeps its length (its arc,
on the sphere) over every sample of the motion the server sends. Undo, redo, reload and a shared
link are checked by comparing the sketch and document the page holds before and after.
"""

from __future__ import annotations

import itertools
import math
import tomllib
import uuid
from pathlib import Path
from typing import Any

import pytest
from playwright.sync_api import expect

SCENES = "Number(document.body.dataset.sceneCount || 0)"


def _settle(page: Any) -> None:
    page.wait_for_function("document.body.dataset.busy === '0'")


def _open(page: Any, url: str) -> None:
    page.goto(url)
    page.wait_for_function(f"{SCENES} >= 1")
    _settle(page)


def _click_model(page: Any, point: list[float]) -> None:
    box = page.locator("#drawing").bounding_box()
    sx, sy = page.evaluate(f"lw.toScreen({list(point)})")
    page.mouse.click(box["x"] + sx, box["y"] + sy)
    _settle(page)


def _click_screen(page: Any, sx: float, sy: float) -> None:
    box = page.locator("#drawing").bounding_box()
    page.mouse.click(box["x"] + sx, box["y"] + sy)
    _settle(page)


def _tool(page: Any, name: str) -> None:
    page.click(f"[data-testid='tool-{name}']")


def _report(page: Any) -> dict[str, Any]:
    return page.evaluate("lw.sketchReport()") or {}


def _at(sketch: dict[str, Any], name: str) -> list[float]:
    return next(j["at"] for j in sketch["joints"] if j["name"] == name)


def _distance(p: list[float], q: list[float], sphere: bool) -> float:
    if not sphere:
        return math.dist(p, q)
    u = [c / math.hypot(*p) for c in p]
    v = [c / math.hypot(*q) for c in q]
    dot = max(-1.0, min(1.0, sum(a * b for a, b in zip(u, v, strict=True))))
    return math.acos(dot)


def _check_runs_as_drawn(page: Any) -> None:
    """The drawing compiled and ran: its pose at input 0 is the drawn one and every link keeps
    its joints' mutual distances over the whole motion."""
    sketch = page.evaluate("lw.sketch()")
    scene = page.evaluate("lw.scene()")
    sphere = sketch.get("space") == "sphere"
    assert scene["family"] == "linkage"
    size = max(1.0, *(abs(c) for j in sketch["joints"] for c in j["at"]))
    pose = scene["pose"]
    for j in sketch["joints"]:
        p = [c / math.hypot(*j["at"]) for c in j["at"]] if sphere else j["at"]
        assert math.dist(pose[j["name"]], p) < 1e-7 * size, j["name"]
    own = next(m for m in scene["modes"] if m["own"])
    checked = 0
    for circuit in own["circuits"]:
        for link in sketch["links"]:
            for a, b in itertools.combinations(link, 2):
                drawn = _distance(_at(sketch, a), _at(sketch, b), sphere)
                for p, q in zip(circuit["positions"][a], circuit["positions"][b], strict=True):
                    if p[0] is None or q[0] is None:
                        continue
                    assert abs(_distance(p, q, sphere) - drawn) < 1e-7 * size, (a, b)
                    checked += 1
    assert checked > 100


def _undo_all(page: Any) -> int:
    steps = 0
    while int(page.evaluate("document.body.dataset.undo")) > 0:
        page.keyboard.press("Control+z")
        _settle(page)
        steps += 1
    return steps


def _redo_all(page: Any) -> None:
    while int(page.evaluate("document.body.dataset.redo")) > 0:
        page.keyboard.press("Control+Shift+z")
        _settle(page)


def _start_empty(page: Any, space: str = "plane") -> None:
    """Open the builder (it shows the page's linkage as a drawing), then an empty sheet."""
    page.click("[data-testid='build']")
    _settle(page)
    expect(page.locator("[data-testid='build-tools']")).to_be_visible()
    page.click(f"[data-testid='new-{space}']")
    _settle(page)
    assert page.evaluate("lw.sketch()")["joints"] == []


def _build_fourbar(page: Any, building: bool = False) -> None:
    if building:
        page.click("[data-testid='new-plane']")
        _settle(page)
    else:
        _start_empty(page)
    _tool(page, "ground")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [4.0, 0.0])
    _tool(page, "link")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [1.0, 1.5])  # a new pin, A, and the crank A0-A
    _click_model(page, [4.5, 3.0])  # B and the coupler A-B
    _click_model(page, [4.0, 0.0])  # the rocker B-B0
    page.keyboard.press("Escape")
    report = _report(page)
    assert report["status"] == "no-driver" and report["dof"] == 1, report
    _tool(page, "driver")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [1.0, 1.5])
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    _settle(page)


# ---------------------------------------------------------------------------------------------


def test_build_a_fourbar_undo_redo_reload_and_share(page: Any, server_url: str) -> None:
    _open(page, server_url)
    original = page.evaluate("lw.document()")
    _build_fourbar(page)
    expect(page.locator("[data-testid='build-report']")).to_have_attribute("data-dof", "1")
    _check_runs_as_drawn(page)
    sketch = page.evaluate("lw.sketch()")
    assert sorted(j["name"] for j in sketch["joints"]) == ["A", "A0", "B", "B0"]
    assert sorted(sorted(link) for link in sketch["links"]) == [
        ["A", "A0"],
        ["A", "B"],
        ["B", "B0"],
    ]
    doc = page.evaluate("lw.document()")

    # every building step undone, back to the example, then all of them redone
    steps = _undo_all(page)
    assert steps >= 8
    assert page.evaluate("lw.sketch()") is None
    assert page.evaluate("lw.document()") == original
    _redo_all(page)
    assert page.evaluate("lw.sketch()") == sketch
    assert page.evaluate("lw.document()") == doc

    # a reload finds the drawing and its linkage
    page.reload()
    page.wait_for_function(f"{SCENES} >= 1")
    page.wait_for_function("lw.sketchReport() !== null")
    _settle(page)
    assert page.evaluate("lw.sketch()") == sketch
    assert page.evaluate("lw.document()") == doc

    # a shared link opens the same drawing in a fresh page
    link = page.evaluate("lw.shareLink()")
    other = page.context.new_page()
    other.goto(link)
    other.wait_for_function(f"{SCENES} >= 1")
    other.wait_for_function("lw.sketchReport() !== null")
    other.wait_for_function("document.body.dataset.busy === '0'")
    assert other.evaluate("lw.sketch()") == sketch
    assert other.evaluate("lw.document()") == doc
    other.close()

    # Done runs it: the builder closes and the linkage moves
    page.click("[data-testid='build']")
    _settle(page)
    expect(page.locator("[data-testid='build-tools']")).to_be_hidden()
    assert page.evaluate("lw.sketch()") is None
    assert page.evaluate("lw.document()") == doc


def test_build_a_watt_sixbar_with_plates(page: Any, server_url: str) -> None:
    # The Watt I six-bar of examples/watt1-example.toml at crank angle 0: A (1, 0), B (4, 4),
    # C (1, 1) on the crank, E (1, 5) on the coupler, D (-2, 1).
    _open(page, server_url)
    _start_empty(page)
    _tool(page, "ground")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [4.0, 0.0])
    _tool(page, "plate")
    for p in ([0.0, 0.0], [1.0, 0.0], [1.0, 1.0]):
        _click_model(page, p)
    page.keyboard.press("Enter")
    _settle(page)
    for p in ([1.0, 0.0], [4.0, 4.0], [1.0, 5.0]):
        _click_model(page, p)
    page.keyboard.press("Enter")
    _settle(page)
    _tool(page, "link")
    for p in ([4.0, 4.0], [4.0, 0.0]):
        _click_model(page, p)
    page.keyboard.press("Escape")
    for p in ([1.0, 1.0], [-2.0, 1.0], [1.0, 5.0]):
        _click_model(page, p)
    page.keyboard.press("Escape")
    assert _report(page)["dof"] == 1
    _tool(page, "driver")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [1.0, 0.0])
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    _settle(page)
    sketch = page.evaluate("lw.sketch()")
    assert sorted(len(link) for link in sketch["links"]) == [2, 2, 2, 3, 3]
    _check_runs_as_drawn(page)
    # the crank turns fully (a Grashof crank-rocker drives the dyad over the whole turn)
    own = next(m for m in page.evaluate("lw.scene()")["modes"] if m["own"])
    assert any(c.get("full") for c in own["circuits"])


def test_build_a_spherical_fourbar(page: Any, server_url: str) -> None:
    _open(page, server_url)
    _start_empty(page, "sphere")
    assert page.evaluate("lw.sketch()")["space"] == "sphere"
    disc = page.evaluate("lw.view().disc")
    cx, cy, r = disc["cx"], disc["cy"], disc["r"]

    def at(u: float, v: float) -> tuple[float, float]:
        return cx + u * r, cy - v * r

    _tool(page, "ground")
    _click_screen(page, *at(-0.35, -0.15))
    _click_screen(page, *at(0.35, -0.15))
    _tool(page, "link")
    _click_screen(page, *at(-0.35, -0.15))
    _click_screen(page, *at(-0.3, 0.15))
    _click_screen(page, *at(0.2, 0.35))
    _click_screen(page, *at(0.35, -0.15))
    page.keyboard.press("Escape")
    _tool(page, "driver")
    _click_screen(page, *at(-0.35, -0.15))
    _click_screen(page, *at(-0.3, 0.15))
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    _settle(page)
    assert page.evaluate("lw.document()")["mechanism"]["space"] == "sphere"
    _check_runs_as_drawn(page)


def test_a_drawing_says_what_it_lacks(page: Any, server_url: str) -> None:
    _open(page, server_url)
    _start_empty(page)
    _tool(page, "ground")
    _click_model(page, [0.0, 0.0])
    _click_model(page, [5.0, 0.0])
    _tool(page, "link")
    for p in ([0.0, 0.0], [1.0, 2.0], [3.0, 3.0], [5.0, 2.0], [5.0, 0.0]):
        _click_model(page, p)
    page.keyboard.press("Escape")
    report = _report(page)
    assert report["status"] == "under" and report["dof"] == 2
    box = page.locator("[data-testid='build-report']")
    expect(box).to_have_attribute("data-status", "under")
    assert "\n" not in report["message"] and "Traceback" not in report["message"]
    # a link across it takes one freedom away
    _click_model(page, [1.0, 2.0])
    _click_model(page, [5.0, 2.0])
    page.keyboard.press("Escape")
    assert _report(page)["dof"] == 1


@pytest.mark.parametrize("key", ["Delete"])
def test_delete_a_joint_and_undo_it(page: Any, server_url: str, key: str) -> None:
    _open(page, server_url)
    _build_fourbar(page)
    sketch = page.evaluate("lw.sketch()")
    _tool(page, "move")
    _click_model(page, [4.5, 3.0])
    page.keyboard.press(key)
    _settle(page)
    after = page.evaluate("lw.sketch()")
    assert "B" not in {j["name"] for j in after["joints"]}
    assert all("B" not in link for link in after["links"])
    page.keyboard.press("Control+z")
    _settle(page)
    assert page.evaluate("lw.sketch()") == sketch


def test_help_overlay_and_tour(page: Any, server_url: str) -> None:
    _open(page, server_url)
    help_box = page.locator("[data-testid='help']")
    page.locator("#drawing").focus()
    page.keyboard.press("?")
    expect(help_box).to_be_visible()
    expect(help_box).to_contain_text("Ctrl+Z")
    page.click("[data-testid='help-tour']")
    seen = []
    while True:
        seen.append(page.locator("[data-testid='help-step']").inner_text())
        # the part the step speaks of is outlined, and only that one
        assert page.locator(".tour-target").count() == 1
        if page.locator("[data-testid='help-next']").count() == 0:
            break
        page.click("[data-testid='help-next']")
    assert len(seen) >= 5 and len(set(seen)) == len(seen)
    page.keyboard.press("Escape")
    expect(help_box).to_be_hidden()
    assert page.locator(".tour-target").count() == 0


def test_pinch_zooms_about_the_fingers(page: Any, server_url: str) -> None:
    _open(page, server_url)
    before = page.evaluate("lw.view().scale")
    box = page.locator("#drawing").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.evaluate(
        """([cx, cy]) => {
          const cv = document.getElementById('drawing');
          const fire = (type, id, x) => cv.dispatchEvent(new PointerEvent(type, {
            pointerId: id, pointerType: 'touch', clientX: x, clientY: cy, bubbles: true,
            isPrimary: id === 1, button: 0 }));
          fire('pointerdown', 1, cx - 40);
          fire('pointerdown', 2, cx + 40);
          for (let k = 1; k <= 5; k++) {
            fire('pointermove', 1, cx - 40 - 8 * k);
            fire('pointermove', 2, cx + 40 + 8 * k);
          }
          fire('pointerup', 1, cx - 80);
          fire('pointerup', 2, cx + 80);
        }""",
        [cx, cy],
    )
    after = page.evaluate("lw.view().scale")
    # the fingers moved from 80 px apart to 160: the drawing is twice as large
    assert after == pytest.approx(2 * before, rel=0.05)


def test_the_page_linkage_opens_as_a_drawing(page: Any, server_url: str) -> None:
    # The crank-rocker example, drawn: its pivots, pins and links, driven at its crank; it
    # compiles back to a linkage that moves as the example does (the same pose at input 0).
    _open(page, server_url)
    pose = page.evaluate("lw.pose()")
    page.click("[data-testid='build']")
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    _settle(page)
    sketch = page.evaluate("lw.sketch()")
    assert {j["name"] for j in sketch["joints"] if j.get("ground")} == {"A0", "B0"}
    assert sketch["drivers"][0]["pivot"] == "A0"
    _check_runs_as_drawn(page)
    page_pose = page.evaluate("lw.scene()")["pose"]
    for name in ("A", "B"):
        assert math.dist(page_pose[name], pose[name]) < 1e-9 * 10


def test_fields_follow_the_drawn_names(page: Any, server_url: str) -> None:
    # The crank-rocker's drawing has a rigid coupler point P; a new drawing's point in the same
    # slot of its document is C: the fields must say C (they once kept P's labels).
    _open(page, server_url)
    page.click("[data-testid='build']")
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    _settle(page)
    expect(page.locator("#fields")).to_contain_text("P u")
    _build_fourbar(page, building=True)
    _tool(page, "plate")
    for p in ([1.0, 1.5], [4.5, 3.0], [3.2, 4.4]):
        _click_model(page, p)
    page.keyboard.press("Enter")
    page.wait_for_function(
        "lw.document().mechanism.joints.some(j => j.name === 'C' && j.type === 'rigid')"
    )
    _settle(page)
    expect(page.locator("#fields")).to_contain_text("C u")
    expect(page.locator("#fields")).not_to_contain_text("P u")


def test_a_drawn_linkage_saves_exports_and_reopens_as_a_drawing(
    page: Any, server_url: str, tmp_path: Any
) -> None:
    _open(page, server_url)
    _build_fourbar(page)
    doc = page.evaluate("lw.document()")
    sketch = page.evaluate("lw.sketch()")
    page.click("#side .tabs button[data-tab=library]")
    name = f"drawn {uuid.uuid4().hex[:6]}"
    page.fill("#lib-name", name)
    page.click("#lib-save")
    page.wait_for_selector(f"text=saved “{name}” in the library")
    row = page.locator(f"#lib-list [data-testid=lib-entry][data-name='{name}']")
    expect(row).to_have_count(1)
    with page.expect_download() as download:
        row.locator("[data-testid=lib-export-toml]").click()
    saved = tomllib.loads(Path(download.value.path()).read_text(encoding="utf-8"))
    assert saved["mechanism"]["family"] == "linkage"
    assert [j["name"] for j in saved["mechanism"]["joints"]] == [
        j["name"] for j in doc["mechanism"]["joints"]
    ]

    # leave the builder, open another example, then the saved one, and draw it again
    page.click("[data-testid='build']")
    _settle(page)
    page.select_option("#example-select", "slider-crank")
    _settle(page)
    row.locator("[data-testid=lib-load]").click()
    page.wait_for_function("lw.document().mechanism.family === 'linkage'")
    _settle(page)
    page.click("[data-testid='build']")
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    again = page.evaluate("lw.sketch()")
    assert {j["name"] for j in again["joints"]} == {j["name"] for j in sketch["joints"]}
    for j in sketch["joints"]:
        assert math.dist(_at(again, j["name"]), j["at"]) < 1e-9
    assert sorted(sorted(x) for x in again["links"]) == sorted(sorted(x) for x in sketch["links"])

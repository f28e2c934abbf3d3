"""The workbench page's core, used the way a person uses it: choose, edit, drag, run, turn.

Every test drives Debian's chromium through Playwright (fixtures in ``conftest.py``) and asserts
on what the page shows: the fields, the status line, the animation's input angle, the plots'
cursors, and the drawing through ``window.lw`` (the pose it draws, where a model point sits on
the canvas). Numbers are checked against the linkage's own constraints (link lengths, the
mirror image of the other assembly), not against earlier output of the page.
"""

from __future__ import annotations

import math
from typing import Any

import pytest
from playwright.sync_api import expect

SCENE_COUNT = "Number(document.body.dataset.sceneCount || 0)"


def _scenes(page: Any) -> int:
    return int(page.evaluate(SCENE_COUNT))


def _settle(page: Any, after: int | None = None) -> None:
    """Wait until a scene newer than ``after`` is drawn and no request is in flight."""
    if after is not None:
        page.wait_for_function(f"{SCENE_COUNT} > {after}")
    page.wait_for_function("document.body.dataset.busy === '0'")


def _open(page: Any, server_url: str, example: str | None = None) -> None:
    page.goto(server_url)
    page.wait_for_function(f"{SCENE_COUNT} >= 1")
    _settle(page)
    if example is not None:
        _choose_example(page, example)


def _choose_example(page: Any, name: str) -> None:
    before = _scenes(page)
    page.select_option("#example-select", name)
    _settle(page, before)
    assert page.evaluate("lw.scene().document.title") is not None


def _canvas_box(page: Any) -> dict[str, float]:
    box = page.locator("#drawing").bounding_box()
    assert box is not None
    return box


def _to_page(page: Any, point: list[float]) -> tuple[float, float]:
    """Page coordinates of a model point on the drawing (through lw.toScreen)."""
    box = _canvas_box(page)
    sx, sy = page.evaluate("p => lw.toScreen(p)", point)
    return box["x"] + sx, box["y"] + sy


def _dist(a: list[float], b: list[float]) -> float:
    return math.dist(a, b)


def _at(page: Any) -> float:
    return float(page.evaluate("lw.at()"))


def _shown_at(page: Any) -> float:
    """The input angle the page shows, read from its text ("θ = −106.1° ↑")."""
    text = page.inner_text("#at-value")
    number = text.split("=")[1].split("°")[0].strip().replace("−", "-")
    return float(number)


# ---------------------------------------------------------------------------------------------


def test_choose_family_and_example(page: Any, server_url: str) -> None:
    _open(page, server_url)
    families = page.eval_on_selector_all("#family-select option", "os => os.map(o => o.value)")
    assert {"fourbar", "spherical-fourbar", "watt1"} <= set(families)
    groups = page.eval_on_selector_all("#example-select optgroup", "gs => gs.map(g => g.label)")
    assert "From the papers" in groups
    papers = page.eval_on_selector_all(
        "#example-select optgroup[label='From the papers'] option", "os => os.map(o => o.value)"
    )
    assert "paper000-fig6-crank-rocker" in papers and "paper000-fig8-sixbar" in papers

    # a family opens with its example; the parameter panel lists that family's fields
    before = _scenes(page)
    page.select_option("#family-select", "slidercrank")
    _settle(page, before)
    assert page.evaluate("lw.scene().family") == "slidercrank"
    assert page.locator("[data-path='mechanism.rod']").is_visible()
    assert page.inner_text("#family-name") == page.evaluate("lw.scene().family_name")

    # a paper's spherical mechanism: the sphere view and the map beside it
    _choose_example(page, "paper000-fig6-crank-rocker")
    assert page.evaluate("lw.scene().space") == "sphere"
    assert page.get_attribute("#drawing", "data-view") == "sphere"
    assert page.locator("#map").is_visible()
    assert page.input_value("#family-select") == "spherical-fourbar"
    assert "paper 000" in page.input_value("#doc-title")
    # every field of the scene is a labelled input holding its value
    for f in page.evaluate("lw.scene().fields"):
        el = page.locator(f"[data-path='{f['path']}']")
        assert el.is_visible()
        if f["kind"] not in ("sign", "choice"):
            assert float(el.input_value()) == pytest.approx(f["value"], rel=1e-9, abs=1e-12)

    # back to a planar linkage: the map goes away
    _choose_example(page, "watt1-example")
    assert page.get_attribute("#drawing", "data-view") == "plane"
    assert not page.locator("#map").is_visible()


def test_rocker_input_marks_and_explains_limit_positions(page: Any, server_url: str) -> None:
    _open(page, server_url, "rocker-input")
    items = page.locator("#limits-list li")
    # each circuit of the rocking input turns back twice: two circuits, four limit positions
    expect(items).to_have_count(4)
    texts = items.all_inner_texts()
    assert all("Limit position" in t for t in texts)
    # where coupler and output fold in line, |A − B0| = 5 ∓ 1: 3.5² + 4² − 2·3.5·4·cos θ = 4², 6²
    folds = [math.degrees(math.acos((28.25 - d * d) / 28.0)) for d in (4.0, 6.0)]
    shown = sorted(float(t.split("θ = ")[1].split("°")[0].replace("−", "-")) for t in texts)
    assert shown == pytest.approx(sorted([-folds[1], -folds[0], folds[0], folds[1]]), abs=0.006)
    assert "θ in" in page.inner_text("#range-text")

    # hover the marker of a limit position on the drawing: its explanation appears
    scene = page.evaluate("lw.scene()")
    own = next(k for k, m in enumerate(scene["modes"]) if m["own"])
    lim = next(x for x in scene["limits"] if x["mode"] == own)
    p = scene["modes"][lim["mode"]]["circuits"][lim["circuit"]]["positions"]["P"][lim["index"]]
    page.mouse.move(*_to_page(page, p))
    tip = page.locator("#tooltip")
    tip.wait_for(state="visible")
    assert tip.inner_text() == lim["text"]

    # clicking a limit in the list shows that position: the input turns back there
    items.nth(1).click()
    shown = _shown_at(page)
    second = [x for x in scene["limits"] if x["mode"] == own][1]
    assert shown == pytest.approx(second["input"], abs=0.06)

    # the animation runs the whole circuit, up one branch and back the other
    circ = scene["modes"][own]["circuits"][0]
    n = len(circ["input"])
    items.nth(0).click()  # sample 0 of the first circuit
    # ten samples a step: the limits sit at samples 0 and n/2, so the steps land on both
    assert n % 20 == 0 and sorted(lim["index"] for lim in scene["limits"][:2]) == [0, n // 2]
    seen = page.evaluate(
        "n => Array.from({length: n / 10}, () => { lw.step(10); return lw.at(); })", n
    )
    lo, hi = min(circ["input"]), max(circ["input"])
    assert min(seen) == pytest.approx(lo) and max(seen) == pytest.approx(hi)
    # the arrow keys step one sample up the branch, and back down
    page.locator("#drawing").focus()
    page.keyboard.press("ArrowRight")
    assert _at(page) == pytest.approx(circ["input"][1])
    assert "↑" in page.inner_text("#at-value")
    page.keyboard.press("ArrowLeft")
    page.keyboard.press("ArrowLeft")
    assert _at(page) == pytest.approx(circ["input"][-1])

    # picking the other circuit writes it into the document (its start, an input on its arc),
    # one undoable step, so that a save, a share link and the CLI trace the circuit picked here
    other = scene["modes"][own]["circuits"][1]["input"]
    steps = page.evaluate("lw.history().undo")
    before = _scenes(page)
    page.select_option("#circuit-select", "1")
    _settle(page, before)
    start = page.evaluate("lw.document().mechanism.start")
    assert min(other) - 1e-6 <= start <= max(other) + 1e-6
    assert not (min(circ["input"]) <= start <= max(circ["input"]))
    assert page.input_value("#circuit-select") == "1"
    assert page.evaluate("lw.history()") == {"undo": steps + 1, "redo": 0, "dirty": True}
    page.evaluate("lw.undo()")
    page.wait_for_function("lw.document().mechanism.start === undefined")


def test_edit_a_field_redraws_the_curve(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    curve0 = page.evaluate("lw.scene().modes.find(m => m.own).circuits[0].positions.P")
    before = _scenes(page)
    page.fill("[data-path='mechanism.crank']", "1.25")
    page.press("[data-path='mechanism.crank']", "Enter")
    _settle(page, before)
    scene = page.evaluate("lw.scene()")
    assert scene["document"]["mechanism"]["crank"] == 1.25
    pose = page.evaluate("lw.pose()")
    # the drawn crank has the typed length, the other links keep theirs
    assert _dist(pose["A0"], pose["A"]) == pytest.approx(1.25, abs=1e-9)
    assert _dist(pose["A"], pose["B"]) == pytest.approx(5.0, abs=1e-9)
    assert _dist(pose["B0"], pose["B"]) == pytest.approx(6.02, abs=1e-9)
    curve1 = scene["modes"][0]["circuits"][0]["positions"]["P"]
    assert max(_dist(a, b) for a, b in zip(curve0, curve1, strict=False)) > 0.05
    # the field shows the value the server accepted
    assert page.input_value("[data-path='mechanism.crank']") == "1.25"

    # a choice field: the other assembly
    before = _scenes(page)
    page.select_option("[data-path='mechanism.assembly']", "-1")
    _settle(page, before)
    assert page.evaluate("lw.document().mechanism.assembly") == -1


def test_bad_value_shows_a_clear_error(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    count = _scenes(page)
    page.fill("[data-path='mechanism.coupler']", "-2")
    page.press("[data-path='mechanism.coupler']", "Enter")
    page.wait_for_function("document.getElementById('status').dataset.kind === 'error'")
    _settle(page)
    message = page.inner_text("#status")
    assert "coupler" in message
    expect(page.locator("[data-path='mechanism.coupler'].invalid")).to_have_count(1)
    # the last good linkage stays drawn, and the document is the last good one
    assert _scenes(page) == count
    assert page.evaluate("lw.document().mechanism.coupler") == 5.0

    # a linkage that cannot assemble anywhere is not an error: the drawing says why
    before = _scenes(page)
    page.fill("[data-path='mechanism.coupler']", "0.5")
    page.press("[data-path='mechanism.coupler']", "Enter")
    _settle(page, before)
    assert page.get_attribute("#status", "data-kind") == "info"
    msg = page.locator("#canvas-message")
    assert msg.is_visible()
    assert "cannot be assembled" in msg.inner_text()

    before = _scenes(page)
    page.fill("[data-path='mechanism.coupler']", "5")
    page.press("[data-path='mechanism.coupler']", "Enter")
    _settle(page, before)
    assert not msg.is_visible()
    expect(page.locator("#fields .invalid")).to_have_count(0)


def test_drag_the_coupler_point(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    doc0 = page.evaluate("lw.document()")
    pose0 = page.evaluate("lw.pose()")
    start = _to_page(page, pose0["P"])
    target = (start[0] + 40, start[1] - 25)
    page.mouse.move(*start)
    page.mouse.down()
    for k in range(1, 9):
        page.mouse.move(start[0] + 40 * k / 8, start[1] - 25 * k / 8)
    page.mouse.up()
    _settle(page)
    doc1 = page.evaluate("lw.document()")
    m0, m1 = doc0["mechanism"], doc1["mechanism"]
    # only the coupler point moved
    assert m1["point"] != m0["point"]
    assert {k: v for k, v in m1.items() if k != "point"} == {
        k: v for k, v in m0.items() if k != "point"
    }
    # and P is drawn under the mouse
    pose1 = page.evaluate("lw.pose()")
    assert _dist(_to_page(page, pose1["P"]), target) < 1.5
    assert page.evaluate("lw.at()") == pytest.approx(page.evaluate("lw.scene().at"))
    # the fields follow
    assert float(page.input_value("[data-path='mechanism.point.u']")) == pytest.approx(
        m1["point"]["u"], rel=1e-9
    )


def test_drag_the_crank_end_turns_the_input(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    at0 = _at(page)
    pose0 = page.evaluate("lw.pose()")
    # A sits on the crank circle about A0; drag it a quarter turn round that circle
    a0, r = pose0["A0"], _dist(pose0["A0"], pose0["A"])
    theta = math.radians(at0)
    page.mouse.move(*_to_page(page, pose0["A"]))
    page.mouse.down()
    for k in range(1, 7):
        t = theta + math.radians(90) * k / 6
        page.mouse.move(*_to_page(page, [a0[0] + r * math.cos(t), a0[1] + r * math.sin(t)]))
    page.mouse.up()
    _settle(page)
    assert _at(page) == pytest.approx(at0 + 90, abs=1.0)
    assert _shown_at(page) == pytest.approx(_at(page), abs=0.06)
    assert page.evaluate("lw.document().mechanism.crank") == pytest.approx(1.0, abs=1e-6)


def test_play_pause_step_and_speed(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    at0 = _shown_at(page)
    page.click("#step-fwd")
    assert _shown_at(page) == pytest.approx(at0 + 1, abs=1e-6)
    page.click("#step-back")
    page.click("#step-back")
    assert _shown_at(page) == pytest.approx(at0 - 1, abs=1e-6) or _shown_at(page) == pytest.approx(
        at0 + 359, abs=1e-6
    )

    # play moves the input; pause holds it
    page.click("#play")
    assert page.get_attribute("#play", "data-state") == "playing"
    page.wait_for_function(f"Math.abs(lw.at() - ({_at(page)})) > 3")
    page.click("#play")
    held = _shown_at(page)
    page.wait_for_timeout(250)
    assert _shown_at(page) == held

    # the keyboard: space plays and pauses, the arrows step
    page.locator("#drawing").focus()
    page.keyboard.press("Space")
    assert page.get_attribute("#play", "data-state") == "playing"
    page.keyboard.press("Space")
    assert page.get_attribute("#play", "data-state") == "paused"
    held = _at(page)
    page.keyboard.press("ArrowRight")
    assert _at(page) == pytest.approx(held + 1, abs=1e-6) or _at(page) == pytest.approx(
        held - 359, abs=1e-6
    )

    # speed: the same wall time turns the input further when faster
    def advance(speed: str) -> int:
        page.fill("#speed", speed)
        i0 = int(page.input_value("#input-slider"))
        page.click("#play")
        page.wait_for_timeout(500)
        page.click("#play")
        n = int(page.get_attribute("#input-slider", "max")) + 1
        return (int(page.input_value("#input-slider")) - i0) % n

    slow, fast = advance("10"), advance("80")
    assert fast > 3 * max(slow, 1)

    # the input-angle slider sets the input directly
    page.fill("#input-slider", "90")
    assert _shown_at(page) == pytest.approx(
        page.evaluate("lw.scene().modes.find(m => m.own).circuits[0].input[90]"), abs=0.06
    )


def test_switch_assembly_mode(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    modes = page.locator("#modes [data-testid='mode-option']")
    expect(modes).to_have_count(2)
    pose0 = page.evaluate("lw.pose()")
    other = page.locator("#modes [aria-checked='false']")
    before = _scenes(page)
    other.click()
    _settle(page, before)
    assert page.evaluate("lw.document().mechanism.assembly") == -1
    assert "assembly −1" in page.inner_text("#modes [aria-checked='true']")
    pose1 = page.evaluate("lw.pose()")
    # same input, the other assembly: B is the mirror image of its old place in the line A–B0
    assert _dist(pose1["A"], pose0["A"]) < 1e-9
    ax, ay = pose0["A"]
    bx, by = pose0["B0"]
    dx, dy = bx - ax, by - ay
    px, py = pose0["B"][0] - ax, pose0["B"][1] - ay
    t = (px * dx + py * dy) / (dx * dx + dy * dy)
    mirror = [ax + 2 * t * dx - px, ay + 2 * t * dy - py]
    assert _dist(pose1["B"], mirror) < 1e-6
    # the legend names both modes, the own one first and bold
    legend = page.inner_text("#legend")
    assert "assembly −1" in legend and "assembly +1" in legend and "this mode" in legend


def test_plots_follow_the_input(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    canvases = page.locator("#plots canvas:visible")
    assert canvases.count() >= 2
    titles = page.locator("#plots .plot:visible .plot-title").all_inner_texts()
    assert any("transmission" in t for t in titles) and any("output" in t for t in titles)
    c0 = float(canvases.first.get_attribute("data-cursor"))
    for _ in range(30):
        page.evaluate("lw.step(1)")
    c1 = float(canvases.first.get_attribute("data-cursor"))
    assert c1 > c0 + 5
    # velocity and acceleration of the traced point
    page.click("[data-testid='plot-kind-velocity']")
    titles = page.locator("#plots .plot:visible .plot-title").all_inner_texts()
    assert any("dP/dθ" in t for t in titles)
    page.click("[data-testid='plot-kind-acceleration']")
    assert page.locator("#plots .plot:visible canvas").first.get_attribute("data-cursor")


def test_sphere_turns_with_the_mouse_and_joints_drag_on_it(page: Any, server_url: str) -> None:
    _open(page, server_url, "paper000-fig6-crank-rocker")
    pose = page.evaluate("lw.pose()")
    r0 = page.evaluate("lw.view().rotation")
    box = _canvas_box(page)
    joints = [_to_page(page, p) for p in pose.values()]
    # an empty spot on the sphere, away from every joint
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    spots = [(cx + dx, cy + dy) for dx in (-60, 0, 60) for dy in (-60, 0, 60)]
    spot = max(spots, key=lambda s: min(math.dist(s, j) for j in joints))
    a0 = _to_page(page, pose["A0"])
    page.mouse.move(*spot)
    page.mouse.down()
    page.mouse.move(spot[0] + 30, spot[1] + 10)
    page.mouse.move(spot[0] + 60, spot[1] + 20)
    page.mouse.up()
    r1 = page.evaluate("lw.view().rotation")
    assert max(abs(a - b) for a, b in zip(r0, r1, strict=True)) > 0.05
    assert math.dist(_to_page(page, pose["A0"]), a0) > 5
    # a rotation: still orthonormal
    rows = [r1[0:3], r1[3:6], r1[6:9]]
    for i in range(3):
        for j in range(3):
            dot = sum(rows[i][k] * rows[j][k] for k in range(3))
            assert dot == pytest.approx(1.0 if i == j else 0.0, abs=1e-9)

    # drag the coupler point P across the front of the sphere; the document follows
    doc0 = page.evaluate("lw.document()")
    p = _to_page(page, pose["P"])
    front = page.evaluate(
        "p => { const R = lw.view().rotation; return R[6]*p[0]+R[7]*p[1]+R[8]*p[2]; }", pose["P"]
    )
    assert front > 0, "P must face the viewer for this test"
    target = (p[0] + 15, p[1] - 10)
    page.mouse.move(*p)
    page.mouse.down()
    page.mouse.move(p[0] + 8, p[1] - 5)
    page.mouse.move(*target)
    page.mouse.up()
    _settle(page)
    doc1 = page.evaluate("lw.document()")
    assert doc1["mechanism"]["point"] != doc0["mechanism"]["point"]
    assert doc1["mechanism"]["crank"] == doc0["mechanism"]["crank"]
    pose1 = page.evaluate("lw.pose()")
    assert math.dist(_to_page(page, pose1["P"]), target) < 2.0
    assert sum(v * v for v in pose1["P"]) == pytest.approx(1.0, abs=1e-9)


def test_six_bar_on_the_sphere_shows_every_mode(page: Any, server_url: str) -> None:
    _open(page, server_url, "paper000-fig8-sixbar")
    scene = page.evaluate("lw.scene()")
    assert len(scene["modes"]) == page.locator("#modes [data-testid='mode-option']").count()
    assert page.locator("#map").is_visible()
    legend = page.inner_text("#legend")
    for m in scene["modes"]:
        assert m["label"] in legend
    assert scene["traced"][0] in legend


def test_lw_overlay_and_pick_points(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    page.evaluate(
        "lw.overlay('target', [[[0, 0], [1, 1], [2, 0]]],"
        " {color: '#228be6', label: 'target curve'})"
    )
    assert "target curve" in page.inner_text("#legend")
    page.evaluate("lw.clearOverlay('target')")
    assert "target curve" not in page.inner_text("#legend")

    page.evaluate("window._picked = null; lw.pickPoints(pts => { window._picked = pts; })")
    box = _canvas_box(page)
    x0, y0 = box["x"] + 120, box["y"] + 200
    page.mouse.move(x0, y0)
    page.mouse.down()
    for k in range(1, 21):
        page.mouse.move(x0 + 6 * k, y0 + 3 * k)
    page.mouse.up()
    picked = page.evaluate("window._picked")
    assert picked is not None and len(picked) >= 10
    first = page.evaluate("p => lw.toScreen(p)", picked[0])
    last = page.evaluate("p => lw.toScreen(p)", picked[-1])
    assert math.dist(first, [120, 200]) < 1.0
    assert math.dist(last, [240, 260]) < 1.0

"""Analysis on the drawing (issue 24, points 5 and 6), used the way a person uses it: toggle the
velocity and acceleration arrows and the instant centres, read the speeds in physical units, open
the analysis summary; on a four-bar and on a spherical four-bar.

The arrows are counted (the drawing's ``data-arrows``) and found on the canvas by their colour
where the joint's velocity points; the speeds shown are checked against the crank's closed form
(|v_A| = crank·ω, |a_A| = crank·ω² at constant speed) and the summary against the library's own
analysis, not against earlier output of the page.
"""

from __future__ import annotations

import json
import math
from typing import Any

import pytest

from linkwright.analysis import analyze
from linkwright.io import load_example
from linkwright.io.report import analysis_report

SCENE_COUNT = "Number(document.body.dataset.sceneCount || 0)"
IDLE = "document.body.dataset.busy === '0'"


def _open(page: Any, server_url: str, example: str | None = None) -> None:
    page.goto(server_url)
    page.wait_for_function(f"{SCENE_COUNT} >= 1 && document.body.dataset.overlaysReady === '1'")
    page.wait_for_function(IDLE)
    if example is not None:
        before = int(page.evaluate(SCENE_COUNT))
        page.select_option("#example-select", example)
        page.wait_for_function(f"{SCENE_COUNT} > {before}")
        page.wait_for_function(IDLE)


def _toggle(page: Any, key: str, wait: str) -> None:
    page.click(f'[data-testid="toggle-{key}"]')
    assert page.get_attribute(f'[data-testid="toggle-{key}"]', "aria-pressed") == "true"
    page.wait_for_function(f"lw.scene() && ({wait})")
    page.wait_for_function(IDLE)


def _drawn(page: Any, attribute: str, count: str) -> str:
    """The drawing's ``data-<attribute>`` once the canvas shows ``count`` of them: it is set
    by the next frame drawn after a toggle, which a busy machine may not have drawn yet."""
    page.wait_for_function(
        f"document.querySelector('#drawing').dataset.{attribute} === '{count}'", timeout=15_000
    )
    return str(page.get_attribute("#drawing", f"data-{attribute}"))


def _colour_near(page: Any, x: float, y: float) -> list[int]:
    """The canvas pixel nearest (x, y) (CSS pixels) whose colour is closest to the velocity
    arrows' #0c8599, within 2 px."""
    return page.evaluate(
        """([x, y]) => {
          const cv = document.querySelector('#drawing');
          const k = cv.width / cv.clientWidth;
          const ctx = cv.getContext('2d');
          let best = null, bd = Infinity;
          for (let dx = -2; dx <= 2; dx++) for (let dy = -2; dy <= 2; dy++) {
            const px = [Math.round((x + dx) * k), Math.round((y + dy) * k)];
            const d = ctx.getImageData(px[0], px[1], 1, 1).data;
            const e = Math.hypot(d[0] - 12, d[1] - 133, d[2] - 153);
            if (e < bd) { bd = e; best = [d[0], d[1], d[2]]; }
          }
          return best;
        }""",
        [x, y],
    )


def test_a_fourbars_vectors_centres_and_speeds(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    # Nothing is asked of the server until a toggle is on.
    assert page.evaluate("'overlays' in lw.scene()") is False
    _toggle(page, "velocity", "lw.scene().overlays")
    moving = page.evaluate("lw.scene().joints.filter(j => !lw.scene().fixed.includes(j)).length")
    assert str(moving) == "3" and _drawn(page, "arrows", "3") == "3"
    # The arrow at A is drawn where A's velocity points (the canvas's y axis points down).
    sample = page.evaluate("lw.overlays.sample()")
    pose = page.evaluate("lw.pose()")
    sx, sy = page.evaluate("p => lw.toScreen(p)", pose["A"])
    vx, vy = sample["velocity"]["A"]
    n = math.hypot(vx, vy)
    r, g, b = _colour_near(page, sx + 30 * vx / n, sy - 30 * vy / n)
    assert math.hypot(r - 12, g - 133, b - 153) < 60, (r, g, b)

    _toggle(page, "acceleration", "true")
    assert _drawn(page, "arrows", "6") == "6"
    _toggle(page, "centres", "true")
    assert _drawn(page, "centres", "6") == "6"  # Kennedy: all six
    assert page.evaluate("lw.scene().overlays.labels") == ["I12", "I13", "I14", "I23", "I24", "I34"]
    key = page.inner_text('[data-testid="centre-bodies"]')
    assert key.endswith("1 frame · 2 A0–A · 3 A–B–P · 4 B0–B")

    # Speeds in physical units: 120 rpm, lengths in mm (the document's numbers are in mm).
    page.fill('[data-testid="input-rpm"]', "120")
    page.press('[data-testid="input-rpm"]', "Enter")
    before = int(page.evaluate(SCENE_COUNT))
    page.select_option('[data-testid="length-unit"]', "mm")
    page.wait_for_function(f"{SCENE_COUNT} > {before}")
    page.wait_for_function(IDLE)
    assert page.evaluate("lw.document().units") == "mm"
    header = page.inner_text("#motion-readout thead")
    assert "mm/s" in header and "mm/s²" in header
    crank = float(load_example("crank-rocker").mechanism.crank)
    w = 120 * 2 * math.pi / 60
    cells = page.eval_on_selector_all(
        '#motion-readout tr[data-joint="A"] td', "tds => tds.map(t => t.textContent)"
    )
    assert cells[0] == "A"
    assert float(cells[1]) == pytest.approx(crank * w, rel=1e-3)
    assert float(cells[2]) == pytest.approx(crank * w * w, rel=1e-3)
    # Turning the toggles off stops drawing them.
    page.click('[data-testid="toggle-velocity"]')
    page.click('[data-testid="toggle-acceleration"]')
    page.wait_for_function("document.querySelector('#drawing').dataset.arrows === '0'")


def test_a_fourbars_summary_shows_its_class_and_coefficients(page: Any, server_url: str) -> None:
    _open(page, server_url, "crank-rocker")
    _toggle(page, "summary", "lw.scene().summary")
    expected = analysis_report(analyze(load_example("crank-rocker").mechanism))
    shown = page.eval_on_selector_all(
        '[data-testid="summary"] dd',
        "dds => Object.fromEntries(dds.map(d => [d.dataset.key, d.textContent]))",
    )
    assert shown["class"] == expected["class"] == "crank-rocker"
    assert shown["grashof"].startswith("Grashof")
    assert float(shown["K_omega"]) == pytest.approx(expected["coefficients"]["K_omega"], rel=1e-3)
    assert float(shown["time_ratio"]) == pytest.approx(expected["time_ratio"], rel=1e-3)
    assert shown["delta"] == "—"  # a crank-rocker has no δ
    assert shown["dead_centres"].startswith("θ = ")
    # A drag does not wait for the analysis: its scenes come without it, and the summary of
    # where the joint was dropped follows once the drag is over.
    asked: list[bool] = []

    def record(request: Any) -> None:
        if request.url.endswith("/api/scene") and request.method == "POST":
            asked.append(bool(json.loads(request.post_data or "{}").get("summary")))

    page.on("request", record)
    box = page.locator("#drawing").bounding_box()
    before = page.evaluate("lw.document().mechanism.point")
    sx, sy = page.evaluate("p => lw.toScreen(p)", page.evaluate("lw.pose()")["P"])
    page.mouse.move(box["x"] + sx, box["y"] + sy)
    page.mouse.down()
    for k in range(1, 6):
        page.mouse.move(box["x"] + sx + 6 * k, box["y"] + sy - 4 * k)
        page.wait_for_timeout(60)
    page.mouse.up()
    page.wait_for_function("lw.scene().summary && document.body.dataset.busy === '0'")
    assert page.evaluate("lw.document().mechanism.point") != before
    assert asked and not asked[0] and asked[-1], asked
    assert (
        page.eval_on_selector('[data-testid="summary"]', "d => d.classList.contains('stale')")
        is False
    )


def test_a_spherical_fourbar_shows_its_axes_and_a_summary(page: Any, server_url: str) -> None:
    _open(page, server_url, "paper000-fig6-crank-rocker")
    assert page.evaluate("lw.scene().space") == "sphere"
    _toggle(page, "centres", "lw.scene().overlays")
    _toggle(page, "summary", "lw.scene().summary")
    assert _drawn(page, "centres", "6") == "6"
    assert page.evaluate("lw.overlays.drawn().axes") == 6
    axes = page.evaluate("lw.overlays.sample().centres")
    assert all(abs(math.hypot(*a) - 1) < 1e-9 for a in axes)
    shown = page.eval_on_selector_all(
        '[data-testid="summary"] dd',
        "dds => Object.fromEntries(dds.map(d => [d.dataset.key, d.textContent]))",
    )
    assert shown["class"] == "crank-rocker" and shown["K_omega"] != "—"
    assert page.is_hidden("#summary-note")
    assert page.get_attribute('[data-testid="status"]', "data-kind") != "error"
    _toggle(page, "velocity", "true")
    assert _drawn(page, "arrows", "3") == "3"
    assert "°/s" in page.inner_text("#motion-readout thead")

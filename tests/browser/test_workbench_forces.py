"""The workbench's forces panel (issue 25 point 5), used the way a person uses it: open the
crank-rocker, open the Forces panel, read that it has no masses, give every link a mass with
one click, read the torque chart and the reactions, see the arrows on the drawing, change the
speed and the length unit, and undo back to no masses; then the same on the sphere.

The page's numbers are held to relations of their own, not to earlier output: without gravity
the torque goes as the speed squared (twice the rpm, four times the torque at the same sample),
a length unit of mm shows kg·mm²/s² as 10⁻⁶ N·m, and an arrow is found on the canvas, by its
colour, where the joint's reaction points.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

SCENE_COUNT = "Number(document.body.dataset.sceneCount || 0)"
IDLE = "document.body.dataset.busy === '0'"
PANEL = "document.querySelector('#forces-panel').dataset.state"
ARROWS = "document.querySelector('#drawing').dataset.forceArrows"


def _open(page: Any, server_url: str, example: str) -> None:
    page.goto(server_url)
    page.wait_for_function(f"{SCENE_COUNT} >= 1 && document.body.dataset.forcesReady === '1'")
    page.wait_for_function(IDLE)
    if page.input_value("#example-select") != example:
        before = int(page.evaluate(SCENE_COUNT))
        page.select_option("#example-select", example)
        page.wait_for_function(f"{SCENE_COUNT} > {before}")
        page.wait_for_function(IDLE)


def _state(page: Any, state: str) -> None:
    page.wait_for_function(f"{PANEL} === '{state}'")
    page.wait_for_function(IDLE)


def _torque_now(page: Any) -> float:
    return float(page.get_attribute('[data-testid="forces-torque-now"]', "data-value"))


def _arrow_colour_at(page: Any, x: float, y: float) -> float:
    """How far (in RGB) the canvas pixel nearest (x, y), within 2 px, is from the force
    arrows' #e8590c."""
    return float(
        page.evaluate(
            """([x, y]) => {
              const cv = document.querySelector('#drawing');
              const k = cv.width / cv.clientWidth;
              const ctx = cv.getContext('2d');
              let best = Infinity;
              for (let dx = -2; dx <= 2; dx++) for (let dy = -2; dy <= 2; dy++) {
                const px = [Math.round((x + dx) * k), Math.round((y + dy) * k)];
                const d = ctx.getImageData(px[0], px[1], 1, 1).data;
                best = Math.min(best, Math.hypot(d[0] - 232, d[1] - 89, d[2] - 12));
              }
              return best;
            }""",
            [x, y],
        )
    )


def test_a_crank_rockers_forces_from_no_masses_to_arrows_and_back(
    page: Any, server_url: str
) -> None:
    _open(page, server_url, "crank-rocker")
    # Nothing is asked of the server while the panel is closed and the arrows are off.
    assert page.evaluate("lw.forces.get()") == {"open": False, "arrows": False, "status": "closed"}
    assert page.evaluate("lw.forces.data()") is None
    page.click('[data-testid="forces-open"]')
    _state(page, "no-masses")
    message = page.inner_text('[data-testid="forces-message"]')
    assert message.startswith("No masses:") and "[mechanism.mass]" in message
    assert "\n" not in message
    button = '[data-testid="forces-add-masses"]'
    assert page.inner_text(button) == "Make every link a uniform body of 1 kg"

    # One click: the masses go through the scene pipeline, and the numbers arrive.
    page.click(button)
    page.wait_for_function("lw.scene().document.mechanism.mass !== undefined")
    _state(page, "ready")
    mass = page.evaluate("lw.scene().document.mechanism.mass")
    assert mass == {"crank": 1.0, "coupler": 1.0, "rocker": 1.0}
    data = page.evaluate("lw.forces.data()")
    samples = len(page.evaluate("lw.scene().modes.find(m => m.own).circuits[0].input"))
    assert len(data["circuits"][0]["torque"]) == samples
    assert page.get_attribute('[data-testid="forces-torque"]', "data-points") == str(samples)
    assert page.get_attribute('[data-testid="forces-reactions"]', "data-series") == "4"
    rows = page.eval_on_selector_all(
        '[data-testid="forces-readout"] tbody tr', "rs => rs.map(r => r.dataset.joint)"
    )
    assert sorted(rows) == ["A", "A0", "B", "B0"]
    # The readout is the sample drawn now.
    sample = page.evaluate("lw.forces.sample()")
    assert _torque_now(page) == sample["torque"]

    # The arrows: one per joint, and one found where B0's reaction points.
    page.click('[data-testid="toggle-forces"]')
    page.wait_for_function(f"{ARROWS} === '4'")
    pose = page.evaluate("lw.pose()")
    force = sample["reactions"]["B0"]
    size = math.hypot(*force)
    length = min(180.0, 60.0 * size / data["scale"]["force"])
    assert length > 12, "an arrow long enough to find"
    sx, sy = page.evaluate(f"lw.toScreen({pose['B0']})")
    along = 0.6 * length / size
    assert _arrow_colour_at(page, sx + along * force[0], sy - along * force[1]) < 40

    # Twice the speed, four times the torque at the same sample (no gravity: T ∝ ω²).
    page.fill('[data-testid="input-rpm"]', "120")
    page.dispatch_event('[data-testid="input-rpm"]', "change")
    page.wait_for_function("lw.forces.data() && lw.forces.data().speed_rpm === 120")
    page.wait_for_function(IDLE)
    assert page.evaluate("lw.forces.sample().input") == sample["input"]
    assert _torque_now(page) == pytest.approx(4 * sample["torque"], rel=1e-9)
    twice = page.evaluate("lw.forces.sample()")["torque"]

    # Lengths in mm: the same numbers, read as kg·mm²/s² = 10⁻⁶ N·m.
    before = int(page.evaluate(SCENE_COUNT))
    page.select_option('[data-testid="length-unit"]', "mm")
    page.wait_for_function(f"{SCENE_COUNT} > {before} && lw.scene().units === 'mm'")
    _state(page, "ready")
    page.wait_for_function("lw.forces.units().torque === 'N·m'")
    assert page.evaluate("lw.forces.sample().torque") == twice
    assert _torque_now(page) == pytest.approx(twice * 1e-6, rel=1e-12)
    assert "N·m" in page.inner_text('[data-testid="forces-torque-now"]')

    # Undo: the unit, then the masses; the panel says again that there are none.
    page.click('[data-testid="undo"]')
    page.wait_for_function("lw.scene().units == null")
    page.click('[data-testid="undo"]')
    page.wait_for_function("lw.scene().document.mechanism.mass === undefined")
    _state(page, "no-masses")
    page.wait_for_function(f"{ARROWS} === '0'")
    assert page.get_attribute('[data-testid="forces-torque"]', "data-points") == "0"


def test_a_spherical_four_bars_forces_and_moments(page: Any, server_url: str) -> None:
    _open(page, server_url, "paper000-fig6-crank-rocker")
    page.evaluate("lw.forces.open(true); lw.forces.arrows(true)")
    _state(page, "no-masses")
    page.click('[data-testid="forces-add-masses"]')
    _state(page, "ready")
    data = page.evaluate("lw.forces.data()")
    assert data["space"] == "sphere" and set(data["circuits"][0]["moments"]) == {
        "A0",
        "A",
        "B",
        "B0",
    }
    # The joints in front of the sphere carry arrows (those behind it are not drawn).
    page.wait_for_function(f"Number({ARROWS}) >= 1")
    head = page.eval_on_selector_all(
        '[data-testid="forces-readout"] thead th', "hs => hs.map(h => h.textContent)"
    )
    assert head[0] == "joint" and head[1].startswith("|R|") and head[2].startswith("|M|")
    assert "least-norm" in page.inner_text("#forces-note")

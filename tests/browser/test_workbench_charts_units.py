"""Issue 24 point 5: the velocity and acceleration charts in physical units at the page's input
speed. The charts' values per radian of input (the kinematic coefficients the server sends)
times ω, and ω², are checked against the same charts' own per-radian readout, at two speeds."""

from __future__ import annotations

import math
import re
from typing import Any

from playwright.sync_api import expect

SCENES = "Number(document.body.dataset.sceneCount || 0)"
NUMBER = re.compile(r"[−-]?\d+(?:\.\d+)?(?:e[−-]?\d+)?")


def _readouts(page: Any, kind: str) -> list[float]:
    page.wait_for_function("document.body.dataset.busy === '0'")
    texts = page.eval_on_selector_all(
        f"[data-testid='plot'][data-diagram='{kind}'] canvas",
        "cs => cs.map(c => c.dataset.readout || '')",
    )
    values = []
    for text in texts:
        for m in NUMBER.findall(text):
            values.append(float(m.replace("−", "-")))
    return values


def test_rate_charts_per_second_at_the_input_speed(page: Any, server_url: str) -> None:
    page.goto(server_url + "/#crank-rocker")
    page.wait_for_function(f"{SCENES} >= 1")
    page.wait_for_function("document.body.dataset.busy === '0'")
    page.evaluate("lw.setAt(70)")
    for kind, order in (("velocity", 1), ("acceleration", 2)):
        page.click(f"[data-testid='plot-kind-{kind}']")
        button = page.locator("[data-testid='plot-physical']")
        expect(button).to_have_text("per radian")
        per_radian = _readouts(page, kind)
        assert per_radian and any(abs(v) > 1e-3 for v in per_radian)
        titles = page.eval_on_selector_all(
            f"[data-testid='plot'][data-diagram='{kind}'] .plot-title span",
            "ss => ss.map(s => s.textContent)",
        )
        assert any("/rad" in t for t in titles)

        button.click()
        expect(button).to_have_text("per second")
        omega = 2 * math.pi * 60 / 60
        titles = page.eval_on_selector_all(
            f"[data-testid='plot'][data-diagram='{kind}'] .plot-title span",
            "ss => ss.map(s => s.textContent)",
        )
        assert any("at 60 rpm" in t and "/s" in t for t in titles), titles
        for v, w in zip(per_radian, _readouts(page, kind), strict=True):
            assert math.isclose(w, v * omega**order, rel_tol=2e-3, abs_tol=1e-9), (v, w)

        # a new input speed rescales them: twice the speed, ω (ω²) times as much again
        page.fill("[data-testid='input-rpm']", "120")
        page.dispatch_event("[data-testid='input-rpm']", "change")
        page.wait_for_function(
            f"[...document.querySelectorAll(\"[data-diagram='{kind}'] .plot-title span\")]"
            ".some(s => s.textContent.includes('at 120 rpm'))"
        )
        for v, w in zip(per_radian, _readouts(page, kind), strict=True):
            assert math.isclose(w, v * (2 * omega) ** order, rel_tol=2e-3, abs_tol=1e-9)
        page.fill("[data-testid='input-rpm']", "60")
        page.dispatch_event("[data-testid='input-rpm']", "change")
        button.click()
        expect(button).to_have_text("per radian")


def test_a_link_carries_the_toggles_the_speed_the_units_and_the_forces_panel(
    page: Any, server_url: str
) -> None:
    page.goto(server_url + "/#crank-rocker")
    page.wait_for_function(f"{SCENES} >= 1")
    page.wait_for_function("document.body.dataset.busy === '0'")
    page.click("[data-testid='toggle-velocity']")
    page.fill("[data-testid='input-rpm']", "90")
    page.dispatch_event("[data-testid='input-rpm']", "change")
    page.click("[data-testid='plot-kind-velocity']")
    page.click("[data-testid='plot-physical']")
    page.click("[data-testid='forces-open']")
    page.click("[data-testid='toggle-forces']")
    page.wait_for_function("document.body.dataset.busy === '0'")
    link = page.evaluate("lw.shareLink()")
    # another browser context: nothing of this page's storage reaches it
    other = page.context.browser.new_context(viewport={"width": 1400, "height": 900})
    fresh = other.new_page()
    fresh.goto(link)
    fresh.wait_for_function(f"{SCENES} >= 1")
    fresh.wait_for_function("document.body.dataset.busy === '0'")
    assert fresh.evaluate("lw.overlays.get().velocity") is True
    assert fresh.evaluate("lw.overlays.units().rpm") == 90
    expect(fresh.locator("[data-testid='input-rpm']")).to_have_value("90")
    expect(fresh.locator("[data-testid='plot-physical']")).to_have_text("per second")
    # the forces panel as it was left: open, its arrows on the drawing
    expect(fresh.locator("[data-testid='forces-open']")).to_have_attribute("aria-expanded", "true")
    expect(fresh.locator("[data-testid='toggle-forces']")).to_have_attribute("aria-pressed", "true")
    other.close()

"""Take the README's screenshots of the workbench: ``python docs/screenshots.py``.

A server runs in this process on a free loopback port with a throwaway data directory, and
Debian's chromium (headless, driven by Playwright) shows the page at 1400×900 in each state; the
pictures go to ``docs/img/workbench/``.
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

from playwright.sync_api import Page, sync_playwright

from linkwright.server.local import CHROMIUM_ARGS, LocalServer, chromium_path

OUT = Path(__file__).parent / "img" / "workbench"


def _settle(page: Page, before: int) -> None:
    page.wait_for_function(f"Number(document.body.dataset.sceneCount) > {before}")
    page.wait_for_function("document.body.dataset.busy !== '1'")
    page.wait_for_timeout(300)


def _example(page: Page, name: str) -> None:
    before = int(page.evaluate("Number(document.body.dataset.sceneCount)"))
    page.select_option("#example-select", name)
    _settle(page, before)


def _tab(page: Page, name: str) -> None:
    page.click(f"#side .tabs button[data-tab={name}]")
    page.wait_for_selector(f"#tab-{name}:not([hidden])")


def shoot(page: Page, url: str) -> list[Path]:
    written = []

    def save(name: str) -> None:
        path = OUT / f"{name}.png"
        page.screenshot(path=str(path))
        written.append(path)

    page.goto(url)
    page.wait_for_function("window.lw && Number(document.body.dataset.sceneCount) >= 1")
    _example(page, "crank-rocker")
    page.evaluate("lw.setAt(60)")
    page.wait_for_timeout(200)
    save("planar")

    _example(page, "rocker-input")
    page.click("[data-testid=limit-item] >> nth=0")
    page.wait_for_timeout(200)
    save("limits")

    _example(page, "paper000-fig6-crank-rocker")
    page.click(".plot-tabs button >> nth=0") if page.locator(".plot-tabs button").count() else None
    save("sphere")

    _example(page, "geared-fivebar")
    _tab(page, "study")
    page.select_option("#study-pivot", "A0")
    page.select_option("#study-direction", "angle")
    page.fill("#study-angle", "180")
    page.fill("#study-step", "0.5")
    page.fill("#study-count", "3")
    page.click("#study-run")
    page.wait_for_selector("#tab-study[data-state=done]", timeout=60_000)
    page.wait_for_timeout(300)
    save("study")

    _example(page, "crank-rocker")
    _tab(page, "synthesis")
    csv = Path(tempfile.mkdtemp()) / "ellipse.csv"
    rows = ["x,y"]
    for k in range(36):
        t = 2 * math.pi * k / 36
        x, y = 3 * math.cos(t), 1.2 * math.sin(t)
        c, s = math.cos(math.radians(25)), math.sin(math.radians(25))
        rows.append(f"{1 + c * x - s * y:.9f},{2 + s * x + c * y:.9f}")
    csv.write_text("\n".join(rows) + "\n", encoding="utf-8")
    page.set_input_files("#synth-csv", str(csv))
    page.wait_for_selector("#tab-synthesis[data-target='36']")
    before = int(page.evaluate("Number(document.body.dataset.sceneCount)"))
    page.click("#synth-ellipse")
    page.wait_for_selector("#tab-synthesis[data-s1]")
    _settle(page, before)
    save("synthesis")

    # the builder: a four-bar with a coupler plate drawn from an empty canvas, then the sphere
    _tab(page, "library")
    _example(page, "crank-rocker")
    page.click("[data-testid=build]")
    page.wait_for_selector("[data-testid=build-tools]:not([hidden])")
    page.click("[data-testid=new-plane]")
    page.wait_for_function("document.body.dataset.busy !== '1'")
    _draw(page, "ground", [[0, 0], [4, 0]])
    _draw(page, "link", [[0, 0], [1, 1.5], [4.5, 3], [4, 0]])
    page.keyboard.press("Escape")
    _draw(page, "plate", [[1, 1.5], [4.5, 3], [3.2, 4.4]])
    page.keyboard.press("Enter")
    page.wait_for_function("document.body.dataset.busy !== '1'")
    _draw(page, "driver", [[0, 0], [1, 1.5]])
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    page.wait_for_timeout(400)
    save("builder")

    page.click("[data-testid=new-sphere]")
    page.wait_for_function("document.body.dataset.busy !== '1'")
    disc = page.evaluate("lw.view().disc")
    box = page.locator("#drawing").bounding_box()

    def on_sphere(u: float, v: float) -> tuple[float, float]:
        return box["x"] + disc["cx"] + u * disc["r"], box["y"] + disc["cy"] - v * disc["r"]

    for tool, points in (
        ("ground", [(-0.35, -0.15), (0.35, -0.15)]),
        ("link", [(-0.35, -0.15), (-0.3, 0.15), (0.2, 0.35), (0.35, -0.15)]),
        ("driver", [(-0.35, -0.15), (-0.3, 0.15)]),
    ):
        page.click(f"[data-testid=tool-{tool}]")
        for u, v in points:
            page.mouse.click(*on_sphere(u, v))
            page.wait_for_function("document.body.dataset.busy !== '1'")
        page.keyboard.press("Escape")
    page.wait_for_function("lw.sketchReport() && lw.sketchReport().status === 'ok'")
    page.wait_for_timeout(400)
    save("builder-sphere")
    return written


def _draw(page: Page, tool: str, points: list[list[float]]) -> None:
    """Click the builder's tool, then each model point in turn."""
    page.click(f"[data-testid=tool-{tool}]")
    box = page.locator("#drawing").bounding_box()
    for p in points:
        sx, sy = page.evaluate(f"lw.toScreen({list(map(float, p))})")
        page.mouse.click(box["x"] + sx, box["y"] + sy)
        page.wait_for_function("document.body.dataset.busy !== '1'")


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    chromium = chromium_path()
    if chromium is None:
        print("Debian's chromium is not installed (apt-get install chromium)", file=sys.stderr)
        return 2
    with LocalServer(tempfile.mkdtemp()) as url, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        for path in shoot(page, url + "/"):
            print(f"wrote {path}")
        browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

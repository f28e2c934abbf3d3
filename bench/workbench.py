"""Workbench latency: from a parameter change to the redrawn curve, on loopback (issue 9).

Run as ``python bench/workbench.py`` (``make bench`` runs it too). A real server (uvicorn, as
``linkwright serve`` starts it) runs in this process's thread; the case is a four-bar at 360
samples whose crank length changes at every request, so nothing can be served from a cache.

Measured in the same run, each as p50 and p95 over ``--repeat`` changes:

* ``scene()`` in process: the computation alone (the floor of every figure below);
* ``GET /api/health`` over HTTP: the round trip of an empty request (the transport's floor);
* ``POST /api/scene`` over HTTP: computation, JSON and transport;
* **in the browser** (Debian's chromium, headless, driven by Playwright): a number typed into
  the crank field until the page has drawn the new curve, timed inside the page with
  ``performance.now()`` from the input event to the end of the page's redraw of the drawing,
  the fields and every plot (the canvases are composited on the next display frame). This is
  the figure the issue's target (p95 under 50 ms) is for.

The ratios print how much of each figure the computation is.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

from linkwright.io import document_to_dict, load_example
from linkwright.server.local import CHROMIUM_ARGS, LocalServer, chromium_path
from linkwright.server.scene import scene

TARGET_P95_MS = 50.0


def _percentiles(ms: list[float]) -> tuple[float, float]:
    a = np.asarray(ms)
    return float(np.percentile(a, 50)), float(np.percentile(a, 95))


def _document(crank: float) -> dict:
    doc = document_to_dict(load_example("crank-rocker"))
    doc["mechanism"]["crank"] = crank
    return doc


def _cranks(n: int) -> list[float]:
    # Crank-rockers all: the crank stays the shortest link and Grashof holds.
    return [float(c) for c in np.linspace(0.8, 1.2, n)]


def _time(fn, repeat: int) -> list[float]:
    out = []
    for i in range(repeat):
        t = time.perf_counter()
        fn(i)
        out.append(1e3 * (time.perf_counter() - t))
    return out


def _browser(url: str, repeat: int) -> list[float] | str:
    path = chromium_path()
    if path is None:
        return "skipped: Debian's chromium is not installed"
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return "skipped: playwright is not installed"
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=path, args=CHROMIUM_ARGS, headless=True)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        page.wait_for_function("() => Number(document.body.dataset.sceneCount || 0) >= 1")
        field = page.locator('[data-path="mechanism.crank"]')
        field.wait_for()
        ms: list[float] = []
        for crank in _cranks(repeat):
            # Timed inside the page: from the input event to the frame after the scene's draw.
            took = page.evaluate(
                """async (value) => {
                    const field = document.querySelector('[data-path="mechanism.crank"]');
                    const before = Number(document.body.dataset.sceneCount);
                    const t0 = performance.now();
                    const drawn = new Promise((resolve) => {
                        lw.on("scene", () => {
                            if (Number(document.body.dataset.sceneCount) > before) {
                                resolve(performance.now());
                            }
                        });
                    });
                    field.value = String(value);
                    field.dispatchEvent(new Event('input', {bubbles: true}));
                    return (await drawn) - t0;
                }""",
                crank,
            )
            ms.append(float(took))
        browser.close()
    return ms


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=200, help="changes timed per case")
    args = parser.parse_args(argv)
    n = args.repeat
    cranks = _cranks(n)
    docs = [_document(c) for c in cranks]
    print(
        f"# workbench latency: four-bar, 360 samples, {n} changes per case; "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}"
    )
    scene(docs[0], samples=360)  # warm: imports, first-time compilation
    compute = _time(lambda i: scene(docs[i], samples=360), n)
    with tempfile.TemporaryDirectory() as tmp, LocalServer(Path(tmp)) as url:
        with httpx.Client(base_url=url, timeout=30) as client:
            client.post("/api/scene", json={"document": docs[0], "samples": 360})
            health = _time(lambda i: client.get("/api/health"), n)
            http = _time(
                lambda i: client.post(
                    "/api/scene", json={"document": docs[i], "samples": 360}
                ).raise_for_status(),
                n,
            )
        browser = _browser(url, n)
    rows = [
        ("scene() in process", compute),
        ("GET /api/health (HTTP floor)", health),
        ("POST /api/scene over HTTP", http),
    ]
    c50, _ = _percentiles(compute)
    print(f"{'case':<44} {'p50 ms':>8} {'p95 ms':>8} {'compute share':>14}")
    for name, ms in rows:
        p50, p95 = _percentiles(ms)
        print(f"{name:<44} {p50:8.2f} {p95:8.2f} {c50 / p50:13.0%}")
    if isinstance(browser, str):
        print(f"{'change → redrawn curve in the browser':<44} {browser}")
        return 0
    p50, p95 = _percentiles(browser)
    verdict = "met" if p95 < TARGET_P95_MS else "NOT met"
    print(f"{'change → redrawn curve in the browser':<44} {p50:8.2f} {p95:8.2f} {c50 / p50:13.0%}")
    print(f"target: p95 under {TARGET_P95_MS:.0f} ms in the browser: {verdict}")
    print(f"(median over {n}; mean {statistics.fmean(browser):.2f} ms, max {max(browser):.2f} ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

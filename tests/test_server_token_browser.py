"""The token of a workbench served beyond loopback, in a real browser (issue 20).

``linkwright serve --host 0.0.0.0`` is started as a user would; Debian's chromium opens the
address it printed. The page's first load sets the token as a cookie and drops it from the
address bar, and from then on every request the page makes (its scripts, the family menu, a
scene, a library save) is answered: none is refused for want of the token. A page opened
without the token gets nothing but the 403 that says where the token is.
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from linkwright.server.local import CHROMIUM_ARGS, chromium_path

playwright_sync = pytest.importorskip("playwright.sync_api")


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[int, str]]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen(
        [sys.executable, "-m", "linkwright", "serve", "--host", "0.0.0.0", "--port", str(port),
         "--data-dir", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        stdin=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        match = re.search(r"/\?token=(\S+)", line)
        assert match, line
        for _ in range(200):
            try:
                if httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.05)
        yield port, match[1]
    finally:
        proc.terminate()
        proc.communicate(timeout=30)


def test_the_page_opened_at_its_printed_address_works(served: tuple[int, str]) -> None:
    port, token = served
    path = chromium_path()
    if path is None:
        if os.environ.get("CI") == "true":
            pytest.fail("Debian's chromium is not installed; CI must run the browser tests")
        pytest.skip("Debian's chromium is not installed (apt-get install chromium)")
    base = f"http://127.0.0.1:{port}"
    with playwright_sync.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=path, args=CHROMIUM_ARGS, headless=True)
        try:
            context = browser.new_context()
            page = context.new_page()
            page.set_default_timeout(15_000)
            refused: list[str] = []
            page.on(
                "response",
                lambda r: refused.append(f"{r.status} {r.url}") if r.status >= 400 else None,
            )
            page.goto(f"{base}/?token={token}")
            assert page.url == f"{base}/"
            # The family menu is filled from the API, and the first scene is drawn.
            page.wait_for_function("document.querySelectorAll('#family-select option').length > 3")
            saved = page.evaluate(
                """async () => {
                    const doc = await (await fetch('/api/examples/crank-rocker')).json();
                    const r = await fetch('/api/library', {method: 'POST',
                        headers: {'Content-Type': 'application/json'},
                        body: JSON.stringify({name: 'from the page', document: doc})});
                    return r.status;
                }"""
            )
            assert saved == 200
            assert refused == [], refused
            # Another browser, without the token: refused, and told where the token is.
            stranger = browser.new_context().new_page()
            answer = stranger.goto(f"{base}/")
            assert answer is not None and answer.status == 403
            assert "token" in stranger.content()
        finally:
            browser.close()

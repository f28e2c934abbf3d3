"""Fixtures for the workbench's browser tests: a real server on loopback and Debian's chromium.

The server runs uvicorn in a thread of the test process (one per xdist worker) on a free port,
with its own data directory; the browser is Debian's ``chromium`` driven by Playwright through
``executable_path`` (Playwright's own browser downloads are not used). Without chromium the
tests are skipped with the reason, except under ``CI=true``, where that is a failure: CI must
run them.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

from linkwright.server.local import CHROMIUM_ARGS, LocalServer, chromium_path

playwright_sync = pytest.importorskip("playwright.sync_api")

# The synthesis panel builds its atlas on first use: a small one keeps that to a second.
os.environ.setdefault("LINKWRIGHT_WORKBENCH_ATLAS_COUNT", "1500")


@pytest.fixture(scope="session")
def server_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The address of a workbench served for this test session, with an empty data directory."""
    with LocalServer(tmp_path_factory.mktemp("workbench-data")) as url:
        yield url


# Module scope, not session: Playwright's sync API runs an event loop in this thread while it
# is open, and tests of other modules that call asyncio.run() on the same pytest-xdist worker
# must not find one running.
@pytest.fixture(scope="module")
def browser() -> Iterator[object]:
    path = chromium_path()
    if path is None:
        message = "Debian's chromium is not installed (apt-get install chromium)"
        if os.environ.get("CI") == "true":
            pytest.fail(message + "; CI must run the browser tests")
        pytest.skip(message)
    with playwright_sync.sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, args=CHROMIUM_ARGS, headless=True)
        yield b
        b.close()


@pytest.fixture()
def page(browser: object, server_url: str) -> Iterator[object]:
    """A fresh 1400×900 page on the workbench; page errors fail the test."""
    context = browser.new_context(viewport={"width": 1400, "height": 900}, accept_downloads=True)
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda exc: errors.append(str(exc)))
    pg.set_default_timeout(15_000)
    yield pg
    context.close()
    assert not errors, f"the page raised: {errors}"

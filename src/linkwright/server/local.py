"""The workbench on this machine, for its tests, benchmark and screenshots: a server in a thread
on a free loopback port, and the flags Debian's chromium needs to run headless here."""

from __future__ import annotations

import os
import shutil
import socket
import threading
import time
from pathlib import Path
from types import TracebackType

__all__ = ["CHROMIUM_ARGS", "LocalServer", "chromium_path"]

CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    # Without these chromium keeps trying to reach Google's hosts, which a closed network refuses.
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
"""Flags for a headless chromium started as root on a machine without a network."""


def chromium_path() -> str | None:
    """Debian's chromium, or the browser named by ``LINKWRIGHT_CHROMIUM``; None if neither."""
    named = os.environ.get("LINKWRIGHT_CHROMIUM")
    if named:
        return named
    return shutil.which("chromium") or shutil.which("chromium-browser")


class LocalServer:
    """``with LocalServer(data_dir) as url:`` serves the workbench on a free loopback port in a
    thread of this process, and stops it on leaving. It listens on 127.0.0.1 only and answers
    only the loopback names (:data:`~linkwright.server.LOOPBACK_HOSTS`), as ``linkwright serve``
    does by default, and is configured by the same :func:`~linkwright.server.runner.make_server`
    (every bound on connections, time and work). ``log_level="error"`` leaves out the line per
    failed request (for a benchmark that fails requests on purpose)."""

    def __init__(self, data_dir: str | Path, *, log_level: str = "warning") -> None:
        from linkwright.server import LOOPBACK_HOSTS, create_app
        from linkwright.server.runner import make_server

        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = int(s.getsockname()[1])
        self.app = create_app(data_dir, allowed_hosts=LOOPBACK_HOSTS)
        self.server = make_server(self.app, "127.0.0.1", self.port, log_level=log_level)
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    def __enter__(self) -> str:
        self.thread.start()
        deadline = time.monotonic() + 30
        while not self.server.started:
            if time.monotonic() > deadline or not self.thread.is_alive():
                raise RuntimeError("the workbench server did not start")
            time.sleep(0.02)
        return f"http://127.0.0.1:{self.port}"

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.server.should_exit = True
        self.thread.join(10)

"""`linkwright serve` listens on loopback unless told otherwise, and says so when told.

A real process is started, as a user would, and its listening socket is read back from the
kernel (``/proc/net/tcp``): the address is 127.0.0.1, so no other machine can reach it.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

pytestmark = pytest.mark.skipif(
    not Path("/proc/net/tcp").exists(), reason="reads the kernel's socket table (Linux)"
)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _listening(port: int) -> list[str]:
    """The IPv4 addresses listening on ``port``, from the kernel's table."""
    found = []
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        address, hex_port = local.split(":")
        if int(hex_port, 16) == port and state == "0A":  # 0A: LISTEN
            found.append(socket.inet_ntoa(bytes.fromhex(address)[::-1]))
    return found


def _serve(tmp_path: Path, *extra: str) -> tuple[subprocess.Popen, int, str]:
    port = _free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "linkwright",
            "serve",
            "--port",
            str(port),
            "--data-dir",
            str(tmp_path),
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    line = proc.stdout.readline()
    for _ in range(200):
        if _listening(port):
            break
        time.sleep(0.05)
    return proc, port, line


def test_serve_listens_on_loopback_by_default(tmp_path):
    proc, port, line = _serve(tmp_path)
    try:
        assert line.startswith(f"linkwright workbench on http://127.0.0.1:{port}")
        assert _listening(port) == ["127.0.0.1"]
        assert httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=10).status_code == 200
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    assert "warning" not in err


def test_serve_on_every_interface_warns_that_it_has_no_login(tmp_path):
    proc, port, _ = _serve(tmp_path, "--host", "0.0.0.0")
    try:
        assert _listening(port) == ["0.0.0.0"]
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    assert "warning: listening on 0.0.0.0" in err and "no login" in err

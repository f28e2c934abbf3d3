"""`linkwright serve` listens on loopback unless told otherwise, and says so when told.

A real process is started, as a user would, and its listening socket is read back from the
kernel (``/proc/net/tcp``): the address is 127.0.0.1, so no other machine can reach it.
Beyond loopback it asks for the token it prints (as Jupyter does): the page's first load at
the printed address sets it as a cookie, and a request without it is refused 403, so neither
another machine nor a page a browser opens (DNS rebinding) can use the library; ``--no-token``
drops it, with a warning. On another loopback address it answers its own address. A failed
request leaves one line on its standard error.
"""

from __future__ import annotations

import os
import re
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


def test_serve_on_every_interface_asks_for_its_token(tmp_path):
    proc, port, line = _serve(tmp_path, "--host", "0.0.0.0")
    try:
        assert _listening(port) == ["0.0.0.0"]
        match = re.match(rf"linkwright workbench on http://0\.0\.0\.0:{port}/\?token=(\S+)  ", line)
        assert match, line
        token = match[1]
        assert len(token) >= 32
        base = f"http://127.0.0.1:{port}"
        # Without the token: nothing but health, whatever the Host (DNS rebinding included).
        for path in ("/", "/api/library", "/api/families"):
            for host in (None, "evil.example"):
                headers = {"host": host} if host else {}
                r = httpx.get(base + path, headers=headers, timeout=10)
                assert r.status_code == 403 and "token" in r.json()["error"], (path, host)
        assert httpx.get(f"{base}/?token=wrong", timeout=10).status_code == 403
        assert httpx.get(f"{base}/api/health", timeout=10).status_code == 200
        # The printed address: the page sets the cookie and drops the token from the address.
        with httpx.Client(base_url=base, timeout=10, follow_redirects=True) as browser:
            page = browser.get(f"/?token={token}")
            assert page.status_code == 200 and "<html" in page.text.lower()
            assert str(page.url) == f"{base}/"
            assert browser.get("/api/library").status_code == 200
            saved = browser.post("/api/library", json={"name": "a", "document": _doc()})
            assert saved.status_code == 200, saved.text
        # A script may send it instead.
        bearer = {"authorization": f"Bearer {token}"}
        assert httpx.get(f"{base}/api/library", headers=bearer, timeout=10).status_code == 200
        assert httpx.get(f"{base}/api/library?token={token}", timeout=10).status_code == 200
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    assert "warning" not in err


def test_serve_without_a_token_needs_saying_so_and_warns(tmp_path):
    proc, port, line = _serve(tmp_path, "--host", "0.0.0.0", "--no-token")
    try:
        assert "?token=" not in line
        assert httpx.get(f"http://127.0.0.1:{port}/api/library", timeout=10).status_code == 200
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    assert "warning: listening on 0.0.0.0 without a token" in err
    assert "any web page a browser there opens" in err


def test_serve_on_another_loopback_address_answers_it(tmp_path):
    proc, port, line = _serve(tmp_path, "--host", "127.0.0.2")
    try:
        assert line.startswith(f"linkwright workbench on http://127.0.0.2:{port}  ")
        for _ in range(100):
            if "127.0.0.2" in _listening(port):
                break
            time.sleep(0.05)
        r = httpx.get(f"http://127.0.0.2:{port}/api/health", timeout=10)
        assert r.status_code == 200, r.text
        r = httpx.get(f"http://127.0.0.2:{port}/api/health", headers={"host": "evil.example"})
        assert r.status_code == 421
    finally:
        proc.terminate()
        proc.communicate(timeout=30)


def test_serve_logs_one_line_per_failed_request(tmp_path):
    proc, port, _ = _serve(tmp_path)
    try:
        base = f"http://127.0.0.1:{port}"
        assert httpx.get(f"{base}/api/health", timeout=10).status_code == 200
        r = httpx.post(f"{base}/api/scene", json={"document": {}}, timeout=10)
        assert r.status_code == 422
        missing = httpx.get(f"{base}/api/library/7", timeout=10)
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=30)
    lines = [x for x in err.splitlines() if "linkwright: " in x]
    assert len(lines) == 2, err
    assert lines[0].endswith(f"linkwright: POST /api/scene 422: {r.json()['error']}")
    assert lines[1].endswith(f"linkwright: GET /api/library/7 404: {missing.json()['error']}")


def _doc() -> dict:
    from linkwright.io import document_to_dict, load_example

    return document_to_dict(load_example("crank-rocker"))


def test_serve_refuses_a_file_that_is_not_a_library_in_one_line(tmp_path):
    (tmp_path / "library.sqlite3").write_text("my notes, not a database\n" * 100)
    done = subprocess.run(
        [sys.executable, "-m", "linkwright", "serve", "--port", str(_free_port()),
         "--data-dir", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: --data-dir: library: ")
    assert "is not a linkwright library" in done.stderr and done.stderr.count("\n") == 1

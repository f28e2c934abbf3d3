"""Internal errors are 500s, never blamed on the request, and every failed request leaves one log
line (issues 20 and 27).

An internal ``ValueError`` used to be answered 422 as if the request were bad, and a
``KeyError`` 404; now only the deliberate user errors (``USER_ERRORS``, ``NOT_FOUND``) are 4xx
and anything else is a 500 with one line naming the type, and its traceback in the log. The
server's own state answers for itself (``StatusError``).
"""

from __future__ import annotations

import logging
import os
import subprocess
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from linkwright.io import document_to_dict, load_example
from linkwright.server import create_app, scene, tools
from linkwright.server.errors import StatusError

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def client(tmp_path: Path) -> TestClient:
    return TestClient(create_app(tmp_path))


def _doc() -> dict:
    return document_to_dict(load_example("crank-rocker"))


def _one_line(response, status: int) -> str:
    assert response.status_code == status, response.text
    body = response.json()
    assert set(body) == {"error"}, body
    assert "\n" not in body["error"] and "Traceback" not in body["error"]
    return body["error"]


BUGS = [
    ValueError("x must be finite"),
    KeyError("joints"),
    IndexError("list index out of range"),
    RuntimeError("oops"),
]


@pytest.mark.parametrize("bug", BUGS, ids=[type(b).__name__ for b in BUGS])
def test_an_internal_error_is_a_500_with_its_traceback_in_the_log(
    client: TestClient,
    monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
    bug: Exception,
) -> None:
    def broken(*args, **kwargs):
        raise bug

    monkeypatch.setattr(scene, "scene", broken)
    with caplog.at_level(logging.WARNING, logger="linkwright.server"):
        r = client.post("/api/scene", json={"document": _doc(), "samples": 24})
    message = _one_line(r, 500)
    assert message == f"internal error ({type(bug).__name__}); the server log has the details"
    # The internal text is not sent to the client; the log has it, with the traceback.
    assert str(bug.args[0]) not in message
    traced = [rec for rec in caplog.records if rec.exc_info is not None]
    assert len(traced) == 1 and traced[0].exc_info[1] is bug
    assert "POST /api/scene" in traced[0].getMessage()


def test_user_errors_stay_4xx(client: TestClient) -> None:
    bad = _doc()
    bad["mechanism"]["crank"] = -1
    assert "crank" in _one_line(client.post("/api/scene", json={"document": bad}), 422)
    # A plain LookupError raised on purpose, with its message, is a 404.
    assert "no family" in _one_line(client.get("/api/families/nothing/default"), 404)
    assert "no bundled example" in _one_line(client.get("/api/examples/nothing"), 404)
    # A non-finite input angle is the request's fault, stopped before the scene sees it.
    r = client.post(
        "/api/scene",
        content=b'{"document": {}, "at": Infinity}',
        headers={"content-type": "application/json"},
    )
    assert _one_line(r, 422) == "at: must be a finite number, got inf"


def test_a_tool_error_is_the_request_s_fault(client: TestClient, monkeypatch) -> None:
    def refuse(*args, **kwargs):
        raise tools.StudyError("pivot: not a pivot")

    monkeypatch.setattr(scene, "scene", refuse)
    assert _one_line(client.post("/api/scene", json={"document": _doc()}), 422) == (
        "pivot: not a pivot"
    )


def test_the_server_s_own_state_answers_for_itself(client: TestClient, monkeypatch) -> None:
    class Full(StatusError):
        status = 507

    def full(*args, **kwargs):
        raise Full("library: disk full")

    monkeypatch.setattr(scene, "scene", full)
    assert _one_line(client.post("/api/scene", json={"document": _doc()}), 507) == (
        "library: disk full"
    )


def test_every_failed_request_leaves_one_log_line(
    client: TestClient, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.INFO, logger="linkwright.server"):
        client.get("/api/health")
        scene_error = client.post("/api/scene", json={"document": {"format": "linkwright/1"}})
        missing = client.get("/api/library/99")
    lines = [rec.getMessage() for rec in caplog.records if rec.name == "linkwright.server"]
    assert lines == [
        f"POST /api/scene 422: {_one_line(scene_error, 422)}",
        f"GET /api/library/99 404: {_one_line(missing, 404)}",
    ], lines


def test_make_run_takes_a_port_and_a_host() -> None:
    def command(*args: str) -> str:
        # Run under `make test`, make would print its Entering/Leaving lines: not wanted here.
        env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MAKELEVEL", "MFLAGS")}
        out = subprocess.run(
            ["make", "--no-print-directory", "-n", "run", *args],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
            env=env,
        ).stdout
        return next(line for line in out.splitlines() if "linkwright serve" in line).strip()

    assert command().endswith("linkwright serve --host 127.0.0.1 --port 8000")
    assert command("PORT=8001").endswith("linkwright serve --host 127.0.0.1 --port 8001")
    assert command("PORT=8002", "HOST=0.0.0.0").endswith(
        "linkwright serve --host 0.0.0.0 --port 8002"
    )

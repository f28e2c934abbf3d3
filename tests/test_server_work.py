"""Bounded work: a few requests computed at once, a bounded queue, 503 beyond it, and health
never behind work (issue 20).

Scenes are made to block (the route's computation waits on an event the test holds), so the
slots and the queue fill exactly as the test says, whatever the machine's speed. Before the
work queue, 45 such requests took every thread of the pool and ``/api/health`` waited behind
them (16 to 30 s in the issue); now health answers at once, the requests past the queue are
refused at once with ``Retry-After``, and those queued are all served once the work ends.
"""

from __future__ import annotations

import asyncio
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import httpx
import pytest
from starlette.types import Receive, Scope, Send

from linkwright.io import document_to_dict, load_example
from linkwright.server import limits, scene
from linkwright.server.local import LocalServer
from linkwright.server.work import RETRY_AFTER_S, WorkQueue

SLOTS, QUEUE = limits.WORK_SLOTS.value, limits.WORK_QUEUE.value


def test_the_bounds_are_in_the_limits_table() -> None:
    table = limits.as_json()
    for name in (
        "work_slots",
        "work_queue",
        "work_wait",
        "connections",
        "header_seconds",
        "body_seconds",
    ):
        assert table[name]["value"] > 0 and len(table[name]["why"]) > 40, name


@pytest.fixture
def blocked_scenes(monkeypatch: pytest.MonkeyPatch):
    """Scenes that wait until the test releases them; yields (release, started count)."""
    release = threading.Event()
    started = []
    real = scene.scene

    def waiting(*args, **kwargs):
        started.append(1)
        assert release.wait(60), "the test never released the scenes"
        return real(*args, **kwargs)

    monkeypatch.setattr(scene, "scene", waiting)
    yield release, started
    release.set()


def test_limit_work_slots(tmp_path: Path, blocked_scenes) -> None:
    """Exactly the slots compute, the queue waits, one more is refused at once, and health
    never waits behind work."""
    release, started = blocked_scenes
    body = {"document": document_to_dict(load_example("crank-rocker")), "samples": 24}
    sent = SLOTS + QUEUE + 9  # 45: the count
    with LocalServer(tmp_path, log_level="error") as url, ThreadPoolExecutor(sent) as pool:

        def post() -> httpx.Response:
            return httpx.post(f"{url}/api/scene", json=body, timeout=60)

        futures = [pool.submit(post) for _ in range(sent)]
        # The refused ones come back at once, the others wait.
        deadline = time.monotonic() + 30
        while sum(f.done() for f in futures) < sent - SLOTS - QUEUE:
            assert time.monotonic() < deadline, "the requests past the queue were not refused"
            time.sleep(0.05)
        refused = [f.result() for f in futures if f.done()]
        assert len(refused) == sent - SLOTS - QUEUE
        for r in refused:
            assert r.status_code == 503
            assert r.headers["retry-after"] == str(RETRY_AFTER_S)
            message = r.json()["error"]
            assert message.startswith("busy:") and "\n" not in message
        assert len(started) == SLOTS  # exactly the slots compute; the rest wait
        # Every slot and the queue are full: health, limits and the page still answer. A frozen
        # server took 16-35 s; on 2 cores shared with the slots' work and another test worker a
        # free route took up to 1.5 s (two fresh runs of a15bd14), so 5 s tells the two apart.
        with httpx.Client(base_url=url, timeout=30) as http:
            for path in ("/api/health", "/api/limits", "/", "/api/families"):
                began = time.perf_counter()
                assert http.get(path).status_code == 200, path
                assert time.perf_counter() - began < 5.0, path
        release.set()
        answers = [f.result() for f in futures if f.result().status_code != 503]
    assert len(answers) == SLOTS + QUEUE
    assert all(r.status_code == 200 for r in answers)


# --------------------------------------------------------------------------------------------
# The queue itself, around a stand-in application
# --------------------------------------------------------------------------------------------


class _Held:
    """An ASGI app whose requests each wait for the test to let them answer."""

    def __init__(self) -> None:
        self.entered: list[str] = []
        self.gate = asyncio.Event()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        self.entered.append(scope["path"])
        await self.gate.wait()
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"{}"})


async def _call(app, path: str, method: str = "POST") -> int:
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://t") as http:
        return (await http.request(method, path)).status_code


def test_limit_work_queue() -> None:
    async def run() -> None:
        held = _Held()
        queue = WorkQueue(held, slots=2, queue=2, wait_s=30)
        calls = [asyncio.create_task(_call(queue, f"/api/w{i}")) for i in range(6)]
        await asyncio.sleep(0.1)
        # Two compute, two wait (the queue's value), the two past it are refused at once.
        assert held.entered == ["/api/w0", "/api/w1"]
        assert queue.running == 2 and queue.waiting == 2
        assert [c.result() for c in calls if c.done()] == [503, 503]
        # Reads are not work: they pass at once.
        read = asyncio.create_task(_call(queue, "/api/families", "GET"))
        await asyncio.sleep(0.05)
        assert held.entered[-1] == "/api/families"
        held.gate.set()
        assert [await c for c in calls[:4]] == [200, 200, 200, 200]
        assert await read == 200
        assert queue.running == 0 and queue.waiting == 0

    asyncio.run(run())


def test_limit_work_wait() -> None:
    async def run() -> None:
        held = _Held()
        queue = WorkQueue(held, slots=1, queue=4, wait_s=0.3)
        first = asyncio.create_task(_call(queue, "/api/w0"))
        await asyncio.sleep(0.05)
        began = time.perf_counter()
        # A request that has waited wait_s for a slot gives up: 503.
        assert await _call(queue, "/api/w1") == 503
        assert 0.25 < time.perf_counter() - began < 5
        assert queue.waiting == 0
        held.gate.set()
        assert await first == 200
        assert queue.running == 0

    asyncio.run(run())


def test_a_slot_passes_to_the_first_waiter_in_order() -> None:
    async def run() -> None:
        held = _Held()
        queue = WorkQueue(held, slots=1, queue=5, wait_s=30)
        calls = []
        for i in range(4):
            calls.append(asyncio.create_task(_call(queue, f"/api/w{i}")))
            await asyncio.sleep(0.02)
        assert held.entered == ["/api/w0"]
        # A waiter that gives up (its client left) does not keep the slot it is handed.
        calls[1].cancel()
        await asyncio.sleep(0.02)
        held.gate.set()
        assert [await calls[i] for i in (0, 2, 3)] == [200, 200, 200]
        assert held.entered == ["/api/w0", "/api/w2", "/api/w3"]
        assert queue.running == 0 and queue.waiting == 0

    asyncio.run(run())

"""Bounded concurrency for the workbench's work: a few requests computed at once, a bounded
queue behind them, and a 503 beyond it.

Every request that may compute (any ``POST``, ``PUT``, ``PATCH`` or ``DELETE`` under ``/api``:
scenes, drags, studies, matches, exports, library writes) takes one of
:data:`~linkwright.server.limits.WORK_SLOTS` slots before it reaches its route, and gives it back
when its answer starts (the work is done by then; a client slow to read its answer must not
hold a slot). When every slot is taken it waits in a queue of at most
:data:`~linkwright.server.limits.WORK_QUEUE` requests, for at most
:data:`~linkwright.server.limits.WORK_WAIT` seconds; a request finding the queue full, or
waiting longer, is answered at once: 503, ``Retry-After``, and one line saying how busy the
server is.

Reads (``GET``, ``HEAD``, ``OPTIONS``: the page, its static files, health, limits, the family
and example menus, library lists and loads) never queue here, and ``/api/health`` and
``/api/limits`` are answered in the event loop itself, so they are never behind work: a thread
pool filled by computations cannot delay them.

The slots bound the work's *concurrency*; what one request may cost, and how long it may run,
is checked by the routes themselves before they start (the cost estimate), so a slot is held
for a bounded time.
"""

from __future__ import annotations

import asyncio
import threading
from collections import deque
from typing import ClassVar

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from linkwright.server.errors import StatusError
from linkwright.server.guard import error_response
from linkwright.server.limits import WORK_QUEUE, WORK_SLOTS, WORK_WAIT

__all__ = ["RETRY_AFTER_S", "Busy", "WorkQueue", "is_work"]

RETRY_AFTER_S = 2
"""What a 503's ``Retry-After`` asks a client to wait, in seconds."""

_READS = frozenset({"GET", "HEAD", "OPTIONS"})


def is_work(scope: Scope) -> bool:
    """Whether a request takes a work slot: any method but a read, under ``/api``."""
    return scope.get("method") not in _READS and str(scope.get("path", "")).startswith("/api/")


class Busy(StatusError):
    """Every work slot is taken and the queue is full (or the wait was too long): 503."""

    status: ClassVar[int] = 503
    headers: ClassVar[dict[str, str] | None] = {"Retry-After": str(RETRY_AFTER_S)}


class WorkQueue:
    """ASGI middleware holding the slots and the queue (module docstring).

    The counts are shared by every event loop the app runs on (a test client may run one per
    request), so they are guarded by a lock and a waiter is woken on its own loop.
    """

    def __init__(
        self,
        app: ASGIApp,
        slots: int = WORK_SLOTS.value,
        queue: int = WORK_QUEUE.value,
        wait_s: float = WORK_WAIT.value,
    ) -> None:
        self.app = app
        self.slots = slots
        self.queue = queue
        self.wait_s = wait_s
        self.running = 0
        self._lock = threading.Lock()
        self._waiters: deque[asyncio.Future[None]] = deque()

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or not is_work(scope):
            await self.app(scope, receive, send)
            return
        try:
            await self._acquire()
        except Busy as exc:
            await error_response(exc.status, str(exc), exc.headers)(scope, receive, send)
            return
        held = True

        async def release_on_answer(message: Message) -> None:
            nonlocal held
            if held and message["type"] == "http.response.start":
                held = False
                self._release()
            await send(message)

        try:
            await self.app(scope, receive, release_on_answer)
        finally:
            if held:
                self._release()

    def _busy(self, why: str) -> Busy:
        return Busy(
            f"busy: {why} ({self.slots} requests are computed at once, at most {self.queue} "
            f"wait); try again in a few seconds"
        )

    async def _acquire(self) -> None:
        loop = asyncio.get_running_loop()
        with self._lock:
            if self.running < self.slots and not self._waiters:
                self.running += 1
                return
            if len(self._waiters) >= self.queue:
                raise self._busy("the queue of waiting requests is full")
            waiter: asyncio.Future[None] = loop.create_future()
            self._waiters.append(waiter)
        try:
            await asyncio.wait_for(asyncio.shield(waiter), self.wait_s)
        except TimeoutError:
            with self._lock:
                if waiter not in self._waiters:
                    # Handed a slot just as the wait ran out: take it after all.
                    return
                self._waiters.remove(waiter)
            raise self._busy(f"waited {self.wait_s:g} s for a free slot") from None
        except asyncio.CancelledError:
            with self._lock:
                handed = waiter not in self._waiters
                if not handed:
                    self._waiters.remove(waiter)
            if handed:
                # The slot was handed over already: pass it on.
                self._release()
            raise

    def _release(self) -> None:
        with self._lock:
            while self._waiters:
                waiter = self._waiters.popleft()
                if waiter.done():
                    continue
                try:
                    # The slot passes straight to the waiter (running stays the same).
                    waiter.get_loop().call_soon_threadsafe(_wake, waiter)
                except RuntimeError:  # its loop is closed: nobody is waiting there any more
                    continue
                return
            self.running -= 1

    @property
    def waiting(self) -> int:
        with self._lock:
            return len(self._waiters)


def _wake(waiter: asyncio.Future[None]) -> None:
    if not waiter.done():
        waiter.set_result(None)

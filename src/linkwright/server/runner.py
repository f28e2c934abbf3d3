"""The one place the workbench's web server is configured: ``linkwright serve``, the tests, the
benchmarks and the screenshots all start it through :func:`make_server`.

uvicorn alone bounds neither the connections it keeps open nor the time a client may take to
send its request: 1,100 half-sent connections once exhausted the process's file descriptors
(slowloris). :class:`GuardedH11` is uvicorn's h11 protocol with two additions, from the limits
table (:mod:`linkwright.server.limits`):

- a request's line and headers must arrive within
  :data:`~linkwright.server.limits.HEADER_SECONDS` of the connection opening (or of its
  previous answer); else the connection is closed, with a 408 if anything had been sent;
- :data:`~linkwright.server.limits.CONNECTIONS` bounds the open connections: a new one past
  the bound closes the slowest of those in the middle of a request (fewest bytes a second),
  so slow clients cannot lock others out. Connections being answered, idle after an answer
  (a browser's, kept alive), or opened in the last quarter second and silent so far (a real
  client's request may be on its way, unread by a busy server) are not closed, so the count
  may pass the bound, up to twice it; past that, with nothing to close, a new connection is
  refused: 503 with ``Retry-After``.

The body's own deadline (:data:`~linkwright.server.limits.BODY_SECONDS`) is kept by the
application's guard (:mod:`linkwright.server.guard`), and how much work runs at once by
:mod:`linkwright.server.work`.
"""

from __future__ import annotations

import asyncio
import copy
import resource
import time
from typing import Any

import h11
import orjson
import uvicorn
from uvicorn.config import LOGGING_CONFIG
from uvicorn.protocols.http.h11_impl import H11Protocol

from linkwright.server.limits import CONNECTIONS, HEADER_SECONDS
from linkwright.server.work import RETRY_AFTER_S

__all__ = ["HEADER_BYTES", "KEEP_ALIVE_S", "GuardedH11", "log_config", "make_server"]

KEEP_ALIVE_S = 5
"""How long an idle connection is kept after an answer (uvicorn's default)."""

HEADER_BYTES = 16 * 1024
"""Largest request line and headers (h11's default, stated here so it stays one): a longer one
is answered 400."""

_SHUTDOWN_S = 5
_OTHER_FILES = 64  # files the process holds besides its connections (libraries, the database)
_NEW_S = 0.25
"""A new connection's time to send its first bytes before it is judged (seconds). Until then
it may take the count of connections past the bound, up to twice the bound."""


def _raw_answer(status: int, reason: str, message: str, extra: str = "") -> bytes:
    body = orjson.dumps({"error": message})
    head = (
        f"HTTP/1.1 {status} {reason}\r\ncontent-type: application/json\r\n"
        f"content-length: {len(body)}\r\n{extra}connection: close\r\n\r\n"
    )
    return head.encode("ascii") + body


_TOO_MANY = _raw_answer(
    503,
    "Service Unavailable",
    "busy: every connection the workbench keeps open is in use; try again in a few seconds",
    f"retry-after: {RETRY_AFTER_S}\r\n",
)
_TOO_SLOW = _raw_answer(
    408,
    "Request Timeout",
    f"request: the request line and headers did not arrive within {HEADER_SECONDS.value} s",
)


class GuardedH11(H11Protocol):
    """uvicorn's h11 protocol with a header deadline and a bound on open connections (module
    docstring)."""

    max_connections = CONNECTIONS.value
    header_seconds: float = HEADER_SECONDS.value

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._waiting_since = time.monotonic()
        self._deadline: asyncio.TimerHandle | None = None
        self._bytes = 0  # received since the deadline was set

    def _open(self) -> bool:
        return self.transport is not None and not self.transport.is_closing()

    def _rank(self) -> tuple[float, float] | None:
        """Where this connection stands in the order of closing to make room (least first), or
        None if it may not be closed.

        Only a connection in the middle of a request (or not begun) may be closed, and the
        slowest goes first: bytes received since its request began, per second (over at least
        a second, so that the first packet of a new connection does not make it look fast),
        the longest waiting first among equals. A slow client (slowloris) sends a few bytes a
        second; a real one sends a whole request at once, or a body at the network's speed.
        Never closed here: a connection being answered, one idle after an answer (a browser's
        kept-alive connection, which it will use again; the keep-alive timeout closes it), and
        one opened less than :data:`_NEW_S` ago that has sent nothing yet (its request may be
        on its way, unread by a busy server).
        """
        cycle = self.cycle
        if not self._open() or not (cycle is None or cycle.response_complete or cycle.more_body):
            return None
        age = time.monotonic() - self._waiting_since
        if self._bytes == 0 and (cycle is not None or age < _NEW_S):
            return None
        return self._bytes / max(age, 1.0), -age

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        super().connection_made(transport)  # type: ignore[arg-type]
        # Connections being closed are still in the set until their loss is seen: not counted.
        live = sum(1 for c in self.connections if not isinstance(c, GuardedH11) or c._open())
        # Past the bound, a slow half-sent connection makes room; past twice it, with none to
        # close, the new one is refused.
        if (
            live > self.max_connections
            and not self._make_room()
            and live > 2 * self.max_connections
        ):
            transport.write(_TOO_MANY)  # type: ignore[attr-defined]
            transport.close()
            return
        self._arm()

    def _make_room(self) -> bool:
        """Close the first connection in the order of :meth:`_rank`; False if none may be
        closed."""
        first: tuple[tuple[float, float], GuardedH11] | None = None
        for other in self.connections:
            if other is self or not isinstance(other, GuardedH11):
                continue
            rank = other._rank()
            if rank is not None and (first is None or rank < first[0]):
                first = (rank, other)
        if first is None:
            return False
        first[1]._drop(answer=False)
        return True

    def _arm(self) -> None:
        """Start the header deadline for the next request on this connection."""
        if self._deadline is not None:
            self._deadline.cancel()
        self._waiting_since = time.monotonic()
        self._bytes = 0
        cycle = self.cycle
        self._deadline = self.loop.call_later(self.header_seconds, self._expire, cycle)

    def _expire(self, cycle: object) -> None:
        self._deadline = None
        # A new request began since the deadline was set: its headers came in time.
        if self.cycle is not cycle or self.transport is None or self.transport.is_closing():
            return
        self._drop(answer=self._bytes > 0)

    def _drop(self, answer: bool) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        if self.transport.is_closing():
            return
        # A 408 only where the client is between requests and has begun a new one (not while
        # it is still sending an old body, nor to a silent idle connection).
        if answer and self.conn.their_state is h11.IDLE:
            self.transport.write(_TOO_SLOW)
        self.transport.close()

    def data_received(self, data: bytes) -> None:
        self._bytes += len(data)
        super().data_received(data)

    def on_response_complete(self) -> None:
        # Armed before the parent may start a pipelined request, so that the deadline sees it.
        if not self.transport.is_closing():
            self._arm()
        super().on_response_complete()

    def connection_lost(self, exc: Exception | None) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        super().connection_lost(exc)


def log_config(level: str = "warning") -> dict[str, Any]:
    """uvicorn's logging configuration plus the workbench's own log (a line per failed
    request, :mod:`linkwright.server.errors`), both to standard error."""
    config = copy.deepcopy(LOGGING_CONFIG)
    config["formatters"]["linkwright"] = {"format": "%(asctime)s linkwright: %(message)s"}
    config["handlers"]["linkwright"] = {
        "formatter": "linkwright",
        "class": "logging.StreamHandler",
        "stream": "ext://sys.stderr",
    }
    config["loggers"]["linkwright.server"] = {
        "handlers": ["linkwright"],
        "level": "ERROR" if level in ("error", "critical") else "WARNING",
        # Kept on to the root as well, so that a test's log capture sees it.
        "propagate": True,
    }
    return config


def connection_bound(most: int = CONNECTIONS.value) -> int:
    """``most`` connections, fewer where this process may not open files for twice as many
    (and the rest it needs); the soft limit on open files is raised toward the hard one first,
    as far as that needs."""
    want = 2 * most + _OTHER_FILES
    try:
        soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        if soft != resource.RLIM_INFINITY and soft < want:
            raised = want if hard == resource.RLIM_INFINITY else min(want, hard)
            resource.setrlimit(resource.RLIMIT_NOFILE, (raised, hard))
            soft = raised
    except (OSError, ValueError):
        return most
    if soft == resource.RLIM_INFINITY:
        return most
    return max(8, min(most, (soft - _OTHER_FILES) // 2))


def make_server(app: Any, host: str, port: int, *, log_level: str = "warning") -> uvicorn.Server:
    """A uvicorn server for the workbench application ``app`` on ``host:port``, with every
    bound of the module docstring. ``log_level`` "error" leaves out the failed-request lines
    (a benchmark that fails requests on purpose)."""
    bound = connection_bound(GuardedH11.max_connections)
    protocol = GuardedH11
    if bound != GuardedH11.max_connections:
        # A subclass, not GuardedH11 itself changed: the lower bound is this server's alone.
        class BoundedH11(GuardedH11):
            max_connections = bound

        protocol = BoundedH11
    config = uvicorn.Config(
        app,
        host=host,
        port=port,
        http=protocol,
        ws="none",
        log_level=log_level,
        log_config=log_config(log_level),
        access_log=False,
        timeout_keep_alive=KEEP_ALIVE_S,
        timeout_graceful_shutdown=_SHUTDOWN_S,
        h11_max_incomplete_event_size=HEADER_BYTES,
    )
    return uvicorn.Server(config)

"""What a failed request answers, and the one log line it leaves.

Three kinds of failure, told apart on purpose (never by the exception's base class alone):

- the request's fault (a bad document, a value over a limit, a joint that cannot go where it
  was dragged): 4xx, the message naming the field; the exception types are listed by the app
  (:data:`linkwright.server.app.USER_ERRORS`), not inferred from ``ValueError``;
- a known condition of the server's own state (:class:`StatusError`: a damaged, full or
  read-only library, a busy server): its own status and a message saying what to do;
- anything else is a bug: 500 with one line naming the exception's type, and the traceback
  in the server's log.

:class:`RequestLog` is the application's outermost middleware: it writes one log line for each
answer of status 400 or more (method, path, status, the error line) and turns any exception
that reached it into that 500, so that no client ever sees a traceback or a plain-text error.
"""

from __future__ import annotations

import logging
from typing import ClassVar

import orjson
from starlette.types import ASGIApp, Message, Receive, Scope, Send

__all__ = ["LOG", "RequestLog", "StatusError", "internal_message"]

LOG = logging.getLogger("linkwright.server")
"""The workbench's log: a line per failed request, a traceback per internal error."""

# An error body is one short JSON line; more than this is not an error body of ours.
_MOST_LOGGED_BYTES = 4096


class StatusError(Exception):
    """A failure that is neither the request's fault nor a bug: the server's own state (its
    library, its load) stops it. Answered with :attr:`status` and the message, which says what
    to do."""

    status: ClassVar[int] = 500
    headers: ClassVar[dict[str, str] | None] = None


def internal_message(exc: BaseException) -> str:
    """The one line a client gets for a bug: the type only (the message may quote internals)."""
    return f"internal error ({type(exc).__name__}); the server log has the details"


def _line(text: str, most: int = 300) -> str:
    text = " ".join(text.split())
    return text if len(text) <= most else text[: most - 1] + "…"


class RequestLog:
    """ASGI middleware: one log line per answer of status ≥ 400, and a JSON 500 (logged with
    its traceback) for any exception the application lets out."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        status = 0
        body = bytearray()

        async def watch(message: Message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = int(message["status"])
            elif message["type"] == "http.response.body" and status >= 400:
                if len(body) < _MOST_LOGGED_BYTES:
                    body.extend(message.get("body", b"")[: _MOST_LOGGED_BYTES - len(body)])
                if not message.get("more_body", False):
                    _log_failure(scope, status, bytes(body))
            await send(message)

        try:
            await self.app(scope, receive, watch)
        except Exception as exc:
            LOG.error("%s %s: internal error", scope.get("method", "?"), _path(scope), exc_info=exc)
            if status:
                # The answer had begun: nothing can be said any more but to end it.
                raise
            payload = orjson.dumps({"error": internal_message(exc)})
            await watch(
                {
                    "type": "http.response.start",
                    "status": 500,
                    "headers": [
                        (b"content-type", b"application/json"),
                        (b"content-length", str(len(payload)).encode()),
                    ],
                }
            )
            await watch({"type": "http.response.body", "body": payload})


def _path(scope: Scope) -> str:
    return _line(str(scope.get("path", "")), 120)


def _log_failure(scope: Scope, status: int, body: bytes) -> None:
    try:
        error = orjson.loads(body).get("error")
    except (orjson.JSONDecodeError, AttributeError):
        error = None
    shown = _line(error) if isinstance(error, str) else f"({len(body)} bytes, not an error body)"
    level = logging.ERROR if status >= 500 else logging.WARNING
    LOG.log(level, "%s %s %d: %s", scope.get("method", "?"), _path(scope), status, shown)

"""What the workbench checks before a request reaches a route, and the names it gives files.

:class:`Guard` is the application's outermost ASGI middleware. It answers, itself and in the
API's ``{"error": "..."}`` form:

- 413 for a body over :data:`~linkwright.server.limits.BODY_BYTES`: at once where the
  ``Content-Length`` says so, else counted as a chunked body (or a multipart upload) arrives;
- 408 for a body that has not arrived whole within
  :data:`~linkwright.server.limits.BODY_SECONDS` of its headers (and the connection is closed);
- 422 for a JSON body nested deeper than :data:`~linkwright.server.limits.JSON_DEPTH`,
  measured on the bytes, in one linear pass (:mod:`linkwright.server.scan`; a large body in a
  thread of its own, so the event loop answers others meanwhile), before any parser recurses
  through them;
- 403 for a state-changing request sent by another site's page (its ``Origin`` is not the
  address the workbench is reached at): the workbench has no login, so a page elsewhere must
  not be able to write to its library (cross-site request forgery);
- 421 for a ``Host`` outside ``allowed_hosts`` where the app was given some (a loopback
  server gives its loopback names and its own address: another name resolving to 127.0.0.1 is
  DNS rebinding);
- 403 for a request without the server's token, where it has one (a server reachable beyond
  loopback): the token comes as a cookie, which the page's first load sets from the printed
  address's ``?token=`` (answering 303 to the same page without it), or as ``?token=`` or
  ``Authorization: Bearer`` from a script. ``/api/health`` needs none.

A client that leaves before its body is whole gets nothing, and its half body is never handed
on as a whole one.

:func:`attachment` builds a ``Content-Disposition`` value from any name (a title, a library
entry) without letting a path or a header break through, and :func:`shown_filename` the one
line an uploaded file's name is shown as.
"""

from __future__ import annotations

import asyncio
import hmac
import re
import unicodedata
import weakref
from collections.abc import Iterable
from typing import Any
from urllib.parse import parse_qsl, quote, urlsplit

import anyio
from starlette.datastructures import Headers
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from linkwright.server.limits import BODY_BYTES, BODY_SECONDS, JSON_DEPTH, json_depth

__all__ = [
    "LOOPBACK_HOSTS",
    "Guard",
    "attachment",
    "error_response",
    "shown_filename",
    "token_cookie",
]

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
"""The names a browser on this machine reaches a loopback-bound workbench by."""

_SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})


def _host_name(netloc: str) -> str:
    """The host of ``host[:port]`` (brackets of an IPv6 literal dropped), lower-cased."""
    try:
        return (urlsplit(f"//{netloc}").hostname or "").lower()
    except ValueError:
        return ""


class Guard:
    """ASGI middleware: body size and nesting, cross-site writes, and (optionally) the Host
    header, checked before the application sees a request (module docstring)."""

    body_seconds: float = BODY_SECONDS.value
    """How long a request's body may take to arrive, from its headers."""

    def __init__(
        self, app: ASGIApp, allowed_hosts: Iterable[str] | None = None, token: str | None = None
    ) -> None:
        self.app = app
        self.allowed = None if allowed_hosts is None else {h.lower() for h in allowed_hosts}
        self.token = token

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = Headers(scope=scope)
        refusal: Response | None = self._refuse_headers(scope, headers)
        if refusal is None and self.token is not None:
            refusal = _check_token(scope, headers, self.token)
        if refusal is not None:
            await refusal(scope, receive, send)
            return
        body, last, refusal = await self._read(receive, self.body_seconds)
        if refusal is not None:
            await refusal(scope, receive, send)
            return
        if last is not None and last["type"] == "http.disconnect":
            # The client left before its body was whole: there is nobody to answer, and half a
            # body must never be taken for a whole one.
            return
        if body and self._json(headers):
            brackets = body.count(b"[") + body.count(b"{")
            if brackets > JSON_DEPTH.value and (depth := await _depth(body)) > JSON_DEPTH.value:
                message = f"body: JSON nested {depth:,} levels, at most {JSON_DEPTH.value} allowed"
                await error_response(422, message)(scope, receive, send)
                return
        await self.app(scope, _replay(body, last, receive), send)

    def _refuse_headers(self, scope: Scope, headers: Headers) -> JSONResponse | None:
        host = headers.get("host", "")
        if self.allowed is not None and _host_name(host) not in self.allowed:
            return error_response(
                421,
                f"host: this workbench answers to {', '.join(sorted(self.allowed))} only, "
                f"not {_short(host)!r}",
            )
        origin = headers.get("origin")
        if scope["method"] not in _SAFE_METHODS and origin is not None:
            parts = urlsplit(origin) if origin != "null" else None
            if parts is None or parts.netloc.lower() != host.lower():
                return error_response(
                    403,
                    f"origin: a page at {_short(origin)!r} may not change this workbench "
                    "(cross-site requests are refused)",
                )
        length = headers.get("content-length")
        if length is not None:
            if not (length.isascii() and length.isdigit()):
                return error_response(
                    400, f"content-length: not a number of bytes: {_short(length)!r}"
                )
            if int(length) > BODY_BYTES.value:
                return error_response(
                    413,
                    f"request body: {int(length):,} bytes, over the {BODY_BYTES.value:,} allowed",
                )
        return None

    @staticmethod
    async def _read(
        receive: Receive, seconds: float
    ) -> tuple[bytes, Message | None, JSONResponse | None]:
        """The whole body (counted as it arrives), the message that ended it if it was not a
        body part (a disconnect), and the refusal if it was too large or too slow."""
        try:
            async with asyncio.timeout(seconds):
                return await Guard._read_all(receive)
        except TimeoutError:
            return (
                b"",
                None,
                error_response(
                    408,
                    f"request body: not received within {seconds:g} s",
                    {"Connection": "close"},
                ),
            )

    @staticmethod
    async def _read_all(receive: Receive) -> tuple[bytes, Message | None, JSONResponse | None]:
        parts: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                return b"".join(parts), message, None
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > BODY_BYTES.value:
                return (
                    b"",
                    None,
                    error_response(
                        413,
                        f"request body: over the {BODY_BYTES.value:,} bytes allowed "
                        f"({size:,} received so far)",
                    ),
                )
            parts.append(chunk)
            if not message.get("more_body", False):
                return b"".join(parts), None, None

    @staticmethod
    def _json(headers: Headers) -> bool:
        # A body without a Content-Type is JSON to some FastAPI versions, so it is measured too.
        kind = headers.get("content-type", "").split(";")[0].strip().lower()
        return not kind or kind == "application/json" or kind.endswith("+json")


# --------------------------------------------------------------------------------------------
# The token of a workbench served beyond loopback
# --------------------------------------------------------------------------------------------

_OPEN_PATHS = frozenset({"/api/health"})


def token_cookie(scope: Scope) -> str:
    """The cookie holding the token: named after the port, since a browser sends a host's
    cookies to every port of it (two workbenches on one machine must not share one)."""
    server = scope.get("server") or ("", None)
    return f"linkwright-token-{server[1] or 0}"


def _check_token(scope: Scope, headers: Headers, token: str) -> Response | None:
    """None if the request carries ``token`` (the cookie, ``?token=`` or ``Authorization:
    Bearer``); else a 403, or for the page opened at its printed address, a redirect that sets
    the cookie and drops the token from the address bar."""
    if scope["path"] in _OPEN_PATHS:
        return None
    name = token_cookie(scope)
    if _same(_cookies(headers.get("cookie", "")).get(name), token):
        return None
    scheme, _, credentials = headers.get("authorization", "").partition(" ")
    if scheme.lower() == "bearer" and _same(credentials.strip(), token):
        return None
    query = dict(parse_qsl(scope.get("query_string", b"").decode("latin-1")))
    if _same(query.get("token"), token):
        if scope["method"] in ("GET", "HEAD") and not scope["path"].startswith("/api/"):
            cookie = f"{name}={token}; Path=/; HttpOnly; SameSite=Strict"
            return Response(
                status_code=303, headers={"Location": scope["path"], "Set-Cookie": cookie}
            )
        return None
    return error_response(
        403,
        "token: this workbench is served beyond this machine and needs its token; open the "
        "address `linkwright serve` printed (it ends in ?token=...)",
    )


def _same(given: str | None, token: str) -> bool:
    # Compared in constant time, so that the answer's timing does not spell the token out.
    return given is not None and hmac.compare_digest(given.encode(), token.encode())


def _cookies(header: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for part in header.split(";"):
        key, sep, value = part.strip().partition("=")
        if sep:
            out.setdefault(key, value)
    return out


# Bodies up to this size are measured in the event loop (well under a millisecond); a larger
# one in a thread of its own, so that the event loop answers others meanwhile. The threads are
# few and apart from the pool the routes use, so bodies never wait behind work, nor the
# reverse.
_INLINE_BYTES = 65_536
_SCAN_THREADS = 2
_limiters: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, anyio.CapacityLimiter] = (
    weakref.WeakKeyDictionary()
)


async def _depth(body: bytes) -> int:
    if len(body) <= _INLINE_BYTES:
        return json_depth(body)
    # One limiter per event loop (a test client may run one per request).
    loop = asyncio.get_running_loop()
    limiter = _limiters.get(loop)
    if limiter is None:
        limiter = _limiters[loop] = anyio.CapacityLimiter(_SCAN_THREADS)
    return await anyio.to_thread.run_sync(json_depth, body, limiter=limiter)


def _replay(body: bytes, last: Message | None, receive: Receive) -> Receive:
    """A ``receive`` that hands the application the body already read, then what follows."""
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            if last is not None and not body:
                return last
            return {"type": "http.request", "body": body, "more_body": False}
        if last is not None:
            return last
        return await receive()

    return replay


def error_response(
    status: int, message: str, headers: dict[str, str] | None = None
) -> JSONResponse:
    """The API's error answer: ``{"error": "..."}`` on one line, whatever a message quoted
    from the request held."""
    line = " ".join(message.splitlines()) or f"HTTP {status}"
    return JSONResponse({"error": line}, status_code=status, headers=headers)


def _short(text: str, most: int = 80) -> str:
    return text if len(text) <= most else text[: most - 1] + "…"


# --------------------------------------------------------------------------------------------
# File names
# --------------------------------------------------------------------------------------------

_UNSAFE_ASCII = re.compile(r"[^A-Za-z0-9._ -]+")
_REFUSED_CATEGORIES = ("Cc", "Cf", "Cs", "Zl", "Zp")


def attachment(name: str, suffix: str, fallback: str = "mechanism") -> str:
    """A ``Content-Disposition`` value naming a file ``name.suffix`` (RFC 6266): an ASCII
    ``filename`` of letters, digits, ``.``, ``_``, ``-`` and spaces (no slash, no quote, no
    leading dot), and the UTF-8 name in ``filename*``, percent-encoded, with path separators
    and control characters made ``_``. Each part is at most 100 characters before the suffix.

    >>> print(attachment("../../etc/passwd", "toml"))
    attachment; filename="etc_passwd.toml"; filename*=UTF-8''_.._etc_passwd.toml
    >>> print(attachment("Kurbel ä", "svg"))
    attachment; filename="Kurbel.svg"; filename*=UTF-8''Kurbel%20%C3%A4.svg
    """
    ascii_name = _UNSAFE_ASCII.sub("_", name).strip(" ._")[:100] or fallback
    utf8_name = "".join(
        "_" if ch in "/\\" or unicodedata.category(ch) in _REFUSED_CATEGORIES else ch for ch in name
    )
    utf8_name = utf8_name.strip(" .")[:100] or fallback
    return (
        f'attachment; filename="{ascii_name}.{suffix}"; '
        f"filename*=UTF-8''{quote(f'{utf8_name}.{suffix}', safe='')}"
    )


def shown_filename(filename: Any) -> str:
    """An uploaded file's name as one short line for messages and default names: the last
    path component only (after ``/`` or ``\\``), controls and line breaks dropped, at most 100
    characters.

    >>> shown_filename("../../etc/passwd"), shown_filename("C:\\\\x\\\\a\\nb.toml")
    ('passwd', 'ab.toml')
    """
    text = str(filename or "")
    text = re.split(r"[/\\]", text)[-1]
    text = "".join(ch for ch in text if unicodedata.category(ch) not in _REFUSED_CATEGORIES)
    text = text.strip()
    return _short(text, 100) or "file"

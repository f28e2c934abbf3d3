"""The workbench's web application: a JSON API and the page that uses it.

:func:`create_app` builds a FastAPI application over one data directory (the library's SQLite
file and the built-in atlases live there). Every failure a user can cause answers JSON
``{"error": "..."}`` with one line naming the field and the problem: one of
:data:`USER_ERRORS` (a bad document, an unreachable drag, points that are not a curve, a value
over a limit) is 422, an unknown library entry, example or path is 404, a name clash is 409; a
request body over :data:`MAX_BODY_BYTES` is 413; a write sent by another site's page is 403
(:mod:`linkwright.server.guard`). The server's own state answers for itself (a damaged, full or
read-only library: 500, 507, 409; a busy server: 503 with ``Retry-After``). Any other exception
is a bug, never blamed on the request: 500 with one line naming its type, and the traceback in
the log (:mod:`linkwright.server.errors`). Nothing answers a traceback. Every bound on a request
is in :mod:`linkwright.server.limits` and served at ``GET /api/limits``.
"""

from __future__ import annotations

from collections.abc import Iterable
from importlib import resources
from pathlib import Path
from typing import Annotated, Any

from fastapi import FastAPI, Request
from fastapi import Path as PathParam
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import compile_path

from linkwright import __version__
from linkwright.analysis.conic import ConicError
from linkwright.analysis.spherical import InvalidHingeRatio, NotASphericalFourBar
from linkwright.atlas.atlas import AtlasError
from linkwright.atlas.build import AtlasBuildError
from linkwright.atlas.families import AtlasFamilyError
from linkwright.atlas.query import AtlasQueryError
from linkwright.atlas.store import AtlasStoreError
from linkwright.curves.fourier import CurveError
from linkwright.engine.circuits import NoPeriod
from linkwright.engine.cost import CostError
from linkwright.geometry.sphere import ProjectionError
from linkwright.io import DocumentError, document_to_dict, list_examples, load_example
from linkwright.io.exports import ExportError
from linkwright.mechanisms.base import InvalidMechanism
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.plot.animation import AnimationError
from linkwright.plot.diagrams import DiagramError
from linkwright.plot.sphere import SpherePlotError
from linkwright.plot.view import PlotError
from linkwright.server import library, limits, scene, tools
from linkwright.server.errors import RequestLog, StatusError
from linkwright.server.guard import LOOPBACK_HOSTS, Guard
from linkwright.server.guard import error_response as _error
from linkwright.server.schema import DocumentBody, document_examples, examples
from linkwright.server.work import WorkQueue
from linkwright.synthesis.ellipse import EllipseError

__all__ = ["LOOPBACK_HOSTS", "MAX_BODY_BYTES", "USER_ERRORS", "NotFound", "create_app"]

MAX_BODY_BYTES = limits.BODY_BYTES.value
"""Largest request body accepted (:data:`linkwright.server.limits.BODY_BYTES`)."""


class NotFound(LookupError):
    """No such thing where the request looked (an example, a family): 404."""


USER_ERRORS: tuple[type[ValueError], ...] = (
    # The request's own values: a document, a limit (its estimated cost too), a library name,
    # a tool's inputs.
    DocumentError,
    limits.LimitError,
    CostError,
    library.LibraryError,
    scene.DragError,
    tools.ToolsError,
    EllipseError,
    ExportError,
    # What the library refuses about the linkage a document describes (it cannot be built,
    # traced, drawn or analysed as asked): the document's fault, named by the message.
    InvalidMechanism,
    NoConstructionPlan,
    NoPeriod,
    DiagramError,
    PlotError,
    SpherePlotError,
    AnimationError,
    ProjectionError,
    CurveError,
    ConicError,
    NotASphericalFourBar,
    InvalidHingeRatio,
    AtlasError,
    AtlasBuildError,
    AtlasFamilyError,
    AtlasQueryError,
    AtlasStoreError,
)
"""The errors that are the request's fault, answered 422 (a :class:`~linkwright.server.library.
LibraryConflict` 409). Any other ``ValueError`` is a bug: 500, with its traceback in the log."""

NOT_FOUND: tuple[type[LookupError], ...] = (NotFound, library.LibraryNotFound)
"""The lookups that are the request's fault (404); a ``KeyError`` or ``IndexError`` is a bug.
A plain ``LookupError`` (raised on purpose, with a message) counts as one of these too."""


class ErrorBody(BaseModel):
    """Every error the workbench answers: one line naming the field and the problem."""

    error: str


class Health(BaseModel):
    ok: bool
    version: str


class LimitEntry(BaseModel):
    """One row of ``GET /api/limits`` (:class:`linkwright.server.limits.Limit`)."""

    value: int
    least: int | None
    unit: str
    applies: str
    why: str


_DOCS = document_examples()


class SceneRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples(*({"document": d, "samples": 48} for d in _DOCS))
    )

    document: DocumentBody
    samples: int = Field(360, ge=limits.SAMPLES.least, le=limits.SAMPLES.value, strict=True)
    at: float | None = Field(None, allow_inf_nan=False)
    diagrams: bool = True
    overlays: bool = False
    summary: bool = False


class DragRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples(
            {"document": _DOCS[0], "joint": "P", "to": [1.0, 3.0], "at": 30.0}
        )
    )

    document: DocumentBody
    joint: str = Field(min_length=1, max_length=limits.TEXT.value)
    to: list[float] = Field(min_length=2, max_length=3)
    at: float = 0.0


_ERRORS: dict[int | str, dict[str, Any]] = {
    "4XX": {
        "model": ErrorBody,
        "description": "The request cannot be served as sent: 400 unreadable, 403 sent by "
        "another site's page (or without the token of a server reachable beyond loopback), "
        "404 no such entry, 408 body too slow, 409 name taken or library read-only, 413 body "
        "too large, 421 wrong host, 422 invalid (the message names the field; GET /api/limits "
        "lists every limit).",
    },
    "5XX": {
        "model": ErrorBody,
        "description": "The server cannot serve it now: 500 an internal error (the server log "
        "has the details) or a damaged library (the message says what to do), 503 busy (every "
        "work slot taken and the queue full: try again after Retry-After seconds), 507 disk "
        "full.",
    },
}


def _static_dir() -> Path:
    return Path(str(resources.files("linkwright.server") / "static"))


def _shown(value: Any, most: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= most else text[: most - 1] + "…"


def _describe(err: dict[str, Any]) -> str:
    """One pydantic error as "field: problem", limits phrased as the API's other messages."""
    loc = [str(p) for p in err.get("loc", ()) if p != "body"]
    kind, ctx, got = err.get("type", ""), err.get("ctx") or {}, err.get("input")
    if kind == "json_invalid":
        where = f" (at character {loc[-1]})" if loc else ""
        return f"body: invalid JSON: {ctx.get('error', 'cannot be read')}{where}"
    where = ".".join(loc) or "body"
    if not loc and kind in ("model_attributes_type", "dict_type", "model_type"):
        return "body: expected a JSON object (sent as Content-Type: application/json)"
    if kind == "missing":
        return f"{where}: missing required field"
    if kind == "less_than_equal":
        return f"{where}: must be at most {ctx['le']}, got {_shown(got)}"
    if kind == "greater_than_equal":
        return f"{where}: must be at least {ctx['ge']}, got {_shown(got)}"
    if kind == "finite_number":
        return f"{where}: must be a finite number, got {_shown(got)}"
    if kind in ("too_long", "string_too_long"):
        unit = "characters" if kind == "string_too_long" else "items"
        size = len(got) if isinstance(got, str | list) else ctx.get("actual_length")
        shown = f"{size:,}" if isinstance(size, int) else "too many"
        return f"{where}: {shown} {unit}, at most {ctx['max_length']:,} allowed"
    return f"{where}: {err.get('msg', 'invalid')}"


def _validation_message(exc: RequestValidationError) -> str:
    return "; ".join(_describe(err) for err in exc.errors()[:3])


def _allow(request: Request, exc: StarletteHTTPException) -> str:
    """The methods a 405's path takes. Starlette names those of the first route matching the
    path only; FastAPI makes one route per method, so the schema's paths are asked instead."""
    app = request.app
    table = getattr(app.state, "methods_by_path", None)
    if table is None:
        table = [
            (compile_path(path)[0], {m.upper() for m in operations})
            for path, operations in app.openapi().get("paths", {}).items()
        ]
        app.state.methods_by_path = table
    methods: set[str] = set()
    for pattern, allowed in table:
        if pattern.match(request.url.path):
            methods |= allowed
    if methods:
        return ", ".join(sorted(methods))
    return next((v for k, v in (exc.headers or {}).items() if k.lower() == "allow"), "")


def _http_message(request: Request, exc: StarletteHTTPException) -> str:
    path = _shown(request.url.path, 120)
    if exc.status_code == 404:
        return f"path: nothing at {path}"
    if exc.status_code == 405:
        allowed = _allow(request, exc)
        return f"method: {request.method} is not allowed at {path} (allowed: {allowed or 'none'})"
    if exc.status_code == 400 and str(exc.detail).startswith("There was an error parsing"):
        return "body: cannot be read as JSON (malformed, or a number too long to read)"
    return f"request: {exc.detail}"


def create_app(
    data_dir: str | Path | None = None,
    *,
    allowed_hosts: Iterable[str] | None = None,
    token: str | None = None,
) -> FastAPI:
    """The workbench application over ``data_dir`` (default: :func:`default_data_dir`).

    Parameters
    ----------
    data_dir : where the library and the atlas live; nothing else is read or written (the
        page and the examples come from the package), and nothing a client sends is used as a
        path.
    allowed_hosts : the only ``Host`` names answered (others get 421); a server bound to the
        loopback address passes :data:`LOOPBACK_HOSTS` (and the address itself), which
        defeats DNS rebinding. None answers any.
    token : if given, every request but ``/api/health`` must carry it (a cookie the page's
        first load sets from ``?token=``, the query, or ``Authorization: Bearer``); else 403.
        A server reachable from other machines needs one (:mod:`linkwright.server.guard`).

    Examples
    --------
    >>> import tempfile
    >>> from fastapi.testclient import TestClient
    >>> client = TestClient(create_app(tempfile.mkdtemp()))
    >>> client.get("/api/health").json()["ok"]
    True
    >>> client.post("/api/scene", json={"document": {"mechanism": {"family": "fourbar"}}}).json()
    {'error': 'document: format: missing required field (expected "linkwright/1")'}
    >>> client.post("/api/scene", json={"document": {}, "samples": 5000}).json()
    {'error': 'samples: must be at most 4096, got 5000'}
    """
    root = Path(data_dir) if data_dir is not None else default_data_dir()
    root.mkdir(parents=True, exist_ok=True)
    app = FastAPI(title="linkwright workbench", version=__version__, responses=_ERRORS)
    app.state.data_dir = root
    app.state.library = library.Library(root / "library.sqlite3")
    # Outermost last: the log sees every answer, the guard every request before any work
    # slot is taken (a slow or refused body never holds one).
    app.add_middleware(WorkQueue)
    app.add_middleware(Guard, allowed_hosts=allowed_hosts, token=token)
    app.add_middleware(RequestLog)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        allowed = _allow(request, exc) if exc.status_code == 405 else ""
        headers = {"Allow": allowed} if allowed else None
        return _error(exc.status_code, _http_message(request, exc), headers)

    @app.exception_handler(RequestValidationError)
    async def _invalid(_: Request, exc: RequestValidationError) -> JSONResponse:
        return _error(422, _validation_message(exc))

    # A handler that raises hands the exception on to RequestLog: a 500, logged with its
    # traceback.
    @app.exception_handler(ValueError)
    async def _value(_: Request, exc: ValueError) -> JSONResponse:
        if not isinstance(exc, USER_ERRORS):
            raise exc
        return _error(409 if isinstance(exc, library.LibraryConflict) else 422, str(exc))

    @app.exception_handler(LookupError)
    async def _missing(_: Request, exc: LookupError) -> JSONResponse:
        if not (isinstance(exc, NOT_FOUND) or type(exc) is LookupError):
            raise exc
        message = exc.args[0] if exc.args and isinstance(exc.args[0], str) else str(exc)
        return _error(404, message)

    @app.exception_handler(StatusError)
    async def _status(_: Request, exc: StatusError) -> JSONResponse:
        return _error(exc.status, str(exc), exc.headers)

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(_static_dir() / "index.html", media_type="text/html")

    # Health and limits are answered in the event loop (async, no thread): a thread pool
    # full of work must never delay them.
    @app.get("/api/health", response_model=Health)
    async def health() -> dict[str, Any]:
        return {"ok": True, "version": __version__}

    @app.get("/api/limits", response_model=dict[str, LimitEntry])
    async def limits_route() -> dict[str, dict[str, Any]]:
        """Every limit on a request: its value (and least value), unit, the fields it applies
        to and why it has that value."""
        return limits.as_json()

    @app.get("/api/families")
    def families() -> list[dict[str, Any]]:
        return scene.families()

    @app.get("/api/families/{family}/default")
    def family_default(
        family: Annotated[str, PathParam(examples=list(scene.FAMILY_EXAMPLES))],
    ) -> dict[str, Any]:
        return scene.family_document(family)

    @app.get("/api/examples")
    def examples() -> list[dict[str, Any]]:
        return scene.examples()

    @app.get("/api/examples/{name}")
    def example(
        name: Annotated[str, PathParam(examples=["crank-rocker", "jansen-leg.toml"])],
    ) -> dict[str, Any]:
        # Only a bundled example's name is ever read, never a path made from the request.
        if name.removesuffix(".toml") not in list_examples():
            raise NotFound(f"example: no bundled example named {_shown(name)}")
        return document_to_dict(load_example(name))

    # A scene is ~10^4 numbers: orjson writes it in well under a millisecond, where FastAPI's
    # encoder and json.dumps take ten (the redraw's latency budget is 50 ms).
    @app.post(
        "/api/scene",
        response_class=Response,
        responses={200: {"content": {"application/json": {}}, "description": "The scene."}},
    )
    def scene_route(body: SceneRequest) -> Response:
        result = scene.scene(
            body.document,
            samples=body.samples,
            at=body.at,
            diagrams=body.diagrams,
            overlays=body.overlays,
            summary=body.summary,
        )
        return Response(scene.to_json(result), media_type="application/json")

    @app.post("/api/drag")
    def drag_route(body: DragRequest) -> dict[str, Any]:
        return scene.drag(body.document, body.joint, body.to, body.at)

    app.include_router(library.router, prefix="/api")
    app.include_router(tools.router, prefix="/api")
    app.mount("/static", StaticFiles(directory=_static_dir()), name="static")
    return app


def default_data_dir() -> Path:
    """Where the workbench keeps its library: the atlas's data directory (``$LINKWRIGHT_DATA``,
    else ``$XDG_DATA_HOME/linkwright``, else ``~/.local/share/linkwright``)."""
    from linkwright.atlas.atlas import data_dir

    return data_dir()

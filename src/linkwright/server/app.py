"""The workbench's web application: a JSON API and the page that uses it.

:func:`create_app` builds a FastAPI application over one data directory (the library's SQLite
file and the built-in atlases live there). Every failure a user can cause answers JSON
``{"error": "..."}`` with one line naming the field and the problem: a ``ValueError`` (a bad
document, an unreachable drag, points that are not a curve) is 422, a ``LookupError`` (an unknown
library entry or example) is 404, a name clash is 409; a request body over
:data:`MAX_BODY_BYTES` is 413. Nothing answers a traceback.
"""

from __future__ import annotations

import logging
from importlib import resources
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, Field

from linkwright import __version__
from linkwright.io import document_to_dict, list_examples, load_example
from linkwright.server import library, scene, tools

__all__ = ["MAX_BODY_BYTES", "create_app"]

MAX_BODY_BYTES = 2_000_000
"""Largest request body accepted (a drawn curve of 20,000 points fits several times over)."""

_log = logging.getLogger("linkwright.server")


class SceneRequest(BaseModel):
    document: dict[str, Any]
    samples: int = Field(360, ge=8, le=4096)
    at: float | None = None
    diagrams: bool = True


class DragRequest(BaseModel):
    document: dict[str, Any]
    joint: str = Field(min_length=1, max_length=64)
    to: list[float] = Field(min_length=2, max_length=3)
    at: float = 0.0


def _static_dir() -> Path:
    return Path(str(resources.files("linkwright.server") / "static"))


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status)


def _validation_message(exc: RequestValidationError) -> str:
    parts = []
    for err in exc.errors()[:3]:
        where = ".".join(str(p) for p in err.get("loc", ()) if p != "body") or "body"
        parts.append(f"{where}: {err.get('msg', 'invalid')}")
    return "; ".join(parts)


def create_app(data_dir: str | Path | None = None) -> FastAPI:
    """The workbench application over ``data_dir`` (default: :func:`default_data_dir`).

    Examples
    --------
    >>> import tempfile
    >>> from fastapi.testclient import TestClient
    >>> client = TestClient(create_app(tempfile.mkdtemp()))
    >>> client.get("/api/health").json()["ok"]
    True
    >>> client.post("/api/scene", json={"document": {"mechanism": {"family": "fourbar"}}}).json()
    {'error': 'document: format: missing required field (expected "linkwright/1")'}
    """
    root = Path(data_dir) if data_dir is not None else default_data_dir()
    root.mkdir(parents=True, exist_ok=True)
    app = FastAPI(title="linkwright workbench", version=__version__)
    app.state.data_dir = root
    app.state.library = library.Library(root / "library.sqlite3")

    @app.middleware("http")
    async def _limit_body(request: Request, call_next: Any) -> Any:
        length = request.headers.get("content-length")
        if length is not None and length.isdigit() and int(length) > MAX_BODY_BYTES:
            return _error(
                413, f"request body: {int(length):,} bytes, over the {MAX_BODY_BYTES:,} allowed"
            )
        return await call_next(request)

    @app.exception_handler(RequestValidationError)
    async def _invalid(_: Request, exc: RequestValidationError) -> JSONResponse:
        return _error(422, _validation_message(exc))

    @app.exception_handler(ValueError)
    async def _value(_: Request, exc: ValueError) -> JSONResponse:
        return _error(409 if isinstance(exc, library.LibraryConflict) else 422, str(exc))

    @app.exception_handler(LookupError)
    async def _missing(_: Request, exc: LookupError) -> JSONResponse:
        message = exc.args[0] if exc.args and isinstance(exc.args[0], str) else str(exc)
        return _error(404, message)

    @app.exception_handler(Exception)
    async def _unexpected(_: Request, exc: Exception) -> JSONResponse:
        _log.exception("unexpected error")
        return _error(500, f"internal error ({type(exc).__name__}); the server log has the details")

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(_static_dir() / "index.html", media_type="text/html")

    @app.get("/api/health")
    def health() -> dict[str, Any]:
        return {"ok": True, "version": __version__}

    @app.get("/api/families")
    def families() -> list[dict[str, Any]]:
        return scene.families()

    @app.get("/api/families/{family}/default")
    def family_default(family: str) -> dict[str, Any]:
        return scene.family_document(family)

    @app.get("/api/examples")
    def examples() -> list[dict[str, Any]]:
        return scene.examples()

    @app.get("/api/examples/{name}")
    def example(name: str) -> dict[str, Any]:
        if name.removesuffix(".toml") not in list_examples():
            raise LookupError(f"example: no bundled example named {name!r}")
        return document_to_dict(load_example(name))

    # A scene is ~10^4 numbers: orjson writes it in well under a millisecond, where FastAPI's
    # encoder and json.dumps take ten (the redraw's latency budget is 50 ms).
    @app.post("/api/scene")
    def scene_route(body: SceneRequest) -> Response:
        result = scene.scene(
            body.document, samples=body.samples, at=body.at, diagrams=body.diagrams
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

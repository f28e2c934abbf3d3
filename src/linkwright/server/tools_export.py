"""The workbench's exports: ``POST /export/{fmt}``, the current document as a file.

PNG, SVG, DXF, CSV, GIF, TOML or JSON (:data:`EXPORTS`), drawn in a scratch folder inside the
data directory and removed once read; the cost is checked before any drawing.

Its own room (split from :mod:`linkwright.server.tools`): one tool, the formats and files.
"""

from __future__ import annotations

import math
import re
import tempfile
import unicodedata
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, Request
from fastapi import Path as PathParam
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field

from linkwright.io import Document, export_csv, export_dxf, export_svg, save_document
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server import budget, limits
from linkwright.server.schema import DocumentBody, examples
from linkwright.server.tools_common import EXAMPLE_DOCUMENT, ToolsError, read_document

__all__ = [
    "EXPORTS",
    "GIF_DPI",
    "GIF_FPS",
    "GIF_FRAMES",
    "PNG_DPI",
    "ExportRequest",
    "export_file",
    "router",
]

router = APIRouter()

GIF_FRAMES, GIF_FPS, GIF_DPI = 48, 24, 80
PNG_DPI = 120


EXPORTS: dict[str, str] = {
    "png": "image/png",
    "svg": "image/svg+xml",
    "dxf": "image/vnd.dxf",
    "csv": "text/csv; charset=utf-8",
    "gif": "image/gif",
    "toml": "application/toml; charset=utf-8",
    "json": "application/json",
}
"""Export formats and their media types."""


class ExportRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"document": EXAMPLE_DOCUMENT, "at": 30.0, "samples": 48})
    )

    document: DocumentBody
    at: float | None = None
    samples: int = Field(360, ge=limits.SAMPLES.least, le=limits.SAMPLES.value, strict=True)


def _filename(doc: Document, fmt: str) -> str:
    """A file name from the title (letters, digits, '.', '_' and '-' only), else the family."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "-", doc.title or "")
    stem = re.sub(r"[-.]{2,}", "-", stem).strip("-._")[:80]
    return f"{stem or doc.family}.{fmt}"


def _plain(title: str | None) -> str | None:
    """A title as one line of drawable text: control characters and line breaks as spaces."""
    if title is None:
        return None
    return " ".join(
        "".join(" " if unicodedata.category(c)[0] in "CZ" else c for c in title).split()
    )


def _write(doc: Document, fmt: str, path: Path, at: float | None, samples: int) -> None:
    mech = doc.mechanism
    title = _plain(doc.title)
    if fmt == "png":
        from linkwright.plot import plot_mechanism, save_figure

        save_figure(plot_mechanism(mech, at=at, samples=samples, title=title), path,
                    dpi=PNG_DPI)  # fmt: skip
    elif fmt == "gif":
        from linkwright.plot import animate

        animate(mech, path, frames=GIF_FRAMES, fps=GIF_FPS, dpi=GIF_DPI, title=title)
    elif fmt == "svg":
        export_svg(mech, path, at=at, samples=samples, units=doc.units, title=title)
    elif fmt == "dxf":
        export_dxf(mech, path, at=at, samples=samples, units=doc.units, title=title)
    elif fmt == "csv":
        export_csv(mech, path, samples=samples)
    else:  # toml, json
        save_document(doc, path)


@router.post(
    "/export/{fmt}",
    response_class=Response,
    responses={
        200: {
            "content": {media: {} for media in dict.fromkeys(EXPORTS.values())},
            "description": "The file, as an attachment.",
        }
    },
)
def export_file(
    fmt: Annotated[str, PathParam(json_schema_extra={"enum": list(EXPORTS)})],
    body: ExportRequest,
    request: Request,
) -> Response:
    """The document as a file (attachment) at input ``at`` (degrees; default: the circuit's
    first sample). The file is drawn in a scratch folder inside the data directory (no name
    the client sends makes a path) and removed once read."""
    fmt = fmt.lower()
    if fmt not in EXPORTS:
        shown = fmt if len(fmt) <= 16 else fmt[:16] + "…"
        raise ToolsError(f"fmt: unknown export format {shown!r} (one of {', '.join(EXPORTS)})")
    doc = read_document(body.document)
    if body.at is not None and not math.isfinite(body.at):
        raise ToolsError(f"at: must be a finite input angle in degrees, got {body.at}")
    at = None if body.at is None else math.radians(body.at)
    name = _filename(doc, fmt)
    with budget.request("samples"):
        budget.check_export(
            doc.mechanism, fmt, body.samples, gif_frames=GIF_FRAMES, gif_dpi=GIF_DPI
        )
    scratch = Path(request.app.state.data_dir) / "scratch"
    scratch.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="export-", dir=scratch) as folder:
        path = Path(folder) / f"export.{fmt}"
        try:
            _write(doc, fmt, path, at, body.samples)
        except NoConstructionPlan as exc:
            raise ToolsError(f"document: cannot be drawn: {exc}") from None
        payload = path.read_bytes()
    return Response(
        payload,
        media_type=EXPORTS[fmt],
        headers={"Content-Disposition": f'attachment; filename="{name}"'},
    )

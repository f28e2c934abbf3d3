"""The workbench's atlas match: ``POST /match``, ``GET /match/status``, ``POST /match/prepare``.

A drawn closed curve is matched against the built-in four-bar atlas (:mod:`linkwright.atlas`),
optionally refined; each candidate comes placed where the curve was drawn. The atlas is built
into the app's data directory on first use (:func:`atlas_count` entries) unless a finished
four-bar atlas is already there (the CLI's built-in one is found and used).

Its own room (split from :mod:`linkwright.server.tools`): one tool, with the app's atlas it
opens or builds once.
"""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path
from typing import Any

import numpy as np
from fastapi import APIRouter, FastAPI, Request
from pydantic import BaseModel, ConfigDict, Field

from linkwright.atlas import AtlasError, build, open_atlas, query
from linkwright.atlas.atlas import Atlas
from linkwright.engine import cost
from linkwright.io import mechanism_to_dict
from linkwright.mechanisms import circuit
from linkwright.server import budget, limits
from linkwright.server.schema import examples
from linkwright.server.tools_common import (
    Array,
    Points,
    ToolsError,
    drawn_points,
    example_ring,
    json_number,
    polyline,
)

__all__ = [
    "ATLAS_COUNT",
    "ATLAS_COUNT_ENV",
    "CURVE_SAMPLES",
    "REFINE_POINTS",
    "MatchError",
    "MatchRequest",
    "atlas_count",
    "match",
    "match_prepare",
    "match_status",
    "router",
]

router = APIRouter()

ATLAS_COUNT = 20_000
"""Entries of the four-bar atlas the workbench builds on first use: it builds in seconds and
matches drawn curves well once refined (``LINKWRIGHT_WORKBENCH_ATLAS_COUNT`` or
``app.state.atlas_count`` change it)."""
ATLAS_COUNT_ENV = "LINKWRIGHT_WORKBENCH_ATLAS_COUNT"
REFINE_POINTS = int(cost.REFINE_POINTS.value)
"""Most drawn points a refined match fits (evenly spaced among them;
:data:`linkwright.engine.cost.REFINE_POINTS` gives the reason)."""
CURVE_SAMPLES = 256
"""Samples of each candidate's curve sent back for drawing."""


class MatchError(ToolsError):
    """Points that are not a curve to match, or an atlas that cannot be had."""


class MatchRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"points": example_ring(24), "top": 3, "refine": False})
    )

    points: Points
    top: int = Field(5, ge=limits.MATCH_TOP.least, le=limits.MATCH_TOP.value, strict=True)
    refine: bool = True


class _AtlasState:
    """The app's four-bar atlas: opened once, built at most once at a time."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.atlas: Atlas | None = None
        self.state = "missing"
        self.progress = 0.0
        self.error: str | None = None
        self.count: int | None = None
        self.thread: threading.Thread | None = None


_STATE_LOCK = threading.Lock()


def _atlas_state(app: FastAPI) -> _AtlasState:
    with _STATE_LOCK:
        state = getattr(app.state, "tools_atlas", None)
        if state is None:
            state = _AtlasState()
            app.state.tools_atlas = state
        return state


def atlas_count(app: FastAPI) -> int:
    """Entries of the atlas the app builds: ``app.state.atlas_count``, else the environment's
    ``LINKWRIGHT_WORKBENCH_ATLAS_COUNT``, else :data:`ATLAS_COUNT`."""
    value: Any = getattr(app.state, "atlas_count", None)
    where = "app.state.atlas_count"
    if value is None:
        value, where = os.environ.get(ATLAS_COUNT_ENV), ATLAS_COUNT_ENV
    if value is None:
        return ATLAS_COUNT
    try:
        count = int(value)
    except (TypeError, ValueError):
        raise MatchError(f"{where}: must be a whole number, got {value!r}") from None
    if count < 100:
        raise MatchError(f"{where}: an atlas needs at least 100 entries, got {count}")
    return count


def _atlas_root(app: FastAPI) -> Path:
    return Path(app.state.data_dir) / "atlas"


def _finished(root: Path) -> Path | None:
    """The largest finished four-bar atlas of seed 0 in ``root`` (the CLI's built-in one among
    them), or None."""
    found: list[tuple[int, Path]] = []
    if root.is_dir():
        for path in root.glob("fourbar-*-seed0-v1"):
            count = path.name.split("-")[1]
            if count.isdigit() and (path / "atlas.json").exists():
                found.append((int(count), path))
    return max(found)[1] if found else None


def _load_atlas(app: FastAPI) -> Atlas:
    """The opened atlas, building it first if the data directory has none (callers wait)."""
    state = _atlas_state(app)
    with state.lock:
        if state.atlas is not None:
            return state.atlas
        root = _atlas_root(app)
        try:
            path = _finished(root)
            if path is None:
                count = atlas_count(app)
                state.state, state.progress, state.count, state.error = "building", 0.0, count, None

                def tick(fraction: float) -> None:
                    state.progress = float(fraction)

                path = root / f"fourbar-{count}-seed0-v1"
                build("fourbar", count, path, workers=0, progress=tick)
            state.atlas = open_atlas(path)
        except (AtlasError, OSError, ValueError) as exc:
            state.state, state.error = "error", f"atlas: {exc}"
            raise MatchError(state.error) from None
        state.state, state.progress, state.count = "ready", 1.0, state.atlas.count
        return state.atlas


def _status(app: FastAPI) -> dict[str, Any]:
    state = _atlas_state(app)
    if state.atlas is None and state.state == "missing":
        path = _finished(_atlas_root(app))
        if path is not None:
            return {"state": "ready", "progress": 1.0, "count": int(path.name.split("-")[1]),
                    "error": None}  # fmt: skip
    return {
        "state": state.state,
        "progress": round(state.progress, 4),
        "count": state.count,
        "error": state.error,
    }


@router.get("/match/status")
def match_status(request: Request) -> dict[str, Any]:
    """Whether the atlas is ready: ``state`` missing | building | ready | error, ``progress``
    of a build in [0, 1], the atlas's ``count``, and the ``error`` of a failed build."""
    return _status(request.app)


@router.post("/match/prepare")
def match_prepare(request: Request) -> dict[str, Any]:
    """Start building (or opening) the atlas in the background, so that the first match does
    not wait for it; answers the status at once."""
    app = request.app
    state = _atlas_state(app)
    with _STATE_LOCK:
        idle = state.atlas is None and (state.thread is None or not state.thread.is_alive())
        if idle:
            state.state = "building"

            def work() -> None:
                # A failure is kept in the state, and raised again to the match that asks.
                with contextlib.suppress(ValueError):
                    _load_atlas(app)

            state.thread = threading.Thread(target=work, name="linkwright-atlas", daemon=True)
            state.thread.start()
    return _status(app)


@router.post("/match")
def match(body: MatchRequest, request: Request) -> dict[str, Any]:
    """The atlas four-bars whose coupler curves best match the drawn closed curve, best first,
    each placed where the curve was drawn. A refined match fits at most
    :data:`REFINE_POINTS` of the points, evenly spaced along the drawing (``fitted`` says how
    many)."""
    points = drawn_points(body.points, 8)
    fitted = points
    if body.refine and len(points) > REFINE_POINTS:
        fitted = points[np.linspace(0, len(points) - 1, REFINE_POINTS).round().astype(int)]
    # The re-ranking traces about 60 candidates; a refinement fits one input per point.
    estimate = cost.Estimate(60 * 5 * (256 + cost.CALL_UNITS), 1e7, "matching a curve")
    if body.refine:
        estimate = estimate + cost.refine(len(fitted), 5)
    budget.check(estimate.holding(budget.answer_bytes(2.0 * body.top * CURVE_SAMPLES, True)))
    # Opening (on first use, building) the atlas is the workbench's setup, not this request's
    # work: the time budget starts after it.
    atlas = _load_atlas(request.app)
    with budget.request("the points, or match without refine"):
        return _match(body, atlas, points, fitted)


def _match(body: MatchRequest, atlas: Atlas, points: Array, fitted: Array) -> dict[str, Any]:
    matches = query(atlas, fitted, top=body.top, refine=body.refine, budget=2.0)
    centred = points - points.mean(axis=0)
    size = float(np.sqrt(np.mean(np.sum(centred**2, axis=1))))
    candidates = []
    for rank, m in enumerate(matches, start=1):
        cost.check_time()
        doc = mechanism_to_dict(m.mechanism, title=f"Atlas match {rank} (entry {m.atlas_id})")
        motion = circuit(m.mechanism, CURVE_SAMPLES, order=0)
        curve = polyline(np.asarray(motion.positions["P"]), motion.valid)
        candidates.append(
            {
                "rank": rank,
                "error": json_number(m.error),
                "distance": json_number(m.distance),
                "relative": json_number(m.distance / size) if size > 0 else None,
                "refined": bool(m.refined),
                "atlas_id": int(m.atlas_id),
                "document": doc,
                "curve": curve + curve[:1],
            }
        )
    return {
        "atlas": {"count": atlas.count},
        "size": size,
        "fitted": len(fitted),
        "candidates": candidates,
    }

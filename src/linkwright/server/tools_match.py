"""The workbench's atlas match: ``POST /match``, ``GET /match/status``, ``POST /match/prepare``.

A drawn closed curve is matched against a built-in atlas (:mod:`linkwright.atlas`), optionally
refined; each candidate comes placed where the curve was drawn. A curve of [x, y] rows is
matched against the four-bar atlas; one of [x, y, z] rows (directions on the sphere) against
the spherical four-bar atlas, and its candidates are spherical four-bars (composed linkages,
whose ground axes stand where the curve was drawn) with curves of unit vectors. Each space's
atlas is built into the app's data directory on first use (:func:`atlas_count` entries) unless
a finished atlas of its family is already there (the CLI's built-in one is found and used);
status and prepare take ``?space=plane`` (the default) or ``?space=sphere``.

Its own room (split from :mod:`linkwright.server.tools`): one tool, with the app's atlases it
opens or builds once each.
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
    CurvePoints,
    ToolsError,
    drawn_curve,
    example_ring,
    json_number,
    polyline,
)

__all__ = [
    "ATLAS_COUNT",
    "ATLAS_COUNT_ENV",
    "CURVE_SAMPLES",
    "REFINE_POINTS",
    "SPACES",
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
SPACES = {"plane": "fourbar", "sphere": "spherical-fourbar"}
"""The atlas family the workbench matches a curve of each space against."""


class MatchError(ToolsError):
    """Points that are not a curve to match, or an atlas that cannot be had."""


class MatchRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"points": example_ring(24), "top": 3, "refine": False})
    )

    points: CurvePoints
    top: int = Field(5, ge=limits.MATCH_TOP.least, le=limits.MATCH_TOP.value, strict=True)
    refine: bool = True
    open: bool = False
    """The points are an open curve, a piece of the curve wanted (every entry is screened)."""


class _AtlasState:
    """One of the app's atlases: opened once, built at most once at a time."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.atlas: Atlas | None = None
        self.state = "missing"
        self.progress = 0.0
        self.error: str | None = None
        self.count: int | None = None
        self.thread: threading.Thread | None = None


_STATE_LOCK = threading.Lock()


def _space(space: str) -> str:
    if space not in SPACES:
        raise MatchError(f"space: must be one of {', '.join(SPACES)}, got {space!r}")
    return space


def _atlas_state(app: FastAPI, space: str = "plane") -> _AtlasState:
    with _STATE_LOCK:
        states = getattr(app.state, "tools_atlases", None)
        if states is None:
            states = app.state.tools_atlases = {}
        if space not in states:
            states[space] = _AtlasState()
        state: _AtlasState = states[space]
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


def _count_of(path: Path, family: str) -> int:
    return int(path.name[len(family) + 1 :].split("-")[0])


def _finished(root: Path, family: str = "fourbar") -> Path | None:
    """The largest finished atlas of ``family`` and seed 0 in ``root`` (the CLI's built-in one
    among them), or None."""
    found: list[tuple[int, Path]] = []
    if root.is_dir():
        for path in root.glob(f"{family}-*-seed0-v1"):
            count = path.name[len(family) + 1 :].split("-")[0]
            if count.isdigit() and (path / "atlas.json").exists():
                found.append((int(count), path))
    return max(found)[1] if found else None


def _load_atlas(app: FastAPI, space: str = "plane") -> Atlas:
    """The opened atlas of ``space``, building it first if the data directory has none
    (callers wait)."""
    state = _atlas_state(app, space)
    family = SPACES[space]
    with state.lock:
        if state.atlas is not None:
            return state.atlas
        root = _atlas_root(app)
        try:
            path = _finished(root, family)
            if path is None:
                count = atlas_count(app)
                state.state, state.progress, state.count, state.error = "building", 0.0, count, None

                def tick(fraction: float) -> None:
                    state.progress = float(fraction)

                path = root / f"{family}-{count}-seed0-v1"
                build(family, count, path, workers=0, progress=tick)
            state.atlas = open_atlas(path)
        except (AtlasError, OSError, ValueError) as exc:
            state.state, state.error = "error", f"atlas: {exc}"
            raise MatchError(state.error) from None
        state.state, state.progress, state.count = "ready", 1.0, state.atlas.count
        return state.atlas


def _status(app: FastAPI, space: str = "plane") -> dict[str, Any]:
    state = _atlas_state(app, space)
    if state.atlas is None and state.state == "missing":
        path = _finished(_atlas_root(app), SPACES[space])
        if path is not None:
            return {"state": "ready", "progress": 1.0, "count": _count_of(path, SPACES[space]),
                    "error": None}  # fmt: skip
    return {
        "state": state.state,
        "progress": round(state.progress, 4),
        "count": state.count,
        "error": state.error,
    }


@router.get("/match/status")
def match_status(request: Request, space: str = "plane") -> dict[str, Any]:
    """Whether the atlas of ``space`` (plane: four-bars, sphere: spherical four-bars) is ready:
    ``state`` missing | building | ready | error, ``progress`` of a build in [0, 1], the
    atlas's ``count``, and the ``error`` of a failed build."""
    return _status(request.app, _space(space))


@router.post("/match/prepare")
def match_prepare(request: Request, space: str = "plane") -> dict[str, Any]:
    """Start building (or opening) the atlas of ``space`` in the background, so that the first
    match does not wait for it; answers its status at once."""
    app = request.app
    space = _space(space)
    state = _atlas_state(app, space)
    with _STATE_LOCK:
        idle = state.atlas is None and (state.thread is None or not state.thread.is_alive())
        if idle:
            state.state = "building"

            def work() -> None:
                # A failure is kept in the state, and raised again to the match that asks.
                with contextlib.suppress(ValueError):
                    _load_atlas(app, space)

            name = f"linkwright-atlas-{space}"
            state.thread = threading.Thread(target=work, name=name, daemon=True)
            state.thread.start()
    return _status(app, space)


@router.post("/match")
def match(body: MatchRequest, request: Request) -> dict[str, Any]:
    """The atlas four-bars whose coupler curves best match the drawn closed curve (with
    ``open``, a piece of one), best first, each placed where the curve was drawn: [x, y]
    points are matched in the plane, [x, y, z] directions on the sphere (against spherical
    four-bars; curves come back as unit vectors).
    A refined match fits at most :data:`REFINE_POINTS` of the points, evenly spaced along the
    drawing (``fitted`` says how many)."""
    points, space = drawn_curve(body.points, 8)
    fitted = points
    if body.refine and len(points) > REFINE_POINTS:
        fitted = points[np.linspace(0, len(points) - 1, REFINE_POINTS).round().astype(int)]
    # The spherical match measures a curve from its mean direction; without one (two opposite
    # points in turn) the query's size is 0/0 and it found nothing, without a word.
    if space == "sphere" and not np.linalg.norm(fitted.mean(axis=0)) > 1e-150:
        raise MatchError(
            "points: the curve has no mean direction (it is balanced about the sphere's centre, "
            "like opposite points in turn); draw it around one side of the sphere"
        )
    # The re-ranking traces about 60 candidates; a refinement fits one input per point.
    estimate = cost.Estimate(60 * 5 * (256 + cost.CALL_UNITS), 1e7, "matching a curve")
    if body.refine:
        estimate = estimate + cost.refine(len(fitted), 5)
    numbers = points.shape[1] * body.top * CURVE_SAMPLES
    budget.check(estimate.holding(budget.answer_bytes(float(numbers), True)))
    # Opening (on first use, building) the atlas is the workbench's setup, not this request's
    # work: the time budget starts after it.
    atlas = _load_atlas(request.app, space)
    with budget.request("the points, or match without refine"):
        return _match(body, atlas, points, fitted)


def _size(points: Array) -> float:
    """The curve's size, the scale of ``relative``: RMS distance from the centroid in the plane;
    on the sphere RMS chord from the mean direction (as :func:`linkwright.atlas.query` measures
    it; the centroid where the points surround the centre so evenly that they have none)."""
    centre = points.mean(axis=0)
    if points.shape[1] == 3:
        norm = float(np.linalg.norm(centre))
        centre = centre / norm if norm > 1e-150 else centre
    return float(np.sqrt(np.mean(np.sum((points - centre) ** 2, axis=1))))


def _curve(points: Array, valid: Any) -> list[list[float] | None]:
    """Rows of every coordinate (two in the plane, a unit vector's three on the sphere), null
    where a sample could not be placed."""
    if points.shape[-1] == 2:
        return polyline(points, valid)
    ok = np.all(np.isfinite(points), axis=-1) & np.asarray(valid, dtype=bool)
    return [[float(c) for c in p] if k else None for p, k in zip(points, ok, strict=True)]


def _match(body: MatchRequest, atlas: Atlas, points: Array, fitted: Array) -> dict[str, Any]:
    matches = query(
        atlas, fitted, top=body.top, refine=body.refine, budget=2.0, open_curve=body.open
    )
    size = _size(points)
    candidates = []
    for rank, m in enumerate(matches, start=1):
        cost.check_time()
        doc = mechanism_to_dict(m.mechanism, title=f"Atlas match {rank} (entry {m.atlas_id})")
        motion = circuit(m.mechanism, CURVE_SAMPLES, order=0)
        curve = _curve(np.asarray(motion.positions["P"]), motion.valid)
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
        "atlas": {"count": atlas.count, "family": atlas.family},
        "size": size,
        "fitted": len(fitted),
        "candidates": candidates,
    }

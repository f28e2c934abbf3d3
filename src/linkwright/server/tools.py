"""The workbench's tools: paper 002's pivot study, synthesis from a drawn curve, and exports.

Routes (mounted under ``/api`` by :func:`linkwright.server.create_app`):

- ``POST /study``: move one fixed pivot ``count`` steps along a direction and trace the curves
  at every step (paper 002, section III). A geared five-bar drawn the paper's way (P on AC at
  twice its length, so C is the midpoint of A–P) keeps its drawing: the moved pivot carries its
  crank end, the cranks' angles and P stay, and the links follow
  (:func:`linkwright.papers.p002.pivot_study`). Every other planar linkage moves only the
  pivot's own document field. A step whose linkage assembles nowhere is reported (``full``
  false, no curve), not refused.
- ``POST /match`` (with ``GET /match/status`` and ``POST /match/prepare``): match a drawn
  closed curve against the built-in four-bar atlas (:mod:`linkwright.atlas`), optionally
  refined; each candidate comes placed where the curve was drawn. The atlas is built into the
  app's data directory on first use (:func:`atlas_count` entries) unless a finished four-bar
  atlas is already there (the CLI's built-in one is found and used).
- ``POST /ellipse`` and ``POST /ellipse/trammel``: fit an ellipse to drawn points and browse
  paper 004's ∞² family of double sliders (elliptic trammels) that trace it
  (:mod:`linkwright.synthesis.ellipse`), each member checked against the ellipse.
- ``POST /export/{fmt}``: the current document as PNG, SVG, DXF, CSV, GIF, TOML or JSON.

Every problem a user can cause raises a ``ValueError`` subclass with one line naming the field,
which the app answers as 422 ``{"error": ...}``; no answer carries NaN (a point that cannot be
placed is ``null``).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import tempfile
import threading
import unicodedata
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, FastAPI, Request
from fastapi import Path as PathParam
from fastapi.responses import Response
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, WithJsonSchema

from linkwright.atlas import AtlasError, build, open_atlas, query
from linkwright.atlas.atlas import Atlas
from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs
from linkwright.io import (
    Document,
    DocumentError,
    document_to_dict,
    export_csv,
    export_dxf,
    export_svg,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.io.documents import WORKING_RANGE
from linkwright.mechanisms import DoubleSlider, GearedFiveBar, Mechanism, circuit, input_range
from linkwright.mechanisms import solve as solve_motion
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server import budget, limits
from linkwright.server.schema import DocumentBody, document_examples, examples
from linkwright.synthesis.ellipse import (
    EllipseError,
    Trammel,
    check_on_ellipse,
    doubleslider_family,
    family_angles,
    fit_ellipse,
)

__all__ = [
    "ATLAS_COUNT",
    "EXPORTS",
    "MAX_POINTS",
    "MAX_STUDY_STEPS",
    "REFINE_POINTS",
    "MatchError",
    "StudyError",
    "ToolsError",
    "atlas_count",
    "router",
]

Array = NDArray[np.float64]

router = APIRouter()

MAX_POINTS = limits.POINTS.value
"""Most points a drawn curve may have (:data:`linkwright.server.limits.POINTS`)."""
MAX_STUDY_STEPS = limits.STUDY_STEPS.value
"""Most steps one pivot study takes (:data:`linkwright.server.limits.STUDY_STEPS`)."""
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
FAMILY_TOLERANCE = 1e-9
"""Largest deviation from the ellipse (relative to its semi-major axis) a family member may
have; the construction is exact, so anything above rounding is a bug and is left out."""
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

_DIRECTIONS = {"left": (-1.0, 0.0), "right": (1.0, 0.0), "up": (0.0, 1.0), "down": (0.0, -1.0)}


class ToolsError(ValueError):
    """A tools request that cannot be served as asked (names the field and the problem)."""


class StudyError(ToolsError):
    """A pivot study asked of a pivot, direction or linkage it cannot move."""


class MatchError(ToolsError):
    """Points that are not a curve to match, or an atlas that cannot be had."""


# --------------------------------------------------------------------------------------------
# Shared helpers
# --------------------------------------------------------------------------------------------


def _document(mapping: Any) -> Document:
    limits.check_document(mapping)
    return parse_document(mapping, source="document")


_COORDINATE = {
    "type": "number",
    "minimum": -WORKING_RANGE.max_size,
    "maximum": WORKING_RANGE.max_size,
}

# Drawn points as the schema describes them; _points checks them with messages naming the row.
_POINTS_SCHEMA = WithJsonSchema(
    {
        "type": "array",
        "items": {
            "type": "array",
            "items": _COORDINATE,
            "minItems": 2,
            "maxItems": 2,
        },
        "maxItems": limits.POINTS.value,
        "description": "The drawn curve: [x, y] rows.",
    }
)
Points = Annotated[list[list[float]], _POINTS_SCHEMA]


def _num(x: Any) -> float | None:
    """A JSON number, or null for NaN and infinities."""
    value = float(x)
    return value if math.isfinite(value) else None


def _points(raw: Sequence[Sequence[float]], least: int, field: str = "points") -> Array:
    """Drawn points as an (N, 2) array, each row two finite numbers."""
    if len(raw) < least:
        raise ToolsError(f"{field}: a curve needs at least {least} points, got {len(raw)}")
    if len(raw) > MAX_POINTS:
        raise ToolsError(f"{field}: at most {MAX_POINTS:,} points, got {len(raw):,}")
    for i, row in enumerate(raw):
        if len(row) != 2:
            raise ToolsError(f"{field}: row {i} has {len(row)} numbers; each point is [x, y]")
    p = np.asarray(raw, dtype=float)
    bad = ~np.all(np.isfinite(p), axis=1)
    if bad.any():
        raise ToolsError(f"{field}: row {int(np.flatnonzero(bad)[0])} is not finite")
    # A document's working range: beyond it squared distances overflow (1e200² is inf).
    largest = np.abs(p).max(axis=1, initial=0.0)
    huge = np.flatnonzero(largest > WORKING_RANGE.max_size)
    if huge.size:
        row = int(huge[0])
        problem = WORKING_RANGE.size_problem(float(largest[row]))
        raise ToolsError(f"{field}: row {row}: a coordinate {problem}")
    return p


def _polyline(points: Array, valid: NDArray[np.bool_] | None = None) -> list[list[float] | None]:
    """Rows as [x, y] pairs, null where a sample could not be placed."""
    ok = np.all(np.isfinite(points), axis=-1)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    return [
        [float(x), float(y)] if k else None for (x, y), k in zip(points[:, :2], ok, strict=True)
    ]


def _traced_curves(
    mechanism: Mechanism, samples: int, arcs: InputArcs | None = None
) -> tuple[bool, bool, dict[str, list]]:
    """(assembles somewhere, turns fully, each traced joint's closed circuits joined by null)."""
    arcs = input_range(mechanism) if arcs is None else arcs
    motions = budget.trace_circuits(mechanism, arcs, samples)
    full = bool(arcs.full) and bool(motions)
    if not motions:
        return False, False, {}
    curves: dict[str, list] = {j: [] for j in mechanism.plan.traced}
    for i, motion in enumerate(motions):
        for joint, rows in curves.items():
            if i:
                rows.append(None)
            line = _polyline(np.asarray(motion.positions[joint]), motion.valid)
            # Every circuit closes (a rocking one comes back down its other branch).
            rows.extend(line + line[:1] if line and line[0] is not None else line)
    return bool(motions), full, curves


# --------------------------------------------------------------------------------------------
# Paper 002's pivot study
# --------------------------------------------------------------------------------------------


_DIRECTION_SCHEMA = WithJsonSchema(
    {
        "anyOf": [
            {"enum": ["left", "right", "up", "down"]},
            {"type": "number", "description": "degrees from +x"},
            {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2},
        ],
        "default": "left",
    }
)


_DOC = document_examples()[0]


def _ring(n: int, a: float = 3.0, b: float = 1.2) -> list[list[float]]:
    """An example drawn curve: n points around an ellipse."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return [
        [round(float(x), 6), round(float(y), 6)]
        for x, y in zip(a * np.cos(t), b * np.sin(t), strict=True)
    ]


class StudyRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples(
            {"document": _DOC, "pivot": "B0", "direction": "right", "step": 0.5, "count": 2,
             "samples": 48}
        )
    )  # fmt: skip

    document: DocumentBody
    pivot: str = Field(min_length=1, max_length=limits.TEXT.value)
    direction: Annotated[list[float] | float | str, _DIRECTION_SCHEMA] = "left"
    step: float = Field(0.5, strict=True, json_schema_extra={"exclusiveMinimum": 0})
    # Checked in study(), whose message gives the whole range; the schema says it too.
    count: int = Field(
        3,
        strict=True,
        json_schema_extra={
            "minimum": limits.STUDY_STEPS.least,
            "maximum": limits.STUDY_STEPS.value,
        },
    )
    samples: int = Field(180, ge=limits.SAMPLES.least, le=limits.SAMPLES.value, strict=True)


def _direction(value: list[float] | float | str) -> Array:
    """A unit vector from [dx, dy], an angle in degrees from +x, or left/right/up/down."""
    if isinstance(value, str):
        if len(value) > limits.TEXT.value:
            raise limits.over(limits.TEXT, "direction", len(value))
        if value.lower() not in _DIRECTIONS:
            raise StudyError(
                f"direction: {value!r} is not one of {', '.join(_DIRECTIONS)}, [dx, dy] or an "
                "angle in degrees"
            )
        return np.array(_DIRECTIONS[value.lower()])
    if isinstance(value, int | float):
        if not math.isfinite(value):
            raise StudyError(f"direction: the angle must be finite, got {value}")
        quarter = value / 90.0
        if quarter == round(quarter):  # exactly along an axis, not 6e-17 off it
            return np.array([(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][round(quarter) % 4])
        return np.array([math.cos(math.radians(value)), math.sin(math.radians(value))])
    if len(value) != 2 or not all(math.isfinite(x) for x in value):
        raise StudyError(f"direction: must be two finite numbers [dx, dy], got {value}")
    length = math.hypot(*value)
    if not length > 0:
        raise StudyError("direction: [0, 0] has no direction")
    return np.asarray(value, dtype=float) / length


def _fixed_joints(mechanism: Mechanism) -> list[str]:
    from linkwright.engine import Fixed

    return [s.name for s in mechanism.plan.steps if isinstance(s, Fixed)]


def _pivot_path(doc: Document, pivot: str) -> list[str | int]:
    """Where the pivot's position lives in the document's mechanism table."""
    mech = doc.raw["mechanism"]
    if doc.family == "linkage":
        for i, joint in enumerate(mech["joints"]):
            if joint["name"] == pivot and joint["type"] == "fixed":
                return ["joints", i, "at"]
    elif doc.family == "slidercrank" and pivot == "L":
        return ["line", "point"]
    elif isinstance(mech.get(pivot), list) and len(mech[pivot]) == 2:
        return [pivot]
    raise StudyError(f"pivot: the {doc.family} has no document field for pivot {pivot!r}")


def _moved(doc: Document, path: list[str | int], shift: Array) -> dict[str, Any]:
    raw = document_to_dict(doc)
    table: Any = raw["mechanism"]
    for key in path[:-1]:
        table = table[key]
    table[path[-1]] = [float(c) for c in np.add(table[path[-1]], shift)]
    return raw


def _fivebar_drawing(doc: Document) -> dict[str, Array] | None:
    """Points 1, 2, 3, 4 and 6 of paper 002's drawing (A0, A, B0, B, P at the input θ1 =
    phase1, where the cranks sit at their drawn angles), or None where the document is not
    drawn the paper's way (P must lie on AC at twice its length, so that C is the midpoint of
    A–P and rebuilding from the drawing gives this very linkage) or does not assemble there."""
    m = doc.mechanism
    link1, u, v = float(m.link1), float(m.u), float(m.v)
    if abs(u - 2.0 * link1) > 1e-9 * link1 or abs(v) > 1e-9 * link1:
        return None
    motion = solve_motion(m, np.array([float(m.phase1)]), order=0)
    if not bool(np.asarray(motion.valid)[0]):
        return None
    return {k: np.asarray(motion.positions[k][0], dtype=float) for k in ("A0", "A", "B0", "B", "P")}


def _drawing_steps(
    drawing: dict[str, Array], pivot: str, d: Array, step: float, count: int, ratio: float
) -> list[tuple[int, Array, GearedFiveBar | None, str | None]]:
    """Paper 002's study: the pivot carries its crank end, P and the other crank stay."""
    from linkwright.mechanisms import InvalidMechanism
    from linkwright.papers.p002 import pivot_study

    out: list[tuple[int, Array, GearedFiveBar | None, str | None]] = []
    if pivot == "A0":
        done = pivot_study(drawing, d, step=step, count=count, ratio=ratio)
        out = [(s.steps, np.array(s.offset), s.mechanism, None) for s in done]
    else:  # B0 with B, the same rule for the other crank
        for k in range(count + 1):
            shift = k * step * d
            try:
                mech = GearedFiveBar.from_drawing(
                    drawing["A0"], drawing["A"], drawing["B0"] + shift, drawing["B"] + shift,
                    drawing["P"], ratio=ratio,
                )  # fmt: skip
            except InvalidMechanism:
                break
            out.append((k, shift, mech, None))
    for k in range(len(out), count + 1):
        # pivot_study stops where the crank end A lands on P: no link AC is left.
        out.append((k, k * step * d, None, "the crank end reaches the traced point P here"))
    return out


@router.post("/study")
def study(body: StudyRequest) -> dict[str, Any]:
    """Move ``pivot`` ``count`` steps of ``step`` along ``direction``; step 0 is the document.

    Examples
    --------
    The crank-rocker of paper 003 (frame 3.5, crank 1, coupler 5, rocker 6.02) with B0 moved
    right: at frame 11.5 the crank no longer turns fully (f + 1 > 5 + 6.02), but it rocks.

    >>> from linkwright.io import document_to_dict, load_example
    >>> doc = document_to_dict(load_example("crank-rocker"))
    >>> body = StudyRequest(document=doc, pivot="B0", direction="right", step=4.0, count=2)
    >>> [(s["offset"], s["full"], s["assembles"]) for s in study(body)["steps"]]
    [([0.0, 0.0], True, True), ([4.0, 0.0], True, True), ([8.0, 0.0], False, True)]
    >>> study(StudyRequest(document=doc, pivot="P"))
    Traceback (most recent call last):
    ...
    linkwright.server.tools.StudyError: pivot: 'P' is not a fixed pivot of this linkage (its
    fixed pivots: A0, B0)

    Its cost (every step's circuits and the answer) is estimated before any step is traced:

    >>> geared = document_to_dict(load_example("geared-fivebar"))
    >>> geared["mechanism"]["ratio"] = 64.0
    >>> study(StudyRequest(document=geared, pivot="A0", count=50, samples=4096))
    Traceback (most recent call last):
    ...
    linkwright.server.budget.TooCostly: too costly: tracing 51 steps × 42 circuits of 4,096 \
samples (6 joints) needs about 7.8e+07 units of work (at most 5e+07 per request) and 3.1 GB of \
memory (at most 268 MB per request); lower count to 3 or fewer, or samples to 352 or fewer, or \
the gear ratio
    """
    with budget.request("count or samples"):
        return _study(body)


def _study(body: StudyRequest) -> dict[str, Any]:
    doc = _document(body.document)
    mech = doc.mechanism
    # Read from the document: a mechanism without a construction plan cannot tell its space.
    if doc.family.startswith("spherical-") or doc.raw["mechanism"].get("space") == "sphere":
        raise StudyError(
            "pivot: the pivot study moves a pivot in the plane; this linkage is spherical"
        )
    if not (math.isfinite(body.step) and body.step > 0):
        raise StudyError(f"step: must be a positive length, got {body.step}")
    if not 0 <= body.count <= MAX_STUDY_STEPS:
        raise StudyError(f"count: must be from 0 to {MAX_STUDY_STEPS} steps, got {body.count}")
    d = _direction(body.direction)
    fixed = _fixed_joints(mech)
    if body.pivot not in fixed:
        raise StudyError(
            f"pivot: {body.pivot!r} is not a fixed pivot of this linkage (its fixed pivots: "
            f"{', '.join(fixed) or 'none'})"
        )
    title = doc.title or "linkage"
    drawing = None
    if doc.family == "geared-fivebar" and body.pivot in ("A0", "B0"):
        drawing = _fivebar_drawing(doc)
    if drawing is not None:
        method = "drawing"
        note = (
            f"paper 002: {body.pivot} carries its crank end; the cranks' angles and P stay, C is "
            "the midpoint of A–P, and the links follow"
        )
        plan = _drawing_steps(drawing, body.pivot, d, body.step, body.count, float(mech.ratio))
        candidates = [
            (k, shift, None if m is None else mechanism_to_dict(m), why)
            for k, shift, m, why in plan
        ]
    else:
        method = "field"
        path = _pivot_path(doc, body.pivot)
        note = f"{body.pivot} moves; every other field stays"
        candidates = []
        for k in range(body.count + 1):
            shift = k * body.step * d
            candidates.append((k, shift, _moved(doc, path, shift), None))
    budget.check_study(mech, body.count, body.samples)
    spent = 0.0
    steps = []
    for k, shift, raw, why in candidates:
        entry: dict[str, Any] = {
            "steps": int(k),
            "offset": [float(shift[0]) + 0.0, float(shift[1]) + 0.0],
            "document": None,
            "full": False,
            "assembles": False,
            "curves": {},
            "note": why,
        }
        if raw is not None:
            if doc.units is not None:
                raw["units"] = doc.units
            raw["title"] = title if k == 0 else f"{title} ({body.pivot} moved {k} steps)"
            try:
                step_doc = parse_document(raw, source=f"step {k}")
            except DocumentError as exc:
                entry["note"] = str(exc)
            else:
                entry["document"] = document_to_dict(step_doc)
                try:
                    cost.check_time()
                    arcs = budget.step_arcs(step_doc.mechanism, body.samples, k, spent)
                    spent += budget.study_estimate(step_doc.mechanism, arcs, 1, body.samples).work
                    assembles, full, curves = _traced_curves(step_doc.mechanism, body.samples, arcs)
                except (budget.TooCostly, cost.CostError):
                    raise  # the whole study is refused, not noted as one step's problem
                except ValueError as exc:  # e.g. no construction plan
                    entry["note"] = str(exc)
                else:
                    entry.update(assembles=assembles, full=full, curves=curves)
                    if not assembles:
                        entry["note"] = "the linkage cannot be assembled at any input here"
        steps.append(entry)
    return {
        "pivot": body.pivot,
        "direction": [float(d[0]), float(d[1])],
        "step": float(body.step),
        "method": method,
        "note": note,
        "steps": steps,
    }


# --------------------------------------------------------------------------------------------
# Atlas match
# --------------------------------------------------------------------------------------------


class MatchRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"points": _ring(24), "top": 3, "refine": False})
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
    points = _points(body.points, 8)
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
        curve = _polyline(np.asarray(motion.positions["P"]), motion.valid)
        candidates.append(
            {
                "rank": rank,
                "error": _num(m.error),
                "distance": _num(m.distance),
                "relative": _num(m.distance / size) if size > 0 else None,
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


# --------------------------------------------------------------------------------------------
# Ellipse → double sliders (paper 004)
# --------------------------------------------------------------------------------------------


Circle = Annotated[str, Field(json_schema_extra={"enum": ["small", "large"]})]


class EllipseRequest(BaseModel):
    model_config = ConfigDict(json_schema_extra=examples({"points": _ring(24), "count": 4}))

    points: Points
    count: int = Field(
        12, ge=limits.ELLIPSE_FAMILY.least, le=limits.ELLIPSE_FAMILY.value, strict=True
    )
    circle: Circle = "small"


_PAIR = {"type": "array", "items": {"type": "number"}, "minItems": 2, "maxItems": 2}
_ELLIPSE_SCHEMA = WithJsonSchema(
    {
        "type": "object",
        "properties": {"center": _PAIR, "axes": _PAIR, "angle": {"type": "number"}},
        "required": ["center", "axes"],
        "description": "An ellipse as /ellipse answers it: centre, semi-axes, angle (degrees).",
    }
)


class TrammelRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples(
            {"ellipse": {"center": [0.0, 0.0], "axes": [3.0, 1.2], "angle": 20.0}, "a": 30.0,
             "b": 120.0}
        )
    )  # fmt: skip

    ellipse: Annotated[dict[str, Any], _ELLIPSE_SCHEMA]
    a: float | None = None
    b: float | None = None
    s1: float | None = None
    s2: float | None = None
    circle: Circle = "small"


def _ellipse_curve(t: Trammel, samples: int = 181) -> list[list[float]]:
    s = np.linspace(0.0, 2.0 * np.pi, samples)
    c, d = math.cos(float(t.beta)), math.sin(float(t.beta))
    x, y = float(t.a) * np.cos(s), float(t.b) * np.sin(s)
    pts = np.column_stack((float(t.X0) + c * x - d * y, float(t.Y0) + d * x + c * y))
    return [[float(px), float(py)] for px, py in pts]


def _ellipse_json(t: Trammel) -> dict[str, Any]:
    return {
        "center": [float(t.X0), float(t.Y0)],
        "axes": [float(t.a), float(t.b)],
        "angle": float(np.degrees(t.beta)),
        "curve": _ellipse_curve(t),
    }


def _trammel_of(value: dict[str, Any]) -> Trammel:
    """The ellipse of a request ({center, axes, angle in degrees}) as a :class:`Trammel`."""
    try:
        cx, cy = (float(x) for x in value["center"])
        a, b = (float(x) for x in value["axes"])
        angle = float(value.get("angle", 0.0))
    except KeyError as exc:
        raise EllipseError(f"ellipse.{exc.args[0]}: missing") from None
    except (TypeError, ValueError):
        raise EllipseError(
            "ellipse: must be {center: [x, y], axes: [a, b], angle: degrees}"
        ) from None
    if not all(math.isfinite(x) for x in (cx, cy, a, b, angle)):
        raise EllipseError("ellipse: center, axes and angle must be finite")
    if not (a > 0 and b > 0):
        raise EllipseError(f"ellipse.axes: both semi-axes must be positive, got [{a}, {b}]")
    if problem := WORKING_RANGE.size_problem(max(abs(cx), abs(cy), a, b)):
        raise EllipseError(f"ellipse: centre and axes {problem}")
    if a < b:  # the major axis is the other one
        a, b, angle = b, a, angle + 90.0
    beta = math.radians((angle + 90.0) % 180.0 - 90.0)
    return Trammel(X0=np.float64(cx), Y0=np.float64(cy), beta=np.float64(beta), a=np.float64(a),
                   b=np.float64(b))  # fmt: skip


def _check_circle(circle: str) -> str:
    if circle not in ("small", "large"):
        shown = circle if len(circle) <= limits.TEXT.value else circle[: limits.TEXT.value] + "…"
        raise EllipseError(f"circle: must be 'small' or 'large', got {shown!r}")
    return circle


def _member(family: DoubleSlider, i: int | tuple[()]) -> DoubleSlider:
    return DoubleSlider(**{k: np.asarray(getattr(family, k))[i] for k in
                           ("M", "alpha", "beta", "p", "q", "h")})  # fmt: skip


def _trammel_entry(m: DoubleSlider, t: Trammel, s1: float, s2: float) -> dict[str, Any] | None:
    """A family member as sent: its document (lengths that are zero but for rounding written
    as 0), and how far the linkage *that document* builds strays from the ellipse; None if it
    strays more than rounding allows."""
    title = f"Double slider s1 = {s1:.2f}°, s2 = {s2:.2f}° (paper 004)"
    doc = mechanism_to_dict(m, title=title)
    mech = doc["mechanism"]
    for key in ("p", "q", "h"):
        if abs(mech[key]) <= 1e-12 * float(t.a):
            mech[key] = 0.0
    deviation = float(check_on_ellipse(parse_document(doc).mechanism, t, samples=360))
    if not deviation <= FAMILY_TOLERANCE:
        return None
    return {"s1": round(s1, 6), "s2": round(s2, 6), "document": doc, "deviation": deviation}


@router.post("/ellipse")
def ellipse(body: EllipseRequest) -> dict[str, Any]:
    """The ellipse fitted to the points and ``count`` double sliders of the ∞² family tracing
    it, spread over the slider angles (s1, s2) of R's and Q's guides from the major axis."""
    with budget.request("count"):
        return _ellipse(body)


def _ellipse(body: EllipseRequest) -> dict[str, Any]:
    points = _points(body.points, 5)
    circle = _check_circle(body.circle)
    try:
        fit = fit_ellipse(points)
    except EllipseError as exc:
        raise EllipseError(f"points: {exc}") from None
    t = fit.trammel
    out = _ellipse_json(t)
    out.update(
        residual=fit.rms,
        residual_max=fit.max,
        residual_relative=fit.rms / float(t.a),
        conic=[float(c) for c in fit.coeffs],
        circle=circle,
    )
    # s1 = 90°, s2 = 0°: Archimedes' trammel (α = 90°, h = 0), first; then the spread family.
    angles = np.vstack((np.radians([[90.0, 0.0]]), family_angles(body.count)))
    members = doubleslider_family(t, angles[:, 0], angles[:, 1], circle=circle)
    # Each member is checked against the ellipse at 360 samples (4 joints each).
    budget.check(
        cost.Estimate(
            len(angles) * 4 * (360 + 3 * cost.CALL_UNITS),
            len(points) * 64 * 8,
            f"fitting {len(points):,} points and checking {len(angles)} double sliders",
        )
    )
    out["family"] = []
    for i, (s1, s2) in enumerate(np.degrees(angles)):
        cost.check_time()
        entry = _trammel_entry(_member(members, i), t, float(s1), float(s2))
        if entry is not None:
            out["family"].append(entry)
    return out


@router.post("/ellipse/trammel")
def ellipse_trammel(body: TrammelRequest) -> dict[str, Any]:
    """One member of the family: slider angles ``a`` = s1 (R's guide) and ``b`` = s2 (Q's),
    degrees from the ellipse's major axis (``s1``/``s2`` are accepted as the same)."""
    t = _trammel_of(body.ellipse)
    circle = _check_circle(body.circle)
    s1 = body.s1 if body.s1 is not None else body.a
    s2 = body.s2 if body.s2 is not None else body.b
    if s1 is None or s2 is None:
        raise EllipseError("a, b: give both slider angles (degrees from the major axis)")
    if not (math.isfinite(s1) and math.isfinite(s2)):
        raise EllipseError(f"a, b: the slider angles must be finite, got {s1}, {s2}")
    try:
        family = doubleslider_family(t, math.radians(s1), math.radians(s2), circle=circle)
    except EllipseError as exc:
        raise EllipseError(f"a, b: {exc}") from None
    out = _trammel_entry(_member(family, ()), t, s1, s2)
    if out is None:  # the construction is exact: only a bug could get here
        raise EllipseError(f"a, b: the double slider at s1 = {s1}°, s2 = {s2}° misses the ellipse")
    out["circle"] = circle
    return out


# --------------------------------------------------------------------------------------------
# Exports
# --------------------------------------------------------------------------------------------


class ExportRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"document": _DOC, "at": 30.0, "samples": 48})
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
    doc = _document(body.document)
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

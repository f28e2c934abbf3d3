"""The workbench's pivot study (paper 002, section III): ``POST /study``.

One fixed pivot moves ``count`` steps along a direction and the curves are traced at every
step. A geared five-bar drawn the paper's way (P on AC at twice its length, so C is the
midpoint of A–P) keeps its drawing: the moved pivot carries its crank end, the cranks' angles
and P stay, and the links follow (:func:`linkwright.papers.p002.pivot_study`). Every other
planar linkage moves only the pivot's own document field. A step whose linkage assembles
nowhere is reported (``full`` false, no curve), not refused.

Its own room (split from :mod:`linkwright.server.tools`): one tool, its request and its errors.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter
from pydantic import BaseModel, ConfigDict, Field, WithJsonSchema

from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs
from linkwright.io import (
    Document,
    DocumentError,
    document_to_dict,
    mechanism_to_dict,
    parse_document,
)
from linkwright.mechanisms import GearedFiveBar, Mechanism, input_range
from linkwright.mechanisms import solve as solve_motion
from linkwright.server import budget, limits
from linkwright.server.schema import DocumentBody, examples
from linkwright.server.tools_common import (
    EXAMPLE_DOCUMENT,
    Array,
    ToolsError,
    polyline,
    read_document,
)

__all__ = ["MAX_STUDY_STEPS", "StudyError", "StudyRequest", "router", "study"]

router = APIRouter()

MAX_STUDY_STEPS = limits.STUDY_STEPS.value
"""Most steps one pivot study takes (:data:`linkwright.server.limits.STUDY_STEPS`)."""
_DIRECTIONS = {"left": (-1.0, 0.0), "right": (1.0, 0.0), "up": (0.0, 1.0), "down": (0.0, -1.0)}


class StudyError(ToolsError):
    """A pivot study asked of a pivot, direction or linkage it cannot move."""


def _traced_curves(
    mechanism: Mechanism, samples: int, arcs: InputArcs | None = None
) -> tuple[bool, bool, dict[str, list[list[float] | None]]]:
    """(assembles somewhere, turns fully, each traced joint's closed circuits joined by null)."""
    arcs = input_range(mechanism) if arcs is None else arcs
    motions = budget.trace_circuits(mechanism, arcs, samples)
    full = bool(arcs.full) and bool(motions)
    if not motions:
        return False, False, {}
    curves: dict[str, list[list[float] | None]] = {j: [] for j in mechanism.plan.traced}
    for i, motion in enumerate(motions):
        for joint, rows in curves.items():
            if i:
                rows.append(None)
            line = polyline(np.asarray(motion.positions[joint]), motion.valid)
            # Every circuit closes (a rocking one comes back down its other branch).
            rows.extend(line + line[:1] if line and line[0] is not None else line)
    return bool(motions), full, curves


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


class StudyRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples(
            {"document": EXAMPLE_DOCUMENT, "pivot": "B0", "direction": "right", "step": 0.5,
             "count": 2, "samples": 48}
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
    if not isinstance(m, GearedFiveBar):
        return None
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
        # pivot_study takes the drawing as plain sequences (the same numbers).
        points = {k: v.tolist() for k, v in drawing.items()}
        done = pivot_study(points, d.tolist(), step=step, count=count, ratio=ratio)
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
    linkwright.server.tools_study.StudyError: pivot: 'P' is not a fixed pivot of this linkage (its
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
    doc = read_document(body.document)
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
        assert isinstance(mech, GearedFiveBar)  # only a geared five-bar has paper 002's drawing
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

"""The workbench's ellipse tool (paper 004): ``POST /ellipse`` and ``POST /ellipse/trammel``.

An ellipse is fitted to drawn points, and paper 004's ∞² family of double sliders (elliptic
trammels) that trace it is browsed (:mod:`linkwright.synthesis.ellipse`), each member checked
against the ellipse.

Its own room (split from :mod:`linkwright.server.tools`): one tool, its requests and answers.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter
from pydantic import BaseModel, ConfigDict, Field, WithJsonSchema

from linkwright.engine import cost
from linkwright.io import mechanism_to_dict, parse_document
from linkwright.io.documents import WORKING_RANGE
from linkwright.mechanisms import DoubleSlider
from linkwright.server import budget, limits
from linkwright.server.schema import examples
from linkwright.server.tools_common import Points, drawn_points, example_ring
from linkwright.synthesis.ellipse import (
    EllipseError,
    Trammel,
    check_on_ellipse,
    doubleslider_family,
    family_angles,
    fit_ellipse,
)

__all__ = [
    "FAMILY_TOLERANCE",
    "EllipseRequest",
    "TrammelRequest",
    "ellipse",
    "ellipse_trammel",
    "router",
]

router = APIRouter()

FAMILY_TOLERANCE = 1e-9
"""Largest deviation from the ellipse (relative to its semi-major axis) a family member may
have; the construction is exact, so anything above rounding is a bug and is left out."""


Circle = Annotated[str, Field(json_schema_extra={"enum": ["small", "large"]})]


class EllipseRequest(BaseModel):
    model_config = ConfigDict(json_schema_extra=examples({"points": example_ring(24), "count": 4}))

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
    return Trammel(
        X0=np.asarray(cx, dtype=np.float64),
        Y0=np.asarray(cy, dtype=np.float64),
        beta=np.asarray(beta, dtype=np.float64),
        a=np.asarray(a, dtype=np.float64),
        b=np.asarray(b, dtype=np.float64),
    )


def _check_circle(circle: str) -> str:
    if circle not in ("small", "large"):
        shown = circle if len(circle) <= limits.TEXT.value else circle[: limits.TEXT.value] + "…"
        raise EllipseError(f"circle: must be 'small' or 'large', got {shown!r}")
    return circle


def _member(family: DoubleSlider, i: int | tuple[()]) -> DoubleSlider:
    member: dict[str, Any] = {
        k: np.asarray(getattr(family, k))[i] for k in ("M", "alpha", "beta", "p", "q", "h")
    }
    return DoubleSlider(**member)


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
    points = drawn_points(body.points, 5)
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

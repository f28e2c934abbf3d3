"""What the workbench's tools share: their error, the document and drawn points they read.

Every tools request names its problem in one line (:class:`ToolsError`, answered 422); a
document in a request is checked against the server's limits before it is parsed
(:func:`read_document`); a drawn curve is an (N, 2) array of finite points within the working
range (:func:`drawn_points`, typed for the schema as :data:`Points`), or on the sphere an (N, 3)
array of unit vectors (:func:`drawn_directions`; :func:`drawn_curve` takes either, typed as
:data:`CurvePoints`); what goes back is JSON
without NaN (:func:`json_number`, :func:`polyline`).

Its own room (split from :mod:`linkwright.server.tools`): the vocabulary of the tools, apart
from the tools themselves (:mod:`~linkwright.server.tools_study`,
:mod:`~linkwright.server.tools_match`, :mod:`~linkwright.server.tools_ellipse`,
:mod:`~linkwright.server.tools_export`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray
from pydantic import Strict, WithJsonSchema

from linkwright.io import Document, parse_document
from linkwright.io.documents import WORKING_RANGE
from linkwright.server import limits
from linkwright.server.schema import document_examples

__all__ = [
    "EXAMPLE_DOCUMENT",
    "MAX_POINTS",
    "CurvePoints",
    "Points",
    "ToolsError",
    "drawn_curve",
    "drawn_directions",
    "drawn_points",
    "example_ring",
    "json_number",
    "polyline",
    "read_document",
]

Array = NDArray[np.float64]
MAX_POINTS = limits.POINTS.value
"""Most points a drawn curve may have (:data:`linkwright.server.limits.POINTS`)."""


class ToolsError(ValueError):
    """A tools request that cannot be served as asked (names the field and the problem)."""


def read_document(mapping: Any) -> Document:
    limits.check_document(mapping)
    return parse_document(mapping, source="document")


_COORDINATE = {
    "type": "number",
    "minimum": -WORKING_RANGE.max_size,
    "maximum": WORKING_RANGE.max_size,
}


# Drawn points as the schema describes them; drawn_points checks them with messages naming the row.
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


# Strict numbers: JSON's true is not a coordinate (lax parsing read it as 1.0, accepting what
# the schema refuses); integers still are.
Points = Annotated[list[list[Annotated[float, Strict()]]], _POINTS_SCHEMA]

# A curve drawn in either space (the atlas match): drawn_curve tells them apart by the rows.
_CURVE_SCHEMA = WithJsonSchema(
    {
        "type": "array",
        "items": {"type": "array", "items": _COORDINATE, "minItems": 2, "maxItems": 3},
        "maxItems": limits.POINTS.value,
        "description": "The drawn curve: [x, y] rows in the plane, or [x, y, z] rows on the "
        "sphere (directions from its centre, normalised); every row alike.",
    }
)
CurvePoints = Annotated[list[list[Annotated[float, Strict()]]], _CURVE_SCHEMA]


def json_number(x: Any) -> float | None:
    """A JSON number, or null for NaN and infinities."""
    value = float(x)
    return value if math.isfinite(value) else None


def _counted(raw: Sequence[Sequence[float]], least: int, field: str) -> None:
    if len(raw) < least:
        raise ToolsError(f"{field}: a curve needs at least {least} points, got {len(raw)}")
    if len(raw) > MAX_POINTS:
        raise ToolsError(f"{field}: at most {MAX_POINTS:,} points, got {len(raw):,}")


def drawn_points(raw: Sequence[Sequence[float]], least: int, field: str = "points") -> Array:
    """Drawn points as an (N, 2) array, each row two finite numbers."""
    _counted(raw, least, field)
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
        at = int(huge[0])
        problem = WORKING_RANGE.size_problem(float(largest[at]))
        raise ToolsError(f"{field}: row {at}: a coordinate {problem}")
    return p


def drawn_directions(raw: Sequence[Sequence[float]], least: int, field: str = "points") -> Array:
    """Drawn points on the sphere as (N, 3) unit vectors: each row three finite numbers, not
    all zero, of which only the direction counts."""
    _counted(raw, least, field)
    for i, row in enumerate(raw):
        if len(row) != 3:
            raise ToolsError(
                f"{field}: row {i} has {len(row)} numbers; each point on the sphere is [x, y, z]"
            )
    p = np.asarray(raw, dtype=float).reshape(-1, 3)
    bad = ~np.all(np.isfinite(p), axis=1)
    if bad.any():
        raise ToolsError(f"{field}: row {int(np.flatnonzero(bad)[0])} is not finite")
    # Scaled by its largest number before the norm: [1e300]*3 would overflow it to inf and
    # [1e-320, 0, 0] underflow it to 0, though both are good directions.
    big = np.abs(p).max(axis=1, initial=0.0)
    zero = np.flatnonzero(big == 0.0)
    if zero.size:
        raise ToolsError(
            f"{field}: row {int(zero[0])} has 3 numbers, all zero: a point on the sphere is a "
            "direction [x, y, z] from its centre"
        )
    p = p / big[:, None]
    unit: Array = p / np.linalg.norm(p, axis=1)[:, None]
    return unit


def drawn_curve(
    raw: Sequence[Sequence[float]], least: int, field: str = "points"
) -> tuple[Array, str]:
    """A drawn curve and its space: (N, 2) points in the plane (:func:`drawn_points`) or (N, 3)
    unit vectors on the sphere (:func:`drawn_directions`). Row 0 says which; every row must
    have as many numbers."""
    _counted(raw, least, field)
    width = len(raw[0])
    if width not in (2, 3):
        raise ToolsError(
            f"{field}: row 0 has {width} numbers; each point is [x, y], or [x, y, z] on the sphere"
        )
    for i, row in enumerate(raw):
        if len(row) != width:
            raise ToolsError(
                f"{field}: row {i} has {len(row)} numbers but row 0 has {width}; every point is "
                "[x, y] (in the plane) or every one [x, y, z] (on the sphere)"
            )
    if width == 2:
        return drawn_points(raw, least, field), "plane"
    return drawn_directions(raw, least, field), "sphere"


def polyline(points: Array, valid: NDArray[np.bool_] | None = None) -> list[list[float] | None]:
    """Rows as [x, y] pairs, null where a sample could not be placed."""
    ok = np.all(np.isfinite(points), axis=-1)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    return [
        [float(x), float(y)] if k else None for (x, y), k in zip(points[:, :2], ok, strict=True)
    ]


EXAMPLE_DOCUMENT = document_examples()[0]


def example_ring(n: int, a: float = 3.0, b: float = 1.2) -> list[list[float]]:
    """An example drawn curve: n points around an ellipse."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return [
        [round(float(x), 6), round(float(y), 6)]
        for x, y in zip(a * np.cos(t), b * np.sin(t), strict=True)
    ]

"""Planar primitives: the few vector operations the engine's plane steps are built from.

Points and vectors are arrays whose last axis has length 2; every function broadcasts over the
leading axes, so one call handles a batch of mechanisms times a batch of input samples.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Meet",
    "circle_circle",
    "circle_line",
    "cross",
    "dot",
    "frame_error",
    "norm",
    "perp",
    "polar",
    "solve_2x2_rows",
    "unit_direction",
]

Array = NDArray[np.float64]

# A pair of circles whose normalised discriminant is above −MEET_TOL still meets: rounding at an
# exact tangency (a dyad's limit position) must not turn the tangency itself into a miss. The
# point is then the tangency's, off each circle by a relative residual of this size at most.
MEET_TOL = 1e-12


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis.

    >>> dot(np.array([1.0, 2.0]), np.array([3.0, 4.0]))
    np.float64(11.0)
    """
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def cross(a: Array, b: Array) -> Array:
    """Scalar (z) component of the cross product ``a × b``; positive when b is to the left of a.

    >>> cross(np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    np.float64(1.0)
    """
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def perp(a: Array) -> Array:
    """``a`` turned by +90° (counter-clockwise).

    >>> perp(np.array([1.0, 0.0]))
    array([0., 1.])
    """
    out = np.empty_like(a)
    out[..., 0] = -a[..., 1]
    out[..., 1] = a[..., 0]
    return out


def norm(a: Array) -> Array:
    """Euclidean length over the last axis.

    >>> norm(np.array([3.0, 4.0]))
    np.float64(5.0)
    """
    return np.hypot(a[..., 0], a[..., 1])


def frame_error(origin: Array, toward: Array, point: Array, u: ArrayLike, v: ArrayLike) -> Array:
    """How far ``point`` is from (u, v) in the frame origin→toward (x along it, v to the left).

    The residual of a rigid point on a link; NaN where origin and toward coincide.

    >>> frame_error(np.array([1.0, 1.0]), np.array([1.0, 3.0]), np.array([0.0, 2.0]), 1.0, 1.0)
    np.float64(0.0)
    """
    e = toward - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        e = e / norm(e)[..., None]
    rel = point - origin
    error: Array = np.hypot(dot(rel, e) - np.asarray(u), cross(e, rel) - np.asarray(v))
    return error


def polar(length: ArrayLike, angle: ArrayLike) -> Array:
    """The vector ``length·(cos angle, sin angle)``.

    >>> np.round(polar(2.0, np.pi / 2), 12)
    array([0., 2.])
    """
    length = np.asarray(length, dtype=float)
    angle = np.asarray(angle, dtype=float)
    return np.stack(np.broadcast_arrays(length * np.cos(angle), length * np.sin(angle)), axis=-1)


def unit_direction(angle: ArrayLike) -> Array:
    """Unit vector at ``angle`` (radians, counter-clockwise from +x).

    >>> unit_direction(0.0)
    array([1., 0.])
    """
    return polar(1.0, angle)


def solve_2x2_rows(row1: Array, row2: Array, rhs1: Array, rhs2: Array) -> tuple[Array, Array]:
    """Solve ``[row1; row2] · x = [rhs1; rhs2]`` by Cramer's rule, batched.

    Returns ``(x, det)``; ``x`` is inf/nan where ``det`` is zero (a singular position): the
    caller masks those samples, this function does not hide them.

    >>> x, det = solve_2x2_rows(np.array([2.0, 0.0]), np.array([0.0, 4.0]), 2.0, 8.0)
    >>> x, det
    (array([1., 2.]), np.float64(8.0))
    """
    det = cross(row1, row2)
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = (rhs1 * row2[..., 1] - rhs2 * row1[..., 1]) / det
        x1 = (row1[..., 0] * rhs2 - row2[..., 0] * rhs1) / det
    return np.stack((x0, x1), axis=-1), det


class Meet(NamedTuple):
    """Where two circles (plane) or small circles (sphere) meet, on one branch, batched."""

    point: Array
    """The meeting point, NaN where ``valid`` is False."""
    margin: Array
    """The normalised discriminant: sin² of the angle at the first centre between the line to
    the second centre and the line to the point; ≥ 0 where the circles meet, 0 where they touch,
    negative where they miss (NaN where the centres coincide)."""
    valid: NDArray[np.bool_]
    """The circles meet (within the tolerance) and the centres are distinct."""


def circle_circle(
    p1: ArrayLike,
    r1: ArrayLike,
    p2: ArrayLike,
    r2: ArrayLike,
    branch: ArrayLike,
    *,
    tol: float = MEET_TOL,
) -> Meet:
    """The point at ``r1`` from ``p1`` and ``r2`` from ``p2`` on ``branch``, batched.

    ``branch`` is the engine's dyad sign (DESIGN.md): the point P has
    ``sign((p2 − p1) × (P − p1)) = branch``. With d = |p2 − p1|, P lies at ``a`` along p1→p2
    and ``h`` to its left (times the branch), ``a = (r1² − r2² + d²)/(2d)`` and
    ``h² = ((r1 + r2)² − d²)(d² − (r1 − r2)²)/(4d²)``: each factor of h² is free of
    cancellation near its own root, and r1² − r2² is taken as (r1 − r2)(r1 + r2), so a
    tangency (outer or inner) and equal radii keep their digits. The margin is h²/r1².

    Points have a last axis of 2; radii and branch broadcast with the leading axes.

    Examples
    --------
    >>> meet = circle_circle([0.0, 0.0], 5.0, [8.0, 0.0], 5.0, 1.0)
    >>> meet.point, float(meet.margin), bool(meet.valid)
    (array([4., 3.]), 0.36, True)
    >>> circle_circle([0.0, 0.0], 1.0, [8.0, 0.0], 1.0, 1.0).point
    array([nan, nan])
    """
    p1, p2 = np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)
    r1, r2 = np.asarray(r1, dtype=float), np.asarray(r2, dtype=float)
    branch = np.asarray(branch, dtype=float)
    delta = p2 - p1
    d2 = dot(delta, delta)
    outer = (r1 + r2) ** 2 - d2
    inner = d2 - (r1 - r2) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        margin = outer * inner / (4.0 * d2 * r1 * r1)
        valid = (margin >= -tol) & (d2 > 0)
        d = np.sqrt(d2)
        a = ((r1 - r2) * (r1 + r2) + d2) / (2.0 * d)
        # NaN where the circles miss, so the point is NaN there (masking h costs half of
        # masking the point).
        h = r1 * np.sqrt(np.where(valid, np.clip(margin, 0.0, None), np.nan))
        point = p1 + (a[..., None] * delta + (branch * h)[..., None] * perp(delta)) / d[..., None]
    return Meet(point, margin, valid)


def circle_line(
    centre: ArrayLike,
    r: ArrayLike,
    line_point: ArrayLike,
    direction: ArrayLike,
    branch: ArrayLike,
    *,
    tol: float = MEET_TOL,
) -> Meet:
    """The point at ``r`` from ``centre`` on the line through ``line_point`` along the unit
    ``direction``, on ``branch``, batched.

    ``branch`` is the engine's slider sign (DESIGN.md): the point B has ``sign((B − H)·d) =
    branch``, H the foot of the centre on the line and d its direction. With s the centre's
    signed distance from the line, B = H ± √(r² − s²)·d; the margin ``(r − s)(r + s)/r²`` (cos²
    of the angle between the line and the radius to B) is taken in product form, exact near
    its root, where the circle touches the line.

    Examples
    --------
    >>> meet = circle_line([0.0, 3.0], 5.0, [0.0, 0.0], [1.0, 0.0], -1.0)
    >>> meet.point, float(meet.margin)
    (array([-4.,  0.]), 0.64)
    """
    centre, line_point = np.asarray(centre, dtype=float), np.asarray(line_point, dtype=float)
    d = np.asarray(direction, dtype=float)
    r, branch = np.asarray(r, dtype=float), np.asarray(branch, dtype=float)
    rel = centre - line_point
    along = dot(rel, d)
    offset = dot(rel, perp(d))
    with np.errstate(divide="ignore", invalid="ignore"):
        margin = (r - offset) * (r + offset) / (r * r)
        valid = margin >= -tol
        half = r * np.sqrt(np.where(valid, np.clip(margin, 0.0, None), np.nan))
    point = line_point + along[..., None] * d + (branch * half)[..., None] * d
    return Meet(point, margin, valid)

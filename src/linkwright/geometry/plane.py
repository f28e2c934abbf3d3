"""Planar primitives: the few vector operations the engine's plane steps are built from.

Points and vectors are arrays whose last axis has length 2; every function broadcasts over the
leading axes, so one call handles a batch of mechanisms times a batch of input samples.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
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
    return np.hypot(dot(rel, e) - np.asarray(u), cross(e, rel) - np.asarray(v))


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

"""Spherical primitives: the few operations the engine's sphere steps are built from.

Points on the unit sphere are unit vectors (the axes of a spherical linkage's revolute joints,
all through the sphere's centre O); a link is a great-circle arc measured by its central angle.
Every function broadcasts over leading axes, so one call handles a batch of mechanisms times a
batch of input samples, like :mod:`linkwright.geometry.plane`.

Angles about a point X are right-handed about +OX: looking at the sphere from outside, above X,
they turn counter-clockwise.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.geometry.plane import MEET_TOL

__all__ = [
    "ProjectionError",
    "SphereMeet",
    "angle_at",
    "arc",
    "best_rotation",
    "circle_frame",
    "circle_point",
    "clear_centre",
    "cross",
    "dot",
    "frame_error",
    "gram",
    "lambert_azimuthal",
    "map_frame",
    "norm",
    "on_circle",
    "point_at",
    "rotate",
    "small_circles",
    "solve_3x3_rows",
    "tangent",
    "unit",
]

Array = NDArray[np.float64]


def dot(a: Array, b: Array) -> Array:
    """Dot product over the last axis.

    >>> dot(np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0, 6.0]))
    np.float64(32.0)
    """
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def cross(a: Array, b: Array) -> Array:
    """Cross product over the last axis (batched).

    >>> cross(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    array([0., 0., 1.])
    """
    a, b = np.broadcast_arrays(a, b)
    out = np.empty(a.shape, dtype=np.result_type(a, b, float))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def norm(a: Array) -> Array:
    """Euclidean length over the last axis.

    >>> norm(np.array([2.0, 3.0, 6.0]))
    np.float64(7.0)
    """
    return np.sqrt(dot(a, a))


def unit(a: ArrayLike) -> Array:
    """``a`` scaled to length 1 (NaN for the zero vector).

    >>> unit([0.0, 3.0, 4.0])
    array([0. , 0.6, 0.8])
    """
    a = np.asarray(a, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return a / norm(a)[..., None]


def arc(a: Array, b: Array) -> Array:
    """Central angle between unit vectors (radians, in [0, π]), accurate at 0 and π alike.

    >>> float(np.degrees(arc(np.array([1.0, 0, 0]), np.array([0.0, 1, 0]))))
    90.0
    """
    return np.arctan2(norm(cross(a, b)), dot(a, b))


def tangent(at: Array, toward: Array) -> Array:
    """Unit tangent at ``at`` along the great circle towards ``toward``.

    NaN where the two are equal or antipodal (no great circle is singled out).

    >>> tangent(np.array([0.0, 0, 1]), np.array([1.0, 0, 1]) / 2**0.5).round(12)
    array([1., 0., 0.])
    """
    return unit(toward - dot(toward, at)[..., None] * at)


def rotate(v: Array, axis: Array, angle: ArrayLike) -> Array:
    """``v`` turned by ``angle`` right-handed about the unit ``axis`` (Rodrigues' formula).

    This is paper 000's matrix T (eq. 6) applied to a vector.

    >>> rotate(np.array([0.0, 1, 0]), np.array([1.0, 0, 0]), np.pi / 2).round(12)
    array([0., 0., 1.])
    """
    angle = np.asarray(angle, dtype=float)[..., None]
    c, s = np.cos(angle), np.sin(angle)
    rotated: Array = v * c + cross(axis, v) * s + axis * dot(axis, v)[..., None] * (1.0 - c)
    return rotated


def point_at(origin: Array, toward: Array, length: ArrayLike, angle: ArrayLike) -> Array:
    """The point at arc ``length`` from ``origin``, at ``angle`` from the great circle
    origin→toward (right-handed about +O·origin).

    How a rigid point sits on a spherical link: paper 000's coupler point C (arc AC, μ = BAC),
    computed by rotating the great circle A→B about OA by μ and walking the arc AC from A.

    >>> a, b = np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    >>> point_at(a, b, np.pi / 2, np.pi / 2).round(12)
    array([0., 0., 1.])
    """
    t = tangent(origin, toward)
    return circle_point(origin, t, cross(origin, t), length, angle)


def circle_point(o: Array, e1: Array, e2: Array, arc_: ArrayLike, theta: ArrayLike) -> Array:
    """``cos arc · o + sin arc (cos θ e1 + sin θ e2)``: the point at angle θ on the small circle
    of ``arc_`` about ``o``, angles from ``e1`` towards ``e2`` (the rows of
    :func:`circle_frame`, given apart where a batch should not pay for stacking them).

    The one formula for a point on a small circle: :func:`on_circle`, :func:`point_at`,
    :func:`small_circles` and the spherical crank use it.

    >>> x, y, z = np.eye(3)
    >>> circle_point(z, x, y, np.pi / 2, np.pi / 2).round(12) + 0.0
    array([0., 1., 0.])
    """
    arc_ = np.asarray(arc_, dtype=float)[..., None]
    theta = np.asarray(theta, dtype=float)[..., None]
    point: Array = np.cos(arc_) * o + np.sin(arc_) * (np.cos(theta) * e1 + np.sin(theta) * e2)
    return point


def circle_frame(axis: ArrayLike, ref: ArrayLike, sense: ArrayLike = 1.0) -> Array:
    """The frame (O, e1, e2) of a small circle about ``axis``, angles measured from ``ref``.

    ``e1`` is the unit tangent at O towards ``ref`` (only its part normal to O counts) and
    ``e2 = sense · (O × e1)``: ``sense = 1`` measures angles right-handed about +O, ``-1``
    left-handed (paper 001 measures θ1 = ∠BAD and θ4 = ∠CDG that way round).

    Returns ``(..., 3, 3)``, the rows O, e1, e2; NaN where ``ref`` is ±O.

    Examples
    --------
    Paper 001's input circle: A = (0, 0, 1), θ1 from the great circle A→D, and eq. 5's
    B = (sin a2 sin θ1, sin a2 cos θ1, cos a2), which turns from +y towards +x:

    >>> a1 = np.radians(60.0)
    >>> circle_frame([0.0, 0.0, 1.0], [0.0, np.sin(a1), np.cos(a1)], -1.0).round(12) + 0.0
    array([[0., 0., 1.],
           [0., 1., 0.],
           [1., 0., 0.]])
    """
    o = np.asarray(axis, dtype=float)
    e1 = tangent(o, np.asarray(ref, dtype=float))
    e2 = np.asarray(sense, dtype=float)[..., None] * cross(o, e1)
    return np.stack(np.broadcast_arrays(o, e1, e2), axis=-2)


def on_circle(frame: ArrayLike, arc_: ArrayLike, theta: ArrayLike) -> Array:
    """The point at angle ``theta`` on the small circle of ``arc_`` in ``frame`` (rows O, e1, e2).

    ``cos arc · O + sin arc (cos θ e1 + sin θ e2)``, batched over the leading axes of all three.

    Examples
    --------
    >>> frame = circle_frame([0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    >>> on_circle(frame, np.pi / 2, np.pi / 2).round(12) + 0.0
    array([0., 1., 0.])
    """
    frame = np.asarray(frame, dtype=float)
    return circle_point(frame[..., 0, :], frame[..., 1, :], frame[..., 2, :], arc_, theta)


class SphereMeet(NamedTuple):
    """Where two small circles meet, on one branch: as
    :class:`linkwright.geometry.plane.Meet`, and the normal ``p1 × p2`` whose sign against the
    point is the branch."""

    point: Array
    margin: Array
    valid: NDArray[np.bool_]
    normal: Array


def small_circles(
    p1: ArrayLike,
    r1: ArrayLike,
    p2: ArrayLike,
    r2: ArrayLike,
    branch: ArrayLike,
    *,
    tol: float = MEET_TOL,
) -> SphereMeet:
    """The point at arc ``r1`` from ``p1`` and arc ``r2`` from ``p2`` on ``branch``, batched.

    ``branch`` is the engine's dyad sign on the sphere (DESIGN.md): the point X has
    ``sign((p1 × p2)·X) = branch``. With d the arc p1p2 and φ the angle at p1 between the great
    circles p1→p2 and p1→X (spherical triangle p1 p2 X with sides d, r1, r2)::

        sin φ · sin r1 sin d = ±√G,   cos φ · sin r1 sin d = cos r2 − cos r1 cos d,

    G the Gram determinant (:func:`gram`, in product form, so a tangency keeps its digits). The
    margin is ``sin² φ = G / (sin² d sin² r1)``, 0 where the circles touch, as in the plane
    (:func:`linkwright.geometry.plane.circle_circle`).

    The frame at p1 (t towards p2, n = p1 × t) is built from the vectors, not from sin d:
    (p1 × p2) × p1 is p2's part normal to p1 and stays normal to p1 to rounding even when it
    is itself only rounding (p2 − cos d·p1 would not), so X is a unit vector however close p1
    and p2 come. Where they are parallel to rounding, t is arbitrary but still a unit normal
    to p1, and the circles can only meet there if r1 ≈ r2 (X may then sit anywhere on its
    circle): X still meets both arcs.

    Examples
    --------
    Two circles of 60° about the x and y axes meet above and below the xy plane:

    >>> x, y = np.eye(3)[:2]
    >>> up = small_circles(x, np.pi / 3, y, np.pi / 3, 1.0)
    >>> (up.point * 2).round(12) + 0.0, bool(up.valid)
    (array([1.      , 1.      , 1.414214]), True)
    >>> bool(small_circles(x, 0.1, y, 0.1, 1.0).valid)  # 90° apart, 0.2 rad cannot reach
    False
    """
    p1, p2 = np.asarray(p1, dtype=float), np.asarray(p2, dtype=float)
    r1, r2 = np.asarray(r1, dtype=float), np.asarray(r2, dtype=float)
    w = cross(p1, p2)
    sin_d = norm(w)
    cos_d = dot(p1, p2)
    g = gram(np.arctan2(sin_d, cos_d), r1, r2)
    with np.errstate(divide="ignore", invalid="ignore"):
        margin = g / (sin_d * np.sin(r1)) ** 2
        valid = (margin >= -tol) & (sin_d > 0)
    t = unit(cross(w, p1))
    # NaN where the circles miss, so the point is NaN there.
    phi = np.arctan2(
        np.asarray(branch, dtype=float) * np.sqrt(np.where(valid, np.clip(g, 0.0, None), np.nan)),
        np.cos(r2) - np.cos(r1) * cos_d,
    )
    point = circle_point(p1, t, cross(p1, t), r1, phi)
    return SphereMeet(point, margin, valid, w)


def angle_at(at: Array, a: Array, b: Array) -> Array:
    """The angle at ``at`` from the great circle at→a to at→b, right-handed about +O·at.

    In (−π, π]. Inverse of :func:`point_at`: ``angle_at(o, t, point_at(o, t, l, x)) == x``.

    >>> o, a, b = np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    >>> float(np.degrees(angle_at(o, a, b)))
    90.0
    """
    ta, tb = tangent(at, a), tangent(at, b)
    return np.arctan2(dot(at, cross(ta, tb)), dot(ta, tb))


def gram(x: ArrayLike, y: ArrayLike, z: ArrayLike) -> Array:
    """Gram determinant of three unit vectors whose pairwise arcs are x, y, z.

    ``1 − cos²x − cos²y − cos²z + 2 cos x cos y cos z``, evaluated as the product
    ``4 sin s sin(s − x) sin(s − y) sin(s − z)`` with s = (x + y + z)/2, so that it is accurate
    near each of its roots: where three arcs just close into a (degenerate) spherical triangle,
    i.e. at a dyad's limit position. It is the squared volume of the three vectors, ≥ 0 exactly
    when such a triangle exists.

    >>> x, y, z = np.radians([50.0, 60.0, 70.0])
    >>> c = np.cos([x, y, z])
    >>> bool(np.isclose(gram(x, y, z), 1 - (c**2).sum() + 2 * c.prod()))
    True
    >>> float(gram(0.5, 0.25, 0.25))  # a degenerate triangle: 0.5 = 0.25 + 0.25
    0.0
    """
    x, y, z = (np.asarray(v, dtype=float) for v in (x, y, z))
    s = 0.5 * (x + y + z)
    value: Array = 4.0 * np.sin(s) * np.sin(s - x) * np.sin(s - y) * np.sin(s - z)
    return value


def solve_3x3_rows(
    row1: Array, row2: Array, row3: Array, rhs1: Array, rhs2: Array, rhs3: Array
) -> tuple[Array, Array]:
    """Solve ``[row1; row2; row3] · x = [rhs1; rhs2; rhs3]`` by Cramer's rule, batched.

    Returns ``(x, det)``; ``x`` is inf/NaN where ``det`` is zero (a singular position): the
    caller masks those samples.

    >>> rows = np.eye(3) * 2.0
    >>> solve_3x3_rows(rows[0], rows[1], rows[2], 2.0, 4.0, 6.0)
    (array([1., 2., 3.]), np.float64(8.0))
    """
    c23, c31, c12 = cross(row2, row3), cross(row3, row1), cross(row1, row2)
    det = dot(row1, c23)
    rhs1, rhs2, rhs3 = (np.asarray(r, dtype=float)[..., None] for r in (rhs1, rhs2, rhs3))
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (rhs1 * c23 + rhs2 * c31 + rhs3 * c12) / det[..., None]
    return x, det


def frame_error(
    origin: Array, toward: Array, point: Array, length: ArrayLike, angle: ArrayLike
) -> Array:
    """How far (chord length) ``point`` is from its place on the link origin→toward.

    The residual of a rigid point on a spherical link, the sphere's
    :func:`linkwright.geometry.plane.frame_error`.

    >>> a, b = np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    >>> float(frame_error(a, b, np.array([0.0, 0, 1]), np.pi / 2, np.pi / 2)) < 1e-15
    True
    """
    return norm(point - point_at(origin, toward, length, angle))


class ProjectionError(ValueError):
    """A direction that a map projection cannot place (zero, infinite, or the antipode)."""


_Y_AXIS = np.array([0.0, 1.0, 0.0])
_Z_AXIS = np.array([0.0, 0.0, 1.0])


def _direction(v: ArrayLike, name: str) -> Array:
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ProjectionError(f"{name}: must be a 3-vector (or an array of them)") from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ProjectionError(f"{name}: must have a last axis of length 3, got shape {arr.shape}")
    if np.any(np.isinf(arr)):
        raise ProjectionError(f"{name}: must not be infinite")
    length = norm(arr)
    if np.any(length == 0):
        raise ProjectionError(f"{name}: the zero vector has no direction")
    return arr / length[..., None]


def map_frame(centre: ArrayLike, north: ArrayLike | None = None) -> tuple[Array, Array]:
    """(east, north) unit vectors of a map's tangent plane at ``centre``, seen from outside.

    North is the part of ``north`` (default +Z) normal to the centre; where that vanishes (a map
    centred on the pole of the hint) +Y, or +Z for an explicit hint, stands in. East = north ×
    centre, so the map is seen from outside the sphere.

    >>> east, up = map_frame([1.0, 0.0, 0.0])
    >>> east, up
    (array([0., 1., 0.]), array([0., 0., 1.]))
    """
    c = _direction(centre, "centre")
    if c.shape != (3,):
        raise ProjectionError(f"centre: must be one 3-vector, got shape {c.shape}")
    hint = _Z_AXIS if north is None else _direction(north, "north")
    if hint.shape != (3,):
        raise ProjectionError(f"north: must be one 3-vector, got shape {hint.shape}")
    if north is not None and norm(cross(hint, c)) < 1e-9:
        raise ProjectionError("north: must not lie along the centre")
    n = hint - (hint @ c) * c
    if norm(n) < 1e-9:
        alt = _Y_AXIS if north is None else (_Z_AXIS if abs(c[2]) < 0.9 else _Y_AXIS)
        n = alt - (alt @ c) * c
    n = n / norm(n)
    return cross(n, c), n


def lambert_azimuthal(
    points: ArrayLike, centre: ArrayLike, *, north: ArrayLike | None = None
) -> Array:
    """Lambert azimuthal equal-area projection of directions onto the plane of a map.

    The map is centred on ``centre`` and seen from outside the sphere, ``north`` drawn up
    (:func:`map_frame`). A direction p at arc δ from the centre goes to distance 2 sin(δ/2)
    from the origin, along its bearing: with E, N the map's east and north unit vectors,
    ``x = k p·E``, ``y = k p·N`` with ``k = √(2 / (1 + p·c))`` (Snyder, *Map Projections: A
    Working Manual*, USGS Professional Paper 1395, 1987, eqs. 24-2 to 24-4, in vector form).
    Areas on the unit sphere are kept: a region of solid angle Ω covers area Ω on the map, so
    a curve's map shows how much of the sphere it encloses; shapes are sheared away from the
    centre.

    Parameters
    ----------
    points : array_like, shape (..., 3)
        Directions (lengths ignored); rows holding NaN (a linkage not assembled) map to NaN.
    centre : array_like, shape (3,)
        The direction at the map's origin.
    north : array_like, shape (3,), optional
        The direction drawn upwards (its part normal to ``centre``); default +Z.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Map coordinates, in units of the sphere's radius (the whole sphere fills the disc of
        radius 2).

    Raises
    ------
    ProjectionError
        For a point at the antipode of the centre (it maps to the whole rim, not one point), a
        zero or infinite vector, or a ``north`` along the centre.

    Examples
    --------
    Centred on +X with +Z up: +Y is east, 90° away at √2; the centre maps to the origin.

    >>> lambert_azimuthal([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [1, 0, 0]).round(6) + 0.0
    array([[0.      , 0.      ],
           [1.414214, 0.      ],
           [0.      , 1.414214]])

    The antipode has no one place on the map:

    >>> lambert_azimuthal([[-1, 0, 0]], [1, 0, 0])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.geometry.sphere.ProjectionError: lambert_azimuthal: a point lies at the antipode ...
    """
    east, up = map_frame(centre, north)
    c = cross(east, up)  # the unit centre: east = north × centre
    p = _direction(points, "points")
    with np.errstate(invalid="ignore"):
        one_plus = 1.0 + p @ c
        if np.any(one_plus < 1e-12):
            raise ProjectionError(
                "lambert_azimuthal: a point lies at the antipode of the centre, which maps to "
                "the whole rim of the map"
            )
        k = np.sqrt(2.0 / one_plus)
    return np.stack((k * (p @ east), k * (p @ up)), axis=-1)


# How far (1 + p·c) a drawn point keeps from the centre's antipode: 1e-6 is 0.08° of arc, where
# the map is still one point (a point at 1e-12 and nearer is refused as the whole rim).
CLEAR = 1e-6
# Tilts tried, in degrees, each in eight bearings: the first centre clear of every point wins.
_TILTS = (2.0, 5.0, 10.0, 20.0, 45.0, 90.0)


def clear_centre(preferred: ArrayLike, points: ArrayLike) -> Array:
    """A map centre near ``preferred`` with none of ``points`` at its antipode.

    The antipode of a Lambert map's centre has no one place on the map (it is the whole rim),
    so a centre chosen as the mean direction of some curves is refused where another drawn point
    lies there (a pivot opposite a curve's mean; a joint passing through it). Such a centre is
    tilted by the least of a few angles, in one of eight bearings, that keeps every point at
    least ``CLEAR`` (in 1 + p·c) from the antipode; with none, the tilt that keeps them
    furthest. Rows holding NaN are ignored.

    >>> c = clear_centre([1.0, 0.0, 0.0], [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    >>> bool(1.0 + c @ [-1.0, 0.0, 0.0] > 1e-6), round(float(np.degrees(np.arccos(c[0]))), 6)
    (True, 2.0)
    >>> clear_centre([0.0, 0.0, 2.0], [[1.0, 0.0, 0.0]])  # nothing opposite: as given
    array([0., 0., 1.])
    """
    c = _direction(preferred, "centre")
    if c.shape != (3,):
        raise ProjectionError(f"centre: must be one 3-vector, got shape {c.shape}")
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    pts = pts[np.isfinite(pts).all(axis=1)]
    if pts.size == 0:
        return c
    pts = pts / norm(pts)[:, None]

    def clearance(centre: Array) -> float:
        return float(np.min(1.0 + pts @ centre))

    if clearance(c) >= CLEAR:
        return c
    east, up = map_frame(c)
    best, best_gap = c, clearance(c)
    for tilt in np.radians(_TILTS):
        for bearing in np.radians(np.arange(0.0, 360.0, 45.0)):
            way = np.cos(bearing) * east + np.sin(bearing) * up
            trial: Array = np.cos(tilt) * c + np.sin(tilt) * way
            gap = clearance(trial)
            if gap >= CLEAR:
                return trial
            if gap > best_gap:
                best, best_gap = trial, gap
    return best


def best_rotation(h: Array) -> tuple[Array, Array]:
    """max over proper rotations R of tr(R·h) (…,) and the R (…, 3, 3) that reaches it, for 3 × 3
    matrices h (…, 3, 3); NaN where h is not finite.

    With h = Σ p qᵀ over paired points, R is the rotation laying the p on the q best (least
    ``Σ |R·p − q|²``, Wahba's problem): with h = U Σ Vᵀ, R = V·diag(1, 1, d)·Uᵀ, d = det(V·Uᵀ), and
    the value is σ1 + σ2 + d·σ3 (Kabsch).

    >>> turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    >>> p = np.eye(3)
    >>> value, r = best_rotation(p.T @ (p @ turn.T))
    >>> float(value), bool(np.allclose(r, turn))
    (3.0, True)
    """
    ok = np.asarray(np.isfinite(h).all(axis=(-2, -1)))
    u, sigma, vt = np.linalg.svd(np.where(ok[..., None, None], h, 0.0))
    d = np.where(np.linalg.det(u) * np.linalg.det(vt) < 0, -1.0, 1.0)
    v = np.swapaxes(vt, -1, -2).copy()
    v[..., 2] *= d[..., None]
    value = sigma[..., 0] + sigma[..., 1] + d * sigma[..., 2]
    r = v @ np.swapaxes(u, -1, -2)
    return np.where(ok, value, np.nan), np.where(ok[..., None, None], r, np.nan)

"""The orthographic view of the unit sphere that the spherical pictures share, and its choice.

A spherical linkage lives on the unit sphere (every joint is the unit vector along its revolute
axis, every link a great-circle arc). This module holds the geometry of looking at it: the
great-circle sampler (:func:`great_arc`), the camera (:class:`SphereView`: a point projects to
its components along the page's right and up, and is near when it faces the eye), the checks
of the vectors a caller hands in, and the default viewing direction of a linkage
(:func:`default_view`): the normalised mean of the ground pivots, raised 35° out of the great
circle that fits them best, then turned to keep every joint, over its whole circuit, clear of
the rim and of the far side. The great circle through the ground pivots is kept level on the
page, so the frame reads like a drawing board.

The drawing itself is in :mod:`linkwright.plot.sphere_draw` and the figures in
:mod:`linkwright.plot.sphere`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import (
    Fixed,
    Motion,
)
from linkwright.geometry import sphere
from linkwright.mechanisms import Mechanism, circuits

__all__ = [
    "BACK_ALPHA",
    "BODY",
    "CURVES",
    "ELEVATION",
    "GROUND",
    "LINK",
    "MINUS",
    "Z_AXIS",
    "SpherePlotError",
    "SphereView",
    "check_curve",
    "default_view",
    "fit_normal",
    "great_arc",
    "ground_pivots",
    "mean_direction",
    "require_sphere",
    "resolve_view",
    "safe_arc",
    "sphere_links",
    "upright",
    "view_of_circuits",
]

Array = NDArray[np.float64]


LINK = "#1f3b57"


GROUND = "#6b6b6b"


BODY = "#9ecae1"


CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")


MINUS = "\N{MINUS SIGN}"


ELEVATION = math.radians(35.0)


BACK_ALPHA = 0.4  # how much of its colour a far-side stroke keeps


Z_AXIS = np.array([0.0, 0.0, 1.0])


_Y = np.array([0.0, 1.0, 0.0])


class SpherePlotError(ValueError):
    """Input that cannot be drawn on the sphere (names the argument and the problem)."""


def great_arc(a: ArrayLike, b: ArrayLike, samples: int = 48) -> Array:
    """Points along the shorter great-circle arc from ``a`` to ``b``, both ends included.

    Vectorised over leading axes: ``a`` and ``b`` of shape ``(..., 3)`` (broadcast together)
    give ``(..., samples, 3)``. The inputs are directions (their lengths are ignored); every
    sample is a unit vector, spaced evenly in angle: with Ω the arc between the two and T the
    unit tangent at ``a`` towards ``b`` (``(a × b) × a`` normalised), sample k is
    ``cos(kΩ/(n−1))·a + sin(kΩ/(n−1))·T`` (spherical linear interpolation written in the
    tangent frame; the end samples are ``a`` and ``b`` themselves).

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Start and end directions.
    samples : int
        Number of points, at least 2.

    Returns
    -------
    numpy.ndarray, shape (..., samples, 3)
        The first sample is ``a / |a|``, the last ``b / |b|``. Where a and b coincide every
        sample is that point.

    Raises
    ------
    SpherePlotError
        If a vector is zero, not finite or not of length 3, if ``samples < 2``, or if a and b
        are antipodal (no great circle is singled out).

    Examples
    --------
    >>> great_arc([1.0, 0, 0], [0, 1.0, 0], 3).round(6)
    array([[1.      , 0.      , 0.      ],
           [0.707107, 0.707107, 0.      ],
           [0.      , 1.      , 0.      ]])

    Antipodal ends have no one great circle between them:

    >>> great_arc([0, 0, 1.0], [0, 0, -1.0])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.sphere_view.SpherePlotError: great_arc: a and b are antipodal (arc 180°), ...
    """
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 2:
        raise SpherePlotError(f"great_arc: samples must be an integer ≥ 2, got {samples!r}")
    a = _directions(a, "a")
    b = _directions(b, "b")
    a, b = np.broadcast_arrays(a, b)
    omega = sphere.arc(a, b)
    if np.any(omega > math.pi - 1e-12):
        raise SpherePlotError(
            "great_arc: a and b are antipodal (arc 180°), so no great circle joins them uniquely"
        )
    # T = (a × b) × a, normalised: orthogonal to a to rounding however close b is to −a
    # (b − (a·b)a would lose that orthogonality as 1/sin Ω), so every sample stays unit.
    with np.errstate(invalid="ignore", divide="ignore"):
        t = sphere.unit(sphere.cross(sphere.cross(a, b), a))
    same = ~np.all(np.isfinite(t), axis=-1)
    t = np.where(same[..., None], 0.0, t)
    k = np.linspace(0.0, 1.0, samples)
    angle = omega[..., None] * k  # (..., samples)
    out: Array = (
        np.cos(angle)[..., None] * a[..., None, :] + np.sin(angle)[..., None] * t[..., None, :]
    )
    out[..., 0, :] = a
    out[..., -1, :] = b
    return out


def _directions(v: ArrayLike, name: str) -> Array:
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise SpherePlotError(f"{name}: must be a 3-vector (or an array of them)") from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise SpherePlotError(f"{name}: must have a last axis of length 3, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SpherePlotError(f"{name}: must be finite")
    length = sphere.norm(arr)
    if np.any(length == 0):
        raise SpherePlotError(f"{name}: the zero vector has no direction")
    return arr / length[..., None]


class SphereView:
    """An orthographic camera: ``eye`` (unit, towards the viewer), ``right`` and ``up`` on the
    page. A point p projects to (p·right, p·up); it is on the near side when p·eye ≥ 0.

    With :func:`stroke` and :func:`great_arc` it draws on the sphere things that are not a
    plan-built linkage (paper 001's triad configurations)."""

    def __init__(self, eye: Array, up_hint: Array | None = None) -> None:
        self.eye = eye
        hint = Z_AXIS if up_hint is None else up_hint
        right = sphere.cross(hint, eye)
        if sphere.norm(right) < 1e-6:  # looking along the hint: any other "up" will do
            right = sphere.cross(_Y if abs(eye[1]) < 0.9 else Z_AXIS, eye)
        self.right = right / sphere.norm(right)
        self.up = sphere.cross(eye, self.right)

    def xy(self, p: Array) -> Array:
        return np.stack((p @ self.right, p @ self.up), axis=-1)

    def depth(self, p: Array) -> Array:
        return p @ self.eye

    def split(self, p: Array) -> tuple[Array, Array]:
        """Page coordinates of a polyline's near and far parts, NaN-broken, meeting on the rim.

        Where consecutive samples lie on opposite sides, the crossing point (moved onto the
        rim, depth 0) is inserted into both parts, so they join without a gap at the outline.
        """
        p = np.asarray(p, dtype=float).reshape(-1, 3)
        d = self.depth(p)
        with np.errstate(invalid="ignore"):
            flips = np.nonzero((d[:-1] * d[1:] < 0) & np.isfinite(d[:-1] * d[1:]))[0]
        if flips.size:
            t = d[flips] / (d[flips] - d[flips + 1])
            q = p[flips] + t[:, None] * (p[flips + 1] - p[flips])
            q = q - self.depth(q)[:, None] * self.eye
            q = q / sphere.norm(q)[:, None]
            p = np.insert(p, flips + 1, q, axis=0)
            d = np.insert(d, flips + 1, 0.0)
        xy = self.xy(p)
        with np.errstate(invalid="ignore"):
            near, far = d >= 0, d <= 0
        return np.where(near[:, None], xy, np.nan), np.where(far[:, None], xy, np.nan)


def resolve_view(view: ArrayLike | None, up: ArrayLike | None, fallback: Array) -> SphereView:
    eye = fallback if view is None else _directions(view, "view")
    if eye.shape != (3,):
        raise SpherePlotError(f"view: must be one 3-vector, got shape {eye.shape}")
    hint = None if up is None else _directions(up, "up")
    if hint is not None and hint.shape != (3,):
        raise SpherePlotError(f"up: must be one 3-vector, got shape {hint.shape}")
    return SphereView(eye, hint)


def safe_arc(a: Array, b: Array) -> Array | None:
    """The arc a→b, or None where it is not drawable (a joint not placed, antipodal ends)."""
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return None
    try:
        return great_arc(a, b)
    except SpherePlotError:
        return None


def check_curve(label: str, points: ArrayLike) -> Array:
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise SpherePlotError(f"curve {label!r}: must be an (N, 3) array of numbers") from None
    if p.ndim != 2 or p.shape[1] != 3:
        raise SpherePlotError(f"curve {label!r}: must have shape (N, 3), got {p.shape}")
    finite = np.all(np.isfinite(p), axis=1)
    if np.any(np.isinf(p)):
        raise SpherePlotError(f"curve {label!r}: holds infinite coordinates")
    off = np.abs(sphere.norm(p[finite]) - 1.0)
    if off.size and off.max() > 1e-6:
        raise SpherePlotError(
            f"curve {label!r}: points must be unit vectors (largest | |p| − 1 | is {off.max():.3g})"
        )
    return p


def mean_direction(points: Array, fallback: Array) -> Array:
    pts = points[np.all(np.isfinite(points), axis=-1)] if points.size else points
    if pts.size == 0:
        return fallback
    m = pts.mean(axis=0)
    size = sphere.norm(m)
    return m / size if size > 1e-9 else fallback


def require_sphere(mechanism: Mechanism) -> None:
    if not isinstance(mechanism, Mechanism):
        raise SpherePlotError(f"mechanism: expected a linkwright Mechanism, got {mechanism!r}")
    if mechanism.space != "sphere":
        raise SpherePlotError(
            f"mechanism: {type(mechanism).__name__} is a planar linkage; draw it with "
            "linkwright.plot.generic.plot_linkage"
        )
    if mechanism.batch_shape != ():
        raise SpherePlotError(
            f"mechanism: draw one linkage at a time, this one has batch shape "
            f"{mechanism.batch_shape}"
        )


def ground_pivots(mechanism: Mechanism) -> dict[str, Array]:
    """The ground pivots from the parameters, so they are known even where nothing assembles."""
    params = mechanism.params()
    return {
        s.name: np.asarray(params[s.at], dtype=float)
        for s in mechanism.plan.steps
        if isinstance(s, Fixed)
    }


def sphere_links(
    mechanism: Mechanism,
) -> tuple[list[tuple[str, str]], list[tuple[str, ...]]]:
    """Binary links as joint pairs, and rigid bodies as triangles, from the plan's steps (a
    rigid point's sides are the triangle's edges, not links of their own)."""
    plan = mechanism.plan
    plates = list(plan.plates)
    edges = {frozenset(pair) for plate in plates for pair in itertools.pairwise((*plate, plate[0]))}
    pairs = [pair for pair in plan.links if frozenset(pair) not in edges]
    return pairs, plates


def default_view(mechanism: Mechanism, *, samples: int = 180) -> Array:
    """The direction :func:`plot_spherical_linkage` looks from unless told otherwise.

    The starting point is the normalised mean g of the ground pivots, raised by 35° towards n,
    the normal of the great circle that fits the ground pivots best (the weakest singular
    direction of their stacked unit vectors), signed towards the mean of the moving joints
    (+Z side on a tie). Coupler points often swing far from the frame, so the view is then
    chosen among 2000 directions spread evenly over the sphere (and that starting one) to keep
    every point clear of the rim and of the far side: each point scores its depth capped at
    0.35 (about 20° inside the rim), the ground pivots weighing as much together as all the
    moving joints over the circuit, with a small bonus for nearness to the starting direction.
    A linkage that never assembles is seen from the starting direction.

    Parameters
    ----------
    mechanism : Mechanism
        One spherical linkage (not a batch).
    samples : int
        Circuit samples of the moving joints taken into account.

    Returns
    -------
    numpy.ndarray, shape (3,)
        A unit vector.

    Raises
    ------
    SpherePlotError
        For a planar linkage or a batch of mechanisms.

    Examples
    --------
    Paper 000's Fig. 6 four-bar: its coupler point swings 50° beyond the crank, yet every
    joint stays on the near hemisphere all the way round:

    >>> from linkwright.mechanisms import SphericalFourBar, circuit
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> v = default_view(fig6)
    >>> round(float(np.linalg.norm(v)), 12)
    1.0
    >>> m = circuit(fig6, 180, order=0)
    >>> {k: bool(np.all(p @ v > 0.3)) for k, p in m.positions.items()}
    {'A0': True, 'B0': True, 'A': True, 'B': True, 'P': True}

    A linkage that never assembles is seen from its ground pivots (here at 0° and 90° on the
    equator), raised 35°:

    >>> v = default_view(SphericalFourBar(*np.radians([90, 10, 20, 30])))
    >>> np.degrees(np.arcsin(v[2])).round(6), bool(np.isclose(v[0], v[1]))
    (np.float64(35.0), True)
    """
    require_sphere(mechanism)
    return view_of_circuits(mechanism, circuits(mechanism, samples, order=0)[1])


def view_of_circuits(mechanism: Mechanism, circuits: list[Motion]) -> Array:
    ground = np.array(list(ground_pivots(mechanism).values())).reshape(-1, 3)
    moving = [
        m.positions[s.name]
        for m in circuits
        for s in mechanism.plan.steps
        if not isinstance(s, Fixed)
    ]
    moving_pts = np.concatenate(moving) if moving else np.zeros((0, 3))
    every = np.concatenate((ground, moving_pts))
    fallback = mean_direction(every, np.ones(3) / math.sqrt(3.0))
    g = mean_direction(ground, fallback)
    n = fit_normal(ground, g)
    side = mean_direction(moving_pts, np.zeros(3)) if moving_pts.size else np.zeros(3)
    lean = float(side @ n)
    if abs(lean) < 1e-9:
        lean = float(n @ Z_AXIS) if abs(float(n @ Z_AXIS)) > 1e-9 else 1.0
    n = n if lean > 0 else -n
    preferred = math.cos(ELEVATION) * g + math.sin(ELEVATION) * n
    if not moving_pts.size:
        return preferred
    return _best_view(ground, moving_pts, preferred)


def _best_view(ground: Array, moving: Array, preferred: Array) -> Array:
    """The direction, among 2000 spread evenly over the sphere, that keeps the linkage's points
    clear of the rim and of the far side, nearest ``preferred`` among near-equals.

    Each point scores its depth capped at 0.35 (about 20° inside the rim): past that it is
    plainly visible and going deeper buys nothing, while a point near or behind the rim costs.
    The ground pivots weigh as much together as the moving joints' whole circuits.
    """
    moving = moving[np.all(np.isfinite(moving), axis=-1)]
    moving = moving[:: max(1, len(moving) // 600)]
    k = np.arange(2000) + 0.5
    z = 1.0 - 2.0 * k / 2000
    lon = math.pi * (3.0 - math.sqrt(5.0)) * k
    r = np.sqrt(1.0 - z * z)
    candidates = np.stack((r * np.cos(lon), r * np.sin(lon), z), axis=-1)
    candidates = np.concatenate((candidates, preferred[None]))

    def score(points: Array) -> Array:
        capped: Array = np.minimum(candidates @ points.T, 0.35).mean(axis=1)
        return capped

    total = score(ground) + score(moving) + 0.02 * (candidates @ preferred)
    best: Array = candidates[int(np.argmax(total))]
    return best


def fit_normal(ground: Array, g: Array) -> Array:
    """Unit normal to g of the great circle fitting the ground pivots (a guess if they are
    fewer than two or all alike)."""
    if len(ground) >= 2:
        _, s, vt = np.linalg.svd(ground)
        # Two or more pivots spread along one great circle: its normal is the weakest direction.
        if s[1] > 1e-9 * s[0]:
            n: Array = vt[-1]
            n = n - (n @ g) * g
            if sphere.norm(n) > 1e-9:
                return n / sphere.norm(n)
    for hint in (Z_AXIS, _Y):
        n = hint - (hint @ g) * g
        if sphere.norm(n) > 1e-6:
            return n / sphere.norm(n)
    raise AssertionError("unreachable: +Z and +Y cannot both be parallel to g")


def upright(n: Array) -> Array:
    """``n`` or ``−n``, whichever points to +Z (else +Y, else +X): the singular vector's sign is
    arbitrary, and a picture must not turn upside down with it."""
    for axis in range(2, -1, -1):
        if abs(float(n[axis])) > 1e-9:
            return n if n[axis] > 0 else -n
    return n

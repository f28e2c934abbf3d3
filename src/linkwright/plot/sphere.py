"""Pictures of spherical linkages: an orthographic view of the unit sphere.

A spherical linkage lives on the unit sphere (every joint is the unit vector along its revolute
axis, every link a great-circle arc), so it is drawn the way a globe is: the sphere's outline, a
faint graticule (meridians and parallels about +Z, every 30°) on the near hemisphere, and on
top of it the links as great-circle arcs, the ground pivots as triangles, the moving joints as
dots with their letters, and the closed paths of the traced joints. Whatever lies on the far
hemisphere is drawn dashed and faded, so depth reads at a glance.

The view is given by the direction ``view`` from which the sphere is seen (the eye is far away
along it). For a linkage the default (:func:`default_view`) starts from the normalised mean of
the ground pivots, raised 35° out of the great circle that fits them best, and then turns to
keep every joint, over its whole circuit, clear of the rim and of the far side: coupler points
often swing far from the frame. The great circle through the ground pivots is kept level on
the page, so the frame reads like a drawing board.

Figures are built on :class:`matplotlib.figure.Figure` with an Agg canvas, never through pyplot
(no global state; works headless and from several threads), as in :mod:`linkwright.plot.generic`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import (
    Fixed,
    Motion,
)
from linkwright.geometry import sphere
from linkwright.geometry.sphere import lambert_azimuthal
from linkwright.mechanisms import Mechanism, circuits, solve
from linkwright.plot.generic import (
    DEAD_COLOR,
    MODE_COLORS,
    OWN_COLOR,
    SECOND_PATH_COLOR,
    _family_title,
    _Features,
    _features,
    _input_status,
    _letter,
    _mode_curves,
    _never_modes,
)
from linkwright.plot.planar import (
    GAMMA_COLOR,
    LIMIT_COLOR,
    _add_note,
    _deg,
    _label_joints,
    _Note,
    _place_notes,
    new_figure,
)

__all__ = [
    "SpherePlotError",
    "SphereView",
    "default_view",
    "great_arc",
    "plot_spherical_curves",
    "plot_spherical_linkage",
    "plot_spherical_mechanism",
    "stroke",
]

Array = NDArray[np.float64]

LINK = "#1f3b57"
GROUND = "#6b6b6b"
BODY = "#9ecae1"
CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")
MINUS = "\N{MINUS SIGN}"
ELEVATION = math.radians(35.0)
BACK_ALPHA = 0.4  # how much of its colour a far-side stroke keeps
_Z = np.array([0.0, 0.0, 1.0])
_Y = np.array([0.0, 1.0, 0.0])


class SpherePlotError(ValueError):
    """Input that cannot be drawn on the sphere (names the argument and the problem)."""


# --------------------------------------------------------------------------------------------
# Geometry of the picture
# --------------------------------------------------------------------------------------------


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
    linkwright.plot.sphere.SpherePlotError: great_arc: a and b are antipodal (arc 180°), ...
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
    out = np.cos(angle)[..., None] * a[..., None, :] + np.sin(angle)[..., None] * t[..., None, :]
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
        hint = _Z if up_hint is None else up_hint
        right = sphere.cross(hint, eye)
        if sphere.norm(right) < 1e-6:  # looking along the hint: any other "up" will do
            right = sphere.cross(_Y if abs(eye[1]) < 0.9 else _Z, eye)
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


def _view(view: ArrayLike | None, up: ArrayLike | None, fallback: Array) -> SphereView:
    eye = fallback if view is None else _directions(view, "view")
    if eye.shape != (3,):
        raise SpherePlotError(f"view: must be one 3-vector, got shape {eye.shape}")
    hint = None if up is None else _directions(up, "up")
    if hint is not None and hint.shape != (3,):
        raise SpherePlotError(f"up: must be one 3-vector, got shape {hint.shape}")
    return SphereView(eye, hint)


# --------------------------------------------------------------------------------------------
# Drawing primitives
# --------------------------------------------------------------------------------------------


def _backdrop(ax: Axes, view: SphereView, avoid: Array | None = None) -> None:
    """Outline, a faint near-side graticule about +Z, the equator a little stronger, and the
    axis tips +X, +Y, +Z where they face the viewer."""
    ax.add_patch(Circle((0, 0), 1.0, facecolor="#f7f9fb", edgecolor="0.25", lw=1.0, zorder=0))
    u = np.linspace(0.0, 2.0 * np.pi, 241)
    for lon in np.radians(np.arange(0, 180, 30)):
        c = np.stack((np.cos(lon) * np.cos(u), np.sin(lon) * np.cos(u), np.sin(u)), axis=-1)
        near, _ = view.split(c)
        ax.plot(*near.T, color="0.82", lw=0.5, zorder=0.5)
    for lat in np.radians(np.arange(-60, 61, 30)):
        c = np.stack(
            (np.cos(lat) * np.cos(u), np.cos(lat) * np.sin(u), np.full_like(u, np.sin(lat))), -1
        )
        near, _ = view.split(c)
        strong = lat == 0
        ax.plot(*near.T, color="0.6" if strong else "0.82", lw=0.8 if strong else 0.5, zorder=0.5)
    for name, tip in zip("XYZ", np.eye(3), strict=True):
        # A joint sitting on an axis (paper 000's A0 is +X) keeps its own label.
        crowded = avoid is not None and bool(np.any(avoid @ tip > math.cos(math.radians(10))))
        if view.depth(tip) > 0.05 and not crowded:
            x, y = view.xy(tip)
            ax.plot(x, y, "+", color="0.55", ms=6, zorder=0.6)
            ax.annotate(
                f"+{name}",
                (x, y),
                xytext=(3, -9),
                textcoords="offset points",
                fontsize=7,
                color="0.5",
            )
    ax.set_xlim(-1.12, 1.12)
    ax.set_ylim(-1.12, 1.12)
    ax.set_aspect("equal")
    ax.set_axis_off()


def stroke(
    ax: Axes, view: SphereView, p: Array, *, color, lw: float, label=None, z=2.0, ls="-"
) -> None:
    """A polyline on the sphere: drawn ``ls`` where near, dashed and faded where far."""
    near, far = view.split(p)
    ax.plot(*near.T, color=color, lw=lw, ls=ls, label=label, zorder=z, solid_capstyle="round")
    ax.plot(*far.T, color=color, lw=lw * 0.8, ls=(0, (3, 2)), alpha=BACK_ALPHA, zorder=z - 1)


def _safe_arc(a: Array, b: Array) -> Array | None:
    """The arc a→b, or None where it is not drawable (a joint not placed, antipodal ends)."""
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return None
    try:
        return great_arc(a, b)
    except SpherePlotError:
        return None


def _check_curve(label: str, points: ArrayLike) -> Array:
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


def _mean_direction(points: Array, fallback: Array) -> Array:
    pts = points[np.all(np.isfinite(points), axis=-1)] if points.size else points
    if pts.size == 0:
        return fallback
    m = pts.mean(axis=0)
    size = sphere.norm(m)
    return m / size if size > 1e-9 else fallback


# --------------------------------------------------------------------------------------------
# Curves
# --------------------------------------------------------------------------------------------


def plot_spherical_curves(
    curves: list[tuple[str, ArrayLike]],
    *,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
    title: str | None = None,
    backdrop: bool = True,
    ax: Axes | None = None,
) -> Figure:
    """Draw curves on the unit sphere, near parts solid and far parts dashed and faded.

    Parameters
    ----------
    curves : list of (label, array of shape (N, 3))
        Each curve's points are unit vectors; NaN rows break the line (samples where a linkage
        was not assembled).
    view : array_like, shape (3,), optional
        Direction from which the sphere is seen. Default: the normalised mean of every finite
        point of every curve (+X if that mean vanishes).
    up : array_like, shape (3,), optional
        The direction drawn upwards on the page (its part normal to ``view``). Default +Z.
    title : str, optional
    backdrop : bool
        Draw the sphere's outline and graticule; pass False to add curves to an axes that
        already shows the sphere in the same view.
    ax : matplotlib.axes.Axes, optional
        Draw into this axes; a new figure is made otherwise.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    SpherePlotError
        For a curve that is not an (N, 3) array of unit vectors, or a zero ``view``.

    Examples
    --------
    >>> u = np.linspace(0, 2 * np.pi, 100)
    >>> circle = np.stack([np.cos(u), np.sin(u), 0 * u], axis=-1)
    >>> fig = plot_spherical_curves([("equator", circle)], view=[1, 1, 1])
    >>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    ['equator']

    Points off the sphere are refused:

    >>> plot_spherical_curves([("wrong", 2 * circle)])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.sphere.SpherePlotError: curve 'wrong': points must be unit vectors ...
    """
    checked = [(str(label), _check_curve(str(label), pts)) for label, pts in curves]
    everything = np.concatenate([p for _, p in checked]) if checked else np.zeros((0, 3))
    cam = _view(view, up, _mean_direction(everything, np.array([1.0, 0.0, 0.0])))
    fig = ax.figure if ax is not None else new_figure((6, 6))
    ax = ax or fig.add_subplot()
    if backdrop:
        _backdrop(ax, cam)
    for i, (label, p) in enumerate(checked):
        stroke(ax, cam, p, color=CURVES[i % len(CURVES)], lw=1.4, label=label)
    if checked:
        ax.legend(loc="lower right", fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


# --------------------------------------------------------------------------------------------
# Linkages
# --------------------------------------------------------------------------------------------


def _require_sphere(mechanism: Mechanism) -> None:
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


def _ground(mechanism: Mechanism) -> dict[str, Array]:
    """The ground pivots from the parameters, so they are known even where nothing assembles."""
    params = mechanism.params()
    return {
        s.name: np.asarray(params[s.at], dtype=float)
        for s in mechanism.plan.steps
        if isinstance(s, Fixed)
    }


def _links(
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
    _require_sphere(mechanism)
    return _default_view(mechanism, circuits(mechanism, samples, order=0)[1])


def _default_view(mechanism: Mechanism, circuits: list[Motion]) -> Array:
    ground = np.array(list(_ground(mechanism).values())).reshape(-1, 3)
    moving = [
        m.positions[s.name]
        for m in circuits
        for s in mechanism.plan.steps
        if not isinstance(s, Fixed)
    ]
    moving_pts = np.concatenate(moving) if moving else np.zeros((0, 3))
    every = np.concatenate((ground, moving_pts))
    fallback = _mean_direction(every, np.ones(3) / math.sqrt(3.0))
    g = _mean_direction(ground, fallback)
    n = _fit_normal(ground, g)
    side = _mean_direction(moving_pts, np.zeros(3)) if moving_pts.size else np.zeros(3)
    lean = float(side @ n)
    if abs(lean) < 1e-9:
        lean = float(n @ _Z) if abs(float(n @ _Z)) > 1e-9 else 1.0
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
        return np.minimum(candidates @ points.T, 0.35).mean(axis=1)

    total = score(ground) + score(moving) + 0.02 * (candidates @ preferred)
    return candidates[int(np.argmax(total))]


def _fit_normal(ground: Array, g: Array) -> Array:
    """Unit normal to g of the great circle fitting the ground pivots (a guess if they are
    fewer than two or all alike)."""
    if len(ground) >= 2:
        _, s, vt = np.linalg.svd(ground)
        # Two or more pivots spread along one great circle: its normal is the weakest direction.
        if s[1] > 1e-9 * s[0]:
            n = vt[-1]
            n = n - (n @ g) * g
            if sphere.norm(n) > 1e-9:
                return n / sphere.norm(n)
    for hint in (_Z, _Y):
        n = hint - (hint @ g) * g
        if sphere.norm(n) > 1e-6:
            return n / sphere.norm(n)
    raise AssertionError("unreachable: +Z and +Y cannot both be parallel to g")


def _upright(n: Array) -> Array:
    """``n`` or ``−n``, whichever points to +Z (else +Y, else +X): the singular vector's sign is
    arbitrary, and a picture must not turn upside down with it."""
    for axis in range(2, -1, -1):
        if abs(float(n[axis])) > 1e-9:
            return n if n[axis] > 0 else -n
    return n


def plot_spherical_linkage(
    mechanism: Mechanism,
    *,
    samples: int = 360,
    at: float | None = None,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
    title: str | None = None,
    extra_curves: list[tuple[str, ArrayLike]] | None = None,
    ax: Axes | None = None,
    annotate: bool = False,
) -> Figure:
    """A spherical linkage at one pose, with the closed paths of its traced joints.

    The links are read from the construction plan, so any sphere-space mechanism is drawn
    without per-family code: a crank joins its pivot to its joint, a dyad joint is joined to
    both parents, and a rigid point (a coupler point) makes a filled spherical triangle with the
    two joints of its link. Each traced joint's path is the whole circuit as the machine runs
    (every circuit where the input cannot turn fully), with the limit positions, where a dyad
    changes branch, marked by crosses.

    Parameters
    ----------
    mechanism : Mechanism
        One spherical linkage (``mechanism.space == "sphere"``, batch shape ``()``).
    samples : int
        Samples per circuit.
    at : float, optional
        Input angle (radians) of the pose drawn, on the mechanism's own assembly. Default: the
        first sample of the first circuit.
    view, up : array_like, shape (3,), optional
        Direction the sphere is seen from, and the direction drawn upwards (its part normal to
        ``view``). Default view: :func:`default_view`; default up: the normal of the great
        circle through the ground pivots, so that the frame is drawn level.
    title : str, optional
        First line of the title; the second says how the input moves and which pose is drawn.
    extra_curves : list of (label, array of shape (N, 3)), optional
        More curves to draw in the same view (another assembly's path, a target curve), dotted;
        unit vectors, NaN rows break the line.
    ax : matplotlib.axes.Axes, optional
        Draw into this axes; a new figure is made otherwise.
    annotate : bool
        Also draw the first traced joint's path in every other assembly mode (dashed, named in
        the legend), and mark the dead centres (the output link drawn dashed there) and the
        transmission-angle extremes, as :mod:`linkwright.plot.generic` defines them.

    Returns
    -------
    matplotlib.figure.Figure
        A linkage that cannot be assembled at any input is drawn as its ground pivots, and the
        title says so.

    Raises
    ------
    SpherePlotError
        For a planar linkage, a batch of mechanisms, a bad ``view``/``up`` or an extra curve
        that is not an (N, 3) array of unit vectors.
    linkwright.mechanisms.sixbar.NoConstructionPlan
        For a mechanism whose input leaves no construction plan (Stephenson III driven at FG).

    Examples
    --------
    >>> from linkwright.mechanisms import SphericalFourBar
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> fig = plot_spherical_linkage(fig6, samples=90)
    >>> print(fig.axes[0].get_title())
    spherical-fourbar
    input turns fully; pose at θ = 0.0°

    A linkage that never assembles shows its ground pivots and says why nothing else:

    >>> stuck = SphericalFourBar(*np.radians([90, 10, 20, 30]))
    >>> print(plot_spherical_linkage(stuck).axes[0].get_title())
    spherical-fourbar
    cannot be assembled at any input: only the ground pivots are drawn
    """
    _require_sphere(mechanism)
    extra = [(str(label), _check_curve(str(label), pts)) for label, pts in extra_curves or []]
    feats = _features(mechanism, samples, every=annotate, marks=annotate)
    fig = ax.figure if ax is not None else new_figure((6.4, 6.6))
    ax = ax or fig.add_subplot()
    head = title or mechanism.family
    _, pose, theta = _sphere_panel(
        ax, mechanism, feats, at=at, view=view, up=up, extra=extra, annotate=annotate
    )
    if not feats.own.circuits:
        ax.set_title(
            f"{head}\ncannot be assembled at any input: only the ground pivots are drawn",
            fontsize=10,
        )
        if extra:
            ax.legend(loc="lower right", fontsize=7)
        return fig
    if pose is not None:
        where = f"pose at θ = {_deg(math.degrees(theta))}°"
    else:
        where = f"no pose: it does not assemble at θ = {_deg(math.degrees(theta))}°"
    ax.set_title(f"{head}\n{_input_status(feats.own.arcs)}; {where}", fontsize=10)
    ax.legend(loc="lower right", fontsize=7)
    return fig


def _pose_at(
    mechanism: Mechanism, feats: _Features, at: float | None
) -> tuple[dict[str, Array] | None, float]:
    """The pose drawn (None where it does not assemble) and its input."""
    if at is None:
        first = feats.own.circuits[0]
        return {name: p[0] for name, p in first.positions.items()}, float(first.input[0])
    one = solve(mechanism, [float(at)], order=0)
    if not bool(one.valid[0]):
        return None, float(at)
    return {name: p[0] for name, p in one.positions.items()}, float(at)


def _sphere_panel(
    ax: Axes,
    mechanism: Mechanism,
    feats: _Features,
    *,
    at: float | None,
    view: ArrayLike | None,
    up: ArrayLike | None,
    extra: list[tuple[str, Array]],
    annotate: bool,
) -> tuple[SphereView, dict[str, Array] | None, float]:
    """Draw the sphere, the paths, the marks and the pose; return the camera and the pose."""
    ground = _ground(mechanism)
    own = feats.own
    circuits = list(own.circuits)
    pivots = np.array(list(ground.values())).reshape(-1, 3)
    eye = _default_view(mechanism, circuits) if view is None else np.ones(3)
    if up is None:
        # The frame's great circle drawn level: the frame reads like a drawing board.
        up = _upright(_fit_normal(pivots, _mean_direction(pivots, eye / sphere.norm(eye))))
    cam = _view(view, up, eye)
    marked = [pivots]
    if circuits:
        marked.append(np.array([p[0] for p in circuits[0].positions.values()]))
    _backdrop(ax, cam, avoid=np.concatenate(marked))
    _frame(ax, cam, ground)
    _seen_from(ax, cam)
    traced = mechanism.plan.traced
    for i, (label, p) in enumerate(extra):
        near, far = cam.split(p)
        color = CURVES[(i + len(traced)) % len(CURVES)]
        ax.plot(*near.T, color=color, lw=1.4, ls=(0, (1, 1.5)), label=label, zorder=3.0)
        ax.plot(*far.T, color=color, lw=1.0, ls=(0, (1, 3)), alpha=BACK_ALPHA, zorder=2.0)
    if not circuits:
        for name, p in ground.items():
            _joint(ax, cam, name, p, ground=True)
        return cam, None, 0.0 if at is None else float(at)
    if annotate:
        for style, label, p in _styled_curves(mechanism, feats):
            stroke(ax, cam, p, label=label, z=3.0, **style)
    else:
        for k, motion in enumerate(circuits):
            for i, joint in enumerate(traced):
                closed = np.concatenate((motion.positions[joint], motion.positions[joint][:1]))
                label = f"path of {joint}" + (f" (circuit {k + 1})" if k else "")
                stroke(ax, cam, closed, color=CURVES[i % len(CURVES)], lw=1.4, label=label, z=3.0)
    limits = feats.of("limit")
    if limits:
        pts = np.array([m.pose[traced[0]] for m in limits])
        ax.plot(*cam.xy(pts).T, "x", color="k", ms=6, zorder=6, label="limit positions", ls="none")
    if annotate:
        for kind, marker, color, label in _MARK_STYLES:
            marks = feats.of(kind)
            if marks:
                pts = np.array([m.pose[traced[0]] for m in marks])
                ax.plot(
                    *cam.xy(pts).T,
                    marker,
                    ms=7,
                    mfc=color,
                    mec="white",
                    mew=0.8,
                    ls="none",
                    zorder=6.5,
                    label=label,
                )
        if feats.output is not None:
            pivot, out = feats.output
            for m in feats.of("dead"):
                e = _safe_arc(m.pose[pivot], m.pose[out]) if pivot is not None else None
                if e is not None:
                    stroke(ax, cam, e, color=DEAD_COLOR, lw=1.3, ls=(0, (4, 2)), z=3.5)
    pose, theta = _pose_at(mechanism, feats, at)
    if pose is not None:
        _draw_pose(ax, cam, mechanism, pose)
    else:
        for name, p in ground.items():
            _joint(ax, cam, name, p, ground=True)
    return cam, pose, theta


# Marker, colour and legend label of the dead centres and γ extremes on either panel.
_MARK_STYLES = (
    ("dead", "s", DEAD_COLOR, "dead centres (output stationary)"),
    ("gmin", "v", GAMMA_COLOR, "γ extremes"),
    ("gmax", "^", GAMMA_COLOR, "_γ extremes"),
)


def _styled_curves(
    mechanism: Mechanism, feats: _Features
) -> list[tuple[dict[str, object], str, Array]]:
    """(line style, legend label, closed curve) of every drawn path, as the planar picture
    draws them: the document's mode bold, each other mode dashed in its colour, the other
    traced joints dotted grey on the document's mode."""
    traced = mechanism.plan.traced
    out: list[tuple[dict[str, object], str, Array]] = []
    colors: dict[tuple[float, ...], str] = {}
    palette = iter(MODE_COLORS)
    several = len(feats.modes) > 1
    for mode, k, p, same in _mode_curves(feats, traced[0]):
        if mode.own:
            style: dict[str, object] = {"color": OWN_COLOR, "lw": 2.2, "ls": "-"}
        else:
            if mode.signs not in colors:
                colors[mode.signs] = next(palette, "0.5")
            style = {"color": colors[mode.signs], "lw": 1.3, "ls": (0, (5, 3))}
        label = mode.label if several else f"path of {traced[0]}"
        if same is not None and not mode.own:
            label += " (same curve)"
        out.append((style, label if k == 0 else "_nolegend_", p))
    for i, joint in enumerate(traced[1:]):
        for k, motion in enumerate(feats.own.circuits):
            p = np.concatenate((motion.positions[joint], motion.positions[joint][:1]))
            style = {
                "color": SECOND_PATH_COLOR if i == 0 else CURVES[i % len(CURVES)],
                "lw": 1.1,
                "ls": (0, (1, 1.5)),
            }
            out.append((style, f"path of {joint}" if k == 0 else "_nolegend_", p))
    return out


# --------------------------------------------------------------------------------------------
# Map projection
# --------------------------------------------------------------------------------------------


def _lat_lon(v: Array) -> tuple[float, float]:
    return math.degrees(math.asin(max(-1.0, min(1.0, float(v[2]))))), math.degrees(
        math.atan2(float(v[1]), float(v[0]))
    )


def _graticule(ax: Axes, centre: Array, step: float, box: tuple[float, float, float, float]):
    """Parallels and meridians about +Z every ``step`` degrees, labelled at the map's left and
    bottom edges; the far side (beyond 120° from the centre) is left out."""
    x0, x1, y0, y1 = box
    u = np.radians(np.linspace(-180.0, 180.0, 721))
    v = np.radians(np.linspace(-90.0, 90.0, 361))

    def project(pts: Array) -> Array:
        far = pts @ centre < -0.5
        pts = np.where(far[:, None], np.nan, pts)
        return lambert_azimuthal(pts, centre)

    def inside(xy: Array) -> Array:
        return (xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1)

    style = {"color": "0.82", "lw": 0.6, "zorder": 0.5}
    text = {"fontsize": 7, "color": "0.5", "clip_on": True, "zorder": 0.6}
    for lat in np.arange(-90.0 + step, 90.0, step):
        r = math.radians(lat)
        xy = project(
            np.stack((np.cos(r) * np.cos(u), np.cos(r) * np.sin(u), np.sin(r) + 0 * u), -1)
        )
        ax.plot(*xy.T, **style)
        ok = inside(xy)
        # Labelled only where the line meets the left edge, so labels stay in one column.
        if ok.any() and float(np.min(xy[ok, 0])) < x0 + 0.06 * (x1 - x0):
            i = int(np.flatnonzero(ok)[np.argmin(xy[ok, 0])])
            if xy[i, 1] < y0 + 0.08 * (y1 - y0):  # the corner belongs to the meridians' labels
                continue
            label = f"lat {lat:.0f}°".replace("-", MINUS)
            ax.text(*xy[i], label, ha="left", va="bottom", **text)
    for lon in np.arange(-180.0, 180.0, step):
        r = math.radians(lon)
        xy = project(np.stack((np.cos(v) * np.cos(r), np.cos(v) * np.sin(r), np.sin(v)), -1))
        ax.plot(*xy.T, **style)
        ok = inside(xy)
        if ok.any() and float(np.min(xy[ok, 1])) < y0 + 0.06 * (y1 - y0):
            i = int(np.flatnonzero(ok)[np.argmin(xy[ok, 1])])
            label = f"lon {lon:.0f}°".replace("-", MINUS)
            ax.text(*xy[i], label, ha="left", va="bottom", rotation=90, **text)


def _map_centre(
    mechanism: Mechanism, feats: _Features, pose: dict[str, Array] | None = None
) -> Array:
    """The normalised mean of every circuit sample of the curves drawn (the first traced
    joint in every mode, the others in the document's), or of the ground pivots if none;
    tilted where a drawn point (any joint of any circuit, a pivot, the pose) lies at its
    antipode, which has no one place on the map
    (:func:`~linkwright.geometry.sphere.clear_centre`)."""
    traced = mechanism.plan.traced
    samples = [c.positions[traced[0]] for mode in feats.modes for c in mode.circuits]
    samples += [c.positions[j] for j in traced[1:] for c in feats.own.circuits]
    pivots = np.array(list(_ground(mechanism).values())).reshape(-1, 3)
    everything = np.concatenate(samples) if samples else np.zeros((0, 3))
    centre = _mean_direction(everything, _mean_direction(pivots, _Z))
    drawn = [p.reshape(-1, 3) for mode in feats.modes for c in mode.circuits
             for p in c.positions.values()]  # fmt: skip
    drawn += [pivots] + [np.asarray(p, dtype=float).reshape(-1, 3) for p in (pose or {}).values()]
    return sphere.clear_centre(centre, np.concatenate(drawn))


def _map_panel(
    ax: Axes,
    mechanism: Mechanism,
    feats: _Features,
    pose: dict[str, Array] | None,
) -> Array:
    """The curves, pivots, marks and pose on a Lambert azimuthal equal-area map centred on the
    curves' mean direction; returns that centre."""
    curves = _styled_curves(mechanism, feats)
    ground = _ground(mechanism)
    centre = _map_centre(mechanism, feats, pose)

    def project(p: Array) -> Array:
        return lambert_azimuthal(p, centre)

    drawn: list[Array] = []
    for style, label, p in curves:
        xy = project(p)
        ax.plot(*xy.T, label=label, zorder=3.6, **style)
        drawn.append(xy)
    traced = mechanism.plan.traced[0]
    notes: list[_Note] = []
    tol = 0.03
    styles = [("limit", "D", LIMIT_COLOR, "input limit positions"), *_MARK_STYLES]
    for kind, marker, color, label in styles:
        marks = feats.of(kind)
        if not marks:
            continue
        xy = project(np.array([m.pose[traced] for m in marks]))
        ax.plot(
            *xy.T, marker, ms=8, mfc=color, mec="white", mew=0.9, ls="none", zorder=7.5,
            label=label if kind != "gmax" or not feats.of("gmin") else "_nolegend_",
        )  # fmt: skip
        for m, q in zip(marks, xy, strict=True):
            _add_note(notes, q, m.text, color, tol)
    dead = feats.of("dead")
    if dead and feats.output is not None and feats.output[0] is not None:
        pivot, out = feats.output
        for m in dead:
            e = _safe_arc(m.pose[pivot], m.pose[out])
            if e is not None:
                xy = project(e)
                ax.plot(*xy.T, color=DEAD_COLOR, lw=1.3, ls=(0, (4, 2)), zorder=3.5)
                drawn.append(xy)
        ends = project(np.array([m.pose[out] for m in dead]))
        ax.plot(
            *ends.T, "s", ms=6, mfc="white", mec=DEAD_COLOR, mew=1.4, ls="none", zorder=3.55,
            label=f"output {pivot}{out} at its dead centres",
        )  # fmt: skip
    for a, b in itertools.pairwise(ground.values()):
        e = _safe_arc(a, b)
        if e is not None:
            ax.plot(*project(e).T, color=GROUND, lw=3.5, solid_capstyle="round", zorder=1.8)
    pts: dict[str, Array] = dict(ground) if pose is None else dict(pose)
    pairs, bodies = _links(mechanism)
    if pose is not None:
        for o, t, p in bodies:
            edges = [_safe_arc(pose[x], pose[y]) for x, y in ((o, t), (t, p), (p, o))]
            if all(e is not None for e in edges):
                ring = project(np.concatenate(edges))  # type: ignore[arg-type]
                ax.add_patch(
                    Polygon(ring, closed=True, facecolor=BODY, edgecolor="none", alpha=0.5)
                )
                ax.plot(*ring.T, color=LINK, lw=1.0, zorder=4)
                drawn.append(ring)
        for a, b in pairs:
            e = _safe_arc(pose[a], pose[b])
            if e is not None:
                xy = project(e)
                ax.plot(*xy.T, color=LINK, lw=2.6, solid_capstyle="round", zorder=4)
                drawn.append(xy)
    taken: dict[str, list[Array]] = {name: [] for name in pts}
    flat = {name: project(p) for name, p in pts.items() if np.all(np.isfinite(p))}
    for a, b in pairs if pose is not None else []:
        if a in flat and b in flat:
            taken[a].append(flat[b] - flat[a])
            taken[b].append(flat[a] - flat[b])
    ground = mechanism.plan.ground
    for name in mechanism.plan.joints:
        if name not in flat:
            continue
        is_ground = name in ground
        style = (
            {"marker": "^", "ms": 10, "mfc": GROUND, "mec": LINK, "mew": 1.0}
            if is_ground
            else {"marker": "o", "ms": 7, "mfc": "white", "mec": LINK, "mew": 1.6}
        )
        if name == traced and not is_ground:
            style.update(mfc=OWN_COLOR, mec="white")
        ax.plot(*flat[name], ls="none", zorder=6, label=f"_joint {name}", **style)
    _label_joints(ax, flat, taken, {n: _letter(n) for n in flat})
    every = np.concatenate([*drawn, *(q[None] for q in flat.values())])
    every = every[np.all(np.isfinite(every), axis=-1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.08 * float(max(hi - lo)) + 0.02
    box = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    reach = max(float(np.max(np.hypot(*every.T))), 1e-3)  # map radius 2 sin(δ/2)
    extent = math.degrees(2.0 * math.asin(min(1.0, reach / 2.0)))
    step = 5.0 if extent < 25.0 else 10.0 if extent < 70.0 else 15.0
    _graticule(ax, centre, step, box)
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xticks([])
    ax.set_yticks([])
    lat, lon = _lat_lon(centre)
    ax.set_title(
        "Lambert azimuthal equal-area map, centred on the curves' mean direction\n"
        f"(lat {_deg(lat)}°, lon {_deg(lon)}°); graticule every {step:.0f}° about +Z",
        fontsize=9.5,
    )
    lines = [
        np.asarray(line.get_xydata(), float)
        for line in ax.lines
        if line.get_linestyle() not in ("None", "none", " ", "") and len(line.get_xydata()) > 1
    ]
    centre_xy = np.nanmean(drawn[0], axis=0) if drawn else np.zeros(2)
    _place_notes(ax, notes, lines, centre_xy)
    return centre


def plot_spherical_mechanism(
    mechanism: Mechanism,
    *,
    samples: int = 720,
    at: float | None = None,
    title: str | None = None,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
) -> Figure:
    """The main picture of a spherical linkage: a 3-D view of the sphere and a map of the
    curves, side by side.

    Left, the sphere seen from outside (:func:`plot_spherical_linkage` with ``annotate``): the
    links as great-circle arcs at the pose, the first traced joint's path in every assembly
    mode (the document's bold), the other traced joints' paths, and the marks of
    :mod:`linkwright.plot.generic` (limit positions, dead centres with the output link there,
    transmission-angle extremes). Right, the same on a Lambert azimuthal equal-area map
    (:func:`linkwright.geometry.sphere.lambert_azimuthal`, +Z up) centred on the curves' mean
    direction (the normalised mean of every circuit sample of the curves drawn), with a
    graticule of latitude and longitude about +Z, the frame, the ground pivots, the pose's links
    as projected arcs and a note at each mark. One legend under both. Equal-area, so a curve's
    map encloses as much as it does on the unit sphere.

    Parameters
    ----------
    mechanism : Mechanism
        One spherical linkage that assembles somewhere.
    samples : int
        Samples per circuit.
    at : float, optional
        Input angle (radians) of the pose, on the document's assembly (the pose of
        :func:`~linkwright.mechanisms.solve`); default the first sample of the first circuit.
    title : str, optional
        The figure's title.
    view, up : array_like, shape (3,), optional
        The 3-D view's direction and up (see :func:`plot_spherical_linkage`).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the sphere, then the map.

    Raises
    ------
    SpherePlotError
        For a planar linkage, a batch, or a linkage that cannot be assembled at any input.

    Examples
    --------
    >>> from linkwright.mechanisms import SphericalFourBar
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> fig = plot_spherical_mechanism(fig6, samples=90)
    >>> len(fig.axes), fig.axes[1].get_title().split(",")[0]
    (2, 'Lambert azimuthal equal-area map')

    A linkage that closes nowhere has nothing to draw:

    >>> plot_spherical_mechanism(SphericalFourBar(*np.radians([90, 10, 20, 30])))
    Traceback (most recent call last):
    ...
    linkwright.plot.sphere.SpherePlotError: mechanism: it cannot be assembled at any input
    """
    _require_sphere(mechanism)
    feats = _features(mechanism, samples)
    if not feats.own.circuits:
        raise SpherePlotError("mechanism: it cannot be assembled at any input")
    fig = new_figure((14.0, 7.6))
    left, right = fig.subplots(1, 2, width_ratios=(1.0, 1.15))
    _, pose, theta = _sphere_panel(
        left, mechanism, feats, at=at, view=view, up=up, extra=[], annotate=True
    )
    status = _input_status(feats.own.arcs)
    where = (
        f"pose at θ = {_deg(math.degrees(theta))}°"
        if pose is not None
        else f"no pose: it does not assemble at θ = {_deg(math.degrees(theta))}°"
    )
    lines = [f"orthographic view of the unit sphere\n{status}; {where}"]
    if len(feats.modes) > 1:
        lines.append("bold: the document's assembly; dashed: the others")
    never = _never_modes(feats)
    if never:
        lines.append("never assembles: " + "; ".join(never))
    if feats.output is not None and feats.of("dead") and feats.output[0] is not None:
        lines.append(
            f"dead centres: where the output link {feats.output[0]}{feats.output[1]} stops"
        )
    left.set_title("\n".join(lines), fontsize=9.5)
    _map_panel(right, mechanism, feats, pose)
    handles, labels = right.get_legend_handles_labels()
    name = _family_title(mechanism)
    head = (
        title
        if title and name.lower() in title.lower()
        else (f"{name} — {title}" if title else name)
    )
    fig.suptitle(head, fontsize=13)
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=min(4, len(labels)),
            fontsize=8.5,
            frameon=False,
        )
    return fig


def _seen_from(ax: Axes, cam: SphereView) -> None:
    eye = ", ".join(f"{c:.2f}" for c in np.round(cam.eye, 2) + 0.0).replace("-", MINUS)
    ax.text(0.0, 0.0, f"seen from ({eye})", transform=ax.transAxes, fontsize=7, color="0.45")


def _frame(ax: Axes, cam: SphereView, ground: dict[str, Array]) -> None:
    """The fixed link: grey arcs joining the ground pivots in the plan's order (they all lie on
    the one frame body, so any chain through them shows it)."""
    pts = list(ground.values())
    for a, b in itertools.pairwise(pts):
        e = _safe_arc(a, b)
        if e is not None:
            stroke(ax, cam, e, color=GROUND, lw=3.5, z=1.8)


def _draw_pose(ax: Axes, cam: SphereView, mechanism: Mechanism, pose: dict[str, Array]) -> None:
    pairs, bodies = _links(mechanism)
    for o, t, p in bodies:
        edges = [_safe_arc(pose[x], pose[y]) for x, y in ((o, t), (t, p), (p, o))]
        if any(e is None for e in edges):
            continue
        ring = np.concatenate(edges)
        centre = sphere.unit(pose[o] + pose[t] + pose[p])
        near = bool(np.all(np.isfinite(centre))) and float(cam.depth(centre)) >= 0
        ax.add_patch(
            Polygon(
                cam.xy(ring),
                closed=True,
                facecolor=BODY,
                edgecolor="none",
                alpha=0.55 if near else 0.2,
                zorder=1.5,
            )
        )
        for e in edges:
            stroke(ax, cam, e, color=LINK, lw=1.2, z=4.0)
    for a, b in pairs:
        e = _safe_arc(pose[a], pose[b])
        if e is not None:
            stroke(ax, cam, e, color=LINK, lw=2.4, z=4.0)
    ground = mechanism.plan.ground
    for name in mechanism.plan.joints:
        _joint(ax, cam, name, pose[name], ground=name in ground)


def _joint(ax: Axes, cam: SphereView, name: str, p: Array, *, ground: bool) -> None:
    if not np.all(np.isfinite(p)):
        return
    near = float(cam.depth(p)) >= 0
    alpha = 1.0 if near else 0.55
    ax.plot(
        *cam.xy(p),
        marker="^" if ground else "o",
        ms=9 if ground else 6,
        color=GROUND if ground else "white",
        mec=LINK,
        alpha=alpha,
        zorder=7,
        label=f"_joint {name}",
    )
    ax.annotate(
        name,
        cam.xy(p),
        xytext=(5, 4),
        textcoords="offset points",
        fontsize=9,
        fontweight="bold" if near else "normal",
        alpha=alpha,
        zorder=8,
    )

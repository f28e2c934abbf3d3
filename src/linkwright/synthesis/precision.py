"""Classical precision-point synthesis of planar four-bars: function, motion and path generation.

Three routes, each returning a :class:`~linkwright.mechanisms.FourBar` that meets its precision
positions exactly, and a report of how it meets them, measured by simulating the result with
the engine (:func:`linkwright.mechanisms.solve`):

- **function generation** (:func:`freudenstein`): the crank angle φ and the rocker angle ψ, both
  measured from the frame line, through three pairs (φi, ψi), from Freudenstein's equation
  (Freudenstein 1955); :func:`chebyshev_spacing` and :func:`function_pairs` turn a function
  y = f(x) over a range into such pairs by the textbook route, :func:`function_error` measures
  the structural error between them;
- **motion generation** (rigid-body guidance) through three poses (:func:`three_pose_fourbar`):
  a moving pivot's three positions fix its centre; :func:`fourbar_from_dyads` builds a four-bar
  from any two compatible dyads (for four and five poses see
  :mod:`linkwright.synthesis.burmester`);
- **path generation with prescribed timing** through three points
  (:func:`path_with_timing`): the standard dyad equations with the coupler's and rocker's
  rotations as the free choices.

Conventions. A pose is the position of the coupler point P and the coupler's angle (radians);
the coupler's own frame in a pose has its origin at P and its x-axis at the pose's angle. A dyad
is a ground pivot (*centre point*) and a moving pivot (*circle point*), the moving pivot given by
its position in the first pose. The four-bar's crank is the first dyad, its input θ the absolute
angle of A − A0 (as :class:`~linkwright.mechanisms.FourBar` defines it), its coupler point P the
poses' point.

Each design reports the input θj at which it reaches precision position j, the assembly sign
(``branch``) it needs there, and two defects (Chase and Mirth 1993): a **branch defect** when the
positions need different assembly signs (the linkage cannot reach them all without passing a
dead-centre position or being taken apart), and an **order defect** when one sweep of the input
meets them out of order (or on different input arcs). Three positions never have an order defect
on a crank that turns fully: two cyclic orders exist and the crank may run either way.

References: F. Freudenstein, "Approximate synthesis of four-bar linkages", Trans. ASME 77 (1955)
853–861. G. N. Sandor and A. G. Erdman, *Advanced Mechanism Design* vol. 2 (Prentice-Hall 1984),
ch. 2 (the standard dyad form W(e^{iβj} − 1) + Z(e^{iαj} − 1) = δj). J. M. McCarthy and G. S.
Soh, *Geometric Design of Linkages*, 2nd ed. (Springer 2011), ch. 4–5. T. R. Chase and J. A.
Mirth, "Circuits and branches of single-degree-of-freedom planar linkages", J. Mech. Des. 115
(1993) 223–230.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, input_range

__all__ = [
    "FunctionDesign",
    "MotionDesign",
    "PrecisionError",
    "chebyshev_spacing",
    "fourbar_from_dyads",
    "freudenstein",
    "function_error",
    "function_pairs",
    "path_with_timing",
    "pose_positions",
    "three_pose_fourbar",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
# Two poses (or pairs) closer than this, relative to the poses' spread, are one.
SAME_TOL = 1e-9
# A linear system whose determinant, relative to the product of its row norms, is below this is
# singular: the precision positions do not fix a linkage.
SINGULAR_TOL = 1e-10
# A dyad whose moving pivot's positions are off a circle about its centre by more than this
# (relative to the poses' spread) does not guide the body through the poses.
DYAD_TOL = 1e-8


class PrecisionError(ValueError):
    """Precision positions that do not define a linkage (names the positions and the numbers)."""


def _wrap(angle: ArrayLike) -> Array:
    """Angle in (−π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), TWO_PI)


def _where(index: tuple[int, ...]) -> str:
    return f" (set {list(index)} of the batch)" if index else ""


def _first(mask: NDArray[np.bool_]) -> tuple[int, ...] | None:
    """Index of the first True of ``mask`` (None if none)."""
    if not np.any(mask):
        return None
    return tuple(int(i) for i in np.argwhere(mask)[0])


def _pose_set(points: ArrayLike, angles: ArrayLike | None, n: int | None, what: str):
    """Checked (points (..., n, 2), angles (..., n) or None, scale (...))."""
    p = np.asarray(points, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 2:
        raise PrecisionError(f"{what}: points must have shape (..., n, 2), got {p.shape}")
    count = p.shape[-2]
    if n is not None and count != n:
        raise PrecisionError(f"{what}: needs exactly {n} precision positions, got {count}")
    if not np.all(np.isfinite(p)):
        raise PrecisionError(f"{what}: points must be finite")
    a = None
    if angles is not None:
        a = np.asarray(angles, dtype=float)
        if a.shape[-1:] != (count,):
            raise PrecisionError(
                f"{what}: needs one angle per point ({count}), got angles of shape {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise PrecisionError(f"{what}: angles must be finite")
        try:
            shape = np.broadcast_shapes(p.shape[:-2], a.shape[:-1])
        except ValueError:
            raise PrecisionError(
                f"{what}: points {p.shape} and angles {a.shape} do not broadcast"
            ) from None
        p = np.broadcast_to(p, shape + (count, 2))
        a = np.broadcast_to(a, shape + (count,))
    gap = plane.norm(p[..., :, None, :] - p[..., None, :, :])
    scale = np.max(gap, axis=(-1, -2))
    # Poses that all share one point differ only by rotations about it: size them by the point.
    scale = np.where(scale > 0, scale, np.maximum(np.max(plane.norm(p), axis=-1), 1.0))
    for i in range(count):
        for j in range(i + 1, count):
            same = gap[..., i, j] <= SAME_TOL * scale
            if a is not None:
                same = same & (np.abs(_wrap(a[..., i] - a[..., j])) <= SAME_TOL)
            at = _first(same)
            if at is not None:
                kind = "poses" if a is not None else "points"
                raise PrecisionError(
                    f"{what}: {kind} {i + 1} and {j + 1} coincide{_where(at)}: "
                    f"{p[at + (i,)].tolist()} and {p[at + (j,)].tolist()}"
                )
    return p, a, scale


def _rotation(angle: Array) -> Array:
    """Rotation matrices (..., 2, 2) by ``angle``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)


def pose_positions(points: ArrayLike, angles: ArrayLike, first: ArrayLike) -> Array:
    """Where points of the coupler lie in every pose, given where they lie in the first.

    The displacement from pose 1 to pose j turns the plane by αj − α1 about the pose points:
    X ↦ Pj + R(αj − α1)(X − P1).

    Parameters
    ----------
    points : (..., n, 2) the poses' coupler points Pj.
    angles : (..., n) the poses' coupler angles αj (radians).
    first : (..., m, 2) positions of m coupler points in the first pose.

    Returns
    -------
    (..., n, m, 2): position of each point in each pose.

    Examples
    --------
    A quarter turn about the origin carries (1, 0) to (0, 1):

    >>> pose_positions([[0, 0], [0, 0]], [0, np.pi / 2], [[1, 0]]).round(12) + 0.0
    array([[[1., 0.]],
    <BLANKLINE>
           [[0., 1.]]])
    """
    p = np.asarray(points, dtype=float)
    a = np.asarray(angles, dtype=float)
    x = np.asarray(first, dtype=float)
    if p.ndim < 2 or p.shape[-1] != 2 or a.shape[-1:] != p.shape[-2:-1] or x.shape[-1:] != (2,):
        raise PrecisionError(
            f"pose_positions: needs points (..., n, 2), angles (..., n) and first (..., m, 2), "
            f"got {p.shape}, {a.shape} and {x.shape}"
        )
    if x.ndim == 1:
        x = x[None]
    rot = _rotation(a - a[..., :1])  # (..., n, 2, 2)
    rel = x[..., None, :, :] - p[..., :1, None, :]  # (..., 1, m, 2)
    return p[..., :, None, :] + np.einsum("...nij,...nmj->...nmi", rot, rel)


# --- the report ----------------------------------------------------------------------------------


def _order_defect(mech: FourBar, inputs: Array) -> NDArray[np.bool_]:
    """True where one sweep of the input does not meet ``inputs`` in their order."""
    arcs = input_range(mech)
    n = inputs.shape[-1]
    step = np.mod(np.diff(inputs, axis=-1), TWO_PI)
    # Round the full circle once at most, one way or the other.
    ccw = np.sum(step, axis=-1) < TWO_PI
    cw = np.sum(TWO_PI - step, axis=-1) < TWO_PI
    turning = ccw | cw
    lo, hi = np.asarray(arcs.lo), np.asarray(arcs.hi)
    if lo.shape[-1] == 0:
        return ~turning
    span = hi - lo
    tol = 1e-9
    # s[..., j, k]: how far input j lies into arc k (NaN-padded arcs never contain it).
    s = np.mod(inputs[..., :, None] - lo[..., None, :], TWO_PI)
    inside = s <= span[..., None, :] + tol
    arc = np.argmax(inside, axis=-1)  # (..., n)
    one_arc = np.all(arc == arc[..., :1], axis=-1) & np.all(np.any(inside, axis=-1), axis=-1)
    along = np.take_along_axis(s, arc[..., None], -1)[..., 0]
    d = np.diff(along, axis=-1)
    monotone = np.all(d > 0, axis=-1) | np.all(d < 0, axis=-1) if n > 1 else np.ones_like(ccw)
    return np.where(np.asarray(arcs.full), ~turning, ~(one_arc & monotone))


def _branches(A0: Array, B0: Array, A: Array, B: Array, scale: Array, what: str) -> Array:
    """Assembly sign at each position: sign of (B0 − A) × (B − A), as FourBar defines it.

    Raises where the crank pin sits on the rocker pivot: the dyad is folded there and the input
    does not fix the coupler (B may be anywhere on its circle).
    """
    gap = plane.norm(B0[..., None, :] - A) / np.asarray(scale)[..., None]
    at = _first(gap <= SAME_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: at precision position {at[-1] + 1}{_where(at[:-1])} the crank pin A lies on "
            "the rocker pivot B0: the linkage is folded there and its input does not fix the "
            "coupler"
        )
    side = plane.cross(B0[..., None, :] - A, B - A)
    return np.where(side >= 0, 1.0, -1.0)


def _simulate(mech: FourBar, inputs: Array, branches: Array):
    """The engine's motion at ``inputs``, each on its own assembly sign."""
    return evaluate(
        mech.plan, mech.params(), inputs, points=mech.points, branches={"B": branches}, order=0
    )


@dataclass(frozen=True)
class MotionDesign:
    """A four-bar guiding a coupler through precision poses, and how it meets them.

    Arrays have the shape ``batch + (n,)``, n the number of poses (``branch_defect`` and
    ``order_defect`` the batch shape).

    Attributes
    ----------
    mechanism : the four-bar (crank = the first dyad, P = the poses' point, ``assembly`` the
        sign it needs at the first pose).
    inputs : the input θj (radians, in (−π, π]) at which it reaches pose j.
    branches : the assembly sign (±1) it needs at pose j.
    branch_defect : the poses need different assembly signs.
    order_defect : one sweep of the input does not meet the poses in order.
    position_error : |P(θj) − Pj| relative to the poses' spread, P(θj) simulated by the engine on
        each pose's own assembly sign.
    angle_error : |coupler angle at θj − αj| (radians), simulated likewise.
    """

    mechanism: FourBar
    inputs: Array
    branches: Array
    branch_defect: NDArray[np.bool_]
    order_defect: NDArray[np.bool_]
    position_error: Array
    angle_error: Array

    @property
    def error(self) -> Array:
        """The larger of the two errors at the worst pose (batch shape)."""
        return np.maximum(np.max(self.position_error, -1), np.max(self.angle_error, -1))


@dataclass(frozen=True)
class FunctionDesign:
    """A four-bar generating output angles ψ from input angles φ, and how it meets the pairs.

    Arrays have the shape ``batch + (3,)`` unless noted.

    Attributes
    ----------
    mechanism : the four-bar, A0 at the origin and B0 on +x.
    coefficients : ``batch + (3,)`` Freudenstein's K1, K2, K3.
    inputs : the four-bar's input θj (radians, in (−π, π]) at pair j: φj + ``crank_offset``.
    outputs : its output angle (of B − B0 from the frame line) there: ψj + ``rocker_offset``.
    crank_offset, rocker_offset : 0, or π where Freudenstein's equation gave the crank (rocker)
        a negative length: the pin then sits opposite the angle φ (ψ) on the same rigid link, so
        the link turns exactly as prescribed (batch shape).
    branches : the assembly sign (±1) it needs at pair j.
    branch_defect : the pairs need different assembly signs (batch shape).
    order_defect : one sweep of the input does not meet the pairs in order (batch shape).
    error : |simulated output − outputs| at each pair (radians), simulated by the engine.
    """

    mechanism: FourBar
    coefficients: Array
    inputs: Array
    outputs: Array
    crank_offset: Array
    rocker_offset: Array
    branches: Array
    branch_defect: NDArray[np.bool_]
    order_defect: NDArray[np.bool_]
    error: Array


# --- function generation -------------------------------------------------------------------------


def freudenstein(phi: ArrayLike, psi: ArrayLike, frame: ArrayLike = 1.0) -> FunctionDesign:
    """The four-bar whose rocker angle is ψi when its crank angle is φi, i = 1, 2, 3.

    With the frame A0B0 of length d along +x, crank a at φ, rocker c at ψ (both from the frame
    line) and coupler b, the loop closes when (Freudenstein 1955)

        K1 cos ψ − K2 cos φ + K3 = cos(φ − ψ),
        K1 = d/a,  K2 = d/c,  K3 = (a² − b² + c² + d²)/(2ac),

    which is linear in K1..K3: three pairs fix them, and a = d/K1, c = d/K2,
    b² = a² + c² + d² − 2acK3 (= |Bj − Aj|² at every pair, so a real four-bar exists whenever K1
    and K2 do not vanish). A negative a (c) puts the pin opposite φ (ψ) on the same link
    (``crank_offset``/``rocker_offset`` π). The assembly is the one the first pair needs; a
    branch defect (pairs needing different ones) is reported, not hidden.

    Parameters
    ----------
    phi, psi : (..., 3) the input and output angles of the precision pairs (radians).
    frame : the frame length d (batch shape), default 1.

    Raises
    ------
    PrecisionError : not exactly three pairs, coincident pairs, pairs whose equations are
        dependent, a zero K1 or K2 (an infinitely long crank or rocker: a slider), or a pair at
        which the crank pin lies on the rocker pivot (folded: the input does not fix ψ).

    Examples
    --------
    The pairs of a known four-bar (a = 1, b = 3, c = 2, d = 3) give back its links:

    >>> phi = np.radians([40.0, 75.0, 110.0])
    >>> ax, ay = np.cos(phi), np.sin(phi)
    >>> P, Q, R = 4 * (3 - ax), -4 * ay, 9 - 4 - (3 - ax) ** 2 - ay**2
    >>> psi = np.arctan2(Q, P) + np.arccos(R / np.hypot(P, Q))
    >>> d = freudenstein(phi, psi, frame=3.0)
    >>> [round(float(x), 9) for x in (d.mechanism.crank, d.mechanism.coupler, d.mechanism.rocker)]
    [1.0, 3.0, 2.0]
    >>> d.coefficients.round(9), bool(d.branch_defect), float(d.error.max()) < 1e-12
    (array([3.  , 1.5 , 1.25]), False, True)

    K3 = (1 − 9 + 4 + 9)/(2·1·2) = 1.25.

    Pairs with the same cosines give the same equation twice:

    >>> freudenstein(np.radians([30, -30, 60]), np.radians([100, -100, 120]))
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision.PrecisionError: freudenstein: the equations of the pairs are
    dependent (relative determinant 0): no unique four-bar
    """
    what = "freudenstein"
    phi = np.asarray(phi, dtype=float)
    psi = np.asarray(psi, dtype=float)
    if phi.shape[-1:] != (3,) or psi.shape[-1:] != (3,):
        raise PrecisionError(
            f"{what}: needs exactly 3 (φ, ψ) pairs, got φ of shape {phi.shape} and ψ of shape "
            f"{psi.shape}"
        )
    if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(psi))):
        raise PrecisionError(f"{what}: angles must be finite")
    d = np.asarray(frame, dtype=float)
    if not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise PrecisionError(f"{what}: the frame must be a positive length, got {d.tolist()}")
    try:
        shape = np.broadcast_shapes(phi.shape[:-1], psi.shape[:-1], d.shape)
    except ValueError:
        raise PrecisionError(f"{what}: φ {phi.shape}, ψ {psi.shape} do not broadcast") from None
    phi = np.broadcast_to(phi, shape + (3,))
    psi = np.broadcast_to(psi, shape + (3,))
    d = np.broadcast_to(d, shape)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        same = (np.abs(_wrap(phi[..., i] - phi[..., j])) <= SAME_TOL) & (
            np.abs(_wrap(psi[..., i] - psi[..., j])) <= SAME_TOL
        )
        at = _first(same)
        if at is not None:
            raise PrecisionError(f"{what}: pairs {i + 1} and {j + 1} coincide{_where(at)}")
    rows = np.stack((np.cos(psi), -np.cos(phi), np.ones_like(phi)), axis=-1)
    rhs = np.cos(phi - psi)
    det = np.linalg.det(rows) / np.prod(np.linalg.norm(rows, axis=-1), axis=-1)
    at = _first(np.abs(det) < SINGULAR_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: the equations of the pairs are dependent (relative determinant "
            f"{abs(float(det[at])):.3g}){_where(at)}: no unique four-bar"
        )
    k = np.linalg.solve(rows, rhs[..., None])[..., 0]
    k1, k2, k3 = k[..., 0], k[..., 1], k[..., 2]
    # |K| = d/|a| beyond 1/SAME_TOL means a crank (rocker) too short to be a link.
    at = _first((np.abs(k1) < SAME_TOL) | (np.abs(k2) < SAME_TOL))
    if at is not None:
        raise PrecisionError(
            f"{what}: K1 = {float(k1[at]):.6g}, K2 = {float(k2[at]):.6g}{_where(at)}: a zero K "
            "makes the crank or rocker infinitely long (the pairs ask for a slider)"
        )
    a = d / k1
    c = d / k2
    # b² is |Bj − Aj|² at every pair (the equation times 2ac), so never negative: it vanishes
    # only where the pairs put the crank pin on the rocker pin.
    b2 = a**2 + c**2 + d**2 - 2 * a * c * k3
    at = _first(b2 <= (SAME_TOL * d) ** 2)
    if at is not None:
        raise PrecisionError(
            f"{what}: K = {k[at].round(9).tolist()}{_where(at)} gives the coupler b² = "
            f"{float(b2[at]):.3g}: the pairs put the crank pin on the rocker pin"
        )
    crank_offset = np.where(a < 0, np.pi, 0.0)
    rocker_offset = np.where(c < 0, np.pi, 0.0)
    inputs = _wrap(phi + crank_offset[..., None])
    outputs = _wrap(psi + rocker_offset[..., None])
    a, c = np.abs(a), np.abs(c)
    A0 = np.zeros(shape + (2,))
    B0 = np.stack((d, np.zeros_like(d)), axis=-1)
    A = plane.polar(a[..., None], inputs)
    B = B0[..., None, :] + plane.polar(c[..., None], outputs)
    branches = _branches(A0, B0, A, B, d, what)
    mech = FourBar(A0=A0, B0=B0, crank=a, coupler=np.sqrt(b2), rocker=c, assembly=branches[..., 0])
    motion = _simulate(mech, inputs, branches)
    rel = motion.positions["B"] - motion.positions["B0"]
    error = np.abs(_wrap(np.arctan2(rel[..., 1], rel[..., 0]) - outputs))
    return FunctionDesign(
        mechanism=mech,
        coefficients=k,
        inputs=inputs,
        outputs=outputs,
        crank_offset=crank_offset,
        rocker_offset=rocker_offset,
        branches=branches,
        branch_defect=np.any(branches != branches[..., :1], axis=-1),
        order_defect=_order_defect(mech, inputs),
        error=error,
    )


def chebyshev_spacing(start: ArrayLike, end: ArrayLike, n: int = 3) -> Array:
    """Chebyshev's precision points on [start, end]: the n zeros of the Chebyshev polynomial.

    xj = (start + end)/2 − (end − start)/2 · cos((2j − 1)π/(2n)), j = 1..n: the spacing that
    (nearly) minimises the largest structural error of an n-point function generator (Freudenstein
    1955; Hartenberg and Denavit, *Kinematic Synthesis of Linkages*, 1964, §11).

    Parameters
    ----------
    start, end : the range of x (broadcast together).
    n : how many precision points (≥ 1).

    Returns
    -------
    ``broadcast(start, end).shape + (n,)``, increasing from start to end.

    Examples
    --------
    >>> chebyshev_spacing(0.0, 1.0).round(6)
    array([0.066987, 0.5     , 0.933013])
    >>> chebyshev_spacing(1.0, 1.0)
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision.PrecisionError: chebyshev_spacing: the range [1.0, 1.0] is empty
    """
    if int(n) != n or n < 1:
        raise PrecisionError(f"chebyshev_spacing: n must be a positive integer, got {n!r}")
    s = np.asarray(start, dtype=float)
    e = np.asarray(end, dtype=float)
    s, e = np.broadcast_arrays(s, e)
    at = _first(~np.isfinite(s) | ~np.isfinite(e) | (s == e))
    if at is not None:
        raise PrecisionError(
            f"chebyshev_spacing: the range [{float(s[at])}, {float(e[at])}] is empty{_where(at)}"
        )
    j = np.arange(1, int(n) + 1)
    return (s + e)[..., None] / 2 - (e - s)[..., None] / 2 * np.cos((2 * j - 1) * np.pi / (2 * n))


def _linear_map(value: Array, lo: Array, hi: Array, to_lo: Array, to_hi: Array) -> Array:
    return to_lo + (value - lo) / (hi - lo) * (to_hi - to_lo)


def _ranges(f, x_range, phi_range, psi_range, what):
    x_range, phi_range, psi_range = (
        np.asarray(r, dtype=float) for r in (x_range, phi_range, psi_range)
    )
    for name, r in (("x_range", x_range), ("phi_range", phi_range), ("psi_range", psi_range)):
        if r.shape[-1:] != (2,):
            raise PrecisionError(f"{what}: {name} must be (start, end) pairs, got shape {r.shape}")
    x0, x1 = x_range[..., 0], x_range[..., 1]
    y0, y1 = np.asarray(f(x0), dtype=float), np.asarray(f(x1), dtype=float)
    for name, lo, hi in (
        ("x_range", x0, x1),
        ("f(x_range)", y0, y1),
        ("phi_range", phi_range[..., 0], phi_range[..., 1]),
        ("psi_range", psi_range[..., 0], psi_range[..., 1]),
    ):
        at = _first(np.broadcast_to(~np.isfinite(lo) | ~np.isfinite(hi) | (lo == hi), np.shape(lo)))
        if at is not None:
            raise PrecisionError(
                f"{what}: {name} must span a range, got [{float(np.asarray(lo)[at])}, "
                f"{float(np.asarray(hi)[at])}]{_where(at)}"
            )
    return x0, x1, y0, y1, phi_range, psi_range


def function_pairs(
    f: Callable[[Array], ArrayLike],
    x_range: ArrayLike,
    phi_range: ArrayLike,
    psi_range: ArrayLike,
    n: int = 3,
) -> tuple[Array, Array, Array]:
    """Precision pairs (φ, ψ) for generating y = f(x) over a range: the textbook route.

    x runs over [x0, x1] as the crank turns linearly from φ0 to φ1, y = f(x) over [f(x0), f(x1)]
    as the rocker turns linearly from ψ0 to ψ1; the precision points are Chebyshev-spaced in x
    (:func:`chebyshev_spacing`).

    Parameters
    ----------
    f : the function, vectorised (called on arrays of x).
    x_range : (..., 2) the range (x0, x1).
    phi_range, psi_range : (..., 2) the crank's and the rocker's angles at x0 and at x1
        (radians, from the frame line): the designer's free choices.
    n : how many pairs (3 for :func:`freudenstein`).

    Returns
    -------
    (x, φ, ψ), each ``batch + (n,)``.

    Examples
    --------
    y = log10 x on [1, 2] (Freudenstein's own example function), the crank from 30° to 120°,
    the rocker from 60° to 150°:

    >>> x, phi, psi = function_pairs(np.log10, (1, 2), np.radians([30, 120]),
    ...                              np.radians([60, 150]))
    >>> x.round(6), np.degrees(phi).round(6), np.degrees(psi).round(6)
    (array([1.066987, 1.5     , 1.933013]), array([ 36.028857,  75.      , 113.971143]),
     array([ 68.41887 , 112.646625, 145.576601]))
    """
    what = "function_pairs"
    x0, x1, y0, y1, phi_range, psi_range = _ranges(f, x_range, phi_range, psi_range, what)
    x = chebyshev_spacing(x0, x1, n)
    y = np.asarray(f(x), dtype=float)
    if not np.all(np.isfinite(y)):
        raise PrecisionError(f"{what}: f is not finite at the precision points x = {x.tolist()}")
    phi = _linear_map(x, x0[..., None], x1[..., None], phi_range[..., :1], phi_range[..., 1:])
    psi = _linear_map(y, y0[..., None], y1[..., None], psi_range[..., :1], psi_range[..., 1:])
    return x, phi, psi


def function_error(
    design: FunctionDesign,
    f: Callable[[Array], ArrayLike],
    x_range: ArrayLike,
    phi_range: ArrayLike,
    psi_range: ArrayLike,
    samples: int = 101,
) -> tuple[Array, Array]:
    """The structural error of a function generator: generated y minus f(x), over the range.

    The design's four-bar is simulated by the engine on its own assembly at the inputs that the
    linear map of :func:`function_pairs` gives x; its output angle is mapped back to y. The
    error vanishes at the precision points.

    Returns
    -------
    (x, error), each ``batch + (samples,)``; the error is NaN where the four-bar cannot assemble
    (its input cannot reach that x).

    Examples
    --------
    >>> rng = ((1, 2), np.radians([30, 120]), np.radians([60, 150]))
    >>> design = freudenstein(*function_pairs(np.log10, *rng)[1:])
    >>> x, err = function_error(design, np.log10, *rng, samples=5)
    >>> x, (err * 1e5).round()
    (array([1.  , 1.25, 1.5 , 1.75, 2.  ]), array([141., -68.,  -0.,  -5.,  23.]))

    (in units of 1e-5, against log10 2 ≈ 0.301 over the range).

    The same route for y = x² on [0, 1] (crank 45°–135°, rocker 135°–225°) has a branch defect:
    the third pair needs the other assembly, so the four-bar, on the first pair's, misses it.

    >>> rng = ((0, 1), np.radians([45, 135]), np.radians([135, 225]))
    >>> design = freudenstein(*function_pairs(np.square, *rng)[1:])
    >>> design.branches, bool(design.branch_defect)
    (array([-1., -1.,  1.]), True)
    """
    what = "function_error"
    x0, x1, y0, y1, phi_range, psi_range = _ranges(f, x_range, phi_range, psi_range, what)
    t = np.linspace(0.0, 1.0, int(samples))
    x = x0[..., None] + (x1 - x0)[..., None] * t
    phi = _linear_map(x, x0[..., None], x1[..., None], phi_range[..., :1], phi_range[..., 1:])
    y = np.asarray(f(x), dtype=float)
    psi = _linear_map(y, y0[..., None], y1[..., None], psi_range[..., :1], psi_range[..., 1:])
    mech = design.mechanism
    theta = phi + np.asarray(design.crank_offset)[..., None]
    motion = evaluate(mech.plan, mech.params(), theta, points=mech.points, order=0)
    rel = motion.positions["B"] - motion.positions["B0"]
    out = np.arctan2(rel[..., 1], rel[..., 0]) - np.asarray(design.rocker_offset)[..., None]
    # The angle error, turned into y by the linear map's slope.
    slope = (y1 - y0)[..., None] / (psi_range[..., 1:] - psi_range[..., :1])
    return x, _wrap(out - psi) * slope


# --- motion generation ---------------------------------------------------------------------------


def _circle_centres(positions: Array, scale: Array, what: str, label: str) -> Array:
    """Centres (..., 2) of the circles through three positions (..., 3, 2) each."""
    p1, p2, p3 = positions[..., 0, :], positions[..., 1, :], positions[..., 2, :]
    r2, r3 = p2 - p1, p3 - p1
    # g − p1 solves r2·x = |r2|²/2, r3·x = |r3|²/2 (the perpendicular bisectors).
    x, det = plane.solve_2x2_rows(r2, r3, plane.dot(r2, r2) / 2, plane.dot(r3, r3) / 2)
    at = _first(np.abs(det) <= SINGULAR_TOL * scale**2)
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label}'s three positions {positions[at].round(9).tolist()} are "
            f"collinear or coincide{_where(at)}: no circle (or a circle of infinite radius, a "
            "slider) passes through them"
        )
    return p1 + x


def _dyad_check(
    positions: Array, centres: Array, scale: Array, what: str, label: str, tol: float
) -> None:
    radius = plane.norm(positions - centres[..., None, :])
    off = np.max(np.abs(radius - radius[..., :1]), axis=-1) / scale
    at = _first(~(off <= tol))
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label}'s positions in the poses lie off a circle about its centre "
            f"{centres[at].round(9).tolist()} by {float(off[at]):.3g} of the poses' spread"
            f"{_where(at)}: that dyad does not guide the body through the poses"
        )


def fourbar_from_dyads(
    points: ArrayLike,
    angles: ArrayLike,
    centres: ArrayLike,
    circles: ArrayLike,
    *,
    tol: float = DYAD_TOL,
) -> MotionDesign:
    """The four-bar made of two dyads that each guide the body through the poses.

    Each dyad is a centre point (ground pivot) and a circle point (moving pivot, at its position
    in the first pose); the first dyad becomes the crank A0A, the second the rocker B0B, the
    poses' point the coupler point P. Any number of poses (≥ 2); the dyads may come from
    :func:`three_pose_fourbar`'s construction or from
    :func:`linkwright.synthesis.burmester.four_pose_dyads` /
    :func:`~linkwright.synthesis.burmester.burmester_points`.

    Parameters
    ----------
    points : (..., n, 2) the poses' coupler points.
    angles : (..., n) the poses' coupler angles (radians).
    centres : (..., 2, 2) the two ground pivots (crank's first).
    circles : (..., 2, 2) the two moving pivots in the first pose.
    tol : how far (relative to the poses' spread) a moving pivot's positions may lie off a circle
        about its centre.

    Raises
    ------
    PrecisionError : coincident poses, a dyad off its circle by more than ``tol``, a moving
        pivot on its centre (a crank of length 0), the two moving pivots together, or a pose at
        which the crank pin lies on the rocker pivot (folded: the input does not fix the pose).

    Examples
    --------
    Four poses of a known four-bar's coupler, with its own pivots, rebuild it:

    >>> from linkwright.mechanisms import FourBar, solve
    >>> fb = FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=2.5, rocker=1.5, u=1, v=0.5)
    >>> m = solve(fb, np.radians([60, 90, 120, 150]))
    >>> line = m.positions["B"] - m.positions["A"]
    >>> angles = np.arctan2(line[:, 1], line[:, 0])
    >>> circles = [m.positions["A"][0], m.positions["B"][0]]
    >>> d = fourbar_from_dyads(m.positions["P"], angles, [[0, 0], [2, 0]], circles)
    >>> np.degrees(d.inputs).round(9), d.branches, float(d.mechanism.u), float(d.mechanism.v)
    (array([ 60.,  90., 120., 150.]), array([1., 1., 1., 1.]), 1.0, 0.5)

    A ground pivot that is not its moving pivot's centre:

    >>> fourbar_from_dyads(m.positions["P"], angles, [[0, 0], [2.1, 0]], circles)
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision.PrecisionError: fourbar_from_dyads: the rocker pivot's
    positions in the poses lie off a circle about its centre [2.1, 0.0] by 0.0655 of the poses'
    spread: that dyad does not guide the body through the poses
    """
    what = "fourbar_from_dyads"
    p, a, scale = _pose_set(points, angles, None, what)
    g = np.asarray(centres, dtype=float)
    c = np.asarray(circles, dtype=float)
    if g.shape[-2:] != (2, 2) or c.shape[-2:] != (2, 2):
        raise PrecisionError(
            f"{what}: centres and circles must have shape (..., 2, 2) (two dyads), got "
            f"{g.shape} and {c.shape}"
        )
    if not (np.all(np.isfinite(g)) and np.all(np.isfinite(c))):
        raise PrecisionError(f"{what}: centres and circles must be finite")
    shape = np.broadcast_shapes(p.shape[:-2], g.shape[:-2], c.shape[:-2])
    p = np.broadcast_to(p, shape + p.shape[-2:])
    a = np.broadcast_to(a, shape + a.shape[-1:])
    g = np.broadcast_to(g, shape + (2, 2))
    c = np.broadcast_to(c, shape + (2, 2))
    scale = np.broadcast_to(scale, shape)
    moved = pose_positions(p, a, c)  # (..., n, 2, 2)
    for k, label in ((0, "crank"), (1, "rocker")):
        arm = plane.norm(c[..., k, :] - g[..., k, :]) / scale
        at = _first(arm <= SAME_TOL)
        if at is not None:
            raise PrecisionError(
                f"{what}: the {label}'s moving pivot {c[at + (k,)].tolist()} lies on its centre"
                f"{_where(at)}: a link of length 0"
            )
        _dyad_check(moved[..., k, :], g[..., k, :], scale, what, f"{label} pivot", tol)
    link = c[..., 1, :] - c[..., 0, :]
    coupler = plane.norm(link)
    at = _first(coupler <= SAME_TOL * scale)
    if at is not None:
        raise PrecisionError(
            f"{what}: the two moving pivots coincide at {c[at + (0,)].tolist()}{_where(at)}: "
            "a coupler of length 0"
        )
    e = link / coupler[..., None]
    rel = p[..., 0, :] - c[..., 0, :]
    A, B = moved[..., 0, :], moved[..., 1, :]
    branches = _branches(g[..., 0, :], g[..., 1, :], A, B, scale, what)
    mech = FourBar(
        A0=g[..., 0, :],
        B0=g[..., 1, :],
        crank=plane.norm(c[..., 0, :] - g[..., 0, :]),
        coupler=coupler,
        rocker=plane.norm(c[..., 1, :] - g[..., 1, :]),
        u=plane.dot(rel, e),
        v=plane.cross(e, rel),
        assembly=branches[..., 0],
    )
    arm = A - g[..., None, 0, :]
    inputs = np.arctan2(arm[..., 1], arm[..., 0])
    # The coupler line A→B sits at a fixed angle to the poses' angle.
    offset = np.arctan2(link[..., 1], link[..., 0]) - a[..., 0]
    motion = _simulate(mech, inputs, branches)
    line = motion.positions["B"] - motion.positions["A"]
    turned = np.arctan2(line[..., 1], line[..., 0]) - offset[..., None]
    return MotionDesign(
        mechanism=mech,
        inputs=inputs,
        branches=branches,
        branch_defect=np.any(branches != branches[..., :1], axis=-1),
        order_defect=_order_defect(mech, inputs),
        position_error=plane.norm(motion.positions["P"] - p) / scale[..., None],
        angle_error=np.abs(_wrap(turned - a)),
    )


def three_pose_fourbar(
    points: ArrayLike,
    angles: ArrayLike,
    circles: ArrayLike,
    *,
    frame: str = "first",
) -> MotionDesign:
    """The four-bar guiding a body through three poses from two chosen moving pivots.

    Each moving pivot (circle point) takes three positions; its ground pivot (centre point) is
    the centre of the circle through them (Burmester; Sandor and Erdman 1984, §2.13; McCarthy
    and Soh 2011, §4.2). Every point of the body but those whose positions are collinear is a
    circle point: three poses leave a designer ∞⁴ four-bars.

    Parameters
    ----------
    points : (..., 3, 2) the poses' coupler points.
    angles : (..., 3) the poses' coupler angles (radians).
    circles : (..., 2, 2) the two moving pivots (crank's first).
    frame : ``"first"``: the moving pivots' positions in the first pose; ``"coupler"``: their
        coordinates in the coupler's own frame (origin at the pose point, x-axis at the pose's
        angle).

    Raises
    ------
    PrecisionError : not three poses, coincident poses, or a moving pivot whose three positions
        are collinear (its centre would be at infinity: a slider).

    Examples
    --------
    >>> pts, ang = [[0, 0], [1, 0.5], [2, 0]], np.radians([0, 30, 60])
    >>> d = three_pose_fourbar(pts, ang, [[0, -1], [1, -1]])
    >>> d.mechanism.A0.round(6), d.mechanism.B0.round(6)
    (array([ 1.893211, -3.387878]), array([ 3.545017, -2.676048]))
    >>> bool(d.branch_defect), bool(d.error < 1e-12)
    (False, True)

    A moving pivot whose three positions are collinear has no centre:

    >>> three_pose_fourbar([[0, 0], [1, 0], [2, 0]], [0, 0, 0], [[0, 1], [1, 1]])
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision.PrecisionError: three_pose_fourbar: the crank pivot's three
    positions [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]] are collinear or coincide: no circle (or a
    circle of infinite radius, a slider) passes through them
    """
    what = "three_pose_fourbar"
    p, a, scale = _pose_set(points, angles, 3, what)
    c = np.asarray(circles, dtype=float)
    if c.shape[-2:] != (2, 2) or not np.all(np.isfinite(c)):
        raise PrecisionError(
            f"{what}: circles must be two finite moving pivots, shape (..., 2, 2), got {c.shape}"
        )
    if frame == "coupler":
        c = p[..., :1, :] + np.einsum("...ij,...kj->...ki", _rotation(a[..., 0]), c)
    elif frame != "first":
        raise PrecisionError(f"{what}: frame must be 'first' or 'coupler', got {frame!r}")
    shape = np.broadcast_shapes(p.shape[:-2], c.shape[:-2])
    p = np.broadcast_to(p, shape + (3, 2))
    a = np.broadcast_to(a, shape + (3,))
    c = np.broadcast_to(c, shape + (2, 2))
    scale = np.broadcast_to(scale, shape)
    moved = pose_positions(p, a, c)  # (..., 3, 2, 2)
    g = np.stack(
        [
            _circle_centres(moved[..., k, :], scale, what, label)
            for k, label in ((0, "crank pivot"), (1, "rocker pivot"))
        ],
        axis=-2,
    )
    return fourbar_from_dyads(p, a, g, c)


# --- path generation with prescribed timing ------------------------------------------------------


def _dyad_solve(
    delta: Array, turn: Array, coupler_turn: Array, scale: Array, what: str, label: str
) -> tuple[Array, Array]:
    """W, Z (complex) of the standard dyad form W(e^{iβj} − 1) + Z(e^{iαj} − 1) = δj, j = 2, 3."""
    m11, m12 = np.exp(1j * turn[..., 0]) - 1, np.exp(1j * coupler_turn[..., 0]) - 1
    m21, m22 = np.exp(1j * turn[..., 1]) - 1, np.exp(1j * coupler_turn[..., 1]) - 1
    det = m11 * m22 - m12 * m21
    at = _first(np.abs(det) <= SINGULAR_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label} dyad's equations are singular (determinant "
            f"{abs(complex(det[at])):.3g}){_where(at)}: choose other rotations (none may be 0 for "
            "both, and the ground link's may not equal the coupler's)"
        )
    W = (delta[..., 0] * m22 - delta[..., 1] * m12) / det
    Z = (m11 * delta[..., 1] - m21 * delta[..., 0]) / det
    return W, Z


def path_with_timing(
    points: ArrayLike,
    crank_rotations: ArrayLike,
    coupler_rotations: ArrayLike,
    rocker_rotations: ArrayLike,
) -> MotionDesign:
    """The four-bar whose coupler point passes three points at three given crank rotations.

    Each side of the four-bar is a dyad: a ground link W and a coupler vector Z to the traced
    point, the point moving by δj = Pj − P1 while the ground link turns by βj and the coupler by
    αj (Sandor and Erdman 1984, §2.9):

        W(e^{iβj} − 1) + Z(e^{iαj} − 1) = δj,   j = 2, 3,

    linear in W, Z once the angles are fixed. The crank rotations β2, β3 are the prescribed
    timing; the coupler rotations α2, α3 and the rocker rotations γ2, γ3 (the second dyad's
    ground-link angles, with the same α) are the designer's free choices (∞⁴ solutions).

    Parameters
    ----------
    points : (..., 3, 2) the path points P1, P2, P3.
    crank_rotations : (..., 2) β2, β3, the crank's rotation from P1 to P2 and to P3 (radians).
    coupler_rotations : (..., 2) α2, α3 (radians, free).
    rocker_rotations : (..., 2) γ2, γ3 (radians, free).

    Returns
    -------
    A :class:`MotionDesign` for the poses (Pj, αj) with α1 = 0: ``inputs[..., j] −
    inputs[..., 0]`` equals βj (mod 2π).

    Raises
    ------
    PrecisionError : coincident points, rotations that make a dyad's equations singular, or
        rocker rotations equal to the crank's (one dyad twice).

    Examples
    --------
    >>> d = path_with_timing([[0, 0], [1, 0.5], [2, 0]], np.radians([60, 120]),
    ...                      np.radians([10, 5]), np.radians([30, 50]))
    >>> np.degrees(d.inputs - d.inputs[0]).round(9), bool(d.error < 1e-12)
    (array([  0.,  60., 120.]), True)
    """
    what = "path_with_timing"
    p, _, scale = _pose_set(points, None, 3, what)
    rot = [
        np.asarray(r, dtype=float) for r in (crank_rotations, coupler_rotations, rocker_rotations)
    ]
    for name, r in zip(
        ("crank_rotations", "coupler_rotations", "rocker_rotations"), rot, strict=True
    ):
        if r.shape[-1:] != (2,) or not np.all(np.isfinite(r)):
            raise PrecisionError(
                f"{what}: {name} must be finite (…, 2) angles, got shape {r.shape}"
            )
    shape = np.broadcast_shapes(p.shape[:-2], *(r.shape[:-1] for r in rot))
    p = np.broadcast_to(p, shape + (3, 2))
    beta, alpha, gamma = (np.broadcast_to(r, shape + (2,)) for r in rot)
    scale = np.broadcast_to(scale, shape)
    at = _first(np.all(np.abs(_wrap(beta - gamma)) <= SAME_TOL, axis=-1))
    if at is not None:
        raise PrecisionError(
            f"{what}: the rocker rotations equal the crank rotations{_where(at)}: the two dyads "
            "would coincide"
        )
    z = p[..., 0] + 1j * p[..., 1]
    delta = z[..., 1:] - z[..., :1]
    centres, circles = [], []
    for turn, label in ((beta, "crank"), (gamma, "rocker")):
        W, Z = _dyad_solve(delta, turn, alpha, scale, what, label)
        moving = z[..., 0] - Z
        ground = moving - W
        centres.append(np.stack((ground.real, ground.imag), -1))
        circles.append(np.stack((moving.real, moving.imag), -1))
    angles = np.concatenate((np.zeros(shape + (1,)), alpha), axis=-1)
    return fourbar_from_dyads(p, angles, np.stack(centres, -2), np.stack(circles, -2))

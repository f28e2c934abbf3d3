"""Burmester theory: four-bars guiding a body through four and five poses.

A dyad (a ground pivot g, the *centre point*, and a moving pivot c, the *circle point*, given by
its position in the first pose) guides the body when c's positions in every pose lie on a
circle about g. Write it in the standard complex form (Sandor and Erdman 1984, ch. 2): the
ground link W turns by βj and the coupler vector Z (moving pivot → pose point) by αj between
pose 1 and pose j, and the pose point moves by δj:

    W(e^{iβj} − 1) + Z(e^{iαj} − 1) = δj,   j = 2, …, n.

- **Four poses** (j = 2, 3, 4): three equations in W, Z have a solution only where the determinant
  of [e^{iβj} − 1, e^{iαj} − 1, δj] vanishes, Δ1 + Δ2 e^{iβ2} + Δ3 e^{iβ3} + Δ4 e^{iβ4} = 0 (the
  Δk cofactors of the first column, Δ1 = −Δ2 − Δ3 − Δ4). For each β2 this closes a
  *compatibility linkage* of links |Δ3|, |Δ4|: two (β3, β4), two dyads. Sweeping β2 traces the
  centre-point curve (the g) and the circle-point curve (the c), both circular cubics
  (:func:`centre_point_curve`, :func:`four_pose_dyads`, :func:`four_pose_fourbar`).
- **Five poses**: the Burmester points are the dyads on both four-pose curves, of poses 1234
  and 1235. Eliminating β4 and β5 (|Δ1 + Δ2u + Δ3v| = |Δ4|, and the same for 1235, with
  u = e^{iβ2}, v = e^{iβ3}, ū = 1/u on the unit circle) leaves two polynomials quadratic in v;
  their resultant is a degree-6 polynomial in u. Two of its roots are spurious for every pose
  set, u = 1 (β ≡ 0, the ground link does not turn) and u = e^{iα2} (β ≡ α, the link turns
  with the coupler), and are divided out; the other four are the Burmester points, real where
  |u| = 1: none, two or four (:func:`burmester_points`, :func:`burmester_fourbars`). The
  polynomial is self-inversive (it comes from modulus equations), so on the unit circle it is a
  real function of β2 times a phase, and its real roots are found as sign changes refined by
  Brent's method rather than read off complex roots (two nearly coincident real roots would
  otherwise pass for a complex pair).

Every dyad, on the curves and at the Burmester points, is then polished by Newton's method on the
real equations |Dj c − g|² = |c − g|² (Dj the displacement from pose 1 to pose j; with β2 held
on the curves) and kept only where they hold to rounding: the complex route alone loses digits
where poses nearly share a pole.

Where the centre point goes to infinity the dyad is a slider (RP): those samples are invalid
here, and the slider dyads (the slider-point circle of three poses, the Ball point of four) and
the slider-cranks they make live in :mod:`linkwright.synthesis.slider_dyads`.

References: L. Burmester, *Lehrbuch der Kinematik* (1888). G. N. Sandor and A. G. Erdman,
*Advanced Mechanism Design* vol. 2 (Prentice-Hall 1984), §2.14–2.20. J. M. McCarthy and G. S.
Soh, *Geometric Design of Linkages*, 2nd ed. (Springer 2011), ch. 5.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from itertools import combinations, permutations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from linkwright.synthesis.precision import (
    MotionDesign,
    PrecisionError,
    batch_place,
    first_true,
    fourbar_from_dyads,
    pose_set,
)

__all__ = [
    "BurmesterCurves",
    "BurmesterPoints",
    "burmester_fourbars",
    "burmester_points",
    "centre_point_curve",
    "four_pose_dyads",
    "four_pose_fourbar",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
# The dyad equations' best 2×2 determinant (in units of the poses' spread) below which a sample
# of the curves is a point at infinity (a slider), not a dyad.
DEGENERATE = 1e-13
# Compatibility cofactors below this (in units of the poses' spread) vanish: the poses only
# translate, or all turn about one point, and the Burmester points are not isolated.
VANISHING = 1e-12
# Accepted residual of (|Dj c − g|² − |c − g|²)/2 (in units of the poses' spread squared, and
# relative to 1 + |g|² + |c|²): a true dyad polishes to rounding (1e-16); beside a double point
# a complex pair leaves a near-miss of the real equations at 1e-12 or so, which is no dyad.
RESIDUAL = 1e-14
NEWTON_STEPS = 6
# A sample of the four-pose curves whose moving pivot is off its circle by more than this
# (relative to the radius, or the poses' spread if larger) is not a dyad.
RADIUS_TOL = 1e-10


def _normalised(points: Array, angles: Array, scale: Array) -> tuple[CArray, Array]:
    """δj (complex, pose 1 at the origin, in units of the spread) and αj − α1."""
    # asarray: the stubs read float + 1j·float as float; the sum is complex128 already.
    z = np.asarray(points[..., 0] + 1j * points[..., 1], dtype=np.complex128) / scale[..., None]
    return z - z[..., :1], angles - angles[..., :1]


def _cofactors(delta: CArray, alpha: Array, k: int) -> tuple[CArray, CArray, CArray, CArray]:
    """Δ1, Δ2, Δ3, Δk of the compatibility equation of poses 1, 2, 3 and k (0-based index)."""
    a = np.exp(1j * alpha) - 1
    d2 = a[..., 2] * delta[..., k] - a[..., k] * delta[..., 2]
    d3 = -(a[..., 1] * delta[..., k] - a[..., k] * delta[..., 1])
    dk = a[..., 1] * delta[..., 2] - a[..., 2] * delta[..., 1]
    return -(d2 + d3 + dk), d2, d3, dk


def _dyads_from_turns(delta: CArray, alpha: Array, turns: CArray) -> tuple[CArray, CArray, Array]:
    """W, Z from the dyad equations of poses 2..n, given e^{iβj} (..., n − 1).

    Uses the best-conditioned pair of equations (all n − 1 agree where the β are compatible);
    returns W, Z and that pair's |determinant|.
    """
    x = turns - 1
    a = np.exp(1j * alpha[..., 1:]) - 1
    d = delta[..., 1:]
    best_det = np.zeros(x.shape[:-1])
    W = np.full(x.shape[:-1], np.nan + 0j)
    Z = np.full(x.shape[:-1], np.nan + 0j)
    for p, q in combinations(range(x.shape[-1]), 2):
        det = x[..., p] * a[..., q] - x[..., q] * a[..., p]
        better = np.abs(det) > best_det
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            w = (d[..., p] * a[..., q] - d[..., q] * a[..., p]) / det
            zz = (x[..., p] * d[..., q] - x[..., q] * d[..., p]) / det
        W = np.where(better, w, W)
        Z = np.where(better, zz, Z)
        best_det = np.where(better, np.abs(det), best_det)
    return W, Z, best_det


# --- four poses ----------------------------------------------------------------------------------


def four_pose_dyads(
    points: ArrayLike, angles: ArrayLike, beta2: ArrayLike
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """The two dyads guiding a body through four poses whose ground link turns by β2 from pose 1
    to pose 2.

    For each β2 the compatibility linkage (links |Δ3|, |Δ4|, closing Δ1 + Δ2e^{iβ2}) has two
    closures, the two dyads; where it cannot close (or where the dyad is at infinity: a slider,
    or where the poses are degenerate and the dyad misses a pose) there is none (``valid``
    False). Each dyad is polished on the real equations: its moving pivot's four positions lie
    on a circle about its centre to within 1e-10 of the radius.

    Parameters
    ----------
    points : (..., 4, 2) the poses' coupler points.
    angles : (..., 4) the poses' coupler angles (radians).
    beta2 : (m,) or ``batch + (m,)`` the ground link's rotation from pose 1 to pose 2 (radians).

    Returns
    -------
    centres, circles : ``batch + (2, m, 2)``: the ground pivots and the moving pivots (in the
        first pose) of the two closures; NaN where ``valid`` is False.
    valid : ``batch + (2, m)``.

    Raises
    ------
    PrecisionError : not four poses, or coincident poses.

    Examples
    --------
    The poses of a four-bar's coupler, and its crank's turn from pose 1 to 2: one of the two
    dyads is its crank, A0 = (0, 0) and A = (cos 20°, sin 20°).

    >>> from linkwright.mechanisms import FourBar, solve
    >>> fb = FourBar(A0=[0, 0], B0=[3, 0.5], crank=1, coupler=3.2, rocker=2.6, u=1, v=1.5)
    >>> m = solve(fb, np.radians([20, 50, 90, 140]))
    >>> line = m.positions["B"] - m.positions["A"]
    >>> angles = np.arctan2(line[:, 1], line[:, 0])
    >>> g, c, ok = four_pose_dyads(m.positions["P"], angles, [np.radians(30)])
    >>> g.round(6) + 0.0, ok
    (array([[[0.      , 0.      ]],
    <BLANKLINE>
           [[0.867759, 8.172181]]]), array([[ True],
           [ True]]))
    >>> np.degrees(np.arctan2(c[0, 0, 1], c[0, 0, 0])).round(9)
    np.float64(20.0)
    """
    p, a, scale = pose_set(points, angles, 4, "four_pose_dyads")
    beta2 = np.asarray(beta2, dtype=float)
    if beta2.ndim == 0:
        beta2 = beta2[None]
    if not np.all(np.isfinite(beta2)):
        raise PrecisionError("four_pose_dyads: beta2 must be finite")
    delta, alpha = _normalised(p, a, scale)
    d1, d2, d3, d4 = (x[..., None, None] for x in _cofactors(delta, alpha, 3))
    u = np.exp(1j * beta2)[..., None, :]  # batch + (1, m)
    R = -(d1 + d2 * u)
    r, m3, m4 = np.abs(R), np.abs(d3), np.abs(d4)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos3 = (r**2 + m3**2 - m4**2) / (2 * r * m3)
    closes = np.abs(cos3) <= 1
    side = np.array([1.0, -1.0])[:, None]
    # The side of R on which Δ3e^{iβ3} lies: the two closures of the compatibility linkage.
    ang3 = np.angle(R) + side * np.arccos(np.clip(cos3, -1, 1))
    # Δ3 or Δ4 vanish only for degenerate pose sets; those samples come out invalid.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = np.exp(1j * ang3) * m3 / d3
        w = (R - d3 * v) / d4
        turns = np.stack(np.broadcast_arrays(u, v, w), axis=-1)
        W, Z, det = _dyads_from_turns(delta[..., None, None, :], alpha[..., None, None, :], turns)
        x = np.stack((-(W + Z).real, -(W + Z).imag, -Z.real, -Z.imag), axis=-1)
    # Newton on the real equations (β2 held) takes each dyad to full precision, where the
    # complex route loses digits (poses that nearly share a pole make Δ4 small).
    dd = np.broadcast_to(delta[..., None, None, 1:], x.shape[:-1] + (3,))
    aa = np.broadcast_to(alpha[..., None, None, 1:], x.shape[:-1] + (3,))
    bb = np.broadcast_to(beta2[..., None, :], x.shape[:-1])
    ok = closes & (det > DEGENERATE) & np.all(np.isfinite(x), axis=-1)
    x = np.where(ok[..., None], x, 0.0)
    x[ok] = _polish(x[ok], dd[ok], aa[ok], bb[ok])
    # Every equation must hold, not only the pair solved: where the poses are degenerate (three
    # sharing a pole: Δ4 = 0 leaves β4 free) the compatibility linkage's closure is not enough.
    with np.errstate(all="ignore"):
        valid = ok & (_radius_error(x, dd, aa) <= RADIUS_TOL) & (_turn_error(x, dd, aa, bb) <= 1e-9)
    shape = valid.shape
    origin = p[..., 0, None, None, :]
    s = scale[..., None, None, None]
    nan = np.full(shape + (2,), np.nan)
    centres = np.where(valid[..., None], origin + s * x[..., :2], nan)
    circles = np.where(valid[..., None], origin + s * x[..., 2:], nan)
    return centres, circles, valid


# --- the real equations of a dyad ----------------------------------------------------------------


def _moved(x: Array, d: CArray, alpha: Array) -> Array:
    """Dj c = Rj c + dj for the circle point c = x[..., 2:] (pose 1 at the origin): (..., m, 2)."""
    c = x[..., None, 2:]
    cs, sn = np.cos(alpha), np.sin(alpha)
    return np.stack(
        (cs * c[..., 0] - sn * c[..., 1] + d.real, sn * c[..., 0] + cs * c[..., 1] + d.imag), -1
    )


def _equations(x: Array, d: CArray, alpha: Array) -> tuple[Array, Array]:
    """Fj = (|Dj c − g|² − |c − g|²)/2 and their Jacobian in (gx, gy, cx, cy), batched.

    x (..., 4) holds g and c; d, alpha (..., m) the displacements of poses 2..m+1 from pose 1.
    Returns F (..., m) and J (..., m, 4).
    """
    g, c = x[..., None, :2], x[..., None, 2:]
    moved = _moved(x, d, alpha)
    e, e1 = moved - g, c - g
    F = 0.5 * (np.sum(e**2, -1) - np.sum(e1**2, -1))
    cs, sn = np.cos(alpha), np.sin(alpha)
    # ∂F/∂g = c − Dj c;  ∂F/∂c = Rjᵀ(Dj c − g) − (c − g).
    rte = np.stack((cs * e[..., 0] + sn * e[..., 1], -sn * e[..., 0] + cs * e[..., 1]), -1)
    return F, np.concatenate((c - moved, rte - e1), -1)


def _turn_equation(x: Array, d: CArray, alpha: Array, beta: Array) -> tuple[Array, Array]:
    """(c − g) turned by β2 is along D2 c − g: e1ᵀ K e2 = 0 with K = cos β2·J − sin β2·I.

    J is the matrix of the planar cross product (e1ᵀ J e2 = e1 × e2). Returns F (...), J (..., 4).
    """
    g, c = x[..., :2], x[..., 2:]
    e1 = c - g
    e2 = _moved(x, d[..., :1], alpha[..., :1])[..., 0, :] - g
    cb, sb = np.cos(beta), np.sin(beta)
    ke2 = np.stack((cb * e2[..., 1] - sb * e2[..., 0], -cb * e2[..., 0] - sb * e2[..., 1]), -1)
    kte1 = np.stack((-cb * e1[..., 1] - sb * e1[..., 0], cb * e1[..., 0] - sb * e1[..., 1]), -1)
    F = np.sum(e1 * ke2, -1)
    ca, sa = np.cos(alpha[..., 0]), np.sin(alpha[..., 0])
    r2t = np.stack(
        (ca * kte1[..., 0] + sa * kte1[..., 1], -sa * kte1[..., 0] + ca * kte1[..., 1]), -1
    )
    return F, np.concatenate((-ke2 - kte1, ke2 + r2t), -1)


def _system(x: Array, d: CArray, alpha: Array, beta: Array | None) -> tuple[Array, Array]:
    F, J = _equations(x, d, alpha)
    if beta is None:
        return F, J
    Fb, Jb = _turn_equation(x, d, alpha, beta)
    return np.concatenate((F, Fb[..., None]), -1), np.concatenate((J, Jb[..., None, :]), -2)


def _polish(
    x: Array, d: CArray, alpha: Array, beta: Array | None = None, steps: int = NEWTON_STEPS
) -> Array:
    """Newton's method on the dyad equations (poses 2..4 and the turn β2, or poses 2..5).

    Each step is kept only where it lowers the largest residual, so a sample that is already
    as good as it gets, or whose Jacobian is singular, stays as it was.
    """
    with np.errstate(all="ignore"):  # samples far out on an asymptote overflow: left as they are
        return _newton(x, d, alpha, beta, steps)


def _newton(x: Array, d: CArray, alpha: Array, beta: Array | None, steps: int) -> Array:
    shape = x.shape[:-1]
    m = np.broadcast_shapes(d.shape, alpha.shape)[-1]
    X = x.reshape(-1, 4).copy()
    D = np.broadcast_to(d, shape + (m,)).reshape(-1, m)
    AL = np.broadcast_to(alpha, shape + (m,)).reshape(-1, m)
    BE = None if beta is None else np.broadcast_to(beta, shape).reshape(-1)

    def system(idx: NDArray[np.intp], xs: Array) -> tuple[Array, Array]:
        return _system(xs, D[idx], AL[idx], None if BE is None else BE[idx])

    everyone = np.arange(len(X))
    F, J = system(everyone, X)
    best = np.where(np.all(np.isfinite(F), -1), np.max(np.abs(F), -1), np.inf)
    # Only samples still improving are iterated; one at rounding level is done.
    active = everyone[np.isfinite(best)]
    for _ in range(steps):
        if active.size == 0:
            break
        Ja, Fa = J[active], F[active]
        det = np.linalg.det(Ja)
        fine = np.isfinite(det) & (np.abs(det) > 1e-300)
        eye = np.broadcast_to(np.eye(4), Ja.shape)
        step = np.linalg.solve(np.where(fine[:, None, None], Ja, eye), -Fa[..., None])[..., 0]
        step = np.where(fine[:, None], step, 0.0)
        # Halve the step until it helps: near a double point the full step overshoots.
        moved = np.zeros(active.size, dtype=bool)
        for t in (1.0, 0.5, 0.25, 0.125):
            rest = np.flatnonzero(~moved)
            if rest.size == 0:
                break
            idx = active[rest]
            trial = X[idx] + t * step[rest]
            F_t, J_t = system(idx, trial)
            r_t = np.max(np.abs(F_t), -1)
            better = r_t < best[idx]
            sel = idx[better]
            X[sel], F[sel], J[sel], best[sel] = trial[better], F_t[better], J_t[better], r_t[better]
            moved[rest[better]] = True
        done = best[active] <= 4 * np.finfo(float).eps * (1 + np.sum(X[active] ** 2, -1))
        active = active[moved & ~done]
    return X.reshape(shape + (4,))


def _radius_error(x: Array, d: CArray, alpha: Array) -> Array:
    """max_j | |Dj c − g| − |c − g| | relative to |c − g| (at least the poses' spread, 1)."""
    g = x[..., None, :2]
    r1 = np.hypot(*np.moveaxis(x[..., 2:] - x[..., :2], -1, 0))
    rj = np.hypot(*np.moveaxis(_moved(x, d, alpha) - g, -1, 0))
    error: Array = np.max(np.abs(rj - r1[..., None]), -1) / np.maximum(r1, 1.0)
    return error


def _turn_error(x: Array, d: CArray, alpha: Array, beta: Array) -> Array:
    """How far the ground link's turn from pose 1 to 2 is from β2 (radians)."""
    e1 = x[..., 2:] - x[..., :2]
    e2 = _moved(x, d[..., :1], alpha[..., :1])[..., 0, :] - x[..., :2]
    turn = np.arctan2(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0], np.sum(e1 * e2, -1))
    off: Array = np.abs(np.angle(np.exp(1j * (turn - beta))))
    return off


@dataclass(frozen=True)
class BurmesterCurves:
    """The centre-point and circle-point curves of four poses, sampled by β2.

    Attributes
    ----------
    beta2 : (samples,) the ground link's rotation from pose 1 to pose 2 (radians, in [−π, π)).
    centres : ``batch + (2, samples, 2)`` points of the centre-point curve (the two closures of
        the compatibility linkage at each β2), NaN where ``valid`` is False.
    circles : the matching circle points (moving pivots in the first pose), likewise.
    valid : ``batch + (2, samples)``.
    """

    beta2: Array
    centres: Array
    circles: Array
    valid: NDArray[np.bool_]


def centre_point_curve(points: ArrayLike, angles: ArrayLike, samples: int = 720) -> BurmesterCurves:
    """The centre-point and circle-point curves of four poses, sampled at ``samples`` β2.

    Every centre point c of the curve guides the body through the four poses with its circle
    point; any two make a four-bar (:func:`four_pose_fourbar`). Each curve is a circular cubic
    through the six poles of the poses (Burmester 1888). Near its real asymptote a curve's
    samples run off to large coordinates: the centre-point curve where the dyad becomes a slider
    (β ≡ 0), the circle-point curve where it becomes a turning slider (β ≡ α).

    Examples
    --------
    >>> pts, ang = [[0, 0], [1, 0.4], [2, 0.3], [2.6, -0.5]], np.radians([0, 20, 35, 70])
    >>> curves = centre_point_curve(pts, ang, samples=8)
    >>> np.degrees(curves.beta2)
    array([-180., -135.,  -90.,  -45.,    0.,   45.,   90.,  135.])
    >>> curves.valid
    array([[False, False, False,  True, False,  True, False, False],
           [False, False, False,  True,  True,  True, False, False]])

    Only β2 in about (−85°, 55°) closes the compatibility linkage for these poses; at β2 = 0 the
    first closure is the slider (the point at infinity of the centre-point curve).
    """
    n = int(samples)
    if n < 2:
        raise PrecisionError(f"centre_point_curve: samples must be at least 2, got {samples!r}")
    beta2 = np.linspace(-np.pi, np.pi, n, endpoint=False)
    centres, circles, valid = four_pose_dyads(points, angles, beta2)
    return BurmesterCurves(beta2=beta2, centres=centres, circles=circles, valid=valid)


def four_pose_fourbar(
    points: ArrayLike, angles: ArrayLike, beta2: ArrayLike, closure: ArrayLike = (0, 0)
) -> MotionDesign:
    """The four-bar of two dyads picked from the four-pose curves by their β2 and closure.

    Parameters
    ----------
    points : (..., 4, 2) the poses' coupler points.
    angles : (..., 4) the poses' coupler angles (radians).
    beta2 : (..., 2) β2 of the crank's dyad and of the rocker's (radians).
    closure : (..., 2) which closure (0 or 1, the first axis of :func:`four_pose_dyads`) each.

    Returns
    -------
    MotionDesign
        The four-bar (``.mechanism``), its residual ``.error`` at the poses and whether the
        poses fall on different branches (``.branch_defect``).

    Raises
    ------
    PrecisionError : a β2 whose compatibility linkage does not close (no real dyad there), or
        whose dyad is at infinity.

    Examples
    --------
    >>> pts, ang = [[0, 0], [1, 0.4], [2, 0.3], [2.6, -0.5]], np.radians([0, 20, 35, 70])
    >>> d = four_pose_fourbar(pts, ang, np.radians([-80, 50]), [1, 1])
    >>> d.mechanism.A0.round(6), d.mechanism.B0.round(6), float(d.error) < 1e-12
    (array([1.767943, 1.694336]), array([0.984834, 3.433125]), True)
    >>> d.branches, bool(d.branch_defect)
    (array([-1., -1., -1.,  1.]), True)

    It passes all four poses exactly, but the last on the other assembly: this pick has a branch
    defect. No dyad turns by 60° between the first two poses:

    >>> four_pose_fourbar(pts, ang, np.radians([60, 50]), [0, 0])
    Traceback (most recent call last):
    ...
    linkwright.synthesis.precision_designs.PrecisionError: four_pose_fourbar: no real dyad at β2 =
    60° (closure 0) for the crank: the compatibility linkage does not close there (or the dyad is a
    slider)
    """
    what = "four_pose_fourbar"
    beta2 = np.asarray(beta2, dtype=float)
    closure = np.asarray(closure)
    if beta2.shape[-1:] != (2,) or closure.shape[-1:] != (2,):
        raise PrecisionError(
            f"{what}: beta2 and closure must give two dyads (..., 2), got {beta2.shape} and "
            f"{closure.shape}"
        )
    if not np.all((closure == 0) | (closure == 1)):
        raise PrecisionError(f"{what}: closure must be 0 or 1, got {closure.tolist()}")
    centres, circles, valid = four_pose_dyads(points, angles, beta2)  # batch + (2, 2[, 2])
    shape = np.broadcast_shapes(valid.shape[:-2], closure.shape[:-1])
    pick = np.broadcast_to(closure, shape + (2,)).astype(int)
    valid = np.broadcast_to(valid, shape + (2, 2))
    ok = np.take_along_axis(valid, pick[..., None, :], -2)[..., 0, :]
    at = first_true(~ok)
    if at is not None:
        k = at[-1]
        b = np.broadcast_to(beta2, shape + (2,))[at]
        raise PrecisionError(
            f"{what}: no real dyad at β2 = {np.degrees(b):.9g}° (closure {int(pick[at])}) for "
            f"the {'crank' if k == 0 else 'rocker'}{batch_place(at[:-1])}: the compatibility "
            "linkage "
            "does not close there (or the dyad is a slider)"
        )

    def take(x: Array) -> Array:
        x = np.broadcast_to(x, shape + (2, 2, 2))
        return np.take_along_axis(x, pick[..., None, :, None], -3)[..., 0, :, :]

    return fourbar_from_dyads(points, angles, take(centres), take(circles))


# --- five poses ----------------------------------------------------------------------------------


def _pmul(a: CArray, b: CArray) -> CArray:
    return np.convolve(a, b)


def _padd(*ps: CArray) -> CArray:
    out = np.zeros(max(len(p) for p in ps), dtype=complex)
    for p in ps:
        out[: len(p)] += p
    return out


def _quadratic_in_v(
    d1: CArray, d2: CArray, d3: CArray, dk: CArray
) -> tuple[CArray, CArray, CArray]:
    """(a2, a1, a0/u) of |Δ1 + Δ2u + Δ3v|² = |Δk|² times uv, as polynomials in u (ascending)."""
    c = np.conj
    a2 = np.array([d3 * c(d2), d3 * c(d1)])
    a1 = _padd(
        _pmul(np.array([d1, d2]), np.array([c(d2), c(d1)])),
        np.array([0, abs(d3) ** 2 - abs(dk) ** 2]),
    )
    a0 = np.array([d1 * c(d3), d2 * c(d3)])
    return a2, a1, a0


def _deflate(p: CArray, roots: Iterable[complex]) -> CArray:
    """p (ascending coefficients) divided by (u − r) for each known root r."""
    for r in roots:
        high = p[::-1]
        out = np.zeros(len(high) - 1, dtype=complex)
        acc = 0j
        for k in range(len(high) - 1):
            acc = high[k] + r * acc
            out[k] = acc
        p = out[::-1]
    return p


def _unit_roots(p: CArray) -> list[float]:
    """The angles β of the roots e^{iβ} of p on the unit circle, found as sign changes.

    p is self-inversive (its coefficients satisfy p_k = c·conj(p_{n−k}), as the resultant of
    two modulus equations must), so p(e^{iβ})·e^{−inβ/2}/√c is real for real β: its roots are
    sign changes, bracketed on a grid (globally, and finely about every root of p near the
    circle, so that two nearly coincident real roots are told from a complex pair) and refined
    by Brent's method.
    """
    n = len(p) - 1
    big = np.max(np.abs(p))
    if n < 1 or big == 0:
        return []
    p = p / big
    k = int(np.argmax(np.abs(p)))
    roots = np.roots(p[::-1])
    if abs(p[n - k]) < 0.5:
        # Not self-inversive to working precision (a degenerate pose set): fall back on the
        # roots that lie on the circle.
        return sorted(float(np.angle(r)) for r in roots if abs(abs(r) - 1) < 1e-7)
    c = p[k] / np.conj(p[n - k])

    def f(beta: ArrayLike) -> Array:
        u = np.exp(1j * np.asarray(beta))
        return np.real(np.polyval(p[::-1], u) * np.exp(-0.5j * n * np.asarray(beta)) / np.sqrt(c))

    grid = [np.linspace(-np.pi, np.pi, 4097)]
    for r in roots:
        if abs(abs(r) - 1) < 0.1:
            grid.append(np.angle(r) + np.linspace(-1e-3, 1e-3, 2001))
            grid.append(np.angle(r) + np.linspace(-1e-6, 1e-6, 201))
    b = np.unique(np.concatenate(grid))
    b = b[(b >= -np.pi) & (b <= np.pi)]
    fb = f(b)
    out = [float(x) for x in b[fb == 0]]
    for i in np.flatnonzero(np.sign(fb[:-1]) * np.sign(fb[1:]) < 0):
        out.append(brentq(f, b[i], b[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))
    # A double root (two Burmester points that coincide) only touches zero: where f comes
    # within rounding of 0 beside a root of p without changing sign, offer angles about that
    # root (the real equations decide whether there is a dyad, and where).
    simple = list(out)
    for r in roots:
        at = np.angle(r)
        if abs(abs(r) - 1) > 1e-4 or any(abs(at - x) < 2e-3 for x in simple):
            continue
        near = np.abs(b - at) <= 1e-3
        if np.min(np.where(near, np.abs(fb), np.inf)) <= 1e-9:
            # The roots of a double root are only good to about the square root of the
            # coefficients' rounding: seed the real equations across that spread.
            spread = max(10 * abs(abs(r) - 1), 1e-6)
            out.extend((at + np.linspace(-spread, spread, 21)).tolist())
    out = sorted(out)
    # −π and π are one angle.
    if len(out) > 1 and out[-1] - out[0] > 2 * np.pi - 1e-12:
        out.pop()
    return out


def _burmester_one(delta: CArray, alpha: Array) -> list[tuple[Array, float, float]] | None:
    """Real Burmester pairs (g, c) of one normalised pose set (complex arrays), residuals."""
    cof4 = _cofactors(delta, alpha, 3)
    cof5 = _cofactors(delta, alpha, 4)
    if max(abs(x) for x in cof4 + cof5) <= VANISHING:
        return None
    a2, a1, a0 = _quadratic_in_v(*cof4)
    b2, b1, b0 = _quadratic_in_v(*cof5)
    # Resultant in v of the two quadratics, over the common factor u: u X² − Y·V.
    X = _padd(_pmul(a2, b0), -_pmul(a0, b2))
    Y = _padd(_pmul(a2, b1), -_pmul(a1, b2))
    V = _padd(_pmul(a1, b0), -_pmul(a0, b1))
    res = _padd(np.concatenate(([0], _pmul(X, X))), -_pmul(Y, V))
    quartic = _deflate(res, (1.0, np.exp(1j * alpha[1])))
    turns2 = _unit_roots(quartic)
    rot = np.exp(1j * alpha[1:])
    d = delta[1:]
    found: list[tuple[Array, float, float]] = []
    for beta2 in turns2:
        u = np.exp(1j * beta2)
        qa = np.polyval(a2[::-1], u), np.polyval(a1[::-1], u), u * np.polyval(a0[::-1], u)
        qb = np.polyval(b2[::-1], u), np.polyval(b1[::-1], u), u * np.polyval(b0[::-1], u)
        vs = np.roots(qa) if abs(qa[0]) > 0 else np.roots(qa[1:])
        if len(vs) == 0:
            continue
        v = vs[int(np.argmin([abs(np.polyval(qb, x)) for x in vs]))]
        if abs(abs(v) - 1) > 1e-4:
            continue
        v = v / abs(v)
        with np.errstate(all="ignore"):  # Δ4 or Δ5 = 0: that pose's turn is not fixed
            w4 = -(cof4[0] + cof4[1] * u + cof4[2] * v) / cof4[3]
            w5 = -(cof5[0] + cof5[1] * u + cof5[2] * v) / cof5[3]
            turns = np.array([u, v, w4 / abs(w4), w5 / abs(w5)])
        if not np.all(np.isfinite(turns)):
            continue
        M = np.stack((turns - 1, rot - 1), axis=-1)
        (W, Z), *_ = np.linalg.lstsq(M, d, rcond=None)
        g, c = -W - Z, -Z
        # Near a double point Newton's method only halves the error each step: allow many.
        x = _polish(np.array([g.real, g.imag, c.real, c.imag]), d, alpha[1:], steps=60)
        resid = float(np.max(np.abs(_equations(x, d, alpha[1:])[0])))
        # Relative to the size of the dyad: far-out pivots carry rounding of |x|²·eps.
        if not resid <= RESIDUAL * (1 + float(np.sum(x**2))):
            continue
        if any(np.max(np.abs(x - y[0])) <= 1e-9 for y in found):
            continue
        found.append((x, resid, beta2))
    found.sort(key=lambda t: t[2])
    return found[:4]


@dataclass(frozen=True)
class BurmesterPoints:
    """The real Burmester points of five poses: the dyads that guide the body through all five.

    Attributes
    ----------
    centres : ``batch + (4, 2)`` the centre points (ground pivots), real ones first (in the
        order of β2), NaN after.
    circles : ``batch + (4, 2)`` the matching circle points (moving pivots in the first pose).
    real : ``batch + (4,)`` which slots hold a real point.
    residual : ``batch + (4,)`` the largest |(|Dj c − g|² − |c − g|²)/2| over the poses, in units
        of the poses' spread squared (NaN after the real points).
    """

    centres: Array
    circles: Array
    real: NDArray[np.bool_]
    residual: Array

    @property
    def count(self) -> NDArray[np.int64]:
        """How many real Burmester points (batch shape): 0, 2 or 4, or 1 or 3 where two of them
        coincide (a double point, counted once)."""
        count: NDArray[np.int64] = np.sum(self.real, axis=-1)
        return count


def burmester_points(points: ArrayLike, angles: ArrayLike) -> BurmesterPoints:
    """The Burmester points of five poses: all real centre/circle point pairs.

    Parameters
    ----------
    points : (..., 5, 2) the poses' coupler points.
    angles : (..., 5) the poses' coupler angles (radians).

    Raises
    ------
    PrecisionError : not five poses, coincident poses, or poses that only translate (or all
        turn about one point), for which the Burmester points are not isolated.

    Examples
    --------
    Five poses of a four-bar's coupler: its own two dyads, (A0, A) and (B0, B) at the first pose,
    are two of the Burmester points; here the other two are real too.

    >>> from linkwright.mechanisms import FourBar, solve
    >>> fb = FourBar(A0=[0, 0], B0=[3, 0.5], crank=1, coupler=3.2, rocker=2.6, u=1, v=1.5)
    >>> m = solve(fb, np.radians([5.7, 45.8, 85.9, 137.5, 200.5]))
    >>> line = m.positions["B"] - m.positions["A"]
    >>> bp = burmester_points(m.positions["P"], np.arctan2(line[:, 1], line[:, 0]))
    >>> int(bp.count), bp.centres.round(6) + 0.0
    (4, array([[ 6.057807,  3.37323 ],
           [ 3.      ,  0.5     ],
           [ 6.388156, -5.631879],
           [ 0.      ,  0.      ]]))
    >>> float(bp.residual.max()) < 1e-12
    True
    """
    p, a, scale = pose_set(points, angles, 5, "burmester_points")
    delta, alpha = _normalised(p, a, scale)
    shape = p.shape[:-2]
    centres = np.full(shape + (4, 2), np.nan)
    circles = np.full(shape + (4, 2), np.nan)
    real = np.zeros(shape + (4,), dtype=bool)
    residual = np.full(shape + (4,), np.nan)
    for idx in np.ndindex(*shape):
        found = _burmester_one(delta[idx], alpha[idx])
        if found is None:
            raise PrecisionError(
                f"burmester_points: the poses{batch_place(idx)} only translate, or all turn about "
                "one "
                "point: every body point has concyclic positions or none does, so the Burmester "
                "points are not isolated"
            )
        for k, (x, r, _) in enumerate(found):
            o, s = p[idx + (0,)], scale[idx]
            centres[idx + (k,)] = o + s * x[:2]
            circles[idx + (k,)] = o + s * x[2:]
            real[idx + (k,)] = True
            residual[idx + (k,)] = r
    return BurmesterPoints(centres=centres, circles=circles, real=real, residual=residual)


def burmester_fourbars(
    points: ArrayLike, angles: ArrayLike
) -> tuple[MotionDesign, NDArray[np.int64]]:
    """Every four-bar made of two real Burmester points of five poses.

    Parameters
    ----------
    points : (5, 2) the poses' coupler points (one pose set).
    angles : (5,) the poses' coupler angles (radians).

    Returns
    -------
    design : a :class:`~linkwright.synthesis.precision.MotionDesign` batched over the ordered
        pairs (crank = the pair's first point): with four real points, twelve four-bars (six
        linkages, each driven from either side; the defects depend on which side drives).
    pairs : (pairs, 2) the indices of the two Burmester points (into :func:`burmester_points`),
        crank first.

    Raises
    ------
    PrecisionError : fewer than two real Burmester points: no four-bar of revolute joints guides
        the body through the five poses.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar, solve
    >>> fb = FourBar(A0=[0, 0], B0=[3, 0.5], crank=1, coupler=3.2, rocker=2.6, u=1, v=1.5)
    >>> m = solve(fb, np.radians([5.7, 45.8, 85.9, 137.5, 200.5]))
    >>> line = m.positions["B"] - m.positions["A"]
    >>> design, pairs = burmester_fourbars(m.positions["P"], np.arctan2(line[:, 1], line[:, 0]))
    >>> ok = ~design.branch_defect & ~design.order_defect
    >>> pairs[ok].tolist()
    [[0, 1], [0, 2], [3, 1], [3, 2]]

    Of the twelve, four meet the poses in order on one assembly: the four-bar itself (3, 1:
    crank A0A, rocker B0B) and three others.
    """
    p, a, _ = pose_set(points, angles, 5, "burmester_fourbars")
    if p.ndim != 2:
        raise PrecisionError(
            f"burmester_fourbars: takes one set of five poses, got a batch of shape {p.shape[:-2]}"
        )
    bp = burmester_points(p, a)
    k = int(bp.count)
    if k < 2:
        raise PrecisionError(
            f"burmester_fourbars: these five poses have {k} real Burmester points: no four-bar of "
            "revolute joints guides the body through them"
        )
    pairs = np.array(list(permutations(range(k), 2)))
    return fourbar_from_dyads(p, a, bp.centres[pairs], bp.circles[pairs]), pairs

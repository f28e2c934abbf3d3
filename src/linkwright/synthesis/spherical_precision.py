"""Precision orientations on the sphere: spherical RR dyads and four-bars guiding a body through
three and four orientations (the spherical Burmester problem).

Formulation (McCarthy and Soh 2011, ch. 7, "Spherical four-bar linkages: design"; Suh and
Radcliffe 1978, ch. 8). A body turns about the centre O of the unit sphere; orientation j is a
rotation matrix Qj (its columns are the body's axes in the fixed frame). Write
Q1j = Qj Q1ᵀ for the rotation from orientation 1 to orientation j. A spherical RR dyad is a fixed
axis G (the *centre axis*) and a moving axis W (the *circle axis*, given by its direction in
orientation 1); it guides the body when W keeps its arc from G in every orientation:

    G · (Q1j − I) W = 0,   j = 2, …, n.

- **Three orientations**: for any W the two equations say G ⟂ (Q12 − I)W and G ⟂ (Q13 − I)W, so
  G = ±unit((Q12 − I)W × (Q13 − I)W): every axis of the body is a circle axis (∞² dyads, ∞⁴
  four-bars), as in the plane (:func:`spherical_three_orientation_fourbar`).
- **Four orientations**: three homogeneous equations in G have a non-zero solution only where
  det[(Q12 − I)W, (Q13 − I)W, (Q14 − I)W] = 0, a cubic cone of circle axes (the *circling-axis
  cone*; its centre axes form the *centre-axis cone*). The rotation axis p of Q12 lies on it
  (there (Q12 − I)p = 0), so each plane through p meets the cone in p and in the two roots of a
  quadratic: sweeping the plane by an angle t in [0, π) traces the cone, two dyads per t
  (:func:`spherical_burmester_cones`, :func:`spherical_four_orientation_fourbar`).

Each dyad's centre axis is the null vector (by SVD) of the matrix of its n − 1 equations, and a
dyad is kept only where every equation holds to ``DYAD_TOL``. The sign of an axis is a choice
(G and −G are one line through O); the centre axis is taken on W's side (G · W ≥ 0), so the
crank's arc is at most 90°.

The four-bar is returned in paper 000's frame (:class:`~linkwright.mechanisms.SphericalFourBar`):
``rotation`` R turns the caller's frame into it (R G1 = +x, R G2 in the xy-plane with y > 0).
Its coupler point P is the body's ``point`` (body coordinates; default its x axis). Each design
reports the input θj at which the linkage reaches orientation j, the assembly sign it needs there
and the errors of the engine's own solution (:func:`linkwright.engine.evaluate`) at θj.

References: J. M. McCarthy and G. S. Soh, *Geometric Design of Linkages*, 2nd ed. (Springer
2011), ch. 7. C. H. Suh and C. W. Radcliffe, *Kinematics and Mechanisms Design* (Wiley 1978),
ch. 8.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import evaluate
from linkwright.geometry import sphere
from linkwright.mechanisms.spherical import SphericalFourBar
from linkwright.synthesis.precision import PrecisionError

__all__ = [
    "SphericalBurmesterCones",
    "SphericalMotionDesign",
    "circle_axis_centre",
    "coupler_frames",
    "spherical_burmester_cones",
    "spherical_four_orientation_fourbar",
    "spherical_fourbar_from_dyads",
    "spherical_three_orientation_fourbar",
]

Array = NDArray[np.float64]
# A rotation matrix whose QᵀQ departs from I by more than this is not a rotation.
ROTATION_TOL = 1e-9
# Two orientations whose relative rotation is smaller than this (radians) are one.
SAME_TOL = 1e-9
# Largest |G · (Q1j − I)W| of an accepted dyad (both unit vectors: radians of arc, roughly).
DYAD_TOL = 1e-10
# Two axes closer than this (radians), or this close to antipodal, coincide as lines.
AXIS_TOL = 1e-9


@dataclass(frozen=True)
class SphericalMotionDesign:
    """A spherical four-bar guiding a body through precision orientations, and how it meets them.

    Attributes
    ----------
    mechanism : the four-bar in paper 000's frame (crank = the first dyad, P = the body's point,
        ``assembly`` the sign it needs at the first orientation).
    rotation : (3, 3) R, the caller's frame → paper 000's frame (x' = R x).
    inputs : (n,) the input θj (radians, in (−π, π]) at which it reaches orientation j.
    branches : (n,) the assembly sign (±1) it needs there.
    branch_defect : the orientations need different assembly signs.
    orientation_error : (n,) the angle (radians) between the coupler's orientation in the
        engine's solution at θj (on each orientation's own sign) and the prescribed one.
    point_error : (n,) the chord between the solved P and the prescribed R Qj point.
    """

    mechanism: SphericalFourBar
    rotation: Array
    inputs: Array
    branches: Array
    branch_defect: bool
    orientation_error: Array
    point_error: Array

    @property
    def error(self) -> float:
        """The larger of the two errors at the worst orientation."""
        return float(max(np.max(self.orientation_error), np.max(self.point_error)))


@dataclass(frozen=True)
class SphericalBurmesterCones:
    """The circling-axis and centre-axis cones of four orientations, sampled by the angle t of
    the plane through the pole axis p of Q12.

    Attributes
    ----------
    t : (samples,) the plane's angle (radians, in [0, π)).
    circles : (2, samples, 3) circle axes (in orientation 1), NaN where ``valid`` is False.
    centres : (2, samples, 3) their centre axes.
    valid : (2, samples) a real dyad that meets every orientation to ``DYAD_TOL``.
    """

    t: Array
    circles: Array
    centres: Array
    valid: NDArray[np.bool_]


def _orientations(orientations: ArrayLike, n: int | None, what: str) -> Array:
    try:
        q = np.asarray(orientations, dtype=float)
    except (TypeError, ValueError):
        raise PrecisionError(f"{what}: orientations must be numbers, shape (n, 3, 3)") from None
    if q.ndim != 3 or q.shape[1:] != (3, 3):
        raise PrecisionError(
            f"{what}: orientations must be rotation matrices, shape (n, 3, 3), got {q.shape}"
        )
    if n is not None and q.shape[0] != n:
        raise PrecisionError(f"{what}: needs exactly {n} orientations, got {q.shape[0]}")
    if q.shape[0] < 2:
        raise PrecisionError(f"{what}: needs at least two orientations, got {q.shape[0]}")
    if not np.all(np.isfinite(q)):
        raise PrecisionError(f"{what}: orientations must be finite")
    off = np.abs(np.einsum("nki,nkj->nij", q, q) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(q)
    bad = np.flatnonzero((off > ROTATION_TOL) | (det <= 0))
    if bad.size:
        j = int(bad[0])
        raise PrecisionError(
            f"{what}: orientation {j + 1} is not a rotation matrix (|QᵀQ − I| = {off[j]:.3g}, "
            f"det = {det[j]:.6g})"
        )
    for j in range(1, q.shape[0]):
        for k in range(j):
            if _angle(q[j] @ q[k].T) <= SAME_TOL:
                raise PrecisionError(
                    f"{what}: orientations {k + 1} and {j + 1} coincide: they prescribe nothing "
                    "apart"
                )
    return q


def _relative(q: Array) -> Array:
    """Q1j = Qj Q1ᵀ minus I, j = 2..n: (n − 1, 3, 3)."""
    out: Array = q[1:] @ q[0].T - np.eye(3)
    return out


def _angle(r: Array) -> float:
    """Rotation angle of r, accurate near 0 (from ‖R − I‖_F = 2√2 sin(θ/2))."""
    s = float(np.linalg.norm(r - np.eye(3))) / (2.0 * np.sqrt(2.0))
    return 2.0 * float(np.arcsin(min(1.0, s)))


def _unit(v: ArrayLike, what: str, label: str) -> Array:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise PrecisionError(f"{what}: {label} must be a finite 3-vector, got shape {a.shape}")
    n = float(np.linalg.norm(a))
    if n == 0.0:
        raise PrecisionError(f"{what}: {label} is the zero vector: no axis")
    out: Array = a / n
    return out


def circle_axis_centre(
    orientations: ArrayLike, circle: ArrayLike, *, tol: float = DYAD_TOL
) -> tuple[Array, float]:
    """The centre axis G of circle axis W (in orientation 1), and the dyad's worst residual.

    G is the unit null vector of the rows (Q1j − I)W (by SVD), on W's side. With three
    orientations it always exists (unless the rows are parallel or vanish); with more it exists
    only on the circling-axis cone, and the residual says how far W is from it.

    Raises
    ------
    PrecisionError : W's positions span no plane to be normal to (W on the rotation axis of
        every relative rotation), or the residual is above ``tol``.
    """
    what = "circle_axis_centre"
    q = _orientations(orientations, None, what)
    w = _unit(circle, what, "circle")
    return _centre(_relative(q), w, what, "circle axis", tol)


def _centre(m: Array, w: Array, what: str, label: str, tol: float) -> tuple[Array, float]:
    rows = m @ w  # (n − 1, 3)
    if rows.shape[0] == 1:
        # Two orientations leave a pencil of centres; the bisecting one is singled out.
        raise PrecisionError(f"{what}: two orientations do not fix the {label}'s centre")
    _, s, vt = np.linalg.svd(rows)
    if s[1] <= AXIS_TOL:
        raise PrecisionError(
            f"{what}: the {label} {w.round(9).tolist()} barely moves between the orientations "
            "(it lies on their common rotation axis): its centre is not fixed"
        )
    g = vt[-1]
    if float(g @ w) < 0:
        g = -g
    residual = float(np.max(np.abs(rows @ g)))
    if not residual <= tol:
        raise PrecisionError(
            f"{what}: the {label} {w.round(9).tolist()} keeps no fixed arc from any axis (off by "
            f"{residual:.3g} rad): it is not on the circling-axis cone of these orientations"
        )
    return g, residual


def coupler_frames(a: Array, b: Array) -> Array:
    """The coupler's frame from its joint axes: columns A, t(A→B), A × t (..., 3, 3)."""
    t = sphere.tangent(a, b)
    frames: Array = np.stack([a, t, sphere.cross(a, t)], axis=-1)
    return frames


def spherical_fourbar_from_dyads(
    orientations: ArrayLike,
    centres: ArrayLike,
    circles: ArrayLike,
    *,
    point: ArrayLike = (1.0, 0.0, 0.0),
    tol: float = DYAD_TOL,
) -> SphericalMotionDesign:
    """The spherical four-bar of two dyads that each guide the body through the orientations.

    Parameters
    ----------
    orientations : (n, 3, 3) rotation matrices Qj (n ≥ 2).
    centres : (2, 3) the two fixed axes (crank's first).
    circles : (2, 3) the two moving axes in orientation 1.
    point : the coupler point in body coordinates (P in orientation j is Qj·point).
    tol : largest accepted |G · (Q1j − I)W|.

    Raises
    ------
    PrecisionError : a dyad that misses an orientation by more than ``tol``, coincident (or
        antipodal) axes where a link needs two (frame, crank, coupler, rocker), or a coupler point
        antipodal to the crank pin.
    """
    what = "spherical_fourbar_from_dyads"
    q = _orientations(orientations, None, what)
    g = np.asarray(centres, dtype=float)
    c = np.asarray(circles, dtype=float)
    if g.shape != (2, 3) or c.shape != (2, 3):
        raise PrecisionError(
            f"{what}: centres and circles must have shape (2, 3), got {g.shape} and {c.shape}"
        )
    g = np.stack([_unit(g[k], what, f"centre {k + 1}") for k in range(2)])
    c = np.stack([_unit(c[k], what, f"circle {k + 1}") for k in range(2)])
    p_body = _unit(point, what, "point")
    m = _relative(q)
    for k, label in ((0, "crank"), (1, "rocker")):
        residual = float(np.max(np.abs((m @ c[k]) @ g[k])))
        if not residual <= tol:
            raise PrecisionError(
                f"{what}: the {label}'s moving axis leaves its arc from its centre by "
                f"{residual:.3g} rad: that dyad does not guide the body through the orientations"
            )
    for x, y, label in (
        (g[0], g[1], "the two fixed axes"),
        (g[0], c[0], "the crank's axes"),
        (c[0], c[1], "the two moving axes"),
        (g[1], c[1], "the rocker's axes"),
    ):
        if min(float(np.linalg.norm(x - y)), float(np.linalg.norm(x + y))) <= AXIS_TOL:
            raise PrecisionError(
                f"{what}: {label} coincide (or are antipodal): a link of arc 0 or 180°"
            )
    e1 = g[0]
    e2 = sphere.unit(g[1] - (g[1] @ e1) * e1)
    rot = np.stack([e1, e2, np.cross(e1, e2)])
    turns = q @ q[0].T  # Q1j, (n, 3, 3)
    moved = rot @ turns  # R Q1j, (n, 3, 3)
    A = moved @ c[0]
    B = moved @ c[1]
    P = rot @ (q @ p_body).T  # (3, n)
    P = P.T
    b0 = rot @ g[1]
    branches = np.sign(sphere.dot(sphere.cross(A, np.broadcast_to(b0, A.shape)), B))
    if np.any(branches == 0):
        raise PrecisionError(
            f"{what}: at orientation {int(np.flatnonzero(branches == 0)[0]) + 1} the coupler "
            "lies on the great circle through the crank pin and the rocker's fixed axis (a dead "
            "centre): the input does not fix the orientation there"
        )
    if float(np.linalg.norm(P[0] + A[0])) <= AXIS_TOL:
        raise PrecisionError(f"{what}: the coupler point is antipodal to the crank pin")
    t = sphere.tangent(A[0], B[0])
    point_angle = float(np.arctan2(sphere.cross(A[0], t) @ P[0], t @ P[0]))
    mech = SphericalFourBar(
        frame=float(sphere.arc(g[0], g[1])),
        crank=float(sphere.arc(g[0], c[0])),
        coupler=float(sphere.arc(c[0], c[1])),
        rocker=float(sphere.arc(g[1], c[1])),
        point_arc=float(sphere.arc(A[0], P[0])),
        point_angle=point_angle if np.isfinite(point_angle) else 0.0,
        assembly=float(branches[0]),
    )
    inputs = np.arctan2(A[:, 2], A[:, 1])
    motion = evaluate(
        mech.plan, mech.params(), inputs, points=mech.points, branches={"B": branches}, order=0
    )
    solved = coupler_frames(motion.positions["A"], motion.positions["B"])
    target = moved @ coupler_frames(c[0], c[1])
    orientation_error = np.array(
        [
            _angle(solved[j] @ target[j].T) if np.all(np.isfinite(solved[j])) else np.inf
            for j in range(q.shape[0])
        ]
    )
    point_error = sphere.norm(motion.positions["P"] - P)
    point_error = np.where(np.isfinite(point_error), point_error, np.inf)
    return SphericalMotionDesign(
        mechanism=mech,
        rotation=rot,
        inputs=inputs,
        branches=branches,
        branch_defect=bool(np.any(branches != branches[0])),
        orientation_error=orientation_error,
        point_error=point_error,
    )


def spherical_three_orientation_fourbar(
    orientations: ArrayLike,
    circles: ArrayLike,
    *,
    point: ArrayLike = (1.0, 0.0, 0.0),
    frame: str = "first",
) -> SphericalMotionDesign:
    """The spherical four-bar guiding a body through three orientations from two chosen moving
    axes (each one's centre axis is the normal of the plane of its three positions).

    Parameters
    ----------
    orientations : (3, 3, 3) rotation matrices Qj.
    circles : (2, 3) the two moving axes (crank's first).
    point : the coupler point, body coordinates.
    frame : ``"first"``: the moving axes as they stand in orientation 1; ``"body"``: in body
        coordinates (turned by Q1).

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> q = Rotation.from_euler("zyx", [[0, 0, 0], [30, 10, 5], [55, 25, 0]], degrees=True)
    >>> d = spherical_three_orientation_fourbar(q.as_matrix(), [[0.2, 0.3, 0.9], [0.6, -0.2, 0.8]])
    >>> bool(d.error < 1e-12), d.branches
    (True, array([ 1., -1., -1.]))

    It reaches all three orientations, but the last two on the other assembly: a branch defect.
    """
    what = "spherical_three_orientation_fourbar"
    q = _orientations(orientations, 3, what)
    c = np.asarray(circles, dtype=float)
    if c.shape != (2, 3) or not np.all(np.isfinite(c)):
        raise PrecisionError(
            f"{what}: circles must be two finite axes, shape (2, 3), got {c.shape}"
        )
    if frame == "body":
        c = c @ q[0].T
    elif frame != "first":
        raise PrecisionError(f"{what}: frame must be 'first' or 'body', got {frame!r}")
    c = np.stack([_unit(c[k], what, f"circle {k + 1}") for k in range(2)])
    m = _relative(q)
    g = np.stack(
        [_centre(m, c[k], what, label, DYAD_TOL)[0] for k, label in enumerate(("crank", "rocker"))]
    )
    return spherical_fourbar_from_dyads(q, g, c, point=point)


def _pole(r: Array) -> Array:
    """The rotation axis of r (r − I given): its null vector."""
    return np.linalg.svd(r)[2][-1, :]


def spherical_burmester_cones(
    orientations: ArrayLike, samples: int = 360
) -> SphericalBurmesterCones:
    """The circling-axis and centre-axis cones of four orientations, sampled at ``samples``
    planes through the pole axis of Q12 (module docstring).

    Every dyad on them guides the body through all four orientations; any two make a four-bar
    (:func:`spherical_four_orientation_fourbar`).
    """
    what = "spherical_burmester_cones"
    n = int(samples)
    if not 2 <= n <= 100_000:
        raise PrecisionError(f"{what}: samples must be 2 to 100000, got {samples!r}")
    q = _orientations(orientations, 4, what)
    m = _relative(q)
    t = np.linspace(0.0, np.pi, n, endpoint=False)
    circles = np.full((2, n, 3), np.nan)
    centres = np.full((2, n, 3), np.nan)
    valid = np.zeros((2, n), dtype=bool)
    for i, ti in enumerate(t):
        for k, w in enumerate(_cone_axes(m, float(ti))):
            try:
                g, _ = _centre(m, w, what, "circle axis", DYAD_TOL)
            except PrecisionError:
                continue
            circles[k, i], centres[k, i], valid[k, i] = w, g, True
    return SphericalBurmesterCones(t=t, circles=circles, centres=centres, valid=valid)


def _cone_axes(m: Array, t: float) -> list[Array]:
    """The (up to two) circle axes in the plane through Q12's pole at angle t (ordered by the
    root λ/μ of the quadratic: the smaller first)."""
    p = _pole(m[0])
    ea = sphere.unit(np.cross(p, np.eye(3)[int(np.argmin(np.abs(p)))]))
    eb = np.cross(p, ea)
    v = np.cos(t) * ea + np.sin(t) * eb

    def form(x: Array, y: Array, z: Array) -> float:
        return float(np.linalg.det(np.stack([m[0] @ x, m[1] @ y, m[2] @ z])))

    # f(λp + μv) = μ(c2 λ² + c1 λμ + c0 μ²): f(p) = 0 since (Q12 − I)p = 0.
    c2 = form(p, p, v) + form(p, v, p) + form(v, p, p)
    c1 = form(p, v, v) + form(v, p, v) + form(v, v, p)
    c0 = form(v, v, v)
    roots: NDArray[np.generic] | list[complex]
    roots = np.roots([c2, c1, c0]) if abs(c2) > 0 else np.array([-c0 / c1]) if c1 else []
    out = []
    for r in sorted(np.real(x) for x in roots if abs(np.imag(x)) <= 1e-12 * (1 + abs(x))):
        out.append(sphere.unit(r * p + v))
    return out[:2]


def spherical_four_orientation_fourbar(
    orientations: ArrayLike,
    t: ArrayLike,
    root: ArrayLike = (0, 0),
    *,
    point: ArrayLike = (1.0, 0.0, 0.0),
) -> SphericalMotionDesign:
    """The spherical four-bar of two dyads picked from the four-orientation cones by their plane
    angle t (radians) and root (0 or 1, the first axis of :class:`SphericalBurmesterCones`).

    Examples
    --------
    Four orientations of a known spherical four-bar's coupler:

    >>> from linkwright.mechanisms import solve
    >>> fb = SphericalFourBar(*np.radians([60, 25, 50, 45, 30, 40]))
    >>> m = solve(fb, np.radians([0, 25, 50, 80]))
    >>> q = coupler_frames(m.positions["A"], m.positions["B"])
    >>> d = spherical_four_orientation_fourbar(q, np.radians([20, 100]))
    >>> bool(d.error < 1e-9)
    True
    """
    what = "spherical_four_orientation_fourbar"
    q = _orientations(orientations, 4, what)
    tt = np.asarray(t, dtype=float)
    rr = np.asarray(root)
    if tt.shape != (2,) or rr.shape != (2,) or not np.all(np.isfinite(tt)):
        raise PrecisionError(f"{what}: t and root must each give two dyads, shape (2,)")
    if not np.all((rr == 0) | (rr == 1)):
        raise PrecisionError(f"{what}: root must be 0 or 1, got {rr.tolist()}")
    m = _relative(q)
    circles, centres = [], []
    for k, label in ((0, "crank"), (1, "rocker")):
        axes = _cone_axes(m, float(tt[k]))
        if len(axes) <= int(rr[k]):
            raise PrecisionError(
                f"{what}: no real circle axis at t = {np.degrees(tt[k]):.9g}° (root {int(rr[k])}) "
                f"for the {label}: the plane meets the cone in fewer real axes"
            )
        w = axes[int(rr[k])]
        circles.append(w)
        centres.append(_centre(m, w, what, f"{label}'s circle axis", DYAD_TOL)[0])
    return spherical_fourbar_from_dyads(q, np.stack(centres), np.stack(circles), point=point)

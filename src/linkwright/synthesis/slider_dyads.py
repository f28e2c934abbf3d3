"""Slider dyads in Burmester synthesis: the points at infinity of the centre-point curves.

A dyad whose centre point goes to infinity becomes a slider (an RP dyad): its circle point C
moves on a straight line, the circle of infinite radius. So the slider points of a set of poses
are the body points whose positions are collinear (Sandor and Erdman 1984, §2.14, "the circle
point at infinity"; McCarthy and Soh 2011, §4.6 and §5.4, the RP dyad).

Write u = X − P1 for a body point in the first pose, Dj = Pj − P1 and Mj = R(αj − α1) − I, so
that Xj − X1 = Dj + Mj u.

- **Three poses**: X1, X2, X3 are collinear where f(u) = (D2 + M2 u) × (D3 + M3 u) = 0. Each Mj
  is a rotation-and-scaling, so the quadratic part u·(M2ᵀ J M3)u is c|u|² with
  c = 4 sin(φ2/2) sin(φ3/2) sin((φ3 − φ2)/2), φj = αj − α1 (J the 90° turn): f = 0 is a circle,
  the *slider-point circle* (Sandor and Erdman's circle through the poles P12, P13 and the image
  pole P23'). Every point on it is a slider point: ∞¹ slider dyads
  (:func:`slider_point_circle`, :func:`slider_line`).
- **Four poses**: the point must lie on the circles of poses 123 and 124. Both pass through the
  pole P12 (whose positions 1 and 2 coincide), so they meet in one more point, always real: the
  *Ball point* (the circle-point curve's point at infinity), the one slider dyad of four poses
  (:func:`four_pose_slider_point`).

A slider dyad and an RR dyad make a slider-crank (:class:`~linkwright.mechanisms.SliderCrank`:
the RR dyad's link the crank, the slider point its pin B, the body the rod carrying P), built and
checked by the engine at every pose by :func:`slider_crank_from_dyads`; the helpers
:func:`three_pose_slider_crank` and :func:`four_pose_slider_crank` choose the dyads as three- and
four-pose synthesis do.

References: G. N. Sandor and A. G. Erdman, *Advanced Mechanism Design* vol. 2 (Prentice-Hall
1984), §2.14–2.20. J. M. McCarthy and G. S. Soh, *Geometric Design of Linkages*, 2nd ed.
(Springer 2011), ch. 4–5.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.mechanisms import SliderCrank, solve
from linkwright.synthesis.burmester import four_pose_dyads
from linkwright.synthesis.precision import PrecisionError, pose_set

__all__ = [
    "SliderCircle",
    "SliderMotionDesign",
    "four_pose_slider_crank",
    "four_pose_slider_point",
    "slider_crank_from_dyads",
    "slider_line",
    "slider_point_circle",
    "three_pose_slider_crank",
]

Array = NDArray[np.float64]
# |c| (the circle's quadratic coefficient, in units of the poses' spread) below which the
# slider points do not form a circle: two poses turned alike (or not at all) relative to pose 1.
DEGENERATE = 1e-9
# Largest distance (relative to the poses' spread) of a slider point's position from its line.
LINE_TOL = 1e-9
_J = np.array([[0.0, 1.0], [-1.0, 0.0]])  # a × b = aᵀ J b


@dataclass(frozen=True)
class SliderCircle:
    """The slider-point circle of three poses, in the first pose: every point on it moves on a
    straight line through the three poses."""

    centre: Array
    radius: float


@dataclass(frozen=True)
class SliderMotionDesign:
    """A slider-crank guiding a body through precision poses, and how it meets them.

    Attributes
    ----------
    mechanism : the slider-crank (crank = the RR dyad, B = the slider point, P = the pose point,
        ``assembly`` the sign it needs at the first pose).
    inputs : (n,) the crank angle θj (radians) at which it reaches pose j.
    branches : (n,) the assembly sign it needs there.
    branch_defect : the poses need different assembly signs.
    position_error : (n,) |P(θj) − Pj| from the engine's solution, relative to the poses' spread.
    angle_error : (n,) |rod angle change − (αj − α1)| (radians) from the engine's solution.
    """

    mechanism: SliderCrank
    inputs: Array
    branches: Array
    branch_defect: bool
    position_error: Array
    angle_error: Array

    @property
    def error(self) -> float:
        return float(max(np.max(self.position_error), np.max(self.angle_error)))


def _poses(
    points: ArrayLike, angles: ArrayLike, n: int | None, what: str
) -> tuple[Array, Array, float]:
    p, a, scale = pose_set(points, angles, n, what)
    if p.ndim != 2:
        raise PrecisionError(f"{what}: one pose set at a time, got points of shape {p.shape}")
    return p, a, float(scale)


def _rot(t: ArrayLike) -> Array:
    c, s = np.cos(t), np.sin(t)
    out: Array = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
    return out


def _positions(p: Array, a: Array, x1: Array) -> Array:
    """Positions (n, 2) of the body point that is at x1 in the first pose."""
    out: Array = p + (_rot(a - a[0]) @ (x1 - p[0]))
    return out


def _circle(p: Array, a: Array, scale: float, what: str) -> tuple[float, Array, float]:
    """(c, b, d) of f(u) = c|u|² + b·u + d for poses 1, 2, 3 of p, a (u in units of scale)."""
    d2, d3 = (p[1] - p[0]) / scale, (p[2] - p[0]) / scale
    m2, m3 = _rot(a[1] - a[0]) - np.eye(2), _rot(a[2] - a[0]) - np.eye(2)
    q = m2.T @ _J @ m3
    c = 0.5 * float(np.trace(q))  # its symmetric part is c·I (module docstring)
    b = m3.T @ _J.T @ d2 + m2.T @ _J @ d3
    d = float(d2 @ _J @ d3)
    if abs(c) <= DEGENERATE:
        raise PrecisionError(
            f"{what}: two of the poses are turned alike (or not at all) from the first: the "
            "slider points form no circle"
        )
    return c, b, d


def slider_point_circle(points: ArrayLike, angles: ArrayLike) -> SliderCircle:
    """The slider-point circle of three poses (module docstring).

    Examples
    --------
    >>> k = slider_point_circle([[0, 0], [1, 0.2], [1.8, 0.9]], np.radians([0, 25, 60]))
    >>> x = k.centre + k.radius * np.array([np.cos(1.0), np.sin(1.0)])
    >>> xs = _positions(np.array([[0, 0], [1, 0.2], [1.8, 0.9]]), np.radians([0, 25, 60]), x)
    >>> bool(abs(float((xs[1] - xs[0]) @ _J @ (xs[2] - xs[0]))) < 1e-12)
    True
    """
    what = "slider_point_circle"
    p, a, scale = _poses(points, angles, 3, what)
    c, b, d = _circle(p, a, scale, what)
    u0 = -b / (2.0 * c)
    r2 = float(u0 @ u0) - d / c
    # The poles lie on it, so it is always real; r2 < 0 is rounding of a point circle.
    return SliderCircle(centre=p[0] + scale * u0, radius=scale * float(np.sqrt(max(r2, 0.0))))


def slider_line(
    points: ArrayLike, angles: ArrayLike, slider: ArrayLike, *, tol: float = LINE_TOL
) -> tuple[Array, float]:
    """The line (a point on it, its angle in radians) on which the body point at ``slider`` (in
    the first pose) moves through the poses.

    Raises
    ------
    PrecisionError : the point's positions are not collinear to ``tol`` (of the poses' spread),
        or they coincide (the point is a pole of every pose: no line).
    """
    what = "slider_line"
    p, a, scale = _poses(points, angles, None, what)
    x1 = np.asarray(slider, dtype=float)
    if x1.shape != (2,) or not np.all(np.isfinite(x1)):
        raise PrecisionError(f"{what}: the slider point must be a finite (x, y)")
    xs = _positions(p, a, x1)
    far = int(np.argmax(np.linalg.norm(xs - xs[0], axis=1)))
    span = float(np.linalg.norm(xs[far] - xs[0]))
    if span <= tol * scale:
        raise PrecisionError(f"{what}: the point {x1.tolist()} does not move between the poses")
    e = (xs[far] - xs[0]) / span
    off = float(np.max(np.abs((xs - xs[0]) @ _J @ e)))
    if not off <= tol * scale:
        raise PrecisionError(
            f"{what}: the point {x1.tolist()} leaves a straight line by {off / scale:.3g} (of the "
            "poses' spread): it is not a slider point of these poses"
        )
    return xs[0], float(np.arctan2(e[1], e[0]))


def four_pose_slider_point(points: ArrayLike, angles: ArrayLike) -> Array:
    """The Ball point of four poses (in the first pose): the one body point whose four positions
    are collinear, the second meeting of the slider-point circles of poses 123 and 124.

    Raises
    ------
    PrecisionError : degenerate poses (the two circles coincide or do not exist).
    """
    what = "four_pose_slider_point"
    p, a, scale = _poses(points, angles, 4, what)
    c3, b3, _ = _circle(p[:3], a[:3], scale, what)
    c4, b4, _ = _circle(p[[0, 1, 3]], a[[0, 1, 3]], scale, what)
    # The radical line of the two circles passes through the pole P12 (on both): walk along it
    # from P12 to the circle's other point.
    n = b3 / c3 - b4 / c4
    if float(np.linalg.norm(n)) <= DEGENERATE:
        raise PrecisionError(f"{what}: the slider-point circles of poses 123 and 124 coincide")
    m2 = _rot(a[1] - a[0]) - np.eye(2)
    pole = np.linalg.solve(m2, -(p[1] - p[0]) / scale)  # D2 + M2 u = 0
    e = np.array([-n[1], n[0]]) / float(np.linalg.norm(n))
    s = -(2.0 * c3 * float(pole @ e) + float(b3 @ e)) / c3
    x1 = p[0] + scale * (pole + s * e)
    slider_line(p, a, x1)  # raises where rounding left it off the line
    out: Array = x1
    return out


def _centre_of(xs: Array, scale: float, what: str) -> Array:
    """The centre of the circle through three points (the RR dyad's ground pivot)."""
    a, b, c = xs
    m = 2.0 * np.stack([b - a, c - a])
    if abs(np.linalg.det(m)) <= DEGENERATE * scale**2:
        raise PrecisionError(
            f"{what}: the crank's moving pivot moves on a line (it is a slider point): no centre"
        )
    out: Array = np.linalg.solve(m, np.array([b @ b - a @ a, c @ c - a @ a]))
    return out


def slider_crank_from_dyads(
    points: ArrayLike, angles: ArrayLike, centre: ArrayLike, circle: ArrayLike, slider: ArrayLike
) -> SliderMotionDesign:
    """The slider-crank of an RR dyad (ground pivot ``centre``, moving pivot ``circle`` in the
    first pose) and a slider dyad (the body point ``slider`` in the first pose), solved by the
    engine at every pose.

    Raises
    ------
    PrecisionError : a dyad that does not guide the body (the RR pivot off its circle, the slider
        point off its line, by more than 1e-9 of the poses' spread), or coincident pivots.
    """
    what = "slider_crank_from_dyads"
    p, a, scale = _poses(points, angles, None, what)
    g = np.asarray(centre, dtype=float)
    c1 = np.asarray(circle, dtype=float)
    b1 = np.asarray(slider, dtype=float)
    for v, label in ((g, "centre"), (c1, "circle"), (b1, "slider")):
        if v.shape != (2,) or not np.all(np.isfinite(v)):
            raise PrecisionError(f"{what}: the {label} point must be a finite (x, y)")
    line_point, line_angle = slider_line(p, a, b1)
    cs = _positions(p, a, c1)
    radius = np.linalg.norm(cs - g, axis=1)
    if radius[0] <= LINE_TOL * scale:
        raise PrecisionError(f"{what}: the crank's pivots coincide (a crank of length 0)")
    if float(np.max(np.abs(radius - radius[0]))) > LINE_TOL * scale:
        raise PrecisionError(
            f"{what}: the crank's moving pivot leaves its circle about the centre: that dyad "
            "does not guide the body through the poses"
        )
    rod = float(np.linalg.norm(b1 - c1))
    if rod <= LINE_TOL * scale:
        raise PrecisionError(f"{what}: the crank pin and the slider point coincide")
    bs = _positions(p, a, b1)
    d = np.array([np.cos(line_angle), np.sin(line_angle)])
    # SliderCrank's assembly: the sign of (B − H)·d, H the foot of the crank pin on the line.
    branches = np.sign((bs - cs) @ d)
    if np.any(branches == 0):
        j = int(np.flatnonzero(branches == 0)[0])
        raise PrecisionError(
            f"{what}: at pose {j + 1} the rod stands square to the slider's line (a dead "
            "centre): the crank does not fix the pose there"
        )
    # P in the rod's frame: origin the crank pin, x along pin → slider, in the first pose.
    ex = (b1 - c1) / rod
    ey = np.array([-ex[1], ex[0]])
    rel = p[0] - c1
    mech = SliderCrank(
        A0=g, crank=float(radius[0]), rod=rod, line_point=line_point, line_angle=line_angle,
        u=float(rel @ ex), v=float(rel @ ey), assembly=float(branches[0]),
    )  # fmt: skip
    inputs = np.arctan2(cs[:, 1] - g[1], cs[:, 0] - g[0])
    position_error = np.empty(len(p))
    angle_error = np.empty(len(p))
    rod0 = float(np.arctan2(ex[1], ex[0]))
    for j in range(len(p)):
        # Each pose on its own assembly sign: a branch defect is reported, not hidden.
        mine = dataclasses.replace(mech, assembly=float(branches[j]))
        m = solve(mine, [inputs[j]], order=0)
        pp, aa, bb = m.positions["P"][0], m.positions["A"][0], m.positions["B"][0]
        position_error[j] = float(np.linalg.norm(pp - p[j])) / scale
        turned = float(np.arctan2(bb[1] - aa[1], bb[0] - aa[0])) - rod0
        angle_error[j] = abs(float(np.angle(np.exp(1j * (turned - (a[j] - a[0]))))))
    bad = ~np.isfinite(position_error) | ~np.isfinite(angle_error)
    position_error[bad] = np.inf
    angle_error[bad] = np.inf
    return SliderMotionDesign(
        mechanism=mech,
        inputs=inputs,
        branches=branches,
        branch_defect=bool(np.any(branches != branches[0])),
        position_error=position_error,
        angle_error=angle_error,
    )


def three_pose_slider_crank(
    points: ArrayLike, angles: ArrayLike, circle: ArrayLike, slider_angle: float
) -> SliderMotionDesign:
    """A slider-crank through three poses: the crank's moving pivot ``circle`` (first pose; its
    centre is the centre of its three positions) and the slider point at ``slider_angle``
    (radians) round the slider-point circle."""
    what = "three_pose_slider_crank"
    p, a, scale = _poses(points, angles, 3, what)
    c1 = np.asarray(circle, dtype=float)
    if c1.shape != (2,) or not np.all(np.isfinite(c1)) or not np.isfinite(slider_angle):
        raise PrecisionError(f"{what}: circle must be a finite (x, y), slider_angle finite")
    k = slider_point_circle(p, a)
    b1 = k.centre + k.radius * np.array([np.cos(slider_angle), np.sin(slider_angle)])
    g = _centre_of(_positions(p, a, c1), scale, what)
    return slider_crank_from_dyads(p, a, g, c1, b1)


def four_pose_slider_crank(
    points: ArrayLike, angles: ArrayLike, beta2: float, closure: int = 0
) -> SliderMotionDesign:
    """A slider-crank through four poses: the crank is the RR dyad at ``beta2`` (radians) and
    ``closure`` (0 or 1) on the Burmester curves (:func:`four_pose_dyads`), the slider the Ball
    point (:func:`four_pose_slider_point`)."""
    what = "four_pose_slider_crank"
    p, a, _ = _poses(points, angles, 4, what)
    if closure not in (0, 1):
        raise PrecisionError(f"{what}: closure must be 0 or 1, got {closure!r}")
    g, c, ok = four_pose_dyads(p, a, [float(beta2)])
    if not ok[closure, 0]:
        raise PrecisionError(
            f"{what}: no real dyad at beta2 = {np.degrees(beta2):.9g}° (closure {closure})"
        )
    return slider_crank_from_dyads(p, a, g[closure, 0], c[closure, 0],
                                   four_pose_slider_point(p, a))  # fmt: skip

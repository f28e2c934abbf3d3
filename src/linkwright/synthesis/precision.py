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

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.geometry import plane
from linkwright.mechanisms import FourBar
from linkwright.synthesis.function_generation import (
    chebyshev_spacing,
    freudenstein,
    freudenstein_fit,
    function_error,
    function_pairs,
)
from linkwright.synthesis.precision_designs import (
    DYAD_TOL,
    SAME_TOL,
    SINGULAR_TOL,
    Array,
    FunctionDesign,
    MotionDesign,
    PrecisionError,
    assembly_branches,
    batch_place,
    find_order_defect,
    first_true,
    pose_positions,
    pose_set,
    rotation_matrix,
    simulate_design,
    wrap_angle,
)
from linkwright.synthesis.precision_designs import TWO_PI as TWO_PI

# A name imported `as` itself moved to a sibling module and is re-exported for older imports;
# a constant among them is read where it lives (set it there, not here).
__all__ = [
    "FunctionDesign",
    "MotionDesign",
    "PrecisionError",
    "batch_place",
    "chebyshev_spacing",
    "first_true",
    "fourbar_from_dyads",
    "freudenstein",
    "freudenstein_fit",
    "function_error",
    "function_pairs",
    "path_with_timing",
    "pose_positions",
    "pose_set",
    "three_pose_fourbar",
]


# --- motion generation ---------------------------------------------------------------------------


def _circle_centres(positions: Array, scale: Array, what: str, label: str) -> Array:
    """Centres (..., 2) of the circles through three positions (..., 3, 2) each."""
    p1, p2, p3 = positions[..., 0, :], positions[..., 1, :], positions[..., 2, :]
    r2, r3 = p2 - p1, p3 - p1
    # g − p1 solves r2·x = |r2|²/2, r3·x = |r3|²/2 (the perpendicular bisectors).
    x, det = plane.solve_2x2_rows(r2, r3, plane.dot(r2, r2) / 2, plane.dot(r3, r3) / 2)
    at = first_true(np.abs(det) <= SINGULAR_TOL * scale**2)
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label}'s three positions {positions[at].round(9).tolist()} are "
            f"collinear or coincide{batch_place(at)}: no circle (or a circle of infinite radius, a "
            "slider) passes through them"
        )
    return p1 + x


def _dyad_check(
    positions: Array, centres: Array, scale: Array, what: str, label: str, tol: float
) -> None:
    radius = plane.norm(positions - centres[..., None, :])
    off = np.max(np.abs(radius - radius[..., :1]), axis=-1) / scale
    at = first_true(~(off <= tol))
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label}'s positions in the poses lie off a circle about its centre "
            f"{centres[at].round(9).tolist()} by {float(off[at]):.3g} of the poses' spread"
            f"{batch_place(at)}: that dyad does not guide the body through the poses"
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
    linkwright.synthesis.precision_designs.PrecisionError: fourbar_from_dyads: the rocker pivot's
    positions in the poses lie off a circle about its centre [2.1, 0.0] by 0.0655 of the poses'
    spread: that dyad does not guide the body through the poses
    """
    what = "fourbar_from_dyads"
    p, a, scale = pose_set(points, angles, None, what)
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
        at = first_true(arm <= SAME_TOL)
        if at is not None:
            raise PrecisionError(
                f"{what}: the {label}'s moving pivot {c[at + (k,)].tolist()} lies on its centre"
                f"{batch_place(at)}: a link of length 0"
            )
        _dyad_check(moved[..., k, :], g[..., k, :], scale, what, f"{label} pivot", tol)
    link = c[..., 1, :] - c[..., 0, :]
    coupler = plane.norm(link)
    at = first_true(coupler <= SAME_TOL * scale)
    if at is not None:
        raise PrecisionError(
            f"{what}: the two moving pivots coincide at {c[at + (0,)].tolist()}{batch_place(at)}: "
            "a coupler of length 0"
        )
    e = link / coupler[..., None]
    rel = p[..., 0, :] - c[..., 0, :]
    A, B = moved[..., 0, :], moved[..., 1, :]
    branches = assembly_branches(g[..., 0, :], g[..., 1, :], A, B, scale, what)
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
    motion = simulate_design(mech, inputs, branches)
    line = motion.positions["B"] - motion.positions["A"]
    turned = np.arctan2(line[..., 1], line[..., 0]) - offset[..., None]
    return MotionDesign(
        mechanism=mech,
        inputs=inputs,
        branches=branches,
        branch_defect=np.any(branches != branches[..., :1], axis=-1),
        order_defect=find_order_defect(mech, inputs),
        position_error=plane.norm(motion.positions["P"] - p) / scale[..., None],
        angle_error=np.abs(wrap_angle(turned - a)),
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

    Returns
    -------
    MotionDesign
        The four-bar (``.mechanism``), its residual ``.error`` at the poses and whether the
        poses fall on different branches (``.branch_defect``).

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
    linkwright.synthesis.precision_designs.PrecisionError: three_pose_fourbar: the crank pivot's
    three positions [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]] are collinear or coincide: no circle (or a
    circle of infinite radius, a slider) passes through them
    """
    what = "three_pose_fourbar"
    p, a, scale = pose_set(points, angles, 3, what)
    c = np.asarray(circles, dtype=float)
    if c.shape[-2:] != (2, 2) or not np.all(np.isfinite(c)):
        raise PrecisionError(
            f"{what}: circles must be two finite moving pivots, shape (..., 2, 2), got {c.shape}"
        )
    if frame == "coupler":
        c = p[..., :1, :] + np.einsum("...ij,...kj->...ki", rotation_matrix(a[..., 0]), c)
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
    delta: NDArray[np.complex128],
    turn: Array,
    coupler_turn: Array,
    scale: Array,
    what: str,
    label: str,
) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
    """W, Z (complex) of the standard dyad form W(e^{iβj} − 1) + Z(e^{iαj} − 1) = δj, j = 2, 3."""
    m11, m12 = np.exp(1j * turn[..., 0]) - 1, np.exp(1j * coupler_turn[..., 0]) - 1
    m21, m22 = np.exp(1j * turn[..., 1]) - 1, np.exp(1j * coupler_turn[..., 1]) - 1
    det = m11 * m22 - m12 * m21
    at = first_true(np.abs(det) <= SINGULAR_TOL)
    if at is not None:
        raise PrecisionError(
            f"{what}: the {label} dyad's equations are singular (determinant "
            f"{abs(complex(det[at])):.3g}){batch_place(at)}: choose other rotations (none may be 0 "
            "for "
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
    MotionDesign
        The poses (Pj, αj) with α1 = 0: ``inputs[..., j] − inputs[..., 0]`` equals βj (mod 2π).

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
    p, _, scale = pose_set(points, None, 3, what)
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
    at = first_true(np.all(np.abs(wrap_angle(beta - gamma)) <= SAME_TOL, axis=-1))
    if at is not None:
        raise PrecisionError(
            f"{what}: the rocker rotations equal the crank rotations{batch_place(at)}: the two "
            "dyads "
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

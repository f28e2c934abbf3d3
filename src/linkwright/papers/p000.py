"""Paper 000 (Özçelik & Şaka): coordinates of coupler points in spherical mechanisms.

The paper finds a coupler point C of a spherical link AB (arc AC, angle μ = BAC) as the
solution of three linear equations: C lies on the plane through O, A and B′, B′ being B turned
by μ about OA (eqs. 6–9), and C·A = cos AC, C·B = cos BC with BC from the spherical law of
cosines (eqs. 10–12); eq. 13 is Cramer's rule for that system. It draws three examples: a
crank-rocker (Fig. 6), a drag link (Fig. 7) and a six-bar (Fig. 8).

linkwright places the same point by turning the great circle A→B about OA by μ and walking the
arc AC from A (:class:`linkwright.engine.SphereRigid`). This module implements the paper's own
system independently, from the printed formulas, and :func:`reproduce` regenerates the three
figures, in every assembly mode, with a page that compares the two ways point by point.

What the formulas need (SEED-NOTES.md): eq. 7 is a pair of equations for the plane's angles α
and β; β follows from both (eq. 8), and "α is calculated by one of the equations above". The
first line, tan α = −z_A / (x_A sin β − y_A cos β), is 0/0 when A lies in the frame plane OXY
(θ2 = 0° or 180° for the four-bar's crank), so α is taken from the line of whichever of A and
B′ is farther from OXY; the first line alone is kept as an option, to show how it degrades.

Where the formulas fail whatever line is used:

- eq. 3 cannot describe a plane that contains OZ (α = 90°, tan α infinite): where the great
  circle AC passes through the poles (e.g. a folded linkage lying in the plane OXZ), eq. 13
  returns noise, reported as NaN;
- the system of eqs. 9–11 is singular for *every* input when μ = ±90° (the normal of the plane
  OAC then lies in the plane OAB, so the three rows are dependent), and ill-conditioned where
  AB, AC or BC is near 0° or 180°.

Measured on 1.8 million random links away from α = 90°, the difference from the rotation is at
most about 8e-16 / (|cos μ| · sin AB · min(sin AC, sin BC)); with the first line of eq. 7
alone, about 6e-16 / (that product · |z_A|).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.geometry import sphere
from linkwright.mechanisms import (
    SphericalFourBar,
    SphericalSixBar,
    circuit,
    input_range,
    solve,
)

__all__ = [
    "FIG6",
    "FIG7",
    "FIG8",
    "TOLERANCE",
    "Alpha90",
    "Degradation",
    "Eq5Check",
    "Fig8Mode",
    "InvalidInput",
    "PointCheck",
    "alpha90_sweep",
    "degradation",
    "eq4_rocker_joint",
    "eq5_checks",
    "eq5_theta4",
    "eq13_coupler_point",
    "fig8_modes",
    "figure_fourbar",
    "figure_sixbar",
    "point_checks",
    "reproduce",
]

Array = NDArray[np.float64]

# Figure captions, degrees, in the paper's order and names.
FIG6 = {"a1": 40.0, "a2": 20.0, "a3": 45.0, "a4": 35.0, "AC": 50.0, "mu": 130.0}
FIG7 = {"a1": 30.0, "a2": 40.0, "a3": 42.0, "a4": 50.0, "AC": 30.0, "mu": -60.0}
FIG8 = {
    "a1": 35.0,
    "a2": 20.0,
    "a3": 42.0,
    "a4": 30.0,
    "AC": 72.0,
    "mu": 22.0,
    "a5": 45.0,  # CE
    "a6": 33.0,  # E0E
    "mu2": 75.0,  # ECD
    "CD": 30.0,
    "B0E0": 85.0,
    "epsilon": 30.0,  # E0B0K
}


VERTICAL_TAN = 1e12
"""Beyond this |tan α| the plane of eq. 3 is taken as containing OZ (α = 90°, singular)."""
SINGULAR_DET = 1e-12
"""Below this |sin AB · cos μ| (the normalised determinant of eqs. 9–11) the system is taken
as singular (μ = ±90° to rounding)."""


class InvalidInput(ValueError):
    """Input that paper 000's formulas cannot take (names the argument and the problem)."""


# --------------------------------------------------------------------------------------------
# The paper's formulas
# --------------------------------------------------------------------------------------------


def _angle(x: ArrayLike, name: str, *, arc: bool = False) -> Array:
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: must be a number or an array of numbers") from None
    if not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: must be finite")
    if arc and np.any((a <= 0) | (a >= np.pi)):
        bad = np.degrees(a[(a <= 0) | (a >= np.pi)]).ravel()[:3].round(9).tolist()
        raise InvalidInput(
            f"{name}: a link's arc must lie strictly between 0° and 180°, got {bad}°"
        )
    return a


def _vectors(x: ArrayLike, name: str) -> Array:
    try:
        v = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: must be an array of 3-vectors") from None
    if v.ndim == 0 or v.shape[-1] != 3:
        raise InvalidInput(f"{name}: must have a last axis of length 3, got shape {v.shape}")
    if np.any(np.isinf(v)):
        raise InvalidInput(f"{name}: must not hold infinite coordinates")
    # NaN rows are samples where the linkage was not assembled: they stay NaN in the result.
    length = sphere.norm(v)
    off = np.abs(length[np.isfinite(length)] - 1.0)
    if off.size and off.max() > 1e-9:
        raise InvalidInput(
            f"{name}: must be unit vectors (a point on the unit sphere), largest | |v| − 1 | is "
            f"{off.max():.3g}"
        )
    return v


def eq5_theta4(
    a1: ArrayLike, a2: ArrayLike, a3: ArrayLike, a4: ArrayLike, theta2: ArrayLike, *, sign=-1
) -> Array:
    """θ4, the rocker angle, from the crank angle θ2 by paper 000's eq. 5 (after McCarthy).

    ``θ4 = 2 arctan((p − √(p² − u² + q²)) / (q + u))`` with
    p = sin a2 sin a4 sin θ2, q = sin a2 sin a4 cos a1 cos θ2 − cos a2 sin a4 sin a1,
    u = cos a3 − cos a1 cos a2 cos a4 − sin a2 cos a4 sin a1 cos θ2. As printed, with the minus
    sign before the root (``sign=-1``); ``sign=+1`` gives the other assembly mode.

    Parameters
    ----------
    a1, a2, a3, a4 : array_like
        Frame, crank, coupler and rocker arcs (radians), each strictly between 0 and π.
    theta2 : array_like
        Crank angle (radians); all arguments broadcast together.
    sign : {-1, +1}
        The sign before the root.

    Returns
    -------
    numpy.ndarray
        θ4 in radians, in (−π, π]; NaN where the four-bar cannot be assembled (p² − u² + q² < 0).

    Raises
    ------
    InvalidInput
        For an arc outside (0, π), a non-finite number or a sign other than ±1.

    Examples
    --------
    Fig. 6's crank-rocker at θ2 = 0° and 90°:

    >>> np.degrees(eq5_theta4(*np.radians([40, 20, 45, 35]), np.radians([0, 90]))).round(6)
    array([71.377625, 77.636228])

    A four-bar that cannot be assembled there:

    >>> eq5_theta4(*np.radians([90, 10, 20, 30]), 0.0)
    np.float64(nan)
    """
    a1, a2, a3, a4 = (
        _angle(v, name, arc=True) for v, name in ((a1, "a1"), (a2, "a2"), (a3, "a3"), (a4, "a4"))
    )
    t = _angle(theta2, "theta2")
    if sign not in (-1, 1):
        raise InvalidInput(f"sign: must be -1 or +1, got {sign!r}")
    p, q, u = _eq5_pqu(a1, a2, a3, a4, t)
    with np.errstate(invalid="ignore", divide="ignore"):
        return 2.0 * np.arctan((p + sign * np.sqrt(p * p - u * u + q * q)) / (q + u))


def _eq5_pqu(a1, a2, a3, a4, t) -> tuple[Array, Array, Array]:
    """Eq. 5's p, q and u, as printed."""
    p = np.sin(a2) * np.sin(a4) * np.sin(t)
    q = np.sin(a2) * np.sin(a4) * np.cos(a1) * np.cos(t) - np.cos(a2) * np.sin(a4) * np.sin(a1)
    u = (
        np.cos(a3)
        - np.cos(a1) * np.cos(a2) * np.cos(a4)
        - np.sin(a2) * np.cos(a4) * np.sin(a1) * np.cos(t)
    )
    return p, q, u


def eq4_rocker_joint(a1: ArrayLike, a4: ArrayLike, theta4: ArrayLike) -> Array:
    """B from the rocker angle θ4 by paper 000's eq. 4.

    ``B = (cos a4 cos a1 − sin a4 sin a1 cos θ4, cos a4 sin a1 + sin a4 cos a1 cos θ4,
    sin a4 sin θ4)``: θ4 = 0 puts B on the frame circle beyond B0.

    Parameters
    ----------
    a1, a4 : array_like
        Frame and rocker arcs (radians), strictly between 0 and π.
    theta4 : array_like
        Rocker angle (radians); NaN gives NaN (a position that does not exist).

    Returns
    -------
    numpy.ndarray, shape (..., 3)

    Raises
    ------
    InvalidInput
        For an arc outside (0, π) or an infinite angle.

    Examples
    --------
    >>> eq4_rocker_joint(np.radians(40), np.radians(35), np.radians([0.0, 90.0])).round(6)
    array([[0.258819, 0.965926, 0.      ],
           [0.627507, 0.526541, 0.573576]])
    """
    a1 = _angle(a1, "a1", arc=True)
    a4 = _angle(a4, "a4", arc=True)
    t = np.asarray(theta4, dtype=float)
    if np.any(np.isinf(t)):
        raise InvalidInput("theta4: must not be infinite")
    x = np.cos(a4) * np.cos(a1) - np.sin(a4) * np.sin(a1) * np.cos(t)
    y = np.cos(a4) * np.sin(a1) + np.sin(a4) * np.cos(a1) * np.cos(t)
    z = np.sin(a4) * np.sin(t)
    return np.stack(np.broadcast_arrays(x, y, z), axis=-1)


def eq13_coupler_point(
    A: ArrayLike,
    B: ArrayLike,
    AB: ArrayLike,
    AC: ArrayLike,
    mu: ArrayLike,
    *,
    alpha_from: str = "better",
) -> Array:
    """The coupler point C of the link AB by paper 000's linear system (eqs. 6–13).

    1. B′ = T·B, T the rotation by μ about OA (eq. 6).
    2. The plane through O, A and B′ is z + tan α (x sin β − y cos β) = 0 (eqs. 3, 7):
       β = atan2(z_A y_B′ − z_B′ y_A, z_A x_B′ − z_B′ x_A) (eq. 8), and tan α from one line of
       eq. 7: ``alpha_from="first"`` takes tan α = −z_A / (x_A sin β − y_A cos β), which is
       0/0 when A is in the plane OXY; ``"better"`` (the default) takes the line of whichever
       of A and B′ lies farther from OXY (the larger denominator, since each denominator is
       its point's z times a common factor), so it never divides 0 by 0.
    3. C solves that plane (eq. 9), C·A = cos AC (eq. 10) and C·B = cos BC (eq. 11) with
       cos BC = cos AB cos AC + sin AB sin AC cos μ (eq. 12), by eq. 13 as printed.

    Parameters
    ----------
    A, B : array_like, shape (..., 3)
        The link's two joints, unit vectors; NaN rows (unassembled samples) give NaN.
    AB : array_like
        The link's arc (the paper's a3), radians, strictly between 0 and π.
    AC, mu : array_like
        Arc from A to C and the angle BAC, right-handed about +OA (radians). All arguments
        broadcast together.
    alpha_from : {"better", "first"}
        Which line of eq. 7 gives α.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        C. NaN where the formulas are singular: μ = ±90° to rounding, |sin AB · cos μ| ≤ 1e-12
        (the normal of the plane OAC lies in the plane OAB, for every input); the plane OAC
        containing OZ (α = 90°, which
        eq. 3 cannot describe: |tan α| > 1e12 is taken as that); the first line's 0/0 with
        ``alpha_from="first"``.

    Raises
    ------
    InvalidInput
        For vectors that are not unit 3-vectors, an arc outside (0, π), a non-finite angle or
        an unknown ``alpha_from``.

    Examples
    --------
    Fig. 6's coupler point at θ2 = 90° (A and B from eqs. 4 and 5):

    >>> a1, a2, a3, a4, ac, mu = np.radians([40, 20, 45, 35, 50, 130])
    >>> t2 = np.radians(90)
    >>> A = np.array([np.cos(a2), np.sin(a2) * np.cos(t2), np.sin(a2) * np.sin(t2)])
    >>> B = eq4_rocker_joint(a1, a4, eq5_theta4(a1, a2, a3, a4, t2))
    >>> eq13_coupler_point(A, B, a3, ac, mu).round(6)
    array([ 0.508573, -0.713401,  0.482092])

    Where A lies in the frame plane (θ2 = 0°) the first line of eq. 7 is 0/0; the default
    takes α from the other line:

    >>> A0 = np.array([np.cos(a2), np.sin(a2), 0.0])
    >>> B0 = eq4_rocker_joint(a1, a4, eq5_theta4(a1, a2, a3, a4, 0.0))
    >>> eq13_coupler_point(A0, B0, a3, ac, mu, alpha_from="first")
    array([nan, nan, nan])
    >>> eq13_coupler_point(A0, B0, a3, ac, mu).round(6)
    array([ 0.866023, -0.499994, -0.003161])
    """
    A = _vectors(A, "A")
    B = _vectors(B, "B")
    AB = _angle(AB, "AB", arc=True)
    AC = _angle(AC, "AC")
    mu = _angle(mu, "mu")
    if alpha_from not in ("better", "first"):
        raise InvalidInput(f"alpha_from: must be 'better' or 'first', got {alpha_from!r}")
    xA, yA, zA = A[..., 0], A[..., 1], A[..., 2]
    xB, yB, zB = B[..., 0], B[..., 1], B[..., 2]
    # Eq. 6: T written out entry by entry, as printed (K = 1 − cos μ).
    c, s = np.cos(mu), np.sin(mu)
    K = 1.0 - c
    xP = (xA * xA * K + c) * xB + (xA * yA * K - zA * s) * yB + (xA * zA * K + yA * s) * zB
    yP = (xA * yA * K + zA * s) * xB + (yA * yA * K + c) * yB + (yA * zA * K - xA * s) * zB
    zP = (xA * zA * K - yA * s) * xB + (yA * zA * K + xA * s) * yB + (zA * zA * K + c) * zB
    # Eq. 8 (atan2 of the printed numerator and denominator).
    beta = np.arctan2(zA * yP - zP * yA, zA * xP - zP * xA)
    sb, cb = np.sin(beta), np.cos(beta)
    with np.errstate(invalid="ignore", divide="ignore"):
        den_a = xA * sb - yA * cb
        den_p = xP * sb - yP * cb
        if alpha_from == "first":
            tan_a = -zA / den_a
        else:
            # Both lines give the same α in exact arithmetic, and each denominator is its own
            # point's z times one common factor (zero where the plane contains OZ). So the
            # line of the point farther from OXY is the one that is not 0/0, and the better
            # conditioned near it; comparing the computed denominators instead would be
            # comparing rounding errors where the plane is nearly vertical.
            tan_a = np.where(np.abs(zA) >= np.abs(zP), -zA / den_a, -zP / den_p)
        # Eq. 12, then eq. 13 as printed.
        ca = np.cos(AC)
        cbc = np.cos(AB) * np.cos(AC) + np.sin(AB) * np.sin(AC) * np.cos(mu)
        u = yB * xA - xB * yA + tan_a * (sb * (yA * zB - zA * yB) - cb * (xB * zA - xA * zB))
        x = (yB * ca - yA * cbc - tan_a * cb * (zA * cbc - zB * ca)) / u
        y = (xA * cbc - xB * ca - tan_a * sb * (zA * cbc - zB * ca)) / u
        z = -tan_a * (sb * (-yA * cbc + yB * ca) - cb * (xA * cbc - xB * ca)) / u
    out = np.stack(np.broadcast_arrays(x, y, z), axis=-1)
    # Eq. 3 cannot describe a plane that contains OZ (α = 90°): there tan α is a rounding
    # error's reciprocal and eq. 13 returns noise, so it is reported as singular instead.
    vertical = np.abs(tan_a) > VERTICAL_TAN
    # u is the system's determinant with the plane's normal (tan α sin β, −tan α cos β, 1)
    # unnormalised; normalised it is ±sin AB · cos μ, zero for every input at μ = ±90°.
    with np.errstate(invalid="ignore", over="ignore"):
        singular = np.abs(u) <= SINGULAR_DET * np.sqrt(1.0 + tan_a * tan_a)
    ok = np.all(np.isfinite(out), axis=-1) & ~vertical & ~singular
    return np.where(ok[..., None], out, np.nan)


# --------------------------------------------------------------------------------------------
# The paper's linkages
# --------------------------------------------------------------------------------------------


def figure_fourbar(number: int, assembly: float = 1.0) -> SphericalFourBar:
    """The four-bar of Fig. 6 (crank-rocker) or Fig. 7 (drag link), coupler point C as P.

    Parameters
    ----------
    number : {6, 7}
        The figure.
    assembly : {+1, -1}
        The mode, sign((A × B0)·B); +1 is eq. 5 as printed.

    Returns
    -------
    SphericalFourBar

    Raises
    ------
    InvalidInput
        For another figure number.

    Examples
    --------
    >>> m = figure_fourbar(6)
    >>> np.degrees([m.frame, m.crank, m.coupler, m.rocker, m.point_arc, m.point_angle])
    array([ 40.,  20.,  45.,  35.,  50., 130.])
    >>> figure_fourbar(5)
    Traceback (most recent call last):
    ...
    linkwright.papers.p000.InvalidInput: number: paper 000's four-bars are Figs 6 and 7, not 5
    """
    table = {6: FIG6, 7: FIG7}
    if number not in table:
        raise InvalidInput(f"number: paper 000's four-bars are Figs 6 and 7, not {number!r}")
    f = table[number]
    return SphericalFourBar(
        *np.radians([f["a1"], f["a2"], f["a3"], f["a4"], f["AC"], f["mu"]]), assembly=assembly
    )


def figure_sixbar(
    epsilon_sign: float = -1.0, assembly: float = -1.0, assembly2: float = 1.0
) -> SphericalSixBar:
    """Fig. 8's six-bar with ε = ``epsilon_sign`` × 30°, right-handed about +OB0.

    The defaults are the reading under which the crank turns fully (:func:`fig8_modes`).

    Parameters
    ----------
    epsilon_sign : {+1, -1}
        The side of E0: −1 puts it below the frame plane.
    assembly, assembly2 : {+1, -1}
        The four-bar's mode sign((A × B0)·B) and the dyad's sign((C × E0)·E).

    Returns
    -------
    SphericalSixBar

    Raises
    ------
    InvalidInput
        For a sign other than ±1 (the mechanism itself checks the assembly signs).

    Examples
    --------
    >>> m = figure_sixbar()
    >>> float(np.degrees(m.ground_angle)), float(m.assembly), float(m.assembly2)
    (-30.0, -1.0, 1.0)
    """
    if epsilon_sign not in (-1, 1):
        raise InvalidInput(f"epsilon_sign: must be -1 or +1, got {epsilon_sign!r}")
    f = FIG8
    return SphericalSixBar(
        *np.radians([f["a1"], f["a2"], f["a3"], f["a4"], f["AC"], f["mu"], f["a5"], f["a6"]]),
        ground_arc=np.radians(f["B0E0"]),
        ground_angle=np.radians(epsilon_sign * f["epsilon"]),
        d_arc=np.radians(f["CD"]),
        d_angle=np.radians(f["mu2"]),
        assembly=assembly,
        assembly2=assembly2,
    )


@dataclass(frozen=True)
class Fig8Mode:
    """One reading of Fig. 8: the sign of ε, the four-bar's assembly, how the crank moves."""

    epsilon: float
    """ε in degrees, right-handed about +OB0."""
    assembly: float
    full: bool
    arcs: tuple[tuple[float, float], ...]
    """The crank's admissible arcs in degrees (empty where it turns fully)."""
    e_branches_distinct: bool
    """Whether assembly2 = ±1 are two different motions (else one circuit passes both)."""


def fig8_modes() -> list[Fig8Mode]:
    """The four readings of Fig. 8 (sign of ε × the four-bar's assembly mode).

    With ε right-handed about +OB0, only ε = −30° with assembly −1 lets the crank turn fully, as
    the paper's figure does ("along whole cycle of the mechanism"); every other reading stops
    at limit positions of the dyad C–E–E0. Its mirror image in the frame plane negates μ and μ2
    too, so it is not among these four.

    Returns
    -------
    list of Fig8Mode
        In the order ε = +30°, −30° and, within each, assembly +1, −1.

    Examples
    --------
    >>> [(m.epsilon, m.assembly, m.full) for m in fig8_modes()]
    [(30.0, 1.0, False), (30.0, -1.0, False), (-30.0, 1.0, False), (-30.0, -1.0, True)]
    """
    out = []
    for eps in (1.0, -1.0):
        for assembly in (1.0, -1.0):
            m = figure_sixbar(eps, assembly, 1.0)
            arcs = input_range(m)
            full = bool(arcs.full)
            spans = tuple(
                (float(np.degrees(lo)), float(np.degrees(hi)))
                for lo, hi in zip(arcs.lo, arcs.hi, strict=True)
                if np.isfinite(lo)
            )
            # A circuit that stops at limits of the dyad C–E–E0 changes E's branch there, so it
            # already runs through both of its modes; otherwise the other mode is a second
            # motion.
            e_dyad = [d.name for d in m.plan.dyads].index("E")
            distinct = not (np.any(arcs.dyad_lo == e_dyad) or np.any(arcs.dyad_hi == e_dyad))
            out.append(Fig8Mode(FIG8["epsilon"] * eps, assembly, full, spans, distinct))
    return out


# --------------------------------------------------------------------------------------------
# Numerical checks
# --------------------------------------------------------------------------------------------

TOLERANCE = 1e-13


@dataclass(frozen=True)
class PointCheck:
    """Eqs. 6–13 against linkwright's rotation about the link's first joint, over a curve."""

    case: str
    point: str
    samples: int
    better: float
    """Largest |ΔC| over every sample, α from the better line of eq. 7."""
    first: float
    """Largest |ΔC| with α from eq. 7's first line, over samples whose link origin O has
    |z_O| ≥ sin 1° (its 0/0 is at z_O = 0); ``first_at_zero`` covers the rest."""
    first_at_zero: float
    """Largest |ΔC| with the first line over the samples with |z_O| < sin 1° (NaN counts as
    infinite)."""


def _point_check(case: str, motion, origin: str, toward: str, point: str, ab, ac, mu) -> PointCheck:
    pos = motion.positions
    ref = pos[point]
    err = {
        line: sphere.norm(
            eq13_coupler_point(pos[origin], pos[toward], ab, ac, mu, alpha_from=line) - ref
        )
        for line in ("better", "first")
    }
    near = np.abs(pos[origin][..., 2]) < math.sin(math.radians(1.0))
    first = np.where(np.isnan(err["first"]), np.inf, err["first"])
    return PointCheck(
        case,
        point,
        int(motion.shape[-1]),
        float(np.max(np.where(np.isnan(err["better"]), np.inf, err["better"]))),
        float(np.max(first[~near])) if np.any(~near) else 0.0,
        float(np.max(first[near])) if np.any(near) else 0.0,
    )


def point_checks(samples: int = 360) -> list[PointCheck]:
    """Eqs. 6–13 against linkwright for every coupler point of the three figures.

    Both four-bar modes of Figs 6 and 7, and C and D of Fig. 8 in its full-turn reading (both
    modes of E), each over a whole circuit of ``samples`` inputs (θ2 = 0°, 180° included).

    Parameters
    ----------
    samples : int
        Samples per circuit.

    Returns
    -------
    list of PointCheck

    Examples
    --------
    >>> checks = point_checks(90)
    >>> [c.point for c in checks]
    ['P', 'P', 'P', 'P', 'C', 'D', 'C', 'D']
    >>> max(c.better for c in checks) < 1e-13
    True
    """
    out = []
    for number in (6, 7):
        for assembly in (1.0, -1.0):
            m = figure_fourbar(number, assembly)
            motion = circuit(m, samples, order=0)
            case = f"Fig. {number}, assembly {_sign(assembly)}"
            out.append(
                _point_check(case, motion, "A", "B", "P", m.coupler, m.point_arc, m.point_angle)
            )
    for assembly2 in (1.0, -1.0):
        m = figure_sixbar(-1.0, -1.0, assembly2)
        motion = circuit(m, samples, order=0)
        case = f"Fig. 8 (ε −30°, assembly −1), assembly2 {_sign(assembly2)}"
        out.append(_point_check(case, motion, "A", "B", "C", m.coupler, m.point_arc, m.point_angle))
        out.append(_point_check(case, motion, "C", "E", "D", m.link5, m.d_arc, m.d_angle))
    return out


def _sign(x: float) -> str:
    return "+1" if x > 0 else "−1"


@dataclass(frozen=True)
class Degradation:
    """How the first line of eq. 7 fails near its 0/0 inputs θ2 = 0°, 180° (four-bar C)."""

    case: str
    deltas: tuple[float, ...]
    """Distances from 0°/180° in degrees (0 = the singular input itself)."""
    first: tuple[float, ...]
    """Largest |ΔC| at θ2 = 0° ± δ and 180° ± δ, first line (inf where NaN)."""
    better: tuple[float, ...]
    """The same with α from the better line."""
    onset: float
    """Largest δ (degrees, on a log grid from 1e-10° to 10°) where the first line is off by
    more than 1e-13."""


def degradation(
    deltas: tuple[float, ...] = (10, 1, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 0),
) -> list[Degradation]:
    """The first line of eq. 7 near its 0/0 inputs θ2 = 0°, 180°, for the coupler points C of
    Figs 6, 7 (both modes) and 8 (full-turn reading), beside the better line.

    Parameters
    ----------
    deltas : tuple of float
        Distances from 0° and 180° in degrees; each is evaluated at 0° ± δ and 180° ± δ.

    Returns
    -------
    list of Degradation

    Examples
    --------
    At θ2 = 0° itself the first line is 0/0 and the better line is exact to rounding:

    >>> d = degradation(deltas=(1.0, 0.0))[0]
    >>> d.case, d.first[1], d.better[1] < 1e-15
    ('Fig. 6, assembly +1', inf, True)
    """
    fine = np.logspace(-10, 1, 221)
    cases = [
        (f"Fig. {n}, assembly {_sign(a)}", figure_fourbar(n, a))
        for n in (6, 7)
        for a in (1.0, -1.0)
    ]
    cases.append(("Fig. 8 (ε −30°, assembly −1), C", figure_sixbar()))
    out = []
    for case, m in cases:

        def errors(d: Array, line: str, m=m) -> Array:
            d = np.radians(np.asarray(d, dtype=float))
            theta = np.concatenate([c + s * d for c in (0.0, math.pi) for s in (1.0, -1.0)])
            motion = solve(m, theta, order=0)
            pos = motion.positions
            joint = "P" if "P" in pos else "C"
            c = eq13_coupler_point(
                pos["A"], pos["B"], m.coupler, m.point_arc, m.point_angle, alpha_from=line
            )
            e = sphere.norm(c - pos[joint])
            e = np.where(np.isnan(e), np.inf, e).reshape(4, -1)
            return e.max(axis=0)

        first = errors(np.asarray(deltas), "first")
        better = errors(np.asarray(deltas), "better")
        over = fine[errors(fine, "first") > TOLERANCE]
        out.append(
            Degradation(
                case,
                tuple(float(d) for d in deltas),
                tuple(float(x) for x in first),
                tuple(float(x) for x in better),
                float(over.max()) if over.size else 0.0,
            )
        )
    return out


@dataclass(frozen=True)
class Alpha90:
    """Eqs. 7–13 (better line) next to an input where the plane OAX contains OZ (α = 90°)."""

    case: str
    point: str
    crossing: float
    """The input θ2 (degrees) where the plane through O, the link's first joint and the point
    contains OZ, found by bracketing and root finding."""
    deltas: tuple[float, ...]
    """Distances from it in degrees (0 = the crossing itself)."""
    errors: tuple[float, ...]
    """Largest |ΔX| at crossing ± δ (inf where NaN: reported singular)."""


def alpha90_sweep(
    deltas: tuple[float, ...] = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0),
) -> list[Alpha90]:
    """Where the figures' planes OAC (and OCD) pass through OZ, and eqs. 7–13 next to it.

    Eq. 3 describes the plane by tan α, infinite where the plane contains OZ; the figures'
    curves cross that set at isolated inputs. At each crossing (Figs 6 and 7 in both modes,
    Fig. 8's C and D in the full-turn reading) this gives the largest difference from
    linkwright's point at crossing ± δ.

    Parameters
    ----------
    deltas : tuple of float
        Distances from the crossing, degrees.

    Returns
    -------
    list of Alpha90

    Examples
    --------
    Fig. 7 (mode +1)'s plane OAC contains OZ near θ2 = 3.11°; 1e-8° away eq. 13 is as good as
    anywhere, at the crossing itself it is reported singular:

    >>> [(round(s.crossing, 4), s.errors[0] < 1e-14, s.errors[1]) for s in
    ...  alpha90_sweep(deltas=(1e-8, 0.0)) if s.case == "Fig. 7, assembly +1"][0]
    (3.1114, True, inf)
    """
    from scipy.optimize import brentq

    cases = [
        (f"Fig. {n}, assembly {_sign(a)}", figure_fourbar(n, a), ("A", "B", "P"))
        for n in (6, 7)
        for a in (1.0, -1.0)
    ]
    m8 = figure_sixbar()
    cases += [("Fig. 8 (ε −30°, assembly −1)", m8, ("A", "B", "C"))]
    cases += [("Fig. 8 (ε −30°, assembly −1)", m8, ("C", "E", "D"))]
    out = []
    for case, m, (origin, toward, point) in cases:
        if point == "D":
            ab, ac, mu = m.link5, m.d_arc, m.d_angle
        else:
            ab, ac, mu = m.coupler, m.point_arc, m.point_angle

        def tilt(theta, m=m, origin=origin, point=point) -> Array:
            pos = solve(m, np.atleast_1d(theta), order=0).positions
            return sphere.cross(pos[origin], pos[point])[..., 2]

        grid = np.radians(np.arange(0.0, 360.5, 0.5))
        z = tilt(grid)
        for i in np.nonzero(np.sign(z[:-1]) != np.sign(z[1:]))[0]:
            root = brentq(lambda t, f=tilt: float(f(t)[0]), grid[i], grid[i + 1], xtol=1e-15)
            d = np.radians(np.asarray(deltas, dtype=float))
            theta = np.concatenate((root - d, root + d))
            pos = solve(m, theta, order=0).positions
            c = eq13_coupler_point(pos[origin], pos[toward], ab, ac, mu)
            e = sphere.norm(c - pos[point])
            e = np.where(np.isnan(e), np.inf, e).reshape(2, -1).max(axis=0)
            out.append(
                Alpha90(
                    case,
                    point,
                    float(np.degrees(root)),
                    tuple(float(x) for x in deltas),
                    tuple(float(x) for x in e),
                )
            )
    return out


@dataclass(frozen=True)
class Eq5Check:
    """Eqs. 4–5 against linkwright's B over a whole crank turn (1° steps)."""

    case: str
    printed: float
    """Largest |B(eqs. 4, 5 as printed) − B| in linkwright's mode +1."""
    printed_theta4: float
    """Largest |θ4 (eq. 5) − φ3| in mode +1, radians (φ3 = linkwright's output angle)."""
    other_sign: float
    """Largest |B(eq. 5 with + before the root) − B| in mode −1."""
    worst_theta2: float
    """The input (degrees) of the largest difference in mode +1."""
    q_plus_u: float
    """|q + u| there: eq. 5's quotient is 0/0 where q + u = 0 and p > 0."""


def eq5_checks(samples: int = 360) -> list[Eq5Check]:
    """Eqs. 4–5 against linkwright's B for the four-bars of Figs 6, 7 and 8.

    Eq. 5 as printed is linkwright's mode +1, the other sign before the root mode −1.

    Parameters
    ----------
    samples : int
        Inputs over one turn of the crank.

    Returns
    -------
    list of Eq5Check

    Examples
    --------
    >>> [(c.case, c.printed < 1e-12, c.other_sign < 1e-12) for c in eq5_checks(90)]
    [('Fig. 6', True, True), ('Fig. 7', True, True), ("Fig. 8's four-bar", True, True)]
    """
    f8 = FIG8
    linkages = {
        "Fig. 6": figure_fourbar(6),
        "Fig. 7": figure_fourbar(7),
        "Fig. 8's four-bar": SphericalFourBar(
            *np.radians([f8[k] for k in ("a1", "a2", "a3", "a4")])
        ),
    }
    theta = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
    out = []
    for case, m in linkages.items():
        row = []
        for sign in (1.0, -1.0):
            motion = solve(m.with_assembly(sign), theta, order=0)
            t4 = eq5_theta4(m.frame, m.crank, m.coupler, m.rocker, theta, sign=-int(sign))
            b = eq4_rocker_joint(m.frame, m.rocker, t4)
            err = sphere.norm(b - motion.positions["B"])
            row.append(float(np.max(err)))
            if sign > 0:
                phi3 = m.output_angle(motion)
                d = np.angle(np.exp(1j * (t4 - phi3)))
                row.append(float(np.max(np.abs(d))))
                k = int(np.argmax(err))
        _, q, u = _eq5_pqu(m.frame, m.crank, m.coupler, m.rocker, theta[k])
        t = theta[k]
        out.append(Eq5Check(case, row[0], row[1], row[2], float(np.degrees(t)), float(abs(q + u))))
    return out


# --------------------------------------------------------------------------------------------
# Regeneration
# --------------------------------------------------------------------------------------------


def _e(x: float) -> str:
    if math.isinf(x):
        return "NaN or ∞"
    return f"{x:.1e}".replace("-", "−")


def _save_both(fig, out: Path, stem: str) -> list[Path]:
    from linkwright.plot import save_figure

    return [save_figure(fig, out / f"{stem}.png"), save_figure(fig, out / f"{stem}.svg")]


def reproduce(out: str | Path, *, samples: int = 360) -> list[Path]:
    """Regenerate Figs 6, 7 and 8 (PNG and SVG) and the page ``paper000.md``; return the files.

    Figs 6 and 7 are drawn in both assembly modes of the four-bar, Fig. 8 in all four
    readings of ε's sign and the four-bar's mode (with both modes of the dyad C–E–E0 where
    they are different motions). The page states the parameters and the reading adopted, and
    the numerical checks: eqs. 6–13 against linkwright's coupler points, the first line of
    eq. 7 near its 0/0 inputs, eq. 5 against linkwright's B.

    Parameters
    ----------
    out : str or pathlib.Path
        Folder to write into (created if missing).
    samples : int
        Samples per circuit, for the pictures and the checks.

    Returns
    -------
    list of pathlib.Path
        ``p000-fig6.png``, ``p000-fig6.svg``, ``p000-fig7.png``, ``p000-fig7.svg``,
        ``p000-fig8.png``, ``p000-fig8.svg``, ``paper000.md`` and the checks' tables as CSV
        (``paper000-point-checks.csv``, ``paper000-eq5-checks.csv``,
        ``paper000-fig8-readings.csv``), in that order.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     print(*(p.name for p in reproduce(tmp, samples=72)))
    p000-fig6.png p000-fig6.svg p000-fig7.png p000-fig7.svg p000-fig8.png p000-fig8.svg
    paper000.md paper000-point-checks.csv paper000-eq5-checks.csv paper000-fig8-readings.csv
    """
    from linkwright.plot import new_figure
    from linkwright.plot.sphere import plot_spherical_linkage

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    names = {6: "crank-rocker", 7: "drag link"}
    for number in (6, 7):
        fig = new_figure((12, 6.6))
        for k, assembly in enumerate((1.0, -1.0)):
            note = " (eq. 5 as printed)" if assembly > 0 else " (eq. 5's other sign)"
            plot_spherical_linkage(
                figure_fourbar(number, assembly),
                samples=samples,
                title=f"Fig. {number}, {names[number]}: assembly {_sign(assembly)}{note}",
                ax=fig.add_subplot(1, 2, k + 1),
            )
        written += _save_both(fig, out, f"p000-fig{number}")
    modes = fig8_modes()
    fig = new_figure((12, 13))
    for k, mode in enumerate(modes):
        eps = 1.0 if mode.epsilon > 0 else -1.0
        m = figure_sixbar(eps, mode.assembly, 1.0)
        extra = None
        if mode.e_branches_distinct:
            other = circuit(figure_sixbar(eps, mode.assembly, -1.0), samples, order=0)
            extra = [("path of D, assembly2 −1", other.positions["D"])]
        verdict = "turns fully: the paper's figure" if mode.full else "crank cannot turn fully"
        plot_spherical_linkage(
            m,
            samples=samples,
            title=(
                f"Fig. 8: ε = {mode.epsilon:+.0f}°, assembly {_sign(mode.assembly)}, "
                f"assembly2 +1 — {verdict}"
            ).replace("-", "−"),
            extra_curves=extra,
            ax=fig.add_subplot(2, 2, k + 1),
        )
    written += _save_both(fig, out, "p000-fig8")
    page = out / "paper000.md"
    page.write_text(_markdown(modes, samples, [p.name for p in written]), encoding="utf-8")
    written.append(page)
    for stem, rows in (
        ("paper000-point-checks", point_checks(samples)),
        ("paper000-eq5-checks", eq5_checks(samples)),
        ("paper000-fig8-readings", modes),
    ):
        written.append(_write_csv(out / f"{stem}.csv", rows))
    return written


def _write_csv(path: Path, rows: list) -> Path:
    """One row per check (a dataclass), its fields as the columns (:func:`_csv_cell`)."""
    import csv
    import dataclasses

    names = [f.name for f in dataclasses.fields(rows[0])]
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(names)
        for row in rows:
            writer.writerow([_csv_cell(getattr(row, n)) for n in names])
    return path


def _csv_cell(value: object) -> str:
    """A CSV cell: numbers with all digits (``inf`` where a method fails, as the checks say),
    ``true``/``false``, text as it is, and a list of arcs as JSON (``[[lo, hi], …]``)."""
    import json

    from linkwright.io.exports import number_text

    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    if isinstance(value, tuple | list):
        return json.dumps([[float(x) for x in arc] for arc in value])
    return number_text(value)


def _markdown(modes: list[Fig8Mode], samples: int, pictures: list[str]) -> str:
    checks = point_checks(samples)
    sweeps = degradation()
    vertical = alpha90_sweep()
    eq5 = eq5_checks(samples)
    worst = max(c.better for c in checks)
    lines = [
        "# Paper 000 (Özçelik & Şaka), Figs 6–8 regenerated",
        "",
        "Coupler curves of spherical linkages, drawn on the unit sphere (orthographic view; the",
        "far hemisphere dashed and faded). Angles in degrees.",
        "",
        "## Parameters (figure captions)",
        "",
        "| figure | a1 (frame) | a2 (crank) | a3 (coupler) | a4 (rocker) | AC | μ = BAC |",
        "|---|---|---|---|---|---|---|",
        *(
            f"| {n} | "
            + " | ".join(
                f"{f[k]:g}".replace("-", "−") for k in ("a1", "a2", "a3", "a4", "AC", "mu")
            )
            + " |"
            for n, f in (("6 (crank-rocker)", FIG6), ("7 (drag link)", FIG7), ("8 (six-bar)", FIG8))
        ),
        "",
        f"Fig. 8 adds a5 = CE = {FIG8['a5']:g}, a6 = E0E = {FIG8['a6']:g}, "
        f"B0E0 = {FIG8['B0E0']:g}, ε = E0B0K = {FIG8['epsilon']:g}, "
        f"CD = {FIG8['CD']:g}, μ2 = ECD = {FIG8['mu2']:g}.",
        "",
        "## Reading adopted",
        "",
        "- Frame circle in OXY: A0 = (1, 0, 0), B0 = (cos a1, sin a1, 0); "
        "A = (cos a2, sin a2 cos θ2, sin a2 sin θ2) (eq. 4).",
        "- μ = BAC is a right-handed rotation about +OA (the matrix T of eq. 6): C is B's great "
        "circle from A turned by μ, at arc AC from A. Likewise D on CE with μ2 = ECD about +OC.",
        "- Assembly mode = sign((A × B0)·B). Eq. 5 as printed (minus before the root) is mode "
        "+1; the plus sign is mode −1 (table below).",
        "- Fig. 8: E0 at arc B0E0 from B0, at angle ε about +OB0 (right-handed) from the frame "
        "circle beyond B0 (K continues A0→B0). The paper prints neither ε's sense nor the "
        "modes; the four readings of (sign of ε, mode of the four-bar) give:",
        "",
        "| ε | assembly | crank | assembly2 ±1 |",
        "|---|---|---|---|",
    ]
    for mode in modes:
        if mode.full:
            crank = "**turns fully** (matches the paper's closed curves)"
        else:
            spans = ", ".join(f"[{lo:.2f}, {hi:.2f}]" for lo, hi in mode.arcs)
            crank = f"rocks over {spans}, stopped by the dyad C–E–E0"
        e2 = (
            "two different motions (both drawn)"
            if mode.e_branches_distinct
            else "one circuit, through both"
        )
        lines.append(
            f"| {mode.epsilon:+.0f} | {_sign(mode.assembly)} | {crank} | {e2} |".replace("-", "−")
        )
    lines += [
        "",
        "So the figure is ε = −30° (E0 below the frame plane, i.e. the printed 30° measured "
        "clockwise seen from outside above B0) with assembly −1. Its mirror image in the frame "
        "plane is the same motion but negates μ and μ2 as well, so it is none of the four.",
        "",
        "## Check 1: the coupler point, eqs. 6–13 against rotation about OA",
        "",
        "linkwright places C by turning the great circle A→B about OA by μ and walking AC "
        "(SphereRigid); here C is also computed by the paper's linear system, implemented from "
        "the printed eqs. 6–13 (`eq13_coupler_point`). Eq. 7's first line, "
        "tan α = −z_A / (x_A sin β − y_A cos β), is 0/0 where A lies in OXY (θ2 = 0°, 180°), so "
        "α is taken from the line of whichever of A, B′ is farther from OXY (the larger "
        "denominator); the first line alone is shown "
        "for comparison. Largest |ΔC| (chord) over whole circuits of "
        f"{samples} samples, θ2 = 0°, 180° included:",
        "",
        "| linkage | point | better line of eq. 7 | first line, \\|z_O\\| ≥ sin 1° | "
        "first line, \\|z_O\\| < sin 1° |",
        "|---|---|---|---|---|",
        *(
            f"| {c.case} | {c.point} | {_e(c.better)} | {_e(c.first)} | {_e(c.first_at_zero)} |"
            for c in checks
        ),
        "",
        f"With α from the better line the two methods agree to {_e(worst)} everywhere "
        f"(required: ≤ {_e(TOLERANCE)}); z_O is the height above OXY of the link's first joint "
        "(A for C, C for D), where the first line is 0/0.",
        "",
        "### Where eqs. 7–13 fail, and the agreement elsewhere",
        "",
        "- Eq. 7's first line is 0/0 where A lies in OXY (θ2 = 0°, 180°); the other line is "
        "0/0 where B′ does, and never both unless A, B′ (so C) are all in OXY, where the "
        "plane is OXY itself and α = 0 follows from either line.",
        "- Eq. 3 cannot describe a plane through OZ (α = 90°, tan α infinite): where the great "
        "circle AC passes through the poles, eq. 13 returns noise, so `eq13_coupler_point` "
        "reports NaN there (|tan α| > 1e12). The figures' curves do cross it at isolated "
        "inputs (table below): right next to them eq. 13 is as good as anywhere.",
        "- Eqs. 9–11 are singular for every input at μ = ±90° and ill-conditioned where AB, AC "
        "or BC nears 0° or 180°.",
        "",
        "On 1.8 million random links the difference from the rotation stayed below "
        "8e−16 / (\\|cos μ\\| · sin AB · min(sin AC, sin BC)), and 6e−16 / (that product · "
        "\\|z_A\\|) with the first line alone. The Hypothesis test on random spherical four-bars "
        "(`tests/test_p000.py`) asserts 1e−13 where that product is ≥ 0.02 (≥ 0.01 times "
        "\\|z_A\\| for the first line) and the plane OAC is at least 1e−10 from OZ.",
        "",
        "Next to the inputs where the plane through O, the link's first joint and the point "
        "contains OZ (largest \\|ΔC\\| at crossing ± δ, better line; NaN or ∞ = reported "
        "singular):",
        "",
        "| linkage | point | crossing θ2 (°) | "
        + " | ".join(f"δ = {d:g}°".replace("e-", "e−") for d in vertical[0].deltas)
        + " |",
        "|---|---|---" + "|---" * len(vertical[0].deltas) + "|",
        *(
            f"| {v.case} | {v.point} | {v.crossing:.4f} | "
            + " | ".join(_e(x) for x in v.errors)
            + " |"
            for v in vertical
        ),
        "",
        "### How close to θ2 = 0°, 180° the first line of eq. 7 degrades",
        "",
        "Largest |ΔC| at θ2 = 0° ± δ and 180° ± δ (δ = 0: the singular inputs themselves; in "
        "floating point sin 180° ≈ 1.2e−16, so there the first line returns a wrong point "
        "rather than NaN):",
        "",
        "| δ (°) | " + " | ".join(s.case for s in sweeps) + " |",
        "|---" * (len(sweeps) + 1) + "|",
    ]
    for i, d in enumerate(sweeps[0].deltas):
        cells = " | ".join(f"{_e(s.first[i])} (better: {_e(s.better[i])})" for s in sweeps)
        lines.append(f"| {d:g} | {cells} |".replace("e-", "e−"))
    onset = max(s.onset for s in sweeps)
    lines += [
        "",
        "The first line stays within 1e−13 for |θ2 − 0°/180°| ≥ δ* with δ* = "
        + ", ".join(f"{s.onset:.2g}° ({s.case})" for s in sweeps)
        + f"; in all, beyond {onset:.2g}°. Its error grows like 1/|z_A|. The better line "
        "shows no degradation at all.",
        "",
        "## Check 2: eq. 5 (θ4) against linkwright's B",
        "",
        f"B from eqs. 4 and 5 at {samples} inputs over a whole turn, against linkwright's B:",
        "",
        "| linkage | eq. 5 as printed vs mode +1: max \\|ΔB\\| | max \\|θ4 − φ3\\| (rad) | "
        "other sign vs mode −1: max \\|ΔB\\| | worst input θ2 (mode +1) | \\|q + u\\| there |",
        "|---|---|---|---|---|---|",
        *(
            f"| {c.case} | {_e(c.printed)} | {_e(c.printed_theta4)} | {_e(c.other_sign)} | "
            f"{c.worst_theta2:g}° | {_e(c.q_plus_u)} |"
            for c in eq5
        ),
        "",
        "Eq. 5's quotient is itself 0/0 where q + u = 0 and p > 0 (p − √(p² − u² + q²) then "
        "vanishes too): the largest differences sit where the crank passes close to that, as "
        "the last two columns show.",
        "",
        "## Files",
        "",
        *(f"- {name}" for name in pictures),
        "",
    ]
    return "\n".join(lines)

"""Paper 000 (Özçelik & Şaka, coordinates of coupler points in spherical mechanisms): its
formulas, implemented independently from the printed text.

Eq. 4 places the rocker joint B, eq. 5 gives the rocker angle θ4 of the spherical four-bar by
the half-angle substitution, and eq. 13 (Cramer's rule for eqs. 9–11) places a coupler point C
of a link AB from the plane through O, A and B′ (B turned by μ about OA, eqs. 6–9) and the arc
lengths AC and BC (eqs. 10–12). Eq. 7 gives the plane's angle α by two lines; the first is 0/0
where A lies in the frame plane OXY, so α is taken from the line of whichever of A and B′ is
farther from OXY (the first line alone is kept as an option, to show how it degrades). Where
the formulas fail whatever line is used (α = 90°, μ = ±90°) the point is NaN; see
:mod:`linkwright.papers.p000` for the whole account.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.geometry import sphere

__all__ = [
    "SINGULAR_DET",
    "VERTICAL_TAN",
    "InvalidInput",
    "eq4_rocker_joint",
    "eq5_pqu",
    "eq5_theta4",
    "eq13_coupler_point",
]

Array = NDArray[np.float64]


VERTICAL_TAN = 1e12
"""Beyond this |tan α| the plane of eq. 3 is taken as containing OZ (α = 90°, singular)."""


SINGULAR_DET = 1e-12
"""Below this |sin AB · cos μ| (the normalised determinant of eqs. 9–11) the system is taken
as singular (μ = ±90° to rounding)."""


class InvalidInput(ValueError):
    """Input that paper 000's formulas cannot take (names the argument and the problem)."""


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
    a1: ArrayLike, a2: ArrayLike, a3: ArrayLike, a4: ArrayLike, theta2: ArrayLike, *, sign: int = -1
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
    p, q, u = eq5_pqu(a1, a2, a3, a4, t)
    with np.errstate(invalid="ignore", divide="ignore"):
        theta4: Array = 2.0 * np.arctan((p + sign * np.sqrt(p * p - u * u + q * q)) / (q + u))
    return theta4


def eq5_pqu(
    a1: ArrayLike, a2: ArrayLike, a3: ArrayLike, a4: ArrayLike, t: ArrayLike
) -> tuple[Array, Array, Array]:
    """Eq. 5's p, q and u, as printed."""
    p: Array = np.sin(a2) * np.sin(a4) * np.sin(t)
    q: Array = np.sin(a2) * np.sin(a4) * np.cos(a1) * np.cos(t) - np.cos(a2) * np.sin(a4) * np.sin(
        a1
    )
    u: Array = (
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

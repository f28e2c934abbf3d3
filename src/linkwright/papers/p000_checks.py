"""Paper 000 (Özçelik & Şaka): numerical checks of its formulas against linkwright's own
construction.

Eq. 13's coupler points are compared point by point with the rotation linkwright uses
(:class:`linkwright.engine.SphereRigid`) over every figure's circuit (:func:`point_checks`);
:func:`degradation` shows how the first line of eq. 7 alone degrades near the frame plane, and
:func:`alpha90_sweep` how every line fails where the plane of eq. 3 contains OZ (α = 90°).
:func:`eq5_checks` checks eq. 5's rocker angle and eq. 4's rocker joint against the solved
linkage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from linkwright.engine import Motion
from linkwright.geometry import sphere
from linkwright.mechanisms import (
    SphericalFourBar,
    SphericalSixBar,
    circuit,
    solve,
)
from linkwright.papers.p000_figures import FIG8, figure_fourbar, figure_sixbar
from linkwright.papers.p000_formulas import (
    Array,
    eq4_rocker_joint,
    eq5_pqu,
    eq5_theta4,
    eq13_coupler_point,
)

__all__ = [
    "TOLERANCE",
    "Alpha90",
    "Degradation",
    "Eq5Check",
    "PointCheck",
    "alpha90_sweep",
    "degradation",
    "eq5_checks",
    "point_checks",
    "sign_label",
]

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


def _point_check(
    case: str,
    motion: Motion,
    origin: str,
    toward: str,
    point: str,
    ab: ArrayLike,
    ac: ArrayLike,
    mu: ArrayLike,
) -> PointCheck:
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
            case = f"Fig. {number}, assembly {sign_label(assembly)}"
            out.append(
                _point_check(case, motion, "A", "B", "P", m.coupler, m.point_arc, m.point_angle)
            )
    for assembly2 in (1.0, -1.0):
        six = figure_sixbar(-1.0, -1.0, assembly2)
        motion = circuit(six, samples, order=0)
        case = f"Fig. 8 (ε −30°, assembly −1), assembly2 {sign_label(assembly2)}"
        out.append(
            _point_check(case, motion, "A", "B", "C", six.coupler, six.point_arc, six.point_angle)
        )
        out.append(_point_check(case, motion, "C", "E", "D", six.link5, six.d_arc, six.d_angle))
    return out


def sign_label(x: float) -> str:
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
    cases: list[tuple[str, SphericalFourBar | SphericalSixBar]] = [
        (f"Fig. {n}, assembly {sign_label(a)}", figure_fourbar(n, a))
        for n in (6, 7)
        for a in (1.0, -1.0)
    ]
    cases.append(("Fig. 8 (ε −30°, assembly −1), C", figure_sixbar()))
    out = []
    for case, m in cases:

        def errors(d: Array, line: str, m: SphericalFourBar | SphericalSixBar = m) -> Array:
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
            worst: Array = e.max(axis=0)
            return worst

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

    cases: list[tuple[str, SphericalFourBar | SphericalSixBar, tuple[str, str, str]]] = [
        (f"Fig. {n}, assembly {sign_label(a)}", figure_fourbar(n, a), ("A", "B", "P"))
        for n in (6, 7)
        for a in (1.0, -1.0)
    ]
    m8 = figure_sixbar()
    cases += [("Fig. 8 (ε −30°, assembly −1)", m8, ("A", "B", "C"))]
    cases += [("Fig. 8 (ε −30°, assembly −1)", m8, ("C", "E", "D"))]
    out = []
    for case, m, (origin, toward, point) in cases:
        if point == "D":
            assert isinstance(m, SphericalSixBar)  # D is Fig. 8's second coupler point
            ab, ac, mu = m.link5, m.d_arc, m.d_angle
        else:
            ab, ac, mu = m.coupler, m.point_arc, m.point_angle

        def tilt(
            theta: ArrayLike,
            m: SphericalFourBar | SphericalSixBar = m,
            origin: str = origin,
            point: str = point,
        ) -> Array:
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
        _, q, u = eq5_pqu(m.frame, m.crank, m.coupler, m.rocker, theta[k])
        t = theta[k]
        out.append(Eq5Check(case, row[0], row[1], row[2], float(np.degrees(t)), float(abs(q + u))))
    return out

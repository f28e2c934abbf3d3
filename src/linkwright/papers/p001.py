"""Paper 001 (Zong, Lu, An, Zhang): the configuration analysis of the spherical Stephenson III.

The paper sets up the position equations of the Stephenson-III spherical six-bar (fixed A, D,
G; input AB; ternary coupler BCE; CD; EF; FG), eliminates down to a degree-8 polynomial (eqs.
19–20) and concludes that the linkage has "at most 8" configurations for input AB. It prints no
numeric example. linkwright's reading (SEED-NOTES.md):

- Driven at AB, one rigid coupler has at most 2 × 2 = 4 configurations (four-bar ABCD × dyad
  EFG). The paper's system (4) fixes only cos σ, so it also admits the mirror-image coupler
  (σ → −σ): its 8 = 4 + 4 counts two mechanisms. :func:`mirror_check` shows the 4 + 4 at one
  input and :func:`eq20_check` finds exactly those configurations (of both couplers) among the
  real roots of the paper's eq. 20.
- Eight genuine configurations occur when the linkage is driven at FG: the coupler is then a
  spherical triad (:func:`linkwright.engine.sphere_triad.sphere_triad`). :data:`EXAMPLE` is a
  mechanism chosen by a search for one with eight real configurations at some θ6 (it has them
  at 66 of the 360 whole degrees of θ6; at :data:`EXAMPLE_INPUT` = 280° they are farthest
  apart).
- :mod:`linkwright.papers.p001_circuits` follows issue 21's example driven at FG (the bundled
  ``paper001-fg``: 8, 4 and 6 configurations at θ6 = −90°, 0°, 120°) over its input: its closed
  circuits, and which configurations join at which limit positions.
- :func:`misprints` checks each misprint of SEED-NOTES.md numerically (and that eqs. 19 and 21
  are right).

:func:`reproduce` writes all of it: a Markdown page, CSV tables and the figures.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.sphere_triad import bilinear_resultant, circle_frame
from linkwright.geometry import sphere
from linkwright.mechanisms import SphericalStephenson3, solve, solve_all
from linkwright.papers import p001_circuits
from linkwright.papers.p001_angles import paper_angles

__all__ = [
    "EXAMPLE",
    "EXAMPLE_INPUT",
    "MIRROR_INPUT",
    "Misprint",
    "configuration_table",
    "count_sweep",
    "eq18_check",
    "eq20_check",
    "example",
    "mirror_check",
    "misprints",
    "reproduce",
]

Array = NDArray[np.float64]

EXAMPLE: dict[str, float] = {
    "a1": 115.0,  # AD
    "a2": 105.0,  # AB, the input link
    "a3": 110.0,  # BC
    "a4": 90.0,  # CD
    "a6": 80.0,  # CE
    "sigma": 70.0,  # 180° − angle BCE (eq. 3's σ: angle BCE is 110°)
    "a7": 65.0,  # EF
    "a8": 85.0,  # FG, the other input link
    "a9": 25.0,  # DG
}
"""The example mechanism (degrees). Input FG has eight real configurations at the whole degrees
θ6 = 168°…186° and 263°…309°; input AB has four, two or none."""
EXAMPLE_INPUT = 280.0
"""θ6 (degrees) of the table of eight configurations: where their smallest separation peaks."""
MIRROR_INPUT = 110.0
"""θ1 (degrees) at which both the coupler and its mirror image have four configurations."""


def example(input: str = "FG", *, mirror: bool = False) -> SphericalStephenson3:
    """:data:`EXAMPLE` as a :class:`SphericalStephenson3` (σ → −σ with ``mirror``).

    >>> example().input, float(np.degrees(example(mirror=True).sigma))
    ('FG', -70.0)
    """
    deg = dict(EXAMPLE)
    if mirror:
        deg["sigma"] = -deg["sigma"]
    return SphericalStephenson3(**{k: np.radians(v) for k, v in deg.items()}, input=input)


def _pair(
    mechanism: SphericalStephenson3 | None,
) -> tuple[SphericalStephenson3, SphericalStephenson3]:
    """The mechanism driven at AB (default :data:`EXAMPLE`) and its mirror coupler (σ → −σ)."""
    m = example("AB") if mechanism is None else replace(mechanism, input="AB")
    return m, replace(m, sigma=-np.asarray(m.sigma))


def _deg(x: Any) -> Array:
    return np.degrees(np.asarray(x, dtype=float))


def count_sweep(samples: int = 360) -> dict[str, Array]:
    """Configurations of :data:`EXAMPLE` over a whole turn of each input (degrees).

    Returns ``input`` (the input angle, degrees, the same grid for θ1 and θ6), ``ab`` and
    ``fg`` (how many configurations for input AB at θ1 and for input FG at θ6),
    ``ab_residual`` and ``fg_residual`` (the largest constraint error of any of them, NaN where
    there is none), ``ab_mirror`` (input AB with σ → −σ) and ``ab_either`` (the coupler or its
    mirror image: what paper 001's system (4) admits; their configurations are distinct
    unless σ is 0° or 180°).

    >>> s = count_sweep(36)
    >>> s["ab"].max(), s["fg"].max(), s["ab_either"].max()
    (np.int64(4), np.int64(8), np.int64(8))
    """
    theta = np.linspace(0.0, 360.0, samples, endpoint=False)
    rad = np.radians(theta)
    ab = solve_all(example("AB"), rad)
    fg = solve_all(example("FG"), rad)
    mirror = solve_all(example("AB", mirror=True), rad)

    def worst(r: Array) -> Array:
        return np.where(
            np.isfinite(r).any(axis=-1), np.nanmax(np.nan_to_num(r, nan=-1.0), -1), np.nan
        )

    return {
        "input": theta,
        "ab": ab.count,
        "ab_residual": worst(ab.residual),
        "fg": fg.count,
        "fg_residual": worst(fg.residual),
        "ab_mirror": mirror.count,
        "ab_either": ab.count + mirror.count,
    }


def configuration_table(theta6: float = EXAMPLE_INPUT) -> list[dict[str, float]]:
    """Every configuration of :data:`EXAMPLE` for input FG at ``theta6`` (degrees).

    One row per configuration: θ1 = ∠BAD, θ4 = ∠CDG, θ5 (at F, from F→G to F→E), θ6 (degrees,
    in (−180°, 180°]), the signs ``assembly`` = sign((B × D)·C) and ``assembly2`` =
    sign((E × G)·F), ``residual``, the largest error against every constraint, and
    ``plan_gap``, the largest chord between its joints and those that the AB-driven
    construction plan places at its θ1 on its signs (NaN where a sign is 0: a limit position).

    >>> rows = configuration_table()
    >>> len(rows), [round(r["theta1"], 3) for r in rows[:2]]
    (8, [-171.04, -168.477])
    """
    m = example("FG")
    every = solve_all(m, np.radians([theta6]))
    angles = {k: _deg(v[0]) for k, v in paper_angles(m, every).items()}
    rows = []
    for k in range(int(every.count[0])):
        row = {name: float(angles[name][k]) for name in ("theta1", "theta4", "theta5", "theta6")}
        row["assembly"] = float(every.assembly[0, k])
        row["assembly2"] = float(every.assembly2[0, k])
        row["residual"] = float(every.residual[0, k])
        row["plan_gap"] = float("nan")
        if every.assembly[0, k] != 0 and every.assembly2[0, k] != 0:
            plan = replace(
                m, input="AB", assembly=every.assembly[0, k], assembly2=every.assembly2[0, k]
            )
            again = solve(plan, np.radians([row["theta1"]]), order=0).positions
            row["plan_gap"] = float(
                max(np.abs(again[j][0] - every.positions[j][0, k]).max() for j in "BCEF")
            )
        rows.append(row)
    return rows


def _system4(m: SphericalStephenson3, b: Array, c: Array, e: Array) -> Array:
    """Largest error of paper 001's system (4): B·C, C·E and B·E, which fix only cos σ."""
    a3, a6, s = m.a3, m.a6, m.sigma
    be = np.cos(a3) * np.cos(a6) - np.sin(a3) * np.sin(a6) * np.cos(s)
    return np.maximum.reduce(
        [
            np.abs(sphere.dot(b, c) - np.cos(a3)),
            np.abs(sphere.dot(c, e) - np.cos(a6)),
            np.abs(sphere.dot(b, e) - be),
        ]
    )


def mirror_check(
    theta1: float = MIRROR_INPUT, mechanism: SphericalStephenson3 | None = None
) -> dict[str, Any]:
    """Input AB of ``mechanism`` (default :data:`EXAMPLE`) and of its mirror coupler (σ → −σ)
    at ``theta1`` (degrees).

    Returns the counts of each (``coupler``, ``mirror``), the number of distinct configurations
    that paper 001's system (4) admits (``either``: all of both), the largest error of every one
    of them against system (4) (``system4``), the smallest chord by which a mirror
    configuration's E misses the place that the mechanism's own coupler gives it
    (``mirror_off``: none of them is a configuration of the mechanism) and the largest
    constraint error of any configuration against its own mechanism (``residual``).

    >>> r = mirror_check()
    >>> r["coupler"], r["mirror"], r["either"], r["system4"] < 1e-14, r["mirror_off"] > 0.1
    (4, 4, 8, True, True)
    """
    rad = np.radians([theta1])
    m, mm = _pair(mechanism)
    own = solve_all(m, rad)
    mir = solve_all(mm, rad)
    n_own, n_mir = int(own.count[0]), int(mir.count[0])
    pos = {
        k: np.concatenate((own.positions[k][0, :n_own], mir.positions[k][0, :n_mir]))
        for k in "BCEF"
    }
    joints = np.concatenate([pos[k] for k in "BCEF"], axis=-1)
    gap = np.abs(joints[:, None] - joints[None]).max(-1)
    distinct = int(len(joints) - np.triu(gap < 1e-7, k=1).any(axis=0).sum())
    off = sphere.frame_error(
        pos["C"][n_own:], pos["B"][n_own:], pos["E"][n_own:], m.a6, np.pi - m.sigma
    )
    residual = np.concatenate((own.residual[0, :n_own], mir.residual[0, :n_mir]))
    return {
        "theta1": theta1,
        "coupler": n_own,
        "mirror": n_mir,
        "either": distinct,
        "system4": float(_system4(m, pos["B"], pos["C"], pos["E"]).max(initial=0.0)),
        "mirror_off": float(off.min(initial=np.inf)),
        "residual": float(residual.max(initial=0.0)),
    }


def _input_b(m: SphericalStephenson3, theta1: float) -> Array:
    """Eq. 5's B = (sin a2 sin θ1, sin a2 cos θ1, cos a2), θ1 in radians."""
    s2, c2 = np.sin(m.a2), np.cos(m.a2)
    return np.array([s2 * np.sin(theta1), s2 * np.cos(theta1), c2])


def _eq5_c(m: SphericalStephenson3, theta4: Any) -> Array:
    """Eq. 5's C = (sin a4 sin θ4, sin a1 cos a4 + cos a1 sin a4 cos θ4, cos a1 cos a4 −
    sin a1 sin a4 cos θ4)."""
    t = np.asarray(theta4, dtype=float)
    s1, c1, s4, c4 = np.sin(m.a1), np.cos(m.a1), np.sin(m.a4), np.cos(m.a4)
    return np.stack(
        (s4 * np.sin(t), s1 * c4 + c1 * s4 * np.cos(t), c1 * c4 - s1 * s4 * np.cos(t)), -1
    )


def _eq17(m: SphericalStephenson3, theta1: float) -> Array:
    """Both roots x4 of the four-bar's quadratic (eq. 14's first line, with f as eq. 13 has it),
    "+" then "−" as in eq. 17.

    B·C − cos a3 = f1 cos θ4 + f2 sin θ4 + f3 with eq. 5's B and C; with x4 = tan(θ4/2),
    (f3 − f1) x4² + 2 f2 x4 + (f1 + f3) = 0. NaN where the four-bar does not close.
    """
    b = _input_b(m, theta1)
    s1, c1, s4, c4 = np.sin(m.a1), np.cos(m.a1), np.sin(m.a4), np.cos(m.a4)
    f1 = s4 * (b[1] * c1 - b[2] * s1)
    f2 = b[0] * s4
    f3 = c4 * (b[1] * s1 + b[2] * c1) - np.cos(m.a3)
    a11, a12, a13 = f3 - f1, 2.0 * f2, f1 + f3
    disc = a12 * a12 - 4.0 * a11 * a13
    root = np.sqrt(disc) if disc >= 0 else np.nan
    # Eq. 17's two roots, the one that would cancel taken as a13/(a11·x) (Vieta), so that a
    # root near x4 = ∞ (θ4 near 180°) keeps its digits.
    q = -0.5 * (a12 + np.copysign(root, a12))
    with np.errstate(divide="ignore", invalid="ignore"):
        big, small = q / a11, a13 / q
    plus_first = a12 < 0  # then −a12 + root is the cancellation-free one
    return np.array([big, small] if plus_first else [small, big])


def eq18_check(
    theta1: float = MIRROR_INPUT, mechanism: SphericalStephenson3 | None = None
) -> list[dict[str, float]]:
    """Eq. 18 with and without its lost factor 2, for ``mechanism`` (default :data:`EXAMPLE`)
    at ``theta1`` (degrees).

    For each sign of eq. 17: θ4 = 2·arctan(x4) and the printed arctan(x4) (degrees), the error
    of eq. 5's C at each against the link BC (|arc BC − a3|, degrees), the chord from that C to
    the nearest C of the configurations that :func:`solve_all` finds (NaN if none),
    and the circuit's sign ``assembly`` = sign((B × D)·C). NaN throughout where the four-bar
    does not close at ``theta1``.

    >>> rows = eq18_check()
    >>> [r["bc_error_2x"] < 1e-12 for r in rows], [r["bc_error_printed"] > 1 for r in rows]
    ([True, True], [True, True])
    """
    m, _ = _pair(mechanism)
    t1 = np.radians(theta1)
    b = _input_b(m, t1)
    every = solve_all(m, np.array([t1]))
    found = every.positions["C"][0, : every.count[0]]
    rows = []
    for sign, x4 in zip((1.0, -1.0), _eq17(m, t1), strict=True):
        row = {"sign": sign, "x4": float(x4)}
        for key, theta4 in (("2x", 2.0 * np.arctan(x4)), ("printed", np.arctan(x4))):
            c = _eq5_c(m, theta4)
            row[f"theta4_{key}"] = float(np.degrees(theta4))
            row[f"bc_error_{key}"] = float(np.degrees(abs(sphere.arc(b, c) - m.a3)))
            gap = sphere.norm(found - c)
            row[f"chord_{key}"] = float(gap.min()) if gap.size else float("nan")
        c = _eq5_c(m, 2.0 * np.arctan(x4))
        row["assembly"] = float(np.sign(sphere.dot(sphere.cross(b, m.params()["D"]), c)))
        rows.append(row)
    return rows


def _e_forms(m: SphericalStephenson3, b: Array, c: Array) -> tuple[Array, Array]:
    """Eq. 13's second and third lines as bilinear forms, rows θ5 and columns θ6.

    F = cos a8 G + sin a8 (cos θ6 t + sin θ6 G × t) (t towards the great circle G→away from
    D) and E = point_at(F, G, a7, θ5): with the unit tangent (G − cos a8 F)/sin a8 and the
    normal F × G / sin a8 at F, both linear in F, E is bilinear in (1, cos θ5, sin θ5) and
    (1, cos θ6, sin θ6). The lines are C·E − cos a6 and B·E − (cos a3 cos a6 − sin a3 sin a6
    cos σ): system (4), which fixes only cos σ.
    """
    p = m.params()
    g = p["G"]
    frame = circle_frame(g, p["away"], 1.0)
    f = np.stack((np.cos(m.a8) * frame[0], np.sin(m.a8) * frame[1], np.sin(m.a8) * frame[2]))
    t = (np.where(np.arange(3)[:, None] == 0, g, 0.0) - np.cos(m.a8) * f) / np.sin(m.a8)
    n = sphere.cross(f, g) / np.sin(m.a8)
    e = np.stack((np.cos(m.a7) * f, np.sin(m.a7) * t, np.sin(m.a7) * n), axis=0)  # [θ5, θ6]
    be = np.cos(m.a3) * np.cos(m.a6) - np.sin(m.a3) * np.sin(m.a6) * np.cos(m.sigma)
    m_g = e @ c
    m_g[0, 0] -= np.cos(m.a6)
    m_k = e @ b
    m_k[0, 0] -= be
    return m_g, m_k


def eq20_check(
    theta1: float = MIRROR_INPUT, mechanism: SphericalStephenson3 | None = None
) -> list[dict[str, Any]]:
    """Paper 001's eq. 20 for input AB of ``mechanism`` (default :data:`EXAMPLE`) at ``theta1``
    (degrees).

    For each circuit of the four-bar (each root of eq. 17, with eq. 18's factor 2), eq. 13's
    second and third lines give, after eliminating x6 = tan(θ6/2) (eq. 19), a polynomial of
    degree 8 in x5 = tan(θ5/2) (eq. 20). Its real roots are compared with θ5 of the
    configurations on that circuit of the coupler (σ) and of its mirror image (−σ).

    Returns per circuit: ``degree`` (of the polynomial), ``real`` (its real roots, θ5 in
    degrees), ``coupler`` and ``mirror`` (the θ5 of those configurations, degrees) and ``gap``
    (the largest distance, degrees, from a real root to the nearest configuration and back).

    >>> rows = eq20_check()
    >>> [(len(r["real"]), len(r["coupler"]), len(r["mirror"])) for r in rows]
    [(4, 2, 2), (4, 2, 2)]
    >>> max(r["gap"] for r in rows) < 1e-8
    True
    """
    m, mm = _pair(mechanism)
    t1 = np.radians(theta1)
    b = _input_b(m, t1)
    rad = np.array([t1])
    sets = []
    for mech in (m, mm):
        every = solve_all(mech, rad)
        theta5 = paper_angles(mech, every)["theta5"][0, : every.count[0]]
        sets.append((every.positions["C"][0, : every.count[0]], theta5))
    rows = []
    for x4 in _eq17(m, t1):
        if not np.isfinite(x4):
            continue
        c = _eq5_c(m, 2.0 * np.arctan(x4))
        m_g, m_k = _e_forms(m, b, c)
        coef = bilinear_resultant(m_g, m_k)
        roots = np.roots(coef[::-1])
        real = roots[np.abs(roots.imag) < 1e-7 * (1.0 + np.abs(roots))].real
        theta5_roots = np.sort(2.0 * np.arctan(real))
        on = [t5[sphere.norm(cs - c) < 1e-9] for cs, t5 in sets]
        configs = np.concatenate(on)

        def far(a: Array, b: Array) -> float:
            if not a.size:
                return 0.0
            if not b.size:
                return np.inf
            diff = np.abs(np.angle(np.exp(1j * (a[:, None] - b[None, :]))))
            return float(np.degrees(diff.min(axis=1).max()))

        rows.append(
            {
                "x4": float(x4),
                "degree": int(np.max(np.flatnonzero(coef != 0), initial=-1)),
                "real": np.degrees(theta5_roots),
                "coupler": np.sort(np.degrees(on[0])),
                "mirror": np.sort(np.degrees(on[1])),
                "gap": max(far(theta5_roots, configs), far(configs, theta5_roots)),
            }
        )
    return rows


@dataclass(frozen=True)
class Misprint:
    """One printed equation of paper 001, checked numerically.

    ``where`` names the equation, ``printed`` and ``corrected`` say what is printed and what
    holds, ``check`` what was computed (with the numbers), and ``confirmed`` whether the
    computation bears out the note (the printed form fails and the corrected one holds; for
    equations found right, that they hold).
    """

    where: str
    printed: str
    corrected: str
    check: str
    confirmed: bool


def _rx(angle: float) -> Array:
    """Eq. 6's R(X, α): counter-clockwise about +x."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rz(angle: float) -> Array:
    """Eq. 6's R(Z, θ): counter-clockwise about +z (the axis OA)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _printed_f(m: SphericalStephenson3, theta6: Array) -> Array:
    """Eqs. 10 and 12's F = (a9 sin θ6, a10 cos θ6, a11) with the printed a9, a10, a11."""
    s1, c1 = np.sin(m.a1), np.cos(m.a1)
    s8, c8, s9, c9 = np.sin(m.a8), np.cos(m.a8), np.sin(m.a9), np.cos(m.a9)
    k9 = c8 * c9 * s1 + c8 * s9 * s1 - s8 * s9 * s1 + s8 * c9 * s1
    k10 = s8 * s9 * s1 - s8 * c9 * s1 - c8 * s9 * s1 - c8 * c9 * s1
    k11 = c8 * c9 * c1 - c8 * s9 * s1 - s8 * s9 * c1 - s8 * c9 * s1
    return np.stack(np.broadcast_arrays(k9 * np.sin(theta6), k10 * np.cos(theta6), k11), -1)


def _half_angle_checks(seed: int = 1) -> dict[str, float]:
    """Eqs. 14–16 against eq. 13 with random coefficients: the largest relative mismatch.

    Each line of eq. 13, times (1 + x4²) or (1 + x5²)(1 + x6²), must equal its quadratic of
    eq. 14 at every angle; the printed coefficients (with f and g as printed, or swapped back)
    and the corrected ones are evaluated at random angles and coefficients.
    """
    rng = np.random.default_rng(seed)
    n = 64
    f = rng.normal(size=(4, n))  # f[1..3]
    g = rng.normal(size=(9, n))  # g[1..8]
    k = rng.normal(size=(9, n))  # k[1..8]
    t4, t5, t6 = rng.uniform(-3.0, 3.0, (3, n))
    x4, x5, x6 = np.tan(t4 / 2), np.tan(t5 / 2), np.tan(t6 / 2)
    c4, s4, c5, s5, c6, s6 = np.cos(t4), np.sin(t4), np.cos(t5), np.sin(t5), np.cos(t6), np.sin(t6)
    w4, w56 = 1 + x4**2, (1 + x5**2) * (1 + x6**2)

    line1 = w4 * (f[1] * c4 + f[2] * s4 + f[3])
    g_line = w56 * (
        g[1] * s5 * s6 + g[2] * c5 * c6 + g[3] * s5 * c6 + g[4] * c5 * s6
        + g[5] * c6 + g[6] * c5 + g[7] * s5 + g[8]
    )  # fmt: skip
    k_line = w56 * (
        k[1] * s5 * s6 + k[2] * c5 * c6 + k[3] * s5 * c6 + k[4] * c5 * s6
        - k[5] * c5 + k[6] * s5 + k[7] * c6 + k[8]
    )  # fmt: skip

    def quad1(c: Array) -> Array:  # eq. 15's left column with the letter c
        return (c[3] - c[1]) * x4**2 + 2 * c[2] * x4 + (c[1] + c[3])

    def quad_k(const: Array) -> Array:  # eq. 15's right column, constant term of a23 given
        a21 = x5**2 * (k[2] + k[5] - k[7] + k[8]) + x5 * (2 * k[6] - 2 * k[3])
        a21 = a21 + (k[8] - k[2] - k[5] - k[7])
        a22 = -2 * k[4] * x5**2 + 4 * k[1] * x5 + 2 * k[4]
        a23 = x5**2 * (k[5] + k[7] + k[8] - k[2]) + x5 * (2 * k[3] + 2 * k[6]) + const
        return a21 * x6**2 + a22 * x6 + a23

    def quad_g(const: Array) -> Array:  # eq. 16 with f read as g, constant term of a33 given
        a31 = x5**2 * (g[2] - g[5] - g[6] + g[8]) + x5 * (2 * g[7] - 2 * g[3])
        a31 = a31 + (g[8] + g[6] - g[5] - g[2])
        a32 = -2 * g[4] * x5**2 + 4 * g[1] * x5 + 2 * g[4]
        a33 = x5**2 * (g[5] + g[8] - g[2] - g[6]) + x5 * (2 * g[3] + 2 * g[7]) + const
        return a31 * x6**2 + a32 * x6 + a33

    def rel(a: Array, b: Array) -> float:
        return float(np.max(np.abs(a - b) / (np.abs(a) + np.abs(b) + 1e-300)))

    # Eq. 15's a11..a13 are printed with g: read with g (g1..g3, the wrong line's letters).
    return {
        "eq15_printed": rel(line1, quad1(g)),
        "eq15_with_f": rel(line1, quad1(f)),
        "a23_printed": rel(k_line, quad_k(k[2] - k[5] + k[7] - k[8])),
        "a23_corrected": rel(k_line, quad_k(k[2] - k[5] + k[7] + k[8])),
        # Eq. 16 with f read as g, its constant term as printed: f2 + f5 + f7 + f8.
        "a33_printed": rel(g_line, quad_g(g[2] + g[5] + g[7] + g[8])),
        "a33_corrected": rel(g_line, quad_g(g[2] + g[5] + g[6] + g[8])),
    }


def _eq19_21_check(seed: int = 2) -> dict[str, float]:
    """Eqs. 19 and 21 on random quadratics that share a root: the resultant vanishes (relative
    to its terms) and eq. 21 returns the shared root."""
    rng = np.random.default_rng(seed)
    n = 64
    root = rng.normal(size=n)
    p, q = rng.normal(size=(2, 2, n))
    # a21 y² + a22 y + a23 = (y − root)(p0 y + p1), likewise with q for a31..a33.
    a21, a22, a23 = p[0], p[1] - root * p[0], -root * p[1]
    a31, a32, a33 = q[0], q[1] - root * q[0], -root * q[1]
    terms = np.array(
        [
            a21**2 * a33**2,
            -a21 * a22 * a32 * a33,
            -2 * a21 * a23 * a31 * a33,
            a21 * a23 * a32**2,
            a22**2 * a31 * a33,
            -a22 * a23 * a31 * a32,
            a23**2 * a31**2,
        ]
    )
    eq19 = np.abs(terms.sum(0)) / np.abs(terms).sum(0)
    eq21 = (a21 * a33 - a31 * a23) / (a31 * a22 - a21 * a32)
    return {"eq19": float(eq19.max()), "eq21": float(np.max(np.abs(eq21 - root)))}


def misprints() -> list[Misprint]:
    """Every misprint of paper 001 listed in SEED-NOTES.md, checked on :data:`EXAMPLE`.

    >>> found = misprints()
    >>> len(found), all(m.confirmed for m in found)
    (9, True)
    """
    m = example("AB")
    p = m.params()
    d, g = p["D"], p["G"]
    far = m.a1 + m.a9
    out = []

    g8 = np.array([0.0, -np.sin(far), np.cos(far)])
    arc_printed, arc_ours = (float(np.degrees(sphere.arc(d, x))) for x in (g8, g))
    out.append(
        Misprint(
            "eq. 8 (G)",
            "G = R(X, a1 + a9)·(0, 0, 1) = (0, −sin(a1 + a9), cos(a1 + a9)): beyond A, not D",
            "G = (0, sin(a1 + a9), cos(a1 + a9)): at arc a1 + a9 from A, beyond D",
            f"arc DG = {arc_printed:.6f}° with the printed G, {arc_ours:.12f}° with the "
            f"corrected one; DG should be a9 = {np.degrees(m.a9):g}°",
            abs(arc_printed - np.degrees(m.a9)) > 1e-6 and abs(arc_ours - np.degrees(m.a9)) < 1e-9,
        )
    )

    theta6 = np.radians(np.arange(0.0, 360.0, 1.0))
    f_printed = _printed_f(m, theta6)
    size = sphere.norm(f_printed)
    out.append(
        Misprint(
            "eqs. 10–12 (F and a9–a11)",
            "F = (a9 sin θ6, a10 cos θ6, a11) with the printed a9, a10, a11",
            "F = cos a8·G + sin a8 (cos θ6·t + sin θ6·G × t): a unit vector at arc a8 from G",
            (
                f"‖F‖ of the printed F is {size.min():.6f} at every θ6 (the printed a10 is −a9)"
                if np.ptp(size) < 1e-12
                else f"‖F‖ of the printed F ranges over [{size.min():.6f}, {size.max():.6f}]"
            )
            + "; a joint on the unit sphere has ‖F‖ = 1",
            bool(np.abs(size - 1.0).max() > 1e-6),
        )
    )

    start = _rx(m.a8) @ g  # G turned by a8 about X: at arc a8 from G, on the great circle AG
    about_z = np.einsum("nij,j->ni", np.stack([_rz(t) for t in theta6]), start)
    about_g = sphere.rotate(start, g, theta6)
    err_z = np.degrees(np.abs(sphere.arc(about_z, g) - m.a8)).max()
    err_g = np.degrees(np.abs(sphere.arc(about_g, g) - m.a8)).max()
    out.append(
        Misprint(
            "eq. 9 (rotation axis)",
            "F = R(Z, θ6)·R(X, a8)·G: θ6 turns about OA (the Z axis)",
            "F turns by θ6 about OG (and E by θ5 about OF)",
            f"with the corrected G, arc FG misses a8 by up to {err_z:.4f}° over a turn of θ6 "
            f"about OA, by {err_g:.1e}° about OG",
            err_z > 1e-3 and err_g < 1e-9,
        )
    )

    half = _half_angle_checks()
    out.append(
        Misprint(
            "eqs. 15–16 (f and g)",
            "a11 = g3 − g1, a12 = 2g2, a13 = g1 + g3; a31..a33 in f1..f8",
            "a11 = f3 − f1, a12 = 2f2, a13 = f1 + f3 (eq. 13's f-line); a31..a33 in g1..g8",
            "with random coefficients and angles, (1 + x4²)·(f1 c4 + f2 s4 + f3) minus the "
            f"quadratic: relative {half['eq15_printed']:.2f} with the printed letters, "
            f"{half['eq15_with_f']:.1e} with f",
            half["eq15_printed"] > 1e-3 and half["eq15_with_f"] < 1e-12,
        )
    )
    out.append(
        Misprint(
            "eq. 15 (a23)",
            "constant term of a23: k2 − k5 + k7 − k8",
            "k2 − k5 + k7 + k8",
            "(1 + x5²)(1 + x6²)·(eq. 13's k-line) minus a21 x6² + a22 x6 + a23: relative "
            f"{half['a23_printed']:.2f} as printed, {half['a23_corrected']:.1e} corrected",
            half["a23_printed"] > 1e-3 and half["a23_corrected"] < 1e-12,
        )
    )
    out.append(
        Misprint(
            "eq. 16 (a33)",
            "constant term of a33: f2 + f5 + f7 + f8 (g2 + g5 + g7 + g8 once f is read as g)",
            "g2 + g5 + g6 + g8",
            "(1 + x5²)(1 + x6²)·(eq. 13's g-line) minus a31 x6² + a32 x6 + a33: relative "
            f"{half['a33_printed']:.2f} as printed, {half['a33_corrected']:.1e} corrected",
            half["a33_printed"] > 1e-3 and half["a33_corrected"] < 1e-12,
        )
    )

    rows = eq18_check()
    worst_2x = max(r["chord_2x"] for r in rows)
    best_1x = min(r["chord_printed"] for r in rows)
    out.append(
        Misprint(
            "eq. 18 (factor 2)",
            "θ4 = arctan((−a12 ± √(a12² − 4 a11 a13)) / (2 a11))",
            "θ4 = 2·arctan(...), since x4 = tan(θ4/2)",
            f"at θ1 = {MIRROR_INPUT:g}°, eq. 5's C at θ4 = 2·arctan(x4) is the solved C to "
            f"{worst_2x:.1e} (chord) on both circuits; at arctan(x4) it is {best_1x:.3f} away "
            f"and misses the link BC by up to {max(r['bc_error_printed'] for r in rows):.2f}°",
            worst_2x < 1e-12 and best_1x > 1e-3,
        )
    )

    right = _eq19_21_check()
    out.append(
        Misprint(
            "eq. 19 (right)",
            "Sylvester resultant of the two quadratics in x6",
            "as printed",
            "on random quadratics that share a root it vanishes to "
            f"{right['eq19']:.1e} of the sum of its terms' magnitudes",
            right["eq19"] < 1e-12,
        )
    )
    out.append(
        Misprint(
            "eq. 21 (right)",
            "x6 = (a21 a33 − a31 a23)/(a31 a22 − a21 a32) (inside θ6 = 2·arctan)",
            "as printed",
            f"on the same quadratics it returns the shared root to {right['eq21']:.1e}",
            right["eq21"] < 1e-9,
        )
    )
    return out


# ----------------------------------------------------------------------------------------------
# Figures
# ----------------------------------------------------------------------------------------------

_LINKS = (("A", "B"), ("B", "C"), ("C", "D"), ("C", "E"), ("B", "E"), ("E", "F"), ("F", "G"))
_GROUND = (("A", "D"), ("D", "G"))


def _draw_configuration(ax: Any, view: Any, pos: dict[str, Array], title: str) -> None:
    from matplotlib.patches import Circle

    from linkwright.plot.sphere import great_arc, stroke

    ax.add_patch(Circle((0.0, 0.0), 1.0, fill=False, color="0.6", lw=0.8))
    for a, b in _GROUND:
        stroke(ax, view, great_arc(pos[a], pos[b]), color="0.45", lw=1.0, ls="--")
    body = np.concatenate([great_arc(pos[a], pos[b]) for a, b in ("BC", "CE", "EB")])
    ax.fill(*view.xy(body).T, color="#f0b27a", alpha=0.45, lw=0)
    for a, b in _LINKS:
        stroke(ax, view, great_arc(pos[a], pos[b]), color="#1f4e79", lw=1.6)
    for name, p in pos.items():
        x, y = view.xy(p)
        ground = name in "ADG"
        ax.plot(
            x,
            y,
            marker="s" if ground else "o",
            ms=5,
            mfc="k" if ground else "w",
            mec="k",
            alpha=1.0 if view.depth(p) >= 0 else 0.5,
        )
        ax.annotate(name, (x, y), xytext=(3, 3), textcoords="offset points", fontsize=7)
    ax.set_title(title, fontsize=7.5)
    ax.set_xlim(-1.08, 1.08)
    ax.set_ylim(-1.08, 1.08)
    ax.set_aspect("equal")
    ax.set_axis_off()


def _counts_figure(sweep: dict[str, Array]) -> Any:
    from linkwright.plot import new_figure

    fig = new_figure((8.0, 5.6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    theta = np.append(sweep["input"], 360.0)

    def steps(ax: Any, counts: Array, **style: Any) -> None:
        ax.step(theta, np.append(counts, counts[0]), where="post", **style)

    steps(
        top,
        sweep["ab_either"],
        color="#c0392b",
        ls="--",
        lw=1.2,
        label="coupler or its mirror image (σ → −σ): paper 001's system (4)",
    )
    steps(top, sweep["ab"], color="#1f4e79", lw=1.8, label="the mechanism (rigid coupler)")
    top.set_ylabel("real configurations")
    top.set_title("Input AB (θ1): four-bar × dyad, at most 4; with the mirror coupler 4 + 4")
    top.legend(loc="lower center", fontsize=8)
    steps(bottom, sweep["fg"], color="#1f4e79", lw=1.8, label="the mechanism")
    bottom.axvline(EXAMPLE_INPUT, color="0.5", lw=0.8, ls=":")
    bottom.set_title("Input FG (θ6): a spherical triad, at most 8 (degree-8 polynomial)")
    bottom.set_xlabel("input angle (degrees)")
    bottom.set_ylabel("real configurations")
    for ax in (top, bottom):
        ax.set_ylim(-0.3, 8.6)
        ax.set_yticks(range(0, 9))
        ax.set_xlim(0, 360)
        ax.set_xticks(range(0, 361, 45))
        ax.grid(alpha=0.3)
    fig.suptitle(_mechanism_text(), fontsize=8)
    return fig


def _configurations_figure(theta6: float) -> Any:
    from linkwright.plot import new_figure
    from linkwright.plot.sphere import SphereView

    m = example("FG")
    every = solve_all(m, np.radians([theta6]))
    angles = paper_angles(m, every)
    count = int(every.count[0])
    pos = [{k: v[0, i] for k, v in every.positions.items()} for i in range(count)]
    seen = np.concatenate([np.stack(list(p.values())) for p in pos]) if pos else np.eye(3)
    up = every.positions["A"][0, 0] if count else np.eye(3)[2]
    view = SphereView(sphere.unit(seen.sum(axis=0)), up)
    fig = new_figure((10.0, 5.6))
    axes = fig.subplots(2, 4).ravel()
    for i, ax in enumerate(axes):
        if i >= count:
            ax.set_axis_off()
            continue
        sign = {1.0: "+", -1.0: "−", 0.0: "0"}
        title = (
            f"#{i + 1}: θ1 = {np.degrees(angles['theta1'][0, i]):.2f}°, "
            f"θ4 = {np.degrees(angles['theta4'][0, i]):.2f}°\n"
            f"θ5 = {np.degrees(angles['theta5'][0, i]):.2f}°, signs "
            f"({sign[float(every.assembly[0, i])]}, {sign[float(every.assembly2[0, i])]})"
        )
        _draw_configuration(ax, view, pos[i], title)
    fig.suptitle(
        f"The {count} configurations for input FG at θ6 = {theta6:g}° (orthographic view; "
        "dashed and faded: behind the sphere)\n" + _mechanism_text(),
        fontsize=8.5,
    )
    return fig


def _mechanism_text() -> str:
    return "AD, AB, BC, CD, CE, σ, EF, FG, DG = " + ", ".join(f"{v:g}°" for v in EXAMPLE.values())


# ----------------------------------------------------------------------------------------------
# The page
# ----------------------------------------------------------------------------------------------


def _write_csv(path: Path, header: list[str], rows: list[list[Any]]) -> Path:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def _num(x: float, digits: int = 4) -> str:
    return "" if not np.isfinite(x) else f"{x + 0.0:.{digits}f}"


def _listed(counts: Array) -> str:
    values = [str(v) for v in np.unique(counts)]
    return ", ".join(values[:-1]) + " and " + values[-1] if len(values) > 1 else values[0]


def _runs(degrees: Array) -> str:
    """Whole degrees as runs: "168°–186°, 263°–309°"."""
    if not degrees.size:
        return "none"
    cut = np.flatnonzero(np.diff(degrees) > 1.5) + 1
    parts = np.split(degrees, cut)
    return ", ".join(f"{p[0]:g}°–{p[-1]:g}°" if len(p) > 1 else f"{p[0]:g}°" for p in parts)


def _histogram(counts: Array, top: int) -> str:
    return ", ".join(
        f"{k}: {int((counts == k).sum())}" for k in range(top + 1) if (counts == k).any()
    )


def reproduce(out: str | Path) -> list[Path]:
    """Write paper 001's configuration analysis for :data:`EXAMPLE` into the folder ``out``.

    Files: ``paper001.md`` (the page), ``paper001-counts.csv`` (configurations and largest
    residual at every degree of each input), ``paper001-configurations.csv`` (the eight at
    :data:`EXAMPLE_INPUT`), ``paper001-circuits.csv`` (issue 21's example driven at FG: where
    its configurations join, :mod:`linkwright.papers.p001_circuits`), and the figures
    ``paper001-counts``, ``paper001-configurations`` and ``paper001-circuits`` as PNG and SVG.
    Returns the paths written.
    """
    from linkwright.plot import save_figure

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sweep = count_sweep(360)
    table = configuration_table(EXAMPLE_INPUT)
    mirror = mirror_check(MIRROR_INPUT)
    eq20 = eq20_check(MIRROR_INPUT)
    errata = misprints()
    written: list[Path] = []

    written.append(
        _write_csv(
            out / "paper001-counts.csv",
            [
                "input_deg",
                "ab_count",
                "ab_max_residual",
                "ab_mirror_count",
                "ab_either_count",
                "fg_count",
                "fg_max_residual",
            ],
            [
                [
                    f"{sweep['input'][i]:g}",
                    int(sweep["ab"][i]),
                    f"{sweep['ab_residual'][i]:.3e}"
                    if np.isfinite(sweep["ab_residual"][i])
                    else "",
                    int(sweep["ab_mirror"][i]),
                    int(sweep["ab_either"][i]),
                    int(sweep["fg"][i]),
                    f"{sweep['fg_residual'][i]:.3e}"
                    if np.isfinite(sweep["fg_residual"][i])
                    else "",
                ]
                for i in range(len(sweep["input"]))
            ],
        )
    )
    written.append(
        _write_csv(
            out / "paper001-configurations.csv",
            [
                "configuration",
                "theta1_deg",
                "theta4_deg",
                "theta5_deg",
                "theta6_deg",
                "assembly",
                "assembly2",
                "max_residual",
            ],
            [
                [
                    i + 1,
                    *(f"{r[k]:.9f}" for k in ("theta1", "theta4", "theta5", "theta6")),
                    int(r["assembly"]),
                    int(r["assembly2"]),
                    f"{r['residual']:.3e}",
                ]
                for i, r in enumerate(table)
            ],
        )
    )
    figures = {
        "paper001-counts": _counts_figure(sweep),
        "paper001-configurations": _configurations_figure(EXAMPLE_INPUT),
    }
    for stem, fig in figures.items():
        for suffix in (".png", ".svg"):
            written.append(save_figure(fig, out / f"{stem}{suffix}"))

    ab_res = np.nanmax(sweep["ab_residual"])
    fg_res = np.nanmax(sweep["fg_residual"])
    eight = sweep["input"][sweep["fg"] == 8]
    lines = [
        "# Paper 001: every real configuration of the spherical Stephenson III",
        "",
        "Zong, Lu, An, Zhang, *A simple method for position analysis of Stephenson-III "
        "spherical six bar mechanism*. Fixed joints A, D, G; input link AB; ternary coupler "
        "BCE (BC = a3, CE = a6, angle BCE = 180° − σ: eq. 3's cos BE = cos a3 cos a6 − "
        "sin a3 sin a6 cos σ); CD; EF; FG. A = (0, 0, 1), "
        "D = (0, sin a1, cos a1), G at arc a1 + a9 from A beyond D; θ1 = ∠BAD with eq. 5's "
        "B = (sin a2 sin θ1, sin a2 cos θ1, cos a2); θ4 = ∠CDG as in eq. 5's C; θ6 the angle "
        "of F about +OG from the great circle G→(away from D) (the supplement of ∠FGD, with "
        "sign); θ5 the joint angle at F, from the great circle F→G to F→E, right-handed "
        "about +OF.",
        "",
        "## The example mechanism",
        "",
        "The paper prints no numeric example. linkwright uses (degrees):",
        "",
        "| a1 = AD | a2 = AB | a3 = BC | a4 = CD | a6 = CE | σ | a7 = EF | a8 = FG | a9 = DG |",
        "|---|---|---|---|---|---|---|---|---|",
        "| " + " | ".join(f"{v:g}" for v in EXAMPLE.values()) + " |",
        "",
        "found by a search over mechanisms with whole-degree arcs for one whose input FG has "
        f"eight real configurations at some θ6: it has eight at {len(eight)} of the 360 whole "
        f"degrees of θ6 ({_runs(eight)}); the counts {_listed(sweep['fg'])} occur for input "
        f"FG and {_listed(sweep['ab'])} for input AB.",
        "",
        "## Configuration counts",
        "",
        "At every whole degree of each input, `solve_all` reports each real "
        "configuration and its error against every constraint, recomputed from the positions "
        "(link arcs, E's place on the coupler, unit norms, the input):",
        "",
        "| input | at most | inputs (of 360) with each count | largest residual |",
        "|---|---|---|---|",
        f"| AB (θ1) | 4 | {_histogram(sweep['ab'], 4)} | {ab_res:.1e} |",
        f"| FG (θ6) | 8 | {_histogram(sweep['fg'], 8)} | {fg_res:.1e} |",
        f"| AB, coupler or mirror (system (4)) | 8 | {_histogram(sweep['ab_either'], 8)} | |",
        "",
        "Input AB: the four-bar ABCD closes on two branches, E follows rigidly, the dyad EFG "
        "closes on two branches: at most 2 × 2 = 4. Input FG: F is placed, and B, C, E form a "
        "spherical triad; eliminating θ4 from its two bilinear equations leaves a polynomial of "
        "degree 8 in tan(θ1/2) (the counterpart of eqs. 19–20), so at most 8. Figure: "
        "paper001-counts.png / .svg; numbers: paper001-counts.csv.",
        "",
        f"## The eight configurations at θ6 = {EXAMPLE_INPUT:g}°",
        "",
        f"(θ6 = {EXAMPLE_INPUT:g}° is {EXAMPLE_INPUT - 360:g}° in (−180°, 180°], as tabulated.) "
        "assembly = sign((B × D)·C) (the four-bar's branch), assembly2 = sign((E × G)·F) (the "
        "dyad's); residual: the largest error against every constraint. Each is also the "
        "configuration that the AB-driven construction plan builds at its θ1 on its signs "
        f"(largest chord between their joints: {max(r['plan_gap'] for r in table):.1e}).",
        "",
        "| # | θ1 (°) | θ4 (°) | θ5 (°) | θ6 (°) | assembly | assembly2 | residual |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(table):
        lines.append(
            f"| {i + 1} | {_num(r['theta1'])} | {_num(r['theta4'])} | {_num(r['theta5'])} | "
            f"{_num(r['theta6'])} | {int(r['assembly']):+d} | {int(r['assembly2']):+d} | "
            f"{r['residual']:.1e} |"
        )
    circuit_lines, circuit_files = p001_circuits.write(out)
    written += circuit_files
    lines += [
        "",
        "Figure: paper001-configurations.png / .svg; numbers: paper001-configurations.csv.",
        "",
        *circuit_lines,
        "## Why the paper counts 8 for input AB",
        "",
        "System (4) fixes the coupler by B·C = cos a3, C·E = cos a6 and "
        "B·E = cos a3 cos a6 − sin a3 sin a6 cos σ, i.e. by cos σ only: E may lie on either "
        "side of the great circle CB, which is the mirror-image coupler (σ → −σ), another "
        f"mechanism. At θ1 = {mirror['theta1']:g}°:",
        "",
        f"- the mechanism has {mirror['coupler']} configurations and its mirror image "
        f"{mirror['mirror']}: {mirror['either']} distinct solutions of system (4), each "
        f"satisfying it to {mirror['system4']:.1e};",
        f"- the mirror configurations' E misses the mechanism's coupler by at least "
        f"{mirror['mirror_off']:.3f} (chord): none of them is a configuration of the mechanism.",
        "",
        "Eq. 20 (eq. 13's second and third lines, x6 eliminated by eq. 19) on each circuit of "
        "the four-bar (each sign of eq. 17, θ4 = 2·arctan x4):",
        "",
        "| x4 | degree | real roots, θ5 (°) | coupler's θ5 (°) | mirror's θ5 (°) | "
        "largest gap (°) |",
        "|---|---|---|---|---|---|",
    ]
    for r in eq20:
        lines.append(
            f"| {r['x4']:.6f} | {r['degree']} | {', '.join(_num(x) for x in r['real'])} | "
            f"{', '.join(_num(x) for x in r['coupler'])} | "
            f"{', '.join(_num(x) for x in r['mirror'])} | {r['gap']:.1e} |"
        )
    lines += [
        "",
        "A real root of eq. 20 is a real configuration: two real quadratics in x6 that share "
        "a complex root share both (a degenerate case). On one circuit there are at most "
        "2 (E, for σ and −σ) × 2 (F) of them, so at most 4 of eq. 20's 8 roots are real, and "
        "the paper's 8 are 2 circuits × 4, half of them the mirror coupler's. One rigid "
        "coupler has at most 4 configurations for input AB; eight genuine configurations "
        "occur for input FG (above).",
        "",
        "## Misprints, checked numerically",
        "",
        "| where | printed | holds | check | confirmed |",
        "|---|---|---|---|---|",
    ]
    for e in errata:
        lines.append(
            f"| {e.where} | {e.printed} | {e.corrected} | {e.check} | "
            f"{'yes' if e.confirmed else 'NO'} |"
        )
    lines += [
        "",
        "Files: " + ", ".join(p.name for p in written) + ".",
        "",
    ]
    page = out / "paper001.md"
    page.write_text("\n".join(lines), encoding="utf-8")
    return [page, *written]

"""Paper 001 (Zong, Lu, An, Zhang; the spherical Stephenson III): the example mechanism and
the numerical checks of the paper's count of configurations.

Driven at AB, one rigid coupler has at most 2 × 2 = 4 configurations (four-bar ABCD × dyad
EFG); the paper's system (4) fixes only cos σ, so it also admits the mirror-image coupler
(σ → −σ), and its "at most 8" counts two mechanisms: :func:`mirror_check` shows the 4 + 4 at
one input, :func:`eq18_check` checks eq. 18 on them, and :func:`eq20_check` finds exactly those
configurations (of both couplers) among the real roots of the paper's eq. 20. Eight genuine
configurations occur when the linkage is driven at FG (:data:`EXAMPLE`, :func:`count_sweep`,
:func:`configuration_table`). See :mod:`linkwright.papers.p001` for the whole account.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.sphere_triad import bilinear_resultant, circle_frame
from linkwright.geometry import sphere
from linkwright.mechanisms import SphericalStephenson3, solve, solve_all
from linkwright.papers.p001_angles import paper_angles

__all__ = [
    "EXAMPLE",
    "EXAMPLE_INPUT",
    "MIRROR_INPUT",
    "CountSweep",
    "configuration_table",
    "count_sweep",
    "eq18_check",
    "eq20_check",
    "example",
    "mirror_check",
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
    degrees: Array = np.degrees(np.asarray(x, dtype=float))
    return degrees


class CountSweep(TypedDict):
    """:func:`count_sweep`'s answer: the input grid (degrees), the counts and the residuals."""

    input: Array
    ab: NDArray[np.int_]
    ab_residual: Array
    fg: NDArray[np.int_]
    fg_residual: Array
    ab_mirror: NDArray[np.int_]
    ab_either: NDArray[np.int_]


def count_sweep(samples: int = 360) -> CountSweep:
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
        largest: Array = np.where(
            np.isfinite(r).any(axis=-1), np.nanmax(np.nan_to_num(r, nan=-1.0), -1), np.nan
        )
        return largest

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
    largest: Array = np.maximum.reduce(
        [
            np.abs(sphere.dot(b, c) - np.cos(a3)),
            np.abs(sphere.dot(c, e) - np.cos(a6)),
            np.abs(sphere.dot(b, e) - be),
        ]
    )
    return largest


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

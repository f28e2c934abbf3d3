"""Paper 001's mechanism driven at FG, followed over its input: its circuits and their joins.

Driven at FG the coupler BCE is a spherical triad with up to 8 configurations at one input.
Followed continuously as the input θ6 turns, the configurations form closed *circuits*: on
each, θ6 rocks between *limit positions*, where two configurations meet and the linkage, which
cannot go on that way, runs on in the other as θ6 turns back (a circuit may also turn fully).
:func:`circuit_joins` traces them (:func:`linkwright.engine.continuation.every_circuit`) and
names, at each limit, the two configurations that meet there by their pose indices (the
document's ``pose``: 0 to 7 in the order of θ1 = ∠BAD at that input).

The mechanism is issue 21's example, bundled as ``paper001-fg`` (:func:`fg_example`): arcs
(71.1, 64.1, 68.6, 65.7, 69.0, σ 102.0, 74.1, 52.6, 19.7) degrees, with 8, 4 and 6
configurations at θ6 = −90°, 0° and 120° (:data:`COUNT_INPUTS`). :func:`write` adds its section
to paper 001's page: the counts, the table of joins and the figure of the circuits.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.continuation import Circuit, every_circuit
from linkwright.geometry import sphere
from linkwright.io import load_example
from linkwright.mechanisms import SphericalStephenson3, solve_all

__all__ = [
    "COUNT_INPUTS",
    "EXAMPLE_NAME",
    "Join",
    "circuit_joins",
    "counts_at",
    "fg_example",
    "theta1",
    "write",
]

Array = NDArray[np.float64]

EXAMPLE_NAME = "paper001-fg"
"""The bundled example: issue 21's arcs, driven at FG."""
COUNT_INPUTS = (-90.0, 0.0, 120.0)
"""θ6 (degrees) where issue 21 states the configuration counts 8, 4 and 6."""
BESIDE = 1e-6
"""Degrees either side of a limit position where its configurations are counted: far beyond
the limit's own error (about 1e-10 rad), far within the gap to the next limit."""
COLORS = ("#1f4e79", "#c0392b", "#27ae60", "#8e44ad", "#d68910", "#17a589", "#7f8c8d", "#a04000")


def fg_example() -> SphericalStephenson3:
    """The bundled ``paper001-fg`` mechanism (driven at FG)."""
    m = load_example(EXAMPLE_NAME).mechanism
    assert isinstance(m, SphericalStephenson3) and m.input == "FG"
    return m


def counts_at(mechanism: SphericalStephenson3, inputs_deg: Any) -> list[int]:
    """How many real configurations there are at each input θ6 (degrees)."""
    found = solve_all(mechanism, np.radians(np.asarray(inputs_deg, dtype=float)))
    return [int(c) for c in np.asarray(found.count).ravel()]


def theta1(mechanism: SphericalStephenson3, b: Array) -> Array:
    """θ1 = ∠BAD of B's positions (radians, in (−π, π]): eq. 5's B = (sin a2 sin θ1,
    sin a2 cos θ1, cos a2), left-handed about +OA from the great circle A→D."""
    p = mechanism.params()
    frame = sphere.circle_frame(p["A"], p["D"], -1.0)
    return np.arctan2(sphere.dot(b, frame[..., 2, :]), sphere.dot(b, frame[..., 1, :]))


@dataclass(frozen=True)
class Join:
    """A limit position: two configurations meet at ``input_deg`` (θ6, in (−180°, 180°]).

    ``poses`` are their pose indices at that input (0-based, in the order of θ1), as the
    circuit meets them (before, after); ``circuit`` numbers the circuit from 1; ``below`` and
    ``above`` count the configurations just below and just above the input (they differ by 2).
    """

    input_deg: float
    poses: tuple[int, int]
    circuit: int
    below: int
    above: int


def circuit_joins(
    mechanism: SphericalStephenson3 | None = None, samples: int = 360
) -> tuple[list[Circuit], list[Join]]:
    """Every circuit of the mechanism driven at FG (default :func:`fg_example`) and every limit
    position on them, in circuit order.

    >>> found, joins = circuit_joins(samples=120)
    >>> len(found), [len(c.limits) for c in found], len(joins)
    (3, [2, 6, 2], 10)
    """
    m = fg_example() if mechanism is None else mechanism
    found = every_circuit(m.plan, m.params(), samples, points=m.points, order=0)
    where = [(k, lim) for k, c in enumerate(found) for lim in c.limits]
    wrapped = [math.degrees(math.remainder(lim.input, 2 * math.pi)) for _, lim in where]
    beside = [x + s for x in wrapped for s in (-BESIDE, BESIDE)]
    counts = counts_at(m, beside) if beside else []
    (step,) = m.plan.triads
    joins = []
    for i, ((k, lim), x) in enumerate(zip(where, wrapped, strict=True)):
        poses = (int(lim.before[step.name]), int(lim.after[step.name]))
        joins.append(Join(x, poses, k + 1, counts[2 * i], counts[2 * i + 1]))
    return found, joins


# ----------------------------------------------------------------------------------------------
# The figure
# ----------------------------------------------------------------------------------------------


def _wrapped_runs(x: Array, y: Array) -> list[tuple[Array, Array]]:
    """A closed curve on the torus of two angles (degrees), cut where either wraps."""
    x = np.append(x, x[0])
    y = np.append(y, y[0])
    xw = (x + 180.0) % 360.0 - 180.0
    yw = (y + 180.0) % 360.0 - 180.0
    cut = np.flatnonzero((np.abs(np.diff(xw)) > 180.0) | (np.abs(np.diff(yw)) > 180.0)) + 1
    return [(a, b) for a, b in zip(np.split(xw, cut), np.split(yw, cut), strict=True) if a.size]


def _figure(m: SphericalStephenson3, found: list[Circuit], joins: list[Join]) -> Any:
    from linkwright.plot import new_figure

    fig = new_figure((13.0, 6.2))
    left, right = fig.subplots(1, 2, width_ratios=(1.15, 1.0))
    traced = m.traced_joint
    every_e = np.concatenate([c.motion.positions[traced] for c in found])
    centre = sphere.unit(np.nansum(every_e, axis=0))
    p = m.params()
    for k, c in enumerate(found):
        color = COLORS[k % len(COLORS)]
        t6 = np.degrees(c.motion.input)
        t1 = np.degrees(theta1(m, c.motion.positions["B"]))
        label = f"circuit {k + 1} ({len(c.limits)} limits)" if c.limits else f"circuit {k + 1}"
        for i, (x, y) in enumerate(_wrapped_runs(t6, t1)):
            left.plot(x, y, color=color, lw=1.6, label=label if i == 0 else "_nolegend_")
        xy = sphere.lambert_azimuthal(
            np.vstack((c.motion.positions[traced], c.motion.positions[traced][:1])), centre
        )
        right.plot(*xy.T, color=color, lw=1.6)
    for n, join in enumerate(joins, start=1):
        c = found[join.circuit - 1]
        i = int(
            np.argmin(
                np.abs(
                    np.remainder(np.radians(join.input_deg) - c.motion.input + np.pi, 2 * np.pi)
                    - np.pi
                )
            )
        )
        y_join = float(np.degrees(theta1(m, c.motion.positions["B"][i])))
        left.plot(join.input_deg, y_join, "D", ms=6, mfc="white", mec="k", zorder=5)
        left.annotate(
            str(n), (join.input_deg, y_join), xytext=(4, 4), textcoords="offset points", fontsize=8
        )
        q = sphere.lambert_azimuthal(c.motion.positions[traced][i], centre)
        right.plot(*q, "D", ms=6, mfc="white", mec="k", zorder=5)
        right.annotate(str(n), q, xytext=(4, 4), textcoords="offset points", fontsize=8)
    for name in ("A", "D", "G"):
        q = sphere.lambert_azimuthal(p[name], centre)
        right.plot(*q, "^", ms=8, mfc="0.35", mec="k", zorder=4)
        right.annotate(name, q, xytext=(5, -10), textcoords="offset points", fontsize=9)
    for counted in COUNT_INPUTS:
        left.axvline(counted, color="0.6", lw=0.8, ls=":")
    left.set_xlim(-180, 180)
    left.set_ylim(-180, 180)
    left.set_xticks(range(-180, 181, 45))
    left.set_yticks(range(-180, 181, 45))
    left.set_xlabel("input θ6 (°)")
    left.set_ylabel("θ1 = ∠BAD (°)")
    left.grid(alpha=0.3)
    left.legend(loc="lower left", fontsize=8)
    left.set_title(
        "every configuration, followed over the input: closed circuits on the torus (θ6, θ1);\n"
        "◇ n: limit position n of the table, where two configurations meet; dotted: θ6 = "
        + ", ".join(f"{x:g}°" for x in COUNT_INPUTS),
        fontsize=9,
    )
    right.set_aspect("equal")
    right.set_xticks([])
    right.set_yticks([])
    right.set_title(
        f"the traced joint {traced} along each circuit, on a Lambert equal-area map of the sphere\n"
        f"(centred on the curves' mean direction; ▲ the fixed joints); {traced} stops and turns "
        f"back\nwhere {traced}, F and G fall on one great circle, so each closed path doubles "
        "back on itself",
        fontsize=9,
    )
    fig.suptitle(
        "Paper 001's Stephenson III driven at FG (issue 21's example, paper001-fg): "
        + ", ".join(
            f"{k} {np.degrees(float(np.asarray(v))):g}°"
            for k, v in zip(
                ("AD", "AB", "BC", "CD", "CE", "σ", "EF", "FG", "DG"),
                (m.a1, m.a2, m.a3, m.a4, m.a6, m.sigma, m.a7, m.a8, m.a9),
                strict=True,
            )
        ),
        fontsize=10,
    )
    return fig


# ----------------------------------------------------------------------------------------------
# The page's section
# ----------------------------------------------------------------------------------------------


def write(out: Path) -> tuple[list[str], list[Path]]:
    """Write the circuits' table (``paper001-circuits.csv``) and figure
    (``paper001-circuits.png``, ``.svg``) into ``out``; return the page's section (Markdown
    lines) and the paths written."""
    from linkwright.plot import save_figure

    m = fg_example()
    found, joins = circuit_joins(m)
    counts = counts_at(m, COUNT_INPUTS)
    written = []
    path = out / "paper001-circuits.csv"
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(
            [
                "limit",
                "theta6_deg",
                "pose_before",
                "pose_after",
                "circuit",
                "configurations_below",
                "configurations_above",
            ]
        )
        for n, j in enumerate(joins, start=1):
            writer.writerow([n, f"{j.input_deg:.9f}", *j.poses, j.circuit, j.below, j.above])
    written.append(path)
    fig = _figure(m, found, joins)
    for suffix in (".png", ".svg"):
        written.append(save_figure(fig, out / f"paper001-circuits{suffix}"))
    arcs = ", ".join(
        f"{np.degrees(float(np.asarray(v))):g}"
        for v in (m.a1, m.a2, m.a3, m.a4, m.a6, m.sigma, m.a7, m.a8, m.a9)
    )
    full = [k + 1 for k, c in enumerate(found) if c.full]
    lines = [
        "## Driven at FG: the configurations followed over the input",
        "",
        f"Issue 21's example (the bundled `{EXAMPLE_NAME}`): AD, AB, BC, CD, CE, σ, EF, FG, "
        f"DG = {arcs} degrees. It has "
        + ", ".join(f"{c}" for c in counts[:-1])
        + f" and {counts[-1]} configurations at θ6 = "
        + ", ".join(f"{x:g}°" for x in COUNT_INPUTS[:-1])
        + f" and {COUNT_INPUTS[-1]:g}°.",
        "",
        "Followed continuously as θ6 turns, its configurations form "
        f"{len(found)} closed circuits"
        + (f" ({', '.join(map(str, full))} turning fully)" if full else "")
        + ". On each, θ6 rocks between limit positions, where two configurations meet (the "
        "triad's three links can no longer turn its ternary link on) and the linkage runs on "
        "in the other as θ6 turns back; just beside a limit there are two configurations "
        "more on one side than on the other. The pose index is the document's `pose`: the "
        "configuration's place (from 0) in the order of θ1 = ∠BAD at that input. Figure: "
        "paper001-circuits.png / .svg; numbers: paper001-circuits.csv.",
        "",
        "| limit | θ6 (°) | pose indices that meet | circuit | configurations just below / above |",
        "|---|---|---|---|---|",
    ]
    for n, j in enumerate(joins, start=1):
        lines.append(
            f"| {n} | {j.input_deg:.4f} | {j.poses[0]} and {j.poses[1]} | {j.circuit} | "
            f"{j.below} / {j.above} |"
        )
    lines.append("")
    return lines, written

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

The example and the checks of the count are in :mod:`linkwright.papers.p001_checks`, the
misprints in :mod:`linkwright.papers.p001_misprints` and the figures in
:mod:`linkwright.papers.p001_figures`; their public names are re-exported here as before.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.papers import p001_circuits
from linkwright.papers.p001_checks import (
    EXAMPLE,
    EXAMPLE_INPUT,
    MIRROR_INPUT,
    Array,
    configuration_table,
    count_sweep,
    eq18_check,
    eq20_check,
    example,
    mirror_check,
)
from linkwright.papers.p001_figures import configurations_figure, counts_figure
from linkwright.papers.p001_misprints import Misprint, misprints

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


def _listed(counts: NDArray[np.int_]) -> str:
    values = [str(v) for v in np.unique(counts)]
    return ", ".join(values[:-1]) + " and " + values[-1] if len(values) > 1 else values[0]


def _runs(degrees: Array) -> str:
    """Whole degrees as runs: "168°–186°, 263°–309°"."""
    if not degrees.size:
        return "none"
    cut = np.flatnonzero(np.diff(degrees) > 1.5) + 1
    parts = np.split(degrees, cut)
    return ", ".join(f"{p[0]:g}°–{p[-1]:g}°" if len(p) > 1 else f"{p[0]:g}°" for p in parts)


def _histogram(counts: NDArray[np.int_], top: int) -> str:
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
        "paper001-counts": counts_figure(sweep),
        "paper001-configurations": configurations_figure(EXAMPLE_INPUT),
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
    for row in eq20:
        lines.append(
            f"| {row['x4']:.6f} | {row['degree']} | {', '.join(_num(x) for x in row['real'])} | "
            f"{', '.join(_num(x) for x in row['coupler'])} | "
            f"{', '.join(_num(x) for x in row['mirror'])} | {row['gap']:.1e} |"
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

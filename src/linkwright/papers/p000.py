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

The formulas are in :mod:`linkwright.papers.p000_formulas`, the figures' linkages in
:mod:`linkwright.papers.p000_figures` and the numerical checks in
:mod:`linkwright.papers.p000_checks`; this module regenerates the figures and the page, and
re-exports their public names as before.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from linkwright.mechanisms import (
    circuit,
)
from linkwright.papers.p000_checks import (
    TOLERANCE,
    Alpha90,
    Degradation,
    Eq5Check,
    PointCheck,
    alpha90_sweep,
    degradation,
    eq5_checks,
    point_checks,
    sign_label,
)
from linkwright.papers.p000_figures import (
    FIG6,
    FIG7,
    FIG8,
    Fig8Mode,
    fig8_modes,
    figure_fourbar,
    figure_sixbar,
)
from linkwright.papers.p000_formulas import (
    InvalidInput,
    eq4_rocker_joint,
    eq5_theta4,
    eq13_coupler_point,
)

if TYPE_CHECKING:  # matplotlib is imported only where a figure is drawn
    from matplotlib.figure import Figure

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


# --------------------------------------------------------------------------------------------
# Regeneration
# --------------------------------------------------------------------------------------------


def _e(x: float) -> str:
    if math.isinf(x):
        return "NaN or ∞"
    return f"{x:.1e}".replace("-", "−")


def _save_both(fig: Figure, out: Path, stem: str) -> list[Path]:
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
                title=f"Fig. {number}, {names[number]}: assembly {sign_label(assembly)}{note}",
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
                f"Fig. 8: ε = {mode.epsilon:+.0f}°, assembly {sign_label(mode.assembly)}, "
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


def _write_csv(path: Path, rows: Sequence[Any]) -> Path:
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
            f"| {mode.epsilon:+.0f} | {sign_label(mode.assembly)} | {crank} | {e2} |".replace(
                "-", "−"
            )
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

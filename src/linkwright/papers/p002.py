"""Paper 002 (Abhyankar & Gajjal): the geared five-bar with a rotation constraint, regenerated.

The paper prints no dimensions: its figures are screenshots of a tool in which the user draws
the two cranks (points 1–2 and 3–4) and the traced point 6, point 5 being the midpoint of 2–6,
and the cranks turn at equal speeds in opposite senses (ratio −1). Its Results section then moves
the fixed pivot 1 step by step (r1, r2 and point 6 kept, L1 and L2 following) and shows how the
curve changes, and shows the curves for the leftmost, rightmost, topmost and lowermost positions
of point 1.

linkwright regenerates that sequence for a drawing of its own (:data:`DRAWING`, stated here and
in the output), with the five-bar built by :meth:`GearedFiveBar.from_drawing`. "Leftmost" etc.
are read as the farthest the pivot can move in that direction, in whole steps, with the input
still turning fully: beyond it the linkage locks and only oscillates, which the study reports.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from linkwright.mechanisms import GearedFiveBar, InvalidMechanism, input_range

__all__ = ["DRAWING", "StudyStep", "pivot_limit", "pivot_study", "reproduce"]

DRAWING: dict[str, tuple[float, float]] = {
    "A0": (0.0, 0.0),  # point 1
    "A": (0.0, 1.0),  # point 2
    "B0": (4.0, 0.0),  # point 3
    "B": (4.0, -1.2),  # point 4
    "P": (1.0, 5.5),  # point 6 (C, point 5, is the midpoint of A–P)
}
STEP = 0.5
MAX_STEPS = 8
DIRECTIONS = {"left": (-1.0, 0.0), "right": (1.0, 0.0), "up": (0.0, 1.0), "down": (0.0, -1.0)}


@dataclass(frozen=True)
class StudyStep:
    """One position of the moved pivot: how many steps, the offset, and the five-bar it gives."""

    steps: int
    offset: tuple[float, float]
    mechanism: GearedFiveBar
    turns_fully: bool


def pivot_study(
    drawing: Mapping[str, Sequence[float]] = DRAWING,
    direction: Sequence[float] = DIRECTIONS["left"],
    *,
    step: float = STEP,
    count: int = 3,
    ratio: float = -1.0,
) -> list[StudyStep]:
    """Move pivot 1 (A0, with its crank end A) ``count`` steps along ``direction``.

    The crank lengths, the crank angles of the drawing and the traced point stay; C stays the
    midpoint of A–P, so link1 and link2 follow (paper 002, section III). Step 0 is the drawing.
    The study stops early where A would land on P (no link AC is left).

    Examples
    --------
    >>> steps = pivot_study(count=2)
    >>> [s.offset for s in steps]
    [(0.0, 0.0), (-0.5, 0.0), (-1.0, 0.0)]
    >>> [round(float(s.mechanism.link1), 6) for s in steps]  # √(21.25, 22.5, 24.25) / 2
    [2.304886, 2.371708, 2.462214]
    """
    d = np.asarray(direction, dtype=float)
    d = d / np.hypot(*d)
    out = []
    for k in range(count + 1):
        shift = k * step * d
        try:
            mech = GearedFiveBar.from_drawing(
                np.add(drawing["A0"], shift),
                np.add(drawing["A"], shift),
                drawing["B0"],
                drawing["B"],
                drawing["P"],
                ratio=ratio,
            )
        except InvalidMechanism:
            break  # the crank end has reached the traced point: no link AC is left
        offset = (float(shift[0]) + 0.0, float(shift[1]) + 0.0)
        out.append(StudyStep(k, offset, mech, bool(input_range(mech).full)))
    return out


def pivot_limit(
    drawing: Mapping[str, Sequence[float]] = DRAWING,
    direction: Sequence[float] = DIRECTIONS["left"],
    *,
    step: float = STEP,
    max_steps: int = MAX_STEPS,
) -> StudyStep:
    """The farthest whole step along ``direction`` at which the input still turns fully.

    Returns the drawing itself if even the first step locks; stops at ``max_steps``.
    """
    steps = pivot_study(drawing, direction, step=step, count=max_steps)
    last = steps[0]
    for s in steps[1:]:
        if not s.turns_fully:
            break
        last = s
    return last


def _describe(m: GearedFiveBar) -> str:
    a0 = np.asarray(m.A0)
    return (
        f"A0 = ({a0[0]:.3g}, {a0[1]:.3g}), link1 = {float(m.link1):.4f}, "
        f"link2 = {float(m.link2):.4f}"
    )


def reproduce(out_dir: str | Path) -> list[Path]:
    """Write paper 002's figures for :data:`DRAWING` and a markdown page; returns the files."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from linkwright.mechanisms import circuit
    from linkwright.plot import save_figure
    from linkwright.plot.generic import draw_pose, plot_linkage, plot_speed

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    original = pivot_study(count=0)[0].mechanism

    fig = Figure(figsize=(8, 9), layout="constrained")
    FigureCanvasAgg(fig)
    # squeeze=False: an array of subfigures, which the stubs type (a bare SubFigure may not be
    # unpacked).
    top, bottom = fig.subfigures(2, 1, squeeze=False, height_ratios=(2.2, 1))[:, 0]
    plot_linkage(original, title="Original configuration (ratio −1)", ax=top.add_subplot())
    plot_speed(original, "P", ax=bottom.add_subplot())
    written.append(save_figure(fig, out / "p002-original.png"))

    # Paper 002 shows the traced points at 5° steps of the input, so their spacing shows speed.
    fig = Figure(figsize=(11, 4), layout="constrained")
    FigureCanvasAgg(fig)
    steps = pivot_study(count=3)
    for i, s in enumerate(steps):
        ax = fig.add_subplot(1, 4, i + 1)
        motion = circuit(s.mechanism, 72, order=0)
        ax.plot(*motion.positions["P"].T, ".", ms=3, color="#c0392b")
        draw_pose(ax, s.mechanism, motion, 0)
        ax.set_aspect("equal")
        ax.set_title("original" if i == 0 else f"left step {i}", fontsize=9)
    written.append(save_figure(fig, out / "p002-left-steps.png"))

    fig = Figure(figsize=(9, 9), layout="constrained")
    FigureCanvasAgg(fig)
    extremes = {name: pivot_limit(direction=d) for name, d in DIRECTIONS.items()}
    labels = {"left": "Leftmost", "right": "Rightmost", "up": "Topmost", "down": "Lowermost"}
    for i, (name, s) in enumerate(extremes.items()):
        ax = fig.add_subplot(2, 2, i + 1)
        plot_linkage(s.mechanism, samples=360, ax=ax)
        ax.set_title(f"{labels[name]} position of point 1: offset {s.offset}", fontsize=9)
    written.append(save_figure(fig, out / "p002-pivot-extremes.png"))

    lines = [
        "# Paper 002, regenerated",
        "",
        "The paper prints no dimensions; this is linkwright's own drawing in the paper's way "
        "(points 1, 2, 3, 4 and the traced 6; C = point 5 the midpoint of 2–6; ratio −1):",
        "",
        "| point | x | y |",
        "|---|---|---|",
        *(f"| {k} | {v[0]} | {v[1]} |" for k, v in DRAWING.items()),
        "",
        f"Original: {_describe(original)}; input turns fully: "
        f"{bool(input_range(original).full)}. Pictures: p002-original.png (curve and the speed "
        "of P along the cycle), p002-left-steps.png (pivot 1 moved left in steps of "
        f"{STEP}), p002-pivot-extremes.png.",
        "",
        "| pivot 1 moved | offset | link1 | link2 | input turns fully |",
        "|---|---|---|---|---|",
    ]
    for i, s in enumerate(steps):
        lines.append(
            f"| left step {i} | {s.offset} | {float(s.mechanism.link1):.4f} | "
            f"{float(s.mechanism.link2):.4f} | {s.turns_fully} |"
        )
    for name, s in extremes.items():
        note = f" (no lock within {MAX_STEPS} steps)" if s.steps == MAX_STEPS else ""
        lines.append(
            f"| {labels[name].lower()} (last full turn{note}) | {s.offset} | "
            f"{float(s.mechanism.link1):.4f} | {float(s.mechanism.link2):.4f} | {s.turns_fully} |"
        )
    lines += [
        "",
        "One step farther (where a lock was found) the linkage locks: the dyad A–C–B cannot "
        "close over the whole turn, and the five-bar oscillates between its locking "
        "positions (as the paper's tool does; `linkwright analyze` lists them).",
        "",
    ]
    page = out / "paper002.md"
    page.write_text("\n".join(lines), encoding="utf-8")
    written.append(page)
    return written

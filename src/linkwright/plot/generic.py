"""Pictures of any linkage the engine builds, drawn from its construction plan.

The four-bar and slider-crank have their own annotated pictures (:mod:`linkwright.plot.planar`);
every other family (geared five-bar, double slider, six-bars, composed linkages) is drawn here
from the plan itself: each step says which joints a link joins, so the drawing needs no
per-family code. Figures are built without pyplot, as in the planar module.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from linkwright.analysis.general import point_speed
from linkwright.engine import Crank, DyadRRP, DyadRRR, Fixed, Motion, Rigid, Trammel
from linkwright.mechanisms import Mechanism, circuit
from linkwright.plot.planar import new_figure

__all__ = ["draw_pose", "plot_linkage", "plot_speed"]

Array = NDArray[np.float64]
LINK = "#1f3b57"
GROUND = "#6b6b6b"
CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")


def _links(mechanism: Mechanism) -> list[tuple[str, str]]:
    """Pairs of joints joined by a link (or lying on one rigid body), from the plan."""
    pairs: list[tuple[str, str]] = []
    for step in mechanism.plan.steps:
        if isinstance(step, Crank):
            pairs.append((step.pivot, step.name))
        elif isinstance(step, DyadRRR):
            pairs += [(step.p1, step.name), (step.p2, step.name)]
        elif isinstance(step, DyadRRP):
            pairs.append((step.p1, step.name))
        elif isinstance(step, Rigid):
            pairs += [(step.origin, step.name), (step.toward, step.name)]
    return pairs


def _guides(mechanism: Mechanism) -> list[tuple[str, float]]:
    """Slider guides as (joint on the guide, direction in radians)."""
    params = mechanism.params()

    def value(p: str | float) -> float:
        return float(np.asarray(params[p] if isinstance(p, str) else p))

    out = []
    for step in mechanism.plan.steps:
        if isinstance(step, DyadRRP):
            out.append((step.line_point, value(step.line_angle)))
        elif isinstance(step, Trammel):
            out += [(step.guide1, value(step.angle1)), (step.guide2, value(step.angle2))]
    return out


def draw_pose(
    ax: Axes, mechanism: Mechanism, motion: Motion, k: int, *, alpha: float = 1.0
) -> None:
    """Draw the linkage at sample ``k`` of ``motion``: links, ground pivots, joint names."""
    pos = {name: p[k] for name, p in motion.positions.items()}
    span = max(float(np.nanmax(np.ptp(np.stack(list(pos.values())), axis=0))), 1e-9)
    for at, angle in _guides(mechanism):
        d = np.array([np.cos(angle), np.sin(angle)]) * span
        ax.plot(*np.stack((pos[at] - d, pos[at] + d)).T, color=GROUND, lw=0.8, ls="--", alpha=alpha)
    for a, b in _links(mechanism):
        ax.plot(
            *np.stack((pos[a], pos[b])).T, color=LINK, lw=2.0, alpha=alpha, solid_capstyle="round"
        )
    for step in mechanism.plan.steps:
        p = pos[step.name]
        if not np.all(np.isfinite(p)):
            continue
        ground = isinstance(step, Fixed)
        ax.plot(
            *p,
            marker="^" if ground else "o",
            ms=8 if ground else 5,
            color=GROUND if ground else "white",
            mec=LINK,
            alpha=alpha,
            zorder=4,
        )
        if alpha == 1.0:
            ax.annotate(step.name, p, xytext=(4, 4), textcoords="offset points", fontsize=8)


def plot_linkage(
    mechanism: Mechanism, *, samples: int = 720, title: str | None = None, ax: Axes | None = None
) -> Figure:
    """The linkage at its first circuit sample and the closed curves of its traced joints.

    Limit positions (where a dyad changes branch) are marked with a cross.
    """
    motion = circuit(mechanism, samples, order=0)
    fig = ax.figure if ax is not None else new_figure((7, 6))
    ax = ax or fig.add_subplot()
    if not np.any(motion.valid):
        ax.text(
            0.5,
            0.5,
            "this linkage cannot be assembled at any input",
            ha="center",
            transform=ax.transAxes,
        )
        return fig
    for i, joint in enumerate(mechanism.plan.traced):
        p = motion.positions[joint]
        closed = np.concatenate((p, p[:1]))
        ax.plot(*closed.T, color=CURVES[i % len(CURVES)], lw=1.4, label=f"path of {joint}")
    limits = np.zeros(motion.shape, dtype=bool)
    for b in motion.branches.values():
        limits |= np.broadcast_to(b != np.roll(b, 1, -1), motion.shape)
    traced = mechanism.plan.traced[0]
    if limits.any():
        ax.plot(*motion.positions[traced][limits].T, "x", color="k", ms=7, label="limit positions")
    draw_pose(ax, mechanism, motion, 0)
    ax.set_aspect("equal")
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=8)
    if title:
        ax.set_title(title)
    return fig


def plot_speed(
    mechanism: Mechanism, joint: str | None = None, *, samples: int = 720, ax: Axes | None = None
) -> Figure:
    """|dP/dθ| of a traced joint over the circuit, against the input (paper 002's velocity)."""
    joint = joint or mechanism.plan.traced[0]
    motion = circuit(mechanism, samples, order=1)
    fig = ax.figure if ax is not None else new_figure((7, 3))
    ax = ax or fig.add_subplot()
    speed = point_speed(motion, joint)
    # Near a limit position the speed per radian of input grows without bound: clip the axis
    # at a high percentile so the rest of the cycle stays readable.
    top = np.nanpercentile(speed, 97) * 1.3 if np.any(np.isfinite(speed)) else 1.0
    ax.plot(np.arange(motion.shape[-1]), speed, color=CURVES[0], lw=1.2)
    ax.set_ylim(0, top)
    ax.set_xlabel("circuit sample (input sweeps its whole circuit)")
    ax.set_ylabel(f"|d{joint}/dθ| per rad")
    ax.grid(True, lw=0.3)
    return fig

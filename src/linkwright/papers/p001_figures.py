"""Paper 001 (Zong, Lu, An, Zhang; the spherical Stephenson III): the figures of the
reproduction, the number of configurations over the input and the eight configurations of the
example at :data:`~linkwright.papers.p001_checks.EXAMPLE_INPUT`, each drawn on the unit sphere.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.geometry import sphere
from linkwright.mechanisms import solve_all
from linkwright.papers.p001_angles import paper_angles
from linkwright.papers.p001_checks import EXAMPLE, EXAMPLE_INPUT, Array, CountSweep, example

__all__ = ["configurations_figure", "counts_figure"]

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


def counts_figure(sweep: CountSweep) -> Any:
    from linkwright.plot import new_figure

    fig = new_figure((8.0, 5.6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    theta = np.append(sweep["input"], 360.0)

    def steps(ax: Any, counts: NDArray[np.int_], **style: Any) -> None:
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


def configurations_figure(theta6: float) -> Any:
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

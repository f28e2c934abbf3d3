"""Pictures of planar linkages: the linkage itself, its coupler curves and its motion diagrams.

Everything here builds :class:`matplotlib.figure.Figure` objects directly, with an Agg canvas
attached, and never touches pyplot's global state: the functions work headless and from several
threads at once.

The transmission angle γ is :func:`linkwright.analysis.transmission_angle` on the sampled
motion; the extremes :func:`plot_curves` marks are the exact ones of
:func:`linkwright.analysis.transmission_extremes`, and its dead centres (where the output stops:
crank and coupler in line, the slider at the ends of its stroke) the exact output extremes of
:func:`linkwright.analysis.output_extremes` (see :mod:`linkwright.plot.generic` for what every
mark means).

The linkage in one pose is drawn by :mod:`linkwright.plot.planar_draw`, notes and legends are
placed by :mod:`linkwright.plot.notes`, and the palette, caption numbers and saving are in
:mod:`linkwright.plot.style`; their public names are re-exported here as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.typing import LineStyleType
from numpy.typing import NDArray

from linkwright.analysis import transmission_angle
from linkwright.engine import Motion
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, Mechanism, SliderCrank, circuits
from linkwright.plot.axes import check_axes, figure_of
from linkwright.plot.notes import (
    Note,
    add_note,
    drawn_lines,
    fit_figure,
    legend_below,
    legend_height,
    place_notes,
)
from linkwright.plot.planar_draw import draw_linkage, ground_symbol, label_joints, require_single
from linkwright.plot.style import (
    CURVE_COLOR,
    LIMIT_COLOR,
    MINUS,
    OTHER_COLOR,
    Array,
    deg_text,
    family_name,
    new_figure,
    num_text,
    save_figure,
    sign_label,
)
from linkwright.plot.style import GAMMA_COLOR as GAMMA_COLOR  # plot.diagrams takes it from here

__all__ = [
    "Note",
    "TracedCircuit",
    "add_note",
    "deg_text",
    "draw_linkage",
    "fit_figure",
    "ground_symbol",
    "label_joints",
    "legend_below",
    "legend_height",
    "new_figure",
    "num_text",
    "place_notes",
    "plot_curves",
    "plot_diagrams",
    "save_figure",
    "speed_limit",
    "traced_circuits",
    "unwrap_finite",
]


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def _dimensions(mechanism: Mechanism) -> str:
    if isinstance(mechanism, FourBar):
        return (
            f"frame {num_text(float(mechanism.frame))}, crank {num_text(float(mechanism.crank))}, "
            f"coupler {num_text(float(mechanism.coupler))}, rocker "
            f"{num_text(float(mechanism.rocker))}, "
            f"P = ({num_text(float(mechanism.u))}, {num_text(float(mechanism.v))})"
        )
    assert isinstance(mechanism, SliderCrank)
    return (
        f"crank {num_text(float(mechanism.crank))}, rod {num_text(float(mechanism.rod))}, "
        f"offset {num_text(float(mechanism.offset))}, "
        f"line at {deg_text(math.degrees(float(mechanism.line_angle)))}°, "
        f"P = ({num_text(float(mechanism.u))}, {num_text(float(mechanism.v))})"
    )


def _transmission_angle_deg(mechanism: Mechanism, motion: Motion) -> Array:
    """γ in degrees at every sample (NaN where not assembled); see the module docstring."""
    return np.degrees(transmission_angle(mechanism, motion))


def _output(mechanism: Mechanism, motion: Motion) -> Array:
    """Four-bar: angle of B − B0 from the frame line A0→B0, radians (wrapped). Slider: s."""
    if isinstance(mechanism, FourBar):
        e = plane.unit_direction(mechanism.frame_angle)
        rel = motion.positions["B"] - np.asarray(mechanism.B0, float)
        return np.arctan2(plane.cross(e, rel), plane.dot(e, rel))
    assert isinstance(mechanism, SliderCrank)
    return mechanism.slider_position(motion)


def unwrap_finite(a: Array) -> Array:
    out = a.copy()
    ok = np.isfinite(a)
    if ok.any():
        out[ok] = np.unwrap(a[ok])
    return out


@dataclass(frozen=True)
class TracedCircuit:
    """One traced circuit and how its samples split into legs."""

    motion: Motion
    full: bool

    @property
    def n(self) -> int:
        return int(self.motion.input.shape[-1])

    @property
    def upper(self) -> int:
        """Index of the upper limit (arc circuits)."""
        return (self.n + 1) // 2

    def closed(self) -> NDArray[np.int64]:
        """Sample indices of the closed circuit: 0, 1, …, n − 1 and 0 again."""
        indices: NDArray[np.int64] = np.r_[np.arange(self.n), 0]
        return indices


def traced_circuits(mechanism: Mechanism, samples: int, order: int = 1) -> list[TracedCircuit]:
    arcs, motions = circuits(mechanism, samples, order=order)
    return [TracedCircuit(m, bool(arcs.full)) for m in motions]


# --------------------------------------------------------------------------------------------
# Coupler curves
# --------------------------------------------------------------------------------------------


def _link_lines(pts: dict[str, Array]) -> list[Array]:
    pairs = [("A0", "A"), ("A", "B"), ("B", "P"), ("P", "A"), ("B0", "B"), ("A0", "B0")]
    return [np.array([pts[a], pts[b]]) for a, b in pairs if a in pts and b in pts]


def plot_curves(
    mechanism: Mechanism,
    *,
    samples: int = 720,
    theta: float | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """The coupler curve of P over the whole circuit, for both assembly modes, with the linkage.

    The mechanism's own assembly is drawn solid, the other dashed in another colour (where the
    input only rocks, the circuit switches branch at each limit, so both modes trace the same
    closed curve and the two lines overlap). On the mechanism's own circuit P is marked and
    annotated at the input's limit positions (where the input cannot go on), at the dead
    centres (where the output stops; the rocker, or the slider, is drawn there too) and at the
    exact extremes of the transmission angle γ. The legend sits under the drawing.

    Parameters
    ----------
    mechanism : Mechanism
        A single :class:`~linkwright.mechanisms.FourBar` or
        :class:`~linkwright.mechanisms.SliderCrank`.
    samples : int, optional
        Samples per circuit.
    theta : float, optional
        Input angle (radians) at which the linkage is drawn, on the mechanism's own assembly
        (the pose of :func:`~linkwright.mechanisms.solve`); default the circuit's first sample
        (the lower limit where the input cannot turn fully).
    title : str, optional
        Appended to the family name in the figure title (the axes' title when ``ax`` is given).
    ax : matplotlib.axes.Axes, optional
        Draw into this (flat) axes, its figure keeping its size and layout, with the legend in
        the axes; a new figure is made otherwise.

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on (``ax``'s top-level figure when ``ax`` is given). One axes with
        equal aspect.
        Curve lines carry the labels ``"assembly +1"`` and
        ``"assembly −1"`` (further circuits of the same mode ``"assembly ±1, circuit k"``); each
        is closed, its last point repeating its first.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> fig = plot_curves(crank_rocker, samples=90, title="crank-rocker")
    >>> fig.get_suptitle()
    'Four-bar — crank-rocker'
    >>> sorted(ln.get_label() for ln in fig.axes[0].lines if ln.get_label().startswith("assembly"))
    ['assembly +1', 'assembly −1']

    Its dead centres, crank and coupler in line (|A0 B| = 5 ± 1, so B is at 6 or 4 from A0):

    >>> ends = next(ln for ln in fig.axes[0].lines if ln.get_label().startswith("output"))
    >>> np.hypot(*ends.get_xydata().T).round(9)
    array([6., 4.])
    """
    mechanism = require_single(mechanism)
    own_figure = check_axes(ax) is None
    fig = new_figure((8.5, 7.0)) if ax is None else figure_of(ax)
    ax = ax if ax is not None else fig.add_subplot()
    sign = float(np.sign(mechanism.assembly))
    mine = traced_circuits(mechanism, samples)
    theirs = traced_circuits(mechanism.with_assembly(-sign), samples)
    tol = 0.02 * float(mechanism.scale)

    # The mechanism's own mode solid, the other dashed on top of it: where the two coincide
    # (an input that rocks) both stay visible.
    for traced, color, ls, lw, s, z in (
        (mine, CURVE_COLOR, "-", 2.0, sign, 3.6),
        (theirs, OTHER_COLOR, (0, (5, 3)), 1.4, -sign, 3.7),
    ):
        for k, c in enumerate(traced):
            xy = c.motion.positions["P"][c.closed()]
            label = sign_label(s) + ("" if k == 0 else f", circuit {k + 1}")
            ax.plot(xy[:, 0], xy[:, 1], color=color, ls=ls, lw=lw, label=label, zorder=z)

    # The paths of the moving pivots (B's is the slider's line, drawn as its guide).
    joints = ("A", "B") if isinstance(mechanism, FourBar) else ("A",)
    first = True
    for c in mine:
        for name in joints:
            xy = c.motion.positions[name][c.closed()]
            ax.plot(
                xy[:, 0],
                xy[:, 1],
                color="0.6",
                lw=0.9,
                ls=(0, (1, 1.5)),
                zorder=1.8,
                label=f"path{'s' if len(joints) > 1 else ''} of {' and '.join(joints)}"
                if first
                else "_nolegend_",
            )
            first = False

    # Limit positions, dead centres and the exact γ extremes of the document's mode, found as
    # for every family (linkwright.plot.generic, which builds on this module: imported here).
    from linkwright.plot.generic import draw_marks, find_features

    notes: list[Note] = []
    feats = find_features(mechanism, samples)
    draw_marks(ax, feats, "P", notes, tol, gamma_label="P at γ extremes")

    ref = mine[0].motion if mine else None
    if theta is None:
        theta = float(ref.input[0]) if ref is not None else 0.0
        drawn = draw_linkage(ax, mechanism, theta, motion=ref)
    else:
        # A chosen input is drawn on the document's own assembly, as solve() places it.
        drawn = draw_linkage(ax, mechanism, float(theta))

    subtitle = _dimensions(mechanism)
    if not mine:
        subtitle += "\nno circuit: the linkage assembles at no input"
    elif not mine[0].full:
        arcs = ", ".join(
            f"[{deg_text(math.degrees(float(c.motion.input[0])))}°, "
            f"{deg_text(math.degrees(float(c.motion.input[c.upper])))}°]"
            for c in mine
        )
        many = len(mine) > 1
        subtitle += (
            f"\ninput rocks over {arcs}{f' ({len(mine)} circuits)' if many else ''}; "
            "the dyad changes branch at each limit,\n"
            f"so both assembly modes trace {'each' if many else 'the same'} closed circuit"
        )
    head = family_name(mechanism) + (f" — {title}" if title else "")
    ax.set_title(subtitle if own_figure else head + "\n" + subtitle, fontsize=9, color="0.3")
    if own_figure:
        fig.suptitle(head, fontsize=13)
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.1)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    handles, labels = ax.get_legend_handles_labels()
    shown = [(h, lab) for h, lab in zip(handles, labels, strict=True) if ", circuit" not in lab]
    if own_figure:
        fit_figure(fig, ax, extra=legend_height(len(shown)))
        if shown:
            legend_below(fig, *zip(*shown, strict=True))
    elif shown:
        # A caller's figure keeps its layout: the legend goes inside the axes.
        ax.legend(*zip(*shown, strict=True), loc="best", fontsize=7)

    # Everything drawn as a line (curves, paths, links, guide) is what the notes must not hide.
    lines = drawn_lines(ax)
    lines += _link_lines(drawn)  # with the coupler plate's edges
    center = np.nanmean(mine[0].motion.positions["P"], axis=0) if mine else np.zeros(2)
    place_notes(ax, notes, lines, center)
    return fig


# --------------------------------------------------------------------------------------------
# Motion diagrams
# --------------------------------------------------------------------------------------------


def speed_limit(speeds: list[Array]) -> float | None:
    """An upper y-limit clipping the spikes of |dP/dθ| next to input limit positions."""
    values = np.concatenate([s[np.isfinite(s)] for s in speeds]) if speeds else np.array([])
    if values.size == 0:
        return None
    top = float(values.max())
    typical = float(np.percentile(values, 90))
    return 1.6 * typical if top > 3.0 * typical > 0 else None


def plot_diagrams(mechanism: Mechanism, *, samples: int = 720, title: str | None = None) -> Figure:
    """Output, transmission angle and traced-point speed against the input angle.

    Three stacked panels over the circuit: the output (four-bar: angle of B − B0 from the frame
    line A0→B0, unwrapped, degrees; slider-crank: slider position along its line), the
    transmission angle γ (degrees) and the speed ``|dP/dθ|`` of the traced point (length per
    radian of input). Where the input only rocks, the circuit's two legs (up on the mechanism's
    assembly, back on the other branch) are drawn as separate lines: they share inputs but not
    outputs. Where the speed grows without bound next to a limit position the speed axis is
    clipped, and says so.

    Parameters
    ----------
    mechanism : Mechanism
        A single :class:`~linkwright.mechanisms.FourBar` or
        :class:`~linkwright.mechanisms.SliderCrank`.
    samples : int, optional
        Samples per circuit.
    title : str, optional
        Appended to the family name in the figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Three axes sharing the input axis (degrees). Lines are labelled ``"full turn"``, or
        ``"up (branch ±1)"`` and ``"back (branch ±1)"`` (``", circuit k"`` inserted for further
        circuits); each line is a leg of the closed circuit, its ends at limit positions.
    """
    require_single(mechanism)
    fig = new_figure((8.0, 9.0))
    axes = fig.subplots(3, 1, sharex=True)
    circuits = traced_circuits(mechanism, samples)
    slider = isinstance(mechanism, SliderCrank)
    speeds: list[Array] = []
    gammas: list[Array] = []

    for k, c in enumerate(circuits):
        m = c.motion
        closed = c.closed()  # sample indices of the closed circuit: 0, 1, …, n − 1, 0
        x = np.degrees(m.input[closed])
        if c.full:
            x[-1] = x[0] + 360.0
        out = _output(mechanism, m)[closed]
        if not slider:
            # Unwrapped along the whole closed circuit: a fully turning output ends 360° on.
            out = np.degrees(unwrap_finite(out))
        gamma = _transmission_angle_deg(mechanism, m)[closed]
        assert m.velocities is not None
        speed = plane.norm(m.velocities["P"])[closed]
        gammas.append(gamma)
        speeds.append(speed)
        circuit_name = "" if k == 0 else f", circuit {k + 1}"
        legs = (
            [np.arange(c.n + 1)]
            if c.full
            else [np.arange(c.upper + 1), np.arange(c.upper, c.n + 1)]
        )
        for j, leg in enumerate(legs):
            ls: LineStyleType
            if c.full:
                label, color, ls = "full turn" + circuit_name, CURVE_COLOR, "-"
            else:
                branch = m.branches.get("B")
                sgn = float(branch[closed[leg[1]]]) if branch is not None else 0.0
                label = ("up" if j == 0 else "back") + circuit_name
                if sgn:
                    label += f" (branch {'+1' if sgn > 0 else MINUS + '1'})"
                color = (CURVE_COLOR, LIMIT_COLOR)[j]
                ls = "-" if j == 0 else (0, (5, 2.5))
            if k > 0:
                color = ("tab:cyan", "tab:pink", "tab:olive")[(k - 1 + j) % 3]
            for ax, y in zip(axes, (out, gamma, speed), strict=True):
                ax.plot(x[leg], y[leg], color=color, ls=ls, lw=1.8, label=label)
        if not c.full:
            for i, side in ((0, "left"), (c.upper, "right")):
                at = math.degrees(float(m.input[i]))
                for ax in axes:
                    ax.axvline(at, color="0.45", lw=0.8, ls=":")
                axes[0].annotate(
                    f"limit {deg_text(at)}°",
                    xy=(at, 1.0),
                    xycoords=("data", "axes fraction"),
                    xytext=(3 if side == "left" else -3, -3),
                    textcoords="offset points",
                    fontsize=8,
                    va="top",
                    ha=side,
                    color="0.3",
                )

    if circuits:
        axes[1].axhline(90.0, color="0.5", lw=0.8, ls=":")
        g = np.concatenate(gammas)
        if np.isfinite(g).any():
            axes[1].set_title(
                f"sampled γ from {deg_text(np.nanmin(g))}° to {deg_text(np.nanmax(g))}° (90° is "
                "ideal)",
                loc="right",
                fontsize=8,
                color="0.3",
            )
        top = speed_limit(speeds)
        if top is not None:
            axes[2].set_ylim(0.0, top)
            axes[2].set_title(
                "axis clipped: |dP/dθ| grows without bound at the input limits",
                loc="right",
                fontsize=8,
                color="0.3",
            )
        else:
            axes[2].set_ylim(bottom=0.0)
        if not circuits[0].full or len(circuits) > 1:
            handles, labels = axes[0].get_legend_handles_labels()
            fig.legend(
                handles,
                labels,
                loc="outside lower center",
                ncols=min(len(labels), 4),
                fontsize=8.5,
                frameon=False,
            )
        else:
            start = math.degrees(float(circuits[0].motion.input[0]))
            axes[2].set_xlim(start, start + 360.0)
            axes[2].set_xticks(start + np.arange(0.0, 361.0, 45.0))
    else:
        axes[2].set_xlim(0.0, 360.0)
        axes[2].set_xticks(np.arange(0.0, 361.0, 45.0))
        for ax in axes:
            ax.set_yticks([])
            ax.text(
                0.5,
                0.5,
                "cannot assemble at any input",
                transform=ax.transAxes,
                ha="center",
                va="center",
                fontsize=11,
                color=LIMIT_COLOR,
            )

    axes[0].set_ylabel("slider position s" if slider else "output angle φ (°)")
    axes[1].set_ylabel("transmission angle γ (°)")
    axes[2].set_ylabel("|dP/dθ| (length/rad)")
    axes[2].set_xlabel("input angle θ (°)")
    for ax in axes:
        ax.grid(True, lw=0.4, alpha=0.5)
    output = (
        "slider position s along the line from the foot of A0"
        if slider
        else ("output φ: angle of B − B0 from the frame line A0→B0")
    )
    axes[0].set_title(f"{_dimensions(mechanism)}\n{output}", fontsize=9, color="0.3")
    fig.suptitle(
        f"{family_name(mechanism)} — motion diagrams" + (f" — {title}" if title else ""),
        fontsize=13,
    )
    return fig

"""Pictures of any linkage the engine builds, drawn from its construction plan.

The four-bar and slider-crank have their own annotated pictures (:mod:`linkwright.plot.planar`);
every other family (geared five-bar, double slider, six-bars, composed linkages) is drawn here
from the plan itself: each step says which joints a link joins, so the drawing needs no
per-family code. Figures are built without pyplot, as in the planar module.

What the main picture of any family marks (assembly modes, limit positions, dead centres,
transmission-angle extremes) is found by :mod:`linkwright.plot.features`; its public names are
re-exported here as before.
"""

from __future__ import annotations

import math
import re
import textwrap

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from numpy.typing import NDArray

from linkwright.analysis.general import point_speed
from linkwright.engine import (
    DyadRRP,
    Motion,
    Trammel,
)
from linkwright.geometry import plane
from linkwright.mechanisms import (
    Mechanism,
    circuit,
    solve,
)
from linkwright.plot.axes import check_axes, figure_of
from linkwright.plot.features import (
    MAX_MODE_DYADS,
    Features,
    closed_loop,
    find_features,
    input_status,
    mechanism_size,
    mode_curves,
    never_modes,
)
from linkwright.plot.notes import (
    Note,
    add_note,
    drawn_lines,
    fit_figure,
    legend_below,
    legend_height,
    place_notes,
)
from linkwright.plot.planar_draw import ground_symbol, label_joints
from linkwright.plot.style import GAMMA_COLOR, LIMIT_COLOR, LineKw, deg_text, new_figure

__all__ = [
    "Features",
    "draw_marks",
    "draw_pose",
    "family_title",
    "find_features",
    "input_status",
    "joint_letter",
    "mode_curves",
    "never_modes",
    "plot_linkage",
    "plot_speed",
]

Array = NDArray[np.float64]
LINK = "#1f3b57"
GROUND = "#6b6b6b"
BODY = "#9ecae1"
CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")
MINUS = "\N{MINUS SIGN}"

# The main picture's palette: the document's mode, the other modes, the marks.
OWN_COLOR = "tab:blue"
MODE_COLORS = ("tab:orange", "tab:green", "tab:pink", "tab:olive", "tab:cyan")
SECOND_PATH_COLOR = "0.45"
DEAD_COLOR = "#8c564b"


# --------------------------------------------------------------------------------------------
# The linkage at one pose
# --------------------------------------------------------------------------------------------


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


def joint_letter(name: str) -> str:
    """A joint's label: A0 as A with subscript 0; names that are not letters+digits as given."""
    found = re.fullmatch(r"([A-Za-z]+)(\d*)", name)
    if not found:
        return name
    letters, digits = found.groups()
    return f"${letters}_{{{digits}}}$" if digits else f"${letters}$"


def _pose_size(ax: Axes, pts: Array) -> float:
    """A twentieth of the drawing's extent (the pose joined with what the axes hold)."""
    pts = pts[np.all(np.isfinite(pts), axis=-1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    lim = ax.dataLim
    if np.all(np.isfinite([lim.x0, lim.x1, lim.y0, lim.y1])) and lim.width > 0:
        lo = np.minimum(lo, [lim.x0, lim.y0])
        hi = np.maximum(hi, [lim.x1, lim.y1])
    return 0.05 * max(float(np.max(hi - lo)), 1e-9)


def draw_pose(
    ax: Axes, mechanism: Mechanism, motion: Motion, k: int, *, alpha: float = 1.0
) -> None:
    """Draw the linkage at sample ``k`` of ``motion``: links, ground pivots, joint names.

    Links are thick lines, rigid bodies (a ternary link, a coupler point's triangle) filled,
    slider guides dashed. At full opacity ground pivots get the hatched ground symbol and every
    joint its letter, set in the widest gap between the links that meet there; a faded pose
    (``alpha < 1``, a ghost) draws triangles for the ground and no letters. Each joint's marker
    is a line labelled ``"_joint NAME"``, so its place can be read back.
    """
    pos = {name: p[k] for name, p in motion.positions.items()}
    finite = np.array([p for p in pos.values() if np.all(np.isfinite(p))])
    if not len(finite):
        return
    span = max(float(np.nanmax(np.ptp(finite, axis=0))), 1e-9)
    for at, angle in _guides(mechanism):
        d = np.array([np.cos(angle), np.sin(angle)]) * span
        ax.plot(*np.stack((pos[at] - d, pos[at] + d)).T, color=GROUND, lw=0.8, ls="--", alpha=alpha)
    for plate in mechanism.plan.plates:
        tri = np.stack([pos[j] for j in plate])
        if np.all(np.isfinite(tri)) and abs(plane.cross(tri[1] - tri[0], tri[2] - tri[0])) > 0:
            ax.add_patch(
                Polygon(
                    tri,
                    closed=True,
                    facecolor=BODY,
                    edgecolor="none",
                    alpha=0.5 * alpha,
                    zorder=3.4,
                )
            )
    pairs = mechanism.plan.links
    for a, b in pairs:
        ax.plot(
            *np.stack((pos[a], pos[b])).T,
            color=LINK,
            lw=2.6,
            alpha=alpha,
            solid_capstyle="round",
            zorder=4,
        )
    plan = mechanism.plan
    traced = set(plan.traced)
    size = _pose_size(ax, finite)
    ground = plan.ground
    for name in plan.joints:
        p = pos[name]
        if not np.all(np.isfinite(p)):
            continue
        is_ground = name in ground
        if is_ground and alpha == 1.0:
            ground_symbol(ax, p, size)
        style: LineKw = {"marker": "o", "ms": 7, "mfc": "white", "mec": LINK, "mew": 1.6}
        if is_ground and alpha < 1.0:
            style = {"marker": "^", "ms": 8, "mfc": GROUND, "mec": LINK, "mew": 1.0}
        elif name in traced:
            style["mfc"], style["mec"] = OWN_COLOR, "white"
        ax.plot(
            *p,
            **style,
            alpha=alpha,
            zorder=6,
            ls="none",
            label=f"_joint {name}",
        )
    if alpha != 1.0:
        return
    taken: dict[str, list[Array]] = {name: [] for name in pos}
    for a, b in pairs:
        if np.all(np.isfinite(pos[a])) and np.all(np.isfinite(pos[b])):
            taken[a].append(pos[b] - pos[a])
            taken[b].append(pos[a] - pos[b])
    for name in ground:
        taken[name] += [np.array([0.0, -1.0]), np.array([0.6, -1.0]), np.array([-0.6, -1.0])]
    for at, angle in _guides(mechanism):
        d = np.array([np.cos(angle), np.sin(angle)])
        taken[at] += [d, -d]
    shown = {n: p for n, p in pos.items() if np.all(np.isfinite(p))}
    label_joints(ax, shown, taken, {n: joint_letter(n) for n in shown})


# --------------------------------------------------------------------------------------------
# The main picture of a planar linkage
# --------------------------------------------------------------------------------------------


def draw_marks(
    ax: Axes,
    feats: Features,
    joint: str,
    notes: list[Note],
    tol: float,
    *,
    gamma_label: str = "γ extremes",
) -> None:
    """Markers on the traced curve for the limits, dead centres and γ extremes, with notes, and
    the output link drawn dashed at each dead centre."""
    styles = {
        "limit": ("D", LIMIT_COLOR, 8, "input limit positions"),
        "dead": ("s", DEAD_COLOR, 8, f"{joint} at dead centres"),
        "gmin": ("v", GAMMA_COLOR, 8, gamma_label),
        "gmax": ("^", GAMMA_COLOR, 8, gamma_label),
    }
    for kind, (marker, color, ms, label) in styles.items():
        marks = feats.of(kind)
        if not marks:
            continue
        xy = np.array([m.pose[joint] for m in marks])
        ax.plot(
            xy[:, 0],
            xy[:, 1],
            marker,
            ms=ms,
            mfc=color,
            mec="white",
            mew=0.9,
            ls="none",
            zorder=7.5,
            label=label if kind != "gmax" or not feats.of("gmin") else "_nolegend_",
        )
        for m in marks:
            add_note(notes, m.pose[joint], m.text, color, tol)
    dead = feats.of("dead")
    if dead and feats.output is not None:
        pivot, out = feats.output
        if pivot is not None:
            for m in dead:
                seg = np.stack((m.pose[pivot], m.pose[out]))
                ax.plot(*seg.T, color=DEAD_COLOR, lw=1.3, ls=(0, (4, 2)), zorder=3.5)
        ends = np.array([m.pose[out] for m in dead])
        ax.plot(
            ends[:, 0],
            ends[:, 1],
            "s",
            ms=6,
            mfc="white",
            mec=DEAD_COLOR,
            mew=1.4,
            ls="none",
            zorder=3.55,
            label=(
                f"output {pivot}{out} at its dead centres"
                if pivot is not None
                else f"slider {out} at the ends of its stroke"
            ),
        )


def plot_linkage(
    mechanism: Mechanism,
    *,
    samples: int = 720,
    title: str | None = None,
    ax: Axes | None = None,
    at: float | None = None,
) -> Figure:
    """The linkage at one pose, its traced curves in every assembly mode, and its marks.

    The curve of the first traced joint is drawn for each combination of branch signs (the
    document's own bold and solid, each other dashed in its own colour and named in the
    legend; a mode that traces the same closed curve as an earlier one says so), the other
    traced joints' curves on the document's mode only. On the document's mode the input's
    limit positions, the dead centres of the output link (and the output link there, dashed)
    and the transmission-angle extremes are marked on the curve and annotated; see the module
    docstring for what each means and which families have them.

    Parameters
    ----------
    mechanism : Mechanism
        One planar linkage (batch shape ``()``) of any family.
    samples : int
        Samples per circuit.
    title : str, optional
        The figure's title (the axes' title when ``ax`` is given).
    ax : matplotlib.axes.Axes, optional
        Draw into this axes (its figure keeps its size); a new figure is made otherwise.
    at : float, optional
        Input angle (radians) of the pose drawn, on the document's assembly: the pose of
        :func:`~linkwright.mechanisms.solve`. Default: the first sample of the first circuit
        (the lower limit where the input rocks).

    Returns
    -------
    matplotlib.figure.Figure
        A linkage that cannot be assembled at any input shows a note saying so; one that cannot
        at ``at`` shows its curves and says that no pose is drawn.

    Examples
    --------
    Paper 002's geared five-bar: both assembly modes, the pose at θ = 0 on the first:

    >>> from linkwright.io import load_example
    >>> fivebar = load_example("geared-fivebar").mechanism
    >>> ax = plot_linkage(fivebar, samples=90, at=0.0).axes[0]
    >>> sorted(ln.get_label() for ln in ax.lines if ln.get_label().startswith("assembly"))
    ['assembly +1', 'assembly −1']

    It has no output link, so no dead centres are marked:

    >>> any(ln.get_label().startswith("dead") for ln in ax.lines)
    False
    """
    own_figure = check_axes(ax) is None
    fig = new_figure((8.5, 7.0)) if ax is None else figure_of(ax)
    ax = ax or fig.add_subplot()
    feats = find_features(mechanism, samples)
    own = feats.own
    if not own.circuits and not any(m.circuits for m in feats.modes):
        ax.text(
            0.5,
            0.5,
            "this linkage cannot be assembled at any input",
            ha="center",
            transform=ax.transAxes,
        )
        return fig
    traced = mechanism.plan.traced
    first = traced[0]
    others = iter(MODE_COLORS)
    colors: dict[tuple[float, ...], str] = {}
    for mode, k, p, same in mode_curves(feats, first):
        style: LineKw
        if mode.own:
            style = {"color": OWN_COLOR, "lw": 2.3, "ls": "-", "zorder": 3.6}
        else:
            if mode.signs not in colors:
                colors[mode.signs] = next(others, "0.5")
            style = {"color": colors[mode.signs], "lw": 1.3, "ls": (0, (5, 3)), "zorder": 3.7}
        name = mode.label if len(feats.modes) > 1 else f"path of {first}"
        if same is not None and not mode.own:
            name += " (same curve)"
        ax.plot(*p.T, label=name if k == 0 else "_nolegend_", **style)
    for i, joint in enumerate(traced[1:]):
        for k, motion in enumerate(own.circuits):
            ax.plot(
                *closed_loop(motion.positions[joint]).T,
                color=SECOND_PATH_COLOR if i == 0 else CURVES[i % len(CURVES)],
                lw=1.1,
                ls=(0, (1, 1.5)),
                zorder=3.2,
                label=f"path of {joint}" if k == 0 else "_nolegend_",
            )
    notes: list[Note] = []
    tol = 0.02 * mechanism_size(mechanism)
    draw_marks(ax, feats, first, notes, tol)

    if at is None and own.circuits:
        pose, theta = own.circuits[0], float(own.circuits[0].input[0])
    else:
        theta = float(at) if at is not None else 0.0
        pose = solve(mechanism, [theta], order=1)
    placed = bool(pose.valid[0])
    if placed:
        draw_pose(ax, mechanism, pose, 0)
    else:
        # The step that fails says why, wrapped to stay inside the axes.
        why = mechanism.plan.unassembled(mechanism.params(), theta, points=mechanism.points)
        ax.text(
            0.5,
            0.5,
            f"cannot assemble at θ = {deg_text(math.degrees(theta))}°"
            + ("" if why is None else "\n" + textwrap.fill(why, 60)),
            transform=ax.transAxes,
            ha="center",
            va="center",
            color=LIMIT_COLOR,
        )

    status = input_status(own.arcs) if own.circuits else "the document's mode never assembles"
    lines = [status + (f"; pose at θ = {deg_text(math.degrees(theta))}°" if placed else "")]
    if len(feats.modes) > 1:
        lines.append("bold: the document's assembly; dashed: the others")
    never = never_modes(feats)
    if never:
        lines.append("never assembles: " + "; ".join(never))
    if not feats.every_mode and len(mechanism.plan.dyads) > MAX_MODE_DYADS:
        lines.append(
            f"only the document's assembly is drawn ({len(mechanism.plan.dyads)} dyads, "
            f"{2 ** len(mechanism.plan.dyads)} combinations)"
        )
    if feats.output is not None and feats.of("dead") and feats.output[0] is not None:
        lines.append(
            f"dead centres: where the output link {feats.output[0]}{feats.output[1]} stops"
        )
    name = family_title(mechanism)
    head = (
        title
        if title and name.lower() in title.lower()
        else (f"{name} — {title}" if title else name)
    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.08)
    ax.grid(True, lw=0.4, alpha=0.5)
    handles, labels = ax.get_legend_handles_labels()
    if own_figure:
        fig.suptitle(head, fontsize=13)
        ax.set_title("\n".join(lines), fontsize=9, color="0.3")
        fit_figure(fig, ax, extra=legend_height(len(labels)) + 0.15 * (len(lines) - 1))
        legend_below(fig, handles, labels)
    else:
        ax.set_title(head + "\n" + "\n".join(lines), fontsize=9)
        if handles:
            ax.legend(loc="best", fontsize=7)
    drawn = drawn_lines(ax)
    center = np.nanmean(own.circuits[0].positions[first], axis=0) if own.circuits else np.zeros(2)
    place_notes(ax, notes, drawn, center)
    return fig


FAMILY_TITLES = {
    "geared-fivebar": "Geared five-bar",
    "doubleslider": "Double slider",
    "watt1": "Watt I six-bar",
    "watt2": "Watt II six-bar",
    "stephenson1": "Stephenson I six-bar",
    "stephenson3": "Stephenson III six-bar",
    "linkage": "Linkage",
    "fourbar": "Four-bar",
    "slidercrank": "Slider-crank",
    "spherical-fourbar": "Spherical four-bar",
    "spherical-sixbar": "Spherical six-bar",
    "spherical-stephenson3": "Spherical Stephenson III six-bar",
}


def family_title(mechanism: Mechanism) -> str:
    return FAMILY_TITLES.get(mechanism.family, type(mechanism).__name__)


def plot_speed(
    mechanism: Mechanism, joint: str | None = None, *, samples: int = 720, ax: Axes | None = None
) -> Figure:
    """|dP/dθ| of a traced joint over the circuit, against the input (paper 002's velocity)."""
    joint = joint or mechanism.plan.traced[0]
    motion = circuit(mechanism, samples, order=1)
    fig = figure_of(ax) if ax is not None else new_figure((7, 3))
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

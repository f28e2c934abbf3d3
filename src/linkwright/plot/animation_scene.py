"""The pieces of a linkage's animation: the closed cycle its frames run, the scene (a figure,
its moving artists and how to move them to a frame), and the scene of a planar linkage.

The frames are samples of the closed circuit the machine runs
(:func:`linkwright.mechanisms.circuit`): a full turn where the input turns fully (several where
a gear ratio makes the linkage repeat only after several turns), else up to one limit position
and back down through the other branch of the dyad at that limit, so that the last frame leads
smoothly into the first. A planar scene holds fixed, equal-aspect axes that take in every frame;
the traced joints' curves are drawn faintly in full and boldly as far as the linkage has come,
and the input angle is written in a corner. The spherical scene is in
:mod:`linkwright.plot.animation_sphere`, the writers in :mod:`linkwright.plot.animation_writers`
and the verb in :mod:`linkwright.plot.animation`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon
from matplotlib.text import Text
from matplotlib.transforms import offset_copy
from numpy.typing import NDArray

from linkwright.engine import (
    DyadRRP,
    Fixed,
    Motion,
    Trammel,
)
from linkwright.mechanisms import Mechanism, circuit, input_range

__all__ = [
    "BLOCK",
    "CURVES",
    "CURVE_SAMPLES",
    "FAR_ALPHA",
    "GROUND",
    "LINK",
    "MINUS",
    "PLATE",
    "WIDTH_IN",
    "AnimationError",
    "Cycle",
    "Progress",
    "Scene",
    "add_titles",
    "angle_label",
    "corner_text",
    "cycle_note",
    "even_pixels",
    "exact_figure",
    "joint_labels",
    "joint_positions",
    "place_label",
    "plane_scene",
    "sample_cycle",
]

Array = NDArray[np.float64]


Progress = Callable[[float], None]


CURVE_SAMPLES = 360  # the circuit is sampled at least this finely, whatever the frame count


WIDTH_IN = 6.4  # every frame is this wide (inches at ``dpi``)


MINUS = "\N{MINUS SIGN}"


LINK = "#1f3b57"


GROUND = "#6b6b6b"


PLATE = "#9ecae1"


BLOCK = "#d9d9d9"


CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")


FAR_ALPHA = 0.4  # how much of its colour a far-side stroke keeps


class AnimationError(ValueError):
    """A request that cannot be animated (names the argument and the problem)."""


@dataclass(frozen=True)
class Cycle:
    """The closed circuit, sampled finely, and which of its samples are the frames.

    The frames are every ``step``-th sample of one fine circuit, so they lie on the curve drawn
    and the gap from the last frame back to the first is one step like every other.
    """

    motion: Motion  # the whole circuit, ``len(frames) * step`` samples, positions only
    frames: NDArray[np.int64]
    full: bool
    turns: int  # input turns before the linkage repeats (a full-turn circuit)

    @property
    def samples(self) -> int:
        return int(self.motion.input.shape[-1])


def sample_cycle(mechanism: Mechanism, frames: int) -> Cycle:
    arcs = input_range(mechanism)
    if bool(arcs.never):
        raise AnimationError(
            "mechanism: this linkage cannot be assembled at any input, so there is no motion "
            "to animate"
        )
    step = max(1, math.ceil(CURVE_SAMPLES / frames))
    motion = circuit(mechanism, frames * step, order=0)
    if not np.any(motion.valid):
        raise AnimationError(
            "mechanism: no pose of this linkage's circuit could be assembled, so there is "
            "nothing to animate"
        )
    full = bool(arcs.full)
    # One period of the input, or two where the circuit comes back on its other branch after
    # one (an exact deltoid, passing the meeting of its dyad's pivots): what the samples span.
    theta = motion.input[np.isfinite(motion.input)]
    span = float(theta[-1] - theta[0]) * motion.input.size / max(motion.input.size - 1, 1)
    turns = max(1, round(span / (2.0 * math.pi))) if full else 1
    return Cycle(motion, np.arange(frames) * step, full, turns)


def _deg(x: float) -> str:
    text = f"{x:.1f}"
    return "0.0" if text == "-0.0" else text.replace("-", MINUS)


def angle_label(cycle: Cycle, i: int) -> str:
    """What the corner says at frame ``i``: the input angle, and where in the cycle it is."""
    theta = cycle.motion.input
    j = int(cycle.frames[i])
    if cycle.full:
        turned = float(theta[j] - theta[0])
        text = f"θ = {_deg(math.degrees(float(theta[j])) % 360.0)}°"
        if cycle.turns > 1:
            turn = min(int(turned // (2.0 * math.pi)) + 1, cycle.turns)
            text += f"  (turn {turn} of {cycle.turns})"
    else:
        # Rocking: the input's next step says which leg of the circuit this is.
        rising = theta[(j + 1) % cycle.samples] > theta[j]
        text = f"θ = {_deg(math.degrees(float(theta[j])))}°  ({'up' if rising else 'back'})"
    if not cycle.motion.valid[j]:
        text += "\nnot assembled here"  # a change point: only the ground is drawn
    return text


def cycle_note(cycle: Cycle) -> str:
    if cycle.full:
        if cycle.turns > 1:
            return f"the input turns {cycle.turns} times before the linkage repeats"
        return "the input turns fully"
    theta = np.degrees(cycle.motion.input)
    return (
        f"the input rocks from {_deg(float(np.nanmin(theta)))}° to "
        f"{_deg(float(np.nanmax(theta)))}° and back, changing branch at its limits"
    )


@dataclass
class Scene:
    fig: Figure
    ax: Axes
    frames: int
    update: Callable[[int], None]
    dynamic: list[Artist] = field(default_factory=list)


def exact_figure(width_px: int, height_px: int, dpi: int) -> Figure:
    """A figure of exactly ``width_px × height_px`` pixels at ``dpi`` (no pyplot)."""
    # A hundredth of a pixel over: the canvas truncates the size, and w/dpi·dpi may round down.
    fig = Figure(figsize=((width_px + 0.01) / dpi, (height_px + 0.01) / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def even_pixels(x: float) -> int:
    """Pixels, rounded to an even count: H.264 in yuv420p needs even frame sizes."""
    return max(2, 2 * round(x / 2.0))


def add_titles(fig: Figure, title: str, note: str, top_px: float) -> None:
    h = fig.get_figheight() * fig.dpi
    fig.text(0.5, 1.0 - 0.12 * top_px / h, title, ha="center", va="top", fontsize=12)
    fig.text(0.5, 1.0 - 0.58 * top_px / h, note, ha="center", va="top", fontsize=8, color="0.35")


def corner_text(ax: Axes) -> Text:
    return ax.text(
        0.015,
        0.985,
        "",
        transform=ax.transAxes,
        ha="left",
        va="top",
        fontsize=10,
        family="DejaVu Sans Mono",
        zorder=9,
        bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": "0.7", "alpha": 0.9},
    )


def joint_labels(ax: Axes, names: list[str]) -> dict[str, Text]:
    where = offset_copy(ax.transData, fig=ax.get_figure(root=True), x=5, y=4, units="points")
    # A light box keeps a letter legible where it falls on a link or a curve. (A stroked halo
    # draws the letters as paths, and pixel snapping can then drop the foot of an "E".)
    box = {"boxstyle": "round,pad=0.12", "fc": "white", "ec": "none", "alpha": 0.75}
    return {
        name: ax.text(0, 0, name, transform=where, fontsize=8, color="0.1", zorder=8, bbox=box)
        for name in names
    }


def place_label(label: Text, xy: Array, alpha: float = 1.0) -> None:
    ok = bool(np.all(np.isfinite(xy)))
    label.set_visible(ok)  # a Text at NaN logs a warning instead of drawing
    if ok:
        label.set_position((float(xy[0]), float(xy[1])))
        label.set_alpha(alpha)


def joint_positions(mechanism: Mechanism, motion: Motion) -> dict[str, Array]:
    """Every joint over the circuit; the ground pivots everywhere, even at a sample where the
    linkage is not assembled (the engine masks the whole pose there)."""
    pos = {name: np.asarray(p, dtype=float) for name, p in motion.positions.items()}
    for step in mechanism.plan.steps:
        if isinstance(step, Fixed):
            p = pos[step.name]
            here = p[np.all(np.isfinite(p), axis=-1)]
            if len(here):
                pos[step.name] = np.broadcast_to(here[0], p.shape)
    return pos


def _line(ax: Axes, **style: Any) -> Line2D:
    """An empty line (or set of markers) whose data each frame sets."""
    return ax.plot([], [], **style)[0]


@dataclass(frozen=True)
class _Guide:
    """A slider's guide line: through joint ``at`` at ``angle``; ``slider`` runs on it."""

    at: str
    angle: float
    slider: Array  # the slider's positions over the circuit, (samples, 2)


def _plane_parts(
    mechanism: Mechanism, motion: Motion
) -> tuple[dict[str, Array], list[tuple[str, str]], list[tuple[str, ...]], list[_Guide], list[str]]:
    """Positions (with the far ends of trammel arms), links, plates, guides and pivots."""
    params = mechanism.params()

    def value(p: str | float) -> float:
        return float(np.asarray(params[p] if isinstance(p, str) else p))

    pos = joint_positions(mechanism, motion)
    pairs: list[tuple[str, str]] = []
    plates: list[tuple[str, ...]] = []
    guides: list[_Guide] = []
    # Links and plates as the steps declare them (a rigid point's sides are its plate's edges).
    plates += mechanism.plan.plates
    edges = {frozenset(pair) for plate in plates for pair in itertools.pairwise((*plate, plate[0]))}
    pairs += [pair for pair in mechanism.plan.links if frozenset(pair) not in edges]
    for step in mechanism.plan.steps:
        if isinstance(step, DyadRRP):
            guides.append(_Guide(step.line_point, value(step.line_angle), pos[step.name]))
        elif isinstance(step, Trammel):
            # The arm's far end runs on the second guide; it is no joint of the plan.
            phi = value(step.phase) + motion.input
            far = pos[step.name] + value(step.arm) * np.stack((np.cos(phi), np.sin(phi)), -1)
            end = f"{step.name}→"
            pos[end] = far
            pairs.append((step.name, end))
            guides += [
                _Guide(step.guide1, value(step.angle1), pos[step.name]),
                _Guide(step.guide2, value(step.angle2), far),
            ]
    used = {n for pair in pairs for n in pair} | {n for plate in plates for n in plate}
    pivots = [s.name for s in mechanism.plan.steps if isinstance(s, Fixed) and s.name in used]
    return pos, pairs, plates, guides, pivots


def _ground_symbol(ax: Axes, at: Array, size: float) -> None:
    """The drawing-office ground: a hatched triangle under the pivot on a short base line."""
    x, y = float(at[0]), float(at[1])
    h, w = 0.9 * size, 0.6 * size
    ax.add_patch(
        Polygon(
            [[x, y], [x - w, y - h], [x + w, y - h]],
            closed=True,
            facecolor="white",
            edgecolor=GROUND,
            hatch="////",
            lw=1.0,
            zorder=1.5,
        )
    )
    ax.plot([x - 1.5 * w, x + 1.5 * w], [y - h, y - h], color=GROUND, lw=1.4, zorder=1.5)


def _block(at: Array, angle: float, size: float) -> Array:
    """Corners of a slider block centred at ``at``, long side along the guide."""
    d = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-d[1], d[0]])
    a, b = 1.1 * size, 0.55 * size
    return np.array(
        [at + sa * a * d + sb * b * n for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    )


def plane_scene(mechanism: Mechanism, cycle: Cycle, title: str, dpi: int) -> Scene:
    motion = cycle.motion
    pos, pairs, plates, guides, pivots = _plane_parts(mechanism, motion)
    joints = [s.name for s in mechanism.plan.steps]
    moving = [s.name for s in mechanism.plan.steps if not isinstance(s, Fixed)]
    traced = list(mechanism.plan.traced)

    every = np.concatenate([p.reshape(-1, 2) for p in pos.values()])
    every = every[np.all(np.isfinite(every), axis=1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    span = max(float(np.max(hi - lo)), 1e-9)
    size = 0.035 * span  # ground symbols and slider blocks

    # Guides span the slider's whole travel (relative to the joint the guide runs through).
    guide_ends: list[tuple[float, float]] = []
    for g in guides:
        d = np.array([math.cos(g.angle), math.sin(g.angle)])
        s = (g.slider - pos[g.at]) @ d
        s = s[np.isfinite(s)]
        margin = 0.08 * span + 1.2 * size
        s0, s1 = (float(s.min()), float(s.max())) if s.size else (0.0, 0.0)
        guide_ends.append((s0 - margin, s1 + margin))
        for t in (s0 - margin, s1 + margin):
            ends = pos[g.at] + t * d
            every = np.concatenate((every, ends[np.all(np.isfinite(ends), axis=1)]))
    for name in pivots:
        p = pos[name][0]
        every = np.concatenate((every, [p - [1.0 * size, 1.0 * size], p + [0, 0]]))

    # Fixed limits over the whole cycle, padded for the letters, fitted to the axes' shape.
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.06 * max(float(np.max(hi - lo)), 1e-9)
    lo, hi = lo - pad, hi + pad
    box = hi - lo
    left, right, bottom, top = 0.62 * dpi, 0.2 * dpi, 0.42 * dpi, 0.72 * dpi
    width = even_pixels(WIDTH_IN * dpi)
    axes_w = width - left - right
    ratio = min(max(float(box[1] / box[0]), 0.35), 1.3)
    height = even_pixels(axes_w * ratio + bottom + top)
    axes_h = height - bottom - top
    ratio = axes_h / axes_w
    centre = 0.5 * (lo + hi)
    if box[1] / box[0] < ratio:
        box = np.array([box[0], box[0] * ratio])
    else:
        box = np.array([box[1] / ratio, box[1]])
    lo, hi = centre - 0.5 * box, centre + 0.5 * box

    fig = exact_figure(width, height, dpi)
    ax = fig.add_axes((left / width, bottom / height, axes_w / width, axes_h / height))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_autoscale_on(False)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.tick_params(labelsize=7)
    add_titles(fig, title, cycle_note(cycle), top)

    # Still: the ground and the traced curves in full, faint.
    for name in pivots:
        _ground_symbol(ax, pos[name][0], size)
    for k, name in enumerate(traced):
        p = pos[name]
        closed = np.concatenate((p, p[:1]))
        ax.plot(*closed.T, color=CURVES[k % len(CURVES)], lw=1.0, alpha=0.3, zorder=2)

    # Moving.
    guide_art = LineCollection([], colors=GROUND, linewidths=1.1, linestyles=(0, (6, 4)))
    guide_art.set_zorder(2.5)
    plate_art = PolyCollection(
        [], facecolors=to_rgba(PLATE, 0.6), edgecolors=LINK, linewidths=1.2, zorder=3
    )
    link_art = LineCollection([], colors=LINK, linewidths=3.2, capstyle="round", zorder=4)
    block_art = PolyCollection([], facecolors=BLOCK, edgecolors=LINK, linewidths=1.3, zorder=4.5)
    for art in (guide_art, plate_art, link_art, block_art):
        ax.add_collection(art, autolim=False)
    colours = [CURVES[k % len(CURVES)] for k in range(len(traced))]
    grown = [_line(ax, color=c, lw=2.2, zorder=3.6, solid_capstyle="round") for c in colours]
    pivot_art = _line(ax, marker="o", ms=7, mfc=GROUND, mec=LINK, mew=1.2, ls="none", zorder=5)
    joint_art = _line(ax, marker="o", ms=6.5, mfc="white", mec=LINK, mew=1.5, ls="none", zorder=5)
    tips = [
        _line(ax, marker="o", ms=7, mfc=c, mec="white", mew=1.0, ls="none", zorder=5.5)
        for c in colours
    ]
    # Ground points that are no pivot (a guide's reference point) go unlettered.
    labels = joint_labels(ax, [n for n in joints if n in pivots or n in moving])
    corner = corner_text(ax)

    def update(i: int) -> None:
        j = int(cycle.frames[i])
        at = {name: p[j] for name, p in pos.items()}

        def finite(*pts: Array) -> bool:
            return all(bool(np.all(np.isfinite(p))) for p in pts)

        segs = []
        for g, (s0, s1) in zip(guides, guide_ends, strict=True):
            d = np.array([math.cos(g.angle), math.sin(g.angle)])
            if finite(at[g.at]):
                segs.append([at[g.at] + s0 * d, at[g.at] + s1 * d])
        guide_art.set_segments(segs)
        plate_art.set_verts(
            [[at[a], at[b], at[c]] for a, b, c in plates if finite(at[a], at[b], at[c])]
        )
        link_art.set_segments([[at[a], at[b]] for a, b in pairs if finite(at[a], at[b])])
        block_art.set_verts(
            [_block(g.slider[j], g.angle, size) for g in guides if finite(g.slider[j])]
        )
        for line, tip, name in zip(grown, tips, traced, strict=True):
            line.set_data(*pos[name][: j + 1].T)  # the curve as far as the linkage has come
            tip.set_data([at[name][0]], [at[name][1]])
        pivot_art.set_data(*np.array([at[n] for n in pivots]).reshape(-1, 2).T)
        joint_art.set_data(*np.array([at[n] for n in moving]).reshape(-1, 2).T)
        for name, label in labels.items():
            place_label(label, at[name])
        corner.set_text(angle_label(cycle, i))

    dynamic: list[Artist] = [
        guide_art,
        plate_art,
        link_art,
        block_art,
        pivot_art,
        joint_art,
        corner,
    ]
    dynamic += grown + tips + list(labels.values())
    return Scene(fig, ax, len(cycle.frames), update, dynamic)

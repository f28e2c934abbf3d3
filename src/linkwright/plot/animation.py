"""Animations of a linkage running its circuit, written as a looping GIF or an MP4 film.

Each frame shows the linkage at one input of the closed circuit the machine runs
(:func:`linkwright.mechanisms.circuit`): a full turn where the input turns fully (several where
a gear ratio makes the linkage repeat only after several turns), else up to one limit position
and back down through the other branch of the dyad at that limit, so that the last frame leads
smoothly into the first and the film loops without a jump. The traced joints' curves are drawn
faintly in full and boldly as far as the linkage has come, and the input angle is written in a
corner. Planar linkages are drawn in the plane with fixed, equal-aspect axes that hold every
frame; spherical ones on an orthographic view of the unit sphere
(:class:`~linkwright.plot.sphere.SphereView` from :func:`~linkwright.plot.sphere.default_view`),
links as great-circle arcs, whatever lies on the far hemisphere dashed and faded.

Rendering is incremental: the figure, the backdrop and every artist are built once, the still
part is rendered once, and each frame only moves the artists' data and redraws them over it
(blitting) instead of redrawing the whole figure. Frames go to Pillow
(GIF, one shared palette, looping forever) or through matplotlib's
:class:`~matplotlib.animation.FFMpegWriter` to ffmpeg (MP4, H.264). The file is written under a
temporary name beside the destination and renamed over it at the end, so an interrupted render
never leaves a partial file at the destination.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import shutil
import subprocess
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib as mpl
import numpy as np
from matplotlib.animation import FFMpegWriter
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
from PIL import Image

from linkwright.engine import (
    DyadRRP,
    Fixed,
    Motion,
    Trammel,
)
from linkwright.files import atomic_path
from linkwright.mechanisms import Mechanism, circuit, input_range
from linkwright.plot.sphere import (
    SpherePlotError,
    SphereView,
    default_view,
    great_arc,
    plot_spherical_curves,
    stroke,
)
from linkwright.plot.sphere import _links as _sphere_links

__all__ = ["AnimationError", "animate"]

Array = NDArray[np.float64]
Progress = Callable[[float], None]

FORMATS = {".gif": "gif", ".mp4": "mp4"}
CURVE_SAMPLES = 360  # the circuit is sampled at least this finely, whatever the frame count
GIF_MAX_FPS = 50  # GIF delays are in hundredths of a second; viewers slow delays under 0.02 s
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


# --------------------------------------------------------------------------------------------
# The cycle
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Cycle:
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


def _cycle(mechanism: Mechanism, frames: int) -> _Cycle:
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
    return _Cycle(motion, np.arange(frames) * step, full, turns)


def _deg(x: float) -> str:
    text = f"{x:.1f}"
    return "0.0" if text == "-0.0" else text.replace("-", MINUS)


def _angle_label(cycle: _Cycle, i: int) -> str:
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


def _cycle_note(cycle: _Cycle) -> str:
    if cycle.full:
        if cycle.turns > 1:
            return f"the input turns {cycle.turns} times before the linkage repeats"
        return "the input turns fully"
    theta = np.degrees(cycle.motion.input)
    return (
        f"the input rocks from {_deg(float(np.nanmin(theta)))}° to "
        f"{_deg(float(np.nanmax(theta)))}° and back, changing branch at its limits"
    )


# --------------------------------------------------------------------------------------------
# Scenes: a figure, its moving artists, and how to move them to a frame
# --------------------------------------------------------------------------------------------


@dataclass
class _Scene:
    fig: Figure
    ax: Axes
    frames: int
    update: Callable[[int], None]
    dynamic: list[Artist] = field(default_factory=list)


def _figure(width_px: int, height_px: int, dpi: int) -> Figure:
    """A figure of exactly ``width_px × height_px`` pixels at ``dpi`` (no pyplot)."""
    # A hundredth of a pixel over: the canvas truncates the size, and w/dpi·dpi may round down.
    fig = Figure(figsize=((width_px + 0.01) / dpi, (height_px + 0.01) / dpi), dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def _even(x: float) -> int:
    """Pixels, rounded to an even count: H.264 in yuv420p needs even frame sizes."""
    return max(2, 2 * round(x / 2.0))


def _titles(fig: Figure, title: str, note: str, top_px: float) -> None:
    h = fig.get_figheight() * fig.dpi
    fig.text(0.5, 1.0 - 0.12 * top_px / h, title, ha="center", va="top", fontsize=12)
    fig.text(0.5, 1.0 - 0.58 * top_px / h, note, ha="center", va="top", fontsize=8, color="0.35")


def _corner(ax: Axes) -> Text:
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


def _labels(ax: Axes, names: list[str]) -> dict[str, Text]:
    where = offset_copy(ax.transData, fig=ax.figure, x=5, y=4, units="points")
    # A light box keeps a letter legible where it falls on a link or a curve. (A stroked halo
    # draws the letters as paths, and pixel snapping can then drop the foot of an "E".)
    box = {"boxstyle": "round,pad=0.12", "fc": "white", "ec": "none", "alpha": 0.75}
    return {
        name: ax.text(0, 0, name, transform=where, fontsize=8, color="0.1", zorder=8, bbox=box)
        for name in names
    }


def _place(label: Text, xy: Array, alpha: float = 1.0) -> None:
    ok = bool(np.all(np.isfinite(xy)))
    label.set_visible(ok)  # a Text at NaN logs a warning instead of drawing
    if ok:
        label.set_position((float(xy[0]), float(xy[1])))
        label.set_alpha(alpha)


def _positions(mechanism: Mechanism, motion: Motion) -> dict[str, Array]:
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


# --------------------------------------------------------------------------------------------
# Planar linkages
# --------------------------------------------------------------------------------------------


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

    pos = _positions(mechanism, motion)
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


def _plane_scene(mechanism: Mechanism, cycle: _Cycle, title: str, dpi: int) -> _Scene:
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
    width = _even(WIDTH_IN * dpi)
    axes_w = width - left - right
    ratio = min(max(float(box[1] / box[0]), 0.35), 1.3)
    height = _even(axes_w * ratio + bottom + top)
    axes_h = height - bottom - top
    ratio = axes_h / axes_w
    centre = 0.5 * (lo + hi)
    if box[1] / box[0] < ratio:
        box = np.array([box[0], box[0] * ratio])
    else:
        box = np.array([box[1] / ratio, box[1]])
    lo, hi = centre - 0.5 * box, centre + 0.5 * box

    fig = _figure(width, height, dpi)
    ax = fig.add_axes((left / width, bottom / height, axes_w / width, axes_h / height))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_autoscale_on(False)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.tick_params(labelsize=7)
    _titles(fig, title, _cycle_note(cycle), top)

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
    labels = _labels(ax, [n for n in joints if n in pivots or n in moving])
    corner = _corner(ax)

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
            _place(label, at[name])
        corner.set_text(_angle_label(cycle, i))

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
    return _Scene(fig, ax, len(cycle.frames), update, dynamic)


# --------------------------------------------------------------------------------------------
# Spherical linkages
# --------------------------------------------------------------------------------------------


def _up(ground: Array) -> Array:
    """The normal of the great circle through the ground pivots, towards +Z (else +Y, +X), so
    the frame is drawn level and the picture does not turn with the sign of a singular vector."""
    n = np.array([0.0, 0.0, 1.0])
    if len(ground) >= 2:
        _, s, vt = np.linalg.svd(ground)
        if s[1] > 1e-9 * s[0]:
            n = vt[-1]
    for axis in (2, 1, 0):
        if abs(float(n[axis])) > 1e-9:
            return n if n[axis] > 0 else -n
    return n


def _arcs(a: Array, b: Array, samples: int) -> Array:
    """Great arcs a→b for rows of endpoints, NaN rows where an arc is not drawable."""
    out = np.full(a.shape[:-1] + (samples, 3), np.nan)
    ok = np.all(np.isfinite(a), axis=-1) & np.all(np.isfinite(b), axis=-1)
    ok &= np.einsum("...k,...k->...", np.nan_to_num(a), np.nan_to_num(b)) > -1.0 + 1e-9
    if np.any(ok):
        # Nearly antipodal ends: leave that frame's arcs undrawn.
        with contextlib.suppress(SpherePlotError):
            out[ok] = great_arc(a[ok], b[ok], samples)
    return out


def _polyline(arcs: Array) -> Array:
    """Arcs (k, samples, 3) as one NaN-broken polyline, for one Line2D."""
    gap = np.full(arcs.shape[:-2] + (1, 3), np.nan)
    return np.concatenate((arcs, gap), axis=-2).reshape(-1, 3)


def _sphere_scene(mechanism: Mechanism, cycle: _Cycle, title: str, dpi: int) -> _Scene:
    motion = cycle.motion
    pos = _positions(mechanism, motion)
    steps = mechanism.plan.steps
    pairs, bodies = _sphere_links(mechanism)
    ground = [s.name for s in steps if isinstance(s, Fixed)]
    moving = [s.name for s in steps if not isinstance(s, Fixed)]
    traced = list(mechanism.plan.traced)
    ground_pts = np.array([pos[n][0] for n in ground]).reshape(-1, 3)

    eye = default_view(mechanism)
    up = _up(ground_pts)
    cam = SphereView(eye, up)

    top, side, bottom = 0.72 * dpi, 0.1 * dpi, 0.1 * dpi
    width = _even(WIDTH_IN * dpi)
    axes_w = width - 2 * side
    height = _even(axes_w + top + bottom)
    fig = _figure(width, height, dpi)
    axes_h = height - top - bottom
    ax = fig.add_axes((side / width, bottom / height, axes_w / width, axes_h / height))
    # The backdrop (outline, graticule, axis tips) from the sphere module, in the same view.
    plot_spherical_curves([], view=eye, up=up, ax=ax)
    ax.set_autoscale_on(False)
    _titles(fig, title, _cycle_note(cycle), top)

    # Still: the frame's arcs and the traced curves in full, faint.
    for a, b in itertools.pairwise(ground):
        arc = _arcs(pos[a][:1], pos[b][:1], 48)[0]
        if np.all(np.isfinite(arc)):
            stroke(ax, cam, arc, color=GROUND, lw=3.5, z=1.8)
    for k, name in enumerate(traced):
        p = pos[name]
        near, far = cam.split(np.concatenate((p, p[:1])))
        color = CURVES[k % len(CURVES)]
        ax.plot(*near.T, color=color, lw=1.0, alpha=0.35, zorder=2)
        ax.plot(*far.T, color=color, lw=0.8, ls=(0, (3, 2)), alpha=0.18, zorder=1.9)

    # Moving. Each stroke is a near and a far line; the far one dashed and faded.
    def pair_of_lines(color: str, lw: float, z: float) -> tuple[Line2D, Line2D]:
        near = ax.plot([], [], color=color, lw=lw, zorder=z, solid_capstyle="round")[0]
        far = ax.plot(
            [], [], color=color, lw=0.8 * lw, ls=(0, (3, 2)), alpha=FAR_ALPHA, zorder=z - 1
        )[0]
        return near, far

    body_art = PolyCollection([], edgecolors="none", zorder=1.5)
    ax.add_collection(body_art, autolim=False)
    edges = pair_of_lines(LINK, 1.2, 4.0)
    links = pair_of_lines(LINK, 2.4, 4.0)
    grown = [pair_of_lines(CURVES[k % len(CURVES)], 2.2, 3.6) for k in range(len(traced))]

    def markers(marker: str, ms: float, face: str, z: float) -> tuple[Line2D, Line2D]:
        style = {"marker": marker, "ms": ms, "mfc": face, "mec": LINK, "ls": "none", "zorder": z}
        return ax.plot([], [], **style)[0], ax.plot([], [], alpha=0.55, **style)[0]

    ground_art = markers("^", 9, GROUND, 7)
    joint_art = markers("o", 6, "white", 7)
    tips = [markers("o", 7, CURVES[k % len(CURVES)], 7.5) for k in range(len(traced))]
    labels = _labels(ax, [s.name for s in steps])
    corner = _corner(ax)
    body_face = np.array(to_rgba(PLATE))

    def show(pts: Array, art: tuple[Line2D, Line2D]) -> None:
        pts = pts.reshape(-1, 3)
        near = cam.depth(pts) >= 0
        art[0].set_data(*cam.xy(pts[near]).reshape(-1, 2).T)
        art[1].set_data(*cam.xy(pts[~near]).reshape(-1, 2).T)

    def split(p: Array, art: tuple[Line2D, Line2D]) -> None:
        near, far = cam.split(p)
        art[0].set_data(*near.T)
        art[1].set_data(*far.T)

    def update(i: int) -> None:
        j = int(cycle.frames[i])
        at = {name: p[j] for name, p in pos.items()}
        if pairs:
            a = np.array([at[x] for x, _ in pairs])
            b = np.array([at[y] for _, y in pairs])
            split(_polyline(_arcs(a, b, 24)), links)
        rings, faces, outline = [], [], []
        for o, t, p in bodies:
            ring = _arcs(np.array([at[o], at[t], at[p]]), np.array([at[t], at[p], at[o]]), 16)
            if not np.all(np.isfinite(ring)):
                continue
            outline.append(ring)
            rings.append(cam.xy(ring.reshape(-1, 3)))
            centre = at[o] + at[t] + at[p]
            faces.append(body_face * [1, 1, 1, 0.55 if cam.depth(centre) >= 0 else 0.2])
        body_art.set_verts(rings)
        body_art.set_facecolors(np.array(faces).reshape(-1, 4))
        split(_polyline(np.concatenate(outline)) if outline else np.zeros((0, 3)), edges)
        for art, name in zip(grown, traced, strict=True):
            split(pos[name][: j + 1], art)
        for art, name in zip(tips, traced, strict=True):
            show(at[name], art)
        show(np.array([at[n] for n in ground]), ground_art)
        show(np.array([at[n] for n in moving]), joint_art)
        for name, label in labels.items():
            p = at[name]
            near = bool(np.all(np.isfinite(p))) and float(cam.depth(p)) >= 0
            _place(label, cam.xy(p), 1.0 if near else 0.55)
        corner.set_text(_angle_label(cycle, i))

    dynamic: list[Artist] = [body_art, *edges, *links, *ground_art, *joint_art, corner]
    for pair in (*grown, *tips):
        dynamic += list(pair)
    dynamic += list(labels.values())
    return _Scene(fig, ax, len(cycle.frames), update, dynamic)


# --------------------------------------------------------------------------------------------
# Rendering and writing
# --------------------------------------------------------------------------------------------


class _Renderer:
    """Draws the still part of a scene once, then each frame's moving artists over a copy."""

    def __init__(self, scene: _Scene) -> None:
        self.scene = scene
        canvas = scene.fig.canvas
        assert isinstance(canvas, FigureCanvasAgg)
        self.canvas = canvas
        for art in scene.dynamic:
            art.set_animated(True)  # left out of the full draw below: that is the backdrop
        canvas.draw()
        self.background = canvas.copy_from_bbox(scene.fig.bbox)
        self.order = sorted(scene.dynamic, key=lambda a: a.get_zorder())

    def frame(self, i: int) -> NDArray[np.uint8]:
        """Frame ``i`` as an RGBA array (height, width, 4), opaque."""
        self.scene.update(i)
        self.canvas.restore_region(self.background)
        for art in self.order:
            self.scene.fig.draw_artist(art)
        return np.array(self.canvas.buffer_rgba(), dtype=np.uint8)


def _durations(frames: int, fps: int) -> list[int]:
    """Per-frame GIF delays (ms, whole hundredths of a second) whose running sum stays within
    half a hundredth of ``k / fps``, so the loop lasts exactly ``frames / fps`` seconds."""
    ticks = [round(k * 100 / fps) for k in range(frames + 1)]
    return [10 * (b - a) for a, b in itertools.pairwise(ticks)]


class _Palette:
    """One 256-colour palette for a whole GIF, and exact pixel → index mapping onto it.

    A frame is mostly a few flat colours (paper, links, plates, curves) and their antialiased
    blends. The most frequent colours of a few sample frames go into the palette as they are,
    so they come out unchanged; the rest of the palette is an octree quantisation of the
    remaining pixels. Every colour met is mapped once to its nearest palette entry (RGB
    distance) and remembered in a table indexed by the 24-bit colour. (Pillow's own mapping onto
    a given palette looks colours up at reduced precision, which turns white paper grey.)
    """

    EXACT = 192

    def __init__(self, sample: NDArray[np.uint8]) -> None:
        codes = _codes(sample)
        uniq, counts = np.unique(codes, return_counts=True)
        keep = uniq[np.argsort(-counts, kind="stable")[: self.EXACT]]
        colours = [_decode(keep)]
        rest = sample[..., :3].reshape(-1, 3)[~np.isin(codes.ravel(), keep)]
        if len(rest):
            octree = Image.fromarray(np.ascontiguousarray(rest.reshape(-1, 1, 3))).quantize(
                256 - len(keep), method=Image.Quantize.FASTOCTREE
            )
            used = sorted(i for _, i in octree.getcolors() or [])
            table = np.array(octree.getpalette() or [], dtype=np.int64).reshape(-1, 3)
            colours.append(table[used])
        self.colours = np.concatenate(colours)[:256]
        self.flat = self.colours.astype(np.uint8).ravel().tolist()
        self.flat += self.flat[-3:] * (256 - len(self.colours))
        self.table = np.full(1 << 24, -1, dtype=np.int16)
        self.table[keep] = np.arange(len(keep))

    def image(self, rgba: NDArray[np.uint8]) -> Image.Image:
        codes = _codes(rgba)
        index = self.table[codes]
        missing = index < 0
        if missing.any():
            new = np.unique(codes[missing])
            d = ((_decode(new)[:, None, :] - self.colours[None, :, :]) ** 2).sum(-1)
            self.table[new] = d.argmin(axis=1)
            index = self.table[codes]
        out = Image.fromarray(index.astype(np.uint8))
        out.putpalette(self.flat)
        return out


def _codes(rgba: NDArray[np.uint8]) -> NDArray[np.uint32]:
    """The 24-bit colour of each opaque RGBA pixel: R + 256·G + 65536·B (one read per pixel)."""
    return np.ascontiguousarray(rgba).view("<u4")[..., 0] & 0xFFFFFF


def _decode(codes: NDArray[np.uint32]) -> NDArray[np.int64]:
    c = codes.astype(np.int64)
    return np.stack((c & 255, (c >> 8) & 255, (c >> 16) & 255), axis=-1)


def _write_gif(scene: _Scene, target: Path, fps: int, progress: Progress | None) -> None:
    renderer = _Renderer(scene)
    n = scene.frames
    # One palette for the whole film, from frames spread over the cycle: the colours are the
    # same throughout, and a shared palette keeps them from flickering between frames.
    palette = _Palette(np.concatenate([renderer.frame(k) for k in sorted({0, n // 3, 2 * n // 3})]))
    images = []
    for i in range(n):
        images.append(palette.image(renderer.frame(i)))
        if progress is not None:
            progress((i + 1) / n)
    with open(target, "xb") as fh:
        images[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            loop=0,
            duration=_durations(n, fps),
        )
        fh.flush()
        os.fsync(fh.fileno())


def _ffmpeg() -> str:
    found = shutil.which(str(mpl.rcParams["animation.ffmpeg_path"]))
    if found is None:
        raise AnimationError(
            "out: writing an .mp4 needs ffmpeg, which was not found on PATH; install ffmpeg "
            "(e.g. `apt install ffmpeg`) or write a .gif instead"
        )
    return found


def _write_mp4(scene: _Scene, target: Path, fps: int, progress: Progress | None) -> None:
    renderer = _Renderer(scene)
    n = scene.frames
    # The frames, already rendered, are shown full size on a bare figure of the same pixel
    # size: grabbing that costs a copy, where grabbing the scene itself would redraw it whole.
    height, width = renderer.frame(0).shape[:2]
    sink = _figure(width, height, int(scene.fig.dpi))
    image = sink.figimage(np.zeros((height, width, 4), np.uint8), origin="upper")
    writer = FFMpegWriter(fps=fps, codec="h264")
    try:
        with writer.saving(sink, str(target), dpi=scene.fig.dpi):
            for i in range(n):
                image.set_data(renderer.frame(i))
                writer.grab_frame()
                if progress is not None:
                    progress((i + 1) / n)
    except subprocess.CalledProcessError as exc:
        raise AnimationError(f"out: ffmpeg failed to write the film: {exc}") from None
    with open(target, "rb") as fh:
        os.fsync(fh.fileno())


# --------------------------------------------------------------------------------------------
# The verb
# --------------------------------------------------------------------------------------------


def _positive_int(name: str, value: Any, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise AnimationError(f"{name}: must be an integer ≥ {least}, got {value!r}")
    return int(value)


def _check_mechanism(mechanism: Any) -> None:
    if not isinstance(mechanism, Mechanism):
        raise AnimationError(f"mechanism: expected a linkwright Mechanism, got {mechanism!r}")
    if mechanism.batch_shape != ():
        raise AnimationError(
            f"mechanism: animate one linkage at a time, this one has batch shape "
            f"{mechanism.batch_shape}"
        )
    try:
        mechanism.plan  # noqa: B018 - some inputs leave no construction plan
    except ValueError as exc:
        raise AnimationError(f"mechanism: cannot be animated: {exc}") from None


def animate(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    frames: int = 120,
    fps: int = 30,
    title: str | None = None,
    dpi: int = 100,
    progress: Callable[[float], None] | None = None,
) -> Path:
    """Write a film of the linkage running its closed circuit: a looping GIF or an MP4.

    Frame k shows the linkage at the k-th of ``frames`` poses spread evenly over the circuit the
    machine runs (:func:`~linkwright.mechanisms.circuit`): one full turn of the input (several
    where a gear ratio makes the linkage repeat only after several), or, where the input cannot
    turn fully, up to its limit and back down on the other branch, so that the last frame leads
    into the first and the film loops seamlessly. Links are drawn as lines, ternary links as
    filled plates, ground pivots on hatched ground symbols, sliders as blocks on dashed guides,
    joints as circles with their letters; the traced joints' curves are drawn faintly in full
    and boldly from the start of the circuit to the current pose, and the input angle θ
    (degrees) is written in the top left corner, with "up"/"back" for a rocking input. The axes
    are fixed over the film (they hold every pose) with equal aspect. A spherical linkage is
    drawn on the unit sphere seen from :func:`~linkwright.plot.sphere.default_view`, links as
    great-circle arcs, its far-side parts dashed and faded.

    Parameters
    ----------
    mechanism : Mechanism
        One planar or spherical linkage of any family (batch shape ``()``).
    out : str or os.PathLike
        Destination; its suffix chooses the format: ``.gif`` (Pillow; loops forever) or ``.mp4``
        (H.264 through ffmpeg, which must be on ``PATH``). Missing parent folders are created.
        The film is written under a temporary name in the same folder and renamed over ``out``
        when complete, so a render that fails or is interrupted leaves no partial file there.
    frames : int
        Number of frames, at least 2.
    fps : int
        Frames per second, at least 1 (at most 50 for a GIF, whose delays are whole hundredths
        of a second: they are spread so that the loop lasts ``frames / fps`` seconds).
    title : str, optional
        Heading of every frame; default the mechanism's family.
    dpi : int
        Resolution: frames are 6.4 inches wide, so ``6.4 · dpi`` pixels (rounded to an even
        count; the height follows the drawing and is even too).
    progress : callable, optional
        Called with the fraction of frames done (in (0, 1]) after each frame is rendered. An
        exception it raises stops the render (and no file is written).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    AnimationError
        For an unknown suffix, an ``.mp4`` without ffmpeg, ``frames < 2`` or another bad
        argument, a batch of mechanisms, a mechanism without a construction plan, or a linkage
        that cannot be assembled at any input.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = animate(crank_rocker, Path(folder) / "crank-rocker.gif", frames=6, dpi=40)
    ...     with Image.open(path) as gif:
    ...         print(path.name, gif.n_frames, gif.size, gif.info["loop"])
    crank-rocker.gif 6 (256, 220) 0

    A linkage that cannot be assembled has no motion to show:

    >>> too_short = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> animate(too_short, "never.gif")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.animation.AnimationError: mechanism: this linkage cannot be assembled at any ...
    """
    path = Path(out)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise AnimationError(
            f"out: write a .gif or an .mp4, not {path.suffix or 'a file without a suffix'!r}"
        )
    frames = _positive_int("frames", frames, 2)
    fps = _positive_int("fps", fps, 1)
    dpi = _positive_int("dpi", dpi, 10)
    if fmt == "gif" and fps > GIF_MAX_FPS:
        raise AnimationError(
            f"fps: a GIF plays at most {GIF_MAX_FPS} frames per second (its delays are whole "
            f"hundredths of a second, and viewers slow shorter ones), got {fps}; write an .mp4"
        )
    if fmt == "mp4":
        _ffmpeg()
    if path.is_dir():
        raise AnimationError(f"out: {str(path)!r} is a folder, not a file name")
    if progress is not None and not callable(progress):
        raise AnimationError(f"progress: must be callable, got {progress!r}")
    _check_mechanism(mechanism)
    cycle = _cycle(mechanism, frames)
    head = title if title is not None else mechanism.family
    if mechanism.space == "sphere":
        scene = _sphere_scene(mechanism, cycle, head, dpi)
    else:
        scene = _plane_scene(mechanism, cycle, head, dpi)

    with atomic_path(path) as temp:
        if fmt == "gif":
            _write_gif(scene, temp, fps, progress)
        else:
            _write_mp4(scene, temp, fps, progress)
    return path

"""Notes and legends that keep out of the drawing's way.

A note is a few lines of text that belong to a point (a dead centre, a transmission-angle
extreme); :func:`place_notes` puts each one where it overlaps the least ink (curves, links,
other notes) near its point, then :func:`fit_figure` grows the axes to take them in. Legends sit
below the axes in columns (:func:`legend_below`), with room reserved by :func:`legend_height`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from linkwright.plot.style import MIXED_NOTE_COLOR, Array

__all__ = [
    "LEGEND_COLUMNS",
    "Note",
    "add_note",
    "drawn_lines",
    "fit_figure",
    "legend_below",
    "legend_height",
    "place_notes",
]


HAlign = Literal["left", "right", "center"]
VAlign = Literal["bottom", "top", "center"]


@dataclass
class Note:
    xy: Array
    lines: list[str]
    color: str


def add_note(notes: list[Note], xy: Array, text: str, color: str, tol: float) -> None:
    """Collect an annotation, merging it into one already placed at (nearly) the same point."""
    for note in notes:
        if float(np.hypot(*(note.xy - xy))) <= tol:
            if text not in note.lines:
                note.lines.append(text)
                if note.color != color:
                    note.color = MIXED_NOTE_COLOR  # one colour would claim every line
            return
    notes.append(Note(np.asarray(xy, float), [text], color))


def _overlap(a: Bbox, b: Bbox) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return float(max(w, 0.0) * max(h, 0.0))


def _ink(segments: Array, box: Bbox) -> float:
    """Total length (display units) of the segments ``(x0, y0, x1, y1)`` inside ``box``.

    Liang–Barsky clipping, vectorised over the segments.
    """
    if not len(segments):
        return 0.0
    x0, y0, x1, y1 = segments.T
    dx, dy = x1 - x0, y1 - y0
    t0 = np.zeros(len(segments))
    t1 = np.ones(len(segments))
    keep = np.ones(len(segments), dtype=bool)
    for p, q in ((-dx, x0 - box.x0), (dx, box.x1 - x0), (-dy, y0 - box.y0), (dy, box.y1 - y0)):
        parallel = p == 0.0
        keep &= ~(parallel & (q < 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(parallel, 0.0, q / np.where(parallel, 1.0, p))
        t0 = np.where(~parallel & (p < 0.0), np.maximum(t0, r), t0)
        t1 = np.where(~parallel & (p > 0.0), np.minimum(t1, r), t1)
    inside = keep & (t1 > t0)
    return float(np.sum((t1 - t0)[inside] * np.hypot(dx, dy)[inside]))


def drawn_lines(ax: Axes) -> list[Array]:
    """Every polyline of ``ax`` drawn as a line (markers alone left out), in data coordinates:
    the ink that :func:`place_notes` keeps its notes off."""
    out = []
    for line in ax.lines:
        if line.get_linestyle() in ("None", "none", " ", ""):
            continue
        xy = np.asarray(line.get_xydata(), float)
        if len(xy) > 1:
            out.append(xy)
    return out


def place_notes(ax: Axes, notes: Sequence[Note], lines: Sequence[Array], center: Array) -> None:
    """Annotate each note with a leader line, choosing the offset that hides the least.

    The figure is laid out once first (notes stay out of the layout), then for each note a ring
    of candidate offsets is scored on overlap with text already placed (joint letters, legend,
    earlier notes), with the drawing (``lines``: polylines in data coordinates), with the axes'
    edge, and on distance from the point.
    """
    if not notes:
        return
    fig = ax.get_figure(root=True)
    assert fig is not None
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    legend = ax.get_legend()
    boxes: list[Bbox] = [t.get_window_extent(renderer) for t in ax.texts if t.get_text()]
    if legend is not None:
        box = legend.get_window_extent(renderer)
        boxes.append(box)
        # Freeze the legend where "best" put it: the notes must not push it elsewhere.
        legend.set_loc(tuple(ax.transAxes.inverted().transform((box.x0, box.y0))))
    axbox = ax.get_window_extent(renderer)
    segs = []
    for line in lines:
        d = ax.transData.transform(np.asarray(line, float).reshape(-1, 2))
        seg = np.concatenate([d[:-1], d[1:]], axis=1)
        segs.append(seg[np.isfinite(seg).all(axis=1)])
    segments = np.concatenate(segs) if segs else np.empty((0, 4))
    c_disp = ax.transData.transform(center)
    px_per_pt = fig.dpi / 72.0
    pad = 0.2 * 8.5 * px_per_pt + 3.0  # the label's rounded box, and some air
    for note in notes:
        xy_disp = ax.transData.transform(note.xy)
        away = xy_disp - c_disp
        away_angle = math.atan2(away[1], away[0]) if np.hypot(*away) > 0 else math.pi / 2
        ann = ax.annotate(
            "\n".join(note.lines),
            xy=(float(note.xy[0]), float(note.xy[1])),
            xytext=(0.0, 0.0),
            textcoords="offset points",
            fontsize=8.5,
            color=note.color,
            arrowprops={"arrowstyle": "-", "color": note.color, "lw": 0.8, "shrinkB": 4},
            bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.85},
            zorder=9,
        )
        ann.set_in_layout(False)
        # Measure the text once (Text's own extent, without the leader line), then slide it.
        ext = Text.get_window_extent(ann, renderer)
        w, h = ext.width + 2.0 * pad, ext.height + 2.0 * pad
        best: tuple[float, tuple[float, float], HAlign, VAlign, Bbox] | None = None
        for radius in (22.0, 34.0, 50.0, 70.0):
            for k in range(24):
                ang = away_angle + 2.0 * math.pi * k / 24.0
                off = (radius * math.cos(ang), radius * math.sin(ang))
                ha: HAlign = "left" if off[0] > 6 else ("right" if off[0] < -6 else "center")
                va: VAlign = "bottom" if off[1] > 6 else ("top" if off[1] < -6 else "center")
                ax_ = xy_disp[0] + off[0] * px_per_pt
                ay_ = xy_disp[1] + off[1] * px_per_pt
                x0 = {"left": ax_ - pad, "right": ax_ - w + pad, "center": ax_ - w / 2}[ha]
                y0 = {"bottom": ay_ - pad, "top": ay_ - h + pad, "center": ay_ - h / 2}[va]
                bb = Bbox.from_bounds(x0, y0, w, h)
                covered = sum(_overlap(bb, other) for other in boxes)
                outside = w * h - _overlap(bb, axbox)
                turn = abs((ang - away_angle + math.pi) % (2.0 * math.pi) - math.pi)
                score = (
                    15.0 * _ink(segments, bb)
                    + 4.0 * covered
                    + 6.0 * outside
                    + 2.0 * radius * px_per_pt
                    + 25.0 * turn
                )
                if best is None or score < best[0]:
                    best = (score, off, ha, va, bb)
        assert best is not None
        _, off, ha, va, bb = best
        ann.xyann = off
        ann.set_horizontalalignment(ha)
        ann.set_verticalalignment(va)
        boxes.append(bb)


def fit_figure(fig: Figure, ax: Axes, width: float = 8.5, *, extra: float = 0.0) -> None:
    """Size the figure so the equal-aspect drawing fills its axes (``extra`` inches of height
    for what sits outside it, e.g. a legend below)."""
    box = ax.dataLim
    ratio = box.height / box.width if box.width > 0 else 1.0
    ratio = min(max(ratio, 0.4), 1.1)
    fig.set_size_inches(width, 0.84 * width * ratio + 1.6 + extra)


LEGEND_COLUMNS = 3


def legend_height(count: int) -> float:
    """Inches a legend of ``count`` entries takes below the drawing."""
    return 0.25 * math.ceil(count / LEGEND_COLUMNS) + 0.15 if count else 0.0


def legend_below(fig: Figure, handles: Sequence[Artist], labels: Sequence[str]) -> None:
    """The figure's legend under the drawing, where it cannot hide a curve."""
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=min(LEGEND_COLUMNS, len(labels)),
            fontsize=8.5,
            frameon=False,
        )

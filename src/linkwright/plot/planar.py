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
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from matplotlib.text import Text
from matplotlib.transforms import Bbox
from numpy.typing import NDArray

from linkwright.analysis import transmission_angle
from linkwright.engine import Motion, evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, Mechanism, SliderCrank, circuit, circuits
from linkwright.mechanisms.registry import family_of

__all__ = ["draw_linkage", "plot_curves", "plot_diagrams", "save_figure"]

Array = NDArray[np.float64]

MINUS = "\N{MINUS SIGN}"

# Colours and styles (one palette for every picture).
CURVE_COLOR = "tab:blue"
OTHER_COLOR = "tab:orange"
LIMIT_COLOR = "tab:red"
GAMMA_COLOR = "tab:purple"
LINK_COLOR = "0.15"
COUPLER_FACE = "#9ecae1"
GROUND_COLOR = "0.35"
MIXED_NOTE_COLOR = "0.2"


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A figure with its own Agg canvas: no pyplot, no global backend switch."""
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _require_single(mechanism: Mechanism) -> None:
    if not isinstance(mechanism, FourBar | SliderCrank):
        raise TypeError(
            f"only FourBar and SliderCrank can be drawn, got {type(mechanism).__name__}"
        )
    if mechanism.batch_shape != ():
        raise ValueError(
            f"draw one linkage at a time; this mechanism has batch shape {mechanism.batch_shape}"
        )


def _family_name(mechanism: Mechanism) -> str:
    return family_of(mechanism).display


def _sign_label(sign: float) -> str:
    return f"assembly {'+1' if sign > 0 else MINUS + '1'}"


def _fmt(x: float) -> str:
    """A number for a caption: up to 4 significant digits, no trailing zeros, true minus."""
    text = f"{x:.4g}"
    return text.replace("-", MINUS)


def _deg(x: float) -> str:
    """An angle in degrees for a caption: one decimal, true minus (never "−0.0")."""
    return f"{round(float(x), 1) + 0.0:.1f}".replace("-", MINUS)


def _dimensions(mechanism: Mechanism) -> str:
    if isinstance(mechanism, FourBar):
        return (
            f"frame {_fmt(float(mechanism.frame))}, crank {_fmt(float(mechanism.crank))}, "
            f"coupler {_fmt(float(mechanism.coupler))}, rocker {_fmt(float(mechanism.rocker))}, "
            f"P = ({_fmt(float(mechanism.u))}, {_fmt(float(mechanism.v))})"
        )
    assert isinstance(mechanism, SliderCrank)
    return (
        f"crank {_fmt(float(mechanism.crank))}, rod {_fmt(float(mechanism.rod))}, "
        f"offset {_fmt(float(mechanism.offset))}, "
        f"line at {_deg(math.degrees(float(mechanism.line_angle)))}°, "
        f"P = ({_fmt(float(mechanism.u))}, {_fmt(float(mechanism.v))})"
    )


def _ground_points(mechanism: Mechanism) -> dict[str, Array]:
    if isinstance(mechanism, FourBar):
        return {"A0": np.asarray(mechanism.A0, float), "B0": np.asarray(mechanism.B0, float)}
    return {"A0": np.asarray(mechanism.A0, float)}


def _symbol_size(ax: Axes, mechanism: Mechanism, pose: Motion) -> float:
    """Size of the ground symbols and slider block: a twentieth of the drawing's extent.

    The extent is that of what the axes already hold (e.g. coupler curves) joined with the
    linkage's own reach, so the symbols read the same at any zoom of the picture.
    """
    pts = [p[0] for p in pose.positions.values() if np.all(np.isfinite(p[0]))]
    pts += list(_ground_points(mechanism).values())
    pts = np.array(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    lim = ax.dataLim
    if np.all(np.isfinite([lim.x0, lim.x1, lim.y0, lim.y1])) and lim.width > 0:
        lo = np.minimum(lo, [lim.x0, lim.y0])
        hi = np.maximum(hi, [lim.x1, lim.y1])
    reach = float(np.max(hi - lo))
    if isinstance(mechanism, FourBar):
        reach = max(reach, float(mechanism.crank + mechanism.frame))
    else:
        assert isinstance(mechanism, SliderCrank)
        reach = max(reach, float(mechanism.crank + mechanism.rod))
    return 0.05 * reach


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


def _unwrap_finite(a: Array) -> Array:
    out = a.copy()
    ok = np.isfinite(a)
    if ok.any():
        out[ok] = np.unwrap(a[ok])
    return out


@dataclass(frozen=True)
class _Circuit:
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
        return np.r_[np.arange(self.n), 0]


def _circuits(mechanism: Mechanism, samples: int, order: int = 1) -> list[_Circuit]:
    arcs, motions = circuits(mechanism, samples, order=order)
    return [_Circuit(m, bool(arcs.full)) for m in motions]


def _pose(mechanism: Mechanism, theta: float, motion: Motion | None) -> Motion:
    """The one-sample motion drawn at ``theta``, on the branch ``motion`` is on nearest to it."""
    branches = None
    if motion is not None and motion.input.ndim == 1 and motion.valid.any():
        d = np.abs((theta - motion.input + np.pi) % (2.0 * np.pi) - np.pi)
        d = np.where(motion.valid, d, np.inf)
        i = int(np.argmin(d))
        if d[i] <= 1e-12:
            return Motion(
                input=motion.input[i : i + 1],
                positions={k: v[i : i + 1] for k, v in motion.positions.items()},
                velocities=(
                    None
                    if motion.velocities is None
                    else {k: v[i : i + 1] for k, v in motion.velocities.items()}
                ),
                accelerations=None,
                valid=motion.valid[i : i + 1],
                regular=motion.regular[i : i + 1],
                branches={k: v[i : i + 1] for k, v in motion.branches.items()},
            )
        branches = {k: v[i : i + 1] for k, v in motion.branches.items()}
    return evaluate(
        mechanism.plan,
        mechanism.params(),
        np.array([theta]),
        points=mechanism.points,
        branches=branches,
        order=1,
    )


# --------------------------------------------------------------------------------------------
# The linkage
# --------------------------------------------------------------------------------------------


def _ground_symbol(ax: Axes, at: Array, size: float, *, zorder: float = 3.0) -> None:
    """A hatched ground triangle hanging below the pivot, with its base line."""
    x, y = at
    h = 0.55 * size
    w = 0.45 * size
    tri = Polygon(
        [[x, y], [x - w, y - h], [x + w, y - h]],
        closed=True,
        facecolor="white",
        edgecolor=GROUND_COLOR,
        hatch="////",
        linewidth=1.2,
        zorder=zorder,
    )
    ax.add_patch(tri)
    ax.plot([x - 1.5 * w, x + 1.5 * w], [y - h, y - h], color=GROUND_COLOR, lw=1.5, zorder=zorder)
    # The hatch itself below the base line, the usual drawing-office symbol.
    for k in range(7):
        x0 = x - 1.5 * w + k * (3.0 * w / 6.0)
        ax.plot(
            [x0, x0 - 0.35 * w],
            [y - h, y - h - 0.35 * w],
            color=GROUND_COLOR,
            lw=0.9,
            zorder=zorder,
        )


def _slider_guide(ax: Axes, mechanism: SliderCrank, extent: tuple[float, float]) -> None:
    d = mechanism.direction
    foot = np.asarray(mechanism.A0, float) - float(mechanism.offset) * plane.perp(d)
    s0, s1 = extent
    p0, p1 = foot + s0 * d, foot + s1 * d
    ax.plot(
        [p0[0], p1[0]],
        [p0[1], p1[1]],
        ls=(0, (6, 4)),
        color=GROUND_COLOR,
        lw=1.2,
        zorder=1.5,
        label="_guide",
    )


def _slider_extent(
    mechanism: SliderCrank, motion: Motion | None, here: Array | None
) -> tuple[float, float]:
    """Along-line span of the guide: the slider's travel in both assembly modes, with a margin."""
    travel = [np.zeros(1)]  # the foot of A0
    refs = [circuit(mechanism.with_assembly(s), 180, order=0) for s in (1.0, -1.0)]
    for m in (*refs, motion):
        if m is not None and m.valid.any():
            travel.append(mechanism.slider_position(m)[m.valid])
    if here is not None:
        travel.append(np.atleast_1d(here))
    s = np.concatenate(travel)
    margin = 0.3 * float(min(mechanism.crank, mechanism.rod))
    return float(s.min() - margin), float(s.max() + margin)


def _slider_block(ax: Axes, mechanism: SliderCrank, at: Array, size: float) -> None:
    d = mechanism.direction
    n = plane.perp(d)
    a, b = 0.65 * size, 0.32 * size
    corners = [at + sa * a * d + sb * b * n for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    ax.add_patch(
        Polygon(corners, closed=True, facecolor="0.85", edgecolor=LINK_COLOR, lw=1.5, zorder=4)
    )


def _label_joints(
    ax: Axes,
    pts: dict[str, Array],
    taken: dict[str, list[Array]],
    texts: dict[str, str] | None = None,
    distance: dict[str, float] | None = None,
) -> None:
    """Letter each joint in the widest free angle between the lines that meet there."""
    texts = texts or {}
    distance = distance or {}
    for name, p in pts.items():
        angles: list[float] = []
        for t in taken.get(name, []):
            if float(np.hypot(*t)) <= 1e-12:
                continue
            a = math.atan2(t[1], t[0])
            # Two links along one line (a point on a link's extension) leave one direction.
            if all(abs((a - b + math.pi) % (2.0 * math.pi) - math.pi) > 1e-9 for b in angles):
                angles.append(a)
        angles.sort()
        if not angles:
            bisector = math.pi / 2
        else:
            gaps = (
                [
                    (angles[(i + 1) % len(angles)] - a) % (2.0 * math.pi)
                    for i, a in enumerate(angles)
                ]
                if len(angles) > 1
                else [2.0 * math.pi]
            )
            i = int(np.argmax(gaps))
            bisector = angles[i] + 0.5 * gaps[i]
        r = distance.get(name, 13.0)
        text = texts.get(name) or {"A0": "$A_0$", "B0": "$B_0$"}.get(name, f"${name}$")
        ax.annotate(
            text,
            xy=p,
            xytext=(r * math.cos(bisector), r * math.sin(bisector)),
            textcoords="offset points",
            ha="center",
            va="center",
            fontsize=11,
            color="0.1",
            zorder=7,
        )


def _incident(pts: dict[str, Array], mechanism: Mechanism) -> dict[str, list[Array]]:
    """For each joint, the directions of what is drawn from it (links, ground, guide)."""
    down = np.array([0.0, -1.0])
    out: dict[str, list[Array]] = {k: [] for k in pts}
    pairs = [("A0", "A"), ("A", "B"), ("B", "P"), ("P", "A"), ("B0", "B"), ("A0", "B0")]
    for a, b in pairs:
        if a in pts and b in pts:
            out[a].append(pts[b] - pts[a])
            out[b].append(pts[a] - pts[b])
    for g in ("A0", "B0"):
        if g in out:
            out[g] += [down, np.array([0.6, -1.0]), np.array([-0.6, -1.0])]
    if isinstance(mechanism, SliderCrank) and "B" in out:
        d = mechanism.direction
        out["B"] += [
            d,
            -d,
            d + 0.5 * plane.perp(d),
            -d + 0.5 * plane.perp(d),
            d - 0.5 * plane.perp(d),
            -d - 0.5 * plane.perp(d),
        ]
    return out


def draw_linkage(
    ax: Axes, mechanism: Mechanism, theta: float, *, motion: Motion | None = None
) -> dict[str, Array]:
    """Draw the linkage at input angle ``theta`` on ``ax``.

    Ground pivots are hatched triangles, the crank and rocker thick lines, the coupler (or the
    slider-crank's rod) a filled triangle A–B–P, the slider a small block on its dashed guide
    line, joints white circles labelled with their letters. Where the linkage cannot be
    assembled at ``theta`` only the ground is drawn, with a note saying so. The axes get an
    equal aspect, so the linkage is not distorted.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    mechanism : Mechanism
        A single (unbatched) :class:`~linkwright.mechanisms.FourBar` or
        :class:`~linkwright.mechanisms.SliderCrank`.
    theta : float
        Input angle, radians.
    motion : Motion, optional
        A motion of this mechanism (e.g. its :func:`~linkwright.mechanisms.circuit`). The pose is
        taken on the branch that motion is on at its sample nearest ``theta``: on the return leg
        of a circuit this is the other branch of the dyad. Without it the mechanism's own
        assembly is used. For a slider-crank the guide line also spans the motion's travel.

    Returns
    -------
    dict of str to numpy.ndarray
        The drawn joints' positions, each of shape ``(2,)``; only the ground pivots when the
        linkage cannot be assembled at ``theta``.

    Raises
    ------
    TypeError
        For a family that has no drawing.
    ValueError
        For a batch of mechanisms.
    """
    _require_single(mechanism)
    theta = float(theta)
    pose = _pose(mechanism, theta, motion)
    ok = bool(pose.valid[0])
    ground = _ground_points(mechanism)
    pts = {k: v[0] for k, v in pose.positions.items()} if ok else {}

    if isinstance(mechanism, SliderCrank):
        here = mechanism.slider_position(pose)[0] if ok else None
        _slider_guide(ax, mechanism, _slider_extent(mechanism, motion, here))
    size = _symbol_size(ax, mechanism, pose)
    for p in ground.values():
        _ground_symbol(ax, p, size)

    if not ok:
        for p in ground.values():
            ax.plot(*p, "o", ms=8, mfc="white", mec=LINK_COLOR, mew=1.8, zorder=6)
        _label_joints(ax, ground, _incident(ground, mechanism))
        ax.text(
            0.5,
            0.5,
            f"cannot assemble at θ = {_deg(math.degrees(theta))}°",
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=12,
            color=LIMIT_COLOR,
            bbox={"boxstyle": "round", "fc": "white", "ec": LIMIT_COLOR, "alpha": 0.9},
            zorder=8,
        )
        if isinstance(mechanism, FourBar):
            # Keep both pivots in view even with nothing else drawn.
            a0, b0 = ground["A0"], ground["B0"]
            ax.plot([a0[0], b0[0]], [a0[1], b0[1]], ls="-.", lw=0.8, color=GROUND_COLOR, zorder=1)
        return dict(ground)

    a, b, p = pts["A"], pts["B"], pts["P"]
    a0 = pts["A0"]
    link = {"color": LINK_COLOR, "lw": 4.0, "solid_capstyle": "round", "zorder": 4}
    ax.plot([a0[0], a[0]], [a0[1], a[1]], **link)
    if isinstance(mechanism, FourBar):
        b0 = pts["B0"]
        ax.plot([b0[0], b[0]], [b0[1], b[1]], **link)
        ax.plot([a0[0], b0[0]], [a0[1], b0[1]], ls="-.", lw=0.8, color=GROUND_COLOR, zorder=1)
    label = f"linkage at θ = {_deg(math.degrees(theta))}°"
    ax.add_patch(
        Polygon(
            [a, b, p],
            closed=True,
            facecolor=COUPLER_FACE,
            edgecolor=LINK_COLOR,
            alpha=0.55,
            lw=1.5,
            joinstyle="round",
            zorder=3.5,
            label=label,
        )
    )
    ax.plot([a[0], b[0]], [a[1], b[1]], **link)
    if isinstance(mechanism, SliderCrank):
        _slider_block(ax, mechanism, b, size)

    drawn = {k: pts[k] for k in mechanism.reported_joints}
    for name, q in drawn.items():
        style = {"ms": 8, "mfc": "white", "mec": LINK_COLOR, "mew": 1.8, "zorder": 6}
        if name == "P":
            style.update(mfc=CURVE_COLOR, mec="white", ms=8)
        # Labelled (hidden from the legend) so the drawn place can be read back.
        ax.plot(*q, "o", label=f"_joint {name}", **style)
    taken = _incident(drawn, mechanism)
    if pose.velocities is not None and np.all(np.isfinite(pose.velocities["P"][0])):
        # The coupler curve runs through P along its velocity.
        taken["P"] += [pose.velocities["P"][0], -pose.velocities["P"][0]]
    labelled = dict(drawn)
    texts: dict[str, str] = {}
    for other in ("A", "B"):
        if float(np.hypot(*(drawn["P"] - drawn[other]))) <= 1e-9 * float(mechanism.scale):
            # P on a pin joint: one letter pair, not two letters on top of each other.
            del labelled["P"]
            texts[other] = f"${other} = P$"
            break
    # The slider's letter clears its block.
    far = {"B": 19.0} if isinstance(mechanism, SliderCrank) else {}
    _label_joints(ax, labelled, taken, texts, far)
    ax.set_aspect("equal", adjustable="datalim")
    return drawn


# --------------------------------------------------------------------------------------------
# Coupler curves
# --------------------------------------------------------------------------------------------


@dataclass
class _Note:
    xy: Array
    lines: list[str]
    color: str


def _add_note(notes: list[_Note], xy: Array, text: str, color: str, tol: float) -> None:
    """Collect an annotation, merging it into one already placed at (nearly) the same point."""
    for note in notes:
        if float(np.hypot(*(note.xy - xy))) <= tol:
            if text not in note.lines:
                note.lines.append(text)
                if note.color != color:
                    note.color = MIXED_NOTE_COLOR  # one colour would claim every line
            return
    notes.append(_Note(np.asarray(xy, float), [text], color))


def _overlap(a: Bbox, b: Bbox) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)


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


def _place_notes(ax: Axes, notes: Sequence[_Note], lines: Sequence[Array], center: Array) -> None:
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
            xy=note.xy,
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
        best: tuple[float, tuple[float, float], str, str, Bbox] | None = None
        for radius in (22.0, 34.0, 50.0, 70.0):
            for k in range(24):
                ang = away_angle + 2.0 * math.pi * k / 24.0
                off = (radius * math.cos(ang), radius * math.sin(ang))
                ha = "left" if off[0] > 6 else ("right" if off[0] < -6 else "center")
                va = "bottom" if off[1] > 6 else ("top" if off[1] < -6 else "center")
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
        ann.set_ha(ha)
        ann.set_va(va)
        boxes.append(bb)


def _link_lines(pts: dict[str, Array]) -> list[Array]:
    pairs = [("A0", "A"), ("A", "B"), ("B", "P"), ("P", "A"), ("B0", "B"), ("A0", "B0")]
    return [np.array([pts[a], pts[b]]) for a, b in pairs if a in pts and b in pts]


def _fit_figure(fig: Figure, ax: Axes, width: float = 8.5, *, extra: float = 0.0) -> None:
    """Size the figure so the equal-aspect drawing fills its axes (``extra`` inches of height
    for what sits outside it, e.g. a legend below)."""
    box = ax.dataLim
    ratio = box.height / box.width if box.width > 0 else 1.0
    ratio = min(max(ratio, 0.4), 1.1)
    fig.set_size_inches(width, 0.84 * width * ratio + 1.6 + extra)


LEGEND_COLUMNS = 3


def _legend_height(count: int) -> float:
    """Inches a legend of ``count`` entries takes below the drawing."""
    return 0.25 * math.ceil(count / LEGEND_COLUMNS) + 0.15 if count else 0.0


def _legend_below(fig: Figure, handles: Sequence, labels: Sequence[str]) -> None:
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


def plot_curves(
    mechanism: Mechanism,
    *,
    samples: int = 720,
    theta: float | None = None,
    title: str | None = None,
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
        Appended to the family name in the figure title.

    Returns
    -------
    matplotlib.figure.Figure
        One axes with equal aspect. Curve lines carry the labels ``"assembly +1"`` and
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
    _require_single(mechanism)
    fig = new_figure((8.5, 7.0))
    ax = fig.add_subplot()
    sign = float(np.sign(mechanism.assembly))
    mine = _circuits(mechanism, samples)
    theirs = _circuits(mechanism.with_assembly(-sign), samples)
    tol = 0.02 * float(mechanism.scale)

    # The mechanism's own mode solid, the other dashed on top of it: where the two coincide
    # (an input that rocks) both stay visible.
    for traced, color, ls, lw, s, z in (
        (mine, CURVE_COLOR, "-", 2.0, sign, 3.6),
        (theirs, OTHER_COLOR, (0, (5, 3)), 1.4, -sign, 3.7),
    ):
        for k, c in enumerate(traced):
            xy = c.motion.positions["P"][c.closed()]
            label = _sign_label(s) + ("" if k == 0 else f", circuit {k + 1}")
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
    from linkwright.plot.generic import _draw_marks, _features

    notes: list[_Note] = []
    feats = _features(mechanism, samples)
    _draw_marks(ax, feats, "P", notes, tol, gamma_label="P at γ extremes")

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
            f"[{_deg(math.degrees(float(c.motion.input[0])))}°, "
            f"{_deg(math.degrees(float(c.motion.input[c.upper])))}°]"
            for c in mine
        )
        many = len(mine) > 1
        subtitle += (
            f"\ninput rocks over {arcs}{f' ({len(mine)} circuits)' if many else ''}; "
            "the dyad changes branch at each limit,\n"
            f"so both assembly modes trace {'each' if many else 'the same'} closed circuit"
        )
    ax.set_title(subtitle, fontsize=9, color="0.3")
    fig.suptitle(_family_name(mechanism) + (f" — {title}" if title else ""), fontsize=13)
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.1)
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    handles, labels = ax.get_legend_handles_labels()
    shown = [(h, lab) for h, lab in zip(handles, labels, strict=True) if ", circuit" not in lab]
    _fit_figure(fig, ax, extra=_legend_height(len(shown)))
    if shown:
        _legend_below(fig, *zip(*shown, strict=True))

    # Everything drawn as a line (curves, paths, links, guide) is what the notes must not hide.
    lines = [
        np.asarray(line.get_xydata(), float)
        for line in ax.lines
        if line.get_linestyle() not in ("None", "none", " ", "") and len(line.get_xydata()) > 1
    ]
    lines += _link_lines(drawn)  # with the coupler plate's edges
    center = np.nanmean(mine[0].motion.positions["P"], axis=0) if mine else np.zeros(2)
    _place_notes(ax, notes, lines, center)
    return fig


# --------------------------------------------------------------------------------------------
# Motion diagrams
# --------------------------------------------------------------------------------------------


def _speed_limit(speeds: list[Array]) -> float | None:
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
    _require_single(mechanism)
    fig = new_figure((8.0, 9.0))
    axes = fig.subplots(3, 1, sharex=True)
    circuits = _circuits(mechanism, samples)
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
            out = np.degrees(_unwrap_finite(out))
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
                    f"limit {_deg(at)}°",
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
                f"sampled γ from {_deg(np.nanmin(g))}° to {_deg(np.nanmax(g))}° (90° is ideal)",
                loc="right",
                fontsize=8,
                color="0.3",
            )
        top = _speed_limit(speeds)
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
        f"{_family_name(mechanism)} — motion diagrams" + (f" — {title}" if title else ""),
        fontsize=13,
    )
    return fig


# --------------------------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------------------------


def save_figure(fig: Figure, path: str | os.PathLike[str], *, dpi: float | None = None) -> Path:
    """Write ``fig`` as PNG (150 dpi unless told), SVG or PDF, chosen by the file extension.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to write.
    path : str or os.PathLike
        Destination ending in ``.png``, ``.svg`` or ``.pdf``; missing parent folders are
        created.
    dpi : float, optional
        Resolution of a PNG (default 150); ignored by the vector formats.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ValueError
        For any other extension, or a ``dpi`` that is not a positive number.
    """
    if dpi is not None and not (isinstance(dpi, int | float) and math.isfinite(dpi) and dpi > 0):
        raise ValueError(f"save_figure: dpi must be a positive number, got {dpi!r}")
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".png", ".svg", ".pdf"):
        raise ValueError(
            f"save_figure writes .png, .svg or .pdf, not {path.suffix or 'no extension'!r}"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    kwargs = {"dpi": 150 if dpi is None else dpi} if suffix == ".png" else {}
    fig.savefig(path, format=suffix[1:], **kwargs)
    return path

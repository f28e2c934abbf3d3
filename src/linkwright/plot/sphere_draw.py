"""Drawing on the orthographic view of the unit sphere: its outline and graticule, strokes
that fade and dash on the far hemisphere, the fixed link, a pose's links and joints, and the
styles of the traced curves.

Everything here draws into a given :class:`matplotlib.axes.Axes` seen through a
:class:`~linkwright.plot.sphere_view.SphereView`; the figures that arrange these pieces are in
:mod:`linkwright.plot.sphere` (never pyplot: no global state, works headless and from several
threads).
"""

from __future__ import annotations

import itertools
import math
from typing import TypedDict

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon
from matplotlib.typing import ColorType, LineStyleType

from linkwright.geometry import sphere
from linkwright.mechanisms import Mechanism
from linkwright.plot.features import Features, mode_curves
from linkwright.plot.generic import (
    DEAD_COLOR,
    MODE_COLORS,
    OWN_COLOR,
    SECOND_PATH_COLOR,
)
from linkwright.plot.sphere_view import (
    BACK_ALPHA,
    BODY,
    CURVES,
    GROUND,
    LINK,
    MINUS,
    Array,
    SphereView,
    safe_arc,
    sphere_links,
)
from linkwright.plot.style import (
    GAMMA_COLOR,
)

__all__ = [
    "MARK_STYLES",
    "CurveStyle",
    "draw_backdrop",
    "draw_frame",
    "draw_joint",
    "draw_pose",
    "seen_from",
    "stroke",
    "styled_curves",
]


def draw_backdrop(ax: Axes, view: SphereView, avoid: Array | None = None) -> None:
    """Outline, a faint near-side graticule about +Z, the equator a little stronger, and the
    axis tips +X, +Y, +Z where they face the viewer."""
    ax.add_patch(Circle((0, 0), 1.0, facecolor="#f7f9fb", edgecolor="0.25", lw=1.0, zorder=0))
    u = np.linspace(0.0, 2.0 * np.pi, 241)
    for lon in np.radians(np.arange(0, 180, 30)):
        c = np.stack((np.cos(lon) * np.cos(u), np.sin(lon) * np.cos(u), np.sin(u)), axis=-1)
        near, _ = view.split(c)
        ax.plot(*near.T, color="0.82", lw=0.5, zorder=0.5)
    for lat in np.radians(np.arange(-60, 61, 30)):
        c = np.stack(
            (np.cos(lat) * np.cos(u), np.cos(lat) * np.sin(u), np.full_like(u, np.sin(lat))), -1
        )
        near, _ = view.split(c)
        strong = lat == 0
        ax.plot(*near.T, color="0.6" if strong else "0.82", lw=0.8 if strong else 0.5, zorder=0.5)
    for name, tip in zip("XYZ", np.eye(3), strict=True):
        # A joint sitting on an axis (paper 000's A0 is +X) keeps its own label.
        crowded = avoid is not None and bool(np.any(avoid @ tip > math.cos(math.radians(10))))
        if view.depth(tip) > 0.05 and not crowded:
            x, y = view.xy(tip)
            ax.plot(x, y, "+", color="0.55", ms=6, zorder=0.6)
            ax.annotate(
                f"+{name}",
                (x, y),
                xytext=(3, -9),
                textcoords="offset points",
                fontsize=7,
                color="0.5",
            )
    ax.set_xlim(-1.12, 1.12)
    ax.set_ylim(-1.12, 1.12)
    ax.set_aspect("equal")
    ax.set_axis_off()


def stroke(
    ax: Axes,
    view: SphereView,
    p: Array,
    *,
    color: ColorType,
    lw: float,
    label: str | None = None,
    z: float = 2.0,
    ls: LineStyleType = "-",
) -> None:
    """A polyline on the sphere: drawn ``ls`` where near, dashed and faded where far."""
    near, far = view.split(p)
    ax.plot(*near.T, color=color, lw=lw, ls=ls, label=label, zorder=z, solid_capstyle="round")
    ax.plot(*far.T, color=color, lw=lw * 0.8, ls=(0, (3, 2)), alpha=BACK_ALPHA, zorder=z - 1)


# Marker, colour and legend label of the dead centres and γ extremes on either panel.
MARK_STYLES = (
    ("dead", "s", DEAD_COLOR, "dead centres (output stationary)"),
    ("gmin", "v", GAMMA_COLOR, "γ extremes"),
    ("gmax", "^", GAMMA_COLOR, "_γ extremes"),
)


class CurveStyle(TypedDict):
    """How :func:`stroke` draws one path (its keyword arguments)."""

    color: ColorType
    lw: float
    ls: LineStyleType


def styled_curves(mechanism: Mechanism, feats: Features) -> list[tuple[CurveStyle, str, Array]]:
    """(line style, legend label, closed curve) of every drawn path, as the planar picture
    draws them: the document's mode bold, each other mode dashed in its colour, the other
    traced joints dotted grey on the document's mode."""
    traced = mechanism.plan.traced
    out: list[tuple[CurveStyle, str, Array]] = []
    colors: dict[tuple[float, ...], str] = {}
    palette = iter(MODE_COLORS)
    several = len(feats.modes) > 1
    for mode, k, p, same in mode_curves(feats, traced[0]):
        if mode.own:
            style: CurveStyle = {"color": OWN_COLOR, "lw": 2.2, "ls": "-"}
        else:
            if mode.signs not in colors:
                colors[mode.signs] = next(palette, "0.5")
            style = {"color": colors[mode.signs], "lw": 1.3, "ls": (0, (5, 3))}
        label = mode.label if several else f"path of {traced[0]}"
        if same is not None and not mode.own:
            label += " (same curve)"
        out.append((style, label if k == 0 else "_nolegend_", p))
    for i, joint in enumerate(traced[1:]):
        for k, motion in enumerate(feats.own.circuits):
            p = np.concatenate((motion.positions[joint], motion.positions[joint][:1]))
            style = {
                "color": SECOND_PATH_COLOR if i == 0 else CURVES[i % len(CURVES)],
                "lw": 1.1,
                "ls": (0, (1, 1.5)),
            }
            out.append((style, f"path of {joint}" if k == 0 else "_nolegend_", p))
    return out


def seen_from(ax: Axes, cam: SphereView) -> None:
    eye = ", ".join(f"{c:.2f}" for c in np.round(cam.eye, 2) + 0.0).replace("-", MINUS)
    ax.text(0.0, 0.0, f"seen from ({eye})", transform=ax.transAxes, fontsize=7, color="0.45")


def draw_frame(ax: Axes, cam: SphereView, ground: dict[str, Array]) -> None:
    """The fixed link: grey arcs joining the ground pivots in the plan's order (they all lie on
    the one frame body, so any chain through them shows it)."""
    pts = list(ground.values())
    for a, b in itertools.pairwise(pts):
        e = safe_arc(a, b)
        if e is not None:
            stroke(ax, cam, e, color=GROUND, lw=3.5, z=1.8)


def draw_pose(ax: Axes, cam: SphereView, mechanism: Mechanism, pose: dict[str, Array]) -> None:
    pairs, bodies = sphere_links(mechanism)
    for o, t, p in bodies:
        edges = [
            e for x, y in ((o, t), (t, p), (p, o)) if (e := safe_arc(pose[x], pose[y])) is not None
        ]
        if len(edges) < 3:
            continue
        ring = np.concatenate(edges)
        centre = sphere.unit(pose[o] + pose[t] + pose[p])
        near = bool(np.all(np.isfinite(centre))) and float(cam.depth(centre)) >= 0
        ax.add_patch(
            Polygon(
                cam.xy(ring),
                closed=True,
                facecolor=BODY,
                edgecolor="none",
                alpha=0.55 if near else 0.2,
                zorder=1.5,
            )
        )
        for e in edges:
            stroke(ax, cam, e, color=LINK, lw=1.2, z=4.0)
    for a, b in pairs:
        e = safe_arc(pose[a], pose[b])
        if e is not None:
            stroke(ax, cam, e, color=LINK, lw=2.4, z=4.0)
    ground = mechanism.plan.ground
    for name in mechanism.plan.joints:
        draw_joint(ax, cam, name, pose[name], ground=name in ground)


def draw_joint(ax: Axes, cam: SphereView, name: str, p: Array, *, ground: bool) -> None:
    if not np.all(np.isfinite(p)):
        return
    near = float(cam.depth(p)) >= 0
    alpha = 1.0 if near else 0.55
    ax.plot(
        *cam.xy(p),
        marker="^" if ground else "o",
        ms=9 if ground else 6,
        color=GROUND if ground else "white",
        mec=LINK,
        alpha=alpha,
        zorder=7,
        label=f"_joint {name}",
    )
    x, y = cam.xy(p)
    ax.annotate(
        name,
        (x, y),
        xytext=(5, 4),
        textcoords="offset points",
        fontsize=9,
        fontweight="bold" if near else "normal",
        alpha=alpha,
        zorder=8,
    )

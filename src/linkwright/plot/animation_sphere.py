"""The scene of a spherical linkage's animation: the linkage on an orthographic view of the
unit sphere (:class:`~linkwright.plot.sphere_view.SphereView` from
:func:`~linkwright.plot.sphere_view.default_view`), links as great-circle arcs, whatever lies
on the far hemisphere dashed and faded, each frame moving the artists of one fixed figure.
"""

from __future__ import annotations

import contextlib
import itertools

import numpy as np
from matplotlib.artist import Artist
from matplotlib.collections import PolyCollection
from matplotlib.colors import to_rgba
from matplotlib.lines import Line2D

from linkwright.engine import (
    Fixed,
)
from linkwright.mechanisms import Mechanism
from linkwright.plot.animation_scene import (
    CURVES,
    FAR_ALPHA,
    GROUND,
    LINK,
    PLATE,
    WIDTH_IN,
    Array,
    Cycle,
    Scene,
    add_titles,
    angle_label,
    corner_text,
    cycle_note,
    even_pixels,
    exact_figure,
    joint_labels,
    joint_positions,
    place_label,
)
from linkwright.plot.sphere import plot_spherical_curves
from linkwright.plot.sphere_draw import stroke
from linkwright.plot.sphere_view import (
    SpherePlotError,
    SphereView,
    default_view,
    great_arc,
    sphere_links,
)
from linkwright.plot.style import LineKw

__all__ = ["sphere_scene"]


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


def sphere_scene(mechanism: Mechanism, cycle: Cycle, title: str, dpi: int) -> Scene:
    motion = cycle.motion
    pos = joint_positions(mechanism, motion)
    steps = mechanism.plan.steps
    pairs, bodies = sphere_links(mechanism)
    ground = [s.name for s in steps if isinstance(s, Fixed)]
    moving = [s.name for s in steps if not isinstance(s, Fixed)]
    traced = list(mechanism.plan.traced)
    ground_pts = np.array([pos[n][0] for n in ground]).reshape(-1, 3)

    eye = default_view(mechanism)
    up = _up(ground_pts)
    cam = SphereView(eye, up)

    top, side, bottom = 0.72 * dpi, 0.1 * dpi, 0.1 * dpi
    width = even_pixels(WIDTH_IN * dpi)
    axes_w = width - 2 * side
    height = even_pixels(axes_w + top + bottom)
    fig = exact_figure(width, height, dpi)
    axes_h = height - top - bottom
    ax = fig.add_axes((side / width, bottom / height, axes_w / width, axes_h / height))
    # The backdrop (outline, graticule, axis tips) from the sphere module, in the same view.
    plot_spherical_curves([], view=eye, up=up, ax=ax)
    ax.set_autoscale_on(False)
    add_titles(fig, title, cycle_note(cycle), top)

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
        style: LineKw = {
            "marker": marker,
            "ms": ms,
            "mfc": face,
            "mec": LINK,
            "ls": "none",
            "zorder": z,
        }
        return ax.plot([], [], **style)[0], ax.plot([], [], alpha=0.55, **style)[0]

    ground_art = markers("^", 9, GROUND, 7)
    joint_art = markers("o", 6, "white", 7)
    tips = [markers("o", 7, CURVES[k % len(CURVES)], 7.5) for k in range(len(traced))]
    labels = joint_labels(ax, [s.name for s in steps])
    corner = corner_text(ax)
    red, green, blue, opacity = to_rgba(PLATE)

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
        rings: list[Array] = []
        faces: list[tuple[float, float, float, float]] = []
        outline: list[Array] = []
        for o, t, p in bodies:
            ring = _arcs(np.array([at[o], at[t], at[p]]), np.array([at[t], at[p], at[o]]), 16)
            if not np.all(np.isfinite(ring)):
                continue
            outline.append(ring)
            rings.append(cam.xy(ring.reshape(-1, 3)))
            centre = at[o] + at[t] + at[p]
            shade = 0.55 if cam.depth(centre) >= 0 else 0.2
            faces.append((red, green, blue, opacity * shade))
        body_art.set_verts(rings)
        body_art.set_facecolor(faces)
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
            place_label(label, cam.xy(p), 1.0 if near else 0.55)
        corner.set_text(angle_label(cycle, i))

    dynamic: list[Artist] = [body_art, *edges, *links, *ground_art, *joint_art, corner]
    for pair in (*grown, *tips):
        dynamic += list(pair)
    dynamic += list(labels.values())
    return Scene(fig, ax, len(cycle.frames), update, dynamic)

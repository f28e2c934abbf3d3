"""The map panel of a spherical mechanism's figure: the sphere unrolled by Lambert's
azimuthal equal-area projection about the linkage's centre, with a labelled graticule
(parallels and meridians about +Z), the links as great-circle arcs and the traced curves.

It is the flat companion of the orthographic view (:mod:`linkwright.plot.sphere_draw`): a map
shows the whole circuit at once, with no far side, at the price of distorting shapes away from
the centre. :func:`~linkwright.plot.sphere.plot_spherical_mechanism` puts the two side by side.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Polygon
from numpy.typing import NDArray

from linkwright.geometry import sphere
from linkwright.geometry.sphere import lambert_azimuthal
from linkwright.mechanisms import Mechanism
from linkwright.plot.features import Features
from linkwright.plot.generic import (
    DEAD_COLOR,
    OWN_COLOR,
    joint_letter,
)
from linkwright.plot.notes import Note, add_note, drawn_lines, place_notes
from linkwright.plot.planar_draw import label_joints
from linkwright.plot.sphere_draw import MARK_STYLES, styled_curves
from linkwright.plot.sphere_view import (
    BODY,
    GROUND,
    LINK,
    MINUS,
    Z_AXIS,
    Array,
    ground_pivots,
    mean_direction,
    safe_arc,
    sphere_links,
)
from linkwright.plot.style import LIMIT_COLOR, LineKw, TextKw, deg_text

__all__ = ["map_panel"]


def _lat_lon(v: Array) -> tuple[float, float]:
    return math.degrees(math.asin(max(-1.0, min(1.0, float(v[2]))))), math.degrees(
        math.atan2(float(v[1]), float(v[0]))
    )


def _graticule(
    ax: Axes, centre: Array, step: float, box: tuple[float, float, float, float]
) -> None:
    """Parallels and meridians about +Z every ``step`` degrees, labelled at the map's left and
    bottom edges; the far side (beyond 120° from the centre) is left out."""
    x0, x1, y0, y1 = box
    u = np.radians(np.linspace(-180.0, 180.0, 721))
    v = np.radians(np.linspace(-90.0, 90.0, 361))

    def project(pts: Array) -> Array:
        far = pts @ centre < -0.5
        pts = np.where(far[:, None], np.nan, pts)
        return lambert_azimuthal(pts, centre)

    def inside(xy: Array) -> NDArray[np.bool_]:
        return (xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1)

    style: LineKw = {"color": "0.82", "lw": 0.6, "zorder": 0.5}
    text: TextKw = {"fontsize": 7, "color": "0.5", "clip_on": True, "zorder": 0.6}
    for lat in np.arange(-90.0 + step, 90.0, step):
        r = math.radians(lat)
        xy = project(
            np.stack((np.cos(r) * np.cos(u), np.cos(r) * np.sin(u), np.sin(r) + 0 * u), -1)
        )
        ax.plot(*xy.T, **style)
        ok = inside(xy)
        # Labelled only where the line meets the left edge, so labels stay in one column.
        if ok.any() and float(np.min(xy[ok, 0])) < x0 + 0.06 * (x1 - x0):
            i = int(np.flatnonzero(ok)[np.argmin(xy[ok, 0])])
            if xy[i, 1] < y0 + 0.08 * (y1 - y0):  # the corner belongs to the meridians' labels
                continue
            label = f"lat {lat:.0f}°".replace("-", MINUS)
            x, y = xy[i]
            ax.text(x, y, label, ha="left", va="bottom", **text)
    for lon in np.arange(-180.0, 180.0, step):
        r = math.radians(lon)
        xy = project(np.stack((np.cos(v) * np.cos(r), np.cos(v) * np.sin(r), np.sin(v)), -1))
        ax.plot(*xy.T, **style)
        ok = inside(xy)
        if ok.any() and float(np.min(xy[ok, 1])) < y0 + 0.06 * (y1 - y0):
            i = int(np.flatnonzero(ok)[np.argmin(xy[ok, 1])])
            label = f"lon {lon:.0f}°".replace("-", MINUS)
            x, y = xy[i]
            ax.text(x, y, label, ha="left", va="bottom", rotation=90, **text)


def _map_centre(
    mechanism: Mechanism, feats: Features, pose: dict[str, Array] | None = None
) -> Array:
    """The normalised mean of every circuit sample of the curves drawn (the first traced
    joint in every mode, the others in the document's), or of the ground pivots if none;
    tilted where a drawn point (any joint of any circuit, a pivot, the pose) lies at its
    antipode, which has no one place on the map
    (:func:`~linkwright.geometry.sphere.clear_centre`)."""
    traced = mechanism.plan.traced
    samples = [c.positions[traced[0]] for mode in feats.modes for c in mode.circuits]
    samples += [c.positions[j] for j in traced[1:] for c in feats.own.circuits]
    pivots = np.array(list(ground_pivots(mechanism).values())).reshape(-1, 3)
    everything = np.concatenate(samples) if samples else np.zeros((0, 3))
    centre = mean_direction(everything, mean_direction(pivots, Z_AXIS))
    drawn = [p.reshape(-1, 3) for mode in feats.modes for c in mode.circuits
             for p in c.positions.values()]  # fmt: skip
    drawn += [pivots] + [np.asarray(p, dtype=float).reshape(-1, 3) for p in (pose or {}).values()]
    return sphere.clear_centre(centre, np.concatenate(drawn))


def map_panel(
    ax: Axes,
    mechanism: Mechanism,
    feats: Features,
    pose: dict[str, Array] | None,
) -> Array:
    """The curves, pivots, marks and pose on a Lambert azimuthal equal-area map centred on the
    curves' mean direction; returns that centre."""
    curves = styled_curves(mechanism, feats)
    ground = ground_pivots(mechanism)
    centre = _map_centre(mechanism, feats, pose)

    def project(p: Array) -> Array:
        return lambert_azimuthal(p, centre)

    drawn: list[Array] = []
    for style, label, p in curves:
        xy = project(p)
        ax.plot(*xy.T, label=label, zorder=3.6, **style)
        drawn.append(xy)
    traced = mechanism.plan.traced[0]
    notes: list[Note] = []
    tol = 0.03
    styles = [("limit", "D", LIMIT_COLOR, "input limit positions"), *MARK_STYLES]
    for kind, marker, color, label in styles:
        marks = feats.of(kind)
        if not marks:
            continue
        xy = project(np.array([m.pose[traced] for m in marks]))
        ax.plot(
            *xy.T, marker, ms=8, mfc=color, mec="white", mew=0.9, ls="none", zorder=7.5,
            label=label if kind != "gmax" or not feats.of("gmin") else "_nolegend_",
        )  # fmt: skip
        for m, q in zip(marks, xy, strict=True):
            add_note(notes, q, m.text, color, tol)
    dead = feats.of("dead")
    pivot, out = feats.output or (None, None)
    if dead and pivot is not None and out is not None:
        for m in dead:
            e = safe_arc(m.pose[pivot], m.pose[out])
            if e is not None:
                xy = project(e)
                ax.plot(*xy.T, color=DEAD_COLOR, lw=1.3, ls=(0, (4, 2)), zorder=3.5)
                drawn.append(xy)
        ends = project(np.array([m.pose[out] for m in dead]))
        ax.plot(
            *ends.T, "s", ms=6, mfc="white", mec=DEAD_COLOR, mew=1.4, ls="none", zorder=3.55,
            label=f"output {pivot}{out} at its dead centres",
        )  # fmt: skip
    for start, end in itertools.pairwise(ground.values()):
        e = safe_arc(start, end)
        if e is not None:
            ax.plot(*project(e).T, color=GROUND, lw=3.5, solid_capstyle="round", zorder=1.8)
    pts: dict[str, Array] = dict(ground) if pose is None else dict(pose)
    pairs, bodies = sphere_links(mechanism)
    if pose is not None:
        for o, t, q in bodies:
            edges = [
                e
                for x, y in ((o, t), (t, q), (q, o))
                if (e := safe_arc(pose[x], pose[y])) is not None
            ]
            if len(edges) == 3:
                ring = project(np.concatenate(edges))
                ax.add_patch(
                    Polygon(ring, closed=True, facecolor=BODY, edgecolor="none", alpha=0.5)
                )
                ax.plot(*ring.T, color=LINK, lw=1.0, zorder=4)
                drawn.append(ring)
        for a, b in pairs:
            e = safe_arc(pose[a], pose[b])
            if e is not None:
                xy = project(e)
                ax.plot(*xy.T, color=LINK, lw=2.6, solid_capstyle="round", zorder=4)
                drawn.append(xy)
    taken: dict[str, list[Array]] = {name: [] for name in pts}
    flat = {name: project(p) for name, p in pts.items() if np.all(np.isfinite(p))}
    for a, b in pairs if pose is not None else []:
        if a in flat and b in flat:
            taken[a].append(flat[b] - flat[a])
            taken[b].append(flat[a] - flat[b])
    fixed = mechanism.plan.ground
    for name in mechanism.plan.joints:
        if name not in flat:
            continue
        is_ground = name in fixed
        mark: LineKw = (
            {"marker": "^", "ms": 10, "mfc": GROUND, "mec": LINK, "mew": 1.0}
            if is_ground
            else {"marker": "o", "ms": 7, "mfc": "white", "mec": LINK, "mew": 1.6}
        )
        if name == traced and not is_ground:
            mark["mfc"], mark["mec"] = OWN_COLOR, "white"
        ax.plot(*flat[name], ls="none", zorder=6, label=f"_joint {name}", **mark)
    label_joints(ax, flat, taken, {n: joint_letter(n) for n in flat})
    every = np.concatenate([*drawn, *(q[None] for q in flat.values())])
    every = every[np.all(np.isfinite(every), axis=-1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.08 * float(max(hi - lo)) + 0.02
    box = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    reach = max(float(np.max(np.hypot(*every.T))), 1e-3)  # map radius 2 sin(δ/2)
    extent = math.degrees(2.0 * math.asin(min(1.0, reach / 2.0)))
    step = 5.0 if extent < 25.0 else 10.0 if extent < 70.0 else 15.0
    _graticule(ax, centre, step, box)
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_aspect("equal", adjustable="box")
    ax.set_xticks([])
    ax.set_yticks([])
    lat, lon = _lat_lon(centre)
    ax.set_title(
        "Lambert azimuthal equal-area map, centred on the curves' mean direction\n"
        f"(lat {deg_text(lat)}°, lon {deg_text(lon)}°); graticule every {step:.0f}° about +Z",
        fontsize=9.5,
    )
    lines = drawn_lines(ax)
    centre_xy = np.nanmean(drawn[0], axis=0) if drawn else np.zeros(2)
    place_notes(ax, notes, lines, centre_xy)
    return centre

"""Pictures of spherical linkages: an orthographic view of the unit sphere.

A spherical linkage lives on the unit sphere (every joint is the unit vector along its revolute
axis, every link a great-circle arc), so it is drawn the way a globe is: the sphere's outline, a
faint graticule (meridians and parallels about +Z, every 30°) on the near hemisphere, and on
top of it the links as great-circle arcs, the ground pivots as triangles, the moving joints as
dots with their letters, and the closed paths of the traced joints. Whatever lies on the far
hemisphere is drawn dashed and faded, so depth reads at a glance.

The view is given by the direction ``view`` from which the sphere is seen (the eye is far away
along it). For a linkage the default (:func:`default_view`) starts from the normalised mean of
the ground pivots, raised 35° out of the great circle that fits them best, and then turns to
keep every joint, over its whole circuit, clear of the rim and of the far side: coupler points
often swing far from the frame. The great circle through the ground pivots is kept level on
the page, so the frame reads like a drawing board.

Figures are built on :class:`matplotlib.figure.Figure` with an Agg canvas, never through pyplot
(no global state; works headless and from several threads), as in :mod:`linkwright.plot.generic`.
This module arranges the figures; the camera and the default view are in
:mod:`linkwright.plot.sphere_view`, the strokes and joints in :mod:`linkwright.plot.sphere_draw`
and the flat map panel in :mod:`linkwright.plot.sphere_map` (their public names are re-exported
here as before).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from linkwright.geometry import sphere
from linkwright.mechanisms import Mechanism, solve
from linkwright.plot.axes import check_axes, figure_of
from linkwright.plot.features import Features, find_features, input_status, never_modes
from linkwright.plot.generic import DEAD_COLOR, family_title
from linkwright.plot.sphere_draw import (
    MARK_STYLES,
    draw_backdrop,
    draw_frame,
    draw_joint,
    draw_pose,
    seen_from,
    stroke,
    styled_curves,
)
from linkwright.plot.sphere_map import map_panel
from linkwright.plot.sphere_view import (
    BACK_ALPHA,
    CURVES,
    Array,
    SpherePlotError,
    SphereView,
    check_curve,
    default_view,
    fit_normal,
    great_arc,
    ground_pivots,
    mean_direction,
    require_sphere,
    resolve_view,
    safe_arc,
    sphere_links,
    upright,
    view_of_circuits,
)
from linkwright.plot.style import deg_text, new_figure

__all__ = [
    "SpherePlotError",
    "SphereView",
    "default_view",
    "great_arc",
    "plot_spherical_curves",
    "plot_spherical_linkage",
    "plot_spherical_mechanism",
    "sphere_links",
    "stroke",
]


# --------------------------------------------------------------------------------------------
# Curves
# --------------------------------------------------------------------------------------------


def plot_spherical_curves(
    curves: list[tuple[str, ArrayLike]],
    *,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
    title: str | None = None,
    backdrop: bool = True,
    ax: Axes | None = None,
) -> Figure:
    """Draw curves on the unit sphere, near parts solid and far parts dashed and faded.

    Parameters
    ----------
    curves : list of (label, array of shape (N, 3))
        Each curve's points are unit vectors; NaN rows break the line (samples where a linkage
        was not assembled).
    view : array_like, shape (3,), optional
        Direction from which the sphere is seen. Default: the normalised mean of every finite
        point of every curve (+X if that mean vanishes).
    up : array_like, shape (3,), optional
        The direction drawn upwards on the page (its part normal to ``view``). Default +Z.
    title : str, optional
    backdrop : bool
        Draw the sphere's outline and graticule; pass False to add curves to an axes that
        already shows the sphere in the same view.
    ax : matplotlib.axes.Axes, optional
        Draw into this axes; a new figure is made otherwise.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    SpherePlotError
        For a curve that is not an (N, 3) array of unit vectors, or a zero ``view``.

    Examples
    --------
    >>> u = np.linspace(0, 2 * np.pi, 100)
    >>> circle = np.stack([np.cos(u), np.sin(u), 0 * u], axis=-1)
    >>> fig = plot_spherical_curves([("equator", circle)], view=[1, 1, 1])
    >>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    ['equator']

    Points off the sphere are refused:

    >>> plot_spherical_curves([("wrong", 2 * circle)])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.sphere_view.SpherePlotError: curve 'wrong': points must be unit vectors ...
    """
    checked = [(str(label), check_curve(str(label), pts)) for label, pts in curves]
    everything = np.concatenate([p for _, p in checked]) if checked else np.zeros((0, 3))
    cam = resolve_view(view, up, mean_direction(everything, np.array([1.0, 0.0, 0.0])))
    fig = figure_of(ax) if ax is not None else new_figure((6, 6))
    ax = ax or fig.add_subplot()
    if backdrop:
        draw_backdrop(ax, cam)
    for i, (label, p) in enumerate(checked):
        stroke(ax, cam, p, color=CURVES[i % len(CURVES)], lw=1.4, label=label)
    if checked:
        ax.legend(loc="lower right", fontsize=8)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


# --------------------------------------------------------------------------------------------
# Linkages
# --------------------------------------------------------------------------------------------


def plot_spherical_linkage(
    mechanism: Mechanism,
    *,
    samples: int = 360,
    at: float | None = None,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
    title: str | None = None,
    extra_curves: Sequence[tuple[str, ArrayLike]] | None = None,
    ax: Axes | None = None,
    annotate: bool = False,
) -> Figure:
    """A spherical linkage at one pose, with the closed paths of its traced joints.

    The links are read from the construction plan, so any sphere-space mechanism is drawn
    without per-family code: a crank joins its pivot to its joint, a dyad joint is joined to
    both parents, and a rigid point (a coupler point) makes a filled spherical triangle with the
    two joints of its link. Each traced joint's path is the whole circuit as the machine runs
    (every circuit where the input cannot turn fully), with the limit positions, where a dyad
    changes branch, marked by crosses.

    Parameters
    ----------
    mechanism : Mechanism
        One spherical linkage (``mechanism.space == "sphere"``, batch shape ``()``).
    samples : int
        Samples per circuit.
    at : float, optional
        Input angle (radians) of the pose drawn, on the mechanism's own assembly. Default: the
        first sample of the first circuit.
    view, up : array_like, shape (3,), optional
        Direction the sphere is seen from, and the direction drawn upwards (its part normal to
        ``view``). Default view: :func:`default_view`; default up: the normal of the great
        circle through the ground pivots, so that the frame is drawn level.
    title : str, optional
        First line of the title; the second says how the input moves and which pose is drawn.
    extra_curves : list of (label, array of shape (N, 3)), optional
        More curves to draw in the same view (another assembly's path, a target curve), dotted;
        unit vectors, NaN rows break the line.
    ax : matplotlib.axes.Axes, optional
        Draw into this axes; a new figure is made otherwise.
    annotate : bool
        Also draw the first traced joint's path in every other assembly mode (dashed, named in
        the legend), and mark the dead centres (the output link drawn dashed there) and the
        transmission-angle extremes, as :mod:`linkwright.plot.generic` defines them.

    Returns
    -------
    matplotlib.figure.Figure
        A linkage that cannot be assembled at any input is drawn as its ground pivots, and the
        title says so.

    Raises
    ------
    SpherePlotError
        For a planar linkage, a batch of mechanisms, a bad ``view``/``up`` or an extra curve
        that is not an (N, 3) array of unit vectors.
    linkwright.mechanisms.sixbar.NoConstructionPlan
        For a mechanism whose input leaves no construction plan (Stephenson III driven at FG).

    Examples
    --------
    >>> from linkwright.mechanisms import SphericalFourBar
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> fig = plot_spherical_linkage(fig6, samples=90)
    >>> print(fig.axes[0].get_title())
    spherical-fourbar
    input turns fully; pose at θ = 0.0°

    A linkage that never assembles shows its ground pivots and says why nothing else:

    >>> stuck = SphericalFourBar(*np.radians([90, 10, 20, 30]))
    >>> print(plot_spherical_linkage(stuck).axes[0].get_title())
    spherical-fourbar
    cannot be assembled at any input: only the ground pivots are drawn
    """
    require_sphere(mechanism)
    extra = [(str(label), check_curve(str(label), pts)) for label, pts in extra_curves or []]
    check_axes(ax)
    feats = find_features(mechanism, samples, every=annotate, marks=annotate)
    fig = figure_of(ax) if ax is not None else new_figure((6.4, 6.6))
    ax = ax or fig.add_subplot()
    head = title or mechanism.family
    _, pose, theta = _sphere_panel(
        ax, mechanism, feats, at=at, view=view, up=up, extra=extra, annotate=annotate
    )
    if not feats.own.circuits:
        ax.set_title(
            f"{head}\ncannot be assembled at any input: only the ground pivots are drawn",
            fontsize=10,
        )
        if extra:
            ax.legend(loc="lower right", fontsize=7)
        return fig
    if pose is not None:
        where = f"pose at θ = {deg_text(math.degrees(theta))}°"
    else:
        where = f"no pose: it does not assemble at θ = {deg_text(math.degrees(theta))}°"
    ax.set_title(f"{head}\n{input_status(feats.own.arcs)}; {where}", fontsize=10)
    ax.legend(loc="lower right", fontsize=7)
    return fig


def _pose_at(
    mechanism: Mechanism, feats: Features, at: float | None
) -> tuple[dict[str, Array] | None, float]:
    """The pose drawn (None where it does not assemble) and its input."""
    if at is None:
        first = feats.own.circuits[0]
        return {name: p[0] for name, p in first.positions.items()}, float(first.input[0])
    one = solve(mechanism, [float(at)], order=0)
    if not bool(one.valid[0]):
        return None, float(at)
    return {name: p[0] for name, p in one.positions.items()}, float(at)


def _sphere_panel(
    ax: Axes,
    mechanism: Mechanism,
    feats: Features,
    *,
    at: float | None,
    view: ArrayLike | None,
    up: ArrayLike | None,
    extra: list[tuple[str, Array]],
    annotate: bool,
) -> tuple[SphereView, dict[str, Array] | None, float]:
    """Draw the sphere, the paths, the marks and the pose; return the camera and the pose."""
    ground = ground_pivots(mechanism)
    own = feats.own
    circuits = list(own.circuits)
    pivots = np.array(list(ground.values())).reshape(-1, 3)
    eye = view_of_circuits(mechanism, circuits) if view is None else np.ones(3)
    if up is None:
        # The frame's great circle drawn level: the frame reads like a drawing board.
        up = upright(fit_normal(pivots, mean_direction(pivots, eye / sphere.norm(eye))))
    cam = resolve_view(view, up, eye)
    marked = [pivots]
    if circuits:
        marked.append(np.array([p[0] for p in circuits[0].positions.values()]))
    draw_backdrop(ax, cam, avoid=np.concatenate(marked))
    draw_frame(ax, cam, ground)
    seen_from(ax, cam)
    traced = mechanism.plan.traced
    for i, (label, p) in enumerate(extra):
        near, far = cam.split(p)
        color = CURVES[(i + len(traced)) % len(CURVES)]
        ax.plot(*near.T, color=color, lw=1.4, ls=(0, (1, 1.5)), label=label, zorder=3.0)
        ax.plot(*far.T, color=color, lw=1.0, ls=(0, (1, 3)), alpha=BACK_ALPHA, zorder=2.0)
    if not circuits:
        for name, p in ground.items():
            draw_joint(ax, cam, name, p, ground=True)
        return cam, None, 0.0 if at is None else float(at)
    if annotate:
        for style, label, p in styled_curves(mechanism, feats):
            stroke(ax, cam, p, label=label, z=3.0, **style)
    else:
        for k, motion in enumerate(circuits):
            for i, joint in enumerate(traced):
                closed = np.concatenate((motion.positions[joint], motion.positions[joint][:1]))
                label = f"path of {joint}" + (f" (circuit {k + 1})" if k else "")
                stroke(ax, cam, closed, color=CURVES[i % len(CURVES)], lw=1.4, label=label, z=3.0)
    limits = feats.of("limit")
    if limits:
        pts = np.array([m.pose[traced[0]] for m in limits])
        ax.plot(*cam.xy(pts).T, "x", color="k", ms=6, zorder=6, label="limit positions", ls="none")
    if annotate:
        for kind, marker, color, label in MARK_STYLES:
            marks = feats.of(kind)
            if marks:
                pts = np.array([m.pose[traced[0]] for m in marks])
                ax.plot(
                    *cam.xy(pts).T,
                    marker,
                    ms=7,
                    mfc=color,
                    mec="white",
                    mew=0.8,
                    ls="none",
                    zorder=6.5,
                    label=label,
                )
        if feats.output is not None:
            pivot, out = feats.output
            for m in feats.of("dead"):
                e = safe_arc(m.pose[pivot], m.pose[out]) if pivot is not None else None
                if e is not None:
                    stroke(ax, cam, e, color=DEAD_COLOR, lw=1.3, ls=(0, (4, 2)), z=3.5)
    pose, theta = _pose_at(mechanism, feats, at)
    if pose is not None:
        draw_pose(ax, cam, mechanism, pose)
    else:
        for name, p in ground.items():
            draw_joint(ax, cam, name, p, ground=True)
    return cam, pose, theta


# --------------------------------------------------------------------------------------------
# Map projection
# --------------------------------------------------------------------------------------------


def plot_spherical_mechanism(
    mechanism: Mechanism,
    *,
    samples: int = 720,
    at: float | None = None,
    title: str | None = None,
    view: ArrayLike | None = None,
    up: ArrayLike | None = None,
    ax: Axes | None = None,
) -> Figure:
    """The main picture of a spherical linkage: a 3-D view of the sphere and a map of the
    curves, side by side.

    Left, the sphere seen from outside (:func:`plot_spherical_linkage` with ``annotate``): the
    links as great-circle arcs at the pose, the first traced joint's path in every assembly
    mode (the document's bold), the other traced joints' paths, and the marks of
    :mod:`linkwright.plot.generic` (limit positions, dead centres with the output link there,
    transmission-angle extremes). Right, the same on a Lambert azimuthal equal-area map
    (:func:`linkwright.geometry.sphere.lambert_azimuthal`, +Z up) centred on the curves' mean
    direction (the normalised mean of every circuit sample of the curves drawn), with a
    graticule of latitude and longitude about +Z, the frame, the ground pivots, the pose's links
    as projected arcs and a note at each mark. One legend under both. Equal-area, so a curve's
    map encloses as much as it does on the unit sphere.

    Parameters
    ----------
    mechanism : Mechanism
        One spherical linkage that assembles somewhere.
    samples : int
        Samples per circuit.
    at : float, optional
        Input angle (radians) of the pose, on the document's assembly (the pose of
        :func:`~linkwright.mechanisms.solve`); default the first sample of the first circuit.
    title : str, optional
        The figure's title.
    view, up : array_like, shape (3,), optional
        The 3-D view's direction and up (see :func:`plot_spherical_linkage`).
    ax : matplotlib.axes.Axes, optional
        Draw the sphere's view alone into this flat axes (the orthographic view is a 2-D
        drawing: a 3-D axes is refused), as :func:`plot_spherical_linkage` with ``annotate``;
        without it a new figure holds the sphere and the map.

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the sphere, then the map; ``ax``'s (top-level) figure when ``ax`` is given.

    Raises
    ------
    SpherePlotError
        For a planar linkage, a batch, or a linkage that cannot be assembled at any input.

    Examples
    --------
    >>> from linkwright.mechanisms import SphericalFourBar
    >>> fig6 = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))
    >>> fig = plot_spherical_mechanism(fig6, samples=90)
    >>> len(fig.axes), fig.axes[1].get_title().split(",")[0]
    (2, 'Lambert azimuthal equal-area map')

    A linkage that closes nowhere has nothing to draw:

    >>> plot_spherical_mechanism(SphericalFourBar(*np.radians([90, 10, 20, 30])))
    Traceback (most recent call last):
    ...
    linkwright.plot.sphere_view.SpherePlotError: mechanism: it cannot be assembled at any input
    """
    require_sphere(mechanism)
    check_axes(ax)
    feats = find_features(mechanism, samples)
    if not feats.own.circuits:
        raise SpherePlotError("mechanism: it cannot be assembled at any input")
    if ax is not None:
        return plot_spherical_linkage(
            mechanism, samples=samples, at=at, view=view, up=up, title=title, ax=ax, annotate=True
        )
    fig = new_figure((14.0, 7.6))
    left, right = fig.subplots(1, 2, width_ratios=(1.0, 1.15))
    _, pose, theta = _sphere_panel(
        left, mechanism, feats, at=at, view=view, up=up, extra=[], annotate=True
    )
    status = input_status(feats.own.arcs)
    where = (
        f"pose at θ = {deg_text(math.degrees(theta))}°"
        if pose is not None
        else f"no pose: it does not assemble at θ = {deg_text(math.degrees(theta))}°"
    )
    lines = [f"orthographic view of the unit sphere\n{status}; {where}"]
    if len(feats.modes) > 1:
        lines.append("bold: the document's assembly; dashed: the others")
    never = never_modes(feats)
    if never:
        lines.append("never assembles: " + "; ".join(never))
    if feats.output is not None and feats.of("dead") and feats.output[0] is not None:
        lines.append(
            f"dead centres: where the output link {feats.output[0]}{feats.output[1]} stops"
        )
    left.set_title("\n".join(lines), fontsize=9.5)
    map_panel(right, mechanism, feats, pose)
    handles, labels = right.get_legend_handles_labels()
    name = family_title(mechanism)
    head = (
        title
        if title and name.lower() in title.lower()
        else (f"{name} — {title}" if title else name)
    )
    fig.suptitle(head, fontsize=13)
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncols=min(4, len(labels)),
            fontsize=8.5,
            frameon=False,
        )
    return fig

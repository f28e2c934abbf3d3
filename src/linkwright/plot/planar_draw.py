"""Drawing a planar linkage (four-bar, slider-crank) in one pose: the links and the coupler
plate, the ground pivots with their hatched symbol, the slider's guide and block, and the joints'
letters placed clear of the links that meet there.

:func:`draw_linkage` draws into a given :class:`matplotlib.axes.Axes`; the figures built on it
(coupler curves, motion diagrams) are in :mod:`linkwright.plot.planar`.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Polygon

from linkwright.engine import Motion, evaluate
from linkwright.geometry import plane
from linkwright.mechanisms import FourBar, Mechanism, SliderCrank, circuit
from linkwright.plot.style import (
    COUPLER_FACE,
    CURVE_COLOR,
    GROUND_COLOR,
    LIMIT_COLOR,
    LINK_COLOR,
    Array,
    LineKw,
    deg_text,
)

__all__ = ["draw_linkage", "ground_symbol", "label_joints", "require_single"]


def require_single(mechanism: Mechanism) -> FourBar | SliderCrank:
    """``mechanism`` itself, if it is one linkage of a family that has a drawing."""
    if not isinstance(mechanism, FourBar | SliderCrank):
        raise TypeError(
            f"only FourBar and SliderCrank can be drawn, got {type(mechanism).__name__}"
        )
    if mechanism.batch_shape != ():
        raise ValueError(
            f"draw one linkage at a time; this mechanism has batch shape {mechanism.batch_shape}"
        )
    return mechanism


def _ground_points(mechanism: FourBar | SliderCrank) -> dict[str, Array]:
    if isinstance(mechanism, FourBar):
        return {
            "A0": np.asarray(mechanism.A0, np.float64),
            "B0": np.asarray(mechanism.B0, np.float64),
        }
    return {"A0": np.asarray(mechanism.A0, np.float64)}


def _symbol_size(ax: Axes, mechanism: FourBar | SliderCrank, pose: Motion) -> float:
    """Size of the ground symbols and slider block: a twentieth of the drawing's extent.

    The extent is that of what the axes already hold (e.g. coupler curves) joined with the
    linkage's own reach, so the symbols read the same at any zoom of the picture.
    """
    placed = [p[0] for p in pose.positions.values() if np.all(np.isfinite(p[0]))]
    placed += list(_ground_points(mechanism).values())
    pts = np.array(placed)
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


def ground_symbol(ax: Axes, at: Array, size: float, *, zorder: float = 3.0) -> None:
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


def label_joints(
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
            xy=(float(p[0]), float(p[1])),
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
    mechanism = require_single(mechanism)
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
        ground_symbol(ax, p, size)

    if not ok:
        for p in ground.values():
            ax.plot(*p, "o", ms=8, mfc="white", mec=LINK_COLOR, mew=1.8, zorder=6)
        label_joints(ax, ground, _incident(ground, mechanism))
        ax.text(
            0.5,
            0.5,
            f"cannot assemble at θ = {deg_text(math.degrees(theta))}°",
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
    link: LineKw = {"color": LINK_COLOR, "lw": 4.0, "solid_capstyle": "round", "zorder": 4}
    ax.plot([a0[0], a[0]], [a0[1], a[1]], **link)
    if isinstance(mechanism, FourBar):
        b0 = pts["B0"]
        ax.plot([b0[0], b[0]], [b0[1], b[1]], **link)
        ax.plot([a0[0], b0[0]], [a0[1], b0[1]], ls="-.", lw=0.8, color=GROUND_COLOR, zorder=1)
    label = f"linkage at θ = {deg_text(math.degrees(theta))}°"
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
        style: LineKw = {"ms": 8, "mfc": "white", "mec": LINK_COLOR, "mew": 1.8, "zorder": 6}
        if name == "P":
            style["mfc"], style["mec"], style["ms"] = CURVE_COLOR, "white", 8
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
    label_joints(ax, labelled, taken, texts, far)
    ax.set_aspect("equal", adjustable="datalim")
    return drawn

"""What every export format is built from: the linkage's topology, its paths over the circuit
and the drawing's geometry, plus the checks of the arguments every format shares.

Which joints a link joins is read from the construction plan (:func:`topology`), the idea of
the plotting modules' link lists, extended to rigid bodies of three or more joints. The paths
follow the circuit the machine runs (:func:`linkwright.mechanisms.circuit`): one turn where the
input turns fully, up and back down its arc where it rocks; a sample the engine could not
place is left out and the curves break there (:func:`circuit_runs`). A :class:`Drawing` holds
the pose and the closed curves in 2-D (plane) or on the unit sphere, for :mod:`.svg` and
:mod:`.dxf`. Every file is written atomically (:func:`write_atomically`). The formats
themselves are described in :mod:`.exports`.
"""

from __future__ import annotations

import itertools
import math
import numbers
import os
import pathlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Trammel,
)
from linkwright.engine.plan import Plan
from linkwright.files import atomic_path
from linkwright.geometry.sphere import lambert_azimuthal, map_frame
from linkwright.mechanisms import Mechanism, circuit, circuits, running_circuit, solve

__all__ = [
    "FORMATS",
    "GROUND",
    "INSUNITS",
    "MAX_SAMPLES",
    "CircuitPaths",
    "Drawing",
    "ExportError",
    "Guide",
    "Topology",
    "build_drawing",
    "checked_samples",
    "circuit_paths",
    "circuit_runs",
    "joint_paths",
    "length_unit",
    "outline",
    "plan_of",
    "pose_at",
    "slerp",
    "target_path",
    "topology",
    "triangle",
    "unit_rows",
    "write_atomically",
]

Array = NDArray[np.float64]

FORMATS = ("csv", "svg", "dxf")
"""The formats :func:`export` writes, by file suffix."""

INSUNITS: dict[str | None, int] = {None: 0, "in": 1, "ft": 2, "mm": 4, "cm": 5, "m": 6}
"""DXF ``$INSUNITS`` codes of the length units a document may name (None: unitless)."""

# Spellings a document may use for each unit (compared lower-case, stripped).
_UNIT_NAMES = {
    "mm": ("mm", "millimeter", "millimeters", "millimetre", "millimetres"),
    "cm": ("cm", "centimeter", "centimeters", "centimetre", "centimetres"),
    "m": ("m", "meter", "meters", "metre", "metres"),
    "in": ("in", "inch", "inches", '"'),
    "ft": ("ft", "foot", "feet", "'"),
    None: ("", "none", "unitless"),
}
# On the sphere lengths are arcs: a document may say so, and the drawing stays unitless.
_ANGLE_UNITS = ("deg", "degree", "degrees", "°", "rad", "radian", "radians")
# SVG has mm, cm and in; m and ft are written in the nearest unit it has, exactly scaled.
MAX_SAMPLES = 1_000_000
GROUND = "#6b6b6b"


class ExportError(ValueError):
    """An export that cannot be written: the message names the argument and the problem."""

    # Its public home stays the exports module: tracebacks and pickles name it from there.
    __module__ = "linkwright.io.exports"


# --------------------------------------------------------------------------------------------
# Link topology
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Guide:
    """A straight slider guide: the line through joint ``through`` at ``angle`` (radians).

    ``sliders`` are the joints that run on it; ``fixed`` says the guide is part of the ground
    (its ``through`` joint is a ground joint).
    """

    through: str
    angle: float
    sliders: tuple[str, ...]
    fixed: bool


@dataclass(frozen=True)
class Topology:
    """Which joints a linkage's links join, read from its construction plan.

    Attributes
    ----------
    ground : every joint fixed to the frame, in plan order.
    pivots : the ground joints that are pivots (a link turns about them), in plan order; a
        ground point that only places a slider guide is not one.
    links : each moving rigid body as the names of its joints, in plan order: two joints for a
        binary link, three or more for a ternary (or larger) link.
    guides : the straight slider guides (plane only).
    """

    ground: tuple[str, ...]
    pivots: tuple[str, ...]
    links: tuple[tuple[str, ...], ...]
    guides: tuple[Guide, ...]


def topology(mechanism: Mechanism) -> Topology:
    """The links of ``mechanism``: which joints each rigid body joins, from its plan.

    Rigid bodies are grown as the plan places its joints, as a machine is assembled: the ground
    holds every fixed joint; a crank is a link from its pivot (cranks on one pivot turning at
    one ratio are one body, as are the double slider's bar and the cranks on it); a dyad adds
    two binary links, or joins the body that already holds both its parents (a rigid
    triangle); a slider pin adds its rod; a point fixed on a link joins every body that holds
    that link's two joints. A body with two ground joints is part of the ground.

    Parameters
    ----------
    mechanism : Mechanism
        Any family, in the plane or on the sphere (one mechanism, not a batch).

    Returns
    -------
    Topology

    Raises
    ------
    ExportError
        If the mechanism has no construction plan (a six-bar driven at its output).

    Examples
    --------
    A four-bar: crank and rocker are binary links, the coupler carries the coupler point.

    >>> from linkwright.mechanisms import FourBar
    >>> t = topology(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=1, v=1))
    >>> t.links
    (('A0', 'A'), ('A', 'B', 'P'), ('B0', 'B'))
    >>> t.pivots
    ('A0', 'B0')
    """
    plan = plan_of(mechanism)
    params = mechanism.params()
    ground: list[str] = []
    bodies: list[list[str]] = []
    # (pivot, ratio) → body index: cranks (and a trammel's bar) turning together are one body.
    turning: dict[tuple[str, float], int] = {}
    guides: list[tuple[str, float, list[str]]] = []
    used_as_pivot: set[str] = set()
    far_ends: dict[str, tuple[int, float, float]] = {}  # trammel → (its guide 2, arm, phase)

    def new_body(*names: str) -> int:
        bodies.append(list(dict.fromkeys(names)))
        return len(bodies) - 1

    def join(a: str, b: str, name: str) -> bool:
        """Add ``name`` to every body that holds ``a`` and ``b``; whether any did."""
        if a in ground and b in ground:
            ground.append(name)
            return True
        shared = [body for body in bodies if a in body and b in body]
        for body in shared:
            body.append(name)
        return bool(shared)

    for step in plan.steps:
        name = step.name
        if isinstance(step, Fixed):
            ground.append(name)
        elif isinstance(step, Crank | SphereCrank):
            used_as_pivot.add(step.pivot)
            key = (step.pivot, _value(params, step.ratio))
            if step.pivot in far_ends and isinstance(step, Crank):
                index, arm, phase = far_ends[step.pivot]
                here = (key[1], _value(params, step.length), _value(params, step.phase))
                if here == (1.0, arm, phase):
                    guides[index][2].append(name)
            if key in turning:
                bodies[turning[key]].append(name)
            else:
                turning[key] = new_body(step.pivot, name)
        elif isinstance(step, Trammel):
            # The slider on guide 1 carries the bar, whose angle is phase + θ: later cranks on
            # the slider at ratio 1 are points of the same bar, and the one as long as the arm
            # and at its phase is the bar's far end, the slider on guide 2.
            turning[(name, 1.0)] = new_body(name)
            guides.append((step.guide1, _value(params, step.angle1), [name]))
            guides.append((step.guide2, _value(params, step.angle2), []))
            far_ends[name] = (len(guides) - 1, _value(params, step.arm), _value(params, step.phase))
        elif isinstance(step, DyadRRR | SphereDyad):
            used_as_pivot.update((step.p1, step.p2))
            if not join(step.p1, step.p2, name):
                new_body(step.p1, name)
                new_body(step.p2, name)
        elif isinstance(step, DyadRRP):
            used_as_pivot.add(step.p1)
            guides.append((step.line_point, _value(params, step.line_angle), [name]))
            if step.p1 in ground and step.line_point in ground:
                ground.append(name)  # a rod from the frame to a fixed guide cannot move
            else:
                new_body(step.p1, name)
        elif isinstance(step, Rigid | SphereRigid):
            used_as_pivot.update((step.origin, step.toward))
            if not join(step.origin, step.toward, name):
                new_body(step.origin, step.toward, name)
        elif step in plan.triads:
            # Several joints at once (a triad, a driven hinge): its rigid bodies are its plates
            # (a triad's ternary link), and each of its links that no plate holds.
            plates = [frozenset(p) for p in step.plates()]
            for plate in step.plates():
                new_body(*plate)
            for a, b in step.links():
                if not any({a, b} <= p for p in plates):
                    used_as_pivot.update((a, b))
                    new_body(a, b)
        else:  # pragma: no cover - a step type this module does not know yet
            raise ExportError(f"joint {name!r}: cannot draw a {type(step).__name__} step")
    # A body on two ground joints cannot move: it is part of the frame, and may ground more.
    grounded = True
    while grounded:
        grounded = False
        for body in bodies:
            if sum(j in ground for j in body) >= 2 and not set(body) <= set(ground):
                ground.extend(j for j in body if j not in ground)
                grounded = True
    sets = [frozenset(b) for b in bodies]
    moving = [
        tuple(body)
        for i, body in enumerate(bodies)
        if len(body) >= 2
        and not sets[i] <= set(ground)
        # a body inside another one (or an earlier copy of itself) is drawn as part of it
        and not any(sets[i] < other or (sets[i] == other and k < i) for k, other in enumerate(sets))
    ]
    pivots = tuple(j for j in ground if j in used_as_pivot)
    return Topology(
        ground=tuple(dict.fromkeys(ground)),
        pivots=pivots,
        links=tuple(moving),
        guides=tuple(Guide(t, a, tuple(s), t in ground) for t, a, s in guides),
    )


def _value(params: Mapping[str, ArrayLike], p: str | float) -> float:
    return float(np.asarray(params[p] if isinstance(p, str) else p, dtype=float))


def plan_of(mechanism: Mechanism) -> Plan:
    try:
        return mechanism.plan
    except ValueError as exc:  # NoConstructionPlan: a six-bar driven at its output
        raise ExportError(f"cannot export: {exc}") from None


# --------------------------------------------------------------------------------------------
# Paths along the circuit
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CircuitPaths:
    index: NDArray[np.int64]  # each kept sample's place on the circuit
    theta: Array
    positions: dict[str, Array]
    samples: int  # samples on the whole circuit, kept or not


def circuit_runs(index: NDArray[np.int64], samples: int) -> list[tuple[NDArray[np.int64], bool]]:
    """The kept samples as pieces of the closed circuit: (positions into ``index``, closed).

    The circuit always closes, so with every sample kept it is one closed piece. A sample the
    engine could not place (rounding at a limit position) breaks it into open pieces, joined
    across the circuit's start where both ends are kept, so no chord bridges a gap.
    """
    k = np.arange(len(index))
    if len(index) == samples:
        return [(k, True)]
    cuts = np.flatnonzero(np.diff(index) > 1) + 1
    pieces = np.split(k, cuts)
    if len(pieces) > 1 and index[0] == 0 and index[-1] == samples - 1:
        pieces = [np.concatenate((pieces[-1], pieces[0]))] + pieces[1:-1]
    return [(piece, False) for piece in pieces]


def checked_samples(samples: object) -> int:
    if (
        isinstance(samples, bool)
        or not isinstance(samples, numbers.Integral)
        or not 3 <= int(samples) <= MAX_SAMPLES
    ):
        raise ExportError(f"samples: must be an integer from 3 to {MAX_SAMPLES}, got {samples!r}")
    return int(samples)


def circuit_paths(mechanism: Mechanism, samples: object) -> CircuitPaths:
    n = checked_samples(samples)
    plan_of(mechanism)
    if mechanism.batch_shape != ():
        raise ExportError(
            f"cannot export a batch of {math.prod(mechanism.batch_shape)} mechanisms "
            f"(shape {mechanism.batch_shape}): export one at a time"
        )
    try:
        if mechanism.plan.triads:
            # A triad's circuits are found together, none where it never assembles.
            found = circuits(mechanism, n, order=0)[1]
            motion = found[running_circuit(mechanism, n)] if found else None
        else:
            motion = circuit(mechanism, n, order=0)
    except ValueError as exc:  # e.g. a gear ratio that never repeats: no closed circuit
        raise ExportError(f"cannot trace the circuit: {exc}") from None
    if motion is None or not np.asarray(motion.valid, dtype=bool).any():
        raise ExportError("the linkage cannot be assembled at any input (with its assembly)")
    valid = np.asarray(motion.valid, dtype=bool)
    return CircuitPaths(
        index=np.flatnonzero(valid),
        theta=np.asarray(motion.input, dtype=float)[valid],
        positions={k: np.asarray(v, dtype=float)[valid] for k, v in motion.positions.items()},
        samples=n,
    )


def joint_paths(mechanism: Mechanism, *, samples: int = 360) -> tuple[Array, dict[str, Array]]:
    """Every joint's positions along the circuit the machine runs.

    Parameters
    ----------
    mechanism : Mechanism
        One mechanism of any family, in the plane or on the sphere.
    samples : int
        Samples along the circuit (3 to 1,000,000). Where the input rocks, the circuit passes
        both legs (the input runs up, then back down), and both limit positions are samples.

    Returns
    -------
    theta : numpy.ndarray, shape (n,)
        The input angle (radians) of each sample: n = ``samples``, less any sample the engine
        could not place (which only rounding at a limit position could cause).
    positions : dict of str to numpy.ndarray
        Every joint of the plan, in plan order: shape (n, 2) in the plane, (n, 3) unit vectors
        on the sphere.

    Raises
    ------
    ExportError
        If the linkage cannot be assembled at any input, ``samples`` is not an integer in
        range, the mechanism is a batch or has no construction plan.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> theta, paths = joint_paths(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5,
    ...                                    rocker=3.5), samples=4)
    >>> np.degrees(theta)
    array([  0.,  90., 180., 270.])
    >>> paths["A"].round(12) + 0.0
    array([[ 1.,  0.],
           [ 0.,  1.],
           [-1.,  0.],
           [ 0., -1.]])

    A four-bar that cannot close at any input:

    >>> joint_paths(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3))
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.io.exports.ExportError: the linkage cannot be assembled at any input ...
    """
    paths = circuit_paths(mechanism, samples)
    return paths.theta, paths.positions


def pose_at(
    mechanism: Mechanism, paths: CircuitPaths, at: object
) -> tuple[float, dict[str, Array]]:
    """The input angle and every joint's position at the drawn pose."""
    if at is None:
        return float(paths.theta[0]), {k: v[0] for k, v in paths.positions.items()}
    if isinstance(at, bool) or not isinstance(at, numbers.Real) or not math.isfinite(at):
        raise ExportError(f"at: must be a finite input angle in radians, got {at!r}")
    motion = solve(mechanism, np.array([float(at)]), order=0)
    if not bool(np.asarray(motion.valid).all()):
        lo, hi = np.degrees(paths.theta.min()), np.degrees(paths.theta.max())
        raise ExportError(
            f"at: the linkage cannot be assembled at the input {math.degrees(at):.6g}° with its "
            f"assembly (its circuit runs over {lo:.6g}° to {hi:.6g}°)"
        )
    return float(at), {k: np.asarray(v, dtype=float)[0] for k, v in motion.positions.items()}


def length_unit(units: object, space: str) -> str | None:
    """The canonical unit name (a key of :data:`INSUNITS`) of a document's units."""
    if units is None:
        return None
    if not isinstance(units, str):
        raise ExportError(f"units: must be a string or None, got {units!r}")
    word = units.strip().lower()
    for canonical, names in _UNIT_NAMES.items():
        if word in names:
            return canonical
    if space == "sphere" and word in _ANGLE_UNITS:
        return None
    known = ", ".join(k for k in INSUNITS if k)
    raise ExportError(f"units: unknown length unit {units!r} (known: {known}, or none)")


# --------------------------------------------------------------------------------------------
# Writing files atomically
# --------------------------------------------------------------------------------------------


def target_path(out: str | os.PathLike[str], suffix: str | None = None) -> tuple[pathlib.Path, str]:
    path = pathlib.Path(out)
    fmt = path.suffix.lower().lstrip(".")
    if suffix is not None and fmt != suffix:
        raise ExportError(
            f"out: a {suffix.upper()} export must end in .{suffix}, got {path.name!r}"
        )
    if fmt not in FORMATS:
        shown = path.suffix or "no suffix"
        raise ExportError(
            f"out: unknown format {shown!r} for {path.name!r} "
            f"(exports are written as {', '.join('.' + f for f in FORMATS)})"
        )
    return path, fmt


def write_atomically(path: pathlib.Path, write: Callable[[pathlib.Path], None]) -> pathlib.Path:
    """Call ``write(temporary)`` and put the result at ``path`` whole
    (:func:`linkwright.files.atomic_path`)."""
    try:
        with atomic_path(path) as temporary:
            write(temporary)
    except OSError as exc:
        raise ExportError(f"out: cannot write {str(path)!r}: {exc.strerror or exc}") from None
    return path


# --------------------------------------------------------------------------------------------
# The drawing, in 2-D page coordinates (plane) or on the unit sphere
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Drawing:
    """Everything the SVG and DXF writers draw, in drawing coordinates (y up)."""

    space: str
    theta: float
    pose: dict[str, Array]  # joint → point (plane) or unit vector (sphere)
    pivots: tuple[str, ...]  # ground pivots drawn
    moving: tuple[str, ...]  # moving joints drawn
    binary: tuple[tuple[str, str], ...]
    polygons: tuple[tuple[str, ...], ...]  # links of ≥ 3 distinct joints, vertices in order
    guides: tuple[tuple[Array, Array, bool], ...]  # (start, end, fixed) at the pose (plane)
    blocks: tuple[Array, ...]  # slider blocks as 4 corners (plane)
    curves: dict[str, list[tuple[Array, bool]]]  # joint → its pieces (points, closed)
    radius: float  # joint circle radius (drawing units; plane) or arc (sphere)
    centre: Array | None  # the sphere's direction at the middle of the SVG page


def build_drawing(mechanism: Mechanism, at: object, samples: object) -> Drawing:
    paths = circuit_paths(mechanism, samples)
    theta, pose = pose_at(mechanism, paths, at)
    topo = topology(mechanism)
    plan = plan_of(mechanism)
    runs = circuit_runs(paths.index, paths.samples)
    traced = {j: [(paths.positions[j][k], closed) for k, closed in runs] for j in plan.traced}
    everything = np.concatenate([*paths.positions.values(), *(p[None] for p in pose.values())])
    if mechanism.space == "sphere":
        centre = unit_rows(everything.mean(axis=0))
        if not np.all(np.isfinite(centre)):  # symmetric about O: any joint will do
            centre = everything[0]
        flat = lambert_azimuthal(everything, centre)
    else:
        centre = None
        flat = everything
    size = float(np.max(np.ptp(flat, axis=0))) or 1.0
    binary, polygons = [], []
    for link in topo.links:
        distinct = _distinct(link, pose, 1e-12 * size)
        if len(distinct) == 2:
            binary.append((distinct[0], distinct[1]))
        elif len(distinct) >= 3:
            polygons.append(_around(distinct, pose, mechanism.space))
    shortest = [_length(pose[a], pose[b], mechanism.space) for a, b in binary]
    shortest = [s for s in shortest if s > 0]
    radius = 0.012 * size
    if shortest:
        radius = min(radius, 0.2 * min(shortest))
    guides, blocks = _guides(topo, paths.positions, pose, radius)
    moving = tuple(j for j in plan.joints if j not in topo.ground)
    return Drawing(
        space=mechanism.space,
        theta=theta,
        pose=pose,
        pivots=topo.pivots,
        moving=moving,
        binary=tuple(binary),
        polygons=tuple(polygons),
        guides=tuple(guides),
        blocks=tuple(blocks),
        curves=traced,
        radius=float(radius),
        centre=centre,
    )


def _length(a: Array, b: Array, space: str) -> float:
    if space == "sphere":
        return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))
    return float(np.hypot(*(b - a)))


def _distinct(link: Iterable[str], pose: Mapping[str, Array], tol: float) -> list[str]:
    """The link's joints, leaving out any that sits on an earlier one (a point put on a pin)."""
    out: list[str] = []
    for j in link:
        if all(np.max(np.abs(pose[j] - pose[k])) > tol for k in out):
            out.append(j)
    return out


def _around(link: list[str], pose: Mapping[str, Array], space: str) -> tuple[str, ...]:
    """The link's joints in order around their centre, so the outline does not cross itself."""
    pts = np.stack([pose[j] for j in link])
    if space == "sphere":
        mean = unit_rows(pts.mean(axis=0))
        e1, e2 = map_frame(mean)
        angle = np.arctan2(pts @ e2, pts @ e1)
    else:
        rel = pts - pts.mean(axis=0)
        angle = np.arctan2(rel[:, 1], rel[:, 0])
    return tuple(link[i] for i in np.argsort(angle, kind="stable"))


def _guides(
    topo: Topology, positions: Mapping[str, Array], pose: Mapping[str, Array], radius: float
) -> tuple[list[tuple[Array, Array, bool]], list[Array]]:
    """Each guide as a segment covering its sliders' travel, and a block at each slider."""
    segments: list[tuple[Array, Array, bool]] = []
    blocks: list[Array] = []
    for guide in topo.guides:
        d = np.array([math.cos(guide.angle), math.sin(guide.angle)])
        n = np.array([-d[1], d[0]])
        base = positions[guide.through]
        sliders = guide.sliders
        # The guide reaches its own joint too, so a guide carried by a link is seen to hang
        # on it, and a fixed one shows where it was placed.
        along = np.concatenate([np.zeros(1), *((positions[j] - base) @ d for j in sliders)])
        lo, hi = float(along.min()), float(along.max())
        pad = 0.1 * (hi - lo) + 4.0 * radius
        origin = pose[guide.through]
        segments.append((origin + (lo - pad) * d, origin + (hi + pad) * d, guide.fixed))
        for j in sliders:
            c = pose[j]
            a, b = 2.2 * radius, 1.5 * radius
            blocks.append(np.stack([c + sa * a * d + sb * b * n for sa, sb in
                                    ((-1, -1), (1, -1), (1, 1), (-1, 1))]))  # fmt: skip
    return segments, blocks


# --------------------------------------------------------------------------------------------
# The sphere on the page
# --------------------------------------------------------------------------------------------


def unit_rows(v: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        unit: Array = v / np.linalg.norm(v, axis=-1, keepdims=True)
    return unit


def slerp(a: Array, b: Array, step: float = math.radians(2.0)) -> Array:
    """Unit vectors along the shorter great-circle arc from a to b, both ends exact."""
    omega = _length(a, b, "sphere")
    n = max(2, math.ceil(omega / step) + 1)
    t = unit_rows(b - np.dot(a, b) * a)
    if not np.all(np.isfinite(t)):
        return np.stack((a, b))
    s = np.linspace(0.0, omega, n)[:, None]
    arc = np.cos(s) * a + np.sin(s) * t
    arc[0], arc[-1] = a, b
    return arc


def outline(joints: tuple[str, ...], pose: Mapping[str, Array], closed: bool) -> Array:
    """Great-circle arcs through the joints in turn (back to the first if closed)."""
    order = list(joints) + ([joints[0]] if closed else [])
    parts = [slerp(pose[a], pose[b]) for a, b in itertools.pairwise(order)]
    out = np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])
    return out[:-1] if closed else out


def triangle(p: Array, r: float) -> Array:
    """The ground symbol: a triangle under the pivot, its apex at the pivot."""
    return p + r * np.array([[0.0, 0.0], [-2.0, -3.2], [2.0, -3.2]])

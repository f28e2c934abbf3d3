"""Export to CAD: joint paths as CSV, the linkage and its curves as SVG and DXF.

Every format is built from the circuit the machine runs (:func:`linkwright.mechanisms.circuit`):
where the input turns fully that is one turn (several for a linkage geared at a fractional
ratio); where it rocks, the input sweeps its arc up and back down and the rows pass both legs.
The drawings show the linkage at one pose and the closed paths of the traced joints.

* **CSV** (:func:`export_csv`): a header row, then one row per circuit sample: ``sample`` (its
  index on the circuit), ``theta_deg`` and ``theta_rad`` (the input; radians too, so that a row
  can be solved again exactly, even at a limit position, where a joint moves like the square
  root of the input), then ``<joint>_x``, ``<joint>_y`` (and ``<joint>_z`` on the sphere, where
  joints are unit vectors) for *every* joint of the plan in plan order, ground joints included
  (constant columns, kept so that every row is a whole pose). Numbers are written by
  :func:`number_text`: full double precision. Plain CSV without a comment line, for
  ``numpy.loadtxt(path, delimiter=",", skiprows=1)`` and spreadsheets.
* **SVG** (:func:`export_svg`): plain SVG 1.1 text, in groups ``<g id="ground">`` (pivots as
  triangles, fixed slider guides dashed), ``"links"`` (binary links as lines, links of three
  or more joints as closed polygons, slider blocks, guides carried by a link), ``"curves"``,
  ``"joints"`` (circles; ground pivots grey, traced joints yellow) and ``"labels"``. The y axis
  is flipped (SVG y = −y), so the picture is upright, and the viewBox fits everything with a
  margin. ``width``/``height`` carry the document's units where SVG has them (mm, cm, in; m
  and ft are written as mm and in, exactly scaled), one drawing unit to the unit; unitless
  drawings are sized in pixels (800 on the longer side). On the sphere the picture is Lambert's
  azimuthal equal-area projection (:func:`linkwright.geometry.sphere.lambert_azimuthal`)
  centred on the mean direction of the joints over the circuit, in units of the sphere's
  radius and sized in pixels; its ``<desc>`` says so and gives the centre.
* **DXF** (:func:`export_dxf`, written with ezdxf, release R2010): layers ``LINKS`` (a LINE per
  binary link, a closed LWPOLYLINE per link of three or more joints and per slider block, a
  LINE per slider guide carried by a link), ``JOINTS`` (a CIRCLE per moving joint), ``GROUND``
  (a CIRCLE and a closed triangle per ground pivot, a LINE per fixed slider guide), ``LABELS``
  (a TEXT per drawn joint) and ``CURVE-<joint>`` (a LWPOLYLINE per traced joint, closed: the
  circuit closes). ``$INSUNITS`` comes from the document's units (mm 4, cm 5, m 6, in 1,
  ft 2; none: 0, unitless). On the sphere the drawing is 3-D, on the sphere of radius 1 about
  the origin (scale it to the real radius in CAD): every link is a POLYLINE along great-circle
  arcs (closed around a link of three or more joints), every curve a closed 3-D POLYLINE of
  unit vectors, every joint a CIRCLE in the sphere's tangent plane at the joint (ground
  pivots on ``GROUND``), and the model view looks at the linkage from outside the sphere.

A sample the engine could not place (only rounding at a limit position could cause one) is
left out: its row is missing (the ``sample`` column shows the gap) and the curves break there
into open pieces rather than bridge it with a chord.

Every file is written atomically: to a temporary file beside the target, then renamed over it
(:func:`os.replace`), so an interrupted export leaves the old file or none, never part of one.

Which joints a link joins is read from the construction plan (:func:`topology`), the idea of
the plotting modules' link lists, extended to rigid bodies of three or more joints.
"""

from __future__ import annotations

import csv
import itertools
import math
import numbers
import os
import pathlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from xml.sax.saxutils import escape, quoteattr

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
from linkwright.engine.plan import placed_joints
from linkwright.files import atomic_path
from linkwright.geometry.sphere import lambert_azimuthal, map_frame
from linkwright.mechanisms import Mechanism, circuit, circuits, solve

__all__ = [
    "FORMATS",
    "INSUNITS",
    "ExportError",
    "Guide",
    "Topology",
    "export",
    "export_csv",
    "export_dxf",
    "export_svg",
    "joint_paths",
    "number_text",
    "topology",
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
_SVG_UNITS = {"mm": ("mm", 1.0), "cm": ("cm", 1.0), "in": ("in", 1.0), "m": ("mm", 1000.0),
              "ft": ("in", 12.0)}  # fmt: skip
MAX_SAMPLES = 1_000_000
SVG_PIXELS = 800.0  # the longer side of a unitless SVG

LINK = "#1f3b57"
BODY = "#c6dbef"
GROUND = "#6b6b6b"
CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")
DXF_CURVE_COLOURS = (1, 5, 3, 6, 30)  # ACI red, blue, green, magenta, orange


class ExportError(ValueError):
    """An export that cannot be written: the message names the argument and the problem."""


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
    plan = _plan(mechanism)
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
            # A ternary link held by three binary links, each from an anchor to its joint.
            for anchor, joint in step.links()[:3]:
                used_as_pivot.add(anchor)
                new_body(anchor, joint)
            new_body(*placed_joints(step))
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


def _plan(mechanism: Mechanism):
    try:
        return mechanism.plan
    except ValueError as exc:  # NoConstructionPlan: a six-bar driven at its output
        raise ExportError(f"cannot export: {exc}") from None


# --------------------------------------------------------------------------------------------
# Paths along the circuit
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Paths:
    index: NDArray[np.int64]  # each kept sample's place on the circuit
    theta: Array
    positions: dict[str, Array]
    samples: int  # samples on the whole circuit, kept or not


def _runs(index: NDArray[np.int64], samples: int) -> list[tuple[NDArray[np.int64], bool]]:
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


def _check_samples(samples: object) -> int:
    if (
        isinstance(samples, bool)
        or not isinstance(samples, numbers.Integral)
        or not 3 <= samples <= MAX_SAMPLES
    ):
        raise ExportError(f"samples: must be an integer from 3 to {MAX_SAMPLES}, got {samples!r}")
    return int(samples)


def _circuit_paths(mechanism: Mechanism, samples: object) -> _Paths:
    n = _check_samples(samples)
    _plan(mechanism)
    if mechanism.batch_shape != ():
        raise ExportError(
            f"cannot export a batch of {math.prod(mechanism.batch_shape)} mechanisms "
            f"(shape {mechanism.batch_shape}): export one at a time"
        )
    try:
        if mechanism.plan.triads:
            # A triad's circuits are found together, none where it never assembles.
            found = circuits(mechanism, n, order=0)[1]
            motion = found[0] if found else None
        else:
            motion = circuit(mechanism, n, order=0)
    except ValueError as exc:  # e.g. a gear ratio that never repeats: no closed circuit
        raise ExportError(f"cannot trace the circuit: {exc}") from None
    valid = np.asarray(motion.valid, dtype=bool) if motion is not None else np.zeros(1, bool)
    if not valid.any():
        raise ExportError("the linkage cannot be assembled at any input (with its assembly)")
    return _Paths(
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
    paths = _circuit_paths(mechanism, samples)
    return paths.theta, paths.positions


def _pose(mechanism: Mechanism, paths: _Paths, at: object) -> tuple[float, dict[str, Array]]:
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


def _units(units: object, space: str) -> str | None:
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


def _target(out: str | os.PathLike[str], suffix: str | None = None) -> tuple[pathlib.Path, str]:
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


def _write_atomically(path: pathlib.Path, write: Callable[[pathlib.Path], None]) -> pathlib.Path:
    """Call ``write(temporary)`` and put the result at ``path`` whole
    (:func:`linkwright.files.atomic_path`)."""
    try:
        with atomic_path(path) as temporary:
            write(temporary)
    except OSError as exc:
        raise ExportError(f"out: cannot write {str(path)!r}: {exc.strerror or exc}") from None
    return path


# --------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------


def export_csv(
    mechanism: Mechanism, out: str | os.PathLike[str], *, samples: int = 360
) -> pathlib.Path:
    """Write every joint's path along the circuit as CSV (see the module notes for columns).

    Parameters
    ----------
    mechanism : Mechanism
        One mechanism of any family.
    out : str or os.PathLike
        Destination ending in ``.csv``; missing parent folders are created.
    samples : int
        Rows (samples along the circuit, 3 to 1,000,000).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ExportError
        As :func:`joint_paths`, or if ``out`` does not end in ``.csv``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from linkwright.mechanisms import FourBar
    >>> four_bar = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    >>> out = export_csv(four_bar, pathlib.Path(tempfile.mkdtemp()) / "paths.csv", samples=4)
    >>> print(out.read_text().splitlines()[0])
    sample,theta_deg,theta_rad,A0_x,A0_y,B0_x,B0_y,A_x,A_y,B_x,B_y,P_x,P_y
    >>> np.loadtxt(out, delimiter=",", skiprows=1)[:, [1, 9, 10]].round(6)
    array([[  0.      ,   4.625   ,   3.443744],
           [ 90.      ,   4.339621,   3.483484],
           [180.      ,   2.775   ,   3.278624],
           [270.      ,   2.660379,   3.233484]])
    """
    path, _ = _target(out, "csv")
    return _write_csv(_circuit_paths(mechanism, samples), path)


def _write_csv(paths: _Paths, path: pathlib.Path) -> pathlib.Path:
    axes = ("x", "y", "z")[: next(iter(paths.positions.values())).shape[-1]]
    header = ["sample", "theta_deg", "theta_rad"]
    header += [f"{joint}_{a}" for joint in paths.positions for a in axes]
    table = np.concatenate(
        [np.degrees(paths.theta)[:, None], paths.theta[:, None], *paths.positions.values()],
        axis=1,
    )

    def write(tmp: pathlib.Path) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as handle:
            rows = csv.writer(handle, lineterminator="\n")
            rows.writerow(header)
            for k, row in zip(paths.index, table, strict=True):
                rows.writerow(_csv_row(int(k), row))

    return _write_atomically(path, write)


def _csv_row(k: int, row: Array) -> list[str]:
    return [str(k), *(number_text(x) for x in row)]


def number_text(value: object) -> str:
    """One number as every CSV (and full-precision text) writer of linkwright prints it.

    A float gives the shortest text that reads back as the same double (Python's ``repr``), an
    integer has no decimal point, NaN (a missing value) gives the empty string and infinities
    ``inf`` and ``-inf`` (which ``float`` reads back). NumPy scalars print as their values:
    under NumPy 2, ``repr`` of one is ``np.float64(…)``, which no CSV reader takes for a number.

    Raises
    ------
    TypeError
        For anything that is not a real number (a bool, a string, an array of several values):
        a text column is the writer's to declare, not this function's to guess.

    Examples
    --------
    >>> [number_text(v) for v in (np.float64(-180.0), np.int64(3), 0.1, math.nan, -math.inf)]
    ['-180.0', '3', '0.1', '', '-inf']
    """
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise TypeError(f"not a number: {value!r}")
    if isinstance(value, numbers.Integral):
        return str(int(value))
    x = float(value)
    return "" if math.isnan(x) else repr(x)


# --------------------------------------------------------------------------------------------
# The drawing, in 2-D page coordinates (plane) or on the unit sphere
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Drawing:
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


def _drawing(mechanism: Mechanism, at: object, samples: object) -> _Drawing:
    paths = _circuit_paths(mechanism, samples)
    theta, pose = _pose(mechanism, paths, at)
    topo = topology(mechanism)
    plan = _plan(mechanism)
    runs = _runs(paths.index, paths.samples)
    traced = {j: [(paths.positions[j][k], closed) for k, closed in runs] for j in plan.traced}
    everything = np.concatenate([*paths.positions.values(), *(p[None] for p in pose.values())])
    if mechanism.space == "sphere":
        centre = _unit_rows(everything.mean(axis=0))
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
    return _Drawing(
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
        mean = _unit_rows(pts.mean(axis=0))
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


def _unit_rows(v: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _slerp(a: Array, b: Array, step: float = math.radians(2.0)) -> Array:
    """Unit vectors along the shorter great-circle arc from a to b, both ends exact."""
    omega = _length(a, b, "sphere")
    n = max(2, math.ceil(omega / step) + 1)
    t = _unit_rows(b - np.dot(a, b) * a)
    if not np.all(np.isfinite(t)):
        return np.stack((a, b))
    s = np.linspace(0.0, omega, n)[:, None]
    arc = np.cos(s) * a + np.sin(s) * t
    arc[0], arc[-1] = a, b
    return arc


def _outline(joints: tuple[str, ...], pose: Mapping[str, Array], closed: bool) -> Array:
    """Great-circle arcs through the joints in turn (back to the first if closed)."""
    order = list(joints) + ([joints[0]] if closed else [])
    parts = [_slerp(pose[a], pose[b]) for a, b in itertools.pairwise(order)]
    out = np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])
    return out[:-1] if closed else out


# --------------------------------------------------------------------------------------------
# SVG
# --------------------------------------------------------------------------------------------


def _fmt(x: float) -> str:
    return repr(float(x) + 0.0)  # + 0.0: no "-0.0"


def _pts(xy: Array) -> str:
    return " ".join(f"{_fmt(x)},{_fmt(-y)}" for x, y in xy)


def export_svg(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    at: float | None = None,
    samples: int = 360,
    units: str | None = None,
    title: str | None = None,
) -> pathlib.Path:
    """Draw the linkage at a pose and its traced joints' curves as an SVG file.

    Parameters
    ----------
    mechanism : Mechanism
        One mechanism of any family, in the plane or on the sphere.
    out : str or os.PathLike
        Destination ending in ``.svg``; missing parent folders are created.
    at : float, optional
        Input angle of the pose (radians), on the mechanism's assembly; default: the first
        sample of the circuit.
    samples : int
        Samples along each curve.
    units : str, optional
        The document's length units (mm, cm, m, in, ft; None: unitless, sized in pixels).
    title : str, optional
        The drawing's ``<title>``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ExportError
        As :func:`joint_paths`; if the linkage does not assemble at ``at``; for unknown units.

    Examples
    --------
    >>> import tempfile, pathlib, xml.etree.ElementTree as ET
    >>> from linkwright.mechanisms import FourBar
    >>> four_bar = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> out = export_svg(four_bar, pathlib.Path(tempfile.mkdtemp()) / "f.svg", samples=90,
    ...                  units="mm")
    >>> svg = ET.parse(out).getroot()
    >>> svg.get("width")[-2:], [g.get("id") for g in svg.iter("{http://www.w3.org/2000/svg}g")]
    ('mm', ['ground', 'links', 'curves', 'joints', 'labels'])
    """
    path, _ = _target(out, "svg")
    unit = _units(units, _plan(mechanism).space)
    drawing = _drawing(mechanism, at, samples)
    text = _svg_text(drawing, unit, title)

    def write(tmp: pathlib.Path) -> None:
        tmp.write_text(text, encoding="utf-8")

    return _write_atomically(path, write)


def _svg_text(d: _Drawing, unit: str | None, title: str | None) -> str:
    sphere = d.centre is not None

    def page(v: Array) -> Array:
        return lambert_azimuthal(v, d.centre) if d.centre is not None else np.asarray(v)

    at = {j: page(p) for j, p in d.pose.items()}
    curves = {j: [(page(c), closed) for c, closed in pieces] for j, pieces in d.curves.items()}
    if sphere:
        binary = [page(_slerp(d.pose[a], d.pose[b])) for a, b in d.binary]
        polygons = [page(_outline(p, d.pose, True)) for p in d.polygons]
    else:
        binary = [np.stack((at[a], at[b])) for a, b in d.binary]
        polygons = [np.stack([at[j] for j in p]) for p in d.polygons]
    drawn = d.pivots + d.moving
    pieces = [c for runs in curves.values() for c, _ in runs]
    pieces += [*binary, *polygons, *d.blocks, np.stack([at[j] for j in drawn])]
    pieces += [np.stack(g[:2]) for g in d.guides]
    box = np.concatenate(pieces)
    lo, hi = box.min(axis=0), box.max(axis=0)
    r = d.radius
    margin = 0.06 * (float(np.max(hi - lo)) or 1.0) + 4 * r
    x0, y0 = lo[0] - margin, -(hi[1] + margin)  # SVG y = −y
    w, h = hi[0] - lo[0] + 2 * margin, hi[1] - lo[1] + 2 * margin
    if unit is not None and not sphere:
        name, factor = _SVG_UNITS[unit]
        width, height = f"{_fmt(w * factor)}{name}", f"{_fmt(h * factor)}{name}"
    else:
        k = SVG_PIXELS / max(w, h)
        width, height = f"{w * k:.2f}", f"{h * k:.2f}"
    stroke = 0.35 * r
    ids = _Ids()
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{width}" '
        f'height="{height}" viewBox="{_fmt(x0)} {_fmt(y0)} {_fmt(w)} {_fmt(h)}">',
        f"<title>{escape(title or 'linkwright export')}</title>",
        f"<desc>{escape(_svg_desc(d, unit))}</desc>",
        f'<g id="ground" stroke="{GROUND}" stroke-width="{_fmt(0.6 * stroke)}">',
    ]
    dashes = f'stroke-dasharray="{_fmt(3 * r)},{_fmt(1.5 * r)}"'
    for start, end, fixed in d.guides:
        if fixed:
            out.append(f"<line {_ends(start, end)} {dashes}/>")
    for j in d.pivots:
        out.append(
            f'<polygon id={ids("ground-", j)} fill="{GROUND}" '
            f'points="{_pts(_triangle(at[j], r))}"/>'
        )
    out.append("</g>")
    out.append(
        f'<g id="links" stroke="{LINK}" stroke-width="{_fmt(stroke)}" stroke-linecap="round" '
        'stroke-linejoin="round">'
    )
    for joints, xy in zip(d.polygons, polygons, strict=True):
        out.append(
            f'<polygon id={ids("link-", *joints)} fill="{BODY}" fill-opacity="0.7" '
            f'points="{_pts(xy)}"/>'
        )
    for (a, b), xy in zip(d.binary, binary, strict=True):
        if sphere:
            out.append(f'<polyline id={ids("link-", a, b)} fill="none" points="{_pts(xy)}"/>')
        else:
            (xa, ya), (xb, yb) = xy
            out.append(
                f'<line id={ids("link-", a, b)} x1="{_fmt(xa)}" y1="{_fmt(-ya)}" '
                f'x2="{_fmt(xb)}" y2="{_fmt(-yb)}"/>'
            )
    for start, end, fixed in d.guides:
        if not fixed:  # a guide carried by a moving joint is part of that link
            out.append(f'<line {_ends(start, end)} stroke-width="{_fmt(0.6 * stroke)}" {dashes}/>')
    for block in d.blocks:
        out.append(f'<polygon fill="white" points="{_pts(block)}"/>')
    out.append("</g>")
    # The curves go over the links, so that no part of a path hides under a coupler plate.
    out.append(
        f'<g id="curves" fill="none" stroke-width="{_fmt(0.6 * stroke)}" stroke-linejoin="round">'
    )
    for i, (joint, runs) in enumerate(curves.items()):
        for xy, closed in runs:
            tag = "polygon" if closed else "polyline"
            out.append(
                f'<{tag} id={ids("curve-", joint)} stroke="{CURVES[i % len(CURVES)]}" '
                f'points="{_pts(xy)}"/>'
            )
    out.append("</g>")
    out.append(f'<g id="joints" stroke="{LINK}" stroke-width="{_fmt(0.5 * stroke)}">')
    for j in drawn:
        fill = GROUND if j in d.pivots else ("#ffd24d" if j in d.curves else "white")
        x, y = at[j]
        out.append(
            f'<circle id={ids("joint-", j)} cx="{_fmt(x)}" cy="{_fmt(-y)}" r="{_fmt(r)}" '
            f'fill="{fill}"/>'
        )
    out.append("</g>")
    # Text is drawn at 12 units and scaled down: renderers hint glyphs at their nominal size,
    # and a font of a few hundredths of a unit (the sphere's pictures) comes out garbled.
    scale = 3.0 * r / 12.0
    out.append(
        f'<g id="labels" font-family="sans-serif" font-size="12" fill="#222222" '
        f'transform="scale({_fmt(scale)})">'
    )
    for j in drawn:
        x, y = at[j]
        out.append(
            f'<text x="{_fmt((x + 1.4 * r) / scale)}" y="{_fmt((-y - 1.4 * r) / scale)}">'
            f"{escape(j)}</text>"
        )
    out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _ends(start: Array, end: Array) -> str:
    return f'x1="{_fmt(start[0])}" y1="{_fmt(-start[1])}" x2="{_fmt(end[0])}" y2="{_fmt(-end[1])}"'


def _svg_desc(d: _Drawing, unit: str | None) -> str:
    if d.centre is not None:
        c = ", ".join(_fmt(v) for v in d.centre)
        desc = (
            "Spherical linkage on the unit sphere, drawn in Lambert's azimuthal equal-area "
            f"projection centred on ({c}), the mean direction of its joints over the circuit: "
            "a point at the arc δ from the centre lies at 2·sin(δ/2) from the middle of the "
            "picture (in units of the sphere's radius), at its own azimuth; up is +z (+y if "
            "the centre is ±z), seen from outside the sphere. Links are great-circle arcs."
        )
    else:
        shown = f"in {unit}" if unit else "unitless"
        desc = f"Planar linkage, lengths {shown}; y points up (SVG y = −y)."
    desc += f" Pose at the input θ = {math.degrees(d.theta):.12g}°."
    whole = all(closed for runs in d.curves.values() for _, closed in runs)
    desc += " Curves: " + (
        "closed, the whole circuit."
        if whole
        else "open pieces (samples where the linkage did not assemble are left out)."
    )
    return desc


class _Ids:
    """Unique XML ids (quoted) from joint names: ASCII letters, digits, - _ . only."""

    def __init__(self) -> None:
        self.used: set[str] = set()

    def __call__(self, prefix: str, *names: str) -> str:
        safe = "-".join(names).encode("ascii", "replace").decode()
        base = prefix + "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in safe)
        ident, k = base, 1
        while ident in self.used:
            k += 1
            ident = f"{base}.{k}"
        self.used.add(ident)
        return quoteattr(ident)


def _triangle(p: Array, r: float) -> Array:
    """The ground symbol: a triangle under the pivot, its apex at the pivot."""
    return p + r * np.array([[0.0, 0.0], [-2.0, -3.2], [2.0, -3.2]])


# --------------------------------------------------------------------------------------------
# DXF
# --------------------------------------------------------------------------------------------


def _layer_name(prefix: str, joint: str) -> str:
    # DXF layer names may not hold <>/\":;?*|=` (nor control characters).
    bad = set('<>/\\":;?*|=`')
    return prefix + "".join("_" if ch in bad or not ch.isprintable() else ch for ch in joint)


def export_dxf(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    at: float | None = None,
    samples: int = 360,
    units: str | None = None,
    title: str | None = None,
) -> pathlib.Path:
    """Draw the linkage at a pose and its traced joints' curves as a DXF file (R2010).

    Layers and entities are listed in the module notes. Planar drawings are in the document's
    units (``$INSUNITS``); spherical ones are 3-D on the sphere of radius 1.

    Parameters
    ----------
    mechanism, out, at, samples, units, title
        As :func:`export_svg`; ``out`` ends in ``.dxf``. The title is kept as the drawing's
        custom header property ``TITLE``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ExportError
        As :func:`export_svg`.

    Examples
    --------
    >>> import tempfile, pathlib, ezdxf
    >>> from linkwright.mechanisms import FourBar
    >>> four_bar = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> out = export_dxf(four_bar, pathlib.Path(tempfile.mkdtemp()) / "f.dxf", samples=90,
    ...                  units="mm")
    >>> doc = ezdxf.readfile(out)
    >>> doc.header["$INSUNITS"], [(e.dxftype(), round(e.dxf.start.distance(e.dxf.end), 12))
    ...                            for e in doc.modelspace().query("LINE[layer=='LINKS']")]
    (4, [('LINE', 1.0), ('LINE', 3.5)])
    """
    import ezdxf

    path, _ = _target(out, "dxf")
    unit = _units(units, _plan(mechanism).space)
    drawing = _drawing(mechanism, at, samples)
    doc = ezdxf.new("R2010", units=INSUNITS[unit])
    doc.header["$MEASUREMENT"] = 0 if unit in ("in", "ft") else 1
    if title:
        doc.header.custom_vars.append("TITLE", title.replace("\n", " "))
    for name, colour in (("LINKS", 5), ("JOINTS", 7), ("GROUND", 8), ("LABELS", 7)):
        doc.layers.add(name, color=colour)
    curve_layers = {}
    for i, joint in enumerate(drawing.curves):
        curve_layers[joint] = _layer_name("CURVE-", joint)
        if curve_layers[joint] not in doc.layers:
            doc.layers.add(curve_layers[joint], color=DXF_CURVE_COLOURS[i % 5])
    msp = doc.modelspace()
    if drawing.space == "sphere":
        _dxf_sphere(msp, drawing, curve_layers)
        # Open looking at the linkage from outside the sphere, along the picture's centre.
        view = doc.set_modelspace_vport(2.5, center=(0.0, 0.0))
        view.dxf.direction = tuple(map(float, drawing.centre))
        view.dxf.target = (0.0, 0.0, 0.0)
    else:
        _dxf_plane(msp, drawing, curve_layers)
        box = np.concatenate(
            [c for runs in drawing.curves.values() for c, _ in runs]
            + [p[None] for p in drawing.pose.values()]
        )
        lo, hi = box.min(axis=0), box.max(axis=0)
        doc.set_modelspace_vport(float(max(hi - lo)) * 1.2 or 1.0, center=tuple((lo + hi) / 2))

    def write(tmp: pathlib.Path) -> None:
        doc.saveas(tmp)

    return _write_atomically(path, write)


def _dxf_plane(msp, d: _Drawing, curve_layers: Mapping[str, str]) -> None:
    r = d.radius
    p = {j: tuple(map(float, v)) for j, v in d.pose.items()}
    for a, b in d.binary:
        msp.add_line(p[a], p[b], dxfattribs={"layer": "LINKS"})
    for joints in d.polygons:
        msp.add_lwpolyline([p[j] for j in joints], close=True, dxfattribs={"layer": "LINKS"})
    for block in d.blocks:
        msp.add_lwpolyline(block.tolist(), close=True, dxfattribs={"layer": "LINKS"})
    for start, end, fixed in d.guides:
        layer = "GROUND" if fixed else "LINKS"
        msp.add_line(tuple(start), tuple(end), dxfattribs={"layer": layer})
    for j in d.pivots:
        msp.add_circle(p[j], r, dxfattribs={"layer": "GROUND"})
        msp.add_lwpolyline(
            _triangle(d.pose[j], r).tolist(), close=True, dxfattribs={"layer": "GROUND"}
        )
    for j in d.moving:
        msp.add_circle(p[j], r, dxfattribs={"layer": "JOINTS"})
    for j in d.pivots + d.moving:
        x, y = p[j]
        msp.add_text(
            j, height=2.2 * r, dxfattribs={"layer": "LABELS", "insert": (x + 1.3 * r, y + 1.3 * r)}
        )
    for j, runs in d.curves.items():
        for xy, closed in runs:
            msp.add_lwpolyline(
                xy.tolist(), format="xy", close=closed, dxfattribs={"layer": curve_layers[j]}
            )


def _dxf_sphere(msp, d: _Drawing, curve_layers: Mapping[str, str]) -> None:
    from ezdxf.math import OCS

    r = d.radius
    for a, b in d.binary:
        msp.add_polyline3d(_slerp(d.pose[a], d.pose[b]).tolist(), dxfattribs={"layer": "LINKS"})
    for joints in d.polygons:
        msp.add_polyline3d(
            _outline(joints, d.pose, True).tolist(), close=True, dxfattribs={"layer": "LINKS"}
        )
    for j in d.pivots + d.moving:
        # A circle (and its label) lies in its entity's plane: the tangent plane at the joint,
        # whose normal is the joint's axis, given as the entity's extrusion (its OCS).
        axis = tuple(map(float, d.pose[j]))
        ocs = OCS(axis)
        layer = "GROUND" if j in d.pivots else "JOINTS"
        msp.add_circle(ocs.from_wcs(axis), r, dxfattribs={"layer": layer, "extrusion": axis})
        label = ocs.from_wcs(axis) + (1.3 * r, 1.3 * r, 0.0)
        msp.add_text(
            j,
            height=2.2 * r,
            dxfattribs={"layer": "LABELS", "insert": label, "extrusion": axis},
        )
    for j, runs in d.curves.items():
        for xyz, closed in runs:
            msp.add_polyline3d(xyz.tolist(), close=closed, dxfattribs={"layer": curve_layers[j]})


# --------------------------------------------------------------------------------------------
# By suffix
# --------------------------------------------------------------------------------------------


def export(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    at: float | None = None,
    samples: int = 360,
    units: str | None = None,
    title: str | None = None,
) -> pathlib.Path:
    """Export ``mechanism`` to ``out``, in the format its suffix names (.csv, .svg or .dxf).

    Parameters
    ----------
    mechanism : Mechanism
        One mechanism of any family, in the plane or on the sphere.
    out : str or os.PathLike
        The destination; missing parent folders are created, and the file is written
        atomically (an interrupted export leaves no partial file).
    at : float, optional
        Input angle (radians) of the pose the drawings show; default: the circuit's first
        sample. The CSV has every sample and ignores it (but still checks it assembles).
    samples : int
        Samples along the circuit (3 to 1,000,000).
    units : str, optional
        The document's units (``Document.units``): mm, cm, m, in or ft (common spellings
        accepted), or None for unitless.
    title : str, optional
        The drawing's title.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ExportError
        For an unknown suffix, unknown units, bad ``samples`` or ``at``, a linkage that cannot
        assemble at any input (or at ``at``), a batch, or a mechanism without a plan.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from linkwright.mechanisms import FourBar
    >>> four_bar = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> export(four_bar, folder / "f.svg", samples=30).name
    'f.svg'
    >>> export(four_bar, folder / "f.step")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.io.exports.ExportError: out: unknown format '.step' for 'f.step' (exports are ...
    """
    path, fmt = _target(out)
    _units(units, _plan(mechanism).space)
    if fmt == "csv":
        paths = _circuit_paths(mechanism, samples)
        _pose(mechanism, paths, at)  # a pose asked for must exist, even if the CSV has them all
        return _write_csv(paths, path)
    writer = export_svg if fmt == "svg" else export_dxf
    return writer(mechanism, path, at=at, samples=samples, units=units, title=title)

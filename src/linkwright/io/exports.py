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
  ``numpy.loadtxt(path, delimiter=",", skiprows=1)`` and spreadsheets. Given ``forces`` (a
  document's masses and loads, :func:`linkwright.dynamics.forces_setup`), the rows go on with
  the forces at each sample (:func:`forces_columns`): ``input_torque``, every reaction
  ``<joint>_Fx``, ``_Fy`` (``_Fz``; on the sphere also ``_Mx``, ``_My``, ``_Mz``, its moment),
  the shaking force ``shaking_Fx`` … and moment, in the document's units.
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
import math
import numbers
import os
import pathlib
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.io.dxf import export_dxf
from linkwright.io.export_geometry import (
    FORMATS,
    INSUNITS,
    CircuitPaths,
    ExportError,
    Guide,
    Topology,
    circuit_paths,
    joint_paths,
    length_unit,
    plan_of,
    pose_at,
    target_path,
    topology,
    write_atomically,
)
from linkwright.io.svg import export_svg
from linkwright.mechanisms import Mechanism

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
    "forces_columns",
    "joint_paths",
    "number_text",
    "topology",
]

Array = NDArray[np.float64]


# --------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------


def export_csv(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    samples: int = 360,
    forces: ForcesSetup | None = None,
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
    forces : (structure, masses, loads), optional
        As :func:`linkwright.dynamics.forces_setup` returns them: the forces' columns follow.

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
    path, _ = target_path(out, "csv")
    paths = circuit_paths(mechanism, samples)
    extra = forces_columns(mechanism, paths, forces) if forces is not None else {}
    return _write_csv(paths, path, extra)


ForcesSetup = tuple[Any, Mapping[str, Any], Any]
"""A document's (structure, masses, loads) for forces: :func:`linkwright.dynamics.forces_setup`."""


def forces_columns(
    mechanism: Mechanism, paths: CircuitPaths, forces: ForcesSetup
) -> dict[str, Array]:
    """The forces at the circuit's samples, as named CSV columns (see the module notes)."""
    from linkwright.dynamics import forces_of
    from linkwright.mechanisms import circuit, circuits, running_circuit

    st, masses, loads = forces
    if mechanism.plan.triads:
        motion = circuits(mechanism, paths.samples, order=2)[1][
            running_circuit(mechanism, paths.samples)
        ]
    else:
        motion = circuit(mechanism, paths.samples, order=2)
    f = forces_of(st, mechanism.params(), motion, masses, loads)
    rows = paths.index
    out: dict[str, Array] = {"input_torque": f.input_torque[rows]}
    for table, letter in ((f.reactions, "F"), (f.moments, "M")):
        for name, vectors in table.items():
            for k, axis in enumerate("xyz"[: vectors.shape[-1]]):
                out[f"{name}_{letter}{axis}"] = vectors[rows, k]
    shaking = f.shaking_force[rows]
    for k, axis in enumerate("xyz"[: shaking.shape[-1]]):
        out[f"shaking_F{axis}"] = shaking[:, k]
    moment = f.shaking_moment[rows]
    if moment.ndim == 1:
        out["shaking_M"] = moment
    else:
        for k, axis in enumerate("xyz"):
            out[f"shaking_M{axis}"] = moment[:, k]
    return out


def _write_csv(
    paths: CircuitPaths, path: pathlib.Path, extra: Mapping[str, Array] | None = None
) -> pathlib.Path:
    axes = ("x", "y", "z")[: next(iter(paths.positions.values())).shape[-1]]
    header = ["sample", "theta_deg", "theta_rad"]
    header += [f"{joint}_{a}" for joint in paths.positions for a in axes]
    extra = extra or {}
    header += list(extra)
    table = np.concatenate(
        [
            np.degrees(paths.theta)[:, None],
            paths.theta[:, None],
            *paths.positions.values(),
            *(np.asarray(v, dtype=float)[:, None] for v in extra.values()),
        ],
        axis=1,
    )

    def write(tmp: pathlib.Path) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as handle:
            rows = csv.writer(handle, lineterminator="\n")
            rows.writerow(header)
            for k, row in zip(paths.index, table, strict=True):
                rows.writerow(_csv_row(int(k), row))

    return write_atomically(path, write)


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
    forces: ForcesSetup | None = None,
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
    forces : (structure, masses, loads), optional
        The CSV carries the forces at each sample too (see :func:`export_csv`).

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
    path, fmt = target_path(out)
    length_unit(units, plan_of(mechanism).space)
    if fmt == "csv":
        paths = circuit_paths(mechanism, samples)
        pose_at(mechanism, paths, at)  # a pose asked for must exist, even if the CSV has them all
        extra = forces_columns(mechanism, paths, forces) if forces is not None else {}
        return _write_csv(paths, path, extra)
    writer = export_svg if fmt == "svg" else export_dxf
    return writer(mechanism, path, at=at, samples=samples, units=units, title=title)

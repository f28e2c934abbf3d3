"""The DXF writer of :mod:`.exports` (:func:`export_dxf`, written with ezdxf, release R2010):
the linkage at one pose on layers ``LINKS``, ``JOINTS``, ``GROUND``, ``LABELS`` and a
``CURVE-<joint>`` layer per traced joint; in 3-D on the unit sphere for a spherical linkage.
:mod:`.exports` describes the entities of each layer and the units.
"""

from __future__ import annotations

import os
import pathlib
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from linkwright.io.export_geometry import (
    INSUNITS,
    Drawing,
    build_drawing,
    length_unit,
    outline,
    plan_of,
    slerp,
    target_path,
    triangle,
    write_atomically,
)
from linkwright.mechanisms import Mechanism

if TYPE_CHECKING:  # ezdxf is imported where a file is written
    from ezdxf.layouts.layout import Modelspace

__all__ = ["export_dxf"]

DXF_CURVE_COLOURS = (1, 5, 3, 6, 30)  # ACI red, blue, green, magenta, orange


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
    # ezdxf.new itself is not an explicit export of the package (mypy's reading of py.typed).
    from ezdxf.filemanagement import new

    path, _ = target_path(out, "dxf")
    unit = length_unit(units, plan_of(mechanism).space)
    drawing = build_drawing(mechanism, at, samples)
    doc = new("R2010", units=INSUNITS[unit])
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
        assert drawing.centre is not None  # build_drawing gives a spherical drawing its centre
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

    return write_atomically(path, write)


def _dxf_plane(msp: Modelspace, d: Drawing, curve_layers: Mapping[str, str]) -> None:
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
            triangle(d.pose[j], r).tolist(), close=True, dxfattribs={"layer": "GROUND"}
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


def _dxf_sphere(msp: Modelspace, d: Drawing, curve_layers: Mapping[str, str]) -> None:
    from ezdxf.math import OCS

    r = d.radius
    for a, b in d.binary:
        msp.add_polyline3d(slerp(d.pose[a], d.pose[b]).tolist(), dxfattribs={"layer": "LINKS"})
    for joints in d.polygons:
        msp.add_polyline3d(
            outline(joints, d.pose, True).tolist(), close=True, dxfattribs={"layer": "LINKS"}
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

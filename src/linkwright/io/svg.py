"""The SVG writer of :mod:`.exports` (:func:`export_svg`): plain SVG 1.1 text, the linkage at
one pose and the closed paths of its traced joints, upright (SVG y = −y). On the sphere the
picture is Lambert's azimuthal equal-area projection
(:func:`linkwright.geometry.sphere.lambert_azimuthal`); :mod:`.exports` describes the groups,
the units and the sizes.
"""

from __future__ import annotations

import math
import os
import pathlib
from xml.sax.saxutils import escape, quoteattr

import numpy as np
from numpy.typing import NDArray

from linkwright.geometry.sphere import lambert_azimuthal
from linkwright.io.export_geometry import (
    GROUND,
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

__all__ = ["export_svg"]

Array = NDArray[np.float64]

_SVG_UNITS = {"mm": ("mm", 1.0), "cm": ("cm", 1.0), "in": ("in", 1.0), "m": ("mm", 1000.0),
              "ft": ("in", 12.0)}  # fmt: skip
SVG_PIXELS = 800.0  # the longer side of a unitless SVG

LINK = "#1f3b57"
BODY = "#c6dbef"
CURVES = ("#c0392b", "#2e86c1", "#27ae60", "#8e44ad", "#d35400")


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
    path, _ = target_path(out, "svg")
    unit = length_unit(units, plan_of(mechanism).space)
    drawing = build_drawing(mechanism, at, samples)
    text = _svg_text(drawing, unit, title)

    def write(tmp: pathlib.Path) -> None:
        tmp.write_text(text, encoding="utf-8")

    return write_atomically(path, write)


def _svg_text(d: Drawing, unit: str | None, title: str | None) -> str:
    sphere = d.centre is not None

    def page(v: Array) -> Array:
        return lambert_azimuthal(v, d.centre) if d.centre is not None else np.asarray(v)

    at = {j: page(p) for j, p in d.pose.items()}
    curves = {j: [(page(c), closed) for c, closed in pieces] for j, pieces in d.curves.items()}
    if sphere:
        binary = [page(slerp(d.pose[a], d.pose[b])) for a, b in d.binary]
        polygons = [page(outline(p, d.pose, True)) for p in d.polygons]
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
            f'<polygon id={ids("ground-", j)} fill="{GROUND}" points="{_pts(triangle(at[j], r))}"/>'
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


def _svg_desc(d: Drawing, unit: str | None) -> str:
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

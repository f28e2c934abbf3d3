"""Reinsberg's optimal transmission: four-bars whose transmission angle swings symmetrically
about 90° (paper 003, after E. Reinsberg, *Ermittlung von übertragungsgünstigen Doppelkurbeln*,
Maschinenbautechnik 26 (1977) 253–258).

Paper 003 states the condition for planar double cranks and crank-rockers as
γ1 + γ2 = 180°, γ1 and γ2 the smallest and largest transmission angle, which it says holds
when the extremes are symmetric about 90°, reached at φ1 = 90° with C, O, A, B on the circle on
AC as diameter (its Fig. 3: O the crank pivot, A the crank pin, B the output pin, C the output
pivot), and it gives L3 = √(L4² + L1² − L2²).

Why, in both spaces: when the input turns fully the transmission angle γ at B is extreme at
φ1 = 0 and 180° (:func:`linkwright.analysis.transmission_extremes`), and cos γ is an affine
function of the squared diagonal d = |A B0| in the plane, of cos d on the sphere, which is in
turn affine in cos φ1:

- plane: d² = L1² + L4² − 2 L1 L4 cos φ1 and cos γ = (L2² + L3² − d²)/(2 L2 L3), so
  γ1 + γ2 = 180° (cos γ1 = −cos γ2) exactly when L1² + L4² = L2² + L3². At φ1 = 90° then
  d² = L1² + L4² = L2² + L3²: the triangles A0 A B0 and B A B0 are right-angled at A0 and at B,
  so both lie on the circle with diameter A B0 (Thales), which is the paper's statement;
- sphere: cos d = cos α1 cos α4 + sin α1 sin α4 cos φ1 and
  cos γ = (cos d − cos α2 cos α3)/(sin α2 sin α3), so γ1 + γ2 = 180° exactly when
  cos α1 cos α4 = cos α2 cos α3. At φ1 = 90° the triangle A0 A B0 has its right angle at A0
  (cos d = cos α1 cos α4, the spherical Pythagoras) and γ = 90°: the triangle B A B0 is
  right-angled at B too. That is the spherical form of the concyclic statement; the points that
  see the arc A B0 at a right angle do not lie on the circle on it as diameter (on that circle
  the angle exceeds 90° by half the triangle's spherical excess), so the circle does not carry
  over.

The condition is linear in one squared length (one cosine), so completing a design for one
unknown link has at most one root; :func:`reinsberg_complete` returns it where the completed
linkage's input turns fully (the setting of the condition). For the pressure angle of a
spherical four-bar, paper 003's analogue (ν_τ balanced by the hinge radii) is
:func:`linkwright.analysis.balanced_mu`.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.analysis import fourbar_class, input_limits, transmission_extremes
from linkwright.analysis.planar import FOURBAR_CLASSES
from linkwright.mechanisms import FourBar, SphericalFourBar, input_range

__all__ = [
    "DIMENSIONS",
    "ReinsbergError",
    "reinsberg_complete",
    "reinsberg_defect",
    "reinsberg_mechanism",
]

Array = NDArray[np.float64]

DIMENSIONS = ("crank", "coupler", "rocker", "frame")
"""The links :func:`reinsberg_complete` solves for: L1/α1, L2/α2, L3/α3, L4/α4 of paper 003."""


class ReinsbergError(ValueError):
    """Reinsberg's condition was asked of something that is not a four-bar, or for an unknown
    dimension or class."""


def _check(fb: object) -> FourBar | SphericalFourBar:
    if not isinstance(fb, FourBar | SphericalFourBar):
        raise ReinsbergError(
            f"Reinsberg's condition is for a FourBar or a SphericalFourBar, got {type(fb).__name__}"
        )
    return fb


def _turns(fb: FourBar | SphericalFourBar) -> NDArray[np.bool_]:
    arcs = input_limits(fb) if isinstance(fb, SphericalFourBar) else input_range(fb)
    return np.asarray(arcs.full) & ~np.asarray(arcs.never)


def reinsberg_defect(fb: FourBar | SphericalFourBar) -> Array:
    """γ1 + γ2 − 180° (radians): how far each four-bar is from Reinsberg's optimum.

    γ1, γ2 are the exact smallest and largest transmission angle over the circuit (the closed
    forms of :func:`linkwright.analysis.transmission_extremes`); the optimum is 0. Positive:
    the angle leans above 90°. NaN where the input does not turn fully (the condition concerns
    crank-rockers and double cranks), including linkages that do not assemble.

    Examples
    --------
    Paper 003's Table 4 double crank (L4 = 1, L1 = 4, L2 = 2, L3 = √13) is one of Reinsberg's:

    >>> fb = FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=[13**0.5, 3.5])
    >>> np.degrees(reinsberg_defect(fb)).round(6)
    array([0.      , 7.493565])

    The first spherical crank-rocker of its Table 1 is not, and a spherical linkage that cannot
    assemble gives NaN:

    >>> arcs = np.radians([[90, 15, 60, 80], [90, 10, 20, 30]])
    >>> np.degrees(reinsberg_defect(SphericalFourBar(*arcs.T))).round(4)
    array([12.2737,     nan])
    """
    fb = _check(fb)
    tx = transmission_extremes(fb)
    return np.where(_turns(fb), tx["min"] + tx["max"] - np.pi, np.nan)


def _dims(fb: FourBar | SphericalFourBar) -> dict[str, Array]:
    return dict(
        zip(
            DIMENSIONS,
            np.broadcast_arrays(*(np.asarray(getattr(fb, n), dtype=float) for n in DIMENSIONS)),
            strict=True,
        )
    )


def _with(fb: FourBar | SphericalFourBar, field: str, value: Array) -> FourBar | SphericalFourBar:
    change: dict[str, Any] = {field: value}
    if isinstance(fb, SphericalFourBar):
        return replace(fb, **change)
    if field == "frame":
        a0, b0 = np.asarray(fb.A0, float), np.asarray(fb.B0, float)
        d = b0 - a0
        along = d / np.linalg.norm(d, axis=-1, keepdims=True)
        return replace(fb, B0=a0 + value[..., None] * along)
    return replace(fb, **change)


def reinsberg_complete(
    fb: FourBar | SphericalFourBar, field: str, *, kind: str | None = None
) -> Array:
    """The value of one link that makes each four-bar one of Reinsberg's (γ1 + γ2 = 180°).

    ``field`` names the unknown link (:data:`DIMENSIONS`); the mechanism's own value of it is
    ignored. Plane: L1² + L4² = L2² + L3², e.g. L3 = √(L1² + L4² − L2²) (paper 003). Sphere:
    cos α1 cos α4 = cos α2 cos α3, e.g. α3 = arccos(cos α1 cos α4 / cos α2). Each has at most
    one root (a positive length, an arc strictly between 0 and π), returned where the
    completed linkage's input turns fully, and, with ``kind`` (a class name of
    :func:`linkwright.analysis.fourbar_class`, e.g. ``"double-crank"``), where it is of that
    class; NaN elsewhere. Lengths in the mechanism's unit, arcs in radians. A frame length is
    set by moving B0 along A0→B0.

    Raises :class:`ReinsbergError` for a mechanism that is not a four-bar, an unknown ``field``
    or an unknown ``kind``.

    Examples
    --------
    Paper 003's Table 4 (L4 = 1, L2 = 2, 2.5, 3 with L1 = 4; printed L3 = 3.61, 3.28, 2.82):

    >>> fb = FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=[2, 2.5, 3], rocker=1)
    >>> reinsberg_complete(fb, "rocker").round(4)
    array([3.6056, 3.2787, 2.8284])

    A spherical double crank in the proportions of paper 003's Table 3 (α1 = 80°, α4 = 10°,
    α2 = 65°): the output arc that balances it; with a coupler of 5° the balancing arc (80.1°)
    would not let the input turn:

    >>> sph = SphericalFourBar(
    ...     frame=np.radians(10), crank=np.radians(80), coupler=np.radians([65, 5]), rocker=1.0)
    >>> np.degrees(reinsberg_complete(sph, "rocker", kind="double-crank")).round(4)
    array([66.1312,     nan])
    """
    fb = _check(fb)
    if field not in DIMENSIONS:
        raise ReinsbergError(f"field: {field!r} is not a link of a four-bar; one of {DIMENSIONS}")
    classes = FOURBAR_CLASSES
    if kind is not None and kind not in classes:
        raise ReinsbergError(f"kind: unknown class {kind!r}; one of {', '.join(classes)}")
    d = _dims(fb)
    # The condition pairs crank with frame and coupler with output: a ∘ b = c ∘ d, solved for
    # the unknown's partner product.
    partner = {"crank": "frame", "frame": "crank", "coupler": "rocker", "rocker": "coupler"}
    other = {"crank": "coupler", "frame": "coupler", "coupler": "crank", "rocker": "crank"}
    p, q = d[partner[field]], d[other[field]]
    r = d[partner[other[field]]]
    spherical = isinstance(fb, SphericalFourBar)
    with np.errstate(all="ignore"):
        if spherical:
            # cos(unknown)·cos(p) = cos(q)·cos(r)
            c = np.cos(q) * np.cos(r) / np.cos(p)
            root = np.arccos(np.clip(c, -1.0, 1.0))
            ok = np.isfinite(c) & (np.abs(c) < 1.0)
        else:
            # unknown² + p² = q² + r²
            sq = q * q + r * r - p * p
            root = np.sqrt(np.clip(sq, 0.0, None))
            ok = sq > 0
    # The completed linkage needs some valid value where there is no root; the old one serves
    # and is masked below.
    value = np.where(ok, root, d[field])
    done = _with(fb, field, value)
    ok = ok & _turns(done)
    if kind is not None:
        ok = ok & (np.asarray(fourbar_class(done)) == kind)
    return np.where(ok, root, np.nan)


def reinsberg_mechanism(
    fb: FourBar | SphericalFourBar, field: str, *, kind: str | None = None
) -> FourBar | SphericalFourBar:
    """The four-bar completed by :func:`reinsberg_complete`: ``field`` replaced by its root.

    For the command line and other callers that want the mechanism itself: raises
    :class:`ReinsbergError` where a linkage of the batch has no root, naming the link, the
    given dimensions (degrees for arcs) and why.

    Examples
    --------
    >>> fb = FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=1)
    >>> done = reinsberg_mechanism(fb, "rocker")
    >>> round(float(done.rocker), 6), float(reinsberg_defect(done))
    (3.605551, 0.0)
    >>> try:
    ...     reinsberg_mechanism(
    ...         FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=3, rocker=1), "rocker")
    ... except ReinsbergError as e:
    ...     print(e)
    rocker: no value makes γ1 + γ2 = 180° (crank 1, coupler 3, frame 2):
    L3² would be L1² + L4² − L2² = -4
    """
    value = reinsberg_complete(fb, field, kind=kind)
    missing = ~np.isfinite(value)
    if np.any(missing):
        first = int(np.flatnonzero(missing)[0])
        i = np.unravel_index(first, value.shape) if value.ndim else ()
        d = {n: float(v[i]) for n, v in _dims(fb).items()}
        spherical = isinstance(fb, SphericalFourBar)
        shown = ", ".join(
            f"{n} {math.degrees(d[n]):g}°" if spherical else f"{n} {d[n]:g}"
            for n in DIMENSIONS
            if n != field
        )
        raise ReinsbergError(
            f"{field}: no value makes γ1 + γ2 = 180° ({shown}): {_why(d, field, kind, spherical)}"
        )
    return _with(fb, field, value)


def _why(d: dict[str, float], field: str, kind: str | None, spherical: bool) -> str:
    """Why one linkage has no Reinsberg completion: no root, or the root's linkage fails."""
    partner = {"crank": "frame", "frame": "crank", "coupler": "rocker", "rocker": "coupler"}
    p = partner[field]
    q, r = (n for n in DIMENSIONS if n not in (field, p))
    if spherical:
        c = math.cos(d[q]) * math.cos(d[r]) / math.cos(d[p]) if math.cos(d[p]) else math.inf
        if not abs(c) < 1.0:
            return f"cos {field} would be cos {q}·cos {r}/cos {p} = {c:g}"
        d[field] = math.acos(c)
        value = f"{math.degrees(d[field]):g}°"
        one: FourBar | SphericalFourBar = SphericalFourBar(**d)
    else:
        sym = {"crank": "L1", "coupler": "L2", "rocker": "L3", "frame": "L4"}
        sq = d[q] ** 2 + d[r] ** 2 - d[p] ** 2
        if not sq > 0:
            return f"{sym[field]}² would be {sym[q]}² + {sym[r]}² − {sym[p]}² = {sq:g}"
        d[field] = math.sqrt(sq)
        value = f"{d[field]:g}"
        one = FourBar(
            A0=[0.0, 0.0],
            B0=[d["frame"], 0.0],
            crank=d["crank"],
            coupler=d["coupler"],
            rocker=d["rocker"],
        )
    cls = str(fourbar_class(one))
    if not bool(_turns(one)):
        return f"with {field} {value} the input does not turn fully (a {cls})"
    return f"with {field} {value} it is a {cls}, not a {kind}"

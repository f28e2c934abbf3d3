"""A named parameter vector for every plan: the free numbers of a mechanism, with their kinds,
their bounds and the symmetries a search must forget.

A mechanism's numbers are of a few kinds, and what a search, a sampler or a normalisation may do
with each follows from its kind:

============  ==========================================================  ======================
kind          what it is                                                  working range (scale s)
============  ==========================================================  ======================
length        a positive distance (a link, a triad's side)                0.02·s to 5·s
coordinate    a signed distance: a pivot's x or y (absolute: it moves     ±3·s about the centre
              with the linkage), a point's place on its link (relative)   (relative: ±5·s)
angle         radians: a direction (a guide's, a crank's phase: it turns  −π to π (an axis's
              with the linkage), an angle on a link, an axis's longitude  latitude ±π/2)
              or latitude on the sphere
arc           a spherical link's arc, strictly between 0 and π (a point's  2° to 178° (a point's
              arc from its joint: 0 to π)                                 arc 0 to π)
ratio         a gear ratio, nonzero                                       fixed at the
                                                                          template's value
============  ==========================================================  ======================

Nothing here is written per family. The kinds are read off the family's class (its
``point_fields``, ``length_fields`` and ``arc_fields``) and off the plan: each step kind says what
its numbers are (:data:`ROLES`: a crank's ``length`` is a length, its ``phase`` a direction; a
rigid point's ``u`` and ``v`` are coordinates on its link; a slider's ``line_angle`` is a
direction). A field the plan does not read itself (a geared five-bar's ``phase1``, a double
slider's ``p``, paper 001's ``sigma``) takes the kind of the plan numbers it moves, found by
moving it a little and comparing :meth:`~linkwright.mechanisms.Mechanism.params`. How each field
turns with the linkage is found the same way, and checked: a similarity applied to the fields
must apply the expected similarity to every plan number.

Discrete choices stay out of the vector: assembly signs, a triad's pose index, the word that
chooses a plan (a Stephenson III's ``input``) and a composed linkage's structure (joint names,
types, parents, traced joints). :meth:`ParameterVector.from_vector` takes them from a template.

Symmetries. A planar linkage moved, turned or scaled as a whole traces the same curve moved,
turned or scaled (the input shifted by the turn where a crank's angle is absolute): the planar
similarity group. :meth:`ParameterVector.normalise` fixes it: the first ground pivot at the
origin, the reference direction (a guide's direction where the plan has one, else the line from
the first ground pivot to the second) along +x, and the family's
:attr:`~linkwright.mechanisms.Mechanism.scale` 1. On the sphere the group is the rotations of
the sphere: a composed spherical linkage is turned so that its first ground axis is +x and its
second lies in the xy-plane (y > 0), paper 000's frame; the named spherical families already
stand in their paper's frame (it has no orientation left to fix), so normalising leaves them as
they are.

This module is the hook the family registry can feed: where a family declares its fields' kinds
itself, :func:`parameter_vector` can read them there instead of deriving them.

Examples
--------
>>> from linkwright.mechanisms import FourBar
>>> m = FourBar(A0=[1, 2], B0=[1, 6], crank=1, coupler=4, rocker=3.5, u=2, v=1)
>>> vector = parameter_vector(m)
>>> vector.names
('A0.x', 'A0.y', 'B0.x', 'B0.y', 'crank', 'coupler', 'rocker', 'u', 'v')
>>> vector.kinds[:5], vector.discrete
(('coordinate', 'coordinate', 'coordinate', 'coordinate', 'length'), ('assembly',))
>>> vector.to_vector(m)
array([1. , 2. , 1. , 6. , 1. , 4. , 3.5, 2. , 1. ])
>>> vector.from_vector(m, vector.to_vector(m)) == m
True

Normalised, A0 is at the origin, B0 on +x and the largest link (here the frame, 4) is 1:

>>> vector.to_vector(vector.normalise(m)).round(12) + 0.0
array([0.   , 0.   , 1.   , 0.   , 0.25 , 1.   , 0.875, 0.5  , 0.25 ])
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

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
from linkwright.engine.triad_steps import SphereTriad, Triad
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "KINDS",
    "ROLES",
    "Parameter",
    "ParameterError",
    "ParameterVector",
    "decode",
    "encode",
    "family_template",
    "parameter_vector",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi

KINDS = ("length", "coordinate", "angle", "arc", "ratio")
"""The kinds of a free number (the module docstring's table)."""

ROLES: tuple[tuple[type, dict[str, str]], ...] = (
    (Fixed, {"at": "point"}),
    (Crank, {"length": "length", "ratio": "ratio", "phase": "phase"}),
    (DyadRRR, {"r1": "length", "r2": "length", "branch": "branch"}),
    (DyadRRP, {"r": "length", "line_angle": "direction", "branch": "branch"}),
    (Rigid, {"u": "offset", "v": "offset"}),
    (Trammel, {"angle1": "direction", "angle2": "direction", "arm": "offset", "phase": "phase"}),
    (
        Triad,
        {"lengths": "length", "side": "length", "u": "offset", "v": "offset", "pose": "branch"},
    ),
    (SphereCrank, {"length": "arc", "ref": "axis", "ratio": "ratio", "phase": "angle"}),
    (SphereDyad, {"r1": "arc", "r2": "arc", "branch": "branch"}),
    (SphereRigid, {"length": "closed-arc", "angle": "angle"}),
    (
        SphereTriad,
        {"lengths": "arc", "side": "arc", "arc": "closed-arc", "angle": "angle", "pose": "branch"},
    ),
)
"""What each step kind's parameters are (its *roles*): ``point`` a planar pivot, ``axis`` a
spherical one, ``length`` a positive distance, ``offset`` a signed one, ``phase`` the angle a
planar crank starts from (absolute), ``direction`` a guide's absolute direction, ``angle`` an
angle measured on the linkage, ``arc`` and ``closed-arc`` spherical arcs (open and closed
interval), ``ratio`` a gear ratio and ``branch`` a discrete choice."""

_KIND_OF_ROLE = {
    "point": "coordinate",
    "axis": "angle",
    "length": "length",
    "offset": "coordinate",
    "phase": "angle",
    "direction": "angle",
    "angle": "angle",
    "arc": "arc",
    "closed-arc": "arc",
    "ratio": "ratio",
}
_SCALES = frozenset({"point", "length", "offset"})
"""Roles whose numbers a similarity scales."""
_ARC_LIMIT = np.radians(2.0)
_PROBE_STEP = 1e-3


class ParameterError(ValueError):
    """A parameter vector that does not fit its family, or a family without one (one line)."""


@dataclass(frozen=True)
class Parameter:
    """One free number of a mechanism.

    Attributes
    ----------
    name : ``"crank"``, ``"A0.x"`` (a planar point's coordinate), ``"B.r1"`` (a composed
        linkage's joint field), ``"A0.lon"`` / ``"A0.lat"`` (a spherical ground axis).
    kind : one of :data:`KINDS`.
    field : the field it is read from (``"A0"``; ``"B.r1"`` for a composed linkage's joint).
    component : 0 or 1 for a point's x or y, or an axis's longitude or latitude; None for a
        number.
    absolute : it moves with the linkage (a pivot's coordinate, an axis, a direction).
    turns : for an angle in the plane, how many times the linkage's turn it takes (1 for a
        direction; 0 for an angle on a link); None where that depends on a crank's ratio.
    closed : an arc that may be 0 or π (a point's arc from its joint).
    """

    name: str
    kind: str
    field: str
    component: int | None = None
    absolute: bool = False
    turns: float | None = 0.0
    closed: bool = False
    crank_ratio: str | float | None = None
    """For a crank's phase: the crank's ratio (a parameter name or a number)."""

    def working(self, scale: float = 1.0, centre: ArrayLike = (0.0, 0.0)) -> tuple[float, float]:
        """The range a sampler or a search draws this number from (module docstring)."""
        if self.kind == "length":
            return (0.02 * scale, 5.0 * scale)
        if self.kind == "coordinate":
            if self.absolute and self.component is not None:
                c = float(np.asarray(centre, dtype=float)[self.component])
                return (c - 3.0 * scale, c + 3.0 * scale)
            return (-5.0 * scale, 5.0 * scale)
        if self.kind == "arc":
            return (0.0, np.pi) if self.closed else (_ARC_LIMIT, np.pi - _ARC_LIMIT)
        if self.kind == "angle" and self.component == 1 and self.absolute:
            return (-np.pi / 2, np.pi / 2)  # an axis's latitude
        if self.kind == "ratio":
            return (-4.0, 4.0)
        return (-np.pi, np.pi)

    @property
    def limits(self) -> tuple[float, float]:
        """Where the number is valid at all (a length above 0, an arc inside (0, π))."""
        if self.kind == "length":
            return (0.0, np.inf)
        if self.kind == "arc":
            return (0.0, np.pi)
        if self.kind == "angle" and self.component == 1 and self.absolute:
            return (-np.pi / 2, np.pi / 2)
        return (-np.inf, np.inf)

    @property
    def periodic(self) -> bool:
        """An angle that a whole turn leaves unchanged."""
        return self.kind == "angle" and not (self.component == 1 and self.absolute)


# --------------------------------------------------------------------------------------------
# Reading a mechanism's fields (named families and composed linkages alike)
# --------------------------------------------------------------------------------------------


def _is_linkage(mech: Any) -> bool:
    return getattr(mech, "family", None) == "linkage" and hasattr(mech, "joints")


def _get(mech: Mechanism, field_id: str) -> Array:
    if _is_linkage(mech):
        joint, attr = field_id.rsplit(".", 1)
        return np.asarray(getattr(mech.joint(joint), attr), dtype=float)  # type: ignore[attr-defined]
    return np.asarray(getattr(mech, field_id), dtype=float)


def _rebuild(mech: Mechanism, changes: Mapping[str, Any]) -> Mechanism:
    """The mechanism with the fields ``changes`` replaced (joint fields ``"B.r1"`` for a
    composed linkage)."""
    if not _is_linkage(mech):
        return replace(mech, **changes)
    per_joint: dict[str, dict[str, Any]] = {}
    for key, value in changes.items():
        joint, attr = key.rsplit(".", 1)
        per_joint.setdefault(joint, {})[attr] = value
    joints = tuple(
        replace(j, **per_joint[j.name]) if j.name in per_joint else j
        for j in mech.joints  # type: ignore[attr-defined]
    )
    return replace(mech, joints=joints)


def _roles(plan: Any) -> dict[str, tuple[str, Any]]:
    """Plan parameter name → (its role, the step that reads it)."""
    out: dict[str, tuple[str, Any]] = {}
    for step in plan.steps:
        for cls, table in ROLES:
            if not isinstance(step, cls):
                continue
            for attr, role in table.items():
                value = getattr(step, attr, None)
                for item in value if isinstance(value, tuple) else (value,):
                    if isinstance(item, str) and item not in out:
                        out[item] = (role, step)
            break
    return out


def _discrete_field(name: str, annotation: Any) -> bool:
    # The base class's own conventions: a word field chooses the plan; ``assembly*`` and
    # ``pose`` are branch choices (mechanisms.base checks them so).
    return annotation == "str" or name.startswith("assembly") or name == "pose"


def _probe_instance(cls: type, words: Mapping[str, str]) -> Mechanism:
    """A valid member of a named family, with distinct numbers so that no dependency hides
    behind a coincidence: what the plan reads is found on it."""
    corners = [(0.0, 0.0), (1.3, 0.2), (0.4, -1.1), (-0.7, 0.9), (2.1, 1.7)]
    values: dict[str, Any] = {}
    points = lengths = arcs = others = 0
    for f in fields(cls):
        if f.type == "str":
            values[f.name] = words.get(f.name, f.default)
        elif f.name == "pose":
            values[f.name] = 0.0
        elif f.name.startswith("assembly"):
            values[f.name] = 1.0
        elif f.name in cls.point_fields:
            values[f.name] = corners[points % len(corners)]
            points += 1
        elif f.name in cls.length_fields:
            values[f.name] = 1.0 + 0.17 * lengths
            lengths += 1
        elif f.name in cls.arc_fields:
            values[f.name] = 0.9 + 0.07 * arcs
            arcs += 1
        else:
            values[f.name] = 0.31 + 0.113 * others
            others += 1
    return cls(**values)  # type: ignore[no-any-return]


# --------------------------------------------------------------------------------------------
# The vector
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ParameterVector:
    """The free numbers of one family (or one composed linkage's structure).

    Attributes
    ----------
    family : the family's name.
    space : ``"plane"`` or ``"sphere"``.
    parameters : each free number, in a fixed order.
    discrete : the fields that are choices, not numbers (assembly signs, pose, input word;
        for a composed linkage its joints' assembly signs).
    symmetry : ``"similarity"`` (plane) or ``"rotation"`` (sphere): the group the vector must
        forget, which :meth:`normalise` fixes.
    in_family_frame : the family itself already fixes the symmetry (a named spherical family in
        its paper's frame): :meth:`normalise` leaves its mechanisms as they are.
    base : the planar point field :meth:`normalise` puts at the origin.
    reference : what :meth:`normalise` turns along +x: ``("direction", field)`` or
        ``("points", base, second)``; None where nothing does.
    input_turn : how far the input shifts when the linkage turns by ψ, per unit ψ (1 where a
        crank's angle is absolute, as a four-bar's; 0 where every crank has its own phase).
    axes : a spherical composed linkage's ground axis fields, in order.
    """

    family: str
    space: str
    parameters: tuple[Parameter, ...]
    discrete: tuple[str, ...]
    symmetry: str
    in_family_frame: bool
    base: str | None
    reference: tuple[str, ...] | None
    input_turn: float
    axes: tuple[str, ...] = ()
    derived: tuple[str, ...] = ()
    """Fields whose kind was found by moving them (the plan reads them only through
    :meth:`~linkwright.mechanisms.Mechanism.params`)."""

    # -- description ------------------------------------------------------------------------

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(p.kind for p in self.parameters)

    def __len__(self) -> int:
        return len(self.parameters)

    def index(self, name: str) -> int:
        """The position of the parameter ``name`` in the vector."""
        for i, p in enumerate(self.parameters):
            if p.name == name:
                return i
        raise ParameterError(
            f"{self.family} has no parameter {name!r}; its parameters: {', '.join(self.names)}"
        )

    def parameter(self, name: str) -> Parameter:
        return self.parameters[self.index(name)]

    def bounds(
        self, scale: float = 1.0, centre: ArrayLike = (0.0, 0.0), template: Mechanism | None = None
    ) -> tuple[Array, Array]:
        """Working bounds (low, high) of every parameter for linkages of size ``scale`` about
        ``centre`` (the module docstring's table); a ratio is fixed at the template's value
        when one is given (a gear ratio is chosen, not fitted)."""
        lo, hi = np.empty(len(self)), np.empty(len(self))
        fixed = self.to_vector(template) if template is not None else None
        for i, p in enumerate(self.parameters):
            lo[i], hi[i] = p.working(scale, centre)
            if p.kind == "ratio" and fixed is not None:
                lo[i] = hi[i] = float(np.ravel(fixed[..., i])[0])
        return lo, hi

    def limits(self) -> tuple[Array, Array]:
        """Where each parameter is valid at all (module docstring)."""
        pairs = [p.limits for p in self.parameters]
        return np.array([a for a, _ in pairs]), np.array([b for _, b in pairs])

    # -- vector ↔ mechanism -------------------------------------------------------------------

    def _check(self, mech: Mechanism) -> None:
        if getattr(mech, "family", None) != self.family:
            raise ParameterError(
                f"a {getattr(mech, 'family', type(mech).__name__)} mechanism does not fit the "
                f"parameter vector of {self.family}"
            )
        if _is_linkage(mech) and parameter_vector(mech).names != self.names:
            raise ParameterError("this linkage's joints differ from the vector's template")

    def to_vector(self, mech: Mechanism) -> Array:
        """The mechanism's free numbers, shape ``batch + (len(self),)``."""
        self._check(mech)
        columns: list[Array] = []
        for p in self.parameters:
            value = _get(mech, p.field)
            if p.field in self.axes:
                unit = value / np.linalg.norm(value, axis=-1, keepdims=True)
                if p.component == 0:
                    value = np.arctan2(unit[..., 1], unit[..., 0])
                else:
                    value = np.arctan2(unit[..., 2], np.hypot(unit[..., 0], unit[..., 1]))
            elif p.component is not None:
                value = value[..., p.component]
            columns.append(value)
        return np.stack(np.broadcast_arrays(*columns), axis=-1).astype(float)

    def from_vector(
        self,
        template: Mechanism,
        x: ArrayLike,
        discrete: Mapping[str, ArrayLike] | None = None,
    ) -> Mechanism:
        """The mechanism with the free numbers ``x`` (shape ``batch + (len(self),)``: a batch of
        mechanisms) and the template's discrete choices, or those given in ``discrete``.

        A spherical ground axis whose direction the vector leaves unchanged keeps the template's
        own vector (which need not be a unit vector), so that a round trip gives the template
        back exactly.
        """
        self._check(template)
        x = np.asarray(x, dtype=float)
        if x.shape[-1:] != (len(self),):
            raise ParameterError(
                f"{self.family}: a parameter vector has {len(self)} numbers, got shape {x.shape}"
            )
        changes: dict[str, Any] = {}
        grouped: dict[str, dict[int, Array]] = {}
        for i, p in enumerate(self.parameters):
            if p.component is None:
                changes[p.field] = x[..., i]
            else:
                grouped.setdefault(p.field, {})[p.component] = x[..., i]
        for name, parts in grouped.items():
            if name in self.axes:
                lon, lat = parts[0], parts[1]
                unit = np.stack(
                    (np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)), axis=-1
                )
                own = _get(template, name)
                own_unit = own / np.linalg.norm(own, axis=-1, keepdims=True)
                same = unit.shape == own.shape and np.max(np.abs(unit - own_unit)) <= 1e-15
                changes[name] = own if same else unit
            else:
                changes[name] = np.stack(np.broadcast_arrays(parts[0], parts[1]), axis=-1)
        for name, value in (discrete or {}).items():
            if name not in self.discrete:
                raise ParameterError(
                    f"{self.family}: {name!r} is not a discrete choice; "
                    f"they are {', '.join(self.discrete) or 'none'}"
                )
            changes[name] = value
        return _rebuild(template, changes)

    # -- symmetries ---------------------------------------------------------------------------

    def transformed(
        self,
        mech: Mechanism,
        scale: ArrayLike = 1.0,
        angle: ArrayLike = 0.0,
        shift: ArrayLike = (0.0, 0.0),
    ) -> Mechanism:
        """The planar linkage scaled by ``scale`` about the origin, turned by ``angle``
        (radians, counter-clockwise) and moved by ``shift``: it traces ``scale·R·P + shift``
        where ``mech`` traces P, at the input shifted by :attr:`input_turn`·``angle``."""
        self._check(mech)
        if self.space != "plane":
            raise ParameterError(f"{self.family} is spherical: it turns, it is not moved")
        s = np.asarray(scale, dtype=float)
        psi = np.asarray(angle, dtype=float)
        t = np.asarray(shift, dtype=float)
        c, n = np.cos(psi), np.sin(psi)
        params = mech.params()
        changes: dict[str, Any] = {}
        for p in self.parameters:
            if p.field in changes:
                continue
            value = _get(mech, p.field)
            if p.component is not None:  # a pivot: both coordinates at once
                x, y = value[..., 0], value[..., 1]
                changes[p.field] = np.stack(
                    (s * (c * x - n * y) + t[..., 0], s * (n * x + c * y) + t[..., 1]), axis=-1
                )
            elif p.kind in ("length", "coordinate"):
                changes[p.field] = s * value
            elif p.kind == "angle":
                changes[p.field] = value + self._turns(p, params) * psi
        return _rebuild(mech, changes)

    def _turns(self, p: Parameter, params: Mapping[str, Array]) -> Array | float:
        if p.turns is not None:
            return p.turns
        ratio = p.crank_ratio
        r = np.asarray(params[ratio] if isinstance(ratio, str) else ratio, dtype=float)
        return 1.0 - r * self.input_turn

    def rotated(self, mech: Mechanism, rotation: ArrayLike) -> Mechanism:
        """A spherical composed linkage turned by the rotation matrix ``rotation`` (3×3): every
        ground axis ``a`` becomes ``rotation @ a``, so every joint turns with it."""
        self._check(mech)
        if not self.axes:
            raise ParameterError(
                f"{self.family} stands in its own frame: it has no ground axes to turn"
                if self.space == "sphere"
                else f"{self.family} is planar: use transformed()"
            )
        R = np.asarray(rotation, dtype=float)
        changes = {name: np.einsum("...ij,...j->...i", R, _get(mech, name)) for name in self.axes}
        return _rebuild(mech, changes)

    def frame(self, mech: Mechanism) -> tuple[Array, Array, Array]:
        """(base point, reference direction, scale) of planar linkages: what :meth:`normalise`
        moves to the origin, turns to 0 and scales to 1."""
        self._check(mech)
        base = _get(mech, self.base) if self.base else np.zeros(2)
        angle: Array = np.zeros(())
        if self.reference is not None and self.reference[0] == "direction":
            angle = _get(mech, self.reference[1])
        elif self.reference is not None:
            d = _get(mech, self.reference[2]) - _get(mech, self.reference[1])
            angle = np.arctan2(d[..., 1], d[..., 0])
        return base, angle, np.asarray(mech.scale, dtype=float)

    def normalise(self, mech: Mechanism) -> Mechanism:
        """The same linkage in its canonical place (module docstring): its curve is the
        original's, moved, turned and scaled (or, on the sphere, turned)."""
        self._check(mech)
        if self.in_family_frame:
            return mech
        if self.space == "sphere":
            a = _get(mech, self.axes[0])
            b = _get(mech, self.axes[1])
            e1 = a / np.linalg.norm(a, axis=-1, keepdims=True)
            w = b - np.sum(b * e1, axis=-1, keepdims=True) * e1
            e2 = w / np.linalg.norm(w, axis=-1, keepdims=True)
            e3 = np.cross(e1, e2)
            return self.rotated(mech, np.stack((e1, e2, e3), axis=-2))
        base, angle, size = self.frame(mech)
        s = 1.0 / size
        psi = -angle
        c, n = np.cos(psi), np.sin(psi)
        shift = -s[..., None] * np.stack(
            (c * base[..., 0] - n * base[..., 1], n * base[..., 0] + c * base[..., 1]), axis=-1
        )
        return self.transformed(mech, s, psi, shift)


# --------------------------------------------------------------------------------------------
# Deriving a family's vector
# --------------------------------------------------------------------------------------------


def parameter_vector(family_or_mech: Any) -> ParameterVector:
    """The parameter vector of a family (its name or class) or of a mechanism.

    A composed linkage's vector depends on its joints, so it needs the linkage itself; a named
    family's depends on the word that chooses its plan (a Stephenson III driven at its output has
    a triad), read from the mechanism, or the family's default for a name or class.

    Raises
    ------
    ParameterError
        For an unknown family name, or ``"linkage"`` without a linkage.
    """
    if isinstance(family_or_mech, Mechanism):
        if _is_linkage(family_or_mech):
            return _linkage_vector(family_or_mech)
        cls = type(family_or_mech)
        words = tuple(
            (f.name, getattr(family_or_mech, f.name)) for f in fields(cls) if f.type == "str"
        )
        return _family_vector(cls, words)
    if isinstance(family_or_mech, str):
        from linkwright.mechanisms import FAMILIES

        if family_or_mech not in FAMILIES:
            raise ParameterError(
                f"family: unknown {family_or_mech!r}; known: {', '.join(FAMILIES)}"
            )
        family_or_mech = FAMILIES[family_or_mech]
    if isinstance(family_or_mech, type) and issubclass(family_or_mech, Mechanism):
        if family_or_mech.family == "linkage":
            raise ParameterError(
                "linkage: a composed linkage's parameters are its joints' numbers; give the "
                "linkage itself (its structure fixes them)"
            )
        return _family_vector(family_or_mech, ())
    raise ParameterError(f"not a family or a mechanism: {family_or_mech!r}")


def family_template(family: str) -> Mechanism:
    """A member of the named family with its default choices (assembly +1, pose 0, the
    default input word) and arbitrary valid numbers: a template whose numbers are all to be
    replaced (:meth:`ParameterVector.from_vector`).

    Raises
    ------
    ParameterError
        For an unknown family, or ``"linkage"``, whose structure only a linkage can give.
    """
    from linkwright.mechanisms import FAMILIES

    if family not in FAMILIES:
        raise ParameterError(f"family: unknown {family!r}; known: {', '.join(FAMILIES)}")
    if family == "linkage":
        raise ParameterError(
            "linkage: a composed linkage's joints come from a template: give a document of "
            "family linkage (its structure is kept, its numbers are free)"
        )
    return _probe_instance(FAMILIES[family], {})


@functools.lru_cache(maxsize=64)
def _family_vector(cls: type, words: tuple[tuple[str, str], ...]) -> ParameterVector:
    probe = _probe_instance(cls, dict(words))
    plan = probe.plan
    roles = _roles(plan)
    space = plan.space
    base_params = probe.params()
    params: list[Parameter] = []
    discrete: list[str] = []
    derived: list[str] = []
    for f in fields(cls):
        name = f.name
        if _discrete_field(name, f.type):
            discrete.append(name)
            continue
        if name in cls.point_fields:
            for k, axis in enumerate("xy"):
                params.append(Parameter(f"{name}.{axis}", "coordinate", name, k, absolute=True))
            continue
        role, step = roles.get(name, (None, None))
        if name in cls.length_fields:
            kind = "length"
        elif name in cls.arc_fields:
            kind = "arc"
        elif role is not None:
            kind = _KIND_OF_ROLE[role]
        else:
            moved = _moved(probe, name, base_params)
            role_set = {roles[k][0] for k in moved if k in roles}
            kind = _derived_kind(cls.__name__, name, role_set, space)
            derived.append(name)
        turns: float | None = 0.0
        ratio = None
        if space == "plane" and kind == "angle" and role == "direction":
            turns = 1.0
        elif space == "plane" and kind == "angle" and role == "phase":
            turns, ratio = None, step.ratio
        params.append(
            Parameter(
                name,
                kind,
                name,
                absolute=turns != 0.0,
                turns=turns,
                # The family's own arc fields are open arcs, whatever step reads them.
                closed=role == "closed-arc" and name not in cls.arc_fields,
                crank_ratio=ratio,
            )
        )
    input_turn = _input_turn(plan, base_params)
    vector = ParameterVector(
        family=cls.family,
        space=space,
        parameters=tuple(params),
        discrete=tuple(discrete),
        symmetry="similarity" if space == "plane" else "rotation",
        in_family_frame=space == "sphere",
        base=None,
        reference=None,
        input_turn=input_turn,
        derived=tuple(derived),
    )
    if space == "plane":
        vector = _with_derived_turns(vector, probe, roles)
        vector = replace(vector, **_gauge(vector, plan, roles))
    return vector


def _moved(probe: Mechanism, name: str, before: Mapping[str, Array]) -> set[str]:
    """The plan parameters that change when the field ``name`` moves a little."""
    value = np.asarray(getattr(probe, name), dtype=float)
    after = replace(probe, **{name: value * (1 + _PROBE_STEP) + _PROBE_STEP}).params()
    return {
        k
        for k, v in before.items()
        if k in after and not np.allclose(np.asarray(v, float), np.asarray(after[k], float))
    }


def _derived_kind(family: str, name: str, roles: set[str], space: str) -> str:
    if roles & {"length", "offset", "point"} and space == "plane":
        return "coordinate"
    if roles & {"phase", "direction", "angle"}:
        return "angle"
    if roles & {"arc", "closed-arc"}:
        return "arc"
    if "ratio" in roles:
        return "ratio"
    if "axis" in roles or "point" in roles:
        return "angle"  # it places a ground axis on the sphere without being an arc: an angle
    raise ParameterError(f"{family}.{name}: the plan does not read it; no kind can be given")


def _input_turn(plan: Any, params: Mapping[str, Array]) -> float:
    """δ/ψ: a crank whose phase is a constant fixes how the input shifts with a turn ψ of the
    linkage (δ = ψ / its ratio); where every crank has its own phase the input stays."""
    found: set[float] = set()
    for step in plan.steps:
        if isinstance(step, Crank | Trammel) and not isinstance(step.phase, str):
            ratio = getattr(step, "ratio", 1.0)
            r = params[ratio] if isinstance(ratio, str) else ratio
            found.add(round(1.0 / float(np.ravel(r)[0]), 12))
    if len(found) > 1:
        raise ParameterError("two cranks with fixed phases turn at different ratios")
    return found.pop() if found else 0.0


def _expected(
    vector: ParameterVector,
    roles: Mapping[str, tuple[str, Any]],
    params: Mapping[str, Array],
    s: float,
    psi: float,
    t: Array,
) -> dict[str, Array]:
    """What a similarity (scale s, turn ψ, shift t) does to each plan parameter, by its role."""
    out: dict[str, Array] = {}
    c, n = math.cos(psi), math.sin(psi)
    for key, value in params.items():
        role, step = roles.get(key, (None, None))
        v = np.asarray(value, dtype=float)
        if role == "point":
            out[key] = np.stack(
                (
                    s * (c * v[..., 0] - n * v[..., 1]) + t[0],
                    s * (n * v[..., 0] + c * v[..., 1]) + t[1],
                ),
                axis=-1,
            )
        elif role in ("length", "offset"):
            out[key] = s * v
        elif role == "direction":
            out[key] = v + psi
        elif role == "phase":
            ratio = getattr(step, "ratio", 1.0)
            r = np.asarray(params[ratio] if isinstance(ratio, str) else ratio, dtype=float)
            out[key] = v + psi - r * vector.input_turn * psi
        else:
            out[key] = v
    return out


def _agrees(
    vector: ParameterVector,
    probe: Mechanism,
    roles: Mapping[str, tuple[str, Any]],
) -> bool:
    s, psi, t = 1.37, 0.61, np.array([0.3, -0.8])
    want = _expected(vector, roles, probe.params(), s, psi, t)
    got = vector.transformed(probe, s, psi, t).params()
    for key, value in want.items():
        if key not in roles:
            continue  # a field kept among the parameters, read by no step
        diff = np.asarray(got[key], float) - value
        if roles.get(key, ("",))[0] in ("direction", "phase", "angle"):
            diff = np.remainder(diff + np.pi, TWO_PI) - np.pi
        if not np.allclose(diff, 0.0, atol=1e-9):
            return False
    return True


def _with_derived_turns(
    vector: ParameterVector, probe: Mechanism, roles: Mapping[str, tuple[str, Any]]
) -> ParameterVector:
    """Each derived angle field turns with the linkage or not: the choice under which the
    similarity acts on every plan parameter as its role says (checked on the probe)."""
    free = [
        i
        for i, p in enumerate(vector.parameters)
        if p.field in vector.derived and p.kind == "angle"
    ]
    for choice in range(2 ** len(free)):
        params = list(vector.parameters)
        for bit, i in enumerate(free):
            turns = float((choice >> bit) & 1)
            params[i] = replace(params[i], turns=turns, absolute=bool(turns))
        trial = replace(vector, parameters=tuple(params))
        if _agrees(trial, probe, roles):
            return trial
    raise ParameterError(
        f"{vector.family}: no assignment of its angles turns it as a whole (its symmetry "
        "cannot be read off its fields)"
    )


def _gauge(
    vector: ParameterVector, plan: Any, roles: Mapping[str, tuple[str, Any]]
) -> dict[str, Any]:
    """The first ground pivot, and the reference direction: a guide's direction field where the
    plan has one, else the line from the first ground pivot to the second."""
    by_field = {p.field: p for p in vector.parameters}
    ground = [s.at for s in plan.steps if isinstance(s, Fixed) and s.at in by_field]
    # A composed linkage's pivots are its fixed joints' ``at`` fields.
    base = ground[0] if ground else None
    reference: tuple[str, ...] | None = None
    for key, (role, _) in roles.items():
        if role == "direction" and key in by_field and by_field[key].turns == 1.0:
            reference = ("direction", key)
            break
    if reference is None and len(ground) >= 2:
        reference = ("points", ground[0], ground[1])
    return {"base": base, "reference": reference}


def _linkage_vector(linkage: Mechanism) -> ParameterVector:
    """A composed linkage's vector: every numeric field of every joint, named ``joint.field``."""
    from linkwright.mechanisms import linkage as lk

    plan = linkage.plan
    roles = _roles(plan)
    space = linkage.space
    params: list[Parameter] = []
    discrete: list[str] = []
    axes: list[str] = []
    for joint in linkage.joints:  # type: ignore[attr-defined]
        kinds = lk._numeric_kinds(joint, space)
        for attr, what in kinds.items():
            key = f"{joint.name}.{attr}"
            if what == "sign":
                discrete.append(key)
                continue
            if what == "point":
                for k, axis in enumerate("xy"):
                    params.append(Parameter(f"{key[:-3]}.{axis}", "coordinate", key, k, True))
                continue
            if what == "axis":
                axes.append(key)
                for k, part in enumerate(("lon", "lat")):
                    params.append(Parameter(f"{key[:-3]}.{part}", "angle", key, k, True, turns=0.0))
                continue
            role, step = roles.get(key, (None, None))
            if role is not None:
                kind = _KIND_OF_ROLE[role]
            elif what == "ratio":
                kind = "ratio"  # a ratio of 1 is written into the plan as a constant
            else:  # pragma: no cover - every other field is a plan parameter
                raise ParameterError(f"joint {joint.name!r}: {attr} is not read by the plan")
            turns: float | None = 0.0
            ratio = None
            if space == "plane" and role == "direction":
                turns = 1.0
            elif space == "plane" and role == "phase":
                turns, ratio = None, step.ratio
            params.append(
                Parameter(
                    key,
                    kind,
                    key,
                    absolute=turns != 0.0,
                    turns=turns,
                    closed=role == "closed-arc",
                    crank_ratio=ratio,
                )
            )
    values = linkage.params()
    vector = ParameterVector(
        family="linkage",
        space=space,
        parameters=tuple(params),
        discrete=tuple(discrete),
        symmetry="similarity" if space == "plane" else "rotation",
        in_family_frame=False,
        base=None,
        reference=None,
        input_turn=_input_turn(plan, values),
        axes=tuple(axes),
    )
    if space == "plane":
        vector = replace(vector, **_gauge(vector, plan, roles))
    return vector


# --------------------------------------------------------------------------------------------
# A mechanism as plain data (a template kept in an atlas's JSON spec)
# --------------------------------------------------------------------------------------------


def _plain(value: Any) -> Any:
    if isinstance(value, str) or value is None:
        return value
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return np.asarray(value, dtype=float).tolist()


def encode(mech: Mechanism) -> dict[str, Any]:
    """One mechanism as plain JSON data (radians, every field; a composed linkage joint by
    joint), which :func:`decode` turns back into an equal mechanism.

    >>> from linkwright.mechanisms import FourBar
    >>> m = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3.5, u=2, v=1)
    >>> decode(encode(m)) == m
    True
    """
    if mech.batch_shape:
        raise ParameterError("a template is one mechanism, not a batch")
    out: dict[str, Any] = {"family": mech.family}
    if _is_linkage(mech):
        out["space"] = mech.space
        out["traced"] = list(mech.traced)  # type: ignore[attr-defined]
        out["joints"] = [
            {"spec": type(j).__name__, **{f.name: _plain(getattr(j, f.name)) for f in fields(j)}}
            for j in mech.joints  # type: ignore[attr-defined]
        ]
        return out
    for f in fields(mech):
        out[f.name] = _plain(getattr(mech, f.name))
    return out


def decode(data: Mapping[str, Any]) -> Mechanism:
    """The mechanism :func:`encode` wrote (an :class:`InvalidMechanism` if it is not one)."""
    from linkwright.mechanisms import FAMILIES
    from linkwright.mechanisms import linkage as lk

    if not isinstance(data, Mapping) or data.get("family") not in FAMILIES:
        raise ParameterError(f"not an encoded mechanism: {str(data)[:80]}")
    body = {k: v for k, v in data.items() if k != "family"}
    if data["family"] != "linkage":
        return FAMILIES[data["family"]](**body)  # type: ignore[no-any-return]
    specs = {cls.__name__: cls for cls in lk._ALL_SPECS}
    joints = []
    for entry in body["joints"]:
        fields_ = {k: v for k, v in entry.items() if k != "spec"}
        joints.append(specs[entry["spec"]](**fields_))
    return lk.Linkage(joints=tuple(joints), traced=tuple(body["traced"]), space=body["space"])

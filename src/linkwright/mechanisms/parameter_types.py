"""The parameter vector's types: the kinds of a mechanism's free numbers, the roles of a
plan's numbers, one free number (:class:`Parameter`) and the vector of a family
(:class:`ParameterVector`), with the symmetries a search must forget.

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

The vectors themselves are derived from the families in :mod:`.parameter_derivation`;
:mod:`.parameters` gathers both.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, TypeGuard

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
from linkwright.engine.hinge_steps import Hinge, SphereHinge
from linkwright.engine.hinge_triad_steps import (
    BodyHingeTriad,
    LegHingeTriad,
    SphereBodyHingeTriad,
    SphereLegHingeTriad,
)
from linkwright.engine.triad_steps import SphereTriad, Triad
from linkwright.mechanisms.base import Mechanism

if TYPE_CHECKING:  # imported where used at run time (linkage imports this module's layer)
    from linkwright.mechanisms.linkage import Linkage

__all__ = [
    "KINDS",
    "KIND_OF_ROLE",
    "ROLES",
    "TWO_PI",
    "Parameter",
    "ParameterError",
    "ParameterVector",
    "field_value",
    "is_linkage",
    "plan_roles",
    "rebuilt",
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
    # A driven hinge's phase is an angle between two links: the linkage's turn leaves it.
    (Hinge, {"r": "length", "a": "length", "b": "length", "phase": "angle", "pose": "branch"}),
    (SphereHinge, {"r": "arc", "a": "arc", "b": "arc", "phase": "angle", "pose": "branch"}),
    (SphereCrank, {"length": "arc", "ref": "axis", "ratio": "ratio", "phase": "angle"}),
    (SphereDyad, {"r1": "arc", "r2": "arc", "branch": "branch"}),
    (SphereRigid, {"length": "closed-arc", "angle": "angle"}),
    (
        SphereTriad,
        {"lengths": "arc", "side": "arc", "arc": "closed-arc", "angle": "angle", "pose": "branch"},
    ),
    # Triads driven at a hinge: the hinge's links as lengths (arcs), its phase an angle.
    (
        LegHingeTriad,
        {
            "lengths": "length",
            "side": "length",
            "u": "offset",
            "v": "offset",
            "a": "length",
            "b": "length",
            "phase": "angle",
            "pose": "branch",
        },
    ),
    (
        BodyHingeTriad,
        {
            "lengths": "length",
            "side": "length",
            "hu": "offset",
            "hv": "offset",
            "arm": "length",
            "phase": "angle",
            "pose": "branch",
        },
    ),
    (
        SphereLegHingeTriad,
        {
            "lengths": "arc",
            "side": "arc",
            "arc": "closed-arc",
            "angle": "angle",
            "a": "arc",
            "b": "arc",
            "phase": "angle",
            "pose": "branch",
        },
    ),
    (
        SphereBodyHingeTriad,
        {
            "lengths": "arc",
            "side": "arc",
            "harc": "arc",
            "hangle": "angle",
            "arm": "arc",
            "phase": "angle",
            "pose": "branch",
        },
    ),
)
"""What each step kind's parameters are (its *roles*): ``point`` a planar pivot, ``axis`` a
spherical one, ``length`` a positive distance, ``offset`` a signed one, ``phase`` the angle a
planar crank starts from (absolute), ``direction`` a guide's absolute direction, ``angle`` an
angle measured on the linkage, ``arc`` and ``closed-arc`` spherical arcs (open and closed
interval), ``ratio`` a gear ratio and ``branch`` a discrete choice."""

# The kind of free number each role is (module docstring).
KIND_OF_ROLE = {
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


def is_linkage(mech: Any) -> TypeGuard[Linkage]:
    return getattr(mech, "family", None) == "linkage" and hasattr(mech, "joints")


def field_value(mech: Mechanism, field_id: str) -> Array:
    if is_linkage(mech):
        joint, attr = field_id.rsplit(".", 1)
        return np.asarray(getattr(mech.joint(joint), attr), dtype=float)
    return np.asarray(getattr(mech, field_id), dtype=float)


def rebuilt(mech: Mechanism, changes: Mapping[str, Any]) -> Mechanism:
    """The mechanism with the fields ``changes`` replaced (joint fields ``"B.r1"`` for a
    composed linkage)."""
    if not is_linkage(mech):
        return replace(mech, **changes)
    per_joint: dict[str, dict[str, Any]] = {}
    for key, value in changes.items():
        joint, attr = key.rsplit(".", 1)
        per_joint.setdefault(joint, {})[attr] = value
    joints = tuple(
        replace(j, **per_joint[j.name]) if j.name in per_joint else j for j in mech.joints
    )
    return replace(mech, joints=joints)


def plan_roles(plan: Any) -> dict[str, tuple[str, Any]]:
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
        # Deriving a vector needs this module's types: imported here, not at the top.
        from linkwright.mechanisms.parameter_derivation import parameter_vector

        if is_linkage(mech) and parameter_vector(mech).names != self.names:
            raise ParameterError("this linkage's joints differ from the vector's template")

    def to_vector(self, mech: Mechanism) -> Array:
        """The mechanism's free numbers, shape ``batch + (len(self),)``."""
        self._check(mech)
        columns: list[Array] = []
        for p in self.parameters:
            value = field_value(mech, p.field)
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
                own = field_value(template, name)
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
        return rebuilt(template, changes)

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
            value = field_value(mech, p.field)
            if p.component is not None:  # a pivot: both coordinates at once
                x, y = value[..., 0], value[..., 1]
                changes[p.field] = np.stack(
                    (s * (c * x - n * y) + t[..., 0], s * (n * x + c * y) + t[..., 1]), axis=-1
                )
            elif p.kind in ("length", "coordinate"):
                changes[p.field] = s * value
            elif p.kind == "angle":
                changes[p.field] = value + self._turns(p, params) * psi
        return rebuilt(mech, changes)

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
        changes = {
            name: np.einsum("...ij,...j->...i", R, field_value(mech, name)) for name in self.axes
        }
        return rebuilt(mech, changes)

    def frame(self, mech: Mechanism) -> tuple[Array, Array, Array]:
        """(base point, reference direction, scale) of planar linkages: what :meth:`normalise`
        moves to the origin, turns to 0 and scales to 1."""
        self._check(mech)
        base = field_value(mech, self.base) if self.base else np.zeros(2)
        angle: Array = np.zeros(())
        if self.reference is not None and self.reference[0] == "direction":
            angle = field_value(mech, self.reference[1])
        elif self.reference is not None:
            d = field_value(mech, self.reference[2]) - field_value(mech, self.reference[1])
            angle = np.arctan2(d[..., 1], d[..., 0])
        return base, angle, np.asarray(mech.scale, dtype=float)

    def normalise(self, mech: Mechanism) -> Mechanism:
        """The same linkage in its canonical place (module docstring): its curve is the
        original's, moved, turned and scaled (or, on the sphere, turned)."""
        self._check(mech)
        if self.in_family_frame:
            return mech
        if self.space == "sphere":
            a = field_value(mech, self.axes[0])
            b = field_value(mech, self.axes[1])
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

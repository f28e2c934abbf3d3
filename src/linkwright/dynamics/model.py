"""Mass properties and loads: what forces need beyond a mechanism, and their validation.

A document writes them as (units: the document's length and mass units, seconds; kilograms and
metres give newtons and newton-metres)::

    [mechanism.mass]          # each moving link named by its length field
    crank = 0.2               # a number alone: a uniform body (see below)
    rocker = { mass = 0.4, centre = { u = 1.5, v = 0.0 }, inertia = 0.3 }
    slider = 0.1              # a slider block: a mass at its pin

    [loads]
    speed = 120               # input speed, rpm (the CLI's --speed replaces it)
    acceleration = 0.0        # input angular acceleration, rad/s²
    inertia = true            # false: a static analysis (weights and loads, no inertia forces)
    gravity = [0.0, -9.81]    # acceleration of gravity, length unit / s² (default: none)
    forces = [{ point = "P", value = [0.0, -10.0] }]
    torques = [{ link = "rocker", value = 2.0 }]
    springs = [{ between = ["P", "B0"], stiffness = 100.0, length = 1.0 }]
    dampers = [{ between = ["B", "B0"], coefficient = 3.0 }]

On the sphere (every link turns about the centre O) a link's points are its joints' axes met
at the sphere of ``radius`` (under ``[loads]``, in the length unit; default 1), gravity and
point forces are vectors [x, y, z], and a link is written::

    crank = 0.2     # a uniform thin bar along the great-circle arc between its two joints
    rocker = { mass = 0.4, centre = { x = 0.9, y = 0.1, z = 0.0 },
               inertia = [[1e-3, 0, 0], [0, 2e-3, 0], [0, 0, 2e-3]] }

``centre`` in the link's frame (x along its first joint's axis, y towards the second joint in
their plane, z = x × y), ``inertia`` the tensor about the centre in that frame (symmetric, its
eigenvalues non-negative and each at most the sum of the other two, as every body's are). A
spherical link with three joints or more needs both. Torques, springs and dampers are planar
only for now.

A link given a mass alone is a uniform slender bar between the two joints its length spans
(the coupler A–B, whatever points it also carries), unless it has three joints (a ternary
link): then it is a uniform triangular plate over those three joints (inertia
m·(a² + b² + c²)/36 about its centroid). A link with four joints or more needs its centre and
inertia. ``centre`` is in the link's frame (origin the joint it hangs from, u towards the joint
it places, v to the left), ``inertia`` the polar moment about the centre (mass × length²).
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from linkwright.dynamics.bodies import Structure

__all__ = [
    "CENTRE_REACH",
    "ForcesInputError",
    "Loads",
    "MassProps",
    "check_forces_input",
    "check_speed",
    "link_lengths",
    "loads_from",
    "masses_from",
]

CENTRE_REACH = 10.0
"""A centre of mass farther from its link's origin than this many link lengths is refused as a
typing slip (no link of a linkage carries its mass that far out)."""
_MAX = 1e12
"""Largest size of a mass, inertia, speed or load: beyond it float64 products overflow."""


class ForcesInputError(ValueError):
    """A mass or load is not valid: ``field`` is its dotted path, ``problem`` what is wrong."""

    def __init__(self, field: str, problem: str) -> None:
        self.field = field
        self.problem = problem
        super().__init__(f"{field}: {problem}")


@dataclass(frozen=True)
class MassProps:
    """A link's mass, its centre (u, v) in the link's frame and its polar moment of inertia
    about the centre; None for the uniform body's (see the module's docstring)."""

    mass: float
    centre: tuple[float, ...] | None = None
    inertia: float | None = None
    tensor: tuple[tuple[float, float, float], ...] | None = None
    """On the sphere: the inertia tensor about the centre, in the link's frame."""


@dataclass(frozen=True)
class Loads:
    """Everything that acts besides the joints: see the module's docstring for the fields."""

    speed_rpm: float = 0.0
    acceleration: float = 0.0
    inertia: bool = True
    gravity: tuple[float, ...] = (0.0, 0.0)
    forces: tuple[tuple[str, tuple[float, ...]], ...] = ()
    torques: tuple[tuple[str, float], ...] = ()
    springs: tuple[tuple[str, str, float, float], ...] = ()
    dampers: tuple[tuple[str, str, float], ...] = ()
    radius: float = 1.0
    """On the sphere: the radius its links run at, in the length unit."""

    @property
    def omega(self) -> float:
        """The input speed, rad/s."""
        return self.speed_rpm * 2.0 * math.pi / 60.0


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _num(value: Any, path: str, *, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ForcesInputError(path, f"must be a number, got {_show(value)}")
    x = float(value)
    if not math.isfinite(x):
        raise ForcesInputError(path, f"must be a finite number, got {_show(value)}")
    if abs(x) > _MAX:
        raise ForcesInputError(path, f"must be at most {_MAX:g} in size, got {_show(value)}")
    if positive and x <= 0:
        raise ForcesInputError(path, f"must be positive, got {_show(value)}")
    if nonneg and x < 0:
        raise ForcesInputError(path, f"must not be negative, got {_show(value)}")
    return x


def _vec(value: Any, path: str, dim: int = 2) -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or len(value) != dim:
        shape = "a pair [x, y]" if dim == 2 else "a vector [x, y, z]"
        raise ForcesInputError(path, f"must be {shape}, got {_show(value)}")
    return tuple(_num(v, f"{path}[{k}]") for k, v in enumerate(value))


def _vec3(value: Any, path: str) -> tuple[float, float, float]:
    x, y, z = _vec(value, path, 3)
    return (x, y, z)


def _table(value: Any, path: str, allowed: tuple[str, ...]) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ForcesInputError(path, f"must be a table, got {_show(value)}")
    for key in value:
        if key not in allowed:
            raise ForcesInputError(path, _unknown("field", str(key), allowed))
    return value


def _unknown(noun: str, key: str, known: tuple[str, ...] | list[str]) -> str:
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.6)
    if close:
        return f"unknown {noun} {key!r} (did you mean {close[0]!r}?)"
    return f"unknown {noun} {key!r} (known: {', '.join(known) or 'none'})"


def link_lengths(structure: Structure, params: Mapping[str, Any]) -> dict[str, float]:
    """Each body's link length (the largest of a batch), by its name, where a length field
    names it: what :func:`masses_from` checks a centre of mass against."""
    return {
        b.name: float(np.max(np.asarray(params[b.name])))
        for b in structure.bodies
        if b.name in params
    }


def masses_from(
    table: Any, structure: Structure, lengths: Mapping[str, float], path: str = "mechanism.mass"
) -> dict[str, MassProps]:
    """The ``[mechanism.mass]`` table checked against the linkage's bodies.

    ``lengths`` maps a link's name to its length (the field's value), for the centre's check.
    Raises :class:`ForcesInputError` naming the field.
    """
    if not isinstance(table, Mapping):
        raise ForcesInputError(path, f"must be a table, got {_show(table)}")
    names = structure.names
    out: dict[str, MassProps] = {}
    for name, value in table.items():
        where = f"{path}.{name}"
        if name not in names:
            raise ForcesInputError(path, _unknown("link", str(name), names))
        body = structure.body(name)
        if structure.space == "sphere":
            out[name] = _sphere_mass(value, where, len(body.joints))
            continue
        if not isinstance(value, Mapping):
            out[name] = MassProps(_num(value, where, positive=True))
            continue
        spec = _table(value, where, ("mass", "centre", "inertia"))
        if "mass" not in spec:
            raise ForcesInputError(f"{where}.mass", "missing required field")
        mass = _num(spec["mass"], f"{where}.mass", positive=True)
        centre = inertia = None
        if "centre" in spec:
            if body.is_block:
                raise ForcesInputError(
                    f"{where}.centre", "a slider block's centre of mass is its pin: leave it out"
                )
            c = _table(spec["centre"], f"{where}.centre", ("u", "v"))
            centre = (
                _num(c.get("u", 0.0), f"{where}.centre.u"),
                _num(c.get("v", 0.0), f"{where}.centre.v"),
            )
            reach = CENTRE_REACH * float(lengths.get(name, math.inf))
            if math.hypot(*centre) > reach:
                raise ForcesInputError(
                    f"{where}.centre",
                    f"is {math.hypot(*centre):.6g} from the link's origin, more than "
                    f"{CENTRE_REACH:g} link lengths ({reach:.6g}): no link carries its mass so far",
                )
        if "inertia" in spec:
            inertia = _num(spec["inertia"], f"{where}.inertia")
            if inertia < 0:
                raise ForcesInputError(
                    f"{where}.inertia",
                    f"must not be negative (a moment of inertia is a sum of m·r²), got {inertia!r}",
                )
        if (centre is None) != (inertia is None) and not body.is_block:
            missing = "inertia" if inertia is None else "centre"
            raise ForcesInputError(
                f"{where}.{missing}",
                "missing: give the centre and the inertia together (or neither, for the uniform "
                "body)",
            )
        if centre is None and not body.is_block and len(body.joints) >= 4:
            raise ForcesInputError(
                where,
                f"the link {name} has {len(body.joints)} joints: give its centre and inertia "
                "(it is neither a bar nor a triangular plate)",
            )
        out[name] = MassProps(mass, centre, inertia)
    return out


def _sphere_mass(value: Any, where: str, joints: int) -> MassProps:
    """A spherical link's mass: alone (a uniform arc bar), or with its centre and tensor."""
    if not isinstance(value, Mapping):
        if joints >= 3:
            raise ForcesInputError(
                where,
                f"a spherical link with {joints} joints needs its centre and inertia tensor "
                "(only a two-joint link is taken as a uniform arc bar)",
            )
        return MassProps(_num(value, where, positive=True))
    spec = _table(value, where, ("mass", "centre", "inertia"))
    if "mass" not in spec:
        raise ForcesInputError(f"{where}.mass", "missing required field")
    mass = _num(spec["mass"], f"{where}.mass", positive=True)
    if ("centre" in spec) != ("inertia" in spec):
        missing = "inertia" if "inertia" not in spec else "centre"
        raise ForcesInputError(
            f"{where}.{missing}",
            "missing: give the centre and the inertia tensor together (or neither, for the "
            "uniform arc bar)",
        )
    if "centre" not in spec:
        return _sphere_mass(mass, where, joints)
    c = _table(spec["centre"], f"{where}.centre", ("x", "y", "z"))
    centre = tuple(_num(c.get(k, 0.0), f"{where}.centre.{k}") for k in "xyz")
    rows = spec["inertia"]
    path = f"{where}.inertia"
    if not isinstance(rows, list | tuple) or len(rows) != 3:
        raise ForcesInputError(
            path, f"must be a 3 × 3 tensor [[..], [..], [..]], got {_show(rows)}"
        )
    tensor = tuple(_vec3(r, f"{path}[{k}]") for k, r in enumerate(rows))
    t = np.array(tensor)
    if not np.allclose(t, t.T, rtol=1e-12, atol=1e-12 * float(np.max(np.abs(t)) or 1.0)):
        raise ForcesInputError(path, "must be symmetric (an inertia tensor is)")
    low, mid, high = np.linalg.eigvalsh(0.5 * (t + t.T))
    slack = 1e-12 * max(abs(high), 1e-300)
    if low < -slack:
        raise ForcesInputError(path, f"has a negative principal moment ({low:.6g})")
    if high > low + mid + slack:
        raise ForcesInputError(
            path,
            f"is not a body's: its largest principal moment {high:.6g} exceeds the sum of the "
            f"other two ({low + mid:.6g})",
        )
    return MassProps(mass, centre, tensor=tensor)


_LOAD_FIELDS = (
    "speed",
    "acceleration",
    "inertia",
    "gravity",
    "forces",
    "torques",
    "springs",
    "dampers",
    "radius",
)
_PLANE_ONLY = ("torques", "springs", "dampers")


def _entries(value: Any, path: str) -> list[Mapping[str, Any]]:
    if not isinstance(value, list | tuple):
        raise ForcesInputError(path, f"must be a list of tables, got {_show(value)}")
    if len(value) > 1000:
        raise ForcesInputError(path, f"has {len(value)} entries, at most 1000")
    return list(value)


def _point(value: Any, path: str, points: tuple[str, ...]) -> str:
    if not isinstance(value, str):
        raise ForcesInputError(path, f"must be a point's name, got {_show(value)}")
    if value not in points:
        raise ForcesInputError(path, _unknown("point", value, points))
    return value


def loads_from(
    table: Any, structure: Structure, points: tuple[str, ...], path: str = "loads"
) -> Loads:
    """The ``[loads]`` table checked against the linkage's points and links.

    ``points`` are the names a load may act at (every placed joint and point).
    """
    if table is None:
        return Loads()
    spec = _table(table, path, _LOAD_FIELDS)
    sphere = structure.space == "sphere"
    dim = 3 if sphere else 2
    for key in _PLANE_ONLY if sphere else ("radius",):
        if key in spec:
            raise ForcesInputError(
                f"{path}.{key}",
                "not on the sphere yet: planar linkages only"
                if sphere
                else "is a spherical linkage's (the radius its links run at)",
            )
    radius = _num(spec.get("radius", 1.0), f"{path}.radius", positive=True)
    speed = _num(spec.get("speed", 0.0), f"{path}.speed")
    accel = _num(spec.get("acceleration", 0.0), f"{path}.acceleration")
    inertia = spec.get("inertia", True)
    if not isinstance(inertia, bool):
        raise ForcesInputError(f"{path}.inertia", f"must be true or false, got {_show(inertia)}")
    gravity = _vec(spec["gravity"], f"{path}.gravity", dim) if "gravity" in spec else (0.0,) * dim
    forces = []
    for k, e in enumerate(_entries(spec.get("forces", []), f"{path}.forces")):
        w = f"{path}.forces[{k}]"
        e = _table(e, w, ("point", "value"))
        p = _point(e.get("point"), f"{w}.point", points)
        if structure.owner(p) is None:
            raise ForcesInputError(
                f"{w}.point", f"{p} is on the frame: a force there moves nothing"
            )
        forces.append((p, _vec(e.get("value"), f"{w}.value", dim)))
    torques = []
    for k, e in enumerate(_entries(spec.get("torques", []), f"{path}.torques")):
        w = f"{path}.torques[{k}]"
        e = _table(e, w, ("link", "value"))
        link = e.get("link")
        if not isinstance(link, str) or link not in structure.names:
            raise ForcesInputError(f"{w}.link", _unknown("link", str(link), structure.names))
        torques.append((link, _num(e.get("value"), f"{w}.value")))
    springs = []
    for k, e in enumerate(_entries(spec.get("springs", []), f"{path}.springs")):
        w = f"{path}.springs[{k}]"
        e = _table(e, w, ("between", "stiffness", "length"))
        a, b = _pair(e.get("between"), f"{w}.between", points)
        stiff = _num(e.get("stiffness"), f"{w}.stiffness", nonneg=True)
        springs.append((a, b, stiff, _num(e.get("length", 0.0), f"{w}.length", nonneg=True)))
    dampers = []
    for k, e in enumerate(_entries(spec.get("dampers", []), f"{path}.dampers")):
        w = f"{path}.dampers[{k}]"
        e = _table(e, w, ("between", "coefficient"))
        a, b = _pair(e.get("between"), f"{w}.between", points)
        dampers.append((a, b, _num(e.get("coefficient"), f"{w}.coefficient", nonneg=True)))
    return Loads(
        speed,
        accel,
        inertia,
        gravity,
        tuple(forces),
        tuple(torques),
        tuple(springs),
        tuple(dampers),
        radius,
    )


def _pair(value: Any, path: str, points: tuple[str, ...]) -> tuple[str, str]:
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise ForcesInputError(path, f"must be two points' names, got {_show(value)}")
    a, b = (_point(v, f"{path}[{k}]", points) for k, v in enumerate(value))
    if a == b:
        raise ForcesInputError(path, f"joins {a} to itself")
    return a, b


def check_speed(masses: Mapping[str, MassProps], loads: Loads, path: str = "loads.speed") -> None:
    """Inertia forces need the input to turn: refuse speed 0 where masses are given and
    inertia is asked for (``inertia = false`` asks for a static analysis instead)."""
    if masses and loads.inertia and loads.speed_rpm == 0 and loads.acceleration == 0:
        raise ForcesInputError(
            path,
            "must be given and non-zero (rpm) for inertia forces; set loads.inertia = false "
            "for a static analysis",
        )


def check_forces_input(mechanism: Any, mass: Any, loads: Any) -> None:
    """Validate a document's ``[mechanism.mass]`` and ``[loads]`` against its mechanism (the
    document reader's one-line hook). Raises :class:`ForcesInputError`; a linkage whose forces
    are not supported (on the sphere) is only refused when forces are asked for."""
    from linkwright.dynamics.bodies import UnsupportedPlan, structure

    if mass is None and loads is None:
        return
    try:
        found = structure(mechanism.plan)
    except UnsupportedPlan:
        return
    params = mechanism.params()
    masses = masses_from(mass, found, link_lengths(found, params)) if mass is not None else {}
    parsed = loads_from(loads, found, mechanism.plan.joints)
    if isinstance(loads, Mapping) and "speed" in loads:
        check_speed(masses, parsed)

"""Mechanism documents: TOML or JSON files that name a family and give its dimensions.

A document speaks degrees; the mechanism objects it builds speak radians. Every field a family
accepts is declared once, in the family registry (:mod:`linkwright.mechanisms.registry`, read
here as :data:`FAMILY_SPECS`), as a *kind* (point, length, angle in degrees,
sign, coupler point, slider line; on the sphere arc, {arc, angle} offset, axis); validation,
defaults, construction and the reverse conversion all read that one table, so a new family is a
new row. The composed family ``linkage`` is one row too: its ``joints`` field is a list of joint
tables, each read through the same kinds from the per-type table :data:`JOINT_SPECS`, or
:data:`SPHERE_JOINT_SPECS` when its ``space`` is ``"sphere"``.

Spherical links are arcs (central angles) in degrees, each strictly between 0 and 180; a point
on a link is ``{arc, angle}``: its arc from the link's first joint (0 to 180) and its angle from
the link, right-handed about that joint's axis (paper 000's AC and μ = BAC). The three spherical
families are ``spherical-fourbar`` (paper 000's frame, crank, coupler, rocker and ``point``),
``spherical-sixbar`` (paper 000's Fig. 8: ``point`` = C, ``link5`` = CE, ``link6`` = E0E,
``ground`` = {B0E0, ε}, ``d`` = {CD, ECD}) and ``spherical-stephenson3`` (paper 001: a1 … a9,
sigma, input "AB" or "FG"). A spherical linkage's fixed joint is an axis ``at = [x, y, z]``,
any non-zero vector along it (the document keeps it as written; the joint is its direction).

Example document (TOML)::

    format = "linkwright/1"
    title = "Crank-rocker"

    [mechanism]
    family = "fourbar"
    A0 = [0.0, 0.0]
    B0 = [3.5, 0.0]
    crank = 1.0
    coupler = 5.0
    rocker = 6.02
    point = { u = 2.5, v = 1.5 }
    assembly = 1

Paper 000's Fig. 6 spherical crank-rocker::

    format = "linkwright/1"

    [mechanism]
    family = "spherical-fourbar"
    frame = 40.0
    crank = 20.0
    coupler = 45.0
    rocker = 35.0
    point = { arc = 50.0, angle = 130.0 }
    assembly = 1

The same linkage composed joint by joint on the sphere (a crank's angle is measured from the
great circle towards its ``toward`` joint, which defaults to the first other fixed joint
listed before it)::

    format = "linkwright/1"

    [mechanism]
    family = "linkage"
    space = "sphere"

    [[mechanism.joints]]
    name = "A0"
    type = "fixed"
    at = [1.0, 0.0, 0.0]

    [[mechanism.joints]]
    name = "B0"
    type = "fixed"
    at = [0.766044443118978, 0.6427876096865393, 0.0]  # (cos 40°, sin 40°, 0)

    [[mechanism.joints]]
    name = "A"
    type = "crank"
    pivot = "A0"
    arc = 20.0
    toward = "B0"

    [[mechanism.joints]]
    name = "B"
    type = "rrr"
    p1 = "A"
    r1 = 45.0
    p2 = "B0"
    r2 = 35.0

    [[mechanism.joints]]
    name = "P"
    type = "rigid"
    origin = "A"
    toward = "B"
    arc = 50.0
    angle = 130.0

A composed linkage (a four-bar written joint by joint, tracing its coupler point P)::

    format = "linkwright/1"

    [mechanism]
    family = "linkage"
    space = "plane"
    traced = ["P"]

    [[mechanism.joints]]
    name = "A0"
    type = "fixed"
    at = [0.0, 0.0]

    [[mechanism.joints]]
    name = "B0"
    type = "fixed"
    at = [3.5, 0.0]

    [[mechanism.joints]]
    name = "A"
    type = "crank"
    pivot = "A0"
    length = 1.0

    [[mechanism.joints]]
    name = "B"
    type = "rrr"
    p1 = "A"
    r1 = 5.0
    p2 = "B0"
    r2 = 6.02

    [[mechanism.joints]]
    name = "P"
    type = "rigid"
    origin = "A"
    toward = "B"
    u = 2.5
    v = 1.5
"""

from __future__ import annotations

import copy
import difflib
import json
import math
import numbers
import os
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from linkwright.files import atomic_path
from linkwright.mechanisms import registry
from linkwright.mechanisms.registry import Derived, FieldSpec

if TYPE_CHECKING:
    from linkwright.mechanisms import Mechanism

__all__ = [
    "FAMILY_SPECS",
    "FORMAT",
    "JOINT_SPECS",
    "KINDS",
    "SPHERE_JOINT_SPECS",
    "WORKING_RANGE",
    "Document",
    "DocumentError",
    "FamilySpec",
    "FieldSpec",
    "document_to_dict",
    "dumps_toml",
    "list_examples",
    "load_document",
    "load_example",
    "mechanism_to_dict",
    "parse_document",
    "save_document",
]

FORMAT = "linkwright/1"
_TOP_LEVEL = ("format", "title", "units", "mechanism")


@dataclass(frozen=True)
class WorkingRange:
    """Where a document's numbers must lie for float64 arithmetic on them to mean something.

    A number outside is refused with its field's path, not solved into overflow, underflow or
    noise: 1e300 squares to infinity, 1e-300 to zero, and a link 1e-12 of the linkage's size
    keeps four digits after the positions' rounding. Lengths and coordinates are in the
    document's own units; the bounds leave any sensible unit (nanometres to kilometres) room.
    """

    max_size: float = 1e12
    """Largest length, coordinate or coupler offset, in the document's units."""
    min_length: float = 1e-12
    """Smallest length, in the document's units."""
    min_share: float = 1e-9
    """Smallest length, and smallest distance between pivots that must differ, as a share of the
    linkage's size (its largest length or coordinate): float64 then keeps about seven digits."""
    max_angle: float = 1e6
    """Largest angle in degrees: beyond it the fraction of a turn keeps fewer than ten digits."""
    min_arc: float = 1e-6
    """How close (degrees) a spherical link's arc may come to 0 or to 180."""
    min_ratio: float = 1e-6
    """Smallest size of a gear ratio (and 1 / the largest)."""

    def size_problem(self, value: float) -> str | None:
        """What is wrong with ``value`` as a length or coordinate's size, or None.

        >>> WORKING_RANGE.size_problem(-3.5) is None
        True
        >>> print(WORKING_RANGE.size_problem(1e300))
        must be at most 1e+12 in size, got 1e+300 (outside linkwright's working range: use
        larger units)
        """
        if abs(value) <= self.max_size:
            return None
        return (
            f"must be at most {self.max_size:g} in size, got {_show(value)} "
            "(outside linkwright's working range: use larger units)"
        )

    def angle_problem(self, value: float) -> str | None:
        """What is wrong with ``value`` as an angle in degrees, or None."""
        if abs(value) <= self.max_angle:
            return None
        return (
            f"must be at most {self.max_angle:g} degrees in size, got {_show(value)} "
            "(outside linkwright's working range: reduce it by whole turns of 360)"
        )

    def ratio_problem(self, value: float) -> str | None:
        """What is wrong with a nonzero ``value`` as a ratio (a gear's, a hinge radii's)."""
        low = self.min_ratio
        if low <= abs(value) <= 1 / low:
            return None
        return (
            f"must be from {low:g} to {1 / low:g} in size, got {_show(value)} "
            "(outside linkwright's working range for ratios)"
        )


WORKING_RANGE = WorkingRange()


class DocumentError(ValueError):
    """A document is not valid: the message names the field path and the problem.

    Attributes
    ----------
    field : str
        Dotted path of the offending field (``"mechanism.crank"``), or ``"document"``.
    problem : str
        What is wrong with it.
    source : str or None
        Where the document came from (a file name), when known.
    """

    def __init__(self, field: str, problem: str, source: str | None = None) -> None:
        self.field = field
        self.problem = problem
        self.source = source
        prefix = f"{source}: " if source else ""
        super().__init__(f"{prefix}{field}: {problem}")

    def with_source(self, source: str | None) -> DocumentError:
        """The same error, attributed to ``source``."""
        return DocumentError(self.field, self.problem, source)


# --------------------------------------------------------------------------------------------
# Kinds: how one document field is checked, turned into constructor arguments, and read back.
# --------------------------------------------------------------------------------------------


def _show(value: Any) -> str:
    """A value as the user wrote it (JSON-ish), short enough for a one-line message."""
    if isinstance(value, float):
        text = repr(value)
    elif isinstance(value, int) and not isinstance(value, bool):
        text = str(value) if abs(value) < 10**30 else f"an integer of {len(str(abs(value)))} digits"
    else:
        try:
            text = json.dumps(value, ensure_ascii=False, allow_nan=True, default=repr)
        except (TypeError, ValueError, RecursionError):
            text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _number(value: Any, path: str, what: str) -> float:
    """A finite float from an int or float (bool is not a number, however Python sees it)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise DocumentError(path, f"must be {what}, got {_show(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise DocumentError(path, f"must be a finite number, got {_show(value)}") from None
    if not math.isfinite(x):
        raise DocumentError(path, f"must be a finite number, got {_show(value)}")
    return x


def _sized(value: Any, path: str, what: str) -> float:
    """A number no larger than the working range allows (a length, coordinate or offset)."""
    x = _number(value, path, what)
    if problem := WORKING_RANGE.size_problem(x):
        raise DocumentError(path, problem)
    return x


def _table(value: Any, path: str, what: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise DocumentError(path, f"must be {what}, got {_show(value)}")
    for key in value:
        if not isinstance(key, str):
            raise DocumentError(path, f"keys must be strings, got {_show(key)}")
    return value


def _check_keys(table: Mapping[str, Any], allowed: tuple[str, ...], path: str) -> None:
    for key in table:
        if key not in allowed:
            raise DocumentError(path, _unknown("field", key, allowed))


def _unknown(noun: str, key: str, known: tuple[str, ...]) -> str:
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    if close:
        return f"unknown {noun} {key!r} (did you mean {close[0]!r}?)"
    return f"unknown {noun} {key!r} (known: {', '.join(known)})"


def _parse_point(value: Any, path: str) -> list[float]:
    what = "a point [x, y]"
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise DocumentError(path, f"must be {what}, got {_show(value)}")
    return [_sized(c, f"{path}[{i}]", "a number") for i, c in enumerate(value)]


def _parse_length(value: Any, path: str) -> float:
    x = _sized(value, path, "a positive number")
    if x <= 0:
        raise DocumentError(path, f"must be a positive number, got {_show(value)}")
    if x < WORKING_RANGE.min_length:
        raise DocumentError(
            path,
            f"must be at least {WORKING_RANGE.min_length:g}, got {_show(value)} "
            "(outside linkwright's working range: use smaller units)",
        )
    return x


def _parse_angle(value: Any, path: str) -> float:
    x = _number(value, path, "an angle in degrees")
    if problem := WORKING_RANGE.angle_problem(x):
        raise DocumentError(path, problem)
    return x


def _parse_sign(value: Any, path: str) -> int:
    x = _number(value, path, "1 or -1")
    if x not in (1.0, -1.0):
        raise DocumentError(path, f"must be 1 or -1, got {_show(value)}")
    return int(x)


def _parse_pose(value: Any, path: str) -> int:
    x = _number(value, path, "a whole number from 0")
    if x != int(x) or not 0 <= x <= 7:
        raise DocumentError(
            path,
            f"must be a whole number from 0 to 7 (a triad's pose index), got {_show(value)}",
        )
    return int(x)


def _parse_uv(value: Any, path: str) -> dict[str, float]:
    table = _table(value, path, "a table {u = .., v = ..}")
    _check_keys(table, ("u", "v"), path)
    # Either coordinate may be left out: a point on the A→B line needs only u.
    return {k: _sized(table.get(k, 0.0), f"{path}.{k}", "a number") for k in ("u", "v")}


def _parse_line(value: Any, path: str) -> dict[str, Any]:
    table = _table(value, path, "a table {point = [x, y], angle = ..}")
    _check_keys(table, ("point", "angle"), path)
    for key in ("point", "angle"):
        if key not in table:
            raise DocumentError(f"{path}.{key}", "missing required field")
    return {
        "point": _parse_point(table["point"], f"{path}.point"),
        "angle": _parse_angle(table["angle"], f"{path}.angle"),
    }


def _parse_arc(value: Any, path: str) -> float:
    x = _number(value, path, "an arc in degrees")
    # Nearer 0 or 180 the link's far end has no direction float64 can hold (and a subnormal
    # arc's radians underflow to 0).
    near = WORKING_RANGE.min_arc
    if not near <= x <= 180 - near:
        raise DocumentError(
            path,
            f"must be an arc strictly between 0 and 180 degrees, got {_show(value)} "
            f"(a spherical link's central angle, at least {near:g} from 0 and from 180)",
        )
    return x


def _parse_offset_arc(value: Any, path: str) -> float:
    x = _number(value, path, "an arc in degrees")
    if not 0 <= x <= 180:
        raise DocumentError(
            path,
            f"must be an arc from 0 to 180 degrees, got {_show(value)} "
            "(for a point on the other side, add 180 to its angle instead)",
        )
    return x


def _arc_angle(strict: bool) -> Callable[[Any, str], dict[str, float]]:
    """A table {arc, angle}: a rigid point's (``strict`` False: 0 ≤ arc ≤ 180) or a ground
    pivot's (``strict``: a link, 0 < arc < 180) place from a joint; angle defaults to 0."""
    parse_arc = _parse_arc if strict else _parse_offset_arc

    def parse(value: Any, path: str) -> dict[str, float]:
        table = _table(value, path, "a table {arc = .., angle = ..}")
        _check_keys(table, ("arc", "angle"), path)
        if "arc" not in table:
            raise DocumentError(f"{path}.arc", "missing required field (an arc in degrees)")
        return {
            "arc": parse_arc(table["arc"], f"{path}.arc"),
            "angle": _parse_angle(table.get("angle", 0.0), f"{path}.angle"),
        }

    return parse


def _parse_axis(value: Any, path: str) -> list[float]:
    what = "an axis [x, y, z] (a vector from the sphere's centre along the joint's axis)"
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise DocumentError(path, f"must be {what}, got {_show(value)}")
    axis = [_sized(c, f"{path}[{i}]", "a number") for i, c in enumerate(value)]
    if not any(axis):
        raise DocumentError(
            path, "must not be the zero vector [0, 0, 0] (its direction is the joint's axis)"
        )
    if max(map(abs, axis)) < WORKING_RANGE.min_length:
        raise DocumentError(
            path,
            f"must have a component of at least {WORKING_RANGE.min_length:g} in size, got "
            f"{_show(value)} (scale the vector up: only its direction counts)",
        )
    return axis


def _parse_signed(value: Any, path: str) -> float:
    return _sized(value, path, "a number")


def _parse_ratio(value: Any, path: str) -> float:
    x = _number(value, path, "a nonzero number")
    if x == 0:
        raise DocumentError(
            path, f"must be a nonzero number, got {_show(value)} (a ratio of 0 does not turn)"
        )
    if problem := WORKING_RANGE.ratio_problem(x):
        raise DocumentError(path, problem)
    return x


def _parse_joint_name(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value:
        raise DocumentError(path, f"must be a joint name (a non-empty string), got {_show(value)}")
    return _text(value, path)


def _parse_names(value: Any, path: str) -> list[str]:
    if not isinstance(value, list | tuple):
        raise DocumentError(path, f"must be a list of joint names, got {_show(value)}")
    if not value:
        raise DocumentError(path, "must name at least one joint")
    return [_parse_joint_name(v, f"{path}[{i}]") for i, v in enumerate(value)]


def _choice(choices: tuple[str, ...], refused: Mapping[str, str] | None = None) -> Kind:
    """A kind whose value is one of a few strings; ``refused`` explains known-but-unsupported."""
    refused = refused or {}
    describe = " or ".join(f'"{c}"' for c in choices)

    def parse(value: Any, path: str) -> str:
        if not isinstance(value, str):
            raise DocumentError(path, f"must be {describe}, got {_show(value)}")
        if value in refused:
            raise DocumentError(path, refused[value])
        if value not in choices:
            raise DocumentError(path, _unknown("value", value, choices))
        return value

    return Kind(
        describe,
        parse,
        lambda v, a: {a[0]: v},
        lambda m, a: str(getattr(m, a[0])),
    )


def tidy_number(x: float, ulps: int = 4) -> float:
    """The shortest decimal within a few units in the last place of ``x``, else ``x`` itself.

    A degrees→radians→degrees trip leaves last-bit noise (30 comes back as 29.999999999999996);
    this undoes it without touching any digit that carries information.

    >>> tidy_number(29.999999999999996), tidy_number(-106.0684593829853)
    (30.0, -106.0684593829853)
    """
    if not math.isfinite(x):
        return x
    tol = ulps * math.ulp(x)
    for places in range(16):
        nice = round(x, places)
        if abs(nice - x) <= tol:
            return nice
    return x


def _deg(rad: float) -> float:
    return tidy_number(math.degrees(rad))


def _scalar(mech: Any, attr: str) -> float:
    import numpy as np

    value = np.asarray(getattr(mech, attr), dtype=float)
    if value.shape != ():
        raise DocumentError(attr, f"must be a single value to be written, got shape {value.shape}")
    return float(value)


def _pair(mech: Any, attr: str, size: int = 2) -> list[float]:
    import numpy as np

    value = np.asarray(getattr(mech, attr), dtype=float)
    if value.shape != (size,):
        what = "point" if size == 2 else "axis"
        raise DocumentError(attr, f"must be a single {what} to be written, got shape {value.shape}")
    return [float(c) for c in value]


def _arc_deg(mech: Any, attr: str, strict: bool) -> float:
    """An arc field in degrees, in the shortest decimal that the document accepts back.

    Every radian value strictly inside (0, π) has its degrees strictly inside (0, 180) (the
    largest float below π gives 179.99999999999997), but tidying may round such a value onto
    180 (or 0, for a strict arc): then the untidied degrees are written.
    """
    exact = math.degrees(_scalar(mech, attr))
    tidy = tidy_number(exact)
    inside = 0 < tidy < 180 if strict else 0 <= tidy <= 180
    return tidy if inside else exact


@dataclass(frozen=True)
class Kind:
    """One kind of document field.

    Attributes
    ----------
    describe : what a valid value looks like (for messages).
    parse : (raw value, path) → canonical document value; raises :class:`DocumentError`.
    to_kwargs : (canonical value, constructor attribute names) → constructor arguments.
    from_mech : (mechanism, attribute names) → canonical document value.
    builds : False for a field that only says how to read the document and passes nothing to
        the constructor.
    context : True for a field read in the light of the fields before it (a linkage's joints,
        whose kinds depend on its ``space``): ``parse`` and ``to_kwargs`` then take the
        family's fields parsed so far as a third argument.
    """

    describe: str
    parse: Callable[..., Any]
    to_kwargs: Callable[..., dict[str, Any]]
    from_mech: Callable[[Any, tuple[str, ...]], Any]
    builds: bool = True
    context: bool = False


KINDS: dict[str, Kind] = {
    "point": Kind(
        "a point [x, y]",
        _parse_point,
        lambda v, a: {a[0]: tuple(v)},
        lambda m, a: _pair(m, a[0]),
    ),
    "length": Kind(
        "a positive number",
        _parse_length,
        lambda v, a: {a[0]: v},
        lambda m, a: _scalar(m, a[0]),
    ),
    "angle_deg": Kind(
        "an angle in degrees",
        _parse_angle,
        lambda v, a: {a[0]: math.radians(v)},
        lambda m, a: _deg(_scalar(m, a[0])),
    ),
    "sign": Kind(
        "1 or -1",
        _parse_sign,
        lambda v, a: {a[0]: float(v)},
        lambda m, a: int(_scalar(m, a[0])),
    ),
    "pose": Kind(
        "a whole number from 0 (a triad's pose index)",
        _parse_pose,
        lambda v, a: {a[0]: float(v)},
        lambda m, a: int(_scalar(m, a[0])),
    ),
    "uv": Kind(
        "a table {u = .., v = ..}",
        _parse_uv,
        lambda v, a: {a[0]: v["u"], a[1]: v["v"]},
        lambda m, a: {"u": _scalar(m, a[0]), "v": _scalar(m, a[1])},
    ),
    "line": Kind(
        "a table {point = [x, y], angle = ..}",
        _parse_line,
        lambda v, a: {a[0]: tuple(v["point"]), a[1]: math.radians(v["angle"])},
        lambda m, a: {"point": _pair(m, a[0]), "angle": _deg(_scalar(m, a[1]))},
    ),
    "number": Kind(
        "a number",
        _parse_signed,
        lambda v, a: {a[0]: v},
        lambda m, a: _scalar(m, a[0]),
    ),
    "ratio": Kind(
        "a nonzero number",
        _parse_ratio,
        lambda v, a: {a[0]: v},
        lambda m, a: _scalar(m, a[0]),
    ),
    "stephenson_input": _choice(("crank", "output")),
    "spherical_input": _choice(("AB", "FG")),
    "arc": Kind(
        "an arc in degrees, strictly between 0 and 180",
        _parse_arc,
        lambda v, a: {a[0]: math.radians(v)},
        lambda m, a: _arc_deg(m, a[0], strict=True),
    ),
    "offset_arc": Kind(
        "an arc in degrees, from 0 to 180",
        _parse_offset_arc,
        lambda v, a: {a[0]: math.radians(v)},
        lambda m, a: _arc_deg(m, a[0], strict=False),
    ),
    "arc_point": Kind(
        "a table {arc = .., angle = ..} (degrees, arc from 0 to 180)",
        _arc_angle(strict=False),
        lambda v, a: {a[0]: math.radians(v["arc"]), a[1]: math.radians(v["angle"])},
        lambda m, a: {
            "arc": _arc_deg(m, a[0], strict=False),
            "angle": _deg(_scalar(m, a[1])),
        },
    ),
    "arc_pivot": Kind(
        "a table {arc = .., angle = ..} (degrees, arc strictly between 0 and 180)",
        _arc_angle(strict=True),
        lambda v, a: {a[0]: math.radians(v["arc"]), a[1]: math.radians(v["angle"])},
        lambda m, a: {
            "arc": _arc_deg(m, a[0], strict=True),
            "angle": _deg(_scalar(m, a[1])),
        },
    ),
    "axis": Kind(
        "an axis [x, y, z]",
        _parse_axis,
        lambda v, a: {a[0]: tuple(v)},
        lambda m, a: _pair(m, a[0], size=3),
    ),
    "space": Kind(
        '"plane" or "sphere"',
        _choice(("plane", "sphere")).parse,
        lambda v, a: {a[0]: v},
        lambda m, a: str(getattr(m, a[0])),
    ),
    "joint": Kind(
        "a joint name",
        _parse_joint_name,
        lambda v, a: {a[0]: v},
        lambda m, a: str(getattr(m, a[0])),
    ),
    "names": Kind(
        "a list of joint names",
        _parse_names,
        lambda v, a: {a[0]: tuple(v)},
        lambda m, a: [str(n) for n in getattr(m, a[0])],
    ),
    "joints": Kind(
        "a list of joint tables [[mechanism.joints]]",
        lambda v, p, m: _parse_joints(v, p, m["space"]),
        lambda v, a, m: {a[0]: _build_joints(v, m["space"])},
        lambda m, a: _joints_from_mech(getattr(m, a[0]), m.space),
        context=True,
    ),
}


@dataclass(frozen=True)
class FamilySpec:
    """A family's document schema: its fields, the points that must differ, and other checks."""

    fields: tuple[FieldSpec, ...]
    distinct: tuple[tuple[str, str, str], ...] = ()
    """(field, other field, why) for points that may not coincide."""
    checks: tuple[Callable[[dict[str, Any]], None], ...] = ()
    """Rules across fields, run on the validated fields; each raises :class:`DocumentError`."""

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.fields)


def _doubleslider_lines(m: dict[str, Any]) -> None:
    # Stricter than the DoubleSlider constructor's bound (|sin α| ≤ 1e-12), so that no alpha the
    # document accepts is refused by the class, and the error names the document's field; the
    # working range keeps the lines as far apart as a spherical arc from 0.
    if abs(math.sin(math.radians(m["alpha"]))) < math.sin(math.radians(WORKING_RANGE.min_arc)):
        raise DocumentError(
            "mechanism.alpha",
            f"must not be a multiple of 180 degrees, got {_show(m['alpha'])} "
            f"(the slider lines would be parallel; keep them {WORKING_RANGE.min_arc:g} "
            "degrees apart at least)",
        )
    _, size = _planar_dimensions(m, FAMILY_SPECS["doubleslider"])
    if abs(m["p"] + m["q"]) <= WORKING_RANGE.min_share * size:
        raise DocumentError(
            "mechanism.q", "p + q must not be 0 (the sliders R and Q would coincide)"
        )


def _linkage_traced(m: dict[str, Any]) -> None:
    names = {j["name"] for j in m["joints"]}
    for i, name in enumerate(m["traced"]):
        if name not in names:
            raise DocumentError(
                f"mechanism.traced[{i}]",
                _unknown("joint", name, tuple(j["name"] for j in m["joints"])),
            )
        if name in m["traced"][:i]:
            raise DocumentError(f"mechanism.traced[{i}]", f"joint {name!r} is listed twice")


# Rules across a family's fields that a document must keep (the registry declares the fields).
_CHECKS: dict[str, tuple[Callable[[dict[str, Any]], None], ...]] = {
    "doubleslider": (_doubleslider_lines,),
    "linkage": (_linkage_traced,),
}


def _family_specs() -> dict[str, FamilySpec]:
    """Every registered family's document schema (:mod:`linkwright.mechanisms.registry`)."""
    return {
        f.name: FamilySpec(fields=f.fields, distinct=f.distinct, checks=_CHECKS.get(f.name, ()))
        for f in registry.families()
    }


FAMILY_SPECS: dict[str, FamilySpec] = _family_specs()
"""Every family's document schema, by family name, derived from the registry (a family
registered after this module was imported is added when a document first names it)."""


def _registered() -> None:
    """Add the families registered since this module was imported (a family of one's own,
    declared in a file of its own, is read like a built-in one)."""
    if len(FAMILY_SPECS) != sum(1 for _ in registry.families()):
        FAMILY_SPECS.clear()
        FAMILY_SPECS.update(_family_specs())


JOINT_SPECS: dict[str, tuple[FieldSpec, ...]] = {
    "fixed": (FieldSpec("at", "point"),),
    "crank": (
        FieldSpec("pivot", "joint"),
        FieldSpec("length", "length"),
        FieldSpec("ratio", "ratio", default=1.0),
        FieldSpec("phase", "angle_deg", default=0.0),
    ),
    "rrr": (
        FieldSpec("p1", "joint"),
        FieldSpec("r1", "length"),
        FieldSpec("p2", "joint"),
        FieldSpec("r2", "length"),
        FieldSpec("assembly", "sign", default=1),
    ),
    "rrp": (
        FieldSpec("p1", "joint"),
        FieldSpec("r", "length"),
        FieldSpec("line_point", "joint"),
        FieldSpec("line_angle", "angle_deg"),
        FieldSpec("assembly", "sign", default=1),
    ),
    "rigid": (
        FieldSpec("origin", "joint"),
        FieldSpec("toward", "joint"),
        FieldSpec("u", "number", default=0.0),
        FieldSpec("v", "number", default=0.0),
    ),
}
"""A planar ``linkage`` joint's fields by its ``type`` (besides ``name`` and ``type``), in
document order; the names are those of the joint spec classes of
:mod:`linkwright.mechanisms.linkage`, and angles are degrees here as everywhere in a document."""

_TOWARD = "the first fixed joint listed before the crank, other than its pivot"

SPHERE_JOINT_SPECS: dict[str, tuple[FieldSpec, ...]] = {
    # Any non-zero vector: the joint is its direction (the class normalises it), so an axis
    # can be written [0, 0, 1] or [1, 1, 0]; the document keeps the vector as written.
    "fixed": (FieldSpec("at", "axis"),),
    "crank": (
        FieldSpec("pivot", "joint"),
        FieldSpec("arc", "arc"),
        FieldSpec("ratio", "ratio", default=1.0),
        FieldSpec("phase", "angle_deg", default=0.0),
        # Filled in by _parse_joints, which sees the joints before the crank.
        FieldSpec("toward", "joint", default=Derived(_TOWARD, lambda m: None)),
    ),
    "rrr": (
        FieldSpec("p1", "joint"),
        FieldSpec("r1", "arc"),
        FieldSpec("p2", "joint"),
        FieldSpec("r2", "arc"),
        FieldSpec("assembly", "sign", default=1),
    ),
    "rigid": (
        FieldSpec("origin", "joint"),
        FieldSpec("toward", "joint"),
        FieldSpec("arc", "offset_arc", default=0.0),
        FieldSpec("angle", "angle_deg", default=0.0),
    ),
}
"""A spherical ``linkage`` joint's fields by its ``type`` (``space = "sphere"``): arcs and angles
in degrees, a fixed joint's ``at`` an axis [x, y, z]; the names are those of
:class:`~linkwright.mechanisms.linkage.FixedJoint`,
:class:`~linkwright.mechanisms.linkage.SphereCrankJoint`,
:class:`~linkwright.mechanisms.linkage.DyadJoint` and
:class:`~linkwright.mechanisms.linkage.SphereRigidJoint`. There is no ``rrp``."""

_JOINT_SPECS_IN: dict[str, dict[str, tuple[FieldSpec, ...]]] = {
    "plane": JOINT_SPECS,
    "sphere": SPHERE_JOINT_SPECS,
}

# Planar habits on the sphere, answered with what to write instead.
_SPHERE_HINTS = {
    ("crank", "length"): "a spherical crank's length is an arc: write arc = <degrees>",
    ("rigid", "u"): "a spherical rigid point is placed by arc and angle (degrees), not u and v",
    ("rigid", "v"): "a spherical rigid point is placed by arc and angle (degrees), not u and v",
}
_NO_SPHERICAL_SLIDER = (
    "a slider (rrp) has no spherical counterpart: a pin on a great-circle guide is an rrr "
    "joint whose second link, 90 degrees long, turns about the guide's pole; write that instead"
)


def _parse_fields(
    table: Mapping[str, Any], specs: tuple[FieldSpec, ...], path: str, out: dict[str, Any]
) -> dict[str, Any]:
    """Parse ``specs`` from ``table`` into ``out`` (defaults filled in); paths under ``path``."""
    for f in specs:
        where = f"{path}.{f.name}"
        kind = KINDS[f.kind]
        if f.name in table:
            value = table[f.name]
            out[f.name] = (
                kind.parse(value, where, out) if kind.context else kind.parse(value, where)
            )
        elif f.default is None:
            raise DocumentError(where, f"missing required field ({kind.describe})")
        elif isinstance(f.default, Derived):
            out[f.name] = f.default.compute(out)
        else:
            out[f.name] = copy.deepcopy(f.default)
    return out


def _parse_joints(value: Any, path: str, space: str) -> list[dict[str, Any]]:
    """A linkage's joint tables, each checked field by field against :data:`JOINT_SPECS` (or
    :data:`SPHERE_JOINT_SPECS` for ``space = "sphere"``).

    How the joints fit together (order, references, cycles, over-constraint) is the Linkage
    class's to judge; :func:`_build` turns its verdict into a path here. The one exception is a
    spherical crank's default ``toward``, which the document must spell out to be complete.
    """
    if not isinstance(value, list | tuple):
        raise DocumentError(path, f"must be a list of joint tables, got {_show(value)}")
    joint_specs = _JOINT_SPECS_IN[space]
    types = tuple(joint_specs)
    out: list[dict[str, Any]] = []
    for i, entry in enumerate(value):
        where = f"{path}[{i}]"
        table = _table(entry, where, "a joint table {name = .., type = .., ...}")
        if "name" not in table:
            raise DocumentError(f"{where}.name", "missing required field (a joint name)")
        name = _parse_joint_name(table["name"], f"{where}.name")
        if "type" not in table:
            raise DocumentError(
                f"{where}.type", f"missing required field (one of {', '.join(types)})"
            )
        kind = table["type"]
        if not isinstance(kind, str):
            raise DocumentError(f"{where}.type", f"must be a string, got {_show(kind)}")
        if space == "sphere" and kind in ("rrp", "slider"):
            raise DocumentError(f"{where}.type", _NO_SPHERICAL_SLIDER)
        if kind not in joint_specs:
            raise DocumentError(f"{where}.type", _unknown("joint type", kind, types))
        specs = joint_specs[kind]
        if space == "sphere":
            for key in table:
                if (kind, key) in _SPHERE_HINTS:
                    raise DocumentError(f"{where}.{key}", _SPHERE_HINTS[(kind, key)])
        _check_keys(table, ("name", "type", *(f.name for f in specs)), where)
        entry = _parse_fields(table, specs, where, {"name": name, "type": kind})
        if space == "sphere" and kind == "crank" and entry["toward"] is None:
            entry["toward"] = _default_toward(entry, out, f"{where}.toward")
        out.append(entry)
    return out


def _default_toward(crank: dict[str, Any], before: list[dict[str, Any]], path: str) -> str:
    """The fixed joint a spherical crank's angle starts towards, when the document names none
    (the same rule as :class:`~linkwright.mechanisms.linkage.SphereCrankJoint`'s)."""
    for j in before:
        if j["type"] == "fixed" and j["name"] != crank["pivot"]:
            return j["name"]
    raise DocumentError(
        path,
        "missing, and no fixed joint other than the pivot is listed before this crank to "
        "default to (the crank's angle is measured from the great circle towards it)",
    )


def _build_joints(joints: list[dict[str, Any]], space: str) -> tuple[Any, ...]:
    from linkwright.mechanisms.linkage import SPACES

    classes = SPACES[space]
    built = []
    for entry in joints:
        kwargs: dict[str, Any] = {"name": entry["name"]}
        for f in _JOINT_SPECS_IN[space][entry["type"]]:
            kwargs.update(KINDS[f.kind].to_kwargs(entry[f.name], f.targets))
        built.append(classes[entry["type"]](**kwargs))
    return tuple(built)


def _joints_from_mech(joints: Any, space: str) -> list[dict[str, Any]]:
    out = []
    for i, joint in enumerate(joints):
        entry: dict[str, Any] = {"name": joint.name, "type": joint.type}
        for f in _JOINT_SPECS_IN[space][joint.type]:
            try:
                entry[f.name] = KINDS[f.kind].from_mech(joint, f.targets)
            except DocumentError as exc:
                raise DocumentError(f"joints[{i}].{f.name}", exc.problem) from None
        out.append(entry)
    return out


def _mechanism_class(family: str) -> type[Mechanism]:
    try:
        return registry.family(family).cls  # type: ignore[no-any-return]
    except LookupError:
        raise DocumentError(
            "mechanism.family", f"family {family!r} is not available in this version"
        ) from None


# --------------------------------------------------------------------------------------------
# Documents
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Document:
    """A validated mechanism document.

    Attributes
    ----------
    title, units : optional display strings.
    family : the family name (a key of :data:`FAMILY_SPECS`).
    mechanism : the mechanism object built from the document (radians inside).
    raw : the validated document as a mapping, every default filled in (degrees).

    Two documents are equal when their validated mappings are: the mechanism is derived from
    ``raw``, and its array fields do not compare to a single truth value.
    """

    title: str | None
    units: str | None
    family: str
    mechanism: Mechanism = field(compare=False, repr=False)
    raw: dict[str, Any] = field(repr=False)


def parse_document(mapping: Any, source: str | None = None) -> Document:
    """Validate a document mapping (as parsed from TOML or JSON) and build its mechanism.

    Parameters
    ----------
    mapping : the parsed document.
    source : where it came from, prefixed to error messages.

    Returns
    -------
    Document

    Raises
    ------
    DocumentError
        On the first problem found, naming its field path.

    Examples
    --------
    >>> doc = parse_document({"format": "linkwright/1", "mechanism": {
    ...     "family": "slidercrank", "A0": [0, 0], "crank": 1, "rod": 3,
    ...     "line": {"point": [0, 0], "angle": 90}}})
    >>> doc.family, round(float(doc.mechanism.line_angle), 6)
    ('slidercrank', 1.570796)
    >>> parse_document({"format": "linkwright/1", "mechanism": {
    ...     "family": "fourbar", "crnak": 1}})
    Traceback (most recent call last):
    ...
    linkwright.io.documents.DocumentError: mechanism: unknown field 'crnak' (did you mean 'crank'?)
    """
    try:
        raw = _validate(mapping)
        mechanism = _build(raw["mechanism"])
    except DocumentError as exc:
        raise exc.with_source(source) from None
    except RecursionError:
        raise DocumentError("document", "is nested too deeply", source) from None
    return Document(
        title=raw.get("title"),
        units=raw.get("units"),
        family=raw["mechanism"]["family"],
        mechanism=mechanism,
        raw=raw,
    )


def _text(value: Any, path: str) -> str:
    if not isinstance(value, str):
        raise DocumentError(path, f"must be a string, got {_show(value)}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise DocumentError(path, "must be valid Unicode text (it has a lone surrogate)") from None
    return value


def _validate(mapping: Any) -> dict[str, Any]:
    doc = _table(mapping, "document", "a table")
    _check_keys(doc, _TOP_LEVEL, "document")
    if "format" not in doc:
        raise DocumentError("format", f'missing required field (expected "{FORMAT}")')
    if doc["format"] != FORMAT:
        raise DocumentError("format", f'expected "{FORMAT}", got {_show(doc["format"])}')
    out: dict[str, Any] = {"format": FORMAT}
    for key in ("title", "units"):
        if key in doc:
            out[key] = _text(doc[key], key)
    if "mechanism" not in doc:
        raise DocumentError("mechanism", "missing required table")
    out["mechanism"] = _validate_mechanism(doc["mechanism"])
    return out


def _validate_mechanism(value: Any) -> dict[str, Any]:
    mech = _table(value, "mechanism", "a table")
    _registered()
    known = tuple(FAMILY_SPECS)
    if "family" not in mech:
        raise DocumentError(
            "mechanism.family", f"missing required field (one of {', '.join(known)})"
        )
    family = mech["family"]
    if not isinstance(family, str):
        raise DocumentError("mechanism.family", f"must be a string, got {_show(family)}")
    if family not in FAMILY_SPECS:
        raise DocumentError("mechanism.family", _unknown("family", family, known))
    spec = FAMILY_SPECS[family]
    _check_keys(mech, ("family", *spec.names), "mechanism")
    out = _parse_fields(mech, spec.fields, "mechanism", {"family": family})
    lengths, size = _planar_dimensions(out, spec)
    least = WORKING_RANGE.min_share * size
    for name, other, why in spec.distinct:
        if math.dist(out[name], out[other]) <= least:
            close = "" if out[name] == out[other] else f"within {least:.3g}, "
            raise DocumentError(
                f"mechanism.{name}", f"coincides with mechanism.{other} ({close}{why})"
            )
    for path, length in lengths:
        if length < least:
            raise DocumentError(
                path,
                f"is {_show(length)}, under {WORKING_RANGE.min_share:g} of the linkage's size "
                f"{size:.6g} (outside linkwright's working range: float64 would leave it too "
                "few digits; make it longer or the rest smaller)",
            )
    for check in spec.checks:
        check(out)
    return out


_COORDINATE_KINDS = ("point", "uv", "line", "number")


def _planar_dimensions(
    mech: dict[str, Any], spec: FamilySpec
) -> tuple[list[tuple[str, float]], float]:
    """A planar linkage's lengths (with their paths) and its size: the largest length or
    coordinate magnitude, which the working range's ``min_share`` is a share of."""
    lengths: list[tuple[str, float]] = []
    magnitudes: list[float] = [0.0]

    def collect(fields: tuple[FieldSpec, ...], values: Mapping[str, Any], path: str) -> None:
        for f in fields:
            value = values[f.name]
            if f.kind == "length":
                lengths.append((f"{path}.{f.name}", value))
                magnitudes.append(value)
            elif f.kind in _COORDINATE_KINDS:
                magnitudes.extend(abs(x) for x in _numbers_in(value))
            elif f.kind == "joints" and values.get("space") == "plane":
                for i, joint in enumerate(value):
                    collect(JOINT_SPECS[joint["type"]], joint, f"{path}.joints[{i}]")

    collect(spec.fields, mech, "mechanism")
    return lengths, max(magnitudes)


def _numbers_in(value: Any) -> list[float]:
    if isinstance(value, Mapping):
        return [x for v in value.values() for x in _numbers_in(v)]
    if isinstance(value, list | tuple):
        return [x for v in value for x in _numbers_in(v)]
    return [value] if isinstance(value, float | int) and not isinstance(value, bool) else []


def _build(mech: Mapping[str, Any]) -> Mechanism:
    from linkwright.mechanisms import InvalidMechanism

    family = mech["family"]
    kwargs: dict[str, Any] = {}
    for f in FAMILY_SPECS[family].fields:
        kind = KINDS[f.kind]
        args = (mech[f.name], f.targets, mech) if kind.context else (mech[f.name], f.targets)
        kwargs.update(kind.to_kwargs(*args))
    cls = _mechanism_class(family)
    try:
        return cls(**kwargs)
    except InvalidMechanism as exc:
        # A composed linkage's structure (order, references, over-constraint) is judged by the
        # Linkage class alone; its error says which joint, which becomes the document path.
        index = getattr(exc, "index", None)
        if index is not None:
            raise DocumentError(f"mechanism.joints[{index}]", str(exc)) from None
        if family == "linkage":
            where = "traced" if getattr(exc, "field", None) == "traced" else "joints"
            raise DocumentError(f"mechanism.{where}", str(exc)) from None
        # For the other families the checks above should leave nothing for the constructor to
        # refuse; if they ever do, its message (which names the constructor field) still
        # reaches the user as a document error.
        raise DocumentError("mechanism", str(exc)) from None


def document_to_dict(doc: Document) -> dict[str, Any]:
    """The document as a plain, JSON/TOML-ready mapping (degrees), every default filled in."""
    return copy.deepcopy(doc.raw)


def mechanism_to_dict(mech: Mechanism, title: str | None = None) -> dict[str, Any]:
    """A document mapping for one mechanism object (its radians written back as degrees).

    Parameters
    ----------
    mech : a single (not batched) mechanism of a family in :data:`FAMILY_SPECS`.
    title : optional document title.

    Raises
    ------
    DocumentError
        For an unknown family or a batched mechanism.

    Examples
    --------
    >>> from linkwright.mechanisms import SliderCrank
    >>> import math
    >>> d = mechanism_to_dict(SliderCrank(A0=[0, 0], crank=1, rod=3, line_angle=math.pi / 6))
    >>> d["mechanism"]["line"]
    {'point': [0.0, 0.0], 'angle': 30.0}
    """
    family = getattr(mech, "family", None)
    _registered()
    if family not in FAMILY_SPECS:
        known = tuple(FAMILY_SPECS)
        raise DocumentError("mechanism.family", _unknown("family", str(family), known))
    body: dict[str, Any] = {"family": family}
    for f in FAMILY_SPECS[family].fields:
        try:
            body[f.name] = KINDS[f.kind].from_mech(mech, f.targets)
        except DocumentError as exc:
            # A list field's kind names the item at fault ("joints[2].r1"); keep that path.
            inner = exc.field if exc.field.startswith(f"{f.name}[") else f.name
            raise DocumentError(f"mechanism.{inner}", exc.problem) from None
    out: dict[str, Any] = {"format": FORMAT}
    if title is not None:
        out["title"] = title
    out["mechanism"] = body
    return out


# --------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------

_SUFFIXES = (".toml", ".json")


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _SUFFIXES:
        raise DocumentError(
            "document",
            f"unknown file type {path.suffix or '(none)'!r}: expected .toml or .json",
            str(path),
        )
    return suffix


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            # Python's json keeps the last of duplicate keys silently; a document with two
            # values for one field is ambiguous, so refuse it as TOML does.
            raise DocumentError("document", f"duplicate key {key!r}")
        out[key] = value
    return out


def _parse_text(text: str, suffix: str, source: str) -> Any:
    if suffix == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            # The parser's message already ends with "(at line L, column C)".
            raise DocumentError("document", f"invalid TOML: {exc}", source) from None
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        where = f"(at line {exc.lineno}, column {exc.colno})"
        raise DocumentError("document", f"invalid JSON: {exc.msg} {where}", source) from None
    except DocumentError as exc:
        raise exc.with_source(source) from None
    except RecursionError:
        raise DocumentError("document", "invalid JSON: nested too deeply", source) from None


def load_document(path: str | os.PathLike[str]) -> Document:
    """Read and validate a ``.toml`` or ``.json`` mechanism document.

    Raises
    ------
    DocumentError
        For an unknown extension, an unreadable or malformed file, or an invalid document.
    """
    path = Path(path)
    suffix = _suffix(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise DocumentError("document", f"cannot read: {exc.strerror or exc}", str(path)) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DocumentError(
            "document", f"not UTF-8 text (byte {exc.start} is {data[exc.start]:#04x})", str(path)
        ) from None
    return parse_document(_parse_text(text, suffix, str(path)), source=str(path))


def save_document(doc: Document | Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Write a document as TOML or JSON (by extension), atomically.

    A mapping is validated first, so only valid documents are ever written, in canonical form
    (every default filled in). The file is written to a temporary file in the same directory,
    flushed and fsynced, then renamed over ``path``: a reader never sees a half-written file and
    a crash leaves the old one intact.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not isinstance(doc, Document):
        doc = parse_document(doc)
    data = document_to_dict(doc)
    if suffix == ".toml":
        text = dumps_toml(data)
    else:
        text = json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    _atomic_write(path, text.encode("utf-8"))
    return path


def _atomic_write(path: Path, payload: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(payload)


# --------------------------------------------------------------------------------------------
# TOML writing: documents are a few scalars and one table of numbers, points and inline tables
# (and, for a composed linkage, an array of joint tables), so a small writer covers them and
# keeps points and (u, v) pairs on one line each.
# --------------------------------------------------------------------------------------------

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def _toml_string(s: str) -> str:
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write the non-finite number {value!r}")
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + items + " }" if items else "{}"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table_list(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, Mapping) for v in value)


def dumps_toml(data: Mapping[str, Any]) -> str:
    """TOML text for a document mapping: scalars first, then one ``[table]`` per mapping.

    Inside a table, a non-empty list of mappings is written last, as an array of tables
    (``[[table.key]]``, one per item): a linkage's joints read one joint per block.

    >>> print(dumps_toml({"format": "linkwright/1", "mechanism": {"A0": [0.0, 1.0]}}))
    format = "linkwright/1"
    <BLANKLINE>
    [mechanism]
    A0 = [0.0, 1.0]
    <BLANKLINE>
    >>> print(dumps_toml({"mechanism": {"family": "linkage", "joints": [{"name": "O"}]}}))
    [mechanism]
    family = "linkage"
    <BLANKLINE>
    [[mechanism.joints]]
    name = "O"
    <BLANKLINE>
    """
    lines = [
        f"{_toml_key(k)} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, Mapping)
    ]
    for key, table in data.items():
        if isinstance(table, Mapping):
            lines += ["", f"[{_toml_key(key)}]"]
            lines += [
                f"{_toml_key(k)} = {_toml_value(v)}"
                for k, v in table.items()
                if not _is_table_list(v)
            ]
            for k, items in table.items():
                if _is_table_list(items):
                    for item in items:
                        lines += ["", f"[[{_toml_key(key)}.{_toml_key(k)}]]"]
                        lines += [f"{_toml_key(n)} = {_toml_value(v)}" for n, v in item.items()]
    return "\n".join(lines).lstrip("\n") + "\n"


# --------------------------------------------------------------------------------------------
# Bundled examples
# --------------------------------------------------------------------------------------------


def _examples_dir() -> Any:
    return resources.files("linkwright").joinpath("examples")


def list_examples() -> list[str]:
    """Names of the bundled example documents (without extension), sorted.

    >>> "crank-rocker" in list_examples()
    True
    """
    return sorted(
        entry.name.removesuffix(".toml")
        for entry in _examples_dir().iterdir()
        if entry.name.endswith(".toml")
    )


def load_example(name: str) -> Document:
    """Load a bundled example by name (``"crank-rocker"`` or ``"crank-rocker.toml"``).

    Raises
    ------
    DocumentError
        For an unknown name.

    Examples
    --------
    >>> load_example("double-crank").family
    'fourbar'
    """
    stem = name.removesuffix(".toml")
    known = tuple(list_examples())
    if stem not in known:
        raise DocumentError("example", _unknown("example", stem, known))
    text = _examples_dir().joinpath(f"{stem}.toml").read_text(encoding="utf-8")
    source = f"example {stem}"
    return parse_document(_parse_text(text, ".toml", source), source=source)

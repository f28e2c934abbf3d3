"""The kinds of a document field: how each is checked, turned into constructor arguments and
read back from a mechanism (:data:`KINDS`), and the reading of a composed linkage's joints.

A document speaks degrees; the mechanism objects it builds speak radians. Each field of the
schema (:mod:`.document_schema`) names its kind; validation, defaults, construction and the
reverse conversion all go through the kind, so a new family needs no code here.
"""

from __future__ import annotations

import copy
import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from linkwright.io.document_schema import (
    JOINT_SPECS_IN,
    WORKING_RANGE,
    DocumentError,
    show,
    unknown_choice,
)
from linkwright.mechanisms.registry import Derived, FieldSpec
from linkwright.mechanisms.spherical import SPHERE_INPUTS
from linkwright.mechanisms.stephenson3_inputs import INPUTS

__all__ = [
    "KINDS",
    "Kind",
    "check_keys",
    "checked_table",
    "checked_text",
    "parse_fields",
    "tidy_number",
]


def _number(value: Any, path: str, what: str) -> float:
    """A finite float from an int or float (bool is not a number, however Python sees it)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise DocumentError(path, f"must be {what}, got {show(value)}")
    try:
        x = float(value)
    except OverflowError:
        raise DocumentError(path, f"must be a finite number, got {show(value)}") from None
    if not math.isfinite(x):
        raise DocumentError(path, f"must be a finite number, got {show(value)}")
    return x


def _sized(value: Any, path: str, what: str) -> float:
    """A number no larger than the working range allows (a length, coordinate or offset)."""
    x = _number(value, path, what)
    if problem := WORKING_RANGE.size_problem(x):
        raise DocumentError(path, problem)
    return x


def checked_table(value: Any, path: str, what: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise DocumentError(path, f"must be {what}, got {show(value)}")
    for key in value:
        if not isinstance(key, str):
            raise DocumentError(path, f"keys must be strings, got {show(key)}")
    return value


def check_keys(table: Mapping[str, Any], allowed: tuple[str, ...], path: str) -> None:
    for key in table:
        if key not in allowed:
            raise DocumentError(path, unknown_choice("field", key, allowed))


def _parse_point(value: Any, path: str) -> list[float]:
    what = "a point [x, y]"
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise DocumentError(path, f"must be {what}, got {show(value)}")
    return [_sized(c, f"{path}[{i}]", "a number") for i, c in enumerate(value)]


def _parse_length(value: Any, path: str) -> float:
    x = _sized(value, path, "a positive number")
    if x <= 0:
        raise DocumentError(path, f"must be a positive number, got {show(value)}")
    if x < WORKING_RANGE.min_length:
        raise DocumentError(
            path,
            f"must be at least {WORKING_RANGE.min_length:g}, got {show(value)} "
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
        raise DocumentError(path, f"must be 1 or -1, got {show(value)}")
    return int(x)


def _parse_pose(value: Any, path: str) -> int:
    x = _number(value, path, "a whole number from 0")
    if x != int(x) or not 0 <= x <= 7:
        raise DocumentError(
            path,
            f"must be a whole number from 0 to 7 (a triad's pose index), got {show(value)}",
        )
    return int(x)


def _parse_uv(value: Any, path: str) -> dict[str, float]:
    table = checked_table(value, path, "a table {u = .., v = ..}")
    check_keys(table, ("u", "v"), path)
    # Either coordinate may be left out: a point on the A→B line needs only u.
    return {k: _sized(table.get(k, 0.0), f"{path}.{k}", "a number") for k in ("u", "v")}


def _parse_line(value: Any, path: str) -> dict[str, Any]:
    table = checked_table(value, path, "a table {point = [x, y], angle = ..}")
    check_keys(table, ("point", "angle"), path)
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
            f"must be an arc strictly between 0 and 180 degrees, got {show(value)} "
            f"(a spherical link's central angle, at least {near:g} from 0 and from 180)",
        )
    return x


def _parse_offset_arc(value: Any, path: str) -> float:
    x = _number(value, path, "an arc in degrees")
    if not 0 <= x <= 180:
        raise DocumentError(
            path,
            f"must be an arc from 0 to 180 degrees, got {show(value)} "
            "(for a point on the other side, add 180 to its angle instead)",
        )
    return x


def _arc_angle(strict: bool) -> Callable[[Any, str], dict[str, float]]:
    """A table {arc, angle}: a rigid point's (``strict`` False: 0 ≤ arc ≤ 180) or a ground
    pivot's (``strict``: a link, 0 < arc < 180) place from a joint; angle defaults to 0."""
    parse_arc = _parse_arc if strict else _parse_offset_arc

    def parse(value: Any, path: str) -> dict[str, float]:
        table = checked_table(value, path, "a table {arc = .., angle = ..}")
        check_keys(table, ("arc", "angle"), path)
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
        raise DocumentError(path, f"must be {what}, got {show(value)}")
    axis = [_sized(c, f"{path}[{i}]", "a number") for i, c in enumerate(value)]
    if not any(axis):
        raise DocumentError(
            path, "must not be the zero vector [0, 0, 0] (its direction is the joint's axis)"
        )
    if max(map(abs, axis)) < WORKING_RANGE.min_length:
        raise DocumentError(
            path,
            f"must have a component of at least {WORKING_RANGE.min_length:g} in size, got "
            f"{show(value)} (scale the vector up: only its direction counts)",
        )
    return axis


def _parse_signed(value: Any, path: str) -> float:
    return _sized(value, path, "a number")


def _parse_ratio(value: Any, path: str) -> float:
    x = _number(value, path, "a nonzero number")
    if x == 0:
        raise DocumentError(
            path, f"must be a nonzero number, got {show(value)} (a ratio of 0 does not turn)"
        )
    if problem := WORKING_RANGE.ratio_problem(x):
        raise DocumentError(path, problem)
    return x


def _parse_joint_name(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value:
        raise DocumentError(path, f"must be a joint name (a non-empty string), got {show(value)}")
    return checked_text(value, path)


def _parse_names(value: Any, path: str) -> list[str]:
    if not isinstance(value, list | tuple):
        raise DocumentError(path, f"must be a list of joint names, got {show(value)}")
    if not value:
        raise DocumentError(path, "must name at least one joint")
    return [_parse_joint_name(v, f"{path}[{i}]") for i, v in enumerate(value)]


def _choice(choices: tuple[str, ...], refused: Mapping[str, str] | None = None) -> Kind:
    """A kind whose value is one of a few strings; ``refused`` explains known-but-unsupported."""
    refused = refused or {}
    quoted = [f'"{c}"' for c in choices]
    describe = (
        " or ".join(quoted)
        if len(quoted) <= 2
        else "one of " + ", ".join(quoted[:-1]) + " or " + quoted[-1]
    )

    def parse(value: Any, path: str) -> str:
        if not isinstance(value, str):
            raise DocumentError(path, f"must be {describe}, got {show(value)}")
        if value in refused:
            raise DocumentError(path, refused[value])
        if value not in choices:
            raise DocumentError(path, unknown_choice("value", value, choices))
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
    "stephenson_input": _choice(INPUTS),
    "spherical_input": _choice(SPHERE_INPUTS),
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


def parse_fields(
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
        raise DocumentError(path, f"must be a list of joint tables, got {show(value)}")
    joint_specs = JOINT_SPECS_IN[space]
    types = tuple(joint_specs)
    out: list[dict[str, Any]] = []
    for i, entry in enumerate(value):
        where = f"{path}[{i}]"
        table = checked_table(entry, where, "a joint table {name = .., type = .., ...}")
        if "name" not in table:
            raise DocumentError(f"{where}.name", "missing required field (a joint name)")
        name = _parse_joint_name(table["name"], f"{where}.name")
        if "type" not in table:
            raise DocumentError(
                f"{where}.type", f"missing required field (one of {', '.join(types)})"
            )
        kind = table["type"]
        if not isinstance(kind, str):
            raise DocumentError(f"{where}.type", f"must be a string, got {show(kind)}")
        if space == "sphere" and kind in ("rrp", "slider"):
            raise DocumentError(f"{where}.type", _NO_SPHERICAL_SLIDER)
        if kind not in joint_specs:
            raise DocumentError(f"{where}.type", unknown_choice("joint type", kind, types))
        specs = joint_specs[kind]
        if space == "sphere":
            for key in table:
                if (kind, key) in _SPHERE_HINTS:
                    raise DocumentError(f"{where}.{key}", _SPHERE_HINTS[(kind, key)])
        check_keys(table, ("name", "type", *(f.name for f in specs)), where)
        entry = parse_fields(table, specs, where, {"name": name, "type": kind})
        if space == "sphere" and kind == "crank" and entry["toward"] is None:
            entry["toward"] = _default_toward(entry, out, f"{where}.toward")
        out.append(entry)
    return out


def _default_toward(crank: dict[str, Any], before: list[dict[str, Any]], path: str) -> str:
    """The fixed joint a spherical crank's angle starts towards, when the document names none
    (the same rule as :class:`~linkwright.mechanisms.linkage.SphereCrankJoint`'s)."""
    for j in before:
        if j["type"] == "fixed" and j["name"] != crank["pivot"]:
            return str(j["name"])
    raise DocumentError(
        path,
        "missing, and no fixed joint other than the pivot is listed before this crank to "
        "default to (the crank's angle is measured from the great circle towards it)",
    )


def _build_joints(joints: list[dict[str, Any]], space: str) -> tuple[Any, ...]:
    from linkwright.mechanisms.joints import SPACES

    classes = SPACES[space]
    built = []
    for entry in joints:
        kwargs: dict[str, Any] = {"name": entry["name"]}
        for f in JOINT_SPECS_IN[space][entry["type"]]:
            kwargs.update(KINDS[f.kind].to_kwargs(entry[f.name], f.targets))
        built.append(classes[entry["type"]](**kwargs))
    return tuple(built)


def _joints_from_mech(joints: Any, space: str) -> list[dict[str, Any]]:
    out = []
    for i, joint in enumerate(joints):
        entry: dict[str, Any] = {"name": joint.name, "type": joint.type}
        for f in JOINT_SPECS_IN[space][joint.type]:
            try:
                entry[f.name] = KINDS[f.kind].from_mech(joint, f.targets)
            except DocumentError as exc:
                raise DocumentError(f"joints[{i}].{f.name}", exc.problem) from None
        out.append(entry)
    return out


def checked_text(value: Any, path: str) -> str:
    if not isinstance(value, str):
        raise DocumentError(path, f"must be a string, got {show(value)}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise DocumentError(path, "must be valid Unicode text (it has a lone surrogate)") from None
    return value

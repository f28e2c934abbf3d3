"""The schema of a mechanism document, derived from the family registry.

Every field a family accepts is declared once, in :mod:`linkwright.mechanisms.registry`, as a
*kind* (point, length, angle in degrees, sign, coupler point, slider line; on the sphere arc,
{arc, angle} offset, axis). :data:`FAMILY_SPECS` reads that table (a new family is a new row),
adding the rules across a family's fields that a document must keep. The composed family
``linkage`` is one row too: its joints' fields are the per-type tables :data:`JOINT_SPECS` and
:data:`SPHERE_JOINT_SPECS`. :data:`WORKING_RANGE` says where a document's numbers must lie, and
:class:`DocumentError` is what a document that breaks the schema raises.

How each kind is checked, built and written back is in :mod:`.document_kinds`; reading a whole
document is :func:`linkwright.io.documents.parse_document`, whose module describes the format.
"""

from __future__ import annotations

import difflib
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from linkwright.mechanisms import registry
from linkwright.mechanisms.registry import Derived, FieldSpec

__all__ = [
    "FAMILY_SPECS",
    "FORMAT",
    "JOINT_SPECS",
    "JOINT_SPECS_IN",
    "SPHERE_JOINT_SPECS",
    "TOP_LEVEL",
    "WORKING_RANGE",
    "DocumentError",
    "FamilySpec",
    "FieldSpec",
    "WorkingRange",
    "planar_dimensions",
    "refresh_family_specs",
    "show",
    "unknown_choice",
]

FORMAT = "linkwright/1"
TOP_LEVEL = ("format", "title", "units", "mechanism", "loads")
"""The keys a document may have at its top level."""


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
            f"must be at most {self.max_size:g} in size, got {show(value)} "
            "(outside linkwright's working range: use larger units)"
        )

    def angle_problem(self, value: float) -> str | None:
        """What is wrong with ``value`` as an angle in degrees, or None."""
        if abs(value) <= self.max_angle:
            return None
        return (
            f"must be at most {self.max_angle:g} degrees in size, got {show(value)} "
            "(outside linkwright's working range: reduce it by whole turns of 360)"
        )

    def ratio_problem(self, value: float) -> str | None:
        """What is wrong with a nonzero ``value`` as a ratio (a gear's, a hinge radii's)."""
        low = self.min_ratio
        if low <= abs(value) <= 1 / low:
            return None
        return (
            f"must be from {low:g} to {1 / low:g} in size, got {show(value)} "
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

    # Its public home stays the documents module: tracebacks and pickles name it from there.
    __module__ = "linkwright.io.documents"

    def __init__(self, field: str, problem: str, source: str | None = None) -> None:
        self.field = field
        self.problem = problem
        self.source = source
        prefix = f"{source}: " if source else ""
        super().__init__(f"{prefix}{field}: {problem}")

    def with_source(self, source: str | None) -> DocumentError:
        """The same error, attributed to ``source``."""
        return DocumentError(self.field, self.problem, source)


def show(value: Any) -> str:
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


def unknown_choice(noun: str, key: str, known: tuple[str, ...]) -> str:
    """ "unknown NOUN 'key'", with the closest known name where one is close."""
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    if close:
        return f"unknown {noun} {key!r} (did you mean {close[0]!r}?)"
    return f"unknown {noun} {key!r} (known: {', '.join(known)})"


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
            f"must not be a multiple of 180 degrees, got {show(m['alpha'])} "
            f"(the slider lines would be parallel; keep them {WORKING_RANGE.min_arc:g} "
            "degrees apart at least)",
        )
    _, size = planar_dimensions(m, FAMILY_SPECS["doubleslider"])
    if abs(m["p"] + m["q"]) <= WORKING_RANGE.min_share * size:
        raise DocumentError(
            "mechanism.q", "p + q must not be 0 (the sliders R and Q would coincide)"
        )


def _linkage_traced(m: dict[str, Any]) -> None:
    # A driven hinge places its far joint too, a triad its j2 and j3 (and a hinge): each a
    # joint to trace, as the joint spec classes say (mechanisms.joints.PLACES).
    from linkwright.mechanisms.joints import PLACES, SPACES

    kinds = SPACES.get(m.get("space", "plane"), SPACES["plane"])
    placed = tuple(
        j[key]
        for j in m["joints"]
        for key in ("name", *PLACES.get(kinds.get(j.get("type", "")), ()))  # type: ignore[arg-type]
        if key in j
    )
    for i, name in enumerate(m["traced"]):
        if name not in placed:
            raise DocumentError(f"mechanism.traced[{i}]", unknown_choice("joint", name, placed))
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


def refresh_family_specs() -> None:
    """Add the families registered since this module was imported (a family of one's own,
    declared in a file of its own, is read like a built-in one)."""
    if len(FAMILY_SPECS) != sum(1 for _ in registry.families()):
        FAMILY_SPECS.clear()
        FAMILY_SPECS.update(_family_specs())


def _triad_places(length: str) -> tuple[FieldSpec, ...]:
    """A triad's joints and binary links: J1 (its name), j2, j3, each J_k at r_k from p_k."""
    return (
        FieldSpec("j2", "joint"),
        FieldSpec("j3", "joint"),
        FieldSpec("p1", "joint"),
        FieldSpec("r1", length),
        FieldSpec("p2", "joint"),
        FieldSpec("r2", length),
        FieldSpec("p3", "joint"),
        FieldSpec("r3", length),
    )


def _hinge_triad_places(length: str) -> tuple[FieldSpec, ...]:
    """A triad driven at a hinge: J1 (its name), j2, j3 and the hinge, J1 and J2 held by r1 from
    p1 and r2 from p2, and the third leg's anchor p3."""
    return (
        FieldSpec("j2", "joint"),
        FieldSpec("j3", "joint"),
        FieldSpec("hinge", "joint"),
        FieldSpec("p1", "joint"),
        FieldSpec("r1", length),
        FieldSpec("p2", "joint"),
        FieldSpec("r2", length),
        FieldSpec("p3", "joint"),
    )


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
    # The input at a moving hinge (HingeJoint): places the hinge (name) and its far joint.
    "hinge": (
        FieldSpec("far", "joint"),
        FieldSpec("z", "joint"),
        FieldSpec("r", "length"),
        FieldSpec("y", "joint"),
        FieldSpec("a", "length"),
        FieldSpec("b", "length"),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("assembly", "sign", default=1),
    ),
    # A triad (TriadJoint): places the ternary link's joints name (J1), j2 and j3 at once.
    "triad": _triad_places("length")
    + (
        FieldSpec("side", "length"),
        FieldSpec("u", "number", default=0.0),
        FieldSpec("v", "number", default=0.0),
        FieldSpec("pose", "pose", default=0),
    ),
    # Triads driven at a hinge of their loop (mechanisms.hinge_joints): they place the hinge
    # too, the linkage's input in place of a crank.
    "hinge-triad": _hinge_triad_places("length")
    + (
        FieldSpec("a", "length"),
        FieldSpec("b", "length"),
        FieldSpec("side", "length"),
        FieldSpec("u", "number", default=0.0),
        FieldSpec("v", "number", default=0.0),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("pose", "pose", default=0),
    ),
    "turning-triad": _hinge_triad_places("length")
    + (
        FieldSpec("r3", "length"),
        FieldSpec("side", "length"),
        FieldSpec("hu", "number"),
        FieldSpec("hv", "number"),
        FieldSpec("arm", "length"),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("pose", "pose", default=0),
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
    "hinge": (
        FieldSpec("far", "joint"),
        FieldSpec("z", "joint"),
        FieldSpec("r", "arc"),
        FieldSpec("y", "joint"),
        FieldSpec("a", "arc"),
        FieldSpec("b", "arc"),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("assembly", "sign", default=1),
    ),
    "triad": _triad_places("arc")
    + (
        FieldSpec("side", "arc"),
        FieldSpec("arc", "offset_arc", default=0.0),
        FieldSpec("angle", "angle_deg", default=0.0),
        FieldSpec("pose", "pose", default=0),
    ),
    "hinge-triad": _hinge_triad_places("arc")
    + (
        FieldSpec("a", "arc"),
        FieldSpec("b", "arc"),
        FieldSpec("side", "arc"),
        FieldSpec("arc", "offset_arc", default=0.0),
        FieldSpec("angle", "angle_deg", default=0.0),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("pose", "pose", default=0),
    ),
    "turning-triad": _hinge_triad_places("arc")
    + (
        FieldSpec("r3", "arc"),
        FieldSpec("side", "arc"),
        FieldSpec("harc", "arc"),
        FieldSpec("hangle", "angle_deg"),
        FieldSpec("arm", "arc"),
        FieldSpec("phase", "angle_deg", default=0.0),
        FieldSpec("pose", "pose", default=0),
    ),
}
"""A spherical ``linkage`` joint's fields by its ``type`` (``space = "sphere"``): arcs and angles
in degrees, a fixed joint's ``at`` an axis [x, y, z]; the names are those of
:class:`~linkwright.mechanisms.linkage.FixedJoint`,
:class:`~linkwright.mechanisms.linkage.SphereCrankJoint`,
:class:`~linkwright.mechanisms.linkage.DyadJoint`,
:class:`~linkwright.mechanisms.linkage.SphereRigidJoint`,
:class:`~linkwright.mechanisms.linkage.HingeJoint` and
:class:`~linkwright.mechanisms.linkage.SphereTriadJoint`. There is no ``rrp``."""

# A linkage's ``space`` → its joints' field tables.
JOINT_SPECS_IN: dict[str, dict[str, tuple[FieldSpec, ...]]] = {
    "plane": JOINT_SPECS,
    "sphere": SPHERE_JOINT_SPECS,
}


_COORDINATE_KINDS = ("point", "uv", "line", "number")


def planar_dimensions(
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

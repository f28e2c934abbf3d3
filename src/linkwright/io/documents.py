"""Mechanism documents: TOML or JSON files that name a family and give its dimensions.

A document speaks degrees; the mechanism objects it builds speak radians. Every field a family
accepts is declared once, in the family registry (:mod:`linkwright.mechanisms.registry`, read
as :data:`FAMILY_SPECS` by :mod:`.document_schema`), as a *kind* (point, length, angle in
degrees, sign, coupler point, slider line; on the sphere arc, {arc, angle} offset, axis);
validation, defaults, construction and the reverse conversion all read that one table, so a
new family is a new row (:mod:`.document_kinds` says how each kind is read). The composed
family ``linkage`` is one row too: its ``joints`` field is a list of joint tables, each read
through the same kinds from the per-type table :data:`JOINT_SPECS`, or
:data:`SPHERE_JOINT_SPECS` when its ``space`` is ``"sphere"``. This module reads and validates
a whole document (:func:`parse_document`) and writes one back (:func:`mechanism_to_dict`); the
schema's names are re-exported here.

Spherical links are arcs (central angles) in degrees, each strictly between 0 and 180; a point
on a link is ``{arc, angle}``: its arc from the link's first joint (0 to 180) and its angle from
the link, right-handed about that joint's axis (paper 000's AC and μ = BAC). The three spherical
families are ``spherical-fourbar`` (paper 000's frame, crank, coupler, rocker and ``point``),
``spherical-sixbar`` (paper 000's Fig. 8: ``point`` = C, ``link5`` = CE, ``link6`` = E0E,
``ground`` = {B0E0, ε}, ``d`` = {CD, ECD}) and ``spherical-stephenson3`` (paper 001: a1 … a9,
sigma, input "AB" or "FG"). A spherical linkage's fixed joint is an axis ``at = [x, y, z]``,
any non-zero vector along it (the document keeps it as written; the joint is its direction).

Every family also takes an optional ``start`` (degrees): where the machine runs. A full turn of
the input starts there; an input that rocks over several arcs (a double rocker's two) runs on
the arc that holds it, so a document says which circuit it means (a synthesised linkage names
the one its answer lies on). Without it, a full turn starts at 0 and a rocking input runs on
its first arc (:func:`linkwright.mechanisms.running_circuit`).

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
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from linkwright.io.document_kinds import (
    KINDS,
    Kind,
    check_keys,
    checked_table,
    checked_text,
    parse_fields,
    tidy_number,
)
from linkwright.io.document_schema import (
    FAMILY_SPECS,
    FORMAT,
    JOINT_SPECS,
    SPHERE_JOINT_SPECS,
    TOP_LEVEL,
    WORKING_RANGE,
    DocumentError,
    FamilySpec,
    FieldSpec,
    WorkingRange,
    planar_dimensions,
    refresh_family_specs,
    show,
    unknown_choice,
)
from linkwright.mechanisms import registry

if TYPE_CHECKING:
    # Re-exported lazily (see __getattr__ at the end): the files module imports this one.
    from linkwright.io.files import list_examples, load_document, load_example, save_document
    from linkwright.io.toml_writer import dumps_toml
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
    "Kind",
    "WorkingRange",
    "document_to_dict",
    "dumps_toml",
    "list_examples",
    "load_document",
    "load_example",
    "mechanism_to_dict",
    "parse_document",
    "save_document",
    "tidy_number",
    "unknown_choice",
]


def _mechanism_class(family: str) -> type[Mechanism]:
    try:
        return registry.family(family).cls
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

    Examples
    --------
    A document is made by :func:`parse_document` (or read by :func:`load_document`); it holds
    the mechanism, ready for every verb, and the mapping with every default filled in:

    >>> doc = parse_document({"format": "linkwright/1", "mechanism": {
    ...     "family": "fourbar", "A0": [0, 0], "B0": [4, 0],
    ...     "crank": 1, "coupler": 3, "rocker": 3.5}})
    >>> doc.family, type(doc.mechanism).__name__, doc.raw["mechanism"]["assembly"]
    ('fourbar', 'FourBar', 1)
    >>> doc == parse_document(doc.raw)
    True

    A linkage that cannot assemble is still a valid document (the verbs say where it fails);
    a field that is not a linkage's is refused, naming the field:

    >>> far = parse_document({"format": "linkwright/1", "mechanism": {
    ...     "family": "fourbar", "A0": [0, 0], "B0": [9, 0],
    ...     "crank": 1, "coupler": 1, "rocker": 1}})
    >>> from linkwright import input_range
    >>> bool(input_range(far.mechanism).never)
    True
    >>> parse_document({"format": "linkwright/1", "mechanism": {
    ...     "family": "fourbar", "A0": [0, 0], "B0": [4, 0],
    ...     "crank": -1, "coupler": 3, "rocker": 3.5}})
    Traceback (most recent call last):
    ...
    linkwright.io.documents.DocumentError: mechanism.crank: must be a positive number, got -1
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
        _check_forces(raw, mechanism)
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


def _validate(mapping: Any) -> dict[str, Any]:
    doc = checked_table(mapping, "document", "a table")
    check_keys(doc, TOP_LEVEL, "document")
    if "format" not in doc:
        raise DocumentError("format", f'missing required field (expected "{FORMAT}")')
    if doc["format"] != FORMAT:
        raise DocumentError("format", f'expected "{FORMAT}", got {show(doc["format"])}')
    out: dict[str, Any] = {"format": FORMAT}
    for key in ("title", "units"):
        if key in doc:
            out[key] = checked_text(doc[key], key)
    if "mechanism" not in doc:
        raise DocumentError("mechanism", "missing required table")
    out["mechanism"] = _validate_mechanism(doc["mechanism"])
    if "loads" in doc:  # checked against the built mechanism, by _check_forces
        out["loads"] = doc["loads"]
    return out


def _check_forces(raw: Mapping[str, Any], mechanism: Mechanism) -> None:
    """The ``[mechanism.mass]`` and ``[loads]`` tables, checked by the forces package."""
    from linkwright.dynamics.model import ForcesInputError, check_forces_input

    try:
        check_forces_input(mechanism, raw["mechanism"].get("mass"), raw.get("loads"))
    except ForcesInputError as exc:
        raise DocumentError(exc.field, exc.problem) from None


def _validate_mechanism(value: Any) -> dict[str, Any]:
    mech = checked_table(value, "mechanism", "a table")
    refresh_family_specs()
    known = tuple(FAMILY_SPECS)
    if "family" not in mech:
        raise DocumentError(
            "mechanism.family", f"missing required field (one of {', '.join(known)})"
        )
    family = mech["family"]
    if not isinstance(family, str):
        raise DocumentError("mechanism.family", f"must be a string, got {show(family)}")
    if family not in FAMILY_SPECS:
        raise DocumentError("mechanism.family", unknown_choice("family", family, known))
    spec = FAMILY_SPECS[family]
    check_keys(mech, ("family", *spec.names, "start", "mass"), "mechanism")
    out = parse_fields(mech, spec.fields, "mechanism", {"family": family})
    if "start" in mech:  # every family's: where the machine runs (Mechanism.start)
        out["start"] = KINDS["angle_deg"].parse(mech["start"], "mechanism.start")
    if "mass" in mech:  # checked against the built mechanism, by _check_forces
        out["mass"] = mech["mass"]
    lengths, size = planar_dimensions(out, spec)
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
                f"is {show(length)}, under {WORKING_RANGE.min_share:g} of the linkage's size "
                f"{size:.6g} (outside linkwright's working range: float64 would leave it too "
                "few digits; make it longer or the rest smaller)",
            )
    for check in spec.checks:
        check(out)
    return out


def _build(mech: Mapping[str, Any]) -> Mechanism:
    from linkwright.mechanisms import InvalidMechanism

    family = mech["family"]
    kwargs: dict[str, Any] = {}
    for f in FAMILY_SPECS[family].fields:
        kind = KINDS[f.kind]
        args = (mech[f.name], f.targets, mech) if kind.context else (mech[f.name], f.targets)
        kwargs.update(kind.to_kwargs(*args))
    if "start" in mech:
        kwargs.update(KINDS["angle_deg"].to_kwargs(mech["start"], ("start",)))
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
    refresh_family_specs()
    if family not in FAMILY_SPECS:
        known = tuple(FAMILY_SPECS)
        raise DocumentError("mechanism.family", unknown_choice("family", str(family), known))
    body: dict[str, Any] = {"family": family}
    for f in FAMILY_SPECS[family].fields:
        try:
            body[f.name] = KINDS[f.kind].from_mech(mech, f.targets)
        except DocumentError as exc:
            # A list field's kind names the item at fault ("joints[2].r1"); keep that path.
            inner = exc.field if exc.field.startswith(f"{f.name}[") else f.name
            raise DocumentError(f"mechanism.{inner}", exc.problem) from None
    if mech.start is not None:
        body["start"] = KINDS["angle_deg"].from_mech(mech, ("start",))
    out: dict[str, Any] = {"format": FORMAT}
    if title is not None:
        out["title"] = title
    out["mechanism"] = body
    return out


# Moved to their own modules; these names stay importable from here for older callers.
_MOVED = {
    "dumps_toml": "linkwright.io.toml_writer",
    "list_examples": "linkwright.io.files",
    "load_document": "linkwright.io.files",
    "load_example": "linkwright.io.files",
    "save_document": "linkwright.io.files",
}


def __getattr__(name: str) -> Any:
    if name in _MOVED:
        import importlib

        return getattr(importlib.import_module(_MOVED[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

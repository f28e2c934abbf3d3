"""The JSON schema of a mechanism document, for the workbench's OpenAPI description.

Routes take a document as a plain mapping and leave every judgement about it to
:func:`~linkwright.io.parse_document` (whose messages name the field): the type
:data:`DocumentBody` validates nothing more than "a JSON object". What it adds is a schema, built
from the same table the parser reads (:data:`~linkwright.io.FAMILY_SPECS`, the joint tables and
the working range), so that ``/openapi.json`` says what a document holds, family by family, and
a schema-driven fuzzer generates documents that reach the mechanisms instead of stopping at the
first missing field. The schema cannot say everything (a composed linkage's references, pivots
that must differ, a linkage that cannot assemble): those are answered 422 like any other.

>>> schema = document_schema()
>>> schema["required"], schema["properties"]["format"]
(['format', 'mechanism'], {'const': 'linkwright/1'})
>>> fourbar = next(s for s in schema["properties"]["mechanism"]["anyOf"]
...                if s["properties"]["family"] == {"const": "fourbar"})
>>> fourbar["required"]
['family', 'A0', 'B0', 'crank', 'coupler', 'rocker']
"""

from __future__ import annotations

import copy
from functools import cache
from typing import Annotated, Any

from pydantic import WithJsonSchema

from linkwright.io import FAMILY_SPECS, document_to_dict, load_example
from linkwright.io.documents import JOINT_SPECS, SPHERE_JOINT_SPECS, WORKING_RANGE, FieldSpec
from linkwright.mechanisms.spherical import SPHERE_INPUTS
from linkwright.mechanisms.stephenson3_inputs import INPUTS
from linkwright.server.limits import DOCUMENT_LIST, TEXT, TITLE

__all__ = ["DocumentBody", "document_examples", "document_schema", "examples"]

FORMAT = "linkwright/1"


def _number(low: float | None = None, high: float | None = None) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "number"}
    if low is not None:
        out["minimum"] = low
    if high is not None:
        out["maximum"] = high
    return out


def _kinds() -> dict[str, dict[str, Any]]:
    """The schema of each field kind of the document parser, within its working range."""
    size = WORKING_RANGE.max_size
    coordinate = _number(-size, size)
    angle = _number(-WORKING_RANGE.max_angle, WORKING_RANGE.max_angle)
    arc = _number(WORKING_RANGE.min_arc, 180 - WORKING_RANGE.min_arc)
    offset_arc = _number(0, 180)
    low = WORKING_RANGE.min_ratio
    joint = {"type": "string", "minLength": 1, "maxLength": TEXT.value}

    def pair(n: int) -> dict[str, Any]:
        return {"type": "array", "items": coordinate, "minItems": n, "maxItems": n}

    def table(properties: dict[str, Any], required: list[str]) -> dict[str, Any]:
        return {
            "type": "object",
            "properties": properties,
            "required": required,
            "additionalProperties": False,
        }

    return {
        "point": pair(2),
        "axis": pair(3),
        "length": _number(WORKING_RANGE.min_length, size),
        "number": coordinate,
        "angle_deg": angle,
        "sign": {"enum": [1, -1]},
        "pose": {"type": "integer", "minimum": 0, "maximum": 7},
        "ratio": {"anyOf": [_number(low, 1 / low), _number(-1 / low, -low)]},
        "uv": table({"u": coordinate, "v": coordinate}, []),
        "line": table({"point": pair(2), "angle": angle}, ["point", "angle"]),
        "arc": arc,
        "offset_arc": offset_arc,
        "arc_point": table({"arc": offset_arc, "angle": angle}, ["arc"]),
        "arc_pivot": table({"arc": arc, "angle": angle}, ["arc"]),
        "stephenson_input": {"enum": list(INPUTS)},
        "spherical_input": {"enum": list(SPHERE_INPUTS)},
        "space": {"enum": ["plane", "sphere"]},
        "joint": joint,
        "names": {
            "type": "array",
            "items": joint,
            "minItems": 1,
            "maxItems": DOCUMENT_LIST.value,
        },
    }


def _fields(
    specs: tuple[FieldSpec, ...], kinds: dict[str, Any], joints: dict[str, Any] | None
) -> tuple[dict[str, Any], list[str]]:
    properties: dict[str, Any] = {}
    required: list[str] = []
    for spec in specs:
        if spec.kind == "joints":
            properties[spec.name] = joints
        else:
            properties[spec.name] = copy.deepcopy(kinds[spec.kind])
        if spec.default is None:
            required.append(spec.name)
    return properties, required


@cache
def _schema() -> dict[str, Any]:
    kinds = _kinds()
    joint_tables = []
    for table in (JOINT_SPECS, SPHERE_JOINT_SPECS):
        for kind, specs in table.items():
            properties, required = _fields(specs, kinds, None)
            joint_tables.append(
                {
                    "type": "object",
                    "properties": {
                        "name": kinds["joint"],
                        "type": {"const": kind},
                        **properties,
                    },
                    "required": ["name", "type", *required],
                    "additionalProperties": False,
                }
            )
    joints = {
        "type": "array",
        "items": {"anyOf": joint_tables},
        "minItems": 1,
        "maxItems": DOCUMENT_LIST.value,
    }
    families = []
    for family, spec in FAMILY_SPECS.items():
        properties, required = _fields(spec.fields, kinds, joints)
        families.append(
            {
                "type": "object",
                # start: every family's, where the machine runs (degrees).
                "properties": {
                    "family": {"const": family},
                    **properties,
                    "start": copy.deepcopy(kinds["angle_deg"]),
                },
                "required": ["family", *required],
                "additionalProperties": False,
            }
        )
    return {
        "type": "object",
        "title": "Document",
        "description": (
            "A linkwright/1 mechanism document (the JSON form of the TOML files; see docs/cli.md)."
            " Angles are degrees. What the schema cannot say (references between joints, pivots"
            " that must differ) is checked when the document is read, and answered 422."
        ),
        "properties": {
            "format": {"const": FORMAT},
            "title": {"type": "string", "maxLength": TITLE.value},
            "units": {"type": "string", "maxLength": TEXT.value},
            "mechanism": {"anyOf": families},
        },
        "required": ["format", "mechanism"],
        "additionalProperties": False,
    }


def document_schema() -> dict[str, Any]:
    """The JSON schema of a document (a fresh copy: callers may change it)."""
    return copy.deepcopy(_schema())


DocumentBody = Annotated[dict[str, Any], WithJsonSchema(document_schema())]
"""A request's document: any JSON object to the validator (the document parser judges it),
described by :func:`document_schema` in the OpenAPI schema."""


EXAMPLE_DOCUMENTS = ("crank-rocker", "paper000-fig6-crank-rocker", "jansen-leg")
"""The bundled examples the schema shows as request examples: a planar four-bar, a spherical
one and a composed linkage."""


@cache
def _examples() -> tuple[dict[str, Any], ...]:
    return tuple(document_to_dict(load_example(name)) for name in EXAMPLE_DOCUMENTS)


def document_examples() -> list[dict[str, Any]]:
    """The example documents of :data:`EXAMPLE_DOCUMENTS` (fresh copies)."""
    return copy.deepcopy(list(_examples()))


def examples(*bodies: dict[str, Any]) -> dict[str, Any]:
    """A model's ``json_schema_extra``: request examples for the OpenAPI page (and the fuzzer's
    first cases)."""
    return {"examples": list(bodies)}

"""What a scene request reads and writes: the family and example menus, a client's document
parsed (and held to the request limits), its editable fields by dotted path, and answers as
JSON (NumPy arrays written straight, NaN as ``null``).

The scene (:mod:`linkwright.server.scene`), its assembly modes
(:mod:`linkwright.server.scene_modes`) and the drag (:mod:`linkwright.server.scene_drag`) all
read documents through here.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import orjson

from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    document_to_dict,
    list_examples,
    load_example,
    parse_document,
)
from linkwright.io.documents import JOINT_SPECS, SPHERE_JOINT_SPECS
from linkwright.mechanisms import registry
from linkwright.mechanisms.spherical import SPHERE_INPUTS
from linkwright.mechanisms.stephenson3_inputs import INPUTS
from linkwright.server.limits import check_document

__all__ = [
    "FAMILY_EXAMPLES",
    "document_space",
    "examples",
    "families",
    "family_document",
    "family_name",
    "fields",
    "get_path",
    "json_number",
    "json_rows",
    "read_document",
    "set_path",
    "sign_paths",
    "to_json",
]

FAMILY_EXAMPLES = {f.name: f.example for f in registry.families()}
"""The bundled example each family opens with (the registry's)."""

# Field kinds the page edits as numbers, and how it labels them.
_SCALAR_KINDS = {
    "length": ("length", ""),
    "arc": ("angle", "°"),
    "offset_arc": ("angle", "°"),
    "angle_deg": ("angle", "°"),
    "number": ("length", ""),
    "ratio": ("ratio", ""),
}


# --------------------------------------------------------------------------------------------
# Families and examples
# --------------------------------------------------------------------------------------------


def family_name(family: str, space: str) -> str:
    """The family's name as the page shows it (the spherical linkage says so)."""
    name = registry.family(family).display
    return f"{name} (sphere)" if family == "linkage" and space == "sphere" else name


def families() -> list[dict[str, Any]]:
    """Every family: its name, group, space and the example it opens with (the registry)."""
    return [
        {
            "family": f.name,
            "name": f.display,
            "group": f.group,
            "space": "sphere" if f.space == "sphere" else "plane",
            "example": f.example,
        }
        for f in registry.families()
    ]


def family_document(family: str) -> dict[str, Any]:
    """The document a family opens with (its bundled example)."""
    if family not in FAMILY_EXAMPLES:
        raise LookupError(f"family: no family named {family!r}")
    return document_to_dict(load_example(FAMILY_EXAMPLES[family]))


_EXAMPLES: list[dict[str, Any]] | None = None


def examples() -> list[dict[str, Any]]:
    """The bundled examples: name, title, family and space (read once)."""
    global _EXAMPLES
    if _EXAMPLES is None:
        rows = []
        for name in list_examples():
            doc = load_example(name)
            rows.append(
                {
                    "name": name,
                    "title": doc.title or name,
                    "family": doc.family,
                    "space": doc.mechanism.space,
                }
            )
        _EXAMPLES = rows
    return copy.deepcopy(_EXAMPLES)


# --------------------------------------------------------------------------------------------
# Fields: every editable scalar of a document, by dotted path
# --------------------------------------------------------------------------------------------


def get_path(tree: Any, path: str) -> Any:
    """The value at a dotted ``path`` (list items by index) in a document's dictionary."""
    for key in path.split("."):
        tree = tree[int(key)] if isinstance(tree, list) else tree[key]
    return tree


def set_path(tree: Any, path: str, value: Any) -> None:
    """Set the value at a dotted ``path`` (list items by index) in a document's dictionary."""
    keys = path.split(".")
    for key in keys[:-1]:
        tree = tree[int(key)] if isinstance(tree, list) else tree[key]
    last = keys[-1]
    if isinstance(tree, list):
        tree[int(last)] = value
    else:
        tree[last] = value


def _field(
    path: str, label: str, value: Any, kind: str, unit: str = "", **more: Any
) -> dict[str, Any]:
    return {"path": path, "label": label, "value": value, "kind": kind, "unit": unit, **more}


def _spec_fields(prefix: str, label: str, kind: str, value: Any) -> list[dict[str, Any]]:
    """The page's fields for one document field of kind ``kind``."""
    if kind in _SCALAR_KINDS:
        what, unit = _SCALAR_KINDS[kind]
        return [_field(prefix, label, value, what, unit)]
    if kind == "sign":
        return [_field(prefix, label, value, "sign", choices=[1, -1])]
    if kind in ("point", "axis"):
        return [
            _field(f"{prefix}.{i}", f"{label} {axis}", v, "coordinate")
            for i, (axis, v) in enumerate(zip("xyz", value, strict=False))
        ]
    if kind == "uv":
        return [_field(f"{prefix}.{k}", f"{label} {k}", value[k], "coordinate") for k in "uv"]
    if kind in ("arc_point", "arc_pivot"):
        return [
            _field(f"{prefix}.arc", f"{label} arc", value["arc"], "angle", "°"),
            _field(f"{prefix}.angle", f"{label} angle", value["angle"], "angle", "°"),
        ]
    if kind == "line":
        return [
            *_spec_fields(f"{prefix}.point", f"{label} point", "point", value["point"]),
            _field(f"{prefix}.angle", f"{label} angle", value["angle"], "angle", "°"),
        ]
    if kind == "stephenson_input":
        return [_field(prefix, label, value, "choice", choices=list(INPUTS))]
    if kind == "spherical_input":
        return [_field(prefix, label, value, "choice", choices=list(SPHERE_INPUTS))]
    return []  # names, joint references, the space: not numbers to edit


def fields(raw: dict[str, Any]) -> list[dict[str, Any]]:
    """Every editable value of a validated document, in document order.

    >>> doc = load_example("crank-rocker")
    >>> [f["path"] for f in fields(document_to_dict(doc))][:4]
    ['mechanism.A0.0', 'mechanism.A0.1', 'mechanism.B0.0', 'mechanism.B0.1']
    """
    mech = raw["mechanism"]
    family = mech["family"]
    out: list[dict[str, Any]] = []
    for spec in FAMILY_SPECS[family].fields:
        if spec.name not in mech:
            continue
        if spec.kind == "joints":
            specs = SPHERE_JOINT_SPECS if mech.get("space") == "sphere" else JOINT_SPECS
            for i, joint in enumerate(mech["joints"]):
                for js in specs[joint["type"]]:
                    if js.name in joint:
                        out += _spec_fields(
                            f"mechanism.joints.{i}.{js.name}",
                            f"{joint['name']} {js.name}",
                            js.kind,
                            joint[js.name],
                        )
            continue
        out += _spec_fields(f"mechanism.{spec.name}", spec.name, spec.kind, mech[spec.name])
    return out


def sign_paths(raw: dict[str, Any]) -> list[str]:
    """The paths of a document's sign fields (those that choose an assembly mode)."""
    return [f["path"] for f in fields(raw) if f["kind"] == "sign"]


# --------------------------------------------------------------------------------------------
# JSON helpers
# --------------------------------------------------------------------------------------------


def json_rows(a: np.ndarray, digits: int = 12) -> np.ndarray:
    """An array rounded to keep the answer small; :func:`to_json` writes NaN and ±inf as null."""
    return np.ascontiguousarray(np.round(np.asarray(a, dtype=float), digits))


def to_json(value: Any) -> bytes:
    """A scene (or any answer holding NumPy arrays) as JSON bytes, NaN and ±inf as ``null``.

    orjson writes a scene's ~10^4 numbers straight from its arrays in well under a millisecond;
    lists of Python floats through ``json`` take ten times as long (the redraw's latency budget
    is 50 ms).

    >>> to_json({"x": np.array([1.5, np.nan])})
    b'{"x":[1.5,null]}'
    """
    return orjson.dumps(value, option=orjson.OPT_SERIALIZE_NUMPY)


def json_number(x: float) -> float | None:
    """``x`` as a float, or None where it is not finite (JSON has no NaN)."""
    x = float(x)
    return x if math.isfinite(x) else None


def document_space(doc: Document) -> str:
    """The document's space, read from the document: a mechanism without a construction plan
    (a spherical Stephenson III driven at FG) cannot tell its own."""
    if registry.family(doc.family).space == "sphere":
        return "sphere"
    return str(doc.raw["mechanism"].get("space", "plane"))


def read_document(document: Any, *, client: bool = False) -> Document:
    """The document parsed; a ``client``'s document (not one made here from a parsed one) is
    first held to the request limits."""
    if not isinstance(document, dict):
        raise DocumentError("document", f"must be a JSON object, got {type(document).__name__}")
    if client:
        check_document(document)
    return parse_document(document, source="document")

"""The family registry: every family declared once, and everything else derived from it.

A family is a mechanism class (a :class:`~linkwright.mechanisms.Mechanism` that builds a plan)
and one :class:`Family` record registered next to it: its document fields (each with a kind,
which says how a document writes it, its unit and its working range, and the class attributes
it fills), its display name and group, whether it lives in the plane or on the sphere, its
joints with what they are (the source paper's letters where there is one), and the bundled
example it opens with. The document schema and parser (:mod:`linkwright.io.documents`), the
workbench's family list and JSON schema, the plot titles and the page's grouping all read this
table; nothing else lists the families.

Adding a family is one file: a module that defines the class and calls :func:`register`
(docs/families.md walks through one). The built-in families register when
:mod:`linkwright.mechanisms` is imported.

Examples
--------
>>> from linkwright.mechanisms import registry
>>> four = registry.family("fourbar")
>>> four.display, four.group, four.space, four.example
('Four-bar', 'Four-bars', 'plane', 'crank-rocker')
>>> [f.name for f in four.fields][:5]
['A0', 'B0', 'crank', 'coupler', 'rocker']
>>> registry.family("four-bar")
Traceback (most recent call last):
...
LookupError: family: no family named 'four-bar' (did you mean 'fourbar'?)
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

__all__ = [
    "GROUPS",
    "KIND_UNITS",
    "Derived",
    "Family",
    "FieldSpec",
    "families",
    "family",
    "family_of",
    "register",
]


@dataclass(frozen=True)
class Derived:
    """A default computed from the fields validated before it (in table order).

    ``describe`` says what it is (for the schema's readers); ``compute`` maps the fields parsed
    so far (document values) to the default's document value.
    """

    describe: str
    compute: Callable[[dict[str, Any]], Any]


@dataclass(frozen=True)
class FieldSpec:
    """A family's document field: its name, its kind, the class attributes it fills and its
    default.

    ``kind`` names how a document writes it (:data:`KIND_UNITS` lists the kinds with their
    units; :mod:`linkwright.io.documents` reads and writes each one and holds its working
    range). ``attrs`` defaults to ``(name,)``; ``default`` of ``None`` makes the field required,
    a :class:`Derived` computes it from the fields before it.
    """

    name: str
    kind: str
    attrs: tuple[str, ...] = ()
    default: Any = None

    @property
    def targets(self) -> tuple[str, ...]:
        return self.attrs or (self.name,)

    @property
    def unit(self) -> str:
        """What the document writes this field in."""
        return KIND_UNITS.get(self.kind, "")


KIND_UNITS: dict[str, str] = {
    "point": "the document's length unit",
    "length": "the document's length unit",
    "number": "the document's length unit",
    "uv": "the document's length unit",
    "line": "the document's length unit, degrees",
    "angle_deg": "degrees",
    "arc": "degrees",
    "offset_arc": "degrees",
    "arc_point": "degrees",
    "arc_pivot": "degrees",
    "axis": "a direction",
    "ratio": "turns per input turn",
    "sign": "±1",
    "pose": "an index",
}
"""The unit of each field kind, as documents write it (the library itself speaks radians)."""


@dataclass(frozen=True)
class Family:
    """One family, declared once.

    Attributes
    ----------
    name : the document's ``family`` value.
    cls : the mechanism class (its ``family`` class attribute is ``name``).
    display : the name people read ("Four-bar").
    group : the heading it is listed under ("Four-bars", "Six-bars", "Spherical", ...).
    space : ``"plane"`` or ``"sphere"`` (a composed linkage may be either: ``"either"``).
    example : the bundled example it opens with.
    fields : its document fields, in document order.
    distinct : (field, other field, why) for points that may not coincide.
    joints : each joint and what it is (the source paper's letter where there is one).
    source : where the family comes from (a seed paper, a textbook).
    analysis : what :func:`linkwright.analysis.analyze` reports beyond what every plan gives
        (circuits, limits, transmission angles of its dyads, traced paths): paper 003's
        closed-form four-bar analysis (``"fourbar"``, ``"slidercrank"``,
        ``"spherical-fourbar"``), the geared five-bar's locking (``"locking"``), the double
        slider's ellipse (``"ellipse"``), or nothing more (``""``).
    """

    name: str
    cls: type
    display: str
    group: str
    space: str
    example: str
    fields: tuple[FieldSpec, ...]
    distinct: tuple[tuple[str, str, str], ...] = ()
    joints: tuple[tuple[str, str], ...] = ()
    source: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    analysis: str = ""

    @property
    def names(self) -> tuple[str, ...]:
        """The document field names, in order."""
        return tuple(f.name for f in self.fields)


_FAMILIES: dict[str, Family] = {}


def register(entry: Family) -> Family:
    """Add a family to the registry (once; its name must be its class's ``family``).

    Returns the entry, so that a module can keep it under a name of its own.
    """
    if getattr(entry.cls, "family", None) != entry.name:
        raise ValueError(
            f"family {entry.name!r}: its class {entry.cls.__name__} says family = "
            f"{getattr(entry.cls, 'family', None)!r}"
        )
    if entry.name in _FAMILIES and _FAMILIES[entry.name] is not entry:
        raise ValueError(f"family {entry.name!r} is registered twice")
    if entry.space not in ("plane", "sphere", "either"):
        raise ValueError(f"family {entry.name!r}: space must be plane, sphere or either")
    _FAMILIES[entry.name] = entry
    return entry


GROUPS = (
    "Four-bars",
    "Slider linkages",
    "Geared linkages",
    "Six-bars",
    "Free linkages",
    "Spherical",
)
"""The order families are listed in, by group (a new group comes after these)."""


def families() -> Iterator[Family]:
    """Every registered family, by group (:data:`GROUPS`), then in the order registered."""
    rank = {g: i for i, g in enumerate(GROUPS)}
    return iter(sorted(_FAMILIES.values(), key=lambda f: rank.get(f.group, len(GROUPS))))


def family(name: str) -> Family:
    """The family called ``name``; a :class:`LookupError` naming the nearest one if none is."""
    try:
        return _FAMILIES[name]
    except (KeyError, TypeError):
        near = difflib.get_close_matches(str(name), list(_FAMILIES), n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise LookupError(f"family: no family named {name!r}{hint}") from None


def family_of(mechanism: object) -> Family:
    """The registry entry of a mechanism (by its class's ``family``)."""
    return family(getattr(mechanism, "family", type(mechanism).__name__))

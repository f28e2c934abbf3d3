"""Mechanism documents: what a valid document builds (defaults, degrees outside and radians
inside, canonical form), and a validation message naming the field for every way one is wrong.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from documents_helpers import (
    FOURBAR,
    SLIDER,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)

from linkwright.io import (
    DocumentError,
    document_to_dict,
    parse_document,
)
from linkwright.mechanisms import FourBar, SliderCrank

# ---------------------------------------------------------------------------------------------
# Valid documents
# ---------------------------------------------------------------------------------------------


def test_fourbar_document_builds_the_mechanism():
    doc = parse_document(FOURBAR)
    m = doc.mechanism
    assert isinstance(m, FourBar)
    assert (doc.title, doc.units, doc.family) == ("test four-bar", "mm", "fourbar")
    np.testing.assert_array_equal(m.A0, [0, 0])
    np.testing.assert_array_equal(m.B0, [4, 0])
    assert (float(m.crank), float(m.coupler), float(m.rocker)) == (1.0, 5.0, 3.5)
    assert (float(m.u), float(m.v), float(m.assembly)) == (2.0, 1.0, -1.0)


def test_slidercrank_angles_are_degrees_in_the_document_and_radians_inside():
    doc = parse_document(SLIDER)
    m = doc.mechanism
    assert isinstance(m, SliderCrank)
    assert float(m.line_angle) == pytest.approx(math.pi / 6, abs=1e-15)
    np.testing.assert_array_equal(m.line_point, [0, -0.5])


def test_defaults_fill_in_point_and_assembly():
    doc = parse_document(SLIDER)
    assert doc.raw["mechanism"]["point"] == {"u": 0.0, "v": 0.0}
    assert doc.raw["mechanism"]["assembly"] == 1
    assert (float(doc.mechanism.u), float(doc.mechanism.v)) == (0.0, 0.0)
    assert float(doc.mechanism.assembly) == 1.0
    assert doc.title is None and doc.units is None


def test_point_coordinates_default_to_zero_one_at_a_time():
    doc = parse_document(with_change(FOURBAR, "mechanism.point", {"u": 1.5}))
    assert doc.raw["mechanism"]["point"] == {"u": 1.5, "v": 0.0}


def test_float_assembly_equal_to_one_is_accepted():
    assert (
        parse_document(with_change(FOURBAR, "mechanism.assembly", -1.0)).raw["mechanism"][
            "assembly"
        ]
        == -1
    )


def test_raw_is_canonical_and_documents_compare_by_it():
    a = parse_document(FOURBAR)
    b = parse_document(json.loads(json.dumps(FOURBAR)))
    assert a == b
    assert a.raw["mechanism"]["crank"] == 1.0 and isinstance(a.raw["mechanism"]["crank"], float)
    assert a != parse_document(with_change(FOURBAR, "mechanism.crank", 1.5))


def test_document_to_dict_is_a_copy():
    doc = parse_document(FOURBAR)
    d = document_to_dict(doc)
    d["mechanism"]["crank"] = 99.0
    assert doc.raw["mechanism"]["crank"] == 1.0


# ---------------------------------------------------------------------------------------------
# Every validation message names its field
# ---------------------------------------------------------------------------------------------

FOURBAR_ERRORS = [
    ("mechanism.crank", -1, "mechanism.crank: must be a positive number, got -1"),
    ("mechanism.crank", 0, "mechanism.crank: must be a positive number, got 0"),
    ("mechanism.coupler", 0.0, "mechanism.coupler: must be a positive number, got 0.0"),
    ("mechanism.rocker", "3", 'mechanism.rocker: must be a positive number, got "3"'),
    ("mechanism.crank", True, "mechanism.crank: must be a positive number, got true"),
    ("mechanism.crank", math.nan, "mechanism.crank: must be a finite number, got nan"),
    ("mechanism.crank", math.inf, "mechanism.crank: must be a finite number, got inf"),
    ("mechanism.A0", [0], "mechanism.A0: must be a point [x, y], got [0]"),
    ("mechanism.A0", [0, 0, 0], "mechanism.A0: must be a point [x, y], got [0, 0, 0]"),
    ("mechanism.A0", "origin", 'mechanism.A0: must be a point [x, y], got "origin"'),
    ("mechanism.A0", [0, False], "mechanism.A0[1]: must be a number, got false"),
    ("mechanism.B0", [math.inf, 0], "mechanism.B0[0]: must be a finite number, got inf"),
    (
        "mechanism.B0",
        [0, 0],
        "mechanism.B0: coincides with mechanism.A0 (the frame A0B0 must have a positive length)",
    ),
    ("mechanism.assembly", 0, "mechanism.assembly: must be 1 or -1, got 0"),
    ("mechanism.assembly", 2, "mechanism.assembly: must be 1 or -1, got 2"),
    ("mechanism.assembly", True, "mechanism.assembly: must be 1 or -1, got true"),
    ("mechanism.point", [1, 2], "mechanism.point: must be a table {u = .., v = ..}, got [1, 2]"),
    ("mechanism.point", {"u": 1, "w": 2}, "mechanism.point: unknown field 'w' (known: u, v)"),
    ("mechanism.point", {"u": None}, "mechanism.point.u: must be a number, got null"),
    ("mechanism.crnak", 1, "mechanism: unknown field 'crnak' (did you mean 'crank'?)"),
    ("mechanism.family", "fourbars", "mechanism.family: unknown family 'fourbars' (did you mean"),
    (
        "mechanism.family",
        "sixbar",
        "mechanism.family: unknown family 'sixbar' (known: fourbar, slidercrank, doubleslider, "
        "geared-fivebar, watt1, watt2, stephenson1, stephenson3, linkage, spherical-fourbar, "
        "spherical-sixbar, spherical-stephenson3)",
    ),
    ("mechanism.family", 4, "mechanism.family: must be a string, got 4"),
    ("format", "linkwright/9", 'format: expected "linkwright/1", got "linkwright/9"'),
    ("format", 1, 'format: expected "linkwright/1", got 1'),
    ("title", 3, "title: must be a string, got 3"),
    ("units", ["mm"], 'units: must be a string, got ["mm"]'),
    ("mechanism", [1], "mechanism: must be a table, got [1]"),
    ("extra", 1, "document: unknown field 'extra'"),
    ("mechanizm", {}, "document: unknown field 'mechanizm' (did you mean 'mechanism'?)"),
]


@pytest.mark.parametrize(("path", "value", "message"), FOURBAR_ERRORS)
def test_fourbar_validation_messages(path, value, message):
    with pytest.raises(DocumentError) as info:
        parse_document(with_change(FOURBAR, path, value))
    assert str(info.value).startswith(message)
    assert info.value.field == message.split(":")[0]


MISSING = [
    (FOURBAR, "format", 'format: missing required field (expected "linkwright/1")'),
    (FOURBAR, "mechanism", "mechanism: missing required table"),
    (FOURBAR, "mechanism.family", "mechanism.family: missing required field"),
    (FOURBAR, "mechanism.A0", "mechanism.A0: missing required field (a point [x, y])"),
    (FOURBAR, "mechanism.B0", "mechanism.B0: missing required field (a point [x, y])"),
    (FOURBAR, "mechanism.crank", "mechanism.crank: missing required field (a positive number)"),
    (FOURBAR, "mechanism.coupler", "mechanism.coupler: missing required field"),
    (FOURBAR, "mechanism.rocker", "mechanism.rocker: missing required field"),
    (SLIDER, "mechanism.rod", "mechanism.rod: missing required field (a positive number)"),
    (SLIDER, "mechanism.line", "mechanism.line: missing required field"),
    (SLIDER, "mechanism.line.angle", "mechanism.line.angle: missing required field"),
    (SLIDER, "mechanism.line.point", "mechanism.line.point: missing required field"),
]


@pytest.mark.parametrize(("base", "path", "message"), MISSING)
def test_missing_field_messages(base, path, message):
    with pytest.raises(DocumentError) as info:
        parse_document(with_change(base, path, delete=True))
    assert str(info.value).startswith(message)


SLIDER_ERRORS = [
    ("mechanism.rod", -3, "mechanism.rod: must be a positive number, got -3"),
    (
        "mechanism.line.angle",
        "30deg",
        'mechanism.line.angle: must be an angle in degrees, got "30deg"',
    ),
    ("mechanism.line.angle", math.nan, "mechanism.line.angle: must be a finite number, got nan"),
    ("mechanism.line.point", [0], "mechanism.line.point: must be a point [x, y], got [0]"),
    ("mechanism.line.pont", [0, 0], "mechanism.line: unknown field 'pont' (did you mean 'point'?)"),
    ("mechanism.line", 0, "mechanism.line: must be a table {point = [x, y], angle = ..}, got 0"),
    ("mechanism.B0", [1, 0], "mechanism: unknown field 'B0'"),
    ("mechanism.coupler", 5, "mechanism: unknown field 'coupler'"),
]


@pytest.mark.parametrize(("path", "value", "message"), SLIDER_ERRORS)
def test_slidercrank_validation_messages(path, value, message):
    with pytest.raises(DocumentError) as info:
        parse_document(with_change(SLIDER, path, value))
    assert str(info.value).startswith(message)


def test_non_mapping_document_and_non_string_keys():
    with pytest.raises(DocumentError, match=r"^document: must be a table, got \[1, 2\]$"):
        parse_document([1, 2])
    with pytest.raises(DocumentError, match=r"^document: keys must be strings, got 1$"):
        parse_document({1: "x"})


def test_huge_integers_are_not_finite_numbers():
    with pytest.raises(DocumentError, match=r"^mechanism\.crank: must be a finite number, got an"):
        parse_document(with_change(FOURBAR, "mechanism.crank", 10**400))


def test_document_error_is_a_value_error_and_carries_the_source():
    with pytest.raises(ValueError, match=r"^here\.toml: mechanism\.crank: must be a positive"):
        parse_document(with_change(FOURBAR, "mechanism.crank", -1), source="here.toml")

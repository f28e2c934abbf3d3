"""Mechanism documents: validation messages, defaults, degrees, round trips, atomic saves."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import importlib
import json
import math
import os
import stat
import tempfile
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import linkwright.mechanisms
from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    document_to_dict,
    list_examples,
    load_document,
    load_example,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.io.documents import JOINT_SPECS, KINDS, dumps_toml
from linkwright.mechanisms import FAMILIES, FourBar, SliderCrank, solve
from linkwright.mechanisms.linkage import CrankJoint, DyadJoint, FixedJoint, Linkage, RigidJoint

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"
EXAMPLE_NAMES = [
    "crank-rocker",
    "double-crank",
    "rocker-input",
    "triple-rocker",
    "slider-crank",
    "offset-slider-crank",
    "jansen-leg",
    "klann-leg",
]


@pytest.fixture(scope="module", autouse=True)
def linkage_family():
    """Documents of family ``linkage`` need the class in FAMILIES (the lead registers it there;
    until then this module registers it for its own tests)."""
    with pytest.MonkeyPatch.context() as mp:
        if "linkage" not in FAMILIES:
            mp.setitem(FAMILIES, "linkage", Linkage)
        yield


# Read before any fixture runs: whether the package itself registers the linkage family.
LINKAGE_REGISTERED = FAMILIES.get("linkage") is Linkage


def family_class(family: str, cls_name: str) -> type:
    """The class of a family whose schema is here, or a skip saying what is missing."""
    cls = getattr(linkwright.mechanisms, cls_name, None)
    if cls is None:
        try:
            module = importlib.import_module("linkwright.mechanisms.sixbar")
        except ImportError:
            module = None
        cls = getattr(module, cls_name, None)
    if cls is None:
        pytest.skip(f"linkwright.mechanisms.{cls_name} is not written yet")
    if FAMILIES.get(family) is not cls:
        pytest.skip(f"family {family!r} is not registered in linkwright.mechanisms.FAMILIES yet")
    return cls


FOURBAR = {
    "format": "linkwright/1",
    "title": "test four-bar",
    "units": "mm",
    "mechanism": {
        "family": "fourbar",
        "A0": [0, 0],
        "B0": [4, 0],
        "crank": 1,
        "coupler": 5,
        "rocker": 3.5,
        "point": {"u": 2, "v": 1},
        "assembly": -1,
    },
}
SLIDER = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "slidercrank",
        "A0": [0, 0],
        "crank": 1,
        "rod": 3,
        "line": {"point": [0, -0.5], "angle": 30},
    },
}


def with_change(base: dict, path: str, value: object = ..., delete: bool = False) -> dict:
    """A deep copy of ``base`` with the dotted ``path`` set to ``value`` (or deleted)."""
    doc = copy.deepcopy(base)
    *parents, last = path.split(".")
    node = doc
    for key in parents:
        node = node[key]
    if delete:
        del node[last]
    else:
        node[last] = value
    return doc


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


# ---------------------------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------------------------


def test_malformed_toml_gives_line_and_column(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('format = "linkwright/1"\n[mechanism]\ncrank = \n')
    with pytest.raises(DocumentError) as info:
        load_document(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: document: invalid TOML: ")
    assert "line 3" in msg and "column" in msg


def test_malformed_json_gives_line_and_column(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{\n  "format": "linkwright/1",\n  "mechanism": {,}\n}\n')
    with pytest.raises(DocumentError, match=r"invalid JSON: .*\(at line 3, column 17\)$"):
        load_document(path)


def test_json_duplicate_keys_are_refused(tmp_path):
    path = tmp_path / "dup.json"
    path.write_text('{"format": "linkwright/1", "format": "linkwright/1"}')
    with pytest.raises(DocumentError, match=r"document: duplicate key 'format'"):
        load_document(path)


def test_json_nan_literal_is_caught_as_not_finite(tmp_path):
    doc = with_change(FOURBAR, "mechanism.crank", "NAN")
    path = tmp_path / "nan.json"
    path.write_text(json.dumps(doc).replace('"NAN"', "NaN"))
    with pytest.raises(DocumentError, match=r"mechanism\.crank: must be a finite number, got nan"):
        load_document(path)


@pytest.mark.parametrize("name", ["mech.yaml", "mech", "mech.txt"])
def test_unknown_extension(tmp_path, name):
    path = tmp_path / name
    path.write_text("{}")
    with pytest.raises(DocumentError, match=r"unknown file type .*expected \.toml or \.json"):
        load_document(path)
    with pytest.raises(DocumentError, match=r"unknown file type"):
        save_document(parse_document(FOURBAR), path)


def test_missing_file_and_non_utf8(tmp_path):
    with pytest.raises(DocumentError, match=r"document: cannot read: No such file"):
        load_document(tmp_path / "none.toml")
    bad = tmp_path / "latin.toml"
    bad.write_bytes(b'title = "caf\xe9"\n')
    with pytest.raises(DocumentError, match=r"not UTF-8"):
        load_document(bad)


def test_toml_and_json_have_the_same_structure(tmp_path):
    toml_path = tmp_path / "m.toml"
    json_path = tmp_path / "m.json"
    save_document(FOURBAR, toml_path)
    save_document(FOURBAR, json_path)
    assert load_document(toml_path) == load_document(json_path) == parse_document(FOURBAR)
    assert json.loads(json_path.read_text())["mechanism"]["point"] == {"u": 2.0, "v": 1.0}


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_round_trip_load_save_load(tmp_path, name, suffix):
    first = load_document(EXAMPLES / f"{name}.toml")
    path = save_document(first, tmp_path / f"copy{suffix}")
    second = load_document(path)
    assert second == first
    assert document_to_dict(second) == document_to_dict(first)
    # And once more from the written file: saving is idempotent byte for byte.
    again = save_document(second, tmp_path / f"again{suffix}")
    assert again.read_bytes() == path.read_bytes()


def test_save_a_mapping_validates_it_first(tmp_path):
    with pytest.raises(DocumentError, match=r"mechanism\.crank"):
        save_document(with_change(FOURBAR, "mechanism.crank", -1), tmp_path / "x.toml")
    assert not (tmp_path / "x.toml").exists()


def test_mechanism_to_dict_converts_radians_back_to_degrees():
    m = SliderCrank(
        A0=[1, 2],
        crank=1,
        rod=3,
        line_point=[0, -0.5],
        line_angle=math.radians(30),
        u=0.5,
        v=-0.25,
        assembly=-1,
    )
    d = mechanism_to_dict(m, title="from code")
    assert d == {
        "format": "linkwright/1",
        "title": "from code",
        "mechanism": {
            "family": "slidercrank",
            "A0": [1.0, 2.0],
            "crank": 1.0,
            "rod": 3.0,
            "line": {"point": [0.0, -0.5], "angle": 30.0},
            "point": {"u": 0.5, "v": -0.25},
            "assembly": -1,
        },
    }
    assert parse_document(d).raw == d


@pytest.mark.parametrize(
    "name", ["crank-rocker", "offset-slider-crank", "triple-rocker", "jansen-leg", "klann-leg"]
)
def test_mechanism_round_trip_through_dict(name):
    doc = load_example(name)
    d = mechanism_to_dict(doc.mechanism, title=doc.title)
    again = parse_document(d)
    assert again.raw["mechanism"] == doc.raw["mechanism"]


def test_mechanism_to_dict_refuses_batches():
    batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1, 2], coupler=5, rocker=3.5)
    with pytest.raises(DocumentError, match=r"^mechanism\.crank: must be a single value"):
        mechanism_to_dict(batch)


def test_save_is_atomic_when_the_rename_fails(tmp_path, monkeypatch):
    path = tmp_path / "m.toml"
    save_document(FOURBAR, path)
    before = path.read_bytes()

    def broken_replace(src, dst):
        raise OSError("disk on fire")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk on fire"):
        save_document(SLIDER, path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.toml"]  # no temporary left behind


def test_save_fsyncs_before_renaming(tmp_path, monkeypatch):
    calls = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        calls.append("fsync")
        real_fsync(fd)

    def replace(a, b):
        calls.append("replace")
        real_replace(a, b)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    save_document(FOURBAR, tmp_path / "m.json")
    assert calls[:2] == ["fsync", "replace"]


def test_save_keeps_an_existing_files_permissions(tmp_path):
    path = tmp_path / "m.toml"
    save_document(FOURBAR, path)
    os.chmod(path, 0o640)
    save_document(SLIDER, path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o640
    assert load_document(path).family == "slidercrank"


# ---------------------------------------------------------------------------------------------
# Bundled examples, checked against their stated geometry
# ---------------------------------------------------------------------------------------------


def test_list_examples():
    assert set(list_examples()) >= set(EXAMPLE_NAMES)
    assert load_example("crank-rocker.toml") == load_example("crank-rocker")
    with pytest.raises(DocumentError, match=r"^example: unknown example 'crank-rocke' \(did you"):
        load_example("crank-rocke")


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_examples_have_a_title_and_a_provenance_comment(name):
    text = (EXAMPLES / f"{name}.toml").read_text()
    assert text.startswith("# ")
    assert load_example(name).title


def four_lengths(doc: Document) -> tuple[float, float, float, float]:
    m = doc.raw["mechanism"]
    frame = math.dist(m["A0"], m["B0"])
    return m["crank"], m["coupler"], m["rocker"], frame


def test_crank_rocker_is_paper_003_table_1():
    doc = load_example("crank-rocker")
    assert four_lengths(doc) == (1.0, 5.0, 6.02, 3.5)
    links = sorted(four_lengths(doc))
    assert links[0] + links[3] < links[1] + links[2]  # Grashof
    assert min(four_lengths(doc)) == doc.raw["mechanism"]["crank"]  # crank shortest


def test_double_crank_is_paper_003_table_4():
    crank, coupler, rocker, frame = four_lengths(load_example("double-crank"))
    assert (crank, coupler, frame) == (4.0, 2.0, 1.0)
    assert rocker == pytest.approx(math.sqrt(13), abs=1e-15)
    assert frame == min(crank, coupler, rocker, frame)


def test_triple_rocker_is_not_grashof():
    s, p, q, l = sorted(four_lengths(load_example("triple-rocker")))
    assert s + l > p + q


def test_rocker_input_is_grashof_driven_at_a_rocker():
    crank, coupler, rocker, frame = four_lengths(load_example("rocker-input"))
    s, p, q, l = sorted((crank, coupler, rocker, frame))
    assert s + l < p + q  # Grashof
    assert rocker == s  # the output is shortest: it turns, the driven link only rocks
    # At θ = 0 the driven link puts A at (3.5, 0): 0.5 from B0, less than coupler − rocker = 4.
    m = load_example("rocker-input").raw["mechanism"]
    a = (m["A0"][0] + m["crank"], m["A0"][1])
    assert math.dist(a, m["B0"]) < m["coupler"] - m["rocker"]


def test_slider_examples_offsets():
    assert load_example("slider-crank").raw["mechanism"]["line"] == {
        "point": [0.0, 0.0],
        "angle": 0.0,
    }
    offset = load_example("offset-slider-crank")
    assert float(offset.mechanism.offset) == pytest.approx(0.5)


CLASS_NAMES = {
    "fourbar": "FourBar",
    "slidercrank": "SliderCrank",
    "geared-fivebar": "GearedFiveBar",
    "doubleslider": "DoubleSlider",
    "watt1": "Watt1",
    "watt2": "Watt2",
    "stephenson1": "Stephenson1",
    "stephenson3": "Stephenson3",
    "linkage": "Linkage",
    "spherical-fourbar": "SphericalFourBar",
    "spherical-sixbar": "SphericalSixBar",
    "spherical-stephenson3": "SphericalStephenson3",
}


def test_every_schema_names_its_class():
    assert set(CLASS_NAMES) == set(FAMILY_SPECS)


@pytest.mark.parametrize("family", sorted(FAMILY_SPECS))
def test_family_specs_cover_the_mechanism_families(family):
    cls = Linkage if family == "linkage" else family_class(family, CLASS_NAMES[family])
    spec = FAMILY_SPECS[family]
    # Fields that only say how to read the document (a linkage's space) build nothing.
    targets = {t for f in spec.fields if KINDS[f.kind].builds for t in f.targets}
    assert targets == {f.name for f in dataclasses.fields(cls)}, family


def test_linkage_is_registered_as_a_family():
    if not LINKAGE_REGISTERED:
        pytest.skip("Linkage is not registered in linkwright.mechanisms.FAMILIES yet")
    assert Linkage.family == "linkage"


def test_joint_specs_cover_the_joint_classes():
    from linkwright.mechanisms.linkage import JOINT_TYPES

    assert set(JOINT_SPECS) == set(JOINT_TYPES)
    for kind, specs in JOINT_SPECS.items():
        names = {f.name for f in dataclasses.fields(JOINT_TYPES[kind])} - {"name"}
        assert {t for f in specs for t in f.targets} == names, kind


# ---------------------------------------------------------------------------------------------
# Fuzzing: the parser only ever raises DocumentError
# ---------------------------------------------------------------------------------------------

scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(10**20), max_value=10**20)
    | st.integers()
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=12)
    | st.sampled_from(["fourbar", "slidercrank", "linkwright/1", "u", "v", "point", "angle"])
)
json_like = st.recursive(
    scalars,
    lambda children: (
        st.lists(children, max_size=4)
        | st.dictionaries(
            st.text(max_size=8) | st.sampled_from(["u", "v", "point", "angle"]),
            children,
            max_size=4,
        )
    ),
    max_leaves=12,
)
field_names = st.sampled_from(
    sorted({f.name for spec in FAMILY_SPECS.values() for f in spec.fields} | {"family", "zzz"})
)


@st.composite
def near_valid_documents(draw):
    """A valid document with a few fields replaced, removed or added at random."""
    doc = copy.deepcopy(draw(st.sampled_from([FOURBAR, SLIDER])))
    mech = doc["mechanism"]
    for _ in range(draw(st.integers(0, 3))):
        name = draw(field_names)
        action = draw(st.sampled_from(["set", "delete", "nested"]))
        if action == "delete":
            mech.pop(name, None)
        elif action == "nested" and isinstance(mech.get(name), dict):
            mech[name][draw(st.sampled_from(["u", "v", "point", "angle", "x"]))] = draw(json_like)
        else:
            mech[name] = draw(json_like)
    if draw(st.booleans()):
        doc[draw(st.sampled_from(["format", "title", "units", "other"]))] = draw(json_like)
    return doc


@settings(max_examples=300, deadline=None)
@given(json_like)
def test_fuzz_arbitrary_values_only_raise_document_error(value):
    with contextlib.suppress(DocumentError):
        parse_document(value)


@settings(max_examples=400, deadline=None)
@given(near_valid_documents())
def test_fuzz_near_valid_documents_only_raise_document_error(doc):
    try:
        result = parse_document(doc)
    except DocumentError as exc:
        assert str(exc).split(":")[0] in {"document", "format", "title", "units"} or str(
            exc
        ).startswith("mechanism")
    else:
        assert isinstance(result, Document)
        assert parse_document(document_to_dict(result)) == result


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.text(max_size=80), st.sampled_from([".toml", ".json"]))
def test_fuzz_arbitrary_file_text_only_raises_document_error(text, suffix):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"doc{suffix}"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        with contextlib.suppress(DocumentError):
            load_document(path)


@settings(max_examples=150, deadline=None)
@given(
    title=st.text(max_size=30),
    crank=st.floats(min_value=1e-6, max_value=1e6),
    angle=st.floats(min_value=-720, max_value=720),
    suffix=st.sampled_from([".toml", ".json"]),
)
def test_fuzz_round_trip_of_any_title_and_numbers(title, crank, angle, suffix):
    doc = with_change(with_change(SLIDER, "mechanism.crank", crank), "mechanism.line.angle", angle)
    doc["title"] = title
    try:
        parsed = parse_document(doc)
    except DocumentError as exc:
        # Only a title that cannot be written as UTF-8 (a lone surrogate) is refused.
        assert str(exc).startswith("title: must be valid Unicode text")
        return
    with tempfile.TemporaryDirectory() as tmp:
        path = save_document(parsed, Path(tmp) / f"doc{suffix}")
        assert load_document(path) == parsed


# ---------------------------------------------------------------------------------------------
# The geared five-bar, the double slider and the six-bars
# ---------------------------------------------------------------------------------------------

FIVEBAR = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "geared-fivebar",
        "A0": [0, 0],
        "B0": [4, 0],
        "crank1": 1,
        "crank2": 1.5,
        "link1": 3,
        "link2": 3.5,
        "phase2": 45,
    },
}
DOUBLESLIDER = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "doubleslider",
        "M": [1, 2],
        "alpha": 90,
        "beta": 30,
        "p": 3,
        "q": -1,
    },
}


def sixbar(family: str) -> dict:
    mech = {
        "family": family,
        "A0": [0, 0],
        "B0": [4, 0],
        "crank": 1,
        "coupler": 5,
        "rocker": 3.5,
        "C": {"u": 0.5, "v": 0.8},
        "link1": 4,
        "link2": 3,
        "point": {"u": 1, "v": 0.5},
        "assembly2": -1,
    }
    if family in ("watt1", "stephenson1"):
        mech["E"] = {"u": 2.0, "v": 1.0}
    else:
        mech["D0"] = [6, 2]
    return {"format": "linkwright/1", "mechanism": mech}


def test_geared_fivebar_document_defaults_and_degrees():
    cls = family_class("geared-fivebar", "GearedFiveBar")
    doc = parse_document(FIVEBAR)
    m = doc.mechanism
    assert isinstance(m, cls)
    raw = doc.raw["mechanism"]
    assert (raw["phase1"], raw["ratio"], raw["assembly"]) == (0.0, -1.0, 1)
    assert raw["point"] == {"u": 0.0, "v": 0.0}
    assert float(m.phase2) == pytest.approx(math.pi / 4, abs=1e-15)
    assert float(m.ratio) == -1.0 and float(m.crank2) == 1.5
    assert parse_document(mechanism_to_dict(m)).raw == doc.raw


def test_geared_fivebar_pivots_may_coincide():
    family_class("geared-fivebar", "GearedFiveBar")
    doc = parse_document(with_change(FIVEBAR, "mechanism.B0", [0, 0]))
    np.testing.assert_array_equal(doc.mechanism.B0, [0, 0])


FIVEBAR_ERRORS = [
    ("mechanism.ratio", 0, "mechanism.ratio: must be a nonzero number, got 0"),
    ("mechanism.ratio", "2:1", 'mechanism.ratio: must be a nonzero number, got "2:1"'),
    ("mechanism.ratio", math.inf, "mechanism.ratio: must be a finite number, got inf"),
    ("mechanism.phase1", None, "mechanism.phase1: must be an angle in degrees, got null"),
    ("mechanism.link2", -3, "mechanism.link2: must be a positive number, got -3"),
    ("mechanism.crank", 1, "mechanism: unknown field 'crank' (did you mean 'crank"),
]


@pytest.mark.parametrize(("path", "value", "message"), FIVEBAR_ERRORS)
def test_geared_fivebar_validation_messages(path, value, message):
    with pytest.raises(DocumentError) as info:
        parse_document(with_change(FIVEBAR, path, value))
    assert str(info.value).startswith(message)


def test_doubleslider_document():
    cls = family_class("doubleslider", "DoubleSlider")
    doc = parse_document(DOUBLESLIDER)
    m = doc.mechanism
    assert isinstance(m, cls)
    assert doc.raw["mechanism"]["h"] == 0.0
    assert float(m.alpha) == pytest.approx(math.pi / 2, abs=1e-15)
    assert float(m.beta) == pytest.approx(math.pi / 6, abs=1e-15)
    assert (float(m.p), float(m.q)) == (3.0, -1.0)
    assert parse_document(mechanism_to_dict(m)).raw == doc.raw


DOUBLESLIDER_ERRORS = [
    (
        "mechanism.alpha",
        180,
        "mechanism.alpha: must not be a multiple of 180 degrees, got 180.0 (the slider lines",
    ),
    ("mechanism.alpha", 0, "mechanism.alpha: must not be a multiple of 180 degrees, got 0"),
    ("mechanism.alpha", -540.0, "mechanism.alpha: must not be a multiple of 180 degrees"),
    ("mechanism.q", -3, "mechanism.q: p + q must not be 0 (the sliders R and Q would coincide)"),
    ("mechanism.p", "3", 'mechanism.p: must be a number, got "3"'),
    ("mechanism.h", math.nan, "mechanism.h: must be a finite number, got nan"),
    ("mechanism.M", [1], "mechanism.M: must be a point [x, y], got [1]"),
]


@pytest.mark.parametrize(("path", "value", "message"), DOUBLESLIDER_ERRORS)
def test_doubleslider_validation_messages(path, value, message):
    with pytest.raises(DocumentError) as info:
        parse_document(with_change(DOUBLESLIDER, path, value))
    assert str(info.value).startswith(message)


def test_doubleslider_negative_lengths_are_signed_numbers():
    family_class("doubleslider", "DoubleSlider")
    doc = parse_document(with_change(DOUBLESLIDER, "mechanism.h", -0.5))
    assert float(doc.mechanism.h) == -0.5


SIXBARS = [
    ("watt1", "Watt1"),
    ("watt2", "Watt2"),
    ("stephenson1", "Stephenson1"),
    ("stephenson3", "Stephenson3"),
]


@pytest.mark.parametrize(("family", "cls_name"), SIXBARS)
def test_sixbar_documents(family, cls_name):
    cls = family_class(family, cls_name)
    doc = parse_document(sixbar(family))
    m = doc.mechanism
    assert isinstance(m, cls)
    assert (float(m.u1), float(m.v1)) == (0.5, 0.8)
    assert (float(m.u), float(m.v), float(m.assembly), float(m.assembly2)) == (1, 0.5, 1, -1)
    if family in ("watt1", "stephenson1"):
        assert (float(m.u2), float(m.v2)) == (2.0, 1.0)
    else:
        np.testing.assert_array_equal(m.D0, [6, 2])
    if family == "stephenson3":
        assert doc.raw["mechanism"]["input"] == "crank" and m.input == "crank"
    assert parse_document(mechanism_to_dict(m)).raw == doc.raw


SIXBAR_ERRORS = [
    ("watt1", "mechanism.E", None, "mechanism.E: missing required field (a table {u = .., v"),
    ("watt1", "mechanism.C", None, "mechanism.C: missing required field"),
    ("watt1", "mechanism.D0", [1, 1], "mechanism: unknown field 'D0'"),
    ("watt2", "mechanism.D0", None, "mechanism.D0: missing required field (a point [x, y])"),
    ("watt2", "mechanism.E", {"u": 1}, "mechanism: unknown field 'E'"),
    ("stephenson1", "mechanism.link1", 0, "mechanism.link1: must be a positive number, got 0"),
    ("stephenson1", "mechanism.assembly2", 3, "mechanism.assembly2: must be 1 or -1, got 3"),
    ("stephenson3", "mechanism.input", "coupler", "mechanism.input: unknown value 'coupler'"),
    ("stephenson3", "mechanism.input", 1, 'mechanism.input: must be "crank" or "output", got 1'),
    ("watt2", "mechanism.input", "crank", "mechanism: unknown field 'input'"),
    ("stephenson3", "mechanism.B0", [0, 0], "mechanism.B0: coincides with mechanism.A0"),
]


@pytest.mark.parametrize(("family", "path", "value", "message"), SIXBAR_ERRORS)
def test_sixbar_validation_messages(family, path, value, message):
    doc = sixbar(family)
    doc = with_change(doc, path, delete=True) if value is None else with_change(doc, path, value)
    with pytest.raises(DocumentError) as info:
        parse_document(doc)
    assert str(info.value).startswith(message)


def test_stephenson3_output_input_is_accepted_by_the_schema():
    family_class("stephenson3", "Stephenson3")
    doc = with_change(sixbar("stephenson3"), "mechanism.input", "output")
    try:
        parsed = parse_document(doc)
    except DocumentError as exc:
        # The class may not solve an output-driven Stephenson III yet; the schema accepted it.
        assert not str(exc).startswith("mechanism.input")
    else:
        assert parsed.raw["mechanism"]["input"] == "output"


# ---------------------------------------------------------------------------------------------
# Composed linkages
# ---------------------------------------------------------------------------------------------

LINKAGE = {
    "format": "linkwright/1",
    "title": "four-bar, joint by joint",
    "mechanism": {
        "family": "linkage",
        "joints": [
            {"name": "A0", "type": "fixed", "at": [0, 0]},
            {"name": "B0", "type": "fixed", "at": [4, 0]},
            {"name": "A", "type": "crank", "pivot": "A0", "length": 1, "phase": 30},
            {"name": "B", "type": "rrr", "p1": "A", "r1": 5, "p2": "B0", "r2": 3.5},
            {"name": "P", "type": "rigid", "origin": "A", "toward": "B", "u": 2, "v": 1},
            {"name": "S", "type": "rrp", "p1": "B", "r": 2, "line_point": "B0", "line_angle": 90},
        ],
    },
}


def test_linkage_document_builds_the_linkage():
    doc = parse_document(LINKAGE)
    m = doc.mechanism
    assert isinstance(m, Linkage) and doc.family == "linkage"
    assert m.traced == ("S",)  # the last joint by default
    raw = doc.raw["mechanism"]
    assert raw["space"] == "plane" and raw["traced"] == ["S"]
    assert raw["joints"][2] == {
        "name": "A",
        "type": "crank",
        "pivot": "A0",
        "length": 1.0,
        "ratio": 1.0,
        "phase": 30.0,
    }
    assert raw["joints"][3]["assembly"] == 1
    assert float(m.joint("A").phase) == pytest.approx(math.pi / 6, abs=1e-15)
    assert float(m.joint("S").line_angle) == pytest.approx(math.pi / 2, abs=1e-15)
    assert m == Linkage(
        joints=(
            FixedJoint("A0", [0, 0]),
            FixedJoint("B0", [4, 0]),
            CrankJoint("A", "A0", 1, phase=math.radians(30)),
            DyadJoint("B", "A", 5, "B0", 3.5),
            RigidJoint("P", "A", "B", 2, 1),
            m.joint("S"),
        )
    )


def test_the_module_docstrings_linkage_example_is_the_crank_rocker_example():
    import linkwright.io.documents as documents

    text = documents.__doc__.split("tracing its coupler point P)::")[1]
    doc = parse_document(tomllib.loads(textwrap.dedent(text)))
    assert doc.family == "linkage" and doc.mechanism.traced == ("P",)
    named = load_example("crank-rocker").mechanism
    theta = np.linspace(0, 2 * np.pi, 12)
    np.testing.assert_allclose(
        solve(doc.mechanism, theta).positions["P"],
        solve(named, theta).positions["P"],
        rtol=0,
        atol=1e-12,
    )


def test_linkage_round_trips_through_mechanism_to_dict_and_files(tmp_path):
    doc = parse_document(with_change(LINKAGE, "mechanism.traced", ["P", "B"]))
    d = mechanism_to_dict(doc.mechanism, title=doc.title)
    assert d == document_to_dict(doc)
    assert parse_document(d) == doc
    for suffix in (".toml", ".json"):
        path = save_document(doc, tmp_path / f"l{suffix}")
        assert load_document(path) == doc
    text = (tmp_path / "l.toml").read_text()
    assert text.count("[[mechanism.joints]]") == 6
    assert 'traced = ["P", "B"]' in text


def test_linkage_from_code_round_trips():
    m = Linkage(
        joints=(
            FixedJoint("O", [0.0, 0.0]),
            CrankJoint("A", "O", 1.0, ratio=-2.0, phase=math.radians(-45)),
            CrankJoint("G", "A", 0.25),
        ),
        traced=("G", "A"),
    )
    d = mechanism_to_dict(m)
    assert d["mechanism"]["joints"][1]["phase"] == -45.0
    assert d["mechanism"]["joints"][1]["ratio"] == -2.0
    assert parse_document(d).mechanism == m


def test_mechanism_to_dict_refuses_a_batched_linkage_naming_the_joint():
    m = Linkage(joints=(FixedJoint("O", [0, 0]), CrankJoint("A", "O", [1.0, 2.0])))
    with pytest.raises(DocumentError, match=r"^mechanism\.joints\[1\]\.length: must be a single"):
        mechanism_to_dict(m)


def joint_change(index: int, key: str, value: object = ..., delete: bool = False) -> dict:
    doc = copy.deepcopy(LINKAGE)
    entry = doc["mechanism"]["joints"][index]
    if delete:
        del entry[key]
    else:
        entry[key] = value
    return doc


LINKAGE_ERRORS = [
    (joint_change(3, "r1", -2), "mechanism.joints[3].r1: must be a positive number, got -2"),
    (
        joint_change(3, "r3", 1),
        "mechanism.joints[3]: unknown field 'r3' (known: name, type, p1, r1, p2, r2, assembly)",
    ),
    (joint_change(3, "assmbly", 1), "mechanism.joints[3]: unknown field 'assmbly' (did you mean"),
    (joint_change(3, "r1", delete=True), "mechanism.joints[3].r1: missing required field"),
    (joint_change(3, "assembly", 0), "mechanism.joints[3].assembly: must be 1 or -1, got 0"),
    (joint_change(2, "ratio", 0), "mechanism.joints[2].ratio: must be a nonzero number, got 0"),
    (joint_change(2, "phase", "30deg"), "mechanism.joints[2].phase: must be an angle in degrees"),
    (joint_change(0, "at", [0]), "mechanism.joints[0].at: must be a point [x, y], got [0]"),
    (joint_change(4, "u", None), "mechanism.joints[4].u: must be a number, got null"),
    (joint_change(5, "line_angle", delete=True), "mechanism.joints[5].line_angle: missing"),
    (
        joint_change(3, "p1", ""),
        "mechanism.joints[3].p1: must be a joint name (a non-empty string)",
    ),
    (joint_change(3, "p1", 7), "mechanism.joints[3].p1: must be a joint name (a non-empty string)"),
    (joint_change(3, "name", delete=True), "mechanism.joints[3].name: missing required field"),
    (joint_change(3, "type", delete=True), "mechanism.joints[3].type: missing required field (one"),
    (joint_change(3, "type", "rr"), "mechanism.joints[3].type: unknown joint type 'rr' (did you"),
    (joint_change(3, "type", 3), "mechanism.joints[3].type: must be a string, got 3"),
    (
        joint_change(3, "p1", "X"),
        "mechanism.joints[3]: joint 'B' is built from 'X', which is not placed before it (no "
        "joint has that name; under-constrained)",
    ),
    (
        joint_change(3, "p1", "P"),
        "mechanism.joints[3]: joint 'B' is built from 'P', which is not placed before it (it is "
        "listed after it; under-constrained)",
    ),
    (joint_change(3, "p2", "A"), "mechanism.joints[3]: joint 'B': p1 and p2 are both 'A'"),
    (joint_change(1, "name", "A0"), "mechanism.joints[1]: joint 'A0' is listed twice"),
    (
        joint_change(1, "at", [0, 0]),
        "mechanism.joints[1]: joint 'B0' repeats joint 'A0' (a ground pivot at the same place)",
    ),
    (
        joint_change(4, "toward", "B0"),
        "mechanism.joints[4]: joint 'P' is fixed on the link 'A'→'B0', but those two joints are "
        "not on one rigid link",
    ),
    (
        with_change(LINKAGE, "mechanism.joints", [{"name": "O", "type": "fixed", "at": [0, 0]}]),
        "mechanism.joints: nothing drives the linkage: none of its joints is a crank",
    ),
    (
        with_change(LINKAGE, "mechanism.joints", []),
        "mechanism.joints: a linkage needs joints",
    ),
    (with_change(LINKAGE, "mechanism.joints", {"A": 1}), "mechanism.joints: must be a list"),
    (with_change(LINKAGE, "mechanism.joints", [3]), "mechanism.joints[0]: must be a joint table"),
    (
        with_change(LINKAGE, "mechanism.joints", delete=True),
        "mechanism.joints: missing required field (a list of joint tables",
    ),
    (with_change(LINKAGE, "mechanism.traced", ["Q"]), "mechanism.traced[0]: unknown joint 'Q'"),
    (with_change(LINKAGE, "mechanism.traced", []), "mechanism.traced: must name at least one"),
    (with_change(LINKAGE, "mechanism.traced", "P"), "mechanism.traced: must be a list of joint"),
    (with_change(LINKAGE, "mechanism.traced", ["P", "P"]), "mechanism.traced[1]: joint 'P' is"),
    (with_change(LINKAGE, "mechanism.traced", [1]), "mechanism.traced[0]: must be a joint name"),
    (
        with_change(LINKAGE, "mechanism.space", "sphere"),
        "mechanism.joints[0].at: must be an axis [x, y, z]",
    ),
    (with_change(LINKAGE, "mechanism.space", "plain"), "mechanism.space: unknown value 'plain'"),
    (
        with_change(LINKAGE, "mechanism.space", 2),
        'mechanism.space: must be "plane" or "sphere", got 2',
    ),
    (with_change(LINKAGE, "mechanism.joint", []), "mechanism: unknown field 'joint' (did you"),
]


@pytest.mark.parametrize(("doc", "message"), LINKAGE_ERRORS)
def test_linkage_validation_messages(doc, message):
    with pytest.raises(DocumentError) as info:
        parse_document(doc)
    assert str(info.value).startswith(message)
    assert info.value.field == message.split(": ")[0]


def test_toml_writer_puts_arrays_of_tables_after_plain_keys():
    text = dumps_toml(
        {"format": "x", "mechanism": {"joints": [{"a": 1}, {"b": [1.0, 2.0]}], "t": 2}}
    )
    assert text == (
        'format = "x"\n\n[mechanism]\nt = 2\n\n[[mechanism.joints]]\na = 1\n\n'
        "[[mechanism.joints]]\nb = [1.0, 2.0]\n"
    )


# ---------------------------------------------------------------------------------------------
# Fuzzing the linkage parser: random joint lists, wrong types, missing fields, cycles
# ---------------------------------------------------------------------------------------------

joint_names = st.sampled_from(["O", "Q", "A", "B", "C", "P"])
name_values = joint_names | st.sampled_from(["", "X", 3, None, ["A"]])
number_values = (
    st.floats(-10, 10, allow_nan=False)
    | st.integers(-3, 3)
    | st.sampled_from([0, -1, 1, math.nan, math.inf, 1e308, "1", True])
)
point_values = st.lists(number_values, min_size=1, max_size=3) | st.tuples(
    st.floats(-5, 5), st.floats(-5, 5)
).map(list)
FIELD_VALUES = {
    "at": point_values,
    "pivot": name_values,
    "p1": name_values,
    "p2": name_values,
    "line_point": name_values,
    "origin": name_values,
    "toward": name_values,
    "length": number_values,
    "r1": number_values,
    "r2": number_values,
    "r": number_values,
    "ratio": number_values,
    "phase": number_values,
    "line_angle": number_values,
    "u": number_values,
    "v": number_values,
    "assembly": st.sampled_from([1, -1, 0, 2, 1.0, "1"]),
}


@st.composite
def joint_tables(draw):
    kind = draw(st.sampled_from([*JOINT_SPECS, "rr", 7]))
    entry = {"name": draw(name_values), "type": kind}
    names = [f.name for f in JOINT_SPECS.get(kind, ())] or draw(
        st.lists(st.sampled_from(sorted(FIELD_VALUES)), max_size=3)
    )
    for field_name in names:
        if draw(st.integers(0, 9)) == 0:
            continue  # a missing field
        entry[field_name] = draw(FIELD_VALUES[field_name])
    if draw(st.integers(0, 9)) == 0:
        entry[draw(st.sampled_from(sorted(FIELD_VALUES) + ["zzz"]))] = draw(json_like)
    if draw(st.integers(0, 19)) == 0:
        del entry[draw(st.sampled_from(["name", "type"]))]
    return entry


@st.composite
def linkage_documents(draw):
    if draw(st.booleans()):
        joints = draw(st.lists(joint_tables(), max_size=7))
    else:
        # A valid leg, shuffled (forward references and cycles) and a little damaged.
        joints = copy.deepcopy(draw(st.sampled_from(LEG_JOINTS)))
        if draw(st.booleans()):
            joints = draw(st.permutations(joints))
        for _ in range(draw(st.integers(0, 2))):
            i = draw(st.integers(0, len(joints) - 1))
            key = draw(st.sampled_from(sorted(joints[i])))
            joints[i][key] = draw(FIELD_VALUES.get(key, name_values))
    mech = {"family": "linkage", "joints": joints}
    if draw(st.booleans()):
        mech["traced"] = draw(st.lists(name_values, max_size=3) | json_like)
    if draw(st.integers(0, 4)) == 0:
        mech["space"] = draw(st.sampled_from(["plane", "sphere", "", 1]))
    return {"format": "linkwright/1", "mechanism": mech}


LEG_JOINTS = [
    tomllib.loads((EXAMPLES / f"{name}.toml").read_text())["mechanism"]["joints"]
    for name in ("jansen-leg", "klann-leg")
] + [LINKAGE["mechanism"]["joints"]]


@settings(max_examples=400, deadline=None)
@given(linkage_documents())
def test_fuzz_linkage_documents_only_raise_document_error(doc):
    try:
        result = parse_document(doc)
    except DocumentError as exc:
        assert str(exc).startswith("mechanism")
    else:
        assert isinstance(result.mechanism, Linkage)
        assert parse_document(document_to_dict(result)) == result
        # From the mechanism (radians) back to degrees an angle may move by an ulp or two.
        again = parse_document(mechanism_to_dict(result.mechanism))
        assert _close(again.raw["mechanism"], result.raw["mechanism"])


def _close(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) or isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-13, abs_tol=1e-300)
    return a == b

"""Mechanism documents: validation messages, defaults, degrees, round trips, atomic saves."""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import json
import math
import os
import stat
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

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
from linkwright.mechanisms import FourBar, SliderCrank

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"

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
        "mechanism.family: unknown family 'sixbar' (known: fourbar, slidercrank)",
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


@pytest.mark.parametrize(
    "name",
    [
        "crank-rocker",
        "double-crank",
        "rocker-input",
        "triple-rocker",
        "slider-crank",
        "offset-slider-crank",
    ],
)
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


@pytest.mark.parametrize("name", ["crank-rocker", "offset-slider-crank", "triple-rocker"])
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
    assert set(list_examples()) >= {
        "crank-rocker",
        "double-crank",
        "rocker-input",
        "triple-rocker",
        "slider-crank",
        "offset-slider-crank",
    }
    assert load_example("crank-rocker.toml") == load_example("crank-rocker")
    with pytest.raises(DocumentError, match=r"^example: unknown example 'crank-rocke' \(did you"):
        load_example("crank-rocke")


@pytest.mark.parametrize(
    "name",
    [
        "crank-rocker",
        "double-crank",
        "rocker-input",
        "triple-rocker",
        "slider-crank",
        "offset-slider-crank",
    ],
)
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


def test_family_specs_cover_the_mechanism_families():
    from linkwright.mechanisms import FAMILIES

    for family, spec in FAMILY_SPECS.items():
        targets = {t for f in spec.fields for t in f.targets}
        assert targets == {f.name for f in dataclasses.fields(FAMILIES[family])}, family


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

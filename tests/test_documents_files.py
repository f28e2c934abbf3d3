"""Mechanism document files: TOML and JSON parse errors with line and column, round trips through
files and through ``mechanism_to_dict``, and atomic saves (fsync before rename, permissions kept,
nothing torn when the rename fails).
"""

from __future__ import annotations

import json
import math
import os
import stat

import pytest
from documents_helpers import (
    EXAMPLE_NAMES,
    EXAMPLES,
    FOURBAR,
    SLIDER,
    linkage_family,  # noqa: F401  (autouse: the linkage family)
    with_change,
)

from linkwright.io import (
    DocumentError,
    document_to_dict,
    load_document,
    load_example,
    mechanism_to_dict,
    parse_document,
    save_document,
)
from linkwright.mechanisms import FourBar, SliderCrank

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

"""The workbench's library: the SQLite store, its routes, and nothing lost when a save is killed.

Documents are checked against :func:`linkwright.io.parse_document` of what went in (the
validator, independent of the store), names against the naming rule as the issue states it,
and durability against what a killed writer had reported as committed before it died.
"""

from __future__ import annotations

import copy
import json
import math
import os
import random
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
import time
import tomllib
import unicodedata
from pathlib import Path
from urllib.parse import unquote

import pytest
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.io import (
    DocumentError,
    document_to_dict,
    list_examples,
    load_example,
    parse_document,
)
from linkwright.server import create_app
from linkwright.server import library as library_module
from linkwright.server.library import (
    MAX_NAME,
    Library,
    LibraryConflict,
    LibraryError,
    LibraryNotFound,
)
from linkwright.server.limits import TITLE

CRANK_ROCKER = {
    "format": "linkwright/1",
    "title": "Crank-rocker",
    "mechanism": {
        "family": "fourbar",
        "A0": [0.0, 0.0],
        "B0": [3.5, 0.0],
        "crank": 1.0,
        "coupler": 5.0,
        "rocker": 6.02,
        "point": {"u": 2.5, "v": 1.5},
        "assembly": 1,
    },
}
SLIDER = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "slidercrank",
        "A0": [0, 0],
        "crank": 1,
        "rod": 3,
        "line": {"point": [0, 0], "angle": 0},
    },
}


def with_mechanism(doc: dict, **fields: object) -> dict:
    out = copy.deepcopy(doc)
    out["mechanism"].update(fields)
    return out


def canonical(doc: dict) -> dict:
    """What the store must keep for ``doc``: the validator's canonical form."""
    return document_to_dict(parse_document(doc))


@pytest.fixture
def lib(tmp_path: Path) -> Library:
    return Library(tmp_path / "library.sqlite3")


@pytest.fixture
def client(tmp_path: Path) -> TestClient:
    return TestClient(create_app(tmp_path))


# --------------------------------------------------------------------------------------------
# The store
# --------------------------------------------------------------------------------------------


def test_save_get_list_keep_the_canonical_document(lib: Library) -> None:
    saved = lib.save("slider", SLIDER)
    assert saved["name"] == "slider"
    assert saved["family"] == "slidercrank"
    assert saved["title"] is None
    # The default the document left out (assembly) are filled in as the validator fills them.
    assert saved["document"] == canonical(SLIDER)
    assert saved["document"] != SLIDER
    assert saved["created"] == saved["modified"]
    assert abs(saved["created"] - time.time()) < 60
    assert lib.get(saved["id"]) == saved
    other = lib.save("Crank-rocker", CRANK_ROCKER)
    assert other["id"] != saved["id"]
    assert [e["name"] for e in lib.list()] == ["Crank-rocker", "slider"]
    assert "document" not in lib.list()[0]
    assert lib.list()[0]["title"] == "Crank-rocker"


def test_list_is_sorted_by_name_ignoring_case(lib: Library) -> None:
    for name in ["beta", "Alpha", "alpha", "Émile", "gamma", "Beta 2"]:
        lib.save(name, SLIDER)
    assert [e["name"] for e in lib.list()] == [
        "Alpha",
        "alpha",
        "beta",
        "Beta 2",
        "gamma",
        "Émile",
    ]


def test_overwrite_keeps_id_and_creation_time(lib: Library) -> None:
    first = lib.save("mine", SLIDER)
    time.sleep(0.01)
    changed = with_mechanism(CRANK_ROCKER, crank=1.5)
    second = lib.save("mine", changed, overwrite=True)
    assert second["id"] == first["id"]
    assert second["created"] == first["created"]
    assert second["modified"] > first["modified"]
    assert second["family"] == "fourbar"
    assert second["title"] == "Crank-rocker"
    assert second["document"] == canonical(changed)
    assert len(lib.list()) == 1


def test_update_rename_delete(lib: Library) -> None:
    entry = lib.save("mine", SLIDER)
    time.sleep(0.01)
    updated = lib.update(entry["id"], CRANK_ROCKER)
    assert (updated["id"], updated["name"], updated["created"]) == (
        entry["id"],
        "mine",
        entry["created"],
    )
    assert updated["document"] == canonical(CRANK_ROCKER)
    assert updated["modified"] > entry["modified"]
    renamed = lib.rename(entry["id"], "  yours\t")
    assert renamed["name"] == "yours"
    assert renamed["document"] == updated["document"]
    assert lib.rename(entry["id"], "yours") == renamed  # same name: nothing to do
    assert lib.delete(entry["id"]) == entry["id"]
    assert lib.list() == []
    # Ids are never given out again: a stale id in a page cannot open someone else's entry.
    assert lib.save("again", SLIDER)["id"] > entry["id"]


def test_conflicts_change_nothing(lib: Library) -> None:
    a = lib.save("a", SLIDER)
    b = lib.save("b", CRANK_ROCKER)
    with pytest.raises(LibraryConflict, match=r"name: an entry named 'a' already exists \(id 1\)"):
        lib.save("a", CRANK_ROCKER)
    with pytest.raises(LibraryConflict, match="'a' already exists"):
        lib.save(" a ", CRANK_ROCKER)  # the same name once stripped
    with pytest.raises(LibraryConflict, match="'b' already exists"):
        lib.rename(a["id"], "b")
    with pytest.raises(LibraryConflict, match="'b' already exists"):
        lib.import_text(json.dumps(SLIDER), "json", name="b")
    assert isinstance(LibraryConflict("x"), ValueError)
    assert lib.get(a["id"]) == a
    assert lib.get(b["id"]) == b
    assert len(lib.list()) == 2


def test_nfc_names_that_look_the_same_are_the_same(lib: Library) -> None:
    lib.save("Übung", SLIDER)  # composed Ü
    with pytest.raises(LibraryConflict):
        lib.save("U\u0308bung", SLIDER)  # U + combining diaeresis


@pytest.mark.parametrize("entry_id", [99, 0, -1, 2**70, True, "x", "1.0", " 1", "١", None, 1.0])
def test_unknown_ids(lib: Library, entry_id: object) -> None:
    lib.save("one", SLIDER)
    for call in (
        lambda: lib.get(entry_id),
        lambda: lib.update(entry_id, SLIDER),
        lambda: lib.rename(entry_id, "x"),
        lambda: lib.delete(entry_id),
        lambda: lib.export_text(entry_id, "toml"),
    ):
        with pytest.raises(LibraryNotFound, match="library: no entry with id"):
            call()
    assert [e["name"] for e in lib.list()] == ["one"]


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("", "name: must not be empty"),
        (" \t\n ", "name: must not be empty"),
        ("x" * (MAX_NAME + 1), f"name: {MAX_NAME + 1} characters, at most {MAX_NAME} allowed"),
        ("a\nb", r"name: contains U\+000A"),
        ("a\x00b", r"name: contains U\+0000"),
        ("a\u2028b", r"name: contains U\+2028"),
        ("a\ud800b", r"name: contains U\+D800"),
        (3, "name: must be a string, got int"),
        (None, "name: must be a string, got NoneType"),
    ],
)
def test_bad_names(lib: Library, name: object, message: str) -> None:
    with pytest.raises(LibraryError, match=message):
        lib.save(name, SLIDER)  # type: ignore[arg-type]
    entry = lib.save("ok", SLIDER)
    with pytest.raises(LibraryError, match=message):
        lib.rename(entry["id"], name)  # type: ignore[arg-type]
    assert [e["name"] for e in lib.list()] == ["ok"]


def test_longest_name_and_emoji(lib: Library) -> None:
    long = "é" * MAX_NAME
    assert lib.save(f"  {long}  ", SLIDER)["name"] == long
    family = "\U0001f468\u200d\U0001f469\u200d\U0001f467"  # joined by ZERO WIDTH JOINER (Cf)
    assert lib.save(family, SLIDER)["name"] == family


@pytest.mark.parametrize(
    ("mechanism", "field"),
    [
        ({"crank": -1.0}, "mechanism.crank"),
        ({"family": "fourbarr"}, "mechanism.family"),
        ({"B0": [0.0, 0.0]}, "mechanism.B0"),
        ({"crnak": 1.0}, "mechanism: unknown field 'crnak'"),
    ],
)
def test_bad_documents_are_refused_and_nothing_is_stored(
    lib: Library, mechanism: dict, field: str
) -> None:
    bad = with_mechanism(CRANK_ROCKER, **mechanism)
    with pytest.raises(DocumentError, match=f"^document: {field}"):
        lib.save("bad", bad)
    entry = lib.save("good", CRANK_ROCKER)
    with pytest.raises(DocumentError, match=f"^document: {field}"):
        lib.update(entry["id"], bad)
    with pytest.raises(DocumentError, match=f"^text: {field}"):
        lib.import_text(json.dumps(bad), "json")
    assert [e["name"] for e in lib.list()] == ["good"]
    assert lib.get(entry["id"])["document"] == canonical(CRANK_ROCKER)


def test_import_names_after_the_title_and_makes_them_unique(lib: Library) -> None:
    text = json.dumps(CRANK_ROCKER)
    names = [lib.import_text(text, "json")["name"] for _ in range(3)]
    assert names == ["Crank-rocker", "Crank-rocker (2)", "Crank-rocker (3)"]
    assert lib.import_text(json.dumps(SLIDER), "json")["name"] == "untitled"
    assert lib.import_text(json.dumps(SLIDER), "json")["name"] == "untitled (2)"
    named = lib.import_text(json.dumps(SLIDER), "json", default_name="from file")
    assert named["name"] == "from file"
    titled = lib.import_text(json.dumps(CRANK_ROCKER), "json", default_name="from file")
    assert titled["name"] == "Crank-rocker (4)"
    assert lib.import_text(json.dumps(SLIDER), "json", name=" chosen ")["name"] == "chosen"


def test_import_name_from_an_awkward_title(lib: Library) -> None:
    # A title may hold line breaks and controls and be any length; a name may not.
    doc = dict(CRANK_ROCKER, title="  two\nlines\x07 and\u2028more  ")
    assert lib.import_text(json.dumps(doc), "json")["name"] == "two lines and more"
    long = dict(CRANK_ROCKER, title="w" * 500)
    first = lib.import_text(json.dumps(long), "json")["name"]
    second = lib.import_text(json.dumps(long), "json")["name"]
    assert first == "w" * MAX_NAME
    assert second == "w" * (MAX_NAME - 4) + " (2)"
    assert len(second) == MAX_NAME
    blank = dict(CRANK_ROCKER, title=" \n ")
    assert lib.import_text(json.dumps(blank), "json")["name"] == "untitled"


def test_import_formats_and_errors(lib: Library) -> None:
    toml_text = lib.export_text(lib.save("x", CRANK_ROCKER)["id"], "toml")
    assert lib.import_text(toml_text.encode("utf-8"), "TOML")["document"] == canonical(CRANK_ROCKER)
    assert lib.import_text("\ufeff" + toml_text, ".toml")["document"] == canonical(CRANK_ROCKER)
    # No format: guessed from the first character.
    assert lib.import_text(toml_text)["family"] == "fourbar"
    assert lib.import_text("  " + json.dumps(SLIDER))["family"] == "slidercrank"
    assert lib.import_text(b"\xef\xbb\xbf" + json.dumps(SLIDER).encode())["family"] == "slidercrank"
    with pytest.raises(LibraryError, match=r"^text: invalid TOML: .*\(at line 2, column 1\)"):
        lib.import_text("a = 1\n=", "toml")
    with pytest.raises(LibraryError, match=r"^text: invalid JSON: .*\(at line 1, column 2\)"):
        lib.import_text("{,}", "json")
    with pytest.raises(LibraryError, match=r"^text: invalid JSON: duplicate key 'format'"):
        lib.import_text('{"format": "linkwright/1", "format": "x"}', "json")
    with pytest.raises(LibraryError, match=r"^text: invalid JSON: nested too deeply"):
        lib.import_text("[" * 100_000 + "]" * 100_000, "json")
    with pytest.raises(LibraryError, match=r"^my.toml: not UTF-8 text \(byte 0\)"):
        lib.import_text(b"\xff", "toml", source="my.toml")
    with pytest.raises(LibraryError, match=r"^text: not UTF-8 text \(byte 2\)"):
        lib.import_text(b"  \xff{}")
    with pytest.raises(LibraryError, match=r"^format: expected 'toml' or 'json', got 'yaml'"):
        lib.import_text(toml_text, "yaml")
    with pytest.raises(DocumentError, match=r"^text: format: missing required field"):
        lib.import_text("title = 'x'", "toml")
    assert len(lib.list()) == 6


def test_export_text(lib: Library) -> None:
    entry = lib.save("x", CRANK_ROCKER)
    as_toml = lib.export_text(entry["id"], "toml")
    as_json = lib.export_text(entry["id"], "json")
    assert parse_document(tomllib.loads(as_toml)) == parse_document(CRANK_ROCKER)
    assert parse_document(json.loads(as_json)) == parse_document(CRANK_ROCKER)
    assert as_toml.startswith('format = "linkwright/1"\n')
    assert as_json.endswith("}\n")
    with pytest.raises(LibraryError, match=r"^format: expected 'toml' or 'json', got 'csv'"):
        lib.export_text(entry["id"], "csv")


def test_a_library_persists_and_is_a_wal_database(tmp_path: Path) -> None:
    path = tmp_path / "deep" / "er" / "library.sqlite3"
    entry = Library(path).save("kept", CRANK_ROCKER)
    again = Library(path)
    assert again.get(entry["id"]) == entry
    with sqlite3.connect(path) as conn:
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert conn.execute("PRAGMA user_version").fetchone()[0] == 1
        columns = [row[1] for row in conn.execute("PRAGMA table_info(entries)")]
    for column in ("id", "name", "document", "family", "created", "modified"):
        assert column in columns
    assert repr(again) == f"Library({str(path)!r})"


def test_not_a_library(tmp_path: Path) -> None:
    junk = tmp_path / "junk.sqlite3"
    junk.write_bytes(b"this is not a database, it is a text file " * 100)
    with pytest.raises(LibraryError, match="is not a linkwright library"):
        Library(junk)
    newer = tmp_path / "newer.sqlite3"
    with sqlite3.connect(newer) as conn:
        conn.execute("PRAGMA user_version = 7")
    with pytest.raises(LibraryError, match=r"newer linkwright \(schema 7; this one reads 1\)"):
        Library(newer)


def test_writers_in_many_threads_all_land(lib: Library) -> None:
    errors: list[BaseException] = []

    def work(t: int) -> None:
        try:
            for k in range(6):
                doc = with_mechanism(CRANK_ROCKER, crank=1.0 + 0.01 * k)
                lib.save(f"t{t} k{k}", doc)
                lib.save("shared", doc, overwrite=True)
                lib.list()
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(t,)) for t in range(6)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    names = {e["name"] for e in lib.list()}
    assert names == {"shared"} | {f"t{t} k{k}" for t in range(6) for k in range(6)}


# --------------------------------------------------------------------------------------------
# Routes
# --------------------------------------------------------------------------------------------


def test_api_every_verb(client: TestClient) -> None:
    assert client.get("/api/library").json() == []
    r = client.post("/api/library", json={"name": "cr", "document": CRANK_ROCKER})
    assert r.status_code == 200
    entry = r.json()
    assert entry["name"] == "cr"
    assert entry["document"] == canonical(CRANK_ROCKER)
    eid = entry["id"]
    listed = client.get("/api/library").json()
    assert listed == [
        {k: entry[k] for k in ("id", "name", "family", "title", "created", "modified")}
    ]
    assert client.get(f"/api/library/{eid}").json() == entry

    r = client.patch(f"/api/library/{eid}", json={"name": "renamed"})
    assert r.status_code == 200
    assert r.json()["name"] == "renamed"

    slider = client.put(f"/api/library/{eid}", json={"document": SLIDER})
    assert slider.status_code == 200
    assert slider.json()["document"] == canonical(SLIDER)
    assert slider.json()["family"] == "slidercrank"
    assert client.get(f"/api/library/{eid}").json()["document"] == canonical(SLIDER)

    over = client.post(
        "/api/library", json={"name": "renamed", "document": CRANK_ROCKER, "overwrite": True}
    )
    assert over.status_code == 200
    assert over.json()["id"] == eid
    assert over.json()["family"] == "fourbar"

    r = client.get(f"/api/library/{eid}/export", params={"format": "toml"})
    assert r.status_code == 200
    assert r.headers["content-type"] == "application/toml; charset=utf-8"
    assert r.headers["content-disposition"].startswith('attachment; filename="renamed.toml"')
    assert parse_document(tomllib.loads(r.text)) == parse_document(CRANK_ROCKER)
    r = client.get(f"/api/library/{eid}/export", params={"format": "json"})
    assert r.headers["content-type"] == "application/json; charset=utf-8"
    assert parse_document(r.json()) == parse_document(CRANK_ROCKER)
    assert (
        client.get(f"/api/library/{eid}/export")
        .headers["content-type"]
        .startswith("application/toml")
    )

    r = client.post("/api/library/import", files={"file": ("mine.toml", r.text, "text/plain")})
    assert r.status_code == 422  # a .toml file holding JSON is refused, naming the file
    assert r.json()["error"].startswith("mine.toml: invalid TOML")
    text = client.get(f"/api/library/{eid}/export").text
    r = client.post("/api/library/import", files={"file": ("mine.toml", text, "application/toml")})
    assert r.status_code == 200
    assert r.json()["name"] == "Crank-rocker"
    r = client.post("/api/library/import", json={"text": text, "format": "toml", "name": "x"})
    assert r.status_code == 200
    assert r.json()["name"] == "x"

    assert client.delete(f"/api/library/{eid}").json() == {"deleted": eid}
    assert sorted(e["name"] for e in client.get("/api/library").json()) == ["Crank-rocker", "x"]


def test_api_import_multipart_names_and_formats(client: TestClient) -> None:
    untitled = json.dumps(SLIDER).encode()
    r = client.post("/api/library/import", files={"file": ("My slider.JSON", untitled)})
    assert r.status_code == 200
    assert r.json()["name"] == "My slider"  # no title: named after the file
    r = client.post(
        "/api/library/import",
        files={"file": ("upload", untitled)},
        data={"name": "given", "format": "json"},
    )
    assert r.json()["name"] == "given"
    r = client.post("/api/library/import", files={"file": ("noext", untitled)})
    assert r.json()["name"] == "noext"  # JSON guessed from the first character
    r = client.post("/api/library/import", files={"file": ("a.yaml", b"x: 1")})
    assert r.status_code == 422
    assert r.json() == {
        "error": "file: unknown file type '.yaml' (a.yaml): expected .toml or .json"
    }
    bad = json.dumps(with_mechanism(CRANK_ROCKER, rocker=0)).encode()
    r = client.post("/api/library/import", files={"file": ("bad.json", bad)})
    assert r.status_code == 422
    assert r.json()["error"].startswith("bad.json: mechanism.rocker: ")
    r = client.post(
        "/api/library/import", files={"file": ("dup.json", untitled)}, data={"name": "given"}
    )
    assert r.status_code == 409


def test_api_import_json_errors(client: TestClient) -> None:
    cases = [
        ({"format": "toml"}, "text: missing required field"),
        ({"text": 3}, "text: must be a string, got int"),
        ({"text": "", "format": 1}, "format: expected 'toml' or 'json', got 'int'"),
        ({"text": "x", "extra": 1}, "body: unknown field 'extra'"),
        ({"text": json.dumps(SLIDER), "name": 5}, "name: must be a string, got int"),
        ({"text": json.dumps(SLIDER), "name": "a\nb"}, "name: contains U+000A"),
    ]
    for body, message in cases:
        r = client.post("/api/library/import", json=body)
        assert r.status_code == 422, body
        assert r.json()["error"].startswith(message), r.json()
    r = client.post("/api/library/import", json=[1])
    assert r.json()["error"].startswith("body: expected a JSON object")
    r = client.post(
        "/api/library/import", content=b"{", headers={"content-type": "application/json"}
    )
    assert r.json() == {"error": "body: not valid JSON"}
    r = client.post("/api/library/import", content=b"x", headers={"content-type": "text/plain"})
    assert r.status_code == 422
    assert r.json()["error"].startswith("body: expected a multipart form")
    assert client.get("/api/library").json() == []
    # A blank name (an empty box on the page) means "name it after the document".
    for blank in (None, "", "  "):
        r = client.post("/api/library/import", json={"text": json.dumps(SLIDER), "name": blank})
        assert r.status_code == 200
    names = [e["name"] for e in client.get("/api/library").json()]
    assert names == ["untitled", "untitled (2)", "untitled (3)"]


def test_api_conflicts_are_409(client: TestClient) -> None:
    a = client.post("/api/library", json={"name": "a", "document": SLIDER}).json()
    client.post("/api/library", json={"name": "b", "document": SLIDER})
    r = client.post("/api/library", json={"name": "a", "document": CRANK_ROCKER})
    assert r.status_code == 409
    assert r.json() == {"error": f"name: an entry named 'a' already exists (id {a['id']})"}
    r = client.patch(f"/api/library/{a['id']}", json={"name": "b"})
    assert r.status_code == 409
    assert r.json()["error"].startswith("name: an entry named 'b' already exists")
    assert client.get(f"/api/library/{a['id']}").json() == a


@pytest.mark.parametrize("eid", ["999", "0", "abc", "-1", "99999999999999999999999"])
def test_api_unknown_ids_are_404(client: TestClient, eid: str) -> None:
    client.post("/api/library", json={"name": "a", "document": SLIDER})
    for method, path, body in [
        ("GET", f"/api/library/{eid}", None),
        ("PATCH", f"/api/library/{eid}", {"name": "x"}),
        ("PUT", f"/api/library/{eid}", {"document": SLIDER}),
        ("DELETE", f"/api/library/{eid}", None),
        ("GET", f"/api/library/{eid}/export", None),
    ]:
        r = client.request(method, path, json=body)
        assert r.status_code == 404, (method, path)
        assert r.json()["error"].startswith("library: no entry with id"), r.json()


def test_api_bad_documents_are_422_naming_the_field(client: TestClient) -> None:
    good = client.post("/api/library", json={"name": "g", "document": CRANK_ROCKER}).json()
    cases = [
        (with_mechanism(CRANK_ROCKER, coupler="long"), "document: mechanism.coupler: "),
        (with_mechanism(CRANK_ROCKER, family="hexbar"), "document: mechanism.family: "),
        ({"mechanism": CRANK_ROCKER["mechanism"]}, "document: format: missing"),
        (dict(CRANK_ROCKER, title=5), "document: title: must be a string"),
    ]
    for doc, message in cases:
        for method, path, body in [
            ("POST", "/api/library", {"name": "n", "document": doc}),
            ("PUT", f"/api/library/{good['id']}", {"document": doc}),
        ]:
            r = client.request(method, path, json=body)
            assert r.status_code == 422
            assert r.json()["error"].startswith(message), r.json()
    for body, field in [
        ({"document": CRANK_ROCKER}, "name"),
        ({"name": "n", "document": [1]}, "document"),
        ({"name": "n"}, "document"),
    ]:
        r = client.post("/api/library", json=body)
        assert r.status_code == 422
        assert r.json()["error"].startswith(field), r.json()
    r = client.post("/api/library", json={"name": "a\tb", "document": CRANK_ROCKER})
    assert r.json() == {"error": "name: contains U+0009 (a control character or line break)"}
    r = client.get(f"/api/library/{good['id']}/export", params={"format": "dxf"})
    assert r.status_code == 422
    assert r.json() == {"error": "format: expected 'toml' or 'json', got 'dxf'"}
    assert [e["name"] for e in client.get("/api/library").json()] == ["g"]
    assert client.get(f"/api/library/{good['id']}").json() == good


def test_api_export_names_the_file_in_unicode(client: TestClient) -> None:
    name = 'Kurbelschwinge "Übung" / 2'
    eid = client.post("/api/library", json={"name": name, "document": SLIDER}).json()["id"]
    disposition = client.get(f"/api/library/{eid}/export").headers["content-disposition"]
    ascii_part, utf8_part = disposition.split("; filename*=UTF-8''")
    assert ascii_part == 'attachment; filename="Kurbelschwinge _bung_ _ 2.toml"'
    # The UTF-8 name keeps its letters and quotes, not its slash (never a path in a file name).
    assert unquote(utf8_part) == name.replace("/", "_") + ".toml"


@pytest.mark.parametrize("example", list_examples())
def test_every_example_round_trips_through_the_library(client: TestClient, example: str) -> None:
    original = load_example(example)
    doc = document_to_dict(original)
    entry = client.post("/api/library", json={"name": example, "document": doc}).json()
    got = client.get(f"/api/library/{entry['id']}").json()
    assert parse_document(got["document"]) == original
    assert got["family"] == original.family
    assert got["title"] == original.title
    for fmt in ("toml", "json"):
        text = client.get(f"/api/library/{entry['id']}/export", params={"format": fmt}).text
        files = {"file": (f"{example}.{fmt}", text.encode("utf-8"))}
        imported = client.post("/api/library/import", files=files).json()
        assert parse_document(imported["document"]) == original
        assert imported["name"].startswith(original.title or example)


# --------------------------------------------------------------------------------------------
# Properties
# --------------------------------------------------------------------------------------------

REFUSED = {"Cc", "Cs", "Zl", "Zp"}


# Bidirectional controls (Unicode's Bidi_Control property): they can make a name read as
# something it is not; and what draws nothing: format marks, combining marks with no base,
# spaces, and the Hangul and Braille blanks that fonts draw empty.
BIDI = (
    set("\u061c\u200e\u200f")
    | {chr(c) for c in range(0x202A, 0x202F)}
    | {chr(c) for c in range(0x2066, 0x206A)}
)
SHOWS_NOTHING = {"Cf", "Mn", "Me", "Zs"}
BLANK = set("\u115f\u1160\u3164\uffa0\u2800")


def name_rule(text: str) -> str | None:
    """The issues' naming rule, written out: the stored name, or None if refused."""
    name = unicodedata.normalize("NFC", text).strip()
    if not 1 <= len(name) <= MAX_NAME:
        return None
    if any(unicodedata.category(ch) in REFUSED or ch in BIDI for ch in name):
        return None
    if all(unicodedata.category(ch) in SHOWS_NOTHING or ch in BLANK for ch in name):
        return None
    return name


names = st.one_of(
    st.text(max_size=20),
    st.text(st.characters(codec="utf-8"), min_size=1, max_size=30),
    st.builds(
        lambda pad, core, tail: pad + core + tail,
        st.sampled_from(["", " ", "\t", "\n ", "\u3000"]),
        st.text(st.characters(exclude_categories=("Cc", "Cs", "Zl", "Zp")), max_size=210),
        st.sampled_from(["", " ", "\r\n", "\x85"]),
    ),
)


@settings(max_examples=60, deadline=None)
@given(name=names)
def test_random_names_through_the_api(api_client: TestClient, name: str) -> None:
    expected = name_rule(name)
    r = api_client.post("/api/library", json={"name": name, "document": SLIDER, "overwrite": True})
    if expected is None:
        assert r.status_code == 422
        assert r.json()["error"].startswith("name: ")
        return
    assert r.status_code == 200, r.json()
    entry = r.json()
    assert entry["name"] == expected
    assert api_client.get(f"/api/library/{entry['id']}").json()["name"] == expected
    assert expected in {e["name"] for e in api_client.get("/api/library").json()}
    renamed = api_client.patch(f"/api/library/{entry['id']}", json={"name": name + " ·"})
    if name_rule(name + " ·") is None:
        assert renamed.status_code == 422
        assert renamed.json()["error"].startswith("name: ")
    else:
        assert renamed.json()["name"] == name_rule(name + " ·")
    assert api_client.delete(f"/api/library/{entry['id']}").status_code == 200


@pytest.fixture(scope="module")
def api_client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    return TestClient(create_app(tmp_path_factory.mktemp("library-api")))


@pytest.fixture(scope="module")
def shared_lib(tmp_path_factory: pytest.TempPathFactory) -> Library:
    return Library(tmp_path_factory.mktemp("library-store") / "library.sqlite3")


coordinate = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False)
length = st.floats(1e-3, 1e3, allow_subnormal=False)
fourbars = st.builds(
    lambda a0, b0, crank, coupler, rocker, u, v, assembly, title: {
        "format": "linkwright/1",
        **({} if title is None else {"title": title}),
        "mechanism": {
            "family": "fourbar",
            "A0": list(a0),
            "B0": list(b0),
            "crank": crank,
            "coupler": coupler,
            "rocker": rocker,
            "point": {"u": u, "v": v},
            "assembly": assembly,
        },
    },
    st.tuples(coordinate, coordinate),
    st.tuples(coordinate, coordinate),
    length,
    length,
    length,
    coordinate,
    coordinate,
    st.sampled_from([1, -1]),
    st.none() | st.text(max_size=40),
    # Pivots closer than 1e-9 of the linkage's size (at most 1e3 here) coincide for the parser.
).filter(lambda d: math.dist(d["mechanism"]["A0"], d["mechanism"]["B0"]) > 1e-5)


@settings(max_examples=40, deadline=None)
@given(doc=fourbars)
def test_random_fourbars_round_trip(shared_lib: Library, doc: dict) -> None:
    expected = parse_document(doc)
    entry = shared_lib.save("random", doc, overwrite=True)
    got = shared_lib.get(entry["id"])
    assert got["document"] == document_to_dict(expected)
    assert (got["family"], got["title"]) == ("fourbar", expected.title)
    for fmt in ("toml", "json"):
        text = shared_lib.export_text(entry["id"], fmt)
        loaded = tomllib.loads(text) if fmt == "toml" else json.loads(text)
        assert parse_document(loaded) == expected
        imported = shared_lib.import_text(text, fmt)
        assert parse_document(imported["document"]) == expected
        assert imported["name"] == name_rule(imported["name"])
        shared_lib.delete(imported["id"])


# --------------------------------------------------------------------------------------------
# Durability: a writer killed mid-save loses nothing it had committed and leaves nothing torn
# --------------------------------------------------------------------------------------------

WRITER = textwrap.dedent(
    """
    import copy, importlib.util, json, sys

    # The store's module alone, without the web application around it (matplotlib and the
    # rest), so that each of the writers starts in well under a second.
    spec = importlib.util.spec_from_file_location("library_under_test", sys.argv[4])
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)

    path, run = sys.argv[1], int(sys.argv[2])
    base = json.loads(sys.argv[3])
    lib = module.Library(path)

    fill_step, fill_period = int(sys.argv[5]), int(sys.argv[6])

    def document(k):
        # Each revision larger than the last (up to the title's limit, ~2 kB), so a torn
        # write would show as a broken document rather than pass unnoticed.
        doc = copy.deepcopy(base)
        doc["title"] = f"rev {k} " + "·" * (fill_step * (k % fill_period))
        doc["mechanism"]["crank"] = 1.0 + (k % 50) / 100
        return doc

    k = 0
    for entry in lib.list():
        if entry["name"] == "growing":
            k = int(entry["title"].split()[1])
    print("ready", flush=True)
    while True:
        k += 1
        entry = lib.save("growing", document(k), overwrite=True)
        print("G", entry["id"], k, flush=True)
        if k % 3 == 0:
            entry = lib.save(f"run {run} rev {k}", document(k))
            print("N", entry["id"], entry["name"], flush=True)
    """
)
# The writer's titles grow by FILL_STEP characters a revision and wrap before the title's limit
# (a title over it is refused, which would end the writer before it is killed).
FILL_STEP = 7
FILL_PERIOD = (TITLE.value - len("rev 1000000 ")) // FILL_STEP


def test_nothing_lost_when_a_writer_is_killed_mid_save(tmp_path: Path) -> None:
    path = tmp_path / "library.sqlite3"
    rng = random.Random()
    growing: dict[int, int] = {}  # id -> newest revision reported committed
    created: dict[int, str] = {}  # id -> name
    reported = 0
    base = json.dumps(CRANK_ROCKER)
    library_source = str(Path(library_module.__file__))
    for run in range(5):
        out = tmp_path / f"writer{run}.out"
        err = tmp_path / f"writer{run}.err"
        argv = [str(path), str(run), base, library_source, str(FILL_STEP), str(FILL_PERIOD)]
        with open(out, "wb") as stdout, open(err, "wb") as stderr:
            child = subprocess.Popen(
                [sys.executable, "-c", WRITER, *argv],
                stdout=stdout,
                stderr=stderr,
            )
        try:
            deadline = time.monotonic() + 60
            while not out.read_bytes().startswith(b"ready\n"):
                assert child.poll() is None, err.read_text()
                assert time.monotonic() < deadline, "the writer did not start"
                time.sleep(0.005)
            delay = rng.uniform(0.05, 0.3)
            time.sleep(delay)
            assert child.poll() is None, err.read_text()
            os.kill(child.pid, signal.SIGKILL)
        finally:
            child.kill()
            child.wait()
        assert child.returncode == -signal.SIGKILL

        # Only whole lines count: the kill may cut the last one short.
        for line in out.read_text().splitlines(keepends=True)[1:]:
            if not line.endswith("\n"):
                continue
            kind, eid, rest = line.split(maxsplit=2)
            if kind == "G":
                growing[int(eid)] = max(growing.get(int(eid), 0), int(rest))
            else:
                created[int(eid)] = rest.strip()
            reported += 1

        with sqlite3.connect(path) as conn:
            assert conn.execute("PRAGMA integrity_check").fetchall() == [("ok",)]
        lib = Library(path)
        entries = {e["id"]: e for e in lib.list()}
        for eid in entries:
            got = lib.get(eid)
            doc = parse_document(got["document"])
            assert (doc.family, doc.title) == (got["family"], got["title"])
            assert doc.title is not None
            k = int(doc.title.split()[1])
            assert len(doc.title) == len(f"rev {k} ") + FILL_STEP * (k % FILL_PERIOD), (
                f"run {run}: torn"
            )
        assert len(growing) <= 1
        for eid, revision in growing.items():
            assert entries[eid]["name"] == "growing", f"run {run} (killed after {delay:.3f} s)"
            assert int(entries[eid]["title"].split()[1]) >= revision
        for eid, name in created.items():
            assert entries[eid]["name"] == name, f"run {run} (killed after {delay:.3f} s)"
        assert set(entries) >= set(growing) | set(created)
    assert reported > 0, "no writer committed anything before it was killed"

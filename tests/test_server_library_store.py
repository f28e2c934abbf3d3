"""The workbench's library store (SQLite): saving, listing, renaming, importing and exporting, and
nothing lost when a save is killed.

Documents are checked against the validator's canonical form of what went in
(tests/server_library_helpers.py), and durability against what a killed writer had reported as
committed before it died.
"""

from __future__ import annotations

import json
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
from pathlib import Path

import pytest
from server_library_helpers import CRANK_ROCKER, SLIDER, canonical, with_mechanism

from linkwright.io import (
    DocumentError,
    parse_document,
)
from linkwright.server import library as library_module
from linkwright.server.library import (
    MAX_NAME,
    Library,
    LibraryConflict,
    LibraryError,
    LibraryNotFound,
)
from linkwright.server.limits import TITLE


@pytest.fixture
def lib(tmp_path: Path) -> Library:
    return Library(tmp_path / "library.sqlite3")


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

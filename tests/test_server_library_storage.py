"""The library tells the truth about its file, and refuses names that lie (issue 20).

- A damaged page (bytes overwritten in the middle of ``library.sqlite3``) is reported as a
  damaged library, with what to do, by the list and by a save alike, and the save is refused:
  nothing is written into a damaged file. Found whether the damage is there when the server
  starts or happens while it runs.
- A full disk answers 507 "disk full" for saves, renames and imports, and a delete always
  works. Tried with SQLite's ``max_page_count`` (the file may not grow), with the error a full
  disk raises injected where even the delete's log cannot be written, and, where this process
  may mount one (root), on a real 4 MB file system filled to the last byte.
- A library that cannot be written is opened read-only: lists, loads and exports work, and
  every change is refused as "the library is read-only" (409), not "not a linkwright library".
  Tried on a folder without write permission, or (for root, whom permissions do not stop) a
  file system mounted read-only.
- Names with bidirectional controls, or that show nothing, are refused in one line.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from linkwright.io import document_to_dict, load_example
from linkwright.server import create_app, store
from linkwright.server.library import Library


def _doc(title: str = "Crank-rocker") -> dict:
    doc = document_to_dict(load_example("crank-rocker"))
    doc["title"] = title
    return doc


def _error(response, status: int) -> str:
    assert response.status_code == status, response.text
    body = response.json()
    assert set(body) == {"error"} and "\n" not in body["error"], body
    return body["error"]


def _client(root: Path) -> TestClient:
    return TestClient(create_app(root))


def _fill(client: TestClient, n: int = 40) -> list[int]:
    ids = []
    for i in range(n):
        r = client.post(
            "/api/library", json={"name": f"entry {i} " + "x" * 150, "document": _doc()}
        )
        assert r.status_code == 200, r.text
        ids.append(r.json()["id"])
    return ids


def _damage(path: Path) -> None:
    """Fold the log into the file, then overwrite 4 KB in its middle (the entries' pages)."""
    with contextlib.closing(sqlite3.connect(path)) as conn:
        conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    size = path.stat().st_size
    assert size > 16_384, size
    with path.open("r+b") as f:
        f.seek(size // 2)
        f.write(b"\xa5" * 4096)


# --------------------------------------------------------------------------------------------
# Damaged
# --------------------------------------------------------------------------------------------


def _damaged_everywhere(client: TestClient, path: Path) -> None:
    listed = _error(client.get("/api/library"), 500)
    assert listed.startswith(f"library: {path} is damaged (")
    assert "move the file aside" in listed and ".recover" in listed
    saved = _error(client.post("/api/library", json={"name": "new", "document": _doc()}), 500)
    assert saved == listed
    assert _error(client.delete("/api/library/1"), 500) == listed
    assert _error(client.get("/api/library/1"), 500) == listed


def test_a_library_damaged_while_serving_is_reported_and_takes_no_save(tmp_path: Path) -> None:
    client = _client(tmp_path)
    _fill(client)
    path = tmp_path / "library.sqlite3"
    _damage(path)
    before = path.read_bytes()
    # The save comes first here: it must not be accepted into the damaged file.
    saved = _error(client.post("/api/library", json={"name": "new", "document": _doc()}), 500)
    assert "is damaged" in saved
    _damaged_everywhere(client, path)
    assert path.read_bytes() == before


def test_a_library_damaged_before_the_server_starts_is_reported(tmp_path: Path) -> None:
    _fill(_client(tmp_path))
    path = tmp_path / "library.sqlite3"
    _damage(path)
    app = create_app(tmp_path)
    assert "DAMAGED" in app.state.library.state_note()
    _damaged_everywhere(TestClient(app), path)


def test_a_file_that_is_no_database_is_still_not_a_library(tmp_path: Path) -> None:
    (tmp_path / "library.sqlite3").write_bytes(b"these are my notes, not a database" * 200)
    with pytest.raises(ValueError, match="is not a linkwright library"):
        create_app(tmp_path)


# --------------------------------------------------------------------------------------------
# Full
# --------------------------------------------------------------------------------------------


def test_a_file_that_may_not_grow_refuses_saves_and_a_delete_makes_room(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    client = _client(tmp_path)
    ids = _fill(client, 5)
    real = store.Store.connect

    def connect(self: store.Store) -> sqlite3.Connection:
        # SQLite's own harness for a full disk: the file may not grow past its size now.
        conn = real(self)
        pages = conn.execute("PRAGMA page_count").fetchone()[0]
        conn.execute(f"PRAGMA max_page_count = {pages}")
        return conn

    monkeypatch.setattr(store.Store, "connect", connect)
    big = _doc("t" * 1000)
    saves = [
        client.post("/api/library", json={"name": f"more {i} " + "z" * 180, "document": big})
        for i in range(30)
    ]
    refused = [r for r in saves if r.status_code != 200]
    assert refused, "the capped file never filled"
    message = _error(refused[0], 507)
    assert message.startswith("library: disk full:") and "deleting always works" in message
    # Deletes free pages: the save refused a moment ago now fits.
    for entry in ids:
        assert client.delete(f"/api/library/{entry}").status_code == 200
    name = "after " + "z" * 180
    assert client.post("/api/library", json={"name": name, "document": big}).status_code == 200


class _FullDisk(sqlite3.Connection):
    """A connection on a disk with no byte left: every write statement fails as SQLite's does
    there (while :attr:`writes_fail`)."""

    writes_fail = True

    def execute(self, sql: str, *args):  # type: ignore[override]
        verb = sql.lstrip().split(None, 1)[0].upper()
        if self.writes_fail and verb in ("INSERT", "UPDATE", "DELETE"):
            raise sqlite3.OperationalError("database or disk is full")
        return super().execute(sql, *args)


def _on_a_full_disk(monkeypatch: pytest.MonkeyPatch, writes_fail) -> None:
    def connect(self: store.Store) -> sqlite3.Connection:
        conn = sqlite3.connect(self.path, timeout=30, isolation_level=None, factory=_FullDisk)
        conn.writes_fail = writes_fail()  # type: ignore[attr-defined]
        return conn

    monkeypatch.setattr(store.Store, "connect", connect)


def test_every_change_on_a_full_disk_says_disk_full(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    client = _client(tmp_path)
    (entry,) = _fill(client, 1)
    _on_a_full_disk(monkeypatch, lambda: True)
    text = json.dumps(_doc("imported"))
    for r in (
        client.post("/api/library", json={"name": "new", "document": _doc()}),
        client.patch(f"/api/library/{entry}", json={"name": "renamed"}),
        client.put(f"/api/library/{entry}", json={"document": _doc("other")}),
        client.post("/api/library/import", json={"text": text}),
    ):
        assert _error(r, 507).startswith("library: disk full: the change was not saved")
    # Reads go on.
    assert [e["id"] for e in client.get("/api/library").json()] == [entry]


def test_a_delete_works_when_not_even_its_log_fits(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    client = _client(tmp_path)
    ids = _fill(client, 3)
    reserve = tmp_path / "library.sqlite3-reserve"
    assert reserve.stat().st_size == store.RESERVE_BYTES
    # The disk is full until the reserve's space is given back.
    _on_a_full_disk(monkeypatch, reserve.exists)
    assert client.delete(f"/api/library/{ids[0]}").json() == {"deleted": ids[0]}
    assert [e["id"] for e in client.get("/api/library").json()] == ids[1:]
    # Given up for the delete, the reserve is taken back while there is space for it.
    assert reserve.exists()


@contextlib.contextmanager
def _mounted(tmp_path: Path, options: str) -> Iterator[Path]:
    """A tmpfs mounted at a new folder (skips where this process may not mount)."""
    point = tmp_path / "mnt"
    point.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a small file system needs root")
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(point)], capture_output=True
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    try:
        yield point
    finally:
        subprocess.run(["umount", "-l", str(point)], check=False)


def test_a_real_full_disk(tmp_path: Path) -> None:
    with _mounted(tmp_path, "size=4m") as root:
        client = _client(root)
        ids = _fill(client, 3)
        # Fill the disk to its last byte.
        with (root / "filler").open("wb", buffering=0) as f, contextlib.suppress(OSError):
            while True:
                f.write(b"\0" * 4096)
        full = client.post("/api/library", json={"name": "more", "document": _doc("t" * 900)})
        codes = [full.status_code]
        for i in range(20):
            if codes[-1] != 200:
                break
            r = client.post("/api/library", json={"name": f"m{i}", "document": _doc("t" * 900)})
            codes.append(r.status_code)
            full = r
        assert "disk full" in _error(full, 507)
        # Deleting works on the full disk, every time.
        for entry in ids:
            assert client.delete(f"/api/library/{entry}").status_code == 200, entry
        names = {e["name"] for e in client.get("/api/library").json()}
        assert not names & {f"entry {i} " + "x" * 150 for i in range(3)}
        client.close()


# --------------------------------------------------------------------------------------------
# Read-only
# --------------------------------------------------------------------------------------------


def _read_only_checks(root: Path, entry: int) -> None:
    app = create_app(root)
    assert app.state.library.read_only and "read-only" in app.state.library.state_note()
    client = TestClient(app)
    assert [e["id"] for e in client.get("/api/library").json()] == [entry]
    assert client.get(f"/api/library/{entry}").json()["document"] == _doc()
    assert client.get(f"/api/library/{entry}/export?format=json").status_code == 200
    writes = [
        client.post("/api/library", json={"name": "new", "document": _doc()}),
        client.patch(f"/api/library/{entry}", json={"name": "renamed"}),
        client.put(f"/api/library/{entry}", json={"document": _doc("other")}),
        client.delete(f"/api/library/{entry}"),
        client.post("/api/library/import", json={"text": "{}", "format": "json"}),
    ]
    for r in writes[:4]:
        message = _error(r, 409)
        assert message.startswith("library: the library is read-only (")
    # An import of a bad document says what is wrong with the document first.
    assert writes[4].status_code in (409, 422)


def test_a_read_only_library_is_served_read_only(tmp_path: Path) -> None:
    root = tmp_path / "data"
    entry = _client(root).post("/api/library", json={"name": "a", "document": _doc()}).json()
    if os.geteuid() != 0:
        for path in (root, *root.iterdir()):
            path.chmod(0o555 if path.is_dir() else 0o444)
        try:
            _read_only_checks(root, entry["id"])
        finally:
            for path in (root, *root.iterdir()):
                path.chmod(0o755 if path.is_dir() else 0o644)
        return
    # Root writes through permissions: a file system mounted read-only stops it.
    with _mounted(tmp_path, "size=4m") as mounted:
        shutil.copytree(root, mounted / "data")
        done = subprocess.run(["mount", "-o", "remount,ro", str(mounted)], capture_output=True)
        if done.returncode != 0:
            pytest.skip("cannot remount read-only here")
        _read_only_checks(mounted / "data", entry["id"])


def test_a_library_that_cannot_be_created_is_empty_and_read_only(tmp_path: Path) -> None:
    if os.geteuid() == 0:
        with _mounted(tmp_path, "size=1m,mode=0555") as mounted:
            subprocess.run(["mount", "-o", "remount,ro", str(mounted)], check=True)
            lib = Library(mounted / "library.sqlite3")
    else:
        folder = tmp_path / "ro"
        folder.mkdir(mode=0o555)
        lib = Library(folder / "library.sqlite3")
    assert lib.read_only and lib.list() == []
    with pytest.raises(store.LibraryReadOnly, match="the library is read-only"):
        lib.save("a", _doc())


# --------------------------------------------------------------------------------------------
# Names that lie
# --------------------------------------------------------------------------------------------

LYING = {
    "report\u202egpj.exe": "U+202E (a bidirectional control",
    "left\u2066mark": "U+2066 (a bidirectional control",
    "a\u200fb": "U+200F (a bidirectional control",
    "\u200b\u200b": "shows nothing",
    "\u200d\ufeff\u2060": "shows nothing",
    "\u3164": "shows nothing",
    "\u0301\u0301": "shows nothing",
}


@pytest.mark.parametrize("name", list(LYING))
def test_names_that_lie_are_refused(tmp_path: Path, name: str) -> None:
    client = _client(tmp_path)
    r = client.post("/api/library", json={"name": name, "document": _doc()})
    message = _error(r, 422)
    assert message.startswith("name: ") and LYING[name] in message
    saved = client.post("/api/library", json={"name": "fine", "document": _doc()}).json()
    assert LYING[name] in _error(
        client.patch(f"/api/library/{saved['id']}", json={"name": name}), 422
    )


def test_real_names_with_joiners_and_marks_are_kept(tmp_path: Path) -> None:
    client = _client(tmp_path)
    for name in ("family \U0001f468\u200d\U0001f469\u200d\U0001f467", "می\u200cخواهم", "e\u0301"):
        assert (
            client.post("/api/library", json={"name": name, "document": _doc()}).status_code == 200
        )


def test_an_import_titled_with_controls_is_named_without_them(tmp_path: Path) -> None:
    client = _client(tmp_path)
    text = json.dumps(_doc("report\u202egpj.exe"))
    assert client.post("/api/library/import", json={"text": text}).json()["name"] == (
        "reportgpj.exe"
    )
    text = json.dumps(_doc("\u200b\u200b"))
    assert client.post("/api/library/import", json={"text": text}).json()["name"] == "untitled"

"""The workbench's library of saved mechanisms: one SQLite file in the data directory.

:class:`Library` keeps named, validated documents (the :func:`~linkwright.io.document_to_dict`
form) with their family, title and creation and modification times. Nothing a stopped server
leaves behind can be half a save: the database runs in WAL mode with ``synchronous=FULL``, and
every write (save, overwrite, rename, delete, import) is one ``BEGIN IMMEDIATE … COMMIT``
transaction, so a process killed mid-save leaves the library as it was before that save or
after it, and a save that returned is on disk. Each call opens its own connection, so one
:class:`Library` may be used from any number of threads (FastAPI runs sync routes in a thread
pool); writers queue on SQLite's lock.

:data:`router` serves the library under ``/library`` (app.py mounts it at ``/api``; the
contract is in the workbench's API notes): list, save, get, rename, overwrite, delete, import
a TOML or JSON file, export one.

Errors: :class:`LibraryError` (a ``ValueError``: a bad name, format or file; answered 422),
:class:`LibraryConflict` (a name already taken; 409), :class:`LibraryNotFound` (a
``LookupError``: no such entry; 404). An invalid document raises
:class:`~linkwright.io.DocumentError` (also a ``ValueError``) naming its field.

The file itself may stop a request (:mod:`linkwright.server.store`): a damaged file is
reported as damaged, with what to do, by every request (500), reads and writes alike, so that
nothing is saved into it; a full disk refuses changes with "disk full" (507), while a delete
always works; a library that cannot be written (a read-only folder or file system) is opened
read-only: lists, loads and exports work, and changes are refused as read-only (409).
"""

from __future__ import annotations

import json
import os
import re
import sqlite3
import time
from collections.abc import Mapping
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, File, Form, Query, Request, UploadFile
from fastapi import Path as PathParam
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field
from starlette.concurrency import run_in_threadpool

from linkwright.server import store
from linkwright.server.guard import attachment, shown_filename
from linkwright.server.library_entries import (
    FORMATS,
    MAX_NAME,
    MAX_TEXT,
    LibraryConflict,
    LibraryError,
    LibraryNotFound,
    check_format,
    check_id,
    check_name,
    decode_text,
    dumps_document,
    file_text,
    name_from_title,
    parse_text,
    sniff_format,
    validated_document,
)
from linkwright.server.schema import DocumentBody, document_examples, examples

__all__ = [
    "FORMATS",
    "MAX_NAME",
    "MAX_TEXT",
    "Library",
    "LibraryConflict",
    "LibraryError",
    "LibraryNotFound",
    "router",
]


_MEDIA_TYPES = {"toml": "application/toml", "json": "application/json"}

_SCHEMA = 1
_TABLE = """CREATE TABLE IF NOT EXISTS entries (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL UNIQUE,
    document TEXT NOT NULL,
    family TEXT NOT NULL,
    title TEXT,
    created REAL NOT NULL,
    modified REAL NOT NULL)"""
_BUSY_SECONDS = 30.0


_SUFFIXED = re.compile(r"^(?P<base>.*) \((?P<n>[0-9]+)\)$")


# --------------------------------------------------------------------------------------------
# The store
# --------------------------------------------------------------------------------------------


class Library:
    """Named mechanism documents in one SQLite file (created on first use).

    Parameters
    ----------
    path : the database file; missing parent folders are created.

    Raises
    ------
    LibraryError
        If ``path`` exists but is not a linkwright library (or is one from a newer version).
        A damaged library, or one that cannot be written, is opened all the same: its state
        is :attr:`damage` and :attr:`read_only`, and each request is answered accordingly.

    Notes
    -----
    Entries are plain mappings: ``id`` (int, never reused), ``name``, ``family``, ``title``
    (the document's, or None), ``created`` and ``modified`` (seconds since the epoch), and, from
    every method but :meth:`list`, ``document`` (the validated document, every default filled).

    Examples
    --------
    >>> import tempfile
    >>> from linkwright.io import document_to_dict, load_example
    >>> lib = Library(Path(tempfile.mkdtemp()) / "library.sqlite3")
    >>> doc = document_to_dict(load_example("crank-rocker"))
    >>> entry = lib.save("mine", doc)
    >>> entry["id"], entry["family"], entry["document"] == doc
    (1, 'fourbar', True)
    >>> lib.save("mine", doc)
    Traceback (most recent call last):
    ...
    linkwright.server.library_entries.LibraryConflict: name: an entry named 'mine' already exists
    (id 1)
    >>> lib.rename(1, "  Grashof  ")["name"]
    'Grashof'
    >>> [(e["id"], e["name"]) for e in lib.list()]
    [(1, 'Grashof')]
    >>> print(lib.export_text(1, "toml").splitlines()[1])
    title = "Crank-rocker (paper 003, Table 1)"
    >>> lib.delete(1)
    1
    >>> lib.get(1)
    Traceback (most recent call last):
    ...
    linkwright.server.library_entries.LibraryNotFound: library: no entry with id 1
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._store = store.Store(self.path, self._prepare, _BUSY_SECONDS)
        except sqlite3.DatabaseError as exc:
            raise LibraryError(
                f"library: {self.path} is not a linkwright library ({exc})"
            ) from None

    def __repr__(self) -> str:
        return f"Library({str(self.path)!r})"

    @property
    def read_only(self) -> bool:
        """Whether the library cannot be written (lists and loads work, changes are refused)."""
        return self._store.read_only

    @property
    def damage(self) -> str | None:
        """Why the library is damaged (what every request is answered), or None."""
        return self._store.damage

    def state_note(self) -> str:
        """A few words on the library's state for the line ``linkwright serve`` prints."""
        return self._store.state_note()

    def _prepare(self, conn: sqlite3.Connection) -> None:
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        if version > _SCHEMA:
            raise LibraryError(
                f"library: {self.path} was written by a newer linkwright "
                f"(schema {version}; this one reads {_SCHEMA})"
            )
        conn.execute(_TABLE)
        conn.execute(f"PRAGMA user_version={_SCHEMA}")

    def _transaction(self, write: bool) -> AbstractContextManager[sqlite3.Connection]:
        """One connection and one transaction (:meth:`linkwright.server.store.Store.
        transaction`): committed when the block ends, rolled back if it raises."""
        return self._store.transaction(write)

    @staticmethod
    def _entry(row: sqlite3.Row, document: bool = True) -> dict[str, Any]:
        out: dict[str, Any] = {
            "id": row["id"],
            "name": row["name"],
            "family": row["family"],
            "title": row["title"],
            "created": row["created"],
            "modified": row["modified"],
        }
        if document:
            out["document"] = json.loads(row["document"])
        return out

    @staticmethod
    def _row(conn: sqlite3.Connection, entry_id: int) -> sqlite3.Row:
        row: sqlite3.Row | None = conn.execute(
            "SELECT * FROM entries WHERE id = ?", (entry_id,)
        ).fetchone()
        if row is None:
            raise LibraryNotFound(f"library: no entry with id {entry_id}")
        return row

    @staticmethod
    def _holder(conn: sqlite3.Connection, name: str) -> int | None:
        row = conn.execute("SELECT id FROM entries WHERE name = ?", (name,)).fetchone()
        return None if row is None else int(row[0])

    @staticmethod
    def _unique(conn: sqlite3.Connection, name: str) -> str:
        """``name``, or ``name (2)``, ``name (3)`` … : the first one free."""
        if Library._holder(conn, name) is None:
            return name
        match = _SUFFIXED.match(name)
        base, n = (match["base"], int(match["n"])) if match else (name, 1)
        while True:
            n += 1
            suffix = f" ({n})"
            candidate = base[: MAX_NAME - len(suffix)].rstrip() + suffix
            if Library._holder(conn, candidate) is None:
                return candidate

    def _insert(
        self,
        conn: sqlite3.Connection,
        name: str,
        document: dict[str, Any],
        family: str,
        title: str | None,
    ) -> int:
        now = time.time()
        cur = conn.execute(
            "INSERT INTO entries (name, document, family, title, created, modified)"
            " VALUES (?, ?, ?, ?, ?, ?)",
            (name, dumps_document(document), family, title, now, now),
        )
        return int(cur.lastrowid or 0)

    # ---------------------------------------------------------------------------- verbs

    def save(
        self, name: str, document: Mapping[str, Any], overwrite: bool = False
    ) -> dict[str, Any]:
        """Save ``document`` under ``name``; with ``overwrite`` an entry of that name is replaced
        (keeping its id and creation time).

        Parameters
        ----------
        name : 1 to :data:`MAX_NAME` characters once stripped, no control characters.
        document : a document mapping; validated with :func:`~linkwright.io.parse_document`
            and stored in its canonical form.
        overwrite : replace an existing entry of the same name instead of refusing.

        Returns
        -------
        dict
            The entry, with its document.

        Raises
        ------
        LibraryError
            For a bad name.
        LibraryConflict
            If the name is taken and ``overwrite`` is false.
        DocumentError
            For an invalid document, naming the field.
        """
        name = check_name(name)
        canonical, family, title = validated_document(document)
        with self._transaction(write=True) as conn:
            holder = self._holder(conn, name)
            if holder is not None and not overwrite:
                raise LibraryConflict(f"name: an entry named {name!r} already exists (id {holder})")
            if holder is None:
                entry_id = self._insert(conn, name, canonical, family, title)
            else:
                entry_id = holder
                conn.execute(
                    "UPDATE entries SET document = ?, family = ?, title = ?, modified = ?"
                    " WHERE id = ?",
                    (dumps_document(canonical), family, title, time.time(), entry_id),
                )
            return self._entry(self._row(conn, entry_id))

    def update(self, entry_id: int, document: Mapping[str, Any]) -> dict[str, Any]:
        """Save ``document`` over entry ``entry_id`` (its name, id and creation time stay).

        Raises
        ------
        LibraryNotFound
            If there is no such entry.
        DocumentError
            For an invalid document, naming the field.
        """
        entry_id = check_id(entry_id)
        canonical, family, title = validated_document(document)
        with self._transaction(write=True) as conn:
            self._row(conn, entry_id)
            conn.execute(
                "UPDATE entries SET document = ?, family = ?, title = ?, modified = ? WHERE id = ?",
                (dumps_document(canonical), family, title, time.time(), entry_id),
            )
            return self._entry(self._row(conn, entry_id))

    def rename(self, entry_id: int, name: str) -> dict[str, Any]:
        """Give entry ``entry_id`` a new name.

        Raises
        ------
        LibraryError
            For a bad name.
        LibraryConflict
            If another entry has that name.
        LibraryNotFound
            If there is no such entry.
        """
        entry_id = check_id(entry_id)
        name = check_name(name)
        with self._transaction(write=True) as conn:
            row = self._row(conn, entry_id)
            if row["name"] != name:
                holder = self._holder(conn, name)
                if holder is not None:
                    raise LibraryConflict(
                        f"name: an entry named {name!r} already exists (id {holder})"
                    )
                conn.execute(
                    "UPDATE entries SET name = ?, modified = ? WHERE id = ?",
                    (name, time.time(), entry_id),
                )
                row = self._row(conn, entry_id)
            return self._entry(row)

    def list(self) -> list[dict[str, Any]]:
        """Every entry without its document, sorted by name (case-insensitively, then exactly).

        Returns
        -------
        list of dict
            ``id``, ``name``, ``family``, ``title``, ``created``, ``modified`` of each entry.
        """
        with self._transaction(write=False) as conn:
            rows = conn.execute(
                "SELECT id, name, family, title, created, modified FROM entries"
            ).fetchall()
        entries = [self._entry(row, document=False) for row in rows]
        return sorted(entries, key=lambda e: (e["name"].casefold(), e["name"]))

    def get(self, entry_id: int) -> dict[str, Any]:
        """Entry ``entry_id`` with its document.

        Raises
        ------
        LibraryNotFound
            If there is no such entry.
        """
        entry_id = check_id(entry_id)
        with self._transaction(write=False) as conn:
            return self._entry(self._row(conn, entry_id))

    def delete(self, entry_id: int) -> int:
        """Remove entry ``entry_id``; returns its id. Ids are never given out again.

        Raises
        ------
        LibraryNotFound
            If there is no such entry.
        """
        entry_id = check_id(entry_id)

        def run() -> None:
            with self._transaction(write=True) as conn:
                if conn.execute("DELETE FROM entries WHERE id = ?", (entry_id,)).rowcount == 0:
                    raise LibraryNotFound(f"library: no entry with id {entry_id}")

        # Works on a full disk too (the store gives up its reserve for it), so that deleting
        # can always make room.
        self._store.delete(run)
        return entry_id

    def import_text(
        self,
        text: str | bytes,
        format: str | None = None,
        name: str | None = None,
        *,
        source: str = "text",
        default_name: str | None = None,
    ) -> dict[str, Any]:
        """Add a new entry from a TOML or JSON document's text.

        Parameters
        ----------
        text : the document file's content (bytes are read as UTF-8).
        format : ``"toml"`` or ``"json"``; None guesses (JSON if the text starts with ``{``).
        name : the entry's name (refused if taken); None names it after the document's title,
            else ``default_name``, else ``"untitled"``, made unique with `` (2)``, `` (3)`` ….
        source : what error messages call the text (a file name).
        default_name : the name to use when there is no ``name`` and the document no title.

        Returns
        -------
        dict
            The new entry, with its document.

        Raises
        ------
        LibraryError
            For a bad format, name or text (naming the line and column of a syntax error).
        LibraryConflict
            If ``name`` is given and taken.
        DocumentError
            For an invalid document, naming the field.

        Examples
        --------
        >>> import tempfile
        >>> lib = Library(Path(tempfile.mkdtemp()) / "library.sqlite3")
        >>> text = '''format = "linkwright/1"
        ... title = "Slider"
        ... [mechanism]
        ... family = "slidercrank"
        ... A0 = [0, 0]
        ... crank = 1
        ... rod = 3
        ... line = { point = [0, 0], angle = 0 }
        ... '''
        >>> [lib.import_text(text, "toml")["name"] for _ in range(3)]
        ['Slider', 'Slider (2)', 'Slider (3)']
        >>> lib.import_text(text.replace("rod = 3", "rod = 0"), "toml")
        Traceback (most recent call last):
        ...
        linkwright.io.documents.DocumentError: text: mechanism.rod: must be a positive number, got 0
        """
        fmt = None if format is None else check_format(format)
        text = decode_text(text, source)
        mapping = parse_text(text, fmt or sniff_format(text), source)
        canonical, family, title = validated_document(mapping, source=source)
        explicit = None if name is None else check_name(name)
        with self._transaction(write=True) as conn:
            if explicit is None:
                chosen = self._unique(conn, name_from_title(title or default_name))
            else:
                holder = self._holder(conn, explicit)
                if holder is not None:
                    raise LibraryConflict(
                        f"name: an entry named {explicit!r} already exists (id {holder})"
                    )
                chosen = explicit
            entry_id = self._insert(conn, chosen, canonical, family, title)
            return self._entry(self._row(conn, entry_id))

    def export_text(self, entry_id: int, format: str = "toml") -> str:
        """Entry ``entry_id``'s document as the text of a ``.toml`` or ``.json`` file.

        Raises
        ------
        LibraryError
            For a format other than ``"toml"`` or ``"json"``.
        LibraryNotFound
            If there is no such entry.
        """
        return file_text(self.get(entry_id)["document"], check_format(format))


# --------------------------------------------------------------------------------------------
# Routes (mounted at /api by app.py)
# --------------------------------------------------------------------------------------------

router = APIRouter()


# The name's rule (NFC, stripped, no controls, at most MAX_NAME characters) is check_name's; the
# schema's length holds for the name as sent too, spaces around it included (a name padded past
# it was once accepted against the schema).
_NAME = Field(max_length=MAX_NAME, json_schema_extra={"minLength": 1})


_DOC = document_examples()[0]


class SaveRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"name": "My four-bar", "document": _DOC, "overwrite": True})
    )

    name: str = _NAME
    document: DocumentBody
    overwrite: bool = False


class RenameRequest(BaseModel):
    model_config = ConfigDict(json_schema_extra=examples({"name": "Renamed"}))

    name: str = _NAME


class UpdateRequest(BaseModel):
    model_config = ConfigDict(json_schema_extra=examples({"document": _DOC}))

    document: DocumentBody


EntryId = Annotated[str, PathParam(examples=["1"], description="An entry's id (digits).")]


def _library(request: Request) -> Library:
    library: Library = request.app.state.library
    return library


def _blank(name: Any) -> bool:
    # An empty name box on the page means "name it after the document", not a bad name.
    return name is None or (isinstance(name, str) and not name.strip())


@router.get("/library")
def list_route(request: Request) -> list[dict[str, Any]]:
    return _library(request).list()


@router.post("/library")
def save_route(body: SaveRequest, request: Request) -> dict[str, Any]:
    return _library(request).save(body.name, body.document, body.overwrite)


_IMPORT_JSON = {
    "requestBody": {
        "content": {
            "application/json": {
                "schema": {
                    "type": "object",
                    "properties": {
                        "text": {"type": "string", "description": "The file's content."},
                        "format": {"enum": ["toml", "json"]},
                        "name": {"type": "string", "maxLength": MAX_NAME},
                    },
                    "required": ["text"],
                    "additionalProperties": False,
                    "examples": [{"text": json.dumps(_DOC), "format": "json"}],
                }
            }
        }
    }
}


@router.post("/library/import", openapi_extra=_IMPORT_JSON)
async def import_route(
    request: Request,
    file: Annotated[UploadFile | None, File()] = None,
    name: Annotated[str | None, Form()] = None,
    format: Annotated[str | None, Form()] = None,
) -> dict[str, Any]:
    library = _library(request)
    if file is not None:
        data = await file.read(MAX_TEXT * 4 + 1)
        # The name the client gave its file is shown in messages and may name the entry; it is
        # never a path here.
        filename = shown_filename(file.filename)
        if not format:
            suffix = Path(filename).suffix.lower()
            if suffix and suffix not in (".toml", ".json"):
                raise LibraryError(
                    f"file: unknown file type {suffix!r} ({filename}): expected .toml or .json"
                )
            format = suffix.lstrip(".") or None
        return await run_in_threadpool(
            library.import_text,
            data,
            format,
            None if _blank(name) else name,
            source=filename,
            default_name=Path(filename).stem or None,
        )
    content_type = request.headers.get("content-type", "")
    if not content_type.startswith("application/json"):
        raise LibraryError(
            'body: expected a multipart form with a \'file\', or JSON {"text", "format", "name"}'
        )
    try:
        body = await request.json()
    except ValueError:
        raise LibraryError("body: not valid JSON") from None
    if not isinstance(body, dict):
        raise LibraryError('body: expected a JSON object {"text", "format", "name"}')
    unknown = sorted(set(body) - {"text", "format", "name"})
    if unknown:
        raise LibraryError(f"body: unknown field {unknown[0]!r} (expected text, format, name)")
    if "text" not in body:
        raise LibraryError("text: missing required field (the document file's content)")
    if not isinstance(body["text"], str):
        raise LibraryError(f"text: must be a string, got {type(body['text']).__name__}")
    name = None if _blank(body.get("name")) else body["name"]
    return await run_in_threadpool(library.import_text, body["text"], body.get("format"), name)


@router.get("/library/{entry_id}")
def get_route(entry_id: EntryId, request: Request) -> dict[str, Any]:
    return _library(request).get(check_id(entry_id))


@router.patch("/library/{entry_id}")
def rename_route(entry_id: EntryId, body: RenameRequest, request: Request) -> dict[str, Any]:
    return _library(request).rename(check_id(entry_id), body.name)


@router.put("/library/{entry_id}")
def update_route(entry_id: EntryId, body: UpdateRequest, request: Request) -> dict[str, Any]:
    return _library(request).update(check_id(entry_id), body.document)


@router.delete("/library/{entry_id}")
def delete_route(entry_id: EntryId, request: Request) -> dict[str, Any]:
    return {"deleted": _library(request).delete(check_id(entry_id))}


@router.get(
    "/library/{entry_id}/export",
    response_class=Response,
    responses={
        200: {
            "content": {f"{media}; charset=utf-8": {} for media in _MEDIA_TYPES.values()},
            "description": "The entry's document as a file.",
        }
    },
)
def export_route(
    entry_id: EntryId,
    request: Request,
    format: Annotated[str, Query(json_schema_extra={"enum": list(FORMATS)})] = "toml",
) -> Response:
    fmt = check_format(format)
    entry = _library(request).get(check_id(entry_id))
    text = file_text(entry["document"], fmt)
    return Response(
        text.encode("utf-8"),
        media_type=f"{_MEDIA_TYPES[fmt]}; charset=utf-8",
        headers={"Content-Disposition": attachment(entry["name"], fmt)},
    )

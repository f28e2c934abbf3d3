"""What the library's SQLite file can be besides well: damaged, on a full disk, or read-only;
each told to the user as what it is, with what to do.

:func:`classify` turns a ``sqlite3`` error into one of the three :class:`LibraryUnavailable`
errors (or None for anything else, which stays a bug): SQLite's result code says which
(``SQLITE_CORRUPT`` and ``SQLITE_NOTADB``: damaged; ``SQLITE_FULL``: disk full;
``SQLITE_READONLY``: read-only), and its message where an error carries no code.

A full disk must not trap the library: deleting an entry writes too (to the write-ahead log),
so on a disk with no byte left even a delete would fail. :class:`Reserve` keeps a small file
beside the library, written while there is space; a delete that finds the disk full removes it
and tries again, so that deleting always works and frees pages for the next save.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import sqlite3
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import ClassVar
from urllib.parse import quote

from linkwright.server.errors import StatusError

__all__ = [
    "RESERVE_BYTES",
    "LibraryDamaged",
    "LibraryFull",
    "LibraryReadOnly",
    "LibraryUnavailable",
    "Reserve",
    "Store",
    "classify",
    "has_sqlite_header",
    "writable",
]

RESERVE_BYTES = 1 << 20
"""Size of the reserve file: room for a delete's log frames many times over."""

# SQLite's primary result codes (the low byte of an extended code).
_READONLY, _IOERR, _CORRUPT, _FULL, _CANTOPEN, _NOTADB = 8, 10, 11, 13, 14, 26
_LOW_SPACE = 64 * 1024  # free bytes under which an I/O error is taken for a full disk
_HEADER = b"SQLite format 3\x00"


class LibraryUnavailable(StatusError):
    """The library's file stops a request (not the request's fault, nor a bug)."""


class LibraryDamaged(LibraryUnavailable):
    """The file is damaged: nothing is read from it or written to it (500)."""

    status: ClassVar[int] = 500


class LibraryFull(LibraryUnavailable):
    """The disk is full: the change was not made (507 Insufficient Storage)."""

    status: ClassVar[int] = 507


class LibraryReadOnly(LibraryUnavailable):
    """The library cannot be written: reads work, changes are refused (409)."""

    status: ClassVar[int] = 409


def damaged(path: Path, detail: str) -> LibraryDamaged:
    return LibraryDamaged(
        f"library: {path} is damaged ({detail}); nothing is read from it or saved to it. "
        f"Stop the workbench, move the file aside (its entries may be recovered with "
        f"`sqlite3 {path.name} .recover`), and start again for a new, empty library"
    )


def full(path: Path) -> LibraryFull:
    return LibraryFull(
        f"library: disk full: the change was not saved (the disk holding {path.parent} has no "
        "space left); free some space, or delete library entries you no longer need "
        "(deleting always works)"
    )


def read_only(path: Path) -> LibraryReadOnly:
    return LibraryReadOnly(
        f"library: the library is read-only ({path} cannot be written): entries can be listed, "
        "opened and exported, not saved, renamed, imported or deleted; make the folder "
        "writable, or start the workbench with --data-dir on a writable folder"
    )


def _code(exc: sqlite3.Error) -> int | None:
    code = getattr(exc, "sqlite_errorcode", None)
    if isinstance(code, int):
        return code & 0xFF
    text = str(exc).lower()
    if "disk is full" in text or "database or disk is full" in text:
        return _FULL
    if "malformed" in text or "not a database" in text:
        return _CORRUPT
    if "readonly" in text or "read-only" in text:
        return _READONLY
    return None


def classify(exc: BaseException, path: Path) -> LibraryUnavailable | None:
    """The :class:`LibraryUnavailable` a storage error means, or None (then it is a bug)."""
    if isinstance(exc, OSError):
        if exc.errno == errno.ENOSPC:
            return full(path)
        if exc.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
            return read_only(path)
        return None
    if not isinstance(exc, sqlite3.Error):
        return None
    code = _code(exc)
    if code in (_CORRUPT, _NOTADB):
        return damaged(path, str(exc))
    if code == _FULL or (code in (_IOERR, _CANTOPEN) and _no_room(path)):
        # SQLite says "disk I/O error" where a full disk stops it making a file it needs.
        return full(path)
    if code == _READONLY:
        return read_only(path)
    return None


def _no_room(path: Path) -> bool:
    try:
        return shutil.disk_usage(path.parent).free < _LOW_SPACE
    except OSError:
        return False


def has_sqlite_header(path: Path) -> bool:
    """Whether the file begins as every SQLite database does (a damaged library does; a file
    that is not a database does not)."""
    try:
        with path.open("rb") as f:
            return f.read(len(_HEADER)) == _HEADER
    except OSError:
        return False


def writable(folder: Path) -> bool:
    """Whether a file can be created in ``folder`` (tried, not guessed from permission bits:
    those do not say that a file system is mounted read-only, nor bind root)."""
    try:
        with tempfile.TemporaryFile(dir=folder, prefix=".linkwright-probe-"):
            return True
    except OSError as exc:
        return exc.errno not in (errno.EROFS, errno.EACCES, errno.EPERM)


class Reserve:
    """A file of :data:`RESERVE_BYTES` beside the library, given up when the disk is full so
    that a delete can still be written (module docstring)."""

    def __init__(self, library: Path) -> None:
        self.path = library.with_name(library.name + "-reserve")

    def ensure(self) -> None:
        """Write the reserve if it is missing (quietly nothing if there is no room for it)."""
        if self.path.exists():
            return
        part = self.path.with_name(self.path.name + ".part")
        try:
            with part.open("wb") as f:
                # Written, not truncated to size: a sparse file would free no space.
                f.write(b"\0" * RESERVE_BYTES)
                f.flush()
                os.fsync(f.fileno())
            part.replace(self.path)
        except OSError:
            with contextlib.suppress(OSError):
                part.unlink()

    def release(self) -> bool:
        """Remove the reserve; whether there was one to remove."""
        try:
            self.path.unlink()
        except OSError:
            return False
        return True


class Store:
    """The library's SQLite file: connections, transactions, and its state (:attr:`damage`,
    :attr:`read_only`), each failure raised as what it is.

    ``prepare`` runs once, in a write transaction, on a file that can be written (it makes the
    schema). A file that cannot be written is opened read-only; a damaged SQLite file is opened
    damaged; any other error of ``prepare`` is raised (the file is not a library).
    """

    def __init__(
        self, path: Path, prepare: Callable[[sqlite3.Connection], None], busy_s: float
    ) -> None:
        self.path = path
        self.busy_s = busy_s
        self.read_only = False
        """Whether the library cannot be written (then reads work and changes are refused)."""
        self.damage: str | None = None
        """Why the library is damaged (the message every request gets), or None."""
        self._uri: str | None = None
        self._prepare_schema = prepare
        self.reserve = Reserve(path)
        self._keeper: sqlite3.Connection | None = None
        try:
            self._prepare(prepare)
        except (sqlite3.DatabaseError, OSError) as exc:
            self._open_as_is(exc)
        else:
            self.reserve.ensure()
            # One connection stays open while the server runs, so that SQLite's log and
            # shared-memory files stay too: each request's connection then needs no new file,
            # which a full disk could not give (reads and deletes must go on there).
            with contextlib.suppress(sqlite3.Error):
                self._keeper = sqlite3.connect(self.path, check_same_thread=False)
                self._keeper.execute("SELECT count(*) FROM sqlite_master").fetchone()
        if self.damage is None and path.exists():
            with contextlib.suppress(LibraryDamaged):
                self.check_pages()

    def _prepare(self, prepare: Callable[[sqlite3.Connection], None]) -> None:
        conn = sqlite3.connect(self.path, timeout=self.busy_s, isolation_level=None)
        try:
            # WAL is a property of the file (it persists); it lets readers go on while one
            # writer commits, and a commit is one append to the log, so a kill cannot tear it.
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("PRAGMA synchronous=FULL")
            conn.execute("BEGIN IMMEDIATE")
            try:
                prepare(conn)
            except BaseException:
                conn.execute("ROLLBACK")
                raise
            conn.execute("COMMIT")
        finally:
            conn.close()

    def _open_as_is(self, exc: BaseException) -> None:
        """Open a file that could not be prepared: read-only if it cannot be written, damaged
        if it is a damaged SQLite file; else ``exc`` is raised again."""
        kind = classify(exc, self.path)
        if isinstance(kind, LibraryReadOnly) or not writable(self.path.parent):
            self.read_only = True
            base = f"file:{quote(str(self.path.resolve()))}?mode=ro"
            # A folder that cannot be written cannot hold SQLite's shared-memory file either;
            # "immutable" reads without it (nothing can change the file there meanwhile).
            for uri in (base, base + "&immutable=1"):
                try:
                    with contextlib.closing(sqlite3.connect(uri, uri=True)) as conn:
                        conn.execute("SELECT count(*) FROM sqlite_master").fetchone()
                except sqlite3.DatabaseError:
                    continue
                self._uri = uri
                return
            if self.path.exists():
                raise exc
            return
        if isinstance(kind, LibraryDamaged) and has_sqlite_header(self.path):
            self.damage = str(damaged(self.path, str(exc)))
            return
        raise exc

    def close(self) -> None:
        """Close the connection kept open (the files SQLite keeps beside the library go)."""
        if self._keeper is not None:
            with contextlib.suppress(sqlite3.Error):
                self._keeper.close()
            self._keeper = None

    def connect(self) -> sqlite3.Connection:
        """A connection to the library (read-only where the library is)."""
        if not self.read_only:
            return sqlite3.connect(self.path, timeout=self.busy_s, isolation_level=None)
        if self._uri is None:
            # No file, in a folder that cannot hold one: an empty library, read-only.
            conn = sqlite3.connect(":memory:", isolation_level=None)
            self._prepare_schema(conn)
            return conn
        return sqlite3.connect(self._uri, uri=True, timeout=self.busy_s, isolation_level=None)

    def check_pages(self, conn: sqlite3.Connection | None = None) -> None:
        """SQLite's quick check of every page (linear in the file): a damaged library is
        marked so and :class:`LibraryDamaged` raised; from then on every request is refused."""
        try:
            if conn is None:
                with contextlib.closing(self.connect()) as own:
                    rows = own.execute("PRAGMA quick_check").fetchall()
            else:
                rows = conn.execute("PRAGMA quick_check").fetchall()
        except sqlite3.DatabaseError as exc:
            if not isinstance(classify(exc, self.path), LibraryDamaged):
                raise
            rows = [(str(exc),)]
        if [tuple(row) for row in rows] != [("ok",)]:
            self.damage = str(damaged(self.path, str(rows[0][0])))
            raise LibraryDamaged(self.damage)

    @contextmanager
    def transaction(self, write: bool) -> Iterator[sqlite3.Connection]:
        """One connection and one transaction: committed when the block ends, rolled back if
        it raises. A write takes SQLite's write lock at once (``BEGIN IMMEDIATE``), so two
        writers queue instead of one failing when it tries to upgrade a read lock, and checks
        every page first, so that nothing is written into a damaged file. An error of the file
        (damaged, disk full, read-only) is raised as what it is."""
        if self.damage is not None:
            raise LibraryDamaged(self.damage)
        if write and self.read_only:
            raise read_only(self.path)
        try:
            conn = self.connect()
            try:
                conn.row_factory = sqlite3.Row
                # FULL: the log is flushed to disk at every commit, so a save that returned
                # survives a power cut too, not only a killed process.
                conn.execute("PRAGMA synchronous=FULL")
                conn.execute("BEGIN IMMEDIATE" if write else "BEGIN")
                try:
                    if write:
                        self.check_pages(conn)
                    yield conn
                except BaseException:
                    if conn.in_transaction:
                        conn.execute("ROLLBACK")
                    raise
                conn.execute("COMMIT")
            finally:
                conn.close()
        except (sqlite3.DatabaseError, OSError) as exc:
            kind = classify(exc, self.path)
            if kind is None:
                raise
            if isinstance(kind, LibraryDamaged):
                self.damage = str(kind)
            raise kind from None
        if write:
            self.reserve.ensure()

    def delete(self, run: Callable[[], None]) -> None:
        """Run a delete (``run``, one write transaction) even on a full disk: if the disk has
        no room for the delete's log, the reserve is given up and the delete tried again."""
        try:
            run()
        except LibraryFull:
            if not self.reserve.release():
                raise
            run()
            with contextlib.suppress(sqlite3.Error), contextlib.closing(self.connect()) as conn:
                # Fold the log into the file and empty it: the space it held is free again.
                conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
            self.reserve.ensure()

    def state_note(self) -> str:
        """A few words on the library's state for the line ``linkwright serve`` prints: empty
        when it is well."""
        if self.damage is not None:
            return "; DAMAGED: the library list says what to do"
        if self.read_only:
            return "; read-only: saves are refused"
        return ""

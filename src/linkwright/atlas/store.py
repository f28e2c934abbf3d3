"""An atlas on disk: shards of mechanisms with their descriptors, a manifest and an index.

Layout of an atlas directory::

    build.json            what is being built (family, count, seed, shard size, samples, …)
    shard-00000.npy       one structured array: rows (params float64[P], descriptor float32[D])
    shard-00000.sha256    the shard's SHA-256, written after it: a shard counts only with it
    …
    index.faiss           the search index (FAISS), or none for an exact search
    atlas.json            written last: the build spec, every shard's count and digest, the
                          index and the build's figures. An atlas is complete once it exists.
    build.lock            held (flock) by the build writing the directory, with its pid

Every file is written whole or not at all (a temporary file in the same directory, flushed to
disk, then renamed over the name), so a build killed at any moment leaves finished shards and
nothing half-written; :func:`finished_shards` re-reads each digest before a resumed build
trusts a shard. A build holds :func:`build_lock` from start to end, so two builds never write
one directory; the kernel drops the lock when its holder dies, however it dies.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import time
from collections.abc import Iterator, Mapping
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from linkwright import files

try:
    import fcntl
except ImportError:  # pragma: no cover - not on POSIX: builds are not locked
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "AtlasLocked",
    "AtlasStoreError",
    "atomic_path",
    "build_lock",
    "clear_partial",
    "file_digest",
    "finished_shards",
    "lock_holder",
    "read_json",
    "read_shard",
    "shard_descriptors",
    "shard_name",
    "shard_table",
    "verify",
    "write_atomic",
    "write_json",
    "write_shard",
]

BUILD = "build.json"
MANIFEST = "atlas.json"
INDEX = "index.faiss"
LOCK = "build.lock"
_TMP = ".tmp-"


class AtlasStoreError(ValueError):
    """An atlas directory that cannot be read or written as asked (names the file)."""


class AtlasLocked(AtlasStoreError):
    """Another process holds the directory's build lock (``pid`` names it, None if unknown)."""

    def __init__(self, message: str, pid: int | None) -> None:
        super().__init__(message)
        self.pid = pid


@contextmanager
def build_lock(directory: Path, *, wait: bool = False) -> Iterator[None]:
    """Hold ``directory``'s build lock for the ``with`` block: ``fcntl.flock`` on ``build.lock``,
    which records the holder's pid while it holds it.

    Without ``wait`` a held lock raises :class:`AtlasLocked` at once, naming the holder's pid;
    with ``wait`` it blocks until the holder is done. A lock left by a killed process never
    blocks: the kernel releases a flock when the last descriptor of its holder closes.
    """
    path = Path(directory) / LOCK
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
            except BlockingIOError:
                pid = _read_pid(fd)
                who = f"pid {pid}" if pid is not None else "a process whose pid is not yet written"
                raise AtlasLocked(
                    f"{directory}: another atlas build ({who}) is writing this directory; wait "
                    "for it to finish, or build into another directory",
                    pid,
                ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        try:
            yield
        finally:
            # Emptied while still held, so that a pid in the file is always a live holder's.
            os.ftruncate(fd, 0)
    finally:
        os.close(fd)


def _read_pid(fd: int) -> int | None:
    """The pid a lock file holds; the holder writes it just after it locks, so wait a moment
    for it rather than report an empty file."""
    deadline = time.monotonic() + 0.5
    while True:
        text = os.pread(fd, 32, 0).decode(errors="replace").strip()
        if text.isdigit():
            return int(text)
        if time.monotonic() > deadline:
            return None
        time.sleep(0.01)


def lock_holder(directory: Path) -> int | None:
    """The pid of a live build holding ``directory``'s lock, or None.

    Read from the lock file, not by trying the lock: trying it would take it for a moment, and
    a build starting in that moment would be refused. A holder empties the file when it lets
    go; the pid a killed holder leaves is recognised as no longer running.
    """
    try:
        text = (Path(directory) / LOCK).read_text(errors="replace").strip()
    except OSError:
        return None
    if not text.isdigit() or int(text) <= 0:
        return None
    pid = int(text)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:  # alive, another user's
        return pid
    return pid


def shard_name(index: int) -> str:
    return f"shard-{index:05d}.npy"


def _digest_name(index: int) -> str:
    return f"shard-{index:05d}.sha256"


def atomic_path(path: Path) -> AbstractContextManager[Path]:
    """:func:`linkwright.files.atomic_path`, its temporary files named for
    :func:`clear_partial`."""
    return files.atomic_path(path, prefix=_TMP)


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (:func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def clear_partial(directory: Path) -> int:
    """Remove temporary files a killed writer left; returns how many."""
    gone = 0
    for p in Path(directory).glob(f"{_TMP}*"):
        p.unlink(missing_ok=True)
        gone += 1
    return gone


def write_json(path: Path, value: Mapping[str, Any]) -> None:
    write_atomic(path, (json.dumps(value, indent=2, sort_keys=True) + "\n").encode())


def read_json(path: Path) -> dict[str, Any]:
    try:
        data: dict[str, Any] = json.loads(Path(path).read_text())
        return data
    except FileNotFoundError:
        raise AtlasStoreError(f"{path}: not found") from None
    except (OSError, ValueError) as exc:
        raise AtlasStoreError(f"{path}: cannot be read ({exc})") from None


def shard_table(params: np.ndarray, descriptors: np.ndarray) -> np.ndarray:
    """One structured array of a shard's rows: ``params`` (float64) and ``descriptor``
    (float32, as the index keeps them)."""
    n, p = params.shape
    d = descriptors.shape[1]
    table = np.empty(n, dtype=[("params", "<f8", (p,)), ("descriptor", "<f4", (d,))])
    table["params"] = params
    table["descriptor"] = descriptors
    return table


def _npy_bytes(table: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, table, allow_pickle=False)
    return buf.getvalue()


def write_shard(directory: Path, index: int, table: np.ndarray) -> str:
    """Write shard ``index`` and then its digest; returns the SHA-256 (hex)."""
    data = _npy_bytes(table)
    digest = hashlib.sha256(data).hexdigest()
    write_atomic(Path(directory) / shard_name(index), data)
    write_atomic(Path(directory) / _digest_name(index), (digest + "\n").encode())
    return digest


def file_digest(path: Path) -> str:
    """The SHA-256 (hex) of a file, read in blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


def finished_shards(directory: Path, sizes: list[int]) -> dict[int, str]:
    """The shards already written whole: their file matches the digest written after it and
    holds the expected number of rows. Any other shard file is removed (it will be redone).
    Returns {shard index: digest}."""
    directory = Path(directory)
    done: dict[int, str] = {}
    for i, size in enumerate(sizes):
        shard, sidecar = directory / shard_name(i), directory / _digest_name(i)
        if not shard.exists():
            sidecar.unlink(missing_ok=True)
            continue
        try:
            expected = sidecar.read_text().strip()
            ok = file_digest(shard) == expected and read_shard(directory, i).shape == (size,)
        except (OSError, ValueError):
            ok = False
        if ok:
            done[i] = expected
        else:
            shard.unlink(missing_ok=True)
            sidecar.unlink(missing_ok=True)
    return done


def read_shard(directory: Path, index: int, mmap: bool = True) -> np.ndarray:
    """Shard ``index`` as its structured array (memory-mapped unless ``mmap`` is false)."""
    path = Path(directory) / shard_name(index)
    try:
        table: np.ndarray = np.load(path, mmap_mode="r" if mmap else None, allow_pickle=False)
        return table
    except FileNotFoundError:
        raise AtlasStoreError(f"{path}: missing shard (rebuild or resume the atlas)") from None


def shard_descriptors(directory: Path, shards: int) -> list[np.ndarray]:
    """Each shard's descriptors (memory-mapped), in order: the blocks of the atlas's index."""
    return [read_shard(directory, i)["descriptor"] for i in range(shards)]


def verify(directory: Path, manifest: Mapping[str, Any], *, hashes: bool = False) -> None:
    """Check that ``manifest`` (the atlas.json read), build.json and the files on disk describe
    one atlas; raise :class:`AtlasStoreError` naming the first mismatch, in one line.

    Always: build.json holds the manifest's spec; the manifest lists the shards the spec's
    count and shard size make; every listed shard is on disk with the row count listed and a
    digest file equal to the listed SHA-256; no other shard file is there; the index file has
    the size listed (atlases built since the manifest lists it). These read file headers only,
    so opening even a 10^8 atlas stays quick. With ``hashes``, also re-hash every shard and the
    index against the manifest (this reads the whole atlas).
    """
    root = Path(directory)
    spec = dict(manifest.get("spec", {}))
    try:
        built = read_json(root / BUILD)
    except AtlasStoreError:
        raise AtlasStoreError(
            f"{root}: {MANIFEST} has no readable {BUILD} beside it; the atlas is damaged, "
            "rebuild it into an empty directory"
        ) from None
    if built != spec:
        keys = sorted(k for k in set(built) | set(spec) if built.get(k) != spec.get(k))
        said = ", ".join(f"{k} {spec.get(k)} in {MANIFEST} but {built.get(k)} in {BUILD}"
                         for k in keys)  # fmt: skip
        raise AtlasStoreError(
            f"{root}: {MANIFEST} and {BUILD} describe different atlases ({said}); rebuild it "
            "into an empty directory"
        )
    listed = list(manifest.get("shards", []))
    count, size = int(spec.get("count", 0)), int(spec.get("shard_size", 1))
    sizes = [size] * (count // size) + ([count % size] if count % size else [])
    if [int(entry.get("count", -1)) for entry in listed] != sizes:
        raise AtlasStoreError(
            f"{root}: {MANIFEST} lists {len(listed)} shards of "
            f"{sum(int(e.get('count', 0)) for e in listed)} rows, but its spec makes "
            f"{len(sizes)} of {count}; the atlas is damaged, rebuild it"
        )
    names = {shard_name(i) for i in range(len(listed))}
    stray = sorted(p.name for p in root.glob("shard-*.npy") if p.name not in names)
    if stray:
        raise AtlasStoreError(
            f"{root}: {stray[0]} is not a shard of this atlas ({MANIFEST} lists "
            f"{len(listed)}); the directory holds parts of another build, rebuild it"
        )
    for i, entry in enumerate(listed):
        shard = root / shard_name(i)
        if not shard.exists():
            raise AtlasStoreError(f"{root}: {shard.name}, listed in {MANIFEST}, is missing")
        try:
            digest = (root / _digest_name(i)).read_text().strip()
            rows = np.load(shard, mmap_mode="r", allow_pickle=False).shape
        except (OSError, ValueError) as exc:
            raise AtlasStoreError(f"{root}: {shard.name} cannot be read ({exc})") from None
        if digest != entry.get("sha256"):
            raise AtlasStoreError(
                f"{root}: {shard.name} is not the shard {MANIFEST} lists (its digest file "
                "says another SHA-256); rebuild the atlas"
            )
        if rows != (int(entry["count"]),):
            raise AtlasStoreError(
                f"{root}: {shard.name} holds {rows[0] if rows else 0} rows, {MANIFEST} says "
                f"{entry['count']}; rebuild the atlas"
            )
        if hashes and file_digest(shard) != digest:
            raise AtlasStoreError(
                f"{root}: {shard.name} does not match its SHA-256 in {MANIFEST} (changed or "
                "damaged since the build); rebuild the atlas"
            )
    index = manifest.get("index", {})
    if index.get("sha256"):
        path = root / INDEX
        if not path.exists():
            raise AtlasStoreError(f"{root}: {INDEX}, listed in {MANIFEST}, is missing")
        if path.stat().st_size != index.get("bytes", path.stat().st_size):
            raise AtlasStoreError(
                f"{root}: {INDEX} is not the index {MANIFEST} lists (its size differs); "
                "rebuild the atlas"
            )
        if hashes and file_digest(path) != index["sha256"]:
            raise AtlasStoreError(
                f"{root}: {INDEX} does not match its SHA-256 in {MANIFEST}; rebuild the atlas"
            )

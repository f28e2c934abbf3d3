"""An atlas on disk: shards of mechanisms with their descriptors, a manifest and an index.

Layout of an atlas directory::

    build.json            what is being built (family, count, seed, shard size, samples, …)
    shard-00000.npy       one structured array: rows (params float64[P], descriptor float32[D])
    shard-00000.sha256    the shard's SHA-256, written after it: a shard counts only with it
    …
    index.faiss           the search index (FAISS), or none for an exact search
    atlas.json            written last: the build spec, every shard's count and digest, the
                          index and the build's figures. An atlas is complete once it exists.

Every file is written whole or not at all (a temporary file in the same directory, flushed to
disk, then renamed over the name), so a build killed at any moment leaves finished shards and
nothing half-written; :func:`finished_shards` re-reads each digest before a resumed build
trusts a shard.
"""

from __future__ import annotations

import hashlib
import io
import json
from collections.abc import Mapping
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Any

import numpy as np

from linkwright import files

__all__ = [
    "AtlasStoreError",
    "atomic_path",
    "clear_partial",
    "finished_shards",
    "read_json",
    "read_shard",
    "shard_descriptors",
    "shard_name",
    "shard_table",
    "write_atomic",
    "write_json",
    "write_shard",
]

BUILD = "build.json"
MANIFEST = "atlas.json"
INDEX = "index.faiss"
_TMP = ".tmp-"


class AtlasStoreError(ValueError):
    """An atlas directory that cannot be read or written as asked (names the file)."""


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
        return json.loads(Path(path).read_text())
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


def _file_digest(path: Path) -> str:
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
            ok = _file_digest(shard) == expected and read_shard(directory, i).shape == (size,)
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
        return np.load(path, mmap_mode="r" if mmap else None, allow_pickle=False)
    except FileNotFoundError:
        raise AtlasStoreError(f"{path}: missing shard (rebuild or resume the atlas)") from None


def shard_descriptors(directory: Path, shards: int) -> list[np.ndarray]:
    """Each shard's descriptors (memory-mapped), in order: the blocks of the atlas's index."""
    return [read_shard(directory, i)["descriptor"] for i in range(shards)]

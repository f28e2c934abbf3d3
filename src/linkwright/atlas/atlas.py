"""An atlas opened for matching, and the built-in atlas each family builds on first use."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.atlas import store
from linkwright.atlas.build import AtlasBuildError, BuildSpec, build
from linkwright.atlas.families import BUILDABLE, FAMILIES, PARAMS
from linkwright.atlas.index import Index

__all__ = ["DEFAULT_COUNTS", "Atlas", "AtlasError", "data_dir", "default_atlas", "open_atlas"]

DEFAULT_COUNTS = {"fourbar": 100_000, "geared-fivebar": 50_000, "spherical-fourbar": 50_000}
"""Sizes of the built-in atlases: each builds in this process in seconds on first use."""


class AtlasError(ValueError):
    """An atlas directory that is missing, unfinished or damaged (names the problem)."""


@dataclass(frozen=True)
class Atlas:
    """A finished atlas: its manifest, and its index loaded for searching."""

    path: Path
    manifest: dict[str, Any]
    index: Index

    @property
    def spec(self) -> BuildSpec:
        return BuildSpec(**self.manifest["spec"])

    @property
    def family(self) -> str:
        return str(self.manifest["spec"]["family"])

    @property
    def count(self) -> int:
        return int(self.manifest["spec"]["count"])

    @property
    def params(self) -> tuple[str, ...]:
        """The names of a row's columns (the manifest's; a composed linkage's depend on it)."""
        return tuple(self.manifest.get("params") or PARAMS[self.family])

    def designs(self, ids: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """The stored parameters of entries ``ids`` (in the family's local frame), by name."""
        ids = np.asarray(ids, dtype=np.int64).ravel()
        if ids.size and (ids.min() < 0 or ids.max() >= self.count):
            raise AtlasError(f"ids: must lie in [0, {self.count}), got {ids.min()}…{ids.max()}")
        size = self.spec.shard_size
        rows = np.empty((ids.size, len(self.params)))
        shard = ids // size
        for s in np.unique(shard):
            at = shard == s
            rows[at] = store.read_shard(self.path, int(s))["params"][ids[at] - s * size]
        return {k: rows[:, i] for i, k in enumerate(self.params)}

    def descriptors(self) -> NDArray[np.float32]:
        """Every entry's descriptor (N, D), read from the shards."""
        parts = store.shard_descriptors(self.path, len(self.spec.sizes))
        return np.ascontiguousarray(np.concatenate(parts), dtype=np.float32)


def open_atlas(path: str | os.PathLike[str], *, hashes: bool = False) -> Atlas:
    """Open the finished atlas in directory ``path`` and load its index.

    The manifest, build.json and the shards on disk are checked against one another first
    (:func:`linkwright.atlas.store.verify`; ``hashes`` re-hashes every file, reading the whole
    atlas), so a directory two builds wrote into, or one with a file swapped, is refused.

    Raises
    ------
    AtlasError
        If ``path`` holds no atlas, an unfinished build (run the build again to finish it), a
        build in progress, or files that do not belong together (names the first mismatch).
    """
    root = Path(path)
    if not root.is_dir():
        raise AtlasError(f"{root}: no such atlas directory")
    if not (root / store.MANIFEST).exists():
        holder = store.lock_holder(root)
        if holder is not None:
            raise AtlasError(f"{root}: an atlas build (pid {holder}) is writing it now")
        if (root / store.BUILD).exists():
            raise AtlasError(
                f"{root}: the build is unfinished; run `linkwright atlas build` with the same "
                "options again to resume it"
            )
        raise AtlasError(f"{root}: not an atlas (no {store.MANIFEST})")
    try:
        manifest = store.read_json(root / store.MANIFEST)
        spec = manifest.get("spec", {})
        if spec.get("family") not in BUILDABLE or spec.get("format") != 1:
            raise AtlasError(f"{root}: an atlas of an unknown family or format ({spec})")
        store.verify(root, manifest, hashes=hashes)
        kind, nprobe = manifest["index"]["kind"], int(manifest["index"]["nprobe"])
    except store.AtlasStoreError as exc:
        raise AtlasError(str(exc)) from None
    except (KeyError, TypeError, AttributeError) as exc:
        raise AtlasError(f"{root}: {store.MANIFEST} is not an atlas manifest ({exc!r})") from None
    try:
        index = Index.load(root / store.INDEX, kind, nprobe, None)
    except ImportError:
        blocks = store.shard_descriptors(root, len(manifest["shards"]))
        index = Index.load(root / store.INDEX, kind, nprobe, np.concatenate(blocks))
    return Atlas(root, manifest, index)


def data_dir() -> Path:
    """Where linkwright keeps its data: ``$LINKWRIGHT_DATA``, else ``$XDG_DATA_HOME/linkwright``,
    else ``~/.local/share/linkwright``."""
    if os.environ.get("LINKWRIGHT_DATA"):
        return Path(os.environ["LINKWRIGHT_DATA"])
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "linkwright"


def default_atlas(
    family: str = "fourbar", progress: Callable[[float], None] | None = None
) -> Atlas:
    """The built-in atlas of ``family`` (:data:`DEFAULT_COUNTS` entries, seed 0), built in this
    process into :func:`data_dir` on first use (seconds), opened from there afterwards."""
    if family not in FAMILIES:
        raise AtlasError(f"family: must be one of {', '.join(FAMILIES)}, got {family!r}")
    count = DEFAULT_COUNTS[family]
    root = data_dir() / "atlas" / f"{family}-{count}-seed0-v1"
    for _ in range(3):
        if (root / store.MANIFEST).exists():
            break
        try:
            build(family, count, root, workers=0, progress=progress)
        except AtlasBuildError:
            if store.lock_holder(root) is None:
                raise
            # Another process (a second query, the workbench) is building this very atlas:
            # wait for it rather than fail, then use what it built.
            with store.build_lock(root, wait=True):
                pass
    return open_atlas(root)

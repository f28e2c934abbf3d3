"""Nearest descriptors: an exact search, or a FAISS inverted-file index for large atlases.

A query is a set of descriptor *variants* (one per normalisation choice, see
:func:`linkwright.curves.descriptor_variants`); a stored curve's distance to the query is its
least distance to any variant. Both searches below answer with that distance.

Up to :data:`EXACT_UP_TO` entries the search is exact (FAISS ``IndexFlatL2``, or NumPy where
FAISS is not installed). Beyond, an ``IndexIVFFlat`` (Jégou, Douze and Schmid's inverted file
with exact distances in the probed lists) with about 2√N lists, trained on an evenly spread
subset, and its ``nprobe`` chosen at build time as the least power of two whose recall@10
against the exact search reaches :data:`TARGET_RECALL` on held-out queries. From
:data:`HALF_PRECISION_FROM` entries the inverted lists hold the descriptors in float16
(``IndexIVFScalarQuantizer``, ``QT_fp16``): half the memory (10 GB rather than 20 GB for 10^8
curves of 51 numbers), at a recall the tuning measures like any other.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.atlas.store import atomic_path

__all__ = [
    "EXACT_UP_TO",
    "HALF_PRECISION_FROM",
    "TARGET_RECALL",
    "Index",
    "exact_blocks",
    "exact_search",
    "faiss_available",
    "merge_variants",
    "recall_at",
]

EXACT_UP_TO = 200_000
HALF_PRECISION_FROM = 30_000_000
TARGET_RECALL = 0.97
_SEED = 1234

Floats = NDArray[np.floating[Any]]
"""Descriptors and distances: float32 where FAISS holds or returns them, float64 in NumPy."""
Ids = NDArray[np.int64]
"""Rows of an atlas (−1: no neighbour)."""


def _faiss() -> Any | None:
    try:
        import faiss
    except ImportError:  # pragma: no cover - faiss is in the dev and atlas extras
        return None
    return faiss


def faiss_available() -> bool:
    return _faiss() is not None


def merge_variants(
    dist: Floats, ids: Ids, variants: int, k: int
) -> tuple[NDArray[np.float64], Ids]:
    """Per query, the k nearest distinct ids over its variants' answers (rows of ``dist`` and
    ``ids`` grouped ``variants`` at a time), each at its least distance. Missing → id −1."""
    q = dist.shape[0] // variants
    dist = dist.reshape(q, -1)
    ids = ids.reshape(q, -1)
    out_d = np.full((q, k), np.inf)
    out_i = np.full((q, k), -1, dtype=np.int64)
    for r in range(q):
        order = np.argsort(dist[r], kind="stable")
        seen_ids, first = np.unique(ids[r][order], return_index=True)
        keep = np.sort(first[seen_ids >= 0])[:k]
        out_d[r, : keep.size] = dist[r][order][keep]
        out_i[r, : keep.size] = ids[r][order][keep]
    return out_d, out_i


class _TopK:
    """The k nearest so far of each query, as blocks of candidates come in (ties by id)."""

    def __init__(self, queries: int, k: int) -> None:
        self.k = k
        self.dist = np.full((queries, 0), np.inf)
        self.ids = np.zeros((queries, 0), dtype=np.int64)

    def add(self, dist: Floats, ids: Ids) -> None:
        d = np.concatenate([self.dist, dist], axis=1)
        i = np.concatenate([self.ids, ids], axis=1)
        order = np.lexsort((i, d), axis=1)[:, : self.k]
        self.dist = np.take_along_axis(d, order, 1)
        self.ids = np.take_along_axis(i, order, 1)


def exact_search(vectors: Floats, queries: Floats, k: int) -> tuple[NDArray[np.float64], Ids]:
    """Squared distances and ids of the k nearest rows of ``vectors`` (N, D) to each query
    (Q, D), by brute force in float64 (ties by the smaller id).

    Near neighbours in a large atlas lie 1e-6 apart (squared) while every descriptor has unit
    length: the expansion |x|² − 2x·q + |q|² loses them in float32 rounding (FAISS's flat index
    uses it for batches of queries), so the reference search works in float64.
    """
    v = np.asarray(vectors)
    qv = np.asarray(queries, dtype=np.float64)
    k = min(k, v.shape[0])
    q2 = np.sum(qv * qv, 1)[:, None]
    best = _TopK(len(qv), k)
    block = max(4096, (1 << 24) // max(1, qv.shape[0]))  # ≤ 128 MB of distances at a time
    for start in range(0, v.shape[0], block):
        part = np.asarray(v[start : start + block], dtype=np.float64)
        d = np.einsum("ij,ij->i", part, part)[None, :] - 2.0 * qv @ part.T + q2
        take = min(k, part.shape[0])
        idx = np.argpartition(d, take - 1, axis=1)[:, :take]
        best.add(np.take_along_axis(d, idx, 1), idx + start)
    return np.maximum(best.dist, 0.0), best.ids


def _f32(block: Floats) -> NDArray[np.float32]:
    return np.ascontiguousarray(block, dtype=np.float32)


def _rows(parts: list[Floats], rows: Ids) -> NDArray[np.float32]:
    """Rows at global positions ``rows`` (sorted) of the blocks taken end to end."""
    starts = np.cumsum([0] + [len(b) for b in parts])
    out = []
    for i, b in enumerate(parts):
        mine = rows[(rows >= starts[i]) & (rows < starts[i + 1])] - starts[i]
        if mine.size:
            out.append(_f32(b[mine]))
    return np.concatenate(out)


def exact_blocks(
    blocks: Sequence[Floats] | Floats, queries: Floats, k: int
) -> tuple[NDArray[np.float64], Ids]:
    """:func:`exact_search` over blocks taken end to end (FAISS's flat search per block where
    it is installed — it computes the few-query distances directly — else NumPy), one block in
    memory at a time."""
    parts = [blocks] if isinstance(blocks, np.ndarray) else list(blocks)
    faiss = _faiss()
    q = _f32(queries)
    best = _TopK(len(q), k)
    start = 0
    for b in parts:
        if faiss is not None:
            flat = faiss.IndexFlatL2(b.shape[1])
            flat.add(_f32(b))
            d, i = flat.search(q, min(k, len(b)))
        else:
            d, i = exact_search(b, q, k)
        best.add(d, i + start)
        start += len(b)
    return best.dist, best.ids


def recall_at(found: Ids, truth: Ids) -> float:
    """Mean fraction of each row of ``truth`` (ids) that ``found`` holds."""
    hits = [np.intersect1d(f[f >= 0], t[t >= 0]).size / max(1, (t >= 0).sum())
            for f, t in zip(found, truth, strict=True)]  # fmt: skip
    return float(np.mean(hits))


@dataclass
class Index:
    """A loaded search index over an atlas's descriptors (``kind`` "exact" or "ivf")."""

    kind: str
    handle: Any
    """A FAISS index, or the (N, D) float32 descriptors for the NumPy exact search."""
    nprobe: int = 0

    @property
    def storage(self) -> str:
        """How the index holds the descriptors: "float16" or "float32"."""
        return "float16" if hasattr(self.handle, "sq") else "float32"

    @property
    def size(self) -> int:
        return int(self.handle.ntotal) if hasattr(self.handle, "ntotal") else len(self.handle)

    @classmethod
    def build(cls, blocks: Sequence[Floats] | Floats, *, kind: str | None = None) -> Index:
        """An index over the rows of ``blocks`` (arrays (n_i, D) in order, e.g. each shard's
        descriptors, memory-mapped: one block at a time is read, so memory stays bounded by the
        index itself): exact up to :data:`EXACT_UP_TO` rows, else IVF."""
        parts = [blocks] if isinstance(blocks, np.ndarray) else list(blocks)
        n = sum(len(b) for b in parts)
        d = parts[0].shape[1]
        faiss = _faiss()
        kind = kind or ("exact" if n <= EXACT_UP_TO or faiss is None else "ivf")
        if kind == "exact":
            if faiss is None:
                return cls("exact", np.concatenate([_f32(b) for b in parts]))
            flat = faiss.IndexFlatL2(d)
            for b in parts:
                flat.add(_f32(b))
            return cls("exact", flat)
        if faiss is None:
            raise ImportError("an IVF index needs faiss (pip install faiss-cpu)")
        nlist = int(np.clip(2 ** round(np.log2(2.0 * np.sqrt(n))), 16, 65536))
        train = _rows(parts, np.linspace(0, n - 1, min(n, 40 * nlist)).astype(np.int64))
        quantizer = faiss.IndexFlatL2(d)
        ivf = (
            faiss.IndexIVFFlat(quantizer, d, nlist)
            if n < HALF_PRECISION_FROM
            else faiss.IndexIVFScalarQuantizer(
                quantizer, d, nlist, faiss.ScalarQuantizer.QT_fp16, faiss.METRIC_L2
            )
        )
        ivf.cp.seed = _SEED
        ivf.train(train)
        for b in parts:
            ivf.add(_f32(b))
        return cls("ivf", ivf, nprobe=1)

    def tune(
        self, blocks: Sequence[Floats] | Floats, queries: Floats, variants: int, k: int = 10
    ) -> float:
        """Choose the least power-of-two ``nprobe`` whose recall@k (over variant sets of
        ``queries``, (Q·V, D)) against the exact search over ``blocks`` (as :meth:`build`)
        reaches :data:`TARGET_RECALL`; returns that recall (1.0 for an exact index)."""
        if self.kind == "exact":
            return 1.0
        truth = merge_variants(*exact_blocks(blocks, queries, k), variants, k)[1]
        nlist = self.handle.nlist
        probe, recall = 1, 0.0
        while True:
            self.nprobe = probe
            recall = recall_at(self.search(queries, variants, k)[1], truth)
            if recall >= TARGET_RECALL or probe >= nlist:
                return recall
            probe *= 2

    def search(self, queries: Floats, variants: int, k: int) -> tuple[NDArray[np.float64], Ids]:
        """(Q, k) squared distances and ids for queries given as (Q·V, D) variant rows."""
        q = np.ascontiguousarray(queries, dtype=np.float32)
        if isinstance(self.handle, np.ndarray):
            d, i = exact_search(self.handle, q, k)
        else:
            if self.kind == "ivf":
                self.handle.nprobe = self.nprobe
            d, i = self.handle.search(q, min(k, self.size))
        return merge_variants(d, i, variants, k)

    def save(self, path: Path) -> None:
        faiss = _faiss()
        if faiss is None or isinstance(self.handle, np.ndarray):
            return  # the NumPy search reads the shards instead
        with atomic_path(path) as tmp:
            faiss.write_index(self.handle, str(tmp))

    @classmethod
    def load(cls, path: Path, kind: str, nprobe: int, vectors: Floats | None = None) -> Index:
        faiss = _faiss()
        if faiss is None or not Path(path).exists():
            if vectors is None:
                raise ImportError("this atlas's index needs faiss (pip install faiss-cpu)")
            return cls("exact", np.ascontiguousarray(vectors, dtype=np.float32))
        return cls(kind, faiss.read_index(str(path)), nprobe=nprobe)

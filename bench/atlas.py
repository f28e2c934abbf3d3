"""Atlas benchmark: build rate, disk per million curves, query latency and recall@10.

    python bench/atlas.py            # 1e5 and 1e6 four-bar atlases (a few minutes)
    python bench/atlas.py --large    # also 1e7 (about 3.2 GB of disk, several minutes)

Every atlas is built into a temporary directory (removed afterwards) by the library's own
:func:`linkwright.atlas.build`: in this process (``--workers 0``) and on a local Dask cluster
of two worker processes. The queries are curves of four-bars drawn from the family's
distribution on a stream no shard uses (so none is in the atlas), each placed anywhere.

Figures, per atlas size N:

- build: curves per second over the shards (sampling, tracing, describing, writing), and the
  whole build with the index;
- disk: bytes per million curves (shards, digests, index);
- index search: p50 and p95 latency of one query (its 4 descriptor variants, 10 nearest),
  against the exact (flat) search in the same run, and recall@10 of the index against it;
- query: p50 of the whole :func:`linkwright.atlas.query` (index, re-ranking 50 candidates by
  the aligned error, placing the best 5), without refinement.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from linkwright.atlas import build, open_atlas, query
from linkwright.atlas.build import BuildSpec, _rng
from linkwright.atlas.families import curves, describe_variants, sample
from linkwright.atlas.index import Index, exact_search, merge_variants, recall_at

QUERIES = 200
_BENCH_STREAM = 2**31 + 1  # neither a shard's stream nor the tuning queries'


def _queries(spec: BuildSpec, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Query curves (count, 128, 2), each moved, turned and scaled at random, and their
    descriptor variants (count, V, D)."""
    rng = _rng(spec, _BENCH_STREAM)
    designs = sample(spec.family, rng, count)
    local = curves(spec.family, designs, 128)
    angle = rng.uniform(-np.pi, np.pi, count)
    rot = np.stack([np.cos(angle), np.sin(angle), -np.sin(angle), np.cos(angle)], -1)
    moved = np.einsum("qnj,qjk->qnk", local, rot.reshape(-1, 2, 2))
    moved = moved * rng.uniform(0.1, 10.0, (count, 1, 1)) + rng.normal(0, 5, (count, 1, 2))
    return moved, describe_variants(spec.family, moved, spec.harmonics)


def _percentiles(times: list[float]) -> tuple[float, float]:
    t = np.array(times) * 1e3
    return float(np.percentile(t, 50)), float(np.percentile(t, 95))


def _timed_searches(
    atlas, curves_q: np.ndarray, variants: np.ndarray, whole: int
) -> tuple[list[np.ndarray], list[float], list[float]]:
    """Each query's 10 ids from the index and its search time, then the whole query's time
    (index, re-ranking, placement) for the first ``whole`` curves."""
    v = variants.shape[1]
    found, t_index, t_query = [], [], []
    for q in variants:
        t = time.perf_counter()
        found.append(atlas.index.search(q, v, 10)[1][0])
        t_index.append(time.perf_counter() - t)
    for pts in curves_q[:whole]:
        t = time.perf_counter()
        query(atlas, pts, top=5)
        t_query.append(time.perf_counter() - t)
    return found, t_index, t_query


def bench_size(n: int, workers: int, root: Path) -> dict[str, float]:
    out = root / f"fourbar-{n}-w{workers}"
    t0 = time.perf_counter()
    manifest = build("fourbar", n, out, workers=workers)
    total = time.perf_counter() - t0
    figures = manifest["build"]
    result = {
        "n": n,
        "workers": workers,
        "rate_shards": n / figures["seconds_shards"],
        "rate_total": n / total,
        "seconds_total": total,
        "mb_per_million": figures["bytes"] / n * 1e6 / 1e6,
        "index": manifest["index"]["kind"],
        "nprobe": manifest["index"]["nprobe"],
        "nlist": manifest["index"]["nlist"],
    }
    atlas = open_atlas(out)
    curves_q, variants = _queries(atlas.spec, QUERIES)
    v = variants.shape[1]
    vectors = atlas.descriptors()
    rows = variants.reshape(-1, variants.shape[-1])
    truth = merge_variants(*exact_search(vectors, rows, 10), v, 10)[1]
    found, t_index, t_query = _timed_searches(atlas, curves_q, variants, whole=50)
    flat = Index.build(vectors, kind="exact")
    t_flat = []
    for q in variants[:50]:
        t = time.perf_counter()
        flat.search(q, v, 10)
        t_flat.append(time.perf_counter() - t)
    result["recall_at_10"] = recall_at(np.array(found), truth)
    result["index_p50_ms"], result["index_p95_ms"] = _percentiles(t_index)
    result["flat_p50_ms"], _ = _percentiles(t_flat)
    result["query_p50_ms"], result["query_p95_ms"] = _percentiles(t_query)
    shutil.rmtree(out)
    return result


def measure_existing(path: Path) -> None:
    """Latency of an atlas built elsewhere (the 10^8 one: `linkwright atlas build --count
    100000000 --scheduler ...`), its recall@10 being the one measured when it was built (exact
    search over 10^8 rows per query is the slow part that the index exists to avoid)."""
    t0 = time.perf_counter()
    atlas = open_atlas(path)
    t_open = time.perf_counter() - t0
    manifest, figures = atlas.manifest, atlas.manifest["build"]
    curves_q, variants = _queries(atlas.spec, QUERIES)
    _, t_index, t_query = _timed_searches(atlas, curves_q, variants, whole=30)
    p50, p95 = _percentiles(t_index)
    q50, _ = _percentiles(t_query)
    index = manifest["index"]
    print(f"| {atlas.count:.0e} | {figures['workers']} | "
          f"{figures['curves_computed'] / figures['seconds_shards']:.3g} | "
          f"{figures['seconds_total']:.0f} s | {figures['bytes'] / atlas.count * 1e6 / 1e6:.0f} | "
          f"{index['kind']} {index['nprobe']}/{index['nlist']} ({index.get('storage', 'float32')})"
          f" | {p50:.2f} / {p95:.2f} ms | — | — | {index['recall_at_10']:.3f} (at build) "
          f"| {q50:.1f} ms |")  # fmt: skip
    print(f"opened in {t_open:.1f} s")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--large", action="store_true", help="also a 1e7 atlas")
    parser.add_argument("--dir", type=Path, default=None, help="where to build (default tmp)")
    parser.add_argument(
        "--measure",
        type=Path,
        default=None,
        metavar="ATLAS",
        help="only time an atlas built before",
    )
    args = parser.parse_args()
    if args.measure is not None:
        measure_existing(args.measure)
        return 0
    sizes = [100_000, 1_000_000] + ([10_000_000] if args.large else [])
    print(f"# atlas benchmark — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {sys.version.split()[0]}")  # fmt: skip
    root = Path(tempfile.mkdtemp(prefix="linkwright-bench-", dir=args.dir))
    header = (
        "| N | workers | build curves/s (shards) | whole build | MB per 1e6 | index "
        "| index p50 / p95 | exact p50 | speed-up | recall@10 | query p50 |"
    )
    print(header)
    print("|---" * 11 + "|")
    try:
        for n in sizes:
            for workers in (0, 2) if n == 1_000_000 else (2,) if n > 1_000_000 else (0,):
                r = bench_size(n, workers, root)
                index = f"{r['index']}" + (f" {r['nprobe']}/{r['nlist']}" if r["nlist"] else "")
                print(
                    f"| {n:.0e} | {workers} | {r['rate_shards']:.3g} | {r['seconds_total']:.1f} s "
                    f"| {r['mb_per_million']:.0f} | {index} | {r['index_p50_ms']:.2f} / "
                    f"{r['index_p95_ms']:.2f} ms | {r['flat_p50_ms']:.2f} ms "
                    f"| {r['flat_p50_ms'] / r['index_p50_ms']:.1f}× | {r['recall_at_10']:.3f} "
                    f"| {r['query_p50_ms']:.1f} ms |",
                    flush=True,
                )
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print("targets: 1e7 built in under 30 min; index query p50 under 20 ms at 1e7 and 5 ms at "
          "1e6 with recall@10 ≥ 0.95 against exact search")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Building an atlas: shards computed as Dask tasks, written atomically, resumable.

The atlas of ``count`` mechanisms is cut into shards of ``shard_size`` rows (the last one
shorter). Shard i draws its designs from its own random stream,
``SeedSequence(seed, spawn_key=(i,))``, so what it holds depends on (family, seed, i, its size,
samples, harmonics) and on nothing else: not on which worker computes it, in what order, or how
many workers there are. Tasks return their rows to the client, which writes them (workers need
no shared disk); a finished shard is never recomputed when a killed build is run again.

Shards are byte-identical across runs and worker counts on machines with the same instruction
set: the compiled kernels give each mechanism the same operations whichever thread runs it.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from linkwright.atlas import store
from linkwright.atlas.families import (
    BUILDABLE,
    FAMILIES,
    AtlasFamilyError,
    atlas_model,
    curves,
    describe,
    describe_variants,
    params_of,
    sample,
)
from linkwright.atlas.index import Index
from linkwright.engine import cost
from linkwright.mechanisms import Mechanism
from linkwright.mechanisms.parameters import ParameterError, decode, encode

__all__ = [
    "DEFAULT_SHARD_SIZE",
    "FORMAT",
    "AtlasBuildError",
    "BuildSpec",
    "build",
    "make_shard",
    "query_designs",
]

FORMAT = 1
DEFAULT_SHARD_SIZE = 65_536
TUNING_QUERIES = 256
_QUERY_STREAM = 2**31  # spawn key of the held-out queries: no shard index reaches it


class AtlasBuildError(ValueError):
    """A build that cannot run as asked (names the problem)."""


@dataclass(frozen=True)
class BuildSpec:
    """What an atlas holds; two builds with equal specs write byte-identical shards.

    ``template`` is the template mechanism of a family without a hand-written distribution
    (:func:`linkwright.mechanisms.parameters.encode`'s plain data): a composed linkage's
    structure, a Stephenson III's input; None for the family's default (a composed linkage has
    none).
    """

    family: str
    count: int
    seed: int = 0
    shard_size: int = DEFAULT_SHARD_SIZE
    samples: int = 64
    harmonics: int = 8
    format: int = FORMAT
    template: dict[str, Any] | None = None

    def __post_init__(self) -> None:
        if self.family not in BUILDABLE:
            raise AtlasBuildError(
                f"--family: must be one of {', '.join(BUILDABLE)}, got {self.family!r}"
            )
        if self.template is not None and self.family in FAMILIES:
            raise AtlasBuildError(
                f"--template: the {self.family} atlas has its own design distribution; a "
                "template is for the other families"
            )
        try:
            atlas_model(self.family, self.mechanism)
        except (AtlasFamilyError, ParameterError, ValueError) as exc:
            raise AtlasBuildError(str(exc)) from None
        checks = (
            ("count", self.count, 1),
            ("shard_size", self.shard_size, 1),
            ("samples", self.samples, 8),
            ("harmonics", self.harmonics, 2),
            ("seed", self.seed, 0),
        )
        for name, value, least in checks:
            if not isinstance(value, int | np.integer) or value < least:
                raise AtlasBuildError(f"{name}: must be a whole number ≥ {least}, got {value!r}")
        if self.harmonics * 2 >= self.samples:
            raise AtlasBuildError(
                f"harmonics: {self.harmonics} harmonics need more than {2 * self.harmonics} "
                f"samples per curve, got {self.samples}"
            )

    @property
    def sizes(self) -> list[int]:
        full, rest = divmod(self.count, self.shard_size)
        return [self.shard_size] * full + ([rest] if rest else [])

    @property
    def mechanism(self) -> Mechanism | None:
        """The template as a mechanism (None: the family's default)."""
        return None if self.template is None else decode(self.template)

    @property
    def params(self) -> tuple[str, ...]:
        """The names of a row's columns."""
        return params_of(self.family, self.mechanism)

    def as_dict(self) -> dict[str, Any]:
        out = asdict(self)
        if self.template is None:
            del out["template"]  # atlases of the hand-written families read as they always did
        return out


def _rng(spec: BuildSpec, stream: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(spec.seed, spawn_key=(stream,)))


def make_shard(spec: BuildSpec, index: int) -> np.ndarray:
    """Shard ``index``'s rows: designs from the shard's own stream, their curves at
    ``spec.samples`` inputs and their descriptors (the Dask task; a pure function)."""
    size = spec.sizes[index]
    template = spec.mechanism
    try:
        params = sample(spec.family, _rng(spec, index), size, template)
    except AtlasFamilyError as exc:
        raise AtlasBuildError(str(exc)) from None
    traced = curves(spec.family, params, spec.samples, template)
    desc = describe(spec.family, traced, spec.harmonics, template)
    if not np.all(np.isfinite(desc)):
        # The filter keeps only linkages that turn fully, so this is a bug, not bad luck.
        raise AtlasBuildError(f"shard {index}: a kept design traced no curve")
    return store.shard_table(np.stack([params[k] for k in spec.params], -1), desc)


def query_designs(spec: BuildSpec, count: int = TUNING_QUERIES) -> dict[str, np.ndarray]:
    """Designs from the family's distribution but outside every shard's stream: the held-out
    queries the index is tuned and measured on."""
    try:
        return sample(spec.family, _rng(spec, _QUERY_STREAM), count, spec.mechanism)
    except AtlasFamilyError as exc:
        raise AtlasBuildError(str(exc)) from None


def _in_process(spec: BuildSpec, todo: list[int]) -> Iterable[tuple[int, np.ndarray]]:
    for i in todo:
        yield i, make_shard(spec, i)


def _on_dask(
    spec: BuildSpec, todo: list[int], workers: int, scheduler: str | None
) -> Iterable[tuple[int, np.ndarray]]:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        from linkwright._extras import hint

        raise AtlasBuildError(
            hint("atlas", "a Dask build") + "; --workers 0 builds in this process"
        ) from None
    # Dask's nannies set OMP_NUM_THREADS=1 (and the like) in this process's environment before
    # they spawn workers, and leave it: FAISS's BLAS, loaded afterwards for the index, would
    # then run on one core.
    environ = dict(os.environ)
    cluster = None
    # distributed ships py.typed but leaves these calls unannotated (disallow_untyped_calls):
    # each is ignored where it is made, not the package as a whole.
    if scheduler is None:
        cluster = LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    try:
        client = Client(  # type: ignore[no-untyped-call]
            cluster if cluster is not None else scheduler, timeout="30s"
        )
    except OSError as exc:
        if cluster is not None:
            cluster.close()
        raise AtlasBuildError(f"--scheduler: cannot reach {scheduler} ({exc})") from None
    try:
        # A window of tasks in flight keeps finished shards from piling up on the workers.
        window = 2 * max(1, sum(client.nthreads().values()))  # type: ignore[no-untyped-call]
        pending = list(todo)
        running = as_completed()  # type: ignore[no-untyped-call]

        def submit_next() -> None:
            i = pending.pop(0)
            running.add(  # type: ignore[no-untyped-call]
                client.submit(make_shard, spec, i, key=f"linkwright-shard-{i}-{os.getpid()}")
            )

        for _ in range(min(window, len(pending))):
            submit_next()
        for future in running:
            table = future.result()
            i = int(future.key.split("-")[2])
            future.release()
            if pending:
                submit_next()
            yield i, table
    finally:
        client.close()  # type: ignore[no-untyped-call]
        if cluster is not None:
            cluster.close()
        os.environ.clear()
        os.environ.update(environ)


def build(
    family: str,
    count: int,
    out: str | os.PathLike[str],
    *,
    seed: int = 0,
    shard_size: int = DEFAULT_SHARD_SIZE,
    samples: int = 64,
    harmonics: int = 8,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[float], None] | None = None,
    template: Mechanism | None = None,
) -> dict[str, Any]:
    """Build (or finish building) an atlas of ``count`` mechanisms of ``family`` in ``out``.

    Parameters
    ----------
    family : any registered family (:data:`~linkwright.atlas.families.BUILDABLE`);
        :mod:`linkwright.atlas.families` states each one's design distribution.
    count : mechanisms in the atlas (all of them turn fully).
    out : the atlas directory (created).
    seed : the same seed gives the same shards, whatever ``workers`` or ``scheduler``.
    shard_size, samples, harmonics : rows per shard; curve samples per turn; harmonics per
        descriptor.
    workers : 0 builds in this process; n > 0 on a local Dask cluster of n processes; default
        the machine's cores, or this process for a single shard.
    scheduler : address of a running Dask scheduler (its workers need linkwright installed).
    progress : called with the fraction done, in [0, 1].
    template : for a family other than the four-bar, the geared five-bar and the spherical
        four-bar, the mechanism whose structure and choices the atlas keeps (a composed
        linkage needs one; a Stephenson III's gives its input); its numbers are not used,
        except a composed linkage's, about which its designs are drawn.

    Returns
    -------
    The manifest (also written to ``out/atlas.json``): the spec, each shard's count and
    SHA-256, the index and the build's figures.

    Raises
    ------
    AtlasBuildError
        For a bad spec, one over the budgets of :func:`linkwright.engine.cost.check_atlas`
        (entries, samples, entries × samples, a shard's memory), or an ``out`` that holds a
        different atlas.
    """
    try:
        encoded = None if template is None else encode(template)
        spec = BuildSpec(family, count, seed, shard_size, samples, harmonics, template=encoded)
    except (AtlasFamilyError, ParameterError) as exc:
        raise AtlasBuildError(str(exc)) from None
    try:
        # Bounded here, not in BuildSpec: an atlas built before a budget changed still opens.
        cost.check_atlas(spec.count, spec.samples, spec.shard_size)
    except cost.CostError as exc:
        raise AtlasBuildError(str(exc)) from None
    root = Path(out)
    if root.exists() and not root.is_dir():
        raise AtlasBuildError(f"--out: {root} exists and is not a directory")
    root.mkdir(parents=True, exist_ok=True)
    # Held from before the first look at the directory to after the last file: a second build
    # into it is refused at once, and never clears this one's temporary files or mixes shards.
    try:
        with store.build_lock(root):
            return _build_locked(spec, root, workers, scheduler, progress)
    except store.AtlasLocked as exc:
        raise AtlasBuildError(f"--out: {exc}") from None


def _build_locked(
    spec: BuildSpec,
    root: Path,
    workers: int | None,
    scheduler: str | None,
    progress: Callable[[float], None] | None,
) -> dict[str, Any]:
    """:func:`build`'s work, done while holding the directory's build lock."""
    family = spec.family
    store.clear_partial(root)
    previous = root / store.BUILD
    if previous.exists():
        held = store.read_json(previous)
        if held != spec.as_dict():
            raise AtlasBuildError(
                f"--out: {root} holds a different atlas ({_describe(held)}); "
                f"choose another directory or delete it"
            )
    if (root / store.MANIFEST).exists():
        if progress:
            progress(1.0)
        return store.read_json(root / store.MANIFEST)
    store.write_json(previous, spec.as_dict())

    t0 = time.perf_counter()
    sizes = spec.sizes
    digests = store.finished_shards(root, sizes)
    todo = [i for i in range(len(sizes)) if i not in digests]
    resumed = len(digests)
    computed = sum(sizes[i] for i in todo)
    if workers is None:
        workers = 0 if len(todo) <= 1 else (os.cpu_count() or 1)
    if workers < 0:
        raise AtlasBuildError(f"--workers: must be 0 (this process) or more, got {workers}")
    results = (
        _on_dask(spec, todo, workers, scheduler)
        if todo and (scheduler is not None or workers > 0)
        else _in_process(spec, todo)
    )
    done_rows = sum(sizes[i] for i in digests)
    shard_weight = 0.9
    for i, table in results:
        digests[i] = store.write_shard(root, i, table)
        done_rows += sizes[i]
        if progress:
            progress(shard_weight * done_rows / spec.count)
    t_shards = time.perf_counter() - t0

    blocks = store.shard_descriptors(root, len(sizes))
    index = Index.build(blocks)
    recall = 1.0  # an exact index finds every neighbour: no queries to tune it on
    if index.kind != "exact":
        queries = describe_variants(
            family,
            curves(family, query_designs(spec), spec.samples, spec.mechanism),
            spec.harmonics,
            spec.mechanism,
        )
        recall = index.tune(blocks, queries.reshape(-1, queries.shape[-1]), queries.shape[-2])
    index.save(root / store.INDEX)
    t_all = time.perf_counter() - t0
    if progress:
        progress(1.0)
    manifest = {
        "spec": spec.as_dict(),
        "params": list(spec.params),
        "shards": [{"count": sizes[i], "sha256": digests[i]} for i in range(len(sizes))],
        "descriptor_size": int(blocks[0].shape[1]),
        "index": {
            "kind": index.kind,
            "nlist": int(getattr(index.handle, "nlist", 0)),
            "nprobe": index.nprobe,
            "storage": index.storage,
            "recall_at_10": recall,
            "tuning_queries": 0 if index.kind == "exact" else TUNING_QUERIES,
            # What `atlas info` and `query` check the index file against.
            **_index_file(root / store.INDEX),
        },
        "build": {
            "seconds_shards": round(t_shards, 3),
            "seconds_total": round(t_all, 3),
            "curves_computed": computed,
            "shards_resumed": resumed,
            "workers": "scheduler " + scheduler if scheduler else workers,
            "bytes": _bytes(root),
        },
    }
    store.write_json(root / store.MANIFEST, manifest)
    return manifest


def _index_file(path: Path) -> dict[str, Any]:
    """The index file's SHA-256 and size, or nothing where the search is exact (no file)."""
    if not path.exists():
        return {}
    return {"sha256": store.file_digest(path), "bytes": path.stat().st_size}


def _describe(spec: dict[str, Any]) -> str:
    keys = ("family", "count", "seed", "shard_size", "samples", "harmonics")
    return ", ".join(f"{k} {spec.get(k)}" for k in keys)


def _bytes(root: Path) -> int:
    return sum(p.stat().st_size for p in root.iterdir() if p.is_file())

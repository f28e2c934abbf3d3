"""Case (d): 10^6 random four-bars × 64 inputs reduced to curve descriptors, in batches.

Run as ``python bench/descriptors.py [--curves N]``; ``bench/run.py`` runs it in a process of its
own so that the peak resident memory it reports is this case's alone. Prints one JSON line: the
rate (curves per second, simulation and descriptors together), the peak RSS, and the NumPy
reference's rate on a slice of the same work, measured in the same run.

Memory is bounded by the batch, not by N: each batch's coupler points (P alone: the descriptors
need no other joint) go into the same preallocated array, and each batch's descriptors (float32,
4·harmonics per curve) are appended to a file, as an atlas shard would be.

``--family NAME`` (``make bench`` runs it for geared five-bars and planar six-bars, issue 22's
target of 5e5 curves/s on 2 cores): the same work for an atlas family, through the atlas's own
path (``atlas.families.curves``: the plan's compiled kernel writing the traced point alone,
then ``describe``). The designs are drawn once from the family's distribution (a thousand,
repeated to fill each batch: drawing designs that turn fully is the atlas's sampling, not what
is timed here); the reference is the same call with the compiled plans switched off (the plan
evaluator), on a slice, in the same run. The line then carries the family, the load average and
the rate per CPU-second of the process too (the machine is shared).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from run import crank_rockers

from linkwright.curves import descriptors
from linkwright.curves.fourier import DEFAULT_HARMONICS, _descriptors_reference
from linkwright.engine.kernels import fourbar_coupler_points

FIELDS = ("A0", "B0", "crank", "coupler", "rocker", "u", "v", "assembly")


def peak_rss() -> int:
    """Bytes: this process image's high-water resident set (VmHWM). Not getrusage's ru_maxrss,
    which Linux carries over from the parent across fork and exec."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
    import resource  # not Linux: the nearest there is

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curves", type=int, default=1_000_000)
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--batch", type=int, default=50_000)
    parser.add_argument("--reference-curves", type=int, default=20_000)
    parser.add_argument("--family", default=None, help="an atlas family (see module doc)")
    args = parser.parse_args(argv)
    if args.family is not None:
        return family_rate(args)
    theta = np.linspace(0.0, 2.0 * np.pi, args.samples, endpoint=False)
    width = 4 * DEFAULT_HARMONICS
    out = np.empty((args.batch, args.samples, 2))

    def batch(start: int, stop: int, seed: int) -> np.ndarray:
        p = crank_rockers(stop - start, seed=seed).params()
        n = stop - start
        return fourbar_coupler_points(*(p[k] for k in FIELDS), theta, out=out[:n])

    warm = batch(0, 1000, 0)
    descriptors(warm[:100])
    descriptors(warm)  # compile both the serial and the parallel kernels first
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "descriptors.f32"
        t0 = time.perf_counter()
        with path.open("wb") as sink:
            for i, start in enumerate(range(0, args.curves, args.batch)):
                stop = min(args.curves, start + args.batch)
                d = descriptors(batch(start, stop, seed=1000 + i))
                d.astype(np.float32).tofile(sink)
        elapsed = time.perf_counter() - t0
        peak = peak_rss()
        kept = np.fromfile(path, dtype=np.float32).reshape(-1, width)
    ref_n = min(args.reference_curves, args.batch, args.curves)
    P = batch(0, min(args.batch, args.curves), seed=1000)[:ref_n]
    t1 = time.perf_counter()
    ref = _descriptors_reference(P)
    ref_elapsed = time.perf_counter() - t1
    agree = float(np.nanmax(np.abs(ref - kept[:ref_n])))
    json.dump(
        {
            "curves": args.curves,
            "samples": args.samples,
            "seconds": elapsed,
            "rate": args.curves / elapsed,
            "peak_rss_bytes": peak,
            "reference_rate": ref_n / ref_elapsed,
            "max_difference_vs_reference": agree,  # float32 storage
            "nan_descriptors": int(np.isnan(kept).any(axis=1).sum()),
        },
        sys.stdout,
    )
    sys.stdout.write("\n")
    return 0


def family_rate(args: argparse.Namespace) -> int:
    """The --family case (module doc): curves and descriptors through the atlas's path."""
    from linkwright.atlas import families
    from linkwright.engine import compile as compiled_plans

    drawn = families.sample(args.family, np.random.default_rng(0), 1000)
    size = len(next(iter(drawn.values())))
    reps = -(-args.batch // size)
    designs = {k: np.concatenate([v] * reps)[: args.batch] for k, v in drawn.items()}

    def batch(n: int) -> np.ndarray:
        part = {k: v[:n] for k, v in designs.items()}
        points = families.curves(args.family, part, args.samples)
        return families.describe(args.family, points, DEFAULT_HARMONICS)

    batch(args.batch)  # compile (or load) the kernels first
    done = 0
    t0, c0 = time.perf_counter(), time.process_time()
    while done < args.curves:
        n = min(args.batch, args.curves - done)
        batch(n).astype(np.float32)
        done += n
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    ref_n = min(args.reference_curves, args.batch, args.curves)
    kept = batch(ref_n)
    available = compiled_plans.available
    compiled_plans.available = lambda: False  # type: ignore[assignment]
    try:
        t1 = time.perf_counter()
        ref = batch(ref_n)
        ref_elapsed = time.perf_counter() - t1
    finally:
        compiled_plans.available = available  # type: ignore[assignment]
    json.dump(
        {
            "family": args.family,
            "compiled": compiled_plans.available(),
            "curves": args.curves,
            "samples": args.samples,
            "seconds": elapsed,
            "rate": args.curves / elapsed,
            "rate_per_cpu_second": args.curves / cpu,
            "load_average": os.getloadavg()[0],
            "reference_rate": ref_n / ref_elapsed,
            "max_difference_vs_reference": float(np.nanmax(np.abs(ref - kept))),
            "same_nan": bool(np.array_equal(np.isnan(ref), np.isnan(kept))),
        },
        sys.stdout,
    )
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

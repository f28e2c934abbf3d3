"""Case (d): 10^6 random four-bars × 64 inputs reduced to curve descriptors, in batches.

Run as ``python bench/descriptors.py [--curves N]``; ``bench/run.py`` runs it in a process of its
own so that the peak resident memory it reports is this case's alone. Prints one JSON line: the
rate (curves per second, simulation and descriptors together), the peak RSS, and the NumPy
reference's rate on a slice of the same work, measured in the same run.

Memory is bounded by the batch, not by N: each batch's coupler points (P alone: the descriptors
need no other joint) go into the same preallocated array, and each batch's descriptors (float32,
4·harmonics per curve) are appended to a file, as an atlas shard would be.
"""

from __future__ import annotations

import argparse
import json
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
    args = parser.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())

"""Engine throughput, every figure against baselines measured in the same run.

Run as ``python bench/run.py`` (``make bench``, which also installs the peers). Cases (issue 5):

(a) 10,000 random Grashof crank-rockers × 360 inputs, positions of every moving joint (A, B, P):
    linkwright's plan (``solve``), its compiled kernel (numba, when installed), the obvious NumPy
    closed form of ``bench/baselines.py`` and pylinkage (when installed);
(b) one four-bar × 360 inputs: the latency of a single call, positions and with derivatives;
(c) 10,000 spherical crank-rockers × 360 inputs (plan, kernel, NumPy closed form);
(d) 10^6 four-bars x 64 inputs reduced to curve descriptors (bench/descriptors.py, its own
    process); (e) path synthesis is bench/synthesis.py; (f) the atlas query is bench/atlas.py.

Every contestant's positions are checked against linkwright's plan before anything is timed.
Rates count joint positions (3 moving joints per mechanism-sample). The bound is memory
bandwidth: writing A, B, P costs 48 bytes per planar mechanism-sample (72 on the sphere). Three
bandwidths are measured in the same run: NumPy's copy and fill on one thread, and a streaming
fill on every thread (what the machine can store at all: the bound each rate is a fraction of).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable

import numpy as np
from baselines import fourbar_positions, spherical_fourbar_positions

from linkwright.engine.kernels import STREAMING
from linkwright.mechanisms import FourBar, SphericalFourBar, solve

MOVING_JOINTS = ("A", "B", "P")
_stream_pair, _store_fence = STREAMING  # plain here; compiled into _streaming_fill
prange = range  # numba.prange in the compiled fill


def crank_rockers(n: int, seed: int = 0) -> FourBar:
    """Grashof crank-rockers: crank in [0.05, 0.19], the other links in [0.6, 1.0], so the crank
    is the shortest link and s + l ≤ 0.19 + 1.0 < 1.2 ≤ p + q: it turns fully, every input is
    assembled. Frames at random places and angles, coupler points anywhere near the coupler."""
    rng = np.random.default_rng(seed)
    frame, coupler, rocker = rng.uniform(0.6, 1.0, (3, n))
    angle = rng.uniform(-np.pi, np.pi, n)
    A0 = rng.uniform(-10.0, 10.0, (n, 2))
    return FourBar(
        A0=A0,
        B0=A0 + frame[:, None] * np.stack((np.cos(angle), np.sin(angle)), -1),
        crank=rng.uniform(0.05, 0.19, n),
        coupler=coupler,
        rocker=rocker,
        u=rng.uniform(-1.0, 1.0, n),
        v=rng.uniform(-1.0, 1.0, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def spherical_crank_rockers(n: int, seed: int = 2) -> SphericalFourBar:
    """Spherical crank-rockers: crank 10°–20°, frame, coupler and rocker 60°–90° (every input
    assembles: the arc A B0 stays within the dyad's range), coupler points anywhere."""
    rng = np.random.default_rng(seed)
    deg = np.radians
    return SphericalFourBar(
        frame=deg(rng.uniform(60, 90, n)),
        crank=deg(rng.uniform(10, 20, n)),
        coupler=deg(rng.uniform(60, 90, n)),
        rocker=deg(rng.uniform(60, 90, n)),
        point_arc=rng.uniform(0.0, 1.0, n),
        point_angle=rng.uniform(-np.pi, np.pi, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def best_of(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm-up: first-touch allocation, caches, compilation
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def median_of(fn: Callable[[], object], runs: int) -> float:
    fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _streaming_fill(out, value):
    # Each thread streams its own blocks of 16-byte pairs, as the planar kernel stores.
    pairs = out.shape[0] // 2
    block = 2**16
    for b in prange((pairs + block - 1) // block):
        for k in range(b * block, min(pairs, (b + 1) * block)):
            _stream_pair(out, k, value, value)
        _store_fence()


def bandwidths(megabytes: int = 400, repeats: int = 5) -> tuple[float, float, float | None]:
    """Bytes per second stored by a large ``np.copyto`` (read + write counted as one write, the
    way the rates below count only what they store), by a large ``fill`` (stores alone, one
    thread), and by a streaming fill on every thread (None without numba): the most the machine
    can store, so the bound of a kernel that only writes its results."""
    src = np.ones(megabytes * 2**20 // 8)
    dst = np.empty_like(src)
    copy = src.nbytes / best_of(lambda: np.copyto(dst, src), repeats)
    fill = dst.nbytes / best_of(lambda: dst.fill(2.0), repeats)
    return copy, fill, streaming_bandwidth(dst, repeats)


def streaming_bandwidth(dst: np.ndarray, repeats: int = 5) -> float | None:
    """Bytes per second a streaming fill of ``dst`` stores on numba's threads (None without
    numba)."""
    kernels = optional_kernels()
    if kernels is None:
        return None
    fill = kernels.compiled(_streaming_fill, helpers=kernels.STREAMING)
    pairs = dst.reshape(-1, 2)
    return dst.nbytes / best_of(lambda: fill(pairs, 2.0), repeats)


def kernel_profile(
    kernels, planar, sphere, theta, streamed_all: float
) -> dict[str, tuple[float, float, float, float]]:
    """What limits each kernel, without hardware counters (this machine's VM has none): its
    rate on one thread and on every thread, each against the most that many threads can store
    (a streaming fill, measured here for one thread; ``streamed_all`` for every thread). A
    kernel far below its bound on one thread is bound by its arithmetic, not by memory.
    ``planar`` and ``sphere`` are each a kernel's arguments and the outputs cases (a) and (c)
    already timed it with."""
    import numba

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        streamed_one = streaming_bandwidth(np.empty(400 * 2**20 // 8))
    finally:
        numba.set_num_threads(threads)
    rates = {}
    for name, fn, (args, out) in (
        ("planar kernel (a)", kernels.fourbar_positions, planar),
        ("spherical kernel (c)", kernels.spherical_fourbar_positions, sphere),
    ):
        joints = len(MOVING_JOINTS) * out[0].shape[0] * out[0].shape[1]
        width = out[0].shape[2]
        measured = []
        for count in (1, threads):
            numba.set_num_threads(count)
            try:
                measured.append(
                    joints / best_of(lambda f=fn, a=args, o=out: f(*a, theta, out=o), 5)
                )
            finally:
                numba.set_num_threads(threads)
        bound = 1 / (8 * width)  # joint positions per stored byte
        rates[name] = (
            measured[0], measured[0] / (bound * streamed_one),
            measured[1], measured[1] / (bound * streamed_all),
        )  # fmt: skip
    return rates


def descriptor_case(curves: int, samples: int) -> dict:
    """Case (d) in a process of its own, so that its peak memory is its own."""
    import json
    import subprocess
    from pathlib import Path

    script = Path(__file__).with_name("descriptors.py")
    done = subprocess.run(
        [sys.executable, str(script), "--curves", str(curves), "--samples", str(samples)],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def check(name: str, got, reference: dict[str, np.ndarray], tol: float) -> None:
    worst = max(
        float(np.nanmax(np.abs(np.asarray(g) - reference[j])))
        for j, g in zip(MOVING_JOINTS, got, strict=True)
    )
    if not worst < tol:
        raise SystemExit(f"{name} disagrees with linkwright's plan by {worst:g}")


def optional_kernels():
    try:
        from linkwright.engine import kernels
    except ImportError:
        return None
    return kernels if kernels.available() else None


def optional_peers():
    try:
        import peers
        import pylinkage  # noqa: F401 - the peer itself, not only its adapter
    except ImportError:
        return None
    return peers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mechanisms", type=int, default=10_000)
    parser.add_argument("--samples", type=int, default=360)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--latency-runs", type=int, default=300)
    parser.add_argument("--descriptor-curves", type=int, default=1_000_000)
    args = parser.parse_args(argv)
    n, s = args.mechanisms, args.samples
    start = time.perf_counter()
    kernels = optional_kernels()
    peers = optional_peers()
    theta = np.linspace(-np.pi, np.pi, s, endpoint=False)
    bandwidth, store_bandwidth, streamed_bandwidth = bandwidths()
    # The most the machine stores on every thread; NumPy's one-thread fill without numba.
    limit = streamed_bandwidth or store_bandwidth

    # (a) planar batch
    m = crank_rockers(n)
    p = {k: np.asarray(v) for k, v in m.params().items()}
    planar_args = tuple(p[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v"))
    planar_args += (p["assembly"],)
    reference = solve(m, theta, order=0)
    assert reference.valid.all(), "the benchmark linkages must all be crank-rockers"
    ref = {j: reference.positions[j] for j in MOVING_JOINTS}
    del reference
    cases_a: list[tuple[str, Callable[[], object]]] = [
        ("linkwright solve (plan), positions", lambda: solve(m, theta, order=0)),
        ("linkwright solve (plan), + derivatives", lambda: solve(m, theta, order=2)),
    ]
    if kernels is not None:
        out = tuple(np.empty((n, s, 2)) for _ in MOVING_JOINTS)
        check("the kernel", kernels.fourbar_positions(*planar_args, theta), ref, 1e-9)
        cases_a.insert(
            0,
            (
                "linkwright kernel (numba), positions",
                lambda: kernels.fourbar_positions(*planar_args, theta, out=out),
            ),
        )
    cases_a.append(("numpy closed form (baseline)", lambda: fourbar_positions(*planar_args, theta)))
    check("the numpy baseline", fourbar_positions(*planar_args, theta), ref, 1e-9)
    if peers is not None:
        ensemble = peers.build_ensemble(m, theta)
        check("pylinkage", peers.pylinkage_ensemble(ensemble, theta), ref, 1e-9)
        cases_a.append(
            ("pylinkage Ensemble.simulate", lambda: peers.pylinkage_ensemble(ensemble, theta))
        )
    del ref
    times_a = [(name, best_of(fn, args.repeats)) for name, fn in cases_a]

    # (b) one four-bar
    one = crank_rockers(1, seed=1)
    one = FourBar(**{k: np.asarray(v)[0] for k, v in one.params().items()})
    q = {k: np.asarray(v)[None] for k, v in one.params().items()}
    one_args = tuple(q[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v"))
    one_args += (q["assembly"],)
    cases_b: list[tuple[str, Callable[[], object]]] = [
        ("linkwright solve (plan), positions", lambda: solve(one, theta, order=0)),
        ("linkwright solve (plan), + derivatives", lambda: solve(one, theta, order=2)),
    ]
    if kernels is not None:
        out1 = tuple(np.empty((1, s, 2)) for _ in MOVING_JOINTS)
        curve = kernels.prepared_fourbar(*one_args, theta)
        curve_motion = kernels.prepared_fourbar(*one_args, theta, order=2)
        cases_b[:0] = [
            ("linkwright kernel, prepared call", curve),
            ("linkwright kernel, prepared + derivatives", curve_motion),
            (
                "linkwright kernel, checked call",
                lambda: kernels.fourbar_positions(*one_args, theta, out=out1),
            ),
        ]
    cases_b.append(("numpy closed form (baseline)", lambda: fourbar_positions(*one_args, theta)))
    if peers is not None:
        single = peers.build_single(one, theta)
        ref_one = {j: solve(one, theta, order=0).positions[j] for j in MOVING_JOINTS}
        check("pylinkage (single)", peers.pylinkage_single(single, theta), ref_one, 1e-9)
        cases_b.append(("pylinkage step_fast", lambda: peers.pylinkage_single(single, theta)))
    times_b = [(name, median_of(fn, args.latency_runs)) for name, fn in cases_b]

    # (c) spherical batch
    sm = spherical_crank_rockers(n)
    sp = {k: np.asarray(v) for k, v in sm.params().items()}
    sphere_args = tuple(
        sp[k]
        for k in ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle", "assembly")
    )
    reference = solve(sm, theta, order=0)
    assert reference.valid.all(), "the spherical benchmark linkages must all assemble"
    sref = {j: reference.positions[j] for j in MOVING_JOINTS}
    del reference
    check("the spherical numpy baseline", spherical_fourbar_positions(*sphere_args, theta), sref,
          1e-12)  # fmt: skip
    cases_c: list[tuple[str, Callable[[], object]]] = [
        ("linkwright solve (plan), positions", lambda: solve(sm, theta, order=0)),
    ]
    if kernels is not None:
        sout = tuple(np.empty((n, s, 3)) for _ in MOVING_JOINTS)
        check("the spherical kernel", kernels.spherical_fourbar_positions(*sphere_args, theta),
              sref, 1e-12)  # fmt: skip
        cases_c.insert(
            0,
            (
                "linkwright kernel (numba), positions",
                lambda: kernels.spherical_fourbar_positions(*sphere_args, theta, out=sout),
            ),
        )
    cases_c.append(
        ("numpy closed form (baseline)", lambda: spherical_fourbar_positions(*sphere_args, theta))
    )
    del sref
    times_c = [(name, best_of(fn, args.repeats)) for name, fn in cases_c]
    profile = (
        kernel_profile(kernels, (planar_args, out), (sphere_args, sout), theta, streamed_bandwidth)
        if kernels
        else None
    )

    print()
    print("linkwright benchmark (issue 5): every figure measured in this run")
    print(
        f"numpy {np.__version__}, Python {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs; batches best of {args.repeats}, single calls median of "
        f"{args.latency_runs}"
    )
    if kernels is not None:
        import numba

        print(f"kernels: numba {numba.__version__}, {numba.get_num_threads()} threads")
    else:
        print("kernels: numba not installed (pip install 'linkwright[fast]')")
    if peers is not None:
        print("peers: " + ", ".join(f"{k} {v}" for k, v in peers.peer_versions().items()))
    else:
        print("peers: pylinkage not installed (make bench installs it)")
    print(
        f"bandwidth: copy {bandwidth / 1e9:.1f} GB/s and fill {store_bandwidth / 1e9:.1f} GB/s "
        "(NumPy, one thread); "
        + (
            f"streaming fill {streamed_bandwidth / 1e9:.1f} GB/s (every thread: the bound)"
            if streamed_bandwidth
            else "no streaming fill without numba (the bound is the fill)"
        )
    )
    samples = n * s
    targets = {"a": 1e9, "c": 2e8}
    for case, title, rows, width in (
        ("a", f"(a) {n:,} planar crank-rockers x {s} inputs", times_a, 48),
        ("c", f"(c) {n:,} spherical crank-rockers x {s} inputs", times_c, 72),
    ):
        base = dict(rows)["numpy closed form (baseline)"]
        peer = dict(rows).get("pylinkage Ensemble.simulate")
        copy_bound = len(MOVING_JOINTS) * bandwidth / width
        bound = len(MOVING_JOINTS) * limit / width
        print()
        print(
            f"{title}; bound {bound:.2e} joint positions/s ({width} B per sample; one thread's "
            f"copy: {copy_bound:.2e})"
        )
        head = f"{'':<42} {'time [s]':>9} {'joint pos/s':>12} {'of bound':>8} {'vs numpy':>9}" + (
            f" {'vs pylinkage':>12}" if peer else ""
        )
        print(head)
        print("-" * len(head))
        for name, t in rows:
            rate = len(MOVING_JOINTS) * samples / t
            line = f"{name:<42} {t:>9.4f} {rate:>12.3e} {rate / bound:>7.1%} {base / t:>8.2f}x"
            print(line + (f" {peer / t:>11.1f}x" if peer else ""))
        best = min(t for name, t in rows if name.startswith("linkwright"))
        rate = len(MOVING_JOINTS) * samples / best
        verdict = "met" if rate >= targets[case] else f"not met ({rate / targets[case]:.0%} of it)"
        print(f"target {targets[case]:.0e} joint positions/s: {verdict}")
        if peer:
            # Storing the same positions at the bound itself would be this much faster than the
            # peer: no simulator of this work can beat the peer by more on this machine.
            ceiling = peer * bound / (len(MOVING_JOINTS) * samples)
            verdict = (
                "met"
                if peer / best >= 300
                else (
                    f"not met: {peer / best:.0f}x; the store bandwidth allows at most "
                    f"{ceiling:.0f}x"
                )
            )
            print(f"target 300x pylinkage: {verdict}")
    print()
    print(f"(b) one planar four-bar x {s} inputs")
    base = dict(times_b)["numpy closed form (baseline)"]
    peer = dict(times_b).get("pylinkage step_fast")
    head = f"{'':<42} {'time [us]':>10} {'vs numpy':>9}" + (
        f" {'vs pylinkage':>12}" if peer else ""
    )
    print(head)
    print("-" * len(head))
    for name, t in times_b:
        line = f"{name:<42} {t * 1e6:>10.1f} {base / t:>8.2f}x"
        print(line + (f" {peer / t:>11.1f}x" if peer else ""))
    fastest = min(t for name, t in times_b if name.startswith("linkwright"))
    verdict = "met" if fastest < 10e-6 else f"not met ({fastest * 1e6:.1f} us)"
    print(f"target: a 360-sample curve under 10 us: {verdict}")
    print()
    if profile is not None:
        import numba

        print()
        print(
            "profile: each kernel on one thread and on every thread, against the streaming "
            "store bound of as many threads"
        )
        all_threads = f"{numba.get_num_threads()} threads"
        head = f"{'':<24} {'one thread':>12} {'of bound':>9} {all_threads:>12} {'of bound':>9}"
        print(head)
        print("-" * len(head))
        for name, (one, one_share, every, every_share) in profile.items():
            print(f"{name:<24} {one:>12.3e} {one_share:>8.0%} {every:>12.3e} {every_share:>8.0%}")
        print("(joint positions/s; a kernel well below its bound is limited by its arithmetic)")
    print()
    d = descriptor_case(args.descriptor_curves, s_desc := 64)
    print(
        f"(d) {d['curves']:,} random crank-rockers x {s_desc} inputs -> descriptors (own process)"
    )
    print(
        f"rate {d['rate']:.3e} curves/s (NumPy reference {d['reference_rate']:.3e}/s: "
        f"{d['rate'] / d['reference_rate']:.1f}x), peak RSS {d['peak_rss_bytes'] / 2**20:.0f} MiB"
    )
    verdict = "met" if d["rate"] >= 1e6 else f"not met ({d['rate'] / 1e6:.0%} of it)"
    print(f"target 1e6 curves/s: {verdict}; peak RSS under 1 GiB: "
          f"{'met' if d['peak_rss_bytes'] < 2**30 else 'not met'}")  # fmt: skip
    print()
    print("(e) path synthesis: python bench/synthesis.py; (f) atlas query: python bench/atlas.py")
    print(f"total {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

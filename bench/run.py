"""Engine throughput: batched four-bar positions, against a hand-written NumPy closed form.

Run as ``python bench/run.py`` (``make bench``). Times, best of several repeats:

* ``solve`` of 10,000 random Grashof crank-rockers (every sample assembled) × 360 inputs,
  positions only (order 0) and with first and second derivatives (order 2);
* the baseline of ``bench/baselines.py``: the obvious ten-line NumPy circle–circle intersection,
  positions only, on the same linkages (and checked to give the same positions);
* one four-bar × 360 inputs: the latency of a single small call (median of many).

Rates count mechanism-samples (mechanisms × inputs) and joint positions (3 moving joints, A, B
and P, per mechanism-sample).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np
from baselines import fourbar_positions

from linkwright.mechanisms import FourBar, solve

MOVING_JOINTS = ("A", "B", "P")


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


def best_of(fn, repeats: int) -> float:
    fn()  # warm-up: first-touch allocation, caches
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def median_of(fn, runs: int) -> float:
    fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mechanisms", type=int, default=10_000)
    parser.add_argument("--samples", type=int, default=360)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--latency-runs", type=int, default=300)
    args = parser.parse_args(argv)
    n, s = args.mechanisms, args.samples
    start = time.perf_counter()

    m = crank_rockers(n)
    theta = np.linspace(-np.pi, np.pi, s, endpoint=False)
    p = {k: np.asarray(v) for k, v in m.params().items()}

    def baseline():
        return fourbar_positions(
            p["A0"], p["B0"], p["crank"], p["coupler"], p["rocker"], p["u"], p["v"],
            p["assembly"], theta,
        )  # fmt: skip

    # Same answer before timing anything: every sample assembled, positions agree.
    motion = solve(m, theta, order=0)
    assert motion.valid.all(), "the benchmark linkages must all be crank-rockers"
    worst = max(
        float(np.max(np.abs(motion.positions[j] - ref)))
        for j, ref in zip(MOVING_JOINTS, baseline(), strict=True)
    )
    assert worst < 1e-9, f"linkwright and the baseline disagree by {worst:g}"
    del motion

    rows = []
    t_base = best_of(baseline, args.repeats)
    for order in (0, 2):
        t = best_of(lambda order=order: solve(m, theta, order=order), args.repeats)
        rows.append((f"linkwright solve, order={order}", t))
    rows.append(("numpy closed form (baseline)", t_base))

    one = crank_rockers(1, seed=1)
    one = FourBar(**{k: np.asarray(v)[0] for k, v in one.params().items()})
    latency = {order: median_of(lambda order=order: solve(one, theta, order=order),
                                args.latency_runs) for order in (0, 2)}  # fmt: skip
    t_base_one = median_of(
        lambda: fourbar_positions(
            *(np.asarray(v)[None] for v in (one.A0, one.B0)),
            *(np.asarray(getattr(one, k))[None] for k in ("crank", "coupler", "rocker", "u", "v")),
            np.asarray(one.assembly)[None], theta,
        ),
        args.latency_runs,
    )  # fmt: skip

    samples = n * s
    print()
    print(f"linkwright engine benchmark: {n:,} Grashof crank-rockers x {s} inputs per call")
    print(
        f"numpy {np.__version__}, Python {platform.python_version()}, "
        f"{platform.machine()}, {os.cpu_count()} CPUs; best of {args.repeats} repeats"
    )
    print()
    head = (
        f"{'case':<32} {'time [s]':>9} {'mech-samples/s':>15} {'joint positions/s':>18} "
        f"{'time / baseline':>16}"
    )
    print(head)
    print("-" * len(head))
    for name, t in rows:
        print(
            f"{name:<32} {t:>9.3f} {samples / t:>15.3e} {len(MOVING_JOINTS) * samples / t:>18.3e} "
            f"{t / t_base:>15.2f}x"
        )
    print()
    print(f"single four-bar x {s} inputs (median of {args.latency_runs} calls):")
    for order, t in latency.items():
        print(f"  linkwright solve, order={order}   {t * 1e6:9.1f} us")
    print(f"  numpy closed form (baseline)  {t_base_one * 1e6:9.1f} us")
    print()
    ratio = (samples / rows[0][1]) / (samples / t_base)
    print(
        f"rate ratio linkwright/baseline (positions): {ratio:.2f} "
        f"(linkwright takes {1 / ratio:.2f}x the baseline's time); "
        f"positions agree to {worst:.1e}; total {time.perf_counter() - start:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

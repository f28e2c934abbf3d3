"""Forces (issue 25): Newton–Euler for 10,000 four-bars × 360 samples, against positions alone.

Run as ``python bench/forces.py`` (``make bench`` runs it). The issue's target: the forces
(derivatives, one linear solve per sample, the energy balance beside it) take at most 10× the
time of solving the positions only. Prints both times, best of ``--repeat``, and their ratio.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from linkwright.dynamics import Loads, MassProps, forces
from linkwright.mechanisms import FourBar
from linkwright.mechanisms.base import solve


def _best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--count", type=int, default=10_000)
    parser.add_argument("--samples", type=int, default=360)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    rng = np.random.default_rng(25)
    n = args.count
    mech = FourBar(
        A0=[0.0, 0.0],
        B0=[4.0, 0.0],
        crank=rng.uniform(0.5, 1.0, n),
        coupler=rng.uniform(4.0, 5.0, n),
        rocker=rng.uniform(3.0, 4.0, n),
    )
    theta = np.linspace(0.0, 2 * np.pi, args.samples, endpoint=False)
    masses = {"crank": 0.2, "coupler": 0.5, "rocker": MassProps(0.4, (1.5, 0.0), 0.3)}
    loads = Loads(speed_rpm=120.0, gravity=(0.0, -9.81))
    positions = _best(lambda: solve(mech, theta, order=0), args.repeat)
    full = _best(lambda: forces(mech, theta, masses, loads), args.repeat)
    print(
        f"forces: {n:,} four-bars x {args.samples} samples: positions only {positions:.2f} s, "
        f"forces {full:.2f} s, ratio {full / positions:.1f}x (target at most 10x)"
    )


if __name__ == "__main__":
    main()

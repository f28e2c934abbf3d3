"""Path synthesis against the classical four-bar benchmarks (issue 6, case (e) of the bench).

Run as ``python bench/synthesis.py`` (``--budget`` seconds per case, ``--seed``). Each case is
a four-bar whose coupler point must pass through target points; the error is the sum of
squared distances, the frame's place and angle are free unless stated:

1. six points on a vertical line, (20, 20) … (20, 45) step 5, free monotonic timing: an exact
   fit exists (published: ≈ 0; "reached" here means ≤ 1e-10);
2. five points at crank angles 30°, 45°, … 90°, frame at the origin along +x; published best
   ≈ 1.9e-6;
3. six points on a semicircle at crank angles 30°, 60°, … 180°, link lengths ≤ 50; published
   best ≈ 1.2162.

Cases 2 and 3 are those of Cabrera, Simon & Prado (Mech. Mach. Theory 37, 2002) and Acharyya &
Mandal (Mech. Mach. Theory 44, 2009), whose crank angle is measured from the frame line θ0:
that is :func:`~linkwright.synthesis.path.fit_path`'s convention. Read as absolute angles
(from +x), case 3 is a different problem, whose optimum is far lower (about 0.66).

For each case the table gives the published value, ours (the error of the returned,
re-verified linkage after the whole budget, or once an exact fit is reached), the time and the
mechanism evaluations it took to first reach the published value, and the totals. The fitted
linkages follow, with the absolute input angles at which they reach each point.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys

import numpy as np

from linkwright.synthesis.path import PathFit, fit_path

CASES = {
    "1 line, free timing": dict(
        points=[(20.0, y) for y in range(20, 46, 5)],
        kwargs=dict(timing="free"),
        published=1e-10,
        shown="≈ 0",
    ),
    "2 five points, frame fixed": dict(
        points=[(3, 3), (2.759, 3.363), (2.372, 3.663), (1.890, 3.862), (1.355, 3.943)],
        kwargs=dict(
            angles=np.radians([30, 45, 60, 75, 90]),
            bounds={"x": (0, 0), "y": (0, 0), "frame_angle": (0, 0)},
        ),
        published=1.9e-6,
        shown="1.9e-6",
        # The optimum (7.4158e-7) is found in well under a second; more time finds nothing.
        budget=0.25,
    ),
    "3 semicircle, lengths <= 50": dict(
        points=[
            (0, 0),
            (1.9098, 5.8779),
            (6.9098, 9.5106),
            (13.09, 9.5106),
            (18.09, 5.8779),
            (20, 0),
        ],
        kwargs=dict(angles=np.radians(np.arange(30, 181, 30)), bounds={"length": (0, 50)}),
        published=1.2162,
        shown="1.2162",
    ),
}


def reached(fit: PathFit, value: float) -> tuple[float | None, int | None]:
    for t, evaluations, error in fit.history:
        if error <= value:
            return t, evaluations
    return None, None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=float, default=60.0, help="seconds per case")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print(
        f"# path synthesis benchmarks: Python {platform.python_version()}, "
        f"numpy {np.__version__}, {os.cpu_count()} CPUs, budget {args.budget:g} s per case, "
        f"seed {args.seed}"
    )
    header = (
        f"{'case':<30} {'published':>10} {'ours':>12} {'time to it':>11} "
        f"{'evals to it':>12} {'total s':>8} {'evals':>9}"
    )
    print(header)
    print("-" * len(header))
    fits = {}
    for name, case in CASES.items():
        budget = args.budget * case.get("budget", 1.0)
        fit = fit_path("fourbar", case["points"], seed=args.seed, budget=budget, **case["kwargs"])
        fits[name] = fit
        t, evals = reached(fit, case["published"])
        when = f"{t:.2f} s" if t is not None else "not reached"
        count = f"{evals}" if evals is not None else "-"
        print(
            f"{name:<30} {case['shown']:>10} {fit.error:>12.6g} {when:>11} {count:>12} "
            f"{fit.elapsed:>8.1f} {fit.evaluations:>9}"
        )
    print()
    for name, fit in fits.items():
        m = fit.mechanism
        print(f"{name}: stopped on {fit.stopped}, rms {fit.rms:.3g}")
        print(
            f"  A0 = {np.round(m.A0, 6).tolist()}, B0 = {np.round(m.B0, 6).tolist()}, "
            f"crank {float(m.crank):.6f}, coupler {float(m.coupler):.6f}, "
            f"rocker {float(m.rocker):.6f}, u {float(m.u):.6f}, v {float(m.v):.6f}, "
            f"assembly {float(m.assembly):+.0f}"
        )
        print(f"  inputs (deg, absolute): {np.round(np.degrees(fit.inputs), 6).tolist()}")
        print(f"  from the frame line:    {np.round(np.degrees(fit.angles), 6).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

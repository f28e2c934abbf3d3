"""Path synthesis against the classical four-bar benchmarks (issue 6, case (e) of the bench).

Run as ``python bench/synthesis.py`` (``--budget`` seconds per case, ``--seed``, ``--cases``).
Each path case is a four-bar whose coupler point must pass through target points; the error is
the sum of squared distances, the frame's place and angle are free unless stated:

1. six points on a vertical line, (20, 20) … (20, 45) step 5, free monotonic timing: an exact
   fit exists (published: ≈ 0; "reached" here means ≤ 1e-10);
2. five points at crank angles 30°, 45°, … 90°, frame at the origin along +x; published best
   ≈ 1.9e-6;
3. six points on a semicircle at crank angles 30°, 60°, … 180°, link lengths ≤ 50; published
   best ≈ 1.2162;
4. Kunjur and Krishnamurty's 18 points (J. Appl. Mech. Robotics 4(2), 1997, as reprinted by
   Cabrera et al. 2002 and later papers; typed from that literature, not checked here against
   a copy of either) at crank steps of 20°, where the steps start a design variable
   (``free_start``); the figure beside it is the one issue 28 quotes, 0.0090289, whose linkage
   we could not see to check that it passes all 18 inputs on one circuit. ``--independent N``
   checks our optimum by N local fits of a closed-form model written apart from linkwright
   (3,000 found the same 0.0099119 and nothing lower);
5. an open path: Wu, Ge, Gao and Guo (J. Mechanisms Robotics 3(3), 2011), 60 points, fitted
   with no timing; beside it the nearest-point error of Wu et al.'s own linkage, traced here
   (200,001 inputs) from four-bar-rs's transcription of it;
6. approximate motion generation through Hsieh's nine poses (NTU master's thesis, 2017), the
   published four-bar (four-bar-rs's transcription, three decimals) and ``fit_motion``'s best,
   both measured here the same way: each pose's miss at the input nearest to it.

``bench/data`` holds the point sets of cases 5 and 6 with their sources.

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
import time
from pathlib import Path

import numpy as np

from linkwright.mechanisms import FourBar, Mechanism, solve
from linkwright.synthesis.motion_fit import fit_motion
from linkwright.synthesis.path import PathFit, fit_path

DATA = Path(__file__).parent / "data"
DENSE = 200_001
"""Inputs over a turn at which a published linkage is traced to measure its error here."""

# Kunjur and Krishnamurty's problem (J. Appl. Mech. Robotics 4(2), 1997), as reprinted by
# Cabrera et al. (2002): 18 points reached at crank steps of 20°, where the steps start free.
KUNJUR_KRISHNAMURTY = [
    (0.5, 1.1), (0.4, 1.1), (0.3, 1.1), (0.2, 1.0), (0.1, 0.9), (0.005, 0.75),
    (0.02, 0.6), (0.0, 0.5), (0.0, 0.4), (0.03, 0.3), (0.1, 0.25), (0.15, 0.2),
    (0.2, 0.3), (0.3, 0.4), (0.4, 0.5), (0.5, 0.7), (0.6, 0.9), (0.6, 1.0),
]  # fmt: skip

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
    "4 Kunjur-Krishnamurty, 18 pts": dict(
        points=KUNJUR_KRISHNAMURTY,
        kwargs=dict(angles=np.radians(np.arange(18) * 20.0), free_start=True),
        published=0.0090289,
        shown="0.0090289",
    ),
}


def kunjur_krishnamurty_multistart(starts: int, seed: int) -> tuple[float, int]:
    """An independent check of case 4's optimum: Levenberg-Marquardt from ``starts`` random
    four-bars on a closed-form model written here apart from linkwright (crank pivot, frame
    angle, four lengths, coupler point, start; the circle intersection on one side at all 18
    inputs), keeping only linkages that assemble at every input and are Grashof crank-rockers
    (so that one circuit passes all 18). Returns the least error and the feasible count."""
    from scipy.optimize import least_squares

    targets = np.array(KUNJUR_KRISHNAMURTY)
    steps = np.radians(20.0) * np.arange(len(targets))

    def left(v: np.ndarray) -> np.ndarray:
        return np.stack([-v[:, 1], v[:, 0]], 1)

    def coupler_points(z: np.ndarray, side: float) -> tuple[np.ndarray, np.ndarray]:
        """The coupler point at the 18 inputs, and how far each input is from assembling."""
        x, y, frame_angle, frame, crank, coupler, rocker, u, v, start = z
        a0 = np.array([x, y])
        b0 = a0 + frame * np.array([np.cos(frame_angle), np.sin(frame_angle)])
        th = frame_angle + start + steps
        a = a0 + crank * np.stack([np.cos(th), np.sin(th)], 1)
        d = b0 - a
        dist = np.linalg.norm(d, axis=1)
        along = (coupler**2 - rocker**2 + dist**2) / (2 * dist)
        height2 = coupler**2 - along**2
        e = d / dist[:, None]
        b = a + along[:, None] * e + side * np.sqrt(np.maximum(height2, 0))[:, None] * left(e)
        line = (b - a) / coupler
        return a + u * line + v * left(line), np.maximum(-height2, 0.0)

    rng = np.random.default_rng(seed)
    lo = np.r_[-10, -10, -np.inf, [0.01] * 4, -10, -10, -np.inf]
    hi = np.r_[10, 10, np.inf, [10] * 4, 10, 10, np.inf]
    best, feasible = np.inf, 0
    for _ in range(starts):
        side = float(rng.choice([-1.0, 1.0]))
        z0 = np.r_[
            rng.uniform(-1.5, 2.0, 2), rng.uniform(0, 2 * np.pi), rng.uniform(0.05, 3.0, 4),
            rng.uniform(-2, 2, 2), rng.uniform(0, 2 * np.pi),
        ]  # fmt: skip

        def misses(z: np.ndarray, side: float = side) -> np.ndarray:
            p, unreached = coupler_points(z, side)
            return np.concatenate([(p - targets).ravel(), 10 * unreached])

        z = least_squares(misses, z0, bounds=(lo, hi), max_nfev=400).x
        p, unreached = coupler_points(z, side)
        lengths = sorted(z[3:7])
        crank_rocker = z[4] == lengths[0] and lengths[0] + lengths[3] <= lengths[1] + lengths[2]
        if unreached.max() == 0 and crank_rocker:
            feasible += 1
            best = min(best, float(np.sum((p - targets) ** 2)))
    return best, feasible


def reached(fit: PathFit, value: float) -> tuple[float | None, int | None]:
    for t, evaluations, error in fit.history:
        if error <= value:
            return t, evaluations
    return None, None


def published_fourbar(
    pivot: tuple[float, float],
    angle: float,
    frame: float,
    crank: float,
    coupler: float,
    rocker: float,
    reach: float,
    turn: float,
) -> FourBar:
    """A four-bar as the papers (and four-bar-rs's transcriptions) give it: the crank pivot, the
    frame's angle, the four lengths, and the traced point at ``reach`` from the crank's joint,
    ``turn`` radians from the coupler line (the reading that reproduces each paper's figure)."""
    a0 = np.asarray(pivot, float)
    return FourBar(
        A0=a0,
        B0=a0 + frame * np.array([np.cos(angle), np.sin(angle)]),
        crank=crank,
        coupler=coupler,
        rocker=rocker,
        u=reach * np.cos(turn),
        v=reach * np.sin(turn),
        assembly=1.0,
    )


def traced(mech: Mechanism) -> tuple[np.ndarray, np.ndarray]:
    """The traced point and the coupler line's angle over a dense turn of the input."""
    m = solve(mech, np.linspace(0.0, 2 * np.pi, DENSE), order=0)
    ok = np.asarray(m.valid)
    line = m.positions["B"] - m.positions["A"]
    return m.positions["P"][ok], np.arctan2(line[ok, 1], line[ok, 0])


def nearest_error(mech: Mechanism, targets: np.ndarray) -> float:
    """Σ of squared distances from each target to the nearest traced point (dense sampling)."""
    P, _ = traced(mech)
    return float(np.sum([np.min(np.sum((P - t) ** 2, axis=1)) for t in targets]))


def pose_misses(
    mech: Mechanism, offset: float, points: np.ndarray, angles: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each pose's position and angle miss at the input that brings the body nearest to it
    (|ΔP|² + (s·Δα)², s the poses' diameter); the body's angle is the coupler line's + offset."""
    P, line = traced(mech)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    dp, da = [], []
    for p, a in zip(points, angles, strict=True):
        gap = np.linalg.norm(P - p, axis=1)
        turn = np.abs(np.angle(np.exp(1j * (line + offset - a))))
        k = int(np.argmin(gap**2 + (spread * turn) ** 2))
        dp.append(gap[k])
        da.append(turn[k])
    return np.array(dp), np.array(da)


def open_path_case(budget: float, seed: int) -> None:
    """Wu et al. (2011)'s open path: their published linkage against ``synth path``'s."""
    targets = np.loadtxt(DATA / "wu2011-open-path.csv", delimiter=",", comments="#")
    # Wu et al.'s linkage for it, as four-bar-rs transcribes it (syn-examples/refer).
    theirs = published_fourbar(
        (198.6, -82.5), 2.670353755551324, 368.5, 74.0, 230.8, 213.6, 150.6, 5.462880558742252
    )
    published = nearest_error(theirs, targets)
    fit = fit_path("fourbar", targets, timing="none", seed=seed, budget=budget)
    ours = nearest_error(fit.mechanism, targets)
    print(
        f"{'5 open path, Wu 2011 (60)':<30} {published:>10.4g} {ours:>12.6g} "
        f"{'-':>11} {'-':>12} {fit.elapsed:>8.1f} {fit.evaluations:>9}"
    )


def motion_case() -> None:
    """Hsieh (2017)'s nine poses: the published four-bar against ``fit_motion``'s best."""
    rows = np.loadtxt(DATA / "hsieh2017-poses.csv", delimiter=",", comments="#")
    points, angles = rows[:, :2], np.arctan2(rows[:, 3], rows[:, 2])
    # Hsieh's four-bar (four-bar-rs's test-mfb/refer): the body is the coupler line + 2.3277.
    theirs = published_fourbar((6.402, 7.259), 2.447, 6.638, 9.832, 7.537, 6.972, 3.545, -2.516)
    start = time.perf_counter()
    best = fit_motion(points, angles, top=1)[0]
    elapsed = time.perf_counter() - start
    for name, mech, offset in (
        ("Hsieh 2017", theirs, 2.3277456234),
        ("fit_motion", best.mechanism, best.angle_offset),
    ):
        dp, da = pose_misses(mech, offset, points, angles)
        print(
            f"  {name:<11} RMS position miss {np.sqrt(np.mean(dp**2)):.4g}, "
            f"largest {dp.max():.4g}; RMS angle miss {np.degrees(np.sqrt(np.mean(da**2))):.3g}°"
        )
    print(f"  fit_motion took {elapsed:.1f} s")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=float, default=60.0, help="seconds per case")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--cases", nargs="*", default=[], help="case numbers to run (default: all of them)"
    )
    parser.add_argument(
        "--independent",
        type=int,
        default=0,
        metavar="STARTS",
        help="check case 4's optimum by this many local fits of an independent model",
    )
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
        if args.cases and name.split()[0] not in args.cases:
            continue
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
    if not args.cases or "5" in args.cases:
        open_path_case(args.budget, args.seed)
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
    if args.independent:
        start = time.perf_counter()
        best, feasible = kunjur_krishnamurty_multistart(args.independent, args.seed)
        print(
            f"\n4, checked apart: {args.independent} Levenberg-Marquardt starts of a closed-form "
            f"model, {feasible} feasible crank-rockers, the least error {best:.10g} "
            f"({time.perf_counter() - start:.0f} s)"
        )
    if not args.cases or "6" in args.cases:
        print("\n6 motion through Hsieh (2017)'s nine poses (both errors measured here)")
        motion_case()
    return 0


if __name__ == "__main__":
    sys.exit(main())

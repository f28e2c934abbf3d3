"""Compiled plans (linkwright.engine.compile): joint positions per second for every kind of linkage.

Run as ``python bench/compiled.py`` (part of ``make bench``). Each case is a batch of random
linkages around a bundled example (every dimension within ±2 % of it, branch signs at random)
× 360 inputs, timed through the compiled plan: ``positions()`` (every moving joint's masked
positions and nothing else: the figure set beside the target), ``place`` at order 0 (each
joint's raw state: positions, valid and regular masks, dyad margins) and at order 2 (with
velocities and accelerations); and through the plan evaluator (``place_all``) in the same run;
the four-bars also through the hand-written kernels of linkwright.engine.kernels. Rates count
the moving joints' positions (ground pivots are not written). Before timing, every compiled
result is checked against the evaluator's.

Each figure is the best of ``--repeats`` runs by the wall clock. ``out=`` is
``positions(out=...)``, writing arrays reused from call to call (fresh arrays of this size are
mapped and faulted in at each call: about as long again as the kernel takes here). The machine
is shared, so the table also gives the ``out=`` rate per CPU-second the process used (all
threads together): what an idle core would do, times the cores for an idle machine. The load
average is printed before and after.

The first-compile and cached-load costs are measured in fresh processes: one with an empty
kernel cache (generate + compile), one after it with the same cache (load the machine code).

Targets (issue 22): planar six-bars ≥ 5e8 joint positions/s, spherical six-bars ≥ 2e8,
Jansen's leg ≥ 3e8, and with derivatives at least a third of that.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from linkwright.engine import compile as lwc  # noqa: E402
from linkwright.engine import kernels  # noqa: E402
from linkwright.engine.evaluate import place_all  # noqa: E402
from linkwright.io import load_example  # noqa: E402

CASES = {
    # name: (example, target positions/s at order 0)
    "planar four-bar": ("crank-rocker", None),
    "planar six-bar (Stephenson III)": ("stephenson3-example", 5e8),
    "planar six-bar (Watt I)": ("watt1-example", 5e8),
    "Jansen's leg": ("jansen-leg", 3e8),
    "spherical four-bar": ("paper000-fig6-crank-rocker", None),
    "spherical six-bar (paper 000)": ("paper000-fig8-sixbar", 2e8),
    "spherical Stephenson III (paper 001)": ("paper001-stephenson3", 2e8),
}


def mechanism(example: str):
    doc = load_example(example)
    return getattr(doc, "mechanism", doc)


def batch(mech, n: int, seed: int = 0, eps: float = 0.02) -> dict[str, np.ndarray]:
    """The example's parameters drawn per mechanism within ±eps (relative)."""
    rng = np.random.default_rng(seed)
    signs = {s.branch for s in mech.plan.dyads}
    out = {}
    for key, value in mech.params().items():
        value = np.asarray(value, dtype=float)
        if key in signs:
            out[key] = rng.choice([-1.0, 1.0], n)
        elif key in mech.points:
            moved = value + eps * rng.uniform(-1.0, 1.0, (n, *value.shape))
            if mech.plan.space == "sphere":
                moved /= np.linalg.norm(moved, axis=-1, keepdims=True)
            out[key] = moved
        else:
            out[key] = value * (1.0 + eps * rng.uniform(-1.0, 1.0, n))
    return out


def best(fn, repeats: int) -> float:
    return timed(fn, repeats)[0]


def timed(fn, repeats: int) -> tuple[float, float]:
    """(least wall seconds, least CPU seconds of this process) of ``repeats`` calls of ``fn``."""
    fn()
    walls, cpus = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return min(walls), min(cpus)


def check(mech, params, theta, order: int) -> None:
    """The compiled states equal the evaluator's (positions and masks) before any timing."""
    _, got = lwc.compiled_plan(mech.plan).place(params, theta, points=mech.points, order=order)
    _, ref = place_all(mech.plan, params, theta, points=mech.points, order=order)
    for name, state in ref.items():
        assert np.array_equal(got[name].valid, state.valid), name
        ok = state.valid
        np.testing.assert_allclose(got[name].pos[ok], state.pos[ok], rtol=1e-12, atol=1e-12)


def hand_written(name: str, mech, params, theta) -> float | None:
    """Seconds of the hand-written four-bar kernel on the same batch (None where none)."""
    if not kernels.available():
        return None
    if name == "planar four-bar":
        args = [params[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v")]

        def run() -> object:
            return kernels.fourbar_positions(*args, params["assembly"], theta)

        return best(run, 5)
    if name == "spherical four-bar":
        args = [
            params[k] for k in ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle")
        ]

        def run() -> object:
            return kernels.spherical_fourbar_positions(*args, params["assembly"], theta)

        return best(run, 5)
    return None


def first_compile(example: str) -> tuple[float, float]:
    """(seconds of the first call in a process with an empty cache, of the first call in a
    second process with that cache): generate + compile, then load."""
    script = (
        "import sys, time, json\n"
        f"sys.path.insert(0, {str(ROOT / 'bench')!r})\n"
        "from compiled import mechanism, batch\n"
        "from linkwright.engine import compile as lwc\n"
        f"m = mechanism({example!r}); p = batch(m, 8)\n"
        "t0 = time.perf_counter()\n"
        "lwc.compiled_plan(m.plan).place(p, [0.0, 1.0], points=m.points, order=0)\n"
        "print(json.dumps(time.perf_counter() - t0))\n"
    )
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, LINKWRIGHT_CACHE=cache)
        times = []
        for _ in range(2):
            done = subprocess.run(
                [sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True
            )
            times.append(json.loads(done.stdout.split()[-1]))
    return times[0], times[1]


def row(name: str, example: str, target: float | None, args, theta: np.ndarray) -> str:
    """One line of the table: the case timed every way, in this run."""
    mech = mechanism(example)
    params = batch(mech, args.n)
    compiled = lwc.compiled_plan(mech.plan)
    small = {k: v[: args.n // 4] for k, v in params.items()}
    for order in (0, 2):
        check(mech, small, theta[:37], order)
    moving = len([j for j in mech.plan.joints if j not in mech.plan.ground])
    count = moving * args.n * args.samples
    joints = tuple(compiled.moving)
    wall, _ = timed(
        lambda: compiled.positions(params, theta, joints, points=mech.points), args.repeats
    )
    out = {j: np.empty((args.n, args.samples, compiled.dim)) for j in joints}
    reused, cpu = timed(
        lambda: compiled.positions(params, theta, joints, points=mech.points, out=out),
        args.repeats,
    )
    rates = {}
    for order in (0, 2):
        t = best(
            lambda o=order: compiled.place(params, theta, points=mech.points, order=o),
            args.repeats,
        )
        rates[order] = count / t
    plan_rates = {}
    for order in (0, 2):
        t = best(
            lambda o=order: place_all(mech.plan, small, theta, points=mech.points, order=o),
            max(1, args.repeats // 2),
        )
        plan_rates[order] = count / 4 / t
    hand = hand_written(name, mech, params, theta)
    vs_hand = f"{hand / wall:8.2f}" if hand else f"{'':>8}"
    tgt = f"{target:7.0e}" if target else f"{'':>7}"
    tgt_d = f"{target / 3:7.0e}" if target else f"{'':>7}"
    return (
        f"{name:38} {count / wall:9.2e} {tgt} {count / reused:9.2e} {count / cpu:9.2e} "
        f"{rates[0]:9.2e} "
        f"{rates[2]:9.2e} {tgt_d} {count / wall / plan_rates[0]:8.1f} "
        f"{rates[2] / plan_rates[2]:9.1f} {vs_hand}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=4000, help="mechanisms per batch")
    parser.add_argument("--samples", type=int, default=360)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    if not lwc.available():
        print("numba is not installed: compiled plans run through the evaluator; nothing to time")
        return
    theta = np.linspace(0.0, 2 * np.pi, args.samples, endpoint=False)
    print(
        f"{args.n} mechanisms x {args.samples} inputs, {lwc.threads()} threads; "
        "joint positions/s (moving joints); ratios measured in this run; "
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs"
    )
    head = (
        f"{'case':38} {'positions':>9} {'target':>7} {'out=':>9} {'per CPU-s':>9} {'place':>9} "
        f"{'+deriv':>9} {'target':>7} {'vs plan':>8} {'vs plan d':>9} {'vs hand':>8}"
    )
    print(head)
    print("-" * len(head))
    for name, (example, target) in CASES.items():
        print(row(name, example, target, args, theta))
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print()
    print("first compile (empty cache) and load (second process), seconds, order 0:")
    for name in ("planar six-bar (Stephenson III)", "spherical six-bar (paper 000)"):
        cold, warm = first_compile(CASES[name][0])
        print(f"  {name:38} compile {cold:6.2f}   cached load {warm:6.2f}")


if __name__ == "__main__":
    main()

"""What a computation will cost, estimated before it starts, and the budgets it must fit.

Limits on sizes (samples, points, frames) do not bound cost: 4,096 samples of a linkage geared
at a ratio of 64 are 42 circuits of 4,096 samples, a composed linkage of 16 dyads has 65,536
assembly configurations, and a grid of 400 nodes per free link is 64 million linkages when three
links are free. This module estimates the *work* and the *peak memory* of a computation from
what determines them (circuits × samples × joints × configurations × steps, gear turns, refine
points, grid sizes, atlas entries × samples, frames × pixels) and refuses it, before any of it
runs, when it does not fit its budget: :class:`CostError`, a user-input error whose one line says
what is too big and what to lower, with numbers. The command line and the workbench server use
the same estimates, against their own budgets (:data:`BUDGETS`).

Units
-----
Work is counted in *placements*: one joint placed at one input for one linkage, the engine's
unit of vectorised work (0.1 to 0.3 µs on the 2-core machine the project is measured on, by
order and family, and more while it is shared). Every call into the engine also costs a fixed
:data:`CALL_UNITS` per plan step (NumPy's dispatch: about 30 µs, the work of 400 placements),
which is what makes many small calls (65,536 sign combinations at one input) expensive. Memory
is counted in bytes of arrays and Python objects held at the peak; the interpreter and its
libraries (about 150 MB) come on top.

Time
----
A server request also runs under a deadline (:func:`deadline`, a context variable): its long
loops (a study's steps, a scene's circuits, a match's refinements) call :func:`check_time`
between iterations and stop with :class:`OverTime`, a one-line "took longer than the N s
budget; lower X". The numeric kernels never look at it.

Examples
--------
>>> from linkwright.engine import Crank, DyadRRR, Fixed, Plan
>>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Crank("A", "A0", "a"),
...              DyadRRR("B", "A", "b", "B0", "c", "s")), traced=("B",))
>>> params = {"A0": [0.0, 0.0], "B0": [4.0, 0.0], "a": 1.0, "b": 4.0, "c": 3.0, "s": 1.0}
>>> shape = Shape.of(plan, params, frozenset({"A0", "B0"}))
>>> shape.joints, shape.dyads, shape.gear
(4, 1, 1.0)
>>> small = trace(shape, 360)
>>> small.check(CLI) is small
True
>>> with_knob(lambda n: trace(shape, n), CLI, 10**9, 2, "--points").check(CLI)
Traceback (most recent call last):
...
linkwright.engine.cost.CostError: too costly: tracing 1 circuit of 1,000,000,000 samples \
(4 joints) needs about 4e+09 units of work (at most 1e+09 here) and 237 GB of memory (at \
most 1.1 GB here); lower --points to 4,530,000 or fewer
"""

from __future__ import annotations

import contextvars
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from linkwright.engine import circuits as _circuits
from linkwright.engine import continuation as _continuation
from linkwright.engine.plan import Crank, Plan, SphereCrank

# The tracer's own sizes (linkwright.engine.circuits), read once; the defaults are its values
# when this model was measured.
GRID = int(getattr(_circuits, "GRID", 1440))
BISECTIONS = int(getattr(_circuits, "BISECTIONS", 64))
SCAN_CHUNK = int(getattr(_circuits, "SCAN_CHUNK", 240))
PATH_PILOT = int(getattr(_circuits, "PATH_PILOT", 64))

__all__ = [
    "BUDGETS",
    "CALL_UNITS",
    "CLI",
    "REQUEST",
    "Budget",
    "CostError",
    "Estimate",
    "OverTime",
    "Scope",
    "Shape",
    "animation",
    "check_atlas",
    "check_combinations",
    "check_gear",
    "check_time",
    "deadline",
    "describe_bytes",
    "follow",
    "grid",
    "largest",
    "lower_to",
    "refine",
    "remaining",
    "solve",
    "trace",
    "with_knob",
]


class CostError(ValueError):
    """A computation whose estimated work or memory is over its budget: the request's (or the
    command line's) fault, so the server answers 422 and the command line exits with 2. The
    message is one line naming what is too big and what to lower, with numbers."""

    http_status: ClassVar[int] = 422


class OverTime(Exception):
    """A server request that ran past its time budget (:func:`deadline`): 503, with one line
    saying which budget and what to lower. Not a ``ValueError``: the request was valid and
    estimated to fit; the machine was slower than the estimate."""

    http_status: ClassVar[int] = 503


# --------------------------------------------------------------------------------------------
# The budget table
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Budget:
    """One budget: its ``value`` in ``unit``, and ``why`` it has that value."""

    name: str
    value: float
    unit: str
    why: str


CLI_WORK = Budget(
    "cli_work",
    1e9,
    "placements",
    "Two to five minutes on the 2-core reference machine: the longest a command's computation "
    "may run before it is a batch job (atlas builds are budgeted on their own). Output a user "
    "asked for (solve's rows) is streamed and not counted.",
)
CLI_BYTES = Budget(
    "cli_bytes",
    2**30,
    "bytes",
    "1 GiB of arrays and objects at the peak: the machine is shared (2 cores, several users); "
    "a geared five-bar traced with --spacing path once took all 24 GB of it.",
)
REQUEST_WORK = Budget(
    "request_work",
    5e7,
    "placements",
    "5 to 15 s: a person waits for a scene, a study or an export; four requests are computed "
    "at once (work_slots), so one request may not hold its slot for minutes.",
)
REQUEST_BYTES = Budget(
    "request_bytes",
    2**28,
    "bytes",
    "256 MiB including the answer: four requests at once then stay within 1 GiB. A study of a "
    "crank geared at 64 once answered 548 MB and peaked at 4 GB.",
)
REQUEST_SECONDS = Budget(
    "request_seconds",
    20,
    "seconds",
    "The estimate is checked first; this deadline, checked between a request's steps, catches "
    "a machine slower than the estimate (or one shared with other work): 503, never a hung page.",
)
GEAR_TURNS = Budget(
    "gear_turns",
    64,
    "turns of a geared crank per input turn (|ratio|)",
    "The limit search samples 1,440 inputs per input turn; a crank turning more than 64 times "
    "per input turn gets fewer than 23 of them per own turn, limits are missed, and the tracing "
    "grows without bound (ratio 1,000: 10^7 refinement nodes, 24 GB).",
)
COMBINATIONS = Budget(
    "combinations",
    4096,
    "assembly configurations",
    "solve --all solves every combination of the dyads' branches: 2^k for k dyads (12 dyads: "
    "4,096, about 3 s per input batch; 16 dyads took 147 s and 1 GB for one input). The "
    "bundled linkage with the most, Jansen's leg, has 5 (32).",
)
REFINE_POINTS = Budget(
    "refine_points",
    500,
    "points",
    "A refinement solves for one input angle per fitted point, so its cost grows faster than "
    "the count (1,000 points: 6 s; 3,000: 26 s; 20,000: 3 to 18.6 GiB and no end). The most "
    "points fitted, evenly spaced along the curve; the distance is still measured to all.",
)
ATLAS_COUNT = Budget(
    "atlas_count",
    10**8,
    "entries",
    "The largest atlas measured: 53 min to build, 25.6 GB of disk, 7.2 GB of index in memory; "
    "beyond it the index no longer fits one machine's memory.",
)
OPEN_SCREEN = Budget(
    "open_screen",
    2_000_000,
    "entries",
    "An open curve is screened against every entry of the atlas (no descriptor indexes a piece "
    "of a curve): 100,000 entries take 5 s on the 2-core reference machine, so this many take "
    "about 100 s, the most a command should compute unasked.",
)
ATLAS_SAMPLES = Budget(
    "atlas_samples",
    4096,
    "samples per curve",
    "Descriptors keep 8 harmonics (16 would need only 33 samples); the default 64 already "
    "resolves them, and a build's time and shard memory grow linearly with the samples.",
)
ATLAS_CURVE_SAMPLES = Budget(
    "atlas_curve_samples",
    6.4e9,
    "entries × samples",
    "What the largest measured build computed (10^8 curves of 64 samples, 53 min); the time "
    "of a build is proportional to it.",
)
SHARD_BYTES = Budget(
    "shard_bytes",
    2**30,
    "bytes per shard",
    "Each worker holds one shard's curves while describing them: up to 180 bytes per curve "
    "sample (a geared five-bar's), so the default 65,536 × 64 samples is 755 MB at most.",
)

BUDGETS: dict[str, Budget] = {
    b.name: b
    for b in (
        CLI_WORK,
        CLI_BYTES,
        REQUEST_WORK,
        REQUEST_BYTES,
        REQUEST_SECONDS,
        GEAR_TURNS,
        COMBINATIONS,
        REFINE_POINTS,
        ATLAS_COUNT,
        OPEN_SCREEN,
        ATLAS_SAMPLES,
        ATLAS_CURVE_SAMPLES,
        SHARD_BYTES,
    )
}
"""Every budget by name, with the reason for its value."""


@dataclass(frozen=True)
class Scope:
    """The pair of budgets a caller checks against: the command line's or a request's."""

    name: str
    work: Budget
    bytes: Budget


CLI = Scope("here", CLI_WORK, CLI_BYTES)
REQUEST = Scope("per request", REQUEST_WORK, REQUEST_BYTES)


# --------------------------------------------------------------------------------------------
# Constants of the model (measured; see tests/test_cost.py for the checks against reality)
# --------------------------------------------------------------------------------------------

CALL_UNITS = 400
"""Placements' worth of fixed cost per plan step per call into the engine (about 30 µs)."""
BYTES_FACTOR = 2.7
"""Peak bytes of an evaluation per byte of the positions (and derivatives) it returns: the
masked copies and the steps' temporaries (measured 2.2 to 2.7)."""
PATH_NODES = 5.0
"""Refinement nodes per sample of ``spacing="path"`` beyond its pilot grid (measured 4.6 to 5.6
on the bundled examples)."""
PATH_CALLS = 20
"""Calls into the engine of one path refinement (a level of bisection each)."""
PATH_BYTES = 3.0
"""Peak bytes per refinement node per byte of a node's positions (measured 2.4: the node
arrays, their interleaved copies, the chords)."""
TRIAD_UNITS = {"plane": 800.0, "sphere": 2000.0, "sphere-AB": 200.0}
"""Placements' worth of work per input of an all-configurations Stephenson III solve, each
configuration checked against every constraint: driven so that a triad remains (polynomial
roots, polishing; measured 49 µs and 135 µs a sample), or paper 001's at AB (its 4 sign
combinations; 11 µs)."""
TRIAD_BYTES = {"plane": 13_000.0, "sphere": 30_000.0, "sphere-AB": 5_000.0}
"""Peak bytes per input of the same (measured 5 to 12 kB, 27.5 kB and 4.6 kB)."""
PY_NUMBER_BYTES = 64
"""Bytes a number costs held in Python lists and dicts for an answer (a float and its slot,
plus a share of its list) and again while being written as JSON."""


# --------------------------------------------------------------------------------------------
# Estimates
# --------------------------------------------------------------------------------------------


def describe_bytes(n: float) -> str:
    """Bytes in words: ``'1.2 GB'``, ``'340 MB'``, ``'12 kB'``.

    >>> describe_bytes(2**30), describe_bytes(3.4e8), describe_bytes(999)
    ('1.1 GB', '340 MB', '999 bytes')
    """
    for size, unit in ((1e12, "TB"), (1e9, "GB"), (1e6, "MB"), (1e3, "kB")):
        if n >= size:
            return f"{n / size:.2g} {unit}" if n < 10 * size else f"{n / size:.0f} {unit}"
    return f"{n:.0f} bytes"


def _count(n: float) -> str:
    return f"{n:,.0f}" if n < 1e15 else f"{n:.3g}"


@dataclass(frozen=True)
class Estimate:
    """The work (placements) and peak bytes of a computation, what it is (``what``, for the
    message) and how to make it cheaper (``lower``: a phrase, or a knob with :func:`largest`)."""

    work: float
    bytes: float
    what: str
    lower: str = ""
    parts: tuple[Estimate, ...] = field(default=(), repr=False, compare=False)

    def __add__(self, other: Estimate) -> Estimate:
        """Two computations one after the other: the work adds, the peak is the larger."""
        return Estimate(
            self.work + other.work,
            max(self.bytes, other.bytes),
            f"{self.what}, then {other.what}",
            self.lower or other.lower,
        )

    def times(self, n: float, what: str | None = None) -> Estimate:
        """``n`` of these one after the other (each one's memory freed before the next)."""
        return Estimate(self.work * n, self.bytes, what or self.what, self.lower)

    def holding(self, extra: float, what: str | None = None) -> Estimate:
        """The same work while ``extra`` bytes (an answer being built) are held too."""
        return Estimate(self.work, self.bytes + extra, what or self.what, self.lower)

    def advise(self, lower: str) -> Estimate:
        return Estimate(self.work, self.bytes, self.what, lower)

    def fits(self, scope: Scope) -> bool:
        return self.work <= scope.work.value and self.bytes <= scope.bytes.value

    def check(self, scope: Scope) -> Estimate:
        """This estimate, if it fits ``scope``; else :class:`CostError`."""
        if self.fits(scope):
            return self
        over = []
        if self.work > scope.work.value:
            over.append(
                f"about {self.work:.2g} units of work (at most {scope.work.value:.2g} {scope.name})"
            )
        else:
            over.append(f"about {self.work:.2g} units of work")
        over.append(
            f"{describe_bytes(self.bytes)} of memory"
            + (
                f" (at most {describe_bytes(scope.bytes.value)} {scope.name})"
                if self.bytes > scope.bytes.value
                else ""
            )
        )
        advice = f"; {self.lower}" if self.lower else ""
        raise CostError(f"too costly: {self.what} needs {' and '.join(over)}{advice}")


def largest(estimate: Callable[[int], Estimate], scope: Scope, low: int, high: int) -> int | None:
    """The largest value of a knob in [low, high] whose estimate fits ``scope`` (estimates grow
    with the knob), or None if even ``low`` does not. For the message: "lower X to N"."""
    if not estimate(low).fits(scope):
        return None
    while high - low > 1:
        mid = (low + high) // 2
        if estimate(mid).fits(scope):
            low = mid
        else:
            high = mid
    return high if estimate(high).fits(scope) else low


def _round_down(n: int) -> int:
    """A number to suggest: three significant digits, rounded down."""
    if n < 1000:
        return n
    unit: int = 10 ** (len(str(n)) - 3)
    return n // unit * unit


def lower_to(
    knob: str, estimate: Callable[[int], Estimate], scope: Scope, least: int, current: int
) -> str:
    """The advice "lower ``knob`` to N or fewer" for a knob the cost grows with, N the largest
    that fits (or that even ``least`` does not fit)."""
    best = largest(estimate, scope, least, max(least, current - 1))
    if best is None:
        return f"even {knob} = {_count(least)} does not fit"
    return f"lower {knob} to {_count(_round_down(best))} or fewer"


# --------------------------------------------------------------------------------------------
# Tracing circuits
# --------------------------------------------------------------------------------------------


def _const(params: Mapping[str, Any], value: Any) -> float:
    raw = params[value] if isinstance(value, str) else value
    return float(np.max(np.abs(np.asarray(raw, dtype=float))))


@dataclass(frozen=True)
class Shape:
    """What a plan's cost depends on: ``joints`` (steps), ``dyads`` (and ``triads``' poses),
    the input ``turns`` in one period (a ratio's denominator), ``gear`` (the turns of the
    fastest crank per input turn, at least 1), ``space`` and whether its limits have a closed
    form (``analytic``)."""

    joints: int
    dyads: int
    turns: int
    gear: float
    space: str
    analytic: bool
    poses: int = 1
    kept: bool = False
    """The linkage is small enough that its arcs are kept between calls
    (:class:`~linkwright.engine.continuation.Memo`): tracing its circuits reuses the one search
    that counted them instead of searching again for each."""

    @classmethod
    def of(
        cls, plan: Plan, params: Mapping[str, Any], points: frozenset[str], *, periodic: bool = True
    ) -> Shape:
        """The shape of ``plan`` with ``params`` (the largest over a batch). ``periodic``: its
        period is needed (tracing a circuit), so an irrational gear ratio raises
        :class:`~linkwright.engine.NoPeriod`; solving at given inputs needs none (1 turn)."""
        turns = 1
        if periodic:
            turns = int(np.max(_circuits.input_turns(plan, params, points=points)))
        gear = 1.0
        for step in plan.steps:
            if isinstance(step, Crank | SphereCrank):
                gear = max(gear, _const(params, step.ratio))
        dyads = plan.dyads
        analytic = (
            plan.space == "plane"
            and len(dyads) == 1
            and turns == 1
            and gear == 1.0
            and all(isinstance(plan.step(p), Crank) or _fixed(plan, p) for p in dyads[0].parents)
        )
        poses = 1
        for step in getattr(plan, "triads", ()):
            poses *= int(getattr(step, "max_poses", 1))
        numbers = sum(np.asarray(v).size for v in params.values())
        kept = numbers <= _continuation.MEMO_NUMBERS
        return cls(len(plan.steps), len(dyads), turns, gear, plan.space, analytic, poses, kept)

    @classmethod
    def of_mechanism(cls, mechanism: Any, *, periodic: bool = True) -> Shape:
        """The shape of a mechanism (anything with ``plan``, ``params()`` and ``points``)."""
        return cls.of(mechanism.plan, mechanism.params(), mechanism.points, periodic=periodic)

    @property
    def dim(self) -> int:
        return 3 if self.space == "sphere" else 2

    @property
    def configurations(self) -> float:
        """Assembly configurations ``solve --all`` enumerates: 2^dyads × triad poses."""
        return 2.0**self.dyads * self.poses


def _fixed(plan: Plan, name: str) -> bool:
    return type(plan.step(name)).__name__ == "Fixed"


def check_gear(shape: Shape, whose: str = "the ") -> None:
    """Refuse a crank turning more than :data:`GEAR_TURNS` times per input turn: beyond it the
    circuit tracer misses limits and its cost has no bound (the budget's reason). ``whose``
    starts the message (``"step 3's "``; by default "the")."""
    if shape.gear > GEAR_TURNS.value:
        raise CostError(
            f"too costly: {whose}gear ratio {shape.gear:g} turns a crank {shape.gear:,.6g} "
            "times per input turn; "
            f"circuits can be traced up to {GEAR_TURNS.value:.0f} (the limit search samples "
            f"1,440 inputs a turn); lower the ratio to {GEAR_TURNS.value:.0f} or less"
        )


def _limits(shape: Shape, changes: float | None) -> tuple[float, float]:
    """(work, bytes) of one search for the input's limits (:func:`input_arcs`), which every
    traced circuit runs again: the predicate on a grid of the period, then every change of it
    bisected, all at once, to the last bit. ``changes`` is the number of limit positions (None:
    its bound, two per turn of every crank a dyad sees)."""
    j = shape.joints
    if shape.analytic:
        return 4 * j * CALL_UNITS, 0.0
    nodes = GRID * shape.turns
    if changes is None:
        changes = min(nodes, 4.0 * max(shape.dyads, 1) * shape.gear * shape.turns)
    work: float = j * (nodes + CALL_UNITS)
    if changes:
        work += (BISECTIONS + 2) * j * (CALL_UNITS + changes)
    if shape.dyads > 1:
        # The walk from limit to limit: a bisection per limit met, and a scan of the period
        # ahead in chunks.
        work += j * (
            (BISECTIONS + 6) * (CALL_UNITS + 1) + 4 * shape.dyads * (CALL_UNITS + SCAN_CHUNK)
        )
    return work, nodes * j * shape.dim * 8 * BYTES_FACTOR


# Following every configuration along its circuits (a plan with a triad, or ``curve --all``),
# measured on paper 001's linkage at FG and the planar Stephenson III at its output: a triad's
# placement costs about 25 dyad placements (its polynomial, polished: paper 001 at FG, 4,096
# samples, took 2.9 s and 131 MB in process, estimated 3.3e7 units and 202 MB), and following
# holds about 48 bytes a coordinate per sample and configuration (a plan of dyads, about 6).
# Its grid has 720 inputs whatever the samples asked for.
TRIAD_WORK, TRIAD_HELD, DYAD_HELD = 25.0, 48.0, 6.0
FOLLOW_GRID = 720


def follow(shape: Shape, samples: int) -> Estimate:
    """Tracing every circuit of every configuration by continuation
    (:func:`linkwright.engine.continuation.every_circuit`) at ``samples`` samples a circuit:
    every configuration solved on the grid and again at the samples; a linkage has no more
    circuits than configurations."""
    check_gear(shape)
    combos = shape.configurations
    triad = shape.poses > 1
    n = max(samples, FOLLOW_GRID)
    per_circuit = n * combos * shape.joints
    return Estimate(
        combos * per_circuit * (TRIAD_WORK if triad else 1.0),
        per_circuit * shape.dim * 8 * (TRIAD_HELD if triad else DYAD_HELD) + combos * samples * 400,
        f"tracing every circuit of {combos:,.0f} configurations at {_count(samples)} samples "
        f"({shape.joints} joints)",
    )


def trace(
    shape: Shape,
    samples: int,
    *,
    circuits: int = 1,
    modes: int = 1,
    spacing: str = "input",
    order: int = 0,
    full: bool | None = None,
) -> Estimate:
    """Tracing ``circuits`` circuits (each in each of ``modes`` assembly modes) of ``samples``
    samples: per circuit the limit search again, the walk between limits and the samples,
    evenly in the input or refined along the path (:func:`linkwright.engine.trace`); and the
    one search per mode that counted the circuits. ``full`` says whether the input turns fully
    (no limits to bisect); None when not known yet. A plan with a triad follows every
    configuration at once (:func:`follow`)."""
    if shape.poses > 1:
        return follow(shape, samples)
    check_gear(shape)
    j, dim = shape.joints, shape.dim
    changes = 0.0 if full else (2.0 * circuits if full is False else None)
    search_work, search_bytes = _limits(shape, changes)
    speed = 1.0 + 0.5 * order  # derivatives: each placement costs more
    sample_bytes = samples * j * dim * 8 * (1 + order) * BYTES_FACTOR
    if spacing == "path":
        nodes = (1.0 if full else 2.0) * max(PATH_PILOT, samples) + PATH_NODES * samples
        sample_work = j * (nodes + PATH_CALLS * CALL_UNITS) + j * samples * speed
        sample_bytes += nodes * j * dim * 8 * PATH_BYTES
    else:
        sample_work = j * (samples * speed + 3 * CALL_UNITS)
    count = circuits * modes
    # Each circuit searches its limits again, unless the search that counted them was kept.
    again = 0.0 if shape.kept else search_work
    work = count * (again + sample_work) + modes * search_work
    # Each circuit's motion is kept for the answer; the search's grid only while it runs.
    held = count * samples * j * dim * 8 * (1 + order)
    peak = held + max(search_bytes, sample_bytes)
    parts = []
    if modes > 1:
        parts.append(f"{modes} assembly modes")
    parts.append(f"{_count(circuits)} circuit{'s' if circuits != 1 else ''}")
    what = f"tracing {' × '.join(parts)} of {_count(samples)} samples ({j} joints)"
    if spacing == "path":
        what += " spaced along the path"
    return Estimate(work, peak, what)


def with_knob(
    build: Callable[[int], Estimate], scope: Scope, current: int, least: int, knob: str
) -> Estimate:
    """``build(current)`` with the advice to lower ``knob`` to what fits, if it does not."""
    estimate = build(current)
    if estimate.fits(scope) or estimate.lower:
        return estimate
    return estimate.advise(lower_to(knob, build, scope, least, current))


# --------------------------------------------------------------------------------------------
# Solving at given inputs, refining a match, animating, searching a grid, building an atlas
# --------------------------------------------------------------------------------------------


def check_combinations(shape: Shape) -> None:
    """Refuse ``solve --all`` on more assembly configurations than :data:`COMBINATIONS`: their
    number doubles with every dyad, whatever the samples."""
    if shape.configurations > COMBINATIONS.value:
        raise CostError(
            f"too costly: --all solves every combination of the {shape.dyads} dyads' branches"
            + (" and the triads' poses" if shape.poses > 1 else "")
            + f", {_count(shape.configurations)} configurations; at most "
            f"{COMBINATIONS.value:,.0f} (12 dyads) are solved; leave out --all to solve the "
            "document's own configuration"
        )


def solve(
    shape: Shape | None,
    samples: int,
    *,
    configurations: float = 1.0,
    order: int = 0,
    triad: str | None = None,
) -> Estimate:
    """Solving at ``samples`` inputs: every one of ``configurations`` (sign combinations) at
    each, or a triad's every configuration (``triad``: its space) by its polynomial. Positions
    and, with ``order``, derivatives; the answer's own memory is the caller's (a command line
    streams it in chunks)."""
    if triad is not None:
        return Estimate(
            samples * TRIAD_UNITS[triad],
            samples * TRIAD_BYTES[triad],
            f"solving every configuration of the triad at {_count(samples)} inputs",
        )
    if shape is None:
        raise ValueError("a plan's shape is needed unless a triad is solved")
    j, dim = shape.joints, shape.dim
    work = configurations * j * (samples * (1.0 + 0.5 * order) + CALL_UNITS)
    peak = configurations * j * (samples * dim * 8 * (1 + order) * BYTES_FACTOR + 4096)
    what = f"solving {_count(configurations)} configuration" + ("s" if configurations != 1 else "")
    return Estimate(work, peak, f"{what} at {_count(samples)} inputs ({j} joints)")


def refine(points: int, joints: int, refined: int = 3, samples: int = 1024) -> Estimate:
    """Refining ``refined`` atlas matches against ``points`` fitted points: each point's nearest
    of ``samples`` curve samples, then least squares of one input per point plus the linkage's
    dozen parameters (60 evaluations a round, a Jacobian of a few evaluations per round)."""
    rounds = 60 * 14
    work = refined * (points * samples * 0.1 + rounds * joints * (points + CALL_UNITS))
    peak = points * samples * 2 * 8 * 2 + points * 16 * 8 * 8
    return Estimate(work, peak, f"refining {refined} matches to {_count(points)} points")


PIXEL_UNITS = 0.4
"""Placements' worth of work to render one pixel of an animation frame (measured 31 ns)."""
MAX_FRAME_ASPECT = 9.5 / 6.4
"""A frame is 6.4 inches wide and at most about 9.5 tall (a drawing's aspect is clamped to
1.3 and the margins added): the pixels of a frame are at most 6.4·9.5·dpi²."""


def animation(frames: int, dpi: int, *, gif: bool, trace_estimate: Estimate) -> Estimate:
    """Rendering ``frames`` frames at ``dpi`` (frames are 6.4 inches wide): each pixel drawn
    once a frame; a GIF holds every frame's palette image (a byte a pixel) until it is written,
    where an MP4 streams them to ffmpeg."""
    width = 6.4 * dpi
    pixels = width * width * MAX_FRAME_ASPECT
    work = frames * pixels * PIXEL_UNITS + trace_estimate.work
    # The frame being drawn (RGBA), its palette lookup (8 bytes a pixel) and the GIF's frames.
    peak = pixels * 16 + (frames * pixels if gif else 0) + trace_estimate.bytes
    kind = "a GIF" if gif else "an MP4"
    return Estimate(
        work,
        peak,
        f"{kind} of {_count(frames)} frames at {dpi} dpi ({_count(pixels)} pixels each)",
    )


TARGET_UNITS = {"fourbar": 80_000.0, "spherical-fourbar": 130_000.0}
"""Placements' worth of work to evaluate paper 003's outputs of one four-bar (its
coefficients' extremes over the input: measured 6 and 10 ms)."""
TARGET_SEEDS = 600
"""Newton iterations started at most (``linkwright.synthesis.targets.MAX_SEEDS``)."""


def grid(family: str, nodes: int, free: int, targets: int) -> Estimate:
    """``synth targets``: the outputs at every node of a grid of ``nodes`` per free link
    (``nodes^free`` four-bars), then Newton from the best nodes (about a stencil of 2·free + 1
    evaluations per seed)."""
    linkages = float(nodes) ** free
    newton = min(TARGET_SEEDS, linkages) * (2 * free + 1)
    work = (linkages + newton) * TARGET_UNITS.get(family, TARGET_UNITS["spherical-fourbar"])
    # The grid's nodes, outputs and residuals (a few copies), and a chunk of four-bars.
    peak = linkages * (free + targets) * 8 * 6 + 1e8
    return Estimate(
        work,
        peak,
        f"searching a grid of {_count(nodes)}^{free} = {_count(linkages)} four-bars",
    )


SHARD_SAMPLE_BYTES = 180
"""Peak bytes per curve sample of an atlas shard being built (a geared five-bar's; 20 to 80
for the four-bars)."""


def check_atlas(count: int, samples: int, shard_size: int) -> None:
    """Refuse an atlas build beyond its budgets (:data:`ATLAS_COUNT`, :data:`ATLAS_SAMPLES`,
    :data:`ATLAS_CURVE_SAMPLES`, :data:`SHARD_BYTES`), naming the option to lower."""
    if count > ATLAS_COUNT.value:
        raise CostError(
            f"too costly: --count {count:,} entries; at most {ATLAS_COUNT.value:,.0f} "
            "(the largest atlas measured: 53 min, 25.6 GB of disk, 7.2 GB of index in memory); "
            "lower --count"
        )
    if samples > ATLAS_SAMPLES.value:
        raise CostError(
            f"too costly: --samples {samples:,} per curve; at most {ATLAS_SAMPLES.value:,.0f} "
            "(the descriptors keep 8 harmonics; 64 resolve them); lower --samples"
        )
    if count * samples > ATLAS_CURVE_SAMPLES.value:
        most = int(ATLAS_CURVE_SAMPLES.value // samples)
        raise CostError(
            f"too costly: {count:,} curves of {samples:,} samples is "
            f"{count * samples:.3g} curve samples; at most {ATLAS_CURVE_SAMPLES.value:.2g} "
            f"(the largest build measured); lower --count to {_count(_round_down(most))} or "
            "--samples"
        )
    shard = min(shard_size, count) * samples * SHARD_SAMPLE_BYTES
    if shard > SHARD_BYTES.value:
        most = int(SHARD_BYTES.value // (samples * SHARD_SAMPLE_BYTES))
        raise CostError(
            f"too costly: a shard of {min(shard_size, count):,} curves of {samples:,} samples "
            f"needs up to {describe_bytes(shard)} per worker (at most "
            f"{describe_bytes(SHARD_BYTES.value)}); lower --shard-size to "
            f"{_count(_round_down(most))} or fewer"
        )


# --------------------------------------------------------------------------------------------
# The deadline of a request
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Deadline:
    at: float
    seconds: float
    lower: str


_DEADLINE: contextvars.ContextVar[_Deadline | None] = contextvars.ContextVar(
    "linkwright_deadline", default=None
)


@contextmanager
def deadline(seconds: float, lower: str) -> Iterator[None]:
    """Run the body with a deadline ``seconds`` from now; :func:`check_time` inside it raises
    :class:`OverTime` once it has passed, saying to lower ``lower``. A deadline already set
    (an outer one) that ends sooner is kept."""
    outer = _DEADLINE.get()
    mine = _Deadline(time.monotonic() + seconds, seconds, lower)
    token = _DEADLINE.set(mine if outer is None or mine.at < outer.at else outer)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def check_time() -> None:
    """Raise :class:`OverTime` if the current deadline (if any) has passed. Called between the
    steps of long loops, never inside the numeric kernels."""
    current = _DEADLINE.get()
    if current is not None and time.monotonic() > current.at:
        raise OverTime(
            f"took longer than the {current.seconds:g} s budget of a request; lower {current.lower}"
        )


def remaining() -> float | None:
    """Seconds left before the current deadline (None without one; 0 once passed)."""
    current = _DEADLINE.get()
    return None if current is None else max(0.0, current.at - time.monotonic())

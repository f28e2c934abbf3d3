"""Every circuit of every configuration, by continuation: for plans with triads, and as a check.

A dyad's branch is a sign that stays put along a branch of motion, so :func:`~linkwright.engine.
circuits.trace` walks a circuit by switching signs at the dyads' limit positions. A triad's
branch is a pose index, a name for one of up to 6 (plane) or 8 (sphere) poses at one input; the
poses keep their order only between inputs where two of them merge, and their order can also
turn over where one pose's angle wraps. So here circuits are followed by continuity:

1. Every configuration (each combination of dyad signs and triad pose indices) is solved on a
   grid of inputs over the input's period. Each is a *node* with a *label*: the dyad signs and
   the sign of each triad's closure (:func:`~linkwright.engine.triad_steps.triad_closure`),
   which stays put along a branch and flips only where two poses merge, like a dyad's sign.
2. Neighbouring samples are joined node to node within each label, by the least total distance
   (an assignment problem). Where the number of nodes of a label changes between two samples,
   or a join is not clearly the nearest, the interval is bisected, all such intervals in one
   batch per round, down to adjacent floating-point inputs.
3. There, a node that ends is a limit position: it is joined to the node of the label that
   differs in the one step that folds, and that ends with it (the two poses merge). A node that
   begins is joined likewise.
4. Every node then has two neighbours, and the joins close into cycles: the circuits. Each is
   resampled (limits kept exactly as samples, even spacing in the input between them, or in
   the joints' travel) and solved once more with derivatives on the configuration followed.

The result names, for each limit position, the configurations that join there.
"""

from __future__ import annotations

import copy
import itertools
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from typing import Any, TypeVar, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

from linkwright.engine.arcs import InputArcs
from linkwright.engine.evaluate import Motion, batch_shape, evaluate
from linkwright.engine.plan import DYAD_TYPES, Fixed, Plan

__all__ = [
    "Circuit",
    "Limit",
    "Memo",
    "arcs_of",
    "circuit_arcs",
    "every_circuit",
    "every_configuration",
    "forget_kept",
]

Array = NDArray[np.float64]
T = TypeVar("T")

# A workbench scene asks for the same linkage's circuits several times (to count them for the
# budget, to draw them, again with derivatives for the diagrams), and a drag asks again for a
# document it has just drawn: the parts that do not depend on what is asked of them (a triad's
# graph of joins, a dyad chain's arcs and samples) are kept for the last few linkages. Only
# small batches are kept, and few graphs (about a megabyte each), so that the memory held
# stays within a few tens of megabytes.
MEMO_SIZE = 32
MEMO_NUMBERS = 4096


_KEPT: list[Memo] = []


def forget_kept() -> None:
    """Forget every kept result (each :class:`Memo`): the next call computes afresh, as a cost
    measurement must, since the cost model bounds the work without them."""
    for memo in _KEPT:
        memo.clear()


class Memo:
    """A small thread-safe LRU of computed values, keyed by a linkage's plan and numbers."""

    def __init__(self, size: int = MEMO_SIZE) -> None:
        self.size = size
        self._items: OrderedDict[Hashable, Any] = OrderedDict()
        self._lock = threading.Lock()
        _KEPT.append(self)

    def get(self, key: Hashable | None, make: Callable[[], T]) -> T:
        """The value kept under ``key``, else ``make()`` (kept unless ``key`` is None)."""
        if key is None:
            return make()
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                # One memo holds several kinds of value, but a key names the call that made
                # its value (the caller's tag and arguments are in it), so what is kept under
                # ``key`` is what this caller's ``make`` returns.
                return cast(T, self._items[key])
        value = make()
        with self._lock:
            self._items[key] = value
            while len(self._items) > self.size:
                self._items.popitem(last=False)
        return value

    def has(self, key: Hashable | None) -> bool:
        with self._lock:
            return key is not None and key in self._items

    def put(self, key: Hashable | None, value: Any) -> None:
        if key is None:
            return
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                self._items.popitem(last=False)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()


def memo_key(
    plan: Plan, params: Mapping[str, ArrayLike], points: frozenset[str], *more: Hashable
) -> Hashable | None:
    """A key naming one linkage's plan and numbers exactly (their bytes), or None where the
    batch is too large to keep or some value cannot be keyed."""
    items = []
    numbers = 0
    for name in sorted(params):
        a = np.asarray(params[name])
        numbers += a.size
        if numbers > MEMO_NUMBERS or a.dtype.hasobject:
            return None
        items.append((name, a.dtype.str, a.shape, a.tobytes()))
    key = (plan, tuple(items), frozenset(points), *more)
    try:
        hash(key)
    except TypeError:
        return None
    return key


TWO_PI = 2.0 * np.pi
GRID = 720
ROUNDS = 64
# A join of two nodes is accepted as continuous when it is shorter than this fraction of the
# distance from either node to any other node of its label: closer poses are resolved by
# bisecting the interval until the motion in it is small beside their separation.
CLEAR = 0.25
# Bisection stops this close to a limit position (relative to the input): the two merging poses
# are then about sqrt(1e-10)·size apart, far more than the solvers need to tell them apart (they
# merge poses closer than 1e-7), so both are seen up to the interval's left end and none past it.
FOLD_WIDTH = 1e-10
# Within that width a branch moves by about the square root of the input's
# rounding (at a limit position) times the mechanism's size: a join longer than this there is a
# branch ending and another beginning.
JUMP = 1e-3


@dataclass(frozen=True)
class Limit:
    """A limit position of the input on a circuit: two configurations merge at ``input``.

    ``before`` and ``after`` are the branch values (dyad sign or triad pose index, by step name)
    of the configurations met on either side of the turn, as the circuit runs.
    """

    input: float
    before: dict[str, float]
    after: dict[str, float]


@dataclass(frozen=True)
class Circuit:
    """One closed circuit: its samples as a :class:`Motion` and the limits it turns at."""

    motion: Motion
    limits: tuple[Limit, ...]

    @property
    def full(self) -> bool:
        """Whether the input turns without a limit on this circuit."""
        return not self.limits


def _branch_steps(plan: Plan) -> list[tuple[str, tuple[float, ...]]]:
    """Each step with a branch, and the values its branch takes."""
    steps: list[tuple[str, tuple[float, ...]]] = []
    for step in plan.steps:
        if isinstance(step, DYAD_TYPES):
            steps.append((step.name, (1.0, -1.0)))
        elif hasattr(step, "max_poses"):
            steps.append((step.name, tuple(float(k) for k in range(step.max_poses))))
    return steps


def every_configuration(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    inputs: ArrayLike,
    *,
    points: frozenset[str] = frozenset(),
    order: int = 2,
) -> tuple[list[dict[str, float]], Motion]:
    """Every combination of branch values, solved at ``inputs`` for a batch of mechanisms.

    Returns the combinations (step name → branch value: a dyad's sign, a triad's pose index) and
    one :class:`Motion` whose leading axis runs over them, before the batch's and the samples'
    (its ``valid`` says which are real at each input). Two combinations can describe one
    configuration only at a limit position, where two branches meet.

    Examples
    --------
    A four-bar has two configurations (its assembly signs) wherever it assembles:

    >>> from linkwright.engine import Crank, DyadRRR, Fixed, Plan
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Crank("A", "A0", 1.0),
    ...              DyadRRR("B", "A", 5.0, "B0", 3.5)), traced=("B",))
    >>> combos, motion = every_configuration(plan, {"A0": [0.0, 0.0], "B0": [4.0, 0.0]},
    ...                                      [0.0, 1.0], points=frozenset({"A0", "B0"}))
    >>> combos, motion.valid.tolist()
    ([{'B': 1.0}, {'B': -1.0}], [[True, True], [True, True]])
    """
    steps = _branch_steps(plan)
    combos = [
        dict(zip([name for name, _ in steps], values, strict=True))
        for values in itertools.product(*(vals for _, vals in steps))
    ]
    theta = np.atleast_1d(np.asarray(inputs, dtype=float))
    # The combinations form a new leading axis, before the batch's and the samples'.
    shape = np.broadcast_shapes(batch_shape(params, points) + (1,), theta.shape)
    lead = (len(combos),) + (1,) * len(shape)
    branches = {name: np.array([c[name] for c in combos]).reshape(lead) for name, _ in steps}
    motion = evaluate(
        plan,
        params,
        np.broadcast_to(theta, (len(combos),) + shape),
        points=points,
        branches=branches,
        order=order,
    )
    return combos, motion


class _Solver:
    """Configurations of one mechanism at any inputs, as nodes: positions and labels."""

    def __init__(self, plan: Plan, params: Mapping[str, ArrayLike], points: frozenset[str]):
        self.plan, self.params, self.points = plan, params, points
        self.moving = [j for j in plan.joints if not isinstance(plan.step(j), Fixed)]
        self.triads = [s.name for s in plan.triads]
        self.steps = _branch_steps(plan)
        self.scale = 1.0

    def solve(self, theta: Array) -> tuple[Array, NDArray[np.int64], NDArray[np.bool_]]:
        """Positions ``(C, n, D)`` of every combination, their labels ``(C, n)`` and validity."""
        combos, motion = every_configuration(
            self.plan, self.params, theta, points=self.points, order=0
        )
        self.combos = combos
        x = np.concatenate([motion.positions[j] for j in self.moving], axis=-1) / self.scale
        label = np.zeros(motion.valid.shape, dtype=np.int64)
        for bit, (name, _) in enumerate(self.steps):
            if name in self.triads:
                side = np.asarray(motion.margins[name]) >= 0
            else:
                side = np.array([c[name] > 0 for c in combos])[:, None]
            label |= np.broadcast_to(side, label.shape).astype(np.int64) << bit
        return x, label, motion.valid


@dataclass
class _Sample:
    """The nodes at one input: positions ``(C, D)``, labels ``(C,)`` and which are real."""

    theta: float
    x: Array
    label: NDArray[np.int64]
    valid: NDArray[np.bool_]


_End = tuple[_Sample, int]
"""A node: a sample and a combination's index in it (a branch ending or beginning there)."""
_Join = tuple[_Sample, int, _Sample, int]
"""Two nodes joined along a branch: (sample, combination) to (sample, combination)."""
_Cycle = list[tuple[_Sample, int, str]]
"""A closed cycle of nodes, each with how it was reached (a join or a turn)."""


def _samples(solver: _Solver, theta: Array) -> list[_Sample]:
    x, label, valid = solver.solve(theta)
    return [_Sample(float(t), x[:, i], label[:, i], valid[:, i]) for i, t in enumerate(theta)]


def _join(a: _Sample, b: _Sample) -> tuple[list[tuple[int, int, float]], bool]:
    """Join the nodes of ``a`` to those of ``b`` label by label, by the least total distance.

    Returns the joins (node in ``a``, node in ``b``, distance) and whether the interval is
    *clean*: every node has a partner of its label and every join is clearly the nearest (its
    length a small part of the separation between the nodes of that label, and of the
    mechanism's size). Otherwise the interval needs bisecting.
    """
    pairs: list[tuple[int, int, float]] = []
    clean = True
    for lab in np.union1d(a.label[a.valid], b.label[b.valid]):
        ia = np.flatnonzero(a.valid & (a.label == lab))
        ib = np.flatnonzero(b.valid & (b.label == lab))
        if len(ia) != len(ib):
            clean = False
        if not len(ia) or not len(ib):
            continue
        cost = np.max(np.abs(a.x[ia][:, None, :] - b.x[ib][None, :, :]), axis=-1)
        rows, cols = linear_sum_assignment(cost)
        moved = cost[rows, cols]
        near = np.full(len(rows), 1.0)  # positions are scaled to the mechanism's size
        if len(ia) > 1 and len(ib) > 1:
            sep_a = np.max(np.abs(a.x[ia][:, None, :] - a.x[ia][None, :, :]), axis=-1)
            sep_b = np.max(np.abs(b.x[ib][:, None, :] - b.x[ib][None, :, :]), axis=-1)
            np.fill_diagonal(sep_a, np.inf)
            np.fill_diagonal(sep_b, np.inf)
            near = np.minimum(near, np.minimum(sep_a.min(1)[rows], sep_b.min(1)[cols]))
        if np.any(moved > CLEAR * near):
            clean = False
        pairs += [
            (int(ia[r]), int(ib[c]), float(d)) for r, c, d in zip(rows, cols, moved, strict=True)
        ]
    return pairs, clean


def _join_all(
    intervals: list[tuple[_Sample, _Sample]],
) -> list[tuple[list[tuple[int, int, float]], bool]]:
    """:func:`_join` of every interval, the clean ones at once.

    Where every node of ``a`` has a partner of its label in ``b`` within ``CLEAR`` of the
    separation of the nodes of that label (the clean case, nearly every interval of the grid),
    the nearest partners are the least-distance assignment and the only one: another pairing
    moves some node to a partner at least 0.75 of a separation away, more than the 0.25 it
    replaces. So each node's nearest partner is the join :func:`_join` finds, the same numbers;
    the other intervals go through :func:`_join` itself.
    """
    if not intervals:
        return []
    xa = np.stack([a.x for a, _ in intervals])  # (n, C, D)
    xb = np.stack([b.x for _, b in intervals])
    la = np.stack([a.label for a, _ in intervals])
    lb = np.stack([b.label for _, b in intervals])
    va = np.stack([a.valid for a, _ in intervals])
    vb = np.stack([b.valid for _, b in intervals])
    same = va[:, :, None] & vb[:, None, :] & (la[:, :, None] == lb[:, None, :])
    cost = np.max(np.abs(xa[:, :, None, :] - xb[:, None, :, :]), axis=-1)
    near_cost = np.where(same, cost, np.inf)
    partner = np.argmin(near_cost, axis=-1)  # (n, C)
    moved = np.take_along_axis(near_cost, partner[..., None], -1)[..., 0]
    kin_a = va[:, :, None] & va[:, None, :] & (la[:, :, None] == la[:, None, :])
    kin_b = vb[:, :, None] & vb[:, None, :] & (lb[:, :, None] == lb[:, None, :])
    count_a = kin_a.sum(-1)
    # Equal counts label by label: each node of a sees as many of its label in b as in a, and
    # each node of b has its label in a.
    counts = np.all(~va | (same.sum(-1) == count_a), -1) & np.all(~vb | same.any(1), -1)
    taken = np.zeros(same.shape, dtype=bool)
    np.put_along_axis(taken, partner[..., None], va[..., None], -1)
    onto = np.all(taken.sum(1) <= 1, -1)

    def separation(x: Array, kin: NDArray[np.bool_]) -> Array:
        d = np.max(np.abs(x[:, :, None, :] - x[:, None, :, :]), axis=-1)
        eye = np.eye(x.shape[1], dtype=bool)
        nearest: Array = np.where(kin & ~eye, d, np.inf).min(-1)
        return nearest

    sep_a = separation(xa, kin_a)
    sep_b = np.take_along_axis(separation(xb, kin_b), partner, -1)
    near = np.where(count_a > 1, np.minimum(1.0, np.minimum(sep_a, sep_b)), 1.0)
    close = ~va | ((moved <= CLEAR * near) & (near > 0))
    fast = counts & onto & np.all(close, -1)
    out = []
    for k, (a, b) in enumerate(intervals):
        if not fast[k]:
            out.append(_join(a, b))
            continue
        rows = np.flatnonzero(va[k])
        rows = rows[np.argsort(la[k][rows], kind="stable")]  # label by label, as _join
        out.append(
            ([(int(i), int(partner[k, i]), float(cost[k, i, partner[k, i]])) for i in rows], True)
        )
    return out


def _differs_in_one(x: int, y: int) -> bool:
    z = x ^ y
    return z != 0 and z & (z - 1) == 0


# Ends of branches this close in the input and in position are one limit position: near a
# double root the solvers see the two merging poses as one (or flicker between one and two)
# over a few rounding units of the input, so one limit can leave its ends in nearby intervals.
END_INPUT = 1e-8
END_DISTANCE = 1e-3


def _pair_ends(ends: list[_End]) -> list[tuple[_End, _End]]:
    """Pair the branch ends of one kind (all ending, or all beginning) into limit positions:
    labels that differ in one step (the two poses merging), nearest first."""
    candidates = []
    for (sa, i), (sb, j) in itertools.combinations(ends, 2):
        if abs(sa.theta - sb.theta) > END_INPUT * max(1.0, abs(sa.theta)):
            continue
        if not _differs_in_one(int(sa.label[i]), int(sb.label[j])):
            continue
        d = float(np.max(np.abs(sa.x[i] - sb.x[j])))
        if d <= END_DISTANCE:
            candidates.append((d, (sa, i), (sb, j)))
    used: set[tuple[int, int]] = set()
    pairs: list[tuple[_End, _End]] = []
    for _, u, v in sorted(candidates, key=lambda c: c[0]):
        ku, kv = (id(u[0]), u[1]), (id(v[0]), v[1])
        if ku not in used and kv not in used:
            pairs.append((u, v))
            used |= {ku, kv}
    return pairs


def _graph(
    solver: _Solver, grid: Array, period: float
) -> tuple[_Sample, _Sample, list[_Join], list[tuple[_End, _End]]]:
    """Nodes (sample index, combination) and their joins over the whole period."""
    samples = _samples(solver, grid)
    wrap = _Sample(samples[0].theta + period, samples[0].x, samples[0].label, samples[0].valid)
    chain = [*samples, wrap]
    # Intervals still to resolve: (left sample, right sample), bisected in rounds.
    open_ = [(chain[i], chain[i + 1]) for i in range(len(chain) - 1)]
    joins: list[_Join] = []
    deaths: list[_End] = []
    births: list[_End] = []
    for _ in range(ROUNDS + 1):
        pending = []
        for (a, b), (pairs, clean) in zip(open_, _join_all(open_), strict=True):
            if clean:
                joins += [(a, i, b, j) for i, j, _ in pairs]
            elif b.theta - a.theta <= FOLD_WIDTH * max(1.0, abs(a.theta)) or _ == ROUNDS:
                # Adjacent inputs: a join that still moves is no continuation but a branch
                # ending at a and another beginning at b.
                pairs = [(i, j, d) for i, j, d in pairs if d <= JUMP]
                joins += [(a, i, b, j) for i, j, _ in pairs]
                left = {int(i) for i in np.flatnonzero(a.valid)} - {i for i, _, _ in pairs}
                right = {int(j) for j in np.flatnonzero(b.valid)} - {j for _, j, _ in pairs}
                deaths += [(a, i) for i in sorted(left)]
                births += [(b, j) for j in sorted(right)]
            else:
                pending.append((a, b))
        if not pending:
            break
        mids = np.array([0.5 * (a.theta + b.theta) for a, b in pending])
        mid = _samples(solver, mids)
        open_ = [p for (a, b), m in zip(pending, mid, strict=True) for p in ((a, m), (m, b))]
    turns = _pair_ends(deaths) + _pair_ends(births)
    return samples[0], wrap, joins, turns


def _cycles(
    first: _Sample,
    wrap: _Sample,
    joins: list[_Join],
    turns: list[tuple[_End, _End]],
    period: float,
) -> list[_Cycle]:
    """Walk the joins into closed cycles of (sample, combination, how it was reached)."""

    # A node is keyed by its sample object's id and combination; the wrap sample is the first.
    def key(s: _Sample, c: int) -> tuple[int, int]:
        return (id(first) if s is wrap else id(s), c)

    sample_of: dict[int, _Sample] = {}
    links: dict[tuple[int, int], list[tuple[tuple[int, int], str]]] = {}
    for a, i, b, j in joins:
        ka, kb = key(a, i), key(b, j)
        sample_of[ka[0]] = first if a is wrap else a
        sample_of[kb[0]] = first if b is wrap else b
        links.setdefault(ka, []).append((kb, "run"))
        links.setdefault(kb, []).append((ka, "run"))
    for (si, i), (sj, j) in turns:
        ki, kj = key(si, i), key(sj, j)
        sample_of[ki[0]] = first if si is wrap else si
        sample_of[kj[0]] = first if sj is wrap else sj
        links.setdefault(ki, []).append((kj, "turn"))
        links.setdefault(kj, []).append((ki, "turn"))
    seen: set[tuple[int, int]] = set()
    cycles = []
    # Start each cycle at a turn if it has one (the lowest limit), else at the first sample.
    order = sorted(links, key=lambda k: (sample_of[k[0]].theta, k[1]))
    starts = [k for k in order if any(how == "turn" for _, how in links[k])] + order
    for start in starts:
        if start in seen or len(links[start]) != 2:
            continue
        cycle = [(sample_of[start[0]], start[1], "start")]
        seen.add(start)
        prev, node = None, start
        # Leave a turn's start along its run, so the circuit goes up from the lower limit.
        here = sample_of[start[0]].theta

        def ahead(link: tuple[tuple[int, int], str], here: float = here) -> float:
            gap = sample_of[link[0][0]].theta - here
            return float(gap - period * np.round(gap / period))

        runs = [lk for lk in links[start] if lk[1] == "run"] or links[start]
        step, how = max(runs, key=ahead)
        while step != start:
            if step in seen or len(links.get(step, ())) != 2:
                break
            seen.add(step)
            cycle.append((sample_of[step[0]], step[1], how))
            prev, node = node, step
            options = [lk for lk in links[node] if lk[0] != prev]
            if not options:
                break
            step, how = options[0]
        else:
            cycles.append(cycle)
    return cycles


def arcs_of(found: list[Circuit], shape: tuple[int, ...] = ()) -> InputArcs:
    """The input's arcs of one linkage with a triad, from its circuits: each rocking circuit's
    range of inputs (its lower end in (−π, π]); ``full`` where every circuit turns fully;
    ``never`` where there is none. The configurations are followed, not the assembly held, so
    the arcs of several circuits may overlap."""
    _one_at_a_time(shape)
    return _arcs_from([(c.motion.input, c.full) for c in found])


def _one_at_a_time(shape: tuple[int, ...]) -> None:
    if shape:
        raise ValueError(
            "the circuits of a linkage with a triad are traced one mechanism at a time: index "
            "the batch (mechanism[i])"
        )


def _arcs_from(found: list[tuple[Array, bool]]) -> InputArcs:
    """:func:`arcs_of` from each circuit's inputs and whether it turns fully."""
    rocking = [theta for theta, full in found if not full]
    lo, hi = [], []
    for theta in rocking:
        x = np.unwrap(theta)
        shift = TWO_PI * np.ceil((x.min() - np.pi) / TWO_PI)  # the lower end into (−π, π]
        lo.append(x.min() - shift)
        hi.append(x.max() - shift)
    width = max(len(rocking), 1)
    pad = np.full(width, np.nan)
    return InputArcs(
        full=np.array(bool(found) and not rocking),
        never=np.array(not found),
        lo=np.array(lo) if rocking else pad,
        hi=np.array(hi) if rocking else pad,
        dyad_lo=np.full(width, -1),
        dyad_hi=np.full(width, -1),
    )


def circuit_arcs(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    samples: int,
    *,
    points: frozenset[str] = frozenset(),
    period: float = TWO_PI,
    shape: tuple[int, ...] = (),
) -> InputArcs:
    """``arcs_of(every_circuit(...))`` without placing the circuits' joints: the arcs need only
    the inputs each circuit is sampled at (its limits among them), not the configuration
    followed at each."""
    _one_at_a_time(shape)
    key = memo_key(plan, params, points, float(period), GRID)
    solver, cycles = _GRAPHS.get(key, lambda: _solved_cycles(plan, params, points, period, GRID))
    found = []
    for c in cycles:
        theta, _, limits = _resample(solver, c, samples, period, choose=False)
        found.append((theta, not limits))
    return _arcs_from(found)


def every_circuit(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    samples: int = 360,
    *,
    points: frozenset[str] = frozenset(),
    order: int = 2,
    period: float = TWO_PI,
    grid: int = GRID,
    spacing: str = "input",
) -> list[Circuit]:
    """Every closed circuit of one mechanism, over all its configurations (module docstring).

    Each circuit has about ``samples`` samples, its limit positions among them; the input is
    spaced evenly between limits (``spacing="input"``), or the joints' travel is
    (``spacing="path"``). Circuits come in the order of the lowest input they reach.

    Examples
    --------
    A crank-rocker driven at its rocker rocks over two arcs: two circuits, each turning at two
    limits, where the assembly sign changes.

    >>> from linkwright.engine import Crank, DyadRRR, Fixed, Plan
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Crank("A", "A0", 3.5),
    ...              DyadRRR("B", "A", 5.0, "B0", 1.0)), traced=("B",))
    >>> found = every_circuit(plan, {"A0": [0.0, 0.0], "B0": [4.0, 0.0]}, 64,
    ...                       points=frozenset({"A0", "B0"}))
    >>> [len(c.limits) for c in found], [sorted({l.before["B"] for l in c.limits}) for c in found]
    ([2, 2], [[-1.0, 1.0], [-1.0, 1.0]])
    """
    key = memo_key(plan, params, points, float(period), int(grid))
    solver, cycles = _GRAPHS.get(key, lambda: _solved_cycles(plan, params, points, period, grid))
    # Which configuration each sample follows does not depend on the order asked for: the
    # drawing (order 0) and the diagrams (order 2) share it.
    resampled = _RESAMPLED.get(
        None if key is None else (key, samples, spacing),
        lambda: [_resample(solver, c, samples, period, spacing) for c in cycles],
    )
    return [
        Circuit(
            evaluate(
                plan,
                params,
                theta.copy(),
                points=points,
                branches={k: v.copy() for k, v in branches.items()},
                order=order,
            ),
            limits,
        )
        for theta, branches, limits in resampled
    ]


_GRAPHS = Memo(8)
_RESAMPLED = Memo()


def _solved_cycles(
    plan: Plan, params: Mapping[str, ArrayLike], points: frozenset[str], period: float, grid: int
) -> tuple[_Solver, list[_Cycle]]:
    """The solver and the closed cycles of joins: all of :func:`every_circuit` that does not
    depend on the samples asked for (kept per linkage, :class:`Memo`)."""
    # The solver is kept and solves again later: on numbers of its own, which a caller that
    # changes its arrays in place afterwards cannot change under it.
    solver = _Solver(plan, copy.deepcopy(dict(params)), points)
    theta0 = -np.pi
    grid_theta = theta0 + period * np.arange(grid) / grid
    # The mechanism's size, for distances between configurations that mean the same everywhere.
    x, _, valid = solver.solve(grid_theta[:: max(1, grid // 64)])
    spread = np.where(valid[..., None], np.abs(x), 0.0)
    solver.scale = max(float(spread.max()) if spread.size else 1.0, 1e-300)
    first, wrap, joins, turns = _graph(solver, grid_theta, period)
    return solver, _cycles(first, wrap, joins, turns, period)


def _unwrapped(cycle: _Cycle, period: float) -> tuple[Array, list[int]]:
    """The inputs along a cycle, unwrapped to run continuously, and where it turns."""
    theta = np.array([s.theta for s, _, _ in cycle])
    turn_at = [k for k, (_, _, how) in enumerate(cycle) if how == "turn"]
    out = theta.copy()
    for k in range(1, len(out)):
        step = theta[k] - theta[k - 1]
        step -= period * np.round(step / period)
        out[k] = out[k - 1] + step
    return out, turn_at


def _resample(
    solver: _Solver,
    cycle: _Cycle,
    samples: int,
    period: float,
    spacing: str = "input",
    *,
    choose: bool = True,
) -> tuple[Array, dict[str, Array], tuple[Limit, ...]]:
    """The cycle's nodes resampled to about ``samples`` inputs: every limit a sample, each
    segment between limits (or the whole turn) sampled evenly in the input (sin² spacing
    between limits, as :func:`~linkwright.engine.circuits.trace`), or with ``spacing="path"``
    evenly in the joints' travel. Returns the inputs, the configuration followed at each (the
    branch of each step; not looked for unless ``choose``) and the limits, for the circuit to
    be solved on."""
    theta, turn_at = _unwrapped(cycle, period)
    combos = [c for _, c, _ in cycle]
    x = np.stack([s.x[c] for s, c, _ in cycle])
    labels = np.array([s.label[c] for s, c, _ in cycle])
    # A turn is the pair (k-1, k) at one input: the node after it starts the next segment.
    bounds = [0, *turn_at, len(cycle)]
    segments = [
        (bounds[i], bounds[i + 1]) for i in range(len(bounds) - 1) if bounds[i + 1] > bounds[i]
    ]
    pieces = []
    for s, e in segments:
        seg_theta, seg_x = theta[s:e], x[s:e]
        if not turn_at:
            # A circuit without limits closes where it started, a whole period on.
            seg_theta = np.append(seg_theta, theta[0] + np.sign(theta[-1] - theta[0]) * period)
            seg_x = np.vstack((seg_x, x[:1]))
        elif e < len(cycle):
            # A segment ends at the next limit, the first node of the next segment.
            seg_theta = np.append(seg_theta, theta[e])
            seg_x = np.vstack((seg_x, x[e]))
        else:
            # The last segment ends where the circuit started, at the same input modulo the
            # period (a circuit may come back a whole turn on).
            gap = theta[0] - theta[-1]
            seg_theta = np.append(seg_theta, theta[-1] + gap - period * np.round(gap / period))
            seg_x = np.vstack((seg_x, x[:1]))
        # The travel along the segment: the largest joint coordinate's chord at each step.
        walked = np.concatenate(([0.0], np.cumsum(np.max(np.abs(np.diff(seg_x, axis=0)), -1))))
        pieces.append((seg_theta, seg_x, walked, labels[s]))
    if spacing == "path":
        measure = np.array([p[2][-1] for p in pieces])
    else:
        measure = np.array([abs(p[0][-1] - p[0][0]) for p in pieces])
    total = float(measure.sum()) or 1.0
    # Each segment's share of the samples, by largest remainders so that they sum to
    # ``samples`` exactly (rounding each share could add one a segment), at least two each.
    raw = samples * measure / total
    counts = np.floor(raw).astype(int)
    counts[np.argsort(counts - raw)[: samples - int(counts.sum())]] += 1
    counts = np.maximum(counts, 2)
    want_theta, want_x, want_label = [], [], []
    for (seg_theta, seg_x, walked, label), count in zip(pieces, counts, strict=True):
        t = np.arange(count) / count
        if spacing == "path" and walked[-1] > 0:
            along = walked  # evenly in the travel
            goal = walked[-1] * t
        else:
            along = np.abs(seg_theta - seg_theta[0])
            ease = t if not turn_at else np.sin(0.5 * np.pi * t) ** 2
            goal = along[-1] * ease
        # Interpolate input and position at each goal along the (monotone) measure.
        k = np.clip(np.searchsorted(along, goal, side="right") - 1, 0, len(along) - 2)
        span = along[k + 1] - along[k]
        w = np.where(span > 0, (goal - along[k]) / np.where(span > 0, span, 1.0), 0.0)
        want_theta.append(seg_theta[k] + w * (seg_theta[k + 1] - seg_theta[k]))
        want_x.append((1 - w)[:, None] * seg_x[k] + w[:, None] * seg_x[k + 1])
        want_label.append(np.full(count, label))
    target_theta = np.concatenate(want_theta)
    target_x = np.concatenate(want_x)
    target_label = np.concatenate(want_label)
    branches: dict[str, Array] = {}
    if choose:
        # Solve every combination at the new inputs and follow the one nearest the interpolation.
        x_all, label_all, valid_all = solver.solve(target_theta)
        dist = np.max(np.abs(x_all - target_x[None]), axis=-1)
        dist = np.where(valid_all & (label_all == target_label[None]), dist, np.inf)
        # Where no node of the label is real (rounding at a limit), take the nearest of any.
        fallback = np.where(valid_all, np.max(np.abs(x_all - target_x[None]), axis=-1), np.inf)
        choice = np.where(np.isfinite(dist.min(0)), dist.argmin(0), fallback.argmin(0))
        chosen = [solver.combos[c] for c in choice]
        branches = {name: np.array([c[name] for c in chosen]) for name, _ in solver.steps}
    limits = []
    # A circuit with limits starts at one: the node it closes on comes before the first.
    for k in ([0] if turn_at else []) + turn_at:
        before = solver.combos[combos[k - 1]]
        after = solver.combos[combos[k]]
        limits.append(Limit(float(cycle[k][0].theta), dict(before), dict(after)))
    return target_theta, branches, tuple(limits)

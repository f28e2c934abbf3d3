"""Input ranges, limit positions and circuit tracing.

A dyad closes while a *closure quantity* q of its parents lies between two thresholds: the
squared distance between its pivots for an RRR dyad, in [(r1 − r2)², (r1 + r2)²], and the signed
distance of its pivot from the guide for an RRP dyad, in [−r, r]. Limit positions of the input
are the roots of q − threshold, i.e. of the dyad's discriminant.

Where every parent of the (single) dyad is a ground pivot or a joint on a crank turning with the
input (ratio 1), q is exactly ``c0 + c1·cos θ + c2·sin θ`` and the limits are closed-form
arc-cosines. Otherwise they are bracketed on a grid of the assembly predicate and bisected to
the last bit. Either way a limit is a root, not the nearest sample.

A circuit is what the machine does when it runs: where the input cannot turn fully, it sweeps an
arc of admissible inputs, and at each end the dyad that reached its limit changes branch, so the
traced curve is closed. :func:`trace` samples that whole closed path with every limit hit exactly,
spaced evenly in the input (``spacing="input"``) or, with a stated bound on every joint's step,
along the joints' paths (``spacing="path"``: for motion that concentrates near a change point).

This module is the public face of tracing; the work lives in rooms of its own, each re-exported
here: the limit search (:mod:`~linkwright.engine.limit_search`), the arcs and the input's
period (:mod:`~linkwright.engine.arc_search`), the walk of a circuit of several dyads
(:mod:`~linkwright.engine.circuit_walk`) and the spacing of its samples
(:mod:`~linkwright.engine.spacing`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arc_search import ARCS_MEMO as ARCS_MEMO
from linkwright.engine.arc_search import MAX_TURNS as MAX_TURNS
from linkwright.engine.arc_search import RATIO_TOL as RATIO_TOL
from linkwright.engine.arc_search import NoPeriod, input_arcs, input_turns
from linkwright.engine.arc_search import search_input_arcs as search_input_arcs
from linkwright.engine.arcs import TWO_PI, InputArcs
from linkwright.engine.circuit_walk import MAX_SEGMENTS as MAX_SEGMENTS
from linkwright.engine.circuit_walk import SCAN_CHUNK as SCAN_CHUNK
from linkwright.engine.circuit_walk import SCAN_NUMBERS as SCAN_NUMBERS
from linkwright.engine.circuit_walk import walk_circuit
from linkwright.engine.continuation import Memo, arcs_of, every_circuit, memo_key
from linkwright.engine.crossings import LIMIT, PLAIN
from linkwright.engine.evaluate import Motion, batch_shape, evaluate
from linkwright.engine.limit_search import BISECTIONS as BISECTIONS
from linkwright.engine.limit_search import GRID, normalised_arcs, turning_form, turns_with_input
from linkwright.engine.limit_search import SNAP_STEPS as SNAP_STEPS
from linkwright.engine.limit_search import TREE_LEVELS as TREE_LEVELS
from linkwright.engine.limit_search import TREE_NUMBERS as TREE_NUMBERS
from linkwright.engine.plan import Plan
from linkwright.engine.spacing import JUMP as JUMP
from linkwright.engine.spacing import MOVING as MOVING
from linkwright.engine.spacing import NOISE as NOISE
from linkwright.engine.spacing import PATH_CHUNK as PATH_CHUNK
from linkwright.engine.spacing import PATH_LEVELS as PATH_LEVELS
from linkwright.engine.spacing import PATH_PILOT as PATH_PILOT
from linkwright.engine.spacing import PATH_STEP as PATH_STEP
from linkwright.engine.spacing import STILL as STILL
from linkwright.engine.spacing import path_samples, sample_segments

__all__ = [
    "InputArcs",
    "NoPeriod",
    "input_arcs",
    "input_turns",
    "normalised_arcs",
    "trace",
]

Array = NDArray[np.float64]
Ints = NDArray[np.int64]
Flags = NDArray[np.bool_]
SAMPLED_MEMO = Memo()
SPACINGS = ("input", "path")


def trace(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    samples: int,
    *,
    points: frozenset[str] = frozenset(),
    circuit: int = 0,
    order: int = 2,
    start: float = 0.0,
    spacing: str = "input",
) -> Motion:
    """Sample the whole circuit of every linkage in the batch with ``samples`` inputs.

    The circuit is what the machine does when it runs. It starts on the document's assembly,
    at ``start`` where the input turns fully (one period: :func:`input_turns`), else at the lower
    end of the ``circuit``-th input arc (arcs ordered by their start). The input then runs up;
    each time a dyad reaches its limit position the input reverses and that dyad changes
    branch (its two branches meet there, so nothing jumps), until the linkage is back where it
    started. A single-dyad linkage sweeps its arc up and back; a six-bar may pass several limits
    of different dyads. Where a dyad's parents meet (:mod:`~linkwright.engine.crossings`: an
    exact kite or deltoid with A passing through B0; on the sphere A through ±B0) the dyad
    changes branch too, but the input runs on: the joint keeps to its analytic branch, whose
    sign flips there. An exact deltoid so comes back after one turn on its other branch, and
    its circuit takes two. Each stretch between two limits or crossings (a *segment*) starts
    with its limit or crossing, an exact sample; on a crossing the joint, undetermined by the
    dyad alone, is placed as the limit of its neighbours. A linkage with no such arc comes back
    with ``valid`` all False.

    Parameters
    ----------
    plan, params, points : the linkages, as for :func:`~linkwright.engine.evaluate`.
    samples : how many samples n per circuit (at least 2).
    circuit : which input arc to trace where the input cannot turn fully.
    order : 0 positions only, 1 with velocities, 2 with accelerations.
    start : where a full turn starts (radians).
    spacing : how the samples are spread along the circuit.

        ``"input"`` (default): segments share the samples in proportion to the joints' travel
        along them, a full turn in even steps of the input, a segment between limits in sin²
        steps (even along the curve near the limits, where the joints move like the square
        root of the input). Near a change point the motion itself concentrates (a four-bar a
        hair from a deltoid swings its rocker half a turn while the input moves by about the
        distance by which A misses B0), and one step of the input can then draw a chord across
        the curve; no bound on the step is claimed.

        ``"path"``: the joints advance in even steps along their own paths. With L_j the length
        of joint j's path over the circuit, and M = Σ max_j (dℓ_j/L_j) the circuit's
        normalised travel (the largest share of its own path any moving joint covers, summed
        along the circuit: 1 ≤ M ≤ the number of moving joints, 1 when they all move in
        proportion), every moving joint's step between consecutive samples, the last to the
        first included, is at most

            2·M·L_j/n + 2ν        (n ≥ 8S),

        S the number of segments (1 for a full turn, 2 for one dyad's arc, one more for each
        crossing passed: 4 for an exact kite), ν = 1e-7 of the linkage's size (near a limit a
        dyad's joint is known to about √ε of its link). The
        samples lie at most M/(n − S) of measure apart, and the grid they are interpolated on
        has cells of at most M/(4n), so c ≤ n/(n − S) + 2/4 ≤ 1.65 < 2. Measured on 12,000
        circuits of random near-singular four-bars, slider-cranks and spherical four-bars (the
        recipes of tests/singular_helpers.py, n = 60 and 360): c ≤ 1.19, median 1.00, wherever
        the positions' rounding is below 1e-6 of the curve. Against the curve's size D_j: a
        path that any line meets at most k times is at most (k/2)·π·D_j long (Cauchy–Crofton),
        so a four-bar's coupler point (its curve has degree 6, k = 6) steps at most
        6π·M·D_j/n + 2ν, its rocker pin (an arc swept there and back, k = 4) 4π·M·D_j/n + 2ν.
        Where A passes within about 1e-12 of B0 the positions themselves carry rounding of
        ε·|A|·(link)/|A − B0| and more, which adds to the step. The cost is about five
        evaluations per sample instead of one.

        Where the positions themselves jump (a dyad whose parents miss each other by more
        than a crossing's rounding but too little for the input's last bits to resolve the
        swing, some 1e-15 to 1e-13 of the linkage's size), no bisection shrinks the step. An
        interval that does not shrink to within a few ulps of input, and still moves a joint
        by more than two mean steps, weighs nothing: no samples are spent on it, and the step
        across it is the jump plus at most a regular step on either side.

    Returns
    -------
    Motion
        Shape ``batch + (samples,)``, with ``branches`` the branch of each dyad at each sample.

    Raises
    ------
    ValueError
        If ``samples`` < 2 or ``spacing`` is not one of the above.

    Examples
    --------
    A four-bar 1e-9 from a deltoid: in one step of the input B swings across the curve, a chord
    of 2.96 (its rocker is 2), while spacing by path keeps every step below 0.4:

    >>> from linkwright.mechanisms import FourBar
    >>> m = FourBar(A0=[0, 0], B0=[1, 0], crank=1 + 1e-9, coupler=2, rocker=2)
    >>> def largest_step(spacing):
    ...     motion = trace(m.plan, m.params(), 48, points=m.points, order=0, spacing=spacing)
    ...     B = motion.positions["B"]
    ...     return round(float(np.linalg.norm(np.roll(B, -1, 0) - B, axis=-1).max()), 3)
    >>> largest_step("input"), largest_step("path")
    (2.964, 0.392)

    Driving the long link of a crank-rocker, the input rocks between arccos(−11/28) and 2π
    minus it; both limits are samples with either spacing:

    >>> rocking = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    >>> motion = trace(rocking.plan, rocking.params(), 8, points=rocking.points, spacing="path")
    >>> np.degrees(motion.input).round(3)
    array([113.132, 129.578, 168.303, 213.011, 246.868, 230.422, 191.697,
           146.989])
    >>> motion.branches["B"]
    array([ 1.,  1.,  1.,  1., -1., -1., -1., -1.])

    A linkage that cannot be assembled has no circuit, and a spacing must be one of the two:

    >>> never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> bool(trace(never.plan, never.params(), 8, points=never.points, spacing="path").valid.any())
    False
    >>> trace(never.plan, never.params(), 8, points=never.points, spacing="arc")
    Traceback (most recent call last):
    ...
    ValueError: spacing must be one of 'input', 'path', got 'arc'
    """
    if plan.triads:
        # A triad's configurations are followed by continuation: every circuit of every one.
        found = every_circuit(
            plan,
            params,
            samples,
            points=points,
            order=order,
            spacing=spacing,
            period=TWO_PI * float(np.max(input_turns(plan, params, points=points))),
        )
        arcs_of(found, batch_shape(params, points))  # one linkage at a time
        if not found:
            # Nothing assembles: a circuit of no valid sample, as for a dyad that never closes.
            theta = np.linspace(-np.pi, np.pi, samples, endpoint=False)
            motion = evaluate(plan, params, theta, points=points, order=order)
            return _restrict(motion, np.zeros(motion.valid.shape, dtype=bool))
        if not 0 <= circuit < len(found):
            raise ValueError(
                f"circuit: {circuit} is not one of the linkage's {len(found)} circuits"
            )
        return found[circuit].motion
    if samples < 2:
        raise ValueError("a circuit needs at least 2 samples")
    if spacing not in SPACINGS:
        raise ValueError(
            f"spacing must be one of {', '.join(map(repr, SPACINGS))}, got {spacing!r}"
        )
    # Where the samples lie does not depend on the order asked for: a scene's drawing (order 0)
    # and its diagrams (order 2) share them.
    theta, branches, on = SAMPLED_MEMO.get(
        memo_key(plan, params, points, "trace", samples, circuit, float(start), spacing),
        lambda: sample_circuit(plan, params, points, samples, circuit, start, spacing),
    )
    motion = evaluate(
        plan,
        params,
        theta.copy(),
        points=points,
        branches={k: v.copy() for k, v in branches.items()} or None,
        order=order,
        crossings=on,
    )
    keep = np.isfinite(theta)
    if keep.all():
        return motion
    return _restrict(motion, keep)


def sample_circuit(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    points: frozenset[str],
    samples: int,
    circuit: int,
    start: float,
    spacing: str,
) -> tuple[Array, dict[str, Array], dict[str, Array] | None]:
    """The inputs of :func:`trace`'s samples, each dyad's branch at each and the crossings."""
    arcs = input_arcs(plan, params, points=points)
    shape = arcs.full.shape
    period = np.broadcast_to(np.asarray(arcs.period, dtype=float), shape)
    idx = np.clip(circuit, 0, arcs.lo.shape[-1] - 1)
    lo = arcs.lo[..., idx]
    hi = arcs.hi[..., idx]
    have_arc = np.isfinite(lo) & (circuit < arcs.lo.shape[-1])
    usable = arcs.full | have_arc
    dyads = plan.dyads
    doc = {
        d.name: np.broadcast_to(np.asarray(params[d.branch], dtype=float), shape).copy()
        for d in dyads
    }
    if len(dyads) <= 1:
        seg_start = np.stack((np.where(arcs.full, start, lo), np.where(arcs.full, np.nan, hi)), -1)
        seg_end = np.stack((np.where(arcs.full, start + period, hi), lo), -1)
        seg_end[..., 1] = np.where(arcs.full, np.nan, seg_end[..., 1])
        seg_branches = {k: np.stack((v, -v), -1) for k, v in doc.items()}
        ends = np.broadcast_to(np.where(arcs.full, PLAIN, LIMIT)[..., None], shape + (2,)).copy()
        segs = (seg_start, seg_end, seg_branches, ends, ends.copy())
        analytic = (
            plan.space == "plane"
            and all(turns_with_input(plan, p, params) for d in dyads for p in d.parents)
            and np.all(np.rint(period / TWO_PI) == 1)
        )
        # crossings.Turning declares float arrays where turning_form's pivot and arm are
        # complex (crossings takes only their differences, moduli and angles).
        turning = cast("crossings.Turning", turning_form) if analytic else None
        segs = crossings.cut_single(plan, params, points, segs, arcs, usable, doc, GRID, turning)
        weight = None
    else:
        theta0 = np.where(arcs.full, start, np.where(have_arc, lo, 0.0))
        first = np.where(arcs.full, PLAIN, LIMIT)
        segs = walk_circuit(plan, params, points, theta0, doc, period, usable, first=first)
        for finer in REFINE_GRIDS:
            failed = usable & ~np.isfinite(segs[0][..., 0])
            if not failed.any():
                break
            # A limit gap narrower than a scan cell was stepped over and the walk wandered into
            # a neighbouring arc without closing: walk those linkages again on a finer scan.
            sub = _subset(params, points, shape, failed)
            again = walk_circuit(
                plan,
                sub,
                points,
                theta0[failed],
                {k: v[failed] for k, v in doc.items()},
                period[failed],
                np.ones(int(failed.sum()), bool),
                grid=finer,
                first=first[failed],
            )
            segs = crossings.scatter(segs, again, failed)
        weight = _path_lengths(plan, params, points, *segs)
    seg_start, seg_end, seg_branches, begin, end = segs
    seg_start = np.where(usable[..., None], seg_start, np.nan)
    # Next to a limit position the input is spaced as sin², not next to a crossing.
    code = crossings.warp_codes(begin, end)
    if spacing == "path":
        theta, segment = path_samples(
            plan, params, points, seg_start, seg_end, seg_branches, samples, code, begin, end
        )
    else:
        theta, segment = sample_segments(seg_start, seg_end, samples, code, weight)
    branches = {
        k: np.take_along_axis(np.nan_to_num(v, nan=1.0), segment, -1)
        for k, v in seg_branches.items()
    }
    on = crossings.flags(
        plan,
        begin,
        end,
        seg_start,
        seg_end,
        segment,
        theta == np.take_along_axis(seg_start, segment, -1),
        theta == np.take_along_axis(seg_end, segment, -1),
    )
    return theta, branches, on


PILOT = 17


def _path_lengths(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    points: frozenset[str],
    seg_start: Array,
    seg_end: Array,
    seg_branches: Mapping[str, Array],
    begin: Ints,
    end: Ints,
) -> Array:
    """How far the joints travel along each segment, from a few samples of each.

    A segment short in the input can be long on the curve (two limits close together, with the
    joints swinging fast between them): sharing samples by the input's travel would draw it as
    one chord. NaN segments weigh 0; a segment of zero travel keeps a tiny weight so that it
    still gets its start.
    """
    f = np.sin(0.5 * np.pi * np.linspace(0.0, 1.0, PILOT)) ** 2
    a, b = seg_start[..., None], seg_end[..., None]
    theta = np.where(np.isfinite(a), np.where(f == 1.0, b, a + (b - a) * f), 0.0)
    shape = seg_start.shape
    flat = theta.reshape(shape[:-1] + (-1,))
    branches = {
        k: np.repeat(np.nan_to_num(v, nan=1.0), PILOT, axis=-1) for k, v in seg_branches.items()
    }
    segment = np.broadcast_to(np.repeat(np.arange(shape[-1]), PILOT), flat.shape)
    ends = np.broadcast_to(np.tile(f, shape[-1]), flat.shape)
    on = crossings.flags(plan, begin, end, seg_start, seg_end, segment, ends == 0.0, ends == 1.0)
    motion = evaluate(plan, params, flat, points=points, branches=branches, order=0, crossings=on)
    travel = np.zeros(shape)
    for pos in motion.positions.values():
        p = pos.reshape(shape + (PILOT, pos.shape[-1]))
        step = np.linalg.norm(np.diff(p, axis=-2), axis=-1)
        travel += np.nansum(step, axis=-1)
    travel = np.where(np.isfinite(seg_start), travel, 0.0)
    tiny = 1e-12 * np.maximum(travel.sum(-1, keepdims=True), 1e-300)
    return np.where(np.isfinite(seg_start), np.maximum(travel, tiny), 0.0)


REFINE_GRIDS = (8 * GRID, 64 * GRID)
_take = crossings.take_rows


def _subset(
    params: Mapping[str, ArrayLike], points: frozenset[str], shape: tuple[int, ...], mask: Flags
) -> dict[str, Array]:
    """The parameters of the linkages selected by ``mask`` (a boolean array of batch shape)."""
    # Boolean indexing takes the selected linkages in row-major order, as flatnonzero does.
    return _take(params, points, shape, np.flatnonzero(mask))


def _restrict(motion: Motion, keep: NDArray[np.bool_]) -> Motion:
    valid = motion.valid & keep
    regular = motion.regular & keep

    def mask(d: dict[str, Array], k: Flags) -> dict[str, Array]:
        return {n: np.where(k[..., None], a, np.nan) for n, a in d.items()}

    def mask_rates(d: dict[str, Array] | None) -> dict[str, Array] | None:
        return None if d is None else mask(d, regular)

    return Motion(
        input=motion.input,
        positions=mask(motion.positions, valid),
        velocities=mask_rates(motion.velocities),
        accelerations=mask_rates(motion.accelerations),
        valid=valid,
        regular=regular,
        branches=motion.branches,
        margins=motion.margins,
        labels=motion.labels,
    )

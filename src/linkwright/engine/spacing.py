"""Where a circuit's samples go: shared between its segments, spaced by input or along paths.

:func:`sample_segments` spreads the samples evenly in the input, sin²-warped next to limit
positions (``spacing="input"``); :func:`path_samples` advances every moving joint in even steps
along its own path, with the bound :func:`~linkwright.engine.circuits.trace` states
(``spacing="path"``). Both share the samples between segments by largest remainder, each
segment keeping its start (a limit position or a crossing) as an exact sample.

Its own room (split from :mod:`linkwright.engine.circuits`): the segments are given (by the
closed form or :mod:`~linkwright.engine.circuit_walk`); this module only decides the inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.evaluate import evaluate
from linkwright.engine.plan import Fixed, Plan

__all__ = [
    "JUMP",
    "MOVING",
    "NOISE",
    "PATH_CHUNK",
    "PATH_LEVELS",
    "PATH_PILOT",
    "PATH_STEP",
    "STILL",
    "path_samples",
    "sample_segments",
]

Array = NDArray[np.float64]
Ints = NDArray[np.int64]
Flags = NDArray[np.bool_]
Params = Mapping[str, ArrayLike]
Scalar = TypeVar("Scalar", bound=np.generic)


def sample_segments(
    seg_start: Array,
    seg_end: Array,
    samples: int,
    code: NDArray[np.int64],
    weight: Array | None = None,
) -> tuple[Array, Ints]:
    """Spread ``samples`` inputs over each linkage's segments, in proportion to their lengths.

    Every segment gets its start (a limit position, or a crossing) as a sample, and the rest are
    shared by largest remainder, ties to the earlier segment, so a sweep up and back down an arc
    puts ``ceil(samples/2)`` samples on the way up. ``code`` says which ends of each segment
    are limit positions (:func:`~linkwright.engine.crossings.warp`); ``weight`` (default: the
    input's travel) is what the samples are shared in proportion to. Linkages without segments
    get NaN inputs.
    """
    length = np.abs(seg_end - seg_start) if weight is None else weight
    seg, first, n, total = _share(length, seg_start, samples)
    a = np.take_along_axis(seg_start, seg, -1)
    b = np.take_along_axis(seg_end, seg, -1)
    k = np.arange(samples)
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = (k - first) / n
        # Between two limit positions the joints move like the square root of the distance to
        # the nearer limit, so even steps of the input would crowd the middle of the curve and
        # leave long chords at its ends. sin²(πf/2) spaces the input quadratically at both ends,
        # which makes the steps along the curve even there. A full turn has no limits: even steps.
        frac = crossings.warp(np.take_along_axis(code, seg, -1), frac)
    theta = a + (b - a) * frac
    theta = np.where(total > 0, theta, np.nan)
    return theta, seg


def _share(length: Array, seg_start: Array, samples: int) -> tuple[Ints, Ints, Ints, Array]:
    """Share ``samples`` between segments in proportion to ``length``; each real one gets its start.

    Returns, per sample, its segment, the index of that segment's first sample and the
    segment's sample count, and per linkage the total length (0: no segments, no samples).
    """
    length = np.where(np.isfinite(length), length, 0.0)
    # An arc shrunk to a point (a linkage just touching its limit) still has its segments, all
    # at that one position: share the samples between them as if they were equal.
    point = (length.sum(-1, keepdims=True) == 0) & np.isfinite(seg_start)
    length = np.where(point, 1.0, length)
    total = length.sum(-1, keepdims=True)
    # Every segment first gets its start, however short: a segment without a sample would drop
    # the branch change it carries, and the curve would jump across it.
    real = length > 0
    base = real.astype(np.int64)
    base = np.where(base.sum(-1, keepdims=True) <= samples, base, 0)
    spare = samples - base.sum(-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total > 0, spare * length / total, 0.0)
    count = np.floor(share).astype(np.int64)
    left = spare - count.sum(-1, keepdims=True)
    frac = share - count
    s = seg_start.shape[-1]
    # Rank segments by remainder (descending), the earlier first among equals.
    rank = np.argsort(np.argsort(-frac, axis=-1, kind="stable"), axis=-1, kind="stable")
    count = base + count + ((rank < left) & real)
    bounds = np.cumsum(count, -1)
    k = np.arange(samples)
    seg = np.minimum(np.sum(k[..., None] >= bounds[..., None, :], axis=-1), s - 1)
    first = np.take_along_axis(bounds - count, seg, -1)
    n = np.take_along_axis(count, seg, -1)
    return seg, first, n, total


# spacing="path": pilot intervals per segment (at least; one per sample otherwise), the largest
# grid cell as a share of the mean step (τ: it sets the bound's c = n/(n − S) + 2τ), bisection
# levels (from a pilot cell down to a few ulps of input is about 50), linkages per chunk (the
# refined grids hold a few thousand nodes per linkage), and the rounding floors: joints moving
# less than STILL of the longest path or MOVING of the linkage's size stand still, chords below
# NOISE of the size are not bisected, and a cell bisected to the last bits that still moves a
# joint by more than JUMP mean steps is a discontinuity.
PATH_PILOT = 64
PATH_STEP = 0.25
PATH_LEVELS = 60
PATH_CHUNK = 256
STILL = 1e-9
MOVING = 1e-6
NOISE = 1e-7
JUMP = 2.0


def path_samples(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    seg_start: Array,
    seg_end: Array,
    seg_branches: Mapping[str, Array],
    samples: int,
    code: Ints,
    begin: Ints,
    end: Ints,
) -> tuple[Array, Ints]:
    """Inputs that advance every moving joint in even steps along its own path.

    Each segment is parametrised by f ∈ [0, 1] as ``a + (b − a)·g(f)``, g the sin² warp next to
    limits (where the joints then move about linearly in f; ``code``, see
    :func:`~linkwright.engine.crossings.warp`) and the identity elsewhere. Ends at a crossing
    (``begin``/``end``) are placed as their limits. A
    pilot grid of ``max(PATH_PILOT, samples)`` intervals per segment is bisected, level by level
    and for the whole batch in one evaluation per level, until no interval's *measure* exceeds
    ``PATH_STEP`` of the mean step M/n. The measure of an interval is the largest, over the
    moving joints, of the chord divided by that joint's path length: the largest displacement,
    each joint in units of its own path, so that a joint with a short path is stepped as evenly
    as one with a long path (a plain largest displacement would let the longest path set the
    step of all, and a sum would dilute it by the number of joints). Samples are then shared
    between segments by measure (each keeps its start, a limit position, as an exact sample)
    and placed at equal measure within each, inverting the cumulative measure by linear
    interpolation in f: monotone in each segment.

    Bisection stops at a few ulps of input (``stuck``); see :func:`_measure` for what such an
    interval then counts as. A linkage's samples do not depend on the batch it comes in.
    """
    shape = seg_start.shape[:-1]
    s = seg_start.shape[-1]
    size = int(np.prod(shape, dtype=np.int64))
    a = seg_start.reshape(size, s)
    b = seg_end.reshape(size, s)
    warps = np.broadcast_to(code, shape + (s,)).reshape(size, s)
    ends = (begin.reshape(size, s), end.reshape(size, s))
    br = {k: np.nan_to_num(v, nan=1.0).reshape(size, s) for k, v in seg_branches.items()}
    joints = [step.name for step in plan.steps if not isinstance(step, Fixed)]
    theta = np.full((size, samples), np.nan)
    seg = np.zeros((size, samples), dtype=np.int64)
    todo = np.flatnonzero(np.isfinite(a).any(-1))
    # Chunks of linkages bound the memory of the refined grids (a few thousand nodes each).
    for lo in range(0, todo.size, PATH_CHUNK):
        rows = todo[lo : lo + PATH_CHUNK]
        theta[rows], seg[rows] = _path_chunk(
            plan,
            _take(params, points, shape, rows),
            points,
            joints,
            a[rows],
            b[rows],
            {k: v[rows] for k, v in br.items()},
            warps[rows],
            samples,
            (ends[0][rows], ends[1][rows]),
        )
    return theta.reshape(shape + (samples,)), seg.reshape(shape + (samples,))


_take = crossings.take_rows


def _path_chunk(
    plan: Plan,
    params: Mapping[str, Array],
    points: frozenset[str],
    joints: list[str],
    a: Array,
    b: Array,
    br: Mapping[str, Array],
    warps: Ints,
    samples: int,
    ends: tuple[Ints, Ints],
) -> tuple[Array, Ints]:
    """:func:`path_samples` for a flat batch ``(m,)`` with segments ``(m, S)``."""
    m, s = a.shape
    af, bf, warp = a.ravel(), b.ravel(), warps.ravel()
    begin, end = (e.ravel() for e in ends)
    flat_br = {k: v.ravel() for k, v in br.items()}

    def inputs(o: Ints, x: Array) -> Array:
        g = crossings.warp(warp[o], x)
        # A segment's far end exactly (a crossing placed there is the limit at that input).
        return np.where(x == 1.0, bf[o], af[o] + (bf[o] - af[o]) * g)

    def place(o: Ints, x: Array) -> dict[str, Array]:
        # One evaluation for every node asked for, each node a linkage of its own.
        rows = o // s
        one = np.zeros((o.size, 1), dtype=np.int64)
        on = crossings.flags(
            plan,
            begin[o][:, None],
            end[o][:, None],
            af[o][:, None],
            bf[o][:, None],
            one,
            (x == 0.0)[:, None],
            (x == 1.0)[:, None],
        )
        motion = evaluate(
            plan,
            {k: v[rows] for k, v in params.items()},
            inputs(o, x)[:, None],
            points=points,
            branches={k: v[o][:, None] for k, v in flat_br.items()} or None,
            order=0,
            crossings=on,
        )
        return {k: v[:, 0] for k, v in motion.positions.items()}

    owners = np.flatnonzero((np.isfinite(a) & np.isfinite(b)).ravel())
    own, f, pos, stuck, size = _refine(inputs, place, joints, owners, m, s, samples)
    measure, open_, _ = _measure(own, pos, stuck, m, s, size, samples)
    weight = np.where(open_ & np.isfinite(measure), measure, 0.0)
    # Cumulative measure at each node, from 0 at its segment's start: summed segment by
    # segment, so that a linkage's samples do not depend on the batch it comes in.
    cum = np.zeros(own.size)
    first = np.flatnonzero(np.concatenate(([True], own[1:] != own[:-1])))
    for lo, hi in zip(first, np.append(first[1:], own.size), strict=True):
        np.cumsum(weight[lo : hi - 1], out=cum[lo + 1 : hi])
    last = np.concatenate((own[1:] != own[:-1], [True]))
    travel = np.zeros(m * s)
    travel[own[last]] = cum[last]
    travel = travel.reshape(m, s)
    real = np.isfinite(a) & np.isfinite(b)
    tiny = 1e-12 * np.maximum(travel.sum(-1, keepdims=True), 1e-300)
    seg, first_k, count, total = _share(np.where(real, np.maximum(travel, tiny), 0.0), a, samples)
    q = (np.arange(samples) - first_k).ravel()
    count = count.ravel()
    target_owner = (np.arange(m)[:, None] * s + seg).ravel()
    seg_travel = travel.ravel()[target_owner]
    target = q * (seg_travel / count)
    # The last node at or below each target in its segment: merge nodes and targets in one
    # sort by (segment, cumulative measure), nodes first among equals.
    n_nodes = own.size
    order = np.lexsort(
        (
            np.concatenate((np.zeros(n_nodes, np.int8), np.ones(target.size, np.int8))),
            np.concatenate((cum, target)),
            np.concatenate((own, target_owner)),
        )
    )
    below = np.maximum.accumulate(np.where(order < n_nodes, order, -1))
    at = np.empty(target.size, dtype=np.int64)
    at[order[order >= n_nodes] - n_nodes] = below[order >= n_nodes]
    nxt = np.minimum(at + 1, n_nodes - 1)
    inside = (at >= 0) & (nxt > at) & (own[np.maximum(at, 0)] == target_owner)
    inside &= own[nxt] == target_owner
    at = np.where(inside, at, 0)
    nxt = np.where(inside, nxt, 0)
    rise = cum[nxt] - cum[at]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.clip((target - cum[at]) / rise, 0.0, 1.0)
    # A segment along which nothing moves (an arc shrunk to a point) is sampled evenly in f.
    x = np.where(inside & (rise > 0) & (seg_travel > 0), f[at] + (f[nxt] - f[at]) * frac, q / count)
    theta = inputs(target_owner, np.where(q == 0, 0.0, x))
    # A segment's first sample is its start, bit for bit: a limit position, exactly.
    theta = np.where(q == 0, af[target_owner], theta).reshape(m, samples)
    return np.where(total > 0, theta, np.nan), seg


def _refine(
    inputs: Callable[[Ints, Array], Array],
    place: Callable[[Ints, Array], dict[str, Array]],
    joints: list[str],
    owners: Ints,
    m: int,
    s: int,
    samples: int,
) -> tuple[Ints, Array, Array, Flags, Array]:
    """The pilot grid of every segment (``owners``, index l·S + s), bisected where it is coarse.

    Returns the nodes sorted by segment and f: their segment, f, positions (joint, node,
    coordinate) and whether the cell they start was bisected to the last bits; and each
    linkage's size (its largest joint distance, for the rounding floors).
    """
    # The pilot: a node per sample already, the rest where the motion asks for them.
    grid = np.linspace(0.0, 1.0, max(PATH_PILOT, samples) + 1)
    own = np.repeat(owners, grid.size)
    f = np.tile(grid, owners.size)
    every = place(own, f)
    pos = np.stack([every[j] for j in joints])
    ref = next(iter(every.values()))
    spread = np.max([np.linalg.norm(p - ref, axis=-1) for p in every.values()], axis=0)
    size = np.zeros(m)
    np.fmax.at(size, own // s, spread)
    stuck = np.zeros(own.size, dtype=bool)
    done = []
    for level in range(PATH_LEVELS + 1):
        split = _splits(own, pos, stuck, m, s, size, samples)
        if level == PATH_LEVELS:
            split[:] = False
        # A linkage with nothing left to split is finished: set its nodes aside.
        busy = np.zeros(m, dtype=bool)
        busy[own[:-1][split] // s] = True
        keep = busy[own // s]
        if not keep.all():
            done.append((own[~keep], f[~keep], pos[:, ~keep], stuck[~keep]))
            own, f, pos, stuck = own[keep], f[keep], pos[:, keep], stuck[keep]
            # A split interval lies within one busy linkage: its left node is kept, and so is
            # its right neighbour.
            split = np.append(split, False)[keep][:-1]
        if not own.size:
            break
        i = np.flatnonzero(split)
        mid = 0.5 * (f[i] + f[i + 1])
        t0, t1, tm = inputs(own[i], f[i]), inputs(own[i], f[i + 1]), inputs(own[i], mid)
        floor = 4.0 * np.spacing(np.maximum(np.maximum(np.abs(t0), np.abs(t1)), 1.0))
        can = (np.abs(t1 - t0) > floor) & ((tm - t0) * (t1 - tm) > 0.0)
        stuck[i[~can]] = True
        i, mid = i[can], mid[can]
        if i.size:
            new = place(own[i], mid)
            # Each midpoint right after its interval's left node: the order stays sorted.
            before = np.zeros(own.size, dtype=np.int64)
            before[i + 1] = 1
            old_at = np.arange(own.size) + np.cumsum(before)
            new_at = i + 1 + np.arange(i.size)
            own = _interleave(own, own[i], old_at, new_at)
            f = _interleave(f, mid, old_at, new_at)
            pos = _interleave(pos, np.stack([new[j] for j in joints]), old_at, new_at, axis=1)
            stuck = _interleave(stuck, np.zeros(i.size, dtype=bool), old_at, new_at)
    done.append((own, f, pos, stuck))
    own, f, stuck = (np.concatenate([d[k] for d in done]) for k in (0, 1, 3))
    pos = np.concatenate([d[2] for d in done], axis=1)
    order = np.lexsort((f, own))
    return own[order], f[order], pos[:, order], stuck[order], size


def _interleave(
    old: NDArray[Scalar], new: NDArray[Scalar], old_at: Ints, new_at: Ints, axis: int = 0
) -> NDArray[Scalar]:
    """``old`` and ``new`` merged into one array, their elements at ``old_at`` and ``new_at``."""
    shape = list(old.shape)
    shape[axis] += new.shape[axis]
    out = np.empty(shape, dtype=old.dtype)
    index: list[slice | Ints] = [slice(None)] * old.ndim
    index[axis] = old_at
    out[tuple(index)] = old
    index[axis] = new_at
    out[tuple(index)] = new
    return out


def _splits(
    own: Ints, pos: Array, stuck: Flags, m: int, s: int, size: Array, samples: int
) -> Flags:
    """Which intervals (by their left node) still need bisecting."""
    measure, open_, big = _measure(own, pos, stuck, m, s, size, samples)
    good = open_ & np.isfinite(measure)
    row = own[:-1] // s
    total = np.bincount(row, np.where(good, measure, 0.0), minlength=m)
    # An interval with one unassembled end is bisected down to the singular input itself. One
    # with both ends unassembled (inside a gap the walk stepped over) holds no motion to place
    # samples on: bisecting it would only double the nodes at every level.
    placed = np.asarray(np.isfinite(pos).all(axis=(0, 2)))
    edge = placed[:-1] != placed[1:]
    split: Flags = (open_ & ~good & edge) | (
        good & big & (measure > PATH_STEP * total[row] / samples)
    )
    return split & ~stuck[:-1]


def _measure(
    own: Ints, pos: Array, stuck: Flags, m: int, s: int, size: Array, samples: int
) -> tuple[Array, Flags, Flags]:
    """Each interval's measure (NaN where an end is unassembled), whether it counts (not a jump
    nor the gap between two segments), and whether it moves a joint above the rounding floor.

    The measure of an interval is the largest chord of a moving joint over it divided by the
    joint's path length (the sum of its chords over the linkage's intervals that count). A joint
    moves if its path is longer than ``STILL`` of the longest and than ``MOVING`` of the
    linkage's size; chords up to ``NOISE`` of the size are rounding (near a limit a dyad's
    joint is known only to about √ε of its link) and are not bisected. An interval bisected to
    the last bits (``stuck``) is a jump if it still moves a joint by more than ``JUMP`` mean
    steps (of a circuit with M = 1), or has an unassembled end; below that it is motion that
    rounding blurs (A a few hundred ulps from B0), and counts.
    """
    same = own[1:] == own[:-1]
    step = np.diff(pos, axis=1)
    chord = np.sqrt(np.einsum("jnk,jnk->jn", step, step))  # (joint, interval)
    row = own[:-1] // s

    def relative(open_: Flags) -> tuple[Array, Flags]:
        counted = open_ & np.isfinite(chord)
        travel = np.stack([np.bincount(row, w, minlength=m) for w in np.where(counted, chord, 0.0)])
        moving = travel > np.maximum(STILL * travel.max(axis=0), MOVING * size)
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(moving[:, row], chord / travel[:, row], 0.0)
        return rel.max(axis=0), moving

    open_ = same
    if stuck.any():
        first, _ = relative(same)
        open_ = same & ~(stuck[:-1] & ~(first <= JUMP / samples))
    measure, moving = relative(open_)
    big = np.where(moving[:, row], chord, 0.0).max(axis=0) > NOISE * size[row]
    return measure, open_, big

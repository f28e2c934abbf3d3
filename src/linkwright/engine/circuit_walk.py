"""The walk along a circuit of several dyads: from limit to limit and crossing to crossing.

Where more than one dyad can reach its limit, a circuit is found by running the machine: the
input runs from an arc's end until some dyad reaches its limit (scanned on a grid and bisected
to the last bit, :func:`~linkwright.engine.limit_search.bisect_brackets`), reverses there with
that dyad on its other branch, and so on until the linkage is back where it started. Crossings
(:mod:`~linkwright.engine.crossings`) change a branch without reversing the input.

Its own room (split from :mod:`linkwright.engine.circuits`): the walk is the one part of
tracing that follows a linkage step by step; where the samples then go is
:mod:`~linkwright.engine.spacing`'s.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arcs import TWO_PI
from linkwright.engine.crossings import LIMIT, PLAIN, Segments
from linkwright.engine.limit_search import GRID, assembled, bisect_brackets
from linkwright.engine.plan import Plan

__all__ = ["MAX_SEGMENTS", "SCAN_CHUNK", "SCAN_NUMBERS", "walk_circuit"]

Array = NDArray[np.float64]
Flags = NDArray[np.bool_]
MAX_SEGMENTS = 32
SCAN_CHUNK = 240
# A small batch scans in longer chunks (a call costs about as much as 300 samples of a six-bar
# on the sphere): up to this many samples a call.
SCAN_NUMBERS = 2880


def walk_circuit(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    points: frozenset[str],
    theta0: Array,
    doc: Mapping[str, Array],
    period: Array,
    usable: Flags,
    grid: int = GRID,
    first: NDArray[np.int64] | None = None,
) -> Segments:
    """Follow each linkage from ``theta0`` on its document branches until it closes.

    At a limit position the dyad there changes branch and the input reverses; at a crossing
    (:mod:`~linkwright.engine.crossings`) the dyad changes branch and the input runs on. After
    a crossing a walk also stops at each turn's return to ``theta0``, to see whether it is home.
    ``first`` says what ``theta0`` is (``PLAIN``, or ``LIMIT`` at an arc's end).

    Returns the segments' starts, ends and per-dyad branches, and what each begins and ends at
    (``PLAIN``, ``LIMIT`` or a crossing's dyad index), shape ``batch + (S,)``, NaN-padded.
    """
    dyads = plan.dyads
    theta = theta0.astype(float).copy()
    direction = np.ones(theta.shape)
    branches = {k: v.copy() for k, v in doc.items()}
    active = usable.copy()
    crossed = np.zeros(theta.shape, dtype=bool)
    kind = np.broadcast_to(PLAIN if first is None else first, theta.shape).astype(np.int64)
    # A walk that starts on a crossing (an arc's end there, with a later dyad failing past it
    # on the sign held) starts as its limit there: the machine runs through it.
    on = crossings.starts_on(plan, params, points, theta, doc)
    kind = np.where(on >= 0, on, kind)
    turns = np.rint(period / TWO_PI)
    cells = grid * int(turns.max()) if turns.size else grid
    starts, ends, snaps, begins, finishes = [], [], [], [], []
    for _ in range(MAX_SEGMENTS):
        if not active.any():
            break
        end, which, hit = _next_limit(
            plan, params, points, theta, direction, branches, period, grid
        )
        seg_end = np.where(hit, end, theta + direction * period)
        # A crossing before the limit (or, with none, up to just past a turn: one may sit
        # exactly a turn on).
        reach = np.where(hit, end, seg_end + direction * (2.0 * period / cells))
        cross, cross_k = crossings.crossings_within(
            plan, params, points, np.where(active, theta, np.nan), reach, cells + 2, branches
        )
        cross, cross_k = cross[..., 0], cross_k[..., 0]
        at_cross = active & np.isfinite(cross)
        at_cross &= ~hit | ((cross - end) * direction < crossings.EXCLUDE)
        seg_end = np.where(at_cross, cross, seg_end)
        # Back at the start of a turn after a crossing: home, or on round again.
        again = theta0 + period * (np.floor((theta - theta0) / period + 1e-9) + 1.0)
        lap = active & crossed & (direction > 0) & ((again - seg_end) * direction < 0.0)
        seg_end = np.where(lap, again, seg_end)
        limit = hit & ~at_cross & ~lap
        starts.append(np.where(active, theta, np.nan))
        ends.append(np.where(active, seg_end, np.nan))
        snaps.append({k: v.copy() for k, v in branches.items()})
        begins.append(kind.copy())
        kind = np.where(limit, LIMIT, np.where(at_cross & ~lap, cross_k, PLAIN))
        finishes.append(kind.copy())
        flip = active & limit
        cut = active & at_cross & ~lap
        for i, d in enumerate(dyads):
            turn = (flip & (which == i)) | (cut & (cross_k == i))
            branches[d.name] = np.where(turn, -branches[d.name], branches[d.name])
        direction = np.where(flip, -direction, direction)
        crossed |= cut
        theta = np.where(active, seg_end, theta)
        gap = np.abs(np.remainder(theta - theta0 + 0.5 * period, period) - 0.5 * period)
        home = (gap <= 1e-9 * period) & (direction > 0)
        for k in branches:
            home &= branches[k] == doc[k]
        active = active & (limit | cut | crossed) & ~home
    if not starts:  # nothing in the batch assembles: no segments at all
        nan = np.full(theta.shape + (1,), np.nan)
        plain = np.full(theta.shape + (1,), PLAIN)
        return (
            nan,
            nan.copy(),
            {k: np.full(theta.shape + (1,), np.nan) for k in doc},
            plain,
            plain.copy(),
        )
    # A walk that does not close within MAX_SEGMENTS is not a circuit we can vouch for.
    failed = active
    seg_start = np.stack(starts, -1)
    seg_end = np.stack(ends, -1)
    seg_start = np.where(failed[..., None], np.nan, seg_start)
    seg_branches = {k: np.stack([s[k] for s in snaps], -1) for k in doc}
    return seg_start, seg_end, seg_branches, np.stack(begins, -1), np.stack(finishes, -1)


def _next_limit(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    points: frozenset[str],
    theta: Array,
    direction: Array,
    branches: Mapping[str, Array],
    period: Array,
    grid: int = GRID,
) -> tuple[Array, NDArray[np.int64], Flags]:
    """The first limit position met going from ``theta`` in ``direction``, within one period.

    Scans the assembly predicate on the branches given in steps of one grid cell, then bisects
    the first failing cell to the last bit. Returns the limit (the assembled end), the index of
    the dyad at its limit there, and whether a limit was met at all.
    """
    shape = theta.shape
    turns = np.rint(period / TWO_PI)
    nodes = grid * int(turns.max()) if turns.size else grid
    step = direction * period / nodes
    br = {k: v[..., None] for k, v in branches.items()}
    found = np.zeros(shape, dtype=bool)
    a = np.full(shape, np.nan)
    b = np.full(shape, np.nan)
    chunk = max(SCAN_CHUNK, SCAN_NUMBERS // max(theta.size, 1))
    for c0 in range(1, nodes + 1, chunk):
        j = np.arange(c0, min(c0 + chunk, nodes + 1))
        th = theta[..., None] + step[..., None] * j
        ok, _ = assembled(plan, params, points, th, br)
        ok = np.broadcast_to(ok, th.shape)
        bad = ~ok
        first = np.argmax(bad, axis=-1)
        new = bad.any(-1) & ~found
        b = np.where(new, np.take_along_axis(th, first[..., None], -1)[..., 0], b)
        prev = theta + step * (c0 + first - 1)
        a = np.where(new, prev, a)
        found |= new
        if found.all():
            break
    a = np.where(found, a, theta)
    b = np.where(found, b, theta)

    def go_right(mid: Array) -> NDArray[np.bool_]:
        ok, _ = assembled(plan, params, points, mid, br)
        return np.broadcast_to(ok, mid.shape)

    a, b = bisect_brackets(a, b, go_right)
    _, margins = assembled(plan, params, points, a[..., None], br)
    which = np.argmin(margins[..., 0, :], axis=-1)
    return a, np.broadcast_to(which, shape), found

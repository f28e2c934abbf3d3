"""Limit positions of the input: bracketed and bisected to the last bit, or in closed form.

A dyad closes while a *closure quantity* q of its parents lies between two thresholds: the
squared distance between its pivots for an RRR dyad, in [(r1 − r2)², (r1 + r2)²], and the signed
distance of its pivot from the guide for an RRP dyad, in [−r, r]. Limit positions of the input
are the roots of q − threshold, i.e. of the dyad's discriminant.

Where every parent of the (single) dyad is a ground pivot or a joint on a crank turning with the
input (ratio 1), q is exactly ``c0 + c1·cos θ + c2·sin θ`` and the limits are closed-form
arc-cosines (:func:`analytic_arcs`). Otherwise they are bracketed on a grid of the assembly
predicate and bisected to the last bit (:func:`numeric_arcs`). Either way a limit is a root, not
the nearest sample.

Its own room (split from :mod:`linkwright.engine.circuits`): how one limit is found, apart from
what is done with the limits (the arcs of :mod:`~linkwright.engine.arc_search`, the walk of
:mod:`~linkwright.engine.circuit_walk`, the samples of :mod:`~linkwright.engine.circuits`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arcs import TWO_PI, InputArcs
from linkwright.engine.evaluate import batch_shape, place_all
from linkwright.engine.plan import Crank, DyadRRP, DyadRRR, Fixed, JointState, Param, Plan
from linkwright.geometry import plane

__all__ = [
    "BISECTIONS",
    "GRID",
    "SNAP_STEPS",
    "TREE_LEVELS",
    "TREE_NUMBERS",
    "analytic_arcs",
    "assembled",
    "bisect_brackets",
    "normalised_arcs",
    "numeric_arcs",
    "turning_form",
    "turns_with_input",
]

Array = NDArray[np.float64]
Flags = NDArray[np.bool_]
Complex = NDArray[np.complex128]
Params = Mapping[str, ArrayLike]
Branches = Mapping[str, ArrayLike] | None
GRID = 1440
BISECTIONS = 64
# Bisection steps taken per evaluation, where the batch is small: the 2^L − 1 midpoints the
# next L steps can visit are evaluated in one call (a call costs far more than a sample), and
# the steps are then taken as one at a time would take them, bit for bit.
TREE_LEVELS = 6
TREE_NUMBERS = 1024


def bisect_brackets(
    a: Array, b: Array, go_right: Callable[[Array], Flags], steps: int = BISECTIONS
) -> tuple[Array, Array]:
    """``steps`` bisections of the brackets ``[a, b]``: at each, ``mid = (a + b)/2`` replaces
    ``a`` where ``go_right(mid)`` holds, else ``b``. ``go_right`` takes midpoints with one more
    axis (the candidates of every bracket) and answers for each."""
    levels = 1
    while levels < TREE_LEVELS and max(a.size, 1) * (2 ** (levels + 1) - 1) <= TREE_NUMBERS:
        levels += 1
    done = 0
    while done < steps:
        depth = min(levels, steps - done)
        # Every bracket the next `depth` steps can reach, level by level; a node's children are
        # its left half (2i) and its right half (2i + 1).
        lo, hi = a[..., None], b[..., None]
        mids = []
        for _ in range(depth):
            m = 0.5 * (lo + hi)
            mids.append(m)
            lo = np.stack((lo, m), -1).reshape(m.shape[:-1] + (2 * m.shape[-1],))
            hi = np.stack((m, hi), -1).reshape(lo.shape)
        right = go_right(np.concatenate(mids, -1))
        node = np.zeros(a.shape, dtype=np.int64)
        offset = 0
        for d, m in enumerate(mids):
            mid = np.take_along_axis(m, node[..., None], -1)[..., 0]
            r = np.take_along_axis(right[..., offset : offset + 2**d], node[..., None], -1)[..., 0]
            a = np.where(r, mid, a)
            b = np.where(r, b, mid)
            node = 2 * node + r
            offset += 2**d
        done += depth
        # Brackets down to adjacent floats (or NaN): every later midpoint is one of the two
        # ends, so the side of each end, asked once, decides all the remaining steps.
        mid = 0.5 * (a + b)
        if done < steps and np.all((mid == a) | (mid == b) | np.isnan(mid)):
            ends = go_right(np.stack((a, b), -1))
            lo, at_lo, at_hi = a, ends[..., 0], ends[..., 1]
            for _ in range(steps - done):
                mid = 0.5 * (a + b)
                r = np.where(mid == lo, at_lo, at_hi)
                a = np.where(r, mid, a)
                b = np.where(r, b, mid)
            break
    return a, b


def _is_ground(plan: Plan, name: str) -> bool:
    return isinstance(plan.step(name), Fixed)


def turns_with_input(plan: Plan, name: str, params: Params | None = None) -> bool:
    """A ground pivot, or a joint on a ground crank turning one-for-one with the input.

    The ratio may be a constant or a named parameter that is 1 for the whole batch.
    """
    step = plan.step(name)
    if isinstance(step, Fixed):
        return True
    if not isinstance(step, Crank) or not _is_ground(plan, step.pivot):
        return False
    ratio = step.ratio
    if isinstance(ratio, str):
        return params is not None and bool(np.all(np.asarray(params[ratio]) == 1.0))
    return ratio == 1.0


def _closure(
    plan: Plan,
    dyad: DyadRRR | DyadRRP,
    states: Mapping[str, JointState],
    params: Params,
    points: frozenset[str],
) -> Array:
    """The dyad's closure quantity q from its parents' (unmasked) positions."""
    if isinstance(dyad, DyadRRR):
        delta = states[dyad.p2].pos - states[dyad.p1].pos
        return plane.dot(delta, delta)
    ang = np.asarray(
        params[dyad.line_angle] if isinstance(dyad.line_angle, str) else dyad.line_angle, float
    )[..., None]
    normal = np.stack(np.broadcast_arrays(-np.sin(ang), np.cos(ang)), axis=-1)
    return plane.dot(states[dyad.p1].pos - states[dyad.line_point].pos, normal)


def _thresholds(dyad: DyadRRR | DyadRRP, params: Params) -> tuple[Array, Array]:
    def val(p: Param) -> Array:
        return np.asarray(params[p] if isinstance(p, str) else p, dtype=float)

    if isinstance(dyad, DyadRRR):
        r1, r2 = val(dyad.r1), val(dyad.r2)
        return (r1 - r2) ** 2, (r1 + r2) ** 2
    r = val(dyad.r)
    return -r, r


def turning_form(plan: Plan, name: str, params: Params) -> tuple[Complex, Complex | np.complex128]:
    """A ground pivot or crank joint as ``O + w·e^{iθ}`` (complex): its pivot O and arm w."""
    step = plan.step(name)
    arm: Complex | np.complex128
    if isinstance(step, Fixed):
        pivot, arm = step.at, np.complex128(0.0)
    else:
        # turns_with_input admits only ground pivots and the cranks turning on them.
        assert isinstance(step, Crank)
        ground = plan.step(step.pivot)
        assert isinstance(ground, Fixed)
        pivot = ground.at
        length = np.asarray(params[step.length] if isinstance(step.length, str) else step.length)
        phase = np.asarray(params[step.phase] if isinstance(step.phase, str) else step.phase)
        arm = length * np.exp(1j * phase)
    o = np.asarray(params[pivot], dtype=float)
    return o[..., 0] + 1j * o[..., 1], arm


def analytic_arcs(plan: Plan, params: Params, points: frozenset[str]) -> InputArcs:
    """Closed-form arcs from q(θ) = c0 + amp·cos(θ − ψ), in half-angle form.

    The arc ends are ``ψ ± a_in`` (where q reaches its upper threshold) and ``ψ ± a_out`` (its
    lower one), with ``sin²(a_in/2) = s_hi`` and ``cos²(a_out/2) = c_lo``. For an RRR dyad both
    come as products of differences of the lengths themselves, q(θ) = (a + b)² − 4ab·sin²(x/2)
    = (a − b)² + 4ab·cos²(x/2) with a = |pivot difference| and b = |arm difference|: no
    cancellation between the large c0 and a small threshold, and no rounding from the
    placement of the frame, so a limit is as exact as its data allow.
    """
    (dyad,) = plan.dyads
    assert isinstance(dyad, DyadRRR | DyadRRP)  # the closed form is planar (search_input_arcs)
    t_lo, t_hi = _thresholds(dyad, params)
    if isinstance(dyad, DyadRRR):
        o1, w1 = turning_form(plan, dyad.p1, params)
        o2, w2 = turning_form(plan, dyad.p2, params)
        big, arm = o2 - o1, w2 - w1
        a, b = np.abs(big), np.abs(arm)
        psi = np.angle(big) - np.angle(arm)  # q is largest where the two line up
        c0, amp = a * a + b * b, 2.0 * a * b
        r1, r2 = (np.asarray(params[r] if isinstance(r, str) else r) for r in (dyad.r1, dyad.r2))
        outer, inner = r1 + r2, np.abs(r1 - r2)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_hi = (a + b - outer) * (a + b + outer) / (2.0 * amp)
            c_lo = (inner - np.abs(a - b)) * (inner + np.abs(a - b)) / (2.0 * amp)
    else:
        _, states = place_all(
            plan, params, np.array([0.0, 0.5 * np.pi, np.pi]), points=points, order=0
        )
        q = _closure(plan, dyad, states, params, points)
        c0 = 0.5 * (q[..., 0] + q[..., 2])
        c1 = 0.5 * (q[..., 0] - q[..., 2])
        c2 = q[..., 1] - c0
        amp = np.hypot(c1, c2)
        psi = np.arctan2(c2, c1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_hi = (amp - (t_hi - c0)) / (2.0 * amp)  # need sin²((θ − ψ)/2) ≥ s_hi
            c_lo = (amp + (t_lo - c0)) / (2.0 * amp)  # and cos²((θ − ψ)/2) ≥ c_lo
    t_lo, t_hi, psi, s_hi, c_lo = np.broadcast_arrays(t_lo, t_hi, psi, s_hi, c_lo)
    flat = amp <= 1e-15 * np.maximum(np.abs(c0), np.abs(t_hi))
    const_ok = (c0 >= t_lo) & (c0 <= t_hi)
    if isinstance(dyad, DyadRRR):
        # Pivots that coincide at every input (equal cranks on one pivot, in phase) leave the
        # dyad undefined everywhere: it never assembles, whatever the thresholds.
        const_ok = const_ok & (c0 > 0.0)
    # Where q is flat the half-angle ratios divide by amp = 0 (±inf, or NaN for 0/0) and mean
    # nothing: the flat test decides there, and adding +inf to −inf would warn.
    s_hi, c_lo = np.where(flat, 0.0, s_hi), np.where(flat, 0.0, c_lo)
    never = np.where(flat, ~const_ok, (s_hi > 1.0) | (c_lo > 1.0) | (s_hi + c_lo > 1.0))
    full = np.where(flat, const_ok, (s_hi <= 0.0) & (c_lo <= 0.0))
    a_in = 2.0 * np.arcsin(np.sqrt(np.clip(s_hi, 0.0, 1.0)))  # |θ − ψ| ≥ a_in
    a_out = 2.0 * np.arccos(np.sqrt(np.clip(c_lo, 0.0, 1.0)))  # |θ − ψ| ≤ a_out
    shape = full.shape
    lo = np.full(shape + (2,), np.nan)
    hi = np.full(shape + (2,), np.nan)
    partial = ~(never | full)
    one_about_psi = partial & (s_hi <= 0.0)  # only the lower threshold binds
    one_about_opp = partial & (c_lo <= 0.0) & ~one_about_psi
    two = partial & ~one_about_psi & ~one_about_opp
    # Each arc as one end plus a width ≥ 0, so that an arc shrunk to a point (a linkage touching
    # its limit) cannot come out with hi below lo by a rounding.
    lo[..., 0] = np.where(one_about_psi, psi - a_out, np.where(one_about_opp, psi + a_in, np.nan))
    hi[..., 0] = np.where(
        one_about_psi,
        psi + a_out,
        np.where(one_about_opp, lo[..., 0] + (TWO_PI - 2 * a_in), np.nan),
    )
    width = np.maximum(a_out - a_in, 0.0)
    lo[..., 0] = np.where(two, psi + a_in, lo[..., 0])
    hi[..., 0] = np.where(two, psi + a_in + width, hi[..., 0])
    lo[..., 1] = np.where(two, psi - a_in - width, np.nan)
    hi[..., 1] = np.where(two, psi - a_in, np.nan)
    zero = np.zeros(lo.shape, dtype=np.int64)
    arcs = normalised_arcs(full, never, lo, hi, zero, zero)
    # Snap after normalising (a shift by 2π rounds, and the snapped value is the one returned);
    # a start snapped past π is wrapped by normalising again, and snapped again.
    for _ in range(2):
        lo, hi = _snap_inside(plan, params, points, arcs.lo, arcs.hi)
        if not np.any(lo > np.pi):
            return replace(arcs, lo=lo, hi=hi)
        arcs = normalised_arcs(full, never, lo, hi, arcs.dyad_lo, arcs.dyad_hi)
    return arcs


SNAP_STEPS = 60


def _snap_inside(
    plan: Plan, params: Params, points: frozenset[str], lo: Array, hi: Array
) -> tuple[Array, Array]:
    """Move closed-form arc ends that rounding left just outside the assembled set into it.

    The closed form is exact up to rounding, but the engine places the dyad from rounded
    positions; where that noise is larger than the assembly tolerance (a small linkage far from
    the origin, near-change-point proportions) the limit itself would come out unassembled.
    Such ends step toward the arc's other end by steps doubling from two ulps, never past the
    arc's middle, until the linkage is assembled there (``valid``); an end that cannot be moved
    inside is left as computed. Most limits need no step: one evaluation checks them all.
    """
    end = np.concatenate((lo, hi), axis=-1)
    other = np.concatenate((hi, lo), axis=-1)
    theta = end.copy()
    active = np.isfinite(end) & np.isfinite(other)
    direction = np.sign(other - end)
    middle = 0.5 * (end + other)
    step = 2.0 * np.spacing(np.maximum(np.abs(end), 1.0))
    for _ in range(SNAP_STEPS):
        if not active.any():
            break
        _, states = place_all(plan, params, np.where(active, theta, 0.0), points=points, order=0)
        ok = np.logical_and.reduce([states[d.name].valid for d in plan.dyads])
        active = active & ~np.broadcast_to(ok, theta.shape)
        moved = theta + direction * step
        past = active & ((moved - middle) * direction >= 0.0)
        theta = np.where(active & ~past, moved, theta)
        theta = np.where(past, end, theta)
        active = active & ~past
        step = 2.0 * step
    theta = np.where(active, end, theta)
    k = lo.shape[-1]
    return theta[..., :k], theta[..., k:]


def normalised_arcs(
    full: Flags,
    never: Flags,
    lo: Array,
    hi: Array,
    dyad_lo: NDArray[np.int64],
    dyad_hi: NDArray[np.int64],
    period: Array | float = TWO_PI,
) -> InputArcs:
    """Put each arc's start in (−π, −π + period] and order arcs by start; padding last."""
    period = np.asarray(period, dtype=float)
    t = period[..., None] if period.ndim else period
    top = -np.pi + t
    # Starts already in range stay bit-for-bit; a shift rounds, and can land a start on −π or a
    # hair above the top (−π + 1 ulp goes to π + 1 ulp via (lo − π)/2π = −1): one more turn then.
    inside = (lo > -np.pi) & (lo <= top)
    shift = np.where(inside, 0.0, t * np.ceil((lo - top) / t))
    lo, hi = lo - shift, hi - shift
    turn = np.where(lo > top, t, np.where(lo <= -np.pi, -t, 0.0))
    lo, hi = lo - turn, hi - turn
    order = np.argsort(np.where(np.isfinite(lo), lo, np.inf), axis=-1)

    def take(a: NDArray[Any]) -> NDArray[Any]:
        return np.take_along_axis(a, order, -1)

    lo, hi = take(lo), take(hi)
    pad = ~np.isfinite(lo)
    return InputArcs(
        full,
        never,
        lo,
        hi,
        np.where(pad, -1, take(dyad_lo)),
        np.where(pad, -1, take(dyad_hi)),
        period if period.ndim else float(period),
    )


def assembled(
    plan: Plan, params: Params, points: frozenset[str], theta: Array, branches: Branches
) -> tuple[Flags, Array]:
    _, states = place_all(plan, params, theta, points=points, branches=branches, order=0)
    ok: Flags | None = np.ones(np.shape(theta), dtype=bool) if np.ndim(theta) > 1 else None
    margins = []
    for dyad in plan.dyads:
        st = states[dyad.name]
        assert st.margin is not None  # a dyad's state carries its margin
        # The strict sign of the discriminant, not the rounding-tolerant `valid`: bisection must
        # converge on the root itself.
        closes = st.valid & (st.margin >= 0.0)
        # Parents that meet with links allowing it (a crossing): closed, far from a limit.
        meet = crossings.meets(dyad, states, params)
        closes = closes | meet
        ok = closes if ok is None else ok & closes
        margin = np.where(np.isfinite(st.margin), np.abs(st.margin), np.inf)
        margins.append(np.where(meet, 1.0, margin))
    stacked = np.stack(margins, axis=-1)
    assert ok is not None  # set by the first dyad (a plan without one is not searched)
    return ok, stacked


def numeric_arcs(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    branches: Branches,
    grid: int = GRID,
    turns: NDArray[np.int64] | None = None,
) -> InputArcs:
    """Arcs by bracketing the assembly predicate on a grid and bisecting every change.

    The grid covers one period of the input (``turns`` whole turns, ``grid`` nodes per turn).
    """
    shape = batch_shape(params, points)
    turns = np.broadcast_to(np.ones(shape, int) if turns is None else turns, shape)
    period = np.asarray(TWO_PI * turns, dtype=np.float64)
    nodes = grid * int(turns.max()) if turns.size else grid
    frac = np.arange(nodes) / nodes
    theta = -np.pi + period[..., None] * frac
    # The grid's closing node, exactly where the next period starts.
    theta_next = np.concatenate((theta[..., 1:], (-np.pi + period)[..., None]), axis=-1)
    ok, _ = assembled(plan, params, points, theta, branches)
    ok = np.broadcast_to(ok, shape + (nodes,))
    nxt = np.roll(ok, -1, axis=-1)
    change = ok != nxt
    n_change = change.sum(axis=-1)
    kmax = int(n_change.max()) if n_change.size else 0
    # Arrays even for one linkage (where a reduction gives a NumPy scalar), as InputArcs holds.
    full = np.asarray(ok.all(axis=-1))
    never = np.asarray(~ok.any(axis=-1))
    per = period if period.ndim else float(period)
    if kmax == 0:
        nanpad = np.full(shape + (1,), np.nan)
        neg = np.full(shape + (1,), -1)
        return InputArcs(full, never, nanpad, nanpad.copy(), neg, neg.copy(), per)
    # Indices of the grid cells where the predicate changes, padded with the first one.
    idx = np.argsort(~change, axis=-1, kind="stable")[..., :kmax]
    has = np.arange(kmax) < n_change[..., None]
    theta = np.broadcast_to(theta, shape + (nodes,))
    a = np.take_along_axis(theta, idx, -1)
    # The next node itself, not a + step: that can round past it, and a change confined to a
    # node (a joint passing exactly through a pivot) would fall outside its own bracket.
    b = np.take_along_axis(np.broadcast_to(theta_next, shape + (nodes,)), idx, -1)
    entering = ~np.take_along_axis(ok, idx, -1)  # invalid → valid going up

    def go_right(mid: Array) -> NDArray[np.bool_]:
        flat = mid.reshape(mid.shape[:-2] + (-1,))
        ok_mid, _ = assembled(plan, params, points, flat, _expand(branches, flat.shape))
        ok_mid = np.broadcast_to(ok_mid, flat.shape).reshape(mid.shape)
        # Keep the bracket [a, b] with a on the entering side's invalid end.
        return np.where(entering[..., None], ~ok_mid, ok_mid)

    a, b = bisect_brackets(a, b, go_right)
    boundary = np.where(entering, b, a)  # the assembled end of the bracket
    _, margins = assembled(plan, params, points, boundary, _expand(branches, boundary.shape))
    which = np.argmin(margins, axis=-1)
    boundary = np.where(has, boundary, np.nan)
    # Pair each entering boundary with the next leaving one, going up around the circle.
    lo = np.where(has & entering, boundary, np.nan)
    hi_cand = np.where(has & ~entering, boundary, np.nan)
    k = lo.shape[-1]
    hi = np.full(lo.shape, np.nan)
    dyad_hi = np.full(lo.shape, -1)
    t = period[..., None] if period.ndim else period
    for i in range(k):
        gap = (hi_cand - lo[..., i : i + 1]) % t
        gap = np.where(np.isfinite(gap), gap, np.inf)
        j = np.argmin(gap, axis=-1)
        end = np.take_along_axis(hi_cand, j[..., None], -1)[..., 0]
        # The bisected end itself (unrounded by lo + gap), a period up where it lies below lo.
        end = np.where(end > lo[..., i], end, end + period)
        hi[..., i] = np.where(np.isfinite(lo[..., i]), end, np.nan)
        dyad_hi[..., i] = np.take_along_axis(which, j[..., None], -1)[..., 0]
    arcs = normalised_arcs(full, never, lo, hi, np.where(has & entering, which, -1), dyad_hi, per)
    # An end moved by a period (or normalised) is rounded, and where the margin is steep (a
    # spherical linkage with A a hair from B0) an ulp can put it outside: snap it back in.
    lo, hi = _snap_inside(plan, params, points, arcs.lo, arcs.hi)
    if np.any(lo > -np.pi + (period[..., None] if np.ndim(period) else period)):
        arcs = normalised_arcs(full, never, lo, hi, arcs.dyad_lo, arcs.dyad_hi, per)
        lo, hi = _snap_inside(plan, params, points, arcs.lo, arcs.hi)
    return replace(arcs, lo=lo, hi=hi)


def _expand(branches: Branches, shape: tuple[int, ...]) -> dict[str, Array] | None:
    if not branches:
        return None
    return {k: np.broadcast_to(np.asarray(v)[..., :1], shape) for k, v in branches.items()}

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
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arcs import TWO_PI, InputArcs
from linkwright.engine.continuation import Memo, arcs_of, circuit_arcs, every_circuit, memo_key
from linkwright.engine.crossings import LIMIT, PLAIN
from linkwright.engine.evaluate import Motion, batch_shape, evaluate, place_all
from linkwright.engine.plan import Crank, DyadRRP, DyadRRR, Fixed, Plan, SphereCrank
from linkwright.geometry import plane

__all__ = [
    "InputArcs",
    "NoPeriod",
    "input_arcs",
    "input_turns",
    "normalised_arcs",
    "trace",
]

Array = NDArray[np.float64]
GRID = 1440
BISECTIONS = 64
# Bisection steps taken per evaluation, where the batch is small: the 2^L − 1 midpoints the
# next L steps can visit are evaluated in one call (a call costs far more than a sample), and
# the steps are then taken as one at a time would take them, bit for bit.
TREE_LEVELS = 6
TREE_NUMBERS = 1024


def _bisect(a: Array, b: Array, go_right, steps: int = BISECTIONS) -> tuple[Array, Array]:
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


def _turns_with_input(plan: Plan, name: str, params: Mapping | None = None) -> bool:
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


def _closure(plan: Plan, dyad: DyadRRR | DyadRRP, states: Mapping, params, points) -> Array:
    """The dyad's closure quantity q from its parents' (unmasked) positions."""
    if isinstance(dyad, DyadRRR):
        delta = states[dyad.p2].pos - states[dyad.p1].pos
        return plane.dot(delta, delta)
    ang = np.asarray(
        params[dyad.line_angle] if isinstance(dyad.line_angle, str) else dyad.line_angle, float
    )[..., None]
    normal = np.stack(np.broadcast_arrays(-np.sin(ang), np.cos(ang)), axis=-1)
    return plane.dot(states[dyad.p1].pos - states[dyad.line_point].pos, normal)


def _thresholds(dyad: DyadRRR | DyadRRP, params) -> tuple[Array, Array]:
    def val(p):
        return np.asarray(params[p] if isinstance(p, str) else p, dtype=float)

    if isinstance(dyad, DyadRRR):
        r1, r2 = val(dyad.r1), val(dyad.r2)
        return (r1 - r2) ** 2, (r1 + r2) ** 2
    r = val(dyad.r)
    return -r, r


def _turning(plan: Plan, name: str, params) -> tuple[Array, Array]:
    """A ground pivot or crank joint as ``O + w·e^{iθ}`` (complex): its pivot O and arm w."""
    step = plan.step(name)
    if isinstance(step, Fixed):
        pivot, arm = step.at, np.complex128(0.0)
    else:
        pivot = plan.step(step.pivot).at
        length = np.asarray(params[step.length] if isinstance(step.length, str) else step.length)
        phase = np.asarray(params[step.phase] if isinstance(step.phase, str) else step.phase)
        arm = length * np.exp(1j * phase)
    o = np.asarray(params[pivot], dtype=float)
    return o[..., 0] + 1j * o[..., 1], arm


def _analytic_arcs(plan: Plan, params, points) -> InputArcs:
    """Closed-form arcs from q(θ) = c0 + amp·cos(θ − ψ), in half-angle form.

    The arc ends are ``ψ ± a_in`` (where q reaches its upper threshold) and ``ψ ± a_out`` (its
    lower one), with ``sin²(a_in/2) = s_hi`` and ``cos²(a_out/2) = c_lo``. For an RRR dyad both
    come as products of differences of the lengths themselves, q(θ) = (a + b)² − 4ab·sin²(x/2)
    = (a − b)² + 4ab·cos²(x/2) with a = |pivot difference| and b = |arm difference|: no
    cancellation between the large c0 and a small threshold, and no rounding from the
    placement of the frame, so a limit is as exact as its data allow.
    """
    (dyad,) = plan.dyads
    t_lo, t_hi = _thresholds(dyad, params)
    if isinstance(dyad, DyadRRR):
        o1, w1 = _turning(plan, dyad.p1, params)
        o2, w2 = _turning(plan, dyad.p2, params)
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


def _snap_inside(plan: Plan, params, points, lo: Array, hi: Array) -> tuple[Array, Array]:
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


def normalised_arcs(full, never, lo, hi, dyad_lo, dyad_hi, period=TWO_PI) -> InputArcs:
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

    def take(a):
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


def _assembled(plan, params, points, theta, branches) -> tuple[NDArray[np.bool_], Array]:
    _, states = place_all(plan, params, theta, points=points, branches=branches, order=0)
    ok = np.ones(np.shape(theta), dtype=bool) if np.ndim(theta) > 1 else None
    margins = []
    for dyad in plan.dyads:
        st = states[dyad.name]
        # The strict sign of the discriminant, not the rounding-tolerant `valid`: bisection must
        # converge on the root itself.
        closes = st.valid & (st.margin >= 0.0)
        # Parents that meet with links allowing it (a crossing): closed, far from a limit.
        meet = crossings.meets(dyad, states, params)
        closes = closes | meet
        ok = closes if ok is None else ok & closes
        margin = np.where(np.isfinite(st.margin), np.abs(st.margin), np.inf)
        margins.append(np.where(meet, 1.0, margin))
    return ok, np.stack(margins, axis=-1)


def _numeric_arcs(plan, params, points, branches, grid: int = GRID, turns=None) -> InputArcs:
    """Arcs by bracketing the assembly predicate on a grid and bisecting every change.

    The grid covers one period of the input (``turns`` whole turns, ``grid`` nodes per turn).
    """
    shape = batch_shape(params, points)
    turns = np.broadcast_to(np.ones(shape, int) if turns is None else turns, shape)
    period = TWO_PI * turns
    nodes = grid * int(turns.max()) if turns.size else grid
    frac = np.arange(nodes) / nodes
    theta = -np.pi + period[..., None] * frac
    # The grid's closing node, exactly where the next period starts.
    theta_next = np.concatenate((theta[..., 1:], (-np.pi + period)[..., None]), axis=-1)
    ok, _ = _assembled(plan, params, points, theta, branches)
    ok = np.broadcast_to(ok, shape + (nodes,))
    nxt = np.roll(ok, -1, axis=-1)
    change = ok != nxt
    n_change = change.sum(axis=-1)
    kmax = int(n_change.max()) if n_change.size else 0
    full = ok.all(axis=-1)
    never = ~ok.any(axis=-1)
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
        ok_mid, _ = _assembled(plan, params, points, flat, _expand(branches, flat.shape))
        ok_mid = np.broadcast_to(ok_mid, flat.shape).reshape(mid.shape)
        # Keep the bracket [a, b] with a on the entering side's invalid end.
        return np.where(entering[..., None], ~ok_mid, ok_mid)

    a, b = _bisect(a, b, go_right)
    boundary = np.where(entering, b, a)  # the assembled end of the bracket
    _, margins = _assembled(plan, params, points, boundary, _expand(branches, boundary.shape))
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


def _expand(branches, shape):
    if not branches:
        return None
    return {k: np.broadcast_to(np.asarray(v)[..., :1], shape) for k, v in branches.items()}


MAX_TURNS = 64
RATIO_TOL = 1e-9


class NoPeriod(ValueError):
    """A geared linkage whose motion never repeats (an irrational gear ratio): no circuit."""


def input_turns(plan: Plan, params: Mapping[str, ArrayLike], *, points=frozenset()) -> NDArray:
    """How many turns of the input before every crank is back where it started.

    A crank geared at the ratio k turns k times per input turn, so the linkage repeats after the
    least q with k·q whole for every crank: q = 1 for integer ratios, 2 for 1.5 or −0.5, 3 for 2/3.

    Raises
    ------
    NoPeriod
        If some ratio is not a fraction with a denominator up to ``MAX_TURNS`` (to 1e-9): such
        a linkage never repeats, and there is no closed circuit to trace.

    Examples
    --------
    >>> from linkwright.engine import Crank, Fixed, Plan
    >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", 1.0, ratio="k")), traced=("A",))
    >>> input_turns(plan, {"O": [0.0, 0.0], "k": [1.0, -1.5, 2 / 3]}, points=frozenset({"O"}))
    array([1, 2, 3])
    """
    shape = batch_shape(params, points)
    ratios = []
    for step in plan.steps:
        if isinstance(step, Crank | SphereCrank):
            r = params[step.ratio] if isinstance(step.ratio, str) else step.ratio
            ratios.append(np.broadcast_to(np.asarray(r, dtype=float), shape))
    turns = np.zeros(shape, dtype=np.int64)
    for q in range(1, MAX_TURNS + 1):
        whole = np.ones(shape, dtype=bool)
        for r in ratios:
            x = r * q
            whole &= np.abs(x - np.round(x)) <= RATIO_TOL * np.maximum(1.0, np.abs(x))
        turns = np.where((turns == 0) & whole, q, turns)
        if np.all(turns > 0):
            return turns
    stuck = turns == 0
    for r in ratios:
        x = r[..., None] * np.arange(1, MAX_TURNS + 1)
        whole = np.abs(x - np.round(x)) <= RATIO_TOL * np.maximum(1.0, np.abs(x))
        alone = stuck & ~whole.any(-1)
        if alone.any():
            raise NoPeriod(
                f"gear ratio {float(r[alone].ravel()[0]):.12g} is not a fraction p/q with "
                f"q ≤ {MAX_TURNS}: the linkage never repeats, so it has no closed circuit "
                "(give a rational ratio, e.g. 1.5 for 3/2)"
            )
    raise NoPeriod(
        f"the gear ratios together repeat only after more than {MAX_TURNS} input turns: "
        "the linkage has no closed circuit to trace"
    )


def input_arcs(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    *,
    points: frozenset[str] = frozenset(),
    method: str = "auto",
) -> InputArcs:
    """Admissible input arcs of each linkage in the batch, assembly as in ``params``.

    ``method`` is ``"analytic"`` (single dyad with a first-order trigonometric closure),
    ``"numeric"`` (grid bracketing and bisection, any plan) or ``"auto"`` (analytic where it
    applies). Tests compare the two. The arcs cover one period of the input
    (:func:`input_turns`): several turns for a linkage geared at a fractional ratio.
    """
    arcs = ARCS_MEMO.get(
        memo_key(plan, params, points, "arcs", method),
        lambda: search_input_arcs(plan, params, points, method),
    )
    # Kept arcs are shared: each caller gets arrays of its own.
    return InputArcs(
        *(np.copy(getattr(arcs, f)) for f in ("full", "never", "lo", "hi", "dyad_lo", "dyad_hi")),
        period=np.copy(arcs.period) if isinstance(arcs.period, np.ndarray) else arcs.period,
    )


ARCS_MEMO = Memo()
SAMPLED_MEMO = Memo()


def search_input_arcs(plan: Plan, params, points: frozenset[str], method: str) -> InputArcs:
    dyads = plan.dyads
    turns = input_turns(plan, params, points=points)
    if plan.triads:
        # A triad's poses are followed from sample to sample, not held: the arcs of every
        # circuit of every configuration (one linkage at a time).
        arcs = circuit_arcs(
            plan,
            params,
            90,
            points=points,
            period=TWO_PI * float(np.max(turns)),
            shape=batch_shape(params, points),
        )
        return replace(arcs, period=TWO_PI * turns)
    if not dyads:
        shape = batch_shape(params, points)
        nanpad = np.full(shape + (1,), np.nan)
        neg = np.full(shape + (1,), -1)
        period = TWO_PI * turns
        return InputArcs(
            np.ones(shape, bool),
            np.zeros(shape, bool),
            nanpad,
            nanpad,
            neg,
            neg,
            period if period.ndim else float(period),
        )
    analytic_ok = (
        plan.space == "plane"
        and len(dyads) == 1
        and all(_turns_with_input(plan, p, params) for p in dyads[0].parents)
        and np.all(turns == 1)
    )
    if method == "analytic" and not analytic_ok:
        raise ValueError("this plan's limits have no closed form; use method='numeric'")
    if method == "analytic" or (method == "auto" and analytic_ok):
        return _analytic_arcs(plan, params, points)
    arcs = _numeric_arcs(plan, params, points, None, turns=turns)
    if len(dyads) > 1:  # a later dyad may fail past a crossing of an earlier one's sign
        arcs = crossings.merge_arcs(plan, params, points, arcs, GRID * int(turns.max()))
    return arcs


MAX_SEGMENTS = 32
SCAN_CHUNK = 240
# A small batch scans in longer chunks (a call costs about as much as 300 samples of a six-bar
# on the sphere): up to this many samples a call.
SCAN_NUMBERS = 2880
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
    plan: Plan, params, points: frozenset[str], samples: int, circuit: int, start: float, spacing
) -> tuple[Array, dict[str, Array], dict[str, NDArray[np.bool_]]]:
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
            and all(_turns_with_input(plan, p, params) for d in dyads for p in d.parents)
            and np.all(np.rint(period / TWO_PI) == 1)
        )
        segs = crossings.cut_single(
            plan, params, points, segs, arcs, usable, doc, GRID, _turning if analytic else None
        )
        weight = None
    else:
        theta0 = np.where(arcs.full, start, np.where(have_arc, lo, 0.0))
        first = np.where(arcs.full, PLAIN, LIMIT)
        segs = _walk(plan, params, points, theta0, doc, period, usable, first=first)
        for finer in REFINE_GRIDS:
            failed = usable & ~np.isfinite(segs[0][..., 0])
            if not failed.any():
                break
            # A limit gap narrower than a scan cell was stepped over and the walk wandered into
            # a neighbouring arc without closing: walk those linkages again on a finer scan.
            sub = _subset(params, points, shape, failed)
            again = _walk(
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
        theta, segment = _path_samples(
            plan, params, points, seg_start, seg_end, seg_branches, samples, code, begin, end
        )
    else:
        theta, segment = _sample_segments(seg_start, seg_end, samples, code, weight)
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


def _sample_segments(
    seg_start: Array,
    seg_end: Array,
    samples: int,
    code: NDArray[np.int64],
    weight: Array | None = None,
) -> tuple[Array, NDArray]:
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


def _share(
    length: Array, seg_start: Array, samples: int
) -> tuple[NDArray, NDArray, NDArray, Array]:
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


PILOT = 17


def _path_lengths(plan, params, points, seg_start, seg_end, seg_branches, begin, end) -> Array:
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


def _path_samples(
    plan, params, points, seg_start, seg_end, seg_branches, samples, code, begin, end
):
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


def _path_chunk(plan, params, points, joints, a, b, br, warps, samples, ends):
    """:func:`_path_samples` for a flat batch ``(m,)`` with segments ``(m, S)``."""
    m, s = a.shape
    af, bf, warp = a.ravel(), b.ravel(), warps.ravel()
    begin, end = (e.ravel() for e in ends)
    flat_br = {k: v.ravel() for k, v in br.items()}

    def inputs(o, x):
        g = crossings.warp(warp[o], x)
        # A segment's far end exactly (a crossing placed there is the limit at that input).
        return np.where(x == 1.0, bf[o], af[o] + (bf[o] - af[o]) * g)

    def place(o, x):
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


def _refine(inputs, place, joints, owners, m, s, samples):
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


def _interleave(old, new, old_at, new_at, axis=0):
    """``old`` and ``new`` merged into one array, their elements at ``old_at`` and ``new_at``."""
    shape = list(old.shape)
    shape[axis] += new.shape[axis]
    out = np.empty(shape, dtype=old.dtype)
    index = [slice(None)] * old.ndim
    index[axis] = old_at
    out[tuple(index)] = old
    index[axis] = new_at
    out[tuple(index)] = new
    return out


def _splits(own, pos, stuck, m, s, size, samples):
    """Which intervals (by their left node) still need bisecting."""
    measure, open_, big = _measure(own, pos, stuck, m, s, size, samples)
    good = open_ & np.isfinite(measure)
    row = own[:-1] // s
    total = np.bincount(row, np.where(good, measure, 0.0), minlength=m)
    # An interval with one unassembled end is bisected down to the singular input itself. One
    # with both ends unassembled (inside a gap the walk stepped over) holds no motion to place
    # samples on: bisecting it would only double the nodes at every level.
    placed = np.isfinite(pos).all(axis=(0, 2))
    edge = placed[:-1] != placed[1:]
    split = (open_ & ~good & edge) | (good & big & (measure > PATH_STEP * total[row] / samples))
    return split & ~stuck[:-1]


def _measure(own, pos, stuck, m, s, size, samples):
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

    def relative(open_):
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


REFINE_GRIDS = (8 * GRID, 64 * GRID)


def _subset(params, points, shape, mask):
    """The parameters of the linkages selected by ``mask`` (a boolean array of batch shape)."""
    # Boolean indexing takes the selected linkages in row-major order, as flatnonzero does.
    return _take(params, points, shape, np.flatnonzero(mask))


def _walk(plan, params, points, theta0, doc, period, usable, grid=GRID, first=None):
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


def _next_limit(plan, params, points, theta, direction, branches, period, grid=GRID):
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
        ok, _ = _assembled(plan, params, points, th, br)
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
        ok, _ = _assembled(plan, params, points, mid, br)
        return np.broadcast_to(ok, mid.shape)

    a, b = _bisect(a, b, go_right)
    _, margins = _assembled(plan, params, points, a[..., None], br)
    which = np.argmin(margins[..., 0, :], axis=-1)
    return a, np.broadcast_to(which, shape), found


def _restrict(motion: Motion, keep: NDArray[np.bool_]) -> Motion:
    valid = motion.valid & keep
    regular = motion.regular & keep

    def mask(d, k):
        return None if d is None else {n: np.where(k[..., None], a, np.nan) for n, a in d.items()}

    return Motion(
        input=motion.input,
        positions=mask(motion.positions, valid),
        velocities=mask(motion.velocities, regular),
        accelerations=mask(motion.accelerations, regular),
        valid=valid,
        regular=regular,
        branches=motion.branches,
        margins=motion.margins,
        labels=motion.labels,
    )

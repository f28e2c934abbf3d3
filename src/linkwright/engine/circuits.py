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
traced curve is closed. :func:`trace` samples that whole closed path with every limit hit exactly.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.evaluate import Motion, batch_shape, evaluate, place_all
from linkwright.engine.plan import Crank, DyadRRP, DyadRRR, Fixed, Plan
from linkwright.geometry import plane

__all__ = ["InputArcs", "input_arcs", "trace"]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi
GRID = 1440
BISECTIONS = 64


@dataclass(frozen=True)
class InputArcs:
    """The admissible inputs of a batch of linkages with their assembly held fixed.

    ``full`` marks linkages whose input turns fully, ``never`` those that assemble nowhere. Else
    ``lo``/``hi`` (shape ``batch + (K,)``, NaN-padded, ``lo`` in (−π, π], ``hi > lo``) are the
    arcs, and ``dyad_lo``/``dyad_hi`` the index (into ``plan.dyads``) of the dyad at its limit
    there (−1 in padding).
    """

    full: NDArray[np.bool_]
    never: NDArray[np.bool_]
    lo: Array
    hi: Array
    dyad_lo: NDArray[np.int64]
    dyad_hi: NDArray[np.int64]

    @property
    def count(self) -> NDArray[np.int64]:
        return np.sum(np.isfinite(self.lo), axis=-1)


def _is_ground(plan: Plan, name: str) -> bool:
    return isinstance(plan.step(name), Fixed)


def _turns_with_input(plan: Plan, name: str) -> bool:
    step = plan.step(name)
    if isinstance(step, Fixed):
        return True
    return (
        isinstance(step, Crank)
        and not isinstance(step.ratio, str)
        and step.ratio == 1.0
        and _is_ground(plan, step.pivot)
    )


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
    arcs = _normalised(full, never, lo, hi, zero, zero)
    # Snap after normalising (a shift by 2π rounds, and the snapped value is the one returned);
    # a start snapped past π is wrapped by normalising again, and snapped again.
    for _ in range(2):
        lo, hi = _snap_inside(plan, params, points, arcs.lo, arcs.hi)
        if not np.any(lo > np.pi):
            return replace(arcs, lo=lo, hi=hi)
        arcs = _normalised(full, never, lo, hi, arcs.dyad_lo, arcs.dyad_hi)
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


def _normalised(full, never, lo, hi, dyad_lo, dyad_hi) -> InputArcs:
    """Put each arc's start in (−π, π] and order arcs by start; padding last."""
    # Starts already in range stay bit-for-bit; a shift rounds, and can land a start on −π or a
    # hair above π (−π + 1 ulp goes to π + 1 ulp via (lo − π)/2π = −1): one more turn then.
    inside = (lo > -np.pi) & (lo <= np.pi)
    shift = np.where(inside, 0.0, TWO_PI * np.ceil((lo - np.pi) / TWO_PI))
    lo, hi = lo - shift, hi - shift
    turn = np.where(lo > np.pi, TWO_PI, np.where(lo <= -np.pi, -TWO_PI, 0.0))
    lo, hi = lo - turn, hi - turn
    order = np.argsort(np.where(np.isfinite(lo), lo, np.inf), axis=-1)

    def take(a):
        return np.take_along_axis(a, order, -1)

    lo, hi = take(lo), take(hi)
    pad = ~np.isfinite(lo)
    return InputArcs(
        full, never, lo, hi, np.where(pad, -1, take(dyad_lo)), np.where(pad, -1, take(dyad_hi))
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
        ok = closes if ok is None else ok & closes
        margins.append(np.where(np.isfinite(st.margin), np.abs(st.margin), np.inf))
    return ok, np.stack(margins, axis=-1)


def _numeric_arcs(plan, params, points, branches, grid: int = GRID) -> InputArcs:
    """Arcs by bracketing the assembly predicate on a grid and bisecting every change."""
    shape = batch_shape(params, points)
    theta = np.linspace(-np.pi, np.pi, grid, endpoint=False)
    ok, _ = _assembled(plan, params, points, theta, branches)
    ok = np.broadcast_to(ok, shape + (grid,))
    nxt = np.roll(ok, -1, axis=-1)
    change = ok != nxt
    n_change = change.sum(axis=-1)
    kmax = int(n_change.max()) if n_change.size else 0
    full = ok.all(axis=-1)
    never = ~ok.any(axis=-1)
    if kmax == 0:
        nanpad = np.full(shape + (1,), np.nan)
        return InputArcs(
            full, never, nanpad, nanpad.copy(), np.full(shape + (1,), -1), np.full(shape + (1,), -1)
        )
    # Indices of the grid cells where the predicate changes, padded with the first one.
    idx = np.argsort(~change, axis=-1, kind="stable")[..., :kmax]
    has = np.arange(kmax) < n_change[..., None]
    a = theta[idx]
    # The next node itself, not a + 2π/grid: that can round past it, and a change confined to a
    # node (a joint passing exactly through a pivot) would fall outside its own bracket.
    b = np.append(theta, np.pi)[idx + 1]
    entering = ~np.take_along_axis(ok, idx, -1)  # invalid → valid going up
    for _ in range(BISECTIONS):
        mid = 0.5 * (a + b)
        ok_mid, _ = _assembled(plan, params, points, mid, _expand(branches, mid.shape))
        ok_mid = np.broadcast_to(ok_mid, mid.shape)
        # Keep the bracket [a, b] with a on the entering side's invalid end.
        go_right = np.where(entering, ~ok_mid, ok_mid)
        a = np.where(go_right, mid, a)
        b = np.where(go_right, b, mid)
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
    for i in range(k):
        gap = (hi_cand - lo[..., i : i + 1]) % TWO_PI
        gap = np.where(np.isfinite(gap), gap, np.inf)
        j = np.argmin(gap, axis=-1)
        end = np.take_along_axis(hi_cand, j[..., None], -1)[..., 0]
        # The bisected end itself (unrounded by lo + gap), a turn up where it lies below lo.
        end = np.where(end > lo[..., i], end, end + TWO_PI)
        hi[..., i] = np.where(np.isfinite(lo[..., i]), end, np.nan)
        dyad_hi[..., i] = np.take_along_axis(which, j[..., None], -1)[..., 0]
    return _normalised(full, never, lo, hi, np.where(has & entering, which, -1), dyad_hi)


def _expand(branches, shape):
    if not branches:
        return None
    return {k: np.broadcast_to(np.asarray(v)[..., :1], shape) for k, v in branches.items()}


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
    applies). Tests compare the two.
    """
    dyads = plan.dyads
    if not dyads:
        shape = batch_shape(params, points)
        nanpad = np.full(shape + (1,), np.nan)
        neg = np.full(shape + (1,), -1)
        return InputArcs(np.ones(shape, bool), np.zeros(shape, bool), nanpad, nanpad, neg, neg)
    analytic_ok = len(dyads) == 1 and all(_turns_with_input(plan, p) for p in dyads[0].parents)
    if method == "analytic" and not analytic_ok:
        raise ValueError("this plan's limits have no closed form; use method='numeric'")
    if method == "analytic" or (method == "auto" and analytic_ok):
        return _analytic_arcs(plan, params, points)
    return _numeric_arcs(plan, params, points, None)


def trace(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    samples: int,
    *,
    points: frozenset[str] = frozenset(),
    circuit: int = 0,
    order: int = 2,
    start: float = 0.0,
) -> Motion:
    """Sample the whole circuit of every linkage in the batch with ``samples`` inputs.

    A linkage whose input turns fully is sampled at ``start + 2πk/samples`` on its own assembly.
    Otherwise its ``circuit``-th input arc (arcs ordered by their start in (−π, π]) is swept up on
    the document's assembly and back down on the other branch of the dyad that limits it, so
    sample 0 is the lower limit and sample ``ceil(samples/2)`` the upper one, both exact. A
    linkage with no such arc comes back with ``valid`` all False.

    Only plans whose circuits are limited by a single dyad are traced here; plans with several
    dyads need the general walker (issue 3).
    """
    if len(plan.dyads) > 1:
        raise NotImplementedError("circuit tracing of plans with several dyads is not built yet")
    if samples < 2:
        raise ValueError("a circuit needs at least 2 samples")
    arcs = input_arcs(plan, params, points=points)
    shape = arcs.full.shape
    k = np.arange(samples)
    full_theta = start + TWO_PI * k / samples
    idx = np.clip(circuit, 0, arcs.lo.shape[-1] - 1)
    lo = arcs.lo[..., idx]
    hi = arcs.hi[..., idx]
    have_arc = np.isfinite(lo) & (circuit < arcs.lo.shape[-1])
    n_up = (samples + 1) // 2
    n_down = samples - n_up
    w = np.concatenate((np.arange(n_up) / n_up, 1.0 - np.arange(n_down) / max(n_down, 1)))
    down = np.concatenate((np.zeros(n_up, bool), np.ones(n_down, bool)))
    arc_theta = lo[..., None] * (1.0 - w) + hi[..., None] * w
    theta = np.where(
        arcs.full[..., None], full_theta, np.where(have_arc[..., None], arc_theta, 0.0)
    )
    branches = None
    if plan.dyads:
        dyad = plan.dyads[0]
        base = np.broadcast_to(np.asarray(params[dyad.branch], dtype=float), shape)[..., None]
        flip = np.where(arcs.full[..., None], False, down)
        branches = {dyad.name: np.where(flip, -base, base)}
    motion = evaluate(plan, params, theta, points=points, branches=branches, order=order)
    usable = (arcs.full | have_arc)[..., None]
    if usable.all():
        return motion
    return _restrict(motion, usable)


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
    )

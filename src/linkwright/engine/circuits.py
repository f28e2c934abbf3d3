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
from dataclasses import dataclass

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


def _analytic_arcs(plan: Plan, params, points) -> InputArcs:
    (dyad,) = plan.dyads
    _, states = place_all(plan, params, np.array([0.0, 0.5 * np.pi, np.pi]), points=points, order=0)
    q = _closure(plan, dyad, states, params, points)
    c0 = 0.5 * (q[..., 0] + q[..., 2])
    c1 = 0.5 * (q[..., 0] - q[..., 2])
    c2 = q[..., 1] - c0
    amp = np.hypot(c1, c2)
    psi = np.arctan2(c2, c1)
    t_lo, t_hi = _thresholds(dyad, params)
    t_lo, t_hi = np.broadcast_arrays(t_lo, t_hi, c0)[:2]
    with np.errstate(divide="ignore", invalid="ignore"):
        xa = (t_lo - c0) / amp  # need cos(θ − ψ) ≥ xa
        xb = (t_hi - c0) / amp  # and cos(θ − ψ) ≤ xb
    flat = amp <= 1e-15 * np.maximum(np.abs(c0), np.abs(t_hi))
    const_ok = (c0 >= t_lo) & (c0 <= t_hi)
    never = np.where(flat, ~const_ok, (xa > 1.0) | (xb < -1.0) | (xa > xb))
    full = np.where(flat, const_ok, (xa <= -1.0) & (xb >= 1.0))
    a_in = np.arccos(np.clip(xb, -1.0, 1.0))  # |θ − ψ| ≥ a_in
    a_out = np.arccos(np.clip(xa, -1.0, 1.0))  # |θ − ψ| ≤ a_out
    shape = full.shape
    lo = np.full(shape + (2,), np.nan)
    hi = np.full(shape + (2,), np.nan)
    partial = ~(never | full)
    one_about_psi = partial & (xb >= 1.0)  # only the lower threshold binds
    one_about_opp = partial & (xa <= -1.0) & ~one_about_psi
    two = partial & ~one_about_psi & ~one_about_opp
    lo[..., 0] = np.where(one_about_psi, psi - a_out, np.where(one_about_opp, psi + a_in, np.nan))
    hi[..., 0] = np.where(
        one_about_psi, psi + a_out, np.where(one_about_opp, psi + TWO_PI - a_in, np.nan)
    )
    lo[..., 0] = np.where(two, psi + a_in, lo[..., 0])
    hi[..., 0] = np.where(two, psi + a_out, hi[..., 0])
    lo[..., 1] = np.where(two, psi - a_out, np.nan)
    hi[..., 1] = np.where(two, psi - a_in, np.nan)
    zero = np.zeros(lo.shape, dtype=np.int64)
    return _normalised(full, never, lo, hi, zero, zero)


def _normalised(full, never, lo, hi, dyad_lo, dyad_hi) -> InputArcs:
    """Put each arc's start in (−π, π] and order arcs by start; padding last."""
    shift = TWO_PI * np.ceil((lo - np.pi) / TWO_PI)
    lo = lo - shift
    hi = hi - shift
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
        return InputArcs(full, never, nanpad, nanpad.copy(), np.full(shape + (1,), -1),
                         np.full(shape + (1,), -1))
    # Indices of the grid cells where the predicate changes, padded with the first one.
    idx = np.argsort(~change, axis=-1, kind="stable")[..., :kmax]
    has = np.arange(kmax) < n_change[..., None]
    step = TWO_PI / grid
    a = theta[idx]
    b = a + step
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
        g = np.take_along_axis(gap, j[..., None], -1)[..., 0]
        hi[..., i] = np.where(np.isfinite(lo[..., i]), lo[..., i] + g, np.nan)
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
    theta = np.where(arcs.full[..., None], full_theta, np.where(have_arc[..., None], arc_theta, 0.0))
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

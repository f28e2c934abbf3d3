"""What a traced circuit through singular geometry is held to (issue 10), checked independently.

Near a change point (s + l = p + q) the motion itself concentrates: a four-bar close to a deltoid
swings its rocker through half a turn while the input moves by as little as the distance by
which A misses B0. :func:`linkwright.engine.trace` with ``spacing="path"`` places the samples by
the joints' travel instead of the input's. ``check_circuit`` holds it, and the default
``spacing="input"``, to:

* every sample satisfies the link-length constraints, recomputed here from positions;
* limit positions are samples, bit for bit the roots ``input_range`` returns, and there the dyad
  is flat to rounding: |A − B0| is coupler ± rocker (the crank pin's distance from the guide is
  the rod; on the sphere the chord A–B0 is that of the arc coupler ± rocker);
* no branch jump: from every sample an independent continuation (the nearest root of the dyad's
  two, computed from the plain formulas of tests/singular_helpers.py, in adaptive input
  substeps) arrives at the next sample;
* with ``spacing="path"`` only, the step bound that :func:`~linkwright.engine.trace` states:
  every moving joint's step is at most ``2·M·L/n + 2ν`` (L its path length, M the circuit's
  normalised travel, ν = 1e-7 of the linkage's size) beyond the rounding its positions carry,
  and a path's length is within the Cauchy–Crofton bound of its curve's size.

The continuation's substeps are chosen by geometry alone, so that they resolve concentrated
motion too: a substep is taken only if the frame of the intersection (the normal of the roots'
line) turns by less than 0.1 rad and the nearest root is at most half as far as the other, on
the side the joint is on. Where the two roots meet (within rounding: near a limit a root is only
known to about √ε of its link, and near A ≈ B0 to less), the joint keeps its side, except at a
turning point of the input (a limit position), where it leaves on the other side, as the machine
does.
"""

from __future__ import annotations

import numpy as np
from singular_helpers import (
    CLOSE,
    FLAT_TOL,
    MOVING,
    NOISE,
    RESIDUAL_TOL,
    STEP_FACTOR,
    TWO_PI,
    formulas,
)

from linkwright.engine import trace
from linkwright.mechanisms import (
    input_range,
)

# ----------------------------------------------------------------------------------------------
# Independent continuation between consecutive samples
# ----------------------------------------------------------------------------------------------

TURN = 0.1  # rad: the most the roots' line may turn in one substep


MAX_SUBSTEPS = 4000


def _side(point, mid, perp):
    return np.sign(((point - mid) * perp).sum(-1))


def continuation(fam, motion, full, period):
    """Continue the dyad's joint from every sample to the next input, nearest root by root.

    Returns, per pair of consecutive samples (cyclic), how far the continuation arrives from
    the next sample beyond the rounding the roots carry there, relative to the scale (NaN where
    a sample is unassembled or the two inputs are equal), and whether some substep could not
    be resolved down to the input's last bits (a singular pose between the two samples).
    """
    theta = motion.input
    B = motion.positions[fam.joint]
    count, n = theta.shape
    rows = np.repeat(np.arange(count), n)
    t0 = theta.ravel()
    target = np.roll(theta, -1, axis=-1)
    target[:, -1] += np.where(full, period, 0.0)
    target = target.ravel()
    start = B.reshape(count * n, -1)
    arrive = np.roll(B, -1, axis=-2).reshape(count * n, -1)
    previous = np.roll(theta, 1, axis=-1)
    previous[:, 0] -= np.where(full, period, 0.0)
    turning = (theta - previous) * (target.reshape(count, n) - theta) < 0.0
    tol = CLOSE * fam.scale[rows]
    mid, half, perp, noise = (np.array(a) for a in fam.roots(rows, t0))
    # The side of the roots' line each sample starts from. Where the two roots are apart that is
    # the sample's own; where they meet, the side of the last sample where they were apart,
    # flipped at each turning point of the input since (a limit: the joint leaves on the other
    # side, as the machine does). A circuit whose roots never part starts on +1.
    own = _side(start, mid, perp)
    apart = ((2 * half > tol + 4 * noise) & (own != 0)).reshape(count, n)
    twice = np.concatenate((apart, apart), axis=-1)
    last = np.maximum.accumulate(np.where(twice, np.arange(2 * n), -1), axis=-1)[:, n:]
    flips = np.cumsum(np.concatenate((turning, turning), axis=-1), axis=-1)
    j = np.maximum(last, 0)
    parity = flips[:, n:] - np.take_along_axis(flips, j, -1)
    own2 = np.concatenate((own.reshape(count, n),) * 2, axis=-1)
    side = np.where(last >= 0, np.take_along_axis(own2, j, -1) * (-1.0) ** parity, 1.0).ravel()
    t, cur = t0.copy(), start.copy()
    step = np.clip(0.25 * (target - t0), -0.05, 0.05)
    todo = np.isfinite(t0) & np.isfinite(target) & (t0 != target)
    todo &= np.isfinite(start).all(-1) & np.isfinite(arrive).all(-1)
    unresolved = np.zeros(t0.size, dtype=bool)
    for _ in range(MAX_SUBSTEPS):
        i = np.flatnonzero(todo)
        if not i.size:
            break
        left = target[i] - t[i]
        h = np.where(np.abs(step[i]) < np.abs(left), step[i], left)
        tn = np.where(np.abs(step[i]) < np.abs(left), t[i] + h, target[i])
        m2, h2, p2, n2 = fam.roots(rows[i], tn)
        sep0, sep1 = 2 * half[i], 2 * h2
        near_tol = tol[i] + 4 * np.maximum(noise[i], n2)
        merged = (sep0 <= near_tol) | (sep1 <= near_tol)
        shift = np.linalg.norm(m2 - mid[i], axis=-1)
        # Passing an exact meeting of the dyad's parents, the roots' frame turns over (their
        # pair stays put): the joint's side, measured in it, flips with it.
        flip = np.where(fam.passes(rows[i], t[i], tn), -1.0, 1.0)
        turn = np.linalg.norm(p2 - flip[:, None] * perp[i], axis=-1)
        expect = flip * side[i]
        near = _side(cur[i], m2, p2)
        near = np.where(near == 0, expect, near)
        d_near = np.linalg.norm(cur[i] - (m2 + (near * h2)[:, None] * p2), axis=-1)
        d_far = np.linalg.norm(cur[i] - (m2 - (near * h2)[:, None] * p2), axis=-1)
        # Apart, the nearest root must be clearly the nearer one and on the joint's side (a
        # substep over a near-crossing of the roots would otherwise pass to the other); where
        # they meet, the midpoint must move little against their separation.
        ok = np.where(
            merged,
            shift <= 0.25 * np.maximum(np.maximum(sep0, sep1), near_tol),
            (d_near <= 0.5 * d_far) & (near == expect),
        )
        ok &= turn < TURN
        tiny = np.abs(tn - t[i]) <= 4 * np.spacing(np.maximum(np.abs(t[i]), 1.0))
        take_it = ok | tiny
        unresolved[i] |= tiny & ~ok
        chosen = np.where(sep0 > near_tol, near, expect)
        j = i[take_it]
        chosen, keep = chosen[take_it], take_it
        t[j] = tn[keep]
        cur[j] = m2[keep] + (chosen * h2[keep])[:, None] * p2[keep]
        mid[j], half[j], perp[j], noise[j] = m2[keep], h2[keep], p2[keep], n2[keep]
        side[j] = np.where(sep1[keep] > near_tol[keep], chosen, expect[keep])
        step[i] = np.where(take_it, 2 * step[i], 0.5 * step[i])
        step[i] = np.clip(step[i], -0.05, 0.05)
        todo[j] &= t[j] != target[j]
    assert not todo.any(), "the continuation did not arrive"
    # How far the continuation arrives from the next sample, beyond the rounding both carry.
    gap = (np.linalg.norm(cur - arrive, axis=-1) - 4 * noise) / fam.scale[rows]
    checked = np.isfinite(t0) & np.isfinite(target) & (t0 != target)
    checked &= np.isfinite(start).all(-1) & np.isfinite(arrive).all(-1)
    gap = np.where(checked, gap, np.nan)
    return gap.reshape(count, n), unresolved.reshape(count, n)


# ----------------------------------------------------------------------------------------------
# The checks
# ----------------------------------------------------------------------------------------------


def circuit_of(m, n, spacing, start=0.0):
    return trace(m.plan, m.params(), n, points=m.points, order=0, spacing=spacing, start=start)


def check_circuit(m, n, spacing, start=0.0):
    """Everything asked of a circuit through singular geometry; returns the step ratios."""
    arcs = input_range(m)
    motion = circuit_of(m, n, spacing, start)
    fam = formulas(m)
    count = motion.input.shape[0]
    rows = np.arange(count)
    never, full = arcs.never, arcs.full
    partial = ~(never | full)
    # Assembled at every sample, limits included, and closed to rounding.
    assert not motion.valid[never].any()
    assert motion.valid[~never].all(), np.argwhere(~motion.valid & ~never[:, None])[:5]
    residual = fam.residual(rows, motion)[~never]
    assert np.all(residual <= RESIDUAL_TOL), np.max(residual)
    # The limits are samples, bit for bit, and the dyad is flat there: they are where the input
    # turns, first up from the lower limit to the upper, then down again, monotonically.
    theta = motion.input
    lo, hi = arcs.lo[:, 0], arcs.hi[:, 0]
    np.testing.assert_array_equal(theta[partial, 0], lo[partial])
    at_hi = np.argmax(theta == hi[:, None], axis=-1)
    assert np.all((theta == hi[:, None]).any(-1)[partial])
    k = np.arange(n)
    ulps = 4 * np.spacing(np.abs(theta) + 1.0)
    up = np.diff(theta, axis=-1) >= -ulps[:, 1:]
    down = np.diff(theta, axis=-1) <= ulps[:, 1:]
    rising = k[None, :-1] < at_hi[:, None]
    assert np.all(np.where(rising, up, down)[partial])
    assert np.all(up[full])
    A = motion.positions["A"]
    for index in (np.zeros(count, dtype=np.int64), at_hi):
        at = np.take_along_axis(A, index[:, None, None], 1)[:, 0]
        flat = fam.flatness(rows, at)[partial]
        assert np.all(flat <= FLAT_TOL), np.max(flat)
    # No branch jump: an independent continuation from each sample arrives at the next.
    period = circuit_period(motion, full)
    gap, unresolved = continuation(fam, motion, full, period)
    assert not unresolved.any(), np.argwhere(unresolved)[:5]
    assert not np.any(gap > CLOSE), np.nanmax(gap)
    if spacing == "path":
        return check_step_bound(fam, motion, full, never, period)
    return None


def circuit_period(motion, full):
    """How far a full circuit's input runs before it closes: one turn, or two for an exact
    deltoid, whose joint comes back after one turn on the other branch (NaN pads partial)."""
    theta = motion.input
    turns = np.ceil((theta[:, -1] - theta[:, 0]) / TWO_PI - 1e-9)
    return np.where(full, TWO_PI * np.maximum(turns, 1), np.nan)


def passes_counted(fam, motion, full, period):
    """How many times each circuit passes an exact meeting of its dyad's parents."""
    theta = motion.input
    count = theta.shape[0]
    target = np.roll(theta, -1, axis=-1)
    target[:, -1] += np.where(full, np.nan_to_num(period), 0.0)
    rows = np.repeat(np.arange(count), theta.shape[1])
    passed = fam.passes(rows, theta.ravel(), target.ravel()).reshape(theta.shape)
    return passed.sum(-1)


def check_step_bound(fam, motion, full, never, period):
    """``spacing="path"``: each moving joint's step ≤ 2·M·L/n + 2ν, with M and L measured on
    the samples themselves (shorter than on the curve, so the check is the stricter), beyond
    the rounding the two samples carry (:meth:`roots`' estimate for B, times the lever from A
    for P; A is exact). Returns the measured c = step·n/(M·L) per joint and linkage, where the
    rounding is below 1e-6 of the curve (NaN elsewhere)."""
    count, n = motion.input.shape
    pos = np.stack([motion.positions[j] for j in "ABP"])
    step = np.linalg.norm(np.roll(pos, -1, axis=-2) - pos, axis=-1)  # (joint, linkage, sample)
    length = step.sum(-1)
    box = np.linalg.norm(np.max(pos, axis=-2) - np.min(pos, axis=-2), axis=-1)
    moving = box > MOVING * fam.scale
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(moving[..., None], step / length[..., None], 0.0)
    travel = rel.max(axis=0).sum(-1)  # M
    # Limits and crossings each start a segment (at most: a full circuit may start on one).
    segments = np.where(full, 1, 2) + passes_counted(fam, motion, full, period)
    assert n >= 8 * segments.max()
    rows = np.repeat(np.arange(count), n)
    noise = fam.roots(rows, motion.input.ravel())[3].reshape(count, n)
    noise = noise + np.roll(noise, -1, axis=-1)
    A, B, P = pos
    lever = np.max(np.linalg.norm(P - A, axis=-1) / np.linalg.norm(B - A, axis=-1), axis=-1)
    blur = np.stack((0 * noise, noise, (1 + lever)[:, None] * noise))
    bound = STEP_FACTOR * (travel * length / n)[..., None] + 2 * (NOISE * fam.scale)[:, None]
    over = step > bound + 2 * blur
    assert not np.any((over & moving[..., None])[:, ~never]), np.max(
        np.where(moving[..., None], step / (bound + 2 * blur), 0.0)
    )
    if fam.crossings is not None:
        # Cauchy–Crofton: a path that any line meets at most k times is at most k/2 times the
        # perimeter of its hull, itself at most π times its diameter (≤ its box's diagonal).
        # (Not for paths at the rounding level, whose samples zigzag.)
        k = np.asarray(fam.crossings)[:, None]
        crofton = length <= 0.5 * k * np.pi * box * (1 + 1e-12)
        assert np.all((crofton | ~moving)[:, ~never])
    # The measured c, where the rounding is below 1e-6 of the curve.
    quiet = moving & (np.max(blur, axis=-1) < 1e-6 * box)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(quiet, step.max(-1) * n / (travel * length), np.nan)

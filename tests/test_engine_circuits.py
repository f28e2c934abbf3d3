"""Traced circuits of random four-bars and slider-cranks: closed, continuous under step halving,
and with no step far beyond the mean (a bound derived next to the check).
"""

from __future__ import annotations

import numpy as np
from engine_helpers import (
    TWO_PI,
    assert_closes,
    fourbar_lengths,
    fourbars,
    norm,
    random_fourbars,
    random_slider_cranks,
    slider_cranks,
    slider_excess,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    circuit,
    input_range,
)

# ----------------------------------------------------------------------------------------------
# 4. Circuits
# ----------------------------------------------------------------------------------------------

# Largest step between consecutive traced points, against perimeter / n (the mean step; the
# perimeter is the polygon's, which is shorter than the curve's, so the check is the stricter).
#
# Full turns: a constant multiple. The input is sampled uniformly, so a step is the curve's
# speed times 2π/n, and the bound is the ratio of the largest speed to the mean speed: measured
# ≤ 10 over 20,000 random four-bars at n = 90, 360, 1440 (≤ 2.5 for slider-cranks).
# Swinging inputs: no constant multiple is sound. Near a limit every joint moves like
# sqrt(θ − θ_limit) (the dyad's half-chord is r1·sqrt(margin), the margin linear in θ), so the
# step next to a limit is ~c·sqrt(2π/n) while perimeter/n ~ 1/n: the ratio grows like sqrt(n)
# (measured max 14.6, 32, 65 at n = 90, 360, 1440: 1.5–1.7·sqrt(n); 0.74·sqrt(n) for
# slider-cranks; a circle traced uniformly in x gives sqrt(8n)/(2π) = 0.45·sqrt(n)). Both need
# the linkage away from its change point: there the speed concentrates without limit (the
# coupler sweeps most of its curve in a vanishing input interval), so near it only the
# step-halving refinement check (continuity) and the closure checks are asserted.
FULL_STEP_MULTIPLE = 16.0


SWING_STEP_MULTIPLE = 3.0  # × sqrt(n)


STEP_CONDITION = 0.05  # |s + l − p − q| / l, resp. distance of |e| from rod ± crank, / scale


def circuit_steps(motion, joint):
    pos = motion.positions[joint]
    steps = norm(np.roll(pos, -1, axis=-2) - pos)
    return steps.max(axis=-1), steps.sum(axis=-1)


def check_circuit(m, n, *, well_conditioned):
    arcs = input_range(m)
    motion = circuit(m, n, order=2)
    full, never = arcs.full, arcs.never
    partial = ~(full | never)
    assembly = np.broadcast_to(np.asarray(m.assembly), full.shape)
    up = (n + 1) // 2  # ceil(n / 2)
    # Never assembled: nothing but NaN, every joint.
    assert not motion.valid[never].any() and not motion.regular[never].any()
    for name, pos in motion.positions.items():
        assert np.all(np.isnan(pos[never])), name
    # Everything else is valid at every sample, limits included, and closes.
    assert np.all(motion.valid[~never])
    branch = np.where(np.arange(n) < up, 1.0, -1.0) * assembly[..., None]
    branch = np.where(full[..., None], assembly[..., None], branch)
    assert_closes(m, motion, branch=np.where(never[..., None], 0.0, branch))
    # The sweep: lower limit at sample 0, upper at sample ceil(n/2), both exact, monotonic.
    theta = motion.input[partial]
    np.testing.assert_array_equal(theta[..., 0], arcs.lo[partial][..., 0])
    np.testing.assert_array_equal(theta[..., up], arcs.hi[partial][..., 0])
    ulps = 4 * np.spacing(np.abs(theta[..., 1:]) + 1.0)  # lo·(1 − w) + hi·w rounds
    assert np.all(np.diff(theta[..., : up + 1], axis=-1) >= -ulps[..., :up])
    assert np.all(np.diff(theta[..., up:], axis=-1) <= ulps[..., up:])
    # Branch: flips once up→down at ceil(n/2) and back at the wrap; constant for full turns.
    b = motion.branches["B"]
    np.testing.assert_array_equal(b[partial], branch[partial])
    flips = np.sum(b != np.roll(b, -1, axis=-1), axis=-1)
    assert np.all(flips[partial] == 2) and np.all(flips[full] == 0)
    # Full turns: one turn at the mechanism's assembly.
    np.testing.assert_allclose(
        motion.input[full], np.broadcast_to(TWO_PI * np.arange(n) / n, motion.input[full].shape)
    )
    # Closed and continuous.
    for joint in ("B", "P"):
        largest, perimeter = circuit_steps(motion, joint)
        sel = ~never & well_conditioned & (perimeter > 0)
        multiple = np.where(full, FULL_STEP_MULTIPLE, SWING_STEP_MULTIPLE * np.sqrt(n))
        bound = multiple * perimeter / n
        assert np.all(largest[sel] <= bound[sel]), np.max(largest[sel] / bound[sel])
    return motion, arcs


def check_refinement(m, sel):
    """Refining 4× shrinks the largest step (square-root singular at the limits: ×1/2, smooth:
    ×1/4); a jump (a wrong branch, a missed limit) would not shrink. Measured ≤ 0.54 on
    well-conditioned linkages."""
    coarse, fine = circuit(m, 360, order=0), circuit(m, 1440, order=0)
    for joint in ("B", "P"):
        big, _ = circuit_steps(coarse, joint)
        small, _ = circuit_steps(fine, joint)
        assert np.all(small[sel] <= 0.6 * big[sel]), np.max(small[sel] / big[sel])


def test_fourbar_batch_circuits():
    rng = np.random.default_rng(20240401)
    m = random_fourbars(rng, 3000)
    _, excess = fourbar_lengths(m)
    well = np.abs(excess) > STEP_CONDITION
    for n in (360, 361):
        _, arcs = check_circuit(m, n, well_conditioned=well)
    partial = ~(arcs.full | arcs.never)
    assert arcs.full.sum() > 400 and partial.sum() > 1500 and arcs.never.sum() > 400
    check_refinement(m, well & ~arcs.never)
    # The second arc of linkages with two: traced from its own lower limit.
    two = arcs.count == 2
    assert two.sum() > 100
    second = circuit(m, 64, order=0, circuit=1)
    np.testing.assert_array_equal(second.input[two, 0], arcs.lo[two, 1])
    np.testing.assert_array_equal(second.input[two, 32], arcs.hi[two, 1])
    assert np.all(second.valid[two]) and not np.any(second.valid[arcs.count == 1])


def test_slider_crank_batch_circuits():
    rng = np.random.default_rng(20240402)
    m = random_slider_cranks(rng, 3000)
    well = slider_excess(m) > STEP_CONDITION
    for n in (360, 361):
        _, arcs = check_circuit(m, n, well_conditioned=well)
    assert arcs.full.sum() > 400 and arcs.never.sum() > 400
    check_refinement(m, well & ~arcs.never)


@settings(max_examples=100, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()), n=st.integers(2, 400))
def test_single_circuit(m, n):
    if isinstance(m, FourBar):
        well = np.abs(fourbar_lengths(m)[1]) > STEP_CONDITION
    else:
        well = slider_excess(m) > STEP_CONDITION
    check_circuit(m, n, well_conditioned=well)


def test_circuit_hand_example():
    """Never-assembling linkage: all NaN; a rocking input: closed at both limits."""
    never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    motion = circuit(never, 12)
    assert not motion.valid.any()
    assert all(np.isnan(p).all() for p in motion.positions.values())
    assert all(np.isnan(v).all() for v in motion.velocities.values())
    rocking = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    motion = circuit(rocking, 8)
    B = motion.positions["B"]
    # At both limits coupler and rocker are folded: |B0 − A| = coupler − rocker.
    for k in (0, 4):
        assert abs(norm(motion.positions["A"][k] - [1.0, 0.0]) - 4.0) < 1e-14
    # Mirroring in the frame line maps (θ, branch) to (−θ, −branch): sample 1 to sample 5.
    np.testing.assert_allclose(motion.input[1] + motion.input[5], 2 * np.pi)
    np.testing.assert_allclose(B[1], B[5] * [1, -1], atol=1e-14)

"""The engine's positions on many random four-bars and slider-cranks, checked against their
constraints recomputed from the positions; the masks (valid, regular), batches against one-by-one
evaluation, and plans directly.

Random mechanisms, strategies and the constraint checks: tests/engine_helpers.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import (
    assert_closes,
    cross,
    fourbar_lengths,
    fourbars,
    limit_inputs,
    random_fourbars,
    random_slider_cranks,
    slider_cranks,
    take,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.engine import evaluate
from linkwright.mechanisms import (
    FourBar,
    SliderCrank,
    circuit,
    configurations,
    input_range,
    solve,
)

# ----------------------------------------------------------------------------------------------
# 1. Every solved position satisfies its constraints
# ----------------------------------------------------------------------------------------------


def test_fourbar_batch_positions_close():
    rng = np.random.default_rng(20240101)
    m = random_fourbars(rng, 20_000)
    _, excess = fourbar_lengths(m)
    assert np.mean(excess < 0) > 0.2 and np.mean(excess > 0) > 0.2  # Grashof and non-Grashof
    assert np.mean(np.abs(excess) < 1e-8) > 0.15  # near the change point
    # Random inputs (many unassembled) and every limit position, exactly.
    theta = np.concatenate(
        (rng.uniform(-np.pi, np.pi, (20_000, 32)), np.nan_to_num(limit_inputs(m))), axis=-1
    )
    motion = solve(m, theta, order=0)
    assert 0.3 < motion.valid.mean() < 0.9
    assert_closes(m, motion)
    limits = np.isfinite(limit_inputs(m))
    assert limits.sum() > 20_000 and motion.valid[:, 32:][limits].all()
    never = input_range(m).never
    assert never.sum() > 1000 and not motion.valid[never].any()


def test_slider_crank_batch_positions_close():
    rng = np.random.default_rng(20240102)
    m = random_slider_cranks(rng, 20_000)
    theta = np.concatenate(
        (rng.uniform(-np.pi, np.pi, (20_000, 32)), np.nan_to_num(limit_inputs(m))), axis=-1
    )
    motion = solve(m, theta, order=0)
    assert 0.3 < motion.valid.mean() < 0.9
    assert_closes(m, motion)
    limits = np.isfinite(limit_inputs(m))
    assert limits.sum() > 20_000 and motion.valid[:, 32:][limits].all()


def _single_inputs(m, data):
    """A handful of inputs for one mechanism: random ones and its exact limit positions."""
    theta = data.draw(st.lists(st.floats(-np.pi, np.pi), min_size=1, max_size=8))
    limits = limit_inputs(m)
    return np.concatenate((theta, limits[np.isfinite(limits)]))


@settings(max_examples=150, deadline=None)
@given(m=fourbars(), data=st.data())
def test_fourbar_single_positions_close(m, data):
    motion = solve(m, _single_inputs(m, data), order=2)
    assert_closes(m, motion)


@settings(max_examples=150, deadline=None)
@given(m=slider_cranks(), data=st.data())
def test_slider_crank_single_positions_close(m, data):
    motion = solve(m, _single_inputs(m, data), order=2)
    assert_closes(m, motion)


def test_assembly_sign_examples():
    """The documented assembly conventions on hand-checkable cases."""
    fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, assembly=1)
    B = solve(fb, [np.pi / 2], order=0).positions["B"][0]
    A = np.array([0.0, 1.0])
    assert cross(np.array([4.0, 0.0]) - A, B - A) > 0
    assert B[1] > 0  # the "open" assembly above the frame
    sc = SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, -0.5], line_angle=0.0, assembly=1)
    B = solve(sc, [0.0, np.pi / 2], order=0).positions["B"]
    assert np.all(B[:, 0] > [1.0, 0.0])  # ahead of A along +x
    np.testing.assert_allclose(B[:, 1], -0.5)


# ----------------------------------------------------------------------------------------------
# 5. Masking invariants
# ----------------------------------------------------------------------------------------------


def check_masks(motion):
    valid, regular = motion.valid, motion.regular
    assert not np.any(regular & ~valid)
    for name, pos in motion.positions.items():
        assert pos.shape == (*valid.shape, 2)
        np.testing.assert_array_equal(np.isnan(pos), np.broadcast_to(~valid[..., None], pos.shape))
        assert np.all(np.isfinite(pos[valid])), name
    for derivatives in (motion.velocities, motion.accelerations):
        for name, d in (derivatives or {}).items():
            np.testing.assert_array_equal(
                np.isnan(d), np.broadcast_to(~regular[..., None], d.shape)
            )
            assert np.all(np.isfinite(d[regular])), name


def test_masks_batch():
    rng = np.random.default_rng(20240501)
    for m in (random_fourbars(rng, 5000), random_slider_cranks(rng, 5000)):
        theta = np.concatenate(
            (rng.uniform(-np.pi, np.pi, (5000, 16)), np.nan_to_num(limit_inputs(m))), axis=-1
        )
        motion = solve(m, theta, order=2)
        check_masks(motion)
        assert 0.2 < motion.valid.mean() < 0.9
        check_masks(circuit(m, 37, order=2))
        for _, config in configurations(m, theta[:, :4], order=2):
            check_masks(config)
        check_masks(solve(m, theta, order=1))
        zero = solve(m, theta, order=0)
        assert zero.velocities is None and zero.accelerations is None
        check_masks(zero)


@settings(max_examples=100, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()), data=st.data())
def test_masks_single(m, data):
    theta = _single_inputs(m, data)
    check_masks(solve(m, theta))
    check_masks(circuit(m, data.draw(st.integers(2, 50))))


def test_exact_toggle_is_valid_but_not_regular():
    """A limit hit exactly: valid, but the derivatives do not exist and are masked.

    At θ = 0, A = (3, 0) and |B0 − A| = |(3, 4)| = 5 = coupler + rocker, all exact in binary:
    the margin is exactly 0, B lies on the line A–B0 and the 2×2 velocity system is singular.
    """
    m = FourBar(A0=[0, 0], B0=[6, 4], crank=3, coupler=2, rocker=3)
    motion = solve(m, [0.0, 0.1])
    assert motion.margins["B"][0] == 0.0
    np.testing.assert_array_equal(motion.valid, [True, True])
    np.testing.assert_array_equal(motion.regular, [False, True])
    check_masks(motion)
    arcs = input_range(m)
    assert np.nanmin(np.abs(np.concatenate((arcs.lo, arcs.hi)))) < 1e-15


# ----------------------------------------------------------------------------------------------
# 6. Batched equals one-by-one
# ----------------------------------------------------------------------------------------------


def _same(a, b):
    if a is None or b is None:
        return a is b
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def _row(x, i):
    if x is None:
        return None
    if isinstance(x, dict):
        return {k: v[i] for k, v in x.items()}
    return np.asarray(x)[i]


@pytest.mark.parametrize("family", ["fourbar", "slidercrank"])
def test_batch_equals_one_by_one(family):
    rng = np.random.default_rng(20240601)
    make = random_fourbars if family == "fourbar" else random_slider_cranks
    m = make(rng, 50)
    theta = rng.uniform(-np.pi, np.pi, 24)
    batch = {
        "solve": solve(m, theta, order=2),
        "circuit": circuit(m, 25, order=2),
        "analytic": input_range(m, method="analytic"),
        "numeric": input_range(m, method="numeric"),
        "configurations": configurations(m, theta[:5], order=1),
    }
    for i in range(50):
        one = take(m, i)
        for name, whole in (("solve", solve(one, theta, order=2)), ("circuit", circuit(one, 25))):
            part = batch[name]
            for field in (
                "input",
                "valid",
                "regular",
                "positions",
                "velocities",
                "accelerations",
                "branches",
                "margins",
            ):
                assert _same(getattr(whole, field), _row(getattr(part, field), i)), (name, field)
        for name in ("analytic", "numeric"):
            arcs, part = input_range(one, method=name), batch[name]
            k = arcs.lo.shape[-1]
            for field in ("full", "never"):
                assert _same(getattr(arcs, field), _row(getattr(part, field), i))
            for field in ("lo", "hi", "dyad_lo", "dyad_hi"):
                row = _row(getattr(part, field), i)
                assert _same(getattr(arcs, field), row[:k]), (name, field)
                pad = -1 if field.startswith("dyad") else np.nan
                assert _same(row[k:], np.full(row[k:].shape, pad))
        for (signs, whole), (signs_b, part) in zip(
            configurations(one, theta[:5], order=1), batch["configurations"], strict=True
        ):
            assert signs == signs_b
            assert _same(whole.positions, _row(part.positions, i))
            assert _same(whole.velocities, _row(part.velocities, i))


def test_batch_shapes_broadcast():
    """Scalar fields broadcast against batched ones; inputs may be per-mechanism."""
    rng = np.random.default_rng(20240602)
    crank = rng.uniform(0.1, 0.5, (3, 4))
    m = FourBar(A0=[0, 0], B0=[2, 0], crank=crank, coupler=2.0, rocker=1.5)
    assert m.batch_shape == (3, 4)
    theta = rng.uniform(-np.pi, np.pi, (3, 4, 7))
    motion = solve(m, theta)
    assert motion.positions["P"].shape == (3, 4, 7, 2)
    one = FourBar(A0=[0, 0], B0=[2, 0], crank=crank[1, 2], coupler=2.0, rocker=1.5)
    assert _same(solve(one, theta[1, 2]).positions, _row(_row(motion.positions, 1), 2))


# ----------------------------------------------------------------------------------------------
# Plans directly
# ----------------------------------------------------------------------------------------------


def test_evaluate_branch_override_matches_assembly():
    """A per-sample branch override is the same as rebuilding with that assembly."""
    rng = np.random.default_rng(20240701)
    m = random_fourbars(rng, 200, near=0.0)
    theta = rng.uniform(-np.pi, np.pi, 16)
    flipped = evaluate(
        m.plan,
        m.params(),
        theta,
        points=m.point_fields,
        branches={"B": -np.asarray(m.assembly)[:, None]},
    )
    other = solve(m.with_assembly(-np.asarray(m.assembly)), theta)
    assert _same(flipped.positions, other.positions)
    assert _same(flipped.accelerations, other.accelerations)


def test_plan_rejects_bad_order():
    from linkwright.engine import Crank, Fixed, Plan

    with pytest.raises(ValueError, match="not placed before"):
        Plan((Crank("A", "A0", 1.0), Fixed("A0", "A0")), traced=("A",))
    with pytest.raises(ValueError, match="placed twice"):
        Plan((Fixed("A0", "A0"), Fixed("A0", "A0")), traced=("A0",))
    with pytest.raises(ValueError, match="traced joint"):
        Plan((Fixed("A0", "A0"),), traced=("P",))

"""Six-bar positions, branch signs, derivatives and configurations against independent geometry.

Two kinds of check, as in the four-bar engine tests: NumPy batches of thousands of random
six-bars per family in one call, and Hypothesis ``@given`` tests on single six-bars drawn from
the same space (tests/sixbar_helpers.py). Derivatives are checked against eighth-order central
finite differences of the positions.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sixbar_helpers import (
    DERIVATIVE_TOL,
    EXAMPLE_NAMES,
    FAR_PIVOT,
    SIXBARS,
    assert_closes,
    check_masks,
    col,
    cross,
    example,
    make,
    norm,
    random_draws,
    random_sixbars,
    sixbars,
    size_of,
)

from linkwright.mechanisms import (
    FourBar,
    configurations,
    solve,
)

# ----------------------------------------------------------------------------------------------
# 1. Positions: every constraint holds, on the requested branches
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_batch_positions_close(cls):
    rng = np.random.default_rng(20250101 + SIXBARS.index(cls))
    draws_ = random_draws(rng, 4000)
    m = make(cls, draws_)
    # Random inputs, and theta0, where a share of the dyads sit exactly at a limit.
    theta = np.concatenate((rng.uniform(-np.pi, np.pi, (4000, 24)), draws_["theta0"][:, None]), -1)
    motion = solve(m, theta, order=2)
    assert 0.1 < motion.valid.mean() < 0.9, motion.valid.mean()
    # An exact limit position is assembled (within rounding), where the four-bar closes.
    four = solve(FourBar(m.A0, m.B0, m.crank, m.coupler, m.rocker), theta[:, -1:], order=0)
    at_limit = (draws_["limit"] > 0) & (draws_["delta"] == 0) & four.valid[:, 0]
    assert at_limit.sum() > 50 and motion.valid[at_limit, -1].all()
    assert np.abs(motion.margins["D"][at_limit, -1]).max() < 1e-12
    assert_closes(m, motion)
    check_masks(motion)
    # The family's scale is the size recomputed here.
    np.testing.assert_allclose(m.scale, size_of(m), rtol=1e-15)


@settings(max_examples=120, deadline=None)
@given(drawn=sixbars(), data=st.data())
def test_single_positions_close(drawn, data):
    m, theta0 = drawn
    theta = np.concatenate(
        (data.draw(st.lists(st.floats(-np.pi, np.pi), min_size=1, max_size=8)), theta0)
    )
    motion = solve(m, theta, order=2)
    assert_closes(m, motion)
    check_masks(motion)


def test_branch_sign_examples():
    """The documented sign conventions on the bundled examples at θ = 0 (integer joints)."""
    for cls, name in zip(SIXBARS, EXAMPLE_NAMES, strict=True):
        m = example(name)
        p = {k: v[0] for k, v in solve(m, [0.0], order=0).positions.items()}
        X = p[FAR_PIVOT[cls]]
        assert np.sign(cross(p["B0"] - p["A"], p["B"] - p["A"])) == m.assembly
        assert np.sign(cross(X - p["C"], p["D"] - p["C"])) == m.assembly2
        for k, v in p.items():
            np.testing.assert_allclose(v, np.round(v * 2) / 2, atol=1e-14, err_msg=k)


# ----------------------------------------------------------------------------------------------
# 2. Derivatives against finite differences
# ----------------------------------------------------------------------------------------------

# Eighth-order central differences on θ + kh, k = −4..4 (as in test_engine_derivatives.py).
D1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0.0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])


D2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])


STENCIL = np.arange(-4, 5)


# The stencil spans ±0.04 rad of the fastest link's rotation: truncation ~ (hω)^8/630, rounding
# ~ eps·(coordinates)/(hω)² ≈ 1e-12 for frames 10 sizes from the origin; both far below 1e-7.
H_OMEGA = 0.01


def check_derivatives_by_differences(m, theta, *, min_margin=0.2):
    """Analytic velocities and accelerations against 8th-order central differences of positions.

    Where the whole stencil is valid and both dyads' margins (sin² of their angles) stay above
    ``min_margin`` on it (near a limit the derivatives blow up like 1/sqrt and differences
    fail), and each dyad's pivots stay well apart (see below).
    The step is scaled by the fastest link's rate ω (read off the motion only to pick h), the
    errors are relative to size·ω^k. Returns the number of samples compared.
    """
    motion = solve(m, theta, order=2)
    s = col(size_of(m))
    X = FAR_PIVOT[type(m)]
    links = [
        ("A0", "A", m.crank),
        ("A", "B", m.coupler),
        ("B0", "B", m.rocker),
        ("C", "D", m.link1),
        (X, "D", m.link2),
    ]
    omega = np.ones_like(motion.input)
    for p, q, length in links:
        dv = norm(motion.velocities[q] - motion.velocities[p]) / col(length)
        da = norm(motion.accelerations[q] - motion.accelerations[p]) / col(length)
        omega = np.fmax(omega, np.fmax(dv, np.sqrt(da)))
    h = H_OMEGA / omega
    stencil = motion.input[..., None] + STENCIL * h[..., None]
    shape = stencil.shape
    around = solve(m, stencil.reshape(*shape[:-2], -1), order=0)
    margin = np.minimum(around.margins["B"], around.margins["D"]).reshape(shape)
    ok = motion.regular & around.valid.reshape(shape).all(-1) & (margin.min(-1) > min_margin)
    # Where a dyad's pivots meet (a rhombus's crank passing over B0) its branch, a side of the
    # line through them, changes meaning, and a stencil across that input differences two
    # branches; nearby, the direction of their difference carries rounding ~eps·|x|/distance.
    # So the pivots must stay apart by more than the stencil lets them close in (16h·|Δv|).
    for p1, p2 in (("A", "B0"), ("C", X)):
        apart = norm(around.positions[p2] - around.positions[p1]).reshape(shape).min(-1)
        closing = norm(motion.velocities[p2] - motion.velocities[p1])
        ok &= apart > 16 * h * closing + 1e-3 * s
    for joint in m.reported_joints:
        pos = around.positions[joint].reshape(*shape, 2)
        vel = np.einsum("k,...kd->...d", D1, pos) / h[..., None]
        acc = np.einsum("k,...kd->...d", D2, pos) / h[..., None] ** 2
        ev = norm(vel - motion.velocities[joint]) / (s * omega)
        ea = norm(acc - motion.accelerations[joint]) / (s * omega**2)
        assert np.all(ev[ok] <= DERIVATIVE_TOL), (joint, np.max(ev[ok]))
        assert np.all(ea[ok] <= DERIVATIVE_TOL), (joint, np.max(ea[ok]))
    return int(ok.sum())


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_batch_derivatives_match_differences(cls):
    rng = np.random.default_rng(20250201 + SIXBARS.index(cls))
    m = random_sixbars(cls, rng, 2000, near=0.1)
    compared = check_derivatives_by_differences(m, rng.uniform(-np.pi, np.pi, (2000, 8)))
    assert compared > 600


@settings(max_examples=60, deadline=None)
@given(drawn=sixbars(), data=st.data())
def test_single_derivatives_match_differences(drawn, data):
    m, _ = drawn
    theta = np.array(data.draw(st.lists(st.floats(-np.pi, np.pi), min_size=1, max_size=6)))
    check_derivatives_by_differences(m, theta)


# ----------------------------------------------------------------------------------------------
# 3. Every configuration
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_configurations(cls):
    rng = np.random.default_rng(20250301 + SIXBARS.index(cls))
    m = random_sixbars(cls, rng, 2000)
    theta = rng.uniform(-np.pi, np.pi, (2000, 8))
    configs = configurations(m, theta, order=1)
    assert sorted(signs for signs, _ in configs) == [(-1, -1), (-1, 1), (1, -1), (1, 1)]
    own = solve(m, theta, order=1)
    mine = (np.asarray(m.assembly), np.asarray(m.assembly2))
    real = np.zeros(theta.shape, dtype=int)
    for (s1, s2), motion in configs:
        signs = {"B": np.full(theta.shape, float(s1)), "D": np.full(theta.shape, float(s2))}
        assert_closes(m, motion, signs)
        real += motion.valid
        # The configuration with the mechanism's own signs is its solve, bit for bit.
        same = (mine[0] == s1) & (mine[1] == s2)
        for joint in m.reported_joints:
            np.testing.assert_array_equal(motion.positions[joint][same], own.positions[joint][same])
            np.testing.assert_array_equal(
                motion.velocities[joint][same], own.velocities[joint][same]
            )
    # A four-bar that closes has two branches; each carries a dyad closing on both or neither.
    four = solve(FourBar(m.A0, m.B0, m.crank, m.coupler, m.rocker), theta, order=0).valid
    assert np.all(real[~four] == 0)
    assert np.all(np.isin(real[four], (0, 2, 4)))
    assert {0, 2, 4} <= set(np.unique(real[four]).tolist())

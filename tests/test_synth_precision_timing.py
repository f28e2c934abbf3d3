"""Path generation with prescribed timing against independent checks: a four-bar's own coupler
points at its own crank rotations give it back, and a design meets its points at the crank
rotations asked for (positions from the closed form of tests/synth_precision_helpers.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from synth_precision_helpers import TOL, coord, fourbar_poses, wrap

from linkwright.mechanisms import configurations
from linkwright.synthesis.precision import (
    PrecisionError,
    path_with_timing,
)

# --- path generation with prescribed timing ------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(fourbar_poses(3))
def test_path_with_timing_recovers_the_fourbar(case):
    fb, _, thetas, points, angles, states = case
    beta = thetas[1:] - thetas[0]
    alpha = angles[1:] - angles[0]
    rocker = [math.atan2(*(s[1] - fb[1])[::-1]) for s in states]
    gamma = np.array(rocker[1:]) - rocker[0]
    # A coupler that only translates (or turns with a ground link) leaves that dyad free.
    for turn in (alpha, beta - alpha, gamma - alpha):
        assume(np.min(np.abs(wrap(turn))) > 0.02)
    design = path_with_timing(points, beta, alpha, gamma)
    m = design.mechanism
    scale = 10 * max(1.0, np.max(np.abs(points)))
    assert np.allclose(m.A0, fb[0], atol=1e-8 * scale)
    assert np.allclose(m.B0, fb[1], atol=1e-8 * scale)
    assert np.allclose([m.crank, m.coupler, m.rocker, m.u, m.v], fb[2:], atol=1e-8 * scale)


@settings(max_examples=30, deadline=None)
@given(
    pts=st.lists(st.tuples(coord, coord), min_size=3, max_size=3),
    turns=st.lists(st.floats(0.3, 2.5), min_size=6, max_size=6),
)
def test_path_with_timing_meets_the_points_at_the_crank_rotations(pts, turns):
    points = np.array(pts)
    assume(
        np.min(np.linalg.norm(points[:, None] - points[None], axis=-1)[np.triu_indices(3, 1)]) > 0.2
    )
    beta, alpha, gamma = np.array(turns[:2]), np.array(turns[2:4]) - 1.4, np.array(turns[4:])
    try:
        design = path_with_timing(points, beta, alpha, gamma)
    except PrecisionError as exc:
        # Free choices that leave a dyad undetermined, or make the two one, are refused.
        assume(not any(w in str(exc) for w in ("singular", "coincide", "folded")))
        raise
    assert np.allclose(wrap(design.inputs[1:] - design.inputs[0] - beta), 0.0, atol=1e-9)
    # Simulated at θ1 + βj on each point's assembly, P passes Pj.
    theta = design.inputs[0] + np.concatenate(([0.0], beta))
    for sign, motion in configurations(design.mechanism, theta):
        at = design.branches == sign[0]
        spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
        assert np.max(
            np.linalg.norm(motion.positions["P"][at] - points[at], axis=-1), initial=0
        ) <= (TOL * spread * 10)


def test_path_with_timing_errors():
    pts = [[0, 0], [1, 0.5], [2, 0]]
    with pytest.raises(PrecisionError, match="crank dyad's equations are singular"):
        path_with_timing(pts, [0.3, 0.6], [0.3, 0.6], [0.2, 0.4])
    with pytest.raises(PrecisionError, match="points 1 and 2 coincide"):
        path_with_timing([[0, 0], [0, 0], [2, 0]], [0.3, 0.6], [0.1, 0.2], [0.2, 0.4])
    with pytest.raises(PrecisionError, match="exactly 3"):
        path_with_timing(pts[:2], [0.3, 0.6], [0.1, 0.2], [0.2, 0.4])
    # Two points at one crank angle: only a folded linkage (A on B0) can do it, and there the
    # input does not fix the coupler.
    with pytest.raises(PrecisionError, match="position 2 the crank pin A lies on the rocker"):
        path_with_timing([[0, 0], [0, 1], [0, 0.5]], [1.0, 1.0], [0.6, -0.4], [2.0, 1.0])
    with pytest.raises(PrecisionError, match="dyads would coincide"):
        path_with_timing(pts, [0.3, 0.6], [0.1, 0.2], [0.3, 0.6])

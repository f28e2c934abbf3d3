"""Approximate motion generation from n ≥ 3 poses (issue 28, item 3).

Every number is recomputed here from the returned linkage: it is solved by the engine at the
inputs it reports, and its pose point and body angle (the coupler line's angle plus the
reported offset) compared with the poses. Poses traced from a known four-bar or slider-crank
must come back met exactly; noisy poses must be met about as well as the noise allows, by a
least-squares optimum (no nearby linkage does better).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from synth_helpers import FAST, run_cli

from linkwright.io import parse_document
from linkwright.mechanisms import DoubleSlider, FourBar, SliderCrank, solve
from linkwright.synthesis.motion_fit import fit_motion
from linkwright.synthesis.precision_designs import PrecisionError


def _poses(mech, inputs):
    m = solve(mech, inputs, order=0)
    line = m.positions["B"] - m.positions["A"]
    return m.positions["P"], np.arctan2(line[:, 1], line[:, 0])


def _diameter(points):
    return float(np.max(np.linalg.norm(points[:, None] - points[None], axis=-1)))


def _recomputed(fit, points, angles, weight, spread):
    """(position misses, angle misses, error) of a fit, from the engine and the poses alone."""
    m = solve(fit.mechanism, fit.inputs, order=0)
    assert m.valid.all()
    dp = np.linalg.norm(m.positions["P"] - points, axis=1)
    # The coupler line: A → B, or R → Q on a double slider (MotionFit's documented offset).
    start, end = ("A", "B") if "A" in m.positions else ("R", "Q")
    line = m.positions[end] - m.positions[start]
    turned = np.arctan2(line[:, 1], line[:, 0]) + fit.angle_offset
    da = np.abs(np.angle(np.exp(1j * (turned - angles))))
    return dp, da, float(np.sum(dp**2 + (weight * spread * da) ** 2))


@FAST
@given(st.integers(0, 2**32 - 1), st.integers(6, 10))
def test_poses_of_a_known_four_bar_are_met(seed, n):
    rng = np.random.default_rng(seed)
    true = FourBar(
        A0=[0, 0], B0=[rng.uniform(1.8, 2.4), 0], crank=rng.uniform(0.6, 1.0),
        coupler=rng.uniform(2.0, 2.6), rocker=rng.uniform(1.6, 2.2),
        u=rng.uniform(0.3, 1.2), v=rng.uniform(-0.6, 0.6),
    )  # fmt: skip
    points, angles = _poses(true, np.linspace(0.3, 0.3 + rng.uniform(2.0, 4.0), n))
    best = fit_motion(points, angles)[0]
    spread = _diameter(points)
    dp, da, error = _recomputed(best, points, angles, 1.0, spread)
    assert error == pytest.approx(best.error, abs=1e-18 * spread**2, rel=1e-6)
    assert np.max(dp) < 1e-7 * spread and np.max(da) < 1e-7


def test_poses_of_a_slider_crank_are_met_by_one():
    sc = SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, 0.3], line_angle=0.2, u=1.2, v=0.7)
    points, angles = _poses(sc, np.radians(np.linspace(20, 200, 9)))
    best = fit_motion(points, angles)[0]
    assert isinstance(best.mechanism, SliderCrank)
    dp, da, _ = _recomputed(best, points, angles, 1.0, 1.0)
    assert np.max(dp) < 1e-8 and np.max(da) < 1e-8


@FAST
@given(st.integers(0, 2**32 - 1), st.integers(6, 10))
def test_poses_of_a_double_slider_are_met_by_one(seed, n):
    """An elliptic trammel's body: two of its points run on lines (two PR dyads), so a double
    slider meets its poses exactly (as may a slider-crank through its Cardan circle's centre,
    which runs on a circle about M)."""
    rng = np.random.default_rng(seed)
    true = DoubleSlider(
        M=rng.uniform(-2, 2, 2), alpha=rng.uniform(0.5, 2.6), beta=rng.uniform(-np.pi, np.pi),
        p=rng.uniform(0.5, 2.0), q=rng.uniform(0.5, 2.0), h=rng.uniform(-1.0, 1.0),
    )  # fmt: skip
    m = solve(true, np.sort(rng.uniform(0, 2 * np.pi, n)), order=0)
    points = m.positions["P"]
    line = m.positions["Q"] - m.positions["R"]
    angles = np.arctan2(line[:, 1], line[:, 0]) + rng.uniform(-np.pi, np.pi)
    spread = _diameter(points)
    fits = [f for f in fit_motion(points, angles) if isinstance(f.mechanism, DoubleSlider)]
    assert fits
    dp, da, error = _recomputed(fits[0], points, angles, 1.0, spread)
    assert error == pytest.approx(fits[0].error, abs=1e-18 * spread**2, rel=1e-6)
    assert np.max(dp) < 1e-7 * spread and np.max(da) < 1e-7


def test_noisy_poses_are_met_by_a_least_squares_optimum():
    rng = np.random.default_rng(7)
    true = FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=2.5, rocker=1.5, u=1, v=0.5)
    points, angles = _poses(true, np.radians(np.linspace(40, 200, 12)))
    points = points + rng.normal(scale=0.01, size=points.shape)
    angles = angles + rng.normal(scale=0.01, size=angles.shape)
    spread = _diameter(points)
    best = fit_motion(points, angles, angle_weight=0.5)[0]
    dp, da, error = _recomputed(best, points, angles, 0.5, spread)
    assert error == pytest.approx(best.error, rel=1e-9)
    # As well as the noise allows: misses of the order of the noise.
    assert np.sqrt(np.mean(dp**2)) < 0.03 and np.sqrt(np.mean(da**2)) < 0.03
    # No better than the true linkage at its own best inputs would be a bug; no worse than it
    # either, since it is a point the search could reach.
    own = _poses(true, np.radians(np.linspace(40, 200, 12)))
    turn = np.angle(np.exp(1j * (own[1] - angles)))
    truth = float(np.sum(np.linalg.norm(own[0] - points, axis=1) ** 2 + (0.5 * spread * turn) ** 2))
    assert best.error <= truth * 1.0001


@pytest.mark.parametrize(("points", "angles"), [([[0, 0], [1, 0]], [0, 1])])
def test_too_few_poses_are_refused(points, angles):
    with pytest.raises(PrecisionError, match="n ≥ 3 poses"):
        fit_motion(points, angles)


def test_synth_motion_ranks_linkages_for_many_poses(tmp_path):
    rng = np.random.default_rng(1)
    true = FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=2.5, rocker=1.5, u=1, v=0.5)
    points, angles = _poses(true, np.radians(np.linspace(40, 200, 8)))
    points = points + rng.normal(scale=0.01, size=points.shape)
    table = tmp_path / "poses.csv"
    np.savetxt(table, np.c_[points, np.degrees(angles)], delimiter=",")
    code, out, err = run_cli("synth", "motion", "--poses", str(table), "--top", "3", "--json")
    assert code == 0, err
    report = json.loads(out)
    assert report["method"] == "least squares" and len(report["designs"]) == 3
    errors = [d["error"] for d in report["designs"]]
    assert errors == sorted(errors) or any(d["branch_defect"] for d in report["designs"])
    for d in report["designs"]:
        mech = parse_document(d["mechanism"]).mechanism
        m = solve(mech, np.radians(d["inputs_deg"]), order=0)
        miss = np.linalg.norm(m.positions["P"] - points, axis=1)
        assert math.sqrt(np.mean(miss**2)) == pytest.approx(d["rms_position_error"], rel=1e-6)
    code, out, err = run_cli("synth", "motion", "--poses", str(table), "--top", "1")
    assert code == 0 and out.startswith("# 1 linkages nearest to 8 poses")

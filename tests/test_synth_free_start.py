"""Prescribed timing with a free start (issue 28, item 2): the angles give the input's steps,
and where the input starts is fitted with the dimensions.

The targets are traced here from a known crank-rocker at inputs s + steps, s unknown to the
fit; the fitted linkage is solved again by the plan-based engine at the inputs it reports,
which must reproduce the targets and keep the prescribed steps exactly.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from synth_helpers import FAST, run_cli

from linkwright.mechanisms import FourBar, solve
from linkwright.synthesis.path import PathSynthesisError, fit_path

EXACT_FIT = {"budget": 600, "max_evaluations": 200_000}


def _diameter(pts: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(pts[:, None] - pts[None], axis=-1)))


@FAST
@given(st.integers(0, 2**32 - 1))
def test_a_free_start_finds_where_the_steps_begin(seed):
    rng = np.random.default_rng(seed)
    true = FourBar(
        A0=[0, 0],
        B0=[rng.uniform(2.6, 3.8), 0],
        crank=rng.uniform(0.4, 0.9),  # Grashof crank-rocker: every input assembles
        coupler=rng.uniform(2.6, 3.8),
        rocker=rng.uniform(2.6, 3.8),
        u=rng.uniform(-1.5, 1.5),
        v=rng.uniform(-1.5, 1.5),
    )
    steps = np.sort(rng.uniform(0, 2 * np.pi, 6))
    steps -= steps[0]
    start = rng.uniform(-np.pi, np.pi)
    pts = solve(true, start + steps, order=0).positions["P"]
    size = _diameter(pts)
    assume(size > 0.2)  # the default bounds scale with the targets' size
    fit = fit_path("fourbar", pts, angles=steps, free_start=True, seed=seed % 1000, **EXACT_FIT)
    again = solve(fit.mechanism, fit.inputs, order=0)
    assert again.valid.all()
    assert np.max(np.linalg.norm(again.positions["P"] - pts, axis=-1)) < 1e-6 * size
    # The steps are the prescribed ones; only where they start moved.
    np.testing.assert_allclose(np.diff(fit.inputs), np.diff(steps), atol=1e-12)
    # Where they start is reported within the first turn (the search may wander by whole turns).
    assert 0.0 <= fit.angles[0] < 2 * np.pi
    assert fit.stopped == "target"


def test_a_free_start_needs_prescribed_angles():
    pts = [[0, 0], [1, 0], [1, 1], [0, 1]]
    with pytest.raises(PathSynthesisError, match="free_start: frees where prescribed angles"):
        fit_path("fourbar", pts, timing="free", free_start=True)


def test_synth_path_free_start_on_the_command_line(tmp_path):
    true = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3.5, u=2, v=1)
    steps = np.arange(6) * 60.0
    pts = solve(true, np.radians(75.0 + steps), order=0).positions["P"]
    table = tmp_path / "points.csv"
    np.savetxt(table, pts, delimiter=",")
    common = ["synth", "path", "--family", "fourbar", "--points", str(table), "--quiet"]
    code, _, err = run_cli(*common, "--free-start")
    assert code != 0 and err.count("\n") == 1 and "give --angles too" in err
    code, out, err = run_cli(
        *common, "--json", "--angles", ",".join(f"{a:g}" for a in steps), "--free-start",
        "--seed", "1", "--budget", "600", "--evaluations", "200000",
    )  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    np.testing.assert_allclose(np.diff(result["inputs_deg"]), np.diff(steps), atol=1e-9)
    assert result["rms"] <= 1e-6 * _diameter(pts)

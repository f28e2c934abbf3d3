"""Tolerance bands (analysis/tolerance.py, `linkwright tolerance`), checked against linkages
rebuilt and solved again: every corner of the tolerance box, uniform Monte Carlo, and a plain
one-sided difference of the engine's positions."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES

from linkwright.analysis.tolerance import ToleranceError, monte_carlo, tolerance_band
from linkwright.cli import main
from linkwright.io import load_example
from linkwright.mechanisms import FourBar, SphericalFourBar, solve
from linkwright.mechanisms.parameters import parameter_vector

FB = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5, u=1.5, v=1)
SF = SphericalFourBar(*np.radians([60, 25, 50, 45, 30, 40]))


def _every_corner(mech, band) -> np.ndarray:
    """Largest displacement along the nominal normal over all 2^k corners, solved by the engine
    (the worst case of a linear model sits at a corner; the band claims it to first order)."""
    vector = parameter_vector(mech)
    index = [vector.index(n) for n in band.names]
    signs = np.array(list(itertools.product([-1.0, 1.0], repeat=len(index))))
    x = np.repeat(vector.to_vector(mech)[None], len(signs), axis=0)
    x[:, index] += signs * band.tolerances
    m = solve(vector.from_vector(mech, x), band.inputs, order=0)
    moved = m.positions[band.point] - band.curve
    return np.max(np.abs(np.einsum("tnd,nd->tn", moved, band.normal)), axis=0)


def test_worst_corner_matches_the_first_order_band_with_second_order_error() -> None:
    gaps = []
    for t in (1e-2, 5e-3):
        band = tolerance_band(FB, t, samples=48)
        worst = _every_corner(FB, band)
        gaps.append(np.max(np.abs(worst - band.half_width) / band.half_width))
    # The gap is the second-order term over a first-order width: O(t), so it halves with t.
    assert gaps[0] < 0.02 and gaps[1] < 0.6 * gaps[0]


@pytest.mark.parametrize("mech, tol", [(FB, 1e-3), (SF, np.radians(0.05))])
def test_uniform_monte_carlo_std_agrees_with_the_predicted_std(mech, tol) -> None:
    band = tolerance_band(mech, tol, samples=24)
    mc = monte_carlo(mech, band, 8000, seed=3)
    assert not mc.failed.any()
    # 8000 trials: the sample std's relative error is about 1/sqrt(2·8000) = 0.8 % (σ); 4 %
    # bounds it over 24 samples, and the first-order model's own error is O(tol) smaller.
    assert np.max(np.abs(np.std(mc.normal, 0) / band.std - 1)) < 0.04
    assert np.max(np.abs(np.std(mc.output, 0) / band.output_std - 1)) < 0.04
    # Every trial stays inside the worst-case band (to second order in the tolerance).
    assert np.all(np.abs(mc.normal) <= band.half_width * 1.01)


def test_sensitivities_agree_with_a_one_sided_difference_of_the_engine() -> None:
    band = tolerance_band(FB, 1e-2, samples=12)
    vector = parameter_vector(FB)
    h = 1e-7
    for k, name in enumerate(band.names):
        x = vector.to_vector(FB)
        x[vector.index(name)] += h
        moved = solve(vector.from_vector(FB, x), band.inputs, order=0).positions["P"]
        fd = np.einsum("nd,nd->n", (moved - band.curve) / h, band.normal)
        assert np.max(np.abs(fd - band.sensitivity[:, k])) < 1e-5


def test_relative_and_per_field_tolerances() -> None:
    band = tolerance_band(FB, 0.01, relative=True, samples=8)
    t = dict(zip(band.names, band.tolerances, strict=True))
    assert t["crank"] == pytest.approx(0.01) and t["rocker"] == pytest.approx(0.035)
    assert t["A0.x"] == pytest.approx(0.04)  # coordinates: of the size, the largest link (4)
    only = tolerance_band(FB, {"crank": 0.01}, samples=8)
    assert only.names == ("crank",)
    assert np.allclose(
        only.half_width, np.abs(band.sensitivity[:, band.names.index("crank")]) * 0.01
    )


@pytest.mark.parametrize(
    "call, words",
    [
        (lambda: tolerance_band(FB, {"nope": 0.1}), "no parameter 'nope'"),
        (lambda: tolerance_band(FB, -0.1), "not negative"),
        (lambda: tolerance_band(FB, 0.1, samples=10**6), "samples must be"),
        (lambda: monte_carlo(FB, tolerance_band(FB, 0.1, samples=8), 10**6), "Monte Carlo"),
    ],
)
def test_bad_requests_are_one_line_errors(call, words) -> None:
    with pytest.raises(ToleranceError, match=words) as info:
        call()
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("key", sorted(FAMILY_EXAMPLES))
def test_every_family_gets_a_band_or_a_clear_refusal(key) -> None:
    mech = load_example(FAMILY_EXAMPLES[key]).mechanism
    try:
        band = tolerance_band(mech, 1e-4, relative=True, samples=16)
    except ToleranceError as exc:
        assert "\n" not in str(exc)
        return
    assert np.all(np.isfinite(band.half_width)) and np.all(band.half_width >= 0)
    mc = monte_carlo(mech, band, 64, seed=1, corners=True)
    ok = mc.failed == 0
    if ok.any():
        assert np.all(np.abs(mc.normal[ok]) <= band.half_width * 1.05 + 1e-12)


def test_cli_tolerance_json_csv_and_plot(tmp_path, capsys) -> None:
    out = tmp_path / "band.png"
    args = ["tolerance", "crank-rocker", "--tol", "0.01", "-n", "12", "--json"]
    assert main([*args, "--monte-carlo", "300", "--plot", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["half_width"]) == 12 and out.stat().st_size > 1000
    worst = np.array(doc["monte_carlo"]["max_deviation"])
    assert np.all(worst <= np.array(doc["half_width"]) * 1.01)
    assert main(["tolerance", "crank-rocker", "--tol", "0.01", "-n", "4", "--csv"]) == 0
    assert capsys.readouterr().out.splitlines()[0].startswith("input_deg,half_width")
    assert main(["tolerance", "crank-rocker", "--tol", "0.01", "--monte-carlo", "90000"]) != 0
    err = capsys.readouterr().err
    assert err.startswith("error: Monte Carlo") and err.count("\n") == 1

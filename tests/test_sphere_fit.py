"""Spherical targets on any sphere (issue 28, item 5): the sphere is fitted first.

Points are placed here on a sphere of known centre and radius, over caps as small as 10°; the
fit must give them back, and `synth path` and `atlas query` must report that sphere and work
on the points' directions from its centre.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from synth_helpers import run_cli

from linkwright.geometry.sphere_fit import SphereFitError, fit_sphere
from linkwright.mechanisms import SphericalFourBar, circuit


def _cap_points(rng, centre, radius, cap, n):
    """n points spread over the cap of angular radius ``cap`` about a random axis."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    helper = np.eye(3)[np.argmin(np.abs(axis))]
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    polar = np.arccos(rng.uniform(np.cos(cap), 1.0, n))
    turn = rng.uniform(0, 2 * np.pi, n)
    # Three points on the cap's rim (on the equator for a cap past it: the rim of a whole
    # sphere is one point), so that the points are never nearly coplanar by chance.
    polar[:3] = min(cap, np.pi / 2)
    turn[:3] = [0.0, 2.1, 4.2]
    around = np.cos(turn)[:, None] * e1 + np.sin(turn)[:, None] * e2
    directions = np.cos(polar)[:, None] * axis + np.sin(polar)[:, None] * around
    return centre + radius * directions, directions


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.floats(1e-3, 1e3),
    st.floats(math.radians(10), math.pi),
    st.integers(5, 60),
)
def test_points_on_a_cap_give_their_sphere_back(seed, radius, cap, n):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-10, 10, 3) * radius
    points, directions = _cap_points(rng, centre, radius, cap, n)
    fitted = fit_sphere(points)
    # Rounding in the points (ε·|p|) moves a cap's centre by about that over the cap's
    # flatness, 1 − cos(cap) ≥ 0.015 here.
    scale = float(np.max(np.abs(points))) / radius
    tol = 1e-11 * scale / (1 - math.cos(cap))
    assert fitted.radius == pytest.approx(radius, rel=tol)
    np.testing.assert_allclose(fitted.centre, centre, atol=tol * radius)
    np.testing.assert_allclose(fitted.directions, directions, atol=tol)
    assert fitted.rms <= tol * radius


def test_noisy_points_are_fitted_in_least_squares():
    rng = np.random.default_rng(4)
    points, _ = _cap_points(rng, np.array([1.0, -2.0, 0.5]), 3.0, math.radians(60), 400)
    noisy = points + rng.normal(scale=1e-3, size=points.shape)
    fitted = fit_sphere(noisy)
    assert fitted.radius == pytest.approx(3.0, abs=2e-3)
    assert fitted.rms == pytest.approx(1e-3, rel=0.2)

    # A least-squares optimum: no nearby sphere is closer to the points.
    def cost(c, r):
        return float(np.sum((np.linalg.norm(noisy - c, axis=1) - r) ** 2))

    best = cost(fitted.centre, fitted.radius)
    for step in rng.normal(scale=1e-4, size=(30, 4)):
        assert best <= cost(fitted.centre + step[:3], fitted.radius + step[3]) * (1 + 1e-12)


@pytest.mark.parametrize(
    ("points", "words"),
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0]], "lie in one plane"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "at least 4 points"),
        ([[1, 1, 1]] * 5, "all coincide"),
        ([[0, 0, 0], [1, 0, np.nan], [0, 1, 0], [0, 0, 1]], "finite"),
    ],
)
def test_points_that_fix_no_sphere_are_refused(points, words):
    with pytest.raises(SphereFitError, match=words):
        fit_sphere(points)


@pytest.fixture
def flap_path(tmp_path):
    """Paper 000's Fig. 6 coupler curve, shrunk to a radius of 0.059 about (0.1, 0.2, 0.3)."""
    m = SphericalFourBar(frame=np.radians(40), crank=np.radians(20), coupler=np.radians(45),
                         rocker=np.radians(35), point_arc=np.radians(50),
                         point_angle=np.radians(130))  # fmt: skip
    unit = circuit(m, 36, order=0).positions["P"][::3]
    table = tmp_path / "flap.csv"
    np.savetxt(table, np.array([0.1, 0.2, 0.3]) + 0.059 * unit, delimiter=",")
    return table


def test_synth_path_fits_the_sphere_of_its_targets(flap_path):
    code, out, err = run_cli(
        "synth", "path", "--family", "spherical-fourbar", "--points", str(flap_path),
        "--no-timing", "--closed", "--json", "--quiet", "--evaluations", "3000",
        "--budget", "600",
    )  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    np.testing.assert_allclose(result["sphere"]["centre"], [0.1, 0.2, 0.3], atol=1e-12)
    assert result["sphere"]["radius"] == pytest.approx(0.059, rel=1e-12)
    code, out, err = run_cli(
        "synth", "path", "--family", "spherical-fourbar", "--points", str(flap_path),
        "--no-timing", "--quiet", "--evaluations", "2000", "--budget", "600",
    )  # fmt: skip
    assert code == 0, err
    assert out.startswith("the points lie on the sphere of radius 0.059 about (0.1, 0.2, 0.3)")


def test_atlas_query_fits_the_sphere_of_its_curve(flap_path):
    code, out, err = run_cli(
        "atlas", "query", "--family", "spherical-fourbar", "--points", str(flap_path),
        "--top", "2", "--json", "--quiet",
    )  # fmt: skip
    assert code == 0, err
    result = json.loads(out)
    assert result["sphere"]["radius"] == pytest.approx(0.059, rel=1e-12)
    assert len(result["matches"]) == 2


def test_planar_points_given_for_the_sphere_are_one_line(tmp_path):
    table = tmp_path / "flat.csv"
    np.savetxt(table, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0]], delimiter=",")
    code, out, err = run_cli("synth", "path", "--family", "spherical-fourbar", "--points",
                          str(table), "--no-timing", "--quiet")  # fmt: skip
    assert code != 0 and out == ""
    assert err.count("\n") == 1 and "not unit vectors, and the points lie in one plane" in err

"""Function generation (Freudenstein's equation, Chebyshev spacing) against independent checks.

A four-bar's own input–output function comes from the circle–circle closed form of
tests/synth_precision_helpers.py; Chebyshev points from ``numpy.polynomial``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from numpy.polynomial import chebyshev
from synth_precision_helpers import cross2, fourbar_state, length, wrap

from linkwright.mechanisms import solve
from linkwright.synthesis.precision import (
    PrecisionError,
    chebyshev_spacing,
    freudenstein,
    function_error,
    function_pairs,
)

# --- function generation -------------------------------------------------------------------------


def closed_form_psi(a, b, c, d, phi, branch):
    """Rocker angle ψ of the four-bar (frame d along +x) at crank angle φ, or None."""
    s = fourbar_state([0, 0], [d, 0], a, b, c, 0, 0, phi, branch)
    if s is None:
        return None
    B = s[1]
    return math.atan2(B[1], B[0] - d)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    a=length,
    b=length,
    c=length,
    d=st.floats(0.5, 3.0),
    branch=st.sampled_from([1.0, -1.0]),
    phis=st.lists(st.floats(-math.pi, math.pi), min_size=3, max_size=3),
)
def test_freudenstein_recovers_a_random_fourbar(a, b, c, d, branch, phis):
    psis = [closed_form_psi(a, b, c, d, p, branch) for p in phis]
    assume(all(p is not None for p in psis))
    # Away from the limit positions, where the two assemblies meet and the sign is moot.
    for p, q in zip(phis, psis, strict=True):
        A = np.array([a * math.cos(p), a * math.sin(p)])
        B = np.array([d + c * math.cos(q), c * math.sin(q)])
        assume(np.linalg.norm([d, 0] - A) > 0.05)  # the dyad's pivots apart (not folded)
        assume(abs(cross2(np.array([d, 0.0]) - A, B - A)) > 1e-3 * b * np.linalg.norm([d, 0] - A))
    rows = np.array([[math.cos(q), -math.cos(p), 1] for p, q in zip(phis, psis, strict=True)])
    assume(abs(np.linalg.det(rows)) / np.prod(np.linalg.norm(rows, axis=1)) > 1e-4)
    design = freudenstein(phis, psis, frame=d)
    m = design.mechanism
    for got, want in ((m.crank, a), (m.coupler, b), (m.rocker, c)):
        assert abs(float(got) - want) <= 1e-7 * max(a, b, c, d)
    assert float(design.crank_offset) == 0.0
    assert float(design.rocker_offset) == 0.0
    assert np.all(design.branches == branch)
    assert not design.branch_defect
    # Freudenstein's constants by their definitions.
    want_k = [d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)]
    assert np.allclose(design.coefficients, want_k, rtol=1e-7, atol=1e-7)
    # Simulated on its own assembly, the output passes each ψ at each φ.
    motion = solve(m, design.inputs)
    rel = motion.positions["B"] - np.array([d, 0.0])
    out = np.arctan2(rel[:, 1], rel[:, 0])
    assert np.max(np.abs(wrap(out - np.array(psis)))) <= 1e-7
    assert np.max(design.error) <= 1e-7


def test_freudenstein_with_the_crank_measured_the_other_way_flips_the_pin():
    a, b, c, d = 1.0, 3.0, 2.0, 3.0
    phi = np.radians([40.0, 75.0, 110.0])
    psi = np.array([closed_form_psi(a, b, c, d, p, 1.0) for p in phi])
    design = freudenstein(phi + np.pi, psi, frame=d)
    assert float(design.crank_offset) == pytest.approx(np.pi)
    assert float(design.rocker_offset) == 0.0
    assert float(design.mechanism.crank) == pytest.approx(a, rel=1e-12)
    # The four-bar's input is the pin's angle: the prescribed φ turned by π.
    assert np.allclose(wrap(design.inputs - phi), 0.0, atol=1e-12)
    assert np.max(design.error) < 1e-12


def test_freudenstein_batch_matches_one_by_one():
    phi = np.radians([[40.0, 75.0, 110.0], [10.0, 50.0, 80.0]])
    psi = np.radians([[70.0, 95.0, 115.0], [100.0, 120.0, 150.0]])
    both = freudenstein(phi, psi, frame=[2.0, 1.0])
    for k, d in enumerate((2.0, 1.0)):
        one = freudenstein(phi[k], psi[k], frame=d)
        assert np.allclose(both.coefficients[k], one.coefficients, rtol=1e-14)
        assert float(both.mechanism.coupler[k]) == pytest.approx(float(one.mechanism.coupler))
        assert np.array_equal(both.branches[k], one.branches)


def test_freudenstein_reports_a_branch_defect():
    # Two pairs on one assembly of a known four-bar, the third on the other.
    a, b, c, d = 1.0, 3.0, 2.0, 3.0
    phi = np.radians([40.0, 75.0, 110.0])
    psi = [closed_form_psi(a, b, c, d, p, s) for p, s in zip(phi, (1, 1, -1), strict=True)]
    design = freudenstein(phi, psi, frame=d)
    assert design.branches.tolist() == [1.0, 1.0, -1.0]
    assert bool(design.branch_defect)
    # Each pair is still met, on its own assembly.
    assert np.max(design.error) < 1e-12
    # On the four-bar's own assembly the third pair is missed.
    motion = solve(design.mechanism, design.inputs)
    rel = motion.positions["B"][2] - [d, 0]
    assert abs(wrap(math.atan2(rel[1], rel[0]) - psi[2])) > 1e-3


def test_freudenstein_errors():
    with pytest.raises(PrecisionError, match="exactly 3"):
        freudenstein([0.1, 0.2], [0.3, 0.4])
    with pytest.raises(PrecisionError, match="pairs 1 and 3 coincide"):
        freudenstein([0.1, 0.2, 0.1], [0.3, 0.4, 0.3])
    with pytest.raises(PrecisionError, match="dependent"):
        freudenstein(np.radians([30, -30, 60]), np.radians([100, -100, 120]))
    with pytest.raises(PrecisionError, match="positive length"):
        freudenstein([0.1, 0.2, 0.5], [0.3, 0.4, 0.6], frame=0.0)
    with pytest.raises(PrecisionError, match="finite"):
        freudenstein([0.1, np.nan, 0.5], [0.3, 0.4, 0.6])
    # A batch names the set at fault.
    with pytest.raises(PrecisionError, match=r"set \[1\]"):
        freudenstein([[0.1, 0.6, 1.1], [0.1, 0.2, 0.1]], [[0.3, 0.4, 0.7], [0.3, 0.4, 0.3]])


def test_freudenstein_zero_k_asks_for_a_slider():
    # Pairs satisfying the equation with K1 = 0 (an infinitely long crank): −K2 cos φ + K3 =
    # cos(φ − ψ) solved for ψ.
    k2, k3 = 0.8, 0.5
    phi = np.radians([20.0, 60.0, 100.0])
    psi = phi - np.arccos(k3 - k2 * np.cos(phi))
    with pytest.raises(PrecisionError, match="zero K"):
        freudenstein(phi, psi)


def test_chebyshev_spacing_is_the_zeros_of_the_chebyshev_polynomial():
    for n in (1, 2, 3, 5):
        roots = np.sort(chebyshev.Chebyshev.basis(n).roots())
        want = 2.0 + 1.5 * (roots + 1)  # mapped from [−1, 1] to [2, 5]
        assert np.allclose(chebyshev_spacing(2.0, 5.0, n), want, atol=1e-14)
    got = chebyshev_spacing([0.0, 1.0], [1.0, 3.0])
    assert got.shape == (2, 3)
    assert np.allclose(got[1], chebyshev_spacing(1.0, 3.0))
    with pytest.raises(PrecisionError, match="empty"):
        chebyshev_spacing(1.0, 1.0)
    with pytest.raises(PrecisionError, match="positive integer"):
        chebyshev_spacing(0.0, 1.0, 0)


def test_function_route_reproduces_a_fourbars_own_function():
    # y = ψ(x) of a known four-bar, x the crank angle: the route must return that four-bar, and
    # its structural error over the whole range is nil.
    a, b, c, d = 1.0, 3.5, 2.5, 3.0

    def f(x):
        return np.vectorize(lambda t: closed_form_psi(a, b, c, d, t, 1.0))(x)

    x_range = (0.3, 2.0)
    psi_range = (float(f(0.3)), float(f(2.0)))
    x, phi, psi = function_pairs(f, x_range, x_range, psi_range)
    assert np.allclose(phi, x) and np.allclose(psi, f(x))
    design = freudenstein(phi, psi, frame=d)
    assert float(design.mechanism.coupler) == pytest.approx(b, rel=1e-9)
    xs, err = function_error(design, f, x_range, x_range, psi_range, samples=41)
    assert np.max(np.abs(err)) < 1e-9
    assert xs[0] == 0.3 and xs[-1] == 2.0


def test_function_error_vanishes_at_the_precision_points():
    rng = ((1.0, 2.0), np.radians([30, 120]), np.radians([60, 150]))
    x, phi, psi = function_pairs(np.log10, *rng)
    design = freudenstein(phi, psi)
    # Evaluate the generated y at the precision x from the closed form, not function_error.
    m = design.mechanism
    for xj in x:
        t = np.radians(30) + (xj - 1.0) * np.radians(90)
        q = closed_form_psi(
            float(m.crank), float(m.coupler), float(m.rocker), 1.0, t, float(m.assembly)
        )
        y = (q - np.radians(60)) / np.radians(90) * math.log10(2)
        assert y == pytest.approx(math.log10(xj), abs=1e-12)
    # Between them the error is small but not nil (the structural error).
    _, err = function_error(design, np.log10, *rng, samples=101)
    assert 1e-4 < np.max(np.abs(err)) < 5e-3


def test_function_pairs_errors():
    with pytest.raises(PrecisionError, match="x_range must span"):
        function_pairs(np.log10, (1, 1), (0, 1), (0, 1))
    with pytest.raises(PrecisionError, match=r"f\(x_range\) must span"):
        function_pairs(np.cos, (-1, 1), (0, 1), (0, 1))
    with pytest.raises(PrecisionError, match="phi_range must be"):
        function_pairs(np.log10, (1, 2), (0, 1, 2), (0, 1))

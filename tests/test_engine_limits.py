"""Limit positions are roots: the engine's input limits against law-of-cosines candidates, a
numeric scan, and the flatness of the dyad there, with a tolerance that adds the rounding noise
the data carry near a change point.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from engine_helpers import (
    EPS,
    LIMIT_MARGIN_TOL,
    TWO_PI,
    angle,
    fourbar_lengths,
    fourbars,
    limit_inputs,
    norm,
    random_fourbars,
    random_slider_cranks,
    slider_cranks,
    take,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    input_range,
    solve,
)

# ----------------------------------------------------------------------------------------------
# 3. Limit positions are roots
# ----------------------------------------------------------------------------------------------


def triangle_angle(a, b, c):
    """The angle opposite side ``c`` of the triangle with sides a, b, c (NaN if there is none).

    Kahan's formula ("Miscalculating area and angles of a needle-like triangle"): accurate to a
    few ulps for every shape, needles and flat triangles included, unlike arccos of the law of
    cosines near 0 and π. A triangle that is flat within the rounding of its sides counts as
    flat (angle 0 or π): that is a tangency, a double root.
    """
    a, b = np.maximum(a, b), np.minimum(a, b)
    flat = 8 * EPS * (a + b + c)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = np.where(b >= c, c - (a - b), b - (a - c))
        mu = np.where((mu < 0) & (mu > -flat), 0.0, mu)
        far = (a - c) + b
        far = np.where((far < 0) & (far > -flat), 0.0, far)
        return 2.0 * np.arctan(np.sqrt(((a - b) + c) * mu / ((a + (b + c)) * far)))


def circular_distance(a, b):
    return np.abs((a - b + np.pi) % TWO_PI - np.pi)


def _root_uncertainty(noise, slope, curvature):
    """How far rounding ``noise`` in f(θ) = target moves a root where f has the given slope:
    noise/|slope| for a simple root, but never more than 2·sqrt(noise/curvature), the shift of a
    double root (where f is flat and the two roots of a near-tangency merge)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        linear = noise / np.abs(slope)
        return 1e-13 + np.fmin(linear, 2 * np.sqrt(noise / curvature)), linear


def fourbar_limit_candidates(m):
    """Input angles where |A − B0| = coupler ± rocker, by the law of cosines in A0 B0 A.

    With f = |A0B0|, r the crank and g = coupler ± rocker, the angle γ at A0 opposite g gives
    θ = α ± γ, α the direction of A0→B0. Returns the angles (batch + (4,), NaN where the
    triangle does not exist), each one's θ-uncertainty implied by rounding the data, and
    whether it is a simple root known to 1e-9. q = |A − B0|² = f² + r² − 2fr·cos(θ − α) meets
    g² with slope 2fr·sin γ and curvature ≤ 2fr; q carries ~eps·((f + r + g)² + f·|position|).
    """
    f, r = np.asarray(m.frame), np.asarray(m.crank)
    frame = np.asarray(m.B0) - np.asarray(m.A0)
    alpha = angle(frame)
    where = norm(np.asarray(m.A0)) + norm(np.asarray(m.B0))
    angles, uncertainty, simple = [], [], []
    for g in (m.coupler + m.rocker, np.abs(m.coupler - m.rocker)):
        gamma = triangle_angle(f, r, g)
        noise = 16 * EPS * ((f + r + g) ** 2 + 2 * f * where)
        du, linear = _root_uncertainty(noise, 2 * f * r * np.sin(gamma), 2 * f * r)
        angles += [alpha + gamma, alpha - gamma]
        uncertainty += [du, du]
        simple += [linear < 1e-9] * 2
    return np.stack(angles, -1), np.stack(uncertainty, -1), np.stack(simple, -1)


def slider_limit_candidates(m):
    """Input angles where A's distance from the guide is ±rod: e + r·sin(θ − λ) = ±rod.

    e the signed distance of A0 from the guide, λ its direction: sin(θ − λ) = (±rod − e)/r.
    Same returns as :func:`fourbar_limit_candidates` (slope r·cos(θ − λ), curvature ≤ r).
    """
    lam = np.asarray(m.line_angle)
    e, r, rod = m.offset, np.asarray(m.crank), np.asarray(m.rod)
    where = norm(np.asarray(m.A0)) + norm(np.asarray(m.line_point))
    noise = 16 * EPS * (r + rod + where)
    angles, uncertainty, simple = [], [], []
    for target in (rod, -rod):
        x = (target - e) / r
        x = np.where(np.abs(x) - 1 < noise / r, np.clip(x, -1, 1), x)  # tangent within rounding
        with np.errstate(invalid="ignore"):
            base = np.arcsin(x)
        du, linear = _root_uncertainty(noise, r * np.cos(base), r)
        angles += [lam + base, lam + np.pi - base]
        uncertainty += [du, du]
        simple += [linear < 1e-9] * 2
    return np.stack(angles, -1), np.stack(uncertainty, -1), np.stack(simple, -1)


def _limit_margin_tolerance(m, theta):
    """|margin| allowed at a limit: 1e-12, plus the rounding noise of the margin itself.

    margin = ((r1 + r2)² − q)(q − (r1 − r2)²)/(4q·r1²) is computed from q = |B0 − A|² (four-bar,
    r1 coupler, r2 rocker), whose rounding δq ≈ 2g·eps·(|A| + |B0| + r) grows with how far the
    frame sits from the origin; at the root q = g² the margin's sensitivity is r2/(r1·g²). For a
    slider-crank the margin is (rod² − e_A²)/rod², e_A carrying eps·(|A| + |line point|).
    """
    motion = solve(m, np.nan_to_num(theta), order=0)
    A = motion.positions["A"]
    if isinstance(m, FourBar):
        r1, r2 = (np.asarray(x)[..., None] for x in (m.coupler, m.rocker))
        B0 = np.asarray(m.B0)[..., None, :]
        g = norm(B0 - A)
        dq = 2 * g * EPS * (norm(A) + norm(B0) + np.asarray(m.crank)[..., None])
        noise = r2 / (r1 * g * g) * dq
    else:
        rod = np.asarray(m.rod)[..., None]
        Lp = np.asarray(m.line_point)[..., None, :]
        noise = 2 * EPS * (norm(A) + norm(Lp)) / rod
    return motion, LIMIT_MARGIN_TOL + 16 * noise


def check_limits(m, method, arcs=None):
    """At every returned limit: assembled, dyad margin ~0, the limiting dyad named."""
    arcs = input_range(m, method=method) if arcs is None else arcs
    theta = np.concatenate((arcs.lo, arcs.hi), axis=-1)
    finite = np.isfinite(theta)
    motion, tol = _limit_margin_tolerance(m, theta)
    assert np.all(motion.valid[finite])
    margin = np.abs(motion.margins["B"])
    assert np.all(margin[finite] <= tol[finite]), np.max(margin[finite] / tol[finite])
    index = np.concatenate((arcs.dyad_lo, arcs.dyad_hi), axis=-1)
    assert np.all(index[finite] == 0) and np.all(index[~finite] == -1)
    # Arcs: lo in (−π, π], hi ≥ lo, sorted, disjoint; NaN padding last; full/never have none.
    # (hi = lo only for a linkage that assembles at a single input, touching its limit.)
    lo, hi = arcs.lo, arcs.hi
    assert np.all((lo[np.isfinite(lo)] > -np.pi) & (lo[np.isfinite(lo)] <= np.pi))
    assert np.array_equal(np.isfinite(lo), np.isfinite(hi))
    assert np.all(hi[np.isfinite(lo)] >= lo[np.isfinite(lo)])
    assert not np.any(np.isfinite(lo)[arcs.full | arcs.never])
    assert not np.any(arcs.full & arcs.never)
    partial = ~(arcs.full | arcs.never)
    assert np.all(arcs.count[partial] >= 1)
    if lo.shape[-1] > 1:
        both = np.isfinite(lo[..., 1])
        assert np.all(lo[..., 1][both] >= hi[..., 0][both])
        assert np.all(hi[..., 1][both] <= lo[..., 0][both] + TWO_PI)
    return arcs, int(finite.sum())


def check_against_candidates(ends, candidates, uncertainty, simple):
    """Each returned limit is one of the closed-form roots and each simple root is returned,
    within the roots' own uncertainty (both sets taken modulo 2π)."""
    dist = circular_distance(ends[..., :, None], candidates[..., None, :])
    dist = np.where(np.isfinite(dist), dist, np.inf)
    # ends → roots: the nearest root within its uncertainty.
    nearest = np.argmin(dist, axis=-1)
    d_end = np.take_along_axis(dist, nearest[..., None], -1)[..., 0]
    u_end = np.take_along_axis(np.nan_to_num(uncertainty, nan=0.0), nearest, -1)
    bad = np.isfinite(ends) & ~(d_end <= u_end)
    assert not bad.any(), (np.argwhere(bad)[:5], d_end[bad][:5], u_end[bad][:5])
    # roots → ends: every simple root is a limit (a tangency may or may not be, by rounding).
    sharp = np.isfinite(candidates) & simple
    d_root = np.min(dist, axis=-2)
    bad = sharp & ~(d_root <= uncertainty)
    assert not bad.any(), (np.argwhere(bad)[:5], d_root[bad][:5], uncertainty[bad][:5])


def check_numeric_agrees(m, analytic):
    """The grid-and-bisection method finds the same arcs wherever its grid can see them.

    The grid has 1440 cells; arcs or gaps narrower than a few cells (only near a change point)
    can fall between its nodes, so the comparison is restricted to arcs and gaps of 3 cells or
    more. There the two must agree to 1e-11 rad: both end on the same rounded predicate.
    """
    numeric = input_range(m, method="numeric")
    check_limits(m, "numeric", numeric)
    cell = TWO_PI / 1440
    lo, hi = analytic.lo, analytic.hi  # at most two arcs
    two = np.isfinite(lo[..., 1])
    pieces = np.stack(
        (
            hi[..., 0] - lo[..., 0],
            hi[..., 1] - lo[..., 1],
            np.where(two, lo[..., 1], lo[..., 0] + TWO_PI) - hi[..., 0],
            lo[..., 0] + TWO_PI - hi[..., 1],
        ),
        axis=-1,
    )
    narrowest = np.min(np.where(np.isfinite(pieces), pieces, TWO_PI), axis=-1)
    seen = analytic.full | analytic.never | (narrowest > 3 * cell)
    assert seen.mean() > 0.6
    assert np.array_equal(numeric.full[seen], analytic.full[seen])
    assert np.array_equal(numeric.never[seen], analytic.never[seen])
    assert np.array_equal(numeric.count[seen], analytic.count[seen])
    k = analytic.lo.shape[-1]
    assert np.all(np.isnan(numeric.lo[seen][..., k:]))
    for a, b in ((analytic.lo, numeric.lo), (analytic.hi, numeric.hi)):
        a, b = a[seen], b[seen][..., :k]
        assert np.array_equal(np.isfinite(a), np.isfinite(b))
        diff = np.abs(a - b)[np.isfinite(a)]
        assert np.all(diff <= 1e-11), np.max(diff)


def test_fourbar_limits_three_ways():
    rng = np.random.default_rng(20240301)
    m = random_fourbars(rng, 20_000)
    analytic, n = check_limits(m, "analytic")
    assert n > 20_000
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *fourbar_limit_candidates(m))
    # The numeric method evaluates a 1440-point grid per linkage: a fifth of the batch will do.
    few = take(m, slice(0, 4000))
    check_numeric_agrees(few, input_range(few, method="analytic"))
    # Grashof's rule: the crank turns fully exactly when s + l < p + q and the crank or the
    # frame is the shortest link (crank-rocker, double-crank).
    lengths, excess = fourbar_lengths(m)
    shortest = np.argmin(lengths, axis=-1)
    turns = (excess < 0) & ((shortest == 0) | (shortest == 1))
    clear = np.abs(excess) > 1e-8
    np.testing.assert_array_equal(analytic.full[clear], turns[clear])


def test_slider_crank_limits_three_ways():
    rng = np.random.default_rng(20240302)
    m = random_slider_cranks(rng, 20_000)
    analytic, n = check_limits(m, "analytic")
    assert n > 20_000
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *slider_limit_candidates(m))
    few = take(m, slice(0, 4000))
    check_numeric_agrees(few, input_range(few, method="analytic"))
    # The crank turns fully exactly when |e| ≤ rod − crank.
    e, crank, rod = np.abs(m.offset), m.crank, m.rod
    clear = np.abs(e - (rod - crank)) > 1e-8 * m.scale
    np.testing.assert_array_equal(analytic.full[clear], (e <= rod - crank)[clear])


@pytest.mark.parametrize("make", [random_fourbars, random_slider_cranks])
def test_limit_margins_plain_tolerance(make):
    """Away from change points and with frames near the origin the rounding term is negligible:
    the margin at every returned limit is below 1e-12 outright."""
    rng = np.random.default_rng(20240303)
    m = make(rng, 20_000, near=0.0, trans=1.0)
    theta = limit_inputs(m)
    finite = np.isfinite(theta)
    motion = solve(m, np.nan_to_num(theta), order=0)
    assert finite.sum() > 10_000 and motion.valid[finite].all()
    assert np.max(np.abs(motion.margins["B"][finite])) < LIMIT_MARGIN_TOL


@settings(max_examples=150, deadline=None)
@given(m=st.one_of(fourbars(), slider_cranks()))
def test_single_limits_are_roots(m):
    analytic, _ = check_limits(m, "analytic")
    candidates = fourbar_limit_candidates if isinstance(m, FourBar) else slider_limit_candidates
    ends = np.concatenate((analytic.lo, analytic.hi), axis=-1)
    check_against_candidates(ends, *candidates(m))
    check_limits(m, "numeric")


def test_limit_hand_example():
    """Driving the long link of a crank-rocker: limits where coupler and rocker fold onto each
    other, cos θ = (f² + r² − (c − k)²)/(2fr) with f = 1, r = 3.5, coupler − rocker = 4."""
    m = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    arcs = input_range(m)
    lim = math.acos((1 + 3.5**2 - 16) / 7)  # |A − B0| = coupler − rocker (folded)
    np.testing.assert_allclose(arcs.lo[0], lim, rtol=0, atol=1e-15)
    np.testing.assert_allclose(arcs.hi[0], TWO_PI - lim, rtol=0, atol=1e-14)
    assert not arcs.full and not arcs.never and arcs.count == 1

"""Ellipse → double slider synthesis (paper 004): every number checked by a second route.

- Coefficients of test ellipses are expanded here from the implicit form
  ((X − X0)cos β + (Y − Y0)sin β)²/a² + (−(X − X0)sin β + (Y − Y0)cos β)²/b² = 1, not through
  eq. 6, then scaled by a random factor of either sign.
- The trammel's centre and axes are checked against the eigen-decomposition of the quadratic
  form (not eqs. 7–12).
- Point-to-ellipse distances are checked against dense sampling refined by a bounded scalar
  minimiser.
- Family members are checked by simulating them with the engine and measuring the traced P
  against the generating ellipse, by the link lengths of paper 004's eq. 14, and by the
  converse: a random double slider is found again, parameter for parameter, in one of the two
  families.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from linkwright.analysis.conic import (
    ConicError,
    conic_invariants,
    conic_kind,
    doubleslider_conic,
    ellipse_conic,
    ellipse_distance,
    normalise_conic,
)
from linkwright.io import mechanism_to_dict, parse_document
from linkwright.mechanisms import DoubleSlider, solve
from linkwright.synthesis.ellipse import (
    EllipseError,
    Trammel,
    check_on_ellipse,
    doubleslider_family,
    doubleslider_from_ellipse,
    ellipse_synthesis,
    family_angles,
    fit_ellipse,
    trammel_from_conic,
)

SETTINGS = settings(max_examples=40, deadline=None)


def implicit_conic(x0, y0, beta, a, b, scale=1.0):
    """A..F of the ellipse, expanded from its implicit form in its own frame."""
    c, s = np.cos(beta), np.sin(beta)
    A = c * c / a**2 + s * s / b**2
    B = 2 * c * s * (1 / a**2 - 1 / b**2)
    C = s * s / a**2 + c * c / b**2
    D = -2 * A * x0 - B * y0
    E = -B * x0 - 2 * C * y0
    F = A * x0 * x0 + B * x0 * y0 + C * y0 * y0 - 1.0
    return scale * np.array([A, B, C, D, E, F])


def ellipse_points(x0, y0, beta, a, b, phi):
    x, y = a * np.cos(phi), b * np.sin(phi)
    c, s = np.cos(beta), np.sin(beta)
    return np.column_stack((x0 + x * c - y * s, y0 + x * s + y * c))


def brute_distance(point, x0, y0, beta, a, b):
    """Dense sampling of the parametric ellipse, refined by a bounded 1-D minimiser."""

    def dist(t):
        q = ellipse_points(x0, y0, beta, a, b, np.atleast_1d(t))
        return np.hypot(q[:, 0] - point[0], q[:, 1] - point[1])

    grid = np.linspace(0, 2 * np.pi, 4001)
    k = int(np.argmin(dist(grid)))
    step = grid[1] - grid[0]
    r = minimize_scalar(
        lambda t: float(dist(t)[0]),
        bounds=(grid[k] - step, grid[k] + step),
        method="bounded",
        options={"xatol": 1e-13},
    )
    return min(float(r.fun), float(dist(grid).min()))


def eigen_ellipse(coeffs):
    """Centre, semi-axes and major-axis direction from the quadratic form's eigenvectors."""
    A, B, C, D, E, F = np.asarray(coeffs) * np.sign(coeffs[0] + coeffs[2])  # A + C > 0
    q = np.array([[A, B / 2], [B / 2, C]])
    centre = np.linalg.solve(2 * q, [-D, -E])
    f0 = F + 0.5 * (D * centre[0] + E * centre[1])
    lam, vec = np.linalg.eigh(q)
    semi = np.sqrt(-f0 / lam)  # the smaller eigenvalue gives the major axis
    return centre, semi[0], semi[1], vec[:, 0]


def same_axis(beta1, beta2):
    """Distance between two line directions, modulo 180°."""
    return abs((beta1 - beta2 + np.pi / 2) % np.pi - np.pi / 2)


ellipses = st.tuples(
    st.floats(-10, 10),  # centre, in units of a
    st.floats(-10, 10),
    st.floats(-np.pi, np.pi),  # major axis angle
    st.floats(-2, 2),  # log10 a
    st.floats(0.05, 1.0),  # b / a
    st.floats(-6, 6),  # log10 of the coefficients' scale
    st.booleans(),  # the coefficients' sign
)


def unpack(e):
    cx, cy, beta, log_a, ratio, log_k, negative = e
    a = 10.0**log_a
    scale = (-1.0 if negative else 1.0) * 10.0**log_k
    return cx * a, cy * a, beta, a, ratio * a, scale


# ----------------------------------------------------------------------------------------------
# Conic helpers


def test_ellipse_distance_matches_brute_force():
    rng = np.random.default_rng(6001)
    for _ in range(60):
        a = 10 ** rng.uniform(-1, 1)
        b = a * rng.uniform(0.03, 1.0)
        x0, y0 = rng.uniform(-3, 3, 2)
        beta = rng.uniform(-np.pi, np.pi)
        spread = a * rng.choice([0.01, 0.3, 1.0, 4.0])
        pts = np.array([x0, y0]) + rng.normal(0, 1, (4, 2)) * spread
        got = ellipse_distance(pts, [x0, y0], a, b, beta)
        want = [brute_distance(p, x0, y0, beta, a, b) for p in pts]
        np.testing.assert_allclose(got, want, atol=1e-9 * a, rtol=0)


def test_ellipse_distance_special_points():
    # The frame's axes, the centre, a vertex, inside the evolute's cusp, a circle.
    a, b = 3.0, 1.0
    pts = [[0, 0], [0, 0.4], [0, -5], [1.0, 0], [2.9, 0], [-7, 0], [3, 0], [0, 1]]
    got = ellipse_distance(pts, [0, 0], a, b, 0.0)
    want = [brute_distance(np.array(p, float), 0, 0, 0, a, b) for p in pts]
    np.testing.assert_allclose(got, want, atol=1e-10)
    # Inside the cusp (a·u < a² − b²) the nearest point is off the axis: closer than b.
    assert got[3] < b
    circle = ellipse_distance([[3, 4], [0, 0], [0.3, -0.4]], [0, 0], 2, 2, 0.7)
    np.testing.assert_allclose(circle, [3, 2, 1.5], atol=1e-14)
    # Batched ellipses against batched points.
    batch = ellipse_distance(np.zeros((2, 5, 2)), [[[0, 0]], [[1, 0]]], [[3], [2]], [[1], [1]], 0)
    # From (−1, 0) relative to the second (a = 2, b = 1): min of 3cos²t + 4cos t + 2 is 2/3.
    np.testing.assert_allclose(batch, [[1] * 5, [np.sqrt(2 / 3)] * 5], atol=1e-14)


def test_ellipse_distance_swapped_axes_and_refusals():
    pts = np.array([[0.3, 2.0], [-4.0, 0.5], [0.1, -0.2]])
    # a < b names the same ellipse with its major axis turned by 90°.
    np.testing.assert_allclose(
        ellipse_distance(pts, [0.5, 0.2], 1.0, 3.0, 0.4),
        ellipse_distance(pts, [0.5, 0.2], 3.0, 1.0, 0.4 + np.pi / 2),
        atol=1e-14,
    )
    for args, words in (
        (([np.nan, 0], [0, 0], 3, 1, 0), "points must be finite"),
        (([0, 0], [0, 0], 3, 0, 0), "positive"),
        (([0, 0], [0, 0], -3, 1, 0), "positive"),
        (([0, 0], [0, 0], np.inf, 1, 0), "semi-axes must be finite"),
        (([0, 0, 0], [0, 0], 3, 1, 0), "last axis of 2"),
    ):
        with pytest.raises(ConicError, match=words):
            ellipse_distance(*args)


@SETTINGS
@given(ellipses)
def test_ellipse_conic_is_eq6_and_normalised(e):
    x0, y0, beta, a, b, _ = unpack(e)
    c = ellipse_conic([x0, y0], a, b, beta)
    # Eq. 6 is the implicit form scaled by a²b² (its own k of eq. 10).
    want = implicit_conic(x0, y0, beta, a, b, scale=a * a * b * b)
    np.testing.assert_allclose(c, want, atol=1e-9 * np.max(np.abs(want)))
    delta, big = conic_invariants(c)
    assert delta == pytest.approx(-4 * a * a * b * b, rel=1e-9)
    assert big == pytest.approx(-((a * b) ** 4), rel=1e-6, abs=1e-9 * np.max(np.abs(c)) ** 2)


# ----------------------------------------------------------------------------------------------
# Coefficients → trammel


@SETTINGS
@given(ellipses)
def test_trammel_matches_generating_ellipse_and_eigen_route(e):
    x0, y0, beta, a, b, scale = unpack(e)
    coeffs = implicit_conic(x0, y0, beta, a, b, scale)
    t = trammel_from_conic(coeffs)
    centre, major, minor, axis = eigen_ellipse(coeffs / np.max(np.abs(coeffs)))
    for got, truth, eig in ((t.a, a, major), (t.b, b, minor)):
        assert got == pytest.approx(truth, rel=1e-8)
        assert got == pytest.approx(eig, rel=1e-8)
    size = a * (1 + np.hypot(x0, y0) / a)
    assert np.hypot(t.X0 - x0, t.Y0 - y0) < 1e-9 * size
    assert np.hypot(t.X0 - centre[0], t.Y0 - centre[1]) < 1e-9 * size
    assert -np.pi / 2 < t.beta <= np.pi / 2
    if b < 0.99 * a:  # a circle has no axis
        assert same_axis(t.beta, beta) < 1e-7
        assert same_axis(t.beta, np.arctan2(axis[1], axis[0])) < 1e-7


def test_trammel_is_vectorised_and_takes_any_scale():
    c = np.array([implicit_conic(1, 2, 0.3, 3, 1), implicit_conic(-1, 0, -1.2, 2, 1.5)])
    t = trammel_from_conic(c * np.array([[-1e-9], [1e12]]))
    np.testing.assert_allclose(t.a, [3, 2], rtol=1e-12)
    np.testing.assert_allclose(t.b, [1, 1.5], rtol=1e-12)
    np.testing.assert_allclose(t.center, [[1, 2], [-1, 0]], atol=1e-12)
    np.testing.assert_allclose(t.beta, [0.3, -1.2], atol=1e-12)
    # Eq. 6 from the trammel is the normalised input (eq. 10).
    np.testing.assert_allclose(t.conic(), normalise_conic(c), rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize(
    ("coeffs", "words"),
    [
        ([1, 0, -1, 0, 0, -1], "hyperbola"),
        ([1, 0, 0, 0, -1, 0], "parabola"),
        ([1, 0, 1, 0, 0, 1], "imaginary ellipse"),
        ([1, 0, 4, -2, 0, 1], "point ellipse"),  # (X − 1)² + 4Y² = 0
        ([1, 0, -1, 0, 0, 0], "degenerate"),  # two crossing lines
        ([0, 0, 0, 1, 1, 1], "degenerate"),  # a line, not a conic
        ([1, 0, 1, np.nan, 0, -1], "finite"),
        ([1, 0, np.inf, 0, 0, -1], "finite"),
        ([1, 0, 1, 0, -1], "six coefficients"),
        (["a", 0, 1, 0, 0, -1], "numbers"),
    ],
)
def test_bad_conics_are_named(coeffs, words):
    with pytest.raises(EllipseError, match=words):
        trammel_from_conic(coeffs)
    with pytest.raises(EllipseError, match=words):
        ellipse_synthesis(conic=coeffs)


def test_bad_conic_in_a_batch_is_located():
    with pytest.raises(EllipseError, match=r"hyperbola.*\(conic \(1,\) of the batch\)"):
        trammel_from_conic([[1, 0, 1, 0, 0, -1], [1, 0, -1, 0, 0, -1]])


# ----------------------------------------------------------------------------------------------
# The ∞² family


@SETTINGS
@given(ellipses, st.floats(-4, 4), st.floats(-4, 4), st.sampled_from(["small", "large"]))
def test_canonical_and_family_trace_the_ellipse(e, s1, s2, circle):
    x0, y0, beta, a, b, scale = unpack(e)
    assume(abs(np.sin(s1 - s2)) > 1e-3 and abs(np.sin(s1 - s2 + 1.5)) > 1e-3)
    assume(circle == "large" or b < (1 - 1e-6) * a)
    coeffs = implicit_conic(x0, y0, beta, a, b, scale)
    truth = Trammel(*(np.float64(v) for v in (x0, y0, beta, a, b)))
    canonical = doubleslider_from_ellipse(coeffs, circle=circle)
    assert float(canonical.alpha) == np.pi / 2 and float(canonical.h) == 0.0
    assert float(canonical.p) == pytest.approx(a, rel=1e-8)
    assert float(canonical.q) == pytest.approx(b if circle == "large" else -b, rel=1e-8)
    member = doubleslider_family(coeffs, [s1, s1 + 1.0], [s2, s2 - 0.5], circle=circle)
    assert member.batch_shape == (2,)
    for m in (canonical, member):
        # Against the generating ellipse, directly...
        p = solve(m, np.linspace(0, 2 * np.pi, 97), order=0).positions["P"]
        d = ellipse_distance(p, [x0, y0], a, b, beta)
        assert np.max(d) / a < 1e-9
        # ... and through check_on_ellipse.
        assert np.max(check_on_ellipse(m, truth, samples=64)) < 1e-9


@SETTINGS
@given(
    st.floats(0.2, 5),
    st.floats(0.05, 0.95),
    st.floats(-np.pi, np.pi),
    st.floats(-np.pi, np.pi),
    st.sampled_from(["small", "large"]),
)
def test_family_link_lengths_are_eq14(a, ratio, s1, s2, circle):
    """|RQ|, |QP|, |RP| of a member, measured on a simulated pose, are eq. 14's d, f, g."""
    b = ratio * a
    assume(abs(np.sin(s1 - s2)) > 1e-3)
    m = doubleslider_family(
        Trammel(*map(np.float64, (0.3, -0.2, 0.4, a, b))), s1, s2, circle=circle
    )
    pose = solve(m, [0.7], order=0).positions
    R, Q, P = (pose[k][0] for k in "RQP")
    two_r = a - b if circle == "small" else a + b
    assert np.linalg.norm(R - Q) == pytest.approx(two_r * abs(np.sin(s1 - s2)), rel=1e-11)
    f = np.sqrt(a**2 * np.sin(s2) ** 2 + b**2 * np.cos(s2) ** 2)
    g = np.sqrt(a**2 * np.sin(s1) ** 2 + b**2 * np.cos(s1) ** 2)
    assert np.linalg.norm(Q - P) == pytest.approx(f, rel=1e-11)
    assert np.linalg.norm(R - P) == pytest.approx(g, rel=1e-11)
    # The guides: R's line at s1, Q's at s2 from the major axis (β = 0.4).
    assert same_axis(float(m.alpha + m.beta), 0.4 + s1) < 1e-12
    assert same_axis(float(m.beta), 0.4 + s2) < 1e-12


def circumcentre(a, b, c):
    m = 2 * np.array([b - a, c - a])
    return np.linalg.solve(m, [b @ b - a @ a, c @ c - a @ a])


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-5, 5),
    st.floats(-5, 5),
    st.floats(0.15, np.pi - 0.15),
    st.floats(-np.pi, np.pi),
    st.floats(-4, 4),
    st.floats(-4, 4),
    st.floats(-3, 3),
)
def test_every_double_slider_is_in_a_family(x0, y0, alpha, beta, p, q, h):
    """Converse: a random double slider's ellipse (eq. 3) → trammel → the family member with
    the random linkage's own guide directions is that linkage, parameter for parameter (up to
    the sign of (p, q, h), which only shifts θ by 180°), on the Cardan circle through M, R, Q."""
    assume(abs(p + q) > 0.1)
    # K = h² + cot α (p + q) h − p q; δ = −4K² (SEED-NOTES): K → 0 is a segment, not an ellipse.
    assume(abs(h * h + (p + q) * h / np.tan(alpha) - p * q) > 0.05 * (p * p + q * q + h * h))
    m = DoubleSlider(M=[x0, y0], alpha=alpha, beta=beta, p=p, q=q, h=h)
    coeffs = doubleslider_conic(m)
    assume(conic_kind(coeffs) == "ellipse")  # p = 0 puts P on R's line: a segment
    t = trammel_from_conic(coeffs)
    assume(t.b > 0.05 * t.a)
    # A pose with both sliders clear of M (at θ = α + β, Q passes through M).
    pose = solve(m, [beta + alpha / 2 + np.pi / 2], order=0).positions
    centre = circumcentre(np.array([x0, y0]), pose["R"][0], pose["Q"][0])
    radius = np.hypot(*(centre - [x0, y0]))
    # The Cardan circle through M, R, Q is one of the two.
    small, large = 0.5 * (t.a - t.b), 0.5 * (t.a + t.b)
    circle = "small" if abs(radius - small) < abs(radius - large) else "large"
    assert radius == pytest.approx(small if circle == "small" else large, rel=1e-8)
    assert np.hypot(*(pose["P"][0] - centre)) == pytest.approx(
        large if circle == "small" else small, rel=1e-8, abs=1e-8 * t.a
    )
    f = doubleslider_family(t, alpha + beta - t.beta, beta - t.beta, circle=circle)
    assert float(f.alpha) == pytest.approx(alpha, abs=1e-12)
    assert float(f.beta) == pytest.approx(beta, abs=1e-12)
    got, want = np.array([f.p, f.q, f.h], float), np.array([p, q, h])
    err = min(np.max(np.abs(got - want)), np.max(np.abs(got + want)))
    assert err < 1e-8 * (1 + np.max(np.abs(want)))
    # Round trip: members of the family trace the random linkage's own ellipse.
    rng = np.random.default_rng(int(abs(x0) * 1e6) % 2**32)
    s = rng.uniform(0, np.pi, (2, 6))
    s[1] = s[0] + rng.uniform(0.2, np.pi - 0.2, 6)
    members = doubleslider_family(coeffs, s[0], s[1], circle=circle)
    own = solve(m, np.linspace(0, 2 * np.pi, 64), order=0).positions["P"]
    assert np.max(ellipse_distance(own, t.center, t.a, t.b, t.beta)) / t.a < 1e-9
    assert np.max(check_on_ellipse(members, coeffs, samples=64)) < 1e-9


def test_mirror_coupler_traces_another_ellipse():
    t = Trammel(*map(np.float64, (0.0, 0.0, 0.0, 3.0, 1.0)))
    m = doubleslider_family(t, 1.3, -0.6)
    assert abs(float(m.h)) > 1.0
    assert check_on_ellipse(m, t) < 1e-14
    mirror = DoubleSlider(M=m.M, alpha=m.alpha, beta=m.beta, p=m.p, q=m.q, h=-m.h)
    assert check_on_ellipse(mirror, t) > 0.05


def test_family_refusals_and_circles():
    circle = [1, 0, 1, 0, 0, -4]  # radius 2
    with pytest.raises(EllipseError, match=r"a circle \(a = b = 2\).*circle='large'"):
        doubleslider_from_ellipse(circle)
    with pytest.raises(EllipseError, match="no small Cardan circle"):
        doubleslider_family(circle, 1.0, 0.0)
    big = doubleslider_from_ellipse(circle, circle="large")
    assert (float(big.p), float(big.q)) == pytest.approx((2, 2))
    assert check_on_ellipse(big, circle) < 1e-14
    members = doubleslider_family(circle, [0.3, 2.0], [1.2, -0.4], circle="large")
    assert np.max(check_on_ellipse(members, circle)) < 1e-14
    with pytest.raises(EllipseError, match="equal modulo 180°"):
        doubleslider_family([1, 0, 9, 0, 0, -9], [0.1, 1.0], [0.1 + 2 * np.pi, 0.0])
    with pytest.raises(EllipseError, match="circle must be 'small' or 'large'"):
        doubleslider_family([1, 0, 9, 0, 0, -9], 1.0, 0.0, circle="medium")
    with pytest.raises(EllipseError, match="finite"):
        doubleslider_family([1, 0, 9, 0, 0, -9], np.nan, 0.0)
    with pytest.raises(EllipseError, match="hyperbola"):
        doubleslider_family([1, 0, -9, 0, 0, -9], 1.0, 0.0)


def test_family_is_vectorised_over_ellipses_and_angles():
    t = trammel_from_conic([implicit_conic(0, 0, 0.1, 3, 1), implicit_conic(5, -2, 1.0, 4, 2.5)])
    s1 = np.array([[0.4], [1.9], [2.5]])  # (3, 1) against the ellipses' (2,)
    m = doubleslider_family(t, s1, -0.3)
    assert m.batch_shape == (3, 2) and np.shape(m.M) == (3, 2, 2)
    dev = check_on_ellipse(m, Trammel(t.X0, t.Y0, t.beta, t.a, t.b))
    assert dev.shape == (3, 2) and np.max(dev) < 1e-13


# ----------------------------------------------------------------------------------------------
# check_on_ellipse


def test_check_on_ellipse_measures_a_turned_trammel():
    # The trammel of X²/9 + Y² = 1 turned by 20°: its worst distance, found by brute force.
    m = DoubleSlider(M=[0, 0], alpha=np.pi / 2, beta=np.radians(20), p=3, q=1)
    got = check_on_ellipse(m, [1, 0, 9, 0, 0, -9], samples=2000)
    phi = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    turned = ellipse_points(0, 0, np.radians(20), 3, 1, phi)
    want = max(brute_distance(p, 0, 0, 0, 3, 1) for p in turned[::5]) / 3
    assert got == pytest.approx(want, rel=1e-4)
    with pytest.raises(EllipseError, match="samples"):
        check_on_ellipse(m, [1, 0, 9, 0, 0, -9], samples=2)


# ----------------------------------------------------------------------------------------------
# Fitting


@SETTINGS
@given(ellipses, st.integers(5, 40), st.integers(0, 2**32 - 1))
def test_fit_recovers_exact_ellipse(e, n, seed):
    x0, y0, beta, a, b, _ = unpack(e)
    rng = np.random.default_rng(seed)
    # Points spread round the ellipse (a cluster on a short arc leaves the fit ill-posed).
    phi = np.linspace(0, 2 * np.pi, n, endpoint=False) + rng.uniform(0, 2 * np.pi)
    phi = phi + rng.uniform(-0.3, 0.3, n) * (2 * np.pi / n)
    fit = fit_ellipse(ellipse_points(x0, y0, beta, a, b, phi))
    t = fit.trammel
    assert abs(t.a - a) < 1e-9 * a and abs(t.b - b) < 1e-9 * a
    assert np.hypot(t.X0 - x0, t.Y0 - y0) < 1e-9 * a
    if b < 0.99 * a:
        assert same_axis(t.beta, beta) < 1e-8
    assert fit.rms < 1e-9 * a and fit.max < 1e-9 * a and fit.count == n
    # The reported coefficients are the generating ellipse's, normalised (eq. 10).
    want = normalise_conic(implicit_conic(x0, y0, beta, a, b))
    np.testing.assert_allclose(fit.coeffs, want, atol=1e-7 * np.max(np.abs(want)))


def test_fit_with_noise_reports_a_sensible_residual():
    rng = np.random.default_rng(6002)
    a, b, sigma = 3.0, 1.5, 0.02
    ratios = []
    for _ in range(20):
        phi = rng.uniform(0, 2 * np.pi, 300)
        clean = ellipse_points(1.0, -2.0, 0.5, a, b, phi)
        fit = fit_ellipse(clean + rng.normal(0, sigma, clean.shape))
        t = fit.trammel
        # The orthogonal residual of isotropic noise is about σ (five fitted parameters
        # absorb a little of it); the ellipse is found to a few σ/√N.
        ratios.append(fit.rms / sigma)
        assert fit.max > fit.rms
        assert abs(t.a - a) < 0.02 and abs(t.b - b) < 0.02
        assert np.hypot(t.X0 - 1.0, t.Y0 + 2.0) < 0.02 and same_axis(t.beta, 0.5) < 0.02
        # The residual is the distance to the fitted ellipse, measured independently.
        pts = clean + 0  # noiseless points are off the fit by its own error only
        assert np.max(ellipse_distance(pts, t.center, t.a, t.b, t.beta)) < 0.03
    assert 0.85 < np.mean(ratios) < 1.05


def test_fit_residual_is_the_orthogonal_distance():
    rng = np.random.default_rng(6003)
    pts = ellipse_points(0, 0, 0.2, 2.0, 1.0, rng.uniform(0, 2 * np.pi, 12))
    pts = pts + rng.normal(0, 0.05, pts.shape)
    fit = fit_ellipse(pts)
    t = fit.trammel
    d = [
        brute_distance(p, float(t.X0), float(t.Y0), float(t.beta), float(t.a), float(t.b))
        for p in pts
    ]
    assert fit.rms == pytest.approx(np.sqrt(np.mean(np.square(d))), rel=1e-8)
    assert fit.max == pytest.approx(max(d), rel=1e-8)


@pytest.mark.parametrize(
    ("points", "words"),
    [
        ([[0, 0], [1, 0], [0, 1], [1, 1]], "at least 5 distinct points, got 4"),
        ([[0, 0], [1, 0], [0, 1], [1, 1], [1, 1], [0, 0]], "got 4 \\(of 6\\)"),
        ([[0, 0], [1, 0], [0, 1], [1, 1], [np.nan, 2]], "finite: row 4"),
        ([[0, 0], [1, 0], [0, 1], [1, 1], [np.inf, 2]], "finite"),
        ([[0, 0], [1, 2], [2, 4], [3, 6], [-1, -2], [7, 14]], "one line"),
        ([[0, 1, 2], [1, 2, 3]], "shape \\(N, 2\\)"),
        ([[t, t * t] for t in np.linspace(-1, 1, 15)], "parabola or a pair of lines"),
        ([[0, 0], [1, 0], [2, 0], [3, 0], [0, 1]], "parabola or a pair of lines"),
    ],
)
def test_fit_refusals(points, words):
    with pytest.raises(EllipseError, match=words):
        fit_ellipse(points)


# ----------------------------------------------------------------------------------------------
# The report behind `linkwright synth ellipse`


def test_synthesis_report_from_conic():
    coeffs = implicit_conic(1.0, 2.0, np.radians(30), 3.0, 1.0, scale=-7.0)
    seen = []
    r = ellipse_synthesis(conic=coeffs, family_samples=12, progress=seen.append)
    assert seen[0] == 0.0 and seen[-1] == 1.0 and seen == sorted(seen)
    assert r["source"] == "conic" and "fit" not in r
    assert r["trammel"] == pytest.approx(
        {"X0": 1.0, "Y0": 2.0, "beta_deg": 30.0, "a": 3.0, "b": 1.0}, rel=1e-12
    )
    np.testing.assert_allclose(r["conic"], normalise_conic(coeffs), rtol=1e-12, atol=1e-12)
    assert r["circle"] == "small" and r["cardan_radius"] == pytest.approx(1.0)
    assert r["canonical"]["deviation"] < 1e-13
    assert len(r["family"]) == 12
    for f in r["family"]:
        s1, s2 = np.radians(f["slider_angles_deg"])
        assert abs(np.sin(s1 - s2)) >= np.sin(np.radians(15)) - 1e-12
        assert f["deviation"] < 1e-13
        # The document round trip keeps the linkage (and it still traces the ellipse).
        doc = parse_document(json.loads(json.dumps(mechanism_to_dict(f["mechanism"]))))
        assert check_on_ellipse(doc.mechanism, coeffs) < 1e-12
    plain = {k: v for k, v in r.items() if k not in ("canonical", "family")}
    json.dumps(plain)  # everything but the mechanisms is plain Python
    large = ellipse_synthesis(conic=coeffs, family_samples=3, circle="large")
    assert large["cardan_radius"] == pytest.approx(2.0)
    assert float(large["canonical"]["mechanism"].q) == pytest.approx(1.0)
    assert max(f["deviation"] for f in large["family"]) < 1e-13


def test_synthesis_report_from_points():
    phi = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    pts = ellipse_points(-3.0, 0.5, -0.4, 5.0, 2.0, phi)
    r = ellipse_synthesis(points=pts, family_samples=2)
    assert r["source"] == "points"
    assert r["fit"]["count"] == 40 and r["fit"]["rms"] < 1e-12 and r["fit"]["max"] < 1e-12
    assert r["trammel"]["a"] == pytest.approx(5.0) and r["trammel"]["b"] == pytest.approx(2.0)
    assert r["trammel"]["beta_deg"] == pytest.approx(np.degrees(-0.4))
    assert len(r["family"]) == 2 and r["canonical"]["deviation"] < 1e-13


def test_synthesis_refusals():
    with pytest.raises(EllipseError, match="not neither"):
        ellipse_synthesis()
    with pytest.raises(EllipseError, match="not both"):
        ellipse_synthesis(conic=[1, 0, 1, 0, 0, -1], points=[[0, 0]] * 5)
    with pytest.raises(EllipseError, match="family_samples"):
        ellipse_synthesis(conic=[1, 0, 1, 0, 0, -1], family_samples=-1)
    with pytest.raises(EllipseError, match="one conic"):
        ellipse_synthesis(conic=[[1, 0, 1, 0, 0, -1]] * 2)
    with pytest.raises(EllipseError, match="a circle"):
        ellipse_synthesis(conic=[1, 0, 1, 0, 0, -1])


def test_family_angles_spread_and_clear_of_parallel():
    s = family_angles(400)
    assert s.shape == (400, 2) and np.all((s >= 0) & (s < np.pi))
    gap = np.abs((s[:, 0] - s[:, 1] + np.pi / 2) % np.pi - np.pi / 2)
    assert np.all(gap >= np.radians(15) - 1e-12)
    assert len({tuple(x) for x in np.round(s, 9)}) == 400
    # Spread: every 30° × 30° cell of the torus clear of the diagonal band holds some pairs.
    cells = {(int(a // np.radians(30)), int(b // np.radians(30))) for a, b in s}
    assert len(cells) >= 30
    np.testing.assert_array_equal(family_angles(5), family_angles(400)[:5])
    assert family_angles(0).shape == (0, 2)


# ----------------------------------------------------------------------------------------------
# Paper 004's sections 3–4, regenerated


def test_paper004_section4_example():
    from linkwright.papers import p004

    r = p004.section4_example()
    pr, ours, eig = r["printed"], r["ours"], r["eigen"]
    assert pr["k"] == pytest.approx(1.0, abs=1e-12)  # eq. 3 is already normalised
    for key in ("X0", "Y0", "a", "b"):
        assert pr[key] == pytest.approx(eig[key], rel=1e-12)
        assert ours[key] == pytest.approx(eig[key], rel=1e-12)
    # Eq. 12 in spreadsheet order is the eigenvector's axis; in the usual order it is not.
    assert (
        same_axis(np.radians(pr["beta_spreadsheet_order_deg"]), np.radians(eig["beta_deg"])) < 1e-12
    )
    assert same_axis(np.radians(pr["beta_usual_order_deg"]), np.radians(eig["beta_deg"])) > 0.1
    assert r["deviation"]["eq12_usual_order"] > 0.1
    assert r["deviation"]["eq12_spreadsheet_order"] < 1e-14
    for row in r["rows"]:
        for k in "dfg":
            assert row[k] == pytest.approx(row[f"{k}_eq14"], rel=1e-12)
        for k in "fg":  # the printed intermediate forms are misprints
            assert abs(row[f"{k}_eq14_intermediate"] - row[k]) > 0.1
        assert row["deviation"] < 1e-14
    assert r["pictured"]["circle"] == "large" and r["pictured"]["parameter_error"] < 1e-12


def test_paper004_synthesis_check():
    from linkwright.papers import p004

    r = p004.synthesis_check(count=40, members=4, samples=90)
    assert r["trammel_error"] < 1e-9 and r["axis_error_deg"] < 1e-9
    assert r["canonical_deviation"] < 1e-9 and r["family_deviation"] < 1e-9
    assert len(r["table"]) == 6

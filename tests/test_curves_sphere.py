"""Spherical curve descriptors and alignment: exact coefficients against quadrature, invariance
to rotations, start, direction and sampling density, size kept, ranking against the aligned
error, and the alignment against scipy's Kabsch solution and a brute-force distance."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve
from scipy.spatial.transform import Rotation

from linkwright.curves import (
    CurveError,
    SphereAlignment,
    sphere_align,
    sphere_descriptor_variants,
    sphere_descriptors,
    sphere_resample,
)
from linkwright.curves.spherical import _moments, _moments_reference
from linkwright.engine.kernels import spherical_fourbar_positions
from linkwright.mechanisms import SphericalFourBar, solve

DEG = np.pi / 180


def _fourbars(rng: np.random.Generator, n: int) -> SphericalFourBar:
    """Random spherical four-bars with a short crank (most of them turn it fully)."""
    return SphericalFourBar(
        frame=rng.uniform(30 * DEG, 80 * DEG, n),
        crank=rng.uniform(5 * DEG, 20 * DEG, n),
        coupler=rng.uniform(30 * DEG, 80 * DEG, n),
        rocker=rng.uniform(30 * DEG, 80 * DEG, n),
        point_arc=rng.uniform(10 * DEG, 70 * DEG, n),
        point_angle=rng.uniform(-np.pi, np.pi, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )


def _coupler_curves(rng: np.random.Generator, n: int, samples: int = 64) -> np.ndarray:
    """Closed coupler curves of random spherical four-bars whose crank turns fully (every
    sample assembles)."""
    theta = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    motion = solve(_fourbars(rng, 2 * n + 8), theta, order=0)
    curves = motion.positions["P"][motion.valid.all(axis=-1)]
    assert len(curves) >= n
    return curves[:n]


def _geodesic(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The point at fraction t of the great-circle arc from a to b (independent of the
    library: slerp)."""
    angle = np.arccos(np.clip(a @ b, -1, 1))
    return (np.sin((1 - t) * angle) * a + np.sin(t * angle) * b) / np.sin(angle)


def _densified(curve: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The same geodesic polygon with extra points inserted on a random half of its arcs."""
    out = []
    for j, p in enumerate(curve):
        out.append(p)
        if rng.random() < 0.5:
            q = curve[(j + 1) % len(curve)]
            for t in np.sort(rng.uniform(0.05, 0.95, rng.integers(1, 4))):
                out.append(_geodesic(p, q, t))
    return np.array(out)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    roll=st.integers(0, 47),
    backwards=st.booleans(),
)
def test_descriptor_invariances(seed, roll, backwards):
    rng = np.random.default_rng(seed)
    curve = _coupler_curves(rng, 1, samples=48)[0]
    turn = Rotation.random(random_state=seed).as_matrix()
    moved = np.roll(curve[::-1] if backwards else curve, roll, axis=0) @ turn.T
    moved = _densified(moved, rng)
    d0 = sphere_descriptors(curve)
    # The stored descriptor is one of the moved curve's variants, to rounding (the canonical
    # choice itself may differ where the normalisation's choices are nearly tied).
    nearest = np.min(np.linalg.norm(sphere_descriptor_variants(moved) - d0, axis=-1))
    assert nearest < 1e-10


def test_near_great_circle_uses_a_stable_pole():
    """A wobbly great circle (mean direction near zero): still invariant, through the scatter
    matrix's pole and its variants."""
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    lat = 0.2 * np.sin(3 * t) + 0.05 * np.cos(2 * t)
    curve = np.stack([np.cos(lat) * np.cos(t), np.cos(lat) * np.sin(t), np.sin(lat)], -1)
    d0 = sphere_descriptors(curve)
    for seed in range(5):
        turn = Rotation.random(random_state=seed).as_matrix()
        moved = np.roll(curve, 7 * seed, axis=0)[:: 1 - 2 * (seed % 2)] @ turn.T
        nearest = np.min(np.linalg.norm(sphere_descriptor_variants(moved) - d0, axis=-1))
        assert nearest < 1e-10


def _quadrature_moments(curve: np.ndarray, harmonics: int):
    """X_0, the scatter matrix and X_1 … X_K of the geodesic polygon by Gauss–Legendre
    quadrature on every arc (an independent derivation of the closed forms)."""
    nodes, weights = np.polynomial.legendre.leggauss(40)
    pts, ds = [], []
    for j, p in enumerate(curve):
        q = curve[(j + 1) % len(curve)]
        angle = np.arccos(np.clip(p @ q, -1, 1))
        u = (q - (p @ q) * p) / np.linalg.norm(q - (p @ q) * p)
        t = 0.5 * angle * (nodes + 1)
        pts.append(np.cos(t)[:, None] * p + np.sin(t)[:, None] * u)
        ds.append((0.5 * angle * weights, angle))
    length = sum(a for _, a in ds)
    starts = np.cumsum([0.0] + [a for _, a in ds])[:-1]
    x = np.concatenate(pts)
    w = np.concatenate([wj for wj, _ in ds])
    s = np.concatenate([s0 + 0.5 * a * (nodes + 1) for s0, (_, a) in zip(starts, ds, strict=True)])
    mean = (w[:, None] * x).sum(0) / length
    scatter = np.einsum("t,ti,tj->ij", w, x, x) / length
    n = np.arange(1, harmonics + 1)
    phase = np.exp(-2j * np.pi * np.outer(n, s) / length)
    return mean, scatter, (phase * w) @ x / length


@pytest.mark.parametrize("moments", [_moments, _moments_reference])
def test_coefficients_against_quadrature(moments):
    rng = np.random.default_rng(1)
    polygon = rng.normal(size=(7, 3)) + [0, 0, 2.5]  # a lopsided heptagon on a cap
    polygon /= np.linalg.norm(polygon, axis=-1, keepdims=True)
    big = rng.normal(size=(5, 3))  # one sprawling over most of the sphere
    big /= np.linalg.norm(big, axis=-1, keepdims=True)
    for curve in (polygon, big):
        want = _quadrature_moments(curve, 8)
        got = moments(curve[None], 8)
        for g, w in zip(got, want, strict=True):
            np.testing.assert_allclose(g[0], w, atol=1e-13)


@pytest.mark.parametrize("moments", [_moments, _moments_reference])
def test_great_circle_at_resonance(moments):
    """L = 2π makes ω_1 = 1, where the formula's sinc argument vanishes: the equator through
    five points has X_1 = (1, −i, 0)/2, X_0 = 0, scatter diag(½, ½, 0) exactly."""
    t = np.linspace(0, 2 * np.pi, 5, endpoint=False)
    equator = np.stack([np.cos(t), np.sin(t), np.zeros(5)], -1)
    mean, scatter, coeffs = moments(equator[None], 4)
    np.testing.assert_allclose(mean[0], 0, atol=1e-15)
    np.testing.assert_allclose(scatter[0], np.diag([0.5, 0.5, 0]), atol=1e-15)
    np.testing.assert_allclose(coeffs[0, 0], [0.5, -0.5j, 0], atol=1e-15)
    np.testing.assert_allclose(coeffs[0, 1:], 0, atol=1e-15)


def test_kernel_matches_numpy_reference():
    rng = np.random.default_rng(3)
    curves = _coupler_curves(rng, 300)
    curves[5, 7] = np.nan  # a linkage that does not assemble there
    curves[6] = curves[6, :1]  # a curve of length 0
    got, want = _moments(curves, 8), _moments_reference(curves, 8)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(np.isnan(g), np.isnan(w))
        assert np.isnan(g[5]).all() and np.isnan(g[6]).all()
        np.testing.assert_allclose(np.nan_to_num(g), np.nan_to_num(w), atol=1e-13)


def test_resample_walks_the_polygon():
    """A spherical square resampled at 400 points: its corners, and between them points on its
    sides, equally spaced along them."""
    colat = 50 * DEG
    az = np.arange(4) * np.pi / 2 + 0.3
    corners = np.stack(
        [np.sin(colat) * np.cos(az), np.sin(colat) * np.sin(az), np.full(4, np.cos(colat))], -1
    )
    dense = sphere_resample(corners, 400)
    np.testing.assert_allclose(np.linalg.norm(dense, axis=-1), 1, atol=1e-15)
    np.testing.assert_allclose(dense[::100], corners, atol=1e-14)
    side = np.arccos(corners[0] @ corners[1])
    steps = np.arccos(np.clip(np.sum(dense * np.roll(dense, -1, 0), -1), -1, 1))
    np.testing.assert_allclose(steps, side / 100, rtol=1e-9)
    normals = np.cross(corners, np.roll(corners, -1, 0))  # each side's great circle
    side_of = np.arange(400) // 100
    np.testing.assert_allclose(np.sum(dense * normals[side_of], -1), 0, atol=1e-15)
    opened = sphere_resample(corners, 7, closed=False)  # 6 steps over the 3 sides from 0 to 3
    np.testing.assert_allclose(opened[::2], corners, atol=1e-14)


def test_descriptor_is_exact_for_a_polygon():
    """An irregular pentagon, and the same pentagon with its 50 resampled points merged in
    along its sides: the same geodesic polygon, the same descriptor to rounding."""
    rng = np.random.default_rng(4)
    corners = rng.normal(size=(5, 3)) + [0, 0, 2]
    corners /= np.linalg.norm(corners, axis=-1, keepdims=True)
    arcs = np.arccos(np.sum(corners * np.roll(corners, -1, 0), -1))
    at = np.concatenate([[0.0], np.cumsum(arcs)[:-1]]) / arcs.sum()  # the corners' fractions
    order = np.argsort(np.concatenate([at, np.arange(50) / 50]), kind="stable")
    merged = np.concatenate([corners, sphere_resample(corners, 50)])[order]
    np.testing.assert_allclose(sphere_descriptors(merged), sphere_descriptors(corners), atol=1e-13)


def _circle(rho: float, axis, count: int = 720) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, count, endpoint=False)
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    a = np.cross(axis, [0.3, 1, 0.2])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    return np.cos(rho) * axis + np.sin(rho) * (np.cos(t)[:, None] * a + np.sin(t)[:, None] * b)


def test_size_is_kept():
    """Small circles of 20° and 40° (a scaled copy, were the sphere a plane): descriptors
    2·sin 10° apart — the chord between matching points of the coaxial circles — and each
    carries its own size: |Z_±1| = sin ρ, H_0 = cos ρ (to the 720-gon's O(1/N²))."""
    d20 = sphere_descriptors(_circle(20 * DEG, [0, 0, 1]))
    d40 = sphere_descriptors(_circle(40 * DEG, [1, -2, 0.5]))
    assert np.linalg.norm(d20 - d40) == pytest.approx(2 * np.sin(10 * DEG), abs=1e-4)
    for d, rho in ((d20, 20 * DEG), (d40, 40 * DEG)):
        assert d[0] == pytest.approx(np.sin(rho), abs=1e-5)  # Z_1 (counter-clockwise)
        assert d[-1] == pytest.approx(np.cos(rho), abs=1e-5)  # H_0
        assert np.linalg.norm(d[1:-1]) < 1e-5


def test_descriptor_distance_ranks_like_sphere_align():
    rng = np.random.default_rng(8)
    atlas = _coupler_curves(rng, 200)
    stored = sphere_descriptors(atlas)
    hits = 0
    for q in range(10):
        turn = Rotation.random(random_state=q).as_matrix()
        query = np.roll(atlas[q][:: 1 - 2 * (q % 2)], 5 * q, axis=0) @ turn.T
        query = query + rng.normal(scale=1e-3, size=query.shape)  # a slightly shaky hand
        query /= np.linalg.norm(query, axis=-1, keepdims=True)
        variants = sphere_descriptor_variants(query)
        dist = np.min(np.linalg.norm(stored[:, None, :] - variants[None], axis=-1), axis=1)
        fit = sphere_align(atlas, query, samples=96)
        exact = fit.error
        # Spearman rank correlation between the two orderings of all 200 curves.
        r = np.corrcoef(np.argsort(np.argsort(dist)), np.argsort(np.argsort(exact)))[0, 1]
        assert r > 0.9
        hits += int(np.argmin(dist) == q)
        # A descriptor distance is a chord RMS at some rotation and start: never below the
        # aligned one but for the band limit, which also filters out the noise (so curves
        # within a few noise levels of the query are left out).
        apart = fit.rms > 0.01
        assert np.all(dist[apart] >= 0.97 * fit.rms[apart])
    assert hits >= 9


@functools.cache
def _equal_arcs(count: int) -> np.ndarray:
    """``count`` points of a coupler curve (paper 000's Fig. 6 crank-rocker) with equal arcs
    between neighbours, solved for to rounding: its resampling at ``count`` is itself."""
    fig6 = np.radians([40, 20, 45, 35, 50, 130])

    def points(theta):
        return spherical_fourbar_positions(*fig6, 1, theta)[2][0]

    def arcs(rest):
        p = points(np.concatenate([[0.0], rest]))
        q = np.roll(p, -1, 0)  # arcs by atan2: arccos loses half the digits of a short one
        return 2 * np.arctan2(np.linalg.norm(q - p, axis=-1), np.linalg.norm(q + p, axis=-1))

    dense = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    step = arcs(dense[1:])
    s = np.concatenate([[0.0], np.cumsum(step)[:-1]]) / step.sum()
    guess = np.interp(np.arange(1, count) / count, s, dense)
    rest = fsolve(lambda r: np.diff(arcs(r)), guess, xtol=1e-13)
    assert np.ptp(arcs(rest)) < 1e-14
    return points(np.concatenate([[0.0], rest]))


@pytest.mark.parametrize("backwards", [False, True])
def test_align_recovers_a_known_rotation(backwards):
    curve = _equal_arcs(64)
    turn = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    order = (11 + (-1 if backwards else 1) * np.arange(64)) % 64  # from point 11 on
    target = curve[order] @ turn.T
    fit = sphere_align(curve, target, samples=64)
    assert isinstance(fit, SphereAlignment)
    np.testing.assert_allclose(fit.rotation, turn, atol=1e-9)
    assert np.linalg.det(fit.rotation) == pytest.approx(1.0, abs=1e-12)
    assert fit.rms < 1e-9 and fit.error < 1e-9
    assert bool(fit.reversed) is backwards
    assert fit.shift == pytest.approx(11 / 64, abs=1e-12)


def _start_at(curve: np.ndarray, fraction: float, backwards: bool) -> np.ndarray:
    """The same geodesic polygon, starting at ``fraction`` of its length (along its own
    direction) and run backwards if asked."""
    nxt = np.roll(curve, -1, 0)
    arcs = np.arccos(np.clip(np.sum(curve * nxt, -1), -1, 1))
    cum = np.concatenate([[0.0], np.cumsum(arcs)]) / arcs.sum()
    j = min(np.searchsorted(cum, fraction, "right") - 1, len(curve) - 1)
    point = _geodesic(curve[j], nxt[j], (fraction - cum[j]) / (cum[j + 1] - cum[j]))
    if backwards:
        return np.concatenate([[point], curve[j::-1], curve[:j:-1]])
    return np.concatenate([[point], curve[j + 1 :], curve[: j + 1]])


def test_align_against_kabsch_and_brute_force_distance():
    rng = np.random.default_rng(5)
    theta = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    mech = _fourbars(rng, 1)
    a = solve(mech, theta, order=0).positions["P"][0]
    other = SphericalFourBar(
        **{k: getattr(mech, k) for k in ("frame", "crank", "coupler", "rocker", "assembly")},
        point_arc=mech.point_arc * 1.05,
        point_angle=mech.point_angle + 0.05,
    )
    turn = Rotation.random(random_state=3).as_matrix()
    b = np.roll(solve(other, theta, order=0).positions["P"][0][::-1], 20, axis=0) @ turn.T
    samples = 128
    fit = sphere_align(a, b, samples=samples)
    rs_b = sphere_resample(b, samples)

    # scipy's Kabsch at every whole shift and both directions: sphere_align also tries those in
    # between, so it is at most that and not far below.
    ra = sphere_resample(a, samples)
    brute = np.inf
    for seq in (ra, np.roll(ra[::-1], 1, 0)):
        for k in range(samples):
            _, rssd = Rotation.align_vectors(rs_b, np.roll(seq, -k, 0))
            brute = min(brute, rssd / np.sqrt(samples))
    assert brute * (1 - 2e-2) <= fit.rms <= brute + 1e-12
    spread = np.sqrt(2 - 2 * np.linalg.norm(rs_b.mean(0)))
    assert fit.error == pytest.approx(fit.rms / spread, rel=1e-12)

    # The fields mean what they say: a started at `shift`, in its direction, turned by R, lies
    # on b's samples with RMS chord `rms` (to the interpolation's O(1/samples²)).
    moved = sphere_resample(_start_at(a, fit.shift, fit.reversed), samples) @ fit.rotation.T
    direct = np.sqrt(np.mean(np.sum((moved - rs_b) ** 2, -1)))
    assert direct == pytest.approx(fit.rms, rel=2e-3)
    # Brute-force distance from each moved point to b's geodesic polygon (densely sampled):
    # never above the point-to-point distance, and of its size.
    t = np.linspace(0, 1, 200, endpoint=False)
    dense = np.concatenate(
        [[_geodesic(p, q, x) for x in t] for p, q in zip(b, np.roll(b, -1, 0), strict=True)]
    )
    near = np.min(np.linalg.norm(moved[:, None] - dense[None], axis=-1), axis=1)
    to_polyline = np.sqrt(np.mean(near**2))
    assert 0.9 * fit.rms < to_polyline <= fit.rms * (1 + 1e-3)


def test_align_coaxial_circles_closed_form():
    """Circles of 20° and 22° about different axes: the best rotation lays one over the other,
    and every point is 2·sin 1° from its partner and from the other circle."""
    fit = sphere_align(_circle(20 * DEG, [0, 0, 1], 90), _circle(22 * DEG, [1, 1, 0], 90))
    assert fit.rms == pytest.approx(2 * np.sin(1 * DEG), rel=1e-3)
    np.testing.assert_allclose(fit.rotation @ [0, 0, 1], np.array([1, 1, 0]) / 2**0.5, atol=1e-6)


def test_batches_and_nan():
    rng = np.random.default_rng(2)
    curves = _coupler_curves(rng, 4)
    curves[1, 3] = np.nan  # does not assemble there
    fit = sphere_align(curves, curves[0], samples=64)
    assert fit.error.shape == (4,) and fit.rotation.shape == (4, 3, 3)
    assert fit.error[0] < 1e-12 and np.isnan(fit.error[1]) and not fit.reversed[1]
    assert np.isnan(fit.rotation[1]).all() and np.isfinite(fit.rotation[[0, 2, 3]]).all()
    d = sphere_descriptors(curves)
    assert d.shape == (4, 51) and np.isnan(d[1]).all() and np.isfinite(d[[0, 2, 3]]).all()
    assert np.isnan(sphere_descriptor_variants(curves)[1]).all()
    antipodal = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 0, 1.0]])  # no arc joins 1 and 2
    assert np.isnan(sphere_descriptors(antipodal)).all()


def test_bad_curves_are_named():
    with pytest.raises(CurveError, match="shape"):
        sphere_descriptors(np.zeros((5, 2)))
    with pytest.raises(CurveError, match="at least 3"):
        sphere_descriptors(np.eye(3)[:2])
    with pytest.raises(CurveError, match="unit vectors"):
        sphere_descriptors(2 * np.eye(3))
    with pytest.raises(CurveError, match="harmonics"):
        sphere_descriptors(np.eye(3), harmonics=0)
    with pytest.raises(CurveError, match="samples"):
        sphere_resample(np.eye(3), 2)

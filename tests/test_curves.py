"""Curve descriptors: invariances, the compiled kernel against the NumPy reference, ranking
against the aligned error, and the aligned error against a brute-force least squares."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.curves import (
    CurveError,
    align,
    aligned_error,
    descriptor_variants,
    descriptors,
    resample,
)
from linkwright.curves.fourier import _descriptors_reference, _turn
from linkwright.mechanisms import FourBar, solve


def _coupler_curves(rng: np.random.Generator, n: int, samples: int = 90) -> np.ndarray:
    """Closed coupler curves of Grashof crank-rockers (crank shortest, so every input turns)."""
    frame, coupler, rocker = rng.uniform(0.6, 1.0, (3, n))
    mech = FourBar(
        A0=np.zeros((n, 2)),
        B0=np.stack([frame, np.zeros(n)], -1),
        crank=rng.uniform(0.05, 0.19, n),
        coupler=coupler,
        rocker=rocker,
        u=rng.uniform(-1, 1, n),
        v=rng.uniform(-1, 1, n),
        assembly=rng.choice([-1.0, 1.0], n),
    )
    theta = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    motion = solve(mech, theta, order=0)
    assert motion.valid.all()
    return motion.positions["P"]


def _moved(curve: np.ndarray, angle: float, scale: float, shift, roll: int, backwards: bool):
    c, s = np.cos(angle), np.sin(angle)
    out = curve[::-1] if backwards else curve
    return scale * np.roll(out, roll, axis=0) @ np.array([[c, s], [-s, c]]) + np.asarray(shift)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    angle=st.floats(-np.pi, np.pi),
    scale=st.floats(1e-3, 1e3),
    shift=st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)),
    roll=st.integers(0, 89),
    backwards=st.booleans(),
)
def test_closed_descriptor_invariances(seed, angle, scale, shift, roll, backwards):
    curve = _coupler_curves(np.random.default_rng(seed), 1)[0]
    moved = _moved(curve, angle, scale, shift, roll, backwards)
    d0 = descriptors(curve)
    assert np.linalg.norm(d0) == pytest.approx(1.0)
    # The stored descriptor is one of the moved curve's variants, to rounding (the canonical
    # choice itself may differ where the normalisation's choices are nearly tied).
    nearest = np.min(np.linalg.norm(descriptor_variants(moved) - d0, axis=-1))
    assert nearest < 1e-8


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    angle=st.floats(-np.pi, np.pi),
    scale=st.floats(1e-3, 1e3),
    backwards=st.booleans(),
)
def test_open_descriptor_invariances(seed, angle, scale, backwards):
    rng = np.random.default_rng(seed)
    stroke = np.cumsum(rng.normal(size=(30, 2)), axis=0)
    moved = _moved(stroke, angle, scale, (3.0, -7.0), 0, backwards)
    d0 = descriptors(stroke, closed=False)
    nearest = np.min(np.linalg.norm(descriptor_variants(moved, closed=False) - d0, axis=-1))
    assert nearest < 1e-8


def test_kernel_matches_numpy_reference():
    rng = np.random.default_rng(3)
    curves = _coupler_curves(rng, 300, samples=64)
    curves[5, 7] = np.nan  # a linkage that does not assemble there
    curves[6] = curves[6, :1]  # a curve of length 0
    for closed in (True, False):
        got = descriptors(curves, closed=closed)
        want = _descriptors_reference(curves, closed=closed)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        assert np.isnan(got[5]).all() and np.isnan(got[6]).all()
        np.testing.assert_allclose(np.nan_to_num(got), np.nan_to_num(want), atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(t=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=64))
def test_turn_is_the_unit_circle_to_rounding(t):
    """The descriptor kernel's polynomial e^{−2πit} against NumPy's, and on the circle."""
    t = np.asarray(t)
    got = np.array([_turn(x) for x in t]).reshape(-1, 2)
    want = np.exp(-2j * np.pi * t)
    np.testing.assert_allclose(got[:, 0], want.real, rtol=0, atol=2e-15)
    np.testing.assert_allclose(got[:, 1], want.imag, rtol=0, atol=2e-15)
    np.testing.assert_allclose(np.hypot(got[:, 0], got[:, 1]), 1.0, rtol=0, atol=1e-15)


def test_polygon_coefficients_are_exact():
    """A polygon's coefficients are its own: a square described through its 4 corners and
    through 400 points along its sides gives the same descriptor (no resampling error)."""
    corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    dense = resample(corners, 400)
    np.testing.assert_allclose(descriptors(corners), descriptors(dense), atol=1e-13)


def _brute_aligned_error(curve, target, samples):
    a = resample(curve, samples)
    b = resample(target, samples)
    a = a[:, 0] + 1j * a[:, 1]
    b = b[:, 0] + 1j * b[:, 1]
    bc = b - b.mean()
    best = np.inf
    for seq in (a, a[::-1]):
        for k in range(samples):
            x = np.roll(seq, k)
            design = np.stack([x, np.ones_like(x)], -1)
            coef, *_ = np.linalg.lstsq(design, b, rcond=None)
            best = min(best, np.sum(np.abs(design @ coef - b) ** 2))
    return np.sqrt(best / np.sum(np.abs(bc) ** 2))


def test_aligned_error_against_brute_force():
    rng = np.random.default_rng(4)
    curves = _coupler_curves(rng, 4)
    for i in range(3):
        got = aligned_error(curves[i], curves[i + 1], samples=64)
        # The brute force tries whole shifts only; aligned_error also those in between.
        brute = _brute_aligned_error(curves[i], curves[i + 1], 64)
        assert brute * (1 - 1e-2) <= got <= brute + 1e-12
    moved = _moved(curves[0], 1.0, 3.0, (2, 2), 11, True)
    assert aligned_error(curves[0], moved) < 1e-3  # only the resampling's offset remains


def test_descriptor_distance_ranks_like_aligned_error():
    rng = np.random.default_rng(8)
    atlas = _coupler_curves(rng, 200)
    stored = descriptors(atlas)
    hits = 0
    for q in range(10):
        query = _moved(atlas[q], 0.3 * q, 2.0, (1, -1), 7 * q, q % 2 == 1)
        query = query + rng.normal(scale=1e-3, size=query.shape)  # a slightly shaky hand
        variants = descriptor_variants(query)
        dist = np.min(np.linalg.norm(stored[:, None, :] - variants[None], axis=-1), axis=1)
        exact = aligned_error(atlas, query, samples=128)
        # Spearman rank correlation between the two orderings of all 200 curves.
        r = np.corrcoef(np.argsort(np.argsort(dist)), np.argsort(np.argsort(exact)))[0, 1]
        assert r > 0.8
        hits += int(np.argmin(dist) == q)
    assert hits == 10


def test_bad_curves_are_named():
    with pytest.raises(CurveError, match="shape"):
        descriptors(np.zeros((5, 3)))
    with pytest.raises(CurveError, match="at least 3"):
        descriptors([[0, 0], [1, 1]])
    with pytest.raises(CurveError, match="harmonics"):
        descriptors(np.eye(3, 2), harmonics=0)
    with pytest.raises(CurveError, match="samples"):
        resample(np.eye(3, 2), 2)


def _vertex_fraction(curve: np.ndarray, index: int) -> float:
    """Where vertex ``index`` lies along the closed polygon, as a fraction of its length."""
    seg = np.linalg.norm(np.roll(curve, -1, axis=0) - curve, axis=-1)
    return float(np.sum(seg[:index]) / np.sum(seg))


def _circular_gap(a: float, b: float) -> float:
    return abs((a - b + 0.5) % 1.0 - 0.5)


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    angle=st.floats(-3.0, 3.0),
    scale=st.floats(1e-2, 1e2),
    shift=st.tuples(st.floats(-1e2, 1e2), st.floats(-1e2, 1e2)),
    roll=st.integers(0, 89),
    backwards=st.booleans(),
)
def test_align_recovers_the_transform(seed, angle, scale, shift, roll, backwards):
    curve = _coupler_curves(np.random.default_rng(seed), 1)[0]
    target = _moved(curve, angle, scale, shift, roll, backwards)
    fit = align(curve, target)
    size = np.sqrt(np.mean(np.sum((curve - curve.mean(0)) ** 2, -1)))  # RMS radius
    # The target starts at the curve's vertex 89 − ((−roll) mod 90) backwards, −roll forwards.
    start = (-roll) % 90
    start = 89 - start if backwards else start
    assert bool(fit.reversed) is backwards
    # Only the resampling's offset remains: the curves' corners make it up to ~1e-3 of the size.
    assert _circular_gap(float(fit.shift), _vertex_fraction(curve, start)) < 1e-4
    assert fit.scale == pytest.approx(scale, rel=5e-4)
    assert abs((fit.rotation - angle + np.pi) % (2 * np.pi) - np.pi) < 5e-4
    reach = scale * (size + np.linalg.norm(curve.mean(0)))  # w's error, carried to the origin
    np.testing.assert_allclose(fit.translation, shift, atol=5e-4 * reach)
    assert fit.rms < 3e-3 * scale * size
    assert fit.error == pytest.approx(aligned_error(curve, target), abs=1e-15)


def _start_at(curve: np.ndarray, fraction: float, backwards: bool) -> np.ndarray:
    """The same closed polygon, starting at ``fraction`` of its length (along its own
    direction) and run backwards if asked."""
    nxt = np.roll(curve, -1, axis=0)
    seg = np.linalg.norm(nxt - curve, axis=-1)
    cum = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
    j = min(np.searchsorted(cum, fraction, "right") - 1, len(curve) - 1)
    point = curve[j] + (fraction - cum[j]) / (cum[j + 1] - cum[j]) * (nxt[j] - curve[j])
    if backwards:
        return np.concatenate([[point], curve[j::-1], curve[:j:-1]])
    return np.concatenate([[point], curve[j + 1 :], curve[: j + 1]])


def _to_polyline(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Distance from each point to the closed polygon (brute force over every side)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    ab = b - a
    t = np.sum((points[:, None] - a) * ab, -1) / np.sum(ab * ab, -1)
    foot = a + np.clip(t, 0, 1)[..., None] * ab
    return np.min(np.linalg.norm(points[:, None] - foot, axis=-1), axis=1)


def test_align_fields_mean_what_they_say():
    """Two different coupler curves: the transform, applied to the curve started at ``shift``
    in its direction, lies on the target with the reported RMS; the distance to the target's
    polygon is never more and of the same size."""
    rng = np.random.default_rng(6)
    a, b = _coupler_curves(rng, 2)
    b = _moved(b, 2.0, 3.0, (1.0, -4.0), 40, True)
    fit = align(a, b)
    c, s = np.cos(fit.rotation), np.sin(fit.rotation)
    started = resample(_start_at(a, fit.shift, fit.reversed), 256)
    moved = fit.scale * started @ np.array([[c, s], [-s, c]]) + fit.translation
    samples = resample(b, 256)
    direct = np.sqrt(np.mean(np.sum((moved - samples) ** 2, -1)))
    assert direct == pytest.approx(fit.rms, rel=2e-3)  # to the interpolation's O(1/256²)
    radius = np.sqrt(np.mean(np.sum((samples - samples.mean(0)) ** 2, -1)))
    assert fit.error == pytest.approx(fit.rms / radius, rel=1e-12)
    near = np.sqrt(np.mean(_to_polyline(moved, b) ** 2))
    assert 0.9 * fit.rms < near <= fit.rms * (1 + 1e-3)


def test_align_batches_and_nan():
    rng = np.random.default_rng(7)
    curves = _coupler_curves(rng, 3)
    curves[1, 4] = np.nan  # a linkage that does not assemble there
    fit = align(curves, curves[0])
    assert fit.error.shape == (3,) and fit.translation.shape == (3, 2)
    assert fit.error[0] < 1e-12 and fit.scale[0] == pytest.approx(1.0)
    assert np.isnan([fit.error[1], fit.rms[1], fit.scale[1], fit.rotation[1], fit.shift[1]]).all()
    assert np.isnan(fit.translation[1]).all() and not fit.reversed[1]
    assert np.isfinite(fit.error[2]) and fit.error[2] > 0
    opened = align(curves[0], curves[0][::-1], closed=False)
    assert opened.reversed and opened.shift == 1 and opened.error < 1e-12

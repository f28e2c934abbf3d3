"""Property tests of the planar primitives in ``linkwright.geometry.plane``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from linkwright.geometry import plane

EPS = np.finfo(float).eps

# Coordinates of real linkages: zero or 1e-6 .. 1e3 in size (subnormal products are not a
# linkage's problem; overflow and underflow of the norm are tested on their own below).
coordinate = st.one_of(st.just(0.0), st.floats(1e-6, 1e3), st.floats(-1e3, -1e-6))
vector = hnp.arrays(np.float64, 2, elements=coordinate)
angle = st.floats(-10.0, 10.0)


def vectors(n):
    return hnp.arrays(np.float64, (n, 2), elements=coordinate)


def _size(*vs):
    return max(1.0, *(float(np.max(np.abs(v))) for v in vs))


@given(vector, vector, vector, st.floats(-10, 10))
def test_dot_is_symmetric_and_bilinear(a, b, c, k):
    assert plane.dot(a, b) == plane.dot(b, a)
    scale = _size(a, b, c) ** 2 * (1 + abs(k))
    assert math.isclose(
        plane.dot(a + c, b), plane.dot(a, b) + plane.dot(c, b), abs_tol=8 * EPS * scale
    )
    assert math.isclose(plane.dot(k * a, b), k * plane.dot(a, b), abs_tol=8 * EPS * scale)
    assert plane.dot(a, a) >= 0


@given(vector, vector, vector)
def test_cross_is_antisymmetric_and_matches_the_3d_cross_product(a, b, c):
    assert plane.cross(a, b) == -plane.cross(b, a)
    assert plane.cross(a, a) == 0
    expected = np.cross(np.append(a, 0.0), np.append(b, 0.0))[2]
    assert math.isclose(plane.cross(a, b), expected, abs_tol=4 * EPS * _size(a, b) ** 2)
    scale = _size(a, b, c) ** 2
    assert math.isclose(
        plane.cross(a + c, b), plane.cross(a, b) + plane.cross(c, b), abs_tol=8 * EPS * scale
    )


@given(vector, vector)
def test_perp_turns_a_quarter_counter_clockwise(a, b):
    p = plane.perp(a)
    assert plane.dot(a, p) == 0  # exact: x·(−y) + y·x
    assert plane.cross(a, p) == plane.dot(a, a)  # left turn, same length
    np.testing.assert_array_equal(plane.perp(p), -a)  # two quarter turns: a half turn
    np.testing.assert_array_equal(plane.perp(plane.perp(plane.perp(p))), a)  # four: none
    # cross(a, b) = dot(perp(a), b): "b to the left of a" is "b along perp(a)".
    assert plane.cross(a, b) == plane.dot(plane.perp(a), b)
    assert p.shape == a.shape and p is not a


@given(vector, st.floats(-1e3, 1e3))
def test_norm(a, k):
    n = plane.norm(a)
    assert n >= 0 and math.isclose(n, math.hypot(*a), rel_tol=2 * EPS)
    assert math.isclose(n * n, plane.dot(a, a), rel_tol=4 * EPS, abs_tol=1e-300)
    assert math.isclose(plane.norm(k * a), abs(k) * n, rel_tol=4 * EPS, abs_tol=1e-300)
    # Triangle inequality.
    assert plane.norm(a + a[::-1]) <= (n + plane.norm(a[::-1])) * (1 + 4 * EPS) + 1e-300


@given(st.floats(-1e3, 1e3), angle)
def test_polar_and_unit_direction(r, t):
    p = plane.polar(r, t)
    assert p.shape == (2,)
    assert math.isclose(plane.norm(p), abs(r), rel_tol=4 * EPS, abs_tol=1e-300)
    u = plane.unit_direction(t)
    assert math.isclose(plane.norm(u), 1.0, rel_tol=4 * EPS)
    np.testing.assert_allclose(p, r * u, rtol=0, atol=4 * EPS * abs(r))
    if r > 1e-200:
        # Its direction is the angle, modulo a turn (away from subnormal components).
        back = math.atan2(p[1], p[0])
        assert abs((back - t + math.pi) % (2 * math.pi) - math.pi) < 1e-12
    # A quarter turn more is perp.
    np.testing.assert_allclose(
        plane.unit_direction(t + math.pi / 2), plane.perp(u), rtol=0, atol=1e-15
    )


@given(vectors(7), vectors(7))
def test_functions_broadcast_over_leading_axes(a, b):
    for f in (plane.dot, plane.cross):
        out = f(a, b)
        assert out.shape == (7,)
        np.testing.assert_array_equal(out, [f(x, y) for x, y in zip(a, b, strict=True)])
    assert plane.norm(a).shape == (7,)
    np.testing.assert_array_equal(plane.perp(a), np.stack([plane.perp(x) for x in a]))
    # Broadcasting a single vector against a batch, and a batch of angles.
    np.testing.assert_array_equal(plane.dot(a, b[0]), [plane.dot(x, b[0]) for x in a])
    r = np.linspace(0.5, 2.0, 7)
    t = np.linspace(-3, 3, 7)
    assert plane.polar(r, t).shape == (7, 2)
    assert plane.polar(r[:, None], t[None, :]).shape == (7, 7, 2)
    assert plane.polar(2.0, t).shape == (7, 2)
    assert plane.unit_direction(t).shape == (7, 2)


@settings(max_examples=200)
@given(vector, vector, vector)
def test_solve_2x2_rows(r1, r2, x):
    rhs1, rhs2 = plane.dot(r1, x), plane.dot(r2, x)
    sol, det = plane.solve_2x2_rows(r1, r2, rhs1, rhs2)
    assert det == plane.cross(r1, r2)
    n1, n2 = plane.norm(r1), plane.norm(r2)
    if n1 == 0 or n2 == 0 or abs(det) <= 1e-6 * n1 * n2:
        return  # singular or nearly: the caller masks these
    # Backward-stable: the residual is rounding-sized relative to the data ...
    size = _size(x)
    assert abs(plane.dot(r1, sol) - rhs1) <= 64 * EPS * n1 * size * (n1 * n2 / abs(det))
    assert abs(plane.dot(r2, sol) - rhs2) <= 64 * EPS * n2 * size * (n1 * n2 / abs(det))
    # ... and the solution is forward-accurate to the condition number.
    cond = n1 * n2 / abs(det)
    np.testing.assert_allclose(sol, x, rtol=0, atol=64 * EPS * cond * size)


def test_solve_2x2_rows_batched_and_singular():
    rows1 = np.array([[1.0, 0.0], [1.0, 2.0], [2.0, 4.0]])
    rows2 = np.array([[0.0, 1.0], [3.0, 4.0], [1.0, 2.0]])  # the last pair is parallel
    rhs1 = np.array([5.0, 5.0, 1.0])
    rhs2 = np.array([7.0, 11.0, 1.0])
    with np.errstate(all="raise"):  # the function handles its own divisions by zero
        sol, det = plane.solve_2x2_rows(rows1, rows2, rhs1, rhs2)
    np.testing.assert_array_equal(det, [1.0, -2.0, 0.0])
    np.testing.assert_allclose(sol[:2], [[5.0, 7.0], [1.0, 2.0]])
    # Singular: inf/nan, not hidden (the caller masks the sample).
    assert not np.all(np.isfinite(sol[2]))


def test_doc_examples_exact():
    assert plane.dot(np.array([1.0, 2.0]), np.array([3.0, 4.0])) == 11.0
    assert plane.cross(np.array([1.0, 0.0]), np.array([0.0, 1.0])) == 1.0
    np.testing.assert_array_equal(plane.perp(np.array([1.0, 0.0])), [0.0, 1.0])
    assert plane.norm(np.array([3.0, 4.0])) == 5.0
    np.testing.assert_array_equal(plane.unit_direction(0.0), [1.0, 0.0])


@pytest.mark.parametrize("big", [1e150, 1e-150])
def test_norm_does_not_overflow_or_underflow(big):
    a = np.array([3.0, 4.0]) * big
    assert math.isclose(plane.norm(a), 5.0 * big, rel_tol=4 * EPS)

"""Slider dyads in planar Burmester synthesis (synthesis/slider_dyads.py): slider points are
checked by computing their positions here (collinear), the poles by their closed form, and every
returned slider-crank is solved again by the engine at each pose."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.mechanisms import SliderCrank, solve
from linkwright.synthesis import PrecisionError
from linkwright.synthesis.slider_dyads import (
    four_pose_slider_crank,
    four_pose_slider_point,
    slider_crank_from_dyads,
    slider_line,
    slider_point_circle,
    three_pose_slider_crank,
)

POSES = np.array([[0.0, 0.0], [1.0, 0.2], [1.8, 0.9]])
ANGLES = np.radians([0.0, 25.0, 60.0])


def _positions(p, a, x):
    """The positions of body point x (first pose) in every pose, written here apart."""
    out = []
    for pj, aj in zip(p, a, strict=True):
        c, s = np.cos(aj - a[0]), np.sin(aj - a[0])
        d = x - p[0]
        out.append(pj + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]]))
    return np.array(out)


def _pole(p, a, j):
    """The pole of the displacement 1 → j in closed form (Sandor and Erdman's construction):
    the fixed point of X ↦ Pj + R(X − P1), i.e. (I − R)X = Pj − R P1."""
    c, s = np.cos(a[j] - a[0]), np.sin(a[j] - a[0])
    r = np.array([[c, -s], [s, c]])
    return np.linalg.solve(np.eye(2) - r, p[j] - r @ p[0])


def _collinearity(xs):
    def cross(u, w):
        return u[0] * w[1] - u[1] * w[0]

    return max(abs(cross(xs[k] - xs[0], xs[1] - xs[0])) for k in range(2, len(xs)))


def _resolve(design, p, a):
    """Solve the slider-crank at its inputs (each pose on its own assembly sign) and return the
    largest position error and rod-angle error against the poses."""
    mech = design.mechanism
    first = solve(replace(mech, assembly=float(design.branches[0])), [design.inputs[0]], order=0)
    rod = first.positions["B"][0] - first.positions["A"][0]
    rod0 = np.arctan2(rod[1], rod[0])
    worst_p = worst_a = 0.0
    for j, (theta, sign) in enumerate(zip(design.inputs, design.branches, strict=True)):
        m = solve(replace(mech, assembly=float(sign)), [theta], order=0)
        assert m.valid[0]
        worst_p = max(worst_p, float(np.linalg.norm(m.positions["P"][0] - p[j])))
        rod = m.positions["B"][0] - m.positions["A"][0]
        turn = np.angle(np.exp(1j * (np.arctan2(rod[1], rod[0]) - rod0 - (a[j] - a[0]))))
        worst_a = max(worst_a, abs(float(turn)))
    return worst_p, worst_a


def test_the_slider_circle_passes_through_the_poles_and_its_points_move_on_lines():
    k = slider_point_circle(POSES, ANGLES)
    for j in (1, 2):
        assert abs(np.linalg.norm(_pole(POSES, ANGLES, j) - k.centre) - k.radius) < 1e-12
    for t in np.linspace(0, 2 * np.pi, 13):
        x = k.centre + k.radius * np.array([np.cos(t), np.sin(t)])
        assert _collinearity(_positions(POSES, ANGLES, x)) < 1e-11
    # A point off the circle is not a slider point, and says so in one line.
    with pytest.raises(PrecisionError, match="not a slider point"):
        slider_line(POSES, ANGLES, k.centre)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-2, 2), min_size=6, max_size=6),
    st.lists(st.floats(10, 170), min_size=2, max_size=2),
    st.floats(0, 2 * np.pi),
)
def test_every_point_of_the_slider_circle_moves_on_a_line(xy, turns, t):
    p = np.reshape(xy, (3, 2))
    a = np.radians([0.0, turns[0], turns[0] + turns[1]])
    assume(abs(turns[1]) > 5 and turns[0] + turns[1] < 350)  # no two poses turned alike
    k = slider_point_circle(p, a)
    assume(k.radius < 1e3)
    x = k.centre + k.radius * np.array([np.cos(t), np.sin(t)])
    xs = _positions(p, a, x)
    spread = max(1.0, k.radius) * max(1.0, float(np.ptp(xs)))
    # The cross product of two position differences: rounding of O(ε · spread²).
    assert _collinearity(xs) <= 1e-10 * spread**2


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.5, 1.5),
    st.floats(2.5, 4.0),
    st.floats(-1, 1),
    st.floats(-np.pi, np.pi),
    st.floats(-1, 1),
    st.floats(-1, 1),
)
def test_the_ball_point_of_a_slider_cranks_poses_is_its_slider_pin(crank, rod, off, angle, u, v):
    sc = SliderCrank(A0=[0.0, 0.0], crank=crank, rod=rod, line_point=[0.0, off],
                     line_angle=angle, u=u, v=v)  # fmt: skip
    m = solve(sc, np.radians([10, 70, 140, 220]), order=0)
    assert np.all(m.valid)
    rod_dir = m.positions["B"] - m.positions["A"]
    a = np.arctan2(rod_dir[:, 1], rod_dir[:, 0])
    b = four_pose_slider_point(m.positions["P"], a)
    # Well-conditioned poses (rod ≥ 2.5 cranks, turns of tens of degrees): a few ε of the size.
    assert np.linalg.norm(b - m.positions["B"][0]) < 1e-8


def test_three_pose_slider_crank_reaches_every_pose():
    for t in (0.3, 1.0, 2.5, 4.0):
        for pin in ([0.5, 0.5], [-1.0, 0.3]):
            d = three_pose_slider_crank(POSES, ANGLES, pin, t)
            err_p, err_a = _resolve(d, POSES, ANGLES)
            assert err_p <= 1e-9 and err_a <= 1e-9
            assert d.error <= 1e-9


def test_four_pose_slider_crank_reaches_every_pose():
    sc = SliderCrank(A0=[0.1, 0.2], crank=1, rod=3, line_point=[0, -0.5], line_angle=0.3,
                     u=1.2, v=0.8)  # fmt: skip
    m = solve(sc, np.radians([10, 60, 120, 170]), order=0)
    rod = m.positions["B"] - m.positions["A"]
    p, a = m.positions["P"], np.arctan2(rod[:, 1], rod[:, 0])
    found = 0
    for beta2 in np.radians([20, 50, 100, 200, 300]):
        for closure in (0, 1):
            try:
                d = four_pose_slider_crank(p, a, beta2, closure)
            except PrecisionError:
                continue
            err_p, err_a = _resolve(d, p, a)
            assert err_p <= 1e-9 and err_a <= 1e-9
            found += 1
    assert found >= 4
    # The crank the poses came from (β2 = 50°, its A0) gives back the slider-crank itself.
    d = four_pose_slider_crank(p, a, np.radians(50), 0)
    assert np.allclose(d.mechanism.A0, [0.1, 0.2], atol=1e-9)
    assert abs(float(d.mechanism.rod) - 3) < 1e-9 and abs(float(d.mechanism.crank) - 1) < 1e-9


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: slider_point_circle([[0, 0], [1, 0], [2, 1]], [0, 0, 0]), "turned alike"),
        (lambda: slider_point_circle([[0, 0], [1, 0], [2, 1]], [0, 0.3, 0.3]), "turned alike"),
        (
            lambda: slider_crank_from_dyads(
                POSES, ANGLES, [0, 0], [0.5, 0.5], slider_point_circle(POSES, ANGLES).centre
            ),
            "not a slider point",
        ),
        (
            lambda: four_pose_slider_crank(
                np.zeros((4, 2)) + np.arange(4)[:, None], [0, 1, 2, 3], 0.5, 2
            ),
            "closure",
        ),
    ],
)
def test_degenerate_requests_are_one_line_errors(call, message):
    with pytest.raises(PrecisionError, match=message) as info:
        call()
    assert "\n" not in str(info.value)

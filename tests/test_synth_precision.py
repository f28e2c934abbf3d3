"""Precision-point synthesis (Freudenstein, Burmester, path with timing) against independent checks.

Every check here is computed without the code under test: four-bar positions from the
circle–circle closed form written below, poses moved by explicit rotations, the centre-point
curve as the vanishing 3×3 determinant of the perpendicular-bisector equations (a formulation
in the centre point g, not in the dyad angles β the library uses), Chebyshev points from
``numpy.polynomial``, and the five-pose solutions by multi-start root finding with scipy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from numpy.polynomial import chebyshev
from scipy.optimize import fsolve

from linkwright.io import mechanism_to_dict, parse_document
from linkwright.mechanisms import circuit, configurations, input_range, solve
from linkwright.synthesis.burmester import (
    burmester_fourbars,
    burmester_points,
    centre_point_curve,
    four_pose_dyads,
    four_pose_fourbar,
)
from linkwright.synthesis.precision import (
    PrecisionError,
    chebyshev_spacing,
    fourbar_from_dyads,
    freudenstein,
    function_error,
    function_pairs,
    path_with_timing,
    pose_positions,
    three_pose_fourbar,
)

TOL = 1e-9

# --- independent geometry ------------------------------------------------------------------------


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def cross2(p, q):
    return p[0] * q[1] - p[1] * q[0]


def rot(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s], [s, c]])


def fourbar_state(A0, B0, a, b, c, u, v, theta, branch):
    """A, B, P and the coupler angle (of B − A) of a four-bar, or None where it cannot close.

    B is b from A and c from B0 on the side sign((B0 − A) × (B − A)) = branch.
    """
    A0, B0 = np.asarray(A0, float), np.asarray(B0, float)
    A = A0 + a * np.array([math.cos(theta), math.sin(theta)])
    d = B0 - A
    L = math.hypot(*d)
    if L < 1e-12:
        return None
    x = (b * b - c * c + L * L) / (2 * L)
    h2 = b * b - x * x
    if h2 < 0:
        return None
    e = d / L
    n = np.array([-e[1], e[0]])
    B = A + x * e + branch * math.sqrt(h2) * n
    ex = (B - A) / b
    P = A + u * ex + v * np.array([-ex[1], ex[0]])
    return A, B, P, math.atan2(ex[1], ex[0])


def moved(points, angles, first):
    """Position in pose j of the body point at ``first`` in pose 1 (explicit rotation)."""
    points = np.asarray(points, float)
    return np.array(
        [
            points[j] + rot(angles[j] - angles[0]) @ (np.asarray(first) - points[0])
            for j in range(len(points))
        ]
    )


def circle_residual(points, angles, centre, circle):
    """How far a dyad's moving pivot is off a circle about its centre, relative to its radius."""
    r = np.linalg.norm(moved(points, angles, circle) - centre, axis=-1)
    return float(np.max(np.abs(r - r[0])) / max(r[0], 1e-300))


def bisector_cubic(points, angles, g, rows):
    """det of the perpendicular-bisector equations in the circle point c for centre g.

    For a circle point c (first pose) its pose-j position is Rj c + dj, and |Rj c + dj − g| =
    |c − g| is linear in c: (Rjᵀ(dj − g) + g)·c = dj·g − |dj|²/2. Three such rows (poses 1, j,
    k, l) have a common c only where the 3×3 determinant of [row | rhs] vanishes: the centre-point
    curve of poses 1 j k l. Returned relative to the product of the rows' norms (the rhs in units
    of the poses' spread), each at least the spread: a row vanishes where g is a pole.
    """
    points = np.asarray(points, float)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    M = []
    for j in rows:
        R = rot(angles[j] - angles[0])
        dj = points[j] - R @ points[0]
        M.append([*(R.T @ (dj - g) + g), (dj @ g - dj @ dj / 2) / spread])
    M = np.array(M)
    return np.linalg.det(M) / np.prod(np.maximum(np.linalg.norm(M, axis=1), spread))


def coupler_poses(fb_args, thetas, branch=1):
    """Poses (P, coupler angle) of a four-bar at the inputs, from the closed form."""
    states = [fourbar_state(*fb_args, t, branch) for t in thetas]
    if any(s is None for s in states):
        return None
    return np.array([s[2] for s in states]), np.array([s[3] for s in states]), states


def check_design_reaches(design, points, angles):
    """The design's four-bar, simulated by the engine on each pose's assembly, meets every pose."""
    mech = design.mechanism
    scale = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    for sign, motion in configurations(mech, design.inputs):
        at = design.branches == sign[0]
        if not np.any(at):
            continue
        assert np.all(motion.valid[at])
        P = motion.positions["P"][at]
        assert np.max(np.linalg.norm(P - points[at], axis=-1)) <= TOL * scale
        line = motion.positions["B"][at] - motion.positions["A"][at]
        turned = np.arctan2(line[:, 1], line[:, 0])
        # The coupler turns with the poses: its line's angle minus the pose angle is constant.
        lag = wrap(turned - angles[at] - (turned[0] - angles[at][0]))
        assert np.max(np.abs(lag)) <= TOL
    # All poses on one assembly line up with the first pose's lag too.
    states = [
        fourbar_state(
            mech.A0,
            mech.B0,
            float(mech.crank),
            float(mech.coupler),
            float(mech.rocker),
            float(mech.u),
            float(mech.v),
            t,
            s,
        )
        for t, s in zip(design.inputs, design.branches, strict=True)
    ]
    lags = wrap(np.array([s[3] for s in states]) - angles)
    assert np.max(np.abs(wrap(lags - lags[0]))) <= TOL
    assert np.max(np.linalg.norm(np.array([s[2] for s in states]) - points, axis=-1)) <= TOL * scale


# --- strategies ----------------------------------------------------------------------------------

coord = st.floats(-1.5, 1.5)
length = st.floats(0.5, 3.0)
offset = st.floats(-2.0, 2.0)


@st.composite
def fourbars(draw):
    """A Grashof four-bar whose crank A0A turns fully (crank shortest), not a change point:
    every input assembles, away from the dyad's limits."""
    a = draw(st.floats(0.3, 1.0))
    b, c, d = (draw(st.floats(a + 0.4, 3.0)) for _ in range(3))
    longest = max(b, c, d)
    assume(a + longest < b + c + d - longest - 0.1)
    A0 = np.array([draw(coord), draw(coord)])
    t = draw(st.floats(-math.pi, math.pi))
    B0 = A0 + d * np.array([math.cos(t), math.sin(t)])
    return (A0, B0, a, b, c, draw(offset), draw(offset))


@st.composite
def fourbar_poses(draw, n):
    """n poses of a random crank-rocker's (or drag link's) coupler on one assembly."""
    fb = draw(fourbars())
    branch = draw(st.sampled_from([1.0, -1.0]))
    t0 = draw(st.floats(-math.pi, math.pi))
    steps = [draw(st.floats(0.3, 1.2)) for _ in range(n - 1)]
    thetas = t0 + np.concatenate(([0.0], np.cumsum(steps)))
    got = coupler_poses(fb, thetas, branch)
    assume(got is not None)
    points, angles, states = got
    # Away from the dyad's limit position, where poses crowd together, and from a folded dyad.
    for s in states:
        A, B = s[0], s[1]
        assume(np.linalg.norm(fb[1] - A) > 0.05)
        side = cross2(fb[1] - A, B - A) / (np.linalg.norm(fb[1] - A) * fb[3])
        assume(abs(side) > 0.05)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    assume(spread > 0.1)
    # The coupler must turn (a parallelogram's only translates).
    assume(np.ptp(angles) > 0.05)
    # Both moving pivots must move (a folded four-bar can hold B still on A0).
    for k in (0, 1):
        q = np.array([s[k] for s in states])
        assume(np.min(np.linalg.norm(q[:, None] - q[None], axis=-1)[np.triu_indices(n, 1)]) > 0.05)
    return fb, branch, thetas, points, angles, states


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


# --- poses, three-pose motion generation ---------------------------------------------------------


def test_pose_positions_is_the_rigid_motion():
    pts = np.array([[0.0, 0.0], [1.0, 2.0], [-1.0, 0.5]])
    ang = np.array([0.3, 1.1, -0.4])
    first = np.array([[2.0, -1.0], [0.5, 0.5]])
    got = pose_positions(pts, ang, first)
    for k in range(2):
        assert np.allclose(got[:, k], moved(pts, ang, first[k]), atol=1e-14)
    # A body point keeps its distance to the pose point.
    assert np.allclose(np.linalg.norm(got[:, 0] - pts, axis=-1), np.linalg.norm(first[0] - pts[0]))


@settings(max_examples=30, deadline=None)
@given(fourbar_poses(3))
def test_three_poses_of_a_fourbar_give_back_its_pivots(case):
    fb, branch, thetas, points, angles, states = case
    A1, B1 = states[0][0], states[0][1]
    design = three_pose_fourbar(points, angles, [A1, B1])
    m = design.mechanism
    scale = max(np.max(np.abs(points)), 1.0) * 10
    assert np.allclose(m.A0, fb[0], atol=1e-8 * scale)
    assert np.allclose(m.B0, fb[1], atol=1e-8 * scale)
    assert np.allclose([m.crank, m.coupler, m.rocker, m.u, m.v], fb[2:], atol=1e-8 * scale)
    assert np.allclose(wrap(design.inputs - thetas), 0.0, atol=1e-8)
    assert np.all(design.branches == branch)
    assert not design.branch_defect


@settings(max_examples=40, deadline=None)
@given(
    pts=st.lists(st.tuples(coord, coord), min_size=3, max_size=3),
    ang=st.lists(st.floats(-math.pi, math.pi), min_size=3, max_size=3),
    circ=st.lists(st.tuples(coord, coord), min_size=2, max_size=2),
)
def test_three_pose_fourbar_on_random_poses(pts, ang, circ):
    points, angles, circles = np.array(pts), np.array(ang), np.array(circ)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    assume(spread > 0.2)
    assume(np.min(np.abs(wrap(angles[:, None] - angles[None]))[np.triu_indices(3, 1)]) > 0.05)
    assume(np.linalg.norm(circles[0] - circles[1]) > 0.1)
    # Keep away from moving pivots whose three positions are nearly collinear.
    for c in circles:
        q = moved(points, angles, c)
        area = abs(cross2(q[1] - q[0], q[2] - q[0]))
        assume(area > 0.02 * max(np.linalg.norm(q[1] - q[0]), np.linalg.norm(q[2] - q[0])) ** 2)
    design = three_pose_fourbar(points, angles, circles)
    m = design.mechanism
    for centre, c in ((m.A0, circles[0]), (m.B0, circles[1])):
        assert circle_residual(points, angles, centre, c) < 1e-9
    # A pose at a dead centre (A, B, B0 in line) is met only to the square root of rounding:
    # the dyad's position there is the root of a vanishing discriminant.
    A, B = moved(points, angles, circles[0]), moved(points, angles, circles[1])
    for a, b in zip(A, B, strict=True):
        side = cross2(m.B0 - a, b - a) / (np.linalg.norm(m.B0 - a) * np.linalg.norm(b - a))
        assume(abs(side) > 1e-3)
    check_design_reaches(design, points, angles)
    # The coupler-frame form of the same pivots gives the same four-bar.
    local = (circles - points[0]) @ rot(angles[0])  # rows: R(α1)ᵀ (c − P1)
    again = three_pose_fourbar(points, angles, local, frame="coupler")
    assert np.allclose(again.mechanism.A0, m.A0, rtol=1e-9, atol=1e-9)
    assert np.allclose(again.mechanism.B0, m.B0, rtol=1e-9, atol=1e-9)


def test_three_pose_fourbar_errors():
    pts, ang = [[0, 0], [1, 0.5], [2, 0]], np.radians([0, 30, 60])
    with pytest.raises(PrecisionError, match="exactly 3"):
        three_pose_fourbar(pts[:2], ang[:2], [[0, -1], [1, -1]])
    with pytest.raises(PrecisionError, match="poses 1 and 3 coincide"):
        three_pose_fourbar([[0, 0], [1, 0.5], [0, 0]], [0.1, 0.2, 0.1], [[0, -1], [1, -1]])
    with pytest.raises(PrecisionError, match="collinear"):
        three_pose_fourbar([[0, 0], [1, 0], [2, 0]], [0, 0, 0], [[0, 1], [1, 1]])
    with pytest.raises(PrecisionError, match="moving pivots coincide"):
        three_pose_fourbar(pts, ang, [[0, -1], [0, -1]])
    with pytest.raises(PrecisionError, match="frame must be"):
        three_pose_fourbar(pts, ang, [[0, -1], [1, -1]], frame="world")
    with pytest.raises(PrecisionError, match="one angle per point"):
        three_pose_fourbar(pts, ang[:2], [[0, -1], [1, -1]])
    # The pole of poses 1 and 2 as a moving pivot: its first two positions coincide.
    z = complex(*pts[1]) - complex(*pts[0]) * np.exp(1j * ang[1])
    pole = z / (1 - np.exp(1j * ang[1]))
    with pytest.raises(PrecisionError, match="collinear or coincide"):
        three_pose_fourbar(pts, ang, [[pole.real, pole.imag], [1, -1]])


def test_fourbar_from_dyads_rejects_a_pivot_off_its_circle():
    pts, ang = np.array([[0, 0], [1, 0.5], [2, 0]]), np.radians([0, 30, 60])
    design = three_pose_fourbar(pts, ang, [[0, -1], [1, -1]])
    centres = np.stack((design.mechanism.A0, design.mechanism.B0))
    fourbar_from_dyads(pts, ang, centres, [[0, -1], [1, -1]])
    with pytest.raises(PrecisionError, match=r"crank pivot's positions .* lie off a circle"):
        fourbar_from_dyads(pts, ang, centres + [[1e-4, 0], [0, 0]], [[0, -1], [1, -1]])
    with pytest.raises(PrecisionError, match="lies on its centre"):
        fourbar_from_dyads(pts, ang, [[0, -1], centres[1]], [[0, -1], [1, -1]])


def test_design_survives_a_document_round_trip():
    pts, ang = [[0, 0], [1, 0.5], [2, 0]], np.radians([0, 30, 60])
    design = three_pose_fourbar(pts, ang, [[0, -1], [1, -1]])
    doc = mechanism_to_dict(design.mechanism)
    back = parse_document(doc)
    back = getattr(back, "mechanism", back)
    motion = solve(back, design.inputs)
    assert np.allclose(motion.positions["P"], pts, atol=1e-9)


# --- four poses ----------------------------------------------------------------------------------


@settings(max_examples=25, deadline=None)
@given(
    pts=st.lists(st.tuples(coord, coord), min_size=4, max_size=4),
    ang=st.lists(st.floats(-math.pi, math.pi), min_size=4, max_size=4),
)
def test_centre_point_curve_dyads_are_compatible(pts, ang):
    points, angles = np.array(pts), np.array(ang)
    gaps = np.linalg.norm(points[:, None] - points[None], axis=-1)[np.triu_indices(4, 1)]
    turns = np.abs(wrap(np.subtract.outer(angles, angles)))[np.triu_indices(4, 1)]
    assume(np.min(np.maximum(gaps, turns)) > 0.1)
    curves = centre_point_curve(points, angles, samples=90)
    spread = np.max(gaps)
    checked = 0
    for k in range(2):
        for i in np.flatnonzero(curves.valid[k]):
            g, c = curves.centres[k, i], curves.circles[k, i]
            # Far along the asymptotes the dyad is nearly a slider; its circle is huge.
            if np.linalg.norm(g) > 50 * spread or np.linalg.norm(c) > 50 * spread:
                continue
            # Independent residual: the four positions of c on one circle about g.
            r = np.linalg.norm(moved(points, angles, c) - g, axis=-1)
            assert np.max(np.abs(r - r[0])) <= 1e-9 * max(r[0], spread)
            # And g on the centre-point curve in the bisector formulation.
            assert abs(bisector_cubic(points, angles, g, (1, 2, 3))) < 1e-8
            # The ground link turns by the sampled β2 between poses 1 and 2.
            q = moved(points, angles, c)
            b2 = math.atan2(*(q[1] - g)[::-1]) - math.atan2(*(q[0] - g)[::-1])
            assert abs(wrap(b2 - curves.beta2[i])) < 1e-7
            checked += 1
    assert np.all(np.isnan(curves.centres[~curves.valid]))


@settings(max_examples=25, deadline=None)
@given(fourbar_poses(4))
def test_a_fourbars_own_dyads_lie_on_its_four_pose_curves(case):
    fb, _, thetas, points, angles, states = case
    beta = thetas[1] - thetas[0]
    g, c, ok = four_pose_dyads(points, angles, [beta])
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    dist = [np.linalg.norm(g[k, 0] - fb[0]) if ok[k, 0] else np.inf for k in range(2)]
    k = int(np.argmin(dist))
    assert dist[k] < 1e-7 * max(spread, 1)
    assert np.linalg.norm(c[k, 0] - states[0][0]) < 1e-7 * max(spread, 1)
    # Both of the four-bar's dyads, picked by their β2, rebuild it.
    rocker_turn = [math.atan2(*(s[1] - fb[1])[::-1]) for s in states[:2]]
    beta_r = rocker_turn[1] - rocker_turn[0]
    gr, _, okr = four_pose_dyads(points, angles, [beta_r])
    kr = int(
        np.argmin([np.linalg.norm(gr[j, 0] - fb[1]) if okr[j, 0] else np.inf for j in range(2)])
    )
    design = four_pose_fourbar(points, angles, [beta, beta_r], [k, kr])
    assert np.allclose(design.mechanism.B0, fb[1], atol=1e-7 * max(spread, 1))
    assert not design.branch_defect
    check_design_reaches(design, points, angles)


def test_four_pose_fourbar_picks_and_errors():
    pts, ang = [[0, 0], [1, 0.4], [2, 0.3], [2.6, -0.5]], np.radians([0, 20, 35, 70])
    design = four_pose_fourbar(pts, ang, np.radians([-30, 40]), [1, 1])
    check_design_reaches(design, np.array(pts, float), ang)
    with pytest.raises(PrecisionError, match="no real dyad at β2 = 60°"):
        four_pose_fourbar(pts, ang, np.radians([60, 40]), [0, 0])
    with pytest.raises(PrecisionError, match="closure must be 0 or 1"):
        four_pose_fourbar(pts, ang, np.radians([-30, 40]), [0, 2])
    with pytest.raises(PrecisionError, match="exactly 4"):
        centre_point_curve(pts[:3], ang[:3])
    with pytest.raises(PrecisionError, match="poses 2 and 4 coincide"):
        centre_point_curve([[0, 0], [1, 0.4], [2, 0.3], [1, 0.4]], [0, 0.2, 0.3, 0.2])


# --- five poses ----------------------------------------------------------------------------------


def independent_burmester(points, angles, starts=300, seed=0):
    """Every real solution of |Dj c − g| = |c − g| (j = 2..5) found by scipy from many starts."""
    points = np.asarray(points, float)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    mats = [rot(angles[j] - angles[0]) for j in range(5)]

    def F(x):
        g, c = x[:2], x[2:]
        return [
            (np.sum((points[j] + mats[j] @ (c - points[0]) - g) ** 2) - np.sum((c - g) ** 2))
            / spread**2
            for j in range(1, 5)
        ]

    rng = np.random.default_rng(seed)
    centre = points.mean(axis=0)
    found = []
    for _ in range(starts):
        x0 = np.concatenate([centre, centre]) + rng.normal(scale=3 * spread, size=4)
        x, _, ier, _ = fsolve(F, x0, full_output=True, xtol=1e-13)
        if ier != 1 or np.max(np.abs(F(x))) > 1e-12:
            continue
        # A dyad of length 0 (g = c) solves nothing unless c is a common pole; skip it.
        if np.linalg.norm(x[:2] - x[2:]) < 1e-6 * spread:
            continue
        if not any(np.linalg.norm(x - y) < 1e-6 * spread for y in found):
            found.append(x)
    return found


@settings(max_examples=15, deadline=None)
@given(fourbar_poses(5))
def test_burmester_points_of_a_fourbars_poses(case):
    fb, _, _, points, angles, states = case
    bp = burmester_points(points, angles)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    # 2 or 4, or 3 where two coincide (a double point is reported once).
    assert int(bp.count) in (2, 3, 4)
    assert np.all(bp.real[: int(bp.count)])
    tol = 1e-7 * max(spread, 1)
    for pivot, moving in ((fb[0], states[0][0]), (fb[1], states[0][1])):
        d = np.linalg.norm(bp.centres[bp.real] - pivot, axis=-1)
        k = int(np.argmin(d))
        assert d[k] < tol
        assert np.linalg.norm(bp.circles[bp.real][k] - moving) < tol
    for g, c in zip(bp.centres[bp.real], bp.circles[bp.real], strict=True):
        if np.linalg.norm(g) > 100 * spread:
            continue
        assert circle_residual(points, angles, g, c) < 1e-8
        assert abs(bisector_cubic(points, angles, g, (1, 2, 3))) < 1e-7
        assert abs(bisector_cubic(points, angles, g, (1, 2, 4))) < 1e-7


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5, 6])
def test_burmester_points_match_a_multistart_search(seed):
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, size=(5, 2)) * [2.0, 1.0]
    angles = np.sort(rng.uniform(-1.5, 1.5, size=5))
    bp = burmester_points(points, angles)
    count = int(bp.count)
    assert count in (0, 2, 4)
    search = independent_burmester(points, angles)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    ours = np.concatenate((bp.centres[bp.real], bp.circles[bp.real]), axis=1)
    # Every solution the search finds is one of ours, and (with 300 starts) it finds them all.
    for x in search:
        assert np.min(np.linalg.norm(ours - x, axis=1)) < 1e-6 * spread
    assert len(search) == count
    for g in bp.centres[bp.real]:
        assert abs(bisector_cubic(points, angles, g, (1, 2, 3))) < 1e-8
        assert abs(bisector_cubic(points, angles, g, (1, 2, 4))) < 1e-8
    if count >= 2:
        design, pairs = burmester_fourbars(points, angles)
        assert len(pairs) == count * (count - 1)
        assert np.max(design.error) < 1e-9
        for k in range(len(pairs)):
            one = fourbar_from_dyads(points, angles, bp.centres[pairs[k]], bp.circles[pairs[k]])
            check_design_reaches(one, points, angles)


def test_burmester_fourbars_of_a_fourbar_include_it_without_defects():
    fb = ([0.0, 0.0], [3.0, 0.5], 1.0, 3.2, 2.6, 1.0, 1.5)
    points, angles, _ = coupler_poses(fb, np.radians([5.7, 45.8, 85.9, 137.5, 200.5]))
    design, _ = burmester_fourbars(points, angles)
    m = design.mechanism
    own = (np.linalg.norm(m.A0, axis=-1) < 1e-9) & (np.linalg.norm(m.B0 - [3, 0.5], axis=-1) < 1e-9)
    assert own.sum() == 1
    k = int(np.flatnonzero(own)[0])
    assert not design.branch_defect[k] and not design.order_defect[k]
    assert np.allclose([m.crank[k], m.coupler[k], m.rocker[k], m.u[k], m.v[k]], fb[2:])
    # Driven from the other side (the rocker B0B as crank) the same linkage swings: it passes a
    # dead centre between poses, a branch defect.
    swapped = (np.linalg.norm(m.B0, axis=-1) < 1e-9) & (
        np.linalg.norm(m.A0 - [3, 0.5], axis=-1) < 1e-9
    )
    assert design.branch_defect[np.flatnonzero(swapped)[0]]


def test_order_defect_of_poses_out_of_sequence():
    # The four-bar meets the poses on one assembly, but its crank (which turns fully) meets them
    # in the order 1, 3, 2, 4: an order defect. The same poses in crank order have none.
    fb = ([0.0, 0.0], [3.0, 0.5], 1.0, 3.2, 2.6, 1.0, 1.5)
    thetas = np.radians([0.0, 100.0, 50.0, 200.0])
    points, angles, states = coupler_poses(fb, thetas)
    circles = [states[0][0], states[0][1]]
    bad = fourbar_from_dyads(points, angles, [fb[0], fb[1]], circles)
    assert not bad.branch_defect and bad.order_defect
    order = [0, 2, 1, 3]
    good = fourbar_from_dyads(points[order], angles[order], [fb[0], fb[1]], circles)
    assert not good.branch_defect and not good.order_defect


def test_burmester_errors():
    pts = [[0, 0], [1, 0.4], [2, 0.3], [2.6, -0.5], [3, 0]]
    ang = np.radians([0, 20, 35, 70, 90])
    with pytest.raises(PrecisionError, match="exactly 5"):
        burmester_points(pts[:4], ang[:4])
    with pytest.raises(PrecisionError, match="poses 1 and 5 coincide"):
        burmester_points(pts[:4] + [pts[0]], [*ang[:4], ang[0]])
    with pytest.raises(PrecisionError, match="one set of five poses"):
        burmester_fourbars([pts, pts], [ang, ang])
    # A parallelogram's coupler only translates: every coupler point is a circle point.
    square = np.stack([np.cos(np.linspace(0, 2, 5)), np.sin(np.linspace(0, 2, 5))], 1)
    with pytest.raises(PrecisionError, match="only translate"):
        burmester_points(square, np.full(5, 0.3))
    # Five rotations about one point.
    with pytest.raises(PrecisionError, match=r"set \[1\] of the batch\) only translate"):
        burmester_points([np.array(pts, float), np.zeros((5, 2)) + 1.0], [ang, ang])
    # Pose sets with no real Burmester point: the search must say so, not return nothing.
    rng = np.random.default_rng(11)
    for _ in range(200):
        p = rng.uniform(-1, 1, size=(5, 2))
        a = rng.uniform(-2, 2, size=5)
        if int(burmester_points(p, a).count) == 0:
            assert independent_burmester(p, a, starts=150) == []
            with pytest.raises(PrecisionError, match="0 real Burmester points"):
                burmester_fourbars(p, a)
            break
    else:
        pytest.fail("no pose set without real Burmester points in 200 draws")


def test_burmester_points_batch_matches_one_by_one():
    rng = np.random.default_rng(7)
    points = rng.uniform(-1, 1, size=(3, 5, 2))
    angles = rng.uniform(-1.5, 1.5, size=(3, 5))
    both = burmester_points(points, angles)
    assert both.centres.shape == (3, 4, 2)
    for k in range(3):
        one = burmester_points(points[k], angles[k])
        assert np.array_equal(one.real, both.real[k])
        assert np.allclose(one.centres[one.real], both.centres[k][both.real[k]])


# --- path generation with prescribed timing ------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(fourbar_poses(3))
def test_path_with_timing_recovers_the_fourbar(case):
    fb, _, thetas, points, angles, states = case
    beta = thetas[1:] - thetas[0]
    alpha = angles[1:] - angles[0]
    rocker = [math.atan2(*(s[1] - fb[1])[::-1]) for s in states]
    gamma = np.array(rocker[1:]) - rocker[0]
    # A coupler that only translates (or turns with a ground link) leaves that dyad free.
    for turn in (alpha, beta - alpha, gamma - alpha):
        assume(np.min(np.abs(wrap(turn))) > 0.02)
    design = path_with_timing(points, beta, alpha, gamma)
    m = design.mechanism
    scale = 10 * max(1.0, np.max(np.abs(points)))
    assert np.allclose(m.A0, fb[0], atol=1e-8 * scale)
    assert np.allclose(m.B0, fb[1], atol=1e-8 * scale)
    assert np.allclose([m.crank, m.coupler, m.rocker, m.u, m.v], fb[2:], atol=1e-8 * scale)


@settings(max_examples=30, deadline=None)
@given(
    pts=st.lists(st.tuples(coord, coord), min_size=3, max_size=3),
    turns=st.lists(st.floats(0.3, 2.5), min_size=6, max_size=6),
)
def test_path_with_timing_meets_the_points_at_the_crank_rotations(pts, turns):
    points = np.array(pts)
    assume(
        np.min(np.linalg.norm(points[:, None] - points[None], axis=-1)[np.triu_indices(3, 1)]) > 0.2
    )
    beta, alpha, gamma = np.array(turns[:2]), np.array(turns[2:4]) - 1.4, np.array(turns[4:])
    try:
        design = path_with_timing(points, beta, alpha, gamma)
    except PrecisionError as exc:
        # Free choices that leave a dyad undetermined, or make the two one, are refused.
        assume(not any(w in str(exc) for w in ("singular", "coincide", "folded")))
        raise
    assert np.allclose(wrap(design.inputs[1:] - design.inputs[0] - beta), 0.0, atol=1e-9)
    # Simulated at θ1 + βj on each point's assembly, P passes Pj.
    theta = design.inputs[0] + np.concatenate(([0.0], beta))
    for sign, motion in configurations(design.mechanism, theta):
        at = design.branches == sign[0]
        spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
        assert np.max(
            np.linalg.norm(motion.positions["P"][at] - points[at], axis=-1), initial=0
        ) <= (TOL * spread * 10)


def test_path_with_timing_errors():
    pts = [[0, 0], [1, 0.5], [2, 0]]
    with pytest.raises(PrecisionError, match="crank dyad's equations are singular"):
        path_with_timing(pts, [0.3, 0.6], [0.3, 0.6], [0.2, 0.4])
    with pytest.raises(PrecisionError, match="points 1 and 2 coincide"):
        path_with_timing([[0, 0], [0, 0], [2, 0]], [0.3, 0.6], [0.1, 0.2], [0.2, 0.4])
    with pytest.raises(PrecisionError, match="exactly 3"):
        path_with_timing(pts[:2], [0.3, 0.6], [0.1, 0.2], [0.2, 0.4])
    # Two points at one crank angle: only a folded linkage (A on B0) can do it, and there the
    # input does not fix the coupler.
    with pytest.raises(PrecisionError, match="position 2 the crank pin A lies on the rocker"):
        path_with_timing([[0, 0], [0, 1], [0, 0.5]], [1.0, 1.0], [0.6, -0.4], [2.0, 1.0])
    with pytest.raises(PrecisionError, match="dyads would coincide"):
        path_with_timing(pts, [0.3, 0.6], [0.1, 0.2], [0.3, 0.6])


def test_three_pose_and_four_pose_batches_match_one_by_one():
    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 1, size=(2, 3, 2))
    angles = rng.uniform(-1.5, 1.5, size=(2, 3))
    circles = rng.uniform(-1, 1, size=(2, 2, 2))
    both = three_pose_fourbar(points, angles, circles)
    assert both.inputs.shape == (2, 3)
    for k in range(2):
        one = three_pose_fourbar(points[k], angles[k], circles[k])
        assert np.allclose(both.mechanism.A0[k], one.mechanism.A0, rtol=1e-13)
        assert np.allclose(both.inputs[k], one.inputs, rtol=1e-13)
    pts4 = rng.uniform(-1, 1, size=(2, 4, 2))
    ang4 = rng.uniform(-1.5, 1.5, size=(2, 4))
    beta = np.linspace(-1, 1, 7)
    g, _, ok = four_pose_dyads(pts4, ang4, beta)
    assert g.shape == (2, 2, 7, 2) and ok.shape == (2, 2, 7)
    for k in range(2):
        g1, _, ok1 = four_pose_dyads(pts4[k], ang4[k], beta)
        assert np.array_equal(ok1, ok[k])
        assert np.allclose(g1[ok1], g[k][ok[k]], rtol=1e-12)


def circuit_order_defect(design, samples=20000):
    """Order defect read off the engine's traced circuit: the sample where each pose is met
    (its input on its assembly), and whether one sweep of the input meets them in order."""
    m = circuit(design.mechanism, samples, order=0)
    n = m.input.shape[-1]
    ks = []
    for t, b in zip(design.inputs, design.branches, strict=True):
        gap = np.abs(wrap(m.input - t)) + np.where(m.branches["B"] == b, 0.0, 10.0)
        k = int(np.argmin(gap))
        if gap[k] > 0.01:
            return None  # not on the traced circuit (another circuit)
        ks.append(k)
    steps = np.diff(ks)
    if np.all(m.branches["B"] == m.branches["B"][0]):
        # The input turns fully: the poses must come round in cyclic order, either way.
        return not (np.sum(steps % n) < n or np.sum(-steps % n) < n)
    # The input rocks: one sweep is one leg of the circuit (between its limits), along which
    # the poses must come in order, either way.
    return not (np.all(steps > 0) or np.all(steps < 0))


def test_order_defect_agrees_with_the_traced_circuit():
    # Poses of crank-rockers (met in crank order, or shuffled): the Burmester four-bars include
    # crank-driven and rocker-driven (rocking input) linkages, with and without order defects.
    rng = np.random.default_rng(5)
    checked, rocking, defects = 0, 0, 0
    for trial in range(12):
        fb = ([0.0, 0.0], [3.0, 0.5], 1.0, 3.2, 2.6, *rng.uniform(-2, 2, size=2))
        thetas = np.sort(rng.uniform(0, 2 * np.pi, size=5))
        if trial % 2:
            thetas = rng.permutation(thetas)
        points, angles, _ = coupler_poses(fb, thetas)
        bp = burmester_points(points, angles)
        design, pairs = burmester_fourbars(points, angles)
        full = input_range(design.mechanism).full
        for k, pair in enumerate(pairs):
            if design.branch_defect[k]:
                continue
            one = fourbar_from_dyads(points, angles, bp.centres[pair], bp.circles[pair])
            assert bool(one.order_defect) == bool(design.order_defect[k])
            want = circuit_order_defect(one)
            if want is None:
                continue
            assert bool(one.order_defect) == want
            checked += 1
            rocking += not bool(full[k])
            defects += want
    assert checked >= 10 and rocking >= 2 and 0 < defects < checked

"""Motion generation through three and four poses against independent checks.

Poses are moved by explicit rotations and the centre-point curve is the vanishing determinant of
the perpendicular-bisector equations (tests/synth_precision_helpers.py), not the dyad angles the
library uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from synth_precision_helpers import (
    bisector_cubic,
    check_design_reaches,
    circle_residual,
    coord,
    cross2,
    fourbar_poses,
    moved,
    rot,
    wrap,
)

from linkwright.io import mechanism_to_dict, parse_document
from linkwright.mechanisms import solve
from linkwright.synthesis.burmester import (
    centre_point_curve,
    four_pose_dyads,
    four_pose_fourbar,
)
from linkwright.synthesis.precision import (
    PrecisionError,
    fourbar_from_dyads,
    pose_positions,
    three_pose_fourbar,
)

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

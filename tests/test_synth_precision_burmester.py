"""Five poses (Burmester points) and the order defect, against independent checks.

The Burmester points are checked against the bisector determinant of
tests/synth_precision_helpers.py and against a multi-start root finding with scipy; the order
defect against a traced circuit.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from scipy.optimize import fsolve
from synth_precision_helpers import (
    bisector_cubic,
    check_design_reaches,
    circle_residual,
    coupler_poses,
    fourbar_poses,
    rot,
    wrap,
)

from linkwright.mechanisms import circuit, input_range
from linkwright.synthesis.burmester import (
    burmester_fourbars,
    burmester_points,
)
from linkwright.synthesis.precision import (
    PrecisionError,
    fourbar_from_dyads,
)

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

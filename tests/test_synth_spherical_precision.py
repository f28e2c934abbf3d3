"""Spherical precision orientations (synthesis/spherical_precision.py): every returned four-bar is
solved again by the engine and its coupler's orientation compared with the prescribed one."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from linkwright.mechanisms import solve
from linkwright.mechanisms.spherical import SphericalFourBar
from linkwright.synthesis.precision import PrecisionError
from linkwright.synthesis.spherical_precision import (
    circle_axis_centre,
    spherical_burmester_cones,
    spherical_four_orientation_fourbar,
    spherical_fourbar_from_dyads,
    spherical_three_orientation_fourbar,
)

TOL = 1e-9


def _frame(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The coupler's frame from its joint axes, written here apart from the library's: columns
    A, the unit tangent towards B, and their cross product."""
    t = b - np.dot(a, b) * a
    t = t / np.linalg.norm(t)
    return np.stack([a, t, np.cross(a, t)], axis=-1)


def _check_design(design, q: np.ndarray, point=(1.0, 0.0, 0.0)) -> None:
    """Solve the returned linkage with linkwright (on each orientation's sign, the mechanism's
    own where there is no branch defect) and compare the coupler's orientation and point with the
    prescribed ones, carried into the linkage's frame by the design's rotation."""
    r = design.rotation
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-14) and np.linalg.det(r) > 0
    mech = design.mechanism
    frames, points = [], []
    for j, theta in enumerate(design.inputs):
        signed = mech if not design.branch_defect else replace(mech, assembly=design.branches[j])
        m = solve(signed, [theta], order=0)
        assert m.valid[0]
        frames.append(_frame(m.positions["A"][0], m.positions["B"][0]))
        points.append(m.positions["P"][0])
    for j in range(len(q)):
        # The coupler turns by R Qj Q1ᵀ Rᵀ from orientation 1: compare with the solved turn.
        want = r @ q[j] @ q[0].T @ r.T @ frames[0]
        assert np.max(np.abs(frames[j] - want)) < TOL
        assert np.max(np.abs(points[j] - r @ q[j] @ np.asarray(point))) < TOL
    assert design.error < TOL


def _orientations_of(fb: SphericalFourBar, inputs) -> np.ndarray:
    m = solve(fb, inputs, order=0)
    assert np.all(m.valid)
    return np.stack([_frame(a, b) for a, b in zip(m.positions["A"], m.positions["B"], strict=True)])


def test_four_orientations_of_a_known_fourbar_rebuild_linkages_through_them() -> None:
    fb = SphericalFourBar(*np.radians([60, 25, 50, 45, 30, 40]))
    q = _orientations_of(fb, np.radians([0, 25, 50, 80]))
    # The known crank is a dyad of the poses: its circle axis has the crank's fixed axis as centre.
    m = solve(fb, [0.0], order=0)
    g, residual = circle_axis_centre(q, m.positions["A"][0])
    assert residual < 1e-13 and np.allclose(np.abs(g), [1, 0, 0], atol=1e-12)
    cones = spherical_burmester_cones(q, samples=90)
    assert cones.valid.sum() > 60
    picked = np.flatnonzero(cones.valid[0])[[0, len(np.flatnonzero(cones.valid[0])) // 2]]
    tried = 0
    for i in picked:
        for k in (0, 1):
            if not cones.valid[1 - k, (i + 30) % 90]:
                continue
            d = spherical_four_orientation_fourbar(
                q, [cones.t[i], cones.t[(i + 30) % 90]], [0, 1 - k]
            )
            _check_design(d, q)
            tried += 1
    assert tried >= 2


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    st.lists(st.floats(-1, 1), min_size=9, max_size=9),
    st.lists(st.floats(-1, 1), min_size=6, max_size=6),
)
def test_three_random_orientations_are_reached_by_the_linkage(euler, axes) -> None:
    q = Rotation.from_rotvec(np.reshape(euler, (3, 3))).as_matrix()
    c = np.reshape(axes, (2, 3))
    assume(np.all(np.linalg.norm(c, axis=1) > 0.3))
    c = c / np.linalg.norm(c, axis=1)[:, None]
    # Keep away from the configurations where the input does not fix the coupler (dead centres,
    # axes nearly together), where no solver meets 1e-9 in orientation.
    for j in range(1, 3):
        assume(np.linalg.norm(q[j] @ q[0].T - np.eye(3)) > 0.1)
    assume(np.linalg.norm(np.cross(*(q[1:] @ q[0].T - np.eye(3)) @ c[0])) > 1e-2)
    try:
        d = spherical_three_orientation_fourbar(q, c)
    except PrecisionError:
        assume(False)
    mech = d.mechanism
    arcs = np.array([mech.frame, mech.crank, mech.coupler, mech.rocker], dtype=float)
    assume(np.all(np.sin(arcs) > 0.05))
    m = solve(replace(mech, assembly=1.0), d.inputs, order=0)
    n = np.cross(m.positions["A"], m.positions["B0"])
    assume(np.all(np.abs(np.einsum("ij,ij->i", n, m.positions["B"])) > 0.05))
    _check_design(d, q)


def test_every_dyad_on_the_cones_keeps_its_arc_in_every_orientation() -> None:
    q = Rotation.from_euler(
        "zyx", [[0, 0, 0], [20, 10, 5], [45, 5, 15], [70, -10, 20]], degrees=True
    ).as_matrix()
    cones = spherical_burmester_cones(q, samples=60)
    assert cones.valid.sum() >= 60
    for k in (0, 1):
        for w, g in zip(
            cones.circles[k][cones.valid[k]], cones.centres[k][cones.valid[k]], strict=True
        ):
            arcs = [np.arccos(np.clip(g @ (q[j] @ q[0].T @ w), -1, 1)) for j in range(4)]
            assert np.ptp(arcs) < 1e-9


def test_bad_orientations_are_one_line_errors() -> None:
    eye = np.eye(3)
    cases = [
        (
            lambda: spherical_three_orientation_fourbar([eye, eye * 2, eye], np.eye(3)[:2]),
            "not a rotation",
        ),
        (lambda: spherical_three_orientation_fourbar([eye, eye], np.eye(3)[:2]), "exactly 3"),
        (lambda: spherical_burmester_cones([eye] * 4), "coincide"),
        (lambda: spherical_three_orientation_fourbar([[1, 2]], np.eye(3)[:2]), "shape (n, 3, 3)"),
    ]
    for call, words in cases:
        with pytest.raises(PrecisionError, match=None) as info:
            call()
        assert words in str(info.value) and "\n" not in str(info.value)


def test_an_axis_off_the_cone_is_refused() -> None:
    fb = SphericalFourBar(*np.radians([60, 25, 50, 45, 30, 40]))
    q = _orientations_of(fb, np.radians([0, 25, 50, 80]))
    with pytest.raises(PrecisionError, match="not on the circling-axis cone"):
        circle_axis_centre(q, [0.3, 0.4, 0.8])
    with pytest.raises(PrecisionError, match="does not guide"):
        spherical_fourbar_from_dyads(q, np.eye(3)[:2], [[0.3, 0.4, 0.8], [0, 0.6, 0.8]])

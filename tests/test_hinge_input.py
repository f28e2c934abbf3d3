"""A linkage driven at a moving hinge (issue 21: the input is the angle between two moving
links), checked against a four-bar driven by its crank, closed forms and differences.

A four-bar A0 A B B0 driven at its coupler–rocker hinge B is the same set of poses as the
crank-driven four-bar: every pose the hinge plan finds is checked against
:class:`~linkwright.mechanisms.FourBar` solved at the crank angle that pose has (a different
step kind and code path), the angle at B against the input, the limit positions against the
law of cosines, the derivatives against an 8th-order central difference, and the traced
circuits for branch jumps.
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from linkwright.cli import main
from linkwright.geometry import sphere
from linkwright.io.documents import load_document, mechanism_to_dict, parse_document
from linkwright.mechanisms import (
    CrankJoint,
    DyadJoint,
    FixedJoint,
    FourBar,
    HingeJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SphereCrankJoint,
    circuits,
    input_range,
    solve,
)
from linkwright.mechanisms.base import configurations

lengths = st.floats(0.3, 5.0)


def _linkage(b0x, crank, coupler, rocker, phase=0.0, assembly=1.0):
    return Linkage(
        joints=(
            FixedJoint("A0", [0.0, 0.0]),
            FixedJoint("B0", [b0x, 0.0]),
            HingeJoint("B", "A", "A0", crank, "B0", coupler, rocker, phase, assembly),
            RigidJoint("P", "A", "B", 0.4 * coupler, 0.3 * coupler),
        ),
        traced="P",
    )


def _angle_at_b(pos):
    """The angle at B from B→B0 to B→A, from positions alone."""
    u, v = pos["A"] - pos["B"], pos["B0"] - pos["B"]
    return np.arctan2(v[..., 0] * u[..., 1] - v[..., 1] * u[..., 0], np.sum(u * v, -1))


@settings(max_examples=60, deadline=None)
@given(
    b0x=st.floats(0.5, 5.0),
    crank=lengths,
    coupler=lengths,
    rocker=lengths,
    phase=st.floats(-np.pi, np.pi),
)
# A rhombus: the crank brings A onto B0, where the reference four-bar has no B (found by a
# fresh run).
@example(b0x=1.9, crank=1.9, coupler=1.9, rocker=1.9, phase=1e-187)
def test_every_pose_is_the_crank_driven_four_bars(b0x, crank, coupler, rocker, phase):
    hinge = _linkage(b0x, crank, coupler, rocker, phase)
    theta = np.linspace(-np.pi, np.pi, 37)
    size = max(b0x, crank, coupler, rocker)
    found = 0
    for _, motion in configurations(hinge, theta, order=0):
        ok = motion.valid
        if not ok.any():
            continue
        found += int(ok.sum())
        pos = {k: v[ok] for k, v in motion.positions.items()}
        # The angle at B is the input (plus the phase).
        turn = np.remainder(_angle_at_b(pos) - (theta[ok] + phase) + np.pi, 2 * np.pi) - np.pi
        assert np.max(np.abs(turn)) <= 1e-9
        # The crank-driven four-bar at A's angle, on the assembly the pose has, places B there.
        a, b, b0 = pos["A"], pos["B"], np.array([b0x, 0.0])
        crank_angle = np.arctan2(a[:, 1], a[:, 0])
        side = np.sign((b0 - a)[:, 0] * (b - a)[:, 1] - (b0 - a)[:, 1] * (b - a)[:, 0])
        assume(np.all(side != 0))
        fb = FourBar(
            A0=[0, 0], B0=[b0x, 0], crank=crank, coupler=coupler, rocker=rocker, assembly=side
        )
        reached = solve(fb, crank_angle[:, None], order=0).positions["B"][:, 0]
        # The reference's own precision: its dyad B meets its limit where the angle at B is 0
        # or π (A, B, B0 in line), and there B is only known to rounding / |sin φ| (√ε at
        # worst); the hinge's own lengths and angle are checked above to 1e-9 regardless.
        # Where the crank brings A onto B0 (crank = |A0 B0|: a rhombus or a kite), the
        # reference's dyad has coincident centres and no B at all, and near there it knows B
        # only to rounding · size / |A B0|; the hinge's own angle is checked above regardless.
        sine = np.abs(np.sin(theta[ok] + phase))
        apart = np.linalg.norm(a - b0, axis=-1)
        defined = apart > 1e-12 * size
        with np.errstate(divide="ignore"):
            tolerance = size * (1e-9 + 1e-14 / sine + 1e-14 * size / apart)
        miss = np.linalg.norm(reached - b, axis=-1)
        assert np.all(miss[defined] <= tolerance[defined])
    if input_range(FourBar(A0=[0, 0], B0=[b0x, 0], crank=crank, coupler=coupler,
                           rocker=rocker)).never:  # fmt: skip
        assert found == 0


def test_limit_positions_are_the_law_of_cosines():
    """The hinge's input stops where Z, X and Y fall in line: |A B0| = |A0 B0| ± crank, and
    |A B0|² = a² + b² − 2ab cos φ."""
    hinge = _linkage(4.0, 1.0, 3.5, 3.0)
    arcs = input_range(hinge)
    a, b = 3.5, 3.0
    ends = [np.arccos((a * a + b * b - d * d) / (2 * a * b)) for d in (3.0, 5.0)]
    expected = sorted([-ends[1], -ends[0], ends[0], ends[1]])
    found = sorted(np.concatenate([arcs.lo[np.isfinite(arcs.lo)], arcs.hi[np.isfinite(arcs.hi)]]))
    np.testing.assert_allclose(found, expected, atol=1e-12)


def _difference(hinge, theta, branch, h=1e-2):
    """First and second derivatives of every joint by an 8th-order central difference."""
    weights1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    weights2 = np.array(
        [-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560]
    )
    steps = np.arange(-4, 5) * h
    shifted = [solve(hinge.with_assembly(branch), theta + s, order=0).positions for s in steps]
    first = {j: sum(w * p[j] for w, p in zip(weights1, shifted, strict=True)) / h for j in "ABP"}
    second = {
        j: sum(w * p[j] for w, p in zip(weights2, shifted, strict=True)) / h**2 for j in "ABP"
    }
    return first, second


@pytest.mark.parametrize("assembly", [1.0, -1.0])
def test_derivatives_match_an_eighth_order_difference(assembly):
    hinge = _linkage(4.0, 1.0, 3.5, 3.0, phase=0.3).with_assembly(assembly)
    # Well inside the arc [54.3°, 100.3°] − phase: the differences' stencil stays on it.
    theta = np.radians(np.linspace(62.0, 92.0, 7)) - 0.3
    motion = solve(hinge, theta, order=2)
    assert motion.valid.all() and motion.regular.all()
    first, second = _difference(hinge, theta, assembly)
    for j in "ABP":
        scale1 = np.max(np.abs(first[j]))
        scale2 = np.max(np.abs(second[j]))
        np.testing.assert_allclose(motion.velocities[j], first[j], atol=1e-7 * scale1)
        np.testing.assert_allclose(motion.accelerations[j], second[j], atol=1e-6 * scale2)


def test_traced_circuits_cross_the_limits_without_a_branch_jump():
    """Along every circuit A changes sides of A0–B0 only at a limit position (a sample where
    it is in line with them: the tracer samples limits, to 1e-12 in θ, and A moves like the
    square root of θ's distance to the limit there, so the sine is ~1e-6, not rounding), never
    by a jump elsewhere (both sides a normal step, ~1e-3, away from the line), its steps stay
    even (the tracer spaces samples as sin² near limits), and the circuit closes."""
    hinge = _linkage(4.0, 1.0, 3.5, 3.0)
    _, found = circuits(hinge, 2000, order=0)
    assert len(found) == 2
    y = np.array([4.0, 0.0])
    for motion in found:
        a = motion.positions["A"]
        assert motion.valid.all()
        sine = (y[0] * a[:, 1] - y[1] * a[:, 0]) / 4.0  # sin of the angle at A0, |A0 A| = 1
        flips = np.flatnonzero(np.sign(sine[1:]) != np.sign(sine[:-1]))
        assert len(flips) >= 1
        for k in flips:
            assert min(abs(sine[k]), abs(sine[k + 1])) <= 1e-4, (k, sine[k], sine[k + 1])
        step = np.linalg.norm(np.diff(a, axis=0), axis=-1)
        assert np.max(step) <= 5 * np.median(step)
        assert np.linalg.norm(a[0] - a[-1]) <= 5 * np.median(step)  # the circuit closes
        # The lengths hold along the whole circuit.
        np.testing.assert_allclose(np.linalg.norm(a, axis=-1), 1.0, atol=1e-12)
        np.testing.assert_allclose(
            np.linalg.norm(motion.positions["B"] - y, axis=-1), 3.0, atol=1e-12
        )


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def test_a_hinge_document_reads_writes_and_analyses(tmp_path):
    hinge = _linkage(4.0, 1.0, 3.5, 3.0, phase=0.2, assembly=-1.0)
    raw = mechanism_to_dict(hinge)
    doc = parse_document(raw)
    # Degrees in the document, radians inside: the numbers come back to rounding.
    for key, value in hinge.params().items():
        np.testing.assert_allclose(doc.mechanism.params()[key], value, rtol=1e-15, atol=1e-15)
    joint = doc.raw["mechanism"]["joints"][2]
    assert joint["type"] == "hinge" and joint["far"] == "A" and joint["assembly"] == -1
    path = tmp_path / "hinge.json"
    path.write_text(json.dumps(doc.raw))
    assert load_document(path).mechanism == doc.mechanism
    code, out, err = _run("analyze", str(path), "--json")
    assert code == 0, err
    arcs = json.loads(out)["input_arcs_deg"]
    assert len(arcs) == 2
    code, out, err = _run("curve", str(path), "--all", "--json", "-n", "50")
    assert code == 0, err


@pytest.mark.parametrize(
    ("joints", "words"),
    [
        (
            [HingeJoint("B", "B", "A0", 1.0, "B0", 3.5, 3.0)],
            "far must be a non-empty joint name other than the hinge's",
        ),
        (
            [HingeJoint("B", "A", "A0", 1.0, "A0", 3.5, 3.0)],
            "the far joint hangs from z and the hinge from y",
        ),
        (
            [HingeJoint("B", "A", "A0", 1.0, "B0", 3.5, 3.0), CrankJoint("C", "A0", 1.0)],
            "already drives the linkage",
        ),
        (
            [HingeJoint("B", "A0", "A0", 1.0, "B0", 3.5, 3.0)],
            "far must be a new joint's name",
        ),
        ([HingeJoint("B", "A", "A0", -1.0, "B0", 3.5, 3.0)], "r"),
    ],
)
def test_ill_formed_hinges_are_refused_in_one_line(joints, words):
    ground = [FixedJoint("A0", [0.0, 0.0]), FixedJoint("B0", [4.0, 0.0])]
    with pytest.raises(InvalidLinkage, match=words):
        Linkage(joints=ground + joints)


# --- on the sphere ----------------------------------------------------------------------------


def _sphere_linkage(frame, crank, coupler, rocker, phase=0.0, assembly=1.0):
    return Linkage(
        joints=(
            FixedJoint("A0", [1.0, 0.0, 0.0]),
            FixedJoint("B0", [np.cos(frame), np.sin(frame), 0.0]),
            HingeJoint("B", "A", "A0", crank, "B0", coupler, rocker, phase, assembly),
        ),
        traced="B",
        space="sphere",
    )


arcs = st.floats(0.2, 1.4)


@settings(max_examples=40, deadline=None)
@given(frame=arcs, crank=arcs, coupler=arcs, rocker=arcs, phase=st.floats(-np.pi, np.pi))
def test_every_spherical_pose_is_the_crank_driven_linkages(frame, crank, coupler, rocker, phase):
    """Each pose against the crank-driven spherical linkage (SphereCrank and SphereDyad, another
    code path) at the crank angle the pose has, and the angle at B against the input."""
    hinge = _sphere_linkage(frame, crank, coupler, rocker, phase)
    theta = np.linspace(-np.pi, np.pi, 37)
    for _, motion in configurations(hinge, theta, order=0):
        ok = motion.valid
        if not ok.any():
            continue
        pos = {k: v[ok] for k, v in motion.positions.items()}
        a, b, a0, b0 = pos["A"], pos["B"], pos["A0"], pos["B0"]
        turn = sphere.angle_at(b, b0, a) - (theta[ok] + phase)
        assert np.max(np.abs(np.remainder(turn + np.pi, 2 * np.pi) - np.pi)) <= 1e-9
        crank_angle = sphere.angle_at(a0, b0, a)
        side = np.sign(np.sum(np.cross(a, b0) * b, axis=-1))
        for k in range(len(crank_angle)):
            assume(side[k] != 0)
            driven = Linkage(
                joints=(
                    FixedJoint("A0", [1.0, 0.0, 0.0]),
                    FixedJoint("B0", [np.cos(frame), np.sin(frame), 0.0]),
                    SphereCrankJoint("A", "A0", crank, toward="B0"),
                    DyadJoint("B", "A", coupler, "B0", rocker, side[k]),
                ),
                traced="B",
                space="sphere",
            )
            reached = solve(driven, [crank_angle[k]], order=0).positions["B"][0]
            # The reference's dyad meets its limit where the angle at B is 0 or π: there B
            # moves like 1/sin of that angle per radian of crank, and the crank angle read off
            # A carries its rounding (over sin of arcs down to 0.2), times links' ratios of up
            # to 7: 6.7e-13/sin was seen, so 1e-11/sin.
            sine = abs(np.sin(theta[ok][k] + phase))
            assert np.linalg.norm(reached - b[k]) <= 1e-9 + 1e-11 / max(sine, 1e-300)


def test_spherical_limits_are_the_spherical_law_of_cosines():
    hinge = _sphere_linkage(np.radians(40), np.radians(20), np.radians(45), np.radians(35))
    found = input_range(hinge)
    a, b = np.radians(45), np.radians(35)
    ends = [
        np.arccos((np.cos(d) - np.cos(a) * np.cos(b)) / (np.sin(a) * np.sin(b)))
        for d in np.radians([20.0, 60.0])
    ]
    expected = sorted([-ends[1], -ends[0], ends[0], ends[1]])
    got = sorted(np.concatenate([found.lo[np.isfinite(found.lo)], found.hi[np.isfinite(found.hi)]]))
    np.testing.assert_allclose(got, expected, atol=1e-12)


@pytest.mark.parametrize("assembly", [1.0, -1.0])
def test_spherical_derivatives_match_an_eighth_order_difference(assembly):
    hinge = _sphere_linkage(0.7, 0.35, 0.8, 0.6, phase=0.2, assembly=assembly)
    arcs_found = input_range(hinge)
    lo, hi = float(arcs_found.lo[..., 1]), float(arcs_found.hi[..., 1])
    theta = np.linspace(lo + 0.2 * (hi - lo), hi - 0.2 * (hi - lo), 7)
    motion = solve(hinge, theta, order=2)
    assert motion.valid.all() and motion.regular.all()
    h = 1e-2 * (hi - lo)
    w1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    w2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])
    shifted = [solve(hinge, theta + k * h, order=0).positions for k in range(-4, 5)]
    for j in "AB":
        first = sum(w * p[j] for w, p in zip(w1, shifted, strict=True)) / h
        second = sum(w * p[j] for w, p in zip(w2, shifted, strict=True)) / h**2
        np.testing.assert_allclose(motion.velocities[j], first, atol=1e-8)
        np.testing.assert_allclose(motion.accelerations[j], second, atol=1e-6)


@pytest.mark.parametrize("phase", [0.0, 1e-187, 1e-12, 1e-9])
def test_a_rhombus_folding_at_its_hinge_has_no_pose_there(phase):
    """All four links 1.9 long: at an angle of 0 at B, A falls on B0 and B may be anywhere on
    its circle. Beside the fold B was once placed 1e171 away and called valid; every pose the
    step gives keeps its links' lengths, and the fold itself is no pose."""
    hinge = _linkage(1.9, 1.9, 1.9, 1.9, phase)
    theta = np.array([0.0, 1e-3, 0.5])
    for _, motion in configurations(hinge, theta, order=0):
        ok = motion.valid
        pos = {k: v[ok] for k, v in motion.positions.items()}
        for p, q, length in (("A0", "A", 1.9), ("A", "B", 1.9), ("B", "B0", 1.9)):
            if p == "A0":
                span = np.linalg.norm(pos[q], axis=-1)
            elif q == "B0":
                span = np.linalg.norm(pos[p] - np.array([1.9, 0.0]), axis=-1)
            else:
                span = np.linalg.norm(pos[p] - pos[q], axis=-1)
            assert np.all(np.abs(span - length) <= 1e-9 * length), (p, q)
        if phase < 1e-7:
            assert not ok[0]

"""The composed family ``linkage``: validation, agreement with the named families, derivatives.

A four-bar or slider-crank written joint by joint must give the named family's numbers (the two
are separate constructions of the same plan steps, with their own parameter names); written with
its dyad's parents swapped it takes a different arithmetic path to the same points. Jansen's and
Klann's legs check the long chains: every sample of a whole turn assembles, every constraint
holds to 1e-10 of the size, and the analytic derivatives match central differences.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.io import load_example
from linkwright.mechanisms import (
    FAMILIES,
    FourBar,
    InvalidMechanism,
    SliderCrank,
    circuit,
    configurations,
    input_range,
    solve,
)
from linkwright.mechanisms.linkage import (
    JOINT_TYPES,
    CrankJoint,
    DyadJoint,
    FixedJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SliderJoint,
)

TURN = np.radians(np.arange(360.0))


@pytest.fixture(scope="module", autouse=True)
def linkage_family():
    """Documents of family ``linkage`` need the class in FAMILIES (the lead registers it there;
    until then these tests register it for themselves)."""
    with pytest.MonkeyPatch.context() as mp:
        if "linkage" not in FAMILIES:
            mp.setitem(FAMILIES, "linkage", Linkage)
        yield


def max_residual(mech: Linkage, motion) -> float:
    res = mech.residuals(motion)
    return max(float(np.nanmax(np.abs(r))) for r in res.values())


def fourbar_linkage(A0, B0, crank, coupler, rocker, u=0.0, v=0.0, assembly=1.0, phase=0.0):
    return Linkage(
        joints=(
            FixedJoint("A0", A0),
            FixedJoint("B0", B0),
            CrankJoint("A", pivot="A0", length=crank, phase=phase),
            DyadJoint("B", p1="A", r1=coupler, p2="B0", r2=rocker, assembly=assembly),
            RigidJoint("P", origin="A", toward="B", u=u, v=v),
        )
    )


# ---------------------------------------------------------------------------------------------
# The bundled legs
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "foot"), [("jansen-leg", "G"), ("klann-leg", "F")])
def test_legs_assemble_over_the_whole_turn(name, foot):
    mech = load_example(name).mechanism
    assert isinstance(mech, Linkage)
    assert mech.traced == (foot,) and mech.traced_joint == foot
    motion = solve(mech, TURN)
    assert motion.valid.all() and motion.regular.all()
    assert np.isfinite(motion.positions[foot]).all()
    assert max_residual(mech, motion) < 1e-10
    # Far from every limit: the leg never comes near jamming.
    assert min(float(m.min()) for m in motion.margins.values()) > 0.05
    # So the crank turns fully, and the circuit the machine runs is that turn.
    assert bool(input_range(mech).full)
    run = circuit(mech, 72)
    np.testing.assert_array_equal(run.positions[foot], solve(mech, run.input).positions[foot])


def test_jansen_leg_matches_an_independent_coordinate_listing():
    # Joint coordinates of the standard figure at the crank's 90° position, as listed to four
    # decimals by an independent MATLAB animation of the leg (DEMO_Jansen_linkage_animation_01,
    # for anim8), which puts the frame pivot at the origin: shifted here by the crank axle
    # (38, 7.8). Its link lengths agree with the holy numbers to about 1e-4.
    mech = load_example("jansen-leg").mechanism
    listed = {
        "A": (38, 22.8),
        "C": (-8.7357, 40.5702),
        "D": (-39.6678, -5.8717),
        "F": (-19.4476, -39.6874),
        "E": (17.0047, -35.4306),
        "G": (30.3109, -82.5894),
    }
    motion = solve(mech, [math.pi / 2], order=0)
    for joint, (x, y) in listed.items():
        np.testing.assert_allclose(motion.positions[joint][0], (x - 38, y - 7.8), atol=5e-4)


def test_jansen_leg_has_the_holy_numbers():
    joints = {j.name: j for j in load_example("jansen-leg").mechanism.joints}
    lengths = sorted(
        float(x)
        for j in joints.values()
        for x in (
            [j.length]
            if isinstance(j, CrankJoint)
            else [j.r1, j.r2]
            if isinstance(j, DyadJoint)
            else []
        )
    )
    # b c d e f g h i j k m; a and l are the frame offsets.
    holy = sorted([41.5, 39.3, 40.1, 55.8, 39.4, 36.7, 65.7, 49, 50, 61.9, 15])
    assert lengths == holy
    np.testing.assert_array_equal(joints["B"].at - joints["O"].at, [-38, -7.8])


def test_klann_leg_stance_is_as_its_comment_says():
    mech = load_example("klann-leg").mechanism
    y = solve(mech, TURN, order=0).positions["F"][:, 1]
    low = np.concatenate([y <= y.min() + 0.5] * 2)
    run = best = 0
    for flag in low:
        run = run + 1 if flag else 0
        best = max(best, run)
    assert min(best, 360) == 184


def test_legs_derivatives_match_central_differences():
    for name in ("jansen-leg", "klann-leg"):
        mech = load_example(name).mechanism
        check_derivatives(mech, np.radians(np.arange(0.0, 360.0, 7.0)))


# ---------------------------------------------------------------------------------------------
# Agreement with the named families
# ---------------------------------------------------------------------------------------------

coords = st.floats(-5, 5, allow_nan=False)
lengths = st.floats(0.3, 5, allow_nan=False)
signs = st.sampled_from([1.0, -1.0])


@st.composite
def fourbars(draw):
    A0 = [draw(coords), draw(coords)]
    B0 = [draw(coords), draw(coords)]
    if math.dist(A0, B0) < 0.3:
        B0[0] += 1.0
    return {
        "A0": A0,
        "B0": B0,
        "crank": draw(lengths),
        "coupler": draw(lengths),
        "rocker": draw(lengths),
        "u": draw(coords),
        "v": draw(coords),
        "assembly": draw(signs),
    }


INPUTS = np.linspace(-math.pi, math.pi, 24, endpoint=False)


def assert_same_motion(a, b, joints, tol=0.0):
    np.testing.assert_array_equal(a.valid, b.valid)
    np.testing.assert_array_equal(a.regular, b.regular)
    for j in joints:
        for kind in ("positions", "velocities", "accelerations"):
            np.testing.assert_allclose(
                getattr(a, kind)[j], getattr(b, kind)[j], rtol=0, atol=tol, err_msg=f"{kind} {j}"
            )


@settings(max_examples=80, deadline=None)
@given(fourbars(), st.floats(-math.pi, math.pi))
def test_fourbar_in_linkage_form_agrees_with_fourbar(dims, phase):
    named = FourBar(**dims)
    composed = fourbar_linkage(**dims)
    # The composed scale also counts the coupler point's offset (a rigid point far out on its
    # link carries errors of that size); the tolerance uses the larger of the two.
    scale = max(float(named.scale), float(composed.scale))
    assert_same_motion(solve(named, INPUTS), solve(composed, INPUTS), "ABP", 1e-12 * scale)
    # A phase on the crank is the four-bar driven from θ + phase.
    shifted = fourbar_linkage(**dims, phase=phase)
    assert_same_motion(solve(named, INPUTS + phase), solve(shifted, INPUTS), "ABP", 1e-12 * scale)
    # The same limits (closed form in both) and the same traced circuit.
    arcs_named, arcs_composed = input_range(named), input_range(composed)
    np.testing.assert_array_equal(arcs_named.full, arcs_composed.full)
    np.testing.assert_allclose(arcs_named.lo, arcs_composed.lo, rtol=0, atol=1e-12)
    np.testing.assert_allclose(arcs_named.hi, arcs_composed.hi, rtol=0, atol=1e-12)
    a, b = circuit(named, 16), circuit(composed, 16)
    np.testing.assert_allclose(a.input, b.input, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.positions["P"], b.positions["P"], rtol=0, atol=1e-9 * scale)
    # Residuals agree in meaning: both tiny wherever assembled.
    motion = solve(composed, INPUTS)
    if motion.valid.any():
        assert max_residual(composed, motion) < 1e-10


@settings(max_examples=80, deadline=None)
@given(fourbars())
def test_dyad_written_from_its_other_parent_gives_the_same_points(dims):
    # Swapping a dyad's parents flips its assembly sign: the same joint, computed from the
    # other circle's centre (a different arithmetic path).
    forward = fourbar_linkage(**dims)
    s = dims["assembly"]
    backward = Linkage(
        joints=(
            FixedJoint("A0", dims["A0"]),
            FixedJoint("B0", dims["B0"]),
            CrankJoint("A", "A0", dims["crank"]),
            DyadJoint("B", "B0", dims["rocker"], "A", dims["coupler"], assembly=-s),
            RigidJoint("P", "A", "B", dims["u"], dims["v"]),
        )
    )
    f, b = solve(forward, INPUTS), solve(backward, INPUTS)
    # Rounding grows like 1/√margin towards a limit position; away from one (sin² of the angle
    # above 1e-4) both paths agree to a few ulps of the size (3.5e-15 seen over 3000 samples).
    clear = f.valid & b.valid & (f.margins["B"] > 1e-4) & (b.margins["B"] > 1e-4)
    scale = float(forward.scale)
    for j in "BP":
        err = np.abs(f.positions[j] - b.positions[j])[clear]
        assert err.size == 0 or err.max() < 1e-12 * scale


@st.composite
def slidercranks(draw):
    A0 = [draw(coords), draw(coords)]
    line_point = draw(st.one_of(st.just(A0), st.tuples(coords, coords).map(list)))
    return {
        "A0": A0,
        "crank": draw(lengths),
        "rod": draw(lengths),
        "line_point": line_point,
        "line_angle": draw(st.floats(-math.pi, math.pi)),
        "u": draw(coords),
        "v": draw(coords),
        "assembly": draw(signs),
    }


@settings(max_examples=80, deadline=None)
@given(slidercranks())
def test_slidercrank_in_linkage_form_agrees_with_slidercrank(dims):
    named = SliderCrank(**dims)
    # A guide through the crank axle is written with the axle itself as the line's point: two
    # fixed joints at one place would be one pivot under two names.
    same = dims["line_point"] == dims["A0"]
    guide = () if same else (FixedJoint("L", dims["line_point"]),)
    composed = Linkage(
        joints=(
            FixedJoint("A0", dims["A0"]),
            *guide,
            CrankJoint("A", "A0", dims["crank"]),
            SliderJoint(
                "B", "A", dims["rod"], "A0" if same else "L", dims["line_angle"], dims["assembly"]
            ),
            RigidJoint("P", "A", "B", dims["u"], dims["v"]),
        )
    )
    tol = 1e-12 * max(float(named.scale), float(composed.scale))
    assert_same_motion(solve(named, INPUTS), solve(composed, INPUTS), "ABP", tol)
    arcs_named, arcs_composed = input_range(named), input_range(composed)
    np.testing.assert_array_equal(arcs_named.full, arcs_composed.full)
    np.testing.assert_allclose(arcs_named.lo, arcs_composed.lo, rtol=0, atol=1e-12)
    motion = solve(composed, INPUTS)
    if motion.valid.any():
        assert max_residual(composed, motion) < 1e-10


# ---------------------------------------------------------------------------------------------
# Derivatives, batches, geared cranks
# ---------------------------------------------------------------------------------------------


def check_derivatives(mech: Linkage, theta: np.ndarray, h: float = 1e-5) -> None:
    """Velocities and accelerations against central differences of positions and velocities.

    The truncation error is h²/6 of the next derivative: about 1e-11 of the size for a linkage
    far from its limits, relatively larger where the derivatives grow towards a limit position
    (hence the relative part of the tolerance); samples too near a limit (sin² of a dyad's angle
    below 0.05), where they blow up, are left out by their dyads' margins.
    """
    here = solve(mech, theta)
    up, down = solve(mech, theta + h), solve(mech, theta - h)
    ok = here.regular & up.regular & down.regular
    for m in (here, up, down):
        for margin in m.margins.values():
            ok &= margin > 0.05
    scale = float(mech.scale)
    for j in mech.reported_joints:
        fd_vel = (up.positions[j] - down.positions[j]) / (2 * h)
        fd_acc = (up.velocities[j] - down.velocities[j]) / (2 * h)
        np.testing.assert_allclose(
            here.velocities[j][ok], fd_vel[ok], rtol=1e-5, atol=1e-6 * scale, err_msg=j
        )
        np.testing.assert_allclose(
            here.accelerations[j][ok], fd_acc[ok], rtol=1e-4, atol=1e-5 * scale, err_msg=j
        )


@settings(max_examples=40, deadline=None)
@given(fourbars(), st.floats(-math.pi, math.pi))
def test_random_fourbar_derivatives_match_central_differences(dims, phase):
    check_derivatives(fourbar_linkage(**dims, phase=phase), INPUTS)


def test_crank_on_a_moving_pivot_is_a_gear_on_the_link():
    # G rides on the crank pin A and turns at −3 times the input, against the ground:
    # G = 2·e^{iθ} + 0.5·e^{i(0.2 − 3θ)} exactly.
    mech = Linkage(
        joints=(
            FixedJoint("O", [0, 0]),
            CrankJoint("A", "O", 2.0),
            CrankJoint("G", "A", 0.5, ratio=-3.0, phase=0.2),
        )
    )
    z = 2 * np.exp(1j * INPUTS) + 0.5 * np.exp(1j * (0.2 - 3 * INPUTS))
    motion = solve(mech, INPUTS)
    np.testing.assert_allclose(motion.positions["G"], np.c_[z.real, z.imag], atol=1e-14)
    dz = 2j * np.exp(1j * INPUTS) - 1.5j * np.exp(1j * (0.2 - 3 * INPUTS))
    np.testing.assert_allclose(motion.velocities["G"], np.c_[dz.real, dz.imag], atol=1e-14)
    assert "G.ratio" in mech.params() and "A.ratio" not in mech.params()
    assert max_residual(mech, motion) < 1e-15
    check_derivatives(mech, INPUTS)


def test_slider_on_a_moving_guide_and_rigid_chain_derivatives():
    # A guide through the crank pin keeps its direction (it translates with A); a rigid point
    # on the rod, and a dyad hung from it, exercise every step kind in one chain.
    mech = Linkage(
        joints=(
            FixedJoint("O", [0, 0]),
            FixedJoint("Q", [3, 1]),
            CrankJoint("A", "O", 1.0, phase=0.3),
            SliderJoint("B", "Q", 2.5, "A", math.radians(20), assembly=-1),
            RigidJoint("P", "Q", "B", 1.2, -0.4),
            DyadJoint("D", "P", 2.0, "O", 3.0),
        ),
        traced=("D", "P"),
    )
    theta = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    motion = solve(mech, theta)
    assert motion.valid.any()
    assert max_residual(mech, motion) < 1e-10
    check_derivatives(mech, theta)


def test_batches_are_stacks_of_single_linkages():
    crank = np.array([0.8, 1.0, 6.0])
    batch = fourbar_linkage([0, 0], [4, 0], crank, 5.0, 3.5, u=1.0, v=0.5)
    assert batch.batch_shape == (3,)
    np.testing.assert_array_equal(batch.scale, [5.0, 5.0, 6.0])
    motion = solve(batch, INPUTS)
    for i, c in enumerate(crank):
        one = solve(fourbar_linkage([0, 0], [4, 0], c, 5.0, 3.5, u=1.0, v=0.5), INPUTS)
        for j in "ABP":
            np.testing.assert_array_equal(motion.positions[j][i], one.positions[j])
    pivots = np.array([[0.0, 0.0], [0.5, 0.0]])
    moved = fourbar_linkage(pivots, [4, 0], 1.0, 5.0, 3.5)
    assert moved.batch_shape == (2,)
    assert max_residual(moved, solve(moved, INPUTS)) < 1e-10
    with pytest.raises(InvalidLinkage, match="do not broadcast"):
        fourbar_linkage([0, 0], [4, 0], np.ones(3), np.ones(2) * 5, 3.5)


# ---------------------------------------------------------------------------------------------
# The Mechanism protocol
# ---------------------------------------------------------------------------------------------


def test_params_plan_and_joints():
    mech = fourbar_linkage([0, 0], [4, 0], 1, 5, 3.5, u=2, v=1, assembly=-1)
    assert mech.family == "linkage" and mech.space == "plane"
    assert mech.plan.joints == ("A0", "B0", "A", "B", "P") == mech.reported_joints
    assert mech.point_fields == frozenset({"A0.at", "B0.at"})
    assert sorted(mech.params()) == [
        "A.length",
        "A.phase",
        "A0.at",
        "B.assembly",
        "B.r1",
        "B.r2",
        "B0.at",
        "P.u",
        "P.v",
    ]
    assert mech.traced == ("P",) and mech.plan.traced == ("P",)
    assert mech.assemblies == {"B": -1.0}
    assert mech.joint("B").r1 == 5.0
    with pytest.raises(KeyError):
        mech.joint("Z")
    # The plan belongs to the instance: another structure has another plan.
    other = Linkage(joints=(FixedJoint("O", [0, 0]), CrankJoint("A", "O", 1)))
    assert other.plan.joints == ("O", "A") and other.traced == ("A",)
    # Lists and a single traced name are accepted and normalised.
    listed = Linkage(joints=[FixedJoint("O", [0, 0]), CrankJoint("A", "O", 1)], traced="O")
    assert isinstance(listed.joints, tuple) and listed.traced == ("O",)
    assert mech == fourbar_linkage([0, 0], [4, 0], 1, 5, 3.5, u=2, v=1, assembly=-1)
    assert set(JOINT_TYPES) == {
        "fixed", "crank", "rrr", "rrp", "rigid", "hinge", "triad", "hinge-triad", "turning-triad"
    }  # fmt: skip


def test_with_assembly_and_configurations():
    jansen = load_example("jansen-leg").mechanism
    flipped = jansen.with_assembly({"C": 1})
    assert flipped.assemblies["C"] == 1 and flipped.assemblies["D"] == jansen.assemblies["D"]
    every = jansen.with_assembly(-1.0)
    assert set(map(float, every.assemblies.values())) == {-1.0}
    with pytest.raises(InvalidLinkage, match="'O' is not a dyad or slider joint"):
        jansen.with_assembly({"O": 1})
    configs = configurations(jansen, [0.3], order=0)
    assert len(configs) == 2**5
    own = tuple(int(s) for s in jansen.assemblies.values())
    (motion,) = [m for signs, m in configs if signs == own]
    np.testing.assert_array_equal(motion.positions["G"], solve(jansen, [0.3]).positions["G"])
    mirrored = fourbar_linkage([0, 0], [4, 0], 1, 5, 3.5).with_assembly(-1)
    named = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, assembly=-1)
    np.testing.assert_array_equal(
        solve(mirrored, INPUTS).positions["B"], solve(named, INPUTS).positions["B"]
    )


def test_residuals_cover_every_constraint():
    mech = Linkage(
        joints=(
            FixedJoint("O", [0, 0]),
            FixedJoint("Q", [3, 0]),
            CrankJoint("A", "O", 1),
            DyadJoint("B", "A", 3, "Q", 2),
            SliderJoint("S", "B", 2, "Q", 0.5),
            RigidJoint("P", "A", "B", 1, 1),
        )
    )
    res = mech.residuals(solve(mech, INPUTS))
    assert sorted(res) == [
        "A.angle",
        "A.length",
        "B.r1",
        "B.r2",
        "P.u",
        "P.v",
        "S.line",
        "S.r",
    ]
    # A wrong position shows up in the constraint it breaks (and only there).
    motion = solve(mech, [0.0])
    motion.positions["S"][...] += np.array([0.0, 0.1])
    broken = {k for k, r in mech.residuals(motion).items() if np.nanmax(np.abs(r)) > 1e-3}
    assert broken == {"S.line", "S.r"}


# ---------------------------------------------------------------------------------------------
# Every ill-formed linkage gets one clear message naming the joint
# ---------------------------------------------------------------------------------------------

O = FixedJoint("O", [0, 0])
Q = FixedJoint("Q", [4, 0])
A = CrankJoint("A", "O", 1)

BAD = [
    ((), None, "a linkage needs joints"),
    ((O, 5), None, "joints[1]: must be a joint spec (FixedJoint, CrankJoint"),
    ((FixedJoint("", [0, 0]), A), None, "joints[0]: name must be a non-empty string"),
    ((FixedJoint(3, [0, 0]), A), None, "joints[0]: name must be a non-empty string, got 3"),
    ((O, A, FixedJoint("O", [1, 1])), None, "joint 'O' is listed twice (joints[0] and joints[2])"),
    (
        (O, CrankJoint("A", "Z", 1)),
        None,
        "joint 'A' is built from 'Z', which is not placed before it (no joint has that name; "
        "under-constrained)",
    ),
    (
        (O, CrankJoint("A", "B", 1), DyadJoint("B", "A", 2, "O", 2)),
        None,
        "joint 'A' is built from 'B', which is not placed before it (it is listed after it; "
        "under-constrained)",
    ),
    ((O, CrankJoint("A", "A", 1)), None, "joint 'A' is built from itself (pivot)"),
    ((O, Q), None, "nothing drives the linkage: none of its joints is a crank or a driven hinge"),
    (
        (O, A, DyadJoint("B", "A", 2, "A", 3)),
        None,
        "joint 'B': p1 and p2 are both 'A' (a dyad needs two different joints",
    ),
    (
        (O, A, SliderJoint("B", "A", 2, "A", 0.0)),
        None,
        "joint 'B': p1 and line_point are both 'A'",
    ),
    ((O, A, RigidJoint("P", "A", "A", 1, 0)), None, "joint 'P': origin and toward are both 'A'"),
    ((O, CrankJoint("A", "O", -2)), None, "joint 'A': length must be a positive length, got -2.0"),
    ((O, CrankJoint("A", "O", 0)), None, "joint 'A': length must be a positive length, got 0.0"),
    ((O, CrankJoint("A", "O", 1, ratio=0)), None, "joint 'A': ratio must be nonzero"),
    ((O, CrankJoint("A", "O", math.nan)), None, "joint 'A': length must be finite, got nan"),
    ((O, CrankJoint("A", "O", "x")), None, "joint 'A': length must be a number, got 'x'"),
    (
        (O, CrankJoint("A", "O", [1, -1])),
        None,
        "joint 'A': length must be a positive length, got [-1.0] (in an array of shape (2,))",
    ),
    ((FixedJoint("O", [0, 0, 0]), A), None, "joint 'O': at must be a point [x, y], got shape"),
    ((FixedJoint("O", [0, math.inf]), A), None, "joint 'O': at must be finite"),
    ((O, Q, A, DyadJoint("B", "A", 5, "Q", 3, assembly=0)), None, "joint 'B': assembly must be"),
    ((O, A, DyadJoint("B", 7, 5, "O", 3)), None, "joint 'B': p1 must be a joint name, got 7"),
    (
        (O, A, FixedJoint("O2", [0.0, 0.0])),
        None,
        "joint 'O2' repeats joint 'O' (a ground pivot at the same place): two names for one "
        "point; over-constrained",
    ),
    (
        (O, Q, A, DyadJoint("B", "A", 5, "Q", 3), DyadJoint("C", "Q", 3, "A", 5, assembly=-1)),
        None,
        "joint 'C' repeats joint 'B' (the same construction from the same joints)",
    ),
    (
        (O, A, CrankJoint("A2", "O", 1)),
        None,
        "joint 'A2' repeats joint 'A' (the same construction",
    ),
    (
        (O, Q, A, DyadJoint("B", "A", 5, "Q", 3), RigidJoint("P", "A", "Q", 1, 1)),
        None,
        "joint 'P' is fixed on the link 'A'→'Q', but those two joints are not on one rigid link",
    ),
    ((O, A), "Z", "traced: 'Z' is not a joint of this linkage"),
    ((O, A), (), "traced: name at least one joint"),
    ((O, A), ("A", "A"), "traced: 'A' is listed twice"),
    ((O, A), 5, "traced: must be joint names, got 5"),
    ((O, A, FixedJoint(["Q"], [4, 0])), None, "joints[2]: name must be a non-empty string"),
    ((O, A), (["A"],), "traced: ['A'] is not a joint of this linkage"),
    (
        (O, CrankJoint("A", "O", np.ones(3)), CrankJoint("B", "O", np.ones(2))),
        None,
        "dimension arrays do not broadcast together",
    ),
    ("OA", None, "joints: must be a sequence of joint specs"),
]


@pytest.mark.parametrize(("joints", "traced", "message"), BAD)
def test_invalid_linkages_are_refused_naming_the_joint(joints, traced, message):
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=joints, traced=traced)
    assert str(info.value).startswith(message)
    assert isinstance(info.value, InvalidMechanism) and isinstance(info.value, ValueError)


def test_invalid_linkage_carries_the_joint_index_and_field():
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=(O, A, DyadJoint("B", "A", -2, "O", 3)))
    assert (info.value.index, info.value.joint, info.value.field) == (2, "B", "r1")
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=(O, A), traced="Z")
    assert (info.value.index, info.value.field) == (None, "traced")


def test_a_rigid_triangle_of_dyads_and_a_grounded_dyad_are_fine():
    # D from B and C, which are on one link: a rigid triangle; a point fixed on C→D is on it.
    # A dyad between two ground pivots is a ground point: rigid with the frame.
    mech = Linkage(
        joints=(
            O,
            Q,
            A,
            DyadJoint("C", "A", 5, "Q", 3),
            DyadJoint("D", "Q", 2, "C", 2),
            RigidJoint("P", "C", "D", 0.5, 0.5),
            DyadJoint("G", "O", 3, "Q", 3),
            RigidJoint("H", "O", "G", 1, 0),
        )
    )
    motion = solve(mech, INPUTS)
    assert motion.valid.all()
    assert max_residual(mech, motion) < 1e-10
    check_derivatives(mech, INPUTS)


# ---------------------------------------------------------------------------------------------
# Fuzzing the class: whatever the joints, only InvalidLinkage, and a built linkage solves
# ---------------------------------------------------------------------------------------------

# Mostly well-formed joints, so that many drawn linkages build and get solved; about one in
# eight has one field replaced by something wrong (a bad or repeated name, a parent not placed
# yet, a bad number, an odd array), so that every refusal is reached too.
junk = st.sampled_from(
    ["", 3, None, ("A",), "O", "A", "Z", 0.0, -1.0, math.nan, math.inf, "x", [[1.0]], [1.0, 2.0]]
)
GOOD = {
    "at": st.tuples(st.floats(-3, 3), st.floats(-3, 3)).map(list),
    "length": st.floats(0.2, 4),
    "r1": st.floats(0.2, 4),
    "r2": st.floats(0.2, 4),
    "r": st.floats(0.2, 4),
    "a": st.floats(0.2, 4),
    "b": st.floats(0.2, 4),
    "ratio": st.sampled_from([1.0, -1.0, 2.0, 0.5]),
    "phase": st.floats(-4, 4),
    "line_angle": st.floats(-4, 4),
    "u": st.floats(-4, 4),
    "v": st.floats(-4, 4),
    "assembly": st.sampled_from([1.0, -1.0]),
    "r3": st.floats(0.2, 4),
    "side": st.floats(0.2, 4),
    "pose": st.sampled_from([0.0, 1.0, 5.0]),
}


@st.composite
def random_joint_lists(draw):
    placed = ["O", "A"]
    joints = []
    for i in range(draw(st.integers(0, 6))):
        cls = draw(st.sampled_from(list(JOINT_TYPES.values())))
        names = [f.name for f in dataclasses.fields(cls)]
        # Distinct parents while there are enough (a triad's three may repeat one).
        parents = itertools.cycle(draw(st.permutations(placed)))
        kwargs = {}
        for field_name in names:
            if field_name == "name":
                kwargs[field_name] = f"J{i}"
            elif field_name in ("far", "j2", "j3"):  # further joints it places: new names
                kwargs[field_name] = f"J{i}{field_name}"
            elif field_name in GOOD:
                kwargs[field_name] = draw(GOOD[field_name])
            else:  # a parent: distinct ones, all placed before
                kwargs[field_name] = next(parents)
        if draw(st.integers(0, 7)) == 0:
            kwargs[draw(st.sampled_from(names))] = draw(junk)
        if draw(st.integers(0, 15)) == 0:
            kwargs[draw(st.sampled_from(names[1:]))] = [0.5, 1.0, 2.0]  # a batch of three
        joints.append(cls(**kwargs))
        placed.append(f"J{i}")
    return joints


@settings(max_examples=300, deadline=None)
@given(random_joint_lists(), st.none() | st.lists(st.sampled_from(["O", "A", "J0", "Z"])))
def test_fuzz_linkages_only_raise_invalid_linkage(joints, traced):
    try:
        mech = Linkage(joints=[O, A, *joints], traced=traced)
    except InvalidLinkage:
        return
    with np.errstate(all="ignore"):
        motion = solve(mech, INPUTS[:4])
        residual = mech.residuals(motion)
    assert set(motion.positions) == set(mech.reported_joints)
    for r in residual.values():
        assert np.all(np.isnan(r) | (np.abs(r) < 1e-9))

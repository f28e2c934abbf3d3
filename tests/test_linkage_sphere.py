"""Spherical composed linkages: the named spherical families spelled out joint by joint, frame
independence, closed forms, residuals, derivatives, and every refusal.

The independent checks: a linkage written joint by joint against the family class that builds
its own plan (with its own parameter names and crank reference); the same linkage turned by an
arbitrary rotation, which must turn every joint with it (nothing may depend on the frame); a
geared crank against its closed form; limit positions against the triangle inequality of arcs;
derivatives against central differences; residuals computed here from dot products.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.mechanisms import (
    InvalidMechanism,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    circuit,
    configurations,
    input_range,
    solve,
)
from linkwright.mechanisms.linkage import (
    CrankJoint,
    DyadJoint,
    FixedJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SliderJoint,
    SphereCrankJoint,
    SphereRigidJoint,
)

INPUTS = np.linspace(-math.pi, math.pi, 24, endpoint=False)
X, Y, Z = np.eye(3)


def fourbar_linkage(
    a1, a2, a3, a4, ac=0.0, mu=0.0, assembly=1.0, phase=0.0, rotation=None, stretch=1.0
):
    """Paper 000's four-bar joint by joint, its frame turned by ``rotation`` and its axes given
    as vectors ``stretch`` long."""
    rotation = np.eye(3) if rotation is None else rotation
    b0 = np.array([math.cos(a1), math.sin(a1), 0.0])
    return Linkage(
        joints=(
            FixedJoint("A0", stretch * (rotation @ X)),
            FixedJoint("B0", stretch * (rotation @ b0)),
            SphereCrankJoint("A", "A0", a2, phase=phase, toward="B0"),
            DyadJoint("B", "A", a3, "B0", a4, assembly=assembly),
            SphereRigidJoint("P", "A", "B", ac, mu),
        ),
        space="sphere",
    )


# Arcs away from 0 and π: a rigid point on a link of arc a carries its link's direction error
# times 1/sin a, which the tolerances below would otherwise have to follow.
arcs = st.floats(0.2, math.pi - 0.2)
angles = st.floats(-math.pi, math.pi)
signs = st.sampled_from([1.0, -1.0])


@st.composite
def fourbars(draw):
    return {
        "a1": draw(arcs),
        "a2": draw(arcs),
        "a3": draw(arcs),
        "a4": draw(arcs),
        "ac": draw(st.floats(0, math.pi)),
        "mu": draw(angles),
        "assembly": draw(signs),
    }


@st.composite
def rotations(draw):
    q = np.array([draw(st.floats(-1, 1)) for _ in range(4)])
    if np.linalg.norm(q) < 0.1:
        q = np.array([1.0, 0.0, 0.0, 0.0])
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def about(axis, angle: float) -> np.ndarray:
    """The rotation by ``angle`` about ``axis``, right-handed (Rodrigues' matrix, written out)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def max_residual(mech, motion) -> float:
    return max(float(np.nanmax(np.abs(r))) for r in mech.residuals(motion).values())


def crank_meets_frame(frame: float, crank: float) -> bool:
    """Whether the crank pin can land on the other frame pivot's axis (or its antipode), where
    the dyad between them has no great circle to stand on: A = ±B0 at θ = 0 or π exactly when
    the crank's arc equals the frame's or its supplement. Both constructions then hold only
    rounding noise, and they need not agree on it."""
    return abs(frame - crank) < 1e-6 or abs(frame + crank - math.pi) < 1e-6


def change_point(a1: float, a2: float, a3: float, a4: float) -> bool:
    """Whether all four joints can lie on one great circle (a change-point linkage).

    With A on the frame's great circle (θ = 0 or π) the arc AB0 has cos(a1 ∓ a2); the dyad lies
    flat when that arc has cos(a3 ± a4). There the input's admissible arc shrinks to a point or
    opens to the full turn by rounding alone, so two constructions may trace differently.
    """
    frame = [math.cos(a1 - a2), math.cos(a1 + a2)]
    dyad = [math.cos(a3 - a4), math.cos(a3 + a4)]
    return min(abs(f - d) for f in frame for d in dyad) < 1e-9


def assert_same_motion(a, b, joints, tol: float = 1e-13) -> None:
    """Two constructions of one linkage give one motion.

    Their rounding differs (by up to about 150 ulps of a unit vector where the trigonometric
    forms and the cross products each round: 3.1e-14 was seen), and it is amplified in two
    ways: an ulp of input moves a joint by its speed times that ulp, and towards a limit
    position a dyad's joint moves like the square root of its margin (sin² of its angle), so an
    ulp there grows like 1/√margin. Each sample is
    held to ``tol·(1 + speed + 0.01/√margin)``. Within 1e-12 of a limit either may assemble and
    the other not; derivatives, which grow like 1/margin, are compared where the margin is above
    1e-6.
    """
    margin = np.minimum.reduce([np.fmin(a.margins[k], b.margins[k]) for k in a.margins])
    edge = ~(margin > 1e-12)
    np.testing.assert_array_equal(a.valid[~edge], b.valid[~edge])
    both = a.valid & b.valid
    smooth = a.regular & b.regular & (margin > 1e-6)
    for j in joints:
        speed = np.nan_to_num(np.linalg.norm(a.velocities[j], axis=-1), nan=0.0)
        slack = 0.01 / np.sqrt(np.where(both & ~edge, margin, 1e-24))
        allow = tol * (1 + speed + slack)
        err = np.abs(a.positions[j] - b.positions[j]).max(axis=-1)
        assert (err[both] <= allow[both]).all(), (j, err[both].max())
        for kind, rtol in (("velocities", 1e-10), ("accelerations", 1e-9)):
            # Relative to each vector's length: a component far smaller than its vector keeps
            # only the vector's absolute rounding.
            x, y = getattr(a, kind)[j][smooth], getattr(b, kind)[j][smooth]
            scale = np.linalg.norm(y, axis=-1) + 1e-3
            assert (np.abs(x - y).max(axis=-1, initial=0.0) <= rtol * scale).all(), (j, kind)


def named_fourbar(d: dict) -> SphericalFourBar:
    return SphericalFourBar(
        d["a1"], d["a2"], d["a3"], d["a4"], d["ac"], d["mu"], assembly=d["assembly"]
    )


# ---------------------------------------------------------------------------------------------
# The named families, spelled out
# ---------------------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(fourbars(), angles)
def test_spherical_fourbar_in_linkage_form_agrees_with_the_family(dims, phase):
    assume(not crank_meets_frame(dims["a1"], dims["a2"]))
    assume(not change_point(dims["a1"], dims["a2"], dims["a3"], dims["a4"]))
    named, composed = named_fourbar(dims), fourbar_linkage(**dims)
    assert_same_motion(solve(named, INPUTS), solve(composed, INPUTS), ("A0", "B0", "A", "B", "P"))
    # A phase on the crank is the four-bar driven from θ + phase.
    shifted = solve(fourbar_linkage(**dims, phase=phase), INPUTS)
    assert_same_motion(solve(named, INPUTS + phase), shifted, ("A", "B", "P"))
    if shifted.valid.any():
        assert max_residual(fourbar_linkage(**dims, phase=phase), shifted) < 1e-13
    # Over a whole circuit, limits included, the two are one linkage. At a limit sample the
    # dyad's joint moves like the square root of the input, so there an ulp of input or crank
    # direction shows as √ulp ~ 1e-8 of position.
    ca, cb = circuit(named, 32), circuit(composed, 32)
    np.testing.assert_allclose(ca.input, cb.input, rtol=0, atol=1e-14)
    near = (ca.margins["B"] < 1e-6) | (cb.margins["B"] < 1e-6)
    for j in ("A", "B", "P"):
        np.testing.assert_allclose(ca.positions[j][~near], cb.positions[j][~near], atol=1e-14)
        np.testing.assert_allclose(ca.positions[j][near], cb.positions[j][near], atol=1e-7)


def test_fig6_linkage_over_its_circuit_is_the_fig6_four_bar():
    fig6 = np.radians([40, 20, 45, 35, 50, 130])
    named = SphericalFourBar(*fig6)
    composed = fourbar_linkage(*fig6)
    a, b = circuit(named, 720), circuit(composed, 720)
    assert a.valid.all() and b.valid.all()
    np.testing.assert_allclose(a.input, b.input, rtol=0, atol=1e-14)
    for j in ("A0", "B0", "A", "B", "P"):
        np.testing.assert_allclose(a.positions[j], b.positions[j], rtol=0, atol=1e-14)


@settings(max_examples=60, deadline=None)
@given(fourbars(), rotations(), st.floats(1e-3, 1e3))
def test_a_turned_frame_turns_every_joint_with_it(dims, rotation, stretch):
    """Nothing may depend on the frame: turned axes (given at any length) turn the motion."""
    assume(not crank_meets_frame(dims["a1"], dims["a2"]))
    base = solve(fourbar_linkage(**dims), INPUTS)
    turned = solve(fourbar_linkage(**dims, rotation=rotation, stretch=stretch), INPUTS)

    def turn(joints: dict) -> dict:
        return {k: v @ rotation.T for k, v in joints.items()}

    expect = dataclasses.replace(
        base,
        positions=turn(base.positions),
        velocities=turn(base.velocities),
        accelerations=turn(base.accelerations),
    )
    # The rotation itself rounds: a few ulps more than two constructions in one frame.
    assert_same_motion(expect, turned, ("A0", "B0", "A", "B", "P"), tol=1e-13)


def test_an_axis_may_be_given_at_any_length():
    a1, a2, a3, a4 = np.radians([40, 20, 45, 35])
    unit = fourbar_linkage(a1, a2, a3, a4)
    long = fourbar_linkage(a1, a2, a3, a4, stretch=1e200)
    short = fourbar_linkage(a1, a2, a3, a4, stretch=1e-200)
    for other in (long, short):
        np.testing.assert_allclose(
            solve(other, INPUTS).positions["B"], solve(unit, INPUTS).positions["B"], atol=1e-15
        )
    # The spec keeps what was written; the plan parameter is the unit vector.
    np.testing.assert_array_equal(long.joint("A0").at, [1e200, 0.0, 0.0])
    np.testing.assert_array_equal(long.params()["A0.at"], [1.0, 0.0, 0.0])


def sixbar_linkage(m: SphericalSixBar) -> Linkage:
    """Paper 000's Fig. 8 joint by joint; E0 placed here from its own formula: at arc B0E0 from
    B0, turned by ε about +OB0 from k, the frame circle's direction beyond B0."""
    a1 = float(m.frame)
    b0 = np.array([math.cos(a1), math.sin(a1), 0.0])
    k = np.array([-math.sin(a1), math.cos(a1), 0.0])
    g, eps = float(m.ground_arc), float(m.ground_angle)
    e0 = math.cos(g) * b0 + math.sin(g) * (math.cos(eps) * k + math.sin(eps) * np.cross(b0, k))
    return Linkage(
        joints=(
            FixedJoint("A0", X),
            FixedJoint("B0", b0),
            FixedJoint("E0", e0),
            SphereCrankJoint("A", "A0", m.crank, toward="B0"),
            DyadJoint("B", "A", m.coupler, "B0", m.rocker, assembly=m.assembly),
            SphereRigidJoint("C", "A", "B", m.point_arc, m.point_angle),
            DyadJoint("E", "C", m.link5, "E0", m.link6, assembly=m.assembly2),
            SphereRigidJoint("D", "C", "E", m.d_arc, m.d_angle),
        ),
        traced=("D", "C"),
        space="sphere",
    )


@settings(max_examples=30, deadline=None)
@given(st.lists(arcs, min_size=7, max_size=7), angles, angles, angles, signs, signs)
def test_spherical_sixbar_in_linkage_form_agrees_with_the_family(a, mu, eps, ecd, s1, s2):
    assume(not crank_meets_frame(a[0], a[1]))
    named = SphericalSixBar(
        a[0], a[1], a[2], a[3], a[4], mu, a[5], a[6], 1.3, eps, 0.4, ecd, s1, s2
    )
    composed = sixbar_linkage(named)
    p, q = solve(named, INPUTS), solve(composed, INPUTS)
    clear = p.valid & q.valid
    for m in (p, q):
        for margin in m.margins.values():
            clear &= margin > 1e-9
    for j in ("E0", "A", "B", "C", "E", "D"):
        np.testing.assert_allclose(
            p.positions[j][clear], q.positions[j][clear], rtol=0, atol=1e-9, err_msg=j
        )


def test_paper000_fig8_as_a_linkage_closes_over_the_whole_turn():
    fig8 = SphericalSixBar(
        *np.radians([35, 20, 42, 30, 72, 22, 45, 33, 85, -30, 30, 75]), assembly=-1
    )
    composed = sixbar_linkage(fig8)
    a, b = solve(fig8, INPUTS), solve(composed, INPUTS)
    assert a.valid.all() and b.valid.all()
    for j in ("E0", "C", "E", "D"):
        np.testing.assert_allclose(a.positions[j], b.positions[j], rtol=0, atol=1e-14)
    assert max_residual(composed, b) < 1e-14


def stephenson3_linkage(m: SphericalStephenson3) -> Linkage:
    """Paper 001's Stephenson III joint by joint: A = z, D and G on the meridian towards +y."""
    a1, a9 = float(m.a1), float(m.a9)
    return Linkage(
        joints=(
            FixedJoint("A", Z),
            FixedJoint("D", [0.0, math.sin(a1), math.cos(a1)]),
            FixedJoint("G", [0.0, math.sin(a1 + a9), math.cos(a1 + a9)]),
            # Eq. 5 turns B = (sin a2 sin θ, sin a2 cos θ, cos a2) from D towards +x: that is
            # left-handed about +OA, a ratio of −1.
            SphereCrankJoint("B", "A", m.a2, ratio=-1.0, toward="D"),
            DyadJoint("C", "B", m.a3, "D", m.a4, assembly=m.assembly),
            SphereRigidJoint("E", "C", "B", m.a6, math.pi - float(m.sigma)),
            DyadJoint("F", "E", m.a7, "G", m.a8, assembly=m.assembly2),
        ),
        traced=("E", "F"),
        space="sphere",
    )


@settings(max_examples=30, deadline=None)
@given(st.lists(arcs, min_size=8, max_size=8), angles, signs, signs)
def test_spherical_stephenson3_in_linkage_form_agrees_with_the_family(a, sigma, s1, s2):
    assume(not crank_meets_frame(a[0], a[1]))  # AD and AB
    # G opposite A (a1 + a9 = 180°) is A's axis again: the family allows it (its G is a point
    # of the plan), a composed linkage refuses it as two names for one revolute.
    assume(abs(a[0] + a[7] - math.pi) > 1e-6)
    named = SphericalStephenson3(*a[:5], sigma, *a[5:], assembly=s1, assembly2=s2)
    composed = stephenson3_linkage(named)
    p, q = solve(named, INPUTS), solve(composed, INPUTS)
    assert_same_motion(p, q, ("G", "B", "C", "E", "F"))
    b = np.sin(float(named.a2))
    # B by eq. 5 of paper 001, written out.
    eq5 = np.stack([b * np.sin(INPUTS), b * np.cos(INPUTS), np.cos(a[1]) + 0 * INPUTS], -1)
    np.testing.assert_allclose(q.positions["B"][q.valid], eq5[q.valid], rtol=0, atol=1e-15)


# ---------------------------------------------------------------------------------------------
# Closed forms, signs and limits
# ---------------------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(arcs, st.sampled_from([1.0, -1.0, 2.0, -3.0, 0.5]), angles)
def test_a_geared_crank_is_its_closed_form(arc, ratio, phase):
    # About +z, its zero towards +x: A = (sin a cos φ, sin a sin φ, cos a), φ = phase + kθ.
    mech = Linkage(
        joints=(
            FixedJoint("O", [0, 0, 5]),
            FixedJoint("Q", [2, 0, 0]),
            SphereCrankJoint("A", "O", arc, ratio=ratio, phase=phase),
        ),
        space="sphere",
    )
    assert mech.joint("A").toward == "Q"  # the default: the first other fixed joint
    phi = phase + ratio * INPUTS
    s, c = math.sin(arc), math.cos(arc)
    motion = solve(mech, INPUTS)
    expect = np.stack([s * np.cos(phi), s * np.sin(phi), c + 0 * phi], -1)
    np.testing.assert_allclose(motion.positions["A"], expect, rtol=0, atol=1e-15)
    vel = np.stack([-s * ratio * np.sin(phi), s * ratio * np.cos(phi), 0 * phi], -1)
    np.testing.assert_allclose(motion.velocities["A"], vel, rtol=0, atol=1e-14)
    acc = np.stack([-s * ratio**2 * np.cos(phi), -s * ratio**2 * np.sin(phi), 0 * phi], -1)
    np.testing.assert_allclose(motion.accelerations["A"], acc, rtol=0, atol=1e-13)
    assert max_residual(mech, motion) < 1e-15


@settings(max_examples=40, deadline=None)
@given(fourbars())
def test_assembly_is_the_side_of_the_great_circle_p1_to_p2(dims):
    assume(not crank_meets_frame(dims["a1"], dims["a2"]))
    mech = fourbar_linkage(**dims)
    m = solve(mech, INPUTS, order=0)
    pos = m.positions
    side = np.sum(np.cross(pos["A"], pos["B0"]) * pos["B"], -1)
    clear = m.valid & (m.margins["B"] > 1e-12)
    assert (np.sign(side[clear]) == dims["assembly"]).all()


@settings(max_examples=40, deadline=None)
@given(fourbars())
def test_limits_are_where_the_arc_triangle_flattens(dims):
    """At an end of an input arc A, B, B0 lie on one great circle: the arc AB0 is
    coupler + rocker, |coupler − rocker|, or 2π − coupler − rocker (the three arcs then make
    the whole great circle): the equalities of the spherical triangle inequalities."""
    mech = fourbar_linkage(**dims)
    arcs_found = input_range(mech)
    if bool(arcs_found.full) or not np.isfinite(arcs_found.lo).any():
        return
    ends = np.concatenate([arcs_found.lo, arcs_found.hi])
    ends = ends[np.isfinite(ends)]
    pos = solve(mech, ends, order=0).positions
    d = np.arccos(np.clip(np.sum(pos["A"] * pos["B0"], -1), -1, 1))
    a3, a4 = dims["a3"], dims["a4"]
    flat = np.min(np.abs(d[:, None] - [a3 + a4, abs(a3 - a4), 2 * math.pi - a3 - a4]), axis=1)
    assert (flat < 1e-7).all(), (d, a3, a4)


@settings(max_examples=25, deadline=None)
@given(fourbars(), rotations())
def test_derivatives_match_central_differences(dims, rotation):
    assume(not crank_meets_frame(dims["a1"], dims["a2"]))
    # A four-bar, turned, with a second dyad hung from its coupler point and a third pivot.
    base = fourbar_linkage(**dims, rotation=rotation)
    mech = Linkage(
        joints=(
            *base.joints,
            FixedJoint("E0", rotation @ np.array([0.3, -0.4, 0.866])),
            DyadJoint("E", "P", 0.9, "E0", 1.1),
        ),
        space="sphere",
    )
    h = 1e-5
    here, up, down = (solve(mech, INPUTS + d) for d in (0.0, h, -h))
    ok = here.regular & up.regular & down.regular
    for m in (here, up, down):
        for margin in m.margins.values():
            ok &= margin > 0.05
    for j in mech.reported_joints:
        fd_vel = (up.positions[j] - down.positions[j]) / (2 * h)
        fd_acc = (up.velocities[j] - down.velocities[j]) / (2 * h)
        np.testing.assert_allclose(here.velocities[j][ok], fd_vel[ok], rtol=1e-5, atol=1e-6)
        np.testing.assert_allclose(here.accelerations[j][ok], fd_acc[ok], rtol=1e-4, atol=1e-5)


# ---------------------------------------------------------------------------------------------
# Residuals, assemblies, batches
# ---------------------------------------------------------------------------------------------


FIG6 = fourbar_linkage(*np.radians([40, 20, 45, 35, 50, 130]))


def test_residuals_cover_every_constraint_and_mean_it():
    motion = solve(FIG6, INPUTS)
    res = FIG6.residuals(motion)
    assert sorted(res) == ["A.angle", "A.arc", "B.r1", "B.r2", "P.point", "unit"]
    assert max_residual(FIG6, motion) < 1e-15
    # Each constraint, recomputed here from dot products, holds as the residual says.
    pos = motion.positions
    cos_ab = np.sum(pos["A"] * pos["B"], -1)
    np.testing.assert_allclose(cos_ab, math.cos(math.radians(45)), atol=1e-15)

    def moved(j: str, new: np.ndarray) -> dict[str, np.ndarray]:
        m = solve(FIG6, [0.3])
        m.positions[j][...] = new
        return FIG6.residuals(m)

    def broken(j: str, new: np.ndarray) -> set[str]:
        return {k for k, r in moved(j, new).items() if np.nanmax(np.abs(r)) > 1e-4}

    at = solve(FIG6, [0.3]).positions
    sin_crank = math.sin(math.radians(20))
    # P turned about z: off its place on the link, still on the sphere.
    assert broken("P", at["P"] @ about(Z, 0.01).T) == {"P.point"}
    # A moved along its own circle about A0 = x: the arc holds, the angle and the coupler do
    # not; the angle's error is the move along that circle, 0.01·sin(crank).
    assert broken("A", at["A"] @ about(X, 0.01).T) == {"A.angle", "B.r1", "P.point"}
    along = moved("A", at["A"] @ about(X, 0.01).T)
    np.testing.assert_allclose(along["A.angle"], 0.01 * sin_crank, rtol=1e-12)
    # ... half-way round its circle: the arc right, the angle off by π (not a sign flip away).
    half = moved("A", at["A"] @ about(X, math.pi).T)
    np.testing.assert_allclose(np.abs(half["A.angle"]), math.pi * sin_crank, rtol=1e-12)
    np.testing.assert_allclose(half["A.arc"], 0.0, atol=1e-15)
    # A moved along its great circle from A0: the angle holds, the arc does not.
    away = about(np.cross(X, at["A"][0]), 0.01)
    assert broken("A", at["A"] @ away.T) == {"A.arc", "B.r1", "P.point"}
    # B pushed off the sphere (out along its own axis: every arc from it holds).
    assert broken("B", 1.01 * at["B"]) == {"unit"}


def test_with_assembly_configurations_and_batches():
    flipped = FIG6.with_assembly(-1)
    assert flipped.space == "sphere" and flipped.assemblies == {"B": -1.0}
    named = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]), assembly=-1)
    np.testing.assert_allclose(
        solve(flipped, INPUTS).positions["P"], solve(named, INPUTS).positions["P"], atol=1e-14
    )
    configs = configurations(FIG6, [0.3], order=0)
    assert [signs for signs, _ in configs] == [(1,), (-1,)]
    # A batch of three rocker arcs is three single linkages side by side.
    rockers = np.radians([30.0, 35.0, 40.0])
    batch = fourbar_linkage(*np.radians([40, 20, 45]), rockers)
    assert batch.batch_shape == (3,) and float(batch.scale) == 1.0
    motion = solve(batch, INPUTS)
    for i, r in enumerate(rockers):
        one = solve(fourbar_linkage(*np.radians([40, 20, 45]), r), INPUTS)
        np.testing.assert_array_equal(motion.positions["B"][i], one.positions["B"])
    # Batched axes, too (a trailing 3).
    axes = np.array([[1.0, 0, 0], [0, 0, 1]])
    two = Linkage(
        joints=(
            FixedJoint("O", axes),
            FixedJoint("Q", [0, 1, 0]),
            SphereCrankJoint("A", "O", 0.5),
        ),
        space="sphere",
    )
    assert two.batch_shape == (2,)
    got = solve(two, [0.0]).positions["A"]
    np.testing.assert_allclose(
        got[:, 0],
        [[math.cos(0.5), math.sin(0.5), 0], [0, math.sin(0.5), math.cos(0.5)]],
        atol=1e-16,
    )


def test_fig6_crank_turns_fully_and_a_rocker_input_has_flat_limits():
    assert bool(input_range(FIG6).full)
    # Driving Fig. 6's rocker: the long link as input swings between two limits.
    a1, a2, a3, a4 = np.radians([40, 20, 45, 35])
    rocker_in = Linkage(
        joints=(
            FixedJoint("B0", [1, 0, 0]),
            FixedJoint("A0", [math.cos(a1), math.sin(a1), 0]),
            SphereCrankJoint("B", "B0", a4),
            DyadJoint("A", "B", a3, "A0", a2),
        ),
        space="sphere",
    )
    arcs_found = input_range(rocker_in)
    assert not bool(arcs_found.full)
    lo, hi = float(arcs_found.lo[0]), float(arcs_found.hi[0])
    # The rocker swings through 82.89° when the crank drives (paper 000's eq. 5, see
    # test_documents_spherical): driven itself, it has the same arc between its limits ...
    assert abs(math.degrees(hi - lo) % 360 - 82.89) < 0.005
    # ... where the crank and the coupler lie on one great circle, stretched and folded.
    pos = solve(rocker_in, [lo, hi], order=0).positions
    reach = np.arccos(np.clip(np.sum(pos["B"] * pos["A0"], -1), -1, 1))
    np.testing.assert_allclose(np.sort(reach), [a3 - a2, a3 + a2], atol=1e-7)
    run = circuit(rocker_in, 64)
    assert run.valid.all() and max_residual(rocker_in, run) < 1e-12


# ---------------------------------------------------------------------------------------------
# Every ill-formed spherical linkage gets one clear message naming the joint
# ---------------------------------------------------------------------------------------------

O = FixedJoint("O", [0, 0, 1])
Q = FixedJoint("Q", [1, 0, 0])
A = SphereCrankJoint("A", "O", 0.5)

BAD = [
    (
        (O, Q, CrankJoint("A", "O", 1.0)),
        "joint 'A' is a planar CrankJoint, but this linkage is spherical: use SphereCrankJoint",
    ),
    (
        (O, Q, A, RigidJoint("P", "O", "A", 1, 0)),
        "joint 'P' is a planar RigidJoint, but this linkage is spherical: use SphereRigidJoint",
    ),
    (
        (O, Q, A, SliderJoint("S", "A", 0.5, "Q", 0.0)),
        "joint 'S': a slider (rrp) has no spherical counterpart: a pin on a great-circle guide is "
        "an rrr dyad whose second link, 90° long, turns about the guide's pole",
    ),
    ((FixedJoint("O", [0, 0]), Q, A), "joint 'O': at must be an axis [x, y, z]"),
    ((FixedJoint("O", [0, 0, 0]), Q, A), "joint 'O': at must not be the zero vector"),
    ((FixedJoint("O", [0, math.nan, 1]), Q, A), "joint 'O': at must be finite, got [nan]"),
    ((O, Q, SphereCrankJoint("A", "O", 0.0)), "joint 'A': arc must be an arc strictly between 0"),
    ((O, Q, SphereCrankJoint("A", "O", math.pi)), "joint 'A': arc must be an arc strictly"),
    (
        (O, Q, SphereCrankJoint("A", "O", [0.5, 4.0])),
        "joint 'A': arc must be an arc strictly between 0 and π (radians), got [4.0] (in an array",
    ),
    ((O, Q, SphereCrankJoint("A", "O", 0.5, ratio=0)), "joint 'A': ratio must be nonzero"),
    (
        (O, SphereCrankJoint("A", "O", 0.5)),
        "joint 'A': a spherical crank's angle is measured from the great circle towards a second "
        "fixed joint (toward), and no fixed joint other than its pivot is listed before it",
    ),
    (
        (O, Q, SphereCrankJoint("A", "O", 0.5, toward="O")),
        "joint 'A': pivot and toward are both 'O'",
    ),
    (
        (O, Q, A, SphereCrankJoint("G", "A", 0.5)),
        "joint 'G': a spherical crank turns about a fixed joint, and 'A' is a crank joint (pivot)",
    ),
    (
        (O, Q, A, SphereCrankJoint("G", "O", 0.7, toward="A")),
        "joint 'G': a spherical crank measures its angle towards a fixed joint, and 'A' is a "
        "crank joint (toward)",
    ),
    (
        (O, Q, SphereCrankJoint("A", "O", 0.5, toward="R"), FixedJoint("R", [0, 1, 0])),
        "joint 'A' is built from 'R', which is not placed before it (it is listed after it",
    ),
    ((O, Q, SphereCrankJoint("A", "O", 0.5, toward=3)), "joint 'A': toward must be a joint name"),
    ((O, Q, A, DyadJoint("B", "A", 0.0, "Q", 1.0)), "joint 'B': r1 must be an arc strictly"),
    ((O, Q, A, DyadJoint("B", "A", 1.0, "Q", 3.2)), "joint 'B': r2 must be an arc strictly"),
    ((O, Q, A, DyadJoint("B", "A", 1.0, "Q", 1.0, 0.5)), "joint 'B': assembly must be 1 or -1"),
    (
        (O, Q, A, SphereRigidJoint("P", "O", "A", -0.1)),
        "joint 'P': arc must be an arc from 0 to π (radians), got -0.1 (for a point on the other "
        "side of the link, turn its angle by π instead)",
    ),
    ((O, Q, A, SphereRigidJoint("P", "O", "A", 3.5)), "joint 'P': arc must be an arc from 0 to"),
    ((O, Q, A, SphereRigidJoint("P", "O", "A", 1, "x")), "joint 'P': angle must be a number"),
    (
        (O, FixedJoint("Q", [0, 0, -3]), A),
        "joint 'Q' repeats joint 'O' (a ground pivot on the same axis, in the same or opposite "
        "direction): two names for one point",
    ),
    ((O, FixedJoint("Q", [0, 0, 2]), A), "joint 'Q' repeats joint 'O' (a ground pivot on the"),
    (
        (O, Q, A, SphereCrankJoint("A2", "O", 0.5, toward="Q")),
        "joint 'A2' repeats joint 'A' (the same construction from the same joints)",
    ),
    (
        (O, Q, A, DyadJoint("B", "A", 1, "Q", 1), DyadJoint("C", "Q", 1, "A", 1, -1)),
        "joint 'C' repeats joint 'B' (the same construction",
    ),
    (
        (O, Q, A, DyadJoint("B", "A", 1, "Q", 1), SphereRigidJoint("P", "A", "Q", 1, 1)),
        "joint 'P' is fixed on the link 'A'→'Q', but those two joints are not on one rigid link",
    ),
    ((O, Q, A, DyadJoint("B", "A", 1, "A", 1)), "joint 'B': p1 and p2 are both 'A'"),
    ((O, Q), "nothing drives the linkage: none of its joints is a crank"),
    (
        (O, Q, A, DyadJoint("B", "A", np.ones(3), "Q", np.ones(2))),
        "dimension arrays do not broadcast together",
    ),
]


@pytest.mark.parametrize(("joints", "message"), BAD)
def test_invalid_spherical_linkages_are_refused_naming_the_joint(joints, message):
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=joints, space="sphere")
    assert str(info.value).startswith(message)
    assert isinstance(info.value, InvalidMechanism) and isinstance(info.value, ValueError)


def test_spherical_joints_in_a_planar_linkage_and_unknown_spaces():
    with pytest.raises(InvalidLinkage, match=r"^joint 'A' is a spherical SphereCrankJoint, but"):
        Linkage(joints=(FixedJoint("O", [0, 0]), FixedJoint("Q", [1, 0]), A))
    with pytest.raises(InvalidLinkage, match=r"at must be a point \[x, y\], got shape \(3,\) \(an"):
        Linkage(joints=(O, CrankJoint("A", "O", 1.0)))
    with pytest.raises(InvalidLinkage, match=r"^space: must be 'plane' or 'sphere', got 'ball'"):
        Linkage(joints=(O, Q, A), space="ball")
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=(O, Q, A, DyadJoint("B", "A", -1.0, "Q", 1.0)), space="sphere")
    assert (info.value.index, info.value.joint, info.value.field) == (3, "B", "r1")
    with pytest.raises(InvalidLinkage) as info:
        Linkage(joints=(O, SphereCrankJoint("A", "O", 0.5)), space="sphere")
    assert (info.value.index, info.value.field) == (1, "toward")


def test_a_half_speed_spherical_crank_is_traced_over_two_turns():
    mech = Linkage(joints=(O, Q, SphereCrankJoint("A", "O", 0.5, ratio=0.5)), space="sphere")
    run = circuit(mech, 8)
    assert run.input[-1] > 2 * math.pi


# ---------------------------------------------------------------------------------------------
# Fuzzing the class: whatever the spherical joints, only InvalidLinkage, and a built linkage
# solves with every constraint held
# ---------------------------------------------------------------------------------------------

junk = st.sampled_from(
    ["", 3, None, "O", "A", "Z", 0.0, -1.0, 4.0, math.nan, math.inf, "x", [0, 0, 0], [1.0, 2.0]]
)
GOOD = {
    "at": st.tuples(*[st.floats(-2, 2)] * 3).map(list),
    "arc": arcs,
    "r1": arcs,
    "r2": arcs,
    "ratio": st.sampled_from([1.0, -1.0, 2.0]),
    "phase": angles,
    "angle": angles,
    "assembly": signs,
}
SPHERE_CLASSES = [FixedJoint, SphereCrankJoint, DyadJoint, SphereRigidJoint]


@st.composite
def random_sphere_joints(draw):
    placed = ["O", "Q", "A"]
    joints = []
    for i in range(draw(st.integers(0, 5))):
        cls = draw(st.sampled_from(SPHERE_CLASSES))
        names = [f.name for f in dataclasses.fields(cls)]
        parents = iter(draw(st.permutations(placed)))
        kwargs = {}
        for field_name in names:
            if field_name == "name":
                kwargs[field_name] = f"J{i}"
            elif field_name == "toward" and cls is SphereCrankJoint:
                kwargs[field_name] = draw(st.sampled_from([None, "O", "Q", "A"]))
            elif field_name == "pivot":
                kwargs[field_name] = draw(st.sampled_from(["O", "Q"]))
            elif field_name in GOOD:
                kwargs[field_name] = draw(GOOD[field_name])
            else:  # a parent: distinct ones, all placed before
                kwargs[field_name] = next(parents)
        if draw(st.integers(0, 6)) == 0:
            kwargs[draw(st.sampled_from(names))] = draw(junk)
        joints.append(cls(**kwargs))
        placed.append(f"J{i}")
    return joints


@settings(max_examples=200, deadline=None)
@given(random_sphere_joints())
def test_fuzz_spherical_linkages_only_raise_invalid_linkage(joints):
    try:
        mech = Linkage(joints=[O, Q, A, *joints], space="sphere")
    except InvalidLinkage:
        return
    with np.errstate(all="ignore"):
        motion = solve(mech, INPUTS[:6])
        residual = mech.residuals(motion)
    assert set(motion.positions) == set(mech.reported_joints)
    for r in residual.values():
        assert np.all(np.isnan(r) | (np.abs(r) < 1e-9))
    # Wherever assembled, every joint is on the unit sphere.
    for p in motion.positions.values():
        assert np.all(np.isnan(p) | (np.abs(np.linalg.norm(p, axis=-1) - 1) < 1e-12)[..., None])

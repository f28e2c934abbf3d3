"""The engine on the sphere: sphere primitives, spherical steps and their derivatives, limits.

Independent references: the input–output equation of the spherical four-bar (paper 000, eq. 5,
printed closed form), implicit differentiation of the constraint A(θ)·B(φ3) = cos a3 for the
rates, central differences of positions for every joint's derivatives, and the closed-form
arc-cosine limits of a four-bar whose arc A B0 is linear in cos θ.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine import Fixed, Plan, SphereCrank, SphereRigid, evaluate
from linkwright.geometry import sphere
from linkwright.mechanisms import (
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    circuit,
    input_range,
    solve,
)
from linkwright.mechanisms.base import InvalidMechanism

DEG = np.pi / 180.0
arcs = st.floats(5.0, 175.0).map(lambda d: d * DEG)
angles = st.floats(-180.0, 180.0).map(lambda d: d * DEG)
signs = st.sampled_from([1.0, -1.0])


def unit_vectors(n: int, rng: np.random.Generator) -> np.ndarray:
    return sphere.unit(rng.normal(size=(n, 3)))


# --------------------------------------------------------------------------------------------
# Primitives
# --------------------------------------------------------------------------------------------


def test_point_at_and_angle_at_are_inverse():
    rng = np.random.default_rng(0)
    o, t = unit_vectors(500, rng), unit_vectors(500, rng)
    length = rng.uniform(0.01, np.pi - 0.01, 500)
    angle = rng.uniform(-np.pi, np.pi, 500)
    p = sphere.point_at(o, t, length, angle)
    assert np.allclose(sphere.norm(p), 1.0, atol=1e-15)
    assert np.allclose(sphere.arc(o, p), length, atol=1e-13)
    assert np.allclose(np.angle(np.exp(1j * (sphere.angle_at(o, t, p) - angle))), 0, atol=1e-12)


def test_point_at_is_paper000_rotation_of_the_great_circle():
    """Paper 000: rotate B about OA by μ (its matrix T, eq. 6), then walk AC along A→B'."""
    rng = np.random.default_rng(1)
    a, b = unit_vectors(300, rng), unit_vectors(300, rng)
    ac, mu = rng.uniform(0.1, 3.0, 300), rng.uniform(-3.0, 3.0, 300)
    b_turned = sphere.rotate(b, a, mu)
    walked = sphere.point_at(a, b_turned, ac, 0.0)
    assert np.max(np.abs(walked - sphere.point_at(a, b, ac, mu))) < 1e-14


def test_gram_matches_determinant():
    rng = np.random.default_rng(2)
    u, v, w = (unit_vectors(400, rng) for _ in range(3))
    det = np.linalg.det(np.stack((u, v, w), axis=-2))
    g = sphere.gram(sphere.arc(u, v), sphere.arc(u, w), sphere.arc(v, w))
    assert np.allclose(g, det**2, atol=1e-14)


def test_solve_3x3_rows_matches_numpy():
    rng = np.random.default_rng(3)
    rows = rng.normal(size=(200, 3, 3))
    rhs = rng.normal(size=(200, 3))
    x, det = sphere.solve_3x3_rows(
        rows[:, 0], rows[:, 1], rows[:, 2], rhs[:, 0], rhs[:, 1], rhs[:, 2]
    )
    assert np.allclose(x, np.linalg.solve(rows, rhs[..., None])[..., 0], atol=1e-9)
    assert np.allclose(det, np.linalg.det(rows))


# --------------------------------------------------------------------------------------------
# The spherical four-bar
# --------------------------------------------------------------------------------------------


def eq5_output(a1, a2, a3, a4, theta):
    """Paper 000's eq. 5 (McCarthy): θ4 in the mode of the printed minus sign."""
    p = np.sin(a2) * np.sin(a4) * np.sin(theta)
    q = np.sin(a2) * np.sin(a4) * np.cos(a1) * np.cos(theta) - np.cos(a2) * np.sin(a4) * np.sin(a1)
    u = (
        np.cos(a3)
        - np.cos(a1) * np.cos(a2) * np.cos(a4)
        - np.sin(a2) * np.cos(a4) * np.sin(a1) * np.cos(theta)
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        return 2.0 * np.arctan((p - np.sqrt(p * p - u * u + q * q)) / (q + u))


@settings(max_examples=60)
@given(arcs, arcs, arcs, arcs, arcs, angles, signs)
def test_fourbar_constraints_and_eq5(a1, a2, a3, a4, pa, pu, sign):
    mech = SphericalFourBar(a1, a2, a3, a4, pa, pu, sign)
    theta = np.linspace(-np.pi, np.pi, 73)
    m = solve(mech, theta)
    assume(m.valid.any())
    for name, err in mech.residuals(m).items():
        assert np.nanmax(np.abs(err)) < 1e-12, name
    # The branch really is the sign of (A × B0)·B, as documented.
    A, B, B0 = (m.positions[k][m.valid] for k in ("A", "B", "B0"))
    triple = sphere.dot(sphere.cross(A, B0), B)
    assert np.all((np.sign(triple) == sign) | (np.abs(triple) < 1e-9))
    # Where A can pass through ±B0 (a2 = a1 or a2 = 180° − a1) the sign of (A × B0)·B flips
    # with A × B0 while eq. 5's root stays put: there the two definitions of a mode part.
    through_b0 = min(abs(a1 - a2), abs(a1 + a2 - np.pi)) < DEG
    if sign == 1.0 and not through_b0 and not folds(a1, a2, a3, a4):
        ref = eq5_output(a1, a2, a3, a4, theta)
        phi3 = mech.output_angle(m)
        ok = m.valid & np.isfinite(ref) & (np.abs(triple_all(m)) > 1e-6)
        diff = np.angle(np.exp(1j * (phi3 - ref)))[ok]
        assert np.all(np.abs(diff) < 1e-9)


def folds(*a: float) -> bool:
    """A change-point linkage: some ±a1 ± a2 ± a3 ± a4 is 0 (mod 2π), within 1°.

    There all four axes can lie in one plane and the two assembly modes meet.
    """
    import itertools

    for s in itertools.product((1, -1), repeat=3):
        total = a[0] + s[0] * a[1] + s[1] * a[2] + s[2] * a[3]
        if abs(np.angle(np.exp(1j * total))) < DEG:
            return True
    return False


def triple_all(m):
    A, B, B0 = (m.positions[k] for k in ("A", "B", "B0"))
    return sphere.dot(sphere.cross(A, B0), B)


def central_difference(mech, theta, order, h):
    """8th-order central differences of every joint's position, step ``h`` per sample."""
    c1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    c2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])
    k = np.arange(-4, 5)
    stencil = solve(mech, theta[:, None] + k * h[:, None], order=0)
    coef = (c1 / h[:, None]) if order == 1 else (c2 / h[:, None] ** 2)
    return {name: np.einsum("nk,nkd->nd", coef, pos) for name, pos in stencil.positions.items()}


def stencil_ok(mech, motion, floor=0.02):
    """Samples whose whole stencil stays assembled, away from every dyad's limit (margin >
    ``floor``), with a step scaled down by the fastest joint's rate; returns (keep, h)."""
    speed = np.max([np.linalg.norm(v, axis=-1) for v in motion.velocities.values()], axis=0)
    h = 1e-3 / np.maximum(1.0, np.nan_to_num(speed, nan=1.0))
    theta = motion.input
    m = solve(mech, theta[:, None] + np.arange(-4, 5) * h[:, None], order=0)
    keep = m.valid.all(axis=-1) & motion.regular
    for margin in m.margins.values():
        keep &= np.all(margin > floor, axis=-1)
    # A dyad whose pivots nearly coincide places its joint only to eps / sin d, and differences
    # over a step shrunk for its fast motion turn that into noise far above 1e-6.
    for step in mech.plan.dyads:
        d = sphere.arc(m.positions[step.p1], m.positions[step.p2])
        keep &= np.all(np.sin(d) > 0.05, axis=-1)
    return keep, h


@settings(max_examples=40)
@given(arcs, arcs, arcs, arcs, arcs, angles, signs)
def test_fourbar_derivatives_match_differences(a1, a2, a3, a4, pa, pu, sign):
    mech = SphericalFourBar(a1, a2, a3, a4, pa, pu, sign)
    theta = np.linspace(-np.pi, np.pi, 37)
    m = solve(mech, theta)
    keep, h = stencil_ok(mech, m)
    assume(keep.any())
    for order, derivs, weight in ((1, m.velocities, 2.0), (2, m.accelerations, 6.05)):
        fd = central_difference(mech, theta, order, h)
        # The stencil's rounding: positions placed to ~1e-14 (margins > 0.02, pivots apart),
        # times the sum of its |weights| over h^order; h shrinks for fast joints, so this can
        # pass 1e-6 (seen: 5e-6 on accelerations with h ~ 3e-5).
        rounding = (1e-14 * weight / h[:, None] ** order)[keep]
        for name in ("A", "B", "P"):
            err = np.abs(fd[name] - derivs[name])[keep]
            # The stencil's truncation error is a vector's (its higher derivatives'), so each
            # component is held to the whole vector's size: a small component of a large
            # acceleration carries the same absolute error (seen: 1.5e-6 on a component of
            # 1.3 where the vector was 115).
            size = np.linalg.norm(derivs[name][keep], axis=-1, keepdims=True)
            assert np.all(err <= 1e-6 * (1.0 + size) + rounding), (name, order, err.max())


@settings(max_examples=40)
@given(arcs, arcs, arcs, arcs, signs)
def test_output_rate_matches_implicit_differentiation(a1, a2, a3, a4, sign):
    """φ3′ = −F_θ / F_φ3 for F = A(θ)·B(φ3) − cos a3, an independent closed form."""
    mech = SphericalFourBar(a1, a2, a3, a4, assembly=sign)
    theta = np.linspace(-np.pi, np.pi, 41)
    m = solve(mech, theta)
    keep = m.regular & np.all([v > 1e-3 for v in m.margins.values()], axis=0)
    assume(keep.any())
    A, B, B0 = m.positions["A"], m.positions["B"], m.positions["B0"]
    dA = m.velocities["A"]
    # B turns about B0: dB/dφ3 = B0 × B.
    f_theta = sphere.dot(dA, B)
    f_phi = sphere.dot(A, sphere.cross(B0, B))
    rate = -f_theta / f_phi
    ours = sphere.dot(sphere.cross(B0, B), m.velocities["B"]) / np.sin(a4) ** 2
    assert np.allclose(ours[keep], rate[keep], rtol=1e-9, atol=1e-12)


@settings(max_examples=60)
@given(arcs, arcs, arcs, arcs, signs)
def test_limits_match_closed_form(a1, a2, a3, a4, sign):
    """cos(arc A B0) = cos a1 cos a2 + sin a1 sin a2 cos θ; the dyad closes while that arc lies
    in [|a3 − a4|, min(a3 + a4, 2π − a3 − a4)]."""
    mech = SphericalFourBar(a1, a2, a3, a4, assembly=sign)
    arcs_ = input_range(mech)
    lo_d, hi_d = abs(a3 - a4), min(a3 + a4, 2 * np.pi - a3 - a4)
    d_min, d_max = abs(a1 - a2), min(a1 + a2, 2 * np.pi - a1 - a2)
    margin = 1e-7
    assume(all(abs(x - y) > margin for x in (lo_d, hi_d) for y in (d_min, d_max)))
    never = d_max < lo_d or d_min > hi_d
    full = d_min > lo_d and d_max < hi_d
    assert bool(arcs_.never) == never
    assert bool(arcs_.full) == full
    if never or full:
        return
    for lo, hi in zip(arcs_.lo, arcs_.hi, strict=True):
        if not np.isfinite(lo):
            continue
        for t in (lo, hi):
            d = np.arccos(np.cos(a1) * np.cos(a2) + np.sin(a1) * np.sin(a2) * np.cos(t))
            assert min(abs(d - lo_d), abs(d - hi_d)) < 1e-9


def test_circuit_of_a_rocker_switches_branch_at_its_limits():
    mech = SphericalFourBar(*np.radians([30.0, 60.0, 20.0, 30.0]))
    assert not input_range(mech).full
    c = circuit(mech, 200)
    assert c.valid.all()
    assert set(np.unique(c.branches["B"])) == {-1.0, 1.0}
    # Closed: the last sample is one step from the first.
    step = np.max(sphere.norm(np.diff(c.positions["P"], axis=0)))
    assert sphere.norm(c.positions["B"][-1] - c.positions["B"][0]) < 3 * step + 1e-12


def test_invalid_arcs_are_named():
    with pytest.raises(InvalidMechanism, match=r"crank.*between 0° and 180°"):
        SphericalFourBar(1.0, np.pi, 1.0, 1.0)
    with pytest.raises(InvalidMechanism, match="rocker"):
        SphericalFourBar(1.0, 1.0, 1.0, 0.0)


def test_never_assembles_gives_masked_nan():
    mech = SphericalFourBar(*np.radians([90.0, 10.0, 20.0, 30.0]))
    m = solve(mech, np.linspace(0, 6, 7))
    assert not m.valid.any()
    assert np.isnan(m.positions["P"]).all()
    assert bool(input_range(mech).never)


def test_plans_do_not_mix_spaces():
    from linkwright.engine import Crank

    with pytest.raises(ValueError, match="either in the plane or on the sphere"):
        Plan(
            (Fixed("O", "O"), Crank("A", "O", 1.0), SphereRigid("P", "O", "A", 0.1, 0.0)),
            traced=("P",),
        )
    with pytest.raises(ValueError, match="not a ground pivot"):
        Plan(
            (
                Fixed("O", "O"),
                SphereCrank("A", "O", 0.5, ref="r"),
                SphereCrank("B", "A", 0.5, ref="r"),
            ),
            traced=("B",),
        )


# --------------------------------------------------------------------------------------------
# Six-bars
# --------------------------------------------------------------------------------------------


@settings(max_examples=40)
@given(
    st.lists(arcs, min_size=7, max_size=7),
    st.lists(angles, min_size=3, max_size=3),
    arcs,
    signs,
    signs,
)
def test_sixbar_constraints_and_derivatives(a, angs, d_arc, s1, s2):
    frame, crank, coupler, rocker, point_arc, link5, link6 = a
    mech = SphericalSixBar(
        frame,
        crank,
        coupler,
        rocker,
        point_arc,
        angs[2],
        link5,
        link6,
        ground_arc=point_arc,
        ground_angle=angs[0],
        d_arc=d_arc,
        d_angle=angs[1],
        assembly=s1,
        assembly2=s2,
    )
    theta = np.linspace(-np.pi, np.pi, 37)
    m = solve(mech, theta)
    assume(m.valid.any())
    for name, err in mech.residuals(m).items():
        assert np.nanmax(np.abs(err)) < 1e-12, name
    keep, h = stencil_ok(mech, m)
    if keep.any():
        fd = central_difference(mech, theta, 1, h)
        for name in ("E", "D"):
            err = np.abs(fd[name] - m.velocities[name])[keep]
            assert np.all(err <= 1e-6 * (1 + np.abs(m.velocities[name][keep]))), name


@settings(max_examples=40)
@given(st.lists(arcs, min_size=8, max_size=8), angles, signs, signs)
def test_stephenson3_constraints(a, sigma, s1, s2):
    a1, a2, a3, a4, a6, a7, a8, a9 = a
    assume(a1 + a9 < 2 * np.pi)
    mech = SphericalStephenson3(a1, a2, a3, a4, a6, sigma, a7, a8, a9, s1, s2)
    m = solve(mech, np.linspace(-np.pi, np.pi, 37))
    assume(m.valid.any())
    for name, err in mech.residuals(m).items():
        assert np.nanmax(np.abs(err)) < 1e-12, name
    # Paper 001's eq. 3 and eq. 5 (B), eq. 8 corrected (G beyond D).
    B, E, G, D = (m.positions[k] for k in ("B", "E", "G", "D"))
    want = np.cos(a3) * np.cos(a6) - np.sin(a3) * np.sin(a6) * np.cos(sigma)
    assert np.nanmax(np.abs(sphere.dot(B, E) - want)) < 1e-12
    theta = m.input
    eq5 = np.stack(
        (np.sin(a2) * np.sin(theta), np.sin(a2) * np.cos(theta), np.cos(a2) + 0 * theta), -1
    )
    assert np.nanmax(np.abs(B - eq5)) < 1e-15
    assert np.allclose(sphere.arc(D, G)[m.valid], a9)


def test_stephenson3_input_word():
    with pytest.raises(InvalidMechanism, match="input"):
        SphericalStephenson3(*np.radians([60, 20, 50, 40, 40, 100, 50, 45, 30]), input="CD")


def test_rigid_step_derivatives_are_exact_on_a_rotating_body():
    """A body turning at unit rate about a fixed axis: every rigid point has v = ω × X."""
    axis = sphere.unit([0.3, -0.2, 0.9])
    ref = np.array([1.0, 0.0, 0.0])
    plan = Plan(
        (
            Fixed("O", "O"),
            SphereCrank("A", "O", 0.7, ref="r"),
            SphereRigid("P", "O", "A", 1.1, 0.4),
        ),
        traced=("P",),
    )
    params = {"O": axis, "r": ref}
    m = evaluate(plan, params, np.linspace(0, 6, 25), points=frozenset({"O", "r"}))
    p = m.positions["P"]
    assert np.allclose(m.velocities["P"], sphere.cross(axis, p), atol=1e-15)
    assert np.allclose(m.accelerations["P"], sphere.cross(axis, sphere.cross(axis, p)), atol=1e-15)


def test_dyad_with_pivots_one_ulp_apart_still_meets_both_arcs():
    """A change point whose crank passes through B0: at θ = 0 the pivots A and B0 differ only by
    rounding, the direction between them is noise, and B must still lie on both circles."""
    r5 = np.radians(5.0)
    below = np.nextafter(r5, 0.0)
    mech = SphericalFourBar(below, r5, below, below)
    m = solve(mech, [0.0, 1e-9, 0.1])
    assert m.valid.all()
    for name, err in mech.residuals(m).items():
        assert np.max(np.abs(err)) < 1e-12, name

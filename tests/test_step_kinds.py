"""Circle ∩ circle written once, and what each step kind owns: closure, residual, sentences.

Independent references: the law-of-cosines construction of a triangle (circle ∩ circle), the
quadratic of a line's parameter (circle ∩ line), a Newton solve of the three constraint
equations on the sphere (small circle ∩ small circle), sin² of the angle at a dyad's first
pivot measured on the placed joint (its closure), the closed-form limit positions of
:func:`~linkwright.engine.input_arcs` (where the closure vanishes), and displacements of a joint
whose effect on each constraint is known exactly (the residuals).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES, INPUT_EXAMPLES
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Trammel,
    input_arcs,
)
from linkwright.engine.evaluate import place_all
from linkwright.engine.state import ASSEMBLY_TOL, param_value
from linkwright.engine.triad_steps import PlaneTriadKind, SphereTriad, SphereTriadKind, Triad
from linkwright.geometry import plane, sphere
from linkwright.io import load_example
from linkwright.mechanisms import FourBar, SliderCrank, solve
from linkwright.mechanisms.base import InvalidMechanism

EPS = float(np.finfo(float).eps)
ALL_KINDS = (
    Fixed,
    Crank,
    SphereCrank,
    DyadRRR,
    DyadRRP,
    SphereDyad,
    Rigid,
    SphereRigid,
    Trammel,
    Triad,
    SphereTriad,
)
EXAMPLES = {**FAMILY_EXAMPLES, **INPUT_EXAMPLES}

coord = st.floats(-10.0, 10.0)
radius = st.floats(0.1, 10.0)
sign = st.sampled_from([1.0, -1.0])


# --------------------------------------------------------------------------------------------
# Circle ∩ circle, circle ∩ line, small circle ∩ small circle
# --------------------------------------------------------------------------------------------


@settings(max_examples=300)
@given(coord, coord, coord, coord, radius, radius, sign)
def test_circle_circle_is_the_law_of_cosines_triangle(x1, y1, x2, y2, r1, r2, branch):
    p1, p2 = np.array([x1, y1]), np.array([x2, y2])
    d = math.hypot(x2 - x1, y2 - y1)
    assume(d > 0.1)
    meet = plane.circle_circle(p1, r1, p2, r2, branch)
    scale = max(r1, r2, d)
    if d > r1 + r2 + 1e-9 * scale or d < abs(r1 - r2) - 1e-9 * scale:
        assert not meet.valid and np.isnan(meet.point).all() and meet.margin < 0
        return
    cos_b = (r1 * r1 + d * d - r2 * r2) / (2.0 * r1 * d)
    assume(abs(cos_b) < 1.0 - 1e-6)  # off a tangency, where the angle is well conditioned
    sin_b = math.sqrt(1.0 - cos_b * cos_b)
    alpha = math.atan2(y2 - y1, x2 - x1) + branch * math.acos(cos_b)
    want = p1 + r1 * np.array([math.cos(alpha), math.sin(alpha)])
    # Rounding of the law of cosines: cos β to 4ε of its terms, β to that over sin β.
    d_cos = 4.0 * EPS * (r1 * r1 + d * d + r2 * r2) / (2.0 * r1 * d)
    tol = r1 * d_cos / sin_b + 8.0 * EPS * (np.abs(p1).max() + scale)
    assert bool(meet.valid)
    np.testing.assert_allclose(meet.point, want, rtol=0, atol=tol)
    np.testing.assert_allclose(meet.margin, sin_b * sin_b, rtol=0, atol=4.0 * d_cos + 1e-15)
    assert np.sign(plane.cross(p2 - p1, meet.point - p1)) == branch


@pytest.mark.parametrize("offset", [0.0, 1e6, -3.5e7])
def test_circle_circle_keeps_its_digits_where_the_circles_touch(offset):
    o = np.array([offset, offset])
    outer = plane.circle_circle(o, 3.0, o + [5.0, 0.0], 2.0, 1.0)  # touching from outside
    inner = plane.circle_circle(o, 5.0, o + [2.0, 0.0], 3.0, -1.0)  # touching from inside
    for meet, at in ((outer, [3.0, 0.0]), (inner, [5.0, 0.0])):
        assert bool(meet.valid) and meet.margin == 0.0
        np.testing.assert_array_equal(meet.point, o + at)
    # Equal radii: r1² − r2² is exactly 0, so the point stays on the bisector however close
    # the centres come.
    tiny = plane.circle_circle([0.0, 0.0], 1.0, [1e-9, 0.0], 1.0, 1.0)
    assert tiny.point[0] == 5e-10 and abs(plane.norm(tiny.point) - 1.0) <= EPS


@settings(max_examples=300)
@given(coord, coord, coord, coord, st.floats(-math.pi, math.pi), radius, sign)
def test_circle_line_solves_the_lines_quadratic(cx, cy, lx, ly, angle, r, branch):
    c, lp = np.array([cx, cy]), np.array([lx, ly])
    d = plane.unit_direction(angle)
    meet = plane.circle_line(c, r, lp, d, branch)
    # |L + t·d − c|² = r²: t² + 2bt + k = 0.
    b = float(np.dot(lp - c, d))
    k = float(np.dot(lp - c, lp - c)) - r * r
    disc = b * b - k
    scale = max(r, float(np.abs(lp - c).max()))
    if disc < -1e-9 * scale * scale:
        assert not meet.valid
        return
    assume(disc > 1e-6 * scale * scale)
    t = -b + branch * math.sqrt(disc)
    tol = 16.0 * EPS * scale * scale / math.sqrt(disc) + 8.0 * EPS * (np.abs(lp).max() + scale)
    np.testing.assert_allclose(meet.point, lp + t * d, rtol=0, atol=tol)
    foot = lp + np.dot(c - lp, d) * d
    assert np.sign(np.dot(meet.point - foot, d)) == branch


def _newton_on_sphere(p1, r1, p2, r2, rng):
    """A point X with X·p1 = cos r1, X·p2 = cos r2, |X| = 1, by Newton from random starts."""
    for _ in range(20):
        x = sphere.unit(rng.normal(size=3))
        for _ in range(60):
            f = np.array([x @ p1 - math.cos(r1), x @ p2 - math.cos(r2), 0.5 * (x @ x - 1.0)])
            jac = np.array([p1, p2, x])
            try:
                x = x - np.linalg.solve(jac, f)
            except np.linalg.LinAlgError:
                break
        f = np.array([x @ p1 - math.cos(r1), x @ p2 - math.cos(r2), 0.5 * (x @ x - 1.0)])
        if np.all(np.isfinite(x)) and np.abs(f).max() < 1e-15:
            return x
    return None


unit3 = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
    lambda v: math.hypot(*v) > 0.1
)
arc = st.floats(0.05, math.pi - 0.05)


@settings(max_examples=150)
@given(unit3, unit3, arc, arc, sign, st.integers(0, 2**32 - 1))
def test_small_circles_agree_with_a_newton_solve_on_the_sphere(u, v, r1, r2, branch, seed):
    p1, p2 = sphere.unit(np.array(u)), sphere.unit(np.array(v))
    d = float(sphere.arc(p1, p2))
    assume(0.05 < d < math.pi - 0.05)
    meet = sphere.small_circles(p1, r1, p2, r2, branch)
    reach = min(r1 + r2, 2.0 * math.pi - r1 - r2)
    if d > reach + 1e-9 or d < abs(r1 - r2) - 1e-9:
        assert not meet.valid
        return
    assume(float(meet.margin) > 1e-3)  # off a tangency: the reference is well conditioned
    x = _newton_on_sphere(p1, r1, p2, r2, np.random.default_rng(seed))
    assert x is not None
    w = sphere.cross(p1, p2)
    if np.sign(w @ x) != branch:  # the other solution is its mirror in the plane of p1, p2
        n = w / np.linalg.norm(w)
        x = x - 2.0 * (x @ n) * n
    np.testing.assert_allclose(meet.point, x, rtol=0, atol=1e-12)


def test_small_circles_stay_on_the_sphere_for_nearly_parallel_axes():
    """The sweep's copy of the spherical dyad built its frame from (p2 − cos d·p1)/sin d and
    put X up to 6e-3 off the unit sphere for axes 1e-14 to 1e-8 apart; the one construction
    (from (p1 × p2) × p1) keeps X a unit vector on both arcs."""
    rng = np.random.default_rng(1)
    n = 2000
    p1 = sphere.unit(rng.normal(size=(n, 3)))
    axis = sphere.unit(np.cross(p1, rng.normal(size=(n, 3))))
    tiny = 10.0 ** rng.uniform(-14, -8, n)
    p2 = sphere.rotate(p1, axis, tiny)
    r1 = rng.uniform(0.2, 2.9, n)
    r2 = r1 + tiny * rng.uniform(-0.5, 0.5, n)  # arcs that let the circles meet
    meet = sphere.small_circles(p1, r1, p2, r2, 1.0)
    assert meet.valid.all()
    assert np.abs(sphere.norm(meet.point) - 1.0).max() <= 2 * EPS
    assert np.abs(sphere.arc(p1, meet.point) - r1).max() <= 4 * EPS
    assert np.abs(sphere.arc(p2, meet.point) - r2).max() <= 1e-7  # rounding of p2 itself


def test_circle_frame_and_on_circle_are_point_at():
    rng = np.random.default_rng(2)
    o, toward = sphere.unit(rng.normal(size=(2, 400, 3)))
    length, angle = rng.uniform(0.01, 3.1, 400), rng.uniform(-3.1, 3.1, 400)
    frame = sphere.circle_frame(o, toward)
    assert np.abs(np.einsum("...ik,...jk->...ij", frame, frame) - np.eye(3)).max() < 16 * EPS
    np.testing.assert_array_equal(
        sphere.on_circle(frame, length, angle), sphere.point_at(o, toward, length, angle)
    )


# --------------------------------------------------------------------------------------------
# Every step kind owns its closure, residual and sentences
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ALL_KINDS, ids=lambda k: k.__name__)
def test_every_step_kind_answers_for_itself(kind):
    for method in ("place", "closure", "residual", "unassembled"):
        assert callable(getattr(kind, method, None)), f"{kind.__name__}.{method}"
    assert isinstance(kind.title, property)
    limits = kind in (DyadRRR, DyadRRP, SphereDyad, Triad, SphereTriad)
    assert callable(getattr(kind, "at_limit", None)) == limits


def _example_steps():
    """Every step of every bundled example, with its mechanism."""
    for key, name in EXAMPLES.items():
        mech = load_example(name).mechanism
        for step in mech.plan.steps:
            yield pytest.param(mech, step, id=f"{key}-{type(step).__name__}-{step.name}")


def _solved(mech, samples=12):
    theta = np.linspace(0.1, 2 * np.pi + 0.1, samples, endpoint=False)
    motion = solve(mech, theta, order=0)
    assert motion.valid.any()
    return motion, mech.params()


def _displaced(step, positions, params, delta):
    """The positions with one joint of ``step`` moved so that exactly ``delta`` of error
    appears in one of its constraints (and no larger one)."""
    out = dict(positions)
    if isinstance(step, PlaneTriadKind | SphereTriadKind):  # a triad, driven at a hinge or not
        name, centre = step.joints[0], step.anchors[0]
    elif isinstance(step, DyadRRR | DyadRRP | SphereDyad):
        name, centre = step.name, step.p1
    elif isinstance(step, Crank | SphereCrank):
        name, centre = step.name, step.pivot
    else:
        name, centre = step.name, None
    p = positions[name]
    if p.shape[-1] == 3:
        if centre is None:  # a rigid point on the sphere: turned about its own normal
            axis = sphere.unit(sphere.cross(p, np.array([0.3, -0.5, 0.8])))
        else:  # away from the centre along the great circle: its arc grows by delta
            axis = sphere.unit(sphere.cross(positions[centre], p))
        out[name] = sphere.rotate(p, axis, delta)
    elif isinstance(step, Trammel):
        normal = plane.perp(plane.unit_direction(param_value(step.angle1, params)))
        out[name] = p + delta * normal
    elif centre is None:
        out[name] = p + delta * np.array([0.6, -0.8])
    else:  # away from the centre: the link grows by delta
        away = p - positions[centre]
        out[name] = p + delta * away / plane.norm(away)[..., None]
    return out, name


@pytest.mark.parametrize(("mech", "step"), list(_example_steps()))
def test_residual_is_rounding_when_solved_and_sees_a_displacement(mech, step):
    motion, params = _solved(mech)
    ok = motion.valid
    theta = motion.input
    here = step.residual(motion.positions, params, theta)
    size = 1.0 if mech.plan.space == "sphere" else float(np.asarray(mech.scale))
    assert np.nanmax(here[ok]) / size < 1e-13
    delta = 1e-6 * size
    moved, name = _displaced(step, motion.positions, params, delta)
    seen = step.residual(moved, params, theta)[ok]
    if isinstance(step, Fixed):
        np.testing.assert_allclose(seen, delta, rtol=1e-9)
        return
    # The chosen displacement puts exactly delta into one constraint (a link, arc, guide or
    # frame); the residual is the largest error, so it sees at least that, to first order.
    assert np.all(seen >= delta * (1.0 - 1e-6)), (name, seen.min() / delta)
    # A step placing several joints (a triad, a driven hinge) couples its constraints: one
    # joint moved shows in several of them, by up to a link ratio, so only the floor holds.
    if not hasattr(step, "max_poses"):
        assert np.all(seen <= delta * (1.0 + 1e-6)), (name, seen.max() / delta)


# The kinds whose closure is sin² (cos² for a slider) of an angle seen on the placed joint.


def _angle_closure(step, positions, params):
    """The closure measured on the placed joint: sin² of the angle at P1 between P1→P2 and
    P1→P (plane, sphere), cos² of the rod's angle to its guide (slider)."""
    p = positions[step.name]
    if isinstance(step, DyadRRR):
        a, b = positions[step.p2] - positions[step.p1], p - positions[step.p1]
        return plane.cross(a, b) ** 2 / (plane.dot(a, a) * plane.dot(b, b))
    if isinstance(step, SphereDyad):
        return np.sin(sphere.angle_at(positions[step.p1], positions[step.p2], p)) ** 2
    d = plane.unit_direction(param_value(step.line_angle, params))
    rod = p - positions[step.p1]
    return plane.dot(rod, d) ** 2 / plane.dot(rod, rod)


@pytest.mark.parametrize("key", sorted(EXAMPLES))
def test_a_dyads_closure_is_the_angle_on_its_joint_and_its_sign_says_where_it_closes(key):
    mech = load_example(EXAMPLES[key]).mechanism
    theta = np.linspace(-np.pi, np.pi, 181)
    params = mech.params()
    _, states = place_all(mech.plan, params, theta, points=mech.points, order=0)
    positions = {k: s.pos for k, s in states.items()}
    for step in mech.plan.dyads:
        parents = np.logical_and.reduce([states[p].valid for p in step.parents])
        closure = step.closure(positions, params)
        valid = states[step.name].valid
        np.testing.assert_array_equal((closure >= -ASSEMBLY_TOL)[parents], valid[parents])
        placed = valid & parents
        want = _angle_closure(step, positions, params)
        np.testing.assert_allclose(closure[placed], want[placed], rtol=0, atol=1e-12)


@given(st.floats(0.2, 3.0), st.floats(0.2, 3.0), st.floats(0.2, 3.0), st.floats(0.2, 3.0), sign)
@settings(max_examples=60)
def test_a_dyads_closure_vanishes_at_the_limit_positions(crank, coupler, rocker, frame, branch):
    mech = FourBar(
        A0=[0, 0], B0=[frame, 0], crank=crank, coupler=coupler, rocker=rocker, assembly=branch
    )
    arcs = input_arcs(mech.plan, mech.params(), points=mech.points)
    assume(not bool(arcs.full) and not bool(arcs.never))
    ends = np.concatenate([arcs.lo, arcs.hi])
    ends = ends[np.isfinite(ends)]
    params = mech.params()
    _, states = place_all(mech.plan, params, ends, points=mech.points, order=0)
    positions = {k: s.pos for k, s in states.items()}
    closure = mech.plan.step("B").closure(positions, params)
    # A limit is a root of the closure sin²φ = outer·inner / (4 d² r1²) (d = |A B0|). Its
    # input is exact to an ulp, and A's coordinates to a few: d² is off by ~ε·d·size, and
    # the factor that vanishes carries that error, over d² r1².
    size = max(crank, coupler, rocker, frame)
    d = plane.norm(positions["B0"] - positions["A"])
    tol = 64.0 * EPS * size**4 / (d * d * coupler * coupler)
    assert np.all(np.abs(closure) <= tol), (closure, tol)


# --------------------------------------------------------------------------------------------
# The plan's residual: every family's check
# --------------------------------------------------------------------------------------------


def _perturbed(mech, rng):
    """The mechanism with every length, angle and point moved a little (the composed linkage,
    whose fields are its joints, as it is)."""
    changes = {}
    scale = float(np.asarray(mech.scale))
    for f in dataclasses.fields(mech):
        value = getattr(mech, f.name)
        if isinstance(value, str) or f.name.startswith("assembly") or f.name in ("pose", "ratio"):
            continue
        arr = np.asarray(value)
        if arr.dtype.kind != "f":
            continue
        if arr.shape == (2,):
            changes[f.name] = arr + 0.03 * scale * rng.uniform(-1, 1, 2)
        elif arr.shape == ():
            changes[f.name] = arr * (1.0 + 0.03 * rng.uniform(-1, 1))
    try:
        return dataclasses.replace(mech, **changes)
    except InvalidMechanism:
        return mech


@settings(max_examples=40)
@given(st.sampled_from(sorted(EXAMPLES)), st.integers(0, 2**32 - 1))
def test_the_plans_residual_checks_every_family(key, seed):
    rng = np.random.default_rng(seed)
    mech = _perturbed(load_example(EXAMPLES[key]).mechanism, rng)
    theta = rng.uniform(-np.pi, np.pi, 24)
    motion = solve(mech, theta, order=0)
    assume(motion.valid.any())
    params = mech.params()
    own = mech.plan.residuals(motion, params)
    assert np.all(np.isnan(own[~motion.valid]))
    assert np.nanmax(own) < 1e-10
    size = None if mech.plan.space == "sphere" else mech.scale
    plan = mech.plan.residuals(motion, params, size=size)
    family = np.max(np.abs(np.stack(list(mech.residuals(motion).values()))), axis=0)
    ok = motion.valid
    # Both are rounding of one set of constraints, measured two ways.
    np.testing.assert_allclose(plan[ok], family[ok], rtol=0, atol=1e-14)


def test_the_plans_residual_sees_a_joint_moved_off_its_constraints():
    # P = A (u = v = 0), so moving B changes no rigid point's error.
    mech = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3, u=0, v=0)
    motion, params = _solved(mech)
    b = motion.positions["B"]
    radial = (b - motion.positions["B0"]) / plane.norm(b - motion.positions["B0"])[..., None]
    moved = dataclasses.replace(motion, positions={**motion.positions, "B": b + 1e-7 * radial})
    size = float(np.asarray(mech.scale))
    found = mech.plan.residuals(moved, params, size=size)[motion.valid]
    np.testing.assert_allclose(found, 1e-7 / size, rtol=1e-6)


# --------------------------------------------------------------------------------------------
# The sentences
# --------------------------------------------------------------------------------------------


def _reason(mech, theta):
    return mech.plan.unassembled(mech.params(), theta, points=mech.points)


def test_a_dyad_says_why_it_cannot_close():
    far = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    assert _reason(far, 0.0) == (
        "the coupler and rocker cannot reach (dyad B: |A B0| = 9 > coupler + rocker = 5)"
    )
    short = FourBar(A0=[0, 0], B0=[1, 0], crank=0.5, coupler=6, rocker=1)
    assert _reason(short, 0.0) == (
        "the coupler and rocker cannot fold that short "
        "(dyad B: |A B0| = 0.5 < |coupler - rocker| = 5)"
    )
    assert _reason(far, math.pi) is not None
    assert _reason(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3), 0.0) is None
    slider = SliderCrank(A0=[0, 0], crank=1, rod=2, line_point=[0, 4])
    assert _reason(slider, 0.0) == (
        "the rod cannot reach the slider's line (dyad B: A is 4 from it > rod = 2)"
    )


def test_a_spherical_dyad_says_why_it_cannot_close():
    from linkwright.mechanisms import SphericalFourBar

    deg = np.radians
    far = SphericalFourBar(*deg([120.0, 20.0, 30.0, 40.0, 10.0, 0.0]))
    assert _reason(far, 0.0) == (
        "the coupler and rocker cannot reach (dyad B: arc AB0 = 100° > "
        "min(coupler + rocker, 360° - coupler - rocker) = 70°)"
    )


def test_a_triads_failure_is_explained_by_the_triad():
    """solve on a Stephenson III driven at its output named no step where the triad had no
    pose ("the triad cannot close"); the triad's own sentence names its links."""
    from linkwright.io.results import solve_document

    doc = load_example("stephenson3-output")
    mech = dataclasses.replace(doc.mechanism, rocker=np.float64(1.0))
    theta = np.radians(np.arange(0.0, 360.0, 10.0))
    bad = np.flatnonzero(~solve(mech, theta, order=0).valid)
    assert bad.size
    result = solve_document(
        dataclasses.replace(doc, mechanism=mech), [float(np.degrees(theta[bad[0]]))]
    )
    reason = result["samples"][0]["reason"]
    assert "the ternary link ABC cannot be held by its three links A0A, B0B and DC" in reason


def test_limit_sentences_come_from_the_step_kinds():
    fb = FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1)
    assert fb.plan.step("B").at_limit().startswith("dyad B: A–B and B–B0 fall in line")
    fg = load_example("paper001-fg").mechanism
    (triad,) = fg.plan.triads
    assert triad.at_limit().startswith(f"triad {''.join(triad.joints)}: two poses merge")
    assert triad.title == f"triad {''.join(triad.joints)}"


def test_a_sliders_branch_is_read_for_a_batch_of_guides():
    """``branch_of`` gave the guide's angle no axis for the samples, so a batch of slider-cranks
    with different guides raised a broadcasting error."""
    m = SliderCrank(
        A0=[0, 0], crank=1.0, rod=3.0, line_point=[0.0, 0.5], line_angle=[0.0, 0.3, -0.4]
    )
    motion = solve(m, np.linspace(0, 6, 5), order=0)
    got = m.plan.step("B").branch_of(motion.positions, m.params())
    np.testing.assert_array_equal(got, np.ones((3, 5)))


def test_a_plot_refused_at_an_input_says_which_step_fails():
    """The refusal gave the range where the linkage assembles but not why it does not at
    ``at``; the failing step's sentence now says so."""
    from linkwright.plot.view import PlotError, plot_mechanism

    rocking = FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1)
    with pytest.raises(PlotError) as info:
        plot_mechanism(rocking, at=math.pi)
    message = str(info.value)
    assert "does not assemble on its own assembly: the coupler and rocker cannot reach" in message
    assert "(dyad B: |A B0| = 7.5 > coupler + rocker = 6)" in message
    assert message.endswith("it does for θ in [−106.1°, −64.1°] and [64.1°, 106.1°]")

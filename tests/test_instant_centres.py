"""Instant centres and instantaneous axes (issue 24, point 6), checked against derivations that do
not share the library's: each body's turning rate from a finite difference of its angle (plane)
or of its orientation (sphere), the velocity field that rate implies at every point, the
Aronhold–Kennedy theorem for a four-bar's six centres and their construction by intersecting
lines (I13 = A0A ∩ B0B, I24 = A0B0 ∩ AB).

Tolerances are those the references can meet: a central difference of step h = 1e-5 is good to
about h²·|ω‴| + eps/h ≈ 1e-9 of the rates; a centre met by two lines at an angle α, or found
from a rate ω near zero, carries an error that grows like eps·D²/(L·sin μ) (D its distance, L
the linkage's size, μ the transmission angle, whose sine conditions the engine's derivatives),
so the four-bar checks are scaled by exactly that.
"""

from __future__ import annotations

import math
from itertools import combinations
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import linkwright as lw
from linkwright.analysis import instant_centres, rigid_bodies
from linkwright.analysis.instant_centres import FAR
from linkwright.engine.evaluate import evaluate
from linkwright.geometry import plane, sphere
from linkwright.io import list_examples, load_example
from linkwright.mechanisms import FourBar, SliderCrank, circuits, input_range, solve

H = 1e-5
PLANE_EXAMPLES = [n for n in list_examples() if load_example(n).mechanism.plan.space == "plane"]
SPHERE_EXAMPLES = [n for n in list_examples() if n not in PLANE_EXAMPLES]


def _shifted(mech: Any, motion: Any, dt: float) -> Any:
    """The motion at inputs shifted by ``dt`` on the same branches (NaN past a limit)."""
    return evaluate(
        mech.plan,
        mech.params(),
        motion.input + dt,
        points=mech.points,
        branches=motion.branches or None,
        order=0,
    )


def _planar_rate(mech: Any, motion: Any, joints: tuple[str, ...]) -> np.ndarray:
    """dφ/dθ of a body's angle φ (the direction from its first joint to its farthest one), by a
    central difference of the angle itself; NaN where the difference is not trustworthy (near a
    limit position, where the rate blows up): there steps h and 2h disagree beyond 1e-7."""
    p = motion.positions
    far = max(joints[1:], key=lambda j: float(np.nanmean(plane.norm(p[j] - p[joints[0]]))))

    def angle(m: Any) -> np.ndarray:
        d = m.positions[far] - m.positions[joints[0]]
        return np.arctan2(d[..., 1], d[..., 0])

    def rate(h: float) -> np.ndarray:
        up, down = _shifted(mech, motion, h), _shifted(mech, motion, -h)
        return np.angle(np.exp(1j * (angle(up) - angle(down)))) / (2 * h)

    fine, coarse = rate(H), rate(2 * H)
    scale = max(1.0, float(np.nanmax(np.abs(fine))))
    return np.where(np.abs(fine - coarse) <= 1e-7 * scale, fine, np.nan)


def _orientation(m: Any, joints: tuple[str, ...]) -> np.ndarray:
    """A body's orientation on the sphere: the rotation whose columns are the frame of two of
    its joints (unit vectors)."""
    a, b = m.positions[joints[0]], m.positions[joints[1]]
    e2 = sphere.unit(b - sphere.dot(a, b)[..., None] * a)
    return np.stack((a, e2, sphere.cross(a, e2)), axis=-1)


def _spherical_rate(mech: Any, motion: Any, joints: tuple[str, ...]) -> np.ndarray:
    """The angular velocity vector by θ: the axial vector of Ṙ·Rᵀ, Ṙ by central difference
    (NaN where steps h and 2h disagree beyond 1e-7, as in :func:`_planar_rate`)."""
    r = _orientation(motion, joints)

    def rate(h: float) -> np.ndarray:
        rdot = (
            _orientation(_shifted(mech, motion, h), joints)
            - _orientation(_shifted(mech, motion, -h), joints)
        ) / (2 * h)
        w = rdot @ np.swapaxes(r, -1, -2)
        return np.stack((w[..., 2, 1], w[..., 0, 2], w[..., 1, 0]), axis=-1)

    fine, coarse = rate(H), rate(2 * H)
    scale = max(1.0, float(np.nanmax(np.abs(fine))))
    good = (np.abs(fine - coarse) <= 1e-7 * scale).all(axis=-1)
    return np.where(good[..., None], fine, np.nan)


# ---------------------------------------------------------------------------------------------
# Bodies


@pytest.mark.parametrize("name", list_examples())
def test_bodies_are_rigid_and_hold_every_link(name: str) -> None:
    mech = load_example(name).mechanism
    bodies = rigid_bodies(mech)
    motion = circuits(mech, 48, order=0)[1][0]
    p = motion.positions
    size = max(
        float(np.nanmax(np.linalg.norm(v - p[mech.plan.joints[0]], axis=-1))) for v in p.values()
    )
    for body in bodies[1:]:
        # Every two joints of a body keep their distance as the linkage runs.
        for a, b in combinations(body.joints, 2):
            d = np.linalg.norm(p[a] - p[b], axis=-1)
            assert np.nanmax(d) - np.nanmin(d) <= 1e-9 * size, (body.name, a, b)
    # Every link the plan draws joins two joints of one body (or of the frame).
    for a, b in mech.plan.links:
        assert any({a, b} <= set(body.joints) for body in bodies), (a, b)


def test_jansen_legs_triangles_are_one_body_each() -> None:
    names = [b.name for b in rigid_bodies(load_example("jansen-leg").mechanism)]
    assert "B–C–D" in names and "E–F–G" in names
    assert len(names) == 8  # the frame, the crank, two triangles and four binary links


# ---------------------------------------------------------------------------------------------
# Plane: every point moves about its centre


@pytest.mark.parametrize("name", PLANE_EXAMPLES)
def test_every_point_turns_about_its_centre_relative_to_the_frame(name: str) -> None:
    mech = load_example(name).mechanism
    for motion in circuits(mech, 60, order=1)[1]:
        ic = instant_centres(mech, motion, pairs="frame")
        fastest = max(float(np.nanmax(plane.norm(v))) for v in motion.velocities.values())
        for k, (_, j) in enumerate(ic.pairs):
            body = ic.bodies[j]
            centre, direction = ic.centre[:, k], ic.direction[:, k]
            for joint in body.joints:
                v = motion.velocities[joint]
                if body.block or len(body.joints) < 2:
                    # A block translates: its centre is at infinity, square to its velocity.
                    if body.block:
                        moving = plane.norm(v) > 1e-9 * fastest
                        assert np.isnan(centre[moving]).all()
                        assert np.allclose(
                            plane.dot(direction[moving], v[moving]), 0, atol=1e-12 * fastest
                        )
                    continue
                rate = _planar_rate(mech, motion, body.joints)
                ok = np.isfinite(centre).all(axis=-1) & np.isfinite(rate) & ic.valid
                assert ok.sum() >= len(ok) // 2, (name, body.name)
                predicted = rate[:, None] * plane.perp(motion.positions[joint] - centre)
                err = np.abs(predicted - v)[ok].max()
                assert err <= 1e-6 * fastest, (name, body.name, joint, err)
            # ω itself is the body's turning rate.
            if not body.block and len(body.joints) >= 2:
                rate = _planar_rate(mech, motion, body.joints)
                ok = np.isfinite(rate) & ic.valid
                assert np.allclose(
                    ic.omega[ok, k], rate[ok], atol=1e-6 * max(1.0, np.abs(rate[ok]).max())
                )


@pytest.mark.parametrize("name", ["crank-rocker", "slider-crank", "watt1-example", "jansen-leg"])
def test_two_bodies_move_alike_at_their_relative_centre(name: str) -> None:
    mech = load_example(name).mechanism
    motion = circuits(mech, 36, order=1)[1][0]
    ic = instant_centres(mech, motion)
    fastest = max(float(np.nanmax(plane.norm(v))) for v in motion.velocities.values())

    def velocity_at(j: int, point: np.ndarray) -> np.ndarray:
        # Body j's velocity field, from one of its joints' engine velocity and its rate by
        # finite differences (a block and the frame do not turn).
        body = ic.bodies[j]
        if j == 0:
            return np.zeros_like(point)
        ref = body.joints[0]
        rate = np.zeros(len(point)) if body.block else _planar_rate(mech, motion, body.joints)
        return motion.velocities[ref] + rate[:, None] * plane.perp(point - motion.positions[ref])

    checked = 0
    for k, (i, j) in enumerate(ic.pairs):
        centre = ic.centre[:, k]
        ok = np.isfinite(centre).all(axis=-1)
        # Far centres magnify the rates' difference error; the near ones say it all.
        ok &= plane.norm(centre - motion.positions[mech.plan.joints[0]]) < 50 * fastest
        if not ok.any():
            continue
        diff = velocity_at(i, centre) - velocity_at(j, centre)
        assert np.abs(diff[ok]).max() <= 1e-6 * fastest, (name, ic.labels[k])
        checked += 1
    assert checked >= len(ic.pairs) // 2


# ---------------------------------------------------------------------------------------------
# Four-bars: Aronhold–Kennedy, and the construction by lines


def _meet(p: np.ndarray, d: np.ndarray, q: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Where the line through p along d meets the line through q along e."""
    with np.errstate(divide="ignore", invalid="ignore"):  # parallel: no point
        return p + plane.cross(q - p, e) / plane.cross(d, e) * d


def _check_fourbar(fb: FourBar, theta: float) -> bool:
    """Kennedy's theorem and the construction for one four-bar at one input; False where it is
    not assembled (or at a singular position) there."""
    motion = solve(fb, [theta], order=1)
    if not bool(motion.valid[0] and motion.regular[0]):
        return False
    ic = instant_centres(fb, motion)
    p = {k: v[0] for k, v in motion.positions.items()}
    assert [b.name for b in ic.bodies] == ["frame", "A0–A", "A–B–P", "B0–B"]
    size = max(
        float(plane.norm(p[a] - p[b]))
        for a, b in (("A0", "B0"), ("A0", "A"), ("A", "B"), ("B0", "B"))
    )
    # The sine of the transmission angle conditions the engine's derivatives.
    sin_mu = abs(float(plane.cross(p["B"] - p["A"], p["B"] - p["B0"]))) / (
        float(fb.coupler) * float(fb.rocker)
    )
    centres = {pair: (ic.centre[0, k], ic.direction[0, k]) for k, pair in enumerate(ic.pairs)}
    # The four primary centres are the pins, exactly.
    for pair, joint in (((0, 1), "A0"), ((1, 2), "A"), ((2, 3), "B"), ((0, 3), "B0")):
        assert np.array_equal(centres[pair][0], p[joint])
    far = max([float(plane.norm(c)) for c, _ in centres.values() if np.isfinite(c).all()] + [size])
    # How far a centre may be off (module docstring), and a direction's angle.
    off = 1e-10 * far * far / size / sin_mu
    # A centre beyond FAR sizes is reported at infinity: its direction is off by up to 1/FAR.
    turn = 1e-10 * far / size / sin_mu + 2 / FAR
    # Aronhold–Kennedy: the three centres of any three bodies lie on one line (a centre at
    # infinity: the line runs along its direction).
    for tri in combinations(range(4), 3):
        lines = [centres[(a, b)] for a, b in combinations(tri, 2)]
        points = [c for c, _ in lines if np.isfinite(c).all()]
        ways = [d for c, d in lines if not np.isfinite(c).all()]
        assert all(np.isfinite(d).all() for d in ways)
        if len(points) == 3:
            u, v = points[1] - points[0], points[2] - points[0]
            nu, nv = float(plane.norm(u)), float(plane.norm(v))
            assert abs(float(plane.cross(u, v))) <= 2 * off * (nu + nv + 2 * off), (tri, theta)
        elif len(points) == 2:
            u = points[1] - points[0]
            nu = float(plane.norm(u))
            assert abs(float(plane.cross(u, ways[0]))) <= 2 * off + turn * nu, (tri, theta)
    # The secondary centres, by intersecting lines.
    by_lines = {
        (0, 2): _meet(p["A0"], p["A"] - p["A0"], p["B0"], p["B"] - p["B0"]),
        (1, 3): _meet(p["A0"], p["B0"] - p["A0"], p["A"], p["B"] - p["A"]),
    }
    for pair, expected in by_lines.items():
        got, direction = centres[pair]
        if np.isfinite(got).all() and np.isfinite(expected).all():
            d = max(float(plane.norm(expected)), size)
            assert float(plane.norm(got - expected)) <= 1e-10 * d * d / size / sin_mu, pair
        elif np.isfinite(direction).all():
            # At infinity: the two lines are parallel, along that direction.
            ends = (("A0", "A"), ("B0", "B")) if pair == (0, 2) else (("A0", "B0"), ("A", "B"))
            for a, b in ends:
                line = p[b] - p[a]
                assert abs(float(plane.cross(line, direction))) <= turn * float(plane.norm(line))
    return True


LENGTH = st.floats(0.2, 5.0)


@given(
    crank=LENGTH,
    coupler=LENGTH,
    rocker=LENGTH,
    frame=LENGTH,
    frame_angle=st.floats(-math.pi, math.pi),
    theta=st.floats(-math.pi, math.pi),
    assembly=st.sampled_from([1, -1]),
)
def test_random_fourbars_obey_kennedy(
    crank, coupler, rocker, frame, frame_angle, theta, assembly
) -> None:
    b0 = [frame * math.cos(frame_angle), frame * math.sin(frame_angle)]
    fb = FourBar(A0=[0, 0], B0=b0, crank=crank, coupler=coupler, rocker=rocker, assembly=assembly)
    _check_fourbar(fb, theta)


@given(
    crank=LENGTH,
    frame=LENGTH,
    exponent=st.floats(-12, -3),
    theta=st.floats(-math.pi, math.pi),
)
def test_near_parallelograms_obey_kennedy(crank, frame, exponent, theta) -> None:
    # A parallelogram's coupler (nearly) translates: I13 runs off towards infinity.
    eps = 10.0**exponent
    fb = FourBar(A0=[0, 0], B0=[frame, 0], crank=crank, coupler=frame * (1 + eps), rocker=crank)
    _check_fourbar(fb, theta)


@given(
    crank=LENGTH,
    coupler=LENGTH,
    rocker=LENGTH,
    frame=LENGTH,
    exponent=st.floats(-9, -2),
)
def test_fourbars_near_their_limit_positions_obey_kennedy(
    crank, coupler, rocker, frame, exponent
) -> None:
    fb = FourBar(A0=[0, 0], B0=[frame, 0], crank=crank, coupler=coupler, rocker=rocker)
    arcs = input_range(fb)
    lo = np.asarray(arcs.lo)
    lo = lo[np.isfinite(lo)]
    if lo.size:
        _check_fourbar(fb, float(lo[0]) + 10.0**exponent)


def test_a_parallelograms_coupler_translates() -> None:
    fb = FourBar(A0=[0, 0], B0=[3, 0], crank=1, coupler=3, rocker=1)
    motion = solve(fb, [0.7], order=1)
    assert np.allclose(motion.positions["B"] - motion.positions["A"], [[3, 0]])  # the parallelogram
    ic = instant_centres(fb, motion)
    centre, direction = ic.between("frame", "A–B–P")
    assert np.isnan(centre).all()
    # Square to the coupler's velocity (the crank's at A: perpendicular to A0A).
    assert abs(float(plane.dot(direction[0], motion.velocities["A"][0]))) <= 1e-12


def test_a_sliders_centre_with_the_frame_is_square_to_its_guide() -> None:
    sc = SliderCrank(A0=[0, 0], crank=1, rod=3, line_point=[0, 0.5], line_angle=0.4)
    ic = instant_centres(sc, np.linspace(0.1, 6.0, 13))
    _, direction = ic.between("frame", "slider B")
    guide = np.array([math.cos(0.4), math.sin(0.4)])
    assert np.allclose(plane.dot(direction, guide), 0, atol=1e-12)
    # Block and rod share the pin B: their centre.
    assert np.array_equal(
        ic.between("A–B–P", "slider B")[0], solve(sc, np.linspace(0.1, 6.0, 13)).positions["B"]
    )


# ---------------------------------------------------------------------------------------------
# Sphere: instantaneous axes


@pytest.mark.parametrize("name", SPHERE_EXAMPLES)
def test_each_body_turns_about_its_axis_on_the_sphere(name: str) -> None:
    mech = load_example(name).mechanism
    motion = circuits(mech, 48, order=1)[1][0]
    ic = instant_centres(mech, motion, pairs="frame")
    for k, (_, j) in enumerate(ic.pairs):
        body = ic.bodies[j]
        rate = _spherical_rate(mech, motion, body.joints)
        ok = np.isfinite(rate).all(axis=-1) & ic.valid
        assert ok.sum() >= len(ok) // 2
        big = max(1.0, float(np.abs(rate[ok]).max()))
        assert np.allclose(ic.omega[ok, k], rate[ok], atol=1e-6 * big), (name, body.name)
        axis = ic.centre[:, k]
        assert np.allclose(sphere.norm(axis[ok]), 1.0)
        turning = sphere.norm(rate) > 1e-3
        assert np.allclose(axis[ok & turning], sphere.unit(rate[ok & turning]), atol=1e-5)
        for joint in body.joints:  # v = ω × P, with the engine's velocities
            predicted = sphere.cross(rate, motion.positions[joint])
            assert np.abs(predicted - motion.velocities[joint])[ok].max() <= 1e-6 * big


def test_a_spherical_crank_turns_about_its_pivot() -> None:
    fb = lw.SphericalFourBar(*np.radians([70, 20, 60, 50]))
    ic = instant_centres(fb, np.linspace(0, 6, 7), pairs="frame")
    axis, direction = ic.between("frame", "A0–A")
    assert direction is None
    assert np.allclose(axis, fb.params()["A0"], atol=1e-15)
    # Seen from the crank the frame turns the other way about the same axis.
    assert np.allclose(ic.between("A0–A", "frame")[0], -axis)


# ---------------------------------------------------------------------------------------------
# What it says where there is nothing to give


def test_a_linkage_that_cannot_assemble_has_no_centres_and_says_why() -> None:
    never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    ic = instant_centres(never, [0.0, 1.0])
    assert np.isnan(ic.centre).all() and np.isnan(ic.omega).all() and not ic.valid.any()
    assert (
        ic.reason
        == "θ = 0°: the coupler and rocker cannot reach (dyad B: |A B0| = 9 > coupler + rocker = 5)"
    )


def test_a_limit_position_is_named_as_singular() -> None:
    rocker = load_example("rocker-input").mechanism
    limit = float(np.asarray(input_range(rocker).lo)[0])
    ic = instant_centres(rocker, [limit])
    assert np.isnan(ic.centre[0, 1]).all()  # I13: the coupler's, where the velocities blow up
    assert "singular" in (ic.reason or "")


def test_a_motion_without_derivatives_is_solved_again_on_its_branches() -> None:
    mech = load_example("rocker-input").mechanism
    plain = circuits(mech, 24, order=0)[1][1]
    full = circuits(mech, 24, order=1)[1][1]
    a, b = instant_centres(mech, plain), instant_centres(mech, full)
    assert np.array_equal(a.centre, b.centre, equal_nan=True)


def test_bad_arguments_are_one_line_errors() -> None:
    fb = load_example("crank-rocker").mechanism
    with pytest.raises(ValueError, match="pairs: must be 'all' or 'frame', got 'some'"):
        instant_centres(fb, [0.0], pairs="some")
    with pytest.raises(ValueError, match="at: every input angle must be a finite number"):
        instant_centres(fb, [np.nan])
    ic = instant_centres(fb, [0.0], pairs="frame")
    with pytest.raises(LookupError, match="no body named 'rotor'"):
        ic.between("frame", "rotor")
    with pytest.raises(LookupError, match="was not computed"):
        ic.between("A0–A", "B0–B")


def test_the_verb_is_in_the_namespaces() -> None:
    assert lw.instant_centres is instant_centres is lw.analysis.instant_centres

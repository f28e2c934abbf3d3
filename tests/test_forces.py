"""Forces (issue 25): Newton–Euler against the energy balance, against momentum, against a
Lagrangian written from finite differences of the energy, and paper 003's M^i.

Every reference here is computed another way than the library's: the energy of a uniform bar
from its end velocities (½m(v_A² + v_A·v_B + v_B²)/3, a closed form), derivatives of it by FFT
or by finite differences of solved positions, never from the library's accelerations.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.dynamics import Loads, MassProps, forces, reduced_inertia, structure
from linkwright.dynamics.planar import forces_of, mechanical_advantage
from linkwright.io import load_example
from linkwright.mechanisms import FourBar, SliderCrank
from linkwright.mechanisms.base import solve

# One example per planar family (and the Stephenson III driven at its output, a triad, and at
# its hinge D; a four-bar driven at a moving hinge).
PLANAR = [
    "crank-rocker",
    "offset-slider-crank",
    "elliptic-trammel",
    "geared-fivebar",
    "watt1-example",
    "watt2-example",
    "stephenson1-example",
    "stephenson3-example",
    "stephenson3-output",
    "stephenson3-driven-at-d",
    "hinge-driven-fourbar",
    "jansen-leg",
    "klann-leg",
]


def _perturbed(mech, scale: float):
    """The example with every length field scaled by ``scale`` (a random, still-assembling
    member of its family; the composed linkages keep their joints)."""
    changes = {n: np.asarray(getattr(mech, n)) * scale for n in mech.length_fields}
    changes.update(
        {n: np.asarray(getattr(mech, n)) * scale for n in mech.point_fields if hasattr(mech, n)}
    )
    try:
        return dataclasses.replace(mech, **changes)
    except (TypeError, ValueError):
        return mech


@st.composite
def _case(draw):
    name = draw(st.sampled_from(PLANAR))
    mech = load_example(name).mechanism
    mech = _perturbed(mech, draw(st.floats(0.2, 5.0)))
    s = structure(mech.plan)
    masses = {}
    for b in s.bodies:
        if not draw(st.booleans()):
            continue
        mass = draw(st.floats(0.01, 10.0))
        if b.is_block or draw(st.booleans()):
            masses[b.name] = MassProps(mass)
        else:
            centre = (draw(st.floats(-2, 2)), draw(st.floats(-2, 2)))
            masses[b.name] = MassProps(mass, centre, draw(st.floats(0.0, 5.0)))
    points = [p for p in mech.plan.joints if s.owner(p) is not None]
    ground = sorted(s.ground)
    loads = Loads(
        speed_rpm=draw(st.floats(-300, 300).filter(lambda x: abs(x) > 1)),
        acceleration=draw(st.floats(-50, 50)),
        gravity=(draw(st.floats(-10, 10)), draw(st.floats(-10, 10))),
        forces=((draw(st.sampled_from(points)), (draw(st.floats(-5, 5)), 1.0)),),
        torques=((draw(st.sampled_from(s.names)), draw(st.floats(-5, 5))),),
        springs=((draw(st.sampled_from(points)), ground[0], draw(st.floats(0, 100)), 0.5),),
        dampers=((draw(st.sampled_from(points)), ground[-1], draw(st.floats(0, 10))),),
    )
    theta = np.array(draw(st.lists(st.floats(0, 2 * np.pi), min_size=1, max_size=8)))
    return name, mech, masses, loads, theta


@settings(max_examples=60)
@given(_case())
def test_newton_euler_matches_energy_balance(case):
    """Every planar family, random sizes, masses, loads and speeds: the driving torque from one
    linear solve of Newton–Euler equals the energy balance's to 1e-9 relative (to the largest
    term of the balance, so that a torque near zero is not asked for digits it cannot have)."""
    name, mech, masses, loads, theta = case
    motion = solve(mech, theta, order=2)
    f = forces_of(structure(mech.plan), mech.params(), motion, masses, loads)
    ok = f.valid
    # Near a singular position the system's condition grows without bound; both methods are
    # then right only to eps·cond. Keep samples the engine calls regular and well away from a
    # limit (every dyad's margin above 1e-4).
    for margin in motion.margins.values():
        ok &= np.abs(np.nan_to_num(margin)) > 1e-4
    if not ok.any():
        return
    scale = _balance_scale(f, masses, loads, motion, mech)
    err = np.abs(f.input_torque - f.energy_torque)[ok]
    assert np.all(err <= 1e-9 * scale[ok]), (name, err.max(), scale[ok].max())


def _balance_scale(f, masses, loads, motion, mech):
    """A size for the torque: the largest force in play times the linkage's size, times the
    largest joint rate (so that rounding of a sum of such terms is below it by the tolerance)."""
    size = float(np.max(mech.scale)) + 1.0
    rates = max(float(np.nanmax(np.abs(v))) for v in motion.velocities.values()) + 1.0
    forces_in_play = [np.abs(f.input_torque) / size]
    forces_in_play += [np.linalg.norm(r, axis=-1) for r in f.reactions.values()]
    stacked = np.nan_to_num(np.stack(np.broadcast_arrays(*forces_in_play)))
    biggest = np.max(stacked, axis=0)
    return (biggest + 1e-12) * size * rates


def _cross(a, b):
    a, b = np.broadcast_arrays(a, b)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _fourbar(**kw):
    base = dict(A0=[0, 0], B0=[4, 0], crank=1.0, coupler=3.5, rocker=3.0, u=0.5, v=0.4)
    base.update(kw)
    return FourBar(**base)


def _bar_energy(m_ab, va, vb):
    """Kinetic energy of a uniform bar from its ends' velocities (closed form)."""
    return m_ab / 6.0 * (np.sum(va * va, -1) + np.sum(va * vb, -1) + np.sum(vb * vb, -1))


def _spectral_derivative(values, period=2 * np.pi):
    n = values.shape[-1]
    k = np.fft.rfftfreq(n, d=period / n) * 2 * np.pi
    return np.fft.irfft(1j * k * np.fft.rfft(values), n)


def test_uniform_bars_at_constant_speed_return_their_energy():
    """A crank-rocker of uniform bars at constant speed, no gravity: ∫T dθ over a turn is 0 to
    1e-9 (the energy returns), and T·ω = dKE/dt with KE from the joints' velocities alone
    (the bar formula) and d/dt = ω d/dθ by spectral differentiation."""
    mech = _fourbar()
    masses = {"crank": 0.3, "coupler": 1.2, "rocker": 0.8}
    rpm = 150.0
    omega = rpm * 2 * np.pi / 60
    n = 1024
    theta = np.arange(n) * 2 * np.pi / n
    f = forces(mech, theta, masses, Loads(speed_rpm=rpm))
    assert f.valid.all()
    torque = f.input_torque
    work = np.sum(torque) * 2 * np.pi / n  # periodic trapezoid: spectrally accurate
    assert abs(work) <= 1e-9 * np.max(np.abs(torque)) * 2 * np.pi

    m = solve(mech, theta, order=1)
    v = {k: x * omega for k, x in m.velocities.items()}
    ke = (
        _bar_energy(masses["crank"], v["A0"], v["A"])
        + _bar_energy(masses["coupler"], v["A"], v["B"])
        + _bar_energy(masses["rocker"], v["B0"], v["B"])
    )
    dke_dt = omega * _spectral_derivative(ke)
    assert np.allclose(torque * omega, dke_dt, rtol=0, atol=1e-9 * np.max(np.abs(dke_dt)))
    assert np.allclose(f.kinetic, ke, rtol=1e-12, atol=0)


def _lagrange_torque(mech, bars, theta, omega, eps, gravity, h=1e-3):
    """T = J ε + ½ J′ ω² + V′ for a one-degree-of-freedom linkage of uniform bars, J(θ) and
    V(θ) from solved positions and first derivatives only, their θ-derivatives by a 6th-order
    central difference (the Lagrangian, independent of Newton–Euler and of accelerations)."""
    g = np.asarray(gravity)

    def energy(th):
        m = solve(mech, th, order=1)
        jj = np.zeros(th.shape)
        vv = np.zeros(th.shape)
        for mass, (a, b) in bars:
            jj += 2 * _bar_energy(mass, m.velocities[a], m.velocities[b])
            vv -= mass * ((m.positions[a] + m.positions[b]) / 2) @ g
        return jj, vv

    w = [(1, 3 / 4), (2, -3 / 20), (3, 1 / 60)]
    djj = np.zeros(theta.shape)
    dvv = np.zeros(theta.shape)
    for k, c in w:
        jp, vp = energy(theta + k * h)
        jm, vm = energy(theta - k * h)
        djj += c * (jp - jm) / h
        dvv += c * (vp - vm) / h
    jj, _ = energy(theta)
    return jj * eps + 0.5 * djj * omega**2 + dvv


@pytest.mark.parametrize("kind", ["fourbar", "slidercrank"])
def test_lagrangian_by_finite_differences(kind):
    """An independent multibody formulation: Lagrange's equation for the one coordinate θ, with
    the energies from positions and velocities only and their derivatives by finite
    differences, agrees with Newton–Euler (to the finite differences' 1e-8)."""
    theta = np.linspace(0.1, 6.0, 25)
    gravity = (0.0, -9.81)
    if kind == "fourbar":
        mech = _fourbar()
        bars = [(0.3, ("A0", "A")), (1.2, ("A", "B")), (0.8, ("B0", "B"))]
        masses = {"crank": 0.3, "coupler": 1.2, "rocker": 0.8}
    else:
        mech = SliderCrank(A0=[0, 0], crank=1.0, rod=3.0, line_point=[0, 0.3], line_angle=0.2)
        bars = [(0.3, ("A0", "A")), (1.2, ("A", "B")), (0.5, ("B", "B"))]  # block: a point
        masses = {"crank": 0.3, "rod": 1.2, "slider": 0.5}
    rpm, eps = 200.0, 7.0
    omega = rpm * 2 * np.pi / 60
    f = forces(mech, theta, masses, Loads(speed_rpm=rpm, acceleration=eps, gravity=gravity))
    want = _lagrange_torque(mech, bars, theta, omega, eps, gravity)
    assert np.allclose(f.input_torque, want, rtol=0, atol=1e-8 * np.max(np.abs(want)))


def test_shaking_force_and_moment_are_the_momentum_balance():
    """What the frame feels equals the loads minus the rate of momentum (force) and of angular
    momentum about the origin (moment): Newton's laws for the whole linkage, no reaction used."""
    mech = load_example("watt1-example").mechanism
    s = structure(mech.plan)
    masses = {
        b.name: MassProps(1.0 + k, (0.1 * k, 0.2), 0.3 + 0.1 * k) for k, b in enumerate(s.bodies)
    }
    g = (0.0, -9.81)
    loads = Loads(speed_rpm=90, acceleration=3.0, gravity=g, forces=(("P", (2.0, -1.0)),))
    theta = np.linspace(0, 2 * np.pi, 13)
    motion = solve(mech, theta, order=2)
    f = forces_of(s, mech.params(), motion, masses, loads)
    from linkwright.dynamics.planar import body_kinematics

    omega, eps = loads.omega, loads.acceleration
    want_f = np.zeros(theta.shape + (2,))
    want_m = np.zeros(theta.shape)
    for b in s.bodies:
        q = body_kinematics(b, masses[b.name], motion)
        a = q.c2 * omega**2 + q.c1 * eps
        al = q.phi2 * omega**2 + q.phi1 * eps
        weight = q.mass * np.asarray(g)
        want_f += weight - q.mass * a
        want_m += _cross(q.c, weight) - q.mass * _cross(q.c, a) - q.inertia * al
    p = motion.positions["P"]
    want_f += np.array([2.0, -1.0])
    want_m += _cross(p, np.array([2.0, -1.0]))
    ok = f.valid
    size = np.max(np.abs(want_f)) + np.max(np.abs(want_m))
    assert np.allclose(f.shaking_force[ok], want_f[ok], rtol=0, atol=1e-10 * size)
    assert np.allclose(f.shaking_moment[ok], want_m[ok], rtol=0, atol=1e-10 * size)


def test_paper003_reduced_inertia():
    """Paper 003: the output's inertia reduced to the input, M^i = ω1² J3 φ3′ φ3″ and
    P^i = M^i ω1, with φ3′, φ3″ from finite differences of the solved rocker angle; and the
    Newton–Euler torque of a four-bar whose rocker alone has inertia (centre at its pivot)."""
    mech = _fourbar()
    theta = np.linspace(0.2, 6.0, 15)
    j3, rpm = 0.35, 100.0
    omega = rpm * 2 * np.pi / 60
    m_i, p_i = reduced_inertia(mech, theta, j3, rpm)

    def rocker_angle(th):
        b = solve(mech, th, order=0).positions["B"] - np.array([4.0, 0.0])
        return np.unwrap(np.arctan2(b[..., 1], b[..., 0]))

    h = 1e-3
    a = {k: rocker_angle(theta + k * h) for k in (-2, -1, 0, 1, 2)}
    d1 = (a[-2] - 8 * a[-1] + 8 * a[1] - a[2]) / (12 * h)
    d2 = (-a[-2] + 16 * a[-1] - 30 * a[0] + 16 * a[1] - a[2]) / (12 * h * h)
    want = omega**2 * j3 * d1 * d2
    assert np.allclose(m_i, want, rtol=0, atol=1e-6 * np.max(np.abs(want)))
    assert np.allclose(p_i, m_i * omega, rtol=1e-15)
    f = forces(mech, theta, {"rocker": MassProps(2.0, (0.0, 0.0), j3)}, Loads(speed_rpm=rpm))
    assert np.allclose(f.input_torque, m_i, rtol=0, atol=1e-12 * np.max(np.abs(m_i)))


def test_static_crank_holds_its_weight_and_mechanical_advantage():
    """Static (no inertia): a four-bar with a weight hung at B on the rocker only; the motor's
    torque equals virtual work, T = −F·(dB/dθ), and the ideal mechanical advantage is
    1/|φ3′| (the rocker's angular rate by finite differences)."""
    mech = _fourbar()
    theta = np.array([0.5, 1.5, 3.0])
    loads = Loads(inertia=False, forces=(("B", (0.0, -10.0)),))
    f = forces(mech, theta, {}, loads)
    h = 1e-5
    db = (
        solve(mech, theta + h, order=0).positions["B"]
        - solve(mech, theta - h, order=0).positions["B"]
    ) / (2 * h)
    want = -db @ np.array([0.0, -10.0])
    assert np.allclose(f.input_torque, want, rtol=0, atol=1e-8 * np.max(np.abs(want)))
    s = structure(mech.plan)
    ma = mechanical_advantage(s, solve(mech, theta, order=2))
    b0 = np.array([4.0, 0.0])

    def ang(th):
        b = solve(mech, th, order=0).positions["B"] - b0
        return np.arctan2(b[..., 1], b[..., 0])

    rate = (ang(theta + h) - ang(theta - h)) / (2 * h)
    assert np.allclose(ma, 1 / np.abs(rate), rtol=1e-8)


def test_every_planar_family_has_bodies_from_its_plan():
    """The bodies are read off the step kinds: the four-bar's three links by their fields, the
    slider-crank's block, the Watt I's ternary crank; Jansen's leg is square (33 unknowns)."""
    fb = structure(FourBar.plan)
    assert fb.names == ("crank", "coupler", "rocker")
    sc = structure(load_example("offset-slider-crank").mechanism.plan)
    assert sc.names == ("crank", "rod", "slider") and sc.body("slider").is_block
    w1 = structure(load_example("watt1-example").mechanism.plan)
    assert w1.body("crank").joints == ("A0", "A", "C")
    jansen = load_example("jansen-leg").mechanism
    f = forces(jansen, [0.4], {}, Loads(speed_rpm=10))
    assert f.valid.all() and len(structure(jansen.plan).bodies) == 11


def test_spherical_plans_have_bodies_too():
    """Paper 001's linkage driven at FG (a spherical triad): its bodies, by the same rules."""
    s = structure(load_example("paper001-fg").mechanism.plan)
    assert s.space == "sphere" and s.pivot == "G"
    assert [len(b.joints) for b in s.bodies] == [2, 2, 2, 2, 3]


@pytest.mark.parametrize("inp", ["rocker", "A", "B", "C", "D", "output"])
def test_a_motor_anywhere_does_the_cranks_work(inp):
    """Statics (weights and a load, no inertia): a motor anywhere holds the same configuration
    with the same power. At each configuration the torque at input ``inp`` is the crank-driven
    linkage's torque times dθ_crank/dθ_inp, the crank angle's rate read off the solved motion
    (the crank pin's velocity); the crank-driven torque is solved on its own plan, at the crank
    angle measured on the configuration. The motor's body pair is checked too: the driven body
    turns relative to the one it reacts on at exactly the input's rate."""
    from linkwright.dynamics.planar import body_kinematics
    from linkwright.mechanisms import configurations

    base = load_example("stephenson3-example").mechanism
    driven = dataclasses.replace(base, input=inp)
    s = structure(driven.plan)
    masses = {b.name: MassProps(1.0 + 0.3 * k) for k, b in enumerate(s.bodies)}
    loads = Loads(inertia=False, gravity=(0.3, -9.81), forces=(("P", (2.0, -1.0)),))
    crank_s = structure(base.plan)
    checked = 0
    for _, motion in configurations(driven, np.radians(np.arange(-180.0, 180.0, 7.0))):
        f = forces_of(s, driven.params(), motion, masses, loads)
        if s.counter is not None:
            kin = [body_kinematics(b, None, motion) for b in s.bodies]
            rate = kin[s.driven].phi1 - kin[s.counter].phi1
            assert np.allclose(rate[motion.regular], 1.0, atol=1e-9)
        for i in np.flatnonzero(f.valid):
            a = motion.positions["A"][i]
            theta = np.arctan2(a[1], a[0])
            rate = motion.velocities["A"][i] @ np.array([-a[1], a[0]]) / (a @ a)  # dθ/dθ_inp
            if (
                abs(rate) < 1e-3
                or min(abs(np.asarray(v)[i]) for v in motion.margins.values()) < 1e-3
            ):
                continue
            base_motion = solve(
                dataclasses.replace(base, assembly=_sign(motion, i, "A", "B", "B0"),
                                    assembly2=_sign(motion, i, "C", "D", "D0")),
                [theta], order=2,
            )  # fmt: skip
            assert base_motion.valid[0]
            g = forces_of(crank_s, base.params(), base_motion, _same(masses, s, crank_s), loads)
            want = g.input_torque[0] * rate
            scale = 1.0 + abs(g.input_torque[0] * rate)
            assert abs(f.input_torque[i] - want) <= 1e-8 * scale, (inp, i)
            checked += 1
    assert checked >= 5


def _sign(motion, i, p1, p, p2):
    """The engine's dyad sign of joint ``p`` placed from ``p1`` then ``p2``: sign((p2 − p1) ×
    (p − p1)), measured on the configuration."""
    x = {k: motion.positions[k][i] for k in (p1, p, p2)}
    return float(np.sign(_cross(x[p2] - x[p1], x[p] - x[p1])))


def _same(masses, s, other):
    """The same bodies' masses under the other plan's names (a body is its set of points)."""
    by_points = {frozenset(b.points): masses[b.name] for b in s.bodies}
    return {b.name: by_points[frozenset(b.points)] for b in other.bodies}

"""Forces (issue 25) against a symbolic multibody model: Lagrange's equation written by SymPy.

The four-bar and the slider-crank are written here from scratch as SymPy expressions: each
joint's position as a function of the crank angle θ (circle ∩ circle, circle ∩ line, in closed
form), each link a uniform slender bar (kinetic energy m/6·(|Ṗ|² + Ṗ·Q̇ + |Q̇|²) between its
ends P, Q, potential m g·(P + Q)/2), the slider a point mass. With T = ½ M(θ) θ̇², Lagrange's
equation for the one coordinate gives the driving torque

    τ = M(θ) θ̈ + ½ M′(θ) θ̇² + V′(θ),

differentiated symbolically: nothing of linkwright's engine, its derivatives or its dynamics
enters the reference.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.dynamics import Loads, forces
from linkwright.mechanisms import FourBar, SliderCrank, input_range

sp = pytest.importorskip("sympy")


def _bar(p, q, mass, g, theta):
    """A uniform bar's M(θ) share (per θ̇²) and its potential energy."""
    dp, dq = (sp.Matrix([sp.diff(c, theta) for c in x]) for x in (p, q))
    inertia = mass / 3 * (dp.dot(dp) + dp.dot(dq) + dq.dot(dq))
    potential = -mass * g.dot((p + q) / 2)
    return inertia, potential


@functools.cache
def _fourbar_torque():
    """τ(θ, ω, ε; lengths, masses, gravity) of a four-bar with A0 at the origin, B0 on +x."""
    theta, omega, eps = sp.symbols("theta omega epsilon", real=True)
    frame, crank, coupler, rocker, sign = sp.symbols("L4 L1 L2 L3 sigma", real=True)
    m1, m2, m3, gx, gy = sp.symbols("m1 m2 m3 gx gy", real=True)
    a0, b0 = sp.Matrix([0, 0]), sp.Matrix([frame, 0])
    a = crank * sp.Matrix([sp.cos(theta), sp.sin(theta)])
    d = b0 - a
    dist = sp.sqrt(d.dot(d))
    along = (coupler**2 - rocker**2 + dist**2) / (2 * dist)
    height = sp.sqrt(coupler**2 - along**2)
    unit = d / dist
    b = a + along * unit + sign * height * sp.Matrix([-unit[1], unit[0]])
    g = sp.Matrix([gx, gy])
    parts = [_bar(a0, a, m1, g, theta), _bar(a, b, m2, g, theta), _bar(b0, b, m3, g, theta)]
    mass = sum(p[0] for p in parts)
    potential = sum(p[1] for p in parts)
    tau = mass * eps + sp.diff(mass, theta) * omega**2 / 2 + sp.diff(potential, theta)
    args = (theta, omega, eps, frame, crank, coupler, rocker, sign, m1, m2, m3, gx, gy)
    return sp.lambdify(args, tau, "numpy")


@functools.cache
def _slidercrank_torque():
    """τ of a slider-crank with A0 at the origin and its line y = e along +x."""
    theta, omega, eps = sp.symbols("theta omega epsilon", real=True)
    crank, rod, e, sign = sp.symbols("L1 L2 e sigma", real=True)
    m1, m2, ms, gx, gy = sp.symbols("m1 m2 ms gx gy", real=True)
    a0 = sp.Matrix([0, 0])
    a = crank * sp.Matrix([sp.cos(theta), sp.sin(theta)])
    b = sp.Matrix([a[0] + sign * sp.sqrt(rod**2 - (e - a[1]) ** 2), e])
    g = sp.Matrix([gx, gy])
    parts = [_bar(a0, a, m1, g, theta), _bar(a, b, m2, g, theta)]
    db = sp.Matrix([sp.diff(c, theta) for c in b])
    mass = sum(p[0] for p in parts) + ms * db.dot(db)
    potential = sum(p[1] for p in parts) - ms * g.dot(b)
    tau = mass * eps + sp.diff(mass, theta) * omega**2 / 2 + sp.diff(potential, theta)
    args = (theta, omega, eps, crank, rod, e, sign, m1, m2, ms, gx, gy)
    return sp.lambdify(args, tau, "numpy")


masses = st.floats(0.05, 3.0)


@settings(max_examples=30, deadline=None)
@given(
    frame=st.floats(1.5, 4.0),
    crank=st.floats(0.2, 1.0),
    coupler=st.floats(2.0, 4.0),
    rocker=st.floats(2.0, 4.0),
    sign=st.sampled_from([1.0, -1.0]),
    m=st.tuples(masses, masses, masses),
    rpm=st.floats(-300.0, 300.0),
    eps=st.floats(-20.0, 20.0),
    gravity=st.tuples(st.floats(-10.0, 10.0), st.floats(-10.0, 10.0)),
)
def test_fourbar_torque_is_lagranges(frame, crank, coupler, rocker, sign, m, rpm, eps, gravity):
    fb = FourBar(
        A0=[0, 0], B0=[frame, 0], crank=crank, coupler=coupler, rocker=rocker, assembly=sign
    )
    arcs = input_range(fb)
    theta = np.linspace(-np.pi, np.pi, 25)
    loads = Loads(speed_rpm=rpm, acceleration=eps, gravity=gravity)
    f = forces(fb, theta, {"crank": m[0], "coupler": m[1], "rocker": m[2]}, loads)
    omega = rpm * 2 * np.pi / 60
    with np.errstate(invalid="ignore"):
        ref = _fourbar_torque()(theta, omega, eps, frame, crank, coupler, rocker, sign,
                                *m, *gravity)  # fmt: skip
    # Away from the limits (where the torque of a rocking input grows without bound): the
    # reference's closed form loses digits as 1/sin of the transmission angle.
    ok = f.valid & np.isfinite(ref)
    if not bool(arcs.full):
        ok &= np.abs(f.input_torque) < 1e6
    scale = 1.0 + np.max(np.abs(ref[ok]), initial=0.0)
    np.testing.assert_allclose(f.input_torque[ok], ref[ok], atol=1e-9 * scale)


@settings(max_examples=30, deadline=None)
@given(
    crank=st.floats(0.2, 1.0),
    rod=st.floats(2.0, 4.0),
    offset=st.floats(-0.8, 0.8),
    sign=st.sampled_from([1.0, -1.0]),
    m=st.tuples(masses, masses, masses),
    rpm=st.floats(-300.0, 300.0),
    eps=st.floats(-20.0, 20.0),
    gravity=st.tuples(st.floats(-10.0, 10.0), st.floats(-10.0, 10.0)),
)
def test_slidercrank_torque_is_lagranges(crank, rod, offset, sign, m, rpm, eps, gravity):
    sc = SliderCrank(
        A0=[0, 0], crank=crank, rod=rod, line_point=[0, offset], line_angle=0.0, assembly=sign
    )
    theta = np.linspace(-np.pi, np.pi, 25)
    loads = Loads(speed_rpm=rpm, acceleration=eps, gravity=gravity)
    f = forces(sc, theta, {"crank": m[0], "rod": m[1], "slider": m[2]}, loads)
    omega = rpm * 2 * np.pi / 60
    ref = _slidercrank_torque()(theta, omega, eps, crank, rod, offset, sign, *m, *gravity)
    assert f.valid.all()  # crank + |offset| < rod: the crank turns fully
    scale = 1.0 + np.max(np.abs(ref))
    np.testing.assert_allclose(f.input_torque, ref, atol=1e-9 * scale)

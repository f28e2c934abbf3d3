"""A Stephenson III driven anywhere: every input's plan against the crank-driven one.

The planar Stephenson III has seven joints and paper 001's spherical one seven; a motor may sit
at any of them (:mod:`linkwright.mechanisms.stephenson3_inputs`, ``SPHERE_PLANS``). Where the
driven hinge lies in the triad's loop, a triad step changes with the input
(:mod:`linkwright.engine.hinge_triad_steps`). Checked here against independent methods:

- **The same configurations.** A configuration is a configuration whatever drives it. At a random
  crank angle every configuration the crank-driven plan finds (dyads: circle ∩ circle) has its
  angle at each joint measured here, from its positions and the input's definition; the
  linkage driven at that joint, at that angle, must list the same configuration. And the other
  way round: every configuration of a linkage driven elsewhere, at a random input, has its crank
  angle measured and must be one of the crank-driven plan's there. The two ways together make
  the sets equal (counts and positions), to 1e-9 of the size.
- **Derivatives** against an 8th-order central difference of positions.
- **Continuity**: every circuit traced through a hinged triad is continuous (no branch jump), as
  ``tests/test_triad_steps.py`` checks the triads.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from test_triad_steps import _central, _continues

from linkwright.engine.continuation import every_circuit
from linkwright.geometry import sphere
from linkwright.mechanisms import SphericalStephenson3, Stephenson3, configurations

PLANE_INPUTS = ("rocker", "output", "A", "B", "C", "D")
SPHERE_INPUTS = ("FG", "DC", "B", "C", "E", "F")
SAME = 1e-9  # of the linkage's size
# Configurations this close to a limit of either plan are ill-conditioned in the other's input
# (a small change of one angle is a large change of the other): left out of the comparison.
CONDITIONED = 1e-3


def _signed(u: np.ndarray, v: np.ndarray) -> float:
    """The counter-clockwise angle from u to v."""
    return float(np.arctan2(u[0] * v[1] - u[1] * v[0], u @ v))


def plane_angle(inp: str, p: dict[str, np.ndarray]) -> float:
    """Each input's θ measured on a configuration, from its definition (the plans module's
    table), written apart from it."""
    x = np.array([1.0, 0.0])
    return {
        "crank": lambda: _signed(x, p["A"] - p["A0"]),
        "rocker": lambda: _signed(x, p["B"] - p["B0"]),
        "output": lambda: _signed(x, p["D"] - p["D0"]),
        "A": lambda: _signed(p["A0"] - p["A"], p["B"] - p["A"]),
        "B": lambda: _signed(p["B0"] - p["B"], p["A"] - p["B"]),
        "C": lambda: _signed(p["B"] - p["A"], p["D"] - p["C"]),
        "D": lambda: _signed(p["D0"] - p["D"], p["C"] - p["D"]),
    }[inp]()


def sphere_angle(inp: str, p: dict[str, np.ndarray]) -> float:
    """θ on paper 001's linkage: eq. 5's θ1 for AB (B = (sin a2 sin θ1, sin a2 cos θ1, …)), the
    angle about each hinge's axis between its great circles otherwise (right-handed)."""
    if inp == "AB":
        return float(np.arctan2(p["B"][0], p["B"][1]))
    vertex, origin, toward = {
        "FG": ("G", "away", "F"),
        "DC": ("D", "A", "C"),
        "B": ("B", "A", "C"),
        "C": ("C", "D", "B"),
        "E": ("E", "C", "F"),
        "F": ("F", "G", "E"),
    }[inp]
    return float(sphere.angle_at(p[vertex], p[origin], p[toward]))


def _configurations(mech, theta: float, space: str):
    """Every well-conditioned configuration at θ, as joint dicts."""
    out = []
    for _, motion in configurations(mech, [theta], order=0):
        if not motion.valid[0]:
            continue
        margins = [abs(float(np.asarray(m)[0])) for m in motion.margins.values()]
        pos = {k: v[0] for k, v in motion.positions.items()}
        if space == "sphere":
            pos["away"] = -pos["D"]
        out.append((min(margins, default=1.0), pos))
    return out


def _match(want: dict[str, np.ndarray], found, size: float) -> float:
    """The least largest-coordinate gap between ``want`` and one of ``found``."""
    keys = [k for k in want if k != "away"]
    gaps = [max(float(np.max(np.abs(want[k] - got[k]))) for k in keys) for _, got in found]
    return min(gaps, default=np.inf) / size


def _compare(base, driven, angle, theta: float, space: str) -> int:
    """The configurations of ``base`` at θ, each found again in ``driven`` at its angle there,
    and those of ``driven`` at its angle, each found in ``base``; returns how many compared."""
    size = float(np.max(np.asarray(base.scale)))
    inp = driven.input
    compared = 0
    for margin, conf in _configurations(base, theta, space):
        phi = angle(inp, conf)
        there = _configurations(driven, phi, space)
        if margin < CONDITIONED or any(m < CONDITIONED for m, _ in there):
            continue
        assert _match(conf, there, size) <= SAME, (inp, theta, phi)
        for _, other in there:
            back = _configurations(base, angle(base.input, other), space)
            if any(m < CONDITIONED for m, _ in back):
                continue
            assert _match(other, back, size) <= SAME, (inp, "back", phi)
            compared += 1
    return compared


def _random_stephenson3(rng: np.random.Generator) -> Stephenson3:
    """The bundled example's shape, each dimension moved by up to 25 %."""

    def near(v, spread=0.25):
        return np.asarray(v, dtype=float) * (1 + spread * rng.uniform(-1, 1, np.shape(v)))

    return Stephenson3(
        A0=[0.0, 0.0], B0=near([4.0, 0.0]), D0=near([2.0, -4.0]), crank=near(1.0),
        coupler=near(5.0), rocker=near(4.0), u1=near(4.0), v1=near(-2.0), link1=near(3.0),
        link2=near(6.0), u=1.5, v=1.0, assembly2=-1,
    )  # fmt: skip


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(seed=st.integers(0, 2**32 - 1), theta=st.floats(-np.pi, np.pi))
def test_a_planar_stephenson3_driven_anywhere_has_the_crank_driven_configurations(seed, theta):
    base = _random_stephenson3(np.random.default_rng(seed))
    compared = 0
    for inp in PLANE_INPUTS:
        driven = Stephenson3(**base.params(), input=inp)
        compared += _compare(base, driven, plane_angle, theta, "plane")
    assume(compared > 0)


P001 = np.radians([71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7])


def paper001(input: str = "AB", arcs: np.ndarray = P001) -> SphericalStephenson3:
    return SphericalStephenson3(*arcs, input=input)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    spread=st.lists(st.floats(-0.1, 0.1), min_size=9, max_size=9),
    theta=st.floats(-np.pi, np.pi),
)
def test_paper001_driven_anywhere_has_the_ab_driven_configurations(spread, theta):
    arcs = P001 * (1 + np.array(spread))
    base = paper001("AB", arcs)
    compared = 0
    for inp in SPHERE_INPUTS:
        compared += _compare(base, paper001(inp, arcs), sphere_angle, theta, "sphere")
    assume(compared > 0)


@pytest.mark.parametrize(
    ("family", "inp", "theta", "joints"),
    [
        ("plane", "C", 2.05, ("A", "B", "C", "D", "P")),
        ("plane", "D", 1.4, ("A", "B", "C", "D", "P")),
        ("sphere", "E", 2.0, ("B", "C", "E", "F")),
        ("sphere", "F", 1.9, ("B", "C", "E", "F")),
    ],
)
def test_hinged_triad_derivatives_match_central_differences(family, inp, theta, joints):
    if family == "plane":
        m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[2, -4], crank=1, coupler=5, rocker=4, u1=4,
                        v1=-2, link1=3, link2=6, u=1.5, v=1, assembly2=-1, input=inp)  # fmt: skip
    else:
        m = paper001(inp)
    params = m.params()
    checked = 0
    for slot, (_, motion) in enumerate(configurations(m, [theta], order=2)):
        if not motion.regular[0]:
            continue
        closure = min(abs(float(np.asarray(v)[0])) for v in motion.margins.values())
        if closure < 0.05:
            continue
        h = min(1e-3, 0.02 * closure**2)
        fd = _central(m.plan, params, m.points, theta, h, slot)
        for joint in joints:
            d1, d2, same = fd[joint]
            assert same
            scale = 1.0 + float(np.max(np.abs(motion.velocities[joint][0])))
            assert np.max(np.abs(motion.velocities[joint][0] - d1)) < 1e-7 * scale / closure**2
            scale = 1.0 + float(np.max(np.abs(motion.accelerations[joint][0])))
            assert np.max(np.abs(motion.accelerations[joint][0] - d2)) < 1e-5 * scale / closure**4
        checked += 1
    assert checked


@pytest.mark.parametrize(("family", "inp"), [("plane", "C"), ("plane", "D"), ("sphere", "E"),
                                             ("sphere", "F")])  # fmt: skip
def test_hinged_triad_circuits_close_and_continue(family, inp):
    if family == "plane":
        m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[2, -4], crank=1, coupler=5, rocker=4, u1=4,
                        v1=-2, link1=3, link2=6, u=1.5, v=1, assembly2=-1, input=inp)  # fmt: skip
        joints = ("A", "B", "C", "D")
    else:
        m = paper001(inp)
        joints = ("B", "C", "E", "F")
    found = every_circuit(m.plan, m.params(), 48, points=m.points)
    assert found
    for c in found:
        assert c.motion.valid.all()
        _continues(m.plan, m.params(), m.points, c, joints)

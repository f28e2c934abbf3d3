"""Independent geometry and strategies for the precision-point synthesis tests
(tests/test_synth_precision_*.py).

Everything here is computed without the code under test: four-bar positions from the
circle–circle closed form written below, poses moved by explicit rotations, and the centre-point
curve as the vanishing 3×3 determinant of the perpendicular-bisector equations (a formulation in
the centre point g, not in the dyad angles β the library uses).
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st

from linkwright.mechanisms import configurations

TOL = 1e-9


# --- independent geometry ------------------------------------------------------------------------


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def cross2(p, q):
    return p[0] * q[1] - p[1] * q[0]


def rot(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s], [s, c]])


def fourbar_state(A0, B0, a, b, c, u, v, theta, branch):
    """A, B, P and the coupler angle (of B − A) of a four-bar, or None where it cannot close.

    B is b from A and c from B0 on the side sign((B0 − A) × (B − A)) = branch.
    """
    A0, B0 = np.asarray(A0, float), np.asarray(B0, float)
    A = A0 + a * np.array([math.cos(theta), math.sin(theta)])
    d = B0 - A
    L = math.hypot(*d)
    if L < 1e-12:
        return None
    x = (b * b - c * c + L * L) / (2 * L)
    h2 = b * b - x * x
    if h2 < 0:
        return None
    e = d / L
    n = np.array([-e[1], e[0]])
    B = A + x * e + branch * math.sqrt(h2) * n
    ex = (B - A) / b
    P = A + u * ex + v * np.array([-ex[1], ex[0]])
    return A, B, P, math.atan2(ex[1], ex[0])


def moved(points, angles, first):
    """Position in pose j of the body point at ``first`` in pose 1 (explicit rotation)."""
    points = np.asarray(points, float)
    return np.array(
        [
            points[j] + rot(angles[j] - angles[0]) @ (np.asarray(first) - points[0])
            for j in range(len(points))
        ]
    )


def circle_residual(points, angles, centre, circle):
    """How far a dyad's moving pivot is off a circle about its centre, relative to its radius."""
    r = np.linalg.norm(moved(points, angles, circle) - centre, axis=-1)
    return float(np.max(np.abs(r - r[0])) / max(r[0], 1e-300))


def bisector_cubic(points, angles, g, rows):
    """det of the perpendicular-bisector equations in the circle point c for centre g.

    For a circle point c (first pose) its pose-j position is Rj c + dj, and |Rj c + dj − g| =
    |c − g| is linear in c: (Rjᵀ(dj − g) + g)·c = dj·g − |dj|²/2. Three such rows (poses 1, j,
    k, l) have a common c only where the 3×3 determinant of [row | rhs] vanishes: the centre-point
    curve of poses 1 j k l. Returned relative to the product of the rows' norms (the rhs in units
    of the poses' spread), each at least the spread: a row vanishes where g is a pole.
    """
    points = np.asarray(points, float)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    M = []
    for j in rows:
        R = rot(angles[j] - angles[0])
        dj = points[j] - R @ points[0]
        M.append([*(R.T @ (dj - g) + g), (dj @ g - dj @ dj / 2) / spread])
    M = np.array(M)
    return np.linalg.det(M) / np.prod(np.maximum(np.linalg.norm(M, axis=1), spread))


def coupler_poses(fb_args, thetas, branch=1):
    """Poses (P, coupler angle) of a four-bar at the inputs, from the closed form."""
    states = [fourbar_state(*fb_args, t, branch) for t in thetas]
    if any(s is None for s in states):
        return None
    return np.array([s[2] for s in states]), np.array([s[3] for s in states]), states


def check_design_reaches(design, points, angles):
    """The design's four-bar, simulated by the engine on each pose's assembly, meets every pose."""
    mech = design.mechanism
    scale = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    for sign, motion in configurations(mech, design.inputs):
        at = design.branches == sign[0]
        if not np.any(at):
            continue
        assert np.all(motion.valid[at])
        P = motion.positions["P"][at]
        assert np.max(np.linalg.norm(P - points[at], axis=-1)) <= TOL * scale
        line = motion.positions["B"][at] - motion.positions["A"][at]
        turned = np.arctan2(line[:, 1], line[:, 0])
        # The coupler turns with the poses: its line's angle minus the pose angle is constant.
        lag = wrap(turned - angles[at] - (turned[0] - angles[at][0]))
        assert np.max(np.abs(lag)) <= TOL
    # All poses on one assembly line up with the first pose's lag too.
    states = [
        fourbar_state(
            mech.A0,
            mech.B0,
            float(mech.crank),
            float(mech.coupler),
            float(mech.rocker),
            float(mech.u),
            float(mech.v),
            t,
            s,
        )
        for t, s in zip(design.inputs, design.branches, strict=True)
    ]
    lags = wrap(np.array([s[3] for s in states]) - angles)
    assert np.max(np.abs(wrap(lags - lags[0]))) <= TOL
    assert np.max(np.linalg.norm(np.array([s[2] for s in states]) - points, axis=-1)) <= TOL * scale


# --- strategies ----------------------------------------------------------------------------------

coord = st.floats(-1.5, 1.5)


length = st.floats(0.5, 3.0)


offset = st.floats(-2.0, 2.0)


@st.composite
def fourbars(draw):
    """A Grashof four-bar whose crank A0A turns fully (crank shortest), not a change point:
    every input assembles, away from the dyad's limits."""
    a = draw(st.floats(0.3, 1.0))
    b, c, d = (draw(st.floats(a + 0.4, 3.0)) for _ in range(3))
    longest = max(b, c, d)
    assume(a + longest < b + c + d - longest - 0.1)
    A0 = np.array([draw(coord), draw(coord)])
    t = draw(st.floats(-math.pi, math.pi))
    B0 = A0 + d * np.array([math.cos(t), math.sin(t)])
    return (A0, B0, a, b, c, draw(offset), draw(offset))


@st.composite
def fourbar_poses(draw, n):
    """n poses of a random crank-rocker's (or drag link's) coupler on one assembly."""
    fb = draw(fourbars())
    branch = draw(st.sampled_from([1.0, -1.0]))
    t0 = draw(st.floats(-math.pi, math.pi))
    steps = [draw(st.floats(0.3, 1.2)) for _ in range(n - 1)]
    thetas = t0 + np.concatenate(([0.0], np.cumsum(steps)))
    got = coupler_poses(fb, thetas, branch)
    assume(got is not None)
    points, angles, states = got
    # Away from the dyad's limit position, where poses crowd together, and from a folded dyad.
    for s in states:
        A, B = s[0], s[1]
        assume(np.linalg.norm(fb[1] - A) > 0.05)
        side = cross2(fb[1] - A, B - A) / (np.linalg.norm(fb[1] - A) * fb[3])
        assume(abs(side) > 0.05)
    spread = np.max(np.linalg.norm(points[:, None] - points[None], axis=-1))
    assume(spread > 0.1)
    # The coupler must turn (a parallelogram's only translates).
    assume(np.ptp(angles) > 0.05)
    # Both moving pivots must move (a folded four-bar can hold B still on A0).
    for k in (0, 1):
        q = np.array([s[k] for s in states])
        assume(np.min(np.linalg.norm(q[:, None] - q[None], axis=-1)[np.triu_indices(n, 1)]) > 0.05)
    return fb, branch, thetas, points, angles, states

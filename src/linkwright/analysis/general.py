"""Analyses that apply to any linkage the engine can build: the geared five-bar, the double
slider, the six-bars and user-composed linkages.

A dyad's transmission angle is the angle at its joint between its two links (for a slider pin,
between the rod and the normal of the guide, as for the slider-crank). It is the quantity
paper 003 studies for the four-bar, taken dyad by dyad: near 0° or 180° the dyad is near its
limit position and transmits badly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import DyadRRP, DyadRRR, Motion, SphereDyad
from linkwright.geometry import plane, sphere
from linkwright.mechanisms.base import Mechanism

__all__ = ["dyad_transmission_angles", "point_speed"]

Array = NDArray[np.float64]
REPORT_SAMPLES = 2048
"""Circuit samples :func:`linkwright.analysis.general_analysis` reads its extremes from."""


def dyad_transmission_angles(mechanism: Mechanism, motion: Motion) -> dict[str, Array]:
    """The transmission angle of every dyad at every sample (radians, in [0, π]).

    RRR dyad J from P1, P2: the angle at J between J→P1 and J→P2. RRP dyad (slider pin J from
    P1 on a guide at angle a): the angle between J→P1 and the guide's normal (a + 90°). On the
    sphere: the angle at J between the great circles J→P1 and J→P2 (the dihedral angle between
    the two links' planes), which is the spherical four-bar's transmission angle.

    Examples
    --------
    A four-bar's one dyad is its coupler–rocker joint B, so this is paper 003's γ:

    >>> from linkwright.mechanisms import FourBar, solve
    >>> m = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=1)
    >>> angles = dyad_transmission_angles(m, solve(m, [np.pi / 2]))
    >>> round(float(np.degrees(angles["B"][0])), 6)   # B = (4, 1): A→B horizontal, B0→B up
    90.0
    """
    params = mechanism.params()
    out: dict[str, Array] = {}
    for dyad in mechanism.plan.dyads:
        j = motion.positions[dyad.name]
        u = motion.positions[dyad.p1] - j
        if isinstance(dyad, DyadRRR):
            w = motion.positions[dyad.p2] - j
        elif isinstance(dyad, DyadRRP):
            angle = dyad.line_angle
            a = np.asarray(params[angle] if isinstance(angle, str) else angle, dtype=float)
            w = np.broadcast_to(plane.perp(plane.unit_direction(a))[..., None, :], u.shape)
        elif isinstance(dyad, SphereDyad):
            at_joint = sphere.angle_at(j, motion.positions[dyad.p1], motion.positions[dyad.p2])
            out[dyad.name] = np.abs(at_joint)
            continue
        else:  # pragma: no cover - every dyad type is listed above
            continue
        out[dyad.name] = np.arctan2(np.abs(plane.cross(u, w)), plane.dot(u, w))
    return out


def point_speed(motion: Motion, joint: str) -> Array:
    """|d joint/dθ|: how far the joint moves per radian of input (paper 002 graphs it).

    Multiply by the input's angular speed for a speed in length per second. On the sphere the
    joint is a unit vector and this is its angular speed, radians of arc per radian of input.

    Examples
    --------
    A point on a crank of length 2 moves 2 per radian:

    >>> from linkwright.mechanisms import FourBar, solve
    >>> m = FourBar(A0=[0, 0], B0=[4, 0], crank=2, coupler=4, rocker=3)
    >>> point_speed(solve(m, [0.3, 1.2]), "A").round(12)
    array([2., 2.])
    """
    if motion.velocities is None:
        raise ValueError("the motion has no velocities: solve it with order ≥ 1")
    speed: Array = np.linalg.norm(motion.velocities[joint], axis=-1)
    return speed

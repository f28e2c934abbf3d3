"""Analyses that apply to any linkage the engine can build: the geared five-bar, the double
slider, the six-bars and user-composed linkages.

A dyad's transmission angle is the angle at its joint between its two links (for a slider pin,
between the rod and the normal of the guide, as for the slider-crank). It is the quantity
paper 003 studies for the four-bar, taken dyad by dyad: near 0° or 180° the dyad is near its
limit position and transmits badly.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import DyadRRP, DyadRRR, Motion, SphereDyad, input_turns
from linkwright.engine.continuation import every_circuit
from linkwright.engine.plan import placed_joints
from linkwright.geometry import plane, sphere
from linkwright.mechanisms.base import Mechanism, circuit, input_range

__all__ = ["dyad_transmission_angles", "general_report", "point_speed"]

Array = NDArray[np.float64]
REPORT_SAMPLES = 2048


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
    return np.linalg.norm(motion.velocities[joint], axis=-1)


def _num(x: Any, digits: int = 12) -> float | None:
    v = float(x)
    return round(v, digits) if math.isfinite(v) else None


def _deg(x: Any) -> float | None:
    return _num(np.degrees(float(x)))


def _extreme(values: Any, largest: bool) -> float:
    """The least or greatest finite value, NaN when there is none (every sample at a toggle,
    say) rather than NumPy's all-NaN warning."""
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        return math.nan
    return float(finite.max() if largest else finite.min())


def general_report(mechanism: Mechanism, *, samples: int = REPORT_SAMPLES) -> dict[str, Any]:
    """The kinematic report of any single linkage the engine builds (degrees; JSON-ready).

    Keys: ``family``, ``assembles``, ``period_turns`` (input turns before the linkage repeats),
    ``input_turns_fully``, ``input_arcs_deg`` (absolute input angles), ``limit_positions``
    (each ``{"input_deg", "dyad"}``: exact roots, the dyad that reaches its limit there; for a
    linkage with a triad every limit of every circuit, ``{"input_deg", "triad", "circuit",
    "poses"}``: the two pose indices that merge there, as the circuit arrives and leaves),
    ``transmission_angle_deg`` (per dyad: ``min``, ``max`` over the circuit),
    ``traced`` (per traced joint: ``path_length``, ``speed_min``, ``speed_max`` per radian of
    input) and ``samples`` (how many circuit samples the extremes were read from: they are
    sampled, not refined, so good to about (period/samples)² of the curvature).
    """
    if mechanism.batch_shape != ():
        raise ValueError("a report is on one mechanism; index the batch first")
    plan = mechanism.plan
    arcs = input_range(mechanism)
    turns = int(input_turns(plan, mechanism.params(), points=mechanism.points))
    dyads = plan.dyads
    report: dict[str, Any] = {
        "family": mechanism.family,
        "assembles": not bool(arcs.never),
        "period_turns": turns,
        "input_turns_fully": bool(arcs.full),
    }
    finite = [
        (lo, hi, dl, dh)
        for lo, hi, dl, dh in zip(arcs.lo, arcs.hi, arcs.dyad_lo, arcs.dyad_hi, strict=True)
        if math.isfinite(lo)
    ]
    report["input_arcs_deg"] = [[_deg(lo), _deg(hi)] for lo, hi, _, _ in finite]
    report["limit_positions"] = [
        {"input_deg": _deg(x), "dyad": dyads[int(d)].name if d >= 0 else None}
        for lo, hi, dl, dh in finite
        for x, d in ((lo, dl), (hi, dh))
    ]
    if plan.triads:
        # A triad's configurations are followed: every limit of every circuit, where two of
        # its poses merge (the circuit may turn there more often than at its arc's ends).
        found = every_circuit(plan, mechanism.params(), 360, points=mechanism.points, order=0)
        report["circuits"] = len(found)
        report["limit_positions"] = [
            {
                "input_deg": _deg(limit.input),
                "triad": "".join(placed_joints(triad)),
                "circuit": k,
                "poses": [int(limit.before[triad.name]), int(limit.after[triad.name])],
            }
            for k, c in enumerate(found)
            for limit in c.limits
            for triad in plan.triads
            if limit.before[triad.name] != limit.after[triad.name]
        ]
    if arcs.never:
        report["reason"] = (
            "some dyad cannot close at any input"
            if not plan.triads
            else f"{plan.triads[0].unassembled()} at any input"
        )
        report["transmission_angle_deg"] = {d.name: {"min": None, "max": None} for d in dyads}
        report["traced"] = {
            j: {"path_length": None, "speed_min": None, "speed_max": None} for j in plan.traced
        }
        report["samples"] = 0
        return report
    motion = circuit(mechanism, samples, order=1)
    angles = dyad_transmission_angles(mechanism, motion)
    report["transmission_angle_deg"] = {
        name: {"min": _deg(_extreme(a, False)), "max": _deg(_extreme(a, True))}
        for name, a in angles.items()
    }
    traced: dict[str, Any] = {}
    for joint in plan.traced:
        pos = motion.positions[joint]
        closed = np.concatenate((pos, pos[:1]), axis=0)
        if plan.space == "sphere":  # arc length on the unit sphere, radians
            length = np.nansum(sphere.arc(closed[:-1], closed[1:]))
        else:
            length = np.nansum(plane.norm(np.diff(closed, axis=0)))
        speed = point_speed(motion, joint)
        traced[joint] = {
            "path_length": _num(length),
            "speed_min": _num(_extreme(speed, False)),
            "speed_max": _num(_extreme(speed, True)),
        }
    report["traced"] = traced
    report["samples"] = samples
    return report

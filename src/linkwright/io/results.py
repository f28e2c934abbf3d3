"""What ``solve`` and ``curve`` answer for a document: JSON-ready results in degrees.

The engine speaks radians and masks what it cannot place; these results are what the command
line and the workbench show: plain floats, degrees as a person would write them, ``None`` where
a joint has no position, and the step kind's sentence where a linkage cannot be assembled.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from linkwright.io.documents import Document
    from linkwright.mechanisms import Mechanism

__all__ = [
    "TRIAD_RULE",
    "NotAssembled",
    "curve_document",
    "ground_joints",
    "ground_xy",
    "solve_document",
    "structure",
    "triad_driven",
    "unassembled_reason",
    "xy",
]


class NotAssembled(ValueError):
    """The linkage cannot be assembled at any input, so it has no curve to trace."""


def xy(row: Any) -> list[float] | None:
    """A joint's coordinates as plain floats: [x, y] in the plane, the unit vector [x, y, z] on
    the sphere; None where it has none (NaN)."""
    values = [float(v) for v in row]
    return values if all(math.isfinite(v) for v in values) else None


def _own_signs(mech: Mechanism) -> tuple[int, ...]:
    import numpy as np

    params = mech.params()
    return tuple(int(np.asarray(params[d.branch])) for d in mech.plan.dyads)


def structure(mech: Mechanism) -> Any:
    """The mechanism's plan as a structure (its joints and links), whatever drives it.

    A Stephenson III driven at its output has no construction plan to evaluate, but its family's
    plan still says which joints are ground pivots.
    """
    from linkwright.mechanisms.sixbar import NoConstructionPlan

    try:
        return mech.plan
    except NoConstructionPlan:
        return type(mech).plan


def triad_driven(mech: Mechanism) -> bool:
    """A family driven so that a triad remains, its input word choosing the plan: the planar
    Stephenson III at its output link D0D or at C or D, the spherical one at FG, E or F (a
    composed linkage lists its configurations as any linkage does)."""
    from linkwright.engine.triad_steps import PlaneTriadKind, SphereTriadKind

    if not isinstance(getattr(mech, "input", None), str):
        return False
    return any(isinstance(s, PlaneTriadKind | SphereTriadKind) for s in structure(mech).steps)


def ground_joints(mech: Mechanism) -> tuple[str, ...]:
    from linkwright.engine import Fixed

    fixed = {s.name for s in structure(mech).steps if isinstance(s, Fixed)}
    return tuple(j for j in mech.reported_joints if j in fixed)


def unassembled_reason(mech: Mechanism, theta: float) -> str:
    """Why the mechanism cannot be assembled at input ``theta`` (radians): the sentence of the
    first step that fails where its parents are placed (the step kind's ``unassembled``).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> far = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> head, why = unassembled_reason(far, 0.0).split(": ", 1)
    >>> head
    'cannot be assembled at this input'
    >>> why
    'the coupler and rocker cannot reach (dyad B: |A B0| = 9 > coupler + rocker = 5)'
    """
    head = "cannot be assembled at this input"
    why = mech.plan.unassembled(mech.params(), theta, points=mech.points)
    return head if why is None else f"{head}: {why}"


def solve_document(
    doc: Document,
    degrees: Sequence[float],
    *,
    all_configurations: bool = False,
    derivatives: bool = False,
) -> dict[str, Any]:
    """The ``solve`` command's JSON-ready result for a document at inputs in degrees."""
    import numpy as np

    from linkwright.mechanisms import configurations, solve

    mech = doc.mechanism
    theta = np.radians(np.asarray(degrees, dtype=float))
    order = 2 if derivatives else 0
    if triad_driven(mech):
        return _solve_triad(doc, degrees, theta, derivatives, own=not all_configurations)
    if all_configurations and not derivatives and doc.family == "spherical-stephenson3":
        # Paper 001's analysis: every configuration with its error against every constraint.
        return _solve_triad(doc, degrees, theta, derivatives, own=False)
    if all_configurations:
        motions = configurations(mech, theta, order=order)
    else:
        motions = [(_own_signs(mech), solve(mech, theta, order=order))]
    joints = mech.reported_joints
    samples = []
    for i, deg in enumerate(degrees):
        found = []
        for signs, m in motions:
            if not bool(m.valid[..., i]):
                continue
            entry: dict[str, Any] = {
                "assembly": [int(s) for s in signs],
                "joints": {j: xy(m.positions[j][..., i, :]) for j in joints},
            }
            # Solved at order 2 when ``derivatives``: both are there.
            if derivatives and m.velocities is not None and m.accelerations is not None:
                entry["velocity"] = {j: xy(m.velocities[j][..., i, :]) for j in joints}
                entry["acceleration"] = {j: xy(m.accelerations[j][..., i, :]) for j in joints}
            found.append(entry)
        sample: dict[str, Any] = {"input_deg": float(deg), "configurations": found}
        if not found:
            sample["reason"] = unassembled_reason(mech, float(theta[i]))
        samples.append(sample)
    return {"family": doc.family, "samples": samples}


def _solve_triad(
    doc: Document, degrees: Sequence[float], theta: Any, derivatives: bool, *, own: bool
) -> dict[str, Any]:
    """The real configurations of a Stephenson III, each verified against every constraint:
    where its input leaves a triad, and for ``solve --all`` on the spherical one (paper 001's
    configuration analysis). With ``own``, only the document's configuration (see
    :data:`TRIAD_RULE`)."""
    import numpy as np

    from linkwright.engine import evaluate
    from linkwright.mechanisms import solve_all

    mech = doc.mechanism
    found = solve_all(mech, theta)
    rates = None
    if derivatives:
        # Each configuration solved again on its own branches (a triad's pose index, a dyad's
        # sign), with the derivatives of its differentiated constraints.
        rates = evaluate(
            mech.plan,
            mech.params(),
            np.broadcast_to(np.asarray(theta)[:, None], found.valid.shape),
            points=mech.points,
            branches=found.branches,
            order=2,
        )
    pose = int(np.asarray(getattr(mech, "pose", 0)))
    triad = mech.plan.triads[0].name if mech.plan.triads else None
    joints = mech.reported_joints
    samples = []
    for i, deg in enumerate(degrees):
        entries = []
        for k in range(found.valid.shape[-1]):
            if not bool(found.valid[i, k]):
                continue
            entry: dict[str, Any] = {
                "assembly": [int(found.assembly[i, k]), int(found.assembly2[i, k])],
                "residual": float(found.residual[i, k]),
                "joints": {j: xy(found.positions[j][i, k]) for j in joints},
            }
            if rates is not None and rates.velocities is not None:
                acc = rates.accelerations or {}  # order 2: there with the velocities
                entry["velocity"] = {j: xy(rates.velocities[j][i, k]) for j in joints}
                entry["acceleration"] = {j: xy(acc[j][i, k]) for j in joints}
            entries.append(entry)
        sample: dict[str, Any] = {"input_deg": float(deg), "configurations": entries}
        if own and triad is not None:
            # The document's configuration is its triad's pose index at this input (what the
            # plan solves, and what plot --at and the workbench show).
            mine = [
                e
                for k, e in zip(np.flatnonzero(found.valid[i]), entries, strict=True)
                if int(found.branches[triad][i, k]) == pose
            ]
            sample["configurations"] = mine
            if entries and not mine:
                sample["reason"] = (
                    f"the triad has {len(entries)} pose(s) at this input, no pose {pose} "
                    "(solve --all lists them)"
                )
        if not entries:
            sample["reason"] = unassembled_reason(mech, float(theta[i]))
        samples.append(sample)
    count = np.asarray(found.count)
    result: dict[str, Any] = {
        "family": doc.family,
        "input": getattr(mech, "input", "crank"),
        "max_configurations": int(count.max()) if count.size else 0,
    }
    if own and triad is not None:
        result["pose"] = pose
        result["rule"] = TRIAD_RULE[doc.family]
    result["samples"] = samples
    return result


# How `solve` without --all picks the document's configuration of a triad: its pose index, the
# one the plan solves. A name for one configuration at one input, stable (the same input gives
# the same answer) but not a branch followed continuously (curve and plot follow those).
TRIAD_RULE = {
    "stephenson3": (
        "the document's pose: the pose-th configuration at each input, in order of the "
        "coupler's angle (of B - A, from -180 to 180 degrees); solve --all lists every "
        "configuration"
    ),
    "spherical-stephenson3": (
        "the document's pose: the pose-th configuration at each input, in order of theta1 "
        "(angle BAD, from -180 to 180 degrees); solve --all lists every configuration"
    ),
}


def ground_xy(mech: Mechanism, joint: str) -> list[float] | None:
    import numpy as np

    from linkwright.engine import Fixed

    step = structure(mech).step(joint)
    if not isinstance(step, Fixed):
        return None
    return xy(np.asarray(mech.params()[step.at], dtype=float))


def curve_document(
    doc: Document, points: int = 360, *, spacing: str = "input", every: bool = False
) -> dict[str, Any]:
    """The ``curve`` command's JSON-ready result: the traced point over the closed circuit
    (``every``: over every circuit of every configuration, each with its limit positions)."""
    import numpy as np

    from linkwright.io.document_kinds import tidy_number
    from linkwright.mechanisms import circuit, circuits, input_range, running_circuit

    mech = doc.mechanism
    if every:
        return _every_curve(doc, points, spacing)
    if mech.plan.triads:
        # Its circuits are found together (none where it never assembles): the one it runs on.
        arcs, motions = circuits(mech, points, order=0, spacing=spacing)
        motion = motions[running_circuit(mech, points, spacing)] if motions else None
    else:
        arcs, motion = None, circuit(mech, points, order=0, spacing=spacing)
    if motion is None or not bool(np.any(motion.valid)):
        raise NotAssembled(f"{doc.family}: the linkage cannot be assembled at any input")
    joint = mech.traced_joint
    # The first branching step's label: a dyad's sign, a triad's closure sign (both change
    # only at a limit position).
    first = next(iter(motion.labels), None)
    if first is not None:
        branch = np.broadcast_to(motion.labels[first], motion.input.shape)
    else:
        branch = np.ones(motion.input.shape)
    return {
        "family": doc.family,
        "joint": joint,
        "closed": True,
        "full_turn": bool(np.all((input_range(mech) if arcs is None else arcs).full)),
        "points": [xy(p) for p in motion.positions[joint]],
        # Degrees as a person would write them: 30, not the 29.999999999999996 of a round trip.
        "input_deg": [tidy_number(float(d)) for d in np.degrees(motion.input)],
        "assembly": [int(b) for b in branch],
    }


def _every_curve(doc: Document, points: int, spacing: str) -> dict[str, Any]:
    """``curve --all``: every circuit of every configuration, followed by continuity through
    the limit positions where two configurations meet (a dyad's branches, a triad's poses)."""
    import numpy as np

    from linkwright.engine.circuits import input_turns
    from linkwright.engine.continuation import every_circuit
    from linkwright.io.document_kinds import tidy_number

    mech = doc.mechanism
    params = mech.params()
    turns = int(np.max(input_turns(mech.plan, params, points=mech.points)))
    found = every_circuit(
        mech.plan,
        params,
        points,
        points=mech.points,
        order=0,
        period=2.0 * np.pi * turns,
        spacing=spacing,
    )
    if not found:
        raise NotAssembled(f"{doc.family}: the linkage cannot be assembled at any input")
    joint = mech.traced_joint
    pieces = []
    for c in found:
        motion = c.motion
        first = next(iter(motion.labels), None)
        branch = motion.labels[first] if first is not None else np.ones(motion.input.shape)
        pieces.append(
            {
                "full_turn": c.full,
                "points": [xy(p) for p in motion.positions[joint]],
                "input_deg": [tidy_number(float(d)) for d in np.degrees(motion.input)],
                "assembly": [int(b) for b in np.broadcast_to(branch, motion.input.shape)],
                # Where two configurations meet: the branch values (dyad signs, triad pose
                # indices) met before and after the turn, as the circuit runs.
                "limits": [
                    {
                        "input_deg": tidy_number(math.degrees(lim.input)),
                        "before": {k: int(v) for k, v in lim.before.items()},
                        "after": {k: int(v) for k, v in lim.after.items()},
                    }
                    for lim in c.limits
                ],
            }
        )
    return {"family": doc.family, "joint": joint, "closed": True, "circuits": pieces}

"""Where a Stephenson III can be driven: one construction plan for each of its seven joints.

The planar Stephenson III (:class:`~linkwright.mechanisms.Stephenson3`, paper 001's topology in
the plane) has the frame A0 B0 D0 and the coupler A B C as its ternaries, joined by the crank
A0A, the rocker B0B and the chain C–D–D0. A motor may sit at any of its seven joints:

========  =============================================  =======================================
input     θ is                                           plan
========  =============================================  =======================================
crank     the angle of A − A0 from +x                    four-bar, C, then the dyad D
rocker    the angle of B − B0 from +x                    the four-bar from its rocker, C, dyad D
output    the angle of D − D0 from +x                    crank D, then the triad A B C
A         the angle at A from A→A0 to A→B                a driven hinge (A, B), C, dyad D
B         the angle at B from B→B0 to B→A                a driven hinge (B, A), C, dyad D
C         the angle of C→D from the coupler's line A→B   the triad A B D with D turning on it
D         the angle at D from D→D0 to D→C                the triad A B C with a hinge in C–D0
========  =============================================  =======================================

Angles are counter-clockwise. The branch words follow the plan: ``assembly`` is the sign of
the dyad that closes the four-bar (B from A and B0 on the crank, A from B and A0 on the rocker;
not used by the others), ``assembly2`` the dyad D (crank, rocker, A, B), ``pose`` the hinge's
side of X (0 or 1, at A and B: :class:`~linkwright.engine.hinge_steps.Hinge`) or the triad's
pose index (0 to 5, output, C and D). The constraints are the same whatever drives the linkage.
"""

from __future__ import annotations

from linkwright.engine import Crank, DyadRRR, Fixed, Plan, Rigid
from linkwright.engine.hinge_steps import Hinge
from linkwright.engine.hinge_triad_steps import BodyHingeTriad, LegHingeTriad
from linkwright.engine.plan import Step
from linkwright.engine.triad_steps import Triad

__all__ = ["DRIVEN_ANGLES", "INPUTS", "PLANS"]

_FRAME = (Fixed("A0", "A0"), Fixed("B0", "B0"), Fixed("D0", "D0"))
_C = Rigid("C", "A", "B", "u1", "v1")
_D = DyadRRR("D", "C", "link1", "D0", "link2", branch="assembly2")
_POINT = Rigid("P", "C", "D", "u", "v")


def _plan(*steps: Step) -> Plan:
    return Plan((*_FRAME, *steps, _POINT), traced=("P",))


PLANS: dict[str, Plan] = {
    "crank": _plan(
        Crank("A", "A0", "crank"),
        DyadRRR("B", "A", "coupler", "B0", "rocker", branch="assembly"),
        _C,
        _D,
    ),
    "output": _plan(
        Crank("D", "D0", "link2"),
        # The coupler ABC, held by the crank, the rocker and the link CD, is a triad.
        Triad(
            ("A", "B", "C"), ("A0", "B0", "D"), ("crank", "rocker", "link1"), "coupler", "u1", "v1"
        ),
    ),
    "rocker": _plan(
        Crank("B", "B0", "rocker"),
        DyadRRR("A", "B", "coupler", "A0", "crank", branch="assembly"),
        _C,
        _D,
    ),
    "A": _plan(Hinge("A", "B", "B0", "rocker", "A0", "coupler", "crank"), _C, _D),
    "B": _plan(Hinge("B", "A", "A0", "crank", "B0", "coupler", "rocker"), _C, _D),
    "C": _plan(
        BodyHingeTriad(
            ("A", "B", "D", "C"),
            ("A0", "B0", "D0"),
            ("crank", "rocker", "link2"),
            "coupler",
            "u1",
            "v1",
            "link1",
        ),
    ),
    "D": _plan(
        LegHingeTriad(
            ("A", "B", "C", "D"),
            ("A0", "B0", "D0"),
            ("crank", "rocker"),
            "coupler",
            "u1",
            "v1",
            "link1",
            "link2",
        ),
    ),
}
"""The plan of each input, in the order of the module's table (the crank's first: the
family's structure)."""

INPUTS = tuple(PLANS)

DRIVEN_ANGLES: dict[str, tuple[str, str, str, str, str]] = {
    "crank": ("A0", "", "", "A", "crank"),
    "rocker": ("B0", "", "", "B", "rocker"),
    "output": ("D0", "", "", "D", "link2"),
    "A": ("A", "A", "A0", "B", "coupler"),
    "B": ("B", "B", "B0", "A", "coupler"),
    "C": ("C", "A", "B", "D", "link1"),
    "D": ("D", "D", "D0", "C", "link1"),
}
"""How each input's θ is measured, for the input's residual: (vertex, from, to, joint, arm):
the joint lies at the arm's length from the vertex, at θ from the direction from → to (+x where
those are empty)."""

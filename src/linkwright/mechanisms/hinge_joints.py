"""Triads driven at a hinge, as joint specs of a composed linkage.

A :class:`~linkwright.mechanisms.joints.HingeJoint` drives a hinge of a loop that a dyad closes.
A hinge of a loop that only a triad closes is written with the triad itself
(:mod:`linkwright.engine.hinge_triad_steps`):

===========================  ================  ===============================================
spec                         ``type``          the driven hinge ``hinge`` (H)
===========================  ================  ===============================================
HingeTriadJoint              ``hinge-triad``   in the third leg: p3–H–J3, |H J3| = ``a``,
                                               |H p3| = ``b``, the angle at H from H→p3 to
                                               H→J3 equal to ``phase + θ``
TurningTriadJoint            ``turning-triad`` on the ternary link, at (``hu``, ``hv``) in its
                                               frame (origin J1, x towards J2); J3 at ``arm``
                                               from H, at ``phase + θ`` from that x axis
===========================  ================  ===============================================

On the sphere (``space = "sphere"``) the same types are :class:`SphereHingeTriadJoint` (the
body as a :class:`~linkwright.mechanisms.joints.SphereTriadJoint`'s, the hinge's links arcs,
the angle about +O·H from the great circle H→p3 to H→J3) and :class:`SphereTurningTriadJoint`
(H at arc ``harc`` from J1, turned by ``hangle`` from the great circle J1→J2; J3 at arc ``arm``
from H, at ``phase + θ`` from the great circle H→J1, right-handed about +O·H). Either is the
linkage's one input, as a driven hinge is; ``pose`` is the triad's pose index.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

from numpy.typing import ArrayLike

from linkwright.engine.hinge_triad_steps import (
    BodyHingeTriad,
    LegHingeTriad,
    SphereBodyHingeTriad,
    SphereLegHingeTriad,
)
from linkwright.engine.state import Step
from linkwright.mechanisms.joint_base import TriadSpec

Key = Callable[[str], str]
"""A linkage's name for one of a joint's numbers (``key("a")`` is ``"A.a"``), which it records
as a plan parameter."""

__all__ = [
    "HINGED_TRIADS",
    "HingeTriadJoint",
    "SphereHingeTriadJoint",
    "SphereTurningTriadJoint",
    "TurningTriadJoint",
]


class _HingedTriad(TriadSpec):
    """A triad spec that also places its driven hinge."""

    hinge: str

    @property
    def placed(self) -> tuple[str, str, str, str]:
        """The joints it places: J1 (its name), J2, J3 and the hinge."""
        return (self.name, self.j2, self.j3, self.hinge)

    @property
    def anchors(self) -> tuple[str, str, str]:
        """The placed joints it hangs from: p1, p2, p3."""
        return (self.p1, self.p2, self.p3)

    def step(self, key: Key) -> Step:
        """The plan step that places its joints, its numbers named by ``key``."""
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class HingeTriadJoint(_HingedTriad):
    """A triad driven at a hinge in its third leg: the ternary link J1 J2 J3 (``name``,
    ``j2``, ``j3``) held by links ``r1`` from ``p1`` and ``r2`` from ``p2``, and by the chain
    p3–H–J3 (H = ``hinge``), |H p3| = ``b`` and |H J3| = ``a``, whose angle at H, from H→p3 to
    H→J3 counter-clockwise, is ``phase + θ``. The link's shape as a
    :class:`~linkwright.mechanisms.joints.TriadJoint`'s.

    Examples
    --------
    The Stephenson III driven at D, between its links CD and D0D: every link keeps its length.

    >>> import numpy as np
    >>> from linkwright import Linkage, configurations
    >>> from linkwright.mechanisms.joints import FixedJoint
    >>> joints = [FixedJoint("A0", [0, 0]), FixedJoint("B0", [4, 0]), FixedJoint("D0", [2, -4]),
    ...           HingeTriadJoint("A", "B", "C", "D", "A0", 1.0, "B0", 4.0, "D0", a=3.0, b=6.0,
    ...                           side=5.0, u=4.0, v=-2.0)]
    >>> found = configurations(Linkage(joints=joints), [np.pi / 2])
    >>> p = next(m for _, m in found if m.valid[0]).positions
    >>> [round(float(np.hypot(*(p[j][0] - p[k][0]))), 12)
    ...  for j, k in (("A", "A0"), ("B", "B0"), ("C", "D"), ("D", "D0"), ("A", "B"))]
    [1.0, 4.0, 3.0, 6.0, 5.0]
    """

    name: str
    j2: str
    j3: str
    hinge: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    a: ArrayLike
    b: ArrayLike
    side: ArrayLike
    u: ArrayLike = 0.0
    v: ArrayLike = 0.0
    phase: ArrayLike = 0.0
    pose: ArrayLike = 0.0

    type: ClassVar[str] = "hinge-triad"

    def step(self, key: Key) -> Step:
        body = (key("side"), key("u"), key("v"), key("a"), key("b"), key("phase"))
        return LegHingeTriad(self.placed, self.anchors, (key("r1"), key("r2")), *body, key("pose"))


@dataclass(frozen=True, eq=False)
class SphereHingeTriadJoint(_HingedTriad):
    """The spherical :class:`HingeTriadJoint`: arcs for lengths, the body as a
    :class:`~linkwright.mechanisms.joints.SphereTriadJoint`'s (J2 at arc ``side`` from J1, J3
    at arc ``arc`` turned by ``angle``), the angle at H about +O·H from the great circle H→p3
    to H→J3."""

    name: str
    j2: str
    j3: str
    hinge: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    a: ArrayLike
    b: ArrayLike
    side: ArrayLike
    arc: ArrayLike = 0.0
    angle: ArrayLike = 0.0
    phase: ArrayLike = 0.0
    pose: ArrayLike = 0.0

    type: ClassVar[str] = "hinge-triad"

    def step(self, key: Key) -> Step:
        body = (key("side"), key("arc"), key("angle"), key("a"), key("b"), key("phase"))
        legs = (key("r1"), key("r2"))
        return SphereLegHingeTriad(self.placed, self.anchors, legs, *body, key("pose"))


@dataclass(frozen=True, eq=False)
class TurningTriadJoint(_HingedTriad):
    """A triad driven at a hinge on its ternary link: the link J1 J2 H (``name``, ``j2``,
    ``hinge``), J2 at ``side`` from J1 and H at (``hu``, ``hv``) in the frame with origin J1 and
    x axis towards J2, carries the link H–J3 (``arm``), turned to ``phase + θ`` from that x axis;
    J1, J2 and J3 hang from ``p1``, ``p2``, ``p3`` by links ``r1``, ``r2``, ``r3``.

    Examples
    --------
    The Stephenson III driven at C, where its link CD turns on the coupler:

    >>> import numpy as np
    >>> from linkwright import Linkage, configurations
    >>> from linkwright.mechanisms.joints import FixedJoint
    >>> joints = [FixedJoint("A0", [0, 0]), FixedJoint("B0", [4, 0]), FixedJoint("D0", [2, -4]),
    ...           TurningTriadJoint("A", "B", "D", "C", "A0", 1.0, "B0", 4.0, "D0", 6.0,
    ...                             side=5.0, hu=4.0, hv=-2.0, arm=3.0)]
    >>> found = configurations(Linkage(joints=joints), [np.pi - np.arctan2(4.0, 3.0)])
    >>> max((m.positions["A"][0].round(9) + 0).tolist() for _, m in found if m.valid[0])
    [1.0, 0.0]
    """

    name: str
    j2: str
    j3: str
    hinge: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    r3: ArrayLike
    side: ArrayLike
    hu: ArrayLike
    hv: ArrayLike
    arm: ArrayLike
    phase: ArrayLike = 0.0
    pose: ArrayLike = 0.0

    type: ClassVar[str] = "turning-triad"

    def step(self, key: Key) -> Step:
        body = (key("side"), key("hu"), key("hv"), key("arm"), key("phase"))
        legs = (key("r1"), key("r2"), key("r3"))
        return BodyHingeTriad(self.placed, self.anchors, legs, *body, key("pose"))


@dataclass(frozen=True, eq=False)
class SphereTurningTriadJoint(_HingedTriad):
    """The spherical :class:`TurningTriadJoint`: H at arc ``harc`` from J1 (strictly between
    0 and π), turned by ``hangle`` from the great circle J1→J2 (right-handed about +O·J1); J3
    at arc ``arm`` from H, at ``phase + θ`` from the great circle H→J1, right-handed about
    +O·H."""

    name: str
    j2: str
    j3: str
    hinge: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    r3: ArrayLike
    side: ArrayLike
    harc: ArrayLike
    hangle: ArrayLike
    arm: ArrayLike
    phase: ArrayLike = 0.0
    pose: ArrayLike = 0.0

    type: ClassVar[str] = "turning-triad"

    def step(self, key: Key) -> Step:
        body = (key("side"), key("harc"), key("hangle"), key("arm"), key("phase"))
        legs = (key("r1"), key("r2"), key("r3"))
        return SphereBodyHingeTriad(self.placed, self.anchors, legs, *body, key("pose"))


HINGED_TRIADS = (
    HingeTriadJoint,
    SphereHingeTriadJoint,
    TurningTriadJoint,
    SphereTurningTriadJoint,
)
"""Every triad spec driven at a hinge: each the linkage's one input, in place of a crank."""

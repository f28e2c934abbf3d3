"""The joint specs a composed :class:`~linkwright.mechanisms.linkage.Linkage` is written with.

Each spec places one joint from joints listed before it, exactly as the engine's construction
plans do (see DESIGN.md). In the plane (``space = "plane"``, the default):

==============  ============  ====================================================================
spec            ``type``      places
==============  ============  ====================================================================
FixedJoint      ``fixed``     a ground pivot at ``at`` = [x, y]
CrankJoint      ``crank``     a joint at ``length`` from ``pivot``, at the absolute angle
                              ``phase + ratio·θ`` (θ the input; every crank is driven by it)
DyadJoint       ``rrr``       the pin of two binary links: circle(p1, r1) ∩ circle(p2, r2)
SliderJoint     ``rrp``       a slider pin: circle(p1, r) ∩ the line through joint
                              ``line_point`` at ``line_angle`` (a guide of fixed direction)
RigidJoint      ``rigid``     a point fixed on the link ``origin``→``toward`` at local (u, v)
HingeJoint      ``hinge``     the linkage driven at a moving hinge: the joint ``name`` (H) and
                              the joint ``far`` (X), with |X z| = ``r``, |H X| = ``a``,
                              |H y| = ``b`` and the angle at H from H→y to H→X equal to
                              ``phase + θ`` (in place of a crank)
TriadJoint      ``triad``     the three joints of a ternary link at once (a triad, an Assur
                              group of class III): ``name`` (J1), ``j2``, ``j3``, held by
                              binary links of lengths ``r1``, ``r2``, ``r3`` to the placed joints
                              ``p1``, ``p2``, ``p3``; J2 at ``side`` from J1 and J3 at (``u``,
                              ``v``) in the frame of J1→J2; ``pose`` picks one of its poses
==============  ============  ====================================================================

A triad driven at a hinge of its own loop is written ``hinge-triad`` (the hinge in its third
leg) or ``turning-triad`` (a link turning on its ternary link): :mod:`.hinge_joints`.

On the sphere (``space = "sphere"``) every joint is a revolute whose axis passes through the
centre O of the unit sphere; a joint is the unit vector along its axis and a link's length is
the arc (central angle, radians) between its joints' axes:

================  ==========  ==================================================================
spec              ``type``    places
================  ==========  ==================================================================
FixedJoint        ``fixed``   a ground pivot on the axis ``at`` = [x, y, z] (any non-zero vector:
                              the joint is its direction, the unit vector ``at / |at|``)
SphereCrankJoint  ``crank``   a joint at arc ``arc`` from the fixed joint ``pivot``, at angle
                              ``phase + ratio·θ`` about +O·pivot from the great circle that
                              runs from the pivot towards the fixed joint ``toward``
DyadJoint         ``rrr``     the pin of two binary links: the small circles of arcs r1 about
                              p1 and r2 about p2 meet
SphereRigidJoint  ``rigid``   a point at arc ``arc`` from ``origin``, at ``angle`` from the
                              great circle origin→toward (right-handed about +O·origin)
HingeJoint        ``hinge``   as in the plane, its lengths arcs and the angle at H between
                              great circles, right-handed about +O·H
SphereTriadJoint  ``triad``   as in the plane, its lengths arcs: J2 at arc ``side`` from J1, J3
                              at arc ``arc`` from J1, at ``angle`` from the great circle J1→J2
                              (right-handed about +O·J1, as a rigid point is placed)
================  ==========  ==================================================================

A slider has no spherical counterpart of its own: a pin whose guide is a great circle is an
``rrr`` dyad whose second link, 90° long, turns about the guide's pole, and is written so.

Angles are radians here (documents speak degrees). Assembly signs are the engine's: a dyad
joint J placed from P1 then P2 has ``assembly = sign((P2 − P1) × (J − P1))`` in the plane
(+1: J to the left of P1→P2) and ``sign((P1 × P2)·J)`` on the sphere (the same side, seen from
outside the sphere); a slider pin B has ``assembly = sign((B − H)·d)``, H the foot of P1 on the
guide and d = (cos line_angle, sin line_angle). Planar rigid points sit at (u, v) in the frame
with origin ``origin`` and x axis towards ``toward`` (v to the left).

A triad has no sign that tells its poses apart along the motion (up to 6 in the plane, 8 on the
sphere); its ``pose`` is the engine's pose index, as the Stephenson III families write theirs:
the slot of the pose at each input in the order of the body's rotation (the direction of
J1→J2) in the plane, and of J2's angle on its circle about p2, from the great circle p2→p1,
on the sphere (:mod:`linkwright.engine.triad_steps`). It names one configuration at one input;
the circuit tracer follows a pose from there by continuity.

This module holds the specs, the tables that map a document's ``type`` to them, what kind of
number each field must be (:func:`numeric_kinds`) and the linkage's error
(:class:`InvalidLinkage`); :mod:`.linkage_checks` checks them and :mod:`.linkage` composes them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.geometry import sphere
from linkwright.mechanisms.base import InvalidMechanism
from linkwright.mechanisms.hinge_joints import (
    HingeTriadJoint,
    SphereHingeTriadJoint,
    SphereTurningTriadJoint,
    TurningTriadJoint,
)
from linkwright.mechanisms.joint_base import JointSpec as _Spec
from linkwright.mechanisms.joint_base import TriadSpec as _TriadSpec

__all__ = [
    "ALL_SPECS",
    "JOINT_TYPES",
    "PLACES",
    "REFERENCES",
    "SPACES",
    "SPHERE_JOINT_TYPES",
    "CrankJoint",
    "DyadJoint",
    "FixedJoint",
    "HingeJoint",
    "InvalidLinkage",
    "Joint",
    "RigidJoint",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereRigidJoint",
    "SphereTriadJoint",
    "TriadJoint",
    "numeric_kinds",
    "placed_by",
    "unit_axis",
]

Array = NDArray[np.float64]


class InvalidLinkage(InvalidMechanism):
    """A composed linkage is ill-formed; says which joint (or ``traced``) and what is wrong.

    Attributes
    ----------
    index : int or None
        Position of the offending joint in ``joints`` (None for problems of the whole linkage).
    joint : str or None
        Its name, when it has a usable one.
    field : str or None
        The joint's field at fault (``"r1"``), or ``"traced"``, or None for structural problems.
    problem : str
        The message (it names the joint itself, so it reads alone).
    """

    # Its public home stays the family's module: tracebacks and pickles name it from there.
    __module__ = "linkwright.mechanisms.linkage"

    def __init__(
        self,
        problem: str,
        *,
        index: int | None = None,
        joint: str | None = None,
        field: str | None = None,
    ) -> None:
        self.index = index
        self.joint = joint
        self.field = field
        self.problem = problem
        super().__init__(problem)


# --------------------------------------------------------------------------------------------
# Joint specs
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FixedJoint(_Spec):
    """A ground pivot.

    Parameters
    ----------
    name : the joint's name.
    at : in the plane its place [x, y] (or a batch of places, shape ``batch + (2,)``); on the
        sphere its axis [x, y, z], any non-zero vector along it (shape ``batch + (3,)``): the
        joint is the unit vector ``at / |at|``, so ``[0, 0, 1]`` and ``[1, 1, 0]`` can be
        written as such. The spec keeps the vector as given.

    Examples
    --------
    >>> from linkwright import Linkage, solve
    >>> ground = [FixedJoint("O", [0, 0]), FixedJoint("B0", [3, 0])]
    >>> arm = [CrankJoint("A", "O", 1.0), DyadJoint("B", "A", 3.0, "B0", 2.0)]
    >>> solve(Linkage(joints=ground + arm), [0.0]).positions["O"].tolist()
    [[0.0, 0.0]]

    A name used twice is refused, naming both places:

    >>> Linkage(joints=ground + [FixedJoint("O", [1, 1])] + arm)
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'O' is listed twice (joints[0] and \
joints[2]); each joint needs its own name
    """

    name: str
    at: ArrayLike

    type: ClassVar[str] = "fixed"
    parents: ClassVar[tuple[str, ...]] = ()


@dataclass(frozen=True, eq=False)
class CrankJoint(_Spec):
    """A joint driven by the input: at ``length`` from ``pivot``, at angle ``phase + ratio·θ``.

    The angle is absolute (from +x, counter-clockwise, radians). ``pivot`` is usually a fixed
    joint; a placed moving joint is allowed too (a gear carried by a link: its arm still turns
    with the input against the ground). ``ratio`` must be nonzero (a crank that does not turn
    drives nothing).

    Examples
    --------
    >>> from linkwright import Linkage, solve
    >>> joints = [FixedJoint("O", [0, 0]), CrankJoint("A", "O", 2.0, phase=0.5)]
    >>> solve(Linkage(joints=joints), [0.0]).positions["A"].round(6).tolist()
    [[1.755165, 0.958851]]

    A crank about a joint that is not placed before it is refused:

    >>> Linkage(joints=[CrankJoint("A", "O", 2.0), FixedJoint("O", [0, 0])])
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'A' is built from 'O', which is not placed \
before it (it is listed after it; under-constrained)
    """

    name: str
    pivot: str
    length: ArrayLike
    ratio: ArrayLike = 1.0
    phase: ArrayLike = 0.0

    type: ClassVar[str] = "crank"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.pivot,)


@dataclass(frozen=True, eq=False)
class DyadJoint(_Spec):
    """The pin of two binary links (an RRR dyad): at ``r1`` from ``p1`` and ``r2`` from ``p2``.

    In the plane ``assembly`` is ``sign((p2 − p1) × (J − p1))``: +1 when the joint lies to the
    left of the line from p1 to p2. On the sphere ``r1`` and ``r2`` are arcs (radians, strictly
    between 0 and π) and ``assembly`` is ``sign((p1 × p2)·J)``: +1 when J lies to the left of
    the great circle p1→p2 seen from outside the sphere.

    Examples
    --------
    B lies at 3 from A and 2 from B0; with links too short it does not assemble:

    >>> import numpy as np
    >>> from linkwright import Linkage, solve
    >>> ground = [FixedJoint("O", [0, 0]), FixedJoint("B0", [3, 0]), CrankJoint("A", "O", 1.0)]
    >>> B = solve(Linkage(joints=ground + [DyadJoint("B", "A", 3.0, "B0", 2.0)]), [0.0])
    >>> B.positions["B"].round(6).tolist()
    [[3.25, 1.984313]]
    >>> short = Linkage(joints=ground + [DyadJoint("B", "A", 0.5, "B0", 0.5)])
    >>> bool(solve(short, [0.0]).valid.any())
    False
    """

    name: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    assembly: ArrayLike = 1.0

    type: ClassVar[str] = "rrr"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.p2)


@dataclass(frozen=True, eq=False)
class HingeJoint(_Spec):
    """The input at a moving hinge: joints ``name`` (the hinge H) and ``far`` (X) at once.

    A motor between two moving links turns the angle at H, from its link to ``y`` (length
    ``b``) to its link to X (length ``a``), through ``phase + θ``; X hangs from ``z`` by a link
    of length ``r`` (:class:`linkwright.engine.hinge_steps.Hinge`). ``assembly`` is X's side:
    ``sign((y − z) × (X − z))``, as a dyad's. A linkage with a hinge has no crank: the hinge is
    its input.

    Examples
    --------
    A four-bar driven at its coupler–rocker hinge B: the angle at B is the input.

    >>> import numpy as np
    >>> from linkwright import Linkage, solve
    >>> hinge = Linkage(joints=[FixedJoint("A0", [0, 0]), FixedJoint("B0", [4, 0]),
    ...                         HingeJoint("B", "A", "A0", 1.0, "B0", 3.5, 3.0)], traced="B")
    >>> m = solve(hinge, [np.pi / 2])
    >>> float(np.hypot(*m.positions["A"][0]).round(12)), bool(m.valid[0])
    (1.0, True)

    A hinge is the linkage's one input: a crank beside it is refused:

    >>> Linkage(joints=[FixedJoint("A0", [0, 0]), FixedJoint("B0", [4, 0]),
    ...                 HingeJoint("B", "A", "A0", 1.0, "B0", 3.5, 3.0),
    ...                 CrankJoint("C", "A0", 1.0)])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'C': the hinge 'B' already drives the ...
    """

    name: str
    far: str
    z: str
    r: ArrayLike
    y: str
    a: ArrayLike
    b: ArrayLike
    phase: ArrayLike = 0.0
    assembly: ArrayLike = 1.0

    type: ClassVar[str] = "hinge"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.z, self.y)

    @property
    def placed(self) -> tuple[str, ...]:
        """The joints it places: the hinge, then X."""
        return (self.name, self.far)


@dataclass(frozen=True, eq=False)
class SliderJoint(_Spec):
    """A slider pin (an RRP dyad): at ``r`` from ``p1``, on the guide line through the joint
    ``line_point`` at the fixed absolute angle ``line_angle`` (radians).

    ``assembly`` is ``sign((B − H)·d)``, H the foot of p1 on the guide, d its direction.

    Examples
    --------
    >>> from linkwright import Linkage, solve
    >>> joints = [FixedJoint("O", [0, 0]), FixedJoint("G", [0, -0.5]),
    ...           CrankJoint("A", "O", 1.0), SliderJoint("B", "A", 2.5, "G", 0.0)]
    >>> solve(Linkage(joints=joints), [0.0]).positions["B"].round(6).tolist()
    [[3.44949, -0.5]]

    A rod too short to reach its guide leaves the slider unassembled there:

    >>> short = joints[:3] + [SliderJoint("B", "A", 0.2, "G", 0.0)]
    >>> bool(solve(Linkage(joints=short), [0.0]).valid[0])
    False
    """

    name: str
    p1: str
    r: ArrayLike
    line_point: str
    line_angle: ArrayLike
    assembly: ArrayLike = 1.0

    type: ClassVar[str] = "rrp"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.line_point)


@dataclass(frozen=True, eq=False)
class RigidJoint(_Spec):
    """A point fixed on the link ``origin``→``toward``: local (u, v), x along the link, v left.

    ``origin`` and ``toward`` must be two joints of one rigid link (their distance constant).

    Examples
    --------
    >>> from linkwright import Linkage, solve
    >>> joints = [FixedJoint("O", [0, 0]), CrankJoint("A", "O", 1.0),
    ...           RigidJoint("P", "O", "A", u=2.0, v=0.0)]
    >>> solve(Linkage(joints=joints), [0.0]).positions["P"].tolist()
    [[2.0, 0.0]]

    A point fixed on two joints of different links is refused (their distance changes):

    >>> two = [FixedJoint("O", [0, 0]), FixedJoint("Q", [3, 0]), CrankJoint("A", "O", 1.0),
    ...        RigidJoint("P", "Q", "A", u=1.0, v=0.0)]
    >>> Linkage(joints=two)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'P' is fixed on the link 'Q'→'A', but ...
    """

    name: str
    origin: str
    toward: str
    u: ArrayLike = 0.0
    v: ArrayLike = 0.0

    type: ClassVar[str] = "rigid"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.origin, self.toward)


@dataclass(frozen=True, eq=False)
class SphereCrankJoint(_Spec):
    """A spherical crank: at arc ``arc`` from the fixed joint ``pivot``, turned by the input.

    Its angle ``phase + ratio·θ`` is measured right-handed about +O·pivot from the great circle
    that runs from the pivot towards the fixed joint ``toward``. ``toward`` defaults to the first
    fixed joint listed before the crank other than its pivot; the linkage stores the name it
    resolved to. Paper 000's crank (A0 = (1, 0, 0), A = (cos a2, sin a2 cos θ, sin a2 sin θ)) is
    ``SphereCrankJoint("A", "A0", a2, toward="B0")`` with B0 on the frame circle at a1 > 0.
    ``arc`` lies strictly between 0 and π; ``ratio`` must be nonzero.

    Examples
    --------
    Paper 000's crank: A = (cos a2, sin a2 cos θ, sin a2 sin θ) about A0 = (1, 0, 0).

    >>> import numpy as np
    >>> from linkwright import Linkage, solve
    >>> joints = [FixedJoint("A0", [1, 0, 0]), FixedJoint("B0", [0, 1, 0]),
    ...           SphereCrankJoint("A", "A0", 0.4, toward="B0")]
    >>> A = solve(Linkage(joints=joints, space="sphere"), [0.3]).positions["A"][0]
    >>> bool(np.allclose(A, [np.cos(0.4), np.sin(0.4) * np.cos(0.3), np.sin(0.4) * np.sin(0.3)]))
    True

    Its pivot must be a fixed joint: a crank about a moving one is refused:

    >>> Linkage(joints=joints + [SphereCrankJoint("C", "A", 0.2, toward="B0")],
    ...         space="sphere")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: ...
    """

    name: str
    pivot: str
    arc: ArrayLike
    ratio: ArrayLike = 1.0
    phase: ArrayLike = 0.0
    toward: str | None = None

    type: ClassVar[str] = "crank"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.pivot,)


@dataclass(frozen=True, eq=False)
class SphereRigidJoint(_Spec):
    """A point fixed on the spherical link ``origin``→``toward``: at arc ``arc`` from the
    origin (0 to π), at ``angle`` from the great circle origin→toward, right-handed about
    +O·origin (paper 000's coupler point C, with arc AC and angle μ = BAC).

    ``origin`` and ``toward`` must be two joints of one rigid link.

    Examples
    --------
    A point at arc 0.5 from A on its link stays at that arc from A:

    >>> import numpy as np
    >>> from linkwright import Linkage, solve
    >>> joints = [FixedJoint("A0", [1, 0, 0]), FixedJoint("B0", [np.cos(1.2), np.sin(1.2), 0]),
    ...           SphereCrankJoint("A", "A0", 0.4), DyadJoint("B", "A", 1.0, "B0", 0.9),
    ...           SphereRigidJoint("C", "A", "B", arc=0.5, angle=0.3)]
    >>> p = solve(Linkage(joints=joints, space="sphere"), [0.3]).positions
    >>> round(float(np.arccos(p["A"][0] @ p["C"][0])), 12)
    0.5

    On two joints that are not on one link it is refused:

    >>> Linkage(joints=joints[:3] + [SphereRigidJoint("C", "A", "B0", arc=0.5)],
    ...         space="sphere")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'C' is fixed on the link 'A'→'B0', but ...
    """

    name: str
    origin: str
    toward: str
    arc: ArrayLike = 0.0
    angle: ArrayLike = 0.0

    type: ClassVar[str] = "rigid"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.origin, self.toward)


@dataclass(frozen=True, eq=False)
class TriadJoint(_TriadSpec):
    """A ternary link J1 J2 J3 (``name``, ``j2``, ``j3``) held by three binary links: J_k at
    ``r_k`` from the placed joint ``p_k``. A triad (an Assur group of class III) places all
    three at once, where no dyad can place any one of them (a Stephenson III driven at its
    output, for one).

    The link's shape: J2 at ``side`` from J1, J3 at (``u``, ``v``) in the frame with origin
    J1 and x axis towards J2 (v to the left). ``pose`` is the engine's pose index, 0 to 5:
    the slot of the pose at each input in the order of the direction of J1→J2
    (:class:`~linkwright.engine.triad_steps.Triad`).

    Examples
    --------
    The Stephenson III six-bar driven at its output link D0D: its coupler ABC is held by the
    crank A0A, the rocker B0B and the link CD. At θ = 90° it has two poses; each holds every
    link to its length:

    >>> import numpy as np
    >>> from linkwright import Linkage, configurations
    >>> joints = [FixedJoint("A0", [0, 0]), FixedJoint("B0", [4, 0]),
    ...           FixedJoint("D0", [0, 2.8]), CrankJoint("D", "D0", 1.0),
    ...           TriadJoint("A", "B", "C", "A0", 1.0, "B0", 3.0, "D", 0.7,
    ...                      side=4.0, u=2.0, v=2.0)]
    >>> found = configurations(Linkage(joints=joints), [np.pi / 2])
    >>> [bool(motion.valid[0]) for _, motion in found]
    [True, True, False, False, False, False]
    >>> p = found[1][1].positions
    >>> [round(float(np.hypot(*(p[j][0] - p[k][0]))), 12)
    ...  for j, k in (("A", "A0"), ("B", "B0"), ("C", "D"), ("A", "B"))]
    [1.0, 3.0, 0.7, 4.0]

    Its other two joints are new joints, named once:

    >>> Linkage(joints=joints[:4] + [TriadJoint("A", "B", "D", "A0", 1.0, "B0", 3.0, "D0",
    ...                                         0.7, side=4.0, u=2.0, v=2.0)])
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'A': j3 must be a new joint's name \
('D' is listed at joints[3]), got 'D'
    """

    name: str
    j2: str
    j3: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    r3: ArrayLike
    side: ArrayLike
    u: ArrayLike = 0.0
    v: ArrayLike = 0.0
    pose: ArrayLike = 0.0


@dataclass(frozen=True, eq=False)
class SphereTriadJoint(_TriadSpec):
    """A spherical ternary link J1 J2 J3 held by three binary links: J_k at arc ``r_k`` from
    the placed joint ``p_k`` (arcs strictly between 0 and π).

    The link's shape: J2 at arc ``side`` from J1, J3 at arc ``arc`` from J1 turned by
    ``angle`` from the great circle J1→J2, right-handed about +O·J1 (as
    :class:`SphereRigidJoint` places a point). ``pose`` is the engine's pose index, 0 to 7:
    the slot of the pose at each input in the order of J2's angle on its circle about p2,
    measured from the great circle p2→p1, right-handed about +O·p2
    (:class:`~linkwright.engine.triad_steps.SphereTriad`).

    Examples
    --------
    Paper 001's Stephenson III driven at FG has 8 real configurations at θ = −90° (issue 21's
    arcs, its coupler BCE a triad held by AB, CD and EF; the paper's θ6 starts from the great
    circle G→(away from D), half a turn from G→D):

    >>> import numpy as np
    >>> from linkwright import Linkage, configurations
    >>> d = np.radians
    >>> a1, a2, a3, a4, a6, sigma, a7, a8, a9 = d([71.1, 64.1, 68.6, 65.7, 69.0, 102.0,
    ...                                           74.1, 52.6, 19.7])
    >>> axis = lambda t: [0.0, np.sin(t), np.cos(t)]
    >>> fg = Linkage(joints=[
    ...     FixedJoint("A", axis(0.0)), FixedJoint("D", axis(a1)), FixedJoint("G", axis(a1 + a9)),
    ...     SphereCrankJoint("F", "G", a8, phase=np.pi, toward="D"),
    ...     SphereTriadJoint("C", "B", "E", "D", a4, "A", a2, "F", a7, side=a3, arc=a6,
    ...                      angle=np.pi - sigma)], space="sphere")
    >>> sum(int(m.valid[0]) for _, m in configurations(fg, [d(-90)]))
    8
    """

    name: str
    j2: str
    j3: str
    p1: str
    r1: ArrayLike
    p2: str
    r2: ArrayLike
    p3: str
    r3: ArrayLike
    side: ArrayLike
    arc: ArrayLike = 0.0
    angle: ArrayLike = 0.0
    pose: ArrayLike = 0.0


Joint = (
    FixedJoint
    | CrankJoint
    | DyadJoint
    | SliderJoint
    | RigidJoint
    | SphereCrankJoint
    | SphereRigidJoint
    | HingeJoint
    | TriadJoint
    | SphereTriadJoint
    | HingeTriadJoint
    | SphereHingeTriadJoint
    | TurningTriadJoint
    | SphereTurningTriadJoint
)
"""Any joint spec."""

JOINT_TYPES: dict[str, type[Joint]] = {
    cls.type: cls
    for cls in (
        FixedJoint,
        CrankJoint,
        DyadJoint,
        SliderJoint,
        RigidJoint,
        HingeJoint,
        TriadJoint,
        HingeTriadJoint,
        TurningTriadJoint,
    )
}
"""Document ``type`` → joint spec class, in the plane."""

SPHERE_JOINT_TYPES: dict[str, type[Joint]] = {
    cls.type: cls
    for cls in (
        FixedJoint,
        SphereCrankJoint,
        DyadJoint,
        SphereRigidJoint,
        HingeJoint,
        SphereTriadJoint,
        SphereHingeTriadJoint,
        SphereTurningTriadJoint,
    )
}
"""Document ``type`` → joint spec class, on the sphere (no ``rrp``: see the module notes)."""

SPACES: dict[str, dict[str, type[Joint]]] = {"plane": JOINT_TYPES, "sphere": SPHERE_JOINT_TYPES}
"""A linkage's ``space`` → the joint spec classes it is built from."""

ALL_SPECS = (
    *JOINT_TYPES.values(),
    SphereCrankJoint,
    SphereRigidJoint,
    SphereTriadJoint,
    SphereHingeTriadJoint,
    SphereTurningTriadJoint,
)

# What each numeric field must be; names are the dataclass fields. A DyadJoint's lengths are
# arcs on the sphere, and a FixedJoint's place an axis: see numeric_kinds.
_NUMERIC: dict[type, dict[str, str]] = {
    FixedJoint: {"at": "point"},
    CrankJoint: {"length": "length", "ratio": "ratio", "phase": "number"},
    DyadJoint: {"r1": "length", "r2": "length", "assembly": "sign"},
    SliderJoint: {"r": "length", "line_angle": "number", "assembly": "sign"},
    RigidJoint: {"u": "number", "v": "number"},
    HingeJoint: {
        "r": "length",
        "a": "length",
        "b": "length",
        "phase": "number",
        "assembly": "sign",
    },
    SphereCrankJoint: {"arc": "arc", "ratio": "ratio", "phase": "number"},
    SphereRigidJoint: {"arc": "offset", "angle": "number"},
    TriadJoint: {
        "r1": "length",
        "r2": "length",
        "r3": "length",
        "side": "length",
        "u": "number",
        "v": "number",
        "pose": "pose",
    },
    SphereTriadJoint: {
        "r1": "arc",
        "r2": "arc",
        "r3": "arc",
        "side": "arc",
        "arc": "offset",
        "angle": "number",
        "pose": "sphere-pose",
    },
    HingeTriadJoint: {
        "r1": "length",
        "r2": "length",
        "a": "length",
        "b": "length",
        "side": "length",
        "u": "number",
        "v": "number",
        "phase": "number",
        "pose": "pose",
    },
    SphereHingeTriadJoint: {
        "r1": "arc",
        "r2": "arc",
        "a": "arc",
        "b": "arc",
        "side": "arc",
        "arc": "offset",
        "angle": "number",
        "phase": "number",
        "pose": "sphere-pose",
    },
    TurningTriadJoint: {
        "r1": "length",
        "r2": "length",
        "r3": "length",
        "side": "length",
        "hu": "number",
        "hv": "number",
        "arm": "length",
        "phase": "number",
        "pose": "pose",
    },
    SphereTurningTriadJoint: {
        "r1": "arc",
        "r2": "arc",
        "r3": "arc",
        "side": "arc",
        "harc": "arc",
        "hangle": "number",
        "arm": "arc",
        "phase": "number",
        "pose": "sphere-pose",
    },
}
_ON_SPHERE: dict[str, str] = {"point": "axis", "length": "arc"}
# The fields of each spec that name a parent joint (validation checks each is placed before).
REFERENCES: dict[type, tuple[str, ...]] = {
    FixedJoint: (),
    CrankJoint: ("pivot",),
    DyadJoint: ("p1", "p2"),
    SliderJoint: ("p1", "line_point"),
    RigidJoint: ("origin", "toward"),
    HingeJoint: ("z", "y"),
    SphereCrankJoint: ("pivot", "toward"),
    SphereRigidJoint: ("origin", "toward"),
    TriadJoint: ("p1", "p2", "p3"),
    SphereTriadJoint: ("p1", "p2", "p3"),
    HingeTriadJoint: ("p1", "p2", "p3"),
    SphereHingeTriadJoint: ("p1", "p2", "p3"),
    TurningTriadJoint: ("p1", "p2", "p3"),
    SphereTurningTriadJoint: ("p1", "p2", "p3"),
}
# The fields of a spec that name the further joints it places (each a new name).
PLACES: dict[type, tuple[str, ...]] = {
    HingeJoint: ("far",),
    TriadJoint: ("j2", "j3"),
    SphereTriadJoint: ("j2", "j3"),
    HingeTriadJoint: ("j2", "j3", "hinge"),
    SphereHingeTriadJoint: ("j2", "j3", "hinge"),
    TurningTriadJoint: ("j2", "j3", "hinge"),
    SphereTurningTriadJoint: ("j2", "j3", "hinge"),
}


def placed_by(joint: Joint) -> tuple[str, ...]:
    """The joints a spec places: its name, and a hinge's far joint or a triad's J2 and J3."""
    return joint.placed if isinstance(joint, HingeJoint | _TriadSpec) else (joint.name,)


def numeric_kinds(joint: Joint, space: str) -> dict[str, str]:
    kinds = _NUMERIC[type(joint)]
    if space == "sphere":
        return {attr: _ON_SPHERE.get(what, what) for attr, what in kinds.items()}
    return kinds


def unit_axis(axis: ArrayLike) -> Array:
    """The unit vector along ``axis``; scaled by its largest component first, so that neither a
    tiny nor a huge vector under- or overflows on the way."""
    at = np.asarray(axis, dtype=float)
    big = np.max(np.abs(at), axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        return sphere.unit(at / big)

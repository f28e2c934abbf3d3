"""Planar six-bars that decompose into dyads: the Watt I, Watt II, Stephenson I and III families.

A single-degree-of-freedom six-bar has seven revolute joints and two ternary links. Where the two
ternaries share a joint it is a **Watt** chain; where they are joined only through binary links
(one path of one binary, one of one binary, one of two binaries) it is a **Stephenson** chain.
Choosing the ground link gives the inversions:

============  ===========================================  ===================================
family        ground                                       construction from a driven crank
============  ===========================================  ===================================
Watt I        a binary link (the four-bar's frame)         four-bar, then a dyad from the
                                                           crank to the coupler
Watt II       a ternary (frame pivots A0, B0, D0)          two four-bars in series: a dyad
                                                           from the rocker to the ground
Stephenson I  the binary joining the two ternaries         four-bar, then a dyad from the
              (crank and rocker are the ternaries)         crank to the rocker
Stephenson II the binary in the path of two binaries       (none: see below)
Stephenson III a ternary (paper 001's topology, planar)    four-bar, then a dyad from the
                                                           coupler to the ground
============  ===========================================  ===================================

Every family here shares the four-bar of :class:`~linkwright.mechanisms.FourBar` exactly: ground
pivots A0 and B0, crank A0A of length ``crank`` driven by the input θ (the angle of A − A0 from
+x), coupler AB, rocker B0B, and ``assembly`` = sign((B0 − A) × (B − A)). Then joint D closes a
second loop as the apex of a dyad of binary links ``link1`` (from C) and ``link2`` (from X, the
joint E on a moving link or the ground pivot D0), with ``assembly2`` = sign((X − C) × (D − C)):
the engine's one branch convention for ``DyadRRR("D", "C", "link1", X, "link2")``. The traced
point P sits at (u, v) in the frame of the link CD (origin C, x-axis along C→D, v to the left).

Joint C (and E) is a point of a moving link given in that link's frame: (u, v) with the origin
at the link's first joint and the x-axis toward its second (v to the left). These attachment
coordinates are required fields: they decide the topology, and zero is no neutral default (C at
the origin of the rocker frame *is* B0, which would freeze the dyad of a Watt II). Exact
coincidences that leave the dyad undefined or immobile are rejected, naming the field; each
family says which.

Why there is no Stephenson II family
------------------------------------
With the ground in the two-binary path, the loop through the ground link has five links (ground,
ternary, binary, ternary, binary): no four-bar contains the ground. Driving either grounded link
(the ternary or the binary) leaves four moving links and six joints, one of them a ternary with
all three of its joints unknown: an Assur group of class III (a *triad*), which no sequence of
dyads can place. Its positions are the roots of a polynomial of degree six, not the intersections
of circles: a triad plan step (:class:`~linkwright.engine.triad_steps.Triad`), as in the
Stephenson III driven at its output (``Stephenson3(input="output")``). A Stephenson II family is
such a plan; it is not declared yet.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import Crank, DyadRRR, Fixed, Motion, Plan, Rigid
from linkwright.engine.plan import Param, Step
from linkwright.geometry import plane
from linkwright.mechanisms.base import (
    Dimension,
    InvalidMechanism,
    Mechanism,
    PlanByInput,
    dimension,
    family_dataclass,
)
from linkwright.mechanisms.planar import (
    ASSEMBLY_FIELD,
    FOURBAR_FIELDS,
    FOURBAR_JOINTS,
    FRAME_DISTINCT,
    POINT_FIELD,
)
from linkwright.mechanisms.registry import Family, FieldSpec, register
from linkwright.mechanisms.stephenson3_inputs import DRIVEN_ANGLES, INPUTS, PLANS

__all__ = [
    "NoConstructionPlan",
    "SixBar",
    "Stephenson1",
    "Stephenson3",
    "Watt1",
    "Watt2",
]

Array = NDArray[np.float64]

# The four-bar every family starts from, step for step the FourBar family's plan.
_FOURBAR = (
    Fixed("A0", "A0"),
    Fixed("B0", "B0"),
    Crank("A", "A0", "crank"),
    DyadRRR("B", "A", "coupler", "B0", "rocker", branch="assembly"),
)
_POINT = Rigid("P", "C", "D", "u", "v")


class NoConstructionPlan(ValueError):
    """A mechanism that has no construction plan. Every family has one now (triads are plan
    steps); kept so that code written against the earlier refusal still imports."""


def _length(motion: Motion, a: str, b: str) -> Array:
    return plane.norm(motion.positions[b] - motion.positions[a])


def _named(p: Param) -> str:
    """A step's parameter by name: a family's plan names every one (no step holds a constant)."""
    if not isinstance(p, str):
        raise TypeError(f"a six-bar's plan step holds the constant {p!r}, not a named parameter")
    return p


def _frame_error(motion: Motion, step: Rigid, params: dict[str, Array]) -> Array:
    """Distance of a rigid point from its place (u, v) in the frame origin→toward."""
    o, t, p = (motion.positions[k] for k in (step.origin, step.toward, step.name))
    u, v = (np.asarray(params[_named(k)], dtype=float)[..., None] for k in (step.u, step.v))
    return plane.frame_error(o, t, p, u, v)


@family_dataclass
class SixBar(Mechanism):
    """What the dyad-decomposable six-bars share: scale, residuals and the input link.

    Not a family itself (it has no fields and no plan). Subclasses name the links that carry
    their attached joints in ``attached`` (joint → the two joints spanning its link's frame) and
    the ground pivots of their frame link in ``ground``.
    """

    ground: ClassVar[tuple[str, ...]] = ("A0", "B0")
    attached: ClassVar[dict[str, tuple[str, str]]] = {}

    if TYPE_CHECKING:  # fields every family declares (not fields of this base)
        # Read-only properties here, not annotations: an annotation would be a dataclass field
        # of this base, ahead of (and out of order with) each family's own.
        @property
        def A0(self) -> Array: ...
        @property
        def B0(self) -> Array: ...
        @property
        def crank(self) -> Array: ...
        @property
        def link2(self) -> Array: ...
        @property
        def assembly2(self) -> Array: ...

    def __post_init__(self) -> None:
        super().__post_init__()
        self._check_attachments()

    def _check_attachments(self) -> None:
        """Reject exact coincidences that leave the second dyad undefined or immobile."""

    @property
    def frame(self) -> Array:
        """Frame length |A0B0|."""
        return plane.norm(np.asarray(self.B0) - np.asarray(self.A0))

    @property
    def input_link(self) -> tuple[str, str]:
        """The driven link as (pivot, joint): θ is the angle of joint − pivot from +x."""
        return ("A0", "A")

    @property
    def scale(self) -> Array:
        """The largest distance between two joints of one link (links, frame, ternary sides).

        For the ternaries that is the longest side of the triangle of their three joints; the
        traced point is not a joint and does not count, as for :class:`FourBar`.
        """
        params = self.params()
        sizes = [super().scale, self.frame]
        for name, (origin, toward) in self.attached.items():
            step = self._steps()[name]
            assert isinstance(step, Rigid)  # an attached joint is a rigid point of its link
            u, v = (np.asarray(params[_named(k)], dtype=float) for k in (step.u, step.v))
            side = self._link_length(origin, toward)
            sizes += [np.hypot(u, v), np.hypot(u - side, v)]
        points = [np.asarray(params[p], dtype=float) for p in self.ground]
        for i, p in enumerate(points):
            for q in points[i + 1 :]:
                sizes.append(plane.norm(q - p))
        largest: Array = np.maximum.reduce(np.broadcast_arrays(*sizes))
        return largest

    def _link_length(self, origin: str, toward: str) -> Array:
        lengths = {("A0", "A"): "crank", ("A", "B"): "coupler", ("B0", "B"): "rocker"}
        return np.asarray(getattr(self, lengths[(origin, toward)]), dtype=float)

    @classmethod
    def _steps(cls) -> dict[str, Step]:
        # Read on the class: a family's constraints are its plan's steps whatever drives it.
        return {s.name: s for s in cls.plan.steps}

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Every constraint's error at each sample of ``motion``, divided by :attr:`scale`.

        One entry per constraint, recomputed from the joint positions: ``ground`` (the ground
        pivots at their places), one per link length (``crank``, ``coupler``, ``rocker``,
        ``link1``, ``link2``: signed length errors), one per rigid point (``C``, ``E``, ``P``:
        distance from its (u, v) place), and ``input`` (the driven joint's distance from where
        the input angle puts it). NaN where ``motion`` is not valid.
        """
        s = np.asarray(self.scale)[..., None]
        params = self.params()
        out: dict[str, Array] = {}
        ground = []
        for step in self._steps().values():
            if isinstance(step, Fixed):
                at = np.asarray(params[step.at], dtype=float)[..., None, :]
                ground.append(plane.norm(motion.positions[step.name] - at))
            elif isinstance(step, Crank):
                length = _named(step.length)
                out[length] = _length(motion, step.pivot, step.name) - params[length][..., None]
            elif isinstance(step, DyadRRR):
                for pivot, r in ((step.p1, _named(step.r1)), (step.p2, _named(step.r2))):
                    out[r] = _length(motion, pivot, step.name) - params[r][..., None]

            elif isinstance(step, Rigid):
                out[step.name] = _frame_error(motion, step, params)
        out["ground"] = np.maximum.reduce(ground)
        out["input"] = self._input_error(motion)
        return {k: v / s for k, v in out.items()}

    def _input_error(self, motion: Motion) -> Array:
        """The driven joint's distance from where the input angle puts it."""
        pivot, joint = self.input_link
        arm = self._link_length(pivot, joint)
        placed = motion.positions[pivot] + plane.polar(arm[..., None], motion.input)
        return plane.norm(motion.positions[joint] - placed)


@family_dataclass
class Watt1(SixBar):
    """Watt I six-bar: a four-bar with a dyad from its crank to its coupler.

    Watt chain (the ternaries, crank A0AC and coupler ABE, share joint A) with a binary link
    grounded: the four-bar's frame A0B0.

    Parameters
    ----------
    A0, B0 : points [x, y]
        Crank and rocker pivots.
    crank, coupler, rocker : positive lengths
        A0A, AB, B0B.
    u1, v1 : float
        C on the crank, in its frame (origin A0, x along A0→A).
    u2, v2 : float
        E on the coupler, in its frame (origin A, x along A→B).
    link1, link2 : positive lengths
        CD and ED.
    u, v : float
        The traced point P on the link CD (origin C, x along C→D); default P = C.
    assembly : ±1
        sign((B0 − A) × (B − A)), as for the four-bar.
    assembly2 : ±1
        sign((E − C) × (D − C)).

    Notes
    -----
    Joints A0, B0, A, B, C, E, D, P. The input θ is the angle of A − A0 from +x. C and E at the
    joint A together (C = (crank, 0), E = (0, 0)) make the dyad's pivots coincide at every
    input, and are rejected.

    Examples
    --------
    The bundled ``watt1-example``. At θ = 0 the four-bar stands at A = (1, 0), B = (4, 4) (its
    coupler along (0.6, 0.8)), so C = A0 + 1·(1, 0) + 1·(0, 1) = (1, 1) and
    E = A + 4·(0.6, 0.8) + 3·(−0.8, 0.6) = (1, 5); D = (−2, 1) is 3 from C and 5 from E, to the
    left of C→E (assembly2 = 1); P = C + 1.5·(−1, 0) − 1·(0, −1):

    >>> from linkwright.mechanisms import solve
    >>> m = Watt1(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=4, u1=1, v1=1, u2=4, v2=3,
    ...           link1=3, link2=5, u=1.5, v=-1)
    >>> at = solve(m, [0.0]).positions
    >>> {k: (at[k][0].round(12) + 0).tolist() for k in ("C", "E", "D", "P")}
    {'C': [1.0, 1.0], 'E': [1.0, 5.0], 'D': [-2.0, 1.0], 'P': [-0.5, 2.0]}

    A member whose frame pivots lie too far apart for its links assembles nowhere, and says so:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import input_range
    >>> bool(input_range(replace(m, B0=[40.0, 0.0])).never)
    True
    """

    A0: Dimension
    B0: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    u1: Dimension
    v1: Dimension
    u2: Dimension
    v2: Dimension
    link1: Dimension
    link2: Dimension
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)

    family: ClassVar[str] = "watt1"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker", "link1", "link2")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "C", "E", "D", "P")
    attached: ClassVar[dict[str, tuple[str, str]]] = {"C": ("A0", "A"), "E": ("A", "B")}
    plan: ClassVar[Plan] = Plan(
        (
            *_FOURBAR,
            Rigid("C", "A0", "A", "u1", "v1"),
            Rigid("E", "A", "B", "u2", "v2"),
            DyadRRR("D", "C", "link1", "E", "link2", branch="assembly2"),
            _POINT,
        ),
        traced=("P",),
    )

    def _check_attachments(self) -> None:
        both_at_a = (
            (np.asarray(self.u1) == np.asarray(self.crank))
            & (np.asarray(self.v1) == 0)
            & (np.asarray(self.u2) == 0)
            & (np.asarray(self.v2) == 0)
        )
        if np.any(both_at_a):
            raise InvalidMechanism(
                "u2, v2: E at (0, 0) is the joint A, where C = (crank, 0) also sits: the dyad's "
                "pivots C and E would coincide at every input"
            )


@family_dataclass
class Watt2(SixBar):
    """Watt II six-bar: two four-bars in series, the second driven by the first one's rocker.

    Watt chain (the ternaries, ground A0B0D0 and rocker B0BC, share joint B0) with a ternary
    grounded.

    Parameters
    ----------
    A0, B0, D0 : points [x, y]
        Crank pivot, rocker pivot, and the second four-bar's output pivot.
    crank, coupler, rocker : positive lengths
        A0A, AB, B0B.
    u1, v1 : float
        C on the rocker, in its frame (origin B0, x along B0→B).
    link1, link2 : positive lengths
        CD (the second coupler) and D0D (the output).
    u, v : float
        The traced point P on the link CD (origin C, x along C→D); default P = C.
    assembly : ±1
        sign((B0 − A) × (B − A)), as for the four-bar.
    assembly2 : ±1
        sign((D0 − C) × (D − C)).

    Notes
    -----
    Joints A0, B0, D0, A, B, C, D, P. The input θ is the angle of A − A0 from +x. C = (0, 0) is
    the pivot B0 itself (the dyad C–D–D0 would be a rigid triangle on the ground) and is
    rejected.

    Examples
    --------
    The bundled ``watt2-example``. At θ = 0 the rocker stands along (0, 1) (B = (4, 4)), so
    C = B0 + 4·(0, 1) + 2·(−1, 0) = (2, 4); D = (5, 4) is 3 from C and 6 from D0 = (5, −2),
    to the left of C→D0 (assembly2 = 1); P = C + 1.5·(1, 0) + 1·(0, 1):

    >>> from linkwright.mechanisms import solve
    >>> m = Watt2(A0=[0, 0], B0=[4, 0], D0=[5, -2], crank=1, coupler=5, rocker=4, u1=4, v1=2,
    ...           link1=3, link2=6, u=1.5, v=1)
    >>> at = solve(m, [0.0]).positions
    >>> {k: (at[k][0].round(12) + 0).tolist() for k in ("C", "D", "P")}
    {'C': [2.0, 4.0], 'D': [5.0, 4.0], 'P': [3.5, 5.0]}

    A member whose frame pivots lie too far apart for its links assembles nowhere, and says so:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import input_range
    >>> bool(input_range(replace(m, B0=[40.0, 0.0])).never)
    True
    """

    A0: Dimension
    B0: Dimension
    D0: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    u1: Dimension
    v1: Dimension
    link1: Dimension
    link2: Dimension
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)

    family: ClassVar[str] = "watt2"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0", "D0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker", "link1", "link2")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "D0", "A", "B", "C", "D", "P")
    ground: ClassVar[tuple[str, ...]] = ("A0", "B0", "D0")
    attached: ClassVar[dict[str, tuple[str, str]]] = {"C": ("B0", "B")}
    plan: ClassVar[Plan] = Plan(
        (
            *_FOURBAR[:2],
            Fixed("D0", "D0"),
            *_FOURBAR[2:],
            Rigid("C", "B0", "B", "u1", "v1"),
            DyadRRR("D", "C", "link1", "D0", "link2", branch="assembly2"),
            _POINT,
        ),
        traced=("P",),
    )

    def _check_attachments(self) -> None:
        if np.any((np.asarray(self.u1) == 0) & (np.asarray(self.v1) == 0)):
            raise InvalidMechanism(
                "u1, v1: C at (0, 0) is the rocker pivot B0: the dyad C–D–D0 would be a rigid "
                "triangle on the ground"
            )


@family_dataclass
class Stephenson1(SixBar):
    """Stephenson I six-bar: a four-bar with a dyad from its crank to its rocker.

    Stephenson chain: the ternaries are the crank A0AC and the rocker B0BE, joined by the
    frame A0B0 (grounded), by the coupler AB and by the two-binary path C–D–E.

    Parameters
    ----------
    A0, B0 : points [x, y]
        Crank and rocker pivots.
    crank, coupler, rocker : positive lengths
        A0A, AB, B0B.
    u1, v1 : float
        C on the crank, in its frame (origin A0, x along A0→A).
    u2, v2 : float
        E on the rocker, in its frame (origin B0, x along B0→B).
    link1, link2 : positive lengths
        CD and ED.
    u, v : float
        The traced point P on the link CD (origin C, x along C→D); default P = C.
    assembly : ±1
        sign((B0 − A) × (B − A)), as for the four-bar.
    assembly2 : ±1
        sign((E − C) × (D − C)).

    Notes
    -----
    Joints A0, B0, A, B, C, E, D, P. The input θ is the angle of A − A0 from +x. C and E both at
    their links' origins (C = A0 and E = B0, both on the ground) would make the dyad a rigid
    triangle on the ground, and are rejected.

    Examples
    --------
    The bundled ``stephenson1-example``. At θ = 0 the crank lies along (1, 0) and the rocker
    along (0, 1) (A = (1, 0), B = (4, 4)), so C = (1, −1) and
    E = B0 + 5·(0, 1) − 1·(−1, 0) = (5, 5); D = (5, −1) is 4 from C and 6 from E, to the right
    of C→E (assembly2 = −1); P = C + 2·(1, 0) + 1·(0, 1):

    >>> from linkwright.mechanisms import solve
    >>> m = Stephenson1(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=4, u1=1, v1=-1,
    ...                 u2=5, v2=-1, link1=4, link2=6, u=2, v=1, assembly2=-1)
    >>> at = solve(m, [0.0]).positions
    >>> {k: (at[k][0].round(12) + 0).tolist() for k in ("C", "E", "D", "P")}
    {'C': [1.0, -1.0], 'E': [5.0, 5.0], 'D': [5.0, -1.0], 'P': [3.0, 0.0]}

    A member whose frame pivots lie too far apart for its links assembles nowhere, and says so:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import input_range
    >>> bool(input_range(replace(m, B0=[40.0, 0.0])).never)
    True
    """

    A0: Dimension
    B0: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    u1: Dimension
    v1: Dimension
    u2: Dimension
    v2: Dimension
    link1: Dimension
    link2: Dimension
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)

    family: ClassVar[str] = "stephenson1"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker", "link1", "link2")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "A", "B", "C", "E", "D", "P")
    attached: ClassVar[dict[str, tuple[str, str]]] = {"C": ("A0", "A"), "E": ("B0", "B")}
    plan: ClassVar[Plan] = Plan(
        (
            *_FOURBAR,
            Rigid("C", "A0", "A", "u1", "v1"),
            Rigid("E", "B0", "B", "u2", "v2"),
            DyadRRR("D", "C", "link1", "E", "link2", branch="assembly2"),
            _POINT,
        ),
        traced=("P",),
    )

    def _check_attachments(self) -> None:
        grounded = (
            (np.asarray(self.u1) == 0)
            & (np.asarray(self.v1) == 0)
            & (np.asarray(self.u2) == 0)
            & (np.asarray(self.v2) == 0)
        )
        if np.any(grounded):
            raise InvalidMechanism(
                "u1, v1, u2, v2: C = A0 and E = B0 are both ground pivots: the dyad C–D–E would "
                "be a rigid triangle on the ground"
            )


@family_dataclass
class Stephenson3(SixBar):
    """Stephenson III six-bar: a four-bar with a dyad from a coupler point to a ground pivot.

    Stephenson chain with a ternary grounded: the frame A0B0D0 and the coupler ABC are the
    ternaries, joined by the crank, the rocker and the two-binary path C–D–D0. This is paper
    001's topology in the plane (its A, B, C, D, E, F, G are our A0, A, B, B0, C, D, D0).

    Parameters
    ----------
    A0, B0, D0 : points [x, y]
        Crank pivot, rocker pivot, and the pivot of the output link D0D.
    crank, coupler, rocker : positive lengths
        A0A, AB, B0B.
    u1, v1 : float
        C on the coupler, in its frame (origin A, x along A→B).
    link1, link2 : positive lengths
        CD and D0D (the output).
    u, v : float
        The traced point P on the link CD (origin C, x along C→D); default P = C.
    assembly : ±1
        sign((B0 − A) × (B − A)), as for the four-bar.
    assembly2 : ±1
        sign((D0 − C) × (D − C)).
    input : {"crank", "rocker", "output", "A", "B", "C", "D"}
        Where the motor sits (:mod:`~linkwright.mechanisms.stephenson3_inputs` has the table):
        at a grounded link, θ its angle from +x (the crank A0A: a four-bar plus a dyad; the
        rocker B0B; the output D0D: the coupler ABC, held by the crank, the rocker and the link
        CD, is then a triad, a plan step with up to six poses,
        :class:`~linkwright.engine.triad_steps.Triad`), or at a moving hinge, θ the angle
        between its two links (A or B: a driven hinge in the four-bar's loop; C or D: a triad
        that changes with the input, :mod:`~linkwright.engine.hinge_triad_steps`). One value
        for the whole batch, since it chooses the plan. Its constraints, and :meth:`residuals`,
        are the same however it is driven, except ``input``.
    pose : 0 to 5
        Driven at the output, C or D: which pose of the triad, in the order of the coupler's
        angle (of B − A) at each input; driven at A or B, which side of its loop the hinge's far
        joint lies on (0 or 1). A name for one configuration at one input, not a branch
        followed along the motion (:func:`~linkwright.mechanisms.circuits` follows those).

    Notes
    -----
    Joints A0, B0, D0, A, B, C, D, P. The coupler point C may be anywhere, A and B included.

    Examples
    --------
    The bundled ``stephenson3-example``. At θ = 0, A = (1, 0) and B = (4, 4), so the coupler
    point is C = A + 4·(0.6, 0.8) − 2·(−0.8, 0.6) = (5, 2); D = (2, 2) is 3 from C and 6 from
    D0 = (2, −4), to the right of C→D0 (assembly2 = −1); P = C + 1.5·(−1, 0) + 1·(0, −1):

    >>> from linkwright.mechanisms import solve
    >>> m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[2, -4], crank=1, coupler=5, rocker=4, u1=4,
    ...                 v1=-2, link1=3, link2=6, u=1.5, v=1, assembly2=-1)
    >>> at = solve(m, [0.0]).positions
    >>> {k: (at[k][0].round(12) + 0).tolist() for k in ("C", "D", "P")}
    {'C': [5.0, 2.0], 'D': [2.0, 2.0], 'P': [3.5, 1.0]}

    Driven at the output, the coupler is a triad. At θ = 90° (D = (2, 2)) it has two poses;
    each holds every link:

    >>> from linkwright.mechanisms import configurations
    >>> driven = Stephenson3(**m.params(), input="output")
    >>> found = configurations(driven, [np.pi / 2])
    >>> [bool(motion.valid[0]) for _, motion in found]
    [True, True, False, False, False, False]
    >>> bool(max(np.max(np.abs(r)) for r in driven.residuals(found[1][1]).values()) < 1e-12)
    True

    A member whose frame pivots lie too far apart for its links assembles nowhere, and says so:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import input_range
    >>> bool(input_range(replace(m, B0=[40.0, 0.0])).never)
    True
    """

    A0: Dimension
    B0: Dimension
    D0: Dimension
    crank: Dimension
    coupler: Dimension
    rocker: Dimension
    u1: Dimension
    v1: Dimension
    link1: Dimension
    link2: Dimension
    u: Dimension = dimension(0.0)
    v: Dimension = dimension(0.0)
    assembly: Dimension = dimension(1.0)
    assembly2: Dimension = dimension(1.0)
    input: str = "crank"
    pose: Dimension = dimension(0.0)

    family: ClassVar[str] = "stephenson3"
    point_fields: ClassVar[frozenset[str]] = frozenset({"A0", "B0", "D0"})
    length_fields: ClassVar[tuple[str, ...]] = ("crank", "coupler", "rocker", "link1", "link2")
    reported_joints: ClassVar[tuple[str, ...]] = ("A0", "B0", "D0", "A", "B", "C", "D", "P")
    ground: ClassVar[tuple[str, ...]] = ("A0", "B0", "D0")
    attached: ClassVar[dict[str, tuple[str, str]]] = {"C": ("A", "B")}
    plan: ClassVar[Plan] = PlanByInput(**PLANS)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        # The base checks the numbers; the word that chooses the plan is checked here, first.
        if not isinstance(self.input, str) or self.input not in INPUTS:
            raise InvalidMechanism(
                f"input: must be one of {', '.join(INPUTS)} (where the motor sits), "
                f"got {self.input!r}"
            )
        super().__post_init__()

    @property
    def input_link(self) -> tuple[str, str]:
        """The driven link as (its pivot or hinge, its far joint)."""
        vertex, _, _, joint, _ = DRIVEN_ANGLES[self.input]
        return (vertex, joint)

    def _input_error(self, motion: Motion) -> Array:
        vertex, origin, toward, joint, arm = DRIVEN_ANGLES[self.input]
        at = motion.positions
        if origin:
            ref = at[toward] - at[origin]
            with np.errstate(invalid="ignore", divide="ignore"):
                ref = ref / plane.norm(ref)[..., None]
        else:
            ref = np.array([1.0, 0.0])
        length = np.asarray(getattr(self, arm), dtype=float)[..., None, None]
        c, s = np.cos(motion.input)[..., None], np.sin(motion.input)[..., None]
        turned = np.concatenate(
            (c * ref[..., :1] - s * ref[..., 1:], s * ref[..., :1] + c * ref[..., 1:]), -1
        )
        return plane.norm(at[joint] - at[vertex] - length * turned)


# --------------------------------------------------------------------------------------------
# The registry
# --------------------------------------------------------------------------------------------


def _sixbar_fields(second: FieldSpec, *, stephenson3: bool = False) -> tuple[FieldSpec, ...]:
    """A six-bar's fields: the four-bar, C, then E or D0, the second dyad and the point. C and E
    are required: where a dyad attaches decides the topology, and no value is neutral."""
    tail = (
        (
            FieldSpec("input", "stephenson_input", default="crank"),
            FieldSpec("pose", "pose", default=0),
        )
        if stephenson3
        else ()
    )
    return (
        *FOURBAR_FIELDS,
        FieldSpec("C", "uv", ("u1", "v1")),
        second,
        FieldSpec("link1", "length"),
        FieldSpec("link2", "length"),
        POINT_FIELD,
        ASSEMBLY_FIELD,
        FieldSpec("assembly2", "sign", default=1),
        *tail,
    )


_E = FieldSpec("E", "uv", ("u2", "v2"))
_D0 = FieldSpec("D0", "point")


def _joints(cls: type[SixBar], roles: dict[str, str]) -> tuple[tuple[str, str], ...]:
    return tuple((j, roles.get(j, dict(FOURBAR_JOINTS).get(j, ""))) for j in cls.reported_joints)


for _cls, _second, _roles, _display in (
    (
        Watt1,
        _E,
        {"C": "on the crank", "E": "on the coupler", "D": "the second dyad's joint"},
        "Watt I six-bar",
    ),
    (
        Watt2,
        _D0,
        {"D0": "the output's pivot", "C": "on the rocker", "D": "the second dyad's joint"},
        "Watt II six-bar",
    ),
    (
        Stephenson1,
        _E,
        {"C": "on the crank", "E": "on the rocker", "D": "the second dyad's joint"},
        "Stephenson I six-bar",
    ),
    (
        Stephenson3,
        _D0,
        {
            "D0": "the output's pivot (paper 001's G)",
            "C": "on the coupler",
            "D": "the output's joint",
        },
        "Stephenson III six-bar",
    ),
):
    register(
        Family(
            name=_cls.family,
            cls=_cls,
            display=_display,
            group="Six-bars",
            space="plane",
            example=f"{_cls.family}-example",
            fields=_sixbar_fields(_second, stephenson3=_cls is Stephenson3),
            distinct=FRAME_DISTINCT,
            joints=_joints(_cls, {**_roles, "P": "traced point on CD"}),
            source="the six-bar chains of Watt and Stephenson (paper 001's topology in the plane)"
            if _cls is Stephenson3
            else "the six-bar chains of Watt and Stephenson",
        )
    )

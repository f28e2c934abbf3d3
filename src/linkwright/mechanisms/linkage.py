"""Family ``linkage``: a planar or spherical linkage the user composes joint by joint.

A :class:`Linkage` is an ordered tuple of joint specs, each placing one joint from joints listed
before it, exactly as the engine's construction plans do (see DESIGN.md). In the plane
(``space = "plane"``, the default):

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
==============  ============  ====================================================================

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
================  ==========  ==================================================================

A slider has no spherical counterpart of its own: a pin whose guide is a great circle is an
``rrr`` dyad whose second link, 90° long, turns about the guide's pole, and is written so.

Angles are radians here (documents speak degrees). Assembly signs are the engine's: a dyad
joint J placed from P1 then P2 has ``assembly = sign((P2 − P1) × (J − P1))`` in the plane
(+1: J to the left of P1→P2) and ``sign((P1 × P2)·J)`` on the sphere (the same side, seen from
outside the sphere); a slider pin B has ``assembly = sign((B − H)·d)``, H the foot of P1 on the
guide and d = (cos line_angle, sin line_angle). Planar rigid points sit at (u, v) in the frame
with origin ``origin`` and x axis towards ``toward`` (v to the left).

Mobility, as a sanity line (Grübler: M = 3(n − 1) − 2j for n links and j lower pairs, the same
count on the sphere, where a body also has three freedoms, its rotations about O): a crank
adds one link and one pin, and its angle is the input (a second crank is geared to the input,
one more constraint); a dyad adds two links and three pins, 3·2 − 2·3 = 0; a slider pin adds a
rod and a block with two pins and one slide, 3·2 − 2·3 = 0 again; a rigid point adds nothing.
So a linkage built this way has exactly one degree of freedom: the four-bar (n = 4, j = 4)
gives 3·3 − 8 = 1, Jansen's leg (n = 8, j = 10) 3·7 − 20 = 1. What a user *can* write wrongly
is therefore an ill-formed construction, and :class:`Linkage` refuses each kind with one
message that names the joint (:class:`InvalidLinkage`).

Parameter names are ``"<joint>.<field>"`` (``"B.r1"``, ``"A0.at"``): two linkages of one
structure compile to equal plans, and batches (arrays with a leading batch shape) work as in
every family. A crank's ratio of exactly 1 (a scalar) is written into the plan as a constant
rather than a parameter, because the engine finds the limits of a dyad hung from such cranks in
closed form. On the sphere ``"<joint>.at"`` is the unit vector (the spec keeps the vector as
given, so that a document reads back as written), and a crank's zero direction is the parameter
``"<toward>.at"`` itself.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields, replace
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Motion,
    Plan,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
)
from linkwright.engine.evaluate import batch_shape
from linkwright.geometry import plane, sphere
from linkwright.mechanisms.base import InvalidMechanism, Mechanism, family_dataclass
from linkwright.mechanisms.registry import Derived, Family, FieldSpec, register

__all__ = [
    "JOINT_TYPES",
    "SPACES",
    "SPHERE_JOINT_TYPES",
    "CrankJoint",
    "DyadJoint",
    "FixedJoint",
    "InvalidLinkage",
    "Joint",
    "Linkage",
    "RigidJoint",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereRigidJoint",
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


class _Spec:
    """Equality by value, arrays included: two specs are equal when every field is.

    The dataclass default compares field tuples with ``==``, which for a point (an array of
    two) has no single truth value; comparing the arrays whole makes linkages comparable.
    """

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same_value(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))

    __hash__ = None  # type: ignore[assignment]  # specs may hold arrays


def _same_value(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    try:
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    except (TypeError, ValueError):
        return a == b


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
class SliderJoint(_Spec):
    """A slider pin (an RRP dyad): at ``r`` from ``p1``, on the guide line through the joint
    ``line_point`` at the fixed absolute angle ``line_angle`` (radians).

    ``assembly`` is ``sign((B − H)·d)``, H the foot of p1 on the guide, d its direction.
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


Joint = (
    FixedJoint
    | CrankJoint
    | DyadJoint
    | SliderJoint
    | RigidJoint
    | SphereCrankJoint
    | SphereRigidJoint
)
"""Any joint spec."""

JOINT_TYPES: dict[str, type[Joint]] = {
    cls.type: cls for cls in (FixedJoint, CrankJoint, DyadJoint, SliderJoint, RigidJoint)
}
"""Document ``type`` → joint spec class, in the plane."""

SPHERE_JOINT_TYPES: dict[str, type[Joint]] = {
    cls.type: cls for cls in (FixedJoint, SphereCrankJoint, DyadJoint, SphereRigidJoint)
}
"""Document ``type`` → joint spec class, on the sphere (no ``rrp``: see the module notes)."""

SPACES: dict[str, dict[str, type[Joint]]] = {"plane": JOINT_TYPES, "sphere": SPHERE_JOINT_TYPES}
"""A linkage's ``space`` → the joint spec classes it is built from."""

_ALL_SPECS = (*JOINT_TYPES.values(), SphereCrankJoint, SphereRigidJoint)

_AXIS_TOL = 1e-12
"""Two ground axes whose unit vectors' cross product is this small are one axis."""

# What each numeric field must be; names are the dataclass fields. A DyadJoint's lengths are
# arcs on the sphere, and a FixedJoint's place an axis: see _numeric_kinds.
_NUMERIC: dict[type, dict[str, str]] = {
    FixedJoint: {"at": "point"},
    CrankJoint: {"length": "length", "ratio": "ratio", "phase": "number"},
    DyadJoint: {"r1": "length", "r2": "length", "assembly": "sign"},
    SliderJoint: {"r": "length", "line_angle": "number", "assembly": "sign"},
    RigidJoint: {"u": "number", "v": "number"},
    SphereCrankJoint: {"arc": "arc", "ratio": "ratio", "phase": "number"},
    SphereRigidJoint: {"arc": "offset", "angle": "number"},
}
_ON_SPHERE: dict[str, str] = {"point": "axis", "length": "arc"}
_REFERENCES: dict[type, tuple[str, ...]] = {
    FixedJoint: (),
    CrankJoint: ("pivot",),
    DyadJoint: ("p1", "p2"),
    SliderJoint: ("p1", "line_point"),
    RigidJoint: ("origin", "toward"),
    SphereCrankJoint: ("pivot", "toward"),
    SphereRigidJoint: ("origin", "toward"),
}


def _numeric_kinds(joint: Joint, space: str) -> dict[str, str]:
    kinds = _NUMERIC[type(joint)]
    if space == "sphere":
        return {attr: _ON_SPHERE.get(what, what) for attr, what in kinds.items()}
    return kinds


def _unit_axis(at: Array) -> Array:
    """The unit vector along ``at``; scaled by its largest component first, so that neither a
    tiny nor a huge vector under- or overflows on the way."""
    big = np.max(np.abs(at), axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        return sphere.unit(at / big)


def _show(value: Array, bad: NDArray[np.bool_]) -> str:
    """The offending value(s): the number itself, or the first few of an array."""
    if value.ndim == 0:
        return repr(float(value))
    return f"{value[bad].ravel()[:3].tolist()} (in an array of shape {value.shape})"


def _numeric(joint: Joint, index: int, attr: str, what: str) -> Array:
    """The field as a float array, checked for ``what`` (point, axis, length, arc, offset,
    ratio, sign, number)."""
    name = joint.name

    def fail(problem: str) -> InvalidLinkage:
        return InvalidLinkage(
            f"joint {name!r}: {attr} {problem}", index=index, joint=name, field=attr
        )

    raw = getattr(joint, attr)
    try:
        value = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        raise fail(f"must be a number, got {raw!r}") from None
    if what == "point" and value.shape[-1:] != (2,):
        hint = (
            " (an axis [x, y, z]? a spherical linkage needs space='sphere')"
            if value.shape == (3,)
            else ""
        )
        raise fail(f"must be a point [x, y], got shape {value.shape}{hint}")
    if what == "axis" and value.shape[-1:] != (3,):
        raise fail(
            "must be an axis [x, y, z] (a vector from the sphere's centre along the joint's "
            f"axis), got shape {value.shape}"
        )
    bad = ~np.isfinite(value)
    if np.any(bad):
        raise fail(f"must be finite, got {_show(value, bad)}")
    if what == "axis" and np.any(np.all(value == 0, axis=-1)):
        raise fail("must not be the zero vector (its direction is the joint's axis)")
    if what == "arc" and np.any((value <= 0) | (value >= np.pi)):
        out = (value <= 0) | (value >= np.pi)
        raise fail(f"must be an arc strictly between 0 and π (radians), got {_show(value, out)}")
    if what == "offset" and np.any((value < 0) | (value > np.pi)):
        out = (value < 0) | (value > np.pi)
        raise fail(
            f"must be an arc from 0 to π (radians), got {_show(value, out)} (for a point on "
            "the other side of the link, turn its angle by π instead)"
        )
    if what == "length" and np.any(value <= 0):
        raise fail(f"must be a positive length, got {_show(value, value <= 0)}")
    if what == "ratio" and np.any(value == 0):
        raise fail("must be nonzero (a crank with ratio 0 does not turn, so it drives nothing)")
    if what == "sign" and not np.all(np.abs(value) == 1):
        raise fail(f"must be 1 or -1, got {_show(value, np.abs(value) != 1)}")
    return value


def _wrong_space(joint: Joint, space: str) -> str:
    """Why a joint of the other space's kind cannot be used here (and what to write instead)."""
    name = joint.name
    if isinstance(joint, SliderJoint):
        return (
            f"joint {name!r}: a slider (rrp) has no spherical counterpart: a pin on a "
            "great-circle guide is an rrr dyad whose second link, 90° long, turns about the "
            "guide's pole; write that DyadJoint instead"
        )
    if space == "sphere":
        instead = {
            CrankJoint: "SphereCrankJoint (an arc, and the fixed joint its angle starts towards)",
            RigidJoint: "SphereRigidJoint (an arc and an angle from the link)",
        }[type(joint)]
        return (
            f"joint {name!r} is a planar {type(joint).__name__}, but this linkage is spherical: "
            f"use {instead}"
        )
    return (
        f"joint {name!r} is a spherical {type(joint).__name__}, but this linkage is planar "
        "(give space='sphere' for a spherical linkage)"
    )


def _default_toward(joint: SphereCrankJoint, placed: list[Joint], index: int) -> str:
    """The first fixed joint listed before the crank other than its pivot."""
    for j in placed:
        if isinstance(j, FixedJoint) and j.name != joint.pivot:
            return j.name
    raise InvalidLinkage(
        f"joint {joint.name!r}: a spherical crank's angle is measured from the great circle "
        "towards a second fixed joint (toward), and no fixed joint other than its pivot is "
        "listed before it",
        index=index,
        joint=joint.name,
        field="toward",
    )


def _check_sphere_crank(
    joint: SphereCrankJoint, placed: list[Joint], seen: dict[str, int], index: int
) -> None:
    """A spherical crank turns about a ground axis, its zero set by another ground axis.

    The engine's crank measures its angle in the pivot's fixed tangent plane, which only a
    ground pivot has; a crank carried by a moving link would need that link's frame.
    """
    name = joint.name

    def fail(problem: str, attr: str) -> InvalidLinkage:
        return InvalidLinkage(f"joint {name!r}: {problem}", index=index, joint=name, field=attr)

    for attr in ("pivot", "toward"):
        other = placed[seen[getattr(joint, attr)]]
        if not isinstance(other, FixedJoint):
            what = "turns about" if attr == "pivot" else "measures its angle towards"
            raise fail(
                f"a spherical crank {what} a fixed joint, and {other.name!r} is a "
                f"{other.type} joint ({attr})",
                attr,
            )
    if joint.toward == joint.pivot:
        raise fail(
            f"pivot and toward are both {joint.pivot!r} (the crank's angle is measured from "
            "the great circle towards a second fixed joint)",
            "toward",
        )


# --------------------------------------------------------------------------------------------
# The family
# --------------------------------------------------------------------------------------------


@family_dataclass
class Linkage(Mechanism):
    """A planar or spherical linkage composed joint by joint, driven by its crank(s).

    Parameters
    ----------
    joints : tuple of joint specs
        In the plane :class:`FixedJoint`, :class:`CrankJoint`, :class:`DyadJoint`,
        :class:`SliderJoint`, :class:`RigidJoint`; on the sphere :class:`FixedJoint`,
        :class:`SphereCrankJoint`, :class:`DyadJoint`, :class:`SphereRigidJoint`. In
        construction order: each joint is built from joints listed before it. At least one
        crank; the input θ turns every crank (``phase + ratio·θ``).
    traced : tuple of str, optional
        The joints whose paths are the linkage's curves; the first is the one a tool draws by
        default. Defaults to the last joint. A single name may be given as a string.
    space : ``"plane"`` (default) or ``"sphere"``
        Where the joints live: points [x, y], or unit vectors (joint axes through the centre
        of the unit sphere) with arcs for lengths.

    Raises
    ------
    InvalidLinkage
        (an :class:`InvalidMechanism`) for an ill-formed linkage, naming the joint: a name that
        is not a non-empty string or is used twice; a joint built from one that is missing or
        listed after it, or from itself (under-constrained); a dyad, slider or rigid point whose
        two parents are one joint; no crank (nothing drives it); lengths that are not positive,
        numbers that are not finite, a ratio of 0, an assembly other than ±1; a rigid point on
        two joints that are not on one rigid link; a joint that repeats an earlier one's
        construction (two names for one point: a pivot listed twice, a dyad given twice); an
        unknown or repeated traced joint; arrays that do not broadcast. On the sphere also: an
        axis that is not three numbers or is zero; an arc outside (0, π) (a rigid point's arc
        outside [0, π]); a crank whose pivot or ``toward`` is not a fixed joint (or no fixed
        joint to default ``toward`` to); two fixed joints on one axis (equal or opposite
        directions); a joint of the other space's kind (a slider above all).

    Examples
    --------
    The crank-rocker of :func:`~linkwright.mechanisms.solve`'s example, written joint by joint:

    >>> from linkwright.mechanisms import solve
    >>> crank_rocker = Linkage(
    ...     joints=(
    ...         FixedJoint("A0", at=[0, 0]),
    ...         FixedJoint("B0", at=[4, 0]),
    ...         CrankJoint("A", pivot="A0", length=1),
    ...         DyadJoint("B", p1="A", r1=5, p2="B0", r2=3.5),
    ...     )
    ... )
    >>> crank_rocker.traced, sorted(crank_rocker.params())
    (('B',), ['A.length', 'A.phase', 'A0.at', 'B.assembly', 'B.r1', 'B.r2', 'B0.at'])

    At θ = 0, A = (1, 0) is 3 from B0, so B is 21.75/6 = 3.625 along A→B0 and
    √(25 − 3.625²) = 3.443744 to its left:

    >>> np.round(solve(crank_rocker, [0.0]).positions["B"], 6)
    array([[4.625   , 3.443744]])

    Every ill-formed linkage is refused with a message naming the joint:

    >>> Linkage(joints=(FixedJoint("A0", [0, 0]), CrankJoint("A", pivot="O", length=1)))
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'A' is built from 'O', which is not \
placed before it (no joint has that name; under-constrained)

    On the sphere: paper 000's Fig. 6 crank-rocker (a1..a4 = 40°, 20°, 45°, 35°; coupler point
    at AC = 50°, μ = BAC = 130°), the crank's angle measured from the frame circle towards B0:

    >>> from linkwright.geometry import sphere
    >>> a1, a2, a3, a4, ac, mu = np.radians([40, 20, 45, 35, 50, 130])
    >>> fig6 = Linkage(
    ...     joints=(
    ...         FixedJoint("A0", at=[1, 0, 0]),
    ...         FixedJoint("B0", at=[np.cos(a1), np.sin(a1), 0]),
    ...         SphereCrankJoint("A", pivot="A0", arc=a2, toward="B0"),
    ...         DyadJoint("B", p1="A", r1=a3, p2="B0", r2=a4),
    ...         SphereRigidJoint("P", origin="A", toward="B", arc=ac, angle=mu),
    ...     ),
    ...     space="sphere",
    ... )
    >>> m = solve(fig6, [0.0])
    >>> np.round(m.positions["B"], 6)
    array([[0.509774, 0.666849, 0.543546]])

    B is on the coupler and the rocker, on the side of +(A × B0) (``assembly = 1``):

    >>> pos = m.positions
    >>> np.degrees(sphere.arc(pos["A"], pos["B"])), np.degrees(sphere.arc(pos["B0"], pos["B"]))
    (array([45.]), array([35.]))
    >>> bool(sphere.dot(sphere.cross(pos["A"], pos["B0"]), pos["B"])[0] > 0)
    True

    A spherical linkage that cannot assemble gives NaN, masked by ``valid``:

    >>> far = Linkage(
    ...     joints=(
    ...         FixedJoint("A0", [1, 0, 0]),
    ...         FixedJoint("B0", [0, 1, 0]),
    ...         SphereCrankJoint("A", "A0", np.radians(10)),
    ...         DyadJoint("B", "A", np.radians(20), "B0", np.radians(30)),
    ...     ),
    ...     space="sphere",
    ... )
    >>> m = solve(far, [0.0])
    >>> m.valid, m.positions["B"]
    (array([False]), array([[nan, nan, nan]]))

    A slider has no spherical joint of its own:

    >>> Linkage(joints=(*far.joints[:3], SliderJoint("B", "A", 1.0, "B0", 0.0)), space="sphere")
    Traceback (most recent call last):
    ...
    linkwright.mechanisms.linkage.InvalidLinkage: joint 'B': a slider (rrp) has no spherical \
counterpart: a pin on a great-circle guide is an rrr dyad whose second link, 90° long, turns \
about the guide's pole; write that DyadJoint instead
    """

    joints: tuple[Joint, ...]
    traced: tuple[str, ...] | str | None = None
    space: str = "plane"  # type: ignore[assignment]  # a field here, a property on Mechanism

    family: ClassVar[str] = "linkage"

    def __post_init__(self) -> None:
        # The base class checks fields named in class-level tables; a composed linkage's fields
        # are per joint, so it validates them itself (and never calls the base check).
        space = self.space
        if not isinstance(space, str) or space not in SPACES:
            raise InvalidLinkage(
                f"space: must be 'plane' or 'sphere', got {space!r}", field="space"
            )
        joints = self._checked_joints()
        traced = self._checked_traced(joints)
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "traced", traced)
        _check_bodies(joints)
        _check_repeats(joints, space)
        steps, params, points = _compile(joints, space)
        object.__setattr__(self, "_plan", Plan(steps, traced=traced))
        for key, value in params.items():  # read-only copies, as every family's fields
            params[key] = frozen = np.array(value, dtype=float)
            frozen.flags.writeable = False
        object.__setattr__(self, "_params", params)
        object.__setattr__(self, "_points", points)
        try:
            batch_shape(params, points)
        except ValueError as exc:
            raise InvalidLinkage(f"dimension arrays do not broadcast together: {exc}") from None

    # -- validation ---------------------------------------------------------------------------

    def _checked_joints(self) -> tuple[Joint, ...]:
        raw = self.joints
        if isinstance(raw, str | bytes) or not isinstance(raw, Iterable):
            raise InvalidLinkage(f"joints: must be a sequence of joint specs, got {raw!r}")
        raw = tuple(raw)
        if not raw:
            raise InvalidLinkage("a linkage needs joints: at least a fixed pivot and a crank")
        space = self.space
        specs = _ALL_SPECS
        names = {j.name for j in raw if isinstance(j, specs) and isinstance(j.name, str)}
        seen: dict[str, int] = {}
        out: list[Joint] = []
        for index, joint in enumerate(raw):
            if not isinstance(joint, specs):
                kinds = ", ".join(cls.__name__ for cls in SPACES[space].values())
                raise InvalidLinkage(
                    f"joints[{index}]: must be a joint spec ({kinds}), got {joint!r}", index=index
                )
            name = joint.name
            if not isinstance(name, str) or not name:
                raise InvalidLinkage(
                    f"joints[{index}]: name must be a non-empty string, got {name!r}",
                    index=index,
                    field="name",
                )
            if name in seen:
                raise InvalidLinkage(
                    f"joint {name!r} is listed twice (joints[{seen[name]}] and joints[{index}]); "
                    "each joint needs its own name",
                    index=index,
                    joint=name,
                    field="name",
                )
            if type(joint) not in SPACES[space].values():
                raise InvalidLinkage(_wrong_space(joint, space), index=index, joint=name)
            if isinstance(joint, SphereCrankJoint) and joint.toward is None:
                joint = replace(joint, toward=_default_toward(joint, out, index))
            for attr in _REFERENCES[type(joint)]:
                parent = getattr(joint, attr)
                if not isinstance(parent, str):
                    raise InvalidLinkage(
                        f"joint {name!r}: {attr} must be a joint name, got {parent!r}",
                        index=index,
                        joint=name,
                        field=attr,
                    )
                if parent == name:
                    raise InvalidLinkage(
                        f"joint {name!r} is built from itself ({attr}); under-constrained",
                        index=index,
                        joint=name,
                        field=attr,
                    )
                if parent not in seen:
                    where = "it is listed after it" if parent in names else "no joint has that name"
                    raise InvalidLinkage(
                        f"joint {name!r} is built from {parent!r}, which is not placed before it "
                        f"({where}; under-constrained)",
                        index=index,
                        joint=name,
                        field=attr,
                    )
            if isinstance(joint, SphereCrankJoint):
                _check_sphere_crank(joint, out, seen, index)
            a, b = (joint.parents + ("", ""))[:2]
            if len(joint.parents) == 2 and a == b:
                what = {
                    "rrr": "a dyad needs two different joints: one link to each",
                    "rrp": "the slider's rod and its guide need two different joints",
                    "rigid": "a link's frame needs two different joints",
                }[joint.type]
                attrs = _REFERENCES[type(joint)]
                raise InvalidLinkage(
                    f"joint {name!r}: {attrs[0]} and {attrs[1]} are both {a!r} ({what})",
                    index=index,
                    joint=name,
                    field=attrs[1],
                )
            values = {
                attr: _numeric(joint, index, attr, what)
                for attr, what in _numeric_kinds(joint, space).items()
            }
            out.append(replace(joint, **values))
            seen[name] = index
        if not any(isinstance(j, CrankJoint | SphereCrankJoint) for j in out):
            raise InvalidLinkage(
                "nothing drives the linkage: none of its joints is a crank (under-constrained)"
            )
        return tuple(out)

    def _checked_traced(self, joints: tuple[Joint, ...]) -> tuple[str, ...]:
        traced = self.traced
        if traced is None:
            return (joints[-1].name,)
        if isinstance(traced, str):
            traced = (traced,)
        if not isinstance(traced, Iterable):
            raise InvalidLinkage(f"traced: must be joint names, got {traced!r}", field="traced")
        traced = tuple(traced)
        if not traced:
            raise InvalidLinkage("traced: name at least one joint", field="traced")
        names = [j.name for j in joints]
        for i, name in enumerate(traced):
            if not isinstance(name, str) or name not in names:
                raise InvalidLinkage(
                    f"traced: {name!r} is not a joint of this linkage", field="traced"
                )
            if name in traced[:i]:
                raise InvalidLinkage(f"traced: {name!r} is listed twice", field="traced")
        return traced

    # -- the Mechanism protocol ---------------------------------------------------------------

    @property
    def plan(self) -> Plan:  # type: ignore[override]
        """The engine plan: one step per joint, in the order given."""
        return self._plan  # type: ignore[attr-defined]

    @property
    def point_fields(self) -> frozenset[str]:  # type: ignore[override]
        """Parameters that are points: ``"<name>.at"`` of every fixed joint."""
        return self._points  # type: ignore[attr-defined]

    @property
    def reported_joints(self) -> tuple[str, ...]:  # type: ignore[override]
        """Every joint, in construction order."""
        return tuple(j.name for j in self.joints)  # type: ignore[union-attr]

    @property
    def traced_joint(self) -> str:  # type: ignore[override]
        """The first traced joint: the one a tool draws when asked for "the" curve."""
        return self.traced[0]  # type: ignore[index]

    def params(self) -> dict[str, Array]:
        """The plan's named parameters (a fresh mapping; the arrays are the linkage's own)."""
        return dict(self._params)  # type: ignore[attr-defined]

    def _indexed(self, shape: tuple[int, ...], index: object) -> Linkage:
        """A batch's linkages at ``index``: every joint's numbers indexed over the batch."""

        def pick(joint: Joint) -> Joint:
            changes = {}
            for f in fields(joint):
                value = getattr(joint, f.name)
                if isinstance(value, str) or f.name in ("name",):
                    continue
                array = np.asarray(value, dtype=float)
                tail = array.shape[-1:] if f.name == "at" else ()
                changes[f.name] = np.broadcast_to(array, shape + tail)[index]  # type: ignore[index]
            return replace(joint, **changes)

        return replace(self, joints=tuple(pick(j) for j in self.joints))  # type: ignore[union-attr]

    def joint(self, name: str) -> Joint:
        """The spec of the joint called ``name`` (``KeyError`` if there is none)."""
        for j in self.joints:  # type: ignore[union-attr]
            if j.name == name:
                return j
        raise KeyError(name)

    @property
    def assemblies(self) -> dict[str, Array]:
        """Each dyad's and slider's assembly sign, by joint name, in construction order."""
        return {
            j.name: j.assembly  # type: ignore[misc]
            for j in self.joints  # type: ignore[union-attr]
            if isinstance(j, DyadJoint | SliderJoint)
        }

    @property
    def scale(self) -> Array:
        """A characteristic size: the largest length, rigid offset or distance between pivots.

        On the sphere it is 1, the sphere's radius (arcs are already relative).
        """
        if self.space == "sphere":
            return np.float64(1.0)
        sizes: list[Array] = []
        pivots: list[Array] = []
        for j in self.joints:  # type: ignore[union-attr]
            if isinstance(j, FixedJoint):
                pivots.append(np.asarray(j.at))
            elif isinstance(j, CrankJoint):
                sizes.append(np.asarray(j.length))
            elif isinstance(j, DyadJoint):
                sizes += [np.asarray(j.r1), np.asarray(j.r2)]
            elif isinstance(j, SliderJoint):
                sizes.append(np.asarray(j.r))
            else:
                sizes.append(np.hypot(j.u, j.v))
        for i, p in enumerate(pivots):
            sizes += [plane.norm(p - q) for q in pivots[:i]]
        return np.maximum.reduce(np.broadcast_arrays(*sizes))

    def with_assembly(self, assembly: ArrayLike | Mapping[str, ArrayLike]) -> Linkage:
        """The same linkage on other assembly signs.

        ``assembly`` is a mapping joint name → sign for the dyads and sliders to change, or one
        sign (or array of signs) given to every dyad and slider (as a four-bar's single
        ``assembly`` is).
        """
        own = self.assemblies
        if isinstance(assembly, Mapping):
            for name in assembly:
                if name not in own:
                    raise InvalidLinkage(
                        f"with_assembly: {name!r} is not a dyad or slider joint of this linkage",
                        joint=name if isinstance(name, str) else None,
                        field="assembly",
                    )
            signs = dict(assembly)
        else:
            signs = dict.fromkeys(own, assembly)
        joints = tuple(
            replace(j, assembly=signs[j.name]) if j.name in signs else j  # type: ignore[call-arg]
            for j in self.joints  # type: ignore[union-attr]
        )
        return Linkage(joints=joints, traced=self.traced, space=self.space)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Every constraint's error at every sample, divided by :attr:`scale`.

        Keys are ``"<joint>.<constraint>"``: a crank's ``length`` and ``angle`` (the arm's
        sideways error against the direction ``phase + ratio·θ``), a dyad's ``r1`` and ``r2``,
        a slider's ``r`` and ``line`` (distance from the guide), a rigid point's ``u`` and ``v``
        (its local coordinates' errors). Each has the motion's shape; NaN where not assembled.

        On the sphere every error is an arc (radians): a crank's ``arc`` (arc from its pivot
        minus its own) and ``angle`` (its angle about the pivot minus ``phase + ratio·θ``,
        wrapped to (−π, π], times the sine of its arc: the error along its own circle), a
        dyad's ``r1`` and ``r2``, a rigid point's ``point`` (arc from its place on its link),
        and ``unit``, the largest departure of any joint from the unit sphere.
        """
        if self.space == "sphere":
            return self._sphere_residuals(motion)
        pos = motion.positions
        s = np.asarray(self.scale)[..., None]
        out: dict[str, Array] = {}

        def dist(a: str, b: str, length: ArrayLike) -> Array:
            return plane.norm(pos[b] - pos[a]) - np.asarray(length)[..., None]

        for j in self.joints:  # type: ignore[union-attr]
            n = j.name
            if isinstance(j, CrankJoint):
                out[f"{n}.length"] = dist(j.pivot, n, j.length) / s
                phi = np.asarray(j.phase)[..., None] + np.asarray(j.ratio)[..., None] * motion.input
                arm = pos[n] - pos[j.pivot]
                out[f"{n}.angle"] = plane.cross(plane.unit_direction(phi), arm) / s
            elif isinstance(j, DyadJoint):
                out[f"{n}.r1"] = dist(j.p1, n, j.r1) / s
                out[f"{n}.r2"] = dist(j.p2, n, j.r2) / s
            elif isinstance(j, SliderJoint):
                out[f"{n}.r"] = dist(j.p1, n, j.r) / s
                normal = plane.perp(plane.unit_direction(j.line_angle))[..., None, :]
                out[f"{n}.line"] = plane.dot(pos[n] - pos[j.line_point], normal) / s
            elif isinstance(j, RigidJoint):
                o, t = pos[j.origin], pos[j.toward]
                e = (t - o) / plane.norm(t - o)[..., None]
                rel = pos[n] - o
                out[f"{n}.u"] = (plane.dot(rel, e) - np.asarray(j.u)[..., None]) / s
                out[f"{n}.v"] = (plane.cross(e, rel) - np.asarray(j.v)[..., None]) / s
        return out

    def _sphere_residuals(self, motion: Motion) -> dict[str, Array]:
        pos = motion.positions
        out: dict[str, Array] = {}

        def per_sample(value: ArrayLike) -> Array:
            return np.asarray(value)[..., None]

        def arc_error(a: str, b: str, length: ArrayLike) -> Array:
            return sphere.arc(pos[a], pos[b]) - per_sample(length)

        # Each error is measured anew from the joints' positions and the spec's own numbers
        # (sphere.angle_at, sphere.point_at), not by the engine's steps.
        for j in self.joints:  # type: ignore[union-attr]
            n = j.name
            if isinstance(j, SphereCrankJoint):
                phi = per_sample(j.phase) + per_sample(j.ratio) * motion.input
                toward = pos[j.toward]
                turned = sphere.angle_at(pos[j.pivot], toward, pos[n]) - phi
                wrapped = np.remainder(turned + np.pi, 2 * np.pi) - np.pi
                out[f"{n}.arc"] = arc_error(j.pivot, n, j.arc)
                out[f"{n}.angle"] = wrapped * np.sin(per_sample(j.arc))
            elif isinstance(j, DyadJoint):
                out[f"{n}.r1"] = arc_error(j.p1, n, j.r1)
                out[f"{n}.r2"] = arc_error(j.p2, n, j.r2)
            elif isinstance(j, SphereRigidJoint):
                o, t = pos[j.origin], pos[j.toward]
                place = sphere.point_at(o, t, per_sample(j.arc), per_sample(j.angle))
                out[f"{n}.point"] = sphere.arc(pos[n], place)
        out["unit"] = np.maximum.reduce([np.abs(sphere.norm(p) - 1.0) for p in pos.values()])
        return out


# --------------------------------------------------------------------------------------------
# Structure checks and compilation
# --------------------------------------------------------------------------------------------


def _check_bodies(joints: tuple[Joint, ...]) -> None:
    """Refuse a rigid point on two joints whose distance is not constant.

    The engine differentiates a rigid point with its link's length held constant; on two joints
    of different links that derivative (and the "point on a link" itself) would be wrong.
    Rigid clusters are grown as the joints are placed: the ground holds every fixed joint; a
    crank or a rod is a two-joint link; a dyad on two joints of one cluster is a rigid triangle
    and joins it; a rigid point joins every cluster that holds its two parents.
    """
    ground: set[str] = set()
    clusters: list[set[str]] = [ground]
    for index, j in enumerate(joints):
        if isinstance(j, FixedJoint):
            ground.add(j.name)
        elif isinstance(j, CrankJoint | SphereCrankJoint):
            clusters.append({j.pivot, j.name})
        elif isinstance(j, DyadJoint):
            shared = [c for c in clusters if j.p1 in c and j.p2 in c]
            for c in shared:
                c.add(j.name)
            if not shared:
                clusters += [{j.p1, j.name}, {j.p2, j.name}]
        elif isinstance(j, SliderJoint):
            # The guide keeps its direction, so only a grounded rod on a grounded guide is rigid
            # with anything beyond the rod itself.
            if j.p1 in ground and j.line_point in ground:
                ground.add(j.name)
            else:
                clusters.append({j.p1, j.name})
        else:
            shared = [c for c in clusters if j.origin in c and j.toward in c]
            if not shared:
                raise InvalidLinkage(
                    f"joint {j.name!r} is fixed on the link {j.origin!r}→{j.toward!r}, but those "
                    "two joints are not on one rigid link (their distance changes as it moves)",
                    index=index,
                    joint=j.name,
                    field="toward",
                )
            for c in shared:
                c.add(j.name)


def _construction(j: Joint, space: str) -> tuple[tuple[Any, ...], ...]:
    """The ways of writing this joint's construction (parent names and values) as one key."""
    if isinstance(j, FixedJoint):
        # On the sphere a pivot is an axis: [2, 0, 0] is [1, 0, 0], and so is [-1, 0, 0].
        return (("axis", _unit_axis(j.at)),) if space == "sphere" else (("fixed", j.at),)
    if isinstance(j, CrankJoint):
        return (("crank", j.pivot, j.length, j.ratio, j.phase),)
    if isinstance(j, SphereCrankJoint):
        return (("crank", j.pivot, j.toward, j.arc, j.ratio, j.phase),)
    if isinstance(j, DyadJoint):
        # The same dyad written from its other parent first has the opposite assembly sign.
        return (
            ("rrr", j.p1, j.r1, j.p2, j.r2, j.assembly),
            ("rrr", j.p2, j.r2, j.p1, j.r1, -np.asarray(j.assembly)),
        )
    if isinstance(j, SliderJoint):
        return (("rrp", j.p1, j.r, j.line_point, j.line_angle, j.assembly),)
    if isinstance(j, SphereRigidJoint):
        return (("rigid", j.origin, j.toward, j.arc, j.angle),)
    return (("rigid", j.origin, j.toward, j.u, j.v),)


def _same(a: tuple[Any, ...], b: tuple[Any, ...]) -> bool:
    """Two construction keys place one point (for some member of a batch)."""
    if len(a) != len(b) or a[0] != b[0]:
        return False
    if a[0] == "axis":
        try:
            # Unit vectors within ~1e-12 rad of one line: one axis, whichever way it points.
            return bool(np.any(sphere.norm(sphere.cross(a[1], b[1])) <= _AXIS_TOL))
        except ValueError:  # batch shapes that do not broadcast: reported after this check
            return False
    together = np.ones((), dtype=bool)
    for x, y in zip(a[1:], b[1:], strict=True):
        if isinstance(x, str) or isinstance(y, str):
            if x != y:
                return False
            continue
        try:
            equal = np.asarray(x) == np.asarray(y)
            if a[0] == "fixed":
                equal = np.all(equal, axis=-1)
            together = together & equal
        except ValueError:  # batch shapes that do not broadcast: reported after this check
            return False
    return bool(np.any(together))


def _check_repeats(joints: tuple[Joint, ...], space: str) -> None:
    """Refuse a joint whose construction repeats an earlier joint's: two names for one point.

    Kinematically harmless by itself, it is always a slip (a pivot pasted twice, a dyad given
    twice), and a link between the two names would need a length of zero; the frame pivots of
    any dyad built on them would coincide and it could never be assembled. On the sphere two
    ground axes in opposite directions are one revolute as well: a dyad between them has no
    great circle to stand on, a crank no direction to start from.
    """
    for index, j in enumerate(joints):
        keys = _construction(j, space)
        for earlier in joints[:index]:
            if any(_same(k, _construction(earlier, space)[0]) for k in keys):
                if not isinstance(j, FixedJoint):
                    what = "the same construction from the same joints"
                elif space == "sphere":
                    what = "a ground pivot on the same axis, in the same or opposite direction"
                else:
                    what = "a ground pivot at the same place"
                raise InvalidLinkage(
                    f"joint {j.name!r} repeats joint {earlier.name!r} ({what}): two names for "
                    "one point; over-constrained as written, use one joint",
                    index=index,
                    joint=j.name,
                )


def _compile(
    joints: tuple[Joint, ...], space: str
) -> tuple[tuple[Any, ...], dict[str, Array], frozenset[str]]:
    """The plan's steps, its named parameters and the point parameters."""
    steps: list[Any] = []
    params: dict[str, Array] = {}
    points: set[str] = set()
    for j in joints:
        n = j.name

        def key(attr: str, j: Joint = j, n: str = n) -> str:
            params[f"{n}.{attr}"] = getattr(j, attr)
            return f"{n}.{attr}"

        if isinstance(j, FixedJoint):
            steps.append(Fixed(n, key("at")))
            points.add(f"{n}.at")
            if space == "sphere":
                params[f"{n}.at"] = _unit_axis(j.at)  # type: ignore[arg-type]
        elif isinstance(j, SphereCrankJoint):
            unit = np.ndim(j.ratio) == 0 and float(j.ratio) == 1.0  # type: ignore[arg-type]
            ratio = 1.0 if unit else key("ratio")
            # The crank's zero direction is the `toward` pivot's own (unit) axis parameter.
            steps.append(
                SphereCrank(
                    n, j.pivot, key("arc"), ref=f"{j.toward}.at", ratio=ratio, phase=key("phase")
                )
            )
        elif isinstance(j, DyadJoint) and space == "sphere":
            steps.append(SphereDyad(n, j.p1, key("r1"), j.p2, key("r2"), branch=key("assembly")))
        elif isinstance(j, SphereRigidJoint):
            steps.append(SphereRigid(n, j.origin, j.toward, key("arc"), key("angle")))
        elif isinstance(j, CrankJoint):
            # A scalar ratio of exactly 1 goes into the plan as a constant: the engine recognises
            # that case (a crank turning with the input) and finds its limits in closed form.
            unit = np.ndim(j.ratio) == 0 and float(j.ratio) == 1.0
            ratio = 1.0 if unit else key("ratio")
            steps.append(Crank(n, j.pivot, key("length"), ratio=ratio, phase=key("phase")))
        elif isinstance(j, DyadJoint):
            steps.append(DyadRRR(n, j.p1, key("r1"), j.p2, key("r2"), branch=key("assembly")))
        elif isinstance(j, SliderJoint):
            steps.append(
                DyadRRP(n, j.p1, key("r"), j.line_point, key("line_angle"), branch=key("assembly"))
            )
        else:
            steps.append(Rigid(n, j.origin, j.toward, key("u"), key("v")))
    return tuple(steps), params, frozenset(points)


# --------------------------------------------------------------------------------------------
# The registry
# --------------------------------------------------------------------------------------------

register(
    Family(
        name="linkage",
        cls=Linkage,
        display="Composed linkage",
        group="Free linkages",
        space="either",
        example="jansen-leg",
        fields=(
            FieldSpec("space", "space", default="plane"),
            FieldSpec("joints", "joints"),
            FieldSpec(
                "traced",
                "names",
                default=Derived(
                    "the last joint",
                    lambda m: [m["joints"][-1]["name"]] if m["joints"] else [],
                ),
            ),
        ),
        joints=(("(any)", "every joint is named in the document"),),
        source="any linkage built joint by joint (Jansen's and Klann's legs are bundled)",
    )
)

"""Family ``linkage``: a planar or spherical linkage the user composes joint by joint.

A :class:`Linkage` is an ordered tuple of joint specs, each placing one joint from joints listed
before it (a driven hinge places two, a triad three), exactly as the engine's construction
plans do (see DESIGN.md). The specs, in the plane and on the sphere, and their assembly signs
are described in :mod:`.joints` (:class:`FixedJoint`, :class:`CrankJoint`, :class:`DyadJoint`,
:class:`SliderJoint`, :class:`RigidJoint`, :class:`HingeJoint`, :class:`TriadJoint`,
:class:`SphereCrankJoint`, :class:`SphereRigidJoint`, :class:`SphereTriadJoint`); the checks
that refuse an ill-formed construction are in :mod:`.linkage_checks`. Both are re-exported
here.

Mobility, as a sanity line (Grübler: M = 3(n − 1) − 2j for n links and j lower pairs, the same
count on the sphere, where a body also has three freedoms, its rotations about O): a crank
adds one link and one pin, and its angle is the input (a second crank is geared to the input,
one more constraint); a dyad adds two links and three pins, 3·2 − 2·3 = 0; a slider pin adds a
rod and a block with two pins and one slide, 3·2 − 2·3 = 0 again; a rigid point adds nothing.
A driven hinge adds three links (z–X, X–H, H–y) and four pins, 3·3 − 2·4 = 1, the freedom its
angle takes as the input in place of a crank's. A triad adds four links (the ternary and its
three binaries) and six pins, 3·4 − 2·6 = 0, as a dyad does. So a linkage built this way has
exactly one degree of freedom: the four-bar (n = 4, j = 4) gives 3·3 − 8 = 1, Jansen's leg
(n = 8, j = 10) 3·7 − 20 = 1. What a user *can* write wrongly is therefore an ill-formed
construction, and :class:`Linkage` refuses each kind with one message that names the joint
(:class:`InvalidLinkage`).

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
from dataclasses import fields, replace
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
from linkwright.engine.hinge_steps import Hinge, SphereHinge
from linkwright.engine.triad_steps import SphereTriad, Triad
from linkwright.geometry import plane, sphere
from linkwright.mechanisms.base import Mechanism, family_dataclass
from linkwright.mechanisms.hinge_joints import HINGED_TRIADS
from linkwright.mechanisms.joints import (
    ALL_SPECS,
    JOINT_TYPES,
    PLACES,
    REFERENCES,
    SPACES,
    SPHERE_JOINT_TYPES,
    CrankJoint,
    DyadJoint,
    FixedJoint,
    HingeJoint,
    InvalidLinkage,
    Joint,
    RigidJoint,
    SliderJoint,
    SphereCrankJoint,
    SphereRigidJoint,
    SphereTriadJoint,
    TriadJoint,
    numeric_kinds,
    placed_by,
    unit_axis,
)
from linkwright.mechanisms.linkage_checks import (
    check_bodies,
    check_repeats,
    check_sphere_crank,
    check_triad,
    checked_number,
    default_toward,
    wrong_space,
)
from linkwright.mechanisms.registry import Derived, Family, FieldSpec, register

__all__ = [
    "ALL_SPECS",
    "JOINT_TYPES",
    "SPACES",
    "SPHERE_JOINT_TYPES",
    "CrankJoint",
    "DyadJoint",
    "FixedJoint",
    "HingeJoint",
    "InvalidLinkage",
    "Joint",
    "Linkage",
    "RigidJoint",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereRigidJoint",
    "SphereTriadJoint",
    "TriadJoint",
    "numeric_kinds",
]

Array = NDArray[np.float64]

DRIVEN_HINGES = (HingeJoint, *HINGED_TRIADS)
"""The specs that drive the linkage at a moving hinge (its one input, in place of a crank)."""

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
        :class:`SliderJoint`, :class:`RigidJoint`, :class:`HingeJoint`, :class:`TriadJoint`;
        on the sphere :class:`FixedJoint`, :class:`SphereCrankJoint`, :class:`DyadJoint`,
        :class:`SphereRigidJoint`, :class:`HingeJoint`, :class:`SphereTriadJoint`. In
        construction order: each joint is built from joints listed before it. At least one
        crank (or one driven hinge); the input θ turns every crank (``phase + ratio·θ``).
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
        directions); a joint of the other space's kind (a slider above all). A triad whose
        J2 or J3 is not a new name, or whose third joint sits on one of the other two, or whose
        pose index is not a whole number below its most poses (6; 8 on the sphere).

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
    space: str = "plane"

    family: ClassVar[str] = "linkage"
    # Per linkage, set once by __post_init__; declared ClassVar only so that the dataclass
    # does not take them for fields (they are derived from ``joints``, never given).
    _plan: ClassVar[Plan]
    _params: ClassVar[dict[str, Array]]
    _points: ClassVar[frozenset[str]]

    def __post_init__(self) -> None:
        # The base class checks fields named in class-level tables; a composed linkage's fields
        # are per joint, so it validates them itself (and never calls the base check).
        self._check_start()
        space = self.space
        if not isinstance(space, str) or space not in SPACES:
            raise InvalidLinkage(
                f"space: must be 'plane' or 'sphere', got {space!r}", field="space"
            )
        joints = self._checked_joints()
        traced = self._checked_traced(joints)
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "traced", traced)
        check_bodies(joints)
        check_repeats(joints, space)
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
        specs = ALL_SPECS
        names = {n for j in raw if isinstance(j, specs) for n in placed_by(j) if isinstance(n, str)}
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
                raise InvalidLinkage(wrong_space(joint, space), index=index, joint=name)
            others: list[str] = [name]
            for attr in PLACES.get(type(joint), ()):
                extra = getattr(joint, attr)
                if not isinstance(extra, str) or not extra or extra in others or extra in seen:
                    taken = (
                        "the hinge's"
                        if isinstance(joint, HingeJoint)
                        else " and ".join(repr(n) for n in others)
                    )
                    what = (
                        f"a non-empty joint name other than {taken}"
                        if not isinstance(extra, str) or not extra or extra in others
                        else f"a new joint's name ({extra!r} is listed at joints[{seen[extra]}])"
                    )
                    raise InvalidLinkage(
                        f"joint {name!r}: {attr} must be {what}, got {extra!r}",
                        index=index,
                        joint=name,
                        field=attr,
                    )
                others.append(extra)
            if isinstance(joint, SphereCrankJoint) and joint.toward is None:
                joint = replace(joint, toward=default_toward(joint, out, index))
            for attr in REFERENCES[type(joint)]:
                parent = getattr(joint, attr)
                if not isinstance(parent, str):
                    raise InvalidLinkage(
                        f"joint {name!r}: {attr} must be a joint name, got {parent!r}",
                        index=index,
                        joint=name,
                        field=attr,
                    )
                if parent in others:
                    itself = "itself" if parent == name else f"{parent!r}, a joint it places"
                    raise InvalidLinkage(
                        f"joint {name!r} is built from {itself} ({attr}); under-constrained",
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
                check_sphere_crank(joint, out, seen, index)
            a, b = (joint.parents + ("", ""))[:2]
            if len(joint.parents) == 2 and a == b:
                what = {
                    "rrr": "a dyad needs two different joints: one link to each",
                    "rrp": "the slider's rod and its guide need two different joints",
                    "rigid": "a link's frame needs two different joints",
                    "hinge": "the far joint hangs from z and the hinge from y: two joints",
                }[joint.type]
                attrs = REFERENCES[type(joint)]
                raise InvalidLinkage(
                    f"joint {name!r}: {attrs[0]} and {attrs[1]} are both {a!r} ({what})",
                    index=index,
                    joint=name,
                    field=attrs[1],
                )
            values: dict[str, Any] = {
                attr: checked_number(joint, index, attr, what)
                for attr, what in numeric_kinds(joint, space).items()
            }
            joint = replace(joint, **values)
            if isinstance(joint, TriadJoint | SphereTriadJoint):
                check_triad(joint, index)
            out.append(joint)
            for placed in placed_by(joint):
                seen[placed] = index
        hinges = [k for k, j in enumerate(out) if isinstance(j, DRIVEN_HINGES)]
        if not hinges and not any(isinstance(j, CrankJoint | SphereCrankJoint) for j in out):
            raise InvalidLinkage(
                "nothing drives the linkage: none of its joints is a crank or a driven hinge "
                "(under-constrained)"
            )
        cranks = [k for k, j in enumerate(out) if isinstance(j, CrankJoint | SphereCrankJoint)]
        if hinges and (cranks or len(hinges) > 1):
            k = (cranks + hinges[1:])[0]
            raise InvalidLinkage(
                f"joint {out[k].name!r}: the hinge {out[hinges[0]].name!r} already drives the "
                "linkage (its one input); a second input over-constrains it",
                index=k,
                joint=out[k].name,
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
        names = [n for j in joints for n in placed_by(j)]
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
        return self._plan

    @property
    def point_fields(self) -> frozenset[str]:  # type: ignore[override]
        """Parameters that are points: ``"<name>.at"`` of every fixed joint."""
        return self._points

    @property
    def reported_joints(self) -> tuple[str, ...]:  # type: ignore[override]
        """Every joint, in construction order."""
        return tuple(n for j in self.joints for n in placed_by(j))

    @property
    def traced_joint(self) -> str:  # type: ignore[override]
        """The first traced joint: the one a tool draws when asked for "the" curve."""
        traced = self.traced
        assert isinstance(traced, tuple)  # __post_init__ made it a tuple of names
        return traced[0]

    def params(self) -> dict[str, Array]:
        """The plan's named parameters (a fresh mapping; the arrays are the linkage's own)."""
        return dict(self._params)

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
                # index is whatever NumPy accepts (an integer, slice, index array or mask).
                changes[f.name] = np.broadcast_to(array, shape + tail)[index]  # type: ignore[call-overload]
            return replace(joint, **changes)

        return replace(self, joints=tuple(pick(j) for j in self.joints))

    def joint(self, name: str) -> Joint:
        """The spec of the joint called ``name`` (``KeyError`` if there is none)."""
        for j in self.joints:
            if name in placed_by(j):
                return j
        raise KeyError(name)

    @property
    def assemblies(self) -> dict[str, Array]:
        """Each dyad's, slider's and driven hinge's assembly sign, by joint name, in
        construction order."""
        return {
            j.name: j.assembly  # type: ignore[misc]
            for j in self.joints
            if isinstance(j, DyadJoint | SliderJoint | HingeJoint)
        }

    @property
    def scale(self) -> Array:
        """A characteristic size: the largest length, rigid offset or distance between pivots.

        On the sphere it is 1, the sphere's radius (arcs are already relative).
        """
        if self.space == "sphere":
            return np.asarray(1.0)
        sizes: list[Array] = []
        pivots: list[Array] = []
        for j in self.joints:
            if isinstance(j, FixedJoint):
                pivots.append(np.asarray(j.at))
            elif isinstance(j, CrankJoint):
                sizes.append(np.asarray(j.length))
            elif isinstance(j, DyadJoint):
                sizes += [np.asarray(j.r1), np.asarray(j.r2)]
            elif isinstance(j, SliderJoint):
                sizes.append(np.asarray(j.r))
            elif isinstance(j, RigidJoint):  # the sphere's joints are not met in the plane
                sizes.append(np.hypot(j.u, j.v))
            elif isinstance(j, HingeJoint):
                sizes += [np.asarray(j.r), np.asarray(j.a), np.asarray(j.b)]
            elif isinstance(j, TriadJoint):
                sizes += [np.asarray(x) for x in (j.r1, j.r2, j.r3, j.side)]
                sizes.append(np.hypot(j.u, j.v))
        for i, p in enumerate(pivots):
            sizes += [plane.norm(p - q) for q in pivots[:i]]
        largest: Array = np.maximum.reduce(np.broadcast_arrays(*sizes))
        return largest

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

        def resigned(j: Joint) -> Joint:
            # Only dyads and sliders are in ``signs`` (it was checked against ``assemblies``).
            if isinstance(j, DyadJoint | SliderJoint | HingeJoint) and j.name in signs:
                return replace(j, assembly=signs[j.name])
            return j

        joints = tuple(resigned(j) for j in self.joints)
        return Linkage(joints=joints, traced=self.traced, space=self.space)

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Every constraint's error at every sample, divided by :attr:`scale`.

        Keys are ``"<joint>.<constraint>"``: a crank's ``length`` and ``angle`` (the arm's
        sideways error against the direction ``phase + ratio·θ``), a dyad's ``r1`` and ``r2``,
        a slider's ``r`` and ``line`` (distance from the guide), a rigid point's ``u`` and ``v``
        (its local coordinates' errors), a triad's ``r1``, ``r2``, ``r3`` (its three links),
        ``side`` (J1 to J2) and ``u``, ``v`` (J3's local coordinates), all under its first
        joint's name. Each has the motion's shape; NaN where not assembled.

        On the sphere every error is an arc (radians): a crank's ``arc`` (arc from its pivot
        minus its own) and ``angle`` (its angle about the pivot minus ``phase + ratio·θ``,
        wrapped to (−π, π], times the sine of its arc: the error along its own circle), a
        dyad's ``r1`` and ``r2``, a rigid point's ``point`` (arc from its place on its link),
        a triad's ``r1``, ``r2``, ``r3``, ``side`` and ``point`` (J3's arc from its place on
        the ternary link), and ``unit``, the largest departure of any joint from the unit
        sphere.
        """
        if self.space == "sphere":
            return self._sphere_residuals(motion)
        pos = motion.positions
        s = np.asarray(self.scale)[..., None]
        out: dict[str, Array] = {}

        def dist(a: str, b: str, length: ArrayLike) -> Array:
            error: Array = plane.norm(pos[b] - pos[a]) - np.asarray(length)[..., None]
            return error

        for j in self.joints:
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
            elif isinstance(j, HingeJoint):
                out[f"{j.far}.r"] = dist(j.z, j.far, j.r) / s
                out[f"{n}.a"] = dist(j.far, n, j.a) / s
                out[f"{n}.b"] = dist(j.y, n, j.b) / s
                # The angle at H against phase + θ, as the sideways error of X (a length).
                phi = np.asarray(j.phase)[..., None] + motion.input
                to_y = (pos[j.y] - pos[n]) / plane.norm(pos[j.y] - pos[n])[..., None]
                turned = np.cos(phi)[..., None] * to_y + np.sin(phi)[..., None] * plane.perp(to_y)
                out[f"{n}.angle"] = plane.cross(turned, pos[j.far] - pos[n]) / s
            elif isinstance(j, TriadJoint):
                for k, (anchor, joint, length) in enumerate(_triad_links(j), start=1):
                    out[f"{n}.r{k}"] = dist(anchor, joint, length) / s
                out[f"{n}.side"] = dist(n, j.j2, j.side) / s
                o, t = pos[n], pos[j.j2]
                e = (t - o) / plane.norm(t - o)[..., None]
                rel = pos[j.j3] - o
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
        for j in self.joints:
            n = j.name
            if isinstance(j, SphereCrankJoint):
                phi = per_sample(j.phase) + per_sample(j.ratio) * motion.input
                assert j.toward is not None  # validation names the default reference
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
            elif isinstance(j, HingeJoint):
                out[f"{j.far}.r"] = arc_error(j.z, j.far, j.r)
                out[f"{n}.a"] = arc_error(j.far, n, j.a)
                out[f"{n}.b"] = arc_error(j.y, n, j.b)
                turned = sphere.angle_at(pos[n], pos[j.y], pos[j.far]) - (
                    per_sample(j.phase) + motion.input
                )
                wrapped = np.remainder(turned + np.pi, 2 * np.pi) - np.pi
                out[f"{n}.angle"] = wrapped * np.sin(per_sample(j.a))
            elif isinstance(j, SphereTriadJoint):
                for k, (anchor, joint, length) in enumerate(_triad_links(j), start=1):
                    out[f"{n}.r{k}"] = arc_error(anchor, joint, length)
                out[f"{n}.side"] = arc_error(n, j.j2, j.side)
                place = sphere.point_at(pos[n], pos[j.j2], per_sample(j.arc), per_sample(j.angle))
                out[f"{n}.point"] = sphere.arc(pos[j.j3], place)
        out["unit"] = np.maximum.reduce([np.abs(sphere.norm(p) - 1.0) for p in pos.values()])
        return out


def _triad_links(j: TriadJoint | SphereTriadJoint) -> tuple[tuple[str, str, ArrayLike], ...]:
    """A triad's three binary links: (anchor, joint, length)."""
    return ((j.p1, j.name, j.r1), (j.p2, j.j2, j.r2), (j.p3, j.j3, j.r3))


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
                params[f"{n}.at"] = unit_axis(j.at)
        elif isinstance(j, SphereCrankJoint):
            unit = np.ndim(j.ratio) == 0 and float(np.asarray(j.ratio)) == 1.0
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
            unit = np.ndim(j.ratio) == 0 and float(np.asarray(j.ratio)) == 1.0

            ratio = 1.0 if unit else key("ratio")
            steps.append(Crank(n, j.pivot, key("length"), ratio=ratio, phase=key("phase")))
        elif isinstance(j, DyadJoint):
            steps.append(DyadRRR(n, j.p1, key("r1"), j.p2, key("r2"), branch=key("assembly")))
        elif isinstance(j, SliderJoint):
            steps.append(
                DyadRRP(n, j.p1, key("r"), j.line_point, key("line_angle"), branch=key("assembly"))
            )
        elif isinstance(j, HingeJoint):
            # The step's branch is a pose index: 0 for the assembly sign −1, 1 for +1.
            params[f"{n}.pose"] = (np.asarray(j.assembly, dtype=float) + 1.0) / 2.0
            kind = SphereHinge if space == "sphere" else Hinge
            steps.append(
                kind(n, j.far, j.z, key("r"), j.y, key("a"), key("b"), key("phase"), f"{n}.pose")
            )
        elif isinstance(j, HINGED_TRIADS):
            steps.append(j.step(key))
        elif isinstance(j, TriadJoint | SphereTriadJoint):
            placed = (n, j.j2, j.j3)
            anchors = (j.p1, j.p2, j.p3)
            lengths = (key("r1"), key("r2"), key("r3"))
            if isinstance(j, SphereTriadJoint):
                body = (key("side"), key("arc"), key("angle"))
                steps.append(SphereTriad(placed, anchors, lengths, *body, pose=key("pose")))
            else:
                body = (key("side"), key("u"), key("v"))
                steps.append(Triad(placed, anchors, lengths, *body, pose=key("pose")))
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

"""The checks a composed linkage's joints pass before they are compiled to a plan.

Each check refuses one kind of ill-formed construction with an :class:`InvalidLinkage` that
names the joint: a field of the wrong kind (:func:`checked_number`), a joint of the other
space's kind (:func:`wrong_space`), a spherical crank not turning about the ground
(:func:`check_sphere_crank`), a rigid point on two joints of different links
(:func:`check_bodies`), and a joint that repeats an earlier one's construction
(:func:`check_repeats`). Why each is refused is said at each check; the mobility argument that
leaves these as the only mistakes a user can make is in :mod:`.linkage`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.sphere_triad import MAX_POSES as SPHERE_POSES
from linkwright.engine.triad import MAX_POSES as PLANE_POSES
from linkwright.geometry import sphere
from linkwright.mechanisms.hinge_joints import (
    HingeTriadJoint,
    SphereHingeTriadJoint,
    SphereTurningTriadJoint,
    TurningTriadJoint,
)
from linkwright.mechanisms.joints import (
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
    unit_axis,
)

__all__ = [
    "check_bodies",
    "check_repeats",
    "check_sphere_crank",
    "check_triad",
    "checked_number",
    "default_toward",
    "wrong_space",
]

Array = NDArray[np.float64]

_AXIS_TOL = 1e-12
"""Two ground axes whose unit vectors' cross product is this small are one axis."""


def _show(value: Array, bad: NDArray[np.bool_]) -> str:
    """The offending value(s): the number itself, or the first few of an array."""
    if value.ndim == 0:
        return repr(float(value))
    return f"{value[bad].ravel()[:3].tolist()} (in an array of shape {value.shape})"


def checked_number(joint: Joint, index: int, attr: str, what: str) -> Array:
    """The field as a float array, checked for ``what`` (point, axis, length, arc, offset,
    ratio, sign, pose, sphere-pose, number)."""
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
    if what in _POSES:
        most = _POSES[what]
        off = (value != np.round(value)) | (value < 0) | (value >= most)
        if np.any(off):
            raise fail(
                f"must be a whole number from 0 to {most - 1} (the triad's pose index), got "
                f"{_show(value, off)}"
            )
    return value


_POSES = {"pose": PLANE_POSES, "sphere-pose": SPHERE_POSES}
"""A triad's pose index runs below its most poses: 6 in the plane, 8 on the sphere."""


def wrong_space(joint: Joint, space: str) -> str:
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
            TriadJoint: "SphereTriadJoint (arcs, and its third joint by an arc and an angle)",
            HingeTriadJoint: "SphereHingeTriadJoint (arcs, and the body as SphereTriadJoint's)",
            TurningTriadJoint: "SphereTurningTriadJoint (arcs; the hinge by an arc and an angle)",
        }[type(joint)]
        return (
            f"joint {name!r} is a planar {type(joint).__name__}, but this linkage is spherical: "
            f"use {instead}"
        )
    return (
        f"joint {name!r} is a spherical {type(joint).__name__}, but this linkage is planar "
        "(give space='sphere' for a spherical linkage)"
    )


def default_toward(joint: SphereCrankJoint, placed: list[Joint], index: int) -> str:
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


def check_sphere_crank(
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


def check_triad(joint: TriadJoint | SphereTriadJoint, index: int) -> None:
    """A triad's ternary link carries three distinct joints.

    With J3 on J1 (or on J2) the link is binary and its two links to the anchors make a dyad:
    the triad's polynomial then has a continuum of roots or none, and the dyad is what to
    write. On the sphere J3 opposite J1 (arc π) is on J1's axis, the same revolute.
    """
    name = joint.name
    if isinstance(joint, TriadJoint):
        u, v, side = (np.asarray(x) for x in (joint.u, joint.v, joint.side))
        on = {"J1": (u == 0) & (v == 0), "J2": (u == side) & (v == 0)}
        attr = "u"
    else:
        arc, angle, side = (np.asarray(x) for x in (joint.arc, joint.angle, joint.side))
        turned = np.remainder(angle, 2 * np.pi)
        on = {
            "J1": (arc == 0) | (arc == np.pi),
            "J2": (arc == side) & ((turned == 0) | (turned == 2 * np.pi)),
        }
        attr = "arc"
    for which, bad in on.items():
        if np.any(bad):
            raise InvalidLinkage(
                f"joint {name!r}: its third joint {joint.j3!r} is placed on {which} "
                f"({joint.placed[0 if which == 'J1' else 1]!r}), so the link carries two joints, "
                "not three; a joint held by two links is a dyad (rrr): write that instead",
                index=index,
                joint=name,
                field=attr,
            )


# --------------------------------------------------------------------------------------------
# The family
# --------------------------------------------------------------------------------------------


def check_bodies(joints: tuple[Joint, ...]) -> None:
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
        elif isinstance(j, HingeJoint):
            clusters += [{j.z, j.far}, {j.far, j.name}, {j.name, j.y}]
        elif isinstance(j, TriadJoint | SphereTriadJoint):
            # Three binary links and the ternary link (ground anchors do not join them: each
            # binary turns about its anchor).
            clusters += [{j.p1, j.name}, {j.p2, j.j2}, {j.p3, j.j3}, {j.name, j.j2, j.j3}]
        elif isinstance(j, HingeTriadJoint | SphereHingeTriadJoint):
            # The third leg is two links, p3–H and H–J3.
            clusters += [{j.p1, j.name}, {j.p2, j.j2}, {j.p3, j.hinge}, {j.hinge, j.j3}]
            clusters.append({j.name, j.j2, j.j3})
        elif isinstance(j, TurningTriadJoint | SphereTurningTriadJoint):
            # The ternary link carries H; the link H–J3 turns on it.
            clusters += [{j.p1, j.name}, {j.p2, j.j2}, {j.p3, j.j3}, {j.hinge, j.j3}]
            clusters.append({j.name, j.j2, j.hinge})
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
        return (("axis", unit_axis(j.at)),) if space == "sphere" else (("fixed", j.at),)
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
    if isinstance(j, HingeJoint):
        return (("hinge", j.z, j.r, j.y, j.a, j.b, j.phase, j.assembly),)
    if isinstance(j, TriadJoint):
        return (("triad", j.p1, j.r1, j.p2, j.r2, j.p3, j.r3, j.side, j.u, j.v, j.pose),)
    if isinstance(j, SphereTriadJoint):
        return (("triad", j.p1, j.r1, j.p2, j.r2, j.p3, j.r3, j.side, j.arc, j.angle, j.pose),)
    if isinstance(j, HingeTriadJoint):
        body: tuple[Any, ...] = (j.side, j.u, j.v)
        return (("hinge-triad", j.p1, j.r1, j.p2, j.r2, j.p3, j.a, j.b, *body, j.phase, j.pose),)
    if isinstance(j, SphereHingeTriadJoint):
        body = (j.side, j.arc, j.angle)
        return (("hinge-triad", j.p1, j.r1, j.p2, j.r2, j.p3, j.a, j.b, *body, j.phase, j.pose),)
    if isinstance(j, TurningTriadJoint):
        body = (j.side, j.hu, j.hv, j.arm)
        return (("turning", j.p1, j.r1, j.p2, j.r2, j.p3, j.r3, *body, j.phase, j.pose),)
    if isinstance(j, SphereTurningTriadJoint):
        body = (j.side, j.harc, j.hangle, j.arm)
        return (("turning", j.p1, j.r1, j.p2, j.r2, j.p3, j.r3, *body, j.phase, j.pose),)
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


def check_repeats(joints: tuple[Joint, ...], space: str) -> None:
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

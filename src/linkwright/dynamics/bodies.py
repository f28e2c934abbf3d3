"""The rigid bodies of a construction plan, and the joints that connect them.

Forces need bodies, which a plan does not list: it places joints. They are read off the step
kinds' own :meth:`links` and :meth:`plates` (never per family), merged where two of them share
two joints or more (they cannot move apart, so they are one body):

- a crank makes the link pivot–joint; cranks about one pivot at one ratio turn as one body;
- a dyad RRR makes its two binary links, a dyad RRP its rod and a *slider block* at the pin
  (a body that only translates, on a guide fixed to the frame);
- a rigid point extends the link that carries it into a plate;
- a triad makes its three binary links and its ternary link;
- a trammel makes a slider block at its joint, and the arm's far end slides on the second
  guide (a massless pin in a slot: a normal force only);
- a driven hinge makes its three binary links, and a triad driven at a hinge its legs, the
  hinge's links and its ternary link. The motor sits between two moving bodies: it turns the
  link from the hinge to the joint it places (X, or the triad's J3) and reacts on the body that
  holds the hinge's other side (the link to Y, or the triad's ternary link).

A body is named by the length field of the link that made it (``crank``, ``coupler``,
``rocker``: the names a document's ``[mechanism.mass]`` table uses); a slider block by
``slider`` (``slider_<pin>`` where a plan has several). Its frame is that link's: origin the
joint it hangs from, x axis towards the joint it places, v to the left.

A *joint* is a point two bodies or more share (the frame counts as a body); a point on one body
only (a coupler point) is a point, where loads may act, not a joint.

On the sphere the same rules read the spherical kinds (crank, dyad, rigid point, triad); a
body's frame is then its link's two joints' axes (origin, toward).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from linkwright.engine.hinge_steps import Hinge, SphereHinge
from linkwright.engine.hinge_triad_steps import (
    BodyHingeTriad,
    LegHingeTriad,
    SphereBodyHingeTriad,
    SphereLegHingeTriad,
)
from linkwright.engine.plan import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Plan,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Trammel,
)

__all__ = ["Body", "Guide", "Structure", "UnsupportedPlan", "structure"]


class UnsupportedPlan(ValueError):
    """A plan whose forces this module cannot set up (the message says why)."""


@dataclass(frozen=True)
class Guide:
    """A straight guide fixed to the frame: through the ground point ``point`` at the angle
    parameter ``angle`` (a field name or a constant, radians)."""

    point: str
    angle: str | float


@dataclass(frozen=True)
class Body:
    """One moving rigid body.

    ``points`` are every named point on it, ``joints`` those it shares with another body or the
    frame; ``frame`` is (origin, toward) of the link that names it (None for a slider block).
    ``guide`` is set for a slider block (it translates along it); ``far_end`` for a trammel's
    arm: (the step, whose far end slides on its second guide).
    """

    name: str
    points: tuple[str, ...]
    joints: tuple[str, ...] = ()
    frame: tuple[str, str] | None = None
    guide: Guide | None = None
    far_end: Trammel | None = field(default=None, compare=False)

    @property
    def is_block(self) -> bool:
        return self.guide is not None


@dataclass(frozen=True)
class Structure:
    """A plan's bodies, in the order its steps make them, and how it is driven.

    ``driven`` is the body the input turns (the first crank's); ``geared`` are the other
    cranks' bodies with their ratio parameters (each turns at ``ratio / driven ratio`` of the
    driven one, through an ideal gear pair on the frame); ``ground`` the frame's points.
    ``counter`` is the body the motor reacts on where it sits at a moving hinge (None: on the
    frame); the input is then the driven body's angle relative to it.
    """

    bodies: tuple[Body, ...]
    ground: frozenset[str]
    driven: int
    driven_ratio: str | float
    geared: tuple[tuple[int, str | float], ...] = ()
    space: str = "plane"
    pivot: str = ""
    """The driven crank's ground pivot, or the driven hinge (on the sphere its axis carries the
    driving torque)."""
    counter: int | None = None

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.bodies)

    def owner(self, point: str) -> int | None:
        """The body a load at ``point`` acts on: the first that carries it (None on the frame:
        a load at a ground pivot goes straight into the frame)."""
        if point in self.ground:
            return None
        for k, b in enumerate(self.bodies):
            if point in b.points:
                return k
        return None

    @property
    def joints(self) -> tuple[str, ...]:
        """Every joint, in plan order of first appearance."""
        seen: dict[str, None] = {}
        for b in self.bodies:
            for j in b.joints:
                seen.setdefault(j, None)
        return tuple(seen)


@dataclass
class _Group:
    points: set[str]
    name: str | None = None
    frame: tuple[str, str] | None = None
    crank: tuple[str, str | float] | None = None  # (pivot, ratio) of the crank that made it
    guide: Guide | None = None
    far_end: Trammel | None = None


def structure(plan: Plan) -> Structure:
    """The bodies of a plan, planar or spherical (see the module's docstring for the rules).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> s = structure(FourBar.plan)
    >>> [(b.name, b.joints) for b in s.bodies]
    [('crank', ('A0', 'A')), ('coupler', ('A', 'B')), ('rocker', ('B0', 'B'))]
    """
    ground = {s.name for s in plan.steps if isinstance(s, Fixed)}
    groups: list[_Group] = []
    for step in plan.steps:
        groups.extend(_groups_of(step, ground))
    merged = _merge(groups, ground)
    moving = [g for g in merged if not len(g.points & ground) >= 2 and not g.points <= ground]
    _name_all(moving)
    count: dict[str, int] = {}
    for g in moving:
        for p in g.points:
            count[p] = count.get(p, 0) + 1
    order = {name: k for k, name in enumerate(plan.joints)}
    bodies = []
    for g in moving:
        pts = tuple(sorted(g.points, key=lambda p: order.get(p, len(order))))
        joints = tuple(p for p in pts if count[p] + (p in ground) >= 2)
        bodies.append(Body(g.name or "", pts, joints, g.frame, g.guide, g.far_end))
    cranks = [k for k, g in enumerate(moving) if g.crank is not None]
    drives = [d for step in plan.steps if (d := _hinge_drive(step)) is not None]
    if drives and not cranks:
        hinge, turned, held = drives[0]

        def holding(pair: tuple[str, str]) -> int:
            return next(k for k, g in enumerate(moving) if set(pair) <= g.points)

        return Structure(
            tuple(bodies),
            frozenset(ground),
            holding(turned),
            1.0,
            (),
            plan.space,
            hinge,
            counter=holding(held),
        )
    if not cranks:
        raise UnsupportedPlan("the plan has no crank: nothing says which link the input drives")
    first_crank = next(s for s in plan.steps if isinstance(s, Crank | SphereCrank))
    driven = next(k for k in cranks if first_crank.name in moving[k].points)
    ratio = first_crank.ratio
    geared = tuple(
        (k, crank[1]) for k in cranks if k != driven and (crank := moving[k].crank) is not None
    )
    return Structure(
        tuple(bodies), frozenset(ground), driven, ratio, geared, plan.space, first_crank.pivot
    )


def _groups_of(step: object, ground: set[str]) -> list[_Group]:
    """The bodies (before merging) one step makes."""
    if isinstance(step, Crank | SphereCrank):
        name = step.length if isinstance(step.length, str) else None
        return [
            _Group(
                {step.pivot, step.name},
                name,
                (step.pivot, step.name),
                crank=(step.pivot, step.ratio),
            )
        ]
    if isinstance(step, DyadRRR | SphereDyad):
        return [
            _Group({step.p1, step.name}, _word(step.r1), (step.p1, step.name)),
            _Group({step.p2, step.name}, _word(step.r2), (step.p2, step.name)),
        ]
    if isinstance(step, DyadRRP):
        if step.line_point not in ground:
            raise UnsupportedPlan(
                f"the slider {step.name} runs on a guide that moves with {step.line_point}: "
                "forces need a guide fixed to the frame"
            )
        return [
            _Group({step.p1, step.name}, _word(step.r), (step.p1, step.name)),
            _Group({step.name}, guide=Guide(step.line_point, step.line_angle)),
        ]
    if isinstance(step, Rigid | SphereRigid):
        return [_Group({step.origin, step.toward, step.name})]
    if isinstance(step, Trammel):
        if step.guide1 not in ground or step.guide2 not in ground:
            raise UnsupportedPlan(f"the trammel {step.name} needs guides fixed to the frame")
        return [
            _Group({step.name}, guide=Guide(step.guide1, step.angle1)),
            # The arm: named and framed by the cranks that hang from the slider.
            _Group({step.name}, far_end=step),
        ]
    if isinstance(step, Fixed):
        return []
    if isinstance(step, Hinge | SphereHinge):
        h, x = step.hinge, step.far
        return [
            _Group({step.z, x}, _word(step.r), (step.z, x)),
            _Group({h, x}, _word(step.a), (h, x)),
            _Group({step.y, h}, _word(step.b), (step.y, h)),
        ]
    if isinstance(step, LegHingeTriad | SphereLegHingeTriad):
        j, k = step.joints, step.anchors
        return [
            _Group({k[0], j[0]}, _word(step.lengths[0]), (k[0], j[0])),
            _Group({k[1], j[1]}, _word(step.lengths[1]), (k[1], j[1])),
            _Group({k[2], j[3]}, _word(step.b), (k[2], j[3])),
            _Group({j[3], j[2]}, _word(step.a), (j[3], j[2])),
            _Group(set(j[:3]), _word(step.side), (j[0], j[1])),
        ]
    if isinstance(step, BodyHingeTriad | SphereBodyHingeTriad):
        j, k = step.joints, step.anchors
        return [
            *(_Group({k[n], j[n]}, _word(step.lengths[n]), (k[n], j[n])) for n in range(3)),
            _Group({j[3], j[2]}, _word(step.arm), (j[3], j[2])),
            _Group({j[0], j[1], j[3]}, _word(step.side), (j[0], j[1])),
        ]
    if hasattr(step, "joints") and hasattr(step, "anchors") and hasattr(step, "lengths"):
        # A triad, planar or spherical.
        joints, anchors, lengths = step.joints, step.anchors, step.lengths
        out = [
            _Group({a, j}, _word(r), (a, j))
            for a, j, r in zip(anchors, joints, lengths, strict=True)
        ]
        body = getattr(step, "body", ())
        named = next((p for p in body if isinstance(p, str)), None)
        out.append(_Group(set(joints), named, (joints[0], joints[1])))
        return out
    raise UnsupportedPlan(f"forces do not know the step kind {type(step).__name__}")


def _hinge_drive(step: object) -> tuple[str, tuple[str, str], tuple[str, str]] | None:
    """For a step driven at a moving hinge: the hinge, two joints of the link its motor turns,
    and two joints of the body the motor reacts on (the input is the angle between them)."""
    if isinstance(step, Hinge | SphereHinge):
        return step.hinge, (step.hinge, step.far), (step.hinge, step.y)
    if isinstance(step, LegHingeTriad | SphereLegHingeTriad):
        j = step.joints
        return j[3], (j[3], j[2]), (j[3], step.anchors[2])
    if isinstance(step, BodyHingeTriad | SphereBodyHingeTriad):
        j = step.joints
        return j[3], (j[3], j[2]), (j[0], j[1])
    return None


def _word(p: str | float) -> str | None:
    return p if isinstance(p, str) else None


def _merge(groups: list[_Group], ground: set[str]) -> list[_Group]:
    """Union of the groups that are one body (:func:`_same_body`), in the order of the first
    step that made each."""
    parent = list(range(len(groups)))

    def root(k: int) -> int:
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    changed = True
    while changed:  # a union can make two other groups share two points: repeat to a fixpoint
        changed = False
        joined = _joined(groups, parent, root)
        for a in joined:
            for b in joined:
                if a < b and root(a) != root(b) and _same_body(joined[a], joined[b]):
                    parent[root(b)] = root(a)
                    changed = True
    return list(_joined(groups, parent, root).values())


def _joined(
    groups: list[_Group], parent: list[int], root: Callable[[int], int]
) -> dict[int, _Group]:
    out: dict[int, _Group] = {}
    for k, g in enumerate(groups):
        r = root(k)
        if r not in out:
            out[r] = _Group(set(g.points), g.name, g.frame, g.crank, g.guide, g.far_end)
            continue
        h = out[r]
        h.points |= g.points
        h.name = h.name or g.name
        h.frame = h.frame or g.frame
        h.crank = h.crank or g.crank
        h.far_end = h.far_end or g.far_end
    return dict(sorted(out.items()))


def _same_body(a: _Group, b: _Group) -> bool:
    if a.guide is not None or b.guide is not None:
        return False  # a slider block shares one pin with its rod, never two points
    if len(a.points & b.points) >= 2:
        return True
    if a.crank is not None and a.crank == b.crank:
        return True
    for arm, other in ((a, b), (b, a)):
        if (
            arm.far_end is not None
            and other.crank is not None
            and other.crank[0] == arm.far_end.name
            and other.crank[1] == 1.0
        ):
            return True
    return False


def _name_all(groups: list[_Group]) -> None:
    """Names for the bodies no length field named, and distinct names throughout."""
    blocks = [g for g in groups if g.guide is not None]
    seen: set[str] = set()
    for g in groups:
        if g.guide is not None:
            pin = next(iter(g.points))
            g.name = "slider" if len(blocks) == 1 else f"slider_{pin}"
        elif g.name is None:
            g.name = "".join(sorted(g.points))
        if g.name in seen:
            g.name = f"{g.name}_{''.join(sorted(g.points))}"
        seen.add(g.name)

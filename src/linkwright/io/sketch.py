"""The drawing compiler: a linkage drawn joint by joint (a "sketch") → a linkage document.

The workbench's builder sends what the designer has drawn: joints (ground pivots, pins,
sliders on fixed guides), links (rigid bodies, each the joints it joins) and drivers (the input
crank and cranks geared to it); :mod:`.sketch_checks` describes the format. :func:`compile_sketch`
says what the drawing is, in one plain sentence, and compiles it once it can run:

1. it reads the drawing (status ``"invalid"``: a name that is not drawn, a link of one joint,
   a coordinate that is not a number, a slider on the sphere, ...; ``"empty"``: nothing drawn);
2. it counts the degrees of freedom (Grübler–Kutzbach,
   :func:`~.sketch_checks.degrees_of_freedom`): ``"under"`` above 1, ``"over"`` below,
   ``"no-driver"`` at 1 without a driver; each message names the joints or link involved;
3. it places the joints one at a time from the ground and the cranks, as the engine's
   construction plans do (:mod:`.sketch_place`), three at a time where a ternary link is held
   by three binary links from placed joints (a triad, a class III Assur group), and writes
   each as a joint of a ``linkage`` document (fixed, crank, rrr, rrp, rigid, triad; degrees,
   as every document speaks), the assembly signs read from the drawing and a triad's pose the
   one that puts its joints where they are drawn at θ = 0. A dyad drawn at a dead point, a
   triad drawn where two of its poses merge, or joints that only a larger Assur group places
   are ``"unplaceable"``;
4. it checks the document by building it through :func:`~linkwright.io.parse_document` and
   solving it: at θ = 0 every joint is where it was drawn (else a bug: :class:`SketchBug`), and
   at a few inputs around the turn every link keeps its joints' distances and every slider
   stays on its guide (a link that does not is one too many: ``"over"``).

:func:`sketch_of_document` (:mod:`.sketch_document`) is the way back: the drawing of a
document, for the builder to edit.

Examples
--------
A four-bar, drawn with its coupler point P:

>>> four_bar = {"joints": [
...     {"name": "A0", "at": [0, 0], "ground": True}, {"name": "A", "at": [1, 0]},
...     {"name": "B", "at": [3, 2]}, {"name": "B0", "at": [4, 0], "ground": True},
...     {"name": "P", "at": [2, 2]}],
...     "links": [["A0", "A"], ["A", "B", "P"], ["B", "B0"]],
...     "drivers": [{"pivot": "A0", "joint": "A"}]}
>>> report = compile_sketch(four_bar)
>>> report.status, report.dof, report.placement
('ok', 1, {'A0': 'ground', 'A': 'crank', 'B': 'dyad', 'B0': 'ground', 'P': 'rigid'})
>>> [j["type"] for j in report.document["mechanism"]["joints"]]
['fixed', 'fixed', 'crank', 'rrr', 'rigid']

Without the rocker it has two degrees of freedom, and says which joints are loose:

>>> loose = dict(four_bar, links=[["A0", "A"], ["A", "B", "P"]])
>>> print(compile_sketch(loose).message)
2 degrees of freedom: joints B and P are not held yet; join them to a ground pivot or another \
link, or gear a second driver to the first
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.sphere_triad import MAX_POSES as SPHERE_POSES
from linkwright.engine.triad import MAX_POSES as PLANE_POSES
from linkwright.geometry import sphere
from linkwright.io.document_kinds import tidy_number
from linkwright.io.document_schema import FORMAT, DocumentError
from linkwright.io.documents import document_to_dict, parse_document
from linkwright.io.sketch_checks import (
    MAX_DRIVERS,
    MAX_JOINTS,
    MAX_LINK_JOINTS,
    MAX_LINKS,
    MAX_NAME,
    Drawing,
    SketchInvalid,
    degrees_of_freedom,
    link_name,
    listed,
    read_sketch,
)
from linkwright.io.sketch_document import SketchError, sketch_of_document
from linkwright.io.sketch_place import Placement, Step, floating_links, place, trial_driver
from linkwright.mechanisms import Mechanism, solve
from linkwright.mechanisms.linkage import Linkage, SphereTriadJoint, TriadJoint

__all__ = [
    "CLOSURE",
    "MAX_DRIVERS",
    "MAX_JOINTS",
    "MAX_LINKS",
    "MAX_LINK_JOINTS",
    "MAX_NAME",
    "STATUSES",
    "SketchBug",
    "SketchError",
    "SketchReport",
    "compile_sketch",
    "sketch_of_document",
]

Array = NDArray[np.float64]

STATUSES = ("empty", "invalid", "under", "over", "no-driver", "unplaceable", "ok")
"""What a drawing can be, from nothing drawn to ready to run."""

CLOSURE = 1e-9
"""How closely (a share of the drawing's size; radians on the sphere) the compiled linkage must
put every joint where it was drawn, and keep every link's lengths as it moves."""

_CHECK_INPUTS = np.concatenate(
    ([0.0, 0.01, -0.01, 0.1, -0.1], np.linspace(0.0, 2.0 * np.pi, 25)[1:-1])
)
"""The inputs (radians) the compiled linkage is checked at: the drawn pose, either side of it
(a rocker drawn near a limit still moves a little), and every 15° around the turn."""


class SketchBug(RuntimeError):
    """The compiled linkage does not put a joint where it was drawn: a bug of the compiler."""


@dataclass(frozen=True)
class SketchReport:
    """What a drawing is, and its document once it can run.

    Attributes
    ----------
    status : one of :data:`STATUSES`.
    dof : the degrees of freedom counted (None for an empty or invalid drawing).
    message : one plain sentence: what the drawing is, or what it lacks.
    document : the ``linkage`` document (status ``"ok"`` only; every default filled in).
    placement : how each placed joint is placed ("ground", "crank", "dyad", "slider",
        "rigid", "triad"), in the drawing's joint order.
    joints : the joints the message is about (for the page to mark).
    links : the indices of the links the message is about.
    """

    status: str
    dof: int | None
    message: str
    document: dict[str, Any] | None = None
    placement: dict[str, str] = field(default_factory=dict)
    joints: tuple[str, ...] = ()
    links: tuple[int, ...] = ()

    def as_json(self) -> dict[str, Any]:
        """The report as the workbench answers it."""
        return {
            "status": self.status,
            "dof": self.dof,
            "message": self.message,
            "document": self.document,
            "placement": dict(self.placement),
            "joints": list(self.joints),
            "links": list(self.links),
        }


def _freedoms(n: int) -> str:
    return f"{n} degree of freedom" if n == 1 else f"{n} degrees of freedom"


def _placed(drawing: Drawing, placement: Placement | None) -> dict[str, str]:
    if placement is None:
        return {}
    return {n: placement.known[n].how for n in drawing.names if n in placement.known}


def _links_named(drawing: Drawing, indices: list[int]) -> str:
    return listed([link_name(drawing.links[k]) for k in indices])


# --------------------------------------------------------------------------------------------
# What is missing, or one too many
# --------------------------------------------------------------------------------------------


def _under(drawing: Drawing, dof: int) -> SketchReport:
    head = _freedoms(dof)
    if not drawing.ground:
        return SketchReport(
            "under", dof, f"{head}: no joint is a ground pivot; make a joint a ground pivot"
        )
    floating = floating_links(drawing)
    if floating:
        joints = tuple(dict.fromkeys(j for k in floating for j in drawing.links[k]))
        return SketchReport(
            "under",
            dof,
            f"{head}: {'link' if len(floating) == 1 else 'links'} "
            f"{_links_named(drawing, floating)} "
            f"{'is' if len(floating) == 1 else 'are'} not joined to the ground; pin "
            f"{'it' if len(floating) == 1 else 'them'} to a ground pivot or another link",
            joints=joints,
            links=tuple(floating),
        )
    trial = list(drawing.drivers) or [d for d in [trial_driver(drawing)] if d is not None]
    placement = place(drawing, trial)
    loose = placement.unplaced(drawing)
    if not loose:
        message = f"{head}: add a link or a ground pivot, or gear a second driver to the first"
        return SketchReport("under", dof, message, placement=_placed(drawing, placement))
    return SketchReport(
        "under",
        dof,
        f"{head}: {'joint' if len(loose) == 1 else 'joints'} {listed(loose)} "
        f"{'is' if len(loose) == 1 else 'are'} not held yet; join "
        f"{'it' if len(loose) == 1 else 'them'} to a ground pivot or another link, or gear a "
        "second driver to the first",
        placement=_placed(drawing, placement),
        joints=tuple(loose),
    )


def _over(drawing: Drawing, dof: int) -> SketchReport:
    if not drawing.links:  # a first pivot or two: nothing moves yet, and nothing is one too many
        return SketchReport(
            "over",
            dof,
            f"{_freedoms(dof)}: only the ground "
            f"{'pivot' if len(drawing.ground) == 1 else 'pivots'} {listed(drawing.ground)} "
            f"{'is' if len(drawing.ground) == 1 else 'are'} drawn, and the ground does not move; "
            "join a ground pivot to a new joint with a link",
            joints=drawing.ground,
        )
    head = f"over-constrained ({_freedoms(dof)})"
    drivers = drawing.drivers
    if len(drivers) > 1 and dof + len(drivers) - 1 >= 1:
        surplus = drivers[len(drivers) - (1 - dof) :]
        free = dof + len(drivers) - 1
        named = listed([f"{d.pivot}–{d.joint}" for d in surplus])
        return SketchReport(
            "over",
            dof,
            f"{head}: without its gear pairs the drawing has {_freedoms(free)}, so the "
            f"{'driver' if len(surplus) == 1 else 'drivers'} {named} "
            f"{'locks' if len(surplus) == 1 else 'lock'} it; remove "
            f"{'that driver' if len(surplus) == 1 else 'those drivers'}",
            joints=tuple(d.joint for d in surplus),
            links=tuple(d.link for d in surplus),
        )
    for k, link in enumerate(drawing.links):
        pivots = [j for j in link if j in drawing.ground]
        if len(pivots) >= 2:
            return SketchReport(
                "over",
                dof,
                f"{head}: link {link_name(link)} joins the ground pivots {listed(pivots)}, which "
                "the ground already holds; remove it (or make its other joints ground pivots)",
                joints=tuple(link),
                links=(k,),
            )
    trial = list(drivers) or [d for d in [trial_driver(drawing)] if d is not None]
    placement = place(drawing, trial)
    found = _one_too_many(drawing, dof, placement, "over", head)
    if found is not None:
        return found
    message = f"{head}: remove a link or a ground pivot"
    return SketchReport("over", dof, message, placement=_placed(drawing, placement))


def _one_too_many(
    drawing: Drawing, dof: int, placement: Placement, status: str, head: str
) -> SketchReport | None:
    """The report naming the first link (or slider guide) that holds more than the placement
    needs, or None where there is none."""
    redundant = placement.redundant_links(drawing)
    if redundant:
        k = redundant[0]
        link = drawing.links[k]
        return SketchReport(
            status,
            dof,
            f"{head}: link {link_name(link)} joins joints that other links already hold, so "
            "it locks the linkage; remove it, or free a joint it holds",
            placement=_placed(drawing, placement),
            joints=link,
            links=(k,),
        )
    guides = placement.redundant_guides(drawing)
    if guides:
        return SketchReport(
            status,
            dof,
            f"{head}: slider {guides[0]} is already held by its links, so its guide locks the "
            "linkage; make it a plain pin, or remove a link it is on",
            placement=_placed(drawing, placement),
            joints=(guides[0],),
        )
    return None


def _stuck(drawing: Drawing, dof: int, placement: Placement) -> SketchReport:
    """The report for a drawing of one degree of freedom whose joints cannot all be placed."""
    left = placement.unplaced(drawing)
    placed = _placed(drawing, placement)
    dead = [j for j in left if j in placement.dead]
    if dead:
        return SketchReport(
            "unplaceable", dof, placement.dead[dead[0]], placement=placed, joints=(dead[0],)
        )
    free = placement.free_left(drawing)
    if free > 0:
        head = (
            f"{'joint' if len(left) == 1 else 'joints'} {listed(left)} can still move with the "
            "input held"
        )
        found = _one_too_many(drawing, dof, placement, "under", head)
        if found is not None:
            joints = tuple(dict.fromkeys((*left, *found.joints)))
            return SketchReport(
                found.status, dof, found.message, placement=placed, joints=joints, links=found.links
            )
        return SketchReport(
            "under",
            dof,
            f"{head}; join {'it' if len(left) == 1 else 'them'} to a ground pivot or another link",
            placement=placed,
            joints=tuple(left),
        )
    near_ground = [
        k
        for k, link in enumerate(drawing.links)
        if any(j in drawing.ground for j in link) and any(j in left for j in link)
    ]
    hint = "; drive a link next to the ground instead"
    if near_ground:
        hint += f", such as {link_name(drawing.links[near_ground[0]])}"
    return SketchReport(
        "unplaceable",
        dof,
        f"joints {listed(left)} cannot be placed from the input one at a time nor as a triad "
        "(a ternary link held by three binary links): placing them needs a larger Assur group "
        f"(class IV or higher), which the drawing compiler does not place{hint}",
        placement=placed,
        joints=tuple(left),
        links=tuple(near_ground[:1]),
    )


# --------------------------------------------------------------------------------------------
# The document
# --------------------------------------------------------------------------------------------


def _num(x: float) -> float:
    return tidy_number(float(x))


def _deg(rad: float) -> float:
    return _num(math.degrees(rad))


def _guide_names(drawing: Drawing, placement: Placement) -> dict[str, str]:
    """A ground pivot's name for each guide that has none: ``<slider>_guide`` where that name
    is free (and short enough), else ``guide<n>``."""
    taken = set(drawing.names)
    out: dict[str, str] = {}
    for step in placement.steps:
        if step.how != "slider" or drawing.guide[step.joint] is not None:
            continue
        name = f"{step.joint}_guide"
        n = 1
        while name in taken or len(name) > MAX_NAME:
            name, n = f"guide{n}", n + 1
        taken.add(name)
        out[step.joint] = name
    return out


def _toward(drawing: Drawing, pivot: str) -> str | None:
    return next((g for g in drawing.ground if g != pivot), None)


def _joint_table(drawing: Drawing, step: Step, guides: dict[str, str]) -> dict[str, Any]:
    at = drawing.at
    name = step.joint
    table: dict[str, Any] = {"name": name}
    flat = drawing.space == "plane"
    if step.how == "ground":
        table.update(type="fixed", at=[_num(x) for x in drawing.given[name]])
    elif step.how == "crank":
        (pivot,) = step.parents
        arm = at[name] - at[pivot]
        assert step.driver is not None  # a crank step is a driver's
        ratio = _num(step.driver.ratio)
        if flat:
            phase = _deg(math.atan2(arm[1], arm[0]))
            table.update(type="crank", pivot=pivot, length=_num(np.hypot(*arm)), ratio=ratio)
            table["phase"] = phase
        else:
            toward = _toward(drawing, pivot)
            assert toward is not None  # compile_sketch reports a crank with none first
            arc = _deg(float(sphere.arc(at[pivot], at[name])))
            phase = _deg(float(sphere.angle_at(at[pivot], at[toward], at[name])))
            table.update(type="crank", pivot=pivot, arc=arc, ratio=ratio, phase=phase)
            table["toward"] = toward
    elif step.how == "dyad":
        p1, p2 = step.parents
        table.update(type="rrr", p1=p1, r1=_length(drawing, p1, name), p2=p2)
        table.update(r2=_length(drawing, p2, name), assembly=step.assembly)
    elif step.how == "triad":
        table.update(_triad_table(drawing, step))
    elif step.how == "slider":
        (p1,) = step.parents
        line_point = drawing.guide[name] or guides[name]
        table.update(type="rrp", p1=p1, r=_length(drawing, p1, name), line_point=line_point)
        table.update(line_angle=_num(drawing.slider[name]), assembly=step.assembly)
    else:
        origin, toward = step.parents
        table.update(type="rigid", origin=origin, toward=toward)
        table.update(_in_frame(at[origin], at[toward], at[name], flat))
    return table


def _in_frame(o: Array, t: Array, p: Array, flat: bool) -> dict[str, float]:
    """Where p sits on the link o→t, as documents write it: (u, v) in the frame with origin o
    and x towards t in the plane; arc from o and angle from the great circle o→t on the
    sphere (degrees)."""
    if flat:
        e = (t - o) / np.hypot(*(t - o))
        rel = p - o
        return {"u": _num(rel @ e), "v": _num(e[0] * rel[1] - e[1] * rel[0])}
    return {"arc": _deg(float(sphere.arc(o, p))), "angle": _deg(float(sphere.angle_at(o, t, p)))}


def _triad_table(drawing: Drawing, step: Step) -> dict[str, Any]:
    """A triad's fields: its joints, its three binary links, the ternary link's shape (the pose
    is chosen once the document is built: :func:`_choose_poses`)."""
    at = drawing.at
    j1, j2, j3 = step.group
    table: dict[str, Any] = {"type": "triad", "j2": j2, "j3": j3}
    for k, (joint, anchor) in enumerate(zip(step.group, step.parents, strict=True), start=1):
        table[f"p{k}"] = anchor
        table[f"r{k}"] = _length(drawing, anchor, joint)
    table["side"] = _length(drawing, j1, j2)
    table.update(_in_frame(at[j1], at[j2], at[j3], drawing.space == "plane"))
    table["pose"] = 0
    return table


def _length(drawing: Drawing, a: str, b: str) -> float:
    if drawing.space == "plane":
        return _num(np.hypot(*(drawing.at[a] - drawing.at[b])))
    return _deg(float(sphere.arc(drawing.at[a], drawing.at[b])))


def _traced(drawing: Drawing, placement: Placement) -> list[str]:
    if drawing.traced:
        return list(drawing.traced)
    driven = {d.joint for d in drawing.drivers}
    points = [
        n
        for n in drawing.names
        if n not in drawing.ground and n not in driven and len(drawing.links_at(n)) == 1
    ]
    return points or [placement.steps[-1].joint]


def _document(drawing: Drawing, placement: Placement) -> dict[str, Any]:
    guides = _guide_names(drawing, placement)
    joints = [_joint_table(drawing, s, guides) for s in placement.steps if s.how == "ground"]
    for slider, name in guides.items():
        at = [_num(x) for x in drawing.given[slider]]
        joints.append({"name": name, "type": "fixed", "at": at})
    # A triad is one joint of the document, written at its first joint's step.
    joints += [
        _joint_table(drawing, s, guides)
        for s in placement.steps
        if s.how != "ground" and (s.how != "triad" or s.joint == s.group[0])
    ]
    document: dict[str, Any] = {"format": FORMAT}
    if drawing.title is not None:
        document["title"] = drawing.title
    document["mechanism"] = {
        "family": "linkage",
        "space": drawing.space,
        "traced": _traced(drawing, placement),
        "joints": joints,
    }
    return document


def _choose_poses(drawing: Drawing, document: dict[str, Any]) -> tuple[str, ...]:
    """Set each triad's ``pose`` in ``document`` to the pose index that puts its joints where
    they are drawn, found by solving the document's own numbers at θ = 0 on every pose (so the
    index is the one the document means wherever it is evaluated at that input). Returns the
    joints of the first triad none of whose poses is where it is drawn (else nothing).

    A triad's poses at θ = 0 depend on the poses of the triads before it, so they are chosen in
    order: one solve of at most 8 poses at one input per triad.
    """
    tables = {t["name"]: t for t in document["mechanism"]["joints"] if t["type"] == "triad"}
    if not tables:
        return ()
    mech = parse_document(document).mechanism
    assert isinstance(mech, Linkage)  # the compiler writes linkage documents
    joints = list(mech.joints)
    for index, spec in enumerate(joints):
        if not isinstance(spec, TriadJoint | SphereTriadJoint):
            continue
        most = PLANE_POSES if isinstance(spec, TriadJoint) else SPHERE_POSES
        joints[index] = replace(spec, pose=np.arange(most, dtype=float))
        every = Linkage(joints=tuple(joints), traced=mech.traced, space=mech.space)
        pos = solve(every, [0.0], order=0).positions
        miss = np.max(
            [np.linalg.norm(pos[j][:, 0] - drawing.at[j], axis=-1) for j in spec.placed], 0
        )
        miss = np.where(np.isnan(miss), np.inf, miss)
        best = int(np.argmin(miss))
        if not miss[best] <= CLOSURE * drawing.size:
            return spec.placed
        joints[index] = replace(spec, pose=float(best))
        tables[spec.name]["pose"] = best
    return ()


# --------------------------------------------------------------------------------------------
# The check
# --------------------------------------------------------------------------------------------


def _check(
    drawing: Drawing, dof: int, placement: Placement, mech: Mechanism
) -> SketchReport | None:
    """Solve the compiled linkage and hold it to the drawing; a report where it falls short."""
    motion = solve(mech, _CHECK_INPUTS, order=0)
    pos = motion.positions
    placed = _placed(drawing, placement)
    if not motion.valid[0]:
        return SketchReport(
            "unplaceable",
            dof,
            "the drawn pose does not assemble as compiled; move a joint a little and try again",
            placement=placed,
        )
    tol = CLOSURE * drawing.size
    for name in drawing.names:
        error = float(np.linalg.norm(pos[name][0] - drawing.at[name]))
        if not error <= tol:
            raise SketchBug(
                f"joint {name} is compiled {error:.3g} from where it was drawn (size "
                f"{drawing.size:.6g})"
            )
    ok = motion.valid
    for k, link in enumerate(drawing.links):
        for i, a in enumerate(link):
            for b in link[i + 1 :]:
                drawn = np.linalg.norm(drawing.at[a] - drawing.at[b])
                moved = np.linalg.norm(pos[a][ok] - pos[b][ok], axis=-1)
                if not float(np.max(np.abs(moved - drawn))) <= tol:
                    return SketchReport(
                        "over",
                        dof,
                        f"link {link_name(link)} would have to change its length between {a} "
                        f"and {b} as the linkage moves, so it locks the linkage; remove it, or "
                        "free a joint it holds",
                        placement=placed,
                        joints=link,
                        links=(k,),
                    )
    for name, angle in drawing.slider.items():
        d = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
        off = pos[name][ok] - drawing.at[name]
        if not float(np.max(np.abs(d[0] * off[:, 1] - d[1] * off[:, 0]))) <= tol:
            return SketchReport(
                "over",
                dof,
                f"slider {name} would have to leave its guide as the linkage moves, so the guide "
                "locks the linkage; make it a plain pin, or remove a link it is on",
                placement=placed,
                joints=(name,),
            )
    return None


def compile_sketch(sketch: Mapping[str, Any] | Any) -> SketchReport:
    """What the drawing ``sketch`` is, and its ``linkage`` document when it can run.

    Never raises for a drawing, however incomplete or wrong (those are states of a drawing,
    reported with their status and message), except :class:`SketchBug` where the compiled
    linkage misplaces a drawn joint (a bug). See the module notes for the statuses.
    """
    try:
        drawing = read_sketch(sketch)
    except SketchInvalid as exc:
        return SketchReport("invalid", None, str(exc))
    if drawing is None:
        return SketchReport(
            "empty",
            None,
            "nothing is drawn yet: place two ground pivots, join them with links through "
            "moving joints, and pick a driver",
        )
    dof = degrees_of_freedom(drawing)
    if dof > 1:
        return _under(drawing, dof)
    if dof < 1:
        return _over(drawing, dof)
    if not drawing.drivers:
        candidate = trial_driver(drawing)
        example = (
            f" ({candidate.pivot}–{candidate.joint}, for one)" if candidate is not None else ""
        )
        return SketchReport(
            "no-driver",
            dof,
            f"1 degree of freedom: pick a driver, a link turning about a ground pivot{example}",
            joints=(candidate.pivot, candidate.joint) if candidate is not None else (),
            links=(candidate.link,) if candidate is not None else (),
        )
    if drawing.space == "sphere":
        for driver in drawing.drivers:
            if _toward(drawing, driver.pivot) is None:
                return SketchReport(
                    "unplaceable",
                    dof,
                    f"a spherical crank's angle is measured towards a second ground pivot, and "
                    f"{driver.pivot} is the only one; add another ground pivot",
                    joints=(driver.pivot,),
                )
    placement = place(drawing, drawing.drivers)
    if placement.unplaced(drawing):
        return _stuck(drawing, dof, placement)
    document = _document(drawing, placement)
    try:
        lost = _choose_poses(drawing, document)
        parsed = parse_document(document)
    except DocumentError as exc:
        # The drawing's checks keep its numbers in the working range, so this is a linkage the
        # Linkage class itself refuses (two joints built the same way, say): its words say why.
        return SketchReport("invalid", dof, exc.problem, placement=_placed(drawing, placement))
    if lost:
        # The triad solvers can miss a pose where the drawing is degenerate for them (on the
        # sphere, each of the ternary's joints drawn on another's anchor): a limit of theirs,
        # said in a line rather than raised as the compiler's bug.
        return SketchReport(
            "unplaceable",
            dof,
            f"the triad {link_name(lost)} is not found in its drawn pose, drawn where its "
            "solution degenerates (its joints on one another's anchors, say); move one of its "
            "joints a little and try again",
            placement=_placed(drawing, placement),
            joints=lost,
        )
    refused = _check(drawing, dof, placement, parsed.mechanism)
    if refused is not None:
        return refused
    first = drawing.drivers[0]
    gears = len(drawing.drivers) - 1
    geared = f" and {gears} gear pair{'s' if gears > 1 else ''}" if gears else ""
    return SketchReport(
        "ok",
        dof,
        f"1 degree of freedom, driven by link {first.pivot}–{first.joint}{geared}: ready to run",
        document=document_to_dict(parsed),
        placement=_placed(drawing, placement),
    )

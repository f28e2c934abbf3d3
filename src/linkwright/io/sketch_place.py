"""Placing a drawing's joints one at a time, as the engine's construction plans do.

:func:`place` starts from the ground pivots and the drivers' cranks and repeats, until nothing
more can be placed: a link with two placed joints carries its other joints rigidly; a slider pin
hangs from a placed joint on one of its links (an RRP dyad); any other pin hangs from placed
joints on two of its links (an RRR dyad). Where none of these is left, a link with no joint
placed whose three joints each hang by a binary link from a placed joint is a triad (an Assur
group of class III, :func:`place_triad`): its three joints are placed at once, and the
dyads go on from there. A dyad drawn at a dead point (its two links in line, or a slider's rod
square to its guide) is not placed: the drawing does not say which way it assembles; nor is a
triad drawn where two of its poses merge. What is left unplaced, which links hold more than the
placement needs, and how many freedoms the unplaced part has are what :mod:`.sketch` explains
to the designer.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from linkwright.engine.triad_steps import triad_closure
from linkwright.geometry import sphere
from linkwright.io.sketch_checks import Drawing, Driver, link_name

__all__ = [
    "PRECISION",
    "TRIAD_ROUNDING",
    "Placement",
    "Step",
    "floating_links",
    "place",
    "place_triad",
    "trial_driver",
]

Array = NDArray[np.float64]

PRECISION = 4e-10
"""How far (a share of the drawing's size) the engine may place a joint from where it is drawn,
as foreseen from the drawing: under half the 1e-9 the compiled linkage is checked to. A dyad (or
slider) whose links meet so nearly in line that rounding could move it further is drawn at a
dead point: the drawing does not say which way it assembles to that precision."""

ROUNDING = 40.0
"""How far rounding moves a dyad's joint, in units in the last place of the drawing's size, at
a unit sine of the angle its links meet at (a slider: cosine of its rod to its guide); it moves
as 1/sine. Measured over 2,000 random dyads drawn near their dead points: at most 8.5 in the
plane, 18 on the sphere, 9 for sliders. So a dyad is placed where that sine is over 2.2e-5."""

TRIAD_ROUNDING = 180.0
"""How far rounding may move a triad's joints, in units in the last place of the drawing's size,
at a unit closure (:func:`~linkwright.engine.triad_steps.triad_closure`, the relative
determinant of its constraints, which vanishes where two poses merge); they move as 1/closure.
Measured over 8,000 random triads drawn near a merge (their three links' lines nearly
concurrent; on the sphere their great circles nearly through one point): at most 7.4 in the
plane, 69 on the sphere. The engine's solvers also lose a pose whose closure is below about
1e-5 in the plane (1e-6 on the sphere), where the two merging poses' roots are not told apart;
180 puts the least closure placed at 1e-4, ten times above that."""


@dataclass(frozen=True)
class Step:
    """How one joint is placed.

    ``how`` is "ground", "crank", "dyad", "slider", "rigid" or "triad"; ``parents`` the joints
    it is placed from (a crank's pivot; a dyad's two; a slider's rod end; a rigid point's origin
    and toward; a triad's three anchors, p1 p2 p3); ``links`` the indices of the drawing's links
    that the step uses; ``assembly`` a dyad's or slider's sign (the engine's conventions,
    :mod:`linkwright.mechanisms.joints`); ``group`` a triad's three joints J1 J2 J3 (each of
    the three has a step, J1's first); ``error`` how far the engine may place the joint from
    where it is drawn, as a share of the drawing's size (rounding, and its parents' errors as
    the step passes them on).
    """

    joint: str
    how: str
    parents: tuple[str, ...] = ()
    links: tuple[int, ...] = ()
    driver: Driver | None = None
    assembly: int = 0
    error: float = 0.0
    group: tuple[str, ...] = ()


@dataclass
class Placement:
    """The steps in order, and each dead point met: joint → the sentence that says so."""

    steps: list[Step] = field(default_factory=list)
    known: dict[str, Step] = field(default_factory=dict)
    dead: dict[str, str] = field(default_factory=dict)

    def add(self, step: Step) -> None:
        self.steps.append(step)
        self.known[step.joint] = step

    def unplaced(self, drawing: Drawing) -> list[str]:
        return [name for name in drawing.names if name not in self.known]

    def redundant_links(self, drawing: Drawing) -> list[int]:
        """Links holding two joints or more that other steps placed: a constraint the placement
        did not need (the ground counts as another step, so a link on two ground pivots is
        one)."""
        out = []
        for k, link in enumerate(drawing.links):
            outside = [j for j in link if j in self.known and k not in self.known[j].links]
            if len(outside) >= 2:
                out.append(k)
        return out

    def redundant_guides(self, drawing: Drawing) -> list[str]:
        """Slider pins placed by their links alone: their guides are constraints too many."""
        return [
            name
            for name in drawing.slider
            if name in self.known and self.known[name].how != "slider"
        ]

    def free_left(self, drawing: Drawing) -> int:
        """The Grübler count of what is not placed, with every placed joint held fixed: 0 for a
        rigid group (a triad, say), more where joints are still free to move."""
        undetermined = [
            k for k, link in enumerate(drawing.links) if not all(j in self.known for j in link)
        ]
        count = 3 * len(undetermined)
        for name in drawing.names:
            bodies = sum(name in drawing.links[k] for k in undetermined)
            if name in self.known:
                count -= 2 * bodies
            elif bodies:
                count -= 2 * (bodies - 1) + (name in drawing.slider)
        return count


def _known_on(placement: Placement, link: Sequence[str]) -> list[str]:
    """The placed joints of a link, in the order they were placed."""
    order = {step.joint: i for i, step in enumerate(placement.steps)}
    return sorted((j for j in link if j in placement.known), key=order.__getitem__)


_EPS = float(np.finfo(float).eps)


def _rounding(own: float) -> float:
    """``own``, plus a step's own rounding: a few units in the last place of the drawing's
    size (its numbers are written to the shortest decimal within 4 of them)."""
    return own + 8.0 * _EPS


def _dyad(
    drawing: Drawing, placement: Placement, p1: str, p2: str, joint: str
) -> tuple[int, float]:
    """The dyad's assembly sign, and how far (a share of the drawing's size) the engine may
    place the joint from where it is drawn: :data:`ROUNDING` over the sine of the angle its
    links meet at, and its parents' errors passed on through the same sine (the inverse of the
    2×2 of the two links' directions)."""
    a, b, j = drawing.at[p1], drawing.at[p2], drawing.at[joint]
    if drawing.space == "plane":
        side = float((b - a)[0] * (j - a)[1] - (b - a)[1] * (j - a)[0])
        u, v = a - j, b - j
        sine = abs(float(u[0] * v[1] - u[1] * v[0])) / float(np.hypot(*u) * np.hypot(*v))
    else:
        side = float(np.dot(np.cross(a, b), j))
        sine = abs(side) / float(np.linalg.norm(np.cross(j, a)) * np.linalg.norm(np.cross(j, b)))
    if sine == 0:
        return 1, math.inf
    inherited = math.sqrt(2.0) * (placement.known[p1].error + placement.known[p2].error)
    return (1 if side > 0 else -1), (ROUNDING * _EPS + inherited) / sine


def _slider(drawing: Drawing, placement: Placement, p1: str, joint: str) -> tuple[int, float]:
    """A slider's assembly sign, sign((B − H)·d) with H the foot of p1 on the guide (the same
    as sign((B − p1)·d)), and how far the engine may place it from where it is drawn: rounding,
    and its rod end's error, over the cosine of the rod's angle to the guide."""
    angle = math.radians(drawing.slider[joint])
    d = np.array([math.cos(angle), math.sin(angle)])
    rod = drawing.at[joint] - drawing.at[p1]
    along = float(rod @ d)
    cosine = abs(along) / float(np.hypot(*rod))
    if cosine == 0:
        return 1, math.inf
    error = (ROUNDING * _EPS + placement.known[p1].error) / cosine
    return (1 if along > 0 else -1), error


def _rigid_error(
    drawing: Drawing, placement: Placement, origin: str, toward: str, joint: str
) -> float:
    """How far a rigid point may be placed from where it is drawn: its origin's error, and the
    link's direction error (its two joints' errors over their distance) times its reach."""
    o, t, p = drawing.at[origin], drawing.at[toward], drawing.at[joint]
    if drawing.space == "plane":
        reach = float(np.hypot(*(p - o))) / float(np.hypot(*(t - o)))
    else:
        reach = float(np.linalg.norm(np.cross(o, p))) / float(np.linalg.norm(np.cross(o, t)))
    turn = placement.known[origin].error + placement.known[toward].error
    return _rounding(placement.known[origin].error + reach * turn)


def _slider_step(drawing: Drawing, placement: Placement, joint: str) -> Step | None:
    for k in drawing.links_at(joint):
        have = _known_on(placement, drawing.links[k])
        if len(have) != 1:
            continue
        sign, error = _slider(drawing, placement, have[0], joint)
        if not error <= PRECISION:
            placement.dead.setdefault(
                joint,
                f"slider {joint} is drawn at a dead point, its rod {have[0]}–{joint} square to "
                "its guide; slide it a little along the guide so the drawing says which way it "
                "assembles",
            )
            continue
        return Step(joint, "slider", (have[0],), (k,), assembly=sign, error=error)
    return None


def _dyad_step(drawing: Drawing, placement: Placement, joint: str) -> Step | None:
    holders: list[tuple[int, str]] = []
    for k in drawing.links_at(joint):
        have = _known_on(placement, drawing.links[k])
        if len(have) == 1:
            holders.append((k, have[0]))
    for i, (k1, p1) in enumerate(holders):
        for k2, p2 in holders[i + 1 :]:
            if p1 == p2:
                continue
            sign, error = _dyad(drawing, placement, p1, p2, joint)
            if not error <= PRECISION:
                placement.dead.setdefault(
                    joint,
                    f"joint {joint} is drawn at a dead point, its links "
                    f"{link_name(drawing.links[k1])} and {link_name(drawing.links[k2])} in "
                    f"line; move {joint} off that line so the drawing says which way it "
                    "assembles",
                )
                continue
            return Step(joint, "dyad", (p1, p2), (k1, k2), assembly=sign, error=error)
    return None


def _rigid_steps(drawing: Drawing, placement: Placement) -> bool:
    """Place every joint a link with two placed joints carries; whether any was placed."""
    progress = False
    for k, link in enumerate(drawing.links):
        have = _known_on(placement, link)
        if len(have) < 2:
            continue
        origin = have[0]
        # The placed joint farthest from the origin sets the link's direction best.
        toward = max(have[1:], key=lambda j: _spread(drawing, origin, j))
        for name in link:
            if name in placement.known:
                continue
            error = _rigid_error(drawing, placement, origin, toward, name)
            if not error <= PRECISION:
                placement.dead.setdefault(
                    name,
                    f"joint {name} is drawn far out on link {link_name(link)}, whose joints "
                    f"{origin} and {toward} are too close together to carry it precisely; draw "
                    "them further apart",
                )
                continue
            placement.add(Step(name, "rigid", (origin, toward), (k,), error=error))
            progress = True
    return progress


def _spread(drawing: Drawing, a: str, b: str) -> float:
    if drawing.space == "plane":
        return float(np.hypot(*(drawing.at[a] - drawing.at[b])))
    return float(np.linalg.norm(np.cross(drawing.at[a], drawing.at[b])))


# --------------------------------------------------------------------------------------------
# Triads
# --------------------------------------------------------------------------------------------


def _triad_holders(
    drawing: Drawing, placement: Placement, k: int
) -> list[tuple[str, int, str]] | None:
    """The link ``k`` as a triad's ternary: its three held joints, each as (joint, the link
    holding it, that link's placed joint); None where it is not one.

    A ternary has no joint placed; each held joint is on one other link besides it, which has
    exactly one placed joint (the anchor) and no other joint that a third link holds; its
    other joints are on it alone (points it carries, placed rigidly afterwards). Slider pins
    make another group, not placed here.
    """
    held: list[tuple[str, int, str]] = []
    for name in drawing.links[k]:
        if name in placement.known or name in drawing.slider:
            return None
        others = [h for h in drawing.links_at(name) if h != k]
        if not others:
            continue
        if len(others) != 1:
            return None
        h = others[0]
        have = _known_on(placement, drawing.links[h])
        loose = [j for j in drawing.links[h] if j != name and j not in placement.known]
        if len(have) != 1 or any(len(drawing.links_at(j)) > 1 for j in loose):
            return None
        held.append((name, h, have[0]))
    return held if len(held) == 3 else None


CLEAR = 1e-3
"""How far apart (a share of the drawing's size; chords on the sphere) a triad's J2 and J1's
anchor, and J1 and J2's anchor, are drawn for the order J1 J2 to be clear. The spherical
solver finds J1 on two circles, about its anchor and about J2; with J2 on that anchor the two
circles are one and the drawn pose can be lost (met on random drawings, where a joint is drawn
on another's anchor), so an order that keeps them apart is taken where there is one."""


def _clearance(drawing: Drawing, order: Sequence[tuple[str, int, str]]) -> float:
    """The lesser distance of J2 from J1's anchor and of J1 from J2's, a share of the size."""
    (j1, _, k1), (j2, _, k2) = order[0], order[1]
    at = drawing.at
    gaps = (np.linalg.norm(at[j2] - at[k1]), np.linalg.norm(at[j1] - at[k2]))
    return float(min(gaps)) / drawing.size


def _wrap_margin(drawing: Drawing, order: Sequence[tuple[str, int, str]]) -> float:
    """How far from where the engine's pose order wraps round the drawn pose's key lies, as a
    cosine (1 farthest): the direction of J1→J2 in the plane (poses sorted by it in
    (−π, π]); on the sphere J2's angle about its anchor K2 from the great circle K2→K1. A pose
    keyed near the wrap could change its index with the last bit of its anchors."""
    (j1, _, k1), (j2, _, k2) = order[0], order[1]
    at = drawing.at
    if drawing.space == "plane":
        d = at[j2] - at[j1]
        return float(d[0] / np.hypot(*d))
    if float(np.linalg.norm(np.cross(at[k1], at[k2]))) < 1e-6:
        return 0.0  # one anchor for both: the engine measures from a coordinate axis
    return float(np.cos(sphere.angle_at(at[k2], at[k1], at[j2])))


def _triad_error(
    drawing: Drawing, placement: Placement, order: Sequence[tuple[str, int, str]]
) -> float:
    """How far (a share of the drawing's size) the engine may place the triad's joints from
    where they are drawn: :data:`TRIAD_ROUNDING` over its closure (the relative determinant of
    its constraints, zero where two poses merge), its anchors' errors passed on the same way."""
    names = [j for j, _, _ in order]
    anchors = [k for _, _, k in order]
    joints = np.stack([drawing.at[j] for j in names])
    held = np.stack([drawing.at[k] for k in anchors])
    flat = drawing.space == "plane"
    lengths = np.hypot(*(joints - held).T) if flat else sphere.arc(joints, held)
    closure = abs(float(triad_closure(joints, held, lengths, drawing.space)))
    if not closure > 0:
        return math.inf
    inherited = math.sqrt(3.0) * sum(placement.known[k].error for k in anchors)
    return (TRIAD_ROUNDING * _EPS + inherited) / closure


def place_triad(drawing: Drawing, placement: Placement) -> bool:
    """Place the first triad that the placed joints hold (its three joints at once); whether
    one was placed. A triad drawn where two of its poses merge is a dead point, as a dyad's."""
    for k, link in enumerate(drawing.links):
        held = _triad_holders(drawing, placement, k)
        if held is None:
            continue
        # J1 and J2 chosen clear of each other's anchors where they can be, and then so that
        # the drawn pose is keyed far from the wrap of the pose order.
        order = max(
            itertools.permutations(held),
            key=lambda o: (min(_clearance(drawing, o), CLEAR), _wrap_margin(drawing, o)),
        )
        error = _triad_error(drawing, placement, order)
        group = tuple(j for j, _, _ in order)
        if not error <= PRECISION:
            sentence = (
                f"the link {link_name(link)} is drawn where two of its poses merge, held by "
                f"{', '.join(f'{a}–{j}' for j, _, a in order)} at a dead point; move one of "
                "its joints a little so the drawing says which pose it is in"
            )
            for name in group:
                placement.dead.setdefault(name, sentence)
            continue
        anchors = tuple(a for _, _, a in order)
        links = (k, *(h for _, h, _ in order))
        for name in group:
            placement.dead.pop(name, None)
            placement.add(Step(name, "triad", anchors, links, error=error, group=group))
        return True
    return False


def place(drawing: Drawing, drivers: Sequence[Driver]) -> Placement:
    """Place the drawing's joints from its ground pivots and ``drivers``, as far as dyads,
    rigid links and triads reach (the drawing's own drivers, or a trial one to see what is left
    free)."""
    placement = Placement()
    for name in drawing.ground:
        placement.add(Step(name, "ground"))
    for driver in drivers:
        if driver.joint not in placement.known:
            error = _rounding(placement.known[driver.pivot].error)
            crank = Step(driver.joint, "crank", (driver.pivot,), (driver.link,), driver, 0, error)
            placement.add(crank)
    # Each round places every joint that a link carries rigidly, then one dyad: the cost is
    # bounded by joints × links × joints per link, a few thousand checks at the limits.
    while True:
        if _rigid_steps(drawing, placement):
            continue
        progress = False
        for name in placement.unplaced(drawing):
            if name in drawing.slider:
                step = _slider_step(drawing, placement, name)
            else:
                step = _dyad_step(drawing, placement, name)
            if step is not None:
                placement.dead.pop(name, None)
                placement.add(step)
                progress = True
                break
        # Only where no dyad is left: a triad's closure is costlier than a dyad's.
        if not progress and not place_triad(drawing, placement):
            return placement


def trial_driver(drawing: Drawing) -> Driver | None:
    """A driver to try where the drawing has none: the first link turning about a ground pivot
    (to say which joints are left free, or which link is one too many)."""
    for k, link in enumerate(drawing.links):
        pivots = [j for j in link if j in drawing.ground]
        moving = [j for j in link if j not in drawing.ground]
        if pivots and moving:
            return Driver(pivots[0], moving[0], 1.0, k)
    return None


def floating_links(drawing: Drawing) -> list[int]:
    """The links that no chain of links joins to a ground pivot."""
    parent = {name: name for name in drawing.names}

    def root(name: str) -> str:
        while parent[name] != name:
            parent[name] = parent[parent[name]]
            name = parent[name]
        return name

    for link in drawing.links:
        for name in link[1:]:
            parent[root(name)] = root(link[0])
    grounded = {root(g) for g in drawing.ground}
    return [k for k, link in enumerate(drawing.links) if root(link[0]) not in grounded]

"""Reading a drawing of a linkage (a "sketch", as the workbench's builder sends it) and counting
its degrees of freedom.

A sketch is JSON: ``space`` ("plane" or "sphere"), an optional ``title``, ``joints`` (each a
``name``, its place ``at`` — [x, y] in the plane, any non-zero [x, y, z] along the joint's axis
on the sphere —, ``ground`` for a ground pivot and, in the plane, ``slider``: the angle in
degrees of a fixed guide line through its drawn place), ``links`` (each the names of the joints
one rigid body joins; the ground is every ground joint and is not listed), ``drivers`` (each a
``pivot``, a ``joint`` and a ``ratio``: the first is the input crank, each further one a crank
geared to it) and optional ``traced`` names. The drawn places are the pose at input θ = 0.

:func:`read_sketch` checks every part of it and gives a :class:`Drawing`, or raises
:class:`SketchInvalid` with one plain sentence naming what is wrong; :func:`degrees_of_freedom`
counts the drawing's mobility (Grübler–Kutzbach). :mod:`.sketch` compiles a drawing to a
linkage document.

Joint names are what a linkage document accepts (a non-empty string; up to 64 characters, the
workbench's bound on a document's names), printable, so that every message stays one line.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.io.document_schema import WORKING_RANGE

__all__ = [
    "MAX_DRIVERS",
    "MAX_JOINTS",
    "MAX_LINKS",
    "MAX_LINK_JOINTS",
    "MAX_NAME",
    "Drawing",
    "Driver",
    "SketchInvalid",
    "degrees_of_freedom",
    "drawing_size",
    "link_name",
    "listed",
    "read_sketch",
    "too_close",
]

Array = NDArray[np.float64]

MAX_JOINTS = 32
"""Most joints a drawing may have, counting the ground pivot each slider's guide may add: the
linkage document it compiles to must fit the workbench's 32 joints (``document_list``)."""
MAX_LINKS = 64
"""Most links: twice the joints, more than any linkage of one degree of freedom needs (a
four-bar has 3 links on 4 joints, Jansen's leg 7 on 8)."""
MAX_LINK_JOINTS = 16
"""Most joints on one link (a ternary link has 3; a plate carrying a row of points a few more)."""
MAX_DRIVERS = 8
"""Most drivers: the input crank and seven cranks geared to it."""
MAX_NAME = 64
"""Longest joint name: the workbench's bound on a document's strings (``text``)."""

_KEYS = ("space", "title", "joints", "links", "drivers", "traced")
_JOINT_KEYS = ("name", "at", "ground", "slider")
_DRIVER_KEYS = ("pivot", "joint", "ratio")
_GUIDE_TOL = 1e-10
"""A ground joint this close to a slider's guide line (a share of the drawing's size) is on it:
the guide runs through it, and no guide pivot is added."""


class SketchInvalid(ValueError):
    """A drawing that cannot be read as one: the message is one plain sentence."""


@dataclass(frozen=True)
class Driver:
    """A crank: ``joint`` turned about the ground pivot ``pivot`` at ``ratio`` times the input,
    on ``link`` (the index of the first link holding both)."""

    pivot: str
    joint: str
    ratio: float
    link: int


@dataclass(frozen=True)
class Drawing:
    """A checked sketch.

    Attributes
    ----------
    space : "plane" or "sphere".
    title : the title, or None.
    names : every joint's name, in the order drawn.
    at : each joint's place: a point in the plane, a unit vector on the sphere.
    given : each joint's place as drawn (on the sphere the vector as given, not yet unit).
    ground : the ground pivots, in the order drawn.
    slider : each slider pin's guide angle (degrees from +x).
    guide : each slider pin's guide pivot: a ground joint on its guide line, or None where a
        guide pivot must be added.
    links : each link's joints (repeats dropped, order kept).
    drivers : the drivers; the first is the input.
    traced : the traced joints asked for (empty: none asked for).
    size : the drawing's size (its largest coordinate or link length; 1 on the sphere).
    """

    space: str
    title: str | None
    names: tuple[str, ...]
    at: dict[str, Array]
    given: dict[str, list[float]]
    ground: tuple[str, ...]
    slider: dict[str, float]
    guide: dict[str, str | None]
    links: tuple[tuple[str, ...], ...]
    drivers: tuple[Driver, ...]
    traced: tuple[str, ...]
    size: float

    def links_at(self, joint: str) -> list[int]:
        """The indices of the links that hold ``joint``."""
        return [i for i, link in enumerate(self.links) if joint in link]


def link_name(link: Sequence[str]) -> str:
    """A link as a designer names it: its joints joined by dashes (``A–B–P``)."""
    return "–".join(link)


def listed(names: Sequence[str], limit: int = 6) -> str:
    """Names as a phrase: ``A``, ``A and B``, ``A, B and C`` (the first ``limit``, then "…")."""
    names = list(names)
    if len(names) > limit:
        names = names[:limit] + [f"{len(names) - limit} more"]
    if len(names) <= 1:
        return "".join(names)
    return f"{', '.join(names[:-1])} and {names[-1]}"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise SketchInvalid(f"{what} must be a number, got {_shown(value)}")
    x = float(value)
    if not math.isfinite(x):
        raise SketchInvalid(f"{what} must be a finite number, got {_shown(value)}")
    return x


def _list(value: Any, what: str, most: int, unit: str) -> list[Any]:
    if not isinstance(value, list | tuple):
        raise SketchInvalid(f"{what} must be a list, got {_shown(value)}")
    if len(value) > most:
        raise SketchInvalid(
            f"the drawing has {len(value):,} {unit}; at most {most} are allowed ({what})"
        )
    return list(value)


def _table(value: Any, what: str, keys: tuple[str, ...]) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise SketchInvalid(f"{what} must be a table, got {_shown(value)}")
    for key in value:
        if key not in keys:
            raise SketchInvalid(
                f"{what} has an unknown part {_shown(key)} (it may have {', '.join(keys)})"
            )
    return value


def _name(value: Any, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise SketchInvalid(f"{what} must be a joint name (a non-empty text), got {_shown(value)}")
    if len(value) > MAX_NAME:
        raise SketchInvalid(
            f"{what} is {len(value):,} characters long; a joint name has at most {MAX_NAME}"
        )
    if not value.isprintable():
        raise SketchInvalid(f"{what} {_shown(value)} has a control character or line break")
    return value


def _known(value: Any, what: str, names: Mapping[str, Any]) -> str:
    name = _name(value, what)
    if name not in names:
        raise SketchInvalid(f"{what} names joint {name}, which is not drawn")
    return name


def _place(value: Any, name: str, space: str) -> tuple[Array, list[float]]:
    size = 2 if space == "plane" else 3
    shape = "[x, y]" if space == "plane" else "[x, y, z] (its axis)"
    if not isinstance(value, list | tuple) or len(value) != size:
        got = f"{len(value)} numbers" if isinstance(value, list | tuple) else _shown(value)
        raise SketchInvalid(f"joint {name}: its place must be {shape}, got {got}")
    given = [_number(x, f"joint {name}: a coordinate") for x in value]
    largest = max(abs(x) for x in given)
    if problem := WORKING_RANGE.size_problem(largest):
        raise SketchInvalid(f"joint {name}: a coordinate {problem}")
    at = np.asarray(given, dtype=float)
    if space == "sphere":
        if largest == 0:
            raise SketchInvalid(
                f"joint {name} is drawn at the sphere's centre; a joint on the sphere is a "
                "direction from it, so its place must not be [0, 0, 0]"
            )
        at = at / largest
        at = at / float(np.linalg.norm(at))
    return at, given


def _read_joints(raw: list[Any], space: str) -> dict[str, dict[str, Any]]:
    joints: dict[str, dict[str, Any]] = {}
    for i, entry in enumerate(raw):
        table = _table(entry, f"joint {i + 1}", _JOINT_KEYS)
        if "name" not in table:
            raise SketchInvalid(f"joint {i + 1} has no name")
        name = _name(table["name"], f"joint {i + 1}'s name")
        if name in joints:
            raise SketchInvalid(f"two joints are named {name}; each joint needs its own name")
        if "at" not in table:
            raise SketchInvalid(f"joint {name} has no place (at)")
        at, given = _place(table["at"], name, space)
        ground = table.get("ground", False)
        if not isinstance(ground, bool):
            raise SketchInvalid(f"joint {name}: ground must be true or false, got {_shown(ground)}")
        slider = table.get("slider")
        if slider is not None:
            if space == "sphere":
                raise SketchInvalid(
                    f"joint {name}: a slider has no spherical counterpart; on the sphere a pin on "
                    "a great-circle guide is a link 90 degrees long turning about the guide's pole"
                )
            if ground:
                raise SketchInvalid(
                    f"joint {name} is a ground pivot and a slider; a ground pivot does not move, "
                    "so it cannot slide"
                )
            slider = _number(slider, f"joint {name}: the slider's angle")
            if problem := WORKING_RANGE.angle_problem(slider):
                raise SketchInvalid(f"joint {name}: the slider's angle {problem}")
        joints[name] = {"at": at, "given": given, "ground": ground, "slider": slider}
    return joints


def _read_links(raw: list[Any], joints: Mapping[str, Any]) -> tuple[tuple[str, ...], ...]:
    links = []
    for i, entry in enumerate(raw):
        members = _list(entry, f"link {i + 1}", MAX_LINK_JOINTS, "joints on one link")
        names = [_known(m, f"link {i + 1}", joints) for m in members]
        link = tuple(dict.fromkeys(names))
        if len(link) < 2:
            raise SketchInvalid(
                f"link {i + 1} ({link_name(link) or 'empty'}) joins fewer than two joints; a "
                "link joins two joints or more"
            )
        links.append(link)
    return tuple(links)


def _read_drivers(
    raw: list[Any], joints: Mapping[str, Any], links: tuple[tuple[str, ...], ...]
) -> tuple[Driver, ...]:
    drivers: list[Driver] = []
    for i, entry in enumerate(raw):
        what = "the input driver" if i == 0 else f"driver {i + 1}"
        table = _table(entry, what, _DRIVER_KEYS)
        for key in ("pivot", "joint"):
            if key not in table:
                raise SketchInvalid(f"{what} has no {key}")
        pivot = _known(table["pivot"], f"{what}'s pivot", joints)
        joint = _known(table["joint"], f"{what}'s joint", joints)
        if not joints[pivot]["ground"]:
            raise SketchInvalid(
                f"{what} turns about {pivot}, which is not a ground pivot; a driver is a link "
                "turning about a ground pivot"
            )
        if joints[joint]["ground"]:
            raise SketchInvalid(f"{what} turns {joint}, a ground pivot, which cannot move")
        shared = [k for k, link in enumerate(links) if pivot in link and joint in link]
        if not shared:
            raise SketchInvalid(
                f"{what} turns {joint} about {pivot}, but no link joins them; draw the link "
                f"{pivot}–{joint} first"
            )
        ratio = _number(table.get("ratio", 1.0), f"{what}'s ratio")
        if ratio == 0:
            raise SketchInvalid(f"{what}'s ratio is 0, so it would not turn; give it a gear ratio")
        if problem := WORKING_RANGE.ratio_problem(ratio):
            raise SketchInvalid(f"{what}'s ratio {problem}")
        if any(d.joint == joint for d in drivers):
            raise SketchInvalid(f"joint {joint} is driven twice; drive it once")
        drivers.append(Driver(pivot, joint, ratio, shared[0]))
    return tuple(drivers)


def drawing_size(space: str, at: Mapping[str, Array], links: Sequence[Sequence[str]]) -> float:
    """A drawing's size: its largest coordinate or distance between joints of one link (1 on
    the sphere, whose radius it is)."""
    if space == "sphere":
        return 1.0
    sizes = [float(np.max(np.abs(p))) for p in at.values()]
    for link in links:
        sizes += [_distance(at[a], at[b]) for i, a in enumerate(link) for b in link[i + 1 :]]
    return max(sizes, default=0.0) or 1.0


def _distance(a: Array, b: Array) -> float:
    return float(np.hypot(*(a - b)))


def _arc_deg(a: Array, b: Array) -> float:
    """The arc between two unit vectors, in degrees (accurate near 0 and 180 alike)."""
    return math.degrees(2.0 * math.atan2(np.linalg.norm(a - b), np.linalg.norm(a + b)))


def too_close(space: str, a: Array, b: Array, size: float) -> str | None:
    """Why two joints' places ``a`` and ``b`` cannot be told apart (or, on the sphere, are
    the two ends of one axis), or None."""
    if space == "plane":
        if _distance(a, b) <= WORKING_RANGE.min_share * size:
            return "drawn at the same place"
        return None
    arc = _arc_deg(a, b)
    least = WORKING_RANGE.min_arc
    if arc < least:
        return "drawn on the same axis"
    if arc > 180.0 - least:
        return "drawn on opposite ends of one axis"
    return None


def _guides(
    joints: Mapping[str, Mapping[str, Any]], ground: tuple[str, ...], size: float
) -> dict[str, str | None]:
    """Each slider's guide pivot: the first ground joint on its guide line, else None."""
    out: dict[str, str | None] = {}
    for name, joint in joints.items():
        if joint["slider"] is None:
            continue
        angle = math.radians(joint["slider"])
        d = np.array([math.cos(angle), math.sin(angle)])
        out[name] = None
        for g in ground:
            off = joints[g]["at"] - joint["at"]
            if abs(d[0] * off[1] - d[1] * off[0]) <= _GUIDE_TOL * size:
                out[name] = g
                break
    return out


def read_sketch(sketch: Any) -> Drawing | None:
    """The drawing ``sketch`` describes, checked; None for an empty one (no joints, links or
    drivers).

    Raises
    ------
    SketchInvalid
        For anything the drawing cannot mean, in one plain sentence naming the joint or link.
    """
    table = _table(sketch, "the drawing", _KEYS)
    space = table.get("space", "plane")
    if space not in ("plane", "sphere"):
        raise SketchInvalid(f"the drawing's space must be 'plane' or 'sphere', got {_shown(space)}")
    title = table.get("title")
    if title is not None and not isinstance(title, str):
        raise SketchInvalid(f"the drawing's title must be a text, got {_shown(title)}")
    raw_joints = _list(table.get("joints", []), "joints", MAX_JOINTS, "joints")
    raw_links = _list(table.get("links", []), "links", MAX_LINKS, "links")
    raw_drivers = _list(table.get("drivers", []), "drivers", MAX_DRIVERS, "drivers")
    raw_traced = table.get("traced")
    if not raw_joints and not raw_links and not raw_drivers:
        return None
    joints = _read_joints(raw_joints, space)
    links = _read_links(raw_links, joints)
    drivers = _read_drivers(raw_drivers, joints, links)
    traced: tuple[str, ...] = ()
    if raw_traced is not None:
        items = _list(raw_traced, "traced", MAX_JOINTS, "traced joints")
        traced = tuple(dict.fromkeys(_known(t, "traced", joints) for t in items))
    at = {name: j["at"] for name, j in joints.items()}
    ground = tuple(name for name, j in joints.items() if j["ground"])
    on_links = {name for link in links for name in link}
    for name, j in joints.items():
        if name not in on_links and not j["ground"]:
            raise SketchInvalid(
                f"joint {name} is on no link; join it to a link, make it a ground pivot, or "
                "delete it"
            )
    size = drawing_size(space, at, links)
    for link in links:
        for i, a in enumerate(link):
            for b in link[i + 1 :]:
                if why := too_close(space, at[a], at[b], size):
                    raise SketchInvalid(
                        f"joints {a} and {b} of link {link_name(link)} are {why}; move one of them"
                    )
    for i, a in enumerate(ground):
        for b in ground[i + 1 :]:
            if why := too_close(space, at[a], at[b], size):
                raise SketchInvalid(f"ground pivots {a} and {b} are {why}; use one pivot")
    guide = _guides(joints, ground, size)
    added = sum(g is None for g in guide.values())
    if len(joints) + added > MAX_JOINTS:
        raise SketchInvalid(
            f"the drawing has {len(joints)} joints and {_plural(added, 'slider')} whose guide "
            f"adds a ground pivot; at most {MAX_JOINTS} joints are allowed in all"
        )
    return Drawing(
        space=space,
        title=title,
        names=tuple(joints),
        at=at,
        given={name: j["given"] for name, j in joints.items()},
        ground=ground,
        slider={name: j["slider"] for name, j in joints.items() if j["slider"] is not None},
        guide=guide,
        links=links,
        drivers=drivers,
        traced=traced,
        size=size,
    )


def degrees_of_freedom(drawing: Drawing) -> int:
    """The drawing's mobility by Grübler–Kutzbach, the same count in the plane and on the
    sphere (a moving body has three freedoms in both): 3 per link, less 2 for each body beyond
    the first that meets at a joint (the ground is a body at a ground pivot), 1 per slider pin
    (its point is held on a line; the slider block is implicit) and 1 per gear pair (each
    driver after the first).

    >>> four_bar = read_sketch({"joints": [
    ...     {"name": "A0", "at": [0, 0], "ground": True}, {"name": "A", "at": [1, 0]},
    ...     {"name": "B", "at": [3, 2]}, {"name": "B0", "at": [4, 0], "ground": True}],
    ...     "links": [["A0", "A"], ["A", "B"], ["B", "B0"]]})
    >>> degrees_of_freedom(four_bar)
    1
    """
    meeting: dict[str, int] = {name: int(name in drawing.ground) for name in drawing.names}
    for link in drawing.links:
        for name in link:
            meeting[name] += 1
    pins = sum(2 * (n - 1) for n in meeting.values() if n >= 1)
    gears = max(len(drawing.drivers) - 1, 0)
    return 3 * len(drawing.links) - pins - len(drawing.slider) - gears

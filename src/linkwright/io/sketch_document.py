"""The way back from a document to a drawing: :func:`sketch_of_document`, for the workbench's
builder to edit a linkage it did not draw.

Every joint is drawn where it is at θ = 0; the links are the rigid bodies the document's
construction plan builds (:func:`~linkwright.io.topology`), each crank about a ground pivot is
a driver and each slider pin keeps its guide's angle, so that :func:`~.sketch.compile_sketch`
gives the drawing back as an equivalent linkage (a triad's ternary link and its three binary
links are links like any other). What a drawing cannot say (a driven hinge, a double slider's
driven slider, a crank about a moving joint) is refused in one line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Trammel,
)
from linkwright.engine.plan import placed_joints
from linkwright.engine.triad_steps import SphereTriad, Triad
from linkwright.io.document_kinds import tidy_number
from linkwright.io.document_schema import DocumentError
from linkwright.io.documents import parse_document
from linkwright.io.export_geometry import ExportError, topology
from linkwright.io.sketch_checks import (
    MAX_DRIVERS,
    MAX_JOINTS,
    MAX_LINK_JOINTS,
    MAX_LINKS,
    MAX_NAME,
    drawing_size,
    listed,
    too_close,
)
from linkwright.mechanisms import InvalidMechanism, Mechanism, input_range, solve
from linkwright.mechanisms.sixbar import NoConstructionPlan

__all__ = ["SketchError", "sketch_of_document"]

Array = NDArray[np.float64]


class SketchError(ValueError):
    """A document that cannot be edited as a drawing (one line saying why)."""


def _num(x: float) -> float:
    return tidy_number(float(x))


def _deg(rad: float) -> float:
    return _num(math.degrees(rad))


_DRAWABLE = (
    Fixed,
    Crank,
    SphereCrank,
    DyadRRR,
    SphereDyad,
    DyadRRP,
    Rigid,
    SphereRigid,
    Triad,
    SphereTriad,
)


def _refuse_steps(mech: Mechanism) -> None:
    try:
        plan = mech.plan
    except (NoConstructionPlan, ValueError) as exc:
        raise SketchError(f"this linkage cannot be edited as a drawing: {exc}") from None
    for step in plan.steps:
        if hasattr(step, "hinge"):  # a driven hinge, or a triad driven at one
            raise SketchError(
                f"joint {step.hinge} drives the linkage at a moving hinge, which a drawing "
                "cannot say yet (a drawing is driven by cranks about ground pivots)"
            )
        if isinstance(step, Trammel):
            raise SketchError(
                f"joint {step.name} is driven along its slider guide (a double slider), which a "
                "drawing cannot say yet: a drawing is driven by cranks about ground pivots"
            )
        if not isinstance(step, _DRAWABLE):
            raise SketchError(
                f"joint {step.name} is placed by a step a drawing cannot say (a drawing is "
                "pivots, pins and sliders on fixed guides, driven by cranks about ground pivots)"
            )


def _pose(mech: Mechanism) -> dict[str, Array]:
    """Every joint at θ = 0, or in the middle of the first input arc where θ = 0 does not
    assemble (the drawing's θ = 0 is then that input)."""
    motion = solve(mech, [0.0], order=0)
    if not motion.valid[0]:
        try:
            arcs = input_range(mech)
        except (ValueError, ArithmeticError) as exc:
            raise SketchError(f"the linkage does not assemble at θ = 0 ({exc})") from None
        if bool(np.all(arcs.never)):
            raise SketchError("the linkage assembles at no input, so it has no pose to draw")
        lo, hi = float(np.ravel(arcs.lo)[0]), float(np.ravel(arcs.hi)[0])
        motion = solve(mech, [0.5 * (lo + hi)], order=0)
        if not motion.valid[0]:
            raise SketchError("the linkage does not assemble at θ = 0, nor inside its input range")
    return {name: np.asarray(p[0], dtype=float) for name, p in motion.positions.items()}


def _value(params: Mapping[str, Any], p: str | float) -> float:
    return float(np.asarray(params[p] if isinstance(p, str) else p, dtype=float))


def sketch_of_document(document: Any) -> dict[str, Any]:
    """The drawing of a linkage document, whose compile gives an equivalent linkage.

    Every joint is drawn where it is at θ = 0 (in the middle of the first input arc where the
    linkage does not assemble at 0); the links are the rigid bodies its plan builds
    (:func:`~linkwright.io.topology`: a crank's link, a dyad's two rods or the body holding
    both its parents, the body a rigid point is fixed on), each crank about a ground pivot is a
    driver (one per body), and each slider pin keeps its guide's angle. A composed linkage and
    every family built from cranks, dyads, sliders, rigid points and triads is drawn so; a driven
    hinge, a double slider or a crank about a moving joint is refused.

    Raises
    ------
    SketchError
        In one line: the document is not valid, or cannot be drawn (and why).
    """
    try:
        parsed = parse_document(document)
    except DocumentError as exc:
        raise SketchError(str(exc)) from None
    mech = parsed.mechanism
    _refuse_steps(mech)
    try:
        topo = topology(mech)
    except (ExportError, InvalidMechanism) as exc:
        raise SketchError(f"this linkage cannot be edited as a drawing: {exc}") from None
    pose = _pose(mech)
    plan = mech.plan
    ground = set(topo.ground)
    names = [j for step in plan.steps for j in placed_joints(step)]
    sphere_space = any(p.shape[-1] == 3 for p in pose.values())
    slider: dict[str, float] = {}
    for guide in topo.guides:
        if not guide.fixed:
            raise SketchError(
                f"slider {listed(guide.sliders)} runs on a guide through the moving joint "
                f"{guide.through}, which a drawing cannot say (a drawn guide is fixed)"
            )
        for pin in guide.sliders:
            if pin not in ground:
                slider[pin] = _deg(guide.angle)
    links = [list(body) for body in topo.links]
    params = mech.params()
    drivers: list[dict[str, Any]] = []
    driven: set[int] = set()
    for step in plan.steps:
        if not isinstance(step, Crank | SphereCrank):
            continue
        if step.pivot not in ground:
            raise SketchError(
                f"joint {step.name} turns about the moving joint {step.pivot} (a gear carried "
                "by a link), which a drawing cannot say: a driver turns about a ground pivot"
            )
        body = next(
            (k for k, link in enumerate(links) if step.pivot in link and step.name in link), None
        )
        if body is None or body in driven:
            continue  # a point of a body another crank already turns
        driven.add(body)
        drivers.append(
            {"pivot": step.pivot, "joint": step.name, "ratio": _num(_value(params, step.ratio))}
        )
    traced = list(plan.traced)
    space = "sphere" if sphere_space else "plane"
    for name, same in _doubles(space, pose, plan.steps, links, ground, traced).items():
        names.remove(name)
        links = [[same if j == name else j for j in link] for link in links]
        links = [list(dict.fromkeys(link)) for link in links]
        traced = list(dict.fromkeys(same if t == name else t for t in traced))
    joints: list[dict[str, Any]] = []
    for name in names:
        entry: dict[str, Any] = {"name": name, "at": [_num(x) for x in pose[name]]}
        if name in ground:
            entry["ground"] = True
        if name in slider:
            entry["slider"] = slider[name]
        joints.append(entry)
    sketch: dict[str, Any] = {"space": space}
    if parsed.title is not None:
        sketch["title"] = parsed.title
    sketch.update(joints=joints, links=links, drivers=drivers, traced=traced)
    _check_drawable(sketch)
    return sketch


def _doubles(
    space: str,
    pose: Mapping[str, Array],
    steps: Sequence[Any],
    links: list[list[str]],
    ground: set[str],
    traced: list[str],
) -> dict[str, str]:
    """The joints a drawing cannot tell from an earlier one, each → that joint: a point fixed
    on a link at one of the link's joints (a family's coupler point left at the origin), and a
    ground point on no link at another ground pivot (a slider's guide point on the crank's
    pivot). A drawing's joints of one link, and its ground pivots, must be apart."""
    size = drawing_size(space, pose, links)
    order: list[str] = []  # the joints placed before the step
    out: dict[str, str] = {}
    for step in steps:
        name = step.name
        before, order = order, order + list(placed_joints(step))
        if isinstance(step, Rigid | SphereRigid):
            near = {j for link in links if name in link for j in link}
        elif name in ground and name not in traced and not any(name in link for link in links):
            near = ground
        else:
            continue
        for other in before:
            if (
                other in near
                and other not in out
                and too_close(space, pose[name], pose[other], size) is not None
            ):
                out[name] = other
                break
    return out


def _check_drawable(sketch: Mapping[str, Any]) -> None:
    """A drawing within the builder's bounds, every moving joint on a link."""
    on_links = {j for link in sketch["links"] for j in link}
    for entry in sketch["joints"]:
        if not entry.get("ground") and entry["name"] not in on_links:
            raise SketchError(f"joint {entry['name']} is on no link, so it cannot be drawn")
        if len(entry["name"]) > MAX_NAME:
            raise SketchError(f"joint names of a drawing have at most {MAX_NAME} characters")
    most = max((len(link) for link in sketch["links"]), default=0)
    for count, limit, what in (
        (len(sketch["joints"]), MAX_JOINTS, "joints"),
        (len(sketch["links"]), MAX_LINKS, "links"),
        (most, MAX_LINK_JOINTS, "joints on one link"),
        (len(sketch["drivers"]), MAX_DRIVERS, "drivers"),
    ):
        if count > limit:
            raise SketchError(f"the drawing would have {count} {what}; at most {limit} are allowed")

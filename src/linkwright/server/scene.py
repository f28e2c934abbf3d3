"""What the workbench page draws, computed from a document: the *scene*, and the *drag* edit.

A scene (:func:`scene`) is everything the page needs to draw a linkage and run it: the editable
fields, the links between the joints, every joint along the traced circuit of every assembly
mode, the limit positions with a sentence explaining each, the pose at the chosen input, and
the motion diagrams (:func:`linkwright.plot.diagram_series`). All numbers are JSON-ready: no
NaN (``None`` stands where a value does not exist).

A drag (:func:`drag`) moves one joint to where the user dropped it by changing the fewest
document fields (:mod:`linkwright.server.scene_drag` says how).

This module assembles the scene and is the public face of the workbench's scene: the parts
live beside it, in :mod:`~linkwright.server.scene_io` (the menus, a document's fields, parsing
and JSON), :mod:`~linkwright.server.scene_modes` (assembly modes, circuits and limit positions)
and :mod:`~linkwright.server.scene_drag` (the drag and the joints it can move).
"""

from __future__ import annotations

import math
import time
from typing import Any, cast

import numpy as np

from linkwright.engine.circuits import NoPeriod
from linkwright.io import document_to_dict, topology
from linkwright.mechanisms import Mechanism, circuits, running_circuit, solve
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.plot.diagrams import DiagramError, diagram_series
from linkwright.plot.view import range_text
from linkwright.server import budget
from linkwright.server.limits import SAMPLES
from linkwright.server.overlays import motion_json, summary_json
from linkwright.server.scene_drag import DragError, drag, drag_handles
from linkwright.server.scene_io import (
    FAMILY_EXAMPLES,
    document_space,
    examples,
    families,
    family_document,
    family_name,
    fields,
    json_number,
    json_rows,
    read_document,
    to_json,
)
from linkwright.server.scene_modes import (
    circuit_json,
    limit_steps,
    map_centre,
    planned_modes,
    share_searches,
)

__all__ = [
    "DIAGRAM_KINDS",
    "FAMILY_EXAMPLES",
    "DragError",
    "drag",
    "examples",
    "families",
    "family_document",
    "fields",
    "scene",
    "to_json",
]

DIAGRAM_KINDS = ("angles", "velocity", "acceleration")
"""The diagrams a scene carries (paper 003's coefficients stay with ``linkwright plot``)."""


# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------


def _topology_json(
    mechanism: Mechanism, sphere: bool
) -> tuple[list[dict[str, Any]], list[dict[str, Any]], list[str]]:
    try:
        topo = topology(mechanism)
    except ValueError:
        return [], [], []
    bodies = [{"name": "frame", "joints": list(topo.pivots), "ground": True}] if topo.pivots else []
    for links in topo.links:
        bodies.append({"name": "–".join(links), "joints": list(links), "ground": False})
    guides = []
    if not sphere:
        for g in topo.guides:
            guides.append(
                {
                    "name": g.through,
                    "through": g.through,
                    "direction": [math.cos(g.angle), math.sin(g.angle)],
                    "sliders": list(g.sliders),
                    "fixed": g.fixed,
                }
            )
    return bodies, guides, list(topo.ground)


def _diagrams(mechanism: Mechanism, samples: int) -> tuple[dict[str, Any] | None, str | None]:
    try:
        data = diagram_series(mechanism, DIAGRAM_KINDS, samples=samples)
    except (DiagramError, NoPeriod) as exc:
        return None, str(exc)
    # diagram_series types its answer as dict[str, object]; its Returns section gives the layout
    # read here (the inputs per circuit, and per kind its panels of series).
    xs = cast(list[np.ndarray], data["x"])
    kinds = cast(dict[str, dict[str, Any]], data["kinds"])
    out: dict[str, Any] = {}
    for kind, body in kinds.items():
        out[kind] = {
            "x": [json_rows(x, 9) for x in xs],
            "limits": data["limits"],
            "details": body["details"],
            "describe": data["describe"],
            "panels": [
                {
                    "ylabel": p["ylabel"],
                    "series": [
                        {
                            "label": s["label"],
                            "color": s["color"],
                            "values": [json_rows(v, 9) for v in s["values"]],
                        }
                        for s in p["series"]
                    ],
                    "ideal": p["ideal"],
                    "note": p["note"],
                    "clip": p["clip"],
                }
                for p in body["panels"]
            ],
        }
    return out, None


def scene(
    document: Any,
    *,
    samples: int = 360,
    at: float | None = None,
    diagrams: bool = True,
    overlays: bool = False,
    summary: bool = False,
) -> dict[str, Any]:
    """Everything the page draws of one document (the module docstring; the contract in the
    server's docs lists every key). ``overlays`` adds the joints' velocities and accelerations
    and the instant centres along the own mode's circuits, ``summary`` the analysis summary
    (:mod:`linkwright.server.overlays`); neither is computed unless asked.

    Raises
    ------
    DocumentError
        For a document that is not valid (naming the field).

    Examples
    --------
    >>> from linkwright.io import load_example
    >>> s = scene(document_to_dict(load_example("rocker-input")), samples=32, diagrams=False)
    >>> s["full"], s["range"], [m["label"] for m in s["modes"]]
    (False, 'θ in [−106.1°, −64.1°] and [64.1°, 106.1°]', ['assembly +1', 'assembly −1'])
    >>> sorted({round(x["input"], 2) for x in s["limits"]})  # |A − B0| = coupler ± rocker
    [-106.07, -64.06, 64.06, 106.07]

    A linkage that cannot be assembled is a scene with nothing to run, and says why:

    >>> never = {"format": "linkwright/1", "mechanism": {"family": "fourbar", "A0": [0, 0],
    ...          "B0": [10, 0], "crank": 1, "coupler": 2, "rocker": 3}}
    >>> s = scene(never, samples=32)
    >>> s["modes"], s["pose"]
    ([], None)
    >>> s["message"]  # doctest: +ELLIPSIS
    'This linkage cannot be assembled at any input angle, in any assembly mode: ...'

    A scene whose circuits cost more than a request may is refused before they are traced
    (:mod:`linkwright.server.budget`):

    >>> geared = document_to_dict(load_example("geared-fivebar"))
    >>> geared["mechanism"]["ratio"] = 1000.0
    >>> scene(geared, samples=360)
    Traceback (most recent call last):
    ...
    linkwright.server.budget.TooCostly: too costly: the gear ratio 1000 turns a crank 1,000 \
times per input turn; circuits can be traced up to 64 (the limit search samples 1,440 inputs a \
turn); lower the ratio to 64 or less
    """
    with budget.request("samples"):
        return _scene(
            document, samples=samples, at=at, diagrams=diagrams, overlays=overlays, summary=summary
        )


def _scene(
    document: Any,
    *,
    samples: int,
    at: float | None,
    diagrams: bool,
    overlays: bool = False,
    summary: bool = False,
) -> dict[str, Any]:
    started = time.perf_counter()
    low, high = SAMPLES.least, SAMPLES.value
    assert low is not None  # limits.py gives the samples a least value
    if isinstance(samples, bool) or not isinstance(samples, int) or not low <= samples <= high:
        raise ValueError(f"samples: must be a whole number from {low} to {high}, got {samples!r}")
    if at is not None and not math.isfinite(at):
        raise ValueError(f"at: must be a finite angle in degrees, got {at!r}")
    doc = read_document(document, client=True)
    raw = document_to_dict(doc)
    mech = doc.mechanism
    space = document_space(doc)
    sphere = space == "sphere"
    bodies, guides, ground = _topology_json(mech, sphere)
    dyads = limit_steps(mech)
    try:
        traced = list(mech.plan.traced)
        joints = [s.name for s in mech.plan.steps]
    except NoConstructionPlan:
        traced, joints = [], []

    modes: list[dict[str, Any]] = []
    never: list[str] = []
    limits: list[dict[str, Any]] = []
    message = None
    traced_variants: list[tuple[str, dict[str, int], bool, Any, list[Any]]] = []
    try:
        planned = planned_modes(doc, samples, diagrams, overlays, summary)
        share_searches([variant.mechanism for _, _, variant, _, _ in planned], samples)
        for label, signs, variant, own, arcs in planned:
            if variant.mechanism.plan.triads:
                # Every circuit of every configuration, found together: the arcs count only
                # the rocking ones, and a circuit that turns fully may run beside them.
                motions = circuits(variant.mechanism, samples, order=0)[1]
            else:
                motions = budget.trace_circuits(variant.mechanism, arcs, samples)
            if motions:
                traced_variants.append((label, signs, own, arcs, motions))
            else:
                never.append(label)
    except NoConstructionPlan as exc:
        message = (
            f"{type(mech).__name__} driven this way has no construction plan to trace, so the "
            f"workbench cannot run it: {exc}"
        )
    except NoPeriod as exc:
        message = f"Its circuit never closes, so it has no cycle to run: {exc}"
    centre = None
    if sphere and traced_variants:
        centre = map_centre([m for *_, ms in traced_variants for m in ms], traced)
    own_arcs = None
    for label, signs, own, arcs, motions in traced_variants:
        k = len(modes)
        full = bool(arcs.full)
        if own:
            own_arcs = arcs
        circuit_bodies = []
        for c, motion in enumerate(motions):
            body, lims = circuit_json(motion, dyads, sphere, full, centre)
            circuit_bodies.append(body)
            for i, theta, text in lims:
                limits.append({"input": theta, "mode": k, "circuit": c, "index": i, "text": text})
        modes.append(
            {
                "label": label,
                "own": own,
                "assembly": signs,
                "full": full,
                "circuits": circuit_bodies,
            }
        )
    own_mode = next((m for m in modes if m["own"]), None)
    if message is None and not modes:
        why = (
            "its triad’s ternary link cannot be held by its three links"
            if mech.plan.triads
            else "some dyad’s links cannot reach each other"
        )
        message = (
            f"This linkage cannot be assembled at any input angle, in any assembly mode: {why}."
        )
    elif message is None and own_mode is None:
        message = (
            "This linkage cannot be assembled in its own assembly mode at any input angle; "
            f"it can in {', '.join(m['label'] for m in modes)}."
        )

    pose = None
    pose_at = at
    if own_mode is not None:
        # The circuit the document runs on (its start), where the page begins.
        runs_on = min(running_circuit(mech, samples), len(own_mode["circuits"]) - 1)
        first = own_mode["circuits"][runs_on]
        if pose_at is None:
            pose_at = first["input"][0]
        motion = solve(mech, np.radians([pose_at]), order=0)
        if bool(np.asarray(motion.valid).all()):
            pose = {k: json_rows(v[0]) for k, v in motion.positions.items()}

    diagram_json = None
    if diagrams and own_mode is not None:
        diagram_json, why_not = _diagrams(mech, samples)
        if why_not and message is None:
            message = why_not

    result = {
        "document": raw,
        "title": doc.title,
        "units": doc.units,
        "family": doc.family,
        "family_name": family_name(doc.family, space),
        "space": space,
        "fields": fields(raw),
        "joints": joints,
        "fixed": ground,
        "traced": traced,
        "handles": drag_handles(raw, joints, ground, pose_at),
        "bodies": bodies,
        "guides": guides,
        "at": json_number(pose_at) if pose_at is not None else None,
        "pose": pose,
        "range": range_text(own_arcs) if own_arcs is not None else "nowhere",
        "full": bool(own_mode["full"]) if own_mode is not None else False,
        "modes": modes,
        "never": never,
        "limits": limits,
        "map_center": json_rows(centre) if centre is not None else None,
        "diagrams": diagram_json,
        "message": message,
    }
    # The velocities, centres and analysis summary (server/overlays.py), only where asked.
    own_motions = next((ms for _, _, own, _, ms in traced_variants if own), [])
    if overlays:
        result["overlays"] = motion_json(mech, own_motions, pose_at) if own_motions else None
    if summary:
        result["summary"] = summary_json(mech)
    result["compute_ms"] = round(1e3 * (time.perf_counter() - started), 3)
    return result

"""What the workbench page draws, computed from a document: the *scene*, and the *drag* edit.

A scene (:func:`scene`) is everything the page needs to draw a linkage and run it: the editable
fields, the links between the joints, every joint along the traced circuit of every assembly
mode, the limit positions with a sentence explaining each, the pose at the chosen input, and
the motion diagrams (:func:`linkwright.plot.diagram_series`). All numbers are JSON-ready: no
NaN (``None`` stands where a value does not exist).

A drag (:func:`drag`) moves one joint to where the user dropped it by changing the fewest
document fields: the fields that move that joint and nothing placed before it (a coupler point
moves by its ``point.u``/``point.v``, a dyad's joint by its two link lengths, a pivot by its
coordinates), found by perturbing each field, and solved by Gauss–Newton; where those fields
alone cannot reach the target (a crank's end, whose length moves it only radially), the input
angle joins them, so dragging a crank's end turns the crank.
"""

from __future__ import annotations

import copy
import itertools
import math
import time
from typing import Any

import numpy as np
import orjson

from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs, NoPeriod
from linkwright.engine.plan import placed_joints
from linkwright.engine.shared import share_arcs, share_samples
from linkwright.geometry.sphere import clear_centre, lambert_azimuthal
from linkwright.io import (
    FAMILY_SPECS,
    Document,
    DocumentError,
    document_to_dict,
    list_examples,
    load_example,
    parse_document,
    topology,
)
from linkwright.io.documents import JOINT_SPECS, SPHERE_JOINT_SPECS, WORKING_RANGE
from linkwright.mechanisms import Mechanism, circuits, registry, solve
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.plot.diagrams import DiagramError, diagram_series
from linkwright.plot.view import range_text
from linkwright.server import budget
from linkwright.server.limits import SAMPLES, check_document
from linkwright.server.overlays import estimate as overlay_cost
from linkwright.server.overlays import motion_json, summary_json

__all__ = [
    "DIAGRAM_KINDS",
    "DragError",
    "drag",
    "examples",
    "families",
    "family_document",
    "scene",
    "to_json",
]

DIAGRAM_KINDS = ("angles", "velocity", "acceleration")
"""The diagrams a scene carries (paper 003's coefficients stay with ``linkwright plot``)."""

FAMILY_EXAMPLES = {f.name: f.example for f in registry.families()}
"""The bundled example each family opens with (the registry's)."""

MAX_MODES = 4
"""Assembly modes drawn: every combination of up to two sign fields (2 × 2)."""

_MINUS = "−"

# Field kinds the page edits as numbers, and how it labels them.
_SCALAR_KINDS = {
    "length": ("length", ""),
    "arc": ("angle", "°"),
    "offset_arc": ("angle", "°"),
    "angle_deg": ("angle", "°"),
    "number": ("length", ""),
    "ratio": ("ratio", ""),
}


class DragError(ValueError):
    """A joint cannot be dragged where asked (the message says why)."""


# --------------------------------------------------------------------------------------------
# Families and examples
# --------------------------------------------------------------------------------------------


def _family_name(family: str, space: str) -> str:
    name = registry.family(family).display
    return f"{name} (sphere)" if family == "linkage" and space == "sphere" else name


def families() -> list[dict[str, Any]]:
    """Every family: its name, group, space and the example it opens with (the registry)."""
    return [
        {
            "family": f.name,
            "name": f.display,
            "group": f.group,
            "space": "sphere" if f.space == "sphere" else "plane",
            "example": f.example,
        }
        for f in registry.families()
    ]


def family_document(family: str) -> dict[str, Any]:
    """The document a family opens with (its bundled example)."""
    if family not in FAMILY_EXAMPLES:
        raise LookupError(f"family: no family named {family!r}")
    return document_to_dict(load_example(FAMILY_EXAMPLES[family]))


_EXAMPLES: list[dict[str, Any]] | None = None


def examples() -> list[dict[str, Any]]:
    """The bundled examples: name, title, family and space (read once)."""
    global _EXAMPLES
    if _EXAMPLES is None:
        rows = []
        for name in list_examples():
            doc = load_example(name)
            rows.append(
                {
                    "name": name,
                    "title": doc.title or name,
                    "family": doc.family,
                    "space": doc.mechanism.space,
                }
            )
        _EXAMPLES = rows
    return copy.deepcopy(_EXAMPLES)


# --------------------------------------------------------------------------------------------
# Fields: every editable scalar of a document, by dotted path
# --------------------------------------------------------------------------------------------


def _get(tree: Any, path: str) -> Any:
    for key in path.split("."):
        tree = tree[int(key)] if isinstance(tree, list) else tree[key]
    return tree


def _set(tree: Any, path: str, value: Any) -> None:
    keys = path.split(".")
    for key in keys[:-1]:
        tree = tree[int(key)] if isinstance(tree, list) else tree[key]
    last = keys[-1]
    if isinstance(tree, list):
        tree[int(last)] = value
    else:
        tree[last] = value


def _field(path: str, label: str, value: Any, kind: str, unit: str = "", **more: Any) -> dict:
    return {"path": path, "label": label, "value": value, "kind": kind, "unit": unit, **more}


def _spec_fields(prefix: str, label: str, kind: str, value: Any) -> list[dict[str, Any]]:
    """The page's fields for one document field of kind ``kind``."""
    if kind in _SCALAR_KINDS:
        what, unit = _SCALAR_KINDS[kind]
        return [_field(prefix, label, value, what, unit)]
    if kind == "sign":
        return [_field(prefix, label, value, "sign", choices=[1, -1])]
    if kind in ("point", "axis"):
        return [
            _field(f"{prefix}.{i}", f"{label} {axis}", v, "coordinate")
            for i, (axis, v) in enumerate(zip("xyz", value, strict=False))
        ]
    if kind == "uv":
        return [_field(f"{prefix}.{k}", f"{label} {k}", value[k], "coordinate") for k in "uv"]
    if kind in ("arc_point", "arc_pivot"):
        return [
            _field(f"{prefix}.arc", f"{label} arc", value["arc"], "angle", "°"),
            _field(f"{prefix}.angle", f"{label} angle", value["angle"], "angle", "°"),
        ]
    if kind == "line":
        return [
            *_spec_fields(f"{prefix}.point", f"{label} point", "point", value["point"]),
            _field(f"{prefix}.angle", f"{label} angle", value["angle"], "angle", "°"),
        ]
    if kind == "stephenson_input":
        return [_field(prefix, label, value, "choice", choices=["crank", "output"])]
    if kind == "spherical_input":
        return [_field(prefix, label, value, "choice", choices=["AB", "FG"])]
    return []  # names, joint references, the space: not numbers to edit


def fields(raw: dict[str, Any]) -> list[dict[str, Any]]:
    """Every editable value of a validated document, in document order.

    >>> doc = load_example("crank-rocker")
    >>> [f["path"] for f in fields(document_to_dict(doc))][:4]
    ['mechanism.A0.0', 'mechanism.A0.1', 'mechanism.B0.0', 'mechanism.B0.1']
    """
    mech = raw["mechanism"]
    family = mech["family"]
    out: list[dict[str, Any]] = []
    for spec in FAMILY_SPECS[family].fields:
        if spec.name not in mech:
            continue
        if spec.kind == "joints":
            specs = SPHERE_JOINT_SPECS if mech.get("space") == "sphere" else JOINT_SPECS
            for i, joint in enumerate(mech["joints"]):
                for js in specs[joint["type"]]:
                    if js.name in joint:
                        out += _spec_fields(
                            f"mechanism.joints.{i}.{js.name}",
                            f"{joint['name']} {js.name}",
                            js.kind,
                            joint[js.name],
                        )
            continue
        out += _spec_fields(f"mechanism.{spec.name}", spec.name, spec.kind, mech[spec.name])
    return out


def _sign_paths(raw: dict[str, Any]) -> list[str]:
    return [f["path"] for f in fields(raw) if f["kind"] == "sign"]


# --------------------------------------------------------------------------------------------
# JSON helpers
# --------------------------------------------------------------------------------------------


def _rows(a: np.ndarray, digits: int = 12) -> np.ndarray:
    """An array rounded to keep the answer small; :func:`to_json` writes NaN and ±inf as null."""
    return np.ascontiguousarray(np.round(np.asarray(a, dtype=float), digits))


def to_json(value: Any) -> bytes:
    """A scene (or any answer holding NumPy arrays) as JSON bytes, NaN and ±inf as ``null``.

    orjson writes a scene's ~10^4 numbers straight from its arrays in well under a millisecond;
    lists of Python floats through ``json`` take ten times as long (the redraw's latency budget
    is 50 ms).

    >>> to_json({"x": np.array([1.5, np.nan])})
    b'{"x":[1.5,null]}'
    """
    return orjson.dumps(value, option=orjson.OPT_SERIALIZE_NUMPY)


def _number(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _space(doc: Document) -> str:
    """The document's space, read from the document: a mechanism without a construction plan
    (a spherical Stephenson III driven at FG) cannot tell its own."""
    if registry.family(doc.family).space == "sphere":
        return "sphere"
    return str(doc.raw["mechanism"].get("space", "plane"))


def _parse(document: Any, *, client: bool = False) -> Document:
    """The document parsed; a ``client``'s document (not one made here from a parsed one) is
    first held to the request limits."""
    if not isinstance(document, dict):
        raise DocumentError("document", f"must be a JSON object, got {type(document).__name__}")
    if client:
        check_document(document)
    return parse_document(document, source="document")


# --------------------------------------------------------------------------------------------
# Assembly modes, circuits and limit positions
# --------------------------------------------------------------------------------------------


def _mode_label(raw: dict[str, Any], paths: list[str], values: tuple[int, ...]) -> str:
    mech = raw["mechanism"]
    parts = []
    for path, v in zip(paths, values, strict=True):
        keys = path.split(".")
        name = mech["joints"][int(keys[2])]["name"] if keys[1] == "joints" else keys[-1]
        parts.append(f"{name} {'+1' if v > 0 else _MINUS + '1'}")
    return ", ".join(parts) if parts else "its only assembly"


def _variants(doc: Document) -> list[tuple[str, dict[str, int], Document, bool]]:
    """(label, sign fields, document, own) for each assembly mode to draw, own first."""
    if doc.mechanism is not None and doc.mechanism.plan.triads:
        # A triad's configurations are followed along its circuits, not chosen by signs: one
        # mode holds every circuit of every configuration.
        return [("every configuration (a triad)", {}, doc, True)]
    raw = document_to_dict(doc)
    paths = _sign_paths(raw)
    own = tuple(int(_get(raw, p)) for p in paths)
    combos = [own]
    if 0 < len(paths) <= 2:
        combos += [c for c in itertools.product((1, -1), repeat=len(paths)) if c != own]
    out = []
    for values in combos:
        variant = copy.deepcopy(raw)
        for p, v in zip(paths, values, strict=True):
            _set(variant, p, v)
        try:
            parsed = doc if values == own else _parse(variant)
        except DocumentError:
            continue
        signs = {p.removeprefix("mechanism."): v for p, v in zip(paths, values, strict=True)}
        out.append((_mode_label(raw, paths, values), signs, parsed, values == own))
    return out


def _degrees(theta: np.ndarray) -> np.ndarray:
    """Continuous degrees along a circuit, the first sample in [−180°, 180°)."""
    t = np.asarray(theta, dtype=float)
    ok = np.isfinite(t)
    out = np.full_like(t, np.nan)
    if ok.any():
        u = np.unwrap(t[ok])
        u -= 2 * np.pi * np.floor((u[0] + np.pi) / (2 * np.pi))
        out[ok] = np.degrees(u)
    return out


def _dyads(mechanism: Mechanism) -> dict[str, Any]:
    try:
        plan = mechanism.plan
    except NoConstructionPlan:
        return {}
    # Every joint of a step that has limit positions (a dyad, a triad), so that any of a
    # triad's joints names it; the step kind says what happens there.
    return {j: s for s in plan.steps if hasattr(s, "at_limit") for j in placed_joints(s)}


def _limit_text(theta_deg: float, changed: list[str], dyads: dict[str, Any], sphere: bool) -> str:
    """Why the input turns back at a limit position, in words."""
    steps = list({id(s): s for s in (dyads.get(name) for name in changed) if s}.values())
    triad = any(hasattr(s, "max_poses") for s in steps)
    reasons = [s.at_limit() for s in steps]
    why = "; ".join(reasons) if reasons else "a dyad reaches the end of its reach"
    if triad:
        # A triad's circuit may run on past a whole turn: the limit is named within one turn.
        theta_deg = math.degrees(math.remainder(math.radians(theta_deg), 2 * math.pi))
        then = "in the other configuration"
    else:
        then = f"with {', '.join(changed) if changed else 'a dyad'} on its other branch (the "
        then += "other assembly)"
    return (
        f"Limit position at θ = {theta_deg:.2f}°: the input cannot turn further this way, "
        f"because {why}. The machine runs on {then} as the input turns back."
    )


def _circuit_json(
    motion: Any, dyads: dict[str, Any], sphere: bool, full: bool, centre: np.ndarray | None
) -> tuple[dict[str, Any], list[tuple[int, float, str]]]:
    theta = _degrees(motion.input)
    limits: list[tuple[int, float, str]] = []
    if not full:
        # The step back to the start is taken within one turn: a triad's circuit may close a
        # whole turn away from where it started.
        step = np.sign((np.diff(np.r_[theta, theta[0]]) + 180.0) % 360.0 - 180.0)
        n = theta.size
        for i in range(n):
            if step[i] != 0 and step[i - 1] != 0 and step[i] != step[i - 1]:
                before, after = (i - 1) % n, (i + 1) % n
                changed = [
                    name
                    for name, b in motion.labels.items()
                    if np.asarray(b)[before] != np.asarray(b)[after]
                ]
                limits.append((i, float(theta[i]), _limit_text(theta[i], changed, dyads, sphere)))
    positions = {k: _rows(v) for k, v in motion.positions.items()}
    mapped = None
    if sphere and centre is not None:
        mapped = {k: _rows(lambert_azimuthal(v, centre)) for k, v in motion.positions.items()}
    body = {
        "full": full,
        "input": _rows(theta),
        "positions": positions,
        "map": mapped,
        "limits": [i for i, _, _ in limits],
    }
    return body, limits


def _map_centre(motions: list[Any], traced: list[str]) -> np.ndarray | None:
    pts = [np.asarray(m.positions[t]) for m in motions for t in traced if t in m.positions]
    if not pts:
        pts = [np.asarray(v) for m in motions for v in m.positions.values()]
    if not pts:
        return None
    p = np.concatenate([q.reshape(-1, 3) for q in pts])
    p = p[np.isfinite(p).all(axis=1)]
    c = p.sum(axis=0) if p.size else np.zeros(3)
    n = float(np.linalg.norm(c))
    centre = c / n if n > 1e-9 else np.array([0.0, 0.0, 1.0])
    # Every joint is mapped: none may lie at the centre's antipode (the whole rim of the map).
    drawn = [np.asarray(v).reshape(-1, 3) for m in motions for v in m.positions.values()]
    return clear_centre(centre, np.concatenate(drawn))


def _share_searches(mechanisms: list[Mechanism], samples: int | None) -> None:
    """The assembly modes' limit searches done in one batch where the modes differ only in
    their numbers, as sign fields make them: their arcs (``samples`` None) or their circuits'
    samples (:func:`~linkwright.engine.circuits.share_samples`)."""
    if len(mechanisms) < 2:
        return
    try:
        plan, points = mechanisms[0].plan, mechanisms[0].points
        if plan.triads or any(m.plan != plan or m.points != points for m in mechanisms):
            return
    except NoConstructionPlan:
        return
    linkages = [m.params() for m in mechanisms]
    if samples is None:
        share_arcs(plan, linkages, points=points)
    else:
        share_samples(plan, linkages, samples, points=points)


def _planned(
    doc: Document, samples: int, diagrams: bool, overlays: bool = False, summary: bool = False
) -> list[tuple[str, dict[str, int], Document, bool, InputArcs]]:
    """Each assembly mode to draw with its input's arcs, once the whole scene's estimated cost
    (every circuit of every mode, the diagrams, the answer) is known to fit a request's budget
    (:mod:`linkwright.server.budget`)."""
    out = []
    estimate: cost.Estimate | None = None
    numbers = 0.0
    variants = _variants(doc)
    _share_searches([variant.mechanism for _, _, variant, _ in variants], None)
    for label, signs, variant, own in variants:
        arcs, part, answer = budget.scene_part(variant.mechanism, samples, own and diagrams)
        if own and (overlays or summary):
            more, extra = overlay_cost(
                variant.mechanism, arcs, samples, overlays=overlays, summary=summary
            )
            part, answer = part + more, answer + extra
        estimate = part if estimate is None else estimate + part
        numbers += answer
        out.append((label, signs, variant, own, arcs))
    if estimate is not None:
        budget.check_scene(estimate, numbers, samples)
    return out


# --------------------------------------------------------------------------------------------
# The scene
# --------------------------------------------------------------------------------------------


def _topology_json(mechanism: Mechanism, sphere: bool) -> tuple[list[dict], list[dict], list[str]]:
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
    out: dict[str, Any] = {}
    for kind, body in data["kinds"].items():
        out[kind] = {
            "x": [_rows(x, 9) for x in data["x"]],
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
                            "values": [_rows(v, 9) for v in s["values"]],
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
    if isinstance(samples, bool) or not isinstance(samples, int) or not low <= samples <= high:
        raise ValueError(f"samples: must be a whole number from {low} to {high}, got {samples!r}")
    if at is not None and not math.isfinite(at):
        raise ValueError(f"at: must be a finite angle in degrees, got {at!r}")
    doc = _parse(document, client=True)
    raw = document_to_dict(doc)
    mech = doc.mechanism
    space = _space(doc)
    sphere = space == "sphere"
    bodies, guides, ground = _topology_json(mech, sphere)
    dyads = _dyads(mech)
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
        planned = _planned(doc, samples, diagrams, overlays, summary)
        _share_searches([variant.mechanism for _, _, variant, _, _ in planned], samples)
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
        centre = _map_centre([m for *_, ms in traced_variants for m in ms], traced)
    own_arcs = None
    for label, signs, own, arcs, motions in traced_variants:
        k = len(modes)
        full = bool(arcs.full)
        if own:
            own_arcs = arcs
        circuit_bodies = []
        for c, motion in enumerate(motions):
            body, lims = _circuit_json(motion, dyads, sphere, full, centre)
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
        first = own_mode["circuits"][0]
        if pose_at is None:
            pose_at = first["input"][0]
        motion = solve(mech, np.radians([pose_at]), order=0)
        if bool(np.asarray(motion.valid).all()):
            pose = {k: _rows(v[0]) for k, v in motion.positions.items()}

    diagram_json = None
    if diagrams and own_mode is not None:
        diagram_json, why = _diagrams(mech, samples)
        if why and message is None:
            message = why

    result = {
        "document": raw,
        "title": doc.title,
        "units": doc.units,
        "family": doc.family,
        "family_name": _family_name(doc.family, space),
        "space": space,
        "fields": fields(raw),
        "joints": joints,
        "fixed": ground,
        "traced": traced,
        "handles": _handles(raw, joints, ground, pose_at),
        "bodies": bodies,
        "guides": guides,
        "at": _number(pose_at) if pose_at is not None else None,
        "pose": pose,
        "range": range_text(own_arcs) if own_arcs is not None else "nowhere",
        "full": bool(own_mode["full"]) if own_mode is not None else False,
        "modes": modes,
        "never": never,
        "limits": limits,
        "map_center": _rows(centre) if centre is not None else None,
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


_MOVABLE: dict[tuple[Any, ...], frozenset[str]] = {}


def _handles(
    raw: dict[str, Any], joints: list[str], ground: list[str], at: float | None
) -> list[str]:
    """The joints a drag can move: every moving joint, and the ground joints some field moves
    (a spherical four-bar's A0 is paper 000's fixed (1, 0, 0)). Which ground joints move depends
    on the family's structure only, so it is found once per structure."""
    mech = raw["mechanism"]
    key = (
        mech["family"],
        mech.get("space"),
        *((j["name"], j["type"]) for j in mech.get("joints", ())),
    )
    if key not in _MOVABLE:
        theta = math.radians(at) if at is not None else 0.0
        base = _pose_of(raw, theta)
        movable: set[str] = set()
        if base is not None:
            for f in fields(raw):
                if f["kind"] not in _EDITABLE:
                    continue
                trial = copy.deepcopy(raw)
                _set(trial, f["path"], float(f["value"]) + 1e-3 * max(1.0, abs(float(f["value"]))))
                moved = _pose_of(trial, theta)
                if moved is not None:
                    movable |= {g for g in ground if np.linalg.norm(moved[g] - base[g]) > 1e-9}
        _MOVABLE[key] = frozenset(movable)
    return [j for j in joints if j not in ground or j in _MOVABLE[key]]


# --------------------------------------------------------------------------------------------
# Dragging a joint
# --------------------------------------------------------------------------------------------

_EDITABLE = ("length", "angle", "coordinate")
_SKIP_LABELS = ("ratio",)


def _pose_of(raw: dict[str, Any], theta: float) -> dict[str, np.ndarray] | None:
    # Every drag and handle search is a loop of these: the request's deadline is checked here.
    cost.check_time()
    try:
        mech = _parse(raw).mechanism
    except DocumentError:
        return None
    try:
        motion = solve(mech, np.array([theta]), order=0)
    except NoConstructionPlan:
        return None
    if not bool(np.asarray(motion.valid).all()):
        return None
    return {k: np.asarray(v[0], dtype=float) for k, v in motion.positions.items()}


def drag(document: Any, joint: str, to: Any, at: float) -> dict[str, Any]:
    """The document with ``joint`` moved to ``to`` at input ``at`` (degrees), changing the
    fewest fields (module docstring), and the input angle it is drawn at.

    Raises
    ------
    DragError
        For an unknown joint, a target of the wrong size, or one the linkage cannot reach.

    Examples
    --------
    Dragging a crank-rocker's coupler point moves it on its coupler, nothing else:

    >>> doc = document_to_dict(load_example("crank-rocker"))
    >>> out = drag(doc, "P", [1.0, 3.0], 30.0)
    >>> {k: v for k, v in out["document"]["mechanism"].items() if v != doc["mechanism"][k]}.keys()
    dict_keys(['point'])
    >>> [round(float(x), 9) for x in _pose_of(out["document"], math.radians(out["at"]))["P"]]
    [1.0, 3.0]
    """
    with budget.request("the number of joints"):
        return _drag(document, joint, to, at)


def _joint_count(doc: Document) -> int:
    try:
        return len(doc.mechanism.plan.steps)
    except NoConstructionPlan:
        return len(type(doc.mechanism).plan.steps)


def _drag(document: Any, joint: str, to: Any, at: float) -> dict[str, Any]:
    doc = _parse(document, client=True)
    raw = document_to_dict(doc)
    sphere = _space(doc) == "sphere"
    target = np.asarray(to, dtype=float)
    if target.shape != ((3,) if sphere else (2,)) or not np.isfinite(target).all():
        raise DragError(
            f"to: must be {'3 finite numbers (a direction)' if sphere else '2 finite numbers'}, "
            f"got {to!r}"
        )
    biggest = float(np.abs(target).max())
    if sphere:
        if not biggest > 0:
            raise DragError("to: a direction must not be the zero vector")
        # Scaled by its largest component first, so that its norm neither overflows (1e200²)
        # nor underflows.
        target = target / biggest
        target = target / np.linalg.norm(target)
    elif problem := WORKING_RANGE.size_problem(biggest):
        raise DragError(f"to: a coordinate {problem}")
    if not math.isfinite(at):
        raise DragError(f"at: must be a finite angle in degrees, got {at!r}")
    theta = math.radians(at)
    budget.check(budget.drag_estimate(len(fields(raw)), _joint_count(doc)))
    base = _pose_of(raw, theta)
    if base is None:
        raise DragError(f"the linkage is not assembled at θ = {at:.6g}°, so nothing can be dragged")
    if joint not in base:
        raise DragError(f"joint: no joint named {joint!r} (joints: {', '.join(base)})")

    # Which fields move the joint, and which of them move the fewest joints placed before it.
    candidates = [
        f for f in fields(raw) if f["kind"] in _EDITABLE and f["label"] not in _SKIP_LABELS
    ]
    own: list[tuple[dict[str, Any], int]] = []
    for f in candidates:
        h = 1e-6 * max(1.0, abs(float(f["value"])))
        trial = copy.deepcopy(raw)
        _set(trial, f["path"], float(f["value"]) + h)
        moved = _pose_of(trial, theta)
        if moved is None:
            continue
        shift = {k: float(np.linalg.norm(moved[k] - base[k])) for k in base}
        if shift[joint] <= 1e-6 * h:  # the field does not move the dragged joint
            continue
        others = sum(1 for k, d in shift.items() if k != joint and d > 1e-6 * h)
        own.append((f, others))
    if not own:
        raise DragError(f"{joint} is fixed by the linkage's other joints: no field moves it alone")
    levels = sorted({n for _, n in own})
    fewest = [f for f, n in own if n == levels[0]]
    every = [f for f, _ in own]
    attempts = [(raw, fewest, False), (raw, fewest, True)]
    if len(levels) > 1:
        attempts += [(raw, every, False), (raw, every, True)]
    # Past a dyad's folded position the joint is on the other branch: the other assemblies.
    for path in _sign_paths(raw):
        flipped = copy.deepcopy(raw)
        _set(flipped, path, -int(_get(raw, path)))
        attempts += [(flipped, fewest, False), (flipped, fewest, True)]
    best: tuple[float, dict[str, Any], float] | None = None
    start = float(np.linalg.norm(base[joint] - target))
    for tree, chosen, use_input in attempts:
        found = _gauss_newton(tree, joint, target, theta, chosen, use_input=use_input)
        if found is None:
            continue
        new, new_theta, miss = found
        if miss <= 1e-9 * max(1.0, float(np.abs(target).max())):
            return {"document": new, "at": _number(math.degrees(new_theta)), "exact": True}
        if miss < start - 1e-12 and (best is None or miss < best[0]):
            best = (miss, new, new_theta)
    if best is None:
        labels = ", ".join(f["label"] for f in every)
        raise DragError(
            f"{joint} cannot move towards there: its fields ({labels}) move it only another "
            "way, or the linkage would not assemble"
        )
    # Out of reach: the nearest position the joint can take (a pivot that only slides on its
    # circle, a point beyond the links' reach).
    return {"document": best[1], "at": _number(math.degrees(best[2])), "exact": False}


def _gauss_newton(
    raw: dict[str, Any],
    joint: str,
    target: np.ndarray,
    theta: float,
    chosen: list[dict[str, Any]],
    *,
    use_input: bool,
) -> tuple[dict[str, Any], float, float] | None:
    """Move ``joint`` towards ``target`` by the ``chosen`` fields (and the input): damped
    Gauss–Newton steps with a forward-difference Jacobian. Returns the document, the input and
    the distance left, or None where the linkage does not assemble to begin with."""
    x = np.array([float(_get(raw, f["path"])) for f in chosen] + ([theta] if use_input else []))
    scale = max(1.0, float(np.abs(target).max()))

    def place(v: np.ndarray) -> tuple[dict[str, Any], float, np.ndarray | None]:
        trial = copy.deepcopy(raw)
        for f, value in zip(chosen, v, strict=False):
            _set(trial, f["path"], float(value))
        t = float(v[-1]) if use_input else theta
        pose = _pose_of(trial, t)
        return trial, t, None if pose is None else pose[joint]

    trial, t, p = place(x)
    if p is None:
        return None
    for _ in range(30):
        r = p - target
        if float(np.linalg.norm(r)) <= 1e-10 * scale:
            break
        J = np.empty((r.size, x.size))
        for j in range(x.size):
            h = 1e-7 * max(1.0, abs(x[j]))
            step = x.copy()
            step[j] += h
            _, _, q = place(step)
            if q is None:
                step[j] -= 2 * h
                _, _, q = place(step)
                h = -h
            if q is None:
                return trial, t, float(np.linalg.norm(r))
            J[:, j] = (q - p) / h
        # Directions the fields cannot move the joint (off the sphere; along a triad's joint's
        # circle when every field turns it the same way) show in the forward differences as
        # singular values at their noise: solving along them would take wild steps.
        dx, *_ = np.linalg.lstsq(J, -r, rcond=1e-6)
        moved = False
        for damping in (1.0, 0.5, 0.25, 0.125, 0.0625):
            cand = x + damping * dx
            trial_c, t_c, q = place(cand)
            if q is not None and np.linalg.norm(q - target) < np.linalg.norm(r):
                x, trial, t, p = cand, trial_c, t_c, q
                moved = True
                break
        if not moved:
            break
    return trial, t, float(np.linalg.norm(p - target))

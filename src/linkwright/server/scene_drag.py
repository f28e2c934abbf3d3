"""The *drag* edit of the workbench, and which joints a drag can move (a scene's handles).

A drag (:func:`drag`) moves one joint to where the user dropped it by changing the fewest
document fields: the fields that move that joint and nothing placed before it (a coupler point
moves by its ``point.u``/``point.v``, a dyad's joint by its two link lengths, a pivot by its
coordinates), found by perturbing each field, and solved by Gauss–Newton; where those fields
alone cannot reach the target (a crank's end, whose length moves it only radially), the input
angle joins them, so dragging a crank's end turns the crank.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from linkwright.engine import cost
from linkwright.io import Document, DocumentError, document_to_dict
from linkwright.io.documents import WORKING_RANGE
from linkwright.mechanisms import solve
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server import budget
from linkwright.server.scene_io import (
    document_space,
    fields,
    get_path,
    json_number,
    read_document,
    set_path,
    sign_paths,
)

__all__ = ["DragError", "drag", "drag_handles"]


class DragError(ValueError):
    """A joint cannot be dragged where asked (the message says why)."""


_MOVABLE: dict[tuple[Any, ...], frozenset[str]] = {}


def drag_handles(
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
                set_path(
                    trial, f["path"], float(f["value"]) + 1e-3 * max(1.0, abs(float(f["value"])))
                )
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
        mech = read_document(raw).mechanism
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

    >>> from linkwright.io import load_example
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
    doc = read_document(document, client=True)
    raw = document_to_dict(doc)
    sphere = document_space(doc) == "sphere"
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
        set_path(trial, f["path"], float(f["value"]) + h)
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
    for path in sign_paths(raw):
        flipped = copy.deepcopy(raw)
        set_path(flipped, path, -int(get_path(raw, path)))
        attempts += [(flipped, fewest, False), (flipped, fewest, True)]
    best: tuple[float, dict[str, Any], float] | None = None
    start = float(np.linalg.norm(base[joint] - target))
    for tree, chosen, use_input in attempts:
        found = _gauss_newton(tree, joint, target, theta, chosen, use_input=use_input)
        if found is None:
            continue
        new, new_theta, miss = found
        if miss <= 1e-9 * max(1.0, float(np.abs(target).max())):
            return {"document": new, "at": json_number(math.degrees(new_theta)), "exact": True}
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
    return {"document": best[1], "at": json_number(math.degrees(best[2])), "exact": False}


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
    x = np.array([float(get_path(raw, f["path"])) for f in chosen] + ([theta] if use_input else []))
    scale = max(1.0, float(np.abs(target).max()))

    def place(v: np.ndarray) -> tuple[dict[str, Any], float, np.ndarray | None]:
        trial = copy.deepcopy(raw)
        for f, value in zip(chosen, v, strict=False):
            set_path(trial, f["path"], float(value))
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

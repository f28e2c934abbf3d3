"""A scene's assembly modes, their circuits and their limit positions.

Every combination of up to two sign fields is an assembly mode to draw (a triad's
configurations are followed along its circuits instead); each mode's circuits are traced once
the whole scene's estimated cost is known to fit a request's budget
(:mod:`linkwright.server.budget`), with the modes' limit searches done in one batch where they
differ only in their numbers. Each circuit becomes its JSON body (inputs in continuous degrees,
joint positions, on a sphere their map) and its limit positions, each with a sentence saying
why the input turns back there.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs
from linkwright.engine.plan import placed_joints
from linkwright.engine.shared import share_arcs, share_samples
from linkwright.geometry.sphere import clear_centre, lambert_azimuthal
from linkwright.io import Document, DocumentError, document_to_dict
from linkwright.mechanisms import Mechanism
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server import budget
from linkwright.server.overlays import estimate as overlay_cost
from linkwright.server.scene_io import get_path, json_rows, read_document, set_path, sign_paths

__all__ = [
    "MAX_MODES",
    "assembly_modes",
    "circuit_json",
    "continuous_degrees",
    "limit_steps",
    "map_centre",
    "planned_modes",
    "share_searches",
]

MAX_MODES = 4
"""Assembly modes drawn: every combination of up to two sign fields (2 × 2)."""

_MINUS = "−"


def _mode_label(raw: dict[str, Any], paths: list[str], values: tuple[int, ...]) -> str:
    mech = raw["mechanism"]
    parts = []
    for path, v in zip(paths, values, strict=True):
        keys = path.split(".")
        name = mech["joints"][int(keys[2])]["name"] if keys[1] == "joints" else keys[-1]
        parts.append(f"{name} {'+1' if v > 0 else _MINUS + '1'}")
    return ", ".join(parts) if parts else "its only assembly"


def assembly_modes(doc: Document) -> list[tuple[str, dict[str, int], Document, bool]]:
    """(label, sign fields, document, own) for each assembly mode to draw, own first."""
    if doc.mechanism is not None and doc.mechanism.plan.triads:
        # A triad's configurations are followed along its circuits, not chosen by signs: one
        # mode holds every circuit of every configuration.
        return [("every configuration (a triad)", {}, doc, True)]
    raw = document_to_dict(doc)
    paths = sign_paths(raw)
    own = tuple(int(get_path(raw, p)) for p in paths)
    combos = [own]
    if 0 < len(paths) <= 2:
        combos += [c for c in itertools.product((1, -1), repeat=len(paths)) if c != own]
    out = []
    for values in combos:
        variant = copy.deepcopy(raw)
        for p, v in zip(paths, values, strict=True):
            set_path(variant, p, v)
        try:
            parsed = doc if values == own else read_document(variant)
        except DocumentError:
            continue
        signs = {p.removeprefix("mechanism."): v for p, v in zip(paths, values, strict=True)}
        out.append((_mode_label(raw, paths, values), signs, parsed, values == own))
    return out


def continuous_degrees(theta: np.ndarray) -> np.ndarray:
    """Continuous degrees along a circuit, the first sample in [−180°, 180°)."""
    t = np.asarray(theta, dtype=float)
    ok = np.isfinite(t)
    out = np.full_like(t, np.nan)
    if ok.any():
        u = np.unwrap(t[ok])
        u -= 2 * np.pi * np.floor((u[0] + np.pi) / (2 * np.pi))
        out[ok] = np.degrees(u)
    return out


def limit_steps(mechanism: Mechanism) -> dict[str, Any]:
    """Each joint placed by a step that has limit positions (a dyad, a triad), to that step."""
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


def circuit_json(
    motion: Any, dyads: dict[str, Any], sphere: bool, full: bool, centre: np.ndarray | None
) -> tuple[dict[str, Any], list[tuple[int, float, str]]]:
    """One traced circuit's JSON body, and its limit positions (sample index, input in degrees,
    why the input turns back there)."""
    theta = continuous_degrees(motion.input)
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
    positions = {k: json_rows(v) for k, v in motion.positions.items()}
    mapped = None
    if sphere and centre is not None:
        mapped = {k: json_rows(lambert_azimuthal(v, centre)) for k, v in motion.positions.items()}
    body = {
        "full": full,
        "input": json_rows(theta),
        "positions": positions,
        "map": mapped,
        "limits": [i for i, _, _ in limits],
    }
    return body, limits


def map_centre(motions: list[Any], traced: list[str]) -> np.ndarray | None:
    """The centre of a spherical scene's map: the traced joints' mean direction, moved where no
    joint lies at its antipode."""
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


def share_searches(mechanisms: list[Mechanism], samples: int | None) -> None:
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
    linkages: list[Mapping[str, ArrayLike]] = [m.params() for m in mechanisms]
    if samples is None:
        share_arcs(plan, linkages, points=points)
    else:
        share_samples(plan, linkages, samples, points=points)


def planned_modes(
    doc: Document, samples: int, diagrams: bool, overlays: bool = False, summary: bool = False
) -> list[tuple[str, dict[str, int], Document, bool, InputArcs]]:
    """Each assembly mode to draw with its input's arcs, once the whole scene's estimated cost
    (every circuit of every mode, the diagrams, the answer) is known to fit a request's budget
    (:mod:`linkwright.server.budget`)."""
    out = []
    estimate: cost.Estimate | None = None
    numbers = 0.0
    variants = assembly_modes(doc)
    share_searches([variant.mechanism for _, _, variant, _ in variants], None)
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

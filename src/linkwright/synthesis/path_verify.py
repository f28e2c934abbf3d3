"""Verification of a path-synthesis candidate of a family with a generic search model.

The candidate is rebuilt in the targets' frame (:meth:`GenericModel.placed`) and solved there by
the plan-based engine, on the configuration the search chose (followed through a triad's
poses: :meth:`GenericModel.reach`); its error is recomputed from those positions, its inputs'
path checked against the limit positions of its circuit, and its constraints against
:mod:`linkwright.analysis`. See :func:`linkwright.synthesis.path.fit_path`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from linkwright.analysis.extrema import golden_max
from linkwright.analysis.general import dyad_transmission_angles
from linkwright.engine import evaluate
from linkwright.mechanisms import circuit, input_range

__all__ = ["in_one_arc", "nearest_on_circuit", "started", "verify_generic"]

Array = NDArray[np.float64]
DENSE = 720
"""Samples of the period on which a candidate's whole circuit is checked."""
REFINE_ROUNDS = 40
"""Golden-section steps that move a nearest-point fit's inputs to their targets' feet."""


def in_one_arc(vmin: float, vmax: float, lo: Array, hi: Array, period: float) -> bool:
    """Whether [vmin, vmax] lies inside one of the arcs [lo, hi] (modulo ``period``)."""
    tol = 1e-9
    for a, b in zip(lo, hi, strict=True):
        if not np.isfinite(a):
            continue
        k = math.floor((vmin - a + tol) / period)
        if vmax - k * period <= b + tol and vmin - k * period >= a - tol:
            return True
    return False


def started(mech: Any, named: Any, inputs: Array) -> tuple[Any, Any]:
    """The answer, and its named family's form, starting where its first target lies: the
    document then names the circuit (the input arc) the answer is on, so that every tool traces
    that circuit, not the linkage's first (:func:`linkwright.mechanisms.running_circuit`)."""
    start = float(np.asarray(inputs).ravel()[0])
    placed = replace(mech, start=start)
    return placed, (placed if named is mech else replace(named, start=start))


def nearest_on_circuit(
    mech: Any, targets: Array, inputs: Array, reached: Array, dist: Array
) -> tuple[Array, Array, Array, dict[str, Array] | None]:
    """Each target's nearest point on the whole circuit ``mech`` runs (its ``start`` names it),
    where that is nearer than the fit's point: (inputs, reached, distances, branches).

    An input that rocks runs its arc up on the assembly and back on the other branch; a
    nearest-point fit found its points on the first leg, and a target nearer the return leg
    was reported too far. Here every target is moved to the nearest of a dense sampling of the
    circuit, then to the foot of its perpendicular by golden-section search in the input on
    that sample's branches. ``branches`` (every dyad's sign at each target) is None when no
    target moved to another branch, so that ``solve(mech, inputs)`` still reproduces them.
    """
    motion = circuit(mech, DENSE * 4, order=0)
    P = np.asarray(motion.positions["P"])
    d2 = np.sum((P[None] - targets[:, None]) ** 2, axis=-1)
    d2 = np.where(np.isfinite(d2), d2, np.inf)
    j = np.argmin(d2, axis=1)
    if not np.any(np.sqrt(d2[np.arange(len(j)), j]) < dist * (1 - 1e-9)):
        return inputs, reached, dist, None
    theta = np.asarray(motion.input)
    signs = {k: np.asarray(v)[j] for k, v in motion.branches.items()}
    n = len(theta)
    a, b = theta[(j - 1) % n], theta[(j + 1) % n]
    a, b = np.minimum(a, b), np.maximum(a, b)
    a, b = np.minimum(a, theta[j]), np.maximum(b, theta[j])

    params = mech.params()

    def gap2(x: Array) -> Array:
        found = evaluate(mech.plan, params, x, points=mech.points, branches=signs, order=0)
        g = np.sum((np.asarray(found.positions["P"]) - targets) ** 2, axis=-1)
        return np.where(np.isfinite(g), g, np.inf)

    foot, closest = golden_max(lambda x: -gap2(x), a, b, steps=REFINE_ROUNDS)
    # The sample itself where the search's interval left the arc (a limit position).
    best = np.where(-closest <= d2[np.arange(len(j)), j], foot, theta[j])
    new = np.sqrt(gap2(best))
    better = new < dist * (1 - 1e-9)
    if not better.any():
        return inputs, reached, dist, None
    at = evaluate(mech.plan, params, best, points=mech.points, branches=signs, order=0)
    own = evaluate(mech.plan, params, inputs, points=mech.points, order=0).branches
    out_inputs = np.where(better, best, inputs)
    out_reached = np.where(better[:, None], np.asarray(at.positions["P"]), reached)
    fit_signs = {k: np.where(better, v, np.asarray(own[k])) for k, v in signs.items()}
    return out_inputs, out_reached, np.where(better, new, dist), fit_signs


def verify_generic(p: Any, cand: Any) -> tuple[dict[str, Any] | None, str]:
    """(the fit's numbers, "") or (None, why it fails), for problem ``p`` and ``cand``."""
    m = p.model
    shape = {k: float(v) for k, v in cand.shape.items()}
    mech, named, R = m.placed(shape, cand.assembly, cand.pose)
    local = m.local(shape, float(cand.assembly))
    psi = m.input_offset(cand.pose)
    transform = _transform(m.space, cand.pose, R)

    def reach(inputs: Array) -> tuple[Array, NDArray[np.bool_], dict[str, Array]]:
        return m.reach(  # type: ignore[no-any-return]
            mech, local, cand.assembly, inputs, psi, transform, p.anchor
        )

    rel = np.asarray(cand.rel, float).copy()
    if m.triads:
        dense = psi + np.linspace(0.0, p.period, DENSE, endpoint=False)
        ok = reach(dense)[1]
        if not ok.any():
            return None, "the linkage never assembles on its configuration"
        full = bool(ok.all())
        arcs = None
    else:
        arcs = input_range(mech)
        if bool(np.asarray(arcs.never)):
            return None, "the linkage never assembles"
        full = bool(np.asarray(arcs.full))
    if p.timing == "none" and full:
        rel = _reproject(p.targets, reach, psi, rel, p.period)
    inputs = rel + psi
    reached, valid, branches = reach(inputs)
    if not valid.all():
        return None, "a target's input cannot be assembled"
    dist = np.sqrt(np.sum((reached - p.targets) ** 2, axis=-1))
    if not full:
        if arcs is not None:
            lo, hi = np.asarray(arcs.lo).ravel(), np.asarray(arcs.hi).ravel()
            inside = in_one_arc(inputs.min(), inputs.max(), lo, hi, float(np.asarray(arcs.period)))
        else:
            inside = bool(reach(np.linspace(inputs.min(), inputs.max(), DENSE // 2))[1].all())
        if not inside:
            return None, "the input passes a limit position between targets"
    if p.timing == "free":
        steps = np.diff(rel) * np.sign(np.sum(np.diff(rel)) or 1.0)
        if np.any(steps < -1e-12) or np.sum(np.abs(np.diff(rel))) > p.period + 1e-9:
            return None, "the free timing is not monotonic within one turn"
    if p.full_turn and not full:
        return None, "its input does not turn fully"
    if p.mu > 0:
        gam = dyad_transmission_angles(mech, circuit(mech, 2048, order=0))
        lo_g = min(float(np.nanmin(g)) for g in gam.values())
        hi_g = max(float(np.nanmax(g)) for g in gam.values())
        if lo_g < p.mu or hi_g > np.pi - p.mu:
            return None, (
                f"its transmission angles span [{np.degrees(lo_g):.3f}°, "
                f"{np.degrees(hi_g):.3f}°], outside [{np.degrees(p.mu):.3f}°, "
                f"{180 - np.degrees(p.mu):.3f}°]"
            )
    if m.triads:
        # The document names the configuration met at the first target (a pose is a name at
        # one input).
        first = {k: v[0] for k, v in branches.items()}
        mech = named = m.with_branches(mech, first)
    mech, named = started(mech, named, inputs)
    error = float(np.sum(dist**2))
    return dict(
        mechanism=mech,
        named=named,
        rotation=R,
        inputs=inputs,
        angles=rel,
        reached=reached,
        distances=dist,
        error=error,
        rms=math.sqrt(error / p.n),
    ), ""


def _transform(space: str, pose: Any, R: Array | None) -> Callable[[Array], Array]:
    """Local positions → the targets' frame."""
    if space == "sphere":
        rot = np.eye(3) if R is None else np.asarray(R)
        return lambda q: np.asarray(q) @ rot.T
    x, y, a = (float(v) for v in pose)
    c, s = math.cos(a), math.sin(a)

    def move(q: Array) -> Array:
        q = np.asarray(q)
        return np.stack((x + c * q[..., 0] - s * q[..., 1], y + s * q[..., 0] + c * q[..., 1]), -1)

    return move


def _reproject(
    targets: Array,
    reach: Callable[[Array], tuple[Array, NDArray[np.bool_], Any]],
    psi: float,
    rel: Array,
    period: float,
) -> Array:
    """Move each target's input to the nearest point of the whole curve: the nearest of a dense
    sampling, then golden-section search between its neighbours, every target in one batch."""
    dense = np.linspace(0.0, period, 2048, endpoint=False)
    curve = reach(dense + psi)[0]
    here = reach(rel + psi)[0]
    d_dense = np.sum((curve[None] - targets[:, None]) ** 2, axis=-1)
    d_dense = np.where(np.isfinite(d_dense), d_dense, np.inf)
    j = np.argmin(d_dense, axis=1)
    now = np.sum((here - targets) ** 2, axis=-1)
    now = np.where(np.isfinite(now), now, np.inf)
    step = dense[1] - dense[0]

    def gap2(x: Array) -> Array:
        g = np.sum((reach(x + psi)[0] - targets) ** 2, axis=-1)
        return np.where(np.isfinite(g), g, np.inf)

    best, closest = golden_max(lambda x: -gap2(x), dense[j] - step, dense[j] + step, REFINE_ROUNDS)
    return np.where(-closest < now, best, rel)

"""Several linkages of one plan traced as one batch, each kept as if traced alone.

A workbench scene draws every assembly mode of a linkage: the same plan with other sign fields,
so the same searches (the input's arcs, the limit positions a circuit turns at) on numbers that
differ only in the signs. Each search costs a few dozen calls of the plan, and a call costs
about as much as a few hundred samples: searched as one batch, the modes cost little more than
one. Every step of the searches is elementwise, so each linkage's arcs and samples are the
numbers :func:`~linkwright.engine.circuits.input_arcs` and :func:`~linkwright.engine.circuits.
trace` find for it alone; they are kept where those look first (their memo), and a later call
for one linkage only places its joints.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arcs import InputArcs
from linkwright.engine.circuits import (
    ARCS_MEMO,
    SAMPLED_MEMO,
    SPACINGS,
    input_arcs,
    input_turns,
    sample_circuit,
    search_input_arcs,
)
from linkwright.engine.continuation import memo_key
from linkwright.engine.evaluate import batch_shape
from linkwright.engine.plan import Crank, Plan, SphereCrank

__all__ = ["share_arcs", "share_samples"]

Array = NDArray[np.float64]


def share_samples(
    plan: Plan,
    linkages: list[Mapping[str, ArrayLike]],
    samples: int,
    *,
    points: frozenset[str] = frozenset(),
    start: float = 0.0,
    spacing: str = "input",
) -> None:
    """Find the samples of every circuit of several single linkages of one plan in one batch,
    and keep each linkage's as :func:`~linkwright.engine.circuits.trace` would find them for it
    alone (every step of the search is elementwise, so they are the same numbers): a later
    trace of one of them then only places its joints. A workbench scene's assembly modes are
    such linkages: the limit searches, a few dozen calls of the plan each, are shared by them.

    Linkages whose numbers cannot be stacked (different names or shapes), or that are batches
    themselves, are left to be traced alone.
    """
    if samples < 2 or spacing not in SPACINGS:
        return
    stacked = _stacked(plan, linkages, points)
    if stacked is None:
        return
    share_arcs(plan, linkages, points=points)
    arcs = [input_arcs(plan, p, points=points) for p in linkages]
    periods = {float(np.asarray(a.period)) for a in arcs}
    if len(periods) != 1:
        return
    counts = [0 if bool(a.never) else 1 if bool(a.full) else int(a.count) for a in arcs]

    def key(p: Mapping[str, ArrayLike], k: int) -> Any:
        return memo_key(plan, p, points, "trace", samples, k, float(start), spacing)

    wanted = [
        k
        for k in range(max(counts))
        if any(
            k < c and not SAMPLED_MEMO.has(key(p, k)) for p, c in zip(linkages, counts, strict=True)
        )
    ]
    if not wanted:
        return
    # The batch's arcs are the linkages' own, padded to one width: nothing is searched twice.
    width = max(a.lo.shape[-1] for a in arcs)

    def pad(field: str, fill: float) -> NDArray[Any]:
        rows = [np.asarray(getattr(a, field)) for a in arcs]
        return np.stack([np.pad(r, (0, width - r.shape[-1]), constant_values=fill) for r in rows])

    ARCS_MEMO.put(
        memo_key(plan, stacked, points, "arcs", "auto"),
        InputArcs(
            np.stack([np.asarray(a.full) for a in arcs]),
            np.stack([np.asarray(a.never) for a in arcs]),
            pad("lo", np.nan),
            pad("hi", np.nan),
            pad("dyad_lo", -1),
            pad("dyad_hi", -1),
            periods.pop(),
        ),
    )
    for k in wanted:
        theta, branches, on = sample_circuit(plan, stacked, points, samples, k, start, spacing)
        for i, (p, c) in enumerate(zip(linkages, counts, strict=True)):
            if k < c:
                mine = None if on is None else {n: v[i] for n, v in on.items() if np.any(v[i])}
                SAMPLED_MEMO.put(
                    key(p, k),
                    (theta[i].copy(), {n: v[i].copy() for n, v in branches.items()}, mine or None),
                )


def _stacked(
    plan: Plan, linkages: list[Mapping[str, ArrayLike]], points: frozenset[str]
) -> dict[str, Array] | None:
    """Several single linkages of a plan (no triad) as one batch, or None where they are not."""
    if len(linkages) < 2 or plan.triads:
        return None
    names = set(linkages[0])
    if any(set(p) != names for p in linkages):
        return None
    try:
        values = {n: [np.asarray(p[n], dtype=float) for p in linkages] for n in names}
    except (TypeError, ValueError):
        return None
    if any(len({v.shape for v in vs}) != 1 for vs in values.values()):
        return None
    if any(batch_shape(p, points) != () for p in linkages):
        return None
    return {n: np.stack(vs) for n, vs in values.items()}


def share_arcs(
    plan: Plan, linkages: list[Mapping[str, ArrayLike]], *, points: frozenset[str] = frozenset()
) -> None:
    """The arcs of several single linkages of a plan of several dyads, searched in one batch
    and kept for each as :func:`~linkwright.engine.circuits.input_arcs` finds them alone: the
    same numbers (every step is elementwise), and the same width of padding (twice the arcs,
    as many changes as the grid saw; the arcs themselves where the crossings' merge rebuilt
    them; one where there are none). Geared linkages, and plans whose arcs have a closed form,
    are left alone: a crank geared fast has many arcs, whose cost the caller bounds before
    searching them."""
    if len(plan.dyads) < 2 or any(
        np.any(np.asarray(p[s.ratio] if isinstance(s.ratio, str) else s.ratio) != 1.0)
        for s in plan.steps
        if isinstance(s, Crank | SphereCrank)
        for p in linkages
    ):
        return
    keys = [memo_key(plan, p, points, "arcs", "auto") for p in linkages]
    if any(k is None for k in keys) or all(ARCS_MEMO.has(k) for k in keys):
        return
    stacked = _stacked(plan, linkages, points)
    if stacked is None:
        return
    turns = input_turns(plan, stacked, points=points)
    if np.any(turns != 1):
        return
    batched = search_input_arcs(plan, stacked, points, "auto")
    merged = np.asarray(crossings.candidates(plan, stacked, turns.shape).any(-1))
    for i, key in enumerate(keys):
        count = int(np.isfinite(batched.lo[i]).sum())
        if count == 0:
            width = 1
        elif merged[i]:
            width = count
        else:
            width = 2 * count
        ARCS_MEMO.put(
            key,
            InputArcs(
                np.asarray(batched.full[i]),
                np.asarray(batched.never[i]),
                batched.lo[i, :width].copy(),
                batched.hi[i, :width].copy(),
                batched.dyad_lo[i, :width].copy(),
                batched.dyad_hi[i, :width].copy(),
                float(np.asarray(batched.period)[i]),
            ),
        )

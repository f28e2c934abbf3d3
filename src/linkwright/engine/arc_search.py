"""The admissible input arcs of a batch: its period in input turns, and the arcs found once.

:func:`input_turns` says how many turns of the input a geared linkage takes to repeat (a
:class:`NoPeriod` where it never does); :func:`input_arcs` finds the arcs over that period, in
closed form or numerically (:mod:`~linkwright.engine.limit_search`), through continuation for a
triad (:mod:`~linkwright.engine.continuation`), and keeps them (``ARCS_MEMO``) for the next
caller with the same linkages.

Its own room (split from :mod:`linkwright.engine.circuits`): the one entry to the limit search
that every caller (the tracer, the server's budget, the analyses) goes through, apart from how
a limit is found and how a circuit is sampled.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import crossings
from linkwright.engine.arcs import TWO_PI, InputArcs
from linkwright.engine.continuation import Memo, circuit_arcs, memo_key
from linkwright.engine.evaluate import batch_shape
from linkwright.engine.limit_search import GRID, analytic_arcs, numeric_arcs, turns_with_input
from linkwright.engine.plan import Crank, Plan, SphereCrank

__all__ = [
    "ARCS_MEMO",
    "MAX_TURNS",
    "RATIO_TOL",
    "NoPeriod",
    "input_arcs",
    "input_turns",
    "search_input_arcs",
]

MAX_TURNS = 64
RATIO_TOL = 1e-9


class NoPeriod(ValueError):
    """A geared linkage whose motion never repeats (an irrational gear ratio): no circuit."""


def input_turns(
    plan: Plan, params: Mapping[str, ArrayLike], *, points: frozenset[str] = frozenset()
) -> NDArray[np.int64]:
    """How many turns of the input before every crank is back where it started.

    A crank geared at the ratio k turns k times per input turn, so the linkage repeats after the
    least q with k·q whole for every crank: q = 1 for integer ratios, 2 for 1.5 or −0.5, 3 for 2/3.

    Raises
    ------
    NoPeriod
        If some ratio is not a fraction with a denominator up to ``MAX_TURNS`` (to 1e-9): such
        a linkage never repeats, and there is no closed circuit to trace.

    Examples
    --------
    >>> from linkwright.engine import Crank, Fixed, Plan
    >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", 1.0, ratio="k")), traced=("A",))
    >>> input_turns(plan, {"O": [0.0, 0.0], "k": [1.0, -1.5, 2 / 3]}, points=frozenset({"O"}))
    array([1, 2, 3])
    """
    shape = batch_shape(params, points)
    ratios = []
    for step in plan.steps:
        if isinstance(step, Crank | SphereCrank):
            r = params[step.ratio] if isinstance(step.ratio, str) else step.ratio
            ratios.append(np.broadcast_to(np.asarray(r, dtype=float), shape))
    turns = np.zeros(shape, dtype=np.int64)
    for q in range(1, MAX_TURNS + 1):
        whole = np.ones(shape, dtype=bool)
        for r in ratios:
            x = r * q
            whole &= np.abs(x - np.round(x)) <= RATIO_TOL * np.maximum(1.0, np.abs(x))
        turns = np.where((turns == 0) & whole, q, turns)
        if np.all(turns > 0):
            return turns
    stuck = turns == 0
    for r in ratios:
        x = r[..., None] * np.arange(1, MAX_TURNS + 1)
        whole = np.abs(x - np.round(x)) <= RATIO_TOL * np.maximum(1.0, np.abs(x))
        alone = stuck & ~whole.any(-1)
        if alone.any():
            raise NoPeriod(
                f"gear ratio {float(r[alone].ravel()[0]):.12g} is not a fraction p/q with "
                f"q ≤ {MAX_TURNS}: the linkage never repeats, so it has no closed circuit "
                "(give a rational ratio, e.g. 1.5 for 3/2)"
            )
    raise NoPeriod(
        f"the gear ratios together repeat only after more than {MAX_TURNS} input turns: "
        "the linkage has no closed circuit to trace"
    )


def input_arcs(
    plan: Plan,
    params: Mapping[str, ArrayLike],
    *,
    points: frozenset[str] = frozenset(),
    method: str = "auto",
) -> InputArcs:
    """Admissible input arcs of each linkage in the batch, assembly as in ``params``.

    ``method`` is ``"analytic"`` (single dyad with a first-order trigonometric closure),
    ``"numeric"`` (grid bracketing and bisection, any plan) or ``"auto"`` (analytic where it
    applies). Tests compare the two. The arcs cover one period of the input
    (:func:`input_turns`): several turns for a linkage geared at a fractional ratio.
    """
    arcs = ARCS_MEMO.get(
        memo_key(plan, params, points, "arcs", method),
        lambda: search_input_arcs(plan, params, points, method),
    )
    # Kept arcs are shared: each caller gets arrays of its own.
    return InputArcs(
        np.copy(arcs.full),
        np.copy(arcs.never),
        np.copy(arcs.lo),
        np.copy(arcs.hi),
        np.copy(arcs.dyad_lo),
        np.copy(arcs.dyad_hi),
        period=np.copy(arcs.period) if isinstance(arcs.period, np.ndarray) else arcs.period,
    )


ARCS_MEMO = Memo()


def search_input_arcs(
    plan: Plan, params: Mapping[str, ArrayLike], points: frozenset[str], method: str
) -> InputArcs:
    dyads = plan.dyads
    turns = input_turns(plan, params, points=points)
    if plan.triads:
        # A triad's poses are followed from sample to sample, not held: the arcs of every
        # circuit of every configuration (one linkage at a time).
        arcs = circuit_arcs(
            plan,
            params,
            90,
            points=points,
            period=TWO_PI * float(np.max(turns)),
            shape=batch_shape(params, points),
        )
        return replace(arcs, period=TWO_PI * turns.astype(np.float64))
    if not dyads:
        shape = batch_shape(params, points)
        nanpad = np.full(shape + (1,), np.nan)
        neg = np.full(shape + (1,), -1)
        period = TWO_PI * turns.astype(np.float64)
        return InputArcs(
            np.ones(shape, bool),
            np.zeros(shape, bool),
            nanpad,
            nanpad,
            neg,
            neg,
            period if period.ndim else float(period),
        )
    analytic_ok = (
        plan.space == "plane"
        and len(dyads) == 1
        and all(turns_with_input(plan, p, params) for p in dyads[0].parents)
        and np.all(turns == 1)
    )
    if method == "analytic" and not analytic_ok:
        raise ValueError("this plan's limits have no closed form; use method='numeric'")
    if method == "analytic" or (method == "auto" and analytic_ok):
        return analytic_arcs(plan, params, points)
    arcs = numeric_arcs(plan, params, points, None, turns=turns)
    if len(dyads) > 1:  # a later dyad may fail past a crossing of an earlier one's sign
        arcs = crossings.merge_arcs(plan, params, points, arcs, GRID * int(turns.max()))
    return arcs

"""Exact extrema of a quantity along a circuit: dense bracketing, then refinement by sections.

A sampled maximum is off by O(h²) of the curvature; refining each bracket (by sections, or by
golden section where the quantity takes one point at a time) to the last bits makes the maxima
of paper 003's coefficients exact to ~1e-12 rather than to the grid (the paper's own spherical
values were evidently read off a 10° grid: see SEED-NOTES.md).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import Motion, evaluate
from linkwright.mechanisms.base import Mechanism, circuit

__all__ = ["CIRCUIT_SAMPLES", "circuit_extremum", "golden_max", "section_max"]

Array = NDArray[np.float64]
INV_PHI = (np.sqrt(5.0) - 1.0) / 2.0
GOLDEN_STEPS = 90
# Samples of the circuit that brackets every extremum before it is refined.
CIRCUIT_SAMPLES = 1024
SECTION_POINTS = 15
SECTION_ROUNDS = 22


def golden_max(
    f: Callable[[Array], Array], a: Array, b: Array, steps: int = GOLDEN_STEPS
) -> tuple[Array, Array]:
    """Maximise unimodal ``f`` on each bracket [a, b] (batched); returns (argmax, max).

    90 golden steps (the default) shrink any bracket below the spacing of doubles; fewer do
    where the answer needs less. The end points are kept as candidates so a maximum sitting on
    an end (a limit position) is found exactly.

    >>> x, fx = golden_max(lambda t: -(t - 0.3) ** 2, np.array([0.0]), np.array([1.0]))
    >>> float(np.round(x[0], 10)), float(fx[0])
    (0.3, -0.0)
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    lo, hi = a.copy(), b.copy()
    c = hi - INV_PHI * (hi - lo)
    d = lo + INV_PHI * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(steps):
        left = fc >= fd
        hi = np.where(left, d, hi)
        lo = np.where(left, lo, c)
        new_c = hi - INV_PHI * (hi - lo)
        new_d = lo + INV_PHI * (hi - lo)
        # Reuse the surviving interior point so each step costs one evaluation per side.
        c, d = np.where(left, new_c, d), np.where(left, c, new_d)
        probe = np.where(left, c, d)
        fp = f(probe)
        fc, fd = np.where(left, fp, fd), np.where(left, fc, fp)
    x = 0.5 * (lo + hi)
    candidates = np.stack((x, a, b))
    values = np.stack((f(x), f(a), f(b)))
    values = np.where(np.isfinite(values), values, -np.inf)
    best = np.argmax(values, axis=0)
    return (
        np.take_along_axis(candidates, best[None], 0)[0],
        np.take_along_axis(values, best[None], 0)[0],
    )


def section_max(
    f: Callable[[Array], Array],
    a: Array,
    b: Array,
    points: int = SECTION_POINTS,
    rounds: int = SECTION_ROUNDS,
) -> tuple[Array, Array]:
    """Maximise unimodal ``f`` on each bracket [a, b] (batched) by sections; returns (argmax,
    max), as :func:`golden_max` does.

    Each round evaluates ``points`` evenly spaced interior points in one call of ``f`` (on a
    new leading axis, which ``f`` must broadcast) and keeps the two intervals beside the best,
    so a bracket shrinks by 2/(points + 1) a round: 22 rounds of 15 points shrink it to 1e-20
    of its width, below the spacing of doubles as golden section's 90 steps do, in 22 calls
    rather than 92. Where each call is dear for its overhead (a plan evaluated a few samples
    at a time) that is several times faster. The end points are candidates too.

    >>> x, fx = section_max(lambda t: -(t - 0.3) ** 2, np.array([0.0]), np.array([1.0]))
    >>> float(np.round(x[0], 12)), float(fx[0])
    (0.3, -0.0)
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    lo, hi = a.copy(), b.copy()
    share = (np.arange(1, points + 1) / (points + 1)).reshape((points,) + (1,) * lo.ndim)
    for _ in range(rounds):
        width = hi - lo
        values = f(lo + share * width)
        best = np.argmax(np.where(np.isfinite(values), values, -np.inf), axis=0)
        lo, hi = lo + best / (points + 1) * width, lo + (best + 2) / (points + 1) * width
    x = 0.5 * (lo + hi)
    candidates = np.stack((x, a, b))
    values = f(candidates)
    values = np.where(np.isfinite(values), values, -np.inf)
    best = np.argmax(values, axis=0)
    return (
        np.take_along_axis(candidates, best[None], 0)[0],
        np.take_along_axis(values, best[None], 0)[0],
    )


def circuit_extremum(
    mechanism: Mechanism,
    quantity: Callable[[Motion], Array],
    *,
    sign: float = 1.0,
    samples: int = CIRCUIT_SAMPLES,
    motion: Motion | None = None,
) -> tuple[Array, Array, Array]:
    """The exact maximum of ``sign·quantity`` over each mechanism's whole circuit.

    ``quantity`` maps a :class:`Motion` of the mechanism to values with the motion's shape.
    ``motion`` is the mechanism's circuit (order 2) when the caller already has it; several
    extrema of one mechanism then share one tracing instead of each repeating it.
    Returns ``(value, input, branch)``: the extreme value of ``quantity`` (not multiplied by
    ``sign``), the input angle where it occurs and the dyad branch there. NaN where the linkage
    never assembles.
    """
    plan = mechanism.plan
    dyad = plan.dyads[0].name
    params = mechanism.params()
    points = mechanism.points
    if motion is None:
        motion = circuit(mechanism, samples)
    values = sign * quantity(motion)
    values = np.where(np.isfinite(values), values, -np.inf)
    n = motion.shape[-1]
    i = np.argmax(values, axis=-1)[..., None]
    theta = motion.input
    branch = motion.branches[dyad]

    def at(k: NDArray[np.int64]) -> tuple[Array, Array]:
        k = k % n
        return np.take_along_axis(theta, k, -1)[..., 0], np.take_along_axis(branch, k, -1)[..., 0]

    t_mid, b_mid = at(i)
    best_x, best_v, best_b = t_mid, np.take_along_axis(values, i, -1)[..., 0], b_mid
    # The maximum lies between the neighbouring samples; each half-bracket lies on one branch
    # (a branch change happens only at a limit, which is itself a sample), so refine both
    # halves, together: a leading axis of two, one evaluation per round for both.
    t_nb, b_nb = (np.stack(pair) for pair in zip(at(i - 1), at(i + 1), strict=True))
    # Across the seam of a full turn (last sample → sample 0) the neighbour is 2π away in
    # value but one step away in motion: take it continuously.
    t_nb = t_mid + np.remainder(t_nb - t_mid + np.pi, 2 * np.pi) - np.pi
    b_use = np.where(b_nb == b_mid, b_mid, b_nb)

    def f(x: Array) -> Array:
        m = evaluate(plan, params, x[..., None], points=points, branches={dyad: b_use[..., None]})
        return (sign * quantity(m))[..., 0]

    x, v = section_max(f, np.minimum(t_mid, t_nb), np.maximum(t_mid, t_nb))
    for side in range(2):
        better = v[side] > best_v
        best_x = np.where(better, x[side], best_x)
        best_v = np.where(better, v[side], best_v)
        best_b = np.where(better, b_use[side], best_b)
    nothing = ~np.isfinite(best_v)
    return (
        np.where(nothing, np.nan, sign * best_v),
        np.where(nothing, np.nan, best_x),
        np.where(nothing, np.nan, best_b),
    )

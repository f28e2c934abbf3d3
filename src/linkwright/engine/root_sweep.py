"""Every root of a scalar residual of one periodic parameter, on each branch, by a sweep.

:func:`sweep_roots` needs no polynomial: the caller's residual of one angle ψ (a
one-degree-of-freedom chain, its other joints placed on each branch by circle–circle
intersections, and the misfit of its last constraint) is sampled on a grid over the period,
its roots are bracketed (a sign change, a sample nearer zero than its neighbours, split by a
golden-section search, or the edge of the assembled range) and bisected to adjacent
floating-point numbers. It is slower than a closed form and is the cross-check and fallback of
the plane's triad (:func:`linkwright.engine.triad.triad_poses_sweep`) and of the spherical triad
(:mod:`linkwright.engine.sphere_triad`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "ResidualFn",
    "SweptRoots",
    "sweep_roots",
]

Array = NDArray[np.float64]


# ----------------------------------------------------------------------------------------------
# The sweep solver
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SweptRoots:
    """Roots of a residual over a periodic parameter, on each branch.

    Attributes
    ----------
    psi : ``(..., m)``, the roots in [lower, upper), sorted, NaN-padded; ``m`` is the largest
        count in the batch.
    branch : ``(..., m)``, the branch each root lies on (NaN in the padding).
    count : ``(...,)``, the number of roots found.
    """

    psi: Array
    branch: Array
    count: NDArray[np.int_]


ResidualFn = Callable[[Array, Array], Array]
"""``residual_fn(psi, branch) -> residual``: shapes ``batch + (m,)``, NaN where not assembled."""


def _bisect(
    same_as_lo: Callable[[Array], NDArray[np.bool_]], lo: Array, hi: Array
) -> tuple[Array, Array]:
    """Halve brackets ``[lo, hi]`` until lo and hi are adjacent floating-point numbers.

    ``same_as_lo(x)`` says, per bracket, whether x lies on lo's side (of a sign change, or of the
    edge of the assembled range). 64 halvings take any bracket within [−4π, 4π] down to
    rounding; the loop stops as soon as no bracket has a representable midpoint left.
    """
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        open_ = (mid != lo) & (mid != hi)
        if not open_.any():
            break
        same = same_as_lo(mid)
        lo = np.where(open_ & same, mid, lo)
        hi = np.where(open_ & ~same, mid, hi)
    return lo, hi


def _golden_min(fn: Callable[[Array], Array], lo: Array, hi: Array) -> tuple[Array, Array]:
    """Minimise ``fn`` on each bracket by golden-section search; returns (argmin, min).

    NaN counts as +inf. 48 steps shrink the bracket by 1e-10, below the sqrt(eps) to which a
    minimum can be located at all; the minimum's *value*, which is what is used, is then exact
    to rounding.
    """
    ratio = 0.5 * (np.sqrt(5.0) - 1.0)

    def f(x: Array) -> Array:
        v = fn(x)
        return np.where(np.isnan(v), np.inf, v)

    x1 = hi - ratio * (hi - lo)
    x2 = lo + ratio * (hi - lo)
    f1, f2 = f(x1), f(x2)
    for _ in range(48):
        left = f1 <= f2  # the minimum is in [lo, x2]
        lo, hi = np.where(left, lo, x1), np.where(left, x2, hi)
        new = np.where(left, hi - ratio * (hi - lo), lo + ratio * (hi - lo))
        f_new = f(new)
        x1, x2, f1, f2 = (
            np.where(left, new, x2),
            np.where(left, x1, new),
            np.where(left, f_new, f2),
            np.where(left, f1, f_new),
        )
    best = f1 <= f2
    return np.where(best, x1, x2), np.where(best, f1, f2)


def sweep_roots(
    residual_fn: ResidualFn,
    batch_shape: tuple[int, ...],
    *,
    branches: Sequence[float] = (1.0, -1.0),
    grid: int = 512,
    lower: float = -np.pi,
    upper: float = np.pi,
) -> SweptRoots:
    """All roots of a scalar residual of one periodic parameter ψ, on each branch, batched.

    The residual is sampled at ``grid`` equal steps of the period [lower, upper) for every
    branch, and every root is bracketed and then bisected to adjacent floating-point numbers
    (the endpoint with the smaller |residual| is reported). Brackets come from three places:

    * a sign change between two neighbouring samples;
    * a sample nearer zero than both neighbours with the same sign (a pair of roots closer than
      a step would hide there): golden-section search finds the extremum between the
      neighbours, and if the residual changes sign there, each side is a bracket;
    * the edge of the assembled range (the residual turns NaN between two samples): the edge is
      found by bisection too, and if the residual changes sign on the last piece up to it, that
      piece is a bracket. A root next to a limit position, where the branches meet, is thus
      found on exactly one of them.

    Missed are: three or more roots within two steps, a pair within a step of an edge that the
    extremum search does not separate, and assembled windows narrower than a step. Next to an
    edge that is a limit position, the residual grows like the square root of ψ's distance to
    it, so a root within about 1e-13 of it is resolved only to about 1e-8 of the residual's
    scale. This is the cross-check and fallback, not the primary solver; choose ``grid``
    accordingly.

    Parameters
    ----------
    residual_fn : ``residual_fn(psi, branch)`` with ``psi`` of shape ``batch_shape + (m,)`` and
        ``branch`` broadcastable to it; returns the residual (NaN where not assembled). It must
        have period ``upper − lower`` in ψ.
    batch_shape : the leading shape of the problems solved together.
    branches : the branch values passed to ``residual_fn``.
    grid : samples per branch and period.
    lower, upper : the period of ψ; roots are reported in [lower, upper).

    Examples
    --------
    The roots of cos 2ψ − 1/2 (one branch) are ±π/6 and ±5π/6:

    >>> found = sweep_roots(lambda psi, b: np.cos(2 * psi) - 0.5, (), branches=(1.0,))
    >>> int(found.count), np.degrees(found.psi).round(9)
    (4, array([-150.,  -30.,   30.,  150.]))

    Two pairs of roots 1e-6 apart, far inside one grid step, are still found (at 1 and
    1 + 1e-6, and half a period away):

    >>> pairs = lambda psi, b: np.sin(psi - 1.0) * np.sin(psi - 1.000001)
    >>> sweep_roots(pairs, (), branches=(1.0,)).psi.round(7)
    array([-2.1415927, -2.1415917,  1.       ,  1.000001 ])
    """
    period = upper - lower
    nb = len(branches)
    step = period / grid
    ticks = lower + step * np.arange(grid + 1, dtype=float)
    ticks[-1] = upper
    br = np.asarray(branches, dtype=float)
    size = int(np.prod(batch_shape, dtype=int))
    psi = np.broadcast_to(ticks[:-1], batch_shape + (nb, grid))
    psi_flat = psi.reshape(batch_shape + (nb * grid,))
    g = np.asarray(residual_fn(psi_flat, np.repeat(br, grid)), dtype=float)
    g = g.reshape((size, nb, grid))

    def call(prob: NDArray[np.int_], branch: Array, x: Array) -> Array:
        """The residual at one point per bracket, brackets gathered by problem index."""
        if prob.size == 0:
            return np.zeros(0)
        # residual_fn works on batch_shape + (m,): scatter the points into a dense (size, m)
        # block, one column per bracket of the same problem (NaN columns cost little).
        slot = _rank_within(prob)
        width = int(slot.max()) + 1
        dense = np.full((size, width), np.nan)
        dense_b = np.full((size, width), br[0])
        dense[prob, slot] = x
        dense_b[prob, slot] = branch
        out = residual_fn(
            dense.reshape(batch_shape + (width,)), dense_b.reshape(batch_shape + (width,))
        )
        return np.asarray(out, dtype=float).reshape(size, width)[prob, slot]

    # The sample after the last is the first, one period on: the residual at ``upper`` and at
    # ``lower`` may round to opposite signs, which would hide a root exactly at the seam.
    g_lo, g_hi = g, np.roll(g, -1, axis=-1)
    fin_lo, fin_hi = np.isfinite(g_lo), np.isfinite(g_hi)
    t_lo, t_hi = ticks[:-1], ticks[1:]

    # 1. Sign changes between finite neighbours (a zero sample counts on both sides: a root
    # exactly at a sample, or at the seam of the period where ψ = ±π round differently).
    with np.errstate(invalid="ignore"):
        change = fin_lo & fin_hi & (g_lo * g_hi <= 0)
    p1, b1, i1 = np.nonzero(change)
    brackets: list[tuple[NDArray[Any], ...]] = [
        (p1, b1, t_lo[i1], t_hi[i1], _lo_side(g_lo[p1, b1, i1], g_hi[p1, b1, i1]))
    ]

    # 2. Samples nearer zero than both (periodic) neighbours, all of one sign.
    mid_g, prev_g, next_g = g, np.roll(g, 1, axis=-1), g_hi
    with np.errstate(invalid="ignore"):
        dip = (
            np.isfinite(prev_g)
            & np.isfinite(mid_g)
            & np.isfinite(next_g)
            & ((prev_g > 0) == (mid_g > 0))
            & ((next_g > 0) == (mid_g > 0))
            & (np.abs(mid_g) <= np.abs(prev_g))
            & (np.abs(mid_g) <= np.abs(next_g))
            & (mid_g != 0)
        )
    p3, b3, i3 = np.nonzero(dip)
    sgn3 = np.sign(mid_g[p3, b3, i3])
    bval3 = br[b3]
    at, value = _golden_min(lambda x: sgn3 * call(p3, bval3, x), t_lo[i3] - step, t_lo[i3] + step)
    hidden = value <= 0
    p3, b3, at, sgn3 = p3[hidden], b3[hidden], at[hidden], sgn3[hidden]
    lo3 = t_lo[i3[hidden]] - step
    hi3 = t_lo[i3[hidden]] + step
    brackets.append((p3, b3, lo3, at, sgn3))
    brackets.append((p3, b3, at, hi3, -sgn3))

    # 3. Edges of the assembled range: bisect on finiteness to the last assembled point.
    p2, b2, i2 = np.nonzero(fin_lo != fin_hi)
    from_lo = fin_lo[p2, b2, i2]
    inside = np.where(from_lo, t_lo[i2], t_hi[i2])
    outside = np.where(from_lo, t_hi[i2], t_lo[i2])
    g_in = np.where(from_lo, g_lo[p2, b2, i2], g_hi[p2, b2, i2])
    bval2 = br[b2]
    edge, _ = _bisect(lambda x: np.isfinite(call(p2, bval2, x)), inside, outside)
    g_edge = call(p2, bval2, edge)
    with np.errstate(invalid="ignore"):
        piece = np.isfinite(g_edge) & (g_in * g_edge <= 0)
    brackets.append(
        (p2[piece], b2[piece], inside[piece], edge[piece], _lo_side(g_in[piece], g_edge[piece]))
    )
    # Without a sign change the last piece may still hide a pair (the residual changes fastest
    # next to a limit position): search its extremum towards zero as in 2.
    rest = np.isfinite(g_edge) & ~piece & (g_in != 0)
    p4, b4, in4, edge4 = p2[rest], b2[rest], inside[rest], edge[rest]
    sgn4, bval4 = np.sign(g_in[rest]), bval2[rest]
    at4, value4 = _golden_min(
        lambda x: sgn4 * call(p4, bval4, x), np.minimum(in4, edge4), np.maximum(in4, edge4)
    )
    hidden = value4 <= 0
    p4, b4, in4, edge4, at4, sgn4 = (x[hidden] for x in (p4, b4, in4, edge4, at4, sgn4))
    brackets.append((p4, b4, in4, at4, sgn4))
    brackets.append((p4, b4, at4, edge4, -sgn4))

    prob = np.concatenate([x[0] for x in brackets])
    bidx = np.concatenate([x[1] for x in brackets])
    lo = np.concatenate([x[2] for x in brackets])
    hi = np.concatenate([x[3] for x in brackets])
    positive = np.concatenate([x[4] for x in brackets]) > 0  # the sign on lo's side
    bval = br[bidx]
    lo, hi = _bisect(lambda x: (call(prob, bval, x) > 0) == positive, lo, hi)
    f_lo, f_hi = np.abs(call(prob, bval, lo)), np.abs(call(prob, bval, hi))
    root = np.where(f_hi < f_lo, hi, lo)
    # Brackets of step 2 may cross the period's end; only those roots are moved into it (an
    # unconditional modulo would round every root to the ulp of ``upper``: at a limit position
    # the residual is a square root of ψ's distance to the edge, and that ulp matters).
    root = np.where(root < lower, root + period, np.where(root >= upper, root - period, root))

    prob, root, bval = _unique_roots(prob, bval, root, lower, upper)
    count = np.bincount(prob, minlength=size)
    width = int(count.max()) if size else 0
    slot = _rank_within(prob)
    psi_out = np.full((size, width), np.nan)
    br_out = np.full((size, width), np.nan)
    psi_out[prob, slot] = root
    br_out[prob, slot] = bval
    return SweptRoots(
        psi=psi_out.reshape(batch_shape + (width,)),
        branch=br_out.reshape(batch_shape + (width,)),
        count=count.reshape(batch_shape),
    )


def _lo_side(g_lo: Array, g_hi: Array) -> Array:
    """The sign a bracket's bisection keeps on its lo side: g_lo's, or if that is 0, −g_hi's."""
    return np.where(g_lo != 0, np.sign(g_lo), -np.sign(g_hi))


def _unique_roots(
    prob: NDArray[np.int_], branch: Array, root: Array, lower: float, upper: float
) -> tuple[NDArray[np.int_], Array, Array]:
    """Drop repeated roots (same problem and branch, a few ulps apart, also across the seam).

    A root at a sample, or at an edge where the branches meet, may be bracketed twice; one
    at the seam appears near ``lower`` and near ``upper``. Returns (problem, ψ, branch), sorted
    by problem, ψ and branch.
    """
    tol = 8.0 * np.finfo(float).eps * max(abs(lower), abs(upper), 1.0)
    order = np.lexsort((root, branch, prob))
    prob, branch, root = prob[order], branch[order], root[order]
    same_group = np.r_[False, (prob[1:] == prob[:-1]) & (branch[1:] == branch[:-1])]
    repeat = same_group & (np.diff(root, prepend=-np.inf) <= tol)
    # Across the seam: a group's last root near ``upper`` and its first near ``lower``.
    last = np.r_[~same_group[1:], True]
    first_of = np.maximum.accumulate(np.where(~same_group, np.arange(prob.size), 0))
    repeat |= (
        last
        & (first_of != np.arange(prob.size))
        & ((upper - root) + (root[first_of] - lower) <= tol)
    )
    keep = ~repeat
    prob, branch, root = prob[keep], branch[keep], root[keep]
    order = np.lexsort((branch, root, prob))
    return prob[order], root[order], branch[order]


def _rank_within(groups: NDArray[np.int_]) -> NDArray[np.int_]:
    """For a sorted-or-not array of group ids, each entry's index among equal ids (stable)."""
    if groups.size == 0:
        return np.zeros(0, dtype=int)
    order = np.argsort(groups, kind="stable")
    sorted_groups = groups[order]
    starts = np.r_[0, np.flatnonzero(np.diff(sorted_groups)) + 1]
    run_start = np.repeat(starts, np.diff(np.r_[starts, sorted_groups.size]))
    rank = np.empty_like(groups)
    rank[order] = np.arange(groups.size) - run_start
    return rank

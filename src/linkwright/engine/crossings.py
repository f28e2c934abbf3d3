"""Exact change points where a dyad's parents meet, and how a circuit passes through them.

A dyad's branch is the geometric sign of DESIGN.md: sign((P2 − P1) × (P − P1)) in the plane,
sign((P1 × P2)·P) on the sphere. Where its parents meet at an input θc (in the plane P1 = P2;
on the sphere P1 = ±P2) with link lengths that allow it (r1 = r2; for antipodal parents on the
sphere r1 + r2 = π), the dyad closes with its joint anywhere on one circle: an exact kite or
deltoid four-bar with A passing through B0. The parents' *gap* D (P2 − P1 in the plane, P1 × P2
on the sphere) passes through zero there and reverses, while the joint of a linkage running
through θc moves on smoothly, on the analytic branch, at right angles to the gap's direction
of travel. So the branch sign flips at θc, and a trace holding the sign would jump to the other
branch there (by 75 % of an exact kite's curve). These *crossings* are where
:func:`~linkwright.engine.circuits.trace` switches the dyad's sign without reversing the input;
a sample exactly on one is placed as the limit of its neighbours
(``crossings=`` of :func:`~linkwright.engine.evaluate.evaluate`).

They are found exactly. Where the dyad's parents turn one-for-one with the input (circuits'
analytic case) the gap is ``big + arm·e^{iθ}`` (complex), which touches zero when |big| = |arm|,
at θc = arg(big) − arg(arm) + π. Otherwise the gap is sampled on a grid of the input: a cell
whose chord D_a → D_b passes the origin within its own length is a candidate, refined by
bisecting the sign of the gap's component along that chord down to adjacent inputs, and kept
where the gap is zero there to the rounding of the parents' positions
(``CROSSING_ULPS``·ε·(|P1| + |P2|)). Only dyads whose lengths allow a meeting
(``RADII_TOL``) are looked at, so linkages without one pay nothing.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.arcs import InputArcs
from linkwright.engine.evaluate import place_all
from linkwright.engine.plan import DyadRRP, DyadRRR, JointState, Param, Plan, SphereDyad
from linkwright.geometry import plane, sphere

__all__ = [
    "CROSSING_ULPS",
    "LIMIT",
    "PLAIN",
    "RADII_TOL",
    "analytic_crossings",
    "candidates",
    "crossings_in_period",
    "crossings_within",
    "cut_single",
    "flags",
    "meets",
    "merge_arcs",
    "scatter",
    "split_single",
    "starts_on",
    "take_rows",
    "warp",
    "warp_codes",
]

Array = NDArray[np.float64]
Ints = NDArray[np.int64]
Flags = NDArray[np.bool_]
Params = Mapping[str, ArrayLike]
Dyad = DyadRRR | DyadRRP | SphereDyad
Segments = tuple[Array, Array, dict[str, Array], Ints, Ints]
"""A circuit's segments: starts, ends, branches, and what each begins and ends at."""
Turning = Callable[[Plan, str, Params], tuple[Array, Array]]
"""A parent joint as ``O + w·e^{iθ}`` (complex ``O`` and ``w``), see circuits' analytic case."""
EPS = float(np.finfo(float).eps)
TWO_PI = 2.0 * np.pi

# The gap at a crossing, in units of ε·(|P1| + |P2|), the rounding of the parents' positions. A
# gap this small cannot be told from zero. Four-bars kept 1e-12 of their size from a deltoid
# (the recipes of tests/singular_helpers.py) miss by 15 and more of these units (the least of
# 200,000 drawn), and swing through half a turn there instead of crossing.
CROSSING_ULPS = 4.0
# How nearly the links must allow the meeting (r1 = r2, or r1 + r2 = π on the sphere), relative
# to r1 + r2 in the plane and in radians on the sphere: a document's equal lengths (or arcs in
# degrees summing to 180) pass, anything a user could mean as different does not.
RADII_TOL = 1e-12
# A crossing this close to where a search starts (radians) is the one just passed.
EXCLUDE = 1e-10
BISECTIONS = 64
# Segment ends (see :func:`split_single`): a plain end, a limit position, or ≥ 0: a crossing of
# that dyad (its index in ``plan.dyads``).
PLAIN, LIMIT = -2, -1


def _value(p: Param, params: Params) -> Array:
    return np.asarray(params[p] if isinstance(p, str) else p, dtype=float)


def _radii_allow(dyad: Dyad, params: Params) -> tuple[Flags, Flags]:
    """Whether the dyad's lengths allow its parents to meet: (coinciding, antipodal)."""
    if not isinstance(dyad, DyadRRR | SphereDyad):
        no = np.zeros((), dtype=bool)
        return no, no
    r1, r2 = _value(dyad.r1, params), _value(dyad.r2, params)
    if isinstance(dyad, SphereDyad):
        return np.abs(r1 - r2) <= RADII_TOL, np.abs(r1 + r2 - np.pi) <= RADII_TOL
    return np.abs(r1 - r2) <= RADII_TOL * (r1 + r2), np.zeros((), dtype=bool)


def candidates(plan: Plan, params: Params, shape: tuple[int, ...]) -> NDArray[np.bool_]:
    """``shape + (dyads,)``: which dyads of which linkages could meet their parents at all."""
    out = np.zeros(shape + (len(plan.dyads),), dtype=bool)
    for i, d in enumerate(plan.dyads):
        same, opposite = _radii_allow(d, params)
        out[..., i] = np.broadcast_to(same | opposite, shape)
    return out


def _gap(
    dyad: DyadRRR | SphereDyad, states: Mapping[str, JointState]
) -> tuple[Array, Array, Array]:
    """The gap D of the dyad's parents, its rounding, and P1·P2 (coincide > 0 > antipodal)."""
    p1, p2 = states[dyad.p1].pos, states[dyad.p2].pos
    if isinstance(dyad, SphereDyad):
        gap, dot = sphere.cross(p1, p2), sphere.dot(p1, p2)
        noise = EPS * (sphere.norm(p1) + sphere.norm(p2))
    else:
        gap, dot = p2 - p1, np.ones(p1.shape[:-1])
        noise = EPS * (plane.norm(p1) + plane.norm(p2))
    return gap, noise, dot


def _closes_there(
    dyad: Dyad, params: Params, dot: Array, samples: bool = True
) -> NDArray[np.bool_]:
    """Whether the links allow the parents' meeting: equal for coinciding parents, summing to
    π for antipodal ones. ``dot`` has the batch shape, plus a samples axis if ``samples``."""
    same, opposite = _radii_allow(dyad, params)
    if samples:
        same, opposite = (np.asarray(x)[..., None] if np.ndim(x) else x for x in (same, opposite))
    shape = np.shape(dot)
    return np.where(dot >= 0.0, np.broadcast_to(same, shape), np.broadcast_to(opposite, shape))


def meets(dyad: Dyad, states: Mapping[str, JointState], params: Params) -> NDArray[np.bool_]:
    """Where the dyad's parents meet (to rounding) and its links allow it: the dyad closes
    there with its joint anywhere on one circle, although its own formula is undefined."""
    same, opposite = _radii_allow(dyad, params)
    if isinstance(dyad, DyadRRP) or not (np.any(same) or np.any(opposite)):
        return np.zeros(np.shape(states[dyad.p1].pos)[:-1], dtype=bool)
    gap, noise, dot = _gap(dyad, states)
    small = np.sqrt(np.sum(gap * gap, axis=-1)) <= CROSSING_ULPS * noise
    both = states[dyad.p1].valid & states[dyad.p2].valid
    met: NDArray[np.bool_] = small & _closes_there(dyad, params, dot) & both
    return met


def analytic_crossings(plan: Plan, params: Params, turning: Turning) -> Array:
    """The crossing input of the one dyad of a plan whose parents turn with the input (batch
    shape, NaN where its parents never meet): θc = arg(big) − arg(arm) + π where |big| = |arm|.

    ``turning(plan, name, params)`` gives a parent as ``O + w·e^{iθ}`` (circuits' analytic
    case).
    """
    (dyad,) = plan.dyads
    if isinstance(dyad, DyadRRP):
        raise TypeError(f"dyad {dyad.name} runs on a guide: its parents never meet")
    o1, w1 = turning(plan, dyad.p1, params)
    o2, w2 = turning(plan, dyad.p2, params)
    big, arm = o2 - o1, w2 - w1
    a, b = np.abs(big), np.abs(arm)
    noise = EPS * (np.abs(o1) + np.abs(w1) + np.abs(o2) + np.abs(w2))
    same, _ = _radii_allow(dyad, params)
    hit = (np.abs(a - b) <= CROSSING_ULPS * noise) & (b > 0) & same
    theta = np.angle(big) - np.angle(arm) + np.pi
    return np.where(hit, np.remainder(theta + np.pi, TWO_PI) - np.pi, np.nan)


def take_rows(
    params: Params, points: frozenset[str], shape: tuple[int, ...], rows: NDArray[np.intp]
) -> dict[str, Array]:
    """The parameters of the linkages ``rows`` (indices into the flattened batch)."""
    out: dict[str, Array] = {}
    for key, value in params.items():
        a = np.asarray(value, dtype=float)
        tail = a.shape[-1:] if key in points else ()
        out[key] = np.broadcast_to(a, shape + tail).reshape((-1,) + tail)[rows]
    return out


def crossings_within(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    start: Array,
    stop: Array,
    cells: int,
    branches: Mapping[str, Array] | None = None,
    chunk: int = 240,
) -> tuple[Array, NDArray[np.int64]]:
    """Every crossing with ``start`` < θ ≤ ``stop`` (or ``stop`` ≤ θ < ``start``), in order.

    ``start``/``stop`` have the batch shape (NaN: nothing to search); the span is cut into
    ``cells`` grid cells. ``branches`` (dyad name → batch-shaped signs) are held along the span.
    Returns the crossings ``batch + (K,)`` in the order met going from start to stop, and the
    index (into ``plan.dyads``) of the dyad each belongs to; NaN and −1 pad.
    """
    shape = np.shape(start)
    size = int(np.prod(shape, dtype=np.int64))
    allow = candidates(plan, params, shape).reshape(size, -1)
    a = np.asarray(start, dtype=float).reshape(size)
    b = np.asarray(stop, dtype=float).reshape(size)
    todo = np.flatnonzero(allow.any(-1) & np.isfinite(a) & np.isfinite(b) & (a != b))
    found_t: list[Array] = []
    found_k: list[NDArray[np.int64]] = []
    found_row: list[NDArray[np.int64]] = []
    if todo.size:
        sub = take_rows(params, points, shape, todo)
        br = {
            k: np.broadcast_to(np.asarray(v, float), shape).reshape(size)[todo][:, None]
            for k, v in (branches or {}).items()
        }
        t, k, r = _scan(plan, sub, points, a[todo], b[todo], cells, br, allow[todo], chunk)
        found_t, found_k, found_row = [t], [k], [todo[r]]
    return _pad(found_t, found_k, found_row, a, shape)


def crossings_in_period(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    usable: Flags,
    period: Array,
    cells: int,
    branches: Mapping[str, Array] | None,
) -> Array:
    """Every crossing over one period of the input, in [−π, −π + period), ``batch + (K,)``
    (NaN-padded), each once: the scan runs a little past the period's end, so that one at
    its very start (where a search starts, and excludes) is still found."""
    shape = np.shape(usable)
    lo = np.where(usable, -np.pi, np.nan)
    over = 2.0 * period / cells
    at, _ = crossings_within(plan, params, points, lo, lo + period + over, cells + 2, branches)
    t = period[..., None] if np.ndim(period) else period
    at = np.remainder(at + np.pi, t) - np.pi
    at = np.sort(at, axis=-1)  # NaN last
    dup = np.zeros(at.shape, dtype=bool)
    dup[..., 1:] = np.abs(np.diff(at, axis=-1)) <= EXCLUDE
    first, last = at[..., :1], np.nanmax(np.where(np.isfinite(at), at, -np.inf), -1)[..., None]
    dup |= (np.abs(at - first - t) <= EXCLUDE) & (at == last) & (at.shape[-1] > 1)
    at = np.sort(np.where(dup, np.nan, at), axis=-1)
    return at.reshape(shape + at.shape[-1:])


def _pad(
    found_t: list[Array],
    found_k: list[Ints],
    found_row: list[Ints],
    a: Array,
    shape: tuple[int, ...],
) -> tuple[Array, Ints]:
    size = a.size
    t = np.concatenate(found_t) if found_t else np.zeros(0)
    k = np.concatenate(found_k) if found_k else np.zeros(0, dtype=np.int64)
    row = np.concatenate(found_row) if found_row else np.zeros(0, dtype=np.int64)
    order = np.lexsort((np.abs(t - a[row]), row))
    t, k, row = t[order], k[order], row[order]
    count = np.bincount(row, minlength=size)
    width = max(int(count.max()) if count.size else 0, 1)
    out_t = np.full((size, width), np.nan)
    out_k = np.full((size, width), -1, dtype=np.int64)
    first = np.concatenate(([0], np.cumsum(count)[:-1]))
    slot = np.arange(row.size) - first[row]
    out_t[row, slot] = t
    out_k[row, slot] = k
    return out_t.reshape(shape + (width,)), out_k.reshape(shape + (width,))


def _gaps_at(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    theta: Array,
    branches: Mapping[str, Array],
    allow: Flags,
) -> list[tuple[Array, Array, Array] | None]:
    """Each allowed dyad's gap, rounding and P1·P2 at inputs ``theta`` (rows × nodes)."""
    _, states = place_all(plan, params, theta, points=points, branches=branches, order=0)
    out: list[tuple[Array, Array, Array] | None] = []
    for i, d in enumerate(plan.dyads):
        # A slider dyad is never allowed (its parents cannot meet).
        if isinstance(d, DyadRRP) or not allow[:, i].any():
            out.append(None)
            continue
        gap, noise, dot = _gap(d, states)
        ok = states[d.p1].valid & states[d.p2].valid
        out.append((np.where(ok[..., None], gap, np.nan), noise, dot))
    return out


def _scan(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    a: Array,
    b: Array,
    cells: int,
    branches: Mapping[str, Array],
    allow: Flags,
    chunk: int,
) -> tuple[Array, Ints, Ints]:
    """:func:`crossings_within` for rows ``(m,)``: the crossings found, their dyads and rows."""
    step = (b - a) / cells
    cand_row: list[Ints] = []
    cand_k: list[Ints] = []
    cand_lo: list[Array] = []
    cand_hi: list[Array] = []
    cand_u: list[Array] = []
    prev: tuple[list[Array | None], Array] | None = None
    for c0 in range(0, cells + 1, chunk):
        j = np.arange(c0, min(c0 + chunk, cells + 1))
        theta = a[:, None] + step[:, None] * j
        theta[:, j == cells] = b[:, None]  # the far end exactly, not a + cells·step
        gaps = _gaps_at(plan, params, points, theta, branches, allow)
        for i, g in enumerate(gaps):
            if g is None:
                continue
            gap, noise, _ = g
            # A node on a crossing to rounding is one (its gap's sign there is noise, so the
            # cells on either side may both miss it); it is taken as a cell of zero width.
            on = np.sqrt(np.sum(gap * gap, -1)) <= CROSSING_ULPS * noise
            on &= allow[:, i : i + 1] & (np.abs(theta - a[:, None]) > EXCLUDE)
            r, c = np.nonzero(on)
            cand_row.append(r)
            cand_k.append(np.full(r.size, i))
            cand_lo.append(theta[r, c])
            cand_hi.append(theta[r, c])
            cand_u.append(np.ones((r.size, gap.shape[-1])))
            th = theta
            if prev is not None:
                last = prev[0][i]
                assert last is not None  # the same dyads are allowed in every chunk
                gap = np.concatenate((last[:, None], gap), axis=1)
                th = np.concatenate((prev[1][:, None], theta), axis=1)
            d0, d1 = gap[:, :-1], gap[:, 1:]
            u = d1 - d0
            f0, f1 = np.sum(d0 * u, -1), np.sum(d1 * u, -1)
            uu = np.sum(u * u, -1)
            with np.errstate(invalid="ignore", divide="ignore"):
                near = d0 - (f0 / uu)[..., None] * u  # the chord's closest point to the origin
                close = np.sum(near * near, -1) <= uu
            hit = (f0 < 0.0) & (f1 >= 0.0) & close & allow[:, i : i + 1]
            hit &= np.abs(th[:, 1:] - a[:, None]) > EXCLUDE
            r, c = np.nonzero(hit)
            cand_row.append(r)
            cand_k.append(np.full(r.size, i))
            cand_lo.append(th[r, c])
            cand_hi.append(th[r, c + 1])
            cand_u.append(u[r, c])
        prev = ([None if g is None else g[0][:, -1] for g in gaps], theta[:, -1])
    if not cand_row or not np.concatenate(cand_row).size:
        return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    row = np.concatenate(cand_row)
    k = np.concatenate(cand_k)
    lo, hi = np.concatenate(cand_lo), np.concatenate(cand_hi)
    u = np.concatenate([x.reshape(-1, x.shape[-1]) for x in cand_u if x.size])
    theta, ok = _refine(plan, params, points, row, k, lo, hi, u, branches)
    ok &= np.abs(theta - a[row]) > EXCLUDE  # the crossing the search starts on
    theta, k, row = theta[ok], k[ok], row[ok]
    # One crossing found from a node and from a cell beside it is one.
    order = np.lexsort((theta, k, row))
    theta, k, row = theta[order], k[order], row[order]
    same = (row[1:] == row[:-1]) & (k[1:] == k[:-1]) & (np.diff(theta) <= EXCLUDE)
    keep = np.concatenate((np.ones(min(theta.size, 1), dtype=bool), ~same))
    return theta[keep], k[keep], row[keep]


def _refine(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    row: Ints,
    k: Ints,
    lo: Array,
    hi: Array,
    u: Array,
    branches: Mapping[str, Array],
) -> tuple[Array, Flags]:
    """Bisect each candidate cell on the sign of the gap's component along its chord ``u``.

    ``lo`` is the end where that component is negative. Returns the input with the smaller gap
    of the final bracket, and whether the gap there is zero to rounding with lengths allowing it.
    """
    rows_params = {key: np.asarray(v, dtype=float)[row] for key, v in params.items()}
    br = {key: v[row] for key, v in branches.items()}
    dyads = plan.dyads
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        inside = (mid - lo) * (hi - mid) > 0.0
        if not inside.any():
            break
        gap = _gap_of(plan, rows_params, points, mid, br, k)[0]
        neg = np.sum(gap * u, -1) < 0.0
        lo = np.where(inside & neg, mid, lo)
        hi = np.where(inside & ~neg, mid, hi)
    g_lo, noise_lo, dot_lo = _gap_of(plan, rows_params, points, lo, br, k)
    g_hi, noise_hi, dot_hi = _gap_of(plan, rows_params, points, hi, br, k)
    n_lo = np.sqrt(np.sum(g_lo * g_lo, -1))
    n_hi = np.sqrt(np.sum(g_hi * g_hi, -1))
    use_hi = ~(n_lo < n_hi)
    theta = np.where(use_hi, hi, lo)
    size = np.where(use_hi, n_hi, n_lo)
    noise = np.where(use_hi, noise_hi, noise_lo)
    dot = np.where(use_hi, dot_hi, dot_lo)
    allowed = np.zeros(row.size, dtype=bool)
    for i, d in enumerate(dyads):
        sel = k == i
        if sel.any():
            one = {key: v[sel] for key, v in rows_params.items()}
            allowed[sel] = _closes_there(d, one, dot[sel], samples=False)
    return theta, (size <= CROSSING_ULPS * noise) & allowed


def _gap_of(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    theta: Array,
    branches: Mapping[str, Array],
    which: Ints,
) -> tuple[Array, Array, Array]:
    """The gap of dyad ``which[i]`` at ``theta[i]`` for each row i (rows are linkages)."""
    _, states = place_all(plan, params, theta[:, None], points=points, branches=branches, order=0)
    dim = 3 if plan.space == "sphere" else 2
    gap = np.full((theta.size, dim), np.nan)
    noise = np.full(theta.size, np.nan)
    dot = np.full(theta.size, np.nan)
    for i, d in enumerate(plan.dyads):
        sel = which == i
        if isinstance(d, DyadRRP) or not sel.any():
            continue
        g, n, p = _gap(d, states)
        gap[sel], noise[sel], dot[sel] = g[sel, 0], n[sel, 0], p[sel, 0]
    return gap, noise, dot


def merge_arcs(
    plan: Plan, params: Params, points: frozenset[str], arcs: InputArcs, cells: int
) -> InputArcs:
    """Input arcs (``InputArcs``) with the arcs that meet at a crossing joined into one.

    Arcs are found with every dyad's sign held; where a dyad's parents meet, the sign held
    past the meeting is the other branch's, on which a later dyad may not close at all. The
    assembled set then stops at the crossing on either side, a boundary that is no limit:
    the machine runs through it. Such arcs are one (and an arc that meets itself a period on
    is a full turn).
    """
    shape = np.shape(arcs.full)
    if not candidates(plan, params, shape).any() or not np.isfinite(arcs.lo).any():
        return arcs
    period = np.broadcast_to(np.asarray(arcs.period, dtype=float), shape)
    doc = {
        d.name: np.broadcast_to(_value(d.branch, params), shape)
        for d in plan.dyads
        if isinstance(d.branch, str) and d.branch in params
    }
    cross = crossings_in_period(
        plan, params, points, np.isfinite(arcs.lo[..., 0]), period, cells, doc
    )
    size = int(np.prod(shape, dtype=np.int64))
    full: Flags = np.array(np.broadcast_to(arcs.full, shape)).reshape(size)
    flat = [np.array(a).reshape(size, -1) for a in (arcs.lo, arcs.hi, arcs.dyad_lo, arcs.dyad_hi)]
    cross = cross.reshape(size, -1)
    rows: list[list[list[Any]]] = []
    per = period.reshape(size)
    for i in range(size):
        keep = np.isfinite(flat[0][i])
        ends = [list(a[i][keep]) for a in flat]
        cs = cross[i][np.isfinite(cross[i])]
        if cs.size and ends[0]:
            full[i] |= _join(ends, cs, per[i])
        rows.append(ends)
    width = max(max(len(r[0]) for r in rows), 1)
    out: list[NDArray[Any]] = [np.full((size, width), np.nan) for _ in range(2)]
    out += [np.full((size, width), -1, dtype=np.int64) for _ in range(2)]
    for i, r in enumerate(rows):
        order = np.argsort(r[0])
        for j in range(4):
            out[j][i, : len(order)] = np.asarray(r[j])[order]
    lo, hi, dyad_lo, dyad_hi = (a.reshape(shape + (width,)) for a in out)
    full = full.reshape(shape)
    nan = np.where(full[..., None], np.nan, 0.0)
    return replace(
        arcs,
        full=full,
        lo=lo + nan,
        hi=hi + nan,
        dyad_lo=np.where(full[..., None], -1, dyad_lo),
        dyad_hi=np.where(full[..., None], -1, dyad_hi),
    )


def _join(ends: list[list[Any]], cs: Array, period: float) -> bool:
    """Join, in place, the arcs ``ends`` = [lo, hi, dyad_lo, dyad_hi] (lists, sorted by lo)
    that meet at a crossing in ``cs``; True if one arc then covers the whole period."""

    def at_crossing(x: float) -> bool:
        gap = np.remainder(cs - x + 0.5 * period, period) - 0.5 * period
        return bool(np.any(np.abs(gap) <= 1e-9 * period))

    lo, hi, _, dhi = ends
    i = 0
    while len(lo) > 1 and i < len(lo):
        j = (i + 1) % len(lo)
        nxt = lo[j] + (period if j == 0 else 0.0)
        if abs(nxt - hi[i]) <= 1e-9 * period and at_crossing(hi[i]):
            hi[i], dhi[i] = hi[j] + (period if j == 0 else 0.0), dhi[j]
            for a in ends:
                del a[j]
            i = 0 if j == 0 else i
            continue
        i += 1
    one = len(lo) == 1 and abs(lo[0] + period - hi[0]) <= 1e-9 * period and at_crossing(hi[0])
    return one


def scatter(full: Segments, part: Segments, mask: Flags) -> Segments:
    """Put ``part``'s segments (the linkages in ``mask``) into ``full``'s, widened as needed.

    Segments are (starts, ends, branches, what each begins at, what each ends at).
    """
    (s0, e0, b0, g0, h0), (s1, e1, b1, g1, h1) = full, part
    width = max(s0.shape[-1], s1.shape[-1])

    def widen(a: NDArray[Any], fill: float = np.nan) -> NDArray[Any]:
        pad = width - a.shape[-1]
        return np.concatenate((a, np.full(a.shape[:-1] + (pad,), fill, a.dtype)), -1) if pad else a

    s0, e0, s1, e1 = (widen(a).copy() for a in (s0, e0, s1, e1))
    g0, h0, g1, h1 = (widen(a, PLAIN).copy() for a in (g0, h0, g1, h1))
    s0[mask], e0[mask], g0[mask], h0[mask] = s1, e1, g1, h1
    branches: dict[str, Array] = {}
    for k in b0:
        b = widen(b0[k]).copy()
        b[mask] = widen(b1[k])
        branches[k] = b
    return s0, e0, branches, g0, h0


def cut_single(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    segs: Segments,
    arcs: InputArcs,
    usable: Flags,
    doc: Mapping[str, Array],
    grid: int,
    turning: Turning | None = None,
) -> Segments:
    """A one-dyad circuit's segments ``segs`` (see :func:`scatter`) cut at its crossings.

    They do not depend on the dyad's own branch: in closed form where its parents turn with
    the input (``turning``, circuits' analytic case, see :func:`analytic_crossings`), else
    bracketed on a grid of ``grid`` cells per turn over one period and bisected.
    """
    dyads = plan.dyads
    if len(dyads) != 1 or not candidates(plan, params, usable.shape).any():
        return segs
    (dyad,) = dyads
    shape = usable.shape
    period = np.broadcast_to(np.asarray(arcs.period, dtype=float), shape)
    if turning is not None and isinstance(dyad, DyadRRR):
        at = analytic_crossings(plan, params, turning)[..., None]
    else:
        turns = np.rint(period / TWO_PI).astype(np.int64)
        cells = grid * int(turns.max()) if turns.size else grid
        at = crossings_in_period(plan, params, points, usable, period, cells, doc)
    at = np.broadcast_to(at, shape + at.shape[-1:])
    has = usable & np.isfinite(at).any(-1)
    if not has.any():
        return segs
    seg_start, seg_end, seg_branches, _, _ = segs
    part = split_single(
        seg_start[has],
        seg_end[has],
        {dyad.name: seg_branches[dyad.name][has]},
        np.broadcast_to(arcs.full, shape)[has],
        period[has],
        at[has],
        dyad.name,
    )
    return scatter(segs, part, has)


def split_single(
    seg_start: Array,
    seg_end: Array,
    seg_branches: Mapping[str, Array],
    full: NDArray[np.bool_],
    period: Array,
    crossings: Array,
    dyad: str,
) -> tuple[Array, Array, dict[str, Array], NDArray[np.int64], NDArray[np.int64]]:
    """A one-dyad circuit's segments, cut where it passes its crossings.

    In: the circuit without them (batch + (2,): a full turn ``[start, start + period]``, or an
    arc up ``[lo, hi]`` and back ``[hi, lo]``) and the crossings (batch + (K,), any turn of
    the input, NaN-padded). At each crossing the dyad's sign flips and the input runs on. Up an
    arc and back it passes each crossing twice and closes as before; a full turn with an odd
    number of crossings comes back on the other branch, so it takes two turns to close.

    Returns the segments (starts, ends, signs) and what each starts and ends at
    (``PLAIN``, ``LIMIT`` or the dyad index 0 for a crossing).
    """
    shape = full.shape
    size = int(np.prod(shape, dtype=np.int64))
    starts = seg_start.reshape(size, -1)
    ends = seg_end.reshape(size, -1)
    sign = np.asarray(seg_branches[dyad]).reshape(size, -1)
    per = np.broadcast_to(period, shape).reshape(size)
    fl = full.reshape(size)
    cross = crossings.reshape(size, -1)
    rows: list[tuple[list[float], list[float], list[float], list[int], list[int]]] = []
    for i in range(size):
        cs = cross[i][np.isfinite(cross[i])]
        if not np.isfinite(starts[i, 0]):
            rows.append(([np.nan], [np.nan], [np.nan], [PLAIN], [PLAIN]))
            continue
        if fl[i]:
            rows.append(_cut_turn(starts[i, 0], per[i], cs, sign[i, 0]))
        else:
            rows.append(_cut_arc(starts[i, 0], ends[i, 0], per[i], cs, sign[i, 0]))
    width = max(len(r[0]) for r in rows) if rows else 1
    out = [np.full((size, width), np.nan) for _ in range(3)]
    at = [np.full((size, width), PLAIN, dtype=np.int64) for _ in range(2)]
    for i, r in enumerate(rows):
        n = len(r[0])
        for j in range(3):
            out[j][i, :n] = r[j]
        for j in range(2):
            at[j][i, :n] = r[3 + j]
    s0, s1, br = (x.reshape(shape + (width,)) for x in out)
    a0, a1 = (x.reshape(shape + (width,)) for x in at)
    return s0, s1, {dyad: br}, a0, a1


def _shifted(cs: Array, lo: float, hi: float, period: float) -> list[float]:
    """The crossings, moved by whole periods, that lie strictly between lo and hi (lo < hi)."""
    out = []
    for c in cs:
        x = c + period * np.ceil((lo - c) / period)
        while x < hi:
            if x - lo > EXCLUDE and hi - x > EXCLUDE:
                out.append(float(x))
            x += period
    return sorted(out)


Cuts = tuple[list[float], list[float], list[float], list[int], list[int]]


def _cut_turn(start: float, period: float, cs: Array, sign: float) -> Cuts:
    turns = 1 if len(cs) % 2 == 0 else 2
    events = _shifted(cs, start, start + turns * period, period)
    bounds = [start, *events, start + turns * period]
    n = len(bounds) - 1
    signs = [sign * (-1.0) ** j for j in range(n)]
    # A turn that starts on a crossing starts (and ends) as its limit.
    on = np.abs(np.remainder(cs - start + 0.5 * period, period) - 0.5 * period) <= EXCLUDE
    edge = 0 if on.any() else PLAIN
    begin = [edge] + [0] * (n - 1)
    end = [0] * (n - 1) + [edge]
    return bounds[:-1], bounds[1:], signs, begin, end


def _cut_arc(lo: float, hi: float, period: float, cs: Array, sign: float) -> Cuts:
    events = _shifted(cs, lo, hi, period)
    up = [lo, *events, hi]
    down = up[::-1]
    bounds0: list[float] = []
    bounds1: list[float] = []
    signs: list[float] = []
    begin: list[int] = []
    end: list[int] = []
    s = sign
    for path in (up, down):
        n = len(path) - 1
        for j in range(n):
            bounds0.append(path[j])
            bounds1.append(path[j + 1])
            signs.append(s)
            begin.append(LIMIT if j == 0 else 0)
            end.append(LIMIT if j == n - 1 else 0)
            s = -s  # a crossing flips the sign; so does the limit at the path's end
    return bounds0, bounds1, signs, begin, end


def starts_on(
    plan: Plan,
    params: Params,
    points: frozenset[str],
    theta: Array,
    branches: Mapping[str, ArrayLike] | None,
) -> NDArray[np.int64]:
    """``PLAIN``, or the index of a dyad whose parents meet at ``theta`` (batch-shaped)."""
    allow = candidates(plan, params, np.shape(theta))
    out = np.full(np.shape(theta), PLAIN, dtype=np.int64)
    if not allow.any():
        return out
    br = None if not branches else {k: np.asarray(v)[..., None] for k, v in branches.items()}
    _, states = place_all(plan, params, np.asarray(theta)[..., None], points=points, branches=br,
                          order=0)  # fmt: skip
    for i, d in reversed(list(enumerate(plan.dyads))):
        out = np.where(meets(d, states, params)[..., 0] & allow[..., i], i, out)
    return out


def warp(code: NDArray[np.int64], f: Array) -> Array:
    """Where along a segment fraction f of it lies, by what its ends are.

    Next to a limit position the joints move like the square root of the distance to it, so
    the input is spaced quadratically there: sin²(πf/2) between two limits, 1 − cos(πf/2) from
    one, sin(πf/2) to one; elsewhere (a full turn, a crossing, where the motion is regular)
    evenly. ``code``: 1 if the segment starts at a limit, plus 2 if it ends at one.
    """
    f = np.asarray(f, dtype=float)
    code = np.broadcast_to(code, f.shape)
    half = 0.5 * np.pi * f
    # One kind of segment throughout (no crossing) is the common case: one formula then.
    if np.all(code == 3):
        return np.sin(half) ** 2
    if np.all(code == 0):
        return f
    return np.select(
        [code == 3, code == 1, code == 2],
        [np.sin(half) ** 2, 1.0 - np.cos(half), np.sin(half)],
        f,
    )


def warp_codes(begin: NDArray[np.int64], end: NDArray[np.int64]) -> NDArray[np.int64]:
    codes: NDArray[np.int64] = (begin == LIMIT).astype(np.int64) + 2 * (end == LIMIT).astype(
        np.int64
    )
    return codes


def flags(
    plan: Plan,
    begin: NDArray[np.int64],
    end: NDArray[np.int64],
    seg_start: Array,
    seg_end: Array,
    segment: NDArray[np.int64],
    at_start: NDArray[np.bool_],
    at_end: NDArray[np.bool_] | None = None,
) -> dict[str, Array] | None:
    """The ``crossings=`` of the samples that lie on one: each sample's ``segment``, and whether
    it is that segment's start (``at_start``) or end (``at_end``) exactly. A sample at a
    segment's start lies on the side the segment runs to, one at its end on the side it came
    from. None where no segment starts or ends at a crossing."""
    if not (np.any(begin >= 0) or np.any(end >= 0)):
        return None

    def take(a: NDArray[Any]) -> NDArray[Any]:
        return np.take_along_axis(a, segment, -1)

    direction = np.sign(np.nan_to_num(take(seg_end) - take(seg_start)))
    b, e = take(begin), take(end)
    out: dict[str, Array] = {}

    for i, d in enumerate(plan.dyads):
        side = np.where(at_start & (b == i), direction, 0.0)
        if at_end is not None:
            side = np.where(at_end & (e == i), -direction, side)
        if np.any(side):
            out[d.name] = side
    return out or None

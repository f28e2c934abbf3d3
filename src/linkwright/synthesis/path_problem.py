"""The problem a path fit searches: targets, timing, bounds and the batched evaluation.

:class:`Problem` holds one call of :func:`~linkwright.synthesis.path.fit_path` after its input
checks: the model of the family, the targets, the timing and the bounds, and evaluates a whole
population of candidate linkages as one batched mechanism. With free or no timing each member's
curve is sampled on a grid and the targets are matched to its chords, in order by a dynamic
programme (:func:`monotone_cost`) or each to the nearest (:func:`nearest_cost`), so that the
global search sees the dimensions only. The timings and the error are those of the module
docstring of :mod:`linkwright.synthesis.path`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Motion
from linkwright.engine.circuits import MAX_TURNS
from linkwright.mechanisms import solve
from linkwright.synthesis.path_families import (
    TWO_PI,
    Model,
    path_margin,
    sampled_gaps,
    sphere_rotation,
    to_user,
)
from linkwright.synthesis.path_follow import Followed
from linkwright.synthesis.path_models import GenericModel
from linkwright.synthesis.path_spec import (
    BETWEEN,
    COVERAGE,
    EXTRA,
    GRID,
    MARGIN,
    SAMPLED_MARGIN,
    SCREEN,
    STARTS,
    PathConstraints,
    PathSynthesisError,
)

__all__ = [
    "Candidate",
    "OutOfTime",
    "Problem",
    "solve_batched",
    "wrap_angle",
]

Array = NDArray[np.float64]

START = "input_start"
"""The unknown a prescribed timing with a free start adds: the input of its first angle."""


# ------------------------------------------------------------------------------------------
# The problem: everything the search evaluates
# ------------------------------------------------------------------------------------------


@dataclass
class Candidate:
    error: float  # Σ d² at the targets
    objective: float  # what the search minimises (the error, plus the closed no-timing term)
    pose: Array  # planar (x, y, frame_angle); sphere a 3×3 rotation
    shape: dict[str, float]
    assembly: float
    rel: Array  # inputs from the frame line at each target


class OutOfTime(Exception):
    pass


class Problem:
    def __init__(
        self,
        model: Model | GenericModel,
        targets: Array,
        angles: Array | None,
        timing: str,
        closed: bool,
        bounds: dict[str, tuple[float, float]],
        cons: PathConstraints,
        size: float,
        free_start: bool = False,
    ) -> None:
        self.model = model
        self.targets = targets
        self.n = len(targets)
        self.angles = angles
        self.timing = timing
        self.closed = closed
        self.size = size
        self.cons = cons
        self.full_turn = cons.full_turn or closed
        self.mu = cons.min_transmission
        self.evaluations = 0
        # A prescribed timing with a free start fits one more unknown, last: the input at which
        # the given angles start (they then prescribe its steps only).
        self.free_start = free_start
        names = model.pose_names + model.shape_names + ((START,) if free_start else ())
        self.names = names
        bounds = {**bounds, START: (0.0, TWO_PI)}
        self.lo = np.array([bounds[k][0] for k in names])
        self.hi = np.array([bounds[k][1] for k in names])
        self.free = self.lo < self.hi
        self.periodic = np.array(
            [
                (k in ("frame_angle", "lon", "spin", START) or k in model.periodic)
                and self.hi[i] - self.lo[i] >= TWO_PI - 1e-9
                for i, k in enumerate(names)
            ]
        )
        self.turns = 1
        if model.family == "geared-fivebar":
            self.turns = _gear_turns(bounds["ratio"])
        elif isinstance(model, GenericModel):
            for name in model.ratios:
                if bounds[name][0] != bounds[name][1]:
                    raise PathSynthesisError(
                        f"bounds[{name!r}]: a gear ratio is chosen, not fitted: give equal "
                        f"bounds, got {bounds[name]}"
                    )
            self.turns = model.turns
        self.period = TWO_PI * self.turns
        self.grid = np.arange(GRID, dtype=np.float64) * (self.period / GRID)
        self.cover_grid = np.arange(COVERAGE, dtype=np.float64) * (self.period / COVERAGE)
        self.sampled = (model.family == "geared-fivebar" or isinstance(model, GenericModel)) and (
            self.full_turn or self.mu > 0
        )
        nn = np.sqrt(np.sum((targets[:, None] - targets[None]) ** 2, axis=-1))
        np.fill_diagonal(nn, np.inf)
        self.coverage_h = 0.6 * float(np.max(np.min(nn, axis=1)))
        self.penalty = 10.0 * size if model.space == "plane" else 2.0 + 10.0 * size
        # A family whose evaluation costs more (a triad solves every pose) searches with
        # proportionally fewer members and starts.
        scale = getattr(model, "search_scale", 1.0)
        self.screen = SCREEN if scale == 1.0 else max(2, int(SCREEN * scale))
        self.starts = STARTS if scale == 1.0 else max(3, int(STARTS * scale))
        self.extra = EXTRA if scale == 1.0 else max(2, int(EXTRA * scale))
        self.seeds: Array | None = None
        # A configuration with a triad is named by its pose at this input (from the frame line):
        # the first target's where the timing is prescribed, so that a branch that rocks
        # between limit positions away from the input 0 can be chosen too.
        self.anchor = float(angles[0]) if angles is not None else 0.0

    # -- decoding -----------------------------------------------------------------------

    def full_params(self, genes: Array) -> tuple[Array, Array]:
        """DE genes (B, free + 1) → all parameters (B, names) and assembly signs (B,)."""
        full = np.broadcast_to((self.lo + self.hi) / 2, (len(genes), len(self.names))).copy()
        full[:, self.free] = genes[:, :-1]
        full[:, ~self.free] = self.lo[~self.free]
        if isinstance(self.model, GenericModel):
            return full, self.model.code(genes[:, -1])
        return full, np.where(genes[:, -1] >= 0, 1.0, -1.0)

    def offsets(self, full: Array) -> Array:
        """Each member's start (B,): where its prescribed angles begin (0 unless it is free)."""
        return full[:, -1] if self.free_start else np.zeros(len(full))

    def split(self, full: Array) -> tuple[Array, dict[str, Array]]:
        """Parameters (B, names) → poses (B, 3) or (B, 3, 3) and shape arrays."""
        shape = {k: full[:, 3 + i] for i, k in enumerate(self.model.shape_names)}
        pose = full[:, :3]
        if self.model.space == "sphere":
            pose = sphere_rotation(pose[:, 0], pose[:, 1], pose[:, 2])
        return pose, shape

    # -- the engine -----------------------------------------------------------------------

    def trace(
        self, pose: Array, shape: dict[str, Array], assembly: Array, rel: Array
    ) -> tuple[Array, NDArray[np.bool_], Motion | Followed]:
        """Traced points in the user's frame at the inputs ``rel`` (K,) or (B, K), the valid
        mask, and the local motion (for margins and the dyad's joints)."""
        if isinstance(self.model, GenericModel):
            local, valid, motion = self.model.evaluate(shape, assembly, rel, self.anchor)
            self.evaluations += len(assembly)
            return to_user(self.model.space, local, pose), valid, motion
        mech = self.model.local(shape, assembly)
        motion = solve(mech, rel, order=0)
        self.evaluations += len(assembly)
        P = to_user(self.model.space, motion.positions["P"], pose)
        return P, motion.valid, motion

    def gaps(
        self,
        shape: dict[str, Array],
        motion: Motion | Followed | None = None,
        sl: slice = slice(None),
        hull: tuple[ArrayLike, ArrayLike] | None = None,
        code: Array | None = None,
    ) -> list[tuple[Array, float]]:
        """Every constraint function g (≤ 0 when met, normalised) with the margin by which
        the search keeps inside it. ``hull`` = (lo, hi): the inputs the path sweeps, which
        must not meet a limit position."""
        c = self.cons
        out = [
            (g, MARGIN)
            for g in self.model.closed_form_gaps(shape, c.classes, self.full_turn, self.mu)
        ]
        if hull is not None and isinstance(self.model, Model):
            m = path_margin(self.model, shape, *hull)
            if m is not None:
                out.append((-m, MARGIN))
        if self.sampled and motion is not None and isinstance(self.model, GenericModel):
            found = self.model.sampled_gaps(motion, sl, self.full_turn, self.mu, shape, code)
            out += [(g, SAMPLED_MARGIN) for g in found]
        elif self.sampled and motion is not None:
            pos = {k: motion.positions[k][:, sl] for k in ("A", "B", "C")}
            mar = {"C": motion.margins["C"][:, sl]}
            out += [(g, SAMPLED_MARGIN) for g in sampled_gaps(pos, mar, self.full_turn, self.mu)]
        return out

    # -- the global search's fitness ----------------------------------------------------

    def fitness(self, genes: Array) -> tuple[Array, Array]:
        """(error, violation) of each member: the violation is 0 for a feasible member."""
        full, assembly = self.full_params(genes)
        pose, shape = self.split(full)
        T = self.targets
        viol = np.zeros(len(genes))
        sl: slice
        hull: tuple[ArrayLike, ArrayLike] | None
        if self.timing == "prescribed":
            assert self.angles is not None  # a prescribed timing comes with its angles
            off = self.offsets(full)[:, None]
            angles = self.angles[None] + off
            mids = _between(self.angles, BETWEEN)[None] + off
            grid = [np.broadcast_to(self.grid, (len(full), GRID))] if self.sampled else []
            rel = np.concatenate([angles, mids, *grid], axis=1)
            P, valid, motion = self.trace(pose, shape, assembly, rel)
            n, nm = self.n, len(mids)
            d2 = np.sum((P[:, :n] - T) ** 2, axis=-1)
            bad = ~valid[:, : n + nm]
            err = np.sum(np.where(valid[:, :n], d2, 0.0), axis=1)
            viol += bad.sum(axis=1)
            sl = slice(n + nm, None)
            hull = (np.min(angles, axis=1), np.max(angles, axis=1))
        else:
            P, valid, motion = self.trace(pose, shape, assembly, self.grid)
            d2, _, seg_ok = _segments(P, valid, T)
            if self.timing == "free":
                err = _monotone_cost(d2, seg_ok)
            else:
                err, runs = _nearest_cost(d2, seg_ok)
                viol += runs
                if self.closed:
                    err = err + self.coverage_cost(P, valid)
            viol += ~np.isfinite(err)
            sl = slice(None)
            hull = None
        for g, margin in self.gaps(shape, motion, sl, hull, assembly):
            viol += np.maximum(g + margin, 0.0)
        err = np.where(np.isfinite(err), err, np.inf)
        return err, viol

    def coverage_cost(self, P: Array, valid: NDArray[np.bool_]) -> Array:
        """The closed no-timing fit's term: curve samples far from every target (B,)."""
        d = np.sqrt(np.min(np.sum((P[:, :, None] - self.targets) ** 2, axis=-1), axis=-1))
        excess = np.where(valid, np.maximum(d - self.coverage_h, 0.0), 0.0)
        cost: Array = (self.n / P.shape[1]) * np.sum(excess**2, axis=1)
        return cost

    # -- assignments for the local search ------------------------------------------------

    def assign(self, pose: Array, shape: dict[str, Array], assembly: Array) -> tuple[Array, float]:
        """Inputs (from the frame line) matching the targets on the grid, for one member, and
        the sense (+1/−1) of a free timing."""
        P, valid, _ = self.trace(pose, shape, assembly, self.grid)
        d2, tpar, seg_ok = _segments(P, valid, self.targets)
        d2, tpar, ok = d2[0], tpar[0], seg_ok[0]
        step = self.period / GRID
        if self.timing == "free":
            idx, sense = _monotone_path(d2, ok)
            raw = self.grid[idx] + step * tpar[np.arange(self.n), idx]
            # A run that passes the grid's end is continued past it, so that the inputs
            # increase (or decrease) as numbers, not only modulo a turn; two targets on one
            # segment in the wrong order get equal inputs.
            s = sense * np.diff(raw)
            s = np.maximum(np.where(s < -0.5 * self.period, s + self.period, s), 0.0)
            return raw[0] + sense * np.r_[0.0, np.cumsum(s)], sense
        idx = np.argmin(d2, axis=1)
        rel = self.grid[idx] + step * tpar[np.arange(self.n), idx]
        if not ok.all():
            # Lift the inputs onto one run of valid samples, so that as numbers they lie in
            # one admissible arc (the run may wrap past the grid's end).
            first = int(np.flatnonzero(ok & ~np.roll(ok, 1))[0]) if (~ok).any() else 0
            rel = np.where(idx >= first, rel, rel + self.period)
        return rel, 1.0


def _segments(
    P: Array, valid: NDArray[np.bool_], T: Array
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Squared distances (B, N, M) from each target to each chord of the sampled curve (the
    chord j joins samples j and j + 1, cyclically), where on it (0..1), and which chords join
    two valid samples. Matching targets to chords rather than samples keeps the grid's
    coarseness out of the global search's errors."""
    Q = np.roll(P, -1, axis=1)
    ok = valid & np.roll(valid, -1, axis=1)
    e = np.where(ok[..., None], Q - P, 0.0)
    rel = T[None, :, None, :] - np.where(ok[..., None], P, 0.0)[:, None]
    ee = np.sum(e * e, axis=-1)[:, None]
    t = np.clip(np.sum(rel * e[:, None], axis=-1) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
    d = rel - t[..., None] * e[:, None]
    d2 = np.where(ok[:, None], np.sum(d * d, axis=-1), np.inf)
    return d2, t, ok


def wrap_angle(angle: float) -> float:
    """An angle in (−π, π]."""
    return float(np.pi - np.mod(np.pi - angle, TWO_PI))


def solve_batched(M: Array, b: Array) -> Array:
    """Batched solve of M x = b, falling back to least squares for a singular matrix."""
    try:
        # The stubs widen solve's float64 answer to floating: astype(copy=False) is a no-op.
        return np.linalg.solve(M, b[..., None])[..., 0].astype(np.float64, copy=False)
    except np.linalg.LinAlgError:
        return np.stack([np.linalg.lstsq(m, c, rcond=None)[0] for m, c in zip(M, b, strict=True)])


def _gear_turns(ratio: tuple[float, float]) -> int:
    """Turns of the input before a geared five-bar repeats (the engine's input_turns)."""
    lo, hi = ratio
    if lo != hi:
        raise PathSynthesisError(
            f"bounds['ratio']: the gear ratio is chosen, not fitted: give equal bounds, "
            f"got ({lo}, {hi})"
        )
    for q in range(1, MAX_TURNS + 1):
        x = lo * q
        if abs(x - round(x)) <= 1e-9 * max(1.0, abs(x)):
            return q
    raise PathSynthesisError(
        f"bounds['ratio']: the gear ratio {lo} is not a fraction with a denominator up to "
        f"{MAX_TURNS}: such a linkage never repeats"
    )


def _between(angles: Array, k: int) -> Array:
    """k samples strictly between each pair of consecutive angles."""
    f = np.arange(1, k + 1) / (k + 1)
    return (angles[:-1, None] + np.diff(angles)[:, None] * f).ravel()


def _monotone_cost(d2: Array, valid: NDArray[np.bool_], starts: int = 3) -> Array:
    """Least Σ d² over order-keeping matches of the targets to grid samples (B,).

    Target 0 takes one of its ``starts`` nearest samples; the others follow in order (equal
    samples allowed) within one turn, in either sense, without crossing an invalid sample.
    """
    B, N, M = d2.shape
    best = np.full(B, np.inf)
    rows = np.arange(B)[:, None]
    for sense in (1, -1):
        dd = d2 if sense == 1 else d2[:, :, ::-1]
        vv = valid if sense == 1 else valid[:, ::-1]
        cand = np.argsort(dd[:, 0, :], axis=1)[:, :starts]
        for c in range(min(starts, M)):
            idx = (cand[:, c][:, None] + np.arange(M)) % M
            allowed = np.cumprod(vv[rows, idx], axis=1).astype(bool)
            acc = np.full((B, M), np.inf)
            acc[:, 0] = dd[rows[:, 0], 0, idx[:, 0]]
            for i in range(1, N):
                di = np.where(allowed, dd[rows, i, idx], np.inf)
                acc = np.minimum.accumulate(acc, axis=1) + di
            best = np.minimum(best, acc.min(axis=1))
    return best


def _monotone_path(
    d2: Array, valid: NDArray[np.bool_], starts: int = 3
) -> tuple[NDArray[np.int64], float]:
    """The indices of :func:`_monotone_cost`'s best match for one member, and its sense."""
    N, M = d2.shape
    best = (np.inf, None, 1.0)
    for sense in (1, -1):
        order = np.arange(M) if sense == 1 else np.arange(M)[::-1]
        for start in np.argsort(d2[0, order])[:starts]:
            idx = order[(start + np.arange(M)) % M]
            allowed = np.cumprod(valid[idx]).astype(bool)
            cost = np.full(M, np.inf)
            cost[0] = d2[0, idx[0]]
            back = np.zeros((N, M), dtype=np.int64)
            for i in range(1, N):
                run = np.minimum.accumulate(cost)
                # Where the running minimum last improved: the argmin of cost[:j + 1].
                improved = np.r_[True, cost[1:] < run[:-1]]
                arg = np.maximum.accumulate(np.where(improved, np.arange(M), 0))
                back[i] = arg
                cost = run + np.where(allowed, d2[i, idx], np.inf)
            j = int(np.argmin(cost))
            if cost[j] < best[0]:
                path = [j]
                for i in range(N - 1, 0, -1):
                    j = int(back[i, j])
                    path.append(j)
                best = (float(cost[path[0]]), idx[np.array(path[::-1])], float(sense))
    if best[1] is None:
        return np.argmin(d2, axis=1), 1.0
    return best[1], best[2]


def _nearest_cost(d2: Array, valid: NDArray[np.bool_]) -> tuple[Array, Array]:
    """Σ of each target's least d² over the samples, and how many runs of valid samples
    beyond one the matches use (they must lie on one admissible arc)."""
    idx = np.argmin(d2, axis=2)  # (B, N)
    err = np.sum(np.take_along_axis(d2, idx[..., None], axis=2)[..., 0], axis=1)
    starts = valid & ~np.roll(valid, 1, axis=1)
    label = np.cumsum(starts, axis=1)
    # A run that wraps past the grid's end continues the first one (label 0 there).
    wraps = valid[:, :1] & valid[:, -1:]
    label = np.where(wraps & (label == 0), label[:, -1:], label)
    used = np.sort(np.take_along_axis(label, idx, axis=1), axis=1)
    runs = np.sum(np.diff(used, axis=1) != 0, axis=1)
    return err, runs.astype(float)

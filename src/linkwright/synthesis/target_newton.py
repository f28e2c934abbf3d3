"""The solver behind a design to targets: grid seeds and batched Newton iterations.

A :class:`TargetProblem` evaluates the outputs of a batch of mechanisms built from free
variables in a box. :func:`grid_axes`, :func:`local_minima` and :func:`cell_seeds` find the
seeds on a grid over the box (cells where each residual changes sign and whose affine model has
its root near the cell, and grid nodes where the misfit is a local minimum); :func:`newton`
iterates all seeds together, each round one batched evaluation (a central-difference Jacobian,
the Newton step with its halvings and Levenberg–Marquardt steps tried at once, never leaving
the box); :func:`merge_points` deduplicates what they reach. The method is described in
:mod:`linkwright.synthesis.targets`.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.mechanisms.base import Mechanism
from linkwright.synthesis.target_outputs import Output, TargetError

__all__ = [
    "CELL_MARGIN",
    "CHUNK",
    "DAMPING",
    "LEAST_SQUARES_SEARCH",
    "LINE_SEARCH",
    "MAX_ITERATIONS",
    "MAX_SEEDS",
    "SAME_POINT",
    "SAME_ROOT",
    "SAME_SEED",
    "STALL_FACTOR",
    "STALL_ROUNDS",
    "STEP",
    "TargetProblem",
    "cell_seeds",
    "grid_axes",
    "local_minima",
    "merge_points",
    "newton",
]

Array = NDArray[np.float64]


# Mechanisms per batched evaluation: the circuit of 1024 samples with two derivatives costs
# about 0.4 MB per spherical four-bar, so a chunk stays near 100 MB.
CHUNK = 256
# Central-difference step, relative to the box's width along each variable. The outputs are
# exact to ~1e-12, so the Jacobian is good to ~1e-6: plenty for Newton and for conditioning.
STEP = 1e-6
MAX_ITERATIONS = 40
# Halvings tried at once with each Newton step (t = 1, 1/2, 1/4, 1/8, 1/16).
LINE_SEARCH = (1.0, 0.5, 0.25, 0.125, 0.0625)
# A seed of a square system stops when its misfit (sum of squares) fell by less than this
# factor over this many rounds.
STALL_ROUNDS = 2
STALL_FACTOR = 0.25
# Least squares: Gauss–Newton converges only linearly to a minimum with a residual, often
# short of it by a steady factor, so longer steps are tried too and the best is taken.
LEAST_SQUARES_SEARCH = (1.0, 2.0, 4.0, 0.5, 0.25, 0.125)
# Levenberg–Marquardt damping tried with each Newton step, relative to trace(JᵀJ).
DAMPING = (1e-4, 1e-2, 1.0)
# Two polished points closer than this (infinity norm, in units of the box's width) are one.
SAME_POINT = 1e-5
# A running seed this close (in grid cells) to a root already found joins it.
SAME_ROOT = 0.5
# Newton seeds closer than this (in grid cells) start the same iteration.
SAME_SEED = 0.25
# An affine model's root this far outside its cell (in cells) does not seed.
CELL_MARGIN = 0.5
# At most this many Newton iterations, those of least misfit: a problem that needs more wants
# a smaller box.
MAX_SEEDS = 600


# --- the solver -------------------------------------------------------------------------------


class TargetProblem:
    """The residuals of a problem at many points, in chunks, with undefined points masked."""

    def __init__(
        self,
        make: Callable[[Array], Mechanism],
        outputs: Sequence[tuple[str, Callable[[Mechanism], ArrayLike]]],
        values: Array,
        lo: Array,
        hi: Array,
        where: Callable[[Mechanism], ArrayLike] | None,
        progress: Callable[[float], None] | None,
    ) -> None:
        self.make = make
        self.outputs = outputs
        self.target = values
        self.scale = np.maximum(np.abs(values), 1.0)
        self.lo, self.hi = lo, hi
        self.where = where
        self.count = 0
        self.progress = progress

    def mechanism(self, x: Array) -> Mechanism:
        try:
            mech = self.make(x)
        except ValueError as exc:
            raise TargetError(
                f"make(x) failed inside the box (x from {np.min(x, axis=0).tolist()} to "
                f"{np.max(x, axis=0).tolist()}): {exc}"
            ) from None
        if not isinstance(mech, Mechanism):
            raise TargetError(f"make(x) must return a Mechanism, got {type(mech).__name__}")
        if mech.batch_shape != x.shape[:-1]:
            raise TargetError(
                f"make(x) for x of shape {x.shape} must give a batch of shape {x.shape[:-1]}, "
                f"got {mech.batch_shape}"
            )
        return mech

    def _outputs(self, x: Array) -> Array:
        n = x.shape[0]
        out = np.full((n, len(self.outputs)), np.nan)
        if n == 0:
            return out
        mech = self.mechanism(x)
        keep = np.ones(n, dtype=bool)
        if self.where is not None:
            keep = np.broadcast_to(np.asarray(self.where(mech), dtype=bool), (n,)).copy()
            if not keep.any():
                return out
            if not keep.all():
                mech = self.mechanism(x[keep])
        shared: dict[int, Mapping[str, ArrayLike]] = {}
        for j, (name, fn) in enumerate(self.outputs):
            if isinstance(fn, Output):
                key = id(fn.basis)
                if key not in shared:
                    shared[key] = fn.basis(mech)
                value = np.asarray(shared[key][fn.key], dtype=float)
            else:
                value = np.asarray(fn(mech), dtype=float)
            if value.shape != (int(keep.sum()),):
                raise TargetError(
                    f"output {name!r} gave shape {value.shape} for a batch of "
                    f"{int(keep.sum())} mechanisms; it must give one value per mechanism"
                )
            out[keep, j] = value
        return out

    def values(self, x: Array, done: float = 0.0, share: float = 0.0) -> Array:
        """Raw outputs at points ``x`` (n, k): (n, m), NaN where undefined."""
        x = np.asarray(x, dtype=float).reshape(-1, self.lo.size)
        parts = []
        with np.errstate(all="ignore"):
            for i in range(0, x.shape[0], CHUNK):
                parts.append(self._outputs(x[i : i + CHUNK]))
                if self.progress is not None and share:
                    self.progress(done + share * min(i + CHUNK, x.shape[0]) / x.shape[0])
        self.count += x.shape[0]
        f = np.concatenate(parts) if parts else np.empty((0, len(self.outputs)))
        kept: Array = np.where(np.all(np.isfinite(f), axis=-1, keepdims=True), f, np.nan)
        return kept

    def residual(self, f: Array) -> Array:
        return (f - self.target) / self.scale

    def stencil(self, x: Array) -> Array:
        """Central-difference points about each x (n, k): (n, 2k, k), x ± h along each axis in
        turn, clipped to the box."""
        k = x.shape[1]
        h = STEP * (self.hi - self.lo)
        pts = np.repeat(x[:, None, :], 2 * k, axis=1)
        for j in range(k):
            pts[:, 2 * j, j] += h[j]
            pts[:, 2 * j + 1, j] -= h[j]
        return np.clip(pts, self.lo, self.hi)

    def jacobian(self, x: Array, fx: Array, fs: Array, pts: Array) -> Array:
        """d output / d x (n, m, k) from the stencil's values fs (n, 2k, m).

        One-sided where a neighbour is undefined or clipped onto x; NaN where both are.
        """
        n, k = x.shape
        jac = np.full((n, fx.shape[-1], k), np.nan)
        for j in range(k):
            fp, fm = fs[:, 2 * j], fs[:, 2 * j + 1]
            xp, xm = pts[:, 2 * j, j], pts[:, 2 * j + 1, j]
            okp = np.all(np.isfinite(fp), -1) & (xp > x[:, j])
            okm = np.all(np.isfinite(fm), -1) & (xm < x[:, j])
            hi_f = np.where(okp[:, None], fp, fx)
            lo_f = np.where(okm[:, None], fm, fx)
            hi_x = np.where(okp, xp, x[:, j])
            lo_x = np.where(okm, xm, x[:, j])
            width = hi_x - lo_x
            with np.errstate(all="ignore"):
                d = (hi_f - lo_f) / width[:, None]
            jac[:, :, j] = np.where((width > 0)[:, None], d, np.nan)
        return jac


def grid_axes(lo: Array, hi: Array, grid: int | Sequence[int] | None) -> list[Array]:
    k = lo.size
    if grid is None:
        sizes = [max(5, min(257, round(1100 ** (1.0 / k))))] * k
    elif isinstance(grid, int | np.integer):
        sizes = [int(grid)] * k
    else:
        sizes = [int(g) for g in grid]
    if len(sizes) != k or min(sizes) < 2:
        raise TargetError(f"grid: give one node count ≥ 2 per free variable ({k}), got {grid!r}")
    return [np.linspace(a, b, n) for a, b, n in zip(lo, hi, sizes, strict=True)]


def local_minima(norm: Array) -> NDArray[np.int64]:
    """Flat indices of the grid nodes no higher than any neighbour (3^k stencil) and lower than
    one."""
    k = norm.ndim
    padded = np.pad(np.where(np.isfinite(norm), norm, np.inf), 1, constant_values=np.inf)
    is_min = np.isfinite(norm)
    # Strictly below some neighbour: the inside of a plateau (an output pinned at a limit, say)
    # is no minimum worth a seed.
    below_one = np.zeros(norm.shape, dtype=bool)
    core = tuple(slice(1, -1) for _ in range(k))
    for off in itertools.product((-1, 0, 1), repeat=k):
        if not any(off):
            continue
        sl = tuple(slice(1 + o, padded.shape[d] - 1 + o) for d, o in enumerate(off))
        is_min &= padded[core] <= padded[sl]
        below_one |= padded[core] < padded[sl]
    return np.flatnonzero(is_min & below_one)


def cell_seeds(axes: list[Array], R: Array) -> tuple[Array, Array]:
    """Seeds from the cells where every residual changes sign: (points, fallbacks), (n, k).

    An affine model r ≈ a + G u fitted to each cell's defined corners (u in cell units) must
    have its root within :data:`CELL_MARGIN` cells of the cell; the seed is that root. The
    fallback is the cell's defined corner of least misfit (in case the root is undefined).
    """
    k = len(axes)
    shape = tuple(a.size for a in axes)
    corners = list(itertools.product((0, 1), repeat=k))
    cell_shape = tuple(n - 1 for n in shape)
    stack = []
    for c in corners:
        sl = tuple(slice(o, o + n) for o, n in zip(c, cell_shape, strict=True))
        stack.append(R[sl])
    C = np.stack(stack, axis=-2).reshape(-1, len(corners), R.shape[-1])  # (cells, 2^k, m)
    ok = np.all(np.isfinite(C), axis=-1)
    enough = ok.sum(-1) >= k + 1
    lo = np.where(ok[..., None], C, np.inf).min(-2)
    hi = np.where(ok[..., None], C, -np.inf).max(-2)
    sign = enough & np.all((lo <= 0) & (hi >= 0), axis=-1)
    cells = np.flatnonzero(sign)
    if cells.size == 0:
        return np.empty((0, k)), np.empty((0, k))
    U = np.array(corners, dtype=float)  # (2^k, k)
    A = np.concatenate([np.ones((len(corners), 1)), U], axis=1)  # (2^k, k+1)
    W = ok[cells].astype(float)  # (n, 2^k)
    Cs = np.where(ok[cells][..., None], C[cells], 0.0)
    M = np.einsum("ci,nc,cj->nij", A, W, A)
    rhs = np.einsum("ci,nc,ncm->nim", A, W, Cs)
    coef = np.linalg.pinv(M) @ rhs  # (n, k+1, m)
    a, G = coef[:, 0, :], np.swapaxes(coef[:, 1:, :], 1, 2)  # (n, m), (n, m, k)
    u = -(np.linalg.pinv(G) @ a[..., None])[..., 0]
    near = np.all((u >= -CELL_MARGIN) & (u <= 1 + CELL_MARGIN), axis=-1) & np.all(
        np.isfinite(u), axis=-1
    )
    index = np.array(np.unravel_index(cells, cell_shape)).T  # (n, k)
    spacing = np.array([a[1] - a[0] for a in axes])
    origin = np.array([[axes[d][i[d]] for d in range(k)] for i in index])
    seeds = origin + np.clip(u, -CELL_MARGIN, 1 + CELL_MARGIN) * spacing
    misfit = np.where(ok[cells], np.max(np.abs(C[cells]), axis=-1), np.inf)
    best = U[np.argmin(misfit, axis=-1)]
    fallback = origin + best * spacing
    return seeds[near], fallback[near]


def merge_points(points: Array, width: Array, tol: float) -> NDArray[np.int64]:
    """Indices of the points to keep: each one farther than ``tol`` (in units of ``width``,
    infinity norm) from every earlier kept one."""
    keep: list[int] = []
    for i in range(points.shape[0]):
        if all(np.max(np.abs(points[i] - points[j]) / width) > tol for j in keep):
            keep.append(i)
    return np.array(keep, dtype=np.int64)


def newton(
    problem: TargetProblem,
    x0: Array,
    fallback: Array,
    cell: Array,
    least_squares: bool,
    tol: float,
) -> tuple[Array, Array, Array]:
    """Damped Newton (Gauss–Newton for least squares) from every seed at once.

    Returns the final points (n, k), their raw outputs (n, m), NaN for seeds that died or
    joined a root another seed had found, and the Jacobian there (n, m, k) where the last
    step computed it afresh (NaN elsewhere).
    Each round is one batched evaluation. A seed whose Jacobian J at x is known tries the
    Newton step shortened by each factor of :data:`LINE_SEARCH` (least squares:
    :data:`LEAST_SQUARES_SEARCH`) and three Levenberg–Marquardt steps (which follow a curved
    valley of the misfit better than a shortened Newton step), and the stencil about the full
    Newton step. The full step is taken when it decreases the misfit enough (Armijo; least
    squares: when it is the best trial), with the fresh Jacobian there; otherwise the best
    decreasing trial, with J updated by Broyden's rank-one formula. A seed whose Jacobian is
    unknown (just seeded) evaluates the stencil about x.
    """
    n, k = x0.shape
    lo, hi = problem.lo, problem.hi
    x = x0.copy()
    pts = problem.stencil(x)
    f_all = problem.values(np.concatenate([x[:, None, :], pts], axis=1))
    f_all = f_all.reshape(n, 2 * k + 1, -1)
    fx, fs = f_all[:, 0], f_all[:, 1:]
    bad = ~np.all(np.isfinite(fx), axis=-1)
    # A seed whose point is undefined restarts from its cell's best defined corner.
    x[bad] = fallback[bad]
    jac = problem.jacobian(x, fx, fs, pts)
    jac[bad] = np.nan
    fresh = ~bad
    if bad.any():
        fx[bad] = problem.values(x[bad])
    alive = np.all(np.isfinite(fx), axis=-1)
    done = ~alive
    scale = problem.scale
    t = np.array(LEAST_SQUARES_SEARCH if least_squares else LINE_SEARCH)
    nt = t.size + len(DAMPING)
    history = [np.full(n, np.inf)] * STALL_ROUNDS
    absorbed = np.zeros(n, dtype=bool)
    for it in range(MAX_ITERATIONS):
        if problem.progress is not None:
            problem.progress(0.5 + 0.45 * it / MAX_ITERATIONS)
        r = problem.residual(fx)
        merit = np.sum(r * r, axis=-1)
        converged = np.max(np.abs(r), axis=-1) <= 1e-3 * tol
        done |= converged & alive
        if not least_squares:
            # Newton converges to a root faster than this; a seed that does not is creeping
            # along a valley of the misfit or into a local minimum of it that is no root.
            done |= merit > STALL_FACTOR * history[-STALL_ROUNDS]
            history.append(merit)
            # A seed within reach of a root already found is heading for it: two roots closer
            # than the grid's resolution are beyond what the grid can tell apart anyway.
            roots = np.flatnonzero(converged & alive)
            if roots.size:
                gap = np.abs(x[:, None, :] - x[None, roots, :]) / cell
                near = np.any(np.all(gap <= SAME_ROOT, axis=-1), axis=-1)
                absorbed[near & ~done] = True
                done |= near
        active = np.flatnonzero(~done)
        if active.size == 0:
            break
        have_j = np.all(np.isfinite(jac[active]), axis=(-1, -2))
        with_j, without_j = active[have_j], active[~have_j]
        batches = []
        if with_j.size:
            js = jac[with_j] / scale[:, None]  # (n, m, k), residual units
            rj = r[with_j][..., None]
            dx = -(np.linalg.pinv(js, rcond=1e-13) @ rj)[..., 0]
            jtj = np.swapaxes(js, 1, 2) @ js
            g = (np.swapaxes(js, 1, 2) @ rj)[..., 0]
            big = np.trace(jtj, axis1=1, axis2=2)[:, None, None]
            eye = np.eye(k)
            # pinv, not solve: J vanishes where an output is flat (γ pinned at a limit, say).
            lm = [
                -(np.linalg.pinv(jtj + lam * big * eye) @ g[..., None])[..., 0] for lam in DAMPING
            ]
            steps = np.concatenate(
                [t[None, :, None] * dx[:, None, :], np.stack(lm, axis=1)], axis=1
            )
            trials = np.clip(x[with_j][:, None, :] + steps, lo, hi)
            tpts = problem.stencil(trials[:, 0])
            batches.append(np.concatenate([trials, tpts], axis=1))
        if without_j.size:
            spts = problem.stencil(x[without_j])
            batches.append(spts)
        flat = [b.reshape(-1, k) for b in batches]
        f = problem.values(np.concatenate(flat))
        if with_j.size:
            size = with_j.size * (nt + 2 * k)
            ft = f[:size].reshape(with_j.size, nt + 2 * k, -1)
            f = f[size:]
            rt = problem.residual(ft[:, :nt])
            mt = np.where(np.all(np.isfinite(rt), -1), np.sum(rt * rt, -1), np.inf)
            base = merit[with_j]
            rows = np.arange(with_j.size)
            if least_squares:
                best = np.argmin(mt, axis=-1)
                full = best == 0
            else:
                full = mt[:, 0] <= (1.0 - 1e-4) * base
                best = np.where(full, 0, np.argmin(mt, axis=-1))
            gain = base - mt[rows, best]
            ok = gain > 0
            moved = trials[rows, best]
            dxs = moved - x[with_j]
            step = np.max(np.abs(dxs) / (hi - lo), axis=-1)
            new_j = problem.jacobian(trials[:, 0], ft[:, 0], ft[:, nt:], tpts)
            # Broyden's update of J along the step actually taken.
            df = ft[rows, best] - fx[with_j]
            pred = (jac[with_j] @ dxs[..., None])[..., 0]
            with np.errstate(all="ignore"):
                upd = (
                    jac[with_j]
                    + ((df - pred)[..., None] * dxs[:, None, :])
                    / np.sum(dxs * dxs, axis=-1)[:, None, None]
                )
            idx = with_j[ok]
            x[idx] = moved[ok]
            fx[idx] = ft[rows[ok], best[ok]]
            jac[with_j[ok & full]] = new_j[ok & full]
            jac[with_j[ok & ~full]] = upd[ok & ~full]
            fresh[with_j[ok & ~full]] = False
            fresh[with_j[ok & full]] = True
            # No trial decreases the misfit (a local minimum of it, or the box's edge), or the
            # step is below the Jacobian's resolution: this seed is as good as it gets.
            stalled = ~ok | (step <= 1e-13)
            if least_squares:
                # Linear convergence to a minimum with a residual: stop once x has settled to
                # well below anything a user reads.
                stalled |= (gain <= 1e-15 * np.maximum(base, 1e-300)) | (step <= 1e-9)
            done[with_j[stalled]] = True
        if without_j.size:
            fs = f.reshape(without_j.size, 2 * k, -1)
            spts = problem.stencil(x[without_j])
            jac[without_j] = problem.jacobian(x[without_j], fx[without_j], fs, spts)
            fresh[without_j] = True
            dead = ~np.all(np.isfinite(jac[without_j]), axis=(-1, -2))
            done[without_j[dead]] = True
    keep = alive & ~absorbed
    return x, np.where(keep[:, None], fx, np.nan), np.where(fresh[:, None, None], jac, np.nan)

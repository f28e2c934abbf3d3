"""Design to targets: every set of free dimensions in a box at which chosen outputs take chosen
values.

A problem is ``k`` free variables x (shape ``(..., k)``), a function ``make(x)`` that builds a
(batched) mechanism from them, and ``m`` targets, each an output (a batched function of the
mechanism) and the value it should take. With ``m = k`` the solutions are isolated points, and
:func:`design_to_targets` reports all of them in the box; with ``m > k`` it reports the local
minima of the misfit (least squares) with their residual.

The search is exhaustive in the sense a grid can be: the outputs are evaluated on a grid over
the whole box at once (one batched run of the engine per chunk), every grid cell in which each
residual changes sign and whose affine model has its root near the cell seeds a Newton
iteration, and so does every grid node where the misfit is a local minimum (a root where two
level curves touch, or nearly do, changes no sign). Newton runs on all seeds together, each
round one batched evaluation: a central-difference Jacobian, the Newton step with its
halvings and three Levenberg–Marquardt steps tried at once, never leaving the box. A seed stops
when it converges, when it stops gaining (a local minimum of the misfit that is no root, or a
crawl along a valley), or when it comes within half a grid cell of a root another seed has
found (two roots closer than that are beyond what the grid resolves: refine the grid or the
box). Each result is deduplicated and kept only if its residual is within ``tol``. Mechanisms
where an output is not defined (the linkage does not assemble, or is of the wrong class) are
masked from the grid and the iteration; no NaN reaches a result.

Conditioning is reported with each solution: the Jacobian of the outputs by the free variables,
its singular values and condition number, and the sensitivity (the pseudo-inverse): how far
each free variable moves per unit change of each target. Paper 003's synthesis example is the
cautionary case: its two targets have almost parallel level curves
(:func:`linkwright.papers.p003.synthesis_example`).

:func:`design_fourbar` sets up the usual problem for the planar and spherical four-bars: fix
some of the four links, free the others, and aim the named outputs of :data:`OUTPUTS` (paper
003's coefficients, the time ratio, the swing, the transmission angle's extremes), all computed
by :mod:`linkwright.analysis`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis import (
    coefficients,
    fourbar_class,
    input_limits,
    output_extremes,
    transmission_extremes,
)
from linkwright.analysis.planar import FOURBAR_CLASSES
from linkwright.mechanisms import FourBar, SphericalFourBar, input_range
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "FOURBAR_DIMENSIONS",
    "OUTPUTS",
    "Output",
    "TargetError",
    "TargetSolution",
    "TargetSolutions",
    "design_fourbar",
    "design_to_targets",
]

Array = NDArray[np.float64]
Progress = Callable[[float], None]

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


class TargetError(ValueError):
    """A design-to-targets problem is not well posed (names the problem and the numbers)."""


# --- named outputs ----------------------------------------------------------------------------


def _coefficient_basis(mechanism: Mechanism) -> Mapping[str, Array]:
    return coefficients(mechanism)


def _transmission_basis(mechanism: Mechanism) -> Mapping[str, Array]:
    tx = transmission_extremes(mechanism)
    return {"gamma_min": tx["min"], "gamma_max": tx["max"]}


def _input_turns(mechanism: Mechanism) -> NDArray[np.bool_]:
    if isinstance(mechanism, SphericalFourBar):
        return np.asarray(input_limits(mechanism).full)
    return np.asarray(input_range(mechanism).full)


def _swing_basis(mechanism: Mechanism) -> Mapping[str, Array]:
    # Paper 003's Ψ belongs to a crank-rocker: the input turns fully and the output rocks.
    ext = output_extremes(mechanism)
    rocking = _input_turns(mechanism) & ~np.asarray(ext["turns"])
    return {"swing": np.where(rocking, ext["max"] - ext["min"], np.nan)}


@dataclass(frozen=True)
class Output:
    """A named output of a four-bar: ``basis(mechanism)[key]``, batched.

    Outputs that share a ``basis`` (the four coefficients, say) are computed once per
    evaluation when they are targets together. ``angle`` marks values in radians (reported in
    degrees).
    """

    name: str
    basis: Callable[[Mechanism], Mapping[str, ArrayLike]]
    key: str
    angle: bool = False
    description: str = ""

    def __call__(self, mechanism: Mechanism) -> Array:
        return np.asarray(self.basis(mechanism)[self.key], dtype=float)


OUTPUTS: dict[str, Output] = {
    o.name: o
    for o in (
        Output(
            "max_Kw",
            _coefficient_basis,
            "K_omega",
            description="max|Kω|, paper 003 eq. 4 (crank-rocker or double crank)",
        ),
        Output(
            "max_Ke",
            _coefficient_basis,
            "K_epsilon",
            description="max|Kε|, paper 003 eq. 4 (crank-rocker or double crank)",
        ),
        Output(
            "max_Kp",
            _coefficient_basis,
            "K_p",
            description="max|Kp|, paper 003 eq. 4 (crank-rocker or double crank)",
        ),
        Output(
            "delta",
            _coefficient_basis,
            "delta",
            description="δ = max φ3′ − min φ3′, non-uniformity of a double crank's output",
        ),
        Output(
            "time_ratio",
            _coefficient_basis,
            "time_ratio",
            description="time ratio of a crank-rocker (≥ 1)",
        ),
        Output(
            "swing",
            _swing_basis,
            "swing",
            angle=True,
            description="Ψ, the rocker's swing (crank-rocker)",
        ),
        Output(
            "gamma_min",
            _transmission_basis,
            "gamma_min",
            angle=True,
            description="smallest transmission angle over the circuit",
        ),
        Output(
            "gamma_max",
            _transmission_basis,
            "gamma_max",
            angle=True,
            description="largest transmission angle over the circuit",
        ),
    )
}
"""The named outputs of the planar and spherical four-bar (all from :mod:`linkwright.analysis`).

``max_Kw``, ``max_Ke``, ``max_Kp`` (paper 003's coefficients), ``delta`` (double crank),
``time_ratio`` (crank-rocker), ``swing`` (Ψ, crank-rocker), ``gamma_min`` and ``gamma_max``
(transmission angle). Each is undefined (masked) where it does not apply.
"""


# --- results ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class TargetSolution:
    """One solution: the free variables, what the outputs reach there and how well posed it is.

    Attributes
    ----------
    x : the free variables, shape ``(k,)`` (library units: lengths, radians).
    values : output name → the value reached.
    errors : output name → value − target.
    residual : the largest |error| / max(|target|, 1).
    jacobian : ``(m, k)``, d output / d x (central differences).
    singular_values : the Jacobian's, largest first.
    condition : largest over smallest singular value (inf where singular).
    sensitivity : ``(k, m)``, the Jacobian's pseudo-inverse: column j is how far x moves per
        unit increase of target j.
    mechanism : the mechanism ``make(x)``.
    """

    x: Array
    values: dict[str, float]
    errors: dict[str, float]
    residual: float
    jacobian: Array
    singular_values: Array
    condition: float
    sensitivity: Array
    mechanism: Mechanism


@dataclass(frozen=True)
class TargetSolutions:
    """Every solution of a design-to-targets problem in its box (see :func:`design_to_targets`).

    Iterating gives the :class:`TargetSolution` objects, in increasing x (lexicographic).
    ``least_squares`` problems (more targets than free variables) hold the local minima of the
    misfit, the smallest residual first. ``evaluated`` counts the mechanisms evaluated in all,
    ``seeds`` the Newton iterations started, ``masked`` the fraction of grid nodes where some
    output was undefined. ``angles`` names the free variables and outputs that are angles.
    """

    free: tuple[str, ...]
    targets: dict[str, float]
    bounds: Array
    grid: tuple[int, ...]
    solutions: tuple[TargetSolution, ...]
    least_squares: bool
    tol: float
    evaluated: int
    seeds: int
    masked: float
    angles: frozenset[str] = frozenset()

    def __len__(self) -> int:
        return len(self.solutions)

    def __iter__(self):
        return iter(self.solutions)

    def __getitem__(self, i: int) -> TargetSolution:
        return self.solutions[i]

    @property
    def x(self) -> Array:
        """All solutions' free variables, shape ``(n, k)``."""
        return np.array([s.x for s in self.solutions]).reshape(-1, len(self.free))

    def report(self, degrees: bool = True) -> dict[str, Any]:
        """JSON-ready summary, angles in degrees (``degrees=False``: radians).

        Keys: ``free``, ``targets``, ``bounds``, ``grid``, ``least_squares``, ``tol``,
        ``evaluated``, ``seeds``, ``masked_fraction``, ``units`` (per free variable and target:
        ``"deg"``, ``"rad"`` or ``""``) and ``solutions``: per solution ``x`` (name → value),
        ``values``, ``errors``, ``residual``, ``singular_values``, ``condition`` (``None`` where
        singular) and ``sensitivity`` (free variable → target → how far it moves per unit of
        the target, in the units shown).
        """
        names = list(self.targets)
        scale = 180.0 / math.pi if degrees else 1.0
        unit = "deg" if degrees else "rad"

        def conv(name: str) -> float:
            return scale if name in self.angles else 1.0

        cx = np.array([conv(n) for n in self.free])
        cy = np.array([conv(n) for n in names])
        sols = []
        for s in self.solutions:
            jac = s.jacobian * cy[:, None] / cx[None, :]
            sv = np.linalg.svd(jac, compute_uv=False)
            cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
            sens = s.sensitivity * cx[:, None] / cy[None, :]
            sols.append(
                {
                    "x": {n: float(v * c) for n, v, c in zip(self.free, s.x, cx, strict=True)},
                    "values": {n: s.values[n] * conv(n) for n in names},
                    "errors": {n: s.errors[n] * conv(n) for n in names},
                    "residual": s.residual,
                    "singular_values": [float(v) for v in sv],
                    "condition": cond if math.isfinite(cond) else None,
                    "sensitivity": {
                        f: {n: float(sens[i, j]) for j, n in enumerate(names)}
                        for i, f in enumerate(self.free)
                    },
                }
            )
        return {
            "free": list(self.free),
            "targets": {n: v * conv(n) for n, v in self.targets.items()},
            "bounds": {
                n: [float(lo * c), float(hi * c)]
                for n, (lo, hi), c in zip(self.free, self.bounds, cx, strict=True)
            },
            "grid": list(self.grid),
            "least_squares": self.least_squares,
            "tol": self.tol,
            "evaluated": self.evaluated,
            "seeds": self.seeds,
            "masked_fraction": self.masked,
            "units": {n: unit if n in self.angles else "" for n in [*self.free, *names]},
            "solutions": sols,
        }


# --- the solver -------------------------------------------------------------------------------


class _Problem:
    """The residuals of a problem at many points, in chunks, with undefined points masked."""

    def __init__(self, make, outputs, values, lo, hi, where, progress):
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
        return np.where(np.all(np.isfinite(f), axis=-1, keepdims=True), f, np.nan)

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


def _grid_axes(lo: Array, hi: Array, grid: int | Sequence[int] | None) -> list[Array]:
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


def _local_minima(norm: Array) -> NDArray[np.int64]:
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


def _cell_seeds(axes: list[Array], R: Array) -> tuple[Array, Array]:
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


def _merge(points: Array, width: Array, tol: float) -> NDArray[np.int64]:
    """Indices of the points to keep: each one farther than ``tol`` (in units of ``width``,
    infinity norm) from every earlier kept one."""
    keep: list[int] = []
    for i in range(points.shape[0]):
        if all(np.max(np.abs(points[i] - points[j]) / width) > tol for j in keep):
            keep.append(i)
    return np.array(keep, dtype=np.int64)


def _newton(
    problem: _Problem,
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


def design_to_targets(
    make: Callable[[Array], Mechanism],
    free: Sequence[str],
    bounds: ArrayLike,
    targets: Mapping[str, tuple[Callable[[Mechanism], ArrayLike], float]],
    *,
    grid: int | Sequence[int] | None = None,
    tol: float = 1e-9,
    where: Callable[[Mechanism], ArrayLike] | None = None,
    angles: Collection[str] = (),
    progress: Progress | None = None,
) -> TargetSolutions:
    """Every point of a box where the outputs of ``make(x)`` hit their targets.

    Parameters
    ----------
    make : builds the mechanisms for free variables ``x`` of shape ``(..., k)``, with batch
        shape ``x.shape[:-1]`` (library units: lengths, radians).
    free : the names of the k free variables.
    bounds : ``(k, 2)``, the box searched: lower and upper bound of each free variable; ``make``
        must accept every point of it.
    targets : output name → ``(output, value)``, with ``output(mechanism)`` one value per
        mechanism of a batch (NaN where undefined). An :class:`Output` from :data:`OUTPUTS`
        shares its analysis with the other targets of the same basis.
    grid : nodes per free variable (an int, or one per variable); by default about 1100 nodes
        in all.
    tol : a solution's largest |value − target| / max(|target|, 1) must not exceed it.
    where : optional mask of the mechanisms to consider (a class, say); the others are treated
        as undefined.
    angles : the free variables that are angles (for :meth:`TargetSolutions.report`).
    progress : called with the fraction done, in [0, 1].

    With as many targets as free variables the solutions are isolated points: every one found
    in the box is returned (see the module's docstring for the search). With more targets the
    local minima of the misfit are returned, smallest residual first (``least_squares``).

    Raises :class:`TargetError` for fewer targets than free variables, an empty or inverted box,
    a ``make`` that fails inside the box, or an output of the wrong shape.

    Examples
    --------
    Paper 003's Table 4 double crank (L4 = 1, L2 = 2): which crank L1 and output L3 give
    max|Kω| = 1.25 and δ = 0.48 (printed for L1 = 5, L3 = 4.69)?

    >>> from linkwright.mechanisms import FourBar
    >>> def make(x):
    ...     return FourBar(A0=[0.0, 0.0], B0=[1.0, 0.0], crank=x[..., 0], coupler=2.0,
    ...                    rocker=x[..., 1])
    >>> found = design_to_targets(
    ...     make, ["crank", "rocker"], [(4.0, 6.0), (3.5, 5.5)],
    ...     {"max_Kw": (OUTPUTS["max_Kw"], 1.25), "delta": (OUTPUTS["delta"], 0.48)}, grid=6)
    >>> [s.x.round(4).tolist() for s in found]
    [[5.0253, 4.7125]]
    >>> s = found[0]
    >>> round(s.values["max_Kw"], 12), round(s.values["delta"], 12), round(s.condition, 3)
    (1.25, 0.48, 1.139)

    An output may be any batched function of the mechanism. Targets that no four-bar in the
    box reaches give no solution:

    >>> def crank_plus_rocker(m):
    ...     return np.asarray(m.crank) + np.asarray(m.rocker)
    >>> len(design_to_targets(
    ...     make, ["crank", "rocker"], [(4.0, 6.0), (3.5, 5.5)],
    ...     {"max_Kw": (OUTPUTS["max_Kw"], 1.25), "sum": (crank_plus_rocker, 20.0)}, grid=4))
    0
    """
    names = list(targets)
    free = tuple(free)
    k, m = len(free), len(names)
    if k == 0:
        raise TargetError("free: give at least one free variable")
    if len(set(free)) != k:
        raise TargetError(f"free: the names must be distinct, got {list(free)}")
    if m < k:
        raise TargetError(
            f"{m} target(s) for {k} free variables: the solutions would not be isolated; "
            "fix more variables or add targets"
        )
    box = np.asarray(bounds, dtype=float)
    if box.shape != (k, 2):
        raise TargetError(
            f"bounds: give (lower, upper) for each of {k} free variables, got shape {box.shape}"
        )
    if not np.all(np.isfinite(box)) or np.any(box[:, 1] <= box[:, 0]):
        raise TargetError(
            f"bounds: each lower bound must be below its upper one, got {box.tolist()}"
        )
    if not (tol > 0 and math.isfinite(tol)):
        raise TargetError(f"tol: must be a positive number, got {tol}")
    values = np.array([float(targets[n][1]) for n in names])
    if not np.all(np.isfinite(values)):
        shown = dict(zip(names, values.tolist(), strict=True))
        raise TargetError(f"targets: every value must be finite, got {shown}")
    outputs = [(n, targets[n][0]) for n in names]
    lo, hi = box[:, 0], box[:, 1]
    problem = _Problem(make, outputs, values, lo, hi, where, progress)
    least_squares = m > k

    axes = _grid_axes(lo, hi, grid)
    shape = tuple(a.size for a in axes)
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, k)
    F = problem.values(nodes, 0.0, 0.5).reshape(shape + (m,))
    R = problem.residual(F)
    masked = float(np.mean(~np.all(np.isfinite(F), axis=-1)))

    norm = np.sqrt(np.sum(R * R, axis=-1))
    minima = _local_minima(norm)
    minima = minima[np.argsort(norm.ravel()[minima])]
    node_seeds = nodes[minima]
    if least_squares:
        seeds, fallback = node_seeds, node_seeds
    else:
        cell, cell_fb = _cell_seeds(axes, R)
        seeds = np.concatenate([cell, node_seeds])
        fallback = np.concatenate([cell_fb, node_seeds])
    spacing = np.array([a[1] - a[0] for a in axes])
    # The most promising first: by the misfit at the node each seed falls back on.
    index = np.rint((fallback - lo) / spacing).astype(np.int64)
    index = np.clip(index, 0, np.array(shape) - 1)
    order = np.argsort(norm[tuple(index.T)], kind="stable") if len(seeds) else index[:, 0]
    seeds, fallback = seeds[order], fallback[order]
    keep = _merge(seeds, spacing, SAME_SEED)[:MAX_SEEDS]
    seeds, fallback = seeds[keep], fallback[keep]

    if seeds.shape[0]:
        x, fx, jac = _newton(problem, seeds, fallback, spacing, least_squares, tol)
    else:
        x, fx, jac = np.empty((0, k)), np.empty((0, m)), np.empty((0, m, k))
    r = problem.residual(fx)
    res = np.max(np.abs(r), axis=-1) if m else np.zeros(len(x))
    ok = np.all(np.isfinite(fx), axis=-1)
    if not least_squares:
        ok &= res <= tol
    x, fx, res, jac = x[ok], fx[ok], res[ok], jac[ok]
    order = np.argsort(res, kind="stable")
    x, fx, res, jac = x[order], fx[order], res[order], jac[order]
    keep = _merge(x, hi - lo, SAME_POINT)
    x, fx, res, jac = x[keep], fx[keep], res[keep], jac[keep]
    if not least_squares:
        order = np.lexsort(x.T[::-1]) if len(x) else np.arange(0)
        x, fx, res, jac = x[order], fx[order], res[order], jac[order]

    solutions = []
    if len(x):
        # The Jacobian where the last Newton step did not leave a central-difference one.
        stale = np.flatnonzero(~np.all(np.isfinite(jac), axis=(-1, -2)))
        if stale.size:
            pts = problem.stencil(x[stale])
            fs = problem.values(pts).reshape(stale.size, 2 * k, m)
            jac[stale] = problem.jacobian(x[stale], fx[stale], fs, pts)
        for i in range(len(x)):
            J = jac[i]
            if np.all(np.isfinite(J)):
                sv = np.linalg.svd(J, compute_uv=False)
                sens = np.linalg.pinv(J)
            else:
                sv, sens = np.full(min(m, k), np.nan), np.full((k, m), np.nan)
            cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
            solutions.append(
                TargetSolution(
                    x=x[i].copy(),
                    values={n: float(fx[i, j]) for j, n in enumerate(names)},
                    errors={n: float(fx[i, j] - values[j]) for j, n in enumerate(names)},
                    residual=float(res[i]),
                    jacobian=J,
                    singular_values=sv,
                    condition=cond,
                    sensitivity=sens,
                    mechanism=problem.mechanism(x[i]),
                )
            )
    if progress is not None:
        progress(1.0)
    angle_names = set(angles) | {n for n, fn in outputs if isinstance(fn, Output) and fn.angle}
    return TargetSolutions(
        free=free,
        targets=dict(zip(names, values.tolist(), strict=True)),
        bounds=box,
        grid=shape,
        solutions=tuple(solutions),
        least_squares=least_squares,
        tol=tol,
        evaluated=problem.count,
        seeds=int(seeds.shape[0]),
        masked=masked,
        angles=frozenset(angle_names),
    )


# --- four-bars --------------------------------------------------------------------------------

FOURBAR_DIMENSIONS: dict[str, tuple[str, ...]] = {
    "fourbar": ("crank", "coupler", "rocker", "frame"),
    "spherical-fourbar": ("crank", "coupler", "rocker", "frame"),
}
"""The dimensions :func:`design_fourbar` fixes or frees: paper 003's L1/α1 crank, L2/α2
coupler, L3/α3 output (``rocker``), L4/α4 frame. Planar ones are lengths, spherical ones arcs."""

# Default box for a free arc, and for a free length relative to the largest fixed length.
ARC_MARGIN = math.radians(1.0)
LENGTH_RANGE = (0.1, 5.0)


def _fourbar_maker(family: str, fixed: Mapping[str, float], free: Sequence[str]):
    def make(x: Array) -> Mechanism:
        x = np.asarray(x, dtype=float)
        dims = {n: x[..., i] for i, n in enumerate(free)}
        dims.update({n: np.full(x.shape[:-1], v) for n, v in fixed.items()})
        if family == "spherical-fourbar":
            return SphericalFourBar(
                frame=dims["frame"],
                crank=dims["crank"],
                coupler=dims["coupler"],
                rocker=dims["rocker"],
            )
        frame = dims["frame"]
        b0 = np.stack([frame, np.zeros_like(frame)], axis=-1)
        return FourBar(
            A0=np.zeros(2),
            B0=b0,
            crank=dims["crank"],
            coupler=dims["coupler"],
            rocker=dims["rocker"],
        )

    return make


def design_fourbar(
    family: str,
    fixed: Mapping[str, float],
    free: Sequence[str],
    targets: Mapping[str, float],
    *,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    kind: str | None = None,
    grid: int | Sequence[int] | None = None,
    tol: float = 1e-9,
    degrees: bool = False,
    progress: Progress | None = None,
) -> TargetSolutions:
    """Every planar or spherical four-bar in a box whose named outputs hit their targets.

    Parameters
    ----------
    family : ``"fourbar"`` or ``"spherical-fourbar"``.
    fixed : dimension → value for the fixed links (:data:`FOURBAR_DIMENSIONS`).
    free : the other links, solved for (as many as targets, or fewer: least squares).
    targets : output name (:data:`OUTPUTS`) → value.
    bounds : free dimension → (low, high); by default an arc spans 1°…179° and a length
        0.1…5 times the largest fixed length (a planar four-bar's outputs do not change with
        scale, so at least one length must be fixed).
    kind : only four-bars of this class count (``"double-crank"``, ``"crank-rocker"``, … as
        :func:`linkwright.analysis.fourbar_class` names them).
    degrees : the spherical arcs (fixed and bounds) and the angle targets (``swing``,
        ``gamma_min``, ``gamma_max``) are given in degrees, as the command line takes them.
        The result is in library units either way; its ``report()`` speaks degrees.

    Raises :class:`TargetError` naming an unknown family, dimension, output or class, a
    dimension both fixed and free or neither, or an invalid fixed value.

    Examples
    --------
    A crank-rocker with crank 1 and frame 4 that swings its rocker through 40° with a
    transmission angle never below 40°: one four-bar in the default box (lengths 0.4 to 20):

    >>> found = design_fourbar("fourbar", {"crank": 1, "frame": 4}, ["coupler", "rocker"],
    ...                        {"swing": 40, "gamma_min": 40}, degrees=True, grid=9)
    >>> [s.x.round(6).tolist() for s in found]
    [[4.665093, 3.484139]]
    >>> r = found.report()["solutions"][0]
    >>> {k: round(v, 9) for k, v in r["values"].items()}, round(r["condition"], 3)
    ({'swing': 40.0, 'gamma_min': 40.0}, 1.819)

    Paper 003's spherical example (α1 = 80°, α4 = 10°, max|Kε| = 1.47, max|Kp| = 1.49) is
    :func:`linkwright.papers.p003.synthesis_example`.

    A link that is no link is an error, in the units it was given:

    >>> design_fourbar("spherical-fourbar", {"crank": 80, "frame": 190, "coupler": 60},
    ...                ["rocker"], {"max_Kw": 1.2}, degrees=True)
    Traceback (most recent call last):
    ...
    linkwright.synthesis.targets.TargetError: frame: must be an arc in (0°, 180°), got 190
    """
    if family not in FOURBAR_DIMENSIONS:
        raise TargetError(f"family: {family!r} is not one of {sorted(FOURBAR_DIMENSIONS)}")
    dims = FOURBAR_DIMENSIONS[family]
    spherical = family == "spherical-fourbar"
    free = tuple(free)
    unknown = [n for n in [*fixed, *free] if n not in dims]
    if unknown:
        raise TargetError(f"{unknown[0]!r} is not a dimension of a {family}; one of {list(dims)}")
    both = sorted(set(fixed) & set(free))
    if both:
        raise TargetError(f"{both[0]!r} is both fixed and free")
    missing = [n for n in dims if n not in fixed and n not in free]
    if missing:
        raise TargetError(f"{', '.join(missing)}: neither fixed nor free; give a value or free it")
    bad = [n for n in targets if n not in OUTPUTS]
    if bad:
        raise TargetError(f"unknown output {bad[0]!r}; one of {', '.join(OUTPUTS)}")
    classes = FOURBAR_CLASSES
    if kind is not None and kind not in classes:
        raise TargetError(f"kind: unknown class {kind!r}; one of {', '.join(classes)}")

    to_rad = math.radians if degrees else float
    fixed_v = {n: (to_rad(v) if spherical else float(v)) for n, v in fixed.items()}
    for n, v in fixed_v.items():
        if not math.isfinite(v) or v <= 0 or (spherical and v >= math.pi):
            shown = math.degrees(v) if spherical else v
            what = "an arc in (0°, 180°)" if spherical else "a positive length"
            raise TargetError(f"{n}: must be {what}, got {shown:g}")
    box = []
    given = dict(bounds or {})
    extra = [n for n in given if n not in free]
    if extra:
        raise TargetError(f"bounds: {extra[0]!r} is not a free dimension ({list(free)})")
    for n in free:
        if n in given:
            lo, hi = (to_rad(b) if spherical else float(b) for b in given[n])
            if spherical and (lo <= 0 or hi >= math.pi):
                raise TargetError(
                    f"bounds: {n}'s arcs must lie strictly between 0° and 180°, got "
                    f"{math.degrees(lo):g}° to {math.degrees(hi):g}°"
                )
            if not spherical and lo <= 0:
                raise TargetError(f"bounds: {n}'s lengths must be positive, got {lo:g} to {hi:g}")
        elif spherical:
            lo, hi = ARC_MARGIN, math.pi - ARC_MARGIN
        else:
            if not fixed_v:
                raise TargetError(
                    "fix at least one length of a planar four-bar, or give bounds for every "
                    "free one: its outputs do not change with scale"
                )
            s = max(fixed_v.values())
            lo, hi = LENGTH_RANGE[0] * s, LENGTH_RANGE[1] * s
        box.append((lo, hi))
    aims = {}
    for n, v in targets.items():
        out = OUTPUTS[n]
        aims[n] = (out, to_rad(v) if (out.angle and degrees) else float(v))
    where = None
    if kind is not None:

        def where(mech: Mechanism) -> NDArray[np.bool_]:
            return np.asarray(fourbar_class(mech)) == kind

    return design_to_targets(
        _fourbar_maker(family, fixed_v, free),
        free,
        box,
        aims,
        grid=grid,
        tol=tol,
        where=where,
        angles=free if spherical else (),
        progress=progress,
    )

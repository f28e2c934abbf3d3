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

import math
from collections.abc import Callable, Collection, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis import fourbar_class
from linkwright.analysis.planar import FOURBAR_CLASSES
from linkwright.mechanisms import FourBar, SphericalFourBar
from linkwright.mechanisms.base import Mechanism
from linkwright.synthesis.target_newton import CELL_MARGIN as CELL_MARGIN
from linkwright.synthesis.target_newton import CHUNK as CHUNK
from linkwright.synthesis.target_newton import DAMPING as DAMPING
from linkwright.synthesis.target_newton import LEAST_SQUARES_SEARCH as LEAST_SQUARES_SEARCH
from linkwright.synthesis.target_newton import LINE_SEARCH as LINE_SEARCH
from linkwright.synthesis.target_newton import MAX_ITERATIONS as MAX_ITERATIONS
from linkwright.synthesis.target_newton import (
    MAX_SEEDS,
    SAME_POINT,
    SAME_SEED,
    TargetProblem,
    cell_seeds,
    grid_axes,
    local_minima,
    merge_points,
    newton,
)
from linkwright.synthesis.target_newton import SAME_ROOT as SAME_ROOT
from linkwright.synthesis.target_newton import STALL_FACTOR as STALL_FACTOR
from linkwright.synthesis.target_newton import STALL_ROUNDS as STALL_ROUNDS
from linkwright.synthesis.target_newton import STEP as STEP
from linkwright.synthesis.target_outputs import (
    OUTPUTS,
    Output,
    TargetError,
    TargetSolution,
    TargetSolutions,
)

# A name imported `as` itself moved to a sibling module and is re-exported for older imports;
# a constant among them is read where it lives (set it there, not here).
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
    problem = TargetProblem(make, outputs, values, lo, hi, where, progress)
    least_squares = m > k

    axes = grid_axes(lo, hi, grid)
    shape = tuple(a.size for a in axes)
    nodes = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, k)
    F = problem.values(nodes, 0.0, 0.5).reshape(shape + (m,))
    R = problem.residual(F)
    masked = float(np.mean(~np.all(np.isfinite(F), axis=-1)))

    norm = np.sqrt(np.sum(R * R, axis=-1))
    minima = local_minima(norm)
    minima = minima[np.argsort(norm.ravel()[minima])]
    node_seeds = nodes[minima]
    if least_squares:
        seeds, fallback = node_seeds, node_seeds
    else:
        cell, cell_fb = cell_seeds(axes, R)
        seeds = np.concatenate([cell, node_seeds])
        fallback = np.concatenate([cell_fb, node_seeds])
    spacing = np.array([a[1] - a[0] for a in axes])
    # The most promising first: by the misfit at the node each seed falls back on.
    index = np.rint((fallback - lo) / spacing).astype(np.int64)
    index = np.clip(index, 0, np.array(shape) - 1)
    order = np.argsort(norm[tuple(index.T)], kind="stable") if len(seeds) else index[:, 0]
    seeds, fallback = seeds[order], fallback[order]
    keep = merge_points(seeds, spacing, SAME_SEED)[:MAX_SEEDS]
    seeds, fallback = seeds[keep], fallback[keep]

    if seeds.shape[0]:
        x, fx, jac = newton(problem, seeds, fallback, spacing, least_squares, tol)
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
    keep = merge_points(x, hi - lo, SAME_POINT)
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


def _fourbar_maker(
    family: str, fixed: Mapping[str, float], free: Sequence[str]
) -> Callable[[Array], Mechanism]:
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

    Returns
    -------
    TargetSolutions
        The four-bars found, best first, each with the outputs it reaches; empty where none
        in the box meets the targets.

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
    linkwright.synthesis.target_outputs.TargetError: frame: must be an arc in (0°, 180°), got 190
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
            # _fourbar_maker builds only these two families.
            assert isinstance(mech, FourBar | SphericalFourBar)
            same: NDArray[np.bool_] = np.asarray(fourbar_class(mech)) == kind
            return same

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

"""Path synthesis by optimisation: a linkage whose traced point passes through target points.

:func:`fit_path` searches the dimensions *and* the placement of a four-bar, slider-crank,
geared five-bar or spherical four-bar so that its traced point P comes as close as it can to N
target points, in the sense of the error

    E = Σ_i |P(θ_i) − T_i|²

(the sum of squared distances; on the sphere, of squared chords between unit vectors), where
θ_i is the input at which the linkage reaches target i. How the θ_i are chosen is the *timing*:

``"prescribed"``
    The user gives the crank angles, measured from the frame line (A0→B0; for the slider-crank
    the guide's direction; on the sphere the frame circle towards B0, paper 000's θ2), as in
    the classical benchmarks (Cabrera, Simon & Prado, *Mech. Mach. Theory* 37, 2002; Acharyya
    & Mandal, *Mech. Mach. Theory* 44, 2009): the fitted linkage's absolute inputs are these
    plus its frame angle. The frame's place and angle are free unless bounded.
``"free"``
    The θ_i are unknowns constrained to move one way: a start angle plus increments ≥ 0 (all
    turned in one sense, either), in all at most one period of the input (one turn; more for
    a geared five-bar at a fractional ratio).
``"none"``
    Nearest-point fit: each target is matched to the point of the traced curve nearest to it,
    in any order. For ``closed`` targets the curve is also kept from wandering off: each of 64
    samples of one turn of the curve adds (N/64)·max(0, d − h)² to what the search minimises,
    d its distance to the nearest target and h = 0.6 × the largest nearest-neighbour spacing
    of the targets (a one-sided, tolerant Chamfer term: a curve that runs between
    neighbouring targets costs nothing). The reported error stays E.

In every timing the targets are reached on the linkage's own assembly mode without passing a
limit position (the input's path from one target to the next lies on one admissible arc), and
``closed`` targets ask for an input that turns fully, so that the curve closes after one turn.

The search is global then local, and repeats until the error target, the time budget or the
evaluation budget is reached:

1. A differential evolution (JADE's current-to-pbest/1 with adaptive F and CR: J. Zhang &
   A. C. Sanderson, *IEEE Trans. Evol. Comput.* 13, 2009; Deb's feasibility rules for the
   constraints: K. Deb, *Comput. Methods Appl. Mech. Eng.* 186, 2000) evaluates each
   generation as one batched mechanism, its first generation screened from ten times as many
   random members. With free or no timing each member's curve is sampled at 96 inputs and the
   targets matched to its chords (in order by a dynamic programme, or each to the nearest), so
   that the population searches the dimensions only.
2. From the 16 best distinct members of the last generation and 16 of the first (which
   still spans more basins), Levenberg–Marquardt with geodesic acceleration
   (Transtrum & Sethna 2012) adjusts dimensions, placement and the θ_i together, all starts in
   one batched evaluation per iteration; the best four continue, and the best of all is
   finished by :func:`scipy.optimize.least_squares`. Constraints enter as weighted hinge
   residuals with a little to spare; that the input's path meets no limit position is exact
   for the four-bars and the slider-crank (the dyad's margin is least at an extreme of the
   input's cosine or sine on the path), sampled for the geared five-bar.
3. The best candidates are rebuilt as named-family mechanisms, solved by the plan-based engine
   at the reported inputs (a no-timing fit first moves each input to the nearest point of the
   whole curve), their errors recomputed from those positions, their input arcs taken from
   :func:`~linkwright.mechanisms.input_range` and their constraints checked with
   :mod:`linkwright.analysis`; the first that passes is returned, with those numbers.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import minimize_scalar

from linkwright.analysis.general import dyad_transmission_angles
from linkwright.analysis.planar import fourbar_class, slidercrank_class, transmission_extremes
from linkwright.mechanisms import (
    FourBar,
    Mechanism,
    SliderCrank,
    SphericalFourBar,
    circuit,
    input_range,
    solve,
)
from linkwright.synthesis.path_families import Model
from linkwright.synthesis.path_models import GenericModel, ModelError, model_for
from linkwright.synthesis.path_problem import Candidate, Problem
from linkwright.synthesis.path_search import Evolution, LocalSearch
from linkwright.synthesis.path_spec import BETWEEN as BETWEEN
from linkwright.synthesis.path_spec import COVERAGE as COVERAGE
from linkwright.synthesis.path_spec import EXTRA as EXTRA
from linkwright.synthesis.path_spec import (
    FAMILIES,
    FURTHER,
    GENERATIONS,
    KEEP,
    LM_FURTHER,
    LM_ITERATIONS,
    MIN_POINTS,
    SPHERE_TOL,
    TIMINGS,
    Array,
    NoFeasibleLinkage,
    PathConstraints,
    PathFit,
    PathSynthesisError,
)
from linkwright.synthesis.path_spec import GEODESIC_RATIO as GEODESIC_RATIO
from linkwright.synthesis.path_spec import GEODESIC_STEP as GEODESIC_STEP
from linkwright.synthesis.path_spec import GRID as GRID
from linkwright.synthesis.path_spec import MARGIN as MARGIN
from linkwright.synthesis.path_spec import SAMPLED_MARGIN as SAMPLED_MARGIN
from linkwright.synthesis.path_spec import SCREEN as SCREEN
from linkwright.synthesis.path_spec import STARTS as STARTS
from linkwright.synthesis.path_spec import STEP as STEP
from linkwright.synthesis.path_spec import WEIGHT as WEIGHT
from linkwright.synthesis.path_verify import in_one_arc as _in_one_arc
from linkwright.synthesis.path_verify import nearest_on_circuit, started, verify_generic

# A name imported `as` itself moved to a sibling module and is re-exported for older imports;
# a constant among them is read where it lives (set it there, not here).
__all__ = [
    "FAMILIES",
    "TIMINGS",
    "NoFeasibleLinkage",
    "PathConstraints",
    "PathFit",
    "PathSynthesisError",
    "fit_path",
]


# ------------------------------------------------------------------------------------------
# Input checks
# ------------------------------------------------------------------------------------------


def _targets(model: Model | GenericModel, points: ArrayLike) -> Array:
    try:
        pts = np.array(points, dtype=float)
    except (TypeError, ValueError):
        raise PathSynthesisError("points: must be an array of numbers") from None
    d = model.dim
    if pts.ndim != 2 or pts.shape[1] != d:
        what = "[x, y] points (shape (N, 2))" if d == 2 else "unit vectors (shape (N, 3))"
        raise PathSynthesisError(f"points: {model.family} needs {what}, got shape {pts.shape}")
    if not np.all(np.isfinite(pts)):
        rows = np.flatnonzero(~np.all(np.isfinite(pts), axis=1)).tolist()
        raise PathSynthesisError(f"points: must be finite, rows {rows[:5]} are not")
    if len(pts) < MIN_POINTS:
        raise PathSynthesisError(
            f"points: at least {MIN_POINTS} target points are needed, got {len(pts)}"
        )
    if d == 3:
        lengths = np.linalg.norm(pts, axis=1)
        off = np.flatnonzero(np.abs(lengths - 1.0) > SPHERE_TOL)
        if off.size:
            raise PathSynthesisError(
                f"points: targets on the sphere must be unit vectors (to {SPHERE_TOL}); "
                f"rows {off[:5].tolist()} have lengths {lengths[off[:5]].round(6).tolist()} "
                "(for points on another sphere, fit_sphere(points).directions from "
                "linkwright.geometry.sphere_fit)"
            )
        pts = pts / lengths[:, None]
    if _diameter(pts) <= 1e-9 * max(1.0, float(np.max(np.abs(pts)))):
        raise PathSynthesisError("points: the targets all coincide; there is no path to fit")
    return pts


def _diameter(pts: Array) -> float:
    diff = pts[:, None, :] - pts[None, :, :]
    return float(np.sqrt(np.max(np.sum(diff * diff, axis=-1))))


def _bounds(
    model: Model | GenericModel, given: Mapping[str, Any] | None, size: float, centre: Array
) -> dict[str, tuple[float, float]]:
    out = model.default_bounds(size, centre)
    if not given:
        return out
    known = set(out) | {"length"}
    if model.space == "sphere":
        known -= {"lon", "sinlat", "spin"}
    for key, value in given.items():
        if key not in known:
            raise PathSynthesisError(
                f"bounds: unknown parameter {key!r} for {model.family}; "
                f"known: {', '.join(sorted(known))}"
            )
        try:
            lo, hi = (float(v) for v in value)
        except (TypeError, ValueError):
            raise PathSynthesisError(
                f"bounds[{key!r}]: must be a pair (low, high), got {value!r}"
            ) from None
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
            raise PathSynthesisError(f"bounds[{key!r}]: need finite low ≤ high, got ({lo}, {hi})")
        for name in model.lengths if key == "length" else (key,):
            out[name] = _checked_bound(model, name, lo, hi, size)
    return out


def _checked_bound(
    model: Model | GenericModel, name: str, lo: float, hi: float, size: float
) -> tuple[float, float]:
    if name in model.lengths:
        if model.space == "sphere":
            if lo >= np.pi or hi <= 0:
                raise PathSynthesisError(
                    f"bounds[{name!r}]: a spherical link's arc lies in (0, π) radians, "
                    f"got ({lo}, {hi})"
                )
            tiny = 1e-6
            return (max(lo, tiny), min(hi, np.pi - tiny))
        if hi <= 0:
            raise PathSynthesisError(f"bounds[{name!r}]: a length must be positive, got {hi}")
        return (max(lo, 1e-6 * size), hi)
    if name in getattr(model, "closed_arcs", ("point_arc",)) and (lo < 0 or hi > np.pi):
        raise PathSynthesisError(f"bounds[{name!r}]: must lie in [0, π], got ({lo}, {hi})")
    if name in getattr(model, "ratios", ("ratio",)) and lo <= 0 <= hi:
        raise PathSynthesisError(
            f"bounds[{name!r}]: the gear ratio must not be 0, so its bounds cannot contain 0, "
            f"got ({lo}, {hi})"
        )
    return (lo, hi)


def _constraints(
    model: Model | GenericModel, given: PathConstraints | Mapping[str, Any] | None
) -> PathConstraints:
    if given is None:
        return PathConstraints()
    if isinstance(given, Mapping):
        unknown = set(given) - {"classes", "full_turn", "min_transmission"}
        if unknown:
            raise PathSynthesisError(
                f"constraints: unknown keys {sorted(unknown)}; "
                "known: classes, full_turn, min_transmission"
            )
        classes = given.get("classes", ())
        given = PathConstraints(
            classes=(classes,) if isinstance(classes, str) else tuple(classes),
            full_turn=bool(given.get("full_turn", False)),
            min_transmission=float(given.get("min_transmission", 0.0)),
        )
    for c in given.classes:
        if c not in model.classes:
            allowed = ", ".join(model.classes) if model.classes else "none (no classes apply)"
            raise PathSynthesisError(
                f"constraints.classes: {c!r} is not a class of {model.family}; allowed: {allowed}"
            )
    mu = given.min_transmission
    if not (math.isfinite(mu) and 0.0 <= mu < np.pi / 2):
        raise PathSynthesisError(
            f"constraints.min_transmission: must lie in [0, π/2) radians, got {mu}"
        )
    if mu > 0 and isinstance(model, GenericModel) and not model.plan.dyads:
        raise PathSynthesisError(
            f"constraints.min_transmission: the {model.family} as given has no dyad, so no "
            "transmission angle to bound"
        )
    return given


# ------------------------------------------------------------------------------------------
# Verification with the plan-based engine and the analysis module
# ------------------------------------------------------------------------------------------


def _verify(p: Problem, cand: Candidate) -> tuple[dict[str, Any] | None, str]:
    if isinstance(p.model, GenericModel):
        return verify_generic(p, cand)
    m = p.model
    mech, named, R = m.placed(cand.shape, cand.assembly, cand.pose)
    psi = 0.0 if m.space == "sphere" else float(cand.pose[2])
    rel = np.asarray(cand.rel, float).copy()
    arcs = input_range(named)
    if bool(np.asarray(arcs.never)):
        return None, "the linkage never assembles"
    full = bool(np.asarray(arcs.full))
    if p.timing == "none" and full:
        rel = _reproject(p, mech, psi, rel)
    inputs = rel + psi
    motion = solve(mech, inputs, order=0)
    if not motion.valid.all():
        return None, "a target's input cannot be assembled"
    reached = motion.positions["P"]
    dist = np.sqrt(np.sum((reached - p.targets) ** 2, axis=-1))
    if not full:
        lo, hi = np.asarray(arcs.lo).ravel(), np.asarray(arcs.hi).ravel()
        if not _in_one_arc(inputs.min(), inputs.max(), lo, hi, float(np.asarray(arcs.period))):
            return None, "the input passes a limit position between targets"
    if p.timing == "free":
        steps = np.diff(rel) * np.sign(np.sum(np.diff(rel)) or 1.0)
        if np.any(steps < -1e-12) or np.sum(np.abs(np.diff(rel))) > p.period + 1e-9:
            return None, "the free timing is not monotonic within one turn"
    c = p.cons
    if c.classes:
        if isinstance(named, SliderCrank):
            name = str(slidercrank_class(named))
        else:
            # Only the four-bars and the slider-crank have classes (checked with the bounds).
            assert isinstance(named, FourBar | SphericalFourBar)
            name = str(fourbar_class(named))
        if name not in c.classes:
            return None, f"its class is {name}, not one of {list(c.classes)}"
    if p.full_turn and not full:
        return None, "its input does not turn fully"
    if p.mu > 0:
        if m.family == "geared-fivebar":
            gam = dyad_transmission_angles(named, circuit(named, 2048, order=0))["C"]
            lo_g, hi_g = float(np.nanmin(gam)), float(np.nanmax(gam))
        else:
            tx = transmission_extremes(named)
            lo_g, hi_g = float(tx["min"]), float(tx["max"])
        if lo_g < p.mu or hi_g > np.pi - p.mu:
            return None, (
                f"its transmission angle spans [{np.degrees(lo_g):.3f}°, "
                f"{np.degrees(hi_g):.3f}°], outside [{np.degrees(p.mu):.3f}°, "
                f"{180 - np.degrees(p.mu):.3f}°]"
            )
    mech, named = started(mech, named, inputs)
    branches = None
    if p.timing == "none" and not full:
        # The circuit the answer runs comes back on its other branch: a target may be nearer.
        inputs, reached, dist, branches = nearest_on_circuit(mech, p.targets, inputs, reached, dist)
        rel = inputs - psi
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
        branches=branches,
    ), ""


def _reproject(p: Problem, mech: Mechanism, psi: float, rel: Array) -> Array:
    """Move each target's input to its nearest point on the whole curve (a full turn)."""
    dense = np.linspace(0.0, p.period, 2048, endpoint=False)
    curve = solve(mech, dense + psi, order=0).positions["P"]
    here = solve(mech, rel + psi, order=0).positions["P"]
    out = rel.copy()
    for i, t in enumerate(p.targets):
        d_dense = np.sum((curve - t) ** 2, axis=-1)
        j = int(np.nanargmin(d_dense))
        now = float(np.sum((here[i] - t) ** 2))
        if not d_dense[j] < now * (1 - 1e-9):
            continue
        step = dense[1] - dense[0]

        def d2(x: float, t: Array = t) -> float:
            q = solve(mech, [x + psi], order=0).positions["P"][0]
            return float(np.sum((q - t) ** 2)) if np.all(np.isfinite(q)) else np.inf

        r = minimize_scalar(
            d2,
            bounds=(dense[j] - step, dense[j] + step),
            method="bounded",
            options={"xatol": 1e-13},
        )
        if r.fun < now:
            out[i] = r.x
    return out


def _seed_genes(p: Problem, seeds: list[tuple[Array, dict[str, float], float]]) -> Array | None:
    """Genes of the members that start from the template (pose, shape and configuration), with
    the free parameters in the search's order and the configuration's gene in its share."""
    if not seeds:
        return None
    rows = []
    k = len(getattr(p.model, "combos", (0,)))
    for pose, shape, code in seeds:
        full = dict(zip(p.model.pose_names, np.asarray(pose, float), strict=True), **shape)
        values = np.array([full.get(n, 0.0) for n in p.names])  # a free start: 0
        rows.append(np.r_[values[p.free], (2.0 * code + 1.0) / k - 1.0])
    return np.array(rows)


# ------------------------------------------------------------------------------------------
# The public verb
# ------------------------------------------------------------------------------------------


def fit_path(
    family: str,
    points: ArrayLike,
    *,
    angles: ArrayLike | None = None,
    timing: str | None = None,
    closed: bool = False,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    constraints: PathConstraints | Mapping[str, Any] | None = None,
    target: float | None = None,
    seed: int = 0,
    budget: float = 10.0,
    max_evaluations: int | None = None,
    population: int | None = None,
    progress: Callable[[float], None] | None = None,
    template: Mechanism | None = None,
    free_start: bool = False,
) -> PathFit:
    """Fit a linkage's traced point to target points (see the module docstring for the method).

    Parameters
    ----------
    family : ``"fourbar"``, ``"slidercrank"``, ``"geared-fivebar"`` or ``"spherical-fourbar"``.
    points : (N, 2) target points, or (N, 3) unit vectors for the spherical four-bar (within
        1 % of unit length; they are normalised). N ≥ 3.
    angles : (N,) crank angles (radians) from the frame line at which each target must be
        reached; only with prescribed timing.
    free_start : with prescribed timing, the angles prescribe the input's steps only: the
        inputs are ``angles`` + s, the offset s fitted with the dimensions (Kunjur and
        Krishnamurty's 18-point problem leaves its start angle free so).
    timing : ``"prescribed"``, ``"free"`` or ``"none"``; default prescribed when ``angles``
        are given, else free.
    closed : the targets lie on a closed curve: the input must turn fully (and the no-timing
        fit keeps the whole curve near the targets).
    bounds : {parameter: (low, high)} over the defaults (lengths 0.02–5 × the targets'
        diameter D, crank pivot within 3 D of their centre, coupler point and slider offset
        within 5 D and 3 D; arcs 2°–178°).
        Parameters: planar ``x``, ``y`` (the crank pivot A0) and ``frame_angle``; the family's
        dimensions (four-bar ``frame``, ``crank``, ``coupler``, ``rocker``, ``u``, ``v``;
        slider-crank ``offset``, ``crank``, ``rod``, ``u``, ``v``; geared five-bar ``frame``,
        ``crank1``, ``crank2``, ``link1``, ``link2``, ``gear_phase`` (θ2 − θ1 ratio offset at
        θ1 on the frame line), ``ratio`` (default fixed at −1), ``u``, ``v``; spherical
        ``frame``, ``crank``, ``coupler``, ``rocker``, ``point_arc``, ``point_angle``) and
        ``length`` for every link length (arc) at once. Equal bounds fix a parameter.
    constraints : :class:`PathConstraints` or a mapping with its fields.
    target : stop once the error is at most this; default N·(1e-8·D)², an exact fit.
    seed : seeds the search: the same seed and budgets give the same result (a time budget
        can stop two runs at different points; ``max_evaluations`` cannot).
    budget : seconds the search may take (the final verification comes on top).
    max_evaluations : stop after this many mechanism evaluations.
    population : members per generation; default max(32, 8 × unknowns).
    progress : called with the fraction of the budget spent, in [0, 1].

    Returns
    -------
    PathFit

    Raises
    ------
    PathSynthesisError
        For bad input: an unknown family or timing, too few or non-finite points, points off
        the unit sphere, ``angles`` of the wrong length or given without prescribed timing,
        unknown or inverted bounds, unknown constraint classes, a budget that is not positive.
    NoFeasibleLinkage
        When no linkage met the constraints within the budget.

    Examples
    --------
    Five points of a crank-rocker's coupler curve at known crank angles come back exactly:

    >>> from linkwright.mechanisms import FourBar, solve
    >>> true = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=4, rocker=3.5, u=2, v=1)
    >>> theta = np.radians([0, 60, 120, 180, 240])
    >>> pts = solve(true, theta).positions["P"]
    >>> fit = fit_path("fourbar", pts, angles=theta, budget=20, seed=1)
    >>> bool(fit.rms < 1e-8), fit.stopped
    (True, 'target')
    >>> bool(np.allclose(solve(fit.mechanism, fit.inputs).positions["P"], pts, atol=1e-7))
    True

    Too few points are refused with the reason:

    >>> fit_path("fourbar", [[0, 0], [1, 0]], timing="free")
    Traceback (most recent call last):
    ...
    linkwright.synthesis.path_spec.PathSynthesisError: points: at least 3 target points are \
needed, got 2

    A linkage that cannot meet its constraints is an error, not a NaN: a slider-crank whose
    crank is longer than its rod never turns fully.

    >>> fit_path("slidercrank", pts, angles=theta, bounds={"crank": (2, 3), "rod": (0.5, 1)},
    ...          constraints={"full_turn": True}, max_evaluations=2000)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.synthesis.path_spec.NoFeasibleLinkage: no slidercrank meeting the constraints and \
assembling at every target was found ...
    """
    t0 = time.perf_counter()
    if family not in FAMILIES:
        raise PathSynthesisError(
            f"family: unknown {family!r}; path synthesis knows {', '.join(FAMILIES)}"
        )
    try:
        model = model_for(family, template)
    except (ModelError, ValueError) as exc:
        raise PathSynthesisError(str(exc)) from None
    if timing is None:
        timing = "prescribed" if angles is not None else "free"
    if timing not in TIMINGS:
        raise PathSynthesisError(f"timing: unknown {timing!r}; known: {', '.join(TIMINGS)}")
    T = _targets(model, points)
    n = len(T)
    ang = None
    if timing == "prescribed":
        if angles is None:
            raise PathSynthesisError("angles: prescribed timing needs one crank angle per point")
        ang = np.array(angles, dtype=float).ravel()
        if ang.shape != (n,):
            raise PathSynthesisError(
                f"angles: need one crank angle per point ({n}), got {ang.size}"
            )
        if not np.all(np.isfinite(ang)):
            raise PathSynthesisError("angles: must be finite")
    elif angles is not None:
        raise PathSynthesisError(f"angles: given, but the timing is {timing!r} (not prescribed)")
    if free_start and timing != "prescribed":
        raise PathSynthesisError(
            f"free_start: frees where prescribed angles start; the timing is {timing!r}"
        )
    if not (isinstance(budget, int | float) and budget > 0 and math.isfinite(budget)):
        raise PathSynthesisError(f"budget: must be a positive number of seconds, got {budget!r}")
    if max_evaluations is not None and max_evaluations < 1:
        raise PathSynthesisError(f"max_evaluations: must be ≥ 1, got {max_evaluations}")
    size = _diameter(T)
    centre = 0.5 * (T.min(axis=0) + T.max(axis=0))
    bnds = _bounds(model, bounds, size, centre)
    cons = _constraints(model, constraints)
    problem = Problem(model, T, ang, timing, closed, bnds, cons, size, free_start)
    goal = n * (1e-8 * size) ** 2 if target is None else float(target)
    if not (goal >= 0 and math.isfinite(goal)):
        raise PathSynthesisError(f"target: must be a non-negative error, got {target!r}")
    unknowns = int(problem.free.sum()) + 1
    scale = getattr(model, "search_scale", 1.0)
    if population is not None:
        pop = int(population)
    else:
        pop = max(32, 8 * unknowns) if scale == 1.0 else max(12, int(8 * unknowns * scale))
    if template is not None and isinstance(model, GenericModel):
        problem.seeds = _seed_genes(problem, model.seeds(T, anchor=problem.anchor, angles=ang))
    if pop < 8:
        raise PathSynthesisError(f"population: need at least 8 members, got {pop}")
    rng = np.random.default_rng(seed)
    deadline = t0 + budget
    history: list[tuple[float, int, float]] = []
    candidates: list[Candidate] = []
    best = np.inf
    best_objective = np.inf
    stopped = "budget"

    def spent() -> float:
        f = (time.perf_counter() - t0) / budget
        if max_evaluations:
            f = max(f, problem.evaluations / max_evaluations)
        return min(f, 1.0)

    def consider(cand: Candidate) -> None:
        """Keep a candidate; if it may beat the best, verify it now (about a millisecond), so
        that the history and the stop on the target speak of verified linkages only."""
        nonlocal best
        candidates.append(cand)
        if cand.error < best:
            result, _ = _verify(problem, cand)
            if result is not None and result["error"] < best:
                best = result["error"]
                history.append((time.perf_counter() - t0, problem.evaluations, best))

    def out_of_budget() -> str | None:
        if best <= goal:
            return "target"
        if max_evaluations is not None and problem.evaluations >= max_evaluations:
            return "evaluations"
        if time.perf_counter() >= deadline:
            return "budget"
        return None

    generations = GENERATIONS if scale == 1.0 else max(10, int(GENERATIONS * scale))
    while True:
        evo = Evolution(problem, pop, rng)
        last, flat = np.inf, 0
        for _ in range(generations):
            if out_of_budget():
                break
            evo.step()
            e, _ = evo.best()
            flat = flat + 1 if not e < last * (1 - 1e-4) else 0
            last = min(last, e)
            if progress is not None:
                progress(spent())
            if flat >= 25:
                break
        # The best few distinct members (feasible first) start a local search, all at once:
        # from the evolved generation, and as many from the first, whose members are spread
        # over more basins.
        X0, err0, viol0 = evo.first
        pool = np.concatenate([evo.X, X0])
        errs, viols = np.concatenate([evo.err, err0]), np.concatenate([evo.viol, viol0])
        order = np.concatenate([evo.order(), len(evo.X) + np.lexsort((err0, viol0))])
        full, asm = problem.full_params(pool[order])
        span = np.where(problem.hi > problem.lo, problem.hi - problem.lo, 1.0)
        chosen: list[int] = []
        quotas = (problem.starts, problem.extra)
        parts = (range(len(evo.X)), range(len(evo.X), len(order)))
        for part, quota in zip(parts, quotas, strict=True):
            taken = 0
            for i in part:
                if taken == quota:
                    break
                if all(
                    np.max(np.abs(full[i] - full[j]) / span) > 0.02 or asm[i] != asm[j]
                    for j in chosen
                ):
                    chosen.append(i)
                    taken += 1
        starts, senses = [], []
        for i in chosen:
            pose, shape = problem.split(full[i : i + 1])
            a = asm[i : i + 1]
            if problem.timing == "prescribed":
                assert problem.angles is not None  # a prescribed timing comes with its angles
                rel = problem.angles + problem.offsets(full[i : i + 1])[0]
                sense = 1.0
            else:
                rel, sense = problem.assign(pose, shape, a)
            e0 = float(errs[order[i]])
            shape1 = {k: float(v[0]) for k, v in shape.items()}
            starts.append(Candidate(e0, e0, pose[0], shape1, float(a[0]), rel))
            senses.append(sense)
        if viols[order[0]] == 0:
            # The evolution's best stands as a candidate even if no local search follows.
            consider(starts[0])
        stopped_now = out_of_budget()
        if stopped_now in ("target", "evaluations"):
            stopped = stopped_now
            break
        local = LocalSearch(problem, starts, senses, deadline, goal)
        local.levenberg_marquardt(LM_ITERATIONS)
        found = [local.candidate(k) for k in range(len(starts))]
        # The most promising few go on: valleys near a change point or a cusp are long.
        top = [k for k in np.argsort(local.best_obj)[:FURTHER] if found[k] is not None]
        if top:
            more = LocalSearch(
                problem, [found[k] for k in top], [senses[k] for k in top], deadline, goal
            )
            more.levenberg_marquardt(LM_FURTHER)
            k = int(np.argmin(more.best_obj))
            if more.best_obj[k] < best_objective * (1 + 1e-9) and not more.reached():
                more.polish(k)
            found += [more.candidate(k) for k in range(len(top))]
        for cand in found:
            if cand is not None:
                consider(cand)
                best_objective = min(best_objective, cand.objective)
        # Only the best candidates are ever verified: keep the list short.
        candidates = sorted(candidates, key=lambda c: c.objective)[:KEEP]
        if progress is not None:
            progress(spent())
        stopped_now = out_of_budget()
        if stopped_now:
            stopped = stopped_now
            break
    if progress is not None:
        progress(1.0)
    candidates.sort(key=lambda c: c.objective)
    reasons = []
    for cand in candidates:
        result, why = _verify(problem, cand)
        if result is not None:
            return PathFit(
                family=family,
                timing=timing,
                elapsed=time.perf_counter() - t0,
                evaluations=problem.evaluations,
                history=tuple(history),
                stopped=stopped,
                **result,
            )
        reasons.append(why)
    detail = (
        f" (the best candidates failed: {'; '.join(dict.fromkeys(reasons))})" if reasons else ""
    )
    raise NoFeasibleLinkage(
        f"no {family} meeting the constraints and assembling at every target was found in "
        f"{time.perf_counter() - t0:.1f} s and {problem.evaluations} evaluations{detail}; "
        "widen the bounds, relax the constraints or give a larger budget"
    )

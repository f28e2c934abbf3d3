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

import contextlib
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares, minimize_scalar

from linkwright.analysis.general import dyad_transmission_angles
from linkwright.analysis.planar import fourbar_class, slidercrank_class, transmission_extremes
from linkwright.engine.circuits import MAX_TURNS
from linkwright.mechanisms import FAMILIES as REGISTERED
from linkwright.mechanisms import Mechanism, circuit, input_range, solve
from linkwright.synthesis.path_families import (
    TWO_PI,
    Model,
    path_margin,
    rodrigues,
    sampled_gaps,
    sphere_rotation,
    to_user,
)
from linkwright.synthesis.path_models import GenericModel, ModelError, model_for
from linkwright.synthesis.path_verify import in_one_arc as _in_one_arc
from linkwright.synthesis.path_verify import verify_generic

__all__ = [
    "FAMILIES",
    "TIMINGS",
    "NoFeasibleLinkage",
    "PathConstraints",
    "PathFit",
    "PathSynthesisError",
    "fit_path",
]

Array = NDArray[np.float64]

FAMILIES = tuple(REGISTERED)
"""The families :func:`fit_path` synthesises: every registered family, the four of
:data:`~linkwright.synthesis.path_families.MODELS` by their hand-written models, the others by
:class:`~linkwright.synthesis.path_models.GenericModel`."""
TIMINGS = ("prescribed", "free", "none")
"""The timings :func:`fit_path` knows (see the module docstring)."""

MIN_POINTS = 3
SPHERE_TOL = 1e-2
"""Target vectors whose length differs from 1 by more than this are refused, not normalised."""
GRID = 96
"""Samples of one turn on which the global search matches targets (free and no timing)."""
COVERAGE = 64
"""Samples of one turn whose distance to the targets the closed no-timing fit penalises."""
BETWEEN = 3
"""Samples checked between consecutive targets for a limit position in the way."""
MARGIN = 1e-7
"""Constraints are met with this much to spare (relative), so that the exact check passes."""
SAMPLED_MARGIN = 2e-3
"""The same for the geared five-bar's sampled constraints (extremes between samples)."""
WEIGHT = 1e4
"""Weight of a constraint's violation against the distances, in least squares."""
SCREEN = 10
"""The first generation is the best of this many times its size of random members."""
GENERATIONS = 60
"""Generations of each evolution (fewer if it stalls for 25) before its local search."""
STARTS = 16
"""Members of each evolution the local search starts from."""
EXTRA = 16
"""And members of its first generation."""
LM_ITERATIONS = 80
"""Levenberg–Marquardt iterations from each of them."""
FURTHER = 4
"""The best few of those continue for LM_FURTHER more iterations."""
LM_FURTHER = 240
GEODESIC_STEP = 0.1
GEODESIC_RATIO = 0.75
"""Finite-difference step (in units of the step) and largest correction ratio of the
geodesic acceleration (Transtrum & Sethna's recommended values)."""
KEEP = 10
"""Candidates kept for the final verification."""
STEP = 1e-8
"""Relative step of the central differences. Near a change point the traced point moves like
the square root of a dimension, and a wider step smears the valley the optimum lies in."""


class PathSynthesisError(ValueError):
    """Bad input to :func:`fit_path`; the message names the argument and the problem."""


class NoFeasibleLinkage(PathSynthesisError):
    """The search found no linkage meeting the constraints (assembly included) in its budget."""


@dataclass(frozen=True)
class PathConstraints:
    """What the fitted linkage must satisfy besides passing near the targets.

    Attributes
    ----------
    classes : names the linkage's type may have: :func:`linkwright.analysis.fourbar_class`'s
        (``crank-rocker``, ``double-crank``, ``rocker-crank``, ``double-rocker``,
        ``triple-rocker``) for the planar and spherical four-bars,
        :func:`~linkwright.analysis.slidercrank_class`'s (``crank-slider``, ``rocker-slider``)
        for the slider-crank. Empty: any.
    full_turn : the input turns fully (for the geared five-bar: over a whole period).
    min_transmission : least transmission angle γ (radians) over the whole circuit: γ stays in
        [μ, π − μ] (planar and spherical four-bar: at B; slider-crank: rod against the guide's
        normal; geared five-bar: at C). As γ is 0 or 180° at a limit position, μ > 0 asks for
        a full turn too.
    """

    classes: tuple[str, ...] = ()
    full_turn: bool = False
    min_transmission: float = 0.0


@dataclass(frozen=True)
class PathFit:
    """The result of :func:`fit_path`, every number recomputed from the plan-based engine.

    Attributes
    ----------
    family, timing : as asked.
    mechanism : the fitted linkage in the frame of the targets: a :class:`FourBar`,
        :class:`SliderCrank` or :class:`GearedFiveBar`; on the sphere a spherical
        :class:`~linkwright.mechanisms.Linkage` (ground axes A0, B0, crank A, dyad B, traced
        point P), since :class:`SphericalFourBar` stands in paper 000's fixed frame.
    named : the same linkage as its named family (planar: ``mechanism`` itself; sphere: the
        :class:`SphericalFourBar`, for :mod:`linkwright.analysis`).
    rotation : sphere only: the 3×3 rotation R with (target frame) = R · (paper 000's frame).
    inputs : (N,) the input angles of ``mechanism`` at which it reaches each target (radians;
        ``solve(fit.mechanism, fit.inputs)`` reproduces ``reached``).
    angles : (N,) the same measured from the frame line (the convention of ``angles``).
    reached : (N, 2) or (N, 3) the traced point at ``inputs``.
    distances : (N,) |reached − target| (chords on the sphere).
    error : Σ distances², the sum of squared distances.
    rms : √(error / N).
    elapsed : seconds spent; evaluations : mechanisms evaluated (one per member per pass).
    history : (seconds, evaluations, error) each time the best error improved.
    stopped : ``"target"``, ``"budget"`` or ``"evaluations"``.
    """

    family: str
    timing: str
    mechanism: Mechanism
    named: Mechanism
    rotation: Array | None
    inputs: Array
    angles: Array
    reached: Array
    distances: Array
    error: float
    rms: float
    elapsed: float
    evaluations: int
    history: tuple[tuple[float, int, float], ...] = field(repr=False)
    stopped: str

    def time_to(self, error: float) -> float | None:
        """Seconds until the search first reached ``error`` or less (None if it never did)."""
        for t, _, e in self.history:
            if e <= error:
                return t
        return None


# ------------------------------------------------------------------------------------------
# Input checks
# ------------------------------------------------------------------------------------------


def _targets(model: Model, points: ArrayLike) -> Array:
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
                f"rows {off[:5].tolist()} have lengths {lengths[off[:5]].round(6).tolist()}"
            )
        pts = pts / lengths[:, None]
    if _diameter(pts) <= 1e-9 * max(1.0, float(np.max(np.abs(pts)))):
        raise PathSynthesisError("points: the targets all coincide; there is no path to fit")
    return pts


def _diameter(pts: Array) -> float:
    diff = pts[:, None, :] - pts[None, :, :]
    return float(np.sqrt(np.max(np.sum(diff * diff, axis=-1))))


def _bounds(
    model: Model, given: Mapping[str, Any] | None, size: float, centre: Array
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


def _checked_bound(model: Model, name: str, lo: float, hi: float, size: float):
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


def _constraints(model: Model, given: PathConstraints | Mapping[str, Any] | None):
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
# The problem: everything the search evaluates
# ------------------------------------------------------------------------------------------


@dataclass
class _Candidate:
    error: float  # Σ d² at the targets
    objective: float  # what the search minimises (the error, plus the closed no-timing term)
    pose: Array  # planar (x, y, frame_angle); sphere a 3×3 rotation
    shape: dict[str, float]
    assembly: float
    rel: Array  # inputs from the frame line at each target


class _OutOfTime(Exception):
    pass


class _Problem:
    def __init__(
        self,
        model: Model,
        targets: Array,
        angles: Array | None,
        timing: str,
        closed: bool,
        bounds: dict[str, tuple[float, float]],
        cons: PathConstraints,
        size: float,
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
        names = model.pose_names + model.shape_names
        self.names = names
        self.lo = np.array([bounds[k][0] for k in names])
        self.hi = np.array([bounds[k][1] for k in names])
        self.free = self.lo < self.hi
        self.periodic = np.array(
            [
                (k in ("frame_angle", "lon", "spin") or k in model.periodic)
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
        self.grid = np.arange(GRID) * (self.period / GRID)
        self.cover_grid = np.arange(COVERAGE) * (self.period / COVERAGE)
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

    def split(self, full: Array) -> tuple[Array, dict[str, Array]]:
        """Parameters (B, names) → poses (B, 3) or (B, 3, 3) and shape arrays."""
        shape = {k: full[:, 3 + i] for i, k in enumerate(self.model.shape_names)}
        pose = full[:, :3]
        if self.model.space == "sphere":
            pose = sphere_rotation(pose[:, 0], pose[:, 1], pose[:, 2])
        return pose, shape

    # -- the engine -----------------------------------------------------------------------

    def trace(self, pose: Array, shape: dict[str, Array], assembly: Array, rel: Array):
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
        self, shape: dict[str, Array], motion=None, sl=None, hull=None, code=None
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
        if self.timing == "prescribed":
            mids = _between(self.angles, BETWEEN)
            rel = np.concatenate([self.angles, mids] + ([self.grid] if self.sampled else []))
            P, valid, motion = self.trace(pose, shape, assembly, rel)
            n, nm = self.n, len(mids)
            d2 = np.sum((P[:, :n] - T) ** 2, axis=-1)
            bad = ~valid[:, : n + nm]
            err = np.sum(np.where(valid[:, :n], d2, 0.0), axis=1)
            viol += bad.sum(axis=1)
            sl = slice(n + nm, None)
            hull = (np.min(self.angles), np.max(self.angles))
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

    def coverage_cost(self, P: Array, valid: Array) -> Array:
        """The closed no-timing fit's term: curve samples far from every target (B,)."""
        d = np.sqrt(np.min(np.sum((P[:, :, None] - self.targets) ** 2, axis=-1), axis=-1))
        excess = np.where(valid, np.maximum(d - self.coverage_h, 0.0), 0.0)
        return (self.n / P.shape[1]) * np.sum(excess**2, axis=1)

    # -- assignments for the local search ------------------------------------------------

    def assign(self, pose, shape, assembly) -> tuple[Array, float]:
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


def _segments(P: Array, valid: NDArray[np.bool_], T: Array):
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


def _wrap(angle: float) -> float:
    """An angle in (−π, π]."""
    return float(np.pi - np.mod(np.pi - angle, TWO_PI))


def _solve(M: Array, b: Array) -> Array:
    """Batched solve of M x = b, falling back to least squares for a singular matrix."""
    try:
        return np.linalg.solve(M, b[..., None])[..., 0]
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


def _monotone_cost(d2: Array, valid: Array, starts: int = 3) -> Array:
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


def _monotone_path(d2: Array, valid: Array, starts: int = 3) -> tuple[NDArray[np.int64], float]:
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


def _nearest_cost(d2: Array, valid: Array) -> tuple[Array, Array]:
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


# ------------------------------------------------------------------------------------------
# Differential evolution (JADE, current-to-pbest/1/bin)
# ------------------------------------------------------------------------------------------


class _Evolution:
    def __init__(self, problem: _Problem, size: int, rng: np.random.Generator) -> None:
        p = problem
        self.p = p
        self.rng = rng
        self.lo = np.r_[p.lo[p.free], -1.0]
        self.hi = np.r_[p.hi[p.free], 1.0]
        self.wrap = np.r_[p.periodic[p.free], False]
        # The first generation is the best of SCREEN times as many random members: one
        # batched evaluation that starts the evolution among the better basins.
        X = rng.uniform(self.lo, self.hi, (p.screen * size, len(self.lo)))
        if p.seeds is not None:
            # Starts from the template the user gave (its own linkage, laid over the targets)
            # take the first places; they are screened like the rest.
            X[: len(p.seeds)] = np.clip(p.seeds[: len(X)], self.lo, self.hi)
            p.seeds = None
        err, viol = p.fitness(X)
        keep = np.lexsort((err, viol))[:size]
        self.X, self.err, self.viol = X[keep], err[keep], viol[keep]
        self.first = (self.X.copy(), self.err.copy(), self.viol.copy())
        self.mu_f, self.mu_cr = 0.5, 0.5

    def order(self) -> NDArray[np.int64]:
        return np.lexsort((self.err, self.viol))

    def step(self) -> None:
        X, rng = self.X, self.rng
        n, d = X.shape
        F = self.mu_f + 0.1 * rng.standard_cauchy(n)
        while np.any(F <= 0):
            bad = F <= 0
            F[bad] = self.mu_f + 0.1 * rng.standard_cauchy(int(bad.sum()))
        F = np.minimum(F, 1.0)
        CR = np.clip(rng.normal(self.mu_cr, 0.1, n), 0.0, 1.0)
        top = self.order()[: max(2, n // 10)]
        pbest = X[rng.choice(top, n)]
        r1 = (np.arange(n) + rng.integers(1, n, n)) % n
        r2 = (r1 + rng.integers(1, n - 1, n)) % n
        r2 = np.where(r2 == np.arange(n), (r2 + 1) % n, r2)
        V = X + F[:, None] * (pbest - X) + F[:, None] * (X[r1] - X[r2])
        cross = rng.random((n, d)) < CR[:, None]
        cross[np.arange(n), rng.integers(0, d, n)] = True
        U = np.where(cross, V, X)
        span = self.hi - self.lo
        wrapped = self.lo + np.mod(U - self.lo, np.where(span > 0, span, 1.0))
        below = np.where(self.lo > U, (self.lo + X) / 2, U)
        inside = np.where(below > self.hi, (self.hi + X) / 2, below)
        U = np.where(self.wrap, wrapped, inside)
        err, viol = self.p.fitness(U)
        better = (viol < self.viol) | ((viol == self.viol) & (err <= self.err))
        if better.any():
            sf, scr = F[better], CR[better]
            self.mu_f = 0.9 * self.mu_f + 0.1 * float(np.sum(sf**2) / np.sum(sf))
            self.mu_cr = 0.9 * self.mu_cr + 0.1 * float(np.mean(scr))
        self.X = np.where(better[:, None], U, X)
        self.err = np.where(better, err, self.err)
        self.viol = np.where(better, viol, self.viol)

    def best(self) -> tuple[float, float]:
        i = self.order()[0]
        return float(self.err[i]), float(self.viol[i])


# ------------------------------------------------------------------------------------------
# Local least squares
# ------------------------------------------------------------------------------------------


class _Local:
    """Least squares from several members at once: dimensions, placement and inputs together.

    Each start has its own assembly, free-timing sense and (sphere) base rotation R0; the
    placement is then R0 times the rotation of a rotation vector, so that no chart of the
    sphere's rotations has a pole in the way. :meth:`levenberg_marquardt` advances every start
    in lock step, evaluating all their finite-difference Jacobians as one batched mechanism;
    :meth:`polish` finishes one start with :func:`scipy.optimize.least_squares`.
    """

    def __init__(
        self, problem: _Problem, starts: list[_Candidate], senses: list[float], deadline: float
    ) -> None:
        p = self.p = problem
        m = p.model
        self.deadline = deadline
        self.assembly = np.array([c.assembly for c in starts])
        self.sense = np.array(senses, float)
        self.sphere = m.space == "sphere"
        self.R0 = np.array([c.pose for c in starts]) if self.sphere else None
        self.shape_free = [k for i, k in enumerate(m.shape_names) if p.free[3 + i]]
        self.pose_free = [] if self.sphere else [i for i in range(3) if p.free[i]]
        lo: list[float] = []
        hi: list[float] = []
        typ: list[float] = []
        columns: list[Array] = []
        if self.sphere:
            columns += [np.zeros(len(starts))] * 3
            lo += [-np.inf] * 3
            hi += [np.inf] * 3
            typ += [1.0] * 3
        else:
            for i in self.pose_free:
                columns.append(np.array([c.pose[i] for c in starts]))
                lo.append(-np.inf if p.periodic[i] else p.lo[i])
                hi.append(np.inf if p.periodic[i] else p.hi[i])
                typ.append(1.0 if i == 2 else p.size)
        linear = m.linear
        for k in self.shape_free:
            i = 3 + m.shape_names.index(k)
            columns.append(np.array([c.shape[k] for c in starts]))
            lo.append(-np.inf if p.periodic[i] else p.lo[i])
            hi.append(np.inf if p.periodic[i] else p.hi[i])
            typ.append(p.size if k in linear else 1.0)
        first = starts[0]
        self.fixed_shape = {k: first.shape[k] for k in m.shape_names if k not in self.shape_free}
        self.fixed_pose = None if self.sphere else np.asarray(first.pose, float).copy()
        if p.timing == "free":
            sticks = []
            for c, sense in zip(starts, senses, strict=True):
                # Stick-breaking: each increment takes a fraction of what is left of the period.
                left, t = p.period, []
                for step in sense * np.diff(c.rel):
                    t.append(min(max(step / left, 0.0), 1.0) if left > 0 else 0.0)
                    left = max(left - step, 0.0)
                sticks.append([c.rel[0], *t])
            columns += list(np.array(sticks).T)
            lo += [-np.inf] + [0.0] * (p.n - 1)
            hi += [np.inf] + [1.0] * (p.n - 1)
            typ += [1.0] * p.n
        elif p.timing == "none":
            columns += list(np.array([c.rel for c in starts]).T)
            lo += [-np.inf] * p.n
            hi += [np.inf] * p.n
            typ += [1.0] * p.n
        self.lo, self.hi = np.array(lo, float), np.array(hi, float)
        self.typ = np.array(typ, float)
        self.x0 = np.clip(np.stack(columns, axis=1), self.lo, self.hi)
        k = len(starts)
        self.best_err = np.full(k, np.inf)
        self.best_obj = np.full(k, np.inf)
        self.best_z = self.x0.copy()

    def decode(self, Z: Array, owner: NDArray[np.int64]):
        p = self.p
        B = len(Z)
        j = 0
        if self.sphere:
            pose = np.einsum("bij,bjk->bik", self.R0[owner], rodrigues(Z[:, :3]))
            j = 3
        else:
            pose = np.broadcast_to(self.fixed_pose, (B, 3)).copy()
            for i in self.pose_free:
                pose[:, i] = Z[:, j]
                j += 1
        shape = {k: np.full(B, v) for k, v in self.fixed_shape.items()}
        for k in self.shape_free:
            shape[k] = Z[:, j]
            j += 1
        if p.timing == "prescribed":
            rel = np.broadcast_to(p.angles, (B, p.n))
        elif p.timing == "free":
            t = Z[:, j + 1 :]
            left = np.full(B, p.period)
            steps = np.empty_like(t)
            for i in range(t.shape[1]):
                steps[:, i] = left * t[:, i]
                left = left - steps[:, i]
            inc = np.concatenate([np.zeros((B, 1)), np.cumsum(steps, axis=1)], axis=1)
            rel = Z[:, j : j + 1] + self.sense[owner][:, None] * inc
        else:
            rel = Z[:, j:]
        return pose, shape, np.asarray(rel, float)

    def residuals(self, Z: Array, owner: NDArray[np.int64]):
        """Residual vectors (B, m), the validity pattern, the errors Σ d², feasibility."""
        p = self.p
        pose, shape, rel = self.decode(Z, owner)
        B = len(Z)
        path = np.sort(rel, axis=1) if p.timing == "none" else rel
        f = np.arange(1, BETWEEN + 1) / (BETWEEN + 1)
        mids = (path[:, :-1, None] + np.diff(path, axis=1)[:, :, None] * f).reshape(B, -1)
        parts = [rel, mids]
        cover = p.timing == "none" and p.closed
        if cover:
            parts.append(np.broadcast_to(p.cover_grid, (B, COVERAGE)))
        if p.sampled:
            parts.append(np.broadcast_to(p.grid, (B, GRID)))
        inputs = np.concatenate(parts, axis=1)
        P, valid, motion = p.trace(pose, shape, self.assembly[owner], inputs)
        n, nm = p.n, mids.shape[1]
        diff = P[:, :n] - p.targets
        ok_t = valid[:, :n]
        res = [np.where(ok_t[..., None], diff, p.penalty).reshape(B, -1)]
        err = np.sum(np.where(ok_t[..., None], diff, 0.0) ** 2, axis=(1, 2))
        res.append(np.where(valid[:, n : n + nm], 0.0, p.penalty))
        at = n + nm
        if cover:
            c = P[:, at : at + COVERAGE]
            d = np.sqrt(np.min(np.sum((c[:, :, None] - p.targets) ** 2, axis=-1), axis=-1))
            ex = np.sqrt(p.n / COVERAGE) * np.maximum(d - p.coverage_h, 0.0)
            res.append(np.where(valid[:, at : at + COVERAGE], ex, p.penalty))
            at += COVERAGE
        sl = slice(at, at + GRID) if p.sampled else None
        feasible = valid[:, : n + nm].all(axis=1)
        hull = (rel.min(axis=1), rel.max(axis=1))
        for g, margin in p.gaps(shape, motion, sl, hull, self.assembly[owner]):
            res.append((WEIGHT * p.size * np.maximum(g + margin, 0.0))[:, None])
            feasible &= g <= 0.0
        return np.concatenate(res, axis=1), valid, err, feasible

    def _note(self, Z: Array, owner, R: Array, err: Array, ok: Array) -> Array:
        """Keep each start's best feasible point; return the objectives Σ r²."""
        obj = np.sum(R * R, axis=1)
        # Penalties vanish at a feasible point, so Σ r² is the objective there.
        better = ok & (obj < self.best_obj[owner])
        for b in np.flatnonzero(better):
            o = owner[b]
            if obj[b] < self.best_obj[o]:
                self.best_obj[o], self.best_err[o], self.best_z[o] = obj[b], err[b], Z[b]
        return obj

    def _jacobians(self, Z: Array, owner, R0: Array, V0: Array) -> Array:
        """Finite-difference Jacobians (K, m, n) at the rows Z, one batched evaluation.

        A difference across a change of validity (a sample that stops assembling) measures the
        penalty's jump, not a slope: such a side is dropped (central → one-sided → 0).
        """
        K, n = Z.shape
        h = STEP * np.maximum(self.typ, np.abs(Z))
        up = np.minimum(Z + h, self.hi)
        dn = np.maximum(Z - h, self.lo)
        eye = np.eye(n, dtype=bool)
        Zp = np.where(eye, up[:, None, :], Z[:, None, :])
        Zm = np.where(eye, dn[:, None, :], Z[:, None, :])
        rows = np.concatenate([Zp.reshape(-1, n), Zm.reshape(-1, n)])
        own = np.concatenate([np.repeat(owner, n), np.repeat(owner, n)])
        R, V, _, _ = self.residuals(rows, own)
        m = R.shape[1]
        Rp, Rm = R[: K * n].reshape(K, n, m), R[K * n :].reshape(K, n, m)
        Vp, Vm = V[: K * n].reshape(K, n, -1), V[K * n :].reshape(K, n, -1)
        sp = np.all(Vp == V0[:, None], axis=2)
        sm = np.all(Vm == V0[:, None], axis=2)
        zi, ui, di = Z, up, dn
        central = sp & sm & (ui > di)
        fwd = sp & ~central & (ui > zi)
        bwd = sm & ~central & ~fwd & (di < zi)

        def safe(x):
            return np.where(x != 0, x, 1.0)

        J = np.where(
            central[..., None],
            (Rp - Rm) / safe(ui - di)[..., None],
            np.where(
                fwd[..., None],
                (Rp - R0[:, None]) / safe(ui - zi)[..., None],
                np.where(bwd[..., None], (R0[:, None] - Rm) / safe(zi - di)[..., None], 0.0),
            ),
        )
        return np.swapaxes(J, 1, 2)

    def levenberg_marquardt(self, iterations: int) -> None:
        """Advance every start by Levenberg–Marquardt steps with geodesic acceleration,
        projected onto the bounds, evaluating all starts together.

        The optima of path synthesis often lie at the end of long curved valleys (near a
        change point, a cusp, a straight stretch of the curve), where plain Gauss–Newton steps
        are cut short by the curvature. The second-order correction along the step (M. K.
        Transtrum & J. P. Sethna, "Improvements to the Levenberg–Marquardt algorithm for
        nonlinear least-squares minimization", arXiv:1201.5885, 2012) follows the valley at
        the price of one more batched evaluation per iteration. Damping is Marquardt's
        diagonal scaling, raised ×4 on a rejected step and lowered ÷3 on an accepted one.
        """
        Z = self.x0.copy()
        K, n = Z.shape
        owner = np.arange(K)
        R, V, err, ok = self.residuals(Z, owner)
        cost = self._note(Z, owner, R, err, ok)
        lam = np.full(K, 1e-3)
        J = self._jacobians(Z, owner, R, V)
        live = np.ones(K, bool)
        eye = np.eye(n)
        for _ in range(iterations):
            if time.perf_counter() > self.deadline or not live.any():
                break
            rows = np.flatnonzero(live)
            Jr, Rr, Zr = J[rows], R[rows], Z[rows]
            A = np.einsum("kmi,kmj->kij", Jr, Jr)
            g = np.einsum("kmi,km->ki", Jr, Rr)
            d = np.diagonal(A, axis1=1, axis2=2)
            d = np.maximum(d, 1e-12 * np.max(d, axis=1, keepdims=True) + 1e-300)
            M = A + (lam[rows][:, None] * d)[:, :, None] * eye
            v = -_solve(M, g)
            # Second directional derivative of the residuals along v, by one more evaluation.
            h = GEODESIC_STEP
            Rh = self.residuals(np.clip(Zr + h * v, self.lo, self.hi), rows)[0]
            rvv = (2.0 / h) * ((Rh - Rr) / h - np.einsum("kmi,ki->km", Jr, v))
            acc = -_solve(M, np.einsum("kmi,km->ki", Jr, rvv))
            size_v = np.sqrt(np.sum(d * v * v, axis=1))
            size_a = np.sqrt(np.sum(d * acc * acc, axis=1))
            # Where the correction is large against the step the valley bends too sharply for
            # it: take the plain step.
            bend = np.isfinite(size_a) & (2.0 * size_a <= GEODESIC_RATIO * size_v)
            step = np.where(bend[:, None], v + 0.5 * acc, v)
            trial = np.clip(Zr + step, self.lo, self.hi)
            Rt, Vt, et, okt = self.residuals(trial, rows)
            ct = self._note(trial, rows, Rt, et, okt)
            accept = np.isfinite(ct) & (ct < cost[rows])
            small = np.abs(cost[rows] - ct) <= 1e-15 * cost[rows] + 1e-300
            acc_rows = rows[accept]
            Z[acc_rows], R[acc_rows], V[acc_rows], cost[acc_rows] = (
                trial[accept],
                Rt[accept],
                Vt[accept],
                ct[accept],
            )
            lam[acc_rows] = np.maximum(lam[acc_rows] / 3.0, 1e-12)
            lam[rows[~accept]] *= 4.0
            live[rows[(lam[rows] > 1e10) | (accept & small)]] = False
            if acc_rows.size:
                J[acc_rows] = self._jacobians(Z[acc_rows], acc_rows, R[acc_rows], V[acc_rows])

    def polish(self, k: int, max_nfev: int = 200) -> None:
        """Finish start k with :func:`scipy.optimize.least_squares` (trust region, bounds)."""
        owner = np.array([k])
        cache: dict[bytes, tuple] = {}

        def evaluate(z: Array):
            key = z.tobytes()
            if key not in cache:
                if time.perf_counter() > self.deadline:
                    raise _OutOfTime
                R, V, err, ok = self.residuals(z[None], owner)
                self._note(z[None], owner, R, err, ok)
                cache.clear()
                cache[key] = (R[0], V[0])
            return cache[key]

        def jac(z: Array) -> Array:
            r, v = evaluate(z)
            return self._jacobians(z[None], owner, r[None], v[None])[0]

        with contextlib.suppress(_OutOfTime):
            least_squares(
                lambda z: evaluate(z)[0],
                self.best_z[k] if np.isfinite(self.best_obj[k]) else self.x0[k],
                jac=jac,
                bounds=(self.lo, self.hi),
                x_scale="jac",
                ftol=1e-15,
                xtol=1e-15,
                gtol=1e-15,
                max_nfev=max_nfev,
            )

    def candidate(self, k: int) -> _Candidate | None:
        if not np.isfinite(self.best_obj[k]):
            return None
        pose, shape, rel = self.decode(self.best_z[k][None], np.array([k]))
        pose = pose[0].copy()
        if not self.sphere:
            pose[2] = _wrap(pose[2])
        periodic = self.p.model.periodic
        return _Candidate(
            float(self.best_err[k]),
            float(self.best_obj[k]),
            pose,
            {n: float(_wrap(v[0]) if n in periodic else v[0]) for n, v in shape.items()},
            float(self.assembly[k]),
            rel[0],
        )


# ------------------------------------------------------------------------------------------
# Verification with the plan-based engine and the analysis module
# ------------------------------------------------------------------------------------------


def _verify(p: _Problem, cand: _Candidate) -> tuple[dict[str, Any] | None, str]:
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
        name = str(slidercrank_class(named) if m.family == "slidercrank" else fourbar_class(named))
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
    ), ""


def _reproject(p: _Problem, mech: Mechanism, psi: float, rel: Array) -> Array:
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

        def d2(x, t=t):
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


def _seed_genes(p: _Problem, seeds: list[tuple[Array, dict[str, float], float]]) -> Array | None:
    """Genes of the members that start from the template (pose, shape and configuration), with
    the free parameters in the search's order and the configuration's gene in its share."""
    if not seeds:
        return None
    rows = []
    k = len(getattr(p.model, "combos", (0,)))
    for pose, shape, code in seeds:
        full = dict(zip(p.model.pose_names, np.asarray(pose, float), strict=True), **shape)
        values = np.array([full[n] for n in p.names])
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
) -> PathFit:
    """Fit a linkage's traced point to target points (see the module docstring for the method).

    Parameters
    ----------
    family : ``"fourbar"``, ``"slidercrank"``, ``"geared-fivebar"`` or ``"spherical-fourbar"``.
    points : (N, 2) target points, or (N, 3) unit vectors for the spherical four-bar (within
        1 % of unit length; they are normalised). N ≥ 3.
    angles : (N,) crank angles (radians) from the frame line at which each target must be
        reached; only with prescribed timing.
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
    linkwright.synthesis.path.PathSynthesisError: points: at least 3 target points are \
needed, got 2

    A linkage that cannot meet its constraints is an error, not a NaN: a slider-crank whose
    crank is longer than its rod never turns fully.

    >>> fit_path("slidercrank", pts, angles=theta, bounds={"crank": (2, 3), "rod": (0.5, 1)},
    ...          constraints={"full_turn": True}, max_evaluations=2000)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.synthesis.path.NoFeasibleLinkage: no slidercrank meeting the constraints and \
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
    if not (isinstance(budget, int | float) and budget > 0 and math.isfinite(budget)):
        raise PathSynthesisError(f"budget: must be a positive number of seconds, got {budget!r}")
    if max_evaluations is not None and max_evaluations < 1:
        raise PathSynthesisError(f"max_evaluations: must be ≥ 1, got {max_evaluations}")
    size = _diameter(T)
    centre = 0.5 * (T.min(axis=0) + T.max(axis=0))
    bnds = _bounds(model, bounds, size, centre)
    cons = _constraints(model, constraints)
    problem = _Problem(model, T, ang, timing, closed, bnds, cons, size)
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
    candidates: list[_Candidate] = []
    best = np.inf
    best_objective = np.inf
    stopped = "budget"

    def spent() -> float:
        f = (time.perf_counter() - t0) / budget
        if max_evaluations:
            f = max(f, problem.evaluations / max_evaluations)
        return min(f, 1.0)

    def consider(cand: _Candidate) -> None:
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
        evo = _Evolution(problem, pop, rng)
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
                rel, sense = problem.angles.copy(), 1.0
            else:
                rel, sense = problem.assign(pose, shape, a)
            e0 = float(errs[order[i]])
            shape1 = {k: float(v[0]) for k, v in shape.items()}
            starts.append(_Candidate(e0, e0, pose[0], shape1, float(a[0]), rel))
            senses.append(sense)
        if viols[order[0]] == 0:
            # The evolution's best stands as a candidate even if no local search follows.
            consider(starts[0])
        stopped_now = out_of_budget()
        if stopped_now in ("target", "evaluations"):
            stopped = stopped_now
            break
        local = _Local(problem, starts, senses, deadline)
        local.levenberg_marquardt(LM_ITERATIONS)
        found = [local.candidate(k) for k in range(len(starts))]
        # The most promising few go on: valleys near a change point or a cusp are long.
        top = [k for k in np.argsort(local.best_obj)[:FURTHER] if found[k] is not None]
        if top:
            more = _Local(problem, [found[k] for k in top], [senses[k] for k in top], deadline)
            more.levenberg_marquardt(LM_FURTHER)
            k = int(np.argmin(more.best_obj))
            if more.best_obj[k] < best_objective * (1 + 1e-9):
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

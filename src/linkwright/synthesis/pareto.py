"""Design as a trade-off: a Pareto front of path error against a second objective.

The front is found by an ε-constraint sweep (Haimes, Lasdon and Wismer 1971; Miettinen,
*Nonlinear Multiobjective Optimization*, 1999, §3.2): the second objective is turned into a
constraint at ``levels`` values, :func:`~linkwright.synthesis.path.fit_path` minimises the error
under each one (each run with its share of the time budget, a different seed), and the designs
that no other design beats on both objectives are kept. A sweep rather than a genetic algorithm
because each constrained run is already a global search, and its constraint is exact.

Objectives (the documented list, :data:`OBJECTIVES`); ``error`` is always the first:

- ``error``: the sum of squared distances from the targets (minimised), recomputed here by
  solving the returned linkage at its inputs.
- ``transmission``: the least deviation of the transmission angle from the square over the
  whole circuit, min(γ, 180° − γ) in degrees (maximised; its ε-constraint is fit_path's
  ``min_transmission``), recomputed here from every dyad's angle over 2048 samples.
- ``size``: the longest link (the frame included) over the targets' diameter (minimised; its
  ε-constraint bounds every link length), recomputed here from the linkage's dimensions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis.general import dyad_transmission_angles
from linkwright.mechanisms import Mechanism, circuit, solve
from linkwright.synthesis.path import PathSynthesisError, fit_path

__all__ = ["MAX_LEVELS", "OBJECTIVES", "ParetoDesign", "ParetoError", "pareto_path"]

Array = NDArray[np.float64]
OBJECTIVES = ("error", "transmission", "size")
# The most ε levels one sweep runs (each is a whole global search).
MAX_LEVELS = 20
# The least time one level gets: below it a global search finds nothing worth comparing.
MIN_LEVEL_SECONDS = 0.5


class ParetoError(ValueError):
    """A request for a Pareto front that cannot be met (bad objectives, budget or targets)."""


@dataclass(frozen=True)
class ParetoDesign:
    """One design of the front: the linkage, its inputs at the targets and its objectives."""

    mechanism: Mechanism
    inputs: Array
    level: float
    error: float
    second: float


def _diameter(points: Array) -> float:
    return float(np.max(np.linalg.norm(points[:, None, :] - points[None, :, :], axis=-1)))


def transmission_margin(mechanism: Mechanism) -> float:
    """The least min(γ, 180° − γ) (degrees) of every dyad over the mechanism's circuit."""
    motion = circuit(mechanism, 2048, order=0)
    worst = math.inf
    for gamma in dyad_transmission_angles(mechanism, motion).values():
        g = np.asarray(gamma, dtype=float)
        g = g[np.isfinite(g)]
        if g.size:
            worst = min(worst, float(np.degrees(np.min(np.minimum(g, np.pi - g)))))
    return worst


def size_ratio(mechanism: Mechanism, diameter: float) -> float:
    """The longest link (the frame A0–B0 included where there is one) over ``diameter``."""
    params = mechanism.params()
    lengths = [float(np.max(np.abs(params[n]))) for n in type(mechanism).length_fields]
    if "A0" in params and "B0" in params:
        lengths.append(float(np.linalg.norm(np.asarray(params["B0"]) - np.asarray(params["A0"]))))
    return max(lengths) / diameter


def non_dominated(values: Array, senses: Sequence[int]) -> NDArray[np.bool_]:
    """Which rows of ``values`` (k, 2) no other row dominates (sense +1 minimise, −1 maximise)."""
    v = np.asarray(values, dtype=float) * np.asarray(senses, dtype=float)
    keep = np.ones(len(v), dtype=bool)
    for i in range(len(v)):
        others = np.delete(v, i, axis=0)
        beaten = np.all(others <= v[i], axis=1) & np.any(others < v[i], axis=1)
        keep[i] = not bool(np.any(beaten))
    return keep


def pareto_path(
    family: str,
    points: ArrayLike,
    *,
    objectives: Sequence[str] = ("error", "transmission"),
    levels: int = 6,
    budget: float = 30.0,
    seed: int = 0,
    timing: str | None = None,
    closed: bool = False,
    progress: Callable[[float], None] | None = None,
) -> list[ParetoDesign]:
    """The Pareto front of path error against ``objectives[1]`` (module docstring), sorted by
    error, each design re-simulated and its objectives recomputed.

    Raises
    ------
    ParetoError : objectives not ``("error", X)`` with X in :data:`OBJECTIVES`, levels outside
        2…MAX_LEVELS, a budget giving a level under MIN_LEVEL_SECONDS, or no level feasible.
    PathSynthesisError : bad targets or family (from :func:`fit_path`).
    """
    objs = tuple(objectives)
    if len(objs) != 2 or objs[0] != "error" or objs[1] not in OBJECTIVES[1:]:
        raise ParetoError(
            f"objectives: give error and one of {', '.join(OBJECTIVES[1:])} (e.g. "
            f"error,transmission), got {','.join(objs)}"
        )
    if not 2 <= levels <= MAX_LEVELS:
        raise ParetoError(f"levels: 2 to {MAX_LEVELS}, got {levels}")
    if not (math.isfinite(budget) and budget / levels >= MIN_LEVEL_SECONDS):
        raise ParetoError(
            f"budget: {budget:g} s gives each of {levels} levels under {MIN_LEVEL_SECONDS} s; "
            "give more time or fewer levels"
        )
    pts = np.asarray(points, dtype=float)
    second = objs[1]
    if pts.ndim != 2 or len(pts) < 3:
        raise PathSynthesisError(f"points: need at least 3 rows, got shape {pts.shape}")
    diameter = _diameter(pts)
    if second == "transmission":
        eps = np.linspace(0.0, 60.0, levels)  # degrees: 60° already squeezes most linkages
    else:
        eps = np.geomspace(0.75, 6.0, levels)[::-1]  # links up to eps × the targets' diameter
    start = time.monotonic()
    found: list[ParetoDesign] = []
    for k, level in enumerate(eps):
        left = budget - (time.monotonic() - start)
        share = left / (levels - k)
        if share < 0.25 * MIN_LEVEL_SECONDS:
            break
        constraints: dict[str, Any] | None = None
        bounds: dict[str, tuple[float, float]] | None = None
        if second == "transmission":
            constraints = {"min_transmission": math.radians(float(level))}
        else:
            bounds = {"length": (1e-3 * diameter, float(level) * diameter)}
        try:
            fit = fit_path(family, pts, timing=timing, closed=closed, seed=seed + k,
                           budget=share, constraints=constraints, bounds=bounds)  # fmt: skip
        except PathSynthesisError as exc:
            if "points" in str(exc) or "family" in str(exc):
                raise
            continue  # nothing feasible at this level within its time: the front skips it
        finally:
            if progress is not None:
                progress((k + 1) / levels)
        reached = solve(fit.mechanism, fit.inputs, order=0).positions["P"]
        error = float(np.sum((reached - pts) ** 2))
        named = fit.named
        value = (
            transmission_margin(named) if second == "transmission" else size_ratio(named, diameter)
        )
        if math.isfinite(error) and math.isfinite(value):
            found.append(ParetoDesign(fit.mechanism, np.asarray(fit.inputs), float(level),
                                      error, value))  # fmt: skip
    if not found:
        raise ParetoError(f"no level found a feasible linkage in {budget:g} s: give more time")
    values = np.array([[d.error, d.second] for d in found])
    keep = non_dominated(values, (1, -1 if second == "transmission" else 1))
    return sorted((d for d, k in zip(found, keep, strict=True) if k), key=lambda d: d.error)

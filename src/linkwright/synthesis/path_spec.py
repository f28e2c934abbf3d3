"""What a path fit is asked and what it returns.

The families and timings :func:`~linkwright.synthesis.path.fit_path` knows, the constants that
size its search (differential evolution after J. Zhang & A. C. Sanderson, *IEEE Trans. Evol.
Comput.* 13, 2009; Levenberg–Marquardt with the geodesic acceleration of Transtrum & Sethna,
2012), its errors, the constraints a fitted linkage must meet (:class:`PathConstraints`) and the
result (:class:`PathFit`). The search itself is described in :mod:`linkwright.synthesis.path`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from linkwright.mechanisms import FAMILIES as REGISTERED
from linkwright.mechanisms import Mechanism

__all__ = [
    "BETWEEN",
    "COVERAGE",
    "EXTRA",
    "FAMILIES",
    "FURTHER",
    "GENERATIONS",
    "GEODESIC_RATIO",
    "GEODESIC_STEP",
    "GRID",
    "KEEP",
    "LM_FURTHER",
    "LM_ITERATIONS",
    "MARGIN",
    "MIN_POINTS",
    "SAMPLED_MARGIN",
    "SCREEN",
    "SPHERE_TOL",
    "STARTS",
    "STEP",
    "TIMINGS",
    "WEIGHT",
    "NoFeasibleLinkage",
    "PathConstraints",
    "PathFit",
    "PathSynthesisError",
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
        ``solve(fit.mechanism, fit.inputs)`` reproduces ``reached`` where ``branches`` is None).
    angles : (N,) the same measured from the frame line (the convention of ``angles``).
    reached : (N, 2) or (N, 3) the traced point at ``inputs``.
    distances : (N,) |reached − target| (chords on the sphere).
    error : Σ distances², the sum of squared distances.
    rms : √(error / N).
    elapsed : seconds spent; evaluations : mechanisms evaluated (one per member per pass).
    history : (seconds, evaluations, error) each time the best error improved.
    stopped : ``"target"``, ``"budget"`` or ``"evaluations"``.
    branches : None, or, where a nearest-point fit (no timing) of a rocking input found targets
        nearest the circuit's return leg, each dyad's sign at each target (joint name → (N,)):
        the distances are then to the nearest point of the whole traced circuit, and
        ``linkwright.engine.evaluate(plan, params, inputs, branches=branches)`` reproduces
        ``reached``.
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
    branches: dict[str, Array] | None = None

    def time_to(self, error: float) -> float | None:
        """Seconds until the search first reached ``error`` or less (None if it never did)."""
        for t, _, e in self.history:
            if e <= error:
                return t
        return None

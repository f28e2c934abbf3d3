"""The named outputs a design to targets can aim, and the results it reports.

:data:`OUTPUTS` names the four-bar outputs of :mod:`linkwright.analysis` that
:func:`~linkwright.synthesis.targets.design_fourbar` aims (paper 003's coefficients, the time
ratio, the swing, the transmission angle's extremes); :class:`TargetSolution` and
:class:`TargetSolutions` carry each solution with its conditioning (the Jacobian of the outputs
by the free variables, its singular values and the sensitivity). Paper 003's synthesis example
is the cautionary case of ill-conditioning (:func:`linkwright.papers.p003.synthesis_example`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis import (
    coefficients,
    input_limits,
    output_extremes,
    transmission_extremes,
)
from linkwright.mechanisms import SphericalFourBar, input_range
from linkwright.mechanisms.base import Mechanism

__all__ = [
    "OUTPUTS",
    "Output",
    "TargetError",
    "TargetSolution",
    "TargetSolutions",
]

Array = NDArray[np.float64]


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

    def __iter__(self) -> Iterator[TargetSolution]:
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

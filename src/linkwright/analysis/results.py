"""What :func:`linkwright.analysis.analyze` returns: typed results, angles in radians.

Nothing here is rounded, wrapped or worded for a reader: :mod:`linkwright.io.report` turns these
into the degrees, JSON and text that the command line and the workbench show. A value the motion
does not have (the swing of an output that turns fully, an extreme of a linkage that never
assembles) is ``None``, never NaN.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = [
    "Analysis",
    "Coefficients",
    "DyadLimit",
    "Ellipse",
    "Extremes",
    "FourBarAnalysis",
    "GeneralAnalysis",
    "Locking",
    "PressureComponents",
    "TracedPath",
    "TriadLimit",
    "finite",
]


def finite(x: Any) -> float | None:
    """``float(x)``, or ``None`` where it is NaN or infinite (a value the motion does not have).

    Examples
    --------
    >>> finite(1.5), finite(float("nan"))
    (1.5, None)
    """
    value = float(x)
    return value if math.isfinite(value) else None


@dataclass(frozen=True)
class Extremes:
    """The least and greatest value of a quantity over the motion, with the inputs (radians,
    absolute) where they occur when those are known."""

    min: float | None
    max: float | None
    min_at: float | None = None
    max_at: float | None = None


@dataclass(frozen=True)
class Coefficients:
    """Paper 003's kinematic coefficients: greatest |ω3/ω1| (``K_omega``), |ε3/ω1²|
    (``K_epsilon``), the pressure coefficient ``K_p`` and the dwell measure ``delta``."""

    K_omega: float | None
    K_epsilon: float | None
    K_p: float | None
    delta: float | None

    @classmethod
    def of(cls, values: Mapping[str, Any] | None) -> Coefficients:
        """From :func:`~linkwright.analysis.coefficients`' mapping (``None``: all unknown)."""
        if values is None:
            return cls(None, None, None, None)
        return cls(*(finite(values[k]) for k in ("K_omega", "K_epsilon", "K_p", "delta")))


@dataclass(frozen=True)
class PressureComponents:
    """A spherical four-bar's pressure angle in paper 003's two components, for the hinge-radius
    ratio ``mu`` = OB/OA (``mu_source``: ``"given"``, ``"balanced"``, or ``"none"`` when no
    positive μ balances them, and the components are unknown)."""

    mu: float | None
    mu_source: str
    normal: Extremes | None
    tangential: Extremes | None


@dataclass(frozen=True)
class FourBarAnalysis:
    """Paper 003's analysis of a four-bar, a slider-crank or a spherical four-bar (radians).

    ``input_arcs`` are the absolute input arcs (lo, hi) where the input rocks (empty when it
    turns fully or never assembles); ``output_range`` the output angle's least and greatest
    value measured from the frame line (four-bars; ``None`` when the output turns fully);
    ``slider_range`` the slider's least and greatest position along its line (slider-crank,
    lengths). ``reference_angle`` is the frame line's direction (absolute = from frame +
    reference; 0 on the sphere, whose input is already measured from the frame circle).
    """

    family: str
    kind: str | None
    assembles: bool
    reason: str | None
    reference_angle: float
    grashof: float | None
    grashof_terms: tuple[float | None, ...] | None
    input_full: bool
    input_arcs: tuple[tuple[float, float], ...]
    output_range: tuple[float, float] | None
    slider_range: tuple[float, float] | None
    transmission: Extremes | None
    pressure: PressureComponents | None
    time_ratio: float | None
    coefficients: Coefficients

    @property
    def spherical(self) -> bool:
        return self.grashof_terms is not None


@dataclass(frozen=True)
class DyadLimit:
    """A limit position of the input (radians): where ``dyad`` cannot close beyond."""

    input: float | None
    dyad: str | None


@dataclass(frozen=True)
class TriadLimit:
    """A limit of a circuit of a linkage with a triad: two of its poses merge there."""

    input: float | None
    triad: str
    circuit: int
    poses: tuple[int, int]


@dataclass(frozen=True)
class TracedPath:
    """A traced joint's path over the circuit: its length and its least and greatest speed per
    radian of input (on the sphere: radians of arc)."""

    path_length: float | None
    speed_min: float | None
    speed_max: float | None


@dataclass(frozen=True)
class Locking:
    """Paper 002's geared five-bar: whether it oscillates between locking positions (inputs,
    radians) and after how many input turns it repeats."""

    oscillates: bool
    locking_positions: tuple[float | None, ...]
    repeats_after_turns: int


@dataclass(frozen=True)
class Ellipse:
    """Paper 004's double slider: its traced ellipse (orientation in radians) and the
    normalised conic A..F of eq. 3."""

    center: tuple[float | None, float | None]
    semi_major: float | None
    semi_minor: float | None
    orientation: float | None
    conic: tuple[float | None, ...]
    kind: str


@dataclass(frozen=True)
class GeneralAnalysis:
    """The analysis of any linkage the engine builds (radians): its input arcs and limit
    positions, each dyad's transmission-angle extremes, each traced joint's path, read from
    ``samples`` circuit samples; a geared five-bar adds its ``locking``, a double slider its
    ``ellipse``. ``circuits`` counts a triad linkage's circuits (``None`` without a triad)."""

    family: str
    assembles: bool
    period_turns: int
    input_turns_fully: bool
    input_arcs: tuple[tuple[float, float], ...]
    limit_positions: tuple[DyadLimit | TriadLimit, ...]
    circuits: int | None
    reason: str | None
    transmission: Mapping[str, Extremes]
    traced: Mapping[str, TracedPath]
    samples: int
    locking: Locking | None = None
    ellipse: Ellipse | None = None


Analysis = FourBarAnalysis | GeneralAnalysis
"""What :func:`~linkwright.analysis.analyze` returns for one mechanism."""

"""Analyses: pure functions of a mechanism (and its motion); nothing cached behind your back.

:func:`analyze` gathers them into one typed result in radians (:mod:`.results`): paper 003's
analysis for four-bars (planar and spherical) and slider-cranks, the general one for every other
family. :func:`linkwright.io.report.analysis_report` renders it in degrees and words for
``linkwright analyze``. :func:`instant_centres` gives the instant centres of a planar linkage's
bodies (all six of a four-bar) and the instantaneous axes of a spherical one's.
"""

from __future__ import annotations

from linkwright.analysis.classes import classify
from linkwright.analysis.conic import (
    conic_invariants,
    conic_kind,
    doubleslider_conic,
    ellipse_axes,
    normalise_conic,
)
from linkwright.analysis.general import dyad_transmission_angles, point_speed
from linkwright.analysis.instant_centres import (
    InstantCentres,
    RigidBody,
    instant_centres,
    rigid_bodies,
)
from linkwright.analysis.planar import (
    coefficients,
    fourbar_class,
    grashof,
    output_angle,
    output_extremes,
    output_rates,
    slidercrank_class,
    stroke,
    transmission_angle,
    transmission_extremes,
)
from linkwright.analysis.results import (
    Analysis,
    Coefficients,
    DyadLimit,
    Ellipse,
    Extremes,
    FourBarAnalysis,
    GeneralAnalysis,
    Locking,
    PressureComponents,
    TracedPath,
    TriadLimit,
)
from linkwright.analysis.spherical import (
    InvalidHingeRatio,
    NotASphericalFourBar,
    balanced_mu,
    grashof_terms,
    input_limits,
    output_limits,
    paper003_normal_extremes,
    paper003_tangential_extremes,
    pressure_angles,
    pressure_extremes,
    spherical_class,
)
from linkwright.analysis.summary import analyze, general_analysis

__all__ = [
    "Analysis",
    "Coefficients",
    "DyadLimit",
    "Ellipse",
    "Extremes",
    "FourBarAnalysis",
    "GeneralAnalysis",
    "InstantCentres",
    "InvalidHingeRatio",
    "Locking",
    "NotASphericalFourBar",
    "PressureComponents",
    "RigidBody",
    "TracedPath",
    "TriadLimit",
    "analyze",
    "balanced_mu",
    "classify",
    "coefficients",
    "conic_invariants",
    "conic_kind",
    "doubleslider_conic",
    "dyad_transmission_angles",
    "ellipse_axes",
    "fourbar_class",
    "general_analysis",
    "grashof",
    "grashof_terms",
    "input_limits",
    "instant_centres",
    "normalise_conic",
    "output_angle",
    "output_extremes",
    "output_limits",
    "output_rates",
    "paper003_normal_extremes",
    "paper003_tangential_extremes",
    "point_speed",
    "pressure_angles",
    "pressure_extremes",
    "rigid_bodies",
    "slidercrank_class",
    "spherical_class",
    "stroke",
    "transmission_angle",
    "transmission_extremes",
]

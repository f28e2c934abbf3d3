"""Synthesis: from what a designer wants (an ellipse, a path, target coefficients, precision
points) to the dimensions of a linkage.

Each route lives in its own module and returns mechanisms (immutable values of
:mod:`linkwright.mechanisms`) with the error it reached; turning them into documents and
printing them is the job of the layers above (``io`` and the command line). Long searches take
an optional ``progress`` callable, called with the fraction done in [0, 1].
"""

from linkwright.synthesis.burmester import (
    BurmesterCurves,
    BurmesterPoints,
    burmester_fourbars,
    burmester_points,
    centre_point_curve,
    four_pose_dyads,
    four_pose_fourbar,
)
from linkwright.synthesis.ellipse import (
    EllipseError,
    EllipseFit,
    check_on_ellipse,
    doubleslider_family,
    doubleslider_from_ellipse,
    ellipse_synthesis,
    family_angles,
    fit_ellipse,
    trammel_from_conic,
)
from linkwright.synthesis.ellipse import Trammel as EllipseTrammel
from linkwright.synthesis.path import (
    NoFeasibleLinkage,
    PathConstraints,
    PathFit,
    PathSynthesisError,
    fit_path,
)
from linkwright.synthesis.precision import (
    FunctionDesign,
    MotionDesign,
    PrecisionError,
    chebyshev_spacing,
    fourbar_from_dyads,
    freudenstein,
    freudenstein_fit,
    function_error,
    function_pairs,
    path_with_timing,
    pose_positions,
    three_pose_fourbar,
)
from linkwright.synthesis.reinsberg import (
    ReinsbergError,
    reinsberg_complete,
    reinsberg_defect,
    reinsberg_mechanism,
)
from linkwright.synthesis.slider_dyads import (
    SliderCircle,
    SliderMotionDesign,
    four_pose_slider_crank,
    four_pose_slider_point,
    slider_crank_from_dyads,
    slider_line,
    slider_point_circle,
    three_pose_slider_crank,
)
from linkwright.synthesis.spherical_precision import (
    SphericalBurmesterCones,
    SphericalMotionDesign,
    circle_axis_centre,
    coupler_frames,
    spherical_burmester_cones,
    spherical_four_orientation_fourbar,
    spherical_fourbar_from_dyads,
    spherical_three_orientation_fourbar,
)
from linkwright.synthesis.targets import (
    OUTPUTS,
    TargetError,
    TargetSolution,
    TargetSolutions,
    design_fourbar,
    design_to_targets,
)

__all__ = [
    "OUTPUTS",
    "BurmesterCurves",
    "BurmesterPoints",
    "EllipseError",
    "EllipseFit",
    "EllipseTrammel",
    "FunctionDesign",
    "MotionDesign",
    "NoFeasibleLinkage",
    "PathConstraints",
    "PathFit",
    "PathSynthesisError",
    "PrecisionError",
    "ReinsbergError",
    "SliderCircle",
    "SliderMotionDesign",
    "SphericalBurmesterCones",
    "SphericalMotionDesign",
    "TargetError",
    "TargetSolution",
    "TargetSolutions",
    "burmester_fourbars",
    "burmester_points",
    "centre_point_curve",
    "chebyshev_spacing",
    "check_on_ellipse",
    "circle_axis_centre",
    "coupler_frames",
    "design_fourbar",
    "design_to_targets",
    "doubleslider_family",
    "doubleslider_from_ellipse",
    "ellipse_synthesis",
    "family_angles",
    "fit_ellipse",
    "fit_path",
    "four_pose_dyads",
    "four_pose_fourbar",
    "four_pose_slider_crank",
    "four_pose_slider_point",
    "fourbar_from_dyads",
    "freudenstein",
    "freudenstein_fit",
    "function_error",
    "function_pairs",
    "path_with_timing",
    "pose_positions",
    "reinsberg_complete",
    "reinsberg_defect",
    "reinsberg_mechanism",
    "slider_crank_from_dyads",
    "slider_line",
    "slider_point_circle",
    "spherical_burmester_cones",
    "spherical_four_orientation_fourbar",
    "spherical_fourbar_from_dyads",
    "spherical_three_orientation_fourbar",
    "three_pose_fourbar",
    "three_pose_slider_crank",
    "trammel_from_conic",
]

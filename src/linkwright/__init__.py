"""linkwright: a kinematics workbench for planar and spherical linkages.

``import linkwright as lw`` gives the public API in one namespace:

* the families, each an immutable value (:class:`FourBar`, :class:`SliderCrank`, the six-bars,
  the spherical linkages, a :class:`Linkage` composed joint by joint);
* the verbs on them: :func:`solve` (positions and derivatives at given inputs),
  :func:`configurations` (every assembly mode), :func:`circuit` and :func:`circuits` (the closed
  motion as the machine runs), :func:`input_range` (where the input may go), :func:`analyze`,
  :func:`classify` and :func:`instant_centres`;
* pictures: :func:`plot_mechanism`, :func:`plot_diagram`, :func:`animate`, :func:`save_figure`
  (each plot draws into a given matplotlib ``ax=`` or makes its own figure);
* documents: :func:`load_document`, :func:`save_document`, :func:`load_example`,
  :func:`list_examples`, :func:`export`;
* synthesis: :func:`ellipse_synthesis`, :func:`fit_path`, :func:`design_fourbar`,
  :func:`three_pose_fourbar`, :func:`four_pose_fourbar`;
* the curve atlas as its own namespace, :mod:`linkwright.atlas` (``lw.atlas.query``).

Inside the library angles are radians and lengths carry no unit. Names are loaded on first use
(PEP 562), so ``import linkwright`` itself costs next to nothing; the subpackages keep their
fuller APIs (``linkwright.engine``, ``linkwright.analysis``, ...).

Examples
--------
>>> import linkwright as lw
>>> crank_rocker = lw.FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
>>> lw.classify(crank_rocker)
'crank-rocker'
>>> motion = lw.circuit(crank_rocker, 8)
>>> bool(motion.valid.all())
True

A linkage that cannot assemble is still a value; it has no class and no circuit:

>>> too_short = lw.FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
>>> lw.classify(too_short) is None, lw.circuits(too_short, 8)[1]
(True, [])
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Any

from linkwright import _display

try:
    __version__ = version("linkwright")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.1.0"

# Each public name and the module that defines it, imported on first use: the engine pulls in
# scipy (about half a second) and the plots matplotlib, which a CLI's --help does not need.
_WHERE: dict[str, str] = {
    # The families (linkwright.mechanisms.registry; tests check this list against it).
    "FourBar": "linkwright.mechanisms",
    "SliderCrank": "linkwright.mechanisms",
    "DoubleSlider": "linkwright.mechanisms",
    "GearedFiveBar": "linkwright.mechanisms",
    "Watt1": "linkwright.mechanisms",
    "Watt2": "linkwright.mechanisms",
    "Stephenson1": "linkwright.mechanisms",
    "Stephenson3": "linkwright.mechanisms",
    "Linkage": "linkwright.mechanisms",
    "SphericalFourBar": "linkwright.mechanisms",
    "SphericalSixBar": "linkwright.mechanisms",
    "SphericalStephenson3": "linkwright.mechanisms",
    # The joints a Linkage is composed of.
    "FixedJoint": "linkwright.mechanisms",
    "CrankJoint": "linkwright.mechanisms",
    "DyadJoint": "linkwright.mechanisms",
    "HingeJoint": "linkwright.mechanisms",
    "SliderJoint": "linkwright.mechanisms",
    "RigidJoint": "linkwright.mechanisms",
    "SphereCrankJoint": "linkwright.mechanisms",
    "SphereRigidJoint": "linkwright.mechanisms",
    "TriadJoint": "linkwright.mechanisms",
    "SphereTriadJoint": "linkwright.mechanisms",
    # Values and errors.
    "Mechanism": "linkwright.mechanisms",
    "Motion": "linkwright.engine",
    "InputArcs": "linkwright.engine",
    "Document": "linkwright.io",
    "InvalidMechanism": "linkwright.mechanisms",
    "InvalidLinkage": "linkwright.mechanisms",
    "DocumentError": "linkwright.io",
    # Motion.
    "solve": "linkwright.mechanisms",
    "configurations": "linkwright.mechanisms",
    "circuit": "linkwright.mechanisms",
    "circuits": "linkwright.mechanisms",
    "input_range": "linkwright.mechanisms",
    # Analysis.
    "analyze": "linkwright.analysis",
    "classify": "linkwright.analysis",
    "instant_centres": "linkwright.analysis",
    # Pictures.
    "plot_mechanism": "linkwright.plot",
    "plot_diagram": "linkwright.plot",
    "animate": "linkwright.plot",
    "save_figure": "linkwright.plot",
    # Documents and exports.
    "load_document": "linkwright.io",
    "save_document": "linkwright.io",
    "load_example": "linkwright.io",
    "list_examples": "linkwright.io",
    "export": "linkwright.io",
    # Synthesis.
    "ellipse_synthesis": "linkwright.synthesis",
    "fit_path": "linkwright.synthesis",
    "design_fourbar": "linkwright.synthesis",
    "three_pose_fourbar": "linkwright.synthesis",
    "four_pose_fourbar": "linkwright.synthesis",
}

# Subpackages reachable as attributes without an import of their own (the atlas needs the
# optional FAISS and Dask only when it builds or searches at scale).
_SUBPACKAGES = frozenset(
    {"analysis", "atlas", "curves", "engine", "io", "mechanisms", "plot", "synthesis"}
)

# Literal, for tools that read it without running the module; tests check it against _WHERE.
__all__ = [
    "CrankJoint",
    "Document",
    "DocumentError",
    "DoubleSlider",
    "DyadJoint",
    "FixedJoint",
    "FourBar",
    "GearedFiveBar",
    "HingeJoint",
    "InputArcs",
    "InvalidLinkage",
    "InvalidMechanism",
    "Linkage",
    "Mechanism",
    "Motion",
    "RigidJoint",
    "SliderCrank",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereRigidJoint",
    "SphereTriadJoint",
    "SphericalFourBar",
    "SphericalSixBar",
    "SphericalStephenson3",
    "Stephenson1",
    "Stephenson3",
    "TriadJoint",
    "Watt1",
    "Watt2",
    "__version__",
    "analyze",
    "animate",
    "atlas",
    "circuit",
    "circuits",
    "classify",
    "configurations",
    "design_fourbar",
    "ellipse_synthesis",
    "export",
    "fit_path",
    "four_pose_fourbar",
    "input_range",
    "instant_centres",
    "list_examples",
    "load_document",
    "load_example",
    "plot_diagram",
    "plot_mechanism",
    "save_document",
    "save_figure",
    "solve",
    "three_pose_fourbar",
]


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        value = getattr(importlib.import_module(_WHERE[name]), name)
    elif name in _SUBPACKAGES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_WHERE, *_SUBPACKAGES})


def _render_svg(value: object) -> str | None:
    # The plots (and matplotlib) load only when a notebook first shows a linkage.
    from linkwright.plot.jupyter import svg

    return svg(value)


# Mechanisms and motions show themselves in Jupyter through this slot (their layers may not
# import the plots); the root package sits above every layer, so it fills it.
_display.renderer = _render_svg


if TYPE_CHECKING:  # what the names are, for type checkers and editors (never run)
    from linkwright import atlas
    from linkwright.analysis import analyze, classify, instant_centres
    from linkwright.engine import InputArcs, Motion
    from linkwright.io import (
        Document,
        DocumentError,
        export,
        list_examples,
        load_document,
        load_example,
        save_document,
    )
    from linkwright.mechanisms import (
        CrankJoint,
        DoubleSlider,
        DyadJoint,
        FixedJoint,
        FourBar,
        GearedFiveBar,
        HingeJoint,
        InvalidLinkage,
        InvalidMechanism,
        Linkage,
        Mechanism,
        RigidJoint,
        SliderCrank,
        SliderJoint,
        SphereCrankJoint,
        SphereRigidJoint,
        SphereTriadJoint,
        SphericalFourBar,
        SphericalSixBar,
        SphericalStephenson3,
        Stephenson1,
        Stephenson3,
        TriadJoint,
        Watt1,
        Watt2,
        circuit,
        circuits,
        configurations,
        input_range,
        solve,
    )
    from linkwright.plot import animate, plot_diagram, plot_mechanism, save_figure
    from linkwright.synthesis import (
        design_fourbar,
        ellipse_synthesis,
        fit_path,
        four_pose_fourbar,
        three_pose_fourbar,
    )

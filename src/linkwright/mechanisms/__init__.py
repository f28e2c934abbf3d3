"""Named mechanism families: thin constructors over engine plans."""

from linkwright.mechanisms.allconfigs import AllConfigurations, solve_all
from linkwright.mechanisms.base import (
    InvalidMechanism,
    Mechanism,
    circuit,
    circuits,
    configurations,
    input_range,
    solve,
)
from linkwright.mechanisms.linkage import (
    CrankJoint,
    DyadJoint,
    FixedJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SliderJoint,
    SphereCrankJoint,
    SphereRigidJoint,
)
from linkwright.mechanisms.planar import DoubleSlider, FourBar, GearedFiveBar, SliderCrank
from linkwright.mechanisms.sixbar import Stephenson1, Stephenson3, Watt1, Watt2
from linkwright.mechanisms.spherical import (
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
)

FAMILIES: dict[str, type[Mechanism]] = {
    cls.family: cls
    for cls in (
        FourBar,
        SliderCrank,
        GearedFiveBar,
        DoubleSlider,
        Watt1,
        Watt2,
        Stephenson1,
        Stephenson3,
        Linkage,
        SphericalFourBar,
        SphericalSixBar,
        SphericalStephenson3,
    )
}

__all__ = [
    "FAMILIES",
    "AllConfigurations",
    "CrankJoint",
    "DoubleSlider",
    "DyadJoint",
    "FixedJoint",
    "FourBar",
    "GearedFiveBar",
    "InvalidLinkage",
    "InvalidMechanism",
    "Linkage",
    "Mechanism",
    "RigidJoint",
    "SliderCrank",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereRigidJoint",
    "SphericalFourBar",
    "SphericalSixBar",
    "SphericalStephenson3",
    "Stephenson1",
    "Stephenson3",
    "Watt1",
    "Watt2",
    "circuit",
    "circuits",
    "configurations",
    "input_range",
    "solve",
    "solve_all",
]

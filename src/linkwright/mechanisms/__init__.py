"""Named mechanism families: thin constructors over engine plans."""

from linkwright.mechanisms import registry
from linkwright.mechanisms.allconfigs import AllConfigurations, solve_all
from linkwright.mechanisms.base import (
    InvalidMechanism,
    Mechanism,
    circuit,
    circuits,
    configurations,
    input_range,
    running_circuit,
    solve,
)
from linkwright.mechanisms.hinge_joints import (
    HingeTriadJoint,
    SphereHingeTriadJoint,
    SphereTurningTriadJoint,
    TurningTriadJoint,
)
from linkwright.mechanisms.linkage import (
    CrankJoint,
    DyadJoint,
    FixedJoint,
    HingeJoint,
    InvalidLinkage,
    Linkage,
    RigidJoint,
    SliderJoint,
    SphereCrankJoint,
    SphereRigidJoint,
    SphereTriadJoint,
    TriadJoint,
)
from linkwright.mechanisms.planar import DoubleSlider, FourBar, GearedFiveBar, SliderCrank
from linkwright.mechanisms.sixbar import Stephenson1, Stephenson3, Watt1, Watt2
from linkwright.mechanisms.spherical import (
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
)

FAMILIES: dict[str, type[Mechanism]] = {f.name: f.cls for f in registry.families()}
"""Every registered family's class, by name (:mod:`linkwright.mechanisms.registry`)."""

__all__ = [
    "FAMILIES",
    "AllConfigurations",
    "CrankJoint",
    "DoubleSlider",
    "DyadJoint",
    "FixedJoint",
    "FourBar",
    "GearedFiveBar",
    "HingeJoint",
    "HingeTriadJoint",
    "InvalidLinkage",
    "InvalidMechanism",
    "Linkage",
    "Mechanism",
    "RigidJoint",
    "SliderCrank",
    "SliderJoint",
    "SphereCrankJoint",
    "SphereHingeTriadJoint",
    "SphereRigidJoint",
    "SphereTriadJoint",
    "SphereTurningTriadJoint",
    "SphericalFourBar",
    "SphericalSixBar",
    "SphericalStephenson3",
    "Stephenson1",
    "Stephenson3",
    "TriadJoint",
    "TurningTriadJoint",
    "Watt1",
    "Watt2",
    "circuit",
    "circuits",
    "configurations",
    "input_range",
    "registry",
    "running_circuit",
    "solve",
    "solve_all",
]

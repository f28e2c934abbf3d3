"""Composed linkages driven at a hinge of a triad's loop (``hinge-triad``, ``turning-triad``).

Each is checked against the family it writes out joint by joint, which builds its plan apart
(:mod:`linkwright.mechanisms.stephenson3_inputs`, paper 001's ``SPHERE_PLANS``): the same real
configurations at every input (counts and positions, matched one to one). A document round-trips
through TOML, and the usual one-line errors name the joint and the field.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from triad_helpers import assert_same_configurations

from linkwright.io import load_document, mechanism_to_dict, save_document
from linkwright.mechanisms import (
    CrankJoint,
    FixedJoint,
    InvalidMechanism,
    Linkage,
    SphericalStephenson3,
    Stephenson3,
)
from linkwright.mechanisms.hinge_joints import (
    HingeTriadJoint,
    SphereHingeTriadJoint,
    SphereTurningTriadJoint,
    TurningTriadJoint,
)

THETA = np.radians(np.arange(-180.0, 180.0, 11.0) + 0.5)
S3 = dict(A0=[0.0, 0.0], B0=[4.0, 0.0], D0=[0.0, 2.8], crank=1.0, coupler=4.0, rocker=3.0,
          u1=2.0, v1=2.0, link1=0.9, link2=0.4)  # fmt: skip
FRAME = [FixedJoint("A0", [0.0, 0.0]), FixedJoint("B0", [4.0, 0.0]), FixedJoint("D0", [0.0, 2.8])]


def plane_linkage(inp: str) -> Linkage:
    if inp == "D":
        last = HingeTriadJoint("A", "B", "C", "D", "A0", 1.0, "B0", 3.0, "D0", a=0.9, b=0.4,
                               side=4.0, u=2.0, v=2.0)  # fmt: skip
    else:
        last = TurningTriadJoint("A", "B", "D", "C", "A0", 1.0, "B0", 3.0, "D0", 0.4, side=4.0,
                                 hu=2.0, hv=2.0, arm=0.9)  # fmt: skip
    return Linkage(joints=[*FRAME, last], traced=("C",))


@pytest.mark.parametrize("inp", ["C", "D"])
def test_a_composed_stephenson3_driven_at_a_hinge_is_the_familys(inp):
    family = Stephenson3(**S3, input=inp)
    compared = assert_same_configurations(
        plane_linkage(inp), family, THETA, ("A", "B", "C", "D"), 1e-9
    )
    assert compared > 20


P001 = np.radians([71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7])


def sphere_linkage(inp: str) -> Linkage:
    """Paper 001's six-bar joint by joint: A = z, D and G on the meridian towards +y."""
    a1, a2, a3, a4, a6, sigma, a7, a8, a9 = P001
    frame = [
        FixedJoint("A", [0.0, 0.0, 1.0]),
        FixedJoint("D", [0.0, math.sin(a1), math.cos(a1)]),
        FixedJoint("G", [0.0, math.sin(a1 + a9), math.cos(a1 + a9)]),
    ]
    turn = math.pi - sigma
    if inp == "F":
        last = SphereHingeTriadJoint("C", "B", "E", "F", "D", a4, "A", a2, "G", a=a7, b=a8,
                                     side=a3, arc=a6, angle=turn)  # fmt: skip
    else:
        last = SphereTurningTriadJoint("C", "B", "F", "E", "D", a4, "A", a2, "G", a8, side=a3,
                                       harc=a6, hangle=turn, arm=a7)  # fmt: skip
    return Linkage(joints=[*frame, last], traced=("E",), space="sphere")


@pytest.mark.parametrize("inp", ["E", "F"])
def test_a_composed_paper001_driven_at_a_hinge_is_the_familys(inp):
    family = SphericalStephenson3(*P001, input=inp)
    compared = assert_same_configurations(
        sphere_linkage(inp), family, THETA, ("B", "C", "E", "F"), 1e-9
    )
    assert compared > 20


@pytest.mark.parametrize("which", ["plane-C", "plane-D", "sphere-E", "sphere-F"])
def test_a_hinge_triad_document_round_trips(tmp_path, which):
    space, inp = which.split("-")
    mech = plane_linkage(inp) if space == "plane" else sphere_linkage(inp)
    path = tmp_path / "doc.toml"
    save_document(mechanism_to_dict(mech), path)
    back = load_document(path).mechanism
    assert_same_configurations(back, mech, THETA[::3], list(mech.reported_joints), 1e-12)


def test_a_hinge_triad_is_the_one_input():
    crank = CrankJoint("E", "A0", 1.0)
    with pytest.raises(InvalidMechanism, match="already drives the linkage"):
        Linkage(joints=[*plane_linkage("D").joints, crank])


def _leg(hinge: str = "D", a: float = 0.9) -> HingeTriadJoint:
    return HingeTriadJoint("A", "B", "C", hinge, "A0", 1.0, "B0", 3.0, "D0", a=a, b=0.4,
                           side=4.0, u=2.0, v=2.0)  # fmt: skip


def test_a_hinge_triad_places_new_joints_only():
    with pytest.raises(InvalidMechanism, match="hinge must be a new joint's name"):
        Linkage(joints=[*FRAME, _leg(hinge="D0")])


def test_a_bad_hinge_triad_length_names_its_field():
    with pytest.raises(InvalidMechanism, match=r"^joint 'A': a "):
        Linkage(joints=[*FRAME, _leg(a=-0.9)])

"""Forces: kinetostatics and inverse dynamics of planar and spherical linkages (issue 25).

:mod:`~linkwright.dynamics.bodies` reads a plan's rigid bodies off its step kinds,
:mod:`~linkwright.dynamics.model` holds mass properties and loads (and their validation),
:mod:`~linkwright.dynamics.planar` solves Newton–Euler link by link and
:mod:`~linkwright.dynamics.spherical` Euler's equations about the sphere's centre, each checked
by the energy balance. :func:`forces` is the one-call entry for a mechanism.
"""

from __future__ import annotations

from linkwright.dynamics.api import forces, forces_setup, reduced_inertia
from linkwright.dynamics.bodies import Body, Structure, UnsupportedPlan, structure
from linkwright.dynamics.model import (
    ForcesInputError,
    Loads,
    MassProps,
    check_forces_input,
    loads_from,
    masses_from,
)
from linkwright.dynamics.planar import Forces, body_kinematics, forces_of, mechanical_advantage

__all__ = [
    "Body",
    "Forces",
    "ForcesInputError",
    "Loads",
    "MassProps",
    "Structure",
    "UnsupportedPlan",
    "body_kinematics",
    "check_forces_input",
    "forces",
    "forces_of",
    "forces_setup",
    "loads_from",
    "masses_from",
    "mechanical_advantage",
    "reduced_inertia",
    "structure",
]

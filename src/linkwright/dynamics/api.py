"""One-call forces for a mechanism, and paper 003's inertia of the output reduced to the input."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.dynamics.bodies import Structure, structure
from linkwright.dynamics.model import (
    Loads,
    MassProps,
    check_speed,
    link_lengths,
    loads_from,
    masses_from,
)
from linkwright.dynamics.planar import Forces, body_kinematics, forces_of
from linkwright.mechanisms.base import Mechanism, solve

__all__ = ["forces", "forces_setup", "reduced_inertia"]

Array = NDArray[np.float64]


def forces(
    mechanism: Mechanism,
    inputs: ArrayLike,
    masses: Mapping[str, Any] | None = None,
    loads: Loads | None = None,
) -> Forces:
    """Newton–Euler forces (and the energy balance's torque) of a planar mechanism at the
    input angles ``inputs`` (radians), on its own assembly.

    ``masses`` maps link names (their length fields) to a :class:`MassProps`, a mass alone
    (a uniform body) or a document-style table ``{"mass": .., "centre": {"u": .., "v": ..},
    "inertia": ..}``.

    Examples
    --------
    A crank-rocker whose rocker alone has mass, its centre at its pivot (so only its inertia
    J counts), driven at 60 rpm: the torque is paper 003's M^i = ω² J φ3′ φ3″.

    >>> from linkwright.mechanisms import FourBar
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3.5, rocker=3)
    >>> rocker = MassProps(1.0, centre=(0.0, 0.0), inertia=0.25)
    >>> f = forces(fb, [0.3, 2.0], {"rocker": rocker}, Loads(speed_rpm=60))
    >>> m_i, _ = reduced_inertia(fb, [0.3, 2.0], 0.25, 60)
    >>> bool(np.allclose(f.input_torque, m_i, rtol=1e-12, atol=0))
    True
    """
    st = structure(mechanism.plan)
    props: dict[str, MassProps] = {}
    plain = {k: v for k, v in (masses or {}).items() if not isinstance(v, MassProps)}
    if plain:
        lengths = link_lengths(st, mechanism.params())
        props.update(masses_from(plain, st, lengths, path="masses"))
    props.update({k: v for k, v in (masses or {}).items() if isinstance(v, MassProps)})
    motion = solve(mechanism, inputs, order=2)
    return forces_of(st, mechanism.params(), motion, props, loads or Loads())


def forces_setup(
    mechanism: Mechanism,
    mass: Any,
    loads: Any,
    *,
    speed: float | None = None,
    speed_field: str = "loads.speed",
) -> tuple[Structure, dict[str, MassProps], Loads]:
    """A document's bodies, ``[mechanism.mass]`` and ``[loads]``, checked for a forces run.

    ``speed`` (rpm) replaces the document's; ``speed_field`` is how an error names it.
    Raises :class:`~linkwright.dynamics.UnsupportedPlan` for a plan forces cannot set up and
    :class:`~linkwright.dynamics.ForcesInputError` naming the field for bad masses or loads.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3.5, rocker=3)
    >>> st, masses, loads = forces_setup(fb, {"crank": 0.2}, {"speed": 60})
    >>> st.names, masses["crank"].mass, loads.speed_rpm
    (('crank', 'coupler', 'rocker'), 0.2, 60.0)
    >>> forces_setup(fb, {"crank": 0.2}, None)
    Traceback (most recent call last):
    ...
    linkwright.dynamics.model.ForcesInputError: loads.speed: must be given and non-zero (rpm) \
for inertia forces; set loads.inertia = false for a static analysis
    """
    from dataclasses import replace

    st = structure(mechanism.plan)
    masses = masses_from(mass or {}, st, link_lengths(st, mechanism.params()))
    parsed = loads_from(loads, st, mechanism.plan.joints)
    if speed is not None:
        parsed = replace(parsed, speed_rpm=float(speed))
    check_speed(masses, parsed, speed_field)
    return st, masses, parsed


def reduced_inertia(
    mechanism: Mechanism,
    inputs: ArrayLike,
    inertia: float,
    speed_rpm: float,
    output: str = "rocker",
) -> tuple[Array, Array]:
    """Paper 003's inertia torque and power of the output link reduced to the input at
    constant speed: M^i = ω1² J3 φ3′ φ3″ and P^i = M^i ω1 (J3 the output's moment of inertia
    about its ground pivot, φ3 its angle, ′ by the input angle, ω1 rad/s from ``speed_rpm``).
    """
    st = structure(mechanism.plan)
    motion = solve(mechanism, inputs, order=2)
    q = body_kinematics(st.body(output), None, motion)
    omega = speed_rpm * 2.0 * np.pi / 60.0
    m_i = omega**2 * inertia * q.phi1 * q.phi2
    return m_i, m_i * omega

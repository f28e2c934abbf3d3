"""Paper 001's own coordinates of its spherical Stephenson III: the joint angles θ1, θ4, θ5, θ6
read off solved positions, and the mechanism's triad at an input, in the form
:func:`~linkwright.engine.sphere_triad.sphere_triad` takes (paper 001's eqs. 4–5).

The engine solves the linkage through its plan (:func:`linkwright.mechanisms.solve_all`); these
readings are what the paper's tables print.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.sphere_triad import circle_frame, on_circle
from linkwright.geometry import sphere
from linkwright.mechanisms import AllConfigurations, SphericalStephenson3

__all__ = ["paper_angles", "triad_of"]

Array = NDArray[np.float64]


def _frames(p: dict[str, Array]) -> tuple[Array, Array, Array]:
    """The circles of B (about A, from D), C (about D, from G) and F (about G, from −D).

    θ1 = ∠BAD and θ4 = ∠CDG turn left-handed (eq. 5: B = (sin a2 sin θ1, sin a2 cos θ1,
    cos a2), C's x component sin a4 sin θ4); θ6 turns right-handed about +OG, as the family's
    plan drives it.
    """
    return (
        circle_frame(p["A"], p["D"], -1.0),
        circle_frame(p["D"], p["G"], -1.0),
        circle_frame(p["G"], p["away"], 1.0),
    )


def triad_of(
    mechanism: SphericalStephenson3, theta6: ArrayLike
) -> tuple[Array, Array, Array, Array, Array, Array, Array, Array, Array]:
    """The arguments of :func:`~linkwright.engine.sphere_triad.sphere_triad` for input FG.

    F is placed at θ6 (radians); the triad is B on the circle about A (θ1), C on the circle
    about D (θ4), BC = a3, E at arc a6 from C and angle π − σ from C→B, EF = a7. Where
    ``theta6`` has a last (samples) axis, the mechanism's parameters get one after their batch
    axes; a scalar ``theta6`` gives the mechanism's batch shape.

    Examples
    --------
    At θ6 = 0, F is on the great circle of A, D and G, beyond G: at arc a1 + a9 + a8 = 225°
    from A.

    >>> m = SphericalStephenson3(*np.radians([115, 105, 110, 90, 80, 70, 65, 85, 25]))
    >>> frame_b, a2, frame_c, a4, a3, a6, turn, f, a7 = triad_of(m, 0.0)
    >>> f.round(6) + 0.0
    array([ 0.      , -0.707107, -0.707107])
    """
    p = mechanism.params()
    theta = np.asarray(theta6, dtype=float)
    frame_b, frame_c, frame_f = _frames(p)
    names = ("a2", "a4", "a3", "a6", "turn", "a7", "a8")
    s = {k: np.asarray(p[k], dtype=float) for k in names}
    if theta.ndim:
        frame_b, frame_c, frame_f = (fr[..., None, :, :] for fr in (frame_b, frame_c, frame_f))
        s = {k: v[..., None] for k, v in s.items()}
    f = on_circle(frame_f, s["a8"], theta)
    return frame_b, s["a2"], frame_c, s["a4"], s["a3"], s["a6"], s["turn"], f, s["a7"]


def paper_angles(mechanism: SphericalStephenson3, configs: AllConfigurations) -> dict[str, Array]:
    """Paper 001's joint angles of each configuration, read off its positions (radians).

    ``theta1`` = ∠BAD (eq. 5's B), ``theta4`` = ∠CDG (eq. 5's C), ``theta6`` the angle of F
    about +OG from G→(away from D) (the input when driven at FG), and ``theta5`` the joint angle
    at F: from the great circle F→G to F→E, right-handed about +OF (the rotation that eq. 9
    means to make about OF). Each has the shape of ``configs.valid``, in (−π, π], NaN where no
    configuration.
    """
    p = mechanism.params()
    frames = [fr[..., None, None, :, :] for fr in _frames(p)]
    pos = configs.positions

    def angle(frame: Array, x: Array) -> Array:
        return np.arctan2(sphere.dot(x, frame[..., 2, :]), sphere.dot(x, frame[..., 1, :]))

    return {
        "theta1": angle(frames[0], pos["B"]),
        "theta4": angle(frames[1], pos["C"]),
        "theta5": sphere.angle_at(pos["F"], pos["G"], pos["E"]),
        "theta6": angle(frames[2], pos["F"]),
    }

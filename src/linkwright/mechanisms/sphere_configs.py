"""Every real configuration of paper 001's spherical Stephenson III, driven at AB or at FG.

Driven at AB (θ1 = ∠BAD, paper 001's eq. 5), the linkage is the spherical four-bar ABCD
followed by the dyad E–F–G: C closes on two branches, E follows rigidly, F closes on two
branches, so there are **at most 2 × 2 = 4** real configurations, each a chain of
circle–circle intersections (:func:`linkwright.mechanisms.configurations`).

Paper 001 says "at most 8" for this input. Its system (4) fixes the coupler's shape by
``cos BE = cos a3 cos a6 − sin a3 sin a6 cos σ``, i.e. by cos σ only: it admits E on either side
of the great circle CB, σ and −σ, which is the mirror-image coupler, another mechanism. Counting
both couplers gives 4 + 4 = 8; one rigid coupler has 4.

Driven at FG (θ6, the angle of F about +OG from the great circle G→(away from D), as
:class:`~linkwright.mechanisms.spherical.SphericalStephenson3` defines it), F is placed first
and the coupler BCE, held by AB, CD and EF, is a spherical triad: **at most 8** real
configurations, the real roots of a degree-8 polynomial
(:func:`linkwright.engine.sphere_triad.sphere_triad`). This is where paper 001's eight
genuinely occur.

:func:`solve_all_spherical` answers both and recomputes every configuration's error against
every constraint from its joint positions. :func:`paper_angles` reads paper 001's joint angles
θ1, θ4, θ5, θ6 off the positions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.sphere_triad import circle_frame, on_circle, sphere_triad
from linkwright.geometry import sphere
from linkwright.mechanisms.allconfigs import AllConfigurations, pack_slots
from linkwright.mechanisms.base import configurations
from linkwright.mechanisms.spherical import SphericalStephenson3

__all__ = [
    "JOINTS",
    "SLOTS",
    "InvalidInputs",
    "paper_angles",
    "solve_all_spherical",
    "triad_of",
]

Array = NDArray[np.float64]

JOINTS = ("A", "D", "G", "B", "C", "E", "F")
"""The joints reported for every configuration."""

SLOTS = {"AB": 4, "FG": 8}
"""The most real configurations at one input: four-bar × dyad, and the triad's degree 8."""

# Two configurations at one input closer than this (largest chord between their joints, on the
# unit sphere) are one: at a limit position both branches of a dyad give the same joints.
SAME_TOL = 1e-7


class InvalidInputs(ValueError):
    """The input samples are not a usable array of finite angles."""


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


def _inputs(mechanism: SphericalStephenson3, inputs: ArrayLike) -> tuple[Array, tuple[int, ...]]:
    theta = np.asarray(inputs, dtype=float)
    if theta.ndim == 0:
        raise InvalidInputs("inputs: give a 1-D array of samples (or batch + samples)")
    if not np.all(np.isfinite(theta)):
        raise InvalidInputs("inputs: every input angle must be finite")
    try:
        batch = np.broadcast_shapes(mechanism.batch_shape, theta.shape[:-1])
    except ValueError as exc:
        raise InvalidInputs(f"inputs: do not broadcast with the mechanism's batch: {exc}") from None
    return np.broadcast_to(theta, batch + theta.shape[-1:]), batch


def _check(mechanism: object) -> SphericalStephenson3:
    if not isinstance(mechanism, SphericalStephenson3):
        family = getattr(mechanism, "family", type(mechanism).__name__)
        raise TypeError(f"solve_all_spherical handles SphericalStephenson3, not {family!r}")
    return mechanism


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
    p = _check(mechanism).params()
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
    p = _check(mechanism).params()
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


def solve_all_spherical(mechanism: SphericalStephenson3, inputs: ArrayLike) -> AllConfigurations:
    """Every real configuration of paper 001's spherical Stephenson III at each input, batched.

    Driven at AB (``mechanism.input == "AB"``, θ1 radians): the four sign combinations
    (``assembly``, ``assembly2``) = (1, 1), (1, −1), (−1, 1), (−1, −1) of the construction
    plan, in that order, each reported where real (and once where two coincide at a limit
    position): at most 4. Driven at FG (θ6 radians): F is placed, then the spherical triad's
    degree-8 polynomial gives at most 8, ordered by θ1 from −π to π. The mechanism's own
    ``assembly`` and ``assembly2`` are not used: every configuration is returned with its
    signs, sign((B × D)·C) and sign((E × G)·F), read off the positions when driven at FG (0
    marks a configuration exactly at that dyad's limit).

    Every configuration's error against every constraint is recomputed from its positions:
    ``AB``, ``BC``, ``CD``, ``EF``, ``FG`` (|arc − length|, radians), ``E`` (chord from its
    place on the coupler), ``unit`` (largest |‖X‖ − 1| of B, C, E, F) and ``input`` (chord from
    where the input angle puts the driven joint).

    Parameters
    ----------
    mechanism : SphericalStephenson3, dimensions may have a batch shape.
    inputs : ``(samples,)`` or ``batch + (samples,)``, radians.

    Returns
    -------
    AllConfigurations
        Arrays ``batch + (samples, slots)``, slots 4 for AB and 8 for FG (see :data:`SLOTS`),
        positions add a trailing 3 (unit vectors); ``driven`` is "AB" or "FG".

    Raises
    ------
    TypeError
        For another family.
    InvalidInputs
        For a scalar or non-finite input, or one that does not broadcast with the batch.

    Examples
    --------
    Input FG of ``linkwright papers 001``'s mechanism at θ6 = 280°: eight configurations, each
    holding every constraint, with their signs:

    >>> from dataclasses import replace
    >>> from linkwright.mechanisms import solve
    >>> fg = SphericalStephenson3(*np.radians([115, 105, 110, 90, 80, 70, 65, 85, 25]), input="FG")
    >>> every = solve_all_spherical(fg, np.radians([280.0]))
    >>> int(every.count[0]), bool(np.nanmax(every.residual) < 1e-14)
    (8, True)
    >>> every.assembly[0].astype(int).tolist()
    [1, -1, -1, 1, 1, 1, -1, 1]
    >>> every.assembly2[0].astype(int).tolist()
    [1, -1, 1, -1, -1, 1, 1, -1]
    >>> np.degrees(paper_angles(fg, every)["theta1"]).round(3)
    array([[-171.04 , -168.477, -106.71 ,  -91.611,  -18.477,   18.475,   46.259,  149.416]])

    Each is the configuration that the AB-driven plan builds on its own signs at its θ1:

    >>> theta1 = paper_angles(fg, every)["theta1"][0]
    >>> gaps = []
    >>> for k in range(8):
    ...     back = replace(fg, input="AB", assembly=every.assembly[0, k],
    ...                    assembly2=every.assembly2[0, k])
    ...     f = solve(back, theta1[k : k + 1], order=0).positions["F"]
    ...     gaps.append(np.abs(f[0] - every.positions["F"][0, k]).max())
    >>> bool(max(gaps) < 1e-12)
    True

    Driven at AB it has at most four (here 0, 4 and 2 at θ1 = 0°, 90°, 200°); a linkage that
    cannot assemble (AD = 90° but AB + BC + CD = 60°) has none, and nothing NaN is valid:

    >>> solve_all_spherical(replace(fg, input="AB"), np.radians([0.0, 90.0, 200.0])).count
    array([0, 4, 2])
    >>> short = SphericalStephenson3(*np.radians([90, 10, 20, 30, 30, 90, 40, 50, 40]), input="FG")
    >>> none = solve_all_spherical(short, [0.0, 1.0])
    >>> none.count, bool(np.isnan(none.positions["B"]).all()), bool(none.valid.any())
    (array([0, 0]), True, False)
    """
    _check(mechanism)
    theta, batch = _inputs(mechanism, inputs)
    driven = mechanism.input
    p = mechanism.params()
    slots = SLOTS[driven]
    # Every array below has the axes batch + (samples, slots); parameters get two unit axes.
    points = ("A", "D", "G", "away")
    q = {k: np.asarray(v, dtype=float)[..., None, None] for k, v in p.items() if k not in points}
    q.update({k: np.asarray(p[k], dtype=float)[..., None, None, :] for k in points})
    shape = batch + theta.shape[-1:] + (slots,)

    if driven == "AB":
        # The plan's dyads divide by sin(arc P1P2), 0 where B lands on ±D: masked, not an error.
        with np.errstate(invalid="ignore", divide="ignore"):
            confs = configurations(mechanism, theta, order=0)
        pos = {k: np.stack([m.positions[k] for _, m in confs], axis=-2) for k in "BCEF"}
        pos = {k: np.broadcast_to(v, shape + (3,)) for k, v in pos.items()}
        valid = np.broadcast_to(np.stack([m.valid for _, m in confs], axis=-1), shape)
        sign1 = np.broadcast_to(np.array([s[0] for s, _ in confs], dtype=float), shape)
        sign2 = np.broadcast_to(np.array([s[1] for s, _ in confs], dtype=float), shape)
        valid = _drop_repeats(pos, valid)
        pos, valid, sign1, sign2 = pack_slots(pos, valid, sign1, sign2)
    else:
        triad = triad_of(mechanism, theta)
        poses = sphere_triad(*triad)
        f = triad[7]
        pos = {"B": poses.b, "C": poses.c, "E": poses.e}
        pos["F"] = np.where(poses.valid[..., None], f[..., None, :], np.nan)
        pos = {k: np.broadcast_to(v, shape + (3,)) for k, v in pos.items()}
        valid = np.broadcast_to(poses.valid, shape)
        with np.errstate(invalid="ignore"):
            sign1 = np.sign(sphere.dot(sphere.cross(pos["B"], q["D"]), pos["C"]))
            sign2 = np.sign(sphere.dot(sphere.cross(pos["E"], q["G"]), pos["F"]))
    for k in ("A", "D", "G"):
        pos[k] = np.where(valid[..., None], q[k], np.nan)
    pos = {k: pos[k] for k in JOINTS}

    frame_b, _, frame_f = (fr[..., None, None, :, :] for fr in _frames(p))
    th = theta[..., None]
    with np.errstate(invalid="ignore"):
        residuals = {
            "AB": np.abs(sphere.arc(pos["A"], pos["B"]) - q["a2"]),
            "BC": np.abs(sphere.arc(pos["B"], pos["C"]) - q["a3"]),
            "CD": np.abs(sphere.arc(pos["C"], pos["D"]) - q["a4"]),
            "E": sphere.frame_error(pos["C"], pos["B"], pos["E"], q["a6"], q["turn"]),
            "EF": np.abs(sphere.arc(pos["E"], pos["F"]) - q["a7"]),
            "FG": np.abs(sphere.arc(pos["F"], pos["G"]) - q["a8"]),
            "unit": np.maximum.reduce([np.abs(sphere.norm(pos[k]) - 1.0) for k in "BCEF"]),
        }
        if driven == "AB":
            placed = on_circle(frame_b, q["a2"], th)
            residuals["input"] = sphere.norm(pos["B"] - placed)
        else:
            placed = on_circle(frame_f, q["a8"], th)
            residuals["input"] = sphere.norm(pos["F"] - placed)
    residuals = {k: np.where(valid, v, np.nan) for k, v in residuals.items()}
    residual = np.where(valid, np.maximum.reduce(list(residuals.values())), np.nan)
    return AllConfigurations(
        driven=driven,
        input=theta,
        positions=pos,
        valid=valid,
        count=valid.sum(axis=-1),
        assembly=np.where(valid, sign1, np.nan),
        assembly2=np.where(valid, sign2, np.nan),
        residuals=residuals,
        residual=residual,
    )


def _drop_repeats(pos: dict[str, Array], valid: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Mark a configuration invalid where an earlier slot holds the same joints."""
    joints = np.concatenate([pos[k] for k in "BCEF"], axis=-1)  # (..., slots, 12)
    joints = np.where(valid[..., None], joints, np.nan)
    gap = np.abs(joints[..., :, None, :] - joints[..., None, :, :]).max(axis=-1)
    n = valid.shape[-1]
    earlier = np.tril(np.ones((n, n), dtype=bool), k=-1)  # [j, i]: i < j
    with np.errstate(invalid="ignore"):
        same = (gap <= SAME_TOL) & earlier
    return valid & ~same.any(axis=-1)

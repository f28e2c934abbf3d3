"""Every real configuration of a Stephenson-III six-bar, driven at its crank or at its output.

Driven at the crank A0A, the six-bar is a four-bar plus a dyad: two branch signs, at most four
configurations, each a chain of circle–circle intersections. Driven at the output D0D, the joint
D is known and the coupler ABC, held by the crank (to A0), the rocker (to B0) and the link CD (to
D), is a triad: an Assur group of class III with up to six configurations, which no construction
plan can place (:func:`linkwright.engine.triad.triad_poses` finds them all).

Both are answered by :func:`solve_all`, which returns every real configuration at each input
sample, with the positions of all joints and each configuration's error against every
constraint, recomputed from the positions.

The mechanism is any object with the fields of
:class:`~linkwright.mechanisms.sixbar.Stephenson3` (read by name): A0, B0, D0 (points), crank
(A0A), coupler (AB), rocker (B0B), u1, v1 (joint C in the coupler frame: origin A, x along A→B,
v to the left), link1 (CD), link2 (D0D), u, v (the traced point P in the frame origin C, x along
C→D) and ``input`` ("crank" or "output"). Its own ``assembly`` and ``assembly2`` are not used:
all configurations are returned, each with its two signs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.triad import circle_intersection, triad_poses
from linkwright.geometry import plane

__all__ = ["JOINTS", "AllConfigurations", "solve_all"]

Array = NDArray[np.float64]

JOINTS = ("A0", "B0", "D0", "A", "B", "C", "D", "P")
"""The joints reported for every configuration (those of the Stephenson-III family)."""

_POINTS = ("A0", "B0", "D0")
_SCALARS = ("crank", "coupler", "rocker", "u1", "v1", "link1", "link2", "u", "v")
_SLOTS = {"crank": 4, "output": 6}
# Two configurations at one input closer than this (largest joint distance relative to the
# mechanism's size) are one: at a limit position both branches of a dyad give the same joints.
SAME_TOL = 1e-7


@dataclass(frozen=True)
class AllConfigurations:
    """Every real configuration of a batch of six-bars at each input sample.

    Arrays have the shape ``batch + (samples, slots)`` (positions add a trailing 2), with
    ``slots`` 4 when driven at the crank and 6 at the output. At each sample the real
    configurations come first, the rest is NaN (``valid`` False). Driven at the crank they are
    in the order of their signs (``assembly``, ``assembly2``) = (1, 1), (1, −1), (−1, 1),
    (−1, −1); at the output in the order of the coupler's angle (of B − A) from −π to π.

    Attributes
    ----------
    driven : "crank" or "output", the link the input drives.
    input : ``batch + (samples,)``, the input angle θ of each sample (radians).
    positions : joint → ``batch + (samples, slots, 2)``, for every name in :data:`JOINTS`.
    valid : ``batch + (samples, slots)``, the slot holds a configuration.
    count : ``batch + (samples,)``, the number of configurations.
    assembly, assembly2 : the signs of (B0 − A) × (B − A) and (D0 − C) × (D − C) of each
        configuration, as the family's fields define them (the branch used when driven at the
        crank; read off the positions when driven at the output, where 0 marks a configuration
        exactly at that dyad's limit).
    residuals : constraint → error of each configuration divided by the mechanism's size:
        ``crank``, ``coupler``, ``rocker``, ``link1``, ``link2`` (|length error|), ``C`` and
        ``P`` (distance from their (u, v) places), ``input`` (the driven joint's distance from
        where θ puts it).
    residual : the largest of ``residuals`` for each configuration.

    For the spherical Stephenson III (:class:`~linkwright.mechanisms.SphericalStephenson3`,
    :func:`~linkwright.mechanisms.sphere_configs.solve_all_spherical`) ``driven`` is "AB" or
    "FG", ``slots`` 4 or 8, positions end in 3 (unit vectors of the joints A, D, G, B, C, E, F),
    configurations driven at FG come in the order of θ1, the signs are those of (B × D)·C and
    (E × G)·F, and the residuals (``AB``, ``BC``, ``CD``, ``E``, ``EF``, ``FG``, ``unit``,
    ``input``) are radians of arc or chords on the unit sphere.
    """

    driven: str
    input: Array
    positions: dict[str, Array]
    valid: NDArray[np.bool_]
    count: NDArray[np.int_]
    assembly: Array
    assembly2: Array
    residuals: dict[str, Array]
    residual: Array


def _on_link(origin: Array, toward: Array, u: Array, v: Array) -> Array:
    """The point (u, v) in the frame origin→toward (x along the link, v to the left)."""
    e = toward - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        e = e / plane.norm(e)[..., None]
    return origin + u[..., None] * e + v[..., None] * plane.perp(e)


def _read(mechanism: Any) -> tuple[dict[str, Array], str]:
    family = getattr(mechanism, "family", "stephenson3")
    if family != "stephenson3":
        raise TypeError(
            f"solve_all handles the planar and spherical Stephenson-III six-bars, not {family!r}"
        )
    missing = [f for f in _POINTS + _SCALARS if not hasattr(mechanism, f)]
    if missing:
        raise TypeError(f"not a Stephenson-III six-bar: no field {', '.join(missing)}")
    driven = getattr(mechanism, "input", "crank")
    if driven not in _SLOTS:
        raise ValueError(f"input: must be 'crank' or 'output', got {driven!r}")
    p = {f: np.asarray(getattr(mechanism, f), dtype=float) for f in _POINTS + _SCALARS}
    for f in _POINTS:
        if p[f].shape[-1:] != (2,):
            raise ValueError(f"{f}: must be a point [x, y], got shape {p[f].shape}")
    return p, driven


def _scale(p: dict[str, Array]) -> Array:
    """The largest distance between two joints of one link (as ``SixBar.scale``)."""
    sizes = [p[k] for k in ("crank", "coupler", "rocker", "link1", "link2")]
    sizes += [np.hypot(p["u1"], p["v1"]), np.hypot(p["u1"] - p["coupler"], p["v1"])]
    sizes += [plane.norm(p[a] - p[b]) for a, b in (("A0", "B0"), ("A0", "D0"), ("B0", "D0"))]
    return np.maximum.reduce(np.broadcast_arrays(*sizes))


def solve_all(mechanism: Any, inputs: ArrayLike) -> AllConfigurations:
    """Every real configuration of a Stephenson-III six-bar at each input, batched.

    Driven at the crank (``mechanism.input == "crank"``, θ the angle of A − A0), the four-bar
    and the dyad C–D–D0 are closed on both branches each: up to 4 configurations. Driven at
    the output (``"output"``, θ the angle of D − D0), D is placed first, and the coupler (A at
    (0, 0), B at (coupler, 0), C at (u1, v1) in its frame) is the body of a triad with anchors
    A0, B0, D and links crank, rocker, link1: up to 6 configurations, from the triad's
    polynomial, each polished and checked by :func:`~linkwright.engine.triad.triad_poses`.
    Every configuration's residuals are then recomputed from its joint positions.

    Parameters
    ----------
    mechanism : a :class:`~linkwright.mechanisms.sixbar.Stephenson3` (or any object with its
        fields, see the module's text); dimensions may have a batch shape.
    inputs : ``(samples,)`` or ``batch + (samples,)``, radians.

    Returns
    -------
    AllConfigurations

    Examples
    --------
    The family's example: at θ = 0 on the crank, A = (1, 0), B = (4, 4) and C = (5, 2); the
    dyad C–D–D0 closes at D = (6.8, −0.4) and, on ``assembly2 = −1``, at D = (2, 2), straight
    above D0 = (2, −4). The four-bar's other branch (B = (4, −4)) leaves C too far from D0:

    >>> from linkwright.mechanisms.sixbar import Stephenson3
    >>> m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[2, -4], crank=1, coupler=5, rocker=4, u1=4,
    ...                 v1=-2, link1=3, link2=6, u=1.5, v=1, assembly2=-1)
    >>> crank = solve_all(m, [0.0])
    >>> int(crank.count[0]), crank.assembly[0, :2].tolist(), crank.assembly2[0, :2].tolist()
    (2, [1.0, 1.0], [1.0, -1.0])
    >>> crank.positions["D"][0, :2].round(12) + 0.0
    array([[ 6.8, -0.4],
           [ 2. ,  2. ]])

    Driven at the output at θ = 90° (D = (2, 2) again) the triad has two configurations: the
    one above, with the crank back at 0, and one with the crank at 50.188°, which the
    crank-driven plan reproduces on the same signs (1, −1):

    >>> out = solve_all(Stephenson3(**{**m.params(), "input": "output"}), [np.pi / 2])
    >>> int(out.count[0])
    2
    >>> out.positions["A"][0, :2].round(6) + 0.0
    array([[0.640271, 0.768149],
           [1.      , 0.      ]])
    >>> out.assembly[0, :2].tolist(), out.assembly2[0, :2].tolist()
    ([1.0, 1.0], [-1.0, -1.0])
    >>> bool(np.nanmax(out.residual) < 1e-14)
    True

    The spherical Stephenson III is answered by
    :func:`~linkwright.mechanisms.sphere_configs.solve_all_spherical` (up to 4 configurations
    driven at AB, 8 at FG).
    """
    if getattr(mechanism, "family", None) == "spherical-stephenson3":
        # Imported here: sphere_configs builds on this module's AllConfigurations.
        from linkwright.mechanisms.sphere_configs import solve_all_spherical

        return solve_all_spherical(mechanism, inputs)
    p, driven = _read(mechanism)
    scale = _scale(p)
    theta = np.asarray(inputs, dtype=float)
    if theta.ndim == 0:
        raise ValueError("inputs: give a 1-D array of samples (or batch + samples)")
    batch = np.broadcast_shapes(
        *(p[f].shape[:-1] for f in _POINTS), *(p[f].shape for f in _SCALARS), theta.shape[:-1]
    )
    theta = np.broadcast_to(theta, batch + theta.shape[-1:])
    # Every array below has the axes batch + (samples, slots); parameters get two unit axes.
    q = {f: p[f][..., None, None, :] for f in _POINTS}
    q.update({f: p[f][..., None, None] for f in _SCALARS})
    th = theta[..., None]
    slots = _SLOTS[driven]

    if driven == "crank":
        s1 = np.array([1.0, 1.0, -1.0, -1.0])
        s2 = np.array([1.0, -1.0, 1.0, -1.0])
        a = q["A0"] + plane.polar(q["crank"], th)
        a = np.broadcast_to(a, batch + theta.shape[-1:] + (4, 2))
        b = circle_intersection(a, q["coupler"], q["B0"], q["rocker"], s1)
        c = _on_link(a, b, q["u1"], q["v1"])
        d = circle_intersection(c, q["link1"], q["D0"], q["link2"], s2)
        sign1 = np.broadcast_to(s1, d.shape[:-1])
        sign2 = np.broadcast_to(s2, d.shape[:-1])
        real = np.isfinite(d).all(axis=-1)
    else:
        d_known = q["D0"][..., 0, :] + plane.polar(q["link2"][..., 0], th[..., 0])
        anchors = np.stack(np.broadcast_arrays(q["A0"][..., 0, :], q["B0"][..., 0, :], d_known), -2)
        lengths = np.stack(
            np.broadcast_arrays(q["crank"][..., 0], q["rocker"][..., 0], q["link1"][..., 0]), -1
        )
        zero = np.zeros_like(q["coupler"][..., 0])
        body = np.stack(
            np.broadcast_arrays(
                np.stack(np.broadcast_arrays(zero, zero), -1),
                np.stack(np.broadcast_arrays(q["coupler"][..., 0], zero), -1),
                np.stack(np.broadcast_arrays(q["u1"][..., 0], q["v1"][..., 0]), -1),
            ),
            -2,
        )
        poses = triad_poses(anchors, lengths, body)  # joints: batch + (samples, 6, 3, 2)
        a, b, c = (poses.joints[..., k, :] for k in range(3))
        d = np.broadcast_to(d_known[..., None, :], a.shape)
        real = poses.valid
        with np.errstate(invalid="ignore"):
            sign1 = np.sign(plane.cross(q["B0"] - a, b - a))
            sign2 = np.sign(plane.cross(q["D0"] - c, d - c))

    pos = {"A": a, "B": b, "C": c, "D": d, "P": _on_link(c, d, q["u"], q["v"])}
    for f in _POINTS:
        pos[f] = np.broadcast_to(q[f], a.shape)
    valid = real & np.isfinite(pos["P"]).all(axis=-1)
    if driven == "crank":
        valid = _drop_repeats(pos, valid, scale[..., None, None])
    pos, valid, sign1, sign2 = pack_slots(pos, valid, sign1, sign2, slots)

    s = scale[..., None, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        residuals = {
            "crank": np.abs(plane.norm(pos["A"] - pos["A0"]) - q["crank"]) / s,
            "coupler": np.abs(plane.norm(pos["B"] - pos["A"]) - q["coupler"]) / s,
            "rocker": np.abs(plane.norm(pos["B"] - pos["B0"]) - q["rocker"]) / s,
            "link1": np.abs(plane.norm(pos["D"] - pos["C"]) - q["link1"]) / s,
            "link2": np.abs(plane.norm(pos["D"] - pos["D0"]) - q["link2"]) / s,
            "C": plane.frame_error(pos["A"], pos["B"], pos["C"], q["u1"], q["v1"]) / s,
            "P": plane.frame_error(pos["C"], pos["D"], pos["P"], q["u"], q["v"]) / s,
        }
        pivot, joint, arm = ("A0", "A", "crank") if driven == "crank" else ("D0", "D", "link2")
        placed = pos[pivot] + plane.polar(q[arm], th)
        residuals["input"] = plane.norm(pos[joint] - placed) / s
    residuals = {k: np.where(valid, v, np.nan) for k, v in residuals.items()}
    residual = np.where(valid, np.maximum.reduce(list(residuals.values())), np.nan)
    return AllConfigurations(
        driven=driven,
        input=theta,
        positions=pos,
        valid=valid,
        count=valid.sum(axis=-1),
        assembly=sign1,
        assembly2=sign2,
        residuals=residuals,
        residual=residual,
    )


def _drop_repeats(pos: dict[str, Array], valid: NDArray[np.bool_], scale: Array) -> NDArray:
    """Mark a configuration invalid where an earlier slot holds the same joints."""
    joints = np.stack([pos[k] for k in ("A", "B", "C", "D")], axis=-2)  # (..., slots, 4, 2)
    joints = np.where(valid[..., None, None], joints, np.nan)
    diff = np.abs(joints[..., :, None, :, :] - joints[..., None, :, :, :]).max(axis=(-1, -2))
    n = valid.shape[-1]
    earlier = np.tril(np.ones((n, n), dtype=bool), k=-1)  # [j, i]: i < j
    with np.errstate(invalid="ignore"):
        same = (diff <= SAME_TOL * scale[..., None]) & earlier
    return valid & ~same.any(axis=-1)


def pack_slots(
    pos: dict[str, Array],
    valid: NDArray[np.bool_],
    sign1: Array,
    sign2: Array,
    slots: int | None = None,
) -> tuple[dict[str, Array], NDArray[np.bool_], Array, Array]:
    """Move the valid configurations to the first ``slots`` slots (stable) and NaN the rest."""
    order = np.argsort(~valid, axis=-1, kind="stable")[..., :slots]
    valid = np.take_along_axis(valid, order, axis=-1)
    keep = valid[..., None]
    packed = {
        k: np.where(keep, np.take_along_axis(v, order[..., None], axis=-2), np.nan)
        for k, v in pos.items()
    }

    def take(a: Array) -> Array:
        a = np.broadcast_to(a, valid.shape[:-1] + a.shape[-1:])
        return np.where(valid, np.take_along_axis(a, order, axis=-1), np.nan)

    return packed, valid, take(sign1), take(sign2)

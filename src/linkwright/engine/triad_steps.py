"""Triads as plan steps: one step places the three joints of a ternary link at once.

A *triad* (an Assur group of class III) is a rigid ternary link carrying joints J1, J2, J3, each
tied by a binary link to a joint already placed (K1, K2, K3). No joint of it is fixed by two
known ones, so no dyad can place it; it appears in a Stephenson III driven at its output (the
coupler held by the crank, the rocker and the output's link) and in paper 001's spherical
Stephenson III driven at FG. As a plan step it is one more kind beside the dyads:

- **placement**: every real pose at each sample, from the polynomial solvers of
  :mod:`linkwright.engine.triad` (degree 6 in the plane) and
  :mod:`linkwright.engine.sphere_triad` (degree 8 on the sphere); the step's branch is the
  *pose index*, the slot of the pose in the order those solvers give (the body's rotation in
  the plane, J2's angle on its circle on the sphere). A dyad's branch is a sign that never
  changes along a branch of motion; a pose index is a name for one of up to 6 or 8 poses at
  one input, and poses keep their order only between inputs where two of them merge, so
  :mod:`linkwright.engine.sheets` follows poses from sample to sample by continuity instead.
- **closure**: the determinant of the differentiated constraints, scaled to be relative
  (:func:`triad_closure`): it vanishes exactly where two poses merge (a limit position of the
  input), and its sign tells the two merging poses apart, as a dyad's branch sign does.
- **residual**: :func:`triad_residual`, written from the constraints alone.
- **explanation**: :meth:`Triad.unassembled` and :meth:`Triad.at_limit`, the sentences the
  faces print.

Derivatives come from the same constraints differentiated once and twice: one 3×3 solve each
for the body's motion (:func:`linkwright.engine.triad.triad_rates` in the plane; on the sphere
every body turns about the centre, J̇ = ω × J, and :func:`sphere_triad_rates` solves for ω and
the angular acceleration).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.sphere_triad import MAX_POSES as SPHERE_POSES
from linkwright.engine.sphere_triad import sphere_triad
from linkwright.engine.state import (
    SINGULAR_SIN,
    Context,
    JointState,
    Param,
    Params,
    Positions,
    param_value,
    pose_slot,
    pose_states,
)
from linkwright.engine.triad import MAX_POSES as PLANE_POSES
from linkwright.engine.triad import triad_poses, triad_rates
from linkwright.geometry import plane, sphere

__all__ = [
    "Changes",
    "PlaneTriadKind",
    "SphereTriad",
    "SphereTriadKind",
    "Triad",
    "TriadSolution",
    "broadcast_scalars",
    "sphere_triad_rates",
    "triad_closure",
    "triad_residual",
]

Array = NDArray[np.float64]
Rates = tuple[Array, Array]
"""A quantity's first and second derivatives by the input."""


def _stack_states(states: list[JointState], attr: str) -> Array:
    return np.stack([getattr(s, attr) for s in states], axis=-2)


def broadcast_scalars(ctx: Context, params: tuple[Param, ...]) -> Array:
    """The step's scalar parameters as one array ``(..., samples, len(params))``."""
    values = [np.broadcast_to(ctx.scalar(p), ctx.theta.shape) for p in params]
    return np.stack(values, axis=-1)


def _solve_distinct(
    solve: Callable[..., tuple[NDArray[Any], ...]], batch: tuple[int, ...], *args: Array
) -> tuple[NDArray[Any], ...]:
    """``solve(*args)`` on each distinct triad once, its results spread back over ``batch``.

    Every configuration of a linkage shares its triads' data up to the triad itself (only the
    pose index differs), so solving each distinct row once saves a factor of the pose count
    where :func:`linkwright.engine.continuation.every_configuration` asks for all of them.
    Each of ``args`` has the shape ``batch`` plus its own trailing axes.
    """
    n = int(np.prod(batch, dtype=int))
    flat = [np.broadcast_to(a, batch + a.shape[len(batch) :]).reshape((n, -1)) for a in args]
    # Rows compared as raw bytes (a 1-D unique, several times faster than ``axis=0``): a
    # signed zero or a NaN payload may then count as distinct, which only costs a solve.
    rows = np.ascontiguousarray(np.concatenate(flat, axis=1))
    keys = rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    picked = (
        np.broadcast_to(a, batch + a.shape[len(batch) :]).reshape((n,) + a.shape[len(batch) :])[
            first
        ]
        for a in args
    )
    results = solve(*picked)
    inverse = inverse.ravel()
    return tuple(np.asarray(r)[inverse].reshape(batch + np.shape(r)[1:]) for r in results)


def _pick(poses: Array, index: NDArray[np.int_]) -> Array:
    """``poses[..., index, :, :]`` per sample: ``(..., P, 3, d)`` → ``(..., 3, d)``."""
    return np.take_along_axis(poses, index[..., None, None, None], axis=-3)[..., 0, :, :]


def triad_closure(joints: Array, anchors: Array, lengths: Array, space: str) -> Array:
    """The triad's closure quantity at a pose: the relative determinant of its constraints.

    In the plane the rows are ``(e_k, ρ_k × e_k / s) / L_k`` with ``e_k = J_k − K_k``,
    ``ρ_k = J_k − J_1`` and s the body's size (the system :func:`triad_rates` solves); on the
    sphere they are ``(J_k × K_k) / sin L_k`` (the system :func:`sphere_triad_rates` solves).
    Each row is then a unit vector (or nearly), so the determinant is in [−1, 1] and 0 exactly
    where the triad is singular: two poses merge there, and they have opposite signs on either
    side of it.

    Examples
    --------
    The symmetric triad of :func:`linkwright.engine.triad.triad_poses` (anchors on a circle of
    radius 2, body joints on one of radius 1, links √3): its two poses, at ±60°, have opposite
    signs.

    >>> from linkwright.engine.triad import triad_poses
    >>> ring = np.array([[0.0, 1.0], [-0.75**0.5, -0.5], [0.75**0.5, -0.5]])
    >>> poses = triad_poses(2 * ring, [3**0.5] * 3, ring)
    >>> closure = triad_closure(poses.joints[:2], 2 * ring, np.full(3, 3**0.5), "plane")
    >>> bool(closure[0] * closure[1] < 0)
    True
    """
    if space == "plane":
        e = joints - anchors
        rho = joints - joints[..., :1, :]
        size = np.maximum(plane.norm(rho[..., 1, :]), plane.norm(rho[..., 2, :]))
        with np.errstate(divide="ignore", invalid="ignore"):
            lever = plane.cross(rho, e) / size[..., None]
            rows = np.concatenate((e, lever[..., None]), axis=-1) / lengths[..., None]
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            rows = sphere.cross(joints, anchors) / np.sin(lengths)[..., None]
    return sphere.dot(rows[..., 0, :], sphere.cross(rows[..., 1, :], rows[..., 2, :]))


def triad_residual(
    joints: Array,
    anchors: Array,
    lengths: Array,
    body: tuple[Array, Array, Array],
    space: str,
    *,
    relative: bool = True,
) -> Array:
    """Largest constraint error of a triad pose, relative to its size (plane; in its units
    with ``relative=False``) or in radians.

    ``body`` is (side, u, v) in the plane (J2 at ``side`` from J1 along the body's x axis, J3 at
    (u, v) in that frame) and (side, arc, angle) on the sphere (J3 at ``arc`` from J1, turned by
    ``angle`` from the great circle J1→J2). Independent of how the pose was found: every link
    length and the body's shape are measured on the positions.

    Examples
    --------
    >>> joints = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]])
    >>> anchors = np.array([[0.0, -1.0], [2.0, -1.0], [-1.0, 1.0]])
    >>> float(triad_residual(joints, anchors, np.ones(3), (2.0, 0.0, 1.0), "plane"))
    0.0
    """
    side, a, b = (np.asarray(x, dtype=float) for x in body)
    if space == "plane":
        size = np.maximum.reduce(
            [np.abs(side), np.hypot(a, b), *np.moveaxis(np.asarray(lengths), -1, 0)]
        )
        links = np.abs(plane.norm(joints - anchors) - lengths)
        shape = np.abs(plane.norm(joints[..., 1, :] - joints[..., 0, :]) - side)
        third = plane.frame_error(joints[..., 0, :], joints[..., 1, :], joints[..., 2, :], a, b)
        worst: Array = np.maximum(np.max(links, axis=-1), np.maximum(shape, third))
        return worst / size if relative else worst
    links = np.abs(sphere.arc(joints, anchors) - lengths)
    shape = np.abs(sphere.arc(joints[..., 0, :], joints[..., 1, :]) - side)
    third = sphere.frame_error(joints[..., 0, :], joints[..., 1, :], joints[..., 2, :], a, b)
    unit = np.max(np.abs(sphere.norm(joints) - 1.0), axis=-1)
    worst_arc: Array = np.maximum.reduce([np.max(links, axis=-1), shape, third, unit])
    return worst_arc


@dataclass(frozen=True)
class Changes:
    """How a triad driven at a hinge changes with the input: its legs' rates (see
    :func:`linkwright.engine.triad.triad_rates`) and its joints' motion relative to the body."""

    legs: Rates | None = None
    body: Rates | None = None


@dataclass(frozen=True)
class TriadSolution:
    """One pose of a triad at each sample: its joints ``(..., 3, d)`` and their derivatives,
    where it is placed and regular, its closure, the pose asked for, and its anchors' states."""

    pos: Array
    vel: Array | None
    acc: Array | None
    valid: NDArray[np.bool_]
    regular: NDArray[np.bool_]
    closure: Array
    asked: Array
    anchors: Array
    anchor_vel: Array | None
    anchor_acc: Array | None


class _TriadStep:
    """What the planar and the spherical triad share: the pose index, the closure, the states.

    A kind supplies its fields (``joints``, ``anchors``, ``lengths``, ``pose`` and the body's
    three numbers, :attr:`body`), :meth:`_poses` (every pose of each distinct triad) and
    :meth:`_rates` (the derivatives of one pose).
    """

    joints: tuple[str, ...]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, ...]
    pose: str
    max_poses: int
    space: str

    @property
    def held(self) -> tuple[str, str, str]:
        """The ternary link's three joints (a triad driven at a hinge places the hinge too)."""
        return (self.joints[0], self.joints[1], self.joints[2])

    @property
    def name(self) -> str:
        """The step's name, under which its pose index is kept: its first joint."""
        return self.joints[0]

    @property
    def parents(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(self.anchors))

    def links(self) -> tuple[tuple[str, str], ...]:
        """The three binary links and the ternary's three sides."""
        j, k = self.held, self.anchors
        return ((k[0], j[0]), (k[1], j[1]), (k[2], j[2]), (j[0], j[1]), (j[1], j[2]), (j[0], j[2]))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The ternary link."""
        return (self.held,)

    @property
    def body(self) -> tuple[Param, Param, Param]:
        raise NotImplementedError

    @property
    def title(self) -> str:
        return f"triad {''.join(self.held)}"

    @staticmethod
    def _read(positions: Positions, names: tuple[str, ...]) -> Array:
        """The positions of ``names`` stacked ``(..., 3, d)``."""
        return np.stack(np.broadcast_arrays(*(positions[n] for n in names)), axis=-2)

    def _lengths(self, params: Params, shape: tuple[int, ...]) -> Array:
        values = [np.broadcast_to(param_value(p, params), shape) for p in self.lengths]
        return np.stack(values, axis=-1)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The relative determinant of the constraints at the placed pose
        (:func:`triad_closure`): 0 where two poses merge, its sign tells them apart. Whether
        the triad assembles at all is its pose count (0 where it has no real pose)."""
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        lengths = self._lengths(params, joints.shape[:-2])
        with np.errstate(invalid="ignore", divide="ignore"):
            return triad_closure(joints, anchors, lengths, self.space)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the three links and of the ternary link's shape
        (:func:`triad_residual`, in the plane's units, radians and chords on the sphere)."""
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        shape = joints.shape[:-2]
        lengths = self._lengths(params, shape)
        side, b1, b2 = (np.broadcast_to(param_value(p, params), shape) for p in self.body)
        return triad_residual(joints, anchors, lengths, (side, b1, b2), self.space, relative=False)

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the step cannot place its joints at an input where it has no pose."""
        j, k = self.held, self.anchors
        return (
            f"the ternary link {''.join(j)} cannot be held by its three links "
            f"{k[0]}{j[0]}, {k[1]}{j[1]} and {k[2]}{j[2]}: the triad has no real pose"
        )

    def at_limit(self) -> str:
        """What happens at a limit position of the input."""
        j = "".join(self.held)
        held = ", ".join(f"{a}{b}" for a, b in zip(self.anchors, self.held, strict=True))
        return (
            f"triad {j}: two poses merge (the ternary link {j}, held by {held}, cannot go on "
            "this way in either)"
        )

    def _poses(
        self, shape: tuple[int, ...], anchors: Array, lengths: Array, body: tuple[Array, ...]
    ) -> tuple[Array, NDArray[np.int_]]:
        """Every pose ``(..., P, 3, d)`` and the count of each triad ``(...)``."""
        raise NotImplementedError

    def _rates(
        self,
        anchors: Array,
        kvel: Array,
        kacc: Array | None,
        pos: Array,
        lengths: Array,
        changes: Changes,
    ) -> tuple[Array, Array | None, NDArray[np.bool_]]:
        """Velocities and accelerations of the joints of one pose, and where they exist."""
        raise NotImplementedError

    def _legs(self, ctx: Context) -> tuple[Array, Rates | None]:
        """The legs' lengths at each sample ``(..., 3)``, and their rates (None: constant)."""
        return broadcast_scalars(ctx, self.lengths), None

    def _shape(self, ctx: Context) -> tuple[Array, Array, Array]:
        """The body's three numbers at each sample."""
        return tuple(np.broadcast_to(ctx.scalar(p), ctx.theta.shape) for p in self.body)  # type: ignore[return-value]

    def _moved(self, ctx: Context, pos: Array) -> Rates | None:
        """Each joint's velocity and acceleration relative to the body ``(..., 3, d)`` (None:
        the body keeps its shape)."""
        return None

    def solve(self, ctx: Context) -> TriadSolution:
        """The pose asked for at each sample, with its derivatives to the context's order."""
        ks = [ctx.joint(a) for a in self.anchors]
        anchors = np.stack(np.broadcast_arrays(*(k.pos for k in ks)), axis=-2)
        lengths, leg_rates = self._legs(ctx)
        body = self._shape(ctx)
        anchored = np.logical_and.reduce([k.valid for k in ks])
        all_joints, count = self._poses(ctx.theta.shape, anchors, lengths, body)
        index, asked = pose_slot(ctx, self.name, self.pose, self.max_poses)
        valid = anchored & (index < count) & (asked == index)
        pos = _pick(np.nan_to_num(all_joints), index)
        with np.errstate(invalid="ignore", divide="ignore"):
            closure = triad_closure(pos, anchors, lengths, self.space)
        regular = valid & np.logical_and.reduce([k.regular for k in ks])
        vel = acc = kvel = kacc = None
        if ctx.order >= 1:
            kvel = _stack_states(ks, "vel")
            kacc = _stack_states(ks, "acc") if ctx.order >= 2 else None
            changes = Changes(leg_rates, self._moved(ctx, pos))
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                vel, acc, fine = self._rates(anchors, kvel, kacc, pos, lengths, changes)
            regular &= fine
        regular &= np.abs(closure) > SINGULAR_SIN
        return TriadSolution(pos, vel, acc, valid, regular, closure, asked, anchors, kvel, kacc)

    def place(self, ctx: Context) -> dict[str, JointState]:
        t = self.solve(ctx)
        return pose_states(self.held, t.pos, t.vel, t.acc, t.valid, t.regular, t.closure, t.asked)


class PlaneTriadKind(_TriadStep):
    """The planar triad's solvers (degree 6, :mod:`linkwright.engine.triad`), for every step
    kind that is a planar triad: :class:`Triad` and the triads driven at a hinge."""

    max_poses = PLANE_POSES
    space = "plane"

    def _poses(
        self, shape: tuple[int, ...], anchors: Array, lengths: Array, body: tuple[Array, ...]
    ) -> tuple[Array, NDArray[np.int_]]:
        side, u, v = body
        zero = np.zeros(shape)
        frame = (np.stack((zero, zero), -1), np.stack((side, zero), -1), np.stack((u, v), -1))

        def solve(k: Array, lengths: Array, body: Array) -> tuple[Array, NDArray[np.int_]]:
            poses = triad_poses(k, lengths, body)
            return poses.joints, poses.count

        joints, count = _solve_distinct(
            solve, shape, np.nan_to_num(anchors), lengths, np.stack(frame, axis=-2)
        )
        return joints, count

    def _rates(
        self,
        anchors: Array,
        kvel: Array,
        kacc: Array | None,
        pos: Array,
        lengths: Array,
        changes: Changes,
    ) -> tuple[Array, Array | None, NDArray[np.bool_]]:
        rates = triad_rates(
            anchors,
            kvel,
            np.zeros_like(kvel) if kacc is None else kacc,
            pos,
            lengths,
            leg_rates=changes.legs,
            body_rates=changes.body,
        )
        return rates.vel, None if kacc is None else rates.acc, rates.regular


@dataclass(frozen=True)
class Triad(PlaneTriadKind):
    """A planar ternary link J1 J2 J3 held by binary links to the placed joints K1, K2, K3.

    J2 lies at ``side`` from J1 and J3 at (``u``, ``v``) in the body's frame (origin J1, x along
    J1→J2, v to the left); link k has length ``lengths[k]``. The branch parameter ``pose`` is
    the pose index, 0 to 5, in the order of the body's rotation at each sample
    (:func:`linkwright.engine.triad.triad_poses`).
    """

    joints: tuple[str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param, Param]
    side: Param
    u: Param
    v: Param
    pose: str = "pose"

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.u, self.v)


def sphere_triad_rates(
    joints: Array,
    anchors: Array,
    anchor_vel: Array,
    anchor_acc: Array | None,
    *,
    leg_rates: tuple[Array, Array] | None = None,
    body_rates: tuple[Array, Array] | None = None,
) -> tuple[Array, Array | None, Array]:
    """Velocities and accelerations of a spherical triad's joints from its anchors'.

    Every body of a spherical linkage turns about the sphere's centre, so the triad's joints
    move as ``J̇_k = ω × J_k`` and ``J̈_k = α × J_k + ω × (ω × J_k)``. Differentiating each link's
    constraint ``J_k·K_k = cos L_k`` once and twice gives, row by row,

    ``ω·(J_k × K_k) = −J_k·K̇_k`` and
    ``α·(J_k × K_k) = −(ω × (ω × J_k))·K_k − 2 (ω × J_k)·K̇_k − J_k·K̈_k``,

    two 3×3 solves. A triad driven at a hinge changes with the input, as in the plane
    (:func:`linkwright.engine.triad.triad_rates`): ``leg_rates`` are each leg's (cos L)′ and
    (cos L)″, added to the right-hand sides; ``body_rates`` each joint's velocity w_k and
    acceleration a_k relative to the body, in the sphere's axes, so that
    ``J̇_k = ω × J_k + w_k`` and ``J̈_k = α × J_k + ω × (ω × J_k) + 2 ω × w_k + a_k``.
    Returns ``(vel, acc, det)``, ``vel`` and ``acc`` of shape ``(..., 3, 3)``
    (joint, component), ``acc`` None when ``anchor_acc`` is, and the determinant of the rows
    (scaled by the caller where it needs a relative one).

    Examples
    --------
    Anchors turning with the body about +z at unit rate carry it rigidly: every joint moves as
    ẑ × J.

    >>> z = np.array([0.0, 0.0, 1.0])
    >>> joints = sphere.unit(np.array([[1.0, 0, 0.3], [0, 1, 0.2], [-1, -1, 0.1]]))
    >>> anchors = sphere.unit(np.array([[1.0, 0.4, 0.9], [0.5, 1, -0.2], [-1, -0.5, -0.6]]))
    >>> vel, acc, _ = sphere_triad_rates(joints, anchors, np.cross(z, anchors),
    ...                                  np.cross(z, np.cross(z, anchors)))
    >>> bool(np.allclose(vel, np.cross(z, joints)))
    True
    >>> bool(np.allclose(acc, np.cross(z, np.cross(z, joints))))
    True
    """
    rows = sphere.cross(joints, anchors)
    r = rows[..., 0, :], rows[..., 1, :], rows[..., 2, :]
    c1, c2 = (0.0, 0.0) if leg_rates is None else leg_rates
    moved, moved_acc = (
        (np.zeros_like(joints), np.zeros_like(joints)) if body_rates is None else body_rates
    )
    rhs1 = c1 - sphere.dot(joints, anchor_vel) - sphere.dot(moved, anchors)
    omega, det = sphere.solve_3x3_rows(*r, rhs1[..., 0], rhs1[..., 1], rhs1[..., 2])
    w = omega[..., None, :]
    vel = sphere.cross(w, joints) + moved
    acc = None
    if anchor_acc is not None:
        spin = sphere.cross(w, sphere.cross(w, joints)) + 2.0 * sphere.cross(w, moved) + moved_acc
        rhs2 = (
            c2
            - sphere.dot(spin, anchors)
            - 2.0 * sphere.dot(vel, anchor_vel)
            - sphere.dot(joints, anchor_acc)
        )
        alpha, _ = sphere.solve_3x3_rows(*r, rhs2[..., 0], rhs2[..., 1], rhs2[..., 2])
        acc = sphere.cross(alpha[..., None, :], joints) + spin
    return vel, acc, det


def _reference(axis: Array, preferred: Array) -> Array:
    """A direction to measure angles about ``axis`` from: ``preferred`` unless it is (nearly)
    parallel to the axis, then whichever coordinate axis is least parallel."""
    fallback = np.eye(3)[np.argmin(np.abs(axis), axis=-1)]
    parallel = sphere.norm(sphere.cross(axis, preferred)) < 1e-6
    return np.where(parallel[..., None], fallback, preferred)


class SphereTriadKind(_TriadStep):
    """The spherical triad's solvers (degree 8, :mod:`linkwright.engine.sphere_triad`), for
    every step kind that is a spherical triad: :class:`SphereTriad` and the triads driven at a
    hinge. ``sense`` orders the poses (see :class:`SphereTriad`)."""

    max_poses = SPHERE_POSES
    space = "sphere"
    sense: float

    def _poses(
        self, shape: tuple[int, ...], anchors: Array, lengths: Array, body: tuple[Array, ...]
    ) -> tuple[Array, NDArray[np.int_]]:
        # Unplaced anchors (NaN) get stand-ins the solver accepts; their poses are not valid.
        placed = np.asarray(np.isfinite(anchors).all(axis=(-1, -2)))
        safe = np.where(placed[..., None, None], anchors, np.eye(3))

        frame_c = sphere.circle_frame(safe[..., 0, :], _reference(safe[..., 0, :], safe[..., 1, :]))
        frame_b = sphere.circle_frame(
            safe[..., 1, :], _reference(safe[..., 1, :], safe[..., 0, :]), self.sense
        )

        # The solver's B is our J2 (its poses come sorted by B's angle) and its C our J1, from
        # which E = J3 is placed towards B.
        def solve(*a: Array) -> tuple[Array, NDArray[np.int_]]:
            fb, fc, f, lengths, side, arc, angle = a
            poses = sphere_triad(
                fb, lengths[:, 1], fc, lengths[:, 0], side, arc, angle, f, lengths[:, 2]
            )
            return np.stack((poses.c, poses.b, poses.e), axis=-2), poses.count

        joints, count = _solve_distinct(
            solve, shape, frame_b, frame_c, safe[..., 2, :], lengths, *body
        )
        return joints, count

    def _rates(
        self,
        anchors: Array,
        kvel: Array,
        kacc: Array | None,
        pos: Array,
        lengths: Array,
        changes: Changes,
    ) -> tuple[Array, Array | None, NDArray[np.bool_]]:
        vel, acc, _ = sphere_triad_rates(
            pos, anchors, kvel, kacc, leg_rates=changes.legs, body_rates=changes.body
        )
        return vel, acc, np.asarray(np.isfinite(vel).all(axis=(-1, -2)))


@dataclass(frozen=True)
class SphereTriad(SphereTriadKind):
    """A spherical ternary link J1 J2 J3 held by binary links to the placed joints K1, K2, K3.

    J2 lies at arc ``side`` from J1, and J3 at arc ``arc`` from J1, turned by ``angle`` from the
    great circle J1→J2 (right-handed about +O·J1, as :class:`~linkwright.engine.SphereRigid`
    places a point); link k has arc ``lengths[k]``. The branch parameter ``pose`` is the pose
    index, 0 to 7, in the order of J2's angle on its circle about K2, measured from the great
    circle K2→K1, right-handed about +O·K2 (``sense = 1``) or left-handed (``sense = -1``), in
    (−π, π] (:func:`linkwright.engine.sphere_triad.sphere_triad`).
    """

    joints: tuple[str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param, Param]
    side: Param
    arc: Param
    angle: Param
    pose: str = "pose"
    sense: float = 1.0

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.arc, self.angle)

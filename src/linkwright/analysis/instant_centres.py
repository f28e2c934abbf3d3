"""Instant centres of a planar linkage and instantaneous axes of a spherical one.

Every rigid body of a linkage moves, at each instant, as a rotation about one point of the
plane (its *instant centre* relative to the frame), or translates (that centre is at infinity,
perpendicular to its velocity). Any two bodies have such a centre relative to each other: the
point where both have the same velocity. On the sphere every body turns about an axis through
the centre O; the *instantaneous axis* is the direction of its angular velocity.

The bodies are read off the construction plan (:func:`rigid_bodies`): each step makes links,
and links that share two joints are one body (a rigid triangle, a coupler carrying its point); a
slider pin adds a *block* that translates along its guide. The centres come from the velocities
the engine already gives (its derivatives with respect to the input, no finite differences):
two points P1, P2 of a body with velocities v1, v2 give its angular velocity
ω = (P2 − P1) × (v2 − v1) / |P2 − P1|² (least squares over all its points), and the velocity
field v(P) = v̄ + ω·J(P − c) (J a quarter turn, c the points' centroid, v̄ their mean velocity)
vanishes at the centre. Two bodies that share a joint have it as their centre exactly (a
revolute pair). A four-bar's six centres obey Aronhold–Kennedy's theorem: the three centres of
any three bodies lie on one line; the tests check that, and ``v_P = ω × (P − I)`` for every
point, against derivatives of the bodies' angles by finite differences.

Velocities are per unit input speed (dθ/dt = 1), so ω is the body's turning per radian of
input; a centre does not depend on the speed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import Motion
from linkwright.engine.evaluate import evaluate
from linkwright.engine.plan import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Plan,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Step,
    Trammel,
    placed_joints,
)
from linkwright.geometry import plane, sphere
from linkwright.mechanisms.base import Mechanism, solve

__all__ = ["FAR", "REST", "InstantCentres", "RigidBody", "instant_centres", "rigid_bodies"]

Array = NDArray[np.float64]
Shape = tuple[int, ...]

FAR = 1e9
"""A centre farther than this many times the linkage's size from its bodies is reported at
infinity (as a direction): a parallelogram's coupler translates exactly, but rounding leaves it a
turning rate of ~1e-16 and a centre 1e16 sizes away, which no drawing can place."""

REST = 1e-10
"""Two bodies whose relative velocity is below this share of the linkage's fastest joint at
every point are at rest relative to each other: every point is then a centre, and none is
reported."""


@dataclass(frozen=True)
class RigidBody:
    """One rigid body of a linkage: its name, the joints it carries and whether it is a slider
    block (it translates along a guide of fixed direction, carrying its pin only).

    The frame is named ``"frame"`` and carries the ground pivots; a moving body is named by its
    joints joined with "–" (as the workbench's scene names its links), a block ``"slider B"``
    after its pin.
    """

    name: str
    joints: tuple[str, ...]
    block: bool = False
    spin: float | None = None
    """The body's turning rate per unit input where its points alone cannot tell (a trammel's
    arm carrying no other joint); None elsewhere."""


@dataclass(frozen=True)
class InstantCentres:
    """The instant centres (plane) or instantaneous axes (sphere) of pairs of bodies.

    Arrays have the motion's shape ``batch + (samples,)`` followed by one axis over ``pairs``.

    Attributes
    ----------
    space : ``"plane"`` or ``"sphere"``.
    bodies : the frame first, then the moving bodies in plan order.
    pairs : ``(i, j)`` indices into ``bodies``, i < j: the frame's pairs first.
    centre : plane, ``(..., pairs, 2)``: the centre where it is a point; NaN where it is at
        infinity or undefined. Sphere, ``(..., pairs, 3)``: the axis of body j relative to body
        i, a unit vector along their relative angular velocity (its antipode is on the axis too).
    direction : plane, ``(..., pairs, 2)``: where the centre is at infinity, the unit direction
        in which it lies (the relative motion is a translation perpendicular to it); NaN where
        the centre is a point. None on the sphere.
    omega : plane, ``(..., pairs)``: the angular velocity of body j relative to body i per unit
        input speed (rad per rad, counter-clockwise positive). Sphere, ``(..., pairs, 3)``: the
        relative angular velocity vector.
    resting : ``(..., pairs)``: the two bodies are at rest relative to each other there, so
        every point is a centre and none is given (NaN).
    valid : ``(...)``: the linkage is assembled with defined velocities at that sample; every
        centre is NaN where it is not.
    reason : why the first sample that is not valid is not, in words (None where all are).
    """

    space: str
    bodies: tuple[RigidBody, ...]
    pairs: tuple[tuple[int, int], ...]
    centre: Array
    direction: Array | None
    omega: Array
    resting: NDArray[np.bool_]
    valid: NDArray[np.bool_]
    reason: str | None

    @property
    def labels(self) -> tuple[str, ...]:
        """Each pair as textbooks label it: ``I13`` for bodies 1 (the frame) and 3, numbered from
        1 in :attr:`bodies` order (``I(10,12)`` past nine bodies)."""
        many = len(self.bodies) > 9
        return tuple(f"I({i + 1},{j + 1})" if many else f"I{i + 1}{j + 1}" for i, j in self.pairs)

    def between(self, a: str, b: str) -> tuple[Array, Array | None]:
        """The centre (or axis) of bodies named ``a`` and ``b``, and its direction at infinity
        (plane; None on the sphere): arrays of the motion's shape with a trailing coordinate
        axis. The sphere's axis is oriented by the turning of ``b`` relative to ``a``.

        Raises
        ------
        LookupError
            For a name that is not one of :attr:`bodies`, or a pair not computed.
        """
        names = [body.name for body in self.bodies]
        for name in (a, b):
            if name not in names:
                raise LookupError(f"body: no body named {name!r} (bodies: {', '.join(names)})")
        i, j = names.index(a), names.index(b)
        key = (min(i, j), max(i, j))
        if key not in self.pairs:
            raise LookupError(f"body: the centre of {a} and {b} was not computed (pairs='frame')")
        k = self.pairs.index(key)
        centre = self.centre[..., k, :]
        if self.space == "sphere" and i > j:
            centre = -centre
        direction = None if self.direction is None else self.direction[..., k, :]
        return centre, direction


# --------------------------------------------------------------------------------------------
# Bodies from the plan
# --------------------------------------------------------------------------------------------


@dataclass
class _Group:
    points: list[str]
    turning: tuple[str, float] | None = None  # (pivot, ratio) of the crank(s) that made it
    block: bool = False
    spin: float | None = None


def _ratio(params: dict[str, Array], value: str | float) -> float:
    raw = params[value] if isinstance(value, str) else value
    return float(np.asarray(raw, dtype=float).reshape(-1)[0])


def _step_groups(step: Step, params: dict[str, Array], groups: list[_Group]) -> list[_Group]:
    """The bodies one step makes (before they are merged with the others)."""
    name = getattr(step, "name", "")
    if isinstance(step, Crank | SphereCrank):
        key = (step.pivot, _ratio(params, step.ratio))
        return [_Group([step.pivot, name], turning=key)]
    if isinstance(step, DyadRRR | SphereDyad):
        # A joint held at fixed distances from two points of one body is a point of that body.
        holders = [g for g in groups if not g.block and {step.p1, step.p2} <= set(g.points)]
        if holders:
            for g in holders:
                g.points.append(name)
            return []
        return [_Group([step.p1, name]), _Group([step.p2, name])]
    if isinstance(step, DyadRRP):
        return [_Group([step.p1, name]), _Group([name], block=True)]
    if isinstance(step, Rigid | SphereRigid):
        return [_Group([step.origin, step.toward, name])]
    if isinstance(step, Trammel):
        # The slider on the first guide, and the arm it carries, which turns one-for-one with
        # the input: cranks on the slider at ratio 1 are points of that arm.
        return [_Group([name], block=True), _Group([name], turning=(name, 1.0), spin=1.0)]
    # Any other kind (a triad, a hinge) says which links and plates it makes; the links that
    # share two joints with a plate or with each other are merged into one body later.
    links = [_Group([a, b]) for a, b in step.links()]
    return links + [_Group(list(p)) for p in step.plates()]


def _merge(groups: list[_Group]) -> list[_Group]:
    """Groups that share two points or more, or turn about one pivot at one ratio, are one body
    (blocks never merge: a block shares only its pin); repeated until nothing changes."""
    out = [_Group(list(g.points), g.turning, g.block, g.spin) for g in groups]
    changed = True
    while changed:
        changed = False
        for a in range(len(out)):
            for b in range(a + 1, len(out)):
                ga, gb = out[a], out[b]
                if ga.block or gb.block:
                    continue
                shared = len(set(ga.points) & set(gb.points))
                if shared >= 2 or (ga.turning is not None and ga.turning == gb.turning):
                    ga.points += [p for p in gb.points if p not in ga.points]
                    ga.turning = ga.turning or gb.turning
                    ga.spin = ga.spin if ga.spin is not None else gb.spin
                    del out[b]
                    changed = True
                    break
            if changed:
                break
    return out


def rigid_bodies(mechanism: Mechanism) -> tuple[RigidBody, ...]:
    """The rigid bodies of a linkage, read off its construction plan: the frame first, then
    every moving body in the order the plan makes them.

    A crank makes a link from its pivot (cranks about one pivot at one ratio are one body); a
    dyad makes two binary links, or its joint joins the body that already holds both its
    parents; a slider pin makes its rod and a block; a rigid point joins the body of the link
    that carries it; any other step (a triad, a hinge) makes the links and plates it draws.
    Links that share two joints are one body, and a body on two ground joints is part of the
    frame.

    Parameters
    ----------
    mechanism : Mechanism
        Any family with a construction plan, in the plane or on the sphere.

    Returns
    -------
    tuple of RigidBody

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar, SliderCrank
    >>> [b.name for b in rigid_bodies(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5,
    ...                                       rocker=3.5, u=1, v=1))]
    ['frame', 'A0–A', 'A–B–P', 'B0–B']
    >>> [b.name for b in rigid_bodies(SliderCrank(A0=[0, 0], crank=1, rod=3))]
    ['frame', 'A0–A', 'A–B–P', 'slider B']
    """
    plan: Plan = mechanism.plan
    params = mechanism.params()
    ground = [s.name for s in plan.steps if isinstance(s, Fixed)]
    groups: list[_Group] = []
    for step in plan.steps:
        if isinstance(step, Fixed):
            continue
        fixed_by_frame = isinstance(step, DyadRRR | SphereDyad | DyadRRP | Rigid | SphereRigid)
        if fixed_by_frame and all(p in ground for p in step.parents):
            # Placed from the frame alone, not by the input: it cannot move.
            ground += [j for j in placed_joints(step) if j not in ground]
            continue
        groups += _step_groups(step, params, groups)
    groups = _merge(groups)
    # A body on two ground joints cannot move: its points are the frame's, which may ground more.
    grounded = True
    while grounded:
        grounded = False
        for g in groups:
            pinned = not g.block and sum(p in ground for p in g.points) >= 2
            if pinned and not set(g.points) <= set(ground):
                ground += [p for p in g.points if p not in ground]
                grounded = True
    moving = [g for g in groups if g.block or sum(p in ground for p in g.points) < 2]
    bodies = [RigidBody("frame", tuple(ground))]
    seen = {"frame"}
    for g in moving:
        name = f"slider {g.points[0]}" if g.block else "–".join(g.points)
        while name in seen:
            name += "'"
        seen.add(name)
        bodies.append(RigidBody(name, tuple(g.points), g.block, g.spin))
    return tuple(bodies)


# --------------------------------------------------------------------------------------------
# Centres
# --------------------------------------------------------------------------------------------


def _motion(mechanism: Mechanism, at: Motion | ArrayLike) -> Motion:
    """A motion with velocities: solved at the inputs ``at``, or ``at`` itself (evaluated
    again with its own branches where it was traced without derivatives)."""
    if not isinstance(at, Motion):
        theta = np.asarray(at, dtype=float)
        if theta.size and not np.isfinite(theta).all():
            raise ValueError("at: every input angle must be a finite number of radians")
        return solve(mechanism, theta, order=1)
    if at.velocities is not None:
        return at
    return evaluate(
        mechanism.plan,
        mechanism.params(),
        at.input,
        points=mechanism.points,
        branches=at.branches or None,
        order=1,
    )


def _reason(mechanism: Mechanism, motion: Motion, ok: NDArray[np.bool_]) -> str | None:
    """Why the first sample that is not ``ok`` is not: the plan's sentence where the linkage
    cannot be assembled, a singular position where it is but its velocities are not defined."""
    if bool(ok.all()):
        return None
    if mechanism.batch_shape != ():
        bad = int((~ok).sum())
        return f"{bad} of {ok.size} samples are not assembled or at a singular position"
    k = int(np.flatnonzero(~ok.reshape(-1))[0])
    theta = float(np.asarray(motion.input, dtype=float).reshape(-1)[k])
    where = f"θ = {math.degrees(theta):.6g}°"
    if not bool(np.asarray(motion.valid).reshape(-1)[k]):
        why = mechanism.plan.unassembled(mechanism.params(), theta, points=mechanism.points)
        return f"{where}: {why or 'the linkage cannot be assembled'}"
    return (
        f"{where}: a singular (limit or toggle) position, where the joints' velocities are not "
        "defined"
    )


def _largest(x: Array) -> Array:
    """The largest finite value over the last axis (0 where none is)."""
    out: Array = np.where(np.isfinite(x), x, 0.0).max(axis=-1, initial=0.0)
    return out


def _stack(values: dict[str, Array], names: Sequence[str]) -> Array:
    return np.stack([values[n] for n in names], axis=-2)


def instant_centres(
    mechanism: Mechanism, at: Motion | ArrayLike, *, pairs: str = "all"
) -> InstantCentres:
    """Instant centres (plane) or instantaneous axes (sphere) of a linkage's bodies.

    Parameters
    ----------
    mechanism : Mechanism
        Any family with a construction plan (one linkage or a batch).
    at : Motion or array_like
        The inputs θ (radians) to solve at, in the mechanism's own assembly; or a motion of it
        (from :func:`~linkwright.mechanisms.solve` or :func:`~linkwright.mechanisms.circuit`),
        whose branches are kept.
    pairs : {"all", "frame"}
        Every pair of bodies (a four-bar's six centres), or only each moving body relative to
        the frame.

    Returns
    -------
    InstantCentres
        NaN where a centre is at infinity (its :attr:`~InstantCentres.direction` is given),
        where two bodies are at rest relative to each other, or where the linkage is not
        assembled or at a singular position (:attr:`~InstantCentres.reason` says why).

    Raises
    ------
    ValueError
        For ``pairs`` other than "all" or "frame", a non-finite input, or a mechanism without a
        construction plan (a six-bar driven at its output).

    Examples
    --------
    A crank-rocker with its crank upright: the crank turns about A0 (I12), the coupler about
    I13, where the crank's line A0A meets the rocker's line B0B (here on the y axis):

    >>> from linkwright.mechanisms import FourBar
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    >>> ic = instant_centres(fb, [np.pi / 2])
    >>> [b.name for b in ic.bodies], ic.labels
    (['frame', 'A0–A', 'A–B–P', 'B0–B'], ('I12', 'I13', 'I14', 'I23', 'I24', 'I34'))
    >>> centre, _ = ic.between("frame", "A–B–P")
    >>> np.round(centre, 6) + 0.0  # B0B meets x = 0 there
    array([[  0.      , -41.027907]])
    >>> round(float(ic.omega[0, 0]), 6)  # the crank turns one-for-one with the input
    1.0

    A slider's block translates: its centre with the frame is at infinity, square to the guide:

    >>> from linkwright.mechanisms import SliderCrank
    >>> sc = instant_centres(SliderCrank(A0=[0, 0], crank=1, rod=3), [1.0], pairs="frame")
    >>> point, direction = sc.between("frame", "slider B")
    >>> point, np.abs(direction).round(12)
    (array([[nan, nan]]), array([[0., 1.]]))

    On the sphere the crank turns about its ground pivot's axis:

    >>> from linkwright.mechanisms import SphericalFourBar
    >>> sph = SphericalFourBar(*np.radians([70, 20, 60, 50]))
    >>> axes = instant_centres(sph, [0.3], pairs="frame")
    >>> np.allclose(axes.between("frame", "A0–A")[0], sph.params()["A0"])
    True

    A linkage that cannot be assembled has no centres, and says why:

    >>> far = instant_centres(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), [0.0])
    >>> bool(np.isnan(far.centre).all())
    True
    >>> far.reason
    'θ = 0°: the coupler and rocker cannot reach (dyad B: |A B0| = 9 > coupler + rocker = 5)'
    """
    if pairs not in ("all", "frame"):
        raise ValueError(f"pairs: must be 'all' or 'frame', got {pairs!r}")
    bodies = rigid_bodies(mechanism)
    motion = _motion(mechanism, at)
    n = len(bodies)
    index = [(i, j) for i in range(n) for j in range(i + 1, n) if pairs == "all" or i == 0]
    assert motion.velocities is not None  # _motion solved to order 1 at least
    pos, vel = motion.positions, motion.velocities
    names = list(pos)
    every = _stack(pos, names)
    speeds = _stack(vel, names)
    ok = np.asarray(motion.valid & motion.regular, dtype=bool)
    # The linkage's size and its fastest joint, per sample: the scales of FAR and REST.
    size = _largest(np.linalg.norm(every - every[..., :1, :], axis=-1))
    fastest = _largest(np.linalg.norm(speeds, axis=-1))
    space = mechanism.plan.space
    if space == "sphere":
        return _sphere(bodies, index, pos, vel, ok, fastest, _reason(mechanism, motion, ok))
    return _plane(bodies, index, pos, vel, ok, size, fastest, _reason(mechanism, motion, ok))


def _fields_plane(
    bodies: tuple[RigidBody, ...], pos: dict[str, Array], vel: dict[str, Array], shape: Shape
) -> list[tuple[Array, Array, Array]]:
    """Each body's velocity field as (ω, c, v̄): v(P) = v̄ + ω·J(P − c)."""
    out = []
    for k, body in enumerate(bodies):
        if k == 0:
            zero = np.zeros(shape + (2,))
            out.append((np.zeros(shape), zero, zero))
            continue
        p = _stack(pos, body.joints)
        v = _stack(vel, body.joints)
        c, vbar = p.mean(axis=-2), v.mean(axis=-2)
        if body.block:
            omega = np.zeros(shape)  # a block keeps its guide's direction
        elif len(body.joints) < 2:
            omega = np.full(shape, body.spin if body.spin is not None else np.nan)
        else:
            dp, dv = p - c[..., None, :], v - vbar[..., None, :]
            with np.errstate(invalid="ignore", divide="ignore"):
                omega = plane.cross(dp, dv).sum(axis=-1) / plane.dot(dp, dp).sum(axis=-1)
        out.append((omega, c, vbar))
    return out


def _plane(
    bodies: tuple[RigidBody, ...],
    index: list[tuple[int, int]],
    pos: dict[str, Array],
    vel: dict[str, Array],
    ok: NDArray[np.bool_],
    size: Array,
    fastest: Array,
    reason: str | None,
) -> InstantCentres:
    shape = ok.shape
    fields = _fields_plane(bodies, pos, vel, shape)
    centres, directions, omegas, resting = [], [], [], []
    for i, j in index:
        wi, ci, vi = fields[i]
        wj, cj, vj = fields[j]
        rel = wj - wi
        # The relative velocity at c_j: v_j(c_j) − v_i(c_j).
        u = vj - (vi + wi[..., None] * plane.perp(cj - ci))
        speed = plane.norm(u)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            point = cj + plane.perp(u) / rel[..., None]
            far = speed > FAR * size * np.abs(rel)
            rest = (speed <= REST * fastest) & (np.abs(rel) * size <= REST * fastest)
            toward = plane.perp(u) / speed[..., None]
        shared = [p for p in bodies[i].joints if p in bodies[j].joints]
        if shared:
            # A revolute pair: the joint is the centre, exactly and even at relative rest.
            point = pos[shared[0]]
            far = np.zeros(shape, dtype=bool)
            rest = np.zeros(shape, dtype=bool)
        point = np.where((far | rest | ~ok)[..., None], np.nan, point)
        toward = np.where((far & ~rest & ok)[..., None], toward, np.nan)
        centres.append(point)
        directions.append(toward)
        omegas.append(np.where(ok, rel, np.nan))
        resting.append(rest & ok)
    return InstantCentres(
        space="plane",
        bodies=bodies,
        pairs=tuple(index),
        centre=_pack(centres, shape, 2),
        direction=_pack(directions, shape, 2),
        omega=np.stack(omegas, axis=-1) if omegas else np.zeros(shape + (0,)),
        resting=np.stack(resting, axis=-1) if resting else np.zeros(shape + (0,), dtype=bool),
        valid=ok,
        reason=reason,
    )


def _pack(rows: list[Array], shape: Shape, dim: int) -> Array:
    return np.stack(rows, axis=-2) if rows else np.zeros(shape + (0, dim))


def _spin_sphere(p: Array, v: Array) -> Array:
    """The angular velocity ω with ω × p_k = v_k for every point k (least squares, exact for a
    rigid rotation about O): (Σ |p|²I − p pᵀ) ω = Σ p × v."""
    rhs = sphere.cross(p, v).sum(axis=-2)
    rows = []
    for a in range(3):
        e = np.zeros(3)
        e[a] = 1.0
        # Row a of Σ (|p|² I − p pᵀ).
        rows.append((sphere.dot(p, p)[..., None] * e - p * p[..., a : a + 1]).sum(axis=-2))
    omega, _ = sphere.solve_3x3_rows(
        rows[0], rows[1], rows[2], rhs[..., 0], rhs[..., 1], rhs[..., 2]
    )
    return omega


def _sphere(
    bodies: tuple[RigidBody, ...],
    index: list[tuple[int, int]],
    pos: dict[str, Array],
    vel: dict[str, Array],
    ok: NDArray[np.bool_],
    fastest: Array,
    reason: str | None,
) -> InstantCentres:
    shape = ok.shape
    spins = [np.zeros(shape + (3,))]
    for body in bodies[1:]:
        spins.append(_spin_sphere(_stack(pos, body.joints), _stack(vel, body.joints)))
    axes, omegas, resting = [], [], []
    for i, j in index:
        rel = spins[j] - spins[i]
        size = sphere.norm(rel)
        rest = size <= REST * fastest
        with np.errstate(invalid="ignore", divide="ignore"):
            axis = rel / size[..., None]
        shared = [p for p in bodies[i].joints if p in bodies[j].joints]
        if shared:
            # A revolute pair turns about its joint's axis, oriented by the turning.
            joint = pos[shared[0]]
            sense = np.where(sphere.dot(rel, joint) < 0, -1.0, 1.0)
            axis = sense[..., None] * joint
            rest = np.zeros(shape, dtype=bool)
        axis = np.where((rest | ~ok)[..., None], np.nan, axis)
        axes.append(axis)
        omegas.append(np.where(ok[..., None], rel, np.nan))
        resting.append(rest & ok)
    return InstantCentres(
        space="sphere",
        bodies=bodies,
        pairs=tuple(index),
        centre=_pack(axes, shape, 3),
        direction=None,
        omega=_pack(omegas, shape, 3),
        resting=np.stack(resting, axis=-1) if resting else np.zeros(shape + (0,), dtype=bool),
        valid=ok,
        reason=reason,
    )

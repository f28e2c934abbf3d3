"""Triads driven at a hinge: a linkage whose driven hinge lies in a loop that only a triad closes.

A Stephenson III has two loops. A hinge of its four-bar loop driven (A or B) is a
:class:`~linkwright.engine.hinge_steps.Hinge`: the law of cosines turns the driven angle into a
diagonal, and a dyad places the rest. A hinge of its second loop driven (C, between the coupler
and the link CD, or D, between CD and the output DD0) leaves no joint that two placed joints fix:
the coupler is held by three legs, a triad (:mod:`linkwright.engine.triad_steps`) that changes
with the input. Two kinds of change cover every hinge of a triad's loop:

- **a leg with a hinge in it** (:class:`LegHingeTriad`, :class:`SphereLegHingeTriad`): the leg
  from the anchor Y (K3) to the triad's joint X (J3) is two links, H–Y (b) and H–X (a), and the
  driven angle φ at H fixes |X Y| = d(φ), d² = a² + b² − 2ab cos φ in the plane and
  cos d = cos a cos b + sin a sin b cos φ on the sphere. The triad with legs (l1, l2, d(φ)) is
  solved as any triad, and H follows from X, Y and φ
  (:func:`~linkwright.engine.hinge_steps.plane_hinge_point`). Its derivatives: the leg's
  constraint gains (d²)′/2 = ab sin φ and (d²)″/2 = ab cos φ (on the sphere (cos d)′ and (cos d)″).
- **a joint turning on the body** (:class:`BodyHingeTriad`): the ternary link carries the hinge H
  at (hu, hv) in its frame, and the link H–X (length ``arm``) turns about H at the angle
  ψ = phase + θ from the body's x axis, so X = J3 sits at H + arm·(cos ψ, sin ψ) in the body's
  frame: a triad whose body changes shape with the input. Its derivatives carry X's motion
  relative to the body, w = arm·(−sin ψ, cos ψ) and a = −arm·(cos ψ, sin ψ) turned into the
  plane's axes (:func:`linkwright.engine.triad.triad_rates`).

Each is one step that places the three joints of the ternary link and the hinge, with the
triad's pose index as its branch, the triad's closure (the legs' lengths measured at the pose)
and a residual written from the links and the driven angle alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.hinge_steps import (
    FOLD,
    Track,
    plane_hinge_point,
    sphere_hinge_point,
)
from linkwright.engine.state import (
    Context,
    JointState,
    Param,
    Params,
    Positions,
    param_value,
    pose_states,
)
from linkwright.engine.triad_steps import (
    Array,
    PlaneTriadKind,
    Rates,
    SphereTriadKind,
    TriadSolution,
    broadcast_scalars,
    triad_closure,
    triad_residual,
)
from linkwright.geometry import plane, sphere

__all__ = ["BodyHingeTriad", "LegHingeTriad", "SphereBodyHingeTriad", "SphereLegHingeTriad"]


def _with_hinge(
    joints: tuple[str, ...], t: TriadSolution, h: Track, ok: NDArray[np.bool_]
) -> dict[str, JointState]:
    """The states of the ternary link's joints and of the hinge (the last of ``joints``): the
    hinge shares the triad's closure and pose; ``ok`` narrows where it can be placed at all."""
    hp, hv, ha = h
    pos = np.concatenate((t.pos, hp[..., None, :]), axis=-2)
    vel = None if t.vel is None or hv is None else np.concatenate((t.vel, hv[..., None, :]), -2)
    acc = None if t.acc is None or ha is None else np.concatenate((t.acc, ha[..., None, :]), -2)
    valid = t.valid & ok
    return pose_states(joints, pos, vel, acc, valid, t.regular & valid, t.closure, t.asked)


def _third(t: TriadSolution) -> tuple[Track, Track]:
    """The third anchor's and the third joint's tracks (Y and X of the hinge's triangle)."""

    def at(x: Array | None, k: int) -> Array | None:
        return None if x is None else x[..., k, :]

    y = (t.anchors[..., 2, :], at(t.anchor_vel, 2), at(t.anchor_acc, 2))
    x = (t.pos[..., 2, :], at(t.vel, 2), at(t.acc, 2))
    return y, x


class _Hinged:
    """A triad step that also places its driven hinge, the last of its joints."""

    joints: tuple[str, str, str, str]

    @property
    def hinge(self) -> str:
        return self.joints[3]

    @property
    def title(self) -> str:
        return f"triad {''.join(self.joints[:3])} driven at {self.hinge}"


class _LegHinge(_Hinged):
    """What the planar and the spherical leg hinge share: their names, links and sentences."""

    joints: tuple[str, str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param]
    a: Param
    b: Param
    phase: Param

    def links(self) -> tuple[tuple[str, str], ...]:
        """The first two legs, the hinge's two links and the ternary's three sides."""
        j, k, h = self.joints, self.anchors, self.hinge
        return (
            (k[0], j[0]),
            (k[1], j[1]),
            (k[2], h),
            (h, j[2]),
            (j[0], j[1]),
            (j[1], j[2]),
            (j[0], j[2]),
        )

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        j, k, h = self.joints, self.anchors, self.hinge
        return (
            f"the ternary link {''.join(j[:3])} cannot be held by its links {k[0]}{j[0]}, "
            f"{k[1]}{j[1]} and the chain {k[2]}{h}{j[2]} with the angle at {h} as driven: the "
            "triad has no real pose"
        )

    def _angle(self, ctx: Context) -> tuple[Array, Array, Array]:
        return ctx.scalar(self.phase) + ctx.theta, ctx.scalar(self.a), ctx.scalar(self.b)

    def at_limit(self) -> str:
        j = "".join(self.joints[:3])
        return (
            f"triad {j} driven at {self.hinge}: two poses merge (the ternary link {j} cannot go "
            "on this way in either)"
        )


@dataclass(frozen=True)
class LegHingeTriad(_LegHinge, PlaneTriadKind):
    """A planar triad J1 J2 J3 whose third leg, from the anchor K3 (Y) to J3 (X), carries the
    driven hinge H: |H X| = ``a``, |H Y| = ``b``, and the angle at H from H→Y to H→X is
    ``phase + θ``. ``joints`` are J1, J2, J3 and H; ``lengths`` the first two legs; the body
    as :class:`~linkwright.engine.triad_steps.Triad`'s.

    Examples
    --------
    A Stephenson III driven at D, the pin between its link CD (3) and its output D0D (6): at a
    driven angle of 90°, C lies √45 from D0, and every link keeps its length.

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> step = LegHingeTriad(("A", "B", "C", "D"), ("A0", "B0", "D0"), (1.0, 4.0), 5.0, 4.0,
    ...                      -2.0, a=3.0, b=6.0)
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Fixed("D0", "D0"), step),
    ...             traced=("C",))
    >>> pts = {"A0": [0.0, 0.0], "B0": [4.0, 0.0], "D0": [2.0, -4.0]}
    >>> m = evaluate(plan, pts, np.array([np.pi / 2]), points=frozenset(pts),
    ...              branches={"A": 0.0})
    >>> p = {k: v[0] for k, v in m.positions.items()}
    >>> [round(float(np.hypot(*(p[i] - p[j]))), 9) for i, j in
    ...  (("A", "A0"), ("B", "B0"), ("A", "B"), ("C", "D"), ("D", "D0"), ("C", "D0"))]
    [1.0, 4.0, 5.0, 3.0, 6.0, 6.708203932]
    """

    joints: tuple[str, str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param]
    side: Param
    u: Param
    v: Param
    a: Param
    b: Param
    phase: Param = 0.0
    pose: str = "pose"

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.u, self.v)

    def _legs(self, ctx: Context) -> tuple[Array, Rates | None]:
        phi, a, b = self._angle(ctx)
        d = np.abs(b - a * np.exp(1j * phi))
        zero = np.zeros(ctx.theta.shape)
        legs = np.concatenate((broadcast_scalars(ctx, self.lengths), d[..., None]), axis=-1)
        # (d²)′/2 and (d²)″/2 from d² = a² + b² − 2ab cos φ; the first two legs keep theirs.
        rates = (
            np.stack(np.broadcast_arrays(zero, zero, a * b * np.sin(phi)), -1),
            np.stack(np.broadcast_arrays(zero, zero, a * b * np.cos(phi)), -1),
        )
        return legs, rates

    def place(self, ctx: Context) -> dict[str, JointState]:
        t = self.solve(ctx)
        phi, a, b = self._angle(ctx)
        y, x = _third(t)
        span = plane.norm(x[0] - y[0])
        return _with_hinge(
            self.joints, t, plane_hinge_point(y, x, phi, a, b), span > FOLD * (a + b)
        )

    def _measured(self, positions: Positions, params: Params) -> tuple[Array, Array, Array]:
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        shape = joints.shape[:-2]
        first = [np.broadcast_to(param_value(p, params), shape) for p in self.lengths]
        third = plane.norm(joints[..., 2, :] - anchors[..., 2, :])
        return joints, anchors, np.stack((*first, third), axis=-1)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The triad's closure with the third leg as long as the hinge's angle makes it."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return triad_closure(*self._measured(positions, params), self.space)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the first two legs, the body's shape, the hinge's two links and
        X against the angle at H (X − H = a·e^{iφ}·(Y − H)/b)."""
        joints, anchors, legs = self._measured(positions, params)
        shape = joints.shape[:-2]
        side, u, v = (np.broadcast_to(param_value(p, params), shape) for p in self.body)
        triad = triad_residual(joints, anchors, legs, (side, u, v), "plane", relative=False)
        a, b = param_value(self.a, params), param_value(self.b, params)
        phi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        h, x, y = positions[self.hinge], joints[..., 2, :], anchors[..., 2, :]
        rel_y, rel_x = y - h, x - h
        turned = np.exp(1j * phi) * (rel_y[..., 0] + 1j * rel_y[..., 1]) * a / b
        errors = (
            triad,
            np.abs(plane.norm(rel_x) - a),
            np.abs(plane.norm(rel_y) - b),
            np.hypot(rel_x[..., 0] - turned.real, rel_x[..., 1] - turned.imag),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst


@dataclass(frozen=True)
class SphereLegHingeTriad(_LegHinge, SphereTriadKind):
    """The spherical leg hinge: a spherical triad J1 J2 J3 whose third leg, from K3 (Y) to J3
    (X), carries the driven hinge H, arcs |H X| = ``a`` and |H Y| = ``b``, the angle at H from
    the great circle H→Y to H→X (right-handed about +O·H) ``phase + θ``. The body and ``sense``
    as :class:`~linkwright.engine.triad_steps.SphereTriad`'s.

    Examples
    --------
    Paper 001's six-bar driven at its joint between the arcs EF and FG (our C–D and D–D0): every
    arc keeps its length, and the angle at D is the input.

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> from linkwright.geometry import sphere
    >>> r = np.radians
    >>> step = SphereLegHingeTriad(("A", "B", "C", "D"), ("A0", "B0", "D0"),
    ...                            (r(30.0), r(40.0)), r(50.0), r(30.0), r(40.0),
    ...                            a=r(35.0), b=r(45.0))
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Fixed("D0", "D0"), step),
    ...             traced=("C",))
    >>> pts = {"A0": sphere.unit(np.array([1.0, 0.0, 0.6])),
    ...        "B0": sphere.unit(np.array([0.2, 1.0, 0.5])),
    ...        "D0": sphere.unit(np.array([-0.4, -0.3, 1.0]))}
    >>> found = [evaluate(plan, pts, np.array([1.0]), points=frozenset(pts),
    ...                   branches={"A": float(k)}) for k in range(8)]
    >>> m = next(f for f in found if f.valid[0])
    >>> p = {k: v[0] for k, v in m.positions.items()}
    >>> [round(float(np.degrees(sphere.arc(p[i], p[j]))), 9) for i, j in
    ...  (("A", "A0"), ("B", "B0"), ("A", "B"), ("C", "D"), ("D", "D0"))]
    [30.0, 40.0, 50.0, 35.0, 45.0]
    >>> round(float(sphere.angle_at(p["D"], p["D0"], p["C"])), 12)
    1.0
    """

    joints: tuple[str, str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param]
    side: Param
    arc: Param
    angle: Param
    a: Param
    b: Param
    phase: Param = 0.0
    pose: str = "pose"
    sense: float = 1.0

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.arc, self.angle)

    def _legs(self, ctx: Context) -> tuple[Array, Rates | None]:
        phi, a, b = self._angle(ctx)
        sab = np.sin(a) * np.sin(b)
        cos_d = np.clip(np.cos(a) * np.cos(b) + sab * np.cos(phi), -1.0, 1.0)
        zero = np.zeros(ctx.theta.shape)
        legs = np.concatenate(
            (broadcast_scalars(ctx, self.lengths), np.arccos(cos_d)[..., None]), axis=-1
        )
        # (cos d)′ and (cos d)″ from the spherical law of cosines.
        rates = (
            np.stack(np.broadcast_arrays(zero, zero, -sab * np.sin(phi)), -1),
            np.stack(np.broadcast_arrays(zero, zero, -sab * np.cos(phi)), -1),
        )
        return legs, rates

    def place(self, ctx: Context) -> dict[str, JointState]:
        t = self.solve(ctx)
        phi, a, b = self._angle(ctx)
        y, x = _third(t)
        chord = sphere.norm(sphere.cross(x[0], y[0]))
        return _with_hinge(
            self.joints, t, sphere_hinge_point(y, x, phi, a, b), chord > FOLD * (a + b)
        )

    def _measured(self, positions: Positions, params: Params) -> tuple[Array, Array, Array]:
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        shape = joints.shape[:-2]
        first = [np.broadcast_to(param_value(p, params), shape) for p in self.lengths]
        third = sphere.arc(joints[..., 2, :], anchors[..., 2, :])
        return joints, anchors, np.stack((*first, third), axis=-1)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The triad's closure with the third leg the arc the hinge's angle makes it."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return triad_closure(*self._measured(positions, params), self.space)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the first two legs, the body, the hinge's two arcs, the angle at
        H (times sin a: X off along its circle about H) and the hinge's unit norm, in
        radians."""
        joints, anchors, legs = self._measured(positions, params)
        shape = joints.shape[:-2]
        side, arc, angle = (np.broadcast_to(param_value(p, params), shape) for p in self.body)
        triad = triad_residual(joints, anchors, legs, (side, arc, angle), "sphere")
        a, b = param_value(self.a, params), param_value(self.b, params)
        phi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        h, x, y = positions[self.hinge], joints[..., 2, :], anchors[..., 2, :]
        turned = np.remainder(sphere.angle_at(h, y, x) - phi + np.pi, 2.0 * np.pi) - np.pi
        errors = (
            triad,
            np.abs(sphere.arc(x, h) - a),
            np.abs(sphere.arc(y, h) - b),
            np.abs(turned) * np.sin(a),
            np.abs(sphere.norm(h) - 1.0),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst


class _BodyHinge(_Hinged):
    """What the planar and the spherical body hinge share: their links and sentences (``link``
    names a binary link in a sentence: "link" or "arc")."""

    anchors: tuple[str, str, str]
    link: str

    def links(self) -> tuple[tuple[str, str], ...]:
        """The three legs, the turning link H–J3 and the ternary's sides J1 J2 H."""
        j, k, h = self.joints, self.anchors, self.hinge
        return (
            (k[0], j[0]),
            (k[1], j[1]),
            (k[2], j[2]),
            (h, j[2]),
            (j[0], j[1]),
            (j[1], h),
            (j[0], h),
        )

    def plates(self) -> tuple[tuple[str, ...], ...]:
        return ((self.joints[0], self.joints[1], self.hinge),)

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        j, k, h = self.joints, self.anchors, self.hinge
        return (
            f"the ternary link {j[0]}{j[1]}{h}, with the {self.link} {h}{j[2]} turned to the "
            f"driven angle, cannot be held by its {self.link}s {k[0]}{j[0]}, {k[1]}{j[1]} and "
            f"{k[2]}{j[2]}: the triad has no real pose"
        )

    def at_limit(self) -> str:
        j = "".join(self.joints[:3])
        return (
            f"triad {j} driven at {self.hinge}: two poses merge (the ternary link, with "
            f"{self.hinge}{self.joints[2]} held at the driven angle, cannot go on this way in "
            "either)"
        )


@dataclass(frozen=True)
class BodyHingeTriad(_BodyHinge, PlaneTriadKind):
    """A planar triad whose ternary link carries the driven hinge H: J1 J2 J3 and H, where H
    sits at (``hu``, ``hv``) in the body's frame (origin J1, x along J1→J2, v to the left) and
    J3 at ``arm`` from H, at the angle ``phase + θ`` from the body's x axis. Leg k, from the
    placed joint K_k to J_k, has length ``lengths[k]``; J2 lies at ``side`` from J1.

    Examples
    --------
    A Stephenson III driven at C, where its link CD (3) turns on the coupler: with CD at
    π − atan(4/3) from the coupler's line AB, one of its poses is the crank-driven example's
    configuration at θ = 0 (:class:`~linkwright.mechanisms.Stephenson3`), A = (1, 0),
    B = (4, 4), C = (5, 2), D = (2, 2); another pose holds every link too.

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> step = BodyHingeTriad(("A", "B", "D", "C"), ("A0", "B0", "D0"), (1.0, 4.0, 6.0), 5.0,
    ...                       4.0, -2.0, 3.0)
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"), Fixed("D0", "D0"), step),
    ...             traced=("C",))
    >>> pts = {"A0": [0.0, 0.0], "B0": [4.0, 0.0], "D0": [2.0, -4.0]}
    >>> at = np.array([np.pi - np.arctan2(4.0, 3.0)])
    >>> found = [evaluate(plan, pts, at, points=frozenset(pts), branches={"A": float(k)})
    ...          for k in range(6)]
    >>> [bool(f.valid[0]) for f in found]
    [True, True, False, False, False, False]
    >>> {k: (found[1].positions[k][0].round(12) + 0).tolist() for k in "ABCD"}
    {'A': [1.0, 0.0], 'B': [4.0, 4.0], 'C': [5.0, 2.0], 'D': [2.0, 2.0]}
    >>> bool(plan.residuals(found[0], pts)[0] < 1e-14)
    True
    """

    joints: tuple[str, str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param, Param]
    side: Param
    hu: Param
    hv: Param
    arm: Param
    phase: Param = 0.0
    pose: str = "pose"

    link = "link"

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.hu, self.hv)

    def _turn(self, ctx: Context) -> tuple[Array, Array]:
        return ctx.scalar(self.phase) + ctx.theta, ctx.scalar(self.arm)

    def _shape(self, ctx: Context) -> tuple[Array, Array, Array]:
        psi, arm = self._turn(ctx)
        side, hu, hv = (ctx.scalar(p) for p in self.body)
        shape = ctx.theta.shape
        return (
            np.broadcast_to(side, shape),
            np.broadcast_to(hu + arm * np.cos(psi), shape),
            np.broadcast_to(hv + arm * np.sin(psi), shape),
        )

    @staticmethod
    def _axes(pos: Array) -> tuple[Array, Array]:
        """The body's x and y axes at a pose ``(..., 3, 2)``."""
        d = pos[..., 1, :] - pos[..., 0, :]
        with np.errstate(invalid="ignore", divide="ignore"):
            x = d / plane.norm(d)[..., None]
        return x, plane.perp(x)

    def _moved(self, ctx: Context, pos: Array) -> Rates | None:
        psi, arm = self._turn(ctx)
        x, y = self._axes(pos)
        c, s = (arm * np.cos(psi))[..., None], (arm * np.sin(psi))[..., None]
        zero = np.zeros_like(pos[..., :2, :])
        w = -s * x + c * y
        a = -c * x - s * y
        return (
            np.concatenate((zero, w[..., None, :]), axis=-2),
            np.concatenate((zero, a[..., None, :]), axis=-2),
        )

    def place(self, ctx: Context) -> dict[str, JointState]:
        t = self.solve(ctx)
        hu, hv = (ctx.scalar(p)[..., None] for p in (self.hu, self.hv))
        side = plane.norm(t.pos[..., 1, :] - t.pos[..., 0, :])[..., None]

        def carried(j: Array | None) -> Array | None:
            # H is linear in J1 and J2 (|J1 J2| stays ``side``), and so are its derivatives.
            if j is None:
                return None
            d = j[..., 1, :] - j[..., 0, :]
            with np.errstate(invalid="ignore", divide="ignore"):
                out: Array = j[..., 0, :] + (hu * d + hv * plane.perp(d)) / side
            return out

        h = carried(t.pos)
        assert h is not None
        return _with_hinge(self.joints, t, (h, carried(t.vel), carried(t.acc)), t.valid)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the three legs, the body's shape with J3 where the driven angle
        puts it, H's place on the body and the turning link's length."""
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        shape = joints.shape[:-2]
        legs = self._lengths(params, shape)
        side, hu, hv, arm = (param_value(p, params) for p in (*self.body, self.arm))
        psi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        body = np.broadcast_arrays(side, hu + arm * np.cos(psi), hv + arm * np.sin(psi))
        triad = triad_residual(
            joints, anchors, legs, (body[0], body[1], body[2]), "plane", relative=False
        )
        h = positions[self.hinge]
        errors = (
            triad,
            plane.frame_error(joints[..., 0, :], joints[..., 1, :], h, hu, hv),
            np.abs(plane.norm(joints[..., 2, :] - h) - arm),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst


def _body_axes(pos: Array, side: Array) -> tuple[Array, Array, Array]:
    """The spherical body's axes at a pose ``(..., 3, 3)``: J1, the tangent at J1 towards J2
    and their cross product (the body frame's z, x and y axes)."""
    j1, j2 = pos[..., 0, :], pos[..., 1, :]
    s = np.sin(side)[..., None]
    with np.errstate(invalid="ignore", divide="ignore"):
        ex = (j2 - np.cos(side)[..., None] * j1) / s
        ey = sphere.cross(j1, j2) / s
    return ex, ey, j1


@dataclass(frozen=True)
class SphereBodyHingeTriad(_BodyHinge, SphereTriadKind):
    """The spherical body hinge: a spherical triad whose ternary link carries the driven hinge
    H, at arc ``harc`` from J1 turned by ``hangle`` from the great circle J1→J2 (right-handed
    about +O·J1), and J3 at arc ``arm`` from H, at the angle ``phase + θ`` from the great
    circle H→J1 (right-handed about +O·H). Legs and ``sense`` as
    :class:`~linkwright.engine.triad_steps.SphereTriad`'s; ``harc`` must lie strictly between
    0 and π (H on J1 leaves its angle undefined).

    Examples
    --------
    Paper 001's six-bar driven at E, where the link EF turns on the coupler BCE: every arc keeps
    its length, and the angle at E from the great circle E→C to E→F is the input.

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> from linkwright.geometry import sphere
    >>> r = np.radians
    >>> step = SphereBodyHingeTriad(("C", "B", "F", "E"), ("D", "A", "G"),
    ...                             (r(65.7), r(64.1), r(52.6)), r(68.6), r(69.0), r(78.0),
    ...                             r(74.1))
    >>> plan = Plan((Fixed("A", "A"), Fixed("D", "D"), Fixed("G", "G"), step), traced=("E",))
    >>> pts = {"A": np.array([0.0, 0.0, 1.0]), "D": np.array([0.0, np.sin(r(71.1)),
    ...        np.cos(r(71.1))]), "G": np.array([0.0, np.sin(r(90.8)), np.cos(r(90.8))])}
    >>> found = [evaluate(plan, pts, np.array([2.0]), points=frozenset(pts),
    ...                   branches={"C": float(k)}) for k in range(8)]
    >>> m = next(f for f in found if f.valid[0])
    >>> p = {k: v[0] for k, v in m.positions.items()}
    >>> [round(float(np.degrees(sphere.arc(p[i], p[j]))), 9) for i, j in
    ...  (("C", "D"), ("B", "A"), ("F", "G"), ("C", "B"), ("C", "E"), ("E", "F"))]
    [65.7, 64.1, 52.6, 68.6, 69.0, 74.1]
    >>> round(float(sphere.angle_at(p["E"], p["C"], p["F"])), 12)
    2.0
    """

    joints: tuple[str, str, str, str]
    anchors: tuple[str, str, str]
    lengths: tuple[Param, Param, Param]
    side: Param
    harc: Param
    hangle: Param
    arm: Param
    phase: Param = 0.0
    pose: str = "pose"
    sense: float = 1.0

    link = "arc"

    @property
    def body(self) -> tuple[Param, Param, Param]:
        return (self.side, self.harc, self.hangle)

    def _local(self, ctx: Context) -> tuple[Array, Array, Array, Array]:
        """H and J3 in the body's frame (J1 = z, J2 in the x–z plane) and J3's first two
        derivatives there, each ``(..., 3)``."""
        psi = ctx.scalar(self.phase) + ctx.theta
        harc, hangle, arm = (ctx.scalar(p) for p in (self.harc, self.hangle, self.arm))
        h = np.stack(
            np.broadcast_arrays(
                np.sin(harc) * np.cos(hangle), np.sin(harc) * np.sin(hangle), np.cos(harc)
            ),
            -1,
        )
        z = np.array([0.0, 0.0, 1.0])
        t = (z - np.cos(harc)[..., None] * h) / np.sin(harc)[..., None]
        n = sphere.cross(h, t)
        c, s = np.cos(psi)[..., None], np.sin(psi)[..., None]
        reach = np.sin(arm)[..., None]
        j3 = np.cos(arm)[..., None] * h + reach * (c * t + s * n)
        shape = ctx.theta.shape + (3,)
        return (
            np.broadcast_to(h, shape),
            np.broadcast_to(j3, shape),
            np.broadcast_to(reach * (c * n - s * t), shape),
            np.broadcast_to(-reach * (c * t + s * n), shape),
        )

    def _shape(self, ctx: Context) -> tuple[Array, Array, Array]:
        _, j3, _, _ = self._local(ctx)
        arc = np.arccos(np.clip(j3[..., 2], -1.0, 1.0))
        angle = np.arctan2(j3[..., 1], j3[..., 0])
        return np.broadcast_to(ctx.scalar(self.side), ctx.theta.shape), arc, angle

    def _moved(self, ctx: Context, pos: Array) -> Rates | None:
        _, _, w, a = self._local(ctx)
        ex, ey, ez = _body_axes(pos, ctx.scalar(self.side))

        def world(v: Array) -> Array:
            out: Array = v[..., :1] * ex + v[..., 1:2] * ey + v[..., 2:] * ez
            return out

        zero = np.zeros_like(pos[..., :2, :])
        return (
            np.concatenate((zero, world(w)[..., None, :]), axis=-2),
            np.concatenate((zero, world(a)[..., None, :]), axis=-2),
        )

    def place(self, ctx: Context) -> dict[str, JointState]:
        t = self.solve(ctx)
        h_local, _, _, _ = self._local(ctx)
        side = np.broadcast_to(ctx.scalar(self.side), ctx.theta.shape)
        s, c = np.sin(side)[..., None], np.cos(side)[..., None]
        # H = hx·ex + hy·ey + hz·J1 with ex = (J2 − cos(side) J1)/sin(side) and
        # ey = J1 × J2 / sin(side): linear in J1, J2 and J1 × J2, and so its derivatives.
        hx, hy, hz = (h_local[..., k : k + 1] for k in range(3))
        p1, p2 = hx / s, hy / s
        p0 = hz - hx * c / s

        def carried(j: Array | None, cross: Array | None) -> Array | None:
            if j is None or cross is None:
                return None
            out: Array = p0 * j[..., 0, :] + p1 * j[..., 1, :] + p2 * cross
            return out

        pos, vel, acc = t.pos, t.vel, t.acc
        cross0 = sphere.cross(pos[..., 0, :], pos[..., 1, :])
        cross1 = cross2 = None
        if vel is not None:
            cross1 = sphere.cross(vel[..., 0, :], pos[..., 1, :]) + sphere.cross(
                pos[..., 0, :], vel[..., 1, :]
            )
            if acc is not None:
                cross2 = (
                    sphere.cross(acc[..., 0, :], pos[..., 1, :])
                    + 2.0 * sphere.cross(vel[..., 0, :], vel[..., 1, :])
                    + sphere.cross(pos[..., 0, :], acc[..., 1, :])
                )
        h = carried(pos, cross0)
        assert h is not None
        track = (h, carried(vel, cross1), carried(acc, cross2))
        return _with_hinge(self.joints, t, track, t.valid)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the three legs, the body with H at its place, the turning arc
        H–J3 and the angle at H from the great circle H→J1 (times sin arm), in radians."""
        joints = self._read(positions, self.held)
        anchors = self._read(positions, self.anchors)
        shape = joints.shape[:-2]
        legs = self._lengths(params, shape)
        side, harc, hangle, arm = (
            np.broadcast_to(param_value(p, params), shape)
            for p in (self.side, self.harc, self.hangle, self.arm)
        )
        psi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        h, j1, j2, j3 = (
            positions[self.hinge],
            joints[..., 0, :],
            joints[..., 1, :],
            joints[..., 2, :],
        )
        links = np.max(np.abs(sphere.arc(joints, anchors) - legs), axis=-1)
        turned = np.remainder(sphere.angle_at(h, j1, j3) - psi + np.pi, 2.0 * np.pi) - np.pi
        errors = (
            links,
            np.abs(sphere.arc(j1, j2) - side),
            sphere.frame_error(j1, j2, h, harc, hangle),
            np.abs(sphere.arc(h, j3) - arm),
            np.abs(turned) * np.sin(arm),
            np.max(np.abs(sphere.norm(joints) - 1.0), axis=-1),
            np.abs(sphere.norm(h) - 1.0),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst

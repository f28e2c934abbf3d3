"""The spherical step kinds of a construction plan: joints are unit vectors (the axes of the
revolute joints, all through the sphere's centre O) and links are great-circle arcs.

As in the plane (:mod:`linkwright.engine.plane_steps`), each kind places its joint and owns
its closure, a residual written from its constraints alone (radians of arc, chords for rigid
points, and the unit norm), and the sentences that explain a failure or a limit position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from linkwright.engine.state import (
    ASSEMBLY_TOL,
    SINGULAR_MARGIN,
    SINGULAR_SIN,
    Array,
    Context,
    JointState,
    OnLink,
    OnPivot,
    Param,
    Params,
    Positions,
    TwoLinkDyad,
    at_crossing,
    combine,
    derivative,
    first,
    mask_derivatives,
    number,
    param_point,
    param_value,
    word,
)
from linkwright.geometry import sphere

__all__ = ["SphereCrank", "SphereDyad", "SphereRigid"]


def _unit_error(point: Array) -> Array:
    """How far a joint is from the unit sphere."""
    return np.abs(sphere.norm(point) - 1.0)


@dataclass(frozen=True)
class SphereCrank(OnPivot):
    """A joint at arc ``length`` from the fixed axis ``pivot``, turned by ``phase + ratio·θ``.

    The angle is measured about +O·pivot (right-handed) from the great circle that runs from
    the pivot towards the vector parameter ``ref`` (only its part normal to the pivot counts).
    Paper 000's crank: pivot A0 = (1, 0, 0), ref +y, A = (cos a2, sin a2 cos θ, sin a2 sin θ).
    The pivot must be a ground joint (:class:`~linkwright.engine.plane_steps.Fixed`); the plan
    checks it.
    """

    name: str
    pivot: str
    length: Param
    ref: str
    ratio: Param = 1.0
    phase: Param = 0.0

    def place(self, ctx: Context) -> JointState:
        o = ctx.joint(self.pivot)
        e1 = sphere.tangent(o.pos, ctx.point(self.ref))
        e2 = sphere.cross(o.pos, e1)
        length = ctx.scalar(self.length)
        k = ctx.scalar(self.ratio)
        phi = ctx.scalar(self.phase) + k * ctx.theta
        pos = sphere.circle_point(o.pos, e1, e2, length, phi)
        valid = o.valid & np.isfinite(pos).all(axis=-1)
        pos = np.where(valid[..., None], pos, np.nan)
        vel = acc = None
        # The joint turns about the fixed axis O at the rate k: Ẋ = k·O × X, Ẍ = k·O × Ẋ.
        rate = np.asarray(k)[..., None]
        if ctx.order >= 1:
            vel = rate * sphere.cross(o.pos, pos)
        if ctx.order >= 2:
            acc = rate * sphere.cross(o.pos, derivative(vel))
        regular = valid & o.regular
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)

    def closure(self, positions: Positions, params: Params) -> Array:
        """|sin| of the arc between the pivot and the reference: 0 where the reference lies
        along the pivot and the crank's angle has no origin."""
        return sphere.norm(sphere.cross(positions[self.pivot], param_point(self.ref, params)))

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest of the arc's error, the angle's (as a chord on the crank's circle) and
        the joint's distance from the unit sphere."""
        o, x = positions[self.pivot], positions[self.name]
        length = param_value(self.length, params)
        phi = param_value(self.phase, params) + param_value(self.ratio, params) * np.asarray(
            theta, dtype=float
        )
        turn = sphere.angle_at(o, param_point(self.ref, params), x) - phi
        turn = np.abs(np.angle(np.exp(1j * turn)))  # wrapped to [0, π]
        arc = np.abs(sphere.arc(o, x) - length)
        worst: Array = np.maximum.reduce([arc, turn * np.abs(np.sin(length)), _unit_error(x)])
        return worst

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return (
            f"the crank {self.pivot}–{self.name} has no angle origin: its reference direction "
            f"lies along the pivot {self.pivot}"
        )


@dataclass(frozen=True)
class SphereDyad(TwoLinkDyad):
    """The joint of two binary spherical links: the small circle of arc ``r1`` about ``p1``
    meets the small circle of arc ``r2`` about ``p2``, on branch ``sign((P1 × P2)·X)``
    (:func:`linkwright.geometry.sphere.small_circles`, whose margin is sin² of the angle at P1,
    0 at a limit position, as in the plane). Velocities and accelerations solve the
    differentiated constraints X·P1 = cos r1, X·P2 = cos r2, X·X = 1 (a 3×3 system with rows
    P1, P2, X).
    """

    in_line: ClassVar[str] = "on one great circle"

    def branch_of(self, positions: Positions, params: Params) -> Array:
        """The branch a placed joint is on, read off positions: sign((P1 × P2)·X)."""
        w = sphere.cross(positions[self.p1], positions[self.p2])
        return np.sign(sphere.dot(w, positions[self.name]))

    def place(self, ctx: Context) -> JointState:
        j1, j2 = ctx.joint(self.p1), ctx.joint(self.p2)
        r1, r2 = ctx.scalar(self.r1), ctx.scalar(self.r2)
        sign = ctx.branch(self.name, self.branch)
        p1, p2 = j1.pos, j2.pos
        meet = sphere.small_circles(p1, r1, p2, r2, sign, tol=ASSEMBLY_TOL)
        margin = meet.margin
        valid = j1.valid & j2.valid & meet.valid
        pos = np.where(valid[..., None], meet.point, np.nan)
        at = ctx.crossing(self.name)
        if at is not None:
            # Where P1 and P2 coincide or are antipodal, X → cos r1·P1 + sin r1·(±n) with n
            # the unit P1 × P2, which turns with its derivative v1 × P2 + P1 × v2.
            rate = sphere.unit(
                sphere.cross(derivative(j1.vel), p2) + sphere.cross(p1, derivative(j2.vel))
            )
            limit = np.cos(r1)[..., None] * p1 + (sign * at * np.sin(r1))[..., None] * rate
            pos, valid, margin = at_crossing(at, limit, pos, valid, margin, j1, j2)
        # sin of the angle at X between its two links: 0 at a limit (toggle) position.
        det_rel = sphere.dot(pos, meet.normal) / (np.sin(r1) * np.sin(r2))
        regular = valid & j1.regular & j2.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        if at is not None:
            regular &= at == 0  # the derivative system is singular there
        zero = np.zeros(pos.shape[:-1])
        # At a singular sample the solve gives inf, and inf·0 below NaN: both are masked.
        with np.errstate(invalid="ignore", over="ignore"):
            vel, acc = self._rates(ctx, j1, j2, pos, zero)
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)

    def _rates(
        self, ctx: Context, j1: JointState, j2: JointState, pos: Array, zero: Array
    ) -> tuple[Array | None, Array | None]:
        p1, p2 = j1.pos, j2.pos
        vel = acc = None
        if ctx.order >= 1:
            v1, v2 = derivative(j1.vel), derivative(j2.vel)
            vel, _ = sphere.solve_3x3_rows(
                p1, p2, pos, -sphere.dot(pos, v1), -sphere.dot(pos, v2), zero
            )
        if ctx.order >= 2:
            v = derivative(vel)
            acc, _ = sphere.solve_3x3_rows(
                p1,
                p2,
                pos,
                -2.0 * sphere.dot(v, v1) - sphere.dot(pos, derivative(j1.acc)),
                -2.0 * sphere.dot(v, v2) - sphere.dot(pos, derivative(j2.acc)),
                -sphere.dot(v, v),
            )

        return vel, acc

    def closure(self, positions: Positions, params: Params) -> Array:
        """The normalised discriminant G / (sin d sin r1)²: sin² of the angle at P1, ≥ 0 where
        the dyad closes, 0 at a limit position; from the parents alone."""
        r1, r2 = param_value(self.r1, params), param_value(self.r2, params)
        return sphere.small_circles(positions[self.p1], r1, positions[self.p2], r2, 1.0).margin

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the two arcs (radians) and of the joint's unit norm."""
        x = positions[self.name]
        e1 = sphere.arc(positions[self.p1], x) - param_value(self.r1, params)
        e2 = sphere.arc(positions[self.p2], x) - param_value(self.r2, params)
        worst: Array = np.maximum.reduce([np.abs(e1), np.abs(e2), _unit_error(x)])
        return worst

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the dyad cannot close: its arcs cannot reach, or cannot fold that short, or its
        parents' axes are parallel (with the numbers in degrees, given positions)."""
        if positions is None or params is None:
            return self._no_numbers()
        d = math.degrees(first(sphere.arc(positions[self.p1], positions[self.p2])))
        r1, r2 = math.degrees(number(self.r1, params)), math.degrees(number(self.r2, params))
        if d == 0 or d == 180:
            return (
                f"the axes {self.p1} and {self.p2} of dyad {self.name} are parallel, so no "
                "great circle joins them"
            )
        w1, w2 = word(self.r1), word(self.r2)
        reach = (f"min({w1} + {w2}, 360° - {w1} - {w2})", min(r1 + r2, 360 - r1 - r2))
        where = f"dyad {self.name}: arc {self.p1}{self.p2} = {d:.6g}°"
        return self._cannot_meet(where, d, reach, abs(r1 - r2), "°")


@dataclass(frozen=True)
class SphereRigid(OnLink):
    """A point fixed on the spherical link ``origin``→``toward``: at arc ``length`` from the
    origin, at ``angle`` from the great circle origin→toward, right-handed about +O·origin.

    Paper 000's coupler point C (arc AC, μ = BAC, its matrix T of eq. 6 and walk along AC). In
    the link's own basis X = a·O + b·T + c·(O × T), with constant a, b, c because O·T is
    constant on a rigid link; positions and both derivatives follow without any solve.
    """

    name: str
    origin: str
    toward: str
    length: Param
    angle: Param

    def place(self, ctx: Context) -> JointState:
        jo, jt = ctx.joint(self.origin), ctx.joint(self.toward)
        length, angle = ctx.scalar(self.length), ctx.scalar(self.angle)
        o, t = jo.pos, jt.pos
        ot = sphere.cross(o, t)
        cos_ot, sin_ot = sphere.dot(o, t), sphere.norm(ot)
        with np.errstate(divide="ignore", invalid="ignore"):
            b = np.sin(length) * np.cos(angle) / sin_ot
            c = np.sin(length) * np.sin(angle) / sin_ot
        a = np.cos(length) - b * cos_ot
        a, b, c = a[..., None], b[..., None], c[..., None]
        valid, regular = combine(jo, jt)
        valid = valid & (sin_ot > 0)
        pos = np.where(valid[..., None], a * o + b * t + c * ot, np.nan)
        vel = acc = None
        if ctx.order >= 1:
            vo, vt = derivative(jo.vel), derivative(jt.vel)
            vel = a * vo + b * vt + c * (sphere.cross(vo, t) + sphere.cross(o, vt))
        if ctx.order >= 2:
            ao, at = derivative(jo.acc), derivative(jt.acc)
            acc = (
                a * ao
                + b * at
                + c * (sphere.cross(ao, t) + 2.0 * sphere.cross(vo, vt) + sphere.cross(o, at))
            )

        regular = regular & valid
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)

    def closure(self, positions: Positions, params: Params) -> Array:
        """sin of the carrying link's arc: 0 where its axes are parallel and it has no frame."""
        return sphere.norm(sphere.cross(positions[self.origin], positions[self.toward]))

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The chord from the point to its place on the link, or its unit-norm error."""
        o, t, x = (positions[k] for k in (self.origin, self.toward, self.name))
        length, angle = param_value(self.length, params), param_value(self.angle, params)
        return np.maximum(sphere.frame_error(o, t, x, length, angle), _unit_error(x))

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return (
            f"the point {self.name} has no place: the axes {self.origin} and {self.toward} are "
            "parallel, so no great circle joins them"
        )

"""The planar step kinds of a construction plan (and the ground pivot, which serves both spaces).

Each kind places its joint from its parents (:meth:`place`, with derivatives from the
differentiated constraints) and owns what is known about it (see :mod:`linkwright.engine.state`):
its closure, a residual written from its constraints alone, and the sentences that explain why
it cannot assemble or where it reaches a limit position. Branch conventions: DESIGN.md and
:mod:`linkwright.engine.plan`.
"""

from __future__ import annotations

from dataclasses import dataclass

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
    always,
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
from linkwright.geometry import plane

__all__ = ["Crank", "DyadRRP", "DyadRRR", "Fixed", "Rigid", "Trammel"]


@dataclass(frozen=True)
class Fixed:
    """A ground pivot at the point parameter ``at``: a point in the plane, a unit vector (the
    joint's axis) on the sphere."""

    name: str
    at: str

    @property
    def parents(self) -> tuple[str, ...]:
        return ()

    @property
    def title(self) -> str:
        return f"ground pivot {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ()

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def place(self, ctx: Context) -> JointState:
        at = ctx.point(self.at)
        # A point [x, y] in the plane, a unit vector [x, y, z] on the sphere.
        pos = np.broadcast_to(at, ctx.theta.shape + at.shape[-1:])
        true = np.ones(ctx.theta.shape, dtype=bool)
        zeros = np.zeros(pos.shape) if ctx.order else None
        return JointState(pos, zeros, zeros, true, true)

    def closure(self, positions: Positions, params: Params) -> Array:
        """1: a ground pivot is always placed."""
        return always(positions, self.name)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """How far the pivot is from its point."""
        off: Array = np.linalg.norm(positions[self.name] - param_point(self.at, params), axis=-1)
        return off

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return f"the ground pivot {self.name} has no finite place ({self.at})"


@dataclass(frozen=True)
class Crank(OnPivot):
    """A joint at ``length`` from ``pivot``, at the absolute angle ``phase + ratio·θ``."""

    name: str
    pivot: str
    length: Param
    ratio: Param = 1.0
    phase: Param = 0.0

    def place(self, ctx: Context) -> JointState:
        o = ctx.joint(self.pivot)
        r = ctx.scalar(self.length)
        k = ctx.scalar(self.ratio)
        phi = ctx.scalar(self.phase) + k * ctx.theta
        c, s = np.cos(phi), np.sin(phi)
        arm = np.stack((r * c, r * s), axis=-1)
        pos = o.pos + arm
        vel = acc = None
        if ctx.order >= 1:
            vel = derivative(o.vel) + (k * r)[..., None] * np.stack((-s, c), axis=-1)
        if ctx.order >= 2:
            acc = derivative(o.acc) - (k * k)[..., None] * arm
        return JointState(pos, vel, acc, o.valid, o.regular)

    def closure(self, positions: Positions, params: Params) -> Array:
        """1: a crank turns wherever its pivot is."""
        return always(positions, self.pivot)

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """How far the joint is from ``length`` along the direction ``phase + ratio·θ``."""
        phi = param_value(self.phase, params) + param_value(self.ratio, params) * np.asarray(
            theta, dtype=float
        )
        want = param_value(self.length, params)[..., None] * plane.unit_direction(phi)
        return plane.norm(positions[self.name] - positions[self.pivot] - want)

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return f"the crank {self.pivot}–{self.name} has no pivot: {self.pivot} is not placed"


@dataclass(frozen=True)
class DyadRRR(TwoLinkDyad):
    """The joint of two binary links: circle(p1, r1) ∩ circle(p2, r2), on branch ``branch``."""

    def branch_of(self, positions: Positions, params: Params) -> Array:
        """The branch a placed joint is on, read off positions: sign((P2 − P1) × (P − P1))."""
        p1, p2 = positions[self.p1], positions[self.p2]
        return np.sign(plane.cross(p2 - p1, positions[self.name] - p1))

    def place(self, ctx: Context) -> JointState:
        j1, j2 = ctx.joint(self.p1), ctx.joint(self.p2)
        r1, r2 = ctx.scalar(self.r1), ctx.scalar(self.r2)
        sign = ctx.branch(self.name, self.branch)
        meet = plane.circle_circle(j1.pos, r1, j2.pos, r2, sign, tol=ASSEMBLY_TOL)
        margin = meet.margin  # = h²/r1² = sin² of the angle at p1
        valid = j1.valid & j2.valid & meet.valid
        pos = np.where(valid[..., None], meet.point, np.nan)
        at = ctx.crossing(self.name)
        if at is not None:
            # Where P1 and P2 coincide, P − P1 ⟂ P2 − P1 in the limit, which turns with
            # the parents' relative velocity (P2 − P1 ≈ (v2 − v1)·Δθ).
            rate = derivative(j2.vel) - derivative(j1.vel)
            with np.errstate(divide="ignore", invalid="ignore"):
                arm = plane.perp(rate) / plane.norm(rate)[..., None]
            limit = j1.pos + (sign * at * r1)[..., None] * arm
            pos, valid, margin = at_crossing(at, limit, pos, valid, margin, j1, j2)
        rel1, rel2 = pos - j1.pos, pos - j2.pos
        det_rel = plane.cross(rel1, rel2) / (r1 * r2)
        regular = valid & j1.regular & j2.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        if at is not None:
            regular &= at == 0  # the derivative system is singular there
        vel = acc = None
        if ctx.order >= 1:
            v1, v2 = derivative(j1.vel), derivative(j2.vel)
            vel, _ = plane.solve_2x2_rows(rel1, rel2, plane.dot(rel1, v1), plane.dot(rel2, v2))
        if ctx.order >= 2:
            w1, w2 = derivative(vel) - v1, derivative(vel) - v2
            acc, _ = plane.solve_2x2_rows(
                rel1,
                rel2,
                plane.dot(rel1, derivative(j1.acc)) - plane.dot(w1, w1),
                plane.dot(rel2, derivative(j2.acc)) - plane.dot(w2, w2),
            )
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The normalised discriminant: sin² of the angle at P1 (≥ 0 where the dyad closes, 0
        at a limit position), from the parents alone."""
        r1, r2 = param_value(self.r1, params), param_value(self.r2, params)
        return plane.circle_circle(positions[self.p1], r1, positions[self.p2], r2, 1.0).margin

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The larger error of the two link lengths."""
        p = positions[self.name]
        e1 = plane.norm(p - positions[self.p1]) - param_value(self.r1, params)
        e2 = plane.norm(p - positions[self.p2]) - param_value(self.r2, params)
        return np.maximum(np.abs(e1), np.abs(e2))

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the dyad cannot close: its links cannot reach, or cannot fold that short (with
        the numbers, given the parents' positions of one linkage at one input)."""
        if positions is None or params is None:
            return self._no_numbers()
        d = first(plane.norm(positions[self.p2] - positions[self.p1]))
        r1, r2 = number(self.r1, params), number(self.r2, params)
        if d == 0:
            return f"the pivots {self.p1} and {self.p2} of dyad {self.name} coincide"
        reach = (f"{word(self.r1)} + {word(self.r2)}", r1 + r2)
        where = f"dyad {self.name}: |{self.p1} {self.p2}| = {d:.6g}"
        return self._cannot_meet(where, d, reach, abs(r1 - r2))


@dataclass(frozen=True)
class DyadRRP:
    """A slider pin: circle(p1, r) ∩ the line through joint ``line_point`` at ``line_angle``.

    The line keeps a fixed direction (a ground guide, or a guide translating with its joint).
    """

    name: str
    p1: str
    r: Param
    line_point: str
    line_angle: Param
    branch: str = "assembly"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.line_point)

    @property
    def title(self) -> str:
        return f"dyad {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.p1, self.name),)

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def _direction(self, params: Params) -> Array:
        return plane.unit_direction(param_value(self.line_angle, params))

    def branch_of(self, positions: Positions, params: Params) -> Array:
        """The branch a placed pin is on, read off positions: sign((B − H)·d), H the foot of
        P1 on the guide and d its direction."""
        along = positions[self.name] - positions[self.p1]
        return np.sign(plane.dot(along, self._direction(params)))

    def place(self, ctx: Context) -> JointState:
        j1, jl = ctx.joint(self.p1), ctx.joint(self.line_point)
        r = ctx.scalar(self.r)
        sign = ctx.branch(self.name, self.branch)
        d = plane.unit_direction(ctx.scalar(self.line_angle))
        n = plane.perp(d)
        meet = plane.circle_line(j1.pos, r, jl.pos, d, sign, tol=ASSEMBLY_TOL)
        margin = meet.margin  # = cos² of the rod's angle to the line
        valid = j1.valid & jl.valid & meet.valid
        pos = np.where(valid[..., None], meet.point, np.nan)
        rel1 = pos - j1.pos
        det_rel = plane.cross(rel1, n) / r
        regular = valid & j1.regular & jl.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        vel = acc = None
        if ctx.order >= 1:
            v1 = derivative(j1.vel)
            vel, _ = plane.solve_2x2_rows(
                rel1, n, plane.dot(rel1, v1), plane.dot(n, derivative(jl.vel))
            )
        if ctx.order >= 2:
            w1 = derivative(vel) - v1
            acc, _ = plane.solve_2x2_rows(
                rel1,
                n,
                plane.dot(rel1, derivative(j1.acc)) - plane.dot(w1, w1),
                plane.dot(n, derivative(jl.acc)),
            )
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The normalised discriminant: cos² of the rod's angle to its guide (≥ 0 where the
        rod reaches the guide, 0 where it stands square to it)."""
        d = self._direction(params)
        r = param_value(self.r, params)
        return plane.circle_line(positions[self.p1], r, positions[self.line_point], d, 1.0).margin

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The larger of the rod's length error and the pin's distance from its guide."""
        pin = positions[self.name]
        rod = plane.norm(pin - positions[self.p1]) - param_value(self.r, params)
        off = plane.cross(self._direction(params), pin - positions[self.line_point])
        return np.maximum(np.abs(rod), np.abs(off))

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the rod cannot reach its guide (with the distance, given positions)."""
        w = word(self.r)
        if positions is None or params is None:
            return f"the {w} of dyad {self.name} cannot reach the slider's line"
        rel = positions[self.p1] - positions[self.line_point]
        off = abs(first(plane.cross(self._direction(params), rel)))
        return (
            f"the {w} cannot reach the slider's line (dyad {self.name}: {self.p1} is "
            f"{off:.6g} from it > {w} = {number(self.r, params):.6g})"
        )

    def at_limit(self) -> str:
        """What happens at a limit position of the input."""
        return (
            f"dyad {self.name}: the rod {self.p1}–{self.name} stands square to its guide, so "
            f"the pin {self.name} is at the end of its reach"
        )


@dataclass(frozen=True)
class Rigid(OnLink):
    """A point fixed on the link ``origin``→``toward``: local (u, v), x along the link, v left.

    Its derivatives use the link's constant length, which is exact because both joints lie on one
    rigid body.
    """

    name: str
    origin: str
    toward: str
    u: Param
    v: Param

    def place(self, ctx: Context) -> JointState:
        jo, jt = ctx.joint(self.origin), ctx.joint(self.toward)
        u, v = ctx.scalar(self.u), ctx.scalar(self.v)
        delta = jt.pos - jo.pos
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_len = 1.0 / plane.norm(delta)
        cu, cv = (u * inv_len)[..., None], (v * inv_len)[..., None]

        def local(vec: Array) -> Array:
            # Where the link's joints met (no frame: inv_len is inf) the sample is masked
            # below; its products are NaN by design, not a warning.
            with np.errstate(invalid="ignore"):
                return cu * vec + cv * plane.perp(vec)

        valid, regular = combine(jo, jt)
        valid = valid & np.isfinite(inv_len)
        pos = np.where(valid[..., None], jo.pos + local(delta), np.nan)
        vel = acc = None
        if ctx.order >= 1:
            vo = derivative(jo.vel)
            vel = vo + local(derivative(jt.vel) - vo)
        if ctx.order >= 2:
            ao = derivative(jo.acc)
            acc = ao + local(derivative(jt.acc) - ao)
        regular = regular & valid
        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)

    def closure(self, positions: Positions, params: Params) -> Array:
        """The length of the carrying link: 0 where its joints coincide and it has no frame."""
        return plane.norm(positions[self.toward] - positions[self.origin])

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """How far the point is from (u, v) in the link's frame."""
        o, t, p = (positions[k] for k in (self.origin, self.toward, self.name))
        u, v = param_value(self.u, params), param_value(self.v, params)
        return plane.frame_error(o, t, p, u, v)

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return (
            f"the point {self.name} has no place: {self.origin} and {self.toward} coincide, so "
            "the link they span has no direction"
        )


@dataclass(frozen=True)
class Trammel:
    """A slider on one guide whose rigid arm, turned by the input, ends on a second guide.

    The joint X runs on the line through ``guide1`` at ``angle1``; the arm from X has length
    ``arm`` and the absolute angle ``phase + θ``, and its far end runs on the line through
    ``guide2`` at ``angle2``. This is the double slider (elliptic trammel) of Kiper et al. driven
    by its coupler angle (paper 004, eqs. 1–2): with w the arm vector, X = G1 + t·e1 and
    (X + w − G2)·n2 = 0 give t = (G2 − G1 − w)·n2 / (e1·n2), linear in w, so positions and both
    derivatives are closed forms. It assembles at every input unless the guides are parallel.
    """

    name: str
    guide1: str
    angle1: Param
    guide2: str
    angle2: Param
    arm: Param
    phase: Param = 0.0

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.guide1, self.guide2)

    @property
    def title(self) -> str:
        return f"slider {self.name}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ()

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def place(self, ctx: Context) -> JointState:
        g1, g2 = ctx.joint(self.guide1), ctx.joint(self.guide2)
        e1 = plane.unit_direction(ctx.scalar(self.angle1))
        n2 = plane.perp(plane.unit_direction(ctx.scalar(self.angle2)))
        arm = ctx.scalar(self.arm)
        phi = ctx.scalar(self.phase) + ctx.theta
        w = arm[..., None] * np.stack((np.cos(phi), np.sin(phi)), axis=-1)
        den = plane.dot(e1, n2)  # sin of the angle between the guides
        parallel = np.abs(den) <= SINGULAR_SIN
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(parallel, np.nan, 1.0 / den)

        def along(g1v: Array, g2v: Array, wv: Array) -> Array:
            return g1v + (plane.dot(g2v - g1v - wv, n2) * inv)[..., None] * e1

        valid, regular = combine(g1, g2)
        valid = valid & ~np.broadcast_to(parallel, valid.shape)
        pos = np.where(valid[..., None], along(g1.pos, g2.pos, w), np.nan)
        regular = regular & valid
        # dw/dθ = perp(w) and d²w/dθ² = −w: the arm turns one-for-one with the input.
        vel = acc = None
        if ctx.order >= 1:
            vel = along(derivative(g1.vel), derivative(g2.vel), plane.perp(w))
        if ctx.order >= 2:
            acc = along(derivative(g1.acc), derivative(g2.acc), -w)

        vel, acc = mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)

    def closure(self, positions: Positions, params: Params) -> Array:
        """|sin| of the angle between the guides: it assembles where this exceeds
        :data:`~linkwright.engine.state.SINGULAR_SIN` (the guides are not parallel)."""
        e1 = plane.unit_direction(param_value(self.angle1, params))
        e2 = plane.unit_direction(param_value(self.angle2, params))
        return np.broadcast_to(np.abs(plane.cross(e1, e2)), np.shape(positions[self.guide1])[:-1])

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The larger distance of the slider from its guide and of the arm's end from its."""
        x = positions[self.name]
        e1 = plane.unit_direction(param_value(self.angle1, params))
        e2 = plane.unit_direction(param_value(self.angle2, params))
        phi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        end = x + param_value(self.arm, params)[..., None] * plane.unit_direction(phi)
        off1 = plane.cross(e1, x - positions[self.guide1])
        off2 = plane.cross(e2, end - positions[self.guide2])
        return np.maximum(np.abs(off1), np.abs(off2))

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        return (
            f"the guides of {self.guide1} and {self.guide2} are parallel, so the arm from the "
            f"slider {self.name} cannot end on the second one"
        )

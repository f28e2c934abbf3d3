"""Construction plans: a linkage as an ordered list of steps, each placing one joint.

A plan says *how* joints are built from joints already known; the numbers (lengths, pivots,
assembly signs) live in a separate mapping of named parameters, so one plan evaluates a whole
batch of mechanisms at once (Pinocchio's model/data split, applied to linkages).

Each step maps its parents' position, velocity and acceleration (derivatives with respect to the
input angle θ) to its own joint's, from the differentiated constraint equations: a 2×2 solve for
a dyad, closed forms for cranks and rigid points. Nothing here differences numerically.

Branch convention (one definition for every dyad, see DESIGN.md): a joint P placed from parents
P1 then P2 has branch ``sign((P2 − P1) × (P − P1))``; a slider pin B placed on a line from P1 has
branch ``sign((B − H)·d)``, H the foot of P1 on the line and d the line's direction. On the
sphere (joints are unit vectors, the axes of the revolute joints) a dyad joint X has branch
``sign((P1 × P2)·X)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from linkwright.geometry import plane, sphere

__all__ = [
    "Crank",
    "DyadRRP",
    "DyadRRR",
    "Fixed",
    "JointState",
    "Param",
    "Plan",
    "Rigid",
    "SphereCrank",
    "SphereDyad",
    "SphereRigid",
    "Step",
    "Trammel",
]

Array = NDArray[np.float64]
Param = str | float
"""A step's numeric parameter: the name of an entry of the parameter mapping, or a constant."""

# Below this |sin| of the angle between a dyad's two links the 2×2 derivative system is treated
# as singular: the relative error of the derivatives grows like eps/sin², so past 1e-8 they are
# no longer trustworthy and are reported as masked rather than as large wrong numbers.
SINGULAR_SIN = 1e-8
# The same bound on the dyad's own margin (sin² of the angle at its first pivot, or cos² of a
# rod's angle to its guide): an exact limit position has margin ~1e-16 yet passes the test above
# by rounding, and its derivatives (infinite in truth) would come out as huge finite numbers.
SINGULAR_MARGIN = 1e-12
# A dyad whose normalised discriminant is above -ASSEMBLY_TOL still closes (rounding at an exact
# limit position must not turn the limit itself into a failure); the clamp leaves a constraint
# residual of the same relative size, far below the 1e-10 promised.
ASSEMBLY_TOL = 1e-12


@dataclass(frozen=True)
class JointState:
    """Position, first and second θ-derivatives of one joint, and where they are defined.

    ``valid`` marks samples where the joint could be placed; ``regular`` marks samples where the
    derivatives are finite (not at a singular, e.g. toggle, position). Both have the batch shape.
    """

    pos: Array
    vel: Array | None
    acc: Array | None
    valid: NDArray[np.bool_]
    regular: NDArray[np.bool_]
    margin: Array | None = None
    """For dyads: the normalised discriminant (≥ 0 where the dyad closes; 0 at a limit)."""
    branch: Array | None = None
    """For dyads: the branch sign used at each sample (for a triad: its pose index)."""
    label: Array | None = None
    """The branch's label that changes only at a limit position: a dyad's sign (its
    ``branch``, when left None), a triad's closure sign (its pose index does not)."""


class Context(Protocol):
    order: int

    def scalar(self, p: Param) -> Array: ...
    def point(self, key: str) -> Array: ...
    def joint(self, name: str) -> JointState: ...
    def branch(self, step_name: str, key: str) -> Array: ...
    def crossing(self, step_name: str) -> Array | None: ...
    @property
    def theta(self) -> Array: ...


class Step(Protocol):
    name: str

    @property
    def parents(self) -> tuple[str, ...]: ...

    def links(self) -> tuple[tuple[str, str], ...]: ...
    def plates(self) -> tuple[tuple[str, ...], ...]: ...
    def place(self, ctx: Context) -> JointState | dict[str, JointState]:
        """The state of the joint the step places (of each joint, for a triad)."""
        ...


def _zeros_like_pos(pos: Array) -> Array:
    return np.zeros_like(pos)


def _combine(*states: JointState) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    valid = states[0].valid
    regular = states[0].regular
    for s in states[1:]:
        valid = valid & s.valid
        regular = regular & s.regular
    return valid, regular


@dataclass(frozen=True)
class Fixed:
    """A ground pivot at the point parameter ``at``: a point in the plane, a unit vector (the
    joint's axis) on the sphere."""

    name: str
    at: str

    @property
    def parents(self) -> tuple[str, ...]:
        return ()

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


@dataclass(frozen=True)
class Crank:
    """A joint at ``length`` from ``pivot``, at the absolute angle ``phase + ratio·θ``."""

    name: str
    pivot: str
    length: Param
    ratio: Param = 1.0
    phase: Param = 0.0

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.pivot,)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.pivot, self.name),)

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

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
            vel = o.vel + (k * r)[..., None] * np.stack((-s, c), axis=-1)
        if ctx.order >= 2:
            acc = o.acc - (k * k)[..., None] * arm
        return JointState(pos, vel, acc, o.valid, o.regular)


@dataclass(frozen=True)
class DyadRRR:
    """The joint of two binary links: circle(p1, r1) ∩ circle(p2, r2), on branch ``branch``."""

    name: str
    p1: str
    r1: Param
    p2: str
    r2: Param
    branch: str = "assembly"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.p2)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.p1, self.name), (self.p2, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def branch_of(self, positions: Mapping[str, Array], params: Mapping[str, Array]) -> Array:
        """The branch a placed joint is on, read off positions: sign((P2 − P1) × (P − P1))."""
        p1, p2 = positions[self.p1], positions[self.p2]
        return np.sign(plane.cross(p2 - p1, positions[self.name] - p1))

    def place(self, ctx: Context) -> JointState:
        j1, j2 = ctx.joint(self.p1), ctx.joint(self.p2)
        r1, r2 = ctx.scalar(self.r1), ctx.scalar(self.r2)
        sign = ctx.branch(self.name, self.branch)
        delta = j2.pos - j1.pos
        d2 = plane.dot(delta, delta)
        # (r1+r2)² − d² and d² − (r1−r2)², each exact near its own root.
        outer = (r1 + r2) ** 2 - d2
        inner = d2 - (r1 - r2) ** 2
        with np.errstate(divide="ignore", invalid="ignore"):
            margin = outer * inner / (4.0 * d2 * r1 * r1)  # = h²/r1² = sin² of the angle at p1
            d = np.sqrt(d2)
            a = ((r1 - r2) * (r1 + r2) + d2) / (2.0 * d)  # r1² − r2² factored: exact as r1 → r2
            h = r1 * np.sqrt(np.clip(margin, 0.0, None))
            pos = (
                j1.pos
                + (a[..., None] * delta + (sign * h)[..., None] * plane.perp(delta))
                / (d[..., None])
            )
        valid = j1.valid & j2.valid & (margin >= -ASSEMBLY_TOL) & (d2 > 0)
        pos = np.where(valid[..., None], pos, np.nan)
        at = ctx.crossing(self.name)
        if at is not None:
            # Where P1 and P2 coincide, P − P1 ⟂ P2 − P1 in the limit, which turns with
            # the parents' relative velocity (P2 − P1 ≈ (v2 − v1)·Δθ).
            rate = j2.vel - j1.vel
            with np.errstate(divide="ignore", invalid="ignore"):
                arm = plane.perp(rate) / plane.norm(rate)[..., None]
            limit = j1.pos + (sign * at * r1)[..., None] * arm
            pos, valid, margin = _at_crossing(at, limit, pos, valid, margin, j1, j2)
        rel1, rel2 = pos - j1.pos, pos - j2.pos
        det_rel = plane.cross(rel1, rel2) / (r1 * r2)
        regular = valid & j1.regular & j2.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        if at is not None:
            regular &= at == 0  # the derivative system is singular there
        vel = acc = None
        if ctx.order >= 1:
            vel, _ = plane.solve_2x2_rows(
                rel1, rel2, plane.dot(rel1, j1.vel), plane.dot(rel2, j2.vel)
            )
        if ctx.order >= 2:
            w1, w2 = vel - j1.vel, vel - j2.vel
            acc, _ = plane.solve_2x2_rows(
                rel1,
                rel2,
                plane.dot(rel1, j1.acc) - plane.dot(w1, w1),
                plane.dot(rel2, j2.acc) - plane.dot(w2, w2),
            )
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)


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

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.p1, self.name),)

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def branch_of(self, positions: Mapping[str, Array], params: Mapping[str, Array]) -> Array:
        """The branch a placed pin is on, read off positions: sign((B − H)·d), H the foot of
        P1 on the guide and d its direction."""
        angle = params[self.line_angle] if isinstance(self.line_angle, str) else self.line_angle
        d = np.stack(np.broadcast_arrays(np.cos(angle), np.sin(angle)), axis=-1)
        along = positions[self.name] - positions[self.p1]
        return np.sign(plane.dot(along, d))

    def place(self, ctx: Context) -> JointState:
        j1, jl = ctx.joint(self.p1), ctx.joint(self.line_point)
        r = ctx.scalar(self.r)
        sign = ctx.branch(self.name, self.branch)
        ang = ctx.scalar(self.line_angle)
        d = np.stack(np.broadcast_arrays(np.cos(ang), np.sin(ang)), axis=-1)
        n = plane.perp(d)
        rel = j1.pos - jl.pos
        along = plane.dot(rel, d)
        offset = plane.dot(rel, n)  # signed distance of p1 from the line
        with np.errstate(divide="ignore", invalid="ignore"):
            margin = (r - offset) * (r + offset) / (r * r)  # = cos² of the rod's angle to the line
            half = r * np.sqrt(np.clip(margin, 0.0, None))
        foot = jl.pos + along[..., None] * d
        pos = foot + (sign * half)[..., None] * d
        valid = j1.valid & jl.valid & (margin >= -ASSEMBLY_TOL)
        pos = np.where(valid[..., None], pos, np.nan)
        rel1 = pos - j1.pos
        det_rel = plane.cross(rel1, n) / r
        regular = valid & j1.regular & jl.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        vel = acc = None
        if ctx.order >= 1:
            vel, _ = plane.solve_2x2_rows(rel1, n, plane.dot(rel1, j1.vel), plane.dot(n, jl.vel))
        if ctx.order >= 2:
            w1 = vel - j1.vel
            acc, _ = plane.solve_2x2_rows(
                rel1, n, plane.dot(rel1, j1.acc) - plane.dot(w1, w1), plane.dot(n, jl.acc)
            )
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)


@dataclass(frozen=True)
class Rigid:
    """A point fixed on the link ``origin``→``toward``: local (u, v), x along the link, v left.

    Its derivatives use the link's constant length, which is exact because both joints lie on one
    rigid body.
    """

    name: str
    origin: str
    toward: str
    u: Param
    v: Param

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.origin, self.toward)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.origin, self.name), (self.toward, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ((self.origin, self.toward, self.name),)

    def place(self, ctx: Context) -> JointState:
        jo, jt = ctx.joint(self.origin), ctx.joint(self.toward)
        u, v = ctx.scalar(self.u), ctx.scalar(self.v)
        delta = jt.pos - jo.pos
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_len = 1.0 / plane.norm(delta)
        cu, cv = (u * inv_len)[..., None], (v * inv_len)[..., None]

        def local(vec: Array) -> Array:
            return cu * vec + cv * plane.perp(vec)

        valid, regular = _combine(jo, jt)
        valid = valid & np.isfinite(inv_len)
        pos = np.where(valid[..., None], jo.pos + local(delta), np.nan)
        vel = jo.vel + local(jt.vel - jo.vel) if ctx.order >= 1 else None
        acc = jo.acc + local(jt.acc - jo.acc) if ctx.order >= 2 else None
        regular = regular & valid
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)


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

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ()

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def place(self, ctx: Context) -> JointState:
        g1, g2 = ctx.joint(self.guide1), ctx.joint(self.guide2)
        e1 = _direction(ctx.scalar(self.angle1))
        n2 = plane.perp(_direction(ctx.scalar(self.angle2)))
        arm = ctx.scalar(self.arm)
        phi = ctx.scalar(self.phase) + ctx.theta
        w = arm[..., None] * np.stack((np.cos(phi), np.sin(phi)), axis=-1)
        den = plane.dot(e1, n2)  # sin of the angle between the guides
        parallel = np.abs(den) <= SINGULAR_SIN
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(parallel, np.nan, 1.0 / den)

        def along(g1v: Array, g2v: Array, wv: Array) -> Array:
            return g1v + (plane.dot(g2v - g1v - wv, n2) * inv)[..., None] * e1

        valid, regular = _combine(g1, g2)
        valid = valid & ~np.broadcast_to(parallel, valid.shape)
        pos = np.where(valid[..., None], along(g1.pos, g2.pos, w), np.nan)
        regular = regular & valid
        # dw/dθ = perp(w) and d²w/dθ² = −w: the arm turns one-for-one with the input.
        vel = along(g1.vel, g2.vel, plane.perp(w)) if ctx.order >= 1 else None
        acc = along(g1.acc, g2.acc, -w) if ctx.order >= 2 else None
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)


@dataclass(frozen=True)
class SphereCrank:
    """A joint at arc ``length`` from the fixed axis ``pivot``, turned by ``phase + ratio·θ``.

    The angle is measured about +O·pivot (right-handed) from the great circle that runs from
    the pivot towards the vector parameter ``ref`` (only its part normal to the pivot counts).
    Paper 000's crank: pivot A0 = (1, 0, 0), ref +y, A = (cos a2, sin a2 cos θ, sin a2 sin θ).
    The pivot must be a ground joint (:class:`Fixed`); the plan checks it.
    """

    name: str
    pivot: str
    length: Param
    ref: str
    ratio: Param = 1.0
    phase: Param = 0.0

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.pivot,)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.pivot, self.name),)

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def place(self, ctx: Context) -> JointState:
        o = ctx.joint(self.pivot)
        e1 = sphere.tangent(o.pos, ctx.point(self.ref))
        e2 = sphere.cross(o.pos, e1)
        length = ctx.scalar(self.length)
        k = ctx.scalar(self.ratio)
        phi = ctx.scalar(self.phase) + k * ctx.theta
        c, s = np.cos(phi)[..., None], np.sin(phi)[..., None]
        radius = np.sin(length)[..., None]
        pos = np.cos(length)[..., None] * o.pos + radius * (c * e1 + s * e2)
        valid = o.valid & np.isfinite(pos).all(axis=-1)
        pos = np.where(valid[..., None], pos, np.nan)
        vel = acc = None
        if ctx.order >= 1:
            vel = np.asarray(k)[..., None] * radius * (c * e2 - s * e1)
        if ctx.order >= 2:
            acc = -(np.asarray(k)[..., None] ** 2) * radius * (c * e1 + s * e2)
        regular = valid & o.regular
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)


@dataclass(frozen=True)
class SphereDyad:
    """The joint of two binary spherical links: the small circle of arc ``r1`` about ``p1``
    meets the small circle of arc ``r2`` about ``p2``, on branch ``sign((P1 × P2)·X)``.

    With d the arc P1P2 and φ the angle at P1 between the great circles P1→P2 and P1→X
    (spherical triangle P1 P2 X with sides d, r1, r2)::

        sin φ · sin r1 sin d = ±√G,   cos φ · sin r1 sin d = cos r2 − cos r1 cos d,

    G the Gram determinant of the three unit vectors (:func:`linkwright.geometry.sphere.gram`),
    taken in product form so that it is accurate at a limit position. The margin is
    ``sin² φ = G / (sin² d sin² r1)``, 0 at a limit position, as in the plane. Velocities and
    accelerations solve the differentiated constraints X·P1 = cos r1, X·P2 = cos r2, X·X = 1
    (a 3×3 system with rows P1, P2, X).
    """

    name: str
    p1: str
    r1: Param
    p2: str
    r2: Param
    branch: str = "assembly"

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.p1, self.p2)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.p1, self.name), (self.p2, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ()

    def branch_of(self, positions: Mapping[str, Array], params: Mapping[str, Array]) -> Array:
        """The branch a placed joint is on, read off positions: sign((P1 × P2)·X)."""
        w = sphere.cross(positions[self.p1], positions[self.p2])
        return np.sign(sphere.dot(w, positions[self.name]))

    def place(self, ctx: Context) -> JointState:
        j1, j2 = ctx.joint(self.p1), ctx.joint(self.p2)
        r1, r2 = ctx.scalar(self.r1), ctx.scalar(self.r2)
        sign = ctx.branch(self.name, self.branch)
        p1, p2 = j1.pos, j2.pos
        w = sphere.cross(p1, p2)
        sin_d = sphere.norm(w)
        cos_d = sphere.dot(p1, p2)
        d = np.arctan2(sin_d, cos_d)
        g = sphere.gram(d, r1, r2)
        with np.errstate(divide="ignore", invalid="ignore"):
            margin = g / (sin_d * np.sin(r1)) ** 2
        # An orthonormal frame at P1 (t towards P2, n = P1 × t) built from the vectors, not from
        # sin d, so that X is a unit vector however close P1 and P2 come.
        # (P1 × P2) × P1 is P2's part normal to P1, and stays normal to P1 to rounding even
        # when it is itself only rounding (P2 − cos d·P1 would not).
        t = sphere.unit(sphere.cross(w, p1))
        n = sphere.cross(p1, t)
        phi = np.arctan2(sign * np.sqrt(np.clip(g, 0.0, None)), np.cos(r2) - np.cos(r1) * cos_d)
        pos = np.cos(r1)[..., None] * p1 + np.sin(r1)[..., None] * (
            np.cos(phi)[..., None] * t + np.sin(phi)[..., None] * n
        )
        # With P1 and P2 parallel to rounding the frame's direction t is arbitrary but still a
        # unit vector normal to P1, and the dyad can only close there if r1 ≈ r2 (a change
        # point, where X may indeed sit anywhere on its circle): X still meets both arcs.
        valid = j1.valid & j2.valid & (margin >= -ASSEMBLY_TOL) & (sin_d > 0)
        pos = np.where(valid[..., None], pos, np.nan)
        at = ctx.crossing(self.name)
        if at is not None:
            # Where P1 and P2 coincide or are antipodal, X → cos r1·P1 + sin r1·(±n) with n
            # the unit P1 × P2, which turns with its derivative v1 × P2 + P1 × v2.
            rate = sphere.unit(sphere.cross(j1.vel, p2) + sphere.cross(p1, j2.vel))
            limit = np.cos(r1)[..., None] * p1 + (sign * at * np.sin(r1))[..., None] * rate
            pos, valid, margin = _at_crossing(at, limit, pos, valid, margin, j1, j2)
        # sin of the angle at X between its two links: 0 at a limit (toggle) position.
        det_rel = sphere.dot(pos, w) / (np.sin(r1) * np.sin(r2))
        regular = valid & j1.regular & j2.regular & (np.abs(det_rel) > SINGULAR_SIN)
        regular &= margin > SINGULAR_MARGIN
        if at is not None:
            regular &= at == 0  # the derivative system is singular there
        vel = acc = None
        zero = np.zeros(pos.shape[:-1])
        # At a singular sample the solve gives inf, and inf·0 below NaN: both are masked.
        with np.errstate(invalid="ignore", over="ignore"):
            vel, acc = self._rates(ctx, j1, j2, pos, zero)
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular, margin=margin, branch=sign)

    def _rates(self, ctx, j1, j2, pos, zero):
        p1, p2 = j1.pos, j2.pos
        vel = acc = None
        if ctx.order >= 1:
            vel, _ = sphere.solve_3x3_rows(
                p1, p2, pos, -sphere.dot(pos, j1.vel), -sphere.dot(pos, j2.vel), zero
            )
        if ctx.order >= 2:
            acc, _ = sphere.solve_3x3_rows(
                p1,
                p2,
                pos,
                -2.0 * sphere.dot(vel, j1.vel) - sphere.dot(pos, j1.acc),
                -2.0 * sphere.dot(vel, j2.vel) - sphere.dot(pos, j2.acc),
                -sphere.dot(vel, vel),
            )
        return vel, acc


@dataclass(frozen=True)
class SphereRigid:
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

    @property
    def parents(self) -> tuple[str, ...]:
        return (self.origin, self.toward)

    def links(self) -> tuple[tuple[str, str], ...]:
        """The links a drawing shows for this step, as pairs of joints."""
        return ((self.origin, self.name), (self.toward, self.name))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        """The rigid bodies of three joints or more that this step makes, to fill."""
        return ((self.origin, self.toward, self.name),)

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
        valid, regular = _combine(jo, jt)
        valid = valid & (sin_ot > 0)
        pos = np.where(valid[..., None], a * o + b * t + c * ot, np.nan)
        vel = acc = None
        if ctx.order >= 1:
            vel = a * jo.vel + b * jt.vel + c * (sphere.cross(jo.vel, t) + sphere.cross(o, jt.vel))
        if ctx.order >= 2:
            acc = (
                a * jo.acc
                + b * jt.acc
                + c
                * (
                    sphere.cross(jo.acc, t)
                    + 2.0 * sphere.cross(jo.vel, jt.vel)
                    + sphere.cross(o, jt.acc)
                )
            )
        regular = regular & valid
        vel, acc = _mask_derivatives(vel, acc, regular)
        return JointState(pos, vel, acc, valid, regular)


def _direction(angle: Array) -> Array:
    return np.stack(np.broadcast_arrays(np.cos(angle), np.sin(angle)), axis=-1)


def _at_crossing(
    at: Array, limit: Array, pos: Array, valid: NDArray[np.bool_], margin: Array, j1, j2
) -> tuple[Array, NDArray[np.bool_], Array]:
    """A dyad's joint where its parents coincide: ``limit`` at the samples marked in ``at``.

    Its two links then lie on each other, at right angles to the parents' line in the limit:
    the margin (sin² of the angle at P1) is 1, far from a limit position.
    """
    on = at != 0
    ok = j1.valid & j2.valid & np.isfinite(limit).all(axis=-1)
    pos = np.where(on[..., None], np.where(ok[..., None], limit, np.nan), pos)
    return pos, np.where(on, ok, valid), np.where(on, 1.0, margin)


def _mask_derivatives(
    vel: Array | None, acc: Array | None, regular: NDArray[np.bool_]
) -> tuple[Array | None, Array | None]:
    keep = regular[..., None]
    if vel is not None:
        vel = np.where(keep, vel, np.nan)
    if acc is not None:
        acc = np.where(keep, acc, np.nan)
    return vel, acc


DYAD_TYPES = (DyadRRR, DyadRRP, SphereDyad)
PLANE_STEPS = (Crank, DyadRRR, DyadRRP, Rigid, Trammel)
SPHERE_STEPS = (SphereCrank, SphereDyad, SphereRigid)


@dataclass(frozen=True)
class Plan:
    """An ordered, validated list of steps for one single-input linkage.

    ``traced`` names the joints whose paths are the linkage's curves (the first is the default).
    """

    steps: tuple[Step, ...]
    traced: tuple[str, ...] = ("P",)

    def __post_init__(self) -> None:
        known: set[str] = set()
        for step in self.steps:
            for parent in step.parents:
                if parent not in known:
                    raise ValueError(
                        f"joint {step.name!r} is built from {parent!r}, "
                        "which is not placed before it"
                    )
            for joint in placed_joints(step):
                if joint in known:
                    raise ValueError(f"joint {joint!r} is placed twice")
                known.add(joint)
        for name in self.traced:
            if name not in known:
                raise ValueError(f"traced joint {name!r} is not placed by the plan")
        if any(_space_of(s) == "plane" for s in self.steps) and any(
            _space_of(s) == "sphere" for s in self.steps
        ):
            raise ValueError("a plan places its joints either in the plane or on the sphere")
        for step in self.steps:
            if isinstance(step, SphereCrank) and not isinstance(self.step(step.pivot), Fixed):
                raise ValueError(
                    f"spherical crank {step.name!r} turns about {step.pivot!r}, "
                    "which is not a ground pivot"
                )

    @property
    def space(self) -> str:
        """``"sphere"`` for a plan of spherical steps, else ``"plane"``."""
        return "sphere" if any(_space_of(s) == "sphere" for s in self.steps) else "plane"

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(j for s in self.steps for j in placed_joints(s))

    @property
    def dyads(self) -> tuple[Step, ...]:
        return tuple(s for s in self.steps if isinstance(s, DYAD_TYPES))

    @property
    def triads(self) -> tuple[Step, ...]:
        """The steps that place several joints at once, each on one of several poses."""
        return tuple(s for s in self.steps if hasattr(s, "max_poses"))

    @property
    def ground(self) -> tuple[str, ...]:
        """The ground pivots."""
        return tuple(s.name for s in self.steps if isinstance(s, Fixed))

    @property
    def links(self) -> tuple[tuple[str, str], ...]:
        """Every link a drawing shows, as pairs of joints, from the steps that make them."""
        return tuple(pair for s in self.steps for pair in s.links())

    @property
    def plates(self) -> tuple[tuple[str, ...], ...]:
        """Every rigid body of three joints or more, to fill in a drawing."""
        return tuple(plate for s in self.steps for plate in s.plates())

    def step(self, name: str) -> Step:
        """The step that places joint ``name``."""
        for s in self.steps:
            if name in placed_joints(s):
                return s
        raise KeyError(name)


def placed_joints(step: Step) -> tuple[str, ...]:
    """The joints a step places: its own name, or several for a triad."""
    return tuple(getattr(step, "joints", (step.name,)))


def _space_of(step: Step) -> str | None:
    """ "plane" or "sphere" for a step kind that belongs to one space, None for a ground pivot."""
    if isinstance(step, PLANE_STEPS):
        return "plane"
    if isinstance(step, SPHERE_STEPS):
        return "sphere"
    return getattr(step, "space", None)

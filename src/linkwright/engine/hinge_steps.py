"""A linkage driven at a moving hinge: the input is the angle between two moving links.

A motor carried by a link (on a coupler, in a robot's elbow) drives the angle at a hinge H
between its link to a placed joint Y (length b) and its link to a joint X (length a), and X
hangs from a placed joint Z by a link of length r. The angle φ at H, from H→Y to H→X
(counter-clockwise), is the input plus a phase. The triangle H X Y then has a known shape: by
the law of cosines |X − Y| = d(φ) with d² = a² + b² − 2ab cos φ, so X is circle(Z, r) ∩
circle(Y, d(φ)), a dyad whose second length follows the input, and H follows from X, Y and φ.
In complex numbers, with q(φ) = b − a e^{iφ} (so |q| = d),

    X − Y = e^{iψ} q,     H = Y + b (X − Y) / q,

ψ the direction of Y→H: smooth in φ wherever d > 0, through φ = 0 and π too, where H lies on
the line X Y and a plain dyad for H would be singular. A four-bar driven at its coupler–rocker
hinge is the smallest case (Z = A0, X = A, H = B, Y = B0); every linkage whose driven hinge
closes such a loop compiles to a plan with this step in place of a crank.

The step has two poses, X on either side of Z→Y (pose 1 on the left, the engine's +1 dyad
sign), and a signed closure, sin of the angle at Z, which vanishes where they merge: the pose
index changes there (a limit position of the input), as a triad's does, and circuit tracing
crosses it the same way (:mod:`linkwright.engine.continuation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.state import (
    ASSEMBLY_TOL,
    SINGULAR_SIN,
    Array,
    Context,
    JointState,
    Param,
    Params,
    Positions,
    derivative,
    first,
    number,
    param_value,
    pose_slot,
    pose_states,
    word,
)
from linkwright.geometry import plane, sphere

FOLD = 1e-7
"""Least |X Y| (relative to a + b) at which H is placed. X meets Y only where |HX| = |HY| and
the angle at H is 0 (a rhombus or a kite folding): there H may be anywhere on its circle about
Y, and just beside it H's direction from Y is X − Y over |X Y|, which rounding in X's
coordinates (about ε·size) spoils by ε·size/|X Y|. Within 1e-7 of the fold that would pass
1e-9 of the size, so the step answers "no pose" there, as a crank-driven four-bar's dyad does
where A falls on B0."""

__all__ = ["Hinge", "SphereHinge", "Track", "plane_hinge_point", "sphere_hinge_point"]


def _complex(v: Array) -> Array:
    c: Array = v[..., 0] + 1j * v[..., 1]
    return c


def _vector(c: Array) -> Array:
    return np.stack((c.real, c.imag), axis=-1)


Track = tuple[Array, Array | None, Array | None]
"""A joint's position and, where asked for, its first two derivatives by the input."""


def plane_hinge_point(y: Track, x: Track, phi: Array, a: Array, b: Array) -> Track:
    """The hinge H of the triangle H X Y with |H X| = a, |H Y| = b and the angle φ at H (from
    H→Y to H→X), from X and Y, and its derivatives from theirs (φ′ = 1).

    In complex numbers, with q(φ) = b − a e^{iφ}, ``H = Y + b (X − Y) / q``: smooth wherever
    |X Y| = |q| > 0, through φ = 0 and π too, where H lies on the line X Y. Used by every step
    that drives a hinge (:class:`Hinge`, the triads of :mod:`.hinge_triad_steps`).
    """
    (yp, vy, ay), (xp, vx, ax) = y, x
    e = np.exp(1j * phi)
    q, q1, q2 = b - a * e, -1j * a * e, a * e
    w = _complex(xp - yp)
    vel_h = acc_h = None
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        h = yp + _vector(b * w / q)
        if vx is not None and vy is not None:
            w1 = _complex(vx - vy)
            vel_h = vy + _vector(b * (w1 / q - w * q1 / q**2))
            if ax is not None and ay is not None:
                w2 = _complex(ax - ay)
                acc_h = ay + _vector(
                    b * (w2 / q - 2 * w1 * q1 / q**2 - w * q2 / q**2 + 2 * w * q1**2 / q**3)
                )
    return h, vel_h, acc_h


def sphere_hinge_point(y: Track, x: Track, phi: Array, a: Array, b: Array) -> Track:
    """The spherical hinge H of the triangle H X Y (arcs |H X| = a, |H Y| = b, the angle φ at
    H from the great circle H→Y to H→X, right-handed about +O·H), from X and Y, and its
    derivatives from theirs: H sits at arc b from Y, turned by the triangle's angle β at Y
    from the great circle Y→X (:func:`_hinge_turn`)."""
    (yp, vy, ay), (xp, vx, ax) = y, x
    beta, beta1, beta2 = _hinge_turn(phi, a, b)
    vel_h = acc_h = None
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        c = sphere.dot(xp, yp)
        s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
        u = xp - c[..., None] * yp
        t = u / s[..., None]
        n = sphere.cross(yp, t)
        cb, sbt = np.cos(b)[..., None], np.sin(b)[..., None]
        cbt, sbeta = np.cos(beta)[..., None], np.sin(beta)[..., None]
        h = cb * yp + sbt * (cbt * t + sbeta * n)
        if vx is not None and vy is not None:
            c1 = sphere.dot(vx, yp) + sphere.dot(xp, vy)
            s1 = -c * c1 / s
            u1 = vx - c1[..., None] * yp - c[..., None] * vy
            t1 = u1 / s[..., None] - u * (s1 / s**2)[..., None]
            n1 = sphere.cross(vy, t) + sphere.cross(yp, t1)
            b1 = beta1[..., None]
            vel_h = cb * vy + sbt * (-sbeta * b1 * t + cbt * t1 + cbt * b1 * n + sbeta * n1)
            if ax is not None and ay is not None:
                c2 = sphere.dot(ax, yp) + 2.0 * sphere.dot(vx, vy) + sphere.dot(xp, ay)
                s2 = -(c1 * c1 + c * c2) / s - c * c * c1 * c1 / s**3
                u2 = ax - c2[..., None] * yp - 2.0 * c1[..., None] * vy - c[..., None] * ay
                t2 = (
                    u2 / s[..., None]
                    - 2.0 * u1 * (s1 / s**2)[..., None]
                    - u * (s2 / s**2)[..., None]
                    + 2.0 * u * (s1 * s1 / s**3)[..., None]
                )
                n2 = sphere.cross(ay, t) + 2.0 * sphere.cross(vy, t1) + sphere.cross(yp, t2)
                b2 = beta2[..., None]
                acc_h = cb * ay + sbt * (
                    -cbt * b1 * b1 * t
                    - sbeta * b2 * t
                    - 2.0 * sbeta * b1 * t1
                    + cbt * t2
                    - sbeta * b1 * b1 * n
                    + cbt * b2 * n
                    + 2.0 * cbt * b1 * n1
                    + sbeta * n2
                )
    return h, vel_h, acc_h


@dataclass(frozen=True)
class _HingeStep:
    """What the planar and the spherical hinge share: their fields (see :class:`Hinge`), how
    they name, draw and index their two poses, and how they hand back their joints' states."""

    hinge: str
    far: str
    z: str
    r: Param
    y: str
    a: Param
    b: Param
    phase: Param = 0.0
    pose: str = "pose"

    max_poses = 2

    @property
    def name(self) -> str:
        """The step's name, under which its pose index is kept: the hinge."""
        return self.hinge

    @property
    def joints(self) -> tuple[str, str]:
        return (self.hinge, self.far)

    @property
    def parents(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys((self.z, self.y)))

    @property
    def title(self) -> str:
        return f"driven hinge {self.hinge}"

    def links(self) -> tuple[tuple[str, str], ...]:
        """The three binary links: Z–X, X–H and H–Y."""
        return ((self.z, self.far), (self.far, self.hinge), (self.hinge, self.y))

    def plates(self) -> tuple[tuple[str, ...], ...]:
        return ()

    def _side(self, ctx: Context) -> tuple[Array, Array, NDArray[np.bool_]]:
        """X's side asked for (the dyad sign of pose 0 is −1, of pose 1 +1), the pose as
        given, and where it names a pose at all."""
        index, asked = pose_slot(ctx, self.name, self.pose, self.max_poses)
        return np.where(index == 1, 1.0, -1.0), asked, asked == index

    def _states(
        self,
        h: Array,
        x: Array,
        rates: tuple[Array | None, Array | None, Array | None, Array | None],
        valid: NDArray[np.bool_],
        regular: NDArray[np.bool_],
        closure: Array,
        asked: Array,
    ) -> dict[str, JointState]:
        """The hinge's and X's states, from their positions and (vel_h, acc_h, vel_x,
        acc_x)."""
        vel_h, acc_h, vel_x, acc_x = rates

        def both(u: Array | None, v: Array | None) -> Array | None:
            return None if u is None or v is None else np.stack((u, v), axis=-2)

        pos = np.stack((h, x), axis=-2)
        vel, acc = both(vel_h, vel_x), both(acc_h, acc_x)
        return pose_states(self.joints, pos, vel, acc, valid, regular, closure, asked)


@dataclass(frozen=True)
class Hinge(_HingeStep):
    """Joints ``hinge`` (H) and ``far`` (X) of a linkage driven at the hinge H.

    X lies at ``r`` from ``z`` and H at ``a`` from X and ``b`` from ``y``; the angle at H from
    H→Y to H→X is ``phase + θ``. The branch parameter ``pose`` is 0 or 1: X to the right or the
    left of Z→Y.

    Examples
    --------
    A four-bar driven at its coupler–rocker hinge B (A0 at the origin, B0 at (4, 0), crank 1,
    coupler 3.5, rocker 3), the angle at B 90°: A is where |A0 A| = 1 and |A B0| = √(3.5² + 3²).

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"),
    ...              Hinge("B", "A", "A0", 1.0, "B0", 3.5, 3.0)), traced=("B",))
    >>> m = evaluate(plan, {"A0": [0.0, 0.0], "B0": [4.0, 0.0]}, np.array([np.pi / 2]),
    ...              points=frozenset({"A0", "B0"}), branches={"B": 1.0})
    >>> a, b = m.positions["A"][0], m.positions["B"][0]
    >>> round(float(np.hypot(*(a - [4.0, 0.0]))), 12), round(float(np.hypot(*a)), 12)
    (4.609772228646, 1.0)
    >>> u, v = a - b, np.array([4.0, 0.0]) - b
    >>> round(float(np.degrees(np.arctan2(v[0] * u[1] - v[1] * u[0], v @ u))), 9)
    90.0

    Where the links cannot close (the angle asks X farther from Y than Z's link reaches), no
    pose exists and the step says why:

    >>> far = evaluate(plan, {"A0": [0.0, 0.0], "B0": [9.0, 0.0]}, np.array([0.0]),
    ...                points=frozenset({"A0", "B0"}), branches={"B": 1.0})
    >>> bool(far.valid[0])
    False
    """

    space = "plane"

    def place(self, ctx: Context) -> dict[str, JointState]:
        jz, jy = ctx.joint(self.z), ctx.joint(self.y)
        r, a, b = ctx.scalar(self.r), ctx.scalar(self.a), ctx.scalar(self.b)
        phi = ctx.scalar(self.phase) + ctx.theta
        d = np.abs(b - a * np.exp(1j * phi))
        sign, asked, named = self._side(ctx)
        meet = plane.circle_circle(jz.pos, r, jy.pos, d, sign, tol=ASSEMBLY_TOL)
        valid = jz.valid & jy.valid & meet.valid & named & (d > FOLD * (a + b))
        x = np.where(valid[..., None], meet.point, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            span = plane.norm(jy.pos - jz.pos)
            closure = plane.cross(jy.pos - jz.pos, x - jz.pos) / (span * r)
        regular = valid & jz.regular & jy.regular & (np.abs(closure) > SINGULAR_SIN)
        vel_x = acc_x = vy = ay = None
        if ctx.order >= 1:
            vz, vy = derivative(jz.vel), derivative(jy.vel)
            rel_z, rel_y = x - jz.pos, x - jy.pos
            dd1 = a * b * np.sin(phi)  # d·d′, from d² = a² + b² − 2ab cos φ
            vel_x, _ = plane.solve_2x2_rows(
                rel_z, rel_y, plane.dot(rel_z, vz), plane.dot(rel_y, vy) + dd1
            )
        if ctx.order >= 2:
            assert vel_x is not None and vy is not None
            az, ay = derivative(jz.acc), derivative(jy.acc)
            sz, sy = vel_x - vz, vel_x - vy
            acc_x, _ = plane.solve_2x2_rows(
                rel_z,
                rel_y,
                plane.dot(rel_z, az) - plane.dot(sz, sz),
                plane.dot(rel_y, ay) - plane.dot(sy, sy) + a * b * np.cos(phi),
            )
        h, vel_h, acc_h = plane_hinge_point((jy.pos, vy, ay), (x, vel_x, acc_x), phi, a, b)
        rates = (vel_h, acc_h, vel_x, acc_x)
        return self._states(h, x, rates, valid, regular, closure, asked)

    def closure(self, positions: Positions, params: Params) -> Array:
        """sin of the angle at Z between Z→Y and Z→X: 0 where X's two poses merge (Z, X, Y in
        line), its sign the pose's side."""
        z, y, x = positions[self.z], positions[self.y], positions[self.far]
        r = param_value(self.r, params)
        with np.errstate(divide="ignore", invalid="ignore"):
            value: Array = plane.cross(y - z, x - z) / (plane.norm(y - z) * r)
        return value

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the three links' lengths and of X against the angle at H
        (X − H = a·e^{iφ}·(Y − H)/b, a length)."""
        z, y = positions[self.z], positions[self.y]
        x, h = positions[self.far], positions[self.hinge]
        r, a, b = (param_value(p, params) for p in (self.r, self.a, self.b))
        phi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        want = _vector(a * np.exp(1j * phi) * _complex(y - h) / b)
        errors = (
            np.abs(plane.norm(x - z) - r),
            np.abs(plane.norm(x - h) - a),
            np.abs(plane.norm(y - h) - b),
            plane.norm(x - h - want),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        """Why the hinge's loop cannot close at an input."""
        h, x, z, y = self.hinge, self.far, self.z, self.y
        if positions is None or params is None:
            return (
                f"driven hinge {h}: at this angle {x} is too far from {y} (or too near) for the "
                f"link {z}{x} to reach"
            )
        span = first(plane.norm(positions[y] - positions[z]))
        r = number(self.r, params)
        return (
            f"driven hinge {h}: {x} must lie at {word(self.r)} = {r:.6g} from {z} and at the "
            f"distance the angle at {h} sets from {y}, but |{z} {y}| = {span:.6g} leaves no "
            "such point at this input"
        )

    def at_limit(self) -> str:
        """What happens at a limit position of the input."""
        return (
            f"driven hinge {self.hinge}: {self.z}, {self.far} and {self.y} fall in line, where "
            f"the two places of {self.far} merge"
        )


def _hinge_turn(phi: Array, a: Array, b: Array) -> tuple[Array, Array, Array]:
    """The angle β at Y of the spherical triangle H X Y (from Y→X to Y→H, right-handed about
    +O·Y) and its first two derivatives by φ, the angle at H; |HX| = a, |HY| = b.

    From the spherical laws of sines and cosines (sin β = sin a sin φ / sin d and
    cos a = cos b cos d + sin b sin d cos β), both multiplied by sin b sin d > 0 and reduced
    with cos d = cos a cos b + sin a sin b cos φ: β = atan2(S, C) with S = sin a sin φ and
    C = cos a sin b − sin a cos b cos φ.
    """
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    sp, cp = np.sin(phi), np.cos(phi)
    s, c = sa * sp, ca * sb - sa * cb * cp
    s1, c1 = sa * cp, sa * cb * sp
    s2, c2 = -sa * sp, sa * cb * cp
    num, den = s1 * c - s * c1, s * s + c * c
    num1, den1 = s2 * c - s * c2, 2.0 * (s * s1 + c * c1)
    with np.errstate(divide="ignore", invalid="ignore"):
        beta1 = num / den
        beta2 = (num1 * den - num * den1) / den**2
    return np.arctan2(s, c), beta1, beta2


@dataclass(frozen=True)
class SphereHinge(_HingeStep):
    """The spherical hinge: joints ``hinge`` (H) and ``far`` (X) of a spherical linkage driven
    at the hinge H, every joint an axis through the sphere's centre and every link an arc.

    X lies at arc ``r`` from ``z``, H at arc ``a`` from X and ``b`` from ``y``, and the angle at
    H from the great circle H→Y to H→X (right-handed about +O·H) is ``phase + θ``. By the
    spherical law of cosines the arc X Y is d(φ), cos d = cos a cos b + sin a sin b cos φ, so X
    is where the small circles about Z (arc r) and Y (arc d) meet, on the side ``pose`` (0 or
    1: ``sign((Z × Y)·X)`` −1 or +1), and H sits at arc b from Y, turned by the triangle's angle
    β at Y from the great circle Y→X (:func:`_hinge_turn`): smooth through φ = 0 and π.

    Examples
    --------
    A spherical four-bar driven at its coupler–rocker hinge B; every arc is kept, and so is the
    angle at B:

    >>> from linkwright.engine import Fixed, Plan, evaluate
    >>> from linkwright.geometry import sphere
    >>> plan = Plan((Fixed("A0", "A0"), Fixed("B0", "B0"),
    ...              SphereHinge("B", "A", "A0", 0.4, "B0", 0.9, 0.7)), traced=("B",))
    >>> b0 = np.array([np.cos(0.8), np.sin(0.8), 0.0])
    >>> m = evaluate(plan, {"A0": [1.0, 0.0, 0.0], "B0": b0}, np.array([1.2]),
    ...              points=frozenset({"A0", "B0"}), branches={"B": 1.0})
    >>> p = {k: v[0] for k, v in m.positions.items()}
    >>> [round(float(sphere.arc(p[i], p[j])), 12) for i, j in (("A0", "A"), ("A", "B"),
    ...                                                         ("B", "B0"))]
    [0.4, 0.9, 0.7]
    >>> round(float(sphere.angle_at(p["B"], p["B0"], p["A"])), 12)
    1.2
    """

    space = "sphere"

    def place(self, ctx: Context) -> dict[str, JointState]:
        jz, jy = ctx.joint(self.z), ctx.joint(self.y)
        r, a, b = ctx.scalar(self.r), ctx.scalar(self.a), ctx.scalar(self.b)
        phi = ctx.scalar(self.phase) + ctx.theta
        sa, sb = np.sin(a), np.sin(b)
        cos_d = np.clip(np.cos(a) * np.cos(b) + sa * sb * np.cos(phi), -1.0, 1.0)
        d = np.arccos(cos_d)
        sign, asked, named = self._side(ctx)
        z, y = jz.pos, jy.pos
        meet = sphere.small_circles(z, r, y, d, sign, tol=ASSEMBLY_TOL)
        valid = jz.valid & jy.valid & meet.valid & named & (np.sin(d) > FOLD * (a + b))
        x = np.where(valid[..., None], meet.point, np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            span = sphere.norm(sphere.cross(z, y))
            closure = sphere.dot(sphere.cross(z, y), x) / (span * np.sin(r))
        regular = valid & jz.regular & jy.regular & (np.abs(closure) > SINGULAR_SIN)
        vel_x = acc_x = vy = ay = None
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            zero = np.zeros(x.shape[:-1])
            if ctx.order >= 1:
                vz, vy = derivative(jz.vel), derivative(jy.vel)
                sin_term = sa * sb * np.sin(phi)  # −(cos d)′
                vel_x, _ = sphere.solve_3x3_rows(
                    z, y, x, -sphere.dot(x, vz), -sphere.dot(x, vy) - sin_term, zero
                )
            if ctx.order >= 2:
                assert vel_x is not None and vy is not None
                az, ay = derivative(jz.acc), derivative(jy.acc)
                acc_x, _ = sphere.solve_3x3_rows(
                    z,
                    y,
                    x,
                    -2.0 * sphere.dot(vel_x, vz) - sphere.dot(x, az),
                    -2.0 * sphere.dot(vel_x, vy) - sphere.dot(x, ay) - sa * sb * np.cos(phi),
                    -sphere.dot(vel_x, vel_x),
                )
        h, vel_h, acc_h = sphere_hinge_point((y, vy, ay), (x, vel_x, acc_x), phi, a, b)
        rates = (vel_h, acc_h, vel_x, acc_x)
        return self._states(h, x, rates, valid, regular, closure, asked)

    def closure(self, positions: Positions, params: Params) -> Array:
        """sin of the angle at Z between the great circles Z→Y and Z→X: 0 where X's two poses
        merge (X on the great circle Z Y), its sign the pose's side."""
        z, y, x = positions[self.z], positions[self.y], positions[self.far]
        r = param_value(self.r, params)
        w = sphere.cross(z, y)
        with np.errstate(divide="ignore", invalid="ignore"):
            value: Array = sphere.dot(w, x) / (sphere.norm(w) * np.sin(r))
        return value

    def residual(self, positions: Positions, params: Params, theta: ArrayLike) -> Array:
        """The largest error of the three arcs, of the angle at H (times sin a: the arc X is
        off along its circle about H) and of the joints' unit norms, in radians."""
        z, y = positions[self.z], positions[self.y]
        x, h = positions[self.far], positions[self.hinge]
        r, a, b = (param_value(p, params) for p in (self.r, self.a, self.b))
        phi = param_value(self.phase, params) + np.asarray(theta, dtype=float)
        turned = sphere.angle_at(h, y, x) - phi
        wrapped = np.remainder(turned + np.pi, 2.0 * np.pi) - np.pi
        errors = (
            np.abs(sphere.arc(z, x) - r),
            np.abs(sphere.arc(x, h) - a),
            np.abs(sphere.arc(y, h) - b),
            np.abs(wrapped) * np.sin(a),
            np.abs(sphere.norm(x) - 1.0),
            np.abs(sphere.norm(h) - 1.0),
        )
        worst: Array = np.maximum.reduce(np.broadcast_arrays(*errors))
        return worst

    def unassembled(self, positions: Positions | None = None, params: Params | None = None) -> str:
        h, x, z, y = self.hinge, self.far, self.z, self.y
        if positions is None or params is None:
            return (
                f"driven hinge {h}: at this angle {x} is too far from {y} (or too near) for the "
                f"arc {z}{x} to reach"
            )
        span = math.degrees(first(sphere.arc(positions[y], positions[z])))
        r = math.degrees(number(self.r, params))
        return (
            f"driven hinge {h}: {x} must lie at {word(self.r)} = {r:.6g}° from {z} and at the arc "
            f"the angle at {h} sets from {y}, but arc {z}{y} = {span:.6g}° leaves no such point "
            "at this input"
        )

    def at_limit(self) -> str:
        return (
            f"driven hinge {self.hinge}: {self.far} falls on the great circle {self.z}{self.y}, "
            f"where its two places merge"
        )

"""Circuits through singular geometry: change points, deltoids, parallelograms, folded poses.

Near a change point (s + l = p + q) the motion itself concentrates: a four-bar close to a deltoid
swings its rocker through half a turn while the input moves by as little as the distance by
which A misses B0. :func:`linkwright.engine.trace` with ``spacing="path"`` places the samples by
the joints' travel instead of the input's. These tests hold it, and the default
``spacing="input"``, to what issue 10 asks of a traced circuit, on random mechanisms drawn at
and around their singularities (NumPy batches, and single mechanisms from Hypothesis):

* every sample satisfies the link-length constraints, recomputed here from positions;
* limit positions are samples, bit for bit the roots ``input_range`` returns, and there the dyad
  is flat to rounding: |A − B0| is coupler ± rocker (the crank pin's distance from the guide is
  the rod; on the sphere the chord A–B0 is that of the arc coupler ± rocker);
* no branch jump: from every sample an independent continuation (the nearest root of the dyad's
  two, computed here from plain formulas, in adaptive input substeps) arrives at the next sample;
* with ``spacing="path"`` only, the step bound that :func:`~linkwright.engine.trace` states:
  every moving joint's step is at most ``2·M·L/n + 2ν`` (L its path length, M the circuit's
  normalised travel, ν = 1e-7 of the linkage's size) beyond the rounding its positions carry,
  and a path's length is within the Cauchy–Crofton bound of its curve's size.

Exact singular poses (A passing through B0 of a deltoid or rhombus, where the motion itself
jumps) are kept out of the random draws and checked by hand: the continuation fails there too,
and only there.

The continuation's substeps are chosen by geometry alone, so that they resolve concentrated
motion too: a substep is taken only if the frame of the intersection (the normal of the roots'
line) turns by less than 0.1 rad and the nearest root is at most half as far as the other, on
the side the joint is on. Where the two roots meet (within rounding: near a limit a root is only
known to about √ε of its link, and near A ≈ B0 to less), the joint keeps its side, except at a
turning point of the input (a limit position), where it leaves on the other side, as the machine
does.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine import evaluate, trace
from linkwright.mechanisms import (
    FourBar,
    GearedFiveBar,
    SliderCrank,
    SphericalFourBar,
    SphericalSixBar,
    Watt1,
    input_range,
)

TWO_PI = 2.0 * np.pi
EPS = np.finfo(float).eps
STEP_FACTOR = 2.0  # the c of trace's bound
NOISE = 1e-7  # ν / size: the rounding floor of positions near a limit (√ε of a link)
RESIDUAL_TOL = 1e-10  # constraint errors, relative to the scale
FLAT_TOL = 1e-12  # the dyad's closure at a limit sample, relative to the scale
CLOSE = 1e-6  # roots (and arrivals) this close, relative to the scale, are one point
MOVING = 1e-5  # a joint whose curve is smaller than this, relative to the scale, stands still

# ----------------------------------------------------------------------------------------------
# Random near-singular mechanisms: one recipe, drawn by NumPy (batches) or Hypothesis (single)
# ----------------------------------------------------------------------------------------------


def _direction(angle):
    return np.stack((np.cos(angle), np.sin(angle)), axis=-1)


def _change_point(x, y, z, longest):
    """A fourth length with s + l = p + q: x + d = y + z (d longest) or x + z = y + d."""
    x, y, z = np.sort(np.stack((x, y, z)), axis=0)
    return np.where(longest, y + z - x, x + z - y)


def _point(r, link, scale):
    """The coupler point: on A (u = v = 0), on B (u = link, v = 0), or anywhere near."""
    u = np.select([r["point"] == 0, r["point"] == 1], [0.0, link], r["uv"][:, 0] * scale)
    v = np.where(r["point"] < 2, 0.0, r["uv"][:, 1] * scale)
    return u, v


def build_fourbars(r):
    """Planar four-bars from a recipe: five kinds, each at or near its singularity.

    0: a change point s + l = p + q (the odd link anywhere); 1: a deltoid, frame ≈ crank and
    coupler ≈ rocker (A grazes B0); 2: the kite the other way, crank ≈ coupler and rocker ≈ frame
    (B grazes A0); 3: a parallelogram or antiparallelogram, frame ≈ coupler and crank ≈ rocker;
    4: any. ``d1``/``d2`` are relative offsets (0, or ±1e-12 .. 1e-6); a deltoid's first is
    never 0: A would pass through B0 itself, an exact singular pose (see the hand examples).
    """
    x, d1, d2 = r["x"], r["d1"], r["d2"]
    a, k, c = x[:, 0], x[:, 1], x[:, 2]
    grazing = np.where(d1 == 0.0, 1e-9, d1)
    change = np.stack((a, k, c, _change_point(a, k, c, r["longest"]) * (1 + d1)), -1)
    change = np.take_along_axis(change, r["perm"], -1)
    kinds = [
        change,
        np.stack((a, a * (1 + grazing), c, c * (1 + d2)), -1),
        np.stack((a, c * (1 + grazing), c, a * (1 + d2)), -1),
        np.stack((a, k, a * (1 + d2), k * (1 + d1)), -1),
        x,
    ]
    lengths = np.choose(r["kind"][:, None], kinds)
    scale = r["scale"]
    lengths = lengths * (scale / lengths.max(axis=1))[:, None]
    A0 = r["A0"] * scale[:, None]
    u, v = _point(r, lengths[:, 2], scale)
    return FourBar(
        A0=A0,
        B0=A0 + lengths[:, :1] * _direction(r["angle"]),
        crank=lengths[:, 1],
        coupler=lengths[:, 2],
        rocker=lengths[:, 3],
        u=u,
        v=v,
        assembly=r["assembly"],
    )


def build_slider_cranks(r):
    """Slider-cranks with the eccentricity at or near ±(rod + crank) (the input's arc shrinks to
    a point) or ±(rod − crank) (the rod stands on the guide's normal while the crank is on it)."""
    crank, rod = r["x"][:, 0], r["x"][:, 1]
    critical = np.where(r["longest"], rod + crank, np.abs(rod - crank))
    e = critical * r["sign"] + r["d1"] * (rod + crank)
    k = r["scale"] / np.maximum(crank, rod)
    d = _direction(r["angle"])
    normal = np.stack((-d[:, 1], d[:, 0]), -1)
    A0 = r["A0"] * r["scale"][:, None]
    u, v = _point(r, rod * k, r["scale"])
    return SliderCrank(
        A0=A0,
        crank=crank * k,
        rod=rod * k,
        line_point=A0 - (e * k)[:, None] * normal + (r["uv"][:, :1] * r["scale"][:, None]) * d,
        line_angle=r["angle"],
        u=u,
        v=v,
        assembly=r["assembly"],
    )


def build_sphericals(r):
    """Spherical four-bars at or near their change point: two arcs summing to the other two
    (all four joints can then lie on one great circle, test_linkage_sphere's ``change_point``),
    half of them near-deltoids (frame ≈ crank, coupler ≈ rocker: A grazes B0). Arcs 0.1 .. 1.3."""
    arcs, d1, d2 = 0.1 + 1.2 * r["x"], r["d1"], r["d2"]
    a, k, c = arcs[:, 0], arcs[:, 1], arcs[:, 2]
    change = np.stack((a, k, c, _change_point(a, k, c, r["longest"]) * (1 + d1)), -1)
    change = np.take_along_axis(change, r["perm"], -1)
    grazing = np.where(d1 == 0.0, 1e-9, d1)
    deltoid = np.stack((a, a * (1 + grazing), c, c * (1 + d2)), -1)
    arcs = np.where((r["kind"] % 2 == 0)[:, None], change, deltoid)
    point_arc = np.select([r["point"] == 0, r["point"] == 1], [0.0, arcs[:, 2]], r["x"][:, 3])
    return SphericalFourBar(
        frame=arcs[:, 0],
        crank=arcs[:, 1],
        coupler=arcs[:, 2],
        rocker=arcs[:, 3],
        point_arc=point_arc,
        point_angle=np.where(r["point"] < 2, 0.0, r["angle"]),
        assembly=r["assembly"],
    )


def through_pivot(m, tol=1e-12):
    """Whether A passes through B0 (to ``tol`` of the scale) where the dyad would close: crank =
    frame and coupler = rocker. There the dyad is undefined and its joint may go either way, an
    exact singular pose, which the random recipes avoid (a deltoid is kept 1e-12 off)."""
    if isinstance(m, SliderCrank):
        return np.zeros(np.shape(m.crank), dtype=bool)
    if isinstance(m, SphericalFourBar):
        a = [np.asarray(getattr(m, f), float) for f in ("frame", "crank", "coupler", "rocker")]
        return (np.abs(a[0] - a[1]) <= tol) & (np.abs(a[2] - a[3]) <= tol)
    s = np.asarray(m.scale)
    return (np.abs(m.frame - m.crank) <= tol * s) & (np.abs(m.coupler - m.rocker) <= tol * s)


FAMILIES = {"fourbar": build_fourbars, "slider": build_slider_cranks, "sphere": build_sphericals}


def _offsets(rng, n):
    """0 for a third, else ±10^U(−12, −6)."""
    size = 10.0 ** rng.uniform(-12.0, -6.0, n) * rng.choice([-1.0, 1.0], n)
    return np.where(rng.random(n) < 1 / 3, 0.0, size)


def random_recipes(rng, n):
    return {
        "x": np.exp(rng.uniform(np.log(0.05), 0.0, (n, 4))),
        "kind": rng.integers(0, 5, n),
        "d1": _offsets(rng, n),
        "d2": _offsets(rng, n),
        "longest": rng.random(n) < 0.5,
        "perm": rng.permuted(np.tile(np.arange(4), (n, 1)), axis=1),
        "sign": rng.choice([-1.0, 1.0], n),
        "scale": 10.0 ** rng.uniform(-3.0, 3.0, n),
        "angle": rng.uniform(-np.pi, np.pi, n),
        "A0": rng.uniform(-10.0, 10.0, (n, 2)),
        "point": rng.integers(0, 3, n),
        "uv": rng.uniform(-2.0, 2.0, (n, 2)),
        "assembly": rng.choice([-1.0, 1.0], n),
    }


_offset = st.one_of(
    st.just(0.0),
    st.builds(lambda e, s: s * 10.0**e, st.floats(-12.0, -6.0), st.sampled_from([-1.0, 1.0])),
)


@st.composite
def recipes(draw):
    """One recipe (as arrays of one) from the same space as :func:`random_recipes`."""
    unit = st.floats(0.05, 1.0)
    r = {
        "x": [[draw(unit) for _ in range(4)]],
        "kind": [draw(st.integers(0, 4))],
        "d1": [draw(_offset)],
        "d2": [draw(_offset)],
        "longest": [draw(st.booleans())],
        "perm": [draw(st.permutations(range(4)))],
        "sign": [draw(st.sampled_from([-1.0, 1.0]))],
        "scale": [10.0 ** draw(st.floats(-3.0, 3.0))],
        "angle": [draw(st.floats(-np.pi, np.pi))],
        "A0": [[draw(st.floats(-10.0, 10.0)), draw(st.floats(-10.0, 10.0))]],
        "point": [draw(st.integers(0, 2))],
        "uv": [[draw(st.floats(-2.0, 2.0)), draw(st.floats(-2.0, 2.0))]],
        "assembly": [draw(st.sampled_from([-1.0, 1.0]))],
    }
    return {k: np.asarray(v) for k, v in r.items()}


# ----------------------------------------------------------------------------------------------
# Plain formulas for each family: the dyad's two roots as mid ± half·perp at an input θ
# ----------------------------------------------------------------------------------------------


def _unit(a):
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def _batch(m, names, points=()):
    shapes = [np.shape(np.asarray(getattr(m, k))) for k in names]
    shapes += [np.shape(np.asarray(getattr(m, k)))[:-1] for k in points]
    return np.broadcast_shapes(*shapes)


def _coupler_frame(A, B, P):
    """(u, v) of P in the frame with origin A and x-axis along A→B."""
    e = _unit(B - A)
    rel = P - A
    return (rel * e).sum(-1), e[..., 0] * rel[..., 1] - e[..., 1] * rel[..., 0]


class Family:
    """What the continuation needs of a family: its dyad's roots at any input and where the
    dyad's parents meet exactly (a crossing: A through B0 of an exact kite, deltoid or rhombus,
    where the roots' frame turns over within an ulp of input)."""

    joint = "B"  # the dyad's joint, the one continued
    joints = "ABP"  # the joints whose steps are bounded
    meet = None  # per linkage: the input θ* where A passes B0 (or −B0) exactly, else NaN

    def _near(self, rows, theta):
        """The copy of θ* (by whole turns) nearest to each θ."""
        star = self.meet[rows]
        return star + TWO_PI * np.round((theta - star) / TWO_PI)

    def passes(self, rows, t0, t1):
        """Whether a step from t0 to t1 passes θ*. At θ* itself the roots' frame is the one
        of larger inputs (see :meth:`roots`), so a step passes it when it changes sides of θ*
        counting θ* as above."""
        if self.meet is None:
            return np.zeros(np.shape(t0), dtype=bool)
        x = self._near(rows, t0)
        out = np.zeros(np.shape(t0), dtype=bool)
        for y in (x - TWO_PI, x, x + TWO_PI):
            out |= (t0 < y) != (t1 < y)
        return out & np.isfinite(x)

    def _limit_frame(self, rows, theta, gap, tiny):
        """Where the parents' gap is below ``tiny`` at an exact meeting: there the frame is
        the limit of its neighbours', ±(unit of the gap's derivative), + above θ*."""
        if self.meet is None:
            return np.zeros(np.shape(theta), dtype=bool), np.ones(np.shape(theta))
        x = self._near(rows, theta)
        return np.isfinite(x) & (gap <= tiny), np.where(theta >= x, 1.0, -1.0)


class PlanarFourBar(Family):
    """Circle(A, coupler) ∩ circle(B0, rocker), with A = A0 + crank·(cos θ, sin θ)."""

    # Cauchy–Crofton: a line meets the closed paths of A, B and P at most this many times (a
    # circle arc swept there and back: 4; the coupler curve, of degree 6: 6).
    crossings = (4, 4, 6)

    def __init__(self, m):
        n = _batch(m, ("crank", "coupler", "rocker", "u", "v"), ("A0", "B0"))

        def b(a, tail=()):
            return np.broadcast_to(np.asarray(a, float), n + tail)

        self.A0, self.B0 = b(m.A0, (2,)), b(m.B0, (2,))
        self.k, self.c, self.r, self.u, self.v = (
            b(getattr(m, f)) for f in ("crank", "coupler", "rocker", "u", "v")
        )
        self.scale = b(m.scale)
        # A passes B0 where crank = |B0 − A0| (to the rounding of the pivots), at the angle of
        # B0 − A0; with coupler = rocker the dyad closes there, B anywhere on a circle.
        rel = self.B0 - self.A0
        frame = np.hypot(rel[..., 0], rel[..., 1])
        size = np.linalg.norm(self.A0, axis=-1) + np.linalg.norm(self.B0, axis=-1) + self.k
        exact = np.abs(frame - self.k) <= 2 * EPS * size
        exact &= np.abs(self.c - self.r) <= 1e-12 * (self.c + self.r)
        self.meet = np.where(exact, np.arctan2(rel[..., 1], rel[..., 0]), np.nan)

    def crank_pin(self, rows, theta):
        return self.A0[rows] + self.k[rows][..., None] * _direction(theta)

    def roots(self, rows, theta):
        """mid, half, perp (the roots are mid ± half·perp) and their rounding."""
        A = self.crank_pin(rows, theta)
        B0, c, r = self.B0[rows], self.c[rows], self.r[rows]
        delta = A - B0
        d = np.hypot(delta[..., 0], delta[..., 1])
        size = np.linalg.norm(A, axis=-1) + np.linalg.norm(B0, axis=-1) + r
        limit, sign = self._limit_frame(rows, theta, d, 1e-9 * size)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = delta / d[..., None]
            along = ((r - c) * (r + c) + d * d) / (2 * d)  # from B0 towards A
        # At an exact meeting B0 − A → 0 along the crank's direction of travel.
        u = np.where(limit[..., None], sign[..., None] * _direction(theta + np.pi / 2), u)
        along = np.where(limit, 0.5 * d, along)
        half = np.sqrt(np.maximum((r - along) * (r + along), 0.0))
        perp = np.stack((-u[..., 1], u[..., 0]), -1)
        # d carries ~ε·(|A| + |B0|), which `along` amplifies by r/d (A near B0), and the
        # half-chord by a square root near a limit. (Not at an exact meeting, where u is the
        # limit's and along = d/2.)
        with np.errstate(divide="ignore"):
            err = 16 * EPS * size * (1 + np.where(limit, 1.0, r / d))
        return B0 + along[..., None] * u, half, perp, err + np.sqrt(2 * r * err)

    def residual(self, rows, motion):
        """The largest constraint error at each sample, relative to the scale."""
        A, B, P = (motion.positions[j] for j in "ABP")
        u, v = _coupler_frame(A, B, P)
        col = [a[rows][:, None] for a in (self.k, self.c, self.r, self.u, self.v)]
        errors = [
            np.linalg.norm(A - self.A0[rows][:, None], axis=-1) - col[0],
            np.linalg.norm(B - A, axis=-1) - col[1],
            np.linalg.norm(B - self.B0[rows][:, None], axis=-1) - col[2],
            u - col[3],
            v - col[4],
        ]
        return np.max(np.abs(errors), axis=0) / self.scale[rows][:, None]

    def flatness(self, rows, A):
        """How far |A − B0| is from coupler ± rocker, relative to the scale."""
        d = np.linalg.norm(A - self.B0[rows], axis=-1)
        c, r = self.c[rows], self.r[rows]
        return np.minimum(np.abs(d - (c + r)), np.abs(d - np.abs(c - r))) / self.scale[rows]


class PlanarSlider(PlanarFourBar):
    """Circle(A, rod) ∩ the guide through line_point at line_angle."""

    crossings = (4, 4, 4)  # the slider-crank's coupler curve is a quartic
    meet = None  # a guide and a pin never meet as two pivots do

    def __init__(self, m):
        n = _batch(m, ("crank", "rod", "line_angle", "u", "v"), ("A0", "line_point"))

        def b(a, tail=()):
            return np.broadcast_to(np.asarray(a, float), n + tail)

        self.A0, self.L = b(m.A0, (2,)), b(m.line_point, (2,))
        self.k, self.c, self.u, self.v = (b(getattr(m, f)) for f in ("crank", "rod", "u", "v"))
        self.dir = _direction(b(m.line_angle))
        self.scale = b(m.scale)

    def _distance(self, rows, A):
        """The foot of A on the guide and A's signed distance from it."""
        d = np.broadcast_to(self.dir[rows], A.shape)
        rel = A - self.L[rows]
        foot = self.L[rows] + (rel * d).sum(-1)[..., None] * d
        return foot, d[..., 0] * rel[..., 1] - d[..., 1] * rel[..., 0]

    def roots(self, rows, theta):
        A = self.crank_pin(rows, theta)
        foot, dist = self._distance(rows, A)
        c = self.c[rows]
        half = np.sqrt(np.maximum((c - np.abs(dist)) * (c + np.abs(dist)), 0.0))
        size = np.linalg.norm(A, axis=-1) + np.linalg.norm(self.L[rows], axis=-1) + c
        err = 16 * EPS * size
        return foot, half, np.broadcast_to(self.dir[rows], A.shape), err + np.sqrt(2 * c * err)

    def residual(self, rows, motion):
        A, B, P = (motion.positions[j] for j in "ABP")
        u, v = _coupler_frame(A, B, P)
        _, off = self._distance(rows[:, None], B)
        col = [a[rows][:, None] for a in (self.k, self.c, self.u, self.v)]
        errors = [
            np.linalg.norm(A - self.A0[rows][:, None], axis=-1) - col[0],
            np.linalg.norm(B - A, axis=-1) - col[1],
            off,
            u - col[2],
            v - col[3],
        ]
        return np.max(np.abs(errors), axis=0) / self.scale[rows][:, None]

    def flatness(self, rows, A):
        """How far the crank pin's distance from the guide is from the rod."""
        _, dist = self._distance(rows, A)
        return np.abs(np.abs(dist) - self.c[rows]) / self.scale[rows]


class Spherical(Family):
    """On the unit sphere: B·A = cos coupler, B·B0 = cos rocker, |B| = 1."""

    crossings = None  # no Crofton bound is stated on the sphere

    def __init__(self, m):
        fields = ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle")
        n = _batch(m, fields)
        self.a1, self.a2, self.a3, self.a4, self.pa, self.pm = (
            np.broadcast_to(np.asarray(getattr(m, f), float), n) for f in fields
        )
        self._dyad(np.stack((np.cos(self.a1), np.sin(self.a1), np.zeros(n)), -1))

    @classmethod
    def dyad(cls, crank, pivot, r1, r2, joint):
        """The dyad ``joint`` on paper 000's crank pin A (arc ``crank`` from +X, turning about
        it from +Y) and the fixed ``pivot`` (unit vectors), with arcs r1 from A, r2 from it."""
        self = cls.__new__(cls)
        n = np.broadcast_shapes(np.shape(crank), np.shape(r1), np.shape(r2), np.shape(pivot)[:-1])
        self.a2, self.a3, self.a4 = (
            np.broadcast_to(np.asarray(a, float), n) for a in (crank, r1, r2)
        )
        self.joint = joint
        self._dyad(np.broadcast_to(np.asarray(pivot, float), n + (3,)))
        return self

    def _dyad(self, pivot):
        self.B0 = pivot
        self.scale = np.ones(pivot.shape[:-1])
        # A passes B0 where the crank's arc is B0's from +X, −B0 where it is π minus that, at
        # B0's angle about +X (from +Y) or half a turn on; the dyad closes there if its arcs are
        # equal (B0) or sum to π (−B0).
        star = np.arctan2(pivot[..., 2], pivot[..., 1])
        rows = np.arange(star.size).reshape(star.shape)
        near, far = self.crank_pin(rows, star), self.crank_pin(rows, star + np.pi)
        same = (np.linalg.norm(near - pivot, axis=-1) <= 4 * EPS) & (
            np.abs(self.a3 - self.a4) <= 1e-12
        )
        opposite = (np.linalg.norm(far + pivot, axis=-1) <= 4 * EPS) & (
            np.abs(self.a3 + self.a4 - np.pi) <= 1e-12
        )
        self.meet = np.where(same, star, np.where(opposite, star + np.pi, np.nan))

    def crank_pin(self, rows, theta):
        """Paper 000's A = (cos a2, sin a2 cos θ, sin a2 sin θ)."""
        a2 = self.a2[rows]
        c = np.broadcast_to(np.cos(a2), np.shape(theta))
        return np.stack((c, np.sin(a2) * np.cos(theta), np.sin(a2) * np.sin(theta)), -1)

    def roots(self, rows, theta):
        A = self.crank_pin(rows, theta)
        B0 = np.broadcast_to(self.B0[rows], A.shape)
        w = np.cross(A, B0)
        w2 = (w * w).sum(-1)
        g = (A * B0).sum(-1)
        c3, c4 = np.cos(self.a3[rows]), np.cos(self.a4[rows])
        limit, sign = self._limit_frame(rows, theta, np.sqrt(w2), 1e-9)
        with np.errstate(invalid="ignore", divide="ignore"):
            mid = ((c3 - g * c4) / w2)[..., None] * A + ((c4 - g * c3) / w2)[..., None] * B0
            perp = w / np.sqrt(w2)[..., None]
        # At an exact meeting the roots are cos r1·A ± sin r1·n, n the unit A × B0, which
        # turns with its derivative A' × B0 (A' = (0, −sin a2 sin θ, sin a2 cos θ)).
        turning = np.stack((np.zeros(np.shape(theta)), -np.sin(theta), np.cos(theta)), -1)
        n = np.cross(turning, B0)
        n = sign[..., None] * n / np.linalg.norm(n, axis=-1, keepdims=True)
        mid = np.where(limit[..., None], np.cos(self.a3[rows])[..., None] * A, mid)
        perp = np.where(limit[..., None], n, perp)
        half = np.sqrt(np.maximum(1.0 - (mid * mid).sum(-1), 0.0))
        with np.errstate(divide="ignore"):
            err = 16 * EPS / np.where(limit, 1.0, w2)  # the midpoint divides by |A × B0|²
        return mid, half, perp, err + np.sqrt(2 * err)

    def residual(self, rows, motion):
        A, B, P = (motion.positions[j] for j in "ABP")

        def cos(x, y):
            return (x * y).sum(-1)

        # P: at arc point_arc from A, turned by point_angle about +OA from the arc AB.
        tb = _unit(B - cos(A, B)[..., None] * A)
        tp = P - cos(A, P)[..., None] * A
        defined = np.linalg.norm(tp, axis=-1) > 1e-3
        with np.errstate(invalid="ignore"):  # P on A: no angle, and none checked
            tp = _unit(tp)
        turn = np.arctan2(cos(np.cross(A, tb), tp), cos(tb, tp)) - self.pm[rows][:, None]
        turn = np.where(defined, np.abs(np.remainder(turn + np.pi, TWO_PI) - np.pi), 0.0)
        col = [np.cos(a[rows])[:, None] for a in (self.a2, self.a3, self.a4, self.pa)]
        errors = [
            A[..., 0] - col[0],
            cos(A, B) - col[1],
            cos(B, self.B0[rows][:, None]) - col[2],
            cos(A, P) - col[3],
            turn,
            np.linalg.norm(B, axis=-1) - 1.0,
        ]
        return np.max(np.abs(errors), axis=0)

    def flatness(self, rows, A):
        """How far the chord A–B0 is from that of the arc coupler ± rocker."""
        chord = np.linalg.norm(A - self.B0[rows], axis=-1)
        a3, a4 = self.a3[rows], self.a4[rows]
        outer = 2 * np.sin(0.5 * (a3 + a4))
        inner = 2 * np.sin(0.5 * np.abs(a3 - a4))
        return np.minimum(np.abs(chord - outer), np.abs(chord - inner))


def formulas(m):
    if isinstance(m, FourBar):
        return PlanarFourBar(m)
    if isinstance(m, SliderCrank):
        return PlanarSlider(m)
    return Spherical(m)


# ----------------------------------------------------------------------------------------------
# Independent continuation between consecutive samples
# ----------------------------------------------------------------------------------------------

TURN = 0.1  # rad: the most the roots' line may turn in one substep
MAX_SUBSTEPS = 4000


def _side(point, mid, perp):
    return np.sign(((point - mid) * perp).sum(-1))


def continuation(fam, motion, full, period):
    """Continue the dyad's joint from every sample to the next input, nearest root by root.

    Returns, per pair of consecutive samples (cyclic), how far the continuation arrives from
    the next sample beyond the rounding the roots carry there, relative to the scale (NaN where
    a sample is unassembled or the two inputs are equal), and whether some substep could not
    be resolved down to the input's last bits (a singular pose between the two samples).
    """
    theta = motion.input
    B = motion.positions[fam.joint]
    count, n = theta.shape
    rows = np.repeat(np.arange(count), n)
    t0 = theta.ravel()
    target = np.roll(theta, -1, axis=-1)
    target[:, -1] += np.where(full, period, 0.0)
    target = target.ravel()
    start = B.reshape(count * n, -1)
    arrive = np.roll(B, -1, axis=-2).reshape(count * n, -1)
    previous = np.roll(theta, 1, axis=-1)
    previous[:, 0] -= np.where(full, period, 0.0)
    turning = (theta - previous) * (target.reshape(count, n) - theta) < 0.0
    tol = CLOSE * fam.scale[rows]
    mid, half, perp, noise = (np.array(a) for a in fam.roots(rows, t0))
    # The side of the roots' line each sample starts from. Where the two roots are apart that is
    # the sample's own; where they meet, the side of the last sample where they were apart,
    # flipped at each turning point of the input since (a limit: the joint leaves on the other
    # side, as the machine does). A circuit whose roots never part starts on +1.
    own = _side(start, mid, perp)
    apart = ((2 * half > tol + 4 * noise) & (own != 0)).reshape(count, n)
    twice = np.concatenate((apart, apart), axis=-1)
    last = np.maximum.accumulate(np.where(twice, np.arange(2 * n), -1), axis=-1)[:, n:]
    flips = np.cumsum(np.concatenate((turning, turning), axis=-1), axis=-1)
    j = np.maximum(last, 0)
    parity = flips[:, n:] - np.take_along_axis(flips, j, -1)
    own2 = np.concatenate((own.reshape(count, n),) * 2, axis=-1)
    side = np.where(last >= 0, np.take_along_axis(own2, j, -1) * (-1.0) ** parity, 1.0).ravel()
    t, cur = t0.copy(), start.copy()
    step = np.clip(0.25 * (target - t0), -0.05, 0.05)
    todo = np.isfinite(t0) & np.isfinite(target) & (t0 != target)
    todo &= np.isfinite(start).all(-1) & np.isfinite(arrive).all(-1)
    unresolved = np.zeros(t0.size, dtype=bool)
    for _ in range(MAX_SUBSTEPS):
        i = np.flatnonzero(todo)
        if not i.size:
            break
        left = target[i] - t[i]
        h = np.where(np.abs(step[i]) < np.abs(left), step[i], left)
        tn = np.where(np.abs(step[i]) < np.abs(left), t[i] + h, target[i])
        m2, h2, p2, n2 = fam.roots(rows[i], tn)
        sep0, sep1 = 2 * half[i], 2 * h2
        near_tol = tol[i] + 4 * np.maximum(noise[i], n2)
        merged = (sep0 <= near_tol) | (sep1 <= near_tol)
        shift = np.linalg.norm(m2 - mid[i], axis=-1)
        # Passing an exact meeting of the dyad's parents, the roots' frame turns over (their
        # pair stays put): the joint's side, measured in it, flips with it.
        flip = np.where(fam.passes(rows[i], t[i], tn), -1.0, 1.0)
        turn = np.linalg.norm(p2 - flip[:, None] * perp[i], axis=-1)
        expect = flip * side[i]
        near = _side(cur[i], m2, p2)
        near = np.where(near == 0, expect, near)
        d_near = np.linalg.norm(cur[i] - (m2 + (near * h2)[:, None] * p2), axis=-1)
        d_far = np.linalg.norm(cur[i] - (m2 - (near * h2)[:, None] * p2), axis=-1)
        # Apart, the nearest root must be clearly the nearer one and on the joint's side (a
        # substep over a near-crossing of the roots would otherwise pass to the other); where
        # they meet, the midpoint must move little against their separation.
        ok = np.where(
            merged,
            shift <= 0.25 * np.maximum(np.maximum(sep0, sep1), near_tol),
            (d_near <= 0.5 * d_far) & (near == expect),
        )
        ok &= turn < TURN
        tiny = np.abs(tn - t[i]) <= 4 * np.spacing(np.maximum(np.abs(t[i]), 1.0))
        take_it = ok | tiny
        unresolved[i] |= tiny & ~ok
        chosen = np.where(sep0 > near_tol, near, expect)
        j = i[take_it]
        chosen, keep = chosen[take_it], take_it
        t[j] = tn[keep]
        cur[j] = m2[keep] + (chosen * h2[keep])[:, None] * p2[keep]
        mid[j], half[j], perp[j], noise[j] = m2[keep], h2[keep], p2[keep], n2[keep]
        side[j] = np.where(sep1[keep] > near_tol[keep], chosen, expect[keep])
        step[i] = np.where(take_it, 2 * step[i], 0.5 * step[i])
        step[i] = np.clip(step[i], -0.05, 0.05)
        todo[j] &= t[j] != target[j]
    assert not todo.any(), "the continuation did not arrive"
    # How far the continuation arrives from the next sample, beyond the rounding both carry.
    gap = (np.linalg.norm(cur - arrive, axis=-1) - 4 * noise) / fam.scale[rows]
    checked = np.isfinite(t0) & np.isfinite(target) & (t0 != target)
    checked &= np.isfinite(start).all(-1) & np.isfinite(arrive).all(-1)
    gap = np.where(checked, gap, np.nan)
    return gap.reshape(count, n), unresolved.reshape(count, n)


# ----------------------------------------------------------------------------------------------
# The checks
# ----------------------------------------------------------------------------------------------


def circuit_of(m, n, spacing, start=0.0):
    return trace(m.plan, m.params(), n, points=m.points, order=0, spacing=spacing, start=start)


def check_circuit(m, n, spacing, start=0.0):
    """Everything asked of a circuit through singular geometry; returns the step ratios."""
    arcs = input_range(m)
    motion = circuit_of(m, n, spacing, start)
    fam = formulas(m)
    count = motion.input.shape[0]
    rows = np.arange(count)
    never, full = arcs.never, arcs.full
    partial = ~(never | full)
    # Assembled at every sample, limits included, and closed to rounding.
    assert not motion.valid[never].any()
    assert motion.valid[~never].all(), np.argwhere(~motion.valid & ~never[:, None])[:5]
    residual = fam.residual(rows, motion)[~never]
    assert np.all(residual <= RESIDUAL_TOL), np.max(residual)
    # The limits are samples, bit for bit, and the dyad is flat there: they are where the input
    # turns, first up from the lower limit to the upper, then down again, monotonically.
    theta = motion.input
    lo, hi = arcs.lo[:, 0], arcs.hi[:, 0]
    np.testing.assert_array_equal(theta[partial, 0], lo[partial])
    at_hi = np.argmax(theta == hi[:, None], axis=-1)
    assert np.all((theta == hi[:, None]).any(-1)[partial])
    k = np.arange(n)
    ulps = 4 * np.spacing(np.abs(theta) + 1.0)
    up = np.diff(theta, axis=-1) >= -ulps[:, 1:]
    down = np.diff(theta, axis=-1) <= ulps[:, 1:]
    rising = k[None, :-1] < at_hi[:, None]
    assert np.all(np.where(rising, up, down)[partial])
    assert np.all(up[full])
    A = motion.positions["A"]
    for index in (np.zeros(count, dtype=np.int64), at_hi):
        at = np.take_along_axis(A, index[:, None, None], 1)[:, 0]
        flat = fam.flatness(rows, at)[partial]
        assert np.all(flat <= FLAT_TOL), np.max(flat)
    # No branch jump: an independent continuation from each sample arrives at the next.
    period = circuit_period(motion, full)
    gap, unresolved = continuation(fam, motion, full, period)
    assert not unresolved.any(), np.argwhere(unresolved)[:5]
    assert not np.any(gap > CLOSE), np.nanmax(gap)
    if spacing == "path":
        return check_step_bound(fam, motion, full, never, period)
    return None


def circuit_period(motion, full):
    """How far a full circuit's input runs before it closes: one turn, or two for an exact
    deltoid, whose joint comes back after one turn on the other branch (NaN pads partial)."""
    theta = motion.input
    turns = np.ceil((theta[:, -1] - theta[:, 0]) / TWO_PI - 1e-9)
    return np.where(full, TWO_PI * np.maximum(turns, 1), np.nan)


def passes_counted(fam, motion, full, period):
    """How many times each circuit passes an exact meeting of its dyad's parents."""
    theta = motion.input
    count = theta.shape[0]
    target = np.roll(theta, -1, axis=-1)
    target[:, -1] += np.where(full, np.nan_to_num(period), 0.0)
    rows = np.repeat(np.arange(count), theta.shape[1])
    passed = fam.passes(rows, theta.ravel(), target.ravel()).reshape(theta.shape)
    return passed.sum(-1)


def check_step_bound(fam, motion, full, never, period):
    """``spacing="path"``: each moving joint's step ≤ 2·M·L/n + 2ν, with M and L measured on
    the samples themselves (shorter than on the curve, so the check is the stricter), beyond
    the rounding the two samples carry (:meth:`roots`' estimate for B, times the lever from A
    for P; A is exact). Returns the measured c = step·n/(M·L) per joint and linkage, where the
    rounding is below 1e-6 of the curve (NaN elsewhere)."""
    count, n = motion.input.shape
    pos = np.stack([motion.positions[j] for j in "ABP"])
    step = np.linalg.norm(np.roll(pos, -1, axis=-2) - pos, axis=-1)  # (joint, linkage, sample)
    length = step.sum(-1)
    box = np.linalg.norm(np.max(pos, axis=-2) - np.min(pos, axis=-2), axis=-1)
    moving = box > MOVING * fam.scale
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.where(moving[..., None], step / length[..., None], 0.0)
    travel = rel.max(axis=0).sum(-1)  # M
    # Limits and crossings each start a segment (at most: a full circuit may start on one).
    segments = np.where(full, 1, 2) + passes_counted(fam, motion, full, period)
    assert n >= 8 * segments.max()
    rows = np.repeat(np.arange(count), n)
    noise = fam.roots(rows, motion.input.ravel())[3].reshape(count, n)
    noise = noise + np.roll(noise, -1, axis=-1)
    A, B, P = pos
    lever = np.max(np.linalg.norm(P - A, axis=-1) / np.linalg.norm(B - A, axis=-1), axis=-1)
    blur = np.stack((0 * noise, noise, (1 + lever)[:, None] * noise))
    bound = STEP_FACTOR * (travel * length / n)[..., None] + 2 * (NOISE * fam.scale)[:, None]
    over = step > bound + 2 * blur
    assert not np.any((over & moving[..., None])[:, ~never]), np.max(
        np.where(moving[..., None], step / (bound + 2 * blur), 0.0)
    )
    if fam.crossings is not None:
        # Cauchy–Crofton: a path that any line meets at most k times is at most k/2 times the
        # perimeter of its hull, itself at most π times its diameter (≤ its box's diagonal).
        # (Not for paths at the rounding level, whose samples zigzag.)
        k = np.asarray(fam.crossings)[:, None]
        crofton = length <= 0.5 * k * np.pi * box * (1 + 1e-12)
        assert np.all((crofton | ~moving)[:, ~never])
    # The measured c, where the rounding is below 1e-6 of the curve.
    quiet = moving & (np.max(blur, axis=-1) < 1e-6 * box)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(quiet, step.max(-1) * n / (travel * length), np.nan)


# ----------------------------------------------------------------------------------------------
# Tests
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("spacing", ["path", "input"])
@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_near_singular_batch(family, spacing):
    rng = np.random.default_rng(20261010)
    m = FAMILIES[family](random_recipes(rng, 300))
    ratio = check_circuit(m, 120, spacing)
    if ratio is not None:  # trace's docstring: measured c ≤ 1.19 where rounding is negligible
        assert np.nanmax(ratio) <= 1.25


@settings(max_examples=60, deadline=None)
@given(
    recipe=recipes(),
    family=st.sampled_from(sorted(FAMILIES)),
    n=st.integers(16, 240),
    spacing=st.sampled_from(["path", "input"]),
)
def test_near_singular_single(recipe, family, n, spacing):
    m = FAMILIES[family](recipe)
    # Within 1e-12 of A passing through B0 the positions' rounding is of the order of the miss:
    # left out (exactly through it is a crossing, tested on its own below).
    assume(not np.any(through_pivot(m)))
    check_circuit(m, n, spacing)


@st.composite
def exact_meetings(draw):
    """A four-bar whose crank pin passes exactly through its rocker pivot, so that the dyad's
    parents meet: planar kites and deltoids (crank = |B0 − A0|, computed from the pivots as
    drawn; coupler = rocker), and spherical ones through B0 (frame = crank, coupler = rocker) or
    through −B0 (frame + crank = coupler + rocker = π). Rocking or turning fully, the coupler
    point on A, on B or anywhere, either assembly."""
    sign = draw(st.sampled_from([-1.0, 1.0]))
    point = draw(st.integers(0, 2))
    if draw(st.booleans()):
        scale = 10.0 ** draw(st.floats(-3.0, 3.0))
        A0 = np.array([draw(st.floats(-10.0, 10.0)), draw(st.floats(-10.0, 10.0))]) * scale
        B0 = A0 + draw(st.floats(0.05, 1.0)) * scale * _direction(draw(st.floats(-np.pi, np.pi)))
        crank = float(np.hypot(*(B0 - A0)))
        link = draw(st.floats(0.05, 2.0)) * scale
        u = [0.0, link, draw(st.floats(-2.0, 2.0)) * scale][point]
        v = 0.0 if point < 2 else draw(st.floats(-2.0, 2.0)) * scale
        return batch_of_one(FourBar(A0=A0, B0=B0, crank=crank, coupler=link, rocker=link, u=u,
                                    v=v, assembly=sign))  # fmt: skip
    frame, coupler = draw(st.floats(0.1, 1.4)), draw(st.floats(0.1, 1.4))
    crank, rocker = frame, coupler
    if draw(st.booleans()):
        crank, rocker = np.pi - frame, np.pi - coupler
    arc = [0.0, coupler, draw(st.floats(0.1, 1.4))][point]
    return batch_of_one(SphericalFourBar(frame=frame, crank=crank, coupler=coupler, rocker=rocker,
                                         point_arc=arc, point_angle=draw(st.floats(-3.0, 3.0)),
                                         assembly=sign))  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(m=exact_meetings(), n=st.integers(40, 240), spacing=st.sampled_from(["path", "input"]))
def test_exact_meeting_single(m, n, spacing):
    """Random four-bars exactly through the meeting of their dyad's parents: every check of a
    circuit holds through it, with no sample missing (tests/test_singular.py's issue 20.4)."""
    assert np.all(np.isfinite(formulas(m).meet))
    check_circuit(m, n, spacing)
    assert circuit_of(m, n, spacing).valid.all()


# ----------------------------------------------------------------------------------------------
# Hand examples
# ----------------------------------------------------------------------------------------------

DELTOID = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=2, rocker=2, u=0.5, v=0.3)
RHOMBUS = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=1, rocker=1, u=0.5, v=0.3)


def batch_of_one(m):
    return type(m)(**{f.name: np.asarray(getattr(m, f.name))[None] for f in fields(m)})


@pytest.mark.parametrize("start", [0.1, 0.0])
@pytest.mark.parametrize("spacing", ["path", "input"])
@pytest.mark.parametrize("m", [DELTOID, RHOMBUS], ids=["deltoid", "rhombus"])
def test_exact_deltoid_and_rhombus_run_through_the_meeting(m, spacing, start):
    """A passes through B0 at θ = 0: there the dyad's parents coincide, its sign flips along
    the motion, and the circuit runs through on the analytic branch (the continuation passes
    it too, and arrives at every next sample). Started on it (θ = 0) or beside it (0.1)."""
    check_circuit(batch_of_one(m), 96, spacing, start)


@pytest.mark.parametrize("n", [24, 25, 97])
@pytest.mark.parametrize("spacing", ["path", "input"])
def test_exact_deltoid_keeps_its_analytic_branch_for_two_turns(spacing, n):
    """The deltoid's B lies on the line from A0 at θ/2, at b(θ) = cos(θ/2) + √(4 − sin²(θ/2))
    from A0 (the kite's axis of symmetry): the branch through θ = 0, continued, comes back
    after one turn as the other one (b(θ + 2π) = cos(θ/2) − √(…), with the direction turned
    over), so the circuit takes two turns. Every sample is on that closed form, the sample at
    the meeting itself (θ = 0: (3, 0); θ = 2π: (−1, 0)) included, and none is missing."""
    m = batch_of_one(DELTOID)
    motion = circuit_of(m, n, spacing)
    assert motion.valid.all()
    theta = motion.input[0]
    assert theta[0] == 0.0 and 3.5 * np.pi < theta[-1] < 4 * np.pi
    half = 0.5 * theta
    b = (np.cos(half) + np.sqrt(4.0 - np.sin(half) ** 2))[:, None] * _direction(half)
    np.testing.assert_allclose(motion.positions["B"][0], b, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(motion.positions["B"][0, 0], [3.0, 0.0])
    on = np.flatnonzero(theta == TWO_PI)
    assert on.size == 1  # the second meeting starts a segment: it is a sample
    np.testing.assert_allclose(motion.positions["B"][0, on[0]], [-1.0, 0.0], atol=1e-15)


# The kite: crank = frame = 4, coupler = rocker = 3, the coupler point on B.
KITE = FourBar(A0=[0, 0], B0=[4, 0], crank=4, coupler=3, rocker=3, u=3, v=0)


def kite_branches(theta):
    """B of the kite in closed form: on the line from A0 at θ/2 (A0 is equidistant from A and
    B0, and so is B: the axis of symmetry), at 4 cos(θ/2) ± √(9 − 16 sin²(θ/2)) from A0."""
    half = 0.5 * theta
    root = np.sqrt(np.maximum(9.0 - 16.0 * np.sin(half) ** 2, 0.0))
    return [((4.0 * np.cos(half) + s * root)[:, None] * _direction(half)) for s in (1.0, -1.0)]


@pytest.mark.parametrize("n", [24, 25, 64, 241])
@pytest.mark.parametrize("spacing", ["path", "input"])
def test_exact_kite_runs_through_its_change_point(spacing, n):
    """Issue 20.4: the kite rocks between ±2 arcsin(3/4) and passes A = B0 at θ = 0 twice,
    where B jumped by 75 % of the curve. Now every check of a circuit holds (continuation
    across θ = 0, the step bound with ``spacing="path"``), no sample is missing, and B keeps
    one closed-form branch all the way up and the other all the way down, meeting at the
    limits; at θ = 0 itself B is (7, 0) going one way and (1, 0) the other."""
    m = batch_of_one(KITE)
    check_circuit(m, max(n, 32) if spacing == "path" else n, spacing)
    motion = circuit_of(m, n, spacing)
    assert motion.valid.all()
    theta, B = motion.input[0], motion.positions["B"][0]
    assert same_branch_each_way(theta, B, kite_branches(theta))
    zero = np.flatnonzero(theta == 0.0)
    assert zero.size == 2
    np.testing.assert_allclose(sorted(B[zero, 0]), [1.0, 7.0], atol=1e-15)
    np.testing.assert_allclose(B[zero, 1], 0.0, atol=1e-15)


def same_branch_each_way(theta, B, branches):
    """Whether B is on one branch all the way up from the lower limit and on the other all
    the way down (either way round). At the limits the two meet, where the closed form's
    square root of a rounded zero is good to ~1e-8 only."""
    up, down = branches
    gap = np.abs(B - up).max(-1), np.abs(B - down).max(-1)
    top = int(np.argmax(theta))
    k = np.arange(theta.size)
    rising, falling = (k > 0) & (k < top), k > top
    ok_a = np.all(gap[0][rising] < 1e-12) and np.all(gap[1][falling] < 1e-12)
    ok_b = np.all(gap[1][rising] < 1e-12) and np.all(gap[0][falling] < 1e-12)
    limits = np.maximum(*gap)[[0, top]]
    return (ok_a or ok_b) and bool(np.all(limits < 1e-7))


def test_curve_command_draws_the_exact_kite_without_a_jump(tmp_path, capsys):
    """`linkwright curve` on the kite with its point at B: closed, no nulls, and no step
    across the curve (it was 75 % of its size), with either spacing."""
    import json

    from linkwright.cli import main

    doc = tmp_path / "kite.toml"
    doc.write_text(
        'format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\nA0 = [0.0, 0.0]\n'
        "B0 = [4.0, 0.0]\ncrank = 4.0\ncoupler = 3.0\nrocker = 3.0\n"
        "point = { u = 3.0, v = 0.0 }\n"
    )
    for spacing in ("input", "path"):
        assert main(["curve", str(doc), "-n", "100", "--spacing", spacing, "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["closed"] and None not in out["points"]
        points = np.array(out["points"])
        size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
        largest = np.linalg.norm(np.roll(points, -1, 0) - points, axis=1).max() / size
        assert largest < 0.06, largest


def test_sample_on_the_meeting_is_the_limit_of_its_neighbours():
    """From θ = 0 the first sample is the meeting itself: B undetermined by the dyad alone,
    placed as the limit of the branch through it (3, 0), not NaN; ``evaluate`` told nothing
    of the crossing still has no position there."""
    m = batch_of_one(DELTOID)
    for spacing in ("input", "path"):
        motion = circuit_of(m, 24, spacing)
        assert motion.valid.all()
        np.testing.assert_array_equal(motion.positions["B"][0, 0], [3.0, 0.0])
    alone = evaluate(m.plan, m.params(), [0.0], points=m.points, order=0)
    assert not alone.valid.any()


def test_watt1_on_the_kite_runs_through_the_change_point():
    """Issue 20.4's Watt I on the same kite (a dyad C–D–E on the four-bar, not a one-dyad
    plan: its circuit is walked numerically) jumped by 79 %. Its four-bar's B now follows the
    kite's closed form up one branch and down the other, every joint satisfies its links,
    the continuation passes θ = 0, and the path steps keep their bound."""
    watt = Watt1(A0=[0, 0], B0=[4, 0], crank=4, coupler=3, rocker=3, u1=0.1, v1=0.6, u2=-0.1,
                 v2=0.4, link1=5.7, link2=6.5, u=1, v=0.5)  # fmt: skip
    m = batch_of_one(watt)
    for spacing, n in (("input", 24), ("input", 101), ("path", 64), ("path", 150)):
        motion = circuit_of(m, n, spacing)
        assert motion.valid.all()
        theta, pos = motion.input[0], {k: v[0] for k, v in motion.positions.items()}
        assert same_branch_each_way(theta, pos["B"], kite_branches(theta))
        # Links, by plain distances; C and E on their links by their frames.
        for a, b, length in (("A0", "A", 4), ("A", "B", 3), ("B0", "B", 3), ("C", "D", 5.7),
                             ("E", "D", 6.5)):  # fmt: skip
            gap = np.linalg.norm(pos[a] - pos[b], axis=-1) - length
            assert np.abs(gap).max() < 1e-12, (a, b)
        for point, (o, t, u, v) in (("C", ("A0", "A", 0.1, 0.6)), ("E", ("A", "B", -0.1, 0.4))):
            x, y = _coupler_frame(pos[o], pos[t], pos[point])
            assert np.abs(x - u).max() < 1e-12 and np.abs(y - v).max() < 1e-12
        gap, unresolved = continuation(PlanarFourBar(m), motion, np.array([False]), np.nan)
        assert not unresolved.any() and np.nanmax(gap) <= CLOSE
        if spacing == "path":
            check_path_steps(motion, "ABCDEP", n, segments=4)


def check_path_steps(motion, joints, n, segments):
    """The step bound of ``spacing="path"`` on one linkage whose positions carry no more than
    ordinary rounding: every moving joint's step ≤ 2·M·L/n + 2ν."""
    assert n >= 8 * segments
    pos = np.stack([motion.positions[j][0] for j in joints])
    step = np.linalg.norm(np.roll(pos, -1, axis=-2) - pos, axis=-1)
    length = step.sum(-1)
    box = np.linalg.norm(pos.max(axis=-2) - pos.min(axis=-2), axis=-1)
    moving = box > MOVING
    rel = np.where(moving[:, None], step / np.where(moving, length, 1.0)[:, None], 0.0)
    travel = rel.max(axis=0).sum()
    bound = STEP_FACTOR * travel * length / n + 2 * NOISE
    assert np.all(step.max(-1)[moving] <= bound[moving]), step.max(-1) / bound


# Spherical four-bars whose crank pin A passes through B0 (frame = crank, coupler = rocker) or
# through its antipode (frame + crank = coupler + rocker = 180°, B then anywhere on the circle
# at the coupler's arc from A): the dyad's parents coincide, or are antipodal.
SPHERE_MEETINGS = {
    "coincide-rocking": SphericalFourBar(frame=np.radians(40), crank=np.radians(40),
                                         coupler=np.radians(25), rocker=np.radians(25),
                                         point_arc=np.radians(30), point_angle=0.6),
    "coincide-full": SphericalFourBar(frame=np.radians(30), crank=np.radians(30),
                                      coupler=np.radians(70), rocker=np.radians(70),
                                      point_arc=np.radians(50), point_angle=-0.4),
    "antipodal": SphericalFourBar(frame=np.radians(110), crank=np.radians(70),
                                  coupler=np.radians(80), rocker=np.radians(100),
                                  point_arc=np.radians(80), point_angle=0.0),
}  # fmt: skip


@pytest.mark.parametrize("n", [32, 33, 120])
@pytest.mark.parametrize("spacing", ["path", "input"])
@pytest.mark.parametrize("name", sorted(SPHERE_MEETINGS))
def test_spherical_parents_meeting_is_run_through(name, spacing, n):
    """On the sphere the sign (P1 × P2)·X flips where P1 = ±P2: every check of a circuit
    holds across it, the continuation passes it, and no sample is missing."""
    m = batch_of_one(SPHERE_MEETINGS[name])
    assert np.all(np.isfinite(formulas(m).meet))  # the recipe meets exactly
    check_circuit(m, n, spacing)
    assert circuit_of(m, n, spacing).valid.all()


def sixbar_through_antipode():
    """Issue 20.4's spherical six-bar: its second dyad's arcs CE + E0E sum to 180°, and C (here
    on the crank pin A: arc AC = 0) passes through −E0 (E0 at 160° from A0 on the frame's
    great circle, the crank 20°), where E is undetermined by the dyad."""
    d = np.radians
    return SphericalSixBar(frame=d(35), crank=d(20), coupler=d(42), rocker=d(30), point_arc=0.0,
                           point_angle=0.0, link5=d(60), link6=d(120), ground_arc=d(125),
                           ground_angle=0.0, d_arc=d(30), d_angle=d(75), assembly=-1,
                           assembly2=1)  # fmt: skip


@pytest.mark.parametrize("n", [48, 49, 200])
@pytest.mark.parametrize("spacing", ["path", "input"])
def test_spherical_sixbar_runs_through_the_antipode(spacing, n):
    """It jumped by 98 % of its curve. E now follows the continuation across C = −E0 (its
    formulas: the dyad on A and E0, with arcs link5 and link6), every joint satisfies its
    arcs, no sample is missing, and the path steps keep their bound."""
    m = batch_of_one(sixbar_through_antipode())
    fam = Spherical.dyad(m.crank, m.params()["E0"], m.link5, m.link6, "E")
    assert np.isfinite(fam.meet).all()
    motion = circuit_of(m, n, spacing)
    assert motion.valid.all()
    pos = {k: v[0] for k, v in motion.positions.items()}
    for a, b, arc in (("A0", "A", m.crank), ("A", "B", m.coupler), ("B0", "B", m.rocker),
                      ("C", "E", m.link5), ("E0", "E", m.link6), ("C", "D", m.d_arc)):  # fmt: skip
        gap = (pos[a] * pos[b]).sum(-1) - np.cos(np.asarray(arc)[0])
        assert np.abs(gap).max() < 1e-12, (a, b)
    np.testing.assert_allclose(pos["C"], pos["A"], atol=1e-15)
    full = np.array([True])
    period = circuit_period(motion, full)
    gap, unresolved = continuation(fam, motion, full, period)
    assert not unresolved.any() and np.nanmax(gap) <= CLOSE
    if spacing == "path":
        segments = 1 + int(passes_counted(fam, motion, full, period)[0])
        check_path_steps(motion, "ABED", n, segments)


def test_near_deltoid_path_spacing_draws_the_swing():
    """1e-9 from the deltoid, B swings half a turn about B0 while the input moves by ~1e-9:
    with even inputs that is one chord of over half the curve's size (continuous, no jump: the
    continuation follows it), with ``spacing="path"`` steps of less than a tenth (0.07)."""
    m = batch_of_one(FourBar(A0=[0, 0], B0=[1, 0], crank=1 + 1e-9, coupler=2, rocker=2))
    ratios = {}
    for spacing in ("input", "path"):
        motion = trace(m.plan, m.params(), 48, points=m.points, order=0, spacing=spacing)
        gap, unresolved = continuation(formulas(m), motion, np.array([True]), TWO_PI)
        assert not unresolved.any() and np.all(gap <= CLOSE)
        B = motion.positions["B"][0]
        size = np.linalg.norm(B.max(axis=0) - B.min(axis=0))
        ratios[spacing] = np.linalg.norm(np.roll(B, -1, axis=0) - B, axis=-1).max() / size
    assert ratios["input"] > 0.5
    assert ratios["path"] < 0.1


def test_parallelogram_and_rocking_crank_hand_examples():
    """An exact parallelogram (through its flat poses at θ = 0 and π, where it may become an
    antiparallelogram) and the rocking long-link crank of test_engine's hand example, whose
    limits are arccos(−11/28) and 2π minus it: both exact samples, the dyad folded there."""
    para = batch_of_one(FourBar(A0=[0, 0], B0=[2, 0], crank=1, coupler=2, rocker=1, v=0.4))
    check_circuit(para, 64, "path")
    rocking = batch_of_one(FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1))
    check_circuit(rocking, 64, "path")
    motion = circuit_of(rocking, 64, "path")
    lim = np.arccos((1 + 3.5**2 - 16) / 7)
    assert abs(motion.input[0, 0] - lim) <= 1e-15
    assert np.min(np.abs(motion.input[0] - (TWO_PI - lim))) <= 1e-14


def test_path_batch_equals_one_by_one():
    rng = np.random.default_rng(20261011)
    for build in (build_fourbars, build_sphericals):
        m = build(random_recipes(rng, 12))
        whole = circuit_of(m, 40, "path")
        for i in range(12):
            one = circuit_of(take(m, i), 40, "path")
            np.testing.assert_array_equal(one.input[0], whole.input[i])
            for j, pos in one.positions.items():
                np.testing.assert_array_equal(pos[0], whole.positions[j][i])


def take(m, i):
    """The ``i``-th mechanism of a batch, as a batch of one."""
    out = {}
    for f in fields(m):
        tail = (2,) if f.name in m.points else ()
        value = np.broadcast_to(np.asarray(getattr(m, f.name), float), m.batch_shape + tail)
        out[f.name] = value[i : i + 1]
    return type(m)(**out)


def test_unknown_spacing_is_refused():
    m = DELTOID
    with pytest.raises(ValueError, match="spacing must be one of 'input', 'path', got 'arc'"):
        trace(m.plan, m.params(), 12, points=m.points, spacing="arc")


@pytest.mark.parametrize("spacing", ["path", "input"])
def test_cranks_that_always_coincide_never_assemble(spacing):
    """Two equal cranks on one pivot, geared 1:1 in phase: the dyad's pivots coincide at every
    input, so it is undefined everywhere: no input assembles it (not a full turn of NaN)."""
    m = GearedFiveBar(A0=[0, 0], B0=[0, 0], crank1=1, crank2=1, link1=1, link2=1, ratio=1)
    arcs = input_range(m)
    assert bool(arcs.never) and not bool(arcs.full)
    motion = trace(m.plan, m.params(), 8, points=m.points, order=0, spacing=spacing)
    assert not motion.valid.any()


def test_curve_command_spacing_path_keeps_steps_short(tmp_path, capsys):
    """`linkwright curve --spacing path` on the near-deltoid: even input steps draw a chord of
    over a third of the curve; along the path no step reaches a tenth of it."""
    import json

    from linkwright.cli import main

    doc = tmp_path / "near-deltoid.json"
    mechanism = {"family": "fourbar", "A0": [0, 0], "B0": [1, 0], "crank": 1 + 1e-9,
                 "coupler": 2, "rocker": 2, "point": {"u": 1, "v": 0.5}}  # fmt: skip
    doc.write_text(json.dumps({"format": "linkwright/1", "mechanism": mechanism}))
    largest = {}
    for spacing in ("input", "path"):
        assert main(["curve", str(doc), "-n", "72", "--spacing", spacing, "--json"]) == 0
        points = np.array(json.loads(capsys.readouterr().out)["points"])
        size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
        largest[spacing] = np.linalg.norm(np.roll(points, -1, 0) - points, axis=1).max() / size
    assert largest["input"] > 0.3 and largest["path"] < 0.1, largest

"""Random near-singular mechanisms and plain formulas for tests/test_singular_*.py.

Four-bars, slider-cranks and spherical four-bars are drawn at and around their singularities
(change points s + l = p + q, deltoids, parallelograms, folded poses) by one recipe, by NumPy for
batches or by Hypothesis for single mechanisms. Exact singular poses (A passing through B0 of a
deltoid or rhombus, where the motion itself jumps) are kept out of the draws; the hand examples
check them. Each family also has plain formulas here: the dyad's two roots as mid ± half·perp at
an input θ, computed without the engine, for the independent continuation of
tests/singular_checks.py.
"""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    SliderCrank,
    SphericalFourBar,
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


def direction(angle):
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
        B0=A0 + lengths[:, :1] * direction(r["angle"]),
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
    d = direction(r["angle"])
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


def coupler_frame(A, B, P):
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
        return self.A0[rows] + self.k[rows][..., None] * direction(theta)

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
        u = np.where(limit[..., None], sign[..., None] * direction(theta + np.pi / 2), u)
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
        u, v = coupler_frame(A, B, P)
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
        self.dir = direction(b(m.line_angle))
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
        u, v = coupler_frame(A, B, P)
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

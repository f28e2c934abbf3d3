"""Shared ground for the six-bar tests (tests/test_sixbar_*.py): random Watt I, Watt II,
Stephenson I and Stephenson III linkages, and the independent constraint checks they are held to.

Every check recomputes what it tests from the joint positions (link lengths, the rigid points'
places in their link frames, the branch signs as cross products) rather than trusting the
engine's bookkeeping. The random draws: four-bars of every Grashof class over a 20:1 length range
(a share within 1e-9 of the change point), the attached joints anywhere within 1.5 sizes of
their links, the second dyad's links scaled to the distance between its pivots at a random input
(a share put exactly at, or 1e-9 either side of, a limit there), scales 1e-3 .. 1e3, frames
turned at random and moved by up to 10 times their size; ``sixbars`` draws single six-bars from
the same space for Hypothesis.

Tolerances are relative to the mechanism's size: the largest distance between two joints of one
link, recomputed here (and checked against the family's ``scale``).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from linkwright.mechanisms import (
    FourBar,
    solve,
)
from linkwright.mechanisms.sixbar import (
    Stephenson1,
    Stephenson3,
    Watt1,
    Watt2,
)

EPS = np.finfo(float).eps


TWO_PI = 2.0 * np.pi


RESIDUAL_TOL = 1e-10


LIMIT_MARGIN_TOL = 1e-12


DERIVATIVE_TOL = 1e-7


EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"


SIXBARS = (Watt1, Watt2, Stephenson1, Stephenson3)


EXAMPLE_NAMES = ("watt1-example", "watt2-example", "stephenson1-example", "stephenson3-example")


# The second dyad's far pivot X: the joint E on a moving link, or the ground pivot D0.
FAR_PIVOT = {Watt1: "E", Watt2: "D0", Stephenson1: "E", Stephenson3: "D0"}


# The link frame (origin, toward) of each attached joint, from the families' docstrings.
ATTACHED = {
    Watt1: {"C": ("A0", "A"), "E": ("A", "B")},
    Watt2: {"C": ("B0", "B")},
    Stephenson1: {"C": ("A0", "A"), "E": ("B0", "B")},
    Stephenson3: {"C": ("A", "B")},
}


COORDS = {"C": ("u1", "v1"), "E": ("u2", "v2"), "P": ("u", "v")}


def _direction(angle):
    angle = np.asarray(angle, dtype=float)
    return np.stack((np.cos(angle), np.sin(angle)), axis=-1)


def _perp(a):
    return np.stack((-a[..., 1], a[..., 0]), axis=-1)


def norm(a):
    return np.hypot(a[..., 0], a[..., 1])


def cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _dot(a, b):
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def col(x):
    """A per-mechanism value as a column against the samples axis."""
    return np.asarray(x, dtype=float)[..., None]


def _pt(x):
    """A per-mechanism point against the samples axis."""
    return np.asarray(x, dtype=float)[..., None, :]


# ----------------------------------------------------------------------------------------------
# Random six-bars
# ----------------------------------------------------------------------------------------------


def _change_point_lengths(x, y, z, longest, delta):
    """A fourth length making {x, y, z, d} a change-point four-bar, then moved by ``delta``
    (as in ``engine_helpers.py``: s + l = p + q exactly before the move)."""
    x, y, z = np.sort(np.stack((x, y, z)), axis=0)
    d = np.where(longest, y + z - x, x + z - y)
    return d + delta * np.maximum(d, z)


def random_draws(rng, n, *, near=0.2, trans=10.0, lever=1.5, scales=(-3.0, 3.0)):
    """The numbers of ``n`` random six-bars (any family), as arrays: see :func:`make`."""
    lengths = np.exp(rng.uniform(np.log(0.05), 0.0, (n, 4)))  # frame, crank, coupler, rocker
    close = rng.random(n) < near
    d = _change_point_lengths(
        lengths[:, 0],
        lengths[:, 1],
        lengths[:, 2],
        rng.random(n) < 0.5,
        rng.choice([-1e-9, 0.0, 1e-9], n),
    )
    lengths[close, 3] = d[close]
    lengths[close] = rng.permuted(lengths[close], axis=1)
    return {
        "lengths": lengths,
        "scale": 10.0 ** rng.uniform(*scales, n),
        "place": rng.uniform(-trans, trans, (n, 2)),
        "frame_angle": rng.uniform(-np.pi, np.pi, n),
        "assembly": rng.choice([-1.0, 1.0], n),
        "attach": rng.uniform(-lever, lever, (n, 4)),
        "ground": rng.uniform(-2.0, 2.0, (n, 2)),
        "point": rng.uniform(-lever, lever, (n, 2)),
        "theta0": rng.uniform(-np.pi, np.pi, n),
        "f1": np.exp(rng.uniform(np.log(0.3), np.log(1.5), n)),
        "f2": np.exp(rng.uniform(np.log(0.3), np.log(1.5), n)),
        "limit": np.where(rng.random(n) < near, rng.choice([1, 2], n), 0),
        "delta": rng.choice([-1e-9, 0.0, 1e-9], n),
        "assembly2": rng.choice([-1.0, 1.0], n),
    }


def make(cls, d):
    """A batched six-bar of family ``cls`` from :func:`random_draws`' numbers.

    The four-bar's lengths are scaled so the longest is ``scale``; the attached joints' (u, v)
    and the traced point's are in units of ``scale``, a ground pivot D0 within 2 of A0. The
    dyad's links are ``f1`` and ``f2`` times the distance d0 between its pivots C and X at the
    input ``theta0`` (those pivots do not depend on the dyad), or, where ``limit`` is 1 or 2,
    link2 = d0 + link1 resp. |d0 − link1| (moved by ``delta``): d0 is then |link1 − link2| or
    link1 + link2, a limit position at theta0 (where the four-bar closes there).
    """
    lengths = d["lengths"] * (d["scale"] / d["lengths"].max(axis=-1))[..., None]
    scale = d["scale"]
    A0 = d["place"] * scale[..., None]
    fields = {
        "A0": A0,
        "B0": A0 + lengths[..., :1] * _direction(d["frame_angle"]),
        "crank": lengths[..., 1],
        "coupler": lengths[..., 2],
        "rocker": lengths[..., 3],
        "u1": d["attach"][..., 0] * scale,
        "v1": d["attach"][..., 1] * scale,
        "u": d["point"][..., 0] * scale,
        "v": d["point"][..., 1] * scale,
        "assembly": d["assembly"],
        "assembly2": d["assembly2"],
    }
    if FAR_PIVOT[cls] == "E":
        fields["u2"] = d["attach"][..., 2] * scale
        fields["v2"] = d["attach"][..., 3] * scale
    else:
        fields["D0"] = A0 + d["ground"] * scale[..., None]
    # Long equal links close at any distance: the probe is assembled wherever the four-bar is.
    probe = cls(**fields, link1=1e6 * scale, link2=1e6 * scale)
    at = solve(probe, np.asarray(d["theta0"])[..., None], order=0).positions
    d0 = norm(at[FAR_PIVOT[cls]] - at["C"])[..., 0]
    d0 = np.where(np.isfinite(d0) & (d0 > 1e-3 * scale), d0, scale)
    link1 = d["f1"] * d0
    link2 = d["f2"] * d0
    link2 = np.where(d["limit"] == 1, d0 + link1, link2)
    link2 = np.where(d["limit"] == 2, np.abs(d0 - link1), link2)
    link2 = link2 * (1.0 + d["delta"])
    link2 = np.where(link2 > 0, link2, d0)  # |d0 − link1| may be 0: any other length will do
    return cls(**fields, link1=link1, link2=link2)


def random_sixbars(cls, rng, n, **kwargs):
    return make(cls, random_draws(rng, n, **kwargs))


def take(mech, i):
    """The ``i``-th mechanism of a batch as a mechanism of its own (one mechanism: itself)."""
    return mech[i] if mech.batch_shape else mech


_unit = st.floats(0.05, 1.0)


@st.composite
def draws(draw, trans=10.0):
    """One six-bar's numbers (the space of :func:`random_draws`), as arrays of one."""
    lengths = [draw(_unit) for _ in range(4)]
    if draw(st.booleans()):
        lengths[3] = float(
            _change_point_lengths(
                *lengths[:3],
                draw(st.booleans()),
                draw(st.sampled_from([-1e-9, 0.0, 1e-9])),
            )
        )
        lengths = [lengths[k] for k in draw(st.permutations(range(4)))]
    lever = st.floats(-1.5, 1.5)
    out = {
        "lengths": [lengths],
        "scale": [10.0 ** draw(st.floats(-3.0, 3.0))],
        "place": [[draw(st.floats(-trans, trans)), draw(st.floats(-trans, trans))]],
        "frame_angle": [draw(st.floats(-np.pi, np.pi))],
        "assembly": [draw(st.sampled_from([1.0, -1.0]))],
        "attach": [[draw(lever) for _ in range(4)]],
        "ground": [[draw(st.floats(-2.0, 2.0)), draw(st.floats(-2.0, 2.0))]],
        "point": [[draw(lever), draw(lever)]],
        "theta0": [draw(st.floats(-np.pi, np.pi))],
        "f1": [draw(st.floats(0.3, 1.5))],
        "f2": [draw(st.floats(0.3, 1.5))],
        "limit": [draw(st.sampled_from([0, 0, 1, 2]))],
        "delta": [draw(st.sampled_from([-1e-9, 0.0, 1e-9]))],
        "assembly2": [draw(st.sampled_from([1.0, -1.0]))],
    }
    return {k: np.asarray(v, dtype=float if k != "limit" else int) for k, v in out.items()}


@st.composite
def sixbars(draw, trans=10.0, batched=False):
    """One six-bar of any family (a batch of one if ``batched``), and its ``theta0``."""
    cls = draw(st.sampled_from(SIXBARS))
    # Attachments exactly at a link's origin are rejected for some families (tested below);
    # the floats drawn here are almost never exactly 0, but Hypothesis likes 0.
    d = draw(draws(trans))
    d["attach"] = np.where(d["attach"] == 0.0, 0.25, d["attach"])
    m = make(cls, d)
    return (m if batched else take(m, 0)), d["theta0"]


# ----------------------------------------------------------------------------------------------
# Independent constraint checks
# ----------------------------------------------------------------------------------------------


def size_of(m):
    """The largest distance between two joints of one link, from the dimensions alone."""
    sides = [m.frame, m.crank, m.coupler, m.rocker, m.link1, m.link2]
    link = {("A0", "A"): m.crank, ("A", "B"): m.coupler, ("B0", "B"): m.rocker}
    for joint, frame in ATTACHED[type(m)].items():
        u, v = (np.asarray(getattr(m, c)) for c in COORDS[joint])
        sides += [np.hypot(u, v), np.hypot(u - link[frame], v)]
    if hasattr(m, "D0"):
        D0 = np.asarray(m.D0)
        sides += [norm(D0 - np.asarray(m.A0)), norm(D0 - np.asarray(m.B0))]
    return np.maximum.reduce(np.broadcast_arrays(*(np.asarray(s, dtype=float) for s in sides)))


def frame_place(motion, origin, toward, u, v):
    """Where (u, v) in the frame origin→toward lies: origin + u·e + v·perp(e)."""
    o, t = motion.positions[origin], motion.positions[toward]
    e = (t - o) / norm(t - o)[..., None]
    return o + col(u)[..., None] * e + col(v)[..., None] * _perp(e)


def sixbar_errors(m, motion, signs=None):
    """Every constraint error of a six-bar motion, recomputed from positions, relative to size.

    Returns ``(errors, wrong)``: ``errors`` maps each constraint to its absolute error over the
    size; ``wrong`` maps "B" and "D" to where the branch sign read off the positions,
    sign((B0 − A) × (B − A)) and sign((X − C) × (D − C)), is not the expected one (``signs``:
    a mapping of per-sample arrays, default the mechanism's own), checked where that cross
    product is not lost in rounding (it is 0 at a limit position, where both branches meet).
    """
    s = col(size_of(m))
    p = motion.positions
    X = FAR_PIVOT[type(m)]
    pivot, joint, arm = ("A0", "A", m.crank)
    if getattr(m, "input", "crank") == "output":
        pivot, joint, arm = ("D0", "D", m.link2)
    errors = {
        "A0": norm(p["A0"] - _pt(m.A0)),
        "B0": norm(p["B0"] - _pt(m.B0)),
        "crank": np.abs(norm(p["A"] - p["A0"]) - col(m.crank)),
        "coupler": np.abs(norm(p["B"] - p["A"]) - col(m.coupler)),
        "rocker": np.abs(norm(p["B"] - p["B0"]) - col(m.rocker)),
        "link1": np.abs(norm(p["D"] - p["C"]) - col(m.link1)),
        "link2": np.abs(norm(p["D"] - p[X]) - col(m.link2)),
        "input": norm(p[joint] - (p[pivot] + col(arm)[..., None] * _direction(motion.input))),
        "P": norm(p["P"] - frame_place(motion, "C", "D", m.u, m.v)),
    }
    if X == "D0":
        errors["D0"] = norm(p["D0"] - _pt(m.D0))
    for name, (origin, toward) in ATTACHED[type(m)].items():
        u, v = (getattr(m, c) for c in COORDS[name])
        errors[name] = norm(p[name] - frame_place(motion, origin, toward, u, v))
    if signs is None:
        signs = {"B": col(m.assembly), "D": col(m.assembly2)}
    wrong = {}
    for dyad, (p1, p2) in {"B": ("A", "B0"), "D": ("C", X)}.items():
        side = cross(p[p2] - p[p1], p[dyad] - p[p1])
        noise = 64 * EPS * (norm(p[p1]) + norm(p[p2]) + s) * s
        wrong[dyad] = (np.abs(side) > noise) & (np.sign(side) != signs[dyad])
    return {k: e / s for k, e in errors.items()}, wrong


def assert_closes(m, motion, signs=None, tol=RESIDUAL_TOL):
    """Every valid sample satisfies every constraint: the family's residuals and ours."""
    valid = motion.valid
    for name, r in m.residuals(motion).items():
        assert np.all(np.abs(r[valid]) <= tol), (name, np.max(np.abs(r[valid])))
        assert np.all(np.isnan(r[~valid])), name
    errors, wrong = sixbar_errors(m, motion, signs)
    for name, e in errors.items():
        assert np.all(e[valid] <= tol), (name, np.max(e[valid]))
    for dyad, w in wrong.items():
        assert not np.any(w & valid), (dyad, np.argwhere(w & valid)[:5])


def check_masks(motion):
    """NaN exactly where not valid (positions) and not regular (derivatives)."""
    valid, regular = motion.valid, motion.regular
    assert not np.any(regular & ~valid)
    for pos in motion.positions.values():
        np.testing.assert_array_equal(np.isnan(pos), np.broadcast_to(~valid[..., None], pos.shape))
    for derivatives in (motion.velocities, motion.accelerations):
        for d in (derivatives or {}).values():
            np.testing.assert_array_equal(
                np.isnan(d), np.broadcast_to(~regular[..., None], d.shape)
            )


# ----------------------------------------------------------------------------------------------
# The bundled examples, read as the families read them
# ----------------------------------------------------------------------------------------------

_DOC_CLASSES = {cls.family: cls for cls in SIXBARS} | {"fourbar": FourBar}


def example_fields(name):
    """A bundled document's mechanism table as constructor fields (the document schema:
    C → u1, v1; E → u2, v2; point → u, v), read with tomllib, independent of the io layer."""
    table = dict(tomllib.loads((EXAMPLES / f"{name}.toml").read_text())["mechanism"])
    table.pop("family")
    for key, (u, v) in (("C", ("u1", "v1")), ("E", ("u2", "v2")), ("point", ("u", "v"))):
        if key in table:
            uv = table.pop(key)
            table[u], table[v] = uv.get("u", 0.0), uv.get("v", 0.0)
    return table


def example(name):
    text = (EXAMPLES / f"{name}.toml").read_text()
    family = tomllib.loads(text)["mechanism"]["family"]
    return _DOC_CLASSES[family](**example_fields(name))

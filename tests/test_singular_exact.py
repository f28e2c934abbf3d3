"""Exact singular poses, checked by hand: deltoids, rhombi, kites, parallelograms, and spherical
linkages whose dyad's parents meet or are antipodal.

There the motion itself may jump (A passing through B0 of a deltoid or rhombus): the independent
continuation of tests/singular_checks.py fails there too, and only there.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from singular_checks import check_circuit, circuit_of, circuit_period, continuation, passes_counted
from singular_helpers import (
    CLOSE,
    MOVING,
    NOISE,
    STEP_FACTOR,
    TWO_PI,
    PlanarFourBar,
    Spherical,
    coupler_frame,
    direction,
    formulas,
)

from linkwright.engine import evaluate, trace
from linkwright.mechanisms import (
    FourBar,
    SphericalFourBar,
    SphericalSixBar,
    Watt1,
)


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
        B0 = A0 + draw(st.floats(0.05, 1.0)) * scale * direction(draw(st.floats(-np.pi, np.pi)))
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
    circuit holds through it, with no sample missing (the singular tests' issue 20.4)."""
    assert np.all(np.isfinite(formulas(m).meet))
    check_circuit(m, n, spacing)
    assert circuit_of(m, n, spacing).valid.all()


# ----------------------------------------------------------------------------------------------
# Hand examples
# ----------------------------------------------------------------------------------------------

DELTOID = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=2, rocker=2, u=0.5, v=0.3)


RHOMBUS = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=1, rocker=1, u=0.5, v=0.3)


def batch_of_one(m):
    # start says where it runs, one value for a batch: not a per-linkage array.
    numbers = (f.name for f in fields(m) if f.name != "start")
    return type(m)(**{name: np.asarray(getattr(m, name))[None] for name in numbers})


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
    b = (np.cos(half) + np.sqrt(4.0 - np.sin(half) ** 2))[:, None] * direction(half)
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
    return [((4.0 * np.cos(half) + s * root)[:, None] * direction(half)) for s in (1.0, -1.0)]


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
            x, y = coupler_frame(pos[o], pos[t], pos[point])
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


def test_unknown_spacing_is_refused():
    m = DELTOID
    with pytest.raises(ValueError, match="spacing must be one of 'input', 'path', got 'arc'"):
        trace(m.plan, m.params(), 12, points=m.points, spacing="arc")

"""Six-bar limits and circuits: limits are roots of the assembly condition, circuits close.

Each circuit is checked against an independent resolution of the input's assembled arcs on a
fine grid, and every sample against the constraint residuals (tests/sixbar_helpers.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from sixbar_helpers import (
    EXAMPLE_NAMES,
    FAR_PIVOT,
    LIMIT_MARGIN_TOL,
    SIXBARS,
    TWO_PI,
    assert_closes,
    col,
    example,
    norm,
    random_sixbars,
    sixbars,
    size_of,
    take,
)

from linkwright.engine import evaluate
from linkwright.mechanisms import (
    circuit,
    input_range,
    solve,
)
from linkwright.mechanisms.sixbar import (
    Watt1,
)

# ----------------------------------------------------------------------------------------------
# 4. Limits and circuits
# ----------------------------------------------------------------------------------------------


def limit_tolerance(m, motion, dyad, branches=None):
    """|margin| allowed where a dyad is at its limit: 1e-12 plus the margin's own rounding.

    A limit is found by bisection as the last input, to the bit, where the dyad still closes
    (margin ≥ 0, the next float down or up giving margin < 0), so its margin is at most what the
    margin changes over an ulp or two of the input. That change is measured here, over ±4 ulps
    (on ``branches``, default the mechanism's own): it is ~1e-16 for a well-conditioned dyad,
    and larger where the dyad's pivots carry amplified rounding (its parents near their own
    limit, a small linkage far from the origin).
    """
    theta = motion.input[..., None] + ULPS * np.spacing(np.abs(motion.input))[..., None]
    flat = theta.reshape(*motion.input.shape[:-1], -1)
    if branches is not None:
        branches = {k: np.repeat(v, len(ULPS), axis=-1) for k, v in branches.items()}
    around = _solve_on(m, flat, branches).margins[dyad].reshape(theta.shape)
    change = np.abs(around - motion.margins[dyad][..., None])
    return LIMIT_MARGIN_TOL + np.nan_to_num(np.nanmax(change, axis=-1, initial=0.0))


ULPS = np.array([-4, -3, -2, -1, 1, 2, 3, 4])


def test_limits_are_roots():
    """Every limit that ``input_range`` finds is assembled, with the named dyad's margin ~0."""
    rng = np.random.default_rng(20250401)
    for cls in SIXBARS:
        m = random_sixbars(cls, rng, 300, near=0.0)
        arcs = input_range(m)
        theta = np.concatenate((arcs.lo, arcs.hi), axis=-1)
        index = np.concatenate((arcs.dyad_lo, arcs.dyad_hi), axis=-1)
        finite = np.isfinite(theta)
        assert finite.any(axis=-1).mean() > 0.3
        motion = solve(m, np.nan_to_num(theta), order=0)
        assert motion.valid[finite].all()
        assert_closes(m, motion)
        for i, dyad in enumerate(("B", "D")):
            at = finite & (index == i)
            tol = limit_tolerance(m, motion, dyad)
            margin = np.abs(motion.margins[dyad])
            assert np.all(margin[at] <= tol[at]), (cls.family, dyad, np.max(margin[at] / tol[at]))


def _wrapped(x):
    return (x + np.pi) % TWO_PI - np.pi


GRID = np.linspace(-np.pi, np.pi, 2048, endpoint=False)


# Runs of the assembly predicate shorter than this many GRID cells count as unresolved: 6 cells
# are 0.018 rad, four cells of the engine's 1440-node scan.
MIN_RUN = 6


def resolved(m):
    """Linkages without features finer than a grid scan can promise to see.

    On either branch of the four-bar (the second dyad's closing does not depend on its own
    branch), sampled on ``GRID``, with each node in one of three states (four-bar open; four-bar
    closed, dyad D open; all closed):

    * every run of a state is at least ``MIN_RUN`` cells long: no narrow arc or gap, and no
      limit of D within a few cells of a limit of the four-bar (where the circuit turns at both
      at once, and a scan starting at one steps over the other);
    * no dyad's margin has a local minimum below ``TANGENCY`` inside an arc: a near-tangency (or
      a four-bar near its change point), where the margin can dip below zero between two nodes,
      a gap far narrower than any grid;
    * the two dyads' margins are never both below ``TANGENCY`` at one node (two limits close
      together, again);
    * a dyad's pivots never come within ``APART`` of the size of each other: where they meet (a
      rhombus's crank passing over B0) its branch, a side of the line through them, changes
      meaning, and the joint jumps sides on a fixed branch.
    """
    ok = np.ones(m.batch_shape, dtype=bool)
    shape = m.batch_shape + (1,)
    size = col(size_of(m))
    for sign in (1.0, -1.0):
        motion = _solve_on(m, GRID, {"B": np.full(shape, sign)})
        p = motion.positions
        margin_b, margin_d = motion.margins["B"], motion.margins["D"]
        four = margin_b >= 0
        state = four.astype(int) + motion.valid
        change = state != np.roll(state, 1, axis=-1)
        for k in range(1, MIN_RUN):
            ok &= ~np.any(change & np.roll(change, -k, axis=-1), axis=-1)
        valid = motion.valid
        inside = valid & np.roll(valid, 1, axis=-1) & np.roll(valid, -1, axis=-1)
        for margin in (margin_b, margin_d):
            low = (margin <= np.roll(margin, 1, axis=-1)) & (margin <= np.roll(margin, -1, axis=-1))
            ok &= ~np.any(inside & low & (margin < TANGENCY), axis=-1)
        ok &= ~np.any(four & (margin_b < TANGENCY) & (np.abs(margin_d) < TANGENCY), axis=-1)
        for p1, p2 in (("A", "B0"), ("C", FAR_PIVOT[type(m)])):
            # (Positions are NaN, and not counted, where the chain is open: no circuit goes there.)
            near = norm(p[p2] - p[p1]) < APART * size
            ok &= ~np.any(near, axis=-1)
    return ok


TANGENCY = 0.05


APART = 0.02


def check_circuit(m, n):
    """The properties of a traced circuit, from the motion and independent re-solves.

    * Every sample closes, with the branch signs the motion reports (read off the positions).
    * A dyad changes branch only at its limit, and the input reverses only at some dyad's
      limit: there its margin is ~0 (:func:`limit_tolerance`), i.e. the limit is a sample.
    * Between consecutive samples, the last to the first included (the curve is closed), the
      linkage stays assembled (the mid-input re-solved on either sample's branches closes) and
      no joint moves farther than its velocity allows: |Δx| ≤ 2(|x'|·|Δθ| + |x''|·Δθ²), the
      larger rates of the two samples, wherever both are regular and away from limits.
    * Input steps are even within a factor: none above 16 times the mean.
    * It starts on the mechanism's own branches; where those assemble over the whole turn with
      room to spare (margins above 1e-3 on a fine grid) it is exactly one turn on them.
    * A linkage that assembles has a circuit. Without one, every joint is NaN.

    All of this is asserted where the linkage is :func:`resolved`: like the engine's own limits,
    a tracer that scans a grid cannot promise to see an arc or a gap narrower than its cells.
    Elsewhere only what is traced must close. Returns the motion, which linkages have a circuit,
    and which of those are resolved.
    """
    motion = circuit(m, n, order=2)
    grid = solve(m, GRID, order=0)
    assembles = grid.valid.any(-1)
    has = motion.valid.any(-1)
    res = resolved(m)
    for pos in motion.positions.values():
        assert np.all(np.isnan(pos[~has]))
    loose = has & ~res
    if loose.any():
        mo = _select(motion, loose)
        assert_closes(take(m, loose), mo, {"B": mo.branches["B"], "D": mo.branches["D"]})
    missed = assembles & ~has & res
    assert not np.any(missed), ("a linkage that assembles has a circuit", np.flatnonzero(missed))
    sel = has & res
    assert np.all(motion.valid[sel]), "a circuit is assembled at every sample"
    if not sel.any():
        return motion, has, sel
    mech = take(m, sel)
    mo = _select(motion, sel)
    branches = mo.branches
    assert_closes(mech, mo, {"B": branches["B"], "D": branches["D"]})
    np.testing.assert_array_equal(branches["B"][:, 0], np.asarray(mech.assembly))
    np.testing.assert_array_equal(branches["D"][:, 0], np.asarray(mech.assembly2))
    tol = {k: limit_tolerance(mech, mo, k, branches) for k in ("B", "D")}
    margin = {k: np.abs(mo.margins[k]) for k in ("B", "D")}

    def nxt(a):
        return np.roll(a, -1, axis=1)

    # Branch changes and reversals at limits only.
    for k in ("B", "D"):
        flip = branches[k] != nxt(branches[k])
        at_limit = (margin[k] <= tol[k]) | (nxt(margin[k]) <= nxt(tol[k]))
        assert np.all(at_limit[flip]), (k, np.argwhere(flip & ~at_limit)[:5])
    step = _wrapped(nxt(mo.input) - mo.input)
    reverse = step * np.roll(step, 1, axis=1) < 0  # the input turns back at sample k
    some_limit = (margin["B"] <= tol["B"]) | (margin["D"] <= tol["D"])
    assert np.all(some_limit[reverse]), np.argwhere(reverse & ~some_limit)[:5]
    # Even steps in the input, within a factor.
    travel = np.abs(step).sum(-1, keepdims=True)
    assert np.all(np.abs(step) <= 16 * travel / n)
    # Continuity: the linkage stays assembled between samples ...
    # A step of more than half a turn (few samples, a long circuit) is read modulo 2π the
    # short way round, which may be the wrong way: past a quarter turn, either way counts.
    mid = mo.input + 0.5 * step
    other = np.where(np.abs(step) > np.pi / 2, mid - np.copysign(np.pi, step), mid)
    ok = np.zeros(mid.shape, dtype=bool)
    for b in (branches, {k: nxt(v) for k, v in branches.items()}):
        ok |= _solve_on(mech, mid, b).valid | _solve_on(mech, other, b).valid
    assert np.all(ok), np.argwhere(~ok)[:5]
    # ... and its joints move no farther than their rates allow, where a step is short enough
    # for the rates to tell (every joint moving less than a tenth of the size by them).
    size = col(size_of(mech))
    smooth = mo.regular & nxt(mo.regular)
    for k in ("B", "D"):
        smooth &= (margin[k] > 1e-4) & (nxt(margin[k]) > 1e-4)
    rates = {j: np.fmax(norm(mo.velocities[j]), norm(nxt(mo.velocities[j]))) for j in mo.velocities}
    for rate in rates.values():
        smooth &= ~(rate * np.abs(step) > 0.1 * size)  # NaN rates are masked by `regular`
    for joint in mech.reported_joints:
        x, a = mo.positions[joint], mo.accelerations[joint]
        moved = norm(nxt(x) - x)
        curve = np.fmax(norm(a), norm(nxt(a)))
        bound = 2 * (rates[joint] * np.abs(step) + curve * step**2) + 1e-12 * size
        assert np.all(moved[smooth] <= bound[smooth]), (joint, np.max((moved / bound)[smooth]))
    # Full turns: one turn on the mechanism's own branches.
    full = grid.valid.all(-1) & (np.minimum(grid.margins["B"], grid.margins["D"]).min(-1) > 1e-3)
    full = full[sel]
    for k, own in (("B", mech.assembly), ("D", mech.assembly2)):
        assert np.all(branches[k][full] == col(own)[full])
    np.testing.assert_allclose(step[full].sum(-1), TWO_PI, rtol=1e-12)
    assert np.all(step[full] > 0)
    return motion, has, sel


def _select(motion, sel):
    def pick(d):
        return None if d is None else {k: v[sel] for k, v in d.items()}

    return type(motion)(
        input=motion.input[sel],
        positions=pick(motion.positions),
        velocities=pick(motion.velocities),
        accelerations=pick(motion.accelerations),
        valid=motion.valid[sel],
        regular=motion.regular[sel],
        branches=pick(motion.branches),
        margins=pick(motion.margins),
    )


def _solve_on(m, theta, branches=None):
    """Solve on per-sample branches (joint → signs), or on the mechanism's own."""
    return evaluate(m.plan, m.params(), theta, points=m.point_fields, branches=branches, order=0)


@pytest.mark.parametrize("cls", SIXBARS, ids=lambda c: c.family)
def test_batch_circuits_are_closed(cls):
    rng = np.random.default_rng(20250501 + SIXBARS.index(cls))
    m = random_sixbars(cls, rng, 200, near=0.0)
    _, has, checked = check_circuit(m, 240)
    assert has.mean() > 0.3 and checked.sum() > 0.4 * has.sum()


# Most random six-bars never assemble or are unresolved (checked in the batches above), so the
# assumption below rejects many draws by design.
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
# At least 24 samples: a six-bar's circuit may travel several turns of the input and pass six
# limits, and with fewer samples one step can exceed three quarters of a turn, which the
# continuity check (reading steps modulo 2π) cannot tell from a short step the other way.
@given(drawn=sixbars(batched=True), n=st.integers(24, 300))
def test_single_circuit_is_closed(drawn, n):
    m, _ = drawn
    # Resolved linkages that assemble: see check_circuit for why, and the next test for those
    # that never do. The unresolved ones are checked in the batches above.
    assume(solve(m, GRID, order=0).valid.any() and resolved(m).all())
    _, _, checked = check_circuit(m, n)
    assert checked.all()


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_example_circuits_are_one_even_turn(name):
    """A well-conditioned full-turn six-bar: one turn, and no step far above the mean."""
    m = example(name)
    motion, _, checked = check_circuit(m, 360)
    assert checked.all()
    for joint in ("D", "P"):
        pos = motion.positions[joint]
        steps = norm(np.roll(pos, -1, axis=-2) - pos)
        assert steps.max() <= 3 * steps.mean(), (joint, steps.max() / steps.mean())


def test_walk_over_a_limit_gap_narrower_than_a_scan_cell():
    """Its arc is 0.025 rad wide, beside a gap finer than the 1440-cell scan: the first walk
    wanders into the next arc and never closes; the finer re-walk traces the arc itself."""
    m = Watt1(
        A0=[-0.010139017633568021, -0.07165371904324314],
        B0=[-0.013892849374577007, -0.06931799195668258],
        crank=0.00619866055722641,
        coupler=0.0007264799321700232,
        rocker=0.007744982727585279,
        u1=-0.006644873058510256,
        v1=-0.00035382378663062453,
        u2=-0.007896687041997466,
        v2=-0.007936789253604503,
        link1=0.0029827940942821485,
        link2=0.004762188633303131,
        assembly=-1,
        assembly2=-1,
    )
    motion = circuit(m, 64)
    arcs = input_range(m)
    assert motion.valid.all()
    assert motion.input.min() == pytest.approx(arcs.lo[0], abs=1e-12)
    assert motion.input.max() == pytest.approx(arcs.hi[0], abs=1e-12)
    for name, r in m.residuals(motion).items():
        assert np.nanmax(np.abs(r)) < 1e-10, name

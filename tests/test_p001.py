"""Paper 001's reproduction: the written files, and each number against an independent check.

The configuration table is rebuilt from its own angles by hand (paper 001's eq. 5 for B and C,
F from θ6 about OG, E from θ5 about OF) and must close every constraint; the counts are compared
with the sweep (for input FG) and with a closed-form count of circle intersections (input AB);
the misprint checks are compared with closed forms of what a misprint does; the claims about
eq. 20 and the mirror coupler are tested on random mechanisms as well.
"""

from __future__ import annotations

import csv
from dataclasses import replace

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine.sphere_triad import sphere_triad_sweep
from linkwright.io import load_example
from linkwright.mechanisms import SphericalStephenson3, configurations, solve_all
from linkwright.papers import p001, p001_circuits
from linkwright.papers.p001_angles import triad_of

DEG = p001.EXAMPLE
TOL = 1e-12


def _p(arcs_deg=None):
    d = DEG if arcs_deg is None else arcs_deg
    return {k: np.radians(v) for k, v in d.items()}


def _fixed(p):
    far = p["a1"] + p["a9"]
    return (
        np.array([0.0, 0.0, 1.0]),
        np.array([0.0, np.sin(p["a1"]), np.cos(p["a1"])]),
        np.array([0.0, np.sin(far), np.cos(far)]),
    )


def _pose_from_angles(p, t1, t4, t5, t6):
    """B, C (eq. 5), F (θ6 about OG from the meridian beyond G), E (θ5 about OF from F→G)."""
    s1, c1 = np.sin(p["a1"]), np.cos(p["a1"])
    s4, c4 = np.sin(p["a4"]), np.cos(p["a4"])
    b = np.array([np.sin(p["a2"]) * np.sin(t1), np.sin(p["a2"]) * np.cos(t1), np.cos(p["a2"])])
    c = np.array([s4 * np.sin(t4), s1 * c4 + c1 * s4 * np.cos(t4), c1 * c4 - s1 * s4 * np.cos(t4)])
    _, _, g = _fixed(p)
    far = p["a1"] + p["a9"]
    t = np.array([0.0, np.cos(far), -np.sin(far)])
    f = np.cos(p["a8"]) * g + np.sin(p["a8"]) * (np.cos(t6) * t + np.sin(t6) * np.cross(g, t))
    tf = (g - (g @ f) * f) / np.linalg.norm(g - (g @ f) * f)
    e = np.cos(p["a7"]) * f + np.sin(p["a7"]) * (np.cos(t5) * tf + np.sin(t5) * np.cross(f, tf))
    return b, c, e, f


def _violation(p, b, c, e, f):
    """Largest constraint violation (dot forms; E by its three conditions on the coupler)."""
    a, d, g = _fixed(p)
    rows = np.stack((c, b, np.cross(c, b)))
    rhs = [
        np.cos(p["a6"]),
        np.cos(p["a3"]) * np.cos(p["a6"]) - np.sin(p["a3"]) * np.sin(p["a6"]) * np.cos(p["sigma"]),
        np.sin(p["a3"]) * np.sin(p["a6"]) * np.sin(p["sigma"]),
    ]
    e_law = np.linalg.solve(rows, rhs)
    return max(
        abs(b @ a - np.cos(p["a2"])),
        abs(b @ c - np.cos(p["a3"])),
        abs(c @ d - np.cos(p["a4"])),
        abs(e @ f - np.cos(p["a7"])),
        abs(f @ g - np.cos(p["a8"])),
        np.abs(e - e_law).max(),
    )


def test_reproduce_writes_the_page_tables_and_figures(tmp_path):
    written = p001.reproduce(tmp_path)
    names = {path.name for path in written}
    assert names == {
        "paper001.md",
        "paper001-counts.csv",
        "paper001-configurations.csv",
        "paper001-counts.png",
        "paper001-counts.svg",
        "paper001-configurations.png",
        "paper001-configurations.svg",
        "paper001-circuits.csv",
        "paper001-circuits.png",
        "paper001-circuits.svg",
    }
    for path in written:
        assert path.exists() and path.stat().st_size > 300
    assert (tmp_path / "paper001-counts.png").read_bytes()[:4] == b"\x89PNG"
    assert "<svg" in (tmp_path / "paper001-configurations.svg").read_text(encoding="utf-8")
    page = (tmp_path / "paper001.md").read_text(encoding="utf-8")
    assert "| 115 | 105 | 110 | 90 | 80 | 70 | 65 | 85 | 25 |" in page
    assert "## The eight configurations at θ6 = 280°" in page
    assert "NO |" not in page  # every misprint confirmed
    assert "nan" not in page.lower()

    with (tmp_path / "paper001-counts.csv").open(encoding="utf-8") as handle:
        counts = list(csv.DictReader(handle))
    assert len(counts) == 360
    fg = np.array([int(r["fg_count"]) for r in counts])
    ab = np.array([int(r["ab_count"]) for r in counts])
    either = np.array([int(r["ab_either_count"]) for r in counts])
    assert fg.max() == 8 and ab.max() == 4 and either.max() == 8
    assert np.all(either >= ab)
    for r in counts:
        for key in ("ab_max_residual", "fg_max_residual"):
            assert r[key] == "" or float(r[key]) < TOL

    # The FG counts against the sweep, an independent method, every 10°.
    m = SphericalStephenson3(**_p(), input="FG")
    theta = np.radians(np.arange(0.0, 360.0, 10.0))
    swept = sphere_triad_sweep(*triad_of(m, theta), grid=2048)
    assert np.array_equal(swept.count, fg[::10])

    with (tmp_path / "paper001-configurations.csv").open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 8

    # Issue 21's example at FG: its counts, and one row per limit position of its circuits.
    assert "## Driven at FG: the configurations followed over the input" in page
    assert "It has 8, 4 and 6 configurations at θ6 = -90°, 0° and 120°." in page
    with (tmp_path / "paper001-circuits.csv").open(encoding="utf-8") as handle:
        joins = list(csv.DictReader(handle))
    assert len(joins) == 10
    for r in joins:
        assert abs(int(r["configurations_below"]) - int(r["configurations_above"])) == 2
        assert f"| {r['limit']} | {float(r['theta6_deg']):.4f} | " in page


def test_the_configuration_table_is_eight_real_configurations():
    p = _p()
    rows = p001.configuration_table()
    assert len(rows) == 8
    _, d, g = _fixed(p)
    poses = []
    for r in rows:
        angles = np.radians([r["theta1"], r["theta4"], r["theta5"], r["theta6"]])
        b, c, e, f = _pose_from_angles(p, *angles)
        assert _violation(p, b, c, e, f) < 1e-11  # angles printed to full precision
        assert abs(r["theta6"] - (p001.EXAMPLE_INPUT - 360.0)) < 1e-9
        assert r["assembly"] == np.sign(np.cross(b, d) @ c)
        assert r["assembly2"] == np.sign(np.cross(e, g) @ f)
        assert r["residual"] < TOL and r["plan_gap"] < 1e-9
        poses.append(np.concatenate((b, c, e)))
    poses = np.array(poses)
    gap = np.abs(poses[:, None] - poses[None]).max(-1) + 9 * np.eye(8)
    assert gap.min() > 0.1


def _closed_form_ab_count(p, theta1):
    """Configurations for input AB by counting circle intersections (None if near-tangent)."""
    _, d, g = _fixed(p)
    b = np.array(
        [np.sin(p["a2"]) * np.sin(theta1), np.sin(p["a2"]) * np.cos(theta1), np.cos(p["a2"])]
    )

    def meet(p1, c1, p2, c2):
        w = np.cross(p1, p2)
        if np.linalg.norm(w) < 1e-6:  # concentric circles: a whole circle, or nothing
            return None
        k = p1 @ p2
        alpha, beta = (c1 - k * c2) / (1 - k * k), (c2 - k * c1) / (1 - k * k)
        base = alpha * p1 + beta * p2
        gamma2 = (1 - base @ base) / (w @ w)
        if abs(gamma2) < 1e-9:
            return None
        return [] if gamma2 < 0 else [base + s * np.sqrt(gamma2) * w for s in (1, -1)]

    cs = meet(b, np.cos(p["a3"]), d, np.cos(p["a4"]))
    if cs is None:
        return None
    total = 0
    for c in cs:
        rows = np.stack((c, b, np.cross(c, b)))
        rhs = [
            np.cos(p["a6"]),
            np.cos(p["a3"]) * np.cos(p["a6"])
            - np.sin(p["a3"]) * np.sin(p["a6"]) * np.cos(p["sigma"]),
            np.sin(p["a3"]) * np.sin(p["a6"]) * np.sin(p["sigma"]),
        ]
        fs = meet(np.linalg.solve(rows, rhs), np.cos(p["a7"]), g, np.cos(p["a8"]))
        if fs is None:
            return None
        total += len(fs)
    return total


def test_count_sweep_against_closed_form_counts():
    sweep = p001.count_sweep(72)
    p, mirror = _p(), {**_p(), "sigma": -_p()["sigma"]}
    for i, deg in enumerate(sweep["input"]):
        own = _closed_form_ab_count(p, np.radians(deg))
        other = _closed_form_ab_count(mirror, np.radians(deg))
        if own is None or other is None:
            continue
        assert sweep["ab"][i] == own
        assert sweep["ab_mirror"][i] == other
        assert sweep["ab_either"][i] == own + other
    assert np.nanmax(sweep["fg_residual"]) < TOL and np.nanmax(sweep["ab_residual"]) < TOL


def test_mirror_check_at_the_example():
    r = p001.mirror_check()
    assert (r["coupler"], r["mirror"], r["either"]) == (4, 4, 8)
    assert r["system4"] < TOL and r["residual"] < TOL
    assert r["mirror_off"] > 0.1


def test_eq20_real_roots_are_the_configurations_of_both_couplers():
    rows = p001.eq20_check()
    assert len(rows) == 2
    for r in rows:
        assert r["degree"] == 8
        assert len(r["real"]) == len(r["coupler"]) + len(r["mirror"]) == 4
        assert r["gap"] < 1e-8


def test_eq18_factor_two():
    p = _p()
    t1 = np.radians(p001.MIRROR_INPUT)
    b = np.array([np.sin(p["a2"]) * np.sin(t1), np.sin(p["a2"]) * np.cos(t1), np.cos(p["a2"])])
    rows = p001.eq18_check()
    assert sorted(r["assembly"] for r in rows) == [-1.0, 1.0]
    for r in rows:
        # θ4 = 2·arctan(x4) is eq. 5's C on the link BC; arctan(x4) is not.
        s1, c1, s4, c4 = np.sin(p["a1"]), np.cos(p["a1"]), np.sin(p["a4"]), np.cos(p["a4"])
        for key, ok in (("2x", True), ("printed", False)):
            t4 = np.radians(r[f"theta4_{key}"])
            c2 = np.array(
                [s4 * np.sin(t4), s1 * c4 + c1 * s4 * np.cos(t4), c1 * c4 - s1 * s4 * np.cos(t4)]
            )
            assert (abs(b @ c2 - np.cos(p["a3"])) < TOL) == ok
        assert abs(np.tan(np.radians(r["theta4_2x"]) / 2) - r["x4"]) < 1e-9 * (1 + abs(r["x4"]))
        assert r["chord_2x"] < TOL and r["chord_printed"] > 1e-3


def test_misprints_against_closed_forms():
    found = {m.where: m for m in p001.misprints()}
    assert all(m.confirmed for m in found.values())
    assert set(found) == {
        "eq. 8 (G)",
        "eqs. 10–12 (F and a9–a11)",
        "eq. 9 (rotation axis)",
        "eqs. 15–16 (f and g)",
        "eq. 15 (a23)",
        "eq. 16 (a33)",
        "eq. 18 (factor 2)",
        "eq. 19 (right)",
        "eq. 21 (right)",
    }
    a1, a8, a9 = DEG["a1"], DEG["a8"], DEG["a9"]
    # The printed G is a1 + a9 on the other side of A: 2·a1 + a9 from D (or 360° less that).
    arc = 2 * a1 + a9
    arc = min(arc, 360 - arc)
    assert f"arc DG = {arc:.6f}° with the printed G" in found["eq. 8 (G)"].check
    # About OA, F (at a1 + a9 − a8 from A) meets G's far side at θ6 = 180°: the arc FG there
    # is (a1 + a9 − a8) + (a1 + a9), folded past 180°.
    far = (a1 + a9 - a8) + (a1 + a9)
    far = min(far, 360 - far)
    assert f"up to {abs(far - a8):.4f}°" in found["eq. 9 (rotation axis)"].check
    # The printed F's length, from eq. 12 evaluated by hand at θ6 = 0 and 90°.
    s1, c1 = np.sin(np.radians(a1)), np.cos(np.radians(a1))
    s8, c8 = np.sin(np.radians(a8)), np.cos(np.radians(a8))
    s9, c9 = np.sin(np.radians(a9)), np.cos(np.radians(a9))
    k9 = s1 * (c8 * c9 + c8 * s9 - s8 * s9 + s8 * c9)
    k11 = c8 * c9 * c1 - c8 * s9 * s1 - s8 * s9 * c1 - s8 * c9 * s1
    assert f"{np.hypot(k9, k11):.6f}" in found["eqs. 10–12 (F and a9–a11)"].check


arc = st.floats(0.15, np.pi - 0.15)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0.15, np.pi - 0.35), min_size=9, max_size=9),
    st.floats(0.05, np.pi - 0.05),
    st.floats(0, 360),
)
def test_eq20_and_the_mirror_on_random_mechanisms(arcs, sigma, theta1):
    names = ("a1", "a2", "a3", "a4", "a6", "sigma", "a7", "a8", "a9")
    # Spread the arcs by a fixed irrational step: Hypothesis' favourite equal values would build
    # degenerate linkages (a1 = a4 with a2 = a3 folds C onto A) in which eq. 20 vanishes
    # identically in θ6 at some x5 without a configuration there.
    arcs = [a + 0.0137 * np.sqrt(2.0) * i for i, a in enumerate(arcs)]
    arcs[5] = sigma
    m = SphericalStephenson3(*arcs)
    mirror = p001.mirror_check(theta1, m)
    assert mirror["system4"] < 1e-12
    assert mirror["either"] == mirror["coupler"] + mirror["mirror"]  # σ ≠ 0, π: all distinct
    assert mirror["coupler"] <= 4 and mirror["mirror"] <= 4
    if mirror["mirror"]:
        assert mirror["mirror_off"] > 0
    p = dict(zip(names, arcs, strict=True))
    count = _closed_form_ab_count(p, np.radians(theta1))
    mirror_count = _closed_form_ab_count({**p, "sigma": -sigma}, np.radians(theta1))
    assume(count is not None and mirror_count is not None)
    assert mirror["coupler"] == count and mirror["mirror"] == mirror_count

    # With EF = FG, E reaches G at θ5 = 0 for every θ6: both lines of eq. 13 lose θ6 there, and
    # eq. 20 vanishes at x5 = 0 without a configuration (the degenerate case of the page).
    assume(abs(arcs[6] - arcs[7]) > 1e-3)
    rows = p001.eq20_check(theta1, m)
    for r in rows:
        # Near a double root (a limit of the dyad EFG) the real-root count is ill-conditioned.
        configs = np.concatenate((r["coupler"], r["mirror"]))
        close = np.abs(np.angle(np.exp(1j * np.radians(configs[:, None] - configs[None]))))
        assume(np.all((close + 9 * np.eye(len(configs))) > 1e-3))
        assume(r["degree"] == 8)
        assert len(r["real"]) == len(configs) <= 4
        assert r["gap"] < 1e-6

    for r in p001.eq18_check(theta1, m):
        if np.isfinite(r["x4"]):
            assert r["bc_error_2x"] < 1e-9


def test_the_mechanism_helper():
    assert p001.example().input == "FG"
    mirror = p001.example("AB", mirror=True)
    assert np.isclose(np.degrees(mirror.sigma), -70.0)
    back = replace(mirror, sigma=-mirror.sigma)
    own = p001.example("AB")
    assert all(np.array_equal(getattr(back, k), getattr(own, k)) for k in p001.EXAMPLE)


# ---------------------------------------------------------------------------------------------
# Issue 21's example driven at FG: its counts, its circuits and where they join
# ---------------------------------------------------------------------------------------------

FG_ARCS = (71.1, 64.1, 68.6, 65.7, 69.0, 102.0, 74.1, 52.6, 19.7)  # issue 21, "Done when"
FG_NAMES = ("a1", "a2", "a3", "a4", "a6", "sigma", "a7", "a8", "a9")


def test_the_bundled_fg_example_is_issue_21s_with_8_4_and_6_configurations():
    m = load_example("paper001-fg").mechanism
    assert m.input == "FG"
    assert [round(float(np.degrees(getattr(m, k))), 9) for k in FG_NAMES] == list(FG_ARCS)
    theta = np.radians([-90.0, 0.0, 120.0])
    assert p001_circuits.counts_at(m, [-90.0, 0.0, 120.0]) == [8, 4, 6]
    # The same counts by an independent method: sign changes of the triad's closure swept
    # around the circle of B (no polynomial, no plan).
    assert sphere_triad_sweep(*triad_of(m, theta), grid=4096).count.tolist() == [8, 4, 6]
    p = {k: np.radians(v) for k, v in zip(FG_NAMES, FG_ARCS, strict=True)}
    found = solve_all(m, theta)
    for i in range(3):
        for k in range(int(found.count[i])):
            b, c, e, f = (found.positions[j][i, k] for j in "BCEF")
            assert _violation(p, b, c, e, f) < 1e-12


def _turning(pos):
    """The triad's closure, written from its constraints: the coupler BCE turning with angular
    velocity w moves each joint X by w × X, which keeps its arc to its anchor K while
    w · (X × K) = 0; the three rows (B × A, C × D, E × F) are singular where two
    configurations meet. Normalised by the rows' lengths."""
    rows = np.array([np.cross(pos["B"], pos["A"]), np.cross(pos["C"], pos["D"]),
                     np.cross(pos["E"], pos["F"])])  # fmt: skip
    return float(np.linalg.det(rows) / np.prod(np.linalg.norm(rows, axis=1)))


def test_the_circuits_join_where_two_configurations_meet():
    m = p001_circuits.fg_example()
    found, joins = p001_circuits.circuit_joins(m)
    assert [len(c.limits) for c in found] == [2, 6, 2]
    assert len(joins) == sum(len(c.limits) for c in found)
    p = {k: np.radians(v) for k, v in zip(FG_NAMES, FG_ARCS, strict=True)}
    for join in joins:
        theta = np.radians(join.input_deg)
        poses = {
            branches[0]: {j: v[0] for j, v in motion.positions.items()}
            for branches, motion in configurations(m, [theta], order=0)
            if motion.valid[0]
        }
        a, b = (poses[k] for k in join.poses)
        # The two configurations are one there: their joints coincide (the limit is found to
        # about 1e-10 rad, so they stand about its square root apart) and each closes every
        # constraint; the triad's closure vanishes for them and not for the others.
        gap = max(float(np.linalg.norm(a[j] - b[j])) for j in "BCE")
        assert gap < 1e-4, (join, gap)
        for pos in (a, b):
            assert _violation(p, *(pos[j] for j in "BCEF")) < 1e-12
            assert abs(_turning(pos)) < 1e-4, join
        others = [abs(_turning(v)) for k, v in poses.items() if k not in join.poses]
        assert others and min(others) > 1e-3, (join, others)
        # Just beside it: two configurations more on one side than on the other.
        below, above = solve_all(m, theta + np.radians([-1e-6, 1e-6])).count.tolist()
        assert (below, above) == (join.below, join.above)
        assert abs(below - above) == 2


def test_each_fg_circuit_follows_one_configuration_between_its_limits():
    """No branch jump: between limits, the configuration the circuit goes on to is the one
    nearest to where it was heading (the last step carried on: the samples step evenly along
    the joints' paths, even near a limit, where two configurations draw close), among every
    configuration at the next input."""
    m = p001_circuits.fg_example()
    found, _ = p001_circuits.circuit_joins(m, samples=720)
    for circuit in found:
        motion = circuit.motion
        x = np.concatenate([motion.positions[j] for j in "BCE"], axis=-1)
        every = solve_all(m, motion.input)
        xs = np.concatenate([every.positions[j] for j in "BCE"], axis=-1)
        # A circuit's inputs run on past a turn; its limits are named within one.
        wrapped = np.remainder(motion.input + np.pi, 2 * np.pi) - np.pi
        limits = np.array([lim.input for lim in circuit.limits])
        at_limit = np.any(np.abs(wrapped[:, None] - limits[None]) < 1e-12, axis=-1)
        assert at_limit.sum() == len(limits)
        n = len(x)
        checked = 0
        for k in range(n):
            nxt = (k + 1) % n
            if at_limit[k] or at_limit[nxt]:
                continue  # a turn: the circuit goes on in the configuration it met there
            heading = 2 * x[k] - x[k - 1]
            d = np.linalg.norm(xs[nxt] - heading, axis=-1)
            d = np.where(every.valid[nxt], d, np.inf)
            own = float(np.linalg.norm(x[nxt] - heading))
            assert own <= float(np.min(d)) + 1e-12, (k, own, np.sort(d)[:2])
            checked += 1
        assert checked >= n - 3 * len(circuit.limits)

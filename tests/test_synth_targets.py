"""Design to targets and Reinsberg's optimal transmission, checked against independent
derivations: the law of cosines for a crank-rocker's swing and transmission angle (paper 003's
own formulas), dense sampling of φ3′ and of the transmission angle from solved positions,
Thales' circle in the plane and the right angle at B on the sphere."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.analysis import (
    coefficients,
    fourbar_class,
    grashof,
    grashof_terms,
    transmission_extremes,
)
from linkwright.geometry import sphere
from linkwright.io import mechanism_to_dict, parse_document
from linkwright.mechanisms import FourBar, SliderCrank, SphericalFourBar, solve
from linkwright.papers import p003
from linkwright.synthesis.reinsberg import (
    ReinsbergError,
    reinsberg_complete,
    reinsberg_defect,
    reinsberg_mechanism,
)
from linkwright.synthesis.targets import (
    OUTPUTS,
    TargetError,
    design_fourbar,
    design_to_targets,
)

DEG = math.pi / 180.0


# --- independent formulas -------------------------------------------------------------------


def law_of_cosines(a, b, c):
    """The angle opposite c in a triangle with sides a, b, c."""
    return np.arccos(np.clip((a * a + b * b - c * c) / (2 * a * b), -1.0, 1.0))


def crank_rocker_swing(L1, L2, L3, L4):
    """Paper 003's Ψp: the rocker's angle at B0 between the two dead centres (A0 B = L2 ± L1)."""
    return law_of_cosines(L4, L3, L1 + L2) - law_of_cosines(L4, L3, L2 - L1)


def crank_rocker_gamma_min(L1, L2, L3, L4):
    """Paper 003's γ1: the transmission angle at φ1 = 0 (A B0 = L4 − L1)."""
    return law_of_cosines(L2, L3, abs(L4 - L1))


def sampled_rates(fb: SphericalFourBar, samples: int = 8192) -> np.ndarray:
    """φ3′ at evenly spaced inputs, from B's velocity about the axis B0 (not the analysis)."""
    m = solve(fb, np.linspace(0.0, 2 * np.pi, samples, endpoint=False))
    b0, b, vb = m.positions["B0"], m.positions["B"], m.velocities["B"]
    w = np.cross(np.broadcast_to(b0, b.shape), b)
    return np.sum(w * vb, axis=-1) / np.sin(float(fb.rocker)) ** 2


def sampled_gamma(fb, samples: int = 20001) -> np.ndarray:
    """The angle at B between B→A and B→B0, at evenly spaced inputs, from solved positions."""
    theta = np.linspace(0.0, 2 * np.pi, samples) + 0.123  # no sample sits on 0 or π
    p = solve(fb, theta, order=0).positions
    a, b, b0 = p["A"], p["B"], np.broadcast_to(p["B0"], p["B"].shape)
    if isinstance(fb, SphericalFourBar):
        u = a - np.sum(a * b, -1, keepdims=True) * b
        v = b0 - np.sum(b0 * b, -1, keepdims=True) * b
    else:
        u, v = a - b, b0 - b
    cos = np.sum(u * v, -1) / (np.linalg.norm(u, axis=-1) * np.linalg.norm(v, axis=-1))
    return np.arccos(np.clip(cos, -1.0, 1.0))


def grid_slack(values: np.ndarray) -> float:
    """How far a periodic sampling's min and max may each miss the true extremes, summed: a
    sampled extreme is off by up to f″(h/2)²/2 = Δ²f/8 (Δ²f the second difference at the
    extreme sample); twice that at each. A fixed 1e-6 failed where the curve bends sharply."""
    d2 = np.abs(np.roll(values, -1) - 2 * values + np.roll(values, 1))
    return float(0.25 * (d2[np.argmin(values)] + d2[np.argmax(values)]))


def input_turns(fb, samples: int = 4096) -> bool:
    """Whether the linkage assembles at every sampled input (the engine, not the closed forms)."""
    theta = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    return bool(solve(fb, theta, order=0).valid.all())


def planar(L1, L2, L3, L4) -> FourBar:
    return FourBar(A0=[0.0, 0.0], B0=[L4, 0.0], crank=L1, coupler=L2, rocker=L3)


# --- design to targets: planar round trips ---------------------------------------------------


@settings(max_examples=4, deadline=None)
@given(
    st.floats(2.5, 5.0),
    st.floats(1.5, 6.0),
    st.floats(1.5, 6.0),
    st.floats(0.2, 0.8),
    st.floats(0.2, 0.8),
    st.floats(0.2, 0.8),
    st.floats(0.2, 0.8),
)
def test_planar_round_trip_swing_and_transmission(L4, L2, L3, a, b, c, d):
    fb = planar(1.0, L2, L3, L4)
    assume(str(fourbar_class(fb)) == "crank-rocker")
    swing = crank_rocker_swing(1.0, L2, L3, L4)
    gamma = crank_rocker_gamma_min(1.0, L2, L3, L4)
    # A root where the two level curves nearly touch is not isolated to grid resolution.
    h = 1e-6
    jac = np.array(
        [
            [
                (f(1.0, L2 + h * e[0], L3 + h * e[1], L4) - f(1.0, L2, L3, L4)) / h
                for e in ((1, 0), (0, 1))
            ]
            for f in (crank_rocker_swing, crank_rocker_gamma_min)
        ]
    )
    assume(np.linalg.cond(jac) < 50)
    found = design_fourbar(
        "fourbar",
        {"crank": 1.0, "frame": L4},
        ["coupler", "rocker"],
        {"swing": swing, "gamma_min": gamma},
        bounds={"coupler": (L2 - a, L2 + b), "rocker": (L3 - c, L3 + d)},
        grid=7,
    )
    assert len(found) >= 1
    hit = np.max(np.abs(found.x - [L2, L3]), axis=-1)
    assert hit.min() < 1e-7, (found.x, [L2, L3])
    for s in found:
        x2, x3 = s.x
        # Every reported solution hits the targets: the analysis and the paper's closed forms.
        assert s.residual <= 1e-9
        assert s.values["swing"] == pytest.approx(swing, abs=1e-9)
        assert crank_rocker_swing(1.0, x2, x3, L4) == pytest.approx(swing, abs=1e-8)
        assert crank_rocker_gamma_min(1.0, x2, x3, L4) == pytest.approx(gamma, abs=1e-8)
        tx = transmission_extremes(s.mechanism)
        assert float(tx["min"]) == pytest.approx(gamma, abs=1e-9)
        # The Jacobian agrees with the closed forms' (finite differences, separately).
        assert np.all(np.isfinite(s.jacobian)) and np.all(np.isfinite(s.sensitivity))
        np.testing.assert_allclose(s.sensitivity @ s.jacobian, np.eye(2), atol=1e-8)


def test_planar_table4_double_crank_by_coefficients():
    # Paper 003's Table 4 (L4 = 1, L2 = 2): the printed row L1 = 5, L3 = 4.69 gives
    # Kω = 1.25, δ = 0.48 to the printed digits. Aim at our exact values for L1 = 5 and
    # L3 = √(1 + 25 − 4) and get the four-bar back.
    L3 = math.sqrt(22.0)
    co = coefficients(planar(5.0, 2.0, L3, 1.0))
    found = design_to_targets(
        lambda x: FourBar(
            A0=[0.0, 0.0], B0=[1.0, 0.0], crank=x[..., 0], coupler=2.0, rocker=x[..., 1]
        ),
        ["crank", "rocker"],
        [(4.0, 6.0), (3.5, 5.5)],
        {
            "max_Kw": (OUTPUTS["max_Kw"], float(co["K_omega"])),
            "delta": (OUTPUTS["delta"], float(co["delta"])),
        },
        grid=6,
    )
    assert len(found) == 1
    np.testing.assert_allclose(found[0].x, [5.0, L3], atol=1e-8)
    # δ and max|Kω| by dense sampling of φ3′ (B's angular rate about B0), not the analysis.
    fb = found[0].mechanism
    m = solve(fb, np.linspace(0.0, 2 * np.pi, 8192, endpoint=False))
    rel = m.positions["B"] - m.positions["B0"]
    vel = m.velocities["B"]
    rate = (rel[..., 0] * vel[..., 1] - rel[..., 1] * vel[..., 0]) / L3**2
    assert rate.max() - rate.min() == pytest.approx(found[0].values["delta"], rel=1e-6)
    assert np.abs(rate).max() == pytest.approx(found[0].values["max_Kw"], rel=1e-6)
    # The mechanism is a document like any other.
    again = parse_document(mechanism_to_dict(fb))
    assert float(again.mechanism.rocker) == pytest.approx(L3, abs=1e-8)


# --- design to targets: spherical round trip ------------------------------------------------


@settings(max_examples=2, deadline=None)
@given(
    st.floats(5.0, 20.0),
    st.floats(60.0, 100.0),
    st.floats(55.0, 120.0),
    st.floats(40.0, 80.0),
    st.floats(2.0, 6.0),
    st.floats(2.0, 6.0),
)
def test_spherical_double_crank_round_trip(frame, crank, coupler, rocker, a, b):
    fb = SphericalFourBar(*np.radians([frame, crank, coupler, rocker]))
    assume(str(fourbar_class(fb)) == "double-crank")
    rates = sampled_rates(fb)
    kw, delta = float(np.abs(rates).max()), float(rates.max() - rates.min())
    co = coefficients(fb)
    assert co["K_omega"] == pytest.approx(kw, rel=1e-6)
    found = design_fourbar(
        "spherical-fourbar",
        {"frame": frame, "crank": crank},
        ["coupler", "rocker"],
        {"max_Kw": float(co["K_omega"]), "delta": float(co["delta"])},
        bounds={"coupler": (coupler - a, coupler + b), "rocker": (rocker - b, rocker + a)},
        kind="double-crank",
        grid=6,
        degrees=True,
    )
    truth = np.radians([coupler, rocker])
    assume(all(np.all(np.isfinite(s.sensitivity)) for s in found))
    assert np.min(np.max(np.abs(found.x - truth), axis=-1)) < 1e-7
    for s in found:
        r = sampled_rates(s.mechanism)
        assert np.abs(r).max() == pytest.approx(kw, rel=1e-6)
        assert r.max() - r.min() == pytest.approx(delta, rel=1e-5, abs=1e-7)
        assert str(fourbar_class(s.mechanism)) == "double-crank"


# --- paper 003's example ---------------------------------------------------------------------


def test_paper003_synthesis_example_lists_every_solution_of_the_whole_square():
    # α1 = 80°, α4 = 10°, max|Kε| = 1.47, max|Kp| = 1.49 over 1° ≤ α2, α3 ≤ 179°.
    syn = p003.synthesis_example()
    sols = syn["solutions"]
    assert len(sols) == 2
    a = sorted((s["alpha2"], s["alpha3"]) for s in sols)
    np.testing.assert_allclose(a, [[76.3648, 127.5430], [103.6352, 52.4570]], atol=1e-4)
    # One mechanism: the axis B flipped (α2, α3 → supplements) ...
    assert a[0][0] + a[1][0] == pytest.approx(180.0, abs=1e-6)
    assert a[0][1] + a[1][1] == pytest.approx(180.0, abs=1e-6)
    for s in sols:
        assert s["residual"] <= 1e-9
        # ... and, recomputed, the targets in every reading: as found (crank 80°), with the
        # axis A flipped (crank 100°, α2 → 180° − α2) and with both axes flipped.
        for crank, a2, a3 in (
            (80.0, s["alpha2"], s["alpha3"]),
            (100.0, s["alpha2_read_100"], s["alpha3"]),
            (100.0, s["alpha2"], 180.0 - s["alpha3"]),
        ):
            co = coefficients(SphericalFourBar(*np.radians([10.0, crank, a2, a3])))
            assert float(co["K_epsilon"]) == pytest.approx(1.47, abs=1e-9)
            assert float(co["K_p"]) == pytest.approx(1.49, abs=1e-9)
        # Ill-conditioned: the level curves are nearly parallel; a change of 0.01 in max|Kε|
        # alone moves α2 by about 16°.
        assert 200 < s["condition"] < 400
        assert abs(s["sensitivity"]["alpha2"]["K_epsilon"]) * 0.01 == pytest.approx(16, abs=0.1)
    # The sensitivity means what it says: moving (α2, α3) along its K_epsilon column changes
    # max|Kε| by one unit per unit and leaves max|Kp| alone (central differences of the exact
    # maxima).
    s = sols[1]
    eps = 1e-6
    d2 = s["sensitivity"]["alpha2"]["K_epsilon"] * eps
    d3 = s["sensitivity"]["alpha3"]["K_epsilon"] * eps
    ends = SphericalFourBar(
        frame=10 * DEG,
        crank=80 * DEG,
        coupler=np.radians(s["alpha2"] + np.array([d2, -d2])),
        rocker=np.radians(s["alpha3"] + np.array([d3, -d3])),
    )
    co = coefficients(ends)
    assert (co["K_epsilon"][0] - co["K_epsilon"][1]) / (2 * eps) == pytest.approx(1.0, abs=1e-3)
    assert (co["K_p"][0] - co["K_p"][1]) / (2 * eps) == pytest.approx(0.0, abs=1e-3)
    # The reading nearest the paper's answer, and the page beside the paper's.
    assert syn["read_100"]["alpha2"] == pytest.approx(76.365, abs=1e-3)
    page = p003.markdown([], syn)
    assert "| 103.6352 | 76.3648 | 52.4570 |" in page
    assert "| paper (fitted eq. 9) | 66.25 | 58.84 |" in page


# --- least squares, masks and errors ----------------------------------------------------------


def test_least_squares_with_three_targets_for_two_lengths():
    L2, L3, L4 = 4.0, 3.0, 4.5
    fb = planar(1.0, L2, L3, L4)
    tx = transmission_extremes(fb)
    swing = float(crank_rocker_swing(1.0, L2, L3, L4))
    make_targets = {"swing": swing, "gamma_min": float(tx["min"]), "gamma_max": float(tx["max"])}
    box = {"coupler": (3.0, 5.0), "rocker": (2.0, 4.0)}
    fixed = {"crank": 1.0, "frame": L4}
    found = design_fourbar(
        "fourbar", fixed, ["coupler", "rocker"], make_targets, bounds=box, grid=7
    )
    assert found.least_squares
    np.testing.assert_allclose(found[0].x, [L2, L3], atol=1e-7)
    assert found[0].residual < 1e-9
    # An inconsistent third target: the best compromise is a true local minimum of the misfit,
    # which no nearby point improves on.
    make_targets["gamma_max"] += 0.05
    found = design_fourbar(
        "fourbar", fixed, ["coupler", "rocker"], make_targets, bounds=box, grid=7
    )
    best = found[0]
    assert best.residual > 1e-3

    def misfit(x2, x3):
        t = transmission_extremes(planar(1.0, x2, x3, L4))
        got = np.array([crank_rocker_swing(1.0, x2, x3, L4), t["min"], t["max"]], dtype=float)
        want = np.array(list(make_targets.values()))
        return float(np.sum(((got - want) / np.maximum(np.abs(want), 1.0)) ** 2))

    at = misfit(*best.x)
    for dx in ((1e-4, 0), (-1e-4, 0), (0, 1e-4), (0, -1e-4), (1e-4, 1e-4), (-1e-4, 1e-4)):
        assert misfit(best.x[0] + dx[0], best.x[1] + dx[1]) >= at - 1e-15


def test_masked_cells_never_leak_nan():
    # Most of the box is not a crank-rocker (the swing is undefined there).
    found = design_fourbar(
        "fourbar",
        {"crank": 1.0, "frame": 4.0},
        ["coupler", "rocker"],
        {"swing": 40.0, "gamma_min": 40.0},
        degrees=True,
        grid=9,
    )
    assert found.masked > 0.5
    assert len(found) == 1
    report = found.report()
    assert report["units"] == {"coupler": "", "rocker": "", "swing": "deg", "gamma_min": "deg"}
    assert report["solutions"][0]["values"]["swing"] == pytest.approx(40.0, abs=1e-9)
    s = found[0]
    assert all(np.isfinite(v) for v in s.values.values())
    L2, L3 = s.x
    assert np.degrees(crank_rocker_swing(1.0, L2, L3, 4.0)) == pytest.approx(40.0, abs=1e-8)
    assert np.degrees(crank_rocker_gamma_min(1.0, L2, L3, 4.0)) == pytest.approx(40.0, abs=1e-8)


def test_progress_is_reported_from_0_to_1():
    seen = []
    design_fourbar(
        "fourbar",
        {"crank": 1.0, "frame": 4.0},
        ["coupler", "rocker"],
        {"swing": 40.0, "gamma_min": 40.0},
        degrees=True,
        grid=5,
        progress=seen.append,
    )
    assert seen and seen[-1] == 1.0
    assert all(0.0 <= p <= 1.0 for p in seen) and seen == sorted(seen)


def make_planar(x):
    return FourBar(A0=[0.0, 0.0], B0=[4.0, 0.0], crank=1.0, coupler=x[..., 0], rocker=x[..., 1])


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (
            lambda: design_to_targets(
                make_planar,
                ["coupler", "rocker"],
                [(3, 5), (2, 4)],
                {"swing": (OUTPUTS["swing"], 0.5)},
            ),
            "1 target(s) for 2",
        ),
        (
            lambda: design_to_targets(
                make_planar,
                ["coupler", "rocker"],
                [(5, 3), (2, 4)],
                {"swing": (OUTPUTS["swing"], 0.5), "gamma_min": (OUTPUTS["gamma_min"], 0.5)},
            ),
            "lower bound must be below",
        ),
        (
            lambda: design_to_targets(
                make_planar,
                ["coupler", "rocker"],
                [(-1, 5), (2, 4)],
                {"swing": (OUTPUTS["swing"], 0.5), "gamma_min": (OUTPUTS["gamma_min"], 0.5)},
                grid=3,
            ),
            "coupler: must be a positive length",
        ),
        (
            lambda: design_to_targets(
                make_planar,
                ["coupler", "rocker"],
                [(3, 5), (2, 4)],
                {"a": (lambda m: np.zeros(3), 0.5), "b": (OUTPUTS["gamma_min"], 0.5)},
                grid=3,
            ),
            "output 'a' gave shape (3,)",
        ),
        (
            lambda: design_fourbar(
                "fourbar", {"crank": 1}, ["coupler", "rocker"], {"swing": 1, "gamma_min": 1}
            ),
            "frame: neither fixed nor free",
        ),
        (
            lambda: design_fourbar(
                "fourbar", {"crank": 1, "frame": 4}, ["coupler", "rocker"], {"swing": 1, "speed": 1}
            ),
            "unknown output 'speed'",
        ),
        (
            lambda: design_fourbar(
                "fourbar",
                {"crank": 1, "frame": 4, "rocker": 3},
                ["coupler", "rocker"],
                {"swing": 1, "gamma_min": 1},
            ),
            "'rocker' is both fixed and free",
        ),
        (
            lambda: design_fourbar("slidercrank", {}, ["crank"], {"swing": 1}),
            "family: 'slidercrank'",
        ),
        (
            lambda: design_fourbar(
                "spherical-fourbar",
                {"crank": 80, "frame": 10, "coupler": 60},
                ["rocker"],
                {"delta": 0.3},
                bounds={"rocker": (0, 90)},
                degrees=True,
            ),
            "rocker's arcs must lie strictly between 0° and 180°, got 0° to 90°",
        ),
    ],
)
def test_problems_that_are_not_well_posed_raise_clear_errors(call, words):
    with pytest.raises(TargetError, match=None) as err:
        call()
    assert words in str(err.value)
    assert isinstance(err.value, ValueError)


# --- Reinsberg ------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.2, 5.0),
    st.floats(0.2, 5.0),
    st.floats(0.2, 5.0),
    st.sampled_from(["crank", "coupler", "rocker", "frame"]),
)
def test_planar_completion_puts_A0_and_B_on_thales_circle(p, q, r, field):
    others = [n for n in ("crank", "coupler", "rocker", "frame") if n != field]
    dims = dict(zip(others, (p, q, r), strict=True))
    dims[field] = 1.0  # ignored by the completion
    fb = planar(dims["crank"], dims["coupler"], dims["rocker"], dims["frame"])
    value = float(reinsberg_complete(fb, field))
    if math.isnan(value):
        # No root: either no positive length balances, or the input does not turn with it.
        other = {"crank": "frame", "frame": "crank", "coupler": "rocker", "rocker": "coupler"}
        pair = {"crank": "coupler", "frame": "coupler", "coupler": "crank", "rocker": "crank"}
        sq = dims[pair[field]] ** 2 + dims[other[pair[field]]] ** 2 - dims[other[field]] ** 2
        if sq > 1e-9:
            dims[field] = math.sqrt(sq)
            done = planar(dims["crank"], dims["coupler"], dims["rocker"], dims["frame"])
            # (A change point turns through a singular position, either way by rounding.)
            assume(abs(float(grashof(done))) > 1e-6)
            assert not input_turns(done)
        return
    dims[field] = value
    done = planar(dims["crank"], dims["coupler"], dims["rocker"], dims["frame"])
    assume(min(dims.values()) > 1e-3 and abs(float(grashof(done))) > 1e-6)
    assert input_turns(done)
    # At φ1 = 90° A0 and B see the diagonal A B0 at right angles: both on the circle on it.
    for asm in (1.0, -1.0):
        pos = solve(
            FourBar(
                A0=[0, 0],
                B0=[dims["frame"], 0],
                crank=dims["crank"],
                coupler=dims["coupler"],
                rocker=dims["rocker"],
                assembly=asm,
            ),
            [np.pi / 2],
            order=0,
        ).positions
        a, b0 = pos["A"][0], pos["B0"][0]
        centre, radius = (a + b0) / 2, np.linalg.norm(a - b0) / 2
        scale = max(dims.values())
        assert np.linalg.norm(pos["A0"][0] - centre) == pytest.approx(radius, abs=1e-9 * scale)
        assert np.linalg.norm(pos["B"][0] - centre) == pytest.approx(radius, abs=1e-9 * scale)
    # And the sampled transmission angle swings symmetrically about 90°.
    g = sampled_gamma(done)
    assert g.min() + g.max() == pytest.approx(np.pi, abs=1e-9 + grid_slack(g))
    assert abs(float(reinsberg_defect(done))) < 1e-9


@settings(max_examples=40, deadline=None)
@given(
    st.floats(5.0, 175.0),
    st.floats(5.0, 175.0),
    st.floats(5.0, 175.0),
    st.sampled_from(["crank", "coupler", "rocker", "frame"]),
)
def test_spherical_completion_has_a_right_angle_at_B_at_90_degrees(p, q, r, field):
    others = [n for n in ("crank", "coupler", "rocker", "frame") if n != field]
    dims = {n: v * DEG for n, v in zip(others, (p, q, r), strict=True)}
    dims[field] = 1.0
    fb = SphericalFourBar(**dims)
    value = float(reinsberg_complete(fb, field))
    if math.isnan(value):
        return
    dims[field] = value
    done = SphericalFourBar(**dims)
    assume(min(min(dims.values()), math.pi - max(dims.values())) > 1e-3)
    assume(np.min(np.abs(grashof_terms(done))) > 1e-6)  # not a change point
    assert 0 < value < math.pi and input_turns(done)
    # At φ1 = 90° the angle at A0 is right by construction; the angle at B is right too.
    for asm in (1.0, -1.0):
        pos = solve(SphericalFourBar(**dims, assembly=asm), [np.pi / 2], order=0).positions
        b = pos["B"][0]
        angle = sphere.angle_at(b, pos["A"][0], pos["B0"][0])
        assert abs(float(angle)) == pytest.approx(np.pi / 2, abs=1e-8)
        assert float(sphere.angle_at(pos["A0"][0], pos["B0"][0], pos["A"][0])) == pytest.approx(
            np.pi / 2, abs=1e-9
        )
    g = sampled_gamma(done)
    assert g.min() + g.max() == pytest.approx(np.pi, abs=1e-9 + grid_slack(g))
    assert abs(float(reinsberg_defect(done))) < 1e-9


@settings(max_examples=30, deadline=None)
@given(st.floats(5.0, 175.0), st.floats(5.0, 175.0), st.floats(5.0, 175.0), st.floats(5.0, 175.0))
def test_defect_is_the_sampled_extremes_sum_minus_180(a1, a2, a3, a4):
    fb = SphericalFourBar(*np.radians([a4, a1, a2, a3]))
    assume(np.min(np.abs(grashof_terms(fb))) > 1e-6)  # not a change point
    defect = float(reinsberg_defect(fb))
    if not input_turns(fb):
        assert math.isnan(defect)
        return
    assume(not math.isnan(defect))  # a change point counted either way
    g = sampled_gamma(fb)
    # (seen: 1e-6 missed by 2e-8 where γ bends sharply near a change point)
    assert defect == pytest.approx(g.min() + g.max() - np.pi, abs=1e-9 + grid_slack(g))


def test_paper003_table4_is_reinsbergs():
    # L4 = 1, L3 = √(L4² + L1² − L2²): every row's output length (printed to 2 decimals, one
    # misprint) and ν = γmax − 90° (printed).
    for L2, L1, L3, *_, nu in p003.TABLE4:
        fb = planar(L1, L2, 1.0, 1.0)
        value = float(reinsberg_complete(fb, "rocker", kind="double-crank"))
        if (L2, L1) != (3.0, 5.5):
            # Rounded or truncated to the printed digits.
            assert -0.005 - 1e-12 <= value - float(L3) < 0.01
        done = planar(L1, L2, value, 1.0)
        assert abs(float(reinsberg_defect(done))) < 1e-12
        gmax = float(transmission_extremes(done)["max"])
        if (L2, L1) != (3.0, 6.0):
            assert -0.005 - 1e-12 <= np.degrees(gmax) - 90 - float(nu) < 0.01
        else:  # the misprint of SEED-NOTES: 22.29 for 22.208
            assert np.degrees(gmax) - 90 == pytest.approx(22.208, abs=5e-4)


def test_reinsberg_completion_returns_nan_where_no_root_and_errors_for_bad_requests():
    # L2 longer than √(L1² + L4²): no output length balances the linkage.
    assert math.isnan(float(reinsberg_complete(planar(1.0, 3.0, 1.0, 2.0), "rocker")))
    # A crank-rocker asked to be a double crank.
    fb = planar(1.0, 4.0, 1.0, 4.5)
    value = float(reinsberg_complete(fb, "rocker"))
    assert value == pytest.approx(math.sqrt(1 + 4.5**2 - 16))
    assert str(fourbar_class(planar(1.0, 4.0, value, 4.5))) == "crank-rocker"
    assert math.isnan(float(reinsberg_complete(fb, "rocker", kind="double-crank")))
    with pytest.raises(ReinsbergError, match="'length' is not a link"):
        reinsberg_complete(fb, "length")
    with pytest.raises(ReinsbergError, match="unknown class 'drag'"):
        reinsberg_complete(fb, "rocker", kind="drag")
    with pytest.raises(ReinsbergError, match="got SliderCrank"):
        reinsberg_defect(SliderCrank(A0=[0, 0], crank=1, rod=3))


def test_reinsberg_mechanism_completes_or_says_why_not():
    # The frame of a planar four-bar is set by moving B0 along A0→B0.
    fb = FourBar(A0=[1.0, 2.0], B0=[1.0, 5.0], crank=4.0, coupler=2.0, rocker=math.sqrt(13.0))
    done = reinsberg_mechanism(fb, "frame", kind="double-crank")
    np.testing.assert_allclose(done.B0, [1.0, 3.0], atol=1e-12)
    assert abs(float(reinsberg_defect(done))) < 1e-12
    sph = SphericalFourBar(*np.radians([10.0, 80.0, 65.0, 50.0]))
    done = reinsberg_mechanism(sph, "rocker")
    assert np.degrees(float(done.rocker)) == pytest.approx(66.1312, abs=1e-4)
    with pytest.raises(ReinsbergError, match=r"would be cos crank·cos frame/cos coupler = 5\.585"):
        reinsberg_mechanism(SphericalFourBar(*np.radians([10.0, 10.0, 80.0, 50.0])), "rocker")
    with pytest.raises(ReinsbergError, match=r"it is a crank-rocker, not a double-crank"):
        reinsberg_mechanism(planar(1.0, 4.0, 1.0, 4.5), "rocker", kind="double-crank")
    with pytest.raises(ReinsbergError, match=r"the input does not turn fully"):
        reinsberg_mechanism(planar(3.0, 1.0, 1.0, 3.5), "rocker")

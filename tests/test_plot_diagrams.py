"""Motion diagrams (``linkwright plot --kind ...``): every kind of every family renders and
saves, and the plotted numbers agree with independent derivations (finite differences of the
solved positions, closed forms of papers 003 and 004, the law of cosines)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import linkwright
from linkwright.analysis import coefficients, paper003_normal_extremes
from linkwright.io import load_document
from linkwright.mechanisms import (
    DoubleSlider,
    FourBar,
    SphericalFourBar,
    configurations,
    input_range,
    solve,
)
from linkwright.plot import save_figure
from linkwright.plot.diagrams import KINDS, DiagramError, plot_diagram

EXAMPLES = Path(linkwright.__file__).parent / "examples"
N = 120  # samples per circuit: enough to check, quick to draw

# One example document per family (the linkage family twice: in the plane and on the sphere),
# plus the four-bar driven at a rocker, whose input cannot turn fully.
FAMILY_EXAMPLES = {**FAMILY_EXAMPLES, "fourbar (rocker input)": "rocker-input"}


def document(name: str):
    return load_document(EXAMPLES / f"{name}.toml")


def mechanism(name: str):
    return document(name).mechanism


def series(ax, name: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every leg drawn for the quantity ``name`` on ``ax``: its first line carries the name,
    further legs ``_name | leg``."""
    found = [
        (np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float))
        for ln in ax.get_lines()
        if ln.get_label() == name or ln.get_label().startswith(f"_{name} |")
    ]
    assert found, [ln.get_label() for ln in ax.get_lines()]
    return found


def only(ax, name: str) -> tuple[np.ndarray, np.ndarray]:
    legs = series(ax, name)
    assert len(legs) == 1
    return legs[0]


def central(f, theta: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """Central difference of f (arrays over the last-but-one or last axis) at theta."""
    return (f(theta + h) - f(theta - h)) / (2.0 * h)


# --------------------------------------------------------------------------------------------
# Every kind of every family renders and saves
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("family", list(FAMILY_EXAMPLES))
def test_every_kind_of_every_family_renders(family, kind, tmp_path):
    doc = document(FAMILY_EXAMPLES[family])
    fig = plot_diagram(doc.mechanism, kind, samples=72, title=doc.title)
    assert doc.title in fig.get_suptitle() or doc.title.lower() in fig.get_suptitle().lower()
    assert fig.axes, "at least one panel"
    for ax in fig.axes:
        assert ax.get_ylabel(), "every panel names what it plots"
        assert "(" in ax.get_ylabel(), f"a unit on {ax.get_ylabel()!r}"
        ys = np.concatenate([np.asarray(ln.get_ydata(), float) for ln in ax.get_lines()])
        assert np.isfinite(ys).sum() > 10, "every panel draws data"
    assert fig.axes[-1].get_xlabel() == "input angle θ (°)"

    png = save_figure(fig, tmp_path / f"{kind}.png")
    svg = save_figure(fig, tmp_path / f"{kind}.svg")
    image = mpimg.imread(png)
    height, width = image.shape[:2]
    assert image.ndim == 3 and width >= 1000 and height >= 500
    assert float(np.std(image[..., :3])) > 0.01, "not a blank picture"
    text = svg.read_text(encoding="utf-8")
    assert text.lstrip().startswith("<?xml") and "<svg" in text


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


def test_bad_kind_is_a_diagram_error():
    fb = mechanism("crank-rocker")
    for bad in ("speed", "", None, 3):
        with pytest.raises(DiagramError, match="kind must be one of angles, velocity"):
            plot_diagram(fb, bad)


def test_a_fourbar_that_cannot_assemble_is_a_diagram_error():
    never = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    for kind in KINDS:
        with pytest.raises(DiagramError, match="cannot be assembled at any input"):
            plot_diagram(never, kind, samples=24)


def test_a_spherical_fourbar_that_cannot_assemble_is_a_diagram_error():
    never = SphericalFourBar(*np.radians([90, 10, 20, 30]))
    with pytest.raises(DiagramError, match="cannot be assembled at any input"):
        plot_diagram(never, "angles", samples=24)


def test_linkages_with_a_triad_have_diagrams():
    """Driven at FG (or a planar Stephenson III at its output) the coupler is a triad: its
    binary links' angles are drawn over every circuit, and each angle's rate is the derivative
    of the angle (a second method: central differences of the drawn curve)."""
    sph = dataclasses.replace(mechanism("paper001-stephenson3"), input="FG")
    plot_diagram(sph, "velocity", samples=24)
    planar = dataclasses.replace(mechanism("stephenson3-example"), input="output")
    fig = plot_diagram(planar, "angles", samples=24)
    assert fig.axes


def test_batches_and_bad_sample_counts_are_diagram_errors():
    batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1.0, 1.2], coupler=5, rocker=3.5)
    with pytest.raises(DiagramError, match="one linkage at a time"):
        plot_diagram(batch, "angles", samples=24)
    fb = mechanism("crank-rocker")
    for bad in (3, 0, 12.5, True):
        with pytest.raises(DiagramError, match="samples"):
            plot_diagram(fb, "angles", samples=bad)


# --------------------------------------------------------------------------------------------
# The numbers
# --------------------------------------------------------------------------------------------


def _phi3(fb: FourBar, theta: np.ndarray, assembly: float | None = None) -> np.ndarray:
    """φ3 from the solved positions: the angle of B − B0 from the frame line (unwrapped)."""
    m = fb if assembly is None else fb.with_assembly(assembly)
    b = solve(m, theta, order=0).positions["B"] - np.asarray(fb.B0, float)
    e = np.asarray(fb.B0, float) - np.asarray(fb.A0, float)
    return np.unwrap(np.arctan2(b[:, 1], b[:, 0]) - math.atan2(e[1], e[0]))


def test_crank_rocker_k_omega_is_paper003_eq3_on_a_finite_difference():
    """Kω(θ) = φ3′·φΨ/Ψ (paper 003, eq. 3): φ3′ by central differences of the solved output,
    Ψ and φΨ from the output's extremes on a dense grid (the crank turning between them on the
    arc through φ1 = 0)."""
    fb = mechanism("crank-rocker")
    fig = plot_diagram(fb, "coefficients", samples=N)
    x, k_omega = only(fig.axes[0], "Kω")
    theta = np.radians(x)
    fd = central(lambda t: _phi3(fb, t), theta)

    grid = np.linspace(0.0, 2.0 * np.pi, 200_001)
    phi = _phi3(fb, grid)
    lo, hi = int(np.argmin(phi)), int(np.argmax(phi))
    psi = phi[hi] - phi[lo]
    ccw = (grid[hi] - grid[lo]) % (2.0 * np.pi)
    through_zero = (0.0 - grid[lo]) % (2.0 * np.pi) < ccw
    phi_psi = ccw if through_zero else 2.0 * np.pi - ccw
    np.testing.assert_allclose(k_omega, fd * phi_psi / psi, rtol=0, atol=2e-4)
    # The line reaches the exact maximum the analysis reports (to the sampling's resolution).
    exact = float(coefficients(fb)["K_omega"])
    assert np.nanmax(np.abs(k_omega)) <= exact * (1 + 1e-9)
    assert np.nanmax(np.abs(k_omega)) >= exact * (1 - 5e-3)


def test_crank_rocker_k_epsilon_is_a_second_difference():
    fb = mechanism("crank-rocker")
    co = {k: float(v) for k, v in coefficients(fb).items()}
    fig = plot_diagram(fb, "coefficients", samples=N)
    x, k_eps = only(fig.axes[1], "Kε")
    theta = np.radians(x)
    h = 1e-4
    second = (_phi3(fb, theta + h) - 2 * _phi3(fb, theta) + _phi3(fb, theta - h)) / h**2
    np.testing.assert_allclose(k_eps, second * co["phi_psi"] ** 2 / co["psi"], rtol=0, atol=1e-4)
    x, k_p = only(fig.axes[2], "Kp")
    _, k_omega = only(fig.axes[0], "Kω")
    np.testing.assert_allclose(k_p, k_omega * k_eps, rtol=1e-12, atol=0)


def test_double_crank_k_omega_is_the_plain_derivative():
    """A double crank: Kω = φ3′ and Kε = 2π·φ3″ (paper 003, after eq. 7)."""
    fb = mechanism("double-crank")
    fig = plot_diagram(fb, "coefficients", samples=N)
    x, k_omega = only(fig.axes[0], "Kω")
    theta = np.radians(x)
    np.testing.assert_allclose(k_omega, central(lambda t: _phi3(fb, t), theta), atol=1e-6)
    x, k_eps = only(fig.axes[1], "Kε")
    h = 1e-4
    second = (_phi3(fb, theta + h) - 2 * _phi3(fb, theta) + _phi3(fb, theta - h)) / h**2
    np.testing.assert_allclose(k_eps, 2 * np.pi * second, atol=1e-4)


def test_rocking_input_draws_each_leg_on_its_own_branch():
    """Driven at a rocker, paper 003's coefficients do not apply: the analogue φ3′ is drawn,
    each leg on the assembly the circuit runs there, its ends at the exact limits."""
    fb = mechanism("rocker-input")
    fig = plot_diagram(fb, "coefficients", samples=N)
    legs = series(fig.axes[0], "φ3")
    arcs = input_range(fb)
    assert len(legs) == 2 * int(arcs.count)
    limits = np.degrees(np.concatenate([arcs.lo, arcs.hi]))
    for x, y in legs:
        # Each leg runs from limit to limit.
        assert np.min(np.abs(limits - x[0])) < 1e-9 and np.min(np.abs(limits - x[-1])) < 1e-9
        theta = np.radians(x)
        inner = (
            np.isfinite(y)
            & (np.abs(np.degrees(theta) - x[0]) > 1)
            & (np.abs(np.degrees(theta) - x[-1]) > 1)
        )
        fits = [
            np.allclose(
                y[inner],
                central(lambda t, s=s: _phi3(fb, t, s), theta[inner], h=1e-6),
                atol=1e-4,
                rtol=1e-5,
            )
            for s in (1.0, -1.0)
        ]
        assert sum(fits) == 1, "each leg on exactly one branch"
    marked = sorted(
        float(ln.get_xdata()[0]) for ln in fig.axes[0].get_lines() if ln.get_label() == "_limit"
    )
    np.testing.assert_allclose(marked, np.sort(limits), atol=1e-9)


def _point(m, joint: str):
    return lambda t: solve(m, t, order=0).positions[joint]


def test_traced_point_velocity_is_a_finite_difference_of_positions():
    fb = mechanism("crank-rocker")
    fig = plot_diagram(fb, "velocity", samples=N)
    x, speed = only(fig.axes[0], "P")
    theta = np.radians(x)
    fd = central(_point(fb, "P"), theta)
    np.testing.assert_allclose(speed, np.linalg.norm(fd, axis=-1), rtol=0, atol=1e-7)
    _, vx = only(fig.axes[1], "P")
    _, vy = only(fig.axes[2], "P")
    np.testing.assert_allclose(vx, fd[:, 0], atol=1e-7)
    np.testing.assert_allclose(vy, fd[:, 1], atol=1e-7)
    # The output's velocity ratio on the last panel is φ3′.
    _, ratio = only(fig.axes[3], "φ3")
    np.testing.assert_allclose(ratio, central(lambda t: _phi3(fb, t), theta), atol=1e-7)


def test_traced_point_acceleration_is_a_second_difference_of_positions():
    fb = mechanism("crank-rocker")
    fig = plot_diagram(fb, "acceleration", samples=N)
    x, acc = only(fig.axes[0], "P")
    theta = np.radians(x)
    p, h = _point(fb, "P"), 1e-4
    second = (p(theta + h) - 2 * p(theta) + p(theta - h)) / h**2
    np.testing.assert_allclose(acc, np.linalg.norm(second, axis=-1), atol=1e-5)


def test_spherical_point_speed_is_the_arc_rate_of_the_unit_vector():
    fb = mechanism("paper000-fig6-crank-rocker")
    fig = plot_diagram(fb, "velocity", samples=N)
    x, speed = only(fig.axes[0], "P")
    theta = np.radians(x)
    p, h = _point(fb, "P"), 1e-6
    # The arc between neighbouring samples over their input step: the speed on the sphere.
    a, b = p(theta + h), p(theta - h)
    arc = np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))
    np.testing.assert_allclose(speed, arc / (2 * h), atol=1e-5)


def test_fourbar_transmission_angle_is_the_law_of_cosines():
    fb = mechanism("crank-rocker")
    fig = plot_diagram(fb, "angles", samples=N)
    x, gamma = only(fig.axes[1], "γ")
    theta = np.radians(x)
    a = np.stack((np.cos(theta), np.sin(theta)), axis=-1) * float(fb.crank)
    d2 = np.sum((a - np.asarray(fb.B0, float)) ** 2, axis=-1)
    l2, l3 = float(fb.coupler), float(fb.rocker)
    expected = np.degrees(np.arccos((l2**2 + l3**2 - d2) / (2 * l2 * l3)))
    np.testing.assert_allclose(gamma, expected, atol=1e-9)
    assert any(np.allclose(ln.get_ydata(), 90.0) for ln in fig.axes[1].get_lines())


def test_spherical_pressure_angles_match_paper003_closed_forms():
    """At φ1 = 0 and 180° the normal component takes paper 003's closed-form extremes, at the
    balanced μ that the subtitle states."""
    fb = mechanism("paper000-fig6-crank-rocker")
    fig = plot_diagram(fb, "angles", samples=N)
    from linkwright.analysis import balanced_mu

    mu = float(balanced_mu(fb))
    assert f"μ = OB/OA = {mu:.4g}" in " ".join(fig.axes[0].get_title().split())
    x, nu_n = only(fig.axes[2], "ν_n (normal)")
    closed = paper003_normal_extremes(fb, mu)
    at0, at180 = np.argmin(np.abs(x - 0.0)), np.argmin(np.abs(x - 180.0))
    assert abs(x[at0]) < 1e-9 and abs(x[at180] - 180.0) < 1e-9
    assert math.isclose(nu_n[at0], math.degrees(float(closed["min"])), abs_tol=1e-9)
    assert math.isclose(nu_n[at180], math.degrees(float(closed["max"])), abs_tol=1e-9)


def test_sixbar_output_rate_is_a_finite_difference_of_the_last_link():
    """Stephenson III: the output is the link D0D; its ω ratio is d/dθ of the solved angle."""
    m = mechanism("stephenson3-example")
    fig = plot_diagram(m, "velocity", samples=N)
    x, ratio = only(fig.axes[3], "D0–D")
    theta = np.radians(x)

    def angle(t):
        d = solve(m, t, order=0).positions["D"] - np.asarray(m.D0, float)
        return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))

    np.testing.assert_allclose(ratio, central(angle, theta), atol=1e-7)


def test_spherical_sixbar_output_rate_is_a_finite_difference():
    """Paper 000's six-bar: the output E0E turns about E0; its rate from solved positions."""
    m = mechanism("paper000-fig8-sixbar")
    fig = plot_diagram(m, "coefficients", samples=N)
    x, rate = only(fig.axes[0], "E about E0")
    theta = np.radians(x)
    e0 = m.params()["E0"]

    def angle(t):
        e = solve(m, t, order=0).positions["E"]
        # Angle about E0 in any fixed frame normal to it: only its derivative is compared.
        u = np.cross(e0, [0.0, 0.0, 1.0])
        u /= np.linalg.norm(u)
        v = np.cross(e0, u)
        return np.unwrap(np.arctan2(e @ v, e @ u))

    np.testing.assert_allclose(rate, central(angle, theta), atol=1e-6)


def test_double_slider_travel_is_paper004_eq2():
    """R runs t = (p + q)·sin(θ − β)/sin α from M (paper 004, eq. 2)."""
    m = mechanism("elliptic-trammel")
    assert isinstance(m, DoubleSlider)
    fig = plot_diagram(m, "angles", samples=N)
    x, travel = only(fig.axes[0], "slider R")
    theta = np.radians(x)
    p, q, a, b = (float(v) for v in (m.p, m.q, m.alpha, m.beta))
    np.testing.assert_allclose(travel, (p + q) * np.sin(theta - b) / np.sin(a), atol=1e-12)


def test_linkage_links_of_one_body_are_drawn_once():
    """Jansen's leg: the triangles B–C–D and E–F–G are rigid, so their links turn together and
    each is one line; six bodies turn (besides the crank)."""
    fig = plot_diagram(mechanism("jansen-leg"), "coefficients", samples=72)
    labels = [ln.get_label() for ln in fig.axes[0].get_lines() if ln.get_label()[0] != "_"]
    assert len(labels) == 6
    assert any("body B–C–D" in lab for lab in labels)
    assert any("body E–F–G" in lab for lab in labels)
    # Triangle B–C–D is rigid: the angle between B→C and B→D is the same at every input.
    m = mechanism("jansen-leg")
    (_, motion), *_ = configurations(m, np.linspace(0, 2 * np.pi, 7), order=0)
    p = motion.positions
    u, w = p["C"] - p["B"], p["D"] - p["B"]
    between = np.arctan2(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0], np.sum(u * w, axis=-1))
    assert np.ptp(between[np.isfinite(between)]) < 1e-9


def test_full_turn_spans_360_degrees_and_rocking_marks_limits():
    fig = plot_diagram(mechanism("crank-rocker"), "angles", samples=36)
    lo, hi = fig.axes[-1].get_xlim()
    assert math.isclose(hi - lo, 360.0)
    fig = plot_diagram(mechanism("rocker-input"), "velocity", samples=N)
    notes = [t.get_text() for t in fig.axes[0].texts]
    assert sum(t.startswith("limit ") for t in notes) == 4
    legend = fig.axes[0].get_legend()
    assert "axis clipped" in legend.get_title().get_text()


# --------------------------------------------------------------------------------------------
# A property: random crank-rockers
# --------------------------------------------------------------------------------------------


@settings(max_examples=5, deadline=None)
@given(
    frame=st.floats(3.0, 4.5),
    coupler=st.floats(4.0, 6.0),
    rocker=st.floats(2.5, 5.0),
)
def test_k_omega_line_never_exceeds_the_exact_maximum(frame, coupler, rocker):
    """For any crank-rocker (crank 1 the shortest, Grashof), the sampled |Kω| stays below the
    exact maximum of paper 003's eq. 4 and the line is φ3′ times the constant φΨ/Ψ."""
    links = sorted([1.0, frame, coupler, rocker])
    assume(links[0] + links[3] < links[1] + links[2] - 1e-3)  # Grashof, crank 1 the shortest
    fb = FourBar(A0=[0, 0], B0=[frame, 0], crank=1.0, coupler=coupler, rocker=rocker)
    assert bool(input_range(fb).full)
    co = {k: float(v) for k, v in coefficients(fb).items()}
    fig = plot_diagram(fb, "coefficients", samples=72)
    x, k_omega = only(fig.axes[0], "Kω")
    assert np.nanmax(np.abs(k_omega)) <= co["K_omega"] * (1 + 1e-9)
    theta = np.radians(x)
    fd = central(lambda t: _phi3(fb, t), theta)
    np.testing.assert_allclose(k_omega, fd * co["phi_psi"] / co["psi"], atol=1e-5)

"""Pictures of spherical linkages: they render headless for every spherical family (and for a
linkage that never assembles), draw the joints where the engine puts them, and the great-circle
sampler stays on the sphere."""

from __future__ import annotations

import ast
import inspect
import math

import matplotlib.image as mpimg
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from linkwright.geometry import sphere
from linkwright.mechanisms import (
    FourBar,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
    circuit,
    solve,
)
from linkwright.plot import save_figure
from linkwright.plot import sphere as sphere_plot
from linkwright.plot.sphere import (
    SpherePlotError,
    default_view,
    great_arc,
    plot_spherical_curves,
    plot_spherical_linkage,
)

N = 120  # circuit samples in these tests: enough to check, fast to draw

FOURBAR = SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]))  # paper 000, Fig. 6
SIXBAR = SphericalSixBar(  # paper 000, Fig. 8, the reading that turns fully
    *np.radians([35, 20, 42, 30, 72, 22, 45, 33, 85, -30, 30, 75]), assembly=-1
)
SIXBAR_ROCKING = SphericalSixBar(*np.radians([35, 20, 42, 30, 72, 22, 45, 33, 85, 30, 30, 75]))
STEPHENSON3 = SphericalStephenson3(*np.radians([60, 20, 50, 40, 30, 100, 50, 40, 50]))
NEVER = SphericalFourBar(*np.radians([90, 10, 20, 30]))  # crank + coupler + rocker < frame

MECHANISMS = {
    "fourbar": FOURBAR,
    "sixbar": SIXBAR,
    "sixbar_rocking": SIXBAR_ROCKING,
    "stephenson3": STEPHENSON3,
    "never": NEVER,
}


def labels(ax) -> set[str]:
    return {t.get_text() for t in ax.texts}


def markers_at(ax, xy, marker) -> list:
    """Lines drawn as a single marker at page point ``xy``."""
    return [
        ln
        for ln in ax.lines
        if ln.get_marker() == marker
        and len(ln.get_xdata()) == 1
        and np.allclose([ln.get_xdata()[0], ln.get_ydata()[0]], xy, atol=1e-12)
    ]


@pytest.fixture(scope="module")
def figures():
    return {name: plot_spherical_linkage(m, samples=N) for name, m in MECHANISMS.items()}


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_renders_to_png(figures, tmp_path, name):
    fig = figures[name]
    path = save_figure(fig, tmp_path / f"{name}.png")
    image = mpimg.imread(path)
    width, height = fig.get_size_inches()
    assert image.shape == (round(height * 150), round(width * 150), 4)
    assert image[..., :3].std() > 0.05  # a drawing, not a blank canvas
    assert isinstance(fig.canvas, FigureCanvasAgg)


@pytest.mark.parametrize("name", ["fourbar", "sixbar", "sixbar_rocking", "stephenson3"])
def test_every_joint_is_labelled_and_every_traced_path_drawn(figures, name):
    m = MECHANISMS[name]
    ax = figures[name].axes[0]
    assert set(m.plan.joints) <= labels(ax)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    for joint in m.plan.traced:
        assert f"path of {joint}" in legend
    assert "cannot be assembled" not in ax.get_title()


def test_rocking_linkage_says_so_and_marks_its_limits(figures):
    ax = figures["sixbar_rocking"].axes[0]
    assert "input rocks over [−37.5°, 235.7°]" in ax.get_title()
    assert "limit positions" in [t.get_text() for t in ax.get_legend().get_texts()]
    assert "input turns fully" in figures["sixbar"].axes[0].get_title()


def test_never_assembling_linkage_draws_its_ground_pivots_and_says_so(figures):
    ax = figures["never"].axes[0]
    assert "cannot be assembled at any input" in ax.get_title()
    assert labels(ax) >= {"A0", "B0"} and not labels(ax) & {"A", "B", "P"}
    assert sum(ln.get_marker() == "^" for ln in ax.lines) == 2


def test_joints_are_drawn_where_the_engine_puts_them():
    # Seen from +X with +Z up the page shows (y, z): right = Z × X = +Y, up = X × Y = +Z.
    at = math.radians(50)
    fig = plot_spherical_linkage(FOURBAR, samples=N, at=at, view=[1, 0, 0], up=[0, 0, 1])
    ax = fig.axes[0]
    pos = solve(FOURBAR, [at], order=0).positions
    for name in ("A", "B", "P"):
        p = pos[name][0]
        assert markers_at(ax, (p[1], p[2]), "o"), name
    for name in ("A0", "B0"):
        p = pos[name][0]
        assert markers_at(ax, (p[1], p[2]), "^"), name
    assert "pose at θ = 50.0°" in ax.get_title()


def test_traced_path_is_the_circuit_split_at_the_rim():
    # Seen from +X: near parts have x ≥ 0. Every drawn point of the path, solid or dashed,
    # is the projection of a circuit point (or of a rim crossing between two of them).
    fig = plot_spherical_linkage(FOURBAR, samples=N, view=[1, 0, 0], up=[0, 0, 1])
    ax = fig.axes[0]
    path = circuit(FOURBAR, N, order=0).positions["P"]
    solid = next(ln for ln in ax.lines if ln.get_label() == "path of P")
    xy = np.column_stack([solid.get_xdata(), solid.get_ydata()])
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    projected = path[:, 1:]
    nearest = np.min(np.linalg.norm(xy[:, None, :] - projected[None], axis=-1), axis=1)
    on_rim = np.abs(np.hypot(xy[:, 0], xy[:, 1]) - 1.0) < 1e-12
    assert np.all((nearest < 1e-12) | on_rim)


def test_a_curve_on_the_far_side_is_dashed_only_and_on_the_near_side_solid_only():
    u = np.linspace(0.0, 2 * np.pi, 50)
    ring = np.stack([np.full_like(u, 0.9), 0.1 * np.cos(u), 0.1 * np.sin(u)], axis=-1)
    ring = sphere.unit(ring)
    for view, near_drawn in (([1, 0, 0], True), ([-1, 0, 0], False)):
        ax = plot_spherical_curves([("ring", ring)], view=view).axes[0]
        solid = next(ln for ln in ax.lines if ln.get_label() == "ring")
        dashed = ax.lines[ax.lines.index(solid) + 1]
        assert np.any(np.isfinite(solid.get_xdata())) == near_drawn
        assert np.any(np.isfinite(dashed.get_xdata())) != near_drawn


def test_extra_curves_and_an_existing_axes():
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    other = circuit(SphericalFourBar(*np.radians([40, 20, 45, 35, 50, 130]), assembly=-1), N)
    out = plot_spherical_linkage(
        FOURBAR, samples=N, ax=ax, extra_curves=[("other mode", other.positions["P"])]
    )
    assert out is fig and fig.axes == [ax]
    assert "other mode" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_default_view_keeps_the_linkage_in_front():
    for m in (FOURBAR, SIXBAR, STEPHENSON3):
        v = default_view(m)
        assert abs(np.linalg.norm(v) - 1.0) < 1e-12
        motion = circuit(m, N, order=0)
        ground = [p[0] for name, p in motion.positions.items() if name in ("A0", "B0", "E0")]
        assert all(float(g @ v) > 0 for g in ground)
        share = np.mean([np.mean(p @ v > 0) for p in motion.positions.values()])
        assert share > 0.95


def test_stephenson3_driven_at_fg_is_drawn_with_its_triad(tmp_path):
    """Driven at FG the coupler BCE is a triad: drawn as a filled ternary link, on every
    circuit of every configuration."""
    m = SphericalStephenson3(*np.radians([60, 20, 50, 40, 30, 100, 50, 40, 50]), input="FG")
    fig = plot_spherical_linkage(m)
    save_figure(fig, tmp_path / "fg.png")
    assert mpimg.imread(tmp_path / "fg.png").shape[0] > 100
    assert ("C", "B", "E") in m.plan.plates


PLANAR = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
BATCH = SphericalFourBar(np.radians([40, 41]), *np.radians([20, 45, 35]))


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: plot_spherical_linkage(PLANAR), "planar"),
        (lambda: plot_spherical_linkage(BATCH), "batch"),
        (lambda: default_view(BATCH), "batch"),
        (lambda: plot_spherical_linkage(FOURBAR, view=[0, 0, 0]), "view"),
        (lambda: plot_spherical_linkage(FOURBAR, view=[1, 0]), "view"),
        (lambda: plot_spherical_linkage(FOURBAR, up=[0, 0, 0]), "up"),
        (lambda: plot_spherical_linkage(FOURBAR, extra_curves=[("x", [[2.0, 0, 0]])]), "unit"),
        (lambda: plot_spherical_curves([("x", np.zeros((3, 2)))]), "shape"),
        (lambda: plot_spherical_curves([("x", [[np.inf, 0, 0]])]), "infinite"),
        (lambda: great_arc([1.0, 0, 0], [-1.0, 0, 0]), "antipodal"),
        (lambda: great_arc([0.0, 0, 0], [1.0, 0, 0]), "zero vector"),
        (lambda: great_arc([1.0, 0, 0], [0, 1.0, 0], samples=1), "samples"),
        (lambda: great_arc([1.0, 0, 0], [0, 1.0, np.nan]), "finite"),
    ],
)
def test_bad_input_is_a_clear_error(call, match):
    with pytest.raises(SpherePlotError, match=match):
        call()


def test_no_pyplot():
    tree = ast.parse(inspect.getsource(sphere_plot))
    imported = [
        alias.name if isinstance(node, ast.Import) else f"{node.module}.{alias.name}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        for alias in node.names
    ]
    assert not [name for name in imported if "pyplot" in name or name.endswith(".use")]


# --------------------------------------------------------------------------------------------
# The great-circle sampler
# --------------------------------------------------------------------------------------------

unit_vectors = (
    st.tuples(*[st.floats(-1, 1)] * 3).map(np.array).filter(lambda v: np.linalg.norm(v) > 1e-3)
)


@settings(max_examples=300, deadline=None)
@given(unit_vectors, unit_vectors, st.integers(2, 200))
def test_great_arc_stays_on_the_sphere_and_hits_both_ends(a, b, n):
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    omega = float(sphere.arc(a, b))
    assume(omega < math.pi - 1e-6)
    pts = great_arc(a, b, n)
    assert pts.shape == (n, 3)
    assert np.max(np.abs(sphere.norm(pts) - 1.0)) < 1e-15
    np.testing.assert_allclose(pts[0], a, atol=1e-15, rtol=0)
    np.testing.assert_allclose(pts[-1], b, atol=1e-15, rtol=0)
    # Evenly spaced along the shorter arc, on the one great circle through a and b (the
    # closed form: each sample at angle k·Ω/(n − 1) from a, and (n − 1 − k)·Ω/(n − 1) from b).
    k = np.arange(n)
    step = omega / (n - 1)
    np.testing.assert_allclose(sphere.arc(pts, a), k * step, atol=1e-7, rtol=1e-12)
    np.testing.assert_allclose(sphere.arc(pts, b), (n - 1 - k) * step, atol=1e-7, rtol=1e-12)
    if omega > 1e-6:
        normal = sphere.unit(sphere.cross(a, b))
        assert np.max(np.abs(pts @ normal)) < 1e-15 / math.sin(min(omega, 1.0)) + 1e-15


def test_great_arc_is_vectorised_and_handles_equal_ends():
    a = np.array([[1.0, 0, 0], [0, 0, 1.0]])
    b = np.array([[0, 1.0, 0], [0, 0, 1.0]])
    pts = great_arc(a, b, 5)
    assert pts.shape == (2, 5, 3)
    np.testing.assert_allclose(pts[0, 2], [math.sqrt(0.5), math.sqrt(0.5), 0], atol=1e-15)
    np.testing.assert_array_equal(pts[1], np.tile([0, 0, 1.0], (5, 1)))


def test_annotated_view_draws_both_modes_and_marks_dead_centres():
    # Seen from +X with +Z up the page shows (y, z); the dead centres' markers are P where the
    # crank and coupler are in line: arc A0B = 45° ± 20° (found here on solve()'s positions).
    fig = plot_spherical_linkage(FOURBAR, samples=N, view=[1, 0, 0], up=[0, 0, 1], annotate=True)
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert {"assembly +1", "assembly \N{MINUS SIGN}1", "dead centres (output stationary)"} <= set(
        legend
    )
    (dead,) = [ln for ln in ax.lines if ln.get_label() == "dead centres (output stationary)"]
    thetas = np.linspace(-np.pi, np.pi, 20001)
    pos = solve(FOURBAR, thetas, order=0).positions
    arc = np.degrees(np.arccos(np.clip(np.sum(pos["A0"] * pos["B"], axis=1), -1, 1)))
    for target in (25.0, 65.0):
        i = int(np.argmin(np.abs(arc - target)))
        p = pos["P"][i]
        assert np.min(np.hypot(*(dead.get_xydata() - [p[1], p[2]]).T)) < 1e-3

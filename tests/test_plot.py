"""Pictures: they render headless, save as readable PNG/SVG, and draw what the engine computed."""

from __future__ import annotations

import ast
import inspect
import math
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from linkwright.mechanisms import FourBar, SliderCrank, circuit, solve
from linkwright.plot import draw_linkage, plot_curves, plot_diagrams, save_figure

MINUS = "\N{MINUS SIGN}"
N = 240  # samples per circuit in these tests: enough to check, fast to draw

MECHANISMS = {
    "crank_rocker": FourBar(A0=[0, 0], B0=[3.5, 0], crank=1, coupler=5, rocker=6.02, u=2.5, v=1.5),
    "rocker_input": FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1, u=2, v=1),
    "non_grashof": FourBar(A0=[0, 0], B0=[4.5, 0], crank=2.5, coupler=2, rocker=3, u=1, v=0.6),
    "inline_slider": SliderCrank(A0=[0, 0], crank=1, rod=3, u=1.5, v=0.3),
    "offset_slider": SliderCrank(
        A0=[0, 0], line_point=[0, -0.5], line_angle=0, crank=1, rod=3, u=1.5, v=0.8
    ),
    "cannot_assemble": FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3),
}


def line(ax, label):
    """The one Line2D on ``ax`` with this label."""
    found = [ln for ln in ax.lines if ln.get_label() == label]
    assert len(found) == 1, [ln.get_label() for ln in ax.lines]
    return found[0]


def texts(fig: Figure) -> list[str]:
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def close_up(a, b, atol=1e-12):
    np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), atol=atol, rtol=0)


@pytest.fixture(scope="module")
def figures():
    """Both figures of every example, drawn once for the module."""
    return {
        name: (plot_curves(m, samples=N, title=name), plot_diagrams(m, samples=N))
        for name, m in MECHANISMS.items()
    }


@pytest.mark.parametrize(("index", "name"), list(enumerate(MECHANISMS)))
def test_figures_save_as_png_and_svg(figures, tmp_path, index, name):
    # Each linkage writes one figure as PNG and the other as SVG, alternating between linkages,
    # so every figure kind meets both formats while the suite stays fast.
    curves, diagrams = figures[name]
    as_png, as_svg = (curves, diagrams) if index % 2 == 0 else (diagrams, curves)
    png = save_figure(as_png, tmp_path / "deep" / "er" / f"{name}.png")
    svg = save_figure(as_svg, str(tmp_path / f"{name}.svg"))
    assert png == tmp_path / "deep" / "er" / f"{name}.png" and png.is_file() and svg.is_file()
    width, height = as_png.get_size_inches()
    image = mpimg.imread(png)
    assert image.shape == (round(height * 150), round(width * 150), 4)
    assert png.stat().st_size > 20_000  # a drawing, not a blank canvas
    assert image[..., :3].std() > 0.05
    root = ET.parse(svg).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert svg.stat().st_size > 30_000
    assert len(list(root.iter("{http://www.w3.org/2000/svg}path"))) > 20


@pytest.mark.parametrize("name", [n for n in MECHANISMS if n != "cannot_assemble"])
def test_coupler_curves_are_the_circuits_of_both_assembly_modes(figures, name):
    mech = MECHANISMS[name]
    ax = figures[name][0].axes[0]
    for sign, label in ((1, "assembly +1"), (-1, f"assembly {MINUS}1")):
        xy = line(ax, label).get_xydata()
        expected = circuit(mech.with_assembly(sign), N).positions["P"]
        close_up(xy[:-1], expected)
        close_up(xy[-1], xy[0])  # drawn closed
    assert ax.get_aspect() == 1.0
    # The legend sits under the drawing, where it cannot hide a curve.
    (legend,) = figures[name][0].legends
    assert {"assembly +1", f"assembly {MINUS}1"} <= {t.get_text() for t in legend.get_texts()}
    assert legend.get_window_extent().y1 <= ax.get_window_extent().y0
    assert figures[name][0].get_suptitle().endswith(name)


def test_own_assembly_is_solid_and_the_other_dashed(figures):
    ax = figures["crank_rocker"][0].axes[0]
    own, other = line(ax, "assembly +1"), line(ax, f"assembly {MINUS}1")
    assert own.get_linestyle() == "-"
    assert other.get_linestyle() != "-"
    assert own.get_color() != other.get_color()
    # A mechanism given on assembly −1 draws that one solid.
    fig = plot_curves(MECHANISMS["crank_rocker"].with_assembly(-1), samples=90)
    assert line(fig.axes[0], f"assembly {MINUS}1").get_linestyle() == "-"


def test_limit_positions_marked_where_the_input_rocks(figures):
    mech = MECHANISMS["rocker_input"]
    fig = figures["rocker_input"][0]
    m = circuit(mech, N)
    upper = math.ceil(N / 2)
    close_up(line(fig.axes[0], "input limit positions").get_xydata(), m.positions["P"][[0, upper]])
    notes = "\n".join(texts(fig))
    lo, hi = np.degrees(m.input[[0, upper]])
    assert f"limit θ = {lo:.1f}°" in notes and f"limit θ = {hi:.1f}°" in notes
    assert "113.1" in notes and "246.9" in notes
    # A crank that turns fully has no limit positions.
    labels = [ln.get_label() for ln in figures["crank_rocker"][0].axes[0].lines]
    assert "input limit positions" not in labels
    assert "limit θ" not in "\n".join(texts(figures["crank_rocker"][0]))


def test_transmission_angle_extremes_are_annotated(figures):
    # Crank-rocker: γ from the law of cosines at θ = 0 (|AB0| = 2.5) and θ = π (|AB0| = 4.5).
    c, r = 5.0, 6.02
    gmin = math.degrees(math.acos((c * c + r * r - 2.5**2) / (2 * c * r)))
    gmax = math.degrees(math.acos((c * c + r * r - 4.5**2) / (2 * c * r)))
    notes = "\n".join(texts(figures["crank_rocker"][0]))
    assert f"γmin = {gmin:.1f}°" in notes and f"γmax = {gmax:.1f}°" in notes
    # Offset slider-crank: the rod is steepest at θ = 90° (rise 1.5 over 3) and flattest
    # past the line at θ = 270° (0.5 over 3): γ = 60° and 90° + asin(1/6).
    notes = "\n".join(texts(figures["offset_slider"][0]))
    assert "γmin = 60.0°" in notes
    assert f"γmax = {90 + math.degrees(math.asin(1 / 6)):.1f}°" in notes
    marks = [ln for ln in figures["offset_slider"][0].axes[0].lines if ln.get_marker() in "v^"]
    m = circuit(MECHANISMS["offset_slider"], N)
    close_up(marks[0].get_xydata()[0], m.positions["P"][N // 4])  # θ = 90°
    close_up(marks[1].get_xydata()[0], m.positions["P"][3 * N // 4])  # θ = 270°


def test_linkage_drawn_at_the_first_sample_by_default(figures):
    mech = MECHANISMS["rocker_input"]
    ax = figures["rocker_input"][0].axes[0]
    m = circuit(mech, N)
    (plate,) = [p for p in ax.patches if str(p.get_label()).startswith("linkage at")]
    assert plate.get_label() == "linkage at θ = 113.1°"
    close_up(plate.get_xy()[:3], np.stack([m.positions[k][0] for k in "ABP"]), atol=1e-9)


def test_cannot_assemble(figures):
    curves, diagrams = figures["cannot_assemble"]
    labels = [ln.get_label() for ln in curves.axes[0].lines]
    assert not any(lab.startswith("assembly") for lab in labels)
    assert "cannot assemble at θ = 0.0°" in texts(curves)
    assert texts(diagrams).count("cannot assemble at any input") == 3
    fig = Figure()
    drawn = draw_linkage(fig.add_subplot(), MECHANISMS["cannot_assemble"], 1.0)
    assert sorted(drawn) == ["A0", "B0"]
    assert "cannot assemble at θ = 57.3°" in texts(fig)


def test_draw_linkage_draws_the_solved_pose():
    mech = MECHANISMS["crank_rocker"]
    fig = Figure()
    ax = fig.add_subplot()
    drawn = draw_linkage(ax, mech, 0.7)
    m = solve(mech, [0.7])
    for k in ("A0", "B0", "A", "B", "P"):
        close_up(drawn[k], m.positions[k][0])
    (plate,) = [p for p in ax.patches if str(p.get_label()).startswith("linkage at")]
    close_up(plate.get_xy()[:3], [drawn["A"], drawn["B"], drawn["P"]])
    letters = {t.get_text() for t in ax.texts}
    assert letters == {"$A_0$", "$B_0$", "$A$", "$B$", "$P$"}
    hatched = [p for p in ax.patches if isinstance(p, Polygon) and p.get_hatch()]
    assert len(hatched) == 2  # the two ground pivots


def test_draw_linkage_follows_the_branch_of_the_motion():
    mech = MECHANISMS["crank_rocker"]
    other = mech.with_assembly(-1)
    thetas = np.linspace(0.0, 2.0 * np.pi, 36, endpoint=False)
    motion = solve(other, thetas)
    for theta in (thetas[5], thetas[5] + 0.01):  # on a sample, and between samples
        drawn = draw_linkage(Figure().add_subplot(), mech, theta, motion=motion)
        close_up(drawn["B"], solve(other, [theta]).positions["B"][0], atol=1e-12)


def test_slider_drawn_on_its_guide():
    mech = MECHANISMS["offset_slider"]
    ax = Figure().add_subplot()
    drawn = draw_linkage(ax, mech, 0.3)
    guide = line(ax, "_guide")
    assert guide.get_linestyle() == "--"
    assert np.allclose(guide.get_ydata(), -0.5)
    assert guide.get_xdata().min() < drawn["B"][0] < guide.get_xdata().max()
    block = [
        p
        for p in ax.patches
        if isinstance(p, Polygon)
        and not p.get_hatch()
        and not str(p.get_label()).startswith("linkage")
    ]
    assert len(block) == 1
    close_up(block[0].get_xy()[:4].mean(axis=0), drawn["B"], atol=1e-12)


def test_diagrams_of_a_rocking_input_have_two_legs(figures):
    mech = MECHANISMS["rocker_input"]
    fig = figures["rocker_input"][1]
    assert len(fig.axes) == 3
    m = circuit(mech, N)
    upper = math.ceil(N / 2)
    up, back = "up (branch +1)", f"back (branch {MINUS}1)"
    out_up, out_back = line(fig.axes[0], up), line(fig.axes[0], back)
    lo, hi = np.degrees(m.input[[0, upper]])
    close_up(out_up.get_xdata()[[0, -1]], [lo, hi], atol=1e-9)
    close_up(out_back.get_xdata()[[0, -1]], [hi, lo], atol=1e-9)
    # Output: angle of B − B0 from the frame line (here +x), up to whole turns.
    rel = m.positions["B"] - np.array([1.0, 0.0])
    phi = np.degrees(np.arctan2(rel[:, 1], rel[:, 0]))
    drawn = np.r_[out_up.get_ydata(), out_back.get_ydata()[1:]]
    expected = np.r_[phi, phi[0]]
    assert np.allclose((drawn - expected + 180.0) % 360.0 - 180.0, 0.0, atol=1e-9)
    assert np.all(np.abs(np.diff(drawn)) < 180.0)  # unwrapped
    # The legs differ in output though they share inputs.
    assert not np.allclose(out_up.get_ydata(), out_back.get_ydata()[::-1])
    for ax in fig.axes:
        assert {ln.get_label() for ln in ax.lines if not ln.get_label().startswith("_")} == {
            up,
            back,
        }


def test_diagram_values_of_a_full_turn(figures):
    mech = MECHANISMS["crank_rocker"]
    fig = figures["crank_rocker"][1]
    m = circuit(mech, N)
    out, gamma, speed = (line(ax, "full turn") for ax in fig.axes)
    close_up(out.get_xdata()[[0, -1]], [0.0, 360.0])
    assert out.get_ydata()[-1] == pytest.approx(out.get_ydata()[0])  # the rocker comes back
    a_b = m.positions["A"] - m.positions["B"]
    b0_b = m.positions["B0"] - m.positions["B"]
    cos = np.sum(a_b * b0_b, axis=1) / np.linalg.norm(a_b, axis=1) / np.linalg.norm(b0_b, axis=1)
    close_up(gamma.get_ydata()[:-1], np.degrees(np.arccos(cos)), atol=1e-9)
    close_up(speed.get_ydata()[:-1], np.linalg.norm(m.velocities["P"], axis=1))


def test_slider_diagram_shows_slider_position(figures):
    mech = MECHANISMS["inline_slider"]
    fig = figures["inline_slider"][1]
    m = circuit(mech, N)
    close_up(line(fig.axes[0], "full turn").get_ydata()[:-1], mech.slider_position(m))
    gamma = line(fig.axes[1], "full turn").get_ydata()
    # Inline: the rod tilts at most asin(1/3) from the line, either way.
    half = math.degrees(math.asin(1 / 3))
    assert gamma.min() == pytest.approx(90 - half, abs=1e-6)
    assert gamma.max() == pytest.approx(90 + half, abs=1e-6)


def test_save_figure_writes_pdf_and_rejects_other_formats(tmp_path):
    fig = plot_curves(MECHANISMS["crank_rocker"], samples=36)
    pdf = save_figure(fig, tmp_path / "picture.pdf")
    assert pdf.read_bytes().startswith(b"%PDF-")
    with pytest.raises(ValueError, match=r"\.png, \.svg or \.pdf"):
        save_figure(Figure(), tmp_path / "picture.jpg")


def test_batches_are_refused():
    batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1.0, 1.5], coupler=5, rocker=3.5)
    with pytest.raises(ValueError, match="one linkage"):
        plot_curves(batch)


def test_figures_from_threads(tmp_path):
    def render(i):
        mech = MECHANISMS["offset_slider" if i % 2 else "rocker_input"]
        return save_figure(plot_curves(mech, samples=60), tmp_path / f"t{i}.png")

    with ThreadPoolExecutor(max_workers=2) as pool:
        paths = list(pool.map(render, range(2)))
    assert all(mpimg.imread(p).shape[-1] == 4 for p in paths)


def test_no_pyplot():
    """Figures are built on Figure and an Agg canvas: pyplot's global state is never touched."""
    import linkwright.plot.planar as module

    tree = ast.parse(inspect.getsource(module))
    imported = [
        alias.name if isinstance(node, ast.Import) else f"{node.module}.{alias.name}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        for alias in node.names
    ]
    assert not [name for name in imported if "pyplot" in name or name.endswith(".use")]
    assert all(
        isinstance(f.canvas, FigureCanvasAgg)
        for f in (
            plot_curves(MECHANISMS["crank_rocker"], samples=36),
            plot_diagrams(MECHANISMS["crank_rocker"], samples=36),
        )
    )

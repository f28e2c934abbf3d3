"""The main picture (``linkwright plot FILE``): every family renders, and what it marks is where
independent derivations put it: dead centres (crank and coupler in line; the output's rate zero),
limit positions (law of cosines), the pose (solve), and the spherical map (a projection formula
written out here, and the equal-area property of Lambert's projection checked on a cap)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES
from hypothesis import assume, given, settings
from hypothesis import example as pinned
from hypothesis import strategies as st

from linkwright.geometry.sphere import ProjectionError, lambert_azimuthal
from linkwright.io import load_document
from linkwright.mechanisms import (
    FourBar,
    SphericalFourBar,
    SphericalStephenson3,
    Stephenson3,
    Watt2,
    circuit,
    solve,
)
from linkwright.plot import save_figure
from linkwright.plot.generic import find_features
from linkwright.plot.view import PlotError, plot_mechanism

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"
MINUS = "\N{MINUS SIGN}"
N = 120  # circuit samples for the pictures that are only rendered


def example(name: str):
    return load_document(EXAMPLES / f"{name}.toml")


def line(ax, label: str):
    found = [ln for ln in ax.lines if ln.get_label() == label]
    assert len(found) == 1, sorted(ln.get_label() for ln in ax.lines)
    return found[0]


def legend_texts(fig) -> list[str]:
    return [t.get_text() for leg in fig.legends for t in leg.get_texts()]


def notes(fig) -> str:
    return "\n".join(t.get_text() for ax in fig.axes for t in ax.texts)


def same_points(a, b, atol=1e-9):
    """The rows of a and b are the same points, in any order."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, (a.shape, b.shape)
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
    assert d.min(axis=1).max() <= atol and d.min(axis=0).max() <= atol, d


def coupler_point(a, b, coupler, u, v):
    e = (b - a) / coupler
    return a + u * e + v * np.array([-e[1], e[0]])


def circle_meet(c1, r1, c2, r2):
    """Both intersections of two circles (law of cosines along the centre line)."""
    d = np.linalg.norm(c2 - c1)
    x = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    h = math.sqrt(r1 * r1 - x * x)
    e = (c2 - c1) / d
    n = np.array([-e[1], e[0]])
    return [c1 + x * e + h * n, c1 + x * e - h * n]


def cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def crank_rocker_dead_centres(a0, b0, crank, coupler, rocker, u, v, assembly):
    """(B, P, θ) where crank and coupler are in line: |A0 B| = coupler ± crank with B on the
    rocker's circle, on the mechanism's assembly side (sign((B0 − A) × (B − A)))."""
    out = []
    for reach, along in ((coupler + crank, 1.0), (coupler - crank, -1.0)):
        for b in circle_meet(a0, reach, b0, rocker):
            a = a0 + along * crank * (b - a0) / np.linalg.norm(b - a0)
            if np.sign(cross2(b0 - a, b - a)) == assembly:
                theta = math.atan2(a[1] - a0[1], a[0] - a0[0])
                out.append((b, coupler_point(a, b, coupler, u, v), theta))
    return out


@pytest.fixture(scope="module")
def figures():
    return {
        family: plot_mechanism(example(name).mechanism, samples=N, title=example(name).title)
        for family, name in FAMILY_EXAMPLES.items()
    }


@pytest.mark.parametrize("family", list(FAMILY_EXAMPLES))
def test_every_family_renders_as_png_and_svg(figures, tmp_path, family):
    fig = figures[family]
    png = save_figure(fig, tmp_path / f"{family}.png")
    svg = save_figure(fig, tmp_path / f"{family}.svg")
    image = mpimg.imread(png)
    width, height = fig.get_size_inches()
    assert abs(image.shape[0] - height * 150) <= 1 and abs(image.shape[1] - width * 150) <= 1
    assert image.shape[2] == 4
    assert image[..., :3].std() > 0.05  # a drawing, not a blank canvas
    root = ET.parse(svg).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert len(list(root.iter("{http://www.w3.org/2000/svg}path"))) > 20
    spherical = family.startswith("spherical") or family == "linkage-sphere"
    assert len(fig.axes) == (2 if spherical else 1)
    # One legend, under the drawing, where it cannot hide a curve.
    (legend,) = fig.legends
    box = legend.get_window_extent()
    assert all(box.y1 <= ax.get_window_extent().y0 + 1 for ax in fig.axes)


def test_crank_rocker_dead_centres_where_crank_and_coupler_are_in_line(figures):
    doc = example("crank-rocker")
    m = doc.mechanism
    ax = figures["fourbar"].axes[0]
    expected = crank_rocker_dead_centres(
        np.array([0.0, 0.0]), np.array([3.5, 0.0]), 1.0, 5.0, 6.02, 2.5, 1.5, 1.0
    )
    assert len(expected) == 2
    same_points(line(ax, "P at dead centres").get_xydata(), [p for _, p, _ in expected])
    rocker_ends = line(ax, "output B0B at its dead centres").get_xydata()
    same_points(rocker_ends, [b for b, _, _ in expected])
    # The dead centres are the rocker's extreme positions: every circuit sample of B lies
    # between them on its arc about B0.
    phi = np.arctan2(*(circuit(m, N).positions["B"] - [3.5, 0.0]).T[::-1])
    ends = np.arctan2(*(rocker_ends - [3.5, 0.0]).T[::-1])
    assert phi.min() >= ends.min() - 1e-12 and phi.max() <= ends.max() + 1e-12
    text = notes(figures["fourbar"])
    assert text.count("dead centre θ") == 2


def test_six_bar_dead_centres_of_a_watt_i_are_its_four_bars(figures):
    # Watt I: the output is the rocker B0B (every other link floats), so its dead centres are
    # those of its four-bar, 1-5-4 on the frame (0, 0)-(4, 0): found here by Brent's method on
    # the link's rate, checked against the closed form.
    m = example("watt1-example").mechanism
    ax = figures["watt1"].axes[0]
    expected = crank_rocker_dead_centres(
        np.array([0.0, 0.0]), np.array([4.0, 0.0]), 1.0, 5.0, 4.0, 0.0, 0.0, 1.0
    )
    same_points(
        line(ax, "output B0B at its dead centres").get_xydata(), [b for b, _, _ in expected]
    )
    # The P markers are P of the solved six-bar at those crank angles.
    solved = solve(m, [theta for _, _, theta in expected]).positions["P"]
    same_points(line(ax, "P at dead centres").get_xydata(), solved)


def test_six_bar_dead_centres_of_a_watt_ii_stop_its_output(figures):
    # Independent of the plotted rates: over a dense sweep of the full-turn input, the output
    # D0D's angle (from solve()) reaches its least and greatest values where the marks put D,
    # and it turns back nowhere else.
    m = example("watt2-example").mechanism
    ax = figures["watt2"].axes[0]
    marked = line(ax, "output D0D at its dead centres").get_xydata() - [5.0, -2.0]
    thetas = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
    d = solve(m, thetas, order=0).positions["D"] - [5.0, -2.0]
    phi = np.arctan2(d[:, 1], d[:, 0])
    step = np.diff(np.r_[phi, phi[0]])
    turns = np.flatnonzero(np.sign(step) != np.sign(np.roll(step, 1)))
    assert len(marked) == len(turns) == 2
    np.testing.assert_allclose(
        sorted(np.arctan2(marked[:, 1], marked[:, 0])), [phi.min(), phi.max()], atol=1e-6
    )
    assert "dead centres: where the output link D0D stops" in ax.get_title()


@settings(max_examples=8, deadline=None)
@given(
    crank=st.floats(0.5, 1.5),
    coupler=st.floats(4.0, 6.0),
    rocker=st.floats(3.0, 6.0),
    frame=st.floats(3.0, 5.0),
    assembly=st.sampled_from([1.0, -1.0]),
)
def test_four_bar_dead_centres_property(crank, coupler, rocker, frame, assembly):
    # Random Grashof crank-rockers (crank shortest): each dead centre has crank and coupler in
    # line, |A0 B| = coupler ± crank, one of each.
    assume(
        crank + max(coupler, rocker, frame)
        < sum((coupler, rocker, frame)) - max(coupler, rocker, frame) - 0.05
    )
    m = FourBar(
        A0=[0, 0], B0=[frame, 0], crank=crank, coupler=coupler, rocker=rocker, assembly=assembly
    )
    feats = find_features(m, 48)
    dead = feats.of("dead")
    assert len(dead) == 2
    reach = sorted(float(np.linalg.norm(d.pose["B"])) for d in dead)
    np.testing.assert_allclose(reach, [coupler - crank, coupler + crank], rtol=0, atol=1e-7)


@settings(max_examples=6, deadline=None)
@given(
    crank=st.floats(0.8, 1.2),
    coupler=st.floats(4.7, 5.3),
    rocker=st.floats(3.8, 4.2),
    link1=st.floats(2.8, 3.2),
    link2=st.floats(5.7, 6.3),
)
def test_six_bar_dead_centres_property(crank, coupler, rocker, link1, link2):
    # Random Watt IIs near the example: at every dead centre found (Brent on the analytic rate),
    # the output D0D's angle differenced from solve() does not move.
    m = Watt2(
        A0=[0, 0],
        B0=[4, 0],
        D0=[5, -2],
        crank=crank,
        coupler=coupler,
        rocker=rocker,
        u1=4,
        v1=2,
        link1=link1,
        link2=link2,
    )
    feats = find_features(m, 60)
    assume(feats.own.circuits)
    dead = feats.of("dead")
    assert dead
    h = 1e-6
    for mark in dead:
        p = solve(m, [mark.theta - h, mark.theta + h], order=0).positions
        rel = p["D"] - p["D0"]
        ang = np.arctan2(rel[:, 1], rel[:, 0])
        rate = float(np.angle(np.exp(1j * (ang[1] - ang[0])))) / (2 * h)
        assert abs(rate) < 1e-6


def test_rocker_input_limits_at_the_law_of_cosines():
    # rocker-input.toml: crank 3.5 from (0, 0), coupler 5, rocker 1 about (4, 0). At a limit the
    # coupler and rocker are in line, |A B0| = 6 or 4: cos θ = (3.5² + 4² − d²)/(2·3.5·4),
    # on both circuits (±θ). B lies on the ray A→B0 at 5 from A.
    doc = example("rocker-input")
    fig = plot_mechanism(doc.mechanism, samples=96)
    ax = fig.axes[0]
    expected = []
    for d in (6.0, 4.0):
        t = math.acos((3.5**2 + 4.0**2 - d * d) / (2 * 3.5 * 4.0))
        for theta in (t, -t):
            a = 3.5 * np.array([math.cos(theta), math.sin(theta)])
            b = a + 5.0 * (np.array([4.0, 0.0]) - a) / d
            expected.append(coupler_point(a, b, 5.0, 2.0, 1.0))
    same_points(line(ax, "input limit positions").get_xydata(), expected)
    text = notes(fig)
    for deg in (64.06, 106.07):
        assert f"limit θ = {deg:.1f}°" in text
        assert f"limit θ = {MINUS}{deg:.1f}°" in text
    # A rocker-input four-bar's output turns fully: it has no dead centres.
    assert not [ln for ln in ax.lines if "dead centre" in ln.get_label()]


@pytest.mark.parametrize(
    ("name", "at"),
    [("crank-rocker", 1.1), ("rocker-input", math.radians(80.0)), ("watt1-example", 2.0)],
)
def test_pose_drawn_at_the_chosen_input_is_the_solved_one(name, at):
    m = example(name).mechanism
    fig = plot_mechanism(m, at=at, samples=60)
    ax = fig.axes[0]
    solved = solve(m, [at], order=0).positions
    drawn = {
        ln.get_label()[len("_joint ") :]: ln.get_xydata()[0]
        for ln in ax.lines
        if ln.get_label().startswith("_joint ")
    }
    assert drawn and set(drawn) <= set(solved)
    for joint, xy in drawn.items():
        np.testing.assert_allclose(xy, solved[joint][0], rtol=0, atol=1e-12)
    assert f"θ = {math.degrees(at):.1f}°" in ax.get_title() + " ".join(legend_texts(fig))


def test_six_bar_draws_every_assembly_combination_and_its_own_boldly(figures):
    ax = figures["watt1"].axes[0]
    labels = set(legend_texts(figures["watt1"]))
    combos = {
        f"assembly {a}, assembly2 {b}" for a in ("+1", f"{MINUS}1") for b in ("+1", f"{MINUS}1")
    }
    assert combos <= labels
    own = line(ax, "assembly +1, assembly2 +1")
    m = example("watt1-example").mechanism
    np.testing.assert_allclose(own.get_xydata()[:-1], circuit(m, N).positions["P"], atol=1e-12)
    for other in combos - {"assembly +1, assembly2 +1"}:
        ln = line(ax, other)
        assert ln.get_linestyle() != "-" and ln.get_linewidth() < own.get_linewidth()


def test_families_without_an_output_mark_no_dead_centres(figures):
    for family in ("geared-fivebar", "doubleslider", "linkage-plane", "linkage-sphere"):
        fig = figures[family]
        assert "dead centre" not in notes(fig)
        assert not [t for t in legend_texts(fig) if "dead centre" in t]


def test_transmission_extremes_of_a_six_bar_are_the_dyads_extremes(figures):
    # The marked γmin is the least transmission angle of either dyad over a dense sweep.
    m = example("watt1-example").mechanism
    thetas = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    p = solve(m, thetas, order=0).positions

    def angle(j, a, b):
        u, w = p[a] - p[j], p[b] - p[j]
        return np.degrees(np.arctan2(np.abs(cross2(u, w)), np.sum(u * w, axis=1)))

    lowest = min(angle("B", "A", "B0").min(), angle("D", "C", "E").min())
    text = notes(figures["watt1"])
    assert f"γmin at B = {lowest:.1f}°" in text


# --------------------------------------------------------------------------------------------
# Spherical: the sphere and the map
# --------------------------------------------------------------------------------------------


def laea(p, c):
    """Lambert azimuthal equal-area, written out: north +Z, east N × c, k = √(2 / (1 + p·c))."""
    z = np.array([0.0, 0.0, 1.0])
    north = z - (z @ c) * c
    north /= np.linalg.norm(north)
    east = np.cross(north, c)
    k = np.sqrt(2.0 / (1.0 + p @ c))
    return np.stack((k * (p @ east), k * (p @ north)), axis=-1)


def test_spherical_map_shows_the_solved_pose_on_lambert_projection():
    doc = example("paper000-fig6-crank-rocker")
    m = doc.mechanism
    at = math.radians(60.0)
    fig = plot_mechanism(m, at=at, samples=N)
    sphere_ax, map_ax = fig.axes
    assert "Lambert azimuthal equal-area" in map_ax.get_title()
    # The centre: the mean direction of the curves drawn (P in both assembly modes).
    both = np.concatenate([circuit(m.with_assembly(s), N).positions["P"] for s in (1.0, -1.0)])
    c = both.mean(axis=0)
    c /= np.linalg.norm(c)
    solved = solve(m, [at], order=0).positions
    drawn = {
        ln.get_label()[len("_joint ") :]: ln.get_xydata()[0]
        for ln in map_ax.lines
        if ln.get_label().startswith("_joint ")
    }
    assert set(drawn) == {"A0", "B0", "A", "B", "P"}
    for joint, xy in drawn.items():
        np.testing.assert_allclose(xy, laea(solved[joint][0], c), rtol=0, atol=1e-12)
    # The own mode's curve on the map is the projected circuit.
    own = line(map_ax, "assembly +1").get_xydata()
    np.testing.assert_allclose(own[:-1], laea(circuit(m, N).positions["P"], c), atol=1e-12)
    # The sphere panel draws the same pose (joints as markers, one per joint).
    on_sphere = [ln.get_label() for ln in sphere_ax.lines if ln.get_label().startswith("_joint")]
    assert sorted(on_sphere) == sorted(f"_joint {k}" for k in drawn)


def test_spherical_dead_centres_have_crank_and_coupler_in_line():
    # Paper 000's Fig. 6: the output B0B stops where A lies on the great circle A0 B, so that
    # arc A0B = coupler ± crank (45° ± 20°).
    m = example("paper000-fig6-crank-rocker").mechanism
    feats = find_features(m, 60)
    dead = feats.of("dead")
    assert len(dead) == 2
    arcs = sorted(math.degrees(math.acos(np.clip(d.pose["A0"] @ d.pose["B"], -1, 1))) for d in dead)
    np.testing.assert_allclose(arcs, [25.0, 65.0], atol=1e-7)


@settings(max_examples=20, deadline=None)
@given(
    lat=st.floats(-80, 80),
    lon=st.floats(-180, 180),
    off=st.floats(0, 100),
    bearing=st.floats(0, 360),
    radius=st.floats(2, 20),
)
# The ring passes 0.0003° from the centre, where arccos(p·c) is good only to ~1e-11.
@pinned(lat=0, lon=0, off=2, bearing=1, radius=2)
def test_lambert_map_keeps_areas(lat, lon, off, bearing, radius):
    # A spherical cap of angular radius r has area 2π(1 − cos r); its boundary, projected and
    # measured by the shoelace formula, must enclose the same area (a polygon of 4000 sides
    # misses it by ~(2π/4000)²/6 relative).
    c = np.array(
        [
            math.cos(math.radians(lat)) * math.cos(math.radians(lon)),
            math.cos(math.radians(lat)) * math.sin(math.radians(lon)),
            math.sin(math.radians(lat)),
        ]
    )
    helper = np.array([0.0, 0.0, 1.0]) if abs(c[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(helper, c)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    b, o = math.radians(bearing), math.radians(off)
    q = math.cos(o) * c + math.sin(o) * (math.cos(b) * e1 + math.sin(b) * e2)
    f1 = np.cross(helper if abs(helper @ q) < 0.9 else e1, q)
    f1 /= np.linalg.norm(f1)
    f2 = np.cross(q, f1)
    r = math.radians(radius)
    t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)[:, None]
    ring = math.cos(r) * q + math.sin(r) * (np.cos(t) * f1 + np.sin(t) * f2)
    xy = lambert_azimuthal(ring, c)
    x, y = xy[:, 0], xy[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert area == pytest.approx(2 * math.pi * (1 - math.cos(r)), rel=1e-5)
    # And it is the formula written out above, azimuthal: distance 2 sin(δ/2) from the centre.
    np.testing.assert_allclose(xy, laea(ring, c), atol=1e-12)
    # 2 sin(δ/2) is the chord |p − c|, which rounds to ~1e-16 at every δ. (Through arccos(p·c)
    # it would not meet 1e-12: near the centre p·c is 1 − δ²/2, and an ulp of it moves δ by
    # ε/δ, 4e-11 at 0.0003° from the centre.)
    np.testing.assert_allclose(np.hypot(x, y), np.linalg.norm(ring - c, axis=-1), atol=1e-12)


def test_lambert_refuses_the_antipode_and_passes_nan_rows():
    with pytest.raises(ProjectionError, match="antipode"):
        lambert_azimuthal([[0.0, 0.0, -1.0]], [0.0, 0.0, 1.0])
    out = lambert_azimuthal([[np.nan, np.nan, np.nan], [1.0, 0.0, 0.0]], [1.0, 0.0, 0.0])
    assert np.isnan(out[0]).all() and np.allclose(out[1], 0.0)
    with pytest.raises(ProjectionError, match="zero"):
        lambert_azimuthal([[0.0, 0.0, 0.0]], [1.0, 0.0, 0.0])


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------


def test_a_mode_that_never_assembles_names_the_ones_that_do():
    m = example("watt2-example").mechanism
    with pytest.raises(PlotError) as err:
        plot_mechanism(replace(m, assembly=-1), samples=32)
    text = str(err.value)
    assert f"own assembly (assembly {MINUS}1, assembly2 +1)" in text
    assert "it does on assembly +1, assembly2 +1" in text


def test_an_input_where_it_does_not_assemble_names_the_range():
    m = example("rocker-input").mechanism
    with pytest.raises(PlotError) as err:
        plot_mechanism(m, at=0.0, samples=60)
    text = str(err.value)
    assert "θ = 0.0°" in text
    assert f"[{MINUS}106.1°, {MINUS}64.1°]" in text and "[64.1°, 106.1°]" in text


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), "any input"),
        (lambda: SphericalFourBar(*np.radians([90, 10, 20, 30])), "any input"),
        (
            lambda: FourBar(A0=[0, 0], B0=[4, 0], crank=[1.0, 1.5], coupler=5, rocker=3.5),
            "batch",
        ),
    ],
)
def test_linkages_that_cannot_be_drawn_are_a_plot_error(make, match):
    with pytest.raises(PlotError, match=match):
        plot_mechanism(make(), samples=32)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Stephenson3(
            A0=[0, 0],
            B0=[4, 0],
            D0=[2, -4],
            crank=1,
            coupler=5,
            rocker=4,
            u1=4,
            v1=-2,
            link1=3,
            link2=6,
            input="output",
        ),
        lambda: SphericalStephenson3(
            *np.radians([60, 20, 50, 40, 40, 100, 50, 45, 30]), input="FG"
        ),
    ],
    ids=["planar-output", "spherical-fg"],
)
def test_linkages_with_a_triad_are_drawn_with_every_circuit(make, tmp_path):
    """Driven so that a triad remains, every circuit of every configuration is drawn: the
    ternary link filled, each circuit's limits marked where two poses merge."""
    m = make()
    fig = plot_mechanism(m, samples=48)
    save_figure(fig, tmp_path / "triad.png")
    assert mpimg.imread(tmp_path / "triad.png").shape[0] > 100
    features = find_features(m, 48)
    circuits = features.own.circuits
    assert circuits and all(c.valid.all() for c in circuits)
    turns = {round(float(mark.theta), 6) for mark in features.of("limit")}
    # Every turn of a circuit's input is a marked limit, and nothing else is.
    expected = set()
    for c in circuits:
        x = np.unwrap(np.append(c.input, c.input[0]))
        step = np.sign(np.diff(x))
        for i in range(len(step)):
            if step[i] != 0 and step[i - 1] != 0 and step[i] != step[i - 1]:
                expected.add(round(float(np.angle(np.exp(1j * x[i]))), 6))
    wrapped = {round(float(np.angle(np.exp(1j * t))), 6) for t in turns}
    assert expected <= wrapped


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"at": float("nan")}, "finite"), ({"samples": 3}, "samples"), ({"at": "1"}, "finite")],
)
def test_bad_arguments_are_a_plot_error(kwargs, match):
    m = Watt2(
        A0=[0, 0],
        B0=[4, 0],
        D0=[5, -2],
        crank=1,
        coupler=5,
        rocker=4,
        u1=4,
        v1=2,
        link1=3,
        link2=6,
    )
    with pytest.raises(PlotError, match=match):
        plot_mechanism(m, **kwargs)

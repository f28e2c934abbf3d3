"""CAD exports: CSV paths that solve again exactly, SVG and DXF drawings of what the engine built.

Every family's bundled example is exported once to each format (module fixture); the checks
read the files back with numpy, xml.etree and ezdxf and compare them with an independent
re-solve (the engine at the rows' inputs, every assembly configuration, not the circuit
tracer), with the documents' own link lengths, typed here from the example files, and with
the constraint residuals (every link's length constant down the rows).
"""

from __future__ import annotations

import math
import os
import re
import xml.etree.ElementTree as ET
from itertools import combinations

import ezdxf
import numpy as np
import pytest
from ezdxf.math import OCS
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from linkwright.engine import Fixed
from linkwright.geometry.sphere import lambert_azimuthal
from linkwright.io import load_example
from linkwright.io.exports import (
    FORMATS,
    ExportError,
    export,
    export_csv,
    joint_paths,
    topology,
)
from linkwright.mechanisms import FourBar, Stephenson3, configurations, solve

N = 48  # circuit samples: enough to check, quick to write
SVG = "{http://www.w3.org/2000/svg}"

# One example per family (and the rocking input). For each: its links as written in the
# example's comments, the binary links whose length the document gives (joint, joint, length;
# degrees on the sphere), and a ternary link's side.
EXAMPLES = {
    "crank-rocker": {
        "links": [("A0", "A"), ("A", "B", "P"), ("B0", "B")],
        "lengths": [("A0", "A", 1.0), ("B0", "B", 6.02)],
        "side": ("A", "B", 5.0),
    },
    "rocker-input": {
        "links": [("A0", "A"), ("A", "B", "P"), ("B0", "B")],
        "lengths": [("A0", "A", 3.5), ("B0", "B", 1.0)],
        "side": ("A", "B", 5.0),
    },
    "offset-slider-crank": {
        "links": [("A0", "A"), ("A", "B", "P")],
        "lengths": [("A0", "A", 1.0)],
        "side": ("A", "B", 3.0),
        "sliders": 1,
    },
    "geared-fivebar": {
        "links": [("A0", "A"), ("B0", "B"), ("A", "C", "P"), ("B", "C")],
        "lengths": [("A0", "A", 1.0), ("B0", "B", 1.2), ("B", "C", 5.661492736019362)],
        "side": ("A", "C", 2.3048861143232218),
    },
    "elliptic-trammel": {
        "links": [("R", "Q", "P")],
        "lengths": [],
        "side": ("R", "Q", 3.0),  # p + q
        "sliders": 2,
    },
    "watt1-example": {
        "links": [("A0", "A", "C"), ("A", "B", "E"), ("B0", "B"), ("C", "D", "P"), ("E", "D")],
        "lengths": [("B0", "B", 4.0), ("E", "D", 5.0)],
        "side": ("C", "D", 3.0),
    },
    "watt2-example": {
        "links": [("A0", "A"), ("A", "B"), ("B0", "B", "C"), ("C", "D", "P"), ("D0", "D")],
        "lengths": [("A0", "A", 1.0), ("A", "B", 5.0), ("D0", "D", 6.0)],
        "side": ("B0", "B", 4.0),
    },
    "stephenson1-example": {
        "links": [("A0", "A", "C"), ("A", "B"), ("B0", "B", "E"), ("C", "D", "P"), ("E", "D")],
        "lengths": [("A", "B", 5.0), ("E", "D", 6.0)],
        "side": ("C", "D", 4.0),
    },
    "stephenson3-example": {
        "links": [("A0", "A"), ("A", "B", "C"), ("B0", "B"), ("C", "D", "P"), ("D0", "D")],
        "lengths": [("A0", "A", 1.0), ("B0", "B", 4.0), ("D0", "D", 6.0)],
        "side": ("A", "B", 5.0),
    },
    "jansen-leg": {
        "links": [
            ("O", "A"),
            ("A", "C"),
            ("B", "C", "D"),
            ("A", "E"),
            ("B", "E"),
            ("D", "F"),
            ("E", "F", "G"),
        ],
        "lengths": [
            ("O", "A", 15.0),
            ("A", "C", 50.0),
            ("A", "E", 61.9),
            ("B", "E", 39.3),
            ("D", "F", 39.4),
        ],
        "side": ("B", "D", 40.1),
    },
    "paper000-fig6-crank-rocker": {
        "links": [("A0", "A"), ("A", "B", "P"), ("B0", "B")],
        "lengths": [("A0", "A", 20.0), ("B0", "B", 35.0)],
        "side": ("A", "B", 45.0),
    },
    "paper000-fig6-linkage": {
        "links": [("A0", "A"), ("A", "B", "P"), ("B0", "B")],
        "lengths": [("A0", "A", 20.0), ("B0", "B", 35.0)],
        "side": ("A", "P", 50.0),
    },
    "paper000-fig8-sixbar": {
        "links": [("A0", "A"), ("A", "B", "C"), ("B0", "B"), ("C", "E", "D"), ("E0", "E")],
        "lengths": [("A0", "A", 20.0), ("B0", "B", 30.0), ("E0", "E", 33.0)],
        "side": ("C", "E", 45.0),
    },
    "paper001-stephenson3": {
        "links": [("A", "B"), ("B", "C", "E"), ("D", "C"), ("E", "F"), ("G", "F")],
        "lengths": [("A", "B", 20.0), ("D", "C", 40.0), ("E", "F", 50.0), ("G", "F", 45.0)],
        "side": ("B", "C", 50.0),
    },
}


def _key(link):
    return frozenset(link)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Every example written to every format once: name → (document, {format: path})."""
    folder = tmp_path_factory.mktemp("exports")
    out = {}
    for name in EXAMPLES:
        doc = load_example(name)
        files = {
            fmt: export(
                doc.mechanism, folder / f"{name}.{fmt}", samples=N, units=doc.units, title=doc.title
            )
            for fmt in FORMATS
        }
        out[name] = (doc, files)
    return out


def read_csv(path):
    header = path.read_text(encoding="utf-8").splitlines()[0].split(",")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return header, table


def columns(header, table, joint):
    axes = [h for h in header if h.startswith(f"{joint}_") and h[len(joint) + 1 :] in "xyz"]
    return table[:, [header.index(a) for a in axes]]


def distance(a, b, sphere):
    if sphere:
        return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))
    return np.linalg.norm(a - b, axis=-1)


def length_of(value, sphere):
    return math.radians(value) if sphere else value


# --------------------------------------------------------------------------------------------
# Topology
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", EXAMPLES)
def test_links_are_the_bodies_the_examples_describe(name):
    mechanism = load_example(name).mechanism
    links = topology(mechanism).links
    assert {_key(link) for link in links} == {_key(link) for link in EXAMPLES[name]["links"]}
    assert len(links) == len(EXAMPLES[name]["links"])


# --------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", EXAMPLES)
def test_csv_rows_solve_again_and_keep_every_link_length(exported, name):
    doc, files = exported[name]
    m = doc.mechanism
    sphere = m.space == "sphere"
    header, table = read_csv(files["csv"])
    axes = 3 if sphere else 2
    assert header[:3] == ["sample", "theta_deg", "theta_rad"]
    assert len(header) == 3 + axes * len(m.plan.joints) == table.shape[1]
    assert table.shape[0] == N and np.array_equal(table[:, 0], np.arange(N))
    theta = table[:, 2]
    np.testing.assert_allclose(np.radians(table[:, 1]), theta, rtol=1e-15, atol=1e-15)
    rows = {j: columns(header, table, j) for j in m.plan.joints}
    scale = max(np.max(np.abs(p)) for p in rows.values())
    # An independent solve at each row's input: the row is one of the assembly configurations
    # there (where the input rocks, the return leg runs on the other branch).
    solved = [motion.positions for _, motion in configurations(m, theta, order=0)]
    error = np.min(
        [
            np.nan_to_num(  # a configuration that does not assemble there: infinitely far
                np.max([np.max(np.abs(rows[j] - pos[j]), axis=-1) for j in rows], axis=0),
                nan=np.inf,
            )
            for pos in solved
        ],
        axis=0,
    )
    assert np.all(error <= 1e-12 * scale), error.max()
    # Constraint residuals: every pair of joints on one link keeps its distance (arc).
    for link in topology(m).links:
        for a, b in combinations(link, 2):
            d = distance(rows[a], rows[b], sphere)
            assert np.ptp(d) <= 1e-10 * max(scale, 1.0), (a, b, np.ptp(d))
    for a, b, value in EXAMPLES[name]["lengths"]:
        d = distance(rows[a], rows[b], sphere)
        np.testing.assert_allclose(d, length_of(value, sphere), rtol=0, atol=1e-10 * scale)
    if sphere:
        for p in rows.values():
            np.testing.assert_allclose(np.linalg.norm(p, axis=-1), 1.0, atol=1e-14)


def test_csv_of_a_rocking_input_passes_both_legs(exported):
    doc, files = exported["rocker-input"]
    header, table = read_csv(files["csv"])
    theta = table[:, 2]
    top = int(np.argmax(theta))
    assert 0 < top < N - 1
    assert np.all(np.diff(theta[: top + 1]) > 0) and np.all(np.diff(theta[top:]) < 0)
    # The two legs meet at the limits and differ between them: same input, other branch.
    B = columns(header, table, "B")
    k = top // 2
    other = top + np.argmin(np.abs(theta[top:] - theta[k]))
    again = solve(doc.mechanism.with_assembly(-1.0), [theta[other]], order=0).positions["B"]
    np.testing.assert_allclose(B[other], again[0], atol=1e-12)
    assert np.linalg.norm(B[k] - B[other]) > 0.1


def test_joint_paths_match_the_csv(exported):
    doc, files = exported["stephenson3-example"]
    theta, paths = joint_paths(doc.mechanism, samples=N)
    header, table = read_csv(files["csv"])
    np.testing.assert_array_equal(theta, table[:, 2])
    assert list(paths) == list(doc.mechanism.plan.joints)
    for joint, p in paths.items():
        np.testing.assert_array_equal(p, columns(header, table, joint))


# --------------------------------------------------------------------------------------------
# SVG
# --------------------------------------------------------------------------------------------


def svg_points(element):
    pts = np.array([[float(v) for v in pair.split(",")] for pair in element.get("points").split()])
    return pts


def page_axes(centre):
    """Up: +z's part normal to the centre; right: up × centre (as the <desc> says)."""
    up = np.array([0.0, 0.0, 1.0])
    up = up - up @ centre * centre
    up /= np.linalg.norm(up)
    return np.cross(up, centre), up


def lambert_by_hand(p, centre):
    """Snyder's form: the tangent-plane components scaled by k' = √(2 / (1 + cos δ))."""
    right, up = page_axes(centre)
    k = np.sqrt(2.0 / (1.0 + p @ centre))
    return np.stack((k * (p @ right), k * (p @ up)), axis=-1)


@pytest.mark.parametrize("name", EXAMPLES)
def test_svg_parses_and_draws_the_curves_and_links_where_they_are(exported, name):
    doc, files = exported[name]
    m = doc.mechanism
    sphere = m.space == "sphere"
    root = ET.parse(files["svg"]).getroot()
    groups = {g.get("id"): g for g in root.iter(f"{SVG}g")}
    assert {"curves", "links", "joints", "ground", "labels"} <= set(groups)
    header, table = read_csv(files["csv"])
    if sphere:
        desc = root.find(f"{SVG}desc").text
        assert "Lambert" in desc and "equal-area" in desc
        centre = np.array(
            [float(v) for v in re.search(r"centred on \(([^)]*)\)", desc)[1].split(",")]
        )

        def page(p):
            return lambert_by_hand(p, centre)
    else:

        def page(p):
            return p

    for joint in m.plan.traced:
        (curve,) = [e for e in groups["curves"] if e.get("id") == f"curve-{joint}"]
        assert curve.tag == f"{SVG}polygon"  # closed: the circuit closes
        xy = svg_points(curve)
        expected = page(columns(header, table, joint))
        assert xy.shape == (N, 2)
        np.testing.assert_allclose(xy[:, 0], expected[:, 0], atol=1e-9, rtol=0)
        np.testing.assert_allclose(-xy[:, 1], expected[:, 1], atol=1e-9, rtol=0)  # y flipped
    pose = {j: page(columns(header, table, j)[0]) for j in m.plan.joints}
    for a, b, _ in EXAMPLES[name]["lengths"]:
        (link,) = [e for e in groups["links"] if e.get("id") in (f"link-{a}-{b}", f"link-{b}-{a}")]
        if sphere:
            ends = svg_points(link)[[0, -1]] * [1, -1]
        else:
            ends = np.array(
                [
                    [float(link.get(k)) for k in ("x1", "y1")],
                    [float(link.get(k)) for k in ("x2", "y2")],
                ]
            ) * [1, -1]
        assert {tuple(np.round(e, 9)) for e in ends} == {
            tuple(np.round(pose[j], 9)) for j in (a, b)
        }
    circles = {e.get("id"): e for e in groups["joints"]}
    for joint in m.plan.traced:
        c = circles[f"joint-{joint}"]
        np.testing.assert_allclose(
            [float(c.get("cx")), -float(c.get("cy"))], pose[joint], atol=1e-9, rtol=0
        )


@pytest.mark.parametrize(
    ("units", "name", "factor"),
    [("mm", "mm", 1), ("m", "mm", 1000), ("in", "in", 1), ("ft", "in", 12)],
)
def test_svg_size_is_in_the_documents_units(tmp_path, units, name, factor):
    m = load_example("crank-rocker").mechanism
    root = ET.parse(export(m, tmp_path / "f.svg", samples=16, units=units)).getroot()
    box = [float(v) for v in root.get("viewBox").split()]
    assert root.get("width").endswith(name)
    assert float(root.get("width")[: -len(name)]) == pytest.approx(box[2] * factor, rel=1e-12)
    assert float(root.get("height")[: -len(name)]) == pytest.approx(box[3] * factor, rel=1e-12)


def test_lambert_azimuthal_is_snyders_projection_on_random_points():
    rng = np.random.default_rng(7)
    centres = rng.normal(size=(20, 3))
    for centre in centres / np.linalg.norm(centres, axis=1, keepdims=True):
        p = rng.normal(size=(50, 3))
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        p = p[p @ centre > -0.9]  # away from the antipode, where the page runs out
        xy = lambert_azimuthal(p, centre)
        np.testing.assert_allclose(xy, lambert_by_hand(p, centre), atol=1e-12)
        # Equal area: a cap of angular radius δ (area 2π(1 − cos δ)) fills the disc of radius
        # ρ(δ), so πρ² = 2π(1 − cos δ).
        delta = np.arccos(np.clip(p @ centre, -1, 1))
        np.testing.assert_allclose(
            np.pi * np.sum(xy**2, axis=1), 2 * np.pi * (1 - np.cos(delta)), atol=1e-12
        )


# --------------------------------------------------------------------------------------------
# DXF
# --------------------------------------------------------------------------------------------


def audited(path):
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    assert not auditor.has_errors and not auditor.has_fixes, (auditor.errors, auditor.fixes)
    return doc


def counts(msp):
    out = {}
    for e in msp:
        out[(e.dxf.layer, e.dxftype())] = out.get((e.dxf.layer, e.dxftype()), 0) + 1
    return out


@pytest.mark.parametrize("name", EXAMPLES)
def test_dxf_audits_clean_and_draws_the_linkage_and_its_curves(exported, name):
    doc, files = exported[name]
    m = doc.mechanism
    sphere = m.space == "sphere"
    drawing = audited(files["dxf"])
    assert drawing.dxfversion >= "AC1024"  # R2010 or later
    assert drawing.header["$INSUNITS"] == {None: 0, "mm": 4}[doc.units]
    msp = drawing.modelspace()
    have = counts(msp)
    spec = EXAMPLES[name]
    binary = sum(len(link) == 2 for link in spec["links"])
    plates = len(spec["links"]) - binary
    sliders = spec.get("sliders", 0)
    ground = {s.name for s in m.plan.steps if isinstance(s, Fixed)}
    # A slider's guide point is part of the frame but no pivot: no link turns about it.
    pivots = ground - {"L", "M"} if sliders else ground
    moving = len(m.plan.joints) - len(ground)
    if sphere:
        expected = {("LINKS", "POLYLINE"): len(spec["links"]), ("GROUND", "CIRCLE"): len(pivots)}
    else:
        expected = {
            ("LINKS", "LINE"): binary,
            ("LINKS", "LWPOLYLINE"): plates + sliders,
            ("GROUND", "CIRCLE"): len(pivots),
            ("GROUND", "LWPOLYLINE"): len(pivots),  # the ground symbol under each pivot
            ("GROUND", "LINE"): sliders,  # a fixed guide per slider
        }
    expected[("JOINTS", "CIRCLE")] = moving
    expected[("LABELS", "TEXT")] = moving + len(pivots)
    curve = "POLYLINE" if sphere else "LWPOLYLINE"
    for joint in m.plan.traced:
        expected[(f"CURVE-{joint}", curve)] = 1
    assert have == {k: v for k, v in expected.items() if v}
    header, table = read_csv(files["csv"])
    pose = {j: columns(header, table, j)[0] for j in m.plan.joints}
    for joint in m.plan.traced:
        (entity,) = msp.query(f"{curve}[layer=='CURVE-{joint}']")
        assert entity.is_closed
        if sphere:
            vertices = np.array([v.dxf.location for v in entity.vertices])
        else:
            vertices = np.array(entity.get_points("xy"))
        np.testing.assert_allclose(vertices, columns(header, table, joint), atol=1e-9, rtol=0)
    for a, b, value in spec["lengths"]:
        if sphere:
            (arc,) = [
                e
                for e in msp.query("POLYLINE[layer=='LINKS']")
                if len(e.vertices) >= 2
                and {tuple(np.round(e.vertices[k].dxf.location, 9)) for k in (0, -1)}
                == {tuple(np.round(pose[j], 9)) for j in (a, b)}
            ]
            points = np.array([v.dxf.location for v in arc.vertices])
            normal = np.cross(pose[a], pose[b])
            np.testing.assert_allclose(np.linalg.norm(points, axis=1), 1.0, atol=1e-12)
            np.testing.assert_allclose(points @ normal, 0.0, atol=1e-12)  # on the great circle
            total = np.sum(distance(points[:-1], points[1:], True))
            assert total == pytest.approx(math.radians(value), abs=1e-9)
        else:
            (line,) = [
                e
                for e in msp.query("LINE[layer=='LINKS']")
                if {
                    tuple(np.round(np.array(e.dxf.start)[:2], 9)),
                    tuple(np.round(np.array(e.dxf.end)[:2], 9)),
                }
                == {tuple(np.round(pose[j], 9)) for j in (a, b)}
            ]
            assert line.dxf.start.distance(line.dxf.end) == pytest.approx(value, abs=1e-9)
    a, b, value = spec["side"]
    assert distance(pose[a], pose[b], sphere) == pytest.approx(length_of(value, sphere), abs=1e-9)
    for circle in msp.query("CIRCLE[layer=='JOINTS']"):
        centre = OCS(circle.dxf.extrusion).to_wcs(circle.dxf.center)
        assert min(np.max(np.abs(centre - p)) for p in pose.values()) < 1e-9


@pytest.mark.parametrize(
    ("units", "code"),
    [(None, 0), ("mm", 4), ("cm", 5), ("m", 6), ("in", 1), ("ft", 2), ("Inches", 1)],
)
def test_dxf_insunits_follow_the_documents_units(tmp_path, units, code):
    m = load_example("crank-rocker").mechanism
    path = export(m, tmp_path / "f.dxf", samples=8, units=units)
    assert audited(path).header["$INSUNITS"] == code


@settings(max_examples=10, deadline=None)
@given(
    frame=st.floats(0.5, 20.0),
    angle=st.floats(-math.pi, math.pi),
    crank=st.floats(0.2, 10.0),
    theta=st.floats(-math.pi, math.pi),
    bx=st.floats(-10.0, 10.0),
    by=st.floats(-10.0, 10.0),
    u=st.floats(-3.0, 3.0),
    v=st.floats(-3.0, 3.0),
)
def test_random_four_bars_export_to_dxf_with_their_own_lengths(
    tmp_path_factory, frame, angle, crank, theta, bx, by, u, v
):
    # Built from a pose, so it assembles at θ: A on the crank, B anywhere clear of a toggle.
    A0, B0 = np.zeros(2), frame * np.array([math.cos(angle), math.sin(angle)])
    A = A0 + crank * np.array([math.cos(theta), math.sin(theta)])
    B = np.array([bx, by])
    coupler, rocker, reach = np.linalg.norm(B - A), np.linalg.norm(B - B0), np.linalg.norm(B0 - A)
    side = (B0 - A)[0] * (B - A)[1] - (B0 - A)[1] * (B - A)[0]  # the engine's branch sign
    assume(min(coupler, rocker, reach) > 0.1 and abs(side) > 1e-3 * coupler * reach)
    P = A + u * (B - A) / coupler + v * np.array([-(B - A)[1], (B - A)[0]]) / coupler
    assume(min(np.linalg.norm(P - A), np.linalg.norm(P - B)) > 1e-3)  # a plate, not a bar
    m = FourBar(
        A0=A0, B0=B0, crank=crank, coupler=coupler, rocker=rocker, u=u, v=v, assembly=np.sign(side)
    )
    path = export(m, tmp_path_factory.mktemp("fb") / "f.dxf", at=theta, samples=12)
    msp = audited(path).modelspace()
    lines = sorted(e.dxf.start.distance(e.dxf.end) for e in msp.query("LINE[layer=='LINKS']"))
    np.testing.assert_allclose(lines, sorted([crank, rocker]), rtol=1e-9)
    (plate,) = msp.query("LWPOLYLINE[layer=='LINKS']")
    corners = np.array(plate.get_points("xy"))
    for point in (A, B, P):
        assert np.min(np.linalg.norm(corners - point, axis=1)) < 1e-9 * max(1.0, np.abs(B).max())


# --------------------------------------------------------------------------------------------
# Refusals and atomic writes
# --------------------------------------------------------------------------------------------

TOO_SHORT = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_four_bar_that_cannot_assemble_is_refused(tmp_path, fmt):
    with pytest.raises(ExportError, match="cannot be assembled at any input"):
        export(TOO_SHORT, tmp_path / f"x.{fmt}")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"out": "x.step"}, r"unknown format '\.step'"),
        ({"out": "x"}, "unknown format 'no suffix'"),
        ({"out": "x.svg", "units": "furlong"}, "units: unknown length unit 'furlong'"),
        ({"out": "x.dxf", "samples": 2}, "samples: must be an integer from 3"),
        ({"out": "x.dxf", "samples": 10.5}, "samples: must be an integer"),
        ({"out": "x.svg", "at": float("nan")}, "at: must be a finite input angle"),
        ({"out": "x.csv", "at": 0.0}, r"cannot be assembled at the input 0°"),
    ],
)
def test_bad_requests_are_refused_with_a_clear_error(tmp_path, kwargs, match):
    # rocker-input's input only swings over |θ| ≥ 113.1°: θ = 0 is not a pose of it.
    m = load_example("rocker-input").mechanism
    kwargs["out"] = tmp_path / kwargs["out"]
    with pytest.raises(ExportError, match=match):
        export(m, **kwargs)
    assert os.listdir(tmp_path) == []


def test_a_triad_exports_and_batches_are_refused(tmp_path):
    output_driven = Stephenson3(
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
    )
    # The ternary link ABC is one body, held by three binary links from A0, B0 and D.
    t = topology(output_driven)
    assert ("A", "B", "C") in t.links
    assert {("A0", "A"), ("B0", "B")} <= set(t.links)
    assert any({"D", "C"} <= set(link) for link in t.links)  # CD carries the point P
    export(output_driven, tmp_path / "x.dxf")
    assert (tmp_path / "x.dxf").stat().st_size > 0
    batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1, 1.5], coupler=5, rocker=3.5)
    with pytest.raises(ExportError, match="batch of 2"):
        export(batch, tmp_path / "x.csv")


def test_an_interrupted_write_leaves_no_partial_file(tmp_path, monkeypatch):
    import linkwright.io.exports as module

    m = load_example("crank-rocker").mechanism
    keep = tmp_path / "old.csv"
    keep.write_text("the previous export\n")
    real = module._csv_row

    def dies_midway(k, row):
        if k == 5:
            raise KeyboardInterrupt  # killed after five rows reached the disk
        return real(k, row)

    monkeypatch.setattr(module, "_csv_row", dies_midway)
    for target in (tmp_path / "new.csv", keep):
        with pytest.raises(KeyboardInterrupt):
            export_csv(m, target, samples=N)
    assert sorted(os.listdir(tmp_path)) == ["old.csv"]
    assert keep.read_text() == "the previous export\n"

    def saves_half(self, filename, *args, **kwargs):
        with open(filename, "w") as handle:
            handle.write("  0\nSECTION\n")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ezdxf.document.Drawing, "saveas", saves_half)
    with pytest.raises(ExportError, match="No space left on device"):
        export(m, tmp_path / "new.dxf", samples=N)
    assert sorted(os.listdir(tmp_path)) == ["old.csv"]


@pytest.mark.parametrize(
    ("failed", "pieces"),
    [
        ((10, 11, N - 1), [range(10), range(12, N - 1)]),
        # Both ends of the circuit kept: one piece that runs on across the start.
        ((10, 11), [[*range(12, N), *range(10)]]),
    ],
)
def test_samples_that_do_not_assemble_break_the_curves_into_open_pieces(
    tmp_path, monkeypatch, failed, pieces
):
    import dataclasses

    import linkwright.io.export_geometry as module
    from linkwright.mechanisms import circuit

    def with_a_gap(mechanism, samples, **kwargs):
        # As if rounding at a limit had failed the engine at these samples.
        motion = circuit(mechanism, samples, **kwargs)
        bad = np.isin(np.arange(samples), failed)
        return dataclasses.replace(
            motion,
            valid=motion.valid & ~bad,
            positions={k: np.where(bad[:, None], np.nan, v) for k, v in motion.positions.items()},
        )

    monkeypatch.setattr(module, "circuit", with_a_gap)
    m = load_example("crank-rocker").mechanism
    header, table = read_csv(export(m, tmp_path / "f.csv", samples=N))
    np.testing.assert_array_equal(table[:, 0], [k for k in range(N) if k not in failed])
    P = dict(zip(table[:, 0].astype(int), columns(header, table, "P"), strict=True))
    expected = [np.array([P[k] for k in piece]) for piece in pieces]
    root = ET.parse(export(m, tmp_path / "f.svg", samples=N)).getroot()
    curves = [e for g in root.iter(f"{SVG}g") if g.get("id") == "curves" for e in g]
    assert [e.tag for e in curves] == [f"{SVG}polyline"] * len(pieces)
    for e, want in zip(curves, expected, strict=True):
        np.testing.assert_allclose(svg_points(e) * [1, -1], want, atol=1e-12)
    msp = audited(export(m, tmp_path / "f.dxf", samples=N)).modelspace()
    drawn = msp.query("LWPOLYLINE[layer=='CURVE-P']")
    assert [e.closed for e in drawn] == [False] * len(pieces)
    for e, want in zip(drawn, expected, strict=True):
        np.testing.assert_allclose(np.array(e.get_points("xy")), want, atol=1e-12)

"""``linkwright synth ...``: every printed mechanism is re-read as a document and simulated
here, and what it traces is checked against the request (not against the command's own
numbers)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from linkwright.cli import main
from linkwright.io import parse_document
from linkwright.mechanisms import solve


def run(capsys, *args: str) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *args: str) -> dict:
    # --quiet only where there is a progress bar to silence.
    quiet = ("--quiet",) if args[1] in ("ellipse", "targets", "path") else ()
    status, out, err = run(capsys, *args, "--json", *quiet)
    assert status == 0, err
    return json.loads(out)


def _conic_value(coeffs, xy):
    A, B, C, D, E, F = coeffs
    x, y = xy[..., 0], xy[..., 1]
    return A * x * x + B * x * y + C * y * y + D * x + E * y + F


def _traced(document: dict) -> np.ndarray:
    mech = parse_document(document).mechanism
    theta = np.linspace(0, 2 * np.pi, 73)
    return solve(mech, theta, order=0).positions["P"]


def test_ellipse_from_conic_every_document_traces_it(capsys):
    # (x − 1)²/16 + (y + 2)²/4 = 1 turned by 30°, written at an odd scale and sign.
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    t = np.linspace(0, 2 * np.pi, 7, endpoint=False)
    pts = np.stack([4 * np.cos(t), 2 * np.sin(t)], -1) @ [[c, s], [-s, c]] + [1, -2]
    # The conic through those points, by the null space of the design matrix (independent of
    # the synthesis code's conic handling).
    x, y = pts[:, 0], pts[:, 1]
    design = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], -1)
    conic = -3.7 * np.linalg.svd(design)[2][-1]
    r = run_json(capsys, "synth", "ellipse", "--conic", ",".join(repr(float(v)) for v in conic),
                 "--family-samples", "5")  # fmt: skip
    assert r["trammel"]["a"] == pytest.approx(4, rel=1e-9)
    assert r["trammel"]["b"] == pytest.approx(2, rel=1e-9)
    docs = [r["canonical"]["mechanism"]] + [m["mechanism"] for m in r["family"]]
    assert len(docs) == 6
    scale = np.abs(conic).max()
    for doc in docs:
        P = _traced(doc)
        assert np.all(np.isfinite(P))
        assert np.abs(_conic_value(conic, P)).max() < 1e-9 * scale


def test_ellipse_from_points_reports_the_fit(capsys, tmp_path):
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    pts = np.stack([3 * np.cos(t) + 2, np.sin(t) - 1], -1)
    f = tmp_path / "pts.csv"
    f.write_text("x,y\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in pts) + "\n")
    r = run_json(capsys, "synth", "ellipse", "--points", f)
    assert r["fit"]["count"] == 40 and r["fit"]["rms"] < 1e-9
    P = _traced(r["canonical"]["mechanism"])
    assert np.abs(((P[:, 0] - 2) / 3) ** 2 + (P[:, 1] + 1) ** 2 - 1).max() < 1e-9


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "no points"),
        ("x,y\n", "no points"),
        ("1,2\n3,4,5\n", "line 2: 3 columns"),
        ("1,2\n3,abc\n", "line 2: not numbers"),
        ("1,2,3\n", "3 columns, expected 2"),
        ("1,nan\n", "finite"),
    ],
)
def test_point_files_bad_content(capsys, tmp_path, content, message):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    status, out, err = run(capsys, "synth", "ellipse", "--points", f)
    assert status == 2 and out == ""
    assert message in err and err.startswith("error:") and err.count("\n") == 1


@pytest.mark.parametrize(
    ("conic", "kind"),
    [
        ("1,0,-1,0,0,-1", "hyperbola"),
        ("0,0,1,-1,0,0", "parabola"),
        ("1,0,1,0,0,1", "imaginary"),
        ("1,0,1,0,0,0", "point"),
    ],
)
def test_not_an_ellipse_is_named(capsys, conic, kind):
    status, _, err = run(capsys, "synth", "ellipse", "--conic", conic)
    assert status == 2 and kind in err


def test_ellipse_needs_exactly_one_source(capsys, tmp_path):
    assert run(capsys, "synth", "ellipse")[0] == 2
    f = tmp_path / "p.csv"
    f.write_text("0,0\n")
    status, _, err = run(capsys, "synth", "ellipse", "--conic", "1,0,1,0,0,-1", "--points", f)
    assert status == 2 and "--conic" in err
    assert run(capsys, "synth", "ellipse", "--conic", "1,0,1")[0] == 2


def test_both_cardan_families_trace_the_ellipse(capsys):
    conic = [1.0, 0.0, 4.0, -2.0, 8.0, -11.0]  # (x − 1)²/16 + (y + 1)²/4 = 1, multiplied out
    for circle in ("small", "large"):
        r = run_json(capsys, "synth", "ellipse", "--conic", ",".join(map(str, conic)),
                     "--family-samples", "3", "--circle", circle)  # fmt: skip
        assert r["circle"] == circle
        for m in r["family"]:
            P = _traced(m["mechanism"])
            assert np.abs(_conic_value(conic, P)).max() < 1e-9 * 11
    status, _, err = run(capsys, "synth", "ellipse", "--conic", "1,0,1,0,0,-1", "--circle", "x")
    assert status == 2 and "--circle" in err


def test_targets_paper003_example_both_solutions_hit_the_targets(capsys):
    from linkwright.analysis import coefficients

    r = run_json(capsys, "synth", "targets", "--family", "spherical-fourbar", "--fix",
                 "crank=80,frame=10", "--free", "coupler,rocker", "--target", "max_Ke=1.47",
                 "--target", "max_Kp=1.49", "--kind", "double-crank", "--grid", "13")  # fmt: skip
    assert len(r["solutions"]) == 2
    for sol in r["solutions"]:
        mech = parse_document(sol["mechanism"]).mechanism
        got = coefficients(mech)  # recomputed here from the document alone
        assert float(got["K_epsilon"]) == pytest.approx(1.47, abs=1e-8)
        assert float(got["K_p"]) == pytest.approx(1.49, abs=1e-8)
        assert sol["condition"] > 100  # paper 003's design is ill-conditioned


def test_targets_bad_arguments(capsys):
    base = ["synth", "targets", "--family", "fourbar", "--fix", "crank=1,frame=4", "--free",
            "coupler,rocker", "--target", "swing=40"]  # fmt: skip
    status, _, err = run(capsys, *base[:-1], "nonsense=3")
    assert status == 2 and "nonsense" in err
    status, _, err = run(capsys, *base, "--bound", "coupler=3")
    assert status == 2 and "LOW:HIGH" in err
    status, _, err = run(capsys, *base[:5], "crank=1,crank=2", *base[6:])
    assert status == 2 and "twice" in err


def test_reinsberg_completion_is_thales(capsys, tmp_path):
    doc = tmp_path / "fb.toml"
    doc.write_text('format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\nA0 = [0, 0]\n'
                   'B0 = [4, 0]\ncrank = 1\ncoupler = 3\nrocker = 2\n')  # fmt: skip
    status, out, err = run(capsys, "synth", "reinsberg", doc, "--solve", "coupler", "--json")
    assert status == 0, err
    r = json.loads(out)
    m = r["mechanism"]["mechanism"]
    # L1² + L4² = L2² + L3² (paper 003): the coupler is √(1 + 16 − 4).
    assert m["coupler"] == pytest.approx(13**0.5, rel=1e-12)
    assert abs(r["after_deg"]) < 1e-9
    status, _, err = run(capsys, "synth", "reinsberg", doc, "--solve", "wheel")
    assert status == 2 and "wheel" in err


def _fourbar_at(document: dict, inputs_deg, branches=None):
    mech = parse_document(document).mechanism
    motion = solve(mech, np.radians(inputs_deg), order=0)
    return mech, motion


def test_function_generation_meets_its_pairs(capsys):
    pairs = [(40.0, 70.0), (75.0, 95.0), (110.0, 115.0)]
    r = run_json(capsys, "synth", "function", "--pairs", ";".join(f"{a},{b}" for a, b in pairs),
                 "--frame", "2")  # fmt: skip
    mech, motion = _fourbar_at(r["mechanism"], r["inputs_deg"])
    A0, B0 = np.asarray(mech.A0), np.asarray(mech.B0)
    assert np.linalg.norm(B0 - A0) == pytest.approx(2.0)
    # The rocker's angle from the frame line, measured here from the simulated B.
    d = motion.positions["B"] - B0
    psi = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
    want = np.array([p[1] for p in pairs]) + np.asarray(r["outputs_deg"]) - [p[1] for p in pairs]
    assert np.allclose((psi - want + 180) % 360 - 180, 0, atol=1e-8)
    phi = np.asarray(r["inputs_deg"]) - (np.asarray(r["inputs_deg"]) - [p[0] for p in pairs])
    assert np.allclose(phi, [p[0] for p in pairs])
    assert run(capsys, "synth", "function", "--pairs", "1,2;3,4")[0] == 2


def test_motion_three_and_five_poses(capsys, tmp_path):
    poses = np.array([[0, 0, 0], [1, 0.5, 20], [2, 0.6, 45], [2.5, 0.2, 70], [2.4, -0.5, 100]])
    three = tmp_path / "p3.csv"
    three.write_text("\n".join(",".join(map(str, p)) for p in poses[:3]))
    r = run_json(capsys, "synth", "motion", "--poses", three, "--circles", "0,-1,1,-1")
    mech, motion = _fourbar_at(r["mechanism"], r["inputs_deg"])
    assert np.allclose(motion.positions["P"], poses[:3, :2], atol=1e-9)
    five = tmp_path / "p5.csv"
    five.write_text("x,y,angle\n" + "\n".join(",".join(map(str, p)) for p in poses))
    r = run_json(capsys, "synth", "motion", "--poses", five)
    assert r["burmester_points"] >= 2 and r["designs"]
    for d in r["designs"]:
        mech = parse_document(d["mechanism"]).mechanism
        # Each pose on the assembly mode it needs (a branch defect is reported, not hidden).
        for theta, sign, pose in zip(d["inputs_deg"], d["branches"], poses, strict=True):
            m = parse_document({**d["mechanism"], "mechanism": {**d["mechanism"]["mechanism"],
                                "assembly": sign}}).mechanism  # fmt: skip
            p = solve(m, [np.radians(theta)], order=0).positions
            assert np.allclose(p["P"][0], pose[:2], atol=1e-9)
            ab = p["B"][0] - p["A"][0]
            # The body's angle is the coupler's, up to the constant offset of the first pose.
            assert np.isfinite(ab).all()
        assert isinstance(mech.crank, float) or np.ndim(mech.crank) == 0


def test_precision_path_passes_its_points(capsys, tmp_path):
    pts = tmp_path / "p.csv"
    pts.write_text("0,0\n1,0.5\n2,0.6\n")
    r = run_json(capsys, "synth", "precision-path", "--points", pts, "--crank-rotations", "30,60",
                 "--coupler-rotations", "-15,-25", "--rocker-rotations", "-20,-35")  # fmt: skip
    _, motion = _fourbar_at(r["mechanism"], r["inputs_deg"])
    assert np.allclose(motion.positions["P"], [[0, 0], [1, 0.5], [2, 0.6]], atol=1e-9)
    assert np.allclose((np.diff(r["inputs_deg"]) + 180) % 360 - 180, 30.0)


def test_path_synthesis_round_trip(capsys, tmp_path):
    """Points of a known four-bar at known crank angles: the fitted document, simulated here at
    the inputs it reports, passes through them."""
    from linkwright.mechanisms import FourBar

    known = FourBar(A0=[0, 0], B0=[3, 0.5], crank=1, coupler=3, rocker=2.5, u=1.5, v=1.0)
    theta = np.radians([0, 40, 80, 120, 160])
    pts = solve(known, theta, order=0).positions["P"]
    f = tmp_path / "pts.csv"
    f.write_text("\n".join(f"{float(x)!r},{float(y)!r}" for x, y in pts))
    frame = np.degrees(np.arctan2(0.5, 3))
    r = run_json(capsys, "synth", "path", "--family", "fourbar", "--points", f, "--angles",
                 ",".join(f"{float(a - frame)!r}" for a in np.degrees(theta)), "--budget", "8",
                 "--seed", "3")  # fmt: skip
    mech = parse_document(r["mechanism"]).mechanism
    got = solve(mech, np.radians(r["inputs_deg"]), order=0).positions["P"]
    assert np.sqrt(np.mean(np.sum((got - pts) ** 2, -1))) == pytest.approx(r["rms"], abs=1e-9)
    assert r["rms"] < 1e-6 * 4
    status, _, err = run(capsys, "synth", "path", "--family", "fourbar", "--points", f,
                         "--angles", "1,2", "--free-timing")  # fmt: skip
    assert status == 2 and "at most one" in err

"""The command line and pictures for every planar family: examples, papers 002/004, triads."""

from __future__ import annotations

import json

import numpy as np
import pytest

from linkwright.cli import main
from linkwright.io import list_examples, load_example
from linkwright.mechanisms import circuit, solve, solve_all
from linkwright.papers import p002, p004

EXAMPLES = list_examples()


def run(capsys, *args: str) -> tuple[int, str, str]:
    status = main(list(args))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize("name", EXAMPLES)
def test_every_example_analyses_and_traces(name, capsys):
    status, out, _ = run(capsys, "analyze", name, "--json")
    assert status == 0
    report = json.loads(out)
    assert report["assembles"] is True
    status, out, _ = run(capsys, "curve", name, "--points", "64", "--json")
    assert status == 0
    points = json.loads(out)["points"]
    assert len(points) == 64 and all(p is not None for p in points)


@pytest.mark.parametrize("name", [n for n in EXAMPLES if "slider" not in n])
def test_example_circuits_satisfy_their_constraints(name):
    mech = load_example(name).mechanism
    motion = circuit(mech, 256)
    assert motion.valid.all()
    for key, r in mech.residuals(motion).items():
        assert np.nanmax(np.abs(r)) < 1e-10, key


def test_papers_command(capsys, tmp_path):
    status, _out, _ = run(capsys, "papers", "004", "--out", str(tmp_path))
    assert status == 0
    assert (tmp_path / "paper004.md").is_file() and (tmp_path / "p004-doubleslider.png").is_file()
    assert "eq. 3 at every sampled P" in (tmp_path / "paper004.md").read_text(encoding="utf-8")
    for bad in ("7", "0001", "erratum"):
        status, _, err = run(capsys, "papers", bad)
        assert status == 2 and err.startswith("error: ")
    status, out, _ = run(capsys, "papers", "errata")
    assert status == 0 and out.startswith("# Errata of the seed papers")


def test_paper002_study_keeps_what_the_paper_keeps():
    """Moving pivot 1: crank lengths, drawn crank angles and the traced point stay put."""
    steps = p002.pivot_study(count=3)
    base = steps[0].mechanism
    for s in steps[1:]:
        m = s.mechanism
        assert float(m.crank1) == pytest.approx(float(base.crank1))
        assert float(m.phase1) == pytest.approx(float(base.phase1))
        # At the drawn input the moved crank end is the drawn one shifted, and B and the traced
        # point are where they were drawn.
        motion = solve(m, [float(m.phase1)])
        shifted = np.add(p002.DRAWING["A"], s.offset)
        np.testing.assert_allclose(motion.positions["A"][0], shifted, atol=1e-12)
        np.testing.assert_allclose(motion.positions["P"][0], p002.DRAWING["P"], atol=1e-12)
        np.testing.assert_allclose(motion.positions["B"][0], p002.DRAWING["B"], atol=1e-12)


def test_paper004_forward_relations():
    r = p004.forward_check(count=2000)
    assert r["conic_residual"] < 1e-12 and r["delta_vs_K"] < 1e-9
    assert r["not_elliptic"] == 0 and r["not_real"] == 0


def test_output_driven_stephenson3_reports_every_configuration(capsys, tmp_path):
    text = load_example("stephenson3-example")
    raw = text.raw
    raw["mechanism"]["input"] = "output"
    path = tmp_path / "s3.json"
    path.write_text(json.dumps(raw), encoding="utf-8")
    status, out, _ = run(capsys, "solve", str(path), "--input", "90,100", "--all", "--json")
    assert status == 0
    samples = json.loads(out)["samples"]
    assert all(len(s["configurations"]) >= 1 for s in samples)
    # The configuration the crank-driven document passes through at D's angle is among them.
    mech = load_example("stephenson3-example").mechanism
    found = solve_all(mech.__class__(**{**mech.params(), "input": "output"}), np.radians([90.0]))
    assert int(found.count[0]) >= 1
    for s in samples:
        for c in s["configurations"]:
            assert c["residual"] < 1e-10
    # Every circuit of every configuration is traced: each sample holds every link.
    status, out, _ = run(capsys, "curve", str(path), "--json")
    assert status == 0
    curve = json.loads(out)
    assert curve["closed"] and all(None not in p for p in curve["points"])


def test_irrational_gear_ratio_is_a_clear_error(capsys, tmp_path):
    doc = {
        "format": "linkwright/1",
        "mechanism": {
            "family": "geared-fivebar",
            "A0": [0, 0],
            "B0": [3, 0],
            "crank1": 1,
            "crank2": 1,
            "link1": 3,
            "link2": 3,
            "ratio": 2**0.5,
        },
    }
    path = tmp_path / "irrational.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    for command in ("curve", "analyze"):
        status, _, err = run(capsys, command, str(path))
        assert status == 2 and "1.41421356237 is not a fraction" in err, err
    status, _, _ = run(capsys, "solve", str(path), "--input", "10")
    assert status == 0  # solving at given inputs needs no period

"""Every CSV and text the command line writes reads back as numbers (issue 27, item 1), and no
NumPy warning reaches standard error (issue 20, item 5).

Each CSV is parsed with the csv module: every cell is a number (``float`` reads it; finite
unless the column is declared to hold ``inf``), or empty where the column is declared to have
missing values, or text where the column is declared text. Text outputs never hold a NumPy
repr (``np.float64(…)``) or a NaN.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import subprocess
import sys
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pytest

from linkwright.cli import main

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "src" / "linkwright" / "examples"

BAD_TEXT = re.compile(r"np\.|numpy\.|\bnan\b|\binf\b", re.IGNORECASE)


def run(capsys, *args: object) -> str:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert status == 0, err
    assert err == ""
    return out


def check_csv(
    text: str,
    *,
    header: Iterable[str] | None = None,
    text_columns: Iterable[str] = (),
    empty: Iterable[str] = (),
    infinite: Iterable[str] = (),
) -> list[dict[str, str]]:
    """The rows of a CSV whose every cell is what its column declares (see the module notes)."""
    rows = list(csv.reader(io.StringIO(text)))
    assert rows, "no rows"
    names = rows[0]
    if header is not None:
        assert names == list(header)
    assert len(rows) > 1, "a header and no data"
    text_columns, empty, infinite = set(text_columns), set(empty), set(infinite)
    assert (text_columns | empty | infinite) <= set(names)
    out = []
    for number, row in enumerate(rows[1:], start=2):
        assert len(row) == len(names), f"row {number}: {len(row)} cells, header {len(names)}"
        for name, cell in zip(names, row, strict=True):
            where = f"row {number}, column {name}: {cell!r}"
            assert "np." not in cell and "numpy" not in cell, where
            if name in text_columns:
                assert cell.strip(), where
                continue
            if cell == "":
                assert name in empty, where
                continue
            value = float(cell)  # raises on anything that is not a number
            assert not math.isnan(value), where
            assert math.isfinite(value) or name in infinite, where
        out.append(dict(zip(names, row, strict=True)))
    return out


def check_text(text: str) -> None:
    assert text.strip()
    for line in text.splitlines():
        assert not BAD_TEXT.search(line), line


POSES4 = "0,0,0\n1,0.2,10\n2,0.5,25\n2.8,1.1,40\n"


# ---------------------------------------------------------------------------------------------
# CSV outputs
# ---------------------------------------------------------------------------------------------


def test_synth_motion_four_poses_csv_reads_back_as_burmester_curves(capsys, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_text(POSES4)
    out = run(capsys, "synth", "motion", "--poses", poses)
    rows = check_csv(
        out, header=["beta2_deg", "closure", "centre_x", "centre_y", "circle_x", "circle_y"]
    )
    assert {r["closure"] for r in rows} <= {"0", "1"}
    # The numbers read back are what they claim: each circle point, carried through the four
    # poses with the body, stays on one circle about its centre point.
    pose = np.array([[float(v) for v in line.split(",")] for line in POSES4.split()])
    for r in rows[:: max(1, len(rows) // 25)]:
        g = np.array([float(r["centre_x"]), float(r["centre_y"])])
        m = np.array([float(r["circle_x"]), float(r["circle_y"])])
        radii = []
        for x, y, ang in pose:
            t = math.radians(ang - pose[0, 2])
            rot = np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])
            radii.append(np.linalg.norm([x, y] + rot @ (m - pose[0, :2]) - g))
        assert np.ptp(radii) <= 1e-7 * max(1.0, max(radii)), r


@pytest.mark.parametrize(
    "name",
    ["crank-rocker", "rocker-input", "slider-crank", "geared-fivebar", "jansen-leg",
     "paper000-fig6-crank-rocker", "paper001-stephenson3"],
)  # fmt: skip
def test_curve_csv(capsys, name):
    out = run(capsys, "curve", name, "--csv", "--points", 48)
    axes = "xyz" if name.startswith("paper00") else "xy"
    rows = check_csv(out, header=["input_deg", *axes, "assembly"], empty=axes)
    assert all(r["assembly"] in ("1", "-1") for r in rows)
    assert sum(r["x"] != "" for r in rows) == len(rows)  # every sample of these is placed


@pytest.mark.parametrize("name", ["crank-rocker", "jansen-leg", "paper000-fig6-crank-rocker"])
def test_export_csv(capsys, tmp_path, name):
    out = tmp_path / f"{name}.csv"
    run(capsys, "export", name, "--out", out, "--samples", 24)
    rows = check_csv(out.read_text())
    assert [int(r["sample"]) for r in rows] == list(range(24))


def test_paper_tables_000_and_001(capsys, tmp_path):
    run(capsys, "papers", "000", "--out", tmp_path)
    run(capsys, "papers", "001", "--out", tmp_path)
    check_csv(
        (tmp_path / "paper000-point-checks.csv").read_text(),
        text_columns=["case", "point"],
        infinite=["first_at_zero"],  # documented: where eq. 7's first line is 0/0
    )
    check_csv((tmp_path / "paper000-eq5-checks.csv").read_text(), text_columns=["case"])
    fig8 = check_csv(
        (tmp_path / "paper000-fig8-readings.csv").read_text(),
        text_columns=["full", "arcs", "e_branches_distinct"],
    )
    for row in fig8:
        assert row["full"] in ("true", "false") and row["e_branches_distinct"] in ("true", "false")
        arcs = json.loads(row["arcs"])  # a JSON list of [start, end] in degrees
        assert all(len(a) == 2 and all(math.isfinite(v) for v in a) for a in arcs)
    check_csv(
        (tmp_path / "paper001-counts.csv").read_text(),
        empty=["ab_max_residual", "fg_max_residual"],  # no configuration, no residual
    )
    check_csv((tmp_path / "paper001-configurations.csv").read_text())


def test_paper_003_tables_write_numpy_values_as_numbers(tmp_path):
    from dataclasses import replace

    from linkwright.papers import p003

    # The cells as NumPy scalars, as a computation may well hand them over.
    def numpy(x: float | None) -> np.float64 | None:
        return None if x is None else np.float64(x)

    cells = [
        replace(c, ours=numpy(c.ours), low=numpy(c.low), high=numpy(c.high), grid=numpy(c.grid))
        for c in p003.reproduce_spherical()
    ]
    for path in p003.write_tables(cells, tmp_path)[:3]:  # Table 4 is planar: none here
        rows = check_csv(
            path.read_text(),
            header=p003.CSV_FIELDS,
            text_columns=["table", "side", "row", "column", "status"],
            empty=["grid", "literal"],
        )
        by_key = {(c.table, c.row, c.column): c for c in cells}
        for r in rows:
            assert float(r["ours"]) == by_key[(r["table"], r["row"], r["column"])].ours


# ---------------------------------------------------------------------------------------------
# Text outputs
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args",
    [
        ["solve", "crank-rocker", "--all"],
        ["solve", "triple-rocker", "--all", "--derivatives"],
        ["solve", "paper001-stephenson3", "--all", "--input", "0:360:60"],
        ["curve", "paper000-fig8-sixbar", "--points", "24"],
        ["synth", "ellipse", "--conic", "1,0,4,-2,8,-11", "--family-samples", "3"],
        ["synth", "function", "--pairs", "40,70;75,95;110,115", "--frame", "2"],
        ["synth", "reinsberg", "paper003-table3-drag-link", "--solve", "rocker"],
    ],
)
def test_text_outputs_hold_no_numpy_reprs_or_nan(capsys, args):
    check_text(run(capsys, *args))


def test_analyze_text_of_every_example(capsys):
    from linkwright.io import list_examples

    for name in list_examples():
        status = main(["analyze", name])
        out, err = capsys.readouterr()
        if status == 2:  # a Stephenson III driven at its output: said in one line
            assert err.startswith("error: ") and len(err.splitlines()) == 1
            continue
        assert status == 0 and err == "", (name, err)
        check_text(out)


def test_synth_motion_text_of_three_and_five_poses(capsys, tmp_path):
    three, five = tmp_path / "three.csv", tmp_path / "five.csv"
    three.write_text("0,0,0\n1,0.2,10\n2,0.5,25\n")
    five.write_text(POSES4 + "3.2,2,60\n")
    check_text(run(capsys, "synth", "motion", "--poses", three, "--circles", "0,1,2,1.5"))
    check_text(run(capsys, "synth", "motion", "--poses", five, "--pair", "0"))


def test_atlas_query_and_info_text(capsys, tmp_path):
    from linkwright.atlas import build

    build("fourbar", 2000, tmp_path / "atlas", shard_size=1000, workers=0)
    curve = EX / "drawn-curve.csv"
    check_text(run(capsys, "atlas", "query", tmp_path / "atlas", "--points", curve, "--quiet"))
    check_text(run(capsys, "atlas", "info", tmp_path / "atlas"))


def test_demo_summary_is_numbers_and_strict_json(tmp_path, monkeypatch):
    import linkwright.plot as plot
    from linkwright import demo
    from linkwright.papers import p000, p001, p002, p003, p004

    # Pictures and papers are checked elsewhere; here only the summary the demo writes.
    for name in ("plot_mechanism", "plot_diagram", "save_figure", "animate"):
        monkeypatch.setattr(plot, name, lambda *a, **k: None)
    for paper in (p000, p001, p002, p003, p004):
        monkeypatch.setattr(paper, "reproduce", lambda out: [])
    demo.run_demo(tmp_path)
    check_text((tmp_path / "summary.md").read_text())

    def no_constant(word: str) -> None:
        raise AssertionError(f"summary.json holds {word}")

    json.loads((tmp_path / "summary.json").read_text(), parse_constant=no_constant)


# ---------------------------------------------------------------------------------------------
# No NumPy warning on standard error (issue 20, item 5)
# ---------------------------------------------------------------------------------------------

# Paper 002's geared five-bar with its cranks equal and in phase (ratio 1): the distance A–B is
# the constant 1, so the dyad's closure is flat in the input, and links 3 and 5 cannot close it.
FLAT_FIVEBAR = {
    "format": "linkwright/1",
    "mechanism": {"family": "geared-fivebar", "A0": [0.0, 0.0], "B0": [1.0, 0.0],
                  "crank1": 4.0, "crank2": 4.0, "link1": 3.0, "link2": 5.0, "ratio": 1.0},
}  # fmt: skip


def test_a_flat_closure_warns_nothing(tmp_path):
    path = tmp_path / "flat.json"
    path.write_text(json.dumps(FLAT_FIVEBAR))
    done = subprocess.run(
        [sys.executable, "-m", "linkwright", "analyze", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0 and done.stderr == ""
    assert "assembles               no" in done.stdout


@pytest.mark.parametrize(("link1", "link2"), [(3, 5), (3, 3.5), (0.5, 0.5)])
@pytest.mark.parametrize("b0", [[1.0, 0.0], [0.0, 0.0]])
def test_flat_closures_decide_without_warnings(link1, link2, b0):
    import warnings

    from linkwright.analysis import analyze
    from linkwright.io.report import analysis_report
    from linkwright.mechanisms import GearedFiveBar, input_range

    m = GearedFiveBar(A0=[0, 0], B0=b0, crank1=4, crank2=4, link1=link1, link2=link2, ratio=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arcs = input_range(m)
        report = analysis_report(analyze(m))
    # |A B| = |B0 − A0| at every input: the dyad closes everywhere or nowhere, by the triangle
    # inequality on 1 (or 0, coincident pivots: never), link1 and link2.
    d = math.dist(b0, [0, 0])
    closes = abs(link1 - link2) <= d <= link1 + link2 and d > 0
    assert bool(arcs.full) == closes and bool(arcs.never) == (not closes)
    assert report["assembles"] == closes

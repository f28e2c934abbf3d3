"""Multi-objective path synthesis (synthesis/pareto.py, `synth pareto`): every design of the
front is re-read, solved again here, its objectives recomputed by a second method (the
four-bar's closed-form transmission extremes, its link lengths from its document) and the
front checked for non-dominance."""

from __future__ import annotations

import json

import numpy as np
import pytest

from linkwright.analysis.planar import transmission_extremes
from linkwright.cli import main
from linkwright.io import parse_document
from linkwright.mechanisms import solve
from linkwright.synthesis.pareto import ParetoError, non_dominated, pareto_path

T = np.linspace(0, 2 * np.pi, 10, endpoint=False)
POINTS = np.c_[2 + np.cos(T), 1 + 0.5 * np.sin(T)]


def _dominated(values, senses):
    v = np.asarray(values) * np.asarray(senses)
    return [any(np.all(o <= x) and np.any(o < x) for o in v) for x in v]


def test_non_dominated_against_a_brute_force_count():
    rng = np.random.default_rng()
    for _ in range(20):
        values = rng.integers(0, 5, size=(12, 2)).astype(float)
        for senses in ((1, 1), (1, -1)):
            assert non_dominated(values, senses).tolist() == [
                not d for d in _dominated(values, senses)
            ]


def test_transmission_front_recomputed(capsys, tmp_path):
    front = pareto_path("fourbar", POINTS, levels=3, budget=4.5, closed=True, timing="none")
    assert front
    for d in front:
        reached = solve(d.mechanism, d.inputs, order=0).positions["P"]
        assert abs(np.sum((reached - POINTS) ** 2) - d.error) <= 1e-12 * max(1.0, d.error)
        tx = transmission_extremes(d.mechanism)
        closed_form = np.degrees(min(float(tx["min"]), np.pi - float(tx["max"])))
        # 2048 samples of the circuit against the closed-form extremes.
        assert abs(closed_form - d.second) < 0.05
        assert d.second >= d.level - 1e-6  # the ε-constraint held
    assert not any(_dominated([[d.error, d.second] for d in front], (1, -1)))


def test_size_front_and_cli(capsys, tmp_path):
    csv = tmp_path / "points.csv"
    csv.write_text("\n".join(f"{x!r},{y!r}" for x, y in POINTS.tolist()))
    png = tmp_path / "front.png"
    status = main(["synth", "pareto", "--family", "fourbar", "--points", str(csv),
                   "--objectives", "error,size", "--levels", "3", "--budget", "4.5",
                   "--closed", "--no-timing", "--json", "--quiet", "--plot", str(png)])  # fmt: skip
    out, err = capsys.readouterr()
    assert status == 0, err
    report = json.loads(out)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    diameter = max(np.linalg.norm(a - b) for a in POINTS for b in POINTS)
    rows = []
    for d in report["designs"]:
        mech = parse_document(d["mechanism"]).mechanism
        reached = solve(mech, np.radians(d["inputs_deg"]), order=0).positions["P"]
        assert abs(np.sum((reached - POINTS) ** 2) - d["error"]) <= 1e-9 * max(1.0, d["error"])
        links = [float(mech.crank), float(mech.coupler), float(mech.rocker),
                 float(np.linalg.norm(np.asarray(mech.B0) - np.asarray(mech.A0)))]  # fmt: skip
        assert abs(max(links) / diameter - d["size"]) < 1e-12
        rows.append([d["error"], d["size"]])
    assert rows and not any(_dominated(rows, (1, 1)))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"objectives": ("error", "speed")}, "objectives"),
        ({"objectives": ("transmission", "error")}, "objectives"),
        ({"levels": 1}, "levels"),
        ({"levels": 30}, "levels"),
        ({"levels": 10, "budget": 1.0}, "budget"),
    ],
)
def test_bad_requests_are_one_line(kwargs, message):
    with pytest.raises(ParetoError, match=message) as info:
        pareto_path("fourbar", POINTS, **kwargs)
    assert "\n" not in str(info.value)


def test_cli_bad_objectives_is_one_line(capsys, tmp_path):
    csv = tmp_path / "points.csv"
    csv.write_text("0,0\n1,0\n1,1\n")
    status = main(["synth", "pareto", "--family", "fourbar", "--points", str(csv),
                   "--objectives", "error,speed"])  # fmt: skip
    _, err = capsys.readouterr()
    assert status == 2 and err.count("\n") == 1 and "objectives" in err

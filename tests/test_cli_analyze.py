"""`linkwright analyze`: a linkage that cannot be assembled has no motion class (issue 27, item
3), and its angles are absolute, as `solve` takes them, with the frame-relative ones under names
that say so (item 4). Every check measures the solved positions here."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from linkwright.cli import main


def run_json(capsys, *args: object) -> dict:
    status = main([str(a) for a in args] + ["--json"])
    out, err = capsys.readouterr()
    assert status == 0 and err == "", err
    return json.loads(out)


def run_text(capsys, *args: object) -> str:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert status == 0 and err == "", err
    return out


def document(tmp_path: Path, name: str, mechanism: dict) -> Path:
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps({"format": "linkwright/1", "mechanism": mechanism}))
    return path


def rotated(angle_deg: float, origin: list[float], point: list[float]) -> list[float]:
    t = math.radians(angle_deg)
    x, y = point
    return [
        origin[0] + x * math.cos(t) - y * math.sin(t),
        origin[1] + x * math.sin(t) + y * math.cos(t),
    ]


# ---------------------------------------------------------------------------------------------
# Item 3: no motion class without a motion
# ---------------------------------------------------------------------------------------------

NEVER = {
    # The issue's four-bar: frame 1, crank 1, coupler 1, rocker 5 (5 > 1 + 1 + 1).
    "fourbar": {"family": "fourbar", "A0": [0, 0], "B0": [1, 0], "crank": 1, "coupler": 1,
                "rocker": 5},
    # Its far cousin: the frame too long.
    "fourbar-far": {"family": "fourbar", "A0": [0, 0], "B0": [10, 0], "crank": 1, "coupler": 2,
                    "rocker": 3},
    # Arcs 10, 20, 30 and a 90° rocker: the loop cannot close on the sphere either.
    "spherical-fourbar": {"family": "spherical-fourbar", "frame": 10, "crank": 20, "coupler": 30,
                          "rocker": 90},
    # The crank end stays 2 ± 0.5 from the line; the rod is 1.
    "slidercrank": {"family": "slidercrank", "A0": [0, 0], "crank": 0.5, "rod": 1,
                    "line": {"point": [0, -2], "angle": 0}},
    # Cranks equal and in phase: |A B| = 1 always, links 3 and 5 cannot close it.
    "geared-fivebar": {"family": "geared-fivebar", "A0": [0, 0], "B0": [1, 0], "crank1": 4,
                       "crank2": 4, "link1": 3, "link2": 5, "ratio": 1},
}  # fmt: skip


@pytest.mark.parametrize("name", list(NEVER))
def test_a_linkage_that_never_assembles_has_no_class(capsys, tmp_path, name):
    path = document(tmp_path, name, NEVER[name])
    report = run_json(capsys, "analyze", path)
    assert report["assembles"] is False and report["reason"]
    # Families with a motion class say it has none; the others have no class key at all.
    assert report.get("class") is None
    text = run_text(capsys, "analyze", path)
    lines = {line.split()[0]: line.split(None, 1)[1] for line in text.splitlines()[1:]
             if len(line.split()) > 1 and not line.startswith(" ")}  # fmt: skip
    assert lines["assembles"] == "no"
    if "class" in report:
        assert lines["class"] == "-"
    # And it truly does not: solve finds no configuration at any of 72 inputs.
    solved = run_json(capsys, "solve", path, "--all", "--input", "0:355:5")
    assert all(not s["configurations"] for s in solved["samples"])


def test_the_issue_fourbar_says_which_link_is_too_long(capsys, tmp_path):
    report = run_json(capsys, "analyze", document(tmp_path, "long", NEVER["fourbar"]))
    assert "the rocker (5) is longer than the other three links together (3)" in report["reason"]


def test_a_linkage_that_assembles_keeps_its_class(capsys):
    assert run_json(capsys, "analyze", "triple-rocker")["class"] == "triple-rocker"
    assert run_json(capsys, "analyze", "crank-rocker")["class"] == "crank-rocker"


# ---------------------------------------------------------------------------------------------
# Item 4: absolute angles, and frame-relative ones by name
# ---------------------------------------------------------------------------------------------

TURN = 40.0  # the frame line's direction in the documents below


def _rocker_input(tmp_path: Path) -> Path:
    """rocker-input.toml (frame 4, crank 3.5, coupler 5, rocker 1: the input only rocks) with
    its frame turned by 40° about A0 = (1, 2)."""
    a0 = [1.0, 2.0]
    return document(tmp_path, "rocker-input-turned", {
        "family": "fourbar", "A0": a0, "B0": rotated(TURN, a0, [4, 0]), "crank": 3.5,
        "coupler": 5, "rocker": 1, "point": {"u": 2, "v": 1},
    })  # fmt: skip


def _crank_rocker(tmp_path: Path) -> Path:
    a0 = [-1.0, 0.5]
    return document(tmp_path, "crank-rocker-turned", {
        "family": "fourbar", "A0": a0, "B0": rotated(TURN, a0, [3.5, 0]), "crank": 1,
        "coupler": 5, "rocker": 6.02,
    })  # fmt: skip


def _rocker_slider(tmp_path: Path) -> Path:
    """Crank 2, rod 3, the line 1.5 below A0 and turned by 40°: the crank rocks, its limits
    where the rod stands square to the line."""
    return document(tmp_path, "rocker-slider-turned", {
        "family": "slidercrank", "A0": [0, 0], "crank": 2, "rod": 3,
        "line": {"point": rotated(TURN, [0, 0], [0, -1.5]), "angle": TURN},
    })  # fmt: skip


def _joints(sample: dict) -> list[dict[str, np.ndarray]]:
    return [{k: np.array(v) for k, v in c["joints"].items()} for c in sample["configurations"]]


def test_fourbar_limit_angles_fed_to_solve_land_on_the_limit(capsys, tmp_path):
    path = _rocker_input(tmp_path)
    report = run_json(capsys, "analyze", path)
    assert report["reference_angle_deg"] == pytest.approx(TURN)
    limits = report["limit_positions_deg"]
    assert len(limits) == 4
    # The same limits from the frame line are the absolute ones less the frame's direction.
    for absolute, from_frame in zip(limits, report["limit_positions_from_frame_deg"], strict=True):
        assert math.remainder(absolute - from_frame - TURN, 360) == pytest.approx(0, abs=1e-9)
    spec = ",".join(repr(a) for a in limits)
    solved = run_json(capsys, "solve", path, "--input", spec, "--all")
    for sample in solved["samples"]:
        configurations = _joints(sample)
        assert configurations, sample
        for j in configurations:
            # At a limit the dyad B is flat: A, B and B0 in line, |A B0| = coupler ± rocker.
            ab, bb0 = j["B"] - j["A"], j["B0"] - j["B"]
            flat = abs(ab[0] * bb0[1] - ab[1] * bb0[0]) / (5 * 1)
            assert flat < 1e-6, (sample["input_deg"], flat)
            reach = np.linalg.norm(j["B0"] - j["A"])
            assert min(abs(reach - 6), abs(reach - 4)) < 1e-9


def test_slider_limit_angles_fed_to_solve_land_on_the_limit(capsys, tmp_path):
    path = _rocker_slider(tmp_path)
    report = run_json(capsys, "analyze", path)
    assert report["class"] == "rocker-slider"
    direction = np.array([math.cos(math.radians(TURN)), math.sin(math.radians(TURN))])
    solved = run_json(capsys, "solve", path, "--all", "--input",
                      ",".join(repr(a) for a in report["limit_positions_deg"]))  # fmt: skip
    for sample in solved["samples"]:
        for j in _joints(sample):
            # At a limit the rod stands square to the slider's line.
            rod = j["B"] - j["A"]
            assert abs(rod @ direction) / 3 < 1e-6, sample["input_deg"]


def test_transmission_extremes_are_at_absolute_inputs(capsys, tmp_path):
    # A crank-rocker's transmission angle is least and greatest with the crank along the frame
    # line (closed form: the law of cosines in A B B0 with |A B0| = frame ∓ crank).
    path = _crank_rocker(tmp_path)
    report = run_json(capsys, "analyze", path)
    tx = report["transmission_angle_deg"]
    # γ grows with |A B0|: least with the crank towards B0 (at the frame's direction), greatest
    # pointing away.
    assert tx["min_at_input_deg"] % 360 == pytest.approx(TURN, abs=1e-6)
    assert tx["max_at_input_deg"] % 360 == pytest.approx(TURN + 180, abs=1e-6)
    for d, key in ((3.5 - 1, "min"), (3.5 + 1, "max")):
        law = math.degrees(math.acos((5**2 + 6.02**2 - d * d) / (2 * 5 * 6.02)))
        assert tx[key] == pytest.approx(law, abs=1e-9)
    solved = run_json(capsys, "solve", path, "--input",
                      f"{tx['min_at_input_deg']!r},{tx['max_at_input_deg']!r}")  # fmt: skip
    for sample, want in zip(solved["samples"], (tx["min"], tx["max"]), strict=True):
        (j,) = _joints(sample)
        u, w = j["A"] - j["B"], j["B0"] - j["B"]
        gamma = math.degrees(math.acos(u @ w / np.linalg.norm(u) / np.linalg.norm(w)))
        assert gamma == pytest.approx(want, abs=1e-6)


def test_output_range_is_absolute_and_from_the_frame(capsys, tmp_path):
    path = _crank_rocker(tmp_path)
    report = run_json(capsys, "analyze", path)
    lo, hi = report["output_range_deg"]
    flo, fhi = report["output_range_from_frame_deg"]
    assert math.remainder(lo - flo - TURN, 360) == pytest.approx(0, abs=1e-9)
    assert hi - lo == pytest.approx(fhi - flo) == pytest.approx(report["swing_deg"])
    # Measured: the direction of B − B0 over a whole turn spans exactly that range.
    solved = run_json(capsys, "solve", path, "--input", "0:359.5:0.5")
    angles = []
    for sample in solved["samples"]:
        (j,) = _joints(sample)
        d = j["B"] - j["B0"]
        angles.append(math.degrees(math.atan2(d[1], d[0])))
    centred = [lo + math.remainder(a - lo, 360) for a in angles]
    assert min(centred) == pytest.approx(lo, abs=1e-3) and max(centred) == pytest.approx(
        hi, abs=1e-3
    )


def test_spherical_input_angles_are_the_documents(capsys):
    # On the sphere the document's θ is already measured from the frame circle: both agree.
    report = run_json(capsys, "analyze", "paper003-table3-drag-link")
    for key in ("input_range", "input_arcs", "limit_positions", "output_range"):
        assert report[f"{key}_deg"] == report[f"{key}_from_frame_deg"]
    assert report["reference_angle_deg"] == 0.0


def test_spherical_limit_angles_fed_to_solve_land_on_the_limit(capsys, tmp_path):
    # Paper 003's arcs α1 = 60 (crank), α2 = 30, α3 = 35, α4 = 40 (frame): a triple-rocker.
    path = document(tmp_path, "sphere-rocks", {
        "family": "spherical-fourbar", "frame": 40, "crank": 60, "coupler": 30, "rocker": 35,
    })  # fmt: skip
    report = run_json(capsys, "analyze", path)
    assert report["class"] == "triple-rocker" and len(report["limit_positions_deg"]) == 2
    solved = run_json(capsys, "solve", path, "--all", "--input",
                      ",".join(repr(a) for a in report["limit_positions_deg"]))  # fmt: skip
    for sample in solved["samples"]:
        assert sample["configurations"], sample
        for j in _joints(sample):
            # At a limit the coupler and rocker lie on one great circle: A, B, B0 coplanar.
            assert abs(np.linalg.det(np.stack([j["A"], j["B"], j["B0"]]))) < 1e-6

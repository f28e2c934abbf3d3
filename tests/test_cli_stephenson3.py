"""The Stephenson III through the command line: `solve` without `--all` gives the document's
configuration where the input leaves a triad (its pose index; issue 27, item 5, and issue 21),
and what the docs say of the
spherical one's `sigma` is what the solved positions measure (item 2)."""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from linkwright.cli import main

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "src" / "linkwright" / "examples"
DOCS = ROOT / "docs" / "cli.md"


def run(capsys, *args: object) -> str:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert status == 0 and err == "", err
    return out


def solve_json(capsys, *args: object) -> dict:
    return json.loads(run(capsys, "solve", *args, "--json"))


def variant(tmp_path: Path, example: str, **changes: object) -> tuple[Path, dict]:
    raw = tomllib.loads((EX / f"{example}.toml").read_text())
    raw["mechanism"].update(changes)
    path = tmp_path / f"{example}-{'-'.join(f'{k}{v}' for k, v in changes.items())}.json"
    path.write_text(json.dumps(raw))
    return path, raw["mechanism"]


def cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def sign(x: float) -> int:
    return 1 if x > 0 else -1 if x < 0 else 0


# Independent readings of each configuration: its signs as the families define them, and the
# quantity solve_all orders its configurations by.


def planar_signs(j: dict[str, np.ndarray]) -> tuple[int, int]:
    return (sign(cross(j["B0"] - j["A"], j["B"] - j["A"])),
            sign(cross(j["D0"] - j["C"], j["D"] - j["C"])))  # fmt: skip


def planar_order(j: dict[str, np.ndarray]) -> float:
    d = j["B"] - j["A"]
    return math.atan2(d[1], d[0])  # the coupler's angle


def sphere_signs(j: dict[str, np.ndarray]) -> tuple[int, int]:
    return (sign(float(np.cross(j["B"], j["D"]) @ j["C"])),
            sign(float(np.cross(j["E"], j["G"]) @ j["F"])))  # fmt: skip


def sphere_order(j: dict[str, np.ndarray]) -> float:
    return math.atan2(j["B"][0], j["B"][1])  # θ1 of eq. 5: B = (s sin θ1, s cos θ1, c)


def configurations(sample: dict) -> list[dict[str, np.ndarray]]:
    return [{k: np.array(v) for k, v in c["joints"].items()} for c in sample["configurations"]]


CASES = {
    "planar": ("stephenson3-example", {"input": "output"}, planar_signs, planar_order),
    "spherical": ("paper001-stephenson3", {"input": "FG"}, sphere_signs, sphere_order),
}


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("pose", [0, 1, 3])
def test_solve_without_all_gives_the_documents_configuration(capsys, tmp_path, case, pose):
    """Without --all, the document's pose: the pose-th of the configurations --all lists at
    that input, in the stated order (read off the positions here), or a reason where there are
    fewer."""
    example, changes, _, order = CASES[case]
    path, _ = variant(tmp_path, example, **changes, pose=pose)
    grid = "0:355:5"
    every = solve_json(capsys, path, "--input", grid, "--all")["samples"]
    own = solve_json(capsys, path, "--input", grid)
    assert own["pose"] == pose and own["rule"]
    shown = 0
    for all_sample, sample in zip(every, own["samples"], strict=True):
        assert sample["input_deg"] == all_sample["input_deg"]
        listed = sorted(configurations(all_sample), key=order)
        got = configurations(sample)
        if len(listed) <= pose:
            assert got == [] and sample["reason"]
            continue
        (j,) = got
        for name in j:
            np.testing.assert_allclose(j[name], listed[pose][name], atol=1e-12)
        shown += 1
    if pose == 0:
        assert shown > 0


@pytest.mark.parametrize("case", list(CASES))
def test_solve_text_without_all_is_not_the_all_listing(capsys, tmp_path, case):
    example, changes, _, _ = CASES[case]
    path, _ = variant(tmp_path, example, **changes)
    everything = run(capsys, "solve", path, "--input", "0:350:10", "--all")
    own = run(capsys, "solve", path, "--input", "0:350:10")
    assert own != everything
    assert "# driven so that a triad remains; shown: the document's pose" in own
    rows = [line for line in own.splitlines() if line and not line.startswith(("#", " input"))]
    assert len(rows) == 36  # one line per input: a configuration, or why there is none


def test_the_chosen_planar_configuration_closes_every_loop(capsys, tmp_path):
    path, m = variant(tmp_path, "stephenson3-example", input="output")
    own = solve_json(capsys, path, "--input", "0:355:5")
    for sample in own["samples"]:
        for j in configurations(sample):
            t = math.radians(sample["input_deg"])
            np.testing.assert_allclose(
                j["D"], np.array(m["D0"]) + m["link2"] * np.array([math.cos(t), math.sin(t)]),
                atol=1e-10,
            )  # fmt: skip
            for a, b, length in (("A0", "A", m["crank"]), ("A", "B", m["coupler"]),
                                 ("B0", "B", m["rocker"]), ("C", "D", m["link1"])):  # fmt: skip
                assert np.linalg.norm(j[b] - j[a]) == pytest.approx(length, abs=1e-10)


# ---------------------------------------------------------------------------------------------
# sigma (issue 27, item 2)
# ---------------------------------------------------------------------------------------------


def angle_bce(j: dict[str, np.ndarray]) -> float:
    """The spherical angle at C between the great circles C→B and C→E, in degrees."""

    def tangent(x: np.ndarray) -> np.ndarray:
        t = x - (x @ j["C"]) * j["C"]
        return t / np.linalg.norm(t)

    return math.degrees(math.acos(np.clip(tangent(j["B"]) @ tangent(j["E"]), -1, 1)))


def _doc_row() -> str:
    (row,) = [line for line in DOCS.read_text().splitlines()
              if line.startswith("| `spherical-stephenson3`")]  # fmt: skip
    return row


def test_the_docs_say_what_sigma_is_as_measured(capsys, tmp_path):
    row = _doc_row()
    assert "`sigma` (angle BCE)" not in row
    assert "angle BCE = 180° − σ" in row
    stated = re.search(r"σ = (\d+) gives angle BCE = (\d+)°", row)
    assert stated, row
    sigma, bce = (float(g) for g in stated.groups())
    path, _ = variant(tmp_path, "paper001-stephenson3", sigma=sigma)
    for flags in ((), ("--all",)):
        solved = solve_json(capsys, path, "--input", "0:350:25", *flags)
        measured = [angle_bce(j) for s in solved["samples"] for j in configurations(s)]
        assert len(measured) >= 10
        assert measured == pytest.approx([bce] * len(measured), abs=1e-9)


@pytest.mark.parametrize("sigma", [30.0, 100.0, 150.0])
def test_angle_bce_is_180_minus_sigma_whatever_drives_it(capsys, tmp_path, sigma):
    for changes in ({}, {"input": "FG"}):
        path, _ = variant(tmp_path, "paper001-stephenson3", sigma=sigma, **changes)
        solved = solve_json(capsys, path, "--input", "0:350:10", "--all")
        measured = [angle_bce(j) for s in solved["samples"] for j in configurations(s)]
        assert measured and measured == pytest.approx([180 - sigma] * len(measured), abs=1e-9)

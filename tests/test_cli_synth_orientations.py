"""``linkwright synth orientations --sphere``: every printed spherical four-bar is re-read as a
document, solved here by the engine, and its coupler's orientations compared with the ones in
the file (independently of the command's own error figures)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from linkwright.cli import main
from linkwright.io import parse_document
from linkwright.mechanisms import solve
from linkwright.mechanisms.spherical import SphericalFourBar

TOL = 1e-9


def run(capsys, *args: str) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def _frame(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # The coupler's frame from its two joint axes, written here apart from the library's.
    t = b - np.dot(a, b) * a
    t = t / np.linalg.norm(t)
    return np.stack([a, t, np.cross(a, t)], axis=-1)


def _check(report: dict, q: np.ndarray, point=(1.0, 0.0, 0.0)) -> None:
    mech = parse_document(report["mechanism"]).mechanism
    r = np.asarray(report["rotation"])
    frames, points = [], []
    for theta, sign in zip(np.radians(report["inputs_deg"]), report["branches"], strict=True):
        m = solve(replace(mech, assembly=float(sign)), [theta], order=0)
        assert m.valid[0]
        frames.append(_frame(m.positions["A"][0], m.positions["B"][0]))
        points.append(m.positions["P"][0])
    for j in range(len(q)):
        want = r @ q[j] @ q[0].T @ r.T @ frames[0]
        assert np.max(np.abs(frames[j] - want)) < TOL
        assert np.max(np.abs(points[j] - r @ q[j] @ np.asarray(point))) < TOL


def _write(tmp_path, rows, header="") -> str:
    path = tmp_path / "orientations.csv"
    path.write_text(header + "\n".join(",".join(repr(float(v)) for v in row) for row in rows))
    return str(path)


def test_three_orientations_as_axis_angle_rows(capsys, tmp_path):
    rows = [[0, 0, 1, 0], [0, 0.3, 1, 30], [0.2, 0.5, 1, 55]]
    # The same rotations built by SciPy (an independent axis-angle → matrix conversion).
    q = np.stack([
        Rotation.from_rotvec(np.radians(a) * np.array(k) / np.linalg.norm(k)).as_matrix()
        for *k, a in rows
    ])  # fmt: skip
    file = _write(tmp_path, rows, "# x, y, z, angle_deg\n")
    status, out, err = run(capsys, "synth", "orientations", "--sphere", "--poses", file,
                           "--circles", "0.2,0.3,0.9,0.6,-0.2,0.8", "--json")  # fmt: skip
    assert status == 0, err
    _check(json.loads(out), q)
    # The text form prints the same linkage as a TOML document.
    status, out, err = run(capsys, "synth", "orientations", "--sphere", "--poses", file,
                           "--circles", "0.2,0.3,0.9,0.6,-0.2,0.8", "--point", "0,1,0")  # fmt: skip
    assert status == 0, err
    assert 'family = "spherical-fourbar"' in out and "largest error" in out


def test_four_orientations_of_a_known_linkage_as_rounded_matrices(capsys, tmp_path):
    fb = SphericalFourBar(*np.radians([60, 25, 50, 45, 30, 40]))
    m = solve(fb, np.radians([0, 25, 50, 80]), order=0)
    q = np.stack([_frame(a, b) for a, b in zip(m.positions["A"], m.positions["B"], strict=True)])
    # Ten decimals: not orthogonal to machine precision, so the command projects them; the check
    # below compares with the unrounded rotations to the rounding's order.
    file = _write(tmp_path, np.round(q.reshape(4, 9), 10))
    status, out, err = run(capsys, "synth", "orientations", "--sphere", "--poses", file,
                           "--t", "20,100", "--json")  # fmt: skip
    assert status == 0, err
    report = json.loads(out)
    assert report["orientation_error"] < 1e-9
    mech = parse_document(report["mechanism"]).mechanism
    r = np.asarray(report["rotation"])
    for j, (theta, sign) in enumerate(zip(np.radians(report["inputs_deg"]), report["branches"],
                                          strict=True)):  # fmt: skip
        s = solve(replace(mech, assembly=float(sign)), [theta], order=0)
        got = _frame(s.positions["A"][0], s.positions["B"][0])
        first = _frame(*(solve(replace(mech, assembly=float(report["branches"][0])),
                               [np.radians(report["inputs_deg"][0])], order=0)
                         .positions[k][0] for k in ("A", "B")))  # fmt: skip
        assert np.max(np.abs(got - r @ q[j] @ q[0].T @ r.T @ first)) < 1e-8


def test_four_orientations_without_t_print_the_cones(capsys, tmp_path):
    q = Rotation.from_euler(
        "zyx", [[0, 0, 0], [30, 10, 5], [55, 25, 0], [80, 30, -10]], degrees=True
    ).as_matrix()
    file = _write(tmp_path, q.reshape(4, 9))
    status, out, err = run(capsys, "synth", "orientations", "--sphere", "--poses", file,
                           "--samples", "36")  # fmt: skip
    assert status == 0, err
    lines = out.strip().splitlines()
    assert lines[0].startswith("t_deg,root,circle_x")
    cells = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert len(cells) > 10
    # Each printed dyad keeps its arc: G · (Q1j − I) W = 0 for j = 2, 3, 4.
    for row in cells:
        w, g = row[2:5], row[5:8]
        for j in range(1, 4):
            assert abs(g @ (q[j] @ q[0].T - np.eye(3)) @ w) < 1e-9
    # A printed pair of (t, root) is a four-bar that reaches every orientation.
    t0, t1 = cells[0], cells[len(cells) // 2]
    status, out, err = run(capsys, "synth", "orientations", "--sphere", "--poses", file,
                           "--t", f"{t0[0]!r},{t1[0]!r}", "--root", f"{int(t0[1])},{int(t1[1])}",
                           "--json")  # fmt: skip
    if status == 0:
        _check(json.loads(out), q)
    else:  # a chosen pair may make a degenerate linkage: then it is said in one line
        assert err.count("\n") == 1 and err.startswith("error:")


@pytest.mark.parametrize(
    ("extra", "rows", "message"),
    [
        ((), [[0, 0, 1, 0], [0, 0, 1, 30], [1, 0, 0, 20]], "--sphere"),
        (("--sphere",), [[0, 0, 1, 0], [0, 0, 1, 30], [1, 0, 0, 20]], "--circles"),
        (("--sphere",), [[0, 0, 1, 0], [0, 0, 1, 30]], "3 or 4 orientations"),
        (("--sphere",), [[0, 0, 0, 10], [0, 0, 1, 30], [1, 0, 0, 20]], "zero vector"),
        (
            ("--sphere",),
            [[1, 0, 0, 0, 1, 0, 0, 0, 1], [2, 0, 0, 0, 1, 0, 0, 0, 1], [1, 0, 0, 0, 1, 0, 0, 0, 1]],
            "not a rotation matrix",
        ),
        (
            ("--sphere", "--circles", "0,0,1,0,1,0"),
            [[0, 0, 1, 0], [0, 0, 1, 0.0], [1, 0, 0, 20]],
            "coincide",
        ),
        (("--sphere", "--t", "10,20"), [[0, 0, 1, 0], [0, 0, 1, 30], [1, 0, 0, 20]], "--t"),
    ],
)
def test_bad_input_is_one_line(capsys, tmp_path, extra, rows, message):
    status, out, err = run(capsys, "synth", "orientations", "--poses", _write(tmp_path, rows),
                           *extra)  # fmt: skip
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("error:") and message in err, err

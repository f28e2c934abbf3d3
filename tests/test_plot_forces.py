"""`plot --kind torque|reactions|shaking` (issue 25): the pictures draw the numbers that
`linkwright forces` prints, in the plane and on the sphere, and bad input ends in one line."""

from __future__ import annotations

import contextlib
import io
import json

import matplotlib
import numpy as np
import pytest

from linkwright.cli import main
from linkwright.dynamics import Loads, MassProps, forces
from linkwright.io.documents import load_example, save_document
from linkwright.mechanisms import FourBar
from linkwright.plot.forces import plot_forces

matplotlib.use("Agg")

PLANE = "\n[mechanism.mass]\ncrank = 0.2\ncoupler = 0.5\nrocker = 0.4\n\n[loads]\nspeed = 120\n"
SPHERE = (
    "\n[mechanism.mass]\ncrank = 0.2\ncoupler = 0.5\nrocker = 0.4\n"
    "\n[loads]\nspeed = 120\ngravity = [0.0, 0.0, -9.81]\nradius = 0.1\n"
)


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def _doc(tmp_path, example: str, extra: str):
    path = tmp_path / f"{example}.toml"
    save_document(load_example(example).raw, path)
    path.write_text(path.read_text() + extra)
    return path


@pytest.mark.parametrize(
    ("example", "extra"),
    [("crank-rocker", PLANE), ("paper000-fig6-crank-rocker", SPHERE)],
)
@pytest.mark.parametrize("kind", ["torque", "reactions", "shaking"])
def test_force_pictures_are_written(tmp_path, example, extra, kind):
    path = _doc(tmp_path, example, extra)
    out = tmp_path / f"{kind}.png"
    code, text, err = _run("plot", str(path), "--kind", kind, "--out", str(out), "--samples", "64")
    assert code == 0, err
    assert out.stat().st_size > 10_000 and text.startswith("wrote ")


def test_the_torque_panel_draws_what_forces_prints(tmp_path):
    """The drawn Newton–Euler line, read back from the axes, is `linkwright forces`'s torque at
    the same inputs (a full turn of a crank-rocker samples the input evenly)."""
    fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3.5, rocker=3)
    theta = np.linspace(0.0, 2 * np.pi, 37)
    f = forces(fb, theta, {"coupler": MassProps(0.5), "rocker": 1.0}, Loads(speed_rpm=90))
    fig = plot_forces(fb, f, "torque")
    drawn = fig.axes[0].lines[0]
    np.testing.assert_allclose(drawn.get_xdata(), np.degrees(theta))
    np.testing.assert_allclose(drawn.get_ydata(), f.input_torque)
    # The CLI prints the same torque for the document of this linkage.
    path = tmp_path / "fb.toml"
    save_document(
        {
            "format": "linkwright/1",
            "mechanism": {
                "family": "fourbar", "A0": [0, 0], "B0": [4, 0], "crank": 1, "coupler": 3.5,
                "rocker": 3, "mass": {"coupler": 0.5, "rocker": 1.0},
            },
            "loads": {"speed": 90},
        },
        path,
    )  # fmt: skip
    code, out, err = _run("forces", str(path), "--input", "0:360:10", "--json")
    assert code == 0, err
    printed = [row["input_torque"] for row in json.loads(out)["samples"]]
    np.testing.assert_allclose(printed, f.input_torque, rtol=1e-12, atol=1e-12)


def test_force_pictures_refuse_bad_masses_in_one_line(tmp_path):
    path = _doc(tmp_path, "crank-rocker", "\n[mechanism.mass]\ncrank = -1\n\n[loads]\nspeed = 60\n")
    code, _, err = _run("plot", str(path), "--kind", "torque", "--out", str(tmp_path / "t.png"))
    assert code != 0 and "mechanism.mass.crank: must be positive" in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("example", "extra"),
    [("crank-rocker", PLANE), ("paper000-fig6-crank-rocker", SPHERE)],
)
def test_the_csv_export_carries_the_forces_that_forces_prints(tmp_path, example, extra):
    path = _doc(tmp_path, example, extra)
    out = tmp_path / "paths.csv"
    code, _, err = _run("export", str(path), "--out", str(out), "--samples", "12")
    assert code == 0, err
    header = out.read_text().splitlines()[0].split(",")
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert "input_torque" in header and "shaking_Fx" in header
    degrees = table[:, header.index("theta_deg")]
    code, text, err = _run(
        "forces", str(path), "--json", "--input", ",".join(f"{d:.15g}" for d in degrees)
    )
    assert code == 0, err
    rows = json.loads(text)["samples"]
    np.testing.assert_allclose(
        table[:, header.index("input_torque")], [r["input_torque"] for r in rows], rtol=1e-9
    )
    np.testing.assert_allclose(
        table[:, header.index("A0_Fx")], [r["reactions"]["A0"][0] for r in rows], rtol=1e-9
    )

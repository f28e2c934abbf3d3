"""The linkwright command line, checked against geometry derived here, not against itself."""

from __future__ import annotations

import itertools
import json
import math
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

import linkwright
from linkwright.cli import CliError, main, parse_inputs

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "src" / "linkwright" / "examples"
TOL = 1e-10


def run(capsys, *args: str) -> tuple[int, str, str]:
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def run_json(capsys, *args: str) -> dict:
    status, out, err = run(capsys, *args, "--json")
    assert status == 0, err
    assert err == ""
    return json.loads(out)


def example(name: str) -> dict:
    import tomllib

    return tomllib.loads((EX / f"{name}.toml").read_text())["mechanism"]


# Independent planar helpers (plain floats, no linkwright code).


def sub(p, q):
    return (p[0] - q[0], p[1] - q[1])


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def dist(p, q):
    return math.hypot(p[0] - q[0], p[1] - q[1])


def sign(x: float) -> int:
    return 1 if x > 0 else -1


def on_frame(a, b, u, v):
    """The point at (u, v) in the frame with origin a and x-axis along a→b, v to the left."""
    length = dist(a, b)
    ex, ey = (b[0] - a[0]) / length, (b[1] - a[1]) / length
    return (a[0] + u * ex - v * ey, a[1] + u * ey + v * ex)


def fourbar_by_hand(m: dict, theta_deg: float, branch: int):
    """A, B, P of a four-bar from the circle intersection, branch = sign((B0−A)×(B−A))."""
    t = math.radians(theta_deg)
    a = (m["A0"][0] + m["crank"] * math.cos(t), m["A0"][1] + m["crank"] * math.sin(t))
    b0 = m["B0"]
    d = dist(a, b0)
    along = (m["coupler"] ** 2 - m["rocker"] ** 2 + d * d) / (2 * d)
    h = math.sqrt(max(m["coupler"] ** 2 - along**2, 0.0))
    ex, ey = (b0[0] - a[0]) / d, (b0[1] - a[1]) / d
    # Left of A→B0 is where (B0 − A) × (B − A) > 0.
    b = (a[0] + along * ex - branch * h * ey, a[1] + along * ey + branch * h * ex)
    p = on_frame(a, b, m["point"]["u"], m["point"]["v"])
    return a, b, p


def check_fourbar_joints(m: dict, theta_deg: float, joints: dict, assembly: int) -> None:
    a0, b0, a, b, p = (joints[k] for k in ("A0", "B0", "A", "B", "P"))
    assert a0 == m["A0"] and b0 == m["B0"]
    t = math.radians(theta_deg)
    assert a[0] - a0[0] == pytest.approx(m["crank"] * math.cos(t), abs=TOL)
    assert a[1] - a0[1] == pytest.approx(m["crank"] * math.sin(t), abs=TOL)
    assert dist(a, a0) == pytest.approx(m["crank"], abs=TOL)
    assert dist(b, a) == pytest.approx(m["coupler"], abs=TOL)
    assert dist(b, b0) == pytest.approx(m["rocker"], abs=TOL)
    assert sign(cross(sub(b0, a), sub(b, a))) == assembly
    q = on_frame(a, b, m["point"]["u"], m["point"]["v"])
    assert p == pytest.approx(list(q), abs=TOL)


# ---------------------------------------------------------------------------------------------
# --version, help, entry points
# ---------------------------------------------------------------------------------------------


def test_version(capsys):
    status, out, err = run(capsys, "--version")
    assert status == 0 and err == ""
    assert out == f"linkwright {linkwright.__version__}\n"
    assert re.fullmatch(r"linkwright \d+\.\d+\.\d+\S*\n", out)


def test_no_arguments_shows_help(capsys):
    status, out, _ = run(capsys)
    assert status == 0
    assert "solve" in out and "curve" in out and "analyze" in out


def test_python_dash_m_and_console_script():
    proc = subprocess.run(
        [sys.executable, "-m", "linkwright", "--version"], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.returncode == 0
    assert proc.stdout == f"linkwright {linkwright.__version__}\n"
    script = Path(sys.executable).with_name("linkwright")
    if script.exists():
        proc = subprocess.run([str(script), "--version"], capture_output=True, text=True)
        assert proc.returncode == 0 and proc.stdout.startswith("linkwright ")


def test_errors_from_a_subprocess_are_one_line_without_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\ncrank = -1\n')
    proc = subprocess.run(
        [sys.executable, "-m", "linkwright", "solve", str(bad)], capture_output=True, text=True
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: ")
    assert "Traceback" not in proc.stderr


# ---------------------------------------------------------------------------------------------
# --input
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        ("0:90:30", [0.0, 30.0, 60.0, 90.0]),
        ("0:100:30", [0.0, 30.0, 60.0, 90.0]),
        ("90:0:-45", [90.0, 45.0, 0.0]),
        ("0:1:0.1", [k / 10 for k in range(11)]),
        ("-10:-10:5", [-10.0]),
        ("15", [15.0]),
        ("1, 2.5,-3", [1.0, 2.5, -3.0]),
        ("0:360:120", [0.0, 120.0, 240.0, 360.0]),
    ],
)
def test_parse_inputs(spec, expected):
    assert parse_inputs(spec) == expected


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("", "empty"),
        ("0:10", "expected START:STOP:STEP"),
        ("0:10:1:2", "expected START:STOP:STEP"),
        ("0:10:0", "STEP must not be zero"),
        ("0:10:-1", "goes away from STOP"),
        ("a:10:1", "START must be a number"),
        ("1,,2", "each angle must be a number"),
        ("nan", "must be a finite number"),
        ("1e999", "must be a finite number"),
        ("0:1e6:1e-3", "more than"),
    ],
)
def test_parse_inputs_errors(spec, message):
    with pytest.raises(CliError, match=re.escape(message)):
        parse_inputs(spec)


def test_default_inputs_are_every_30_degrees_without_360(capsys):
    data = run_json(capsys, "solve", EX / "crank-rocker.toml")
    assert [s["input_deg"] for s in data["samples"]] == [30.0 * k for k in range(12)]


# ---------------------------------------------------------------------------------------------
# solve
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["crank-rocker", "double-crank"])
def test_solve_satisfies_the_loop_equations(capsys, name):
    m = example(name)
    data = run_json(capsys, "solve", EX / f"{name}.toml", "--input", "0:360:15")
    assert data["family"] == "fourbar"
    assert len(data["samples"]) == 25
    for sample in data["samples"]:
        (config,) = sample["configurations"]
        assert config["assembly"] == [m["assembly"]]
        assert set(config["joints"]) == {"A0", "B0", "A", "B", "P"}
        check_fourbar_joints(m, sample["input_deg"], config["joints"], m["assembly"])
        _, b, _ = fourbar_by_hand(m, sample["input_deg"], m["assembly"])
        assert config["joints"]["B"] == pytest.approx(list(b), abs=TOL)


def test_solve_all_gives_both_mirror_configurations(capsys):
    m = example("triple-rocker")
    data = run_json(capsys, "solve", EX / "triple-rocker.toml", "--all", "--input", "-90:90:30")
    for sample in data["samples"]:
        configs = {tuple(c["assembly"]): c["joints"] for c in sample["configurations"]}
        assert set(configs) == {(1,), (-1,)}
        for signs, joints in configs.items():
            check_fourbar_joints(m, sample["input_deg"], joints, signs[0])
        # Mirror images about the line A–B0: reflecting B of one gives B of the other.
        a, b0 = configs[(1,)]["A"], configs[(1,)]["B0"]
        b_up, b_down = configs[(1,)]["B"], configs[(-1,)]["B"]
        length = dist(a, b0)
        ex, ey = (b0[0] - a[0]) / length, (b0[1] - a[1]) / length
        rel = sub(b_up, a)
        along = rel[0] * ex + rel[1] * ey
        mirrored = (a[0] + 2 * along * ex - rel[0], a[1] + 2 * along * ey - rel[1])
        assert b_down == pytest.approx(list(mirrored), abs=TOL)


def test_solve_reports_why_a_linkage_cannot_assemble(capsys):
    m = example("triple-rocker")
    data = run_json(capsys, "solve", EX / "triple-rocker.toml", "--all", "--input", "180")
    (sample,) = data["samples"]
    assert sample["configurations"] == []
    # At θ = 180° A is at (−2, 0), 7 from B0: more than coupler + rocker = 6.5.
    a = (-m["crank"], 0.0)
    assert dist(a, m["B0"]) > m["coupler"] + m["rocker"]
    assert sample["reason"].startswith("cannot be assembled at this input: the coupler and rocker")
    assert "cannot reach" in sample["reason"] and "dyad B" in sample["reason"]


def test_solve_reason_when_the_links_cannot_fold_short_enough(capsys):
    data = run_json(capsys, "solve", EX / "rocker-input.toml", "--input", "0")
    assert "cannot fold that short" in data["samples"][0]["reason"]


def test_slider_crank_solve(capsys):
    m = example("offset-slider-crank")
    data = run_json(capsys, "solve", EX / "offset-slider-crank.toml", "--all", "-i", "0:330:30")
    lp, ang = m["line"]["point"], math.radians(m["line"]["angle"])
    d = (math.cos(ang), math.sin(ang))
    for sample in data["samples"]:
        assert {tuple(c["assembly"]) for c in sample["configurations"]} == {(1,), (-1,)}
        for config in sample["configurations"]:
            j = config["joints"]
            assert set(j) == {"A0", "A", "B", "P"}
            t = math.radians(sample["input_deg"])
            assert j["A"] == pytest.approx([m["crank"] * math.cos(t), m["crank"] * math.sin(t)])
            assert dist(j["A"], j["A0"]) == pytest.approx(m["crank"], abs=TOL)
            assert dist(j["B"], j["A"]) == pytest.approx(m["rod"], abs=TOL)
            assert cross(d, sub(j["B"], lp)) == pytest.approx(0.0, abs=TOL)  # B on the line
            rel = sub(j["A"], lp)
            foot = (
                lp[0] + (rel[0] * d[0] + rel[1] * d[1]) * d[0],
                lp[1] + (rel[0] * d[0] + rel[1] * d[1]) * d[1],
            )
            bh = sub(j["B"], foot)
            assert sign(bh[0] * d[0] + bh[1] * d[1]) == config["assembly"][0]
            q = on_frame(j["A"], j["B"], m["point"]["u"], m["point"]["v"])
            assert j["P"] == pytest.approx(list(q), abs=TOL)


def test_derivatives_match_finite_differences(capsys):
    h = 0.01  # degrees
    theta = 40.0
    spec = f"{theta - h},{theta},{theta + h}"
    data = run_json(capsys, "solve", EX / "crank-rocker.toml", "--derivatives", "-i", spec)
    before, mid, after = (s["configurations"][0] for s in data["samples"])
    hr = math.radians(h)
    for joint in ("A0", "B0", "A", "B", "P"):
        for c in (0, 1):
            p0, p1, p2 = (x["joints"][joint][c] for x in (before, mid, after))
            assert mid["velocity"][joint][c] == pytest.approx((p2 - p0) / (2 * hr), abs=1e-6)
            accel = (p2 - 2 * p1 + p0) / hr**2
            assert mid["acceleration"][joint][c] == pytest.approx(accel, abs=1e-5)


def test_derivatives_are_null_at_a_singular_position(capsys, tmp_path):
    # Coupler and rocker fall in line at θ = 180°: |A B0| = 1 + 2 = 3 = coupler + rocker.
    doc = tmp_path / "toggle.json"
    doc.write_text(
        json.dumps(
            {
                "format": "linkwright/1",
                "mechanism": {
                    "family": "fourbar",
                    "A0": [0, 0],
                    "B0": [2, 0],
                    "crank": 1,
                    "coupler": 1.5,
                    "rocker": 1.5,
                },
            }
        )
    )
    data = run_json(capsys, "solve", doc, "--derivatives", "-i", "90,180")
    regular, toggle = (s["configurations"][0] for s in data["samples"])
    assert all(v is not None for v in regular["velocity"].values())
    assert toggle["joints"]["B"] == pytest.approx([0.5, 0.0], abs=1e-7)
    assert set(toggle["velocity"].values()) == {None}
    assert set(toggle["acceleration"].values()) == {None}


def test_solve_text_output(capsys):
    status, out, err = run(capsys, "solve", EX / "triple-rocker.toml", "-i", "0,180")
    assert status == 0 and err == ""
    assert out.startswith("# Triple-rocker (non-Grashof) [fourbar]")
    assert "B.x" in out and "cannot be assembled at this input" in out
    status, out, _ = run(capsys, "solve", EX / "slider-crank.toml", "--derivatives", "-i", "0")
    assert "velocities, per radian of input" in out and "accelerations" in out


def test_a_bundled_example_can_be_named_instead_of_a_path(capsys):
    data = run_json(capsys, "solve", "double-crank", "-i", "0")
    assert data["family"] == "fourbar"


# ---------------------------------------------------------------------------------------------
# curve
# ---------------------------------------------------------------------------------------------


def test_curve_full_turn_json(capsys):
    m = example("crank-rocker")
    data = run_json(capsys, "curve", EX / "crank-rocker.toml")
    assert (data["family"], data["joint"], data["closed"], data["full_turn"]) == (
        "fourbar",
        "P",
        True,
        True,
    )
    assert data["input_deg"] == pytest.approx([float(k) for k in range(360)], abs=1e-9)
    assert data["assembly"] == [1] * 360
    assert len(data["points"]) == 360
    for deg, p in zip(data["input_deg"], data["points"], strict=True):
        assert p == pytest.approx(list(fourbar_by_hand(m, deg, 1)[2]), abs=TOL)


def test_curve_of_a_rocking_input_changes_branch_at_the_limits(capsys):
    m = example("rocker-input")
    n = 40
    data = run_json(capsys, "curve", EX / "rocker-input.toml", "--points", str(n))
    assert data["full_turn"] is False and data["closed"] is True
    assert data["assembly"] == [1] * (n // 2) + [-1] * (n // 2)
    # Samples 0 and n/2 are the limit positions: coupler and rocker folded in line, one
    # stretched out and the other folded back.
    limits = []
    for k in (0, n // 2):
        t = math.radians(data["input_deg"][k])
        a = (m["crank"] * math.cos(t), m["crank"] * math.sin(t))
        limits.append(dist(a, m["B0"]))
    assert sorted(limits) == pytest.approx(
        [m["coupler"] - m["rocker"], m["coupler"] + m["rocker"]], abs=1e-9
    )
    # Closed: the step from the last point back to the first is no bigger than the others.
    pts = data["points"] + data["points"][:1]
    steps = [dist(p, q) for p, q in itertools.pairwise(pts)]
    assert steps[-1] < 3 * max(steps[:-1])
    rows = zip(data["input_deg"], data["points"], data["assembly"], strict=True)
    for k, (deg, p, s) in enumerate(rows):
        # At a limit the hand formula's sqrt of a near-zero difference keeps only half the digits.
        tol = 1e-6 if k in (0, n // 2) else 1e-9
        assert p == pytest.approx(list(fourbar_by_hand(m, deg, s)[2]), abs=tol)


def test_curve_csv(capsys):
    status, out, err = run(capsys, "curve", EX / "slider-crank.toml", "--csv", "-n", "12")
    assert status == 0 and err == ""
    lines = out.splitlines()
    assert lines[0] == "input_deg,x,y,assembly"
    assert len(lines) == 13
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    assert [r[0] for r in rows] == pytest.approx([30.0 * k for k in range(12)])
    assert {r[3] for r in rows} == {1.0}


def test_curve_text(capsys):
    status, out, _ = run(capsys, "curve", EX / "triple-rocker.toml", "-n", "10")
    assert status == 0
    assert "rocks between its limits" in out
    assert len(out.splitlines()) == 3 + 10


# ---------------------------------------------------------------------------------------------
# analyze and demo
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["crank-rocker", "offset-slider-crank", "rocker-input"])
def test_analyze_json_has_the_keys(capsys, name):
    data = run_json(capsys, "analyze", EX / f"{name}.toml")
    for key in (
        "class",
        "input_range_deg",
        "output_range_deg",
        "swing_deg",
        "transmission_angle_deg",
        "time_ratio",
        "coefficients",
    ):
        assert key in data
    assert {"min", "max"} <= set(data["transmission_angle_deg"])
    assert {"K_omega", "K_epsilon", "K_p", "delta"} <= set(data["coefficients"])


def test_analyze_text(capsys):
    status, out, err = run(capsys, "analyze", EX / "crank-rocker.toml")
    assert status == 0 and err == ""
    assert out.startswith("# Crank-rocker") and "transmission_angle_deg" in out


def test_demo_calls_run_demo_and_prints_its_result(capsys, monkeypatch, tmp_path):
    seen = []
    fake = types.ModuleType("linkwright.demo")

    def run_demo(out_dir):
        seen.append(out_dir)
        return [Path(out_dir) / "a.png", Path(out_dir) / "b.csv"]

    fake.run_demo = run_demo
    monkeypatch.setitem(sys.modules, "linkwright.demo", fake)
    status, out, _ = run(capsys, "demo", "--out", tmp_path / "d")
    assert status == 0
    assert seen == [tmp_path / "d"]
    assert out.splitlines() == [str(tmp_path / "d" / "a.png"), str(tmp_path / "d" / "b.csv")]


# ---------------------------------------------------------------------------------------------
# Errors: status 2, one line on stderr, nothing on stdout
# ---------------------------------------------------------------------------------------------


def bad_docs(tmp_path: Path) -> dict[str, Path]:
    out = {}
    out["typo"] = tmp_path / "typo.toml"
    out["typo"].write_text(
        'format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\nA0 = [0, 0]\nB0 = [1, 0]\n'
        "crnak = 1\n"
    )
    out["broken"] = tmp_path / "broken.json"
    out["broken"].write_text('{"format": "linkwright/1",\n "mechanism": }')
    out["never"] = tmp_path / "never.toml"
    out["never"].write_text(
        'format = "linkwright/1"\n[mechanism]\nfamily = "fourbar"\nA0 = [0, 0]\nB0 = [10, 0]\n'
        "crank = 1\ncoupler = 2\nrocker = 3\n"
    )
    return out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["solve", "{typo}"], "mechanism: unknown field 'crnak' (did you mean 'crank'?)"),
        (["solve", "{broken}"], "invalid JSON: Expecting value (at line 2, column 15)"),
        (["solve", "{tmp}/missing.toml"], "cannot read: No such file or directory"),
        (["solve", "{tmp}/mech.yaml"], "unknown file type '.yaml'"),
        (["solve", str(EX / "crank-rocker.toml"), "--input", "0:10:0"], "STEP must not be zero"),
        (["solve", str(EX / "crank-rocker.toml"), "--jsn"], "No such option: --jsn"),
        (["solve"], "Missing argument"),
        (["frobnicate"], "No such command 'frobnicate'"),
        (["curve", str(EX / "crank-rocker.toml"), "--csv", "--json"], "cannot be used together"),
        (["curve", str(EX / "crank-rocker.toml"), "--points", "1"], "--points"),
        (["curve", "{never}"], "cannot be assembled at any input"),
        (["analyze", "{typo}"], "mechanism: unknown field 'crnak'"),
    ],
)
def test_errors(capsys, tmp_path, args, message):
    paths = {k: str(v) for k, v in bad_docs(tmp_path).items()}
    argv = [a.format(tmp=tmp_path, **paths) for a in args]
    status, out, err = run(capsys, *argv)
    assert status == 2
    assert out == ""
    assert err.startswith("error: ") and err.endswith("\n") and err.count("\n") == 1
    assert message in err
    assert "Traceback" not in err


def test_unexpected_failures_are_one_line_too(capsys, monkeypatch):
    import linkwright.mechanisms

    def boom(*args, **kwargs):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(linkwright.mechanisms, "solve", boom)
    monkeypatch.delenv("LINKWRIGHT_TRACEBACK", raising=False)
    status, _, err = run(capsys, "solve", EX / "crank-rocker.toml")
    assert status == 1
    assert err.startswith("error: internal error: RuntimeError: kaboom") and err.count("\n") == 1


def test_json_output_never_contains_nan(capsys):
    status, out, _ = run(
        capsys,
        "solve",
        EX / "rocker-input.toml",
        "--all",
        "--derivatives",
        "--json",
        "-i",
        "0:360:5",
    )
    assert status == 0
    assert "NaN" not in out and "Infinity" not in out
    json.loads(out)

"""Forces in documents and on the command line (issue 25): one-line errors naming the field,
and the JSON shape the issue fixes."""

from __future__ import annotations

import json

import pytest

from linkwright.cli.entry import main
from linkwright.io.documents import DocumentError, parse_document

BASE = {
    "family": "fourbar",
    "A0": [0.0, 0.0],
    "B0": [4.0, 0.0],
    "crank": 1.0,
    "coupler": 3.5,
    "rocker": 3.0,
}


def _doc(mass=None, loads=None):
    mech = dict(BASE)
    if mass is not None:
        mech["mass"] = mass
    out = {"format": "linkwright/1", "mechanism": mech}
    if loads is not None:
        out["loads"] = loads
    return out


@pytest.mark.parametrize(
    ("mass", "loads", "field", "words"),
    [
        ({"crank": -1.0}, None, "mechanism.mass.crank", "positive"),
        ({"crank": 0}, None, "mechanism.mass.crank", "positive"),
        (
            {"crank": {"mass": 1.0, "centre": {"u": 0.5}, "inertia": -0.1}},
            None,
            "mechanism.mass.crank.inertia",
            "negative",
        ),
        (
            {"crank": {"mass": 1.0, "centre": {"u": 50.0}, "inertia": 0.1}},
            None,
            "mechanism.mass.crank.centre",
            "link lengths",
        ),
        (
            {"crank": {"mass": 1.0, "centre": {"u": 0.5}}},
            None,
            "mechanism.mass.crank.inertia",
            "together",
        ),
        ({"crnak": 1.0}, None, "mechanism.mass", "did you mean 'crank'"),
        (
            None,
            {"forces": [{"point": "Q", "value": [0, 1]}]},
            "loads.forces[0].point",
            "unknown point 'Q'",
        ),
        (None, {"forces": [{"point": "A0", "value": [0, 1]}]}, "loads.forces[0].point", "frame"),
        (
            None,
            {"torques": [{"link": "rockr", "value": 1}]},
            "loads.torques[0].link",
            "did you mean 'rocker'",
        ),
        ({"crank": 1.0}, {"speed": 0}, "loads.speed", "inertia"),
        (None, {"sped": 3}, "loads", "did you mean 'speed'"),
    ],
)
def test_bad_masses_and_loads_are_one_line_errors(mass, loads, field, words):
    with pytest.raises(DocumentError) as info:
        parse_document(_doc(mass, loads))
    assert info.value.field == field
    assert words in info.value.problem
    assert "\n" not in str(info.value)


def test_static_analysis_at_speed_zero_is_allowed():
    doc = parse_document(_doc({"crank": 1.0}, {"speed": 0, "inertia": False}))
    assert doc.raw["loads"]["inertia"] is False


def _run(tmp_path, capsys, args, mass=None, loads=None):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(_doc(mass, loads)))
    status = main(["forces", str(path), *args])
    return status, capsys.readouterr()


def test_cli_json_shape_and_units(tmp_path, capsys):
    """`forces FILE --speed RPM --json`: samples with input_deg, input_torque and every
    reaction named by its joint; the driving torque agrees with the energy balance."""
    status, out = _run(
        tmp_path,
        capsys,
        ["--speed", "60", "--input", "0,90", "--json"],
        {
            "crank": 0.2,
            "coupler": 0.5,
            "rocker": {"mass": 0.4, "centre": {"u": 1.5, "v": 0.0}, "inertia": 0.3},
        },
    )
    assert status == 0, out.err
    data = json.loads(out.out)
    assert [s["input_deg"] for s in data["samples"]] == [0.0, 90.0]
    first = data["samples"][0]
    assert set(first["reactions"]) == {"A0", "A", "B", "B0"}
    assert abs(first["input_torque"] - first["energy_torque"]) <= 1e-9 * abs(first["input_torque"])
    assert "N·m" in data["units"]["torque"]


def test_cli_all_configurations_and_csv(tmp_path, capsys):
    status, out = _run(
        tmp_path, capsys, ["--speed", "60", "-i", "0", "--all", "--json"], {"crank": 1.0}
    )
    assert status == 0, out.err
    assemblies = [s["assembly"] for s in json.loads(out.out)["samples"]]
    assert sorted(assemblies) == [[-1], [1]]
    status, out = _run(tmp_path, capsys, ["--speed", "60", "-i", "0,10", "--csv"], {"crank": 1.0})
    assert status == 0
    header = out.out.splitlines()[0].split(",")
    assert header[:4] == ["input_deg", "input_torque", "A0.x", "A0.y"]


def test_cli_refuses_missing_speed_sphere_and_cost(tmp_path, capsys):
    status, out = _run(tmp_path, capsys, [], {"crank": 1.0})
    assert status == 2 and "speed" in out.err and "\n" not in out.err.strip()
    # The sphere has forces too (tests/test_forces_sphere.py): massless, they are all zero.
    status = main(["forces", "paper001-fg", "--speed", "10", "--input", "0", "--json"])
    assert status == 0
    assert json.loads(capsys.readouterr().out)["samples"][0]["input_torque"] == 0.0
    # Refused before any work: 900,000 inputs times 128 configurations of Jansen's leg.
    status = main(["forces", "jansen-leg", "--speed", "60", "-i", "0:359.9:0.0004", "--all"])
    err = capsys.readouterr().err
    assert status == 2 and ("too costly" in err or "at most" in err), err

"""The scene's overlays and analysis summary (issue 24, points 5 and 6), checked from outside:
the velocities and accelerations against finite differences of the engine's positions, the
centres against their construction by lines, the summary's numbers against ``linkwright analyze
--json`` and its dead centres against the closed form (crank and coupler in line); and the
overlays cost nothing unless asked, and are estimated with the scene before any work starts.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

from linkwright.cli import main
from linkwright.engine import cost
from linkwright.engine.evaluate import evaluate
from linkwright.geometry import plane
from linkwright.io import document_to_dict, load_example, parse_document
from linkwright.server import budget, create_app, overlays, scene

H = 1e-5


def _scene(name: str, **kw: Any) -> dict[str, Any]:
    """The scene of a bundled example as the page receives it (JSON: NaN as null)."""
    doc = document_to_dict(load_example(name))
    return json.loads(scene.to_json(scene.scene(doc, samples=kw.pop("samples", 48), **kw)))


def _own(sc: dict[str, Any]) -> dict[str, Any]:
    return next(m for m in sc["modes"] if m["own"])


def _array(rows: Any) -> np.ndarray:
    return np.array(rows, dtype=float)  # JSON's null reads as NaN


@pytest.mark.parametrize(
    "name",
    ["crank-rocker", "rocker-input", "slider-crank", "watt1-example", "paper000-fig6-crank-rocker"],
)
def test_the_scenes_vectors_are_the_rates_of_its_positions(name: str) -> None:
    sc = _scene(name, overlays=True, diagrams=False)
    mech = parse_document(sc["document"]).mechanism
    ov = sc["overlays"]
    own = _own(sc)
    assert len(ov["circuits"]) == len(own["circuits"])
    for circ, rates in zip(own["circuits"], ov["circuits"], strict=True):
        theta = np.radians(_array(circ["input"]))
        # The branches each sample ran on, read back off the scene's own positions.
        branches = {}
        for step in mech.plan.dyads:
            pos = {k: _array(v) for k, v in circ["positions"].items()}
            branches[step.name] = np.sign(step.branch_of(pos, mech.params()))

        def at(dt: float, branches: dict = branches, theta: np.ndarray = theta) -> Any:
            return evaluate(
                mech.plan, mech.params(), theta + dt, points=mech.points, branches=branches, order=0
            )

        up, down, here = at(H), at(-H), at(0.0)
        for joint, v in rates["velocity"].items():
            v, a = _array(v), _array(rates["acceleration"][joint])
            p = here.positions[joint]
            assert np.allclose(p, _array(circ["positions"][joint]), atol=1e-10, equal_nan=True)
            fd_v = (up.positions[joint] - down.positions[joint]) / (2 * H)
            fd_a = (up.positions[joint] - 2 * p + down.positions[joint]) / H**2
            # Away from limit positions (where the rates blow up) the differences are good to
            # h² of the third derivative: compare where both are modest.
            ok = np.isfinite(v).all(axis=-1) & (np.linalg.norm(a, axis=-1) < 50)
            ok &= np.isfinite(fd_v).all(axis=-1)
            assert ok.sum() >= len(ok) // 2, joint
            scale = max(1.0, float(np.abs(v[ok]).max()))
            assert np.abs(fd_v - v)[ok].max() <= 1e-6 * scale, joint
            assert np.abs(fd_a - a)[ok].max() <= 1e-3 * max(1.0, float(np.abs(a[ok]).max())), joint


def test_the_scenes_centres_are_where_the_lines_meet() -> None:
    sc = _scene("crank-rocker", overlays=True, at=40.0)
    ov = sc["overlays"]
    assert ov["labels"] == ["I12", "I13", "I14", "I23", "I24", "I34"]
    p = {k: _array(v) for k, v in sc["pose"].items()}

    def meet(a: np.ndarray, d: np.ndarray, b: np.ndarray, e: np.ndarray) -> np.ndarray:
        return a + plane.cross(b - a, e) / plane.cross(d, e) * d

    centres = _array(ov["pose"]["centres"])
    assert np.allclose(centres[0], p["A0"]) and np.allclose(centres[2], p["B0"])
    assert np.allclose(centres[1], meet(p["A0"], p["A"] - p["A0"], p["B0"], p["B"] - p["B0"]))
    assert np.allclose(centres[4], meet(p["A0"], p["B0"] - p["A0"], p["A"], p["B"] - p["A"]))
    # Along the circuit too: I13 on the crank's line and on the rocker's, sample for sample.
    circ = _own(sc)["circuits"][0]
    q = {k: _array(v) for k, v in circ["positions"].items()}
    i13 = _array(ov["circuits"][0]["centres"])[:, 1]
    size = 10.0
    for a, b in (("A0", "A"), ("B0", "B")):
        line = q[b] - q[a]
        off = plane.cross(line, i13 - q[a]) / plane.norm(line)
        assert np.abs(off).max() <= 1e-9 * max(size, float(np.abs(i13).max()))


def test_a_sliders_block_has_its_centre_at_infinity_in_the_scene() -> None:
    sc = _scene("offset-slider-crank", overlays=True, at=30.0)
    ov = sc["overlays"]
    k = next(i for i, (a, b) in enumerate(ov["pairs"]) if a == 0 and ov["bodies"][b]["block"])
    assert ov["pose"]["centres"][k] == [None, None]
    d = _array(ov["pose"]["directions"][k])
    guide = sc["guides"][0]["direction"]
    assert abs(float(np.dot(d, guide))) <= 1e-12


def test_on_the_sphere_the_centres_are_unit_axes() -> None:
    sc = _scene("paper000-fig6-crank-rocker", overlays=True, summary=True, at=20.0)
    ov = sc["overlays"]
    assert ov["space"] == "sphere" and ov["pose"]["directions"] is None
    axes = _array(ov["pose"]["centres"])
    assert np.allclose(np.linalg.norm(axes, axis=-1), 1.0)
    # The crank turns about its ground pivot A0.
    assert np.allclose(axes[0], _array(sc["pose"]["A0"]))
    assert sc["summary"]["note"] is None
    rows = {r["key"]: r for r in sc["summary"]["rows"]}
    assert rows["class"]["text"] == "crank-rocker" and rows["K_omega"]["value"] > 0


def _cli_report(tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(document_to_dict(load_example(name))))
    assert main(["analyze", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    return json.loads(out)


@pytest.mark.parametrize(
    "name",
    ["crank-rocker", "rocker-input", "slider-crank", "paper000-fig6-crank-rocker", "watt1-example"],
)
def test_the_summarys_numbers_are_those_of_analyze(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cli = _cli_report(tmp_path, name, capsys)
    summary = _scene(name, summary=True, diagrams=False)["summary"]
    assert summary["report"] == cli
    rows = {r["key"]: r for r in summary["rows"]}
    if "coefficients" in cli:
        assert rows["class"]["value"] == cli["class"]
        assert rows["time_ratio"]["value"] == cli["time_ratio"]
        for key, value in cli["coefficients"].items():
            assert rows[key]["value"] == value
            assert (rows[key]["text"] == "—") == (value is None)
        assert rows["limits"]["value"] == cli["limit_positions_deg"]
        tx = cli["transmission_angle_deg"]
        assert rows["transmission"]["value"] == [tx["min"], tx["max"]]
    else:
        assert [r["text"] for r in summary["rows"] if r["key"].startswith("K")] == ["—"] * 3
        assert rows["limits"]["value"] == [x["input_deg"] for x in cli["limit_positions"]]


def test_the_dead_centres_are_where_crank_and_coupler_fall_in_line() -> None:
    doc = load_example("crank-rocker")
    fb = doc.mechanism
    a, b, c = float(fb.crank), float(fb.coupler), float(fb.rocker)
    a0, b0 = np.asarray(fb.A0, float), np.asarray(fb.B0, float)
    expected = []
    for reach, turn in ((a + b, 0.0), (b - a, math.pi)):
        # B at `reach` from A0 and c from B0 (both intersections); A on the line A0B.
        d = float(np.linalg.norm(b0 - a0))
        x = (reach**2 - c**2 + d**2) / (2 * d)
        y = math.sqrt(reach**2 - x**2)
        base = math.atan2(*(b0 - a0)[::-1])
        for s in (1, -1):
            expected.append(math.degrees(base + s * math.atan2(y, x) + turn) % 360)
    rows = {r["key"]: r for r in overlays.summary_json(fb)["rows"]}
    got = [v % 360 for v in rows["dead_centres"]["value"]]
    assert len(got) == 2
    for g in got:
        assert min(abs(g - e) for e in expected) <= 1e-7


def test_families_without_a_quantity_show_a_dash_not_an_error() -> None:
    rows = {r["key"]: r["text"] for r in _scene("jansen-leg", summary=True)["summary"]["rows"]}
    assert rows["class"] == rows["time_ratio"] == rows["K_omega"] == rows["dead_centres"] == "—"
    assert rows["input_range"] == "turns fully"
    never = {
        "format": "linkwright/1",
        "mechanism": {
            "family": "fourbar",
            "A0": [0, 0],
            "B0": [10, 0],
            "crank": 1,
            "coupler": 2,
            "rocker": 3,
        },
    }
    sc = json.loads(scene.to_json(scene.scene(never, samples=32, overlays=True, summary=True)))
    assert sc["overlays"] is None
    assert "longer than the other three links together" in sc["summary"]["note"]
    # Grashof's sum is a number of the lengths alone; nothing of a motion is.
    assert {r["text"] for r in sc["summary"]["rows"] if r["key"] != "grashof"} == {"—"}


def test_overlays_cost_nothing_unless_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    monkeypatch.setattr(scene, "motion_json", lambda *a, **k: calls.append("motion"))
    monkeypatch.setattr(scene, "summary_json", lambda *a, **k: calls.append("summary"))
    sc = _scene("crank-rocker")
    assert "overlays" not in sc and "summary" not in sc and calls == []


def test_overlays_are_estimated_with_the_scene_before_any_work(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    seen: list[float] = []
    real = budget.check_scene

    def spy(estimate: cost.Estimate, numbers: float, samples: int) -> None:
        seen.append(estimate.work)
        real(estimate, numbers, samples)

    monkeypatch.setattr(budget, "check_scene", spy)
    _scene("crank-rocker", samples=360)
    _scene("crank-rocker", samples=360, overlays=True, summary=True)
    plain, more = seen
    assert more > plain
    # A budget the plain scene fits but the overlays do not: refused, and nothing computed.
    smaller = dataclasses.replace(cost.REQUEST.work, value=(plain + more) / 2)
    monkeypatch.setattr(cost, "REQUEST", dataclasses.replace(cost.REQUEST, work=smaller))
    calls = []
    monkeypatch.setattr(scene, "motion_json", lambda *a, **k: calls.append(1))
    _scene("crank-rocker", samples=360)
    with pytest.raises(budget.TooCostly, match="too costly"):
        _scene("crank-rocker", samples=360, overlays=True, summary=True)
    assert calls == []


def test_the_route_takes_the_flags() -> None:
    client = TestClient(create_app(Path(__import__("tempfile").mkdtemp())))
    doc = document_to_dict(load_example("crank-rocker"))
    plain = client.post("/api/scene", json={"document": doc, "samples": 24}).json()
    assert "overlays" not in plain
    both = client.post(
        "/api/scene", json={"document": doc, "samples": 24, "overlays": True, "summary": True}
    ).json()
    assert len(both["overlays"]["circuits"][0]["velocity"]["A"]) == 24
    assert both["summary"]["rows"][0] == {
        "key": "class",
        "label": "Class",
        "text": "crank-rocker",
        "value": "crank-rocker",
    }
    bad = client.post("/api/scene", json={"document": doc, "overlays": "maybe"})
    assert bad.status_code == 422 and "overlays" in bad.json()["error"]


def test_the_summary_kept_for_a_linkage_is_the_callers_own() -> None:
    fb = load_example("crank-rocker").mechanism
    first = overlays.summary_json(fb)
    spoilt = copy.deepcopy(first)
    first["rows"].clear()
    assert overlays.summary_json(fb) == spoilt

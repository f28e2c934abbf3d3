"""The workbench's forces panel, server side (issue 25 point 5): ``POST /api/forces``.

Its numbers are held to ``linkwright forces`` run on the same document at the same speed (the
CLI's own parse and solve, at the panel's inputs), and to an independent relation computed from
the scene alone: at constant speed without gravity the input power T·ω is the rate of the
kinetic energy, which is written from the positions the scene sends by finite differences (a
uniform bar's energy is m/6·(v_P² + v_P·v_Q + v_Q²), its end velocities differenced in θ), never
from the dynamics module. Also: a document without masses gets one plain line and no work, the
one-click masses are accepted for every bundled example, and a request over budget is refused
in one line before any work.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient

from linkwright.cli.entry import main
from linkwright.engine import cost
from linkwright.io import document_to_dict, list_examples, load_example
from linkwright.server import create_app, forces_panel
from linkwright.server.scene import scene, to_json


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    return TestClient(create_app(tmp_path_factory.mktemp("forces-panel")))


def _doc(name: str, mass: dict[str, Any] | None = None, loads: Any = None) -> dict[str, Any]:
    doc = document_to_dict(load_example(name))
    if mass is not None:
        doc["mechanism"]["mass"] = mass
    if loads is not None:
        doc["loads"] = loads
    return doc


def _post(client: TestClient, body: dict[str, Any]) -> dict[str, Any]:
    r = client.post("/api/forces", json=body)
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()
    return out


def _refused(client: TestClient, body: dict[str, Any], *words: str) -> str:
    r = client.post("/api/forces", json=body)
    assert r.status_code == 422, r.text
    error = r.json()["error"]
    assert "\n" not in error and "Traceback" not in error
    for w in words:
        assert w in error, error
    return str(error)


# --------------------------------------------------------------------------------------------
# The numbers: those of `linkwright forces`, and the energy's rate from the scene's positions
# --------------------------------------------------------------------------------------------

PLANE_MASSES = {
    "crank": 0.2,
    "coupler": {"mass": 0.5, "centre": {"u": 2.0, "v": 0.4}, "inertia": 0.3},
    "rocker": 0.4,
}
SPHERE_MASSES = {"crank": 0.2, "coupler": 0.5, "rocker": 0.4}


@pytest.mark.parametrize(
    ("name", "mass", "loads"),
    [
        ("crank-rocker", PLANE_MASSES, {"gravity": [0.0, -9.81], "speed": 20}),
        ("rocker-input", {"crank": 0.3, "coupler": 0.6, "rocker": 0.2}, None),
        (
            "paper000-fig6-crank-rocker",
            SPHERE_MASSES,
            {"gravity": [0.0, 0.0, -9.81], "radius": 0.1},
        ),
    ],
)
def test_the_panels_numbers_are_those_of_linkwright_forces(
    client: TestClient,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    name: str,
    mass: dict[str, Any],
    loads: Any,
) -> None:
    doc = _doc(name, mass, loads)
    rpm = 75.0
    out = _post(client, {"document": doc, "speed": rpm, "samples": 72, "at": 33.0})
    assert out["message"] is None and out["speed_rpm"] == rpm and out["masses"] is True
    assert out["circuits"], "the own mode runs"
    path = tmp_path / "doc.json"
    path.write_text(json.dumps(doc))

    def cli(spec: str, *more: str) -> list[dict[str, Any]]:
        argv = ["forces", str(path), "--speed", str(rpm), "--input", spec, "--json", *more]
        assert main(argv) == 0
        rows: list[dict[str, Any]] = json.loads(capsys.readouterr().out)["samples"]
        return rows

    # Some samples of every circuit. A rocking input's circuit runs up one assembly and back on
    # the other, so the CLI gives every configuration (--all) and the sample is the one it is
    # on: equal to 1e-9, where the other differs by order one.
    picked = [(c, i) for c, _ in enumerate(out["circuits"]) for i in range(0, 72, 7)]
    degrees = [out["circuits"][c]["input"][i] for c, i in picked]
    rows = cli(",".join(repr(d) for d in degrees), "--all")
    size = max(abs(r["input_torque"]) for r in rows if r["input_torque"] is not None)
    checked = 0
    for (c, i), deg in zip(picked, degrees, strict=True):
        body = out["circuits"][c]
        if body["torque"][i] is None:  # a singular sample (a limit position)
            continue
        here = [r for r in rows if r["input_deg"] == deg and r["input_torque"] is not None]
        row = min(here, key=lambda r: abs(r["input_torque"] - body["torque"][i]))
        # The answer rounds to 12 decimals; the rest is the same arithmetic.
        assert body["torque"][i] == pytest.approx(row["input_torque"], rel=1e-9, abs=1e-11)
        for joint, force in row["reactions"].items():
            assert body["reactions"][joint][i] == pytest.approx(force, rel=1e-9, abs=1e-9 * size)
        for joint, moment in row.get("moments", {}).items():
            assert body["moments"][joint][i] == pytest.approx(moment, rel=1e-9, abs=1e-9 * size)
        checked += 1
    assert checked >= 10
    # The scene's pose, on the document's own assembly as the CLI solves without --all.
    (at,) = cli("33.0")
    if at["input_torque"] is None:  # 33° is outside a rocker-input's arcs
        assert out["pose"] is None
    else:
        assert out["pose"]["torque"] == pytest.approx(at["input_torque"], rel=1e-9, abs=1e-11)
        for joint, force in at["reactions"].items():
            assert out["pose"]["reactions"][joint] == pytest.approx(force, rel=1e-9, abs=1e-9)
    # The two methods the dynamics module carries agree along the whole circuit too.
    for body in out["circuits"]:
        t, e = np.array(body["torque"], float), np.array(body["energy_torque"], float)
        ok = np.isfinite(t)
        assert np.allclose(t[ok], e[ok], rtol=1e-7, atol=1e-7 * size)


BARS = {"crank": 0.3, "coupler": 1.2, "rocker": 0.9}
"""Uniform bars: crank A0–A, coupler A–B (P is a point on it, not a joint), rocker B0–B."""


def _stencil(x: np.ndarray, h: float) -> np.ndarray:
    """d/dθ of a periodic series by the five-point central difference (error h⁴/30·x⁽⁵⁾)."""
    ahead = np.roll(x, -1, 0) - np.roll(x, 1, 0)
    twice = np.roll(x, -2, 0) - np.roll(x, 2, 0)
    return np.asarray((8 * ahead - twice) / (12 * h))


def _power_mismatch(client: TestClient, samples: int, rpm: float) -> float:
    """max |T·ω − dKE/dt| over max |T·ω| along a crank-rocker's turn, KE from the scene's
    positions alone."""
    doc = _doc("crank-rocker", BARS)
    sc = json.loads(to_json(scene(doc, samples=samples, diagrams=False)))
    own = next(m for m in sc["modes"] if m["own"])
    (circuit,) = own["circuits"]
    theta = np.array(circuit["input"], dtype=float)
    step = np.diff(theta)
    # One full turn, evenly spaced, no sample repeated: the stencil may wrap around.
    assert np.allclose(step, 360.0 / samples, atol=1e-9)
    assert theta[-1] - theta[0] + step[0] == pytest.approx(360.0)
    out = _post(client, {"document": doc, "speed": rpm, "samples": samples})
    (body,) = out["circuits"]
    # Sample i of the panel is sample i of the scene.
    assert np.array(body["input"], dtype=float) == pytest.approx(theta, abs=1e-9)
    h = math.radians(360.0 / samples)
    omega = rpm * 2 * math.pi / 60
    v = {k: _stencil(np.array(p, dtype=float), h) for k, p in circuit["positions"].items()}

    def bar(m: float, a: str, b: str) -> np.ndarray:
        va, vb = v[a], v[b]
        return np.asarray(m / 6 * ((va * va).sum(-1) + (va * vb).sum(-1) + (vb * vb).sum(-1)))

    # KE = ω²·K(θ) at constant speed; dKE/dt = ω·dKE/dθ.
    k = bar(BARS["crank"], "A0", "A") + bar(BARS["coupler"], "A", "B")
    k = k + bar(BARS["rocker"], "B0", "B")
    rate = omega**3 * _stencil(k, h)
    power = np.array(body["torque"], dtype=float) * omega
    assert np.isfinite(power).all()
    return float(np.max(np.abs(power - rate)) / np.max(np.abs(power)))


def test_input_power_is_the_rate_of_kinetic_energy_from_the_scenes_positions(
    client: TestClient,
) -> None:
    # The five-point stencil, applied for the velocities and again for the energy's rate, errs
    # by about h⁴ times the fifth derivatives: at 1° steps (h = 0.0175) about 1.2e-6 of the
    # largest power here. 1e-5 holds that with room; a wrong torque (a missing term, a sign)
    # misses by order one.
    coarse = _power_mismatch(client, 360, 90.0)
    assert coarse < 1e-5
    # The mismatch is the stencil's own: halving the step cuts it by about 2⁴ = 16.
    fine = _power_mismatch(client, 720, 90.0)
    assert fine < coarse / 8


# --------------------------------------------------------------------------------------------
# No masses, the one-click masses, what cannot be computed
# --------------------------------------------------------------------------------------------


def test_a_document_without_masses_gets_one_plain_line_and_no_work(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[int] = []
    monkeypatch.setattr(forces_panel, "forces_of", lambda *a, **k: calls.append(1))
    out = _post(client, {"document": _doc("crank-rocker"), "speed": 60})
    assert out["message"] == forces_panel.NO_MASS
    assert "\n" not in out["message"] and "[mechanism.mass]" in out["message"]
    assert out["masses"] is False and out["circuits"] == [] and calls == []
    assert out["suggest"] == {"crank": 1.0, "coupler": 1.0, "rocker": 1.0}
    assert out["links"] == ["crank", "coupler", "rocker"]


def test_loads_without_masses_are_computed_and_the_line_still_shows(client: TestClient) -> None:
    # A 10 N force straight down at the crank's end A alone: the motor holds F·crank·cos θ.
    loads = {"forces": [{"point": "A", "value": [0.0, -10.0]}]}
    out = _post(client, {"document": _doc("crank-rocker", loads=loads), "samples": 36})
    assert out["message"] == forces_panel.NO_MASS
    (body,) = out["circuits"]
    theta = np.radians(np.array(body["input"], dtype=float))
    crank = load_example("crank-rocker").raw["mechanism"]["crank"]
    assert np.array(body["torque"], dtype=float) == pytest.approx(
        10.0 * crank * np.cos(theta), abs=1e-8
    )


@pytest.mark.parametrize("name", list_examples())
def test_the_one_click_masses_work_for_every_example(client: TestClient, name: str) -> None:
    out = _post(client, {"document": _doc(name), "samples": 24})
    if not out["links"]:  # a plan forces do not know: said in one line, not refused
        assert out["message"].startswith("No forces") and "\n" not in out["message"]
        return
    assert out["suggest"], name
    massed = _post(client, {"document": _doc(name, out["suggest"]), "samples": 24, "at": 10.0})
    assert massed["masses"] is True and massed["message"] is None
    # Newton–Euler against the energy balance, every sample of every circuit.
    for body in massed["circuits"]:
        t = np.array(body["torque"], dtype=float)
        e = np.array(body["energy_torque"], dtype=float)
        ok = np.isfinite(t)
        assert ok.any(), name
        size = float(np.max(np.abs(t[ok])))
        assert np.allclose(t[ok], e[ok], rtol=1e-7, atol=1e-7 * size), name
        assert set(body["reactions"]) == set(massed["where"]), name
    left = set(out["links"]) - set(out["suggest"])
    if left:  # only the sphere's ternary links, and the note names them
        assert out["space"] == "sphere" and all(n in out["suggest_note"] for n in left)


def test_a_plan_forces_do_not_know_is_a_message_not_an_error(client: TestClient) -> None:
    # A slider on a guide carried by a moving joint: forces need a guide fixed to the frame.
    doc = {
        "format": "linkwright/1",
        "mechanism": {
            "family": "linkage",
            "joints": [
                {"name": "O", "type": "fixed", "at": [0.0, 0.0]},
                {"name": "A", "type": "crank", "pivot": "O", "length": 1.0},
                {"name": "Q", "type": "fixed", "at": [3.0, 0.0]},
                {"name": "S", "type": "rrp", "p1": "Q", "r": 2.5, "line_point": "A",
                 "line_angle": 90.0},
            ],
            "mass": {"A.length": 1.0},
        },
    }  # fmt: skip
    out = _post(client, {"document": doc})
    assert out["message"].startswith("No forces for this linkage yet: the slider S runs on a guide")
    assert out["circuits"] == []


def test_a_motor_at_a_moving_hinge_has_its_forces(client: TestClient) -> None:
    out = _post(client, {"document": _doc("hinge-driven-fourbar", {"B.r": 1.0, "B.a": 0.5})})
    assert out["message"] is None and out["circuits"]


# --------------------------------------------------------------------------------------------
# Bounds and bad input
# --------------------------------------------------------------------------------------------


def test_a_too_costly_request_is_refused_in_one_line_before_any_work(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    doc = _doc("crank-rocker", BARS)
    seen: list[float] = []
    real = forces_panel.estimate

    def spy(*args: Any) -> Any:
        found = real(*args)
        seen.append(found[1].work)
        return found

    monkeypatch.setattr(forces_panel, "estimate", spy)
    _post(client, {"document": doc, "samples": 360})
    (work,) = seen
    # A budget the scene of this linkage fits but its forces do not.
    plain = scene(doc, samples=360, diagrams=False)
    assert plain["modes"]
    smaller = dataclasses.replace(cost.REQUEST.work, value=work / 2)
    monkeypatch.setattr(cost, "REQUEST", dataclasses.replace(cost.REQUEST, work=smaller))
    calls: list[int] = []
    monkeypatch.setattr(forces_panel, "forces_of", lambda *a, **k: calls.append(1))
    error = _refused(client, {"document": doc, "samples": 360}, "too costly", "Newton–Euler")
    assert "lower samples to about" in error
    assert calls == []


def test_a_crank_geared_too_fast_is_refused_before_tracing(client: TestClient) -> None:
    doc = _doc("geared-fivebar", {"crank1": 1.0})
    doc["mechanism"]["ratio"] = 1000.0
    _refused(client, {"document": doc}, "too costly", "gear ratio 1000")


@pytest.mark.parametrize(
    ("speed", "words"),
    [
        (0, "speed: must be above 0"),
        (-60, "speed: must be above 0"),
        (2e6, "at most 1,000,000 rpm"),
        ("fast", "speed"),
        (True, "speed"),
    ],
)
def test_a_bad_speed_is_one_line_naming_it(client: TestClient, speed: Any, words: str) -> None:
    _refused(client, {"document": _doc("crank-rocker", BARS), "speed": speed}, words)


def test_bad_samples_and_documents_are_one_line(client: TestClient) -> None:
    doc = _doc("crank-rocker", BARS)
    _refused(client, {"document": doc, "samples": 4}, "samples")
    bad = _doc("crank-rocker", {"crank": -1.0})
    _refused(client, {"document": bad}, "mechanism.mass.crank", "positive")

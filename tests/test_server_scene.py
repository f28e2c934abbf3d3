"""The workbench's scene and drag (server/scene.py) and its core routes, checked against
independent derivations: link lengths constant along every traced circuit, limit positions where
the law of cosines puts them, dragged joints exactly where they were dropped."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkwright.io import document_to_dict, list_examples, load_example
from linkwright.server import create_app
from linkwright.server import scene as scenes
from linkwright.server.scene import DragError, drag, fields


def scene(document: dict, **kwargs) -> dict:
    """The scene as the page receives it: through JSON, where NaN must be null."""
    return json.loads(scenes.to_json(scenes.scene(document, **kwargs)))


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    return TestClient(create_app(tmp_path_factory.mktemp("data")))


def _doc(name: str) -> dict:
    return document_to_dict(load_example(name))


def _fourbar(A0, B0, crank, coupler, rocker, u=1.0, v=0.5, assembly=1) -> dict:
    return {
        "format": "linkwright/1",
        "mechanism": {
            "family": "fourbar",
            "A0": list(A0),
            "B0": list(B0),
            "crank": crank,
            "coupler": coupler,
            "rocker": rocker,
            "point": {"u": u, "v": v},
            "assembly": assembly,
        },
    }


def _distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    if a.shape[-1] == 3:  # arcs on the unit sphere, from the chord (exact near 0, unlike arccos)
        return 2 * np.arcsin(np.clip(np.linalg.norm(a - b, axis=-1) / 2, 0.0, 1.0))
    return np.linalg.norm(a - b, axis=-1)


@pytest.mark.parametrize("name", list_examples())
def test_every_example_is_a_rigid_motion(name: str) -> None:
    """Every body's joints keep their distances along every circuit of every mode, and the scene
    is strict JSON (no NaN)."""
    s = scene(_doc(name), samples=48, diagrams=False)
    json.dumps(s, allow_nan=False)  # strict JSON: every NaN went out as null
    assert s["modes"], s["message"]
    assert s["modes"][0]["own"]
    for mode in s["modes"]:
        for c in mode["circuits"]:
            pos = {k: np.array(v, dtype=float) for k, v in c["positions"].items()}
            n = len(c["input"])
            assert all(p.shape[0] == n for p in pos.values())
            for body in s["bodies"]:
                for a, b in itertools.combinations(body["joints"], 2):
                    d = _distance(pos[a], pos[b])
                    d = d[np.isfinite(d)]
                    assert np.ptp(d) <= 1e-9 * max(1.0, d.max()), (name, body, a, b)


def test_scene_carries_fields_pose_and_diagrams() -> None:
    s = scene(_doc("crank-rocker"), samples=90, at=30.0)
    mech = s["document"]["mechanism"]
    values = {f["path"]: f["value"] for f in s["fields"]}
    assert values["mechanism.crank"] == mech["crank"]
    assert values["mechanism.point.u"] == mech["point"]["u"]
    assert {f["path"] for f in s["fields"] if f["kind"] == "sign"} == {"mechanism.assembly"}
    # The pose at 30°: A on the crank circle at 30° from +x.
    a = np.array(s["pose"]["A"]) - np.array(mech["A0"])
    assert math.degrees(math.atan2(a[1], a[0])) == pytest.approx(30.0, abs=1e-9)
    assert np.hypot(*a) == pytest.approx(mech["crank"], abs=1e-12)
    assert set(s["diagrams"]) == {"angles", "velocity", "acceleration"}
    angles = s["diagrams"]["angles"]
    gamma = next(p for p in angles["panels"] if p["ideal"] == 90.0)
    # The transmission angle from the closed form at θ = x: cos γ = (b² + c² − |A B0|²)/(2bc).
    x = np.radians(np.array(angles["x"][0], dtype=float))
    b, c = mech["coupler"], mech["rocker"]
    A = np.c_[np.cos(x), np.sin(x)] * mech["crank"]
    AB0 = np.linalg.norm(A - np.array(mech["B0"]), axis=1)
    gamma_closed = np.degrees(np.arccos((b**2 + c**2 - AB0**2) / (2 * b * c)))
    shown = np.array(gamma["series"][0]["values"][0], dtype=float)
    assert np.allclose(
        np.minimum(shown, 180 - shown), np.minimum(gamma_closed, 180 - gamma_closed), atol=1e-6
    )


def test_rocker_limits_where_the_law_of_cosines_puts_them() -> None:
    s = scene(_doc("rocker-input"), samples=64, diagrams=False)
    mech = s["document"]["mechanism"]
    r, b, c = mech["crank"], mech["coupler"], mech["rocker"]
    d = np.hypot(*np.subtract(mech["B0"], mech["A0"]))
    # |A − B0| = b ± c at the limits: cos θ = (r² + d² − (b ± c)²) / (2 r d).
    closed = sorted(
        sign * math.degrees(math.acos((r * r + d * d - (b + k * c) ** 2) / (2 * r * d)))
        for k in (1, -1)
        for sign in (1, -1)
    )
    own = [lim for lim in s["limits"] if lim["mode"] == 0]
    assert sorted(round(lim["input"], 9) for lim in own) == pytest.approx(closed, abs=1e-9)
    for lim in own:
        c0 = s["modes"][0]["circuits"][lim["circuit"]]
        assert lim["index"] in c0["limits"]
        A = np.array(c0["positions"]["A"][lim["index"]])
        assert abs(np.hypot(*(A - mech["B0"])) - b) == pytest.approx(c, abs=1e-9)
        assert "Limit position" in lim["text"] and "fall in line" in lim["text"]
    assert not s["full"] and s["range"].startswith("θ in")


def test_a_linkage_that_cannot_assemble_is_a_scene_that_says_so() -> None:
    s = scene(_fourbar([0, 0], [10, 0], 1, 2, 3), samples=16)
    assert s["modes"] == [] and s["pose"] is None and s["diagrams"] is None
    assert "cannot be assembled" in s["message"]
    assert sorted(s["never"]) == ["assembly +1", "assembly −1"]


def test_sphere_scene_has_a_map() -> None:
    s = scene(_doc("paper000-fig6-crank-rocker"), samples=36, diagrams=False)
    centre = np.array(s["map_center"])
    c = s["modes"][0]["circuits"][0]
    p = np.array(c["positions"]["P"], dtype=float)
    m = np.array(c["map"]["P"], dtype=float)
    # Lambert azimuthal equal-area: distance from the map's centre = 2 sin(δ/2), δ the arc.
    delta = np.arccos(np.clip(p @ centre, -1, 1))
    assert np.allclose(np.hypot(m[:, 0], m[:, 1]), 2 * np.sin(delta / 2), atol=1e-9)
    assert np.allclose(np.linalg.norm(p, axis=1), 1.0, atol=1e-12)
    assert "A0" not in s["handles"]  # paper 000's A0 is (1, 0, 0) by definition


def _pose(document: dict, at: float) -> dict[str, np.ndarray]:
    s = scene(document, samples=16, at=at, diagrams=False)
    assert s["pose"] is not None
    return {k: np.array(v) for k, v in s["pose"].items()}


def _changed(before: dict, after: dict) -> set[str]:
    return {k for k in after["mechanism"] if after["mechanism"][k] != before["mechanism"][k]}


crank_rockers = st.tuples(
    st.floats(0.5, 1.5), st.floats(4.0, 6.0), st.floats(3.0, 4.0), st.floats(0.0, 359.0)
).filter(lambda t: t[1] - t[2] < 4.0 - t[0] and t[1] + t[2] > 4.0 + t[0])


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(crank_rockers, st.floats(-0.2, 0.2), st.floats(-0.2, 0.2))
def test_drag_puts_the_joint_under_the_pointer(dims, dx, dy) -> None:
    crank, coupler, rocker, at = dims
    doc = _fourbar([0, 0], [4, 0], crank, coupler, rocker)
    pose = _pose(doc, at)

    def assembles(a: np.ndarray, b0: np.ndarray) -> bool:
        # The dyad A–B–B0 closes with room to spare (the drag clamps a target that does not).
        d = float(np.linalg.norm(b0 - a))
        return abs(coupler - rocker) + 1e-6 < d < coupler + rocker - 1e-6

    for joint, allowed in (("P", {"point"}), ("B", {"coupler", "rocker"}), ("B0", {"B0"})):
        target = pose[joint] + [dx, dy]
        if joint == "B0" and not assembles(pose["A"], target):
            continue
        out = drag(doc, joint, target.tolist(), at)
        assert _changed(doc, out["document"]) <= allowed
        assert out["at"] == pytest.approx(at)
        after = _pose(out["document"], out["at"])
        assert np.linalg.norm(after[joint] - target) <= 1e-8
    # A crank's end: its length and the input angle follow the pointer (a second method: polar
    # coordinates of the target about A0).
    target = pose["A"] + [dx, dy]
    if not assembles(target, pose["B0"]):
        return
    out = drag(doc, "A", target.tolist(), at)
    assert out["document"]["mechanism"]["crank"] == pytest.approx(np.hypot(*target), abs=1e-9)
    expected = math.degrees(math.atan2(target[1], target[0]))
    assert (out["at"] - expected + 180) % 360 - 180 == pytest.approx(0.0, abs=1e-7)


def test_drag_across_the_fold_changes_assembly() -> None:
    doc = _fourbar([0, 0], [4, 0], 1, 5, 3.5, assembly=1)
    pose = _pose(doc, 90.0)
    # Mirror B in the line A–B0: only the other assembly puts B there with these pivots.
    a, b0, b = pose["A"], pose["B0"], pose["B"]
    t = (b0 - a) / np.linalg.norm(b0 - a)
    mirrored = a + 2 * ((b - a) @ t) * t - (b - a)
    out = drag(doc, "B", mirrored.tolist(), 90.0)
    assert out["document"]["mechanism"]["assembly"] == -1
    assert np.linalg.norm(_pose(out["document"], 90.0)["B"] - mirrored) < 1e-8


@pytest.mark.parametrize(
    "name",
    [
        "offset-slider-crank",
        "geared-fivebar",
        "elliptic-trammel",
        "watt2-example",
        "jansen-leg",
        "paper000-fig6-crank-rocker",
    ],
)
def test_drag_every_family(name: str) -> None:
    doc = _doc(name)
    s = scene(doc, samples=16, diagrams=False)
    at = s["at"]
    pose = _pose(doc, at)
    for joint in s["handles"]:
        p = pose[joint]
        if p.size == 3:
            axis = np.cross(p, [0.3, -0.5, 0.8])
            axis /= np.linalg.norm(axis)
            target = math.cos(0.02) * p + math.sin(0.02) * np.cross(axis, p)
        else:
            target = p + [0.03, -0.02]
        out = drag(doc, joint, target.tolist(), at)
        after = _pose(out["document"], out["at"])[joint]
        miss = np.linalg.norm(after - target)
        if out["exact"]:
            assert miss <= 1e-7, (name, joint)
        else:  # out of reach: it moved towards the pointer
            assert miss < np.linalg.norm(p - target), (name, joint)


def test_drag_refusals() -> None:
    doc = _doc("crank-rocker")
    with pytest.raises(DragError, match="no joint named 'Q'"):
        drag(doc, "Q", [0, 0], 0.0)
    with pytest.raises(DragError, match="2 finite numbers"):
        drag(doc, "P", [0, float("nan")], 0.0)
    with pytest.raises(DragError, match="not assembled"):
        drag(_doc("rocker-input"), "P", [0, 0], 0.0)


def test_fields_name_every_number_of_a_composed_linkage() -> None:
    doc = _doc("jansen-leg")
    paths = {f["path"] for f in fields(doc)}
    joints = doc["mechanism"]["joints"]
    for i, j in enumerate(joints):
        for key, value in j.items():
            if isinstance(value, int | float) and not isinstance(value, bool) and key != "assembly":
                assert f"mechanism.joints.{i}.{key}" in paths


# --------------------------------------------------------------------------------------------
# Routes
# --------------------------------------------------------------------------------------------


def test_routes_families_examples_and_scene(client: TestClient) -> None:
    fams = client.get("/api/families").json()
    assert {f["family"] for f in fams} >= {"fourbar", "spherical-fourbar", "linkage"}
    names = {e["name"] for e in client.get("/api/examples").json()}
    assert names == set(list_examples())
    for f in fams:
        doc = client.get(f"/api/families/{f['family']}/default").json()
        assert doc["mechanism"]["family"] == f["family"]
    doc = client.get("/api/examples/crank-rocker").json()
    r = client.post("/api/scene", json={"document": doc, "samples": 120})
    assert r.status_code == 200
    assert len(r.json()["modes"][0]["circuits"][0]["input"]) == 120


@pytest.mark.parametrize(
    ("body", "status", "message"),
    [
        (
            {"document": {"format": "linkwright/1", "mechanism": {"family": "fourbar"}}},
            422,
            "mechanism",
        ),
        ({"document": _fourbar([0, 0], [4, 0], -1, 5, 3.5)}, 422, "mechanism.crank"),
        ({"document": _fourbar([0, 0], [4, 0], 1, 5, 3.5), "samples": 5}, 422, "samples"),
        ({"document": _fourbar([0, 0], [4, 0], 1, 5, 3.5), "samples": 10**6}, 422, "samples"),
        ({"document": "not a document"}, 422, "document"),
        ({}, 422, "document"),
    ],
)
def test_scene_refusals(client: TestClient, body: dict, status: int, message: str) -> None:
    r = client.post("/api/scene", json=body)
    assert r.status_code == status
    assert message in r.json()["error"]
    assert "Traceback" not in r.text


def test_route_errors(client: TestClient) -> None:
    assert client.get("/api/examples/nope").status_code == 404
    assert "nope" in client.get("/api/examples/nope").json()["error"]
    assert client.get("/api/families/nope/default").status_code == 404
    r = client.post(
        "/api/drag", json={"document": _doc("crank-rocker"), "joint": "Q", "to": [0, 0]}
    )
    assert r.status_code == 422 and "Q" in r.json()["error"]
    r = client.post("/api/scene", content=b"{" * 10, headers={"content-type": "application/json"})
    assert r.status_code == 422
    big = b" " * 2_100_000
    r = client.post("/api/scene", content=big, headers={"content-type": "application/json"})
    assert r.status_code == 413 and "bytes" in r.json()["error"]


def test_page_is_served(client: TestClient) -> None:
    r = client.get("/")
    assert r.status_code == 200 and "<html" in r.text.lower()
    assert client.get("/static/app.js").status_code == 200

"""The workbench's atlas match on the sphere (server/tools_match.py): a curve of [x, y, z] rows
is matched against the spherical four-bar atlas, refined, and each candidate comes back as a
spherical four-bar placed where the curve was drawn, its curve as unit vectors.

Numbers are checked against independent derivations: the candidate's document is solved here
through linkwright's ordinary API (parse_document, solve) and its traced curve compared with the
drawn points by great-circle distance; the document's links are checked by the arcs between its
solved joints; the curve's size is computed here from its definition.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkwright.engine import cost
from linkwright.io import parse_document
from linkwright.mechanisms import SphericalFourBar, circuit, solve
from linkwright.server import create_app

ATLAS_COUNT = 1_500  # the browser tests' size: builds in a second or two, refinement does the rest
DENSE = 8192

# Spherical four-bars whose cranks turn fully, well inside the atlas's distribution (arcs in
# degrees: frame, crank, coupler, rocker, point arc, point angle; then the assembly sign).
KNOWN = {
    "paper000-fig6": ([40, 20, 45, 35, 50, 130], 1.0),
    "wide": ([70, 30, 60, 55, 35, -60], -1.0),
}


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    app = create_app(tmp_path_factory.mktemp("workbench-match-sphere"))
    app.state.atlas_count = ATLAS_COUNT
    return TestClient(app)


def _no_nan(text: str) -> dict:
    def refuse(name: str) -> None:
        raise AssertionError(f"the answer carries {name}")

    return json.loads(text, parse_constant=refuse)


def post(client: TestClient, body: dict) -> dict:
    r = client.post("/api/match", json=body)
    assert r.status_code == 200, r.text
    return _no_nan(r.text)


def error(client: TestClient, body: object, path: str = "/api/match") -> str:
    # Sent as text, so that a NaN can be sent too.
    r = client.post(path, content=json.dumps(body), headers={"Content-Type": "application/json"})
    assert r.status_code == 422, r.text
    message = r.json()["error"]
    assert isinstance(message, str) and "\n" not in message and "Traceback" not in message
    return message


def rotation(q: np.ndarray) -> np.ndarray:
    """The rotation of the unit quaternion along ``q`` (w, x, y, z)."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def traced(name: str, n: int) -> np.ndarray:
    dims, assembly = KNOWN[name]
    known = SphericalFourBar(*np.radians(dims), assembly=assembly)
    motion = circuit(known, n, order=0)
    assert motion.valid.all()
    return np.asarray(motion.positions["P"])


def angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Great-circle distance between unit vectors (2·asin of half the chord: accurate when
    small, where acos is not)."""
    chord = np.linalg.norm(a - b, axis=-1)
    return 2.0 * np.arcsin(np.clip(chord / 2.0, 0.0, 1.0))


def size_of(points: np.ndarray) -> float:
    """RMS chord from the points' mean direction: the size the route's ``relative`` uses."""
    c = points.mean(axis=0)
    c = c / np.linalg.norm(c)
    return float(np.sqrt(np.mean(np.sum((points - c) ** 2, axis=1))))


def document_curve(document: dict) -> tuple[np.ndarray, float]:
    """The document's traced point at DENSE inputs over a turn, solved here, and the largest
    great-circle step between neighbouring samples. The document is checked on the way: a
    spherical four-bar (two ground axes, a crank, a dyad, a coupler point) whose solved joints
    keep its links' arcs."""
    mech = document["mechanism"]
    assert mech["space"] == "sphere"
    kinds = {j["name"]: j["type"] for j in mech["joints"]}
    assert kinds == {"A0": "fixed", "B0": "fixed", "A": "crank", "B": "rrr", "P": "rigid"}
    parsed = parse_document(document).mechanism
    theta = np.linspace(0.0, 2.0 * np.pi, DENSE, endpoint=False)
    motion = solve(parsed, theta, order=0)
    assert motion.valid.all(), "the candidate's crank does not turn fully"
    pos = {k: np.asarray(v) for k, v in motion.positions.items()}
    joints = {j["name"]: j for j in mech["joints"]}
    a0 = np.array(joints["A0"]["at"]) / np.linalg.norm(joints["A0"]["at"])
    b0 = np.array(joints["B0"]["at"]) / np.linalg.norm(joints["B0"]["at"])
    arcs = [
        (a0, pos["A"], joints["A"]["arc"]),
        (pos["A"], pos["B"], joints["B"]["r1"]),
        (b0, pos["B"], joints["B"]["r2"]),
        (pos["A"], pos["P"], joints["P"]["arc"]),
    ]
    for a, b, degrees in arcs:
        assert np.max(np.abs(angle(a, b) - math.radians(degrees))) < 1e-9
    P = pos["P"]
    step = float(np.max(angle(P, np.roll(P, -1, axis=0))))
    return P, step


def rms_gap(points: np.ndarray, curve: np.ndarray) -> float:
    """RMS great-circle distance from each point to its nearest sample of ``curve``."""
    nearest = [float(np.min(angle(curve, q))) for q in points]
    return float(np.sqrt(np.mean(np.square(nearest))))


def check_recovered(res: dict, points: np.ndarray, tolerance: float) -> None:
    """The best candidate's own curve, solved from its document, runs within ``tolerance`` of
    the curve's size (RMS great-circle distance) of the points; the curve sent for drawing is
    unit vectors on that same curve."""
    size = size_of(points)
    assert res["size"] == pytest.approx(size, rel=1e-12)
    assert res["atlas"] == {"count": ATLAS_COUNT, "family": "spherical-fourbar"}
    best = res["candidates"][0]
    curve, step = document_curve(best["document"])
    # A point's nearest sample is at most half a step farther than the curve itself.
    assert rms_gap(points, curve) <= tolerance * size + step / 2
    assert best["relative"] == pytest.approx(best["distance"] / size, rel=1e-9)
    assert best["relative"] <= tolerance
    sent = np.array([p for p in best["curve"] if p is not None], dtype=float)
    assert len(sent) == len(best["curve"]) and best["curve"][0] == best["curve"][-1]
    assert np.max(np.abs(np.linalg.norm(sent, axis=1) - 1.0)) < 1e-12
    assert max(float(np.min(angle(curve, q))) for q in sent) <= step / 2 + 1e-9


def test_match_recovers_a_spherical_fourbar(client: TestClient) -> None:
    """Paper 000's Fig. 6 crank-rocker's coupler curve (48 points), turned: matched against the
    spherical atlas (built on first use, in the data directory) and refined to within 1 % of
    its size; the ranks run 1, 2, …"""
    assert client.get("/api/match/status?space=sphere").json()["state"] in ("missing", "ready")
    R = rotation(np.array([0.3, -0.5, 0.7, 0.2]))
    points = traced("paper000-fig6", 48) @ R.T
    res = post(client, {"points": points.tolist(), "top": 3, "refine": True})
    assert 1 <= len(res["candidates"]) <= 3
    assert [c["rank"] for c in res["candidates"]] == list(range(1, len(res["candidates"]) + 1))
    assert res["fitted"] == 48
    check_recovered(res, points, 0.01)
    status = client.get("/api/match/status?space=sphere").json()
    assert status == {"state": "ready", "progress": 1.0, "count": ATLAS_COUNT, "error": None}
    root = client.app.state.data_dir / "atlas"
    assert (root / f"spherical-fourbar-{ATLAS_COUNT}-seed0-v1").is_dir()
    # The planar atlas is its own: matching on the sphere did not build it.
    assert not (root / f"fourbar-{ATLAS_COUNT}-seed0-v1").exists()


def test_match_an_open_piece_of_a_spherical_curve(client: TestClient) -> None:
    """Half of paper 000's Fig. 6 coupler curve, turned and sent as an open curve: every entry
    is screened for the arc that matches it, and the refined best runs within 1 % of the
    piece's size (its distance is to the whole placed curve, so the piece need not close)."""
    R = rotation(np.array([-0.4, 0.2, 0.6, 0.5]))
    points = traced("paper000-fig6", 96)[:48] @ R.T
    res = post(client, {"points": points.tolist(), "top": 2, "refine": True, "open": True})
    check_recovered(res, points, 0.01)
    # Taken as closed, the same half-curve is a different shape, matched far less well.
    closed = post(client, {"points": points.tolist(), "top": 2, "refine": True})
    assert closed["candidates"][0]["relative"] > 2 * res["candidates"][0]["relative"]


_QUATERNION = st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 4).filter(
    lambda q: math.fsum(c * c for c in q) > 0.05
)


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(q=_QUATERNION, name=st.sampled_from(sorted(KNOWN)), n=st.integers(24, 90))
def test_match_is_found_however_the_curve_is_turned(
    client: TestClient, q: tuple[float, ...], name: str, n: int
) -> None:
    """A known spherical four-bar's coupler curve, turned by any rotation of the sphere and
    drawn with any number of points: the refined best candidate runs within 1 % of its size."""
    points = traced(name, n) @ rotation(np.array(q)).T
    res = post(client, {"points": points.tolist(), "top": 2, "refine": True})
    check_recovered(res, points, 0.01)


def test_only_the_direction_of_a_row_counts(client: TestClient) -> None:
    """Rows are directions: the same curve with each row scaled by its own positive factor
    (tiny to huge) is the same match."""
    points = traced("wide", 40)
    factors = np.geomspace(1e-200, 1e200, len(points))[np.random.default_rng().permutation(40)]
    unit = post(client, {"points": points.tolist(), "top": 3, "refine": False})
    scaled = post(client, {"points": (points * factors[:, None]).tolist(), "top": 3,
                           "refine": False})  # fmt: skip
    assert scaled["size"] == pytest.approx(unit["size"], rel=1e-12)
    assert [c["atlas_id"] for c in scaled["candidates"]] == [
        c["atlas_id"] for c in unit["candidates"]
    ]
    for a, b in zip(scaled["candidates"], unit["candidates"], strict=True):
        assert a["distance"] == pytest.approx(b["distance"], rel=1e-9, abs=1e-12)


def _ring(n: int, tilt: float = 0.6) -> list[list[float]]:
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack((np.full(n, 1.0), tilt * np.cos(t), 0.5 * tilt * np.sin(t))).tolist()


@pytest.mark.parametrize(
    ("points", "needle"),
    [
        (_ring(9)[:3] + [[0, 0, 0]] + _ring(9)[3:],
         "points: row 3 has 3 numbers, all zero: a point on the sphere is a direction"),
        (_ring(9)[:5] + [[1, float("nan"), 0]] + _ring(9)[5:], "points: row 5 is not finite"),
        (_ring(9)[:5] + [[1, float("inf"), 0]] + _ring(9)[5:], "points: row 5 is not finite"),
        (_ring(9)[:4] + [[1, 0]] + _ring(9)[4:],
         "points: row 4 has 2 numbers but row 0 has 3; every point is [x, y] (in the plane) or "
         "every one [x, y, z] (on the sphere)"),
        ([[1, 0]] * 4 + _ring(5), "points: row 4 has 3 numbers but row 0 has 2"),
        ([[1, 0, 0, 0]] * 9, "points: row 0 has 4 numbers; each point is [x, y], or [x, y, z]"),
        ([[0, 0, 1], [0, 0, -1]] * 5, "points: the curve has no mean direction"),
        ([[0, 0, 2]] * 4 + [[0, 0, 0.5]] * 5, "points: all the same point"),
        (_ring(5), "points: a curve needs at least 8 points, got 5"),
        ([[True, False, 1]] + _ring(9), "points.0.0"),
    ],
)  # fmt: skip
def test_bad_rows_are_refused_in_one_line(client: TestClient, points: list, needle: str) -> None:
    assert needle in error(client, {"points": points})


def test_status_and_prepare_of_the_sphere_atlas(tmp_path: Path) -> None:
    """``?space=sphere`` names the spherical atlas: prepare builds it in the background (and
    only it), status follows it, and a later app finds it finished in the data directory."""
    app = create_app(tmp_path)
    app.state.atlas_count = 500
    client = TestClient(app)
    missing = {"state": "missing", "progress": 0.0, "count": None, "error": None}
    assert client.get("/api/match/status?space=sphere").json() == missing
    first = client.post("/api/match/prepare?space=sphere").json()
    assert first["state"] in ("building", "ready")
    deadline = time.monotonic() + 120
    while client.get("/api/match/status?space=sphere").json()["state"] != "ready":
        assert time.monotonic() < deadline
        time.sleep(0.1)
    ready = {"state": "ready", "progress": 1.0, "count": 500, "error": None}
    assert client.get("/api/match/status?space=sphere").json() == ready
    assert client.get("/api/match/status").json() == missing  # the plane's: not built
    assert client.get("/api/match/status?space=plane").json() == missing
    assert (tmp_path / "atlas" / "spherical-fourbar-500-seed0-v1" / "atlas.json").exists()
    again = TestClient(create_app(tmp_path))  # its own default count: it finds the one there
    assert again.get("/api/match/status?space=sphere").json() == ready
    for path in ("/api/match/status?space=moon", "/api/match/prepare?space="):
        method = client.get if "status" in path else client.post
        r = method(path)
        assert r.status_code == 422
        assert r.json()["error"].startswith("space: must be one of plane, sphere, got")


def test_a_costly_match_is_refused_before_any_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The estimate is checked before the atlas is built or searched: a work budget below a
    refined match's refuses it in one line and leaves the atlas unbuilt."""
    app = create_app(tmp_path)
    app.state.atlas_count = 500
    client = TestClient(app)
    smaller = dataclasses.replace(cost.REQUEST.work, value=1.0)
    monkeypatch.setattr(cost, "REQUEST", dataclasses.replace(cost.REQUEST, work=smaller))
    message = error(client, {"points": _ring(40), "refine": True})
    assert "too costly" in message
    assert client.get("/api/match/status?space=sphere").json()["state"] == "missing"
    assert not (tmp_path / "atlas").exists() or not any((tmp_path / "atlas").iterdir())


def test_most_points_and_most_candidates_on_the_sphere(client: TestClient) -> None:
    """The limits hold on the sphere too: 20,000 directions refined (500 fitted) answer, and
    twenty candidates unrefined."""
    points = traced("paper000-fig6", 20_000)
    res = post(client, {"points": points.tolist(), "top": 1, "refine": True})
    assert res["fitted"] == 500 and res["candidates"][0]["relative"] < 0.01
    res = post(client, {"points": _ring(48), "top": 20, "refine": False})
    assert [c["rank"] for c in res["candidates"]] == list(range(1, 21))
    errors = [c["error"] for c in res["candidates"]]
    assert errors == sorted(errors)

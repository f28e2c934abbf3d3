"""The workbench's cost limits (issue 20, item 2): a request is held to the cost estimate before
its work starts (422 naming what to lower), and to a time budget while it runs (503).

The hostile requests of the issue run in a process of their own under an address-space limit
and a timeout, through the real application; the rest run in this process. The ``test_limit_*``
tests cover the rows this adds to ``GET /api/limits``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import resource
import subprocess
import sys

import pytest
from fastapi.testclient import TestClient

from linkwright.engine import cost
from linkwright.io import document_to_dict, load_example, parse_document
from linkwright.mechanisms import input_range
from linkwright.server import budget, create_app, limits, tools

CAP_BYTES = 2_500_000_000
TIMEOUT_S = 240

DRIVER = """
import json, resource, sys, tempfile, warnings
warnings.simplefilter("ignore")
from fastapi.testclient import TestClient
from linkwright.server import create_app
path, body = sys.argv[1], json.loads(sys.argv[2])
answer = TestClient(create_app(tempfile.mkdtemp())).post(path, json=body)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
# The process's own high-water mark: ru_maxrss survives the fork and exec from the test's
# worker, so it starts at the worker's size, however large.
try:
    with open("/proc/self/status") as status_file:
        for line in status_file:
            if line.startswith("VmHWM:"):
                peak = int(line.split()[1]) * 1024
except OSError:
    pass
print(json.dumps({"status": answer.status_code, "body": answer.text[:2000], "peak": peak}))
"""


def post_capped(path: str, body: dict) -> dict:
    """A request sent to a fresh application in a process of its own, limited to
    :data:`CAP_BYTES` of address space: its status, the start of its body, its peak memory."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (CAP_BYTES, CAP_BYTES))

    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, "-c", DRIVER, path, json.dumps(body)],
        capture_output=True,
        text=True,
        env=env,
        preexec_fn=limit,
        timeout=TIMEOUT_S,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def geared(ratio: float) -> dict:
    doc = document_to_dict(load_example("geared-fivebar"))
    doc["mechanism"]["ratio"] = ratio
    return doc


@pytest.fixture(scope="module")
def client() -> TestClient:
    import tempfile

    return TestClient(create_app(tempfile.mkdtemp()))


# --------------------------------------------------------------------------------------------
# The requests, refused before their work
# --------------------------------------------------------------------------------------------


def test_a_scene_geared_at_1000_is_refused_at_once() -> None:
    # 497 bytes that once took 114 s.
    answer = post_capped("/api/scene", {"document": geared(1000.0), "samples": 360})
    assert answer["status"] == 422, answer
    error = json.loads(answer["body"])["error"]
    assert "1,000 times per input turn" in error and "lower the ratio to 64" in error
    assert answer["peak"] < 400 * 2**20


def test_a_study_of_a_crank_geared_at_64_is_refused_at_once() -> None:
    # 561 bytes that once ran 85-96 s, answered 548 MB and peaked at 4 GB.
    body = {"document": geared(64.0), "pivot": "A0", "count": 50, "samples": 4096}
    answer = post_capped("/api/study", body)
    assert answer["status"] == 422, answer
    error = json.loads(answer["body"])["error"]
    assert error.startswith("too costly: tracing 51 steps × 42 circuits of 4,096 samples")
    assert "lower count to" in error and "\n" not in error
    assert answer["peak"] < 400 * 2**20
    # The count it proposes does fit.
    fewer = int(error.split("lower count to ")[1].split()[0])
    mech = parse_document(geared(64.0)).mechanism
    assert budget.study_estimate(mech, input_range(mech), fewer + 1, 4096).fits(cost.REQUEST)


def test_an_export_of_too_many_circuits_is_refused(client) -> None:
    body = {"document": geared(1000.0), "samples": 360}
    answer = client.post("/api/export/png", json=body)
    assert answer.status_code == 422 and "lower the ratio" in answer.json()["error"]


# --------------------------------------------------------------------------------------------
# The time budget
# --------------------------------------------------------------------------------------------


@pytest.fixture
def no_time(monkeypatch) -> None:
    """A request's time budget of zero: the first check between steps is already late."""
    budget = cost.Budget("request_seconds", 0.0, "seconds", "test")
    monkeypatch.setattr(cost, "REQUEST_SECONDS", budget)


def test_a_study_past_its_time_budget_answers_503(client, no_time) -> None:
    doc = document_to_dict(load_example("crank-rocker"))
    answer = client.post(
        "/api/study", json={"document": doc, "pivot": "B0", "count": 3, "samples": 64}
    )
    assert answer.status_code == 503, answer.text
    error = answer.json()["error"]
    assert error == "took longer than the 0 s budget of a request; lower count or samples"


def test_a_rocking_scene_past_its_time_budget_answers_503(client, no_time) -> None:
    doc = document_to_dict(load_example("rocker-input"))  # two circuits, checked between
    answer = client.post("/api/scene", json={"document": doc, "samples": 64})
    assert answer.status_code == 503 and "lower samples" in answer.json()["error"]


def test_a_drag_past_its_time_budget_answers_503(client, no_time) -> None:
    doc = document_to_dict(load_example("crank-rocker"))
    answer = client.post("/api/drag", json={"document": doc, "joint": "P", "to": [1, 3], "at": 30})
    assert answer.status_code == 503 and "lower the number of joints" in answer.json()["error"]


# --------------------------------------------------------------------------------------------
# Inside the budget, everything still works
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["jansen-leg", "paper000-fig8-sixbar", "geared-fivebar"])
def test_bundled_examples_draw_at_the_largest_samples(client, name) -> None:
    doc = document_to_dict(load_example(name))
    answer = client.post("/api/scene", json={"document": doc, "samples": 4096})
    assert answer.status_code == 200, answer.text
    assert answer.json()["modes"]


def test_a_study_inside_the_budget_runs(client) -> None:
    doc = document_to_dict(load_example("crank-rocker"))
    body = {"document": doc, "pivot": "B0", "direction": "right", "count": 50, "samples": 4096}
    answer = client.post("/api/study", json=body)
    assert answer.status_code == 200 and len(answer.json()["steps"]) == 51


# --------------------------------------------------------------------------------------------
# The rows of GET /api/limits
# --------------------------------------------------------------------------------------------


def test_limit_gear_turns(client) -> None:
    served = client.get("/api/limits").json()["gear_turns"]
    assert served["value"] == limits.GEAR_TURNS.value == 64
    at = {"document": geared(64.0), "pivot": "A0", "count": 0, "samples": 8}
    assert client.post("/api/study", json=at).status_code == 200
    past = {"document": geared(65.0), "pivot": "A0", "count": 0, "samples": 8}
    answer = client.post("/api/study", json=past)
    assert answer.status_code == 422 and "65 times per input turn" in answer.json()["error"]


def _study_cost(doc: dict, count: int, samples: int) -> cost.Estimate:
    mech = parse_document(doc).mechanism
    return budget.study_estimate(mech, input_range(mech), count + 1, samples)


def test_limit_request_work(client, monkeypatch) -> None:
    value = client.get("/api/limits").json()["request_work"]["value"]
    assert value == limits.REQUEST_WORK.value == cost.REQUEST_WORK.value
    doc = geared(16.0)
    few, many = _study_cost(doc, 10, 64), _study_cost(doc, 50, 64)
    assert few.work < many.work <= value and many.bytes <= limits.REQUEST_BYTES.value
    # Since the tracer keeps its limit search for the circuits it traces, every study within
    # the step limit fits the request's work before its memory; a work budget between eleven
    # and fifty-one steps shows the work alone refusing.
    lower = dataclasses.replace(cost.REQUEST_WORK, value=0.5 * (few.work + many.work))
    monkeypatch.setattr(cost, "REQUEST", cost.Scope("per request", lower, cost.REQUEST_BYTES))
    body = {"document": doc, "pivot": "A0", "count": 50, "samples": 64}
    error = client.post("/api/study", json=body).json()["error"]
    assert f"units of work (at most {lower.value:.2g} per request)" in error
    assert "memory (at most" not in error
    body["count"] = 10
    assert client.post("/api/study", json=body).status_code == 200


def _many_traced() -> dict:
    """A four-bar whose coupler carries 28 traced points: every step of a study answers 28
    curves."""
    joints = [
        {"name": "A0", "type": "fixed", "at": [0.0, 0.0]},
        {"name": "B0", "type": "fixed", "at": [4.0, 0.0]},
        {"name": "A", "type": "crank", "pivot": "A0", "length": 1.0},
        {"name": "B", "type": "rrr", "p1": "A", "r1": 4.0, "p2": "B0", "r2": 3.0},
    ]
    points = [f"P{i}" for i in range(28)]
    for i, name in enumerate(points):
        joints.append({"name": name, "type": "rigid", "origin": "A", "toward": "B", "u": 0.1 * i,
                       "v": 1.0})  # fmt: skip
    return {
        "format": "linkwright/1",
        "mechanism": {"family": "linkage", "space": "plane", "traced": points, "joints": joints},
    }


def test_limit_request_bytes(client) -> None:
    value = client.get("/api/limits").json()["request_bytes"]["value"]
    assert value == limits.REQUEST_BYTES.value == cost.REQUEST_BYTES.value
    doc = _many_traced()
    big = _study_cost(doc, 50, 4096)
    assert big.work <= limits.REQUEST_WORK.value < big.bytes and value < big.bytes
    assert _study_cost(doc, 5, 4096).bytes <= value
    body = {"document": doc, "pivot": "A0", "count": 50, "samples": 4096}
    answer = client.post("/api/study", json=body)
    assert answer.status_code == 422
    assert "of memory (at most 268 MB per request)" in answer.json()["error"]


def test_limit_request_seconds(client) -> None:
    served = client.get("/api/limits").json()["request_seconds"]
    assert served["value"] == limits.REQUEST_SECONDS.value == cost.REQUEST_SECONDS.value
    # The deadline a request's loops check is the one served.
    with budget.request("samples"):
        left = cost.remaining()
    assert left is not None and served["value"] - 1 < left <= served["value"]


def test_limit_refine_points(client) -> None:
    served = client.get("/api/limits").json()["refine_points"]
    assert served["value"] == limits.REFINE_POINTS.value == tools.REFINE_POINTS == 500
    import numpy as np

    from linkwright.atlas.query import thinned

    points = np.random.default_rng(0).normal(size=(501, 2))
    assert len(thinned(points, 500)) == 500 and len(thinned(points[:500], 500)) == 500

"""The workbench's drawing compiler routes (server/tools_sketch.py): ``POST /api/sketch`` and
``POST /api/sketch/from-document``.

A drawing in any state (empty, invalid, under- or over-constrained, without a driver,
unplaceable, ready) is answered 200 with its report; a body that is not a drawing at all is
answered 422 in one line naming the field. Each ``sketch_*`` limit is tried at its value (not
refused for it) and one past (refused, naming it). The document a drawing compiles to is one the
scene route runs.
"""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient

from linkwright.io import document_to_dict, load_example
from linkwright.server import create_app, limits
from linkwright.server.tools_sketch import EXAMPLE_SKETCH


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    return TestClient(create_app(tmp_path_factory.mktemp("sketch")))


def answer(client: TestClient, sketch: object) -> dict:
    r = client.post("/api/sketch", json={"sketch": sketch})
    assert r.status_code == 200, r.text
    body = json.loads(r.text, parse_constant=lambda name: pytest.fail(f"the answer has {name}"))
    assert set(body) == {"status", "dof", "message", "document", "placement", "joints", "links"}
    assert "\n" not in body["message"]
    return body


def refused(response, *needles: str) -> str:
    assert response.status_code == 422, response.text
    body = response.json()
    assert set(body) == {"error"}
    message = body["error"]
    assert "\n" not in message and "Traceback" not in message
    for needle in needles:
        assert needle in message, (needle, message)
    return message


def pin(name: str, x: float, y: float, **extra: object) -> dict:
    return {"name": name, "at": [x, y], **extra}


FOUR_BAR = EXAMPLE_SKETCH


@pytest.mark.parametrize(
    ("sketch", "status", "dof"),
    [
        ({}, "empty", None),
        ({"joints": [pin("A", 0, 0)], "links": [["A", "Z"]]}, "invalid", None),
        ({**FOUR_BAR, "links": FOUR_BAR["links"][:2]}, "under", 2),
        ({**FOUR_BAR, "links": [*FOUR_BAR["links"], ["A", "B0"]]}, "over", 0),
        ({**FOUR_BAR, "drivers": []}, "no-driver", 1),
        (
            {**FOUR_BAR, "joints": [pin("A0", 0, 0, ground=True), pin("A", 1, 0), pin("B", 2, 0),
                                    pin("B0", 4, 0, ground=True), pin("P", 2, 1)]},
            "unplaceable",
            1,
        ),
        (FOUR_BAR, "ok", 1),
    ],
)  # fmt: skip
def test_every_state_of_a_drawing_is_answered_200(
    client: TestClient, sketch: dict, status: str, dof: int | None
) -> None:
    body = answer(client, sketch)
    assert (body["status"], body["dof"]) == (status, dof), body["message"]
    assert (body["document"] is not None) == (status == "ok")


def test_a_compiled_drawing_runs_in_the_scene(client: TestClient) -> None:
    body = answer(client, FOUR_BAR)
    assert body["placement"] == {"A0": "ground", "A": "crank", "B": "dyad", "B0": "ground",
                                 "P": "rigid"}  # fmt: skip
    document = body["document"]
    assert document["title"] == "A drawn four-bar"
    scene = client.post("/api/scene", json={"document": document, "samples": 36})
    assert scene.status_code == 200, scene.text


@pytest.mark.parametrize(
    ("body", "needles"),
    [
        ([], ("body",)),
        ({}, ("sketch", "missing")),
        ({"sketch": []}, ("sketch",)),
        ({"sketch": {"jionts": []}}, ("sketch.jionts",)),
        ({"sketch": {"joints": [{"name": "A", "at": [0, 0], "colour": 1}]}}, ("colour",)),
        ({"sketch": {"joints": [{"name": "A", "at": [0, True]}]}}, ("sketch.joints.0.at.1",)),
        ({"sketch": {"joints": [{"name": "A", "at": [0, "1"]}]}}, ("sketch.joints.0.at.1",)),
        ({"sketch": {"joints": [{"name": "A", "at": [0, 1, 2, 3]}]}}, ("at", "3")),
        ({"sketch": {"joints": [{"name": "", "at": [0, 1]}]}}, ("name",)),
        ({"sketch": {"joints": [{"name": "A", "at": [0, 1], "ground": "yes"}]}}, ("ground",)),
        ({"sketch": {"space": "torus"}}, ("space",)),
        ({"sketch": {"links": [["A", 3]]}}, ("links",)),
        ({"sketch": {"drivers": [{"pivot": "A0"}]}}, ("joint",)),
        ({"sketch": {"title": "x" * (limits.TITLE.value + 1)}}, ("title", "at most 1,000")),
        ({"sketch": {"joints": [{"name": "J" * (limits.TEXT.value + 1), "at": [0, 0]}]}},
         ("name", f"at most {limits.TEXT.value}")),
    ],
)  # fmt: skip
def test_a_body_that_is_not_a_drawing_is_refused_in_one_line(
    client: TestClient, body: object, needles: tuple[str, ...]
) -> None:
    refused(client.post("/api/sketch", json=body), *needles)


# --------------------------------------------------------------------------------------------
# The limits, at and one past each
# --------------------------------------------------------------------------------------------


def _joints(n: int) -> list[dict]:
    return [pin(f"J{i}", float(i), float(i % 2)) for i in range(n)]


def _served(response) -> None:
    assert response.status_code == 200, response.text


def test_limit_sketch_joints(client: TestClient) -> None:
    most = limits.SKETCH_JOINTS.value
    chain = [[f"J{i}", f"J{i + 1}"] for i in range(most - 1)]
    _served(client.post("/api/sketch", json={"sketch": {"joints": _joints(most), "links": chain}}))
    refused(
        client.post("/api/sketch", json={"sketch": {"joints": _joints(most + 1), "links": chain}}),
        "sketch.joints",
        f"at most {most}",
    )
    # A slider's guide pivot counts too: the drawing says so (a state of the drawing, 200).
    joints = _joints(most)
    joints[0]["slider"] = 90.0
    body = answer(client, {"joints": joints, "links": chain})
    assert body["status"] == "invalid" and f"at most {most}" in body["message"]


def test_limit_sketch_links(client: TestClient) -> None:
    most = limits.SKETCH_LINKS.value
    sketch = {"joints": _joints(2), "links": [["J0", "J1"]] * most}
    _served(client.post("/api/sketch", json={"sketch": sketch}))
    sketch["links"].append(["J0", "J1"])
    refused(client.post("/api/sketch", json={"sketch": sketch}), "sketch.links", f"at most {most}")


def test_limit_sketch_link_joints(client: TestClient) -> None:
    most = limits.SKETCH_LINK_JOINTS.value
    names = [f"J{i}" for i in range(most + 1)]
    sketch = {"joints": _joints(most + 1), "links": [names[:most], names[-2:]]}
    _served(client.post("/api/sketch", json={"sketch": sketch}))
    sketch["links"] = [names]
    refused(
        client.post("/api/sketch", json={"sketch": sketch}), "sketch.links.0", f"at most {most}"
    )


def test_limit_sketch_drivers(client: TestClient) -> None:
    most = limits.SKETCH_DRIVERS.value
    drivers = [{"pivot": "G", "joint": "J0"}] * most
    sketch = {"joints": [pin("G", 5, 5, ground=True), *_joints(2)],
              "links": [["G", "J0", "J1"]], "drivers": drivers}  # fmt: skip
    body = answer(client, sketch)  # served (the drawing itself says the joint is driven twice)
    assert "driven twice" in body["message"]
    sketch["drivers"] = drivers + drivers[:1]
    refused(
        client.post("/api/sketch", json={"sketch": sketch}), "sketch.drivers", f"at most {most}"
    )


# --------------------------------------------------------------------------------------------
# The way back
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["jansen-leg", "paper000-fig6-linkage", "klann-leg"])
def test_a_document_draws_and_compiles_back(client: TestClient, name: str) -> None:
    document = document_to_dict(load_example(name))
    r = client.post("/api/sketch/from-document", json={"document": document})
    assert r.status_code == 200, r.text
    sketch = r.json()
    assert "slider" not in json.dumps(sketch) and None not in sketch.values()
    body = answer(client, sketch)
    assert body["status"] == "ok", body["message"]
    assert len(body["document"]["mechanism"]["joints"]) == len(sketch["joints"])


def test_a_document_without_a_drawing_is_refused_in_one_line(client: TestClient) -> None:
    hinge = document_to_dict(load_example("hinge-driven-fourbar"))
    refused(client.post("/api/sketch/from-document", json={"document": hinge}), "hinge")
    refused(
        client.post("/api/sketch/from-document", json={"document": {"format": "x"}}),
        "document",
        "format",
    )
    big = document_to_dict(load_example("jansen-leg"))
    big["title"] = "x" * (limits.TITLE.value + 1)
    refused(client.post("/api/sketch/from-document", json={"document": big}), "title")

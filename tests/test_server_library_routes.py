"""The workbench library's routes: every verb, multipart and JSON imports, and the status codes
of conflicts (409), unknown ids (404) and bad documents (422 naming the field).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from urllib.parse import unquote

import pytest
from fastapi.testclient import TestClient
from server_library_helpers import CRANK_ROCKER, SLIDER, canonical, with_mechanism

from linkwright.io import (
    document_to_dict,
    list_examples,
    load_example,
    parse_document,
)
from linkwright.server import create_app


@pytest.fixture
def client(tmp_path: Path) -> TestClient:
    return TestClient(create_app(tmp_path))


# --------------------------------------------------------------------------------------------
# Routes
# --------------------------------------------------------------------------------------------


def test_api_every_verb(client: TestClient) -> None:
    assert client.get("/api/library").json() == []
    r = client.post("/api/library", json={"name": "cr", "document": CRANK_ROCKER})
    assert r.status_code == 200
    entry = r.json()
    assert entry["name"] == "cr"
    assert entry["document"] == canonical(CRANK_ROCKER)
    eid = entry["id"]
    listed = client.get("/api/library").json()
    assert listed == [
        {k: entry[k] for k in ("id", "name", "family", "title", "created", "modified")}
    ]
    assert client.get(f"/api/library/{eid}").json() == entry

    r = client.patch(f"/api/library/{eid}", json={"name": "renamed"})
    assert r.status_code == 200
    assert r.json()["name"] == "renamed"

    slider = client.put(f"/api/library/{eid}", json={"document": SLIDER})
    assert slider.status_code == 200
    assert slider.json()["document"] == canonical(SLIDER)
    assert slider.json()["family"] == "slidercrank"
    assert client.get(f"/api/library/{eid}").json()["document"] == canonical(SLIDER)

    over = client.post(
        "/api/library", json={"name": "renamed", "document": CRANK_ROCKER, "overwrite": True}
    )
    assert over.status_code == 200
    assert over.json()["id"] == eid
    assert over.json()["family"] == "fourbar"

    r = client.get(f"/api/library/{eid}/export", params={"format": "toml"})
    assert r.status_code == 200
    assert r.headers["content-type"] == "application/toml; charset=utf-8"
    assert r.headers["content-disposition"].startswith('attachment; filename="renamed.toml"')
    assert parse_document(tomllib.loads(r.text)) == parse_document(CRANK_ROCKER)
    r = client.get(f"/api/library/{eid}/export", params={"format": "json"})
    assert r.headers["content-type"] == "application/json; charset=utf-8"
    assert parse_document(r.json()) == parse_document(CRANK_ROCKER)
    assert (
        client.get(f"/api/library/{eid}/export")
        .headers["content-type"]
        .startswith("application/toml")
    )

    r = client.post("/api/library/import", files={"file": ("mine.toml", r.text, "text/plain")})
    assert r.status_code == 422  # a .toml file holding JSON is refused, naming the file
    assert r.json()["error"].startswith("mine.toml: invalid TOML")
    text = client.get(f"/api/library/{eid}/export").text
    r = client.post("/api/library/import", files={"file": ("mine.toml", text, "application/toml")})
    assert r.status_code == 200
    assert r.json()["name"] == "Crank-rocker"
    r = client.post("/api/library/import", json={"text": text, "format": "toml", "name": "x"})
    assert r.status_code == 200
    assert r.json()["name"] == "x"

    assert client.delete(f"/api/library/{eid}").json() == {"deleted": eid}
    assert sorted(e["name"] for e in client.get("/api/library").json()) == ["Crank-rocker", "x"]


def test_api_import_multipart_names_and_formats(client: TestClient) -> None:
    untitled = json.dumps(SLIDER).encode()
    r = client.post("/api/library/import", files={"file": ("My slider.JSON", untitled)})
    assert r.status_code == 200
    assert r.json()["name"] == "My slider"  # no title: named after the file
    r = client.post(
        "/api/library/import",
        files={"file": ("upload", untitled)},
        data={"name": "given", "format": "json"},
    )
    assert r.json()["name"] == "given"
    r = client.post("/api/library/import", files={"file": ("noext", untitled)})
    assert r.json()["name"] == "noext"  # JSON guessed from the first character
    r = client.post("/api/library/import", files={"file": ("a.yaml", b"x: 1")})
    assert r.status_code == 422
    assert r.json() == {
        "error": "file: unknown file type '.yaml' (a.yaml): expected .toml or .json"
    }
    bad = json.dumps(with_mechanism(CRANK_ROCKER, rocker=0)).encode()
    r = client.post("/api/library/import", files={"file": ("bad.json", bad)})
    assert r.status_code == 422
    assert r.json()["error"].startswith("bad.json: mechanism.rocker: ")
    r = client.post(
        "/api/library/import", files={"file": ("dup.json", untitled)}, data={"name": "given"}
    )
    assert r.status_code == 409


def test_api_import_json_errors(client: TestClient) -> None:
    cases = [
        ({"format": "toml"}, "text: missing required field"),
        ({"text": 3}, "text: must be a string, got int"),
        ({"text": "", "format": 1}, "format: expected 'toml' or 'json', got 'int'"),
        ({"text": "x", "extra": 1}, "body: unknown field 'extra'"),
        ({"text": json.dumps(SLIDER), "name": 5}, "name: must be a string, got int"),
        ({"text": json.dumps(SLIDER), "name": "a\nb"}, "name: contains U+000A"),
    ]
    for body, message in cases:
        r = client.post("/api/library/import", json=body)
        assert r.status_code == 422, body
        assert r.json()["error"].startswith(message), r.json()
    r = client.post("/api/library/import", json=[1])
    assert r.json()["error"].startswith("body: expected a JSON object")
    r = client.post(
        "/api/library/import", content=b"{", headers={"content-type": "application/json"}
    )
    assert r.json() == {"error": "body: not valid JSON"}
    r = client.post("/api/library/import", content=b"x", headers={"content-type": "text/plain"})
    assert r.status_code == 422
    assert r.json()["error"].startswith("body: expected a multipart form")
    assert client.get("/api/library").json() == []
    # A blank name (an empty box on the page) means "name it after the document".
    for blank in (None, "", "  "):
        r = client.post("/api/library/import", json={"text": json.dumps(SLIDER), "name": blank})
        assert r.status_code == 200
    names = [e["name"] for e in client.get("/api/library").json()]
    assert names == ["untitled", "untitled (2)", "untitled (3)"]


def test_api_conflicts_are_409(client: TestClient) -> None:
    a = client.post("/api/library", json={"name": "a", "document": SLIDER}).json()
    client.post("/api/library", json={"name": "b", "document": SLIDER})
    r = client.post("/api/library", json={"name": "a", "document": CRANK_ROCKER})
    assert r.status_code == 409
    assert r.json() == {"error": f"name: an entry named 'a' already exists (id {a['id']})"}
    r = client.patch(f"/api/library/{a['id']}", json={"name": "b"})
    assert r.status_code == 409
    assert r.json()["error"].startswith("name: an entry named 'b' already exists")
    assert client.get(f"/api/library/{a['id']}").json() == a


@pytest.mark.parametrize("eid", ["999", "0", "abc", "-1", "99999999999999999999999"])
def test_api_unknown_ids_are_404(client: TestClient, eid: str) -> None:
    client.post("/api/library", json={"name": "a", "document": SLIDER})
    for method, path, body in [
        ("GET", f"/api/library/{eid}", None),
        ("PATCH", f"/api/library/{eid}", {"name": "x"}),
        ("PUT", f"/api/library/{eid}", {"document": SLIDER}),
        ("DELETE", f"/api/library/{eid}", None),
        ("GET", f"/api/library/{eid}/export", None),
    ]:
        r = client.request(method, path, json=body)
        assert r.status_code == 404, (method, path)
        assert r.json()["error"].startswith("library: no entry with id"), r.json()


def test_api_bad_documents_are_422_naming_the_field(client: TestClient) -> None:
    good = client.post("/api/library", json={"name": "g", "document": CRANK_ROCKER}).json()
    cases = [
        (with_mechanism(CRANK_ROCKER, coupler="long"), "document: mechanism.coupler: "),
        (with_mechanism(CRANK_ROCKER, family="hexbar"), "document: mechanism.family: "),
        ({"mechanism": CRANK_ROCKER["mechanism"]}, "document: format: missing"),
        (dict(CRANK_ROCKER, title=5), "document: title: must be a string"),
    ]
    for doc, message in cases:
        for method, path, body in [
            ("POST", "/api/library", {"name": "n", "document": doc}),
            ("PUT", f"/api/library/{good['id']}", {"document": doc}),
        ]:
            r = client.request(method, path, json=body)
            assert r.status_code == 422
            assert r.json()["error"].startswith(message), r.json()
    for body, field in [
        ({"document": CRANK_ROCKER}, "name"),
        ({"name": "n", "document": [1]}, "document"),
        ({"name": "n"}, "document"),
    ]:
        r = client.post("/api/library", json=body)
        assert r.status_code == 422
        assert r.json()["error"].startswith(field), r.json()
    r = client.post("/api/library", json={"name": "a\tb", "document": CRANK_ROCKER})
    assert r.json() == {"error": "name: contains U+0009 (a control character or line break)"}
    r = client.get(f"/api/library/{good['id']}/export", params={"format": "dxf"})
    assert r.status_code == 422
    assert r.json() == {"error": "format: expected 'toml' or 'json', got 'dxf'"}
    assert [e["name"] for e in client.get("/api/library").json()] == ["g"]
    assert client.get(f"/api/library/{good['id']}").json() == good


def test_api_export_names_the_file_in_unicode(client: TestClient) -> None:
    name = 'Kurbelschwinge "Übung" / 2'
    eid = client.post("/api/library", json={"name": name, "document": SLIDER}).json()["id"]
    disposition = client.get(f"/api/library/{eid}/export").headers["content-disposition"]
    ascii_part, utf8_part = disposition.split("; filename*=UTF-8''")
    assert ascii_part == 'attachment; filename="Kurbelschwinge _bung_ _ 2.toml"'
    # The UTF-8 name keeps its letters and quotes, not its slash (never a path in a file name).
    assert unquote(utf8_part) == name.replace("/", "_") + ".toml"


@pytest.mark.parametrize("example", list_examples())
def test_every_example_round_trips_through_the_library(client: TestClient, example: str) -> None:
    original = load_example(example)
    doc = document_to_dict(original)
    entry = client.post("/api/library", json={"name": example, "document": doc}).json()
    got = client.get(f"/api/library/{entry['id']}").json()
    assert parse_document(got["document"]) == original
    assert got["family"] == original.family
    assert got["title"] == original.title
    for fmt in ("toml", "json"):
        text = client.get(f"/api/library/{entry['id']}/export", params={"format": fmt}).text
        files = {"file": (f"{example}.{fmt}", text.encode("utf-8"))}
        imported = client.post("/api/library/import", files=files).json()
        assert parse_document(imported["document"]) == original
        assert imported["name"].startswith(original.title or example)


def test_a_name_longer_than_the_schema_says_is_refused_as_sent(client: TestClient) -> None:
    # The schema's maxLength holds for the name as sent: one space and 200 stars is 201
    # characters, though 200 once stripped (the contract fuzzer found it accepted).
    entry = client.post("/api/library", json={"name": "x", "document": CRANK_ROCKER}).json()
    padded = " " + "*" * 200
    r = client.patch(f"/api/library/{entry['id']}", json={"name": padded})
    assert r.status_code == 422
    assert r.json()["error"] == "name: 201 characters, at most 200 allowed"
    r = client.post("/api/library", json={"name": padded, "document": CRANK_ROCKER})
    assert r.status_code == 422 and "at most 200" in r.json()["error"]
    # a name of exactly 200 characters with no padding is still fine
    r = client.patch(f"/api/library/{entry['id']}", json={"name": "*" * 200})
    assert r.status_code == 200 and r.json()["name"] == "*" * 200

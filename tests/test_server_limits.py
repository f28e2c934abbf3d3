"""The workbench's limits, its loopback binding, its refusal of client paths, and a bounded load.

Every limit of :mod:`linkwright.server.limits` is tried at its value (the request passes that
limit) and one past it (refused 4xx with one line naming the field and the limit). The request
body's size is tried as a JSON body with a Content-Length, as a chunked body without one, and as
a multipart upload. Names a client sends (examples, families, export formats, library names and
ids, uploaded file names, titles) are tried as paths ("../../etc/passwd", absolute paths, NUL
bytes, very long names): nothing outside the data directory is read or written. The load test
(bench/load.py) runs small here: 300 requests at concurrency 32, and not one error.
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path
from urllib.parse import quote, unquote

import pytest
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.io import document_to_dict, load_example
from linkwright.server import LOOPBACK_HOSTS, create_app, limits
from linkwright.server.limits import LIMITS
from linkwright.server.local import LocalServer

SECRET = "linkwright-secret-9f3c"  # in files beside the data directory: never to be answered


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    app = create_app(tmp_path_factory.mktemp("limits"))
    app.state.atlas_count = 100  # the smallest atlas: builds in well under a second
    return TestClient(app)


def doc(name: str = "crank-rocker") -> dict:
    return document_to_dict(load_example(name))


def refused(response, status: int, *needles: str) -> str:
    """The one-line error of a refused request, which must name every needle."""
    assert response.status_code == status, response.text
    body = response.json()
    assert set(body) == {"error"}, body
    message = body["error"]
    assert "\n" not in message and "Traceback" not in message, message
    for needle in needles:
        assert needle in message, (needle, message)
    return message


def passed(response, limit: str) -> None:
    """A request at a limit: served, or refused for another reason than that limit."""
    if response.status_code != 200:
        message = response.json()["error"]
        unit = LIMITS[limit].unit
        assert f"at most {LIMITS[limit].value:,}" not in message, message
        assert f"{unit}, at most" not in message, message


# --------------------------------------------------------------------------------------------
# The table
# --------------------------------------------------------------------------------------------


def test_limits_are_served_read_only(client: TestClient) -> None:
    r = client.get("/api/limits")
    assert r.status_code == 200
    table = r.json()
    assert table == limits.as_json()
    assert set(table) == set(LIMITS)
    for name, entry in table.items():
        assert isinstance(entry["value"], int) and entry["value"] > 0, name
        assert entry["unit"] and entry["applies"] and len(entry["why"]) > 40, name
    for method in ("POST", "PUT", "PATCH", "DELETE"):
        refused(client.request(method, "/api/limits"), 405, "method", "GET")


def test_every_limit_is_tested_here() -> None:
    """Each limit has its ``test_limit_<name>`` in one of the test modules."""
    source = "".join(p.read_text(encoding="utf-8") for p in Path(__file__).parent.glob("test_*.py"))
    for name in LIMITS:
        assert f"def test_limit_{name}" in source, name


# --------------------------------------------------------------------------------------------
# Body size: Content-Length, chunked, multipart
# --------------------------------------------------------------------------------------------

LIMIT = limits.BODY_BYTES.value


def _scene_body(size: int) -> bytes:
    """A valid scene request padded with white space to exactly ``size`` bytes."""
    body = json.dumps({"document": doc(), "samples": 8, "diagrams": False}).encode()
    return body + b" " * (size - len(body))


def _chunks(data: bytes, size: int = 65_536):
    for i in range(0, len(data), size):
        yield data[i : i + size]


def _multipart(size: int, boundary: str = "lw-boundary") -> bytes:
    """A multipart upload of a TOML document, padded with a comment to exactly ``size`` bytes."""
    head = (
        f"--{boundary}\r\n"
        'Content-Disposition: form-data; name="file"; filename="big.toml"\r\n'
        "Content-Type: application/toml\r\n\r\n"
    ).encode()
    tail = f"\r\n--{boundary}--\r\n".encode()
    toml = b'format = "linkwright/1"\n[mechanism]\nfamily = "slidercrank"\nA0 = [0, 0]\n'
    toml += b"crank = 1\nrod = 3\nline = { point = [0, 0], angle = 0 }\n#"
    pad = size - len(head) - len(toml) - len(tail) - 1
    return head + toml + b"x" * pad + b"\n" + tail


_JSON = {"content-type": "application/json"}
_FORM = {"content-type": "multipart/form-data; boundary=lw-boundary"}


def test_limit_body_bytes(client: TestClient) -> None:
    at, over = _scene_body(LIMIT), _scene_body(LIMIT + 1)
    assert len(at) == LIMIT
    assert client.post("/api/scene", content=at, headers=_JSON).status_code == 200
    refused(
        client.post("/api/scene", content=over, headers=_JSON),
        413,
        "request body",
        "2,000,001 bytes",
        "2,000,000",
    )


def test_limit_body_bytes_holds_for_chunked_bodies(client: TestClient) -> None:
    request = client.build_request("POST", "/api/scene", content=_chunks(b"x"), headers=_JSON)
    assert "content-length" not in request.headers  # what the test is about: no length given
    at = client.post("/api/scene", content=_chunks(_scene_body(LIMIT)), headers=_JSON)
    assert at.status_code == 200
    over = client.post("/api/scene", content=_chunks(_scene_body(LIMIT + 1)), headers=_JSON)
    refused(over, 413, "request body", "2,000,000 bytes allowed")


def test_limit_body_bytes_holds_for_uploads(client: TestClient) -> None:
    at = client.post("/api/library/import", content=_multipart(LIMIT), headers=_FORM)
    assert at.status_code == 200, at.text
    assert at.json()["family"] == "slidercrank"
    refused(
        client.post("/api/library/import", content=_multipart(LIMIT + 1), headers=_FORM),
        413,
        "request body",
        "2,000,000",
    )
    chunked = client.post(
        "/api/library/import", content=_chunks(_multipart(LIMIT + 1)), headers=_FORM
    )
    refused(chunked, 413, "request body", "2,000,000")


def test_a_length_that_is_not_a_number_is_refused(client: TestClient) -> None:
    r = client.post("/api/scene", content=b"{}", headers={**_JSON, "content-length": "2e9"})
    assert r.status_code in (400, 422)


# --------------------------------------------------------------------------------------------
# JSON nesting
# --------------------------------------------------------------------------------------------


def _nested_body(depth: int) -> bytes:
    """A scene request whose deepest value is ``depth`` levels down (the body is level 1)."""
    body = json.dumps({"document": doc(), "samples": 8, "diagrams": False, "pad": 0}).encode()
    inner = b"[" * (depth - 1) + b"]" * (depth - 1)
    return body.replace(b'"pad": 0', b'"pad": ' + inner)


def test_limit_json_depth(client: TestClient) -> None:
    depth = limits.JSON_DEPTH.value
    assert limits.json_depth(_nested_body(depth)) == depth
    assert client.post("/api/scene", content=_nested_body(depth), headers=_JSON).status_code == 200
    refused(
        client.post("/api/scene", content=_nested_body(depth + 1), headers=_JSON),
        422,
        "body",
        f"nested {depth + 1} levels, at most {depth} allowed",
    )
    # Far deeper than the parser could recurse: refused the same way, not a 500.
    deep = b'{"document": ' + b"[" * 100_000 + b"]" * 100_000 + b"}"
    refused(client.post("/api/scene", content=deep, headers=_JSON), 422, "nested 100,001 levels")


def _depth(value: object) -> int:
    """Nesting by recursion over the parsed value: the independent count."""
    if isinstance(value, dict):
        return 1 + max((_depth(v) for v in value.values()), default=0)
    if isinstance(value, list):
        return 1 + max((_depth(v) for v in value), default=0)
    return 0


_json = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=3)
    ),
    max_leaves=40,
)


@settings(max_examples=200, deadline=None)
@given(value=_json, indent=st.sampled_from([None, 1]))
def test_json_depth_counts_what_the_parser_would_recurse_through(value: object, indent) -> None:
    """On the bytes, brackets in strings (escaped quotes included) not counted: the depth of
    the parsed value."""
    text = json.dumps(value, indent=indent, ensure_ascii=False).encode()
    assert limits.json_depth(text) == _depth(value)
    if isinstance(value, dict) and _depth(value) > limits.JSON_DEPTH.value:
        with pytest.raises(limits.LimitError, match="nested"):
            limits.check_document(value)


def test_limit_json_depth_holds_for_imported_documents(client: TestClient) -> None:
    depth = limits.JSON_DEPTH.value

    def text(levels: int) -> str:
        # The document is level 1 and its mechanism level 2: "x" holds the rest.
        x = "[" * (levels - 2) + "]" * (levels - 2)
        return '{"format": "linkwright/1", "mechanism": {"family": "fourbar", "x": ' + x + "}}"

    at = client.post("/api/library/import", json={"text": text(depth), "format": "json"})
    passed(at, "json_depth")
    refused(at, 422, "unknown field 'x'")  # what the parser says once the limit is passed
    over = client.post("/api/library/import", json={"text": text(depth + 1), "format": "json"})
    refused(over, 422, "text", f"nested {depth + 1} levels, at most {depth} allowed")
    toml = "a = " + "[" * 5_000 + "]" * 5_000
    deep = client.post("/api/library/import", json={"text": toml, "format": "toml"})
    refused(deep, 422, "text", "nested too deeply")


# --------------------------------------------------------------------------------------------
# Sample counts, steps, points, top-K, family size
# --------------------------------------------------------------------------------------------


def test_limit_samples(client: TestClient) -> None:
    most, least = limits.SAMPLES.value, limits.SAMPLES.least
    for samples in (least, most):
        r = client.post("/api/scene", json={"document": doc(), "samples": samples})
        assert r.status_code == 200
        assert len(json.loads(r.content)["modes"][0]["circuits"][0]["input"]) == samples
    body = {"document": doc(), "samples": most + 1}
    refused(client.post("/api/scene", json=body), 422, "samples", f"at most {most}", "4097")
    body = {"document": doc(), "samples": least - 1}
    refused(client.post("/api/scene", json=body), 422, "samples", f"at least {least}")
    # The study and the exports take the same bound.
    study = {"document": doc(), "pivot": "B0", "count": 0, "samples": most}
    assert client.post("/api/study", json=study).status_code == 200
    refused(client.post("/api/study", json=study | {"samples": most + 1}), 422, "samples")
    export = {"document": doc(), "samples": most}
    r = client.post("/api/export/csv", json=export)
    assert r.status_code == 200
    assert len(r.text.splitlines()) > most  # a header and a row per sample
    refused(client.post("/api/export/csv", json=export | {"samples": most + 1}), 422, "samples")


def test_limit_study_steps(client: TestClient) -> None:
    most = limits.STUDY_STEPS.value
    body = {"document": doc(), "pivot": "B0", "step": 0.01, "count": most, "samples": 8}
    r = client.post("/api/study", json=body)
    assert r.status_code == 200
    assert [s["steps"] for s in r.json()["steps"]] == list(range(most + 1))
    refused(
        client.post("/api/study", json=body | {"count": most + 1}),
        422,
        "count",
        f"from 0 to {most}",
    )
    refused(client.post("/api/study", json=body | {"count": -1}), 422, "count")


def _ring(n: int) -> list[list[float]]:
    return [[3 * math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n)] for i in range(n)]


def test_limit_points(client: TestClient) -> None:
    most = limits.POINTS.value
    r = client.post("/api/ellipse", json={"points": _ring(most), "count": 0})
    assert r.status_code == 200
    assert r.json()["axes"] == pytest.approx([3.0, 1.0], abs=1e-9)  # the ring drawn
    # A refined match of that many points fits 500 of them: it answers in seconds, not minutes.
    r = client.post("/api/match", json={"points": _ring(most), "top": 1, "refine": True})
    assert r.status_code == 200 and r.json()["fitted"] == 500
    assert r.json()["candidates"][0]["relative"] < 0.05
    for path in ("/api/ellipse", "/api/match"):
        refused(
            client.post(path, json={"points": _ring(most + 1)}),
            422,
            "points",
            "at most 20,000 points",
            "20,001",
        )


def test_limit_match_top(client: TestClient) -> None:
    most = limits.MATCH_TOP.value
    body = {"points": _ring(48), "top": most, "refine": False}
    r = client.post("/api/match", json=body)
    assert r.status_code == 200, r.text
    assert [c["rank"] for c in r.json()["candidates"]] == list(range(1, most + 1))
    refused(client.post("/api/match", json=body | {"top": most + 1}), 422, "top", f"at most {most}")
    refused(client.post("/api/match", json=body | {"top": 0}), 422, "top", "at least 1")


def test_limit_ellipse_family(client: TestClient) -> None:
    most = limits.ELLIPSE_FAMILY.value
    body = {"points": _ring(64), "count": most}
    r = client.post("/api/ellipse", json=body)
    assert r.status_code == 200
    assert len(r.json()["family"]) == most + 1  # Archimedes' trammel first, then the count
    refused(
        client.post("/api/ellipse", json=body | {"count": most + 1}),
        422,
        "count",
        f"at most {most}",
    )


# --------------------------------------------------------------------------------------------
# Documents: lists, title, strings; library names
# --------------------------------------------------------------------------------------------


def _linkage(joints: int, name: str = "F") -> dict:
    """A composed four-bar (pivots ``name`` and G, crank A, dyad B) with rigid points added
    until it has ``joints`` joints."""
    table = [
        {"name": name, "type": "fixed", "at": [0.0, 0.0]},
        {"name": "G", "type": "fixed", "at": [4.0, 0.0]},
        {"name": "A", "type": "crank", "pivot": name, "length": 1.0},
        {"name": "B", "type": "rrr", "p1": "A", "r1": 4.0, "p2": "G", "r2": 3.0},
    ]
    before, last = "A", "B"
    for k in range(joints - len(table)):
        table.append({"name": f"R{k}", "type": "rigid", "origin": last, "toward": before,
                      "u": 0.5, "v": 0.1})  # fmt: skip
        before, last = last, f"R{k}"
    return {"format": "linkwright/1", "mechanism": {"family": "linkage", "joints": table}}


def test_limit_document_list(client: TestClient) -> None:
    most = limits.DOCUMENT_LIST.value
    body = {"document": _linkage(most), "samples": 8, "diagrams": False}
    r = client.post("/api/scene", json=body)
    assert r.status_code == 200
    assert len(json.loads(r.content)["joints"]) == most
    refused(
        client.post("/api/scene", json=body | {"document": _linkage(most + 1)}),
        422,
        "document: mechanism.joints",
        f"{most + 1} entries, at most {most} allowed",
    )
    traced = _linkage(4)
    traced["mechanism"]["traced"] = ["B"] * (most + 1)
    refused(
        client.post("/api/scene", json={"document": traced}),
        422,
        "mechanism.traced",
        f"at most {most}",
    )
    # The library holds documents to the same bound.
    save = client.post("/api/library", json={"name": "long", "document": _linkage(most + 1)})
    refused(save, 422, "mechanism.joints", f"at most {most}")


def test_limit_title(client: TestClient) -> None:
    most = limits.TITLE.value
    body = {"document": doc() | {"title": "t" * most}, "samples": 8}
    r = client.post("/api/scene", json=body)
    assert r.status_code == 200 and json.loads(r.content)["title"] == "t" * most
    body["document"]["title"] += "t"
    refused(
        client.post("/api/scene", json=body),
        422,
        "document: title",
        "1,001 characters, at most 1,000 allowed",
    )
    refused(client.post("/api/export/svg", json=body), 422, "title", "1,000")


def test_limit_text(client: TestClient) -> None:
    most = limits.TEXT.value
    name = "F" * most
    body = {"document": _linkage(4, name), "samples": 8, "diagrams": False}
    r = client.post("/api/scene", json=body)
    assert r.status_code == 200 and name in json.loads(r.content)["joints"]
    # Every joint a document may name can be dragged: drag.joint has the same bound.
    drag = {"document": _linkage(4, name), "joint": name, "to": [0.5, 0.5], "at": 10.0}
    passed(client.post("/api/drag", json=drag), "text")
    refused(
        client.post("/api/scene", json=body | {"document": _linkage(4, name + "F")}),
        422,
        "document: mechanism.joints[0].name",
        f"{most + 1} characters, at most {most} allowed",
    )
    refused(
        client.post("/api/drag", json=drag | {"joint": name + "F"}),
        422,
        "joint",
        f"at most {most} allowed",
    )
    study = {"document": doc(), "pivot": "P" * (most + 1)}
    refused(client.post("/api/study", json=study), 422, "pivot", f"at most {most}")
    units = {"document": doc() | {"units": "m" * (most + 1)}}
    refused(client.post("/api/scene", json=units), 422, "document: units", f"at most {most}")


def test_limit_name(client: TestClient) -> None:
    most = limits.NAME.value
    r = client.post("/api/library", json={"name": "n" * most, "document": doc()})
    assert r.status_code == 200 and r.json()["name"] == "n" * most
    over = {"name": "m" * (most + 1), "document": doc()}
    refused(
        client.post("/api/library", json=over),
        422,
        "name",
        f"{most + 1} characters, at most {most} allowed",
    )
    entry = r.json()["id"]
    refused(client.patch(f"/api/library/{entry}", json={"name": "r" * (most + 1)}), 422, "name")


# --------------------------------------------------------------------------------------------
# Errors the framework raises are the API's errors too
# --------------------------------------------------------------------------------------------


def test_unknown_paths_methods_and_bodies_answer_json(client: TestClient) -> None:
    refused(client.get("/api/nothing"), 404, "path", "/api/nothing")
    r = client.get("/api/scene")
    refused(r, 405, "method", "GET", "POST")
    assert r.headers["allow"] == "POST"
    assert client.request("OPTIONS", "/api/library/1").headers["allow"] == (
        "DELETE, GET, PATCH, PUT"
    )
    refused(client.post("/api/scene", content=b"{", headers=_JSON), 422, "body", "invalid JSON")
    huge = b'{"document": {}, "samples": ' + b"9" * 5_000 + b"}"
    refused(client.post("/api/scene", content=huge, headers=_JSON), 400, "body")
    refused(client.post("/api/scene", content=b"[]", headers=_JSON), 422, "body")


# --------------------------------------------------------------------------------------------
# Loopback, hosts, origins
# --------------------------------------------------------------------------------------------


def test_local_server_listens_on_loopback_only(tmp_path: Path) -> None:
    server = LocalServer(tmp_path / "data")
    assert server.server.config.host == "127.0.0.1"
    with server as url:
        assert url.startswith("http://127.0.0.1:")
        sockets = [s for srv in server.server.servers for s in srv.sockets]
        assert sockets and all(s.getsockname()[0] == "127.0.0.1" for s in sockets)
        import httpx

        with httpx.Client(base_url=url, timeout=30) as http:
            assert http.get("/api/health").status_code == 200
            # Another name for this machine is DNS rebinding: refused.
            refused(http.get("/api/health", headers={"host": "evil.example"}), 421, "host")


def test_hosts_outside_the_allowed_are_refused(tmp_path: Path) -> None:
    app = create_app(tmp_path, allowed_hosts=LOOPBACK_HOSTS)
    for host in ("127.0.0.1:8000", "localhost", "[::1]:8000"):
        assert TestClient(app, base_url=f"http://{host}").get("/api/health").status_code == 200
    refused(TestClient(app).get("/api/health"), 421, "host", "testserver")
    # No list: every host is answered (a server opened to the network with --host).
    assert TestClient(create_app(tmp_path)).get("/api/health").status_code == 200


def test_writes_from_another_site_are_refused(client: TestClient) -> None:
    body = {"name": "csrf", "document": doc()}
    for origin in ("http://evil.example", "null", "http://testserver.evil.example"):
        r = client.post("/api/library", json=body, headers={"origin": origin})
        refused(r, 403, "origin", "cross-site")
        r = client.delete("/api/library/1", headers={"origin": origin})
        refused(r, 403, "origin")
    assert "csrf" not in {e["name"] for e in client.get("/api/library").json()}
    # The page's own requests carry its own origin; reads from anywhere are answered.
    same = client.post("/api/library", json=body, headers={"origin": "http://testserver"})
    assert same.status_code == 200
    assert client.get("/api/health", headers={"origin": "http://evil.example"}).status_code == 200


# --------------------------------------------------------------------------------------------
# No client-supplied paths
# --------------------------------------------------------------------------------------------

HOSTILE = [
    "../../etc/passwd",
    "../secret.txt",
    "..\\..\\secret.txt",
    "/etc/passwd",
    "crank-rocker\x00.toml",
    "crank-rocker%00",
    "....//....//secret.txt",
    "x" * 5_000,
]


def _files(root: Path, skip: Path) -> dict[str, tuple[int, int]]:
    """Every file and folder under ``root`` but inside ``skip``: path → (size, mtime)."""
    out = {}
    for path in root.rglob("*"):
        if path == skip or skip in path.parents:
            continue
        stat = path.stat()
        out[str(path.relative_to(root))] = (stat.st_size, stat.st_mtime_ns)
    return out


@pytest.fixture
def sandbox(tmp_path: Path):
    """A data directory with decoys beside it, and a client over it."""
    data = tmp_path / "data"
    (tmp_path / "secret.txt").write_text(SECRET)
    (tmp_path / "etc").mkdir()
    (tmp_path / "etc" / "passwd").write_text(SECRET)
    client = TestClient(create_app(data))
    before = _files(tmp_path, data)
    yield tmp_path, data, client
    assert _files(tmp_path, data) == before  # nothing outside the data directory changed
    scratch = data / "scratch"
    assert not scratch.exists() or not any(scratch.iterdir())  # exports clean up after them


def _absolute(root: Path) -> list[str]:
    return [*HOSTILE, str(root / "secret.txt"), str(root / "etc" / "passwd")]


def _seen(response) -> None:
    assert SECRET not in response.text
    if response.status_code >= 400:
        refused(response, response.status_code)


def test_names_in_paths_never_read_files(sandbox) -> None:
    root, _, client = sandbox
    for name in _absolute(root):
        for raw in (quote(name, safe=""), quote(name, safe="/")):
            for url in (
                f"/api/examples/{raw}",
                f"/api/families/{raw}/default",
                f"/api/library/{raw}",
                f"/api/library/{raw}/export",
                f"/static/{raw}",
            ):
                r = client.get(url)
                assert r.status_code in (404, 422), (url, r.status_code)
                _seen(r)
            r = client.post(f"/api/export/{raw}", json={"document": doc()})
            assert r.status_code in (404, 405, 422), (name, r.status_code)
            _seen(r)
    for url in ("/static/%2e%2e/%2e%2e/secret.txt", "/static/..%2f..%2fsecret.txt"):
        _seen(client.get(url))


def test_library_names_are_names_not_paths(sandbox) -> None:
    root, data, client = sandbox
    for name in _absolute(root):
        r = client.post("/api/library", json={"name": name, "document": doc(), "overwrite": True})
        if r.status_code != 200:  # a control character or too long: refused, naming the name
            refused(r, 422, "name")
            continue
        entry = r.json()
        assert entry["name"] == name
        for fmt in ("toml", "json"):
            r = client.get(f"/api/library/{entry['id']}/export", params={"format": fmt})
            assert r.status_code == 200 and SECRET not in r.text
            ascii_part, utf8_part = r.headers["content-disposition"].split("; filename*=UTF-8''")
            filename = ascii_part.removeprefix('attachment; filename="').removesuffix('"')
            for shown in (filename, unquote(utf8_part)):
                assert "/" not in shown and "\\" not in shown and not shown.startswith(".")
                assert shown.endswith(f".{fmt}") and len(shown) <= 105
        r = client.patch(f"/api/library/{entry['id']}", json={"name": name + " (renamed)"})
        assert r.status_code in (200, 422)
        assert client.delete(f"/api/library/{entry['id']}").status_code == 200
        for fmt in (name, quote(name, safe="")):
            r = client.get("/api/library/1/export", params={"format": fmt})
            assert r.status_code in (404, 422)
            _seen(r)
    assert sorted(p.name for p in data.iterdir() if p.is_file())[:1] == ["library.sqlite3"]


def test_uploaded_file_names_are_never_paths(sandbox) -> None:
    root, _, client = sandbox
    text = json.dumps(doc("offset-slider-crank") | {"title": None}).replace(', "title": null', "")
    for name in [*_absolute(root), "a\nb.json", "evil.json\r\nX-Header: 1"]:
        files = {"file": (name, text.encode(), "application/json")}
        r = client.post("/api/library/import", files=files, data={"format": "json"})
        _seen(r)
        if r.status_code == 200:
            entry = r.json()["name"]
            assert "/" not in entry and "\\" not in entry and "\x00" not in entry
            assert "\n" not in entry and len(entry) <= limits.NAME.value
        else:
            refused(r, r.status_code)
    # A broken file named by a hostile name: the message shows the last component, one line.
    bad = {"file": ("../../etc/passwd.toml\nsecond line", b"not = [toml", "text/plain")}
    message = refused(client.post("/api/library/import", files=bad), 422, "passwd.toml")
    assert "../" not in message and "etc/" not in message


def test_export_file_names_come_from_titles_made_safe(sandbox) -> None:
    root, _, client = sandbox
    for title in [*_absolute(root)[:6], "", ".hidden", "con", "a" * 900]:
        body = {"document": doc() | {"title": title}, "samples": 8}
        for fmt in ("svg", "toml"):
            r = client.post(f"/api/export/{fmt}", json=body)
            if r.status_code != 200:
                refused(r, 422)
                continue
            disposition = r.headers["content-disposition"]
            filename = disposition.split('filename="')[1].split('"')[0]
            assert "/" not in filename and "\\" not in filename and ".." not in filename
            assert not filename.startswith(".") and filename.endswith(f".{fmt}")
            assert len(filename) <= 90


# --------------------------------------------------------------------------------------------
# Load: bench/load.py, small
# --------------------------------------------------------------------------------------------


def _load_module():
    path = Path(__file__).resolve().parents[1] / "bench" / "load.py"
    spec = importlib.util.spec_from_file_location("linkwright_bench_load", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_load_300_requests_at_concurrency_32_without_an_error() -> None:
    load = _load_module()
    report = load.run_local(requests=300, concurrency=32, seed=1)
    assert len(report.records) == 300
    assert not report.errors, load.format_report(report, "test")
    endpoints = {r.endpoint for r in report.records}
    assert endpoints == {name for name, _ in load.MIX}
    table = load.format_report(report, "test")
    assert "overall" in table and "errors by status: none" in table

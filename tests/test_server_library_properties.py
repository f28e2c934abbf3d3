"""Properties of the workbench library: random names through the routes against the naming rule
as the issue states it (written out here, independent of the store), and random four-bars
round-tripping through the store.
"""

from __future__ import annotations

import json
import math
import tomllib
import unicodedata

import pytest
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st
from server_library_helpers import SLIDER

from linkwright.io import (
    document_to_dict,
    parse_document,
)
from linkwright.server import create_app
from linkwright.server.library import (
    MAX_NAME,
    Library,
)

# --------------------------------------------------------------------------------------------
# Properties
# --------------------------------------------------------------------------------------------

REFUSED = {"Cc", "Cs", "Zl", "Zp"}


# Bidirectional controls (Unicode's Bidi_Control property): they can make a name read as
# something it is not; and what draws nothing: format marks, combining marks with no base,
# spaces, and the Hangul and Braille blanks that fonts draw empty.
BIDI = (
    set("\u061c\u200e\u200f")
    | {chr(c) for c in range(0x202A, 0x202F)}
    | {chr(c) for c in range(0x2066, 0x206A)}
)


SHOWS_NOTHING = {"Cf", "Mn", "Me", "Zs"}


BLANK = set("\u115f\u1160\u3164\uffa0\u2800")


def name_rule(text: str) -> str | None:
    """The issues' naming rule, written out: the stored name, or None if refused."""
    name = unicodedata.normalize("NFC", text).strip()
    if not 1 <= len(name) <= MAX_NAME:
        return None
    if any(unicodedata.category(ch) in REFUSED or ch in BIDI for ch in name):
        return None
    if all(unicodedata.category(ch) in SHOWS_NOTHING or ch in BLANK for ch in name):
        return None
    return name


names = st.one_of(
    st.text(max_size=20),
    st.text(st.characters(codec="utf-8"), min_size=1, max_size=30),
    st.builds(
        lambda pad, core, tail: pad + core + tail,
        st.sampled_from(["", " ", "\t", "\n ", "\u3000"]),
        st.text(st.characters(exclude_categories=("Cc", "Cs", "Zl", "Zp")), max_size=210),
        st.sampled_from(["", " ", "\r\n", "\x85"]),
    ),
)


@settings(max_examples=60, deadline=None)
@given(name=names)
def test_random_names_through_the_api(api_client: TestClient, name: str) -> None:
    expected = name_rule(name)
    r = api_client.post("/api/library", json={"name": name, "document": SLIDER, "overwrite": True})
    if expected is None:
        assert r.status_code == 422
        assert r.json()["error"].startswith("name: ")
        return
    assert r.status_code == 200, r.json()
    entry = r.json()
    assert entry["name"] == expected
    assert api_client.get(f"/api/library/{entry['id']}").json()["name"] == expected
    assert expected in {e["name"] for e in api_client.get("/api/library").json()}
    renamed = api_client.patch(f"/api/library/{entry['id']}", json={"name": name + " ·"})
    if name_rule(name + " ·") is None:
        assert renamed.status_code == 422
        assert renamed.json()["error"].startswith("name: ")
    else:
        assert renamed.json()["name"] == name_rule(name + " ·")
    assert api_client.delete(f"/api/library/{entry['id']}").status_code == 200


@pytest.fixture(scope="module")
def api_client(tmp_path_factory: pytest.TempPathFactory) -> TestClient:
    return TestClient(create_app(tmp_path_factory.mktemp("library-api")))


@pytest.fixture(scope="module")
def shared_lib(tmp_path_factory: pytest.TempPathFactory) -> Library:
    return Library(tmp_path_factory.mktemp("library-store") / "library.sqlite3")


coordinate = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False)


length = st.floats(1e-3, 1e3, allow_subnormal=False)


fourbars = st.builds(
    lambda a0, b0, crank, coupler, rocker, u, v, assembly, title: {
        "format": "linkwright/1",
        **({} if title is None else {"title": title}),
        "mechanism": {
            "family": "fourbar",
            "A0": list(a0),
            "B0": list(b0),
            "crank": crank,
            "coupler": coupler,
            "rocker": rocker,
            "point": {"u": u, "v": v},
            "assembly": assembly,
        },
    },
    st.tuples(coordinate, coordinate),
    st.tuples(coordinate, coordinate),
    length,
    length,
    length,
    coordinate,
    coordinate,
    st.sampled_from([1, -1]),
    st.none() | st.text(max_size=40),
    # Pivots closer than 1e-9 of the linkage's size (at most 1e3 here) coincide for the parser.
).filter(lambda d: math.dist(d["mechanism"]["A0"], d["mechanism"]["B0"]) > 1e-5)


@settings(max_examples=40, deadline=None)
@given(doc=fourbars)
def test_random_fourbars_round_trip(shared_lib: Library, doc: dict) -> None:
    expected = parse_document(doc)
    entry = shared_lib.save("random", doc, overwrite=True)
    got = shared_lib.get(entry["id"])
    assert got["document"] == document_to_dict(expected)
    assert (got["family"], got["title"]) == ("fourbar", expected.title)
    for fmt in ("toml", "json"):
        text = shared_lib.export_text(entry["id"], fmt)
        loaded = tomllib.loads(text) if fmt == "toml" else json.loads(text)
        assert parse_document(loaded) == expected
        imported = shared_lib.import_text(text, fmt)
        assert parse_document(imported["document"]) == expected
        assert imported["name"] == name_rule(imported["name"])
        shared_lib.delete(imported["id"])

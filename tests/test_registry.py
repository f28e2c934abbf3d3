"""The family registry: every family declared once, and a family of one's own in one file.

The worked example of docs/families.md (docs/families/press_sixbar.py) is registered in a fresh
process, so the families of the other tests stay the built-in ones; there documents, the CLI,
the pictures and the workbench must all know it, each checked against the family's own
constraints.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from linkwright.io import FAMILY_SPECS, load_example
from linkwright.mechanisms import FAMILIES, registry
from linkwright.server.scene import families

ROOT = Path(__file__).resolve().parents[1]


def test_every_family_is_declared_once_and_everything_lists_the_same():
    names = [f.name for f in registry.families()]
    assert len(names) == len(set(names))
    assert list(FAMILIES) == names
    assert list(FAMILY_SPECS) == names
    assert [f["family"] for f in families()] == names
    displays = [f.display for f in registry.families()]
    assert len(displays) == len(set(displays))
    for entry in registry.families():
        assert entry.cls.family == entry.name
        doc = load_example(entry.example)
        assert doc.family == entry.name, entry.name
        if entry.space != "either":
            assert doc.mechanism.space == entry.space
        joints = {j for j, _ in entry.joints}
        if entry.name != "linkage":
            assert joints == set(entry.cls.reported_joints), entry.name
        for spec in entry.fields:
            assert spec.kind in registry.KIND_UNITS or spec.kind in (
                "stephenson_input",
                "spherical_input",
                "space",
                "joints",
                "names",
            ), spec


def test_an_unknown_family_names_the_nearest():
    with pytest.raises(LookupError, match="did you mean 'watt1'"):
        registry.family("watt-1")


def test_a_family_of_ones_own_in_one_file(tmp_path):
    """docs/families.md's worked example: registered, it is a family like any other."""
    doc = tmp_path / "press.toml"
    doc.write_text(
        textwrap.dedent(
            """\
            format = "linkwright/1"
            title = "Press six-bar"

            [mechanism]
            family = "press-sixbar"
            A0 = [0.0, 0.0]
            B0 = [4.0, 0.0]
            crank = 1.0
            coupler = 4.0
            rocker = 3.5
            C = { u = 2.0, v = 1.5 }
            rod = 4.0
            guide = { point = [2.0, 6.0], angle = 90.0 }
            """
        ),
        encoding="utf-8",
    )
    script = textwrap.dedent(
        f"""\
        import contextlib, io, json, sys, tempfile
        sys.path.insert(0, {str(ROOT / "docs" / "families")!r})
        import press_sixbar  # the one file
        from fastapi.testclient import TestClient
        from linkwright.cli import main
        from linkwright.io import load_document, document_to_dict
        from linkwright.server import create_app

        out = {{}}
        for verb in (["solve", "--input", "0:360:30", "--json"], ["curve", "--json"],
                     ["analyze", "--json"], ["plot", "--out", {str(tmp_path / "p.png")!r}],
                     ["export", "--out", {str(tmp_path / "p.svg")!r}]):
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                code = main([verb[0], {str(doc)!r}, *verb[1:]])
            out[verb[0]] = (code, buf.getvalue())
        client = TestClient(create_app(tempfile.mkdtemp()))
        fams = client.get("/api/families").json()
        schema = client.get("/openapi.json").json()
        body = document_to_dict(load_document({str(doc)!r}))
        scene = client.post("/api/scene", json={{"document": body, "samples": 48}})
        print(json.dumps({{
            "out": out,
            "family": [f for f in fams if f["family"] == "press-sixbar"],
            "in_schema": "press-sixbar" in json.dumps(schema),
            "scene": scene.status_code,
        }}))
        """
    )
    run = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    codes = {verb: code for verb, (code, _) in result["out"].items()}
    assert set(codes.values()) == {0}, codes
    assert result["family"] == [
        {
            "family": "press-sixbar",
            "name": "Press six-bar",
            "group": "Six-bars",
            "space": "plane",
            "example": "crank-rocker",
        }
    ]
    assert result["in_schema"] and result["scene"] == 200
    # The solved ram stays on its guide (x = 2) and every link keeps its length.
    solved = json.loads(result["out"]["solve"][1])
    for sample in solved["samples"]:
        (conf,) = sample["configurations"]
        j = {k: np.array(v) for k, v in conf["joints"].items()}
        assert abs(j["D"][0] - 2.0) < 1e-12
        assert abs(np.linalg.norm(j["D"] - j["C"]) - 4.0) < 1e-12
        assert abs(np.linalg.norm(j["B"] - j["A"]) - 4.0) < 1e-12
    curve = json.loads(result["out"]["curve"][1])
    assert curve["closed"] and curve["full_turn"]
    assert (tmp_path / "p.png").stat().st_size > 0 and (tmp_path / "p.svg").stat().st_size > 0

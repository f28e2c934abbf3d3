"""The tutorial notebook (docs/tutorial.ipynb) runs from top to bottom, and what it shows is what
it says (issue 23 item 5)."""

from __future__ import annotations

from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat", reason="the dev extra installs nbformat")
nbclient = pytest.importorskip("nbclient", reason="the dev extra installs nbclient")

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "tutorial.ipynb"


def test_tutorial_notebook_runs_and_shows_its_linkages() -> None:
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # Bounded: each cell has two minutes, the whole notebook takes about ten seconds.
    nbclient.NotebookClient(nb, timeout=120, kernel_name="python3").execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    pictures = [o["data"]["image/svg+xml"] for o in outputs if "image/svg+xml" in o.get("data", {})]
    # The crank-rocker, its circuit, the linkage that cannot assemble, the synthesised one and
    # the Jansen leg each show an SVG.
    assert len(pictures) >= 5
    assert any("cannot be assembled at any input" in p for p in pictures)
    printed = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "None []" in printed  # the linkage that cannot assemble: no class, no circuit
    assert printed.rstrip().endswith("True")  # the synthesised four-bar meets its poses

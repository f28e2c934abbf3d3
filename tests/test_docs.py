"""The documentation site (issue 23 item 4): it builds with warnings as errors, its gallery has
an example for every registered family and every seed paper, each with its picture, and the
getting-started page's examples print what the page says.

The whole build (about a minute on 2 cores, most of it the gallery running its examples) is
one test, run into a scratch copy of docs/ so that it never races a `make docs` in the tree.
"""

from __future__ import annotations

import doctest
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from linkwright.mechanisms import registry

pytest.importorskip("sphinx_gallery", reason="the docs extra (in dev) installs sphinx-gallery")

DOCS = Path(__file__).resolve().parents[1] / "docs"
GALLERY = DOCS / "gallery"
PAPERS = ("000", "001", "002", "003", "004")


def _family_examples() -> dict[str, Path]:
    """The family gallery's examples by family name (``plot_NN_<name>.py``, '-' written '_')."""
    found: dict[str, Path] = {}
    for path in sorted((GALLERY / "families").glob("plot_*.py")):
        match = re.fullmatch(r"plot_\d\d_(\w+)\.py", path.name)
        assert match, f"{path.name}: name family examples plot_NN_<family>.py"
        found[match.group(1).replace("_", "-")] = path
    return found


def test_every_family_and_every_paper_has_a_gallery_example() -> None:
    names = [f.name for f in registry.families()]
    examples = _family_examples()
    assert sorted(examples) == sorted(names)
    # Numbered in the registry's order, so the gallery lists them as the workbench does.
    assert list(examples) == names
    for paper in PAPERS:
        assert (GALLERY / "papers" / f"plot_paper{paper}.py").is_file()


def test_each_family_example_builds_its_own_family() -> None:
    """An example named for a family must make a mechanism of that family, not another."""
    for name, path in _family_examples().items():
        cls = registry.family(name).cls.__name__
        text = path.read_text(encoding="utf-8")
        example = registry.family(name).example
        assert f"lw.{cls}(" in text or f'load_example("{example}")' in text, (
            f"{path.name} builds no {cls} (nor loads the family's example, {example})"
        )


def test_getting_started_examples_print_what_the_page_says() -> None:
    os.environ.setdefault("MPLBACKEND", "Agg")
    result = doctest.testfile(
        str(DOCS / "getting-started.rst"),
        module_relative=False,
        optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS,
        verbose=False,
    )
    assert result.attempted > 20
    assert result.failed == 0


def test_the_site_builds_with_warnings_as_errors(tmp_path: Path) -> None:
    source = tmp_path / "docs"
    shutil.copytree(DOCS, source, ignore=shutil.ignore_patterns("_build", "generated"))
    out = tmp_path / "html"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    build = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-b",
            "html",
            "-W",
            "--keep-going",
            "-q",
            "-d",
            str(tmp_path / "doctrees"),
            str(source),
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert build.returncode == 0, build.stdout[-4000:] + build.stderr[-8000:]

    for page in ("index", "getting-started", "cli", "families", "api"):
        assert (out / f"{page}.html").is_file(), page
    # The CLI reference and the family guide are the Markdown files themselves, included whole.
    cli = (out / "cli.html").read_text(encoding="utf-8")
    assert "Every verb for every family" in cli
    assert "linkwright synth" in cli
    assert "Adding a family: one file" in (out / "families.html").read_text(encoding="utf-8")

    # The API reference documents the top-level namespace and each subpackage from docstrings.
    api = out / "generated" / "api"
    for module in (
        "linkwright",
        "linkwright.mechanisms",
        "linkwright.analysis",
        "linkwright.synthesis",
        "linkwright.plot",
        "linkwright.io",
        "linkwright.engine",
        "linkwright.atlas",
    ):
        assert (api / f"{module}.html").is_file(), module
    mechanisms = (api / "linkwright.mechanisms.html").read_text(encoding="utf-8")
    assert 'id="linkwright.mechanisms.FourBar"' in mechanisms
    # `lw.FourBar` in the namespace's table links to where FourBar is documented.
    top = (api / "linkwright.html").read_text(encoding="utf-8")
    assert 'href="linkwright.mechanisms.html#linkwright.mechanisms.FourBar"' in top
    # A docstring's |A − B0| is an absolute value, shown as written (not a substitution).
    assert "|A − B0|" in (api / "linkwright.engine.html").read_text(encoding="utf-8")

    # Every example ran and left at least one picture on its page.
    gallery = out / "generated" / "gallery"
    examples = [*(_family_examples().values()), *(GALLERY / "papers").glob("plot_*.py")]
    assert len(examples) == len(list(registry.families())) + len(PAPERS)
    for example in examples:
        page = gallery / example.parent.name / f"{example.stem}.html"
        html = page.read_text(encoding="utf-8")
        pictures = re.findall(r'src="((?:\.\./)+_images/sphx_glr_[^"]+\.png)"', html)
        assert pictures, f"{example.name} shows no picture"
        for picture in pictures:
            assert (page.parent / picture).stat().st_size > 5_000, picture

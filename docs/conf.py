"""Sphinx configuration of linkwright's documentation site (``make docs``).

The site is built from the package's own docstrings (autodoc, NumPy style through napoleon),
the Markdown pages beside this file (docs/cli.md and docs/families.md, included unchanged
through MyST) and a sphinx-gallery of runnable examples (docs/gallery/, one per family and one
per seed paper). Everything generated lands in docs/_build and docs/generated (both ignored).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.transforms import SphinxTransform

import linkwright

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # the gallery's image scraper (_scraper.py) lives beside us

project = "linkwright"
author = "the linkwright developers"
copyright = "the linkwright developers"
release = linkwright.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
# The gallery's sources are Python files that sphinx-gallery turns into pages of generated/.
exclude_patterns = ["_build", "gallery/**"]

# docs/cli.md opens at level 2 ("## Command line"): it is written to sit under the README's
# title, and the site gives it a page of its own unchanged.
suppress_warnings = ["myst.header"]
myst_heading_anchors = 3

autosummary_generate = True
# The subpackages that document the objects the top-level namespace re-exports, in the order
# an owner is looked for (docs/api.rst lists the same pages).
API_OWNERS = (
    "linkwright.mechanisms",
    "linkwright.analysis",
    "linkwright.synthesis",
    "linkwright.plot",
    "linkwright.io",
    "linkwright.engine",
)


def _namespace_groups() -> list[tuple[str, list[str]]]:
    """The top-level names, by kind, each spelt where it is documented (its subpackage)."""
    groups: dict[str, list[str]] = {"Classes": [], "Exceptions": [], "Functions": []}
    for name in linkwright.__all__:
        obj = getattr(linkwright, name)
        owner = next(
            (m for m in API_OWNERS if getattr(importlib.import_module(m), name, None) is obj),
            None,
        )
        if owner is None:  # __version__, and the atlas module named in the page's text
            continue
        if isinstance(obj, type):
            kind = "Exceptions" if issubclass(obj, BaseException) else "Classes"
        else:
            kind = "Functions"
        # Relative to the page's module, linkwright: autosummary refuses its own name there.
        groups[kind].append(f"{owner.removeprefix('linkwright.')}.{name}")
    return [(kind, names) for kind, names in groups.items() if names]


autosummary_context = {"namespace_groups": _namespace_groups()}
autodoc_member_order = "bysource"
# Signatures carry the types; repeating them in the description only adds noise.
autodoc_typehints = "signature"
autodoc_typehints_format = "short"
autoclass_content = "class"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
# The docstrings often write "name : what it is" with prose where a type would stand. Rendered
# as text (not as cross-references), prose such as "points [x, y]" links nowhere.
napoleon_use_param = False
napoleon_custom_sections = [("Attributes", "params_style")]
napoleon_use_rtype = False

html_theme = "pydata_sphinx_theme"
html_title = f"linkwright {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}

sphinx_gallery_conf = {
    "examples_dirs": ["gallery"],
    "gallery_dirs": ["generated/gallery"],
    "filename_pattern": r"/",  # every example runs: each one draws its picture
    "image_scrapers": ("matplotlib", "_scraper.scrape"),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "plot_gallery": True,
    "abort_on_example_error": True,
    # The table of run times would be written into docs/ itself, outside the ignored folders.
    "write_computation_times": False,
}


class PlainBars(SphinxTransform):
    """Read ``|x|`` in a docstring as the absolute value its author wrote, not as a substitution.

    The library's docstrings are plain text first (``help()``, doctests, the terminal) and
    write |A − B0| for a distance; reStructuredText parses that as a substitution reference.
    No page defines substitutions of its own, so any reference left undefined after Sphinx's
    own (|version|, |release|, |today|) is put back as the text it was written as.
    """

    default_priority = 215  # after Sphinx's DefaultSubstitutions (210), before docutils' (220)

    def apply(self, **kwargs: Any) -> None:
        defined = self.document.substitution_defs
        for ref in list(self.document.findall(nodes.substitution_reference)):
            if ref["refname"] not in defined:
                ref.replace_self(nodes.Text(f"|{ref.astext()}|"))


def alias_namespace(app: Sphinx, env: Any) -> None:
    """Let ``linkwright.FourBar`` name the object documented as ``linkwright.mechanisms.FourBar``.

    ``import linkwright as lw`` re-exports the public API of the subpackages. Each object is
    documented once, in its subpackage; documenting it again under ``linkwright`` would give
    every cross-reference two targets. The top-level names are noted as aliases instead, so
    references to them resolve and a fuzzy reference still prefers the documented name.
    """
    domain = env.get_domain("py")
    objects = dict(domain.objects)
    for name in linkwright.__all__:
        obj = getattr(linkwright, name)
        for module in API_OWNERS:
            owner = f"{module}.{name}"
            entry = objects.get(owner)
            if entry is None or entry.aliased:
                continue
            if getattr(importlib.import_module(module), name, None) is not obj:
                continue
            domain.objects[f"linkwright.{name}"] = entry._replace(aliased=True)
            break


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_transform(PlainBars)
    app.connect("env-updated", alias_namespace)
    return {"parallel_read_safe": True, "parallel_write_safe": True}

"""Sphinx-gallery image scraper for figures built without pyplot.

linkwright's plot verbs build :class:`matplotlib.figure.Figure` objects on an Agg canvas and
never register them with pyplot, so sphinx-gallery's own matplotlib scraper cannot see them.
This one looks for figures bound to names in the example's namespace after each code block
and saves those it has not saved before (a figure is shown once, after the block that made it).
"""

from __future__ import annotations

import weakref
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

# Figures already saved, by example file. Weak references, not ids: once a figure is collected
# its id may be reused by a new figure, which must then be shown.
_SEEN: dict[str, weakref.WeakSet[Figure]] = {}


def scrape(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
    """Save every :class:`~matplotlib.figure.Figure` in the example's globals not yet saved."""
    seen = _SEEN.setdefault(str(block_vars["src_file"]), weakref.WeakSet())
    figures = [
        value
        for value in block_vars["example_globals"].values()
        if isinstance(value, Figure) and value not in seen
    ]
    paths: list[str] = []
    for fig, path in zip(figures, block_vars["image_path_iterator"], strict=False):
        seen.add(fig)
        fig.savefig(path, dpi=80)
        paths.append(str(Path(path)))
    return figure_rst(paths, gallery_conf["src_dir"])

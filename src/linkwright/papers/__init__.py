"""Reproductions of the seed papers' tables and figures, beside the printed numbers.

:func:`errata` returns the errata page: what linkwright's re-derivations found wrong in print,
paper by paper, each with how it was checked (``linkwright papers errata`` prints it).
"""

from __future__ import annotations

from importlib.resources import files

__all__ = ["errata"]


def errata() -> str:
    """The errata of the seed papers (Markdown), as shipped with the package.

    >>> errata().splitlines()[0]
    '# Errata of the seed papers found by linkwright'
    """
    return files("linkwright.papers").joinpath("errata.md").read_text(encoding="utf-8")

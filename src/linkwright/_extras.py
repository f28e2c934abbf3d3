"""The optional parts of linkwright and the one-line hint a missing one gives.

The core install (engine, analyses, documents, plots, command line) needs numpy, scipy,
matplotlib, typer and ezdxf. The rest are extras, each named after what it brings:

``server``
    the browser workbench, ``linkwright serve`` (fastapi, uvicorn, python-multipart, orjson);
``atlas``
    the curve atlas at scale: a FAISS index and Dask builds (without them the atlas searches
    exactly with NumPy and builds in one process);
``fast``
    compiled kernels (numba; without it the same numbers come interpreted).

Imports of this module cost nothing: it looks modules up with :func:`importlib.util.find_spec`
and imports none of them.
"""

from __future__ import annotations

import importlib.util
from types import MappingProxyType

__all__ = ["EXTRAS", "MissingExtra", "has", "hint", "missing", "require"]

EXTRAS = MappingProxyType(
    {
        "server": ("fastapi", "uvicorn", "multipart", "orjson"),
        "atlas": ("faiss", "dask", "distributed"),
        "fast": ("numba",),
    }
)
"""Each extra's importable modules (``multipart`` is python-multipart's)."""

_WHAT = MappingProxyType(
    {
        "server": "the workbench",
        "atlas": "this atlas feature",
        "fast": "the compiled kernels",
    }
)


class MissingExtra(ImportError):
    """An optional part of linkwright was used without its extra installed; the message is
    one line that says which extra and how to install it."""


def _present(module: str) -> bool:
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):  # a blocked or half-installed module counts as missing
        return False


def missing(extra: str) -> tuple[str, ...]:
    """The modules of ``extra`` that cannot be imported here.

    >>> missing("no-such-extra")
    Traceback (most recent call last):
    ...
    ValueError: unknown extra 'no-such-extra'; the extras are server, atlas, fast
    """
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}; the extras are {', '.join(EXTRAS)}")
    return tuple(m for m in EXTRAS[extra] if not _present(m))


def has(extra: str) -> bool:
    """Whether every module of ``extra`` can be imported.

    >>> isinstance(has("server"), bool)
    True
    """
    return not missing(extra)


def hint(extra: str, what: str | None = None) -> str:
    """The one-line message for a missing ``extra``.

    >>> hint("server")
    "the workbench needs the server extra: pip install 'linkwright[server]'"
    >>> hint("atlas", "a Dask build")
    "a Dask build needs the atlas extra: pip install 'linkwright[atlas]'"
    """
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}; the extras are {', '.join(EXTRAS)}")
    return f"{what or _WHAT[extra]} needs the {extra} extra: pip install 'linkwright[{extra}]'"


def require(extra: str, what: str | None = None) -> None:
    """Raise :class:`MissingExtra` with :func:`hint` unless ``extra`` is installed.

    >>> require("no-such-extra")
    Traceback (most recent call last):
    ...
    ValueError: unknown extra 'no-such-extra'; the extras are server, atlas, fast
    """
    if missing(extra):
        raise MissingExtra(hint(extra, what))

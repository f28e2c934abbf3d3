"""Mechanism documents as files: reading and writing them (atomically), and the bundled
examples."""

from __future__ import annotations

import json
import os
import tomllib
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from linkwright.files import atomic_path
from linkwright.io.documents import (
    Document,
    DocumentError,
    document_to_dict,
    parse_document,
    unknown_choice,
)
from linkwright.io.toml_writer import dumps_toml

__all__ = ["list_examples", "load_document", "load_example", "save_document"]

# --------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------

_SUFFIXES = (".toml", ".json")


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _SUFFIXES:
        raise DocumentError(
            "document",
            f"unknown file type {path.suffix or '(none)'!r}: expected .toml or .json",
            str(path),
        )
    return suffix


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            # Python's json keeps the last of duplicate keys silently; a document with two
            # values for one field is ambiguous, so refuse it as TOML does.
            raise DocumentError("document", f"duplicate key {key!r}")
        out[key] = value
    return out


def _parse_text(text: str, suffix: str, source: str) -> Any:
    if suffix == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            # The parser's message already ends with "(at line L, column C)".
            raise DocumentError("document", f"invalid TOML: {exc}", source) from None
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        where = f"(at line {exc.lineno}, column {exc.colno})"
        raise DocumentError("document", f"invalid JSON: {exc.msg} {where}", source) from None
    except DocumentError as exc:
        raise exc.with_source(source) from None
    except RecursionError:
        raise DocumentError("document", "invalid JSON: nested too deeply", source) from None


def load_document(path: str | os.PathLike[str]) -> Document:
    """Read and validate a ``.toml`` or ``.json`` mechanism document.

    Parameters
    ----------
    path : str or os.PathLike
        A file ending in ``.toml`` or ``.json``.

    Returns
    -------
    Document
        The document; ``.mechanism`` is its linkage.

    Raises
    ------
    DocumentError
        For an unknown extension, an unreadable or malformed file, or an invalid document.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = save_document(load_example("crank-rocker"), folder / "mine.toml")
    >>> load_document(folder / "mine.toml").mechanism.family
    'fourbar'

    A linkage that cannot assemble is still a valid document (it says so when analysed):

    >>> never = {"format": "linkwright/1",
    ...          "mechanism": {"family": "fourbar", "A0": [0, 0], "B0": [10, 0], "crank": 1,
    ...                        "coupler": 2, "rocker": 3}}
    >>> _ = save_document(never, folder / "never.json")
    >>> float(load_document(folder / "never.json").mechanism.crank)
    1.0
    """
    path = Path(path)
    suffix = _suffix(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise DocumentError("document", f"cannot read: {exc.strerror or exc}", str(path)) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DocumentError(
            "document", f"not UTF-8 text (byte {exc.start} is {data[exc.start]:#04x})", str(path)
        ) from None
    return parse_document(_parse_text(text, suffix, str(path)), source=str(path))


def save_document(doc: Document | Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Write a document as TOML or JSON (by extension), atomically.

    A mapping is validated first, so only valid documents are ever written, in canonical form
    (every default filled in). The file is written to a temporary file in the same directory,
    flushed and fsynced, then renamed over ``path``: a reader never sees a half-written file and
    a crash leaves the old one intact.

    Parameters
    ----------
    doc : Document or mapping
        A document, or its mapping (as a ``.json`` document reads).
    path : str or os.PathLike
        Destination ending in ``.toml`` or ``.json``.

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> save_document(load_example("double-crank"), folder / "a.toml").name
    'a.toml'

    An invalid mapping is refused before anything is written:

    >>> save_document({"mechanism": {"family": "fourbar", "crank": -1}}, folder / "b.toml")
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.io.documents.DocumentError: ...
    >>> (folder / "b.toml").exists()
    False
    """
    path = Path(path)
    suffix = _suffix(path)
    if not isinstance(doc, Document):
        doc = parse_document(doc)
    data = document_to_dict(doc)
    if suffix == ".toml":
        text = dumps_toml(data)
    else:
        text = json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    _atomic_write(path, text.encode("utf-8"))
    return path


def _atomic_write(path: Path, payload: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(payload)


def _examples_dir() -> Any:
    return resources.files("linkwright").joinpath("examples")


def list_examples() -> list[str]:
    """Names of the bundled example documents (without extension), sorted.

    Parameters
    ----------
    None

    Returns
    -------
    list of str
        The names :func:`load_example` takes.

    Examples
    --------
    >>> "crank-rocker" in list_examples()
    True
    """
    return sorted(
        entry.name.removesuffix(".toml")
        for entry in _examples_dir().iterdir()
        if entry.name.endswith(".toml")
    )


def load_example(name: str) -> Document:
    """Load a bundled example by name (``"crank-rocker"`` or ``"crank-rocker.toml"``).

    Parameters
    ----------
    name : str
        One of :func:`list_examples`, with or without its extension.

    Returns
    -------
    Document
        The example; ``.mechanism`` is its linkage.

    Raises
    ------
    DocumentError
        For an unknown name.

    Examples
    --------
    >>> load_example("double-crank").family
    'fourbar'

    An unknown name is refused with the nearest one:

    >>> load_example("crank-rockr")
    Traceback (most recent call last):
    ...
    linkwright.io.documents.DocumentError: example: unknown example 'crank-rockr' (did you \
mean 'crank-rocker'?)
    """
    stem = name.removesuffix(".toml")
    known = tuple(list_examples())
    if stem not in known:
        raise DocumentError("example", unknown_choice("example", stem, known))
    text = _examples_dir().joinpath(f"{stem}.toml").read_text(encoding="utf-8")
    source = f"example {stem}"
    return parse_document(_parse_text(text, ".toml", source), source=source)

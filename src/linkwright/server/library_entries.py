"""What a library entry may be: its name, id, file format and text, and the library's errors.

The checks every request of the workbench's library (:mod:`linkwright.server.library`) makes
before it reaches the database: :func:`check_name` (a name is NFC, stripped, one line, visible,
at most :data:`MAX_NAME` characters, with no control, bidirectional-control or invisible
characters that would make it read as what it is not), :func:`check_id`, :func:`check_format`,
and the reading of an imported text (:func:`decode_text`, :func:`parse_text`: TOML or JSON,
with duplicate JSON keys refused) into a validated document (:func:`validated_document`). The
errors are :class:`LibraryError` (a ``ValueError``; answered 422), :class:`LibraryConflict`
(409) and :class:`LibraryNotFound` (a ``LookupError``; 404).
"""

from __future__ import annotations

import json
import tomllib
import unicodedata
from collections.abc import Mapping
from typing import Any

from linkwright.io import document_to_dict, parse_document
from linkwright.io.documents import dumps_toml
from linkwright.server import limits

__all__ = [
    "FORMATS",
    "MAX_NAME",
    "MAX_TEXT",
    "LibraryConflict",
    "LibraryError",
    "LibraryNotFound",
    "check_format",
    "check_id",
    "check_name",
    "decode_text",
    "dumps_document",
    "file_text",
    "name_from_title",
    "parse_text",
    "sniff_format",
    "validated_document",
]

MAX_NAME = limits.NAME.value
"""Longest entry name, in characters (after stripping): :data:`linkwright.server.limits.NAME`."""

MAX_TEXT = 2_000_000
"""Longest document text :meth:`Library.import_text` reads, in characters."""

FORMATS = ("toml", "json")
"""Document file formats the library imports and exports."""


# SQLite's INTEGER is 64-bit signed; a larger Python int cannot even be bound.
_MAX_ID = 2**63 - 1
# Characters a name may not hold: controls (tabs and newlines included), lone surrogates (they
# cannot be stored as UTF-8) and the Unicode line and paragraph separators (a name is one line).
_REFUSED_CATEGORIES = frozenset({"Cc", "Cs", "Zl", "Zp"})
# Bidirectional controls (marks, embeddings, overrides, isolates): a right-to-left override
# shows "report\u202egpj.exe" as "reportexe.jpg", so a name would read as what it is not.
_BIDI_CONTROLS = frozenset(
    [
        "\u061c",
        "\u200e",
        "\u200f",
        *map(chr, range(0x202A, 0x202F)),
        *map(chr, range(0x2066, 0x206A)),
    ]
)
# Characters that show nothing: formats (zero-width space, joiners), marks with nothing to
# mark, spaces, and the blank fillers of Hangul and Braille. A name of only these looks empty.
_INVISIBLE_CATEGORIES = frozenset({"Cf", "Mn", "Me", "Zs"})
_BLANKS = frozenset("\u115f\u1160\u3164\uffa0\u2800")


class LibraryError(ValueError):
    """A library request is invalid: the message names the field and the problem."""


class LibraryConflict(LibraryError):
    """An entry with that name already exists (the workbench answers 409)."""


class LibraryNotFound(LookupError):
    """No library entry has that id (the workbench answers 404)."""

    def __str__(self) -> str:
        # KeyError-style quoting of the message would read oddly in {"error": ...}.
        return str(self.args[0]) if self.args else "library: no such entry"


# --------------------------------------------------------------------------------------------
# Names, ids, formats, texts
# --------------------------------------------------------------------------------------------


def check_name(name: Any, field: str = "name") -> str:
    """The stored form of a name: NFC (so names that look the same are the same), stripped."""
    if not isinstance(name, str):
        raise LibraryError(f"{field}: must be a string, got {type(name).__name__}")
    text = unicodedata.normalize("NFC", name).strip()
    if not text:
        raise LibraryError(f"{field}: must not be empty")
    if len(text) > MAX_NAME:
        raise LibraryError(f"{field}: {len(text)} characters, at most {MAX_NAME} allowed")
    for ch in text:
        if unicodedata.category(ch) in _REFUSED_CATEGORIES:
            raise LibraryError(
                f"{field}: contains U+{ord(ch):04X} (a control character or line break)"
            )
        if ch in _BIDI_CONTROLS:
            raise LibraryError(
                f"{field}: contains U+{ord(ch):04X} (a bidirectional control, which can make a "
                "name read differently from what it is)"
            )
    if all(_invisible(ch) for ch in text):
        raise LibraryError(f"{field}: shows nothing (only zero-width or format characters)")
    return text


def _invisible(ch: str) -> bool:
    return unicodedata.category(ch) in _INVISIBLE_CATEGORIES or ch in _BLANKS


def name_from_title(title: str | None) -> str:
    """A valid name made from a document title (or ``"untitled"``): controls and line breaks
    become spaces, runs of white space one space, and the result is cut to the length limit."""
    if not title:
        return "untitled"
    cleaned = "".join(
        " " if unicodedata.category(ch) in _REFUSED_CATEGORIES else ch
        for ch in title
        if ch not in _BIDI_CONTROLS
    )
    cleaned = " ".join(unicodedata.normalize("NFC", cleaned).split())[:MAX_NAME].strip()
    if all(_invisible(ch) for ch in cleaned):
        return "untitled"
    return cleaned


def check_id(entry_id: Any) -> int:
    # Only plain decimal digits: int() would also read " 5", "+5", "5_0" and non-ASCII digits.
    if isinstance(entry_id, str) and entry_id.isascii() and entry_id.isdigit():
        value = int(entry_id)
    elif isinstance(entry_id, int) and not isinstance(entry_id, bool):
        value = entry_id
    else:
        raise LibraryNotFound(f"library: no entry with id {entry_id!r}")
    if not 0 < value <= _MAX_ID:
        raise LibraryNotFound(f"library: no entry with id {value}")
    return value


def check_format(fmt: Any, field: str = "format") -> str:
    if not isinstance(fmt, str) or fmt.lower().lstrip(".") not in FORMATS:
        shown = fmt if isinstance(fmt, str) else type(fmt).__name__
        raise LibraryError(f"{field}: expected 'toml' or 'json', got {shown!r}")
    return fmt.lower().lstrip(".")


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            # json keeps the last of two values silently; a document that says two things
            # about one field is refused, as TOML refuses it.
            raise LibraryError(f"duplicate key {key!r}")
        out[key] = value
    return out


def decode_text(text: Any, source: str) -> str:
    """A document's text: bytes read as UTF-8, a byte-order mark dropped, the size checked."""
    if isinstance(text, bytes | bytearray):
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise LibraryError(f"{source}: not UTF-8 text (byte {exc.start})") from None
    if not isinstance(text, str):
        raise LibraryError(f"{source}: must be text, got {type(text).__name__}")
    if len(text) > MAX_TEXT:
        raise LibraryError(f"{source}: {len(text):,} characters, over the {MAX_TEXT:,} allowed")
    return text.removeprefix("\ufeff")


def parse_text(text: str, fmt: str, source: str) -> Any:
    """The mapping a TOML or JSON document text holds; errors start with ``source``."""
    if fmt == "toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise LibraryError(f"{source}: invalid TOML: {exc}") from None
        except RecursionError:  # tomllib recurses once per nested array or inline table
            raise LibraryError(f"{source}: invalid TOML: nested too deeply") from None
        except ValueError:
            raise LibraryError(f"{source}: invalid TOML: a number too long to read") from None
    try:
        return json.loads(text, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        where = f"(at line {exc.lineno}, column {exc.colno})"
        raise LibraryError(f"{source}: invalid JSON: {exc.msg} {where}") from None
    except LibraryError as exc:
        raise LibraryError(f"{source}: invalid JSON: {exc}") from None
    except RecursionError:
        raise LibraryError(f"{source}: invalid JSON: nested too deeply") from None
    except ValueError:  # an integer of more digits than Python converts
        raise LibraryError(f"{source}: invalid JSON: a number too long to read") from None


def sniff_format(text: str) -> str:
    # A TOML document cannot start with "{" (a key or a [table] comes first); JSON's must.
    return "json" if text.lstrip()[:1] == "{" else "toml"


def validated_document(
    document: Any, source: str = "document"
) -> tuple[dict[str, Any], str, str | None]:
    """(canonical mapping, family, title) of a document; LimitError for one over the request
    limits, DocumentError naming the field."""
    limits.check_document(document, source)
    doc = parse_document(document, source=source)
    return document_to_dict(doc), doc.family, doc.title


def file_text(document: Mapping[str, Any], fmt: str) -> str:
    if fmt == "toml":
        return dumps_toml(document)
    return json.dumps(document, indent=2, ensure_ascii=False, allow_nan=False) + "\n"


def dumps_document(document: Mapping[str, Any]) -> str:
    return json.dumps(document, ensure_ascii=False, allow_nan=False, separators=(",", ":"))

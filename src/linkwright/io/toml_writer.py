"""A small TOML writer for mechanism documents (:func:`dumps_toml`).

The standard library reads TOML but does not write it; documents are a few scalars and one
table of numbers, points and inline tables, so a writer of that much keeps points and (u, v)
pairs on one line each.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

__all__ = ["dumps_toml"]

# --------------------------------------------------------------------------------------------
# TOML writing: documents are a few scalars and one table of numbers, points and inline tables
# (and, for a composed linkage, an array of joint tables), so a small writer covers them and
# keeps points and (u, v) pairs on one line each.
# --------------------------------------------------------------------------------------------

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {
    '"': '\\"',
    "\\": "\\\\",
    "\b": "\\b",
    "\t": "\\t",
    "\n": "\\n",
    "\f": "\\f",
    "\r": "\\r",
}


def _toml_string(s: str) -> str:
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"cannot write the non-finite number {value!r}")
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{ " + items + " }" if items else "{}"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table_list(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, Mapping) for v in value)


def dumps_toml(data: Mapping[str, Any]) -> str:
    """TOML text for a document mapping: scalars first, then one ``[table]`` per mapping.

    Inside a table, a non-empty list of mappings is written last, as an array of tables
    (``[[table.key]]``, one per item): a linkage's joints read one joint per block.

    >>> print(dumps_toml({"format": "linkwright/1", "mechanism": {"A0": [0.0, 1.0]}}))
    format = "linkwright/1"
    <BLANKLINE>
    [mechanism]
    A0 = [0.0, 1.0]
    <BLANKLINE>
    >>> print(dumps_toml({"mechanism": {"family": "linkage", "joints": [{"name": "O"}]}}))
    [mechanism]
    family = "linkage"
    <BLANKLINE>
    [[mechanism.joints]]
    name = "O"
    <BLANKLINE>
    """
    lines = [
        f"{_toml_key(k)} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, Mapping)
    ]
    for key, table in data.items():
        if isinstance(table, Mapping):
            lines += ["", f"[{_toml_key(key)}]"]
            lines += [
                f"{_toml_key(k)} = {_toml_value(v)}"
                for k, v in table.items()
                if not _is_table_list(v)
            ]
            for k, items in table.items():
                if _is_table_list(items):
                    for item in items:
                        lines += ["", f"[[{_toml_key(key)}.{_toml_key(k)}]]"]
                        lines += [f"{_toml_key(n)} = {_toml_value(v)}" for n, v in item.items()]
    return "\n".join(lines).lstrip("\n") + "\n"


# --------------------------------------------------------------------------------------------
# Bundled examples
# --------------------------------------------------------------------------------------------

r"""How deeply a JSON body nests, read from its bytes in one linear pass.

The workbench refuses a body nested deeper than :data:`~linkwright.server.limits.JSON_DEPTH`
before any parser sees it (Python's parser recurses once per level). The measure must itself
cost no more than reading the body: a regular expression that skips strings backtracks on a run
of unterminated escaped quotes (33 ``[`` then 64 KB of ``\"`` took 35 s, in the event loop), so
:func:`json_depth` finds the strings with array arithmetic instead. Each step is a whole-array
NumPy operation on the body's bytes (or on its quotes, backslashes and brackets), so a 2 MB body
takes milliseconds whatever it holds.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["json_depth"]

_QUOTE, _BACKSLASH = ord('"'), ord("\\")
_STEP = np.zeros(256, dtype=np.int8)
_STEP[[ord("["), ord("{")]] = 1
_STEP[[ord("]"), ord("}")]] = -1


def _escaped(codes: np.ndarray, quotes: np.ndarray) -> NDArray[np.bool_]:
    """Whether each quote at the positions ``quotes`` follows an odd run of backslashes."""
    slashes = np.flatnonzero(codes == _BACKSLASH)
    if slashes.size == 0:
        return np.zeros(quotes.size, dtype=bool)
    # Runs of consecutive backslashes: where each starts and ends (the end inclusive).
    breaks = np.flatnonzero(np.diff(slashes) != 1)
    starts = slashes[np.concatenate(([0], breaks + 1))]
    ends = slashes[np.concatenate((breaks, [slashes.size - 1]))]
    # The run ending just before a quote, if there is one.
    k = np.searchsorted(ends, quotes - 1)
    found = k < ends.size
    k = np.minimum(k, ends.size - 1)
    after_run = found & (ends[k] == quotes - 1)
    odd: NDArray[np.bool_] = after_run & ((ends[k] - starts[k] + 1) % 2 == 1)
    return odd


def json_depth(body: bytes) -> int:
    r"""How deeply a JSON text nests its arrays and objects (0 for a scalar), read from the
    bytes without parsing them (the parser is what a deep body would overflow); brackets inside
    strings do not count. Linear in the body's length, whatever its bytes.

    Up to the first byte a JSON parser would refuse, the count is the depth the parser reaches
    there: strings open and close at quotes not escaped by an odd run of backslashes, as in
    JSON. Nothing after a refused byte is parsed, so a count that differs there cannot let a
    parser recurse deeper than counted.

    >>> json_depth(b'{"a": [1, {"b": "[[["}]}'), json_depth(b"[" * 40), json_depth(b"7")
    (3, 40, 0)
    >>> json_depth(rb'[["\\"], "\"[["]')
    2
    """
    codes = np.frombuffer(body, dtype=np.uint8)
    steps = _STEP[codes]
    brackets = np.flatnonzero(steps)
    if brackets.size == 0:
        return 0
    quotes = np.flatnonzero(codes == _QUOTE)
    if quotes.size:
        quotes = quotes[~_escaped(codes, quotes)]
        # A bracket is inside a string when an odd number of quotes come before it.
        brackets = brackets[np.searchsorted(quotes, brackets) % 2 == 0]
    if brackets.size == 0:
        return 0
    return max(0, int(np.cumsum(steps[brackets], dtype=np.int64).max()))

"""Moved to :mod:`linkwright.cli.budget`; this name stays so that older imports keep working."""

from linkwright.cli.budget import (
    CHUNK_BYTES,
    check_animation,
    check_drawing,
    check_followed,
    check_grid,
    check_trace,
    solve_chunk,
    stream_solve,
)

__all__ = [
    "CHUNK_BYTES",
    "check_animation",
    "check_drawing",
    "check_followed",
    "check_grid",
    "check_trace",
    "solve_chunk",
    "stream_solve",
]

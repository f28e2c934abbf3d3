"""What the synthesis and atlas tests share: the command line run in-process, the distance from
points to a traced closed curve, and the few-examples settings of a search that takes seconds."""

from __future__ import annotations

import contextlib
import io

import numpy as np
from hypothesis import HealthCheck, Phase, settings

from linkwright.cli import main

FAST = settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    phases=[Phase.explicit, Phase.reuse, Phase.generate],
    suppress_health_check=[HealthCheck.filter_too_much],
)
"""Few examples, no shrinking (a fit takes seconds; the seed alone names the case), and the same
examples on every run: a global search can miss on a rare hard case, and a test that fails once
in a hundred runs says nothing useful."""


def run_cli(*args: str) -> tuple[int, str, str]:
    """``linkwright ARGS`` in this process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def polyline_distance(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Distance from each point to the closed polyline ``curve`` (projection on its segments)."""
    a, b = curve, np.roll(curve, -1, axis=0)
    d = b - a
    rel = points[:, None, :] - a[None]
    t = np.clip(np.sum(rel * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300), 0.0, 1.0)
    gap = rel - t[..., None] * d
    return np.sqrt(np.min(np.sum(gap * gap, -1), axis=1))

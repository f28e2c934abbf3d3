"""Where compiled plans' kernels are kept and how they run: the disk cache and the threads.

A generated source goes to :func:`cache_dir` under a name taken from its hash, written
atomically (processes race for it), and is compiled with numba's ``cache=True``, so a second
process loads the machine code instead of compiling it (:func:`load_kernel`). A large batch
is cut into ranges of mechanisms run on :func:`threads` threads (:func:`run_ranges`).

Its own room (split from :mod:`linkwright.engine.compile`): files, modules and threads, apart
from the generator (:mod:`~linkwright.engine.compile_source`) and the plans that use them.
"""

from __future__ import annotations

import hashlib
import importlib.util
import itertools
import os
import sys
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SERIAL_CELLS", "cache_dir", "load_kernel", "run_ranges", "threads"]


def cache_dir() -> Path:
    """Where generated kernels and numba's machine code for them are kept."""
    root = os.environ.get("LINKWRIGHT_CACHE")
    if root:
        return Path(root) / "kernels"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "linkwright" / "kernels"


_LOCK = threading.Lock()
_LOADED: dict[str, Any] = {}


def _write(directory: Path, name: str, source: str) -> Path:
    """The source at ``directory/name``, written atomically (processes race for it)."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    if path.exists() and path.read_text() == source:
        return path
    fd, tmp = tempfile.mkstemp(dir=directory, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(source)
    os.replace(tmp, path)
    return path


def load_kernel(source: str) -> Any:
    """The compiled ``kernel`` of a generated source, from the disk cache where it is there."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:24]
    with _LOCK:
        if digest in _LOADED:
            return _LOADED[digest]
        name = f"lw_{digest}.py"
        try:
            path = _write(cache_dir(), name, source)
        except OSError:
            # An unwritable cache: compile anyway, from a private directory (no reuse).
            path = _write(Path(tempfile.mkdtemp(prefix="linkwright-kernels-")), name, source)
        module_name = f"linkwright_kernels.lw_{digest}"
        spec = importlib.util.spec_from_file_location(module_name, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module
        spec.loader.exec_module(module)
        _LOADED[digest] = module.kernel
        return module.kernel


# Below this many mechanism-samples a batch runs on the calling thread: handing ranges to
# threads costs tens of microseconds, what about 10^4 samples of a six-bar take.
SERIAL_CELLS = 2**14


_POOL: ThreadPoolExecutor | None = None


def threads() -> int:
    """The threads a large batch runs on: ``NUMBA_NUM_THREADS`` where set, else the cores."""
    value = os.environ.get("NUMBA_NUM_THREADS")
    return max(1, int(value)) if value and value.isdigit() else (os.cpu_count() or 1)


def run_ranges(kernel: Any, n: int, per_mechanism: int, args: tuple[Any, ...]) -> None:
    """``kernel(lo, hi, *args)`` over [0, n), split into ranges run on threads when large."""
    global _POOL
    workers = min(threads(), n)
    if workers <= 1 or n * per_mechanism < SERIAL_CELLS:
        kernel(0, n, *args)
        return
    if _POOL is None or _POOL._max_workers < workers:
        _POOL = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="linkwright-kernel")
    # A few ranges per thread even out threads slowed by other work on the machine.
    parts = min(n, 4 * workers)
    bounds = np.linspace(0, n, parts + 1).astype(int)
    futures = [
        _POOL.submit(kernel, int(lo), int(hi), *args)
        for lo, hi in itertools.pairwise(bounds)
        if hi > lo
    ]
    for f in futures:
        f.result()

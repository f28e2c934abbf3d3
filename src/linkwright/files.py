"""Files written whole or not at all: the one atomic-write recipe every writer uses.

A killed or failing writer must never leave a half-written picture, drawing, document or atlas
shard where the user expects a complete one (nothing lost on save). The recipe: write to a
unique hidden file beside the target (same folder, so the rename cannot cross file systems;
same suffix, so writers that go by it, ffmpeg or ezdxf, accept it), flush it to disk, rename it
over the target (atomic on POSIX), then flush the folder so the rename survives a crash.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path"]


@contextmanager
def atomic_path(path: str | os.PathLike[str], *, prefix: str = ".") -> Iterator[Path]:
    """A temporary path to write ``path``'s content to; renamed over ``path`` on success.

    Missing parent folders are created. An existing file keeps its permissions. On any
    failure inside the block (KeyboardInterrupt included) the temporary file is removed and
    ``path`` is left as it was. ``prefix`` starts the temporary file's name (hidden by default),
    so a folder's leftovers from a SIGKILL can be found and removed.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_path(folder / "a.txt") as tmp:
    ...     _ = tmp.write_text("whole")
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('whole', ['a.txt'])
    >>> try:
    ...     with atomic_path(folder / "a.txt") as tmp:
    ...         _ = tmp.write_text("half")
    ...         raise RuntimeError("killed")
    ... except RuntimeError:
    ...     pass
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('whole', ['a.txt'])
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{prefix}{path.stem}.{secrets.token_hex(6)}.part{path.suffix}")
    try:
        yield tmp
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        if path.exists():
            os.chmod(tmp, path.stat().st_mode & 0o7777)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    try:  # not every platform lets a folder be opened
        fd = os.open(path.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)

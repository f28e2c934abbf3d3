"""Nothing lost: a process killed mid-save leaves the previous version whole.

Document saves (and every file the command line writes) go through one recipe,
:func:`linkwright.files.atomic_path`: write a temporary file beside the target, fsync it,
rename it over the target, fsync the folder. These tests kill real processes with SIGKILL
while they save, over and over, and check that what is on disk is always one whole version.
The workbench library's SQLite transactions have their own kill test
(``tests/test_server_library_store.py``); atlas shards are checked by their digests on resume, and
a shard damaged after its digest was written is rebuilt, not trusted.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from linkwright.atlas import build
from linkwright.atlas.store import finished_shards, shard_name
from linkwright.io import load_document

pytestmark = pytest.mark.skipif(os.name != "posix", reason="SIGKILL is POSIX")

# A title of a few megabytes makes each save take long enough (write, fsync, rename) for a
# kill to land inside it rather than between two saves.
SAVER = textwrap.dedent(
    """
    import sys
    from linkwright.io import load_example, save_document
    from linkwright.io.documents import document_to_dict

    path, size = sys.argv[1], int(sys.argv[2])
    doc = document_to_dict(load_example("crank-rocker"))
    k = 0
    while True:
        k += 1
        doc["title"] = f"version {k} " + "x" * size
        doc["mechanism"]["crank"] = 1.0 + (k % 2) * 0.25
        save_document(doc, path)
        print(k, flush=True)
    """
)


def _kill_while_saving(path: Path, size: int, rng: random.Random) -> int:
    """Start a saver, let it save at least once, kill it at a random moment; the last version
    it reported saved."""
    proc = subprocess.Popen(
        [sys.executable, "-c", SAVER, str(path), str(size)],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
    )
    try:
        first = proc.stdout.readline()
        assert first.strip(), "the saver never finished a save"
        time.sleep(rng.uniform(0.0, 0.25))
        proc.send_signal(signal.SIGKILL)
        rest = proc.communicate(timeout=30)[0]
    finally:
        proc.kill()
    reported = [int(line) for line in (first + rest).split()]
    return max(reported)


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_a_document_save_killed_at_random_leaves_a_whole_version(tmp_path, suffix):
    path = tmp_path / f"doc{suffix}"
    size = 4_000_000
    rng = random.Random(10)
    for _ in range(4):
        last = _kill_while_saving(path, size, rng)
        doc = load_document(path)  # parses: never half a file
        version = int(doc.title.split()[1])
        # The file is the last save the process reported, or the one it was in the middle of
        # renaming when it died; never older, never a mix of two.
        assert version in (last, last + 1)
        assert doc.title == f"version {version} " + "x" * size
        assert doc.raw["mechanism"]["crank"] == 1.0 + (version % 2) * 0.25
    # The killed saves' temporary files are hidden beside the document, never in its place.
    others = [p.name for p in tmp_path.iterdir() if p != path]
    assert all(name.startswith(".doc.") and ".part" in name for name in others), others


def test_a_picture_written_by_a_killed_command_is_whole_or_absent(tmp_path):
    """`linkwright plot` killed at random: the PNG is either the previous whole one or new."""
    out = tmp_path / "linkage.png"
    argv = [sys.executable, "-m", "linkwright", "plot", "crank-rocker", "--out", str(out),
            "--quiet"]  # fmt: skip
    subprocess.run(argv, check=True, capture_output=True, timeout=120)
    whole = out.read_bytes()
    rng = random.Random(11)
    for _ in range(3):
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(rng.uniform(0.3, 1.5))
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        data = out.read_bytes()
        assert data.startswith(b"\x89PNG") and data.endswith(b"IEND\xaeB`\x82")
        assert len(data) == len(whole)


def test_an_atlas_shard_damaged_after_its_digest_is_rebuilt(tmp_path):
    """Resume trusts a shard only if its bytes still match the digest written after it: one
    with a flipped byte and one cut short are set aside and rebuilt, bit for bit."""
    out = tmp_path / "atlas"
    first = build("fourbar", 6_000, out, shard_size=2_000, workers=0, seed=3)
    sizes = [s["count"] for s in first["shards"]]
    shard = out / shard_name(1)
    data = bytearray(shard.read_bytes())
    data[-7] ^= 0xFF  # one flipped byte in the curve data
    shard.write_bytes(bytes(data))
    (out / shard_name(2)).write_bytes(b"half a shard")
    # As after a kill: no manifest yet, so the build resumes rather than reporting it done.
    (out / "atlas.json").unlink()
    assert set(finished_shards(out, sizes)) == {0}  # the damaged ones are set aside
    again = build("fourbar", 6_000, out, shard_size=2_000, workers=0, seed=3)
    assert [s["sha256"] for s in again["shards"]] == [s["sha256"] for s in first["shards"]]
    assert again["build"]["shards_resumed"] == 1
    assert again["build"]["curves_computed"] == 4_000

"""Two builds never write one atlas directory, and an atlas whose files do not belong together is
named as such by `atlas info` and `atlas query` (issue 20, item 6). Real processes throughout:
the lock is an flock, which only another process (or a killed one) can test honestly."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from linkwright.atlas import AtlasBuildError, AtlasError, build, open_atlas
from linkwright.atlas.store import build_lock, lock_holder
from linkwright.cli import main

ROOT = Path(__file__).resolve().parents[1]
CURVE = ROOT / "src" / "linkwright" / "examples" / "drawn-curve.csv"

HOLD = """
import sys, time
from pathlib import Path
from linkwright.atlas.store import build_lock
with build_lock(Path(sys.argv[1])):
    print("held", flush=True)
    time.sleep(120)
"""


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "linkwright", *args], capture_output=True, text=True, timeout=300
    )


def _build_args(out: Path, seed: int, count: int = 3000) -> list[str]:
    return ["atlas", "build", "--family", "fourbar", "--count", str(count), "--shard-size",
            str(count // 6), "--workers", "0", "--seed", str(seed), "--out", str(out),
            "--quiet"]  # fmt: skip


def _holder(directory: Path) -> subprocess.Popen:
    """A process holding the directory's build lock until it is killed."""
    directory.mkdir(parents=True, exist_ok=True)
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(directory)], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None and proc.stdout.readline().strip() == "held"
    return proc


def _one_error_line(stderr: str) -> str:
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr
    return lines[0]


def test_a_second_build_is_refused_at_once_naming_the_holder(tmp_path):
    out = tmp_path / "held"
    holder = _holder(out)
    try:
        assert lock_holder(out) == holder.pid
        done = _cli(*_build_args(out, seed=0))
        assert done.returncode == 2
        line = _one_error_line(done.stderr)
        assert f"pid {holder.pid}" in line and "another atlas build" in line
        # Refused before it touched anything: the holder's directory is as it was.
        assert sorted(p.name for p in out.iterdir()) == ["build.lock"]
        with pytest.raises(AtlasBuildError, match=f"pid {holder.pid}"):
            build("fourbar", 1000, out, workers=0)
        with pytest.raises(AtlasError, match=f"build \\(pid {holder.pid}\\) is writing it"):
            open_atlas(out)
    finally:
        holder.kill()
        holder.wait()


def test_a_lock_left_by_a_killed_build_does_not_block(tmp_path):
    out = tmp_path / "killed"
    holder = _holder(out)
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    # The pid it wrote is still in the file, but the kernel let go of the lock with the process.
    assert (out / "build.lock").read_text().strip() == str(holder.pid)
    assert lock_holder(out) is None
    done = _cli(*_build_args(out, seed=0))
    assert done.returncode == 0, done.stderr
    assert open_atlas(out, hashes=True).spec.seed == 0
    # A finished build lets go too, and leaves no pid behind.
    assert (out / "build.lock").read_text() == "" and lock_holder(out) is None
    with build_lock(out):
        pass


@pytest.mark.parametrize("round_", range(2))
def test_two_builds_released_together_leave_one_whole_atlas(tmp_path, round_):
    out = tmp_path / "race"
    procs = {
        seed: subprocess.Popen(
            [sys.executable, "-m", "linkwright", *_build_args(out, seed, count=60_000)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for seed in (0, 1)
    }
    results = {seed: (p.wait(timeout=300), p.stderr.read()) for seed, p in procs.items()}
    for p in procs.values():
        p.stdout.close()
        p.stderr.close()
    winners = [seed for seed, (status, _) in results.items() if status == 0]
    assert len(winners) == 1, results
    (winner,) = winners
    loser = 1 - winner
    status, err = results[loser]
    line = _one_error_line(err)
    assert status == 2
    # Refused by the lock while the winner ran, or, had it come after, by the finished atlas.
    assert f"pid {procs[winner].pid}" in line or "holds a different atlas" in line, line
    atlas = open_atlas(out, hashes=True)
    assert atlas.spec.seed == winner
    assert json.loads((out / "build.json").read_text())["seed"] == winner


@pytest.fixture(scope="module")
def two_atlases(tmp_path_factory) -> tuple[Path, Path]:
    base = tmp_path_factory.mktemp("atlases")
    for seed in (0, 1):
        build("fourbar", 3000, base / f"seed{seed}", seed=seed, shard_size=1000, workers=0)
    return base / "seed0", base / "seed1"


def _damaged(two_atlases, tmp_path, how) -> Path:
    seed0, seed1 = two_atlases
    out = tmp_path / "damaged"
    shutil.copytree(seed0, out)
    how(out, seed1)
    return out


def _set_seed(out: Path, _: Path) -> None:
    spec = json.loads((out / "build.json").read_text())
    (out / "build.json").write_text(json.dumps({**spec, "seed": 1}))


def _other_shard_and_digest(out: Path, other: Path) -> None:
    for name in ("shard-00001.npy", "shard-00001.sha256"):
        shutil.copy(other / name, out / name)


def _other_shard_only(out: Path, other: Path) -> None:
    shutil.copy(other / "shard-00001.npy", out / "shard-00001.npy")


def _stray_shard(out: Path, other: Path) -> None:
    shutil.copy(other / "shard-00002.npy", out / "shard-00003.npy")


def _missing_shard(out: Path, _: Path) -> None:
    (out / "shard-00002.npy").unlink()


def _other_index(out: Path, other: Path) -> None:
    shutil.copy(other / "index.faiss", out / "index.faiss")  # the same size: only a hash tells


def _grown_index(out: Path, _: Path) -> None:
    with open(out / "index.faiss", "ab") as f:
        f.write(b"\0")


@pytest.mark.parametrize(
    ("how", "named", "quick"),
    [
        (_set_seed, "seed 0 in atlas.json but 1 in build.json", True),
        (_other_shard_and_digest, "shard-00001.npy is not the shard atlas.json lists", True),
        (_other_shard_only, "shard-00001.npy does not match its SHA-256", False),
        (_stray_shard, "shard-00003.npy is not a shard of this atlas", True),
        (_missing_shard, "shard-00002.npy, listed in atlas.json, is missing", True),
        (_other_index, "index.faiss does not match its SHA-256", False),
        (_grown_index, "index.faiss is not the index atlas.json lists", True),
    ],
)
def test_info_and_query_name_files_that_do_not_belong_together(
    two_atlases, tmp_path, capsys, how, named, quick
):
    out = _damaged(two_atlases, tmp_path, how)
    assert main(["atlas", "info", str(out)]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert named in line, line
    query = ["atlas", "query", str(out), "--points", str(CURVE), "--quiet"]
    if quick:  # found from the manifest, the digest files and the headers alone
        assert main(query) == 2
        assert named in _one_error_line(capsys.readouterr().err)
    else:  # only re-hashing the shard finds a swap that kept the digest file
        assert main(["atlas", "info", "--quick", str(out)]) == 0
        capsys.readouterr()


def test_an_undamaged_atlas_passes_every_check(two_atlases, capsys):
    seed0, _ = two_atlases
    assert main(["atlas", "info", str(seed0)]) == 0
    assert "3000 fourbar curves (seed 0)" in capsys.readouterr().out
    manifest = json.loads((seed0 / "atlas.json").read_text())
    assert manifest["index"]["bytes"] == (seed0 / "index.faiss").stat().st_size


def test_the_built_in_atlas_waits_for_a_build_in_progress(tmp_path, monkeypatch):
    import threading

    from linkwright.atlas import atlas as atlas_module
    from linkwright.atlas import default_atlas

    monkeypatch.setenv("LINKWRIGHT_DATA", str(tmp_path))
    monkeypatch.setitem(atlas_module.DEFAULT_COUNTS, "fourbar", 2000)
    root = tmp_path / "atlas" / "fourbar-2000-seed0-v1"
    holder = _holder(root)  # another query, say, building it
    threading.Timer(1.0, holder.kill).start()
    try:
        atlas = default_atlas("fourbar")  # waits for the lock, then builds: no error
    finally:
        holder.kill()
        holder.wait()
    assert atlas.count == 2000 and lock_holder(root) is None

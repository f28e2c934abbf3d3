"""The command line's cost checks (issue 20, item 3): inputs inside the documented ranges that
once exhausted the machine's memory or ran for minutes are refused at once, with one line
naming what to lower; large answers are streamed, in bounded memory.

Every hostile command runs in its own process under an address-space limit (RLIMIT_AS) and a
timeout, so a regression fails the test, not the machine. The process reports its own peak
resident memory, which the streaming tests compare between sizes.
"""

from __future__ import annotations

import io
import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import linkwright
from linkwright import cli
from linkwright.cli import shared as cli_shared
from linkwright.cli.budget import stream_solve
from linkwright.cli.solve import _solve_text
from linkwright.io import document_to_dict, load_example
from linkwright.io.results import solve_document

CAP_BYTES = 2_500_000_000
"""The address space each command may use: a hostile one that slipped through fails with a
MemoryError inside it instead of taking the machine."""
TIMEOUT_S = 240
QUICK_RSS = 400 * 2**20
"""A refusal computes nothing: its process stays near the interpreter's own size."""

# The peak is the process's own high-water mark (VmHWM, kilobytes): ru_maxrss survives the
# fork and exec from the test's worker, so it starts at the worker's size, however large.
DRIVER = """
import resource, sys
from linkwright.cli import main
try:
    status = main(sys.argv[1:])
finally:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    try:
        with open("/proc/self/status") as status_file:
            for line in status_file:
                if line.startswith("VmHWM:"):
                    peak = int(line.split()[1])
    except OSError:
        pass
    sys.stderr.write(f"\\nMAXRSS {peak}\\n")
sys.exit(status)
"""


def run_capped(
    *args: str, stdout: Path | None = None, cap: int = CAP_BYTES
) -> tuple[int, str, list[str], int]:
    """(status, stdout, the stderr lines, peak resident bytes) of ``linkwright ARGS`` run in a
    process limited to ``cap`` bytes of address space."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))

    # One BLAS thread: its per-thread buffers would otherwise count against the cap.
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env.pop("LINKWRIGHT_TRACEBACK", None)
    sink = open(stdout, "w", encoding="utf-8") if stdout is not None else subprocess.PIPE  # noqa: SIM115
    try:
        proc = subprocess.run(
            [sys.executable, "-c", DRIVER, *args],
            stdout=sink,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            preexec_fn=limit,
            timeout=TIMEOUT_S,
            check=False,
        )
    finally:
        if stdout is not None:
            sink.close()
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    rss = [ln for ln in lines if ln.startswith("MAXRSS ")]
    peak = int(rss[-1].split()[1]) * 1024 if rss else 0  # Linux reports kilobytes
    lines = [ln for ln in lines if not ln.startswith("MAXRSS ")]
    return proc.returncode, proc.stdout or "", lines, peak


def refused(args: tuple[str, ...], *hints: str) -> str:
    status, _, err, peak = run_capped(*args)
    assert status == 2, (status, err)
    assert len(err) == 1 and err[0].startswith("error: too costly"), err
    for hint in hints:
        assert hint in err[0], err[0]
    assert peak < QUICK_RSS, peak
    return err[0]


def _document(tmp_path: Path, name: str, doc: dict) -> str:
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)


def geared(tmp_path: Path, ratio: float) -> str:
    doc = document_to_dict(load_example("geared-fivebar"))
    doc["mechanism"]["ratio"] = ratio
    return _document(tmp_path, f"geared-{ratio:g}.json", doc)


def chain(tmp_path: Path, dyads: int) -> str:
    """A composed linkage of ``dyads`` dyads on one crank, every one of whose 2^dyads branch
    combinations assembles."""
    joints = [
        {"name": "O", "type": "fixed", "at": [0.0, 0.0]},
        {"name": "B", "type": "fixed", "at": [-38.0, -7.8]},
        {"name": "A", "type": "crank", "pivot": "O", "length": 15.0},
    ]
    for i in range(1, dyads + 1):
        joints.append(
            {"name": f"D{i}", "type": "rrr", "p1": "A", "r1": 50.0 + 0.01 * i, "p2": "B",
             "r2": 41.5, "assembly": 1}
        )  # fmt: skip
    doc = {
        "format": "linkwright/1",
        "mechanism": {"family": "linkage", "space": "plane", "traced": ["D1"], "joints": joints},
    }
    return _document(tmp_path, f"chain-{dyads}.json", doc)


# --------------------------------------------------------------------------------------------
# Refused at once, naming what to lower
# --------------------------------------------------------------------------------------------


def test_curve_of_a_crank_geared_at_1000_along_the_path_is_refused(tmp_path) -> None:
    # It once took the whole 24 GB machine.
    refused(("curve", geared(tmp_path, 1000.0), "--spacing", "path"), "lower the ratio to 64")


def test_curve_along_the_path_at_a_million_points_is_refused(tmp_path) -> None:
    line = refused(
        ("curve", geared(tmp_path, 64.0), "--spacing", "path", "-n", "1000000"), "lower --points"
    )
    fits = int(line.rsplit("lower --points to ", 1)[1].split()[0].replace(",", ""))
    assert 10_000 <= fits < 1_000_000


def test_solve_all_on_sixteen_dyads_is_refused(tmp_path) -> None:
    # 2^16 combinations took 147 s and 1 GB for one input.
    refused(("solve", chain(tmp_path, 16), "--all", "-i", "0"), "65,536", "leave out --all")


def test_solve_all_on_twelve_dyads_at_many_inputs_is_refused(tmp_path) -> None:
    refused(
        ("solve", chain(tmp_path, 12), "--all", "-i", "0:359:1"),
        "4,096 configurations",
        "lower the number of inputs",
    )


def test_plot_of_many_circuits_at_many_samples_is_refused(tmp_path) -> None:
    out = tmp_path / "p.png"
    refused(("plot", geared(tmp_path, 64.0), "--samples", "100000", "--out", str(out)), "--samples")
    assert not out.exists()


@pytest.mark.parametrize(("suffix", "hint"), [(".gif", "write an .mp4"), (".mp4", "--dpi")])
def test_animations_at_their_maxima_are_refused(tmp_path, suffix, hint) -> None:
    out = tmp_path / f"a{suffix}"
    args = ("animate", "crank-rocker", "--out", str(out), "--frames", "5000", "--dpi", "600")
    refused(args, "5,000 frames at 600 dpi", "lower --frames", hint)
    assert not out.exists()


@pytest.mark.parametrize(
    ("family", "fix", "free", "targets"),
    [
        (
            "spherical-fourbar",
            "crank=80,frame=10",
            "coupler,rocker",
            ("max_Ke=1.47", "max_Kp=1.49"),
        ),
        ("fourbar", "crank=1", "coupler,rocker,frame", ("max_Kw=1.25", "delta=0.48", "swing=40")),
    ],
)
def test_synth_targets_at_the_largest_grid_is_refused(family, fix, free, targets) -> None:
    args = ["synth", "targets", "--family", family, "--fix", fix, "--free", free, "--grid", "400"]
    for target in targets:
        args += ["--target", target]
    refused(tuple(args), "400^", "lower --grid")


@pytest.mark.parametrize(
    ("options", "hint"),
    [
        (("--count", "1000000000000"), "lower --count"),
        (("--count", "1000", "--samples", "100000"), "lower --samples"),
        (("--count", "100000000", "--samples", "1000"), "lower --count"),
        (("--count", "10000000", "--shard-size", "10000000"), "lower --shard-size"),
    ],
)
def test_atlas_builds_beyond_their_budgets_are_refused(tmp_path, options, hint) -> None:
    out = tmp_path / "atlas"
    refused(("atlas", "build", "--family", "fourbar", "--out", str(out), *options), hint)
    assert not out.exists()


# --------------------------------------------------------------------------------------------
# Large answers: computed in bounded memory
# --------------------------------------------------------------------------------------------


def test_solve_all_streams_its_rows_in_bounded_memory(tmp_path) -> None:
    # The bundled spherical Stephenson III at 10^6 inputs once held ~14 GB; its rows are now
    # written a chunk at a time, so four times the inputs take no more memory.
    peaks = {}
    for n in (10_000, 40_000):
        out = tmp_path / f"solve-{n}.json"
        step = f"{360 / n:.10f}"
        args = ("solve", "paper001-stephenson3", "--all", "-i", f"0:{359.9999}:{step}", "--json")
        status, _, err, peaks[n] = run_capped(*args, stdout=out)
        assert status == 0 and not err, err
        text = out.read_text(encoding="utf-8")
        assert text.startswith('{"family": "spherical-stephenson3"') and text.endswith("}\n")
        assert text.count('"input_deg": ') == n
    assert peaks[40_000] < peaks[10_000] + 64 * 2**20, peaks
    whole = json.loads((tmp_path / "solve-10000.json").read_text(encoding="utf-8"))
    assert len(whole["samples"]) == 10_000 and whole["max_configurations"] == 4


def _drawn(path: Path, n: int) -> None:
    """The bundled hand-drawn curve, closed and interpolated to ``n`` points."""
    rows = cli_shared.read_points(Path(linkwright.__file__).parent / "examples" / "drawn-curve.csv")
    p = np.vstack([rows, rows[:1]])
    t = np.linspace(0.0, len(p) - 1.0, n + 1)[:-1]
    q = np.column_stack([np.interp(t, np.arange(len(p)), p[:, i]) for i in range(2)])
    np.savetxt(path, q, delimiter=",")


def test_atlas_query_refines_twenty_thousand_points_in_bounded_memory(tmp_path) -> None:
    # 20,000+ points once took 3 to 18.6 GiB: the refinement now fits 500 of them, evenly
    # spaced, and measures the distance to all.
    atlas = tmp_path / "atlas"
    status, _, err, _ = run_capped(
        "atlas", "build", "--family", "fourbar", "--count", "2000", "--out", str(atlas),
        "--workers", "0", "--quiet",
    )  # fmt: skip
    assert status == 0, err
    points = tmp_path / "drawn.csv"
    _drawn(points, 20_000)
    status, out, err, peak = run_capped(
        "atlas", "query", str(atlas), "--points", str(points), "--refine", "--budget", "1",
        "--top", "3", "--json", "--quiet",
    )  # fmt: skip
    assert status == 0 and not err, err
    report = json.loads(out)
    assert report["points"] == 20_000 and report["matches"]
    assert peak < 1_000_000_000, peak


# --------------------------------------------------------------------------------------------
# Streaming writes what one answer would
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "all_", "derivatives"),
    [
        ("crank-rocker", False, False),
        ("crank-rocker", True, True),
        ("jansen-leg", True, False),
        ("paper001-stephenson3", True, False),
    ],
)
@pytest.mark.parametrize("chunk", [1, 7, 10_000])
def test_streamed_solve_is_the_whole_answer(name, all_, derivatives, chunk) -> None:
    doc = cli_shared.load_file(name)
    degrees = cli.parse_inputs("0:359:13")
    whole = solve_document(doc, degrees, all_configurations=all_, derivatives=derivatives)
    for as_json in (False, True):
        buffer = io.StringIO()
        stream_solve(
            degrees,
            chunk,
            lambda part: solve_document(
                doc, part, all_configurations=all_, derivatives=derivatives
            ),
            lambda result: _solve_text(doc, result, derivatives),
            cli_shared.to_json_ready,
            buffer,
            as_json=as_json,
        )
        if as_json:
            assert json.loads(buffer.getvalue()) == json.loads(cli_shared.dump_json(whole))
        else:
            assert buffer.getvalue() == _solve_text(doc, whole, derivatives)


def test_bundled_examples_still_run_at_the_defaults(capsys) -> None:
    for name in ("geared-fivebar", "jansen-leg", "paper000-fig8-sixbar", "rocker-input"):
        for args in (
            ("curve", name),
            ("curve", name, "--spacing", "path"),
            ("solve", name, "--all"),
        ):
            assert cli.main(list(args)) == 0, args
        capsys.readouterr()

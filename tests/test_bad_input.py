"""Bad documents and arguments: every one gives exit status 2 and one line naming the problem.

Issue 10's list, one case each (malformed TOML and JSON, unknown family or field, missing or
wrongly typed fields, NaN and infinity, zero and negative lengths, spherical arcs of 180° or
more, coincident pivots, absurd magnitudes, a gear ratio of 0, empty point files, CSV with text
or ragged rows), then Hypothesis fuzzing of documents and command lines: thousands of generated
cases, each run through the real command line in this process. Whatever the input, the command
either succeeds with nothing on standard error and no NaN or infinity in what it prints, or
exits with status 2 and a single ``error:`` line; never a traceback, a warning or status 1.
A few cases run in a real subprocess too, so the exit status is the process's own.
"""

from __future__ import annotations

import copy
import json
import math
import re
import subprocess
import sys
import tomllib
import warnings
from pathlib import Path

import pytest
from documents_helpers import with_change as changed
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from linkwright.cli import main
from linkwright.io.documents import WORKING_RANGE, dumps_toml

EXAMPLES = Path(__file__).resolve().parents[1] / "src" / "linkwright" / "examples"
DOCUMENTS = {
    p.stem: tomllib.loads(p.read_text(encoding="utf-8")) for p in sorted(EXAMPLES.glob("*.toml"))
}
# A print of a number that is not one: "nan", "inf", "-inf", "NaN", "Infinity" as a token.
NOT_A_NUMBER = re.compile(r"(?<![A-Za-z])(nan|-?inf|NaN|-?Infinity)(?![A-Za-z])")


def run_cli(capsys, argv: list[str]) -> tuple[int, str, str, list[str]]:
    """Run the command line in this process: status, stdout, stderr and the warnings raised.

    pytest records warnings instead of printing them, so they are caught here explicitly: a
    RuntimeWarning (overflow, an invalid value) is a NaN or an infinity on its way out.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = main(argv)
    out, err = capsys.readouterr()
    return status, out, err, [f"{w.category.__name__}: {w.message}" for w in caught]


def assert_refused(status: int, err: str, *needles: str) -> None:
    assert status == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), err
    assert "Traceback" not in err and "internal error" not in err, err
    for needle in needles:
        assert needle in lines[0], (needle, err)


def assert_clean(status: int, out: str, err: str, caught: list[str], context: object = "") -> None:
    """Either a success that prints only numbers, or a refusal of one line: nothing else."""
    event(f"exit status {status}")
    assert not caught, (caught, context)
    if status == 0:
        assert err == "", err
        assert not NOT_A_NUMBER.search(out), NOT_A_NUMBER.search(out)
    else:
        assert_refused(status, err)


def write(tmp_path: Path, doc: object, suffix: str = ".json") -> Path:
    path = tmp_path / f"doc{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(doc, allow_nan=True), encoding="utf-8")
    else:
        path.write_text(dumps_toml(doc), encoding="utf-8")
    return path


FOURBAR = DOCUMENTS["crank-rocker"]
SPHERE = DOCUMENTS["paper000-fig6-crank-rocker"]
GEARED = DOCUMENTS["geared-fivebar"]
SLIDER = DOCUMENTS["slider-crank"]
JANSEN = DOCUMENTS["jansen-leg"]
NAN, INF = float("nan"), float("inf")

# (case, document, field named in the message, words of the message)
DOCUMENT_CASES = [
    (
        "unknown family",
        changed(FOURBAR, "mechanism.family", "fourbarr"),
        "mechanism.family",
        "did you mean 'fourbar'",
    ),
    ("unknown field", changed(FOURBAR, "mechanism.cranck", 1.0), "mechanism", "'cranck'"),
    (
        "missing field",
        changed(FOURBAR, "mechanism.rocker", delete=True),
        "mechanism.rocker",
        "missing",
    ),
    ("missing mechanism", changed(FOURBAR, "mechanism", delete=True), "mechanism", "missing"),
    (
        "text for a number",
        changed(FOURBAR, "mechanism.crank", "1.0"),
        "mechanism.crank",
        "positive number",
    ),
    (
        "list for a number",
        changed(FOURBAR, "mechanism.crank", [1.0]),
        "mechanism.crank",
        "positive number",
    ),
    (
        "bool for a number",
        changed(FOURBAR, "mechanism.crank", True),
        "mechanism.crank",
        "positive number",
    ),
    ("number for a point", changed(FOURBAR, "mechanism.A0", 0), "mechanism.A0", "[x, y]"),
    ("short point", changed(FOURBAR, "mechanism.A0", [0]), "mechanism.A0", "[x, y]"),
    ("NaN length", changed(FOURBAR, "mechanism.coupler", NAN), "mechanism.coupler", "finite"),
    (
        "infinite coordinate",
        changed(FOURBAR, "mechanism.B0", [INF, 0]),
        "mechanism.B0[0]",
        "finite",
    ),
    (
        "NaN offset",
        changed(FOURBAR, "mechanism.point", {"u": NAN, "v": 0}),
        "mechanism.point.u",
        "finite",
    ),
    ("zero length", changed(FOURBAR, "mechanism.crank", 0), "mechanism.crank", "positive"),
    (
        "negative length",
        changed(FOURBAR, "mechanism.rocker", -6.02),
        "mechanism.rocker",
        "positive",
    ),
    (
        "arc of 180",
        changed(SPHERE, "mechanism.coupler", 180),
        "mechanism.coupler",
        "strictly between 0 and 180",
    ),
    (
        "arc over 180",
        changed(SPHERE, "mechanism.crank", 200.5),
        "mechanism.crank",
        "strictly between 0 and 180",
    ),
    (
        "arc of 0",
        changed(SPHERE, "mechanism.frame", 0),
        "mechanism.frame",
        "strictly between 0 and 180",
    ),
    (
        "arc a hair from 180",
        changed(SPHERE, "mechanism.rocker", 180 - 1e-9),
        "mechanism.rocker",
        "at least 1e-06 from 0 and from 180",
    ),
    (
        "coincident pivots",
        changed(FOURBAR, "mechanism.B0", [0.0, 0.0]),
        "mechanism.B0",
        "coincides with mechanism.A0",
    ),
    (
        "pivots a rounding apart",
        changed(FOURBAR, "mechanism.B0", [1e-14, 0.0]),
        "mechanism.B0",
        "coincides with mechanism.A0",
    ),
    (
        "length of 1e300",
        changed(FOURBAR, "mechanism.crank", 1e300),
        "mechanism.crank",
        "working range",
    ),
    (
        "length of 1e-300",
        changed(FOURBAR, "mechanism.crank", 1e-300),
        "mechanism.crank",
        "working range",
    ),
    (
        "coordinate of 1e300",
        changed(FOURBAR, "mechanism.A0", [-1e300, 0]),
        "mechanism.A0[0]",
        "working range",
    ),
    (
        "offset of 1e300",
        changed(FOURBAR, "mechanism.point", {"u": 1e300, "v": 0}),
        "mechanism.point.u",
        "working range",
    ),
    (
        "a link 1e-11 of the rest",
        changed(FOURBAR, "mechanism.crank", 6e-11),
        "mechanism.crank",
        "under 1e-09 of the linkage's size",
    ),
    ("huge integer", changed(FOURBAR, "mechanism.crank", 10**400), "mechanism.crank", "finite"),
    (
        "angle of 1e300",
        changed(SLIDER, "mechanism.line.angle", 1e300),
        "mechanism.line.angle",
        "degrees",
    ),
    ("gear ratio 0", changed(GEARED, "mechanism.ratio", 0), "mechanism.ratio", "nonzero"),
    (
        "gear ratio 1e300",
        changed(GEARED, "mechanism.ratio", 1e300),
        "mechanism.ratio",
        "working range",
    ),
    (
        "gear ratio 1e-300",
        changed(GEARED, "mechanism.ratio", -1e-300),
        "mechanism.ratio",
        "working range",
    ),
    ("sign 0", changed(FOURBAR, "mechanism.assembly", 0), "mechanism.assembly", "1 or -1"),
    ("wrong format", changed(FOURBAR, "format", "linkwright/2"), "format", "linkwright/1"),
    (
        "joint length of 1e-300",
        {
            **JANSEN,
            "mechanism": {
                **JANSEN["mechanism"],
                "joints": [
                    {**j, "r1": 1e-300} if j.get("type") == "rrr" else j
                    for j in JANSEN["mechanism"]["joints"]
                ],
            },
        },
        "mechanism.joints[",
        "working range",
    ),
    ("not a table", [1, 2, 3], "document", "table"),
]


@pytest.mark.parametrize(
    ("case", "doc", "field", "words"), DOCUMENT_CASES, ids=[c[0] for c in DOCUMENT_CASES]
)
@pytest.mark.parametrize("command", ["solve", "curve", "analyze"])
def test_each_bad_document_is_one_line_naming_its_field(
    tmp_path, capsys, case, doc, field, words, command
):
    path = write(tmp_path, doc)
    status, out, err, caught = run_cli(capsys, [command, str(path)])
    assert_refused(status, err, f"{path}: {field}", words)
    assert out == "" and not caught


MALFORMED = [
    ("doc.toml", "format = \n", "invalid TOML"),
    ("doc.toml", '[mechanism]\nfamily = "fourbar"\nfamily = "fourbar"\n', "invalid TOML"),
    ("doc.json", '{"format": "linkwright/1",', "invalid JSON"),
    ("doc.json", '{"format": "linkwright/1", "format": "linkwright/1"}', "duplicate key"),
    ("doc.json", "[" * 100_000, "nested too deeply"),
    ("doc.json", "", "invalid JSON"),
    ("doc.toml", "", "format: missing required field"),
    ("doc.json", "NaN", "document: must be a table"),
    ("doc.yaml", "format: linkwright/1", "expected .toml or .json"),
]


@pytest.mark.parametrize(("name", "text", "words"), MALFORMED)
def test_malformed_files_are_one_line(tmp_path, capsys, name, text, words):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    status, _, err, _ = run_cli(capsys, ["solve", str(path)])
    assert_refused(status, err, str(path), words)


def test_a_file_that_is_not_text_or_not_there(tmp_path, capsys):
    binary = tmp_path / "doc.toml"
    binary.write_bytes(b"\xff\xfe\x00format")
    assert_refused(*run_cli(capsys, ["solve", str(binary)])[::2], "not UTF-8")
    missing = tmp_path / "missing.toml"
    assert_refused(*run_cli(capsys, ["curve", str(missing)])[::2], "cannot read")
    assert_refused(*run_cli(capsys, ["analyze", str(tmp_path)])[::2], str(tmp_path))


POINT_FILES = [
    ("empty", "", "no points"),
    ("header only", "x,y\n", "no points"),
    ("comments only", "# nothing\n\n", "no points"),
    ("text in a row", "0,0\n1,abc\n2,2\n", "line 2: not numbers"),
    ("ragged rows", "0,0\n1,1,1\n2,2\n", "line 2: 3 columns"),
    ("one column", "0\n1\n2\n", "line 1: 1 columns"),
    ("NaN", "0,0\nnan,1\n2,2\n", "line 2: coordinates must be finite"),
    ("infinity", "0,0\n1,inf\n2,2\n", "line 2: coordinates must be finite"),
    ("absurd", "0,0\n1,1e300\n2,2\n", "line 2: a coordinate must be at most 1e+12"),
]


@pytest.mark.parametrize(("case", "text", "words"), POINT_FILES, ids=[p[0] for p in POINT_FILES])
@pytest.mark.parametrize(
    "argv",
    [
        ["synth", "ellipse", "--points"],
        ["synth", "path", "--family", "fourbar", "--no-timing", "--closed", "--points"],
        ["atlas", "query", "--points"],
    ],
    ids=["ellipse", "path", "atlas"],
)
def test_bad_point_files_are_one_line_with_the_line_number(
    tmp_path, capsys, case, text, words, argv
):
    path = tmp_path / "points.csv"
    path.write_text(text, encoding="utf-8")
    status, _, err, _ = run_cli(capsys, [*argv, str(path)])
    assert_refused(status, err, str(path), words)


ARGUMENT_CASES = [
    (["solve", "crank-rocker", "-i", "0:360:0"], "STEP must not be zero"),
    (["solve", "crank-rocker", "-i", "nan"], "finite"),
    (["solve", "crank-rocker", "-i", "1e300"], "working range"),
    (["solve", "crank-rocker", "-i", "0:1e6:1e-3"], "more than"),
    (["solve", "crank-rocker", "-i", "a:b"], "START:STOP:STEP"),
    (["solve", "crank-rocker", "-i", ""], "empty"),
    (["curve", "crank-rocker", "-n", "1"], "--points"),
    (["curve", "crank-rocker", "-n", "many"], "--points"),
    (["curve", "crank-rocker", "--csv", "--json"], "cannot be used together"),
    (["curve", "crank-rocker", "--spacing", "arc"], "--spacing: must be input or path"),
    (["plot", "crank-rocker", "--at", "inf"], "--at"),
    (["plot", "crank-rocker", "--at", "1e300"], "working range"),
    (["plot", "crank-rocker", "--out", "x.jpg"], "--out"),
    (["analyze", "paper000-fig6-crank-rocker", "--mu", "nan"], "mu"),
    (["analyze", "paper000-fig6-crank-rocker", "--mu", "-1"], "mu"),
    (["synth", "ellipse", "--conic", "1,0,1,0,0"], "expected 6 numbers"),
    (["synth", "ellipse", "--conic", "1,0,1,0,0,1"], "ellipse"),
    (["solve", "no-such-example"], "no-such-example"),
    (["frobnicate"], "No such command"),
    (["solve", "crank-rocker", "--bogus"], "No such option"),
]


@pytest.mark.parametrize(
    ("argv", "words"), ARGUMENT_CASES, ids=[" ".join(a) for a, _ in ARGUMENT_CASES]
)
def test_bad_arguments_are_one_line(tmp_path, monkeypatch, capsys, argv, words):
    monkeypatch.chdir(tmp_path)
    status, _, err, caught = run_cli(capsys, argv)
    assert_refused(status, err, words)
    assert not caught


def test_a_real_process_exits_2_with_one_line(tmp_path):
    """The exit status and the single line, seen from outside the process."""
    bad = write(tmp_path, changed(FOURBAR, "mechanism.crank", 1e300))
    for argv in (["solve", str(bad)], ["curve", "crank-rocker", "-n", "0"]):
        proc = subprocess.run(
            [sys.executable, "-m", "linkwright", *argv],
            capture_output=True,
            text=True,
            timeout=120,
            stdin=subprocess.DEVNULL,
        )
        assert proc.returncode == 2, proc.stderr
        assert len(proc.stderr.splitlines()) == 1 and proc.stderr.startswith("error: ")
        assert proc.stdout == ""


# ---------------------------------------------------------------------------------------------
# Fuzzing: documents mutated at random, and command lines built from random tokens
# ---------------------------------------------------------------------------------------------

# Values that break documents in every way the issue lists, and a few that are fine.
nasty_numbers = st.sampled_from(
    [
        0,
        -1,
        -0.0,
        1e300,
        -1e300,
        1e-300,
        5e-324,
        NAN,
        INF,
        -INF,
        180,
        180.0000001,
        360,
        1e12,
        1e13,
        10**30,
        1e-13,
        2.5,
        1,
        True,
    ]
)
nasty = st.one_of(
    nasty_numbers,
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**20), 10**20),
    st.text(max_size=6),
    st.lists(nasty_numbers, max_size=4),
    st.dictionaries(
        st.sampled_from(["u", "v", "arc", "angle", "point", "x"]), nasty_numbers, max_size=3
    ),
    st.none(),
)


def _leaves(node, path=()):
    """Every (path, value) in a nested document, tables and lists included."""
    yield path, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _leaves(v, (*path, i))


def _set(doc, path, value):
    target = doc
    for key in path[:-1]:
        target = target[key]
    if value is _DELETE:
        del target[path[-1]]
    else:
        target[path[-1]] = value


_DELETE = object()


@st.composite
def mutated_documents(draw):
    """A bundled example with one to three of its fields replaced, deleted or scaled."""
    doc = copy.deepcopy(DOCUMENTS[draw(st.sampled_from(sorted(DOCUMENTS)))])
    for _ in range(draw(st.integers(1, 3))):
        spots = [p for p, _ in _leaves(doc) if p and p[0] == "mechanism" and len(p) > 1]
        path = draw(st.sampled_from(spots))
        action = draw(st.sampled_from(["replace", "replace", "delete", "scale", "rename"]))
        value = draw(nasty)
        try:
            current = doc
            for key in path:
                current = current[key]
            if action == "delete" and isinstance(path[-1], str):
                _set(doc, path, _DELETE)
            elif action == "scale" and isinstance(current, int | float):
                _set(doc, path, current * draw(st.sampled_from([1e-15, 1e-9, 1e9, 1e15, -1])))
            elif action == "rename" and isinstance(path[-1], str):
                parent = doc
                for key in path[:-1]:
                    parent = parent[key]
                parent[path[-1] + draw(st.sampled_from(["_", "x", "0"]))] = parent.pop(path[-1])
            else:
                _set(doc, path, value)
        except (KeyError, IndexError, TypeError):
            pass
    return doc


COMMANDS = [
    ["solve", "-i", "0:360:45"],
    ["curve", "-n", "24"],
    ["analyze"],
    ["solve", "--all", "-i", "10,200", "--derivatives", "--json"],
    ["curve", "-n", "9", "--json"],
]


@settings(
    # Each example runs a command on a damaged document: 500 of them (fresh each run) keep this
    # fuzz to a share of the suite's 10 minutes that the rest can afford.
    max_examples=500,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    doc=mutated_documents(),
    suffix=st.sampled_from([".json", ".toml"]),
    command=st.sampled_from(COMMANDS),
)
def test_fuzz_documents_through_the_command_line(tmp_path, capsys, doc, suffix, command):
    try:
        path = write(tmp_path, doc, suffix)
    except (TypeError, ValueError):  # TOML cannot hold None or NaN keys: use JSON for it
        path = write(tmp_path, doc, ".json")
    name, *options = command
    assert_clean(*run_cli(capsys, [name, str(path), *options]), (command, doc))


OPTION_VALUES = st.one_of(
    st.sampled_from(
        [
            "0",
            "-1",
            "nan",
            "inf",
            "1e300",
            "1e-300",
            "0:360:0",
            "0:360:-1",
            "0:360:30",
            "1,2,3",
            "",
            " ",
            "x",
            "--",
            "-5:5:1",
            "99999999999",
            "360",
            "2",
            "720",
            "0.5",
            "1e6",
            "1e7",
        ]
    ),
    st.text(alphabet="0123456789.:,-e naif", max_size=10),
)
ARGUMENT_SHAPES = [
    (
        "solve",
        ["-i", "--input"],
        ["crank-rocker", "rocker-input", "geared-fivebar", "paper000-fig6-crank-rocker"],
    ),
    ("curve", ["-n", "--points"], ["crank-rocker", "slider-crank", "paper000-fig6-linkage"]),
    ("analyze", ["--mu"], ["paper000-fig6-crank-rocker", "crank-rocker"]),
]


@settings(
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(shape=st.sampled_from(ARGUMENT_SHAPES), data=st.data())
def test_fuzz_command_line_options(tmp_path, monkeypatch, capsys, shape, data):
    command, options, examples = shape
    argv = [command, data.draw(st.sampled_from(examples))]
    for _ in range(data.draw(st.integers(0, 2))):
        argv += [
            data.draw(st.sampled_from([*options, "--json", "--bogus"])),
            data.draw(OPTION_VALUES),
        ]
    monkeypatch.chdir(tmp_path)
    assert_clean(*run_cli(capsys, argv))


@settings(
    max_examples=200,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    text=st.text(max_size=200) | st.binary(max_size=200).map(lambda b: b.decode("latin-1")),
    suffix=st.sampled_from([".toml", ".json"]),
)
def test_fuzz_arbitrary_file_contents(tmp_path, capsys, text, suffix):
    path = tmp_path / f"doc{suffix}"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    status, out, err, caught = run_cli(capsys, ["solve", str(path)])
    assert_clean(status, out, err, caught)


@settings(
    max_examples=200,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(
    rows=st.lists(
        st.lists(
            st.one_of(st.floats(), st.text(alphabet="0123456789.e-xn ", max_size=5)), max_size=4
        ),
        max_size=8,
    )
)
def test_fuzz_point_files(tmp_path, capsys, rows):
    path = tmp_path / "points.csv"
    path.write_text("\n".join(",".join(map(str, r)) for r in rows), encoding="utf-8")
    status, out, err, caught = run_cli(capsys, ["synth", "ellipse", "--points", str(path)])
    assert_clean(status, out, err, caught)


def test_working_range_numbers_are_the_documented_ones():
    # The README's reliability section quotes these; a change must change it too.
    assert (WORKING_RANGE.max_size, WORKING_RANGE.min_length, WORKING_RANGE.min_share) == (
        1e12,
        1e-12,
        1e-9,
    )
    assert (WORKING_RANGE.max_angle, WORKING_RANGE.min_arc, WORKING_RANGE.min_ratio) == (
        1e6,
        1e-6,
        1e-6,
    )
    assert math.isfinite(WORKING_RANGE.max_size**2 * WORKING_RANGE.max_size**2)

"""The command line's typer app, its shared options and the helpers every command uses.

Documents and the command line speak degrees; the engine speaks radians. Errors end the program
with status 2 and one line ``error: <message>`` on standard error, never a traceback. numpy and
the engine are imported inside the commands, so ``linkwright --help`` and ``--version`` start
fast.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping, Sequence
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from linkwright import __version__

if TYPE_CHECKING:
    from linkwright.io import Document
    from linkwright.mechanisms import Mechanism

# Samples a --input range may ask for: far beyond any useful table, well below running out of
# memory.
MAX_SAMPLES = 1_000_000
DEFAULT_INPUTS = [float(30 * k) for k in range(12)]


class CliError(Exception):
    """A problem with how the command was used; reported as ``error: <message>``, status 2."""


app = typer.Typer(
    name="linkwright",
    help="Kinematics workbench for planar and spherical linkages: solve, trace, analyse, draw "
    "and export mechanism documents.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
)


def _version_callback(value: bool) -> None:
    if value:
        sys.stdout.write(f"linkwright {__version__}\n")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            help="Print the version and exit.",
            is_eager=True,
            callback=_version_callback,
        ),
    ] = False,
) -> None:
    """Kinematics workbench for planar and spherical linkages: solve, trace, analyse, draw and
    export mechanism documents.

    FILE is a .toml or .json mechanism document (or the name of a bundled example).
    """


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------


def decimal_text(text: str, what: str, *, angle: bool = False) -> Decimal:
    # ``what`` names an option (``--angles``) or a part of --input's range (``START``).
    where = f"{what}:" if what.startswith("--") else f"--input: {what}"
    try:
        value = Decimal(text.strip())
    except InvalidOperation:
        raise CliError(f"{where} must be a number, got {text.strip()!r}") from None
    if not value.is_finite() or not math.isfinite(float(value)):
        raise CliError(f"{where} must be a finite number, got {text.strip()!r}")
    in_working_range(float(value), where, angle=angle)
    return value


def in_working_range(value: float, where: str, *, angle: bool = False) -> None:
    """The documents' working range, for numbers given on the command line or in point files."""
    from linkwright.io.documents import WORKING_RANGE

    check = WORKING_RANGE.angle_problem if angle else WORKING_RANGE.size_problem
    if problem := check(value):
        raise CliError(f"{where} {problem}")


def parse_inputs(spec: str) -> list[float]:
    """Input angles (degrees) from ``START:STOP:STEP`` or a comma-separated list.

    A range includes STOP when it lands on the grid. Arithmetic is decimal, so ``0:1:0.1`` gives
    exactly the eleven numbers written, not ten with a rounding shortfall.

    Raises
    ------
    CliError
        For a malformed spec, a zero step, a step away from STOP, or too many samples.

    Examples
    --------
    >>> parse_inputs("0:90:30")
    [0.0, 30.0, 60.0, 90.0]
    >>> parse_inputs("0:100:30")
    [0.0, 30.0, 60.0, 90.0]
    >>> parse_inputs("10, -5.5,720")
    [10.0, -5.5, 720.0]
    """
    text = spec.strip()
    if not text:
        raise CliError("--input: empty; expected START:STOP:STEP or a comma list of degrees")
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise CliError(f"--input: expected START:STOP:STEP, got {spec!r}")
        start, stop, step = (
            decimal_text(p, w, angle=True)
            for p, w in zip(parts, ("START", "STOP", "STEP"), strict=True)
        )
        if step == 0:
            raise CliError("--input: STEP must not be zero")
        span = (stop - start) / step
        if span < 0:
            raise CliError(f"--input: STEP {step} goes away from STOP ({start} to {stop})")
        if span >= MAX_SAMPLES:
            raise CliError(f"--input: {spec!r} asks for more than {MAX_SAMPLES} samples")
        return [float(start + k * step) for k in range(int(span) + 1)]
    items = text.split(",")
    if len(items) > MAX_SAMPLES:
        raise CliError(f"--input: more than {MAX_SAMPLES} samples")
    return [float(decimal_text(p, "each angle", angle=True)) for p in items]


def load_file(file: str) -> Document:
    from linkwright.io import list_examples, load_document, load_example

    path = Path(file)
    if not path.exists() and not path.suffix and file in list_examples():
        return load_example(file)
    return load_document(path)


def axes_of(mech: Mechanism) -> str:
    from linkwright.io.results import structure

    return "xyz" if structure(mech).space == "sphere" else "xy"


def to_json_ready(value: Any) -> Any:
    from linkwright.io.report import jsonable

    return jsonable(value)


def dump_json(obj: Any) -> str:
    from linkwright.io.report import json_text

    return json_text(obj)


def fmt_number(x: Any, width: int = 11, places: int = 6) -> str:
    if x is None:
        return "-".rjust(width)
    if isinstance(x, bool) or not isinstance(x, int | float):
        return str(x).rjust(width)
    if not math.isfinite(x):
        return "-".rjust(width)
    if abs(x) < 0.5 * 10.0**-places:
        x = 0.0  # no "-0.000000" for a coordinate that is zero up to rounding
    return f"{x:{width}.{places}f}"


def signs_text(signs: Sequence[int]) -> str:
    return ",".join(f"{s:+d}" for s in signs)


def document_heading(doc: Document) -> str:
    name = f"{doc.title} [{doc.family}]" if doc.title else f"[{doc.family}]"
    return f"# {name}" + (f", lengths in {doc.units}" if doc.units else "")


# --------------------------------------------------------------------------------------------
# Commands
# --------------------------------------------------------------------------------------------

FileArg = Annotated[
    str,
    typer.Argument(
        metavar="FILE",
        help="Mechanism document (.toml or .json), or the name of a bundled example.",
        show_default=False,
    ),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")]

QuietOpt = Annotated[bool, typer.Option("--quiet", help="No progress bar.")]


# Points a point file may hold: far beyond any drawn curve, well below running out of memory.
MAX_POINTS = 100_000


UNIT_TOL = 0.01
"""Spherical targets within this of unit length are taken as unit vectors as they are."""


def sphere_directions(points: Any) -> tuple[Any, dict[str, Any] | None]:
    """Spherical targets as unit vectors: as given where they are (within 1 %), else the
    directions from the centre of the sphere fitted to them, with that sphere's centre,
    radius and RMS distance (:func:`linkwright.geometry.sphere_fit.fit_sphere`)."""
    import numpy as np

    from linkwright.geometry.sphere_fit import SphereFitError, fit_sphere

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        return pts, None
    if np.all(np.abs(np.linalg.norm(pts, axis=1) - 1.0) <= UNIT_TOL):
        return pts, None
    try:
        fitted = fit_sphere(pts)
    except SphereFitError as exc:
        raise CliError(f"--points: not unit vectors, and {exc}") from None
    info = {"centre": fitted.centre.tolist(), "radius": fitted.radius, "rms": fitted.rms}
    return fitted.directions, info


def sphere_text(info: dict[str, Any] | None) -> str:
    """The line that says which sphere the points were put on ("" for unit vectors)."""
    if info is None:
        return ""
    centre = ", ".join(f"{c:.6g}" for c in info["centre"])
    return (
        f"the points lie on the sphere of radius {info['radius']:.6g} about ({centre}) "
        f"(RMS {info['rms']:.3g} off it): fitted as directions from its centre; distances "
        "below are in units of its radius\n"
    )


def read_points(path: Path, columns: tuple[int, ...] = (2,)) -> list[list[float]]:
    """Rows of numbers from a CSV (comma, semicolon or whitespace separated) point file.

    A first line that is not numbers is a header and skipped; blank lines and lines starting
    with ``#`` are skipped. Every other row must hold as many finite numbers as one of
    ``columns`` says, all rows alike; anything else is a :class:`CliError` naming the line.
    """
    if not path.exists():
        raise CliError(f"{path}: no such file")
    if path.is_dir():
        raise CliError(f"{path}: is a folder, not a point file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise CliError(f"{path}: not a text file (expected CSV rows of numbers)") from None
    rows: list[list[float]] = []
    width = None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        cells = [c for c in stripped.replace(";", ",").replace(",", " ").split() if c]
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if not rows and width is None:
                width = -1  # a header line: the next line starts the data
                continue
            raise CliError(f"{path}, line {number}: not numbers: {stripped!r}") from None
        if width is None or width == -1:
            width = len(values)
            if width not in columns:
                want = " or ".join(str(c) for c in columns)
                raise CliError(f"{path}, line {number}: {width} columns, expected {want}")
        elif len(values) != width:
            raise CliError(f"{path}, line {number}: {len(values)} columns, the rows above have "
                           f"{width}")  # fmt: skip
        if not all(math.isfinite(v) for v in values):
            raise CliError(f"{path}, line {number}: coordinates must be finite numbers")
        for v in values:
            in_working_range(v, f"{path}, line {number}: a coordinate")
        rows.append(values)
        if len(rows) > MAX_POINTS:
            raise CliError(f"{path}: more than {MAX_POINTS} points")
    if not rows:
        raise CliError(f"{path}: no points in the file")
    return rows


class Progress:
    """A progress bar on standard error for a library call that reports fractions done; only on
    a terminal (a log or a pipe gets no bar characters), and not with ``--quiet``."""

    def __init__(self, label: str, quiet: bool) -> None:
        self.label, self.quiet = label, quiet
        self.bar: Any = None
        self.done = 0

    def __enter__(self) -> Progress:
        if not self.quiet and sys.stderr.isatty():
            self.bar = typer.progressbar(length=1000, label=self.label, file=sys.stderr)
            self.bar.__enter__()
        return self

    def __call__(self, fraction: float) -> None:
        if self.bar is None:
            return
        target = int(1000 * min(max(float(fraction), 0.0), 1.0))
        if target > self.done:
            self.bar.update(target - self.done)
            self.done = target

    def __exit__(self, *exc: Any) -> None:
        if self.bar is not None:
            self.bar.__exit__(*exc)


def documents_json(value: Any) -> Any:
    """The synthesis reports with every mechanism replaced by its document."""
    from linkwright.io import mechanism_to_dict
    from linkwright.mechanisms import Mechanism

    if isinstance(value, Mechanism):
        return mechanism_to_dict(value)
    if isinstance(value, Mapping):
        return {k: documents_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [documents_json(v) for v in value]
    return value


def parse_floats(
    text: str, what: str, count: int | None = None, *, angle: bool = False
) -> list[float]:
    items = [t for t in text.replace(";", ",").split(",") if t.strip()]
    values = [float(decimal_text(t.strip(), what, angle=angle)) for t in items]
    if count is not None and len(values) != count:
        raise CliError(f"{what}: expected {count} numbers, got {len(values)}")
    return values


def mechanism_toml(document: Mapping[str, Any]) -> str:
    from linkwright.io.documents import dumps_toml

    return dumps_toml(document).rstrip()


def family_and_template(
    family: str | None, template: str | None, numbers: str
) -> tuple[str, Mechanism | None]:
    """The family a search or an atlas is of, and its template mechanism (``--template``):
    the family defaults to the template's, and a composed linkage needs one (``numbers`` says
    what becomes of the template's numbers)."""
    like = load_file(template).mechanism if template is not None else None
    if family is None and like is None:
        raise CliError("--family: give a family, or a --template document to take it from")
    name = family if family is not None else like.family  # type: ignore[union-attr]
    if name == "linkage" and like is None:
        raise CliError(
            "--family linkage: a composed linkage's joints come from a document: give "
            f"--template FILE (its structure is kept, {numbers})"
        )
    return name, like

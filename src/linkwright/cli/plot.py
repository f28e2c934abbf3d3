"""``linkwright plot``, ``animate`` and ``export``: pictures, animations and CAD files."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from linkwright.cli.shared import (
    CliError,
    FileArg,
    Progress,
    QuietOpt,
    app,
    in_working_range,
    load_file,
)

PLOT_KINDS = (
    "linkage",
    "angles",
    "velocity",
    "acceleration",
    "coefficients",
    "torque",
    "reactions",
    "shaking",
)
FORCE_KINDS = ("torque", "reactions", "shaking")
PICTURE_SUFFIXES = (".png", ".svg", ".pdf")
AtOpt = Annotated[
    float | None,
    typer.Option(
        "--at",
        metavar="DEG",
        help="Input angle of the pose drawn, degrees (default: the circuit's first sample).",
        show_default=False,
    ),
]


def _suffix(out: Path, allowed: Sequence[str], what: str) -> None:
    if out.suffix.lower() not in allowed:
        raise CliError(f"--out: {what} are written as {', '.join(allowed)}; got {out.name!r}")


def _at(value: float | None) -> float | None:
    if value is None:
        return None
    if not math.isfinite(value):
        raise CliError(f"--at: must be a finite angle in degrees, got {value}")
    in_working_range(value, "--at:", angle=True)
    return math.radians(value)


def _wrote(path: Path | str) -> None:
    sys.stdout.write(f"wrote {os.fspath(path)}\n")


@app.command()
def plot(
    file: FileArg,
    out: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="X.png|X.svg|X.pdf",
            help="Picture to write (default: FILE's name, with -KIND for a diagram, as .png).",
            show_default=False,
        ),
    ] = None,
    kind: Annotated[
        str,
        typer.Option(
            "--kind",
            metavar="KIND",
            help="linkage (the linkage, its curves, limit positions, dead centres and "
            "transmission-angle extremes), angles, velocity, acceleration or coefficients "
            "(diagrams against the input), torque, reactions or shaking (forces over the "
            "circuit, from the document's [mechanism.mass] and [loads]: docs/forces.md).",
        ),
    ] = "linkage",
    at: AtOpt = None,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=16, max=100_000, help="Samples.")
    ] = 720,
    quiet: QuietOpt = False,
) -> None:
    """Draw the linkage and its coupler curves, or a diagram of its motion against the input.

    Spherical linkages get a 3-D view of the sphere and a map projection of their curves.
    """
    if kind not in PLOT_KINDS:
        raise CliError(f"--kind: expected one of {', '.join(PLOT_KINDS)}; got {kind!r}")
    doc = load_file(file)
    stem = Path(file).stem
    out = out or Path(f"{stem}.png" if kind == "linkage" else f"{stem}-{kind}.png")
    _suffix(out, PICTURE_SUFFIXES, "pictures")
    if kind != "linkage" and at is not None:
        raise CliError("--at: only the linkage picture shows a pose; leave it out for a diagram")
    from linkwright.cli.budget import check_drawing, check_followed

    check_drawing(doc.mechanism, samples, knob="--samples", least=16, order=2)
    if doc.mechanism.plan.triads:
        check_followed(doc.mechanism, samples, knob="--samples")
    from linkwright.plot import save_figure
    from linkwright.plot.diagrams import DiagramError, plot_diagram
    from linkwright.plot.view import PlotError, plot_mechanism

    if kind in FORCE_KINDS:
        _wrote(save_figure(_force_figure(doc, kind, samples, file), out))
        return
    try:
        if kind == "linkage":
            figure = plot_mechanism(doc.mechanism, at=_at(at), samples=samples, title=doc.title)
        else:
            figure = plot_diagram(doc.mechanism, kind, samples=samples, title=doc.title)
    except (PlotError, DiagramError) as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(save_figure(figure, out))


def _force_figure(doc: Any, kind: str, samples: int, file: str) -> Any:
    """The force diagram of a document over its circuit (masses and loads from the document,
    checked as ``linkwright forces`` checks them)."""
    from linkwright.cli.forces import document_forces
    from linkwright.dynamics import forces_of
    from linkwright.mechanisms.base import circuit
    from linkwright.plot.forces import plot_forces

    st, masses, loads = document_forces(doc)
    motion = circuit(doc.mechanism, samples)
    result = forces_of(st, doc.mechanism.params(), motion, masses, loads)
    # The document's mass unit (kg when none is named) and length unit: N·m and N for metres.
    length = doc.units or "length"
    units = ("N·m", "N") if doc.units == "m" else (f"mass·{length}²/s²", f"mass·{length}/s²")
    return plot_forces(doc.mechanism, result, kind, title=doc.title, units=units)


@app.command()
def animate(
    file: FileArg,
    out: Annotated[
        Path,
        typer.Option("--out", metavar="X.gif|X.mp4", help="Animation to write (MP4 needs ffmpeg)."),
    ],
    frames: Annotated[
        int, typer.Option("--frames", metavar="N", min=2, max=5000, help="Frames per cycle.")
    ] = 120,
    fps: Annotated[int, typer.Option("--fps", metavar="N", min=1, max=120)] = 30,
    dpi: Annotated[int, typer.Option("--dpi", metavar="N", min=20, max=600)] = 100,
    quiet: QuietOpt = False,
) -> None:
    """Animate one cycle of the mechanism, its traced curves growing as it runs."""
    _suffix(out, (".gif", ".mp4"), "animations")
    doc = load_file(file)
    from linkwright.cli.budget import check_animation

    check_animation(doc.mechanism, frames, dpi, gif=out.suffix.lower() == ".gif")
    from linkwright.plot.animation import AnimationError
    from linkwright.plot.animation import animate as render

    try:
        with Progress("animating", quiet) as progress:
            path = render(
                doc.mechanism, out, frames=frames, fps=fps, dpi=dpi, title=doc.title,
                progress=progress,
            )  # fmt: skip
    except AnimationError as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(path)


@app.command()
def export(
    file: FileArg,
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            metavar="X.csv|X.svg|X.dxf",
            help="CSV: every joint's path over the circuit (and the forces, where the "
            "document has masses or loads); SVG and DXF: the linkage at the pose and its "
            "coupler curves, in the document's units.",
        ),
    ],
    at: AtOpt = None,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=8, max=100_000, help="Curve samples.")
    ] = 360,
) -> None:
    """Export the mechanism's paths (CSV) or its drawing (SVG, DXF) for CAD."""
    _suffix(out, (".csv", ".svg", ".dxf"), "exports")
    doc = load_file(file)
    from linkwright.cli.budget import check_drawing, check_followed

    check_drawing(doc.mechanism, samples, knob="--samples", least=8)
    if doc.mechanism.plan.triads:
        check_followed(doc.mechanism, samples, knob="--samples")
    from linkwright.io.exports import ExportError
    from linkwright.io.exports import export as write

    forces = None
    if out.suffix.lower() == ".csv" and (
        doc.raw["mechanism"].get("mass") or doc.raw.get("loads") is not None
    ):
        # A document with masses or loads exports its forces beside the paths.
        from linkwright.cli.forces import document_forces

        where = f"{file}: forces: "
        forces = document_forces(doc, unsupported=where, invalid=where)
    try:
        path = write(
            doc.mechanism,
            out,
            at=_at(at),
            samples=samples,
            units=doc.units,
            title=doc.title,
            forces=forces,
        )
    except ExportError as exc:
        raise CliError(f"{file}: {exc}") from None
    _wrote(path)

"""``linkwright tolerance``: the band of the traced curve (and output angle) under dimensional
tolerances, to first order, optionally checked by a seeded Monte Carlo."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from linkwright.cli.shared import (
    CliError,
    FileArg,
    JsonOpt,
    app,
    document_heading,
    dump_json,
    fmt_number,
    load_file,
)


def _band_document(band: Any, sphere: bool, mc: Any | None) -> dict[str, Any]:
    # Arc-valued quantities (a spherical band, every output angle) speak degrees.
    unit = np.degrees if sphere else (lambda v: v)
    doc: dict[str, Any] = {
        "point": band.point,
        "parameters": list(band.names),
        "tolerances": [
            float(v) for v in (np.degrees(band.tolerances) if sphere else band.tolerances)
        ],
        "method": "first order, fourth-order central differences",
        "input_deg": np.degrees(band.inputs).tolist(),
        "curve": band.curve.tolist(),
        "half_width": unit(band.half_width).tolist(),
        "std": unit(band.std).tolist(),
        "max_half_width": float(unit(np.max(band.half_width))),
    }
    if band.output_half_width is not None:
        doc["output_half_width_deg"] = np.degrees(band.output_half_width).tolist()
        doc["output_std_deg"] = np.degrees(band.output_std).tolist()
        doc["max_output_half_width_deg"] = float(np.degrees(np.max(band.output_half_width)))
    if mc is not None:
        dev = np.abs(mc.normal)
        doc["monte_carlo"] = {
            "trials": int(mc.normal.shape[0]),
            "max_deviation": unit(np.nanmax(dev, axis=0)).tolist(),
            "std": unit(np.nanstd(mc.normal, axis=0)).tolist(),
            "failed_samples": int(np.sum(mc.failed)),
        }
        if mc.output is not None:
            doc["monte_carlo"]["output_std_deg"] = np.degrees(np.nanstd(mc.output, 0)).tolist()
    return doc


def _plot(band: Any, sphere: bool, out: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from linkwright.files import atomic_path

    panels = 2 if band.output_half_width is not None else 1
    fig = Figure(figsize=(6 * panels, 5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, panels, 1)
    if sphere:
        ax.plot(np.degrees(band.inputs), np.degrees(band.half_width), label="worst case")
        ax.plot(np.degrees(band.inputs), np.degrees(band.std), label="std (uniform errors)")
        ax.set(xlabel="input (deg)", ylabel="half-width across the curve (deg of arc)")
        ax.legend()
    else:
        closed = np.r_[np.arange(band.inputs.size), 0]
        edge = band.half_width[:, None] * band.normal
        for sign in (1, -1):
            side = band.curve + sign * edge
            ax.plot(side[closed, 0], side[closed, 1], color="tab:orange", lw=0.8)
        ax.plot(band.curve[closed, 0], band.curve[closed, 1], color="tab:blue", label="nominal")
        ax.set_aspect("equal")
        ax.set(title=f"{band.point}: nominal curve and worst-case band")
        ax.legend()
    if band.output_half_width is not None:
        ax2 = fig.add_subplot(1, panels, 2)
        ax2.plot(np.degrees(band.inputs), np.degrees(band.output_half_width), label="worst case")
        ax2.plot(np.degrees(band.inputs), np.degrees(band.output_std), label="std")
        ax2.set(xlabel="input (deg)", ylabel="output angle half-width (deg)")
        ax2.legend()
    with atomic_path(out) as temp:
        fig.savefig(temp, format="png")


@app.command()
def tolerance(
    file: FileArg,
    tol: Annotated[
        float,
        typer.Option(
            "--tol",
            help="± on every link length, pivot and point coordinate (length units) and "
            "spherical arc (degrees); with --relative a fraction.",
        ),
    ],
    relative: Annotated[
        bool,
        typer.Option(
            "--relative",
            help="--tol is a fraction of each length's or arc's value (of the linkage's size for "
            "coordinates).",
        ),
    ] = False,
    samples: Annotated[int, typer.Option("--samples", "-n", metavar="N", min=2)] = 360,
    trials: Annotated[
        int,
        typer.Option("--monte-carlo", metavar="N", min=0, help="Check by N seeded random trials."),
    ] = 0,
    seed: Annotated[int, typer.Option("--seed", min=0)] = 0,
    as_csv: Annotated[bool, typer.Option("--csv", help="Print CSV.")] = False,
    as_json: JsonOpt = False,
    plot: Annotated[
        Path | None, typer.Option("--plot", metavar="OUT.png", help="Picture of the band.")
    ] = None,
) -> None:
    """The band of the traced curve under dimensional tolerances (first order)."""
    if as_csv and as_json:
        raise CliError("--csv and --json cannot be used together")
    if not np.isfinite(tol) or tol <= 0:
        raise CliError(f"--tol: must be a positive number, got {tol!r}")
    from linkwright.analysis.tolerance import (
        MAX_SAMPLES,
        ToleranceError,
        monte_carlo,
        tolerance_band,
    )

    if samples > MAX_SAMPLES:
        raise CliError(f"--samples: at most {MAX_SAMPLES}, got {samples}")
    doc = load_file(file)
    mech = doc.mechanism
    sphere = mech.plan.space == "sphere"
    value = tol if relative or not sphere else float(np.radians(tol))
    try:
        band = tolerance_band(mech, value, relative=relative, samples=samples)
        mc = monte_carlo(mech, band, trials, seed=seed) if trials else None
    except ToleranceError as exc:
        raise CliError(str(exc)) from None
    result = _band_document(band, sphere, mc)
    if plot is not None:
        _plot(band, sphere, plot)
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    has_out = "output_half_width_deg" in result
    head = ["input_deg", "half_width", "std"] + (["output_half_width_deg"] if has_out else [])
    if mc is not None:
        head.append("mc_max_deviation")
    rows = []
    for j, deg in enumerate(result["input_deg"]):
        row = [deg, result["half_width"][j], result["std"][j]]
        if has_out:
            row.append(result["output_half_width_deg"][j])
        if mc is not None:
            row.append(result["monte_carlo"]["max_deviation"][j])
        rows.append(row)
    if as_csv:
        from linkwright.io.exports import number_text

        lines = [",".join(head)] + [",".join(number_text(v) for v in r) for r in rows]
        sys.stdout.write("\n".join(lines) + "\n")
        return
    unit = "degrees of arc" if sphere else "length units"
    out = [
        document_heading(doc),
        f"# band of {band.point} across its curve ({unit}), first order; "
        f"{len(band.names)} parameters toleranced: {', '.join(band.names)}",
        f"# widest: ±{fmt_number(result['max_half_width']).strip()} (worst case)",
        " ".join(f"{h:>11}" for h in head),
    ]
    out += [" ".join(fmt_number(v) for v in r) for r in rows]
    sys.stdout.write("\n".join(out) + "\n")

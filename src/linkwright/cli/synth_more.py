"""More ``linkwright synth ...`` subcommands: spherical precision orientations (and, registered
on the same group, the commands that do not fit in :mod:`linkwright.cli.synth`)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from linkwright.cli.shared import (
    CliError,
    JsonOpt,
    documents_json,
    dump_json,
    mechanism_toml,
    parse_floats,
    read_points,
)
from linkwright.cli.synth import synth_app

# A typed-in rotation matrix (a few decimals) is not orthogonal to machine precision: up to this
# departure of QᵀQ from I it is projected onto the nearest rotation; beyond it, it is a typo.
ROUNDED_ROTATION_TOL = 1e-5
# The most cone samples `orientations` will print (each one solves a 3 × 3 SVD per root).
MAX_CONE_SAMPLES = 100_000


def orientations_from_rows(rows: list[list[float]], where: str) -> Any:
    """Rotation matrices (n, 3, 3) from file rows: 9 numbers (a matrix, row by row) or 4 (a unit
    axis x, y, z and an angle in degrees, right-handed about the axis)."""
    import numpy as np

    out = []
    for j, row in enumerate(rows, start=1):
        if len(row) == 4:
            axis = np.asarray(row[:3])
            n = float(np.linalg.norm(axis))
            if n == 0.0:
                raise CliError(f"{where}: orientation {j}: the axis is the zero vector")
            k = axis / n
            a = np.radians(row[3])
            kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
            # Rodrigues: R = I + sin a [k]× + (1 − cos a) [k]×².
            out.append(np.eye(3) + np.sin(a) * kx + (1.0 - np.cos(a)) * (kx @ kx))
        else:
            q = np.reshape(np.asarray(row, dtype=float), (3, 3))
            off = float(np.abs(q.T @ q - np.eye(3)).max())
            if off > ROUNDED_ROTATION_TOL or np.linalg.det(q) <= 0:
                raise CliError(
                    f"{where}: orientation {j} is not a rotation matrix (|QᵀQ − I| = {off:.3g}, "
                    f"det = {np.linalg.det(q):.6g})"
                )
            u, _, vt = np.linalg.svd(q)
            out.append(u @ vt)  # the nearest rotation (polar factor)
    return np.stack(out)


def _spherical_report(design: Any) -> dict[str, Any]:
    from dataclasses import replace

    import numpy as np

    # Its start, the input at the first orientation, names the circuit that passes them.
    return {
        "mechanism": replace(design.mechanism, start=float(np.asarray(design.inputs).ravel()[0])),
        "rotation": np.asarray(design.rotation).tolist(),
        "inputs_deg": np.degrees(design.inputs).tolist(),
        "branches": np.asarray(design.branches).astype(int).tolist(),
        "branch_defect": bool(design.branch_defect),
        "orientation_error": float(np.max(design.orientation_error)),
        "point_error": float(np.max(design.point_error)),
    }


@synth_app.command("orientations")
def synth_orientations(
    poses: Annotated[
        Path,
        typer.Option(
            "--poses",
            metavar="FILE.csv",
            help="3 or 4 orientations, one a row: a rotation matrix (9 numbers, row by row) or "
            "an axis and angle (x, y, z, angle_deg).",
        ),
    ],
    sphere: Annotated[
        bool, typer.Option("--sphere", help="Spherical orientations (the only kind here).")
    ] = False,
    circles: Annotated[
        str | None,
        typer.Option(
            "--circles",
            metavar="X1,Y1,Z1,X2,Y2,Z2",
            help="3 orientations: the two moving axes (crank's first), as in orientation 1.",
        ),
    ] = None,
    t: Annotated[
        str | None,
        typer.Option(
            "--t",
            metavar="T1,T2",
            help="4 orientations: each dyad's plane angle on the cone (deg, in [0, 180)).",
        ),
    ] = None,
    root: Annotated[
        str, typer.Option("--root", metavar="I,J", help="4 orientations: each dyad's root, 0 or 1.")
    ] = "0,0",
    point: Annotated[
        str,
        typer.Option("--point", metavar="X,Y,Z", help="The coupler point, body coordinates."),
    ] = "1,0,0",
    samples: Annotated[
        int,
        typer.Option(
            "--samples",
            metavar="N",
            min=2,
            max=MAX_CONE_SAMPLES,
            help="4 orientations without --t: planes at which the cones are printed.",
        ),
    ] = 180,
    as_json: JsonOpt = False,
) -> None:
    """Spherical Burmester synthesis: a spherical four-bar guiding a body through 3 or 4
    orientations (McCarthy and Soh, ch. 7). Four orientations without --t print the
    circling-axis and centre-axis cones as CSV to choose the dyads from."""
    import numpy as np

    from linkwright.synthesis.precision import PrecisionError
    from linkwright.synthesis.spherical_precision import (
        spherical_burmester_cones,
        spherical_four_orientation_fourbar,
        spherical_three_orientation_fourbar,
    )

    if not sphere:
        raise CliError(
            "orientations: only spherical orientations are synthesised here: give --sphere "
            "(planar poses: `linkwright synth motion`)"
        )
    q = orientations_from_rows(read_points(poses, (4, 9)), str(poses))
    p = parse_floats(point, "--point", 3)
    try:
        if len(q) == 3:
            if t is not None:
                raise CliError("--t: is for 4 orientations; 3 take --circles")
            if circles is None:
                raise CliError("3 orientations: give the moving axes with --circles "
                               "X1,Y1,Z1,X2,Y2,Z2")  # fmt: skip
            c = np.reshape(parse_floats(circles, "--circles", 6), (2, 3))
            design = spherical_three_orientation_fourbar(q, c, point=p)
        elif len(q) == 4:
            if circles is not None:
                raise CliError("--circles: is for 3 orientations; 4 take --t and --root")
            if t is None:
                from linkwright.io.exports import number_text

                cones = spherical_burmester_cones(q, samples)
                out = ["t_deg,root,circle_x,circle_y,circle_z,centre_x,centre_y,centre_z"]
                for k in range(2):
                    for i in np.flatnonzero(cones.valid[k]):
                        cells = (np.degrees(cones.t[i]), k, *cones.circles[k, i],
                                 *cones.centres[k, i])  # fmt: skip
                        out.append(",".join(number_text(float(v)) for v in cells))
                sys.stdout.write("\n".join(out) + "\n")
                return
            roots = [int(v) for v in parse_floats(root, "--root", 2)]
            if any(v not in (0, 1) for v in roots):
                raise CliError("--root: each must be 0 or 1")
            tt = np.radians(parse_floats(t, "--t", 2, angle=True))
            design = spherical_four_orientation_fourbar(q, tt, roots, point=p)
        else:
            raise CliError(f"--poses: 3 or 4 orientations, got {len(q)}")
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = documents_json(_spherical_report(design))
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    lines = [
        "inputs (deg): " + ", ".join(f"{v:.6g}" for v in report["inputs_deg"]),
        "in its paper's frame: x' = R·x, R = " + str(np.round(design.rotation, 12).tolist()),
    ]
    if report["branch_defect"]:
        lines.append("warning: branch defect (the orientations need different assembly modes: "
                     f"{report['branches']})")  # fmt: skip
    lines.append(f"largest error: orientation {report['orientation_error']:.2e} rad, point "
                 f"{report['point_error']:.2e}")  # fmt: skip
    lines.append(mechanism_toml(report["mechanism"]))
    sys.stdout.write("\n".join(lines) + "\n")


@synth_app.command("pareto")
def synth_pareto(
    family: Annotated[
        str, typer.Option("--family", metavar="F", help="fourbar, slidercrank, geared-fivebar …")
    ],
    points: Annotated[
        Path, typer.Option("--points", metavar="FILE.csv", help="Target points: rows x, y.")
    ],
    objectives: Annotated[
        str,
        typer.Option(
            "--objectives",
            metavar="error,X",
            help="error and one of transmission (min transmission angle, maximised) or size "
            "(longest link over the targets' diameter, minimised).",
        ),
    ] = "error,transmission",
    levels: Annotated[
        int, typer.Option("--levels", metavar="N", min=2, max=20, help="ε-constraint levels.")
    ] = 6,
    budget: Annotated[
        float, typer.Option("--budget", metavar="SECONDS", min=1.0, max=86_400.0)
    ] = 30.0,
    seed: Annotated[int, typer.Option("--seed", metavar="N", min=0)] = 0,
    no_timing: Annotated[
        bool, typer.Option("--no-timing", help="Nearest-point fit (default: free timing).")
    ] = False,
    closed: Annotated[bool, typer.Option("--closed", help="The points lie on a closed curve.")] = (
        False
    ),
    plot: Annotated[
        Path | None, typer.Option("--plot", metavar="OUT.png", help="Draw the front.")
    ] = None,
    as_json: JsonOpt = False,
    quiet: Annotated[bool, typer.Option("--quiet", help="No progress bar.")] = False,
) -> None:
    """Multi-objective path synthesis: the Pareto front of path error against a second
    objective, by an ε-constraint sweep of path-synthesis runs sharing --budget."""
    import numpy as np

    from linkwright.cli.shared import Progress
    from linkwright.synthesis.pareto import ParetoError, pareto_path
    from linkwright.synthesis.path import PathSynthesisError

    objs = tuple(o.strip() for o in objectives.split(","))
    if plot is not None and plot.suffix.lower() != ".png":
        raise CliError(f"--plot: writes a PNG, got {plot.name!r}")
    pts = read_points(points, (2,))
    try:
        with Progress("front", quiet) as progress:
            front = pareto_path(family, pts, objectives=objs, levels=levels, budget=budget,
                                seed=seed, timing="none" if no_timing else None, closed=closed,
                                progress=progress)  # fmt: skip
    except (ParetoError, PathSynthesisError) as exc:
        raise CliError(str(exc)) from None
    second = objs[1]
    report = documents_json({
        "objectives": list(objs),
        "designs": [
            {"error": d.error, second: d.second, "level": d.level, "inputs_deg":
             [float(v) for v in np.degrees(d.inputs)], "mechanism": d.mechanism}
            for d in front
        ],
    })  # fmt: skip
    if plot is not None:
        _plot_front(front, second, plot)
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    out = [f"# Pareto front: {len(front)} designs, error (sum of squared distances) and {second}"]
    for k, d in enumerate(report["designs"]):
        out.append(f"## design {k}: error {d['error']:.6g}, {second} {d[second]:.6g}")
        out.append(mechanism_toml(d["mechanism"]))
    sys.stdout.write("\n".join(out) + "\n")


def _plot_front(front: Any, second: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    xs = [d.error for d in front]
    ys = [d.second for d in front]
    ax.plot(xs, ys, "o-")
    for k, (x, y) in enumerate(zip(xs, ys, strict=True)):
        ax.annotate(str(k), (x, y), textcoords="offset points", xytext=(4, 4))
    ax.set_xscale("log")
    ax.set_xlabel("path error (sum of squared distances)")
    ax.set_ylabel("least transmission angle (deg)" if second == "transmission"
                  else "longest link / targets' diameter")  # fmt: skip
    ax.set_title("Pareto front (labels: design numbers)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)

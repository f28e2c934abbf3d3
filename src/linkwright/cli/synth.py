"""``linkwright synth ...``: from an ellipse, a path, target values or precision points to a
linkage."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any

import typer

from linkwright.cli.shared import (
    CliError,
    FileArg,
    JsonOpt,
    Progress,
    QuietOpt,
    app,
    decimal_text,
    documents_json,
    dump_json,
    family_and_template,
    fmt_number,
    load_file,
    mechanism_toml,
    parse_floats,
    read_points,
    sphere_directions,
    sphere_text,
)

synth_app = typer.Typer(
    help="Synthesis: from an ellipse, a path, target values or precision points to a linkage.",
    no_args_is_help=True,
)
app.add_typer(synth_app, name="synth")


@synth_app.command("ellipse")
def synth_ellipse(
    conic: Annotated[
        str | None,
        typer.Option(
            "--conic",
            metavar="A,B,C,D,E,F",
            help="Ellipse A·x² + B·xy + C·y² + D·x + E·y + F = 0 (any scale).",
        ),
    ] = None,
    points: Annotated[
        Path | None,
        typer.Option("--points", metavar="FILE.csv", help="Points to fit an ellipse to."),
    ] = None,
    family_samples: Annotated[
        int,
        typer.Option(
            "--family-samples",
            metavar="N",
            min=0,
            max=10_000,
            help="Members of the ∞² double-slider family to list.",
        ),
    ] = 0,
    circle: Annotated[
        str,
        typer.Option(
            "--circle",
            metavar="small|large",
            help="Which Cardan circle the family rolls: radius (a − b)/2 (paper 004's "
            "section 4) or (a + b)/2.",
        ),
    ] = "small",
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Double sliders (elliptic trammels) tracing an ellipse (paper 004): the canonical one and
    members of a whole ∞² family, each as a document, with the traced curve's deviation.

    Every double slider tracing the ellipse rolls one of two Cardan circles, so the ∞²
    solutions come in two families (--circle)."""
    from linkwright.synthesis.ellipse import EllipseError, ellipse_synthesis

    if (conic is None) == (points is None):
        raise CliError("give the ellipse as --conic A,B,C,D,E,F or as --points FILE.csv")
    if circle not in ("small", "large"):
        raise CliError(f"--circle: must be small or large, got {circle!r}")
    coeffs = parse_floats(conic, "--conic", 6) if conic is not None else None
    pts = read_points(points) if points is not None else None
    try:
        with Progress("double sliders", quiet or family_samples < 50) as progress:
            result = ellipse_synthesis(
                coeffs, pts, family_samples, circle=circle, progress=progress
            )
    except EllipseError as exc:
        raise CliError(str(exc)) from None
    result = documents_json(result)
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    t = result["trammel"]
    out = [
        f"# ellipse: centre ({fmt_number(t['X0']).strip()}, {fmt_number(t['Y0']).strip()}), "
        f"axis angle {fmt_number(t['beta_deg']).strip()} deg, "
        f"semi-axes a = {fmt_number(t['a']).strip()}, "
        f"b = {fmt_number(t['b']).strip()}"
    ]
    if "fit" in result:
        f = result["fit"]
        out.append(f"# fitted to {f['count']} points: RMS distance {f['rms']:.3g}, "
                   f"max {f['max']:.3g}")  # fmt: skip
    out.append(f"canonical trammel: deviation {result['canonical']['deviation']:.2e} (of a)")
    out.append(mechanism_toml(result["canonical"]["mechanism"]))
    for member in result["family"]:
        s1, s2 = member["slider_angles_deg"]
        out.append(f"family member ({result['circle']} circle), guides at {s1:g} and {s2:g} deg "
                   f"from the major axis: deviation {member['deviation']:.2e}")  # fmt: skip
    sys.stdout.write("\n".join(out) + "\n")


def _assignments(items: Sequence[str], what: str) -> dict[str, str]:
    """``name=value`` items (each may itself be a comma list) as a dict of strings."""
    out: dict[str, str] = {}
    for item in items:
        for part in [p for p in item.split(",") if p.strip()] if "=" in item else [item]:
            if "=" not in part:
                raise CliError(f"{what}: expected name=value, got {part!r}")
            name, value = (t.strip() for t in part.split("=", 1))
            if name in out:
                raise CliError(f"{what}: {name} given twice")
            out[name] = value
    return out


def _bounds(items: Sequence[str]) -> dict[str, tuple[float, float]]:
    """``--bound NAME=LOW:HIGH`` items as {name: (low, high)}, in the units given."""
    bounds: dict[str, tuple[float, float]] = {}
    for name, text in _assignments(items, "--bound").items():
        low, sep, high = text.partition(":")
        if not sep:
            raise CliError(f"--bound {name}: expected LOW:HIGH, got {text!r}")
        bounds[name] = (float(decimal_text(low, "--bound")), float(decimal_text(high, "--bound")))
    return bounds


@synth_app.command("targets")
def synth_targets(
    family: Annotated[
        str, typer.Option("--family", metavar="fourbar|spherical-fourbar", help="Family.")
    ],
    fix: Annotated[
        list[str],
        typer.Option(
            "--fix",
            metavar="LINK=VALUE[,…]",
            help="Fixed links (crank, coupler, rocker, frame); arcs in degrees.",
        ),
    ],
    free: Annotated[
        str, typer.Option("--free", metavar="LINK[,…]", help="The links to solve for.")
    ],
    target: Annotated[
        list[str],
        typer.Option(
            "--target",
            metavar="OUTPUT=VALUE",
            help="max_Kw, max_Ke, max_Kp, delta, time_ratio, swing, gamma_min, "
            "gamma_max (angles in degrees).",
        ),
    ],
    bound: Annotated[
        list[str] | None,
        typer.Option("--bound", metavar="LINK=LOW:HIGH", help="Search box of a free link."),
    ] = None,
    kind: Annotated[
        str | None,
        typer.Option("--kind", metavar="CLASS", help="Only this class, e.g. double-crank."),
    ] = None,
    grid: Annotated[
        int | None,
        typer.Option("--grid", metavar="N", min=3, max=400, help="Grid nodes per free link."),
    ] = None,
    tol: Annotated[float, typer.Option("--tol", metavar="T", min=0.0)] = 1e-9,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Every four-bar in the search box whose named outputs hit their target values (paper
    003's synthesis), with each solution's conditioning; least squares with more targets than
    free links."""
    from linkwright.synthesis.targets import TargetError, design_fourbar

    fixed = {k: float(decimal_text(v, f"--fix {k}")) for k, v in _assignments(fix, "--fix").items()}
    goals = {
        k: float(decimal_text(v, f"--target {k}"))
        for k, v in _assignments(target, "--target").items()
    }
    bounds = _bounds(bound or [])
    names = [n.strip() for n in free.split(",") if n.strip()]
    from linkwright.cli.budget import check_grid

    check_grid(family, grid, len(names), len(goals))
    try:
        with Progress("searching", quiet) as progress:
            found = design_fourbar(
                family, fixed, names, goals, bounds=bounds or None, kind=kind, grid=grid,
                tol=tol, degrees=True, progress=progress,
            )  # fmt: skip
    except TargetError as exc:
        raise CliError(str(exc)) from None
    report = found.report()
    for entry, solution in zip(report["solutions"], found, strict=True):
        entry["mechanism"] = solution.mechanism
    report = documents_json(report)
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    out = [f"# {len(report['solutions'])} solution(s) in the box; {report['evaluated']} grid "
           f"points evaluated"]  # fmt: skip
    for i, sol in enumerate(report["solutions"], start=1):
        units = report["units"]
        xs = ", ".join(f"{k} = {v:.6g} {units.get(k, '')}".rstrip() for k, v in sol["x"].items())
        vals = ", ".join(f"{k} = {v:.6g}" for k, v in sol["values"].items())
        out.append(f"solution {i}: {xs}; {vals}; residual {sol['residual']:.2e}, condition "
                   f"{sol['condition']:.3g}")  # fmt: skip
    sys.stdout.write("\n".join(out) + "\n")


@synth_app.command("reinsberg")
def synth_reinsberg(
    file: FileArg,
    solve_for: Annotated[
        str,
        typer.Option(
            "--solve",
            metavar="LINK",
            help="The link to solve for: crank, coupler, rocker or frame.",
        ),
    ],
    kind: Annotated[
        str | None,
        typer.Option("--kind", metavar="CLASS", help="Only a root of this class counts."),
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Complete a four-bar to Reinsberg's optimal transmission (paper 003): the one length or
    arc that makes the extreme transmission angles sum to 180°."""
    import numpy as np

    from linkwright.mechanisms import FourBar, SphericalFourBar
    from linkwright.synthesis.reinsberg import (
        ReinsbergError,
        reinsberg_defect,
        reinsberg_mechanism,
    )

    doc = load_file(file)
    mech = doc.mechanism
    if not isinstance(mech, FourBar | SphericalFourBar):
        raise CliError(f"reinsberg: a fourbar or spherical-fourbar document, not {mech.family}")
    try:
        done = reinsberg_mechanism(mech, solve_for, kind=kind)
    except (ReinsbergError, ValueError) as exc:
        raise CliError(str(exc)) from None
    value = float(np.asarray(getattr(done, solve_for)))
    arc = isinstance(mech, SphericalFourBar)
    result = {
        "before_deg": float(np.degrees(reinsberg_defect(mech))),
        "field": solve_for,
        "value": float(np.degrees(value)) if arc else value,
        "unit": "deg" if arc else "length",
        "after_deg": float(np.degrees(reinsberg_defect(done))),
        "mechanism": done,
    }
    result = documents_json(result)
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    unit = " deg" if arc else ""
    sys.stdout.write(
        f"{solve_for} = {result['value']:.9g}{unit}: γ1 + γ2 − 180° goes from "
        f"{fmt_number(result['before_deg'], 0, 6)} to {fmt_number(result['after_deg'], 0, 9)} deg\n"
        + mechanism_toml(result["mechanism"])
        + "\n"
    )


def design_report(design: Any, index: tuple[int, ...] = ()) -> dict[str, Any]:
    """A precision design (one of a batch at ``index``) as plain values, angles in degrees."""
    import numpy as np

    from linkwright.mechanisms import FourBar

    mech = design.mechanism
    params = {k: np.asarray(v)[index] if np.ndim(v) > (1 if k in ("A0", "B0") else 0) else v
              for k, v in mech.params().items()}  # fmt: skip
    inputs = np.asarray(design.inputs)[index]
    # Its start, the input at the first position, names the circuit that passes them.
    one = FourBar(**{k: params[k] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v",
                                              "assembly")}, start=float(inputs[0]))  # fmt: skip
    out: dict[str, Any] = {
        "inputs_deg": np.degrees(inputs),
        "branches": np.asarray(design.branches)[index].astype(int),
        "branch_defect": bool(np.asarray(design.branch_defect)[index]),
        "order_defect": bool(np.asarray(design.order_defect)[index]),
        "mechanism": one,
    }
    if hasattr(design, "position_error"):
        out["position_error"] = float(np.max(np.asarray(design.position_error)[index]))
        out["angle_error_deg"] = float(np.degrees(np.max(np.asarray(design.angle_error)[index])))
    else:
        out["outputs_deg"] = np.degrees(np.asarray(design.outputs)[index])
        out["coefficients"] = np.asarray(design.coefficients)[index]
        out["error_deg"] = float(np.degrees(np.max(np.asarray(design.error)[index])))
    return out


def design_text(report: Mapping[str, Any]) -> str:
    lines = ["inputs (deg): " + ", ".join(f"{v:.6g}" for v in report["inputs_deg"])]
    if report["branch_defect"]:
        lines.append("warning: branch defect (the positions need different assembly modes)")
    if report["order_defect"]:
        lines.append("warning: order defect (one sweep of the input does not meet them in order)")
    if "position_error" in report:
        lines.append(f"largest error: position {report['position_error']:.2e} (of the spread), "
                     f"angle {report['angle_error_deg']:.2e} deg")  # fmt: skip
    else:
        lines.append(f"largest output error: {report['error_deg']:.2e} deg")
    lines.append(mechanism_toml(report["mechanism"]))
    return "\n".join(lines)


def angle_pairs(text: str, what: str, width: int = 2) -> list[list[float]]:
    """Rows of ``width`` numbers from "a,b;c,d;…" (or one row a line), checked as ``what``."""
    rows = [r for r in text.replace("\n", ";").split(";") if r.strip()]
    return [parse_floats(r, what, width) for r in rows]


@synth_app.command("motion")
def synth_motion(
    poses: Annotated[
        Path,
        typer.Option(
            "--poses",
            metavar="FILE.csv",
            help="Rows x, y, angle_deg: the coupler point and the body's angle.",
        ),
    ],
    circles: Annotated[
        str | None,
        typer.Option(
            "--circles",
            metavar="X1,Y1,X2,Y2",
            help="3 poses: the two moving pivots, in the first pose.",
        ),
    ] = None,
    beta2: Annotated[
        str | None,
        typer.Option(
            "--beta2",
            metavar="B1,B2",
            help="4 poses: the two dyads' β2 on the centre-point curve (deg).",
        ),
    ] = None,
    closure: Annotated[
        str, typer.Option("--closure", metavar="I,J", help="4 poses: each dyad's closure, 0 or 1.")
    ] = "0,0",
    pair: Annotated[
        int | None,
        typer.Option("--pair", metavar="K", min=0, help="5 poses: print only design K."),
    ] = None,
    approximate: Annotated[
        bool,
        typer.Option(
            "--approximate",
            help="Least squares for any number of poses (the default from 6): the four-bars, "
            "slider-cranks and double sliders that come closest, ranked.",
        ),
    ] = False,
    angle_weight: Annotated[
        float,
        typer.Option(
            "--angle-weight",
            metavar="W",
            min=0.0,
            max=1e6,
            help="Least squares: how much a radian of angle error weighs against the poses' "
            "spread.",
        ),
    ] = 1.0,
    top: Annotated[
        int, typer.Option("--top", metavar="K", min=1, max=100, help="Least squares: designs.")
    ] = 5,
    as_json: JsonOpt = False,
) -> None:
    """Motion generation: a four-bar guiding a body through 3, 4 or 5 poses exactly
    (Burmester; four poses without --beta2 print the centre-point and circle-point curves as
    CSV), or, from 6 poses or with --approximate, the four-bars, slider-cranks and double
    sliders that come closest to them (least squares over poses)."""
    import numpy as np

    from linkwright.cli.synth_motion_fit import MAX_POSES, approximate_report, approximate_text
    from linkwright.synthesis.burmester import (
        burmester_fourbars,
        burmester_points,
        centre_point_curve,
        four_pose_fourbar,
    )
    from linkwright.synthesis.precision import PrecisionError, three_pose_fourbar

    rows = np.array(read_points(poses, (3,)))
    points, angles = rows[:, :2], np.radians(rows[:, 2])
    if approximate or len(rows) > 5:
        if not 3 <= len(rows) <= MAX_POSES:
            raise CliError(f"--poses: least squares takes 3 to {MAX_POSES} poses, got {len(rows)}")
        try:
            fitted = documents_json(approximate_report(points, angles, angle_weight, top))
        except PrecisionError as exc:
            raise CliError(str(exc)) from None
        if not fitted["designs"]:
            raise CliError("no pair of fitted dyads assembles at every pose")
        sys.stdout.write(dump_json(fitted) if as_json else approximate_text(fitted) + "\n")
        return
    try:
        if len(rows) == 3:
            if circles is None:
                raise CliError("3 poses: give the moving pivots with --circles X1,Y1,X2,Y2")
            design = three_pose_fourbar(
                points, angles, np.reshape(parse_floats(circles, "--circles", 4), (2, 2))
            )
            report: Any = design_report(design)
        elif len(rows) == 4:
            if beta2 is None:
                from linkwright.io.exports import number_text

                curves = centre_point_curve(points, angles)
                out = ["beta2_deg,closure,centre_x,centre_y,circle_x,circle_y"]
                for c in range(2):
                    for i in np.flatnonzero(curves.valid[c]):
                        g, m = curves.centres[c, i], curves.circles[c, i]
                        cells = (np.degrees(curves.beta2[i]), c, g[0], g[1], m[0], m[1])
                        out.append(",".join(number_text(v) for v in cells))
                sys.stdout.write("\n".join(out) + "\n")
                return
            b = np.radians(parse_floats(beta2, "--beta2", 2))
            ij = [int(v) for v in parse_floats(closure, "--closure", 2)]
            if any(v not in (0, 1) for v in ij):
                raise CliError("--closure: each must be 0 or 1")
            report = design_report(four_pose_fourbar(points, angles, b, tuple(ij)))
        elif len(rows) == 5:
            found = burmester_points(points, angles)
            designs, pairs = burmester_fourbars(points, angles)
            count = len(pairs)
            if count == 0:
                raise CliError(
                    f"these 5 poses have {found.count} real Burmester point(s): no four-bar"
                )
            if pair is not None and pair >= count:
                raise CliError(f"--pair: there are {count} designs (0 … {count - 1})")
            chosen = range(count) if pair is None else [pair]
            report = {
                "burmester_points": int(found.count),
                "designs": [
                    {"pair": [int(v) for v in pairs[k]], **design_report(designs, (k,))}
                    for k in chosen
                ],
            }
        else:
            raise CliError(f"--poses: at least 3 poses, got {len(rows)}")
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = documents_json(report)
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    if "designs" in report:
        text = [f"# {report['burmester_points']} real Burmester points"]
        for d in report["designs"]:
            text.append(f"## design with Burmester points {d['pair']}\n" + design_text(d))
        sys.stdout.write("\n".join(text) + "\n")
    else:
        sys.stdout.write(design_text(report) + "\n")


@synth_app.command("precision-path")
def synth_precision_path(
    points: Annotated[
        Path, typer.Option("--points", metavar="FILE.csv", help="Three points x, y.")
    ],
    crank: Annotated[
        str, typer.Option("--crank-rotations", metavar="A2,A3", help="From point 1 (deg).")
    ],
    coupler: Annotated[
        str, typer.Option("--coupler-rotations", metavar="B2,B3", help="Free choice (deg).")
    ],
    rocker: Annotated[
        str, typer.Option("--rocker-rotations", metavar="G2,G3", help="Free choice (deg).")
    ],
    as_json: JsonOpt = False,
) -> None:
    """Path generation with prescribed timing: the coupler point passes three points at given
    crank rotations (the coupler's and rocker's rotations are the free choices)."""
    import numpy as np

    from linkwright.synthesis.precision import PrecisionError, path_with_timing

    pts = np.array(read_points(points))
    if len(pts) != 3:
        raise CliError(f"--points: path generation with timing takes 3 points, got {len(pts)}")
    rot = [np.radians(parse_floats(t, w, 2)) for t, w in ((crank, "--crank-rotations"),
           (coupler, "--coupler-rotations"), (rocker, "--rocker-rotations"))]  # fmt: skip
    try:
        design = path_with_timing(pts, *rot)
    except PrecisionError as exc:
        raise CliError(str(exc)) from None
    report = documents_json(design_report(design))
    if as_json:
        sys.stdout.write(dump_json(report))
        return
    sys.stdout.write(design_text(report) + "\n")


@synth_app.command("path")
def synth_path(
    points: Annotated[
        Path,
        typer.Option(
            "--points",
            metavar="FILE.csv",
            help="Target points: rows x, y (x, y, z on the sphere: unit vectors, or points on "
            "any sphere, which is fitted first).",
        ),
    ],
    family: Annotated[
        str | None,
        typer.Option(
            "--family",
            metavar="F",
            help="Any family (fourbar, slidercrank, geared-fivebar, doubleslider, watt1, watt2, "
            "stephenson1, stephenson3, linkage, spherical-fourbar, spherical-sixbar, "
            "spherical-stephenson3); default the template's.",
        ),
    ] = None,
    angles: Annotated[
        str | None,
        typer.Option(
            "--angles",
            metavar="LIST",
            help="Crank angles (deg, from the frame line) at each point.",
        ),
    ] = None,
    free_start: Annotated[
        bool,
        typer.Option(
            "--free-start",
            help="With --angles: they give the input's steps; where it starts is fitted too.",
        ),
    ] = False,
    free_timing: Annotated[
        bool, typer.Option("--free-timing", help="Unknown but monotonic input angles.")
    ] = False,
    no_timing: Annotated[
        bool, typer.Option("--no-timing", help="Nearest-point fit: no input angles at all.")
    ] = False,
    closed: Annotated[
        bool, typer.Option("--closed", help="The points lie on a closed curve.")
    ] = False,
    bound: Annotated[
        list[str] | None,
        typer.Option(
            "--bound",
            metavar="NAME=LOW:HIGH",
            help="Search bounds (lengths; arcs and angles in degrees).",
        ),
    ] = None,
    kind: Annotated[
        list[str] | None,
        typer.Option("--kind", metavar="CLASS", help="Allowed class(es), e.g. crank-rocker."),
    ] = None,
    full_turn: Annotated[
        bool, typer.Option("--full-turn", help="The input must turn fully.")
    ] = False,
    min_transmission: Annotated[
        float,
        typer.Option(
            "--min-transmission",
            metavar="DEG",
            min=0.0,
            max=90.0,
            help="Least transmission angle over the circuit.",
        ),
    ] = 0.0,
    seed: Annotated[int, typer.Option("--seed", metavar="N", min=0)] = 0,
    budget: Annotated[
        float, typer.Option("--budget", metavar="SECONDS", min=0.1, max=86_400.0)
    ] = 10.0,
    evaluations: Annotated[
        int | None,
        typer.Option(
            "--evaluations",
            metavar="N",
            min=1,
            max=100_000_000,
            help="Stop after N mechanism evaluations (with --seed: the same result on any "
            "machine, where --budget stops a slower one earlier).",
        ),
    ] = None,
    template: Annotated[
        str | None,
        typer.Option(
            "--template",
            metavar="FILE",
            help="A mechanism document: its family, structure and choices are kept and its "
            "numbers start the search (needed for --family linkage).",
        ),
    ] = None,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Path synthesis by optimisation: a global search over batched populations, then local
    least squares. Prints the error (sum of squared distances), the RMS and the mechanism."""
    import numpy as np

    from linkwright.synthesis.path import PathSynthesisError, fit_path
    from linkwright.synthesis.path_models import ModelError, model_for

    if sum((angles is not None, free_timing, no_timing)) > 1:
        raise CliError("give at most one of --angles, --free-timing and --no-timing")
    if free_start and angles is None:
        raise CliError("--free-start frees where the --angles start: give --angles too")
    family, like = family_and_template(family, template, "its numbers are free")
    try:
        model = model_for(family, like)
    except ModelError as exc:
        raise CliError(str(exc)) from None
    timing = "prescribed" if angles is not None else "none" if no_timing else "free"
    pts = np.array(read_points(points, (2, 3)))
    sphere = None
    if model.space == "sphere":
        pts, sphere = sphere_directions(pts)
    given = np.radians(parse_floats(angles, "--angles", angle=True)) if angles is not None else None
    in_degrees = ANGLE_BOUNDS | set(getattr(model, "angles", ()))
    bounds = {
        name: (math.radians(lo), math.radians(hi))
        if name in in_degrees or model.space == "sphere"  # on the sphere: all angles
        else (lo, hi)
        for name, (lo, hi) in _bounds(bound or []).items()
    }
    constraints = {
        "classes": tuple(kind or ()),
        "full_turn": full_turn,
        "min_transmission": math.radians(min_transmission),
    }
    try:
        with Progress("searching", quiet) as progress:
            fit = fit_path(
                family, pts, angles=given, timing=timing, closed=closed, bounds=bounds or None,
                constraints=constraints, seed=seed, budget=budget, progress=progress,
                template=like, max_evaluations=evaluations, free_start=free_start,
            )  # fmt: skip
    except PathSynthesisError as exc:
        raise CliError(str(exc)) from None
    # A family with a triad on the sphere stands in its paper's frame (no composed linkage
    # holds a triad): the rotation carries its curve onto the points.
    own_frame = fit.rotation is not None and fit.mechanism is fit.named
    result = documents_json({
        **({"sphere": sphere} if sphere is not None else {}),
        "error": fit.error,
        "rms": fit.rms,
        **({"rotation": np.asarray(fit.rotation).tolist()} if own_frame else {}),
        "mechanism": fit.mechanism,
        "inputs_deg": np.degrees(fit.inputs),
        "angles_deg": np.degrees(fit.angles),
        "distances": fit.distances,
        # Targets nearest the circuit's return leg: each dyad's sign at each target.
        **({"branches": {k: np.asarray(v).astype(int) for k, v in fit.branches.items()}}
           if fit.branches is not None else {}),
        "seconds": fit.elapsed,
        "evaluations": fit.evaluations,
        "stopped": fit.stopped,
    })  # fmt: skip
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    sys.stdout.write(
        sphere_text(sphere)
        + f"error {fit.error:.6g} (sum of squared distances), RMS {fit.rms:.6g}; "
        f"{fit.evaluations} linkages in {fit.elapsed:.1f} s, stopped at the {fit.stopped}\n"
        + "inputs (deg): "
        + ", ".join(f"{v:.6g}" for v in result["inputs_deg"])
        + "\n"
        + (
            "nearest on the circuit's return leg: "
            + "; ".join(
                f"{k} signs {np.asarray(v).astype(int).tolist()}" for k, v in fit.branches.items()
            )
            + "\n"
            if fit.branches is not None
            else ""
        )
        + (
            "in its paper's frame: the points are R·(its traced point), R = "
            + str(np.round(np.asarray(fit.rotation), 12).tolist())
            + "\n"
            if own_frame
            else ""
        )
        + mechanism_toml(result["mechanism"])
        + "\n"
    )


# Path-synthesis bounds given in degrees on the command line.
ANGLE_BOUNDS = frozenset({"frame_angle", "gear_phase", "point_angle"})

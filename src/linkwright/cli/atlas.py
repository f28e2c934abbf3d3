"""``linkwright atlas ...``: build a curve atlas, describe it, match a curve against it."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import typer

from linkwright.cli.shared import (
    CliError,
    JsonOpt,
    Progress,
    QuietOpt,
    app,
    documents_json,
    dump_json,
    family_and_template,
    mechanism_toml,
    read_points,
    sphere_directions,
    sphere_text,
)

atlas_app = typer.Typer(
    help="The curve atlas: build one, match a curve against it, describe it.",
    no_args_is_help=True,
)
app.add_typer(atlas_app, name="atlas")

AtlasFamilyOpt = Annotated[
    str,
    typer.Option("--family", metavar="F", help="fourbar, geared-fivebar or spherical-fourbar."),
]


@atlas_app.command("build")
def atlas_build(
    count: Annotated[int, typer.Option("--count", metavar="N", min=1, help="Mechanisms.")],
    out: Annotated[Path, typer.Option("--out", metavar="DIR", help="The atlas directory.")],
    family: Annotated[
        str | None,
        typer.Option(
            "--family",
            metavar="F",
            help="Any family (fourbar, geared-fivebar, spherical-fourbar with their own "
            "distributions; the others by their parameters); default the template's.",
        ),
    ] = None,
    seed: Annotated[int, typer.Option("--seed", metavar="S", min=0)] = 0,
    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            metavar="N",
            min=0,
            help="Local Dask worker processes (0: this process). Default: one per core.",
        ),
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler."),
    ] = None,
    shard_size: Annotated[
        int, typer.Option("--shard-size", metavar="N", min=1, help="Mechanisms per shard.")
    ] = 65_536,
    samples: Annotated[
        int, typer.Option("--samples", metavar="N", min=8, help="Curve samples per turn.")
    ] = 64,
    template: Annotated[
        str | None,
        typer.Option(
            "--template",
            metavar="FILE",
            help="A mechanism document whose structure and choices the atlas keeps (needed "
            "for --family linkage; a Stephenson III's gives its input).",
        ),
    ] = None,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Sample a family's designs, keep those whose input turns fully, trace and describe their
    curves in shards (Dask tasks) and index them. A killed build resumes where it stopped."""
    from linkwright.atlas import AtlasBuildError, build

    family, like = family_and_template(family, template, "its numbers are drawn about its own")
    try:
        with Progress("building", quiet) as progress:
            manifest = build(
                family, count, out, seed=seed, shard_size=shard_size, samples=samples,
                workers=workers, scheduler=scheduler, progress=progress, template=like,
            )  # fmt: skip
    except AtlasBuildError as exc:
        raise CliError(str(exc)) from None
    except KeyboardInterrupt:
        raise CliError(
            "interrupted: finished shards are kept; run the same command again to resume"
        ) from None
    if as_json:
        sys.stdout.write(dump_json({"path": str(out), **manifest}))
        return
    sys.stdout.write(_atlas_summary(out, manifest))


def _atlas_summary(path: Path, manifest: Mapping[str, Any]) -> str:
    spec, index, figures = manifest["spec"], manifest["index"], manifest["build"]
    rate = figures["curves_computed"] / max(figures["seconds_shards"], 1e-9)
    probe = f", nprobe {index['nprobe']} of {index['nlist']} lists" if index["nlist"] else ""
    return (
        f"{path}: {spec['count']} {spec['family']} curves (seed {spec['seed']}) in "
        f"{len(manifest['shards'])} shards, {figures['bytes'] / 1e6:.1f} MB\n"
        + (
            f"index: {index['kind']}{probe}; recall@10 against exact search "
            f"{index['recall_at_10']:.3f} on {index['tuning_queries']} held-out curves\n"
            if index["tuning_queries"]
            else f"index: {index['kind']}; recall@10 1 (an exact search finds every neighbour: "
            "nothing to tune)\n"
        )
        + f"built {figures['curves_computed']} curves in {figures['seconds_shards']:.1f} s "
        f"({rate:.3g} curves/s), {figures['seconds_total']:.1f} s with the index; "
        f"{figures['shards_resumed']} shards resumed\n"
    )


@atlas_app.command("info")
def atlas_info(
    directory: Annotated[Path, typer.Argument(metavar="DIR", help="An atlas directory.")],
    quick: Annotated[
        bool,
        typer.Option(
            "--quick",
            help="Check the files against the manifest by their digest files and headers only, "
            "without re-hashing every shard (which reads the whole atlas).",
        ),
    ] = False,
    as_json: JsonOpt = False,
) -> None:
    """What an atlas holds: family, size, shards, index and the figures of its build, once its
    manifest, build.json, shards and index are checked against one another."""
    from linkwright.atlas import AtlasError, open_atlas

    try:
        atlas = open_atlas(directory, hashes=not quick)
    except AtlasError as exc:
        raise CliError(str(exc)) from None
    if as_json:
        sys.stdout.write(dump_json({"path": str(directory), **atlas.manifest}))
        return
    sys.stdout.write(_atlas_summary(directory, atlas.manifest))


@atlas_app.command("query")
def atlas_query(
    points: Annotated[
        Path,
        typer.Option(
            "--points",
            metavar="FILE.csv",
            help="The curve: rows x, y (x, y, z for a spherical atlas: unit vectors, or points "
            "on any sphere, which is fitted first).",
        ),
    ],
    directory: Annotated[
        Path | None,
        typer.Argument(metavar="[DIR]", help="An atlas directory; default the built-in one."),
    ] = None,
    family: Annotated[
        str,
        typer.Option("--family", metavar="F", help="The built-in atlas's family (without DIR)."),
    ] = "fourbar",
    top: Annotated[int, typer.Option("--top", metavar="K", min=1, max=1000)] = 5,
    refine: Annotated[
        bool, typer.Option("--refine", help="Optimise the best matches locally.")
    ] = False,
    open_curve: Annotated[
        bool,
        typer.Option(
            "--open",
            help="The points are an open curve, a piece of the curve wanted.",
        ),
    ] = False,
    tolerance: Annotated[
        float,
        typer.Option(
            "--tolerance",
            metavar="FRACTION",
            min=1e-9,
            max=1.0,
            help="Refine until the RMS distance is this fraction of the curve's size.",
        ),
    ] = 0.001,
    budget: Annotated[
        float, typer.Option("--budget", metavar="SECONDS", min=0.01, max=3600.0)
    ] = 5.0,
    as_json: JsonOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Match a closed curve (or, with --open, a piece of one) against an atlas: the best
    mechanisms, each placed where the curve was drawn, with its aligned error and the transform
    from the atlas."""
    import numpy as np

    from linkwright.atlas import (
        AtlasBuildError,
        AtlasError,
        AtlasQueryError,
        default_atlas,
        open_atlas,
        query,
    )

    pts, sphere = sphere_directions(np.array(read_points(points, (2, 3))))
    try:
        with Progress("matching", quiet) as progress:
            atlas = open_atlas(directory) if directory is not None else default_atlas(family)
            t0 = time.perf_counter()
            matches = query(
                atlas, pts, top=top, refine=refine, tolerance=tolerance, budget=budget,
                open_curve=open_curve,
                progress=progress,
            )  # fmt: skip
            elapsed = time.perf_counter() - t0
    except (AtlasError, AtlasQueryError, AtlasBuildError) as exc:
        raise CliError(str(exc)) from None
    rows = []
    for rank, m in enumerate(matches, start=1):
        transform: dict[str, Any]
        if m.translation is None:
            transform = {"rotation_matrix": np.asarray(m.rotation)}
        else:
            transform = {
                "scale": m.scale,
                "rotation_deg": math.degrees(float(m.rotation)),
                "translation": m.translation,
            }
        rows.append({
            "rank": rank,
            "atlas_id": m.atlas_id,
            "error": m.error,
            "distance": m.distance,
            "transform": transform,
            "descriptor_distance": m.descriptor_distance,
            "refined": m.refined,
            "mechanism": m.mechanism,
        })  # fmt: skip
    result = documents_json({
        **({"sphere": sphere} if sphere is not None else {}),
        "atlas": str(atlas.path),
        "family": atlas.family,
        "entries": atlas.count,
        "points": len(pts),
        "seconds": elapsed,
        "matches": rows,
    })  # fmt: skip
    if as_json:
        sys.stdout.write(dump_json(result))
        return
    lines = [sphere_text(sphere).rstrip("\n")] if sphere is not None else []
    lines.append(
        f"{len(matches)} matches from {atlas.count} {atlas.family} curves in {elapsed:.2f} s"
    )
    for row, m in zip(result["matches"], matches, strict=True):
        lines.append(
            f"#{row['rank']}  entry {m.atlas_id}: aligned error {m.error:.3%}, RMS distance "
            f"{m.distance:.4g}{' (refined)' if m.refined else ''}"
        )
    lines.append("best:\n" + mechanism_toml(result["matches"][0]["mechanism"]))
    sys.stdout.write("\n".join(lines) + "\n")

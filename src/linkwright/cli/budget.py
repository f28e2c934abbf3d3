"""The command line's cost checks, and ``solve``'s output streamed in chunks.

Every command a user can make expensive estimates its work and memory first
(:mod:`linkwright.engine.cost`, against :data:`~linkwright.engine.cost.CLI`) and refuses with
one line naming what to lower; the checks that need a mechanism are here, so that the commands
in :mod:`linkwright.cli` each call one function. ``solve`` is the exception: its answer grows
with what the user asked for (a row per input and configuration), so it is not refused for its
size but computed and written a chunk of inputs at a time (:func:`stream_solve`), its memory
bounded by the chunk.
"""

from __future__ import annotations

import contextlib
import json
import tempfile
from collections.abc import Callable, Mapping, Sequence
from typing import IO, Any

from linkwright.engine import cost

__all__ = [
    "CHUNK_BYTES",
    "check_animation",
    "check_drawing",
    "check_followed",
    "check_grid",
    "check_trace",
    "solve_chunk",
    "stream_solve",
]

CHUNK_BYTES = 64 * 2**20
"""Memory one chunk of ``solve``'s inputs may take (its engine arrays and its rows as Python
objects): 64 MiB, a few percent of the command line's budget."""
MAX_CHUNK = 65_536
OBJECT_BYTES = 220
"""Bytes of one joint's row in ``solve``'s answer held as Python objects (a list of two or
three floats and its dict entry), and again as text."""
DRAWN_POINT_BYTES = 300
"""Bytes matplotlib holds per point of a drawn curve (its path, its transformed copy)."""


def _shape(mechanism: Any, *, periodic: bool = True) -> cost.Shape | None:
    """The mechanism's cost shape, or None where it has no construction plan (a Stephenson III
    driven at its output: the command's own error says so)."""
    from linkwright.mechanisms.sixbar import NoConstructionPlan

    try:
        return cost.Shape.of_mechanism(mechanism, periodic=periodic)
    except NoConstructionPlan:
        return None


def check_trace(
    mechanism: Any,
    samples: int,
    *,
    knob: str,
    least: int = 2,
    spacing: str = "input",
    every_circuit: bool = False,
    modes: int = 1,
    order: int = 0,
    sample_bytes: float = 0.0,
) -> None:
    """Refuse tracing ``mechanism`` at ``samples`` (the option ``knob``, at least ``least``)
    where its estimate is over the command line's budget: its circuit (``every_circuit``: all
    of them, counted first by the cheap limit search), in ``modes`` assembly modes, holding
    ``sample_bytes`` more per sample for the answer."""
    shape = _shape(mechanism)
    if shape is None:
        return
    cost.check_gear(shape)
    circuits, full = 1, None
    if every_circuit:
        from linkwright.mechanisms import input_range

        arcs = input_range(mechanism)
        full = bool(arcs.full)
        circuits = 1 if full or bool(arcs.never) else int(arcs.count)

    def estimate(n: int) -> cost.Estimate:
        traced = cost.trace(
            shape, n, circuits=circuits, modes=modes, spacing=spacing, order=order, full=full
        )
        return traced.holding(modes * circuits * n * sample_bytes)

    cost.with_knob(estimate, cost.CLI, samples, least, knob).check(cost.CLI)


def check_drawing(mechanism: Any, samples: int, *, knob: str, least: int, order: int = 1) -> None:
    """Refuse a picture or a drawing (``plot``, ``export``) over the command line's budget: every
    circuit in each assembly mode it draws (both; four for two sign fields), each point held
    by matplotlib or the file writer."""
    shape = _shape(mechanism)
    if shape is None:
        return
    modes = 2 ** min(shape.dyads, 2)
    check_trace(
        mechanism,
        samples,
        knob=knob,
        least=least,
        every_circuit=True,
        modes=modes,
        order=order,
        sample_bytes=DRAWN_POINT_BYTES * 2,
    )


def check_animation(mechanism: Any, frames: int, dpi: int, *, gif: bool) -> None:
    """Refuse an animation over the command line's budget (frames × pixels, a GIF's frames
    held until written), naming ``--frames``."""
    import math

    shape = _shape(mechanism)
    if shape is None:
        return
    cost.check_gear(shape)
    step = max(1, math.ceil(360 / frames))

    def estimate(n: int) -> cost.Estimate:
        traced = cost.trace(shape, n * step)
        return cost.animation(n, dpi, gif=gif, trace_estimate=traced)

    found = estimate(frames)
    if found.fits(cost.CLI):
        return
    advice = cost.lower_to("--frames", estimate, cost.CLI, 2, frames)
    if gif:
        advice += ", lower --dpi, or write an .mp4 (its frames are not held)"
    else:
        advice += " or lower --dpi"
    found.advise(advice).check(cost.CLI)


def check_followed(mechanism: Any, points: int, knob: str = "--points") -> None:
    """Refuse tracing every circuit of every configuration over the command line's budget."""
    shape = cost.Shape.of_mechanism(mechanism)
    cost.check_combinations(shape)
    cost.with_knob(lambda n: cost.follow(shape, n), cost.CLI, points, 2, knob).check(cost.CLI)


def check_grid(family: str, grid: int | None, free: int, targets: int) -> None:
    """Refuse ``synth targets`` whose grid (``--grid`` nodes per free link) is over budget."""
    if grid is None or free < 1:
        return

    def estimate(n: int) -> cost.Estimate:
        return cost.grid(family, n, free, targets)

    cost.with_knob(estimate, cost.CLI, grid, 2, "--grid").check(cost.CLI)


# --------------------------------------------------------------------------------------------
# solve, in chunks
# --------------------------------------------------------------------------------------------


def _triad(doc: Any, all_configurations: bool, derivatives: bool) -> str | None:
    """The space of the triad solve ``solve`` runs (as :func:`linkwright.io.results.solve_document`
    chooses it), or None for a plan's sign combinations."""
    mech = doc.mechanism
    from linkwright.io.results import triad_driven

    output_driven = triad_driven(mech)
    paper001 = all_configurations and not derivatives and doc.family == "spherical-stephenson3"
    if output_driven:
        return "sphere" if doc.family.startswith("spherical-") else "plane"
    return "sphere-AB" if paper001 else None


def solve_chunk(doc: Any, samples: int, *, all_configurations: bool, derivatives: bool) -> int:
    """How many inputs ``solve`` computes at once, after refusing a solve whose engine work is
    over the command line's budget (its rows are streamed, so their number is not refused).

    Raises
    ------
    CostError
        For more assembly configurations than a ``--all`` may solve, or too much work.
    """
    order = 2 if derivatives else 0
    triad = _triad(doc, all_configurations, derivatives)
    shape = None if triad is not None else _shape(doc.mechanism, periodic=False)
    joints = len(doc.mechanism.reported_joints)
    if triad is not None:
        configurations = {"sphere": 8.0, "plane": 6.0}.get(triad, 4.0)
        engine = cost.TRIAD_BYTES[triad]
    elif shape is not None:
        if all_configurations:
            cost.check_combinations(shape)
        configurations = shape.configurations if all_configurations else 1.0
        engine = configurations * shape.joints * shape.dim * 8 * (1 + order) * cost.BYTES_FACTOR
    else:
        return 1
    per_input = engine + configurations * joints * OBJECT_BYTES * (1 + order)
    chunk = int(max(1, min(MAX_CHUNK, CHUNK_BYTES // per_input)))

    def estimate(n: int) -> cost.Estimate:
        found = cost.solve(shape, n, configurations=configurations, order=order, triad=triad)
        # Every chunk pays the engine's fixed cost again.
        calls = -(-n // chunk) * configurations * (shape.joints if shape else 1)
        return cost.Estimate(
            found.work + calls * cost.CALL_UNITS,
            min(n, chunk) * per_input,
            found.what,
        )

    knob = "the number of inputs (--input)"
    cost.with_knob(estimate, cost.CLI, samples, 1, knob).check(cost.CLI)
    return chunk


def stream_solve(
    degrees: Sequence[float],
    chunk: int,
    compute: Callable[[Sequence[float]], Mapping[str, Any]],
    render: Callable[[Mapping[str, Any]], str],
    jsonable: Callable[[Any], Any],
    out: IO[str],
    *,
    as_json: bool,
) -> None:
    """Write ``solve``'s answer for ``degrees``, computing ``chunk`` inputs at a time with
    ``compute`` (inputs → the JSON-ready result of those inputs).

    JSON: the result's keys, its ``samples`` written as they come, and a summary over all
    samples (``max_configurations``) after them; one chunk writes what one ``json.dumps`` of
    the whole result would, but for that key's place. Text: ``render`` of each chunk, whose
    sections (separated by blank lines: positions, then velocities and accelerations) are
    joined across chunks; the later sections wait in temporary files, not in memory.
    """
    if as_json:
        _stream_json(degrees, chunk, compute, jsonable, out)
    else:
        _stream_text(degrees, chunk, compute, render, out)


def _dumps(value: Any, jsonable: Callable[[Any], Any]) -> str:
    return json.dumps(jsonable(value), allow_nan=False, ensure_ascii=False)


SUMMARY_KEYS = ("max_configurations",)
"""Keys of ``solve``'s JSON that summarise every sample: written after the samples."""


def _stream_json(
    degrees: Sequence[float],
    chunk: int,
    compute: Callable[[Sequence[float]], Mapping[str, Any]],
    jsonable: Callable[[Any], Any],
    out: IO[str],
) -> None:
    summary: dict[str, int] = {}
    started = wrote = False
    for lo in range(0, max(len(degrees), 1), chunk):
        result = compute(degrees[lo : lo + chunk])
        if not started:
            head = [
                f"{_dumps(k, jsonable)}: {_dumps(v, jsonable)}"
                for k, v in result.items()
                if k != "samples" and k not in SUMMARY_KEYS
            ]
            out.write("{" + "".join(f"{h}, " for h in head) + '"samples": [')
        for key in SUMMARY_KEYS:
            if key in result:
                summary[key] = max(summary.get(key, 0), int(result[key]))
        rows = ", ".join(_dumps(s, jsonable) for s in result["samples"])
        if rows:
            out.write((", " if wrote else "") + rows)
            wrote = True
        started = True
    tail = "".join(f", {_dumps(k, jsonable)}: {v}" for k, v in summary.items())
    out.write("]" + tail + "}\n")


def _stream_text(
    degrees: Sequence[float],
    chunk: int,
    compute: Callable[[Sequence[float]], Mapping[str, Any]],
    render: Callable[[Mapping[str, Any]], str],
    out: IO[str],
) -> None:
    with contextlib.ExitStack() as stack:
        spools: list[IO[str]] = []
        for lo in range(0, max(len(degrees), 1), chunk):
            text = render(compute(degrees[lo : lo + chunk])).rstrip("\n")
            preamble, *sections = text.split("\n\n")
            if lo == 0:
                out.write(preamble)
                for i, section in enumerate(sections):
                    if i == 0:
                        out.write("\n\n" + section)
                    else:
                        spool = stack.enter_context(tempfile.TemporaryFile("w+", encoding="utf-8"))
                        spool.write("\n\n" + section)
                        spools.append(spool)
                continue
            for i, section in enumerate(sections):
                # A later chunk's section without its label and column header.
                rows = section.split("\n", 2)[2] if section.count("\n") >= 2 else ""
                if not rows:
                    continue
                if i == 0:
                    out.write("\n" + rows)
                else:
                    spools[i - 1].write("\n" + rows)
        for held in spools:
            held.seek(0)
            while block := held.read(1 << 20):
                out.write(block)
        out.write("\n")

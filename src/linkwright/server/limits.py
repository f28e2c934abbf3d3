"""Every bound the workbench puts on a request, in one table, each with the reason for its value.

The workbench computes whatever a request asks for (a scene, a study, a match), so each
quantity a client chooses is bounded: the body's size and nesting, sample counts, list sizes,
the match's top-K, string lengths. :data:`LIMITS` holds them all; the app serves the table
read-only at ``GET /api/limits``. A request over a limit is answered 413 (the body's size) or
422 (anything else) with ``{"error": "..."}`` naming the field and the limit. The server's own
bounds (work at once, connections, time to send a request) are in the table too; past those
the answer is 503 with ``Retry-After`` or 408.

Examples
--------
>>> LIMITS["samples"].value, LIMITS["samples"].least
(4096, 8)
>>> check_document({"format": "linkwright/1", "title": "x" * 1001, "mechanism": {}})
Traceback (most recent call last):
...
linkwright.server.limits.LimitError: document: title: 1,001 characters, at most 1,000 allowed
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from linkwright.engine import cost as _cost
from linkwright.io import sketch_checks as _sketch

# Measured on the bytes in one linear pass (its own module: see there why not a regex).
from linkwright.server.scan import json_depth

__all__ = [
    "BODY_BYTES",
    "BODY_SECONDS",
    "CONNECTIONS",
    "DOCUMENT_LIST",
    "ELLIPSE_FAMILY",
    "GEAR_TURNS",
    "HEADER_SECONDS",
    "JSON_DEPTH",
    "LIMITS",
    "MATCH_TOP",
    "NAME",
    "POINTS",
    "REFINE_POINTS",
    "REQUEST_BYTES",
    "REQUEST_SECONDS",
    "REQUEST_WORK",
    "SAMPLES",
    "SKETCH_DRIVERS",
    "SKETCH_JOINTS",
    "SKETCH_LINKS",
    "SKETCH_LINK_JOINTS",
    "STUDY_STEPS",
    "TEXT",
    "TITLE",
    "WORK_QUEUE",
    "WORK_SLOTS",
    "WORK_WAIT",
    "Limit",
    "LimitError",
    "as_json",
    "check_document",
    "json_depth",
    "over",
]


class LimitError(ValueError):
    """A request over one of the workbench's limits (the message names the field and the
    limit; the app answers 422)."""


@dataclass(frozen=True)
class Limit:
    """One bound: its largest ``value`` (and smallest, ``least``, where there is one) in
    ``unit``, the request fields it ``applies`` to, and ``why`` it has that value."""

    name: str
    value: int
    unit: str
    applies: str
    why: str
    least: int | None = None


BODY_BYTES = Limit(
    "body_bytes",
    2_000_000,
    "bytes",
    "every request body: JSON, or a multipart upload; with or without Content-Length "
    "(a chunked body is counted as it arrives)",
    "A drawn curve at its 20,000-point limit is about 0.8 MB of JSON and a document a few kB; "
    "the body is held whole to be parsed, so its size bounds the memory one request can pin.",
)
JSON_DEPTH = Limit(
    "json_depth",
    32,
    "levels",
    "the nesting of a JSON request body, and of a document imported into the library",
    "The deepest request a client needs is 6 levels (a point of a composed linkage's joint in "
    "a document in the body); Python's JSON and TOML parsers recurse once per level, so a bound "
    "far below the interpreter's recursion limit keeps a hostile body from exhausting the stack.",
)
SAMPLES = Limit(
    "samples",
    4096,
    "samples",
    "scene.samples, study.samples, export.samples (input angles traced per circuit)",
    "The page draws 360; 4096 is a step under 0.1°. A scene's time and size grow linearly: "
    "4096 samples of the spherical six-bar take 0.4 s and 11 MB of JSON.",
    least=8,
)
STUDY_STEPS = Limit(
    "study_steps",
    50,
    "steps",
    "study.count (each step is a whole traced linkage)",
    "The page offers a handful; 51 linkages of 4096 samples each take about 2 s and 8 MB.",
    least=0,
)
POINTS = Limit(
    "points",
    20_000,
    "points",
    "match.points, ellipse.points (a drawn curve)",
    "The page samples the pointer (a few hundred points) and a CSV of 20,000 rows is a finely "
    "traced curve. Fitting and matching are linear in it (20,000 points: 0.3 s); a refined "
    "match fits 500 of them, evenly spaced (its cost grows faster than the count).",
)
MATCH_TOP = Limit(
    "match_top",
    20,
    "candidates",
    "match.top (the top-K of the atlas match)",
    "Each candidate is refined and traced again; twenty is more than a person compares.",
    least=1,
)
ELLIPSE_FAMILY = Limit(
    "ellipse_family",
    200,
    "double sliders",
    "ellipse.count (members of paper 004's family listed)",
    "The page lists 12; each member is checked against the ellipse at 360 samples.",
    least=0,
)
DOCUMENT_LIST = Limit(
    "document_list",
    32,
    "entries",
    "any list in a document (a composed linkage's joints, its traced joints)",
    "The largest bundled linkage has 8 joints. A scene's and a drag's time grow faster than "
    "the square of the joint count: a chain of 32 dyads takes 0.8 s to draw and 3 s to drag, "
    "one of 64 takes 3.5 s and 22 s.",
)
TITLE = Limit(
    "title",
    1_000,
    "characters",
    "a document's title",
    "A title is a line on the page and the source of a file or library name; 1,000 characters "
    "is a paragraph.",
)
TEXT = Limit(
    "text",
    64,
    "characters",
    "every other string of a document (family, units, joint names and references), drag.joint, "
    "study.pivot, study.direction, ellipse.circle",
    "Names a joint or a choice: any readable name fits, and a document's joints can all be "
    "dragged (drag.joint has the same bound).",
)
NAME = Limit(
    "name",
    200,
    "characters",
    "library entry names (after stripping), in save, rename and import",
    "A name is one line in the library list and a file name on export.",
)

# The server's own bounds (not a request's fields): how much work runs at once, how many
# connections stay open, and how long a client may take to send a request. Enforced by
# server/work.py (503 with Retry-After) and server/runner.py (connections, header and body
# timeouts).
WORK_SLOTS = Limit(
    "work_slots",
    4,
    "requests",
    "requests computed at once: every POST, PUT, PATCH and DELETE under /api (reads, health "
    "and the page never take a slot)",
    "Two per core of the 2-core machine the workbench is measured on: more would share the same "
    "cores (and Python's lock) and finish no sooner, while filling the thread pool that the "
    "page's reads use.",
)
WORK_QUEUE = Limit(
    "work_queue",
    32,
    "requests",
    "requests waiting for a work slot; one more is answered 503 with Retry-After at once",
    "The page sends one computation per action; 32 waiting is eight rounds of the slots, longer "
    "than a person waits, and each waiting request holds its body (at most body_bytes).",
)
WORK_WAIT = Limit(
    "work_wait",
    30,
    "seconds",
    "the time a request waits for a work slot before it is answered 503 with Retry-After",
    "A person gives up well before; an answer saying the server is busy is better than a "
    "page that hangs.",
)
CONNECTIONS = Limit(
    "connections",
    256,
    "connections",
    "open connections; past the bound a new one closes the slowest of those in the middle of "
    "a request (fewest bytes a second); those being answered, kept alive, or new and silent "
    "for under a quarter second are kept, up to twice the bound, past which a new one is "
    "refused (503)",
    "A browser opens at most six per server. Twice the bound (512) stays under the 1,024 files "
    "a process may open by default, which 1,100 half-sent connections once exhausted (where "
    "the process may open fewer, the bound is lowered to fit).",
)
HEADER_SECONDS = Limit(
    "header_seconds",
    10,
    "seconds",
    "the time from a connection's opening (or its previous answer) to a whole request line "
    "and headers; a slower connection is closed (408 if it had sent anything)",
    "A browser sends its headers in one packet; a client that trickles them (slowloris) would "
    "otherwise hold a connection for ever.",
)
BODY_SECONDS = Limit(
    "body_seconds",
    30,
    "seconds",
    "the time from a request's headers to the end of its body; a slower body is answered 408 "
    "and the connection closed",
    "The largest body (2 MB) arrives in 30 s at 70 kB/s, slower than any network the page is "
    "used over; a client that trickles its body would otherwise hold a connection for ever.",
)

# What one request may cost, whatever its sizes: the cost estimate of the work (checked before
# it starts: 422 naming what to lower), and its time (checked between its steps: 503). One
# table for the command line and the server: linkwright.engine.cost; enforced by
# server/budget.py in the scene, drag, study, match, ellipse and export routes.
REQUEST_WORK = Limit(
    "request_work",
    int(_cost.REQUEST_WORK.value),
    "work units (one joint placed at one input)",
    "the estimated work of a scene, drag, study, match, ellipse or export: circuits × samples "
    "× joints × steps, with each circuit's limit search (a gear ratio multiplies the circuits)",
    _cost.REQUEST_WORK.why,
)
REQUEST_BYTES = Limit(
    "request_bytes",
    int(_cost.REQUEST_BYTES.value),
    "bytes",
    "the estimated peak memory of the same requests, their answer included",
    _cost.REQUEST_BYTES.why,
)
REQUEST_SECONDS = Limit(
    "request_seconds",
    int(_cost.REQUEST_SECONDS.value),
    "seconds",
    "the time a scene, drag, study, match or ellipse may compute: checked between circuits, "
    "steps and refinements; past it the answer is 503",
    _cost.REQUEST_SECONDS.why,
)
GEAR_TURNS = Limit(
    "gear_turns",
    int(_cost.GEAR_TURNS.value),
    "turns of a crank per input turn",
    "the size of a gear ratio whose circuits are traced (scene, study, export)",
    _cost.GEAR_TURNS.why,
)
REFINE_POINTS = Limit(
    "refine_points",
    int(_cost.REFINE_POINTS.value),
    "points",
    "the drawn points a refined match fits (more are thinned evenly; the distance is still "
    "measured to all of them)",
    _cost.REFINE_POINTS.why,
)

# A drawing's sizes (POST /api/sketch): the compiler's own bounds, in linkwright.io.sketch_checks.
SKETCH_JOINTS = Limit(
    "sketch_joints",
    _sketch.MAX_JOINTS,
    "joints",
    "sketch.joints, with the ground pivot each slider's guide may add (a drawing over it is "
    "answered status invalid)",
    "The linkage document a drawing compiles to must fit document_list (32 joints); the "
    "compile places each joint once and checks the linkage at 28 inputs: a chain of 15 dyads "
    "on 32 joints takes about 6 ms.",
)
SKETCH_LINKS = Limit(
    "sketch_links",
    _sketch.MAX_LINKS,
    "links",
    "sketch.links",
    "Twice the joints, more than a linkage of one degree of freedom needs (a four-bar has 3 "
    "links on 4 joints, Jansen's leg 7 on 8).",
)
SKETCH_LINK_JOINTS = Limit(
    "sketch_link_joints",
    _sketch.MAX_LINK_JOINTS,
    "joints",
    "each link of sketch.links",
    "A ternary link has 3 joints and a plate carrying a row of points a few more; each pair of "
    "a link's joints is checked at every input, so the bound keeps that square small.",
)
SKETCH_DRIVERS = Limit(
    "sketch_drivers",
    _sketch.MAX_DRIVERS,
    "drivers",
    "sketch.drivers (the input crank and the cranks geared to it)",
    "A gear train of eight cranks is more than any drawn linkage uses; each further driver is "
    "one more gear pair to trace.",
)

LIMITS: dict[str, Limit] = {
    limit.name: limit
    for limit in (
        BODY_BYTES,
        JSON_DEPTH,
        SAMPLES,
        STUDY_STEPS,
        POINTS,
        MATCH_TOP,
        ELLIPSE_FAMILY,
        DOCUMENT_LIST,
        TITLE,
        TEXT,
        NAME,
        WORK_SLOTS,
        WORK_QUEUE,
        WORK_WAIT,
        CONNECTIONS,
        HEADER_SECONDS,
        BODY_SECONDS,
        REQUEST_WORK,
        REQUEST_BYTES,
        REQUEST_SECONDS,
        GEAR_TURNS,
        REFINE_POINTS,
        SKETCH_JOINTS,
        SKETCH_LINKS,
        SKETCH_LINK_JOINTS,
        SKETCH_DRIVERS,
    )
}
"""Every limit by name (what ``GET /api/limits`` serves)."""


def as_json() -> dict[str, dict[str, Any]]:
    """The table as ``GET /api/limits`` serves it: name → {value, least, unit, applies, why}.

    >>> sorted(as_json()["match_top"])
    ['applies', 'least', 'unit', 'value', 'why']
    """
    return {
        name: {k: v for k, v in asdict(limit).items() if k != "name"}
        for name, limit in LIMITS.items()
    }


def over(limit: Limit, field: str, got: int) -> LimitError:
    """The error for ``field`` at ``got`` units, over ``limit``.

    >>> str(over(NAME, "name", 201))
    'name: 201 characters, at most 200 allowed'
    """
    return LimitError(f"{field}: {got:,} {limit.unit}, at most {limit.value:,} allowed")


# --------------------------------------------------------------------------------------------
# A document's strings, lists and nesting
# --------------------------------------------------------------------------------------------


def _path(parent: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{parent}[{key}]"
    return f"{parent}.{key}" if parent else key


def check_document(document: Any, field: str = "document") -> None:
    """Refuse a document over the limits before it is parsed: a list of more than
    :data:`DOCUMENT_LIST` entries, a title over :data:`TITLE` characters, any other string
    (keys included) over :data:`TEXT`, nesting over :data:`JSON_DEPTH`. Everything else about
    it is :func:`~linkwright.io.parse_document`'s to judge. Paths are written as the document
    parser writes them (``mechanism.joints[3].name``), after ``field``.

    Raises
    ------
    LimitError
        Naming the first value over a limit.

    Examples
    --------
    >>> joints = [{"name": f"J{i}", "type": "fixed", "at": [0, i]} for i in range(33)]
    >>> check_document({"mechanism": {"family": "linkage", "joints": joints}})
    Traceback (most recent call last):
    ...
    linkwright.server.limits.LimitError: document: mechanism.joints: 33 entries, at most 32 allowed
    """
    # Iterative, so that the walk itself cannot overflow the stack on a deep value.
    stack: list[tuple[Any, str, int]] = [(document, "", 1)]
    while stack:
        value, path, depth = stack.pop()
        if isinstance(value, dict | list):
            if depth > JSON_DEPTH.value:
                raise LimitError(
                    f"{field}: nested {depth} levels, at most {JSON_DEPTH.value} allowed"
                )
            if isinstance(value, list):
                if len(value) > DOCUMENT_LIST.value:
                    raise over(DOCUMENT_LIST, f"{field}: {path or 'document'}", len(value))
                # Reversed onto the stack, so that the walk (and the first error) goes in
                # document order.
                stack.extend(
                    (v, _path(path, i), depth + 1) for i, v in reversed(list(enumerate(value)))
                )
            else:
                for key, v in reversed(value.items()):
                    if isinstance(key, str) and len(key) > TEXT.value:
                        raise LimitError(
                            f"{field}: {path or 'document'}: a key of {len(key):,} characters, "
                            f"at most {TEXT.value} allowed"
                        )
                    stack.append((v, _path(path, str(key)), depth + 1))
        elif isinstance(value, str):
            limit = TITLE if path == "title" else TEXT
            if len(value) > limit.value:
                raise over(limit, f"{field}: {path or 'document'}", len(value))

"""A request's cost, checked before its work starts, and its time budget while it runs.

The estimates are the command line's (:mod:`linkwright.engine.cost`), held to a request's
budgets (:data:`linkwright.engine.cost.REQUEST`: work, memory with the answer, and seconds; all
served at ``GET /api/limits``). A route runs its work inside :func:`request`, which

- turns a :class:`~linkwright.engine.cost.CostError` (the estimate is over budget) into
  :class:`TooCostly`, a :class:`~linkwright.server.limits.LimitError`: 422 with the one line
  that says what to lower;
- sets the request's deadline (:data:`~linkwright.engine.cost.REQUEST_SECONDS`), which its long
  loops check between steps, and turns the :class:`~linkwright.engine.cost.OverTime` they raise
  into :class:`OverTime`: 503, "took longer than the 20 s budget of a request; lower X".

The routes' estimates are here too (a scene's modes, a drag, a study and its steps, an export),
so that each route calls one function before its work, and its long loops trace circuits with
:func:`trace_circuits`, which checks the deadline between them.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, ClassVar

import numpy as np

from linkwright.engine import cost
from linkwright.engine.circuits import InputArcs, NoPeriod
from linkwright.mechanisms import Mechanism, circuit, input_range
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server.errors import StatusError
from linkwright.server.limits import SAMPLES, LimitError

__all__ = [
    "OverTime",
    "TooCostly",
    "answer_bytes",
    "check",
    "check_export",
    "check_scene",
    "check_study",
    "circuit_count",
    "drag_estimate",
    "request",
    "scene_part",
    "step_arcs",
    "study_estimate",
    "trace_circuits",
]

JSON_NUMBER_BYTES = 24
"""Bytes a number of an answer takes as JSON text (about 18 digits and a separator)."""


class TooCostly(LimitError):
    """A request whose estimated work or memory is over a request's budget (422)."""


class OverTime(StatusError):
    """A request that ran past its time budget (503): it was estimated to fit, but the machine
    was slower (or busier) than the estimate. No ``Retry-After``: the same request would take
    as long again."""

    status: ClassVar[int] = 503


@contextmanager
def request(lower: str) -> Iterator[None]:
    """Run a request's work under its deadline; ``lower`` names what to lower when it is late
    (``"samples"``, ``"count or samples"``)."""
    try:
        with cost.deadline(cost.REQUEST_SECONDS.value, lower):
            yield
    except cost.CostError as exc:
        raise TooCostly(str(exc)) from None
    except cost.OverTime as exc:
        raise OverTime(str(exc)) from None


def check(estimate: cost.Estimate) -> cost.Estimate:
    """``estimate`` held to a request's budgets (raises :class:`TooCostly`)."""
    try:
        return estimate.check(cost.REQUEST)
    except cost.CostError as exc:
        raise TooCostly(str(exc)) from None


def answer_bytes(numbers: float, python: bool = False) -> float:
    """Memory an answer of ``numbers`` numbers holds while it is written: its JSON text, and,
    for one built of Python lists (``python``), the lists too."""
    return numbers * (JSON_NUMBER_BYTES + (cost.PY_NUMBER_BYTES if python else 0))


# --------------------------------------------------------------------------------------------
# Circuits, traced with the deadline checked between them
# --------------------------------------------------------------------------------------------


def circuit_count(arcs: InputArcs) -> int:
    """Circuits a linkage runs on its assembly: none, one full turn, or one per input arc."""
    return 0 if bool(arcs.never) else 1 if bool(arcs.full) else int(arcs.count)


def trace_circuits(mechanism: Mechanism, arcs: InputArcs, samples: int) -> list[Any]:
    """Every circuit of ``mechanism`` on its assembly (one where the input turns fully, one per
    arc where it rocks), the request's deadline checked between circuits."""
    if bool(arcs.never):
        return []
    if bool(arcs.full):
        return [circuit(mechanism, samples, order=0)]
    motions = []
    for k in range(int(arcs.count)):
        cost.check_time()
        motions.append(circuit(mechanism, samples, order=0, circuit=k))
    return motions


def _fewer_samples(estimate: cost.Estimate, samples: int) -> str:
    """Advice for a drawing over budget: fewer samples where that is enough, else the gear ratio
    (the circuits' count, whose limit searches do not shrink with the samples)."""
    share = max(estimate.work / cost.REQUEST.work.value, estimate.bytes / cost.REQUEST.bytes.value)
    fewer = int(samples / share)
    least = SAMPLES.least
    assert least is not None  # limits.py gives the samples a least value
    if fewer >= least:
        return f"lower samples to about {fewer:,} or fewer"
    return "lower the gear ratio (it sets how many circuits there are) or simplify the linkage"


# --------------------------------------------------------------------------------------------
# The routes' estimates
# --------------------------------------------------------------------------------------------


def scene_part(
    mechanism: Mechanism, samples: int, diagrams: bool
) -> tuple[InputArcs, cost.Estimate, float]:
    """One assembly mode of a scene: its input's arcs (the cheap first pass that counts its
    circuits; a crank geared too fast is refused before it), the estimate of tracing every
    circuit (and, with ``diagrams``, again with derivatives), and the numbers it answers."""
    shape = cost.Shape.of_mechanism(mechanism)
    cost.check_gear(shape)
    arcs = input_range(mechanism)
    count = circuit_count(arcs)
    full = bool(arcs.full)
    part = cost.trace(shape, samples, circuits=max(count, 1), full=full)
    numbers: float = count * samples * shape.joints * shape.dim * (2 if shape.dim == 3 else 1)
    if diagrams and count:
        part = part + cost.trace(shape, samples, circuits=count, full=full, order=2)
        numbers += 12.0 * count * samples  # three diagrams of about a dozen series a circuit
    return arcs, part, numbers


def check_scene(estimate: cost.Estimate, numbers: float, samples: int) -> None:
    """A whole scene (its modes' :func:`scene_part` added up, its answer held) against a
    request's budgets."""
    whole = estimate.holding(answer_bytes(numbers), estimate.what)
    if not whole.fits(cost.REQUEST):
        check(whole.advise(_fewer_samples(whole, samples)))


DRAG_POSE_UNITS = 2000
"""Placements' worth of work per joint of one trial pose of a drag: the document copied and
parsed again, then solved at one input (measured 0.1 to 0.2 ms a joint)."""


def drag_estimate(fields: int, joints: int) -> cost.Estimate:
    """A drag's work: each of ``fields`` perturbed once, then the first two Gauss–Newton attempts
    of about ten steps, each a pose per chosen field and a few for the line search. Further
    attempts (the other assemblies) run only where these fail: the deadline bounds them."""
    poses = 2 * fields + 2 * 10 * 6
    return cost.Estimate(
        poses * joints * DRAG_POSE_UNITS,
        poses * joints * 4096.0,
        f"dragging a joint of a linkage of {joints} joints ({fields} fields)",
        "use a linkage of fewer joints",
    )


def study_estimate(
    mechanism: Mechanism, arcs: InputArcs, steps: int, samples: int
) -> cost.Estimate:
    """A study of ``steps`` linkages like ``mechanism`` (each with as many circuits as it has)
    at ``samples``: their tracing, and the answer (each traced joint's points, as Python lists
    and as JSON)."""
    shape = cost.Shape.of_mechanism(mechanism)
    count = circuit_count(arcs)
    traced = len(mechanism.plan.traced)
    one = cost.trace(shape, samples, circuits=max(count, 1), full=bool(arcs.full))
    numbers = steps * max(count, 1) * (samples + 1) * traced * 2
    what = (
        f"tracing {steps} steps × {count:,} circuit{'s' if count != 1 else ''} of "
        f"{samples:,} samples ({shape.joints} joints)"
    )
    return one.times(steps, what).holding(answer_bytes(numbers, python=True))


def _study_advice(mechanism: Mechanism, arcs: InputArcs, steps: int, samples: int) -> str:
    """What to lower for a study over budget: the step count, the samples, or else the ratio."""
    scope = cost.REQUEST
    options = []

    def by_count(n: int) -> cost.Estimate:
        return study_estimate(mechanism, arcs, n + 1, samples)

    def by_samples(n: int) -> cost.Estimate:
        return study_estimate(mechanism, arcs, steps, n)

    most = cost.largest(by_count, scope, 0, steps)
    if most is not None and most < steps - 1:
        options.append(f"count to {most} or fewer")
    least = SAMPLES.least
    assert least is not None  # limits.py gives the samples a least value
    fewer = cost.largest(by_samples, scope, least, samples)
    if fewer is not None and fewer < samples:
        options.append(f"samples to {fewer:,} or fewer")
    if circuit_count(arcs) > 1 and float(np.max(np.abs(getattr(mechanism, "ratio", 1.0)))) != 1:
        options.append("the gear ratio")
    if not options:
        return "use a simpler linkage"
    return "lower " + ", or ".join(options)


def _has_plan(mechanism: Mechanism) -> bool:
    try:
        mechanism.plan  # noqa: B018 - building the plan is the test
    except NoConstructionPlan:
        return False
    return True


def _periodic(mechanism: Mechanism) -> bool:
    try:
        cost.Shape.of_mechanism(mechanism)
    except NoPeriod:
        return False
    return True


def check_study(mechanism: Mechanism, count: int, samples: int) -> None:
    """A study of ``count`` steps from ``mechanism``, estimated from the document's own linkage
    (a linkage without a plan or a period is noted step by step instead)."""
    if not (_has_plan(mechanism) and _periodic(mechanism)):
        return
    cost.check_gear(cost.Shape.of_mechanism(mechanism))
    arcs = input_range(mechanism)
    estimate = study_estimate(mechanism, arcs, count + 1, samples)
    if not estimate.fits(cost.REQUEST):
        check(estimate.advise(_study_advice(mechanism, arcs, count + 1, samples)))


def step_arcs(mechanism: Mechanism, samples: int, k: int, spent: float) -> InputArcs:
    """A study step's input arcs, once its circuits are known to fit what is left of the budget
    (a moved pivot can give a linkage more circuits than the document's, which the estimate
    counted)."""
    cost.check_gear(cost.Shape.of_mechanism(mechanism), f"step {k}'s ")
    arcs = input_range(mechanism)
    step = study_estimate(mechanism, arcs, 1, samples)
    if spent + step.work > cost.REQUEST.work.value:
        raise TooCostly(
            f"too costly: step {k} has {circuit_count(arcs):,} circuits, more than the "
            f"estimate counted, and the study would need more than "
            f"{cost.REQUEST.work.value:.2g} units of work (a request's budget); lower count or "
            "samples"
        )
    return arcs


def check_export(
    mechanism: Mechanism, fmt: str, samples: int, *, gif_frames: int, gif_dpi: int
) -> None:
    """An export's drawing against a request's budgets: its circuits at ``samples`` in every
    assembly mode the picture draws, a GIF's frames, the file's numbers. The drawing itself
    runs in matplotlib, which cannot be stopped between steps, so the estimate is the bound."""
    if fmt in ("toml", "json") or not _has_plan(mechanism):
        return
    shape = cost.Shape.of_mechanism(mechanism)
    cost.check_gear(shape)
    arcs = input_range(mechanism)
    count = max(circuit_count(arcs), 1)
    modes = 2 ** min(len(mechanism.plan.dyads), 2)
    estimate = cost.trace(shape, samples, circuits=count, modes=modes, full=bool(arcs.full))
    if fmt == "gif":
        frames = gif_frames * max(1, -(-360 // gif_frames))
        one = cost.trace(shape, frames, circuits=1, full=bool(arcs.full))
        estimate = estimate + cost.animation(gif_frames, gif_dpi, gif=True, trace_estimate=one)
    # A CSV holds every joint's path; a picture or a drawing the traced curves and the pose.
    drawn = shape.joints if fmt == "csv" else len(mechanism.plan.traced) + 1
    numbers = modes * count * samples * drawn * shape.dim
    estimate = estimate.holding(answer_bytes(numbers, python=True))
    if not estimate.fits(cost.REQUEST):
        check(estimate.advise(_fewer_samples(estimate, samples)))

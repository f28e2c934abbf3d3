"""The workbench's forces panel: ``POST /forces`` (issue 25, point 5).

The page asks for forces only while its forces panel is open or its force arrows are on: a
separate request, sent after the scene it belongs to, so that a plain edit's redraw costs what
it did before. The answer is :mod:`linkwright.dynamics`'s, through the same setup as
``linkwright forces`` (:func:`linkwright.dynamics.forces_setup`, the input speed replaced as
``--speed`` replaces it), along the very samples the scene draws: every circuit of the document's
own assembly mode, traced as :func:`linkwright.server.scene.scene` traces them, then placed again
with derivatives on the branches they ran, so that sample ``i`` of circuit ``c`` here is sample
``i`` of ``modes[own].circuits[c]`` there. The same at the scene's pose (``at``).

- ``circuits``: per circuit, ``input`` (continuous degrees, the scene's), ``torque`` (the
  driving torque, Newton–Euler), ``energy_torque`` (the same by the energy balance, a check a
  reader can see), ``reactions`` (name → force per sample; on the sphere also ``moments``);
- ``where``: each reaction's joint (``"A:C.r1"``, the force at A on the link ``C.r1``, is at A);
- ``message``: one plain line where the document has no masses (how to add them), and
  ``suggest``: a ``[mechanism.mass]`` table giving every link one mass unit as a uniform body
  (docs/forces.md says which shape), for the page's one-click button; a link that cannot take
  a mass alone (a spherical ternary link needs its centre and tensor) is left out and named in
  ``suggest_note``.

Units are the document's (mass unit, length unit, seconds); the page converts them to N and N·m
where it knows the length unit. Nothing is computed for a document with no masses and no loads.
The work (the circuits, their derivatives, one dense solve per sample) is estimated and held to
a request's budget before it starts (:mod:`linkwright.server.budget`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter
from fastapi.responses import Response
from pydantic import BaseModel, ConfigDict, Field, Strict

from linkwright.dynamics import (
    Forces,
    ForcesInputError,
    Loads,
    MassProps,
    Structure,
    UnsupportedPlan,
    forces_of,
    forces_setup,
    masses_from,
    structure,
)
from linkwright.dynamics.model import link_lengths
from linkwright.engine import cost
from linkwright.engine.circuits import NoPeriod
from linkwright.engine.evaluate import Motion
from linkwright.io import Document
from linkwright.mechanisms import Mechanism, circuits, solve
from linkwright.mechanisms.sixbar import NoConstructionPlan
from linkwright.server import budget, limits
from linkwright.server.overlays import with_rates
from linkwright.server.scene_io import json_rows, read_document, to_json
from linkwright.server.scene_modes import continuous_degrees
from linkwright.server.schema import DocumentBody, examples
from linkwright.server.tools_common import EXAMPLE_DOCUMENT, ToolsError

__all__ = ["MAX_RPM", "NO_MASS", "ForcesRequest", "estimate", "forces_json", "router"]

router = APIRouter()

MAX_RPM = 1e6
"""The fastest input the panel computes (the page's speed control stops there too)."""

SUGGESTED_MASS = 1.0
"""The one-click masses: every link this many mass units, a uniform body."""

NO_MASS = (
    "No masses: give the links masses in the document's [mechanism.mass] table (docs/forces.md), "
    "or use the button below to make every link a uniform body of one mass unit."
)
"""What the panel says of a document without masses (one line)."""


class ForcesRequest(BaseModel):
    model_config = ConfigDict(
        json_schema_extra=examples({"document": EXAMPLE_DOCUMENT, "speed": 60.0, "samples": 72})
    )

    document: DocumentBody
    speed: Annotated[float, Strict()] = Field(
        60.0,
        allow_inf_nan=False,
        json_schema_extra={"exclusiveMinimum": 0, "maximum": MAX_RPM},
    )
    """The input speed in rpm (the page's speed control); it replaces the document's
    ``loads.speed`` as ``linkwright forces --speed`` does."""
    samples: int = Field(360, ge=limits.SAMPLES.least, le=limits.SAMPLES.value, strict=True)
    at: float | None = Field(None, allow_inf_nan=False)
    """The scene's pose (degrees): its forces come too (``pose``)."""


# --------------------------------------------------------------------------------------------
# Cost
# --------------------------------------------------------------------------------------------


def estimate(mechanism: Mechanism, st: Structure, samples: int) -> tuple[Any, cost.Estimate, float]:
    """The own mode's arcs, the work of its forces (its circuits traced, placed again with
    derivatives, one Newton–Euler solve per sample: the unknowns' cube, as ``linkwright forces``
    counts it) and the numbers the answer holds. Raises
    :class:`~linkwright.server.budget.TooCostly` for a crank geared past the limit, before
    anything is traced."""
    arcs, tracing, _ = budget.scene_part(mechanism, samples, diagrams=False)
    shape = cost.Shape.of_mechanism(mechanism)
    # A triad's configurations are followed: up to one circuit each, each sample a triad solve.
    triad = shape.poses > 1
    count = shape.poses if triad else budget.circuit_count(arcs)
    per = max(count, 1) * samples
    rates = cost.solve(None, per, triad=shape.space) if triad else cost.solve(shape, per, order=2)
    unknowns = 3 * len(st.bodies)
    solves = cost.Estimate(
        per * (unknowns**3 / 3.0 + unknowns**2) / 50.0,
        per * unknowns * (unknowns + 4) * 8 * 3,
        f"solving Newton–Euler ({unknowns} unknowns) at {per:,} samples",
    )
    joints = len(st.joints) + sum(len(b.joints) for b in st.bodies)  # a reaction per body's pin
    dim = shape.dim * (2 if shape.dim == 3 else 1)  # the sphere adds each revolute's moment
    numbers = per * (3.0 + joints * dim)
    return arcs, tracing + rates + solves, numbers


# --------------------------------------------------------------------------------------------
# The answer
# --------------------------------------------------------------------------------------------


def _masked(values: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Samples where the linkage is not assembled (or singular) as NaN, written as null."""
    out = np.asarray(values, dtype=float)
    ok = np.asarray(valid, dtype=bool).reshape(_ok_shape(out))
    return json_rows(np.where(ok, out, np.nan))


def _ok_shape(values: np.ndarray) -> tuple[int, ...]:
    """A per-sample mask's shape against ``values`` (a vector per sample adds an axis)."""
    return values.shape[:1] + (1,) * (values.ndim - 1)


def _circuit_json(f: Forces, degrees: np.ndarray) -> dict[str, Any]:
    valid = np.asarray(f.valid, dtype=bool)
    out: dict[str, Any] = {
        "input": json_rows(degrees),
        "torque": _masked(f.input_torque, valid),
        "energy_torque": _masked(f.energy_torque, valid),
        "reactions": {k: _masked(v, valid) for k, v in f.reactions.items()},
    }
    if f.moments:
        out["moments"] = {k: _masked(v, valid) for k, v in f.moments.items()}
    return out


def _typical(circuits_json: Sequence[Mapping[str, Any]]) -> float | None:
    """A force to scale the arrows by: the 95th percentile of the reactions' magnitudes (the
    few samples by a limit position, where they grow without bound, do not set it)."""
    sizes = [
        np.linalg.norm(np.asarray(v, dtype=float), axis=-1).reshape(-1)
        for c in circuits_json
        for v in c["reactions"].values()
    ]
    lengths = np.concatenate(sizes) if sizes else np.zeros(0)
    lengths = lengths[np.isfinite(lengths)]
    if not lengths.size:
        return None
    size = float(np.percentile(lengths, 95))
    return size if size > 0 else None


def _suggestion(st: Structure, mechanism: Mechanism) -> tuple[dict[str, float], str | None]:
    """The one-click masses: each link that can take a mass alone (a uniform body), and a note
    naming those that cannot."""
    lengths = link_lengths(st, mechanism.params())
    table: dict[str, float] = {}
    left: list[str] = []
    for name in st.names:
        try:
            masses_from({name: SUGGESTED_MASS}, st, lengths)
        except ForcesInputError:
            left.append(name)
            continue
        table[name] = SUGGESTED_MASS
    note = None
    if left:
        note = (
            f"{', '.join(left)} stay{'s' if len(left) == 1 else ''} massless: a link of three "
            "joints or more on the sphere needs its centre and inertia tensor (docs/forces.md)"
        )
    return table, note


def _acting(masses: Mapping[str, MassProps], loads: Loads) -> bool:
    """Whether anything acts: a mass, or a load that needs none."""
    return bool(masses or loads.forces or loads.torques or loads.springs or loads.dampers)


def _own_motions(mechanism: Mechanism, arcs: Any, samples: int) -> list[Motion]:
    """The own mode's circuits, traced as the scene traces them."""
    if mechanism.plan.triads:
        return list(circuits(mechanism, samples, order=0)[1])
    return budget.trace_circuits(mechanism, arcs, samples)


def _pose(
    mechanism: Mechanism, st: Structure, masses: dict[str, MassProps], loads: Loads, at: float
) -> dict[str, Any] | None:
    here = solve(mechanism, np.radians([at]), order=2)
    if not bool(np.asarray(here.valid).all()):
        return None
    f = forces_of(st, mechanism.params(), here, masses, loads)
    one = _circuit_json(f, np.asarray([at]))
    return {
        key: ({k: v[0] for k, v in value.items()} if isinstance(value, dict) else value[0])
        for key, value in one.items()
    }


def forces_json(
    document: Any, *, speed: float = 60.0, samples: int = 360, at: float | None = None
) -> dict[str, Any]:
    """The forces panel's numbers for ``document`` at ``speed`` rpm (the module docstring).

    Raises :class:`~linkwright.server.tools_common.ToolsError` (one line naming the field) for
    a bad speed or samples, :class:`~linkwright.server.budget.TooCostly` for work over a
    request's budget (before it starts); a document the forces cannot be set up for (a plan
    kind forces do not know) is answered with its reason in ``message``, not refused.

    Examples
    --------
    >>> from linkwright.io import document_to_dict, load_example
    >>> doc = document_to_dict(load_example("crank-rocker"))
    >>> out = forces_json(doc, samples=24)
    >>> out["message"].split(":")[0], out["suggest"], out["circuits"]
    ('No masses', {'crank': 1.0, 'coupler': 1.0, 'rocker': 1.0}, [])
    >>> doc["mechanism"]["mass"] = out["suggest"]
    >>> out = forces_json(doc, samples=24, at=30.0)
    >>> len(out["circuits"][0]["torque"]), sorted(out["circuits"][0]["reactions"])
    (24, ['A', 'A0', 'B', 'B0'])
    >>> bool(np.isclose(out["pose"]["torque"], out["pose"]["energy_torque"], rtol=1e-9))
    True
    """
    with budget.request("samples"):
        return _forces_json(document, speed=speed, samples=samples, at=at)


def _check_request(speed: float, samples: int, at: float | None) -> None:
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not math.isfinite(speed):
        raise ToolsError(f"speed: must be a finite number of rpm, got {speed!r}")
    if not 0 < speed <= MAX_RPM:
        raise ToolsError(f"speed: must be above 0 and at most {MAX_RPM:,.0f} rpm, got {speed:g}")
    low, high = limits.SAMPLES.least, limits.SAMPLES.value
    assert low is not None  # limits.py gives the samples a least value
    if isinstance(samples, bool) or not isinstance(samples, int) or not low <= samples <= high:
        raise ToolsError(f"samples: must be a whole number from {low} to {high}, got {samples!r}")
    if at is not None and not math.isfinite(at):
        raise ToolsError(f"at: must be a finite angle in degrees, got {at!r}")


def _forces_json(document: Any, *, speed: float, samples: int, at: float | None) -> dict[str, Any]:
    started = time.perf_counter()
    _check_request(speed, samples, at)
    doc: Document = read_document(document, client=True)
    mech = doc.mechanism
    table = doc.raw["mechanism"].get("mass") or {}
    out: dict[str, Any] = {
        "space": "sphere" if _space(mech) == "sphere" else "plane",
        "units": doc.units,
        "speed_rpm": float(speed),
        "document_speed_rpm": _document_speed(doc),
        "links": [],
        "masses": bool(table),
        "message": None,
        "suggest": {},
        "suggest_note": None,
        "inertia": True,
        "where": {},
        "circuits": [],
        "pose": None,
        "scale": {"force": None},
        "note": None,
    }
    try:
        st = structure(mech.plan)
        _, masses, loads = forces_setup(
            mech, table, doc.raw.get("loads"), speed=speed, speed_field="speed"
        )
    except NoConstructionPlan as exc:
        out["message"] = f"No forces: this linkage has no construction plan ({exc})"
        return _done(out, started)
    except UnsupportedPlan as exc:
        out["message"] = f"No forces for this linkage yet: {exc}"
        return _done(out, started)
    except ForcesInputError as exc:  # the document reader checked these: only the speed is new
        raise ToolsError(str(exc)) from None
    out["links"] = list(st.names)
    out["inertia"] = loads.inertia
    out["suggest"], out["suggest_note"] = _suggestion(st, mech)
    if not table:
        out["message"] = NO_MASS
    if not _acting(masses, loads):
        return _done(out, started)
    if st.space == "sphere":
        out["note"] = (
            "on the sphere the bearing forces are statically indeterminate: these are the "
            "least-norm set that balances each link (docs/forces.md)"
        )
    try:
        arcs, work, numbers = estimate(mech, st, samples)
    except NoPeriod as exc:
        out["message"] = f"No forces: its circuit never closes ({exc})"
        return _done(out, started)
    budget.check_scene(work, numbers, samples)
    params = mech.params()
    bodies = []
    for motion in _own_motions(mech, arcs, samples):
        cost.check_time()
        f = forces_of(st, params, with_rates(mech, motion), masses, loads)
        bodies.append(_circuit_json(f, continuous_degrees(motion.input)))
    out["circuits"] = bodies
    if bodies:
        out["where"] = {name: name.split(":")[0] for name in bodies[0]["reactions"]}
    if at is not None:
        out["pose"] = _pose(mech, st, masses, loads, at)
    out["scale"] = {"force": _typical(bodies)}
    return _done(out, started)


def _space(mechanism: Mechanism) -> str:
    try:
        return str(mechanism.plan.space)
    except NoConstructionPlan:
        return "plane"


def _document_speed(doc: Document) -> float | None:
    loads = doc.raw.get("loads")
    if isinstance(loads, Mapping) and isinstance(loads.get("speed"), int | float):
        return float(loads["speed"])
    return None


def _done(out: dict[str, Any], started: float) -> dict[str, Any]:
    out["compute_ms"] = round(1e3 * (time.perf_counter() - started), 3)
    return out


@router.post(
    "/forces",
    response_class=Response,
    responses={200: {"content": {"application/json": {}}, "description": "The forces."}},
)
def forces_route(body: ForcesRequest) -> Response:
    """The driving torque and every joint's reaction along the own assembly mode's circuits at
    the input speed ``speed`` (rpm), for the workbench's forces panel."""
    result = forces_json(body.document, speed=body.speed, samples=body.samples, at=body.at)
    return Response(to_json(result), media_type="application/json")

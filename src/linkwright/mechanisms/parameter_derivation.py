"""Deriving a family's parameter vector (:func:`parameter_vector`) from its class and plan.

Nothing here is written per family. The kinds are read off the family's class (its
``point_fields``, ``length_fields`` and ``arc_fields``) and off the plan: each step kind says what
its numbers are (:data:`ROLES`: a crank's ``length`` is a length, its ``phase`` a direction; a
rigid point's ``u`` and ``v`` are coordinates on its link; a slider's ``line_angle`` is a
direction). A field the plan does not read itself (a geared five-bar's ``phase1``, a double
slider's ``p``, paper 001's ``sigma``) takes the kind of the plan numbers it moves, found by
moving it a little and comparing :meth:`~linkwright.mechanisms.Mechanism.params`. How each field
turns with the linkage is found the same way, and checked: a similarity applied to the fields
must apply the expected similarity to every plan number.

A composed linkage's vector is read off its joints instead (every numeric field of every joint,
named ``joint.field``), so it needs the linkage itself. The types (kinds, roles,
:class:`~.parameter_types.ParameterVector`) are in :mod:`.parameter_types`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import Crank, Fixed, Trammel
from linkwright.mechanisms.base import Mechanism
from linkwright.mechanisms.joints import numeric_kinds
from linkwright.mechanisms.parameter_types import (
    KIND_OF_ROLE,
    TWO_PI,
    Parameter,
    ParameterError,
    ParameterVector,
    is_linkage,
    plan_roles,
)

if TYPE_CHECKING:  # imported where used at run time (linkage imports this module's layer)
    from linkwright.mechanisms.linkage import Linkage

__all__ = ["family_template", "parameter_vector"]

Array = NDArray[np.float64]
_PROBE_STEP = 1e-3


def parameter_vector(family_or_mech: Any) -> ParameterVector:
    """The parameter vector of a family (its name or class) or of a mechanism.

    A composed linkage's vector depends on its joints, so it needs the linkage itself; a named
    family's depends on the word that chooses its plan (a Stephenson III driven at its output has
    a triad), read from the mechanism, or the family's default for a name or class.

    Raises
    ------
    ParameterError
        For an unknown family name, or ``"linkage"`` without a linkage.
    """
    if isinstance(family_or_mech, Mechanism):
        if is_linkage(family_or_mech):
            return _linkage_vector(family_or_mech)
        cls = type(family_or_mech)
        words = tuple(
            (f.name, getattr(family_or_mech, f.name)) for f in fields(cls) if f.type == "str"
        )
        # mypy reads the instances' own __hash__ as the class object's, so takes a family
        # class for unhashable (python/mypy#11470); a class is hashable.
        return _family_vector(cls, words)  # type: ignore[arg-type]
    if isinstance(family_or_mech, str):
        from linkwright.mechanisms import FAMILIES

        if family_or_mech not in FAMILIES:
            raise ParameterError(
                f"family: unknown {family_or_mech!r}; known: {', '.join(FAMILIES)}"
            )
        family_or_mech = FAMILIES[family_or_mech]
    if isinstance(family_or_mech, type) and issubclass(family_or_mech, Mechanism):
        if family_or_mech.family == "linkage":
            raise ParameterError(
                "linkage: a composed linkage's parameters are its joints' numbers; give the "
                "linkage itself (its structure fixes them)"
            )
        return _family_vector(family_or_mech, ())  # type: ignore[arg-type]  # as above

    raise ParameterError(f"not a family or a mechanism: {family_or_mech!r}")


def family_template(family: str) -> Mechanism:
    """A member of the named family with its default choices (assembly +1, pose 0, the
    default input word) and arbitrary valid numbers: a template whose numbers are all to be
    replaced (:meth:`ParameterVector.from_vector`).

    Raises
    ------
    ParameterError
        For an unknown family, or ``"linkage"``, whose structure only a linkage can give.
    """
    from linkwright.mechanisms import FAMILIES

    if family not in FAMILIES:
        raise ParameterError(f"family: unknown {family!r}; known: {', '.join(FAMILIES)}")
    if family == "linkage":
        raise ParameterError(
            "linkage: a composed linkage's joints come from a template: give a document of "
            "family linkage (its structure is kept, its numbers are free)"
        )
    return _probe_instance(FAMILIES[family], {})


@functools.lru_cache(maxsize=64)
def _family_vector(cls: type[Mechanism], words: tuple[tuple[str, str], ...]) -> ParameterVector:
    probe = _probe_instance(cls, dict(words))
    plan = probe.plan
    roles = plan_roles(plan)
    space = plan.space
    base_params = probe.params()
    params: list[Parameter] = []
    discrete: list[str] = []
    derived: list[str] = []
    for f in fields(cls):
        name = f.name
        if name == "start":  # where it runs, not a dimension (Mechanism.start)
            continue
        if _discrete_field(name, f.type):
            discrete.append(name)
            continue
        if name in cls.point_fields:
            for k, axis in enumerate("xy"):
                params.append(Parameter(f"{name}.{axis}", "coordinate", name, k, absolute=True))
            continue
        role, step = roles.get(name, (None, None))
        if name in cls.length_fields:
            kind = "length"
        elif name in cls.arc_fields:
            kind = "arc"
        elif role is not None:
            kind = KIND_OF_ROLE[role]
        else:
            moved = _moved(probe, name, base_params)
            role_set = {roles[k][0] for k in moved if k in roles}
            kind = _derived_kind(cls.__name__, name, role_set, space)
            derived.append(name)
        turns: float | None = 0.0
        ratio = None
        if space == "plane" and kind == "angle" and role == "direction":
            turns = 1.0
        elif space == "plane" and kind == "angle" and role == "phase" and step is not None:
            turns, ratio = None, step.ratio
        params.append(
            Parameter(
                name,
                kind,
                name,
                absolute=turns != 0.0,
                turns=turns,
                # The family's own arc fields are open arcs, whatever step reads them.
                closed=role == "closed-arc" and name not in cls.arc_fields,
                crank_ratio=ratio,
            )
        )
    input_turn = _input_turn(plan, base_params)
    vector = ParameterVector(
        family=cls.family,
        space=space,
        parameters=tuple(params),
        discrete=tuple(discrete),
        symmetry="similarity" if space == "plane" else "rotation",
        in_family_frame=space == "sphere",
        base=None,
        reference=None,
        input_turn=input_turn,
        derived=tuple(derived),
    )
    if space == "plane":
        vector = _with_derived_turns(vector, probe, roles)
        vector = replace(vector, **_gauge(vector, plan, roles))
    return vector


def _moved(probe: Mechanism, name: str, before: Mapping[str, Array]) -> set[str]:
    """The plan parameters that change when the field ``name`` moves a little."""
    value = np.asarray(getattr(probe, name), dtype=float)
    moved: dict[str, Any] = {name: value * (1 + _PROBE_STEP) + _PROBE_STEP}
    after = replace(probe, **moved).params()
    return {
        k
        for k, v in before.items()
        if k in after and not np.allclose(np.asarray(v, float), np.asarray(after[k], float))
    }


def _derived_kind(family: str, name: str, roles: set[str], space: str) -> str:
    if roles & {"length", "offset", "point"} and space == "plane":
        return "coordinate"
    if roles & {"phase", "direction", "angle"}:
        return "angle"
    if roles & {"arc", "closed-arc"}:
        return "arc"
    if "ratio" in roles:
        return "ratio"
    if "axis" in roles or "point" in roles:
        return "angle"  # it places a ground axis on the sphere without being an arc: an angle
    raise ParameterError(f"{family}.{name}: the plan does not read it; no kind can be given")


def _input_turn(plan: Any, params: Mapping[str, Array]) -> float:
    """δ/ψ: a crank whose phase is a constant fixes how the input shifts with a turn ψ of the
    linkage (δ = ψ / its ratio); where every crank has its own phase the input stays."""
    found: set[float] = set()
    for step in plan.steps:
        if isinstance(step, Crank | Trammel) and not isinstance(step.phase, str):
            ratio = getattr(step, "ratio", 1.0)
            r = params[ratio] if isinstance(ratio, str) else ratio
            found.add(round(1.0 / float(np.ravel(r)[0]), 12))
    if len(found) > 1:
        raise ParameterError("two cranks with fixed phases turn at different ratios")
    return found.pop() if found else 0.0


def _expected(
    vector: ParameterVector,
    roles: Mapping[str, tuple[str, Any]],
    params: Mapping[str, Array],
    s: float,
    psi: float,
    t: Array,
) -> dict[str, Array]:
    """What a similarity (scale s, turn ψ, shift t) does to each plan parameter, by its role."""
    out: dict[str, Array] = {}
    c, n = math.cos(psi), math.sin(psi)
    for key, value in params.items():
        role, step = roles.get(key, (None, None))
        v = np.asarray(value, dtype=float)
        if role == "point":
            out[key] = np.stack(
                (
                    s * (c * v[..., 0] - n * v[..., 1]) + t[0],
                    s * (n * v[..., 0] + c * v[..., 1]) + t[1],
                ),
                axis=-1,
            )
        elif role in ("length", "offset"):
            out[key] = s * v
        elif role == "direction":
            out[key] = v + psi
        elif role == "phase":
            ratio = getattr(step, "ratio", 1.0)
            r = np.asarray(params[ratio] if isinstance(ratio, str) else ratio, dtype=float)
            out[key] = v + psi - r * vector.input_turn * psi
        else:
            out[key] = v
    return out


def _agrees(
    vector: ParameterVector,
    probe: Mechanism,
    roles: Mapping[str, tuple[str, Any]],
) -> bool:
    s, psi, t = 1.37, 0.61, np.array([0.3, -0.8])
    want = _expected(vector, roles, probe.params(), s, psi, t)
    got = vector.transformed(probe, s, psi, t).params()
    for key, value in want.items():
        if key not in roles:
            continue  # a field kept among the parameters, read by no step
        diff = np.asarray(got[key], float) - value
        if roles.get(key, ("",))[0] in ("direction", "phase", "angle"):
            diff = np.remainder(diff + np.pi, TWO_PI) - np.pi
        if not np.allclose(diff, 0.0, atol=1e-9):
            return False
    return True


def _with_derived_turns(
    vector: ParameterVector, probe: Mechanism, roles: Mapping[str, tuple[str, Any]]
) -> ParameterVector:
    """Each derived angle field turns with the linkage or not: the choice under which the
    similarity acts on every plan parameter as its role says (checked on the probe)."""
    free = [
        i
        for i, p in enumerate(vector.parameters)
        if p.field in vector.derived and p.kind == "angle"
    ]
    for choice in range(2 ** len(free)):
        params = list(vector.parameters)
        for bit, i in enumerate(free):
            turns = float((choice >> bit) & 1)
            params[i] = replace(params[i], turns=turns, absolute=bool(turns))
        trial = replace(vector, parameters=tuple(params))
        if _agrees(trial, probe, roles):
            return trial
    raise ParameterError(
        f"{vector.family}: no assignment of its angles turns it as a whole (its symmetry "
        "cannot be read off its fields)"
    )


def _gauge(
    vector: ParameterVector, plan: Any, roles: Mapping[str, tuple[str, Any]]
) -> dict[str, Any]:
    """The first ground pivot, and the reference direction: a guide's direction field where the
    plan has one, else the line from the first ground pivot to the second."""
    by_field = {p.field: p for p in vector.parameters}
    ground = [s.at for s in plan.steps if isinstance(s, Fixed) and s.at in by_field]
    # A composed linkage's pivots are its fixed joints' ``at`` fields.
    base = ground[0] if ground else None
    reference: tuple[str, ...] | None = None
    for key, (role, _) in roles.items():
        if role == "direction" and key in by_field and by_field[key].turns == 1.0:
            reference = ("direction", key)
            break
    if reference is None and len(ground) >= 2:
        reference = ("points", ground[0], ground[1])
    return {"base": base, "reference": reference}


def _linkage_vector(linkage: Linkage) -> ParameterVector:
    """A composed linkage's vector: every numeric field of every joint, named ``joint.field``."""
    plan = linkage.plan
    roles = plan_roles(plan)
    space = linkage.space
    params: list[Parameter] = []
    discrete: list[str] = []
    axes: list[str] = []
    for joint in linkage.joints:
        kinds = numeric_kinds(joint, space)
        for attr, what in kinds.items():
            key = f"{joint.name}.{attr}"
            if what == "sign":
                discrete.append(key)
                continue
            if what == "point":
                for k, axis in enumerate("xy"):
                    params.append(Parameter(f"{key[:-3]}.{axis}", "coordinate", key, k, True))
                continue
            if what == "axis":
                axes.append(key)
                for k, part in enumerate(("lon", "lat")):
                    params.append(Parameter(f"{key[:-3]}.{part}", "angle", key, k, True, turns=0.0))
                continue
            role, step = roles.get(key, (None, None))
            if role is not None:
                kind = KIND_OF_ROLE[role]
            elif what == "ratio":
                kind = "ratio"  # a ratio of 1 is written into the plan as a constant
            else:  # pragma: no cover - every other field is a plan parameter
                raise ParameterError(f"joint {joint.name!r}: {attr} is not read by the plan")
            turns: float | None = 0.0
            ratio = None
            if space == "plane" and role == "direction":
                turns = 1.0
            elif space == "plane" and role == "phase" and step is not None:
                turns, ratio = None, step.ratio
            params.append(
                Parameter(
                    key,
                    kind,
                    key,
                    absolute=turns != 0.0,
                    turns=turns,
                    closed=role == "closed-arc",
                    crank_ratio=ratio,
                )
            )
    values = linkage.params()
    vector = ParameterVector(
        family="linkage",
        space=space,
        parameters=tuple(params),
        discrete=tuple(discrete),
        symmetry="similarity" if space == "plane" else "rotation",
        in_family_frame=False,
        base=None,
        reference=None,
        input_turn=_input_turn(plan, values),
        axes=tuple(axes),
    )
    if space == "plane":
        vector = replace(vector, **_gauge(vector, plan, roles))
    return vector


def _discrete_field(name: str, annotation: Any) -> bool:
    # The base class's own conventions: a word field chooses the plan; ``assembly*`` and
    # ``pose`` are branch choices (mechanisms.base checks them so).
    return annotation == "str" or name.startswith("assembly") or name == "pose"


def _probe_instance(cls: type[Mechanism], words: Mapping[str, str]) -> Mechanism:
    """A valid member of a named family, with distinct numbers so that no dependency hides
    behind a coincidence: what the plan reads is found on it."""
    corners = [(0.0, 0.0), (1.3, 0.2), (0.4, -1.1), (-0.7, 0.9), (2.1, 1.7)]
    values: dict[str, Any] = {}
    points = lengths = arcs = others = 0
    for f in fields(cls):
        if f.name == "start":
            continue
        if f.type == "str":
            values[f.name] = words.get(f.name, f.default)
        elif f.name == "pose":
            values[f.name] = 0.0
        elif f.name.startswith("assembly"):
            values[f.name] = 1.0
        elif f.name in cls.point_fields:
            values[f.name] = corners[points % len(corners)]
            points += 1
        elif f.name in cls.length_fields:
            values[f.name] = 1.0 + 0.17 * lengths
            lengths += 1
        elif f.name in cls.arc_fields:
            values[f.name] = 0.9 + 0.07 * arcs
            arcs += 1
        else:
            values[f.name] = 0.31 + 0.113 * others
            others += 1
    return cls(**values)

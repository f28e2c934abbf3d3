"""What an atlas holds for each family: the design distribution it samples, the filter that keeps
only linkages whose input turns fully, and the curve each one traces.

Every atlas mechanism stands in its family's *local frame*, the one
:mod:`linkwright.synthesis.path_families` searches in: planar linkages have the crank pivot A0 at
the origin and the frame line A0→B0 along +x with length 1 (curves are matched up to a
similarity, so the frame's length is the unit); spherical four-bars stand in paper 000's frame.
A stored row is the family's shape parameters (:data:`PARAMS`) then the assembly sign.

Design distributions (``log-uniform`` on [a, b] means exp of a uniform on [ln a, ln b]):

===================  ===========================================================================
family               parameters
===================  ===========================================================================
fourbar              frame 1; crank, coupler, rocker log-uniform on [0.2, 5]; coupler point
                     u = coupler·U(−1, 2), v = coupler·U(−1.5, 1.5); assembly ±1 (½ each)
geared-fivebar       frame 1; crank1, crank2 log-uniform on [0.1, 2]; link1, link2 log-uniform
                     on [0.3, 5]; gear ratio one of −2, −1, 1, 2 (¼ each); gear phase
                     U(−π, π); u = link1·U(−1, 2), v = link1·U(−1.5, 1.5); assembly ±1
spherical-fourbar    frame, crank, coupler, rocker U(10°, 170°); point arc U(0°, 90°); point
                     angle U(−180°, 180°); assembly ±1
===================  ===========================================================================

Kept are the linkages whose input turns fully with the dyad clear of its limit positions all
the way round: the closure margin of :func:`~linkwright.synthesis.path_families.path_margin`
(four-bars; exact over the whole turn), or the same margin of the geared five-bar's dyad
sampled at 256 inputs, at least :data:`MARGIN`. One turn of the input then traces the whole
coupler curve, a closed curve (the five-bar's gear ratios are whole numbers, so it closes after
one turn too).

Every other registered family (:data:`BUILDABLE`: the slider-crank, the double slider, the
six-bars, a composed linkage, the spherical six-bars) is sampled through its parameter vector
(:mod:`linkwright.mechanisms.parameters`) and its search model
(:class:`~linkwright.synthesis.path_models.GenericModel`), in the model's local frame (first
ground pivot at the origin, reference direction along +x; the second ground pivot at (1, 0)
where the reference is the line to it), each number by its kind:

=====================  =======================================================================
kind                   distribution
=====================  =======================================================================
length                 log-uniform on [0.2, 5]
coordinate             U(−2, 2) (a pivot's place, a point's place on its link, a signed length)
angle                  U(−180°, 180°) (an axis's latitude: uniform on the sphere)
arc                    U(10°, 170°); a point's arc from its joint U(0°, 90°)
ratio                  the template's (a gear ratio is chosen, not drawn)
configuration          each combination of the plan's branches (assembly signs, a triad's pose
                       at the input 0) alike
=====================  =======================================================================

A composed linkage keeps its template's structure and configuration, and its numbers are drawn
about the template's own (normalised): lengths × e^N(0, 0.2), coordinates and angles
+ N(0, 0.2), arcs + N(0, 0.1 rad); drawn from the whole box, almost none of a linkage of many
dyads would assemble. Each draw is normalised (:meth:`~linkwright.mechanisms.parameters.
ParameterVector.normalise`: scale 1) and kept when every sample of a turn (256) assembles on its
configuration with every dyad's closure margin (a triad's closure) at least :data:`MARGIN`, and
(a triad's configuration being followed) the turn ends where it began. A family of which too few
draws turn fully (fewer than ``count`` in :data:`ROUNDS` rounds) is refused, naming the share
kept.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from linkwright.curves import (
    descriptor_variants,
    descriptors,
    sphere_descriptor_variants,
    sphere_descriptors,
)
from linkwright.engine import compile as compiled_plans
from linkwright.engine import kernels
from linkwright.mechanisms import FAMILIES as REGISTERED
from linkwright.mechanisms import Mechanism, solve
from linkwright.mechanisms.parameters import ParameterError, family_template
from linkwright.synthesis.path_families import MODELS, Model, path_margin
from linkwright.synthesis.path_models import GenericModel, ModelError, model_for

__all__ = [
    "BUILDABLE",
    "FAMILIES",
    "MARGIN",
    "PARAMS",
    "ROUNDS",
    "AtlasFamilyError",
    "atlas_model",
    "curves",
    "describe",
    "describe_variants",
    "params_of",
    "sample",
    "space_of",
]

Array = NDArray[np.float64]

FAMILIES = ("fourbar", "geared-fivebar", "spherical-fourbar")
"""The families with a hand-written design distribution (the table above) and a built-in atlas."""
BUILDABLE = tuple(REGISTERED)
"""Every family an atlas can be built of: the registered families."""
PARAMS: dict[str, tuple[str, ...]] = {f: MODELS[f].shape_names + ("assembly",) for f in FAMILIES}
MARGIN = 0.01
"""Least closure margin kept (a fraction of the dyad's range; see the module docstring)."""

_GEAR_RATIOS = np.array([-2.0, -1.0, 1.0, 2.0])
_CHECK_SAMPLES = 256
ROUNDS = 64
"""Rounds of draws a generic family gets to yield ``count`` designs that turn fully: each round
draws ``count`` designs, and at least 2,048 (256 with a triad, whose checks cost more)."""
CODE = "configuration"
"""The column of a generic family's row that holds its configuration code."""


class AtlasFamilyError(ValueError):
    """An unknown family, or parameters that do not belong to it."""


def _family(family: str) -> str:
    if family not in BUILDABLE:
        raise AtlasFamilyError(f"family: must be one of {', '.join(BUILDABLE)}, got {family!r}")
    return family


def atlas_model(family: str, template: Mechanism | None = None) -> Model | GenericModel:
    """The model an atlas of ``family`` samples and places through (a composed linkage's needs
    its template)."""
    _family(family)
    try:
        if family in FAMILIES:
            return model_for(family)
        if template is not None and template.family != family:
            raise ModelError(f"template: a {template.family} mechanism, not a {family}")
        return GenericModel(template if template is not None else family_template(family))
    except (ModelError, ParameterError) as exc:
        raise AtlasFamilyError(str(exc)) from None


def params_of(family: str, template: Mechanism | None = None) -> tuple[str, ...]:
    """The names of an atlas row's columns: the shape parameters, then the assembly sign (or a
    generic family's configuration code)."""
    if family in PARAMS:
        return PARAMS[family]
    return atlas_model(family, template).shape_names + (CODE,)


def space_of(family: str, template: Mechanism | None = None) -> str:
    """``"plane"`` or ``"sphere"``: where the family's curves lie."""
    return atlas_model(family, template).space


def _log_uniform(rng: np.random.Generator, lo: float, hi: float, n: int) -> Array:
    return np.exp(rng.uniform(np.log(lo), np.log(hi), n))


def _draw(family: str, rng: np.random.Generator, n: int) -> dict[str, Array]:
    """n designs from the family's distribution (the module docstring's table), unfiltered."""
    sign = np.where(rng.random(n) < 0.5, -1.0, 1.0)
    if family == "fourbar":
        crank, coupler, rocker = (_log_uniform(rng, 0.2, 5.0, n) for _ in range(3))
        return {
            "frame": np.ones(n),
            "crank": crank,
            "coupler": coupler,
            "rocker": rocker,
            "u": coupler * rng.uniform(-1.0, 2.0, n),
            "v": coupler * rng.uniform(-1.5, 1.5, n),
            "assembly": sign,
        }
    if family == "geared-fivebar":
        crank1, crank2 = (_log_uniform(rng, 0.1, 2.0, n) for _ in range(2))
        link1, link2 = (_log_uniform(rng, 0.3, 5.0, n) for _ in range(2))
        return {
            "frame": np.ones(n),
            "crank1": crank1,
            "crank2": crank2,
            "link1": link1,
            "link2": link2,
            "gear_phase": rng.uniform(-np.pi, np.pi, n),
            "ratio": _GEAR_RATIOS[rng.integers(0, _GEAR_RATIOS.size, n)],
            "u": link1 * rng.uniform(-1.0, 2.0, n),
            "v": link1 * rng.uniform(-1.5, 1.5, n),
            "assembly": sign,
        }
    lo, hi = np.radians(10.0), np.radians(170.0)
    return {
        "frame": rng.uniform(lo, hi, n),
        "crank": rng.uniform(lo, hi, n),
        "coupler": rng.uniform(lo, hi, n),
        "rocker": rng.uniform(lo, hi, n),
        "point_arc": rng.uniform(0.0, np.pi / 2, n),
        "point_angle": rng.uniform(-np.pi, np.pi, n),
        "assembly": sign,
    }


def _fivebar_margin(shape: Mapping[str, Array], samples: int = _CHECK_SAMPLES) -> Array:
    """The geared five-bar's least closure margin over a turn, sampled: the dyad A–C–B closes
    while d = |AB| lies in [|link1 − link2|, link1 + link2]; the margin is path_margin's planar
    one, min((l1 + l2)² − d², d² − (l1 − l2)²)/(l1 + l2)²."""
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    c = {k: np.asarray(shape[k])[:, None] for k in shape}
    phi = c["gear_phase"] + c["ratio"] * theta
    dx = c["frame"] + c["crank2"] * np.cos(phi) - c["crank1"] * np.cos(theta)
    dy = c["crank2"] * np.sin(phi) - c["crank1"] * np.sin(theta)
    d2 = dx * dx + dy * dy
    lo, hi = (c["link1"] - c["link2"]) ** 2, (c["link1"] + c["link2"]) ** 2
    margin: Array = np.min(np.minimum(hi - d2, d2 - lo), axis=-1) / hi[:, 0]
    return margin


def _turns_fully(family: str, shape: Mapping[str, Array]) -> NDArray[np.bool_]:
    margin = path_margin(MODELS[family], shape, 0.0, 2.0 * np.pi)
    if margin is not None:
        return margin >= MARGIN
    # Most draws fail already at one of 16 inputs: only the rest are checked at 256.
    ok = _fivebar_margin(shape, 16) >= MARGIN
    ok[ok] = _fivebar_margin({k: v[ok] for k, v in shape.items()}) >= MARGIN
    return ok


def sample(
    family: str, rng: np.random.Generator, count: int, template: Mechanism | None = None
) -> dict[str, Array]:
    """``count`` designs of ``family`` from its distribution, keeping only those whose input
    turns fully (module docstring). Draws rounds of ``count`` candidates until enough are kept,
    so the result depends on ``rng``'s state alone.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> designs = sample("fourbar", rng, 1000)
    >>> sorted(designs) == sorted(PARAMS["fourbar"]), designs["crank"].shape
    (True, (1000,))

    Each one's crank turns fully: Grashof's condition, with the crank or the frame shortest.

    >>> lengths = np.stack([designs[k] for k in ("frame", "crank", "coupler", "rocker")])
    >>> s, l = lengths.min(0), lengths.max(0)
    >>> bool(np.all(s + l <= lengths.sum(0) - s - l))
    True
    >>> bool(np.all((designs["crank"] == s) | (designs["frame"] == s)))
    True
    """
    _family(family)
    if count < 0:
        raise AtlasFamilyError(f"count: must not be negative, got {count}")
    if family not in FAMILIES:
        return _sample_generic(atlas_model(family, template), rng, count)  # type: ignore[arg-type]
    kept: list[dict[str, Array]] = []
    total = 0
    while total < count:
        draw = _draw(family, rng, max(count, 1))
        ok = _turns_fully(family, draw)
        kept.append({k: v[ok] for k, v in draw.items()})
        total += int(ok.sum())
    out = {k: np.concatenate([d[k] for d in kept])[:count] for k in PARAMS[family]}
    return out


def curves(
    family: str, params: Mapping[str, Array], samples: int, template: Mechanism | None = None
) -> Array:
    """The coupler curves (n, samples, 2), or unit vectors (n, samples, 3) on the sphere, of
    the designs ``params`` in the local frame, at ``samples`` inputs equally spaced over one
    turn from the frame line. NaN where a design does not assemble.

    Examples
    --------
    The four-bar with frame 1, crank 0.5, coupler 1.2, rocker 1 and P at the coupler's B end
    traces B, 1 from B0 = (1, 0):

    >>> one = {"frame": [1.0], "crank": [0.5], "coupler": [1.2], "rocker": [1.0],
    ...        "u": [1.2], "v": [0.0], "assembly": [1.0]}
    >>> P = curves("fourbar", one, 8)
    >>> np.hypot(P[0, :, 0] - 1, P[0, :, 1]).round(12)
    array([1., 1., 1., 1., 1., 1., 1., 1.])
    """
    _family(family)
    if family not in FAMILIES:
        model = atlas_model(family, template)
        names = params_of(family, template)
        p = {k: np.atleast_1d(np.asarray(params[k], dtype=float)) for k in names}
        code = p.pop(CODE)
        turns = model.turns  # type: ignore[union-attr]
        theta = np.linspace(0.0, 2.0 * np.pi * turns, samples, endpoint=False)
        if not model.triads and compiled_plans.available():  # type: ignore[union-attr]
            # The traced point alone through the plan's compiled kernel (same numbers).
            return _compiled_curve(model.local(p, code), model.traced, theta)
        return model.evaluate(p, code, theta, around=False)[0]  # type: ignore[union-attr]
    p = {k: np.atleast_1d(np.asarray(params[k], dtype=float)) for k in PARAMS[family]}
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    n = p["assembly"].shape[0]
    if family == "fourbar" and kernels.available():
        a0 = np.zeros((n, 2))
        b0 = np.stack([p["frame"], np.zeros(n)], axis=-1)
        args = (p["crank"], p["coupler"], p["rocker"], p["u"], p["v"], p["assembly"])
        return kernels.fourbar_coupler_points(a0, b0, *args, theta)
    if family == "spherical-fourbar" and kernels.available():
        names = ("frame", "crank", "coupler", "rocker", "point_arc", "point_angle", "assembly")
        frame, crank, coupler, rocker, arc, angle, assembly = (p[k] for k in names)
        return kernels.spherical_fourbar_coupler_points(
            frame, crank, coupler, rocker, arc, angle, assembly, theta
        )
    mech = MODELS[family].local(p, p["assembly"])
    if compiled_plans.available():
        return _compiled_curve(mech, "P", theta)
    return solve(mech, theta, order=0).positions["P"]


def _compiled_curve(mech: Mechanism, joint: str, theta: Array) -> Array:
    """``solve(mech, theta, order=0).positions[joint]``, computed by the compiled plan, which
    writes that joint's positions only (NaN where the design does not assemble)."""
    plan = compiled_plans.compiled_plan(mech.plan)
    return plan.positions(mech.params(), theta, (joint,), points=mech.points)[joint]


def describe(
    family: str, points: Array, harmonics: int, template: Mechanism | None = None
) -> Array:
    """Descriptors of closed curves traced by ``family`` (planar or spherical)."""
    if space_of(_family(family), template) == "sphere":
        return sphere_descriptors(points, harmonics=harmonics)
    return descriptors(points, harmonics=harmonics)


def describe_variants(
    family: str, points: Array, harmonics: int, template: Mechanism | None = None
) -> Array:
    """Every descriptor variant (…, V, D) of closed curves, for queries."""
    if space_of(_family(family), template) == "sphere":
        return sphere_descriptor_variants(points, harmonics=harmonics)
    return descriptor_variants(points, harmonics=harmonics)


# --------------------------------------------------------------------------------------------
# Every other family, through its parameter vector
# --------------------------------------------------------------------------------------------


def _draw_generic(model: GenericModel, rng: np.random.Generator, n: int) -> dict[str, Array]:
    """n designs of a generic family from its distribution (module docstring), unfiltered."""
    v = model.vector
    around = None
    if model.family == "linkage":
        own = v.to_vector(v.normalise(model.template))
        around = {name: float(own[i]) for i, name in enumerate(v.names)}
    out: dict[str, Array] = {}
    for name in model.shape_names:
        p = v.parameter(name)
        gauge = name in model.lengths and p.kind in ("coordinate", "angle")
        if around is not None:
            t = around[name]
            if p.kind == "length" or (gauge and p.kind == "coordinate"):
                out[name] = t * np.exp(rng.normal(0.0, 0.2, n))
            elif p.kind == "arc" or gauge:
                hi = np.pi if p.closed else np.radians(178.0)
                lo = 0.0 if p.closed else np.radians(2.0)
                out[name] = np.clip(t + rng.normal(0.0, 0.1, n), lo, hi)
            elif p.kind == "ratio":
                out[name] = np.full(n, t)
            else:
                out[name] = t + rng.normal(0.0, 0.2, n)
        elif gauge and p.kind == "coordinate":
            out[name] = np.ones(n)  # the second ground pivot at (1, 0): the unit of length
        elif p.kind == "length":
            out[name] = _log_uniform(rng, 0.2, 5.0, n)
        elif p.kind == "coordinate":
            out[name] = rng.uniform(-2.0, 2.0, n)
        elif p.kind == "arc" or gauge:
            hi = np.pi / 2 if p.closed else np.radians(170.0)
            out[name] = rng.uniform(0.0 if p.closed else np.radians(10.0), hi, n)
        elif p.kind == "ratio":
            out[name] = np.full(n, float(np.asarray(v.to_vector(model.template))[v.index(name)]))
        elif p.component == 1 and p.absolute:  # an axis's latitude: uniform on the sphere
            out[name] = np.arcsin(rng.uniform(-1.0, 1.0, n))
        else:
            out[name] = rng.uniform(-np.pi, np.pi, n)
    if model.family == "linkage":
        out[CODE] = np.zeros(n)
    else:
        out[CODE] = rng.integers(0, len(model.combos), n).astype(float)
    return out


def _generic_turns_fully(
    model: GenericModel, draw: Mapping[str, Array], samples: int
) -> NDArray[np.bool_]:
    """Which draws assemble at every sample of a turn on their configuration, every closure
    margin at least MARGIN, and (followed through a triad) end the turn where they began."""
    shape = {k: v for k, v in draw.items() if k != CODE}
    theta = np.linspace(0.0, 2.0 * np.pi * model.turns, samples + 1)
    # Forwards only: a full turn is one branch run from the input 0 round to 2π.
    _, valid, motion = model.evaluate(shape, draw[CODE], theta, around=False)
    ok = valid.all(axis=1)
    triads = {t.name for t in model.triads}
    for name in model.branch_steps:
        m = motion.margins[name]
        m = np.abs(m) if name in triads else m
        ok &= np.min(np.where(np.isfinite(m), m, -1.0), axis=1) >= MARGIN
    if triads:
        size = max(float(np.nanmax(np.abs(p))) for p in motion.positions.values())
        for p in motion.positions.values():
            ok &= np.all(np.abs(p[:, 0] - p[:, -1]) <= 1e-7 * max(size, 1.0), axis=-1)
    return np.asarray(ok)


def _sample_generic(model: GenericModel, rng: np.random.Generator, count: int) -> dict[str, Array]:
    names = model.shape_names + (CODE,)
    kept: list[dict[str, Array]] = []
    total = drawn = 0
    size = max(count, 256 if model.triads else 2048)
    for _ in range(ROUNDS):
        if total >= count:
            break
        draw = _draw_generic(model, rng, size)
        drawn += size
        ok = _generic_turns_fully(model, draw, 16)
        if ok.any():
            sub = {k: v[ok] for k, v in draw.items()}
            ok2 = _generic_turns_fully(model, sub, _CHECK_SAMPLES)
            kept.append(_normalised(model, {k: v[ok2] for k, v in sub.items()}))
            total += int(ok2.sum())
    if total < count:
        raise AtlasFamilyError(
            f"{model.family}: only {total} of {drawn} designs drawn turn fully clear of their "
            f"limit positions, fewer than the {count} asked for; ask for fewer"
            + (" or give a template that turns fully" if model.family == "linkage" else "")
        )
    return {k: np.concatenate([d[k] for d in kept])[:count] for k in names}


def _normalised(model: GenericModel, draw: Mapping[str, Array]) -> dict[str, Array]:
    """The draws in the vector's canonical place (scale 1); the configuration as it was."""
    if len(draw[CODE]) == 0:
        return dict(draw)
    shape = {k: v for k, v in draw.items() if k != CODE}
    mech = model.vector.normalise(model.local(shape, draw[CODE]))
    x = model.vector.to_vector(mech)
    out = {name: x[..., model.vector.index(name)] for name in model.shape_names}
    out[CODE] = draw[CODE]
    return out

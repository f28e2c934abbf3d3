"""Matching a curve against an atlas: nearest descriptors, re-ranked by the aligned error,
placed where the query was drawn, optionally refined.

1. The query's descriptor variants are searched in the atlas's index for ``candidates`` entries.
2. Each candidate's curve is traced again, densely (256 inputs), and aligned onto the query
   (:func:`linkwright.curves.align`: a similarity in the plane, a rotation of the sphere; best
   start and direction); candidates are ranked by that aligned error.
3. Each of the best ``top`` is carried by its transform into the query's frame: in the plane its
   lengths are scaled, its crank pivot moved and its frame line turned; on the sphere its axes
   are rotated. So each one traces the query where the user drew it.
4. With ``refine``, the best few are optimised locally (:func:`linkwright.synthesis.fit_path`
   started from them within tight bounds, no timing, closed curve) until the RMS distance from
   the query's points to the curve is within ``tolerance`` of the query's size, or the budget
   runs out; a refinement is kept only where it is better. It fits at most
   :data:`REFINE_POINTS` of the points, evenly spaced along the query (its cost grows faster
   than their count); the distance that decides is measured to all of them.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial import cKDTree

from linkwright.atlas.atlas import Atlas
from linkwright.atlas.families import CODE, atlas_model, curves, describe_variants
from linkwright.curves import Alignment, SphereAlignment, align, sphere_align
from linkwright.engine import cost
from linkwright.mechanisms import Mechanism, solve
from linkwright.synthesis.path_families import Model, rodrigues, sphere_rotation
from linkwright.synthesis.path_models import GenericModel

__all__ = ["AtlasQueryError", "Match", "query"]

Array = NDArray[np.float64]

RANK_SAMPLES = 256
REFINED = 3
"""How many of the best matches ``refine`` optimises."""
DISTANCE_SAMPLES = 1024
REFINE_POINTS = int(cost.REFINE_POINTS.value)
"""Most query points a refinement fits (:data:`linkwright.engine.cost.REFINE_POINTS`)."""


class AtlasQueryError(ValueError):
    """A query that cannot be matched (names the problem)."""


@dataclass(frozen=True)
class Match:
    """One atlas entry matched to a query curve.

    Attributes
    ----------
    atlas_id : the entry's row in the atlas.
    mechanism : the linkage placed in the query's frame (planar: the family's mechanism;
        sphere: a spherical :class:`~linkwright.mechanisms.Linkage`), tracing the query.
    named : the same linkage as its named family (sphere: the
        :class:`~linkwright.mechanisms.SphericalFourBar` in paper 000's frame).
    error : aligned RMS error of the curve against the query, relative to the query's RMS
        radius (plane) or RMS chord from its mean direction (sphere).
    distance : RMS distance from the query's points to ``mechanism``'s curve, in the query's
        units (chords on the sphere): no realignment, the placed linkage itself.
    scale, rotation, translation : the transform that carried the atlas curve onto the query:
        query ≈ scale·R(rotation)·atlas + translation (plane, rotation in radians); on the sphere
        scale 1, rotation the 3×3 matrix and translation None.
    descriptor_distance : the index's distance (squared, between descriptors).
    refined : whether ``mechanism`` came from the local refinement.
    """

    atlas_id: int
    mechanism: Mechanism
    named: Mechanism
    error: float
    distance: float
    scale: float
    rotation: float | Array
    translation: Array | None
    descriptor_distance: float
    refined: bool = False
    params: dict[str, float] = field(default_factory=dict, repr=False)
    """The placed linkage's parameters (pose and shape, :func:`fit_path`'s names)."""


def _query_points(space: str, points: ArrayLike) -> Array:
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise AtlasQueryError("points: must be numbers") from None
    dim = 2 if space == "plane" else 3
    if p.ndim != 2 or p.shape[1] != dim:
        what = "(N, 2) points" if dim == 2 else "(N, 3) unit vectors"
        raise AtlasQueryError(f"points: this atlas's curves need {what}, got shape {p.shape}")
    if len(p) < 3:
        raise AtlasQueryError(f"points: a curve needs at least 3 points, got {len(p)}")
    if not np.all(np.isfinite(p)):
        raise AtlasQueryError("points: must be finite (found NaN or infinity)")
    if dim == 3:
        r = np.linalg.norm(p, axis=1)
        if np.any(np.abs(r - 1.0) > 0.01):
            raise AtlasQueryError(
                "points: must be unit vectors on the sphere (within 1 %); for points on "
                "another sphere, fit_sphere(points).directions from linkwright.geometry.sphere_fit"
            )
        p = p / r[:, None]
    span = np.max(np.linalg.norm(p - p.mean(axis=0), axis=1))
    if not span > 1e-12 * max(1.0, float(np.max(np.abs(p)))):
        raise AtlasQueryError("points: all the same point; a curve needs extent")
    return p


def _to_sphere_pose(R: Array) -> tuple[float, float, float]:
    """(lon, sinlat, spin) of a rotation as :func:`sphere_rotation` builds it."""
    a0, t = R[:, 0], R[:, 1]
    lon = float(np.arctan2(a0[1], a0[0]))
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(a0, east)
    return lon, float(np.clip(a0[2], -1.0, 1.0)), float(np.arctan2(t @ north, t @ east))


def _placed_params(
    model: Any, design: dict[str, float], fit: Alignment | SphereAlignment, k: int
) -> dict[str, float]:
    """The atlas design ``design`` carried by alignment ``fit`` (entry k) into the query frame,
    as fit_path's parameters."""
    out = dict(design)
    if model.space == "sphere":
        lon, sinlat, spin = _to_sphere_pose(fit.rotation[k])
        out.update(lon=lon, sinlat=sinlat, spin=spin)
        return out
    assert isinstance(fit, Alignment)  # a planar model's fit is planar
    s = float(fit.scale[k])
    for name in model.linear:
        if name in design:
            out[name] = design[name] * s
    tx, ty = (float(c) for c in fit.translation[k])
    out.update(x=tx, y=ty, frame_angle=float(fit.rotation[k]))
    return out


def _code(params: dict[str, float]) -> float:
    """The row's assembly sign (or a generic family's configuration code)."""
    return params["assembly"] if "assembly" in params else params[CODE]


class _Placed:
    """A design placed in the query's frame: its linkage (user's frame and the family's own)
    and its traced point at any inputs, on the design's configuration."""

    def __init__(self, model: Any, params: dict[str, float], pose: Any = None) -> None:
        self.model = model
        shape = {k: params[k] for k in model.shape_names}
        if pose is None:
            if model.space == "sphere":
                pose = sphere_rotation(
                    np.array(params["lon"]), np.array(params["sinlat"]), np.array(params["spin"])
                )
            else:
                pose = (params["x"], params["y"], params["frame_angle"])
        self.code = _code(params)
        self.user, self.named, self.rotation = model.placed(shape, self.code, pose)
        self.turns = getattr(model, "turns", 1)
        self.offset = 0.0
        if isinstance(model, GenericModel):
            self.offset = model.input_offset(pose)
            self.local = model.local(shape, self.code)
            if model.space == "sphere":
                R = np.asarray(pose, dtype=float)
                self.transform = lambda p: np.asarray(p) @ R.T
            else:
                x, y, a = (float(v) for v in pose)
                c, n = np.cos(a), np.sin(a)
                self.transform = lambda p: np.stack(
                    (x + c * p[..., 0] - n * p[..., 1], y + n * p[..., 0] + c * p[..., 1]), -1
                )

    def points(self, inputs: Array) -> Array:
        if isinstance(self.model, Model):
            return solve(self.user, inputs, order=0).positions["P"]
        traced: Array = self.model.reach(
            self.user, self.local, self.code, inputs, self.offset, self.transform
        )[0]
        return traced

    def curve(self, samples: int) -> tuple[Array, Array]:
        """Inputs over one period of the input (from the frame's 0) and the traced points."""
        theta = self.offset + np.linspace(0.0, 2.0 * np.pi * self.turns, samples, endpoint=False)
        return theta, self.points(theta)


def _distance(points: Array, curve: Array) -> float:
    """RMS distance from each point to the closed polyline ``curve`` (chords on the sphere):
    the foot on either segment beside the point's nearest vertex (the curve is sampled finely
    enough that the nearest segment is one of those two)."""
    m = len(curve)
    near = cKDTree(curve).query(points)[1]
    best = np.full(len(points), np.inf)
    for first in (near - 1, near):
        a, b = curve[first % m], curve[(first + 1) % m]
        d, rel = b - a, points - a
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.clip(np.sum(rel * d, -1) / np.sum(d * d, -1), 0.0, 1.0)
        gap = rel - np.nan_to_num(t)[:, None] * d
        best = np.minimum(best, np.sum(gap * gap, -1))
    return float(np.sqrt(np.mean(best)))


def _aligned(
    space: str, curve: Array, target: Array, samples: int = RANK_SAMPLES
) -> Alignment | SphereAlignment:
    if space == "plane":
        return align(curve, target, samples=samples)
    return sphere_align(curve, target, samples=samples)


def query(
    atlas: Atlas,
    points: ArrayLike,
    *,
    top: int = 5,
    candidates: int | None = None,
    refine: bool = False,
    tolerance: float = 0.001,
    budget: float = 5.0,
    progress: Callable[[float], None] | None = None,
    open_curve: bool = False,
) -> list[Match]:
    """The ``top`` atlas entries whose curves best match the closed curve through ``points``,
    best first, each placed in the query's frame (module docstring). Refinements that converge
    to one linkage are returned once, so ``refine`` may return fewer than ``top``.

    With ``open_curve`` the points are an open curve, a piece of the curve wanted: every entry
    is screened for the arc that best matches it, and the best are fitted by iterated closest
    points (:mod:`linkwright.atlas.partial`); ``error`` is then the RMS distance over the
    query's RMS radius (on the sphere its RMS chord from its mean direction).

    Parameters
    ----------
    atlas : an opened atlas (:func:`~linkwright.atlas.open_atlas`,
        :func:`~linkwright.atlas.default_atlas`).
    points : (N, 2) points of the query curve, or (N, 3) unit vectors for a spherical atlas; the
        last point joins the first.
    top : matches returned.
    candidates : entries taken from the index and re-ranked; default max(50, 10·top).
    refine : optimise the best :data:`REFINED` matches locally (deterministically).
    tolerance : refinement stops once the RMS distance from the query's points to the curve is
        at most this fraction of the query's size (its RMS radius; on the sphere its RMS chord
        from its mean direction).
    budget : seconds for each refinement.
    progress : called with the fraction done, in [0, 1].

    Raises
    ------
    AtlasQueryError
        For points that are not a curve of this atlas's space, or bad counts.
    """
    family = atlas.family
    template = atlas.spec.mechanism
    model = atlas_model(family, template)
    q = _query_points(model.space, points)
    if not (isinstance(top, int) and top >= 1):
        raise AtlasQueryError(f"top: must be a whole number ≥ 1, got {top!r}")
    want = max(50, 10 * top) if candidates is None else int(candidates)
    if want < top:
        raise AtlasQueryError(f"candidates: must be at least top ({top}), got {want}")
    if not (tolerance > 0):
        raise AtlasQueryError(f"tolerance: must be positive, got {tolerance}")
    if open_curve:
        return _open_query(atlas, model, q, top, want, refine, tolerance, budget, progress)
    variants = describe_variants(family, q[None], atlas.spec.harmonics, template)[0]
    dist, ids = atlas.index.search(variants, variants.shape[0], min(want, atlas.count))
    keep = ids[0] >= 0
    dist, ids = dist[0][keep], ids[0][keep]
    # Ranked coarsely (64 samples) first, then the best few finely: the aligned error's
    # refinement between samples is the query's largest cost.
    coarse = _aligned(model.space, curves(family, atlas.designs(ids), 64, template), q, 64).error
    keep = np.argsort(np.where(np.isfinite(coarse), coarse, np.inf), kind="stable")
    keep = np.sort(keep[: max(2 * top, 10)])
    dist, ids = dist[keep], ids[keep]
    designs = atlas.designs(ids)
    fit = _aligned(model.space, curves(family, designs, RANK_SAMPLES, template), q)
    order = np.argsort(np.where(np.isfinite(fit.error), fit.error, np.inf), kind="stable")[:top]
    size = _size(model.space, q)
    # The chosen curves, densely, carried by their transforms: what each placed linkage traces.
    dense = curves(family, {n: v[order] for n, v in designs.items()}, DISTANCE_SAMPLES, template)
    if isinstance(fit, SphereAlignment):
        dense = np.einsum("kij,knj->kni", fit.rotation[order], dense)
    else:
        c, s = np.cos(fit.rotation[order]), np.sin(fit.rotation[order])
        turn = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)
        dense = fit.scale[order, None, None] * np.einsum("kij,knj->kni", turn, dense)
        dense = dense + fit.translation[order][:, None, :]
    matches: list[Match] = []
    for rank, k in enumerate(order):
        matches.append(
            _match(model, designs, fit, int(k), int(ids[k]), _distance(q, dense[rank]), dist[k])
        )
        if progress:
            progress(0.2 * (rank + 1) / len(order) if refine else (rank + 1) / len(order))
    if refine:
        matches = _refine_best(model, q, matches, size, tolerance, budget, progress, 0.2)
    return matches


SCREEN_SAMPLES = 64
"""Samples of each entry's curve in the open-curve screen."""
SCREEN_CHUNK = 20_000
"""Entries screened at once (the screen holds a few complex arrays of this many curves)."""
OPEN_SHORTLIST = 1500
"""Entries of an open-curve screen that go on to a quick fit."""
OPEN_COARSE = 256
"""Samples of each shortlisted curve in the quick fit."""


def _open_query(
    atlas: Atlas,
    model: Any,
    q: Array,
    top: int,
    want: int,
    refine: bool,
    tolerance: float,
    budget: float,
    progress: Callable[[float], None] | None,
) -> list[Match]:
    """:func:`query` for an open curve (its docstring)."""
    from linkwright.atlas.partial import (
        QUERY_SAMPLES,
        by_length,
        fit_piece,
        fit_sphere_pieces,
        resampled,
        screen_pieces,
        screen_sphere_pieces,
    )

    family, template = atlas.family, atlas.spec.mechanism
    sphere = model.space == "sphere"
    most = int(cost.OPEN_SCREEN.value)
    if atlas.count > most:
        raise AtlasQueryError(
            f"open_curve: an open curve is screened against every entry, and this atlas has "
            f"{atlas.count:,} (at most {most:,}: {cost.OPEN_SCREEN.why}); match it against a "
            "smaller atlas"
        )
    piece = resampled(q, QUERY_SAMPLES)
    score = np.full(atlas.count, np.inf)
    # Where each entry's best arc is laid: a similarity w, t (complex) in the plane, a rotation
    # about the centre on the sphere.
    ws = np.full(atlas.count, np.nan + 0j)
    ts = np.full(atlas.count, np.nan + 0j)
    turns = np.full((atlas.count, 3, 3), np.nan) if sphere else None
    # The sphere's screen holds nine correlations of every curve at once: fewer at a time.
    chunk = SCREEN_CHUNK // 4 if sphere else SCREEN_CHUNK
    for start in range(0, atlas.count, chunk):
        cost.check_time()
        ids = np.arange(start, min(start + chunk, atlas.count))
        traced = curves(family, atlas.designs(ids), 2 * SCREEN_SAMPLES, template)
        arcs = by_length(traced, SCREEN_SAMPLES)
        if turns is not None:
            score[ids], turns[ids] = screen_sphere_pieces(arcs, piece)
        else:
            score[ids], ws[ids], ts[ids] = screen_pieces(arcs, piece)
        if progress:
            progress(0.5 * min(1.0, (start + chunk) / atlas.count))

    def fitted_pieces(
        curves: Array, points: Array, entries: Array, hows: list[Any] | None
    ) -> list[tuple[Any, float]]:
        """[(how each is laid, RMS distance)] of curves fitted to ``points``, from ``hows`` (or
        from the screen's placements of ``entries``)."""
        if turns is not None:
            start = turns[entries] if hows is None else np.array(hows)
            found, distances = fit_sphere_pieces(curves, points, start)
            return [(f, float(d)) for f, d in zip(found, distances, strict=True)]
        out: list[tuple[Any, float]] = []
        for k, i in enumerate(entries):
            w, t = (complex(ws[i]), complex(ts[i])) if hows is None else hows[k]
            w, t, gap = fit_piece(curves[k], points, w, t)
            out.append(((w, t), gap))
        return out

    def laid(curve: Array, how: Any) -> Array:
        return curve @ how.T if turns is not None else _carried(curve, *how)

    # A short piece is ambiguous, and the screen's arcs and starts are quantised: many entries
    # go on to a quick fit (a coarse curve, the query thinned), the best of them to a fine one.
    shortlist = np.argsort(score, kind="stable")[: min(OPEN_SHORTLIST, atlas.count)]
    shortlist = shortlist[np.isfinite(score[shortlist])]
    coarse = curves(family, atlas.designs(shortlist), OPEN_COARSE, template)
    first = fitted_pieces(coarse, piece, shortlist, None)
    keep = np.argsort([f[1] for f in first], kind="stable")[: max(want // 2, top)]
    chosen = shortlist[keep]
    designs = atlas.designs(chosen)
    dense = curves(family, designs, DISTANCE_SAMPLES, template)
    size = _size(model.space, q)
    # Fitted on the query resampled (its cost is points × curve samples a round), then measured
    # on every point.
    fit_points = resampled(q, min(len(q), 2 * QUERY_SAMPLES))
    fitted = fitted_pieces(dense, fit_points, chosen, [first[j][0] for j in keep])
    rms = np.array([_distance(q, laid(dense[k], f[0])) for k, f in enumerate(fitted)])
    order = np.argsort(np.where(np.isfinite(rms), rms, np.inf), kind="stable")[:top]
    none, zeros = np.zeros(len(fitted), dtype=bool), np.zeros(len(fitted))
    fit: Alignment | SphereAlignment
    if turns is not None:
        fit = SphereAlignment(
            error=rms / size, rms=rms, rotation=np.array([f[0] for f in fitted]),
            reversed=none, shift=zeros,
        )  # fmt: skip
    else:
        w = np.array([f[0][0] for f in fitted])
        t = np.array([f[0][1] for f in fitted])
        fit = Alignment(
            error=rms / size, rms=rms, scale=np.abs(w), rotation=np.angle(w),
            translation=np.stack([t.real, t.imag], -1), reversed=none, shift=zeros,
        )  # fmt: skip
    matches = []
    for rank, k in enumerate(order):
        if not np.isfinite(rms[k]):
            break
        matches.append(
            _match(model, designs, fit, int(k), int(chosen[k]), rms[k], score[chosen[k]])
        )
        if progress:
            progress(0.5 + (0.1 if refine else 0.5) * (rank + 1) / len(order))
    if refine:
        matches = _refine_best(model, q, matches, size, tolerance, budget, progress, 0.6)
        # The error of an open match is its distance over the query's size, refined or not.
        matches = [replace(m, error=m.distance / size) for m in matches]
    return matches


def _match(
    model: Any,
    designs: dict[str, Array],
    fit: Alignment | SphereAlignment,
    k: int,
    atlas_id: int,
    distance: float,
    descriptor_distance: float,
) -> Match:
    """Entry ``k`` of ``designs`` carried by ``fit`` into the query's frame, as a match."""
    design = {name: float(v[k]) for name, v in designs.items()}
    params = _placed_params(model, design, fit, k)
    placed = _Placed(model, params)
    scale: float
    rotation: float | Array
    translation: Array | None
    if isinstance(fit, SphereAlignment):
        scale, rotation, translation = 1.0, np.array(fit.rotation[k]), None
    else:
        scale, rotation = float(fit.scale[k]), float(fit.rotation[k])
        translation = np.array(fit.translation[k])
    return Match(
        atlas_id=atlas_id,
        mechanism=placed.user,
        named=placed.named,
        error=float(fit.error[k]),
        distance=float(distance),
        scale=scale,
        rotation=rotation,
        translation=translation,
        descriptor_distance=float(descriptor_distance),
        params=params,
    )


def _refine_best(
    model: Any,
    q: Array,
    matches: list[Match],
    size: float,
    tolerance: float,
    budget: float,
    progress: Callable[[float], None] | None,
    done: float,
) -> list[Match]:
    """The best :data:`REFINED` matches refined (each kept only where better), all of them
    sorted by distance and without repeats; ``progress`` runs on from ``done`` to 1."""
    chosen = matches[:REFINED]
    fitted = thinned(q, REFINE_POINTS)
    for i, m in enumerate(chosen):
        cost.check_time()
        better = _refine(model, fitted, m, size, tolerance, budget, q)
        if better is not None:
            matches[i] = better
        if progress:
            progress(done + (1.0 - done) * (i + 1) / len(chosen))
    matches.sort(key=lambda m: m.distance)
    return _distinct(matches, size, set(model.linear) | {"x", "y"})


def _carried(curve: Array, w: complex, t: complex) -> Array:
    """Points (n, 2) moved by the similarity p ↦ w·p + t (complex)."""
    z = w * (curve[:, 0] + 1j * curve[:, 1]) + t
    return np.stack([z.real, z.imag], -1)


def _distinct(matches: list[Match], size: float, scaled: set[str]) -> list[Match]:
    """Matches without repeats: refinements of different entries can converge to one linkage,
    and a designer choosing among candidates wants each once. ``scaled``: the parameters in
    the curve's units (lengths, places)."""

    def close(a: Match, b: Match) -> bool:
        # Within 0.1 % of the curve's size (lengths, places) or 1e-3 rad (angles, arcs).
        planar = a.translation is not None
        return a.params.keys() == b.params.keys() and all(
            abs(a.params[n] - b.params[n]) <= 1e-3 * (size if planar and n in scaled else 1)
            for n in a.params
        )

    kept: list[Match] = []
    for m in matches:
        same = any(close(m, k) for k in kept)
        if not same:
            kept.append(m)
    return kept


def _size(space: str, q: Array) -> float:
    """The query's size: RMS distance of its points from their centroid (plane), or RMS chord
    from their mean direction (sphere)."""
    c = q.mean(axis=0)
    if space == "sphere":
        c = c / np.linalg.norm(c)
    return float(np.sqrt(np.mean(np.sum((q - c) ** 2, axis=1))))


def thinned(points: Array, most: int) -> Array:
    """At most ``most`` of ``points``, evenly spaced along them (the first and last kept).

    >>> thinned(np.arange(10.0)[:, None], 4).ravel()
    array([0., 3., 6., 9.])
    """
    if len(points) <= most:
        return points
    kept: Array = points[np.linspace(0, len(points) - 1, most).round().astype(int)]
    return kept


def _refine(
    model: Any,
    q: Array,
    m: Match,
    size: float,
    tolerance: float,
    budget: float,
    everything: Array | None = None,
) -> Match | None:
    """Least squares from the match: its parameters and one input per fitted point ``q``
    together, residuals P(θ_i) − q_i, so the optimum puts each θ_i at its point's foot on the
    curve and minimises the RMS distance from the points to the curve. Lengths move as
    logarithms (they stay positive), arcs within (0, π); the sphere's pose as a small rotation
    after the match's. Whether it is better is judged by the distance to ``everything`` (all
    the query's points; default ``q``)."""
    everything = q if everything is None else everything
    p0 = dict(m.params)
    sphere = model.space == "sphere"
    names = [n for n in model.shape_names if n not in getattr(model, "ratios", ("ratio",))]
    names += ["w0", "w1", "w2"] if sphere else ["x", "y", "frame_angle"]
    logs = [n in model.lengths and not sphere for n in names]
    x0 = np.array([np.log(p0[n]) if lg else (0.0 if n[0] == "w" and sphere else p0[n])
                   for n, lg in zip(names, logs, strict=True)])  # fmt: skip
    R0 = np.asarray(m.rotation) if sphere else None
    lo = np.full(len(names), -np.inf)
    hi = np.full(len(names), np.inf)
    if sphere:
        for i, n in enumerate(names):
            if n in model.lengths:
                lo[i], hi[i] = 1e-3, np.pi - 1e-3
            elif n in getattr(model, "closed_arcs", ("point_arc",)):
                lo[i], hi[i] = 0.0, np.pi
    x0 = np.clip(x0, lo + 1e-12, hi - 1e-12)

    def params_of(x: Array) -> dict[str, float]:
        out = dict(p0)
        for n, lg, v in zip(names, logs, x, strict=True):
            out[n] = float(np.exp(v)) if lg else float(v)
        return out

    def mechanism(x: Array) -> _Placed | None:
        par = params_of(x)
        pose: Array | tuple[float, float, float]
        if sphere:
            assert R0 is not None  # set above for a spherical model
            pose = R0 @ rodrigues(np.array([par["w0"], par["w1"], par["w2"]]))
        else:
            pose = (par["x"], par["y"], par["frame_angle"])
        try:
            return _Placed(model, par, pose)
        except ValueError:
            return None

    # Each point's input starts at its nearest sample of the match's curve.
    start = mechanism(x0)
    if start is None:
        return None
    theta_grid, dense = start.curve(DISTANCE_SAMPLES)
    near = np.argmin(np.sum((q[:, None, :] - dense[None]) ** 2, axis=-1), axis=1)
    n_par, n_pts = len(names), len(q)
    z0 = np.concatenate([x0, theta_grid[near]])

    def residuals(z: Array) -> Array:
        placed = mechanism(z[:n_par])
        if placed is None:
            return np.full(n_pts * q.shape[1], 10.0 * size)
        P = placed.points(z[n_par:])
        return np.nan_to_num(P - q, nan=10.0 * size).ravel()

    sparsity = np.zeros((n_pts * q.shape[1], n_par + n_pts), dtype=bool)
    sparsity[:, :n_par] = True
    for i in range(n_pts):
        sparsity[i * q.shape[1] : (i + 1) * q.shape[1], n_par + i] = True
    goal = tolerance * size
    began = time.perf_counter()
    z, best = z0, float(np.sqrt(np.mean(residuals(z0).reshape(n_pts, -1) ** 2) * q.shape[1]))
    bounds = (np.r_[lo, np.full(n_pts, -np.inf)], np.r_[hi, np.full(n_pts, np.inf)])
    while best > goal and time.perf_counter() - began < budget:
        cost.check_time()
        sol = least_squares(
            residuals, z, jac_sparsity=sparsity, bounds=bounds, method="trf", max_nfev=60,
            x_scale="jac",
        )  # fmt: skip
        rms = float(np.sqrt(2.0 * sol.cost / n_pts))
        if not rms < best * (1 - 1e-3):
            break
        z, best = sol.x, rms
    user = mechanism(z[:n_par])
    if user is None:
        return None
    traced = user.curve(DISTANCE_SAMPLES)[1]
    if not np.all(np.isfinite(traced)):
        return None  # refined past a limit position: the input no longer turns fully
    distance = _distance(everything, traced)
    if not distance < m.distance:
        return None
    again = _aligned(model.space, user.curve(RANK_SAMPLES)[1][None], everything)
    named = _Placed(model, params_of(z[:n_par]), (0.0, 0.0, 0.0) if not sphere else np.eye(3)).named
    return Match(
        atlas_id=m.atlas_id,
        mechanism=user.user,
        named=named,
        error=float(again.error[0]),
        distance=distance,
        scale=m.scale,
        rotation=m.rotation,
        translation=m.translation,
        descriptor_distance=m.descriptor_distance,
        refined=True,
        params=params_of(z[:n_par]),
    )

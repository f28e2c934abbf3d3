"""Search models for every family, from its parameter vector: what path synthesis and the atlas
know of a family that has no hand-written model.

:mod:`linkwright.synthesis.path_families` holds hand-written models of the four-bar, the
slider-crank, the geared five-bar and the spherical four-bar (closed-form Grashof constraints,
exact limit positions along a path). Every other registered family (the double slider, the
six-bars, a composed linkage, the spherical six-bars) gets a :class:`GenericModel` built from
its :class:`~linkwright.mechanisms.parameters.ParameterVector` and a template mechanism (for a
composed linkage, the linkage whose structure is kept; for a named family any member: its
numbers are all replaced). The model has the same interface, so the search of
:mod:`linkwright.synthesis.path` and the atlas run it unchanged:

- **Local frame** (plane): the vector's gauge fixed: its first ground pivot at the origin and its
  reference direction along +x (the second pivot at (d, 0), d > 0, or the guide's angle 0); the
  pose (x, y, frame_angle) carries it to the user's frame. The linkage is not scaled: its
  lengths are in the targets' units. On the sphere a composed linkage has its first ground axis
  at +x and its second in the xy-plane; a named spherical family stands in its paper's frame;
  the pose is a rotation.
- **Shape**: every other number of the vector; a gear ratio is fixed at the template's value.
- **Configuration**: one code per combination of the plan's branches (each dyad's assembly sign,
  a triad's pose); a composed linkage keeps its template's signs. A dyad's sign holds along a
  branch of motion, so such a configuration is solved as it is. A triad's pose index is only a
  name at one input (the poses are ordered by an angle at each input, and reorder where two
  cross or one wraps), so a configuration with a triad is *followed*: every pose is solved at
  the inputs and on a grid over the input's period, and the branch is continued from the coded
  pose at the frame's input 0 to its nearest configuration sample by sample
  (:func:`follow`); where the nearest is not clearly nearest (a limit position, two poses
  passing close) the branch ends there.
- **Constraints**: no closed forms; a full turn (and the closed-curve fit's) is sampled from
  every dyad's closure margin (a triad's: its closure) on a grid of the period, and a least
  transmission angle from every dyad's transmission angle there.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.analysis.general import dyad_transmission_angles
from linkwright.engine import (
    DyadRRP,
    DyadRRR,
    Fixed,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    input_turns,
)
from linkwright.engine.continuation import every_configuration
from linkwright.geometry import sphere
from linkwright.mechanisms import (
    FAMILIES,
    DyadJoint,
    FixedJoint,
    Linkage,
    Mechanism,
    SphereCrankJoint,
    SphereRigidJoint,
    solve,
)
from linkwright.mechanisms.parameters import ParameterError, family_template, parameter_vector
from linkwright.synthesis.path_families import MODELS, Model

__all__ = [
    "FOLLOW_GRID",
    "Followed",
    "GenericModel",
    "ModelError",
    "follow",
    "model_for",
    "rotation_pose",
]

Array = NDArray[np.float64]
TWO_PI = 2.0 * np.pi

FOLLOW_GRID = 40
"""Samples a period of the input on which a triad's branch is followed between inputs."""
CLEAR = 0.5
"""A followed branch continues to its nearest configuration only while that is nearer than
this fraction of the distance to the next nearest."""
JUMP = 0.9
"""A followed branch's next sample may lie off the line through its last two by at most this
fraction of the step (a smooth branch: by about the step's square; a jump to another branch,
where the branch ended at a limit position between two samples: by about the whole step)."""
CHUNK_SAMPLES = 400_000
"""Mechanism-samples evaluated at once (bounds the memory of a large population)."""


class ModelError(ValueError):
    """A family that has no search model as asked (one line: which, and what to give)."""


@dataclass(frozen=True)
class Followed:
    """Positions on one configuration at each input, as a :class:`~linkwright.engine.Motion`
    has them (``positions``, ``valid``, ``margins``), and the branch values used."""

    positions: dict[str, Array]
    valid: NDArray[np.bool_]
    margins: dict[str, Array]
    branches: dict[str, Array]


def model_for(family: str, template: Mechanism | None = None) -> Model | GenericModel:
    """The search model of ``family``: the hand-written one where there is one, else a
    :class:`GenericModel` of ``template`` (default: a member of the family with its default
    choices; a composed linkage needs its template).

    Raises
    ------
    ModelError
        For an unknown family, a template of another family, or a composed linkage without one.
    """
    if family not in FAMILIES:
        raise ModelError(f"family: unknown {family!r}; known: {', '.join(FAMILIES)}")
    if template is not None and template.family != family:
        raise ModelError(
            f"template: a {template.family} document, but the family asked is {family}"
        )
    if family in MODELS:
        return MODELS[family]
    if template is None:
        try:
            template = family_template(family)
        except ParameterError as exc:
            raise ModelError(str(exc)) from None
    if template.batch_shape:
        raise ModelError("template: one mechanism, not a batch")
    return GenericModel(template)


def _step_branch(step: Any) -> str | None:
    """The parameter that holds a step's branch: a dyad's sign, a triad's pose."""
    if isinstance(step, DyadRRR | DyadRRP | SphereDyad):
        return step.branch if isinstance(step.branch, str) else None
    if hasattr(step, "max_poses"):
        return step.pose  # type: ignore[no-any-return]
    return None


class GenericModel:
    """The search model of one family, from its parameter vector (module docstring)."""

    exact_margin = False

    def __init__(self, template: Mechanism) -> None:
        v = parameter_vector(template)
        self.template = template
        self.vector = v
        self.family = template.family
        self.space = v.space
        self.plan = template.plan
        self.traced = template.traced_joint
        self.classes: tuple[str, ...] = ()
        self.triads = self.plan.triads
        fixed: dict[str, float] = {}
        gauge_lengths: list[str] = []
        by_field: dict[str, list[str]] = {}
        for p in v.parameters:
            by_field.setdefault(p.field, []).append(p.name)
        if v.space == "plane":
            if v.base:
                fixed.update(dict.fromkeys(by_field[v.base], 0.0))
            if v.reference and v.reference[0] == "direction":
                fixed[by_field[v.reference[1]][0]] = 0.0
            elif v.reference:
                x_name, y_name = by_field[v.reference[2]]
                fixed[y_name] = 0.0
                gauge_lengths.append(x_name)
        elif v.axes:
            first, second = by_field[v.axes[0]], by_field[v.axes[1]]
            fixed.update({first[0]: 0.0, first[1]: 0.0, second[1]: 0.0})
            gauge_lengths.append(second[0])  # the second axis's longitude: its arc from +x
        self.fixed = fixed
        self.shape_names = tuple(n for n in v.names if n not in fixed)
        kinds = {p.name: p for p in v.parameters}
        plane = v.space == "plane"
        self.lengths = tuple(
            n
            for n in self.shape_names
            if n in gauge_lengths
            or kinds[n].kind == "length"
            or (kinds[n].kind == "arc" and not kinds[n].closed)
        )
        self.closed_arcs = tuple(
            n for n in self.shape_names if kinds[n].kind == "arc" and kinds[n].closed
        )
        self.ratios = tuple(n for n in self.shape_names if kinds[n].kind == "ratio")
        self.linear = (
            tuple(n for n in self.shape_names if kinds[n].kind in ("length", "coordinate"))
            if plane
            else ()
        )
        self.periodic = frozenset(
            n for n in self.shape_names if kinds[n].periodic and n not in gauge_lengths
        )
        self.angles = tuple(
            n
            for n in self.shape_names
            if kinds[n].kind in ("angle", "arc") and n not in self.linear
        )
        self._kinds = kinds
        # The configurations: every combination of the plan's branches (a composed linkage keeps
        # its template's, part of the structure it was given).
        steps = [(s, b) for s in self.plan.steps if (b := _step_branch(s)) is not None]
        own = template.params()
        if self.family == "linkage" or not steps:
            choices = [[float(np.asarray(own[b]))] for _, b in steps]
        else:
            choices = [
                [float(k) for k in range(s.max_poses)] if hasattr(s, "max_poses") else [1.0, -1.0]
                for s, _ in steps
            ]
        self.branch_fields = tuple(b for _, b in steps)
        self.branch_steps = tuple(s.name for s, _ in steps)
        self.combos = [
            dict(zip(self.branch_fields, c, strict=True)) for c in itertools.product(*choices)
        ]
        self._codes = {b: np.array([combo[b] for combo in self.combos]) for b in self.branch_fields}
        try:
            self.turns = int(np.max(input_turns(self.plan, own, points=template.points)))
        except ValueError:
            self.turns = 1

    # -- the interface path synthesis uses --------------------------------------------------

    @property
    def dim(self) -> int:
        return 2 if self.space == "plane" else 3

    @property
    def pose_names(self) -> tuple[str, ...]:
        return ("x", "y", "frame_angle") if self.space == "plane" else ("lon", "sinlat", "spin")

    @property
    def configurations(self) -> int:
        return len(self.combos)

    @property
    def search_scale(self) -> float:
        """Share of the usual population and starts a search gives this family: a triad
        solves every pose at every sample, several times a dyad's cost."""
        return 0.2 if self.triads else 1.0

    def own_code(self) -> int:
        """The configuration code of the template's own branch choices (0 if none fits)."""
        own = self.template.params()
        for k, combo in enumerate(self.combos):
            if all(float(np.asarray(own[b])) == v for b, v in combo.items()):
                return k
        return 0

    def seeds(
        self,
        targets: Array,
        count: int = 8,
        anchor: float = 0.0,
        angles: Array | None = None,
    ) -> list[tuple[Array, dict[str, float], float]]:
        """Starts from the template: its own linkage on each of its configurations, laid over
        the targets; the ``count`` that lie closest. With the inputs ``angles`` given, its
        points there are matched to the targets one to one (the least-squares similarity, or
        rotation on the sphere); else its curve is, by iterated closest points from several
        turns (scaled to the targets in the plane; on the sphere its mean direction turned
        onto theirs, then spun). (pose, shape, code) each; none where the template does not
        assemble."""
        v = self.vector
        if self.space == "plane":
            base, angle, _ = v.frame(self.template)
            c, n = float(np.cos(-angle)), float(np.sin(-angle))
            bx, by = (float(q) for q in base)
            shift = (-(c * bx - n * by), -(n * bx + c * by))
            local = v.transformed(self.template, 1.0, -angle, shift)
        elif v.axes:
            local = v.normalise(self.template)
        else:
            local = self.template
        x = v.to_vector(local)
        shape = {name: float(x[i]) for i, name in enumerate(v.names) if name in self.shape_names}
        codes = np.arange(len(self.combos), dtype=float)[:16]
        grid = anchor + np.linspace(0.0, TWO_PI * self.turns, 64, endpoint=False)
        batch = {k: np.full(len(codes), q) for k, q in shape.items()}
        curves, valid, _ = self.evaluate(batch, codes, grid, anchor)
        found: list[tuple[float, tuple[Array, dict[str, float], float]]] = []
        if angles is not None:
            at = np.broadcast_to(np.asarray(angles, dtype=float), (len(codes), len(targets)))
            reached, there, _ = self.evaluate(batch, codes, at, anchor)
            for code, pts, ok in zip(codes, reached, there, strict=True):
                if not ok.all():
                    continue
                if self.space == "plane":
                    w, t, miss = _paired_fit(pts, targets)
                    scaled = {q: v * abs(w) if q in self.linear else v for q, v in shape.items()}
                    seed = (np.array([t.real, t.imag, np.angle(w)]), scaled, float(code))
                else:
                    R, miss = _paired_turn(pts, targets)
                    seed = (rotation_pose(R), shape, float(code))
                found.append((miss, seed))
            found.sort(key=lambda item: item[0])
            return [seed for _, seed in found[:count]]
        for code, curve, ok in zip(codes, curves, valid, strict=True):
            pts = curve[ok]
            if len(pts) < 3:
                continue
            for k in range(count):
                spin = TWO_PI * k / count - np.pi
                if self.space == "plane":
                    size = _diameter(pts)
                    w0 = (_diameter(targets) / size if size > 0 else 1.0) * np.exp(1j * spin)
                    w, t, miss = _nearest_fit(pts, targets, w0)
                    scaled = {
                        q: val * abs(w) if q in self.linear else val for q, val in shape.items()
                    }
                    seed = (np.array([t.real, t.imag, np.angle(w)]), scaled, float(code))
                else:
                    mc, mt = sphere.unit(pts.mean(axis=0)), sphere.unit(targets.mean(axis=0))
                    R, miss = _nearest_turn(pts, targets, _about(mt, spin) @ _turning(mc, mt))
                    seed = (rotation_pose(R), shape, float(code))
                found.append((miss, seed))
        found.sort(key=lambda item: item[0])
        return [seed for _, seed in found[:count]]

    def code(self, gene: Array) -> Array:
        """A configuration code for each gene in [−1, 1]."""
        k = len(self.combos)
        return np.clip(np.floor((np.asarray(gene) + 1.0) * 0.5 * k), 0, k - 1).astype(float)

    def default_bounds(self, size: float, centre: Array) -> dict[str, tuple[float, float]]:
        """Bounds of every parameter for targets of diameter ``size`` around ``centre``."""
        if self.space == "plane":
            out = {
                "x": (centre[0] - 3 * size, centre[0] + 3 * size),
                "y": (centre[1] - 3 * size, centre[1] + 3 * size),
                "frame_angle": (-np.pi, np.pi),
            }
        else:
            out = {"lon": (-np.pi, np.pi), "sinlat": (-1.0, 1.0), "spin": (-np.pi, np.pi)}
        lo, hi = self.vector.bounds(
            size if self.space == "plane" else 1.0, (0.0, 0.0), self.template
        )
        for i, name in enumerate(self.vector.names):
            if name in self.shape_names:
                out[name] = (float(lo[i]), float(hi[i]))
        for name in self.lengths:
            if self._kinds[name].kind == "coordinate":  # the second pivot's distance
                out[name] = (0.02 * size, 5.0 * size)
            elif self._kinds[name].kind == "angle":  # the second axis's arc from the first
                out[name] = (np.radians(2.0), np.radians(178.0))
        return out

    def local(self, shape: Mapping[str, ArrayLike], code: ArrayLike) -> Mechanism:
        """The (batched) mechanism standing in the local frame."""
        code = np.asarray(code)
        arrays = {k: np.asarray(v, dtype=float) for k, v in shape.items()}
        batch = np.broadcast_shapes(code.shape, *(a.shape for a in arrays.values()))
        x = np.empty(batch + (len(self.vector),))
        for i, name in enumerate(self.vector.names):
            x[..., i] = arrays[name] if name in arrays else self.fixed[name]
        idx = np.broadcast_to(code, batch).astype(int)
        discrete = {} if self.family == "linkage" else {b: c[idx] for b, c in self._codes.items()}
        return self.vector.from_vector(self.template, x, discrete)

    def placed(
        self, shape: Mapping[str, float], code: float, pose: Any
    ) -> tuple[Mechanism, Mechanism, Array | None]:
        """(mechanism in the user's frame, the family's own mechanism, rotation or None).

        Planar: both are one mechanism, moved and turned by ``pose`` = (x, y, frame_angle).
        Sphere: the family's mechanism in its own frame, and the user's: a composed linkage
        turned by the rotation ``pose``; a named family rewritten as a composed linkage whose
        ground axes are turned (a family with a triad cannot be: it is returned in its own
        frame, and ``rotation`` carries its curve onto the targets).
        """
        s = {k: float(v) for k, v in shape.items()}
        local = self.local(s, float(code))
        if self.space == "plane":
            x, y, psi = (float(p) for p in pose)
            user = self.vector.transformed(local, 1.0, psi, (x, y))
            return user, user, None
        R = np.asarray(pose, dtype=float)
        if self.vector.axes:
            return self.vector.rotated(local, R), local, R
        if self.triads:
            return local, local, R
        return _sphere_linkage(local, R), local, R

    def input_offset(self, pose: Any) -> float:
        """How far the user frame's input is from the local frame's."""
        if self.space == "sphere":
            return 0.0
        return float(self.vector.input_turn * float(pose[2]))

    def closed_form_gaps(self, *_: Any) -> list[Array]:
        return []

    def sampled(self, full_turn: bool, mu: float) -> bool:
        return full_turn or mu > 0

    def evaluate(
        self,
        shape: Mapping[str, Array],
        code: Array,
        inputs: Array,
        anchor: float = 0.0,
        around: bool = True,
    ) -> tuple[Array, NDArray[np.bool_], Any]:
        """Traced points in the local frame at ``inputs`` (K,) or (B, K), validity, and the
        motion (positions, margins) the sampled constraints read. A configuration with a triad
        is the one through the coded pose at the local input ``anchor``; ``around``: as
        :func:`follow`."""
        mech = self.local(shape, code)
        rows = int(np.prod(mech.batch_shape)) if mech.batch_shape else 1
        per = max(1, CHUNK_SAMPLES // max(1, np.shape(inputs)[-1] * (8 if self.triads else 1)))
        if rows > per and mech.batch_shape:
            codes = np.broadcast_to(np.asarray(code), (rows,))
            parts = [
                self._evaluate_one(
                    mech[i : i + per], _rows(inputs, i, per), codes[i : i + per], anchor, around
                )
                for i in range(0, rows, per)
            ]
            motion = Followed(
                {k: np.concatenate([p.positions[k] for p in parts]) for k in parts[0].positions},
                np.concatenate([p.valid for p in parts]),
                {k: np.concatenate([p.margins[k] for p in parts]) for k in parts[0].margins},
                {k: np.concatenate([p.branches[k] for p in parts]) for k in parts[0].branches},
            )
        else:
            motion = self._evaluate_one(mech, inputs, code, anchor, around)
        return motion.positions[self.traced], motion.valid, motion

    def _evaluate_one(
        self, mech: Mechanism, inputs: Array, code: Array, anchor: float, around: bool
    ) -> Followed:
        if not self.triads:
            m = solve(mech, inputs, order=0)
            return Followed(m.positions, m.valid, m.margins, m.branches)
        n = mech.batch_shape[0] if mech.batch_shape else 1
        codes = np.broadcast_to(np.asarray(code, dtype=int), (n,))
        start = {
            step: self._codes[b][codes]
            for step, b in zip(self.branch_steps, self.branch_fields, strict=True)
        }
        theta = np.broadcast_to(np.asarray(inputs, dtype=float), (n, np.shape(inputs)[-1]))
        return follow(mech, start, theta, np.full(n, anchor), TWO_PI * self.turns, around=around)

    def sampled_gaps(
        self, motion: Any, sl: slice, full_turn: bool, mu: float, shape: Any, code: Any
    ):
        """Constraints read off a sampled period (each ≤ 0 when met): every dyad's (and
        triad's) least closure margin for a full turn, every dyad's transmission angle."""
        gaps: list[Array] = []
        if full_turn or mu > 0:
            least = None
            for name in self.branch_steps:
                m = motion.margins[name][:, sl]
                m = np.where(np.isfinite(m), np.abs(m) if name in _triad_names(self) else m, -1.0)
                least = m.min(axis=1) if least is None else np.minimum(least, m.min(axis=1))
            if least is None:  # nothing can stop it (a double slider): only validity counts
                least = np.where(motion.valid[:, sl].all(axis=1), 1.0, -1.0)
            gaps.append(-least)
        if mu > 0:
            mech = self.local(shape, code)
            view = Followed(
                {k: v[:, sl] for k, v in motion.positions.items()}, motion.valid[:, sl], {}, {}
            )
            angles = dyad_transmission_angles(mech, view)  # type: ignore[arg-type]
            worst = np.full(len(code), -1.0)
            for gam in angles.values():
                c = np.abs(np.cos(gam))
                worst = np.maximum(worst, np.max(np.where(np.isfinite(c), c, 1.0), axis=1))
            gaps.append(worst - np.cos(mu))
        return gaps

    # -- verification: the user-frame mechanism itself ---------------------------------------

    def reach(
        self,
        mech: Mechanism,
        local: Mechanism,
        code: float,
        inputs: Array,
        offset: float,
        transform: Any,
        anchor: float = 0.0,
    ) -> tuple[Array, NDArray[np.bool_], dict[str, Array]]:
        """The traced point of the user-frame ``mech`` at ``inputs`` (user frame), solved by the
        engine on the candidate's configuration, its validity, and the branch values used.

        With a triad, the configuration is followed from the one at the input ``offset`` +
        ``anchor`` that lies where the local frame's coded configuration does at ``anchor``
        (``transform`` carries local positions to ``mech``'s frame); a named spherical family
        with a triad stays in its own frame, and its points are turned by ``transform`` (a
        rotation) afterwards.
        """
        inputs = np.asarray(inputs, dtype=float)
        if not self.triads:
            m = solve(mech, inputs, order=0)
            return m.positions[self.traced], m.valid, m.branches
        start_local = self._start_configuration(local, anchor)
        if start_local is None:
            return np.full(inputs.shape + (self.dim,), np.nan), np.zeros(inputs.shape, bool), {}
        # On the sphere a family with a triad stands in its own frame (placed() returns it so).
        turned_frame = self.space == "sphere"
        want = start_local if turned_frame else {k: transform(v) for k, v in start_local.items()}
        combos, motion = every_configuration(
            mech.plan, mech.params(), [offset + anchor], points=mech.points, order=0
        )
        best, dist = -1, np.inf
        for k in range(len(combos)):
            if not motion.valid[k, 0]:
                continue
            d = sum(float(np.sum((motion.positions[j][k, 0] - w) ** 2)) for j, w in want.items())
            if d < dist:
                best, dist = k, d
        if best < 0:
            return np.full(inputs.shape + (self.dim,), np.nan), np.zeros(inputs.shape, bool), {}
        start = {name: np.array([v]) for name, v in combos[best].items()}
        got = follow(mech, start, inputs[None], np.array([offset + anchor]), TWO_PI * self.turns)
        points = got.positions[self.traced][0]
        if turned_frame and transform is not None:
            points = transform(points)
        return points, got.valid[0], {k: v[0] for k, v in got.branches.items()}

    def _start_configuration(self, local: Mechanism, anchor: float) -> dict[str, Array] | None:
        """The joints of the local mechanism's coded configuration at the input ``anchor`` (its
        own branch fields are the code's: :meth:`local`)."""
        m = solve(local, [anchor], order=0)
        if not m.valid[0]:
            return None
        return {k: v[0] for k, v in m.positions.items()}

    def with_branches(self, mech: Mechanism, branches: Mapping[str, float]) -> Mechanism:
        """The mechanism whose document names the configuration met at a target: a triad's
        pose there (the document's pose is a name at one input)."""
        changes = {}
        for step, b in zip(self.branch_steps, self.branch_fields, strict=True):
            if step in branches and self.family != "linkage":
                changes[b] = float(branches[step])
        return replace(mech, **changes) if changes else mech


def _diameter(pts: Array) -> float:
    diff = pts[:, None, :] - pts[None, :, :]
    return float(np.sqrt(np.max(np.sum(diff * diff, axis=-1))))


def _paired_fit(points: Array, targets: Array) -> tuple[complex, complex, float]:
    """The least-squares similarity z ↦ w·z + t (complex) of ``points`` onto ``targets``, pair
    by pair, and its residual (in the points' units)."""
    a = points[:, 0] + 1j * points[:, 1]
    b = targets[:, 0] + 1j * targets[:, 1]
    da, db = a - a.mean(), b - b.mean()
    energy = float(np.sum(np.abs(da) ** 2))
    w = complex(np.sum(np.conj(da) * db) / energy) if energy > 0 else 1.0 + 0j
    t = b.mean() - w * a.mean()
    return w, t, float(np.sum(np.abs(w * a + t - b) ** 2) / max(abs(w), 1e-300) ** 2)


def _paired_turn(points: Array, targets: Array) -> tuple[Array, float]:
    """The rotation (Kabsch) of ``points`` onto ``targets``, pair by pair, and its residual."""
    u, _, vt = np.linalg.svd(targets.T @ points)
    R = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    return R, float(np.sum((points @ R.T - targets) ** 2))


def _nearest_fit(
    curve: Array, targets: Array, w: complex, rounds: int = 12
) -> tuple[complex, complex, float]:
    """Iterated closest points: the similarity z ↦ w·z + t (complex) that lays the sampled
    curve over the targets, each target matched to its nearest curve point, from ``w``."""
    a = curve[:, 0] + 1j * curve[:, 1]
    b = targets[:, 0] + 1j * targets[:, 1]
    t = b.mean() - w * a.mean()
    for _ in range(rounds):
        near = a[np.argmin(np.abs((w * a + t)[None, :] - b[:, None]), axis=1)]
        da, db = near - near.mean(), b - b.mean()
        energy = float(np.sum(np.abs(da) ** 2))
        if energy <= 0:
            break
        w = complex(np.sum(np.conj(da) * db) / energy)
        t = b.mean() - w * near.mean()
    miss = np.min(np.abs((w * a + t)[None, :] - b[:, None]), axis=1)
    return w, t, float(np.sum(miss**2) / max(abs(w), 1e-300) ** 2)


def _nearest_turn(curve: Array, targets: Array, R: Array, rounds: int = 12) -> tuple[Array, float]:
    """The same on the sphere: the rotation (Kabsch) laying the curve over the targets."""
    for _ in range(rounds):
        moved = curve @ R.T
        near = curve[np.argmin(np.sum((moved[None] - targets[:, None]) ** 2, axis=-1), axis=1)]
        u, _, vt = np.linalg.svd(targets.T @ near)
        d = np.sign(np.linalg.det(u @ vt))
        R = u @ np.diag([1.0, 1.0, d]) @ vt
    moved = curve @ R.T
    return R, float(np.sum(np.min(np.sum((moved[None] - targets[:, None]) ** 2, axis=-1), axis=1)))


def _about(axis: Array, angle: float) -> Array:
    """The rotation by ``angle`` about the unit vector ``axis``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def _turning(a: Array, b: Array) -> Array:
    """The least rotation carrying the unit vector a onto b."""
    axis = np.cross(a, b)
    s = float(np.linalg.norm(axis))
    if s < 1e-12:
        if float(np.dot(a, b)) > 0:
            return np.eye(3)
        other = np.eye(3)[int(np.argmin(np.abs(a)))]
        return _about(sphere.unit(np.cross(a, other)), np.pi)
    return _about(axis / s, float(np.arctan2(s, np.dot(a, b))))


def rotation_pose(R: Array) -> Array:
    """(lon, sinlat, spin) of a rotation, as :func:`~linkwright.synthesis.path_families.
    sphere_rotation` builds it from them."""
    a0, t = R[:, 0], R[:, 1]
    lon = float(np.arctan2(a0[1], a0[0]))
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(a0, east)
    return np.array([lon, float(np.clip(a0[2], -1.0, 1.0)), float(np.arctan2(t @ north, t @ east))])


def _triad_names(model: GenericModel) -> frozenset[str]:
    return frozenset(t.name for t in model.triads)


def _rows(inputs: Array, start: int, count: int) -> Array:
    inputs = np.asarray(inputs)
    return inputs[start : start + count] if inputs.ndim == 2 else inputs


# --------------------------------------------------------------------------------------------
# Following a configuration with a triad
# --------------------------------------------------------------------------------------------


def follow(
    mech: Mechanism,
    start: Mapping[str, Array],
    inputs: Array,
    anchor: Array,
    period: float = TWO_PI,
    grid: int = FOLLOW_GRID,
    around: bool = True,
) -> Followed:
    """One configuration of each linkage of a batch, followed by continuity.

    ``start`` gives, per branching step (by step name), its branch value at the input
    ``anchor`` (B,); the configuration is the branch of motion through it, continued from the
    anchor up and down the input (not taken modulo a turn: a branch between two limit positions
    may span more than one) to each of ``inputs`` (B, K), through a grid of ``grid`` samples a
    ``period`` covering at least a period either side. An input the branch does not reach
    directly (it turns back at a limit position first) is looked for a period further round,
    the other way (unless ``around`` is False): a branch that rocks about the anchor is so
    seen whole on any one turn of the input. Each step goes to the nearest configuration,
    only while it is clearly nearest (:data:`CLEAR`); past that the configuration is not
    valid.

    Examples
    --------
    A Stephenson III driven at its output (bundled ``stephenson3-output``) has two circuits; the
    one through pose 0 at the input 0 is followed for a whole turn, and closes:

    >>> from linkwright.mechanisms import Stephenson3
    >>> m = Stephenson3(A0=[0, 0], B0=[4, 0], D0=[0, 2.8], crank=1, coupler=4, rocker=3,
    ...                 u1=2, v1=2, link1=0.7, link2=1, input="output")
    >>> theta = np.linspace(0, 2 * np.pi, 9)[None]
    >>> got = follow(m, {"A": np.array([0.0])}, theta, np.zeros(1))
    >>> P = got.positions["P"][0]
    >>> bool(got.valid.all()), bool(np.allclose(P[0], P[-1]))
    (True, True)
    """
    inputs = np.asarray(inputs, dtype=float)
    anchor = np.asarray(anchor, dtype=float)
    rel = inputs - anchor[:, None]
    got, alive = _follow_once(mech, start, rel, anchor, grid * 1.0 / period)
    # Inputs the branch turns back from before reaching: a period round the other way (a
    # second, smaller walk, for the linkages that need it).
    need = np.flatnonzero(alive & ~got.valid.all(axis=1)) if around else np.zeros(0, int)
    if need.size:
        other = np.where(rel > 0, rel - period, rel + period)[need]
        sub = mech[need] if mech.batch_shape else mech
        part = {k: np.asarray(v)[need] if np.ndim(v) else v for k, v in start.items()}
        more, _ = _follow_once(sub, part, other, anchor[need], grid * 1.0 / period)
        take = ~got.valid[need] & more.valid
        rows = need[:, None]

        def merged(a: Array, b: Array) -> Array:
            out = a.copy()
            mask = take if b.ndim == 2 else take[..., None]
            out[need] = np.where(mask, b, a[rows[:, 0]])
            return out

        got = Followed(
            {n: merged(v, more.positions[n]) for n, v in got.positions.items()},
            merged(got.valid, more.valid),
            {n: merged(v, more.margins[n]) for n, v in got.margins.items()},
            {n: merged(v, more.branches[n]) for n, v in got.branches.items()},
        )
    return got


def _follow_once(
    mech: Mechanism, start: Mapping[str, Array], rel: Array, anchor: Array, density: float
) -> tuple[Followed, NDArray[np.bool_]]:
    """:func:`follow` on the inputs ``anchor + rel`` directly (no second way round), with
    ``density`` grid samples a radian; also whether the start exists at the anchor."""
    b = rel.shape[0]
    step = 1.0 / density
    low = min(0.0, float(np.min(rel))) if rel.size else 0.0
    high = max(0.0, float(np.max(rel))) if rel.size else 0.0
    offsets = step * np.arange(math.floor(low / step), math.ceil(high / step) + 1)
    n_grid = len(offsets)
    # The grid first, so that the anchor (offset 0) sorts before any input equal to it.
    theta = anchor[:, None] + np.concatenate([np.broadcast_to(offsets, (b, n_grid)), rel], axis=1)
    order = np.argsort(theta, axis=1, kind="stable")
    ordered = np.take_along_axis(theta, order, axis=1)
    where = np.argsort(order, axis=1)  # each sample's place in the sorted sequence
    home = where[:, int(np.flatnonzero(offsets == 0.0)[0])]
    combos, motion = every_configuration(
        mech.plan, mech.params(), ordered, points=mech.points, order=0
    )
    c = len(combos)
    rows = np.arange(b)
    names = list(motion.positions)
    x = np.concatenate([motion.positions[n] for n in names], axis=-1)  # (C, B, S, D)
    ok = motion.valid  # (C, B, S)
    x = np.where(ok[..., None], x, np.nan)
    match = np.ones((c, b), dtype=bool)
    for name, values in start.items():
        vals = np.array([combo[name] for combo in combos])
        match &= vals[:, None] == np.broadcast_to(np.asarray(values, dtype=float), (b,))[None]
    at_home = ok[:, rows, home]
    first = np.argmax(match & at_home, axis=0)
    alive0 = (match & at_home).any(axis=0)
    count = theta.shape[1]
    chosen = np.zeros((b, count), dtype=int)
    good = np.zeros((b, count), dtype=bool)
    chosen[rows, home], good[rows, home] = first, alive0
    # Each configuration's labels (a dyad's sign, a triad's closure sign) stay put along a
    # branch of motion and change only where it ends at a limit position.
    labels = np.stack([np.broadcast_to(v, ok.shape) for v in motion.labels.values()], axis=-1)
    size = float(np.nanmax(np.abs(x))) if np.isfinite(x).any() else 1.0

    def walk(sequence: range, sense: int) -> None:
        cur, alive = first.copy(), alive0.copy()
        prev = x[cur, rows, home]
        label = labels[cur, rows, home]
        at = ordered[rows, home]
        # The step before (its start and input span): the branch continues where a straight
        # line through the last two samples points, to within a fraction of the step.
        before = np.full_like(prev, np.nan)
        width = np.full(b, np.nan)
        for s in sequence:
            moving = (s - home) * sense > 0  # rows already past their anchor this way
            if not moving.any():
                continue
            d = np.sqrt(np.nansum((x[:, :, s] - prev[None]) ** 2, axis=-1))
            same = np.all(labels[:, :, s] == label[None], axis=-1)
            d = np.where(ok[:, :, s] & same, d, np.inf)
            if c > 1:
                part = np.partition(d, 1, axis=0)
                near, second = part[0], part[1]
            else:
                near, second = d[0], np.full(b, np.inf)
            nxt = np.argmin(d, axis=0)
            # Clearly the nearest, and no jump: where the branch ends at a limit position between
            # two samples, the nearest configuration left lies off the line it was running on.
            span = np.abs(ordered[:, s] - at)
            guess = prev + (prev - before) * (span / np.where(width > 0, width, np.nan))[:, None]
            off = np.sqrt(np.nansum((x[nxt, rows, s] - guess) ** 2, axis=-1))
            steady = ~np.isfinite(width) | (off <= JUMP * near) | (near <= 1e-9 * size)
            keep = np.isfinite(near) & (near < CLEAR * second) & steady
            alive = np.where(moving, alive & keep, alive)
            cur = np.where(moving & alive, nxt, cur)
            chosen[:, s] = np.where(moving, cur, chosen[:, s])
            good[:, s] = np.where(moving, alive, good[:, s])
            grows = moving & alive & (span > 1e-9)
            before = np.where(grows[:, None], prev, before)
            width = np.where(grows, span, width)
            at = np.where(grows, ordered[:, s], at)
            prev = np.where(grows[:, None], x[cur, rows, s], prev)

    walk(range(count), 1)
    walk(range(count - 1, -1, -1), -1)
    place = where[:, n_grid:]
    pick = np.take_along_axis(chosen, place, axis=1)
    valid = np.take_along_axis(good, place, axis=1)
    at = (pick, rows[:, None], place)

    def gather(array: Array) -> Array:
        out = array[at]
        mask = valid if out.ndim == 2 else valid[..., None]
        return np.where(mask, out, np.nan)

    branches = {
        step: np.where(valid, np.array([combo[step] for combo in combos])[pick], np.nan)
        for step in combos[0]
    }
    followed = Followed(
        {n: gather(motion.positions[n]) for n in names},
        valid,
        {n: gather(m) for n, m in motion.margins.items()},
        branches,
    )
    return followed, alive0


# --------------------------------------------------------------------------------------------
# A named spherical family as a composed linkage (so that it can be turned anywhere)
# --------------------------------------------------------------------------------------------


def _sphere_linkage(mech: Mechanism, R: Array) -> Linkage:
    """The named spherical mechanism written joint by joint, every ground axis turned by R."""
    params = mech.params()

    def number(value: Any) -> float:
        return float(np.asarray(params[value] if isinstance(value, str) else value))

    fixed: dict[str, Array] = {}
    joints: list[Any] = []
    for step in mech.plan.steps:
        if isinstance(step, Fixed):
            axis = sphere.unit(np.asarray(params[step.at], dtype=float))
            fixed[step.name] = axis
            joints.append(FixedJoint(step.name, at=R @ axis))
        elif isinstance(step, SphereCrank):
            toward, turn = _toward(step, params, fixed)
            joints.append(
                SphereCrankJoint(
                    step.name,
                    pivot=step.pivot,
                    arc=number(step.length),
                    ratio=number(step.ratio),
                    phase=number(step.phase) + turn,
                    toward=toward,
                )
            )
        elif isinstance(step, SphereDyad):
            joints.append(
                DyadJoint(
                    step.name,
                    p1=step.p1,
                    r1=number(step.r1),
                    p2=step.p2,
                    r2=number(step.r2),
                    assembly=number(step.branch),
                )
            )
        elif isinstance(step, SphereRigid):
            joints.append(
                SphereRigidJoint(
                    step.name,
                    origin=step.origin,
                    toward=step.toward,
                    arc=number(step.length),
                    angle=number(step.angle),
                )
            )
        else:  # pragma: no cover - a triad is returned in its own frame (GenericModel.placed)
            raise ModelError(f"{mech.family}: step {step.name!r} has no joint of a linkage")
    return Linkage(joints=tuple(joints), traced=mech.plan.traced, space="sphere")


def _toward(step: SphereCrank, params: Mapping[str, Any], fixed: Mapping[str, Array]):
    """The ground joint whose great circle from the crank's pivot is the crank's zero
    direction (a plan may name any vector; a linkage names a joint), and π where it runs the
    other way along it."""
    pivot = fixed[step.pivot]
    ref = sphere.tangent(pivot, np.asarray(params[step.ref], dtype=float))
    for name, axis in fixed.items():
        if name == step.pivot:
            continue
        t = sphere.tangent(pivot, axis)
        if np.linalg.norm(np.cross(t, ref)) <= 1e-9:
            return name, 0.0 if float(np.dot(t, ref)) > 0 else np.pi
    raise ModelError(
        f"crank {step.name!r}: no ground joint lies on the great circle its angle starts along"
    )

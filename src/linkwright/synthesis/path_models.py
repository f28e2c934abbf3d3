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
from collections.abc import Mapping
from dataclasses import replace
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
from linkwright.synthesis.path_alignment import (
    axis_rotation,
    diameter,
    nearest_fit,
    nearest_turn,
    paired_fit,
    paired_turn,
    rotation_pose,
    turning_rotation,
)
from linkwright.synthesis.path_families import MODELS, Model
from linkwright.synthesis.path_follow import CLEAR as CLEAR
from linkwright.synthesis.path_follow import FOLLOW_GRID, Followed, follow
from linkwright.synthesis.path_follow import JUMP as JUMP

# A name imported `as` itself moved to a sibling module and is re-exported for older imports;
# a constant among them is read where it lives (set it there, not here).
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


CHUNK_SAMPLES = 400_000
"""Mechanism-samples evaluated at once (bounds the memory of a large population)."""


class ModelError(ValueError):
    """A family that has no search model as asked (one line: which, and what to give)."""


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
                    w, t, miss = paired_fit(pts, targets)
                    scaled = {q: v * abs(w) if q in self.linear else v for q, v in shape.items()}
                    seed = (np.array([t.real, t.imag, np.angle(w)]), scaled, float(code))
                else:
                    R, miss = paired_turn(pts, targets)
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
                    size = diameter(pts)
                    w0 = (diameter(targets) / size if size > 0 else 1.0) * np.exp(1j * spin)
                    w, t, miss = nearest_fit(pts, targets, w0)
                    scaled = {
                        q: val * abs(w) if q in self.linear else val for q, val in shape.items()
                    }
                    seed = (np.array([t.real, t.imag, np.angle(w)]), scaled, float(code))
                else:
                    mc, mt = sphere.unit(pts.mean(axis=0)), sphere.unit(targets.mean(axis=0))
                    R, miss = nearest_turn(
                        pts, targets, axis_rotation(mt, spin) @ turning_rotation(mc, mt)
                    )
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
    ) -> list[Array]:
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


def _triad_names(model: GenericModel) -> frozenset[str]:
    return frozenset(t.name for t in model.triads)


def _rows(inputs: Array, start: int, count: int) -> Array:
    inputs = np.asarray(inputs)
    return inputs[start : start + count] if inputs.ndim == 2 else inputs


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


def _toward(
    step: SphereCrank, params: Mapping[str, Any], fixed: Mapping[str, Array]
) -> tuple[str, float]:
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

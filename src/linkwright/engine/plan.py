"""Construction plans: a linkage as an ordered list of steps, each placing one joint.

A plan says *how* joints are built from joints already known; the numbers (lengths, pivots,
assembly signs) live in a separate mapping of named parameters, so one plan evaluates a whole
batch of mechanisms at once (Pinocchio's model/data split, applied to linkages).

Each step maps its parents' position, velocity and acceleration (derivatives with respect to the
input angle θ) to its own joint's, from the differentiated constraint equations: a 2×2 solve for
a dyad, closed forms for cranks and rigid points. Nothing here differences numerically.

Branch convention (one definition for every dyad, see DESIGN.md): a joint P placed from parents
P1 then P2 has branch ``sign((P2 − P1) × (P − P1))``; a slider pin B placed on a line from P1 has
branch ``sign((B − H)·d)``, H the foot of P1 on the line and d the line's direction. On the
sphere (joints are unit vectors, the axes of the revolute joints) a dyad joint X has branch
``sign((P1 × P2)·X)``.

The step kinds live in :mod:`linkwright.engine.plane_steps` and
:mod:`linkwright.engine.sphere_steps` (triads in :mod:`linkwright.engine.triad_steps`), what
they share in :mod:`linkwright.engine.state`; this module orders them into a :class:`Plan` and
re-exports them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.plane_steps import Crank, DyadRRP, DyadRRR, Fixed, Rigid, Trammel
from linkwright.engine.sphere_steps import SphereCrank, SphereDyad, SphereRigid
from linkwright.engine.state import (
    ASSEMBLY_TOL,
    SINGULAR_MARGIN,
    SINGULAR_SIN,
    Context,
    JointState,
    Param,
    Step,
)

if TYPE_CHECKING:
    from linkwright.engine.evaluate import Motion

__all__ = [
    "ASSEMBLY_TOL",
    "SINGULAR_MARGIN",
    "SINGULAR_SIN",
    "Context",
    "Crank",
    "DyadRRP",
    "DyadRRR",
    "Fixed",
    "JointState",
    "Param",
    "Plan",
    "Rigid",
    "SphereCrank",
    "SphereDyad",
    "SphereRigid",
    "Step",
    "Trammel",
]

Array = NDArray[np.float64]

DYAD_TYPES = (DyadRRR, DyadRRP, SphereDyad)
PLANE_STEPS = (Crank, DyadRRR, DyadRRP, Rigid, Trammel)
SPHERE_STEPS = (SphereCrank, SphereDyad, SphereRigid)


@dataclass(frozen=True)
class Plan:
    """An ordered, validated list of steps for one single-input linkage.

    ``traced`` names the joints whose paths are the linkage's curves (the first is the default).
    """

    steps: tuple[Step, ...]
    traced: tuple[str, ...] = ("P",)

    def __post_init__(self) -> None:
        known: set[str] = set()
        for step in self.steps:
            for parent in step.parents:
                if parent not in known:
                    raise ValueError(
                        f"joint {step.name!r} is built from {parent!r}, "
                        "which is not placed before it"
                    )
            for joint in placed_joints(step):
                if joint in known:
                    raise ValueError(f"joint {joint!r} is placed twice")
                known.add(joint)
        for name in self.traced:
            if name not in known:
                raise ValueError(f"traced joint {name!r} is not placed by the plan")
        if any(_space_of(s) == "plane" for s in self.steps) and any(
            _space_of(s) == "sphere" for s in self.steps
        ):
            raise ValueError("a plan places its joints either in the plane or on the sphere")
        for step in self.steps:
            if isinstance(step, SphereCrank) and not isinstance(self.step(step.pivot), Fixed):
                raise ValueError(
                    f"spherical crank {step.name!r} turns about {step.pivot!r}, "
                    "which is not a ground pivot"
                )

    @property
    def space(self) -> str:
        """``"sphere"`` for a plan of spherical steps, else ``"plane"``."""
        return "sphere" if any(_space_of(s) == "sphere" for s in self.steps) else "plane"

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(j for s in self.steps for j in placed_joints(s))

    @property
    def dyads(self) -> tuple[DyadRRR | DyadRRP | SphereDyad, ...]:
        return tuple(s for s in self.steps if isinstance(s, DYAD_TYPES))

    @property
    def triads(self) -> tuple[Step, ...]:
        """The steps that place several joints at once, each on one of several poses."""
        return tuple(s for s in self.steps if hasattr(s, "max_poses"))

    @property
    def ground(self) -> tuple[str, ...]:
        """The ground pivots."""
        return tuple(s.name for s in self.steps if isinstance(s, Fixed))

    @property
    def links(self) -> tuple[tuple[str, str], ...]:
        """Every link a drawing shows, as pairs of joints, from the steps that make them."""
        return tuple(pair for s in self.steps for pair in s.links())

    @property
    def plates(self) -> tuple[tuple[str, ...], ...]:
        """Every rigid body of three joints or more, to fill in a drawing."""
        return tuple(plate for s in self.steps for plate in s.plates())

    def step(self, name: str) -> Step:
        """The step that places joint ``name``."""
        for s in self.steps:
            if name in placed_joints(s):
                return s
        raise KeyError(name)

    def unassembled(
        self, params: Mapping[str, ArrayLike], theta: float, *, points: frozenset[str] = frozenset()
    ) -> str | None:
        """Why one linkage cannot be assembled at input ``theta`` (radians): the sentence of the
        first step that fails where its parents are placed (its kind's ``unassembled``), or None
        where it assembles.

        Examples
        --------
        >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", 1.0), Fixed("Q", "Q"),
        ...              DyadRRR("B", "A", "coupler", "Q", "rocker")), traced=("B",))
        >>> params = {"O": np.zeros(2), "Q": np.array([5.0, 0.0]), "coupler": 2.0,
        ...           "rocker": 3.0, "assembly": 1.0}
        >>> plan.unassembled(params, np.pi, points=frozenset("OQ"))
        'the coupler and rocker cannot reach (dyad B: |A Q| = 6 > coupler + rocker = 5)'
        >>> plan.unassembled(params, 0.0, points=frozenset("OQ")) is None
        True
        """
        from linkwright.engine.evaluate import place_all

        _, states = place_all(self, params, np.array([theta]), points=points, order=0)
        placed = {name: bool(np.all(state.valid)) for name, state in states.items()}
        positions = {name: state.pos for name, state in states.items()}
        for s in self.steps:
            if not placed[placed_joints(s)[0]] and all(placed[p] for p in s.parents):
                return s.unassembled(positions, params)
        return None

    def residuals(
        self, motion: Motion, params: Mapping[str, ArrayLike], *, size: ArrayLike | None = None
    ) -> Array:
        """The largest constraint error over every step, at each sample of ``motion``.

        Each step's :meth:`residual` is written from its constraints alone (link lengths, guide
        distances, rigid frames, unit norms), independently of how it placed its joint, so this
        is a check of any solved motion of any family. In the plane the errors are divided by
        ``size`` (default: the linkage's extent in ``motion``, the largest distance of a joint
        from the first placed one); on the sphere they are radians of arc and chords of the unit
        sphere. NaN where the motion is not valid.

        Examples
        --------
        >>> from linkwright.engine.evaluate import evaluate
        >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", 1.0), Fixed("Q", "Q"),
        ...              DyadRRR("B", "A", 3.0, "Q", 2.0)), traced=("B",))
        >>> params = {"O": np.zeros(2), "Q": np.array([3.0, 0.0]), "assembly": 1.0}
        >>> motion = evaluate(plan, params, np.linspace(0, 6, 7), points=frozenset("OQ"))
        >>> bool(np.all(plan.residuals(motion, params) < 1e-15))
        True
        """
        theta = np.asarray(motion.input, dtype=float)
        worst = np.zeros(theta.shape)
        for s in self.steps:
            worst = np.maximum(worst, s.residual(motion.positions, params, theta))
        if self.space == "plane":
            scale: Array
            if size is None:
                origin = motion.positions[self.joints[0]]
                reach = [np.linalg.norm(p - origin, axis=-1) for p in motion.positions.values()]
                with np.errstate(invalid="ignore"):
                    extent = np.where(motion.valid, np.maximum.reduce(reach), 0.0)
                scale = np.max(extent, axis=-1, keepdims=True)
            else:
                scale = np.asarray(size, dtype=float)[..., None]
            with np.errstate(divide="ignore", invalid="ignore"):
                worst = worst / np.where(scale > 0, scale, 1.0)
        return np.where(motion.valid, worst, np.nan)


def placed_joints(step: Step) -> tuple[str, ...]:
    """The joints a step places: its own name, or several for a triad."""
    return tuple(getattr(step, "joints", (step.name,)))


def _space_of(step: Step) -> str | None:
    """ "plane" or "sphere" for a step kind that belongs to one space, None for a ground pivot."""
    if isinstance(step, PLANE_STEPS):
        return "plane"
    if isinstance(step, SPHERE_STEPS):
        return "sphere"
    return getattr(step, "space", None)

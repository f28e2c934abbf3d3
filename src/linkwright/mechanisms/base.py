"""What every named family shares: an immutable value that compiles to a plan and parameters.

The verbs that act on mechanisms (:func:`solve`, :func:`circuit`, :func:`configurations`,
:func:`input_range`) are free functions, so a mechanism stays a plain value: dimensions that may
be arrays with a leading batch shape (one object can stand for a million linkages) and the
assembly choice.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import Any, ClassVar, Self, TypeVar, dataclass_transform, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine import InputArcs, Motion, Plan, evaluate, input_arcs, trace
from linkwright.engine.continuation import arcs_of, every_circuit, every_configuration
from linkwright.engine.evaluate import batch_shape, take

__all__ = [
    "Mechanism",
    "circuit",
    "circuits",
    "configurations",
    "input_range",
    "running_circuit",
    "solve",
]

Array = NDArray[np.float64]


_Family = TypeVar("_Family")


@dataclass_transform(frozen_default=True, eq_default=False)
def family_dataclass(cls: type[_Family]) -> type[_Family]:
    """The decorator every family uses: frozen, with :class:`Mechanism`'s value equality (a plain
    dataclass would compare arrays with ``==``, which has no single truth value)."""
    return dataclass(frozen=True, eq=False)(cls)


class Dimension:
    """The annotation of a family's numeric field: given as anything array-like, read back as
    the read-only float array ``Mechanism.__post_init__`` made of it.

    Only the type checker reads it (as a descriptor, whose ``__set__`` types the constructor's
    argument and ``__get__`` the attribute); at run time the field is a plain dataclass field.
    """

    @overload
    def __get__(self, obj: None, owner: type) -> Self: ...
    @overload
    def __get__(self, obj: object, owner: type) -> Array: ...
    def __get__(self, obj: object, owner: type) -> Any:
        raise NotImplementedError("Dimension is an annotation, never instantiated")

    def __set__(self, obj: object, value: ArrayLike) -> None:
        raise NotImplementedError("Dimension is an annotation, never instantiated")


def dimension(default: ArrayLike) -> Any:
    """A :class:`Dimension` field's default (typed ``Any`` so that a number may stand for it)."""
    return default


class PlanByInput:
    """The family's plan for the link its input drives: read on the class, the crank's (the
    family's structure, for schemas and lists of dyads); on an instance, its own input's."""

    def __init__(self, **plans: Plan) -> None:
        self.plans = plans

    def __get__(self, obj: object, owner: type | None = None) -> Plan:
        if obj is None:
            return next(iter(self.plans.values()))
        return self.plans[getattr(obj, "input", next(iter(self.plans)))]


class InvalidMechanism(ValueError):
    """A mechanism's dimensions are not a linkage (names the field and the problem)."""


@dataclass(frozen=True, eq=False)
class Mechanism:
    """Base of the named families. Subclasses declare their plan and their point fields.

    A mechanism is a value: its arrays are read-only copies, two mechanisms are equal when their
    family and fields are, they hash accordingly, and a batch indexes and slices into
    mechanisms. Families are declared with :data:`family_dataclass` (a frozen dataclass that
    keeps this equality).

    Examples
    --------
    >>> from linkwright import FourBar
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5)
    >>> fb == FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3, rocker=3.5)
    True
    >>> batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1, 2], coupler=3, rocker=3.5)
    >>> len(batch), float(batch[1].crank)
    (2, 2.0)
    >>> fb.crank[...] = 2
    Traceback (most recent call last):
    ...
    ValueError: assignment destination is read-only
    """

    family: ClassVar[str]
    plan: ClassVar[Plan]
    point_fields: ClassVar[frozenset[str]] = frozenset()
    length_fields: ClassVar[tuple[str, ...]] = ()
    arc_fields: ClassVar[tuple[str, ...]] = ()
    """Spherical link lengths (central angles, radians), each strictly between 0 and π."""
    derived_points: ClassVar[frozenset[str]] = frozenset()
    """Point (or unit-vector) parameters that :meth:`params` adds beyond the fields."""
    reported_joints: ClassVar[tuple[str, ...]] = ()
    traced_joint: ClassVar[str] = "P"
    start: float | None = field(default=None, kw_only=True)
    """Where the machine runs (radians), None for the default: a full turn of the input starts
    here; an input that rocks runs the circuit over the arc that holds it (see :func:`circuit`).
    A choice of how the linkage runs, like its assembly, not a dimension: not a plan parameter,
    and one value for a whole batch."""

    def __post_init__(self) -> None:
        self._check_start()
        for f in fields(self):
            if f.type == "str" or f.name == "start":  # a word field (a six-bar's input) is the
                continue  # family's to check; the start is checked above
            # A copy, made read-only: the caller's array stays theirs, and the value cannot
            # change under a motion or a cache computed from it.
            value = np.array(getattr(self, f.name), dtype=float)
            if f.name in self.point_fields and value.shape[-1:] != (2,):
                raise InvalidMechanism(f"{f.name}: must be a point [x, y], got shape {value.shape}")
            if not np.all(np.isfinite(value)):
                raise InvalidMechanism(f"{f.name}: must be finite, got {_show(value)}")
            if f.name in self.length_fields and np.any(value <= 0):
                raise InvalidMechanism(f"{f.name}: must be a positive length, got {_show(value)}")
            if f.name in self.arc_fields and np.any((value <= 0) | (value >= np.pi)):
                bad = value[(value <= 0) | (value >= np.pi)]
                raise InvalidMechanism(
                    f"{f.name}: a spherical link's arc must lie strictly between 0° and 180°, "
                    f"got {np.degrees(bad).ravel()[:3].round(9).tolist()}°"
                )
            if f.name == "pose":
                self._check_pose(value)
            # assembly, assembly2: the branch signs of a family's dyads.
            if f.name.startswith("assembly") and not np.all(np.abs(value) == 1):
                bad = value[np.abs(value) != 1]
                shown = repr(float(value)) if value.ndim == 0 else bad.ravel()[:3].tolist()
                raise InvalidMechanism(f"{f.name}: must be 1 or -1, got {shown}")
            value.flags.writeable = False
            object.__setattr__(self, f.name, value)
        try:
            self.batch_shape  # noqa: B018 - broadcasting check
        except ValueError as exc:
            raise InvalidMechanism(f"dimension arrays do not broadcast together: {exc}") from None

    def _check_start(self) -> None:
        if self.start is None:
            return
        value = np.asarray(self.start, dtype=float)
        if value.ndim or not np.isfinite(value):
            raise InvalidMechanism(f"start: must be one finite angle, got {self.start!r}")
        object.__setattr__(self, "start", float(value))

    def _check_pose(self, value: Array) -> None:
        """A triad's pose index: a whole number below its pose count."""
        triads = self.plan.triads
        most = max((t.max_poses for t in triads), default=1)  # type: ignore[attr-defined]
        if np.any((value != np.round(value)) | (value < 0) | (value >= most)):
            bad = value[(value != np.round(value)) | (value < 0) | (value >= most)]
            raise InvalidMechanism(
                f"pose: must be a whole number from 0 to {most - 1} (the triad's pose index), "
                f"got {bad.ravel()[:3].tolist()}"
            )

    def params(self) -> dict[str, Array]:
        """The named parameters of the plan (lengths, radians, points, assembly sign): every
        numeric field; a word (a Stephenson III's ``input``) chooses the plan, not a number, and
        :attr:`start` where it runs."""
        return {
            f.name: value
            for f in fields(self)
            if f.name != "start" and not isinstance(value := getattr(self, f.name), str)
        }

    @property
    def points(self) -> frozenset[str]:
        """The names of the plan parameters that are points (or unit vectors), not scalars."""
        return self.point_fields | self.derived_points

    @property
    def space(self) -> str:
        """``"plane"`` or ``"sphere"``: where the plan places the joints."""
        return self.plan.space

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return batch_shape(self.params(), self.points)

    @property
    def scale(self) -> Array:
        """A characteristic size (the largest length), for relative tolerances."""
        lengths = [np.asarray(getattr(self, n), dtype=float) for n in self.length_fields]
        if not lengths:
            return np.asarray(1.0)
        largest: Array = np.maximum.reduce(np.broadcast_arrays(*lengths))
        return largest

    def residuals(self, motion: Motion) -> dict[str, Array]:
        """Every constraint's error at each sample of ``motion``, divided by :attr:`scale`:
        each family writes its own, from its constraints alone."""
        raise NotImplementedError(f"{type(self).__name__} does not measure its constraints")

    def with_assembly(self, assembly: ArrayLike) -> Mechanism:

        # The base class declares no ``assembly``; every family that has one gets it replaced
        # (dataclasses.replace checks the name at run time).
        change: dict[str, Any] = {"assembly": assembly}
        return replace(self, **change)

    # -- a value: equality, hashing and batch indexing -------------------------------------------

    def __eq__(self, other: object) -> bool:
        """Two mechanisms are equal when they are of one family with equal fields, arrays
        compared whole (shape and every value)."""
        if type(other) is not type(self):
            return NotImplemented
        return _frozen(self) == _frozen(other)

    def _repr_svg_(self) -> str | None:
        # Jupyter's picture of the linkage, drawn by the plots: they sit above this layer, so
        # the package root lends them through linkwright._display.
        from linkwright._display import repr_svg

        return repr_svg(self)

    def __hash__(self) -> int:
        return hash((type(self).__name__, _frozen(self)))

    def __len__(self) -> int:
        shape = self.batch_shape
        if not shape:
            raise TypeError(f"{type(self).__name__} is one mechanism, not a batch: it has no len()")
        return shape[0]

    def __getitem__(self, index: object) -> Mechanism:
        """The mechanisms of a batch at ``index`` (an integer, a slice, an array of indices or
        a mask over the batch's leading axes), as one mechanism or a smaller batch.

        Examples
        --------
        >>> from linkwright.mechanisms import FourBar
        >>> batch = FourBar(A0=[0, 0], B0=[4, 0], crank=[1.0, 1.5, 2.0], coupler=5, rocker=3.5)
        >>> len(batch), float(batch[1].crank), batch[1:].batch_shape
        (3, 1.5, (2,))
        >>> batch[0] == FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
        True
        >>> FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)[0]
        Traceback (most recent call last):
        ...
        TypeError: FourBar is one mechanism, not a batch: it cannot be indexed
        """
        shape = self.batch_shape
        if not shape:
            raise TypeError(
                f"{type(self).__name__} is one mechanism, not a batch: it cannot be indexed"
            )
        return self._indexed(shape, index)

    def _indexed(self, shape: tuple[int, ...], index: object) -> Mechanism:
        changes = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, np.ndarray):
                continue
            tail = value.shape[-1:] if f.name in self.point_fields else ()
            # index is whatever NumPy accepts (an integer, slice, index array or mask).
            changes[f.name] = np.broadcast_to(value, shape + tail)[index]  # type: ignore[call-overload]
        return replace(self, **changes)


def _frozen(value: object) -> object:
    """A hashable image of a field value: arrays by shape and values (−0.0 as 0.0), dataclass
    values (a composed linkage's joints) field by field, sequences item by item."""
    if isinstance(value, np.ndarray):
        return ("array", value.shape, (value + 0.0).tobytes())
    if is_dataclass(value) and not isinstance(value, type):
        return (type(value).__name__, tuple(_frozen(getattr(value, f.name)) for f in fields(value)))
    if isinstance(value, tuple | list):
        return tuple(_frozen(v) for v in value)
    if isinstance(value, float | int | np.floating | np.integer) and not isinstance(value, bool):
        return float(value) + 0.0
    return value


def _show(value: Array) -> str:
    if value.ndim == 0:
        return repr(float(value))
    bad = value[~np.isfinite(value) | (value <= 0)] if value.size else value
    return f"{bad.ravel()[:3].tolist()} (of an array of shape {value.shape})"


def solve(mechanism: Mechanism, inputs: ArrayLike, *, order: int = 2) -> Motion:
    """Positions (and ``order`` derivatives) of every joint at the inputs (radians).

    ``inputs`` has shape ``(samples,)`` or ``batch + (samples,)``. The mechanism's own assembly
    is used; samples where it cannot be assembled are masked (``motion.valid``).

    Parameters
    ----------
    mechanism : Mechanism
        One linkage, or a batch (dimension arrays with a leading batch shape).
    inputs : array_like
        Input angles θ, radians.
    order : int
        Derivatives by θ to compute: 0 (positions), 1 (and velocities), 2 (and accelerations).

    Returns
    -------
    Motion
        Every joint's positions (and derivatives) at the inputs; ``valid`` masks the samples
        where the linkage is assembled.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5)
    >>> m = solve(crank_rocker, [0.0, np.pi / 2])
    >>> np.round(m.positions["B"], 6)
    array([[4.625   , 3.443744],
           [4.339621, 3.483484]])

    A linkage that cannot assemble gives NaN positions, masked by ``valid``:

    >>> too_short = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> m = solve(too_short, [0.0])
    >>> m.valid, m.positions["B"]
    (array([False]), array([[nan, nan]]))
    """
    return evaluate(
        mechanism.plan, mechanism.params(), inputs, points=mechanism.points, order=order
    )


def configurations(
    mechanism: Mechanism, inputs: ArrayLike, *, order: int = 2
) -> list[tuple[tuple[int, ...], Motion]]:
    """Every assembly configuration at the inputs: one motion per combination of branches.

    Returns ``[(branches, motion), ...]``: ``branches`` holds one value per branching step in
    plan order (a dyad's sign ±1, a triad's pose index 0 … 5, or 0 … 7 on the sphere); each
    motion's ``valid`` says where that configuration is real. Any family, any batch.

    Parameters
    ----------
    mechanism : Mechanism
        One linkage or a batch; its own assembly choice is ignored.
    inputs : array_like
        Input angles θ, radians.
    order : int
        Derivatives by θ to compute (0, 1 or 2).

    Returns
    -------
    list of (tuple of int, Motion)
        Each combination of branches with its motion.

    Examples
    --------
    A four-bar has its two assembly modes; a linkage that cannot assemble has none real:

    >>> from linkwright.mechanisms import FourBar
    >>> found = configurations(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5), [0.0])
    >>> [(signs, bool(m.valid[0])) for signs, m in found]
    [((1,), True), ((-1,), True)]
    >>> found = configurations(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), [0.0])
    >>> [bool(m.valid[0]) for _, m in found]
    [False, False]
    """
    combos, motion = every_configuration(
        mechanism.plan, mechanism.params(), inputs, points=mechanism.points, order=order
    )
    return [
        (tuple(int(v) for v in combo.values()), take(motion, k)) for k, combo in enumerate(combos)
    ]


def circuit(
    mechanism: Mechanism,
    samples: int = 360,
    *,
    order: int = 2,
    circuit: int | None = None,
    spacing: str = "input",
) -> Motion:
    """The whole closed circuit, as the machine runs, sampled at ``samples`` inputs.

    Where the input turns fully this is one turn on the mechanism's assembly (several for a
    linkage geared at a fractional ratio). Where it cannot, the input sweeps its arc up and back
    down, the dyad at its limit changing branch at each limit position (both limits are
    samples, exactly); a linkage of several dyads may pass limits of different dyads before it
    closes. Between limits the input is spaced as sin², so that the joints, which move like the
    square root of the distance to a limit, advance in even steps along their curves.

    ``spacing="path"`` places the samples by the joints' travel instead (limits still exact):
    every joint's step stays within 2·M·L/n (+ rounding) of its path length L, even near a
    change point, where the motion concentrates in a sliver of the input and even input steps
    draw chords across the curve; see :func:`linkwright.engine.trace`. It costs a few
    milliseconds a mechanism, so batches keep the default.

    Parameters
    ----------
    mechanism : Mechanism
        One linkage or a batch.
    samples : int
        Samples along the circuit.
    order : int
        Derivatives by θ to compute (0, 1 or 2).
    circuit : int, optional
        Which circuit (0 first, in the order of :func:`circuits`); by default the one the
        mechanism runs on (:func:`running_circuit`: through its :attr:`~Mechanism.start`).
    spacing : {"input", "path"}
        How samples are spaced (see above).

    Returns
    -------
    Motion
        The circuit's samples in the order the machine runs them; where the linkage cannot
        be assembled at any input, every sample is invalid.

    Examples
    --------
    Driving the long link of a crank-rocker, the input swings over |θ| ≥ arccos(−11/28):

    >>> from linkwright.mechanisms import FourBar
    >>> rocker_input = FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1)
    >>> m = circuit(rocker_input, 8)
    >>> np.degrees(m.input).round(3)
    array([113.132, 132.717, 180.   , 227.283, 246.868, 227.283, 180.   ,
           132.717])
    >>> m.branches["B"]
    array([ 1.,  1.,  1.,  1., -1., -1., -1., -1.])

    A linkage that cannot assemble has no circuit: every sample is invalid.

    >>> bool(circuit(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), 8).valid.any())
    False

    A double rocker runs on one of two arcs; its ``start`` says which (here the second):

    >>> rocking = FourBar(A0=[0, 0], B0=[4, 0], crank=3, coupler=1, rocker=3.5, start=1.0)
    >>> np.degrees(circuit(rocking, 4).input).round(3)
    array([38.625, 58.605, 78.585, 58.605])
    """
    chosen = running_circuit(mechanism, samples, spacing) if circuit is None else circuit
    start = mechanism.start if mechanism.start is not None and circuit is None else 0.0
    return trace(
        mechanism.plan,
        mechanism.params(),
        samples,
        points=mechanism.points,
        order=order,
        circuit=chosen,
        start=start,
        spacing=spacing,
    )


def running_circuit(mechanism: Mechanism, samples: int = 360, spacing: str = "input") -> int:
    """Which of :func:`circuits` the mechanism runs on: the one through its ``start``.

    Without a ``start``, the first. An input that turns fully has one circuit. An input that
    rocks runs over the arc that holds ``start`` (modulo the period), or the arc nearest to it
    where none does (an edited linkage whose arcs moved). A linkage with a triad follows its
    configurations, and several circuits may pass ``start``: the one through the mechanism's
    own configuration there (its pose and assembly), found by position. A batch must run on
    one circuit number throughout.

    Parameters
    ----------
    mechanism : Mechanism
        One linkage, or a batch (families without a triad).
    samples, spacing : for a linkage with a triad, the sampling its circuits are found on
        (that of :func:`circuits`).

    Returns
    -------
    int
        The circuit's number, 0 first.

    Raises
    ------
    ValueError
        For a batch whose members run on different circuit numbers.

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> double_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=3, coupler=1, rocker=3.5)
    >>> arcs = input_range(double_rocker)
    >>> np.degrees(arcs.lo).round(2), np.degrees(arcs.hi).round(2)
    (array([-78.58,  38.62]), array([-38.62,  78.58]))
    >>> [running_circuit(replace(double_rocker, start=np.radians(a))) for a in (60, -60, 180)]
    [1, 0, 0]
    """
    start = mechanism.start
    if start is None:
        return 0
    if mechanism.plan.triads:
        return _triad_circuit(mechanism, start, samples, spacing)
    arcs = input_range(mechanism)
    lo, hi = np.asarray(arcs.lo, float), np.asarray(arcs.hi, float)
    period = np.asarray(arcs.period, float)[..., None]
    # How far start lies beyond each arc, both ways round the period (0 inside it).
    above = lo + np.mod(start - lo, period)
    gap = np.where(above <= hi, 0.0, np.minimum(above - hi, lo + period - above))
    gap = np.where(np.isfinite(gap), gap, np.inf)
    rocking = ~(np.asarray(arcs.full) | np.asarray(arcs.never))
    chosen = np.argmin(gap, axis=-1)[rocking]
    if chosen.size == 0:
        return 0
    if np.any(chosen != chosen.flat[0]):
        raise ValueError(
            "start: the linkages of this batch run on different circuits through it; "
            "trace them one at a time (mechanism[i])"
        )
    return int(chosen.flat[0])


def _triad_circuit(mechanism: Mechanism, start: float, samples: int, spacing: str) -> int:
    """The circuit nearest to the mechanism's own configuration at ``start``."""
    found = every_circuit(
        mechanism.plan,
        mechanism.params(),
        samples,
        points=mechanism.points,
        order=0,
        spacing=spacing,
    )
    if len(found) < 2:
        return 0
    own = solve(mechanism, [start], order=0)
    size = float(np.max(mechanism.scale))
    scores = []
    for candidate in found:
        motion = candidate.motion
        # Input distance in the linkage's lengths, so that a circuit through start on another
        # configuration loses to the one whose joints are where the mechanism's are.
        off = np.abs(np.angle(np.exp(1j * (motion.input - start)))) * size
        if bool(own.valid[0]):
            for name, at in own.positions.items():
                if name in motion.positions:
                    apart = np.linalg.norm(motion.positions[name] - at[0], axis=-1)
                    off = off + np.where(np.isfinite(apart), apart, np.inf)
        scores.append(float(np.min(np.where(motion.valid, off, np.inf))))
    return int(np.argmin(scores))


def circuits(
    mechanism: Mechanism, samples: int = 360, *, order: int = 2, spacing: str = "input"
) -> tuple[InputArcs, list[Motion]]:
    """The input's arcs, and every closed circuit the linkage runs on its assembly.

    One :func:`circuit` where the input turns fully; where it rocks, one per arc it rocks over
    (each up and back, switching branch at its limits); none where it cannot be assembled. A
    linkage with a triad has its configurations followed rather than its assembly held: every
    circuit of every configuration (:func:`linkwright.engine.continuation.every_circuit`).

    Parameters
    ----------
    mechanism : Mechanism
        One linkage (a batch for families without a triad).
    samples : int
        Samples along each circuit.
    order : int
        Derivatives by θ to compute (0, 1 or 2).
    spacing : {"input", "path"}
        How samples are spaced (see :func:`circuit`).

    Returns
    -------
    (InputArcs, list of Motion)
        The input's arcs and one motion per circuit (none for a linkage that cannot be
        assembled at any input).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> arcs, motions = circuits(FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1), 8)
    >>> bool(arcs.full), len(motions)
    (False, 2)
    >>> circuits(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3), 8)[1]
    []
    """
    if mechanism.plan.triads:
        # The configurations of a triad are followed, not held: every circuit of every one.
        found = every_circuit(
            mechanism.plan,
            mechanism.params(),
            samples,
            points=mechanism.points,
            order=order,
            spacing=spacing,
        )
        return arcs_of(found, mechanism.batch_shape), [c.motion for c in found]
    arcs = input_range(mechanism)
    if bool(arcs.never):
        return arcs, []
    if bool(arcs.full):
        return arcs, [circuit(mechanism, samples, order=order, spacing=spacing)]
    count = int(arcs.count)
    return arcs, [
        circuit(mechanism, samples, order=order, circuit=k, spacing=spacing) for k in range(count)
    ]


def input_range(mechanism: Mechanism, *, method: str = "auto") -> InputArcs:
    """The admissible input arcs (limit positions as exact roots) of each mechanism.

    For a linkage with a triad, the arcs of its circuits (:func:`circuits`), one mechanism at a
    time; their limits are found to about 1e-10 rad.

    Parameters
    ----------
    mechanism : Mechanism
        One linkage, or a batch (families without a triad).
    method : {"auto", "numeric"}
        ``"auto"`` uses each dyad's closed form where there is one; ``"numeric"`` always
        brackets the roots of the dyads' discriminants (a cross-check).

    Returns
    -------
    InputArcs
        ``full`` where the input turns fully, ``never`` where it cannot be assembled at any
        input, else the arcs ``lo`` … ``hi`` (radians) it rocks over.

    Examples
    --------
    Driving the long link of a crank-rocker, its input rocks over |θ| ≥ arccos(−11/28)
    (the law of cosines with A0 B at its longest, coupler + rocker):

    >>> from linkwright.mechanisms import FourBar
    >>> arcs = input_range(FourBar(A0=[0, 0], B0=[1, 0], crank=3.5, coupler=5, rocker=1))
    >>> bool(arcs.full), int(arcs.count), np.degrees([arcs.lo[0], arcs.hi[0]]).round(3)
    (False, 1, array([113.132, 246.868]))
    >>> round(float(np.degrees(np.arccos(-11 / 28))), 3)
    113.132

    A linkage that cannot assemble:

    >>> bool(input_range(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)).never)
    True
    """
    return input_arcs(mechanism.plan, mechanism.params(), points=mechanism.points, method=method)

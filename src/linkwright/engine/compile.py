"""Compiled plans: a numba kernel generated from a plan's steps, cached on disk per plan shape.

The plan evaluator (:func:`linkwright.engine.evaluate.place_all`) runs each step over whole
arrays, so a batch streams through memory a few dozen times. :func:`compiled_plan` turns a plan
into one loop over mechanisms × samples that places every joint of one sample in registers and
writes only the results: positions, valid and regular masks, dyad margins and, with
``order=1`` or ``2``, velocities and accelerations from the differentiated constraints; or,
through :meth:`CompiledPlan.positions`, the masked positions of the joints asked for and
nothing else. Each step kind contributes the scalar form of its own placement
(:mod:`linkwright.engine.compile_steps`: the evaluator's formulas, rearranged where that saves
a division or a libm call per sample, so the numbers are the evaluator's to rounding);
tests/test_compile.py compares them family by family. The sample loop is written so that LLVM
vectorises it (see :data:`BLOCK` and compile_steps' module doc).

One kernel is generated per plan *shape*: the step kinds and their wiring, which parameters are
per-mechanism arrays and which one value for the whole batch, the derivative order, and whether
every assembly mode is placed in one pass (:meth:`CompiledPlan.configurations`). Parameter
names do not enter the source, so two composed linkages of one structure share a kernel. The
source goes to ``$LINKWRIGHT_CACHE/kernels`` (default ``$XDG_CACHE_HOME/linkwright/kernels``,
else ``~/.cache/linkwright/kernels``) and is compiled with numba's ``cache=True``: a second
process loads the machine code instead of compiling it.

What stays with the evaluator (the compiled plan calls :func:`place_all` and says so in
:attr:`CompiledPlan.reason`): plans with triads (their polynomial solve is not generated),
plans of more than :data:`MAX_STEPS` steps (compile time grows with the source), per-sample
branch overrides and crossings (circuit tracing), and everything when numba (the ``fast``
extra) is not installed. The evaluator stays the reference.

This module is the public face: the kernel generator lives in
:mod:`~linkwright.engine.compile_source`, the disk cache and the threads in
:mod:`~linkwright.engine.compile_cache`.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.compile_cache import SERIAL_CELLS as SERIAL_CELLS
from linkwright.engine.compile_cache import cache_dir, load_kernel, run_ranges
from linkwright.engine.compile_cache import threads as threads
from linkwright.engine.compile_source import BLOCK as BLOCK
from linkwright.engine.compile_source import GENERATOR_VERSION as GENERATOR_VERSION
from linkwright.engine.compile_source import (
    KernelShape,
    ScalarProbe,
    crank_steps,
    generate,
    kernel_outputs,
)
from linkwright.engine.compile_steps import fragment
from linkwright.engine.evaluate import (
    Motion,
    batch_shape,
    evaluate,
    motion_of_states,
    place_all,
)
from linkwright.engine.plan import Plan, placed_joints
from linkwright.engine.plane_steps import Fixed
from linkwright.engine.state import JointState, Param

__all__ = [
    "MAX_MODES",
    "MAX_STEPS",
    "CompiledPlan",
    "available",
    "cache_dir",
    "compiled_plan",
    "solve",
]

Array = NDArray[np.float64]


MAX_STEPS = 64
"""Longer plans stay with the evaluator: numba's compile time grows faster than the source."""


MAX_MODES = 4096
"""At most this many assembly modes (2^dyads) are placed in one pass."""


MAX_RATIOS = 64
"""A crank ratio drawn per mechanism from at most this many values gets one row of cosines per
value (see _trig); more, and one row per mechanism."""


MAX_OUTPUT_BYTES = 2**33
"""A configurations() call that would write more than this is refused before any work."""


def available() -> bool:
    """Whether numba is installed, so that plans run compiled (else through the evaluator)."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def _fallback_reason(plan: Plan) -> str | None:
    if not available():
        return "numba is not installed (the 'fast' extra): the plan evaluator places it"
    if len(plan.steps) > MAX_STEPS:
        return f"more than {MAX_STEPS} steps: the plan evaluator places it"
    for step in plan.steps:
        if fragment(step) is None:
            return f"{step.title} has no compiled form: the plan evaluator places it"
    return None


class CompiledPlan:
    """A plan with its generated kernels (see the module doc); made by :func:`compiled_plan`.

    :meth:`place` returns what :func:`~linkwright.engine.evaluate.place_all` returns (the
    broadcast inputs and every joint's raw state), :meth:`evaluate` a masked
    :class:`~linkwright.engine.evaluate.Motion` as :func:`~linkwright.engine.evaluate.evaluate`
    does, and :meth:`configurations` every assembly mode in one pass, as
    :func:`linkwright.engine.continuation.every_configuration` does. ``reason`` is None where
    the kernels run, else why the evaluator places the plan.
    """

    def __init__(self, plan: Plan) -> None:
        self.plan = plan
        self.reason = _fallback_reason(plan)
        self.moving = [j for j in plan.joints if not isinstance(plan.step(j), Fixed)]
        self.dyads = [s.name for s in plan.dyads]
        self.dim = 3 if plan.space == "sphere" else 2

    @property
    def compiled(self) -> bool:
        """Whether this plan runs through generated kernels."""
        return self.reason is None

    # ..

    def _scalars(self) -> list[str]:
        """Every named scalar the steps read, points split into components (``key[c]``)."""
        names: list[str] = []
        probe = ScalarProbe(self.dim)
        for step in self.plan.steps:
            emit = fragment(step)
            assert emit is not None
            emit(step, probe)
        for name in probe.used:
            if name not in names:
                names.append(name)
        return names

    def _prepare(
        self, params: Mapping[str, ArrayLike], theta: ArrayLike, points: frozenset[str]
    ) -> tuple[KernelShape, Array, Array, list[Array], int, tuple[int, ...]]:
        theta = np.asarray(theta, dtype=float)
        if theta.ndim == 0:
            theta = theta[None]
        full = np.broadcast_shapes(batch_shape(params, points) + (1,), theta.shape)
        lead, samples = full[:-1], full[-1]
        n = int(np.prod(lead, dtype=np.int64))
        shape = KernelShape()
        batched: list[Array] = []
        uniform: list[float] = []
        for name in self._scalars():
            key, comp = (name[:-3], int(name[-2])) if name.endswith("]") else (name, None)
            value = np.asarray(params[key], dtype=float)
            if comp is not None:
                value = value[..., comp]
            if value.size == 1:
                shape.uniform[name] = len(uniform)
                uniform.append(float(value.reshape(())))
            else:
                shape.batched[name] = len(batched)
                batched.append(np.broadcast_to(value, lead).reshape(n))
        T = theta.reshape(1, samples) if theta.size == samples else np.broadcast_to(theta, full)
        trig = [_trig(step, params, shape, T, lead, n, batched) for step in crank_steps(self.plan)]
        S = np.stack(batched, axis=-1) if batched else np.zeros((n, 0))
        U = np.array(uniform, dtype=float)
        return shape, S, U, trig, n, full

    def _run(
        self,
        params: Mapping[str, ArrayLike],
        theta: ArrayLike,
        points: frozenset[str],
        order: int,
        modes: bool,
        joints: tuple[str, ...] | None = None,
        into: list[Array] | None = None,
    ) -> tuple[Array, list[Array], tuple[int, ...]]:
        """The kernel run over the batch: the broadcast inputs, the output arrays in the
        kernel's order (:func:`kernel_outputs`) and the batch's full shape."""
        count = 2 ** len(self.dyads) if modes else 1
        if modes and count > MAX_MODES:
            raise ValueError(
                f"{len(self.dyads)} dyads have {count} assembly modes; at most {MAX_MODES} "
                "are placed in one pass"
            )
        theta_a = np.asarray(theta, dtype=float)
        full = np.broadcast_shapes(
            batch_shape(params, points) + (1,), theta_a.shape if theta_a.ndim else (1,)
        )
        n, samples = int(np.prod(full[:-1], dtype=np.int64)), full[-1]
        J, K, d = len(self.moving), len(self.dyads), self.dim
        cells = count * n * samples
        if joints is None:
            need = cells * (J * (2 + 8 * d * (1 + min(order, 2))) + 8 * K)
        else:
            need = cells * 8 * d * len(joints)
        need += 16 * n * samples * len(crank_steps(self.plan))  # at most, the cranks' trig
        if need > MAX_OUTPUT_BYTES:
            raise ValueError(
                f"the result would take {need / 2**30:.1f} GiB (more than "
                f"{MAX_OUTPUT_BYTES / 2**30:.0f}): place fewer mechanisms or samples at once"
            )
        shape, S, U, trig, n, full = self._prepare(params, theta, points)
        kernel = load_kernel(generate(self.plan, shape, order, modes, joints))
        # One array per output (each a few tens of MB at most for a bench-sized batch): the
        # allocator reuses blocks of that size, where one array for every joint would be mapped
        # afresh (and its pages faulted in) at every call.
        outs: list[Array] = []
        lead = (count, n, samples) if joints is None else (n, samples)
        for name in kernel_outputs(self.plan, order, modes, joints) if into is None else ():
            if name.startswith(("OK", "RG")):
                outs.append(np.empty(lead, dtype=bool))
            elif name.startswith("M"):
                outs.append(np.empty(lead))
            else:
                outs.append(np.empty((*lead, d)))
        if into is not None:
            outs = [a.reshape(*lead, d) for a in into]  # views: checked by the caller
        run_ranges(kernel, n, samples * count, (samples, S, U, *trig, *outs))
        return np.broadcast_to(theta_a, full), outs, full

    def _states(
        self,
        params: Mapping[str, ArrayLike],
        points: frozenset[str],
        outs: list[Array],
        full: tuple[int, ...],
        order: int,
        mode: int | None,
    ) -> dict[str, JointState]:
        """Every joint's state, for one mode of the kernel's outputs (None: the only one)."""
        m = 0 if mode is None else mode
        named = dict(
            zip(kernel_outputs(self.plan, order, mode is not None, None), outs, strict=True)
        )
        states: dict[str, JointState] = {}
        moving = {name: k for k, name in enumerate(self.moving)}
        dyads = {name: k for k, name in enumerate(self.dyads)}
        vec = full + (self.dim,)
        for step in self.plan.steps:
            for name in placed_joints(step):
                if isinstance(step, Fixed):
                    at = np.asarray(params[step.at], dtype=float)[..., None, :]
                    pos = np.broadcast_to(at, full + at.shape[-1:])
                    true = np.ones(full, dtype=bool)
                    zeros = np.zeros(pos.shape) if order else None
                    states[name] = JointState(pos, zeros, zeros, true, true)
                    continue
                k = moving[name]
                state = JointState(
                    pos=named[f"P{k}"][m].reshape(vec),
                    vel=named[f"V{k}"][m].reshape(vec) if order >= 1 else None,
                    acc=named[f"A{k}"][m].reshape(vec) if order >= 2 else None,
                    valid=named[f"OK{k}"][m].reshape(full),
                    regular=named[f"RG{k}"][m].reshape(full),
                )
                if name in dyads:
                    sign: Array | np.float64
                    if mode is None:
                        sign = np.asarray(params[step.branch], dtype=float)[..., None]  # type: ignore[attr-defined]
                    else:
                        sign = np.float64(
                            1.0 - 2.0 * ((mode >> (len(dyads) - 1 - dyads[name])) & 1)
                        )
                    state = JointState(
                        state.pos,
                        state.vel,
                        state.acc,
                        state.valid,
                        state.regular,
                        margin=named[f"M{dyads[name]}"][m].reshape(full),
                        branch=np.broadcast_to(sign, full),
                    )
                states[name] = state
        return states

    def positions(
        self,
        params: Mapping[str, ArrayLike],
        theta: ArrayLike,
        joints: tuple[str, ...] | None = None,
        *,
        points: frozenset[str] = frozenset(),
        out: Mapping[str, Array] | None = None,
    ) -> dict[str, Array]:
        """The positions of ``joints`` (default: the plan's traced joints; moving joints only),
        NaN wherever the mechanism is not assembled, as :func:`~linkwright.engine.evaluate.
        evaluate`'s Motion masks them: the kernel writes nothing else (no masks, margins or
        other joints), for work that needs only curves (the atlas, batch sampling).

        ``out`` (joint → a C-contiguous float64 array of the result's shape) is written
        instead of new arrays: a loop over batches then reuses its memory, where fresh arrays
        of a few tens of MB cost about as much in page faults as the kernel takes to fill
        them."""
        chosen = tuple(self.plan.traced if joints is None else joints)
        for name in chosen:
            if name not in self.moving:
                raise ValueError(
                    f"positions: {name!r} is not a moving joint of this plan "
                    f"(moving: {', '.join(self.moving)})"
                )
        into = None
        if out is not None:
            theta_a = np.asarray(theta, dtype=float)
            full = np.broadcast_shapes(
                batch_shape(params, points) + (1,), theta_a.shape if theta_a.ndim else (1,)
            )
            into = [_checked_out(out, name, full + (self.dim,)) for name in chosen]
        if self.reason is not None:
            motion = evaluate(self.plan, params, theta, points=points, order=0)
            got = {name: motion.positions[name] for name in chosen}
            if into is not None:
                for name, a in zip(chosen, into, strict=True):
                    a[...] = got[name]
                return dict(zip(chosen, into, strict=True))
            return got
        _, outs, full = self._run(params, theta, points, 0, False, chosen, into)
        return {
            name: out.reshape(full + (self.dim,)) for name, out in zip(chosen, outs, strict=True)
        }

    def place(
        self,
        params: Mapping[str, ArrayLike],
        theta: ArrayLike,
        *,
        points: frozenset[str] = frozenset(),
        branches: Mapping[str, ArrayLike] | None = None,
        order: int = 2,
        crossings: Mapping[str, ArrayLike] | None = None,
    ) -> tuple[Array, dict[str, JointState]]:
        """As :func:`~linkwright.engine.evaluate.place_all`: the broadcast inputs and every
        joint's raw state (positions NaN where not valid, derivatives NaN where not regular).
        Per-sample ``branches`` and ``crossings`` go to the evaluator."""
        if order not in (0, 1, 2):
            raise ValueError(f"order: must be 0, 1 or 2, got {order!r}")
        if (
            self.reason is not None
            or branches
            or (crossings and any(np.any(v) for v in crossings.values()))
        ):
            return place_all(
                self.plan,
                params,
                theta,
                points=points,
                branches=branches,
                order=order,
                crossings=crossings,
            )
        theta_b, outs, full = self._run(params, theta, points, order, modes=False)
        return theta_b, self._states(params, points, outs, full, order, None)

    def evaluate(
        self,
        params: Mapping[str, ArrayLike],
        theta: ArrayLike,
        *,
        points: frozenset[str] = frozenset(),
        order: int = 2,
    ) -> Motion:
        """As :func:`~linkwright.engine.evaluate.evaluate`: a masked Motion."""
        theta_b, states = self.place(params, theta, points=points, order=order)
        return _motion(theta_b, states, order)

    def configurations(
        self,
        params: Mapping[str, ArrayLike],
        theta: ArrayLike,
        *,
        points: frozenset[str] = frozenset(),
        order: int = 2,
    ) -> tuple[list[dict[str, float]], Motion]:
        """Every combination of dyad branches in one pass, as
        :func:`linkwright.engine.continuation.every_configuration`: the combinations (joint →
        sign) and one Motion whose leading axis runs over them. Plans the kernels do not place
        (see ``reason``) go to that function."""
        if order not in (0, 1, 2):
            raise ValueError(f"order: must be 0, 1 or 2, got {order!r}")
        if self.reason is not None:
            from linkwright.engine.continuation import every_configuration

            return every_configuration(self.plan, params, theta, points=points, order=order)
        theta_b, outs, full = self._run(params, theta, points, order, modes=True)
        combos = [
            dict(zip(self.dyads, values, strict=True))
            for values in itertools.product((1.0, -1.0), repeat=len(self.dyads))
        ]
        motions = [
            _motion(theta_b, self._states(params, points, outs, full, order, k), order)
            for k in range(len(combos))
        ]
        return combos, _stack_motions(motions)


def _trig(
    step: Any,
    params: Mapping[str, ArrayLike],
    shape: KernelShape,
    T: Array,
    lead: tuple[int, ...],
    n: int,
    columns: list[Array],
) -> Array:
    """cos and sin of a crank's angle ``phase + ratio·t`` (``phase + t`` for a trammel) by
    NumPy, as the evaluator computes them (2, rows, samples), and how the kernel reads them
    (``shape.cranks``): one row for the batch where the inputs and the ratio are shared (the
    phase too, or else the kernel turns the row by each mechanism's phase), else one row per
    mechanism. Where the inputs are shared and the ratio is drawn per mechanism from a few
    values (a geared five-bar's gear ratios), one row per value, the mechanism's row number
    appended to ``columns`` (the per-mechanism scalars). So the sample loop calls no libm
    function for a crank, and NumPy's cos and sin (tens of ns an element here) run on as few
    elements as the batch allows."""

    def value(p: Param) -> Array:
        return np.asarray(params[p] if isinstance(p, str) else p, dtype=float)

    samples = T.shape[-1]
    ratio = value(getattr(step, "ratio", 1.0))
    phase = value(step.phase)
    if T.shape[0] == 1 and ratio.size == 1:
        if phase.size == 1:
            phi = float(phase.reshape(())) + float(ratio.reshape(())) * T
            shape.cranks[step.name] = ("0", False)
        else:
            phi = float(ratio.reshape(())) * T
            shape.cranks[step.name] = ("0", True)
        return np.stack((np.cos(phi), np.sin(phi)))
    if T.shape[0] == 1 and ratio.size > 1:
        values, rows = np.unique(np.broadcast_to(ratio, lead).reshape(n), return_inverse=True)
        if len(values) <= MAX_RATIOS:
            shape.cranks[step.name] = (f"int(s{len(columns)})", phase.size > 1)
            shape.batched[f"row of {step.name}"] = len(columns)
            columns.append(rows.astype(float))
            if phase.size == 1:
                phi = float(phase.reshape(())) + values[:, None] * T
            else:
                phi = values[:, None] * T
            return np.stack((np.cos(phi), np.sin(phi)))
    full = lead + (samples,)
    angle = _expand(phase, lead) + _expand(ratio, lead) * np.broadcast_to(T, full)
    shape.cranks[step.name] = ("i", False)
    return np.stack((np.cos(angle), np.sin(angle))).reshape(2, n, samples)


def _checked_out(out: Mapping[str, Array], name: str, shape: tuple[int, ...]) -> Array:
    """``out[name]`` where the kernel can write it, else a one-line ValueError."""
    if name not in out:
        raise ValueError(f"out: no array for joint {name!r}")
    a = out[name]
    if not isinstance(a, np.ndarray) or a.dtype != np.float64 or not a.flags.c_contiguous:
        raise ValueError(f"out[{name!r}]: must be a C-contiguous float64 array")
    if a.shape != shape or not a.flags.writeable:
        raise ValueError(f"out[{name!r}]: must be writeable, of shape {shape}, got {a.shape}")
    return a


def _expand(value: Array, lead: tuple[int, ...]) -> Array:
    """A scalar parameter broadcast to the batch with a trailing sample axis."""
    return np.broadcast_to(value, lead).reshape(lead + (1,)) if value.size > 1 else value


def _motion(theta: Array, states: dict[str, JointState], order: int) -> Motion:
    """The masked Motion of raw states, by evaluate()'s rules (its own function)."""
    return motion_of_states(theta, states, order)


def _stack_motions(motions: list[Motion]) -> Motion:
    """One Motion with a new leading axis over ``motions``."""

    def stack(get: Any) -> Any:
        first = get(motions[0])
        if first is None:
            return None
        if isinstance(first, dict):
            return {k: np.stack([get(m)[k] for m in motions]) for k in first}
        return np.stack([get(m) for m in motions])

    return Motion(
        input=stack(lambda m: m.input),
        positions=stack(lambda m: m.positions),
        velocities=stack(lambda m: m.velocities),
        accelerations=stack(lambda m: m.accelerations),
        valid=stack(lambda m: m.valid),
        regular=stack(lambda m: m.regular),
        branches=stack(lambda m: m.branches),
        margins=stack(lambda m: m.margins),
        labels=stack(lambda m: m.labels),
    )


_PLANS: dict[Plan, CompiledPlan] = {}


def compiled_plan(plan: Plan) -> CompiledPlan:
    """The compiled form of ``plan`` (made once per plan; kernels generated on first use).

    Examples
    --------
    >>> from linkwright.engine.plan import Crank, DyadRRR, Fixed, Plan
    >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", 1.0), Fixed("Q", "Q"),
    ...              DyadRRR("B", "A", 3.0, "Q", 2.0)), traced=("B",))
    >>> params = {"O": np.zeros(2), "Q": np.array([3.0, 0.0]), "assembly": 1.0}
    >>> motion = compiled_plan(plan).evaluate(params, [0.0, 1.0], points=frozenset("OQ"))
    >>> motion.positions["B"].round(6).tolist()
    [[3.25, 1.984313], [3.318098, 1.974541]]
    >>> from linkwright.engine.evaluate import evaluate
    >>> reference = evaluate(plan, params, [0.0, 1.0], points=frozenset("OQ"))
    >>> bool(np.allclose(motion.positions["B"], reference.positions["B"], rtol=1e-12, atol=0))
    True
    """
    if plan not in _PLANS:
        _PLANS[plan] = CompiledPlan(plan)
    return _PLANS[plan]


def solve(mechanism: Any, inputs: ArrayLike, *, order: int = 2) -> Motion:
    """:func:`linkwright.mechanisms.solve` through the compiled plan: the opt-in hook for batch
    work (same Motion, to rounding where the kernels run; the evaluator where they do not).
    """
    return compiled_plan(mechanism.plan).evaluate(
        mechanism.params(), inputs, points=mechanism.points, order=order
    )

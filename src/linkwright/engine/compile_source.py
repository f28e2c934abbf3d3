"""The kernel generator of compiled plans: a plan's steps written out as one numba function.

:func:`generate` writes the source of the kernel of a plan for one *shape* of its parameters
(:class:`KernelShape`: which are per-mechanism columns, which uniform values, how each crank's
cosines and sines arrive): one loop over mechanisms × samples that places every joint of one
sample in registers (each step kind's fragment comes from
:mod:`linkwright.engine.compile_steps`) and writes only the results (:func:`kernel_outputs`).
:class:`ScalarProbe` runs the same fragments to learn which parameters a plan reads.

Its own room (split from :mod:`linkwright.engine.compile`): the generator is text in, text
out, with no numba and no NumPy work in it; the disk cache and the threads are
:mod:`~linkwright.engine.compile_cache`'s, and running a plan is
:class:`~linkwright.engine.compile.CompiledPlan`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from linkwright.engine.compile_steps import HOIST, fragment
from linkwright.engine.plan import Plan
from linkwright.engine.plane_steps import Crank, Fixed, Trammel
from linkwright.engine.sphere_steps import SphereCrank
from linkwright.engine.state import Param

__all__ = [
    "BLOCK",
    "GENERATOR_VERSION",
    "KernelShape",
    "ScalarProbe",
    "crank_steps",
    "generate",
    "kernel_outputs",
]

GENERATOR_VERSION = 3
"""Part of every kernel's hash: bump it when a fragment changes, so old sources are not used."""


@dataclass
class KernelShape:
    """How one call's parameters meet the plan: which are per-mechanism (columns of S), which
    uniform (entries of U), and how each crank's cosines and sines arrive (the compiled plan
    computes them with NumPy before the kernel runs, :mod:`linkwright.engine.compile`)."""

    batched: dict[str, int] = field(default_factory=dict)  # scalar name → column of S
    uniform: dict[str, int] = field(default_factory=dict)  # scalar name → entry of U
    # crank step name → (row of its trig array: "0" shared or "i" per mechanism, rotated by
    # its own phase in the kernel)
    cranks: dict[str, tuple[str, bool]] = field(default_factory=dict)


BLOCK = 64
"""Samples per block of the sample loop. The block's results go to a scratch array whose row
stride is this constant, so LLVM can tell its rows apart without a runtime check per pair (with
a stride known only at run time it gave up: "too many memory checks needed"), and the block
stays in the first-level cache for the copies to the outputs that follow."""


class _Names:
    """The generator's side of :class:`linkwright.engine.compile_steps.Names`."""

    def __init__(self, plan: Plan, shape: KernelShape, order: int, modes: bool) -> None:
        self.order = order
        self.dim = 3 if plan.space == "sphere" else 2
        self.shape = shape
        self.modes = modes
        self.index = {j: k for k, j in enumerate(plan.joints)}
        self.dyads = [s.name for s in plan.dyads]
        self.cranks = list(shape.cranks)
        self.hoisted: list[str] = []

    def joint(self, name: str) -> str:
        return f"j{self.index[name]}_"

    def scalar(self, p: Param) -> str:
        if not isinstance(p, str):
            return repr(float(p))
        if p in self.shape.batched:
            return f"s{self.shape.batched[p]}"
        return f"u{self.shape.uniform[p]}"

    def point(self, key: str) -> tuple[str, ...]:
        return tuple(self.scalar(f"{key}[{c}]") for c in range(self.dim))

    def sign(self, step_name: str, key: str) -> str:
        if self.modes:
            return f"g{self.dyads.index(step_name)}"
        return self.scalar(key)

    def trig(self, step: Any) -> tuple[str, str]:
        k = self.cranks.index(step.name)
        row, rotated = self.shape.cranks[step.name]
        c, s = f"C{k}[0, {row}, j]", f"C{k}[1, {row}, j]"
        if not rotated:
            return c, s
        # cos and sin of ratio·t, turned by the mechanism's own phase (the angle-sum formulas):
        # one NumPy cos and sin per sample row, not one libm call per mechanism and sample.
        phase = self.scalar(step.phase)
        self.hoisted += [f"q{k}c = math.cos({phase})", f"q{k}s = math.sin({phase})"]
        return f"(q{k}c * {c} - q{k}s * {s})", f"(q{k}s * {c} + q{k}c * {s})"


def crank_steps(plan: Plan) -> list[Any]:
    """The steps turned by the input, whose cosines and sines the caller computes."""
    return [s for s in plan.steps if isinstance(s, Crank | SphereCrank | Trammel)]


def kernel_outputs(
    plan: Plan, order: int, modes: bool, joints: tuple[str, ...] | None
) -> list[str]:
    """The output arguments of a kernel, in order: ``joints`` None for every joint's state
    (positions, derivatives up to ``order``, valid and regular masks, dyad margins), else the
    masked positions of those joints only."""
    moving = [j for j in plan.joints if not isinstance(plan.step(j), Fixed)]
    if joints is not None:
        return [f"P{k}" for k in range(len(joints))]
    names: list[str] = []
    for k in range(len(moving)):
        names.append(f"P{k}")
        if order >= 1:
            names.append(f"V{k}")
        if order >= 2:
            names.append(f"A{k}")
        names += [f"OK{k}", f"RG{k}"]
    names += [f"M{k}" for k in range(len(plan.dyads))]
    return names


def generate(
    plan: Plan,
    shape: KernelShape,
    order: int,
    modes: bool,
    joints: tuple[str, ...] | None = None,
) -> str:
    """The source of the kernel of ``plan`` for one shape of its parameters (see module doc).

    The kernel's arguments: lo, hi (the mechanisms it places), ns (samples per mechanism),
    S (n, columns) per-mechanism scalars, U (entries,) uniform ones, one array
    (2, 1 or n, samples) of cosines and sines per crank, then the outputs (:func:`kernel_outputs`):
    per moving joint P, V, A (modes, n, samples, dim), OK, RG (modes, n, samples), per dyad M
    (modes, n, samples); or, with ``joints``, P (n, samples, dim) per joint named, NaN wherever
    any joint of the mechanism is not placed (as a Motion masks them).
    """
    g = _Names(plan, shape, order, modes)
    moving = [j for j in plan.joints if not isinstance(plan.step(j), Fixed)]
    comps = "xyz"[: g.dim]
    body: list[str] = []
    for step in plan.steps:
        emit = fragment(step)
        assert emit is not None  # compiled_plan checked every step
        for line in emit(step, g):
            if line.startswith(HOIST):
                g.hoisted.append(line[len(HOIST) :])
            else:
                body.append(line)
    # The block's results go to scratch rows first (unit stride, see BLOCK); one copy loop per
    # output array follows, each with one pair of arrays for LLVM to check for overlap.
    fill: list[str] = []
    copies: list[list[str]] = []
    r = 0
    m = "m, " if modes else "0, "
    if joints is not None:
        oks = " & ".join(f"{g.joint(name)}ok" for name in moving) or "True"
        body.append(f"bad = 0.0 if {oks} else nan")
        for k, name in enumerate(joints):
            v = g.joint(name)
            copy = []
            for c, comp in enumerate(comps):
                fill.append(f"R[{r}, jj] = {v}{comp} + bad")
                copy.append(f"P{k}[i, j0 + jj, {c}] = R[{r}, jj]")
                r += 1
            copies.append(copy)
    else:
        for k, name in enumerate(moving):
            v = g.joint(name)
            for kind, least, out in (("", 0, "P"), ("v", 1, "V"), ("a", 2, "A")):
                if order >= least:
                    copy = []
                    for c, comp in enumerate(comps):
                        fill.append(f"R[{r}, jj] = {v}{kind}{comp}")
                        copy.append(f"{out}{k}[{m}i, j0 + jj, {c}] = R[{r}, jj]")
                        r += 1
                    copies.append(copy)
            for flag, out in (("ok", "OK"), ("rg", "RG")):
                fill.append(f"R[{r}, jj] = 1.0 if {v}{flag} else 0.0")
                copies.append([f"{out}{k}[{m}i, j0 + jj] = R[{r}, jj] != 0.0"])
                r += 1
        for k, name in enumerate(g.dyads):
            fill.append(f"R[{r}, jj] = {g.joint(name)}mg")
            copies.append([f"M{k}[{m}i, j0 + jj] = R[{r}, jj]"])
            r += 1
    trig_args = [f"C{k}" for k in range(len(g.cranks))]
    outputs = kernel_outputs(plan, order, modes, joints)
    args = ", ".join(["lo", "hi", "ns", "S", "U", *trig_args, *outputs])
    out_lines = [
        f"# generated by linkwright.engine.compile (generator {GENERATOR_VERSION}): do not edit",
        "import math",
        "",
        "import numba",
        "import numpy as np",
        "",
        "",
        # A serial function over a range of mechanisms, released from the GIL: the caller
        # runs ranges on threads. numba's own parallel loop would compile the whole body a
        # second time with its parallel passes (three times the compile time in all).
        '@numba.njit(cache=True, error_model="numpy", nogil=True, boundscheck=False)',
        f"def kernel({args}):",
        "    nan = np.nan",
        f"    R = np.empty(({max(r, 1)}, {BLOCK}))",
        "    for i in range(lo, hi):",
    ]
    out_lines += [f"        s{c} = S[i, {c}]" for c in shape.batched.values()]
    out_lines += [f"        u{c} = U[{c}]" for c in shape.uniform.values()]
    out_lines += ["        " + line for line in g.hoisted]
    pad = "        "
    if modes:
        count = 2 ** len(g.dyads)
        last = len(g.dyads) - 1
        out_lines.append(f"        for m in range({count}):")
        # itertools.product's order over (1, −1) per dyad, as continuation.every_configuration.
        out_lines += [
            f"            g{k} = 1.0 - 2.0 * ((m >> {last - k}) & 1)" for k in range(len(g.dyads))
        ]
        pad = "            "
    out_lines += [
        pad + f"for j0 in range(0, ns, {BLOCK}):",
        pad + f"    nb = min({BLOCK}, ns - j0)",
        pad + "    for jj in range(nb):",
        pad + "        j = j0 + jj",
    ]
    out_lines += [pad + "        " + line for line in body + fill]
    for copy in copies:
        out_lines.append(pad + "    for jj in range(nb):")
        out_lines += [pad + "        " + line for line in copy]
    return "\n".join(out_lines) + "\n"


class ScalarProbe:
    """A Names that records the scalars a plan's fragments read."""

    order = 2

    def __init__(self, dim: int) -> None:
        self.dim = dim
        self.used: list[str] = []

    def joint(self, name: str) -> str:
        return "j_"

    def scalar(self, p: Param) -> str:
        if isinstance(p, str):
            self.used.append(p)
        return "0.0"

    def point(self, key: str) -> tuple[str, ...]:
        return tuple(self.scalar(f"{key}[{c}]") for c in range(self.dim))

    def sign(self, step_name: str, key: str) -> str:
        return self.scalar(key)

    def trig(self, step: Any) -> tuple[str, str]:
        # The phase is read in the kernel where it is turned per mechanism (compile's _trig).
        self.scalar(step.phase)
        return "0.0", "0.0"

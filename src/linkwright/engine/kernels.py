"""Compiled position kernels for the two hottest cases: planar and spherical four-bars.

The construction plan (:mod:`linkwright.engine.plan`) evaluates any linkage as a sequence of
whole-array NumPy steps; each step allocates its temporaries, so a batch of n mechanisms ×
samples inputs streams through memory a few dozen times. These kernels place A, B and P of a
four-bar in one pass per sample, writing only the results (or P alone, for work that needs only
the coupler curves), with the formulas and conventions of
the plan's steps (Crank, DyadRRR, Rigid; SphereCrank, SphereDyad, SphereRigid):

- planar: A = A0 + crank·(cos θ, sin θ); B = circle(A, coupler) ∩ circle(B0, rocker) on the
  branch sign((B0 − A) × (B − A)) = assembly; P = A + u·e + v·perp(e), e the unit vector A→B.
- spherical (paper 000's frame): A0 = (1, 0, 0), B0 = (cos a1, sin a1, 0),
  A = (cos a2, sin a2 cos θ, sin a2 sin θ); B on the coupler and rocker arcs on the branch
  sign((A × B0)·B) = assembly; P at arc ``point_arc`` from A and angle ``point_angle`` = BAP
  about +OA.

Where the dyad does not close (its margin, sin² of the angle at A, below ``-ASSEMBLY_TOL``) all
three joints are NaN, as in :class:`linkwright.engine.Motion`. Positions only: velocities and
accelerations still come from :func:`linkwright.mechanisms.solve`.

numba is optional. :func:`available` says whether the kernels are compiled; without numba the
same loops run as plain Python (correct, but only fit for a handful of samples).
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.engine.kernel_loops import (
    CHUNK,
    STREAMING,
    planar_kernel,
    planar_motion_kernel,
    spherical_kernel,
)
from linkwright.engine.plan import ASSEMBLY_TOL, SINGULAR_MARGIN, SINGULAR_SIN

__all__ = [
    "KernelInputError",
    "available",
    "compiled",
    "fourbar_coupler_points",
    "fourbar_motion",
    "fourbar_positions",
    "positions",
    "prepared_fourbar",
    "spherical_fourbar_coupler_points",
    "spherical_fourbar_positions",
]

Array = NDArray[np.float64]
Triple = tuple[Array, Array, Array]


# The planar position kernel writes outputs larger than this (about a last-level cache's share)
# with streaming stores: a plain store first reads its cache line from memory, so a kernel
# writing far more than the caches hold runs at the copy bandwidth; a streaming store does not,
# and runs at the store bandwidth (1.6x faster for case (a) of bench/run.py). Smaller outputs
# stay in the caches for whoever reads them next.
STREAM_BYTES = 8 * 2**20


def _streams(*outputs: Array) -> bool:
    """Whether a kernel writes ``outputs`` with streaming stores: large enough, and aligned as
    a 16-byte store needs (NumPy's own arrays always are; a view from elsewhere may not be)."""
    stored = [a for a in outputs if a.size]
    return sum(a.nbytes for a in stored) > STREAM_BYTES and all(
        a.ctypes.data % 16 == 0 for a in stored
    )


class KernelInputError(ValueError):
    """Arguments a kernel cannot take (names the argument and the problem)."""


_KERNELS: dict[tuple[Any, bool, bool], Callable[..., Any]] = {}


def _numba() -> Any | None:
    try:
        import numba
    except ImportError:
        return None
    return numba


def available() -> bool:
    """Whether numba is installed, so that the kernels run compiled.

    Without it they still give the same numbers, interpreted (about a thousand times slower).

    Examples
    --------
    >>> isinstance(available(), bool)
    True
    """
    return _numba() is not None


def compiled(
    plain: Callable[..., Any],
    parallel: bool = True,
    reassociate: bool = False,
    helpers: tuple[Callable[..., Any], ...] = (),
) -> Callable[..., Any]:
    """``plain`` compiled by numba (cached on disk, so a later process pays no compile), or
    ``plain`` itself without numba. A loop over ``prange`` in ``plain``'s module runs on all
    threads when ``parallel``; that module defines ``prange = range`` for the interpreted case.
    ``reassociate`` lets LLVM reorder sums (so it can vectorise reductions): results then differ
    from the interpreted ones in the last bits. NaN and infinity keep their meaning either way.

    ``helpers`` are plain functions of the same module that ``plain`` calls. The compiled
    ``plain`` calls their compiled forms, inlined (so that loops calling them still vectorise):
    a helper's ``numba_form(numba)``, where it has one (for what only LLVM can say, such as a
    streaming store), or the helper compiled. The module itself keeps the plain functions, so
    the interpreted path never meets a compiled object.
    """
    key = (plain, parallel, reassociate)
    if key not in _KERNELS:
        numba = _numba()
        if numba is None:
            _KERNELS[key] = plain
        else:
            # The names the compiled loops resolve as globals, in a namespace of their own.
            namespace = dict(plain.__globals__, prange=numba.prange)
            for helper in helpers:
                form = getattr(helper, "numba_form", None)
                namespace[helper.__name__] = (
                    form(numba)
                    if form is not None
                    else numba.njit(cache=True, inline="always", error_model="numpy")(helper)
                )
            function = types.FunctionType(
                plain.__code__, namespace, plain.__name__, plain.__defaults__, plain.__closure__
            )
            # numba's disk cache tells functions apart by name and bytecode, not by options:
            # without a name of its own, the first variant compiled (serial, say) would be
            # loaded for every other (parallel) from then on.
            variant = ("parallel" if parallel else "serial") + (
                "_reassociate" if reassociate else ""
            )
            function.__qualname__ = f"{plain.__qualname__}.{variant}"
            fastmath = {"reassoc", "contract"} if reassociate else False
            # NumPy's error model: a division by zero at a sample that cannot close gives inf or
            # NaN (masked by ``bad``) as it does interpreted, instead of raising mid-batch.
            _KERNELS[key] = numba.njit(
                cache=True, fastmath=fastmath, parallel=parallel, error_model="numpy"
            )(function)
    return _KERNELS[key]


def _kernel(name: str, parallel: bool = True) -> Any:
    # A batch of at most one chunk runs serially: starting threads costs more than it saves.
    kernels: dict[str, Callable[..., None]] = {
        "planar": planar_kernel,
        "planar-motion": planar_motion_kernel,
        "sphere": spherical_kernel,
    }
    return compiled(kernels[name], parallel, helpers=STREAMING)


def _theta(theta: ArrayLike) -> tuple[Array, Array]:
    t = np.asarray(theta, dtype=float)
    if t.ndim != 1:
        raise KernelInputError(f"theta: must have shape (samples,), got {t.shape}")
    if not np.all(np.isfinite(t)):
        raise KernelInputError("theta: input angles must be finite")
    # One sincos per sample, shared by every mechanism of the batch.
    return np.ascontiguousarray(np.cos(t)), np.ascontiguousarray(np.sin(t))


# The columns of the packed parameters each kernel reads (one row per mechanism).
PLANAR_FIELDS = (("A0", 2), ("B0", 2), ("crank", 1), ("coupler", 1), ("rocker", 1), ("u", 1),
                 ("v", 1), ("assembly", 1))  # fmt: skip
SPHERE_FIELDS = (("frame", 1), ("crank", 1), ("coupler", 1), ("rocker", 1), ("point_arc", 1),
                 ("point_angle", 1), ("assembly", 1))  # fmt: skip


def _pack(fields: tuple[tuple[str, int], ...], values: tuple[ArrayLike, ...]) -> Array:
    """The parameters of n mechanisms as one (n, columns) array, each broadcast to n: a field of
    width 1 is a value or (n,) values, one of width 2 a point [x, y] or (n, 2) points. One
    array, checked at once, makes a single call cheap (few arguments, few NumPy calls)."""
    arrays = []
    sizes = set()
    for (name, width), value in zip(fields, values, strict=True):
        a = np.asarray(value, dtype=float)
        if width == 2 and a.shape[-1:] != (2,):
            raise KernelInputError(
                f"{name}: must be a point [x, y] or an (n, 2) array, got {a.shape}"
            )
        per = a.shape[:-1] if width == 2 else a.shape
        if len(per) > 1:
            raise KernelInputError(f"{name}: must be one value per mechanism, got shape {a.shape}")
        if per and per[0] != 1:
            sizes.add(per[0])
        arrays.append(a.reshape(-1, width))
    if len(sizes) > 1:
        raise KernelInputError(f"per-mechanism arrays disagree on n: {sorted(sizes)}")
    n = sizes.pop() if sizes else 1
    columns = np.cumsum([0] + [width for _, width in fields])
    packed = np.empty((n, columns[-1]))
    for a, start, stop in zip(arrays, columns[:-1], columns[1:], strict=True):
        packed[:, start:stop] = a
    finite = np.isfinite(packed).all(axis=0)
    if not finite.all():
        column = int(np.argmin(finite))
        name = fields[int(np.searchsorted(columns, column, side="right")) - 1][0]
        raise KernelInputError(f"{name}: must be finite")
    return packed


def _field(packed: Array, fields: tuple[tuple[str, int], ...], name: str) -> Array:
    """One field's column(s) of packed parameters (a view)."""
    start = 0
    for field, width in fields:
        if field == name:
            return packed[:, start] if width == 1 else packed[:, start : start + width]
        start += width
    raise KeyError(name)


def _check_signs(assembly: Array) -> None:
    if not np.all(np.abs(assembly) == 1):
        raise KernelInputError("assembly: must be 1 or -1")


def _output(out: Array | None, name: str, shape: tuple[int, ...]) -> Array:
    if out is None:
        return np.empty(shape)
    if not (
        isinstance(out, np.ndarray)
        and out.shape == shape
        and out.dtype == np.float64
        and out.flags.c_contiguous
        and out.flags.writeable
    ):
        raise KernelInputError(
            f"out: {name} must be a writeable C-contiguous float64 array of shape {shape}"
        )
    return out


def _outputs(out: Triple | None, shape: tuple[int, ...]) -> Triple:
    if out is None:
        return np.empty(shape), np.empty(shape), np.empty(shape)
    if len(out) != 3:
        raise KernelInputError("out: must be three arrays (A, B, P)")
    A, B, P = (_output(a, name, shape) for name, a in zip("ABP", out, strict=True))
    return A, B, P


def _position_outputs(out: Any, shape: tuple[int, ...], coupler_only: bool) -> tuple[Any, ...]:
    """What a position kernel takes last: whether it stores A and B, and A, B, P. Where only P
    is asked for, A and B are empty placeholders (nothing is written to them), and ``out`` is
    P's array alone."""
    if coupler_only:
        unstored = np.empty((0, 0, shape[-1]))
        return False, unstored, unstored, _output(out, "P", shape)
    return (True, *_outputs(out, shape))


def _planar_position_outputs(
    out: Any, shape: tuple[int, ...], coupler_only: bool
) -> tuple[Any, ...]:
    """:func:`_position_outputs` for the planar kernel, which also takes whether it streams."""
    store_ab, A, B, P = _position_outputs(out, shape, coupler_only)
    return store_ab, _streams(A, B, P), A, B, P


def _planar_args(
    A0: ArrayLike, B0: ArrayLike, crank: ArrayLike, coupler: ArrayLike, rocker: ArrayLike,
    u: ArrayLike, v: ArrayLike, assembly: ArrayLike, theta: ArrayLike, out: Any, order: int = 0,
    coupler_only: bool = False,
) -> tuple[Any, ...]:  # fmt: skip
    """The planar kernel's arguments, checked and broadcast, its outputs last (three for
    positions, after whether A and B are stored; nine, grouped as positions, velocities,
    accelerations, for ``order`` 2)."""
    params = _pack(PLANAR_FIELDS, (A0, B0, crank, coupler, rocker, u, v, assembly))
    for k in ("crank", "coupler", "rocker"):
        if np.any(_field(params, PLANAR_FIELDS, k) <= 0):
            raise KernelInputError(f"{k}: must be a positive length")
    _check_signs(_field(params, PLANAR_FIELDS, "assembly"))
    cos_t, sin_t = _theta(theta)
    shape = (params.shape[0], cos_t.shape[0], 2)
    head = (params, cos_t, sin_t, ASSEMBLY_TOL)
    if order == 0:
        return (*head, *_planar_position_outputs(out, shape, coupler_only))
    if order != 2:
        raise KernelInputError(f"order: must be 0 (positions) or 2 (with derivatives), got {order}")
    groups = (None, None, None) if out is None else out
    if len(groups) != 3:
        raise KernelInputError("out: must be three triples (positions, velocities, accelerations)")
    outputs = [a for group in groups for a in _outputs(group, shape)]
    return (*head, SINGULAR_SIN, SINGULAR_MARGIN, *outputs)


def fourbar_positions(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Triple | None = None,
) -> Triple:
    """Joints A, B, P of n planar four-bars at the shared inputs θ, in one compiled pass.

    Conventions of :class:`linkwright.mechanisms.FourBar`. All samples of all mechanisms
    share ``theta``; the sines and cosines are taken once.

    Parameters
    ----------
    A0, B0 : ground pivots, shape (2,) or (n, 2).
    crank, coupler, rocker : link lengths (> 0), shape () or (n,).
    u, v : coupler point P in the frame with origin A and x-axis along A→B, shape () or (n,).
    assembly : sign((B0 − A) × (B − A)), ±1, shape () or (n,).
    theta : input angles (radians), shape (samples,).
    out : optional preallocated (A, B, P), each float64 C-contiguous (n, samples, 2).

    Returns
    -------
    A, B, P : arrays of shape (n, samples, 2); NaN (all three) where the dyad does not close.

    Examples
    --------
    The crank-rocker of :func:`linkwright.mechanisms.solve`'s example, P the coupler's midpoint
    lifted by 1; at θ = 0, A = (1, 0) and B = (4.625, 3.443744) (|AB| = 5, |B0B| = 3.5):

    >>> A, B, P = fourbar_positions([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0, np.pi])
    >>> B[0].round(6)
    array([[4.625   , 3.443744],
           [2.775   , 3.278624]])
    >>> P[0, 0].round(6)  # (1, 0) + 2.5·(0.725, 0.688749) + 1·(−0.688749, 0.725)
    array([2.123751, 2.446872])

    At θ = π, A = (−1, 0) is d = 5 from B0: B lies (25 − 12.25 + 25)/10 = 3.775 along A→B0 and
    √(25 − 3.775²) = 3.278624 to its left. A linkage that cannot assemble is NaN:

    >>> A, B, P = fourbar_positions([0, 0], [10, 0], 1, 2, 3, 0, 0, 1, [0.0])
    >>> A, B
    (array([[[nan, nan]]]), array([[[nan, nan]]]))
    """
    args = _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, out)
    _kernel("planar", parallel=args[0].shape[0] > CHUNK)(*args)
    return args[-3:]


def fourbar_coupler_points(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Array | None = None,
) -> Array:
    """P alone of :func:`fourbar_positions`, shape (n, samples, 2): a third of its stores, for
    work that needs only the coupler curves (descriptors, an atlas).

    ``out`` is an optional preallocated P, float64 C-contiguous (n, samples, 2).

    Examples
    --------
    >>> fourbar_coupler_points([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0]).round(6)
    array([[[2.123751, 2.446872]]])
    >>> fourbar_coupler_points([0, 0], [10, 0], 1, 2, 3, 0, 0, 1, [0.0])
    array([[[nan, nan]]])
    """
    args = _planar_args(
        A0, B0, crank, coupler, rocker, u, v, assembly, theta, out, coupler_only=True
    )
    _kernel("planar", parallel=args[0].shape[0] > CHUNK)(*args)
    P: Array = args[-1]
    return P


def fourbar_motion(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: tuple[Triple, Triple, Triple] | None = None,
) -> tuple[Triple, Triple, Triple]:
    """Positions, velocities and accelerations (d/dθ, d²/dθ²) of A, B, P in one compiled pass.

    Arguments as :func:`fourbar_positions`. The derivatives are those of the plan's steps: the
    differentiated loop constraints of the dyad, (B − A)·(B′ − A′) = 0 and (B − B0)·B′ = 0, and
    their derivatives, solved by Cramer's rule. They are NaN where the plan's are: where the
    linkage does not assemble, and at a singular position (B − A parallel to B − B0, a limit
    position of the input), where they do not exist.

    Returns
    -------
    (A, B, P), (A′, B′, P′), (A″, B″, P″) : each array of shape (n, samples, 2).

    Examples
    --------
    At θ = 0 the crank-rocker of :func:`fourbar_positions` has A′ = (0, 1), and B′ is the
    solution of (3.625, 3.443744)·B′ = 3.443744 (the coupler's row) and (0.625, 3.443744)·B′ = 0
    (the rocker's): their difference gives 3·B′x = 3.443744, and B′y = −0.625·B′x/3.443744 =
    −0.625/3.

    >>> (A, B, P), (dA, dB, dP), _ = fourbar_motion([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0])
    >>> dA[0, 0], dB[0, 0].round(6)
    (array([0., 1.]), array([ 1.147915, -0.208333]))
    """
    args = _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, out, order=2)
    _kernel("planar-motion", parallel=args[0].shape[0] > CHUNK)(*args)
    return args[-9:-6], args[-6:-3], args[-3:]


def prepared_fourbar(
    A0: ArrayLike,
    B0: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    order: int = 0,
) -> Callable[[], Any]:
    """A zero-argument call that recomputes :func:`fourbar_positions` (``order`` 0) or
    :func:`fourbar_motion` (``order`` 2) for fixed arguments.

    Everything that does not change between calls (checks, broadcasting, the sines and cosines
    of θ, the output arrays) is done once here; each call is then one compiled pass, without
    threads (starting them costs more than one short curve). This is the latency path: an
    interactive tool redrawing one curve as a dimension is dragged re-prepares only when the
    dimension changes. The returned arrays are overwritten by the next call.

    Examples
    --------
    >>> curve = prepared_fourbar([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0, np.pi])
    >>> A, B, P = curve()
    >>> B[0].round(6)
    array([[4.625   , 3.443744],
           [2.775   , 3.278624]])
    >>> motion = prepared_fourbar([0, 0], [4, 0], 1, 5, 3.5, 2.5, 1.0, 1, [0.0], order=2)
    >>> motion()[1][1][0, 0].round(6)
    array([ 1.147915, -0.208333])
    """
    args = _planar_args(A0, B0, crank, coupler, rocker, u, v, assembly, theta, None, order)
    kernel = _kernel("planar" if order == 0 else "planar-motion", parallel=args[0].shape[0] > CHUNK)
    result = args[-3:] if order == 0 else (args[-9:-6], args[-6:-3], args[-3:])

    def run() -> Any:
        kernel(*args)
        return result

    return run


def spherical_fourbar_positions(
    frame: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    point_arc: ArrayLike,
    point_angle: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Triple | None = None,
) -> Triple:
    """Joints A, B, P (unit vectors) of n spherical four-bars at the shared inputs θ.

    Conventions of :class:`linkwright.mechanisms.SphericalFourBar` (paper 000's frame; all
    angles in radians). The dyad's Gram determinant is taken in its product form, as in
    :func:`linkwright.geometry.sphere.gram`, so a limit position stays a limit position.

    Parameters
    ----------
    frame, crank, coupler, rocker : arcs a1..a4, each in (0, π), shape () or (n,).
    point_arc, point_angle : arc AP and angle BAP about +OA, shape () or (n,).
    assembly : sign((A × B0)·B), ±1, shape () or (n,).
    theta : input angles (radians), shape (samples,).
    out : optional preallocated (A, B, P), each float64 C-contiguous (n, samples, 3).

    Returns
    -------
    A, B, P : arrays of shape (n, samples, 3); NaN (all three) where the dyad does not close.

    Examples
    --------
    Paper 000's Fig. 6 crank-rocker at θ = 0 (as :class:`~linkwright.mechanisms.SphericalFourBar`
    gives it):

    >>> fig6 = np.radians([40, 20, 45, 35, 50, 130])
    >>> A, B, P = spherical_fourbar_positions(*fig6, 1, [0.0])
    >>> B.round(6)
    array([[[0.509774, 0.666849, 0.543546]]])

    Every arc is kept: |AB| = 45°, |B0B| = 35°.

    >>> b0 = np.array([np.cos(fig6[0]), np.sin(fig6[0]), 0.0])
    >>> np.degrees(np.arccos([A[0, 0] @ B[0, 0], b0 @ B[0, 0]])).round(9)
    array([45., 35.])

    A linkage that cannot assemble is NaN:

    >>> spherical_fourbar_positions(*np.radians([90, 10, 20, 30, 0, 0]), 1, [0.0])[1]
    array([[[nan, nan, nan]]])
    """
    spherical = (frame, crank, coupler, rocker, point_arc, point_angle, assembly)
    joints: Triple = _spherical_run(*spherical, theta, out, coupler_only=False)
    return joints


def spherical_fourbar_coupler_points(
    frame: ArrayLike,
    crank: ArrayLike,
    coupler: ArrayLike,
    rocker: ArrayLike,
    point_arc: ArrayLike,
    point_angle: ArrayLike,
    assembly: ArrayLike,
    theta: ArrayLike,
    out: Array | None = None,
) -> Array:
    """P alone of :func:`spherical_fourbar_positions`, shape (n, samples, 3): a third of its
    stores, for work that needs only the coupler curves (descriptors, an atlas).

    ``out`` is an optional preallocated P, float64 C-contiguous (n, samples, 3).

    Examples
    --------
    >>> fig6 = np.radians([40, 20, 45, 35, 50, 130])
    >>> P = spherical_fourbar_coupler_points(*fig6, 1, [0.0, 1.0])
    >>> bool(np.array_equal(P, spherical_fourbar_positions(*fig6, 1, [0.0, 1.0])[2]))
    True
    >>> spherical_fourbar_coupler_points(*np.radians([90, 10, 20, 30, 0, 0]), 1, [0.0])
    array([[[nan, nan, nan]]])
    """
    spherical = (frame, crank, coupler, rocker, point_arc, point_angle, assembly)
    P: Array = _spherical_run(*spherical, theta, out, coupler_only=True)
    return P


def _spherical_run(
    frame: ArrayLike, crank: ArrayLike, coupler: ArrayLike, rocker: ArrayLike,
    point_arc: ArrayLike, point_angle: ArrayLike, assembly: ArrayLike, theta: ArrayLike,
    out: Any, coupler_only: bool,
) -> Any:  # fmt: skip

    values = (frame, crank, coupler, rocker, point_arc, point_angle, assembly)
    params = _pack(SPHERE_FIELDS, values)
    for k in ("frame", "crank", "coupler", "rocker"):
        arc = _field(params, SPHERE_FIELDS, k)
        if np.any((arc <= 0) | (arc >= np.pi)):
            raise KernelInputError(f"{k}: a spherical link's arc must lie strictly in (0, π)")
    _check_signs(_field(params, SPHERE_FIELDS, "assembly"))
    cos_t, sin_t = _theta(theta)
    n = params.shape[0]
    outputs = _position_outputs(out, (n, cos_t.shape[0], 3), coupler_only)
    _kernel("sphere", parallel=n > CHUNK)(params, cos_t, sin_t, ASSEMBLY_TOL, *outputs)
    return outputs[-1] if coupler_only else outputs[1:]


def positions(mechanism: Any, theta: ArrayLike) -> dict[str, Array]:
    """A, B, P of a :class:`~linkwright.mechanisms.FourBar` or
    :class:`~linkwright.mechanisms.SphericalFourBar` through the kernels.

    The mechanism's batch shape must be () or (n,); the result has the shape of
    ``solve(mechanism, theta).positions`` for those joints: batch + (samples, 2 or 3).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar
    >>> pos = positions(FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5), [0.0])
    >>> pos["B"].round(6)
    array([[4.625   , 3.443744]])
    """
    # By the family's registered name, not by class: the engine sits below the mechanisms
    # layer and may not import it (the layer contract in pyproject.toml).
    family = getattr(mechanism, "family", None)
    if family not in ("fourbar", "spherical-fourbar"):
        raise KernelInputError(
            f"positions: kernels exist for FourBar and SphericalFourBar, "
            f"not {type(mechanism).__name__}"
        )
    batch = mechanism.batch_shape
    if len(batch) > 1:
        raise KernelInputError(f"positions: batch shape must be () or (n,), got {batch}")
    m = mechanism
    if family == "fourbar":
        A, B, P = fourbar_positions(
            m.A0, m.B0, m.crank, m.coupler, m.rocker, m.u, m.v, m.assembly, theta
        )
    else:
        A, B, P = spherical_fourbar_positions(
            m.frame, m.crank, m.coupler, m.rocker, m.point_arc, m.point_angle, m.assembly, theta
        )
    if not batch:
        A, B, P = A[0], B[0], P[0]
    return {"A": A, "B": B, "P": P}

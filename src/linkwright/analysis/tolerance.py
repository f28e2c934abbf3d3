"""Tolerance analysis: how far the traced curve (and the output angle) can move when each
dimension is off by up to ± its tolerance, to first order, with a seeded Monte-Carlo check.

The numbers toleranced are the family's parameter vector
(:func:`linkwright.mechanisms.parameters.parameter_vector`): by default every link length,
pivot and point coordinate and spherical arc (and a composed spherical linkage's ground axes'
longitude and latitude); a gear ratio and the angles of a crank's phase or a guide's direction
only where named. At each input sample θ the traced point P moves by ∂P/∂xi per unit of
parameter i; only its component along the curve's normal n (in the plane: the tangent dP/dθ
turned by 90°; on the sphere: P × dP/dθ) widens the curve, the tangential part being a shift in
timing. The band's half-width is then

- ``half_width`` = Σ |∂P/∂xi · n| ti, the worst case of independent tolerances ±ti (reached, to
  first order, at a corner of the tolerance box),
- ``std`` = (Σ (∂P/∂xi · n)² ti²/3)^½, the standard deviation when each error is uniform on
  [−ti, ti],

and the same for the output angle (four-bars, planar and spherical), at fixed θ.

Derivatives. The engine carries derivatives with respect to the input only. Complex steps do not
pass through its steps (branch signs, ``arctan2``, ``np.where`` masks drop the imaginary part),
and an analytic route would need every step kind's partial derivatives with respect to its
numbers. So the sensitivities are a fourth-order central difference,
(−f(x+2h) + 8f(x+h) − 8f(x−h) + f(x−2h))/12h with h = 1e-3 of the linkage's size (1e-3 rad for
arcs and angles): truncation error O(h⁴) ≈ 1e-12 relative and rounding ≈ 1e-16/h ≈ 1e-13, so
far below any tolerance that matters, all 4k + 1 linkages evaluated in one batch.
``derivative_error`` reports the gap to the second-order estimate (an upper bound on the error,
in the band's units) so a caller sees where it is not small: next to a limit position, where the
band itself is not first-order.

Cost: ``samples`` ≤ :data:`MAX_SAMPLES`, Monte Carlo ``n`` ≤ :data:`MAX_TRIALS` with
n · samples ≤ :data:`MAX_EVALUATIONS`, checked before any work.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from linkwright.engine import Motion
from linkwright.engine.arcs import InputArcs
from linkwright.mechanisms import FourBar, SphericalFourBar, input_range, solve
from linkwright.mechanisms.base import Mechanism
from linkwright.mechanisms.parameters import ParameterError, parameter_vector

__all__ = [
    "MAX_EVALUATIONS",
    "MAX_SAMPLES",
    "MAX_TRIALS",
    "MonteCarlo",
    "ToleranceBand",
    "ToleranceError",
    "monte_carlo",
    "tolerance_band",
]

Array = NDArray[np.float64]
MAX_SAMPLES = 4096
MAX_TRIALS = 20_000
MAX_EVALUATIONS = 4_000_000
STEP = 1e-3
# Where the inputs do not turn fully, this fraction of each end of the arc is left out: at a limit
# position ∂P/∂x is infinite (a square-root singularity) and no first-order band exists.
LIMIT_MARGIN = 0.02
_DEFAULT_KINDS = frozenset({"length", "coordinate", "arc"})


class ToleranceError(ValueError):
    """Bad tolerances, samples or counts, or a linkage that cannot be analysed (one line)."""


@dataclass(frozen=True)
class ToleranceBand:
    """The first-order band of a linkage's traced curve (and output angle) under tolerances.

    Arrays are per input sample (N) unless noted; k is the number of toleranced parameters.

    Attributes
    ----------
    point : the traced joint's name.
    names : (k,) the toleranced parameters, ``tolerances`` (k,) their ± (absolute).
    inputs : (N,) radians.
    curve : (N, 2) or (N, 3) the nominal traced point; ``normal`` the unit normal there.
    sensitivity : (N, k) ∂P/∂xi · n.
    half_width, std : (N,) the worst-case and standard-deviation half-widths (module docstring).
    output_sensitivity, output_half_width, output_std : likewise for the output angle
        (radians), None where the family has none.
    derivative_error : (N,) bound on the derivatives' error, in units of ``half_width``.
    """

    point: str
    names: tuple[str, ...]
    tolerances: Array
    inputs: Array
    curve: Array
    normal: Array
    sensitivity: Array
    half_width: Array
    std: Array
    output_sensitivity: Array | None
    output_half_width: Array | None
    output_std: Array | None
    derivative_error: Array


@dataclass(frozen=True)
class MonteCarlo:
    """Seeded Monte-Carlo deviations: ``normal`` (n, N) the traced point's displacement along
    the nominal normal, ``output`` (n, N) the output angle's (radians), None where none; trials
    where a perturbed linkage does not assemble at a sample are NaN there and counted in
    ``failed`` (n,)."""

    normal: Array
    output: Array | None
    failed: NDArray[np.int64]


def _tolerances(
    mech: Mechanism, tol: float | Mapping[str, float], relative: bool
) -> tuple[list[int], Array, Array]:
    vector = parameter_vector(mech)
    x = np.asarray(vector.to_vector(mech), dtype=float)
    if x.ndim != 1:
        raise ToleranceError("tolerance analysis takes one linkage, not a batch")
    size = float(np.max(np.asarray(mech.scale)))
    if isinstance(tol, Mapping):
        picked = []
        for name, value in tol.items():
            try:
                picked.append((vector.index(name), float(value)))
            except ParameterError as exc:
                raise ToleranceError(str(exc)) from None
    else:
        picked = [
            (i, float(tol))
            for i, p in enumerate(vector.parameters)
            if p.kind in _DEFAULT_KINDS or (p.kind == "angle" and p.field in vector.axes)
        ]
    if not picked:
        raise ToleranceError(f"{vector.family} has no parameter to tolerance")
    index = [i for i, _ in picked]
    t = np.array([v for _, v in picked])
    if not np.all(np.isfinite(t)) or np.any(t < 0):
        raise ToleranceError("tolerances must be finite and not negative")
    if relative:
        kinds = [vector.parameters[i].kind for i in index]
        # A coordinate's value depends on where the origin is: relative to the linkage's size.
        base = np.array(
            [
                size if k == "coordinate" else 1.0 if k == "angle" else abs(x[i])
                for k, i in zip(kinds, index, strict=True)
            ]
        )
        t = t * base
    steps = np.array(
        [
            STEP * (size if vector.parameters[i].kind in ("length", "coordinate") else 1.0)
            for i in index
        ]
    )
    return index, t, steps


def _inputs(mech: Mechanism, samples: int) -> Array:
    arcs: InputArcs = input_range(mech)
    if bool(np.all(arcs.full)):
        period = float(np.max(np.asarray(arcs.period)))
        return np.linspace(0.0, period, samples, endpoint=False)
    if bool(np.all(arcs.never)):
        raise ToleranceError("the linkage cannot be assembled at any input")
    lo, hi = float(np.ravel(arcs.lo)[0]), float(np.ravel(arcs.hi)[0])
    pad = LIMIT_MARGIN * (hi - lo)
    return np.linspace(lo + pad, hi - pad, samples)


def _check_samples(samples: int) -> int:
    n = int(samples)
    if not 2 <= n <= MAX_SAMPLES:
        raise ToleranceError(f"samples must be 2 to {MAX_SAMPLES}, got {samples!r}")
    return n


def _traced(mech: Mechanism) -> str:
    traced = mech.plan.traced
    if not traced:
        raise ToleranceError(f"{mech.family} traces no point")
    return str(traced[0])


def _output(mech: Mechanism, motion: Motion) -> Array | None:
    if isinstance(mech, FourBar | SphericalFourBar):
        from linkwright.analysis.planar import output_angle

        return output_angle(mech, motion)
    return None


def _normal(curve: Array, velocity: Array) -> Array:
    if curve.shape[-1] == 2:
        n = np.stack([-velocity[..., 1], velocity[..., 0]], axis=-1)
    else:
        n = np.cross(curve, velocity)
    size = np.linalg.norm(n, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out: Array = n / size
    return out


def tolerance_band(
    mech: Mechanism,
    tol: float | Mapping[str, float],
    *,
    relative: bool = False,
    samples: int = 360,
    inputs: Array | None = None,
) -> ToleranceBand:
    """The first-order band of ``mech``'s traced curve under tolerances (module docstring).

    Parameters
    ----------
    tol : one ± for every default parameter, or parameter name → ± (only those toleranced).
    relative : tolerances are fractions: of each length's or arc's value, of the linkage's
        size (its largest length) for coordinates, and of a radian for an axis's longitude or
        latitude.
    samples : input samples over the full turn, or over the first input arc less 2 % at each
        end where the input rocks; ``inputs`` (radians) overrides them.

    Raises
    ------
    ToleranceError : bad tolerances or samples, a batch, or a nominal linkage that does not
        assemble (or is singular) at a sample.
    """
    index, t, steps = _tolerances(mech, tol, relative)
    vector = parameter_vector(mech)
    names = tuple(vector.names[i] for i in index)
    if inputs is None:
        theta = _inputs(mech, _check_samples(samples))
    else:
        theta = np.asarray(inputs, dtype=float).ravel()
        _check_samples(theta.size)
        if not np.all(np.isfinite(theta)):
            raise ToleranceError("inputs must be finite")
    x = vector.to_vector(mech)
    k = len(index)
    offsets = np.array([-2.0, -1.0, 1.0, 2.0])
    batch = np.repeat(x[None, :], 1 + 4 * k, axis=0)
    for j, i in enumerate(index):
        batch[1 + 4 * j : 5 + 4 * j, i] += offsets * steps[j]
    family = vector.from_vector(mech, batch)
    motion = solve(family, theta, order=1)
    point = _traced(mech)
    pos = motion.positions[point]  # (1 + 4k, N, d)
    if not bool(np.all(motion.valid[0])) or not bool(np.all(motion.regular[0])):
        bad = int(np.flatnonzero(~(motion.valid[0] & motion.regular[0]))[0])
        raise ToleranceError(
            f"the linkage does not assemble regularly at input {np.degrees(theta[bad]):.6g}°: "
            "no band there"
        )
    if not bool(np.all(motion.valid)):
        raise ToleranceError(
            "a step of the derivatives leaves the linkage unassembled: a sample lies within "
            f"{STEP:g} of a limit position (choose inputs away from it)"
        )
    curve = pos[0]
    assert motion.velocities is not None  # solved with order=1
    normal = _normal(curve, motion.velocities[point][0])
    output = _output(mech, motion)

    def derivatives(f: Array) -> tuple[Array, Array]:
        """Fourth- and second-order central differences of f (1 + 4k, N, ...) → (k, N, ...)."""
        f = f[1:].reshape((k, 4) + f.shape[1:])
        h = steps.reshape((k,) + (1,) * (f.ndim - 2))
        four = (f[:, 0] - 8 * f[:, 1] + 8 * f[:, 2] - f[:, 3]) / (12 * h)
        two = (f[:, 2] - f[:, 1]) / (2 * h)
        return four, np.abs(four - two)

    dp, err = derivatives(pos)
    sens = np.einsum("knd,nd->nk", dp, normal)
    half = np.abs(sens) @ t
    std = np.sqrt((sens**2) @ (t**2) / 3.0)
    derr = np.linalg.norm(err, axis=-1).T @ t
    o_sens = o_half = o_std = None
    if output is not None:
        # The output angle is wrapped to (−π, π]: differences are taken on the circle.
        wrapped = output[0] + np.angle(np.exp(1j * (output - output[0])))
        o_d, _ = derivatives(wrapped)
        o_sens = o_d.T
        o_half = np.abs(o_sens) @ t
        o_std = np.sqrt((o_sens**2) @ (t**2) / 3.0)
    if not (np.all(np.isfinite(half)) and np.all(np.isfinite(normal))):
        raise ToleranceError(
            "the traced point stands still at a sample (a cusp): its normal, and the band's "
            "width across the curve, are undefined there"
        )
    return ToleranceBand(
        point=point,
        names=names,
        tolerances=t,
        inputs=theta,
        curve=curve,
        normal=normal,
        sensitivity=sens,
        half_width=half,
        std=std,
        output_sensitivity=o_sens,
        output_half_width=o_half,
        output_std=o_std,
        derivative_error=derr,
    )


def monte_carlo(
    mech: Mechanism, band: ToleranceBand, n: int, *, seed: int = 0, corners: bool = False
) -> MonteCarlo:
    """Deviations of ``n`` linkages drawn uniformly in the band's tolerance box (or at its
    corners, each sign ±1 with probability ½, where ``corners``), solved at the band's inputs."""
    trials = int(n)
    if not 1 <= trials <= MAX_TRIALS or trials * band.inputs.size > MAX_EVALUATIONS:
        raise ToleranceError(
            f"Monte Carlo takes 1 to {MAX_TRIALS} trials and at most {MAX_EVALUATIONS} "
            f"linkage-samples in all; got {n!r} trials × {band.inputs.size} samples"
        )
    vector = parameter_vector(mech)
    index = [vector.index(name) for name in band.names]
    rng = np.random.default_rng(seed)
    if corners:
        u = rng.choice([-1.0, 1.0], size=(trials, len(index)))
    else:
        u = rng.uniform(-1.0, 1.0, size=(trials, len(index)))
    x = np.repeat(vector.to_vector(mech)[None, :], trials, axis=0)
    x[:, index] += u * band.tolerances
    motion = solve(vector.from_vector(mech, x), band.inputs, order=0)
    moved = motion.positions[band.point] - band.curve
    normal = np.einsum("tnd,nd->tn", moved, band.normal)
    output = _output(mech, motion)
    out = None
    if output is not None:
        nominal = _output(mech, solve(mech, band.inputs, order=0))
        assert nominal is not None  # the same mechanism gave an output above
        out = np.angle(np.exp(1j * (output - nominal)))
    failed = np.sum(~motion.valid, axis=-1).astype(np.int64)
    return MonteCarlo(normal=normal, output=out, failed=failed)

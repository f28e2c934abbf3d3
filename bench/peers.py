"""Peer baselines for the engine benchmark: pylinkage's numba four-bar on bench/run.py's linkages.

pylinkage (https://github.com/HugoFara/pylinkage, 1.3.0) simulates a linkage by stepping its
crank through a constant angular increment and placing every other joint from the previous
step: an ``RRRDyad`` takes the circle–circle intersection *nearest to its previous position*
(hysteresis, not a branch sign), a ``FixedDyad`` sits at a distance and angle from the line
between its two anchors. Two entry points are used, each timed without its set-up:

* ``Ensemble.simulate`` — pylinkage's batched API: one topology, per-member constraints and
  initial positions, one numba ``simulate`` call per member;
* ``Linkage.step_fast`` — its fastest single-linkage path (numba ``simulate`` plus syncing the
  joint objects before and after).

Mapping of ``linkwright.mechanisms.FourBar`` onto pylinkage, joint by joint: A0, B0 →
``Ground``; A → ``Crank`` about A0; B → ``RRRDyad(A, B0, coupler, rocker)``; P →
``FixedDyad(A, B, hypot(u, v), atan2(v, u))`` (angle measured from A→B, counter-clockwise, as
linkwright's (u, v) frame with v to the left).

Inputs: pylinkage's crank advances *before* each recorded step, so a uniform grid θ₀, θ₀ + Δ,
… is reproduced by starting the crank at θ₀ − Δ with angular velocity Δ per step.

Assembly: the two circle–circle solutions are mirror images in the line A–B0, so any point
strictly on one side of that line is nearer to the solution on that side. B is seeded with
H = A(θ₀) + assembly · J(B0 − A(θ₀)) (J: rotation by +90°), for which
(B0 − A) × (H − A) = assembly · |B0 − A|² has linkwright's sign; the first step then picks
linkwright's assembly and hysteresis keeps it. That holds while the two assemblies stay
further apart than B moves in one step — always for the benchmark's Grashof crank-rockers,
whose assemblies never meet; a linkage that passes a dead centre or cannot assemble at some
input is not reproduced (pylinkage may change branch there, or stay NaN), so the peers refuse
nothing but promise agreement only for fully rotating cranks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib.metadata import version

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.mechanisms import FourBar

__all__ = [
    "EnsemblePeer",
    "PeerInputError",
    "SinglePeer",
    "build_ensemble",
    "build_single",
    "peer_versions",
    "pylinkage_ensemble",
    "pylinkage_single",
]

Positions = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]

# pylinkage's joint order in every linkage built here; trajectories are indexed by it.
_A, _B, _P = 2, 3, 4


class PeerInputError(ValueError):
    """Input the pylinkage peer cannot reproduce (not a FourBar, not a uniform input grid)."""


def peer_versions() -> dict[str, str]:
    """Versions of the peer packages (pylinkage and numba), for the benchmark's header."""
    return {name: version(name) for name in ("pylinkage", "numba")}


def _grid(theta: ArrayLike) -> tuple[NDArray[np.float64], float, float]:
    """theta as a checked uniform grid: (theta, first input, increment)."""
    t = np.asarray(theta, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise PeerInputError(f"theta must be 1-D with at least 2 inputs, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise PeerInputError("theta has non-finite inputs")
    step = (t[-1] - t[0]) / (t.size - 1)
    # pylinkage only turns its crank by a constant increment per step.
    if step == 0.0 or np.max(np.abs(np.diff(t) - step)) > 1e-12 * max(1.0, abs(step)):
        raise PeerInputError("theta must be uniformly spaced: pylinkage steps its crank evenly")
    return t, float(t[0]), float(step)


def _fourbar_arrays(mech: FourBar) -> tuple[tuple[int, ...], dict[str, NDArray[np.float64]]]:
    """Batch shape and the mechanism's parameters broadcast to it, flattened to (n, ...)."""
    if not isinstance(mech, FourBar):
        raise PeerInputError(f"the pylinkage peer models FourBar only, got {type(mech).__name__}")
    p = {k: np.asarray(v, dtype=float) for k, v in mech.params().items()}
    batch = np.broadcast_shapes(
        p["A0"].shape[:-1], p["B0"].shape[:-1],
        *(p[k].shape for k in ("crank", "coupler", "rocker", "u", "v", "assembly")),
    )  # fmt: skip
    n = math.prod(batch)
    flat = {
        k: np.broadcast_to(v, batch + ((2,) if k in ("A0", "B0") else ())).reshape(
            (n, 2) if k in ("A0", "B0") else (n,)
        )
        for k, v in p.items()
    }
    return batch, flat


def _initial_positions(p: dict[str, NDArray[np.float64]], start: float, step: float):
    """Joint positions (n, 5, 2) before pylinkage's first step (see the module docstring)."""
    A_prev = p["A0"] + p["crank"][:, None] * np.array(
        [math.cos(start - step), math.sin(start - step)]
    )
    A_first = p["A0"] + p["crank"][:, None] * np.array([math.cos(start), math.sin(start)])
    d = p["B0"] - A_first
    hint = A_first + p["assembly"][:, None] * np.stack((-d[:, 1], d[:, 0]), -1)
    return np.stack((p["A0"], p["B0"], A_prev, hint, A_prev), axis=1)


def _linkage(A0, B0, crank, coupler, rocker, u, v, A_prev, hint, step):
    """One pylinkage Linkage (joints A0, B0, A, B, P in that order)."""
    from pylinkage.actuators import Crank
    from pylinkage.components import Ground
    from pylinkage.dyads import FixedDyad, RRRDyad
    from pylinkage.simulation import Linkage

    g_a0 = Ground(float(A0[0]), float(A0[1]), name="A0")
    g_b0 = Ground(float(B0[0]), float(B0[1]), name="B0")
    a = Crank(
        anchor=g_a0,
        radius=float(crank),
        angular_velocity=step,
        initial_angle=math.atan2(A_prev[1] - A0[1], A_prev[0] - A0[0]),
        name="A",
    )
    b = RRRDyad(
        a.output, g_b0, float(coupler), float(rocker), x=float(hint[0]), y=float(hint[1]), name="B"
    )
    pt = FixedDyad(a.output, b, math.hypot(u, v), math.atan2(v, u), name="P")
    return Linkage([g_a0, g_b0, a, b, pt], name="fourbar")


def _split(traj: NDArray[np.float64], batch: tuple[int, ...]) -> Positions:
    s = traj.shape[-3]
    return tuple(traj[..., j, :].reshape(batch + (s, 2)) for j in (_A, _B, _P))  # type: ignore[return-value]


@dataclass(frozen=True)
class EnsemblePeer:
    """A pylinkage ``Ensemble`` of four-bars, ready to simulate on one input grid."""

    ensemble: object
    theta: NDArray[np.float64]
    batch: tuple[int, ...]


@dataclass(frozen=True)
class SinglePeer:
    """One compiled pylinkage ``Linkage``, ready for ``step_fast`` on one input grid."""

    linkage: object
    start: tuple[tuple[float, float], ...]
    theta: NDArray[np.float64]


def build_ensemble(mech: FourBar, theta: ArrayLike) -> EnsemblePeer:
    """Set up pylinkage's batched ``Ensemble`` for the four-bars ``mech`` (any batch shape)."""
    from pylinkage.population import Ensemble

    t, start, step = _grid(theta)
    batch, p = _fourbar_arrays(mech)
    init = _initial_positions(p, start, step)
    template = _linkage(
        *(p[k][0] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v")),
        init[0, 2], init[0, 3], step,
    )  # fmt: skip
    # Per-member constraints in Linkage.get_constraints() order: crank radius (its angular
    # velocity is shared by the topology), coupler, rocker, then P's distance and angle.
    dims = np.stack(
        (p["crank"], p["coupler"], p["rocker"], np.hypot(p["u"], p["v"]),
         np.arctan2(p["v"], p["u"])),
        axis=1,
    )  # fmt: skip
    ens = Ensemble(template, dims, init)
    _ = ens.template  # compile the shared solver data now, outside any timing
    return EnsemblePeer(ens, t, batch)


def build_single(mech: FourBar, theta: ArrayLike) -> SinglePeer:
    """Set up one pylinkage ``Linkage`` (a FourBar without batch dimensions) for ``step_fast``."""
    t, start, step = _grid(theta)
    batch, p = _fourbar_arrays(mech)
    if batch != ():
        raise PeerInputError(f"pylinkage_single takes one four-bar, got batch shape {batch}")
    init = _initial_positions(p, start, step)[0]
    linkage = _linkage(
        *(p[k][0] for k in ("A0", "B0", "crank", "coupler", "rocker", "u", "v")),
        init[2], init[3], step,
    )  # fmt: skip
    linkage.compile()
    start_coords = tuple((float(x), float(y)) for x, y in linkage.get_coords())
    return SinglePeer(linkage, start_coords, t)


def _check_theta(peer_theta: NDArray[np.float64], theta: ArrayLike) -> None:
    t = np.asarray(theta, dtype=float)
    if t.shape != peer_theta.shape or not np.array_equal(t, peer_theta):
        raise PeerInputError("theta differs from the grid the peer was built for")


def pylinkage_ensemble(mech: FourBar | EnsemblePeer, theta: ArrayLike) -> Positions:
    """Positions of A, B, P, each batch + (samples, 2), by pylinkage's ``Ensemble.simulate``.

    ``mech`` is a batched FourBar (built on the spot) or an ``EnsemblePeer`` from
    ``build_ensemble`` (only the simulation runs: what the benchmark times).
    """
    peer = mech if isinstance(mech, EnsemblePeer) else build_ensemble(mech, theta)
    _check_theta(peer.theta, theta)
    traj = peer.ensemble.simulate(iterations=peer.theta.size, dt=1.0, store=False)
    return _split(traj, peer.batch)


def pylinkage_single(mech: FourBar | SinglePeer, theta: ArrayLike) -> Positions:
    """Positions of A, B, P, each (samples, 2), for one four-bar by pylinkage's ``step_fast``.

    ``mech`` is a FourBar (built on the spot) or a ``SinglePeer`` from ``build_single``.
    ``step_fast`` leaves the linkage at its last pose, so the seeded start is restored first:
    every call then walks the same inputs from the same assembly.
    """
    peer = mech if isinstance(mech, SinglePeer) else build_single(mech, theta)
    _check_theta(peer.theta, theta)
    peer.linkage.set_coords(peer.start)
    traj = peer.linkage.step_fast(iterations=peer.theta.size, dt=1.0)
    return _split(traj, ())

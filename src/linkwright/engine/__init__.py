"""The engine: construction plans, batched evaluation with derivatives, limits and circuits."""

from linkwright.engine.circuits import InputArcs, NoPeriod, input_arcs, input_turns, trace
from linkwright.engine.evaluate import Motion, evaluate
from linkwright.engine.plan import (
    Crank,
    DyadRRP,
    DyadRRR,
    Fixed,
    Plan,
    Rigid,
    SphereCrank,
    SphereDyad,
    SphereRigid,
    Trammel,
)
from linkwright.engine.sphere_triad import SphereTriadPoses, sphere_triad, sphere_triad_sweep
from linkwright.engine.triad import TriadPoses, sweep_roots, triad_poses, triad_rates

__all__ = [
    "Crank",
    "DyadRRP",
    "DyadRRR",
    "Fixed",
    "InputArcs",
    "Motion",
    "NoPeriod",
    "Plan",
    "Rigid",
    "SphereCrank",
    "SphereDyad",
    "SphereRigid",
    "SphereTriadPoses",
    "Trammel",
    "TriadPoses",
    "evaluate",
    "input_arcs",
    "input_turns",
    "sphere_triad",
    "sphere_triad_sweep",
    "sweep_roots",
    "trace",
    "triad_poses",
    "triad_rates",
]

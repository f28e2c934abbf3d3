"""What a motion diagram plots: a family's output, or its moving links, as functions of a motion.

A :class:`Quantity` is a scalar of the linkage along a motion with its first two derivatives by
the input angle θ, derived from the circuit's analytic derivatives (nothing is differenced
numerically): a link's angle in the plane, a joint's angle about a ground axis on the sphere,
a slider pin's travel along its guide. :func:`outputs_of` picks a family's output (a four-bar's
φ3, a slider's position, a six-bar's last link) or, for families without one, every moving
link, links of one rigid body once.

Its own room (split from :mod:`linkwright.plot.diagrams`): the kinematics of what is shown,
apart from the panels that show it (:mod:`~linkwright.plot.diagram_panels`,
:mod:`~linkwright.plot.diagram_kinds`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from linkwright.analysis import output_angle, output_rates
from linkwright.engine import DyadRRP, DyadRRR, Fixed, Motion, SphereDyad
from linkwright.geometry import plane, sphere
from linkwright.mechanisms import (
    DoubleSlider,
    FourBar,
    Mechanism,
    SliderCrank,
    SphericalFourBar,
    SphericalSixBar,
    SphericalStephenson3,
)
from linkwright.mechanisms.sixbar import SixBar

__all__ = ["Outputs", "Quantity", "outputs_of"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Quantity:
    """A scalar of the linkage along a motion, with its first two derivatives by θ.

    ``unit`` is ``"angle"`` (radians, drawn in degrees) or ``"length"``.
    """

    label: str
    unit: str
    value: Callable[[Motion], Array]
    rates: Callable[[Motion], tuple[Array, Array]]


def _link_angle(origin: str, joint: str, label: str) -> Quantity:
    """Angle of joint − origin from +x; ψ′ = (r × r′)/|r|², ψ″ from differentiating that."""

    def value(m: Motion) -> Array:
        r = m.positions[joint] - m.positions[origin]
        return np.arctan2(r[..., 1], r[..., 0])

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        r = m.positions[joint] - m.positions[origin]
        r1 = m.velocities[joint] - m.velocities[origin]
        r2 = m.accelerations[joint] - m.accelerations[origin]
        q = plane.dot(r, r)
        w = plane.cross(r, r1) / q
        return w, plane.cross(r, r2) / q - 2.0 * plane.dot(r, r1) * w / q

    return Quantity(label, "angle", value, rates)


def _pivot_angle(pivot: str, ref: str, joint: str, label: str) -> Quantity:
    """On the sphere: the angle of ``joint`` about the fixed axis ``pivot``, right-handed, from
    the great circle pivot→ref. The joint turns on a circle about the pivot, so
    dJ/dψ = pivot × J and, dotting J′ and J″ with it, ψ′ = (p × J)·J′/|p × J|² and
    ψ″ = (p × J)·J″/|p × J|² (as the spherical four-bar's output rates)."""

    def value(m: Motion) -> Array:
        j = m.positions[joint]
        return sphere.angle_at(
            np.broadcast_to(m.positions[pivot], j.shape),
            np.broadcast_to(m.positions[ref], j.shape),
            j,
        )

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        j = m.positions[joint]
        w = sphere.cross(np.broadcast_to(m.positions[pivot], j.shape), j)
        s2 = sphere.dot(w, w)
        return sphere.dot(w, m.velocities[joint]) / s2, sphere.dot(w, m.accelerations[joint]) / s2

    return Quantity(label, "angle", value, rates)


def _travel(line_point: str, direction: Array, joint: str, label: str) -> Quantity:
    """Position of a slider pin along its guide, measured from the guide's point."""

    def along(d: dict[str, Array]) -> Array:
        return plane.dot(d[joint] - d[line_point], direction)

    def rates(m: Motion) -> tuple[Array, Array]:
        assert m.velocities is not None and m.accelerations is not None
        return along(m.velocities), along(m.accelerations)

    return Quantity(label, "length", lambda m: along(m.positions), rates)


@dataclass
class Outputs:
    """The quantities a family's diagrams show, and how to name them."""

    quantities: list[Quantity]
    single: bool
    """One output link (four-bars, slider-crank, six-bars) or several moving links."""
    describe: str
    """A line for the subtitle: what the quantities are, measured from what."""
    symbol: str = "ψ"
    skipped: list[str] = field(default_factory=list)


def _fixed(mechanism: Mechanism, name: str) -> bool:
    return isinstance(mechanism.plan.step(name), Fixed)


def _guide_direction(mechanism: Mechanism, dyad: DyadRRP) -> Array:
    angle = dyad.line_angle
    value = mechanism.params()[angle] if isinstance(angle, str) else angle
    return plane.unit_direction(np.asarray(value, dtype=float))


def _dyad_links(mechanism: Mechanism) -> tuple[list[tuple[Quantity, tuple[str, ...]]], list[str]]:
    """Every link a dyad hangs on, as (quantity, the link's joints); and the links left out.

    Planar links by their angle from +x, slider pins by their travel; on the sphere only links
    on a ground pivot have one angle (a floating spherical body's attitude is three angles).
    """
    out: list[tuple[Quantity, tuple[str, ...]]] = []
    skipped: list[str] = []
    fixed = list(mechanism.plan.ground)
    for dyad in mechanism.plan.dyads:
        j = dyad.name
        if isinstance(dyad, DyadRRR):
            for p in (dyad.p1, dyad.p2):
                out.append((_link_angle(p, j, f"{p}–{j}"), (p, j)))
        elif isinstance(dyad, DyadRRP):
            out.append((_link_angle(dyad.p1, j, f"{dyad.p1}–{j}"), (dyad.p1, j)))
            direction = _guide_direction(mechanism, dyad)
            out.append((_travel(dyad.line_point, direction, j, f"slider {j}"), (j,)))
        elif isinstance(dyad, SphereDyad):
            for p in (dyad.p1, dyad.p2):
                ref = next((f for f in fixed if f != p), None)
                if _fixed(mechanism, p) and ref is not None:
                    out.append((_pivot_angle(p, ref, j, f"{j} about {p}"), (p, j)))
                else:
                    skipped.append(f"{p}–{j}")
    # A triad hangs on its three binary links, each from an anchor to one of its joints.
    for triad in mechanism.plan.triads:
        for p, j in triad.links()[:3]:
            ref = next((f for f in fixed if f != p), None)
            if mechanism.space == "plane":
                out.append((_link_angle(p, j, f"{p}–{j}"), (p, j)))
            elif _fixed(mechanism, p) and ref is not None:
                out.append((_pivot_angle(p, ref, j, f"{j} about {p}"), (p, j)))
            else:
                skipped.append(f"{p}–{j}")
    return out, skipped


def outputs_of(mechanism: Mechanism, reference: Motion) -> Outputs:
    """The output of a family that has one, else every moving link; ``reference`` (a circuit
    with derivatives) groups links that turn as one body."""
    if isinstance(mechanism, FourBar):
        q = Quantity(
            "φ3",
            "angle",
            lambda m: output_angle(mechanism, m),
            lambda m: output_rates(mechanism, m),
        )
        return Outputs([q], True, "φ3: angle of B − B0 from the frame line A0→B0", "φ3")
    if isinstance(mechanism, SliderCrank):
        q = Quantity("s", "length", mechanism.slider_position, lambda m: output_rates(mechanism, m))
        return Outputs([q], True, "s: slider position along its line from the foot of A0", "s")
    if isinstance(mechanism, SphericalFourBar):
        q = Quantity(
            "φ3",
            "angle",
            mechanism.output_angle,
            lambda m: output_rates(mechanism, m),
        )
        return Outputs([q], True, "φ3: angle of B about +OB0 from the frame circle beyond B0", "φ3")
    if isinstance(mechanism, DoubleSlider):
        r_dir = plane.unit_direction(np.asarray(mechanism.alpha + mechanism.beta, dtype=float))
        q_dir = plane.unit_direction(np.asarray(mechanism.beta, dtype=float))
        return Outputs(
            [_travel("M", r_dir, "R", "slider R"), _travel("M", q_dir, "Q", "slider Q")],
            False,
            "the coupler turns with the input (its angle is θ + 180°) and the sliders only "
            "translate: their travels along the guides from M are shown",
            "t",
        )
    if isinstance(mechanism, SixBar | SphericalSixBar | SphericalStephenson3) and (
        mechanism.plan.dyads
    ):
        # The last link: the one from the second dyad's second pivot (E or D0 in the plane,
        # the ground pivot E0 or G on the sphere) to its joint.
        dyad = mechanism.plan.dyads[-1]
        assert not isinstance(dyad, DyadRRP)  # a six-bar's last dyad is a revolute one
        j, p = dyad.name, dyad.p2
        if mechanism.space == "sphere":
            ref = next(s.name for s in mechanism.plan.steps if isinstance(s, Fixed) and s.name != p)
            q = _pivot_angle(p, ref, j, f"{j} about {p}")
            what = f"ψ: angle of {j} about +O{p} from the great circle {p}→{ref} (last link {p}{j})"
        else:
            q = _link_angle(p, j, f"{p}–{j}")
            what = f"ψ: angle of the last link, {j} − {p}, from +x"
        return Outputs([q], True, what, "ψ")
    links, skipped = _dyad_links(mechanism)
    grouped = _group_bodies(links, reference)
    if mechanism.space == "sphere":
        what = "each link on a ground pivot: its angle about that pivot (right-handed)"
    else:
        what = "each dyad's links: angle from +x (links of one rigid body shown once)"
    return Outputs(grouped, False, what, "ψ", skipped)


def _group_bodies(
    links: list[tuple[Quantity, tuple[str, ...]]], reference: Motion
) -> list[Quantity]:
    """Links that turn as one rigid body (pinned together, equal ψ′ at every sample) shown
    once, named by the body's joints; sliders are kept as they are."""
    groups: list[tuple[Quantity, list[str], Array]] = []
    for q, joints in links:
        if q.unit != "angle":
            groups.append((q, list(joints), np.array([])))
            continue
        w = q.rates(reference)[0]
        scale = 1.0 + float(np.nanmax(np.abs(w))) if np.isfinite(w).any() else 1.0
        for g in groups:
            other = g[2]
            # Two links pinned at a common joint that always turn alike are one rigid body
            # (a triangle); parallel links elsewhere (a parallelogram) stay apart.
            shared = any(x in g[1] for x in joints)
            if (
                shared
                and other.shape == w.shape
                and np.allclose(w, other, rtol=0.0, atol=1e-9 * scale, equal_nan=True)
            ):
                g[1].extend(x for x in joints if x not in g[1])
                break
        else:
            groups.append((q, list(joints), w))
    out = []
    for q, body, _ in groups:
        if q.unit == "angle" and len(body) > 2:
            q = Quantity(f"{q.label} (body {'–'.join(body)})", q.unit, q.value, q.rates)
        out.append(q)
    return out

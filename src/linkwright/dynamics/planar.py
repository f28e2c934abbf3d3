"""Kinetostatics and inverse dynamics of planar linkages: Newton–Euler, and the energy balance.

Given a solved :class:`~linkwright.engine.Motion` (positions and their first and second
derivatives by the input angle θ), the input speed ω (and acceleration ε) turn them into
velocities and accelerations: ẋ = x′ω, ẍ = x″ω² + x′ε. Then, for every moving body (see
:mod:`linkwright.dynamics.bodies`), Newton–Euler about its centre of mass,

    Σ F = m·a_c,     Σ (r − c) × F + Σ τ = I·φ̈,

with unknowns every joint's reaction (in the plane: both components), each slider block's
normal force and moment from its guide, the driving torque on the driven link, and the torque
each geared crank's gear pair carries: one square linear system per sample, solved batched.

The second method, the energy balance, needs no reaction: the input power is the rate of
change of kinetic plus potential energy less the power of the loads. Divided by the driven
link's angular velocity, everything is a per-radian derivative times a time rate, so it holds
at speed 0 too (virtual work):

    T·φ_d′ = Σ [m c′·a_c + I φ′ φ̈] − Σ m g·c′ + Σ k (ℓ − ℓ0) ℓ′ − Σ F·x_P′ − Σ τ φ′ + Σ c ℓ̇ ℓ′.

Sign conventions: a reaction named by a ground pivot is the force the frame exerts on the
link; one named by a moving joint, the force the body placed earlier (in plan order) exerts on
the one placed later; at a joint of three bodies or more, ``"X:body"`` names each body's. The
driving torque is the torque the motor on the frame exerts on the driven link (positive
counter-clockwise); a motor at a moving hinge exerts it on the link it turns and the opposite
on the body it reacts on, and the frame takes none of it. Shaking force and moment: what the
moving links exert on the frame through its bearings, guides, motor and gears (moment about the
origin).

Units: the document's mass and length units and seconds: kilograms and metres give newtons,
newton-metres and joules.
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.dynamics.bodies import Body, Structure, structure
from linkwright.dynamics.model import ForcesInputError, Loads, MassProps
from linkwright.engine import Motion
from linkwright.engine.state import param_value
from linkwright.geometry import plane

__all__ = [
    "Forces",
    "Kinematics",
    "body_kinematics",
    "check_inputs",
    "forces_of",
    "mechanical_advantage",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Kinematics:
    """One body's motion per radian of input: its angle's derivatives φ′, φ″ and its centre of
    mass's position and derivatives, with its mass and inertia about the centre."""

    phi1: Array
    phi2: Array
    c: Array
    c1: Array
    c2: Array
    mass: float
    inertia: Array


@dataclass(frozen=True)
class Forces:
    """Every force of a linkage over a batch of mechanisms and samples (shape ``S`` = the
    motion's ``batch + (samples,)``; vectors add an axis of 2). NaN where the motion is not
    regular (not assembled, or at a singular position).

    Attributes
    ----------
    input : θ, radians.
    input_torque : the driving torque from Newton–Euler.
    energy_torque : the same from the energy balance (the check).
    reactions : joint name → force (see the module's sign conventions); on the sphere the
        least-norm bearing forces (see :mod:`linkwright.dynamics.spherical`).
    moments : on the sphere, joint name → the reaction moment its revolute carries.
    guides : slider block name → (normal force along the guide's left normal, moment).
    gears : geared link name → the torque its gear pair exerts on it.
    shaking_force, shaking_moment : on the frame (moment about the origin; on the sphere a
        vector about the centre).
    kinetic, potential : energies (potential: gravity and springs).
    """

    input: Array
    input_torque: Array
    energy_torque: Array
    reactions: dict[str, Array]
    moments: dict[str, Array] = field(default_factory=dict)
    guides: dict[str, Array] = field(default_factory=dict)
    gears: dict[str, Array] = field(default_factory=dict)
    shaking_force: Array = field(default_factory=lambda: np.zeros(0))
    shaking_moment: Array = field(default_factory=lambda: np.zeros(0))
    kinetic: Array = field(default_factory=lambda: np.zeros(0))
    potential: Array = field(default_factory=lambda: np.zeros(0))
    valid: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))


def _frame(body: Body, m: Motion) -> tuple[Array, Array, Array, Array, Array, Array]:
    """(origin, d, d′, d″, origin′, origin″) of the body's frame link, d = toward − origin."""
    assert body.frame is not None
    o, t = body.frame
    pos, vel, acc = m.positions, m.velocities, m.accelerations
    assert vel is not None and acc is not None
    return pos[o], pos[t] - pos[o], vel[t] - vel[o], acc[t] - acc[o], vel[o], acc[o]


def check_inputs(st: Structure, masses: Mapping[str, MassProps], motion: Motion) -> None:
    """Refuse masses on links the linkage does not have, and a motion without derivatives
    (what both spaces' solvers need before they start)."""
    for name in masses:
        if name not in st.names:
            raise ForcesInputError("mass", f"unknown link {name!r} (known: {', '.join(st.names)})")
    if motion.velocities is None or motion.accelerations is None:
        raise ValueError("forces need a motion solved with order=2")


def body_kinematics(body: Body, props: MassProps | None, m: Motion) -> Kinematics:
    """A body's angle derivatives and its centre of mass's motion, per radian of input."""
    vel, acc = m.velocities, m.accelerations
    if vel is None or acc is None:
        raise ValueError("forces need a motion solved with order=2")
    mass = 0.0 if props is None else props.mass
    if body.is_block or body.frame is None:
        pin = body.points[0]
        zero = np.zeros(m.input.shape)
        return Kinematics(zero, zero, m.positions[pin], vel[pin], acc[pin], mass, zero)
    o, d, d1, d2, o1, o2 = _frame(body, m)
    len2 = plane.dot(d, d)
    cr1 = plane.cross(d, d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        phi1 = cr1 / len2
        phi2 = plane.cross(d, d2) / len2 - 2.0 * plane.dot(d, d1) * cr1 / len2**2
    if props is not None and props.centre is not None:
        u, v = props.centre
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / np.sqrt(len2)[..., None]

        def local(x: Array) -> Array:
            return (u * x + v * plane.perp(x)) * inv

        c, c1, c2 = o + local(d), o1 + local(d1), o2 + local(d2)
        inertia = np.full(m.input.shape, float(props.inertia or 0.0))
    elif len(body.joints) == 3:
        n0, n1, n2 = body.joints
        pos = m.positions
        c = (pos[n0] + pos[n1] + pos[n2]) / 3.0
        c1 = (vel[n0] + vel[n1] + vel[n2]) / 3.0
        c2 = (acc[n0] + acc[n1] + acc[n2]) / 3.0
        sides = (
            plane.dot(pos[n1] - pos[n0], pos[n1] - pos[n0])
            + plane.dot(pos[n2] - pos[n1], pos[n2] - pos[n1])
            + plane.dot(pos[n0] - pos[n2], pos[n0] - pos[n2])
        )
        inertia = mass * sides / 36.0
    else:
        c, c1, c2 = o + 0.5 * d, o1 + 0.5 * d1, o2 + 0.5 * d2
        inertia = mass * len2 / 12.0
    return Kinematics(phi1, phi2, c, c1, c2, mass, np.asarray(inertia, dtype=float))


def forces_of(
    plan_or_structure: object,
    params: Mapping[str, ArrayLike],
    motion: Motion,
    masses: Mapping[str, MassProps],
    loads: Loads,
) -> Forces:
    """Newton–Euler and the energy balance over a solved motion (``order=2``).

    Parameters
    ----------
    plan_or_structure : the mechanism's plan (or its :func:`structure`).
    params : the plan's parameters (``mechanism.params()``).
    motion : the solved motion, with derivatives.
    masses : link name → :class:`MassProps` (links left out are massless).
    loads : the loads and the input speed.

    Examples
    --------
    A crank alone, a uniform bar of 2 kg and 0.5 m turning at 60 rpm under gravity: the motor
    holds its weight, T = m g (L/2) cos θ.

    >>> from linkwright.engine import Crank, Fixed, Plan, evaluate
    >>> plan = Plan((Fixed("O", "O"), Crank("A", "O", "crank")), traced=("A",))
    >>> params = {"O": np.zeros(2), "crank": np.asarray(0.5)}
    >>> m = evaluate(plan, params, np.array([0.0, np.pi / 3]), points=frozenset("O"))
    >>> f = forces_of(plan, params, m, {"crank": MassProps(2.0)},
    ...               Loads(speed_rpm=60, gravity=(0.0, -9.81)))
    >>> np.round(f.input_torque, 6), np.round(2 * 9.81 * 0.25 * np.cos([0, np.pi / 3]), 6)
    (array([4.905 , 2.4525]), array([4.905 , 2.4525]))
    """
    st = (
        plan_or_structure
        if isinstance(plan_or_structure, Structure)
        else structure(
            plan_or_structure  # type: ignore[arg-type]
        )
    )
    if st.space == "sphere":
        from linkwright.dynamics.spherical import forces_of_sphere

        return forces_of_sphere(st, params, motion, masses, loads)
    check_inputs(st, masses, motion)
    shape = motion.input.shape
    omega = loads.omega if loads.inertia else 0.0
    eps = loads.acceleration if loads.inertia else 0.0
    kin = [body_kinematics(b, masses.get(b.name), motion) for b in st.bodies]
    nb = len(st.bodies)
    index = {b.name: k for k, b in enumerate(st.bodies)}
    g = np.asarray(loads.gravity, dtype=float)

    # Accelerations in time, and the right-hand side: m a − F_ext, I φ̈ − M_ext (about c).
    rhs = np.zeros(shape + (3 * nb,))
    acc_c, alpha = [], []
    for k, q in enumerate(kin):
        a = q.c2 * omega**2 + q.c1 * eps
        al = q.phi2 * omega**2 + q.phi1 * eps
        acc_c.append(a)
        alpha.append(al)
        rhs[..., 3 * k : 3 * k + 2] = q.mass * (a - g)
        rhs[..., 3 * k + 2] = q.inertia * al
    ext = _point_loads(st, motion, loads, omega)
    for k, point, force in ext:
        rhs[..., 3 * k : 3 * k + 2] -= force
        rhs[..., 3 * k + 2] -= plane.cross(motion.positions[point] - kin[k].c, force)
    for link, tau in loads.torques:
        rhs[..., 3 * index[link] + 2] -= tau

    # The columns: each unknown's forces and moments on the bodies.
    columns: list[Array] = []
    labels: list[tuple[str, str]] = []  # (kind, name)

    def column() -> Array:
        col = np.zeros(shape + (3 * nb,))
        columns.append(col)
        return col

    for joint in st.joints:
        on = [k for k, b in enumerate(st.bodies) if joint in b.joints]
        hub = None if joint in st.ground else on[0]
        others = on if hub is None else on[1:]
        x = motion.positions[joint]
        for k in others:
            name = joint if len(others) == 1 else f"{joint}:{st.bodies[k].name}"
            for axis in range(2):
                unit = np.zeros(2)
                unit[axis] = 1.0
                col = column()
                col[..., 3 * k + axis] = 1.0
                col[..., 3 * k + 2] = plane.cross(x - kin[k].c, unit)
                if hub is not None:
                    col[..., 3 * hub + axis] = -1.0
                    col[..., 3 * hub + 2] = -plane.cross(x - kin[hub].c, unit)
                labels.append(("reaction", name))
    for k, b in enumerate(st.bodies):
        if b.guide is not None:
            n = plane.perp(plane.unit_direction(param_value(b.guide.angle, params)))
            n = np.broadcast_to(n, shape + (2,))
            col = column()
            col[..., 3 * k : 3 * k + 2] = n
            col[..., 3 * k + 2] = plane.cross(motion.positions[b.points[0]] - kin[k].c, n)
            labels.append(("guide", b.name))
            col = column()
            col[..., 3 * k + 2] = 1.0
            labels.append(("guide", b.name))
        if b.far_end is not None:
            t = b.far_end
            end, n2 = _far_end(t, params, motion)
            col = column()
            col[..., 3 * k : 3 * k + 2] = n2
            col[..., 3 * k + 2] = plane.cross(end - kin[k].c, n2)
            labels.append(("far_end", b.name))
    col = column()
    col[..., 3 * st.driven + 2] = 1.0
    if st.counter is not None:  # a motor at a moving hinge: it reacts on the other side
        col[..., 3 * st.counter + 2] = -1.0
    labels.append(("input", ""))
    ratio_d = param_value(st.driven_ratio, params)
    for k, ratio in st.geared:
        col = column()
        col[..., 3 * k + 2] = 1.0
        col[..., 3 * st.driven + 2] = -param_value(ratio, params) / ratio_d
        labels.append(("gear", st.bodies[k].name))
    if len(columns) != 3 * nb:
        raise ValueError(
            f"the linkage's {nb} bodies and its joints make {len(columns)} unknown forces for "
            f"{3 * nb} equations: its forces are not determined by Newton–Euler"
        )
    matrix = np.stack(columns, axis=-1)
    # Finite positions and derivatives (a regular sample) make a finite system.
    ok = motion.regular & np.all(np.isfinite(rhs), axis=-1)
    solution = solve_samples(matrix, rhs, ok)

    reactions: dict[str, Array] = {}
    guides: dict[str, Array] = {}
    gears: dict[str, Array] = {}
    torque = np.full(shape, np.nan)
    k = 0
    shake_f = np.zeros(shape + (2,))
    shake_m = np.zeros(shape)
    while k < len(labels):
        kind, name = labels[k]
        if kind == "reaction":
            f = solution[..., k : k + 2]
            reactions[name] = f
            joint = name.split(":")[0]
            if joint in st.ground:
                shake_f -= f
                shake_m -= plane.cross(motion.positions[joint], f)
            k += 2
            continue
        if kind == "guide":
            b = st.body(name)
            assert b.guide is not None  # "guide" labels come only from bodies with a guide
            n = plane.perp(plane.unit_direction(param_value(b.guide.angle, params)))
            nf, mom = solution[..., k], solution[..., k + 1]
            guides[name] = np.stack((nf, mom), axis=-1)
            f = nf[..., None] * n
            shake_f -= f
            shake_m -= plane.cross(motion.positions[b.points[0]], f) + mom
            k += 2
            continue
        if kind == "far_end":
            b = st.body(name)
            end, n2 = _far_end(b.far_end, params, motion)
            f = solution[..., k][..., None] * n2
            guides[f"{name}:far_end"] = np.stack((solution[..., k], np.zeros(shape)), axis=-1)
            shake_f -= f
            shake_m -= plane.cross(end, f)
        elif kind == "input":
            torque = solution[..., k]
            if st.counter is None:
                shake_m -= torque
        elif kind == "gear":
            gear_tau = solution[..., k]
            gears[name] = gear_tau
            ratio = dict((st.bodies[j].name, r) for j, r in st.geared)[name]
            shake_m -= gear_tau * (1.0 - param_value(ratio, params) / ratio_d)
        k += 1

    energy, kinetic, potential = _energy(st, kin, acc_c, alpha, motion, loads, omega, g, index)
    mask = ok & np.isfinite(torque)
    nan = np.where(mask, 1.0, np.nan)
    return Forces(
        input=motion.input,
        input_torque=torque * nan,
        energy_torque=energy * nan,
        reactions={n: f * nan[..., None] for n, f in reactions.items()},
        guides={n: f * nan[..., None] for n, f in guides.items()},
        gears={n: t * nan for n, t in gears.items()},
        shaking_force=shake_f * nan[..., None],
        shaking_moment=shake_m * nan,
        kinetic=kinetic * nan,
        potential=potential * nan,
        valid=mask,
    )


def _far_end(t: object, params: Mapping[str, ArrayLike], motion: Motion) -> tuple[Array, Array]:
    """A trammel arm's far end and the left normal of the guide it slides on."""
    from linkwright.engine.plan import Trammel

    assert isinstance(t, Trammel)
    phi = param_value(t.phase, params) + motion.input
    arm = param_value(t.arm, params)[..., None] * plane.unit_direction(phi)
    end = motion.positions[t.name] + arm
    n2 = plane.perp(plane.unit_direction(param_value(t.angle2, params)))
    return end, np.broadcast_to(n2, end.shape)


def solve_samples(matrix: Array, rhs: Array, ok: NDArray[np.bool_]) -> Array:
    """One solve per sample; NaN where the sample is not ``ok`` or its system is singular."""
    n = matrix.shape[-1]
    # In place (the system is the caller's scratch): an identity where the sample is not ok.
    matrix[~ok] = np.eye(n)
    rhs[~ok] = 0.0
    safe, b = matrix, rhs
    try:
        x = np.linalg.solve(safe, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        flat_a, flat_b = safe.reshape(-1, n, n), b.reshape(-1, n)
        x = np.full(flat_b.shape, np.nan)
        for i in range(flat_a.shape[0]):
            with contextlib.suppress(np.linalg.LinAlgError):  # singular: stays NaN
                x[i] = np.linalg.solve(flat_a[i], flat_b[i])
        x = x.reshape(b.shape)
    return np.where(ok[..., None], x, np.nan)


def _point_loads(
    st: Structure, motion: Motion, loads: Loads, omega: float
) -> list[tuple[int, str, Array]]:
    """(body, point, force) of every point force, spring and damper end on a moving body."""
    out: list[tuple[int, str, Array]] = []
    for point, value in loads.forces:
        k = st.owner(point)
        if k is not None:
            out.append(
                (k, point, np.broadcast_to(np.asarray(value), motion.positions[point].shape))
            )
    pairs = [(a, b, s, l0, 0.0) for a, b, s, l0 in loads.springs]
    pairs += [(a, b, 0.0, 0.0, c) for a, b, c in loads.dampers]
    for a, b, stiff, free, damp in pairs:
        ell, ell1, unit = _span(motion, a, b)
        tension = stiff * (ell - free) + damp * ell1 * omega
        for point, sign in ((a, -1.0), (b, 1.0)):
            k = st.owner(point)
            if k is not None:
                out.append((k, point, sign * tension[..., None] * unit))
    return out


def _span(motion: Motion, a: str, b: str) -> tuple[Array, Array, Array]:
    """|a − b|, its derivative by θ, and the unit vector from b to a."""
    assert motion.velocities is not None
    d = motion.positions[a] - motion.positions[b]
    ell = plane.norm(d)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = d / ell[..., None]
    ell1 = plane.dot(unit, motion.velocities[a] - motion.velocities[b])
    return ell, ell1, unit


def _energy(
    st: Structure,
    kin: list[Kinematics],
    acc_c: list[Array],
    alpha: list[Array],
    motion: Motion,
    loads: Loads,
    omega: float,
    g: Array,
    index: Mapping[str, int],
) -> tuple[Array, Array, Array]:
    """The driving torque by the energy balance (per radian of the driven link), and the
    kinetic and potential energies."""
    shape = motion.input.shape
    rate = np.zeros(shape)  # input power / ω
    kinetic = np.zeros(shape)
    potential = np.zeros(shape)
    for q, a, al in zip(kin, acc_c, alpha, strict=True):
        rate += q.mass * plane.dot(q.c1, a - g) + q.inertia * q.phi1 * al
        kinetic += 0.5 * omega**2 * (q.mass * plane.dot(q.c1, q.c1) + q.inertia * q.phi1**2)
        potential -= q.mass * plane.dot(q.c, g)
    assert motion.velocities is not None
    for point, value in loads.forces:
        rate -= plane.dot(np.asarray(value), motion.velocities[point])
    for link, tau in loads.torques:
        rate -= tau * kin[index[link]].phi1
    for end_a, end_b, stiff, free in loads.springs:
        ell, ell1, _ = _span(motion, end_a, end_b)
        rate += stiff * (ell - free) * ell1
        potential += 0.5 * stiff * (ell - free) ** 2
    for end_a, end_b, damp in loads.dampers:
        _, ell1, _ = _span(motion, end_a, end_b)
        rate += damp * omega * ell1 * ell1
    turn = kin[st.driven].phi1
    if st.counter is not None:
        turn = turn - kin[st.counter].phi1
    with np.errstate(divide="ignore", invalid="ignore"):
        torque = rate / turn
    return torque, kinetic, potential


def mechanical_advantage(st: Structure, motion: Motion, output: str | None = None) -> Array:
    """The ideal mechanical advantage: output load over input torque with no inertia or
    friction, |dθ/dφ_out| for a turning output (its angle's rate), |dθ/dx| (per length unit)
    for a slider block's travel. ``output``: the link's name (default: the last link on the
    frame that the input does not drive)."""
    if output is None:
        driven = {st.driven, *(k for k, _ in st.geared)}
        on_frame = [
            k
            for k, b in enumerate(st.bodies)
            if k not in driven and (b.is_block or any(j in st.ground for j in b.joints))
        ]
        if not on_frame:
            raise ValueError("the linkage has no output link on the frame: name one")
        k = on_frame[-1]
    else:
        k = st.names.index(output)
    body = st.bodies[k]
    q = body_kinematics(body, None, motion)
    rate = plane.norm(q.c1) if body.is_block else np.abs(q.phi1)
    with np.errstate(divide="ignore"):
        return 1.0 / rate

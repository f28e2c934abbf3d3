"""Kinetostatics and inverse dynamics of spherical linkages: Euler about the centre, and the
energy balance.

Every body of a spherical linkage turns about the sphere's centre O, so each is a rigid body
with a fixed point. Its angular velocity per radian of input, w, follows from any two of its
joints' axes P, Q and their derivatives (P′ = w × P): the least-squares normal equations
``(2𝟙 − PPᵀ − QQᵀ) w = P × P′ + Q × Q′`` are exact for a rigid motion and regular while P ∦ Q;
the same system with ``P″ − w × P′`` gives w′. In time, Ω = ω w and Ω̇ = ω² w′ + ε w.

Euler's equation about the fixed point, with I_O the body's inertia tensor about O in the
world frame at that instant,

    Σ M_O = I_O Ω̇ + Ω × (I_O Ω),

has as unknowns each revolute joint's reaction moment (two components, perpendicular to its
axis: a revolute transmits no moment about its own axis) and the driving torque about the
driven crank's ground axis: 3 per body, as many as the equations (Grübler on the sphere,
3(n − 1) − 2j = 1). The reaction *forces* are another matter: every joint's axis passes
through O, so a spherical linkage is overconstrained as a spatial one (a four-bar by 3 per
loop) and its bearings' forces are statically indeterminate; Newton's Σ F = m a_c fixes only
their sum per body. We report the least-norm set (the forces the fewest bearings' preloads
would add nothing to) and say so; the shaking force on the frame, their sum, is determinate.

The energy balance checks the torque without any reaction:

    T (A0·w_d) = Σ w·(I_O Ω̇) − Σ m g·c′ − Σ R F·P′.

Units: the document's mass and length units (``radius`` gives the sphere's size) and
seconds.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from linkwright.dynamics.bodies import Body, Structure, UnsupportedPlan
from linkwright.dynamics.model import ForcesInputError, Loads, MassProps
from linkwright.dynamics.planar import Forces, check_inputs, solve_samples
from linkwright.engine import Motion
from linkwright.geometry import sphere

__all__ = ["SphereKinematics", "angular_rates", "forces_of_sphere", "sphere_kinematics"]

Array = NDArray[np.float64]


def angular_rates(
    p: Array, q: Array, p1: Array, q1: Array, p2: Array | None = None, q2: Array | None = None
) -> tuple[Array, Array | None]:
    """A rigid body's angular velocity w (per radian of input) and its derivative w′ from two
    of its points on the unit sphere and their derivatives (see the module's docstring).

    Examples
    --------
    A body turning about +z at unit rate:

    >>> z = np.array([0.0, 0.0, 1.0])
    >>> p, q = np.array([1.0, 0, 0]), sphere.unit(np.array([0.0, 1, 1]))
    >>> w, _ = angular_rates(p, q, np.cross(z, p), np.cross(z, q))
    >>> w.round(12) + 0.0
    array([0., 0., 1.])
    """
    eye = np.eye(3)
    m = 2.0 * eye - p[..., :, None] * p[..., None, :] - q[..., :, None] * q[..., None, :]
    rhs = sphere.cross(p, p1) + sphere.cross(q, q1)
    with np.errstate(invalid="ignore", divide="ignore"):
        w: Array = np.asarray(np.linalg.solve(m, rhs[..., None])[..., 0], dtype=float)
        if p2 is None or q2 is None:
            return w, None
        rp = p2 - sphere.cross(w, p1)
        rq = q2 - sphere.cross(w, q1)
        dw = np.linalg.solve(m, (sphere.cross(p, rp) + sphere.cross(q, rq))[..., None])
    return w, np.asarray(dw[..., 0], dtype=float)


class SphereKinematics:
    """One body's rotation per radian of input (w, w′), its centre of mass (in the length
    unit) and inertia tensor about O in the world frame, at every sample."""

    def __init__(self, w: Array, dw: Array, c: Array, inertia: Array, mass: float) -> None:
        self.w, self.dw, self.c, self.inertia, self.mass = w, dw, c, inertia, mass

    @property
    def c1(self) -> Array:
        """The centre's derivative by the input angle."""
        return sphere.cross(self.w, self.c)

    def c2(self) -> Array:
        """The centre's second derivative by the input angle."""
        return sphere.cross(self.dw, self.c) + sphere.cross(self.w, self.c1)


def _outer(a: Array, b: Array) -> Array:
    return a[..., :, None] * b[..., None, :]


def sphere_kinematics(
    body: Body, props: MassProps | None, m: Motion, radius: float
) -> SphereKinematics:
    """A spherical body's rotation, centre and inertia about O (a massless body: zeros)."""
    if body.frame is None:
        raise UnsupportedPlan(f"the body {body.name} has no link to measure its rotation by")
    vel, acc = m.velocities, m.accelerations
    if vel is None or acc is None:
        raise ValueError("forces need a motion solved with order=2")
    o, t = body.frame
    e1 = m.positions[o]
    w, dw = angular_rates(e1, m.positions[t], vel[o], vel[t], acc[o], acc[t])
    assert dw is not None
    shape = m.input.shape
    if props is None:
        return SphereKinematics(w, dw, np.zeros(shape + (3,)), np.zeros(shape + (3, 3)), 0.0)
    # The link's frame: x along its first joint's axis, y towards the second in their plane.
    e2 = sphere.unit(m.positions[t] - sphere.dot(m.positions[t], e1)[..., None] * e1)
    e3 = sphere.cross(e1, e2)
    mass, r = props.mass, radius
    if props.tensor is None:
        # A uniform thin bar along the arc from e1, of angle β: its centroid at R sin(β/2)/(β/2)
        # on the bisector, and I_O = m R² (𝟙 − ⟨u uᵀ⟩) with u = cos s e1 + sin s e2, s ∈ [0, β].
        beta = sphere.arc(e1, m.positions[t])[..., None, None]
        half = 0.5 * beta[..., 0]
        bisector = np.cos(half) * e1 + np.sin(half) * e2
        c = r * (np.sin(half) / half) * bisector
        s2 = np.sin(2.0 * beta) / (4.0 * beta)
        mean = (
            (0.5 + s2) * _outer(e1, e1)
            + (0.5 - s2) * _outer(e2, e2)
            + (np.sin(beta) ** 2 / (2.0 * beta)) * (_outer(e1, e2) + _outer(e2, e1))
        )
        inertia = mass * r * r * (np.eye(3) - mean)
    else:
        frame = np.stack((e1, e2, e3), axis=-1)  # columns: the link's axes in the world
        local = np.asarray(props.centre, dtype=float)
        about_o = np.asarray(props.tensor, dtype=float) + mass * (
            np.dot(local, local) * np.eye(3) - np.outer(local, local)
        )
        c = frame @ local
        inertia = frame @ about_o @ np.swapaxes(frame, -1, -2)
    return SphereKinematics(w, dw, c, inertia, mass)


def _perpendicular_basis(axis: Array) -> tuple[Array, Array]:
    """Two unit vectors perpendicular to ``axis`` and to each other."""
    helper = np.eye(3)[np.argmin(np.abs(axis), axis=-1)]
    u = sphere.unit(sphere.cross(axis, helper))
    return u, sphere.cross(axis, u)


def forces_of_sphere(
    st: Structure,
    params: Mapping[str, ArrayLike],
    motion: Motion,
    masses: Mapping[str, MassProps],
    loads: Loads,
) -> Forces:
    """Euler about the centre and the energy balance over a solved spherical motion.

    ``reactions`` are the least-norm bearing forces (indeterminate on the sphere: see the
    module's docstring) and ``moments`` each revolute joint's reaction moment; the shaking
    force and moment are 3-vectors (moment about O). Sign conventions as in the plane
    (:mod:`linkwright.dynamics.planar`): a ground pivot's reaction is the frame's on the link,
    a moving joint's the earlier body's on the later one.

    Examples
    --------
    A lone spherical crank, a uniform arc bar of 2 kg through 90° on a sphere of radius
    0.5 m from the pole z to the equator, held still under gravity along −y: the motor
    carries the weight's moment about the crank's axis z, m g R (sin 45°/(π/4))·cos 45° (the
    arc's centroid lies on its bisector at R sin(β/2)/(β/2)).

    >>> from linkwright.engine import Fixed, Plan, SphereCrank, evaluate
    >>> from linkwright.dynamics.bodies import structure
    >>> plan = Plan((Fixed("O", "O"), Fixed("X", "X"), SphereCrank("A", "O", "crank", "X")),
    ...             traced=("A",))
    >>> params = {"O": np.array([0.0, 0, 1]), "X": np.array([1.0, 0, 0]),
    ...           "crank": np.asarray(np.pi / 2)}
    >>> m = evaluate(plan, params, np.array([0.0]), points=frozenset("OX"))
    >>> f = forces_of_sphere(structure(plan), params, m, {"crank": MassProps(2.0)},
    ...                      Loads(inertia=False, gravity=(0.0, -9.81, 0.0), radius=0.5))
    >>> c = 0.5 * (np.sin(np.pi / 4) / (np.pi / 4)) * np.cos(np.pi / 4)
    >>> bool(np.isclose(f.input_torque[0], 2 * 9.81 * c, rtol=1e-12))
    True
    """
    if st.geared:
        raise UnsupportedPlan("geared cranks on the sphere: their forces are not implemented yet")
    check_inputs(st, masses, motion)
    assert motion.velocities is not None  # checked: the energy balance reads them below
    shape = motion.input.shape
    omega = loads.omega if loads.inertia else 0.0
    eps = loads.acceleration if loads.inertia else 0.0
    r = loads.radius
    kin = [sphere_kinematics(b, masses.get(b.name), motion, r) for b in st.bodies]
    nb = len(st.bodies)
    g = np.asarray(loads.gravity, dtype=float)
    if g.shape != (3,):
        if np.any(g):
            raise ForcesInputError("loads.gravity", "must be a vector [x, y, z] on the sphere")
        g = np.zeros(3)  # Loads()'s default, written for the plane: no gravity
    pos = motion.positions

    # Right-hand sides: Euler (moments about O) and Newton (forces), per body.
    moment_rhs = np.zeros(shape + (3 * nb,))
    force_rhs = np.zeros(shape + (3 * nb,))
    spin_rate = []
    for k, q in enumerate(kin):
        big_w, big_dw = omega * q.w, omega**2 * q.dw + eps * q.w
        spin_rate.append(big_dw)
        i_w = np.einsum("...ij,...j->...i", q.inertia, big_w)
        euler = np.einsum("...ij,...j->...i", q.inertia, big_dw) + sphere.cross(big_w, i_w)
        moment_rhs[..., 3 * k : 3 * k + 3] = euler - sphere.cross(q.c, q.mass * g)
        acc_c = omega**2 * q.c2() + eps * q.c1
        force_rhs[..., 3 * k : 3 * k + 3] = q.mass * (acc_c - g)
    for point, value in loads.forces:
        k_owner = st.owner(point)
        if k_owner is None:
            continue
        f_ext = np.broadcast_to(np.asarray(value, dtype=float), shape + (3,))
        moment_rhs[..., 3 * k_owner : 3 * k_owner + 3] -= sphere.cross(r * pos[point], f_ext)
        force_rhs[..., 3 * k_owner : 3 * k_owner + 3] -= f_ext

    # Columns: each joint's two moment components (on the later body +, on the hub −), then
    # the driving torque about the driven crank's ground axis.
    moment_cols: list[Array] = []
    force_cols: list[Array] = []
    names: list[tuple[str, str]] = []  # (label, joint) for each joint incidence
    for joint in st.joints:
        on = [k for k, b in enumerate(st.bodies) if joint in b.joints]
        hub = None if joint in st.ground else on[0]
        others = on if hub is None else on[1:]
        u, v = _perpendicular_basis(pos[joint])
        for k in others:
            label = joint if len(others) == 1 else f"{joint}:{st.bodies[k].name}"
            names.append((label, joint))
            for vec in (u, v):
                col = np.zeros(shape + (3 * nb,))
                col[..., 3 * k : 3 * k + 3] = vec
                if hub is not None:
                    col[..., 3 * hub : 3 * hub + 3] = -vec
                moment_cols.append(col)
            for axis in range(3):
                incidence = np.zeros(3 * nb)
                incidence[3 * k + axis] = 1.0
                if hub is not None:
                    incidence[3 * hub + axis] = -1.0
                force_cols.append(incidence)
    drive_axis = pos[st.pivot]
    col = np.zeros(shape + (3 * nb,))
    col[..., 3 * st.driven : 3 * st.driven + 3] = drive_axis
    if st.counter is not None:  # a motor at a moving hinge: it reacts on the other side
        col[..., 3 * st.counter : 3 * st.counter + 3] = -drive_axis
    moment_cols.append(col)
    if len(moment_cols) != 3 * nb:
        raise UnsupportedPlan(
            f"the linkage's {nb} bodies and its joints make {len(moment_cols)} unknown moments "
            f"for {3 * nb} equations: its torques are not determined by Euler's equations"
        )
    ok = motion.regular & np.all(np.isfinite(moment_rhs), axis=-1)
    ok &= np.all(np.isfinite(force_rhs), axis=-1)
    solution = solve_samples(np.stack(moment_cols, axis=-1), moment_rhs, ok)
    # Newton's equations fix only each body's total: the least-norm forces (pseudo-inverse of
    # a constant incidence matrix of full row rank).
    incidence = np.stack(force_cols, axis=-1)
    forces = np.where(ok[..., None], force_rhs, 0.0) @ np.linalg.pinv(incidence).T

    reactions: dict[str, Array] = {}
    moments: dict[str, Array] = {}
    shake_f = np.zeros(shape + (3,))
    shake_m = np.zeros(shape + (3,))
    for n, (label, joint) in enumerate(names):
        u, v = _perpendicular_basis(pos[joint])
        mom = solution[..., 2 * n, None] * u + solution[..., 2 * n + 1, None] * v
        force = forces[..., 3 * n : 3 * n + 3]
        reactions[label], moments[label] = force, mom
        if joint in st.ground:
            shake_f -= force
            shake_m -= mom
    torque = solution[..., -1]
    if st.counter is None:
        shake_m -= torque[..., None] * drive_axis

    # The energy balance, per radian of input.
    rate = np.zeros(shape)
    kinetic = np.zeros(shape)
    potential = np.zeros(shape)
    for q, big_dw in zip(kin, spin_rate, strict=True):
        rate += sphere.dot(q.w, np.einsum("...ij,...j->...i", q.inertia, big_dw))
        rate -= q.mass * sphere.dot(g, q.c1)
        kinetic += 0.5 * omega**2 * sphere.dot(q.w, np.einsum("...ij,...j->...i", q.inertia, q.w))
        potential -= q.mass * sphere.dot(g, q.c)
    for point, value in loads.forces:
        rate -= r * sphere.dot(np.asarray(value, dtype=float), motion.velocities[point])
    with np.errstate(divide="ignore", invalid="ignore"):
        turn = kin[st.driven].w if st.counter is None else kin[st.driven].w - kin[st.counter].w
        energy = rate / sphere.dot(drive_axis, turn)

    mask = ok & np.isfinite(torque)
    nan = np.where(mask, 1.0, np.nan)
    return Forces(
        input=motion.input,
        input_torque=torque * nan,
        energy_torque=energy * nan,
        reactions={n: f * nan[..., None] for n, f in reactions.items()},
        moments={n: f * nan[..., None] for n, f in moments.items()},
        shaking_force=shake_f * nan[..., None],
        shaking_moment=shake_m * nan[..., None],
        kinetic=kinetic * nan,
        potential=potential * nan,
        valid=mask,
    )

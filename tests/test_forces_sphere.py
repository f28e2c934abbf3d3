"""Forces on the sphere (issue 25): Euler about the centre against the energy balance, against
paper 003's reduced inertia with the output's angle differentiated by FFT, against momentum
by finite differences of solved positions, and a full turn's work.

The references are computed another way than the library's: angles and centres from solved
positions (never from its velocities or accelerations), differentiated spectrally over a full
turn or by central differences.
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.cli import main
from linkwright.dynamics import ForcesInputError, Loads, MassProps, loads_from, masses_from
from linkwright.dynamics import structure as body_structure
from linkwright.dynamics.planar import forces_of
from linkwright.io import load_example
from linkwright.mechanisms import SphericalFourBar, input_range
from linkwright.mechanisms.base import solve

SPHERICAL = [
    "paper000-fig6-crank-rocker",
    "paper000-fig6-linkage",
    "paper000-fig8-sixbar",
    "paper001-stephenson3",
    "paper001-fg",
    "paper001-driven-at-e",
]


def _tensor(rng: np.random.Generator, size: float) -> tuple[tuple[float, ...], ...]:
    """A random body's inertia tensor (a sum of point masses' m(|r|²𝟙 − r rᵀ): always valid)."""
    points = rng.normal(size=(4, 3)) * size
    weights = rng.uniform(0.1, 1.0, 4)
    t = sum(w * (p @ p * np.eye(3) - np.outer(p, p)) for w, p in zip(weights, points, strict=True))
    return tuple(map(tuple, t))


def _masses(s, rng: np.random.Generator, radius: float) -> dict[str, MassProps]:
    out = {}
    for b in s.bodies:
        if len(b.joints) >= 3 or rng.random() < 0.5:
            centre = tuple(rng.normal(size=3) * 0.5 * radius)
            out[b.name] = MassProps(
                rng.uniform(0.1, 2.0), centre, tensor=_tensor(rng, 0.3 * radius)
            )
        else:
            out[b.name] = MassProps(rng.uniform(0.1, 2.0))
    return out


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(SPHERICAL),
    seed=st.integers(0, 2**31),
    radius=st.floats(0.01, 10.0),
    speed=st.floats(-600.0, 600.0),
    accel=st.floats(-50.0, 50.0),
)
def test_euler_matches_the_energy_balance_on_every_spherical_example(
    name, seed, radius, speed, accel
):
    mech = load_example(name).mechanism
    s = body_structure(mech.plan)
    rng = np.random.default_rng(seed)
    masses = _masses(s, rng, radius)
    traced = mech.plan.traced[0]
    loads = Loads(
        speed_rpm=speed,
        acceleration=accel,
        gravity=tuple(rng.normal(size=3) * 9.81),
        forces=((traced, tuple(rng.normal(size=3))),),
        radius=radius,
    )
    theta = np.radians(np.arange(0.0, 360.0, 10.0))
    motion = solve(mech, theta, order=2)
    f = forces_of(s, mech.params(), motion, masses, loads)
    ok = f.valid
    assert ok.sum() >= 3
    scale = np.max(np.abs(f.input_torque[ok]))
    # Both sides are sums of the same products; their rounding is a few eps of the largest
    # term, and the system's conditioning (the examples stay away from their limits) less
    # than 1e3: 1e-9 of the largest torque holds with a wide margin.
    assert np.max(np.abs(f.input_torque - f.energy_torque)[ok]) <= 1e-9 * scale


def _rocker_angle(positions: dict[str, np.ndarray], b0: np.ndarray) -> np.ndarray:
    """The output's angle about its ground axis B0, from B's positions alone."""
    ref = np.array([0.0, 0.0, 1.0]) if abs(b0[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    t = np.cross(b0, ref)
    t /= np.linalg.norm(t)
    n = np.cross(b0, t)
    b = positions["B"]
    return np.unwrap(np.arctan2(b @ n, b @ t))


def _spectral(values: np.ndarray, order: int) -> np.ndarray:
    """The ``order``-th derivative of a periodic sampling over 2π (its mean slope kept)."""
    n = len(values)
    x = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    slope = 0.0
    if order and abs(values[-1] - values[0]) > np.pi:
        slope = (values[-1] - values[0]) * n / ((n - 1) * 2 * np.pi)
    periodic = values - slope * x
    k = np.fft.fftfreq(n, 1.0 / n)
    out = np.fft.ifft((1j * k) ** order * np.fft.fft(periodic)).real
    return out + (slope if order == 1 else 0.0)


def test_an_isotropic_rocker_gives_paper_003s_reduced_inertia():
    """A rocker whose mass sits on its own axis with an isotropic tensor J about its centre
    turns about B0 only: Euler gives J φ3̈, so the torque is paper 003's M^i = ω² J φ3′ φ3″."""
    fb = SphericalFourBar(*np.radians([50.0, 20.0, 45.0, 35.0]))
    assert bool(input_range(fb).full)
    j, speed, radius = 0.02, 90.0, 0.2
    masses = {"rocker": MassProps(1.5, (radius, 0.0, 0.0), tensor=tuple(map(tuple, j * np.eye(3))))}
    theta = np.linspace(0.0, 2 * np.pi, 256, endpoint=False)
    motion = solve(fb, theta, order=2)
    s = body_structure(fb.plan)
    f = forces_of(s, fb.params(), motion, masses, Loads(speed_rpm=speed, radius=radius))
    phi = _rocker_angle(motion.positions, motion.positions["B0"][0])
    omega = speed * 2 * np.pi / 60
    expected = omega**2 * j * _spectral(phi, 1) * _spectral(phi, 2)
    np.testing.assert_allclose(f.input_torque, expected, atol=1e-9 * np.max(np.abs(expected)))


def test_a_full_turn_at_constant_speed_returns_its_work():
    """No gravity, no loads, constant speed: the kinetic energy is periodic, so the input's work
    over a turn, ∫T dθ, vanishes (trapezoid over a periodic sampling: spectrally exact)."""
    mech = load_example("paper000-fig6-crank-rocker").mechanism
    s = body_structure(mech.plan)
    masses = _masses(s, np.random.default_rng(3), 0.5)
    theta = np.linspace(0.0, 2 * np.pi, 512, endpoint=False)
    f = forces_of(
        s, mech.params(), solve(mech, theta, order=2), masses, Loads(speed_rpm=200, radius=0.5)
    )
    assert f.valid.all()
    work = np.mean(f.input_torque) * 2 * np.pi
    assert abs(work) <= 1e-9 * np.mean(np.abs(f.input_torque)) * 2 * np.pi
    # The kinetic energy returns too.
    assert np.ptp(f.kinetic) > 0


def test_the_shaking_force_is_the_momentum_rate_by_differences():
    """Σ of the frame's bearing forces is determinate even where each is not: it balances the
    links' momentum rate, here from central differences of the centres' solved positions."""
    mech = load_example("paper000-fig8-sixbar").mechanism
    s = body_structure(mech.plan)
    radius, speed = 0.3, 60.0
    masses = {b.name: MassProps(1.0 + k) for k, b in enumerate(s.bodies) if len(b.joints) == 2}
    g = np.array([0.0, -9.81, 2.0])
    theta = np.radians(np.arange(0.0, 360.0, 15.0))
    f = forces_of(
        s,
        mech.params(),
        solve(mech, theta, order=2),
        masses,
        Loads(speed_rpm=speed, gravity=tuple(g), radius=radius),
    )

    def centres(t: np.ndarray) -> dict[str, np.ndarray]:
        pos = solve(mech, t, order=0).positions
        out = {}
        for b in s.bodies:
            if b.name not in masses:
                continue
            p, q = pos[b.frame[0]], pos[b.frame[1]]
            beta = np.arccos(np.clip(np.sum(p * q, -1), -1, 1))[..., None]
            bisector = (p + q) / np.linalg.norm(p + q, axis=-1, keepdims=True)
            out[b.name] = radius * np.sin(beta / 2) / (beta / 2) * bisector
        return out

    h = 1e-3
    c_m2, c_m1, c_p1, c_p2 = (centres(theta + k * h) for k in (-2, -1, 1, 2))
    c_0 = centres(theta)
    omega = speed * 2 * np.pi / 60
    total = np.zeros(theta.shape + (3,))
    for name, m in masses.items():
        second = (-c_p2[name] + 16 * c_p1[name] - 30 * c_0[name] + 16 * c_m1[name] - c_m2[name]) / (
            12 * h * h
        )
        total += m.mass * (omega**2 * second - g)
    scale = np.max(np.abs(total))
    np.testing.assert_allclose(-f.shaking_force, total, atol=1e-6 * scale)


def _run(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def _document(tmp_path, extra: str):
    text = load_example("paper000-fig6-crank-rocker").raw
    from linkwright.io.documents import save_document

    path = tmp_path / "sphere.toml"
    save_document(text, path)
    path.write_text(path.read_text() + extra)
    return path


def test_linkwright_forces_on_a_spherical_document(tmp_path):
    path = _document(
        tmp_path,
        "\n[mechanism.mass]\ncrank = 0.2\nrocker = 0.4\n"
        "coupler = { mass = 0.5, centre = { x = 0.08, y = 0.02, z = 0.0 }, "
        "inertia = [[2e-4, 0, 0], [0, 3e-4, 0], [0, 0, 4e-4]] }\n"
        "\n[loads]\nspeed = 120\ngravity = [0.0, 0.0, -9.81]\nradius = 0.1\n",
    )
    code, out, err = _run("forces", str(path), "--input", "0:350:10", "--json")
    assert code == 0, err
    rows = json.loads(out)["samples"]
    assert len(rows) == 36
    for row in rows:
        assert row["input_torque"] == pytest.approx(row["energy_torque"], rel=1e-9, abs=1e-12)
        assert set(row["reactions"]) == set(row["moments"]) == {"A0", "A", "B", "B0"}
        assert len(row["shaking_force"]) == len(row["shaking_moment"]) == 3
    code, out, _ = _run("forces", str(path), "--input", "0", "--csv")
    assert code == 0 and "A0.mx" in out.splitlines()[0]


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ("\n[loads]\nspeed = 60\ntorques = [{ link = \"rocker\", value = 1.0 }]\n",
         "loads.torques: not on the sphere yet"),
        ("\n[loads]\nspeed = 60\nradius = -1\n", "loads.radius: must be positive"),
        ("\n[loads]\ngravity = [0.0, -9.81]\n", "loads.gravity: must be a vector [x, y, z]"),
        ("\n[mechanism.mass]\nrocker = { mass = 1.0, centre = { x = 0.1 }, "
         "inertia = [[1, 2, 0], [0, 1, 0], [0, 0, 1]] }\n[loads]\nspeed = 60\n",
         "mechanism.mass.rocker.inertia: must be symmetric"),
        ("\n[mechanism.mass]\nrocker = { mass = 1.0, centre = { x = 0.1 }, "
         "inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 3]] }\n[loads]\nspeed = 60\n",
         "exceeds the sum of the other two"),
        ("\n[mechanism.mass]\nrocker = { mass = 1.0, centre = { x = 0.1 } }\n[loads]\nspeed = 60\n",
         "mechanism.mass.rocker.inertia: missing"),
    ],
)  # fmt: skip
def test_bad_spherical_masses_and_loads_end_in_one_line(tmp_path, extra, words):
    path = _document(tmp_path, extra)
    code, _, err = _run("forces", str(path), "--input", "0")
    assert code != 0
    assert words in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_a_ternary_spherical_link_needs_its_tensor():
    mech = load_example("paper000-fig8-sixbar").mechanism
    s = body_structure(mech.plan)
    with pytest.raises(ForcesInputError, match="needs its centre and inertia tensor"):
        masses_from({"coupler": 1.0}, s, {})
    with pytest.raises(ForcesInputError, match="is a spherical linkage's"):
        loads_from({"radius": 2.0}, body_structure(load_example("crank-rocker").mechanism.plan), ())

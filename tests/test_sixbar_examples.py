"""The bundled six-bar and straight-line examples: they turn fully, load as documents, and the
straight-line linkages (Watt, Chebyshev, Hoeken) trace the straight lines their closed forms
promise.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from sixbar_helpers import EXAMPLE_NAMES, EXAMPLES, FAR_PIVOT, assert_closes, cross, example

from linkwright.mechanisms import (
    input_range,
    solve,
)


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_sixbar_examples_turn_fully(name):
    """Each six-bar example assembles, regular, over its whole crank turn, its second dyad well
    away from its limits (sin of the angle at D above 0.6)."""
    text = (EXAMPLES / f"{name}.toml").read_text()
    assert text.startswith("# ")
    doc = tomllib.loads(text)
    assert doc["format"] == "linkwright/1" and doc["title"]
    m = example(name)
    assert type(m).family == doc["mechanism"]["family"]
    motion = solve(m, np.linspace(-np.pi, np.pi, 7200, endpoint=False), order=2)
    assert motion.valid.all() and motion.regular.all()
    assert_closes(m, motion)
    p = motion.positions
    X = p[FAR_PIVOT[type(m)]]
    sin_d = np.abs(cross(p["C"] - p["D"], X - p["D"])) / (m.link1 * m.link2)
    assert sin_d.min() > 0.6
    arcs = input_range(m)
    assert arcs.full and not arcs.never
    # The four-bar they share: Grashof with the crank shortest (a crank-rocker).
    s, *_, longest = sorted([float(m.frame), float(m.crank), float(m.coupler), float(m.rocker)])
    assert s == m.crank and s + longest < float(m.frame + m.coupler + m.rocker) - longest


@pytest.mark.parametrize(
    "name",
    EXAMPLE_NAMES + ("watt-straight-line", "chebyshev-straight-line", "hoeken-straight-line"),
)
def test_examples_load_as_documents(name):
    """Where the io layer knows the family, the document builds the same mechanism."""
    from linkwright.io.documents import FAMILY_SPECS, load_example

    mine = example(name)
    if type(mine).family not in FAMILY_SPECS:
        pytest.skip(f"no document schema for {type(mine).family!r} yet")
    loaded = load_example(name).mechanism
    assert type(loaded) is type(mine)
    for key, value in mine.params().items():
        np.testing.assert_array_equal(getattr(loaded, key), value, err_msg=key)


def test_watt_straight_line():
    """Watt's linkage (levers 4, link 2, the link's midpoint traced): over a travel of ±0.8 (a
    fifth of a lever) the midpoint strays at most 6.7e-4 (0.017 % of a lever) from the line
    x = 0; halving the travel divides that by about 2^5 (the symmetric linkage's midpoint is
    an undulation point: the deviation is of fifth order in the travel)."""
    m = example("watt-straight-line")
    motion = solve(m, np.linspace(-0.4, 0.4, 40001), order=0)
    assert motion.valid.all()
    P = motion.positions["P"]
    np.testing.assert_allclose(P[20000], [0.0, 0.0], atol=1e-15)  # the middle position
    deviation = {}
    for travel in (0.8, 0.4):
        inside = np.abs(P[:, 1]) <= travel
        assert P[inside, 1].min() < -0.99 * travel and P[inside, 1].max() > 0.99 * travel
        deviation[travel] = np.abs(P[inside, 0]).max()
    assert 6.6e-4 < deviation[0.8] < 6.8e-4
    assert 1 / 40 < deviation[0.4] / deviation[0.8] < 1 / 25


def test_chebyshev_straight_line():
    """Chebyshev's linkage (frame 4, crossed levers 5, coupler 2, its midpoint traced): exact at
    (4, 4), (2, 4) and (0, 4); between, 0 ≤ y − 4 ≤ 0.00976, so the best line, y = 4.0049, is
    within 0.1 % of a lever (0.0049 of 5) over the whole stroke from x = 4 to x = 0."""
    m = example("chebyshev-straight-line")
    lo, hi = math.atan2(3, 4), math.pi / 2  # one lever vertical at each end
    theta = np.linspace(lo, hi, 20001)
    motion = solve(m, theta, order=0)
    assert motion.valid.all()
    P = motion.positions["P"]
    np.testing.assert_allclose(P[0], [4.0, 4.0], atol=1e-14)
    np.testing.assert_allclose(P[-1], [0.0, 4.0], atol=1e-14)
    assert np.all(np.diff(P[:, 0]) < 0)  # a stroke from x = 4 to x = 0
    # The middle: x = 2 by bisection, where y = 4 again.
    a, b = lo, hi
    for _ in range(60):
        mid = 0.5 * (a + b)
        x = solve(m, [mid], order=0).positions["P"][0, 0]
        a, b = (mid, b) if x > 2 else (a, mid)
    np.testing.assert_allclose(solve(m, [a], order=0).positions["P"][0], [2.0, 4.0], atol=1e-12)
    rise = P[:, 1] - 4.0
    assert rise.min() > -1e-14 and 0.00975 < rise.max() < 0.00976
    assert (rise.max() - rise.min()) / 2 < 1e-3 * m.crank


def test_hoeken_straight_line():
    """Hoeken's linkage (crank 1, frame 2, coupler 2.5, rocker 2.5, P at 5 along the coupler):
    over the half turn of the crank centred on 180°, P runs from (4, 4) to (0, 4) within 0.00976
    of y = 4, the same band as Chebyshev's linkage, of which it is a cognate."""
    m = example("hoeken-straight-line")
    motion = solve(m, np.linspace(np.pi / 2, 3 * np.pi / 2, 20001), order=1)
    assert motion.valid.all()
    P = motion.positions["P"]
    np.testing.assert_allclose(P[0], [4.0, 4.0], atol=1e-14)
    np.testing.assert_allclose(P[-1], [0.0, 4.0], atol=1e-14)
    rise = P[:, 1] - 4.0
    assert rise.min() > -1e-14 and 0.00975 < rise.max() < 0.00976
    speed = -motion.velocities["P"][:, 0]  # P runs toward −x as the crank turns on
    assert speed.min() > 1.0 - 1e-9 and speed.max() < 1.34
    cheb = example("chebyshev-straight-line")
    band = solve(cheb, np.linspace(math.atan2(3, 4), math.pi / 2, 20001), order=0)
    np.testing.assert_allclose(rise.max(), band.positions["P"][:, 1].max() - 4.0, rtol=1e-6)

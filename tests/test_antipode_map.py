"""A Lambert map whose centre has a drawn point at its antipode (issue 20.4).

The map's centre is the mean direction of the curves drawn; the antipode of the centre is the
whole rim of the map, so :func:`~linkwright.geometry.sphere.lambert_azimuthal` refuses a point
there. A spherical six-bar whose second dyad's arcs sum to 180° put one there: its traced point
runs on the crank pin's circle (C = A, D = C), whose mean is A0, and its pivot E0 sits at −A0
(145° beyond B0, which is 35° from A0, on one great circle). The workbench answered 422 "a point
lies at the antipode" and ``linkwright plot`` an internal error. The centre is now tilted, by
the least of a few angles, until every drawn point keeps clear of its antipode.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linkwright.geometry.sphere import CLEAR, clear_centre, lambert_azimuthal, map_frame
from linkwright.io import parse_document
from linkwright.plot import save_figure
from linkwright.plot.view import plot_mechanism
from linkwright.server import scene as scenes

OPPOSITE = {
    "format": "linkwright/1",
    "mechanism": {
        "family": "spherical-sixbar", "frame": 35.0, "crank": 20.0, "coupler": 42.0,
        "rocker": 30.0, "point": {"arc": 0.0, "angle": 0.0}, "link5": 100.0, "link6": 80.0,
        "ground": {"arc": 145.0, "angle": 0.0}, "d": {"arc": 0.0, "angle": 0.0},
        "assembly": -1, "assembly2": 1,
    },
}  # fmt: skip


def test_the_sixbar_pivot_is_opposite_its_curves_mean():
    """The premise, measured: the mean of the traced curve is A0 and E0 is −A0, to rounding
    (so that a map centred on that mean cannot place E0)."""
    m = parse_document(OPPOSITE).mechanism
    e0 = m.params()["E0"]
    np.testing.assert_allclose(e0, [-1.0, 0.0, 0.0], atol=1e-15)
    with pytest.raises(ValueError, match="antipode"):
        lambert_azimuthal(e0[None], [1.0, 0.0, 0.0])


def test_workbench_scene_maps_a_pivot_opposite_the_curves():
    out = json.loads(scenes.to_json(scenes.scene(OPPOSITE)))
    centre = np.array(out["map_center"])
    assert abs(np.linalg.norm(centre) - 1.0) < 1e-9
    # Tilted off A0 by the least tilt tried (2°), every mapped point finite, inside the disc.
    assert np.degrees(np.arccos(np.clip(centre[0], -1.0, 1.0))) == pytest.approx(2.0, abs=1e-6)
    mode = out["modes"][0]["circuits"][0]
    for xy in mode["map"].values():
        xy = np.array(xy, dtype=float)
        assert np.isfinite(xy).all() and np.all(np.hypot(*xy.T) <= 2.0 + 1e-12)


def test_plot_draws_a_pivot_opposite_the_curves(tmp_path):
    fig = plot_mechanism(parse_document(OPPOSITE).mechanism, samples=90)
    save_figure(fig, tmp_path / "six.png")
    assert (tmp_path / "six.png").stat().st_size > 0


def test_clear_centre_keeps_a_clear_centre_and_tilts_the_least():
    np.testing.assert_array_equal(clear_centre([0, 0, 3.0], [[1.0, 0, 0], [np.nan] * 3]), [0, 0, 1])
    c = clear_centre([0.0, 0.0, 1.0], [[0.0, 0.0, -1.0]])
    assert 1.0 + c[2] * -1.0 >= CLEAR
    assert np.degrees(np.arccos(c[2])) == pytest.approx(2.0)


@settings(max_examples=40, deadline=None)
@given(
    centre=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    others=st.lists(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), max_size=6),
)
def test_clear_centre_leaves_every_point_mappable(centre, others):
    """Whatever the points (one of them the centre's antipode), the centre returned keeps
    each point at least CLEAR from its antipode when a tilt of at most 90° can, and the map
    places every point then."""
    c0 = np.array(centre)
    if np.linalg.norm(c0) < 1e-3:
        c0 = np.array([0.0, 0.0, 1.0])
    c0 = c0 / np.linalg.norm(c0)
    pts = np.array([-c0] + [p for p in others if np.linalg.norm(p) > 1e-3]).reshape(-1, 3)
    pts = pts / np.linalg.norm(pts, axis=1, keepdims=True)
    c = clear_centre(c0, pts)
    assert abs(np.linalg.norm(c) - 1.0) < 1e-12
    # Seven points at most, so some bearing of the 2° tilt keeps clear of them all: the eight
    # tilted antipodes are 1.5° apart, and a point within 0.08° of one is far from the rest.
    assert np.min(1.0 + pts @ c) >= CLEAR
    xy = lambert_azimuthal(pts, c)
    assert np.isfinite(xy).all()
    east, _ = map_frame(c)
    assert np.isfinite(east).all()

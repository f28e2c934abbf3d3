"""Animations: every family's example becomes a GIF that decodes, loops and moves; a rocking
input's film runs up and back so that it loops without a jump; MP4 needs ffmpeg and says so;
a render that fails leaves no file behind. Kept lean: few frames, low resolution."""

from __future__ import annotations

import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from family_examples import FAMILY_EXAMPLES, family_of
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from PIL import Image, ImageChops

import linkwright
from linkwright.io import load_document
from linkwright.mechanisms import (
    FAMILIES,
    FourBar,
    GearedFiveBar,
    input_range,
)
from linkwright.plot import animation_scene, animation_sphere, animation_writers
from linkwright.plot.animation import AnimationError, animate

EXAMPLES = Path(linkwright.__file__).parent / "examples"
FRAMES = 8
DPI = 40
WIDTH = 256  # 6.4 inches at 40 dpi

EXAMPLE_OF = {key: f"{name}.toml" for key, name in FAMILY_EXAMPLES.items()}

CRANK_ROCKER = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
# rocker-input.toml: the 3.5 link driven, the 1 link turning fully; the input rocks.
ROCKER_INPUT = FourBar(A0=[0, 0], B0=[4, 0], crank=3.5, coupler=5, rocker=1, u=2, v=1)
NEVER = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)


def frames_of(path: Path) -> tuple[list[Image.Image], list[int], dict]:
    """Every frame (decoded to RGB), each frame's delay (ms) and the first frame's info."""
    images, delays = [], []
    with Image.open(path) as gif:
        info = dict(gif.info)
        for k in range(gif.n_frames):
            gif.seek(k)
            images.append(gif.convert("RGB"))
            delays.append(int(gif.info["duration"]))
    return images, delays, info


def test_the_examples_cover_every_family() -> None:
    families = {family_of(name) for name in EXAMPLE_OF}
    assert families == set(FAMILIES)
    for name, file in EXAMPLE_OF.items():
        mechanism = load_document(EXAMPLES / file).mechanism
        family = family_of(name)
        space = name[len(family) + 1 :]
        assert mechanism.family == family
        assert space in ("", mechanism.space)


@pytest.mark.parametrize("name", sorted(EXAMPLE_OF))
def test_every_family_renders_a_looping_gif(name: str, tmp_path: Path) -> None:
    doc = load_document(EXAMPLES / EXAMPLE_OF[name])
    out = animate(doc.mechanism, tmp_path / "film.gif", frames=FRAMES, fps=20, dpi=DPI)
    assert out == tmp_path / "film.gif"
    images, delays, info = frames_of(out)
    assert len(images) == FRAMES
    assert info["loop"] == 0  # loops forever
    width, height = images[0].size
    assert width == WIDTH and height % 2 == 0 and height > 0.5 * WIDTH
    assert all(im.size == (width, height) for im in images)
    # The loop lasts frames / fps seconds, in whole hundredths.
    assert sum(delays) == pytest.approx(1000 * FRAMES / 20, abs=10)
    for a, b in zip(images, images[1:] + images[:1], strict=True):
        assert ImageChops.difference(a, b).getbbox() is not None  # the linkage moves
    assert sorted(p.name for p in tmp_path.iterdir()) == ["film.gif"]  # no temporary left


def test_a_rocking_input_runs_both_legs_and_loops_seamlessly(tmp_path: Path) -> None:
    loaded = load_document(EXAMPLES / "rocker-input.toml").mechanism
    assert isinstance(loaded, FourBar)
    for field in ("A0", "B0", "crank", "coupler", "rocker", "u", "v", "assembly"):
        np.testing.assert_array_equal(getattr(loaded, field), getattr(ROCKER_INPUT, field))
    frames = 12
    cycle = animation_scene.sample_cycle(ROCKER_INPUT, frames)
    theta = cycle.motion.input[cycle.frames]
    # The input's limits, by the cosine rule: coupler and rocker fold in line, |A B0| = 5 ± 1,
    # with |A B0|² = 3.5² + 4² − 2·3.5·4·cos θ. The machine's circuit is the arc below the frame.
    low, high = (-math.acos((3.5**2 + 4**2 - d**2) / (2 * 3.5 * 4)) for d in (6.0, 4.0))
    assert math.degrees(low) == pytest.approx(-106.07, abs=5e-3)  # as the document says
    assert theta[0] == pytest.approx(low, abs=1e-9)  # the film starts at a limit, exactly
    assert np.all((theta >= low - 1e-9) & (theta <= high + 1e-9))
    assert cycle.motion.input.max() == pytest.approx(high, abs=1e-9)
    # Up, then back: the input rises to the other limit and falls again, one reversal inside
    # the film, and the dyad runs on both branches.
    step = np.diff(theta)
    assert np.count_nonzero(np.diff(np.sign(step))) == 1
    assert step[0] > 0 and step[-1] < 0
    assert set(cycle.motion.branches["B"][cycle.frames]) == {1.0, -1.0}
    assert theta.max() > high - (high - low) / frames  # it gets to the far limit
    # Seamless: from the last frame back to the first is a step like the others, both for the
    # input and for the coupler point, and nowhere near the curve's size.
    p = cycle.motion.positions["P"][cycle.frames]
    moves = np.linalg.norm(np.diff(p, axis=0), axis=1)
    gap = float(np.linalg.norm(p[-1] - p[0]))
    assert gap <= 1.5 * moves.max()
    assert gap < 0.25 * float(np.ptp(p, axis=0).max())
    assert abs(theta[-1] - theta[0]) <= np.abs(step).max()
    # And each frame is a real pose: the link lengths hold.
    pos = {k: v[cycle.frames] for k, v in cycle.motion.positions.items()}
    for a, b, length in (("A0", "A", 3.5), ("A", "B", 5.0), ("B0", "B", 1.0)):
        np.testing.assert_allclose(np.linalg.norm(pos[b] - pos[a], axis=1), length, atol=1e-9)

    images, _, _ = frames_of(animate(ROCKER_INPUT, tmp_path / "rocking.gif", frames=12, dpi=DPI))
    assert len(images) == 12


def test_a_gear_ratio_runs_every_turn_before_the_film_loops() -> None:
    # Geared at 1/2 the linkage repeats after two input turns (period 4π): the film covers both.
    half = GearedFiveBar(A0=[0, 0], B0=[4, 0], crank1=1, crank2=1, link1=3, link2=3, ratio=0.5)
    cycle = animation_scene.sample_cycle(half, 8)
    theta = cycle.motion.input[cycle.frames]
    np.testing.assert_allclose(theta, np.arange(8) * 4 * np.pi / 8, atol=1e-12)
    labels = [animation_scene.angle_label(cycle, i) for i in range(8)]
    assert labels[3] == "θ = 270.0°  (turn 1 of 2)"
    assert labels[4] == "θ = 0.0°  (turn 2 of 2)"


@pytest.mark.parametrize("name", ["watt1", "spherical-sixbar"])
def test_the_axes_stay_fixed_and_hold_every_frame(name: str) -> None:
    mechanism = load_document(EXAMPLES / EXAMPLE_OF[name]).mechanism
    cycle = animation_scene.sample_cycle(mechanism, 10)
    build = (
        animation_sphere.sphere_scene
        if mechanism.space == "sphere"
        else animation_scene.plane_scene
    )
    scene = build(mechanism, cycle, "test", DPI)
    renderer = animation_writers.Renderer(scene)
    limits = (scene.ax.get_xlim(), scene.ax.get_ylim())
    shapes = {renderer.frame(i).shape for i in range(scene.frames)}
    assert (scene.ax.get_xlim(), scene.ax.get_ylim()) == limits
    assert len(shapes) == 1
    (x0, x1), (y0, y1) = limits
    box = scene.ax.get_window_extent()
    # Equal aspect: one unit is as long across as up.
    assert (x1 - x0) / box.width == pytest.approx((y1 - y0) / box.height, rel=1e-6)
    for p in cycle.motion.positions.values():
        pts = p[cycle.frames]
        if mechanism.space == "sphere":
            assert np.all(np.abs(pts) <= 1 + 1e-12)  # on the unit sphere, inside the ±1.12 view
            assert (x0, x1, y0, y1) == pytest.approx((-1.12, 1.12, -1.12, 1.12))
        else:
            assert np.all((pts[:, 0] > x0) & (pts[:, 0] < x1))
            assert np.all((pts[:, 1] > y0) & (pts[:, 1] < y1))


def test_progress_counts_the_frames(tmp_path: Path) -> None:
    seen: list[float] = []
    animate(CRANK_ROCKER, tmp_path / "a.gif", frames=5, dpi=DPI, progress=seen.append)
    assert seen == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0])


def test_an_interrupted_render_leaves_no_file(tmp_path: Path) -> None:
    def stop(fraction: float) -> None:
        if fraction >= 0.5:
            raise KeyboardInterrupt  # what Ctrl-C raises mid-render

    out = tmp_path / "films" / "a.gif"
    with pytest.raises(KeyboardInterrupt):
        animate(CRANK_ROCKER, out, frames=6, dpi=DPI, progress=stop)
    assert not out.exists()
    assert list(out.parent.iterdir()) == []

    # A file already there is kept whole until a complete film replaces it.
    out.write_bytes(b"the old film")
    with pytest.raises(KeyboardInterrupt):
        animate(CRANK_ROCKER, out, frames=6, dpi=DPI, progress=stop)
    assert out.read_bytes() == b"the old film"
    assert list(out.parent.iterdir()) == [out]


def test_mp4_without_ffmpeg_says_how_to_get_one(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(shutil, "which", lambda *args, **kwargs: None)
    with pytest.raises(AnimationError, match=r"install ffmpeg.*\.gif"):
        animate(CRANK_ROCKER, tmp_path / "a.mp4", frames=4, dpi=DPI)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not on PATH")
def test_mp4_with_ffmpeg(tmp_path: Path) -> None:
    out = animate(CRANK_ROCKER, tmp_path / "a.MP4", frames=6, fps=12, dpi=DPI)
    data = out.read_bytes()
    assert data[4:8] == b"ftyp"  # an ISO media file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.MP4"]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"out": "film.png"}, r"\.gif or an \.mp4, not '\.png'"),
        ({"out": "film"}, "without a suffix"),
        ({"frames": 1}, r"frames: must be an integer ≥ 2, got 1"),
        ({"frames": 2.5}, "frames: must be an integer"),
        ({"fps": 0}, "fps: must be an integer ≥ 1"),
        ({"fps": 60}, "at most 50 frames per second"),
        ({"dpi": 0}, "dpi: must be an integer"),
        ({"mechanism": NEVER}, "cannot be assembled at any input"),
        ({"mechanism": "crank-rocker.toml"}, "expected a linkwright Mechanism"),
        ({"mechanism": FourBar([0, 0], [4, 0], [1, 1.2], 5, 3.5)}, "batch shape"),
    ],
)
def test_bad_requests_are_refused_before_anything_is_written(
    kwargs: dict, match: str, tmp_path: Path
) -> None:
    args = {"mechanism": CRANK_ROCKER, "out": "film.gif", "dpi": DPI, **kwargs}
    with pytest.raises(AnimationError, match=match):
        animate(args.pop("mechanism"), tmp_path / args.pop("out"), **args)
    assert list(tmp_path.iterdir()) == []


def test_animation_error_is_a_value_error() -> None:
    assert issubclass(AnimationError, ValueError)


lengths = st.floats(0.4, 5.0)


@settings(max_examples=40, deadline=None)
@given(
    frame=lengths,
    crank=lengths,
    coupler=lengths,
    rocker=lengths,
    assembly=st.sampled_from([1.0, -1.0]),
    frames=st.integers(2, 30),
)
# A rhombus: A passes through B0 (its film once missed that pose, and now takes two turns).
@example(frame=1.0, crank=1.0, coupler=1.0, rocker=1.0, assembly=1.0, frames=19)
def test_random_four_bar_films_are_closed_cycles_of_real_poses(
    frame: float, crank: float, coupler: float, rocker: float, assembly: float, frames: int
) -> None:
    fourbar = FourBar(
        A0=[0, 0], B0=[frame, 0], crank=crank, coupler=coupler, rocker=rocker, assembly=assembly
    )
    arcs = input_range(fourbar)
    assume(not bool(arcs.never))
    cycle = animation_scene.sample_cycle(fourbar, frames)
    assert len(cycle.frames) == frames
    pos = {k: v[cycle.frames] for k, v in cycle.motion.positions.items()}
    theta = cycle.motion.input[cycle.frames]
    # Every pose is real, even where A passes through B0 (an exact rhombus or deltoid, where
    # the dyad alone leaves B anywhere on a circle: it is drawn as the limit of its neighbours).
    valid = cycle.motion.valid[cycle.frames]
    assert valid.all()
    scale = max(frame, crank, coupler, rocker)
    for a, b, length in (("A0", "A", crank), ("A", "B", coupler), ("B0", "B", rocker)):
        err = np.abs(np.linalg.norm(pos[b][valid] - pos[a][valid], axis=1) - length)
        assert err.max(initial=0.0) <= 1e-7 * scale
    if bool(arcs.full):
        # One turn in even steps, the wrap from the last frame to the first one more. Where A
        # passes through B0 the dyad comes back on its other branch after one turn: two turns,
        # each a segment starting exactly where A is on B0; an odd count of samples n leaves
        # one segment a sample short, so its steps are longer by 1/(n − 1) (and the other's
        # shorter by 1/(n + 1)).
        period = 2 * np.pi * cycle.turns
        exact = abs(frame - crank) <= 1e-12 * scale and abs(coupler - rocker) <= 1e-12 * scale
        assert cycle.turns == 1 or exact
        rtol = 1e-7 if cycle.turns == 1 else 1.0 / (cycle.motion.input.size - 1) + 1e-7
        steps = np.diff(np.r_[theta, theta[0] + period])
        np.testing.assert_allclose(steps, period / frames, rtol=rtol)
    else:
        # The film starts at a limit position: there the dyad A–B–B0 folds, |A B0| being the
        # sum or the difference of coupler and rocker.
        reach = float(np.linalg.norm(pos["A"][0] - pos["B0"][0]))
        fold = min(abs(reach - (coupler + rocker)), abs(reach - abs(coupler - rocker)))
        assert fold <= 1e-6 * scale
        # Up to the other limit and back: the wrap is no bigger a step than those in the film.
        if frames > 2:
            steps = np.abs(np.diff(theta))
            assert abs(theta[-1] - theta[0]) <= steps.max() + 1e-12


def test_a_rhombus_film_runs_through_its_fold(tmp_path: Path) -> None:
    # A rhombus has A on B0 at θ = 0, where the dyad alone leaves B anywhere on a circle. The
    # film runs through it on the branch it is on (B = A + B0 − A0, the parallelogram, there
    # (2, 0)), and takes two turns to repeat: the dyad's sign flips each time A passes B0.
    rhombus = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=1, rocker=1, u=0.5, v=0.3)
    cycle = animation_scene.sample_cycle(rhombus, 6)
    assert cycle.motion.valid[cycle.frames].all() and cycle.turns == 2
    np.testing.assert_allclose(cycle.motion.positions["B"][cycle.frames[0]], [2.0, 0.0])
    assert animation_scene.angle_label(cycle, 0) == "θ = 0.0°  (turn 1 of 2)"
    images, _, _ = frames_of(animate(rhombus, tmp_path / "r.gif", frames=6, dpi=DPI))
    assert len(images) == 6


def test_a_pose_that_does_not_assemble_says_so() -> None:
    # No traced circuit leaves a pose out any more; should one (a joint a rounding error from
    # undetermined), its frame shows the ground and says so.
    rhombus = FourBar(A0=[0, 0], B0=[1, 0], crank=1, coupler=1, rocker=1, u=0.5, v=0.3)
    cycle = animation_scene.sample_cycle(rhombus, 6)
    valid = cycle.motion.valid.copy()
    valid[cycle.frames[1]] = False
    holed = replace(cycle, motion=replace(cycle.motion, valid=valid))
    assert animation_scene.angle_label(holed, 1) == "θ = 120.0°  (turn 1 of 2)\nnot assembled here"

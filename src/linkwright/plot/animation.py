"""Animations of a linkage running its circuit, written as a looping GIF or an MP4 film.

Each frame shows the linkage at one input of the closed circuit the machine runs
(:func:`linkwright.mechanisms.circuit`): a full turn where the input turns fully (several where
a gear ratio makes the linkage repeat only after several turns), else up to one limit position
and back down through the other branch of the dyad at that limit, so that the last frame leads
smoothly into the first and the film loops without a jump. The traced joints' curves are drawn
faintly in full and boldly as far as the linkage has come, and the input angle is written in a
corner. Planar linkages are drawn in the plane with fixed, equal-aspect axes that hold every
frame; spherical ones on an orthographic view of the unit sphere
(:class:`~linkwright.plot.sphere.SphereView` from :func:`~linkwright.plot.sphere.default_view`),
links as great-circle arcs, whatever lies on the far hemisphere dashed and faded.

Rendering is incremental: the figure, the backdrop and every artist are built once, the still
part is rendered once, and each frame only moves the artists' data and redraws them over it
(blitting) instead of redrawing the whole figure. Frames go to Pillow
(GIF, one shared palette, looping forever) or through matplotlib's
:class:`~matplotlib.animation.FFMpegWriter` to ffmpeg (MP4, H.264). The file is written under a
temporary name beside the destination and renamed over it at the end, so an interrupted render
never leaves a partial file at the destination.

This module holds the verb and its checks; the cycle and the planar scene are in
:mod:`linkwright.plot.animation_scene`, the spherical scene in
:mod:`linkwright.plot.animation_sphere` and the GIF and MP4 writers in
:mod:`linkwright.plot.animation_writers`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from linkwright.files import atomic_path
from linkwright.mechanisms import Mechanism
from linkwright.plot.animation_scene import (
    AnimationError,
    plane_scene,
    sample_cycle,
)
from linkwright.plot.animation_sphere import sphere_scene
from linkwright.plot.animation_writers import find_ffmpeg, write_gif, write_mp4

__all__ = ["AnimationError", "animate"]


FORMATS = {".gif": "gif", ".mp4": "mp4"}
GIF_MAX_FPS = 50  # GIF delays are in hundredths of a second; viewers slow delays under 0.02 s


# --------------------------------------------------------------------------------------------
# The verb
# --------------------------------------------------------------------------------------------


def _positive_int(name: str, value: Any, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise AnimationError(f"{name}: must be an integer ≥ {least}, got {value!r}")
    return int(value)


def _check_mechanism(mechanism: Any) -> None:
    if not isinstance(mechanism, Mechanism):
        raise AnimationError(f"mechanism: expected a linkwright Mechanism, got {mechanism!r}")
    if mechanism.batch_shape != ():
        raise AnimationError(
            f"mechanism: animate one linkage at a time, this one has batch shape "
            f"{mechanism.batch_shape}"
        )
    try:
        mechanism.plan  # noqa: B018 - some inputs leave no construction plan
    except ValueError as exc:
        raise AnimationError(f"mechanism: cannot be animated: {exc}") from None


def animate(
    mechanism: Mechanism,
    out: str | os.PathLike[str],
    *,
    frames: int = 120,
    fps: int = 30,
    title: str | None = None,
    dpi: int = 100,
    progress: Callable[[float], None] | None = None,
) -> Path:
    """Write a film of the linkage running its closed circuit: a looping GIF or an MP4.

    Frame k shows the linkage at the k-th of ``frames`` poses spread evenly over the circuit the
    machine runs (:func:`~linkwright.mechanisms.circuit`): one full turn of the input (several
    where a gear ratio makes the linkage repeat only after several), or, where the input cannot
    turn fully, up to its limit and back down on the other branch, so that the last frame leads
    into the first and the film loops seamlessly. Links are drawn as lines, ternary links as
    filled plates, ground pivots on hatched ground symbols, sliders as blocks on dashed guides,
    joints as circles with their letters; the traced joints' curves are drawn faintly in full
    and boldly from the start of the circuit to the current pose, and the input angle θ
    (degrees) is written in the top left corner, with "up"/"back" for a rocking input. The axes
    are fixed over the film (they hold every pose) with equal aspect. A spherical linkage is
    drawn on the unit sphere seen from :func:`~linkwright.plot.sphere.default_view`, links as
    great-circle arcs, its far-side parts dashed and faded.

    Parameters
    ----------
    mechanism : Mechanism
        One planar or spherical linkage of any family (batch shape ``()``).
    out : str or os.PathLike
        Destination; its suffix chooses the format: ``.gif`` (Pillow; loops forever) or ``.mp4``
        (H.264 through ffmpeg, which must be on ``PATH``). Missing parent folders are created.
        The film is written under a temporary name in the same folder and renamed over ``out``
        when complete, so a render that fails or is interrupted leaves no partial file there.
    frames : int
        Number of frames, at least 2.
    fps : int
        Frames per second, at least 1 (at most 50 for a GIF, whose delays are whole hundredths
        of a second: they are spread so that the loop lasts ``frames / fps`` seconds).
    title : str, optional
        Heading of every frame; default the mechanism's family.
    dpi : int
        Resolution: frames are 6.4 inches wide, so ``6.4 · dpi`` pixels (rounded to an even
        count; the height follows the drawing and is even too).
    progress : callable, optional
        Called with the fraction of frames done (in (0, 1]) after each frame is rendered. An
        exception it raises stops the render (and no file is written).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    AnimationError
        For an unknown suffix, an ``.mp4`` without ffmpeg, ``frames < 2`` or another bad
        argument, a batch of mechanisms, a mechanism without a construction plan, or a linkage
        that cannot be assembled at any input.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> from linkwright.mechanisms import FourBar
    >>> crank_rocker = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=5, rocker=3.5, u=2, v=1)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = animate(crank_rocker, Path(folder) / "crank-rocker.gif", frames=6, dpi=40)
    ...     with Image.open(path) as gif:
    ...         print(path.name, gif.n_frames, gif.size, gif.info["loop"])
    crank-rocker.gif 6 (256, 220) 0

    A linkage that cannot be assembled has no motion to show:

    >>> too_short = FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)
    >>> animate(too_short, "never.gif")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.plot.animation_scene.AnimationError: mechanism: this linkage cannot be assembled ...
    """
    path = Path(out)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise AnimationError(
            f"out: write a .gif or an .mp4, not {path.suffix or 'a file without a suffix'!r}"
        )
    frames = _positive_int("frames", frames, 2)
    fps = _positive_int("fps", fps, 1)
    dpi = _positive_int("dpi", dpi, 10)
    if fmt == "gif" and fps > GIF_MAX_FPS:
        raise AnimationError(
            f"fps: a GIF plays at most {GIF_MAX_FPS} frames per second (its delays are whole "
            f"hundredths of a second, and viewers slow shorter ones), got {fps}; write an .mp4"
        )
    if fmt == "mp4":
        find_ffmpeg()
    if path.is_dir():
        raise AnimationError(f"out: {str(path)!r} is a folder, not a file name")
    if progress is not None and not callable(progress):
        raise AnimationError(f"progress: must be callable, got {progress!r}")
    _check_mechanism(mechanism)
    cycle = sample_cycle(mechanism, frames)
    head = title if title is not None else mechanism.family
    if mechanism.space == "sphere":
        scene = sphere_scene(mechanism, cycle, head, dpi)
    else:
        scene = plane_scene(mechanism, cycle, head, dpi)

    with atomic_path(path) as temp:
        if fmt == "gif":
            write_gif(scene, temp, fps, progress)
        else:
            write_mp4(scene, temp, fps, progress)
    return path

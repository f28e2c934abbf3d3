"""Writing an animation's frames to a file: a looping GIF through Pillow (one shared palette
for every frame) or an MP4 film through matplotlib's
:class:`~matplotlib.animation.FFMpegWriter` and ffmpeg (H.264).

Rendering is incremental: the still part of the scene is rendered once, and each frame only
moves the artists' data and redraws them over it (blitting) instead of redrawing the whole
figure.
"""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess
from pathlib import Path
from typing import Protocol

import matplotlib as mpl
import numpy as np
from matplotlib.animation import FFMpegWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.transforms import BboxBase
from numpy.typing import NDArray
from PIL import Image

from linkwright.plot.animation_scene import AnimationError, Progress, Scene, exact_figure

__all__ = ["Renderer", "find_ffmpeg", "write_gif", "write_mp4"]


class _BlitCanvas(Protocol):
    """The Agg canvas's blitting methods, as :class:`Renderer` uses them (matplotlib leaves
    FigureCanvasAgg's methods unannotated)."""

    def draw(self) -> None: ...
    def copy_from_bbox(self, bbox: BboxBase) -> object: ...
    def restore_region(self, region: object) -> None: ...
    def buffer_rgba(self) -> memoryview: ...


def _blit_canvas(fig: Figure) -> _BlitCanvas:
    canvas = fig.canvas
    assert isinstance(canvas, FigureCanvasAgg)  # exact_figure gives every scene an Agg canvas
    return canvas


class Renderer:
    """Draws the still part of a scene once, then each frame's moving artists over a copy."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.canvas = _blit_canvas(scene.fig)
        for art in scene.dynamic:
            art.set_animated(True)  # left out of the full draw below: that is the backdrop
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(scene.fig.bbox)
        self.order = sorted(scene.dynamic, key=lambda a: a.get_zorder())

    def frame(self, i: int) -> NDArray[np.uint8]:
        """Frame ``i`` as an RGBA array (height, width, 4), opaque."""
        self.scene.update(i)
        self.canvas.restore_region(self.background)
        for art in self.order:
            self.scene.fig.draw_artist(art)
        return np.array(self.canvas.buffer_rgba(), dtype=np.uint8)


def _durations(frames: int, fps: int) -> list[int]:
    """Per-frame GIF delays (ms, whole hundredths of a second) whose running sum stays within
    half a hundredth of ``k / fps``, so the loop lasts exactly ``frames / fps`` seconds."""
    ticks = [round(k * 100 / fps) for k in range(frames + 1)]
    return [10 * (b - a) for a, b in itertools.pairwise(ticks)]


class _Palette:
    """One 256-colour palette for a whole GIF, and exact pixel → index mapping onto it.

    A frame is mostly a few flat colours (paper, links, plates, curves) and their antialiased
    blends. The most frequent colours of a few sample frames go into the palette as they are,
    so they come out unchanged; the rest of the palette is an octree quantisation of the
    remaining pixels. Every colour met is mapped once to its nearest palette entry (RGB
    distance) and remembered in a table indexed by the 24-bit colour. (Pillow's own mapping onto
    a given palette looks colours up at reduced precision, which turns white paper grey.)
    """

    EXACT = 192

    def __init__(self, sample: NDArray[np.uint8]) -> None:
        codes = _codes(sample)
        uniq, counts = np.unique(codes, return_counts=True)
        keep = uniq[np.argsort(-counts, kind="stable")[: self.EXACT]]
        colours = [_decode(keep)]
        rest = sample[..., :3].reshape(-1, 3)[~np.isin(codes.ravel(), keep)]
        if len(rest):
            octree = Image.fromarray(np.ascontiguousarray(rest.reshape(-1, 1, 3))).quantize(
                256 - len(keep), method=Image.Quantize.FASTOCTREE
            )
            used = []
            for _, index in octree.getcolors() or []:
                assert isinstance(index, int)  # a "P" image's pixels are palette indices
                used.append(index)
            used.sort()
            table = np.array(octree.getpalette() or [], dtype=np.int64).reshape(-1, 3)
            colours.append(table[used])
        self.colours = np.concatenate(colours)[:256]
        self.flat = self.colours.astype(np.uint8).ravel().tolist()
        self.flat += self.flat[-3:] * (256 - len(self.colours))
        self.table = np.full(1 << 24, -1, dtype=np.int16)
        self.table[keep] = np.arange(len(keep))

    def image(self, rgba: NDArray[np.uint8]) -> Image.Image:
        codes = _codes(rgba)
        index = self.table[codes]
        missing = index < 0
        if missing.any():
            new = np.unique(codes[missing])
            d = ((_decode(new)[:, None, :] - self.colours[None, :, :]) ** 2).sum(-1)
            self.table[new] = d.argmin(axis=1)
            index = self.table[codes]
        out = Image.fromarray(index.astype(np.uint8))
        out.putpalette(self.flat)
        return out


def _codes(rgba: NDArray[np.uint8]) -> NDArray[np.uint32]:
    """The 24-bit colour of each opaque RGBA pixel: R + 256·G + 65536·B (one read per pixel)."""
    codes: NDArray[np.uint32] = np.bitwise_and(
        np.ascontiguousarray(rgba).view("<u4")[..., 0], np.uint32(0xFFFFFF)
    )
    return codes


def _decode(codes: NDArray[np.uint32]) -> NDArray[np.int64]:
    c = codes.astype(np.int64)
    return np.stack((c & 255, (c >> 8) & 255, (c >> 16) & 255), axis=-1)


def write_gif(scene: Scene, target: Path, fps: int, progress: Progress | None) -> None:
    renderer = Renderer(scene)
    n = scene.frames
    # One palette for the whole film, from frames spread over the cycle: the colours are the
    # same throughout, and a shared palette keeps them from flickering between frames.
    palette = _Palette(np.concatenate([renderer.frame(k) for k in sorted({0, n // 3, 2 * n // 3})]))
    images = []
    for i in range(n):
        images.append(palette.image(renderer.frame(i)))
        if progress is not None:
            progress((i + 1) / n)
    with open(target, "xb") as fh:
        images[0].save(
            fh,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            loop=0,
            duration=_durations(n, fps),
        )
        fh.flush()
        os.fsync(fh.fileno())


def find_ffmpeg() -> str:
    found = shutil.which(str(mpl.rcParams["animation.ffmpeg_path"]))
    if found is None:
        raise AnimationError(
            "out: writing an .mp4 needs ffmpeg, which was not found on PATH; install ffmpeg "
            "(e.g. `apt install ffmpeg`) or write a .gif instead"
        )
    return found


def write_mp4(scene: Scene, target: Path, fps: int, progress: Progress | None) -> None:
    renderer = Renderer(scene)
    n = scene.frames
    # The frames, already rendered, are shown full size on a bare figure of the same pixel
    # size: grabbing that costs a copy, where grabbing the scene itself would redraw it whole.
    height, width = renderer.frame(0).shape[:2]
    sink = exact_figure(width, height, int(scene.fig.dpi))
    image = sink.figimage(np.zeros((height, width, 4), np.uint8), origin="upper")
    writer = FFMpegWriter(fps=fps, codec="h264")
    try:
        with writer.saving(sink, str(target), dpi=scene.fig.dpi):
            for i in range(n):
                image.set_data(renderer.frame(i))
                writer.grab_frame()
                if progress is not None:
                    progress((i + 1) / n)
    except subprocess.CalledProcessError as exc:
        raise AnimationError(f"out: ffmpeg failed to write the film: {exc}") from None
    with open(target, "rb") as fh:
        os.fsync(fh.fileno())

"""Force diagrams against the input: the driving torque, the joints' reactions, the shaking
force and moment on the frame (``linkwright plot --kind torque|reactions|shaking``).

The numbers are :mod:`linkwright.dynamics`'s over the document's circuit; this module only
draws them. The torque panel draws the energy balance's torque over Newton–Euler's as a check a
reader can see (the two lines coincide), and marks where the torque is largest.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from linkwright.dynamics import Forces
from linkwright.mechanisms import Mechanism
from linkwright.plot.style import family_name, new_figure

__all__ = ["FORCE_KINDS", "plot_forces"]

FORCE_KINDS = ("torque", "reactions", "shaking")

Array = NDArray[np.float64]


def _magnitude(vectors: Array) -> Array:
    out: Array = np.linalg.norm(vectors, axis=-1) if np.ndim(vectors) > 1 else np.abs(vectors)
    return out


def plot_forces(
    mechanism: Mechanism,
    result: Forces,
    kind: str,
    *,
    title: str | None = None,
    units: tuple[str, str] = ("N·m", "N"),
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """Draw one kind of force diagram of a solved :class:`~linkwright.dynamics.Forces`.

    Parameters
    ----------
    mechanism : the linkage the forces are of (for the title).
    result : forces over samples of one circuit (``result.input`` in radians, 1-D).
    kind : ``"torque"`` (Newton–Euler's driving torque with the energy balance's over it),
        ``"reactions"`` (each joint's reaction force magnitude; on the sphere also its reaction
        moment's) or ``"shaking"`` (the shaking force's magnitude and components, and the
        shaking moment).
    title : a heading; default the family's name.
    units : how the torque and the force are written on the axes.
    ax : axes to draw into (one, or two for ``reactions`` on the sphere and ``shaking``).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> from linkwright.dynamics import Loads, MassProps, forces
    >>> from linkwright.mechanisms import FourBar
    >>> fb = FourBar(A0=[0, 0], B0=[4, 0], crank=1, coupler=3.5, rocker=3)
    >>> f = forces(fb, np.linspace(0, 2 * np.pi, 73), {"rocker": 1.0}, Loads(speed_rpm=60))
    >>> fig = plot_forces(fb, f, "torque")
    >>> len(fig.axes), fig.axes[0].get_ylabel()
    (1, 'input torque (N·m)')

    A linkage that assembles nowhere has nothing to draw, and says so:

    >>> far = FourBar(A0=[0, 0], B0=[9, 0], crank=1, coupler=1, rocker=1)
    >>> fig = plot_forces(far, forces(far, [0.0, 1.0]), "torque")
    >>> fig.axes[0].texts[0].get_text()
    'no sample assembles'
    >>> plot_forces(fb, f, "bending")
    Traceback (most recent call last):
    ...
    ValueError: kind: expected one of torque, reactions, shaking; got 'bending'
    """
    if kind not in FORCE_KINDS:
        raise ValueError(f"kind: expected one of {', '.join(FORCE_KINDS)}; got {kind!r}")
    torque_unit, force_unit = units
    spherical = bool(result.moments)
    panels = 2 if (kind == "shaking" or (kind == "reactions" and spherical)) else 1
    if ax is None:
        fig = new_figure((8.0, 3.2 * panels))
        axes = list(fig.subplots(panels, 1, sharex=True, squeeze=False)[:, 0])
    else:
        axes = [ax] if isinstance(ax, Axes) else list(ax)
        if len(axes) != panels:
            raise ValueError(f"ax: the {kind!r} diagram draws {panels} panel(s), got {len(axes)}")
        fig = axes[0].get_figure()
    theta = np.degrees(np.asarray(result.input, dtype=float))
    ok = np.asarray(result.valid, dtype=bool)
    heading = title or family_name(mechanism)
    axes[0].set_title(f"{heading}: {kind}")
    axes[-1].set_xlabel("input angle θ (°)")
    if not ok.any():
        axes[0].text(0.5, 0.5, "no sample assembles", ha="center", transform=axes[0].transAxes)
        return fig

    def masked(values: Array) -> Array:
        return np.where(ok, values, np.nan)

    if kind == "torque":
        a = axes[0]
        a.plot(theta, masked(result.input_torque), lw=2.0, label="Newton–Euler")
        a.plot(theta, masked(result.energy_torque), "k--", lw=1.0, label="energy balance")
        peak = int(np.nanargmax(np.abs(masked(result.input_torque))))
        a.plot(theta[peak], result.input_torque[peak], "o", color="C3")
        a.annotate(
            f"{result.input_torque[peak]:.4g} at {theta[peak]:.1f}°",
            (theta[peak], result.input_torque[peak]),
            textcoords="offset points",
            xytext=(6, 6),
        )
        a.axhline(0.0, color="0.6", lw=0.6)
        a.set_ylabel(f"input torque ({torque_unit})")
        a.legend(loc="best", fontsize="small")
    elif kind == "reactions":
        for name, force in result.reactions.items():
            axes[0].plot(theta, masked(_magnitude(force)), label=name)
        axes[0].set_ylabel(f"|reaction| ({force_unit})")
        axes[0].legend(loc="best", fontsize="small", ncol=2)
        if spherical:
            # Statically indeterminate on the sphere: the least-norm set (dynamics.spherical).
            axes[0].legend(loc="best", fontsize="small", ncol=2, title="least-norm forces")
            for name, moment in result.moments.items():
                axes[1].plot(theta, masked(_magnitude(moment)), label=name)
            axes[1].set_ylabel(f"|reaction moment| ({torque_unit})")
            axes[1].legend(loc="best", fontsize="small", ncol=2)
    else:
        shaking = np.asarray(result.shaking_force)
        axes[0].plot(theta, masked(_magnitude(shaking)), "k", lw=2.0, label="|F|")
        for k, axis in enumerate("xyz"[: shaking.shape[-1]]):
            axes[0].plot(theta, masked(shaking[..., k]), lw=1.0, label=axis)
        axes[0].set_ylabel(f"shaking force ({force_unit})")
        axes[0].legend(loc="best", fontsize="small", ncol=4)
        moment = np.asarray(result.shaking_moment)
        if moment.ndim > 1:
            axes[1].plot(theta, masked(_magnitude(moment)), "k", lw=2.0, label="|M|")
            for k, axis in enumerate("xyz"):
                axes[1].plot(theta, masked(moment[..., k]), lw=1.0, label=axis)
            axes[1].legend(loc="best", fontsize="small", ncol=4)
            axes[1].set_ylabel(f"shaking moment about O ({torque_unit})")
        else:
            axes[1].plot(theta, masked(moment), "k", lw=1.5)
            axes[1].set_ylabel(f"shaking moment ({torque_unit})")
    for a in axes:
        a.grid(True, lw=0.4, alpha=0.6)
    return fig

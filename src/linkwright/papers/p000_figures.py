"""Paper 000 (Özçelik & Şaka): the linkages of its figures, the spherical crank-rocker
(Fig. 6), drag link (Fig. 7) and six-bar (Fig. 8), with the printed dimensions, and the
assembly modes in which Fig. 8's six-bar runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from linkwright.mechanisms import (
    SphericalFourBar,
    SphericalSixBar,
    input_range,
)
from linkwright.papers.p000_formulas import InvalidInput

__all__ = ["FIG6", "FIG7", "FIG8", "Fig8Mode", "fig8_modes", "figure_fourbar", "figure_sixbar"]

# Figure captions, degrees, in the paper's order and names.
FIG6 = {"a1": 40.0, "a2": 20.0, "a3": 45.0, "a4": 35.0, "AC": 50.0, "mu": 130.0}


FIG7 = {"a1": 30.0, "a2": 40.0, "a3": 42.0, "a4": 50.0, "AC": 30.0, "mu": -60.0}


FIG8 = {
    "a1": 35.0,
    "a2": 20.0,
    "a3": 42.0,
    "a4": 30.0,
    "AC": 72.0,
    "mu": 22.0,
    "a5": 45.0,  # CE
    "a6": 33.0,  # E0E
    "mu2": 75.0,  # ECD
    "CD": 30.0,
    "B0E0": 85.0,
    "epsilon": 30.0,  # E0B0K
}


def figure_fourbar(number: int, assembly: float = 1.0) -> SphericalFourBar:
    """The four-bar of Fig. 6 (crank-rocker) or Fig. 7 (drag link), coupler point C as P.

    Parameters
    ----------
    number : {6, 7}
        The figure.
    assembly : {+1, -1}
        The mode, sign((A × B0)·B); +1 is eq. 5 as printed.

    Returns
    -------
    SphericalFourBar

    Raises
    ------
    InvalidInput
        For another figure number.

    Examples
    --------
    >>> m = figure_fourbar(6)
    >>> np.degrees([m.frame, m.crank, m.coupler, m.rocker, m.point_arc, m.point_angle])
    array([ 40.,  20.,  45.,  35.,  50., 130.])
    >>> figure_fourbar(5)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    linkwright.papers.p000_formulas.InvalidInput: number: paper 000's four-bars are Figs 6 and ...
    """
    table = {6: FIG6, 7: FIG7}
    if number not in table:
        raise InvalidInput(f"number: paper 000's four-bars are Figs 6 and 7, not {number!r}")
    f = table[number]
    a1, a2, a3, a4, ac, mu = np.radians([f["a1"], f["a2"], f["a3"], f["a4"], f["AC"], f["mu"]])
    return SphericalFourBar(a1, a2, a3, a4, ac, mu, assembly=assembly)


def figure_sixbar(
    epsilon_sign: float = -1.0, assembly: float = -1.0, assembly2: float = 1.0
) -> SphericalSixBar:
    """Fig. 8's six-bar with ε = ``epsilon_sign`` × 30°, right-handed about +OB0.

    The defaults are the reading under which the crank turns fully (:func:`fig8_modes`).

    Parameters
    ----------
    epsilon_sign : {+1, -1}
        The side of E0: −1 puts it below the frame plane.
    assembly, assembly2 : {+1, -1}
        The four-bar's mode sign((A × B0)·B) and the dyad's sign((C × E0)·E).

    Returns
    -------
    SphericalSixBar

    Raises
    ------
    InvalidInput
        For a sign other than ±1 (the mechanism itself checks the assembly signs).

    Examples
    --------
    >>> m = figure_sixbar()
    >>> float(np.degrees(m.ground_angle)), float(m.assembly), float(m.assembly2)
    (-30.0, -1.0, 1.0)
    """
    if epsilon_sign not in (-1, 1):
        raise InvalidInput(f"epsilon_sign: must be -1 or +1, got {epsilon_sign!r}")
    f = FIG8
    arcs = np.radians([f["a1"], f["a2"], f["a3"], f["a4"], f["AC"], f["mu"], f["a5"], f["a6"]])
    a1, a2, a3, a4, ac, mu, a5, a6 = arcs
    return SphericalSixBar(
        a1,
        a2,
        a3,
        a4,
        ac,
        mu,
        a5,
        a6,
        ground_arc=np.radians(f["B0E0"]),
        ground_angle=np.radians(epsilon_sign * f["epsilon"]),
        d_arc=np.radians(f["CD"]),
        d_angle=np.radians(f["mu2"]),
        assembly=assembly,
        assembly2=assembly2,
    )


@dataclass(frozen=True)
class Fig8Mode:
    """One reading of Fig. 8: the sign of ε, the four-bar's assembly, how the crank moves."""

    epsilon: float
    """ε in degrees, right-handed about +OB0."""
    assembly: float
    full: bool
    arcs: tuple[tuple[float, float], ...]
    """The crank's admissible arcs in degrees (empty where it turns fully)."""
    e_branches_distinct: bool
    """Whether assembly2 = ±1 are two different motions (else one circuit passes both)."""


def fig8_modes() -> list[Fig8Mode]:
    """The four readings of Fig. 8 (sign of ε × the four-bar's assembly mode).

    With ε right-handed about +OB0, only ε = −30° with assembly −1 lets the crank turn fully, as
    the paper's figure does ("along whole cycle of the mechanism"); every other reading stops
    at limit positions of the dyad C–E–E0. Its mirror image in the frame plane negates μ and μ2
    too, so it is not among these four.

    Returns
    -------
    list of Fig8Mode
        In the order ε = +30°, −30° and, within each, assembly +1, −1.

    Examples
    --------
    >>> [(m.epsilon, m.assembly, m.full) for m in fig8_modes()]
    [(30.0, 1.0, False), (30.0, -1.0, False), (-30.0, 1.0, False), (-30.0, -1.0, True)]
    """
    out = []
    for eps in (1.0, -1.0):
        for assembly in (1.0, -1.0):
            m = figure_sixbar(eps, assembly, 1.0)
            arcs = input_range(m)
            full = bool(arcs.full)
            spans = tuple(
                (float(np.degrees(lo)), float(np.degrees(hi)))
                for lo, hi in zip(arcs.lo, arcs.hi, strict=True)
                if np.isfinite(lo)
            )
            # A circuit that stops at limits of the dyad C–E–E0 changes E's branch there, so it
            # already runs through both of its modes; otherwise the other mode is a second
            # motion.
            e_dyad = [d.name for d in m.plan.dyads].index("E")
            distinct = not (np.any(arcs.dyad_lo == e_dyad) or np.any(arcs.dyad_hi == e_dyad))
            out.append(Fig8Mode(FIG8["epsilon"] * eps, assembly, full, spans, distinct))
    return out

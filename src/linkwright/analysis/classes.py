"""One mechanism's motion class, by family: the name :func:`linkwright.analysis.analyze` reports.

The per-family rules (and their batched forms) are :func:`~linkwright.analysis.fourbar_class`,
:func:`~linkwright.analysis.slidercrank_class` and
:func:`~linkwright.analysis.spherical_class`; this module only chooses among them and says
``None`` for a linkage that has no motion to classify.
"""

from __future__ import annotations

from linkwright.analysis.planar import fourbar_class, slidercrank_class
from linkwright.analysis.spherical import spherical_class
from linkwright.mechanisms import FourBar, Mechanism, SliderCrank, SphericalFourBar, input_range

__all__ = ["classify"]


def classify(mechanism: Mechanism) -> str | None:
    """The motion class of one four-bar, slider-crank or spherical four-bar.

    Four-bars by Grashof's condition and their shortest link (``"crank-rocker"``,
    ``"double-crank"``, ``"double-rocker"``, ``"rocker-crank"``, ``"change-point"``,
    ``"triple-rocker"``); slider-cranks by whether the crank turns (``"crank-slider"``,
    ``"rocker-slider"``, ``"change-point"``); spherical four-bars by the spherical conditions.

    Parameters
    ----------
    mechanism : Mechanism
        One :class:`~linkwright.mechanisms.FourBar`, :class:`~linkwright.mechanisms.SliderCrank`
        or :class:`~linkwright.mechanisms.SphericalFourBar` (batch shape ``()``; for a batch use
        the per-family functions, which broadcast).

    Returns
    -------
    str or None
        The class; ``None`` when the linkage cannot be assembled at any input (it has no
        motion to classify, whatever Grashof's inequality alone would say).

    Raises
    ------
    ValueError
        For a batch, or a family without named classes (the six-bars, the geared five-bar,
        the double slider, composed linkages: :func:`~linkwright.analysis.analyze` reports
        whether their input turns fully instead).

    Examples
    --------
    >>> from linkwright.mechanisms import FourBar, SliderCrank
    >>> classify(FourBar(A0=[0, 0], B0=[1, 0], crank=4, coupler=2, rocker=13**0.5))
    'double-crank'
    >>> classify(SliderCrank(A0=[0, 0], crank=1, rod=3))
    'crank-slider'

    A linkage that cannot assemble has no class (Grashof alone would call it a triple-rocker):

    >>> print(classify(FourBar(A0=[0, 0], B0=[10, 0], crank=1, coupler=2, rocker=3)))
    None
    """
    if not isinstance(mechanism, Mechanism):
        raise ValueError(f"classify: expected a linkwright mechanism, got {mechanism!r}")
    if mechanism.batch_shape != ():
        raise ValueError(
            f"classify: one mechanism at a time, got a batch of shape {mechanism.batch_shape} "
            "(fourbar_class and the like classify batches)"
        )
    if not isinstance(mechanism, SphericalFourBar | FourBar | SliderCrank):
        raise ValueError(
            f"classify: a {mechanism.family} has no named motion classes; analyze() says "
            "whether its input turns fully"
        )
    if bool(input_range(mechanism).never):
        return None
    if isinstance(mechanism, SphericalFourBar):
        return str(spherical_class(mechanism))
    if isinstance(mechanism, FourBar):
        return str(fourbar_class(mechanism))
    return str(slidercrank_class(mechanism))

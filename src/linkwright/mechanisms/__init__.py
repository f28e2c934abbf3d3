"""Named mechanism families: thin constructors over engine plans."""

from linkwright.mechanisms.base import (
    InvalidMechanism,
    Mechanism,
    circuit,
    configurations,
    input_range,
    solve,
)
from linkwright.mechanisms.planar import DoubleSlider, FourBar, GearedFiveBar, SliderCrank

FAMILIES: dict[str, type[Mechanism]] = {
    cls.family: cls for cls in (FourBar, SliderCrank, GearedFiveBar, DoubleSlider)
}

__all__ = [
    "FAMILIES",
    "DoubleSlider",
    "FourBar",
    "GearedFiveBar",
    "InvalidMechanism",
    "Mechanism",
    "SliderCrank",
    "circuit",
    "configurations",
    "input_range",
    "solve",
]

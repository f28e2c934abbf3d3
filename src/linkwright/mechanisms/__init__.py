"""Named mechanism families: thin constructors over engine plans."""

from linkwright.mechanisms.base import (
    InvalidMechanism,
    Mechanism,
    circuit,
    configurations,
    input_range,
    solve,
)
from linkwright.mechanisms.planar import FourBar, SliderCrank

FAMILIES: dict[str, type[Mechanism]] = {cls.family: cls for cls in (FourBar, SliderCrank)}

__all__ = [
    "FAMILIES",
    "FourBar",
    "InvalidMechanism",
    "Mechanism",
    "SliderCrank",
    "circuit",
    "configurations",
    "input_range",
    "solve",
]

"""Curves: descriptors that forget position, size, orientation, start and direction, and the
aligned error between two curves (the atlas matches curves with them)."""

from linkwright.curves.fourier import (
    CurveError,
    aligned_error,
    descriptor_variants,
    descriptors,
    resample,
)

__all__ = ["CurveError", "aligned_error", "descriptor_variants", "descriptors", "resample"]

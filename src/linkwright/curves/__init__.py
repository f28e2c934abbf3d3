"""Curves: descriptors that forget position, size, orientation, start and direction, and the
aligned error between two curves (the atlas matches curves with them); on the unit sphere,
descriptors that forget rotation, start and direction but keep size."""

from linkwright.curves.fourier import (
    Alignment,
    CurveError,
    align,
    aligned_error,
    descriptor_variants,
    descriptors,
    resample,
)
from linkwright.curves.spherical import (
    SphereAlignment,
    sphere_align,
    sphere_descriptor_variants,
    sphere_descriptors,
    sphere_resample,
)

__all__ = [
    "Alignment",
    "CurveError",
    "SphereAlignment",
    "align",
    "aligned_error",
    "descriptor_variants",
    "descriptors",
    "resample",
    "sphere_align",
    "sphere_descriptor_variants",
    "sphere_descriptors",
    "sphere_resample",
]

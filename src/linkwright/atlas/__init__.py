"""The curve atlas: many mechanisms' coupler curves, described, indexed and matched.

Build one (:func:`build`, ``linkwright atlas build``), open it (:func:`open_atlas`, or the
built-in :func:`default_atlas`) and match a curve (:func:`query`, ``linkwright atlas query``).
"""

from linkwright.atlas.atlas import (
    DEFAULT_COUNTS,
    Atlas,
    AtlasError,
    data_dir,
    default_atlas,
    open_atlas,
)
from linkwright.atlas.build import AtlasBuildError, BuildSpec, build
from linkwright.atlas.families import FAMILIES, PARAMS, sample
from linkwright.atlas.query import AtlasQueryError, Match, query

__all__ = [
    "DEFAULT_COUNTS",
    "FAMILIES",
    "PARAMS",
    "Atlas",
    "AtlasBuildError",
    "AtlasError",
    "AtlasQueryError",
    "BuildSpec",
    "Match",
    "build",
    "data_dir",
    "default_atlas",
    "open_atlas",
    "query",
    "sample",
]

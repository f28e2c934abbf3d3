"""The workbench's tools: paper 002's pivot study, synthesis from a drawn curve, and exports.

Routes (mounted under ``/api`` by :func:`linkwright.server.create_app`):

- ``POST /study``: move one fixed pivot ``count`` steps along a direction and trace the curves
  at every step (paper 002, section III). A geared five-bar drawn the paper's way (P on AC at
  twice its length, so C is the midpoint of A–P) keeps its drawing: the moved pivot carries its
  crank end, the cranks' angles and P stay, and the links follow
  (:func:`linkwright.papers.p002.pivot_study`). Every other planar linkage moves only the
  pivot's own document field. A step whose linkage assembles nowhere is reported (``full``
  false, no curve), not refused.
- ``POST /match`` (with ``GET /match/status`` and ``POST /match/prepare``): match a drawn
  closed curve against the built-in four-bar atlas (:mod:`linkwright.atlas`), or a curve drawn
  on the sphere (rows of three numbers) against a spherical four-bar atlas, optionally
  refined; each candidate comes placed where the curve was drawn. Each atlas is built into the
  app's data directory on first use (:func:`atlas_count` entries) unless a finished one is
  already there (the CLI's built-in four-bar atlas is found and used).
- ``POST /ellipse`` and ``POST /ellipse/trammel``: fit an ellipse to drawn points and browse
  paper 004's ∞² family of double sliders (elliptic trammels) that trace it
  (:mod:`linkwright.synthesis.ellipse`), each member checked against the ellipse.
- ``POST /export/{fmt}``: the current document as PNG, SVG, DXF, CSV, GIF, TOML or JSON.
- ``POST /sketch`` and ``POST /sketch/from-document``: the builder's drawing compiled to a
  linkage document (its degrees of freedom, and what it lacks, said in one sentence), and a
  document's drawing (:mod:`~linkwright.server.tools_sketch`).
- ``POST /forces``: the driving torque and every joint's reaction along the circuits a scene
  draws, at the page's input speed, for the forces panel (:mod:`~linkwright.server.forces_panel`).

Every problem a user can cause raises a ``ValueError`` subclass with one line naming the field,
which the app answers as 422 ``{"error": ...}``; no answer carries NaN (a point that cannot be
placed is ``null``).

This module is the public face: it gathers the tools' routes into one :data:`router`, each tool
a room of its own (:mod:`~linkwright.server.tools_study`, :mod:`~linkwright.server.tools_match`,
:mod:`~linkwright.server.tools_ellipse`, :mod:`~linkwright.server.tools_export`, sharing
:mod:`~linkwright.server.tools_common`).
"""

from __future__ import annotations

from fastapi import APIRouter

from linkwright.server import (
    forces_panel,
    tools_ellipse,
    tools_export,
    tools_match,
    tools_sketch,
    tools_study,
)
from linkwright.server.tools_common import MAX_POINTS, ToolsError
from linkwright.server.tools_common import Array as Array
from linkwright.server.tools_common import Points as Points
from linkwright.server.tools_ellipse import FAMILY_TOLERANCE as FAMILY_TOLERANCE
from linkwright.server.tools_ellipse import Circle as Circle
from linkwright.server.tools_ellipse import EllipseRequest as EllipseRequest
from linkwright.server.tools_ellipse import TrammelRequest as TrammelRequest
from linkwright.server.tools_ellipse import ellipse as ellipse
from linkwright.server.tools_ellipse import ellipse_trammel as ellipse_trammel
from linkwright.server.tools_export import EXPORTS
from linkwright.server.tools_export import GIF_DPI as GIF_DPI
from linkwright.server.tools_export import GIF_FPS as GIF_FPS
from linkwright.server.tools_export import GIF_FRAMES as GIF_FRAMES
from linkwright.server.tools_export import PNG_DPI as PNG_DPI
from linkwright.server.tools_export import ExportRequest as ExportRequest
from linkwright.server.tools_export import export_file as export_file
from linkwright.server.tools_match import ATLAS_COUNT, REFINE_POINTS, MatchError, atlas_count
from linkwright.server.tools_match import ATLAS_COUNT_ENV as ATLAS_COUNT_ENV
from linkwright.server.tools_match import CURVE_SAMPLES as CURVE_SAMPLES
from linkwright.server.tools_match import MatchRequest as MatchRequest
from linkwright.server.tools_match import match as match
from linkwright.server.tools_match import match_prepare as match_prepare
from linkwright.server.tools_match import match_status as match_status
from linkwright.server.tools_study import MAX_STUDY_STEPS, StudyError
from linkwright.server.tools_study import StudyRequest as StudyRequest
from linkwright.server.tools_study import study as study

__all__ = [
    "ATLAS_COUNT",
    "EXPORTS",
    "MAX_POINTS",
    "MAX_STUDY_STEPS",
    "REFINE_POINTS",
    "MatchError",
    "StudyError",
    "ToolsError",
    "atlas_count",
    "router",
]

# The tools' routes, in the order the OpenAPI schema has always listed them.
router = APIRouter()
router.include_router(tools_study.router)
router.include_router(tools_match.router)
router.include_router(tools_ellipse.router)
router.include_router(tools_export.router)
router.include_router(tools_sketch.router)
router.include_router(forces_panel.router)

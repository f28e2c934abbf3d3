"""The workbench's drawing compiler: ``POST /sketch`` and ``POST /sketch/from-document``.

The builder sends the drawing on the canvas (joints, links, drivers; the format is in
:mod:`linkwright.io.sketch_checks`) after every edit; the answer says what the drawing is (its
status, degrees of freedom and one sentence) and carries its ``linkage`` document once it can
run (:func:`linkwright.io.sketch.compile_sketch`). A drawing that is incomplete, over-constrained
or wrong is answered 200 with its status: those are states of a drawing, not request errors.
Only a body that is not a drawing at all (wrong types, unknown fields, lists over the
``sketch_*`` limits) is answered 422.

``/sketch/from-document`` is the way back: the drawing of a document, for the builder to edit
(:func:`linkwright.io.sketch.sketch_of_document`), or 422 saying in one line why it has none.

Its own room (split from :mod:`linkwright.server.tools`): one tool, its requests and answers.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter
from pydantic import BaseModel, ConfigDict, Field, Strict

from linkwright.io.sketch import STATUSES, SketchError, compile_sketch, sketch_of_document
from linkwright.server import limits
from linkwright.server.schema import DocumentBody, examples
from linkwright.server.tools_common import EXAMPLE_DOCUMENT, ToolsError

__all__ = ["EXAMPLE_SKETCH", "Sketch", "SketchAnswer", "SketchRequest", "router", "sketch"]

router = APIRouter()

Number = Annotated[float, Strict()]
Name = Annotated[str, Field(min_length=1, max_length=limits.TEXT.value)]

EXAMPLE_SKETCH: dict[str, Any] = {
    "space": "plane",
    "title": "A drawn four-bar",
    "joints": [
        {"name": "A0", "at": [0.0, 0.0], "ground": True},
        {"name": "A", "at": [1.0, 0.0]},
        {"name": "B", "at": [3.0, 2.0]},
        {"name": "B0", "at": [4.0, 0.0], "ground": True},
        {"name": "P", "at": [2.0, 2.5]},
    ],
    "links": [["A0", "A"], ["A", "B", "P"], ["B", "B0"]],
    "drivers": [{"pivot": "A0", "joint": "A", "ratio": 1.0}],
    "traced": ["P"],
}


class SketchJoint(BaseModel):
    """A drawn joint: its name and place; a ground pivot, or (plane only) a pin on a fixed
    guide line through its place at ``slider`` degrees from +x."""

    model_config = ConfigDict(extra="forbid")

    name: Name
    at: list[Number] = Field(min_length=2, max_length=3)
    ground: Annotated[bool, Strict()] = False
    slider: Number | None = None


class SketchDriver(BaseModel):
    """A crank: ``joint`` turned about the ground pivot ``pivot`` at ``ratio`` × the input."""

    model_config = ConfigDict(extra="forbid")

    pivot: Name
    joint: Name
    ratio: Number = 1.0


class Sketch(BaseModel):
    """A drawing: joints, links (each the joints one rigid body joins), drivers (the first is
    the input crank, each further one geared to it) and the traced joints."""

    model_config = ConfigDict(extra="forbid")

    space: Literal["plane", "sphere"] = "plane"
    title: str | None = Field(None, max_length=limits.TITLE.value)
    joints: list[SketchJoint] = Field([], max_length=limits.SKETCH_JOINTS.value)
    links: list[Annotated[list[Name], Field(max_length=limits.SKETCH_LINK_JOINTS.value)]] = Field(
        [], max_length=limits.SKETCH_LINKS.value
    )
    drivers: list[SketchDriver] = Field([], max_length=limits.SKETCH_DRIVERS.value)
    traced: list[Name] | None = Field(None, max_length=limits.SKETCH_JOINTS.value)


class SketchRequest(BaseModel):
    model_config = ConfigDict(
        extra="forbid", json_schema_extra=examples({"sketch": EXAMPLE_SKETCH})
    )

    sketch: Sketch


class FromDocumentRequest(BaseModel):
    model_config = ConfigDict(json_schema_extra=examples({"document": EXAMPLE_DOCUMENT}))

    document: DocumentBody


class SketchAnswer(BaseModel):
    """What the drawing is: its status, degrees of freedom (null when empty or invalid), one
    sentence, its document (status "ok" only), how each placed joint is placed, and the joints
    and links (indices) the sentence is about."""

    status: Annotated[str, Field(json_schema_extra={"enum": list(STATUSES)})]
    dof: int | None
    message: str
    document: dict[str, Any] | None
    placement: dict[str, str]
    joints: list[str]
    links: list[int]


@router.post("/sketch", response_model=SketchAnswer)
def sketch(body: SketchRequest) -> dict[str, Any]:
    """Count the drawing's degrees of freedom, say what it lacks, and compile it to a linkage
    document once it has one degree of freedom and a driver."""
    return compile_sketch(body.sketch.model_dump(exclude_none=True)).as_json()


@router.post("/sketch/from-document", response_model=Sketch, response_model_exclude_none=True)
def sketch_from_document(body: FromDocumentRequest) -> dict[str, Any]:
    """The drawing of a document (every joint where it is at θ = 0), for the builder to edit."""
    limits.check_document(body.document)
    try:
        return sketch_of_document(body.document)
    except SketchError as exc:
        raise ToolsError(f"document: {exc}") from None

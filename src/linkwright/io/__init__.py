"""Reading and writing mechanism documents (TOML and JSON), the bundled examples, and exports
(CSV paths, SVG and DXF drawings).

:mod:`.documents` is the schema (derived from the family registry) and the reading of a
document's mapping; :mod:`.files` reads and writes the files and finds the examples;
:mod:`.toml_writer` writes TOML; :mod:`.results` and :mod:`.report` give what the command line
and the workbench show (degrees, JSON, sentences).
"""

from linkwright.io.documents import (
    FAMILY_SPECS,
    FORMAT,
    Document,
    DocumentError,
    FamilySpec,
    FieldSpec,
    document_to_dict,
    mechanism_to_dict,
    parse_document,
)
from linkwright.io.exports import (
    FORMATS,
    INSUNITS,
    ExportError,
    Guide,
    Topology,
    export,
    export_csv,
    export_dxf,
    export_svg,
    joint_paths,
    topology,
)
from linkwright.io.files import list_examples, load_document, load_example, save_document

__all__ = [
    "FAMILY_SPECS",
    "FORMAT",
    "FORMATS",
    "INSUNITS",
    "Document",
    "DocumentError",
    "ExportError",
    "FamilySpec",
    "FieldSpec",
    "Guide",
    "Topology",
    "document_to_dict",
    "export",
    "export_csv",
    "export_dxf",
    "export_svg",
    "joint_paths",
    "list_examples",
    "load_document",
    "load_example",
    "mechanism_to_dict",
    "parse_document",
    "save_document",
    "topology",
]

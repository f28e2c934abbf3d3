"""Reading and writing mechanism documents (TOML and JSON), and the bundled examples."""

from linkwright.io.documents import (
    FAMILY_SPECS,
    FORMAT,
    Document,
    DocumentError,
    FamilySpec,
    FieldSpec,
    document_to_dict,
    list_examples,
    load_document,
    load_example,
    mechanism_to_dict,
    parse_document,
    save_document,
)

__all__ = [
    "FAMILY_SPECS",
    "FORMAT",
    "Document",
    "DocumentError",
    "FamilySpec",
    "FieldSpec",
    "document_to_dict",
    "list_examples",
    "load_document",
    "load_example",
    "mechanism_to_dict",
    "parse_document",
    "save_document",
]

"""One bundled example per family, the composed linkage once in the plane and once on the sphere.

The picture, diagram, animation and CLI tests all run over these, and the README's gallery shows
them (its file names are these keys).
"""

from linkwright.server.scene import FAMILY_EXAMPLES as WORKBENCH_EXAMPLES

# The workbench's choice for every family, the composed linkage split by space.
FAMILY_EXAMPLES = {
    **{k: v for k, v in WORKBENCH_EXAMPLES.items() if k != "linkage"},
    "linkage-plane": WORKBENCH_EXAMPLES["linkage"],
    "linkage-sphere": "paper000-fig6-linkage",
}


def family_of(key: str) -> str:
    """The family a key names ("linkage-plane" → "linkage")."""
    return key.removesuffix("-plane").removesuffix("-sphere")

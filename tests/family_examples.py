"""One bundled example per family, the composed linkage once in the plane and once on the sphere.

The picture, diagram, animation and CLI tests all run over these, and the README's gallery shows
them (its file names are these keys). :data:`INPUT_EXAMPLES` adds the linkages driven elsewhere
than at a crank (so that a triad remains, or at a moving hinge); tests/test_family_verbs.py runs
every verb on them and compares their gallery pictures.
"""

from linkwright.server.scene import FAMILY_EXAMPLES as WORKBENCH_EXAMPLES

# The workbench's choice for every family, the composed linkage split by space.
FAMILY_EXAMPLES = {
    **{k: v for k, v in WORKBENCH_EXAMPLES.items() if k != "linkage"},
    "linkage-plane": WORKBENCH_EXAMPLES["linkage"],
    "linkage-sphere": "paper000-fig6-linkage",
}

# Families driven elsewhere than at their crank, where a triad remains (key → example).
INPUT_EXAMPLES = {
    "stephenson3-output": "stephenson3-output",
    "spherical-stephenson3-fg": "paper001-fg",
    "linkage-hinge": "hinge-driven-fourbar",
    "stephenson3-hinge": "stephenson3-driven-at-d",
    "spherical-stephenson3-hinge": "paper001-driven-at-e",
}

_FAMILY_OF_INPUT = {
    "stephenson3-output": "stephenson3",
    "spherical-stephenson3-fg": "spherical-stephenson3",
    "linkage-hinge": "linkage",
    "stephenson3-hinge": "stephenson3",
    "spherical-stephenson3-hinge": "spherical-stephenson3",
}


def family_of(key: str) -> str:
    """The family a key names ("linkage-plane" → "linkage", "stephenson3-output" →
    "stephenson3")."""
    if key in _FAMILY_OF_INPUT:
        return _FAMILY_OF_INPUT[key]
    return key.removesuffix("-plane").removesuffix("-sphere")

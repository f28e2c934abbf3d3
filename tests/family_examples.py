"""One bundled example per family, the composed linkage once in the plane and once on the sphere.

The picture, diagram, animation and CLI tests all run over these, and the README's gallery shows
them (its file names are these keys).
"""

FAMILY_EXAMPLES = {
    "fourbar": "crank-rocker",
    "slidercrank": "offset-slider-crank",
    "geared-fivebar": "geared-fivebar",
    "doubleslider": "elliptic-trammel",
    "watt1": "watt1-example",
    "watt2": "watt2-example",
    "stephenson1": "stephenson1-example",
    "stephenson3": "stephenson3-example",
    "spherical-fourbar": "paper000-fig6-crank-rocker",
    "spherical-sixbar": "paper000-fig8-sixbar",
    "spherical-stephenson3": "paper001-stephenson3",
    "linkage-plane": "jansen-leg",
    "linkage-sphere": "paper000-fig6-linkage",
}


def family_of(key: str) -> str:
    """The family a key names ("linkage-plane" → "linkage")."""
    return key.removesuffix("-plane").removesuffix("-sphere")

"""linkwright: a kinematics workbench for planar linkages."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("linkwright")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.1.0"

__all__ = ["__version__"]

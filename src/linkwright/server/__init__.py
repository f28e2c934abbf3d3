"""The browser workbench (``linkwright serve``): a FastAPI application serving a JSON API and a
page with no build step. See :mod:`linkwright.server.app`."""

from linkwright._extras import require

# Without its extra the workbench says which to install, in one line, before any import fails.
require("server")

from linkwright.server.app import (  # noqa: E402 - after the check above
    LOOPBACK_HOSTS,
    MAX_BODY_BYTES,
    create_app,
    default_data_dir,
)

__all__ = ["LOOPBACK_HOSTS", "MAX_BODY_BYTES", "create_app", "default_data_dir"]

"""The browser workbench (``linkwright serve``): a FastAPI application serving a JSON API and a
page with no build step. See :mod:`linkwright.server.app`."""

from linkwright.server.app import LOOPBACK_HOSTS, MAX_BODY_BYTES, create_app, default_data_dir

__all__ = ["LOOPBACK_HOSTS", "MAX_BODY_BYTES", "create_app", "default_data_dir"]

"""Browser tests of the workbench (a package, so its conftest does not clash with tests/conftest.py)."""

"""Browser tests of the workbench: a package, so that its conftest and tests/conftest.py
do not clash."""

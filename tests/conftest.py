"""Shared test configuration: Hypothesis profiles, and a scratch data directory.

``ci`` is derandomized (the same examples on every run, so a red CI build is reproducible) and
is selected whenever the environment variable ``CI`` is set; ``dev`` (the default) explores new
examples on every run. Neither sets a deadline: the engine's first call on a new shape pays
NumPy's warm-up, which says nothing about the code under test.
"""

from __future__ import annotations

import os
import tempfile

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

# The built-in atlas and the workbench's library live in linkwright's data directory: tests (and
# the commands they start, which inherit the environment) use a scratch one, never the user's.
os.environ.setdefault("LINKWRIGHT_DATA", tempfile.mkdtemp(prefix="linkwright-test-data-"))

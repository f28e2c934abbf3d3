"""Shared test configuration: Hypothesis profiles.

``ci`` is derandomized (the same examples on every run, so a red CI build is reproducible) and
is selected whenever the environment variable ``CI`` is set; ``dev`` (the default) explores new
examples on every run. Neither sets a deadline: the engine's first call on a new shape pays
NumPy's warm-up, which says nothing about the code under test.
"""

from __future__ import annotations

import os

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

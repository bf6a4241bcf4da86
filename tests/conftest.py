"""Shared test configuration: hypothesis profiles.

``ci`` (the default) runs hundreds of examples per property with no deadline and a
derandomised seed, so a failure in CI reproduces on any machine; hypothesis also
prints the ``@reproduce_failure`` blob. ``dev`` is a quicker profile for local runs:
``HYPOTHESIS_PROFILE=dev python -m pytest``.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=300,
    deadline=None,
    derandomize=True,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", max_examples=50, deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

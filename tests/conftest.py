"""Shared test configuration: hypothesis profiles.

``ci`` (the default) runs hundreds of examples per property with no deadline and a
derandomised seed, so a failure in CI reproduces on any machine; hypothesis also
prints the ``@reproduce_failure`` blob. ``dev`` is a quicker profile for local runs:
``HYPOTHESIS_PROFILE=dev python -m pytest``. ``long`` is ``dev`` without the *explain*
phase, for the ``LUMPED_LARGE`` runs with ``--hypothesis-seed``: once a draw fails,
hypothesis traces every line of every later draw to explain the failure, which slows a
network run tens of times (a shrink step of a 4-mass draw ran for more than 15 minutes).
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, Phase, settings

settings.register_profile(
    "ci",
    max_examples=300,
    deadline=None,
    derandomize=True,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", max_examples=50, deadline=None, print_blob=True)
settings.register_profile("long", settings.get_profile("dev"),
                          phases=[p for p in Phase if p is not Phase.explain])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

"""Hypothesis profiles: a bounded number of examples in the default selection, a longer run
with FLOWCURVE_HYPOTHESIS=long (e.g. ``FLOWCURVE_HYPOTHESIS=long python -m pytest tests/property
--hypothesis-show-statistics``)."""

import os

from hypothesis import HealthCheck, settings

settings.register_profile("default", max_examples=25, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("long", max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("FLOWCURVE_HYPOTHESIS", "default"))

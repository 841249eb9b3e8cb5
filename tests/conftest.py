"""Suite-wide rules.

Tests that need the real validation records in ``shared/`` (beside the checkout, or
``FLOWCURVE_SHARED``) or the CalculiX solver skip with a reason on a developer's machine that
lacks them; in CI (``CI`` set) such a skip is a failure, so a missing folder or solver can
never turn the published-value or solver checks silently off.
"""

from __future__ import annotations

import os

import pytest

MISSING_DATA_WORDS = ("validation data", "is not installed")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if os.environ.get("CI") and report.skipped and isinstance(report.longrepr, tuple):
        reason = str(report.longrepr[2])
        if any(word in reason for word in MISSING_DATA_WORDS):
            report.outcome = "failed"
            report.longrepr = f"in CI this must be present: {reason}"


@pytest.fixture
def model_clock():
    """Simulated host time (:class:`flowcurve.clock.ModelClock`): the fast tests' clock."""
    from flowcurve.clock import ModelClock

    return ModelClock()


@pytest.fixture
def model_time_rig(model_clock):
    """``model_time_rig(material, **kw)`` → a started VirtualRig whose devices are opened
    in-process (``virtual://``) and run on ``model_clock``; closed after the test."""
    from flowcurve.rig.virtual.rig import VirtualRig

    rigs = []

    def make(*args, **kwargs):
        rig = VirtualRig(*args, clock=model_clock, link="inprocess", **kwargs)
        rigs.append(rig)
        return rig.start()

    yield make
    for rig in rigs:
        rig.close()

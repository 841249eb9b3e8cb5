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

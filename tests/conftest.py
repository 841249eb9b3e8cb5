"""Suite-wide rules.

The real validation records are in the repository (``tests/data/``). Tests that need the
CalculiX solver, Chromium or a package of the test extra skip with
a reason ("… is not installed", "validation data …") on a developer's machine that lacks
them; in CI (``CI`` set, not "false"/"0") such a skip is a failure, a whole file skipped at
import included, so a missing folder, solver or browser can never turn checks silently off.

Property tests (hypothesis), wherever they are, draw the same cases on every run (profile
``default``: derandomized, 25 examples unless a test says more), so a red CI run is a case anyone
re-runs and a green one does not turn red by luck. ``FLOWCURVE_HYPOTHESIS=long`` draws 400 new
cases a test (and ``explore`` new ones at each test's own count): the campaigns that look for
what the repeatable draw has not met, e.g. ``FLOWCURVE_HYPOTHESIS=explore python3 -m pytest -m slow
tests/property --hypothesis-show-statistics``.
"""

from __future__ import annotations

import os

import pytest

MISSING_DATA_WORDS = ("validation data", "is not installed")

try:
    from hypothesis import HealthCheck, settings
except ImportError:  # the test extra is not installed: the property tests skip on their own
    pass
else:  # here, not in a sub-folder's conftest: a profile loaded there would reach only the tests collected after it
    settings.register_profile("default", max_examples=25, deadline=None, derandomize=True,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("long", max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("explore", deadline=None, suppress_health_check=[HealthCheck.too_slow])
    settings.load_profile(os.environ.get("FLOWCURVE_HYPOTHESIS", "default"))


def _in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


def _missing_is_a_failure_in_ci(report) -> None:
    if _in_ci() and report.skipped and isinstance(report.longrepr, tuple):
        reason = str(report.longrepr[2])
        if any(word in reason for word in MISSING_DATA_WORDS):
            report.outcome = "failed"
            report.longrepr = f"in CI this must be present: {reason}"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    _missing_is_a_failure_in_ci(outcome.get_result())


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):  # a module-level importorskip skips the whole file at collection
    outcome = yield
    _missing_is_a_failure_in_ci(outcome.get_result())


@pytest.fixture
def model_clock():
    """Simulated host time (:class:`flowcurve.clock.ModelClock`): the fast tests' clock."""
    from flowcurve.clock import ModelClock

    return ModelClock()


@pytest.fixture(params=["inprocess", pytest.param("pty", marks=pytest.mark.pty)])
def device_link(request):
    """Where the virtual devices run: ``{"clock": ..., "link": ...}`` for their constructors.
    In-process (``virtual://``) on a model clock in the default selection; the same test on
    pseudo-terminals in real time with ``-m pty``."""
    from flowcurve.clock import WALL, ModelClock

    if request.param == "pty":
        return {"clock": WALL, "link": "pty"}
    return {"clock": ModelClock(), "link": "inprocess"}


def _rig_factory(link):
    from flowcurve.rig.virtual.rig import VirtualRig

    rigs = []

    def make(*args, **kwargs):
        rig = VirtualRig(*args, **link, **kwargs)
        rigs.append(rig)
        return rig.start()

    return rigs, make


@pytest.fixture
def rig_factory(device_link):
    """``rig_factory(material, **kw)`` → a started VirtualRig on ``device_link`` (sleep with
    ``rig.clock.sleep``), closed after the test."""
    rigs, make = _rig_factory(device_link)
    yield make
    for rig in rigs:
        rig.close()


@pytest.fixture
def model_time_rig(model_clock):
    """Like ``rig_factory``, in-process on ``model_clock`` only: for the tests that check
    times exactly."""
    rigs, make = _rig_factory({"clock": model_clock, "link": "inprocess"})
    yield make
    for rig in rigs:
        rig.close()

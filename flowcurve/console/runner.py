"""One test at a time on the console's rig, run in a thread with the ``run`` command's code.

The test itself is :func:`flowcurve.services.run.run_test` — the procedure on the virtual rig
in this process or on a configured rig — exactly as ``flowcurve run`` runs it: the same record, the same stop
criteria, the same heater safety (the heater is switched off on every way out of the
procedure, and the furnace's watchdog is armed while it runs). The browser only watches:
closing or reloading it changes nothing; a stop or abort button sets a flag the procedure
reads at its next tick. When the console itself shuts down, a running test is aborted and
waited for, so the heater is off and the record closed before the process ends.
"""

from __future__ import annotations

import datetime as _dt
import logging
import re
import threading
from dataclasses import dataclass, field
from pathlib import Path

from flowcurve.acquisition.procedure import post_prompts
from flowcurve.acquisition.safety import Interrupted
from flowcurve.console.live_state import ABORTED_STATE, COMPLETE_STATE, FAILED_STATE, ConsoleView
from flowcurve.errors import FlowcurveError
from flowcurve.services import FieldError
from flowcurve.services.run import RunSetup, run_test

log = logging.getLogger(__name__)

OPERATOR_STOP = "operator stop (console)"
ABORT_SIGNAME = "the console's abort button"  # the record says "stopped by the console's abort button"
SHUTDOWN_SIGNAME = "the console shutting down"
HEATER_WINDOW_PERIODS = 1.5  # the heater shows "on" while its relay was on within this many control periods
# ... and at least this many wall seconds: the pages look 20 times a second, and at a time scale of 60 a
# 2 s control period is 33 ms, so a relay pulsing through the heat-up read "off" in 4 of 8 looks
HEATER_WINDOW_MIN_S = 1.0


class BusyError(FlowcurveError):
    """A test is running on this rig already."""


def record_name(setup: RunSetup, now: _dt.datetime | None = None) -> str:
    """``compression-<specimen id>-<date-time>.csv``, safe as a file name."""
    now = now or _dt.datetime.now()
    sid = re.sub(r"[^A-Za-z0-9._-]+", "_", setup.spec.specimen_id).strip("._")[:40]
    parts = [setup.spec.test] + ([sid] if sid else []) + [f"{now:%Y%m%d-%H%M%S}"]
    return "-".join(parts) + ".csv"


@dataclass
class TestRun:
    """One test started from the console: its view (live state) and, once ended, its outcome."""

    __test__ = False

    test_id: int
    setup: RunSetup
    record: Path
    view: ConsoleView
    thread: threading.Thread | None = None
    outcome: object | None = None  # acquisition.procedure.Outcome
    error: str | None = None  # a fault, named as ``run`` names it
    error_field: str | None = None  # the request field a refusal names (services.FieldError), else None
    stop_reason: str | None = None
    abort_reason: str | None = None
    post: dict[str, float] = field(default_factory=dict)
    result: dict | None = None  # summary of the identification
    heater_source: object | None = None  # what tells the heater state (virtual furnace or driver)
    form: dict[str, str] = field(default_factory=dict)  # the set-up form as entered (other pages show it)
    # set by the test thread once outcome, post and error are final, before it tells the pages:
    # a page that sees the test ended always sees its outcome with it
    ended: threading.Event = field(default_factory=threading.Event)

    @property
    def running(self) -> bool:
        """Whether the test's thread is still running."""
        return self.thread is not None and not self.ended.is_set() and self.thread.is_alive()

    def summary(self) -> dict:
        """The run as the pages show it: id, record, state and outcome."""
        o = self.outcome
        return {
            "test_id": self.test_id,
            "test": self.setup.spec.test,
            "record": self.record.name,
            "running": self.running,
            "status": getattr(o, "status", None),
            "reason": getattr(o, "reason", None),
            "samples": getattr(o, "samples", None),
            "duration_s": getattr(o, "duration_s", None),
            "max_force_N": getattr(o, "max_force_N", None),
            "error": self.error,
            "post": dict(self.post),
            "post_prompts": post_prompts(self.setup.spec.test, self.setup.spec.geometry_mm),  # dface's says when it is needed
            "result": self.result,
            "setup": dict(self.form),
        }


class TestRunner:
    """Starts tests (one at a time), stops and aborts them, and keeps the last one."""

    __test__ = False

    def __init__(self, records_dir: Path, *, config=None, virtual_setup=None, open_rig=None):
        self.records_dir = Path(records_dir)
        self.config = config  # rig.config.RigConfig, or None for the virtual rig
        # open_rig(time_scale) → a context manager giving a RigIO; default DriverRig(config) (benchmarks pass their own)
        self.open_rig = open_rig
        self.virtual_setup = virtual_setup  # virtual rig: called with it before each test (faults, for tests)
        self._lock = threading.Lock()
        self._next_id = 1
        self.current: TestRun | None = None
        self._before: TestRun | None = None  # the test shown before the current one was started

    @property
    def virtual(self) -> bool:
        """Whether tests run on the virtual rig (no configuration and no rig opener)."""
        return self.config is None and self.open_rig is None

    def start(self, setup: RunSetup, form: dict | None = None) -> TestRun:
        """Start ``setup`` on its own thread; BusyError when a test runs already."""
        with self._lock:
            if self.current is not None and self.current.running:
                raise BusyError(f"a test is running on this rig already ({self.current.record.name}); stop it first")
            self.records_dir.mkdir(parents=True, exist_ok=True)
            view = ConsoleView(self._next_id, time_scale=setup.time_scale, heater_window_s=max(HEATER_WINDOW_MIN_S, HEATER_WINDOW_PERIODS * self._control_period_s() / setup.time_scale))
            run = TestRun(self._next_id, setup, self.records_dir / record_name(setup), view)
            run.view.heater = lambda: self._heater_on(run)
            run.form = {str(k): str(v) for k, v in (form or {}).items()}
            self._next_id += 1
            self._before = self.current
            run.thread = threading.Thread(target=self._run, args=(run,), name=f"flowcurve-console-test-{run.test_id}", daemon=False)
            self.current = run
            run.thread.start()
            return run

    def discard(self, run: TestRun) -> None:
        """Forget a test the procedure refused before it began (nothing recorded): the pages
        show the test before it again, not a fault and a record name for a test that never ran."""
        with self._lock:
            if self.current is run and not run.running and not run.record.exists():
                self.current = self._before

    def _control_period_s(self) -> float:
        from flowcurve.rig.config import FurnaceConfig

        furnace = self.config.furnace if self.config is not None else None
        return furnace.control_period_s if furnace is not None else FurnaceConfig.control_period_s

    def stop(self) -> bool:
        """Operator stop: recording ends, the record is complete. False when nothing runs."""
        run = self.current
        if run is None or not run.running:
            return False
        run.stop_reason = OPERATOR_STOP
        return True

    def abort(self, why: str = ABORT_SIGNAME) -> bool:
        """Abort: the test ends at once, the record is marked aborted. False when nothing runs."""
        run = self.current
        if run is None or not run.running:
            return False
        run.abort_reason = why
        return True

    def shutdown(self, timeout_s: float = 30.0) -> None:
        """Abort a running test and wait for the procedure to switch off and close the record."""
        run = self.current
        if run is not None and run.running:
            log.warning("console shutting down: aborting test %s (%s)", run.test_id, run.record)
            self.abort(SHUTDOWN_SIGNAME)
        if run is not None and run.thread is not None:
            run.thread.join(timeout_s)

    # the test thread -----------------------------------------------------------------------
    @staticmethod
    def _stop_requested(run: TestRun):
        def asked() -> str | None:
            """The console's stop reason, or None; raises Interrupted when the test was aborted."""
            if run.abort_reason:
                raise Interrupted(run.abort_reason)
            return run.stop_reason

        return asked

    @staticmethod
    def _heater_on(run: TestRun) -> bool | None:
        source = run.heater_source
        if source is None:
            return None
        if hasattr(source, "relay_on"):  # the virtual furnace: the relay itself
            return bool(source.relay_on)
        return bool(getattr(source, "heater_is_on", False))  # the furnace driver: the last command

    def _run(self, run: TestRun) -> None:
        try:
            self._procedure(run)
        finally:
            self._end(run)

    def _procedure(self, run: TestRun) -> None:
        def attach(rig) -> None:  # the virtual rig: its furnace's relay; a driver rig: its furnace driver
            """Hand the run the rig's heater (for the pages) and apply the virtual rig's setup."""
            run.heater_source = rig.model.furnace if self.virtual else getattr(rig, "furnace", None)
            if self.virtual and self.virtual_setup is not None:
                self.virtual_setup(rig)

        try:
            run.outcome = run_test(run.setup, run.record, config=self.config, view=run.view, stop_requested=self._stop_requested(run),
                                   on_rig=attach, open_rig=self.open_rig)
        except FlowcurveError as exc:  # could not start (a device that does not answer, a bad set-point)
            run.error = str(exc)
            run.error_field = exc.field if isinstance(exc, FieldError) else None
        except BaseException as exc:  # the procedure closed the record as aborted and switched the heater off
            log.exception("test %s ended with an unexpected error", run.test_id)
            run.error = " ".join(f"{type(exc).__name__}: {exc}".split())

    @staticmethod
    def _end(run: TestRun) -> None:
        """Outcome, post and error final → ``ended`` → the view's last state (which wakes the pages).

        In this order, so that a page told the test ended finds its outcome beside it; the
        procedure's own "done" shows as "stopping" until then (the rig is still being released).
        The last state is "complete", "aborted" (stopped before its end, the record kept) or
        "failed" (a fault, or a test that could not start), each its own word on the page.
        """
        o = run.outcome
        if o is not None:
            run.post = dict(o.post)
            if o.error is not None:
                run.error = str(o.error)
        run.ended.set()
        if run.error:
            run.view.set_state(FAILED_STATE, f"{run.error} (the record keeps everything up to the fault)" if o is not None else run.error)
        else:
            run.view.set_state(COMPLETE_STATE if o.status == "complete" else ABORTED_STATE, f"{o.status}: {o.reason}")

"""Test procedures: tension and compression, from specimen entry to the amended record.

The procedure drives a :class:`~acquisition.rig_io.RigIO` (see :mod:`acquisition.session` for the real and the
virtual rig) through the phases

1. optional heating to a set-point and a soak until the temperature is steady,
2. tare of the load cell,
3. recording while the crosshead runs (the virtual rig is started by the procedure; on the
   real rig the operator starts the motor and the procedure waits for motion),
4. stop on fracture, target displacement, force limit, operator stop or a device fault,
5. post-test measurements written into the record with :func:`amend_record`.

The record is written as the test runs (:class:`RecordWriter`), so a crash keeps all but
the last second; the heater is off on every way out (:class:`HeaterSafety`).
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from flowcurve.acquisition.live import LiveView, Snapshot
from flowcurve.record.format import STATUS_ABORTED, STATUS_COMPLETE, RecordWriter, amend_record
from flowcurve.record.summary import MEASURED_SPEED_KEY, speed_mismatch
from flowcurve.acquisition.safety import HeaterSafety, Interrupted, check_temperature
from flowcurve.acquisition.keys import KeyWatcher
from flowcurve.acquisition.rig_io import RigIO  # noqa: F401  (procedure.RigIO, as before)
from flowcurve.acquisition.sampler import Sampler
from flowcurve.acquisition.channel_guards import install_guards
from flowcurve.acquisition.specimen_geometry import geometry_problem
from flowcurve.acquisition.stream_notes import StreamNotes
from flowcurve.clock import WALL, Clock
from flowcurve.rig.config import SETPOINT_MARGIN_C, setpoint_refusal
from flowcurve.errors import FlowcurveError, RecordWriteError, SafetyError
from flowcurve.acquisition.stopping import CARRY_AGREE_MM, CARRY_MAX_S, MOTION_MM, STALE_CROSSHEAD_S, STALE_WAIT_S, SpeedMeter, StopCriteria, StopState, TARGET_TICK_MIN_S, loop_tick_s, stop_reason, target_reached

WATCH_COOLING_S = 45.0  # test seconds the furnace is watched after an over-temperature
WATCH_UNHEATED_S = 15.0  # ... and after a test it did not heat (no stored heat to wait out: a stuck relay shows in ~12 s)
# ... and on while the furnace still rises, up to this (then named): four times the 30 s allowed for stored heat to reach
# the thermocouple; the virtual furnace's time constant C/(dP_loss/dT) ≈ 410 s at 850 C keeps a stuck relay's rise
# (≥ 0.7 K/s below its 900 C maximum) within 25 % of its rate over it: the check (≥ 0.3 K/s) names it long before
WATCH_LONGEST_S = 120.0
HEAT_STEPS_PER_PERIOD = 4
HEAT_MIN_TICK_S = 0.005  # host seconds
FORCE_LIMIT_OF_CAPACITY = 0.98  # default force limit: this fraction of the frame's capacity
TEST_GEOMETRY = {"tension": ("d0_mm", "l0_mm"), "compression": ("d0_mm", "h0_mm")}
POST_KEYS = {
    "tension": ("post.lu_mm", "post.dk_mm", "post.du_mm", "post.neck_radius_mm"),
    "compression": ("post.hk_mm", "post.dmax_mm", "post.dface_mm"),  # dface optional: μ near sticking (docs/methods.md §4a.2)
}
POST_PROMPTS = {
    "post.lu_mm": "gauge length after fracture lu [mm]",
    "post.dk_mm": "diameter at fracture dk [mm]",
    "post.du_mm": "diameter in the uniform part du [mm]",
    "post.neck_radius_mm": "neck profile radius [mm]",
    "post.hk_mm": "final height hk [mm]",
    "post.dmax_mm": "maximum barrel diameter dmax [mm]",
    "post.dface_mm": "original end-face diameter dface, its machined area without the folded side [mm] (optional)",
}
FACE_ASKED_FROM_H0_OVER_D0 = 1.6  # a compression specimen this tall: dface asked for, not optional (near sticking dmax barely tells μ)
FACE_ASKED_PROMPT = ("original end-face diameter dface, its machined area without the folded side [mm] "
                     "(needed: h0/d0 {ratio:.2f} ≥ 1.6, where the bulge barely tells friction)")


def face_asked(test: str, geometry_mm: dict) -> bool:
    """True when the end face's diameter is asked for: compression with h0/d0 ≥ 1.6."""
    d0, h0 = geometry_mm.get("d0_mm"), geometry_mm.get("h0_mm")
    return test == "compression" and bool(d0) and bool(h0) and h0 / d0 >= FACE_ASKED_FROM_H0_OVER_D0


def post_prompts(test: str, geometry_mm: dict) -> dict[str, str]:
    """The post-test prompts for this specimen (dface's says why it is needed on a tall one)."""
    prompts = {k: POST_PROMPTS[k] for k in POST_KEYS[test]}
    if face_asked(test, geometry_mm):
        prompts["post.dface_mm"] = FACE_ASKED_PROMPT.format(ratio=geometry_mm["h0_mm"] / geometry_mm["d0_mm"])
    return prompts


def missing_post_keys(test: str, geometry_mm: dict, have) -> list[str]:
    """The post-test measurements still to be given (dface only when asked for)."""
    optional = () if face_asked(test, geometry_mm) else ("post.dface_mm",)
    return [k for k in POST_KEYS.get(test, ()) if k not in have and k not in optional]


class ProcedureError(FlowcurveError):
    """A test that cannot be started as asked (missing geometry, no furnace for heating)."""


@dataclass
class TestSpec:
    """Everything about the test to run.

    Attributes
    ----------
    test : str
        "tension" or "compression".
    material, operator, specimen_id : str
        Written to the record's header.
    geometry_mm : dict
        d0_mm with l0_mm and optionally parallel_length_mm (Lc ≥ l0; tension) or h0_mm (compression), mm.
    temperature_C : float, optional
        Heating set-point, °C; None: room temperature.
    speed_mm_per_s : float
        Crosshead speed, mm/s.
    soak_s, soak_band_C, heat_timeout_s : float
        Test seconds the temperature stays within ±``soak_band_C`` °C; the longest heating, s.
    stop : StopCriteria
        When loading stops (fracture, target, force limit).
    post, extra_meta : dict
        Post-test measurements given up front (mm); more header values.
    opening_events : list of (name, text)
        Events written as the record opens: what was found before the test (a geometry other
        than the one the virtual rig simulates: ``geometry_mismatch``).
    """

    __test__ = False  # not a pytest test class

    test: str
    material: str = "unknown"
    operator: str = ""
    specimen_id: str = ""
    geometry_mm: dict[str, float] = field(default_factory=dict)  # d0_mm, l0_mm [, parallel_length_mm] / h0_mm
    temperature_C: float | None = None  # heating set-point; None = room temperature
    speed_mm_per_s: float = 0.01
    soak_s: float = 60.0  # test seconds the temperature must stay within the band
    soak_band_C: float = 5.0
    heat_timeout_s: float = 7200.0
    stop: StopCriteria = field(default_factory=StopCriteria)
    post: dict[str, float] = field(default_factory=dict)  # post-test measurements given up front
    extra_meta: dict[str, str] = field(default_factory=dict)
    opening_events: list[tuple[str, str]] = field(default_factory=list)

    def check(self) -> None:
        """ProcedureError unless the test, geometry (specimen_geometry.geometry_problem) and speed (> 0 mm/s) are valid."""
        if self.test not in TEST_GEOMETRY:
            raise ProcedureError(f"test must be tension or compression, not {self.test!r}")
        problem = geometry_problem(self.test, TEST_GEOMETRY[self.test], self.geometry_mm)
        if problem:
            raise ProcedureError(problem)
        if not self.speed_mm_per_s > 0:
            raise ProcedureError(f"crosshead speed must be > 0 mm/s, got {self.speed_mm_per_s}")

    def meta(self, rig: RigIO) -> dict[str, object]:
        """The record's header of this test on ``rig``: test, material, date, geometry, rig and instruments."""
        m: dict[str, object] = {
            "test": self.test,
            "material": self.material,
            "operator": self.operator,
            "date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
            "specimen.id": self.specimen_id or _dt.datetime.now().strftime(f"{self.test[0].upper()}%Y%m%d-%H%M%S"),
            "nominal_temperature_C": self.temperature_C if self.temperature_C is not None else 20.0,
            "crosshead_speed_mm_per_s": self.speed_mm_per_s,
        }
        if rig.frame_stiffness_N_per_um:
            m["rig.frame_stiffness_N_per_um"] = rig.frame_stiffness_N_per_um
        m.update(getattr(rig, "instruments_meta", None) or {})  # instruments.force_class … (uncertainty budgets)
        m.update(getattr(rig, "writer_meta", None) or {})  # writer.stamping: how the samples were stamped
        for key, v in self.geometry_mm.items():
            m[f"specimen.{key}"] = v
        m.update(self.extra_meta)
        return m


@dataclass
class Outcome:
    """What a run produced."""

    path: Path
    status: str
    reason: str
    samples: int
    duration_s: float
    max_force_N: float
    post: dict[str, float]
    error: FlowcurveError | None = None
    losses: str = ""  # what the record declares lost or rejected ("" when nothing)


def heating_progress(start_C: float, now_C: float, setpoint_C: float) -> float:
    """Fraction of the way from the start temperature to the set-point, in [0, 1]."""
    span = setpoint_C - start_C
    return 1.0 if abs(span) < 1e-9 else min(max((now_C - start_C) / span, 0.0), 1.0)


class Procedure(StreamNotes):
    """One test on one rig, written to ``path`` as it runs; :meth:`run` runs it.

    Parameters
    ----------
    rig : RigIO
        The rig (:class:`flowcurve.acquisition.session.DriverRig` or the virtual one).
    spec : TestSpec
        The test.
    path : str or PathLike
        The record file.
    view : LiveView, optional
        What shows the test live (default: nothing shown).
    interactive, prompt : bool, callable
        Ask the operator at the terminal, through ``prompt``.
    stop_requested : callable, optional
        Another thread's stop button: an operator-stop reason or None; may raise Interrupted.

    Raises
    ------
    ProcedureError
        Invalid geometry or speed; heating asked of a rig without a furnace or above its maximum.
    """

    tick_s = 0.05  # main-loop period (host seconds)

    def __init__(self, rig: RigIO, spec: TestSpec, path: str | os.PathLike, *, view: LiveView | None = None, interactive: bool = False, prompt: Callable[[str], str] = input, stop_requested: Callable[[], str | None] | None = None):
        spec.check()
        if spec.temperature_C is not None:
            if not rig.has_furnace:
                raise ProcedureError("heating was asked for but the rig configuration has no furnace")
            if spec.temperature_C >= rig.max_temperature_C:
                raise ProcedureError(f"set-point {spec.temperature_C:g} C is not below the configured maximum {rig.max_temperature_C:g} C")
            refusal = setpoint_refusal(spec.temperature_C, rig.max_temperature_C, getattr(rig, "setpoint_margin_C", SETPOINT_MARGIN_C))
            if refusal:
                raise ProcedureError(f"set-point {refusal}")
        self.rig, self.spec, self.path = rig, spec, Path(path)
        self.view = view or LiveView(quiet=True)
        self.interactive, self.prompt = interactive, prompt
        self.timebase: Clock = getattr(rig, "timebase", WALL)
        # another thread's stop button (the console): an operator-stop reason, or None; it may raise Interrupted to abort
        self.stop_requested = stop_requested or (lambda: None)
        self._t0 = 0.0
        self.writer: RecordWriter | None = None
        self._writing = False
        self._ending_process = False  # the test was ended by the system stopping the program (not an operator's Ctrl-C)
        self._heater_released = False  # set at the end's switch-off: the furnace channel reads, no longer controls
        self._retried_noted: dict[str, int] = {}  # exchanges retried per device, as the record's events last said
        self._failed_noted: dict[str, int] = {}  # ... of them failed on every retry too
        self._wrong_noted: dict[str, int] = {}  # replies from another module's address the events named, per device
        self._unshown_rows: list[np.ndarray] = []  # recorded rows no snapshot has carried yet (the last batch)
        self._end_reason = ""
        self._motion_seen = False  # the start event written (or the procedure drives the crosshead itself)
        self._storage_error: RecordWriteError | None = None
        self._dropped = 0
        self._restarts_noted = 0
        self._missing_noted = 0  # the load cell's missing frames the events named so far
        self._carried_stop: tuple | None = None  # (t, x of the last reading, t of the stop, speed): a stop on a carried-on position
        self._latency_noted = 0.0  # the load cell's stream latency the events named so far (host s)
        self._undecided_noted = 0  # the load cell's stream gaps neither latency nor loss could be told of, named so far
        self._late_noted: dict[str, int] = {}
        self._rejected_noted: dict[str, int] = {}
        self._speed = SpeedMeter()

    # clock: test seconds since the procedure started (time-scaled on the virtual rig)
    def clock(self) -> float:
        """Test seconds since the procedure started (time-scaled on the virtual rig)."""
        return (self.timebase.now() - self._t0) * self.rig.time_scale

    def to_clock(self, t_host: float) -> float:
        """Host time ``t_host`` (s) as test seconds."""
        return (t_host - self._t0) * self.rig.time_scale

    def _event(self, name: str, text: str = "") -> None:
        if self.writer is not None and self._writing:
            self._storing(self.writer.event, self.clock(), name, text)

    def _write_rows(self, rows: np.ndarray) -> None:
        if self._writing:
            self._storing(self.writer.append_rows, rows)
            self._speed.update(rows)

    def _speed_meta(self) -> dict[str, object]:
        """The header's measured crosshead speed (mm/s, when the crosshead travelled far enough to tell it)."""
        measured = self._speed.speed_mm_per_s()
        out: dict[str, object] = {} if measured is None else {MEASURED_SPEED_KEY: float(f"{measured:.4g}")}
        # the crosshead's stamps: the count was read somewhere in its exchange's bracket (± the widest kept
        # half-width, host s): a rectangular u in the record's time (the testing rate's U, identification/quality/conformity.py)
        half_s = getattr(self.rig, "position_half_width_s", 0.0) * getattr(self.rig, "time_scale", 1.0)
        if half_s > 0:
            out["instruments.crosshead_stamp_u_s"] = float(f"{half_s / math.sqrt(3.0):.3g}")
        return out

    def _note_speed(self) -> None:
        """A ``speed_mismatch`` event and the operator told when the crosshead ran at another speed than commanded."""
        mismatch = speed_mismatch(self.spec.speed_mm_per_s, self._speed.speed_mm_per_s())
        if mismatch:
            self._event("speed_mismatch", mismatch)
            self._alert(f"crosshead: {mismatch} — set the machine's speed to the test's")

    def _storing(self, write, *args) -> None:
        """A write to the record; a full disk (or any OSError) stops the recording, once."""
        try:
            write(*args)
        except OSError as exc:
            self._writing = False
            self._storage_error = RecordWriteError(
                f"{self.path}: cannot write the record any more ({_os_reason(exc)}) — the test was stopped; what "
                f"reached the disk is kept (up to {self.writer.rows_written} samples). Free space, then 'flowcurve recover {self.path}'")
            raise self._storage_error from None

    def _close(self, status: str, extra: dict) -> None:
        was_writing, self._writing = self._writing, False
        if not was_writing and self._storage_error is not None:
            try:  # the disk is full: let go of the file; recover completes the header later
                self.writer._fh.close()
            except OSError:
                pass
            return
        try:
            self.writer.close(status, extra)
        except OSError as exc:
            self._storage_error = self._storage_error or RecordWriteError(
                f"{self.path}: cannot finish the record ({_os_reason(exc)}); {self.writer.rows_written} samples are "
                f"on disk. Free space, then 'flowcurve recover {self.path}'")

    def run(self) -> Outcome:
        """Run the test: heat and soak, tare, record until a stop criterion, post-test measurements.

        The heater is off and the motion stopped on every way out; the record is closed complete or
        aborted (with the reason).

        Returns
        -------
        Outcome
            Path, status, reason, samples, duration, maximum force and post-test measurements.
        """
        spec, rig = self.spec, self.rig
        self._t0 = self.timebase.now()
        rig.set_clock(self.clock)
        self._open_record()
        status, reason, error = STATUS_COMPLETE, "", None
        state = StopState()
        sampler: Sampler | None = None
        try:
            # the drivers retry heater-off themselves: one attempt here, then the module watchdog
            with HeaterSafety(rig.heater_off, arm_watchdog=rig.arm_watchdog if rig.has_furnace else None, log=self._event, retries=1) as safety:
                try:
                    if spec.temperature_C is not None:
                        self._heat()
                    self.view.show(Snapshot("tare", time_s=self.clock()), force=True)
                    rig.tare()
                    self._event("tare")
                    sampler = Sampler(rig.channels(self.clock, self.to_clock))
                    install_guards(sampler, self.rig, self.spec.speed_mm_per_s)
                    if rig.has_furnace:  # keep holding the set-point (or just read), feed the watchdog
                        furnace = sampler.channels["temperature_C"]
                        furnace.read = self._furnace_read(lambda exc: furnace.on_fault(furnace.device, str(exc), exc))
                    sampler.start()
                    reason = self._record(sampler, state)
                except Interrupted as exc:
                    self._ending_process = exc.signame != "SIGINT"  # SIGTERM, a console shutting down: no one waits at a keyboard
                    if exc.signame == "SIGINT" and sampler is not None:  # Ctrl-C while loading: an operator stop
                        reason = "operator stop (Ctrl-C)"
                    else:
                        status, reason = STATUS_ABORTED, str(exc)
                except FlowcurveError as exc:
                    status, reason, error = STATUS_ABORTED, str(exc), exc
                finally:
                    self._end_reason = reason
                    self._stop_motion_first(sampler, error)
                    self._let_streams_finish(sampler, error)
                    self._heater_released = True  # no control step from here on commands the heater
                    safety.switch_off(reason or "end of test")
                    self._stop_motion()
                    if sampler is not None:
                        status, reason, error = self._final_rows(sampler, safety, status, reason, error)
                    error = self._after_safety_stop(error, safety.off_confirmed)
                    reason = self._stop_noted(reason, error, safety.off_confirmed)
        except BaseException as exc:  # anything unexpected: keep the record, mark it aborted
            self._close(STATUS_ABORTED, {"abort_reason": " ".join(f"{type(exc).__name__}: {exc}".split())})
            raise
        return self._outcome(status, reason, error, state)

    def _open_record(self) -> None:
        """Create the record file before anything moves or heats (RecordWriteError if it cannot be)."""
        rig = self.rig
        columns = ["time_s", "force_N", "crosshead_mm"] + (["temperature_C"] if rig.has_furnace else [])
        try:
            self.writer = RecordWriter(self.path, self.spec.meta(rig), columns)
        except OSError as exc:  # before anything moves or heats
            raise RecordWriteError(f"{self.path}: cannot create the record ({_os_reason(exc)}) — the test was not "
                                   "started; give --out a folder you can write to, with free space") from None
        self._writing = True
        for name, text in self.spec.opening_events:
            self._event(name, text)

    def _let_streams_finish(self, sampler: Sampler | None, error: FlowcurveError | None) -> None:
        """At the stop, before the heater goes off: the frames still on the line, or the crosshead's
        reading after a carried-on stop, are waited for; then the reading threads let go of the ports."""
        lag = getattr(self.rig, "stream_latency_s", 0.0) if sampler is not None and error is None else 0.0
        if lag > 0:  # the line still holds the frames sent before the stop: stop, then let them arrive
            self._stop_motion()
            self.timebase.sleep(lag + self.tick_s)
        if sampler is not None and error is None and self._carried_stop:
            self._stop_motion()  # stopped on a carried-on position: the rows wait for a reading after the stop
            self._await_reading(sampler.channels.get("crosshead_mm"), self.clock())
        if sampler is not None:  # the reading threads let go of the ports first
            sampler.request_stop()

    def _note_motion(self, rows: np.ndarray) -> bool:
        """The ``start`` event at the first row :data:`MOTION_MM` from zero (tare zeroes the counter), once."""
        if not self._motion_seen and rows.size:
            moved = np.flatnonzero(np.abs(rows[:, 2]) > MOTION_MM)
            if moved.size:
                self._motion_seen = True
                self._storing(self.writer.event, float(rows[moved[0], 0]), "start", f"crosshead motion detected ({rows[moved[0], 2]:+.3f} mm)")
        return self._motion_seen

    def _final_rows(self, sampler: Sampler, safety: HeaterSafety, status: str, reason: str,
                    error: FlowcurveError | None) -> tuple[str, str, FlowcurveError | None]:
        """After the switch-off: the last rows written, a fault found while stopping told, the losses
        and the speed noted; returns (status, reason, error)."""
        final = self._carry_crosshead(sampler, self._drop_unbracketed(sampler, sampler.finish()))
        if self.rig.has_furnace and safety.off_confirmed:  # a control step in flight at the switch-off
            safety.switch_off(reason or "end of test")  # may have switched it on again: off once more
        self._feed_watchdog()  # the furnace channel has stopped feeding it
        late = sampler.fault
        if error is None and isinstance(late, SafetyError):  # found while stopping: still told
            error = late
            self._event("fault", str(late))
        silent = sampler.failing_at_end() if error is None and late is None else None
        if silent is not None:  # a device silent at the end: its values there are unknown
            status, error = STATUS_ABORTED, silent
            self._event("fault", str(silent))
        self._unshown_rows.append(final)
        try:
            self._note_motion(final)  # rows taken after a target the stream's freshest reading reached
            self._write_rows(final)
            self._note_losses(sampler, final=True)
            self._note_speed()
        except RecordWriteError as exc:
            status, reason, error = STATUS_ABORTED, reason or str(exc), error or exc
        return status, reason, error

    def _stop_noted(self, reason: str, error: FlowcurveError | None, off_confirmed: bool) -> str:
        """The retries noted, an unconfirmed heater-off told, the ``stop`` event written; the reason
        (a safety error's, when one came after the stop)."""
        try:
            self._note_retries(final=True)  # the furnace watch's exchanges too
        except RecordWriteError:
            pass
        if error is not None and reason != str(error) and isinstance(error, SafetyError):
            reason = str(error)
        if not off_confirmed and self.rig.has_furnace:
            self._alert("furnace: heater-off not confirmed — the furnace module's watchdog switches it off "
                        "by itself; if the furnace keeps heating, switch off its mains power")
        try:
            self._event("stop", reason)
        except RecordWriteError:
            pass
        return reason

    def _outcome(self, status: str, reason: str, error: FlowcurveError | None, state: StopState) -> Outcome:
        """The record closed with its stop and loss keys, the post-test measurements asked and
        amended when complete, the last snapshot shown: the test's outcome."""
        extra = {"stop_reason": reason, **self._loss_meta(), **self._speed_meta()}
        if status == STATUS_ABORTED:
            extra["abort_reason"] = reason
        samples = self.writer.rows_written
        self._close(status, extra)
        self._feed_watchdog()
        if self._storage_error is not None:
            status, error = STATUS_ABORTED, error if isinstance(error, RecordWriteError) else self._storage_error
        post = {}
        if status == STATUS_COMPLETE:
            post = self._post_measurements()
            if post:
                amend_record(self.path, post)
            self._feed_watchdog()
        tail = [r for r in self._unshown_rows if r.size]
        self.view.show(Snapshot("done", time_s=self.clock(), samples=samples, message=reason,
                                rows=np.concatenate(tail) if tail else None), force=True)
        return Outcome(self.path, status, reason, samples, self.clock(), state.max_force_N, post, error, self._loss_summary())

    # phases --------------------------------------------------------------------------------
    def _heat(self) -> None:
        spec, rig = self.spec, self.rig
        setpoint = spec.temperature_C
        start_C = check_temperature(rig.read_temperature_C(), rig.max_temperature_C)
        self._event("heater_on", f"set-point {setpoint:g} C")
        t_start = self.clock()
        steady_since = None
        # at least HEAT_STEPS_PER_PERIOD control steps per heater period (test seconds), however
        # fast the (virtual) rig's time runs; HEAT_MIN_TICK_S is what a host can keep up with
        period = getattr(rig, "control_period_s", None)
        tick = self.tick_s if not period else min(self.tick_s, max(HEAT_MIN_TICK_S, period / HEAT_STEPS_PER_PERIOD / rig.time_scale))
        while True:
            temp = check_temperature(rig.hold_temperature(setpoint), rig.max_temperature_C)
            rig.host_ok()
            now = self.clock()
            if abs(temp - setpoint) <= spec.soak_band_C:
                steady_since = now if steady_since is None else steady_since
                if now - steady_since >= spec.soak_s:
                    self._event("soak_reached", f"{temp:.1f} C for {spec.soak_s:g} s")
                    return
                state, msg = "soaking", f"{now - steady_since:.0f}/{spec.soak_s:g} s at {temp:.1f} C"
            else:
                steady_since = None
                state, msg = "heating", f"{temp:.1f} -> {setpoint:g} C"
            if now - t_start > spec.heat_timeout_s:
                raise ProcedureError(f"the furnace did not reach {setpoint:g} C within {spec.heat_timeout_s:g} s (now {temp:.1f} C)")
            self.view.show(Snapshot(state, time_s=now, temperature_C=temp, progress=heating_progress(start_C, temp, setpoint), message=msg))
            asked = self.stop_requested()
            if asked:  # before loading, a stop ends the test unloaded: aborted
                raise Interrupted(asked)
            self.timebase.sleep(tick)

    def _furnace_read(self, stop: Callable[[FlowcurveError], None]) -> Callable[[], float]:
        """The furnace channel's read: hold the set-point (or read), the stuck-relay check of an
        unheated test, feed the watchdog. A heater command answered from another module's address
        stops the test at once (``stop``; the heater's state is unknown, no more commands), where
        a read's failures are counted and retried by the channel."""
        setpoint, rig = self.spec.temperature_C, self.rig

        from flowcurve.rig.furnace import StuckRelayCheck  # (pyserial: not on the parser's import path)

        # a test that never heats has the heater commanded off throughout: a furnace that warms is a stuck relay
        never_heated = (StuckRelayCheck(self._furnace_name(), settle_s=0.0, max_temperature_C=rig.max_temperature_C)
                        if setpoint is None else None)

        def guarded() -> float:
            """One furnace read: a control step toward the set-point while heating holds, else a reading, °C."""
            hold = setpoint is not None and not self._heater_released
            try:
                temp = rig.hold_temperature(setpoint) if hold else rig.read_temperature_C()
            except FlowcurveError as exc:
                if getattr(exc, "commanded", False):  # rig.transport.WrongAddressError on @AADO
                    self._heater_released = True
                    stop(exc)
                raise
            check_temperature(temp, rig.max_temperature_C)
            if never_heated is not None:
                never_heated.update(temp, self.clock(), False)
            rig.host_ok()
            return temp

        return guarded

    def _start_loading(self) -> StopCriteria:
        """The crosshead started (or the operator asked to start it); the stop criteria, with the
        force limit at FORCE_LIMIT_OF_CAPACITY of the frame's capacity when none is given."""
        spec, rig = self.spec, self.rig
        direction = 1 if spec.test == "tension" else -1
        if rig.can_drive:
            rig.start_crosshead(spec.speed_mm_per_s, direction)
            self._event("start", f"crosshead {spec.speed_mm_per_s:g} mm/s")
        else:
            self.view.say(f"Start the crosshead motor ({'up, tension' if direction > 0 else 'down, compression'}, {spec.speed_mm_per_s:g} mm/s); recording waits for motion.")
        crit = spec.stop
        capacity = getattr(rig, "max_force_N", None)
        if crit.force_limit_N is None and capacity:
            crit = replace(crit, force_limit_N=FORCE_LIMIT_OF_CAPACITY * capacity)
        return crit

    def _show_recording(self, sampler: Sampler, now: float, moving: bool, rate: float, curve_x: list, curve_f: list,
                        rows: np.ndarray) -> None:
        """The live view's snapshot while recording: the latest readings, the rate, the curve so far."""
        latest = sampler.latest()
        self.view.show(Snapshot(
            "recording" if moving else "waiting",
            time_s=now,
            force_N=latest.get("force_N", math.nan),
            crosshead_mm=latest.get("crosshead_mm", math.nan),
            temperature_C=latest.get("temperature_C", math.nan),
            rate_per_s=rate,
            samples=self.writer.rows_written,
            curve_mm=np.concatenate(curve_x) if curve_x else None,
            curve_N=np.concatenate(curve_f) if curve_f else None,
            rows=rows if rows.size else None,
        ))

    def _record(self, sampler: Sampler, state: StopState) -> str:
        """Record rows until a stop criterion, the displacement target, a fault, q or a stop request; the reason."""
        spec, rig = self.spec, self.rig
        crit = self._start_loading()
        moving = self._motion_seen = rig.can_drive
        curve_x: list[np.ndarray] = []
        curve_f: list[np.ndarray] = []
        rate_t, rate_n = self.clock(), 0
        rate = math.nan
        with KeyWatcher(self.interactive) as keys:
            while True:
                rows = sampler.take_rows()
                self._note_losses(sampler)
                if rows.size:
                    self._write_rows(rows)
                    self._unshown_rows.append(rows)  # until a snapshot carries them (a stop, fault or q ends the loop first)
                    moving = self._note_motion(rows)
                    curve_x.append(rows[::10, 2])
                    curve_f.append(rows[::10, 1])
                    reason = stop_reason(rows, state, crit)
                    if reason:
                        return reason  # the done snapshot carries the rows to live plots
                crosshead = sampler.channels.get("crosshead_mm")
                reason = target_reached(crosshead.stream.last() if crosshead is not None else None, crit, now_s=self.clock(),
                                        speed_mm_per_s=spec.speed_mm_per_s if rig.can_drive else 0.0,
                                        stale_s=STALE_CROSSHEAD_S * rig.time_scale, carry_max_s=CARRY_MAX_S * rig.time_scale)
                if reason:
                    if "carried on" in reason:  # the end waits for a crosshead reading after the stop
                        self._carried_stop = (*crosshead.stream.last(), self.clock(), spec.speed_mm_per_s)
                    return reason
                fault = sampler.fault or sampler.check_silence()
                if fault is not None:
                    self._event("fault", str(fault))
                    raise fault
                if keys.quit_pressed():
                    return "operator stop (q)"
                asked = self.stop_requested()
                if asked:
                    return asked
                now = self.clock()
                if now - rate_t >= 1.0 * rig.time_scale:
                    released = sampler.released
                    rate = (released - rate_n) / ((now - rate_t) / rig.time_scale)
                    rate_t, rate_n = now, released
                self._show_recording(sampler, now, moving, rate, curve_x, curve_f, rows)
                self._unshown_rows.clear()
                last = crosshead.stream.last() if crosshead is not None else None
                self.timebase.sleep(loop_tick_s(last, crit, spec.speed_mm_per_s, rig.time_scale, self.tick_s))

    def _stop_motion_first(self, sampler: Sampler | None, error: FlowcurveError | None) -> None:
        """A test that ended on its criterion, the drive answering: the motion stops before the heater,
        since it goes on loading the specimen unrecorded while a faulty furnace's heater-off is retried
        (the heater's inertia and watchdog wait one command); on a device fault the heater goes first."""
        if error is None and sampler is not None and self.rig.can_drive:
            self._stop_motion()

    def _stop_motion(self) -> None:
        try:
            if self.rig.can_drive:
                self.rig.stop_crosshead()
            else:  # always, --quiet too: the motor is the operator's
                self._alert(f"Stop the crosshead motor ({self._end_reason or 'end of test'}).")
        except Exception as exc:  # never let this hide the real end of the test
            self._event("fault", f"crosshead stop failed: {exc}")

    # plausibility and losses ------------------------------------------------------------------
    def _await_reading(self, channel, after_s: float) -> None:
        """Wait (up to STALE_WAIT_S host seconds) for ``channel``'s first reading after ``after_s`` (test s)."""
        deadline = self.timebase.now() + STALE_WAIT_S
        while channel is not None and channel.stream.last_time() < after_s and self.timebase.now() < deadline:
            self.timebase.sleep(TARGET_TICK_MIN_S)

    def _carry_crosshead(self, sampler: Sampler, rows: np.ndarray) -> np.ndarray:
        """After a stop on a carried-on position: the rows between the last reading before the stop
        and the first after it get the crosshead carried on at the speed to the stop, x = x₀ + v·(t − t₀)
        (linear interpolation across the stop would bend it), when the reading after the stop agrees
        with the carried-on stop within CARRY_AGREE_MM; else they are left out (an event says so)."""
        if not self._carried_stop or not rows.size:
            return rows
        t0, x0, t_stop, v = self._carried_stop
        after = sampler.channels["crosshead_mm"].stream.last()
        gap = (rows[:, 0] > t0) & (rows[:, 0] <= (after[0] if after else np.inf))
        direction = 1.0 if x0 >= 0 else -1.0
        x_stop = x0 + direction * v * (t_stop - t0)  # the crosshead at the stop, carried on at the speed
        if after is not None and after[0] > t_stop and abs(after[1] - x_stop) <= CARRY_AGREE_MM:
            rows = rows.copy()
            rows[gap, 2] = x0 + direction * v * (np.minimum(rows[gap, 0], t_stop) - t0)
            self._event("carried", f"crosshead encoder: {int(gap.sum())} rows between its readings at {t0:.3f} and "
                                   f"{after[0]:.3f} s carried on at {v:g} mm/s to the stop (the reading after it agrees "
                                   f"within {CARRY_AGREE_MM:g} mm)")
            return rows
        self._dropped += int(gap.sum())
        self._event("dropped", f"{int(gap.sum())} force samples in the crosshead encoder's gap across the stop left out "
                               "(no reading after the stop agrees with the carried-on position)")
        return rows[~gap]

    def _drop_unbracketed(self, sampler: Sampler, rows: np.ndarray) -> np.ndarray:
        """The last rows without their faulted channel's values: a held value is no reading."""
        fault = sampler.fault
        device = getattr(fault, "device", None)
        for ch in list(sampler.channels.values())[1:]:
            if ch.device == device and rows.size:
                keep = rows[:, 0] <= ch.stream.last_time()
                self._dropped += int(np.count_nonzero(~keep))
                if not keep.all():
                    self._event("dropped", f"{int(np.count_nonzero(~keep))} force samples after the {device}'s last "
                                           f"reading ({ch.stream.last_time():.3f} s) left out")
                return rows[keep]
        return rows

    def _after_safety_stop(self, error: FlowcurveError | None, off_confirmed: bool = True) -> FlowcurveError | None:
        """After a heated test or an over-temperature the heater is off, or must be: watch the
        furnace cool for a while; if it keeps heating, the relay is stuck (SafetyError, the
        operator cuts the power) — nothing watches the furnace once the process has ended.
        After a test that did not heat, while the furnace answers, a shorter watch without
        settling (no stored heat): a relay that stuck during a short test shows only then."""
        watch = getattr(self.rig, "watch_heater_off", None)
        heated = self.spec.temperature_C is not None and not isinstance(error, SafetyError)
        over = isinstance(error, SafetyError) and "over-temperature" in str(error)
        unheated = (self.spec.temperature_C is None and self.rig.has_furnace
                    and getattr(error, "device", None) != self._furnace_name())
        if not (watch and (heated or over or unheated)):
            return error
        # the heater-off confirmed, or only sent: then the module's own watchdog switches it off once the host is silent
        unconfirmed = "" if off_confirmed else " — heater-off not confirmed: the module's hardware watchdog switches it off"
        if self._ending_process and not over:  # a service manager or a console shutting down will not wait the watch out
            if heated:
                self._alert(f"furnace: {'heater off; ' if off_confirmed else ''}the program is being stopped, so nothing "
                            f"watches the furnace cool — check that it does (a stuck relay keeps heating){unconfirmed}")
            return error
        if heated or over:
            self._alert(f"furnace: {'over-temperature — ' if over else ''}{'heater off; ' if off_confirmed else ''}watching "
                        f"that it cools ({WATCH_COOLING_S:g} s test time, longer while it still rises){unconfirmed}")
            seconds, settle = WATCH_COOLING_S, {}
        else:
            seconds, settle = WATCH_UNHEATED_S, {"settle_s": 0.0}

        def extended(why: str) -> None:
            """Tell the operator, and the record, that the furnace watch was extended and why."""
            self._alert(f"furnace: {why}")
            self._event("watch_extended", why)

        try:
            watch(seconds, **settle, longest_s=WATCH_LONGEST_S, on_extend=extended)
        except SafetyError as exc:
            self._event("fault", str(exc))
            if error is None:
                return exc
            # the relay finding first (the operator must act), and the fault that stopped the test in its own words
            both = SafetyError(exc.device, f"{str(exc)[len(exc.device) + 2:]}; the test had stopped on: {error}")
            both.stopped_by = error
            return both
        except FlowcurveError:
            pass
        return error

    def _furnace_name(self) -> str:
        return getattr(getattr(self.rig, "furnace", None), "name", "furnace")

    def _feed_watchdog(self) -> None:
        """Until the rig disarms the furnace module's watchdog at close, keep it fed: a trip
        after a clean stop is no fault (the heater is off) but reads like one."""
        try:
            self.rig.host_ok()
        except (FlowcurveError, OSError):
            pass

    def _alert(self, text: str) -> None:
        getattr(self.view, "alert", self.view.say)(text)

    def _post_measurements(self) -> dict[str, float]:
        keys = POST_KEYS[self.spec.test]
        post = {k: v for k, v in self.spec.post.items() if v is not None}
        missing = [k for k in keys if k not in post]
        if missing:
            measured = self.rig.post_test_measurements() or {}
            post.update({k: float(v) for k, v in measured.items() if k in missing and v is not None})
        missing = [k for k in keys if k not in post]
        if missing and self.interactive:
            self.view.say("Post-test measurements (Enter to skip; add later with 'flowcurve annotate'):")
            prompts = post_prompts(self.spec.test, self.spec.geometry_mm)
            asked = missing_post_keys(self.spec.test, self.spec.geometry_mm, ())
            for key in missing:
                text = self.prompt(f"  {prompts.get(key, key)}: ").strip()
                if not text and key == "post.dface_mm" and key in asked:  # asked for: once more, saying why
                    text = self.prompt("  dface is needed to tell μ on a specimen this tall; measure the original end face "
                                       "(Enter again to add it later with 'flowcurve annotate'): ").strip()
                if text:
                    try:
                        post[key] = float(text)
                    except ValueError:
                        self.view.say(f"  not a number, skipped: {text!r}")
            still = missing_post_keys(self.spec.test, self.spec.geometry_mm, post)
            if still:
                self.view.say(f"still missing: {', '.join(still)} (add with 'flowcurve annotate RECORD --set KEY=VALUE')")
        return post


def _os_reason(exc: OSError) -> str:
    return exc.strerror or str(exc) if isinstance(exc, OSError) else str(exc)

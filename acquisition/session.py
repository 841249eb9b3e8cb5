"""The rig as a procedure sees it: the real drivers over the configured ports.

:class:`DriverRig` implements :class:`acquisition.rig_io.RigIO` with the device of each role
(:mod:`rig.roles`) its configuration names: a force device (default
:class:`rig.loadcell.LoadCell`, streaming ``MSV?0``, stamped on arrival), a position device
(:class:`rig.encoder.CrossheadEncoder`) and a temperature device (:class:`rig.furnace.Furnace`)
with its :class:`rig.furnace.TemperatureController`. The same class serves the virtual rig: it then
talks to the virtual devices' pseudo-terminals through the same drivers, and the optional
``virtual`` handle lets the procedure start the crosshead and read the post-test
measurements the way an operator would.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable

from flowcurve.acquisition.sampler import Channel
from flowcurve.clock import WALL, Clock
from flowcurve.errors import DeviceError, SafetyError
from flowcurve.record.format import WRITER_STAMPING, WRITER_STAMPING_KEY
from flowcurve.rig.furnace import STUCK_RELAY_ADVICE, StuckRelayCheck
from flowcurve.rig.roles import ForceDevice, PositionDevice, TemperatureDevice

logger = logging.getLogger(__name__)

# Host seconds a device may stay silent before the test stops (the drivers' own
# time-outs and retries come first; this catches a read that hangs or returns nothing).
SILENCE_MIN_S = 1.5
SILENCE_TIMEOUTS = 10  # ... or this many of the device's reply time-outs, if longer
ENCODER_PERIOD_S = 0.02  # host-time polling period of the encoder box
FURNACE_PERIOD_S = 0.25  # of the furnace module (DCON replies take up to 0.3 s) ...
FURNACE_MIN_PERIOD_S = 0.02  # ... shorter on a time-scaled virtual rig: 4 steps per control period
FURNACE_VERIFY_S = 1.0  # host seconds between the furnace module's address checks (@AADI)
STUCK_SETTLE_S = 30.0  # test seconds with the heater off before the furnace must not rise any more
STILL_RISING_C = 1.0  # a furnace risen more than this over the stuck-relay check's confirm_s (5 s) still rises (noise ~0.1 C)
STREAM_BLOCK = 20  # load-cell frames per read call at most
BRACKET_SLACK_S = 0.002  # host seconds a crosshead exchange's half-width may exceed the narrowest one's
BRACKET_KEEP_S = 0.2  # ... a reading is kept at least this often (host seconds) all the same


def force_filter_meta(loadcell) -> dict[str, float]:
    """``instruments.force_filter_Hz``: the −3 dB point of the amplifier's low-pass the test sets (``[loadcell] filter``,
    ASF1…8), whose lag the identification states (identification/quality/filter_lag.py); nothing for no filter."""
    from flowcurve.rig.codecs.aed import ASF_CUTOFF_HZ

    cutoff = ASF_CUTOFF_HZ.get(getattr(loadcell, "filter", None))
    return {"instruments.force_filter_Hz": cutoff} if cutoff else {}


class DriverRig:
    """A configured rig opened for one test: the procedure's RigIO over the device drivers.

    Parameters
    ----------
    config : RigConfig
        The rig's configuration.
    time_scale : float
        Test seconds per host second: 1 on the real rig, the virtual rig's when its model runs faster.
    virtual : VirtualRig, optional
        The virtual rig to drive (crosshead, post-test measurements); None on the real rig.
    stream : bool
        Read the load cell as a ``MSV?0`` stream (True) or poll ``MSV?`` (False).
    timebase : Clock, optional
        Host time: the virtual rig's clock when there is one, else the wall clock.
    """

    loadcell: ForceDevice
    encoder: PositionDevice
    furnace: TemperatureDevice | None

    def __init__(self, config, *, time_scale: float = 1.0, virtual=None, stream: bool = True,
                 timebase: Clock | None = None):
        self.config = config
        self.timebase: Clock = timebase or (virtual.clock if virtual is not None else WALL)
        self.time_scale = float(time_scale)
        self.virtual = virtual
        self.stream = stream
        self.can_drive = virtual is not None
        self.has_furnace = config.furnace is not None
        self.max_temperature_C = config.furnace.max_temperature_C if self.has_furnace else float("inf")
        self.setpoint_margin_C = config.furnace.setpoint_margin_C if self.has_furnace else 0.0
        self.control_period_s = config.furnace.control_period_s if self.has_furnace else None
        self.frame_stiffness_N_per_um = config.frame.stiffness_N_per_um
        enc = config.encoder  # one count of the encoder in mm: the crosshead readings' quantum (the testing rate's U)
        self.instruments_meta = {**config.instruments.meta(),  # the instruments' classes, for the results' uncertainty
                                 "instruments.crosshead_resolution_mm": enc.screw_lead_mm / enc.gear_ratio / enc.counts_per_rev,
                                 **force_filter_meta(config.loadcell)}
        self.writer_meta = {WRITER_STAMPING_KEY: WRITER_STAMPING}  # how this driver stamps (the record's writer.stamping)
        self.max_force_N = config.frame.max_force_N
        self.loadcell = config.loadcell.create()
        self.encoder = config.encoder.create()
        self.furnace = config.furnace.create() if self.has_furnace else None
        self.loadcell_period_s = 1.0 / self.loadcell.supported_rates_Hz()[config.loadcell.rate_code]
        self._controller = None
        self._stuck = None
        self._verified_at = -float("inf")
        self.position_half_width_s = 0.0
        self.positions_doubted = 0
        self._narrowest_half_s = float("inf")
        self._position_kept_at = -float("inf")
        self._clock: Callable[[], float] = lambda: self.timebase.now() * self.time_scale

    # life cycle ------------------------------------------------------------------------------
    def open(self) -> "DriverRig":
        """Open and configure every device of the rig; the rig (closed again on an error)."""
        try:
            self.loadcell.open()
            self.loadcell.configure(**self.config.loadcell.settings)
            self.encoder.open()
            self.encoder.position_mm()  # answers at all?
            if self.furnace is not None:
                self.furnace.open()
                self.furnace.clear_watchdog()  # a watchdog that tripped earlier blocks the outputs
                self.furnace.heater_off()
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        """Stop the stream, heater off (Furnace.close does it), release every port.

        The furnace's host watchdog is disarmed only after an acknowledged heater-off; if
        that fails it stays armed and switches the heater off by itself.
        """
        if self.furnace is not None and self.furnace.transport.is_open:
            try:
                if self.furnace.heater_off() and self.furnace.watchdog_armed:
                    self.furnace.disarm_watchdog()
            except (DeviceError, OSError) as exc:  # the watchdog stays armed: the module switches off by itself
                logger.warning("%s: disarming the watchdog failed (%s); it stays armed and switches the heater off by itself", self.furnace.name, exc)
            self.furnace.transport.close()  # heater-off tried just now: no second round in Furnace.close
        for dev in (self.loadcell, self.encoder, self.furnace):
            if dev is None:
                continue
            try:
                dev.close()
            except (DeviceError, OSError) as exc:  # closing must go on to the next device
                logger.warning("%s: closing failed: %s", dev.name, exc)

    def __enter__(self) -> "DriverRig":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    # channels --------------------------------------------------------------------------------
    def channels(self, clock: Callable[[], float], to_clock: Callable[[float], float]) -> dict[str, Channel]:
        """One reading thread per device; force first (the reference clock)."""
        self._to_clock = to_clock
        cell = self.loadcell
        if self.stream:
            started = []

            def read_force():  # stamped by the driver on the stream's rhythm (rig.loadcell.stream_stamps)
                """The load cell's stream (started on the first call): (time s, force N) readings."""
                if not started:
                    cell.start_stream()
                    started.append(True)
                return [(to_clock(s.t_monotonic_s), s.force_N) for s in cell.read_stream(STREAM_BLOCK, 0.1)]

            def flush_force():
                """The frames the driver held after a gap it had not decided yet (rig.loadcell.gap_after_verdict)."""
                return [(to_clock(s.t_monotonic_s), s.force_N) for s in cell.flush_held()] if started else []

            heard = lambda: cell.frames_received  # noqa: E731 - held frames are no silence
        else:

            def read_force():
                """One polled load cell reading: [(time s, force N)]."""
                s = cell.read()
                return [(to_clock(s.t_monotonic_s), s.force_N)]

            flush_force, heard = None, None

        chans = {
            # polled: once per output period (a faster poll would read the same value again)
            "force_N": Channel(cell.name, read_force, clock, period_s=0.0 if self.stream else self.loadcell_period_s, silence_s=self._silence_s(self.config.loadcell), timebase=self.timebase, heard=heard, flush=flush_force),
            "crosshead_mm": Channel(self.encoder.name, self._read_position, clock, period_s=ENCODER_PERIOD_S, silence_s=self._silence_s(self.config.encoder), timebase=self.timebase, stands=True),
        }
        if self.furnace is not None:
            per_control = self.config.furnace.control_period_s / 4.0 / self.time_scale
            furnace_period = max(FURNACE_MIN_PERIOD_S, min(FURNACE_PERIOD_S, per_control))  # not `period`: read_force's closure holds that name
            chans["temperature_C"] = Channel(self.furnace.name, self._read_temperature, clock, period_s=furnace_period, silence_s=self._silence_s(self.config.furnace), timebase=self.timebase)
        return chans

    @property
    def stream_restarts(self) -> int:
        """How often the load cell's garbled stream was restarted (frames are lost each time)."""
        return self.loadcell.stream_resyncs

    @property
    def frames_lost(self) -> int:
        """Load-cell frames the stream restarts cost (estimated from the gaps they left)."""
        return self.loadcell.frames_lost

    @property
    def stream_latency_s(self) -> float:
        """Host seconds the load cell's line latency grew since its stream started (its frames are
        stamped that much before they arrive: :func:`rig.loadcell.gap_is_latency`)."""
        return self.loadcell.latency_s

    @property
    def stream_gaps_undecided(self) -> list[tuple[float, float]]:
        """The load cell's stream gaps that neither the step rule nor the frames after them told apart
        (rig.loadcell.gap_after_verdict): (test s of the frame before the gap, test s the later stamps are in doubt)."""
        return self._on_test_clock(getattr(self.loadcell, "gaps_undecided", []))

    @property
    def stream_gaps_in_doubt(self) -> list[tuple[float, float]]:
        """The load cell's stream gaps taken as lost frames where the force stayed within its noise across
        them (no evidence either way): as :attr:`stream_gaps_undecided`."""
        return self._on_test_clock(getattr(self.loadcell, "gaps_in_doubt", []))

    def _on_test_clock(self, gaps) -> list[tuple[float, float]]:
        to_clock = getattr(self, "_to_clock", None)
        return [(to_clock(t) if to_clock else t, doubt * self.time_scale) for t, doubt in gaps]

    @property
    def late_replies(self) -> dict[str, int]:
        """Replies discarded as stale (they came after their time-out), per device."""
        return {dev.name: dev.transport.late_replies for dev in (self.loadcell, self.encoder, self.furnace) if dev is not None}

    @property
    def retried_exchanges(self) -> dict[str, int]:
        """Exchanges repeated after a silent or garbled reply (the reading was then taken), per device."""
        return {dev.name: dev.transport.retried_exchanges for dev in (self.loadcell, self.encoder, self.furnace) if dev is not None}

    @staticmethod
    def _silence_s(section) -> float:
        return max(SILENCE_MIN_S, SILENCE_TIMEOUTS * section.timeout_s)

    def _read_position(self) -> list[tuple[float, float]]:
        """The crosshead position stamped at the middle of its exchange: the request and the
        reply bracket the moment the counter was read (after a retry, the attempt that was answered:
        ``transport.last_request_s``). A reading whose bracket is wider than the
        narrowest one by more than BRACKET_SLACK_S (the host was held up meanwhile: its time is
        doubtful by half of that) is left out while one was kept within BRACKET_KEEP_S — the
        next comes one poll later, and the stream never falls silent. The widest half-width of a
        kept reading (host seconds) is :attr:`position_half_width_s`; :attr:`positions_doubted` counts
        those left out."""
        asked, mm, answered = self._bracketed(self.encoder, self.encoder.position_mm)
        half = 0.5 * (answered - asked)
        self._narrowest_half_s = min(self._narrowest_half_s, half)
        if half > self._narrowest_half_s + BRACKET_SLACK_S and answered - self._position_kept_at < BRACKET_KEEP_S:
            self.positions_doubted += 1
            return []
        self._position_kept_at = answered
        self.position_half_width_s = max(self.position_half_width_s, half)
        return [(self._to_clock(0.5 * (asked + answered)), mm)]

    def _bracketed(self, device, read) -> tuple[float, object, float]:
        """(asked, value, answered) on the timebase: ``read()``'s request and reply bracket the moment
        the device took its reading; after a retry the bracket opens at the attempt that was answered
        (``transport.last_request_s``)."""
        asked = self.timebase.now()
        value = read()
        answered = self.timebase.now()
        transport = device.transport
        if transport.clock is self.timebase and transport.last_request_s is not None:
            asked = max(asked, transport.last_request_s)  # the attempt that got the reply
        return asked, value, answered

    # furnace ---------------------------------------------------------------------------------
    def _read_temperature(self) -> list[tuple[float, float]]:
        """The temperature channel's reading, stamped at the middle of its own exchange as the
        crosshead's is (a retried read within the attempt that was answered), then the checks of
        :meth:`read_temperature_C` (which run after the exchange, outside its bracket)."""
        asked, t, answered = self._bracketed(self.furnace, self.furnace.temperature_C)
        self._check_furnace(t)
        return [(self._to_clock(0.5 * (asked + answered)), t)]

    def read_temperature_C(self) -> float:
        """A reading; the heater relay must follow (a rise with the heater off for long: stuck),
        and every FURNACE_VERIFY_S the module proves its address (``@AADI``: ``>`` data has none)."""
        t = self.furnace.temperature_C()
        self._check_furnace(t)
        return t

    def _check_furnace(self, t: float) -> None:
        """The stuck-relay check on a reading, and the module's address proof every FURNACE_VERIFY_S."""
        if self._stuck is None:
            self._stuck = StuckRelayCheck(self.furnace.name, settle_s=STUCK_SETTLE_S, max_temperature_C=self.max_temperature_C)
        self._stuck.update(t, self._clock(), self.furnace.heater_is_on)
        now = self.timebase.now()
        if now - self._verified_at >= FURNACE_VERIFY_S:
            self.furnace.digital_io()
            self._verified_at = now

    def watch_heater_off(self, seconds: float, settle_s: float = STUCK_SETTLE_S, *, longest_s: float | None = None,
                         on_extend: Callable[[str], None] | None = None) -> float:
        """After a safety stop: read the furnace for ``seconds`` test seconds with the heater
        off; SafetyError if it keeps heating (a stuck relay — the operator must cut the power),
        at once when it crosses the configured maximum.
        ``settle_s``: the stored heat's time (0 after a test that did not heat). A furnace still
        rising (over STILL_RISING_C in the check's last confirm_s) at ``seconds`` is watched on
        until it stops rising, up to ``longest_s`` (``on_extend`` is told why, once); still
        rising then: SafetyError. Returns the test seconds watched."""
        check = StuckRelayCheck(self.furnace.name, settle_s=settle_s, max_temperature_C=self.max_temperature_C)
        start = self._clock()
        end, longest = start + seconds, start + max(seconds, longest_s or seconds)
        told = on_extend is None
        while True:
            now = self._clock()
            if now >= end:  # and from then on at every reading
                rise = check.rising_C()
                if rise <= STILL_RISING_C:
                    return now - start
                if now >= longest:
                    raise SafetyError(self.furnace.name, f"heater does not switch off (relay stuck?): still rising "
                                      f"({rise:+.1f} C in {check.confirm_s:g} s) with the heater off for {now - start:.0f} s, "
                                      f"longer than stored heat lasts — {STUCK_RELAY_ADVICE}")
                if not told:
                    told = True
                    on_extend(f"still rising ({rise:+.1f} C in the last {check.confirm_s:g} s) after {seconds:g} s with the "
                              f"heater off: watching on, up to {longest - start:g} s, to tell a stuck relay from stored heat")
            check.update(self.furnace.temperature_C(), self._clock(), False)
            self.furnace.host_ok()
            self.timebase.sleep(max(FURNACE_MIN_PERIOD_S, min(FURNACE_PERIOD_S, 1.0 / self.time_scale)))

    def hold_temperature(self, setpoint_C: float) -> float:
        """One step of the furnace's TemperatureController on the test clock; the reading."""
        if self._controller is None or self._controller.setpoint_C != setpoint_C:
            self._controller = self.config.furnace.controller(self.furnace, setpoint_C, clock=self._clock)
        return float(self._controller.step()["temperature_C"])

    def set_clock(self, clock: Callable[[], float]) -> None:
        """The test clock (test seconds): the controller's ramp and period run on it."""
        self._clock = clock

    def heater_off(self) -> None:
        """Heater off; DeviceError when the furnace does not acknowledge it."""
        if self.furnace is not None and not self.furnace.heater_off():
            raise DeviceError(self.furnace.name, "heater-off not acknowledged")

    def arm_watchdog(self) -> None:
        """Arm the furnace module's watchdog with the configured timeout."""
        self.furnace.arm_watchdog(self.config.furnace.watchdog_timeout_s)

    def host_ok(self) -> None:
        """Tell the furnace module's watchdog the host is alive."""
        if self.furnace is not None:
            self.furnace.host_ok()

    # motion ----------------------------------------------------------------------------------
    def tare(self) -> None:
        """Load cell to net zero and the crosshead counter to zero."""
        self.loadcell.tare()
        self.encoder.zero()

    def start_crosshead(self, speed_mm_per_s: float, direction: int) -> None:
        """The virtual rig's motor at the test's speed (the direction is the test's: the twin knows it)."""
        self.virtual.start_crosshead(speed_mm_per_s=speed_mm_per_s)

    def stop_crosshead(self) -> None:
        """Stop the virtual rig's crosshead."""
        self.virtual.stop_crosshead()

    def post_test_measurements(self) -> dict[str, float] | None:
        """The virtual rig's post-test measurements (mm), None on a real rig."""
        if self.virtual is None:
            return None
        return {k: float(v) for k, v in self.virtual.post_test_measurements().items()}


@dataclass
class VirtualRun:
    """A test recorded on the virtual rig, with the truth it was generated from."""

    outcome: object  # acquisition.procedure.Outcome
    material: object  # flowcurve.rig.virtual.materials.Material
    strain_rate_per_s: float  # the model's nominal rate (v / Lc, the parallel length, or v / h0)
    temperature_C: float  # furnace temperature while loading
    friction_mu: float
    compression_response: str = "fe"  # the virtual rig's compression response (rig.virtual.responses.COMPRESSION_RESPONSES)
    tension_response: str = "fe"  # the virtual rig's tension neck (rig.virtual.responses.TENSION_RESPONSES)


def run_virtual_test(spec, path, *, material: str, time_scale: float, view=None, interactive: bool = False, stream: bool = True, friction_mu: float = 0.1, rig_setup=None, config_overrides: dict | None = None, initial_temperature_C: float | None = None, clock: Clock = WALL, link: str = "pty", stop_requested=None, compression_response: str = "fe", tension_response: str = "fe", faults: tuple = ()) -> VirtualRun:
    """Run ``spec`` on a virtual rig in this process through the real drivers.

    Parameters
    ----------
    spec : TestSpec
        The test; the virtual specimen takes its geometry.
    path : str or Path
        The record file.
    material, time_scale : str, float
        The virtual material; test seconds per host second.
    view, interactive, stream, stop_requested : optional
        As :class:`Procedure` and :class:`DriverRig` take them.
    friction_mu, initial_temperature_C : float, optional
        Die friction of compression; the furnace's start temperature, °C.
    rig_setup, config_overrides, faults : optional
        ``rig_setup(virtual_rig)`` before the start; keywords of ``rig.config.virtual_config``;
        FaultSpec drills (``--fault``), listed in the header.
    clock, link : Clock, str
        "pty" in real time (default), or "inprocess" with a ModelClock in simulated time.
    compression_response, tension_response : str
        The physics: "fe" (CalculiX runs) or "slab"; "fe" or "bridgman" (the header says which).

    Returns
    -------
    VirtualRun
        The procedure's Outcome with the truth the record was generated from (material, rate,
        temperature, μ, responses).
    """
    from flowcurve.acquisition.procedure import Procedure
    from flowcurve.rig.config import virtual_config
    from flowcurve.rig.virtual.physics import Specimen
    from flowcurve.rig.virtual.rig import VirtualRig

    specimen = Specimen.from_geometry(spec.test, spec.geometry_mm)
    with VirtualRig(material, test=spec.test, specimen=specimen, speed_mm_per_s=spec.speed_mm_per_s, time_scale=time_scale, friction_mu=friction_mu, temperature_C=initial_temperature_C, clock=clock, link=link, compression_response=compression_response, tension_response=tension_response) as vr:
        response = compression_response if spec.test == "compression" else tension_response
        spec.extra_meta.setdefault("rig.virtual", f"{vr.model.material.name}, time scale {time_scale:g}, {spec.test} response {response}")
        spec.extra_meta.setdefault(f"virtual.{spec.test}_response", response)
        spec.extra_meta.setdefault("material.E_MPa", repr(float(vr.model.material.E_MPa)))  # the handbook values an operator would enter
        spec.extra_meta.setdefault("material.nu", repr(float(vr.model.material.nu)))
        if spec.test == "tension":  # the rig's own bar: its parallel length is known (l0 unless given), so the record states it
            spec.extra_meta.setdefault("specimen.parallel_length_mm", repr(float(specimen.parallel_mm)))
        if faults:
            spec.extra_meta.setdefault("virtual.faults", " ".join(f.describe() for f in faults))
        for fault in faults:
            vr.schedule(fault)
        if rig_setup is not None:
            rig_setup(vr)
        config = virtual_config(**{**vr.config_kwargs(), **(config_overrides or {})})
        with DriverRig(config, time_scale=time_scale, virtual=vr, stream=stream) as rig:
            outcome = Procedure(rig, spec, path, view=view, interactive=interactive, stop_requested=stop_requested).run()
        model = vr.model
        return VirtualRun(outcome, model.material, model.nominal_strain_rate_per_s, model.loading_temperature_C, friction_mu,
                          compression_response, tension_response)

"""The virtual rig: the physical model and the three device twins on pseudo-terminals.

::

    with VirtualRig("12Kh18N10T", test="tension", speed_mm_per_s=0.01, time_scale=200) as rig:
        config = rig.config()          # a RigConfig pointing at rig.ports
        ...                            # drivers talk to rig.ports["loadcell"] etc.
        rig.start_crosshead()          # the operator starts the machine
        rig.inject("furnace", "silence")

**One model clock.** Model time = host time since the rig started × ``time_scale``.
Every read by a device first advances the model to that time, so the load cell, the
encoder and the furnace always see one consistent state. ``time_scale=100`` runs a
10 µm/s test a hundred times faster: a 30-minute tension test in 18 s, a furnace heat-up
of 10 minutes in 6 s; the devices' own timing (output rate ``ICR``, DCON host watchdog)
stays in host time, as the host sees it.

**Host time** is ``clock`` (:mod:`flowcurve.clock`): the wall clock by default, with the
devices on pseudo-terminals (``link="pty"``, :attr:`ports` are ``/dev/pts/N``) for drivers
in this or another process; or, with ``link="inprocess"``, ``virtual://`` ports that only
this process opens (:mod:`flowcurve.rig.virtual.protocol_virtual`) — on a
:class:`flowcurve.clock.ModelClock` the whole rig then runs in simulated time::

    clock = ModelClock()
    with VirtualRig("steel45", clock=clock, link="inprocess") as rig:
        ...                            # drivers on rig.ports; clock.advance(0.3) or clock.sleep(0.3)
"""

from __future__ import annotations

import bisect
import threading
from collections import deque

from flowcurve.clock import WALL, Clock
from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.physics import FurnaceParams, RigModel, Specimen
from flowcurve.rig.virtual.aed import AEDAmplifier
from flowcurve.rig.virtual.dcon import I7011
from flowcurve.rig.virtual.encoder_box import EncoderBox
from flowcurve.rig.virtual.faults import MODEL_FAULTS, WIRE_FAULTS
from flowcurve.rig.virtual.fault_spec import FaultSpec

DEVICES = ("loadcell", "encoder", "furnace")
HISTORY_STATES = 1024  # model states remembered for the load cell's late frames (some seconds of host time)


class VirtualRig:
    """Context manager running the model and the three devices (see the module docstring)."""

    def __init__(self, material="12Kh18N12M3TL", test: str = "tension", specimen: Specimen | None = None, *,
                 temperature_C: float | None = None, speed_mm_per_s: float = 0.01,
                 time_scale: float = 1.0, seed: int = 0, frame_stiffness_N_per_um: float = 136.0,
                 friction_mu: float = 0.1, force_noise_N: float = 3.0, nominal_load_N: float = 100e3,
                 furnace: FurnaceParams = FurnaceParams(), stroke_limit_mm: float | None = None,
                 loadcell_address: int = 31, furnace_address: int = 0x01, encoder_address: int = 0x02,
                 checksum: bool = False, encoder_initial_count: int = 0, aed_settings: dict | None = None,
                 clock: Clock = WALL, link: str = "pty", compression_response: str = "fe", tension_response: str = "fe"):
        if not time_scale > 0:
            raise ConfigError(f"time_scale: must be positive, got {time_scale}")
        self.time_scale = float(time_scale)
        self.model = RigModel(material, test, specimen, speed_mm_per_s=speed_mm_per_s,
                              frame_stiffness_N_per_um=frame_stiffness_N_per_um, friction_mu=friction_mu,
                              furnace=furnace, initial_temperature_C=temperature_C,
                              force_noise_N=force_noise_N, stroke_limit_mm=stroke_limit_mm, seed=seed,
                              compression_response=compression_response, tension_response=tension_response)
        self.nominal_load_N = float(nominal_load_N)
        self.checksum = checksum
        self._lock = threading.RLock()
        self.clock = clock
        self.link = link
        self._t0 = clock.now()
        self._running = False
        self._motion_start_s: float | None = None  # model time the crosshead first moved
        self._scheduled: list[FaultSpec] = []  # --fault ...@SECONDS not yet due
        self.faults_applied: list[tuple[float, FaultSpec]] = []  # (model time, spec), in order
        self._history: deque[tuple[float, float, bool]] = deque(maxlen=HISTORY_STATES)  # (model s, true force N, moving)
        self.devices: dict = {}
        try:
            self.devices["loadcell"] = AEDAmplifier(self._loadcell_sample, source_at=self._loadcell_sample_at,
                                                    nominal_load_N=nominal_load_N,
                                                    address=loadcell_address, settings=aed_settings, seed=seed + 1,
                                                    clock=clock, link=link)
            self.devices["encoder"] = EncoderBox(self._encoder_counts, address=encoder_address,
                                                 checksum_on=checksum, initial_count=encoder_initial_count,
                                                 seed=seed + 2, clock=clock, link=link)
            self.devices["furnace"] = I7011(self._thermocouple, self._set_heater, address=furnace_address,
                                            checksum_on=checksum, seed=seed + 3, clock=clock, link=link)
        except BaseException:
            self.close()
            raise
        self.devices["encoder"].counts_per_mm = self.model.counts_per_mm
        for name in ("encoder", "furnace"):
            self.devices[name].time_scale = self.time_scale  # the watchdogs count model time

    # -- clock and model access (called from the device threads) --------------------------
    def now(self) -> float:
        """Model time in seconds."""
        return (self.clock.now() - self._t0) * self.time_scale

    def sync(self, t: float | None = None) -> RigModel:
        """Advance the model to the present model time (or to model time ``t``, if later than
        the model's) and return it (hold :attr:`lock`); scheduled faults that are due switch on;
        the state is remembered for :meth:`_loadcell_sample_at`."""
        with self._lock:
            m = self.model
            m.advance_to(self.now() if t is None else t)
            if self._scheduled:
                self._apply_due()
            if not self._history or m.time_s > self._history[-1][0]:
                self._history.append((m.time_s, m.force_N, m.moving))
            return m

    def since_motion_s(self) -> float | None:
        """Model seconds since the crosshead first started (None: not yet)."""
        return None if self._motion_start_s is None else self.model.time_s - self._motion_start_s

    @property
    def lock(self) -> threading.RLock:
        """The lock over the rig's model and devices."""
        return self._lock

    def _loadcell_sample(self):
        with self._lock:
            m = self.sync()
            return m.time_s, m.measured_force_N(), not m.moving

    def _loadcell_sample_at(self, host_t: float):
        """The load cell's input at clock time ``host_t`` (a stream frame's due time): the model
        advanced to it, or, when the model has already run past it, its true force interpolated
        linearly between the remembered states around it, plus the sensor noise. None: further
        back than the model remembers."""
        t = (host_t - self._t0) * self.time_scale
        with self._lock:
            m = self.model
            if t >= m.time_s:
                self.sync(t)
                return m.time_s, m.measured_force_N(), not m.moving
            times = [h[0] for h in self._history]
            i = bisect.bisect_right(times, t)
            if i == 0:
                return None
            (t0, f0, moving), (t1, f1, _) = self._history[i - 1], self._history[min(i, len(times) - 1)]
            force = f0 if t1 <= t0 else f0 + (f1 - f0) * (t - t0) / (t1 - t0)  # linear between the states
            noise = m.rng.normal(0.0, m.force_noise_N) if m.force_noise_N > 0 else 0.0
            return t, force + noise, not moving

    def _encoder_counts(self) -> int:
        with self._lock:
            return self.sync().encoder_counts()

    def _thermocouple(self) -> float:
        with self._lock:
            return self.sync().thermocouple_C()

    def _set_heater(self, on: bool) -> None:
        with self._lock:
            self.sync().set_heater(on)

    # -- life cycle ---------------------------------------------------------------------
    def start(self) -> "VirtualRig":
        """Start the devices and the model's time; the rig."""
        with self._lock:
            self._t0 = self.clock.now() - self.model.time_s / self.time_scale
        for dev in self.devices.values():
            dev.start()
        self._running = True
        return self

    def close(self) -> None:
        """Stop every device thread and close every pty (idempotent)."""
        for dev in self.devices.values():
            dev.close()
        self._running = False

    def __enter__(self) -> "VirtualRig":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # -- what the tests and the operator do ----------------------------------------------
    @property
    def ports(self) -> dict[str, str]:
        """Serial ports: ``{"loadcell": "/dev/pts/N", ...}`` (or ``virtual://loadcell-N`` in-process)."""
        return {name: dev.port for name, dev in self.devices.items()}

    def start_crosshead(self, speed_mm_per_s: float | None = None) -> None:
        """The motor on, at ``speed_mm_per_s`` when given (else at the speed it was set to)."""
        with self._lock:
            m = self.sync()
            if speed_mm_per_s is not None:
                m.set_speed(speed_mm_per_s)
            m.start_crosshead()
            if m.moving and self._motion_start_s is None:
                self._motion_start_s = m.time_s
                self._apply_due()

    def stop_crosshead(self) -> None:
        """Stop the crosshead."""
        with self._lock:
            m = self.sync()
            m.stop_crosshead()

    def set_speed(self, speed_mm_per_s: float) -> None:
        """The motor's speed dial, mm/s (takes effect at once, running or not)."""
        with self._lock:
            self.sync().set_speed(speed_mm_per_s)

    def schedule(self, spec: FaultSpec) -> None:
        """A fault of ``--fault`` (:mod:`rig.virtual.fault_spec`): on now, or ``spec.at_s``
        model seconds after the crosshead starts moving."""
        self._device(spec.device)
        with self._lock:
            self._scheduled.append(spec)
            if spec.at_s is None:
                self._apply_due()

    def _apply_due(self) -> None:
        since = self.since_motion_s()
        due = [f for f in self._scheduled if f.at_s is None or (since is not None and since >= f.at_s)]
        self._scheduled = [f for f in self._scheduled if f not in due]
        for spec in due:
            self.faults_applied.append((self.model.time_s, spec))
            self._switch_on(spec)

    def _switch_on(self, spec: FaultSpec) -> None:
        """Apply one due fault without waiting on any device thread (called under the rig lock)."""
        dev, kind, value = self.devices[spec.device], spec.kind, spec.value
        if kind in ("corrupt", "spike"):  # a spike: one load-cell frame, smaller than what the rate rules see
            dev.corrupt_next(value)
        elif kind == "jump":
            dev.jump(value)
        elif kind == "wrong_address":
            dev.reply_address = int(value)
        elif kind == "open_thermocouple":
            self.model.thermocouple_open = True
        elif kind == "relay_stuck":
            self.model.furnace.set_relay_stuck(True)
        else:  # wire faults: the device's thread (or its next exchange) sees them
            kw = {"fraction": value} if kind in ("drop", "garble") else {"seconds": value} if kind == "delay" else {}
            dev.faults.inject(kind, **kw)
            if dev.link == "pty":
                dev.wake()  # (in-process the next exchange or timer looks at the faults)

    def inject(self, device: str, fault: str, **kw) -> None:
        """Switch a fault on: wire faults (``silence``, ``drop``, ``garble``, ``delay``,
        ``unplug``) on any device; ``open_thermocouple`` and ``relay_stuck`` on the furnace."""
        dev = self._device(device)
        if fault in MODEL_FAULTS.get(device, ()):
            with self._lock:
                m = self.sync()
                if fault == "open_thermocouple":
                    m.thermocouple_open = True
                else:
                    m.furnace.set_relay_stuck(True)
            return
        if fault not in WIRE_FAULTS:
            known = WIRE_FAULTS + MODEL_FAULTS.get(device, ())
            raise ConfigError(f"{device}: unknown fault '{fault}' (known: {', '.join(known)})")
        if fault == "unplug":
            dev.unplug()
        else:
            dev.faults.inject(fault, **kw)
            dev.wake()

    def clear(self, device: str) -> None:
        """All faults of a device off (an unplugged device stays unplugged)."""
        dev = self._device(device)
        dev.faults.clear()
        if device == "furnace":
            with self._lock:
                m = self.sync()
                m.thermocouple_open = False
                m.furnace.set_relay_stuck(False)
        dev.wake()

    def _device(self, device: str):
        if device not in self.devices:
            raise ConfigError(f"device: unknown virtual device '{device}' (known: {', '.join(DEVICES)})")
        return self.devices[device]

    def post_test_measurements(self) -> dict[str, str]:
        """``post.*`` record keys the operator would measure on the specimen now."""
        with self._lock:
            return self.sync().post_test_measurements()

    def metadata(self) -> dict[str, str]:
        """Record metadata describing the virtual test (material, specimen, speed, frame)."""
        m = self.model
        s = m.specimen
        meta = {
            "test": m.test,
            "material": m.material.name,
            "nominal_temperature_C": f"{m.furnace.temperature_C:.1f}",
            "crosshead_speed_mm_per_s": f"{m.speed_mm_per_s:g}",
            "rig.frame_stiffness_N_per_um": f"{m.frame_stiffness_N_per_um:g}",
            "specimen.d0_mm": f"{s.d0_mm:g}",
        }
        meta["specimen.l0_mm" if m.test == "tension" else "specimen.h0_mm"] = f"{s.length0_mm:g}"
        if m.test == "tension":  # its own bar: the parallel length is known (l0 unless given), so it is stated
            meta["specimen.parallel_length_mm"] = f"{s.parallel_mm:g}"
        return meta

    def config(self):
        """A RigConfig for the drivers pointing at this rig's ports (``rig.config.virtual_config``)."""
        from flowcurve.rig.config import virtual_config  # the drivers' module; imported late on purpose

        return virtual_config(**self.config_kwargs())

    def config_kwargs(self) -> dict:
        """What :meth:`config` passes to ``virtual_config``."""
        return {
            "ports": self.ports,
            "frame_stiffness_N_per_um": self.model.frame_stiffness_N_per_um,
            "nominal_load_N": self.nominal_load_N,
            "loadcell_address": self.devices["loadcell"].address,
            "furnace_address": self.devices["furnace"].address,
            "encoder_address": self.devices["encoder"].address,
            "checksum": self.checksum,
            "virtual_test": self.model.test,  # [virtual]: the bar simulated, for a host to compare its test's with
            **{f"virtual_{key}": value for key, value in self.model.specimen.geometry_mm.items()},
        }

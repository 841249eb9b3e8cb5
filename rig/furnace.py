"""The furnace: I-7011-class DCON module (type-K thermocouple in, heater on a digital output)
and the temperature controller that holds a set-point with it.

Safety rules kept here: the heater is never switched on at or above the maximum temperature;
an open thermocouple (over-range reading confirmed by ``$AAB``) or an over-temperature
switches the heater off and raises :class:`~flowcurve.errors.SafetyError`; ``heater_off``
retries and raises no device error (each failed attempt is logged); :meth:`Furnace.arm_watchdog` makes the module switch the heater
off by itself when the PC stops talking; closing the furnace switches the heater off.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from itertools import takewhile
from typing import Iterator

from flowcurve.errors import DeviceError, FlowcurveError, SafetyError
from flowcurve.rig.codecs import dcon
from flowcurve.rig.roles import TemperatureDevice
from flowcurve.rig.transport import DconDevice, WrongAddressError

logger = logging.getLogger(__name__)

HEATER_OFF_ATTEMPTS = 3


class OutputsRefused(DeviceError):
    """The module answered ``?`` to ``@AADO`` (watchdog trip or alarm owns the outputs)."""
APPROACH_DONE_C = 0.05  # the eased set-point counts as reached this close


class Furnace(DconDevice):
    """The furnace module: ``temperature_C()``, ``heater(on)``, ``heater_off()``, watchdog.

    ``data_format`` (engineering units, % of range or hex) is read from the module (``$AA2``)
    before the first reading unless given.

    Every ``!AA``/``?AA`` reply must carry the module's address (:meth:`DconDevice.query`): a
    reading answered by another address is asked again; a heater command (``@AADO``) answered
    so raises :class:`~rig.transport.WrongAddressError` at once (the test stops), and from then
    on no acknowledgement of this module is believed (:attr:`acks_trusted`): the heater is not
    switched on again, :meth:`heater_off` still sends the command but reports it unconfirmed, so
    the host watchdog stays armed and switches the heater off by itself.
    """

    config_section = "furnace"

    def __init__(self, port_url, *, name: str = "furnace", address: int = 1, heater_do_bit: int = 0,
                 max_temperature_C: float = 900.0, baudrate: int = 9600, parity: str = "N",
                 timeout_s: float = 0.3, checksum: bool = False,
                 data_format: int | None = None, type_code: int = 0x0F, opener=None):
        super().__init__(port_url, name=name, address=address, baudrate=baudrate, parity=parity,
                         timeout_s=timeout_s, checksum=checksum, opener=opener)
        if heater_do_bit not in (0, 1):
            raise ValueError(f"the I-7011 has digital outputs 0 and 1, not {heater_do_bit}")
        if not max_temperature_C > 0:
            raise ValueError(f"maximum temperature must be positive, got {max_temperature_C}")
        self.heater_mask = 1 << heater_do_bit
        self.max_temperature_C = float(max_temperature_C)
        self.data_format = data_format  # None: learnt from $AA2 before the first reading
        self.full_scale_C = dcon.FULL_SCALE_C.get(type_code, dcon.FULL_SCALE_C[0x0F])
        self.heater_is_on = False
        self.watchdog_armed = False
        self.acks_trusted = True  # False once a heater command was answered from another address

    @classmethod
    def from_config(cls, section, **kw) -> "Furnace":
        """The furnace module of a rig file's ``[furnace]`` section (:class:`rig.config.FurnaceConfig`)."""
        return cls(section.port, address=section.address, checksum=section.checksum,
                   heater_do_bit=section.heater_do_bit, max_temperature_C=section.max_temperature_C,
                   **section.transport_kwargs("furnace"), **kw)

    def check_lines(self, section) -> Iterator[str]:
        """What ``flowcurve rig check`` prints of the open module: identity, settings (a note when it
        is not set for a type-K thermocouple), the reading, the heater and the host watchdog's status."""
        cfg = self.configuration()
        yield f"  identity: module {self.module_name()}, firmware {self.firmware()}"
        yield (f"  settings: address {cfg.address:02X}, input type {cfg.thermocouple or f'{cfg.type_code:02X}'}, "
               f"{cfg.baud} baud, checksum {'on' if cfg.checksum else 'off'}; max {section.max_temperature_C:g} C")
        if cfg.thermocouple != "K":
            yield "  note: the module is not set for a type-K thermocouple"
        status = self.watchdog_status()
        yield (f"  reading: {self.temperature_C():.1f} C (cold junction {self.cold_junction_C():.1f} C); "
               f"heater off; host watchdog status {status:02X}{' (timed out earlier)' if status & 0x04 else ''}")

    def close(self) -> None:
        """Heater off (best effort), then release the port."""
        if self.transport.is_open:
            self.heater_off()
        super().close()

    # -- temperature ------------------------------------------------------------------
    def temperature_C(self) -> float:
        """``#AA`` → thermocouple temperature in °C.

        An over- or under-range reading is checked with ``$AAB``: an open thermocouple, or a
        reading out of range, switches the heater off and raises :class:`SafetyError`. Above
        ``max_temperature_C`` the heater is switched off; if it was on, SafetyError too (if it
        was off and the furnace crossed the maximum so: :class:`StuckRelayCheck`, which every
        heater-off reader runs).
        """
        if self.data_format is None:
            self.configuration()
        value, text = self.query("#", "", self._reading)
        if math.isfinite(value):
            if value > self.max_temperature_C:
                # above the limit the heater goes off whoever reads; if it was on, stop too
                was_on = self.heater_is_on
                self.heater_off()
                if was_on:
                    raise SafetyError(self.name, f"over-temperature: {value:.1f} C above the maximum "
                                                 f"{self.max_temperature_C:g} C; heater off")
            return value
        try:
            is_open = self.open_thermocouple()
        except FlowcurveError:
            is_open = None
        self.heater_off()
        if is_open:
            raise SafetyError(self.name, "thermocouple open (over-range reading confirmed by $AAB); heater off")
        side = "over" if value > 0 else "under"
        raise SafetyError(self.name, f"temperature reading {side} range ('>{text}'); heater off")

    def configuration(self) -> dcon.Configuration:
        """``$AA2``, and take the module's data format and input range for its readings."""
        cfg = super().configuration()
        self.data_format = cfg.data_format
        self.full_scale_C = dcon.FULL_SCALE_C.get(cfg.type_code, self.full_scale_C)
        return cfg

    def _reading(self, reply: dcon.Reply) -> tuple[float, str]:
        value = dcon.parse_analog(reply, data_format=self.data_format, full_scale=self.full_scale_C)
        return value, reply.body

    def open_thermocouple(self) -> bool:
        """``$AAB`` → True when the module detects an open thermocouple."""
        return self.query("$", "B", dcon.parse_open_thermocouple, self.address)

    # -- heater -----------------------------------------------------------------------
    def _write_outputs(self, outputs: int) -> None:
        # @AADOdd is idempotent: safe to repeat after a lost reply — not after another module's
        # acknowledgement (which module switched what is then unknown)
        try:
            reply = self.query("@", dcon.digital_output_body(outputs), addressed=True, commanded=True)
        except WrongAddressError:
            self.acks_trusted = False
            raise
        if reply.refused:
            if self._watchdog_tripped():
                raise OutputsRefused(self.name, "outputs locked: the host watchdog timed out "
                                                "(heater at its safe value); clear it with ~AA1")
            raise OutputsRefused(self.name, "refused '@AADO' (the alarm owns the digital outputs?)")
        if reply.lead != "!":
            raise DeviceError(self.name, f"garbled reply to '@AADO': '{reply.lead}{reply.body}'")

    def _watchdog_tripped(self) -> bool:
        try:
            return bool(self.watchdog_status() & dcon.WATCHDOG_TIMED_OUT)
        except DeviceError:
            return False

    def heater(self, on: bool, reading_C: float | None = None) -> None:
        """Switch the heater; refuses to switch it on at or above the maximum temperature.
        ``reading_C``: a reading the caller took in the same step (the controller's), checked
        instead of reading again — a reading of its own would reach no one else (a corrupt one
        would go unnamed)."""
        if not on:
            self._write_outputs(0)
            self.heater_is_on = False
            return
        if not self.acks_trusted:
            raise DeviceError(self.name, "heater not switched on: a heater command was answered from another "
                                         "module's address in this session (its acknowledgements are not believed)")
        t = self.temperature_C() if reading_C is None else reading_C
        if t >= self.max_temperature_C:
            self.heater_off()
            raise SafetyError(self.name, f"heater not switched on: {t:.1f} C is at or above the "
                                         f"maximum {self.max_temperature_C:g} C")
        self._write_outputs(self.heater_mask)
        self.heater_is_on = True

    def heater_off(self) -> bool:
        """Heater off, best effort: retries; a device or port failure is logged, not raised.
        True if the module acknowledged, or refused but reports the heater output off (after
        a watchdog trip); False too after a heater command was answered from another address
        (the command is sent, its acknowledgement not believed: the host watchdog stays armed)."""
        for attempt in range(1, HEATER_OFF_ATTEMPTS + 1):
            try:
                self._write_outputs(0)
                self.heater_is_on = False
                if not self.acks_trusted:
                    logger.warning("%s: heater off sent and acknowledged, but not believed: a heater command was answered "
                                   "from another address; the module's host watchdog switches the heater off", self.name)
                    return False
                return True
            except OutputsRefused as refused:
                try:  # the module talks but will not switch: is the output off already?
                    if not self.digital_io()["outputs"] & self.heater_mask:
                        self.heater_is_on = False
                        return True
                    logger.warning("heater off, attempt %d of %d: %s; the heater output is still on",
                                   attempt, HEATER_OFF_ATTEMPTS, refused)
                except (DeviceError, OSError) as exc:
                    logger.warning("heater off, attempt %d of %d: %s; reading the outputs back failed: %s",
                                   attempt, HEATER_OFF_ATTEMPTS, refused, exc)
            except (DeviceError, OSError) as exc:
                logger.warning("heater off, attempt %d of %d failed: %s", attempt, HEATER_OFF_ATTEMPTS, exc)
        logger.error("%s: heater off not confirmed after %d attempts", self.name, HEATER_OFF_ATTEMPTS)
        return False

    def cold_junction_C(self) -> float:
        """``$AA3``: the module's cold-junction (terminal) temperature."""
        return self.query("$", "3", dcon.parse_analog)

    def digital_io(self) -> dict[str, int]:
        """``@AADI`` → alarm state, digital outputs, digital inputs (the reply's address checked)."""
        reply = self.query("@", "DI", addressed=lambda r: r.refused or len(r.body) == 7)  # (!SOOII carries none)
        try:
            return dcon.parse_digital_io(reply, self.address)
        except ValueError as exc:
            raise DeviceError(self.name, f"garbled answer to '@AADI': {exc}") from None

    # -- host watchdog ----------------------------------------------------------------
    def arm_watchdog(self, timeout_s: float) -> None:
        """Heater-off as the DO power-on and safe value (``~AA5PPSS``), then enable the host
        watchdog (``~AA3EVV``): the heater goes off by itself if ``~**`` stops for ``timeout_s``."""
        self.query("~", dcon.safe_value_body(0, 0), dcon.expect_ack, self.address, "~AA5PPSS")
        self.set_watchdog(True, timeout_s)
        self.host_ok()
        self.watchdog_armed = True

    def disarm_watchdog(self) -> None:
        """Disable the host watchdog (after the heater is off)."""
        self.set_watchdog(False, 0.1)
        self.watchdog_armed = False


STUCK_RELAY_ADVICE = "switch off the furnace's mains power now: software cannot switch this heater off"


class StuckRelayCheck:
    """A heater relay that does not switch off: with the heater off for longer than
    ``settle_s`` (dead time and stored heat) the furnace can only cool, so a rise of more than
    ``rise_C`` above the lowest reading since then means the heater still heats — when the
    rise goes on: ``confirm_s`` after it passed ``rise_C`` the furnace is ``confirm_rise_C``
    hotter still. A thermal lag (the elements' stored heat reaching the thermocouple late)
    rises ever slower to its peak; a stuck relay keeps heating (0.8 K/s at 850 C on the rig's
    6 kW). A lag still rising faster than ``confirm_rise_C / confirm_s`` after ``settle_s``
    cannot be told from a stuck relay this way (the README's fault table).

    With ``max_temperature_C`` given, a reading above it is named at once when the furnace
    crossed it with the heater commanded off (a heater-off reading at or below it came first; a
    reading more than ``rise_C`` above the one before is no heating — a corrupt reading, left to
    the over-temperature rule — so a furnace really that hot is named at the next reading):
    stored heat alone carries a furnace over its maximum only when the heater went off within
    that heat's rise of it (the virtual furnace: 5 s dead time x 0.85 K/s at 850 C, about 4 C),
    so a set-point must leave ``rig.config.SETPOINT_MARGIN_C`` below the maximum (the test is refused).
    A furnace already above it when the heater went off (an over-temperature stop) is left to
    the rise check until it falls back below.

    :meth:`update` (reading °C, time s, heater commanded on) raises :class:`SafetyError`;
    :meth:`rising_C` is the rise over the last ``confirm_s`` with the heater off (a watch that
    ends while the furnace still rises goes on: :meth:`DriverRig.watch_heater_off`).
    """

    def __init__(self, device: str = "furnace", *, settle_s: float = 30.0, rise_C: float = 5.0,
                 confirm_s: float = 5.0, confirm_rise_C: float = 1.5, max_temperature_C: float = math.inf):
        self.device = device
        self.max_temperature_C = float(max_temperature_C)
        self._off_below_max = False  # a heater-off reading at or below the maximum since the heater went off
        self.settle_s = float(settle_s)
        self.rise_C = float(rise_C)
        self.confirm_s = float(confirm_s)
        self.confirm_rise_C = float(confirm_rise_C)
        self._off_since: float | None = None
        self._off_min_C = math.inf
        self._risen: tuple[float, float] | None = None  # (time, reading) when the rise passed rise_C
        self._recent: deque[tuple[float, float]] = deque()  # (time, reading) with the heater off, the last confirm_s and one before

    def update(self, temperature_C: float, now: float, heater_on: bool) -> None:
        """Take one reading (``temperature_C`` at ``now`` s, heater state)."""
        if heater_on:
            self._off_since = None
            self._recent.clear()
            return
        if self._off_since is None:
            self._off_since, self._off_min_C, self._risen, self._off_below_max = now, math.inf, None, False
        last_C = self._recent[-1][1] if self._recent else temperature_C
        if temperature_C <= self.max_temperature_C:
            self._off_below_max = True
        elif self._off_below_max and temperature_C - last_C <= self.rise_C:  # crossed heating, not one jumping reading
            raise SafetyError(self.device, f"heater does not switch off (relay stuck?): {temperature_C:.1f} C, above the "
                                           f"maximum {self.max_temperature_C:g} C, {now - self._off_since:.0f} s after the "
                                           f"heater was commanded off — the heater is commanded off and the furnace still "
                                           f"heats: {STUCK_RELAY_ADVICE}")
        self._recent.append((now, temperature_C))
        while len(self._recent) > 2 and now - self._recent[1][0] >= self.confirm_s:
            self._recent.popleft()
        if now - self._off_since < self.settle_s:
            return
        self._off_min_C = min(self._off_min_C, temperature_C)
        rise = temperature_C - self._off_min_C
        if rise <= self.rise_C:
            self._risen = None
            return
        if self._risen is None:
            self._risen = (now, temperature_C)
        since, then_C = self._risen
        if now - since >= self.confirm_s and temperature_C - then_C >= self.confirm_rise_C:
            raise SafetyError(self.device, f"heater does not switch off (relay stuck?): {rise:.1f} C rise with the heater "
                                           f"off for {now - self._off_since:.0f} s, still rising — {STUCK_RELAY_ADVICE}")

    def rising_C(self) -> float:
        """The reading's rise over the last ``confirm_s`` with the heater off (0 before that long)."""
        if len(self._recent) < 2 or self._recent[-1][0] - self._recent[0][0] < self.confirm_s:
            return 0.0
        return self._recent[-1][1] - self._recent[0][1]


class TemperatureController:
    """Holds a furnace at ``setpoint_C`` with a time-proportioned heater output.

    Each ``period_s`` a PI law on the error to a ramped set-point (rising at most
    ``max_rate_C_per_min``, easing in over ``approach_s``) gives the duty cycle; within the period the heater is on for
    ``duty × period_s``. Above ``max_temperature_C`` the heater is switched off and
    :class:`SafetyError` raised; so it is when the furnace keeps heating more than
    ``stuck_rise_C`` with the heater off for over ``stuck_settle_s``, or crosses the maximum
    with the heater off (a stuck relay: :class:`StuckRelayCheck`).
    Call :meth:`step` from a loop (``now`` in monotonic s, or the ``clock`` given).
    """

    def __init__(self, furnace: TemperatureDevice, setpoint_C: float, *, max_temperature_C: float,
                 max_rate_C_per_min: float, period_s: float = 2.0, kp_per_C: float = 0.05,
                 ki_per_C_s: float = 0.0005, approach_s: float = 30.0, stuck_settle_s: float = 30.0, stuck_rise_C: float = 5.0,
                 clock=time.monotonic):
        self.max_temperature_C = min(float(max_temperature_C), furnace.max_temperature_C)
        if not setpoint_C < self.max_temperature_C:
            raise ValueError(f"set-point {setpoint_C:g} C is not below the maximum "
                             f"{self.max_temperature_C:g} C")
        if not (max_rate_C_per_min > 0 and period_s > 0):
            raise ValueError("heating rate and period must be positive")
        self.furnace = furnace
        self.setpoint_C = float(setpoint_C)
        self.max_rate_C_per_s = max_rate_C_per_min / 60.0
        self.period_s = float(period_s)
        self.kp = kp_per_C
        self.ki = ki_per_C_s
        self.clock = clock
        self.approach_s = float(approach_s)
        self.ramp_C: float | None = None
        self.integral = 0.0
        self.duty = 0.0
        self.temperature_C: float | None = None
        self._last_t: float | None = None
        self._period_start: float | None = None
        self._target_on_s = 0.0
        self._on_s = 0.0
        self._history: deque[tuple[float, float]] = deque(maxlen=200_000)
        self.stuck_settle_s = stuck_settle_s
        self.stuck_rise_C = stuck_rise_C
        self._stuck = StuckRelayCheck(furnace.name, settle_s=stuck_settle_s, rise_C=stuck_rise_C,
                                      max_temperature_C=self.max_temperature_C)

    def step(self, now: float | None = None) -> dict[str, float | bool]:
        """Read the temperature, update ramp and duty, switch the heater; returns the state.

        Any failure on the way (reading, switching, a safety limit) switches the heater off
        before the error propagates.
        """
        now = self.clock() if now is None else now
        try:
            return self._step(now)
        except BaseException:
            self.furnace.heater_off()
            raise

    def _step(self, now: float) -> dict[str, float | bool]:
        t = self.furnace.temperature_C()  # SafetyError on an open thermocouple
        self.temperature_C = t
        self._check_heater_follows(t, now)  # first: over the maximum with the heater off is a stuck relay
        if t > self.max_temperature_C:
            raise SafetyError(self.furnace.name, f"over-temperature: {t:.1f} C above the maximum "
                                                 f"{self.max_temperature_C:g} C; heater off")
        dt = 0.0 if self._last_t is None else max(0.0, now - self._last_t)
        self._last_t = now
        if self.furnace.heater_is_on:
            self._on_s += dt  # heater-on time delivered since the last step
        self._update_ramp(t, dt)
        if self._period_start is None or now - self._period_start >= self.period_s:
            self._period_start = now
            self._update_duty(t)
            # time-proportioning: on for duty x period, plus what the last period owed
            # (the loop's step size quantizes on-times; carrying the rest keeps the mean exact).
            # A loop stepping slower than the period (a fast time-scaled rig) makes each step a
            # period of its own: on for the whole step when the duty owed asks for over half
            period = max(self.period_s, dt)
            carry = min(period, max(-period, self._target_on_s - self._on_s))
            self._target_on_s = max(0.0, self.duty * period + carry)
            self._on_s = 0.0
        want_on = self._target_on_s - self._on_s > 0.5 * dt
        if want_on != self.furnace.heater_is_on:
            self.furnace.heater(want_on, reading_C=t)
        if self.furnace.watchdog_armed:
            self.furnace.host_ok()
        self._update_soak(t, now)
        return {"temperature_C": t, "ramp_setpoint_C": self.ramp_C, "duty": self.duty,
                "heater_on": self.furnace.heater_is_on}

    def _check_heater_follows(self, t: float, now: float) -> None:
        self._stuck.update(t, now, self.furnace.heater_is_on)

    def _update_ramp(self, t: float, dt: float) -> None:
        # rate limit: the working set-point rises at most max_rate x dt from the start
        # temperature, and eases into the set-point with time constant approach_s (without
        # the easing, the integral built up while ramping overshoots by ~5 C at 30 C/min)
        if self.ramp_C is None:
            self.ramp_C = min(t, self.setpoint_C)
        gap = self.setpoint_C - self.ramp_C
        rise = self.max_rate_C_per_s * dt
        if self.approach_s > 0:
            rise = min(rise, gap * min(1.0, dt / self.approach_s))
        self.ramp_C = min(self.setpoint_C, self.ramp_C + rise)
        if self.setpoint_C - self.ramp_C < APPROACH_DONE_C:
            self.ramp_C = self.setpoint_C

    def _update_duty(self, t: float) -> None:
        # PI on the duty cycle, integrating only while the output is not saturated (anti-windup)
        error = self.ramp_C - t
        candidate = self.integral + error * self.period_s
        duty = self.kp * error + self.ki * candidate
        if 0.0 <= duty <= 1.0 or (duty > 1.0 and error < 0) or (duty < 0.0 and error > 0):
            self.integral = candidate
        self.duty = min(1.0, max(0.0, self.kp * error + self.ki * self.integral))

    def _update_soak(self, t: float, now: float) -> None:
        # history since the ramp reached the set-point, for soaked(); a ramp restart clears it
        if self.ramp_C < self.setpoint_C:
            self._history.clear()
        else:
            self._history.append((now, t))

    def soaked(self, tolerance: float = 2.0, hold_s: float = 60.0) -> bool:
        """True once the temperature has stayed within ±``tolerance`` °C of the set-point for
        the last ``hold_s`` seconds, counted from when the ramp reached the set-point."""
        if not self._history or self._history[-1][0] - self._history[0][0] < hold_s:
            return False
        end = self._history[-1][0]
        window = takewhile(lambda sample: end - sample[0] <= hold_s, reversed(self._history))
        return all(abs(t - self.setpoint_C) <= tolerance for _, t in window)

    def stop(self) -> None:
        """Heater off (best effort)."""
        self.furnace.heater_off()

"""Heater safety: the heater switches off on every exit path.

:class:`HeaterSafety` is a context manager around a test:

* on entry it arms the furnace module's hardware watchdog with the heater-off safe value
  (``arm_watchdog``), so that a process that dies without a word (``kill -9``, power cut of
  the PC) still ends with the heater off once the module stops hearing from the host;
* it installs SIGINT and SIGTERM handlers that raise :class:`Interrupted` in the main thread
  (so ``finally`` blocks and the record writer run), and registers an ``atexit`` hook;
* on every exit — normal end, exception, Ctrl-C, SIGTERM, interpreter exit — it calls
  ``heater_off`` (retried), then restores the previous handlers.

:func:`check_temperature` is the over-temperature / open-thermocouple rule the furnace
channel applies to every reading; it raises :class:`SafetyError` naming the device.
"""

from __future__ import annotations

import atexit
import logging
import math
import signal
import threading
import time
from typing import Callable

from flowcurve.errors import DeviceError, SafetyError

logger = logging.getLogger(__name__)

# DCON family modules report a broken thermocouple as an over-range or under-range reading
OPEN_THERMOCOUPLE_HIGH_C = 9999.0


class Interrupted(KeyboardInterrupt):
    """The operator or the system asked the test to stop (SIGINT / SIGTERM)."""

    def __init__(self, signame: str):
        super().__init__(signame)
        self.signame = signame

    def __str__(self) -> str:
        return f"stopped by {self.signame}"


def check_temperature(temperature_C: float, max_C: float, device: str = "furnace") -> float:
    """Return the reading if it is safe; raise SafetyError on over-temperature or open TC."""
    if temperature_C is None or not math.isfinite(temperature_C) or temperature_C >= OPEN_THERMOCOUPLE_HIGH_C:
        raise SafetyError(device, f"thermocouple open or out of range (reading {temperature_C}); heater switched off")
    if temperature_C > max_C:
        raise SafetyError(device, f"over-temperature: {temperature_C:.1f} C above the configured maximum {max_C:.1f} C; heater switched off")
    return temperature_C


class HeaterSafety:
    """Context manager: watchdog armed at entry, heater off on every way out.

    heater_off: switches the heater output off (may raise; it is retried ``retries`` times).
    arm_watchdog: arms the module's host watchdog with the heater-off safe value (or None).
    log: ``log(event_name, text)`` receives ``heater_off`` / ``safety_error`` events.
    """

    def __init__(self, heater_off: Callable[[], None], *, arm_watchdog: Callable[[], None] | None = None, log: Callable[[str, str], None] | None = None, retries: int = 3):
        self.heater_off = heater_off
        self.arm_watchdog = arm_watchdog
        self.log = log
        self.retries = retries
        self.off_confirmed = False
        self.off_error: str | None = None
        self._done = False
        self.attempted = False
        self._exiting = False
        self._lock = threading.Lock()
        self._old_handlers: dict[int, object] = {}

    # signals -------------------------------------------------------------------------------
    def _raise_interrupted(self, signum, frame) -> None:
        if self._exiting:  # already on the way out: do not interrupt the heater switch-off
            return
        raise Interrupted(signal.Signals(signum).name)

    def _install_handlers(self) -> None:
        if threading.current_thread() is not threading.main_thread():
            return  # signal handlers can only be set from the main thread
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._old_handlers[sig] = signal.signal(sig, self._raise_interrupted)

    def _restore_handlers(self) -> None:
        for sig, old in self._old_handlers.items():
            signal.signal(sig, old if old is not None else signal.SIG_DFL)
        self._old_handlers.clear()

    # the one action that matters -----------------------------------------------------------
    def switch_off(self, reason: str = "end of test") -> bool:
        """Switch the heater off (idempotent per attempt; retried). True when it succeeded."""
        with self._lock:
            self.attempted = True
            last = None
            for attempt in range(self.retries):
                try:
                    self.heater_off()
                    self.off_confirmed = True
                    self.off_error = None
                    if self.log and not self._done:
                        self.log("heater_off", reason)
                    self._done = True
                    return True
                except Exception as exc:  # keep trying whatever failed: the heater must go off
                    last = exc
                    logger.warning("heater off, attempt %d of %d failed: %s", attempt + 1, self.retries, exc)
                    if not isinstance(exc, (DeviceError, OSError)):  # a bug: its traceback at -vv
                        logger.debug("heater off: internal error", exc_info=True)
                    time.sleep(0.05 * (attempt + 1))
            self.off_error = " ".join(str(last).split())
            if self.log:
                self.log("fault", f"heater_off failed: {self.off_error}; the module watchdog will switch it off")
            return False

    def _atexit(self) -> None:
        self.switch_off("process exit")

    # context -------------------------------------------------------------------------------
    def __enter__(self) -> "HeaterSafety":
        atexit.register(self._atexit)
        self._install_handlers()
        try:
            if self.arm_watchdog:
                self.arm_watchdog()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self._exiting = True
        try:
            if exc_type is None:
                reason = "end of test"
            elif issubclass(exc_type, KeyboardInterrupt):
                reason = str(exc) if isinstance(exc, Interrupted) else "interrupted"
            else:
                reason = " ".join(f"{exc_type.__name__}: {exc}".split())
            if not (self.attempted and self.off_confirmed is False and self.off_error):
                self.switch_off(reason)  # (after a failed attempt the module watchdog takes over)
        finally:
            self._restore_handlers()
            atexit.unregister(self._atexit)

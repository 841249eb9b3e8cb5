"""What a test procedure needs from a rig, real or virtual (:class:`RigIO`)."""

from __future__ import annotations

from typing import Callable, Protocol

from flowcurve.acquisition.sampler import Channel
from flowcurve.clock import Clock


class RigIO(Protocol):
    """What a procedure needs from a rig (real or virtual); built by acquisition.session."""

    has_furnace: bool
    can_drive: bool  # True on the virtual rig: the procedure starts the crosshead itself
    time_scale: float  # test seconds per host second (1 on the real rig)
    timebase: Clock  # host time: the wall clock, or a model clock in the fast tests
    max_temperature_C: float
    setpoint_margin_C: float  # a set-point leaves this below the maximum (rig.config.SETPOINT_MARGIN_C when absent)
    frame_stiffness_N_per_um: float | None
    loadcell_period_s: float

    def set_clock(self, clock: Callable[[], float]) -> None:
        """Stamp the devices' readings in test seconds from ``clock``."""
    def channels(self, clock: Callable[[], float], to_clock: Callable[[float], float]) -> dict[str, Channel]:
        """The sampler's channels by column name; ``clock`` and ``to_clock`` give test seconds (host time → test s)."""
    def read_temperature_C(self) -> float:
        """The furnace's temperature, °C."""
    def hold_temperature(self, setpoint_C: float) -> float:
        """One control step toward ``setpoint_C`` (°C); the reading, °C."""
    def heater_off(self) -> None:
        """Heater off; raises when the furnace does not acknowledge it."""
    def arm_watchdog(self) -> None:
        """Arm the furnace module's watchdog."""
    def host_ok(self) -> None:
        """Tell the furnace module's watchdog the host is alive."""
    def tare(self) -> None:
        """Load cell to net zero and the crosshead counter to zero."""
    def start_crosshead(self, speed_mm_per_s: float, direction: int) -> None:
        """Start the crosshead at ``speed_mm_per_s`` (mm/s) in ``direction`` (+1 up, tension; -1 down, compression)."""
    def stop_crosshead(self) -> None:
        """Stop the crosshead."""
    def post_test_measurements(self) -> dict[str, float] | None:
        """The rig's own post-test measurements (mm), None when the operator gives them."""

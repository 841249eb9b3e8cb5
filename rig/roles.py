"""The rig's device roles as :class:`typing.Protocol` s, and the models that fill each role.

A role is what the acquisition layer (:mod:`acquisition.session`, the procedure through it, the
:class:`rig.furnace.TemperatureController`) calls on a device — nothing of its wire protocol:

- force: the load-cell amplifier (:class:`ForceDevice`; :class:`rig.loadcell.LoadCell`);
- position: the crosshead encoder (:class:`PositionDevice`; :class:`rig.encoder.CrossheadEncoder`);
- temperature: the furnace module (:class:`TemperatureDevice`; :class:`rig.furnace.Furnace`).

The rig configuration names a device's model per section (``model = "hbm-aed"``); :data:`MODELS`
maps each model name to its driver class (``"module:Class"``, imported when the rig is opened),
which builds itself from its section with ``from_config(section, **kw)``. A new device is its
driver's module and one entry here (docs/extending.md). This module imports only ``typing``.
"""

from __future__ import annotations

import importlib
from typing import Any, Iterator, Protocol, Sequence, runtime_checkable


@runtime_checkable
class Link(Protocol):
    """What the acquisition reads of a device's line (:class:`rig.transport.SerialTransport`):
    whether it is open, its clock, the last request's time and what it had to repeat or discard."""

    is_open: bool
    clock: Any  # flowcurve.clock.Clock: the port's host time
    last_request_s: float | None
    late_replies: int
    retried_exchanges: int

    def close(self) -> None:
        """Close the link."""


@runtime_checkable
class Device(Protocol):
    """Every role: a name for messages, its line, opened and closed; what ``flowcurve rig check``
    prints of it (``check_lines``, on an open device) and the line settings it tries when the
    device is silent (``probe_parities``, with ``answers``)."""

    name: str
    probe_parities: tuple[str, ...]
    transport: Link

    def open(self) -> Any:
        """Open the device's port and check it answers; the device."""
    def close(self) -> None:
        """Close the device's port."""
    def check_lines(self, section: Any) -> Iterator[str]:
        """``flowcurve rig check``'s lines of the open device: identity, settings against ``section``, a reading."""
    def answers(self) -> None:
        """One exchange that names the device; raises DeviceError when silent (``rig check --probe``)."""


class ForceReading(Protocol):
    """One force value stamped in host seconds on the port's clock."""

    t_monotonic_s: float
    force_N: float


@runtime_checkable
class ForceDevice(Device, Protocol):
    """Force role (load-cell amplifier): polled or streamed force readings, tare and output rates.

    ``supported_rates_Hz()[rate_code]`` is the rate its section's ``rate_code`` sets.

    Attributes
    ----------
    name, transport : str, Link
        A name for messages; its serial line.
    stream_resyncs, latency_s : int, float
        What its stream lost or delayed: resynchronisations, latency in host seconds.
    """

    stream_resyncs: int
    latency_s: float

    @property
    def frames_lost(self) -> int:
        """Stream frames lost so far."""
    def supported_rates_Hz(self) -> Sequence[float]:
        """The output rates the device offers, Hz."""
    def resolution_N(self) -> float:
        """One count of the output, N (0 when unknown)."""
    def configure(self, **settings: Any) -> None:
        """Apply ``settings`` (rate, filter …)."""
    def tare(self) -> None:
        """Set the output to net zero."""
    def read(self) -> ForceReading:
        """One reading, polled."""
    def start_stream(self) -> None:
        """Start streaming readings."""
    def read_stream(self, max_samples: int, timeout: float) -> Sequence[ForceReading]:
        """Up to ``max_samples`` streamed readings, waiting up to ``timeout`` s."""


@runtime_checkable
class PositionDevice(Device, Protocol):
    """Position role (crosshead encoder): the crosshead's travel in mm since :meth:`zero`.

    Attributes
    ----------
    name, transport : str, Link
        A name for messages; its serial line.
    """

    def position_mm(self) -> float:
        """The crosshead position, mm."""
    def zero(self) -> None:
        """Set the position counter to zero."""


@runtime_checkable
class TemperatureDevice(Device, Protocol):
    """Temperature role (furnace module): the reading, the heater, the address check and the host watchdog.

    Attributes
    ----------
    name, transport : str, Link
        A name for messages; its serial line.
    max_temperature_C : float
        The heater is never on at or above it, °C.
    heater_is_on, watchdog_armed : bool
        The heater output as last commanded; the module watchdog armed (it switches the heater off by itself).
    """

    max_temperature_C: float
    heater_is_on: bool
    watchdog_armed: bool

    def temperature_C(self) -> float:
        """The thermocouple temperature, °C."""
    def heater(self, on: bool, reading_C: float | None = None) -> None:
        """Switch the heater ``on`` or off (``reading_C``: the reading it acts on, °C)."""
    def heater_off(self) -> bool:
        """Heater off; whether the module acknowledged it."""
    def digital_io(self) -> dict[str, int]:
        """The digital outputs' states by name."""
    def clear_watchdog(self) -> None:
        """Clear a tripped module watchdog."""
    def arm_watchdog(self, timeout_s: float) -> None:
        """Arm the module watchdog: outputs safe after ``timeout_s`` s without the host."""
    def disarm_watchdog(self) -> None:
        """Disarm the module watchdog."""
    def host_ok(self) -> None:
        """Tell the module watchdog the host is alive."""


ROLES: dict[str, type] = {"force": ForceDevice, "position": PositionDevice, "temperature": TemperatureDevice}
SECTION_ROLES = {"loadcell": "force", "encoder": "position", "furnace": "temperature"}  # the rig file's sections

# model name -> driver class ("module:Class", or the class) per role; the first is the default
MODELS: dict[str, dict[str, str | type]] = {
    "force": {"hbm-aed": "flowcurve.rig.loadcell:LoadCell"},
    "position": {"dcon-encoder": "flowcurve.rig.encoder:CrossheadEncoder"},
    "temperature": {"dcon-i7011": "flowcurve.rig.furnace:Furnace"},
}
DEFAULT_MODELS = {role: next(iter(models)) for role, models in MODELS.items()}


def driver_class(role: str, model: str) -> type:
    """The driver class registered for ``model`` in ``role`` (imported now).

    Parameters
    ----------
    role : str
        "force", "position" or "temperature".
    model : str
        A model name of :data:`MODELS` (``hbm-aed``).

    Returns
    -------
    type
        The driver class.

    Raises
    ------
    KeyError
        Naming the known models when there is none.
    """
    try:
        entry = MODELS[role][model]
    except KeyError:
        raise KeyError(f"no {role} device model {model!r} (known: {', '.join(MODELS.get(role, ()))})") from None
    if isinstance(entry, str):
        module, _, name = entry.partition(":")
        entry = getattr(importlib.import_module(module), name)
    return entry

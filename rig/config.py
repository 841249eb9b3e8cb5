"""Rig configuration: a TOML file with sections ``[loadcell]``, ``[encoder]``, ``[furnace]``,
``[frame]``, validated on load into frozen dataclasses.

Unknown keys, wrong types and out-of-range values raise :class:`ConfigError` naming the file
and the key (``rig.toml: [furnace] max_temperature_C: must be in 0 < x <= 1370, got 2000``).
``[furnace]`` is optional (a rig without a furnace); the others are required. Each device
section may name its ``model`` (:data:`rig.roles.MODELS`; default the drivers this rig was built
with). See ``rig/example-rig.toml`` for every key with its meaning. ``[virtual]`` is written by
``flowcurve rig virtual`` alone: the specimen its twins simulate (:class:`VirtualConfig`).
"""

from __future__ import annotations

import datetime as _dt
import math
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, ClassVar

from flowcurve.errors import ConfigError
from flowcurve.rig.codecs import aed
from flowcurve.rig.roles import DEFAULT_MODELS, MODELS, driver_class

# A furnace set-point must leave this much below [furnace] max_temperature_C: after a working switch-off
# the heat already in the elements carries the furnace above its set-point, and a furnace that crosses its
# maximum with the heater off is named a stuck relay (rig.furnace.StuckRelayCheck). About twice the largest
# overshoot measured on the virtual furnace (2.6 C; bench/stored_heat.py, docs/operator.md "Set-point margin").
SETPOINT_MARGIN_C = 5.0

PARITIES = ("N", "E", "O")
BAUDS = (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)


def _in(lo, hi, *, lo_open=False):
    def check(v):
        """None when ``v`` is in range, else the message."""
        ok = (lo < v if lo_open else lo <= v) and v <= hi
        return None if ok else f"must be in {lo} {'<' if lo_open else '<='} x <= {hi}, got {v}"
    return check


def _iso_date(value: str) -> str | None:
    try:
        _dt.date.fromisoformat(value)
    except ValueError:
        return f"must be a date YYYY-MM-DD, got {value!r}"
    return None


def _one_of(choices):
    return lambda v: None if v in choices else f"must be one of {', '.join(map(str, choices))}, got {v!r}"


def _cof(v):
    try:
        aed.output_format(v)
    except ValueError as exc:
        return str(exc)
    return None


@dataclass(frozen=True)
class SerialConfig:
    """What every device section has: the port and its line settings; ``role`` (rig.roles.ROLES)
    and ``model`` (rig.roles.MODELS) choose the driver."""

    role: ClassVar[str]
    port: str
    baud: int = 9600
    parity: str = "N"
    timeout_s: float = 0.2
    address: int = 0

    def transport_kwargs(self, name: str) -> dict[str, Any]:
        """The SerialTransport keywords of this section for device ``name``."""
        return dict(name=name, baudrate=self.baud, parity=self.parity, timeout_s=self.timeout_s)

    def create(self, **kw):
        """The driver of this section's ``model`` built from this section (port not opened yet)."""
        return driver_class(self.role, self.model).from_config(self, **kw)


@dataclass(frozen=True)
class LoadCellConfig(SerialConfig):
    role: ClassVar[str] = "force"
    model: str = DEFAULT_MODELS["force"]
    parity: str = "E"
    address: int = 31
    nominal_load_N: float | None = None
    calibration_N_per_count: float | None = None
    output_format: int = 3
    rate_code: int = 0
    # ASF2 (FMD0: -3 dB at 3.5 Hz, first-order lag about 45 ms). The amplifier's factory ASF5
    # (0.3 Hz) lags the force by about 0.5 s: 5 µm of crosshead at 10 µm/s, which bends the
    # elastic line of a short compression specimen (its whole elastic shortening is ~15 µm).
    filter: int = 2
    select_address: bool = False

    @property
    def settings(self) -> dict[str, int]:
        """Keyword arguments of :meth:`rig.loadcell.LoadCell.configure` for this section."""
        return {"rate_code": self.rate_code, "filter": self.filter, "fmt": self.output_format}


@dataclass(frozen=True)
class EncoderConfig(SerialConfig):
    role: ClassVar[str] = "position"
    model: str = DEFAULT_MODELS["position"]
    address: int = 2
    checksum: bool = False
    counts_per_rev: int = 10_000
    gear_ratio: float = 1.0
    screw_lead_mm: float = 100.0


@dataclass(frozen=True)
class FurnaceConfig(SerialConfig):
    role: ClassVar[str] = "temperature"
    model: str = DEFAULT_MODELS["temperature"]
    address: int = 1
    timeout_s: float = 0.3
    checksum: bool = False
    heater_do_bit: int = 0
    max_temperature_C: float = 900.0
    max_heating_rate_C_per_min: float = 30.0
    watchdog_timeout_s: float = 10.0
    control_period_s: float = 2.0
    approach_s: float = 30.0
    kp_per_C: float = 0.05
    ki_per_C_s: float = 0.0005
    setpoint_margin_C: float = SETPOINT_MARGIN_C

    def controller(self, furnace, setpoint_C: float, **kw):
        """A :class:`rig.furnace.TemperatureController` with this section's limits and tuning."""
        from flowcurve.rig.furnace import TemperatureController

        return TemperatureController(furnace, setpoint_C, max_temperature_C=self.max_temperature_C,
                                     max_rate_C_per_min=self.max_heating_rate_C_per_min,
                                     period_s=self.control_period_s, approach_s=self.approach_s,
                                     kp_per_C=self.kp_per_C,
                                     ki_per_C_s=self.ki_per_C_s, **kw)


@dataclass(frozen=True)
class FrameConfig:
    stiffness_N_per_um: float = 136.0
    max_force_N: float = 100_000.0
    # what the machine can do and take: a test asking for more is refused before it starts
    min_speed_mm_per_s: float = 0.001
    max_speed_mm_per_s: float = 2.0
    travel_mm: float = 250.0
    max_specimen_diameter_mm: float = 30.0
    max_specimen_length_mm: float = 200.0


@dataclass(frozen=True)
class InstrumentsConfig:
    """The measuring instruments' classes, for the results' uncertainty budgets (written into each record)."""

    force_class: float = 1.0  # ISO 7500-1 class of the force-measuring system
    extensometer_class: float = 1.0  # ISO 9513 class of the extensometer
    diameter_resolution_mm: float = 0.01  # resolution of the diameter measurement
    length_resolution_mm: float = 0.01  # resolution of lengths and heights (L0, Lu, h0, hk)
    crosshead_strain_error_pct: float = 2.0  # bound on a strain from crosshead travel (no extensometer)
    # calibration data (optional; a report with none of it is "not for release"): certificate number and due date
    force_certificate: str | None = None
    force_due_date: str | None = None  # ISO date, YYYY-MM-DD
    force_U_rel_pct: float | None = None  # the certificate's relative expanded uncertainty, %
    force_resolution_N: float | None = None
    extensometer_certificate: str | None = None
    extensometer_due_date: str | None = None
    micrometer_mpe_mm: float | None = None  # maximum permissible error (diameters)
    micrometer_certificate: str | None = None
    micrometer_due_date: str | None = None
    caliper_mpe_mm: float | None = None  # maximum permissible error (lengths)
    caliper_certificate: str | None = None
    caliper_due_date: str | None = None
    thermocouple_tolerance_C: float | None = None  # e.g. ±1.5 °C for IEC 60584-1 class 1 type K
    thermocouple_certificate: str | None = None
    thermocouple_due_date: str | None = None

    def meta(self) -> dict[str, float | str]:
        """The record metadata (``instruments.<key>``) the identification reads them from (unset keys left out)."""
        return {f"instruments.{f.name}": getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class VirtualConfig:
    """``[virtual]``: written by ``flowcurve rig virtual`` alone — the specimen its twins simulate
    (mm, the record's geometry keys), so that ``flowcurve run --config`` can tell a test stating
    another geometry. A real rig's file has no such table."""

    test: str = "tension"
    d0_mm: float | None = None
    l0_mm: float | None = None
    parallel_length_mm: float | None = None  # the parallel length Lc (tension): l0 when not given
    h0_mm: float | None = None

    @property
    def geometry_mm(self) -> dict[str, float]:
        """The geometry given (key → mm)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name != "test" and getattr(self, f.name) is not None}


VIRTUAL_GEOMETRY = {"tension": ("d0_mm", "l0_mm"), "compression": ("d0_mm", "h0_mm")}  # [virtual]'s keys each test needs


@dataclass(frozen=True)
class RigConfig:
    """The whole rig, as its TOML file configures it.

    Attributes
    ----------
    loadcell, encoder : LoadCellConfig, EncoderConfig
        The force and position devices' ports and settings.
    furnace : FurnaceConfig or None
        The furnace controller; None on a rig without one.
    frame : FrameConfig
        The frame: capacity (N), stiffness (N/µm), stroke (mm), speed range (mm/s).
    source : str
        The file read ("<virtual>" for the virtual rig's).
    instruments : InstrumentsConfig
        Classes, certificates and resolutions of the instruments (uncertainty budgets).
    virtual : VirtualConfig or None
        The specimen the virtual rig simulates (``flowcurve rig virtual``'s file only).
    """

    loadcell: LoadCellConfig
    encoder: EncoderConfig
    furnace: FurnaceConfig | None
    frame: FrameConfig
    source: str = "<virtual>"
    instruments: InstrumentsConfig = InstrumentsConfig()  # [instruments] is optional: the defaults
    virtual: VirtualConfig | None = None


_SERIAL_CHECKS = {
    "port": (str, lambda v: None if v.strip() else "must not be empty"),
    "baud": (int, _one_of(BAUDS)),
    "parity": (str, _one_of(PARITIES)),
    "timeout_s": (float, _in(0.0, 10.0, lo_open=True)),
}
SCHEMA: dict[str, tuple[type, dict[str, tuple[type, Any]]]] = {
    "loadcell": (LoadCellConfig, _SERIAL_CHECKS | {
        "model": (str, _one_of(MODELS["force"])),
        "address": (int, _in(0, 99)),
        "nominal_load_N": (float, _in(0.0, 1e7, lo_open=True)),
        "calibration_N_per_count": (float, _in(0.0, 1.0, lo_open=True)),
        "output_format": (int, _cof),
        "rate_code": (int, _in(0, 7)),
        "filter": (int, _in(0, 8)),
        "select_address": (bool, None),
    }),
    "encoder": (EncoderConfig, _SERIAL_CHECKS | {
        "model": (str, _one_of(MODELS["position"])),
        "address": (int, _in(0, 255)),
        "checksum": (bool, None),
        "counts_per_rev": (int, _in(1, 10**7)),
        "gear_ratio": (float, _in(0.0, 1000.0, lo_open=True)),
        "screw_lead_mm": (float, _in(0.0, 1000.0, lo_open=True)),
    }),
    "furnace": (FurnaceConfig, _SERIAL_CHECKS | {
        "model": (str, _one_of(MODELS["temperature"])),
        "address": (int, _in(0, 255)),
        "checksum": (bool, None),
        "heater_do_bit": (int, _in(0, 1)),
        "max_temperature_C": (float, _in(0.0, 1370.0, lo_open=True)),
        "max_heating_rate_C_per_min": (float, _in(0.0, 200.0, lo_open=True)),
        "watchdog_timeout_s": (float, _in(0.1, 25.5)),
        "control_period_s": (float, _in(0.1, 60.0)),
        "approach_s": (float, _in(0.0, 3600.0)),
        "kp_per_C": (float, _in(0.0, 10.0)),
        "ki_per_C_s": (float, _in(0.0, 1.0)),
        "setpoint_margin_C": (float, _in(0.0, 500.0)),
    }),
    "frame": (FrameConfig, {
        "stiffness_N_per_um": (float, _in(0.0, 1e6, lo_open=True)),
        "max_force_N": (float, _in(0.0, 1e8, lo_open=True)),
        "min_speed_mm_per_s": (float, _in(0.0, 1000.0, lo_open=True)),
        "max_speed_mm_per_s": (float, _in(0.0, 1000.0, lo_open=True)),
        "travel_mm": (float, _in(0.0, 10_000.0, lo_open=True)),
        "max_specimen_diameter_mm": (float, _in(0.0, 1000.0, lo_open=True)),
        "max_specimen_length_mm": (float, _in(0.0, 10_000.0, lo_open=True)),
    }),
    "instruments": (InstrumentsConfig, {
        "force_class": (float, _one_of((0.5, 1.0, 2.0, 3.0))),
        "extensometer_class": (float, _one_of((0.2, 0.5, 1.0, 2.0))),
        "diameter_resolution_mm": (float, _in(0.0, 1.0, lo_open=True)),
        "length_resolution_mm": (float, _in(0.0, 1.0, lo_open=True)),
        "crosshead_strain_error_pct": (float, _in(0.0, 50.0, lo_open=True)),
        "force_U_rel_pct": (float, _in(0.0, 10.0, lo_open=True)),
        "force_resolution_N": (float, _in(0.0, 1e6, lo_open=True)),
        "micrometer_mpe_mm": (float, _in(0.0, 1.0, lo_open=True)),
        "caliper_mpe_mm": (float, _in(0.0, 1.0, lo_open=True)),
        "thermocouple_tolerance_C": (float, _in(0.0, 50.0, lo_open=True)),
        **{f"{i}_certificate": (str, lambda v: None if v else "must not be empty")
           for i in ("force", "extensometer", "micrometer", "caliper", "thermocouple")},
        **{f"{i}_due_date": (str, _iso_date) for i in ("force", "extensometer", "micrometer", "caliper", "thermocouple")},
    }),
    "virtual": (VirtualConfig, {
        "test": (str, _one_of(tuple(VIRTUAL_GEOMETRY))),
        "d0_mm": (float, _in(0.0, 1000.0, lo_open=True)),
        **{key: (float, _in(0.0, 10_000.0, lo_open=True)) for key in ("l0_mm", "parallel_length_mm", "h0_mm")},
    }),
}
REQUIRED_SECTIONS = ("loadcell", "encoder", "frame")


def setpoint_refusal(setpoint_C: float, max_temperature_C: float, margin_C: float = SETPOINT_MARGIN_C) -> str | None:
    """Why a set-point below the maximum is still refused (None: it is not): it must leave
    ``margin_C`` below ``max_temperature_C`` for the stored heat after the heater switches off.
    The text follows the set-point's name (``--temperature``, ``set-point``)."""
    highest = max_temperature_C - margin_C
    if setpoint_C <= highest:
        return None
    return (f"must leave {margin_C:g} C below the furnace's maximum {max_temperature_C:g} C, got {setpoint_C:g}: after the "
            f"heater switches off, the heat already in the elements carries the furnace a few C above its set-point, and a "
            f"furnace past its maximum with the heater off is named a stuck relay — give at most {highest:g} C (the margin "
            f"is [furnace] setpoint_margin_C)")


def _value(where: str, key: str, value: Any, kind: type, check) -> Any:
    if kind is str and isinstance(value, _dt.date):  # a TOML date literal (due_date = 2027-03-31)
        value = value.isoformat()
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        raise ConfigError(f"{where} {key}: must be {_TYPE_NAMES[kind]}, got {type(value).__name__} {value!r}")
    if kind is float and not math.isfinite(value):
        raise ConfigError(f"{where} {key}: must be finite, got {value}")
    if kind is str:
        value = value.strip()
        if key == "parity":
            value = value.upper()
    problem = check(value) if check else None
    if problem:
        raise ConfigError(f"{where} {key}: {problem}")
    return value


_TYPE_NAMES = {int: "an integer", float: "a number", str: "a string", bool: "true or false"}


def _section(origin: str, name: str, table: Any):
    cls, checks = SCHEMA[name]
    where = f"{origin}: [{name}]"
    if not isinstance(table, dict):
        raise ConfigError(f"{where}: must be a table, got {table!r}")
    values = {}
    for key, value in table.items():
        if key not in checks:
            known = ", ".join(f.name for f in fields(cls))
            raise ConfigError(f"{where} {key}: unknown key (known: {known})")
        values[key] = _value(where, key, value, *checks[key])
    if "port" in checks and "port" not in values:
        raise ConfigError(f"{where} port: missing (a device path, e.g. /dev/ttyUSB0, or a pyserial URL)")
    if name == "frame" and values.get("min_speed_mm_per_s", FrameConfig.min_speed_mm_per_s) > values.get("max_speed_mm_per_s", FrameConfig.max_speed_mm_per_s):
        raise ConfigError(f"{where} min_speed_mm_per_s: must not be above max_speed_mm_per_s")
    if name == "virtual":
        test = values.get("test", VirtualConfig.test)
        needs, may = VIRTUAL_GEOMETRY[test], VIRTUAL_GEOMETRY[test] + (("parallel_length_mm",) if test == "tension" else ())
        for key in [k for k in needs if k not in values] + [k for k in values if k != "test" and k not in may]:
            raise ConfigError(f"{where} {key}: " + (f"missing (a {test} specimen's)" if key in needs else f"not a {test} specimen's length"))
        if values.get("parallel_length_mm", math.inf) < values.get("l0_mm", 0.0):
            raise ConfigError(f"{where} parallel_length_mm: must be at least l0_mm (the gauge marks lie on it)")
    if name == "loadcell":
        given = [k for k in ("nominal_load_N", "calibration_N_per_count") if k in values]
        if len(given) != 1:
            raise ConfigError(f"{where} nominal_load_N: give exactly one of nominal_load_N and "
                              f"calibration_N_per_count (got {len(given)})")
    return cls(**values)


def instruments_given(table: Any, origin: str) -> dict:
    """The keys an ``[instruments]`` table gives, checked as the rig configuration checks them
    (also for a lab file's ``[instruments]``): ``{key: value}`` without the defaults."""
    section = _section(origin, "instruments", table)
    return {k: getattr(section, k) for k in table}


def parse_config(data: dict, origin: str = "<config>") -> RigConfig:
    """Validate an already-parsed TOML document (``origin`` names it in errors)."""
    for name in data:
        if name not in SCHEMA:
            raise ConfigError(f"{origin}: [{name}]: unknown section (known: {', '.join(SCHEMA)})")
    for name in REQUIRED_SECTIONS:
        if name not in data:
            raise ConfigError(f"{origin}: [{name}]: missing section")
    sections = {name: _section(origin, name, data[name]) for name in data}
    config = RigConfig(sections["loadcell"], sections["encoder"], sections.get("furnace"),
                       sections["frame"], origin, sections.get("instruments", InstrumentsConfig()), sections.get("virtual"))
    ports = [s.port for s in (config.loadcell, config.encoder, config.furnace)
             if s is not None and not s.port.startswith("loop://")]
    if len(set(ports)) != len(ports):
        raise ConfigError(f"{origin}: two devices share one port ({', '.join(ports)}); each needs its own")
    return config


def load_config(path) -> RigConfig:
    """Read and validate a rig TOML file.

    Parameters
    ----------
    path : str or PathLike
        The rig's TOML file.

    Returns
    -------
    RigConfig
        The checked configuration.

    Raises
    ------
    ConfigError
        Naming the file, section and key of a missing or refused value.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such rig configuration file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    return parse_config(data, str(path))


# Unprefixed keyword arguments of virtual_config and the sections they go to.
_SHORTCUTS = {"nominal_load_N": ("loadcell",), "frame_stiffness_N_per_um": ("frame",),
              "checksum": ("encoder", "furnace"), "max_temperature_C": ("furnace",)}


def virtual_config(ports: dict[str, str], **overrides) -> RigConfig:
    """A configuration for the virtual rig's pseudo-terminals, validated like a file.

    ``ports`` maps ``loadcell``, ``encoder`` (and ``furnace``) to port paths. Overrides are
    ``<section>_<key>=value`` (``furnace_max_temperature_C=500``, ``loadcell_address=5``) or the
    shortcuts ``nominal_load_N``, ``frame_stiffness_N_per_um``, ``checksum``, ``max_temperature_C``.
    """
    data: dict[str, dict] = {"loadcell": {"nominal_load_N": 100_000.0}, "encoder": {}, "frame": {}}
    for name, port in ports.items():
        if name not in ("loadcell", "encoder", "furnace"):
            raise ConfigError(f"<virtual>: ports: unknown device {name!r}")
        data.setdefault(name, {})["port"] = port
    for key, value in overrides.items():
        if key == "frame_stiffness_N_per_um":
            data["frame"]["stiffness_N_per_um"] = value
            continue
        targets = _SHORTCUTS.get(key)
        if targets:
            for section in targets:
                if section in data:
                    data[section][key] = value
            continue
        section, _, name = key.partition("_")
        if section not in SCHEMA or not name:
            raise ConfigError(f"<virtual>: {key}: unknown override (use <section>_<key>)")
        data.setdefault(section, {})[name] = value
    if "calibration_N_per_count" in data["loadcell"] and "nominal_load_N" not in overrides:
        del data["loadcell"]["nominal_load_N"]
    return parse_config(data, "<virtual>")


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(v)


def to_toml(config: RigConfig) -> str:
    """The configuration as a TOML document that :func:`load_config` reads back identically."""
    lines = [f"# flowcurve rig configuration (written from {config.source})"]
    for name in ("loadcell", "encoder", "furnace", "frame", "instruments", "virtual"):
        section = getattr(config, name)
        if section is None:
            continue
        lines.append(f"\n[{name}]")
        for f in fields(section):
            value = getattr(section, f.name)
            if value is not None:
                lines.append(f"{f.name} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"

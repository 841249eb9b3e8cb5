"""Fault drills without code: ``DEVICE:KIND[:VALUE][@SECONDS]`` → :class:`FaultSpec`.

Pure parsing and description (no devices here): ``rig virtual``, ``run`` and ``demo`` take
``--fault`` options in this form and hand the specs to :meth:`rig.virtual.rig.VirtualRig.schedule`.

* DEVICE: ``loadcell``, ``encoder`` or ``furnace``;
* KIND: one of :data:`KINDS` (which devices each applies to: :data:`APPLIES_TO`);
* VALUE: a rate or a size in the unit :data:`VALUE_UNITS` gives (``loadcell:garble:0.05`` —
  5 % of the frames; ``encoder:jump:50`` — a 50 mm counter step; ``loadcell:spike:900@40`` — one
  frame 900 N high 40 s into the test); :data:`DEFAULT_VALUES` when
  omitted; kinds without a value refuse one;
* SECONDS: model seconds after the crosshead starts moving (``loadcell:corrupt@5``); without
  it the fault is on from the start.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from flowcurve.errors import ConfigError

DEVICES = ("loadcell", "encoder", "furnace")
ALL = DEVICES

# kind → (devices it applies to, what it does)
KINDS: dict[str, tuple[tuple[str, ...], str]] = {
    "silence": (ALL, "the device stops answering"),
    "drop": (ALL, "a fraction VALUE of the replies is lost"),
    "garble": (ALL, "a fraction VALUE of the replies is corrupted beyond decoding"),
    "delay": (ALL, "replies leave VALUE seconds late"),
    "unplug": (ALL, "the port vanishes (cable pulled)"),
    "corrupt": (ALL, "one well-formed reply carries a wrong value (+VALUE)"),
    "spike": (("loadcell",), "one frame reads VALUE N high, the next is true again (a spike)"),
    "jump": (("encoder",), "the counter steps by VALUE mm and stays stepped"),
    "wrong_address": (("furnace",), "replies come from address VALUE instead of the configured one"),
    "open_thermocouple": (("furnace",), "the thermocouple breaks (reading over range)"),
    "relay_stuck": (("furnace",), "the heater relay sticks on whatever the output says"),
}
APPLIES_TO = {kind: devices for kind, (devices, _) in KINDS.items()}

# kind → default VALUE (per device where the unit differs); kinds absent take no value
DEFAULT_VALUES: dict[str, dict[str, float]] = {
    "drop": {d: 1.0 for d in ALL},
    "garble": {d: 1.0 for d in ALL},
    "delay": {d: 0.5 for d in ALL},
    "corrupt": {"loadcell": 20000.0, "encoder": 50.0, "furnace": 200.0},
    "spike": {"loadcell": 900.0},
    "jump": {"encoder": 50.0},
    "wrong_address": {"furnace": 3.0},
}
VALUE_UNITS = {
    "drop": {d: "fraction of replies, 0..1" for d in ALL},
    "garble": {d: "fraction of replies, 0..1" for d in ALL},
    "delay": {d: "s" for d in ALL},
    "corrupt": {"loadcell": "N", "encoder": "mm", "furnace": "C"},
    "spike": {"loadcell": "N"},
    "jump": {"encoder": "mm"},
    "wrong_address": {"furnace": "address, 0..255"},
}

_FORM = re.compile(r"^(?P<device>[a-z_]+):(?P<kind>[a-z_]+)(?::(?P<value>[^@]+))?(?:@(?P<at>.+))?$")


@dataclass(frozen=True)
class FaultSpec:
    """One scheduled fault: ``value`` in the kind's unit, ``at_s`` model seconds after the
    crosshead starts moving (None: from the start)."""

    device: str
    kind: str
    value: float | None = None
    at_s: float | None = None

    def describe(self) -> str:
        """``loadcell:garble:0.05@5`` — the option's own form (defaults written out)."""
        text = f"{self.device}:{self.kind}"
        if self.value is not None:
            text += f":{self.value:.12g}"
        if self.at_s is not None:
            text += f"@{self.at_s:.12g}"
        return text


def parse_fault(text: str) -> FaultSpec:
    """``'loadcell:garble:0.05@5'`` → FaultSpec; ConfigError naming what is wrong."""
    where = f"--fault {text!r}"
    m = _FORM.match(text.strip().lower())
    if not m:
        raise ConfigError(f"{where}: give DEVICE:KIND[:VALUE][@SECONDS], e.g. loadcell:garble:0.05 or loadcell:corrupt@5")
    device, kind = m.group("device"), m.group("kind")
    if device not in DEVICES:
        raise ConfigError(f"{where}: unknown device '{device}' (one of {', '.join(DEVICES)})")
    if kind not in KINDS:
        raise ConfigError(f"{where}: unknown fault '{kind}' (one of {', '.join(KINDS)})")
    if device not in APPLIES_TO[kind]:
        raise ConfigError(f"{where}: '{kind}' applies to {', '.join(APPLIES_TO[kind])}, not the {device}")
    value = _value(where, device, kind, m.group("value"))
    at = None
    if m.group("at") is not None:
        at = _number(where, "SECONDS", m.group("at"))
        if at < 0:
            raise ConfigError(f"{where}: SECONDS must be >= 0 (model seconds after the crosshead starts), got {at:g}")
    return FaultSpec(device, kind, value, at)


def parse_faults(texts) -> tuple[FaultSpec, ...]:
    """Every ``--fault`` option (None or empty: no faults)."""
    return tuple(parse_fault(t) for t in texts or ())


def _value(where: str, device: str, kind: str, raw: str | None) -> float | None:
    defaults = DEFAULT_VALUES.get(kind)
    if defaults is None:
        if raw is not None:
            raise ConfigError(f"{where}: '{kind}' takes no VALUE")
        return None
    if raw is None:
        return defaults[device]
    value = _number(where, "VALUE", raw)
    unit = VALUE_UNITS[kind][device]
    if kind in ("drop", "garble") and not 0.0 < value <= 1.0:
        raise ConfigError(f"{where}: VALUE is a {unit}, got {value:g}")
    if kind == "delay" and not value > 0:
        raise ConfigError(f"{where}: VALUE is a delay in s, > 0, got {value:g}")
    if kind == "wrong_address" and not (value == int(value) and 0 <= value <= 255):
        raise ConfigError(f"{where}: VALUE is an {unit}, got {value:g}")
    if kind in ("corrupt", "spike", "jump") and value == 0:
        raise ConfigError(f"{where}: VALUE is a size in {unit}, not 0")
    return value


def _number(where: str, what: str, raw: str) -> float:
    try:
        value = float(raw)
    except ValueError:
        raise ConfigError(f"{where}: {what} is not a number: {raw!r}") from None
    if not math.isfinite(value):
        raise ConfigError(f"{where}: {what} must be finite, got {raw!r}")
    return value


def help_text() -> str:
    """The ``--fault`` help: the form, then each kind with the devices it applies to."""
    lines = []
    for kind, (devices, what) in KINDS.items():
        unit = VALUE_UNITS.get(kind)
        if unit:
            units = sorted(set(unit.values()))
            default = DEFAULT_VALUES[kind]
            vals = ", ".join(sorted({f"{default[d]:g}" for d in devices})) if len(set(unit.values())) == 1 else \
                ", ".join(f"{d} {default[d]:g}" for d in devices)
            what += f" (VALUE: {' / '.join(units)}; default {vals})"
        lines.append(f"{kind} [{'any device' if devices == ALL else ', '.join(devices)}]: {what}")
    return ("inject a fault on the virtual rig: DEVICE:KIND[:VALUE][@SECONDS] (repeatable); DEVICE loadcell|encoder|furnace; "
            "SECONDS = model time after the crosshead starts moving (default: from the start). Kinds: " + "; ".join(lines))

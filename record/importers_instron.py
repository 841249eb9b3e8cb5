"""The INSTRON export of the 42CrMoS4 validation set: a tab-separated ``key:<TAB>value<TAB>unit``
header, a names row, a units row, then samples; its published results kept as ``published.<name>``."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path



from flowcurve.record.format import MAX_MAGNITUDE, Record, shown
from flowcurve.errors import RecordError
from flowcurve.record.importers_csv import Column, _read_columns
from flowcurve.record.importers_text import EXTENSOMETER_GAUGE_KEY, FIRST_DATA_LINE_KEY, Text, decode_text, to_native


INSTRON_COLUMNS = {
    "Time": ("time_s", "time"),
    "Displacement": ("extensometer_mm", "length"),  # the extensometer on the gauge length
    "Force": ("force_N", "force"),
    "Machine Displacement": ("crosshead_mm", "length"),
}

# header key → (metadata key, quantity) for numbers converted through the unit table
INSTRON_NUMBERS = {
    "Gauge diameter": ("specimen.d0_mm", "length"),
    "Parallel length": ("specimen.parallel_length_mm", "length"),
    "Original cross-section": ("specimen.s0_mm2", "area"),
    "Cross-section after fracture": ("post.sk_mm2", "area"),
    "Yield stress at 0.2% plastic strain": ("published.Rp02_MPa", "stress"),
    "Yield stress at 1% plastic strain": ("published.Rp1_MPa", "stress"),
    "Ultimate tensile strength": ("published.Rm_MPa", "stress"),
    "Uniform elongation": ("published.Ag_pct", "percent"),
    "Elongation after fracture": ("published.A_pct", "percent"),
    "Reduction of area": ("published.Z_pct", "percent"),
    "Slope of linear-elastic region": ("published.E_MPa", "stress"),
    "Crosshead seperation speed": ("crosshead_speed_mm_per_s", "speed"),  # sic, as INSTRON spells it
    "Crosshead separation speed": ("crosshead_speed_mm_per_s", "speed"),
    "Strain rate": ("published.strain_rate_per_s", "rate"),
}
INSTRON_TEXT = {
    "Specimen name": "specimen.name",
    "Specimen ID": "specimen.id",
    "Material": "material",
    "Specimen type": "specimen.type",
    "Machine type": "rig.machine",
    "Standard": "standard",
    "Heat treatment batch": "material.batch",
    "Date": "date",
}
ROOM_TEMPERATURE_C = 23.0


def _is_instron(lines: list[str]) -> bool:
    lines = lines[:60]
    keyed = sum(1 for line in lines if re.match(r"^[^\t]+:\t", line))
    return keyed >= 3 and any(line.split("\t")[:1] == ["Time"] and "Force" in line.split("\t") for line in lines)


def read_instron(path: str | os.PathLike, *, text: Text | None = None) -> Record:
    """Read an INSTRON (Bluehill-style) tab-separated export with a ``key:\\tvalue\\tunit`` header."""
    path = Path(path)
    source = str(path)
    text = text or decode_text(path)
    lines = text.head
    meta: dict[str, str] = {"source_format": "instron-export"}
    warnings: list[str] = []
    names_idx = None
    for i, line in enumerate(lines):
        cells = line.split("\t")
        if cells[0] == "Time" and "Force" in cells:
            names_idx = i
            break
        key = cells[0].rstrip()
        if not key.endswith(":"):
            continue
        key = key[:-1].strip()
        value = cells[1].strip() if len(cells) > 1 else ""
        unit = cells[2].strip() if len(cells) > 2 else ""
        if key in INSTRON_NUMBERS:
            meta_key, quantity = INSTRON_NUMBERS[key]
            number = _header_number(value, source, i + 1, key)
            meta[meta_key] = repr(float(to_native(number, unit, quantity, source=source, column=key)))
        elif key == "Gauge length":
            number = _header_number(value, source, i + 1, key)
            l0 = repr(float(to_native(number, unit, "length", source=source, column=key)))
            meta["specimen.l0_mm"] = l0
            meta[EXTENSOMETER_GAUGE_KEY] = l0  # the Displacement column is the extensometer
        elif key == "Test temperature":
            if value.upper() == "RT":
                meta["nominal_temperature_C"] = repr(ROOM_TEMPERATURE_C)
                meta["nominal_temperature_as_written"] = value  # for the models a number; for conformity "not stated"
                warnings.append(f"test temperature 'RT' taken as {ROOM_TEMPERATURE_C:g} °C")
            else:
                number = _header_number(value, source, i + 1, key)
                meta["nominal_temperature_C"] = repr(float(to_native(number, unit, "temperature", source=source, column=key)))
        elif key in INSTRON_TEXT:
            if key == "Date":
                value = value.removesuffix(" 00:00:00")
            meta[INSTRON_TEXT[key]] = value
    if names_idx is None:
        raise RecordError(source, "INSTRON export without a column row starting with 'Time'")
    if "post.sk_mm2" in meta:
        # dk from the measured area after fracture, S = π dk²/4
        meta["post.dk_mm"] = repr(math.sqrt(4.0 * float(meta["post.sk_mm2"]) / math.pi))
    if "Round Tensile" in meta.get("specimen.type", "") or "tensile" in meta.get("specimen.type", "").lower():
        meta["test"] = "tension"
    names = lines[names_idx].split("\t")
    units = lines[names_idx + 1].split("\t") if names_idx + 1 < len(lines) else []
    if len(units) < len(names):
        raise RecordError(source, "the units row under the column row is missing or short", line=names_idx + 2)
    missing = [n for n in INSTRON_COLUMNS if n not in names]
    if missing:
        raise RecordError(source, f"missing column(s) {', '.join(missing)} (found: {shown(', '.join(names), 200)})", line=names_idx + 1)
    mapping = {names.index(name): Column(native, quantity, units[names.index(name)], name) for name, (native, quantity) in INSTRON_COLUMNS.items()}
    data = _read_columns(source, text, sep="\t", decimal=".", first_data_line=names_idx + 2, mapping=mapping)
    meta[FIRST_DATA_LINE_KEY] = str(names_idx + 3)
    return Record(meta=meta, data=data, source=source, warnings=warnings)


def _header_number(value: str, source: str, line: int, key: str) -> float:
    try:
        number = float(value.replace(",", "."))
    except ValueError:
        raise RecordError(source, f"'{key}' is not a number: {shown(value)}", line=line) from None
    if not math.isfinite(number) or abs(number) > MAX_MAGNITUDE:
        raise RecordError(source, f"'{key}' = {value!r} is not a measurement (infinite, not a number or beyond {MAX_MAGNITUDE:g})", line=line)
    return number

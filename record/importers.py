"""Read a test record from any file the lab meets: native, INSTRON export, or any CSV.

:func:`load_record` is the one entry point. It returns an
:class:`flowcurve.record.format.Record` with the native unit-named columns (``time_s``,
``force_N``, ``crosshead_mm`` and, where the file has them, ``extensometer_mm``,
``temperature_C``), whatever units the file used:

* native flowcurve records (``# flowcurve-record: 1``) are read by
  :func:`flowcurve.record.format.read_record`;
* the INSTRON export of the 42CrMoS4 validation set (tab-separated ``key:<TAB>value<TAB>unit``
  header, a names row, a units row, then samples) is recognised and mapped, its published
  results kept as ``published.<name>`` metadata;
* any other CSV is read through a column mapping ``{"force": ("Load", "kN"), ...}``.

Units are converted through :data:`UNITS`; a unit it does not know is an error, never a guess.
"""

from __future__ import annotations

import csv
import math
import os
import re
from pathlib import Path
from typing import Mapping

import pandas as pd

from flowcurve.record.format import Record, is_native, read_record
from flowcurve.errors import RecordError

# -- units ---------------------------------------------------------------------------------

# unit (as written in files, case-sensitive first, then lower-case) → (quantity, factor, offset)
# value_native = value * factor + offset; native units: N, mm, s, °C, MPa, mm², %, 1/s, mm/s.
UNITS: dict[str, tuple[str, float, float]] = {
    # force → N
    "N": ("force", 1.0, 0.0),
    "kN": ("force", 1e3, 0.0),
    "MN": ("force", 1e6, 0.0),
    "mN": ("force", 1e-3, 0.0),
    "daN": ("force", 10.0, 0.0),
    "lbf": ("force", 4.4482216152605, 0.0),
    "kip": ("force", 4448.2216152605, 0.0),
    "kgf": ("force", 9.80665, 0.0),
    "tf": ("force", 9806.65, 0.0),
    # length → mm
    "mm": ("length", 1.0, 0.0),
    "m": ("length", 1e3, 0.0),
    "cm": ("length", 10.0, 0.0),
    "µm": ("length", 1e-3, 0.0),
    "μm": ("length", 1e-3, 0.0),  # Greek mu, as some exports write it
    "um": ("length", 1e-3, 0.0),
    "in": ("length", 25.4, 0.0),
    "inch": ("length", 25.4, 0.0),
    # time → s
    "s": ("time", 1.0, 0.0),
    "sec": ("time", 1.0, 0.0),
    "ms": ("time", 1e-3, 0.0),
    "min": ("time", 60.0, 0.0),
    "h": ("time", 3600.0, 0.0),
    # temperature → °C
    "°C": ("temperature", 1.0, 0.0),
    "C": ("temperature", 1.0, 0.0),
    "degC": ("temperature", 1.0, 0.0),
    "Cel": ("temperature", 1.0, 0.0),
    "K": ("temperature", 1.0, -273.15),
    "°F": ("temperature", 5.0 / 9.0, -32.0 * 5.0 / 9.0),
    "F": ("temperature", 5.0 / 9.0, -32.0 * 5.0 / 9.0),
    # stress → MPa
    "MPa": ("stress", 1.0, 0.0),
    "N/mm²": ("stress", 1.0, 0.0),
    "N/mm2": ("stress", 1.0, 0.0),
    "kPa": ("stress", 1e-3, 0.0),
    "Pa": ("stress", 1e-6, 0.0),
    "GPa": ("stress", 1e3, 0.0),
    "psi": ("stress", 6.894757293168e-3, 0.0),
    "ksi": ("stress", 6.894757293168, 0.0),
    # area → mm²
    "mm²": ("area", 1.0, 0.0),
    "mm2": ("area", 1.0, 0.0),
    "mm^2": ("area", 1.0, 0.0),
    "m²": ("area", 1e6, 0.0),
    "m2": ("area", 1e6, 0.0),
    "in²": ("area", 645.16, 0.0),
    "in2": ("area", 645.16, 0.0),
    # ratios → %
    "%": ("percent", 1.0, 0.0),
    "": ("ratio", 1.0, 0.0),
    # rates
    "1/s": ("rate", 1.0, 0.0),
    "s-1": ("rate", 1.0, 0.0),
    "s^-1": ("rate", 1.0, 0.0),
    "/s": ("rate", 1.0, 0.0),
    "mm/s": ("speed", 1.0, 0.0),
    "mm/min": ("speed", 1.0 / 60.0, 0.0),
    "µm/s": ("speed", 1e-3, 0.0),
    "um/s": ("speed", 1e-3, 0.0),
    "m/s": ("speed", 1e3, 0.0),
    "in/min": ("speed", 25.4 / 60.0, 0.0),
}

# the native column each mapped quantity becomes, and the quantity its unit must measure
MAPPED_COLUMNS: dict[str, tuple[str, str]] = {
    "time": ("time_s", "time"),
    "force": ("force_N", "force"),
    "crosshead": ("crosshead_mm", "length"),
    "extensometer": ("extensometer_mm", "length"),
    "temperature": ("temperature_C", "temperature"),
}
REQUIRED_MAPPED = ("force", "crosshead")  # time may be derived from the crosshead speed


class UnitError(RecordError):
    """A unit the unit table does not know, or one that measures the wrong quantity."""


def unit_conversion(unit: str, quantity: str | None = None, *, source: str = "<option>", column: str | None = None) -> tuple[float, float]:
    """``(factor, offset)`` turning values in ``unit`` into the native unit of its quantity.

    Raises :class:`UnitError` for an unknown unit or one of another quantity than ``quantity``.
    """
    key = unit.strip()
    entry = UNITS.get(key)
    if entry is None:
        lowered = {k.lower(): v for k, v in UNITS.items()}
        entry = lowered.get(key.lower())
    if entry is None:
        known = sorted({k for k, v in UNITS.items() if quantity is None or v[0] == quantity} - {""})
        raise UnitError(source, f"unknown unit {unit!r} (known{' ' + quantity if quantity else ''} units: {', '.join(known)})", column=column)
    if quantity is not None and entry[0] != quantity:
        raise UnitError(source, f"unit {unit!r} measures {entry[0]}, not {quantity}", column=column)
    return entry[1], entry[2]


def to_native(values, unit: str, quantity: str | None = None, *, source: str = "<option>", column: str | None = None):
    """Convert ``values`` (scalar or array) from ``unit`` to the native unit of ``quantity``."""
    factor, offset = unit_conversion(unit, quantity, source=source, column=column)
    if factor == 1.0 and offset == 0.0:
        return values
    return values * factor + offset


# -- entry point ---------------------------------------------------------------------------


def load_record(path: str | os.PathLike, *, columns: Mapping[str, tuple[str, str | None]] | None = None, meta: Mapping[str, str] | None = None) -> Record:
    """Read a record file of any supported kind; ``meta`` overrides or adds metadata.

    columns: for a plain CSV, which file column is which quantity and in which unit, e.g.
        ``{"force": ("Load", "kN"), "crosshead": ("Extension", "mm"), "time": ("Time", "s")}``
        (keys: time, force, crosshead, extensometer, temperature). A unit of ``None`` takes
        the unit from the file's units row. Ignored (with a warning) for native records and
        INSTRON exports, which describe their own columns.
    Raises :class:`RecordError` (one line naming file, line, column) for anything unreadable.
    """
    path = Path(path)
    _check_readable(path)
    if is_native(path):
        record = read_record(path)
        kind = "native flowcurve record"
    elif _is_instron(path):
        record = read_instron(path)
        kind = "INSTRON export"
    elif columns:
        record = read_mapped_csv(path, columns)
        kind = None
    else:
        raise RecordError(path, "not a flowcurve record and no column mapping given; name the columns, e.g. --column force=Load:kN --column crosshead=Extension:mm --column time=Time:s" + _found_columns_hint(path))
    if columns and kind is not None:
        record.warnings.append(f"the column mapping was ignored: a {kind} names its own columns and units")
    if meta:
        for key, value in meta.items():
            if value is not None:
                record.meta[key] = str(value)
    if "time_s" not in record.data.columns:
        _derive_time(record)
    return record


def _derive_time(record: Record) -> None:
    """A CSV without a time column: time from the crosshead travel at the stated speed."""
    speed = record.positive("crosshead_speed_mm_per_s")
    if speed is None:
        raise RecordError(record.source, "no time column mapped and no crosshead speed to derive it from (give --column time=NAME:UNIT, or the speed as metadata crosshead_speed_mm_per_s)")
    crosshead = record.data["crosshead_mm"].to_numpy(dtype=float)
    record.data.insert(0, "time_s", (crosshead - crosshead[0]) / speed)  # t = Δl / v
    record.warnings.append(f"no time column: time derived from the crosshead travel at {speed:g} mm/s")


def _check_readable(path: Path) -> None:
    if path.is_dir():
        raise RecordError(path, "is a folder, not a record file")
    if not path.exists():
        raise RecordError(path, "no such file")
    try:
        size = path.stat().st_size
    except OSError as exc:  # pragma: no cover - permissions and the like
        raise RecordError(path, f"cannot be read ({exc.strerror})") from None
    if size == 0:
        raise RecordError(path, "the file is empty")


def _head_lines(path: Path, n: int = 200) -> list[str]:
    """The first ``n`` lines of a text file (decoded UTF-8, BOM dropped)."""
    lines = []
    try:
        with open(path, encoding="utf-8-sig", newline="") as fh:
            for _ in range(n):
                line = fh.readline()
                if not line:
                    break
                lines.append(line.rstrip("\r\n"))
    except UnicodeDecodeError:
        raise RecordError(path, "is not UTF-8 text") from None
    except OSError as exc:
        raise RecordError(path, f"cannot be read ({exc.strerror})") from None
    return lines


def _found_columns_hint(path: Path) -> str:
    lines = [line for line in _head_lines(path, 5) if line.strip()]
    if not lines:
        return ""
    delim = _sniff_delimiter(lines[0])
    names = [c.strip() for c in lines[0].split(delim)]
    return f" (the first line holds: {', '.join(names[:12])})"


# -- INSTRON export ------------------------------------------------------------------------

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


def _is_instron(path: Path) -> bool:
    lines = _head_lines(path, 60)
    keyed = sum(1 for line in lines if re.match(r"^[^\t]+:\t", line))
    return keyed >= 3 and any(line.split("\t")[:1] == ["Time"] and "Force" in line.split("\t") for line in lines)


def read_instron(path: str | os.PathLike) -> Record:
    """Read an INSTRON (Bluehill-style) tab-separated export with a ``key:\\tvalue\\tunit`` header."""
    path = Path(path)
    source = str(path)
    lines = _head_lines(path, 200)
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
            meta["specimen.extensometer_gauge_mm"] = l0  # the Displacement column is the extensometer
        elif key == "Test temperature":
            if value.upper() == "RT":
                meta["nominal_temperature_C"] = repr(ROOM_TEMPERATURE_C)
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
        raise RecordError(source, f"missing column(s) {', '.join(missing)} (found: {', '.join(names)})", line=names_idx + 1)
    mapping = {name: (native, quantity, units[names.index(name)]) for name, (native, quantity) in INSTRON_COLUMNS.items()}
    data = _read_columns(path, sep="\t", decimal=".", names=names, first_data_line=names_idx + 2, mapping=mapping)
    return Record(meta=meta, data=data, source=source, warnings=warnings)


def _header_number(value: str, source: str, line: int, key: str) -> float:
    try:
        return float(value.replace(",", "."))
    except ValueError:
        raise RecordError(source, f"'{key}' is not a number: {value!r}", line=line) from None


# -- any CSV through a column mapping ------------------------------------------------------


def _sniff_delimiter(line: str) -> str:
    """Tab, semicolon or comma: whichever splits the column-name row into most cells."""
    counts = {d: line.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] > 0 else ","


def _is_number(cell: str, decimal: str) -> bool:
    cell = cell.strip()
    if decimal == ",":
        cell = cell.replace(",", ".")
    try:
        float(cell)
    except ValueError:
        return False
    return True


def read_mapped_csv(path: str | os.PathLike, columns: Mapping[str, tuple[str, str | None]]) -> Record:
    """Read a CSV whose columns are named by ``columns`` (quantity → (file column, unit))."""
    path = Path(path)
    source = str(path)
    unknown = [q for q in columns if q not in MAPPED_COLUMNS]
    if unknown:
        raise RecordError(source, f"unknown quantity {', '.join(map(repr, unknown))} in the column mapping (use: {', '.join(MAPPED_COLUMNS)})")
    missing_q = [q for q in REQUIRED_MAPPED if q not in columns]
    if missing_q:
        raise RecordError(source, f"the column mapping lacks {', '.join(missing_q)} (give e.g. --column {missing_q[0]}=NAME:UNIT)")
    wanted = {q: (spec[0], spec[1]) for q, spec in columns.items()}
    lines = _head_lines(path, 200)
    if not any(line.strip() for line in lines):
        raise RecordError(source, "the file is empty")
    # the column-name row: the first line that holds every mapped name
    names_idx = None
    delim = ","
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        d = _sniff_delimiter(line)
        cells = [c.strip().strip('"') for c in next(csv.reader([line], delimiter=d))]
        if all(name in cells for name, _ in wanted.values()):
            names_idx, delim, names = i, d, cells
            break
    if names_idx is None:
        # the likeliest names row: the line (of the first 200) split into the most cells
        widest = max((line for line in lines if line.strip()), key=lambda line: line.count(_sniff_delimiter(line)))
        found = [c.strip().strip('"') for c in widest.split(_sniff_delimiter(widest))]
        absent = [name for name, _ in wanted.values() if name not in found]
        raise RecordError(source, f"no column named {', '.join(map(repr, absent))} (columns found: {', '.join(found)})")
    rest = [(j, line) for j, line in enumerate(lines) if j > names_idx and line.strip()]
    if not rest:
        raise RecordError(source, "the file has a column row but no samples (header only)", line=names_idx + 1)
    # decimal comma: a ';' or tab file whose numbers are written 1,25
    decimal = "."
    sample = rest[-1][1] if len(rest) > 1 else rest[0][1]
    if delim != "," and re.search(r"(^|" + re.escape(delim) + r")\s*-?\d+,\d+", sample):
        decimal = ","
    # an optional units row right under the names row
    first_j, first_line = rest[0]
    first_cells = [c.strip().strip('"') for c in first_line.split(delim)]
    mapped_idx = [names.index(name) for name, _ in wanted.values()]
    has_units_row = all(k < len(first_cells) for k in mapped_idx) and not any(_is_number(first_cells[k], decimal) for k in mapped_idx if first_cells[k])
    file_units = {}
    if has_units_row:
        for name, _ in wanted.values():
            file_units[name] = first_cells[names.index(name)].strip("[]() ")
        first_data = first_j + 1
        if len(rest) < 2:
            raise RecordError(source, "the file has column and units rows but no samples (header only)", line=first_j + 1)
    else:
        first_data = first_j
    mapping = {}
    for quantity, (name, unit) in wanted.items():
        native, kind = MAPPED_COLUMNS[quantity]
        declared = file_units.get(name)
        if unit is None or unit == "":
            if not declared:
                raise UnitError(source, f"no unit given for column '{name}' and the file has no units row (give --column {quantity}={name}:UNIT)")
            unit = declared
        elif declared and declared != unit:
            try:
                same = unit_conversion(declared, kind, source=source, column=name) == unit_conversion(unit, kind, source=source, column=name)
            except UnitError:
                same = False
            if not same:
                raise UnitError(source, f"the mapping says {unit!r} but the file's units row says {declared!r}; check units", column=name)
        unit_conversion(unit, kind, source=source, column=name)  # unknown unit → error now
        mapping[name] = (native, kind, unit)
    data = _read_columns(path, sep=delim, decimal=decimal, names=names, first_data_line=first_data, mapping=mapping)
    return Record(meta={"source_format": "csv"}, data=data, source=source)


# -- the fast sample reader shared by both importers ---------------------------------------


def _read_columns(path: Path, *, sep: str, decimal: str, names: list[str], first_data_line: int, mapping: Mapping[str, tuple[str, str, str]]) -> pd.DataFrame:
    """Read the mapped columns with pandas' C engine and convert each to its native unit.

    mapping: file column → (native column, quantity, unit). ``first_data_line`` is 0-based.
    """
    source = str(path)
    usecols = list(mapping)
    try:
        raw = pd.read_csv(
            path,
            sep=sep,
            decimal=decimal,
            header=None,
            names=names,
            usecols=usecols,
            skiprows=first_data_line,
            engine="c",
            dtype=float,
            skip_blank_lines=True,
            encoding="utf-8-sig",
            quotechar='"',
        )
    except (ValueError, pd.errors.ParserError):
        _raise_bad_cell(path, sep, decimal, names, first_data_line, usecols)
        raise  # pragma: no cover - _raise_bad_cell always raises
    if raw.empty:
        raise RecordError(source, "the file has no samples (header only)", line=first_data_line)
    data = pd.DataFrame(index=raw.index)
    order = ["time_s", "force_N", "crosshead_mm", "extensometer_mm", "temperature_C"]
    converted = {}
    for name, (native, quantity, unit) in mapping.items():
        converted[native] = to_native(raw[name].to_numpy(dtype=float), unit, quantity, source=source, column=name)
    for native in sorted(converted, key=lambda c: order.index(c) if c in order else len(order)):
        data[native] = converted[native]
    return data.reset_index(drop=True)


def _raise_bad_cell(path: Path, sep: str, decimal: str, names: list[str], first_data_line: int, usecols: list[str]) -> None:
    """Slow path, only after a failed read: find the first bad cell and raise with its place."""
    source = str(path)
    index = {name: names.index(name) for name in usecols}
    with open(path, encoding="utf-8-sig", newline="") as fh:
        for line_no, line in enumerate(fh, start=1):
            if line_no <= first_data_line or not line.strip():
                continue
            cells = line.rstrip("\r\n").split(sep)
            for name, k in index.items():
                if k >= len(cells):
                    raise RecordError(source, f"{len(cells)} cells, column '{name}' is missing", line=line_no)
                cell = cells[k].strip().strip('"')
                if cell == "":
                    continue
                if not _is_number(cell, decimal) or (decimal == "." and "," in cell):
                    raise RecordError(source, f"not a number: {cell!r}", line=line_no, column=name)
    raise RecordError(source, "the samples cannot be parsed as numbers")


def parse_column_option(text: str) -> tuple[str, tuple[str, str | None]]:
    """``'force=Load:kN'`` → ``('force', ('Load', 'kN'))``; ``'force=Load'`` leaves the unit to the file.

    The unit is split at the last ``:`` so a column name may itself contain colons.
    """
    quantity, sep, rest = text.partition("=")
    quantity = quantity.strip().lower()
    if not sep or not rest.strip():
        raise RecordError("--column", f"{text!r} is not QUANTITY=COLUMN[:UNIT] (e.g. force=Load:kN)")
    if quantity not in MAPPED_COLUMNS:
        raise RecordError("--column", f"unknown quantity {quantity!r} in {text!r} (use: {', '.join(MAPPED_COLUMNS)})")
    name, colon, unit = rest.rpartition(":")
    if not colon:
        return quantity, (rest.strip(), None)
    return quantity, (name.strip(), unit.strip() or None)


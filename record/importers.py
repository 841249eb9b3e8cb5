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
* any other CSV or text export (Instron Bluehill, Zwick testXpert, MTS TestSuite and the
  like) is read through a column mapping ``{"force": ("Load", "kN"), ...}`` or, without one,
  by the column names it recognises (:func:`recognise_quantity`), with the units written in
  the names (``Load [kN]``) or in a units row; an extensometer column in a strain unit
  becomes elongation with the extensometer gauge length Le. Text may be UTF-8 (with or
  without BOM), UTF-16 (Excel's "Unicode text") or Windows-1252, with decimal commas and
  thousands separators.

Units are converted through :data:`UNITS`; a unit it does not know is an error, never a guess.
Crosshead-less records (force and extensometer only) come back without ``crosshead_mm``.
"""

from __future__ import annotations

import codecs
import csv
import io
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

if TYPE_CHECKING:  # pandas is imported where columns are read, so `flowcurve --help` stays fast
    import pandas as pd

import numpy as np

from flowcurve.record.format import MAX_MAGNITUDE, Record, is_native, read_record, shown
from flowcurve.errors import MissingValueError, RecordError

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
    # ratios → % (strain columns: % or a ratio, see strain_factor)
    "%": ("percent", 1.0, 0.0),
    "": ("ratio", 1.0, 0.0),
    "-": ("ratio", 1.0, 0.0),
    "mm/mm": ("ratio", 1.0, 0.0),
    "m/m": ("ratio", 1.0, 0.0),
    "in/in": ("ratio", 1.0, 0.0),
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
REQUIRED_MAPPED = ("force",)  # and a displacement (crosshead or extensometer); time may be derived


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
        raise UnitError(source, f"unknown unit {shown(unit)} (known{' ' + quantity if quantity else ''} units: {', '.join(known)})", column=column)
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

EXTENSOMETER_GAUGE_KEY = "specimen.extensometer_gauge_mm"


def load_record(path: str | os.PathLike, *, columns: Mapping[str, tuple[str, str | None]] | None = None, meta: Mapping[str, str] | None = None) -> Record:
    """Read a record file of any supported kind; ``meta`` overrides or adds metadata.

    columns: for a plain CSV, which file column is which quantity and in which unit, e.g.
        ``{"force": ("Load", "kN"), "crosshead": ("Extension", "mm"), "time": ("Time", "s")}``
        (keys: time, force, crosshead, extensometer, temperature). A unit of ``None`` takes
        the unit from the column's name (``Load [kN]``) or the file's units row. Without a
        mapping, columns whose names are recognisable (:func:`recognise_quantity`) are used.
        Ignored (with a warning) for native records and INSTRON exports, which describe their
        own columns.
    An extensometer column in a strain unit (``%``, ``mm/mm``, ``-``) becomes elongation with
    the extensometer gauge length Le (``specimen.extensometer_gauge_mm``, e.g. from ``meta``).
    Raises :class:`RecordError` (one line naming file, line, column) for anything unreadable.
    """
    path = Path(path)
    _check_readable(path)
    if is_native(path):
        record = read_record(path)
        kind = "native flowcurve record"
    else:
        text = decode_text(path)
        if _is_instron(text.head):
            record = read_instron(path, text=text)
            kind = "INSTRON export"
        else:
            record = read_csv_export(path, columns, text=text)
            kind = None
        record.warnings[:0] = text.warnings
    if columns and kind is not None:
        record.warnings.append(f"the column mapping was ignored: a {kind} names its own columns and units")
    if meta:
        for key, value in meta.items():
            if value is not None:
                record.meta[key] = str(value)
    if STRAIN_COLUMN in record.data.columns:
        _strain_to_elongation(record)
    _check_magnitudes(record)
    for key in [k for k in record.meta if k.startswith(SOURCE_PREFIX)]:
        del record.meta[key]  # where columns and samples stood in the file: for messages only
    if "time_s" not in record.data.columns:
        _derive_time(record)
    return record


def _strain_to_elongation(record: Record) -> None:
    """An extensometer strain column → elongation over the extensometer gauge length Le."""
    label = record.meta.get(STRAIN_LABEL_KEY, STRAIN_COLUMN)
    record.meta[COLUMN_LABEL_PREFIX + "extensometer_mm"] = label
    le = record.meta.get(EXTENSOMETER_GAUGE_KEY)
    if le is None or not le.strip():
        raise MissingValueError(record.source, (EXTENSOMETER_GAUGE_KEY,), what="holds strain, not elongation: the extensometer gauge length Le (ISO 6892-1) is needed", column=label)
    gauge = record.positive(EXTENSOMETER_GAUGE_KEY)
    strain = record.data.pop(STRAIN_COLUMN).to_numpy(dtype=float)
    record.data["extensometer_mm"] = strain * gauge  # ΔLe = e·Le
    record.meta.setdefault("extensometer_source", f"strain column '{label}' × Le {gauge:g} mm")


def _check_magnitudes(record: Record) -> None:
    """Infinite or overflowing samples (1e308, inf) are an error naming the line and column."""
    values = record.data.to_numpy(dtype=float)
    with np.errstate(invalid="ignore"):
        bad = np.abs(values) > MAX_MAGNITUDE  # inf included; NaN (an empty cell) is a missing value
    if not bad.any():
        return
    row, col = (int(v[0]) for v in np.nonzero(bad))
    native = record.data.columns[col]
    first_line = record.meta.get(FIRST_DATA_LINE_KEY)
    message = f"{float(values[row, col])!r} is beyond any measurement (|value| > {MAX_MAGNITUDE:g} {native.rsplit('_', 1)[-1]}): an overflow or a wrong column"
    if first_line is None:  # a native record: events may stand between samples, so count samples
        raise RecordError(record.source, f"sample {row + 1}: {message}", column=native)
    raise RecordError(record.source, message, line=int(first_line) + row, column=record.meta.get(COLUMN_LABEL_PREFIX + native, native))


def _derive_time(record: Record) -> None:
    """A CSV without a time column: time from the crosshead travel at the stated speed."""
    if "crosshead_mm" not in record.data.columns:
        raise RecordError(record.source, "no time column and no crosshead column to derive it from; name the time column: --column time=NAME:UNIT")
    speed = record.positive("crosshead_speed_mm_per_s")
    if speed is None:
        raise RecordError(record.source, "no time column mapped and no crosshead speed to derive it from (give --column time=NAME:UNIT, or the speed with --speed MM_PER_S, metadata crosshead_speed_mm_per_s)")
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


# -- text as other labs' software writes it ------------------------------------------------


@dataclass
class Text:
    """A decoded text file: the whole text, its first lines and what decoding had to say."""

    text: str
    encoding: str
    warnings: list[str] = field(default_factory=list)
    head: list[str] = field(default_factory=list)  # the first HEAD_LINES lines, without line ends

    def lines(self):
        """Every line without its line end (1-based numbering is index + 1)."""
        return self.text.splitlines()


HEAD_LINES = 200


def decode_text(path: str | os.PathLike) -> Text:
    """Read a text file as labs' software writes it.

    UTF-8 with or without a BOM; UTF-16 with a BOM (Excel's "Unicode text") or without one
    (recognised by its zero bytes); otherwise Windows-1252 (an "ANSI" export), with a warning.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise RecordError(path, f"cannot be read ({exc.strerror})") from None
    warnings: list[str] = []
    if raw.startswith(codecs.BOM_UTF8):
        encoding, raw = "utf-8", raw[len(codecs.BOM_UTF8):]
    elif raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        encoding = "utf-16"
    elif len(raw) >= 4 and raw[1:200:2].count(0) > 0.9 * len(raw[1:200:2]):
        encoding = "utf-16-le"
    elif len(raw) >= 4 and raw[0:200:2].count(0) > 0.9 * len(raw[0:200:2]):
        encoding = "utf-16-be"
    else:
        encoding = "utf-8"
    try:
        text = raw.decode(encoding)
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        if encoding != "utf-8":
            raise RecordError(path, f"is not valid {encoding.upper()} text", line=line) from None
        try:
            text = raw.decode("cp1252")
        except UnicodeDecodeError:
            raise RecordError(path, "is neither UTF-8, UTF-16 nor Windows-1252 text", line=line) from None
        encoding = "cp1252"
        warnings.append(f"not UTF-8 (line {line}): read as Windows-1252 ('ANSI') text")
    if "\x00" in text:
        raise RecordError(path, f"holds NUL characters after decoding as {encoding}: a binary file, not text")
    if "\r" in text:  # CR LF (Windows) and CR alone (old Mac-style exports) end lines as LF does
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    head = text.split("\n", HEAD_LINES)[:HEAD_LINES]
    return Text(text=text, encoding=encoding, warnings=warnings, head=[line.rstrip("\r") for line in head])


def _found_columns_hint(lines: list[str]) -> str:
    lines = [line for line in lines if line.strip()]
    if not lines:
        return ""
    widest = max(lines[:50], key=lambda line: line.count(sniff_delimiter(line)))
    names = split_cells(widest, sniff_delimiter(widest))
    return f" (the widest of the first lines holds: {', '.join(names[:12])})"


def split_cells(line: str, delim: str) -> list[str]:
    """The cells of one line, quotes removed (as Bluehill writes them) and trimmed; a line the csv
    module refuses (a cell over its 131 072-character limit) is split at every delimiter."""
    if not line:
        return []
    try:
        cells = next(csv.reader([line], delimiter=delim))
    except csv.Error:
        cells = line.split(delim)
    return [c.strip().strip('"').strip() for c in cells]


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


# -- any CSV: columns recognised by name, or named through a mapping -----------------------

# metadata keys the CSV reader leaves for load_record (removed before the record is returned)
SOURCE_PREFIX = "source."
FIRST_DATA_LINE_KEY = SOURCE_PREFIX + "first_data_line"
COLUMN_LABEL_PREFIX = SOURCE_PREFIX + "column."
STRAIN_COLUMN = "extensometer_strain"  # an extensometer column in a strain unit, as a ratio
STRAIN_LABEL_KEY = COLUMN_LABEL_PREFIX + STRAIN_COLUMN

UNCERTAIN = "uncertain"
# quantity → pattern on a lower-cased column name (its unit removed); tried in this order,
# the first match wins. "ignore" catches derived columns (stress, true strain, rates) and
# crosshead-based strain ("Tensile strain (Extension)", testXpert's "Nominal strain").
NAME_PATTERNS: tuple[tuple[str, str], ...] = (
    ("ignore", r"true|wahr|stress|spannung|rate|speed|geschwindigkeit|cycle|zyklus|energy|energie|work|arbeit|count|nominal|nominell"),
    ("ignore", r"(strain|dehnung).*(extension|crosshead|travel|grip|traverse|machine)|width|breite"),
    ("uncertain", r"standardweg|standard travel"),  # testXpert: the extensometer if fitted, else the crosshead
    ("extensometer", r"extensometer|strain|dehnung"),
    ("temperature", r"temp"),
    ("time", r"time|zeit"),
    ("force", r"load|force|kraft"),
    ("crosshead", r"extension|crosshead|displacement|position|travel|stroke|traverse|grip|weg\b"),
)


def recognise_quantity(name: str) -> str | None:
    """The quantity a column name stands for (``'Load'`` → ``'force'``), ``None`` if unknown.

    ``name`` is without its unit. Covers the English names of Instron Bluehill, Zwick
    testXpert and MTS TestSuite exports and the German ones of testXpert. An "extensometer"
    column holds elongation or strain: its unit decides which.
    """
    quantity = recognise_column(name)
    return None if quantity == UNCERTAIN else quantity


def recognise_column(name: str) -> str | None:
    """Like :func:`recognise_quantity`, but ``'uncertain'`` for a channel that may be either
    displacement (testXpert's "Standardweg"/"Standard travel")."""
    lowered = name.strip().lower()
    for quantity, pattern in NAME_PATTERNS:
        if re.search(pattern, lowered):
            return None if quantity == "ignore" else quantity
    return None


_UNIT_IN_NAME = re.compile(r"^(?P<name>.*?)\s*(?:\((?P<paren>[^()]*)\)|\[(?P<square>[^\[\]]*)\])\s*$")


def split_name_unit(cell: str) -> tuple[str, str | None]:
    """``'Load [kN]'`` → ``('Load', 'kN')``, ``'Time (s)'`` → ``('Time', 's')``.

    A name's last bracket is its unit when in square brackets or when the unit table knows it;
    otherwise (``'Tensile strain (Strain 1)'``) it is part of the name.
    """
    m = _UNIT_IN_NAME.match(cell.strip())
    if not m or not m.group("name"):
        return cell.strip(), None
    if m.group("square") is not None:
        return m.group("name"), m.group("square").strip()
    unit = m.group("paren").strip()
    return (m.group("name"), unit) if _unit_entry(unit) is not None and unit else (cell.strip(), None)


def _unit_entry(unit: str) -> tuple[str, float, float] | None:
    key = unit.strip()
    entry = UNITS.get(key)
    if entry is None:
        entry = {k.lower(): v for k, v in UNITS.items()}.get(key.lower())
    return entry


def strain_factor(unit: str, *, source: str, column: str) -> float:
    """Factor turning a strain in ``unit`` (``%``, ``mm/mm``, ``-``) into a ratio."""
    entry = _unit_entry(unit) if unit.strip() else None
    if entry is None or entry[0] not in ("percent", "ratio"):
        raise UnitError(source, f"unit {unit!r} is neither a length nor a strain unit (strain: %, mm/mm, in/in, -)", column=column)
    return entry[1] * (0.01 if entry[0] == "percent" else 1.0)


@dataclass(frozen=True)
class Column:
    """One file column to read: the native column it becomes, its quantity, unit and file name."""

    native: str
    quantity: str  # a quantity of the unit table, or "strain" (→ a ratio)
    unit: str
    label: str


def sniff_delimiter(line: str) -> str:
    """Tab, semicolon or comma: whichever splits the column-name row into most cells."""
    counts = {d: line.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] > 0 else ","


def is_number(cell: str, decimal: str, thousands: str | None = None) -> bool:
    cell = cell.strip()
    if thousands:
        cell = cell.replace(thousands, "")
    if decimal == ",":
        cell = cell.replace(",", ".")
    try:
        float(cell)
    except ValueError:
        return False
    return True


# numbers with thousands separators, as Bluehill writes them quoted ("1,004.80328") or a
# German export writes them (1.004,80328)
_THOUSANDS_COMMA = re.compile(r'(?:^|[,;\t"])-?\d{1,3}(?:,\d{3})+\.\d*(?=$|[,;\t"])', re.MULTILINE)
_THOUSANDS_POINT = re.compile(r'(?:^|[;\t"])-?\d{1,3}(?:\.\d{3})+,\d*(?=$|[;\t"])', re.MULTILINE)


def number_style(text: str, delim: str, sample: str) -> tuple[str, str | None]:
    """(decimal mark, thousands separator) of the numbers in a file with this delimiter.

    Thousands separators are taken only where the file shows both marks in one number
    ("1,004.8", "1.004,8"); a ';' or tab file whose numbers are written 1,25 has a decimal comma.
    """
    both = "." in text and "," in text  # a cheap test first: the searches scan the whole text
    if both and (delim != "," or '"' in text) and _THOUSANDS_COMMA.search(text):
        return ".", ","
    if both and delim != "," and _THOUSANDS_POINT.search(text):
        return ",", "."
    if delim != "," and re.search(r"(^|" + re.escape(delim) + r")\s*\"?-?\d+,\d+", sample):
        return ",", None
    return ".", None


def read_csv_export(path: str | os.PathLike, columns: Mapping[str, tuple[str, str | None]] | None = None, *, text: Text | None = None) -> Record:
    """Read a lab's CSV/text export: columns named by ``columns`` or recognised by name.

    The names row is the first line holding every mapped name (or, without a mapping, the
    first line with a recognisable force column and a crosshead or extensometer column);
    a preamble above it is skipped. Units come from the mapping, the names (``Load [kN]``) or
    a units row under the names (``kN`` or ``(kN)``); they must agree, and one is needed.
    """
    path = Path(path)
    source = str(path)
    text = text or decode_text(path)
    lines = text.head
    if not any(line.strip() for line in lines):
        raise RecordError(source, "the file is empty")
    warnings: list[str] = []
    if columns:
        names_idx, delim, cells, chosen = _mapped_row(source, lines, columns)
    else:
        names_idx, delim, cells, chosen = _recognised_row(source, lines, warnings)
    rest = [(j, line) for j, line in enumerate(lines) if j > names_idx and line.strip()]
    if not rest:
        raise RecordError(source, "the file has a column row but no samples (header only)", line=names_idx + 1)
    decimal, thousands = number_style(text.text, delim, rest[-1][1] if len(rest) > 1 else rest[0][1])
    # an optional units row right under the names row: text (not numbers) under the chosen columns
    first_j, first_line = rest[0]
    first_cells = split_cells(first_line, delim)
    under = [first_cells[k] if k < len(first_cells) else "" for k, _, _ in chosen.values()]
    has_units_row = any(under) and not any(is_number(c, decimal) for c in under if c)
    row_units: dict[int, str] = {}
    if has_units_row:
        row_units = {k: first_cells[k].strip("[]() ") for k, _, _ in chosen.values() if k < len(first_cells)}
        first_data = first_j + 1
        if len(rest) < 2:
            raise RecordError(source, "the file has column and units rows but no samples (header only)", line=first_j + 1)
    else:
        first_data = first_j
    mapping: dict[int, Column] = {}
    for quantity, (k, given_unit, name_unit) in chosen.items():
        label = cells[k]
        unit = _resolve_unit(source, quantity, label, given_unit, name_unit, row_units.get(k) or None, units_line=first_j + 1 if has_units_row else None)
        native, kind = MAPPED_COLUMNS[quantity]
        if quantity == "extensometer" and _unit_entry(unit) is not None and _unit_entry(unit)[0] != "length":
            strain_factor(unit, source=source, column=label)  # not a strain unit either → error now
            native, kind = STRAIN_COLUMN, "strain"
        else:
            unit_conversion(unit, kind, source=source, column=label)  # unknown unit → error now
        mapping[k] = Column(native, kind, unit, label)
    data = _read_columns(source, text, sep=delim, decimal=decimal, thousands=thousands, first_data_line=first_data, mapping=mapping)
    meta = {"source_format": "csv", FIRST_DATA_LINE_KEY: str(first_data + 1)}
    meta.update({f"{COLUMN_LABEL_PREFIX}{c.native}": c.label for c in mapping.values()})
    return Record(meta=meta, data=data, source=source, warnings=warnings)


def _resolve_unit(source: str, quantity: str, label: str, given: str | None, in_name: str | None, in_row: str | None, *, units_line: int | None) -> str:
    """The one unit of a column from the mapping, its name and the units row; they must agree."""
    declared = in_name or in_row
    if in_name and in_row and not _same_unit(in_name, in_row):
        raise UnitError(source, f"the name says {in_name!r} but the units row says {in_row!r}; check units", line=units_line, column=label)
    if not given:
        if not declared:
            raise UnitError(source, f"no unit: neither in the column name (e.g. '{label} [UNIT]') nor in a units row under it; give it: --column {quantity}={label}:UNIT", column=label)
        return declared
    if declared and not _same_unit(given, declared):
        raise UnitError(source, f"the mapping says {given!r} but the file's {'units row' if in_row and not in_name else 'column name'} says {declared!r}; check units", column=label)
    return given


def _same_unit(a: str, b: str) -> bool:
    ea, eb = _unit_entry(a), _unit_entry(b)
    return a.strip() == b.strip() or (ea is not None and ea == eb)


def _mapped_row(source: str, lines: list[str], columns: Mapping[str, tuple[str, str | None]]):
    """The names row holding every mapped column; → (index, delimiter, cells, chosen)."""
    unknown = [q for q in columns if q not in MAPPED_COLUMNS]
    if unknown:
        raise RecordError(source, f"unknown quantity {', '.join(map(repr, unknown))} in the column mapping (use: {', '.join(MAPPED_COLUMNS)})")
    missing_q = [q for q in REQUIRED_MAPPED if q not in columns]
    if missing_q or not any(q in columns for q in DISPLACEMENTS):
        lacking = " and ".join([*missing_q, *([] if any(q in columns for q in DISPLACEMENTS) else ["crosshead or extensometer"])])
        raise RecordError(source, f"the column mapping lacks {lacking} (give e.g. --column {(missing_q or ['crosshead'])[0]}=NAME:UNIT)")
    for i, delim, cells, split in _candidate_rows(lines):
        chosen = {}
        for quantity, (name, unit) in columns.items():
            k = _find_cell(name, cells, split)
            if k is None:
                break
            chosen[quantity] = (k, unit, split[k][1])
        else:
            return i, delim, cells, chosen
    widest = max((line for line in lines[:50] if line.strip()), key=lambda line: line.count(sniff_delimiter(line)))
    found = split_cells(widest, sniff_delimiter(widest))
    absent = [name for name, _ in columns.values() if _find_cell(name, found, [split_name_unit(c) for c in found]) is None]
    raise RecordError(source, f"no column named {', '.join(map(repr, absent))} (columns found: {', '.join(found)})")


def _candidate_rows(lines: list[str]):
    """Each non-blank line as a possible names row: (index, delimiter, cells, (name, unit) per cell)."""
    for i, line in enumerate(lines):
        if line.strip():
            delim = sniff_delimiter(line)
            cells = split_cells(line, delim)
            yield i, delim, cells, [split_name_unit(c) for c in cells]


def _find_cell(name: str, cells: list[str], split: list[tuple[str, str | None]]) -> int | None:
    """Index of the cell named ``name``, written with or without its unit (``Load``, ``Load [kN]``)."""
    if name in cells:
        return cells.index(name)
    bare = [s[0] for s in split]
    return bare.index(name) if name in bare else None


DISPLACEMENTS = ("crosshead", "extensometer")


def _recognised_row(source: str, lines: list[str], warnings: list[str]):
    """The first line whose names show a force and a displacement; → (index, delimiter, cells, chosen)."""
    for i, delim, cells, split in _candidate_rows(lines):
        quantities = [recognise_column(name) for name, _ in split]
        if "force" not in quantities or not any(q in quantities for q in (*DISPLACEMENTS, UNCERTAIN)):
            continue
        uncertain = [cells[k] for k, q in enumerate(quantities) if q == UNCERTAIN]
        if uncertain and not any(q in quantities for q in DISPLACEMENTS):
            raise RecordError(source, f"column '{uncertain[0]}' is the extensometer when one is fitted, else the crosshead: say which, naming the columns: --column extensometer={uncertain[0]}:UNIT (or crosshead=...) --column force=NAME:UNIT", line=i + 1)
        warnings += [f"column '{name}' left aside: it is the extensometer when one is fitted, else the crosshead (to use it: --column extensometer={name}:UNIT ...)" for name in uncertain]
        chosen = {}
        for quantity in MAPPED_COLUMNS:
            hits = [k for k, q in enumerate(quantities) if q == quantity]
            if len(hits) > 1:
                listed = ", ".join(f"'{cells[k]}'" for k in hits)
                raise RecordError(source, f"columns {listed} all look like the {quantity}; choose one: --column {quantity}=NAME[:UNIT] (and name the others you need)", line=i + 1)
            if hits:
                chosen[quantity] = (hits[0], None, split[hits[0]][1])
        return i, delim, cells, chosen
    raise RecordError(source, "not a flowcurve record, and no column row I recognise (a force column with a crosshead or extensometer column); name the columns, e.g. --column force=Load:kN --column crosshead=Extension:mm --column time=Time:s" + _found_columns_hint(lines))


# -- the fast sample reader shared by both importers ---------------------------------------


def _read_columns(source: str, text: Text, *, sep: str, decimal: str, first_data_line: int, mapping: Mapping[int, Column], thousands: str | None = None) -> pd.DataFrame:
    """Read the chosen columns with pandas' C engine and convert each to its native unit.

    mapping: 0-based file column index → :class:`Column`. ``first_data_line`` is 0-based.
    """
    import pandas as pd

    usecols = sorted(mapping)
    try:
        raw = pd.read_csv(
            io.StringIO(text.text),
            sep=sep,
            decimal=decimal,
            thousands=thousands,
            header=None,
            usecols=usecols,
            skiprows=first_data_line,
            engine="c",
            dtype=float,
            skip_blank_lines=True,
            quotechar='"',
        )
    except (ValueError, pd.errors.ParserError):
        _raise_bad_cell(source, text, sep, decimal, thousands, first_data_line, mapping)
        raise  # pragma: no cover - _raise_bad_cell always raises
    if raw.empty:
        raise RecordError(source, "the file has no samples (header only)", line=first_data_line)
    data = pd.DataFrame(index=raw.index)
    order = ["time_s", "force_N", "crosshead_mm", "extensometer_mm", STRAIN_COLUMN, "temperature_C"]
    converted = {}
    for k, col in mapping.items():
        values = raw[k].to_numpy(dtype=float)
        if col.quantity == "strain":
            converted[col.native] = values * strain_factor(col.unit, source=source, column=col.label)
        else:
            with np.errstate(over="ignore"):  # 1e308 kN → inf N, reported by _check_magnitudes
                converted[col.native] = to_native(values, col.unit, col.quantity, source=source, column=col.label)
    for native in sorted(converted, key=lambda c: order.index(c) if c in order else len(order)):
        data[native] = converted[native]
    return data.reset_index(drop=True)


def _raise_bad_cell(source: str, text: Text, sep: str, decimal: str, thousands: str | None, first_data_line: int, mapping: Mapping[int, Column]) -> None:
    """Slow path, only after a failed read: find the first bad cell and raise with its place."""
    for line_no, line in enumerate(text.lines(), start=1):
        if line_no <= first_data_line or not line.strip():
            continue
        cells = split_cells(line, sep)
        for k, col in mapping.items():
            if k >= len(cells):
                raise RecordError(source, f"{len(cells)} cells, column '{col.label}' is missing", line=line_no)
            cell = cells[k]
            if cell == "":
                continue
            if not is_number(cell, decimal, thousands) or (decimal == "." and not thousands and "," in cell):
                raise RecordError(source, f"not a number: {shown(cell)}", line=line_no, column=col.label)
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


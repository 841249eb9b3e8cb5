"""Text and units as other labs' software writes them: the unit table (:data:`UNITS`) and its
conversions, decoding (UTF-8, UTF-16, Windows-1252), cells, delimiters, decimal and thousands
separators, units in column names, and the keys that say where a column stood in the file."""

from __future__ import annotations

import codecs
import csv
import os
import re
from dataclasses import dataclass, field
from pathlib import Path



from flowcurve.record.format import shown
from flowcurve.errors import RecordError


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


# metadata keys the CSV reader leaves for load_record (removed before the record is returned)
SOURCE_PREFIX = "source."
FIRST_DATA_LINE_KEY = SOURCE_PREFIX + "first_data_line"
COLUMN_LABEL_PREFIX = SOURCE_PREFIX + "column."
STRAIN_COLUMN = "extensometer_strain"  # an extensometer column in a strain unit, as a ratio
STRAIN_LABEL_KEY = COLUMN_LABEL_PREFIX + STRAIN_COLUMN
EXTENSOMETER_GAUGE_KEY = "specimen.extensometer_gauge_mm"


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


def sniff_delimiter(line: str) -> str:
    """Tab, semicolon or comma: whichever splits the column-name row into most cells."""
    counts = {d: line.count(d) for d in ("\t", ";", ",")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] > 0 else ","


def is_number(cell: str, decimal: str, thousands: str | None = None) -> bool:
    """Whether ``cell`` reads as a number with this ``decimal`` and ``thousands`` separator."""
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

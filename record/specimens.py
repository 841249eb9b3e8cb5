"""Per-specimen dimensions for a multi-file run: a table with one row per record file.

``flowcurve identify *.csv --specimens specimens.csv`` reads a table such as::

    file;d0 (mm);l0 (mm);le (mm);lu (mm);dk (mm)
    T600-01.csv;6,01;30;25;36,2;3,9
    T600-02.csv;5,98;30;25;35,8;4,0

written as labs keep it (comma, semicolon or tab separated, decimal comma with ``;`` or tab,
UTF-8, UTF-16 or Windows-1252 as :func:`flowcurve.record.importers_text.decode_text` reads them).
Every dimension column carries its unit: in the name (``d0 (mm)``, ``d0 [in]``, ``d0_mm``)
or in a units row right under the names. An empty cell gives no value (the record's header
or an option may give it). The ``file`` column names the record by path, file name or stem.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from flowcurve.errors import RecordError
from flowcurve.record.format import MAX_MAGNITUDE
from flowcurve.record.importers_text import UnitError, is_number, sniff_delimiter, split_cells, decode_text, split_name_unit, to_native

# table column (lower case) → (metadata key, quantity of its unit); quantity None → text
TABLE_COLUMNS: dict[str, tuple[str, str | None]] = {
    "d0": ("specimen.d0_mm", "length"),
    "l0": ("specimen.l0_mm", "length"),
    "lc": ("specimen.parallel_length_mm", "length"),  # parallel length (tension): what the crosshead stretches
    "h0": ("specimen.h0_mm", "length"),
    "le": ("specimen.extensometer_gauge_mm", "length"),
    "s0": ("specimen.s0_mm2", "area"),
    "lu": ("post.lu_mm", "length"),
    "dk": ("post.dk_mm", "length"),  # smallest diameter at the fracture
    "du": ("post.du_mm", "length"),  # diameter in the uniform part after the test
    "sk": ("post.sk_mm2", "area"),
    "neck_radius": ("post.neck_radius_mm", "length"),
    "hk": ("post.hk_mm", "length"),
    "dmax": ("post.dmax_mm", "length"),
    "smax": ("post.smax_mm2", "area"),
    "dface": ("post.dface_mm", "length"),
    "speed": ("crosshead_speed_mm_per_s", "speed"),
    "temperature": ("nominal_temperature_C", "temperature"),
    "test": ("test", None),
    "material": ("material", None),
    "id": ("specimen.id", None),
}
FILE_COLUMN = "file"
# a unit written into the name the project's way: d0_mm, s0_mm2
_SUFFIX_UNIT = re.compile(r"^(?P<name>.+?)_(?P<unit>mm2|mm|mm_per_s|C)$")
_SUFFIX_UNITS = {"mm2": "mm²", "mm": "mm", "mm_per_s": "mm/s", "C": "°C"}


@dataclass
class SpecimenRow:
    """One row of the table: the file it names, its line and the metadata it gives."""

    file: str
    line: int
    meta: dict[str, str]


@dataclass
class SpecimenTable:
    """The rows of a specimens table, looked up by record path."""

    source: str
    rows: list[SpecimenRow]
    columns: dict[str, str]  # metadata key → the table's column name, for messages

    def row_for(self, record_path: str | os.PathLike) -> SpecimenRow:
        """The one row naming ``record_path`` (by path, file name or stem); an error otherwise."""
        path = Path(record_path)
        hits = [r for r in self.rows if _names(r.file, path)]
        if not hits:
            listed = ", ".join(r.file for r in self.rows[:8]) + (", …" if len(self.rows) > 8 else "")
            raise RecordError(self.source, f"no row for the record '{record_path}' in column '{FILE_COLUMN}' (it holds: {listed})")
        if len(hits) > 1:
            lines = ", ".join(str(r.line) for r in hits)
            raise RecordError(self.source, f"lines {lines} all name the record '{record_path}'; keep one", column=FILE_COLUMN)
        return hits[0]

    def unused(self, record_paths) -> list[SpecimenRow]:
        """Rows that name none of ``record_paths`` (a typo in the table, or a record not given)."""
        paths = [Path(p) for p in record_paths]
        return [r for r in self.rows if not any(_names(r.file, p) for p in paths)]


def _names(cell: str, path: Path) -> bool:
    """Does a table's ``file`` cell name this record: same path, file name or stem?"""
    named = Path(cell.replace("\\", "/"))
    if named == path or (named.is_absolute() or len(named.parts) > 1) and _same_file(named, path):
        return True
    return len(named.parts) == 1 and cell in (path.name, path.stem)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:  # pragma: no cover - unresolvable paths name nothing
        return False


def read_specimen_table(path: str | os.PathLike) -> SpecimenTable:
    """Read a specimens table. Raises :class:`RecordError` naming the table, line and column."""
    path = Path(path)
    source = str(path)
    if path.is_dir():
        raise RecordError(source, "is a folder, not a specimens table")
    if not path.exists():
        raise RecordError(source, "no such file (the --specimens table)")
    lines = decode_text(path).lines()
    numbered = [(i + 1, line) for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise RecordError(source, "the specimens table is empty")
    names_line, header = numbered[0]
    delim = sniff_delimiter(header)
    names = split_cells(header, delim)
    body = numbered[1:]
    decimal = "," if delim != "," and any(re.search(r"\d,\d", line) for _, line in body) else "."
    units_row = None
    if body:
        cells = split_cells(body[0][1], delim)
        dims = [k for k, n in enumerate(names) if _column_key(n)[0] in TABLE_COLUMNS and TABLE_COLUMNS[_column_key(n)[0]][1]]
        if dims and all(k >= len(cells) or not is_number(cells[k], decimal) for k in dims) and any(k < len(cells) and cells[k] for k in dims):
            units_row, body = cells, body[1:]
    if FILE_COLUMN not in [n.lower() for n in names]:
        raise RecordError(source, f"no column '{FILE_COLUMN}' naming the record of each row (columns: {', '.join(names)})", line=names_line)
    spec, columns, file_k = _column_specs(names, units_row, source, names_line)
    rows = []
    seen: dict[str, int] = {}
    for line_no, line in body:
        cells = split_cells(line, delim)
        file = cells[file_k] if file_k < len(cells) else ""
        if not file:
            raise RecordError(source, "the row names no record file", line=line_no, column=names[file_k])
        if file in seen:
            raise RecordError(source, f"'{file}' is named twice (also on line {seen[file]})", line=line_no, column=names[file_k])
        seen[file] = line_no
        meta = _row_meta(cells, spec, names, decimal, source, line_no)
        rows.append(SpecimenRow(file=file, line=line_no, meta=meta))
    if not rows:
        raise RecordError(source, "the specimens table has names but no rows", line=names_line)
    return SpecimenTable(source=source, rows=rows, columns=columns)


def _column_specs(names: list[str], units_row: list[str] | None, source: str, names_line: int):
    """Each column's (metadata key, quantity, unit) by index, metadata key → column name, and the
    index of the file column; a unit from the name or the units row, checked against the table."""
    spec: dict[int, tuple[str, str, str | None]] = {}  # index → (metadata key, quantity, unit)
    columns: dict[str, str] = {}
    file_k = None
    for k, name in enumerate(names):
        key, unit = _column_key(name)
        if key == FILE_COLUMN:
            file_k = k
            continue
        if key not in TABLE_COLUMNS:
            raise RecordError(source, f"unknown column (known: {FILE_COLUMN}, {', '.join(TABLE_COLUMNS)})", line=names_line, column=name)
        meta_key, quantity = TABLE_COLUMNS[key]
        if meta_key in columns:
            raise RecordError(source, f"two columns give '{key}' ('{columns[meta_key]}' and '{name}')", line=names_line, column=name)
        columns[meta_key] = name
        if quantity is not None:
            in_row = units_row[k].strip("[]() ") if units_row is not None and k < len(units_row) and units_row[k] else None
            if unit and in_row and unit != in_row:
                raise UnitError(source, f"the name says {unit!r} but the units row says {in_row!r}; check units", line=names_line + 1, column=name)
            unit = unit or in_row
            if not unit:
                raise UnitError(source, f"no unit: write it in the name ('{key} (mm)' or '{key}_mm') or in a units row under the names", line=names_line, column=name)
            to_native(1.0, unit, quantity, source=source, column=name)  # unknown or wrong unit → error now
        spec[k] = (meta_key, quantity, unit)
    return spec, columns, file_k


def _row_meta(cells: list[str], spec: dict, names: list[str], decimal: str, source: str, line_no: int) -> dict[str, str]:
    """One row's metadata: text as written, numbers converted to the native unit."""
    meta = {}
    for k, (meta_key, quantity, unit) in spec.items():
        cell = cells[k] if k < len(cells) else ""
        if not cell:
            continue
        if quantity is None:
            meta[meta_key] = cell
            continue
        value = _table_number(cell, decimal, source, line_no, names[k], positive=quantity != "temperature")
        meta[meta_key] = repr(float(to_native(value, unit, quantity, source=source, column=names[k])))
    return meta


def _column_key(name: str) -> tuple[str, str | None]:
    """``'d0 (mm)'`` → ``('d0', 'mm')``, ``'d0_mm'`` → ``('d0', 'mm')``, ``'File'`` → ``('file', None)``."""
    bare, unit = split_name_unit(name)
    bare = bare.strip()
    m = _SUFFIX_UNIT.match(bare)
    if unit is None and m and m.group("name").lower() in TABLE_COLUMNS:
        return m.group("name").lower(), _SUFFIX_UNITS[m.group("unit")]
    return bare.lower(), unit


def _table_number(cell: str, decimal: str, source: str, line: int, column: str, *, positive: bool = True) -> float:
    """A finite number, not an overflow, and > 0 when ``positive`` (dimensions, speeds)."""
    text = cell.replace(",", ".") if decimal == "," else cell
    try:
        value = float(text)
    except ValueError:
        raise RecordError(source, f"not a number: {cell!r}", line=line, column=column) from None
    if not abs(value) < MAX_MAGNITUDE or (positive and value <= 0.0):
        raise RecordError(source, f"{cell!r} is not a measurement (it must be finite{' and > 0' if positive else ''})", line=line, column=column)
    return value

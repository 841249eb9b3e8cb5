"""Any CSV or text export (Instron Bluehill, Zwick testXpert, MTS TestSuite and the like): columns
mapped through ``{"force": ("Load", "kN"), ...}`` or recognised by their names
(:func:`recognise_quantity`), units from the names or a units row, and the fast sample reader."""

from __future__ import annotations

import io
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

if TYPE_CHECKING:  # pandas is imported where columns are read, so `flowcurve --help` stays fast
    import pandas as pd

import numpy as np

from flowcurve.record.format import Record, shown
from flowcurve.errors import RecordError
from flowcurve.record.importers_text import COLUMN_LABEL_PREFIX, FIRST_DATA_LINE_KEY, MAPPED_COLUMNS, REQUIRED_MAPPED, STRAIN_COLUMN, Text, UnitError, _found_columns_hint, _unit_entry, decode_text, is_number, number_style, sniff_delimiter, split_cells, split_name_unit, strain_factor, to_native, unit_conversion


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


@dataclass(frozen=True)
class Column:
    """One file column to read: the native column it becomes, its quantity, unit and file name."""

    native: str
    quantity: str  # a quantity of the unit table, or "strain" (→ a ratio)
    unit: str
    label: str


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

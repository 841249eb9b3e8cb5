"""The adhesiometer test table (``flowcurve-adhesion``, version 1): one row per test.

A rotating-sphere adhesiometer test (docs/methods.md §6, seed 004 section 3.2) gives three
numbers: the normal force N_z, the moment M_z resisting the slow rotation of the sphere, and
the radius r of the imprint measured afterwards. A series of tests is one UTF-8 CSV::

    # flowcurve-adhesion: 1
    # material: steel 45
    # sphere.diameter_mm: 8.0
    # sphere.Rp_um: 0.20
    # sphere.tm: 0.50
    test_id,normal_force_N,moment_N_m,imprint_radius_mm,temperature_C,trace_file
    A1,500.0,0.0512,0.412,20.0,traces/A1.csv
    ...

* ``# key: value`` header lines (optional) hold what is common to the series; the sphere
  keys may instead be per-test columns (``sphere_diameter_mm``, ``sphere_Rp_um``,
  ``sphere_tm``), a cell overriding the header.
* Required columns: ``normal_force_N``, ``moment_N_m``, ``imprint_radius_mm``,
  ``temperature_C``. Optional: ``test_id``, the sphere columns, ``flow_stress_MPa`` (the
  surface flow stress σ_S of that test when it is known, e.g. from a tension test at that
  temperature — the refined fit then does not estimate it for that test, seed 3.2.3) and
  ``trace_file`` (a CSV ``time_s,moment_N_m`` of the test's M_z(t), relative to the table).
  A test whose ``moment_N_m`` cell is empty takes M_z as the mean of the second half of its
  trace (the steady sliding part).
* Any other CSV is read through the same ``--column QUANTITY=COLUMN:UNIT`` mapping as the
  other records (:mod:`flowcurve.record.importers`), units converted through its unit table;
  a moment unit is a force unit times a length unit (``N*m``, ``N*mm``, ``kN*m``, ``lbf*in``).

Bad rows (r ≤ 0, N_z ≤ 0, M_z < 0, a missing value, a cell that is not a number) raise a
one-line :class:`~flowcurve.errors.RecordError` naming the file, the line and the column.
"""

from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

if TYPE_CHECKING:  # pandas is imported where tables are read, so `flowcurve --help` stays fast
    import pandas as pd

import numpy as np

from flowcurve.errors import RecordError
from flowcurve.record.format import parse_header_line
from flowcurve.record.importers import parse_column_option
from flowcurve.record.importers_text import (
    UnitError,
    _check_readable,
    _found_columns_hint,
    decode_text,
    is_number,
    sniff_delimiter,
    unit_conversion,
)

FORMAT_NAME = "flowcurve-adhesion"
FORMAT_VERSION = 1

# mapped quantity → (native column, quantity its unit measures, native unit for the option help)
ADHESION_COLUMNS: dict[str, tuple[str, str, str]] = {
    "normal_force": ("normal_force_N", "force", "N"),
    "moment": ("moment_N_m", "moment", "N*m"),
    "imprint_radius": ("imprint_radius_mm", "length", "mm"),
    "temperature": ("temperature_C", "temperature", "C"),
    "sphere_diameter": ("sphere_diameter_mm", "length", "mm"),
    "sphere_rp": ("sphere_Rp_um", "length", "um"),
    "sphere_tm": ("sphere_tm", "ratio", ""),
    "flow_stress": ("flow_stress_MPa", "stress", "MPa"),
    "test_id": ("test_id", "text", ""),
    "trace_file": ("trace_file", "text", ""),
}
REQUIRED = ("normal_force", "moment", "imprint_radius", "temperature")
NUMERIC = tuple(q for q, (_, kind, _) in ADHESION_COLUMNS.items() if kind != "text")
# header keys giving a series-wide value of a per-test quantity
HEADER_KEYS = {"sphere.diameter_mm": "sphere_diameter_mm", "sphere.Rp_um": "sphere_Rp_um", "sphere.tm": "sphere_tm"}
# the native table names its own columns in native units
NATIVE_MAPPING = {q: (native, unit) for q, (native, _, unit) in ADHESION_COLUMNS.items()}
_MOMENT_ALIASES = {"nm": "N*m", "nmm": "N*mm", "knm": "kN*m", "n.m": "N*m", "n.mm": "N*mm"}
_MM_PER_UM = 1e-3


@dataclass
class AdhesionTable:
    """A series of adhesiometer tests: one row per test, native unit-named columns.

    data: columns of :data:`ADHESION_COLUMNS` (native names) plus ``source`` (the file) and
        ``line`` (1-based line of the row in it); sphere columns filled from the header.
    traces: test_id → DataFrame ``time_s, moment_N_m`` for the tests that have a trace.
    """

    data: pd.DataFrame
    meta: dict[str, str] = field(default_factory=dict)
    traces: dict[str, pd.DataFrame] = field(default_factory=dict)
    sources: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.data)

    def column(self, name: str) -> np.ndarray:
        """Column ``name`` as floats."""
        return self.data[name].to_numpy(dtype=float)

    @property
    def material(self) -> str:
        """The material named in the header ("" when none)."""
        return self.meta.get("material", "")


# -- units ------------------------------------------------------------------------------------


def moment_conversion(unit: str, *, source: str = "<option>", column: str | None = None) -> float:
    """Factor turning a moment in ``unit`` (force unit × length unit, e.g. ``kN*m``) into N·m."""
    text = unit.strip().replace("·", "*").replace("⋅", "*").replace(" ", "")
    text = _MOMENT_ALIASES.get(text.lower(), text)
    force_unit, star, length_unit = text.partition("*")
    if not star:
        raise UnitError(source, f"unknown moment unit {unit!r} (write force*length: N*m, N*mm, kN*m, lbf*in)", column=column)
    force_factor, _ = unit_conversion(force_unit, "force", source=source, column=column)
    length_factor, _ = unit_conversion(length_unit, "length", source=source, column=column)
    return force_factor * length_factor * 1e-3  # N·mm → N·m


def _converter(quantity: str, unit: str | None, *, source: str, column: str):
    """value → native value for one mapped quantity (the unit table of record.importers_text)."""
    native, kind, _ = ADHESION_COLUMNS[quantity]
    if kind == "text":
        return None
    if unit is None or unit == "":
        if kind == "ratio":
            return lambda v: v
        raise UnitError(source, f"no unit given for column '{column}' and the file has no units row (give --column {quantity}={column}:UNIT)")
    if kind == "moment":
        factor = moment_conversion(unit, source=source, column=column)
        return lambda v: v * factor
    factor, offset = unit_conversion(unit, kind, source=source, column=column)
    if native == "sphere_Rp_um":
        factor /= _MM_PER_UM  # the table keeps the microrelief in µm
    return lambda v: v * factor + offset


# -- the --column option -------------------------------------------------------------------------


def parse_adhesion_column_option(text: str) -> tuple[str, tuple[str, str | None]]:
    """``'moment=Torque:N*mm'`` → ``('moment', ('Torque', 'N*mm'))`` (quantities: :data:`ADHESION_COLUMNS`).

    The COLUMN[:UNIT] part is split exactly as :func:`flowcurve.record.importers.parse_column_option` does.
    """
    quantity, _, rest = text.partition("=")
    if quantity.strip().lower() not in ADHESION_COLUMNS or not rest.strip():
        raise RecordError("--column", f"{text!r} is not QUANTITY=COLUMN[:UNIT] with a quantity of: {', '.join(ADHESION_COLUMNS)} "
                          "(e.g. moment=Torque:N*m)")
    return quantity.strip().lower(), parse_column_option("force=" + rest)[1]


# -- reading -----------------------------------------------------------------------------------


def read_adhesion_tables(paths, *, columns: Mapping[str, tuple[str, str | None]] | None = None) -> AdhesionTable:
    """Read and join several tables (native ones, or foreign CSVs through ``columns``)."""
    import pandas as pd

    tables = [read_adhesion_table(p, columns=columns) for p in paths]
    if not tables:
        raise RecordError("RECORD", "no adhesion table given")
    meta: dict[str, str] = {}
    for t in tables:
        for key, value in t.meta.items():
            meta.setdefault(key, value)
    data = pd.concat([t.data for t in tables], ignore_index=True)
    traces = {k: v for t in tables for k, v in t.traces.items()}
    return AdhesionTable(data=data, meta=meta, traces=traces, sources=[s for t in tables for s in t.sources],
                         warnings=[w for t in tables for w in t.warnings])


def read_adhesion_table(path: str | os.PathLike, *, columns: Mapping[str, tuple[str, str | None]] | None = None) -> AdhesionTable:
    """One table: the native format (``# flowcurve-adhesion: 1``) or any CSV through ``columns``.

    columns: quantity → (file column, unit or None for the file's units row), e.g.
        ``{"normal_force": ("Fz", "kN"), "moment": ("Mz", "N*mm"), ...}``. Ignored (with a
        warning) for a native table, which names its own columns.
    """
    import pandas as pd

    path = Path(path)
    source = str(path)
    _check_readable(path)
    lines = _read_lines(path)
    native = bool(lines) and lines[0].replace(" ", "").lower().startswith(f"#{FORMAT_NAME}:")
    warnings: list[str] = []
    meta, body_start = _header(lines, source)
    mapping = _mapping(path, native, columns, warnings)
    names_line = lines[body_start]
    delim = sniff_delimiter(names_line)
    names = [c.strip().strip('"') for c in next(csv.reader([names_line], delimiter=delim))]
    if native:
        mapping = {q: spec for q, spec in mapping.items() if spec[0] in names}
        missing = [ADHESION_COLUMNS[q][0] for q in REQUIRED if q not in mapping]
        if missing:
            raise RecordError(source, f"missing column(s) {', '.join(missing)} (found: {', '.join(names)})", line=body_start + 1)
    absent = [spec[0] for spec in mapping.values() if spec[0] not in names]
    if absent:
        raise RecordError(source, f"no column named {', '.join(map(repr, absent))} (columns found: {', '.join(names)})", line=body_start + 1)
    rows = [(j + 1, next(csv.reader([line], delimiter=delim))) for j, line in enumerate(lines) if j > body_start and line.strip() and not line.startswith("#")]
    if not rows:
        raise RecordError(source, "the table has a column row but no tests", line=body_start + 1)
    numeric_idx = [names.index(mapping[q][0]) for q in mapping if q in NUMERIC]
    # decimal comma: a ';' or tab file whose numbers are written 1,25 (as record.importers_text decides)
    decimal = "."
    if delim != "," and any(re.fullmatch(r"\s*-?\d+,\d+\s*", cells[k]) for _, cells in rows for k in numeric_idx if k < len(cells)):
        decimal = ","
    # an optional units row right under the names row: no mapped numeric cell is a number
    file_units, rows = _units_row(rows, names, numeric_idx, decimal, source)
    converters = {}
    for quantity, (name, unit) in mapping.items():
        declared = file_units.get(name) or None
        if not native and (unit is None or unit == ""):
            unit = declared
        converters[quantity] = _converter(quantity, unit, source=source, column=name)
    records = []
    for line_no, cells in rows:
        records.append(_parse_row(cells, names, mapping, converters, meta, source, line_no, decimal))
    data = pd.DataFrame.from_records(records)
    data.insert(0, "source", source)
    table = AdhesionTable(data=data, meta=meta, sources=[source], warnings=warnings)
    _attach_traces(table, path)
    return table


def _header(lines: list[str], source: str) -> tuple[dict[str, str], int]:
    """The ``# key: value`` header's metadata and the index of the column row after it."""
    meta: dict[str, str] = {}
    body_start = 0
    for i, line in enumerate(lines):
        if not line.startswith("#"):
            body_start = i
            break
        parsed = parse_header_line(line)
        if parsed:
            meta[parsed[0]] = parsed[1]
    else:
        raise RecordError(source, "the table has a header but no column row")
    return meta, body_start


def _mapping(path: Path, native: bool, columns, warnings: list[str]) -> dict[str, tuple[str, str | None]]:
    """The quantity → (column, unit) mapping: a native table's own, else the one given, checked."""
    source = str(path)
    if native:
        if columns:
            warnings.append("the column mapping was ignored: a flowcurve-adhesion table names its own columns and units")
        mapping = {q: spec for q, spec in NATIVE_MAPPING.items()}
    elif columns:
        mapping = dict(columns)
    else:
        raise RecordError(source, "not a flowcurve-adhesion table and no column mapping given; name the columns, e.g. "
                          "--column normal_force=Fz:N --column moment=Mz:N*m --column imprint_radius=r:mm "
                          "--column temperature=T:C" + _found_columns_hint(decode_text(path).head))
    unknown = [q for q in mapping if q not in ADHESION_COLUMNS]
    if unknown:
        raise RecordError(source, f"unknown quantity {', '.join(map(repr, unknown))} in the column mapping (use: {', '.join(ADHESION_COLUMNS)})")
    if not native:
        missing = [q for q in REQUIRED if q not in mapping]
        if missing:
            raise RecordError(source, f"the column mapping lacks {', '.join(missing)} (give e.g. --column {missing[0]}=NAME:{ADHESION_COLUMNS[missing[0]][2]})")
    return mapping


def _units_row(rows: list, names: list[str], numeric_idx: list[int], decimal: str, source: str) -> tuple[dict[str, str], list]:
    """An optional units row right under the names row (no mapped numeric cell is a number):
    (column name → unit, the rows after it)."""
    first_line, first_cells = rows[0]
    file_units: dict[str, str] = {}
    if all(k < len(first_cells) for k in numeric_idx) and not any(is_number(first_cells[k], decimal) for k in numeric_idx if first_cells[k].strip()):
        file_units = {names[k]: first_cells[k].strip().strip('"').strip("[]() ") for k in range(min(len(names), len(first_cells)))}
        rows = rows[1:]
        if not rows:
            raise RecordError(source, "the table has column and units rows but no tests", line=first_line)
    return file_units, rows


def _read_lines(path: Path) -> list[str]:
    try:
        return path.read_text(encoding="utf-8-sig").splitlines()
    except UnicodeDecodeError:
        raise RecordError(path, "is not UTF-8 text") from None
    except OSError as exc:  # pragma: no cover - permissions and the like
        raise RecordError(path, f"cannot be read ({exc.strerror})") from None


def _header_number(meta: Mapping[str, str], key: str, source: str) -> float | None:
    raw = meta.get(key)
    if raw is None or raw.strip() == "":
        return None
    try:
        return float(raw)
    except ValueError:
        raise RecordError(source, f"header '{key}' is not a number: {raw!r}") from None


def _parse_row(cells, names, mapping, converters, meta, source: str, line_no: int, decimal: str) -> dict:
    """One test row → native values; a bad cell is a one-line error naming file, line, column."""
    row: dict = {"line": line_no}
    for quantity, (name, _unit) in mapping.items():
        native, kind, _ = ADHESION_COLUMNS[quantity]
        k = names.index(name)
        cell = cells[k].strip().strip('"') if k < len(cells) else ""
        if kind == "text":
            row[native] = cell or None
            continue
        if cell == "":
            row[native] = math.nan
            continue
        if not is_number(cell, decimal) or (decimal == "." and "," in cell):
            raise RecordError(source, f"not a number: {cell!r}", line=line_no, column=name)
        row[native] = float(converters[quantity](float(cell.replace(",", "."))))
    for key, native in HEADER_KEYS.items():
        if not math.isfinite(row.get(native, math.nan)):
            value = _header_number(meta, key, source)
            row[native] = math.nan if value is None else value
    _check_row(row, mapping, source, line_no)
    if not row.get("test_id"):
        row["test_id"] = f"{Path(source).stem}:{line_no}"
    return row


def _check_row(row: dict, mapping, source: str, line_no: int) -> None:
    """The physical checks of one test: N_z > 0, M_z ≥ 0, r > 0, a temperature given."""
    def col(quantity):
        """The table column of ``quantity``."""
        return mapping[quantity][0]

    if not math.isfinite(row["temperature_C"]):
        raise RecordError(source, "missing temperature", line=line_no, column=col("temperature"))
    if not math.isfinite(row["normal_force_N"]):
        raise RecordError(source, "missing normal force N_z", line=line_no, column=col("normal_force"))
    if row["normal_force_N"] <= 0:
        raise RecordError(source, f"normal force N_z must be > 0, got {row['normal_force_N']:g} N", line=line_no, column=col("normal_force"))
    if not math.isfinite(row["imprint_radius_mm"]):
        raise RecordError(source, "missing imprint radius r", line=line_no, column=col("imprint_radius"))
    if row["imprint_radius_mm"] <= 0:
        raise RecordError(source, f"imprint radius r must be > 0, got {row['imprint_radius_mm']:g} mm", line=line_no, column=col("imprint_radius"))
    moment = row["moment_N_m"]
    if math.isfinite(moment) and moment < 0:
        raise RecordError(source, f"moment M_z must be >= 0, got {moment:g} N*m", line=line_no, column=col("moment"))
    if not math.isfinite(moment) and not row.get("trace_file"):
        raise RecordError(source, "missing moment M_z (and no trace_file to take it from)", line=line_no, column=col("moment"))
    flow = row.get("flow_stress_MPa", math.nan)
    if math.isfinite(flow) and flow <= 0:
        raise RecordError(source, f"flow stress must be > 0, got {flow:g} MPa", line=line_no, column=col("flow_stress"))


def _attach_traces(table: AdhesionTable, path: Path) -> None:
    """Read each test's M_z(t) trace; an empty moment cell takes the trace's steady mean."""
    if "trace_file" not in table.data.columns:
        return
    for i, row in table.data.iterrows():
        name = row.get("trace_file")
        if not isinstance(name, str) or not name:
            continue
        trace = read_moment_trace(path.parent / name, table_source=str(path), line=int(row["line"]))
        table.traces[str(row["test_id"])] = trace
        if not math.isfinite(row["moment_N_m"]):
            moment = steady_moment(trace)
            table.data.loc[i, "moment_N_m"] = moment
            table.warnings.append(f"{row['test_id']}: M_z = {moment:.4g} N*m, the mean of the second half of its trace")


def read_moment_trace(path: Path, *, table_source: str, line: int) -> pd.DataFrame:
    """A trace file: CSV with columns ``time_s, moment_N_m``."""
    import pandas as pd

    if not path.exists():
        raise RecordError(table_source, f"trace file {str(path)!r} not found", line=line, column="trace_file")
    try:
        trace = pd.read_csv(path, comment="#", dtype=float)
    except (ValueError, pd.errors.ParserError) as exc:
        raise RecordError(path, f"not a trace of numbers time_s,moment_N_m ({exc})") from None
    missing = [c for c in ("time_s", "moment_N_m") if c not in trace.columns]
    if missing or trace.empty:
        raise RecordError(path, f"a trace needs the columns time_s,moment_N_m and samples (found: {', '.join(trace.columns)})")
    return trace[["time_s", "moment_N_m"]]


def steady_moment(trace: pd.DataFrame) -> float:
    """M_z of a trace: the mean over its second half (past the run-in of the rotation)."""
    moment = trace["moment_N_m"].to_numpy(dtype=float)
    return float(np.mean(moment[len(moment) // 2:]))


# -- writing -----------------------------------------------------------------------------------


def write_adhesion_table(path: str | os.PathLike, data: pd.DataFrame, meta: Mapping[str, object] | None = None,
                         traces: Mapping[str, pd.DataFrame] | None = None) -> Path:
    """Write a native table (and its traces into ``traces/`` beside it)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = data.copy()
    if traces:
        (path.parent / "traces").mkdir(exist_ok=True)
        names = []
        for test_id in data["test_id"]:
            trace = traces.get(test_id)
            if trace is None:
                names.append("")
                continue
            name = f"traces/{test_id}.csv"
            trace.to_csv(path.parent / name, index=False, float_format="%.9g", lineterminator="\n")
            names.append(name)
        data["trace_file"] = names
    order = [native for native, _, _ in ADHESION_COLUMNS.values()]
    order = ["test_id"] + [c for c in order if c in data.columns and c != "test_id"]
    lines = [f"# {FORMAT_NAME}: {FORMAT_VERSION}"]
    for key, value in (meta or {}).items():
        lines.append(f"# {key}: {value!r}" if isinstance(value, float) else f"# {key}: {value}")
    text = "\n".join(lines) + "\n" + data[order].to_csv(index=False, float_format="%.9g", lineterminator="\n")
    path.write_text(text, encoding="utf-8")
    return path

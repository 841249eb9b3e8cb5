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
  by the column names it recognises (:func:`.importers_csv.recognise_quantity`), with the units written in
  the names (``Load [kN]``) or in a units row; an extensometer column in a strain unit
  becomes elongation with the extensometer gauge length Le. Text may be UTF-8 (with or
  without BOM), UTF-16 (Excel's "Unicode text") or Windows-1252, with decimal commas and
  thousands separators.

The families are read in :mod:`.importers_instron` and :mod:`.importers_csv`, on the text and
unit layer of :mod:`.importers_text`. Units are converted through its :data:`UNITS`; a unit it
does not know is an error, never a guess.
Crosshead-less records (force and extensometer only) come back without ``crosshead_mm``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

import numpy as np

from flowcurve.record.format import MAX_MAGNITUDE, Record, is_native, read_record
from flowcurve.errors import MissingValueError, RecordError
from flowcurve.record.importers_text import EXTENSOMETER_GAUGE_KEY, COLUMN_LABEL_PREFIX, FIRST_DATA_LINE_KEY, MAPPED_COLUMNS, SOURCE_PREFIX, STRAIN_COLUMN, STRAIN_LABEL_KEY, _check_readable, decode_text
from flowcurve.record.importers_instron import _is_instron, read_instron
from flowcurve.record.importers_csv import read_csv_export


def load_record(path: str | os.PathLike, *, columns: Mapping[str, tuple[str, str | None]] | None = None, meta: Mapping[str, str] | None = None) -> Record:
    """Read a record file of any supported kind (native, CSV, INSTRON, text).

    An extensometer column in a strain unit (``%``, ``mm/mm``) becomes elongation over the gauge
    length ``specimen.extensometer_gauge_mm``.

    Parameters
    ----------
    path : str or PathLike
        The file.
    columns : Mapping, optional
        For a plain CSV: quantity → (file column, unit), e.g. ``{"force": ("Load", "kN")}`` (keys:
        time, force, crosshead, extensometer, temperature; unit None: from the column's name or the
        units row); None: recognisable names are used. Ignored (with a warning) by self-describing files.
    meta : Mapping, optional
        Header values overriding or adding to the file's.

    Returns
    -------
    Record
        In the native units (s, N, mm, °C).

    Raises
    ------
    RecordError
        One line naming file, line and column for anything unreadable.
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


"""Real records and the ways a file goes wrong between the machine and `flowcurve identify`.

The bases are records as they are met: the INSTRON export and the virtual rig's compression
record of examples/data, a native tension record, and Bluehill, testXpert (UTF-16, decimal
commas) and MTS exports of a Ramberg–Osgood test (tests/identify/lab_exports.py). Each mutation is
a pure function of the file's bytes and a few drawn numbers, as the input campaign of issue 29
made them: truncations, byte flips, bad header and cell values, scaled and shuffled columns,
other encodings and line endings, junk (random bytes, lines over the csv module's 131 072
characters, NUL bytes).
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from flowcurve.record.format import Record, write_record
from flowcurve.record.importers_text import sniff_delimiter

from ..identify.lab_exports import tension_truth, write_bluehill, write_mts, write_testxpert

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "data"
EXPORT_ARGS = ["--test", "tension", "--d0", "6", "--l0", "30", "--le", "25"]  # what the exports do not say about the specimen


@dataclass(frozen=True)
class Base:
    name: str  # file name, with the extension the lab would give it
    data: bytes
    args: tuple[str, ...] = ()  # the identify options the unmutated file needs


def native_tension(tmp: Path) -> Path:
    """A native tension record (crosshead and extensometer) of the Ramberg–Osgood test."""
    t = tension_truth(samples=600)
    meta = {"test": "tension", "material": "Ramberg-Osgood", "specimen.d0_mm": repr(t.d0_mm), "specimen.l0_mm": repr(t.l0_mm),
            "specimen.extensometer_gauge_mm": repr(t.le_mm), "crosshead_speed_mm_per_s": "0.02", "rig.frame_stiffness_N_per_um": "60"}
    data = pd.DataFrame({"time_s": t.time_s, "force_N": t.force_N, "crosshead_mm": t.crosshead_mm, "extensometer_mm": t.extensometer_mm})
    return write_record(tmp / "native-tension.csv", Record(meta=meta, data=data, source="native-tension"))


def bases(tmp: Path) -> list[Base]:
    """The unmutated records, each of which identifies."""
    t = tension_truth(samples=600)
    made = [
        Base("46NT71.csv", (EXAMPLES / "46NT71.csv").read_bytes()),
        Base("compression-steel45.csv", (EXAMPLES / "compression-steel45.csv").read_bytes()),
        Base("native-tension.csv", native_tension(tmp).read_bytes()),
        Base("bluehill.csv", write_bluehill(tmp / "bluehill.csv", t).read_bytes(), tuple(EXPORT_ARGS)),
        Base("testxpert.txt", write_testxpert(tmp / "testxpert.txt", t).read_bytes(), tuple(EXPORT_ARGS)),
        Base("mts.csv", write_mts(tmp / "mts.csv", t).read_bytes(), tuple(EXPORT_ARGS)),
    ]
    return made


# -- the text view a mutation works on ----------------------------------------------------------


def _decode(data: bytes) -> tuple[str, str]:
    for bom, encoding in ((b"\xff\xfe", "utf-16"), (b"\xfe\xff", "utf-16"), (b"\xef\xbb\xbf", "utf-8-sig")):
        if data.startswith(bom):
            return data.decode(encoding), encoding
    return data.decode("utf-8", errors="surrogateescape"), "utf-8"


def _encode(text: str, encoding: str) -> bytes:
    return text.encode(encoding, errors="surrogateescape" if encoding == "utf-8" else "replace")


def _lines(data: bytes) -> tuple[list[str], str, str]:
    """(lines without ends, the line end, the encoding)."""
    text, encoding = _decode(data)
    end = "\r\n" if "\r\n" in text else "\n"
    return text.split(end), end, encoding


def _join(lines: list[str], end: str, encoding: str) -> bytes:
    return _encode(end.join(lines), encoding)


def _is_sample(line: str, delim: str) -> bool:
    cells = line.replace('"', "").replace(",", ".").split(delim) if delim != "," else next(csv.reader([line]), [""])
    try:
        [float(c.replace(",", "")) for c in cells if c.strip()]
    except ValueError:
        return False
    return bool(line.strip()) and not line.startswith("#")


def _table(lines: list[str]) -> tuple[str, list[int], int | None]:
    """(delimiter, indices of the sample lines, index of the column-names row)."""
    names = next((i for i, line in enumerate(lines) if not line.startswith("#") and sniff_delimiter(line) in line and line.count(sniff_delimiter(line)) >= 2
                  and not _is_sample(line, sniff_delimiter(line))), None)
    delim = sniff_delimiter(lines[names]) if names is not None else ","
    samples = [i for i, line in enumerate(lines) if (names is None or i > names) and _is_sample(line, delim)]
    if names is not None and lines[names].startswith("Time\t") and "Force" in lines[names]:
        pass  # INSTRON: its names row is found like the others
    return delim, samples, names


def _split(line: str, delim: str) -> list[str]:
    return next(csv.reader([line], delimiter=delim), [])


def _unsplit(cells: list[str], delim: str) -> str:
    buf = io.StringIO()
    csv.writer(buf, delimiter=delim, lineterminator="").writerow(cells)
    return buf.getvalue()


def _number(cell: str, delim: str) -> float | None:
    c = cell.strip().strip('"')
    c = c.replace(",", ".") if delim != "," and "," in c and "." not in c else c.replace(",", "")
    try:
        return float(c)
    except ValueError:
        return None


# -- mutations ----------------------------------------------------------------------------------

JUNK_CELLS = ("", " ", "abc", "nan", "NaN", "inf", "-inf", "1e999", "-1e999", "1e308", "1,5", "1.2.3", "--", "0x1F", "#", '"', "1 000", "∞", "N/A", "-0")
JUNK_VALUES = ("", "abc", "nan", "inf", "-1", "0", "1e999", "1e-300", "RT", "300 K", "ü", "# x: y", ",,,", "\t")


def truncate(data: bytes, fraction: float) -> bytes:
    """The file cut short at ``fraction`` of its length (a copy interrupted, a crash)."""
    return data[: int(fraction * len(data))]


def flip_bytes(data: bytes, positions: list[float], values: list[int]) -> bytes:
    """Bytes XOR-ed with ``values`` at ``positions`` (fractions of the length): a bad disk or link."""
    out = bytearray(data)
    for p, v in zip(positions, values):
        if out:
            out[min(int(p * len(out)), len(out) - 1)] ^= v
    return bytes(out)


def bad_header_value(data: bytes, which: float, junk: str) -> bytes:
    """One header line's value (after ':' or the first delimiter) replaced by ``junk``."""
    lines, end, encoding = _lines(data)
    delim, samples, names = _table(lines)
    head = [i for i in range(names if names is not None else (samples[0] if samples else len(lines))) if lines[i].strip()]
    if not head:
        return data
    i = head[min(int(which * len(head)), len(head) - 1)]
    line = lines[i]
    for sep in (":\t", ": ", ":", "\t", delim):
        if sep in line:
            key, _, _ = line.partition(sep)
            lines[i] = key + sep + junk
            break
    else:
        lines[i] = junk
    return _join(lines, end, encoding)


def bad_cell(data: bytes, row: float, column: int, junk: str) -> bytes:
    """One sample cell replaced by ``junk``."""
    lines, end, encoding = _lines(data)
    delim, samples, _ = _table(lines)
    if not samples:
        return data
    i = samples[min(int(row * len(samples)), len(samples) - 1)]
    cells = _split(lines[i], delim)
    cells[column % len(cells)] = junk
    lines[i] = _unsplit(cells, delim) if junk not in ('"',) else delim.join(cells)
    return _join(lines, end, encoding)


def scale_column(data: bytes, column: int, factor: float) -> bytes:
    """Every sample of one column × ``factor`` (0: a dead channel; −1: a reversed sign; 1e±6: units)."""
    lines, end, encoding = _lines(data)
    delim, samples, _ = _table(lines)
    decimal_comma = delim != "," and any("," in lines[i] for i in samples[:5])
    for i in samples:
        cells = _split(lines[i], delim)
        k = column % len(cells)
        value = _number(cells[k], delim)
        if value is not None:
            text = f"{value * factor:.9g}"
            cells[k] = text.replace(".", ",") if decimal_comma else text
            lines[i] = _unsplit(cells, delim)
    return _join(lines, end, encoding)


def shuffle_columns(data: bytes, seed: int, names_only: bool) -> bytes:
    """The columns in another order — whole columns (a rearranged export), or the names row alone
    (every column under another's name)."""
    lines, end, encoding = _lines(data)
    delim, samples, names = _table(lines)
    if names is None or not samples:
        return data
    width = len(_split(lines[names], delim))
    order = np.random.default_rng(seed).permutation(width)
    touched = [names] if names_only else [i for i in range(names, len(lines)) if len(_split(lines[i], delim)) == width]
    for i in touched:
        cells = _split(lines[i], delim)
        lines[i] = _unsplit([cells[k] for k in order], delim)
    return _join(lines, end, encoding)


ENCODINGS = ("utf-8", "utf-8-sig", "utf-16", "utf-16-le", "utf-16-be", "cp1252", "latin-1", "utf-32", "cp437")


def reencode(data: bytes, encoding: str) -> bytes:
    """The same text in another encoding (what it cannot hold becomes '?')."""
    text, _ = _decode(data)
    return text.encode(encoding, errors="replace")


def line_endings(data: bytes, style: str, seed: int = 0) -> bytes:
    """Lines ended by CR alone (old Mac exports), CR LF, or a mixture of LF, CR LF and CR."""
    text = data.replace(b"\r\n", b"\n")
    if style == "cr":
        return text.replace(b"\n", b"\r")
    if style == "crlf":
        return text.replace(b"\n", b"\r\n")
    rng = np.random.default_rng(seed)
    parts = text.split(b"\n")
    ends = rng.choice([b"\n", b"\r\n", b"\r"], size=max(len(parts) - 1, 0))
    return b"".join(p + e for p, e in zip(parts, ends)) + parts[-1]


def junk(data: bytes, where: float, kind: str, seed: int = 0) -> bytes:
    """Junk inserted at ``where`` (a fraction of the lines): random bytes, a line of 140 000
    characters (over the csv module's field limit), NUL bytes, a block of blank lines, or text."""
    lines = data.split(b"\n")
    i = min(int(where * len(lines)), len(lines))
    rng = np.random.default_rng(seed)
    piece = {
        "bytes": bytes(rng.integers(0, 256, 64, dtype=np.uint8)),
        "long_line": b"x" * 140_000,
        "long_number": b"1" * 140_000,
        "long_cells": b",".join([b"1"] * 70_000),
        "nul": b"\x00" * 16,
        "blank": b"\n" * 20,
        "text": "Prüfung abgebrochen; Kraft > Grenzwert".encode("utf-8"),
    }[kind]
    return b"\n".join(lines[:i] + [piece] + lines[i:])


JUNK_KINDS = ("bytes", "long_line", "long_number", "long_cells", "nul", "blank", "text")

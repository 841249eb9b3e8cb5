"""Small independent readers for the card tests: Abaqus/CalculiX keyword files, Radioss
fixed-format blocks and CalculiX .dat print-outs. Written from the formats' rules, not from
the writers' code."""

from __future__ import annotations

import re

import numpy as np


def read_inp(text: str) -> list[tuple[str, dict[str, str], list[list[str]]]]:
    """Abaqus-style keyword file → [(KEYWORD, {PARAM: value}, data rows)]; '**' lines are comments."""
    blocks = []
    for line in text.splitlines():
        if line.startswith("**") or not line.strip():
            continue
        if line.startswith("*"):
            head, *params = [p.strip() for p in line[1:].split(",")]
            opts = {}
            for p in params:
                key, _, value = p.partition("=")
                opts[key.strip().upper()] = value.strip()
            blocks.append((head.upper(), opts, []))
        else:
            if not blocks:
                raise ValueError(f"data line before any keyword: {line!r}")
            blocks[-1][2].append([f.strip() for f in line.split(",")])
    return blocks


def floats(rows) -> np.ndarray:
    return np.array([[float(f) for f in row if f != ""] for row in rows])


def read_radioss(text: str) -> list[tuple[str, list[str]]]:
    """Radioss block format → [(header '/MAT/PLAS_JOHNS/1', lines)], '#' lines are comments."""
    blocks = []
    for line in text.splitlines():
        if line.startswith("#"):
            continue
        if line.startswith("/"):
            blocks.append((line.strip(), []))
        elif blocks:
            blocks[-1][1].append(line)
    return blocks


def fixed_fields(line: str, widths) -> list[str]:
    out, pos = [], 0
    for w in widths:
        out.append(line[pos:pos + w].strip())
        pos += w
    return out


def read_dat(text: str) -> dict[str, list[tuple[float, np.ndarray]]]:
    """CalculiX .dat → {'stresses'|'equivalent plastic strain'|'forces': [(time, rows)]}."""
    out: dict[str, list] = {}
    current = None
    for line in text.splitlines():
        m = re.match(r"\s*(stresses|equivalent plastic strain|forces)\b.*time\s+(\S+)", line)
        if m:
            current = []
            out.setdefault(m.group(1), []).append((float(m.group(2)), current))
            continue
        if current is not None and line.strip():
            current.append([float(v) for v in line.split()])
    return {k: [(t, np.array(rows)) for t, rows in v] for k, v in out.items()}

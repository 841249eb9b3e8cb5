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


# -- OpenRadioss, read by the CARD format strings of its own input definitions ----------------
# Transcribed verbatim from OpenRadioss hm_cfg_files/config/CFG/radioss2025/MAT/matl2_plas_johns.cfg
# (FORMAT(radioss2025) and FORMAT(radioss2023), Iflag = 0, no RHO_O) and .../FAIL/fail_johnson.cfg
# (FORMAT(radioss2025), FORMAT(radioss2024)); not from our writer.
RADIOSS_LAYOUTS = {
    ("PLAS_JOHNS", "2025"): [
        ("%20lg", ["RHO_I"]),
        ("%20lg%20lg%10d%10d%20lg", ["E", "Nu", "Iflag", "flagVP", "Pmin"]),
        ("%20lg%20lg%20lg%20lg%20lg", ["a", "b", "n", "EPS_p_max", "SIG_max0"]),
        ("%20lg%20lg%10d%10d%20lg%20lg", ["c", "EPS_DOT_0", "ICC", "Fsmooth", "F_cut", "Chard"]),
        ("%20lg%20lg%20lg%20lg%20lg", ["m", "T_melt", "rhoC_p", "T_r", "T_max"]),
    ],
    ("PLAS_JOHNS", "2023"): [
        ("%20lg", ["RHO_I"]),
        ("%20lg%20lg%10d%10d", ["E", "Nu", "Iflag", "flagVP"]),
        ("%20lg%20lg%20lg%20lg%20lg", ["a", "b", "n", "EPS_p_max", "SIG_max0"]),
        ("%20lg%20lg%10d%10d%20lg%20lg", ["c", "EPS_DOT_0", "ICC", "Fsmooth", "F_cut", "Chard"]),
        ("%20lg%20lg%20lg%20lg", ["m", "T_melt", "rhoC_p", "T_r"]),
    ],
    ("JOHNSON", "2025"): [
        ("%20lg%20lg%20lg%20lg%20lg", ["D1", "D2", "D3", "D4", "D5"]),
        ("%20lg%10d%10d%20lg%20lg%10s%10d", ["Epsilon_Dot_0", "Ifail_sh", "Ifail_so", "EPSF_MIN", "Dadv", "_BLANK_", "Ixfem"]),
        ("%10d", ["FAILIP"]),
    ],
    ("JOHNSON", "2023"): [  # radioss2024 format: the one before 2025
        ("%20lg%20lg%20lg%20lg%20lg", ["D1", "D2", "D3", "D4", "D5"]),
        ("%20lg%10d%10d%20lg%20lg%10s%10d", ["Epsilon_Dot_0", "Ifail_sh", "Ifail_so", "EPSF_MIN", "Dadv", "_BLANK_", "Ixfem"]),
    ],
}


def read_card_format(line: str, fmt: str, names) -> dict:
    """One line read by a CFG CARD format ('%20lg%10d...'): blank fields are None, every
    character beyond the format must be blank (a shifted layout cannot pass)."""
    widths = [(int(w), kind) for w, kind in re.findall(r"%(\d+)(lg|d|s)", fmt)]
    out, pos = {}, 0
    for (w, kind), name in zip(widths, names):
        text = line[pos:pos + w].strip()
        pos += w
        if not text:
            out[name] = None
        elif kind == "d":
            out[name] = int(text)
        elif kind == "lg":
            out[name] = float(text)
        else:
            out[name] = text
    if line[pos:].strip():
        raise ValueError(f"characters beyond the {fmt} layout: {line[pos:]!r}")
    return out


def read_radioss_block(lines, kind: str, version: str) -> dict:
    """The data lines of a /MAT/PLAS_JOHNS (after its title) or /FAIL/JOHNSON block as {field: value}."""
    layout = RADIOSS_LAYOUTS[(kind, version)]
    if len(lines) != len(layout):
        raise ValueError(f"{kind} {version}: {len(lines)} data lines, the definition has {len(layout)}")
    fields = {}
    for line, (fmt, names) in zip(lines, layout):
        fields.update(read_card_format(line, fmt, names))
    return fields

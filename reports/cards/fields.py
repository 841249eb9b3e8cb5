"""Fields of a deck: fixed-width numbers (LS-DYNA, Radioss), free-format numbers (Abaqus,
CalculiX), comment blocks, and plain ASCII text.

Every fixed-width field keeps at least one blank before its value, so that two values never
run together on the page (a full 10-character field is legal, but ``1.29333e112.6e-7`` cannot
be read by a person); the value is the closest the remaining characters hold.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np

from flowcurve.errors import FlowcurveError


class CardError(FlowcurveError):
    """A fit file or option that cannot make the requested card (names the key or option)."""


# Characters our texts use that a solver's reader may refuse: their ASCII spelling.
ASCII_SPELLING = {
    "ε̇": "epsdot", "°": "", "±": "+/-", "–": "-", "—": "-", "−": "-", "·": "*", "×": "x", "≤": "<=", "≥": ">=",
    "ε": "eps", "σ": "sigma", "ρ": "rho", "ν": "nu", "μ": "mu", "η": "eta", "̇": "",
    "²": "2", "³": "3", "…": "...", "’": "'", "‘": "'", "“": '"', "”": '"',
}


# Russian steel grades (12Х18Н10Т) in the Latin spelling of their standards (12Kh18N10T).
CYRILLIC = dict(zip("АБВГДЕЁЖЗИЙКЛМНОПРСТУФХЦЧШЩЪЫЬЭЮЯ",
                    ["A", "B", "V", "G", "D", "E", "E", "Zh", "Z", "I", "Y", "K", "L", "M", "N", "O", "P", "R", "S",
                     "T", "U", "F", "Kh", "Ts", "Ch", "Sh", "Shch", "", "Y", "", "E", "Yu", "Ya"]))


def ascii_text(text: str) -> str:
    """``text`` in plain ASCII: known symbols spelled out, Cyrillic transliterated, anything
    else as '?'."""
    for char, spelling in ASCII_SPELLING.items():
        text = text.replace(char, spelling)
    text = "".join(latin(c) for c in text)
    return text.encode("ascii", "replace").decode("ascii")


def latin(char: str) -> str:
    """A Cyrillic letter in Latin spelling (lower case kept), any other character as is."""
    if char in CYRILLIC:
        return CYRILLIC[char]
    return CYRILLIC[char.upper()].lower() if char.upper() in CYRILLIC else char


def comment_block(lines, prefix: str, width: int = 78) -> str:
    """Comment lines in plain ASCII, wrapped to ``width`` columns (fixed-format readers stop at 80)."""
    out = []
    for line in lines:
        out += textwrap.wrap(ascii_text(line), width - len(prefix), subsequent_indent="  ", break_on_hyphens=False) or [""]
    return "\n".join(f"{prefix}{line}".rstrip() for line in out) + "\n"


def number(value) -> str:
    """A free-format number, 10 significant digits (no binary noise like 7.820000000000002e-09)."""
    return f"{float(value):.10g}"


def fixed(value, width: int = 10, digits: int | None = None) -> str:
    """``value`` right-aligned in a field of ``width`` characters with at least one blank
    before it, as close to the value as ``width - 1`` characters hold; never truncated (a
    value that cannot fit is an error, not a wrong number). ``digits`` caps the significant
    digits (curve points need no more than 8). None leaves the field blank (the default)."""
    if value is None:
        return " " * width
    room = width - 1
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        text = str(int(value))
        if len(text) > room:
            raise CardError(f"integer {value} does not fit a {width}-character field")
        return text.rjust(width)
    value = float(value)
    if not math.isfinite(value):
        raise CardError(f"cannot write {value} into a card field")
    if value == 0.0:
        return "0.0".rjust(width)
    if digits is not None:
        value = float(f"{value:.{digits}g}")
    candidates = {compact(repr(value))}
    candidates |= {compact(f"{value:.{d}g}") for d in range(1, 16)}
    candidates |= {compact(f"{value:.{d}e}") for d in range(0, 15)}
    whole = {t for t in candidates if "e" not in t and "." not in t}  # a real needs its point: 280.0 or 280.
    candidates = (candidates - whole) | {t + ".0" for t in whole} | {t + "." for t in whole}
    fitting = [t for t in candidates if len(t) <= room]
    if not fitting:
        raise CardError(f"{value!r} does not fit a {width}-character field")
    return min(fitting, key=lambda t: (abs(float(t) - value), "e" in t, t.endswith("."), len(t))).rjust(width)


def compact(text: str) -> str:
    """'1.5e-09' -> '1.5e-9', '2e+05' -> '2e5'."""
    if "e" in text:
        mantissa, exponent = text.split("e")
        sign = "-" if exponent.startswith("-") else ""
        return f"{mantissa}e{sign}{exponent.lstrip('+-').lstrip('0') or '0'}"
    return text


def fixed_line(fields, width: int = 10, digits: int | None = None) -> str:
    """One fixed-format line of equal-width fields."""
    return "".join(fixed(v, width, digits) for v in fields).rstrip()


def mixed_line(*fields) -> str:
    """One line of (value, width) fields of different widths (Radioss' 20/10 layout)."""
    return "".join(fixed(v, w) for v, w in fields).rstrip()

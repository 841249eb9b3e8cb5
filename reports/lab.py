"""The laboratory header of a test report: a small TOML file (``flowcurve report --lab lab.toml``).

Every key is optional; a missing key takes the default of :class:`LabHeader`, and the report
says when the header is the default (no lab file given). Keys::

    [lab]
    name = "Materials Testing Laboratory"
    address = "…"
    accreditation = "ISO/IEC 17025, DAkkS D-PL-…"
    report_number = "2026-0147"
    customer = "…"
    approved_by = "…"
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, fields
from pathlib import Path

from flowcurve.errors import FlowcurveError


class LabFileError(FlowcurveError):
    """A lab header file that cannot be read or holds an unknown key."""


@dataclass(frozen=True)
class LabHeader:
    name: str = "Materials testing laboratory"
    address: str = ""
    accreditation: str = "not stated"
    report_number: str = ""  # default: the report's date
    customer: str = ""
    approved_by: str = ""
    source: str = "defaults (no --lab file)"

    def rows(self) -> list[tuple[str, str]]:
        """(label, text) of the keys that have text, in header order."""
        labels = (("laboratory", self.name), ("address", self.address), ("accreditation", self.accreditation),
                  ("report number", self.report_number), ("customer", self.customer), ("approved by", self.approved_by))
        return [(k, v) for k, v in labels if v]


def load_lab(path=None) -> LabHeader:
    """The header from ``path`` (its ``[lab]`` table, or top-level keys), or the defaults when None."""
    if path is None:
        return LabHeader()
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise LabFileError(f"{path}: no such lab header file") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise LabFileError(f"{path}: cannot read the lab header: {exc}") from None
    table = data.get("lab", data)
    known = {f.name for f in fields(LabHeader)} - {"source"}
    for key, value in table.items():
        if key not in known:
            raise LabFileError(f"{path}: [lab] {key}: unknown key (known: {', '.join(sorted(known))})")
        if not isinstance(value, str):
            raise LabFileError(f"{path}: [lab] {key}: must be text, got {value!r}")
    return LabHeader(**table, source=path.name)

"""The laboratory's part of a test report: a small TOML file (``flowcurve report --lab lab.toml``).

Every key is optional; a missing key takes the default of :class:`LabHeader`, and the report
says when the header is the default (no lab file given). Keys (docs/test-report.md, "lab.toml")::

    [lab]
    name = "Materials Testing Laboratory"
    address = "…"
    accreditation = "ISO/IEC 17025, DAkkS D-PL-…"
    report_number = "2026-0147"          # or report_number_scheme = "PL-{year}-{series}"
    revision = 1                         # supersedes revision 0 of the same number
    date_of_issue = 2026-11-27           # default: the day the report is written
    customer = "…"
    approved_by = "…"
    compression_standard = "ASTM E9-19"  # the standard the lab's compression tests follow
    decision_rule = "simple acceptance"  # or "guard band" (guard_band_U = 1.0: w = 1·U)

    [instruments]                        # as the rig configuration's [instruments]; used where a record has none
    force_class = 0.5
    force_certificate = "K-2231"
    force_due_date = 2027-03-31
"""

from __future__ import annotations

import datetime as _dt
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from flowcurve.errors import FlowcurveError


class LabFileError(FlowcurveError):
    """A lab header file that cannot be read or holds an unknown key."""


DECISION_RULES = ("simple acceptance", "guard band")
# the testing rate's own rule (identification/quality/conformity.py: band_verdict), whatever the lab chose for the results
RATE_RULE = ("The testing-rate statements are made with a guard band w = U (k = 2) of each phase's measured rate: a phase "
             "conforms when rate ± U lies inside the method's band, does not when it lies outside, and is 'not resolved' "
             "when it straddles the band's edge.")


@dataclass(frozen=True)
class LabHeader:
    name: str = "Materials testing laboratory"
    address: str = ""
    accreditation: str = "not stated"
    report_number: str = ""  # default: report_number_scheme
    report_number_scheme: str = "{series}-{date}"
    revision: int = 0
    date_of_issue: str = ""  # default: the day the report is written
    customer: str = ""
    approved_by: str = ""
    compression_standard: str = ""
    decision_rule: str = "simple acceptance"
    guard_band_U: float = 1.0  # guard band w as a multiple of U (decision_rule "guard band")
    instruments: dict = field(default_factory=dict)  # [instruments]: the lab's calibration data
    given: frozenset = frozenset()  # the [lab] keys the file gave
    source: str = "defaults (no --lab file)"

    def number(self, series: str, date: str) -> str:
        """The report number: ``report_number``, else the scheme filled with series, date and year."""
        return self.report_number or self.report_number_scheme.format(series=series, date=date, year=date[:4])

    def revision_text(self) -> str:
        """The revision as the report's header says it."""
        return f"{self.revision}, supersedes revision {self.revision - 1}" if self.revision > 0 else "0 (first issue)"

    def decision_rule_text(self) -> str:
        """The decision rule of every conformity statement (ISO/IEC 17025 7.8.6, ILAC-G8:09/2019), in words."""
        chosen = "" if "decision_rule" in self.given else " (the default: no rule chosen in the lab file)"
        if self.decision_rule == "guard band":
            return (f"Decision rule (ISO/IEC 17025 7.8.6, ILAC-G8:09/2019 guarded acceptance): a statement 'conforms' needs the "
                    f"value inside its limit by at least the guard band w = {self.guard_band_U:g}·U; within w of the limit the "
                    "statement is 'not decided'. " + RATE_RULE + " The temperature statements carry no U of their own: "
                    "they are made on the value (w = 0).")
        return ("Decision rule (ISO/IEC 17025 7.8.6, ILAC-G8:09/2019 simple acceptance, w = 0): a value on its side of the "
                "limit conforms; the measurement uncertainty is not deducted, so a value close to a limit carries a risk of "
                f"a false decision of up to 50 %{chosen}. " + RATE_RULE)


_TYPES = {"revision": int, "guard_band_U": float}


def _check(path: Path, key: str, value):
    kind = _TYPES.get(key, str)
    if key == "date_of_issue" and isinstance(value, _dt.date):
        value = value.isoformat()
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise LabFileError(f"{path}: [lab] {key}: must be {'a number' if kind is float else 'an integer' if kind is int else 'text'}, "
                           f"got {value!r}")
    if key == "decision_rule" and value not in DECISION_RULES:
        raise LabFileError(f"{path}: [lab] decision_rule: must be one of {', '.join(DECISION_RULES)}, got {value!r}")
    if key == "revision" and value < 0 or key == "guard_band_U" and not 0 < value <= 3:
        raise LabFileError(f"{path}: [lab] {key}: out of range, got {value!r}")
    if key == "date_of_issue":
        try:
            _dt.date.fromisoformat(value)
        except ValueError:
            raise LabFileError(f"{path}: [lab] date_of_issue: must be a date YYYY-MM-DD, got {value!r}") from None
    if key == "report_number_scheme":
        try:
            value.format(series="s", date="2026-01-01", year="2026")
        except (KeyError, IndexError, ValueError) as exc:
            raise LabFileError(f"{path}: [lab] report_number_scheme: use only {{series}}, {{date}}, {{year}}: {exc}") from None
    return value


def _instruments(path: Path, table, check) -> dict:
    """``[instruments]`` checked by ``check(table, origin)`` (the rig configuration's schema, given by the
    application layer: reports do not import rig), else kept as written with its dates as ISO text."""
    if not isinstance(table, dict):
        raise LabFileError(f"{path}: [instruments]: must be a table, got {table!r}")
    if check is not None:
        try:
            return check(table, str(path))
        except FlowcurveError as exc:
            raise LabFileError(str(exc)) from None
    return {k: v.isoformat() if isinstance(v, _dt.date) else v for k, v in table.items()}


def load_lab(path=None, check_instruments=None) -> LabHeader:
    """The header from ``path`` (its ``[lab]`` table, or top-level keys, and ``[instruments]``), or the defaults when None.
    ``check_instruments(table, origin)``: the rig configuration's check of ``[instruments]`` (rig.config.instruments_given)."""
    if path is None:
        return LabHeader()
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise LabFileError(f"{path}: no such lab header file") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise LabFileError(f"{path}: cannot read the lab header: {exc}") from None
    table = data.get("lab", {k: v for k, v in data.items() if k != "instruments"})
    known = {f.name for f in fields(LabHeader)} - {"source", "instruments"}
    values = {}
    for key, value in table.items():
        if key not in known:
            raise LabFileError(f"{path}: [lab] {key}: unknown key (known: {', '.join(sorted(known))})")
        values[key] = _check(path, key, value)
    instruments = _instruments(path, data.get("instruments", {}), check_instruments)
    return LabHeader(**values, instruments=instruments, given=frozenset(values), source=path.name)


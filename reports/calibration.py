"""The calibration data behind a specimen's results, and whether the report may be released.

A record's own ``instruments.*`` (as tested that day, in result.json's ``record.instruments``)
win; where a record has none, the lab file's ``[instruments]`` are used and the report says so.
A report is "not for release" when the force measuring system, the extensometer (when the
strain came from one) or the dimension gauges have no certificate, when a certificate was past
its due date on the test date, or when the budget's classes are not the calibrated ones.
"""

from __future__ import annotations

import datetime as _dt

NOT_FOR_RELEASE = "instrument data: defaults — not for release"
# (key prefix, name in the report, the class/MPE key and its unit)
INSTRUMENTS = (("force", "force measuring system", "force_class", "ISO 7500-1 class"),
               ("extensometer", "extensometer", "extensometer_class", "ISO 9513 class"),
               ("micrometer", "micrometer", "micrometer_mpe_mm", "MPE, mm"),
               ("caliper", "caliper", "caliper_mpe_mm", "MPE, mm"),
               ("thermocouple", "thermocouples", "thermocouple_tolerance_C", "tolerance, °C"))
HEATED_ABOVE_C = 35.0  # ISO 6892-1 §10: room temperature is 10–35 °C


def iso_date(text) -> _dt.date | None:
    """The date at the start of ``text`` (``2022-08-18``, ``2026-11-23T09:30:04+00:00``), or None."""
    try:
        return _dt.date.fromisoformat(str(text or "")[:10])
    except ValueError:
        return None


def effective(record_inst: dict, lab_inst: dict) -> tuple[dict, dict[str, str]]:
    """(instrument data, source per instrument): per instrument the record's own data where it states a
    certificate (as tested that day), else the lab file's where it has any, else what the record states."""
    data, sources = {}, {}
    for prefix, *_ in INSTRUMENTS:
        own = {k: v for k, v in record_inst.items() if k.startswith(f"{prefix}_")}
        lab = {k: v for k, v in lab_inst.items() if k.startswith(f"{prefix}_")}
        if own.get(f"{prefix}_certificate") or (own and not lab):
            data.update(own)
            sources[prefix] = "record (as tested)"
        elif lab:
            data.update(lab)
            sources[prefix] = "lab file (the record states none)"
        else:
            sources[prefix] = "not stated"
    return data, sources


def instrument_cell(inst: dict, prefix: str, class_key: str, what: str) -> str:
    """'ISO 7500-1 class 0.5; certificate K-2231, due 2027-03-31' or 'not stated'."""
    parts = []
    if inst.get(class_key) is not None:
        parts.append(f"{what} {inst[class_key]:g}" if isinstance(inst[class_key], float) else f"{what} {inst[class_key]}")
    if prefix == "force" and inst.get("force_U_rel_pct") is not None:
        parts.append(f"certificate U {inst['force_U_rel_pct']:g} %")
    if prefix == "force" and inst.get("force_resolution_N") is not None:
        parts.append(f"resolution {inst['force_resolution_N']:g} N")
    cert = inst.get(f"{prefix}_certificate")
    if cert:
        parts.append(f"certificate {cert}, due {inst.get(f'{prefix}_due_date') or 'not stated'}")
    return "; ".join(parts) or "not stated"


def release_problems(inst: dict, *, test_date: _dt.date | None, issued: _dt.date, extensometer: bool, heated: bool,
                     budget_inst: dict) -> list[str]:
    """Why results on ``inst`` may not be released (empty: they may)."""
    needed = ["force"] + (["extensometer"] if extensometer else []) + (["thermocouple"] if heated else [])
    problems = [f"{name}: no calibration certificate" for prefix, name, *_ in INSTRUMENTS
                if prefix in needed and not inst.get(f"{prefix}_certificate")]
    if not inst.get("micrometer_certificate") and not inst.get("caliper_certificate"):
        problems.append("dimensions: no micrometer or caliper certificate")
    on = test_date or issued
    for prefix, name, *_ in INSTRUMENTS:
        due = iso_date(inst.get(f"{prefix}_due_date"))
        if inst.get(f"{prefix}_certificate") and due is None:
            problems.append(f"{name}: certificate without a due date")
        elif due is not None and due < on:
            problems.append(f"{name}: certificate due {due.isoformat()}, before the test date {on.isoformat()}")
    for key in ("force_class", "extensometer_class"):
        if inst.get(key) is not None and budget_inst.get(key) is not None and float(inst[key]) != float(budget_inst[key]):
            problems.append(f"U was computed with {key.replace('_', ' ')} {budget_inst[key]:g}, the calibrated one is {inst[key]:g}")
    return problems

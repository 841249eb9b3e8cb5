"""The ``record`` block of ``result.json``: where a record came from and at what conditions.

Derived from the record alone (header and sample count), so identification, series fits and
reports describe a record the same way.
"""

from __future__ import annotations

import math

from flowcurve.record.format import Record

# the header key of the gauge length (tension) or initial height (compression)
GAUGE_KEY = {"tension": "specimen.l0_mm", "compression": "specimen.h0_mm"}


def record_summary(record: Record) -> dict:
    """The ``record`` block of ``result.json``: where the data came from and at what conditions."""
    test = record.test
    meta = record.meta
    speed = record.number("crosshead_speed_mm_per_s")
    gauge = record.number(GAUGE_KEY[test])
    rate = speed / gauge if speed is not None and gauge else None
    specimen = {k.split(".", 1)[1]: _number_or_text(v) for k, v in meta.items() if k.startswith("specimen.")}
    post = {k.split(".", 1)[1]: _number_or_text(v) for k, v in meta.items() if k.startswith("post.")}
    published = {k.split(".", 1)[1]: _number_or_text(v) for k, v in meta.items() if k.startswith("published.")}
    summary = {
        "path": record.source,
        "name": record.name,
        "test": test,
        "material": meta.get("material"),
        "nominal_temperature_C": record.number("nominal_temperature_C"),
        "crosshead_speed_mm_per_s": speed,
        "strain_rate_per_s": rate,  # nominal: crosshead speed / gauge length (or height)
        "samples": int(len(record.data)),
        "truncated": bool(record.truncated),
        "specimen": specimen,
        "post": post,
    }
    if published:
        summary["published"] = published
    summary.update(identity(meta))
    return summary


def identity(meta) -> dict:
    """Who tested what, when and with which instruments: the header keys a test report names
    (``date``, ``operator``, ``specimen.id``, ``specimen.orientation``, ``standard`` and the
    ``instruments.*`` data as tested that day); absent keys are left out, never guessed."""
    out = {key: meta[m].strip() for key, m in (("date", "date"), ("operator", "operator"), ("specimen_id", "specimen.id"),
                                               ("orientation", "specimen.orientation"), ("standard", "standard"))
           if str(meta.get(m) or "").strip()}
    instruments = {k.split(".", 1)[1]: _number_or_text(v) for k, v in meta.items() if k.startswith("instruments.")}
    if instruments:
        out["instruments"] = instruments
    return out


def _number_or_text(value: str):
    try:
        number = float(value)
    except (TypeError, ValueError):
        return value
    return number if math.isfinite(number) else value

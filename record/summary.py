"""The ``record`` block of ``result.json``: where a record came from and at what conditions.

Derived from the record alone (header and sample count), so identification, series fits and
reports describe a record the same way.
"""

from __future__ import annotations

import math

from flowcurve.record.format import Record

# the header key of the gauge length (tension) or initial height (compression)
GAUGE_KEY = {"tension": "specimen.l0_mm", "compression": "specimen.h0_mm"}


# a crosshead measured this far off its commanded speed ran at another speed: named (event, warnings), its rate the measured one's
SPEED_TOLERANCE = 0.05  # beyond a machine's speed error and the measurement's (≤ 2 %, acquisition.procedure.SPEED_MIN_TRAVEL_MM)
MEASURED_SPEED_KEY = "crosshead_speed_measured_mm_per_s"


def speed_mismatch(commanded_mm_per_s: float | None, measured_mm_per_s: float | None) -> str | None:
    """One line when the measured crosshead speed is off the commanded one beyond SPEED_TOLERANCE, else None."""
    if not commanded_mm_per_s or measured_mm_per_s is None:
        return None
    off = measured_mm_per_s / commanded_mm_per_s - 1.0  # relative deviation of the measured speed
    if abs(off) <= SPEED_TOLERANCE:
        return None
    return (f"the crosshead ran at {measured_mm_per_s:.4g} mm/s (measured from the encoder), not the commanded "
            f"{commanded_mm_per_s:g} mm/s ({100 * off:+.0f} %, beyond ±{100 * SPEED_TOLERANCE:g} %): the strain rate is the measured speed's")


def record_summary(record: Record) -> dict:
    """The ``record`` block of ``result.json``: where the data came from and at what conditions;
    the strain rate from the measured crosshead speed when the record has one."""
    test = record.test
    meta = record.meta
    speed = record.number("crosshead_speed_mm_per_s")
    measured = record.number(MEASURED_SPEED_KEY)
    gauge = record.number(GAUGE_KEY[test])
    moved = measured if measured is not None else speed
    rate = moved / gauge if moved is not None and gauge else None  # ε̇ = v / l0 (or h0)
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
        "strain_rate_per_s": rate,  # nominal: crosshead speed (measured when known) / gauge length (or height)
        "samples": int(len(record.data)),
        "truncated": bool(record.truncated),
        "specimen": specimen,
        "post": post,
    }
    if measured is not None:
        summary[MEASURED_SPEED_KEY] = measured
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

"""The spread a doubtful post-test measurement leaves in a compression result's budgets.

When the record declares a heating fault after its last row (:func:`..identify.after_loading_warnings`)
the measured final height hk may include flow after the record. The record itself holds a second
estimate: the specimen's shortening as the crosshead measured it, frame compliance removed
(K_l = 1 in (3.1)). The result is identified again on the specimen as the record left it, and the
difference between the two values of each budgeted quantity enters that budget as a method
component, the truth taken anywhere within ± the difference (rectangular).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

from flowcurve.identification.quality import uncertainty as un

COMPONENT = "method: post-test measurements after a heating fault"
BASIS = ("the specimen stood under load while heated after the record: the measured hk against the record's own "
         "shortening (K_l = 1), ± their results' difference (rectangular)")


def record_final_height_mm(result: Mapping) -> float | None:
    """hk as the record's shortening gives it: h0 + spring-back − max specimen displacement ((3.1) with K_l = 1)."""
    indicator = result.get("indicator") or {}
    spec = (result.get("record") or {}).get("specimen") or {}
    h0, shortening = spec.get("h0_mm"), indicator.get("max_specimen_displacement_mm")
    springback = indicator.get("springback_mm") or 0.0
    if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in (h0, shortening, springback)):
        return None
    hk = float(h0) + float(springback) - float(shortening)
    return hk if 0.0 < hk < float(h0) else None


def as_left_by_record(record, hk_mm: float):
    """A copy of ``record`` whose post-test measurements describe the specimen at ``hk_mm``: hk
    replaced, the measured diameters scaled by √(hk/hk_mm) and areas by hk/hk_mm (volume constant)."""
    meta = dict(record.meta)
    hk = float(meta["post.hk_mm"])
    for key, power in (("post.dmax_mm", 0.5), ("post.dtop_mm", 0.5), ("post.dface_mm", 0.5), ("post.smax_mm2", 1.0)):
        if meta.get(key) not in (None, ""):
            meta[key] = f"{float(meta[key]) * (hk / hk_mm) ** power:.6g}"
    meta["post.hk_mm"] = f"{hk_mm:.6g}"
    return dataclasses.replace(record, meta=meta)


def _budgets(uncertainty: Mapping) -> dict[tuple[str, ...], dict]:
    """Every budget of a compression result's uncertainty block by its path (friction_mu, Rp02_MPa,
    flow_stress_MPa/<ε>, hardening/<constant>)."""
    out: dict[tuple[str, ...], dict] = {}
    for key, b in uncertainty.items():
        if key in ("flow_stress_MPa", "hardening") and isinstance(b, Mapping):
            out.update({(key, k): v for k, v in b.items() if isinstance(v, dict)})
        elif isinstance(b, dict) and "components" in b:
            out[(key,)] = b
    return out


def widen(uncertainty: Mapping, alternative: Mapping) -> list[str]:
    """Add :data:`COMPONENT` to each budget of ``uncertainty`` that ``alternative`` (the same
    result on the specimen as the record left it) also states: u = |Δ|/√3 (GUM 4.3.7). Returns the
    paths that ``alternative`` lacks (their budgets are left as they were)."""
    from flowcurve.identification.quality.assurance import extend_budget

    theirs, missing = _budgets(alternative), []
    for path, b in _budgets(uncertainty).items():
        other = theirs.get(path)
        if b.get("U") is None or other is None or other.get("value") is None or b.get("value") is None:
            missing.append("/".join(path))
            continue
        diff = abs(float(b["value"]) - float(other["value"]))
        extend_budget(b, [un.Component(COMPONENT, float(other["value"]), str(b.get("unit") or ""), un.rectangular(diff), 1.0, BASIS)])
    return missing

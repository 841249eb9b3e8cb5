"""The load-cell amplifier's low-pass filter: what its lag leaves in a result's budgets.

A record may state the amplifier's filter (``instruments.force_filter_Hz``, the −3 dB point of a
first-order low-pass: the rig writes it from its ``[loadcell] filter``). Such a filter delays the
force by τ = 1/(2π·f_c) against the crosshead. On a straight stretch (the elastic line) that is a
constant shift of the travel, which the strain zero takes up; where the force's rate turns (the
yield knee) it rounds the curve instead: the first plastic points read low, the more so the faster
the test. The result is identified again with the force the filter delayed restored
(F = F_f + τ·dF_f/dt, the first-order filter's own equation), and the difference of each hardening
constant, of Rp0.2 and of each flow-curve point enters its budget as a component, u = |Δ| (a
systematic effect left uncorrected, stated as its size).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from flowcurve.identification.indicator import GIVEN_WINDOW_POINTS
from flowcurve.identification.quality import uncertainty as un

FILTER_KEY = "instruments.force_filter_Hz"
COMPONENT = "force filter lag"
BASIS = ("the amplifier's first-order low-pass delays the force by τ = 1/(2π·f_c): the constant refitted with the "
         "force restored, F_f + τ·dF_f/dt; u = |Δ| (uncorrected)")


def lag_s(record) -> float | None:
    """τ = 1/(2π·f_c) in the record's seconds of the filter the record states (``instruments.force_filter_Hz``); None without one."""
    try:
        fc = float(record.meta.get(FILTER_KEY, ""))
    except (TypeError, ValueError):
        return None
    return 1.0 / (2.0 * math.pi * fc) if fc > 0 and math.isfinite(fc) else None


def restored_force(time_s, force_N, tau_s: float) -> np.ndarray:
    """The force before a first-order low-pass of time constant ``tau_s``: F = F_f + τ·dF_f/dt, the
    derivative the chord over t ± τ (linear between samples; one-sided at the ends), which keeps the
    noise's share of the correction below the noise itself (≈ 0.7·its σ). Inputs in s and N; output N."""
    t, f = np.asarray(time_s, dtype=float), np.asarray(force_N, dtype=float)
    ok = np.isfinite(t) & np.isfinite(f)
    out = f.copy()
    if ok.sum() < 2 or not tau_s > 0:
        return out
    tt, ff = t[ok], f[ok]
    lo, hi = np.maximum(tt - tau_s, tt[0]), np.minimum(tt + tau_s, tt[-1])
    span = hi - lo
    with np.errstate(invalid="ignore", divide="ignore"):
        slope = np.where(span > 0, (np.interp(hi, tt, ff) - np.interp(lo, tt, ff)) / span, 0.0)
    out[ok] = ff + tau_s * slope
    return out


def unlagged(record, tau_s: float):
    """A copy of ``record`` with its force restored (:func:`restored_force`) up to its largest force, and no
    filter stated. Beyond the maximum the record is left as it is: the hardening is read before it, and a
    break's drop (the fracture's, not the filter's) would read as a lag to undo."""
    data = record.data.copy()
    force = data["force_N"].to_numpy(dtype=float)
    if not np.isfinite(force).any():
        return record
    top = int(np.nanargmax(np.abs(force)))
    restored = restored_force(data["time_s"].to_numpy(), force, tau_s)
    data["force_N"] = np.concatenate([restored[: top + 1], force[top + 1:]])
    meta = {k: v for k, v in record.meta.items() if k != FILTER_KEY}
    return dataclasses.replace(record, meta=meta, data=data)


def pinned_options(result: Mapping, test: str, options: Mapping) -> dict:
    """``options`` with the choices ``result`` made pinned, so that the force restored moves the constants and not a
    choice (the law, E's window, tension's fracture point): those the caller gave are kept."""
    out = dict(options)
    hard, modulus = result.get("hardening") or {}, result.get("modulus") or {}
    if hard.get("law"):
        out.setdefault("law", hard["law"])
    window = modulus.get("window_MPa")
    # a window the automatic choice drew over fewer samples than a given one needs is left to that choice again
    enough = (modulus.get("n_points") or 0) >= GIVEN_WINDOW_POINTS
    if "modulus_window" not in out and enough and window and len(window) == 2 and float(window[1]) > float(window[0]):
        out.setdefault("modulus_window_MPa", (float(window[0]), float(window[1])))
    if test == "tension" and hard.get("fracture_point") in ("included", "excluded"):
        out.setdefault("fracture_point", hard["fracture_point"].removesuffix("d"))
    return out


WIDENED_BLOCKS = ("hardening", "flow_stress_MPa")  # blocks of budgets the lag moves: the constants, the flow-curve points
WIDENED_VALUES = ("Rp02_MPa",)  # single budgets it moves: the offset yield at the rounded knee


def widen(uncertainty: Mapping, alternative: Mapping, *, component: str = COMPONENT, basis: str = BASIS,
          values: tuple = WIDENED_VALUES, blocks: tuple = WIDENED_BLOCKS) -> list[str]:
    """Add ``component`` to each budget of ``uncertainty`` the lag moves (``blocks``' members, ``values``)
    that ``alternative`` (the result with the force restored) also states: u = |Δ|. Returns the keys
    ("block key" in a block) ``alternative`` lacks."""
    pairs = [(key, uncertainty.get(key), alternative.get(key)) for key in values if key in uncertainty]
    for block in blocks:
        mine, theirs = uncertainty.get(block) or {}, alternative.get(block) or {}
        pairs += [(key if block == "hardening" else f"{block} {key}", b, theirs.get(key) if isinstance(theirs, Mapping) else None)
                  for key, b in (mine.items() if isinstance(mine, Mapping) else ())]
    missing = []
    for key, b, other in pairs:
        if not isinstance(b, dict) or b.get("U") is None or b.get("value") is None or not isinstance(other, Mapping) or other.get("value") is None:
            missing.append(key)
            continue
        diff = abs(float(b["value"]) - float(other["value"]))
        _add(b, un.Component(component, float(other["value"]), str(b.get("unit") or ""), diff, 1.0, basis))
    return missing


def _add(b: dict, component: un.Component) -> None:
    """``b`` with ``component`` added: u, U and k again (the instrument's: ``u_method`` kept); a one-sided
    budget's ``interval`` again from its value and the new U."""
    old = [un.Component(**{k: c[k] for k in ("name", "value", "unit", "u", "sensitivity", "basis", "dof") if k in c}) for c in b["components"]]
    b.update(un.budget(b["value"], b["unit"], [*old, component], note=b.get("note", "")))
    if b.get("one_sided") == "lower":
        b["interval"] = [b["value"], b["value"] + b["U"]]
    elif b.get("one_sided") == "upper":
        b["interval"] = [b["value"] - b["U"], b["value"]]

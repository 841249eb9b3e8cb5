"""ISO 6892-1 tensile results from an engineering stress–strain curve.

Rp0.2 by the offset method (intersection with the line of slope E through e = 0.2 %),
Rm (maximum force), Ag (plastic extension at maximum force, %), A (after fracture, %),
Z (reduction of area, standard (S0 − Su)/S0, %). Strains are engineering strains (ΔL/L),
stresses in MPa.
"""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError

# a single-step force drop larger than this fraction of Fm is the fracture
FRACTURE_DROP = 0.2


def nan_argmax(values) -> int:
    """np.nanargmax without its NaN-free copy of the array when there is no NaN (np.argmax
    returns the first NaN if there is one, else the same first maximum as nanargmax)."""
    values = np.asarray(values)
    i = int(np.argmax(values))
    return i if not np.isnan(values[i]) else int(np.nanargmax(values))


def first_index(condition, start: int, stop: int, chunk: int = 4096) -> int | None:
    """The first index i in [start, stop) where ``condition`` holds (None: nowhere); ``condition``
    maps a slice of the samples to booleans, evaluated over doubling chunks, so a crossing early
    in a long record (the elastic line's top, the 0.2 % offset) costs no pass over the rest."""
    while start < stop:
        end = min(stop, start + chunk)
        hit = condition(slice(start, end))
        i = int(np.argmax(hit))
        if hit[i]:
            return start + i
        start, chunk = end, 2 * chunk
    return None


def max_force_index(force_N) -> int:
    """Index of the maximum force Fm (the first one on a flat top)."""
    force = np.asarray(force_N, dtype=float)
    return nan_argmax(force)


def fracture_index(force_N, i_m: int | None = None) -> int:
    """Index of the last sample before fracture: the sample before the largest single-step
    force drop after Fm when that drop exceeds 20 % of Fm, else the last sample. ``i_m``: Fm's
    index (:func:`max_force_index`) when the caller has it."""
    force = np.asarray(force_N, dtype=float)
    i_m = max_force_index(force) if i_m is None else i_m
    tail = force[i_m:]
    if tail.size < 2:
        return force.size - 1
    drops = tail[:-1] - tail[1:]
    j = nan_argmax(drops)
    if drops[j] > FRACTURE_DROP * force[i_m]:
        return i_m + j
    return force.size - 1


def offset_yield_strength(strain, stress_MPa, E_MPa: float, offset: float = 0.002, *, start_MPa: float = 0.0) -> tuple[float, float]:
    """Proof strength Rp (offset method, ISO 6892-1 §13.1): the first point after ``start_MPa``
    where the curve crosses the line σ = E·(e − offset). Returns (Rp_MPa, fractional index)."""
    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    i_m = nan_argmax(s)
    def g(at):  # > 0 left of the offset line
        return s[at] - E_MPa * (e[at] - offset)

    begin = (first_index(lambda at: s[at] >= start_MPa, 0, s.size) or 0) if start_MPa > 0 else 0
    k = first_index(lambda at: g(at) <= 0, begin, i_m + 1)
    if k is None:
        raise IdentificationError(f"the curve never reaches {100 * offset:g} % plastic extension before maximum force: no Rp{100 * offset:g}")
    if k == 0:
        raise IdentificationError("the curve starts beyond the offset line: check the strain zero (toe)")
    x = g(k - 1) / (g(k - 1) - g(k))  # linear interpolation between k−1 and k
    return float(s[k - 1] + x * (s[k] - s[k - 1])), float(k - 1 + x)


def plastic_extension_pct(strain, stress_MPa, E_MPa: float):
    """Plastic extension in %: 100·(e − σ/E)."""
    return 100.0 * (np.asarray(strain, dtype=float) - np.asarray(stress_MPa, dtype=float) / E_MPa)


def gauge_extension_at_fracture(e_L, length_mm: float, l0_mm: float, a_u: float, s_f_MPa: float, E_MPa: float | None) -> float:
    """The gauge marks' engineering extension at fracture from e_L over the crosshead's length L ≥ L0, the neck
    within the marks and the rest of L uniform at the plastic elongation a_u, elastic at the fracture force:
    e_g = (e_L·L − (L − L0)·e_out)/L0, e_out = (1 + a_u)(1 + s_f(1 + a_u)/E) − 1 (true stress s_f(1 + a_u))."""
    elastic = s_f_MPa * (1.0 + a_u) / E_MPa if E_MPa else 0.0
    e_out = (1.0 + a_u) * (1.0 + elastic) - 1.0
    return float((e_L * length_mm - (length_mm - l0_mm) * e_out) / l0_mm)


MAD_SAMPLES = 50_000  # a longer series is read at an even stride: the median's own scatter is then ~0.5 % of σ


def mad_sigma(values) -> float:
    """A normal scatter's standard deviation from the median absolute deviation: 1.4826·MAD.
    Of the k-th differences of white noise σ, it gives σ·√C(2k, k) (√2, √6, √20 for k = 1, 2, 3).
    Over :data:`MAD_SAMPLES` values, every m-th value is taken (a one-hour record's noise in O(n/m))."""
    v = np.asarray(values, dtype=float)
    if v.size > MAD_SAMPLES:
        v = v[:: -(-v.size // MAD_SAMPLES)]
    return float(1.4826 * np.median(np.abs(v - np.median(v))))


def mad_sigma_of_differences(values, order: int) -> float:
    """:func:`mad_sigma` of ``np.diff(values, order)``, its k-th differences evaluated only where
    mad_sigma reads them (every m-th past :data:`MAD_SAMPLES`): the same number without k passes
    over a long record. Δᵏx[i] by np.diff's own recursion, Δᵏx[i] = Δᵏ⁻¹x[i + 1] − Δᵏ⁻¹x[i]."""
    v = np.asarray(values, dtype=float)
    size = v.size - order
    if size <= MAD_SAMPLES:
        return mad_sigma(np.diff(v, order))
    at = np.arange(0, size, -(-size // MAD_SAMPLES))
    parts = [v[at + j] for j in range(order + 1)]
    for _ in range(order):
        parts = [b - a for a, b in zip(parts[:-1], parts[1:])]
    return mad_sigma(parts[0])


def max_force_band(strain, stress_MPa, *, window: int = 50) -> tuple[float, float]:
    """(lowest, highest) strain of the samples within the noise of the maximum force: a flat
    maximum's plateau (ISO 6892-1 §13: Ag at its mid-point). Band: σ ≥ σ_max − 2√2·s, s the stress
    noise from third differences about the maximum, s = 1.4826·MAD(Δ³σ)/√20; noise-free, the
    maximum's own strain twice."""
    e, s = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    i_m = nan_argmax(s)
    near = s[max(i_m - window, 0): i_m + window + 1]
    d3 = np.diff(near[np.isfinite(near)], 3)  # a smooth curve's third differences vanish, the noise's do not
    if d3.size < 3:
        return float(e[i_m]), float(e[i_m])
    noise = mad_sigma(d3) / np.sqrt(20.0)  # Δ³ of white noise: variance 20 s²
    band = np.flatnonzero(s >= s[i_m] - 2.0 * np.sqrt(2.0) * noise)  # two noisy samples differ by √2·s
    return float(np.nanmin(e[band])), float(np.nanmax(e[band]))


def elongation_after_fracture_pct(l0_mm: float, lu_mm: float) -> float:
    """A = (Lu − L0)/L0 · 100 (3.8), from the gauge length measured after fracture."""
    if not lu_mm > 0 or not l0_mm > 0:
        raise IdentificationError(f"gauge lengths must be > 0 mm (L0 {l0_mm!r}, Lu {lu_mm!r})")
    return 100.0 * (lu_mm - l0_mm) / l0_mm


def reduction_of_area_pct(s0_mm2: float, su_mm2: float) -> float:
    """Z = (S0 − Su)/S0 · 100 — the standard form ((3.9) prints /Su, a misprint)."""
    if not 0 < su_mm2 <= s0_mm2:
        raise IdentificationError(f"the area after fracture {su_mm2!r} mm² must be > 0 and not larger than the original {s0_mm2!r} mm²: check post.dk_mm")
    return 100.0 * (s0_mm2 - su_mm2) / s0_mm2


# ISO 6892-1 3.10.2.1: ReH is the stress "at the moment when the first decrease in force is observed".
# Observed = beats the noise: a drop by more than YIELD_DROP_NOISE noise standard deviations (and this
# fraction of the stress, for a record too smooth or too coarse to show its noise) that lasts two samples
# (docs/methods.md §3.3a: why 0.2 %, measured on the 42CrMoS4 set)
YIELD_DROP = 0.002
# 6, not 3: where the stress rises slowly against its noise (a seating toe sampled at 100 Hz) the
# running maximum rides the noise's peaks, and two samples 3 σ under it came by chance (a "ReH" of 98 MPa)
YIELD_DROP_NOISE = 6.0
MAX_YIELD_POINT_EXTENSION_PCT = 0.5  # a force maximum this early is the onset of yield, not of necking


def yield_point(strain, stress_MPa, *, noise_MPa: float = 0.0, E_MPa: float | None = None, start_MPa: float = 0.0) -> dict | None:
    """Upper and lower yield strength and the yield point extension (ISO 6892-1 3.10.2, 3.7.4).

    ReH: the maximum stress before the first drop of more than 6 noise standard deviations
    (and 0.2 % of the stress) that lasts two samples — searched before the maximum force (over the whole record when, with
    ``E_MPa``, the maximum force lies within 0.5 % plastic extension: the record ends on the
    plateau). ReL: the lowest stress on the yield plateau,
    the initial transient (from ReH to the local maximum after the first minimum) disregarded
    unless nothing else is left. Ae: the extension from ReH to the start of uniform work hardening — the last sample up
    to Fm still within the plateau band (ReL + half the drop, at most 2 % of ReL, at least 3
    noise deviations), in % of the gauge length. None when the curve has no yield point.
    ``start_MPa``: ReH lies above it (give the start of the fitted elastic line, not its top, which
    can reach ReH: a dip below the start is noise at zero force or in the toe, not yield); with ``E_MPa``, ReH lies within 0.5 % plastic
    extension (a later drop is a relaxation in a pause). A search on to the record's end stops at the
    fracture; a stress that falls to zero after the maximum is no plateau (None).
    Returns ReH_MPa, ReL_MPa, Ae_pct and the sample indices of ReH and of the plateau end.
    """
    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    i_m = nan_argmax(s)
    if E_MPa is not None and i_m + 1 < s.size and 100.0 * (e[i_m] - s[i_m] / E_MPa) <= MAX_YIELD_POINT_EXTENSION_PCT:
        i_m = fracture_index(s)  # the largest force at the onset of yield: an upper yield point, the record may end on the plateau
    head = s[: i_m + 1]
    run = np.maximum.accumulate(head)
    threshold = np.maximum(YIELD_DROP * run, YIELD_DROP_NOISE * noise_MPa)
    below = (run - head > threshold) & (run > start_MPa)
    if not np.any(below[:-1] & below[1:]):
        return None  # no drop that lasts (the test below only narrows them): no yield point
    if E_MPa is not None:  # ReH ends the elastic line: a drop from a maximum beyond 0.5 % plastic extension is a relaxation (a pause), not yield
        at_max = np.maximum.accumulate(np.where(head >= run, np.arange(head.size), 0))
        below &= 100.0 * (e[at_max] - run / E_MPa) <= MAX_YIELD_POINT_EXTENSION_PCT
    drops = np.nonzero(below[:-1] & below[1:])[0]  # a drop that lasts: a lone low sample is a bad frame, not yield
    if drops.size == 0:
        return None
    j = int(drops[0])
    i_h = int(np.argmax(head[:j]))
    if i_h == 0:
        return None
    reh = float(s[i_h])
    # the rest of the curve up to Fm, and the first local minimum after ReH (the transient)
    after = s[i_h + 1: i_m + 1]
    if after.size < 2:
        return None
    d = np.diff(after)
    rising = np.nonzero(d > 0)[0]
    first_min = int(rising[0]) if rising.size else after.size - 1
    falling = np.nonzero(d[first_min:] < 0)[0]  # the transient ends at the next local maximum
    transient_end = first_min + int(falling[0]) if falling.size else first_min
    band_of = lambda low: low + float(np.clip(0.5 * (reh - low), 3.0 * noise_MPa, 0.02 * low))  # noqa: E731
    level = float(np.min(after))
    if not level > 0:
        return None  # the stress falls to zero (unloaded, broken): no Lüders plateau
    top = band_of(level)
    within = np.nonzero(after <= top)[0]
    end = int(within[-1])  # the last sample on the plateau
    plateau = after[transient_end + 1: end + 1]
    rel = float(np.min(plateau)) if plateau.size else float(np.min(after[: end + 1]))
    i_end = i_h + 1 + end
    return {"ReH_MPa": reh, "ReL_MPa": rel, "Ae_pct": float(100.0 * (e[i_end] - e[i_h])),
            "ReH_index": i_h, "plateau_end_index": i_end}

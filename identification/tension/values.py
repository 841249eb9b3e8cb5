"""Tension's options and the values of one record (docs/methods.md §2–§3): true stress and plastic
strain, the fracture index, the fracture point's variant, whether the specimen broke."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError
from flowcurve.identification import iso6892
from flowcurve.identification.laws.hardening import MAX_STRAIN, MAX_STRESS_MPa


TRUE_STRESS_FORMS = ("constant_volume", "gost_3_6")  # the default first; the seed's (3.6) for comparison
HARDENING_METHODS = ("least_squares", "three_point")
MODULUS_REFERENCES = ("Rp02", "Rm")
FIT_POINTS = 30  # the uniform range is resampled to this many points, evenly in εp
MIN_YIELD_OFFSET = 0.002
FRACTURE_POINT_MODES = ("auto", "include", "exclude")
MAX_E_UNCERTAINTY = 0.10  # a regressed E less certain than this (relative standard error) is no modulus
# auto: the fracture point may cost the uniform range at most this much max error (percentage points)
FRACTURE_POINT_SLACK_PCT = 2.0
# a record ending below this fraction of Fm, after Fm, has reached fracture (an export cut at
# the break, as Bluehill writes it, ends at 0.68–0.86 Fm on the 42CrMoS4 records); one ending
# above it was stopped before fracture, unless it shows the break as a force drop
FRACTURE_END_FORCE = 0.9
# a record ending below this fraction of Fm went on past the break (the force fell to the
# unloaded level); its break may be spread over several samples by the amplifier's filter
BROKEN_END_FORCE = 0.2
# (3.6) against constant volume at Fm: a larger split is reported (≈ ε_u²/2: 2 % at ε_u 0.2)
TRUE_STRESS_SPLIT_PCT = 2.0


def true_stress_gost(eng_stress_MPa, log_strain, K_MPa: float):
    """True stress with the lateral contraction of (3.4)–(3.5), the corrected (3.6):
    σ_t = (3K/2)·[√((1 − ε)² + (4/3)·σ_e/K) − (1 − ε)]."""
    one_minus = 1.0 - np.asarray(log_strain, dtype=float)
    s = np.asarray(eng_stress_MPa, dtype=float)
    # (3.6) corrected: factor 3K/2, not 2/(3K). Written as 2σ_e/(√(...) + (1 − ε)) to avoid
    # cancellation when σ_e ≪ K (identical algebraically).
    return 2.0 * s / (np.sqrt(one_minus**2 + (4.0 / 3.0) * s / K_MPa) + one_minus)


def true_stress_constant_volume(eng_stress_MPa, eng_strain):
    """True stress at constant volume: σ_t = σ_e·(1 + e)."""
    return np.asarray(eng_stress_MPa, dtype=float) * (1.0 + np.asarray(eng_strain, dtype=float))


def true_plastic_strain(log_strain, true_stress_MPa, E_MPa: float):
    """True plastic strain (3.7): εp = ε − σ_t/E."""
    return np.asarray(log_strain, dtype=float) - np.asarray(true_stress_MPa, dtype=float) / E_MPa


def bulk_modulus(E_MPa: float, poisson: float) -> float:
    """K = E/(3(1 − 2ν))."""
    if not -1.0 < poisson < 0.5:
        raise IdentificationError(f"Poisson's ratio must lie in (-1, 0.5), got {poisson!r}")
    return E_MPa / (3.0 * (1.0 - 2.0 * poisson))


def uniform_error_pct(fit, eps_p, stress_MPa) -> float:
    """Max |σ_fit/σ − 1| over the uniform range only, % (the fracture point left out)."""
    return float(100 * np.max(np.abs(fit(eps_p) / stress_MPa - 1.0)))


def choose_fracture_variant(pair: dict, eps_p, stress_MPa, mode: str) -> tuple[str, str]:
    """Which fit of a law to report: "with" or "without" the fracture point, and why.

    auto: with it, unless its max error over the uniform range exceeds the fit without it by
    more than FRACTURE_POINT_SLACK_PCT (the uniform range is not sacrificed to one point)."""
    if "with" not in pair:
        return "without", "no fracture point"
    if mode == "include":
        return "with", "fracture point included (option)"
    if mode == "exclude":
        return "without", "fracture point excluded (option)"
    e_with = uniform_error_pct(pair["with"], eps_p, stress_MPa)
    e_without = uniform_error_pct(pair["without"], eps_p, stress_MPa)
    if e_with <= e_without + FRACTURE_POINT_SLACK_PCT:
        return "with", f"included: uniform-range max error {e_with:.2f} % with it, {e_without:.2f} % without"
    return "without", (f"excluded: with it the uniform-range max error would be {e_with:.2f} % instead of {e_without:.2f} % "
                       "(the law cannot pass through both; see hardening_alternatives)")


def _two_numbers(value, name: str, what: str, upper: float) -> tuple[float, float] | None:
    """(lo, hi) with 0 ≤ lo < hi ≤ upper from an option, or None; else a one-line error naming it."""
    if value is None:
        return None
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise IdentificationError(f"{name} must be two {what} LO,HI, got {value!r}") from None
    if not (0 <= lo < hi <= upper):
        raise IdentificationError(f"{name} must satisfy 0 ≤ LO < HI ≤ {upper:g} ({what}), got {value!r}")
    return lo, hi


def _check_window(window, name: str, *, fractions: bool) -> tuple[float, float] | None:
    """A (lo, hi) modulus window: fractions 0 ≤ lo < hi ≤ 1, or MPa 0 ≤ lo < hi; or None."""
    return _two_numbers(window, name, "fractions" if fractions else "stresses in MPa", 1.0 if fractions else MAX_STRESS_MPa)


def check_fit_range(fit_range) -> tuple[float, float] | None:
    """A (lo, hi) plastic-strain range with 0 ≤ lo < hi, or None."""
    return _two_numbers(fit_range, "fit_range", "plastic strains (fractions)", MAX_STRAIN)


def _increasing(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keep the points where x strictly exceeds every earlier x (noise makes εp wobble)."""
    keep = np.ones(x.size, dtype=bool)
    keep[1:] = x[1:] > np.maximum.accumulate(x)[:-1]
    return np.compress(keep, x), np.compress(keep, y)  # x[keep], y[keep]: a noisy mask, which boolean indexing takes branch by branch


def fracture_index(force_N) -> int:
    """The last sample before fracture: :func:`iso6892.fracture_index`, except for a break the
    load cell's low-pass filter spread over several samples — no single step above 20 % of Fm,
    the record ending below BROKEN_END_FORCE × Fm —, where it is the sample before the largest
    step after Fm: a first-order filter's first step after a sudden drop is its largest."""
    force = np.asarray(force_N, dtype=float)
    i_m = iso6892.max_force_index(force)
    i_k = iso6892.fracture_index(force, i_m)
    if i_k < force.size - 1 or force.size - i_m < 3 or not force[-1] <= BROKEN_END_FORCE * force[i_m]:
        return i_k
    return i_m + int(np.nanargmax(force[i_m:-1] - force[i_m + 1:]))


def reaches_fracture(force_N: np.ndarray, i_k: int | None = None) -> bool:
    """Does the record reach fracture: a single-step drop of more than 20 % of Fm after Fm
    (the break), or a last force below FRACTURE_END_FORCE × Fm (a necked specimen, the
    record cut at the break)? ``i_k``: :func:`fracture_index` of ``force_N`` when the caller has it."""
    i_k = fracture_index(force_N) if i_k is None else i_k
    Fm = float(np.nanmax(force_N))
    return i_k < force_N.size - 1 or float(force_N[-1]) <= FRACTURE_END_FORCE * Fm


FRACTURE_KEYS = ("post.lu_mm", "post.dk_mm", "post.sk_mm2", "post.neck_radius_mm")  # measured on the broken halves


def unbroken_statement(record: Record) -> str | None:
    """The record's own word that its specimen did not break, or None: a ``stop_reason`` naming
    another end (a target, a force limit, a stop) with a force that shows no break
    (:func:`reaches_fracture`)."""
    reason = " ".join(str(record.meta.get("stop_reason") or "").split())
    if not reason or "fracture" in reason.lower() or not record.has("force_N"):
        return None
    force = record.column("force_N")
    force = force[np.isfinite(force)]
    return None if force.size < 3 or reaches_fracture(force) else reason


def without_fracture_values(record: Record) -> tuple[Record, list[str]]:
    """An unbroken specimen has no fracture values: the record without them (post.lu_mm, dk, sk,
    neck radius — an unbroken bar's are no A, Z or fracture point), and the warning saying why."""
    stopped = unbroken_statement(record)
    if stopped is None:
        return record, []
    given = [k for k in FRACTURE_KEYS if k in record.meta]
    kept = replace(record, meta={k: v for k, v in record.meta.items() if k not in FRACTURE_KEYS})
    left_out = f"; {', '.join(given)} left out (not fracture values)" if given else ""
    return kept, [f"the specimen did not break (the test ended on: {stopped[:120]}): no A, no Z and no fracture point"
                  f"{left_out}; the rest is reported"]

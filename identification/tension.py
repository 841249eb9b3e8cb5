"""Tension identification (docs/methods.md §2–§3, seed 3.1.2): record → ISO 6892-1 results, true
stress–strain curve, neck-corrected fracture point and hardening law.

The strain comes from the extensometer when the record has one (``use_extensometer=None``
decides automatically), otherwise from the crosshead: frame compliance removed (§2.1), toe
compensated, and scaled to the measured elongation post.lu_mm when it was measured (3.1).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification import iso6892
from flowcurve.record.summary import record_summary
from flowcurve.identification.elastic_modulus import apparent_modulus_warning, choose_modulus, tension_E_source
from flowcurve.identification.hardening import MAX_STRAIN, MAX_STRESS_MPa, HardeningFit, fit_hardening, three_point_fit
from flowcurve.identification.indicator import DEFAULT_MODULUS_METHOD, FEW_SAMPLES, ModulusFit, elastic_modulus, reread_if_stepped, strain_quantum_noise, yield_onset_from_rate, compensate_toe, fit_modulus, remove_frame_compliance, scale_to_measured
from flowcurve.identification.necking import METHODS as NECK_METHODS
from flowcurve.identification.necking import neck_corrections
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import TensionHardening, TensionResult
from flowcurve.identification.strain_zero import apply_to_fit, tension_or_compression_zero

logger = logging.getLogger(__name__)

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
    return x[keep], y[keep]


def fracture_index(force_N) -> int:
    """The last sample before fracture: :func:`iso6892.fracture_index`, except for a break the
    load cell's low-pass filter spread over several samples — no single step above 20 % of Fm,
    the record ending below BROKEN_END_FORCE × Fm —, where it is the sample before the largest
    step after Fm: a first-order filter's first step after a sudden drop is its largest."""
    force = np.asarray(force_N, dtype=float)
    i_k = iso6892.fracture_index(force)
    i_m = iso6892.max_force_index(force)
    if i_k < force.size - 1 or force.size - i_m < 3 or not force[-1] <= BROKEN_END_FORCE * force[i_m]:
        return i_k
    return i_m + int(np.nanargmax(force[i_m:-1] - force[i_m + 1:]))


def reaches_fracture(force_N: np.ndarray) -> bool:
    """Does the record reach fracture: a single-step drop of more than 20 % of Fm after Fm
    (the break), or a last force below FRACTURE_END_FORCE × Fm (a necked specimen, the
    record cut at the break)?"""
    i_k = fracture_index(force_N)
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


def _check_post_dimensions(record: Record, d0: float, l0: float, lu: float | None) -> None:
    """Measurements after fracture that no tension test can give: Lu < L0, du or dk > d0."""
    if lu is not None and lu < l0:
        raise RecordError(record.source, f"Lu = {lu:g} mm (post.lu_mm, --lu) is shorter than L0 = {l0:g} mm (specimen.l0_mm, --l0): a specimen does not shorten in tension")
    for name in ("du", "dk"):
        d = record.positive(f"post.{name}_mm")
        if d is not None and d > d0:
            raise RecordError(record.source, f"{name} = {d:g} mm (post.{name}_mm{', --dk' if name == 'dk' else ''}) is larger than d0 = {d0:g} mm (specimen.d0_mm, --d0): a specimen does not thicken in tension")


def _why_no_fit(hardening: str, law: str, fracture: dict, sig_t_rp: float | None, warnings: list[str]) -> str:
    """Why a fit is missing: the input it lacks only when that input is missing, else its failure."""
    if hardening == "three_point" and not fracture:
        return "it needs the fracture point: post.dk_mm (--dk) or post.sk_mm2"
    if hardening == "three_point" and sig_t_rp is None:
        return "it needs Rp0.2 on the true curve, and the uniform range does not reach 0.2 % plastic strain"
    failed = [w for w in warnings if w.startswith(f"{hardening.replace('_', '-')} {law} fit failed")]
    return failed[-1] if failed else "no fit was made"


def _strain_source(record: Record, use_extensometer: bool | None, force: np.ndarray, l0: float, options: dict) -> dict:
    """Displacement (mm), the length it refers to (mm) and how it was obtained."""
    has_ext = record.has("extensometer_mm")
    if use_extensometer and not has_ext:
        raise RecordError(record.source, "use_extensometer was requested but the record has no extensometer channel", column="extensometer_mm")
    warnings: list[str] = []
    if has_ext and use_extensometer is not False:
        ext = record.column("extensometer_mm")
        gaps = np.nonzero(~np.isfinite(ext[: fracture_index(force) + 1]))[0]
        if gaps.size:
            message = f"the extensometer channel has no value from sample {gaps[0] + 1} on (removed before fracture?)"
            if not record.has("crosshead_mm"):
                raise RecordError(record.source, message + "; the record has no crosshead column to identify from instead", column="extensometer_mm")
            if use_extensometer:
                raise RecordError(record.source, message + "; identify from the crosshead instead (use_extensometer=False)", column="extensometer_mm")
            fallback = _strain_source(record, False, force, l0, options)
            fallback["warnings"].insert(0, message + ": the crosshead is used instead")
            return fallback
        gauge = record.positive("specimen.extensometer_gauge_mm", default=l0)
        if "specimen.extensometer_gauge_mm" not in record.meta:
            warnings.append(f"specimen.extensometer_gauge_mm missing: the extensometer gauge length is taken as l0 = {l0:g} mm")
        return {"disp": ext - ext[0], "length": gauge, "source": "extensometer", "stiffness": None, "scalable": False, "warnings": warnings}
    if not record.has("crosshead_mm"):
        raise RecordError(record.source, "the record has no crosshead column: its strain can only come from the extensometer (leave out --no-extensometer)", column="crosshead_mm")
    cross = record.column("crosshead_mm")
    gaps = np.nonzero(~np.isfinite(cross[: fracture_index(force) + 1]))[0]
    if gaps.size:
        raise RecordError(record.source, f"the crosshead channel has no value at sample {gaps[0] + 1} (of {gaps.size} before fracture); the strain cannot be followed through the gap", column="crosshead_mm")
    step = None
    if record.has("time_s"):  # a 10 µm count is 3e-4 of a 30 mm length: re-read between counts
        cross, step = reread_if_stepped(record.column("time_s"), cross)
    disp = cross - cross[0]
    stiffness = options.get("frame_stiffness_N_per_um")
    if stiffness is None:
        stiffness = record.positive("rig.frame_stiffness_N_per_um")
    if stiffness is not None:
        disp = remove_frame_compliance(disp, force - force[0], stiffness)
    else:
        warnings.append("no frame stiffness (rig.frame_stiffness_N_per_um): the crosshead displacement still includes the frame; strains and E are not the specimen's")
    length = options.get("crosshead_length_mm") or record.positive("specimen.parallel_length_mm", default=l0)
    return {"disp": disp, "length": float(length), "source": "crosshead", "stiffness": stiffness, "scalable": True, "warnings": warnings,
            "step_mm": step}


@dataclass
class _Inputs:
    """What the record gives: geometry, the force (finite samples only), stress, strain source."""

    record: Record
    d0: float
    l0: float
    s0: float
    data: pd.DataFrame  # the samples with a force value
    sub: Record  # the record of those samples
    force: np.ndarray
    eng_stress: np.ndarray
    i_m: int  # index of the maximum force
    Fm: float
    Rm: float
    src: dict  # :func:`_strain_source`: displacement, its length, how it was obtained
    lu: float | None
    length: float  # the length the strain refers to (l0 when scaled to a measured Lu)
    warnings: list[str]
    unbroken: bool = False  # the record says the specimen did not break (:func:`unbroken_statement`)


@dataclass
class _ElasticLine:
    """E, Rp0.2 and the strain they define (toe-compensated, scaled)."""

    E: float
    mod: ModulusFit
    Rp02: float
    window_MPa: tuple[float, float]
    disp: np.ndarray  # corrected elongation, mm
    strain: np.ndarray  # engineering strain
    toe_mm: float
    scale_factor: float | None
    noise_MPa: float
    warnings: list[str]


@dataclass
class _IsoResults:
    """ISO 6892-1 results beyond Rp0.2: yield point, Ag, A, Z."""

    yp: dict | None
    e_m: float  # engineering strain at Fm
    Ag: float
    i_k: int  # index of the fracture
    A: float | None
    A_method: str | None
    At: float | None  # total extension at fracture, %
    su: float | None  # area after fracture, mm²
    su_source: str | None
    dk: float | None
    Z: float | None
    warnings: list[str]


@dataclass
class _TrueCurve:
    """True strain, stress and plastic strain; the uniform range up to Fm, increasing in εp."""

    strain: np.ndarray  # the specimen's engineering strain (the line's, unless its slope is apparent)
    log_strain: np.ndarray
    sig_t: np.ndarray
    eps_p: np.ndarray
    eps_u: float  # true strain at Fm
    ep_u: np.ndarray  # the uniform range, εp strictly increasing
    sig_u: np.ndarray
    curve: pd.DataFrame  # the flow curve from Rp0.2 on (true_curve.csv)
    sig_t_rp: float | None  # true stress at 0.2 % plastic strain
    eps_p_at_Rm: float
    E_specimen: float  # the E that strips the specimen's elastic strain (∞: left out)
    warnings: list[str]


@dataclass
class _Hardening:
    """The hardening fits: the main one, the alternatives, and the points they were fitted to."""

    grid: np.ndarray
    fit_sig: np.ndarray
    weight: float
    extra: list
    three_points: list | None
    fits: dict
    variants: dict
    main_key: str
    main: HardeningFit
    main_fracture: tuple
    warnings: list[str]
    start: dict | None = None  # the curve's start as far as it rests on the strain zero (§2.11)


def _check_options(*, true_stress, neck, hardening, modulus_reference, fracture_point, fit_range, modulus_window, modulus_window_MPa):
    """The options, checked: (fit_range, modulus window fractions, modulus window MPa)."""
    if true_stress not in TRUE_STRESS_FORMS:
        raise IdentificationError(f"true_stress must be one of {', '.join(TRUE_STRESS_FORMS)}, not {true_stress!r}")
    if neck not in NECK_METHODS:
        raise IdentificationError(f"neck must be one of {', '.join(NECK_METHODS)}, not {neck!r}")
    if hardening not in HARDENING_METHODS:
        raise IdentificationError(f"hardening must be one of {', '.join(HARDENING_METHODS)}, not {hardening!r}")
    if modulus_reference not in MODULUS_REFERENCES:
        raise IdentificationError(f"modulus_reference must be one of {', '.join(MODULUS_REFERENCES)}, not {modulus_reference!r}")
    if fracture_point not in FRACTURE_POINT_MODES:
        raise IdentificationError(f"fracture_point must be one of {', '.join(FRACTURE_POINT_MODES)}, not {fracture_point!r}")
    fit_range = check_fit_range(fit_range)
    fractions = _check_window(modulus_window, "modulus_window", fractions=True)
    window_fixed_MPa = _check_window(modulus_window_MPa, "modulus_window_MPa", fractions=False)
    if fractions is not None and window_fixed_MPa is not None:
        raise IdentificationError("give modulus_window (fractions) or modulus_window_MPa, not both")
    return fit_range, fractions, window_fixed_MPa


SPIKE_NOISE_FACTOR, SPIKE_FRACTION = 12.0, 0.25  # a lone force sample this far (× noise σ, × peak force) from its agreeing neighbours is corrupt: farther than an upper yield point stands


def isolated_force_spikes(force_N) -> np.ndarray:
    """Indices of lone corrupt force samples: unlike both neighbours, which agree with each other
    (no specimen's force jumps and comes back within one sample; a fracture does not come back).
    |F_k − (F_k−1 + F_k+1)/2| > max(12 σ, 25 % of the peak of the 3-sample median) and
    |F_k+1 − F_k−1| < a quarter of that; σ from second differences (robust)."""
    f = np.asarray(force_N, dtype=float)
    if f.size < 5:
        return np.zeros(0, dtype=int)
    deviation = np.abs(f[1:-1] - 0.5 * (f[:-2] + f[2:]))
    gap = np.abs(f[2:] - f[:-2])
    a, b, c = f[:-2], f[1:-1], f[2:]
    peak = float(np.max(np.abs(np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c)))))  # median of three, in closed form
    if not np.any((deviation > SPIKE_FRACTION * peak) & (gap < 0.25 * deviation)):
        return np.zeros(0, dtype=int)  # none beyond the peak share: none beyond the larger threshold either (the noise median is not needed)
    threshold = max(SPIKE_NOISE_FACTOR * _stress_noise_MPa(f), SPIKE_FRACTION * peak)
    return np.flatnonzero((deviation > threshold) & (gap < 0.25 * deviation)) + 1


def _inputs(record: Record, *, use_extensometer, frame_stiffness_N_per_um, crosshead_length_mm, scale: bool) -> _Inputs:
    """Geometry, force and engineering stress, and the strain source of a tension record."""
    warnings: list[str] = []
    d0 = record.positive("specimen.d0_mm", required=True)
    l0 = record.positive("specimen.l0_mm", required=True)
    s0 = record.positive("specimen.s0_mm2", default=math.pi * d0**2 / 4.0)  # F0 = π d0²/4
    force = record.column("force_N")
    ok = np.isfinite(force)
    if not ok.all():
        warnings.append(f"{int((~ok).sum())} samples without a force value were left out")
    spikes = np.flatnonzero(ok)[isolated_force_spikes(force[ok])]
    if spikes.size:
        ok[spikes] = False
        warnings.append(f"{spikes.size} force sample(s) unlike both neighbours (a corrupt load-cell frame) left out: "
                        + ", ".join(f"sample {k + 1} ({force[k]:.6g} N)" for k in spikes[:5]) + (" …" if spikes.size > 5 else ""))
    data = (record.data[ok] if not ok.all() else record.data).reset_index(drop=True)  # all kept: no copy (copy-on-write)
    force = force[ok]
    sub = Record(meta=record.meta, data=data, source=record.source)
    i_m = iso6892.max_force_index(force)
    Fm = float(force[i_m])
    if Fm <= 0 or i_m == 0 or Fm - force[0] <= 0.05 * abs(Fm):
        raise RecordError(record.source, "the force never rises: no tension test in this record (check the force column and its sign)", column="force_N")
    eng_stress = force / s0
    Rm = Fm / s0
    if Rm > MAX_STRESS_MPa:
        raise IdentificationError(f"{record.source}: Rm = {Rm:.4g} MPa is implausible - check units of force (N) and diameter (mm)")

    src = _strain_source(sub, use_extensometer, force, l0, {"frame_stiffness_N_per_um": frame_stiffness_N_per_um, "crosshead_length_mm": crosshead_length_mm})
    warnings += src["warnings"]
    lu = record.positive("post.lu_mm")
    _check_post_dimensions(record, d0, l0, lu)
    length = src["length"]
    if src["scalable"] and scale and lu is not None:
        if lu <= l0:
            raise IdentificationError(f"{record.source}: post.lu_mm = {lu:g} mm is not longer than l0 = {l0:g} mm")
        length = l0
    return _Inputs(record=record, d0=d0, l0=l0, s0=s0, data=data, sub=sub, force=force, eng_stress=eng_stress, i_m=i_m,
                   Fm=Fm, Rm=Rm, src=src, lu=lu, length=length, warnings=warnings)


def _stress_noise_MPa(stress_MPa: np.ndarray) -> float:
    """Noise standard deviation of a stress signal from its second differences (robust MAD)."""
    curvature = np.diff(stress_MPa, 2)  # second differences: a linear trend leaves none, white noise σ leaves σ√6
    return float(1.4826 * np.median(np.abs(curvature - np.median(curvature))) / math.sqrt(6.0)) if curvature.size else 0.0


def _first_guesses(inp: _Inputs, automatic: bool) -> list[float]:
    """Yield stresses to start the automatic window from: the force rate's onset (if any), then Rm."""
    first_guesses = [inp.Rm]  # when the first guess leaves too few samples on the elastic line
    if automatic and inp.record.has("time_s"):
        try:  # a yield guess from the force rate (constant speed): a sparse elastic line needs a good one
            onset = yield_onset_from_rate(inp.data["time_s"].to_numpy(float)[: inp.i_m + 1], inp.force[: inp.i_m + 1]) / inp.s0
            if 0 < onset <= inp.Rm:
                first_guesses.insert(0, onset)
        except IdentificationError as exc:
            logger.debug("no yield estimate from the force rate: %s", exc)
    return first_guesses


def _modulus_window(step: int, ref: float, first_guesses: list[float], strain0, eng_stress, *, fractions, window_fixed_MPa,
                    modulus_reference: str, noise_MPa: float, strain_noise: float, method: str = DEFAULT_MODULUS_METHOD,
                    crosshead: bool = False):
    """The stress window of the elastic line at one step: given (MPa, or × the reference stress) or
    the most linear stretch; returns (window_MPa, line_points, how, auto fit or None, reference)."""
    if window_fixed_MPa is not None:
        return window_fixed_MPa, 5, "given window (MPa)", None, ref
    if fractions is not None:
        return (fractions[0] * ref, fractions[1] * ref), 5, f"given window {fractions[0]:g}–{fractions[1]:g} × {modulus_reference}", None, ref
    try:
        auto = elastic_modulus(method, strain0, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise, crosshead=crosshead)  # the window is the same before toe and scaling
    except IdentificationError:
        if step > 0 or not first_guesses:
            raise
        while True:  # a sparse elastic line may hold too few samples below the first guess
            ref = first_guesses.pop(0)
            try:
                auto = elastic_modulus(method, strain0, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise, crosshead=crosshead)
                break
            except IdentificationError:
                if not first_guesses:
                    raise
    return auto.window_MPa, min(auto.n_points, 5), auto.source, auto, ref


def _resolved(mod: ModulusFit) -> bool:
    """A regressed E known to within :data:`MAX_E_UNCERTAINTY` (relative standard error)."""
    return bool(mod.E_stderr_MPa <= MAX_E_UNCERTAINTY * mod.E_MPa)


def _chosen_modulus(mod: ModulusFit, E_MPa: float | None, handbook_E: float | None, given_window: bool) -> float:
    """The E used: the option, else the handbook's when the line has few samples, else the regressed
    one; ``mod.source`` says which."""
    if E_MPa is not None:
        E, mod.source = float(E_MPa), "option E_MPa"
    elif handbook_E is not None and not given_window and mod.n_points < FEW_SAMPLES:
        E, mod.source = handbook_E, f"handbook material.E_MPa (only {mod.n_points} samples on the elastic line)"
    else:
        E = mod.E_MPa
    return E


def _line_without_samples(inp: _Inputs, E: float, why: str, *, scale: bool, noise_MPa: float) -> _ElasticLine:
    """No elastic line in the record (too few samples before the yield): the given or handbook E
    strips the elastic strain, the toe is not compensated (there is no line to find it on)."""
    disp, scale_factor = inp.src["disp"], None
    if inp.src["scalable"] and scale and inp.lu is not None:
        disp, scale_factor = scale_to_measured(disp, inp.lu - inp.l0)  # (3.1) K_l = Δl_p / max Δl
    strain = disp / inp.length
    if np.nanmax(np.abs(strain)) > MAX_STRAIN:
        raise IdentificationError(f"{inp.record.source}: engineering strain up to {np.nanmax(strain):.4g} is implausible - check units of the displacement (mm) and l0 (mm)")
    mod = ModulusFit(math.nan, math.nan, math.nan, math.nan, 0, (0.0, 0.0), source=f"given or handbook E (no elastic line: {why})")
    Rp02, _ = iso6892.offset_yield_strength(strain, inp.eng_stress, E, MIN_YIELD_OFFSET)
    warnings = [f"no elastic line ({why}): the toe is not compensated and Rp0.2 and the start of the flow curve rest on "
                f"the given E = {E:.4g} MPa alone"]
    return _ElasticLine(E=E, mod=mod, Rp02=Rp02, window_MPa=(0.0, 0.0), disp=disp, strain=strain, toe_mm=0.0,
                        scale_factor=scale_factor, noise_MPa=noise_MPa, warnings=warnings)


def _elastic_line(inp: _Inputs, *, fractions, window_fixed_MPa, modulus_reference: str, E_MPa: float | None,
                  toe: bool, scale: bool, modulus_method: str = DEFAULT_MODULUS_METHOD) -> _ElasticLine:
    """E, the toe and Rp0.2, which depend on each other through the window: iterated to a fixed point."""
    record, force, eng_stress, i_m, length, src = inp.record, inp.force, inp.eng_stress, inp.i_m, inp.length, inp.src
    automatic = fractions is None and window_fixed_MPa is None
    ref = 0.5 * inp.Rm if modulus_reference == "Rp02" else inp.Rm
    first_guesses = _first_guesses(inp, automatic)
    noise_MPa = _stress_noise_MPa(eng_stress[: i_m + 1])
    raw_channel = "extensometer_mm" if src["source"] == "extensometer" else "crosshead_mm"
    strain_noise = strain_quantum_noise(inp.sub.column(raw_channel)[: i_m + 1] / length)  # the encoder's quantum, before the compliance
    # the handbook E is the material's; a crosshead diagram without the frame's stiffness has the frame's compliance in its slope
    apparent = src["source"] == "crosshead" and src["stiffness"] is None
    handbook_E = record.positive("material.E_MPa") if E_MPa is None and not apparent else None
    disp0 = src["disp"]
    toe_mm, scale_factor = 0.0, None
    unresolved = None  # the line's fit when it was not resolved and the handbook E took its place (kept from then on)
    for step in range(6):
        try:
            window_MPa, line_points, how, auto, ref = _modulus_window(
                step, ref, first_guesses, disp0 / length, eng_stress, fractions=fractions, window_fixed_MPa=window_fixed_MPa,
                modulus_reference=modulus_reference, noise_MPa=noise_MPa, strain_noise=strain_noise, method=modulus_method,
                crosshead=src["source"] != "extensometer")
        except IdentificationError as exc:
            if unresolved is None:
                if automatic and (E_MPa is not None or handbook_E is not None):  # no line to be found: the E given
                    return _line_without_samples(inp, E_MPa if E_MPa is not None else handbook_E, str(exc), scale=scale, noise_MPa=noise_MPa)
                raise
            break  # no line below the handbook E's Rp0.2 either: the last step's window and Rp0.2 stand
        disp = disp0
        if toe:
            disp, toe_mm = compensate_toe(disp0, force, window_N=(window_MPa[0] * inp.s0, window_MPa[1] * inp.s0), min_points=line_points)
        if src["scalable"] and scale and inp.lu is not None:
            disp, scale_factor = scale_to_measured(disp, inp.lu - inp.l0)  # (3.1) K_l = Δl_p / max Δl
        strain = disp / length
        mod = fit_modulus(strain, eng_stress, window_MPa, min_points=line_points)
        mod.source = how
        if auto is not None:
            mod.quality = auto.quality
            mod.sdar_failed = auto.sdar_failed
            mod.E_stderr_MPa = max(mod.E_stderr_MPa, auto.E_stderr_MPa * mod.E_MPa / auto.E_MPa) if np.isfinite(mod.E_stderr_MPa) else auto.E_stderr_MPa
        E = _chosen_modulus(mod, E_MPa, handbook_E, given_window=not automatic)
        if unresolved is None and handbook_E is not None and E == mod.E_MPa and not _resolved(mod):
            unresolved = replace(mod)
        if unresolved is not None:
            E, mod.source = handbook_E, (f"handbook material.E_MPa (the elastic line is not resolved: E = {unresolved.E_MPa:.4g} ± "
                                         f"{unresolved.E_stderr_MPa:.2g} MPa from {unresolved.n_points} samples, {unresolved.source})")
        if E == mod.E_MPa and not _resolved(mod):
            raise IdentificationError(
                f"{record.source}: the elastic line is not resolved: E = {E:.4g} ± {mod.E_stderr_MPa:.2g} MPa from {mod.n_points} samples "
                f"({mod.source}); " + ("give the frame stiffness (rig.frame_stiffness_N_per_um), use an extensometer or sample faster "
                                       "(the handbook E is not this diagram's slope: the frame is in it)" if apparent
                                       else "give the handbook modulus (--E or material.E_MPa) or sample faster"))
        Rp02, _ = iso6892.offset_yield_strength(strain, eng_stress, E, MIN_YIELD_OFFSET, start_MPa=window_MPa[0])
        if window_fixed_MPa is not None or modulus_reference == "Rm" or abs(Rp02 - ref) <= 1e-6 * Rp02:
            break
        ref = Rp02
    if np.nanmax(np.abs(strain)) > MAX_STRAIN:
        raise IdentificationError(f"{record.source}: engineering strain up to {np.nanmax(strain):.4g} is implausible - check units of the displacement (mm) and l0 (mm)")
    warnings: list[str] = []
    if unresolved is not None:
        warnings.append(f"the elastic line is not resolved (E = {unresolved.E_MPa:.4g} ± {unresolved.E_stderr_MPa:.2g} MPa from "
                        f"{unresolved.n_points} samples): the handbook E = {E:.4g} MPa is used instead (sample faster to measure E)")
    if E > 1e6 or E < 1e3:
        warnings.append(f"apparent modulus {E:.4g} MPa is far from any metal's: check units, the frame stiffness or the window")
    return _ElasticLine(E=E, mod=mod, Rp02=Rp02, window_MPa=window_MPa, disp=disp, strain=strain, toe_mm=toe_mm,
                        scale_factor=scale_factor, noise_MPa=noise_MPa, warnings=warnings)


def sdar_warnings(mod: ModulusFit) -> list[str]:
    """The checks of ASTM E3076-18 that SDAR's least-residual window failed, as a warning: when
    its line gives E (the failure stands beside it) or when the project's window replaced it."""
    if mod.sdar_failed:
        return [f"SDAR (ASTM E3076-18): the least-residual window failed {', '.join(mod.sdar_failed)}; E is from flowcurve's own "
                "automatic window instead (not an E3076 result)"]
    failed = [k for k, v in (mod.quality or {}).items() if not v.get("passed", True)]
    return [f"SDAR (ASTM E3076-18): the least-residual window failed {', '.join(failed)}; E is reported from it"] if failed else []


def _iso_results(inp: _Inputs, line: _ElasticLine) -> _IsoResults:
    """ISO 6892-1 results after Rp0.2: yield point (ReH, ReL, Ae), Ag, A and Z."""
    record, force, strain, eng_stress, E = inp.record, inp.force, line.strain, inp.eng_stress, line.E
    warnings: list[str] = []
    yp = iso6892.yield_point(strain, eng_stress, noise_MPa=line.noise_MPa, E_MPa=E, start_MPa=line.window_MPa[0])
    if yp is not None:
        warnings.append(f"the curve has a yield point (ReH {yp['ReH_MPa']:.1f} MPa, ReL {yp['ReL_MPa']:.1f} MPa, Ae {yp['Ae_pct']:.2f} %): "
                        "Rp0.2 lies on the Lüders plateau; report ReH/ReL (ISO 6892-1); the plateau is left out of the hardening fit")
    e_m = float(np.mean(iso6892.max_force_band(strain, eng_stress)))  # ISO 6892-1 §13: a flat maximum's mid-point
    Ag = float(iso6892.plastic_extension_pct(e_m, inp.Rm, E))
    i_k = fracture_index(force)
    At = float(100.0 * strain[i_k]) if reaches_fracture(force) else None  # ISO 6892-1 3.6.6: elastic and plastic
    if inp.lu is not None:
        A, A_method = iso6892.elongation_after_fracture_pct(inp.l0, inp.lu), "measured gauge length after fracture (post.lu_mm)"
    elif At is not None:
        A = float(iso6892.plastic_extension_pct(strain[i_k], eng_stress[i_k], E))
        A_method = f"{inp.src['source']} at fracture, elastic part removed (no post.lu_mm)"
    else:
        A, A_method = None, None
        if not inp.unbroken:  # (an unbroken specimen's warning says it already)
            warnings.append(f"the record ends at {100.0 * force[-1] / inp.Fm:.0f} % of Fm without a fracture: A is not reported (measure Lu and give it: post.lu_mm, --lu)")
    su = record.positive("post.sk_mm2")
    dk = record.positive("post.dk_mm")
    su_source = "post.sk_mm2" if su is not None else None
    if su is None and dk is not None:
        su, su_source = math.pi * dk**2 / 4.0, "post.dk_mm"
    Z = iso6892.reduction_of_area_pct(inp.s0, su) if su is not None else None
    return _IsoResults(yp=yp, e_m=e_m, Ag=Ag, i_k=i_k, A=A, A_method=A_method, At=At, su=su, su_source=su_source, dk=dk, Z=Z, warnings=warnings)


def specimen_strain(strain, eng_stress_MPa, E_line_MPa: float, E_specimen_MPa: float):
    """The specimen's engineering strain from a diagram whose elastic slope E_line includes a
    compliance in series (frame, grips): e_s = (e − σ_e/E_line) + σ_e/E_s — the plastic extension
    with the elastic slope (ISO 6892-1), plus the specimen's own elastic strain (none for E_s = ∞)."""
    s = np.asarray(eng_stress_MPa, dtype=float)
    return np.asarray(strain, dtype=float) - s / E_line_MPa + s / E_specimen_MPa


def _specimen_modulus(inp: _Inputs, line: _ElasticLine) -> tuple[float, str | None]:
    """The specimen's E for the true curve, and a note when it is not the line's slope: on a
    crosshead record whose slope is apparent (the frame, grips or toe in it) the one rule's E
    (:func:`.elastic_modulus.choose_modulus`: material.E_MPa, else the class the material names),
    else none (∞: the specimen's elastic strain is left out)."""
    if inp.src["source"] != "crosshead" or tension_E_source(line.mod.source, "crosshead") != "apparent":
        return line.E, None
    choice = choose_modulus(handbook=inp.record.positive("material.E_MPa"), material=inp.record.meta.get("material"))
    elastic = f"the crosshead's elastic extension is removed with the diagram's slope (apparent E = {line.E:.4g} MPa, ISO 6892-1's way for Rp)"
    if choice.E_MPa is not None:
        far = apparent_modulus_warning(line.E, inp.record.meta.get("material"), what="the crosshead diagram's slope")
        return choice.E_MPa, f"{elastic}; the specimen's own elastic strain is the rule's E = {choice.E_MPa:.4g} MPa ({choice.basis})" + (
            f"; {far}" if far and inp.src["stiffness"] is not None else "")
    if inp.src["stiffness"] is not None:
        return line.E, None  # the frame removed and no E to say otherwise: the line's slope
    return math.inf, (f"no frame stiffness and no handbook E: {elastic}; the specimen's own elastic strain (Rm/E, about "
                      f"{100 * inp.Rm / 2.1e5:.2g} % for a steel) is left out of the true stress, which reads that much low "
                      "(give material.E_MPa, name the material's grade or give rig.frame_stiffness_N_per_um)")


def _true_curve(inp: _Inputs, line: _ElasticLine, true_stress: str, poisson: float) -> _TrueCurve:
    """The true curve of the uniform range (up to Fm): true strain, stress and plastic strain, of
    the specimen's strain (:func:`specimen_strain` where the line's slope is apparent)."""
    E, i_m = line.E, inp.i_m
    E_s, note = _specimen_modulus(inp, line)
    strain = line.strain if note is None else specimen_strain(line.strain, inp.eng_stress, E, E_s)
    log_strain = np.log1p(strain)  # (3.2) ε = ln((l0 + Δl)/l0)
    if true_stress == "gost_3_6":
        sig_t = true_stress_gost(inp.eng_stress, log_strain, bulk_modulus(E_s, poisson))
    else:
        sig_t = true_stress_constant_volume(inp.eng_stress, strain)
    eps_p = true_plastic_strain(log_strain, sig_t, E_s)
    uni = slice(0, i_m + 1)
    ep_u, sig_u = _increasing(eps_p[uni], sig_t[uni])
    in_range = ep_u >= MIN_YIELD_OFFSET  # the flow curve from Rp0.2 on, as for compression; elastic jitter left out
    curve = pd.DataFrame({"true_plastic_strain": ep_u[in_range], "true_stress_MPa": sig_u[in_range]})
    sig_t_rp = float(np.interp(MIN_YIELD_OFFSET, ep_u, sig_u)) if ep_u[-1] > MIN_YIELD_OFFSET else None
    return _TrueCurve(strain=strain, log_strain=log_strain, sig_t=sig_t, eps_p=eps_p, eps_u=float(log_strain[i_m]), ep_u=ep_u, sig_u=sig_u,
                      curve=curve, sig_t_rp=sig_t_rp, eps_p_at_Rm=float(eps_p[i_m]), E_specimen=E_s, warnings=[note] if note else [])


def _true_stress_warnings(inp: _Inputs, line: _ElasticLine, true: _TrueCurve, true_stress: str) -> list[str]:
    """(3.6)'s cross-section F0·(1 − ε + σ/(3K)) is first order in ε: at a large uniform strain
    it reads the true stress high against constant volume (≈ ε²/2): say so past TRUE_STRESS_SPLIT_PCT."""
    if true_stress != "gost_3_6":
        return []
    i_m = inp.i_m
    split = 100.0 * (float(true.sig_t[i_m]) / float(true_stress_constant_volume(inp.eng_stress[i_m], true.strain[i_m])) - 1.0)
    if not split > TRUE_STRESS_SPLIT_PCT:
        return []
    return [f"true stress (3.6) at Fm reads {split:.1f} % above constant volume σ_e·(1 + e): its cross-section is first order "
            f"in the strain, and the uniform strain {true.eps_u:.3f} is beyond that; --true-stress constant_volume for such a material"]


def _neck_correction(inp: _Inputs, iso: _IsoResults, true: _TrueCurve) -> tuple[dict, list[str]]:
    """The fracture point with every neck correction (empty without the area after fracture), and warnings."""
    if iso.su is None:
        return {}, [] if inp.unbroken else ["no post.dk_mm or post.sk_mm2: no reduction of area, fracture point or neck correction; the hardening law is fitted to the uniform range only"]
    su, force_k = iso.su, float(inp.force[iso.i_k])
    eps_f = math.log(inp.s0 / su)  # (3.13) ε_f = ln(F0/Fk)
    avg = float(inp.force[iso.i_k] / su)  # P_k / F_k
    neck_radius = inp.record.positive("post.neck_radius_mm")
    dk_for_neck = iso.dk if iso.dk is not None else math.sqrt(4.0 * su / math.pi)
    fracture = neck_corrections(avg, eps_f, true.eps_u, d_k_mm=dk_for_neck, neck_radius_mm=neck_radius)
    fracture.update({"true_strain": eps_f, "avg_stress_MPa": avg, "force_N": force_k, "area_source": iso.su_source})
    return fracture, []


def _fit_points(inp: _Inputs, iso: _IsoResults, true: _TrueCurve, fit_range) -> tuple[np.ndarray, np.ndarray, float]:
    """The uniform range resampled evenly in εp for the fits (from past a Lüders plateau, within
    fit_range): (grid, stress, the fit range's lower end)."""
    plateau_end = float(true.eps_p[iso.yp["plateau_end_index"]]) if iso.yp is not None else MIN_YIELD_OFFSET
    fit_lo, fit_hi = (max(MIN_YIELD_OFFSET, plateau_end), np.inf) if fit_range is None else fit_range
    ep_u, sig_u = true.ep_u, true.sig_u
    sel = (ep_u >= max(fit_lo, MIN_YIELD_OFFSET)) & (ep_u <= fit_hi)
    if sel.sum() < 4:
        raise IdentificationError(f"{inp.record.source}: the uniform range has fewer than 4 points beyond 0.2 % plastic strain"
                                  + (f" within the fit range {fit_lo:g}–{fit_hi:g}" if fit_range is not None else "") + "; no hardening law")
    grid = np.linspace(ep_u[sel][0], ep_u[sel][-1], FIT_POINTS)
    return grid, np.interp(grid, ep_u[sel], sig_u[sel]), fit_lo


def _three_points(inp: _Inputs, iso: _IsoResults, true: _TrueCurve, fracture: dict, neck: str, fit_lo: float) -> list | None:
    """The three points of the three-point fits (yield, Fm, fracture), or None without a fracture point or Rp0.2."""
    if not fracture or true.sig_t_rp is None:
        return None
    first = (MIN_YIELD_OFFSET, true.sig_t_rp) if iso.yp is None else (fit_lo, float(np.interp(fit_lo, true.ep_u, true.sig_u)))
    return [first, (true.eps_p_at_Rm, float(true.sig_t[inp.i_m])), (fracture["true_strain"], fracture[neck]["stress_MPa"])]


def _fit_laws(grid, fit_sig, extra: list, three_points: list | None, fracture_point: str) -> tuple[dict, dict, dict, list[str]]:
    """Every law by least squares (with and without the fracture point) and by three points:
    (fits, least-squares variants, fracture-point choices, warnings)."""
    fits: dict = {}
    variants: dict = {}
    choices: dict = {}
    warnings: list[str] = []
    for name in ("johnson_cook", "swift", "voce"):
        try:
            pair = {"without": fit_hardening(grid, fit_sig, name)}
        except IdentificationError as exc:
            warnings.append(f"least-squares {name} fit failed: {exc}")
        else:
            if extra:  # a fracture point the law cannot pass through leaves the uniform range's fit
                try:
                    pair["with"] = fit_hardening(grid, fit_sig, name, extra_points=extra)
                except IdentificationError as exc:
                    warnings.append(f"least-squares {name} fit with the fracture point failed ({exc}); the uniform range alone is fitted")
            chosen, why = choose_fracture_variant(pair, grid, fit_sig, fracture_point)
            if extra and "with" not in pair:
                why = "excluded: the fit through the fracture point failed"
            fits[f"least_squares_{name}"] = pair[chosen]
            choices[name] = (chosen, why)
            variants.update({f"least_squares_{name}_{v}_fracture_point": f for v, f in pair.items()})
        if three_points is not None:
            try:
                fits[f"three_point_{name}"] = three_point_fit(three_points, name, curve=(grid, fit_sig))
            except IdentificationError as exc:
                warnings.append(f"three-point {name} fit failed: {exc}")
    return fits, variants, choices, warnings


def _hardening_fits(inp: _Inputs, iso: _IsoResults, true: _TrueCurve, fracture: dict, *, neck: str, law: str, hardening: str,
                    fracture_weight: float | None, fit_range, fracture_point: str) -> _Hardening:
    """The hardening laws fitted to the uniform range (and the fracture point); the main one chosen."""
    warnings: list[str] = []
    grid, fit_sig, fit_lo = _fit_points(inp, iso, true, fit_range)
    weight = math.sqrt(FIT_POINTS) if fracture_weight is None else float(fracture_weight)
    extra = [(fracture["true_strain"], fracture[neck]["stress_MPa"], weight)] if fracture else []
    if fracture_point == "include" and not extra:
        warnings.append("--fracture-point include: there is no fracture point (post.dk_mm or post.sk_mm2 missing); the uniform range alone is fitted")
    three_points = _three_points(inp, iso, true, fracture, neck, fit_lo)
    fits, variants, choices, fit_warnings = _fit_laws(grid, fit_sig, extra, three_points, fracture_point)
    warnings += fit_warnings
    main_key = f"{hardening}_{law}"
    if main_key not in fits:
        raise IdentificationError(f"{inp.record.source}: the {hardening.replace('_', ' ')} {law} fit is not available ({_why_no_fit(hardening, law, fracture, true.sig_t_rp, warnings)})")
    main = fits[main_key]
    main_fracture = choices.get(law, (None, None)) if hardening == "least_squares" else ("with", "three-point fit through the fracture point")
    warnings += [f"hardening: {w}" for w in main.warnings]
    return _Hardening(grid=grid, fit_sig=fit_sig, weight=weight, extra=extra, three_points=three_points, fits=fits, variants=variants,
                      main_key=main_key, main=main, main_fracture=main_fracture, warnings=warnings)


def _strain_zero(inp: _Inputs, line: _ElasticLine, hard: _Hardening, law: str) -> tuple[_Hardening, list[str]]:
    """The strain zero's uncertainty δε0 and its effect on the main fit's start and constants (§2.11)."""
    mod = line.mod
    top = line.Rp02 if line.Rp02 is not None and np.isfinite(line.Rp02) else float(np.nanmax(inp.eng_stress[: inp.i_m + 1]))
    window = line.window_MPa if line.window_MPa[1] > line.window_MPa[0] else (0.0, top)  # no line: the zero read up to Rp0.2
    zero = tension_or_compression_zero(line.strain[: inp.i_m + 1], inp.eng_stress[: inp.i_m + 1], window_MPa=window, E_line_MPa=mod.E_MPa,
                                       E_line_stderr_MPa=mod.E_stderr_MPa, E_used_MPa=line.E, line_resolved=line.E == mod.E_MPa)
    done = hard.variants.get(f"least_squares_{law}_without_fracture_point")  # fit_hardening(grid, fit_sig, law) already made

    def refit(e, s):
        return done if done is not None and e is hard.grid and s is hard.fit_sig else fit_hardening(e, s, law)

    main, start, warnings = apply_to_fit(hard.main, hard.grid, hard.fit_sig, zero, refit)
    return replace(hard, main=main, start=start), warnings


def _curves(inp: _Inputs, line: _ElasticLine, true: _TrueCurve, fracture: dict, hard: _Hardening, neck: str) -> dict[str, pd.DataFrame]:
    """The intermediate curves for plots: raw and corrected diagram, engineering, true, fit, fracture point
    (the record-long ones share the identification's arrays: copy=False spares stacking them into blocks)."""
    data, uni = inp.data, slice(0, inp.i_m + 1)
    eps_end = fracture.get("true_strain", float(hard.grid[-1]))
    fit_eps = np.linspace(0.0, eps_end, 200)
    curves = {
        "raw_diagram": data[[c for c in ("time_s", "force_N", "crosshead_mm", "extensometer_mm") if c in data.columns]].copy(),
        "corrected_diagram": pd.DataFrame({"elongation_mm": line.disp, "force_N": inp.force}, copy=False),
        "engineering": pd.DataFrame({"engineering_strain": line.strain, "engineering_stress_MPa": inp.eng_stress}, copy=False),
        "true": pd.DataFrame({"true_strain": true.log_strain[uni], "true_plastic_strain": true.eps_p[uni], "true_stress_MPa": true.sig_t[uni]}, copy=False),
        "fit": pd.DataFrame({"true_plastic_strain": fit_eps, "true_stress_MPa": hard.main(fit_eps)}),
    }
    if fracture:
        curves["fracture_point"] = pd.DataFrame({"true_plastic_strain": [fracture["true_strain"]], "true_stress_MPa": [fracture[neck]["stress_MPa"]]})
    return curves


def _result(inp: _Inputs, line: _ElasticLine, iso: _IsoResults, true: _TrueCurve, fracture: dict, hard: _Hardening, warnings: list[str], *,
            toe: bool, true_stress: str, poisson: float, neck: str, law: str, hardening: str) -> TensionResult:
    """The typed result (result.json) of a tension identification."""
    E, mod, yp, main = line.E, line.mod, iso.yp, hard.main
    E_source = tension_E_source(mod.source, inp.src["source"])  # the E handed on, by the rule of elastic_modulus
    rule = choose_modulus(given=E if E_source == "given" else None, handbook=inp.record.positive("material.E_MPa"),
                          measured=mod.E_MPa if inp.src["source"] == "extensometer" and _resolved(mod) else None,
                          measured_u_MPa=mod.E_stderr_MPa, material=inp.record.meta.get("material"))
    E_material, E_material_source = rule.E_MPa, rule.source
    return TensionResult(
        E_MPa=E,
        E_stderr_MPa=mod.E_stderr_MPa if E == mod.E_MPa else None,
        modulus={**mod.as_dict(), "E_MPa": E, "E_regressed_MPa": mod.E_MPa, "E_source": E_source,
                 "E_material_MPa": E_material, "E_material_source": E_material_source},
        Rp02_MPa=line.Rp02,
        yield_point=yp is not None,  # ISO 6892-1: with a yield point ReH/ReL are the yield strengths
        ReH_MPa=yp["ReH_MPa"] if yp else None,
        ReL_MPa=yp["ReL_MPa"] if yp else None,
        Ae_pct=yp["Ae_pct"] if yp else None,
        Rm_MPa=inp.Rm,
        Fm_N=inp.Fm,
        Ag_pct=iso.Ag,
        Agt_pct=100.0 * iso.e_m,
        At_pct=iso.At,
        A_pct=iso.A,
        A_method=iso.A_method,
        Z_pct=iso.Z,
        uniform_true_strain=true.eps_u,
        uniform_true_plastic_strain=true.eps_p_at_Rm,
        fracture_true_strain=fracture.get("true_strain"),
        fracture_true_stress_MPa=fracture[neck]["stress_MPa"] if fracture else None,
        fracture_avg_stress_MPa=fracture.get("avg_stress_MPa"),
        neck_corrections={k: v for k, v in fracture.items() if k in NECK_METHODS or k.startswith("a_over_R")},
        hardening=TensionHardening(
            fit=main, fracture_point_weight=hard.weight if hard.extra and hard.main_fracture[0] == "with" else None,
            fracture_point={"with": "included", "without": "excluded"}.get(hard.main_fracture[0], "none"),
            fracture_point_choice=hard.main_fracture[1],
            uniform_range_error_pct=uniform_error_pct(main, hard.grid, hard.fit_sig),
            fit_range=[float(hard.grid[0]), float(hard.grid[-1])], start_uncertainty=hard.start),
        hardening_alternatives={**{k: f.as_dict() for k, f in hard.fits.items() if k != hard.main_key},
                                **{k: f.as_dict() for k, f in hard.variants.items()}},
        three_points=[{"true_plastic_strain": e, "true_stress_MPa": s} for e, s in hard.three_points] if hard.three_points else None,
        modulus_window_MPa=list(line.window_MPa),
        methods={
            "strain_source": inp.src["source"],
            "strain_length_mm": inp.length,
            "frame_stiffness_N_per_um": inp.src["stiffness"],
            "crosshead_step_interpolated_mm": inp.src.get("step_mm"),  # a stepped reading re-read between its steps (None: as read)
            "toe_compensation_mm": line.toe_mm if toe else None,
            "scale_factor_Kl": line.scale_factor,
            "modulus": mod.source,
            "modulus_r2": mod.r2,
            "Rp02": "offset method, ISO 6892-1: intersection with the 0.2 % line of slope E",
            "Ag": "plastic extension at maximum force, 100·(e_m − Rm/E)",
            "Z": "(S0 − Su)/S0" if iso.Z is not None else None,
            "true_curve_strain": ("the specimen's: crosshead strain less σ_e/E_apparent" + (f", plus σ_e/{true.E_specimen:.4g} MPa (the rule's E: material.E_MPa or the class's)" if math.isfinite(true.E_specimen) else " (its own elastic strain left out)")
                                  if true.warnings else "the strain source's, elastic strain σ_t/E removed for εp"),
            "true_stress": "(3.6) corrected, K = E/(3(1 − 2ν))" if true_stress == "gost_3_6" else "σ_e(1 + e), constant volume",
            "poisson": poisson,
            "neck_correction": neck,
            "hardening": f"{hardening} {law}",
        },
        warnings=warnings,
        record=record_summary(inp.record),
    )


def identify_tension(record: Record, *, use_extensometer: bool | None = None, frame_stiffness_N_per_um: float | None = None,
                     crosshead_length_mm: float | None = None, toe: bool = True, scale: bool = True,
                     modulus_window: tuple[float, float] | None = None, modulus_reference: str = "Rp02",
                     modulus_window_MPa: tuple[float, float] | None = None,
                     E_MPa: float | None = None, poisson: float = 0.3, true_stress: str = "constant_volume",
                     neck: str = "davidenkov", law: str = "johnson_cook", hardening: str = "least_squares",
                     fracture_weight: float | None = None, fit_range: tuple[float, float] | None = None,
                     fracture_point: str = "auto", modulus_method: str = DEFAULT_MODULUS_METHOD) -> Identification:
    """Identify a tension record: ISO 6892-1 results, true curve, fracture point, hardening law.

    use_extensometer: None = use the extensometer channel when the record has one.
    frame_stiffness_N_per_um: overrides rig.frame_stiffness_N_per_um (crosshead path).
    crosshead_length_mm: length the crosshead elongation refers to (default: the parallel
        length if given, else l0); with post.lu_mm measured and ``scale`` it is l0 (3.1).
    modulus_window: E is regressed over (lo, hi) × the reference stress (Rp0.2, iterated,
        or Rm); modulus_window_MPa: over (lo, hi) MPa; neither (default): over the most linear
        stretch of the first loading (:func:`identification.indicator.auto_modulus`), or all of
        its samples when there are few — then the handbook ``material.E_MPa`` when the record
        has one. A line whose E is not resolved (standard error over 10 %) gives way to the
        handbook E with a warning, and without one is an error. The window in MPa and
        ``modulus.source`` are reported. E_MPa fixes the modulus. modulus_method: "window" (that
        automatic window), "sdar" (ASTM E3076-18, :func:`identification.indicator.sdar_modulus`) or
        "auto" (default: SDAR on the crosshead, the window on an extensometer).
    true_stress: "constant_volume" (default, σ_e·(1 + e)) or "gost_3_6" (the seed's corrected
        (3.6), with ν = ``poisson``: it linearises the area and reads high at large strain,
        docs/methods.md §3.2; kept for comparison).
    neck: the neck correction used for the fracture point (all are reported).
    law, hardening: the hardening law and method of the main fit; the others are reported.
    fracture_weight: weight of the fracture point in the least squares (default √N, so that
        it counts as much as the N points of the uniform range).
    fit_range: (lo, hi) true plastic strain of the uniform range used by the hardening fits.
    fracture_point: "include" / "exclude" the neck-corrected fracture point from the least
        squares, or "auto" (default): include it unless it costs the uniform range more than
        2 percentage points of max error (:func:`choose_fracture_variant`); both variants are
        kept in ``hardening_alternatives``.
    """
    fit_range, fractions, window_fixed_MPa = _check_options(
        true_stress=true_stress, neck=neck, hardening=hardening, modulus_reference=modulus_reference, fracture_point=fracture_point,
        fit_range=fit_range, modulus_window=modulus_window, modulus_window_MPa=modulus_window_MPa)
    record, unbroken = without_fracture_values(record)
    inp = _inputs(record, use_extensometer=use_extensometer, frame_stiffness_N_per_um=frame_stiffness_N_per_um,
                  crosshead_length_mm=crosshead_length_mm, scale=scale)
    inp.warnings[:0] = unbroken
    inp.unbroken = bool(unbroken)
    line = _elastic_line(inp, fractions=fractions, window_fixed_MPa=window_fixed_MPa, modulus_reference=modulus_reference,
                         E_MPa=E_MPa, toe=toe, scale=scale, modulus_method=modulus_method)
    iso = _iso_results(inp, line)
    true = _true_curve(inp, line, true_stress, poisson)
    fracture, neck_warnings = _neck_correction(inp, iso, true)
    hard = _hardening_fits(inp, iso, true, fracture, neck=neck, law=law, hardening=hardening, fracture_weight=fracture_weight,
                           fit_range=fit_range, fracture_point=fracture_point)
    hard, start_warnings = _strain_zero(inp, line, hard, law)
    warnings = (inp.warnings + line.warnings + sdar_warnings(line.mod) + iso.warnings + true.warnings + _true_stress_warnings(inp, line, true, true_stress) + neck_warnings
                + hard.warnings + start_warnings)
    result = _result(inp, line, iso, true, fracture, hard, warnings, toe=toe, true_stress=true_stress, poisson=poisson,
                     neck=neck, law=law, hardening=hardening)
    return Identification(result=result, true_curve=true.curve, curves=_curves(inp, line, true, fracture, hard, neck))

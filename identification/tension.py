"""Tension identification (docs/methods.md §2–§3, seed 3.1.2): record → ISO 6892-1 results, true
stress–strain curve, neck-corrected fracture point and hardening law.

The strain comes from the extensometer when the record has one (``use_extensometer=None``
decides automatically), otherwise from the crosshead: frame compliance removed (§2.1), toe
compensated, and scaled to the measured elongation post.lu_mm when it was measured (3.1).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification import iso6892
from flowcurve.record.summary import record_summary
from flowcurve.identification.hardening import MAX_STRAIN, MAX_STRESS_MPa, fit_hardening, three_point_fit
from flowcurve.identification.indicator import FEW_SAMPLES, auto_modulus, strain_quantum_noise, yield_onset_from_rate, compensate_toe, fit_modulus, remove_frame_compliance, scale_to_measured
from flowcurve.identification.necking import METHODS as NECK_METHODS
from flowcurve.identification.necking import neck_corrections
from flowcurve.identification.outcome import Identification

logger = logging.getLogger(__name__)

TRUE_STRESS_FORMS = ("gost_3_6", "constant_volume")
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


def reaches_fracture(force_N: np.ndarray) -> bool:
    """Does the record reach fracture: a single-step drop of more than 20 % of Fm after Fm
    (the break), or a last force below FRACTURE_END_FORCE × Fm (a necked specimen, the
    record cut at the break)?"""
    i_k = iso6892.fracture_index(force_N)
    Fm = float(np.nanmax(force_N))
    return i_k < force_N.size - 1 or float(force_N[-1]) <= FRACTURE_END_FORCE * Fm


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
        gaps = np.nonzero(~np.isfinite(ext[: iso6892.fracture_index(force) + 1]))[0]
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
    gaps = np.nonzero(~np.isfinite(cross[: iso6892.fracture_index(force) + 1]))[0]
    if gaps.size:
        raise RecordError(record.source, f"the crosshead channel has no value at sample {gaps[0] + 1} (of {gaps.size} before fracture); the strain cannot be followed through the gap", column="crosshead_mm")
    disp = cross - cross[0]
    stiffness = options.get("frame_stiffness_N_per_um")
    if stiffness is None:
        stiffness = record.positive("rig.frame_stiffness_N_per_um")
    if stiffness is not None:
        disp = remove_frame_compliance(disp, force - force[0], stiffness)
    else:
        warnings.append("no frame stiffness (rig.frame_stiffness_N_per_um): the crosshead displacement still includes the frame; strains and E are not the specimen's")
    length = options.get("crosshead_length_mm") or record.positive("specimen.parallel_length_mm", default=l0)
    return {"disp": disp, "length": float(length), "source": "crosshead", "stiffness": stiffness, "scalable": True, "warnings": warnings}


def identify_tension(record: Record, *, use_extensometer: bool | None = None, frame_stiffness_N_per_um: float | None = None,
                     crosshead_length_mm: float | None = None, toe: bool = True, scale: bool = True,
                     modulus_window: tuple[float, float] | None = None, modulus_reference: str = "Rp02",
                     modulus_window_MPa: tuple[float, float] | None = None,
                     E_MPa: float | None = None, poisson: float = 0.3, true_stress: str = "gost_3_6",
                     neck: str = "davidenkov", law: str = "johnson_cook", hardening: str = "least_squares",
                     fracture_weight: float | None = None, fit_range: tuple[float, float] | None = None,
                     fracture_point: str = "auto") -> Identification:
    """Identify a tension record: ISO 6892-1 results, true curve, fracture point, hardening law.

    use_extensometer: None = use the extensometer channel when the record has one.
    frame_stiffness_N_per_um: overrides rig.frame_stiffness_N_per_um (crosshead path).
    crosshead_length_mm: length the crosshead elongation refers to (default: the parallel
        length if given, else l0); with post.lu_mm measured and ``scale`` it is l0 (3.1).
    modulus_window: E is regressed over (lo, hi) × the reference stress (Rp0.2, iterated,
        or Rm); modulus_window_MPa: over (lo, hi) MPa; neither (default): over the most linear
        stretch of the first loading (:func:`identification.indicator.auto_modulus`), or all of
        its samples when there are few — then the handbook ``material.E_MPa`` when the record
        has one. The window in MPa and ``modulus.source`` are reported. E_MPa fixes the modulus.
    true_stress: "gost_3_6" (the corrected (3.6), with ν = ``poisson``) or "constant_volume".
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

    warnings: list[str] = []
    d0 = record.positive("specimen.d0_mm", required=True)
    l0 = record.positive("specimen.l0_mm", required=True)
    s0 = record.positive("specimen.s0_mm2", default=math.pi * d0**2 / 4.0)  # F0 = π d0²/4
    force = record.column("force_N")
    ok = np.isfinite(force)
    if not ok.all():
        warnings.append(f"{int((~ok).sum())} samples without a force value were left out")
    data = record.data[ok].reset_index(drop=True)
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
    disp0 = src["disp"]
    lu = record.positive("post.lu_mm")
    _check_post_dimensions(record, d0, l0, lu)
    scale_factor = None
    length = src["length"]
    if src["scalable"] and scale and lu is not None:
        if lu <= l0:
            raise IdentificationError(f"{record.source}: post.lu_mm = {lu:g} mm is not longer than l0 = {l0:g} mm")
        length = l0

    # E, the toe and Rp0.2 depend on each other through the window: iterate to a fixed point
    ref = 0.5 * Rm if modulus_reference == "Rp02" else Rm
    first_guesses = [Rm]  # when the first guess leaves too few samples on the elastic line
    if fractions is None and window_fixed_MPa is None and record.has("time_s"):
        try:  # a yield guess from the force rate (constant speed): a sparse elastic line needs a good one
            onset = yield_onset_from_rate(data["time_s"].to_numpy(float)[: i_m + 1], force[: i_m + 1]) / s0
            if 0 < onset <= Rm:
                first_guesses.insert(0, onset)
        except IdentificationError as exc:
            logger.debug("no yield estimate from the force rate: %s", exc)
    curvature = np.diff(eng_stress[: i_m + 1], 2)  # second differences: a linear trend leaves none, white noise σ leaves σ√6
    noise_MPa = float(1.4826 * np.median(np.abs(curvature - np.median(curvature))) / math.sqrt(6.0)) if curvature.size else 0.0
    raw_channel = "extensometer_mm" if src["source"] == "extensometer" else "crosshead_mm"
    strain_noise = strain_quantum_noise(sub.column(raw_channel)[: i_m + 1] / length)  # the encoder's quantum, before the compliance
    handbook_E = record.positive("material.E_MPa") if E_MPa is None else None
    toe_mm = 0.0
    for step in range(6):
        if window_fixed_MPa is not None:
            window_MPa, line_points, how = window_fixed_MPa, 5, "given window (MPa)"
        elif fractions is not None:
            window_MPa = (fractions[0] * ref, fractions[1] * ref)
            line_points, how = 5, f"given window {fractions[0]:g}–{fractions[1]:g} × {modulus_reference}"
        else:
            try:
                auto = auto_modulus(disp0 / length, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise)  # the window is the same before toe and scaling
            except IdentificationError:
                if step > 0 or not first_guesses:
                    raise
                while True:  # a sparse elastic line may hold too few samples below the first guess
                    ref = first_guesses.pop(0)
                    try:
                        auto = auto_modulus(disp0 / length, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise)
                        break
                    except IdentificationError:
                        if not first_guesses:
                            raise
            window_MPa, line_points, how = auto.window_MPa, min(auto.n_points, 5), auto.source
        disp = disp0
        if toe:
            disp, toe_mm = compensate_toe(disp0, force, window_N=(window_MPa[0] * s0, window_MPa[1] * s0), min_points=line_points)
        if src["scalable"] and scale and lu is not None:
            disp, scale_factor = scale_to_measured(disp, lu - l0)  # (3.1) K_l = Δl_p / max Δl
        strain = disp / length
        mod = fit_modulus(strain, eng_stress, window_MPa, min_points=line_points)
        mod.source = how
        if window_fixed_MPa is None and fractions is None:
            mod.E_stderr_MPa = max(mod.E_stderr_MPa, auto.E_stderr_MPa * mod.E_MPa / auto.E_MPa) if np.isfinite(mod.E_stderr_MPa) else auto.E_stderr_MPa
        E = mod.E_MPa
        if E_MPa is not None:
            E, mod.source = float(E_MPa), "option E_MPa"
        elif handbook_E is not None and fractions is None and window_fixed_MPa is None and mod.n_points < FEW_SAMPLES:
            E, mod.source = handbook_E, f"handbook material.E_MPa (only {mod.n_points} samples on the elastic line)"
        if E == mod.E_MPa and not mod.E_stderr_MPa <= MAX_E_UNCERTAINTY * E:
            raise IdentificationError(
                f"{record.source}: the elastic line is not resolved: E = {E:.4g} ± {mod.E_stderr_MPa:.2g} MPa from {mod.n_points} samples "
                f"({mod.source}); give the handbook modulus (--E or material.E_MPa) or sample faster")
        Rp02, _ = iso6892.offset_yield_strength(strain, eng_stress, E, MIN_YIELD_OFFSET, start_MPa=window_MPa[0])
        if window_fixed_MPa is not None or modulus_reference == "Rm" or abs(Rp02 - ref) <= 1e-6 * Rp02:
            break
        ref = Rp02
    if np.nanmax(np.abs(strain)) > MAX_STRAIN:
        raise IdentificationError(f"{record.source}: engineering strain up to {np.nanmax(strain):.4g} is implausible - check units of the displacement (mm) and l0 (mm)")
    if E > 1e6 or E < 1e3:
        warnings.append(f"apparent modulus {E:.4g} MPa is far from any metal's: check units, the frame stiffness or the window")

    # ISO 6892-1 results
    yp = iso6892.yield_point(strain, eng_stress, noise_MPa=noise_MPa, E_MPa=E)
    if yp is not None:
        warnings.append(f"the curve has a yield point (ReH {yp['ReH_MPa']:.1f} MPa, ReL {yp['ReL_MPa']:.1f} MPa, Ae {yp['Ae_pct']:.2f} %): "
                        "Rp0.2 lies on the Lüders plateau; report ReH/ReL (ISO 6892-1); the plateau is left out of the hardening fit")
    e_m = float(strain[i_m])
    Ag = float(iso6892.plastic_extension_pct(e_m, Rm, E))
    i_k = iso6892.fracture_index(force)
    if lu is not None:
        A, A_method = iso6892.elongation_after_fracture_pct(l0, lu), "measured gauge length after fracture (post.lu_mm)"
    elif reaches_fracture(force):
        A = float(iso6892.plastic_extension_pct(strain[i_k], eng_stress[i_k], E))
        A_method = f"{src['source']} at fracture, elastic part removed (no post.lu_mm)"
    else:
        A, A_method = None, None
        warnings.append(f"the record ends at {100.0 * force[-1] / Fm:.0f} % of Fm without a fracture: A is not reported (measure Lu and give it: post.lu_mm, --lu)")
    su = record.positive("post.sk_mm2")
    dk = record.positive("post.dk_mm")
    su_source = "post.sk_mm2" if su is not None else None
    if su is None and dk is not None:
        su, su_source = math.pi * dk**2 / 4.0, "post.dk_mm"
    Z = iso6892.reduction_of_area_pct(s0, su) if su is not None else None

    # true curve (uniform range up to Fm)
    log_strain = np.log1p(strain)  # (3.2) ε = ln((l0 + Δl)/l0)
    if true_stress == "gost_3_6":
        sig_t = true_stress_gost(eng_stress, log_strain, bulk_modulus(E, poisson))
    else:
        sig_t = true_stress_constant_volume(eng_stress, strain)
    eps_p = true_plastic_strain(log_strain, sig_t, E)
    uni = slice(0, i_m + 1)
    eps_u = float(log_strain[i_m])
    ep_u, sig_u = _increasing(eps_p[uni], sig_t[uni])
    in_range = ep_u >= MIN_YIELD_OFFSET  # the flow curve from Rp0.2 on, as for compression; elastic jitter left out
    true_curve = pd.DataFrame({"true_plastic_strain": ep_u[in_range], "true_stress_MPa": sig_u[in_range]})
    sig_t_rp = float(np.interp(MIN_YIELD_OFFSET, ep_u, sig_u)) if ep_u[-1] > MIN_YIELD_OFFSET else None
    eps_p_at_Rm = float(eps_p[i_m])

    # fracture point with the neck corrections
    fracture: dict = {}
    if su is not None:
        eps_f = math.log(s0 / su)  # (3.13) ε_f = ln(F0/Fk)
        avg = float(force[i_k] / su)  # P_k / F_k
        neck_radius = record.positive("post.neck_radius_mm")
        dk_for_neck = dk if dk is not None else math.sqrt(4.0 * su / math.pi)
        fracture = neck_corrections(avg, eps_f, eps_u, d_k_mm=dk_for_neck, neck_radius_mm=neck_radius)
        fracture.update({"true_strain": eps_f, "avg_stress_MPa": avg, "force_N": float(force[i_k]), "area_source": su_source})
    else:
        warnings.append("no post.dk_mm or post.sk_mm2: no reduction of area, fracture point or neck correction; the hardening law is fitted to the uniform range only")

    # hardening
    plateau_end = float(eps_p[yp["plateau_end_index"]]) if yp is not None else MIN_YIELD_OFFSET
    fit_lo, fit_hi = (max(MIN_YIELD_OFFSET, plateau_end), np.inf) if fit_range is None else fit_range
    sel = (ep_u >= max(fit_lo, MIN_YIELD_OFFSET)) & (ep_u <= fit_hi)
    if sel.sum() < 4:
        raise IdentificationError(f"{record.source}: the uniform range has fewer than 4 points beyond 0.2 % plastic strain"
                                  + (f" within the fit range {fit_lo:g}–{fit_hi:g}" if fit_range is not None else "") + "; no hardening law")
    grid = np.linspace(ep_u[sel][0], ep_u[sel][-1], FIT_POINTS)
    fit_sig = np.interp(grid, ep_u[sel], sig_u[sel])
    weight = math.sqrt(FIT_POINTS) if fracture_weight is None else float(fracture_weight)
    extra = [(fracture["true_strain"], fracture[neck]["stress_MPa"], weight)] if fracture else []
    if fracture_point == "include" and not extra:
        warnings.append("--fracture-point include: there is no fracture point (post.dk_mm or post.sk_mm2 missing); the uniform range alone is fitted")
    three_points = None
    if fracture and sig_t_rp is not None:
        first = (MIN_YIELD_OFFSET, sig_t_rp) if yp is None else (fit_lo, float(np.interp(fit_lo, ep_u, sig_u)))
        three_points = [first, (eps_p_at_Rm, float(sig_t[i_m])), (fracture["true_strain"], fracture[neck]["stress_MPa"])]
    fits: dict = {}
    variants: dict = {}
    choices: dict = {}
    for name in ("johnson_cook", "swift", "voce"):
        try:
            pair = {"without": fit_hardening(grid, fit_sig, name)}
            if extra:
                pair["with"] = fit_hardening(grid, fit_sig, name, extra_points=extra)
        except IdentificationError as exc:
            warnings.append(f"least-squares {name} fit failed: {exc}")
        else:
            chosen, why = choose_fracture_variant(pair, grid, fit_sig, fracture_point)
            fits[f"least_squares_{name}"] = pair[chosen]
            choices[name] = (chosen, why)
            variants.update({f"least_squares_{name}_{v}_fracture_point": f for v, f in pair.items()})
        if three_points is not None:
            try:
                fits[f"three_point_{name}"] = three_point_fit(three_points, name, curve=(grid, fit_sig))
            except IdentificationError as exc:
                warnings.append(f"three-point {name} fit failed: {exc}")
    main_key = f"{hardening}_{law}"
    if main_key not in fits:
        raise IdentificationError(f"{record.source}: the {hardening.replace('_', ' ')} {law} fit is not available ({_why_no_fit(hardening, law, fracture, sig_t_rp, warnings)})")
    main = fits[main_key]
    main_fracture = choices.get(law, (None, None)) if hardening == "least_squares" else ("with", "three-point fit through the fracture point")
    warnings += [f"hardening: {w}" for w in main.warnings]

    eps_end = fracture.get("true_strain", float(grid[-1]))
    fit_eps = np.linspace(0.0, eps_end, 200)
    curves = {
        "raw_diagram": data[[c for c in ("time_s", "force_N", "crosshead_mm", "extensometer_mm") if c in data.columns]].copy(),
        "corrected_diagram": pd.DataFrame({"elongation_mm": disp, "force_N": force}),
        "engineering": pd.DataFrame({"engineering_strain": strain, "engineering_stress_MPa": eng_stress}),
        "true": pd.DataFrame({"true_strain": log_strain[uni], "true_plastic_strain": eps_p[uni], "true_stress_MPa": sig_t[uni]}),
        "fit": pd.DataFrame({"true_plastic_strain": fit_eps, "true_stress_MPa": main(fit_eps)}),
    }
    if fracture:
        curves["fracture_point"] = pd.DataFrame({"true_plastic_strain": [fracture["true_strain"]], "true_stress_MPa": [fracture[neck]["stress_MPa"]]})

    result = {
        "test": "tension",
        "E_MPa": E,
        "E_stderr_MPa": mod.E_stderr_MPa if E == mod.E_MPa else None,
        "modulus": {**mod.as_dict(), "E_MPa": E, "E_regressed_MPa": mod.E_MPa},
        "Rp02_MPa": Rp02,
        "yield_point": yp is not None,  # ISO 6892-1: with a yield point ReH/ReL are the yield strengths
        "ReH_MPa": yp["ReH_MPa"] if yp else None,
        "ReL_MPa": yp["ReL_MPa"] if yp else None,
        "Ae_pct": yp["Ae_pct"] if yp else None,
        "Rm_MPa": Rm,
        "Fm_N": Fm,
        "Ag_pct": Ag,
        "Agt_pct": 100.0 * e_m,
        "A_pct": A,
        "A_method": A_method,
        "Z_pct": Z,
        "uniform_true_strain": eps_u,
        "uniform_true_plastic_strain": eps_p_at_Rm,
        "fracture_true_strain": fracture.get("true_strain"),
        "fracture_true_stress_MPa": fracture[neck]["stress_MPa"] if fracture else None,
        "fracture_avg_stress_MPa": fracture.get("avg_stress_MPa"),
        "neck_corrections": {k: v for k, v in fracture.items() if k in NECK_METHODS or k.startswith("a_over_R")},
        "hardening": {**main.as_dict(), "fracture_point_weight": weight if extra and main_fracture[0] == "with" else None,
                      "fracture_point": {"with": "included", "without": "excluded"}.get(main_fracture[0], "none"),
                      "fracture_point_choice": main_fracture[1],
                      "uniform_range_error_pct": uniform_error_pct(main, grid, fit_sig),
                      "fit_range": [float(grid[0]), float(grid[-1])]},
        "hardening_alternatives": {**{k: f.as_dict() for k, f in fits.items() if k != main_key},
                                   **{k: f.as_dict() for k, f in variants.items()}},
        "three_points": [{"true_plastic_strain": e, "true_stress_MPa": s} for e, s in three_points] if three_points else None,
        "modulus_window_MPa": list(window_MPa),
        "methods": {
            "strain_source": src["source"],
            "strain_length_mm": length,
            "frame_stiffness_N_per_um": src["stiffness"],
            "toe_compensation_mm": toe_mm if toe else None,
            "scale_factor_Kl": scale_factor,
            "modulus": mod.source,
            "modulus_r2": mod.r2,
            "Rp02": "offset method, ISO 6892-1: intersection with the 0.2 % line of slope E",
            "Ag": "plastic extension at maximum force, 100·(e_m − Rm/E)",
            "Z": "(S0 − Su)/S0" if Z is not None else None,
            "true_stress": "(3.6) corrected, K = E/(3(1 − 2ν))" if true_stress == "gost_3_6" else "σ_e(1 + e), constant volume",
            "poisson": poisson,
            "neck_correction": neck,
            "hardening": f"{hardening} {law}",
        },
        "warnings": warnings,
    }
    result["record"] = record_summary(record)
    return Identification(result=result, true_curve=true_curve, curves=curves)

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
from flowcurve.errors import IdentificationError
from flowcurve.identification import iso6892
from flowcurve.record.summary import record_summary
from flowcurve.identification.elastic_modulus import apparent_modulus_warning, choose_modulus, tension_E_source
from flowcurve.identification.laws.hardening import THREE_POINT_LAWS, HardeningFit, fit_hardening, resolve_law, three_point_fit
from flowcurve.identification.indicator import DEFAULT_MODULUS_METHOD
from flowcurve.identification.tension.necking import METHODS as NECK_METHODS
from flowcurve.identification.tension.necking import neck_corrections
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import TensionHardening, TensionResult
from flowcurve.identification.strain_zero import apply_to_fit, tension_or_compression_zero
from flowcurve.identification.tension.values import FIT_POINTS, FRACTURE_POINT_MODES, HARDENING_METHODS, MIN_YIELD_OFFSET, MODULUS_REFERENCES, TRUE_STRESS_FORMS, TRUE_STRESS_SPLIT_PCT, _check_window, _increasing, bulk_modulus, check_fit_range, choose_fracture_variant, reaches_fracture, true_plastic_strain, true_stress_constant_volume, true_stress_gost, uniform_error_pct, without_fracture_values
from flowcurve.identification.tension.inputs import _Inputs, _inputs
from flowcurve.identification.tension.elastic import _ElasticLine, _elastic_line, _resolved, sdar_warnings

logger = logging.getLogger(__name__)


def _why_no_fit(hardening: str, law: str, fracture: dict, sig_t_rp: float | None, warnings: list[str]) -> str:
    """Why a fit is missing: the input it lacks only when that input is missing, else its failure."""
    if hardening == "three_point" and not fracture:
        return "it needs the fracture point: post.dk_mm (--dk) or post.sk_mm2"
    if hardening == "three_point" and sig_t_rp is None:
        return "it needs Rp0.2 on the true curve, and the uniform range does not reach 0.2 % plastic strain"
    failed = [w for w in warnings if w.startswith(f"{hardening.replace('_', '-')} {law} fit failed")]
    return failed[-1] if failed else "no fit was made"


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
    A_terms: dict | None  # A from the curve (no post.lu_mm): what it was read from, for its budget
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


def _check_options(*, true_stress, neck, law, hardening, modulus_reference, fracture_point, fit_range, modulus_window, modulus_window_MPa):
    """The options, checked: (fit_range, modulus window fractions, modulus window MPa)."""
    if hardening == "three_point" and law not in THREE_POINT_LAWS:
        raise IdentificationError(f"--hardening three-point solves {', '.join(THREE_POINT_LAWS)}, not {law}; fit {law} by least squares (--hardening lsq)")
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


def _gauge_strain_at_fracture(inp: _Inputs, strain: np.ndarray, Ag_pct: float, E_MPa: float | None) -> tuple[float, float | None]:
    """(strain at fracture of the gauge L0, a_u) for At and A without post.lu_mm: the diagram's own where it refers
    to L0 (an extensometer, or a crosshead over l0; a_u None); over a parallel length L > L0, the marks' share
    (:func:`.iso6892.gauge_extension_at_fracture`, a_u from post.du_mm, else Ag)."""
    e_L = float(strain[inp.i_k])
    if inp.src.get("source") != "crosshead" or not inp.length > inp.l0 * (1.0 + 1e-9):
        return e_L, None
    a_u = inp.record.specimen.uniform_plastic_elongation  # (d0/du)² − 1, constant volume
    a_u = max(Ag_pct, 0.0) / 100.0 if a_u is None else a_u
    return iso6892.gauge_extension_at_fracture(e_L, inp.length, inp.l0, a_u, float(inp.eng_stress[inp.i_k]), E_MPa), a_u


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
    i_k = inp.i_k
    e_k, a_u = _gauge_strain_at_fracture(inp, strain, Ag, E)
    At = float(100.0 * e_k) if reaches_fracture(force, i_k) else None  # ISO 6892-1 3.6.6: elastic and plastic
    over = "" if a_u is None else f" over L0 (the parallel length's {inp.length - inp.l0:.3g} mm beyond the marks uniform at Ag)"
    A_terms = None
    if inp.lu is not None:
        A, A_method = iso6892.elongation_after_fracture_pct(inp.l0, inp.lu), "measured gauge length after fracture (post.lu_mm)"
    elif At is not None:
        A = float(iso6892.plastic_extension_pct(e_k, eng_stress[i_k], E))
        A_method = f"{inp.src['source']} at fracture{over}, elastic part removed (no post.lu_mm)"
        A_terms = {"gauge_strain": e_k, "strain_at_fracture": float(strain[i_k]), "stress_at_fracture_MPa": float(eng_stress[i_k]),
                   "E_MPa": E, "sample_step_strain": float(strain[i_k] - strain[i_k - 1]) if i_k > 0 else 0.0,
                   "length_mm": inp.length, "l0_mm": inp.l0, "uniform_plastic_elongation": a_u}
    else:
        A, A_method = None, None
        if not inp.unbroken:  # (an unbroken specimen's warning says it already)
            warnings.append(f"the record ends at {100.0 * force[-1] / inp.Fm:.0f} % of Fm without a fracture: A is not reported (measure Lu and give it: post.lu_mm, --lu)")
    spec = record.specimen
    su, su_source, dk = spec.fracture_area_mm2, spec.fracture_area_source, spec.dk_mm  # Sk, else π·dk²/4
    Z = iso6892.reduction_of_area_pct(inp.s0, su) if su is not None else None
    return _IsoResults(yp=yp, e_m=e_m, Ag=Ag, i_k=i_k, A=A, A_method=A_method, At=At, A_terms=A_terms, su=su, su_source=su_source, dk=dk, Z=Z, warnings=warnings)


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
    curve = pd.DataFrame({"true_plastic_strain": ep_u[in_range], "true_stress_MPa": sig_u[in_range]}, copy=False)  # fresh arrays: no copy
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


NECK_ONSET_SIGMAS = 2.0  # ε_f this many of its reading's standard uncertainties below the uniform plastic strain still breaks at the neck's onset


def _fracture_strain_u(inp: _Inputs, dk_mm: float) -> float:
    """Standard uncertainty of ε_f = ln(F0/Fk) = 2·ln(d0/dk) from the readings of d0 and dk (the record's
    micrometer, or the defaults): u = 2·√(u(d0)²/d0² + u(dk)²/dk²)."""
    from flowcurve.identification.quality.assurance import instruments_from_meta
    from flowcurve.identification.quality.uncertainty import dimension_u

    inst = instruments_from_meta(inp.record.meta)
    res, mpe = inst["diameter_resolution_mm"], inst["micrometer_mpe_mm"]
    # u(ε_f) = 2·√((u_d0/d0)² + (u_dk/dk)²)
    return 2.0 * math.hypot(dimension_u(inp.d0, res, mpe) / inp.d0, dimension_u(dk_mm, res, mpe) / dk_mm)


def _neck_correction(inp: _Inputs, iso: _IsoResults, true: _TrueCurve) -> tuple[dict, list[str]]:
    """The fracture point with every neck correction (empty without the area after fracture), and warnings."""
    if iso.su is None:
        return {}, [] if inp.unbroken else ["no post.dk_mm or post.sk_mm2: no reduction of area, fracture point or neck correction; the hardening law is fitted to the uniform range only"]
    su, force_k = iso.su, float(inp.force[iso.i_k])
    eps_f = math.log(inp.s0 / su)  # (3.13) ε_f = ln(F0/Fk)
    avg = float(inp.force[iso.i_k] / su)  # P_k / F_k
    neck_radius = inp.record.specimen.neck_radius_mm
    dk_for_neck = iso.dk if iso.dk is not None else math.sqrt(4.0 * su / math.pi)
    # a break at the onset of necking: ε_f up to the uniform strain's elastic part σ/E above the plastic one, or within
    # NECK_ONSET_SIGMAS of its own reading's standard uncertainty below it, is no neck (a/R 0); further below: a misread dk
    eps_u = eps_f if true.eps_p_at_Rm - NECK_ONSET_SIGMAS * _fracture_strain_u(inp, dk_for_neck) <= eps_f < true.eps_u else true.eps_u
    fracture = neck_corrections(avg, eps_f, eps_u, d_k_mm=dk_for_neck, neck_radius_mm=neck_radius)
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


def _fit_laws(grid, fit_sig, extra: list, three_points: list | None, fracture_point: str, law: str = "johnson_cook") -> tuple[dict, dict, dict, list[str]]:
    """Today's three laws and ``law`` by least squares (with and without the fracture point) and by three points:
    (fits, least-squares variants, fracture-point choices, warnings)."""
    fits: dict = {}
    variants: dict = {}
    choices: dict = {}
    warnings: list[str] = []
    for name in dict.fromkeys((*THREE_POINT_LAWS, law)):
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
        if three_points is not None and name in THREE_POINT_LAWS:
            try:
                fits[f"three_point_{name}"] = three_point_fit(three_points, name, curve=(grid, fit_sig))
            except IdentificationError as exc:
                warnings.append(f"three-point {name} fit failed: {exc}")
    return fits, variants, choices, warnings


def _hardening_fits(inp: _Inputs, iso: _IsoResults, true: _TrueCurve, fracture: dict, points: tuple, *, neck: str, law: str, hardening: str,
                    fracture_weight: float | None, fracture_point: str) -> _Hardening:
    """The hardening laws fitted to the uniform range's ``points`` (:func:`_fit_points`) and the fracture point; the main one chosen."""
    warnings: list[str] = []
    grid, fit_sig, fit_lo = points
    weight = math.sqrt(FIT_POINTS) if fracture_weight is None else float(fracture_weight)
    extra = [(fracture["true_strain"], fracture[neck]["stress_MPa"], weight)] if fracture else []
    if fracture_point == "include" and not extra:
        warnings.append("--fracture-point include: there is no fracture point (post.dk_mm or post.sk_mm2 missing); the uniform range alone is fitted")
    three_points = _three_points(inp, iso, true, fracture, neck, fit_lo)
    fits, variants, choices, fit_warnings = _fit_laws(grid, fit_sig, extra, three_points, fracture_point, law)
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
        """The hardening fit of (``e``, ``s``), reusing the main one when they are its points."""
        return done if done is not None and e is hard.grid and s is hard.fit_sig else fit_hardening(e, s, law)

    main, start, warnings = apply_to_fit(hard.main, hard.grid, hard.fit_sig, zero, refit)
    return replace(hard, main=main, start=start), warnings


def _curves(inp: _Inputs, line: _ElasticLine, true: _TrueCurve, fracture: dict, hard: _Hardening, neck: str) -> dict[str, pd.DataFrame]:
    """The intermediate curves for plots: raw and corrected diagram, engineering, true, fit, fracture point
    (the record-long ones share the identification's arrays: copy=False spares stacking them into blocks; the raw
    diagram is a column selection, already a copy: a lazy one under pandas' copy-on-write, a taken one before it)."""
    data, uni = inp.data, slice(0, inp.i_m + 1)
    eps_end = fracture.get("true_strain", float(hard.grid[-1]))
    fit_eps = np.linspace(0.0, eps_end, 200)
    curves = {
        "raw_diagram": data[[c for c in ("time_s", "force_N", "crosshead_mm", "extensometer_mm") if c in data.columns]],  # a selection is its own copy
        "corrected_diagram": pd.DataFrame({"elongation_mm": line.disp, "force_N": inp.force}, copy=False),
        "engineering": pd.DataFrame({"engineering_strain": line.strain, "engineering_stress_MPa": inp.eng_stress}, copy=False),
        "true": pd.DataFrame({"true_strain": true.log_strain[uni], "true_plastic_strain": true.eps_p[uni], "true_stress_MPa": true.sig_t[uni]}, copy=False),
        "fit": pd.DataFrame({"true_plastic_strain": fit_eps, "true_stress_MPa": hard.main(fit_eps)}),
    }
    if fracture:
        curves["fracture_point"] = pd.DataFrame({"true_plastic_strain": [fracture["true_strain"]], "true_stress_MPa": [fracture[neck]["stress_MPa"]]})
    return curves


def _methods(inp: _Inputs, line: _ElasticLine, iso: _IsoResults, true: _TrueCurve, *, toe: bool, true_stress: str, poisson: float,
             neck: str, law: str, hardening: str) -> dict:
    """How each result was obtained (result.json's ``methods``)."""
    return {
        "strain_source": inp.src["source"],
        "strain_length_mm": inp.length,
        **({"strain_length_stated": inp.src["length_stated"]} if "length_stated" in inp.src else {}),  # the crosshead's: Lc given, or l0 assumed
        "frame_stiffness_N_per_um": inp.src["stiffness"],
        "crosshead_step_interpolated_mm": inp.src.get("step_mm"),  # a stepped reading re-read between its steps (None: as read)
        "toe_compensation_mm": line.toe_mm if toe else None,
        "scale_factor_Kl": line.scale_factor,
        **({"scale_Kl": line.scale} if line.scale is not None else {}),  # (3.1)'s terms: Lu − L0 against the plastic elongation at the fracture
        "modulus": line.mod.source,
        "modulus_r2": line.mod.r2,
        "Rp02": "offset method, ISO 6892-1: intersection with the 0.2 % line of slope E",
        "Ag": "plastic extension at maximum force, 100·(e_m − Rm/E)",
        "Z": "(S0 − Su)/S0" if iso.Z is not None else None,
        **({"A_from_curve": iso.A_terms} if iso.A_terms is not None else {}),  # A without post.lu_mm: read off the curve at the break
        "true_curve_strain": ("the specimen's: crosshead strain less σ_e/E_apparent" + (f", plus σ_e/{true.E_specimen:.4g} MPa (the rule's E: material.E_MPa or the class's)" if math.isfinite(true.E_specimen) else " (its own elastic strain left out)")
                              if true.warnings else "the strain source's, elastic strain σ_t/E removed for εp"),
        "true_stress": "(3.6) corrected, K = E/(3(1 − 2ν))" if true_stress == "gost_3_6" else "σ_e(1 + e), constant volume",
        "poisson": poisson,
        "neck_correction": neck,
        "hardening": f"{hardening} {law}",
    }


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
        methods=_methods(inp, line, iso, true, toe=toe, true_stress=true_stress, poisson=poisson, neck=neck, law=law, hardening=hardening),
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

    The rules behind the defaults: docs/methods.md §3.7.

    Parameters
    ----------
    record : Record
        A tension record (elongation from the extensometer or the crosshead).
    use_extensometer, frame_stiffness_N_per_um, crosshead_length_mm, scale, toe : optional
        The extensometer (None: when recorded); else the crosshead with the frame's stiffness (N/µm,
        default the record's) over a length, mm (parallel length, else l0; scaled to post.lu_mm with
        ``scale``, (3.1)); ``toe`` compensates a soft start.
    modulus_window, modulus_window_MPa, modulus_reference, modulus_method, E_MPa : optional
        E's window in fractions of ``modulus_reference`` (Rp02, Rm) or in MPa (default: the most
        linear stretch); "window", "sdar" (ASTM E3076-18) or "auto"; ``E_MPa`` fixes E, MPa.
    true_stress, poisson : str, float
        "constant_volume" σ = σe·(1 + e), or "gost_3_6" (3.6) with ν (docs/methods.md §3.2).
    neck, law, hardening : str
        The neck correction of the fracture point; the main fit's law and method.
    fracture_weight, fracture_point, fit_range : optional
        The fracture point's weight (√N), "include", "exclude" or "auto"; (lo, hi) εp fitted.

    Returns
    -------
    Identification
        A TensionResult (E, Rp0.2, Rm, Ag, A, Z, fits, uncertainty) and the curves.
    """
    fit_range, fractions, window_fixed_MPa = _check_options(
        true_stress=true_stress, neck=neck, law=law, hardening=hardening, modulus_reference=modulus_reference,
        fracture_point=fracture_point, fit_range=fit_range, modulus_window=modulus_window, modulus_window_MPa=modulus_window_MPa)
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
    points = _fit_points(inp, iso, true, fit_range)  # the uniform range resampled: the law chosen on it (--law best) and fitted to it
    law, law_choice = resolve_law(law, *points[:2])
    hard = _hardening_fits(inp, iso, true, fracture, points, neck=neck, law=law, hardening=hardening, fracture_weight=fracture_weight,
                           fracture_point=fracture_point)
    hard, start_warnings = _strain_zero(inp, line, hard, law)
    hard.main.law_choice = law_choice  # the main fit's copy only (result.json's hardening)
    warnings = (inp.warnings + line.warnings + sdar_warnings(line.mod) + iso.warnings + true.warnings + _true_stress_warnings(inp, line, true, true_stress) + neck_warnings
                + hard.warnings + start_warnings)
    result = _result(inp, line, iso, true, fracture, hard, warnings, toe=toe, true_stress=true_stress, poisson=poisson,
                     neck=neck, law=law, hardening=hardening)
    return Identification(result=result, true_curve=true.curve, curves=_curves(inp, line, true, fracture, hard, neck))

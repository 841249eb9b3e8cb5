"""Compression (upsetting) identification with barrelling friction — seed 004, section 3.1.3.

From a compression record (force, crosshead travel) and the post-test measurements (final
height hk, bulge diameter dmax or largest cross-section smax):

1. the indicator diagram: frame compliance removed (§2.1) and the shortening scaled to the
   measured height change, K_l = (h0 − hk)/max Δl ((3.1), worked example 0.96);
2. current height h = h0 − Δl, strain ε = −ln(h/h0) (3.31), volume-constant diameter
   d_n = d0·√(h0/h) (3.28), mean pressure σ_n = P/S, S = π·d_n²/4 ((3.30)/(3.32));
3. the friction coefficient by every method of :mod:`identification.friction` (default: the
   CalculiX table ``fe_table``; the seed's bulge regression (3.19) and Ebrahimi–Najafizadeh
   side by side);
4. the flow curve corrected by every correction (the CalculiX force factor ``fe_table``
   (default), K_σ/K_ε, Siebel, exact slab), each
   kept as the curve ``true_<method>``;
5. the hardening law fitted (:func:`identification.hardening.fit_hardening`) to the default
   corrected curve.

The elastic modulus used to strip elastic strain is the ``E_MPa`` option (a handbook value)
when given, else the record's ``material.E_MPa`` (entered at the test), otherwise the apparent modulus of the initial linear part (§2.3). When ``E_MPa`` is
given, the measured hk (after unloading) is also corrected for the specimen's elastic
spring-back before the shortening is scaled.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification import friction as fr
from flowcurve.identification.hardening import fit_hardening
from flowcurve.identification.indicator import fit_modulus, remove_frame_compliance, scale_to_measured
from flowcurve.identification.outcome import Identification
from flowcurve.identification.tension import true_plastic_strain

YIELD_OFFSET = 0.002  # 0.2 % offset for the compression yield and the start of the fit
MAX_FIT_POINTS = 600  # the hardening fit uses at most this many points, evenly spread in strain
FIT_CURVE_POINTS = 200


def compression_sign(values: np.ndarray) -> float:
    """+1 or −1: the sign that makes the larger excursion of a signal positive."""
    return -1.0 if abs(np.nanmin(values)) > abs(np.nanmax(values)) else 1.0


def loading_branch_end(travel_mm: np.ndarray, force_N: np.ndarray, near: float = 0.005) -> int:
    """Index of the end of loading: the largest force among the samples at the top of travel.

    The crosshead reverses at the end of loading; near the top, encoder steps make the travel
    flat over several samples, and the unloading samples there carry a clearly lower force.
    ``near`` is the part of the largest travel counted as "the top".
    """
    top = np.nanmax(travel_mm)
    candidates = np.nonzero(travel_mm >= top * (1.0 - near))[0]
    return int(candidates[np.nanargmax(force_N[candidates])])


def offset_yield(eps_p, stress_MPa, offset: float = YIELD_OFFSET) -> float | None:
    """Stress where the plastic strain first reaches ``offset`` (running maximum, interpolated)."""
    eps_run = np.maximum.accumulate(np.asarray(eps_p, dtype=float))
    if eps_run[-1] < offset:
        return None
    i = int(np.argmax(eps_run >= offset))
    if i == 0:
        return float(stress_MPa[0])
    e0, e1 = eps_run[i - 1], eps_run[i]
    w = 0.0 if e1 == e0 else (offset - e0) / (e1 - e0)
    return float(stress_MPa[i - 1] + w * (stress_MPa[i] - stress_MPa[i - 1]))


def plastic_strain(strain, stress_MPa, E_MPa: float | None):
    """Plastic part of a (compressive, positive) true strain; the total strain when E is unknown."""
    if E_MPa is None:
        return np.asarray(strain, dtype=float).copy()
    return true_plastic_strain(strain, stress_MPa, E_MPa)  # (3.7) ε_p = ε − σ/E


def _fit_subset(eps_p: np.ndarray, start: float) -> np.ndarray:
    """Indices of the plastic range (ε_p ≥ start, after the running maximum passed it), thinned."""
    past = np.maximum.accumulate(eps_p) >= start
    idx = np.nonzero(past & (eps_p > 0))[0]
    if idx.size > MAX_FIT_POINTS:
        # evenly in strain, so the long end of the curve does not outweigh the start
        targets = np.linspace(eps_p[idx[0]], eps_p[idx[-1]], MAX_FIT_POINTS)
        order = np.argsort(eps_p[idx], kind="stable")
        pos = np.searchsorted(eps_p[idx][order], targets).clip(0, idx.size - 1)
        idx = np.unique(idx[order][pos])
    return idx


def _meta_geometry(record: Record) -> dict:
    src = record.source
    d0 = record.positive("specimen.d0_mm", required=True)
    h0 = record.positive("specimen.h0_mm", required=True)
    hk = record.positive("post.hk_mm", required=True)
    if hk >= h0:
        raise RecordError(src, f"'post.hk_mm' = {hk:g} mm must be below 'specimen.h0_mm' = {h0:g} mm (the specimen is shorter after compression)")
    dmax = record.positive("post.dmax_mm")
    smax = record.positive("post.smax_mm2")
    if dmax is None and smax is None:
        raise RecordError(src, "required metadata 'post.dmax_mm' (bulge diameter) or 'post.smax_mm2' (largest cross-section) is missing; the friction cannot be identified without it")
    dtop = record.positive("post.dtop_mm")
    return {"d0": d0, "h0": h0, "hk": hk, "dmax": dmax, "smax": smax, "dtop": dtop}


def _friction_all(geo: dict, chosen: str, warnings: list[str], curve=None) -> tuple[fr.FrictionResult, dict[str, fr.FrictionResult | str]]:
    if chosen not in fr.FRICTION_METHODS:
        raise IdentificationError(f"unknown friction method {chosen!r} (choose from {', '.join(fr.FRICTION_METHODS)})")
    results: dict[str, fr.FrictionResult | str] = {}
    for method in fr.FRICTION_METHODS:
        try:
            results[method] = fr.identify_friction(method, geo["d0"], geo["h0"], geo["hk"], d_max_mm=geo["dmax"], s_max_mm2=geo["smax"], d_top_mm=geo["dtop"], curve=curve)
        except IdentificationError as exc:
            if method == chosen:
                raise
            results[method] = str(exc)
            warnings.append(f"friction method {method} not applicable: {exc}")
    return results[chosen], results


def _apparent_modulus(strain: np.ndarray, stress: np.ndarray, warnings: list[str], window_MPa=None):
    """Apparent modulus of the first loading (§2.3); None (with a warning) when it fails."""
    if window_MPa is None:
        # a crude yield estimate: the nominal stress at 1 % strain; fit between 10 % and 40 % of it
        ref = float(np.interp(0.01, np.maximum.accumulate(strain), stress)) if strain[-1] > 0.01 else float(np.max(stress))
        window_MPa = (0.1 * ref, 0.4 * ref)
    try:
        fit = fit_modulus(strain, stress, tuple(window_MPa))
    except IdentificationError as exc:
        warnings.append(f"apparent modulus not identified ({exc}); elastic strain not removed — give E_MPa")
        return None
    return fit


def identify_compression(
    record: Record,
    *,
    friction_method: str = fr.DEFAULT_FRICTION_METHOD,
    friction_correction: str = fr.DEFAULT_CORRECTION,
    law: str = "johnson_cook",
    E_MPa: float | None = None,
    frame_stiffness_N_per_um: float | None = None,
    modulus_window_MPa: tuple[float, float] | None = None,
) -> Identification:
    """Identify a compression record: friction, friction-corrected true curves and hardening.

    Options: ``friction_method`` (one of ``fe_table`` (default), ``bulge_regression``,
    ``ebrahimi_najafizadeh``), ``friction_correction`` (``fe_table`` (default), ``k_sigma``,
    ``siebel``, ``slab``), ``law`` of the hardening fit, ``E_MPa`` (handbook modulus for elastic strain and
    spring-back; otherwise the apparent modulus), ``frame_stiffness_N_per_um`` (otherwise the
    record's ``rig.frame_stiffness_N_per_um``), ``modulus_window_MPa``.
    """
    src = record.source
    if friction_correction not in fr.CORRECTIONS:
        raise IdentificationError(f"unknown friction correction {friction_correction!r} (choose from {', '.join(fr.CORRECTIONS)})")
    if E_MPa is not None and not (math.isfinite(E_MPa) and E_MPa > 0):
        raise IdentificationError(f"E_MPa must be > 0, got {E_MPa!r}")
    E_source = "option"
    if E_MPa is None and record.positive("material.E_MPa") is not None:
        # a short stiff specimen's elastic line is about one encoder count: the handbook
        # modulus the operator entered strips elastic strain better than a regression on it
        E_MPa, E_source = record.positive("material.E_MPa"), "record (material.E_MPa)"
    geo = _meta_geometry(record)
    d0, h0, hk = geo["d0"], geo["h0"], geo["hk"]
    warnings: list[str] = []

    # friction first: it needs only the post-test measurements, and bad ones should stop early
    chosen, frictions = _friction_all(geo, friction_method, [])

    # -- indicator diagram ------------------------------------------------------------------
    t = record.column("time_s")
    force_raw = record.column("force_N")
    cross_raw = record.column("crosshead_mm")
    ok = np.isfinite(t) & np.isfinite(force_raw) & np.isfinite(cross_raw)
    t, force_raw, cross_raw = t[ok], force_raw[ok], cross_raw[ok]
    if t.size < 10:
        raise RecordError(src, f"only {t.size} complete samples (time, force, crosshead); a compression identification needs more")
    force = force_raw * compression_sign(force_raw)
    travel = cross_raw - cross_raw[0]
    travel = travel * compression_sign(travel)

    stiffness = frame_stiffness_N_per_um if frame_stiffness_N_per_um is not None else record.positive("rig.frame_stiffness_N_per_um")
    if stiffness is not None:
        specimen = remove_frame_compliance(travel, force, stiffness)
    else:
        specimen = travel.copy()
        warnings.append("no frame stiffness ('rig.frame_stiffness_N_per_um'): the frame compliance is left to the scaling K_l")
    end = loading_branch_end(travel, force)
    t, force, travel, specimen = t[: end + 1], force[: end + 1], travel[: end + 1], specimen[: end + 1]
    if end < 10:
        raise IdentificationError(f"{src}: the loading branch has only {end + 1} samples")

    # measured shortening at the largest load: h0 − hk plus the elastic spring-back when E is known
    d_k = float(fr.nominal_diameter(d0, h0, hk))
    springback = 0.0
    if E_MPa is not None:
        springback = hk * (force[-1] / (math.pi * d_k**2 / 4.0)) / E_MPa  # elastic strain σ/E over hk
    measured = h0 - hk + springback
    shortening, K_l = scale_to_measured(np.clip(specimen, 0.0, None), measured)  # (3.1) K_l = (h0 − hk)/max Δl
    if abs(K_l - 1.0) > 0.1:
        warnings.append(f"scaling factor K_l = {K_l:.3f} differs from 1 by more than 10 %: check the frame stiffness, hk and the crosshead channel")

    # -- nominal curve ----------------------------------------------------------------------
    h = h0 - shortening
    strain = fr.height_strain(h, h0)  # (3.31)
    d_n = fr.nominal_diameter(d0, h0, h)  # (3.28)
    area = math.pi * d_n**2 / 4.0  # (3.30)
    pressure = force / area  # (3.32) σ_n = P/S_i

    E_used, E_fit = E_MPa, None
    if E_MPa is None:
        E_fit = _apparent_modulus(strain, pressure, warnings, modulus_window_MPa)
        E_used, E_source = (E_fit.E_MPa, "apparent") if E_fit is not None else (None, "none")

    # -- friction (again, now with the curve: the FE table's μ depends on the hardening) ----
    chosen, frictions = _friction_all(geo, friction_method, warnings, curve=(strain, pressure))
    mu = chosen.mu

    # -- friction corrections ---------------------------------------------------------------
    curves: dict[str, pd.DataFrame] = {
        "raw_diagram": pd.DataFrame({"crosshead_displacement_mm": travel, "force_N": force}),
        "corrected_diagram": pd.DataFrame({"specimen_displacement_mm": shortening, "force_N": force}),
        "nominal": pd.DataFrame({"true_strain": strain, "mean_pressure_MPa": pressure, "height_mm": h}),
    }
    corrected: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for method in fr.CORRECTIONS:
        eps_t, sig_t = fr.correct(method, strain, pressure, mu, d_n / 2.0, h)
        eps_tp = plastic_strain(eps_t, sig_t, E_used)
        corrected[method] = (eps_tp, sig_t)
        curves[f"true_{method}"] = pd.DataFrame({"true_plastic_strain": eps_tp, "true_stress_MPa": sig_t, "true_strain": eps_t})

    # -- hardening fits ---------------------------------------------------------------------
    fits = {}
    for method, (eps_tp, sig_t) in corrected.items():
        idx = _fit_subset(eps_tp, YIELD_OFFSET)
        if idx.size < 4:
            if method == friction_correction:
                raise IdentificationError(f"{src}: the plastic range has only {idx.size} points; nothing to fit (did the specimen yield?)")
            continue
        try:
            fits[method] = fit_hardening(eps_tp[idx], sig_t[idx], law)
        except IdentificationError as exc:
            if method == friction_correction:
                raise
            warnings.append(f"hardening fit on the {method} curve failed: {exc}")
    fit = fits[friction_correction]
    eps_def, sig_def = corrected[friction_correction]
    grid = np.linspace(fit.strain_range[0], fit.strain_range[1], FIT_CURVE_POINTS)
    curves["fit"] = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": fit(grid)})

    # from where the plastic strain has passed the 0.2 % offset: the curve a card starts from
    plastic = np.nonzero((np.maximum.accumulate(eps_def) >= YIELD_OFFSET) & (eps_def >= 0))[0]
    true_curve = pd.DataFrame({"true_plastic_strain": eps_def[plastic], "true_stress_MPa": sig_def[plastic]})

    rp02 = offset_yield(plastic_strain(strain, pressure, E_used), pressure) if E_used is not None else None
    duration = float(t[-1] - t[0])
    strain_rate = float(strain[-1] / duration) if duration > 0 else None

    friction_block = {m: (r.mu if isinstance(r, fr.FrictionResult) else None) for m, r in frictions.items()}
    result = {
        "test": "compression",
        "E_MPa": E_used,
        "E_source": E_source,  # option (handbook) / apparent (initial slope, §2.3) / none
        "Rp02_MPa": rp02,  # compression yield: mean pressure at 0.2 % plastic strain
        "Rm_MPa": None,
        "Ag_pct": None,
        "A_pct": None,
        "Z_pct": None,
        "fracture_true_strain": None,
        "fracture_true_stress_MPa": None,
        "max_force_N": float(np.max(force)),
        "final_true_strain": float(strain[-1]),
        "friction_mu": mu,
        "friction_method": chosen.method,
        "friction": friction_block,
        "friction_details": {m: (r.as_dict() if isinstance(r, fr.FrictionResult) else {"method": m, "error": r}) for m, r in frictions.items()},
        "friction_correction": friction_correction,
        "hardening": {**fit.as_dict(), "correction": friction_correction},
        "hardening_by_correction": {m: f.as_dict() for m, f in fits.items()},
        "indicator": {
            "frame_stiffness_N_per_um": stiffness,
            "K_l": K_l,
            "measured_shortening_mm": measured,
            "springback_mm": springback,
            "max_specimen_displacement_mm": float(np.max(specimen)),
        },
        "methods": {
            "friction": f"{chosen.method} (all: {', '.join(fr.FRICTION_METHODS)})",
            "correction": f"{friction_correction} (all: {', '.join(fr.CORRECTIONS)})",
            "stress": "mean pressure P/S, S = pi*d_n^2/4, d_n = d0*sqrt(h0/h) (3.28)-(3.32)",
            "scaling": "K_l = (h0 - hk [+ spring-back]) / max(specimen displacement) (3.1)",
            "hardening": f"{law} least squares on the {friction_correction} curve, eps_p >= {YIELD_OFFSET}",
        },
        "warnings": warnings,
        "record": {
            "path": src,
            "material": record.meta.get("material"),
            "nominal_temperature_C": record.number("nominal_temperature_C"),
            "crosshead_speed_mm_per_s": record.number("crosshead_speed_mm_per_s"),
            "strain_rate_per_s": strain_rate,  # mean true strain rate of the loading branch
            "specimen": {"d0_mm": d0, "h0_mm": h0},
            "post": {"hk_mm": hk, "dmax_mm": geo["dmax"], "smax_mm2": geo["smax"]},
        },
    }
    if E_fit is not None:
        result["E_apparent_stderr_MPa"] = E_fit.E_stderr_MPa
    return Identification(result=result, true_curve=true_curve, curves=curves)

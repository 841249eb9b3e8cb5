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
from dataclasses import replace

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.record.specimen import circle_area_mm2
from flowcurve.errors import IdentificationError
from flowcurve.identification.compression import friction as fr
from flowcurve.identification.elastic_modulus import METAL_E_RANGE_MPa, ModulusChoice, apparent_modulus_warning
from flowcurve.identification.laws.hardening import HardeningFit, fit_hardening, resolve_law
from flowcurve.identification.indicator import DEFAULT_MODULUS_METHOD, FEW_POINTS_TOP, SDAR_REACH, ModulusFit, auto_modulus, elastic_modulus, fit_modulus, scale_to_measured, yield_onset_from_rate
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import CompressionHardening, CompressionResult
from flowcurve.identification.strain_zero import apply_to_fit, known_slope_offsets, tension_or_compression_zero
from flowcurve.identification.compression.values import FIT_CURVE_POINTS, YIELD_OFFSET, _Diagram, _Friction, _Line, _Nominal, _Yield, _check_options, _fit_points, _handbook_modulus, _hardening_fits, _inputs, _meta_geometry, offset_yield, plastic_strain
from flowcurve.identification.compression.friction_result import _dface_advice, correction_mu_sensitivity, _fe_correction_uncertainty, _friction_all, _friction_correction, _model_form_shares, _mu_stderr_basis


def _offset_onset_MPa(strain0, stress0, line: ModulusFit, offset: float = YIELD_OFFSET) -> float | None:
    """Stress where the strain first exceeds the elastic line by ``offset`` (the line's zero at
    zero stress, i.e. toe-compensated): the yield estimate that sets the next window."""
    beyond = strain0 - (stress0 - line.intercept_MPa) / line.E_MPa
    past = np.nonzero((beyond >= offset) & (stress0 >= line.window_MPa[0]))[0]  # on the line's rise, not in the toe's noise
    return float(stress0[past[0]]) if past.size and stress0[past[0]] > 0 else None


def elastic_line(t, specimen_mm, force_N, *, area0_mm2: float, h0_mm: float, window_MPa=None, window=None,
                 modulus_reference: str = "Rp02", method: str = DEFAULT_MODULUS_METHOD) -> tuple[ModulusFit, float]:
    """The elastic line of the first loading and the toe it reveals (§2.3, ISO 6892-1 toe).

    Strain regressed on stress over the widest linear window (:func:`auto_modulus`, iterated
    on the 0.2 % offset yield from a first estimate off the force rate), or over ``window_MPa``
    (MPa) / ``window`` (fractions of the yield estimate, or of the largest stress with
    ``modulus_reference`` "Rm"). Returns the line in (specimen displacement/h0, P/S0) and the
    toe offset (mm): where the line meets zero force. ``method`` "sdar": the line SDAR finds
    (ASTM E3076-18) on the loading up to twice the force rate's yield estimate."""
    strain0 = np.asarray(specimen_mm, dtype=float) / h0_mm
    stress0 = np.asarray(force_N, dtype=float) / area0_mm2
    if window_MPa is None and window is None and method == "sdar":
        line = elastic_modulus(method, strain0, stress0, 0.0, upto_MPa=SDAR_REACH * yield_onset_from_rate(t, force_N) / area0_mm2,
                               strain_on_stress=True)
    elif window_MPa is not None:
        line = fit_modulus(strain0, stress0, tuple(window_MPa), strain_on_stress=True)
        line.source = "given window (MPa)"
    else:
        ref = float(np.max(stress0)) if modulus_reference == "Rm" and window is not None else yield_onset_from_rate(t, force_N) / area0_mm2
        for _ in range(4):
            if window is not None:
                line = fit_modulus(strain0, stress0, (window[0] * ref, window[1] * ref), strain_on_stress=True)
                line.source = f"given window {window[0]:g}–{window[1]:g} × {'largest stress' if modulus_reference == 'Rm' else 'the yield stress'}"
            else:
                line = auto_modulus(strain0, stress0, ref, strain_on_stress=True)
            if modulus_reference == "Rm" and window is not None:
                break
            new_ref = _offset_onset_MPa(strain0, stress0, line)
            if new_ref is None or abs(new_ref - ref) <= 1e-3 * ref:
                break
            ref = new_ref
    if not line.E_MPa > 0:
        raise IdentificationError("the elastic line does not rise: no modulus")
    toe_mm = -line.intercept_MPa / line.E_MPa * h0_mm  # ε = c0 + σ/E → Δl0 = c0·h0
    return line, float(toe_mm)


def toe_offsets(specimen_mm, force_N, window_MPa, *, E_MPa: float, area0_mm2: float, h0_mm: float) -> np.ndarray:
    """The offsets Δl − h0·σ/E (mm) of the first loading's samples in the window: one value, the
    toe, for samples on an elastic line of slope E."""
    stress = np.asarray(force_N, dtype=float) / area0_mm2
    disp = np.asarray(specimen_mm, dtype=float)
    top = int(np.argmax(stress >= window_MPa[1])) if np.any(stress >= window_MPa[1]) else stress.size
    on = np.flatnonzero(stress[:top] >= window_MPa[0])
    if on.size == 0:
        raise IdentificationError("no sample of the first loading in the elastic window")
    return disp[on] - h0_mm * stress[on] / E_MPa  # Δl = Δl0 + h0·σ/E


def toe_spread_warning(offsets_mm: np.ndarray, window_MPa, *, E_MPa: float, h0_mm: float) -> str | None:
    """A warning when the window's samples are not on one line of slope E: their offsets spread
    wider than the line's own length h0·Δσ/E (a sparse record whose first loaded samples are
    already plastic, a force lagging the travel). The strain zero is then uncertain by half the spread."""
    spread = float(np.ptp(offsets_mm)) if offsets_mm.size else 0.0
    span = h0_mm * (window_MPa[1] - window_MPa[0]) / E_MPa
    if not spread > span:
        return None
    return (f"the strain zero is not resolved: the {offsets_mm.size} samples taken for the elastic line lie off one line of "
            f"E = {E_MPa:.4g} MPa by {1000 * spread:.0f} µm (the line itself spans {1000 * span:.0f} µm), so the start of the "
            f"flow curve is uncertain by ±{spread / 2 / h0_mm:.4f} in strain (sample faster near the yield)")


def compensate_toe_line(specimen_mm, force_N, line: ModulusFit, toe_mm: float, *, area0_mm2: float, h0_mm: float) -> np.ndarray:
    """ISO 6892-1 toe compensation: the displacement shifted so that the elastic line passes
    through zero force, and the samples before the line (the toe) replaced by the line."""
    out = np.asarray(specimen_mm, dtype=float) - toe_mm
    force = np.asarray(force_N, dtype=float)
    on_line = np.nonzero(force / area0_mm2 >= line.window_MPa[0])[0]
    head = np.arange(on_line[0]) if on_line.size else np.arange(0)
    out[head] = np.clip(force[head], 0.0, None) / area0_mm2 / line.E_MPa * h0_mm  # the toe replaced by the line
    return out


MIN_LINE_SLOPE_FRACTION = 0.2  # a regressed line flatter than this part of the handbook E reaches past yield


def _yield_estimate_MPa(diagram: _Diagram, area0_mm2: float) -> float | None:
    """The force rate's estimate of the yield stress (:func:`yield_onset_from_rate`), None without one."""
    try:
        return yield_onset_from_rate(diagram.t, diagram.force) / area0_mm2
    except IdentificationError:
        return None


def toe_on_flattest_offsets(specimen_mm, force_N, *, E_MPa: float, area0_mm2: float, h0_mm: float, upto_MPa: float,
                            run: int = 3) -> tuple[float, tuple[float, float]]:
    """The toe (mm) of an elastic line of known slope E from a few coarse samples: the offset
    Δl − h0·σ/E grows while the toe closes, stays put on the elastic line and grows again past
    yield, so the line is the run of ``run`` consecutive samples of the first loading (up to
    ``upto_MPa``) whose offsets spread least; returns their median offset and their stress range."""
    stress = np.asarray(force_N, dtype=float) / area0_mm2
    disp = np.asarray(specimen_mm, dtype=float)
    top = int(np.argmax(stress >= upto_MPa)) if np.any(stress >= upto_MPa) else stress.size
    on = np.flatnonzero(stress[:top] > 0.02 * upto_MPa)
    if on.size < run:
        raise IdentificationError(f"only {on.size} samples of the first loading below {upto_MPa:.4g} MPa: no elastic line to place")
    offset = disp[on] - h0_mm * stress[on] / E_MPa  # Δl = Δl0 + h0·σ/E on the line
    runs = np.lib.stride_tricks.sliding_window_view(offset, run)
    k = int(np.argmin(np.ptp(runs, axis=1)))
    return float(np.median(runs[k])), (float(stress[on[k]]), float(stress[on[k + run - 1]]))


def _line_of_known_slope(diagram: _Diagram, area0_mm2: float, h0_mm: float, E_MPa: float) -> tuple[ModulusFit, float] | None:
    """(line, toe mm) when the line's own slope cannot be regressed (a few samples, an encoder count
    longer than the line, a toe that lasts into it) but E is known: slope E placed on the flattest
    offsets of the first loading up to 0.9 × the force rate's yield estimate
    (:func:`toe_on_flattest_offsets`; less than one count of a stepped crosshead is no toe); None
    without such samples."""
    ref = _yield_estimate_MPa(diagram, area0_mm2)
    if ref is None:
        return None
    try:
        toe_mm, window = toe_on_flattest_offsets(diagram.specimen, diagram.force, E_MPa=E_MPa, area0_mm2=area0_mm2, h0_mm=h0_mm,
                                                 upto_MPa=FEW_POINTS_TOP * ref)
    except IdentificationError:
        return None
    if diagram.step_mm is not None and abs(toe_mm) < diagram.step_mm:
        toe_mm = 0.0  # less than one count of a stepped crosshead: not told from the count's rounding
    line = ModulusFit(E_MPa, float("nan"), -E_MPa * toe_mm / h0_mm, float("nan"), 3, window,
                      source=f"handbook E = {E_MPa:g} MPa placed on the flattest offsets of the first loading ({window[0]:.4g}–{window[1]:.4g} MPa; "
                             "too few or too coarse samples for a slope of their own)")
    return line, toe_mm


def _elastic_line(diagram: _Diagram, geo: dict, *, E_MPa: float | None, modulus_window_MPa, modulus_window,
                  modulus_reference: str, toe: bool, modulus_method: str = DEFAULT_MODULUS_METHOD) -> _Line:
    """The elastic line and the toe: the linear part extended to zero force (ISO 6892-1)."""
    warnings: list[str] = []
    apparent = None
    area0 = geo["area0"]
    specimen = diagram.specimen
    try:
        line, toe_mm = elastic_line(diagram.t, specimen, diagram.force, area0_mm2=area0, h0_mm=geo["h0"], window_MPa=modulus_window_MPa,
                                    window=modulus_window, modulus_reference=modulus_reference, method=modulus_method)
    except IdentificationError as exc:
        known = None if E_MPa is None else _line_of_known_slope(diagram, area0, geo["h0"], E_MPa)
        line, toe_mm = known if known is not None else (None, 0.0)
        if line is None:
            warnings.append(f"no elastic line ({exc}): the toe is not compensated; "
                            + (f"the handbook E = {E_MPa:g} MPa strips the elastic strain; Rp0.2 is not reported (no strain zero "
                               "to read its offset from: sample faster)" if E_MPa is not None
                               else "no modulus, so the elastic strain is not removed and there is no Rp0.2 — give E_MPa"))
    else:
        apparent = line.E_MPa
        onset = _yield_estimate_MPa(diagram, area0)
        if E_MPa is not None and onset is not None and (line.window_MPa[0] > onset or line.E_MPa < MIN_LINE_SLOPE_FRACTION * E_MPa):
            known = _line_of_known_slope(diagram, area0, geo["h0"], E_MPa)
            warnings.append(f"the line regressed on the first loading ({line.E_MPa:.4g} MPa over {line.window_MPa[0]:.4g}–{line.window_MPa[1]:.4g} MPa) "
                            f"starts above the force rate's yield estimate {onset:.4g} MPa or is flatter than {MIN_LINE_SLOPE_FRACTION:g} × E: not the elastic line; "
                            + (f"the handbook E = {E_MPa:g} MPa is placed on the first loading instead" if known is not None else "the toe is not compensated"))
            line, toe_mm = known if known is not None else (None, 0.0)
        elif E_MPa is not None:
            try:
                offsets = toe_offsets(specimen, diagram.force, line.window_MPa, E_MPa=E_MPa, area0_mm2=area0, h0_mm=geo["h0"])
            except IdentificationError as exc:  # the regressed window holds no sample of the first loading: E placed instead
                known = _line_of_known_slope(diagram, area0, geo["h0"], E_MPa)
                warnings.append(f"the regressed line's window {line.window_MPa[0]:.4g}–{line.window_MPa[1]:.4g} MPa ({exc}): "
                                + (f"the handbook E = {E_MPa:g} MPa is placed on the first loading instead" if known is not None
                                   else "the toe is not compensated"))
                line, toe_mm = known if known is not None else (None, 0.0)
            else:
                toe_mm = float(np.median(offsets))  # the toe of a line of known slope E; its offsets' spread judged
                # as δε0 judges it: the top sample's plastic part is where the plastic part starts (the spacing term), not a spread
                judged = geo["h0"] * known_slope_offsets(specimen / geo["h0"], diagram.force / area0, line.window_MPa, E_MPa)
                warnings += [w for w in [toe_spread_warning(judged, line.window_MPa, E_MPa=E_MPa, h0_mm=geo["h0"])] if w]
        elif line.E_MPa < METAL_E_RANGE_MPa[0]:
            warnings.append(f"apparent modulus {line.E_MPa:.4g} MPa over {line.window_MPa[0]:.4g}–{line.window_MPa[1]:.4g} MPa is far below any metal's: "
                            "the line found may be a toe or a stretch past yield, and Rp0.2 with it — give the handbook E (--E or material.E_MPa) "
                            "or name the material's grade")
    if line is not None and toe:
        on_line = line if E_MPa is None else replace(line, E_MPa=E_MPa)  # the toe replaced by the line the offset was read on
        specimen = compensate_toe_line(specimen, diagram.force, on_line, toe_mm, area0_mm2=area0, h0_mm=geo["h0"])
    return _Line(line=line, toe_mm=toe_mm, specimen=specimen, warnings=warnings, apparent_MPa=apparent)


def _nominal_curve(diagram: _Diagram, geo: dict, specimen: np.ndarray, E_MPa: float | None) -> _Nominal:
    """The shortening scaled to the measured one (3.1) and the nominal curve: strain (3.31), mean pressure (3.28)–(3.32)."""
    warnings: list[str] = []
    d0, h0, hk, force = geo["d0"], geo["h0"], geo["hk"], diagram.force
    # measured shortening at the largest load: h0 − hk plus the elastic spring-back — from the handbook E,
    # else as the unloading branch shows it (the frame compliance removed), else none (K_l then scales
    # the loaded shortening to the unloaded one: 0.5 % short for a 9 mm specimen at 1000 MPa)
    d_k = float(fr.nominal_diameter(d0, h0, hk))
    springback, source = 0.0, None
    if E_MPa is not None:
        springback, source = hk * (force[-1] / circle_area_mm2(d_k)) / E_MPa, "handbook E"  # elastic strain σ/E over hk
    elif diagram.springback is not None and diagram.stiffness is not None:
        springback, source = diagram.springback[0], f"unloading branch ({diagram.springback[1]} samples)"
    measured = h0 - hk + springback
    shortening, K_l = scale_to_measured(np.clip(specimen, 0.0, None), measured)  # (3.1) K_l = (h0 − hk)/max Δl
    if abs(K_l - 1.0) > 0.1:
        warnings.append(f"scaling factor K_l = {K_l:.3f} differs from 1 by more than 10 %: check the frame stiffness, hk and the crosshead channel")
    h = h0 - shortening
    strain = fr.height_strain(h, h0)  # (3.31)
    d_n = fr.nominal_diameter(d0, h0, h)  # (3.28)
    area = circle_area_mm2(d_n)  # (3.30)
    pressure = force / area  # (3.32) σ_n = P/S_i
    return _Nominal(springback=springback, springback_source=source, measured=measured, shortening=shortening, K_l=K_l, h=h, strain=strain, d_n=d_n,
                    pressure=pressure, warnings=warnings)


def _modulus_and_yield(nominal: _Nominal, line: ModulusFit | None, E_MPa: float | None, E_source: str) -> _Yield:
    """E (handbook, else the elastic line's slope on the scaled strain) and Rp0.2 on the nominal curve."""
    E_used, E_fit = E_MPa, None
    if E_MPa is None and line is not None:
        E_fit = line
        E_used, E_source = line.E_MPa / nominal.K_l, "apparent"  # the line's slope on the scaled strain
    elif E_MPa is None:
        E_source = "none"
    pressure = nominal.pressure
    rp02 = offset_yield(plastic_strain(nominal.strain, pressure, E_used), pressure) if E_used is not None else None
    i_yield = int(np.argmax(pressure >= rp02)) if rp02 is not None else 0
    if line is None:  # no line to place the strain zero on: the offset would be read on an uncompensated toe
        rp02 = None
    return _Yield(E_used=E_used, E_fit=E_fit, E_source=E_source, rp02=rp02, i_yield=i_yield)


def _strain_zero(diagram: _Diagram, geo: dict, line: _Line, nominal: _Nominal, yld: _Yield, friction: _Friction, fits: dict,
                 fit_range, law: str, friction_correction: str) -> tuple[dict, list[str]]:
    """The strain zero's uncertainty δε0 and its effect on the main fit's start and constants (§2.11);
    the main fit in ``fits`` gets the widened standard errors."""
    stress = diagram.force / geo["area0"]
    strain = line.specimen / geo["h0"]
    top = int(np.nanargmax(stress))
    el = line.line
    if el is None:
        window, E_line, E_se = (0.0, float(nominal.pressure[yld.i_yield])), math.nan, math.nan
    else:
        window, E_line, E_se = el.window_MPa, el.E_MPa, el.E_stderr_MPa
    E_used = yld.E_used if yld.E_used is not None else E_line
    zero = tension_or_compression_zero(strain[: top + 1], stress[: top + 1], window_MPa=window, E_line_MPa=E_line, E_line_stderr_MPa=E_se,
                                       E_used_MPa=E_used, line_resolved=yld.E_source == "apparent" and np.isfinite(E_se),
                                       zero_E_MPa=E_used if el is not None and yld.E_source != "apparent" else None)
    eps_tp, sig_t, _ = friction.corrected[friction_correction]
    idx = _fit_points(eps_tp, yld.i_yield, fit_range)
    fits[friction_correction], start, warnings = apply_to_fit(fits[friction_correction], eps_tp[idx], sig_t[idx], zero,
                                                              lambda e, s: fit_hardening(e, s, law))
    return start, warnings


def _flow_curve(eps_p: np.ndarray, stress_MPa: np.ndarray, i_yield: int, uncertainty_pct: np.ndarray | None = None,
                dsigma_dmu_MPa: np.ndarray | None = None) -> pd.DataFrame:
    """The curve a card starts from: where the plastic strain has passed the 0.2 % offset (with the
    correction's per-point uncertainty, %, where it has one, and the applied correction's ∂σ/∂μ, MPa
    per unit μ: a series fit weighs each point by u(μ)·|∂σ/∂μ|, docs/methods.md §5.10)."""
    plastic = np.nonzero((np.maximum.accumulate(eps_p) >= YIELD_OFFSET) & (eps_p >= 0) & (np.arange(eps_p.size) >= i_yield))[0]
    curve = {"true_plastic_strain": eps_p[plastic], "true_stress_MPa": stress_MPa[plastic]}
    if uncertainty_pct is not None:
        curve["correction_uncertainty_pct"] = uncertainty_pct[plastic]
    if dsigma_dmu_MPa is not None:
        curve["dsigma_dmu_MPa"] = np.asarray(dsigma_dmu_MPa, dtype=float)[plastic]
    return pd.DataFrame(curve)


def _curves(diagram: _Diagram, nominal: _Nominal, friction: _Friction, fit: HardeningFit) -> dict[str, pd.DataFrame]:
    """The intermediate curves for plots: raw and corrected diagram, nominal, one per correction, the fit."""
    curves: dict[str, pd.DataFrame] = {
        "raw_diagram": pd.DataFrame({"crosshead_displacement_mm": diagram.travel, "force_N": diagram.force}),
        "corrected_diagram": pd.DataFrame({"specimen_displacement_mm": nominal.shortening, "force_N": diagram.force}),
        "nominal": pd.DataFrame({"true_strain": nominal.strain, "mean_pressure_MPa": nominal.pressure, "height_mm": nominal.h}),
    }
    for method, (eps_tp, sig_t, eps_t) in friction.corrected.items():
        curves[f"true_{method}"] = pd.DataFrame({"true_plastic_strain": eps_tp, "true_stress_MPa": sig_t, "true_strain": eps_t})
    grid = np.linspace(fit.strain_range[0], fit.strain_range[1], FIT_CURVE_POINTS)
    curves["fit"] = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": fit(grid)})
    return curves


def _result(record: Record, geo: dict, diagram: _Diagram, line: _Line, nominal: _Nominal, yld: _Yield, friction: _Friction,
            fits: dict, warnings: list[str], *, start: dict | None = None, E_MPa: float | None, law: str, friction_correction: str, toe: bool) -> CompressionResult:
    """The typed result (result.json) of a compression identification."""
    t, strain, chosen, frictions, fit = diagram.t, nominal.strain, friction.chosen, friction.frictions, fits[friction_correction]
    duration = float(t[-1] - t[0])
    strain_rate = float(strain[-1] / duration) if duration > 0 else None
    K_l, el = nominal.K_l, line.line
    return CompressionResult(
        E_MPa=yld.E_used,
        E_source=yld.E_source,  # option (handbook) / apparent (initial slope, §2.3) / none
        Rp02_MPa=yld.rp02,  # compression yield: mean pressure at 0.2 % plastic strain
        max_force_N=float(np.max(diagram.force)),
        final_true_strain=float(strain[-1]),
        friction_mu=chosen.mu,
        friction_mu_range=chosen.extra.get("mu_range"),
        friction_method=chosen.method,
        friction={m: (r.mu if isinstance(r, fr.FrictionResult) else None) for m, r in frictions.items()},
        friction_details={m: (r.as_dict() if isinstance(r, fr.FrictionResult) else {"method": m, "error": r}) for m, r in frictions.items()},
        friction_correction=friction_correction,
        hardening=CompressionHardening(fit=fit, correction=friction_correction, start_uncertainty=start),
        hardening_by_correction={m: f.as_dict() for m, f in fits.items()},
        indicator={
            "frame_stiffness_N_per_um": diagram.stiffness,
            "K_l": K_l,
            "measured_shortening_mm": nominal.measured,
            "springback_mm": nominal.springback,
            "springback_source": nominal.springback_source,  # handbook E / unloading branch / None (not added)
            "max_specimen_displacement_mm": float(np.max(line.specimen)),
            "crosshead_step_interpolated_mm": diagram.step_mm,  # a stepped reading re-read between its steps (None: as read)
            **({"toe_compensation_mm": line.toe_mm if toe else None} if el is not None else {}),
        },
        methods={
            "friction": f"{chosen.method} (all: {', '.join(fr.FRICTION_METHODS)})",
            "friction_mu_stderr": _mu_stderr_basis(chosen),
            "correction": f"{friction_correction} (all: {', '.join(fr.CORRECTIONS)})",
            "stress": "mean pressure P/S, S = pi*d_n^2/4, d_n = d0*sqrt(h0/h) (3.28)-(3.32)",
            "scaling": "K_l = (h0 - hk [+ spring-back]) / max(specimen displacement) (3.1)",
            "elastic_volume": (f"fe_table: sigma_f = p / (factor * J), J = exp(-(1 - 2 nu) sigma_f / E), nu {geo['nu']:g} ({geo['nu_source']})"
                               if yld.E_used is not None else "fe_table: volume-constant area (no modulus)"),
            "hardening": f"{law} least squares on the {friction_correction} curve, eps_p >= {YIELD_OFFSET}",
        },
        warnings=warnings,
        dface_advice=_dface_advice(chosen),
        record={
            "path": record.source,
            "material": record.meta.get("material"),
            "nominal_temperature_C": record.number("nominal_temperature_C"),
            "crosshead_speed_mm_per_s": record.number("crosshead_speed_mm_per_s"),
            "strain_rate_per_s": strain_rate,  # mean true strain rate of the loading branch
            "specimen": {"d0_mm": geo["d0"], "h0_mm": geo["h0"]},
            "post": {"hk_mm": geo["hk"], "dmax_mm": geo["dmax"], "smax_mm2": geo["smax"]},
        },
        E_apparent_stderr_MPa=yld.E_fit.E_stderr_MPa / K_l if yld.E_fit is not None else None,
        modulus=None if el is None else {**el.as_dict(), "E_MPa": yld.E_used, "E_line_MPa": el.E_MPa / K_l,
                                         "E_stderr_MPa": el.E_stderr_MPa / K_l, "source": yld.E_source if E_MPa is not None else el.source},
    )


def _modulus_method(choice: ModulusChoice, yld: _Yield, line: _Line) -> dict:
    """result.json's methods.elastic_modulus: the E that stripped the elastic strain, its standard
    uncertainty and where it came from (the rule's class), and the first loading's apparent slope."""
    if yld.E_source == "apparent" and yld.E_used is not None:
        scale = yld.E_used / yld.E_fit.E_MPa if yld.E_fit is not None else math.nan  # 1/K_l: the slope on the scaled strain
        u = yld.E_fit.E_stderr_MPa * scale if yld.E_fit is not None else math.nan
        out = {"E_MPa": yld.E_used, "u_MPa": u if math.isfinite(u) else None, "source": "apparent",
               "basis": "the first loading's slope (frame removed, toe and grips in it): no defensible E (no --E, material.E_MPa or class)"}
    else:
        out = {"E_MPa": choice.E_MPa, "u_MPa": choice.u_MPa if choice.E_MPa is not None else None, "source": choice.source, "basis": choice.basis}
    out["apparent_MPa"] = line.apparent_MPa
    return out


def _mu_sensitivity(geo: dict, nominal: _Nominal, friction, friction_correction: str, E_used: float | None, curves: dict) -> np.ndarray:
    """∂σ/∂μ of the correction applied, across μ's stated range (:func:`correction_mu_sensitivity`), also
    written into its true curve's ``dsigma_dmu_MPa`` column: the flow stress budget's μ term reads this
    correction's sensitivity, not Siebel's (uncertainty.flow_stress_budget)."""
    sensitivity = correction_mu_sensitivity(geo, nominal, friction.chosen.mu, friction_correction, E_used,
                                            mu_range=friction.chosen.extra.get("mu_range"))
    curves[f"true_{friction_correction}"]["dsigma_dmu_MPa"] = sensitivity
    return sensitivity


def identify_compression(record: Record, *, friction_method: str = fr.DEFAULT_FRICTION_METHOD,
                         friction_correction: str = fr.DEFAULT_CORRECTION, law: str = "johnson_cook", E_MPa: float | None = None,
                         frame_stiffness_N_per_um: float | None = None, modulus_window_MPa: tuple[float, float] | None = None,
                         modulus_window: tuple[float, float] | None = None, modulus_reference: str = "Rp02", toe: bool = True,
                         fit_range: tuple[float, float] | None = None, modulus_method: str = DEFAULT_MODULUS_METHOD) -> Identification:
    """Identify a compression record: friction, friction-corrected true curves and hardening.

    Parameters
    ----------
    record : Record
        A compression record with its post-test measurements (barrel, faces).
    friction_method, friction_correction : str
        μ by "fe_table", "bulge_regression" or "ebrahimi_najafizadeh"; the correction by
        "fe_table", "k_sigma", "siebel" or "slab".
    law, fit_range : str, tuple
        The hardening law; (lo, hi) true plastic strain of its fit.
    E_MPa, frame_stiffness_N_per_um : float, optional
        Handbook E (MPa; else the apparent one) and frame stiffness (N/µm; else the record's).
    modulus_window_MPa, modulus_window, modulus_reference, modulus_method, toe : optional
        E's window in MPa or in fractions of ``modulus_reference`` (Rp02, Rm); "window", "sdar",
        "auto" (:func:`elastic_line`); ``toe`` compensates a soft start.

    Returns
    -------
    Identification
        A CompressionResult (friction, yield, fits, uncertainty) and the curves.
    """
    _check_options(friction_correction, E_MPa)
    E_MPa, E_source, E_choice = _handbook_modulus(record, E_MPa)
    geo = _meta_geometry(record)
    _friction_all(geo, friction_method, [])  # friction first: it needs only the post-test measurements, and bad ones should stop early
    diagram = _inputs(record, frame_stiffness_N_per_um)
    line = _elastic_line(diagram, geo, E_MPa=E_MPa, modulus_window_MPa=modulus_window_MPa, modulus_window=modulus_window,
                         modulus_reference=modulus_reference, toe=toe, modulus_method=modulus_method)
    if E_choice.source == "class":
        line.warnings += [w for w in [apparent_modulus_warning(line.apparent_MPa, record.meta.get("material"))] if w]
    nominal = _nominal_curve(diagram, geo, line.specimen, E_MPa)
    yld = _modulus_and_yield(nominal, line.line, E_MPa, E_source)
    friction = _friction_correction(geo, nominal, friction_method, yld.E_used)
    eps_c, sig_c, _ = friction.corrected[friction_correction]
    chosen_on = _fit_points(eps_c, yld.i_yield, fit_range)
    law, law_choice = resolve_law(law, eps_c[chosen_on], sig_c[chosen_on])  # --law best: chosen on the reported curve's fit points
    fits, fit_warnings = _hardening_fits(record.source, friction.corrected, yld.i_yield, fit_range, law, friction_correction)
    start, start_warnings = _strain_zero(diagram, geo, line, nominal, yld, friction, fits, fit_range, law, friction_correction)
    warnings = diagram.warnings + line.warnings + nominal.warnings + friction.warnings + fit_warnings + start_warnings
    result = _result(record, geo, diagram, line, nominal, yld, friction, fits, warnings, start=start, E_MPa=E_MPa, law=law,
                     friction_correction=friction_correction, toe=toe)
    result.methods["elastic_modulus"] = _modulus_method(E_choice, yld, line)
    result.hardening.fit.law_choice = law_choice
    eps_def, sig_def, _ = friction.corrected[friction_correction]
    _model_form_shares(record.source, geo, nominal, yld, friction, fits[friction_correction], result, fit_range, law, friction_correction)
    uncertainty = None
    if friction_correction == "fe_table":
        uncertainty, result.methods["correction_uncertainty"], fold_warnings = _fe_correction_uncertainty(geo, friction, yld.E_used)
        result.warnings.extend(fold_warnings)
    curves = _curves(diagram, nominal, friction, fits[friction_correction])
    if uncertainty is not None:  # the flow stress budgets state the correction's own σ per point (assurance)
        curves["true_fe_table"]["correction_uncertainty_pct"] = uncertainty
    sensitivity = _mu_sensitivity(geo, nominal, friction, friction_correction, yld.E_used, curves)
    return Identification(result=result, true_curve=_flow_curve(eps_def, sig_def, yld.i_yield, uncertainty, sensitivity), curves=curves)

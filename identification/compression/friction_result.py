"""Friction in a compression identification (docs/methods.md §4): μ by every method, the chosen
correction's curve, and what μ's uncertainty does to the constants (its share, the FE table's
resolution, the model form, the end-face advice)."""

from __future__ import annotations

import math

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.compression import friction as fr
from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.laws.hardening import RANGE_SHARE_PART, HardeningFit, pattern_shift, range_shift, static_form
from flowcurve.identification.results import CompressionResult
from flowcurve.identification.compression.values import _Friction, _Nominal, _Yield, _fit_points, _hardening_fits, plastic_strain


def _friction_all(geo: dict, chosen: str, warnings: list[str], curve=None) -> tuple[fr.FrictionResult, dict[str, fr.FrictionResult | str]]:
    if chosen not in fr.FRICTION_METHODS:
        raise IdentificationError(f"unknown friction method {chosen!r} (choose from {', '.join(fr.FRICTION_METHODS)})")
    results: dict[str, fr.FrictionResult | str] = {}
    for method in fr.FRICTION_METHODS:
        try:
            results[method] = fr.identify_friction(method, geo["d0"], geo["h0"], geo["hk"], d_max_mm=geo["dmax"], s_max_mm2=geo["smax"], d_top_mm=geo["dtop"], curve=curve,
                                                     d_face_mm=geo.get("dface"))
        except IdentificationError as exc:
            if method == chosen:
                raise
            results[method] = str(exc)
            warnings.append(f"friction method {method} not applicable: {exc}")
    return results[chosen], results


MU_RESOLUTION_WARN = 0.02  # μ moved by more than this by one dmax resolution step: say so
MEASURE_THE_FACE = ", or measure the original end face's diameter (post.dface_mm), which still shrinks with μ there"


def _fe_table_warnings(chosen: fr.FrictionResult) -> list[str]:
    """What the FE table's μ cannot promise: a hardening beyond its axes, a barrel that no
    longer grows with μ (near sticking: μ is then a lower bound; the force factor is as flat)."""
    if chosen.method != "fe_table":
        return []
    out = [f"FE table: {w}; read at the table's edge (--method inverse-fe runs the record's own law)" for w in chosen.extra.get("outside_table", [])]
    continued = chosen.extra.get("continued_runs_from_strain")
    if continued is not None:
        out.append(f"FE table: μ and the correction beyond ε {continued:.2f} rest on runs that stopped there (the side folding onto the "
                   "platen) and were continued along the next lower μ: an estimate (--method inverse-fe runs the record itself)")
    sensitivity = chosen.extra.get("sensitivity", {})
    by_face = "mu_per_dface_resolution" in sensitivity
    dmu = sensitivity.get("mu_per_dface_resolution" if by_face else "mu_per_dmax_resolution")
    told_by = "the end face (a dface" if by_face else "the bulge (a dmax"
    if sensitivity and dmu is None:
        out.append(f"FE table: the bulge does not grow with μ near {chosen.mu:.3f} (the faces stick): take μ as a lower bound{MEASURE_THE_FACE}")
    elif dmu is not None and dmu > MU_RESOLUTION_WARN:
        out.append(f"FE table: μ {chosen.mu:.3f} is poorly told by {told_by} reading off by {fr.DIAMETER_RESOLUTION_MM} mm moves it by "
                   f"{dmu:.2g}; the faces nearly stick): take μ as a lower bound"
                   + ("" if by_face else MEASURE_THE_FACE))
    return out


def _friction_disagreement(chosen: fr.FrictionResult) -> str | None:
    """A warning when the end face's μ and the bulge's differ beyond their combined standard
    errors (:data:`.fe.model_form.DISAGREE_SIGMAS`), else None: the shape pulls μ two ways."""
    z = chosen.extra.get("face_bulge_disagreement_sigmas")
    if z is None or not z > mf.DISAGREE_SIGMAS:
        return None
    return (f"friction: μ from the end face {chosen.mu:.3f} ± {chosen.extra['mu_stderr']:.3f} and from the bulge "
            f"{chosen.extra['mu_from_bulge']:.3f} ± {chosen.extra['mu_from_bulge_stderr']:.3f} disagree ({z:.1f} combined standard "
            "errors): the upsetting model does not describe this specimen's shape; the hardening is poor")


def _mu_share(src: str, geo: dict, nominal: _Nominal, friction: _Friction, i_yield: int, fit_range, law: str,
              friction_correction: str, E_used: float | None) -> dict[str, float]:
    """μ's share of the constants' standard errors: the curve corrected and fitted again at μ ∓ its
    standard error ({} when μ has none or a refit fails)."""
    se_mu = friction.chosen.extra.get("mu_stderr")
    if not (se_mu and math.isfinite(se_mu) and friction_correction in fr.CORRECTIONS):
        return {}
    eps_p = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    elastic = None if E_used is None else (E_used, geo["nu"])
    params = []
    for mu in (max(friction.chosen.mu - se_mu, 0.0), friction.chosen.mu + se_mu):
        eps_t, sig_t = fr.correct(friction_correction, nominal.strain, nominal.pressure, mu, nominal.d_n / 2.0, nominal.h, eps_p=eps_p, elastic=elastic)
        try:
            fits, _ = _hardening_fits(src, {friction_correction: (plastic_strain(eps_t, sig_t, E_used), sig_t, eps_t)}, i_yield, fit_range, law,
                                      friction_correction)
        except IdentificationError:
            return {}
        params.append(fits[friction_correction].params)
    return mf.through_mu(*params)


def _constants_stderr(src: str, geo: dict, nominal: _Nominal, friction: _Friction, fit: HardeningFit, i_yield: int, fit_range, law: str,
                      friction_correction: str, E_used: float | None) -> dict[str, dict[str, float]]:
    """The shares of the hardening constants' standard errors beyond the fit's: μ's (:func:`_mu_share`);
    on the FE table's correction, the model form's force error (:func:`.fe.model_form.force_model_form`)
    as a uniform offset and as one growing with strain, each refitted; and the fit range's (the
    constants fitted again over the first half of the range, :func:`.hardening.range_shift`): a
    curve whose shape departs from the law moves correlated constants (A and n) far more than the
    curve itself moves."""
    shares: dict[str, dict[str, float]] = {}
    by_mu = _mu_share(src, geo, nominal, friction, i_yield, fit_range, law, friction_correction, E_used)
    if by_mu:
        shares["friction μ (fits at μ ∓ its standard error)"] = by_mu
    eps_tp, sig_t, _ = friction.corrected[friction_correction]
    idx = _fit_points(eps_tp, i_yield, fit_range)
    eps_fit, sig_fit = eps_tp[idx], sig_t[idx]
    if friction_correction == "fe_table":
        u_force = mf.force_model_form(friction.chosen.mu)
        eps_t = friction.corrected[friction_correction][2]
        end = float(np.nanmax(eps_t[np.isfinite(sig_t)])) if np.isfinite(sig_t).any() else None
        patterns = mf.correction_force_patterns(eps_fit, eps_t[idx], friction.chosen.mu, geo["h0"] / geo["d0"], end)
        by_pattern = [pattern_shift(eps_fit, sig_fit, u_force, g, law) for g in patterns]
        how = "uniform and growing with strain" if len(patterns) == 2 else "following friction's share along the stroke"
        shares[f"FE model form ({u_force:.1%} of the force at μ {friction.chosen.mu:.3f}, {how})"] = {
            k: mf.quadrature(*(b.get(k, 0.0) for b in by_pattern)) for k in fit.params}
    by_range = range_shift(eps_fit, sig_fit, law)
    if by_range:
        shares[f"fit range (fitted again over its first {RANGE_SHARE_PART:.0%})"] = by_range
    return shares


def trade_off_note(fit: HardeningFit, limit: float = 0.9) -> str | None:
    """A note when two constants' correlation exceeds ``limit``: the curve is known better than either."""
    pairs = [(abs(r), a, b, r) for a, row in fit.correlations.items() for b, r in row.items() if a < b and abs(r) > limit]
    if not pairs:
        return None
    _, a, b, r = max(pairs)
    return (f"{a} and {b} trade off (correlation {r:+.2f}): the curve is known better than either constant; "
            "compare fits through the curve, not constant by constant")


def stderr_shares(shares: dict[str, dict[str, float]], fit: HardeningFit) -> dict[str, dict[str, float]]:
    """The shares as result.json's ``hardening.stderr_shares``: "method: <share>" → {result key (A_MPa …): u}
    (:func:`.quality.uncertainty.constant_budget` states each as its own component)."""
    keys = dict(zip(static_form(fit.law).names, static_form(fit.law).keys))
    return {f"method: {name}": {keys[k]: float(u) for k, u in per.items() if k in keys} for name, per in shares.items()}


def _model_form_shares(src: str, geo: dict, nominal: _Nominal, yld: _Yield, friction: _Friction, fit: HardeningFit, result: CompressionResult,
                       fit_range, law: str, friction_correction: str) -> None:
    """The main fit's standard errors with μ's and the model form's shares (:func:`_constants_stderr`)
    in quadrature, each share also kept apart (:func:`stderr_shares`) so that the budget states it as
    a component of its own; said in ``methods.hardening_stderr``; a face and bulge that disagree make
    it poor, with a warning."""
    shares = _constants_stderr(src, geo, nominal, friction, fit, yld.i_yield, fit_range, law, friction_correction, yld.E_used)
    fit.stderr = mf.combined_stderr(fit.stderr, *shares.values())
    result.hardening.stderr_shares = stderr_shares(shares, fit)
    note = trade_off_note(fit)
    result.methods["hardening_stderr"] = "; ".join(["the fit's standard errors", *shares]) + " (in quadrature)" + (f". {note}" if note else "")
    disagreement = _friction_disagreement(friction.chosen)
    if disagreement:
        fit.doubt = disagreement
        result.warnings.append(disagreement)


def _dface_advice(chosen: fr.FrictionResult) -> str | None:
    """The advice to measure dface when the FE table's μ rests on a bulge that hardly tells it, else None."""
    sensitivity = chosen.extra.get("sensitivity", {})
    if chosen.method != "fe_table" or "mu_per_dface_resolution" in sensitivity or not sensitivity:
        return None
    dmu = sensitivity.get("mu_per_dmax_resolution")
    return fr.DFACE_ADVICE if dmu is None or dmu > MU_RESOLUTION_WARN else None


def _friction_correction(geo: dict, nominal: _Nominal, friction_method: str, E_used: float | None) -> _Friction:
    """μ (again, now with the curve: the FE table's μ depends on the hardening) and the curve by every correction."""
    warnings: list[str] = []
    eps_p = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    curve = (nominal.strain, nominal.pressure) if eps_p is None else (nominal.strain, nominal.pressure, eps_p)
    chosen, frictions = _friction_all(geo, friction_method, warnings, curve=curve)
    warnings += _fe_table_warnings(chosen)
    corrected = {}
    elastic = None if E_used is None else (E_used, geo["nu"])  # fe_table: the pressure on the loaded area
    for method in fr.CORRECTIONS:
        eps_t, sig_t = fr.correct(method, nominal.strain, nominal.pressure, chosen.mu, nominal.d_n / 2.0, nominal.h, eps_p=eps_p, elastic=elastic)
        corrected[method] = (plastic_strain(eps_t, sig_t, E_used), sig_t, eps_t)
    return _Friction(chosen=chosen, frictions=frictions, corrected=corrected, warnings=warnings)


MU_SENSITIVITY_STEP = 0.01  # the secant's half step in μ (the FE table's μ nodes are 0.05 apart)


def correction_mu_sensitivity(geo: dict, nominal: _Nominal, mu: float, friction_correction: str, E_used: float | None,
                              step: float = MU_SENSITIVITY_STEP, mu_range=None) -> np.ndarray:
    """∂σ/∂μ, MPa per unit μ, at every point of the nominal curve, of the correction actually applied: the curve
    corrected again at the ends of μ's stated ±1σ range ``mu_range`` [lo, hi] (u(μ) = (hi − lo)/2), the secant
    between them, so that u(μ)·∂σ/∂μ is half the change of σ across that range; without a range (or an empty
    one) at μ ± ``step`` (the lower end at μ = 0 at most).

    The range is where μ is stated to lie: near sticking it is one-sided (the end face or the bulge no longer
    grows with μ, or the table's runs were continued: up to the table's largest μ), and the local slope at μ times its
    half-width extrapolated σ's change to a μ below the range, where σ moves most (issue 43)."""
    # ∂σ/∂μ ≈ (σ(hi) − σ(lo)) / (hi − lo), σ by fr.correct on the same p(ε); hi, lo the range's ends or μ ± s
    eps_p = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    elastic = None if E_used is None else (E_used, geo["nu"])
    lo, hi = max(mu - step, 0.0), mu + step
    if mu_range is not None and len(mu_range) == 2 and all(v is not None and math.isfinite(v) for v in mu_range) \
            and float(mu_range[1]) - float(mu_range[0]) > 1e-9:
        lo, hi = max(float(mu_range[0]), 0.0), float(mu_range[1])
    sig_lo, sig_hi = (fr.correct(friction_correction, nominal.strain, nominal.pressure, m, nominal.d_n / 2.0, nominal.h, eps_p=eps_p,
                                 elastic=elastic)[1] for m in (lo, hi))
    return (np.asarray(sig_hi, dtype=float) - np.asarray(sig_lo, dtype=float)) / (hi - lo)


def _fe_correction_uncertainty(geo: dict, friction: _Friction, E_used: float | None) -> tuple[np.ndarray, str, list[str]]:
    """Per point of the fe_table-corrected curve: its stress's σ, % (:func:`.fe.model_form.corrected_stress_uncertainty_pct`:
    the model form's force share at μ, growing to the inverse's 3 % over the band before the table's
    fold-over onset, :func:`.friction.fe_fold_over_onset`), what it holds, and a warning when the
    curve reaches that band."""
    eps_tp, sig_t, eps_t = friction.corrected["fe_table"]
    mu, h0_d0 = friction.chosen.mu, geo["h0"] / geo["d0"]
    ok = np.isfinite(sig_t) & (eps_t > 0)
    onset = fr.fe_fold_over_onset(mu, h0_d0, eps_t[ok], sig_t[ok], eps_tp[ok] if E_used is not None else None)
    u = mf.corrected_stress_uncertainty_pct(eps_t, mu, onset, h0_d0, float(np.nanmax(eps_t[ok])) if ok.any() else None)
    u_mf = 100.0 * mf.force_model_form(mu)
    basis = (f"fe_table: per point (true_curve.csv correction_uncertainty_pct) the model form's {u_mf:.1f} % of the force at μ {mu:.3f}"
             + (f", growing to {float(u.max()):.1f} % over ε {onset - mf.FOLD_OVER_BAND:.2f}–{onset:.2f} before the table's fold-over onset"
                if onset is not None else "; no fold-over in the table's runs at this μ, h0/d0 and hardening"))
    warnings = []
    band = None if onset is None else onset - mf.FOLD_OVER_BAND
    if band is not None and np.nanmax(eps_t) > band and float(u.max()) > u_mf + 0.05:
        order = np.argsort(eps_t[ok])
        eps_p_band = float(np.interp(band, eps_t[ok][order], eps_tp[ok][order]))
        warnings.append(f"fe_table correction: the points from ε {band:.2f} (ε_p {eps_p_band:.2f}) on carry the side folding onto the platen "
                        f"(the table's runs fold over from ε {onset:.2f} at μ {mu:.3f}, h0/d0 {h0_d0:.2g}; a finer model folds over earlier "
                        f"and differs by up to 2 % in force there): their uncertainty grows from {u_mf:.1f} % to {float(u.max()):.1f} % "
                        "(true_curve.csv correction_uncertainty_pct)")
    return u, basis, warnings


def _mu_stderr_basis(chosen: fr.FrictionResult) -> str:
    """What μ's standard error (``friction_details[method].mu_stderr``) holds, for result.json's methods."""
    if chosen.extra.get("mu_stderr") is None:
        return "none: mu has no standard error"
    basis = chosen.extra.get("mu_stderr_basis")
    return basis if basis else f"half mu_range ({chosen.extra.get('mu_range_basis')})"

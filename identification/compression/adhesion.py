"""Adhesion friction constants τ0, β0, k_b, θ_k (and σ_S) from rotating-sphere tests.

The friction law of the seed's cutting simulations (2.25), docs/methods.md §6:

    τ = τ_a + τ_d,   τ_d = μ_d·σ_n,   τ_a = τ0 + (β0 − k_b·max(0, T − θ_k))·σ_nr

with σ_n the nominal and σ_nr the real contact pressure (σ_nr = σ_n / K_r, K_r the ratio of
real to nominal contact area). Two identifications from adhesiometer tests (N_z, M_z, r, T):

* :func:`fit_simple` — (3.35)–(3.37): the mean shear stress of each test τ_n = 0.540·M_z/r³,
  minus the deformation part μ_d·σ̄_n, against the mean pressure σ̄_n = N_z/(π r²), by least
  squares. (3.35) is exact for a shear that follows the Hertz pressure; it reads a uniform
  shear τ0 as (32/(9π))·τ0 = 1.132·τ0 (:data:`UNIFORM_SHEAR_WEIGHT`), so the intercept of the
  regression is divided by that factor (the raw intercept is reported as ``tau0_intercept_MPa``).
* :func:`fit_refined` — (3.38)–(3.44): every test's moment from the Hertz pressure
  distribution (3.43) integrated over the imprint (3.39), in closed form, fitted to all
  (N_z, M_z, r) at once for τ0, β0 and the surface flow stress σ_S.

Relations the seed leaves unstated, and what is used here (named in the result):

* K_r(σ_n/σ_S) — :func:`contact_ratio_bowden_tabor`: under plastic contact the real area carries
  the flow pressure of the softer body, p_real = c·σ_S with Tabor's constraint factor c = 3
  (Bowden & Tabor, *The Friction and Lubrication of Solids*, Oxford 1950, ch. 1; Tabor,
  *The Hardness of Metals*, Oxford 1951: H ≈ 3Y); hence K_r = min(1, σ_n/(3σ_S)).
  ``"none"`` (K_r = 1, σ_nr = σ_n) is the seed's simple fit with the nominal pressure.
* μ_d — given by the user, or :func:`deformation_friction_kragelsky` from the microrelief of the
  sphere (R_p, t_m, an asperity radius): Kragelsky's deformation component for plastic
  contact, μ_d = 0.55·√(h/r_a), with the penetration h from the bearing curve t_p = t_m·(h/R_p)^ν
  at the real contact ratio (I. V. Kragelsky, *Friction and Wear*, Butterworths 1965;
  Kragelsky, Dobychin, Kombalov, *Friction and Wear: Calculation Methods*, Pergamon 1982).
* Hot constants k_b, θ_k: fitted when tests at two or more temperatures ≥ 600 °C exist (seed
  3.2.1 step д); otherwise the seed's first approximation θ_k = 700 °C, k_b = β0/300.

Units: N, mm, MPa (N/mm²), °C; moments N·mm inside (the table keeps N·m).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.record.adhesion import AdhesionTable

log = logging.getLogger(__name__)

HERTZ_MEAN_FACTOR = 16.0 / (3.0 * math.pi**2)  # (3.35) = 0.540
UNIFORM_SHEAR_WEIGHT = 32.0 / (9.0 * math.pi)  # (3.35) applied to a uniform shear: 1.132
TABOR_CONSTRAINT = 3.0  # H ≈ 3·σ_S (Tabor 1951)
HOT_FROM_C = 600.0  # seed 3.2.1 д: hot tests at 600, 700, 800 °C
SEED_THETA_K_C = 700.0  # seed 3.2.1: θ_k ≈ 700 °C
SEED_KB_DIVISOR = 300.0  # seed 3.2.1: k_b ≈ β0/300
N_MM_PER_N_M = 1e3

EQUATION = ("tau_MPa = tau0 + (beta0 - k_b*max(0, T - theta_k))*sigma_nr + mu_d*sigma_n; "
            "sigma_nr = sigma_n/K_r (real contact pressure)")

CONTACT_RATIO_MODELS = {
    "none": "K_r = 1: the real pressure is the nominal pressure (seed (3.37) with sigma_nr = N_z/(pi r^2))",
    "bowden_tabor": ("K_r = min(1, sigma_n/(3 sigma_S)): the real contact carries the flow pressure 3 sigma_S "
                     "(Bowden & Tabor 1950; Tabor, The Hardness of Metals, 1951)"),
}
MU_D_KRAGELSKY = ("mu_d = 0.55*sqrt(h/r_a), h = R_p*(K_r/t_m)^(1/nu): Kragelsky's deformation component for plastic "
                  "contact with the bearing curve t_p = t_m*(h/R_p)^nu (Kragelsky 1965; Kragelsky, Dobychin, Kombalov 1982)")


# -- the seed's relations (pure, vectorized) ------------------------------------------------------


def mean_shear_stress(moment_N_mm, radius_mm):
    """# (3.35) τ_n = 16/(3π²)·M_z/r³ (MPa from N·mm and mm)."""
    return HERTZ_MEAN_FACTOR * np.asarray(moment_N_mm, dtype=float) / np.asarray(radius_mm, dtype=float) ** 3


def nominal_mean_pressure(force_N, radius_mm):
    """# (3.37) σ̄_n = N_z/(π r²), the nominal mean pressure over the imprint (MPa)."""
    return np.asarray(force_N, dtype=float) / (math.pi * np.asarray(radius_mm, dtype=float) ** 2)


def hertz_pressure(force_N, radius_mm, r_mm):
    """# (3.43) σ_n(r) = 3N/(2π a³)·√(a² − r²) (MPa), zero outside the imprint."""
    a = np.asarray(radius_mm, dtype=float)
    return 3.0 * np.asarray(force_N, dtype=float) / (2.0 * math.pi * a**3) * np.sqrt(np.maximum(a**2 - np.asarray(r_mm, dtype=float) ** 2, 0.0))


def beta_at(temperature_C, beta0, k_b, theta_k_C):
    """# (2.25) β(T) = β0 − k_b·max(0, T − θ_k)."""
    return beta0 - k_b * np.maximum(0.0, np.asarray(temperature_C, dtype=float) - theta_k_C)


def adhesion_shear(sigma_nr, temperature_C, tau0, beta0, k_b, theta_k_C):
    """# (2.25) τ_a = τ0 + β(T)·σ_nr on the real contact (MPa)."""
    return tau0 + beta_at(temperature_C, beta0, k_b, theta_k_C) * np.asarray(sigma_nr, dtype=float)


def contact_ratio_bowden_tabor(pressure_ratio, constraint=TABOR_CONSTRAINT):
    """# K_r for (3.42)/(3.44): min(1, (σ_n/σ_S)/c), c = 3 (Bowden & Tabor 1950; Tabor 1951)."""
    return np.minimum(1.0, np.asarray(pressure_ratio, dtype=float) / constraint)


def contact_ratio(model: str, pressure_MPa, flow_stress_MPa):
    """K_r of the named model at nominal pressure ``pressure_MPa`` (1 for ``"none"``)."""
    p = np.asarray(pressure_MPa, dtype=float)
    if model == "none":
        return np.ones_like(p)
    if model == "bowden_tabor":
        return contact_ratio_bowden_tabor(p / np.asarray(flow_stress_MPa, dtype=float))
    raise IdentificationError(f"unknown contact-area model {model!r} (use: {', '.join(CONTACT_RATIO_MODELS)})")


def hertz_moment_integral(radius_mm):
    """# (3.39) with (3.43): ∫₀ᵃ r²·√(a² − r²) dr = π a⁴/16 (closed form)."""
    return math.pi * np.asarray(radius_mm, dtype=float) ** 4 / 16.0


def _quarter_disc_moment(r, a):
    """Antiderivative of r²·√(a² − r²): [r(2r² − a²)√(a² − r²) + a⁴ arcsin(r/a)]/8."""
    return (r * (2.0 * r**2 - a**2) * np.sqrt(np.maximum(a**2 - r**2, 0.0)) + a**4 * np.arcsin(np.clip(r / a, 0.0, 1.0))) / 8.0


def contact_ratio_moment_integral(radius_mm, peak_ratio):
    """# (3.39)/(3.44) ∫₀ᵃ r²·K_r(σ_n(r)/σ_S) dr for K_r = min(1, σ_n/(3σ_S)), closed form.

    peak_ratio q = p0/(3σ_S), p0 = 3N/(2π a²) the Hertz peak: K_r = q·√(1 − r²/a²) where that is
    below 1; the core r < r_c = a√(1 − 1/q²) is in full contact (K_r = 1) when q > 1.
    """
    a = np.asarray(radius_mm, dtype=float)
    q = np.asarray(peak_ratio, dtype=float)
    rc = np.where(q > 1.0, a * np.sqrt(np.maximum(1.0 - 1.0 / np.maximum(q, 1.0) ** 2, 0.0)), 0.0)
    return rc**3 / 3.0 + (q / a) * (_quarter_disc_moment(a, a) - _quarter_disc_moment(rc, a))


def refined_moment(force_N, radius_mm, temperature_C, tau0, beta0, k_b, theta_k_C, flow_stress_MPa, mu_d,
                   model: str = "bowden_tabor"):
    """# (3.38)–(3.44) M_z = 2π∫₀ᵃ r²·τ_n(r) dr (N·mm) for the Hertz pressure (3.43).

    τ_n = μ_d·σ_n + (τ0 + β·σ_nr)·K_r with σ_nr = σ_n/K_r (3.40)–(3.44), i.e. τ_n = μ_d·σ_n +
    τ0·K_r + β·σ_n, integrated in closed form: (3π/16)(μ_d + β)·N·a + 2π·τ0·∫r²K_r dr.
    """
    N = np.asarray(force_N, dtype=float)
    a = np.asarray(radius_mm, dtype=float)
    beta = beta_at(temperature_C, beta0, k_b, theta_k_C)
    if model == "none":
        contact = a**3 / 3.0
    elif model == "bowden_tabor":
        peak = 3.0 * N / (2.0 * math.pi * a**2)
        contact = contact_ratio_moment_integral(a, peak / (TABOR_CONSTRAINT * np.asarray(flow_stress_MPa, dtype=float)))
    else:
        raise IdentificationError(f"unknown contact-area model {model!r} (use: {', '.join(CONTACT_RATIO_MODELS)})")
    return 3.0 * math.pi / 16.0 * (np.asarray(mu_d, dtype=float) + beta) * N * a + 2.0 * math.pi * tau0 * contact


def deformation_friction_kragelsky(Rp_um, tm, asperity_radius_um, contact_ratio_value, bearing_exponent=2.0):
    """# μ_d for (2.25)/(3.41): 0.55·√(h/r_a), h = R_p·(K_r/t_m)^(1/ν) (Kragelsky 1965, plastic contact).

    The penetration is capped at the full bearing (t_p = 1).
    """
    tm = np.asarray(tm, dtype=float)
    eps = np.power(np.minimum(np.asarray(contact_ratio_value, dtype=float), 1.0) / tm, 1.0 / bearing_exponent)
    eps = np.minimum(eps, np.power(1.0 / tm, 1.0 / bearing_exponent))
    return 0.55 * np.sqrt(np.asarray(Rp_um, dtype=float) * eps / np.asarray(asperity_radius_um, dtype=float))


# -- the fits -------------------------------------------------------------------------------------


@dataclass
class FrictionFit:
    """Identified constants of (2.25), their uncertainties and what they were identified on."""

    method: str
    values: dict[str, float | None]  # tau0_MPa, beta0, k_b_per_C, theta_k_C, sigma_S_MPa, mu_d
    stderr: dict[str, float | None]
    correlations: dict[str, dict[str, float]]
    sources: dict[str, str]
    tests: list[dict]
    contact_model: str
    covered: dict[str, list[float]]
    report: str = ""
    extra: dict = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        """friction.json (docs/adhesion.md)."""
        out: dict = {"schema": "flowcurve-friction/1", "model": "adhesion_deformation_2.25", "method": self.method,
                     "equation": EQUATION}
        for key, value in self.values.items():
            out[key] = value
            out[f"{key}_stderr"] = self.stderr.get(key)
        out.update({f"{key}_source": text for key, text in self.sources.items()})
        out["contact_ratio_model"] = self.contact_model
        out["contact_ratio_model_source"] = CONTACT_RATIO_MODELS[self.contact_model]
        out["correlations"] = self.correlations
        out["range"] = self.covered
        out.update(self.extra)
        out["tests"] = self.tests
        out["warnings"] = list(self.warnings)
        out["report"] = self.report
        return out


@dataclass
class _Series:
    """The table as arrays in the fit's units (N, mm, N·mm, °C, MPa)."""

    test_id: list[str]
    force_N: np.ndarray
    moment_N_mm: np.ndarray
    radius_mm: np.ndarray
    temperature_C: np.ndarray
    flow_stress_MPa: np.ndarray  # NaN where unknown
    mu_d: np.ndarray
    mu_d_source: str

    @property
    def pressure_MPa(self):
        """Nominal mean contact pressure of each point, MPa."""
        return nominal_mean_pressure(self.force_N, self.radius_mm)


def _series(table: AdhesionTable, *, mu_d: float | None, flow_stress_MPa: float | None, contact_model: str,
            asperity_radius_um: float | None, bearing_exponent: float, mu_d_source: str | None = None) -> _Series:
    d = table.data
    n = len(d)
    flow = d["flow_stress_MPa"].to_numpy(dtype=float) if "flow_stress_MPa" in d else np.full(n, np.nan)
    if flow_stress_MPa is not None:
        flow = np.where(np.isfinite(flow), flow, flow_stress_MPa)
    s = _Series(test_id=[str(t) for t in d["test_id"]], force_N=table.column("normal_force_N"),
                moment_N_mm=table.column("moment_N_m") * N_MM_PER_N_M, radius_mm=table.column("imprint_radius_mm"),
                temperature_C=table.column("temperature_C"), flow_stress_MPa=flow, mu_d=np.zeros(n), mu_d_source="")
    if mu_d is not None:
        if not (0.0 <= mu_d < 1.0):
            raise IdentificationError(f"--mu-d must be in [0, 1), got {mu_d:g}")
        s.mu_d = np.full(n, float(mu_d))
        s.mu_d_source = mu_d_source or "given (--mu-d)"
        return s
    rp = d["sphere_Rp_um"].to_numpy(dtype=float) if "sphere_Rp_um" in d else np.full(n, np.nan)
    tm = d["sphere_tm"].to_numpy(dtype=float) if "sphere_tm" in d else np.full(n, np.nan)
    if asperity_radius_um is None or not (np.all(np.isfinite(rp)) and np.all(np.isfinite(tm))):
        raise IdentificationError("the deformation component mu_d is needed: give it (--mu-d VALUE), or the sphere's microrelief "
                                  "(sphere.Rp_um and sphere.tm in the table) together with --asperity-radius UM")
    if np.any(tm <= 0) or np.any(tm > 1) or np.any(rp <= 0):
        raise IdentificationError("the microrelief needs R_p > 0 and 0 < t_m <= 1")
    if contact_model == "none":
        ratio = np.ones(n)
    else:
        if not np.all(np.isfinite(flow)):
            raise IdentificationError("mu_d from the microrelief with the bowden_tabor contact model needs the flow stress of every test "
                                      "(flow_stress_MPa column or --flow-stress); or give --mu-d")
        ratio = contact_ratio(contact_model, s.pressure_MPa, flow)
    s.mu_d = deformation_friction_kragelsky(rp, tm, asperity_radius_um, ratio, bearing_exponent)
    s.mu_d_source = MU_D_KRAGELSKY + f"; r_a = {asperity_radius_um:g} um, nu = {bearing_exponent:g}"
    return s


def _split_hot(s: _Series, hot_from_C: float) -> tuple[np.ndarray, list[float]]:
    hot = s.temperature_C >= hot_from_C
    cold = ~hot
    if np.count_nonzero(cold) < 3:
        raise IdentificationError(f"tau0 and beta0 need at least 3 tests below {hot_from_C:g} C (found {np.count_nonzero(cold)})")
    loads = np.unique(np.round(s.pressure_MPa[cold], 6))
    if loads.size < 2:
        raise IdentificationError("tau0 and beta0 need tests at two or more different pressures (all tests below "
                                  f"{hot_from_C:g} C have the mean pressure {loads[0]:.4g} MPa)")
    hot_temps = sorted(set(np.round(s.temperature_C[hot], 1).tolist()))
    return hot, hot_temps


def _hot_plan(s: _Series, hot: np.ndarray, hot_temps: list[float]) -> tuple[dict, str]:
    """Which of k_b, θ_k are fitted, with their start values and bounds."""
    cold_max = float(np.max(s.temperature_C[~hot]))
    if len(hot_temps) >= 2:
        return {"k_b": (True, None), "theta_k": (True, (cold_max, max(hot_temps)))}, \
            f"fitted to {np.count_nonzero(hot)} tests at {', '.join(f'{t:g}' for t in hot_temps)} C (seed 3.2.1 step d)"
    if len(hot_temps) == 1 and hot_temps[0] > SEED_THETA_K_C:
        return {"k_b": (True, None), "theta_k": (False, None)}, \
            (f"k_b fitted to {np.count_nonzero(hot)} tests at {hot_temps[0]:g} C with theta_k fixed at the seed's "
             f"{SEED_THETA_K_C:g} C (one hot temperature cannot give both)")
    return {"k_b": (False, None), "theta_k": (False, None)}, \
        ("seed's first approximation (section 3.2.1): theta_k = 700 C, k_b = beta0/300 -- "
         + ("no tests at or above 600 C" if not hot_temps else f"one hot temperature {hot_temps[0]:g} C is not above 700 C"))


def _add_hot_params(params, plan: dict, beta0_start: float) -> None:
    vary_kb, _ = plan["k_b"]
    vary_th, bounds = plan["theta_k"]
    params.add("k_b", value=beta0_start / SEED_KB_DIVISOR, min=0.0, vary=vary_kb)
    if vary_th:
        lo, hi = bounds
        params.add("theta_k", value=float(np.clip(SEED_THETA_K_C, lo + 1.0, hi - 1.0)), min=lo, max=hi)
    else:
        params.add("theta_k", value=SEED_THETA_K_C, vary=False)


def _minimize(residual, params, plan, temperatures_C):
    """lmfit least squares; with θ_k free, started once inside every interval between the test
    temperatures (the hinge max(0, T − θ_k) has a kink at each) and the best kept."""
    import lmfit

    starts = [params["theta_k"].value]
    if plan["theta_k"][0]:
        lo, hi = plan["theta_k"][1]
        temps = np.unique(np.concatenate([[lo, hi], np.asarray(temperatures_C, dtype=float)]))
        temps = temps[(temps >= lo) & (temps <= hi)]
        starts = [0.5 * (x + y) for x, y in zip(temps[:-1], temps[1:])] or starts
    best = None
    for start in starts:
        trial = params.copy()
        trial["theta_k"].value = start
        with np.errstate(invalid="ignore"):  # a start in the wrong interval may leave a singular covariance
            result = lmfit.minimize(residual, trial, method="least_squares")
        if best is None or (result.success and result.chisqr < best.chisqr):
            best = result
    return best


def _finish_hot(params, plan) -> None:
    """The seed's first approximation k_b = β0/300 when k_b was not fitted."""
    if not plan["k_b"][0]:
        params["k_b"].value = params["beta0"].value / SEED_KB_DIVISOR


def _start_linear(tau, pressure) -> tuple[float, float]:
    slope, intercept = np.polyfit(pressure, tau, 1)
    return float(intercept), float(slope)


def _stderr(params, name):
    se = params[name].stderr
    return None if (se is None or not params[name].vary or not math.isfinite(se)) else float(se)


def _correlations(params, keys: dict[str, str]) -> dict[str, dict[str, float]]:
    return {keys[p]: {keys[q]: float(c) for q, c in (params[p].correl or {}).items() if q in keys}
            for p in keys if params[p].vary and params[p].correl}


def _covered(s: _Series) -> dict[str, list[float]]:
    p = s.pressure_MPa
    return {"nominal_mean_pressure_MPa": [float(p.min()), float(p.max())],
            "temperature_C": [float(s.temperature_C.min()), float(s.temperature_C.max())],
            "imprint_radius_mm": [float(s.radius_mm.min()), float(s.radius_mm.max())],
            "normal_force_N": [float(s.force_N.min()), float(s.force_N.max())]}


PARAM_KEYS = {"tau0": "tau0_MPa", "beta0": "beta0", "k_b": "k_b_per_C", "theta_k": "theta_k_C", "sigma_S": "sigma_S_MPa"}


def fit_simple(table: AdhesionTable, *, mu_d: float | None = None, contact_model: str = "none",
               flow_stress_MPa: float | None = None, hot_from_C: float = HOT_FROM_C, weights: str = "relative",
               asperity_radius_um: float | None = None, bearing_exponent: float = 2.0,
               accuracy: tuple[float, float] | None = None, mu_d_source: str | None = None) -> FrictionFit:
    """# (3.35)–(3.37) with (2.25): τ_adh = K_r·((32/(9π))·τ0 + β(T)·σ_nr) against the tests' τ_n − μ_d·σ̄_n.

    contact_model ``"none"`` is the seed's: σ_nr = σ̄_n = N_z/(π r²). ``"bowden_tabor"`` needs the
    flow stress of each test (table column or ``flow_stress_MPa``). weights: ``"relative"``
    (residuals divided by the measured τ_adh, for errors proportional to the reading) or
    ``"absolute"`` (the plain sum of squares of the seed). accuracy: (relative scatter of M_z,
    scatter of r in µm) of the instrument — each residual is then divided by its effective
    standard deviation (:func:`_weighted_fit`) instead. mu_d_source: how a given ``mu_d`` is
    described (default "given (--mu-d)"; a demo's default says so).
    """
    import lmfit

    s = _series(table, mu_d=mu_d, flow_stress_MPa=flow_stress_MPa, contact_model=contact_model,
                asperity_radius_um=asperity_radius_um, bearing_exponent=bearing_exponent, mu_d_source=mu_d_source)
    if contact_model != "none" and not np.all(np.isfinite(s.flow_stress_MPa)):
        raise IdentificationError(f"the {contact_model} contact model needs the flow stress of every test (flow_stress_MPa column or --flow-stress)")
    hot, hot_temps = _split_hot(s, hot_from_C)

    def quantities(radius):
        p = nominal_mean_pressure(s.force_N, radius)
        tau_n = mean_shear_stress(s.moment_N_mm, radius)  # (3.35)
        kr = contact_ratio(contact_model, p, s.flow_stress_MPa)
        return p, tau_n, tau_n - s.mu_d * p, kr, p / kr  # (3.36) deformation part removed; (3.42) on the mean pressure

    p, tau_n, tau_adh, kr, sigma_nr = quantities(s.radius_mm)
    spread = np.ptp(sigma_nr[~hot]) / np.mean(sigma_nr[~hot])
    if spread < 1e-3:
        raise IdentificationError(f"the real pressure is the same in every test below {hot_from_C:g} C ({np.mean(sigma_nr[~hot]):.4g} MPa): "
                                  f"with the {contact_model} contact model the mean pressure of a plastic imprint never exceeds the "
                                  "flow pressure, so beta0 cannot be separated from tau0; use --method refined, or the contact model 'none'")
    intercept0, slope0 = _start_linear(tau_adh[~hot], sigma_nr[~hot])
    params = lmfit.Parameters()
    params.add("tau0", value=max(intercept0 / UNIFORM_SHEAR_WEIGHT, 1e-3))
    params.add("beta0", value=slope0)
    plan, hot_source, use = _hot_terms(params, s, hot, hot_temps, slope0)

    def deviation(v, radius):
        """model − measured τ_adh (MPa) with the imprint radii ``radius``."""
        _, _, measured, ratio, real = quantities(radius)
        return ratio * (UNIFORM_SHEAR_WEIGHT * v["tau0"] + beta_at(s.temperature_C, v["beta0"], v["k_b"], v["theta_k"]) * real) - measured

    def model(v):
        return deviation(v, s.radius_mm) + tau_adh

    result = _weighted_fit(deviation, params, plan, s, use, measured=tau_adh, moment_part=tau_n, weights=weights, accuracy=accuracy)
    _finish_hot(result.params, plan)
    v = result.params.valuesdict()
    predicted = model(v)
    tests = _test_rows(s, p, sigma_nr, use, measured=tau_adh, predicted=predicted, name="tau_adh_MPa",
                       extra={"tau_n_MPa": tau_n, "contact_ratio": kr})
    fit = _make_fit("simple", result, s, plan, hot_source, contact_model, tests, sigma_S=None)
    fit.extra["tau0_intercept_MPa"] = float(UNIFORM_SHEAR_WEIGHT * v["tau0"])
    fit.extra["tau0_intercept_note"] = ("intercept of (3.37) on the 0.540 mean stress (3.35); tau0_MPa = intercept*9*pi/32 "
                                        "because (3.35) reads a uniform shear as 32/(9 pi) = 1.132 times itself")
    _note_weights_and_hot(fit, weights, accuracy, hot, plan, hot_from_C, hot_source)
    return fit


def fit_refined(table: AdhesionTable, *, mu_d: float | None = None, contact_model: str = "bowden_tabor",
                flow_stress_MPa: float | None = None, hot_from_C: float = HOT_FROM_C, weights: str = "relative",
                asperity_radius_um: float | None = None, bearing_exponent: float = 2.0,
                sigma_S_start_MPa: float | None = None, accuracy: tuple[float, float] | None = None,
                mu_d_source: str | None = None) -> FrictionFit:
    """# (3.38)–(3.44): τ0, β0, σ_S (and k_b, θ_k) by least squares of every test's moment.

    Tests whose flow stress is known (``flow_stress_MPa`` column, or ``flow_stress_MPa``) use it;
    the others share one fitted σ_S (seed 3.2.3: hardening assumed equal in all tests).
    weights: ``"relative"`` ((M_model − M_z)/M_z) or ``"absolute"`` (the plain sum (3.38), N·mm);
    accuracy as in :func:`fit_simple`.
    """
    import lmfit

    if contact_model not in CONTACT_RATIO_MODELS:
        raise IdentificationError(f"unknown contact-area model {contact_model!r} (use: {', '.join(CONTACT_RATIO_MODELS)})")
    s = _series(table, mu_d=mu_d, flow_stress_MPa=flow_stress_MPa, contact_model=contact_model,
                asperity_radius_um=asperity_radius_um, bearing_exponent=bearing_exponent, mu_d_source=mu_d_source)
    hot, hot_temps = _split_hot(s, hot_from_C)
    p = s.pressure_MPa
    known = np.isfinite(s.flow_stress_MPa)
    shared = contact_model != "none" and not known.all()
    if shared and np.count_nonzero(~known & ~hot) < 4:
        raise IdentificationError("the refined fit needs at least 4 tests below "
                                  f"{hot_from_C:g} C without a known flow stress to estimate sigma_S (or give flow_stress_MPa)")
    tau_n = mean_shear_stress(s.moment_N_mm, s.radius_mm)
    intercept0, slope0 = _start_linear((tau_n - s.mu_d * p)[~hot], p[~hot])
    params = lmfit.Parameters()
    params.add("tau0", value=max(intercept0 / UNIFORM_SHEAR_WEIGHT, 1e-3), min=0.0)
    params.add("beta0", value=slope0)
    start_S = sigma_S_start_MPa or float(np.median(p[~hot]) / 2.0)  # mean pressure of a plastic imprint ≈ 2–3 σ_S
    params.add("sigma_S", value=start_S, min=1e-3 * start_S, vary=shared)
    plan, hot_source, use = _hot_terms(params, s, hot, hot_temps, slope0)
    hot_shared = hot & ~known & use

    def deviation(v, radius):
        """model − measured M_z (N·mm) with the imprint radii ``radius``."""
        flow = np.where(known, s.flow_stress_MPa, v["sigma_S"])
        return refined_moment(s.force_N, radius, s.temperature_C, v["tau0"], v["beta0"], v["k_b"], v["theta_k"],
                              flow, s.mu_d, model=contact_model) - s.moment_N_mm

    def model(v):
        return deviation(v, s.radius_mm) + s.moment_N_mm

    result = _weighted_fit(deviation, params, plan, s, use, measured=s.moment_N_mm, moment_part=s.moment_N_mm,
                           weights=weights, accuracy=accuracy)
    if not result.success:
        raise IdentificationError(f"the refined adhesion fit did not converge: {result.message}")
    _finish_hot(result.params, plan)
    v = result.params.valuesdict()
    flow = np.where(known, s.flow_stress_MPa, v["sigma_S"])
    kr = contact_ratio(contact_model, p, flow)
    tests = _test_rows(s, p, p / kr, use, measured=s.moment_N_mm / N_MM_PER_N_M, predicted=model(v) / N_MM_PER_N_M,
                       name="moment_N_m", extra={"tau_n_MPa": tau_n, "flow_stress_MPa": flow})
    fit = _make_fit("refined", result, s, plan, hot_source, contact_model, tests, sigma_S=shared)
    if hot_shared.any() and contact_model != "none":
        fit.warnings.append(f"{np.count_nonzero(hot_shared)} hot test(s) without a known flow stress share the fitted sigma_S "
                            "of the cold tests; give flow_stress_MPa for tests at temperature")
    _note_weights_and_hot(fit, weights, accuracy, hot, plan, hot_from_C, hot_source)
    return fit


def _hot_terms(params, s: _Series, hot, hot_temps, slope0: float):
    """The hot tests' plan and its parameters (k_b, θ_k) added: (plan, how the hot tests are
    treated, which tests the fit uses — the hot ones only when β(T) is fitted)."""
    plan, hot_source = _hot_plan(s, hot, hot_temps)
    _add_hot_params(params, plan, slope0)
    use = np.ones(len(s.force_N), bool) if plan["k_b"][0] else ~hot
    return plan, hot_source, use


def _note_weights_and_hot(fit: FrictionFit, weights: str, accuracy, hot, plan, hot_from_C: float, hot_source: str) -> None:
    """The weighting said in the fit's extra; the hot tests left out said in its warnings."""
    fit.extra["weights"] = _weights_text(weights, accuracy)
    if hot.any() and not plan["k_b"][0]:
        fit.warnings.append(f"{np.count_nonzero(hot)} test(s) at or above {hot_from_C:g} C not used: {hot_source}")


def _weighted_fit(deviation, params, plan, s: _Series, use, *, measured, moment_part, weights: str, accuracy):
    """Least squares of ``deviation(v, radius)`` (model − measured) over the tests in ``use``.

    Without ``accuracy`` each deviation is divided by the measured value (``weights="relative"``)
    or not at all (``"absolute"``). With ``accuracy = (s_M, δr_um)`` it is divided by its
    effective standard deviation √((s_M·m_i)² + (∂d_i/∂r_i·δr)²) — the effective-variance method
    (J. Orear, Am. J. Phys. 50 (1982) 912) for the error of the measured imprint radius, which
    enters both sides — evaluated at a first fit and refitted once; ``moment_part`` m_i is the
    part of the measured value proportional to M_z.
    """
    def fit_with(scale):
        """The fit with residuals divided by ``scale``."""
        return _minimize(lambda pars: (deviation(pars.valuesdict(), s.radius_mm) / scale)[use], params, plan, s.temperature_C[use])

    result = fit_with(_weights(measured, weights))
    if accuracy is None:
        return result
    moment_rel, radius_um = accuracy
    if moment_rel < 0 or radius_um < 0 or moment_rel + radius_um == 0:
        raise IdentificationError(f"the instrument accuracy must be >= 0 and not both 0, got moment {moment_rel:g}, radius {radius_um:g} um")
    v = result.params.valuesdict()
    step = 1e-6 * s.radius_mm  # each test's deviation depends on its own radius only: one vectorized difference
    slope = (deviation(v, s.radius_mm + step) - deviation(v, s.radius_mm - step)) / (2.0 * step)
    scale = np.sqrt((moment_rel * np.asarray(moment_part)) ** 2 + (slope * radius_um * 1e-3) ** 2)
    for name in params:
        params[name].value = result.params[name].value
    return fit_with(scale)


def _weights_text(weights: str, accuracy) -> str:
    if accuracy is None:
        return weights
    return (f"effective variance (Orear 1982): moment scatter {100 * accuracy[0]:g} %, imprint radius scatter {accuracy[1]:g} um")


def _weights(measured, weights: str):
    if weights == "relative":
        if np.any(np.asarray(measured) <= 0):
            raise IdentificationError("relative weights need every measured value > 0; use weights 'absolute'")
        return np.asarray(measured, dtype=float)
    if weights == "absolute":
        return np.ones_like(np.asarray(measured, dtype=float))
    raise IdentificationError(f"weights must be 'relative' or 'absolute', not {weights!r}")


def _test_rows(s: _Series, pressure, sigma_nr, used, *, measured, predicted, name: str, extra: dict) -> list[dict]:
    rows = []
    for i, test_id in enumerate(s.test_id):
        row = {"test_id": test_id, "normal_force_N": float(s.force_N[i]), "moment_N_m": float(s.moment_N_mm[i] / N_MM_PER_N_M),
               "imprint_radius_mm": float(s.radius_mm[i]), "temperature_C": float(s.temperature_C[i]),
               "nominal_mean_pressure_MPa": float(pressure[i]), "real_pressure_MPa": float(sigma_nr[i]),
               "mu_d": float(s.mu_d[i]), "used": bool(used[i]),
               name: float(measured[i]), f"model_{name}": float(predicted[i]),
               "residual_pct": float(100.0 * (predicted[i] - measured[i]) / measured[i]) if measured[i] else None}
        for key, values in extra.items():
            row[key] = float(values[i])
        rows.append(row)
    return rows


UNDETERMINED_WHY = {"sigma_S_MPa": " (the tested moments hardly depend on it: the real contact is nearly full over the tested "
                                   "pressures; give flow_stress_MPa, or test where the contact is partial); not used in cards"}


def undetermined_values(values: dict, stderr: dict) -> list[str]:
    """The fitted values smaller than their own standard error, |v| < se: not determined by the tests."""
    return [key for key, v in values.items() if v is not None and stderr.get(key) is not None and abs(v) < stderr[key]]


def _make_fit(method: str, result, s: _Series, plan, hot_source: str, contact_model: str, tests, *, sigma_S) -> FrictionFit:
    import lmfit

    pars = result.params
    mu = s.mu_d
    values = {"tau0_MPa": float(pars["tau0"].value), "beta0": float(pars["beta0"].value),
              "k_b_per_C": float(pars["k_b"].value), "theta_k_C": float(pars["theta_k"].value),
              "sigma_S_MPa": float(pars["sigma_S"].value) if sigma_S else None,
              "mu_d": float(np.mean(mu))}
    stderr = {"tau0_MPa": _stderr(pars, "tau0"), "beta0": _stderr(pars, "beta0"), "k_b_per_C": _stderr(pars, "k_b"),
              "theta_k_C": _stderr(pars, "theta_k"), "sigma_S_MPa": _stderr(pars, "sigma_S") if sigma_S else None,
              "mu_d": None}
    keys = {k: v for k, v in PARAM_KEYS.items() if k in pars}
    sources = {"hot_constants": hot_source, "mu_d": s.mu_d_source + ("" if np.ptp(mu) == 0 else " (mean over the tests; per test in 'tests')")}
    if method == "refined":
        sources["sigma_S_MPa"] = ("fitted (3.38), one value shared by the tests without a known flow stress" if sigma_S else
                                  ("not used (contact model 'none')" if contact_model == "none" else "given per test (flow_stress_MPa)"))
    covered = _covered(s)
    used = np.array([t["used"] for t in tests])
    covered["temperature_C"] = [float(s.temperature_C[used].min()), float(s.temperature_C[used].max())]
    fit = FrictionFit(method=method, values=values, stderr=stderr, correlations=_correlations(pars, keys), sources=sources,
                      tests=tests, contact_model=contact_model, covered=covered, report=lmfit.fit_report(result))
    fit.extra["undetermined"] = undetermined_values(values, stderr)
    for key in fit.extra["undetermined"]:
        sources[key] = "UNDETERMINED (smaller than its own standard error); " + sources.get(key, "fitted")
        fit.warnings.append(f"{key} = {values[key]:.4g} ± {stderr[key]:.2g} is smaller than its own uncertainty: "
                            f"these tests do not determine it{UNDETERMINED_WHY.get(key, '')}")
    fit.extra["tests_used"] = int(used.sum())
    fit.extra["rms_residual_pct"] = float(np.sqrt(np.mean([t["residual_pct"] ** 2 for t in tests if t["used"]])))
    return fit


def fit_friction(table: AdhesionTable, method: str = "simple", **options) -> FrictionFit:
    """The chosen identification (``"simple"`` or ``"refined"``)."""
    if method == "simple":
        return fit_simple(table, **options)
    if method == "refined":
        return fit_refined(table, **options)
    raise IdentificationError(f"method must be 'simple' or 'refined', not {method!r}")

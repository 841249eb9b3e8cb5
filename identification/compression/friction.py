"""Friction at the platens of a compression (upsetting) test, and the flow-curve corrections.

Pure functions on post-test measurements and on (mean pressure, strain) arrays; equation
numbers refer to the seed (the thesis named in docs/methods.md), section 3.1.3 (§4 there). All lengths in mm, stresses
in MPa, strains are logarithmic (true) strains.

Friction from the barrelled specimen (each returns a :class:`FrictionResult`):

* ``fe_table`` (default): the bulge ΔR/h of CalculiX upsetting runs over μ, h0/d0, strain and
  hardening (:mod:`identification.fe.model.table`, package data) inverted for the Coulomb μ; the
  hardening exponent is read from the record's own curve when it is given.
* ``bulge_regression``: the seed's FE regression (3.18) inverted for the mean
  Coulomb coefficient μ (3.19).
* ``ebrahimi_najafizadeh``: the barrelling method of Ebrahimi & Najafizadeh (2004) for the
  Tresca friction factor m; converted to μ by equating the Tresca shear stress m·σ_f/√3 with
  the Coulomb shear stress μ·p at p ≈ σ_f, i.e. μ = m/√3 (the small-μ equivalence; it is also
  exactly the μ for which the Siebel mean pressures of the two friction laws agree). The μ for
  which the exact Coulomb slab pressure equals the Tresca slab pressure at the final geometry
  is reported alongside as ``mu_equal_slab_pressure``.

Corrections turning the mean pressure p = P/S (S from volume constancy) and the strain into
flow stress and strain (:data:`CORRECTIONS`): ``fe_table`` (default: the CalculiX force factor
F/(σ_f·A) of the same table), ``k_sigma`` (the seed's K_σ/K_ε regressions
(3.21)–(3.27)), ``siebel`` (p/σ_f = 1 + 2μr/(3h)) and ``slab`` (the exact Coulomb
slab solution p/σ_f = 2(e^c − c − 1)/c², c = 2μr/h).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.model import model_form as mf

FRICTION_METHODS = ("fe_table", "bulge_regression", "ebrahimi_najafizadeh")
DEFAULT_FRICTION_METHOD = "fe_table"

# (3.18) regression constants: ΔR/h = C·ε^P·(1 − exp(−K·μ^Q))
BULGE_C = 0.0683
BULGE_P = 0.83
BULGE_K = 26.7
BULGE_Q = 1.53

# A measured diameter less than half this reading resolution (mm) below the volume-constant
# diameter d_n is read as "no bulge" (μ = 0) rather than as a negative bulge; on the radius
# that is a quarter of it.
DIAMETER_RESOLUTION_MM = 0.01
# The model form of the methods that read μ from the barrel alone (they know neither the hardening nor,
# (3.19), h0/d0): the rms of (μ_method − μ)/μ on the CalculiX table's barrels, μ 0.05–0.2 × h0/d0 0.6–2.5
# × n 0.05–0.65 × ε 0.3–0.7 (bench/friction_model_form.py; docs/methods.md §4.8).
MU_MODEL_FORM = {"bulge_regression": 0.41, "ebrahimi_najafizadeh": 0.44}
DFACE_ADVICE = ("measure the original end face's diameter (post.dface_mm) and identify again: μ is poorly told by the bulge "
                "(the faces nearly stick), and the end face still shrinks with μ there")  # result.json's dface_advice


@dataclass(frozen=True)
class FrictionResult:
    """The friction identified by one method: μ, the inputs it used, extra figures (e.g. m)."""

    method: str
    mu: float
    inputs: dict[str, float] = field(default_factory=dict)
    extra: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict:
        """The result as result.json's friction block."""
        return {"method": self.method, "mu": self.mu, "inputs": dict(self.inputs), **self.extra}


# -- geometry -------------------------------------------------------------------------------


def nominal_diameter(d0_mm, h0_mm, h_mm):
    """Diameter of the friction-free cylinder of height h (volume constancy)."""
    # (3.17)/(3.28) d_n = d0·√(h0/h)
    return d0_mm * np.sqrt(h0_mm / np.asarray(h_mm, dtype=float))


def bulge_excess(d_max_mm, d_n_mm):
    """Radial excess of the bulge over the friction-free cylinder."""
    # (3.29) ΔR = (d_φ − d_n)/2
    return (d_max_mm - d_n_mm) / 2.0


def height_strain(h_mm, h0_mm):
    """Logarithmic compressive strain (positive for shortening)."""
    # (3.31) ε_p = −ln(h/h0)
    return -np.log(np.asarray(h_mm, dtype=float) / h0_mm)


def diameter_from_area(area_mm2):
    """Diameter of the circle of area S (largest cross-section S_max → d_φ)."""
    # d_φ = √(4·S_max/π)
    return np.sqrt(4.0 * np.asarray(area_mm2, dtype=float) / math.pi)


# -- bulge regression (3.18)/(3.19) ---------------------------------------------------------


def bulge_ratio(eps_p, mu):
    """ΔR/h predicted by the seed's FE regression for strain ε_p and friction μ."""
    # (3.18) ΔR/h = 0.0683·ε_p^0.83·(1 − exp(−26.7·μ^1.53))
    eps_p = np.asarray(eps_p, dtype=float)
    mu = np.asarray(mu, dtype=float)
    return BULGE_C * eps_p**BULGE_P * (1.0 - np.exp(-BULGE_K * mu**BULGE_Q))


def mu_from_bulge_ratio(delta_r_over_h: float, eps_p: float) -> float:
    """Mean Coulomb friction μ from the bulge ratio ΔR/h at strain ε_p (inverse of (3.18)).

    Raises IdentificationError outside the regression's range: ε_p ≤ 0, a negative bulge, or a
    bulge the regression cannot produce at any μ (logarithm argument ≤ 0).
    """
    if not (math.isfinite(delta_r_over_h) and math.isfinite(eps_p)):
        raise IdentificationError(f"bulge regression (3.19): inputs must be finite (ΔR/h = {delta_r_over_h}, ε_p = {eps_p})")
    if eps_p <= 0:
        raise IdentificationError(f"bulge regression (3.19): the strain ε_p = {eps_p:.4g} must be > 0 (the final height must be below the initial height)")
    if delta_r_over_h < 0:
        raise IdentificationError(f"bulge regression (3.19): negative bulge ΔR/h = {delta_r_over_h:.4g} (the measured maximum diameter is smaller than the volume-constant diameter d_n; check d0, h0, hk and dmax)")
    saturation = BULGE_C * eps_p**BULGE_P
    arg = 1.0 - delta_r_over_h / saturation
    if arg <= 0:
        raise IdentificationError(
            f"bulge regression (3.19): ΔR/h = {delta_r_over_h:.4g} is beyond what (3.18) gives at any friction "
            f"for ε_p = {eps_p:.4g} (at most {saturation:.4g}); logarithm argument {arg:.4g} ≤ 0"
        )
    # (3.19) μ = [ln(1 − (ΔR/h)·ε_p^−0.83/0.0683)/(−26.7)]^(1/1.53)
    return float((math.log(arg) / -BULGE_K) ** (1.0 / BULGE_Q))


def _measured_max_diameter(d_max_mm: float | None, s_max_mm2: float | None) -> tuple[float, dict[str, float]]:
    if d_max_mm is not None:
        return float(d_max_mm), {"dmax_mm": float(d_max_mm)}
    if s_max_mm2 is not None:
        if s_max_mm2 <= 0:
            raise IdentificationError(f"the largest cross-section area S_max = {s_max_mm2:g} mm² must be > 0")
        return float(diameter_from_area(s_max_mm2)), {"smax_mm2": float(s_max_mm2)}
    raise IdentificationError("friction needs the bulge: give the maximum diameter 'post.dmax_mm' or the largest cross-section area 'post.smax_mm2'")


def _check_geometry(d0_mm: float, h0_mm: float, hk_mm: float) -> None:
    for name, v in (("d0", d0_mm), ("h0", h0_mm), ("hk", hk_mm)):
        if not (math.isfinite(v) and v > 0):
            raise IdentificationError(f"friction: {name} = {v} mm must be a positive number")
    if hk_mm >= h0_mm:
        raise IdentificationError(f"friction: the final height hk = {hk_mm:g} mm must be below the initial height h0 = {h0_mm:g} mm")


def friction_bulge_regression(d0_mm: float, h0_mm: float, hk_mm: float, *, d_max_mm: float | None = None, s_max_mm2: float | None = None) -> FrictionResult:
    """Mean friction μ from the post-test shape by the seed's regression ((3.28), (3.29), (3.31), (3.19)).

    Give the measured maximum (bulge) diameter ``d_max_mm`` or the largest cross-section area
    ``s_max_mm2`` (the diameter takes precedence when both are given). ``mu_stderr``: the
    readings' resolution through (3.19) (:func:`resolution_stderr`).
    """
    _check_geometry(d0_mm, h0_mm, hk_mm)
    d_max, used = _measured_max_diameter(d_max_mm, s_max_mm2)
    mu, extra = _bulge_regression(d0_mm, h0_mm, hk_mm, d_max)
    inputs = {"d0_mm": d0_mm, "h0_mm": h0_mm, "hk_mm": hk_mm, **used}
    readings = {"d0_mm": d0_mm, "h0_mm": h0_mm, "hk_mm": hk_mm, "d_max_mm": d_max}
    extra.update(_mu_stderr("bulge_regression", mu, lambda **x: _bulge_regression(**x)[0], readings))
    return FrictionResult("bulge_regression", mu, inputs, extra)


def _bulge_regression(d0_mm: float, h0_mm: float, hk_mm: float, d_max_mm: float) -> tuple[float, dict]:
    """(μ, figures) of (3.19) from the four readings."""
    d_n = float(nominal_diameter(d0_mm, h0_mm, hk_mm))
    delta_r = float(bulge_excess(d_max_mm, d_n))
    if -DIAMETER_RESOLUTION_MM / 4 <= delta_r < 0:
        delta_r = 0.0  # within the reading resolution of d_max: no bulge, μ = 0
    eps_p = float(height_strain(hk_mm, h0_mm))
    mu = mu_from_bulge_ratio(delta_r / hk_mm, eps_p)
    return mu, {"d_max_mm": d_max_mm, "d_n_mm": d_n, "delta_R_mm": delta_r, "eps_p": eps_p}


def resolution_stderr(mu_of: Callable[..., float], readings: dict[str, float], resolution_mm: float = DIAMETER_RESOLUTION_MM) -> float:
    """μ's standard error from its readings (mm), each off by ± ``resolution_mm``: the method's own
    formula ``mu_of(**readings)`` at each reading ± its resolution, the half-differences in quadrature.
    A side the formula cannot read (e.g. no bulge left) is replaced by the centre (a one-sided difference)."""
    # σ_μ = √Σ_i ((μ(x_i + δ) − μ(x_i − δ))/2)²
    centre = mu_of(**readings)
    halves = []
    for name, value in readings.items():
        sides = []
        for sign in (1.0, -1.0):
            try:
                sides.append(mu_of(**{**readings, name: value + sign * resolution_mm}))
            except IdentificationError:
                pass
        halves.append((max(sides) - min(sides)) / 2.0 if len(sides) == 2 else (abs(sides[0] - centre) if sides else 0.0))
    return mf.quadrature(*halves)


def _mu_stderr(method: str, mu: float, mu_of: Callable[..., float], readings: dict[str, float]) -> dict:
    """μ's standard error of a method that reads the barrel alone: the readings' resolution
    (:func:`resolution_stderr`) and the method's model form (:data:`MU_MODEL_FORM` of μ), in quadrature."""
    by_resolution, by_model = resolution_stderr(mu_of, readings), MU_MODEL_FORM[method] * mu
    se = mf.quadrature(by_resolution, by_model)
    basis = (f"the method's formula at {', '.join(readings)} each ± {DIAMETER_RESOLUTION_MM} mm (their resolution) and its "
             f"model form, {MU_MODEL_FORM[method]:.0%} of mu (rms against the CalculiX upsetting table), in quadrature")
    return {"mu_stderr": se, "mu_stderr_resolution": by_resolution, "mu_stderr_model_form": by_model, "mu_stderr_basis": basis,
            "mu_range": [max(mu - se, 0.0), mu + se], "mu_range_basis": f"mu ± its standard error: {', '.join(readings)} ± {DIAMETER_RESOLUTION_MM} mm and the model form's {MU_MODEL_FORM[method]:.0%} of mu"}


# -- Ebrahimi–Najafizadeh (2004) ------------------------------------------------------------


def barrel_top_radius(r0_mm, h0_mm, h_mm, r_max_mm):
    """Top-face radius of a barrelled cylinder from volume constancy, parabolic-barrel volume.

    The barrel volume π·h·(2R_M² + R_T²)/3 (a parabolic profile to first order in R_M − R_T)
    equals π·R0²·h0, so R_T = √(3·R0²·h0/h − 2·R_M²).
    """
    # R_T = √(3·R0²·h0/h − 2·R_M²)
    return np.sqrt(3.0 * r0_mm**2 * h0_mm / h_mm - 2.0 * np.asarray(r_max_mm, dtype=float) ** 2)


def barrelling_parameter(r_max_mm, r_top_mm, r_mean_mm, h_mm, dh_mm):
    """Barrelling parameter b of Ebrahimi & Najafizadeh."""
    # b = 4·(ΔR/R)·(h/Δh), ΔR = R_M − R_T
    return 4.0 * (r_max_mm - r_top_mm) / r_mean_mm * (h_mm / dh_mm)


def friction_factor_from_barrelling(b, r_mean_mm, h_mm):
    """Tresca friction factor m from the barrelling parameter b."""
    # m = (R/h)·b / (4/√3 − 2b/(3√3))
    return (r_mean_mm / h_mm) * b / (4.0 / math.sqrt(3.0) - 2.0 * b / (3.0 * math.sqrt(3.0)))


def mu_from_friction_factor(m):
    """Coulomb μ equivalent to the Tresca factor m: m·σ_f/√3 = μ·p at p ≈ σ_f."""
    # μ = m/√3 (equal Siebel mean pressures: 1 + 2μr/(3h) = 1 + 2mr/(3√3·h))
    return np.asarray(m, dtype=float) / math.sqrt(3.0)


def mu_equal_slab_pressure(m: float, r_over_h: float) -> float:
    """Coulomb μ whose exact slab mean pressure equals the Tresca slab pressure for factor m.

    Solves 2(e^c − c − 1)/c² = 1 + 2m·r/(3√3·h) with c = 2μr/h.
    """
    target = 1.0 + 2.0 * m * r_over_h / (3.0 * math.sqrt(3.0))
    if m <= 0:
        return 0.0
    f = lambda mu: float(slab_factor(mu, r_over_h, 1.0)) - target  # noqa: E731
    hi = 1.0
    while f(hi) < 0:
        hi *= 2.0
    from scipy.optimize import brentq  # here, so `flowcurve --help` stays fast

    return float(brentq(f, 0.0, hi, xtol=1e-12))


def friction_ebrahimi_najafizadeh(d0_mm: float, h0_mm: float, hk_mm: float, *, d_max_mm: float | None = None, s_max_mm2: float | None = None, d_top_mm: float | None = None) -> FrictionResult:
    """Friction factor m (and μ = m/√3) by the barrelling method of Ebrahimi & Najafizadeh (2004).

    The top-face diameter ``d_top_mm`` is used when measured; otherwise it follows from volume
    constancy with a parabolic barrel (:func:`barrel_top_radius`). ``mu_stderr``: the readings'
    resolution through the method (:func:`resolution_stderr`).
    """
    _check_geometry(d0_mm, h0_mm, hk_mm)
    d_max, used = _measured_max_diameter(d_max_mm, s_max_mm2)
    if d_top_mm is not None:
        used["dtop_mm"] = float(d_top_mm)
    mu, extra = _ebrahimi_najafizadeh(d0_mm, h0_mm, hk_mm, d_max, d_top_mm)
    inputs = {"d0_mm": d0_mm, "h0_mm": h0_mm, "hk_mm": hk_mm, **used}
    readings = {"d0_mm": d0_mm, "h0_mm": h0_mm, "hk_mm": hk_mm, "d_max_mm": d_max, **({"d_top_mm": float(d_top_mm)} if d_top_mm is not None else {})}
    mu_of = lambda **x: _ebrahimi_najafizadeh(**{"d_top_mm": None, **x})[0]  # noqa: E731
    extra.update(_mu_stderr("ebrahimi_najafizadeh", mu, mu_of, readings))
    return FrictionResult("ebrahimi_najafizadeh", mu, inputs, extra)


def _ebrahimi_najafizadeh(d0_mm: float, h0_mm: float, hk_mm: float, d_max_mm: float, d_top_mm: float | None) -> tuple[float, dict]:
    """(μ, figures) of Ebrahimi & Najafizadeh from the readings (``d_top_mm`` None: the parabolic barrel's)."""
    d_max = d_max_mm
    r0, r_max = d0_mm / 2.0, d_max / 2.0
    r_mean = float(nominal_diameter(d0_mm, h0_mm, hk_mm)) / 2.0
    if r_mean - DIAMETER_RESOLUTION_MM / 4 <= r_max < r_mean:
        r_max = r_mean  # within the reading resolution of d_max: no bulge
    if r_max < r_mean:
        raise IdentificationError(f"Ebrahimi-Najafizadeh: negative bulge (maximum radius {r_max:.4g} mm below the volume-constant radius {r_mean:.4g} mm)")
    if d_top_mm is not None:
        r_top = d_top_mm / 2.0
    else:
        radicand = 3.0 * r0**2 * h0_mm / hk_mm - 2.0 * r_max**2
        if radicand <= 0:
            raise IdentificationError(f"Ebrahimi-Najafizadeh: a maximum diameter of {d_max:.4g} mm is too large for a barrel of this volume (no top-face radius satisfies volume constancy)")
        r_top = float(barrel_top_radius(r0, h0_mm, hk_mm, r_max))
    if r_top > r_max:
        raise IdentificationError(f"Ebrahimi-Najafizadeh: the top-face radius {r_top:.4g} mm exceeds the maximum radius {r_max:.4g} mm")
    dh = h0_mm - hk_mm
    b = float(barrelling_parameter(r_max, r_top, r_mean, hk_mm, dh))
    m = float(friction_factor_from_barrelling(b, r_mean, hk_mm))
    if not (0.0 <= m <= 1.0):
        raise IdentificationError(f"Ebrahimi-Najafizadeh: friction factor m = {m:.4g} is outside [0, 1] (barrelling parameter b = {b:.4g}); the bulge is not a friction barrel")
    mu = float(mu_from_friction_factor(m))
    return mu, {"m": m, "b": b, "R_mean_mm": r_mean, "R_max_mm": r_max, "R_top_mm": r_top, "mu_equal_slab_pressure": mu_equal_slab_pressure(m, r_mean / hk_mm)}


def identify_friction(method: str, d0_mm: float, h0_mm: float, hk_mm: float, *, d_max_mm: float | None = None, s_max_mm2: float | None = None, d_top_mm: float | None = None, curve=None,
                      d_face_mm: float | None = None) -> FrictionResult:
    """Friction by the named method (one of :data:`FRICTION_METHODS`); ``curve`` = (strain,
    mean pressure MPa[, plastic strain]) of the record, used by ``fe_table`` for the hardening;
    ``d_face_mm`` (the original end face) is read by ``fe_table`` in place of the bulge."""
    if method == "fe_table":
        return friction_fe_table(d0_mm, h0_mm, hk_mm, d_max_mm=d_max_mm, s_max_mm2=s_max_mm2, curve=curve, d_face_mm=d_face_mm)
    if method == "bulge_regression":
        return friction_bulge_regression(d0_mm, h0_mm, hk_mm, d_max_mm=d_max_mm, s_max_mm2=s_max_mm2)
    if method == "ebrahimi_najafizadeh":
        return friction_ebrahimi_najafizadeh(d0_mm, h0_mm, hk_mm, d_max_mm=d_max_mm, s_max_mm2=s_max_mm2, d_top_mm=d_top_mm)
    raise IdentificationError(f"unknown friction method {method!r} (choose from {', '.join(FRICTION_METHODS)})")


# -- CalculiX table (identification/fe) ----------------------------------------------------

FE_DEFAULT_HARDENING = (0.3, 0.002)  # Swift (n, ε0) used when the record's curve is not given
FE_HARDENING_ITERATIONS = 3


FE_FIT_FROM_TOTAL_STRAIN = 0.02  # without the plastic strain, the Swift fit starts where the elastic part is small


def _fit_start(plastic: bool) -> float:
    from flowcurve.identification.fe.model.table import SWIFT_FIT_FROM

    return SWIFT_FIT_FROM if plastic else FE_FIT_FROM_TOTAL_STRAIN


def _swift_of(eps_p, sigma, plastic: bool) -> tuple[float, float]:
    from flowcurve.identification.fe.model.table import swift_hardening

    return swift_hardening(eps_p, sigma, start=_fit_start(plastic))


def _fe_flow_stress(table, strain, pressure_MPa, mu: float, h0_d0: float, eps_p=None):
    """σ_f = p / factor(μ, h0/d0, n, ε0, ε) with the Swift (n, ε0) read from the corrected curve
    σ_f(ε_p) itself (fixed point) → (σ_f, (n, ε0)); below the table's first strain the factor is
    read on ε_p (the table's start). Without ``eps_p`` the total strain stands in, from ε = 0.02 on.
    Each point's factor is read at the curve's Swift exponent near its strain
    (:func:`~flowcurve.identification.fe.model.table.local_swift_exponent`, the whole curve's ε0): the
    factor follows the hardening at the strain, which for a saturating law falls well below the
    whole curve's n. The returned (n, ε0) is the whole curve's."""
    from flowcurve.identification.fe.model.table import local_swift_exponent

    strain = np.asarray(strain, dtype=float)
    pressure = np.asarray(pressure_MPa, dtype=float)
    plastic = eps_p is not None
    eps_fit = np.asarray(eps_p, dtype=float) if plastic else strain
    lookup = np.clip(strain, 0.0, table.strain[-1])  # beyond the table: its last strain's factor
    sigma = pressure
    hardening = FE_DEFAULT_HARDENING
    for _ in range(FE_HARDENING_ITERATIONS):
        hardening = _swift_of(eps_fit, sigma, plastic)
        n = local_swift_exponent(eps_fit, sigma, hardening[1], eps_fit, start=_fit_start(plastic), fallback=hardening[0])
        sigma = pressure / table.force_factor_at(mu, h0_d0, n, lookup, eps0=hardening[1], eps_p=eps_p)
    return sigma, hardening


def _fe_mu_lowering_n(table, dR_over_h: float, h0_d0: float, hardening: tuple[float, float], eps: float) -> tuple[float, tuple[float, float], bool]:
    """(μ, (n, ε0), clamped) from the table's bulge at the Swift hardening (n, ε0); a bulge too
    large for n is tried at the table's lower n values (less hardening barrels more); beyond
    them all, the face sticks: the table's largest μ, flagged as clamped."""
    n, eps0 = hardening
    candidates = [n] + sorted((float(v) for v in table.n if v < n), reverse=True)
    for value in candidates:
        try:
            return table.mu_from_bulge(dR_over_h, h0_d0, value, eps, eps0=eps0), (value, eps0), False
        except IdentificationError as exc:
            if "beyond the largest" not in str(exc):
                raise
    return table.mu_from_bulge(dR_over_h, h0_d0, candidates[-1], eps, eps0=eps0, clamp=True), (candidates[-1], eps0), True


def friction_fe_table(d0_mm: float, h0_mm: float, hk_mm: float, *, d_max_mm: float | None = None, s_max_mm2: float | None = None, curve=None,
                      d_face_mm: float | None = None) -> FrictionResult:
    """Coulomb μ from the bulge by the CalculiX table: ΔR/h (3.29) at ε = ln(h0/hk) (3.31) inverted.

    The table's hardening, the Swift (n, ε0) of the curve, comes from ``curve`` = (strain, mean
    pressure[, plastic strain]) corrected with the table's own force factor (a fixed point,
    starting from the uncorrected curve); without a curve n = 0.3, ε0 = 0.002. A bulge too large
    for that n is read at the table's lower n.

    With ``d_face_mm``, the diameter of the original end face (its machined area, not the side
    folded onto the platen), μ comes from the face instead: near sticking it still shrinks with
    μ where the barrel has stopped growing (at h0/d0 1, μ 0.2 → 0.3: 0.56 mm against 0.04 mm of
    dmax). The bulge's μ stays in the result (``mu_from_bulge``).
    """
    from flowcurve.identification.fe.model.table import UpsettingTable

    _check_geometry(d0_mm, h0_mm, hk_mm)
    d_max, used = _measured_max_diameter(d_max_mm, s_max_mm2)
    d_n = float(nominal_diameter(d0_mm, h0_mm, hk_mm))
    delta_r = float(bulge_excess(d_max, d_n))
    if -DIAMETER_RESOLUTION_MM / 4 <= delta_r < 0:
        delta_r = 0.0
    if delta_r < 0:
        raise IdentificationError(f"FE table: negative bulge ΔR = {delta_r:.4g} mm (dmax below the volume-constant diameter {d_n:.4g} mm; check d0, h0, hk and dmax)")
    eps_k = float(height_strain(hk_mm, h0_mm))
    table = UpsettingTable.load()
    h0_d0 = h0_mm / d0_mm
    eps_p = curve[2] if curve is not None and len(curve) > 2 else None
    hardening = _swift_of(curve[0] if eps_p is None else eps_p, curve[1], eps_p is not None) if curve is not None else FE_DEFAULT_HARDENING
    face = None
    if d_face_mm is not None:
        if not (math.isfinite(d_face_mm) and 0 < d_face_mm <= d_n + DIAMETER_RESOLUTION_MM):
            raise IdentificationError(f"FE table: the end face's diameter {d_face_mm:g} mm must be positive and not above the volume-constant diameter {d_n:.4g} mm")
        face = min(d_face_mm / d_n, 1.0)
    mu, hardening, clamped = _fe_mu_fixed_point(table, curve, eps_p, hardening, face, delta_r / hk_mm, h0_d0, eps_k)
    n, eps0 = hardening
    inputs = {"d0_mm": d0_mm, "h0_mm": h0_mm, "hk_mm": hk_mm, **used, **({"dface_mm": float(d_face_mm)} if face is not None else {})}
    extra = {"d_n_mm": d_n, "delta_R_mm": delta_r, "eps_p": eps_k, "hardening_n": n, "hardening_eps0": eps0,
             "hardening_from": "record curve (Swift fit)" if curve is not None else "default", "beyond_table_sticking": clamped,
             "table": Path(table.path).name, "table_ccx_version": table.meta.get("ccx_version"), "table_date": table.meta.get("date")}
    if face is None:
        extra.update(mu_basis="bulge (dmax)", sensitivity=_fe_mu_sensitivity(table, mu, h0_d0, hardening, eps_k, hk_mm),
                     mu_range=_fe_mu_range(table, delta_r, hk_mm, h0_d0, hardening, eps_k),
                     mu_range_basis=f"the bulge with dmax ± {DIAMETER_RESOLUTION_MM} mm and the FE model form's ± {mf.BULGE_MODEL_FORM:.0%} of it")
        extra["mu_stderr"] = mf.stderr_of_range(*extra["mu_range"])
    else:
        extra.update(_fe_face_extra(table, face, mu, d_n, delta_r, hk_mm, h0_d0, hardening, eps_k))
    outside = _outside_table(table, h0_d0, n, eps0)
    if outside:
        extra["outside_table"] = outside
    _open_if_continued(extra, table, mu, h0_d0, n, eps_k, eps0)
    return FrictionResult("fe_table", mu, inputs, extra)


def _fe_mu_fixed_point(table, curve, eps_p, hardening: tuple[float, float], face: float | None, bulge_over_hk: float,
                       h0_d0: float, eps_k: float) -> tuple[float, tuple[float, float], bool]:
    """(μ, Swift (n, ε0), beyond the table's sticking) read from the bulge ΔR/hk or the end face d/d_n (``face``),
    and with a ``curve`` the fixed point: the curve corrected with the table's force factor at μ, its Swift refitted,
    μ read again (FE_HARDENING_ITERATIONS times)."""

    def read_mu(hardening):
        """μ of the FE table at ``hardening`` (n, ε0)."""
        if face is None:
            return _fe_mu_lowering_n(table, bulge_over_hk, h0_d0, hardening, eps_k)
        mu = table.mu_from_face(face, h0_d0, hardening[0], eps_k, eps0=hardening[1], clamp=True)
        return mu, hardening, mu >= float(table.mu[-1]) - 1e-12

    mu, hardening, clamped = read_mu(hardening)
    if curve is not None:
        for _ in range(FE_HARDENING_ITERATIONS):
            _, hardening = _fe_flow_stress(table, curve[0], curve[1], mu, h0_d0, eps_p)
            mu, hardening, clamped = read_mu(hardening)
    return mu, hardening, clamped


def _fe_face_extra(table, face: float, mu: float, d_n: float, delta_r: float, hk_mm: float, h0_d0: float,
                   hardening: tuple[float, float], eps_k: float) -> dict:
    """What μ from the end face (d/d_n = ``face``) adds to the FE table's result: its range over the face's σ (the
    resolution and the model form), its sensitivity, and the bulge's μ beside it with their disagreement."""
    n, eps0 = hardening

    def face_mu(half):
        """μ at the face ratio ± ``half`` (the table's spread)."""
        return [table.mu_from_face(min(face + sign * half, 1.0), h0_d0, n, eps_k, eps0=eps0, clamp=True) for sign in (1.0, -1.0)]

    lo, hi = face_mu(mf.face_sigma(d_n, DIAMETER_RESOLUTION_MM))
    lo_res, hi_res = face_mu(DIAMETER_RESOLUTION_MM / d_n)
    try:
        bulge_mu = _fe_mu_lowering_n(table, delta_r / hk_mm, h0_d0, hardening, eps_k)[0]
        bulge_range = _fe_mu_range(table, delta_r, hk_mm, h0_d0, hardening, eps_k)
    except IdentificationError:
        bulge_mu = bulge_range = None
    extra = dict(mu_basis="original end face (dface)", mu_from_bulge=bulge_mu, d_face_over_d_n=face,
                 sensitivity={"mu_per_dface_resolution": max(hi_res - lo_res, 0.0) / 2.0}, mu_range=[lo, hi],
                 mu_range_basis=f"the end face with dface ± {DIAMETER_RESOLUTION_MM} mm and the FE model form's ± {mf.FACE_MODEL_FORM} of d/d_n",
                 mu_stderr=mf.stderr_of_range(lo, hi))
    if bulge_range is not None:
        se_bulge = mf.stderr_of_range(*bulge_range)
        extra.update(mu_from_bulge_range=bulge_range, mu_from_bulge_stderr=se_bulge,
                     face_bulge_disagreement_sigmas=mf.disagreement(mu, extra["mu_stderr"], bulge_mu, se_bulge))
    return extra


def _open_if_continued(extra: dict, table, mu: float, h0_d0: float, n: float, eps_k: float, eps0: float) -> None:
    """Where the table's runs above μ stopped and were continued, no run reached this shape above it: μ is a lower
    bound, and ``extra``'s range opens to the table's largest μ (its standard error with it)."""
    continued = table.continued_at(mu, h0_d0, n, eps_k, eps0)
    if continued is None:
        return
    extra["continued_runs_from_strain"] = continued
    extra["mu_range"] = [extra["mu_range"][0], float(table.mu[-1])]
    extra["mu_range_basis"] += f"; open to the table's largest μ (its runs stopped at ε {continued:.2f} and were continued)"
    extra["mu_stderr"] = mf.stderr_of_range(*extra["mu_range"])


def _fe_mu_sensitivity(table, mu: float, h0_d0: float, hardening: tuple[float, float], eps: float, hk_mm: float) -> dict:
    """How well the bulge tells μ: the μ a dmax reading off by its resolution (0.01 mm) moves.
    Near sticking the barrel stops growing with μ, and μ is then a lower bound at best."""
    # ΔR = (dmax − d_n)/2 → δμ = (δd/2) / (dΔR/dμ), dΔR/dμ = hk·d(ΔR/h)/dμ
    n, eps0 = hardening
    lo, hi = max(mu - 0.02, 0.0), min(mu + 0.02, float(table.mu[-1]))
    if hi <= lo:
        return {}
    b_lo, b_hi = (float(table.bulge_at(m, h0_d0, n, [eps], eps0)[0]) for m in (lo, hi))
    slope_mm = (b_hi - b_lo) * hk_mm / (hi - lo)  # dΔR/dμ, mm
    if not (math.isfinite(slope_mm) and slope_mm > 0):  # a flat barrel: no μ moves it (None: not told at all)
        return {"dR_mm_per_mu": slope_mm if math.isfinite(slope_mm) else None, "mu_per_dmax_resolution": None}
    return {"dR_mm_per_mu": slope_mm, "mu_per_dmax_resolution": DIAMETER_RESOLUTION_MM / 2.0 / slope_mm}


def _fe_mu_range(table, delta_r_mm: float, hk_mm: float, h0_d0: float, hardening: tuple[float, float], eps: float) -> list[float]:
    """[μ_lo, μ_hi]: the μ the table reads for the bulge ΔR less and plus its uncertainty
    (:func:`.fe.model_form.bulge_sigma_mm`: dmax's resolution, 0.01 mm, and the model form's share of ΔR). Near
    sticking the barrel stops growing with μ and the interval opens up to the table's largest μ:
    what the bulge can tell, stated rather than hidden in a point value."""
    # ΔR ± √((δd/2)² + (u·ΔR)²) (3.29) inverted at the record's (h0/d0, n, ε0, ε)
    n, eps0 = hardening
    half = mf.bulge_sigma_mm(delta_r_mm, DIAMETER_RESOLUTION_MM)
    return [table.mu_from_bulge(max(delta_r_mm + sign * half, 0.0) / hk_mm, h0_d0, n, eps, eps0=eps0, clamp=True) for sign in (-1.0, 1.0)]


def _outside_table(table, h0_d0: float, n: float, eps0: float) -> list[str]:
    """The record's hardening beyond the table's axes (read at the nearest edge)."""
    out = []
    if not (table.n[0] - 1e-9 <= n <= table.n[-1] + 1e-9):
        out.append(f"hardening n {n:.3g} outside the table's {table.n[0]:g}–{table.n[-1]:g}")
    if table.eps0.size > 1 and eps0 > table.eps0[-1] * 1.001:  # below the first ε0 the early hardening is inside the 0.2 % offset
        out.append(f"Swift ε0 {eps0:.3g} (a high yield for its hardening) beyond the table's {table.eps0[-1]:g}")
    return out


DEFAULT_POISSON = 0.3  # metals; a record's material.nu replaces it


def elastic_volume_ratio(stress_MPa, E_MPa: float, nu: float = DEFAULT_POISSON):
    """V/V0 of a specimen under the axial compressive stress σ (positive): plastic flow keeps the
    volume, the elastic strains (−σ/E axial, +νσ/E lateral) shrink it."""
    # J = exp(ε_axial + 2·ε_lateral) = exp(−(1 − 2ν)·σ/E)
    return np.exp(-(1.0 - 2.0 * nu) * np.asarray(stress_MPa, dtype=float) / E_MPa)


def fe_fold_over_onset(mu: float, h0_d0: float, strain, stress_MPa, eps_p=None) -> float | None:
    """The FE table's fold-over onset (height strain) for a record corrected at ``mu``: read at its
    h0/d0 and the Swift (n, ε0) of its corrected curve (:meth:`.fe.model.table.UpsettingTable.fold_over_at`,
    the earliest of the cell's runs); None when none of them folds over."""
    from flowcurve.identification.fe.model.table import UpsettingTable

    table = UpsettingTable.load()
    n, eps0 = _swift_of(strain if eps_p is None else eps_p, stress_MPa, eps_p is not None)
    return table.fold_over_at(mu, min(max(h0_d0, float(table.h0_d0[0])), float(table.h0_d0[-1])), n, eps0)


def correct_fe_table(strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=None, elastic=None):
    """(strain, p) → (strain, σ_f) with the CalculiX force factor F/(σ_f·A) of the FE table; the
    table's hardening from the Swift fit of σ_f over ``eps_p`` (the plastic strain; without it
    the total strain from 0.02 on).

    The table's factor is relative to its μ = 0 run, whose force is σ_f times the *loaded* area:
    A·J, smaller than the volume-constant A by the elastic volume change J. With ``elastic`` =
    (E MPa, ν) the pressure p = F/A is put on that area, as the table's reference was (+0.1–0.3 %
    at 300–1100 MPa; CalculiX's own homogeneous runs show it: docs/methods.md §4a.2)."""
    # σ_f = p / (factor(μ, h0/d0, n, ε)·J(σ_f)), factor from identification/fe (make_table), J one fixed-point step
    from flowcurve.identification.fe.model.table import UpsettingTable, specimen_proportion

    strain = np.atleast_1d(np.asarray(strain, dtype=float))
    radius, height = (np.broadcast_to(np.asarray(v, dtype=float), strain.shape) for v in (radius_mm, height_mm))
    table = UpsettingTable.load()
    sel = strain > 0.01
    h0_d0 = specimen_proportion(strain[sel], radius[sel], height[sel]) if sel.any() else 1.0
    sigma, _ = _fe_flow_stress(table, strain, pressure_MPa, mu, h0_d0, eps_p)
    if elastic is not None:
        sigma = sigma / elastic_volume_ratio(sigma, *elastic)
    return strain, sigma


# -- corrections of the flow curve ----------------------------------------------------------


def k_sigma(mu, eps_p):
    """The seed's stress correction factor K_σ(μ, ε_p)."""
    # (3.24) K_σ = 1 + 0.2166μ + 1.344μ·ε_p − 0.5512μ² − 1.8164μ·ε_p²
    eps_p = np.asarray(eps_p, dtype=float)
    return 1.0 + 0.2166 * mu + 1.344 * mu * eps_p - 0.5512 * mu**2 - 1.8164 * mu * eps_p**2


def k_eps(mu, eps_p):
    """The seed's strain correction factor K_ε(μ, ε_p)."""
    # (3.27) K_ε = 1 + 4.353μ − 1.05·ε_p·μ
    eps_p = np.asarray(eps_p, dtype=float)
    return 1.0 + 4.353 * mu - 1.05 * eps_p * mu


def siebel_factor(mu, radius_mm, height_mm):
    """Mean pressure over flow stress by Siebel's approximation."""
    # p/σ_f = 1 + 2μr/(3h)
    return 1.0 + 2.0 * mu * np.asarray(radius_mm, dtype=float) / (3.0 * np.asarray(height_mm, dtype=float))


def slab_factor(mu, radius_mm, height_mm):
    """Mean pressure over flow stress by the exact Coulomb slab solution (no sticking)."""
    # p/σ_f = 2(e^c − c − 1)/c², c = 2μr/h
    c = np.asarray(2.0 * mu * np.asarray(radius_mm, dtype=float) / np.asarray(height_mm, dtype=float), dtype=float)
    small = np.abs(c) < 1e-3
    cs = np.where(small, 1.0, c)  # avoid 0/0 where the series is used
    exact = 2.0 * (np.expm1(cs) - cs) / cs**2
    series = 1.0 + c / 3.0 + c**2 / 12.0 + c**3 / 60.0  # Taylor series of the same function
    return np.where(small, series, exact)


def correct_k_sigma(strain, pressure_MPa, mu, radius_mm=None, height_mm=None, eps_p=None):
    """(strain, σ_n) → (ε_t, σ_t) by the seed's regressions (no hardening enters: ``eps_p`` unused)."""
    # (3.21) σ_t = K_σ·σ_n, (3.25) ε_t = K_ε·ε_n
    strain = np.asarray(strain, dtype=float)
    return k_eps(mu, strain) * strain, k_sigma(mu, strain) * np.asarray(pressure_MPa, dtype=float)


def correct_siebel(strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=None):
    """(strain, p) → (strain, σ_f) with Siebel's mean-pressure factor (``eps_p`` unused)."""
    # σ_f = p / (1 + 2μr/(3h))
    return np.asarray(strain, dtype=float), np.asarray(pressure_MPa, dtype=float) / siebel_factor(mu, radius_mm, height_mm)


def correct_slab(strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=None):
    """(strain, p) → (strain, σ_f) with the exact Coulomb slab factor (``eps_p`` unused)."""
    # σ_f = p·c²/(2(e^c − c − 1)), c = 2μr/h
    return np.asarray(strain, dtype=float), np.asarray(pressure_MPa, dtype=float) / slab_factor(mu, radius_mm, height_mm)


CORRECTIONS: dict[str, Callable] = {
    "fe_table": correct_fe_table,
    "k_sigma": correct_k_sigma,
    "siebel": correct_siebel,
    "slab": correct_slab,
}
DEFAULT_CORRECTION = "fe_table"


def correct(method: str, strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=None, elastic=None):
    """Apply the named correction (one of :data:`CORRECTIONS`) → (strain, flow stress MPa);
    ``eps_p`` (the plastic strain) lets ``fe_table`` read the curve's hardening, ``elastic``
    (E MPa, ν) puts its pressure on the loaded area (:func:`correct_fe_table`). The analytic
    corrections keep their textbook volume-constant area."""
    try:
        fn = CORRECTIONS[method]
    except KeyError:
        raise IdentificationError(f"unknown friction correction {method!r} (choose from {', '.join(CORRECTIONS)})") from None
    if not (math.isfinite(mu) and mu >= 0):
        raise IdentificationError(f"friction correction: μ = {mu} must be a finite number ≥ 0")
    if fn is correct_fe_table:
        return fn(strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=eps_p, elastic=elastic)
    return fn(strain, pressure_MPa, mu, radius_mm, height_mm, eps_p=eps_p)

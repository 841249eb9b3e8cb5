"""Model-form error of the upsetting model: how far another defensible model (mesh, contact,
increments, another code's formulation) puts the final shape and the force at the same law, μ
and h0/d0, as standard deviations, and what they do to μ and the hardening constants.

The figures are the spread measured by ``bench/model_form_spread.py`` (docs/methods.md §4a.4):
the product's model against a finer mesh, a softer stick slope, 200 increments and the second
model of the tests (tests/fe/second_model.py), summed in quadrature per case, the largest case.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

# σ of the bulge ΔR = (dmax − d_n)/2, relative (mesh, increments, second model in quadrature)
BULGE_MODEL_FORM = 0.05
# σ of the original end face's d/d_n, absolute (the second model's rim node sits this much wider)
FACE_MODEL_FORM = 0.02
# σ of the force at a given law, μ and h0/d0, relative, per unit μ (it grows with friction's share of the force)
FORCE_MODEL_FORM_PER_MU = 0.12
# the shape of the fe_table correction's model form along the stroke: "friction_share" (0.12·μ at the stroke's end, where it
# was measured, scaled by Siebel's friction share m(ε)/m(ε_end) before it; for the constants that one pattern),
# "friction_share_points" (so on the curve's points only, the constants' uniform and linear patterns kept) or "uniform"
# (0.12·μ all along): measured by bench/model_form_shape.py (docs/methods.md §4a.7), not adopted
MODEL_FORM_SHAPE = "uniform"
# two μ whose difference exceeds this many combined standard errors disagree
DISAGREE_SIGMAS = 2.0
# where the side folds onto the platen: the model's own force error, ±1 % (its sawtooth, docs/calculix.md; its mesh 0.4 %)
FORCE_SIGMA_PCT = 1.0
# the strain before the fold-over's onset over which the model's force error grows (another model's record at the true
# law and μ: 0.3 % below ε 0.45, 0.5–0.9 % at 0.45–0.55, 1.3–1.7 % at 0.55–0.6 for an onset at 0.616)
FOLD_OVER_BAND = 0.1
# a force's σ grows over the FOLD_OVER_BAND before the fold-over to this many times FORCE_SIGMA_PCT at the onset and
# beyond (the inverse's weights, §4a.3; a finer discretisation differs by up to 1.6–2.0 % there, §4a.5)
FOLD_OVER_SIGMA_FACTOR = 3.0


def quadrature(*parts: float) -> float:
    """√(Σ part²): independent standard uncertainties combined."""
    return math.sqrt(sum(float(p) ** 2 for p in parts))


def bulge_sigma_mm(delta_r_mm: float, resolution_mm: float, share: float = BULGE_MODEL_FORM) -> float:
    """σ of a bulge ΔR (mm) against the model: half dmax's resolution and the model's relative
    ``share`` of ΔR (the model form's by default; the mesh's alone for weighting a fit)."""
    # σ_ΔR = √((δd/2)² + (u_b·ΔR)²)
    return quadrature(resolution_mm / 2.0, share * delta_r_mm)


def face_sigma(d_n_mm: float, resolution_mm: float, share: float = FACE_MODEL_FORM) -> float:
    """σ of the end face's d/d_n against the model: dface's resolution over d_n and the model's
    absolute ``share`` (the model form's by default; the mesh's alone for weighting a fit)."""
    # σ_f = √((δd/d_n)² + u_f²)
    return quadrature(resolution_mm / d_n_mm, share)


def stderr_of_range(lo: float, hi: float) -> float:
    """The standard error a ±1σ interval [lo, hi] of μ stands for: half its width."""
    return abs(float(hi) - float(lo)) / 2.0


def disagreement(mu_a: float, se_a: float, mu_b: float, se_b: float) -> float:
    """|μ_a − μ_b| in combined standard errors (inf when both are exact and differ)."""
    # z = |μ_a − μ_b| / √(se_a² + se_b²)
    diff, se = abs(mu_a - mu_b), quadrature(se_a, se_b)
    return diff / se if se > 0 else (math.inf if diff > 0 else 0.0)


def disagree(mu_a: float, se_a: float, mu_b: float, se_b: float) -> bool:
    """True when two μ differ by more than :data:`DISAGREE_SIGMAS` combined standard errors."""
    return disagreement(mu_a, se_a, mu_b, se_b) > DISAGREE_SIGMAS


def force_model_form(mu: float) -> float:
    """σ of the model's force at friction μ, relative: :data:`FORCE_MODEL_FORM_PER_MU`·μ."""
    return FORCE_MODEL_FORM_PER_MU * max(float(mu), 0.0)


def fold_over_ramp(strain, onset: float | None) -> np.ndarray:
    """0 before the :data:`FOLD_OVER_BAND` that ends at the fold-over's ``onset``, growing linearly
    to 1 at the onset and 1 beyond it (all 0 when there is no onset)."""
    # g = clip((ε − ε_f + b)/b, 0, 1)
    eps = np.asarray(strain, float)
    if onset is None:
        return np.zeros(eps.shape)
    return np.clip((eps - onset + FOLD_OVER_BAND) / FOLD_OVER_BAND, 0.0, 1.0)


def friction_share_shape(strain, mu: float, h0_d0: float, strain_ref: float) -> np.ndarray:
    """Siebel's share of friction in the mean pressure along the stroke, m(ε) = k/(1 + k), k = μ·d/(3h),
    d/h = (d0/h0)·e^(1.5ε) (volume constant), relative to its value at ``strain_ref``: m(ε)/m(ε_ref)
    (its μ → 0 limit e^(1.5(ε − ε_ref)) at μ 0)."""
    # m(ε)/m(ε_ref) = e^(1.5(ε − ε_ref))·(1 + k_ref)/(1 + k)
    eps = np.asarray(strain, float)
    k = max(float(mu), 0.0) / (3.0 * float(h0_d0)) * np.exp(1.5 * eps)
    k_ref = max(float(mu), 0.0) / (3.0 * float(h0_d0)) * math.exp(1.5 * float(strain_ref))
    return np.exp(1.5 * (eps - float(strain_ref))) * (1.0 + k_ref) / (1.0 + k)


def model_form_shape(strain, mu: float, h0_d0: float | None, strain_ref: float | None) -> np.ndarray:
    """The fe_table correction's model form along the stroke, relative to :func:`force_model_form` (1 at the
    stroke's end ``strain_ref``, where 0.12·μ was measured, §4a.7): :data:`MODEL_FORM_SHAPE` "friction_share"
    (:func:`friction_share_shape`) or "uniform" (1 all along; also without h0/d0 or a stroke's end)."""
    eps = np.asarray(strain, float)
    if MODEL_FORM_SHAPE == "uniform" or h0_d0 is None or strain_ref is None or not math.isfinite(strain_ref):
        return np.ones(eps.shape)
    return friction_share_shape(eps, mu, h0_d0, strain_ref)


def corrected_stress_uncertainty_pct(strain, mu: float, onset: float | None, h0_d0: float | None = None,
                                     strain_ref: float | None = None) -> np.ndarray:
    """σ of a flow stress corrected by the model's force factor, % per point at ``strain``: the
    model form's force share at μ (:func:`force_model_form`, shaped along the stroke by :func:`model_form_shape`),
    growing over the band before the fold-over's ``onset`` (:func:`fold_over_ramp`) to
    :data:`FOLD_OVER_SIGMA_FACTOR` × :data:`FORCE_SIGMA_PCT` (the inverse's σ there) where that is larger."""
    # u = u_mf·s(ε) + g·max(k·σ_F − u_mf·s(ε), 0)
    u_mf = 100.0 * force_model_form(mu) * model_form_shape(strain, mu, h0_d0, strain_ref)
    return u_mf + fold_over_ramp(strain, onset) * np.maximum(FOLD_OVER_SIGMA_FACTOR * FORCE_SIGMA_PCT - u_mf, 0.0)


def shift_of_bias(jac, bias) -> np.ndarray:
    """The parameter shift a systematic residual offset ``bias`` (one per row, residual units)
    makes in a least-squares fit with Jacobian ``jac`` (rows × parameters)."""
    # δx = −J⁺·δr
    J = np.nan_to_num(np.asarray(jac, float))  # a column a failed run left blank moves nothing
    return -np.linalg.lstsq(J, np.asarray(bias, float), rcond=None)[0]


def correction_force_patterns(eps_p, strain, mu: float, h0_d0: float | None, strain_ref: float | None) -> tuple[np.ndarray, ...]:
    """The shapes the fe_table correction's model form takes along the fitted points (plastic strain ``eps_p``, true
    strain ``strain``) for the constants' refits: with :data:`MODEL_FORM_SHAPE` "friction_share" the one
    :func:`model_form_shape` at ``strain``, else :func:`force_patterns` over ``eps_p``."""
    if MODEL_FORM_SHAPE != "friction_share" or h0_d0 is None or strain_ref is None:
        return force_patterns(eps_p)
    return (model_form_shape(strain, mu, h0_d0, strain_ref),)


def force_patterns(strain) -> tuple[np.ndarray, np.ndarray]:
    """The shapes the model form's force error takes along the stroke: a uniform offset and one
    growing from 0 to 1 over the strain (friction's share of the force grows with d/h)."""
    eps = np.asarray(strain, float)
    return np.ones_like(eps), (eps - eps.min()) / max(np.ptp(eps), 1e-12)


def force_model_form_stderr(jac, force_rows, strain, force_sigma_pct: float, mu: float) -> np.ndarray:
    """Per parameter: the shift a force model error of :func:`force_model_form` at μ makes, as a
    uniform offset and as one growing from 0 to it over the strain, in quadrature. ``force_rows``
    index the rows of ``jac`` holding the force residuals (in units of ``force_sigma_pct`` %)."""
    J = np.asarray(jac, float)
    rows = np.asarray(force_rows)
    shifts = []
    for pattern in force_patterns(strain):
        bias = np.zeros(J.shape[0])
        bias[rows] = 100.0 * force_model_form(mu) * pattern / force_sigma_pct
        shifts.append(shift_of_bias(J, bias))
    return np.hypot(*shifts)


def through_mu(params_lo: Mapping[str, float], params_hi: Mapping[str, float]) -> dict[str, float]:
    """Per constant: half the change between fits at μ − se and μ + se (μ's share of its standard error)."""
    return {k: abs(float(params_hi[k]) - float(params_lo[k])) / 2.0 for k in params_lo if k in params_hi}


def combined_stderr(stderr: Mapping[str, float | None], *shares: Mapping[str, float]) -> dict[str, float | None]:
    """The fit's standard errors with other shares added in quadrature (None stays None: undetermined)."""
    out: dict[str, float | None] = {}
    for k, se in stderr.items():
        if se is None or not math.isfinite(se):
            out[k] = se
            continue
        out[k] = quadrature(se, *(s.get(k, 0.0) for s in shares))
    return out

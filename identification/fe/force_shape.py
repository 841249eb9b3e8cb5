"""Where an inverse FE fit's μ came from: what its force rows alone and its shape rows alone tell
of μ at the fit point, each with its standard error (the fit's and the model form's, in
quadrature), and whether the two disagree beyond their combined standard errors
(:func:`.model_form.disagree`) — the force curve and the bulge pulling μ apart, as a model whose
form differs from the record's does."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.fe.solver_fit import parameter_covariance


@dataclass(frozen=True)
class MuBySide:
    """μ (and its standard error) the force rows alone and the shape rows alone tell; NaN where a
    side does not tell μ (a singular column, a row that does not move with μ)."""

    mu_force: float
    stderr_force: float
    mu_shape: float
    stderr_shape: float

    @property
    def force_told(self) -> bool:
        """Whether the force gave μ (finite value and error)."""
        return math.isfinite(self.mu_force) and math.isfinite(self.stderr_force)

    @property
    def shape_told(self) -> bool:
        """Whether the shape gave μ (finite value and error)."""
        return math.isfinite(self.mu_shape) and math.isfinite(self.stderr_shape)

    @property
    def disagreement_sigmas(self) -> float:
        """|μ_force − μ_shape| in combined standard errors; NaN unless both sides tell μ."""
        if not (self.force_told and self.shape_told):
            return float("nan")
        return mf.disagreement(self.mu_force, self.stderr_force, self.mu_shape, self.stderr_shape)

    @property
    def combined_stderr(self) -> float:
        """The standard error of the two sides' estimates combined by their weights, (se_f⁻² + se_s⁻²)^(−1/2);
        the one side's where only one tells μ; NaN where neither does."""
        # se = (Σ se_i⁻²)^(−1/2) over the sides that tell μ
        told = [se for se, ok in ((self.stderr_force, self.force_told), (self.stderr_shape, self.shape_told)) if ok and se > 0]
        return float(sum(se**-2 for se in told) ** -0.5) if told else math.nan

    @property
    def disagree(self) -> bool:
        """True when both sides tell μ and differ by more than :data:`.model_form.DISAGREE_SIGMAS`."""
        return self.disagreement_sigmas > mf.DISAGREE_SIGMAS  # NaN compares False

    def as_dict(self) -> dict:
        """result.json's keys (NaN: not told; written as null)."""
        return {"mu_force_alone": {"mu": self.mu_force, "stderr": self.stderr_force},
                "mu_shape_alone": {"mu": self.mu_shape, "stderr": self.stderr_shape},
                "force_shape_disagreement_sigmas": self.disagreement_sigmas}


def mu_force_alone(jac, residuals, x, force_rows, *, k: int = -1, x_scale=None, model_form_stderr: float = 0.0) -> tuple[float, float]:
    """(μ, standard error) the force rows alone tell, all parameters free: the linearised
    Gauss–Newton step from the fit point ``x`` over those rows of ``jac`` and ``residuals``
    (rows in units of their σ), the covariance of :func:`.solver_fit.parameter_covariance` over
    its misfit (pooled, serially correlated), ``model_form_stderr`` in quadrature; (NaN, NaN) where
    the force rows do not determine parameter ``k`` (μ)."""
    # x_f = x − J_f⁺·r_f ;  se² = [(J_fᵀJ_f)⁻¹·s²]_kk + se_mf²
    J = np.asarray(jac, float)[force_rows]
    r = np.asarray(residuals, float)[force_rows]
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        return math.nan, math.nan
    step = -np.linalg.lstsq(J, r, rcond=None)[0]
    cov, undetermined = parameter_covariance(J, r + J @ step, x_scale, correlated=True)
    k = k % J.shape[1]
    if k in undetermined or not np.isfinite(cov[k, k]):
        return math.nan, math.nan
    return float(np.asarray(x, float)[k] + step[k]), mf.quadrature(math.sqrt(max(cov[k, k], 0.0)), model_form_stderr)


def mu_shape_alone(jac, residuals, x, shape_rows, *, k: int = -1, model_form_offsets=None) -> tuple[float, float]:
    """(μ, standard error) the shape rows alone tell with the law's constants held at the fit:
    parameter ``k`` (μ) moved alone by least squares over those rows of ``jac`` and ``residuals``
    (rows in units of their σ), with the shift each row's ``model_form_offsets`` (σ units) makes,
    in quadrature; (NaN, NaN) where the rows do not move with μ."""
    # μ_s = μ − Σ J_ik·r_i / Σ J_ik² ;  se² = 1/Σ J_ik² + Σ (o_i·J_ik / Σ J_ik²)²
    g = np.asarray(jac, float)[shape_rows, k]
    r = np.asarray(residuals, float)[shape_rows]
    info = float(g @ g) if np.all(np.isfinite(g)) and np.all(np.isfinite(r)) else math.nan
    if not info > 0.0:
        return math.nan, math.nan
    offsets = np.zeros_like(g) if model_form_offsets is None else np.asarray(model_form_offsets, float)
    return float(np.asarray(x, float)[k] - (g @ r) / info), mf.quadrature(1.0 / math.sqrt(info), *(offsets * g / info))


def inverse_mu_by_side(jac, residuals, x, strain, force_sigma_pct: float, n_shape: int, *, x_scale=None) -> MuBySide:
    """:class:`MuBySide` of an inverse FE fit whose rows are the force at ``strain`` (in units of
    ``force_sigma_pct`` %), then ``n_shape`` shape rows in units of their σ (the model form's share in it); μ the last
    parameter. The force side adds the shift the model form's force error (0.12·μ, uniform and
    growing) makes in it, in quadrature."""
    J = np.asarray(jac, float)
    n_force = len(strain)
    force_rows, shape_rows = np.arange(n_force), np.arange(n_force, n_force + n_shape)
    mu = float(np.asarray(x, float)[-1])
    if np.all(np.isfinite(J[force_rows])):
        force_mf = float(mf.force_model_form_stderr(J[force_rows], force_rows, strain, force_sigma_pct, mu)[-1])
    else:
        force_mf = math.nan
    mu_f, se_f = mu_force_alone(J, residuals, x, force_rows, x_scale=x_scale, model_form_stderr=force_mf)
    mu_s, se_s = mu_shape_alone(J, residuals, x, shape_rows)
    return MuBySide(mu_f, se_f, mu_s, se_s)


def force_shape_check(side: MuBySide, shape: str) -> tuple[str, str | None]:
    """(what the comparison found, a warning or None) for an inverse fit whose shape rows are
    ``shape`` (e.g. "dmax and dface"): a warning only when both sides tell μ and disagree."""
    told = [name for name, ok in (("the force curve", side.force_told), (shape, side.shape_told)) if not ok]
    if told:
        return (f"μ from the force and from the shape not compared: {' and '.join(told)} alone do{'es' if len(told) == 1 else ''} not "
                "tell μ at the fit (a singular column, or rows that do not move with μ)"), None
    z = side.disagreement_sigmas
    found = (f"μ from the force curve alone {side.mu_force:.3f} ± {side.stderr_force:.3f}, from {shape} alone "
             f"{side.mu_shape:.3f} ± {side.stderr_shape:.3f}: {z:.1f} combined standard errors apart")
    if not side.disagree:
        return found, None
    return found, (f"inverse FE: {found} (more than {mf.DISAGREE_SIGMAS:g}): the force and the shape pull μ apart — the upsetting "
                   f"model's form differs from this record's, or a measurement is off: check the measured {shape}, the "
                   "frame's compliance and the force's zero; the hardening is poor")

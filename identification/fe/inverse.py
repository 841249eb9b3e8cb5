"""Inverse FE identification of compression: the hardening law and μ with CalculiX in the loop.

Fits the upsetting model (:mod:`.model.upsetting`, run to the record's shortening) to the record's
frame-corrected force–stroke curve, the bulge diameter dmax and, where measured, the end face's
dface, by weighted least squares (scipy ``least_squares``) warm-started from the fast (``fe_table``)
identification. Residuals: force at ``FORCE_POINTS`` strokes in units of ``FORCE_SIGMA_PCT``;
dmax and dface in units of their resolution and the model form's share
(:data:`.model.model_form.BULGE_MODEL_FORM`, :data:`.model.model_form.FACE_MODEL_FORM`).
Standard errors: the weighted Gauss–Newton covariance (:func:`.solver_fit.parameter_stderr`), the
force rows' variance inflated by (1 + ρ)/(1 − ρ) for their serial correlation. Method and
measured history: docs/methods.md §4a.3.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np
import pandas as pd

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.force_shape import force_shape_check, inverse_mu_by_side
from flowcurve.identification.fe.law_choice import best_law_for, check_law
from flowcurve.identification.fe.machine import model_elastics
from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.fe.solver_fit import fit_time_limit, fit_with_solver, progress_on_whole_clock, serial_correlation
from flowcurve.identification.compression.friction import DFACE_ADVICE, DIAMETER_RESOLUTION_MM, nominal_diameter
from flowcurve.identification.fe.model.ccx import timeout_by
from flowcurve.identification.fe.model.model_form import FOLD_OVER_SIGMA_FACTOR, FORCE_SIGMA_PCT, fold_over_ramp
from flowcurve.identification.fe.model.deck import PLASTIC_ROWS
from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting
from flowcurve.identification.laws.hardening import fit_hardening, static_form
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import CompressionBudget, CompressionInverseFE, InverseHardening
from flowcurve.record.specimen import circle_area_mm2

log = logging.getLogger(__name__)

FORCE_POINTS = 30
FROM_STRAIN = 0.02
MU_BOUNDS = (0.0, 0.35)
REL_STEP = 0.01  # finite-difference step, relative (absolute 0.005 for μ)
# a warm start whose run stops (near sticking, or a tall specimen folding onto the platen at some μ) is moved in μ
START_MU_STEPS = (-0.01, 0.01, -0.02, 0.02)
MU_TOLD = 0.02  # a μ standard error beyond this is said to be poorly told (as the fast method's dmax sensitivity)
TIME_LIMIT_S = 270.0  # the default wall-time budget: the held-out records C1–C3 end within 5 min on 2 cores
MIN_FORCE_STRAIN = 0.3  # the force is fitted at least this far, even where the side folds over earlier
# a force point's σ (FORCE_SIGMA_PCT) grows over the FOLD_OVER_BAND before the warm start's fold-over to
# FOLD_OVER_SIGMA_FACTOR times it (model_form.py); weighed as the rest, those points held C1's μ 0.013 low, and cut off,
# they left C3's law unheld beyond ε 0.4 (its curve 1.1 %, verify 3.2 %)


@dataclass(frozen=True)
class _Problem:
    law: str
    d0: float
    h0: float
    h_end: float
    E: float
    increments: int
    deadline: float | None = None  # wall clock (time.time()) by which a run must end: it is stopped there (the time limit)


def _model(problem: _Problem, x, **settings) -> UpsettingModel:
    """The run at parameters x (law…, μ); ``settings`` of a retry (another stick slope or increments)."""
    law = static_form(problem.law)
    params = dict(zip(law.names, (float(v) for v in x[:-1])))
    eps = np.concatenate([[0.0], np.geomspace(1e-4, 2.0, PLASTIC_ROWS)])
    sig = law.func(eps, **params)
    return UpsettingModel(problem.d0, problem.h0, problem.h_end, float(x[-1]), tuple(map(float, eps)), tuple(map(float, sig)),
                          E_MPa=problem.E, **{"increments": problem.increments, **settings}).realising()  # the law as the specimen's, not ccx's reading


@dataclass(frozen=True)
class _Run:
    stroke_mm: np.ndarray
    force_N: np.ndarray
    dmax_unloaded_mm: float
    dface_unloaded_mm: float  # the original end face (the top rim node), sprung back like dmax
    wall_s: float
    cached: bool
    retried: bool = False  # the model's own settings stopped and a retry's carried it
    fold_over_strain: float | None = None  # where the side began to fold onto the platen (None: it did not)


def _run(problem: _Problem, x) -> _Run | None:
    """Stroke, force and unloaded dmax of one CalculiX run; None when it did not converge, also
    when run again with the table's retries (:data:`.make_table.RETRY_SETTINGS`: a softer stick
    slope, other increments — where the side folds onto the platen a run stops at a strain that
    moves with the increment size)."""
    from flowcurve.identification.fe.model.ccx import SolverError
    from flowcurve.identification.fe.make_table import RETRY_SETTINGS

    tried = []
    for settings in ({}, *RETRY_SETTINGS):
        model = _model(problem, x, **settings)
        if model in tried:  # a retry on the inverse's own increments is the first run again
            continue
        tried.append(model)
        timeout_s = timeout_by(problem.deadline)
        if timeout_s is None:  # the time limit has come: no run (the fit ends with its best so far)
            log.info("inverse FE: run at %s not started: the time limit has come", x)
            return None
        try:
            r = simulate_upsetting(model, timeout_s=timeout_s)
            break
        except SolverError as exc:
            log.info("inverse FE: run at %s%s failed (%s)", x, f" with {settings}" if settings else "", exc)
    else:
        return None
    # dmax is measured unloaded: elastic spring-back of the diameter, d·(1 − ν·σ/E), σ = F/A at the end
    sigma_end = r.force_N[-1] / (math.pi * problem.d0**2 * problem.h0 / (4.0 * r.height_mm[-1]))
    springback = 1.0 - r.model.nu * sigma_end / problem.E
    return _Run(np.concatenate([[0.0], r.stroke_mm]), np.concatenate([[0.0], r.force_N]), float(r.dmax_mm[-1]) * springback,
                float(r.dtop_mm[-1]) * springback, r.wall_s, r.cached, len(tried) > 1, getattr(r, "fold_over_strain", None))


def _warm_start_run(problem: _Problem, x0) -> _Run | None:
    """The run at the warm start, before the fit (it stays in the run cache for the fit's first point)."""
    return _run(problem, x0)


def force_fit_limit(strain_max: float, fold_over_strain: float | None) -> float:
    """The strain up to which the force is fitted: the fold-over's onset (where the model's force
    error grows: the side folding onto the platen, its sawtooth, the mesh), held to at least
    :data:`MIN_FORCE_STRAIN` (or the record's end); beyond it the shape rows speak."""
    if fold_over_strain is None:
        return strain_max
    return float(min(strain_max, max(fold_over_strain, MIN_FORCE_STRAIN)))


def force_sigma_pct(strain, fold_over_strain: float | None) -> np.ndarray:
    """Per force point at ``strain``: its σ in the fit, % — :data:`FORCE_SIGMA_PCT`, growing linearly
    to :data:`FOLD_OVER_SIGMA_FACTOR` times it over the :data:`FOLD_OVER_BAND` of strain before the
    fold-over's onset (and beyond it), where the model's force error grows."""
    # σ_i = σ_F·(1 + (k − 1)·clip((ε_i − ε_f + b)/b, 0, 1))
    eps = np.asarray(strain, float)
    if fold_over_strain is None:
        return np.full(eps.shape, FORCE_SIGMA_PCT)
    return FORCE_SIGMA_PCT * (1.0 + (FOLD_OVER_SIGMA_FACTOR - 1.0) * fold_over_ramp(eps, fold_over_strain))


POOR_FORCE_RMS_PCT = 1.5  # a force misfit above this: the model (law, μ) does not describe the record
POOR_DMAX_MM = 0.02  # a bulge misfit above this (twice a caliper's 0.01 mm) and above twice its σ (the model form's share)


def poor_shape_misfit(residual_mm: float, sigma_mm: float = 0.0) -> bool:
    """True when a diameter's misfit exceeds both :data:`POOR_DMAX_MM` and twice its σ in the fit
    (resolution and the model form's share: another model places the end face 0.1–0.2 mm apart)."""
    return not abs(residual_mm) <= max(POOR_DMAX_MM, 2.0 * sigma_mm)


def _fit_warnings(force_rms_pct: float, dmax_residual_mm: float, mu: float, sol, dmax_sigma_mm: float = 0.0) -> list[str]:
    """What a user must not miss about an inverse fit: a force or bulge misfit the law and μ
    leave, a μ on its bound, an optimiser that did not converge."""
    out = []
    if not force_rms_pct <= POOR_FORCE_RMS_PCT:
        out.append(f"inverse FE: the fitted model misses the force by {force_rms_pct:.2g} % RMS (more than {POOR_FORCE_RMS_PCT:g} %): "
                   "the law or μ does not describe this record; try another --law, and check the fast result")
    if poor_shape_misfit(dmax_residual_mm, dmax_sigma_mm):
        out.append(f"inverse FE: the fitted model misses dmax by {dmax_residual_mm:+.3f} mm")
    if not MU_BOUNDS[0] + 1e-4 < mu < MU_BOUNDS[1] - 1e-4:
        out.append(f"inverse FE: μ {mu:.3f} sits on its bound ({MU_BOUNDS[0]:g}–{MU_BOUNDS[1]:g})")
    if sol.status <= 0 and not getattr(sol, "cut", False):  # a cut says so in its own warning
        out.append(f"inverse FE: the optimiser stopped before converging ({sol.message})")
    return out


@dataclass(frozen=True)
class _Inputs:
    """What the compression inverse reads before its fit: the record's curve, the model's elastics and the shape."""

    fast: Any  # the fast identification (warm start; its result is the inverse's base)
    stroke: np.ndarray
    force: np.ndarray
    elastics: Any  # .machine.ModelElastics
    diagram_options: dict
    dmax: float
    dface: float | None
    law_choice: dict
    problem: _Problem
    strain: np.ndarray


def _inputs(record, law: str, E_MPa: float | None, increments: int) -> _Inputs:
    """The record read for the fit: its force–stroke (again with the model's E and the fitted frame stiffness), the
    geometry and the post-test shape, the law (``auto``: :func:`.law_choice.best_law_for` the fast curve)."""
    from flowcurve.identification.fe.verify import record_force_stroke

    stroke, force, fast = record_force_stroke(record)
    elastics = model_elastics(record, fast.result, E_MPa)  # never an apparent slope; k stated or fitted by closure
    diagram_options = {**({"E_MPa": elastics.E_MPa} if elastics.E_basis != "the record's material.E_MPa" else {}),
                       **({"frame_stiffness_N_per_um": elastics.frame_stiffness_N_per_um} if elastics.frame_stiffness_stderr_N_per_um is not None else {})}
    if diagram_options:  # the record read again with the model's E and the fitted frame stiffness
        stroke, force, fast = record_force_stroke(record, **diagram_options)
    spec = record.specimen
    d0, h0, dmax = spec.d0_mm, spec.h0_mm, spec.dmax_mm
    if dmax is None:
        raise IdentificationError(f"{record.source}: --method inverse-fe needs the bulge diameter 'post.dmax_mm'")
    dface = spec.dface_mm  # optional: near sticking it tells μ where dmax cannot (§4a.2)
    law_choice = {"given": law}
    if law == "auto":
        law, rms = best_law_for(fast.true_curve)
        law_choice = {"chosen": law, "by": "the smallest RMS error of a fit to the fast (fe_table) curve", "rms_error_pct": rms}
    problem = _Problem(law, d0, h0, h0 - float(np.max(stroke)), float(elastics.E_MPa), increments)
    return _Inputs(fast, stroke, force, elastics, diagram_options, dmax, dface, law_choice, problem, -np.log(1.0 - stroke / h0))


@dataclass(frozen=True)
class _Start:
    """The warm start (the fast identification's law refitted in the requested one, its μ) and the bounds."""

    p0: list
    mu0: float
    x0: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    x_scale: np.ndarray


def _warm_start(inp: _Inputs) -> _Start:
    """The fit's start: the fast identification's law (refitted in the requested law when needed) and μ, in the bounds."""
    law = inp.problem.law
    law_info = static_form(law)
    fast = inp.fast
    if fast.result["hardening"].get("law") == law:
        p0 = [fast.result["hardening"][k] for k in law_info.keys]
    else:
        tc = fast.true_curve
        p0 = [fit_hardening(tc["true_plastic_strain"].to_numpy(), tc["true_stress_MPa"].to_numpy(), law).params[n] for n in law_info.names]
    mu0 = float(np.clip(fast.result["friction_mu"], MU_BOUNDS[0] + 0.005, MU_BOUNDS[1] - 0.01))
    x0 = np.array([*map(float, p0), mu0])
    lo = np.array([law_info.bounds[n][0] for n in law_info.names] + [MU_BOUNDS[0]])
    hi = np.array([law_info.bounds[n][1] for n in law_info.names] + [MU_BOUNDS[1]])
    x0 = np.clip(x0, lo + 1e-9, np.where(np.isfinite(hi), hi - 1e-9, np.inf))
    x_scale = np.maximum(np.abs(x0), 1e-3)
    x_scale[-1] = 0.05
    return _Start(p0, mu0, x0, lo, hi, x_scale)


@dataclass(frozen=True)
class _Rows:
    """The fit's rows: force points (strain, stroke, force, σ %) and the shape's σ (mm); the warm start's run."""

    first: _Run | None
    fold_over: float | None
    targets: np.ndarray
    s_pts: np.ndarray
    f_pts: np.ndarray
    f_sigma: np.ndarray
    shape_sigma: dict
    row_sigma: np.ndarray


def _rows(record, inp: _Inputs, x0) -> _Rows:
    """The force rows up to the fold-over's onset in the warm start's run (the time limit and the model's force error
    both grow where the side folds onto the platen; beyond it dmax and dface speak) and the shape rows' σ."""
    problem, stroke, strain, dmax, dface = inp.problem, inp.stroke, inp.strain, inp.dmax, inp.dface
    first = _warm_start_run(problem, x0)
    fold_over = first.fold_over_strain if first is not None else None
    force_to = force_fit_limit(float(strain.max()), fold_over)
    targets = np.linspace(max(FROM_STRAIN, strain[strain > 0].min()), force_to, FORCE_POINTS)
    s_pts = problem.h0 * (1.0 - np.exp(-targets))
    f_pts = np.interp(s_pts, stroke, inp.force)
    f_sigma = force_sigma_pct(targets, fold_over)  # each force point's σ, %

    # what is known of the shape rows beforehand (diameters, mm): resolution and the model form's share (another defensible
    # model's shape at the same law and μ, fe/model/model_form.py), in quadrature — the mesh's share alone let the end face, whose
    # rim corner the models place 0.01–0.02 d_n apart, pull μ 0.01–0.02 low on the second model's records (docs/methods.md §4a.7)
    hk = record.specimen.hk_mm or problem.h_end
    d_n = float(nominal_diameter(problem.d0, problem.h0, hk))
    shape_sigma = {"dmax": 2.0 * mf.bulge_sigma_mm(max(dmax - d_n, 0.0) / 2.0, DIAMETER_RESOLUTION_MM)}
    if dface is not None:
        shape_sigma["dface"] = mf.face_sigma(d_n, DIAMETER_RESOLUTION_MM) * d_n
    # E's uncertainty in the spring-back d·ν·σ/E of the model's diameters, in quadrature (σ = F/A at the end)
    E = inp.elastics.E_MPa
    springback_rel = 0.3 * float(np.max(inp.force)) / circle_area_mm2(d_n) / E * inp.elastics.E_stderr_MPa / E
    shape_sigma = {k: math.hypot(v, springback_rel * (dmax if k == "dmax" else dface)) for k, v in shape_sigma.items()}
    # every row in units of its own σ: the force rows' is pooled from their misfit for the covariance, the diameters' known
    row_sigma = np.array([np.nan] * FORCE_POINTS + [1.0] * len(shape_sigma))
    return _Rows(first, fold_over, targets, s_pts, f_pts, f_sigma, shape_sigma, row_sigma)


def _residuals(rows: _Rows, dmax: float, dface: float | None):
    """The residuals of a run: the force points' misfit in % over their σ, the diameters' in mm over theirs."""

    def residuals_of(out: _Run) -> np.ndarray:
        """Residuals of FE run ``out``: force % over the sigma, then the shape (dmax, dface) over theirs."""
        r_f = 100.0 * (np.interp(rows.s_pts, out.stroke_mm, out.force_N) - rows.f_pts) / rows.f_pts
        shape = [(out.dmax_unloaded_mm - dmax) / rows.shape_sigma["dmax"]]
        if dface is not None:
            shape.append((out.dface_unloaded_mm - dface) / rows.shape_sigma["dface"])
        return np.concatenate([r_f / rows.f_sigma, shape])

    return residuals_of


def _steps(x):
    """Finite-difference steps: :data:`REL_STEP` of each law constant, 0.005 of μ."""
    h = np.maximum(np.abs(x) * REL_STEP, 1e-6)
    h[-1] = 0.005
    return h


def _fit(inp: _Inputs, start: _Start, rows: _Rows, before: float, *, workers, scheduler, max_runs, progress, time_limit_s):
    """The least-squares fit with CalculiX in the loop, within what ``before`` (the fast identification, the closure, the
    warm start's run) left of the budget: a run still going at the time limit is stopped there (a batch's length is
    not known beforehand: where the side folds over its runs stop and are retried, and a tall record's first Jacobian
    ran 250 s past a mean of 90)."""
    x0 = start.x0
    fit_limit = fit_time_limit(time_limit_s, before)
    fit_problem = inp.problem if fit_limit is None else replace(inp.problem, deadline=time.time() + fit_limit)
    return fit_with_solver(partial(_run, fit_problem), _residuals(rows, inp.dmax, inp.dface), x0, start.lo, start.hi,
                           n_residuals=FORCE_POINTS + 1 + (inp.dface is not None), steps=_steps, x_scale=start.x_scale,
                           workers=workers, scheduler=scheduler, max_runs=max_runs,
                           progress=progress_on_whole_clock(progress, before, len(x0), time_limit_s),
                           other_starts=[np.append(x0[:-1], x0[-1] + dmu) for dmu in START_MU_STEPS], row_sigma=rows.row_sigma,
                           correlated=True, time_limit_s=fit_limit)


def _uncertainty(sol, rows: _Rows, x_scale):
    """(standard errors, what each side tells of μ, μ's standard error from the shape alone): the fit's, with the
    force's model-form share in quadrature, μ's no surer than the force's and the shape's estimates combined."""
    se = sol.stderr
    by_side = None
    if sol.jac is not None:  # the force's model-form share of the standard errors, in quadrature with the fit's (the shape's is in its σ)
        se = np.hypot(se, mf.force_model_form_stderr(sol.jac, np.arange(FORCE_POINTS), rows.targets, rows.f_sigma, float(sol.x[-1])))
        # what the force alone and the shape alone tell of μ (each with its model form, fe/force_shape.py)
        by_side = inverse_mu_by_side(sol.jac, sol.residuals, sol.x, rows.targets, rows.f_sigma, len(rows.shape_sigma), x_scale=x_scale)
        # μ is no surer than the two sides' estimates combined: the force rows' pooled σ (their misfit) let the fit's own
        # covariance read μ far surer than the models' force difference allows (docs/methods.md §4a.7)
        if np.isfinite(se[-1]):  # an undetermined μ stays so
            se[-1] = np.fmax(se[-1], by_side.combined_stderr)
    # what the shape alone tells of μ, beside what the fit tells with the force (information, not a bound: the force
    # curve's error is counted as serially correlated in the fit's covariance)
    shape_rows = list(range(FORCE_POINTS, len(rows.row_sigma)))
    mu_se_shape = sol.stderr_from_rows(len(sol.x) - 1, shape_rows, rows.row_sigma)
    return se, by_side, (mu_se_shape if np.isfinite(mu_se_shape) else None)


@dataclass(frozen=True)
class _Misfit:
    """The fitted model's misfit: force rows in %, their RMS, the diameters' in mm."""

    r_force: np.ndarray
    force_rms: float
    d_res_mm: float
    face_res_mm: float | None


def _misfit(sol, rows: _Rows, dface: float | None) -> _Misfit:
    r = sol.residuals
    r_force = r[:FORCE_POINTS] * rows.f_sigma
    return _Misfit(r_force, float(np.sqrt(np.mean(r_force**2))), float(r[FORCE_POINTS] * rows.shape_sigma["dmax"]),
                   float(r[FORCE_POINTS + 1] * rows.shape_sigma["dface"]) if dface is not None else None)


def _all_warnings(sol, se, misfit: _Misfit, rows: _Rows, law_keys, dface, time_limit_s) -> list[str]:
    """The fit's warnings: misfits, μ on a bound or poorly told, failed and undetermined runs, a cut."""
    mu, shape_sigma = float(sol.x[-1]), rows.shape_sigma
    warnings = _fit_warnings(misfit.force_rms, misfit.d_res_mm, mu, sol, shape_sigma["dmax"]) + sol.failed_runs_warnings() \
        + sol.undetermined_warnings([*law_keys, "μ"])
    warnings += sol.cut_warnings("inverse FE", time_limit_s)
    if misfit.face_res_mm is not None and poor_shape_misfit(misfit.face_res_mm, shape_sigma["dface"]):
        warnings.append(f"inverse FE: the fitted model misses the end face dface by {misfit.face_res_mm:+.3f} mm (its σ ± {shape_sigma['dface']:.3f} mm)")
    if se[-1] > MU_TOLD:  # NaN (undetermined) is warned above
        shape = "dmax and dface" if dface is not None else "dmax (the faces nearly stick; the original end face, post.dface_mm, would tell more)"
        known = " and ".join(f"{k} to ± {v:.3f} mm" for k, v in shape_sigma.items())
        warnings.append(f"inverse FE: μ {mu:.3f} ± {se[-1]:.3f} is poorly told by the force curve and {shape}: the model knows "
                        f"{known} (the resolution and the model form's share of the shape), and μ moves them little here")
    return warnings


def _budget(sol, rows: _Rows, inp: _Inputs, time_limit_s, wall: float) -> CompressionBudget:
    """result.json's ``inverse_fe.budget``: the limit, whether it cut the fit, what was fitted."""
    targets, fold_over, strain, dface = rows.targets, rows.fold_over, inp.strain, inp.dface
    done = (f"force fitted over strain {targets[0]:.3g}–{targets[-1]:.3g} of {strain.max():.3g} ("
            + (f"the side folds onto the platen from {fold_over:.3g} in the warm start's run" if fold_over is not None
               else "no fold-over in the warm start's run" if rows.first is not None else "the warm start's run failed")
            + f"); shape {', '.join(['dmax'] + (['dface'] if dface is not None else []))} at the end; {sol.runs} runs; "
            + ("cut by the time limit" if sol.cut else "converged or stopped by the optimiser"))
    return CompressionBudget(time_limit_s=time_limit_s, cut=sol.cut, solver_runs=sol.runs, wall_s=round(wall, 1), fold_over_strain=fold_over,
                             force_fitted_to_strain=float(targets[-1]), record_strain=float(strain.max()), done=done)


def _inverse_block(sol, se, mu_se_shape, misfit: _Misfit, rows: _Rows, inp: _Inputs, start: _Start, budget: CompressionBudget,
                   increments: int, wall: float) -> CompressionInverseFE:
    """result.json's ``inverse_fe`` block: μ and its standard errors, the misfits, the runs, the budget, the model."""
    law_info, dface, elastics = static_form(inp.problem.law), inp.dface, inp.elastics
    return CompressionInverseFE(
        law=inp.law_choice, mu=float(sol.x[-1]), mu_stderr=float(se[-1]), mu_stderr_shape_alone=mu_se_shape,
        force_residual_serial_correlation=serial_correlation(sol.residuals[:FORCE_POINTS]),
        shape_sigma_mm=rows.shape_sigma, solver_runs=sol.runs, failed_solver_runs=sol.failed_runs,
        retried_solver_runs=sol.retried_runs, solver_s=round(sol.solver_s, 1), wall_s=round(wall, 1),
        force_rms_residual_pct=misfit.force_rms, force_max_residual_pct=float(np.max(np.abs(misfit.r_force))),
        dmax_residual_mm=misfit.d_res_mm, dface_residual_mm=misfit.face_res_mm,  # None (not written) without dface
        shape_measured=["hk", "dmax"] + (["dface"] if dface is not None else []), optimizer=sol.optimizer(), budget=budget,
        warm_start={"mu": start.mu0, **{k: float(v) for k, v in zip(law_info.keys, start.p0)}},
        model={"increments": increments, **elastics.as_dict(), "diagram_options": inp.diagram_options, "h_end_mm": inp.problem.h_end,
               "force_points": FORCE_POINTS, "force_sigma_pct": FORCE_SIGMA_PCT, "force_sigma_pct_at_fold_over": float(rows.f_sigma[-1]),
               "from_strain": FROM_STRAIN})


def _assemble(inp: _Inputs, sol, se, by_side, block: CompressionInverseFE, misfit: _Misfit, rows: _Rows, warnings: list[str]) -> Identification:
    """The identification: the fast result with the inverse's law, μ and its block, the law's curve, the force rows."""
    law, law_info, fast, dface, elastics = inp.problem.law, static_form(inp.problem.law), inp.fast, inp.dface, inp.elastics
    e_hi = float(fast.result["hardening"]["strain_range"][1]) if fast.result.get("hardening") else float(inp.strain.max())
    hardening = InverseHardening(law, dict(zip(law_info.names, map(float, sol.x[:-1]))), {n: float(se[i]) for i, n in enumerate(law_info.names)},
                                 float(np.max(np.abs(misfit.r_force))), misfit.force_rms, [0.002, e_hi])
    grid = np.linspace(0.002, e_hi, 200)
    true_curve = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": hardening(grid)})
    if by_side is not None:  # the force and the shape apart beyond their combined se: a warning, poor
        found, warning = force_shape_check(by_side, "dmax and dface" if dface is not None else "dmax")
        block = replace(block, by_side=by_side, force_shape_check=found)
        warnings += [warning] if warning else []
    result = replace(fast.result, friction_mu=float(sol.x[-1]), friction_method="inverse_fe", friction_correction="inverse_fe",
                     hardening=hardening, inverse_fe=block,
                     dface_advice=DFACE_ADVICE if dface is None and not se[-1] <= MU_TOLD else None,  # the inverse judges μ itself
                     methods={**fast.result.methods, "inverse": "CalculiX upsetting in the loop (scipy least_squares), warm start: fast fe_table identification"})
    if elastics.E_source == "handbook" and inp.diagram_options.get("E_MPa"):  # a class's handbook value, not the fast's "option"
        result.E_MPa, result.E_source = elastics.E_MPa, f"handbook ({elastics.E_basis})"
    if warnings:
        result.warnings = [*result.warnings, *warnings]
        hardening.quality = "poor"
    curves = dict(fast.curves)
    curves["inverse_fe_force"] = pd.DataFrame({"specimen_displacement_mm": rows.s_pts, "force_N": rows.f_pts, "residual_pct": misfit.r_force})
    return Identification(result=result, true_curve=true_curve, curves=curves)


def identify_inverse_fe_compression(record, *, law: str = "auto", workers: int | None = None, scheduler=None, increments: int = 50,
                                    max_runs: int = 150, progress=None, E_MPa: float | None = None,
                                    time_limit_s: float | None | str = "default") -> Identification:
    """Fit a hardening law and μ to a compression record's force–stroke and dmax with CalculiX in the loop.

    The model's E and frame stiffness: :func:`.machine.model_elastics` (never an apparent slope).

    Parameters
    ----------
    record : Record
        A compression record with dmax measured.
    law : str
        A law name, or "auto": the law that best fits the fast curve (:func:`.law_choice.best_law_for`).
    workers, scheduler : optional
        Parallel CalculiX runs: local processes, or a Dask scheduler's address.
    increments, max_runs : int
        The model's load increments; the most solver runs.
    progress : callable, optional
        ``progress(runs, elapsed_s, left_s)``.
    E_MPa : float, optional
        Young's modulus, MPa.
    time_limit_s : float, None or "default"
        The wall-time budget, s (None: none; "default": :data:`TIME_LIMIT_S`).

    Returns
    -------
    Identification
        Whose result carries the ``inverse_fe`` block (docs/methods.md §4a.3).
    """
    check_law(law)
    time_limit_s = TIME_LIMIT_S if time_limit_s == "default" else time_limit_s
    if record.test != "compression":
        raise IdentificationError(f"{record.source}: the compression inverse FE needs a compression record (this is {record.test!r})")
    t0 = time.perf_counter()
    inp = _inputs(record, law, E_MPa, increments)
    start = _warm_start(inp)
    rows = _rows(record, inp, start.x0)
    before = time.perf_counter() - t0  # the fast identification, the closure, the warm start's run: the budget's and the progress's clock
    sol = _fit(inp, start, rows, before, workers=workers, scheduler=scheduler, max_runs=max_runs, progress=progress,
               time_limit_s=time_limit_s)
    se, by_side, mu_se_shape = _uncertainty(sol, rows, start.x_scale)
    wall = time.perf_counter() - t0
    misfit = _misfit(sol, rows, inp.dface)
    warnings = _all_warnings(sol, se, misfit, rows, static_form(inp.problem.law).keys, inp.dface, time_limit_s)
    block = _inverse_block(sol, se, mu_se_shape, misfit, rows, inp, start, _budget(sol, rows, inp, time_limit_s, wall), increments, wall)
    return _assemble(inp, sol, se, by_side, block, misfit, rows, warnings)

"""Inverse FE identification of compression: hardening law and μ with CalculiX in the loop.

The frame-corrected force–stroke curve of the record (the fast identification's
``corrected_diagram``) and the measured bulge diameter dmax are fitted by the upsetting model
(:mod:`.upsetting`) run to the record's shortening (so the final height hk is met by
construction; the FE dmax is taken after the elastic spring-back d·(1 − ν·σ/E), the unloading
run itself can fail with friction, CALCULIX.md): scipy ``least_squares`` over the hardening constants and μ, warm-started from
the fast (``fe_table``) identification. The Jacobian's finite-difference runs go side by side
(:func:`.pool.run_many`: ``workers`` processes or a Dask ``scheduler``); repeated parameter
sets come from the run cache. Residuals: force misfit in % at ``FORCE_POINTS`` strokes
(ε ≥ 0.02), and the dmax misfit in units of ``DMAX_SCALE_MM`` weighted by √(force points)
so the shape counts as much as the whole force curve. Uncertainties from (JᵀJ)⁻¹·s².
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from functools import partial

import numpy as np
import pandas as pd

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.solver_fit import fit_with_solver
from flowcurve.identification.fe.upsetting import PLASTIC_ROWS, UpsettingModel, simulate_upsetting
from flowcurve.identification.hardening import LAWS
from flowcurve.identification.outcome import Identification

log = logging.getLogger(__name__)

FORCE_POINTS = 30
DMAX_SCALE_MM = 0.005
FROM_STRAIN = 0.02
MU_BOUNDS = (0.0, 0.35)
REL_STEP = 0.01  # finite-difference step, relative (absolute 0.005 for μ)


@dataclass(frozen=True)
class _Problem:
    law: str
    d0: float
    h0: float
    h_end: float
    E: float
    increments: int


def _model(problem: _Problem, x) -> UpsettingModel:
    law = LAWS[problem.law]
    params = dict(zip(law.names, (float(v) for v in x[:-1])))
    eps = np.concatenate([[0.0], np.geomspace(1e-4, 2.0, PLASTIC_ROWS)])
    sig = law.func(eps, **params)
    return UpsettingModel(problem.d0, problem.h0, problem.h_end, float(x[-1]), tuple(map(float, eps)), tuple(map(float, sig)),
                          E_MPa=problem.E, increments=problem.increments)


@dataclass(frozen=True)
class _Run:
    stroke_mm: np.ndarray
    force_N: np.ndarray
    dmax_unloaded_mm: float
    wall_s: float
    cached: bool


def _run(problem: _Problem, x) -> _Run | None:
    """Stroke, force and unloaded dmax of one CalculiX run; None when it did not converge."""
    from flowcurve.identification.fe.ccx import SolverError

    try:
        r = simulate_upsetting(_model(problem, x))
    except SolverError as exc:
        log.info("inverse FE: run at %s failed (%s)", x, exc)
        return None
    # dmax is measured unloaded: elastic spring-back of the diameter, d·(1 − ν·σ/E), σ = F/A at the end
    sigma_end = r.force_N[-1] / (math.pi * problem.d0**2 * problem.h0 / (4.0 * r.height_mm[-1]))
    d_unloaded = float(r.dmax_mm[-1]) * (1.0 - r.model.nu * sigma_end / problem.E)
    return _Run(np.concatenate([[0.0], r.stroke_mm]), np.concatenate([[0.0], r.force_N]), d_unloaded, r.wall_s, r.cached)


def identify_inverse_fe(record, *, law: str = "johnson_cook", workers: int | None = None, scheduler=None, increments: int = 50,
                        max_runs: int = 150, progress=None) -> Identification:
    """Fit ``law`` and μ to the record's force–stroke and dmax with CalculiX in the loop (a tension
    record: the hardening beyond Fm, :func:`.inverse_tension.identify_inverse_fe_tension`)."""
    from flowcurve.identification.fe.verify import record_force_stroke

    if law not in LAWS:
        raise IdentificationError(f"unknown hardening law {law!r}; choose one of {', '.join(LAWS)}")
    if record.test == "tension":
        from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

        return identify_inverse_fe_tension(record, workers=workers, scheduler=scheduler, progress=progress, law=law)
    if record.test != "compression":
        raise IdentificationError(f"{record.source}: --method inverse-fe needs a compression or tension record (this is {record.test!r})")
    t0 = time.perf_counter()
    stroke, force, fast = record_force_stroke(record)
    d0 = record.positive("specimen.d0_mm", required=True)
    h0 = record.positive("specimen.h0_mm", required=True)
    dmax = record.positive("post.dmax_mm")
    if dmax is None:
        raise IdentificationError(f"{record.source}: --method inverse-fe needs the bulge diameter 'post.dmax_mm'")
    E = record.positive("material.E_MPa") or fast.result.get("E_MPa") or 200_000.0
    problem = _Problem(law, d0, h0, h0 - float(np.max(stroke)), float(E), increments)
    strain = -np.log(1.0 - stroke / h0)
    targets = np.linspace(max(FROM_STRAIN, strain[strain > 0].min()), strain.max(), FORCE_POINTS)
    s_pts = h0 * (1.0 - np.exp(-targets))
    f_pts = np.interp(s_pts, stroke, force)

    # warm start: the fast identification's law (refitted in the requested law when needed)
    law_info = LAWS[law]
    if fast.result["hardening"].get("law") == law:
        p0 = [fast.result["hardening"][k] for k in law_info.keys]
    else:
        from flowcurve.identification.hardening import fit_hardening

        tc = fast.true_curve
        p0 = [fit_hardening(tc["true_plastic_strain"].to_numpy(), tc["true_stress_MPa"].to_numpy(), law).params[n] for n in law_info.names]
    mu0 = float(np.clip(fast.result["friction_mu"], MU_BOUNDS[0] + 0.005, MU_BOUNDS[1] - 0.01))
    x0 = np.array([*map(float, p0), mu0])
    lo = np.array([law_info.bounds[n][0] for n in law_info.names] + [MU_BOUNDS[0]])
    hi = np.array([law_info.bounds[n][1] for n in law_info.names] + [MU_BOUNDS[1]])
    x0 = np.clip(x0, lo + 1e-9, np.where(np.isfinite(hi), hi - 1e-9, np.inf))

    w_d = math.sqrt(FORCE_POINTS)

    def residuals_of(out: _Run) -> np.ndarray:
        r_f = 100.0 * (np.interp(s_pts, out.stroke_mm, out.force_N) - f_pts) / f_pts
        return np.concatenate([r_f, [w_d * (out.dmax_unloaded_mm - dmax) / DMAX_SCALE_MM]])

    def steps(x):
        h = np.maximum(np.abs(x) * REL_STEP, 1e-6)
        h[-1] = 0.005
        return h

    x_scale = np.maximum(np.abs(x0), 1e-3)
    x_scale[-1] = 0.05
    sol = fit_with_solver(partial(_run, problem), residuals_of, x0, lo, hi, n_residuals=FORCE_POINTS + 1, steps=steps,
                          x_scale=x_scale, workers=workers, scheduler=scheduler, max_runs=max_runs, progress=progress)
    r, se = sol.residuals, sol.stderr
    params = dict(zip(law_info.names, map(float, sol.x[:-1])))
    mu = float(sol.x[-1])
    wall = time.perf_counter() - t0
    force_rms = float(np.sqrt(np.mean(r[:-1] ** 2)))
    d_res_mm = float(r[-1] / w_d * DMAX_SCALE_MM)

    e_hi = float(fast.result["hardening"]["strain_range"][1]) if fast.result.get("hardening") else float(strain.max())
    grid = np.linspace(0.002, e_hi, 200)
    true_curve = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": law_info.func(grid, **params)})
    hardening = {"law": law, "method": "inverse_fe", **{k: params[n] for n, k in zip(law_info.names, law_info.keys)},
                 **{f"{k}_stderr": float(se[i]) for i, k in enumerate(law_info.keys)},
                 "fit_error_pct": float(np.max(np.abs(r[:-1]))), "rms_error_pct": force_rms, "strain_range": [0.002, e_hi]}
    result = dict(fast.result)
    result.update({
        "friction_mu": mu, "friction_method": "inverse_fe", "friction_correction": "inverse_fe",
        "hardening": hardening,
        "inverse_fe": {
            "mu": mu, "mu_stderr": float(se[-1]), "solver_runs": sol.runs, "solver_s": round(sol.solver_s, 1),
            "wall_s": round(wall, 1), "force_rms_residual_pct": force_rms, "force_max_residual_pct": float(np.max(np.abs(r[:-1]))),
            "dmax_residual_mm": d_res_mm, "optimizer": sol.optimizer(),
            "warm_start": {"mu": mu0, **{k: float(v) for k, v in zip(law_info.keys, p0)}},
            "model": {"increments": increments, "E_MPa": float(E), "h_end_mm": problem.h_end, "force_points": FORCE_POINTS,
                      "dmax_scale_mm": DMAX_SCALE_MM, "from_strain": FROM_STRAIN},
        },
    })
    result["methods"] = {**result.get("methods", {}), "inverse": "CalculiX upsetting in the loop (scipy least_squares), warm start: fast fe_table identification"}
    curves = dict(fast.curves)
    curves["inverse_fe_force"] = pd.DataFrame({"specimen_displacement_mm": s_pts, "force_N": f_pts, "residual_pct": r[:-1]})
    return Identification(result=result, true_curve=true_curve, curves=curves)

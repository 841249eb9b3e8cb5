"""Inverse FE identification of tension beyond the maximum force: the necking range in CalculiX.

Up to the maximum force the true curve is measured directly; beyond it the section is no
longer uniform, and the neck corrections (Davidenkov, Bridgman, Mirone) estimate the flow
stress at one point, the fracture, from a/R. Here the hardening beyond the uniform range is
found instead by running the CAX8R necking model (:mod:`.tension`) and matching the record's
frame-corrected force–elongation curve from Fm to fracture and the measured neck diameter dk:

* uniform range: the record's own true curve up to Rm (averaged onto the *PLASTIC rows);
* beyond ε_pu (the plastic strain at Rm): σ = σ_u + H·(1 − exp(−b·(ε_p − ε_pu)))/b, the
  initial slope H and its decay b fitted (b → 0: linear hardening; large b: saturation). The
  warm start is Considère's H = σ_u (dσ/dε = σ at the maximum force) and b = 1.

Residuals: force misfit in % at ``FORCE_POINTS`` elongations between Fm and fracture, and
the neck radius misfit in units of ``NECK_SCALE_MM`` weighted by √(force points). The result
carries the FE-consistent flow curve to the fracture strain, the law refitted to it, and the
neck corrections' fracture stresses against the FE one.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import partial

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.solver_fit import fit_with_solver
from flowcurve.identification.fe.upsetting import PLASTIC_ROWS
from flowcurve.identification.outcome import Identification

log = logging.getLogger(__name__)

FORCE_POINTS = 20
NECK_SCALE_MM = 0.01
UNIFORM_ROWS = 20  # rows of the measured uniform curve in the *PLASTIC table
B_BOUNDS = (1e-3, 60.0)
REL_STEP = 0.02  # finite-difference step, relative
INCREMENTS = 100  # CAX8R 8×30 with 0.01 increments: force and neck within 0.35 % of converged (tension.py)


def extended_curve(eps_p, uniform_eps_p, uniform_stress_MPa, H_MPa: float, b: float):
    """The measured uniform curve up to its end ε_pu, then σ_u + H·(1 − e^(−b·(ε_p − ε_pu)))/b."""
    e = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
    eps_pu, sigma_u = float(uniform_eps_p[-1]), float(uniform_stress_MPa[-1])
    d = np.clip(e - eps_pu, 0.0, None)
    beyond = sigma_u + H_MPa * (-np.expm1(-b * d)) / b
    return np.where(e <= eps_pu, np.interp(e, uniform_eps_p, uniform_stress_MPa), beyond)


@dataclass(frozen=True)
class _Problem:
    d0: float
    l0: float
    elongation: float  # the record's elongation at fracture: the FE run goes this far
    E: float
    uniform_eps_p: tuple  # the measured uniform curve on a few rows, ending at ε_pu
    uniform_stress_MPa: tuple
    increments: int


@dataclass(frozen=True)
class _Run:
    elongation_mm: np.ndarray
    force_N: np.ndarray
    neck_radius_mm: np.ndarray
    wall_s: float
    cached: bool


def plastic_rows(problem: _Problem, H_MPa: float, b: float) -> tuple[tuple, tuple]:
    """*PLASTIC rows of the extended curve: the uniform rows, then a geometric spacing to 2."""
    ue = np.asarray(problem.uniform_eps_p)
    beyond = ue[-1] + np.geomspace(1e-3, 2.0, PLASTIC_ROWS - ue.size)
    eps = np.concatenate([ue, beyond])
    sig = extended_curve(eps, ue, problem.uniform_stress_MPa, H_MPa, b)
    return tuple(map(float, eps)), tuple(map(float, sig))


def _run(problem: _Problem, x) -> _Run | None:
    """Force, elongation and neck radius of one CalculiX necking run; None when it failed."""
    from flowcurve.identification.fe.ccx import SolverError
    from flowcurve.identification.fe.tension import TensionModel, simulate_tension

    eps, sig = plastic_rows(problem, float(x[0]), float(x[1]))
    try:
        r = simulate_tension(TensionModel(problem.d0, problem.l0, problem.elongation, eps, sig, E_MPa=problem.E, increments=problem.increments))
    except SolverError as exc:
        log.info("inverse FE tension: run at (H, b) = %s failed (%s)", x, exc)
        return None
    return _Run(np.concatenate([[0.0], r.elongation_mm]), np.concatenate([[0.0], r.force_N]),
                np.concatenate([[problem.d0 / 2.0], r.neck_radius_mm]), r.wall_s, r.cached)


def _necking_range(fast) -> tuple[np.ndarray, np.ndarray, int, int]:
    """(elongation, force, index of Fm, index of the last sample before fracture)."""
    from flowcurve.identification import iso6892

    diagram = fast.curves["corrected_diagram"]
    elong = diagram["elongation_mm"].to_numpy(dtype=float)
    force = diagram["force_N"].to_numpy(dtype=float)
    return elong, force, int(iso6892.max_force_index(force)), int(iso6892.fracture_index(force))


def identify_inverse_fe_tension(record, *, workers: int | None = None, scheduler=None, increments: int = INCREMENTS,
                                max_runs: int = 40, progress=None, **tension_options) -> Identification:
    """The hardening beyond the maximum force, fitted to the record's necking range with CalculiX."""
    import time

    import pandas as pd

    from flowcurve.identification.hardening import fit_hardening
    from flowcurve.identification.tension import identify_tension, reaches_fracture

    t0 = time.perf_counter()
    fast = identify_tension(record, **tension_options)
    res = fast.result
    elong, force, i_m, i_k = _necking_range(fast)
    if not reaches_fracture(force):
        raise IdentificationError(f"{record.source}: --method inverse-fe needs a tension record that reaches fracture (the necking range is what it fits)")
    if i_k - i_m < 5:
        raise IdentificationError(f"{record.source}: only {i_k - i_m} samples between Fm and fracture; the necking range is too short for --method inverse-fe")
    dk = record.positive("post.dk_mm")
    d0 = record.positive("specimen.d0_mm", required=True)
    l0 = float(res["methods"]["strain_length_mm"])
    E = record.positive("material.E_MPa") or res.get("E_MPa") or 200_000.0

    # the uniform range: the record's true curve, averaged onto UNIFORM_ROWS rows ending at ε_pu
    uni = fast.curves["true"]
    ep_u, sig_u = uni["true_plastic_strain"].to_numpy(dtype=float), uni["true_stress_MPa"].to_numpy(dtype=float)
    eps_pu = float(res["uniform_true_plastic_strain"])
    sel = (ep_u >= 0.0) & (ep_u <= eps_pu)
    if sel.sum() < UNIFORM_ROWS:
        raise IdentificationError(f"{record.source}: only {int(sel.sum())} samples in the uniform range; --method inverse-fe needs {UNIFORM_ROWS}")
    ep_s, sig_s = ep_u[sel], sig_u[sel]
    edges = np.concatenate([[0.0], np.geomspace(max(1e-4, eps_pu / 300.0), eps_pu, UNIFORM_ROWS)])
    rows_e, rows_s = [0.0], [float(np.median(sig_s[ep_s <= max(edges[1], ep_s.min())]))]
    for lo, hi in zip(edges[1:-1], edges[2:]):
        inside = (ep_s > lo) & (ep_s <= hi)
        if inside.any():
            rows_e.append(float(ep_s[inside].mean()))
            rows_s.append(float(sig_s[inside].mean()))
    rows_s = list(np.maximum.accumulate(rows_s))  # *PLASTIC must not soften in the uniform range
    rows_e[-1] = eps_pu
    problem = _Problem(float(d0), l0, float(elong[i_k]), float(E), tuple(rows_e), tuple(rows_s), increments)
    sigma_u = rows_s[-1]

    e_pts = np.linspace(elong[i_m], elong[i_k], FORCE_POINTS + 1)[1:]
    f_pts = np.interp(e_pts, elong[: i_k + 1], force[: i_k + 1])
    w_neck = math.sqrt(FORCE_POINTS) if dk is not None else 0.0

    def residuals_of(out: _Run) -> np.ndarray:
        r_f = 100.0 * (np.interp(e_pts, out.elongation_mm, out.force_N) - f_pts) / f_pts
        a_end = float(np.interp(problem.elongation, out.elongation_mm, out.neck_radius_mm))
        return np.concatenate([r_f, [w_neck * (a_end - (dk or 0.0) / 2.0) / NECK_SCALE_MM]])

    x0 = np.array([sigma_u, 1.0])  # Considère: dσ/dε_p = σ at the maximum force
    lo, hi = np.array([0.0, B_BOUNDS[0]]), np.array([10.0 * sigma_u, B_BOUNDS[1]])
    sol = fit_with_solver(partial(_run, problem), residuals_of, x0, lo, hi, n_residuals=FORCE_POINTS + 1,
                          steps=lambda x: np.maximum(np.abs(x) * REL_STEP, 1e-3), x_scale=np.array([sigma_u, 1.0]),
                          workers=workers, scheduler=scheduler, max_runs=max_runs, xtol=1e-3, ftol=1e-4, progress=progress,
                          what="inverse FE (tension)")
    (H, b), (H_se, b_se) = map(float, sol.x), map(float, sol.stderr)
    r = sol.residuals
    on_bound = [name for name, v, l_, h_ in zip(("H", "b"), sol.x, lo, hi) if v <= l_ + 1e-9 or v >= h_ - 1e-9]
    res_warning = f"inverse FE: {', '.join(on_bound)} on a bound; the necking range may not be matched" if on_bound else None
    if float(np.max(np.abs(r[:-1]))) > 5.0:
        res_warning = (res_warning + "; " if res_warning else "inverse FE: ") + f"force residual up to {float(np.max(np.abs(r[:-1]))):.1f} % beyond Fm"

    eps_f = res.get("fracture_true_strain")
    e_end = float(eps_f) if eps_f is not None else 1.5 * eps_pu
    grid = np.linspace(0.002, e_end, 200)
    flow = extended_curve(grid, rows_e, rows_s, H, b)
    true_curve = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": flow})
    law = res["hardening"].get("law") or "swift"
    refit = fit_hardening(grid, flow, law)
    fe_fracture = float(extended_curve(e_end, rows_e, rows_s, H, b)) if eps_f is not None else None
    necks = {m: {"stress_MPa": v["stress_MPa"], "vs_fe_pct": 100.0 * (v["stress_MPa"] / fe_fracture - 1.0)}
             for m, v in (res.get("neck_corrections") or {}).items() if isinstance(v, dict) and fe_fracture}
    warnings = list(res.get("warnings", []))
    if res_warning:
        warnings.append(res_warning)
    warnings += sol.undetermined_warnings(["H", "b"], "inverse FE (tension)")
    if dk is None:
        warnings.append("inverse FE: no post.dk_mm: only the force beyond Fm is fitted, not the neck diameter")

    result = dict(res)
    result["hardening_alternatives"] = {**res.get("hardening_alternatives", {}), "fast": res["hardening"]}
    result["hardening"] = {**refit.as_dict(), "method": "inverse_fe", "fitted_to": "the FE-consistent flow curve (measured uniform range, CalculiX necking range)",
                           "strain_range": [0.002, e_end]}
    result["fracture_true_stress_MPa"] = fe_fracture if fe_fracture is not None else res.get("fracture_true_stress_MPa")
    result["warnings"] = warnings
    result["inverse_fe"] = {
        "H_MPa": H, "H_MPa_stderr": H_se, "b": b, "b_stderr": b_se, "sigma_u_MPa": sigma_u,
        "uniform_rows": {"true_plastic_strain": rows_e, "true_stress_MPa": rows_s},
        "uniform_true_plastic_strain": eps_pu, "fracture_true_stress_MPa": fe_fracture, "neck_corrections_vs_fe": necks,
        "solver_runs": sol.runs, "solver_s": round(sol.solver_s, 1), "wall_s": round(time.perf_counter() - t0, 1),
        "force_rms_residual_pct": float(np.sqrt(np.mean(r[:-1] ** 2))), "force_max_residual_pct": float(np.max(np.abs(r[:-1]))),
        "neck_radius_residual_mm": float(r[-1] / w_neck * NECK_SCALE_MM) if dk is not None else None,
        "optimizer": sol.optimizer(), "warm_start": {"H_MPa": float(x0[0]), "b": float(x0[1])},
        "model": {"elements": "CAX8R 8x30 quarter model", "increments": increments, "E_MPa": float(E), "l0_mm": l0,
                  "elongation_mm": problem.elongation, "force_points": FORCE_POINTS, "neck_scale_mm": NECK_SCALE_MM},
    }
    result["methods"] = {**res.get("methods", {}), "inverse": "CalculiX necking (CAX8R) in the loop beyond Fm (scipy least_squares), uniform range measured"}
    curves = dict(fast.curves)
    curves["inverse_fe_force"] = pd.DataFrame({"elongation_mm": e_pts, "force_N": f_pts, "residual_pct": r[:-1]})
    curves["fit"] = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": refit(grid)})
    return Identification(result=result, true_curve=true_curve, curves=curves)

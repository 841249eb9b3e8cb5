"""Inverse FE identification of tension beyond the maximum force: the necking range in CalculiX.

Fits the CAX8R necking model (:mod:`.model.tension`) to the record's frame-corrected
force–elongation curve and the neck diameter dk. Law: the measured true curve up to
ε_a = ``UNIFORM_FRACTION``·ε_pu; beyond it σ = σ_a + ∫ H·(1 + β·c·x)^(−1/c) dx
(:func:`hardening_beyond`: c = 0 Voce, c = 1/(1 − n) Swift); the taper δ that starts the neck,
r(z) = R·(1 − δ·cos(πz/l0)), is fitted too. Residuals: the force misfit in units of
``FORCE_SIGMA_PCT`` at ``FORCE_POINTS_UNIFORM`` + ``FORCE_POINTS`` elongations, the neck radius
in units of its σ. Returns the FE-consistent flow curve to fracture, the law refitted to it and
the neck corrections' fracture stresses beside the FE one. Method and measured history:
docs/methods.md §4a.4.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace
from functools import partial
from typing import Any

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.elastic_modulus import modulus_for_model
from flowcurve.identification.fe.law_choice import best_law_for
from flowcurve.identification.fe.solver_fit import fit_time_limit, fit_with_solver, progress_on_whole_clock, serial_correlation
from flowcurve.identification.fe.model.deck import PLASTIC_ROWS
from flowcurve.identification.laws.hardening import fit_hardening
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import InverseBudget, TensionInverseFE, TensionInverseHardening

log = logging.getLogger(__name__)

FORCE_POINTS = 20  # from Fm to fracture
FORCE_POINTS_UNIFORM = 10  # from ε_a to Fm
FORCE_SIGMA_PCT = 0.35  # the model's own force error: 8×30, 0.01 increments within 0.35 % of converged (tension.py)
NECK_RESOLUTION_MM = 0.005  # a caliper's 0.01 mm on the diameter, on the radius
NECK_MESH_MM = 0.004  # the mesh's share on the radius: twice the 2 µm of 8×30 against 10×40 (same law and taper, Voce; stop 26)
UNIFORM_FRACTION = 0.5  # the measured curve is used up to this fraction of ε_pu
UNIFORM_ROWS = 20  # rows of the measured uniform curve in the *PLASTIC table
FAMILY_LO = (0.0, 1e-2, 0.0)  # H (MPa), β, c of hardening_beyond (c = 0, Voce, is a law, not a limit of the search)
FAMILY_HI = (1e6, 1e3, 10.0)
TAPER_BOUNDS = (5e-4, 0.02)  # δ: 0.05–2 % of the radius
TAPER_START = 0.005  # the model's default (tension.py)
START_LAWS = ("johnson_cook", "swift", "voce")  # warm starts: each fitted on the uniform range, extrapolated
POOR_FORCE_RMS_PCT = 1.0  # the fitted model's force misfit beyond this (RMS; measured 0.07–0.12 %): a warning
LAW_RMS_WARN_PCT = 1.0  # a chosen law this far from the FE-consistent curve (RMS), with a better one within it: say so
TAPER_STEP = 2.5e-4  # finite-difference step of δ, absolute
REL_STEP = 0.02  # finite-difference step of H, β and c, relative
INCREMENTS = 100  # CAX8R 8×30 with 0.01 increments: force and neck within 0.35 % of converged (tension.py)
# the default wall-time budget, s (--time-limit; a fit it cuts ends with its best run so far), set not to cut a normal run:
# bench/inverse_fe_tension.py's Swift record took 18 runs, 328 s on 2 workers, empty cache, load average 4–6 (18 s a run);
# §4a.4's records took up to 42 runs (229 s on an idle machine), 765 s at that loaded rate
TIME_LIMIT_S = 900.0


def hardening_beyond(d, H_MPa, beta, c):
    """∫₀^d H·(1 + β·c·x)^(−1/c) dx: the stress gained d beyond ε_a with the slope decaying from H.

    β is the slope's initial relative decay, c the shape of its tail: c = 0 is Voce's exponential
    H·e^(−β·d); c = 1/(1 − n) with β = (1 − n)/(ε0 + ε_a) is Swift's K·(ε0 + ε)^n from ε_a; c = 1
    the logarithm. One family, continuous in c, for hardening that saturates and hardening that
    does not (within 0.01 % of Voce, Swift and Johnson–Cook curves from ε_pu/2 to fracture).
    """
    # u = ln(1 + β·c·d)/c (→ β·d as c → 0); ∫ = H·(e^((c − 1)·u) − 1)/(β·(c − 1)) (→ H·u/β as c → 1)
    d, H, beta, c = (np.asarray(v, float) for v in (d, H_MPa, beta, c))
    small = c < 1e-9
    u = np.where(small, beta * d, np.log1p(beta * np.where(small, 1.0, c) * d) / np.where(small, 1.0, c))
    k = c - 1.0
    near_log = np.abs(k * u) < 1e-9
    return H * np.where(near_log, u, np.expm1(np.where(near_log, 0.0, k) * u) / np.where(near_log, 1.0, k)) / beta


def extended_curve(eps_p, uniform_eps_p, uniform_stress_MPa, H_MPa, beta, c):
    """The measured curve up to its end ε_a, then σ_a + :func:`hardening_beyond` (ε_p − ε_a)."""
    e = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
    eps_a, sigma_a = float(uniform_eps_p[-1]), float(uniform_stress_MPa[-1])
    beyond = sigma_a + hardening_beyond(np.clip(e - eps_a, 0.0, None), H_MPa, beta, c)
    return np.where(e <= eps_a, np.interp(e, uniform_eps_p, uniform_stress_MPa), beyond)


def uniform_rows(eps_p, stress_MPa, eps_end: float, rows: int = UNIFORM_ROWS) -> tuple[list, list]:
    """The measured curve on about ``rows`` *PLASTIC rows ending at (ε_end, σ(ε_end)).

    Bins geometric in ε_p; each row is its bin's mean (ε_p, σ), which a locally straight curve
    passes through. The end row's σ is a quadratic fit of the last bin's samples taken at ε_end:
    the bin's mean placed at ε_end (as this did up to stop 25) reads σ low by the slope times the
    bin's half width — 2.4 % on a Voce curve at ε 0.19, which the fit of the necking range then
    took up in H and b.
    """
    ep, sig = np.asarray(eps_p, float), np.asarray(stress_MPa, float)
    edges = np.concatenate([[0.0], np.geomspace(max(1e-4, eps_end / 300.0), eps_end, rows)])
    rows_e, rows_s = [0.0], [float(np.median(sig[ep <= max(edges[1], ep.min())]))]
    for lo, hi in zip(edges[1:-1], edges[2:]):
        inside = (ep > lo) & (ep <= hi)
        if inside.any():
            rows_e.append(float(ep[inside].mean()))
            rows_s.append(float(sig[inside].mean()))
    last = ep > edges[-2]
    if last.sum() >= 5:  # σ at ε_end: the last bin's quadratic (a straight line on few samples) at its end
        sigma_end = float(np.polyfit(ep[last] - eps_end, sig[last], 2 if last.sum() >= 10 else 1)[-1])
    else:
        sigma_end = rows_s[-1]
    if rows_e[-1] >= eps_end:
        del rows_e[-1], rows_s[-1]
    rows_e.append(float(eps_end))
    rows_s.append(sigma_end)
    return rows_e, list(map(float, np.maximum.accumulate(rows_s)))  # *PLASTIC must not soften in the measured range


@dataclass(frozen=True)
class _Problem:
    d0: float
    l0: float
    elongation: float  # the record's elongation at fracture: the FE run goes this far
    E: float
    uniform_eps_p: tuple  # the measured curve on a few rows, ending at ε_a
    uniform_stress_MPa: tuple
    increments: int
    deadline: float | None = None  # wall clock (time.time()) by which a run must end: it is stopped there (the time limit)


@dataclass(frozen=True)
class _Run:
    elongation_mm: np.ndarray
    force_N: np.ndarray
    neck_radius_mm: np.ndarray
    wall_s: float
    cached: bool


def plastic_rows(problem: _Problem, H_MPa: float, beta: float, c: float) -> tuple[tuple, tuple]:
    """*PLASTIC rows of the extended curve: the uniform rows, then a geometric spacing to 2."""
    ue = np.asarray(problem.uniform_eps_p)
    beyond = ue[-1] + np.geomspace(1e-3, 2.0, PLASTIC_ROWS - ue.size)
    eps = np.concatenate([ue, beyond])
    sig = extended_curve(eps, ue, problem.uniform_stress_MPa, H_MPa, beta, c)
    return tuple(map(float, eps)), tuple(map(float, sig))


def _run(problem: _Problem, x) -> _Run | None:
    """Force, elongation and neck radius of one CalculiX necking run at x = (H, β, c, δ); None when it
    failed, or when the problem's deadline stopped it or came before it (:func:`.ccx.timeout_by`)."""
    from flowcurve.identification.fe.model.ccx import SolverError, timeout_by
    from flowcurve.identification.fe.model.tension import TensionModel, simulate_tension

    eps, sig = plastic_rows(problem, float(x[0]), float(x[1]), float(x[2]))
    timeout_s = timeout_by(problem.deadline)
    if timeout_s is None:  # the time limit has come: no run (the fit ends with its best so far)
        log.info("inverse FE tension: run at (H, β, c, taper) = %s not started: the time limit has come", x)
        return None
    try:
        r = simulate_tension(TensionModel(problem.d0, problem.l0, problem.elongation, eps, sig, E_MPa=problem.E,
                                          imperfection=float(x[3]), increments=problem.increments), timeout_s=timeout_s)
    except SolverError as exc:
        log.info("inverse FE tension: run at (H, β, c, taper) = %s failed (%s)", x, exc)
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


def fracture_stress_stderr(covariance, x, strain_beyond: float) -> float | None:
    """The standard error of σ_a + :func:`hardening_beyond` at d = ε_f − ε_a from the (H, β, c)
    block of the fit's covariance (σ_a, measured, held): √(gᵀ·C·g), g by central differences."""
    if covariance is None:
        return None
    c = np.asarray(covariance, float)[:3, :3]
    if not np.all(np.isfinite(c)):
        return None
    x = np.asarray(x, float)[:3]
    g = np.empty(3)
    for k in range(3):
        h = 1e-6 * max(abs(x[k]), 1e-3)
        up, down = x.copy(), x.copy()
        up[k] += h
        down[k] -= h
        g[k] = (hardening_beyond(strain_beyond, *up) - hardening_beyond(strain_beyond, *down)) / (2.0 * h)
    return float(math.sqrt(max(float(g @ c @ g), 0.0)))


def family_start(eps_p, stress_MPa, eps_a: float, sigma_a: float) -> tuple[float, float, float]:
    """(H, β, c) of :func:`hardening_beyond` nearest a curve beyond ε_a (least squares in %)."""
    from scipy.optimize import least_squares

    e, s = np.asarray(eps_p, float), np.asarray(stress_MPa, float)
    keep = e > eps_a
    d, s = e[keep] - eps_a, s[keep]
    slope0 = max(float((s[0] - sigma_a) / d[0]) if d.size and d[0] > 0 else sigma_a, 1.0)
    sol = least_squares(lambda x: (sigma_a + hardening_beyond(d, *x)) / s - 1.0, [slope0, 1.0 / max(eps_a, 1e-3), 1.0],
                        bounds=(FAMILY_LO, FAMILY_HI), x_scale=[slope0, 1.0 / max(eps_a, 1e-3), 1.0])
    return tuple(map(float, sol.x))


@dataclass(frozen=True)
class _Inputs:
    """What the tension inverse reads before its fit: the fast identification, the necking range, the measured rows."""

    fast: Any  # the fast identification (its result is the inverse's base)
    elong: np.ndarray  # the frame-corrected diagram
    force: np.ndarray
    i_m: int  # Fm
    i_k: int  # the last sample before fracture
    dk: float | None
    l0: float
    E_source: str
    ep_u: np.ndarray  # the record's true curve
    sig_u: np.ndarray
    eps_pu: float
    eps_a: float
    rows_e: list  # the measured curve on UNIFORM_ROWS rows, ending at ε_a
    rows_s: list
    problem: _Problem


def _inputs(record, increments: int, tension_options: dict) -> _Inputs:
    """The fast identification, the necking range (Fm to fracture), and the record's true curve up to ε_a averaged
    onto UNIFORM_ROWS rows; an error naming what is missing when the record cannot be fitted."""
    from flowcurve.identification.tension.identify import identify_tension, reaches_fracture

    fast = identify_tension(record, **tension_options)
    res = fast.result
    elong, force, i_m, i_k = _necking_range(fast)
    if not reaches_fracture(force):
        raise IdentificationError(f"{record.source}: --method inverse-fe needs a tension record that reaches fracture (the necking range is what it fits)")
    if i_k - i_m < 5:
        raise IdentificationError(f"{record.source}: only {i_k - i_m} samples between Fm and fracture; the necking range is too short for --method inverse-fe")
    dk, d0 = record.specimen.dk_mm, record.specimen.d0_mm
    l0 = float(res["methods"]["strain_length_mm"])
    E, E_source = modulus_for_model(record, res, tension_options.get("E_MPa"), what="the inverse FE model")  # never an apparent slope

    # the measured range: the record's true curve up to ε_a, averaged onto UNIFORM_ROWS rows
    uni = fast.curves["true"]
    ep_u, sig_u = uni["true_plastic_strain"].to_numpy(dtype=float), uni["true_stress_MPa"].to_numpy(dtype=float)
    eps_pu = float(res["uniform_true_plastic_strain"])
    eps_a = UNIFORM_FRACTION * eps_pu
    sel = (ep_u >= 0.0) & (ep_u <= eps_a)
    if sel.sum() < UNIFORM_ROWS:
        raise IdentificationError(f"{record.source}: only {int(sel.sum())} samples up to ε_p {eps_a:.3g} ({UNIFORM_FRACTION:g} of the uniform "
                                  f"range); --method inverse-fe needs {UNIFORM_ROWS}")
    rows_e, rows_s = uniform_rows(ep_u[sel], sig_u[sel], eps_a)
    problem = _Problem(float(d0), l0, float(elong[i_k]), float(E), tuple(rows_e), tuple(rows_s), increments)
    return _Inputs(fast, elong, force, i_m, i_k, dk, l0, E_source, ep_u, sig_u, eps_pu, eps_a, rows_e, rows_s, problem)


@dataclass(frozen=True)
class _Rows:
    """The fit's rows: force points ε_a to Fm, then Fm to fracture (elongation mm, force N), the neck radius's σ."""

    e_pts: np.ndarray
    f_pts: np.ndarray
    neck_sigma: float
    row_sigma: np.ndarray

    @property
    def n_force(self) -> int:
        """The number of force residuals."""
        return self.e_pts.size


def _rows(inp: _Inputs) -> _Rows:
    """Force points from ε_a to Fm and from Fm to fracture (the elongation at ε_a from its log strain) and the rows' σ."""
    elong, force, i_m, i_k = inp.elong, inp.force, inp.i_m, inp.i_k
    true_strain = inp.fast.curves["true"]["true_strain"].to_numpy(dtype=float)
    e_a = inp.l0 * math.expm1(float(true_strain[int(np.argmax(inp.ep_u >= inp.eps_a))]))
    e_pts = np.concatenate([np.linspace(e_a, elong[i_m], FORCE_POINTS_UNIFORM + 1)[1:],
                            np.linspace(elong[i_m], elong[i_k], FORCE_POINTS + 1)[1:]])
    f_pts = np.interp(e_pts, elong[: i_k + 1], force[: i_k + 1])
    row_sigma = np.array([np.nan] * e_pts.size + ([1.0] if inp.dk is not None else []))
    return _Rows(e_pts, f_pts, math.hypot(NECK_RESOLUTION_MM, NECK_MESH_MM), row_sigma)


def _residuals(rows: _Rows, dk: float | None, elongation: float):
    """The residuals of a run: the force points' misfit in % over FORCE_SIGMA_PCT, the neck radius's in mm over its σ."""

    def residuals_of(out: _Run) -> np.ndarray:
        """Residuals of FE run ``out``: force % over the sigma, then dk over its sigma."""
        r_f = 100.0 * (np.interp(rows.e_pts, out.elongation_mm, out.force_N) - rows.f_pts) / rows.f_pts / FORCE_SIGMA_PCT
        if dk is None:
            return r_f
        a_end = float(np.interp(elongation, out.elongation_mm, out.neck_radius_mm))
        return np.concatenate([r_f, [(a_end - dk / 2.0) / rows.neck_sigma]])

    return residuals_of


@dataclass(frozen=True)
class _Starts:
    """The warm starts by law, the bounds of (H, β, c, δ) and the strain the curve is carried to."""

    starts: dict
    lo: np.ndarray
    hi: np.ndarray
    e_end: float  # the fracture strain (1.5·ε_pu without one)
    sigma_u: float


def _warm_starts(record, inp: _Inputs) -> _Starts:
    """The family nearest each law fitted on the measured uniform range and extrapolated to fracture (they part beyond
    Fm: a saturating law against a power law); all run at once, the fit starts from the best."""
    ep_u, sig_u, eps_pu, eps_a = inp.ep_u, inp.sig_u, inp.eps_pu, inp.eps_a
    sigma_u = float(np.interp(eps_pu, ep_u, sig_u))
    eps_f = inp.fast.result.get("fracture_true_strain")
    e_end = float(eps_f) if eps_f is not None else 1.5 * eps_pu
    uniform_in = (ep_u > 0.002) & (ep_u <= eps_pu)
    reach = np.linspace(eps_a, e_end, 60)
    lo = np.array([*FAMILY_LO, TAPER_BOUNDS[0]])
    hi = np.array([20.0 * sigma_u, *FAMILY_HI[1:], TAPER_BOUNDS[1]])
    starts = {}
    for start_law in START_LAWS:
        try:
            law_fit = fit_hardening(ep_u[uniform_in], sig_u[uniform_in], start_law)
        except IdentificationError as exc:
            log.info("inverse FE tension: no %s warm start (%s)", start_law, exc)
            continue
        starts[start_law] = np.clip([*family_start(reach, law_fit(reach), eps_a, inp.rows_s[-1]), TAPER_START], lo + 1e-9, hi - 1e-9)
    if not starts:
        raise IdentificationError(f"{record.source}: no hardening law fits the uniform range; --method inverse-fe has no warm start")
    return _Starts(starts, lo, hi, e_end, sigma_u)


def _steps(x):
    """Finite-difference steps: :data:`REL_STEP` of H, β and c, :data:`TAPER_STEP` of δ."""
    h = np.maximum(np.abs(x) * REL_STEP, 1e-3)
    h[3] = TAPER_STEP
    return h


def _fit(inp: _Inputs, st: _Starts, rows: _Rows, before: float, *, workers, scheduler, max_runs, progress, time_limit_s):
    """The least-squares fit with CalculiX in the loop within what ``before`` (the fast identification) left of the
    budget; a run still going at the limit is stopped there (as compression's)."""
    x0, *others = st.starts.values()
    fit_limit = fit_time_limit(time_limit_s, before)
    problem = inp.problem
    fit_problem = problem if fit_limit is None else replace(problem, deadline=time.time() + fit_limit)
    return fit_with_solver(partial(_run, fit_problem), _residuals(rows, inp.dk, problem.elongation), x0, st.lo, st.hi,
                           n_residuals=rows.row_sigma.size, steps=_steps,
                           x_scale=np.array([st.sigma_u, max(x0[1], 1.0), 1.0, TAPER_START]), workers=workers, scheduler=scheduler,
                           max_runs=max_runs, xtol=1e-3, ftol=1e-4, progress=progress_on_whole_clock(progress, before, len(x0), time_limit_s),
                           what="inverse FE (tension)", row_sigma=rows.row_sigma, correlated=True, other_starts=others, best_start=True,
                           time_limit_s=fit_limit)


NAMES = ("H", "beta", "c", "taper")


def _fit_problems(sol, st: _Starts, rows: _Rows, dk: float | None) -> tuple[list[str], float, float, float | None]:
    """(what is wrong with the fit, force RMS %, force max %, neck radius misfit mm): a parameter on a bound (c's lower
    bound, 0, is Voce itself, not a limit the fit ran into), a force or neck misfit, an optimiser that did not converge."""
    r_force = sol.residuals[:rows.n_force] * FORCE_SIGMA_PCT
    on_bound = [name for name, v, l_, h_ in zip(NAMES, sol.x, st.lo, st.hi) if (v <= l_ + 1e-9 and name != "c") or v >= h_ - 1e-9]
    force_rms, force_max = float(np.sqrt(np.mean(r_force**2))), float(np.max(np.abs(r_force)))
    neck_res_mm = float(sol.residuals[rows.n_force] * rows.neck_sigma) if dk is not None else None
    problems = [f"{', '.join(on_bound)} on a bound; the necking range may not be matched"] if on_bound else []
    if force_rms > POOR_FORCE_RMS_PCT or force_max > 5.0:
        problems.append(f"force residual {force_rms:.2f} % RMS, up to {force_max:.1f} % beyond ε_a: the model does not follow the record")
    if sol.status <= 0 and not sol.cut:  # a cut says so in its own warning
        problems.append(f"the optimiser stopped before converging ({sol.message})")
    if neck_res_mm is not None and abs(neck_res_mm) > 3.0 * rows.neck_sigma:
        problems.append(f"the fitted model misses the neck radius by {neck_res_mm:+.3f} mm")
    return problems, force_rms, force_max, neck_res_mm


@dataclass(frozen=True)
class _Curve:
    """The FE-consistent flow curve, the law refitted to it and the fracture stress it gives."""

    grid: np.ndarray
    e_end: float  # the grid's end: the fracture strain (1.5·ε_pu without one)
    true_curve: Any  # pandas frame
    refit: Any  # HardeningFit
    law_rms: dict
    warning_law: str | None
    fe_fracture: float | None
    fe_fracture_se: float | None


def _fe_curve(sol, inp: _Inputs, st: _Starts, refit_law: str | None) -> _Curve:
    """The measured curve to ε_a, the fitted family beyond it, to the fracture strain; refitted in ``refit_law`` (None:
    the law that follows it best; a warning when a given law follows it poorly and another well)."""
    import pandas as pd

    H, beta, c, _ = map(float, sol.x)
    grid = np.linspace(0.002, st.e_end, 200)
    flow = extended_curve(grid, inp.rows_e, inp.rows_s, H, beta, c)
    true_curve = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": flow})
    best, law_rms = best_law_for(true_curve)
    refit = fit_hardening(grid, flow, refit_law or best)
    if refit_law and refit_law != best and law_rms.get(refit_law, 0.0) > LAW_RMS_WARN_PCT > law_rms[best]:
        warning_law = (f"inverse FE: {refit_law} follows the FE-consistent curve within {law_rms[refit_law]:.1f} % RMS only, {best} within "
                       f"{law_rms[best]:.2f} % (--law {best}); true_curve.csv holds the curve itself")
    else:
        warning_law = None
    fractured = inp.fast.result.get("fracture_true_strain") is not None
    fe_fracture = float(extended_curve(st.e_end, inp.rows_e, inp.rows_s, H, beta, c)) if fractured else None
    fe_fracture_se = fracture_stress_stderr(sol.covariance, sol.x, st.e_end - inp.eps_a) if fractured else None
    return _Curve(grid, st.e_end, true_curve, refit, law_rms, warning_law, fe_fracture, fe_fracture_se)


def _budget(sol, inp: _Inputs, st: _Starts, rows: _Rows, time_limit_s, wall: float) -> InverseBudget:
    """result.json's ``inverse_fe.budget``: the limit, whether it cut the fit, what was fitted."""
    e_pts = rows.e_pts
    done = (f"force fitted over elongation {e_pts[0]:.3g}–{e_pts[-1]:.3g} mm (ε_a to fracture, {rows.n_force} points)"
            + (", the neck radius at fracture" if inp.dk is not None else ", no neck diameter") + f"; {len(st.starts)} warm starts, "
            + f"{sol.runs} runs; " + ("cut by the time limit" if sol.cut else "converged or stopped by the optimiser"))
    return InverseBudget(time_limit_s=time_limit_s, cut=sol.cut, solver_runs=sol.runs, wall_s=round(wall, 1), done=done)


def _inverse_block(sol, inp: _Inputs, st: _Starts, rows: _Rows, curve: _Curve, misfit: tuple, time_limit_s, wall: float) -> TensionInverseFE:
    """result.json's ``inverse_fe`` block: the family and taper with their standard errors, the fracture stress, the
    neck corrections against it, the runs, the budget, the misfits, the model."""
    (H, beta, c, taper), (H_se, beta_se, c_se, taper_se) = map(float, sol.x), map(float, sol.stderr)
    _, force_rms, force_max, neck_res_mm = misfit
    fe_fracture = curve.fe_fracture
    necks = {m: {"stress_MPa": v["stress_MPa"], "vs_fe_pct": 100.0 * (v["stress_MPa"] / fe_fracture - 1.0)}
             for m, v in (inp.fast.result.get("neck_corrections") or {}).items() if isinstance(v, dict) and fe_fracture}
    return TensionInverseFE(
        H_MPa=H, H_MPa_stderr=H_se, beta=beta, beta_stderr=beta_se, c=c, c_stderr=c_se, taper=taper, taper_stderr=taper_se,
        sigma_a_MPa=inp.rows_s[-1], measured_to_true_plastic_strain=inp.eps_a, sigma_u_MPa=st.sigma_u,
        uniform_rows={"true_plastic_strain": inp.rows_e, "true_stress_MPa": inp.rows_s},
        uniform_true_plastic_strain=inp.eps_pu, fracture_true_stress_MPa=fe_fracture, fracture_true_stress_MPa_stderr=curve.fe_fracture_se,
        neck_corrections_vs_fe=necks, solver_runs=sol.runs, failed_solver_runs=sol.failed_runs, solver_s=round(sol.solver_s, 1),
        wall_s=round(wall, 1), budget=_budget(sol, inp, st, rows, time_limit_s, wall),
        force_rms_residual_pct=force_rms, force_max_residual_pct=force_max,
        force_residual_serial_correlation=serial_correlation(sol.residuals[:rows.n_force]), neck_radius_residual_mm=neck_res_mm,
        law_rms_error_pct=curve.law_rms, optimizer=sol.optimizer(),
        warm_starts={k: {"H_MPa": float(v[0]), "beta": float(v[1]), "c": float(v[2]), "taper": float(v[3])} for k, v in st.starts.items()},
        model={"elements": "CAX8R 8x30 quarter model", "increments": inp.problem.increments, "E_MPa": inp.problem.E, "E_source": inp.E_source,
               "l0_mm": inp.l0, "elongation_mm": inp.problem.elongation, "force_points": rows.n_force, "force_sigma_pct": FORCE_SIGMA_PCT,
               "neck_radius_sigma_mm": rows.neck_sigma, "uniform_fraction": UNIFORM_FRACTION})


def _assemble(sol, inp: _Inputs, rows: _Rows, curve: _Curve, fit_warnings: list[str], block: TensionInverseFE,
              force_residual_pct) -> Identification:
    """The identification: the fast result with the refitted law, the FE fracture stress, the warnings and the
    ``inverse_fe`` block; the FE-consistent curve, the force rows and the law's curve."""
    import pandas as pd

    res = inp.fast.result
    warnings = [*res.warnings, *fit_warnings, *([curve.warning_law] if curve.warning_law else [])]
    if inp.dk is None:
        warnings.append("inverse FE: no post.dk_mm: only the force is fitted, not the neck diameter; the taper and the hardening "
                        "beyond Fm are then told apart by the force curve alone")
    result = replace(res, hardening_alternatives={**res.hardening_alternatives, "fast": res["hardening"]},
                     # a card from this curve must not read "good" when the fit warned (as compression's inverse)
                     hardening=TensionInverseHardening(curve.refit, [0.002, curve.e_end], fit_poor=bool(fit_warnings)),
                     fracture_true_stress_MPa=curve.fe_fracture if curve.fe_fracture is not None else res.fracture_true_stress_MPa,
                     warnings=warnings, inverse_fe=block,
                     methods={**res.methods, "inverse": "CalculiX necking (CAX8R) in the loop beyond ε_a with the taper fitted "
                                                       "(scipy least_squares), the curve measured up to ε_a"})
    curves = dict(inp.fast.curves)
    curves["inverse_fe_force"] = pd.DataFrame({"elongation_mm": rows.e_pts, "force_N": rows.f_pts, "residual_pct": force_residual_pct})
    curves["fit"] = pd.DataFrame({"true_plastic_strain": curve.grid, "true_stress_MPa": curve.refit(curve.grid)})
    return Identification(result=result, true_curve=curve.true_curve, curves=curves)


def identify_inverse_fe_tension(record, *, workers: int | None = None, scheduler=None, increments: int = INCREMENTS,
                                max_runs: int = 60, progress=None, refit_law: str | None = None, time_limit_s: float | None = TIME_LIMIT_S,
                                **tension_options) -> Identification:
    """Fit the hardening beyond ε_a and the taper to a tension record's force and neck diameter with CalculiX.

    Parameters
    ----------
    record : Record
        A tension record with dk measured.
    workers, scheduler : optional
        Parallel CalculiX runs: local processes, or a Dask scheduler's address.
    increments, max_runs : int
        The model's load increments; the most solver runs.
    progress : callable, optional
        ``progress(runs, elapsed_s, left_s)``.
    refit_law : str, optional
        The law the FE-consistent curve is refitted in; None: the one that follows it best.
    time_limit_s : float, optional
        The wall-time budget, s (None: none); a fit cut by it answers with the best run so far.
    **tension_options
        Options of :func:`identify_tension` (the fast identification).

    Returns
    -------
    Identification
        Whose result carries the ``inverse_fe`` block (docs/methods.md §4a.4).
    """
    t0 = time.perf_counter()
    inp = _inputs(record, increments, tension_options)
    rows = _rows(inp)
    st = _warm_starts(record, inp)
    before = time.perf_counter() - t0  # the fast identification: the budget's and the progress's clock start with it
    sol = _fit(inp, st, rows, before, workers=workers, scheduler=scheduler, max_runs=max_runs, progress=progress, time_limit_s=time_limit_s)
    misfit = _fit_problems(sol, st, rows, inp.dk)
    curve = _fe_curve(sol, inp, st, refit_law)
    # what is wrong with the fit itself (not with the law refitted to its curve, which has its own quality)
    problems = misfit[0]
    fit_warnings = (["inverse FE: " + "; ".join(problems)] if problems else []) + sol.failed_runs_warnings("inverse FE (tension)") \
        + sol.undetermined_warnings(list(NAMES), "inverse FE (tension)") + sol.cut_warnings("inverse FE (tension)", time_limit_s)
    wall = time.perf_counter() - t0
    block = _inverse_block(sol, inp, st, rows, curve, misfit, time_limit_s, wall)
    return _assemble(sol, inp, rows, curve, fit_warnings, block, sol.residuals[:rows.n_force] * FORCE_SIGMA_PCT)

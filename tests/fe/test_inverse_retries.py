"""The compression inverse's retries (no solver): a run that stops is run again with the table's
retry settings in order, and the fit counts the runs only a retry carried — in the fold-over band
(the Voce record with its end face: 42 of 78 runs stopped) that is where its time goes."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import flowcurve.identification.fe.inverse as inv
from flowcurve.identification.fe.model.ccx import SolverError

PROBLEM = inv._Problem("voce", 5.0, 9.0, 4.47, 200_000.0, 50)
X = np.array([300.0, 400.0, 5.0, 0.2])


@pytest.fixture
def solver(monkeypatch):
    """A stand-in for CalculiX whose runs with the listed stick slopes stop; it logs every model it is given."""
    state = SimpleNamespace(log=[], stops={1.0e7})

    def model(problem, x, **settings):
        return (settings.get("stick_slope_MPa_per_mm", 1.0e7), settings.get("increments", problem.increments), float(x[-1]))

    def simulate(m, timeout_s=None):  # the run's time-out (ccx.timeout_by) is not modelled here
        state.log.append(m[:2])
        if m[0] in state.stops:
            raise SolverError("stopped at step time 0.82 < 1 (*ERROR: too many cutbacks)")
        h = np.linspace(9.0, 4.47, 11)[1:]
        return SimpleNamespace(stroke_mm=9.0 - h, force_N=1e4 * (9.0 / h) * (1.0 + m[2]), height_mm=h, dmax_mm=np.full(10, 7.0),
                               dtop_mm=np.full(10, 6.0), model=SimpleNamespace(nu=0.3), wall_s=1.0, cached=False)

    monkeypatch.setattr(inv, "_model", model)
    monkeypatch.setattr(inv, "simulate_upsetting", simulate)
    return state


def test_a_stopped_run_is_run_again_and_says_a_retry_carried_it(solver):
    out = inv._run(PROBLEM, X)
    assert solver.log == [(1.0e7, 50), (1.0e6, 50)] and out.retried
    solver.stops, solver.log = set(), []
    assert not inv._run(PROBLEM, X).retried and solver.log == [(1.0e7, 50)]


def test_every_try_stopping_is_a_failed_run(solver):
    solver.stops = {1.0e7, 1.0e6}
    assert inv._run(PROBLEM, X) is None
    # the model's own, the softer slope, 80 increments; 50 increments is the model's own run again
    assert solver.log == [(1.0e7, 50), (1.0e6, 50), (1.0e7, 80)]


def test_the_fit_counts_the_runs_a_retry_carried(solver):
    """Checked against the runs' own flags as the run function returned them (in-process, one worker)."""
    from flowcurve.identification.fe.solver_fit import fit_with_solver

    flags = []

    def run(x):
        out = inv._run(PROBLEM, np.array([300.0, 400.0, 5.0, x[0]]))
        flags.append(out.retried)
        return out

    target = 1e4 * (9.0 / np.linspace(9.0, 4.47, 11)[1:]) * 1.15
    fit = fit_with_solver(run, lambda out: out.force_N[1:] - target, [0.2], [0.0], [0.5], n_residuals=10,
                          steps=lambda x: np.full(1, 1e-3), x_scale=np.ones(1), workers=1)
    np.testing.assert_allclose(fit.x, [0.15], atol=1e-6)
    assert fit.retried_runs == sum(flags) == fit.runs > 0 and fit.failed_runs == 0  # every first try stopped
    solver.stops, flags[:] = set(), []
    assert fit_with_solver(run, lambda out: out.force_N[1:] - target, [0.2], [0.0], [0.5], n_residuals=10,
                           steps=lambda x: np.full(1, 1e-3), x_scale=np.ones(1), workers=1).retried_runs == 0 == sum(flags)


def test_the_summary_counts_the_runs_a_retry_carried():
    from flowcurve.cli.identification import solver_runs_text

    assert solver_runs_text({"solver_runs": 43, "failed_solver_runs": 4, "retried_solver_runs": 9}) == \
        "43 solver runs (4 did not converge, 9 converged only when retried)"
    assert solver_runs_text({"solver_runs": 27, "retried_solver_runs": 2}, "") == "27 (2 converged only when retried)"
    assert solver_runs_text({"solver_runs": 27}) == "27 solver runs"

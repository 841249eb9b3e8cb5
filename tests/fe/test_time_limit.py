"""The inverses' wall-time budget (issue 37; compression and tension): a fit whose runs would outlast ``time_limit_s``
ends by it with the best parameter set run so far, marked ``cut``, its standard errors from the
last Jacobian; the time left it shows is held to the limit; the force is fitted up to the
fold-over's onset. Closed-form "runs" that take a known time on a model clock (the fit's clock
replaced, so the machine's load does not move the test), no solver."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import flowcurve.identification.fe.solver_fit as solver_fit
from flowcurve.cli.progress import budget_text
from flowcurve.identification.fe.inverse import MIN_FORCE_STRAIN, force_fit_limit, force_sigma_pct
from flowcurve.identification.fe.model.model_form import FOLD_OVER_BAND, FOLD_OVER_SIGMA_FACTOR, FORCE_SIGMA_PCT
from flowcurve.identification.fe.solver_fit import fit_with_solver, time_left_s

T = np.linspace(0.0, 1.0, 12)
RUN_S = 0.05


CLOCK = {"now": 0.0}  # the model clock, s


@pytest.fixture(autouse=True)
def _model_clock(monkeypatch):
    CLOCK["now"] = 0.0
    monkeypatch.setattr(solver_fit, "time", SimpleNamespace(perf_counter=lambda: CLOCK["now"]))


class _Out:
    cached = False

    def __init__(self, y):
        self.y, self.wall_s = y, RUN_S


def _slow_exp(x):
    """y = a·exp(b·t), one run taking RUN_S on the model clock: a fit that needs several iterations."""
    CLOCK["now"] += RUN_S
    return _Out(x[0] * np.exp(x[1] * T))


def _fit(limit, seen=None):
    target = 2.0 * np.exp(1.5 * T)
    return fit_with_solver(_slow_exp, lambda out: out.y - target, np.array([0.5, -1.0]), [0.01, -5.0], [10.0, 5.0], n_residuals=T.size,
                           steps=lambda x: np.full(2, 1e-6), x_scale=np.ones(2), workers=1, time_limit_s=limit,
                           progress=(lambda runs, elapsed, left: seen.append((runs, elapsed, left))) if seen is not None else None)


def test_without_a_limit_the_fit_converges():
    sol = _fit(None)
    assert not sol.cut and sol.x == pytest.approx([2.0, 1.5], rel=1e-5)


def test_a_time_limit_cuts_the_fit_to_its_best_run_so_far():
    full = _fit(None)
    limit = 0.3 * full.wall_s
    t0 = CLOCK["now"]
    seen = []
    sol = _fit(limit, seen)
    wall = CLOCK["now"] - t0
    assert sol.cut and "time limit" in sol.message
    assert sol.runs < full.runs
    assert wall <= limit + 1e-9  # no batch was started that would end past the limit
    # the answer is the least misfit of the runs made, and it has standard errors from a Jacobian
    start_cost = float(np.sum((0.5 * np.exp(-T) - 2.0 * np.exp(1.5 * T)) ** 2))
    assert float(sol.residuals @ sol.residuals) < start_cost
    assert np.all(np.isfinite(sol.stderr))
    # the time left shown never reaches past the limit
    assert all(left is None or elapsed + left <= limit + 1e-9 for _, elapsed, left in seen)


def test_a_fit_whose_batches_vary_stays_within_its_limit():
    """Every third run, the first among them, takes ten times as long (a run that stops where the side folds over and is
    retried): the next batch is judged at the longest so far, so the fit never ends past its limit
    (at the mean batch time it would)."""
    calls = {"n": 0}

    def uneven(x):
        calls["n"] += 1
        CLOCK["now"] += RUN_S * (10.0 if calls["n"] % 3 == 1 else 1.0)
        return _Out(x[0] * np.exp(x[1] * T))

    target = 2.0 * np.exp(1.5 * T)
    for limit in np.linspace(0.6, 2.0, 15):  # the first run (0.5) always runs: there is no best run to end with before it
        calls["n"], t0 = 0, CLOCK["now"]
        sol = fit_with_solver(uneven, lambda out: out.y - target, np.array([0.5, -1.0]), [0.01, -5.0], [10.0, 5.0], n_residuals=T.size,
                              steps=lambda x: np.full(2, 1e-6), x_scale=np.ones(2), workers=1, time_limit_s=limit)
        assert CLOCK["now"] - t0 <= limit + 1e-9 or not sol.cut, (limit, CLOCK["now"] - t0)


def test_time_left_is_the_typical_fit_at_the_rate_so_far_held_to_the_limit():
    assert time_left_s(0, 0.0, 4, 270.0) is None
    assert time_left_s(10, 50.0, 4, None) == pytest.approx(5.0 * (8 * 5 - 10))
    assert time_left_s(10, 50.0, 4, 100.0) == pytest.approx(50.0)
    assert time_left_s(50, 250.0, 4, 270.0) == pytest.approx(20.0)
    assert "about 20 s left (time limit 270 s)" in budget_text(50, 250.0, 20.0, limit_s=270.0)


def test_the_force_is_fitted_to_the_fold_over_onset_but_not_less_than_the_minimum():
    assert force_fit_limit(0.69, None) == 0.69
    assert force_fit_limit(0.69, 0.6) == 0.6
    assert force_fit_limit(0.69, 0.1) == MIN_FORCE_STRAIN
    assert force_fit_limit(0.25, 0.1) == 0.25


def test_a_force_points_sigma_grows_over_the_band_before_the_fold_over():
    eps = np.array([0.1, 0.5, 0.55, 0.6, 0.65])
    np.testing.assert_allclose(force_sigma_pct(eps, None), FORCE_SIGMA_PCT)
    k = FOLD_OVER_SIGMA_FACTOR
    onset = 0.5 + FOLD_OVER_BAND  # the band is 0.5–0.6
    np.testing.assert_allclose(force_sigma_pct(eps, onset), FORCE_SIGMA_PCT * np.array([1.0, 1.0, (1.0 + k) / 2.0, k, k]))


# ---- the tension inverse (identify_inverse_fe_tension) keeps the same budget ------------------------------------------

TENSION_RUN_S = 10.0  # one stand-in necking run on the model clock


@pytest.fixture
def slow_tension_runs(monkeypatch):
    """The tension inverse's runs replaced by a closed form (no solver) that takes TENSION_RUN_S on
    the model clock, which the whole identification reads (the fast part takes no model time): the
    record's own corrected force scaled by 1 + (H/H* − 1)·u + 10·(δ − δ*)·u², u the elongation over
    its end, H* 1.2 times the first start's H, δ* 0.008 — a fit that takes several Jacobians."""
    import time

    import flowcurve.identification.fe.inverse_tension as inv
    from flowcurve.identification.tension.identify import identify_tension

    from .test_inverse_tension_inputs import _record

    monkeypatch.setattr(time, "perf_counter", lambda: CLOCK["now"])
    record = _record(0.7)
    diagram = identify_tension(record).curves["corrected_diagram"]
    elong, force = diagram["elongation_mm"].to_numpy(), diagram["force_N"].to_numpy()
    state = {}

    def run(problem, x):
        CLOCK["now"] += TENSION_RUN_S
        target = state.setdefault("target", (1.2 * float(x[0]), 0.008))
        u = elong / elong.max()
        factor = 1.0 + (x[0] / target[0] - 1.0) * u + 10.0 * (x[3] - target[1]) * u**2
        return inv._Run(elong, force * factor, np.full(elong.size, 2.2), TENSION_RUN_S, False)

    monkeypatch.setattr(inv, "_run", run)
    return record


def test_a_time_limit_cuts_the_tension_fit_with_a_warning(slow_tension_runs):
    from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

    full = identify_inverse_fe_tension(slow_tension_runs, workers=1, time_limit_s=None).result
    assert not full["inverse_fe"]["budget"]["cut"] and not any("time limit" in w for w in full["warnings"])
    assert full["inverse_fe"]["budget"]["solver_runs"] * TENSION_RUN_S > 75.0  # the limit below would cut it
    seen = []
    t0 = CLOCK["now"]
    cut = identify_inverse_fe_tension(slow_tension_runs, workers=1, time_limit_s=75.0,
                                      progress=lambda runs, elapsed, left: seen.append((runs, elapsed, left))).result
    budget = cut["inverse_fe"]["budget"]
    assert budget["cut"] and budget["time_limit_s"] == 75.0 and "cut by the time limit" in budget["done"]
    assert CLOCK["now"] - t0 <= 75.0 and budget["solver_runs"] < full["inverse_fe"]["budget"]["solver_runs"]
    said = [w for w in cut["warnings"] if "cut by the time limit (75 s, --time-limit)" in w]
    assert said and "the best parameter set run so far, not a converged fit" in said[0]
    assert not any("stopped before converging" in w for w in cut["warnings"])  # the cut says so once
    assert cut["hardening"]["quality"] == "poor"
    assert seen and all(left is None or elapsed + left <= 75.0 + 1e-9 for _, elapsed, left in seen)


def test_the_cli_passes_the_time_limit_to_a_tension_record(slow_tension_runs, tmp_path, capsys):
    import json

    from flowcurve.cli import main
    from flowcurve.record.format import write_record

    path = write_record(tmp_path / "t.csv", slow_tension_runs)
    assert main(["identify", str(path), "--method", "inverse-fe", "--workers", "1", "--time-limit", "75", "--no-plots",
                 "--out", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    budget = json.loads((tmp_path / "out" / "t" / "result.json").read_text())["inverse_fe"]["budget"]
    assert budget["time_limit_s"] == 75.0 and budget["cut"]
    assert "(time limit 75 s)" in err  # the progress line shows the tension's limit too


def test_the_time_limit_help_names_both_inverses_and_their_defaults(capsys):
    from flowcurve.cli import main
    from flowcurve.identification.fe import inverse, inverse_tension

    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "inverse-fe (compression and tension)" in text
    assert f"compression {inverse.TIME_LIMIT_S:g}" in text and f"tension {inverse_tension.TIME_LIMIT_S:g}" in text


def test_a_run_past_the_deadline_is_not_started_and_one_before_it_is_stopped_there(monkeypatch):
    """The compression inverse's run keeps the fit's deadline: none is started after it, and one
    started before it gets the time left as its solver time-out (a run that stops at the fold-over
    and is retried would otherwise run past the limit)."""
    import time

    import flowcurve.identification.fe.inverse as inv

    from flowcurve.identification.fe.model.ccx import SolverError

    timeouts = []

    def stopped(model, timeout_s=600.0):
        timeouts.append(timeout_s)
        raise SolverError("timed out")

    monkeypatch.setattr(inv, "simulate_upsetting", stopped)
    monkeypatch.setattr(inv, "_model", lambda problem, x, **settings: ("model", tuple(x), tuple(sorted(settings.items()))))
    problem = inv._Problem("johnson_cook", 6.0, 9.0, 4.5, 200_000.0, 50, deadline=time.time() - 1.0)
    assert inv._run(problem, np.array([100.0, 1000.0, 0.5, 0.1])) is None and timeouts == []
    problem = inv._Problem("johnson_cook", 6.0, 9.0, 4.5, 200_000.0, 50, deadline=time.time() + 30.0)
    assert inv._run(problem, np.array([100.0, 1000.0, 0.5, 0.1])) is None
    assert timeouts and all(0.0 < t <= 30.0 for t in timeouts)


def test_runs_stopped_by_the_limit_end_the_fit_and_are_not_counted_failed():
    """A batch that ends past the limit, its runs None (stopped there): the fit is cut with its best
    run so far, and those runs are not 'did not converge'."""
    target = 2.0 * np.exp(1.5 * T)
    state = {"n": 0}

    def run(x):
        state["n"] += 1
        if state["n"] <= 3:
            CLOCK["now"] += RUN_S
            return _Out(x[0] * np.exp(x[1] * T))
        CLOCK["now"] += 10.0  # the next batch runs into the limit and is stopped
        return None

    sol = fit_with_solver(run, lambda out: out.y - target, np.array([0.5, -1.0]), [0.01, -5.0], [10.0, 5.0], n_residuals=T.size,
                          steps=lambda x: np.full(2, 1e-6), x_scale=np.ones(2), workers=1, time_limit_s=1.0)
    assert sol.cut and sol.failed_runs == 0 and sol.runs > 3


# ---- the tension inverse's runs keep the deadline (a run still going at the limit is stopped there) ---------------------

HANGING_CALL = 5  # the solver call that does not end by itself (a run that stalls and would go on to its own time-out)


@pytest.fixture
def hanging_tension_solver(monkeypatch):
    """CalculiX replaced below the tension inverse's run (``tension.simulate_tension``) by a closed form
    on the model clock, which ``time.time`` and ``time.perf_counter`` both read: a run takes
    TENSION_RUN_S, except call :data:`HANGING_CALL`, which runs until its solver time-out and then
    raises the solver's time-out error (as ``ccx.run_deck``). Each call's start and time-out are
    logged. The force is the record's own, scaled by 1 + (σ_end/σ_end* − 1)·u + 10·(δ − δ*)·u²
    (σ_end the last *PLASTIC row, * the first call's, δ* 0.008): a fit of several Jacobians."""
    import time

    import flowcurve.identification.fe.model.tension as tension
    from flowcurve.identification.fe.model.ccx import SolverError
    from flowcurve.identification.tension.identify import identify_tension

    from .test_inverse_tension_inputs import _record

    monkeypatch.setattr(time, "perf_counter", lambda: CLOCK["now"])
    monkeypatch.setattr(time, "time", lambda: CLOCK["now"])
    record = _record(0.7)
    diagram = identify_tension(record).curves["corrected_diagram"]
    elong, force = diagram["elongation_mm"].to_numpy()[1:], diagram["force_N"].to_numpy()[1:]
    calls = []

    def simulate(model, *, timeout_s=600.0, **_):
        calls.append((CLOCK["now"], timeout_s))
        if len(calls) == HANGING_CALL or timeout_s < TENSION_RUN_S:
            CLOCK["now"] += timeout_s
            raise SolverError(f"CalculiX run 'tension' timed out after {timeout_s:g} s")
        CLOCK["now"] += TENSION_RUN_S
        target = calls and getattr(simulate, "target", None) or (model.stress_MPa[-1] * 1.2, 0.008)
        simulate.target = target
        u = elong / elong.max()
        factor = 1.0 + (model.stress_MPa[-1] / target[0] - 1.0) * u + 10.0 * (model.imperfection - target[1]) * u**2
        return SimpleNamespace(elongation_mm=elong, force_N=force * factor, neck_radius_mm=np.full(elong.size, 2.2),
                               wall_s=TENSION_RUN_S, cached=False)

    monkeypatch.setattr(tension, "simulate_tension", simulate)
    return record, calls


def test_a_tension_run_still_going_at_the_limit_is_stopped_there_and_not_counted_failed(hanging_tension_solver):
    """Limit 75 s, runs of 10 s: the three warm starts (0–30 s), then a Jacobian's four runs, of which
    the second (from 40 s) does not end by itself. It is given the time left as its solver time-out
    and stopped at the deadline; the runs after it are not started; the identification ends by its
    limit, cut, with the best run so far, and the stopped run is no failed one. (Before the runs
    kept the deadline, the stalled run went on to the solver's own 600 s time-out.)"""
    from flowcurve.identification.fe.model.ccx import DEFAULT_TIMEOUT_S
    from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

    record, calls = hanging_tension_solver
    t0 = CLOCK["now"]
    deadline = t0 + 75.0  # the fast identification takes no model time: the fit's deadline is the whole limit's
    result = identify_inverse_fe_tension(record, workers=1, time_limit_s=75.0).result
    assert CLOCK["now"] - t0 <= 75.0 + 1e-9  # the command ends by its limit
    assert len(calls) == HANGING_CALL  # the stalled run was the last one started
    assert all(start < deadline for start, _ in calls)  # no run starts after the deadline
    assert all(0.0 < timeout <= DEFAULT_TIMEOUT_S and start + timeout <= deadline + 1e-9 for start, timeout in calls)
    start, timeout = calls[HANGING_CALL - 1]
    assert start + timeout == pytest.approx(deadline)  # the stalled run's time-out ends at the deadline
    inv = result["inverse_fe"]
    assert inv["budget"]["cut"] and "cut by the time limit" in inv["budget"]["done"]
    assert inv["failed_solver_runs"] == 0 and not any("did not converge" in w for w in result["warnings"])
    assert any("cut by the time limit (75 s, --time-limit)" in w for w in result["warnings"])
    assert result["hardening"]["quality"] == "poor"


def test_a_tension_run_without_a_limit_keeps_the_solvers_own_time_out(hanging_tension_solver):
    """Without a time limit no deadline is set: every run has the solver's default time-out
    (the stalled one fails after it, and is a failed run)."""
    from flowcurve.identification.fe.model.ccx import DEFAULT_TIMEOUT_S
    from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

    record, calls = hanging_tension_solver
    result = identify_inverse_fe_tension(record, workers=1, time_limit_s=None).result
    assert calls and all(timeout == DEFAULT_TIMEOUT_S for _, timeout in calls)
    assert result["inverse_fe"]["failed_solver_runs"] >= 1 and not result["inverse_fe"]["budget"]["cut"]


def test_a_limit_that_stops_the_warm_starts_says_so(hanging_tension_solver):
    """A limit within the warm starts' batch (three runs of 10 s): at 15 s the first start ends and
    the second is stopped — the fit is cut with the one run that ended, its stopped runs not
    counted failed, its parameters without standard errors (no Jacobian); at 8 s no start ends,
    and the error names the time limit, not "the solver run failed at the warm start"."""
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.fe.inverse_tension import identify_inverse_fe_tension

    record, calls = hanging_tension_solver
    result = identify_inverse_fe_tension(record, workers=1, time_limit_s=15.0).result
    assert CLOCK["now"] <= 15.0 + 1e-9 and len(calls) == 2  # the third start is not begun
    inv = result["inverse_fe"]
    assert inv["budget"]["cut"] and inv["failed_solver_runs"] == 0
    assert all(not np.isfinite(inv[k]) for k in ("H_MPa_stderr", "beta_stderr", "c_stderr", "taper_stderr"))
    assert any("cut by the time limit" in w and "no Jacobian was formed: no standard errors" in w for w in result["warnings"])
    assert result["hardening"]["quality"] == "poor"

    calls.clear()
    CLOCK["now"] = 0.0
    with pytest.raises(IdentificationError, match="time limit") as err:
        identify_inverse_fe_tension(record, workers=1, time_limit_s=8.0)
    assert "failed at the warm start" not in str(err.value)
    assert CLOCK["now"] <= 8.0 + 1e-9 and len(calls) == 1

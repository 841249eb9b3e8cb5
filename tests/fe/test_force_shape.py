"""Where the compression inverse's μ came from (identification/fe/force_shape.py, issue 37): the μ
its force rows alone and its shape rows alone tell, against closed forms of a linear model whose
force rows and shape rows are built to imply known μ; and through ``identify_inverse_fe`` with
CalculiX replaced by that linear model, that a record whose force and shape pull μ apart gets a
warning and a poor hardening, and one whose force and shape agree does not."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flowcurve.identification.fe import force_shape as fs
from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.fe.solver_fit import serial_inflation

M = 30
T = np.linspace(0.05, 1.0, M)
# force rows (σ units) per unit of three law constants and μ: the law's 1, t, t²; μ's t³ (its own signature)
J_FORCE = np.column_stack([np.ones(M), T, T**2, 5.0 * T**3])
NOISE = 0.3 * np.cos(7.3 * np.arange(M))  # a fixed misfit the model cannot take up


def _orthogonal(J, v):
    """v less its projection on J's columns: a misfit that moves no least-squares parameter."""
    return v - J @ np.linalg.lstsq(J, v, rcond=None)[0]


def _rows(x_fit, x_force, mu_shape, g):
    """Jacobian and residuals at x_fit of force rows that vanish (but for a misfit) at x_force and
    shape rows g·(μ − mu_shape) that vanish at mu_shape (the law's constants do not move them)."""
    e = _orthogonal(J_FORCE, NOISE)
    jac = np.vstack([J_FORCE, np.column_stack([np.zeros((len(g), 3)), g])])
    res = np.concatenate([J_FORCE @ (x_fit - x_force) + e, np.asarray(g) * (x_fit[-1] - mu_shape)])
    return jac, res, e


def test_the_force_alone_is_the_gauss_newton_step_with_its_pooled_serially_correlated_stderr():
    """Linear rows: the step lands on the force's own μ exactly; its standard error is
    √([(JᵀJ)⁻¹]_μμ·s²), s² = |e|²/(m − p)·(1 + ρ)/(1 − ρ), computed here by the explicit inverse."""
    x_force, x_fit = np.array([1.0, 0.5, -0.2, 0.12]), np.array([1.1, 0.4, -0.1, 0.18])
    jac, res, e = _rows(x_fit, x_force, 0.18, [3.0])
    mu, se = fs.mu_force_alone(jac, res, x_fit, np.arange(M))
    s2 = float(e @ e) / (M - 4) * serial_inflation(e)
    assert mu == pytest.approx(0.12, abs=1e-12)
    assert se == pytest.approx(math.sqrt(np.linalg.inv(J_FORCE.T @ J_FORCE)[-1, -1] * s2), rel=1e-9)
    assert fs.mu_force_alone(jac, res, x_fit, np.arange(M), model_form_stderr=0.05)[1] == pytest.approx(math.hypot(se, 0.05))


def test_the_shape_alone_moves_mu_alone_with_its_model_form_offsets():
    """μ_s = μ − Σg·r/Σg², se² = 1/Σg² + Σ(o·g/Σg²)² (two rows: dmax and dface)."""
    x_fit = np.array([1.0, 0.5, -0.2, 0.15])
    g = np.array([2.0, -4.0])
    jac, res, _ = _rows(x_fit, x_fit, 0.21, g)
    mu, se = fs.mu_shape_alone(jac, res, x_fit, [M, M + 1], model_form_offsets=[0.5, 1.5])
    info = float(g @ g)
    assert mu == pytest.approx(0.21, abs=1e-12)
    assert se == pytest.approx(math.sqrt(1.0 / info + (0.5 * 2.0 / info) ** 2 + (1.5 * -4.0 / info) ** 2), rel=1e-12)


def _by_side(mu_force, mu_shape, g=(8.0,)):
    x_fit = np.array([1.0, 0.5, -0.2, 0.15])
    jac, res, _ = _rows(x_fit, np.array([1.0, 0.5, -0.2, mu_force]), mu_shape, np.asarray(g, float))
    mu_f, se_f = fs.mu_force_alone(jac, res, x_fit, np.arange(M))
    mu_s, se_s = fs.mu_shape_alone(jac, res, x_fit, [M])
    return fs.MuBySide(mu_f, se_f, mu_s, se_s)


def test_agreeing_sides_give_no_warning_and_sides_three_standard_errors_apart_do():
    agree = _by_side(0.15, 0.15)
    assert agree.force_told and agree.shape_told and agree.disagreement_sigmas < 1e-9 and not agree.disagree
    found, warning = fs.force_shape_check(agree, "dmax")
    assert warning is None and "0.0 combined standard errors apart" in found
    # the shape's μ moved 3 combined standard errors from the force's (both sides' se do not depend on μ here)
    apart = _by_side(0.15, 0.15 + 3.0 * math.hypot(agree.stderr_force, agree.stderr_shape))
    assert apart.disagreement_sigmas == pytest.approx(3.0) and apart.disagree
    found, warning = fs.force_shape_check(apart, "dmax")
    assert warning is not None and "pull μ apart" in warning and "the hardening is poor" in warning
    assert f"{apart.mu_force:.3f} ± {apart.stderr_force:.3f}" in warning and f"{apart.mu_shape:.3f} ± {apart.stderr_shape:.3f}" in warning
    # 1.9 apart is within the bound
    assert not _by_side(0.15, 0.15 + 1.9 * math.hypot(agree.stderr_force, agree.stderr_shape)).disagree


def test_the_sides_combine_by_their_weights():
    side = fs.MuBySide(0.14, 0.03, 0.16, 0.04)
    assert side.combined_stderr == pytest.approx(0.024)  # (0.03⁻² + 0.04⁻²)^(−1/2) = 0.03·0.04/0.05
    assert fs.MuBySide(0.14, 0.03, math.nan, math.nan).combined_stderr == pytest.approx(0.03)
    assert math.isnan(fs.MuBySide(math.nan, math.nan, math.nan, math.nan).combined_stderr)


def test_a_shape_row_that_does_not_move_with_mu_is_undetermined_not_a_warning():
    side = _by_side(0.10, 0.30, g=(0.0,))
    assert side.force_told and not side.shape_told and math.isnan(side.mu_shape)
    assert not side.disagree and math.isnan(side.disagreement_sigmas)
    found, warning = fs.force_shape_check(side, "dmax")
    assert warning is None and "not compared" in found and "dmax alone does not tell μ" in found


def test_force_rows_that_cannot_tell_mu_from_the_law_are_undetermined():
    """μ's force signature the same as a law constant's: a null direction, no μ from the force."""
    x_fit = np.array([1.0, 0.5, -0.2, 0.15])
    jac, res, _ = _rows(x_fit, x_fit, 0.15, np.array([8.0]))
    jac[:M, -1] = 2.0 * jac[:M, 1]
    assert all(math.isnan(v) for v in fs.mu_force_alone(jac, res, x_fit, np.arange(M)))
    found, warning = fs.force_shape_check(fs.MuBySide(math.nan, math.nan, 0.15, 0.01), "dmax")
    assert warning is None and "the force curve alone does not tell μ" in found


def test_the_inverse_layout_counts_the_force_model_form_on_the_force_side():
    """Force rows at strain, then dmax and dface (their σ hold the shape's model form): the force
    side gets the shift the force model form (fe/model/model_form.py) makes in the force-alone fit; the
    shape side is μ moved alone over the two rows, 1/√Σg²."""
    x_fit = np.array([1.0, 0.5, -0.2, 0.15])
    g = np.array([6.0, 3.0])
    jac, res, _ = _rows(x_fit, x_fit, 0.15, g)
    jac[:M, 1], jac[:M, -1] = T**3, 5.0 * np.sqrt(T)  # law 1, t³, t²; μ √t: a ramp the law does not take up moves μ
    side = fs.inverse_mu_by_side(jac, res, x_fit, T, 1.0, 2)
    mu_f, se_f = fs.mu_force_alone(jac, res, x_fit, np.arange(M))
    force_mf = mf.force_model_form_stderr(jac[:M], np.arange(M), T, 1.0, 0.15)[-1]
    assert force_mf > 0.1 * se_f
    assert side.mu_force == pytest.approx(mu_f) and side.stderr_force == pytest.approx(math.hypot(se_f, force_mf))
    assert side.stderr_shape == pytest.approx(1.0 / math.sqrt(float(g @ g)))


# ---- through identify_inverse_fe, CalculiX replaced by a linear model of the record ---------------------------------

DATA = Path(__file__).parent / "data"


@pytest.fixture
def linear_solver(monkeypatch):
    """``_run`` replaced by test_inverse_numbers_unchanged.linear_runs: the record's own frame-corrected
    force times the law's change and 1 + 0.5·t³·(μ − mu_force), dmax and dface moved with (μ − mu_shape);
    the warm start (the inverse's first run) is the law's reference."""
    import flowcurve.identification.fe.inverse as inv
    import flowcurve.identification.fe.verify as verify

    from .test_inverse_numbers_unchanged import linear_runs

    state = {"mu_force": 0.05, "mu_shape": 0.05}
    capture, run = linear_runs(state)
    monkeypatch.setattr(verify, "record_force_stroke", capture)
    monkeypatch.setattr(inv, "_run", run)
    return state


@pytest.mark.parametrize("mu_force, mu_shape, warned", [(0.05, 0.05, False), (0.03, 0.12, True)])
def test_force_and_shape_pulling_mu_apart_warn_and_mark_the_hardening_poor(linear_solver, mu_force, mu_shape, warned):
    from flowcurve.identification.identify import identify_inverse_fe
    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.record.format import read_record

    linear_solver.update(mu_force=mu_force, mu_shape=mu_shape)
    result = to_jsonable(identify_inverse_fe(read_record(DATA / "second_model_C2.csv"), law="johnson_cook", workers=1,
                                             time_limit_s=None).result)
    inv = result["inverse_fe"]
    force, shape = inv["mu_force_alone"], inv["mu_shape_alone"]
    # each side tells its own μ (linear model: the shape exactly, the force within its misfit)
    assert shape["mu"] == pytest.approx(mu_shape, abs=1e-6)
    assert abs(force["mu"] - mu_force) < force["stderr"]
    assert (inv["force_shape_disagreement_sigmas"] > mf.DISAGREE_SIGMAS) is warned
    said = [w for w in result.get("warnings", []) if "pull μ apart" in w]
    assert bool(said) is warned
    if warned:
        assert result["hardening"]["quality"] == "poor"
        assert f"{force['mu']:.3f} ± {force['stderr']:.3f}" in said[0] and "dmax and dface" in said[0]
    else:
        assert result["hardening"].get("quality") != "poor", result.get("warnings")

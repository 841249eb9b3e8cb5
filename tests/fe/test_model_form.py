"""The model form's share of the uncertainty (identification/fe/model/model_form.py): its pure functions
against closed forms, and what it does to the default identification (fe_table) of a record."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.identification.compression import friction as fr
from flowcurve.identification.fe.model import model_form as mf


def test_a_uniform_bias_shifts_the_intercept_of_a_line_fit_and_not_its_slope():
    """y = a + b·x fitted by least squares: adding c to every residual moves a by −c, b by 0
    (closed form); a bias growing as x moves b by −c/(x range) and a by +c·x0/(x range)."""
    x = np.linspace(0.1, 0.7, 30)
    J = np.column_stack([np.ones_like(x), x])  # ∂r/∂(a, b) of r = a + b·x − y
    np.testing.assert_allclose(mf.shift_of_bias(J, np.full(x.size, 0.3)), [-0.3, 0.0], atol=1e-12)
    ramp = 0.3 * (x - x[0]) / (x[-1] - x[0])
    np.testing.assert_allclose(mf.shift_of_bias(J, ramp), [0.3 * x[0] / 0.6, -0.3 / 0.6], atol=1e-12)


def test_the_force_model_form_share_is_both_patterns_in_quadrature():
    x = np.linspace(0.1, 0.7, 30)
    J = np.column_stack([np.ones_like(x), x, np.zeros_like(x)])  # a third parameter the force does not move
    se = mf.force_model_form_stderr(J, np.arange(x.size), x, 1.0, 0.2)
    c = 100.0 * mf.FORCE_MODEL_FORM_PER_MU * 0.2
    np.testing.assert_allclose(se, [math.hypot(c, c * 0.1 / 0.6), c / 0.6, 0.0], atol=1e-9)


def test_disagreement_in_combined_standard_errors():
    assert mf.disagreement(0.2, 0.03, 0.1, 0.04) == pytest.approx(2.0)
    assert not mf.disagree(0.2, 0.03, 0.1, 0.04) and mf.disagree(0.2, 0.03, 0.09, 0.04)
    assert mf.disagreement(0.1, 0.0, 0.1, 0.0) == 0.0 and mf.disagreement(0.1, 0.0, 0.2, 0.0) == math.inf


def test_shares_add_in_quadrature_and_an_undetermined_constant_stays_undetermined():
    out = mf.combined_stderr({"A": 3.0, "n": None, "B": float("nan")}, {"A": 4.0, "n": 1.0}, {"B": 2.0})
    assert out["A"] == pytest.approx(5.0) and out["n"] is None and math.isnan(out["B"])
    assert mf.through_mu({"A": 100.0, "n": 0.3}, {"A": 110.0, "n": 0.28}) == pytest.approx({"A": 5.0, "n": 0.01})


@pytest.fixture(scope="module")
def table():
    from flowcurve.identification.fe.model.table import UpsettingTable

    return UpsettingTable.load()


def _shape(table, mu, h0_d0, n=0.3, eps=0.6, d0=6.0):
    h0 = d0 * h0_d0
    hk = h0 * math.exp(-eps)
    d_n = d0 * math.sqrt(h0 / hk)
    return d0, h0, hk, d_n + 2 * hk * float(table.bulge_at(mu, h0_d0, n, [eps])[0]), d_n * float(table.face_at(mu, h0_d0, n, [eps])[0])


def test_the_end_face_range_is_the_mu_of_the_face_less_and_plus_its_model_form_sigma(table):
    """The table's own end face read back: μ inside its range, whose ends are the μ of d/d_n ± √((0.01/d_n)² + u_f²)."""
    d0, h0, hk, dmax, dface = _shape(table, 0.15, 1.5)
    res = fr.identify_friction("fe_table", d0, h0, hk, d_max_mm=dmax, d_face_mm=dface)
    d_n = res.extra["d_n_mm"]
    lo, hi = res.extra["mu_range"]
    assert lo < res.mu < hi and res.extra["mu_stderr"] == pytest.approx((hi - lo) / 2)
    sigma = math.hypot(fr.DIAMETER_RESOLUTION_MM / d_n, mf.FACE_MODEL_FORM)
    for m, sign in ((lo, 1.0), (hi, -1.0)):  # a smaller face is a larger μ
        assert float(table.face_at(m, 1.5, 0.3, [0.6])[0]) == pytest.approx(dface / d_n + sign * sigma, abs=2e-4)
    assert res.extra["face_bulge_disagreement_sigmas"] < 0.2  # the same model's face and bulge agree


def test_a_face_and_a_bulge_of_different_mu_disagree_and_make_the_hardening_poor(table):
    """The end face of μ 0.3 with the bulge of μ 0.05 (h0/d0 1.5): the μ differ by far more than
    their combined standard errors; the default says so naming both, and marks the hardening poor."""
    from flowcurve.identification.compression.friction_result import _friction_disagreement

    d0, h0, hk, dmax, _ = _shape(table, 0.05, 1.5)
    *_, dface = _shape(table, 0.3, 1.5)
    res = fr.identify_friction("fe_table", d0, h0, hk, d_max_mm=dmax, d_face_mm=dface)
    assert res.extra["face_bulge_disagreement_sigmas"] > mf.DISAGREE_SIGMAS
    msg = _friction_disagreement(res)
    assert msg and f"{res.mu:.3f}" in msg and f"{res.extra['mu_from_bulge']:.3f}" in msg and "poor" in msg
    agree = fr.identify_friction("fe_table", d0, h0, hk, d_max_mm=dmax, d_face_mm=_shape(table, 0.05, 1.5)[4])
    assert _friction_disagreement(agree) is None


def test_a_record_whose_face_and_bulge_disagree_has_a_poor_hardening(tmp_path):
    """The second model's C2 (μ 0.05) with an end face 0.6 mm smaller than its own (μ near 0.1
    by the face, 0.046 by the bulge): the result warns, naming both μ, and its hardening is poor;
    with its own end face it is not. The constants' standard errors count μ's and the model form's force share."""
    import shutil
    from pathlib import Path

    from flowcurve.identification.compression.identify import identify_compression
    from flowcurve.record.format import amend_record, read_record

    src = Path(__file__).parent / "data" / "second_model_C2.csv"
    own = identify_compression(read_record(src)).result
    assert own["hardening"]["quality"] == "good" and not any("disagree" in w for w in own["warnings"])
    h = own["hardening"]
    u_force = mf.force_model_form(own["friction_mu"])
    assert h["A_MPa_stderr"] >= u_force * h["A_MPa"] and h["B_MPa_stderr"] >= u_force * h["B_MPa"]
    assert "friction μ" in own["methods"]["hardening_stderr"]
    path = tmp_path / src.name
    shutil.copyfile(src, path)
    amend_record(path, {"post.dface_mm": f"{float(read_record(src).meta['post.dface_mm']) - 0.6:.4f}"})
    bad = identify_compression(read_record(path)).result
    detail = bad["friction_details"]["fe_table"]
    said = [w for w in bad["warnings"] if "disagree" in w]
    assert said and f"{bad['friction_mu']:.3f}" in said[0] and f"{detail['mu_from_bulge']:.3f}" in said[0], bad["warnings"]
    assert bad["hardening"]["quality"] == "poor"


def test_the_corrected_stress_uncertainty_grows_over_the_band_before_the_fold_over():
    """The model form's 0.12·μ before the band, linear growth to the inverse's 3 % at the onset, held beyond
    (closed form); at μ 0.3 the model form (3.6 %) is the larger and stays; no onset: the model form alone."""
    onset = 0.5
    eps = np.array([0.2, onset - mf.FOLD_OVER_BAND, onset - mf.FOLD_OVER_BAND / 2, onset, 0.7])
    u_mf = 100 * 0.12 * 0.1
    top = mf.FOLD_OVER_SIGMA_FACTOR * mf.FORCE_SIGMA_PCT
    np.testing.assert_allclose(mf.corrected_stress_uncertainty_pct(eps, 0.1, onset), [u_mf, u_mf, (u_mf + top) / 2, top, top])
    np.testing.assert_allclose(mf.corrected_stress_uncertainty_pct(eps, 0.3, onset), 3.6)
    np.testing.assert_allclose(mf.corrected_stress_uncertainty_pct(eps, 0.1, None), u_mf)


def test_the_inverse_weighs_the_fold_over_band_with_the_same_constants():
    from flowcurve.identification.fe import inverse

    assert (inverse.FOLD_OVER_SIGMA_FACTOR, inverse.FORCE_SIGMA_PCT) == (mf.FOLD_OVER_SIGMA_FACTOR, mf.FORCE_SIGMA_PCT)
    eps = np.linspace(0.1, 0.7, 13)
    np.testing.assert_allclose(inverse.force_sigma_pct(eps, 0.5), mf.FORCE_SIGMA_PCT * (1 + 2 * mf.fold_over_ramp(eps, 0.5)))

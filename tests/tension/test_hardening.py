"""Hardening laws and their fits, checked against constants known in advance."""

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import (
    fit_hardening, static_form, johnson_cook_static, swift, three_point_fit, voce,
)

EPS = np.linspace(0.002, 0.12, 80)
TRUTH = {
    "johnson_cook": {"A": 410.0, "B": 280.0, "n": 0.47},  # steel 45, table 3.2
    "swift": {"K": 950.0, "eps0": 0.012, "n": 0.21},
    "voce": {"sigma0": 320.0, "Q": 260.0, "b": 18.0},
}


def test_laws_closed_forms():
    # hand-computed values: 410 + 280·0.25^0.47, 950·1.012^0.21, 320 + 260(1 − e^{-1.8})
    assert johnson_cook_static(0.25, 410, 280, 0.47) == pytest.approx(410 + 280 * np.exp(0.47 * np.log(0.25)))
    assert johnson_cook_static(0.0, 410, 280, 0.47) == 410
    assert swift(1.0, 950, 0.012, 0.21) == pytest.approx(950 * 1.012**0.21)
    assert voce(0.1, 320, 260, 18) == pytest.approx(320 + 260 * (1 - np.exp(-1.8)))


@pytest.mark.parametrize("law", list(TRUTH))
def test_least_squares_recovers_known_constants_from_noisy_data(law):
    rng = np.random.default_rng(7)
    exact = static_form(law).func(EPS, **TRUTH[law])
    noisy = exact + rng.normal(0, 1.0, EPS.size)  # 1 MPa scatter
    fit = fit_hardening(EPS, noisy, law)
    for name, value in TRUTH[law].items():
        # within 4 standard errors and the standard error itself small
        assert abs(fit.params[name] - value) < 4 * fit.stderr[name], (name, fit.params[name], fit.stderr[name])
    assert fit.rms_error_pct < 0.5
    assert fit.strain_range == pytest.approx((EPS[0], EPS[-1]))
    assert np.allclose(fit(EPS), static_form(law).func(EPS, **fit.params))
    assert "[[Variables]]" in fit.report


def test_extra_point_pulls_the_extrapolation():
    # true law hardens on beyond the uniform range; a fit with the fracture point reproduces it
    truth = TRUTH["johnson_cook"]
    fracture = (0.9, johnson_cook_static(0.9, **truth))
    rng = np.random.default_rng(3)
    noisy = johnson_cook_static(EPS, **truth) + rng.normal(0, 2.0, EPS.size)
    with_point = fit_hardening(EPS, noisy, extra_points=[(*fracture, 10.0)])
    assert with_point(0.9) == pytest.approx(fracture[1], rel=0.01)
    assert with_point.strain_range[1] == pytest.approx(0.9)


@pytest.mark.parametrize("law", list(TRUTH))
def test_three_point_passes_through_its_points_and_matches_lsq_on_exact_data(law):
    exact = static_form(law).func(EPS, **TRUTH[law])
    idx = [0, 40, 79]
    tp = three_point_fit([(EPS[i], exact[i]) for i in idx], law)
    assert np.allclose(tp(EPS[idx]), exact[idx], rtol=1e-10)
    lsq = fit_hardening(EPS, exact, law)
    for name, value in TRUTH[law].items():
        assert tp.params[name] == pytest.approx(value, rel=1e-6)
        assert lsq.params[name] == pytest.approx(tp.params[name], rel=1e-5)
    assert tp.method == "three_point" and lsq.method == "least_squares"


def test_three_point_on_inexact_points_still_passes_exactly():
    pts = [(0.002, 500.0), (0.09, 720.0), (0.85, 1300.0)]
    tp = three_point_fit(pts)
    assert np.allclose(tp([p[0] for p in pts]), [p[1] for p in pts], rtol=1e-10)
    curve_eps = np.linspace(0.002, 0.09, 20)
    checked = three_point_fit(pts, curve=(curve_eps, 500 + 3000 * curve_eps))
    assert checked.fit_error_pct > 0


def test_as_dict_keys_carry_units():
    fit = fit_hardening(EPS, johnson_cook_static(EPS, **TRUTH["johnson_cook"]))
    d = fit.as_dict()
    for key in ("law", "method", "A_MPa", "B_MPa", "n", "A_MPa_stderr", "B_MPa_stderr", "n_stderr",
                "fit_error_pct", "rms_error_pct", "strain_range"):
        assert key in d
    assert fit_hardening(EPS, swift(EPS, **TRUTH["swift"]), "swift").as_dict()["K_MPa"] == pytest.approx(950, rel=1e-5)
    assert "sigma0_MPa" in fit_hardening(EPS, voce(EPS, **TRUTH["voce"]), "voce").as_dict()


@pytest.mark.parametrize("eps, sig, match", [
    (EPS, johnson_cook_static(EPS, 410e6, 280e6, 0.47), "check units"),
    (EPS * 100, johnson_cook_static(EPS, 410, 280, 0.47), "check units"),
    (EPS, np.full(EPS.size, 400.0) - EPS, "do not harden"),
    (EPS - 0.01, johnson_cook_static(EPS, 410, 280, 0.47), "negative plastic strain"),
])
def test_bad_input_is_a_clear_error(eps, sig, match):
    with pytest.raises(IdentificationError, match=match):
        fit_hardening(eps, sig)


def test_bad_law_and_bad_points():
    with pytest.raises(IdentificationError, match="unknown law 'ludwig' .did you mean 'ludwik'"):
        fit_hardening(EPS, EPS, "ludwig")
    with pytest.raises(IdentificationError, match="rise with strain"):
        three_point_fit([(0.002, 500), (0.1, 450), (0.8, 900)])
    with pytest.raises(IdentificationError, match="exactly 3"):
        three_point_fit([(0.002, 500), (0.1, 600)])

"""Friction identification and flow-curve corrections, checked against independent values."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flowcurve.errors import FlowcurveError, IdentificationError
from flowcurve.identification.compression import friction as fr


# -- the seed's worked example (004, 3.1.4), from the post-test measurements alone -----------


def test_seed_worked_example_from_diameter():
    res = fr.friction_bulge_regression(5.989, 6.982, 3.55, d_max_mm=8.60)
    assert res.method == "bulge_regression"
    assert res.extra["d_n_mm"] == pytest.approx(8.40, abs=0.005)  # seed: d_n = 8.40 mm
    assert res.extra["delta_R_mm"] == pytest.approx(0.10, abs=0.005)  # seed: ΔR = 0.10 mm
    assert res.extra["eps_p"] == pytest.approx(0.68, abs=0.005)  # seed: ε_p = 0.68
    assert 0.10 <= res.mu <= 0.11  # seed prints 0.11 from rounded inputs
    assert res.inputs == {"d0_mm": 5.989, "h0_mm": 6.982, "hk_mm": 3.55, "dmax_mm": 8.60}


def test_seed_worked_example_from_largest_area():
    # the seed measured S_max = 58.09 mm², "which corresponds to d_φ = 8.60 mm"
    res = fr.friction_bulge_regression(5.989, 6.982, 3.55, s_max_mm2=58.09)
    assert res.extra["d_max_mm"] == pytest.approx(8.60, abs=0.005)
    assert res.inputs["smax_mm2"] == 58.09
    assert 0.10 <= res.mu <= 0.11


# -- closed forms ------------------------------------------------------------------------------


@pytest.mark.parametrize("mu", [0.0, 0.01, 0.05, 0.11, 0.2, 0.35, 0.6])
@pytest.mark.parametrize("eps", [0.05, 0.3, 0.68, 1.2])
def test_bulge_regression_round_trip(mu, eps):
    ratio = float(fr.bulge_ratio(eps, mu))
    assert fr.mu_from_bulge_ratio(ratio, eps) == pytest.approx(mu, abs=1e-9)


def test_bulge_regression_round_trip_through_geometry():
    # build d_max from (3.18) at a known μ, then identify μ from the "measurements"
    d0, h0, hk, mu = 6.0, 7.0, 3.9, 0.17
    eps = math.log(h0 / hk)
    d_n = d0 * math.sqrt(h0 / hk)
    d_max = d_n + 2 * hk * float(fr.bulge_ratio(eps, mu))
    assert fr.friction_bulge_regression(d0, h0, hk, d_max_mm=d_max).mu == pytest.approx(mu, rel=1e-9)


def test_volume_constancy_and_area_diameter():
    d_n = fr.nominal_diameter(6.0, 7.0, np.array([7.0, 3.5]))
    assert np.allclose(math.pi * d_n**2 / 4 * np.array([7.0, 3.5]), math.pi * 36 / 4 * 7.0)
    assert float(fr.diameter_from_area(math.pi * 25 / 4)) == pytest.approx(5.0)


def test_slab_tends_to_siebel_by_its_series():
    # 2(e^c − c − 1)/c² = 1 + c/3 + c²/12 + O(c³); Siebel is the first two terms, 1 + c/3
    r_over_h = 1.3
    for mu in (1e-1, 1e-2, 1e-3, 1e-5, 1e-7):
        c = 2 * mu * r_over_h
        slab = float(fr.slab_factor(mu, r_over_h, 1.0))
        siebel = float(fr.siebel_factor(mu, r_over_h, 1.0))
        assert siebel == pytest.approx(1 + c / 3, rel=1e-14)
        # the gap is c²/12 up to the next term c³/60
        assert abs(slab - siebel - c**2 / 12) <= c**3 / 60 * 1.2 + 1e-15
    assert float(fr.slab_factor(0.0, 4.0, 3.0)) == 1.0


def test_slab_factor_against_high_precision():
    # independent: the closed form evaluated with 50 digits (no cancellation), small and large c
    mpmath = pytest.importorskip("mpmath")
    mpmath.mp.dps = 50
    for c in (1e-9, 3e-6, 9.99e-4, 1.001e-3, 0.05, 0.7, 3.0):
        cm = mpmath.mpf(c)
        ref = float(2 * (mpmath.e**cm - cm - 1) / cm**2)
        assert float(fr.slab_factor(c / 2, 1.0, 1.0)) == pytest.approx(ref, rel=1e-12)


def test_slab_factor_is_the_mean_of_the_coulomb_pressure_profile():
    # independent: integrate p(r) = σ exp(2μ(R − r)/h) over the face numerically
    mu, R, h = 0.3, 4.2, 3.5
    mean, _ = quad(lambda r: math.exp(2 * mu * (R - r) / h) * 2 * math.pi * r, 0, R)
    assert float(fr.slab_factor(mu, R, h)) == pytest.approx(mean / (math.pi * R**2), rel=1e-10)


def test_k_factors_are_one_without_friction():
    eps = np.linspace(0, 1.5, 7)
    assert np.all(fr.k_sigma(0.0, eps) == 1.0)
    assert np.all(fr.k_eps(0.0, eps) == 1.0)
    strain, stress = fr.correct_k_sigma(eps, 500 + 0 * eps, 0.0)
    assert np.all(strain == eps) and np.all(stress == 500)


def test_k_factors_at_the_seed_example_by_hand():
    # μ = 0.11, ε = 0.68 by hand from (3.24) and (3.27)
    ks = 1 + 0.2166 * 0.11 + 1.344 * 0.11 * 0.68 - 0.5512 * 0.11**2 - 1.8164 * 0.11 * 0.68**2
    ke = 1 + 4.353 * 0.11 - 1.05 * 0.68 * 0.11
    assert float(fr.k_sigma(0.11, 0.68)) == pytest.approx(ks, rel=1e-14)
    assert float(fr.k_eps(0.11, 0.68)) == pytest.approx(ke, rel=1e-14)


def test_corrections_without_friction_leave_the_curve():
    eps = np.linspace(0.01, 0.7, 20)
    p = 105 + 1392 * eps**0.642
    for name in fr.CORRECTIONS:
        s, f = fr.correct(name, eps, p, 0.0, 4.0, 3.0)
        assert np.allclose(s, eps) and np.allclose(f, p)


def test_ebrahimi_najafizadeh_hand_computed_case():
    # R0 = 3, h0 = 7, h = 3.5, R_M = 4.5 worked by hand:
    # R = 3·√2 = 4.24264; R_T = √(3·9·2 − 2·20.25) = √13.5 = 3.67423
    # b = 4·(4.5 − 3.67423)/4.24264·(3.5/3.5) = 0.778540
    # m = (4.24264/3.5)·0.778540/(4/√3 − 2·0.778540/(3√3)) = 0.943717/2.009717 = 0.469578
    res = fr.friction_ebrahimi_najafizadeh(6.0, 7.0, 3.5, d_max_mm=9.0)
    assert res.extra["R_top_mm"] == pytest.approx(3.67423, abs=2e-5)
    assert res.extra["b"] == pytest.approx(0.778540, abs=2e-6)
    assert res.extra["m"] == pytest.approx(0.469578, abs=2e-6)
    assert res.mu == pytest.approx(0.469578 / math.sqrt(3), abs=2e-6)
    # the equal-slab-pressure μ makes the exact Coulomb slab pressure equal the Tresca one
    mu_eq = res.extra["mu_equal_slab_pressure"]
    tresca = 1 + 2 * res.extra["m"] * (4.24264 / 3.5) / (3 * math.sqrt(3))
    assert float(fr.slab_factor(mu_eq, 4.242641, 3.5)) == pytest.approx(tresca, rel=1e-6)
    assert mu_eq < res.mu  # the slab pressure grows faster than Siebel's


def test_ebrahimi_najafizadeh_with_measured_top_diameter():
    res = fr.friction_ebrahimi_najafizadeh(6.0, 7.0, 3.5, d_max_mm=9.0, d_top_mm=2 * 3.67423461417)
    assert res.extra["m"] == pytest.approx(0.469578, abs=2e-6)
    assert res.inputs["dtop_mm"] == pytest.approx(7.34846922834)


def test_ebrahimi_najafizadeh_no_bulge_is_no_friction():
    d_n = 6.0 * math.sqrt(7.0 / 3.5)
    res = fr.friction_ebrahimi_najafizadeh(6.0, 7.0, 3.5, d_max_mm=d_n)
    assert res.extra["m"] == pytest.approx(0.0, abs=1e-12) and res.mu == pytest.approx(0.0, abs=1e-12)


# -- inputs outside a method's range: a clear one-line error, never NaN ------------------------


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=8.0), "negative bulge"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=9.5), "logarithm argument"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=7.0, d_max_mm=6.0), "below the initial height"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=8.0, d_max_mm=6.0), "below the initial height"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5), "post.dmax_mm"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, s_max_mm2=-3.0), "must be > 0"),
        (dict(d0_mm=-6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=9.0), "d0"),
    ],
)
def test_bulge_regression_rejects_out_of_range(kwargs, words):
    with pytest.raises(IdentificationError) as exc:
        fr.friction_bulge_regression(**kwargs)
    msg = str(exc.value)
    assert words in msg and "\n" not in msg
    assert isinstance(exc.value, FlowcurveError)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=8.0), "negative bulge"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=11.0), "too large"),
        (dict(d0_mm=6.0, h0_mm=7.0, hk_mm=3.5, d_max_mm=9.0, d_top_mm=9.4), "exceeds the maximum"),
    ],
)
def test_ebrahimi_najafizadeh_rejects_out_of_range(kwargs, words):
    with pytest.raises(IdentificationError, match=words):
        fr.friction_ebrahimi_najafizadeh(**kwargs)


def test_unknown_names_are_clear():
    with pytest.raises(IdentificationError, match="choose from"):
        fr.identify_friction("guess", 6.0, 7.0, 3.5, d_max_mm=9.0)
    with pytest.raises(IdentificationError, match="choose from"):
        fr.correct("bridgman", [0.1], [100.0], 0.1, 4.0, 3.0)
    with pytest.raises(IdentificationError, match="μ"):
        fr.correct("slab", [0.1], [100.0], float("nan"), 4.0, 3.0)


def test_no_bulge_within_reading_resolution_is_no_friction():
    d_n = 6.0 * math.sqrt(7.0 / 3.5)
    for method in fr.FRICTION_METHODS:
        assert fr.identify_friction(method, 6.0, 7.0, 3.5, d_max_mm=d_n - 0.004).mu == pytest.approx(0.0, abs=1e-12)
        with pytest.raises(IdentificationError, match="negative bulge"):
            fr.identify_friction(method, 6.0, 7.0, 3.5, d_max_mm=d_n - 0.02)

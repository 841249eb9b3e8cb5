"""The rate and temperature laws (Zerilli–Armstrong bcc and fcc, the hyperbolic-sine law with
the Zener–Hollomon parameter) against values computed here by hand from published constants
and against closed forms the laws must satisfy."""

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import get_law

R = 8.314462618  # J/(mol K)

# F. J. Zerilli, R. W. Armstrong, J. Appl. Phys. 61 (1987) 1816, constants for Armco iron (bcc)
# and OFHC copper (fcc) as that paper gives them (C3, C4 in 1/K; C0 of copper as quoted from it)
ARMCO_IRON = dict(C0=0.0, C1=1033.0, C3=0.00698, C4=0.000415, C5=266.0, n=0.289)
OFHC_COPPER = dict(C0=65.0, C2=890.0, C3=0.0028, C4=0.000115)


def test_zerilli_armstrong_bcc_equals_the_hand_computed_armco_iron_value():
    T = 20.0 + 273.15  # K: the law takes °C at its interface
    hand = 0.0 + 1033.0 * math.exp(-0.00698 * T + 0.000415 * T * math.log(1000.0)) + 266.0 * 0.1**0.289
    assert get_law("zerilli_armstrong_bcc").stress(0.1, 1000.0, 20.0, **ARMCO_IRON) == pytest.approx(hand, rel=1e-12)


def test_zerilli_armstrong_fcc_equals_the_hand_computed_ofhc_copper_value():
    T = 300.0 + 273.15
    hand = 65.0 + 890.0 * math.sqrt(0.2) * math.exp(-0.0028 * T + 0.000115 * T * math.log(0.01))
    assert get_law("zerilli_armstrong_fcc").stress(0.2, 0.01, 300.0, **OFHC_COPPER) == pytest.approx(hand, rel=1e-12)


def test_zerilli_armstrongs_structure_fcc_yield_and_bcc_hardening_do_not_depend_on_rate_or_temperature():
    # the paper's point: in fcc metals the thermal part multiplies the hardening (the yield stress at
    # εp 0 is C0 at every condition); in bcc metals the hardening C5·εp^n adds to the thermal yield
    rates, temps = np.array([[1e-3], [1.0], [1e3]]), np.array([-100.0, 20.0, 400.0])
    fcc = get_law("zerilli_armstrong_fcc").stress(0.0, rates, temps, **OFHC_COPPER)
    assert np.allclose(fcc, 65.0, rtol=1e-14)
    bcc = get_law("zerilli_armstrong_bcc")
    rise = bcc.stress(0.3, rates, temps, **ARMCO_IRON) - bcc.stress(0.0, rates, temps, **ARMCO_IRON)
    assert np.allclose(rise, 266.0 * 0.3**0.289, rtol=1e-12)


HS = dict({f"{s}{i}": 0.0 for s in ("alpha", "n", "Q", "lnA") for i in range(6)},
          alpha0=0.012, alpha1=-0.004, n0=5.0, n1=1.5, Q0=3.2e5, Q2=-4e4, lnA0=27.0, lnA3=2.0)


def _hand_constants(eps):
    return 0.012 - 0.004 * eps, 5.0 + 1.5 * eps, 3.2e5 - 4e4 * eps**2, 27.0 + 2.0 * eps**3


def test_hyperbolic_sine_equals_the_hand_computed_value_with_strain_compensation():
    eps, rate, T_C = 0.3, 0.1, 900.0
    alpha, n, Q, lnA = _hand_constants(eps)
    Z = rate * math.exp(Q / (R * (T_C + 273.15)))
    hand = math.asinh((Z / math.exp(lnA)) ** (1.0 / n)) / alpha
    assert get_law("hyperbolic_sine").stress(eps, rate, T_C, **HS) == pytest.approx(hand, rel=1e-12)


def test_hyperbolic_sine_satisfies_the_sellars_tegart_rate_equation_even_where_z_overflows_a_float():
    # ε̇ = A·sinh(ασ)^n·exp(−Q/(RT)) (Sellars & Tegart 1966) read back from the law's σ, and at
    # 20 °C (Z/A ≈ e^105) the stress from the large-argument form asinh x ≈ ln 2x
    law = get_law("hyperbolic_sine")
    eps = np.array([0.05, 0.3, 0.6])
    for rate, T_C in ((0.001, 700.0), (0.1, 900.0), (10.0, 1100.0)):
        sig = law.stress(eps, rate, T_C, **HS)
        alpha, n, Q, lnA = _hand_constants(eps)
        back = np.exp(lnA) * np.sinh(alpha * sig) ** n * np.exp(-Q / (R * (T_C + 273.15)))
        assert back == pytest.approx(np.full(3, rate), rel=1e-9)
    alpha, n, Q, lnA = _hand_constants(0.0)
    log_ZA = math.log(1.0) + Q / (R * 293.15) - lnA
    assert law.stress(0.0, 1.0, 20.0, **HS) == pytest.approx((math.log(2.0) + log_ZA / n) / alpha, rel=1e-12)


def test_the_guesses_read_the_constants_off_a_series():
    eps, rate, temp = np.meshgrid(np.linspace(0.05, 0.6, 12), [0.001, 0.01, 0.1], [700.0, 800.0, 900.0], indexing="ij")
    const = dict(HS, alpha1=0.0, n1=0.0, Q2=0.0, lnA3=0.0)  # constant coefficients: the guess's own form
    law = get_law("hyperbolic_sine")
    guess = law.guess(eps, law.stress(eps, rate, temp, **const), rate, temp)
    assert guess["Q0"] == pytest.approx(3.2e5, rel=0.05) and guess["n0"] == pytest.approx(5.0, rel=0.1)
    assert guess["alpha0"] == pytest.approx(0.012, rel=0.1)
    fcc = get_law("zerilli_armstrong_fcc")
    guess = fcc.guess(eps, fcc.stress(eps, rate, temp, **OFHC_COPPER), rate, temp)
    assert guess == pytest.approx(OFHC_COPPER, rel=1e-9)  # its thermal start is copper's: C0, C2 solved exactly
    with pytest.raises(IdentificationError, match="needs each point's strain rate and temperature"):
        fcc.guess(eps, eps)

"""The full Johnson-Cook model and its clamps against the closed form written out by hand."""

import math

import numpy as np
import pytest

from flowcurve.identification.laws.johnson_cook import homologous_temperature, johnson_cook, log_rate_ratio

P = {"A": 792.0, "B": 510.0, "n": 0.26, "C": 0.014, "m": 1.03}
R = {"ref_strain_rate_per_s": 1.0, "ref_temperature_C": 24.85, "melt_temperature_C": 1519.85}


def hand(eps, rate, T):
    """σ written out with math, the clamps as if-statements."""
    static = 792.0 + 510.0 * eps**0.26
    lnr = math.log(rate / 1.0) if rate > 1.0 else 0.0
    ts = (T - 24.85) / (1519.85 - 24.85)
    ts = 0.0 if ts < 0 else (1.0 if ts > 1 else ts)
    return static * (1 + 0.014 * lnr) * (1 - ts**1.03)


@pytest.mark.parametrize("eps,rate,T", [
    (0.1, 10.0, 400.0),       # inside the range: every bracket active
    (0.05, 1e-3, 400.0),      # rate below the reference: no rate effect
    (0.2, 50.0, -60.0),       # below the reference temperature: no thermal effect
    (0.0, 1.0, 24.85),        # the reference condition at zero strain: σ = A
    (0.3, 1e4, 1600.0),       # above melting: zero stress
])
def test_model_matches_the_closed_form(eps, rate, T):
    assert johnson_cook(eps, rate, T, **P, **R) == pytest.approx(hand(eps, rate, T), rel=1e-12, abs=1e-9)


def test_clamps_state_the_conventions():
    # below T_r: T* = 0, above T_m: T* = 1
    assert homologous_temperature([-100.0, 24.85, 1519.85, 2000.0], 24.85, 1519.85).tolist() == [0.0, 0.0, 1.0, 1.0]
    # ln ε̇* clamped at 0 below ε̇0, exact above
    assert log_rate_ratio([1e-4, 1.0, math.e**2], 1.0).tolist() == pytest.approx([0.0, 0.0, 2.0])
    # a slower test is not weaker than the reference one: same stress at 1e-3 and 1 1/s
    eps = np.linspace(0, 0.3, 7)
    np.testing.assert_allclose(johnson_cook(eps, 1e-3, 24.85, **P, **R), 792 + 510 * eps**0.26, rtol=1e-13)

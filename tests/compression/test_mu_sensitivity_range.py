"""The flow stress's μ term spans μ's stated range (issue 43): u(μ)·∂σ/∂μ is half σ's change across [lo, hi]."""

import math

import numpy as np

from flowcurve.identification.compression.friction_result import correction_mu_sensitivity
from flowcurve.identification.compression.values import _Nominal


def _nominal(d0=6.0, h0=9.0):
    h = np.linspace(h0 * 0.98, h0 * 0.55, 12)
    strain = np.log(h0 / h)
    d_n = d0 * np.sqrt(h0 / h)
    return _Nominal(springback=0.0, springback_source=None, measured=h0 - h[-1], shortening=h0 - h, K_l=1.0, h=h, strain=strain,
                    d_n=d_n, pressure=500.0 + 300.0 * strain, warnings=[])


def _siebel_sigma(nom, mu):
    """Siebel's closed form σ = p / (1 + μ·d/(3h))."""
    return nom.pressure / (1.0 + mu * nom.d_n / (3.0 * nom.h))


def test_range_secant_is_half_the_change_of_sigma_across_the_stated_range():
    nom = _nominal()
    lo, hi = 0.16, 0.35  # one-sided: μ 0.18 near sticking, the range open to the table's largest μ
    sens = correction_mu_sensitivity({"nu": 0.3}, nom, 0.18, "siebel", None, mu_range=[lo, hi])
    u_mu = (hi - lo) / 2.0
    expected = (_siebel_sigma(nom, hi) - _siebel_sigma(nom, lo)) / 2.0
    np.testing.assert_allclose(u_mu * sens, expected, rtol=1e-12)
    # the local slope at μ extrapolated over the half-width overstates: σ is convex in μ, flatter above μ
    local = correction_mu_sensitivity({"nu": 0.3}, nom, 0.18, "siebel", None)
    assert np.all(np.abs(u_mu * local) > np.abs(expected))


def test_without_a_range_the_secant_at_mu_is_siebel_s_derivative():
    nom = _nominal()
    mu = 0.1
    sens = correction_mu_sensitivity({"nu": 0.3}, nom, mu, "siebel", None, mu_range=None)
    c = nom.d_n / (3.0 * nom.h)
    np.testing.assert_allclose(sens, -nom.pressure * c / (1.0 + mu * c) ** 2, rtol=2e-3)
    # an empty range (u(μ) = 0) falls back to the same secant
    np.testing.assert_allclose(correction_mu_sensitivity({"nu": 0.3}, nom, mu, "siebel", None, mu_range=[mu, mu]), sens)
    assert math.isfinite(float(sens[0]))

"""The seed's worked relations against the integrals they come from (quadrature, not the closed forms)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flowcurve.identification.compression.adhesion import (
    HERTZ_MEAN_FACTOR,
    UNIFORM_SHEAR_WEIGHT,
    beta_at,
    contact_ratio_moment_integral,
    deformation_friction_kragelsky,
    hertz_moment_integral,
    hertz_pressure,
    mean_shear_stress,
    refined_moment,
)


def _moment_and_mean(shear, a):
    """M = 2π∫ρ²τ dρ and the area mean τ̄ = (2π∫ρτ dρ)/(πa²) of a shear distribution τ(ρ)."""
    moment = quad(lambda r: 2 * math.pi * r * r * shear(r), 0, a, epsabs=0, epsrel=1e-13)[0]
    mean = quad(lambda r: 2 * math.pi * r * shear(r), 0, a, epsabs=0, epsrel=1e-13)[0] / (math.pi * a * a)
    return moment, mean


def test_constant_of_3_35_is_the_mean_of_a_hertz_shaped_shear():
    """(3.35): for τ ∝ √(a² − ρ²), τ̄ = k·M/a³ with k = 16/(3π²) = 0.540."""
    a = 0.7
    moment, mean = _moment_and_mean(lambda r: math.sqrt(a * a - r * r), a)
    k = mean * a**3 / moment
    assert k == pytest.approx(HERTZ_MEAN_FACTOR, rel=1e-10)
    assert round(k, 3) == 0.540
    assert mean_shear_stress(moment, a) == pytest.approx(mean, rel=1e-10)


def test_3_35_reads_a_uniform_shear_as_32_over_9pi_of_itself():
    a = 0.45
    moment, mean = _moment_and_mean(lambda r: 1.0, a)
    assert mean_shear_stress(moment, a) / mean == pytest.approx(UNIFORM_SHEAR_WEIGHT, rel=1e-10)
    assert UNIFORM_SHEAR_WEIGHT == pytest.approx(1.1318, abs=1e-4)


def test_hertz_integral_of_3_39_closed_form():
    for a in (0.05, 0.3, 1.2):
        numeric = quad(lambda r: r * r * math.sqrt(a * a - r * r), 0, a, epsabs=0, epsrel=1e-13)[0]
        assert hertz_moment_integral(a) == pytest.approx(numeric, rel=1e-10)


def test_hertz_pressure_carries_the_load():
    N, a = 800.0, 0.5
    load = quad(lambda r: 2 * math.pi * r * hertz_pressure(N, a, r), 0, a, epsabs=0, epsrel=1e-12)[0]
    assert load == pytest.approx(N, rel=1e-9)


@pytest.mark.parametrize("q", [0.3, 1.0, 1.01, 1.5, 4.0])
def test_contact_ratio_integral_closed_form(q):
    """∫ρ²·min(1, q√(1 − ρ²/a²)) dρ: closed form against quadrature with the kink as a break point."""
    a = 0.6
    kink = a * math.sqrt(1 - 1 / q**2) if q > 1 else None

    def f(r):
        return r * r * min(1.0, q * math.sqrt(max(1 - (r / a) ** 2, 0.0)))

    numeric = quad(f, 0, a, points=[kink] if kink else None, epsabs=0, epsrel=1e-12, limit=200)[0]
    assert contact_ratio_moment_integral(a, q) == pytest.approx(numeric, rel=1e-9)


def test_refined_moment_full_contact_against_quadrature_of_2_25():
    """K_r = 1: M = 2π∫ρ²(μ_d·σ_n + τ0 + β·σ_n)dρ with the Hertz σ_n, hot β included."""
    N, a, T = 600.0, 0.42, 750.0
    tau0, beta0, kb, thk, mud = 60.0, 0.06, 2e-4, 700.0, 0.03
    beta = beta0 - kb * (T - thk)
    numeric = quad(lambda r: 2 * math.pi * r * r * (tau0 + (beta + mud) * hertz_pressure(N, a, r)), 0, a, epsabs=0, epsrel=1e-12)[0]
    assert refined_moment(N, a, T, tau0, beta0, kb, thk, 500.0, mud, model="none") == pytest.approx(numeric, rel=1e-9)


def test_beta_hinge():
    assert beta_at([20.0, 700.0, 800.0], 0.05, 1e-4, 700.0) == pytest.approx([0.05, 0.05, 0.04])


def test_kragelsky_mu_d_at_the_mean_line():
    """At K_r = t_m the bearing curve reaches the mean line: h = R_p, μ_d = 0.55·√(R_p/r_a)."""
    assert deformation_friction_kragelsky(0.2, 0.5, 50.0, 0.5) == pytest.approx(0.55 * math.sqrt(0.2 / 50.0))
    # the penetration grows with the contact ratio as (K_r/t_m)^(1/ν): μ_d as its square root
    ratio = deformation_friction_kragelsky(0.2, 0.5, 50.0, 0.125, bearing_exponent=2.0) / deformation_friction_kragelsky(0.2, 0.5, 50.0, 0.5)
    assert ratio == pytest.approx(np.sqrt(np.sqrt(0.25)))

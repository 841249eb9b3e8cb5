"""The virtual adhesiometer's forward model against closed forms it does not use."""

from __future__ import annotations

import math

import pytest

from flowcurve.errors import DeviceError
from flowcurve.rig.virtual.adhesiometer import FrictionTruth, VirtualAdhesiometer


def test_coulomb_moment_is_johnsons_closed_form():
    """τ = μ·σ_n under the Hertz pressure: M = (3π/16)·μ·N·a (Johnson, Contact Mechanics, §7.4)."""
    dev = VirtualAdhesiometer(truth=FrictionTruth(tau0_MPa=0.0, beta0=0.0, k_b_per_C=0.0, mu_d=0.1), contact="full")
    N, a = 700.0, 0.45
    assert dev.moment_N_mm(N, a, 20.0) == pytest.approx(3 * math.pi / 16 * 0.1 * N * a, rel=1e-9)


def test_uniform_shear_moment():
    """τ = τ0 everywhere: M = (2π/3)·τ0·a³."""
    dev = VirtualAdhesiometer(truth=FrictionTruth(tau0_MPa=50.0, beta0=0.0, k_b_per_C=0.0, mu_d=0.0), contact="full")
    assert dev.moment_N_mm(300.0, 0.3, 20.0) == pytest.approx(2 * math.pi / 3 * 50.0 * 0.3**3, rel=1e-9)


def test_partial_contact_below_the_flow_pressure_is_coulomb_like():
    """Bowden–Tabor contact with σ_n < 3Y everywhere: τ = (τ0/(3Y) + β + μ_d)·σ_n, a Coulomb law."""
    truth = FrictionTruth(tau0_MPa=60.0, beta0=0.04, mu_d=0.02)
    dev = VirtualAdhesiometer(truth=truth, contact="bowden_tabor")
    Y = dev.surface_flow_stress_MPa(20.0)
    a = 0.5
    N = 0.9 * 3 * Y * 2 * math.pi * a * a / 3  # Hertz peak 0.9·3Y
    mu = truth.tau0_MPa / (3 * Y) + truth.beta0 + truth.mu_d
    assert dev.moment_N_mm(N, a, 20.0) == pytest.approx(3 * math.pi / 16 * mu * N * a, rel=1e-8)


def test_imprint_radius_balances_the_load_and_pressure_stays_in_the_plastic_range():
    dev = VirtualAdhesiometer()
    Y = dev.surface_flow_stress_MPa(20.0)
    for N in (5.0, 100.0, 1000.0, 3000.0):
        a = dev.imprint_radius_mm(N, 20.0)
        pm = N / (math.pi * a * a)
        assert pm == pytest.approx(dev.mean_pressure_MPa(a, 20.0), rel=1e-8)
        assert 1.1 * Y <= pm <= 3.0 * Y * (1 + 1e-12)
    assert dev.mean_pressure_MPa(dev.imprint_radius_mm(3000.0, 20.0), 20.0) == pytest.approx(3.0 * Y)


def test_an_elastic_contact_leaves_no_imprint():
    with pytest.raises(DeviceError, match="no permanent imprint"):
        VirtualAdhesiometer().imprint_radius_mm(0.5, 20.0)


def test_hot_material_is_softer():
    dev = VirtualAdhesiometer()
    assert dev.surface_flow_stress_MPa(800.0) < 0.6 * dev.surface_flow_stress_MPa(20.0)

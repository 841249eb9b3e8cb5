"""The flow curve CalculiX realises from a *PLASTIC table, and the rows that realise a law.

A one-element CAX4R cylinder compressed with no contact is homogeneous: its Cauchy stress is
the top reaction over the loaded area, both read from the solver. Against that closed form
the plain rows read low by an amount that scales with σ/E (so the solver's, not the law's),
and the rows of :func:`realising_rows` reproduce the law.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from flowcurve.identification.fe.model.realised_law import realised_curve, realising_rows
from flowcurve.identification.fe.model.deck import plastic_table
from flowcurve.identification.fe.model.upsetting import UpsettingModel

pytestmark = [pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]


def seed_law(eps_p):
    return 105.0 + 1392.0 * np.power(np.clip(eps_p, 0.0, None), 0.642)  # the seed's (3.34)


H0, H_END, INCREMENTS = 7.2, 7.2 * math.exp(-0.7), 70  # the seed-law record's strain path


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))


def deviation(rows, E_MPa, at=np.array([0.1, 0.3, 0.6]), increments=INCREMENTS):
    e, s = realised_curve(*rows, E_MPa=E_MPa, nu=0.3, h0_mm=H0, h_end_mm=H_END, increments=increments, first_increment=1.0 / 3000)
    return np.interp(at, e, s / seed_law(e) - 1.0)


def test_plain_rows_read_low_by_the_increment_size_and_by_stress_over_modulus():
    rows = plastic_table(seed_law)
    # measured at ε 0.1, 0.3, 0.6: −0.28, −0.40, −0.53 % (70 increments); −0.12, −0.20, −0.28 % (700);
    # with E ten times higher and 700 increments −0.06, −0.09, −0.11 % (the rows' chords remain)
    coarse, fine = deviation(rows, 194_000.0), deviation(rows, 194_000.0, increments=700)
    stiff = deviation(rows, 1_940_000.0, increments=700)
    assert np.all(coarse < -0.002) and coarse[-1] < -0.004
    assert np.all(fine - coarse > 0.001)  # the increment size
    assert np.all(stiff - fine > 0.0005) and stiff[-1] - fine[-1] > 0.001  # σ/E


def test_realising_rows_reproduce_the_law():
    eps, sig = plastic_table(seed_law)
    rows = realising_rows(eps, sig, E_MPa=194_000.0, nu=0.3, h0_mm=H0, h_end_mm=H_END, increments=INCREMENTS, first_increment=1.0 / 3000)
    assert np.all(rows >= sig)  # raised: the solver reads its rows low
    again = deviation((eps, rows), 194_000.0, at=np.linspace(0.05, 0.65, 13))
    assert np.max(np.abs(again)) < 7e-4  # measured ≤ 0.05 % (the chords between rows remain)


@pytest.mark.slow
def test_an_upsetting_model_realising_its_law_at_mu_0_gives_the_law_on_the_loaded_area():
    """The whole upsetting model on the records' mesh (O-grid, platen, contact) at μ = 0 with the
    realising rows: F over the loaded area is the law (measured within 0.1 %; the plain rows
    −0.5 % at ε 0.6)."""
    from flowcurve.identification.fe.model.upsetting import simulate_upsetting
    from flowcurve.identification.compression.friction import elastic_volume_ratio

    m = UpsettingModel.from_law(6.0, H0, H_END, 0.0, seed_law, E_MPa=194_000.0, increments=INCREMENTS, first_increment=1.0 / 3000)
    errors = []
    for r in (simulate_upsetting(m), simulate_upsetting(m.realising())):
        area_constant = math.pi * 36.0 * H0 / (4.0 * r.height_mm)
        sigma = r.force_N / area_constant  # first on the volume-constant area, then on the loaded one
        sigma = r.force_N / (area_constant * elastic_volume_ratio(sigma, 194_000.0, 0.3))
        eps_p = r.strain - sigma / 194_000.0
        sel = (eps_p > 0.05) & (eps_p < 0.65)
        errors.append(np.max(np.abs(sigma[sel] / seed_law(eps_p[sel]) - 1.0)))
    assert errors[1] < 0.0015 and errors[0] > 0.004

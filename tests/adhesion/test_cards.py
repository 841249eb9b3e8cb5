"""Friction cards read back by readers of their own (Abaqus) and ansys-dyna-core (LS-DYNA);
μ compared with the law (2.25) evaluated here by hand from the constants."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from flowcurve.reports.friction_cards import FrictionCardError, friction_card

LAW = {"method": "simple", "tests_used": 24, "tau0_MPa": 80.0, "beta0": 0.05, "k_b_per_C": 1e-4, "theta_k_C": 650.0,
       "mu_d": 0.02, "sigma_S_MPa": 500.0, "hot_constants_source": "fitted",
       "range": {"nominal_mean_pressure_MPa": [600.0, 1500.0], "temperature_C": [20.0, 800.0]}}


def mu_by_hand(p, T):
    beta = 0.05 - 1e-4 * max(0.0, T - 650.0)
    return (80.0 + (beta + 0.02) * p) / p


def _abaqus_blocks(text):
    """Keyword file → [(KEYWORD, data rows)], '**' comments skipped."""
    blocks = []
    for line in text.splitlines():
        if line.startswith("**") or not line.strip():
            continue
        if line.startswith("*"):
            blocks.append((line[1:].split(",")[0].strip().upper(), []))
        else:
            blocks[-1][1].append([float(f) for f in line.split(",")])
    return blocks


@pytest.mark.parametrize("units, stress_factor", [("mm-s-t-N-MPa", 1.0), ("m-s-kg-N-Pa", 1e6), ("mm-ms-kg-kN-GPa", 1e-3)])
def test_abaqus_friction_table(units, stress_factor):
    text = friction_card(LAW, "abaqus", units)
    assert text.isascii()
    blocks = _abaqus_blocks(text)
    assert [b[0] for b in blocks] == ["SURFACE INTERACTION", "FRICTION"]
    rows = np.array(blocks[1][1])
    assert rows.shape[1] == 4  # mu, slip rate, pressure, temperature
    assert np.all(rows[:, 1] == 0.0)
    temps = list(dict.fromkeys(rows[:, 3]))
    assert temps[0] == 20.0 and temps[-1] == 800.0 and 650.0 in temps  # θ_k tabulated: linear in T is exact
    for mu, _, p, T in rows:
        assert mu == pytest.approx(mu_by_hand(p / stress_factor, T), rel=1e-7)
    # pressure increases fastest within each temperature
    for T in temps:
        p = rows[rows[:, 3] == T, 2]
        assert np.all(np.diff(p) > 0) and p[0] == pytest.approx(600.0 * stress_factor) and p[-1] == pytest.approx(1500.0 * stress_factor)
    assert "identified on nominal mean pressure 600..1500 MPa" in text.replace("\n** ", " ").replace("  ", " ")


def test_lsdyna_contact_and_table_read_by_ansys_dyna_core():
    dyna = pytest.importorskip("ansys.dyna.core", reason="ansys-dyna-core (the independent keyword reader) is not installed")
    text = friction_card(LAW, "lsdyna", "mm-s-t-N-MPa", at_pressure_MPa=1000.0, at_temperature_C=700.0)
    assert text.isascii()
    deck = dyna.Deck()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        deck.loads(text)
    by_type = {}
    for kw in deck.keywords:
        by_type.setdefault(type(kw).__name__, []).append(kw)
    contact = by_type["ContactAutomaticSurfaceToSurface"][0]
    assert contact.fs == pytest.approx(mu_by_hand(1000.0, 700.0), rel=1e-5)
    assert contact.fd == contact.fs
    assert contact.vc == pytest.approx(500.0 / math.sqrt(3.0), rel=1e-5)
    table = by_type["DefineTable"][0]
    curves = by_type["DefineCurve"]  # in the table's order, right after it
    temperatures = [float(v) for v in table.points]
    assert len(curves) == len(temperatures) and temperatures[0] == 20.0 and temperatures[-1] == 800.0
    for T, c in zip(temperatures, curves):
        curve = c.curves
        for p, mu in zip(curve["a1"], curve["o1"]):
            assert mu == pytest.approx(mu_by_hand(p, T), rel=1e-5)


def test_lsdyna_without_sigma_S_has_no_stress_limit():
    law = {**LAW, "sigma_S_MPa": None}
    text = friction_card(law, "lsdyna", "mm-s-t-N-MPa")
    assert "VC = 0 (sigma_S not identified" in text


def test_card_needs_the_constants():
    with pytest.raises(FrictionCardError, match="lacks tau0_MPa"):
        friction_card({k: v for k, v in LAW.items() if k != "tau0_MPa"}, "abaqus")

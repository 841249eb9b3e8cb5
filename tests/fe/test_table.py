"""The shipped CalculiX upsetting table: provenance, limits, and the low-friction closed form.

At small μ and while the specimen is still nearly cylindrical (the slab solution assumes no
barrel), the Coulomb slab solution p/σ_f = 2(e^c − c − 1)/c², c = 2μr/h, is close to the FE
force factor (the CalculiX check in tests/compression found them within 1 % at μ = 0.1 up to
ε 0.5); the table, made by another route (full FE runs normalised by μ = 0), must agree with
it there. Beyond, tall barrelled specimens fall below the slab factor (measured: −1.6 % at
h0/d0 1.6, μ 0.1, ε 0.6), which is what the FE table is for.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification import friction as fr
from flowcurve.identification.fe.table import UpsettingTable, effective_hardening_exponent, specimen_proportion


@pytest.fixture(scope="module")
def table():
    return UpsettingTable.load()


def test_provenance_names_the_solver_mesh_and_command(table):
    meta = table.meta
    assert meta["ccx_version"].startswith("ccx 2.")
    assert meta["mesh"]["nr"] > 0 and meta["increments"] > 0 and "make_table" in meta["command"] and meta["date"]
    assert table.force_factor.shape == table.bulge.shape == (table.mu.size, table.h0_d0.size, table.n.size, table.strain.size)


@pytest.mark.parametrize("mu", [0.05, 0.1])
@pytest.mark.parametrize("h0_d0", [0.6, 1.0, 1.6])
def test_force_factor_matches_the_slab_solution_at_low_friction(table, mu, h0_d0):
    eps = np.linspace(0.1, 0.4, 7)
    h = h0_d0 * np.exp(-eps)  # d0 = 1
    r = 0.5 * np.sqrt(h0_d0 / h)
    fe = table.force_factor_at(mu, h0_d0, 0.2, eps)
    slab = fr.slab_factor(mu, r, h)
    assert np.all(np.abs(fe / slab - 1.0) < 0.01), fe / slab


def test_frictionless_row_and_monotone_friction(table):
    assert np.allclose(table.force_factor_at(0.0, 1.3, 0.3, [0.2, 0.5]), 1.0)
    b = [float(table.bulge_at(mu, 1.3, 0.3, [0.5])[0]) for mu in (0.0, 0.05, 0.1, 0.2, 0.3)]
    assert b[0] == pytest.approx(0.0, abs=1e-9) and np.all(np.diff(b) > 0)


def test_bulge_inverts_off_the_grid(table):
    b = float(table.bulge_at(0.12, 1.3, 0.33, [0.55])[0])
    assert table.mu_from_bulge(b, 1.3, 0.33, 0.55) == pytest.approx(0.12, abs=2e-3)


def test_out_of_range_is_one_line(table):
    with pytest.raises(IdentificationError, match="h0/d0 = 3"):
        table.mu_from_bulge(0.01, 3.0, 0.3, 0.5)
    with pytest.raises(IdentificationError, match="beyond the table"):
        table.mu_from_bulge(0.01, 1.0, 0.3, 1.5)


def test_effective_exponent_and_proportion_closed_forms():
    e = np.linspace(0.05, 0.8, 50)
    assert effective_hardening_exponent(e, 700 * e**0.37) == pytest.approx(0.37, abs=1e-9)
    h0, d0 = 9.0, 6.0
    eps = np.array([0.1, 0.4])
    h = h0 * np.exp(-eps)
    assert specimen_proportion(eps, d0 / 2 * np.sqrt(h0 / h), h) == pytest.approx(1.5)


def test_fe_table_friction_reads_its_own_bulge(table):
    """A barrel built from the table's bulge at μ = 0.15 reads back as 0.15 (no curve: n = 0.3)."""
    d0, h0, hk = 6.0, 9.0, 4.5
    eps = math.log(h0 / hk)
    dmax = d0 * math.sqrt(h0 / hk) + 2 * hk * float(table.bulge_at(0.15, 1.5, 0.3, [eps])[0])
    res = fr.identify_friction("fe_table", d0, h0, hk, d_max_mm=dmax)
    assert res.mu == pytest.approx(0.15, abs=2e-3) and res.extra["hardening_from"] == "default"

"""The CalculiX runner and the upsetting/tension decks against closed forms.

μ = 0 upsetting stays a homogeneous cylinder: the force is σ_f(ε_p)·A(h) with A = π d0² h0/(4h)
and ε_p = ln(h0/h) − σ/E (docs/calculix.md: the O-grid model is within 0.3–0.6 % of it), and the
outer diameter is d0·√(h0/h) (volume constancy). A deck ccx rejects, or a run that stops
before the end of the step, must raise a one-line SolverError even when ccx exits 0.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from scipy.optimize import brentq

from flowcurve.identification.fe.model.ccx import SolverError, run_deck
from flowcurve.identification.fe.model.realised_law import one_element_deck
from flowcurve.identification.fe.model.deck import plastic_table
from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

pytestmark = [pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]

E = 200_000.0


def swift(eps_p):
    return 900.0 * np.power(0.01 + np.clip(eps_p, 0.0, None), 0.25)


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))


def test_frictionless_upsetting_is_the_homogeneous_closed_form():
    m = UpsettingModel.from_law(6.0, 6.0, 3.6, 0.0, swift, E_MPa=E, nr=8, layer_fraction=1.0 / 12.0, increments=20)  # quick: a coarse mesh
    r = simulate_upsetting(m)
    assert r.completed and r.time[-1] == pytest.approx(1.0)
    eps = r.strain
    sel = eps > 0.05
    area = math.pi * 9.0 * 6.0 / r.height_mm[sel]
    # closed form: σ = σ_f(ε − σ/E) solved per point
    sigma = np.array([brentq(lambda s: s - swift(e - s / E), 1.0, 5000.0) for e in eps[sel]])
    ratio = r.force_N[sel] / (sigma * area)
    assert np.all(np.abs(ratio - 1.0) < 0.006), ratio
    assert np.allclose(r.dmax_mm[sel], 6.0 * np.sqrt(6.0 / r.height_mm[sel]), rtol=2e-3)
    # the second call is served from the cache, the same numbers
    again = simulate_upsetting(m)
    assert again.cached and np.array_equal(again.force_N, r.force_N)


def test_loaded_area_shrinks_by_the_elastic_volume_change():
    """Plastic flow keeps the volume, the elastic strains do not: CalculiX's loaded cylinder has
    the area A·J of :func:`elastic_volume_ratio`, J = exp(−(1 − 2ν)σ/E), below the volume-constant
    A = A0·h0/h — the reference the FE table's force factor (normalised by μ = 0) was taken on."""
    from flowcurve.identification.compression.friction import elastic_volume_ratio

    E_soft, nu = 80_000.0, 0.3  # a low modulus: J − 1 ≈ −0.5 % at 1000 MPa, well above the check's 0.02 %
    eps_rows, stress_rows = plastic_table(swift)
    deck = one_element_deck(eps_rows, stress_rows, radius_mm=3.0, height_mm=3.0, h_end_mm=3.0 * math.exp(-0.4), E_MPa=E_soft, nu=nu, increments=40)
    out = run_deck(deck, name="one element", use_cache=False)
    h = 3.0 + (3.0 * math.exp(-0.4) - 3.0) * out.time
    radius = 3.0 + out.displacements["OUTER"][:, -1, 0]
    sigma = -out.totals["TOP"][:, 1] * 180.0 / (math.pi * radius**2)  # the 2° sector's reaction, on the loaded area
    loaded_over_constant = radius**2 / (9.0 * 3.0 / h)
    sel = sigma > 500.0
    assert sel.sum() > 10 and np.all(1.0 - elastic_volume_ratio(sigma[sel], E_soft, nu) > 2e-3)
    np.testing.assert_allclose(loaded_over_constant[sel], elastic_volume_ratio(sigma[sel], E_soft, nu), rtol=2e-4)


def test_a_deck_ccx_rejects_is_a_solver_error():
    with pytest.raises(SolverError, match="failed|no results"):
        run_deck("*HEADING\nbroken\n*NODE\n1,0,0\n*STEP\n*STATIC\n*END STEP\n", name="broken", use_cache=False)


def test_a_run_stopped_before_the_end_is_reported_not_returned():
    # a 1000 % compression of one element cannot converge: ccx gives up with cutbacks
    m = UpsettingModel.from_law(6.0, 6.0, 0.05, 0.3, swift, E_MPa=E, nr=4, increments=2)
    with pytest.raises(SolverError, match="did not converge|failed"):
        simulate_upsetting(m, timeout_s=120)


@pytest.mark.slow
def test_tension_force_maximum_is_at_considere_strain():
    """Before the neck F = σ_f·A0·l0/l; the maximum force where dσ/dε = σ (Considère): for
    Swift σ = K(ε0 + ε_p)^n that is ε_p = n − ε0 (0.24 here)."""
    from flowcurve.identification.fe.model.tension import TensionModel, simulate_tension

    m = TensionModel.from_law(6.0, 30.0, 9.0, swift, E_MPa=E, increments=60)
    r = simulate_tension(m)
    eps = np.log(1.0 + r.elongation_mm / 30.0)
    imax = int(np.argmax(r.force_N))
    eps_p_max = eps[imax] - r.force_N[imax] / (9.0 * math.pi * np.exp(-eps[imax])) / E
    assert eps_p_max == pytest.approx(0.24, abs=0.03)
    early = (eps > 0.02) & (eps < 0.15)
    sigma = np.array([brentq(lambda s: s - swift(e - s / E), 1.0, 5000.0) for e in eps[early]])
    closed = sigma * 9.0 * math.pi * np.exp(-eps[early])
    assert np.all(np.abs(r.force_N[early] / closed - 1.0) < 0.012)  # the 0.5 % radius imperfection costs ≤ 1 %
    assert r.neck_radius_mm[-1] < 0.8 * 3.0  # a neck formed

"""The flow stress budget's μ term takes the sensitivity of the friction correction actually applied
(issue 43: Siebel's ∂σ/∂μ overstated the fe_table correction's, a blanket on the CalculiX records).

Checked against Siebel's closed form, against the virtual rig's own copy of the CalculiX runs (code of
the rig layer, not the product's table) and through a whole identification."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from flowcurve.identification.compression.friction_result import MU_SENSITIVITY_STEP, correction_mu_sensitivity
from flowcurve.identification.quality import uncertainty as un

D0, H0 = 6.0, 7.0


def _nominal(pressure_of):
    """A nominal curve (strain ε = ln(h0/h), volume-constant diameter, mean pressure p(ε, h, d))."""
    strain = np.linspace(0.01, 0.7, 140)
    h = H0 * np.exp(-strain)
    d_n = D0 * np.sqrt(H0 / h)
    return SimpleNamespace(strain=strain, h=h, d_n=d_n, pressure=pressure_of(strain, h, d_n))


def test_siebel_sensitivity_is_its_closed_form():
    """σ = p/(1 + μk), k = d/(3h): ∂σ/∂μ = −p·k/(1 + μk)² (the secant of ±0.01 within 1e-3)."""
    nominal = _nominal(lambda e, h, d: 900.0 * e ** 0.3 * (1 + 0.1 * d / (3 * h)))
    mu = 0.1
    k = nominal.d_n / (3 * nominal.h)
    closed = -nominal.pressure * k / (1 + mu * k) ** 2
    got = correction_mu_sensitivity({"nu": 0.3}, nominal, mu, "siebel", None)
    assert got == pytest.approx(closed, rel=1e-3)


def test_fe_table_sensitivity_is_the_fe_runs_not_siebels():
    """A Swift curve pressed as the virtual rig's CalculiX copy makes it (p = σ·f(μ, h0/d0, n, ε)): the fe_table
    correction's ∂σ/∂μ is −σ·∂ln f/∂μ of that copy over ε 0.05–0.25 (within 10 %; further on the factor hardly moves with
    μ near 0.2 and the two copies' readings of n part), and from ε 0.3 on it is less than half of Siebel's, which the
    budget used before."""
    from flowcurve.rig.virtual.fe_response import UpsettingResponse

    table, n, mu = UpsettingResponse.load(), 0.3, 0.2
    law = lambda e: 800.0 * (0.002 + e) ** n  # noqa: E731
    nominal = _nominal(lambda e, h, d: law(e) * table.force_factor_at(mu, H0 / D0, n, e))
    got = correction_mu_sensitivity({"nu": 0.3}, nominal, mu, "fe_table", None)
    s = MU_SENSITIVITY_STEP
    f_lo, f_hi = (table.force_factor_at(m, H0 / D0, n, nominal.strain) for m in (mu - s, mu + s))
    independent = -law(nominal.strain) * np.log(f_hi / f_lo) / (2 * s)  # −σ·∂ln f/∂μ, the secant of the same span
    sel = (nominal.strain >= 0.05) & (nominal.strain <= 0.25)
    assert got[sel] == pytest.approx(independent[sel], rel=0.10)
    siebel = un.flow_stress_budget(800.0, 0.5, D0, H0, 3.5, un.INSTRUMENT_DEFAULTS, mu=mu, u_mu=0.01)["components"][4]["sensitivity"] / 800.0
    late = nominal.strain >= 0.3
    assert np.all(np.abs(got[late] / law(nominal.strain[late])) < 0.5 * abs(siebel))


def test_budget_uses_the_given_sensitivity():
    """With ``mu_sensitivity`` the μ term is u(μ)·|∂σ/∂μ| as given; without it Siebel's (the old budget)."""
    sigma, eps, mu, u_mu = 700.0, 0.4, 0.15, 0.02
    given = un.flow_stress_budget(sigma, eps, D0, H0, 3.6, un.INSTRUMENT_DEFAULTS, mu=mu, u_mu=u_mu, mu_sensitivity=-123.0)
    term = next(c for c in given["components"] if c["name"] == "friction μ")
    assert term["sensitivity"] == -123.0 and term["contribution"] == pytest.approx(123.0 * u_mu)
    h = H0 * math.exp(-eps)
    k = D0 * math.sqrt(H0 / h) / (3 * h)
    old = next(c for c in un.flow_stress_budget(sigma, eps, D0, H0, 3.6, un.INSTRUMENT_DEFAULTS, mu=mu, u_mu=u_mu)["components"]
               if c["name"] == "friction μ")
    assert old["sensitivity"] == pytest.approx(-sigma * k / (1 + mu * k))


def test_identification_states_the_applied_correction_s_sensitivity():
    """A closed-form record at μ 0.2 made with the CalculiX runs' friction (tests/series/compression_series.py):
    every flow stress budget's μ term carries the fe_table curve's ∂σ/∂μ at its strain, not Siebel's."""
    import warnings

    from flowcurve.identification.identify import identify
    from tests.series.compression_series import compression_record

    record, _ = compression_record(300.0, 0.05, mu=0.2, response="fe", reading_mm=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ident = identify(record)
    curve = ident.curves["true_fe_table"]
    flow = ident.result["uncertainty"]["flow_stress_MPa"]
    assert flow
    for at, b in flow.items():
        term = next(c for c in b["components"] if c["name"] == "friction μ")
        expected = np.interp(float(at), curve["true_plastic_strain"], curve["dsigma_dmu_MPa"])
        assert term["sensitivity"] == pytest.approx(expected) and "applied correction" in term["basis"]

"""A read off the curve at the break (no post.lu_mm) states a U: its sensitivities are the derivatives of the
method's own formula (iso6892.gauge_extension_at_fracture, then 100·(e_g − s_k/E)), taken here numerically."""

import pytest

from flowcurve.identification import iso6892
from flowcurve.identification.quality.uncertainty import elongation_from_curve_budget

TERMS = {"strain_at_fracture": 0.43, "stress_at_fracture_MPa": 1400.0, "E_MPa": 196_000.0, "sample_step_strain": 0.002,
         "length_mm": 42.0, "l0_mm": 30.0, "uniform_plastic_elongation": 0.365}


def A_of(e_L=TERMS["strain_at_fracture"], E=TERMS["E_MPa"], a_u=TERMS["uniform_plastic_elongation"]):
    s_k = TERMS["stress_at_fracture_MPa"]
    e_g = iso6892.gauge_extension_at_fracture(e_L, TERMS["length_mm"], TERMS["l0_mm"], a_u, s_k, E)
    return float(iso6892.plastic_extension_pct(e_g, s_k, E))


def _derivative(f, x, h):
    return (f(x + h) - f(x - h)) / (2.0 * h)


def test_sensitivities_are_the_formulas_derivatives():
    b = elongation_from_curve_budget(A_of(), TERMS, strain_rel_u=0.0115, u_E_MPa=2000.0, u_a_u=0.01)
    by = {c["name"]: c for c in b["components"]}
    assert by["strain scale at the break"]["sensitivity"] == pytest.approx(_derivative(lambda x: A_of(e_L=x), 0.43, 1e-5), rel=1e-3)
    assert by["E of the elastic part removed"]["sensitivity"] == pytest.approx(_derivative(lambda x: A_of(E=x), 196_000.0, 10.0), rel=1e-3)
    assert by["uniform elongation beyond the marks a_u"]["sensitivity"] == pytest.approx(
        _derivative(lambda x: A_of(a_u=x), 0.365, 1e-5), rel=1e-3)
    assert by["strain scale at the break"]["u"] == pytest.approx(0.43 * 0.0115)
    assert by["the break within one sample's travel"]["u"] == pytest.approx(0.002 / 12 ** 0.5)


def test_a_parallel_length_equal_to_the_gauge_has_no_uniform_term():
    terms = dict(TERMS, length_mm=30.0, uniform_plastic_elongation=None)
    b = elongation_from_curve_budget(40.0, terms, strain_rel_u=0.01, u_E_MPa=2000.0)
    assert [c["name"] for c in b["components"]] == ["strain scale at the break", "E of the elastic part removed",
                                                    "the break within one sample's travel"]

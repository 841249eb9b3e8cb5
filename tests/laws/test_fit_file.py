"""law_of_fit: one reader of fit.json's law for v1 (Johnson–Cook top-level keys) and v2 (the "law" block)."""

import math

import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws import base
from flowcurve.identification.laws.base import Law, Parameter
from flowcurve.identification.laws.fit_file import law_of_fit

V1 = {"schema": "flowcurve-fit/1", "model": "johnson_cook", "A_MPa": 90.0, "B_MPa": 292.0, "n": 0.31, "C": 0.025,
      "m": 1.09, "ref_strain_rate_per_s": 1e-3, "ref_temperature_C": 20.0, "melt_temperature_C": 1083.0}


class _Linear(Law):
    """σ = s0 + k·εp (a test law, registered for one test only)."""

    name = "_test_linear_fitfile"
    display_name = "linear (test)"
    parameters = (Parameter("s0", "s0_MPa", "MPa", 0.0, 1e4), Parameter("k", "k_MPa", "MPa", 0.0, 1e5))
    equation = latex = source = "test"

    def evaluate(self, eps_p, strain_rate_per_s, temperature_C, *, s0, k):
        return s0 + k * eps_p


def test_a_v1_file_reads_as_johnson_cook_from_its_top_level_keys():
    law, values = law_of_fit(V1)
    assert law.name == "johnson_cook"
    assert values == {"A": 90.0, "B": 292.0, "n": 0.31, "C": 0.025, "m": 1.09, "ref_strain_rate_per_s": 1e-3,
                      "ref_temperature_C": 20.0, "melt_temperature_C": 1083.0}
    hand = (90 + 292 * 0.1**0.31) * (1 + 0.025 * math.log(1.0 / 1e-3)) * (1 - (280.0 / 1063.0) ** 1.09)
    assert law.stress(0.1, 1.0, 300.0, **values) == pytest.approx(hand, rel=1e-12)


def test_a_v2_file_reads_as_its_law_not_the_top_level_keys(monkeypatch):
    base.registered_laws()
    monkeypatch.setitem(base._REGISTRY, _Linear.name, _Linear())
    fit = {**V1, "schema": "flowcurve-fit/2", "model": "_test_linear_fitfile",
           "law": {"name": "_test_linear_fitfile", "display_name": "linear (test)", "equation": "test",
                   "parameters": {"s0_MPa": 100.0, "k_MPa": 50.0}, "stderr": {"s0_MPa": 1.0, "k_MPa": None},
                   "conditions": {}, "temperature_unit": "C"}}
    law, values = law_of_fit(fit)
    assert law.name == "_test_linear_fitfile" and values == {"s0": 100.0, "k": 50.0}
    assert law.stress(0.2, **values) == pytest.approx(110.0)


def test_a_missing_value_or_unknown_schema_is_a_one_line_error():
    with pytest.raises(IdentificationError, match="no value for m"):
        law_of_fit({k: v for k, v in V1.items() if k != "m"})
    with pytest.raises(IdentificationError, match="schema 'flowcurve-fit/9'"):
        law_of_fit({**V1, "schema": "flowcurve-fit/9"})
    with pytest.raises(IdentificationError, match="unknown law"):
        law_of_fit({**V1, "schema": "flowcurve-fit/2", "law": {"name": "nolaw", "parameters": {}, "conditions": {}}})

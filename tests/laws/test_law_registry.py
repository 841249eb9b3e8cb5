"""The law registry (identification/laws/base.py): every law found without a list, evaluated
through one interface, with named errors."""

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.base import Law, get_law, registered_laws

JC = dict(A=300.0, B=500.0, n=0.3, C=0.02, m=1.0, ref_strain_rate_per_s=1e-3, ref_temperature_C=20.0,
          melt_temperature_C=1500.0)


def test_johnson_cook_through_the_registry_equals_the_hand_computed_value():
    # (2.19) at εp 0.1, ε̇ 1 1/s, 300 °C, evaluated here by hand
    hand = (300 + 500 * 0.1**0.3) * (1 + 0.02 * math.log(1.0 / 1e-3)) * (1 - (280.0 / 1480.0) ** 1.0)
    assert get_law("johnson_cook").stress(0.1, 1.0, 300.0, **JC) == pytest.approx(hand, rel=1e-12)


def test_every_registered_law_carries_what_the_cards_and_docs_need():
    laws = registered_laws()
    assert "johnson_cook" in laws
    for name, law in laws.items():
        assert isinstance(law, Law) and law.name == name
        assert law.display_name and law.equation and law.latex and law.source and law.parameters
        keys = [p.key for p in law.parameters + law.conditions]
        assert len(set(keys)) == len(keys)
        for p in law.parameters + law.conditions:
            assert p.lower < p.upper
            if p.unit:  # a dimensioned constant carries its unit in its JSON key
                assert p.key != p.name or p.name.endswith(("_per_s", "_C", "_K")), (name, p.name)


def test_keys_round_trip_and_bounds_are_named():
    jc = get_law("johnson_cook")
    assert jc.from_keys(jc.to_keys(JC)) == JC
    assert jc.to_keys(JC)["A_MPa"] == 300.0
    with pytest.raises(IdentificationError, match="n = 3 is outside"):
        jc.check({**JC, "n": 3.0})


def test_an_unknown_law_or_a_missing_value_is_a_one_line_error():
    with pytest.raises(IdentificationError, match="did you mean 'johnson_cook'"):
        get_law("johnsoncook")
    with pytest.raises(IdentificationError, match="no value for m"):
        get_law("johnson_cook").stress(0.1, 1.0, 20.0, **{k: v for k, v in JC.items() if k != "m"})
    with pytest.raises(IdentificationError, match="strain rate"):
        get_law("johnson_cook").stress(0.1, None, 20.0, **JC)


def test_the_stress_broadcasts_and_clips_negative_strain():
    out = get_law("johnson_cook").stress(np.array([-0.1, 0.0, 0.2]), np.array([[1e-3], [1.0]]), 20.0, **JC)
    assert out.shape == (2, 3)
    assert out[0, 0] == out[0, 1] == pytest.approx(300.0)

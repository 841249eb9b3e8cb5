"""A series states the Type A spread of its repeats (issue 43): per condition, at fixed plastic strains,
the repeats' standard deviation s, u = s/√n and U with Student's t at n − 1 degrees of freedom."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import t

from flowcurve.identification.series.fit import condition_curves
from flowcurve.identification.series.members import SeriesMember

EPS = np.linspace(0.002, 0.3, 200)


def _member(name, shift_MPa, rate=0.001, T=20.0):
    return SeriesMember(name, EPS, 400.0 + 500.0 * EPS ** 0.4 + shift_MPa, rate, T)


def test_three_repeats_give_the_type_a_budget_by_hand():
    curves = condition_curves([_member("a", -6.0), _member("b", 0.0), _member("c", 9.0), _member("hot", 0.0, T=300.0)])
    cold = next(c for c in curves if c.temperature_C == 20.0)
    assert next(c for c in curves if c.temperature_C == 300.0).repeats is None  # one record: no Type A
    b = cold.repeats["0.1"]
    values = np.array([-6.0, 0.0, 9.0]) + 400.0 + 500.0 * 0.1 ** 0.4
    s = values.std(ddof=1)
    assert b["value"] == pytest.approx(values.mean(), rel=1e-5) and b["s_MPa"] == pytest.approx(s, rel=1e-3)
    assert b["u"] == pytest.approx(s / math.sqrt(3), rel=1e-3) and b["k"] == pytest.approx(t.ppf(0.975, 2))
    assert b["U"] == pytest.approx(t.ppf(0.975, 2) * s / math.sqrt(3), rel=1e-3) and "ν_eff = 2.0" in b["coverage"]
    assert set(cold.repeats) == {"0.002", "0.05", "0.1", "0.2", "0.3"}

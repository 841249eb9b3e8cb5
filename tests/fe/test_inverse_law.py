"""The inverse FE fit's law when none is given: the one that best fits the fast curve. Checked on
closed-form curves of each law (with 0.3 % noise) — the law that made the curve must win."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from flowcurve.identification.fe.inverse import best_law_for
from flowcurve.identification.fe.synthetic import johnson_cook_flow, swift_flow, voce_flow

CURVES = {
    "johnson_cook": lambda e: johnson_cook_flow(e, A=105.0, B=1392.0, n=0.642),
    "swift": lambda e: swift_flow(e, K=800.0, eps0=0.01, n=0.3),
    "voce": lambda e: voce_flow(e, s0=300.0, q=400.0, b=5.0),
}


@pytest.mark.parametrize("law", list(CURVES))
def test_the_law_that_made_the_curve_is_chosen(law):
    e = np.linspace(0.002, 0.65, 300)
    s = CURVES[law](e) * (1.0 + np.random.default_rng(3).normal(0.0, 0.003, e.size))
    chosen, rms = best_law_for(pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": s}))
    assert chosen == law, rms
    assert set(rms) == set(CURVES) and rms[law] < 0.5

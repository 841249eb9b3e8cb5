"""Hensel–Spittel (identification/laws/hensel_spittel.py) against a hand-computed value, its guess
against the law that made the data, and the terms a series cannot support fixed at 0."""

import math

import numpy as np
import pytest

from flowcurve.identification.laws.base import get_law

HS = dict(A=1800.0, m1=-0.0028, m2=0.20, m3=0.12, m4=-0.008, m5=0.0001, m7=-0.6, m8=0.0001, m9=0.05)


def test_the_law_equals_the_hand_computed_value():
    eps, rate, T = 0.2, 0.01, 800.0
    hand = (1800.0 * math.exp(-0.0028 * T) * T**0.05 * eps**0.2 * math.exp(-0.008 / eps) * (1 + eps) ** (0.0001 * T)
            * math.exp(-0.6 * eps) * rate**0.12 * rate ** (0.0001 * T))
    assert get_law("hensel_spittel").stress(eps, rate, T, **HS) == pytest.approx(hand, rel=1e-12)


def test_the_guess_recovers_the_law_from_its_own_values():
    law = get_law("hensel_spittel")
    e, r, t = np.meshgrid(np.linspace(0.02, 0.8, 40), [1e-3, 1e-2, 1e-1], [700.0, 800.0, 900.0], indexing="ij")
    e, r, t = e.ravel(), r.ravel(), t.ravel()
    got = law.guess(e, law.stress(e, r, t, **HS), r, t)
    assert law.stress(e, r, t, **got) == pytest.approx(law.stress(e, r, t, **HS), rel=1e-6)


def test_terms_a_series_cannot_tell_are_fixed_at_zero_and_named():
    law = get_law("hensel_spittel")
    e = np.linspace(0.02, 0.8, 20)
    one_t = law.unsupported(e, np.full(e.size, 0.01), np.full(e.size, 800.0))
    assert set(one_t) == {"m1", "m5", "m8", "m9", "m3"} and "one temperature" in one_t["m1"]
    two_t = law.unsupported(np.tile(e, 2), np.repeat([0.01, 0.1], e.size), np.repeat([700.0, 800.0], e.size))
    assert set(two_t) == {"m9"}
    guess = law.guess(e, law.stress(e, 0.01, 800.0, **HS), 0.01, 800.0)
    assert all(guess[k] == 0.0 for k in one_t)

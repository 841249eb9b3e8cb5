"""Fixed-width fields: never longer than the field, never truncated, as exact as they can be."""

import numpy as np
import pytest

from flowcurve.reports.cards import CardError, fixed


@pytest.mark.parametrize("width, rel", [(10, 5e-6), (20, 1e-15)])
def test_random_values_fit_and_read_back(width, rel):
    rng = np.random.default_rng(7)
    values = rng.choice([-1, 1], 2000) * 10.0 ** rng.uniform(-15, 15, 2000) * rng.uniform(1, 10, 2000)
    for v in values:
        text = fixed(v, width)
        assert len(text) == width
        assert float(text) == pytest.approx(v, rel=rel if v > 0 else max(rel, 5e-4))


@pytest.mark.parametrize("value", [280.0, 7.85e-9, 0.642, 1673.15, 4.6e8, 0.25])
def test_ordinary_values_are_exact_and_apart(value):
    text = fixed(value)
    assert float(text) == value
    assert text[0] == " "  # a blank keeps it apart from the field before


def test_integers_and_blanks():
    assert fixed(101) == "       101"
    assert fixed(None) == " " * 10
    with pytest.raises(CardError):
        fixed(12345678901)
    with pytest.raises(CardError):
        fixed(float("nan"))

"""Fixed-width fields: never longer than the field, never truncated, as exact as they can be."""

import numpy as np
import pytest

from flowcurve.reports.cards import CardError, fixed


def best_digits(value, room):
    """Significant digits of the longest plain or e-notation spelling of ``value`` within
    ``room`` characters (worked out here, independently of the writer)."""
    for d in range(17, 0, -1):
        mantissa, exponent = f"{value:.{d - 1}e}".split("e")
        e_text = f"{mantissa}e{int(exponent)}"
        plain = f"{value:.{d}g}"
        plain += "" if "." in plain else "."  # a real field needs its decimal point
        if len(e_text) <= room or ("e" not in plain and len(plain) <= room):
            return d
    return 0


@pytest.mark.parametrize("width", [10, 20])
def test_random_values_fit_apart_and_read_back(width):
    rng = np.random.default_rng(7)
    values = rng.choice([-1, 1], 2000) * 10.0 ** rng.uniform(-15, 15, 2000) * rng.uniform(1, 10, 2000)
    for v in values:
        text = fixed(v, width)
        assert len(text) == width and text[0] == " "  # never fused with the field before
        digits = best_digits(v, width - 1)
        assert float(text) == pytest.approx(v, rel=0.51 * 10.0 ** (1 - digits))


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

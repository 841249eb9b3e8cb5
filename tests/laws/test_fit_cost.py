"""The hardening fits' cheaper paths (issue 43) give the numbers of the paths they replace: the
forward-difference Jacobian is scipy's "2-point" one, bit for bit, inside and at the bounds."""

import numpy as np
import pytest

from flowcurve.identification.laws.hardening import forward_jacobian, johnson_cook_static

EPS = np.linspace(0.004, 0.3, 30)
SIG = johnson_cook_static(EPS, 300.0, 600.0, 0.35)
LO, HI = np.array([0.0, 0.0, 0.01]), np.array([np.inf, np.inf, 2.0])


def residual(x):
    """Residuals of A + B·εp^n against the closed-form curve."""
    return johnson_cook_static(EPS, *x) - SIG


@pytest.mark.parametrize("x", [[310.0, 580.0, 0.4], [0.0, 580.0, 0.4], [310.0, 580.0, 2.0 - 1e-12], [310.0, 580.0, 0.01]],
                         ids=["inside", "on the lower bound", "at the upper bound", "on a lower bound > 0"])
def test_forward_jacobian_is_scipys_two_point_difference(x):
    from scipy.optimize._numdiff import approx_derivative

    x = np.array(x)
    expected = approx_derivative(residual, x, method="2-point", bounds=(LO, HI), f0=residual(x))
    got = forward_jacobian(residual, x, LO, HI)
    assert np.array_equal(got, expected)
    assert got.flags.f_contiguous  # laid out as scipy's, so the solver's linear algebra rounds alike


def test_a_trust_region_fit_with_it_ends_where_scipys_own_difference_does():
    from scipy.optimize import least_squares

    x0 = np.array([250.0, 700.0, 0.5])
    plain = least_squares(residual, x0, bounds=(LO, HI), x_scale="jac")
    fast = least_squares(residual, x0, jac=lambda x: forward_jacobian(residual, x, LO, HI), bounds=(LO, HI), x_scale="jac")
    assert np.array_equal(plain.x, fast.x) and plain.nfev == fast.nfev
    assert fast.x == pytest.approx([300.0, 600.0, 0.35], rel=1e-6)

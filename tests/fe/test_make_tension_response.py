"""The pure measurements the virtual rig's tension response is made of (no solver): each against
a closed form obtained another way."""

import math

import numpy as np
import pytest

from flowcurve.identification.fe.make_tension_response import (end_axial_strain, increasing, neck_elongation_over_d0,
                                                                neck_force_factor, neck_plastic_strain, profile_a_over_R)


@pytest.mark.parametrize("a_mm,R_mm,rel", [(2.0, 20.0, 1e-3), (2.5, 10.0, 3e-3), (2.0, 5.0, 2e-2)])
def test_profile_fit_reads_the_radius_of_a_circular_neck(a_mm, R_mm, rel):
    # a circular arc of radius R through the neck r(0) = a, sampled as the deck's surface nodes
    # would be; the quartic term takes up the arc's z⁴ part while the window 1.5·a is small
    # against R (measured: −0.0 % at a/R 0.1, −0.14 % at 0.25, −1.2 % at 0.4, −14 % at 0.6,
    # where the window nearly reaches R: the FE necks pass a/R 0.4 only 0.55–0.8 of strain past
    # their onset; the virtual materials break at 0.22–0.24)
    z = np.linspace(0.0, 15.0, 81)
    inside = z < R_mm
    r = a_mm + R_mm - np.sqrt(R_mm**2 - z[inside] ** 2)
    assert profile_a_over_R(z[inside], r, a_mm) == pytest.approx(a_mm / R_mm, rel=rel)


def test_profile_fit_needs_four_nodes_in_its_window():
    z = np.array([0.0, 1.0, 2.0, 8.0, 9.0])
    assert math.isnan(profile_a_over_R(z, 3.0 + 0.01 * z**2, 1.0))  # window 1.5 mm: 2 nodes


def test_uniform_bar_strains_and_force_factor():
    # a uniform bar at plastic strain 0.2 and stress 600 MPa: radius a = a0·exp(−ε_p/2 − ν σ/E)
    E, nu, a0, eps_p, sigma = 200e3, 0.3, 3.0, 0.2, 600.0
    a = a0 * math.exp(-eps_p / 2 - nu * sigma / E)
    force = sigma * math.pi * a * a
    assert neck_plastic_strain(a, a0, force, E, nu) == pytest.approx(eps_p, abs=1e-12)
    assert end_axial_strain(a, a0, force, E, nu) == pytest.approx(eps_p + sigma / E, abs=1e-12)
    assert neck_force_factor(force, a, sigma) == pytest.approx(1.0, abs=1e-12)
    # a uniform gauge adds no neck: Δl = l0·(e^ε − 1)
    assert neck_elongation_over_d0(30.0 * math.expm1(eps_p + sigma / E), eps_p + sigma / E, 30.0, 6.0) == pytest.approx(0.0, abs=1e-12)


def test_increasing_keeps_only_new_maxima():
    assert increasing([0.0, 0.1, 0.1, 0.05, 0.2, 0.3]).tolist() == [True, True, False, False, True, True]

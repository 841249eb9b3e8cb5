"""Unit systems: hand-checked values and round trips through every system."""

import math

import numpy as np
import pytest

from flowcurve.reports.units import UNIT_SYSTEMS, UnitSystem, UnitsError, convert, get_unit_system


# Values worked out by hand from the definitions (1 t = 1000 kg, 1 mm = 1e-3 m, ...).
HAND_CHECKED = [
    ("mm-s-t-N-MPa", 7850.0, "kg_per_m3", 7.85e-9),
    ("mm-ms-kg-kN-GPa", 7850.0, "kg_per_m3", 7.85e-6),
    ("m-s-kg-N-Pa", 7850.0, "kg_per_m3", 7850.0),
    ("mm-ms-g-N-MPa", 7850.0, "kg_per_m3", 7.85e-3),
    ("mm-s-t-N-MPa", 1.0, "MPa", 1.0),
    ("mm-ms-kg-kN-GPa", 1.0, "MPa", 1e-3),
    ("m-s-kg-N-Pa", 1.0, "MPa", 1e6),
    ("mm-s-t-N-MPa", 1.0, "per_s", 1.0),
    ("mm-ms-kg-kN-GPa", 1.0, "per_s", 1e-3),
    ("mm-s-t-N-MPa", 460.0, "J_per_kgK", 4.6e8),
    ("mm-ms-kg-kN-GPa", 460.0, "J_per_kgK", 460.0),  # mm²/ms² = m²/s²
    ("m-s-kg-N-Pa", 460.0, "J_per_kgK", 460.0),
    ("mm-s-t-N-MPa", 16.0, "W_per_mK", 16.0),  # N/(s·K) in both
    ("mm-ms-kg-kN-GPa", 16.0, "W_per_mK", 16e-6),  # kN·mm/ms/mm/K = 1e6 W/(m·K)
    ("mm-s-t-N-MPa", 1.0, "J", 1e3),  # 1 J = 1000 N·mm
    ("mm-ms-kg-kN-GPa", 1.0, "J", 1.0),  # kN·mm = J
    ("mm-s-t-N-MPa", 1.0, "N", 1.0),
    ("mm-ms-kg-kN-GPa", 1.0, "N", 1e-3),
]


@pytest.mark.parametrize("system, value, unit, expected", HAND_CHECKED)
def test_hand_checked_values(system, value, unit, expected):
    assert convert(value, unit, system) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("name", sorted(UNIT_SYSTEMS))
def test_round_trip_through_every_system(name):
    system = UNIT_SYSTEMS[name]
    rng = np.random.default_rng(1)
    values = rng.uniform(-1e3, 1e3, 20)
    from flowcurve.reports.units import DIMENSIONS

    for quantity in DIMENSIONS:
        # SI → system → SI
        np.testing.assert_allclose(system.to_si(system.to_system(values, quantity), quantity), values, rtol=1e-14)
        # system A → SI → system B → SI agrees with the direct route
        for other in UNIT_SYSTEMS.values():
            via_b = other.to_si(other.to_system(system.to_si(values, quantity), quantity), quantity)
            np.testing.assert_allclose(via_b, system.to_si(values, quantity), rtol=1e-14)


@pytest.mark.parametrize("name", sorted(UNIT_SYSTEMS))
def test_derived_units_are_consistent(name):
    """Newton's law and stress = force/area hold in the system's own numbers."""
    s = UNIT_SYSTEMS[name]
    m_si, a_si = 2.5, 9.81  # kg, m/s²
    force = s.to_system(m_si * a_si, "force")
    mass = s.to_system(m_si, "mass")
    accel = s.to_system(a_si, "length") / s.to_system(1.0, "time") ** 2
    assert force == pytest.approx(mass * accel, rel=1e-12)
    area = s.to_system(3e-6, "area")
    assert s.to_system(m_si * a_si / 3e-6, "stress") == pytest.approx(force / area, rel=1e-12)
    # energy = force × length, conductivity = power / (length·K)
    assert s.to_system(7.0, "energy") == pytest.approx(s.to_system(7.0, "force") * s.to_system(1.0, "length"), rel=1e-12)


def test_inconsistent_name_is_refused():
    with pytest.raises(UnitsError, match="millinewton|not the kN"):
        UnitSystem.parse("mm-s-kg-kN-GPa")


def test_unknown_system_names_the_choices():
    with pytest.raises(UnitsError, match="mm-s-t-N-MPa"):
        get_unit_system("furlong-fortnight")


def test_temperature_absolute_or_celsius():
    assert UnitSystem.temperature(20.0, absolute=True) == pytest.approx(293.15)
    assert UnitSystem.temperature(20.0, absolute=False) == 20.0
    assert math.isclose(UnitSystem.temperature(-273.15, absolute=True), 0.0, abs_tol=1e-12)

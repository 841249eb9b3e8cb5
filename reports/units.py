"""Consistent unit systems for solver decks, derived from their base units.

A solver has no units: the numbers in a deck only agree with each other when every
quantity is expressed in one *consistent* system, fixed by three base units (length, time,
mass). Force, stress, density, specific heat, ... follow from those three; nothing here is a
hand-typed conversion table. Each system also states the force and stress units its name
promises, and :class:`UnitSystem` refuses a name that its base units do not deliver (which
is why the popular-sounding ``mm-s-kg-kN-GPa`` is not offered: kg·mm/s² is a millinewton).

Values enter in SI (``to_system``) and leave in SI (``to_si``); lab quantities such as
``stress_MPa`` are converted to SI first by :func:`from_lab`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flowcurve.errors import FlowcurveError

ABSOLUTE_ZERO_C = -273.15


class UnitsError(FlowcurveError):
    """An unknown unit system or quantity, or an inconsistent unit system."""


# Quantity → exponents of (length, time, mass, temperature difference).
DIMENSIONS: dict[str, tuple[int, int, int, int]] = {
    "length": (1, 0, 0, 0),
    "time": (0, 1, 0, 0),
    "mass": (0, 0, 1, 0),
    "temperature_difference": (0, 0, 0, 1),
    "dimensionless": (0, 0, 0, 0),
    "area": (2, 0, 0, 0),
    "volume": (3, 0, 0, 0),
    "velocity": (1, -1, 0, 0),
    "strain_rate": (0, -1, 0, 0),
    "frequency": (0, -1, 0, 0),  # Radioss' filter cut-off F_cut
    "force": (1, -2, 1, 0),
    "stress": (-1, -2, 1, 0),
    "energy": (2, -2, 1, 0),
    "power": (2, -3, 1, 0),
    "density": (-3, 0, 1, 0),
    "specific_heat": (2, -2, 0, -1),  # J/(kg·K) = m²/(s²·K)
    "volumetric_heat_capacity": (-1, -2, 1, -1),  # J/(m³·K), Radioss' rho·Cp
    "conductivity": (1, -3, 1, -1),  # W/(m·K)
    "expansion": (0, 0, 0, -1),  # 1/K
    "stiffness": (0, -2, 1, 0),  # N/m
}

# The force and stress units a system's name may promise, in SI.
NAMED_FORCE_N = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "MN": 1e6}
NAMED_STRESS_PA = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9}
NAMED_LENGTH_M = {"m": 1.0, "mm": 1e-3, "cm": 1e-2}
NAMED_TIME_S = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
NAMED_MASS_KG = {"kg": 1.0, "t": 1e3, "g": 1e-3}


@dataclass(frozen=True)
class UnitSystem:
    """A consistent system named ``length-time-mass-force-stress`` (e.g. ``mm-s-t-N-MPa``).

    Temperatures are in kelvin-sized degrees; whether a deck writes them in °C or K is
    the card writer's choice (:meth:`temperature`).
    """

    name: str
    length_m: float
    time_s: float
    mass_kg: float
    force_name: str
    stress_name: str

    def __post_init__(self):
        force = self.scale("force")
        stress = self.scale("stress")
        promised_force = NAMED_FORCE_N[self.force_name]
        promised_stress = NAMED_STRESS_PA[self.stress_name]
        if not (math.isclose(force, promised_force, rel_tol=1e-12) and math.isclose(stress, promised_stress, rel_tol=1e-12)):
            raise UnitsError(
                f"unit system {self.name}: its base units give force {force:g} N and stress {stress:g} Pa, "
                f"not the {self.force_name} and {self.stress_name} its name promises"
            )

    @classmethod
    def parse(cls, name: str) -> "UnitSystem":
        """Build a system from its name ``length-time-mass-force-stress``."""
        parts = name.strip().split("-")
        if len(parts) != 5:
            raise UnitsError(f"unit system {name!r}: expected length-time-mass-force-stress, e.g. mm-s-t-N-MPa")
        length, time, mass, force, stress = parts
        tables = ((length, NAMED_LENGTH_M, "length"), (time, NAMED_TIME_S, "time"), (mass, NAMED_MASS_KG, "mass"),
                  (force, NAMED_FORCE_N, "force"), (stress, NAMED_STRESS_PA, "stress"))
        for unit, table, what in tables:
            if unit not in table:
                raise UnitsError(f"unit system {name!r}: unknown {what} unit {unit!r} (known: {', '.join(table)})")
        return cls(name, NAMED_LENGTH_M[length], NAMED_TIME_S[time], NAMED_MASS_KG[mass], force, stress)

    def scale(self, quantity: str) -> float:
        """Size of this system's unit of ``quantity`` in SI (e.g. stress in mm-s-t → 1e6 Pa)."""
        try:
            a, b, c, _ = DIMENSIONS[quantity]
        except KeyError:
            raise UnitsError(f"unknown quantity {quantity!r} (known: {', '.join(DIMENSIONS)})") from None
        return self.length_m**a * self.time_s**b * self.mass_kg**c

    def to_system(self, value_si, quantity: str):
        """An SI value expressed in this system."""
        return value_si / self.scale(quantity)

    def to_si(self, value, quantity: str):
        """A value in this system expressed in SI."""
        return value * self.scale(quantity)

    @staticmethod
    def temperature(value_C, absolute: bool):
        """A temperature for a deck: kelvin if the solver wants absolute temperatures, else °C."""
        return value_C - ABSOLUTE_ZERO_C if absolute else value_C


UNIT_SYSTEMS: dict[str, UnitSystem] = {
    name: UnitSystem.parse(name)
    for name in ("mm-s-t-N-MPa", "mm-ms-kg-kN-GPa", "m-s-kg-N-Pa", "mm-ms-g-N-MPa")
}
DEFAULT_UNIT_SYSTEM = "mm-s-t-N-MPa"


def get_unit_system(name: str) -> UnitSystem:
    """The named system; a one-line error listing the known ones otherwise."""
    try:
        return UNIT_SYSTEMS[name]
    except KeyError:
        raise UnitsError(f"unknown unit system {name!r} (choose one of: {', '.join(UNIT_SYSTEMS)})") from None


# Lab quantities (as named in result.json / fit.json) → (SI quantity, factor to SI).
LAB_UNITS: dict[str, tuple[str, float]] = {
    "MPa": ("stress", 1e6),
    "GPa": ("stress", 1e9),
    "kg_per_m3": ("density", 1.0),
    "J_per_kgK": ("specific_heat", 1.0),
    "W_per_mK": ("conductivity", 1.0),
    "per_K": ("expansion", 1.0),
    "per_s": ("strain_rate", 1.0),
    "mm": ("length", 1e-3),
    "N": ("force", 1.0),
    "J": ("energy", 1.0),
}


def from_lab(value, unit: str):
    """A lab value (``unit`` as in a key suffix: ``MPa``, ``kg_per_m3``, ``per_s`` ...) → (SI value, quantity)."""
    try:
        quantity, factor = LAB_UNITS[unit]
    except KeyError:
        raise UnitsError(f"unknown lab unit {unit!r} (known: {', '.join(LAB_UNITS)})") from None
    return value * factor, quantity


def convert(value, unit: str, system: UnitSystem | str):
    """A lab value (``stress_MPa`` → unit ``MPa``) expressed in a deck's unit system."""
    if isinstance(system, str):
        system = get_unit_system(system)
    value_si, quantity = from_lab(value, unit)
    return system.to_system(value_si, quantity)

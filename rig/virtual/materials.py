"""A small library of virtual materials for the virtual rig (docs/methods.md §5, seed tables 1.1, 3.2).

Each :class:`Material` carries Johnson–Cook flow-stress constants (table 3.2), elastic
constants (table 1.1) and a fracture strain, so that :mod:`flowcurve.rig.virtual.physics` can produce the
record a real specimen of that steel would give. Values not printed in the seed are marked
*assumed* and chosen to be plausible; they are the "truth" of the virtual rig, not data.

Conventions (also those a card written from identified constants must state):

* flow stress ``σ = (A + B·εp^n)·(1 + C·ln ε̇*)·(1 − T*^m)`` in MPa, ε̇* = ε̇/ε̇0 with no rate
  effect below ε̇0 (ε̇* clamped to ≥ 1), T* = (T − T_r)/(T_m − T_r) clamped to [0, 1];
* ε̇0 = 1e-3 /s (*assumed*: a quasi-static reference, so the rig's 2e-4…6e-2 /s show the
  rate term), T_r = 20 °C, T_m *assumed* per steel;
* fracture strain (true, ln F0/Fk) at the reference state from the reduction of area ψ of
  table 1.1, ``ε_f0 = −ln(1 − ψ)``, scaled by the Johnson–Cook D4 (rate) and D5
  (temperature) factors of table 3.2: ``ε_f = ε_f0·(1 + D4·ln ε̇*)·(1 + D5·T*)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from flowcurve.errors import ConfigError


@dataclass(frozen=True)
class Material:
    """A virtual material: Johnson–Cook hardening, elasticity and ductility."""

    name: str
    A_MPa: float
    B_MPa: float
    n: float
    C: float
    m: float
    E_MPa: float
    nu: float
    fracture_strain: float  # true strain ln(F0/Fk) at the reference rate and temperature
    D4: float = 0.0
    D5: float = 0.0
    eps_dot0_per_s: float = 1e-3
    T_ref_C: float = 20.0
    T_melt_C: float = 1450.0
    density_kg_per_m3: float = 7800.0

    def homologous(self, temperature_C):
        """T* = (T − T_r)/(T_m − T_r), clamped to [0, 1]."""
        t = (np.asarray(temperature_C, dtype=float) - self.T_ref_C) / (self.T_melt_C - self.T_ref_C)
        return np.clip(t, 0.0, 1.0)

    def rate_ratio(self, strain_rate_per_s):
        """ε̇* = ε̇/ε̇0, clamped to ≥ 1 (no rate effect below ε̇0)."""
        return np.maximum(np.asarray(strain_rate_per_s, dtype=float) / self.eps_dot0_per_s, 1.0)

    def rate_temperature_factor(self, strain_rate_per_s, temperature_C):
        """(1 + C·ln ε̇*)·(1 − T*^m), the Johnson–Cook multiplier of (2.19)."""
        return (1.0 + self.C * np.log(self.rate_ratio(strain_rate_per_s))) * (
            1.0 - self.homologous(temperature_C) ** self.m)

    def flow_stress(self, eps_p, strain_rate_per_s=0.0, temperature_C=20.0):
        """# (2.19) Johnson–Cook flow stress in MPa at plastic strain eps_p (≥ 0)."""
        eps = np.maximum(np.asarray(eps_p, dtype=float), 0.0)
        return (self.A_MPa + self.B_MPa * eps ** self.n) * self.rate_temperature_factor(
            strain_rate_per_s, temperature_C)

    def hardening_slope(self, eps_p, strain_rate_per_s=0.0, temperature_C=20.0):
        """dσ/dεp in MPa (derivative of (2.19) in εp; infinite at εp = 0 when n < 1)."""
        eps = np.asarray(eps_p, dtype=float)
        with np.errstate(divide="ignore"):
            return self.n * self.B_MPa * eps ** (self.n - 1.0) * self.rate_temperature_factor(
                strain_rate_per_s, temperature_C)

    def fracture_strain_at(self, strain_rate_per_s=0.0, temperature_C=20.0) -> float:
        """# (2.22) rate and temperature factors of Johnson–Cook fracture on ε_f0."""
        rate = math.log(float(self.rate_ratio(strain_rate_per_s)))
        factor = (1.0 + self.D4 * rate) * (1.0 + self.D5 * float(self.homologous(temperature_C)))
        return max(self.fracture_strain * factor, 1e-3)

    @property
    def bulk_modulus_MPa(self) -> float:
        """K = E/(3(1 − 2ν))."""
        return self.E_MPa / (3.0 * (1.0 - 2.0 * self.nu))


def _from_reduction_of_area(psi_pct: float) -> float:
    """True fracture strain from the reduction of area ψ: ε_f = −ln(1 − ψ) (3.13)."""
    return -math.log(1.0 - psi_pct / 100.0)


MATERIALS: dict[str, Material] = {
    m.name: m
    for m in (
        # Steel 45 (GOST 1050): table 3.2 JC, table 1.1 E 200 GPa, ν 0.26, ψ 40 %; T_m assumed.
        Material("steel45", 410.0, 280.0, 0.47, 0.0037, 1.1, 200e3, 0.26,
                 _from_reduction_of_area(40.0), D4=0.063, D5=2.8, T_melt_C=1480.0,
                 density_kg_per_m3=7800.0),
        # 12Kh18N10T: table 3.2 JC, table 1.1 E 180 GPa, ν 0.3, ψ 55 %; T_m assumed.
        Material("12Kh18N10T", 280.0, 1215.0, 0.43, 0.031, 1.0, 180e3, 0.3,
                 _from_reduction_of_area(55.0), D4=-0.015, D5=-0.5, T_melt_C=1420.0,
                 density_kg_per_m3=7920.0),
        # 12Kh18N12M3TL (cast): table 3.2 JC, table 1.1 E 194 GPa, ν 0.25, ψ 30 %; T_m assumed.
        Material("12Kh18N12M3TL", 105.0, 1392.0, 0.642, 0.01, 0.517, 194e3, 0.25,
                 _from_reduction_of_area(30.0), D4=-0.029, D5=-0.3, T_melt_C=1400.0,
                 density_kg_per_m3=7820.0),
    )
}

_ALIASES = {"45": "steel45", "steel 45": "steel45", "steel_45": "steel45"}


def get_material(name: str | Material, **overrides) -> Material:
    """The material called ``name`` (case-insensitive), with fields replaced by ``overrides``.

    >>> get_material("12Kh18N12M3TL", fracture_strain=1.0).fracture_strain
    1.0
    """
    if isinstance(name, Material):
        material = name
    else:
        key = _ALIASES.get(str(name).strip().lower(), str(name).strip())
        by_lower = {k.lower(): v for k, v in MATERIALS.items()}
        if key.lower() not in by_lower:
            raise ConfigError(f"material: unknown virtual material '{name}' "
                              f"(known: {', '.join(MATERIALS)})")
        material = by_lower[key.lower()]
    if overrides:
        unknown = set(overrides) - set(Material.__dataclass_fields__)
        if unknown:
            raise ConfigError(f"material: unknown field(s) {', '.join(sorted(unknown))}")
        material = replace(material, **overrides)
    return material

"""Radioss block-format card: /MAT/PLAS_JOHNS (law 2, Johnson–Cook).

Fields of 20 characters (10 for the integer flags), one card per line. Radioss wants
absolute temperatures (its default reference is 298 K) and the volumetric heat capacity
ρ·Cp; ε̇0 is per the deck's time unit. The material's unit system must match the model's
/BEGIN input units.
"""

from __future__ import annotations

from flowcurve.reports.cards import CardData, comment_block, fixed, header_lines
from flowcurve.reports.units import UnitSystem

MAT_ID = 1


def row(*fields) -> str:
    """One line of (value, width) fields."""
    return "".join(fixed(v, w) for v, w in fields).rstrip()


def radioss_card(data: CardData, units: UnitSystem, **_ignored) -> str:
    """The /MAT/PLAS_JOHNS block (rate and temperature dependent; no failure strain or stress cap)."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    cp = units.to_system(data.require("specific_heat_J_per_kgK"), "specific_heat")
    rho_cp = rho * cp  # volumetric heat capacity, the unit system's own ρ·Cp
    A, B = (units.to_system(v * 1e6, "stress") for v in (data.A_MPa, data.B_MPa))
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    t_melt = units.temperature(data.require("melt_temperature_C"), absolute=True)
    t_ref = units.temperature(data.ref_temperature_C, absolute=True)
    time_unit = units.name.split("-")[1]
    out = [comment_block(header_lines(data, units, "Radioss", f"temperatures in K, strain rates per {time_unit}"), "# ").rstrip("\n")]
    out += [
        "# EPS_p_max, SIG_max0, T_max left 0 (Radioss default 1e30: no failure, no stress cap).",
        f"/MAT/PLAS_JOHNS/{MAT_ID}",
        data.material[:100],
        "#              RHO_I",
        row((rho, 20)),
        "#                  E                  nu     Iflag",
        row((E, 20), (nu, 20), (0, 10)),
        "#                  a                   b                   n           EPS_p_max            SIG_max0",
        row((A, 20), (B, 20), (data.n, 20), (0.0, 20), (0.0, 20)),
        "#                  c           EPS_DOT_0       ICC   Fsmooth               F_cut               Chard",
        row((data.C, 20), (eps0, 20), (0, 10), (0, 10), (0.0, 20), (0.0, 20)),
        "#                  m              T_melt               T_max               RHOCP                 T_r",
        row((data.m, 20), (t_melt, 20), (0.0, 20), (rho_cp, 20), (t_ref, 20)),
    ]
    if data.friction_mu is not None:
        out.append(f"# friction mu = {data.friction_mu:.4g} (specimen-platen, from barrelling): Fric of the contact interface (/INTER/TYPE7)")
    return "\n".join(out) + "\n"

"""Abaqus material cards: the Johnson–Cook form and the equivalent temperature table.

Two materials in one file: ``<NAME>_JC`` (``*PLASTIC, HARDENING=JOHNSON COOK`` with
``*RATE DEPENDENT, TYPE=JOHNSON COOK``) and ``<NAME>_TABLE`` (tabular ``*PLASTIC`` with a
temperature column, from the identified curves or the law). Temperatures in °C (Johnson–Cook
uses temperature differences; the model's temperatures must be in °C as well), ε̇0 per the
deck's time unit. A friction coefficient, when identified, comes as ``*SURFACE INTERACTION``.
"""

from __future__ import annotations

from flowcurve.reports.cards import MAX_TABLE_ROWS, CardData, comment_block, header_lines
from flowcurve.reports.cards.calculix import material_name, number, plastic_rows
from flowcurve.reports.units import UnitSystem


def _common(data: CardData, units: UnitSystem, name: str) -> list[str]:
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    out = [f"*MATERIAL, NAME={name}", "*ELASTIC", f"{number(E)}, {number(data.require('poisson'))}", "*DENSITY", number(rho)]
    if data.specific_heat_J_per_kgK is not None:
        out += ["*SPECIFIC HEAT", number(units.to_system(data.specific_heat_J_per_kgK, "specific_heat"))]
    if data.conductivity_W_per_mK is not None:
        out += ["*CONDUCTIVITY", number(units.to_system(data.conductivity_W_per_mK, "conductivity"))]
    if data.expansion_per_K is not None:
        out += [f"*EXPANSION, ZERO={number(data.ref_temperature_C)}", number(units.to_system(data.expansion_per_K, "expansion"))]
    return out


def abaqus_card(data: CardData, units: UnitSystem, *, curves: str = "auto", strain_rate_per_s: float | None = None,
                temperatures_C=None, max_rows: int = MAX_TABLE_ROWS) -> str:
    """The card text with both materials (and the friction interaction if identified)."""
    base = material_name(data)
    A, B = (units.to_system(v * 1e6, "stress") for v in (data.A_MPa, data.B_MPa))
    melt = data.require("melt_temperature_C")
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    rows, tables = plastic_rows(data, units, curves=curves, strain_rate_per_s=strain_rate_per_s,
                                temperatures_C=temperatures_C, max_rows=max_rows)
    origin = "identified true curves" if tables[0].origin == "measured" else "the Johnson-Cook law tabulated"
    rate_text = ", ".join(sorted({f"{c.strain_rate_per_s:.3g}" for c in tables}))
    time_unit = units.name.split("-")[1]
    out = [comment_block(header_lines(data, units, "Abaqus", f"temperatures in °C, strain rates per {time_unit}"), "** ").rstrip("\n")]
    out += ["**", f"** {base}_JC: Johnson-Cook; transition temperature = reference temperature."]
    out += _common(data, units, f"{base}_JC")
    out += [
        "*PLASTIC, HARDENING=JOHNSON COOK",
        ", ".join(number(v) for v in (A, B, data.n, data.m, melt, data.ref_temperature_C)),
        "*RATE DEPENDENT, TYPE=JOHNSON COOK",
        f"{number(data.C)}, {number(eps0)}",
        "**",
        f"** {base}_TABLE: {origin} at strain rate {rate_text} 1/s, per temperature, from zero plastic strain.",
    ]
    out += _common(data, units, f"{base}_TABLE")
    out.append("*PLASTIC")
    out += rows
    if data.friction_mu is not None:
        out += [
            "**",
            f"** friction mu = {data.friction_mu:.4g} identified from specimen barrelling (specimen-platen contact)",
            "*SURFACE INTERACTION, NAME=FRICTION_MU",
            "*FRICTION",
            number(data.friction_mu),
        ]
    return "\n".join(out) + "\n"

"""Abaqus material cards: the Johnson-Cook form and the equivalent temperature table.

Two materials in one file: ``<NAME>_JC`` (``*PLASTIC, HARDENING=JOHNSON COOK`` with
``*RATE DEPENDENT, TYPE=JOHNSON COOK``) and ``<NAME>_TABLE`` (tabular ``*PLASTIC`` with a
temperature column, from the identified curves or the law). Temperatures in C (Johnson-Cook
uses temperature differences; the model's temperatures must be in C as well), eps_dot0 per the
deck's time unit. A friction coefficient, when identified, comes as ``*SURFACE INTERACTION``.
"""

from __future__ import annotations

from flowcurve.reports.cards.calculix import material_name, plastic_rows
from flowcurve.reports.cards.data import DAMAGE_KEYS, CardData, CardOptions, header_lines
from flowcurve.reports.cards.fields import comment_block, number
from flowcurve.reports.cards.tables import origin_text
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


# Abaqus writes the Johnson-Cook failure strain in the pressure-deviatoric stress ratio p/q (p the pressure stress,
# positive in compression; q the Mises stress): [d1 + d2·exp(d3·p/q)]·[1 + d4·ln(rate*)]·(1 + d5·T^), and p/q = −η
# with η = σ_m/σ_eq of Johnson & Cook (1985), whose exp(D3·η) this is only with d3 = −D3 (docs/methods.md §5)
ABAQUS_D_SIGN = {"D1": 1.0, "D2": 1.0, "D3": -1.0, "D4": 1.0, "D5": 1.0}
ABAQUS_DAMAGE_CONVENTION = ("damage (*DAMAGE INITIATION, JOHNSON COOK): Abaqus' eps_D = [d1 + d2*exp(d3*p/q)]*[1 + d4*ln(rate/rate0)]"
                            "*(1 + d5*T^), p/q the pressure-deviatoric stress ratio (p > 0 in compression) = -triaxiality; "
                            "hence d3 = -D3 of Johnson & Cook (1985), whose D3 multiplies sigma_m/sigma_eq (positive in tension)")


def abaqus_damage_constants(fracture: dict[str, float]) -> list[float]:
    """d1..d5 as Abaqus reads them from the identified Johnson-Cook (1985) D1..D5: d3 = −D3."""
    return [ABAQUS_D_SIGN[k] * fracture[k] for k in DAMAGE_KEYS]


def damage_lines(data: CardData, units: UnitSystem, options: CardOptions) -> list[str]:
    """*DAMAGE INITIATION, CRITERION=JOHNSON COOK (d1..d5 with d3 = −D3, melting and transition
    temperature, reference strain rate, per the Abaqus keyword reference) and the user's *DAMAGE EVOLUTION."""
    if not data.fracture:
        return []
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    out = ["*DAMAGE INITIATION, CRITERION=JOHNSON COOK",
           ", ".join(number(v) for v in abaqus_damage_constants(data.fracture)
                     + [data.require("melt_temperature_C"), data.ref_temperature_C, eps0])]
    if options.damage_displacement_mm is None:
        out.append(comment_block(["No *DAMAGE EVOLUTION given (--damage-displacement): Abaqus evaluates the criterion "
                                  "(JCCRT) for output only; the material does not soften or fail."], "** ").rstrip("\n"))
    else:
        u_f = units.to_system(options.damage_displacement_mm * 1e-3, "length")
        out.append(comment_block(["*DAMAGE EVOLUTION set by the user (not identified): linear softening over an "
                                  f"equivalent plastic displacement of {options.damage_displacement_mm:g} mm"], "** ").rstrip("\n"))
        out += ["*DAMAGE EVOLUTION, TYPE=DISPLACEMENT, SOFTENING=LINEAR", number(u_f)]
    return out


def johnson_cook_material(data: CardData, units: UnitSystem, options: CardOptions, base: str) -> list[str]:
    """``<NAME>_JC``: *PLASTIC, HARDENING=JOHNSON COOK with *RATE DEPENDENT and the damage lines."""
    A, B = (units.to_system(v * 1e6, "stress") for v in (data.A_MPa, data.B_MPa))
    melt = data.require("melt_temperature_C")
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    out = ["**", f"** {base}_JC: Johnson-Cook; transition temperature = reference temperature."]
    out += _common(data, units, f"{base}_JC")
    out += [
        "*PLASTIC, HARDENING=JOHNSON COOK",
        ", ".join(number(v) for v in (A, B, data.n, data.m, melt, data.ref_temperature_C)),
        "*RATE DEPENDENT, TYPE=JOHNSON COOK",
        f"{number(data.C)}, {number(eps0)}",
    ]
    return out + damage_lines(data, units, options)


def abaqus_card(data: CardData, units: UnitSystem, options: CardOptions) -> str:
    """The card text with both materials (and the friction interaction if identified)."""
    base = material_name(data)
    rows, tables = plastic_rows(data, units, options)
    origin = origin_text(tables, data)
    rate_text = ", ".join(sorted({f"{c.strain_rate_per_s:.3g}" for c in tables}))
    time_unit = units.name.split("-")[1]
    out = [comment_block(header_lines(data, units, "Abaqus", f"temperatures in C, strain rates per {time_unit}", options)
                         + ([ABAQUS_DAMAGE_CONVENTION, f"d3 = {number(-data.fracture['D3'])} written for the identified "
                                                            f"D3 = {number(data.fracture['D3'])}"] if data.fracture else []),
                         "** ").rstrip("\n")]
    out += johnson_cook_material(data, units, options, base) if data.is_johnson_cook else [
        "**", f"** no {base}_JC material: Abaqus' HARDENING=JOHNSON COOK carries only Johnson-Cook constants and the fit's "
        f"law is {data.law.display_name}; the table below carries it"]
    out += [
        "**",
        f"** {base}_TABLE: {origin} at strain rate {rate_text} 1/s, per temperature, from zero plastic strain",
        f"** to {options.extend_to:g} (the fitted law beyond the last measured point).",
    ]
    out += _common(data, units, f"{base}_TABLE")
    out.append("*PLASTIC")
    out += rows
    out += damage_lines(data, units, options)
    if data.friction_mu is not None:
        out += [
            "**",
            f"** friction mu = {data.friction_mu:.4g} identified from specimen barrelling (specimen-platen contact)",
            "*SURFACE INTERACTION, NAME=FRICTION_MU",
            "*FRICTION",
            number(data.friction_mu),
        ]
    return "\n".join(out) + "\n"

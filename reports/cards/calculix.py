"""CalculiX (ccx 2.20) material card: tabular *PLASTIC with temperatures.

CalculiX 2.20 misreads ``*PLASTIC, HARDENING=JOHNSON COOK`` silently and ignores
``*RATE DEPENDENT`` (docs/calculix.md), so the card carries the flow curve as a table: one block per
temperature, each starting at zero plastic strain, at most ~100 rows (longer tables gave
stresses ~8 % low). Temperatures in C; the model must set
``*INITIAL CONDITIONS, TYPE=TEMPERATURE`` or CalculiX silently uses the lowest curve.
"""

from __future__ import annotations

import re

from flowcurve.reports.cards.data import CardData, CardOptions, header_lines
from flowcurve.reports.cards.fields import comment_block, number
from flowcurve.reports.cards.tables import flow_tables, origin_text
from flowcurve.reports.units import UnitSystem


def material_name(data: CardData) -> str:
    """A solver-safe material name (letters, digits, underscores; ≤ 80 characters)."""
    name = re.sub(r"[^A-Za-z0-9_]+", "_", data.material).strip("_") or "MATERIAL"
    return name[:80].upper()


def plastic_rows(data: CardData, units: UnitSystem, options: CardOptions,
                 temperature_column: bool = True) -> tuple[list[str], list]:
    """The ``*PLASTIC`` data lines (stress, plastic strain[, temperature C]) and the curves."""
    tables = flow_tables(data, options)
    rows = []
    for curve in tables:
        stress = units.to_system(curve.stress_MPa * 1e6, "stress")
        for s, e in zip(stress, curve.plastic_strain):
            fields = [number(s), number(e)] + ([number(curve.temperature_C)] if temperature_column else [])
            rows.append(", ".join(fields))
    return rows, tables


def calculix_card(data: CardData, units: UnitSystem, options: CardOptions) -> str:
    """The card text: *MATERIAL with *ELASTIC, *DENSITY, thermal constants if given, *PLASTIC table."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    rows, tables = plastic_rows(data, units, options)
    rate_text = ", ".join(sorted({f"{c.strain_rate_per_s:.3g}" for c in tables}))
    origin = origin_text(tables, data)
    temps = ", ".join(f"{c.temperature_C:g}" for c in tables)
    out = [comment_block(header_lines(data, units, "CalculiX 2.20", "temperatures in C", options), "** ").rstrip("\n")]
    out += [
        "**",
        f"** *PLASTIC: {origin} at strain rate {rate_text} 1/s (CalculiX 2.20 has no working rate",
        f"** dependence), one block per temperature ({temps} C), each from zero plastic strain",
        f"** to {options.extend_to:g} (the fitted law beyond the last measured point).",
        "** Johnson-Cook's own keyword is misread silently by ccx 2.20: this table is the correct form.",
        "** Set *INITIAL CONDITIONS, TYPE=TEMPERATURE in the model, or ccx uses the lowest-temperature curve.",
        *(["** D1-D5 not written: Johnson-Cook damage cards exist only from ccx 2.23 (docs/calculix.md)."] if data.fracture else []),
        f"*MATERIAL, NAME={material_name(data)}",
        "*ELASTIC",
        f"{number(E)}, {number(nu)}",
        "*DENSITY",
        number(rho),
    ]
    if data.specific_heat_J_per_kgK is not None:
        out += ["*SPECIFIC HEAT", number(units.to_system(data.specific_heat_J_per_kgK, "specific_heat"))]
    if data.conductivity_W_per_mK is not None:
        out += ["*CONDUCTIVITY", number(units.to_system(data.conductivity_W_per_mK, "conductivity"))]
    if data.expansion_per_K is not None:
        out += [f"*EXPANSION, ZERO={number(data.ref_temperature_C)}", number(data.expansion_per_K)]
    out.append("*PLASTIC")
    out += rows
    if data.friction_mu is not None:
        out += [
            "**",
            f"** friction mu = {data.friction_mu:.4g} (specimen-platen, from barrelling): in the contact definition use",
            "** *FRICTION",
            f"** {number(data.friction_mu)}, <stick slope>",
        ]
    return "\n".join(out) + "\n"

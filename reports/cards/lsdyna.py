"""LS-DYNA keyword deck: *MAT_JOHNSON_COOK (MAT_015) with its equation of state, and
*MAT_PIECEWISE_LINEAR_PLASTICITY (MAT_024) on the identified curves.

Fixed format: 10-character fields (8 to a card), curve points in two 20-character fields.
Temperatures are written in kelvin (the thermal solver and MAT_015's default TR = 298 are
absolute); strain rates per the deck's time unit.
"""

from __future__ import annotations

import math

from flowcurve.reports.cards import CardData, comment_block, fixed, header_lines, rate_tables
from flowcurve.reports.units import UnitSystem

MAT_JC_ID = 1
MAT_PLP_ID = 2
EOS_ID = 1
TABLE_ID = 100  # *DEFINE_TABLE; its curves are 101, 102, ...
CURVE_ID = 101
CURVE_DIGITS = 8  # significant digits of curve points
NO_SPALL_PC = -1e20  # PC: no pressure cut-off worth the name (the user sets one for spall)
NO_FAILURE_D1 = 1e20  # JC failure strain D1 when no fracture criterion was identified


def card(fields, width: int = 10, digits: int | None = None) -> str:
    """One fixed-format card line."""
    return "".join(fixed(v, width, digits) for v in fields).rstrip()


def names(*labels) -> str:
    """The '$#' comment naming a card's fields, in LS-PrePost's style."""
    text = "".join(label.rjust(10) for label in labels)
    return "$#" + text[2:]


def lsdyna_card(data: CardData, units: UnitSystem, *, curves: str = "auto", temperature_C: float | None = None,
                max_rows: int = 100) -> str:
    """The deck text. ``curves``: 'measured', 'law' or 'auto' for the MAT_024 curves;
    ``temperature_C``: the temperature of those curves (MAT_024 has no temperature)."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    cp = units.to_system(data.require("specific_heat_J_per_kgK"), "specific_heat")
    tm = units.temperature(data.require("melt_temperature_C"), absolute=True)
    tr = units.temperature(data.ref_temperature_C, absolute=True)
    A, B = (units.to_system(v * 1e6, "stress") for v in (data.A_MPa, data.B_MPa))
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    G = E / (2.0 * (1.0 + nu))  # shear modulus
    K = E / (3.0 * (1.0 - 2.0 * nu))  # bulk modulus, the linear EOS slope
    d = [data.fracture.get(f"D{i}") for i in range(1, 6)]

    tables = rate_tables(data, temperature_C, curves, max_rows)
    time_unit = units.name.split("-")[1]
    out = ["*KEYWORD"]
    out.append(comment_block(header_lines(data, units, "LS-DYNA", "temperatures in K, strain rates per " + time_unit), "$ ").rstrip("\n"))
    out += [
        "$",
        comment_block([
            f"MAT {MAT_JC_ID}: Johnson-Cook. On solid elements it needs the equation of state EOSID {EOS_ID} "
            "on its *PART (linear, bulk modulus K = E/(3(1-2nu))). PC = -1e20 and SPALL = 1: no pressure cut-off.",
            "D1-D5: " + ("identified fracture constants." if any(v is not None for v in d)
                         else f"no fracture criterion was identified: D1 = {NO_FAILURE_D1:g} (a failure strain never "
                              "reached; EROD = 0 would erode elements at a zero failure strain) - replace D1-D5 if "
                              "the model needs failure."),
        ], "$ ").rstrip("\n"),
        "*MAT_JOHNSON_COOK",
        names("mid", "ro", "g", "e", "pr", "dtf", "vp", "rateop"),
        card([MAT_JC_ID, rho, G, E, nu, None, 0.0, 0.0]),
        names("a", "b", "n", "c", "m", "tm", "tr", "epso"),
        card([A, B, data.n, data.C, data.m, tm, tr, eps0]),
        names("cp", "pc", "spall", "it", "d1", "d2", "d3", "d4"),
        card([cp, NO_SPALL_PC, 1.0, 0.0] + ([v or 0.0 for v in d[:4]] if any(v is not None for v in d)
                                            else [NO_FAILURE_D1, 0.0, 0.0, 0.0])),
        names("d5", "c2/p", "erod", "efmin", "numint"),
        card([d[4] or 0.0, 0.0, 0.0, 0.0, 0.0]),
        "*EOS_LINEAR_POLYNOMIAL",
        names("eosid", "c0", "c1", "c2", "c3", "c4", "c5", "c6"),
        card([EOS_ID, 0.0, K, 0.0, 0.0, 0.0, 0.0, 0.0]),
        names("e0", "v0"),
        card([0.0, 1.0]),
    ]

    temp_text = f"{tables[0].temperature_C:.6g} °C"
    origin = "identified true curves" if tables[0].origin == "measured" else "the Johnson-Cook law tabulated"
    several = len(tables) > 1
    if several:
        rates = [units.to_system(c.strain_rate_per_s, "strain_rate") for c in tables]
        use_log = rates[0] < 1.0  # LS-DYNA reads the table values as ln(rate) when the first is negative
        lcss = TABLE_ID
        rate_text = "strain rates " + ", ".join(f"{c.strain_rate_per_s:.3g}" for c in tables) + " 1/s"
    else:
        lcss = CURVE_ID
        rate_text = f"strain rate {tables[0].strain_rate_per_s:.3g} 1/s (rate-independent card)"
    out += [
        "$",
        comment_block([f"MAT {MAT_PLP_ID}: piecewise linear plasticity on {origin} at {temp_text}, {rate_text}; "
                       "curves start at zero plastic strain; beyond their last point LS-DYNA extrapolates the last slope."],
                      "$ ").rstrip("\n"),
        "*MAT_PIECEWISE_LINEAR_PLASTICITY",
        names("mid", "ro", "e", "pr", "sigy", "etan", "fail", "tdel"),
        card([MAT_PLP_ID, rho, E, nu, units.to_system(float(tables[0].stress_MPa[0]) * 1e6, "stress"), 0.0, 0.0, 0.0]),
        names("c", "p", "lcss", "lcsr", "vp"),
        card([0.0, 0.0, lcss, 0, 0.0]),
        names("eps1", "eps2", "eps3", "eps4", "eps5", "eps6", "eps7", "eps8"),
        "",
        names("es1", "es2", "es3", "es4", "es5", "es6", "es7", "es8"),
        "",
    ]
    if several:
        out += [
            f"$ table over {'ln(strain rate)' if use_log else 'strain rate'} per {time_unit}; "
            f"curves {CURVE_ID}-{CURVE_ID + len(tables) - 1} follow in order",
            "*DEFINE_TABLE",
            names("tbid", "sfa", "offa"),
            card([TABLE_ID, 1.0, 0.0]),
            "$#" + "value".rjust(18),
        ]
        out += [card([math.log(r) if use_log else r], 20) for r in rates]
    for i, curve in enumerate(tables):
        out += [
            "*DEFINE_CURVE",
            names("lcid", "sidr", "sfa", "sfo", "offa", "offo", "dattyp"),
            card([CURVE_ID + i, 0, 1.0, 1.0, 0.0, 0.0, 0]),
            "$#" + "a1".rjust(18) + "o1".rjust(20),
        ]
        stress = units.to_system(curve.stress_MPa * 1e6, "stress")
        out += [card([e, s], 20, CURVE_DIGITS) for e, s in zip(curve.plastic_strain, stress)]

    if data.friction_mu is not None:
        out += [
            "$",
            comment_block([f"friction mu = {data.friction_mu:.4g} identified from specimen barrelling (specimen-platen "
                           "contact). Set SSID/MSID to your segment sets; static and dynamic coefficients are taken equal."],
                          "$ ").rstrip("\n"),
            "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE",
            names("ssid", "msid", "sstyp", "mstyp", "sboxid", "mboxid", "spr", "mpr"),
            card([0, 0, 0, 0, 0, 0, 0, 0]),
            names("fs", "fd", "dc", "vc", "vdc", "penchk", "bt", "dt"),
            card([data.friction_mu, data.friction_mu, 0.0, 0.0, 0.0, 0, 0.0, 1e20]),
            names("sfs", "sfm", "sst", "mst", "sfst", "sfmt", "fsf", "vsf"),
            card([1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]),
        ]
    out.append("*END")
    return "\n".join(out) + "\n"

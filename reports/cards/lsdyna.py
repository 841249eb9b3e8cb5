"""LS-DYNA keyword deck: *MAT_JOHNSON_COOK (MAT_015) with its equation of state and fracture
constants, and *MAT_PIECEWISE_LINEAR_PLASTICITY (MAT_024) on the tabulated curves.

Fixed format: 10-character fields (8 to a card), curve points and table values in
20-character fields. Temperatures in kelvin (MAT_015's default TR = 298 is absolute); strain
rates per the deck's time unit. Every ID is ``id_offset`` + a base (MID 1 and 2, EOSID 1,
table 100, curves 101...).

Rate table convention: the *DEFINE_TABLE values are always ln(strain rate per deck time
unit), and the first value is always negative, which is LS-DYNA's signal to read all of them
as ln(rate) (a row below the slowest rate is added when needed, carrying the curve at eps_dot0:
no rate effect below eps_dot0). LS-DYNA then interpolates between the curves linearly in
ln(rate), in every unit system alike, which is exactly the Johnson-Cook rate factor
1 + C ln(eps_dot/eps_dot0). The rows include eps_dot0, where the law bends.
"""

from __future__ import annotations

import dataclasses
import math

from flowcurve.reports.cards.data import DAMAGE_KEYS, CardData, CardOptions, header_lines
from flowcurve.reports.cards.fields import CardError, comment_block, fixed_line
from flowcurve.reports.cards.tables import (flow_tables, group_by_temperature, law_grid, law_temperatures, origin_text, rate_tables,
                                            source_of)
from flowcurve.reports.units import UnitSystem

MAT_JC_ID = 1
MAT_PLP_ID = 2
EOS_ID = 1
MAT_TJC_ID = 1  # *MAT_TABULATED_JOHNSON_COOK (MAT_224) when asked for alone
TABLE_ID = 100  # *DEFINE_TABLE; its curves are 101, 102, ...
CURVE_ID = 101
TEMPERATURE_TABLE_ID = 200  # MAT_224's LCKT; its curves are 201, 202, ...
TAYLOR_QUINNEY_BETA = 0.9  # MAT_224 BETA: fraction of plastic work turned into heat (Taylor-Quinney)
CURVE_DIGITS = 8  # significant digits of curve points
NO_SPALL_PC = -1e20  # PC: no pressure cut-off worth the name (the user sets one for spall)
NO_FAILURE_D1 = 1e20  # JC failure strain D1 when no fracture criterion was identified


def names(*labels) -> str:
    """The '$#' comment naming a card's fields, in LS-PrePost's style."""
    text = "".join(label.rjust(10) for label in labels)
    return "$#" + text[2:]


def johnson_cook_block(data: CardData, units: UnitSystem, mid: int, eosid: int) -> list[str]:
    """*MAT_JOHNSON_COOK and its *EOS_LINEAR_POLYNOMIAL."""
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
    d = [data.fracture[k] for k in DAMAGE_KEYS] if data.fracture else [NO_FAILURE_D1, 0.0, 0.0, 0.0, 0.0]
    note = ("D1-D5: the identified Johnson-Cook fracture constants, triaxiality sigma_m/sigma_eq positive in tension "
            "(Johnson-Cook 1985, the convention in which published D1-D5 with D3 < 0 are entered here; the LS-DYNA "
            "manual writes it p/sigma_eff)."
            if data.fracture else
            f"D1-D5: no fracture criterion was identified: D1 = {NO_FAILURE_D1:g} (a failure strain never reached; "
            "EROD = 0 would erode elements at a zero failure strain) - replace D1-D5 if the model needs failure.")
    return [
        comment_block([f"MAT {mid}: Johnson-Cook. On solid elements it needs the equation of state EOSID {eosid} "
                       "on its *PART (linear, bulk modulus K = E/(3(1-2nu))). PC = -1e20 and SPALL = 1: no pressure "
                       "cut-off.", note], "$ ").rstrip("\n"),
        "*MAT_JOHNSON_COOK",
        names("mid", "ro", "g", "e", "pr", "dtf", "vp", "rateop"),
        fixed_line([mid, rho, G, E, nu, None, 0.0, 0.0]),
        names("a", "b", "n", "c", "m", "tm", "tr", "epso"),
        fixed_line([A, B, data.n, data.C, data.m, tm, tr, eps0]),
        names("cp", "pc", "spall", "it", "d1", "d2", "d3", "d4"),
        fixed_line([cp, NO_SPALL_PC, 1.0, 0.0] + d[:4]),
        names("d5", "c2/p", "erod", "efmin", "numint"),
        fixed_line([d[4], 0.0, 0.0, 0.0, 0.0]),
        "*EOS_LINEAR_POLYNOMIAL",
        names("eosid", "c0", "c1", "c2", "c3", "c4", "c5", "c6"),
        fixed_line([eosid, 0.0, K, 0.0, 0.0, 0.0, 0.0, 0.0]),
        names("e0", "v0"),
        fixed_line([0.0, 1.0]),
    ]


def table_rows(data: CardData, units: UnitSystem, tables) -> list[tuple[float, object]]:
    """(ln rate per deck time unit, curve) rows, the first always negative (see the module)."""
    rows = [(math.log(units.to_system(c.strain_rate_per_s, "strain_rate")), c) for c in tables]
    if rows[0][0] >= 0.0:  # below eps_dot0 the law has no rate effect: the eps_dot0 curve again
        rows.insert(0, (min(rows[0][0] - math.log(10.0), math.log(0.1)), tables[0]))
    return rows


def piecewise_linear_block(data: CardData, units: UnitSystem, options: CardOptions, mid: int) -> list[str]:
    """*MAT_PIECEWISE_LINEAR_PLASTICITY on the rate tables (or one curve), with its curves."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    tables = rate_tables(data, options)
    time_unit = units.name.split("-")[1]
    table_id, curve_id = TABLE_ID + options.id_offset, CURVE_ID + options.id_offset
    temp_text = f"{tables[0].temperature_C:.6g} C"
    origin = origin_text(tables, data)
    rows = table_rows(data, units, tables) if len(tables) > 1 else [(None, tables[0])]
    several = len(rows) > 1
    if several:
        rate_text = ("strain rates " + ", ".join(f"{c.strain_rate_per_s:.3g}" for c in tables)
                     + f" 1/s (including the reference rate {data.ref_strain_rate_per_s:.3g} 1/s)")
    else:
        rate_text = f"strain rate {tables[0].strain_rate_per_s:.3g} 1/s (rate-independent card)"
    out = [
        "$",
        comment_block([f"MAT {mid}: piecewise linear plasticity on {origin} at {temp_text}, {rate_text}; "
                       "curves start at zero plastic strain and continue beyond the last measured point with the "
                       f"fitted law to plastic strain {options.extend_to:g}; beyond that LS-DYNA extrapolates the "
                       "last slope."], "$ ").rstrip("\n"),
        "*MAT_PIECEWISE_LINEAR_PLASTICITY",
        names("mid", "ro", "e", "pr", "sigy", "etan", "fail", "tdel"),
        fixed_line([mid, rho, E, nu, units.to_system(float(tables[0].stress_MPa[0]) * 1e6, "stress"), 0.0, 0.0, 0.0]),
        names("c", "p", "lcss", "lcsr", "vp"),
        fixed_line([0.0, 0.0, table_id if several else curve_id, 0, 0.0]),
        names("eps1", "eps2", "eps3", "eps4", "eps5", "eps6", "eps7", "eps8"),
        "",
        names("es1", "es2", "es3", "es4", "es5", "es6", "es7", "es8"),
        "",
    ]
    if several:
        out += table_lines(table_id, [value for value, _ in rows],
                           f"table {table_id}: values are ln(strain rate per {time_unit}); the first is negative, so "
                           "LS-DYNA reads them all as ln(rate) and interpolates linearly in ln(rate) (the Johnson-Cook rate law itself; "
                           f"a law table has nodes added where another law bends); curves {curve_id}-{curve_id + len(rows) - 1} follow in order")
    out += curve_lines(curve_id, [curve for _, curve in rows], units)
    return out


def table_lines(table_id: int, values, note: str) -> list[str]:
    """A *DEFINE_TABLE with its values (20-character fields), after a comment ``note``."""
    out = [comment_block([note], "$ ").rstrip("\n"), "*DEFINE_TABLE", names("tbid", "sfa", "offa"), fixed_line([table_id, 1.0, 0.0]),
           "$#" + "value".rjust(18)]
    return out + [fixed_line([value], 20) for value in values]


def curve_lines(first_id: int, curves, units: UnitSystem) -> list[str]:
    """*DEFINE_CURVE per curve (plastic strain, stress in the deck's unit), IDs from ``first_id``."""
    out = []
    for i, curve in enumerate(curves):
        out += [
            "*DEFINE_CURVE",
            names("lcid", "sidr", "sfa", "sfo", "offa", "offo", "dattyp"),
            fixed_line([first_id + i, 0, 1.0, 1.0, 0.0, 0.0, 0]),
            "$#" + "a1".rjust(18) + "o1".rjust(20),
        ]
        stress = units.to_system(curve.stress_MPa * 1e6, "stress")
        out += [fixed_line([e, s], 20, CURVE_DIGITS) for e, s in zip(curve.plastic_strain, stress)]
    return out


def tabulated_jc_tables(data: CardData, options: CardOptions):
    """MAT_224's two tables in lab units: the rate curves at the reference temperature T_R
    (LCK1) and the temperature curves at the slowest of those rates (LCKT), T_R among them."""
    t_ref = data.ref_temperature_C
    rate_curves = rate_tables(data, dataclasses.replace(options, temperature_C=t_ref))
    quasi_static = rate_curves[0].strain_rate_per_s
    at_rate = dataclasses.replace(options, strain_rate_per_s=quasi_static)
    if source_of(data, options) == "law":
        temps = law_temperatures(data, options) if options.temperatures_C is None else list(options.temperatures_C)
        temps = law_grid(data, [t_ref, *temps], options, rate=quasi_static)
        at_rate = dataclasses.replace(at_rate, temperatures_C=temps)
    temp_curves = flow_tables(data, at_rate)
    if not any(abs(c.temperature_C - t_ref) <= options.temperature_tolerance_C for c in temp_curves):
        tested = ", ".join(f"{t:g}" for t, _ in group_by_temperature(data.curves, options.temperature_tolerance_C))
        raise CardError(f"{data.source_path}: *MAT_224 scales by the curve at the reference temperature {t_ref:g} C and none "
                        f"was measured there (tested: {tested} C); use the law (--curves law)")
    return rate_curves, temp_curves


def product_form_miss(data: CardData, rates, temperatures_C, extend_to: float) -> float:
    """The largest relative miss of MAT_224's product form sigma(eps, rate, TR) sigma(eps, rate0, T)/sigma(eps, rate0, TR)
    against the law itself over ``rates`` x ``temperatures_C`` (rate0 the slowest): 0 for a law whose rate and
    temperature effects are factors (Johnson-Cook)."""
    import numpy as np

    eps = extend_to * np.linspace(0.0, 1.0, 25) ** 2
    r0, t_ref = min(rates), data.ref_temperature_C
    worst = 0.0
    for rate in rates:
        for temp in temperatures_C:
            truth = np.asarray(data.flow_stress_MPa(eps, rate, temp), float)
            product = (np.asarray(data.flow_stress_MPa(eps, rate, t_ref), float) * np.asarray(data.flow_stress_MPa(eps, r0, temp), float)
                       / np.asarray(data.flow_stress_MPa(eps, r0, t_ref), float))
            ok = truth > 0
            if ok.any():
                worst = max(worst, float(np.max(np.abs(product[ok] / truth[ok] - 1.0))))
    return round(worst, 6)  # float noise of an exact product is no miss


def tabulated_johnson_cook_block(data: CardData, units: UnitSystem, options: CardOptions, mid: int) -> list[str]:
    """*MAT_TABULATED_JOHNSON_COOK (MAT_224): LCK1 a *DEFINE_TABLE over ln(rate) of stress curves at
    T_R, LCKT a *DEFINE_TABLE over temperature (K) of quasi-static curves; yield
    sigma = k1(eps_p, rate) k_t(eps_p, T)/k_t(eps_p, T_R) (keyword manual, MAT_224)."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    cp = units.to_system(data.require("specific_heat_J_per_kgK"), "specific_heat")
    tr = units.temperature(data.ref_temperature_C, absolute=True)
    time_unit = units.name.split("-")[1]
    rate_curves, temp_curves = tabulated_jc_tables(data, options)
    k1_id, k1_curve = TABLE_ID + options.id_offset, CURVE_ID + options.id_offset
    kt_id, kt_curve = TEMPERATURE_TABLE_ID + options.id_offset, TEMPERATURE_TABLE_ID + 1 + options.id_offset
    rows = table_rows(data, units, rate_curves)
    rates = ", ".join(f"{c.strain_rate_per_s:.3g}" for c in rate_curves)
    temps = ", ".join(f"{c.temperature_C:.4g}" for c in temp_curves)
    miss = product_form_miss(data, [c.strain_rate_per_s for c in rate_curves], [c.temperature_C for c in temp_curves],
                             options.extend_to)
    note = [
        f"MAT {mid}: tabulated Johnson-Cook (MAT_224) on {origin_text(rate_curves, data)}: yield stress "
        "sigma = k1(eps_p, rate) * kt(eps_p, T)/kt(eps_p, TR); k1 = LCK1, the curves at the reference temperature "
        f"TR = {data.ref_temperature_C:g} C over strain rates {rates} 1/s; kt = LCKT, the curves at the quasi-static rate "
        f"{rate_curves[0].strain_rate_per_s:.3g} 1/s over temperatures {temps} C (written in K).",
        f"The product form is exact for a law whose rate and temperature effects are factors (Johnson-Cook); for the fitted "
        f"{data.law.display_name} law it misses the law by up to {100 * miss:.2g} % over the rows' rates x temperatures"
        + (" - use --format flow-table or MAT_024 per temperature where that matters." if miss > 0.005 else "."),
        "Interpolation and extrapolation: in plastic strain the fitted law continues each curve beyond its last measured "
        f"point to {options.extend_to:g} (then LS-DYNA extrapolates the last slope); linearly in ln(rate) and in T between "
        "the curves (a law table has nodes added where the law bends between tested conditions); beyond the slowest and "
        "fastest rate and the coldest and hottest temperature LS-DYNA holds the end curve: clamped to the tabulated "
        "(tested) range, never below the quasi-static curve, no softening the data did not show.",
        f"BETA = {TAYLOR_QUINNEY_BETA:g} (Taylor-Quinney): adiabatic heating with CP in a structural-only run; set BETA = 0 "
        "if the curves already hold the heating of fast tests. No failure identified: LCF, LCG, LCH, LCI = 0.",
    ]
    out = [
        "$",
        comment_block(note, "$ ").rstrip("\n"),
        "*MAT_TABULATED_JOHNSON_COOK",
        names("mid", "ro", "e", "pr", "cp", "tr", "beta", "numint"),
        fixed_line([mid, rho, E, nu, cp, tr, TAYLOR_QUINNEY_BETA, 1.0]),
        names("lck1", "lckt", "lcf", "lcg", "lch", "lci"),
        fixed_line([k1_id, kt_id, 0, 0, 0, 0]),
        names("failopt", "numavg", "ncyfail", "erode", "lcps"),
        fixed_line([0, 1, 1, 0, 0]),
    ]
    out += table_lines(k1_id, [value for value, _ in rows],
                       f"LCK1 table {k1_id}: values are ln(strain rate per {time_unit}); the first is negative, so LS-DYNA "
                       f"reads them all as ln(rate); curves {k1_curve}-{k1_curve + len(rows) - 1} follow in order")
    out += curve_lines(k1_curve, [c for _, c in rows], units)
    out += table_lines(kt_id, [units.temperature(c.temperature_C, absolute=True) for c in temp_curves],
                       f"LCKT table {kt_id}: values are temperatures in K; curves {kt_curve}-{kt_curve + len(temp_curves) - 1} "
                       "follow in order")
    out += curve_lines(kt_curve, temp_curves, units)
    return out


def erosion_block(options: CardOptions, mids) -> list[str]:
    """*MAT_ADD_EROSION with the user's maximum effective strain on each material."""
    text = (f"MAT {mids[1]} has no fracture law of its own; on MAT {mids[0]} it acts besides D1-D5." if len(mids) > 1
            else f"On MAT {mids[0]}.")
    out = ["$", comment_block([f"*MAT_ADD_EROSION (asked for): elements erode at effective strain EFFEPS = "
                               f"{options.erosion_strain:g} (the user's value, not identified). {text}"], "$ ").rstrip("\n")]
    for mid in mids:
        out += ["*MAT_ADD_EROSION",
                names("mid", "excl", "mxpres", "mneps", "effeps", "voleps", "numfip", "ncs"),
                fixed_line([mid, None, None, None, options.erosion_strain, None, 1.0, 1.0])]
    return out


def contact_template(data: CardData) -> list[str]:
    """The identified friction as a commented-out contact card: the user fills SSID/MSID."""
    lines = [
        "*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE",
        names("surfa", "surfb", "surfatyp", "surfbtyp", "saboxid", "sbboxid", "sapr", "sbpr"),
        "   <SURFA>   <SURFB>" + fixed_line([0, 0, 0, 0, 0, 0]),
        names("fs", "fd", "dc", "vc", "vdc", "penchk", "bt", "dt"),
        fixed_line([data.friction_mu, data.friction_mu, 0.0, 0.0, 0.0, 0, 0.0, 1e20]),
        names("sfsa", "sfsb", "sast", "sbst", "sfsat", "sfsbt", "fsf", "vsf"),
        fixed_line([1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]),
    ]
    return ["$", comment_block([
        f"TEMPLATE (not active): friction mu = {data.friction_mu:.4g} identified from specimen barrelling "
        "(specimen-platen contact); static and dynamic coefficients taken equal. To use it, replace <SURFA> and "
        "<SURFB> (SSID, MSID) by your segment set IDs, remove the '$' before *CONTACT and replace the leading '$' of its "
        "data lines by a blank."], "$ ").rstrip("\n")] + [
        line if line.startswith("$#") else "$" + line if line.startswith("*") else "$" + line[1:] for line in lines]


def lsdyna_card(data: CardData, units: UnitSystem, options: CardOptions) -> str:
    """The deck text."""
    time_unit = units.name.split("-")[1]
    which = options.lsdyna_material
    if which in (None, "15"):
        data.require_johnson_cook("LS-DYNA's *MAT_JOHNSON_COOK (MAT_015" + (", written with MAT_024 unless --lsdyna-material)"
                                                                          if which is None else ")"))
    mid_jc, mid_plp = MAT_JC_ID + options.id_offset, (MAT_PLP_ID if which is None else MAT_JC_ID) + options.id_offset
    out = ["*KEYWORD"]
    out.append(comment_block(header_lines(data, units, "LS-DYNA", f"temperatures in K, strain rates per {time_unit}", options),
                             "$ ").rstrip("\n"))
    out.append("$")
    mids = []
    if which in (None, "15"):
        out += johnson_cook_block(data, units, mid_jc, EOS_ID + options.id_offset)
        mids.append(mid_jc)
    if which in (None, "24"):
        out += piecewise_linear_block(data, units, options, mid_plp)
        mids.append(mid_plp)
    if which == "224":
        out += tabulated_johnson_cook_block(data, units, options, MAT_TJC_ID + options.id_offset)
        mids.append(MAT_TJC_ID + options.id_offset)
    if options.erosion_strain is not None:
        out += erosion_block(options, mids)
    if data.friction_mu is not None:
        out += contact_template(data)
    out.append("*END")
    return "\n".join(out) + "\n"

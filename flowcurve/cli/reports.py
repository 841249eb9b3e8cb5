"""``flowcurve card`` (material cards from fit.json) and ``flowcurve report`` (a series report)."""

from __future__ import annotations

import sys

from flowcurve.reports.card_formats import FORMATS  # light: the writers are imported when used
from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM, UNIT_SYSTEMS
from flowcurve.services.card import CardRequest, ReportRequest, card, report


def register(subparsers) -> None:
    """Add ``card`` and ``report`` to the subcommands."""
    p = subparsers.add_parser(
        "card",
        help="material card for an FE solver from a series fit (fit.json)",
        description=(
            "Write a material card from fit.json (the output of 'flowcurve fit'): LS-DYNA "
            "(*MAT_JOHNSON_COOK with its EOS, *MAT_PIECEWISE_LINEAR_PLASTICITY on the identified "
            "curves), Abaqus (Johnson-Cook and a temperature table), OpenRadioss (/MAT/PLAS_JOHNS) or "
            "CalculiX (temperature table), a flow-stress table (flow-table: CSV for forming codes); any "
            "registered law of fit.json through the tables, Johnson-Cook-only cards refuse another; the Johnson-Cook fracture constants D1-D5 when fit.json has "
            "them. Constants missing from fit.json are given as options, in lab units. The card states "
            "its unit system and the range it was identified on. Every tabulated curve continues beyond "
            "its last measured point with the fitted law up to --extend-to, in every format alike."
        ),
    )
    p.add_argument("fit", metavar="FIT.json", help="fit.json written by 'flowcurve fit'")
    p.add_argument("--format", "-f", required=True, choices=FORMATS, help="solver")
    p.add_argument("--units", "-u", default=DEFAULT_UNIT_SYSTEM, choices=sorted(UNIT_SYSTEMS),
                   help=f"consistent unit system of the deck (default {DEFAULT_UNIT_SYSTEM})")
    p.add_argument("-o", "--output", metavar="FILE", help="write the card here (default: standard output)")
    p.add_argument("--name", metavar="TEXT", help="material name in the card (default: fit.json's material)")
    p.add_argument("--E", dest="E_MPa", type=float, metavar="MPa", help="Young's modulus, MPa (overrides fit.json)")
    p.add_argument("--poisson", type=float, metavar="NU", help="Poisson's ratio (overrides fit.json)")
    p.add_argument("--density", dest="density_kg_per_m3", type=float, metavar="KG_PER_M3", help="density, kg/m3")
    p.add_argument("--cp", dest="specific_heat_J_per_kgK", type=float, metavar="J_PER_KGK", help="specific heat, J/(kg K)")
    p.add_argument("--melt-temp", dest="melt_temperature_C", type=float, metavar="C", help="melting temperature, °C")
    p.add_argument("--conductivity", dest="conductivity_W_per_mK", type=float, metavar="W_PER_MK", help="thermal conductivity, W/(m K)")
    p.add_argument("--expansion", dest="expansion_per_K", type=float, metavar="PER_K", help="thermal expansion coefficient, 1/K")
    p.add_argument("--friction", dest="friction_mu", type=float, metavar="MU", help="friction coefficient (overrides fit.json)")
    p.add_argument("--curves", choices=("auto", "measured", "law"), default="auto",
                   help="tabulated curves from the measured true curves or the fitted law (default: measured when fit.json has them)")
    p.add_argument("--strain-rate", dest="strain_rate_per_s", type=float, metavar="1/s",
                   help="strain rate of the temperature tables (Abaqus/CalculiX; default: the reference rate)")
    p.add_argument("--temperature", dest="temperature_C", type=float, metavar="C",
                   help="LS-DYNA: temperature of the MAT_024 curves (default: the reference temperature)")
    p.add_argument("--max-rows", type=int, default=100, metavar="N", help="rows per tabulated curve (default 100; CalculiX needs ≤ ~100)")
    p.add_argument("--extend-to", type=float, metavar="EPS_P",
                   help="extend every tabulated curve beyond its last measured point with the fitted law to this plastic strain (default 2)")
    p.add_argument("--temperature-tolerance", dest="temperature_tolerance_C", type=float, metavar="C",
                   help="curves closer than this in temperature are one temperature (default 1 °C)")
    p.add_argument("--id-offset", type=int, metavar="N", help="add N to every numeric ID of the deck (materials, EOS, tables, curves; default 0)")
    p.add_argument("--radioss-version", choices=("2025", "2023"),
                   help="OpenRadioss input layout: 2025 (current, default) or 2023 (the layout before 2025)")
    p.add_argument("--fcut", dest="fcut_hz", type=float, metavar="HZ", help="Radioss strain-rate filter cut-off frequency, Hz (default 10000)")
    p.add_argument("--erosion-strain", type=float, metavar="EPS",
                   help="LS-DYNA: add *MAT_ADD_EROSION with this maximum effective strain (EFFEPS) to both materials")
    p.add_argument("--lsdyna-material", choices=("15", "24", "224"),
                   help="LS-DYNA: only *MAT_JOHNSON_COOK (15), only *MAT_PIECEWISE_LINEAR_PLASTICITY (24, any law) or "
                        "*MAT_TABULATED_JOHNSON_COOK (224: rate and temperature tables, any law); default 15 and 24 (Johnson-Cook)")
    p.add_argument("--damage-displacement", dest="damage_displacement_mm", type=float, metavar="MM",
                   help="Abaqus: *DAMAGE EVOLUTION, TYPE=DISPLACEMENT with this equivalent plastic displacement at failure, mm")
    p.set_defaults(func=run_card)

    r = subparsers.add_parser(
        "report",
        help="test report of a series as PDF and HTML (results ± U, conformity, curves, fit, card)",
        description=(
            "The test report a lab sends its customer, as report.pdf and report.html: the lab header, "
            "the standard and method designation (ISO 6892-1), the specimens with test date and operator, the "
            "instruments' calibration ('not for release' on every page without it), the results of the "
            "'flowcurve identify' result folders under DIR rounded as ISO 6892-1 §22 prescribes with "
            "their expanded uncertainty U (k = 2), the conformity of testing rate and temperature under the lab's decision rule, the "
            "uncertainty budgets, the figures, the series fit (fit.json under DIR) and a link to the "
            "LS-DYNA card written into cards/ beside the report."
        ),
    )
    r.add_argument("dir", metavar="DIR", help="folder holding the result folders and the fit folder")
    r.add_argument("-o", "--output", metavar="FILE", help="HTML file to write (default: DIR/report.html); the PDF goes beside it")
    r.add_argument("--lab", metavar="LAB.toml", help="lab file: [lab] name, address, accreditation, report_number or "
                   "report_number_scheme, revision, date_of_issue, customer, approved_by, compression_standard, decision_rule, "
                   "guard_band_U; [instruments] classes, certificates and due dates (docs/test-report.md; default: a generic "
                   "header, said so in the report)")
    r.add_argument("--no-pdf", action="store_true", help="write the HTML only")
    r.add_argument("--units", "-u", default=DEFAULT_UNIT_SYSTEM, choices=sorted(UNIT_SYSTEMS), help="unit system of the card")
    r.add_argument("--title", metavar="TEXT", help="report title")
    for option, dest, metavar in (("--E", "E_MPa", "MPa"), ("--poisson", "poisson", "NU"), ("--density", "density_kg_per_m3", "KG_PER_M3"),
                                  ("--cp", "specific_heat_J_per_kgK", "J_PER_KGK"), ("--melt-temp", "melt_temperature_C", "C")):
        r.add_argument(option, dest=dest, type=float, metavar=metavar, help=f"for the card, if fit.json lacks it ({metavar})")
    r.set_defaults(func=run_report)


def card_request(args) -> CardRequest:
    """The typed request of ``flowcurve card``'s options."""
    return CardRequest(**{k: getattr(args, k) for k in CardRequest.__dataclass_fields__})


def run_card(args) -> int:
    """``flowcurve card``: a material card of a fit.json, printed or written; the exit status."""
    request = card_request(args)
    text = card(request)
    if request.output:
        print(f"{request.format} card ({request.units}) written to {request.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def run_report(args) -> int:
    """``flowcurve report``: the series report (HTML, PDF) of result folders; the exit status."""
    written = report(ReportRequest(args.dir, args.output, lab=args.lab, pdf=not args.no_pdf, units=args.units, title=args.title,
                                   **{k: getattr(args, k) for k in ("E_MPa", "poisson", "density_kg_per_m3", "specific_heat_J_per_kgK",
                                                                    "melt_temperature_C")}))
    print(f"report written to {', '.join(map(str, written))}", file=sys.stderr)
    return 0

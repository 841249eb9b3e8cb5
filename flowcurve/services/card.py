"""Material cards and the test report: typed requests and the services ``flowcurve card``,
``flowcurve report`` and the console call.

:func:`card` writes a card from fit.json (:class:`CardRequest`; constants missing from the fit
named at once), :func:`report` a series report (:class:`ReportRequest`), and
:func:`missing_for_fit_and_card` every input a fit and its card lack, by request field.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM as DEFAULT_UNITS
from flowcurve.services import choice


@dataclass(kw_only=True)
class Constants:
    """The material constants a card takes beyond fit.json's (override them), in lab units."""

    E_MPa: float | None = None
    poisson: float | None = None
    density_kg_per_m3: float | None = None
    specific_heat_J_per_kgK: float | None = None
    melt_temperature_C: float | None = None


@dataclass
class CardRequest(Constants):
    """A material card of a fit, as ``flowcurve card`` and the console ask for it.

    Attributes
    ----------
    fit : str
        The fit.json file.
    format, units : str
        The card format (a name of :data:`flowcurve.reports.card_formats.WRITERS`) and unit system.
    output : str, optional
        The card file written; None: the text is only returned.
    name : str, optional
        The material's name on the card.
    E_MPa, poisson, density_kg_per_m3, specific_heat_J_per_kgK, melt_temperature_C : float, optional
        Constants overriding fit.json's: MPa, –, kg/m³, J/(kg K), °C.
    conductivity_W_per_mK, expansion_per_K, friction_mu : float, optional
        Constants some cards take: W/(m K), 1/K, the tool–workpiece μ.
    curves, max_rows, strain_rate_per_s, temperature_C, extend_to, temperature_tolerance_C : optional
        The flow tables: source ("auto", "measured", "law"), rows, the rate (1/s) and temperatures
        (°C) tabulated, the strain they reach, the tolerance matching a temperature, °C.
    id_offset, radioss_version, fcut_hz, erosion_strain, damage_displacement_mm, lsdyna_material : optional
        Format options: ids, the Radioss version, a filter cut-off (Hz), erosion strain, damage
        displacement (mm) and the LS-DYNA material (as ``flowcurve card`` names them).
    """

    fit: str
    format: str
    units: str = DEFAULT_UNITS
    output: str | None = None
    name: str | None = None
    conductivity_W_per_mK: float | None = None
    expansion_per_K: float | None = None
    friction_mu: float | None = None
    curves: str = "auto"
    max_rows: int = 100
    strain_rate_per_s: float | None = None
    temperature_C: float | None = None
    extend_to: float | None = None
    temperature_tolerance_C: float | None = None
    id_offset: int | None = None
    radioss_version: str | None = None
    fcut_hz: float | None = None
    erosion_strain: float | None = None
    damage_displacement_mm: float | None = None
    lsdyna_material: str | None = None

    def check(self) -> CardRequest:
        """The request, or FieldError naming its first refused field (format, units, LS-DYNA material)."""
        from flowcurve.reports.card_formats import FORMATS
        from flowcurve.reports.cards.data import LSDYNA_MATERIALS
        from flowcurve.reports.units import UNIT_SYSTEMS

        choice("format", "--format/-f", self.format, FORMATS)
        choice("units", "--units/-u", self.units, sorted(UNIT_SYSTEMS))
        if self.lsdyna_material is not None:
            choice("lsdyna_material", "--lsdyna-material", str(self.lsdyna_material), LSDYNA_MATERIALS)
        return self

    def options(self) -> dict:
        """The card writer's options."""
        return {k: getattr(self, k) for k in CARD_OPTIONS}


@dataclass
class ReportRequest(Constants):
    """A series report of the result folders under ``dir``.

    Attributes
    ----------
    dir : str
        The folder of result folders (and fit folders).
    output : str, optional
        The HTML file written (default ``dir``/report.html); the PDF goes beside it.
    lab : str, optional
        The laboratory's TOML file (name, accreditation, approver).
    pdf : bool
        Write the PDF too.
    units, title : str
        The unit system of the cards linked; the report's title.
    E_MPa, poisson, density_kg_per_m3, specific_heat_J_per_kgK, melt_temperature_C : float, optional
        Constants for the cards the report writes (MPa, –, kg/m³, J/(kg K), °C).
    """

    dir: str
    output: str | None = None
    lab: str | None = None
    pdf: bool = True
    units: str = DEFAULT_UNITS
    title: str | None = None


CONSTANT_OPTIONS = ("E_MPa", "poisson", "density_kg_per_m3", "specific_heat_J_per_kgK", "melt_temperature_C",
                    "conductivity_W_per_mK", "expansion_per_K", "friction_mu")


def overrides(args) -> dict:
    """The constants given on the command line (``args``), keyed as CardRequest takes them."""
    out = {k: getattr(args, k, None) for k in CONSTANT_OPTIONS}
    if getattr(args, "name", None):
        out["material"] = args.name
    return {k: v for k, v in out.items() if v is not None}


CARD_OPTIONS = ("curves", "max_rows", "strain_rate_per_s", "temperature_C", "extend_to", "temperature_tolerance_C",
                "id_offset", "radioss_version", "fcut_hz", "erosion_strain", "damage_displacement_mm", "lsdyna_material")


# stand-ins for constants a card lacks, only to find every other one it lacks too (never written)
_STAND_INS = {"E_MPa": 2.0e5, "poisson": 0.3, "density_kg_per_m3": 7850.0, "specific_heat_J_per_kgK": 460.0,
              "conductivity_W_per_mK": 40.0, "expansion_per_K": 1.2e-5}


def missing_constants(data, fmt: str, units: str, options: dict) -> list[str]:
    """Every constant (CardData attribute) the card in ``fmt`` needs and ``data`` lacks, in the
    order the card asks for them: the card is made on a copy, a stand-in filling each gap found."""
    import copy

    from flowcurve.reports.cards import write_card
    from flowcurve.reports.cards.data import MissingConstant

    probe, missing = copy.copy(data), []
    while True:
        try:
            write_card(probe, fmt, units, **options)
            return missing
        except MissingConstant as exc:
            if exc.name in missing:  # a stand-in the card refuses: name what was found so far
                return missing
            missing.append(exc.name)
            stand_in = probe.ref_temperature_C + 1000.0 if exc.name == "melt_temperature_C" else _STAND_INS[exc.name]
            setattr(probe, exc.name, stand_in)


def missing_text(names: list[str], labels: dict[str, str] | None = None) -> str:
    """'Poisson's ratio (--poisson), density in kg/m3 (--density)': each constant as
    ``labels`` names it (the console's form), else with the option that gives it."""
    from flowcurve.reports.cards.data import CONSTANTS

    labels = labels or {}
    return ", ".join(labels.get(n) or f"{CONSTANTS[n][2]} ({CONSTANTS[n][1]})" for n in names)


def card(req: CardRequest) -> str:
    """The material card of a fit, in the request's format and unit system.

    Parameters
    ----------
    req : CardRequest
        fit.json, ``format`` (a name of :data:`flowcurve.reports.card_formats.WRITERS`), ``units``,
        constants that override or add to the fit's, the card options and ``output``.

    Returns
    -------
    str
        The card's text, also written to ``req.output`` when given.

    Raises
    ------
    FieldError
        A request value refused, naming its field.
    CardError
        Every constant the card needs that neither fit.json nor the request gives, at once.
    """
    from flowcurve.reports.cards import load_card_data, write_card
    from flowcurve.reports.cards.fields import CardError

    req.check()
    data = load_card_data(req.fit, **overrides(req))
    missing = missing_constants(data, req.format, req.units, req.options())
    if missing:
        why_no_E = f" (the fit file's E is {data.E_source})" if "E_MPa" in missing and getattr(data, "E_source", None) else ""
        raise CardError(f"{req.fit}: the {req.format} card needs {len(missing)} value(s) not in the fit file: "
                        f"{missing_text(missing)}; give them as options or as keys in the fit file{why_no_E}")
    text = write_card(data, req.format, req.units, **req.options())
    if req.output:
        Path(req.output).write_text(text, encoding="utf-8")
    return text


def report(req: ReportRequest) -> list:
    """Write the series report of ``req``.

    Parameters
    ----------
    req : ReportRequest
        The folder of results, the output, the lab file and the card constants.

    Returns
    -------
    list of Path
        The files written (HTML, then PDF when asked).
    """
    from flowcurve.reports.lab import load_lab
    from flowcurve.reports.report import write_report
    from flowcurve.rig.config import instruments_given

    lab = load_lab(req.lab, check_instruments=instruments_given)  # [instruments] as the rig configuration's
    return write_report(req.dir, req.output, units=req.units, title=req.title, lab=lab, pdf=req.pdf, **overrides(req))


def missing_for_fit_and_card(members, fit_req, card_req) -> dict[str, str]:
    """Every input the fit of ``members`` (``fit_req``) and its card (``card_req``) lack, found
    before anything is written: request field (FitRequest's, else CardRequest's) → why."""
    from flowcurve.reports.cards.data import CONSTANTS, card_data_from_fit
    from flowcurve.services.fit import FIT_INPUTS, missing_inputs

    missing = {k: f"needed: {FIT_INPUTS[k][2]}" for k in missing_inputs(
        members, ref_strain_rate_per_s=fit_req.ref_rate, ref_temperature_C=fit_req.ref_temp, melt_temperature_C=fit_req.melt_temp,
        fixed=fit_req.fixed())}
    # the card's constants as fit.json will carry them (the records' mean E and Poisson's ratio), the law a stand-in
    Es = [m.E_MPa for m in members if m.E_MPa is not None]
    nus = [m.poisson_ratio for m in members if m.poisson_ratio is not None]
    provisional = {"A_MPa": 1.0, "B_MPa": 1.0, "n": 0.5, "melt_temperature_C": fit_req.melt_temp,
                   "E_MPa": sum(Es) / len(Es) if Es else None, "poisson_ratio": sum(nus) / len(nus) if nus else None}
    data = card_data_from_fit(provisional, "fit.json", **overrides(card_req))
    for name in missing_constants(data, card_req.format, card_req.units, card_req.options()):
        missing.setdefault("melt_temp" if name == "melt_temperature_C" else name,
                           f"needed: the {card_req.format} card needs the {CONSTANTS[name][2]}")
    return missing

"""What a series test report says, as blocks both renderers share (:mod:`.report` HTML, :mod:`.report_pdf` PDF).

Built from a folder holding ``flowcurve identify`` result folders (``result.json`` with its
``uncertainty`` and ``methods.conformity``, PNG plots) and optionally a ``flowcurve fit``
folder (``fit.json``): the lab header, the standard and method designation, the specimen and
test table, the results rounded as ISO 6892-1 §22 prescribes each with its expanded
uncertainty U (k = 2), the conformity of testing rate and temperature, the uncertainty
budgets, the figures, the series fit and links to the material cards written beside the
report. Every name in it is relative: file names, never the paths of the machine that made it.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from flowcurve import __version__
from flowcurve.errors import FlowcurveError
from flowcurve.identification.laws.base import constant_keys, display_name_of, registered_laws
from flowcurve.identification.outcome import read_json_object
from flowcurve.reports import calibration as cal
from flowcurve.reports.lab import LabHeader
from flowcurve.reports.rounding import ISO_6892_1_RULES, STEPS, format_range, format_step, format_uncertainty, value_with_U


class ReportError(FlowcurveError):
    """A report folder that holds nothing to report, or files that cannot be read."""


@dataclass
class Heading:
    text: str
    level: int = 2


@dataclass
class Para:
    text: str
    kind: str = ""  # "", "warn" or "note"


@dataclass
class Facts:
    rows: list[tuple[str, str]]


@dataclass
class Table:
    columns: list[str]
    rows: list[list[str]]
    caption: str = ""


@dataclass
class Figure:
    path: Path
    caption: str


@dataclass
class Link:
    text: str
    href: str  # relative to the report file


@dataclass
class Report:
    title: str
    lab: LabHeader
    blocks: list = field(default_factory=list)
    number: str = ""  # the report number, on every page
    issued: str = ""  # date of issue
    not_for_release: str = ""  # on every page and the HTML's header when set
    engineer: list = field(default_factory=list)  # "for the engineer": command-line hints, codes (HTML only)

    def add(self, *blocks) -> None:
        """Append ``blocks`` to the report."""
        self.blocks.extend(blocks)

    def for_engineer(self, text: str) -> None:
        """Add a note for the engineer (once)."""
        if text not in self.engineer:
            self.engineer.append(text)


NOT_STATED = "not stated"
# a command-line hint or code in a text: an option, a command, a file's key
HINT = re.compile(r"--[a-z]|'flowcurve |flowcurve [a-z]+ |\.json\b|\.csv\b|\[[a-z_]+\]|\b[a-z][a-z0-9]*_[a-z0-9_]+\b")


def customer_text(text: str, report: Report | None = None) -> str:
    """``text`` without command-line hints or file keys (parenthesised hints and clauses holding one are
    dropped); the whole text goes to the report's "for the engineer" notes when anything was dropped."""
    out = re.sub(r"\s*\([^()]*\)", lambda m: "" if HINT.search(m.group(0)) else m.group(0), text)
    out = "; ".join(c for c in out.split("; ") if not HINT.search(c)).strip()
    if out != text and report is not None:
        report.for_engineer(text)
    return out


PLOT_CAPTIONS = {"diagram": "indicator diagram: force against displacement, as recorded and corrected",
                 "stress_strain": "stress–strain curves; the selected true curve with its hardening fit",
                 "corrections": "true curves by friction correction"}
FRICTION_METHODS = {"fe_table": "CalculiX upsetting table", "bulge_regression": "bulge regression",
                    "ebrahimi_najafizadeh": "Ebrahimi–Najafizadeh"}
FLOW_SHOWN = ("0.1", "0.2", "0.3")  # compression flow stress columns (true plastic strain)


# ---- reading --------------------------------------------------------------------------------

def _read_json(path: Path) -> dict:
    return read_json_object(path, ReportError)


def find_results(root: Path) -> list[tuple[str, Path, dict]]:
    """(name, folder, result.json) of every identify result folder under ``root``."""
    return [(p.parent.name, p.parent, _read_json(p)) for p in sorted(root.rglob("result.json"))]


def find_fit(root: Path) -> Path | None:
    """The series fit under ``root`` (the shallowest ``fit.json``)."""
    fits = sorted(root.rglob("fit.json"), key=lambda p: (len(p.parts), str(p)))
    return fits[0] if fits else None


def _rec(result: dict) -> dict:
    block = result.get("record")
    return block if isinstance(block, dict) else {}


def _sub(result: dict, name: str) -> dict:
    block = _rec(result).get(name)
    return block if isinstance(block, dict) else {}


def _spec(result: dict, key: str):
    value = _sub(result, "specimen").get(key)
    return value if value is not None else _rec(result).get(f"specimen.{key}")


def _num(value) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) else None


def _g(value, digits: int = 3) -> str:
    """``digits`` significant digits, without an exponent between 10⁻⁴ and 10⁷ (226090, not 2.2609e+05)."""
    v = _num(value)
    if v is None:
        return "–"
    if v == 0 or not 1e-4 <= abs(v) < 1e7:
        return f"{v:.{digits}g}"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(v))))
    text = f"{round(v, decimals):.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _short(value) -> str:
    """Three significant digits, trailing zeros dropped (0.05, 0.00167)."""
    v = _num(value)
    return "–" if v is None else f"{v:.3g}"


def _unc(result: dict) -> dict:
    u = result.get("uncertainty")
    return u if isinstance(u, dict) else {}


def _U(result: dict, key: str) -> float | None:
    b = _unc(result).get(key)
    return _num(b.get("U")) if isinstance(b, dict) and not b.get("given") else None


def _with_U(result: dict, key: str, step_key: str | None = None) -> str:
    return value_with_U(_num(result.get(key)), _U(result, key), STEPS.get(step_key or key))


def relative_name(path) -> str:
    """A record's name for the report: its file name, never the absolute path."""
    return Path(str(path)).name if path else "–"


# ---- E and its source -----------------------------------------------------------------------

def modulus_source(result: dict) -> str:
    """given (handbook/option), measured (extensometer) or apparent (crosshead, compression)."""
    if result.get("test") == "compression":
        src = str(result.get("E_source") or "")
        return "apparent (initial slope)" if src.startswith("apparent") else ("–" if src in ("", "none") else "given (handbook)")
    if result.get("E_stderr_MPa") is None:
        return "given (handbook)"
    if (result.get("methods") or {}).get("strain_source") == "extensometer":
        return "measured (extensometer)"
    return "apparent (crosshead)"


def modulus_cell(result: dict) -> str:
    """Young's modulus of a result as the table shows it."""
    E = _num(result.get("E_MPa"))
    if E is None:
        return "–"
    source = modulus_source(result)
    U = _U(result, "E_MPa") if source.startswith("measured") else None
    return value_with_U(E / 1000.0, U / 1000.0 if U else None, STEPS["E_GPa"])


# ---- identity and calibration ---------------------------------------------------------------

def specimen_id(name: str, result: dict) -> str:
    """The specimen's ID as the record states it (``specimen.id``), else its result folder's name."""
    rec = _rec(result)
    return str(rec.get("specimen_id") or _spec(result, "id") or name)


def stated(value) -> str:
    """``value`` as text, or "not stated"."""
    return str(value).strip() if value is not None and str(value).strip() else NOT_STATED


def test_date(result: dict) -> str:
    """The record's test date (its day, ``2022-08-18``) or 'not stated'."""
    date = cal.iso_date(_rec(result).get("date"))
    return date.isoformat() if date else stated(_rec(result).get("date"))


def calibration(report: Report, results: list, issued: str) -> tuple[list, list[str]]:
    """The instruments table (one block per set of specimens with the same data) and why the report may not be released."""
    groups: dict[str, list] = {}
    problems: dict[str, list[str]] = {}
    for name, _, r in results:
        record_inst = _rec(r).get("instruments") if isinstance(_rec(r).get("instruments"), dict) else {}
        inst, sources = cal.effective(record_inst, report.lab.instruments)
        sid = specimen_id(name, r)
        rows = [[label, cal.instrument_cell(inst, prefix, class_key, what), sources[prefix]]
                for prefix, label, class_key, what in cal.INSTRUMENTS]
        groups.setdefault(repr(rows), [rows, []])[1].append(sid)
        heated = (_num(_rec(r).get("nominal_temperature_C")) or 0.0) > cal.HEATED_ABOVE_C
        for p in cal.release_problems(inst, test_date=cal.iso_date(_rec(r).get("date")), issued=cal.iso_date(issued),
                                      extensometer=(r.get("methods") or {}).get("strain_source") == "extensometer",
                                      heated=heated, budget_inst=_unc(r).get("instruments") or {}):
            problems.setdefault(p, []).append(sid)
    rows = [[", ".join(sids) if i == 0 else "", *row] for rows_, sids in groups.values() for i, row in enumerate(rows_)]
    return ([Table(["specimens", "instrument", "class / MPE; calibration certificate, due date", "data from"], rows,
                   "calibration of the measuring instruments (ISO/IEC 17025 6.4, 6.5)")],
            [f"{p} ({', '.join(sids)})" for p, sids in problems.items()])


# ---- sections -------------------------------------------------------------------------------

def header(report: Report, series: str, results: list) -> None:
    """Add the report's header: laboratory, report number, revision, dates."""
    lab = report.lab
    rows = [("laboratory", lab.name), ("address", lab.address or NOT_STATED), ("accreditation", lab.accreditation),
            ("report number", report.number), ("revision", lab.revision_text()), ("date of issue", report.issued),
            ("customer", lab.customer or NOT_STATED), ("test series", f"{series} ({len(results)} specimen(s))"),
            ("evaluated with", f"flowcurve {__version__}")]
    report.add(Facts(rows))
    if report.not_for_release:
        report.add(Para(report.not_for_release.upper(), "warn"))
    if lab.source.startswith("defaults"):
        report.add(Para("Lab header: defaults (no lab file).", "note"))
        report.for_engineer("The lab header is the default: give 'flowcurve report --lab lab.toml' with the laboratory's name, "
                            "accreditation, report number, customer, approved_by, decision_rule and [instruments] "
                            "(docs/test-report.md).")
    report.add(Para("The results relate only to the items tested. This report shall not be reproduced except in full "
                    "without the laboratory's written approval.", "note"))


def designations(results: list, lab: LabHeader) -> list[tuple[str, str]]:
    """(specimen, designation) rows of the standards each result conforms to."""
    rows = []
    for name, _, r in results:
        conf = (r.get("methods") or {}).get("conformity") or {}
        rate = conf.get("testing_rate") or {}
        if r.get("test") == "tension":
            text = rate.get("designation") or "ISO 6892-1:2019 (testing rate not evaluated)"
            heated = (conf.get("temperature") or {}).get("standard")
            if heated and heated != rate.get("standard"):
                text += f"; temperature: {heated}"
        else:
            text = f"compression (upsetting): {lab.compression_standard or 'standard not stated'}"
        rows.append((specimen_id(name, r), text))
    return rows


def specimen_table(results: list) -> Table:
    """The specimens table: id, record, material, orientation, date, operator."""
    rows = [[specimen_id(n, r), relative_name(_rec(r).get("path")), str(_rec(r).get("material") or NOT_STATED),
             stated(_rec(r).get("orientation")), test_date(r), stated(_rec(r).get("operator"))] for n, _, r in results]
    return Table(["specimen", "record", "material", "orientation", "test date", "operator"], rows)


def conditions_table(results: list) -> Table:
    """The test conditions table: geometry, temperature, crosshead speed and strain rates."""
    cols = ["specimen", "test", "d0, mm", "L0 / h0, mm", "Lc, mm", "temperature, °C", "crosshead, mm/s", "strain rate, 1/s (tension: ė_Lc elastic / yield / to Rm, measured)"]
    rows = []
    for name, _, r in results:
        rec = _rec(r)
        length = _spec(r, "l0_mm") if _spec(r, "l0_mm") is not None else _spec(r, "h0_mm")
        rows.append([specimen_id(name, r), str(r.get("test", "–")), format_step(_num(_spec(r, "d0_mm")), 0.001),
                     format_step(_num(length), 0.01), format_step(_num(_spec(r, "parallel_length_mm")), 0.01),
                     format_step(_num(rec.get("nominal_temperature_C")), 1.0), _short(rec.get("crosshead_speed_mm_per_s")),
                     measured_strain_rates(r)])
    return Table(cols, rows)


def measured_strain_rates(result: dict) -> str:
    """The strain rates the conformity check judged (tension: ė_Lc per phase, elastic / yield / to Rm);
    else the record's stated strain rate."""
    rate = (((result.get("methods") or {}).get("conformity") or {}).get("testing_rate") or {})
    phases = rate.get("phases") or {}
    measured = [_num((phases.get(p) or {}).get("strain_rate_per_s")) for p in ("elastic", "yield", "to_Rm")]
    if any(v is not None for v in measured):
        return " / ".join(_short(v) for v in measured)
    return _short(_rec(result).get("strain_rate_per_s"))


def remarks(result: dict) -> str:
    """What the reader must know before using the row: a poor fit, the number of warnings."""
    out = []
    if (result.get("hardening") or {}).get("quality") == "poor":
        out.append("poor hardening fit")
    if result.get("warnings"):
        out.append(f"{len(result['warnings'])} warning(s) below")
    return "; ".join(out) or "–"


def tension_table(results: list) -> Table | None:
    """The tension results table (E, Rp0.2, Rm, Ag, A, Z with U), or None without tension."""
    rows = [[specimen_id(n, r), modulus_cell(r), modulus_source(r), _with_U(r, "Rp02_MPa"), _with_U(r, "Rm_MPa"),
             _with_U(r, "Ag_pct"), _with_U(r, "A_pct"), _with_U(r, "Z_pct"), remarks(r)]
            for n, _, r in results if r.get("test") == "tension"]
    if not rows:
        return None
    return Table(["specimen", "E, GPa", "E from", "Rp0.2, MPa", "Rm, MPa", "Ag, %", "A, %", "Z, %", "remarks"], rows,
                 "tension (ISO 6892-1): value ± U (k = 2)")


def _or_dash(result: dict, key: str) -> str:
    return _with_U(result, key) if _num(result.get(key)) is not None else "—"


def iso_table(results: list, report: Report | None = None) -> Table | None:
    """ReH, ReL, Ae, Agt, At, how A was obtained, Z, E's method and the test date: what the result carries, '—' else."""
    rows = [[specimen_id(n, r), _or_dash(r, "ReH_MPa"), _or_dash(r, "ReL_MPa"), _or_dash(r, "Ae_pct"), _or_dash(r, "Agt_pct"),
             _or_dash(r, "At_pct"), _or_dash(r, "Z_pct"), stated(customer_text(str(r.get("A_method") or ""), report)),
             stated((r.get("modulus") or {}).get("source") or (r.get("methods") or {}).get("modulus")), test_date(r)]
            for n, _, r in results if r.get("test") == "tension"]
    if not rows:
        return None
    return Table(["specimen", "ReH, MPa", "ReL, MPa", "Ae, %", "Agt, %", "At, %", "Z, %", "A obtained", "E obtained", "test date"],
                 rows, "further ISO 6892-1 results ('—': not determined, e.g. no yield point)")


def friction_cell(result: dict) -> str:
    """μ with its range where the method gives an asymmetric one (``0.084 (0.075–0.093)``), else μ ± U."""
    rng = result.get("friction_mu_range")
    if isinstance(rng, list) and len(rng) == 2 and all(_num(x) is not None for x in rng):
        return f"{format_step(_num(result.get('friction_mu')), STEPS['friction_mu'])} ({format_range(rng[0], rng[1], STEPS['friction_mu'])})"
    return _with_U(result, "friction_mu")


def compression_table(results: list) -> Table | None:
    """The compression results table, or None without compression."""
    comp = [(n, r) for n, _, r in results if r.get("test") == "compression"]
    if not comp:
        return None
    rows = []
    for n, r in comp:
        flow = _unc(r).get("flow_stress_MPa") or {}
        cells = [value_with_U(_num((flow.get(e) or {}).get("value")), _num((flow.get(e) or {}).get("U")), 1.0) for e in FLOW_SHOWN]
        rows.append([specimen_id(n, r), modulus_cell(r), modulus_source(r), _with_U(r, "Rp02_MPa"), friction_cell(r), *cells,
                     FRICTION_METHODS.get(str(r.get("friction_method")), str(r.get("friction_method", "–")).replace("_", " ")),
                     remarks(r)])
    return Table(["specimen", "E, GPa", "E from", "Rp0.2, MPa", "friction μ (range)", *[f"σ at εp {e}, MPa" for e in FLOW_SHOWN],
                  "friction method", "remarks"], rows,
                 "compression: value ± U (k = 2), μ with the range of its method; σ is the selected true curve")


def compression_measures(results: list) -> Table | None:
    """The upset specimen's measured height hk, bulge diameter dmax and face diameter dface."""
    rows = [[specimen_id(n, r), format_step(_num(_sub(r, "post").get("hk_mm")), 0.01),
             format_step(_num(_sub(r, "post").get("dmax_mm")), 0.01), format_step(_num(_sub(r, "post").get("dface_mm")), 0.01)]
            for n, _, r in results if r.get("test") == "compression"]
    return Table(["specimen", "hk, mm", "dmax, mm", "dface, mm"], rows, "measured after the test ('–': not in the result)") if rows else None


def constant_text(value, budget, step: float | None) -> str:
    """A hardening constant as printed: ``'812 ± 14'``, or where its budget is one-sided (a constant on
    its bound: the value lies on the bound's inward side only) its interval as a range, outward to
    ``step``, ``'0–1 (on its lower bound)'``."""
    b = budget if isinstance(budget, dict) else {}
    interval = b.get("interval")
    if b.get("one_sided") and isinstance(interval, (list, tuple)) and len(interval) == 2:
        return f"{format_range(_num(interval[0]), _num(interval[1]), step)} (on its {b['one_sided']} bound)"
    return value_with_U(value, _num(b.get("U")), step)


def hardening_table(results: list) -> Table:
    """The hardening constants table of every result."""
    rows = []
    for n, _, r in results:
        h = r.get("hardening") or {}
        hu = _unc(r).get("hardening") or {}

        def cell(key, h=h, hu=hu):
            """A hardening constant with its U, rounded (:func:`constant_text`)."""
            return constant_text(_num(h.get(key)), hu.get(key), STEPS.get(key))
        rng = h.get("strain_range") or h.get("fit_range") or [None, None]
        law = str(h.get("law") or "–")
        constants = ([cell("A_MPa"), cell("B_MPa"), cell("n")] if law in ("johnson_cook", "–")
                     else ["; ".join(f"{sym} {cell(key)}{' ' + unit if unit else ''}" for sym, key, unit in constant_keys(law)), "", ""])
        rows.append([specimen_id(n, r), display_name_of(law) if law != "–" else law, *constants,
                     f"{format_step(_num(rng[0]), 0.001)} – {format_step(_num(rng[1]), 0.001)}",
                     f"{format_step(_num(h.get('fit_error_pct')), 0.1)} / {format_step(_num(h.get('rms_error_pct')), 0.1)}",
                     str(h.get("quality", "–"))])
    return Table(["specimen", "law", "A, MPa", "B, MPa", "n", "fitted εp range", "max / rms error, %", "quality"], rows,
                 "per specimen: the hardening law fitted to each specimen's own curve (Johnson–Cook's σ = A + B·εpⁿ in the "
                 "A, B, n columns; another law's constants in words in the first); value ± U (k = 2) of that one "
                 "fit (its statistics and the stress scale) — not the constants of the series")


def _verdict(block: dict) -> str:
    c = block.get("conforms")
    return "conforms" if c is True else ("does not conform" if c is False else NOT_STATED)


def conformity_table(results: list, report: Report | None = None) -> Table:
    """The conformity table: each result's checks against its standard."""
    rows = []
    for n, _, r in results:
        conf = (r.get("methods") or {}).get("conformity") or {}
        rate, temp = conf.get("testing_rate") or {}, conf.get("temperature") or {}
        rows.append([specimen_id(n, r), customer_text(f"{_verdict(rate)}: " + "; ".join(rate.get("findings") or ["not evaluated"]), report),
                     customer_text(f"{_verdict(temp)}: " + "; ".join(temp.get("findings") or ["not evaluated"]), report)])
    return Table(["specimen", "testing rate (ISO 6892-1 §10)", "temperature (ISO 6892-1 §10 / ISO 6892-2)"], rows)


def heated_table(results: list) -> Table | None:
    """ISO 6892-2's temperature rows of the heated tests: tolerance, measured deviation, gradient, soak."""
    rows = []
    for n, _, r in results:
        temp = ((r.get("methods") or {}).get("conformity") or {}).get("temperature") or {}
        if not str(temp.get("standard", "")).startswith("ISO 6892-2"):
            continue
        tol, dev = _num(temp.get("tolerance_C")), _num(temp.get("max_deviation_C"))
        gradient, soak = _num(temp.get("gradient_C")), _num(temp.get("soak_min"))
        rows.append([specimen_id(n, r), format_step(_num(temp.get("nominal_C")), 1.0), f"± {tol:g}" if tol else "by agreement",
                     format_step(dev, 0.1) if dev is not None else "not measured",
                     format_step(gradient, 0.1) if gradient is not None else "not measured",
                     format_step(soak, 1.0) if soak is not None else NOT_STATED, _verdict(temp)])
    if not rows:
        return None
    return Table(["specimen", "T, °C", "permitted deviation, °C", "largest deviation, °C", "gradient, °C", "soak, min", "verdict"],
                 rows, "heated tests (ISO 6892-2:2018 §10.3, Table 1; soak at least 10 min before loading)")


BUDGET_NAMES = {"E_MPa": "E, MPa", "Rp02_MPa": "Rp0.2, MPa", "Rm_MPa": "Rm, MPa", "Ag_pct": "Ag, %", "A_pct": "A, %",
                "Z_pct": "Z, %", "friction_mu": "friction μ"}


def budget_tables(name: str, result: dict, report: Report | None = None) -> list:
    """One table per specimen: each result's components, then u_c and U."""
    unc = _unc(result)
    budgets = [(BUDGET_NAMES[k], unc[k]) for k in BUDGET_NAMES if isinstance(unc.get(k), dict) and unc[k].get("components")]
    budgets += [(f"σ at εp {e}, MPa", b) for e, b in (unc.get("flow_stress_MPa") or {}).items()]
    budgets += [(f"{k.replace('_MPa', ', MPa')} (hardening)", b) for k, b in (unc.get("hardening") or {}).items()]
    if not budgets:
        if report is not None:
            report.for_engineer(f"{name}: result.json has no uncertainty budget (identified before budgets existed): identify again.")
        return [Para(f"{name}: no uncertainty budget in the result (evaluated before budgets existed).", "warn")]
    rows = []
    for label, b in budgets:
        for i, c in enumerate(b["components"]):
            unit = f" {c['unit']}" if c["unit"] != "1" else ""
            rows.append([label if i == 0 else "", c["name"], f"{_g(c['value'], 5)}{unit}", _g(c["u"]), _g(c["sensitivity"]),
                         _g(c["contribution"])])
        if b.get("certifiable") is False:
            rows.append([label if not b["components"] else "", "not certifiable (see the note)", f"{_g(b['value'], 5)}", "–", "", "no U"])
            continue
        U_text = f"U = {format_uncertainty(b['U'])}" + (f", one-sided on its {b['one_sided']} bound: " + ("value to value + U" if b["one_sided"] == "lower" else "value − U to value")
                                                              if b.get("one_sided") else "")
        rows.append(["", "combined uc, U (k = 2)", f"{_g(b['value'], 5)}", _g(b["u"]), "", U_text])
    inst = unc.get("instruments") or {}
    facts = (f"{name}: force ISO 7500-1 class {inst.get('force_class', '–')}, extensometer ISO 9513 class "
             f"{inst.get('extensometer_class', '–')}, diameters at {inst.get('diameter_resolution_mm', '–')} mm, lengths at "
             f"{inst.get('length_resolution_mm', '–')} mm; source: {customer_text(str(inst.get('source', '–')), report)}")
    strain = unc.get("strain_scale") or {}
    if strain:
        facts += f". Strain: {strain.get('basis')}, relative u {_g(strain.get('u_rel'))}"
    notes = [f"{label}: {customer_text(b['note'], report)}" for label, b in budgets
             if b.get("note") and not b["note"].startswith("at true plastic strain")]
    notes += [customer_text(n, report) for n in stream_gap_rows_note(result)]
    return [Heading(f"Uncertainty budget — {name}", 3), Para(facts, "note"),
            Table(["result", "input", "value", "u (standard)", "sensitivity c", "contribution |c|·u"], rows),
            *([Para("; ".join(notes), "note")] if notes else [])]


def stream_gap_rows_note(result: dict) -> list[str]:
    """The strain from which the true curve's rows carry a load-cell stream gap's doubt (result.json
    methods.stream_gap_rows), in a sentence; empty without one."""
    rows = (result.get("methods") or {}).get("stream_gap_rows") or {}
    start, most = _num(rows.get("from_plastic_strain")), _num(rows.get("max_u_MPa"))
    if start is None:
        return []
    unread = f"; {rows['rows_without_u']} rows without it (the other reading's curve does not reach their strain)" if rows.get("rows_without_u") else ""
    return [f"true curve: the rows from plastic strain {_g(start, 3)} on carry a load-cell stream gap's doubt (latency or loss "
            f"undecided), up to {_g(most)} MPa; each row's own: true_curve.csv stream_gap_u_MPa{unread}"]


def figures(name: str, folder: Path) -> list:
    """The figures of a result folder's plots, captioned."""
    return [Figure(p, f"{name}: {PLOT_CAPTIONS.get(p.stem, p.stem.replace('_', ' '))}") for p in sorted(folder.glob("*.png"))]


def in_words(text: str) -> str:
    """A warning from the identification with its code names in words (johnson_cook → Johnson–Cook)."""
    for code, word in {**{n: law.display_name for n, law in registered_laws().items()}, **FRICTION_METHODS}.items():
        text = text.replace(code, word)
    return text


def specimen_warnings(results: list, report: Report | None = None) -> list:
    """Each result's warnings as report paragraphs."""
    return [Para(f"{specimen_id(n, r)}: {customer_text(in_words(str(w)), report)}", "warn")
            for n, _, r in results for w in r.get("warnings") or []]


def standards_text() -> str:
    """The rounding and uncertainty statement of the report."""
    rules = "; ".join(f"{what} to {step}" for what, step in ISO_6892_1_RULES)
    return (f"Results are rounded as ISO 6892-1:2019 §22 prescribes ({rules}), or finer where U is finer (§22 allows "
            "'or better'), so that value ± U always holds the unrounded result; other quantities to the steps the "
            "documentation lists. U is the expanded uncertainty (GUM, k = 2, about 95 % coverage) from the instruments' "
            "classes and the fits' statistics, given with two significant digits rounded up. E 'given' is a handbook "
            "value, not measured: it carries no U.")


def signature_block(lab: LabHeader) -> list:
    """The approval block: approved by, signature, date."""
    return [Heading("Approval"), Facts([("approved by", lab.approved_by or NOT_STATED), ("signature", "_" * 30),
                                        ("date", "_" * 16)])]


def series_name(root: Path) -> str:
    """The series' name: the folder's own name, also when given as '.' or with a trailing separator."""
    return root.resolve().name or "series"


def build_content(root, *, lab: LabHeader | None = None, title: str | None = None, fit_blocks=None) -> Report:
    """The report of the series under ``root``. ``fit_blocks(fit_path, fit, material, report)`` adds the series fit's blocks."""
    root = Path(root)
    if not root.is_dir():
        raise ReportError(f"{root}: no such folder")
    fit_path = find_fit(root)
    results = [(n, folder, r) for n, folder, r in find_results(root) if fit_path is None or fit_path.parent not in folder.parents]
    if not results and fit_path is None:
        raise ReportError(f"{root}: no result folders (result.json) and no fit.json to report")
    materials = Counter(str(_rec(r).get("material")) for _, _, r in results if _rec(r).get("material"))
    material = materials.most_common(1)[0][0] if materials else None
    lab = lab or LabHeader()
    series = series_name(root)
    issued = lab.date_of_issue or _dt.date.today().isoformat()
    report = Report(title or f"Test report{': ' + material if material else ''}", lab, number=lab.number(series, issued),
                    issued=issued)
    instruments, problems = calibration(report, results, issued)
    if problems:
        report.not_for_release = cal.NOT_FOR_RELEASE
    header(report, series, results)
    if results:
        report.add(Heading("Standard and method"), Facts(designations(results, lab)), Para(standards_text(), "note"))
        report.add(Heading("Specimens"), specimen_table(results))
        report.add(Heading("Test conditions"), conditions_table(results))
        report.add(Heading("Measuring instruments"), *instruments)
        if problems:
            report.add(Para(f"{cal.NOT_FOR_RELEASE}: " + "; ".join(problems), "warn"))
        report.add(Heading("Results"))
        report.add(*[t for t in (tension_table(results), iso_table(results, report), compression_table(results),
                                 compression_measures(results)) if t is not None])
        report.add(hardening_table(results))
        warnings = specimen_warnings(results, report)
        if warnings:
            report.add(Heading("Warnings", 3), *warnings,
                       Para("U covers the instruments and the fits' statistics, not the identification's own errors that "
                            "these warnings point at.", "note"))
        report.add(Heading("Conformity of the test conditions"), Para(lab.decision_rule_text(), "note"), conformity_table(results, report),
                   *[t for t in (heated_table(results),) if t is not None])
        report.add(Heading("Figures"))
        for n, folder, r in results:
            report.add(*figures(specimen_id(n, r), folder))
    if fit_path is not None and fit_blocks is not None:
        report.add(*fit_blocks(fit_path, _read_json(fit_path), material, report))
    elif fit_path is None:
        report.add(Heading("Johnson–Cook fit of the series"),
                   Para("No series fit in this report; the hardening laws above are per specimen.", "note"))
    if results:
        report.add(Heading("Uncertainty budgets"))
        for n, _, r in results:
            report.add(*budget_tables(specimen_id(n, r), r, report))
    report.add(*signature_block(lab))
    return report

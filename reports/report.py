"""``flowcurve report``: the test report a lab sends its customer, as HTML and PDF.

:func:`write_report` writes ``report.html`` (one file: the figures embedded) and ``report.pdf``
(matplotlib's PDF backend, no browser) from the same content (:mod:`.report_content`), and
the series fit's material card into ``cards/`` beside them, linked from the report.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from flowcurve.errors import FlowcurveError
from flowcurve.reports.lab import LabHeader
from flowcurve.reports.report_content import (Facts, Figure, Heading, Link, Para, Report, ReportError, Table, _g, build_content,
                                              customer_text, find_fit, find_results)
from flowcurve.reports.rounding import STEPS, format_step, value_with_U
from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM

__all__ = ["ReportError", "build_report", "find_fit", "find_results", "report_content", "write_report"]

JC_EQUATION = ("Johnson–Cook: σ = (A + B·εpⁿ)·(1 + C·ln ε*)·(1 − T*ᵐ), with ε* = strain rate / reference strain rate "
               "(at least 1) and T* = (T − Tref)/(Tmelt − Tref) (between 0 and 1)")
FIT_CONSTANTS = (("A_MPa", "A, MPa"), ("B_MPa", "B, MPa"), ("n", "n"), ("C", "C"), ("m", "m"))


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-") or "material"


def card_blocks(fit_path: Path, material: str | None, units: str, cards_dir: Path | None, link_base: Path | None,
                overrides: dict, report: Report) -> list:
    """Write the report's cards (the registry's ``in_report`` formats) into ``cards_dir`` and
    link them; or say what each lacks. The other formats are named for 'flowcurve card'."""
    from flowcurve.reports.cards import FORMATS, report_formats

    blocks: list = [Heading("Material card", 3)]
    shown = report_formats()
    written = [_card_block(fmt, fit_path, material, units, cards_dir, link_base, overrides, report) for fmt in shown]
    blocks += [b for b, _ in written]
    others = [name for name in FORMATS if name not in {f.name for f in shown}]
    if cards_dir is not None and others and any(ok for _, ok in written):
        report.for_engineer(f"Other solvers: 'flowcurve card fit.json --format {'|'.join(others)}'.")
    return blocks


def _card_block(fmt, fit_path: Path, material: str | None, units: str, cards_dir: Path | None, link_base: Path | None,
                overrides: dict, report: Report):
    """One card of format ``fmt`` (a CardFormat) written and linked: (block, written?)."""
    from flowcurve.reports.cards import load_card_data, write_card

    label = f"{fmt.display_name} card"
    try:
        data = load_card_data(fit_path, **overrides)
        if material and data.material == "material":
            data.material = material
        text = write_card(data, fmt.name, units)
    except FlowcurveError as exc:
        report.for_engineer(f"{label} not written: {exc}. Give the missing constant to 'flowcurve report' "
                            "(e.g. --poisson, --density) or write it into fit.json; 'flowcurve card' writes the other formats.")
        return Para(f"{label} not written: {customer_text(str(exc))}.", "warn"), False
    if cards_dir is None:
        return Para(f"{label} ({units}): written beside the report file.", "note"), False
    cards_dir.mkdir(parents=True, exist_ok=True)
    card = cards_dir / f"{_slug(data.material)}-{fmt.name}-{_slug(units)}.{fmt.suffix}"
    card.write_text(text, encoding="utf-8")
    href = card.relative_to(link_base).as_posix() if link_base else card.name
    contents = f", {fmt.contents}" if fmt.contents else ""
    return Link(f"{label} ({units}{contents}): {href}", href), True


def fit_law_rows(fit: dict) -> tuple[str, str, list[list[str]]]:
    """(law name, equation, rows [constant, value ± U (k = 2), how]) of a fit.json: its law block's
    constants (a v1 file is Johnson–Cook's), U twice the total standard uncertainty (the fit's
    standard error and the curves' shape band, fit.json ``total_uncertainty``) where stated, else twice
    the standard error; a fixed constant or one on its bound has no U and says why."""
    from flowcurve.identification.laws.base import get_law
    from flowcurve.identification.laws.fit_file import law_of_fit

    total, fixed, bound = (fit.get(k) or {} for k in ("total_uncertainty", "fixed", "at_bound"))
    if isinstance(fit.get("law"), dict):
        law, values = law_of_fit(fit)
        stderr = {**{k[:-7]: v for k, v in fit.items() if k.endswith("_stderr")}, **(fit["law"].get("stderr") or {})}
        keyed = [(p.key, p.name, f"{p.name}{', ' + p.unit if p.unit else ''}", values.get(p.name)) for p in law.parameters]
    else:
        law, stderr = get_law("johnson_cook"), {k[:-7]: v for k, v in fit.items() if k.endswith("_stderr")}
        keyed = [(key, key.split("_")[0], label, fit.get(key)) for key, label in FIT_CONSTANTS]
    rows = []
    for key, name, label, value in keyed:
        u = total.get(key) if isinstance(total.get(key), (int, float)) else stderr.get(key)
        if key in fixed or name in fixed:
            how, u = "given, not identified", None
        elif key in bound or name in bound:
            how, u = f"on its {bound.get(key) or bound.get(name)} bound: not identified", None
        else:
            how = "fitted"
        U = 2.0 * u if isinstance(u, (int, float)) else None
        rows.append([label, value_with_U(value, U, STEPS.get(key)), how])
    equation = JC_EQUATION if law.name == "johnson_cook" else f"{law.display_name}: {fit['law'].get('equation') or law.equation}"
    return law.name, equation, rows


def fit_blocks_factory(units: str, cards_dir: Path | None, link_base: Path | None, overrides: dict):
    """The report's fit section builder for this unit system, cards folder and constants."""
    def fit_blocks(fit_path: Path, fit: dict, material: str | None, report: Report) -> list:
        """The fitted law's constants ± U (k = 2, :func:`fit_law_rows`), conditions, range, errors, plots, card link."""
        from flowcurve.errors import IdentificationError
        from flowcurve.identification.laws.base import display_name_of

        try:
            law_name, equation, rows = fit_law_rows(fit)
        except IdentificationError as exc:
            raise ReportError(f"{fit_path}: {exc}") from None
        rng = fit.get("range") or {}

        def span(key, step, unit=""):
            """The range of ``key`` as "lo – hi unit" at the rounding ``step``."""
            r = rng.get(key)
            return f"{format_step(r[0], step)} – {format_step(r[1], step)}{unit}" if isinstance(r, list) and len(r) == 2 else "–"

        jc_facts = [("reference strain rate", f"{_g(fit.get('ref_strain_rate_per_s'))} 1/s"),
                    ("reference temperature", f"{format_step(fit.get('ref_temperature_C'), 1.0)} °C"),
                    ("melting temperature", f"{format_step(fit.get('melt_temperature_C'), 1.0)} °C")]
        facts = [("method", str(fit.get("method", "–"))), *(jc_facts if law_name == "johnson_cook" else []),
                 ("identified on: plastic strain", span("plastic_strain", 0.001)),
                 ("identified on: strain rate", span("strain_rate_per_s", None, " 1/s")),
                 ("identified on: temperature", span("temperature_C", 1.0, " °C")),
                 ("max / rms error", f"{format_step(fit.get('fit_error_pct'), 0.1)} / {format_step(fit.get('rms_error_pct'), 0.1)} %")]
        per_record = [[str(r.get("name", "?")), format_step(r.get("temperature_C"), 1.0), _g(r.get("strain_rate_per_s")),
                       format_step(r.get("fit_error_pct"), 0.1), format_step(r.get("rms_error_pct"), 0.1)]
                      for r in fit.get("records") or [] if isinstance(r, dict)]
        if fit.get("equation"):
            report.for_engineer(f"fit.json equation: {fit['equation']}")
        blocks = [Heading(f"{display_name_of(law_name)} fit of the series"), Para(equation, "note"),
                  Table(["constant", "value ± U (k = 2)", ""], rows,
                        "series: one set of constants fitted to all specimens together; U from this fit's statistics and, "
                        "where the fit states it, the curves' shape error (it does not hold the spread between specimens, "
                        "see the per-specimen constants)"), Facts(facts)]
        blocks += [Para(customer_text(str(w), report), "warn") for w in fit.get("warnings") or []]
        if per_record:
            blocks.append(Table(["record", "temperature, °C", "strain rate, 1/s", "max error, %", "rms error, %"], per_record,
                                "error of the fit per record"))
        blocks += [Figure(p, f"series fit: {p.stem.replace('_', ' ')}") for p in sorted((fit_path.parent / "plots").glob("*.png"))]
        blocks.append(Para("The constants hold on the range above only; beyond it the law is extrapolated, at the user's risk.", "warn"))
        return blocks + card_blocks(fit_path, material, units, cards_dir, link_base, overrides, report)
    return fit_blocks


# ---- HTML -----------------------------------------------------------------------------------

STYLE = """body{font-family:'DejaVu Sans',Arial,sans-serif;max-width:1100px;margin:1.5em auto;color:#222;font-size:14px}
h1{font-size:22px;border-bottom:2px solid #444;padding-bottom:4px}h2{font-size:18px;margin-top:1.6em;border-bottom:1px solid #bbb}
h3{font-size:15px}table{border-collapse:collapse;margin:0.6em 0;font-size:13px}th,td{border:1px solid #bbb;padding:3px 7px;
text-align:left;vertical-align:top}thead th{background:#eee}table.facts th{background:#f6f6f6;font-weight:normal;color:#555}
figure{margin:1em 0}img{max-width:100%;height:auto;border:1px solid #ddd}figcaption{font-size:12px;color:#555}
.warn{color:#a00}.release{color:#fff;background:#a00;padding:4px 8px;font-weight:bold}.ident{font-size:12px;color:#555}.note{color:#555;font-size:13px}td.num{white-space:nowrap}caption{text-align:left;caption-side:top}"""


def _cell(text: str) -> str:
    return f"<td class='num'>{html.escape(text)}</td>" if re.match(r"^[-\d.]+( ± [\d.]+)?$", text) else f"<td>{html.escape(text)}</td>"


def to_html(report: Report) -> str:
    """The report as a standalone HTML page."""
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(report.title)}</title>"
             f"<style>{STYLE}</style></head><body>"]
    if report.not_for_release:
        parts.append(f"<p class='release'>{html.escape(report.not_for_release)}</p>")
    parts.append(f"<p class='ident'>report {html.escape(report.number)}, revision {report.lab.revision}, issued "
                 f"{html.escape(report.issued)}</p><h1>{html.escape(report.title)}</h1>")
    for b in report.blocks:
        if isinstance(b, Heading):
            parts.append(f"<h{b.level}>{html.escape(b.text)}</h{b.level}>")
        elif isinstance(b, Para):
            parts.append(f"<p class='{b.kind}'>{html.escape(b.text)}</p>")
        elif isinstance(b, Facts):
            parts.append("<table class='facts'><tbody>" + "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
                                                                  for k, v in b.rows) + "</tbody></table>")
        elif isinstance(b, Table):
            head = "".join(f"<th>{html.escape(c)}</th>" for c in b.columns)
            body = "".join("<tr>" + "".join(_cell(c) for c in row) + "</tr>" for row in b.rows)
            cap = f"<caption class='note'>{html.escape(b.caption)}</caption>" if b.caption else ""
            parts.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
        elif isinstance(b, Figure):
            data = base64.b64encode(b.path.read_bytes()).decode("ascii")
            parts.append(f"<figure><img alt='{html.escape(b.caption)}' src='data:image/png;base64,{data}'>"
                         f"<figcaption>{html.escape(b.caption)}</figcaption></figure>")
        elif isinstance(b, Link):
            parts.append(f"<p><a href='{html.escape(b.href)}'>{html.escape(b.text)}</a></p>")
    if report.engineer:
        parts.append("<hr><h2>For the engineer (not part of the test report)</h2><ul class='note'>"
                     + "".join(f"<li>{html.escape(t)}</li>" for t in report.engineer) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def build_report(root, *, units: str = DEFAULT_UNIT_SYSTEM, title: str | None = None, lab: LabHeader | None = None,
                 cards_dir=None, link_base=None, **overrides) -> str:
    """The report of the series under ``root`` as HTML text (cards written to ``cards_dir`` when given)."""
    return to_html(report_content(root, units, title, lab, cards_dir, link_base, overrides))


def report_content(root, units: str = DEFAULT_UNIT_SYSTEM, title: str | None = None, lab: LabHeader | None = None,
                   cards_dir=None, link_base=None, overrides: dict | None = None) -> Report:
    """The report's content (both renderers' input); cards written to ``cards_dir`` when given."""
    fit_blocks = fit_blocks_factory(units, Path(cards_dir) if cards_dir else None, Path(link_base) if link_base else None, overrides or {})
    return build_content(root, lab=lab, title=title, fit_blocks=fit_blocks)


def write_report(root, output=None, *, units: str = DEFAULT_UNIT_SYSTEM, title: str | None = None, lab: LabHeader | None = None,
                 pdf: bool = True, **overrides) -> list[Path]:
    """Write the series report of the results under ``root`` and the cards it links.

    Parameters
    ----------
    root : str or Path
        The folder of result and fit folders.
    output : str or Path, optional
        The HTML file (default ``root``/report.html); the PDF goes beside it.
    units, title : str
        The cards' unit system; the report's title.
    lab : LabHeader, optional
        The laboratory's header.
    pdf : bool
        Write the PDF too.
    **overrides
        Card constants (E_MPa, poisson …).

    Returns
    -------
    list of Path
        The files written.
    """
    from flowcurve.reports.report_pdf import write_pdf

    out = Path(output) if output else Path(root) / "report.html"
    report = report_content(root, units, title, lab, out.parent / "cards", out.parent, overrides)
    written = []
    try:
        out.write_text(to_html(report), encoding="utf-8")
        written.append(out)
        if pdf:
            written.append(write_pdf(report, out.with_suffix(".pdf")))
    except OSError as exc:
        raise ReportError(f"{out}: cannot write the report: {exc}") from None
    return written

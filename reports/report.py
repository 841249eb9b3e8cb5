"""One self-contained HTML report per test series — what a lab hands to a customer.

Built from a folder holding the result folders of ``flowcurve identify`` (``result.json``,
``true_curve.csv``, PNG plots) and the output of ``flowcurve fit`` (``fit.json`` with its
``curves/`` and ``plots/``): the specimens, their results, the plots (embedded as base64, so
the file stands alone), the Johnson–Cook constants with their uncertainties and range, and
the LS-DYNA card.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
from collections import Counter
from pathlib import Path

from flowcurve import __version__
from flowcurve.errors import FlowcurveError
from flowcurve.reports.cards import CardData, load_card_data, write_card
from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM
from flowcurve.identification.outcome import read_json_object


class ReportError(FlowcurveError):
    """A report folder that holds nothing to report, or files that cannot be read."""


SPECIMEN_COLUMNS = (  # (heading, getter on (name, result))
    ("specimen", lambda n, r: n),
    ("test", lambda n, r: r.get("test")),
    ("material", lambda n, r: _rec(r).get("material")),
    ("d0 (mm)", lambda n, r: _spec(r, "d0_mm")),
    ("l0 / h0 (mm)", lambda n, r: _spec(r, "l0_mm") if _spec(r, "l0_mm") is not None else _spec(r, "h0_mm")),
    ("temperature (°C)", lambda n, r: _rec(r).get("nominal_temperature_C")),
    ("crosshead speed (mm/s)", lambda n, r: _rec(r).get("crosshead_speed_mm_per_s")),
    ("strain rate (1/s)", lambda n, r: _rec(r).get("strain_rate_per_s")),
    ("record", lambda n, r: _rec(r).get("path")),
)
RESULT_COLUMNS = (
    ("specimen", lambda n, r: n),
    ("E (MPa)", lambda n, r: r.get("E_MPa")),
    ("Rp0.2 (MPa)", lambda n, r: r.get("Rp02_MPa")),
    ("Rm (MPa)", lambda n, r: r.get("Rm_MPa")),
    ("Ag (%)", lambda n, r: r.get("Ag_pct")),
    ("A (%)", lambda n, r: r.get("A_pct")),
    ("Z (%)", lambda n, r: r.get("Z_pct")),
    ("fracture true strain", lambda n, r: r.get("fracture_true_strain")),
    ("fracture true stress (MPa)", lambda n, r: r.get("fracture_true_stress_MPa")),
    ("friction μ", lambda n, r: r.get("friction_mu")),
    ("hardening", lambda n, r: _hardening(r)),
)


def _rec(result: dict) -> dict:
    block = result.get("record")
    return block if isinstance(block, dict) else {}


def _spec(result: dict, key: str):
    spec = _rec(result).get("specimen")
    if isinstance(spec, dict) and spec.get(key) is not None:
        return spec.get(key)
    return _rec(result).get(f"specimen.{key}")


def _hardening(result: dict) -> str | None:
    h = result.get("hardening")
    if not isinstance(h, dict):
        return None
    params = ", ".join(f"{k.replace('_MPa', '')} = {_fmt(h[k])}" for k in ("A_MPa", "B_MPa", "n", "K_MPa", "eps0", "sigma0_MPa", "Q_MPa", "b")
                       if h.get(k) is not None)
    err = f" (max error {_fmt(h['fit_error_pct'])} %)" if h.get("fit_error_pct") is not None else ""
    return f"{h.get('law', '')}: {params}{err}"


def _fmt(value) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, (int, float)):
        return f"{value:.6g}"
    return str(value)


def _read_json(path: Path) -> dict:
    return read_json_object(path, ReportError)


def find_results(root: Path) -> list[tuple[str, Path, dict]]:
    """(name, folder, result.json) of every identify result folder under ``root``."""
    out = []
    for path in sorted(root.rglob("result.json")):
        out.append((path.parent.name, path.parent, _read_json(path)))
    return out


def find_fit(root: Path) -> Path | None:
    """The series fit under ``root`` (the shallowest ``fit.json``)."""
    fits = sorted(root.rglob("fit.json"), key=lambda p: (len(p.parts), str(p)))
    return fits[0] if fits else None


def png_tag(path: Path, caption: str) -> str:
    """An <img> with the PNG embedded as base64 (the report stays one file)."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (f'<figure><img alt="{html.escape(caption)}" src="data:image/png;base64,{data}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def table(columns, rows) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h, _ in columns)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(_fmt(get(n, r)))}</td>" for _, get in columns) + "</tr>"
                   for n, r in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def fit_section(fit_path: Path, fit: dict) -> str:
    """Constants with uncertainties, reference condition, range, errors per record, plots."""
    rows = []
    for key, label in (("A_MPa", "A (MPa)"), ("B_MPa", "B (MPa)"), ("n", "n"), ("C", "C"), ("m", "m")):
        fixed = key in (fit.get("fixed") or {})
        note = "given, not identified" if fixed else ""
        rows.append(f"<tr><td>{label}</td><td>{_fmt(fit.get(key))}</td><td>{_fmt(fit.get(key + '_stderr'))}</td>"
                    f"<td>{note}</td></tr>")
    constants = ("<table><thead><tr><th>constant</th><th>value</th><th>standard error</th><th></th></tr></thead>"
                 f"<tbody>{''.join(rows)}</tbody></table>")
    rng = fit.get("range") or {}

    def span(key, unit=""):
        r = rng.get(key)
        return f"{_fmt(r[0])} – {_fmt(r[1])}{unit}" if isinstance(r, list) and len(r) == 2 else "–"

    facts = [
        ("method", fit.get("method")),
        ("reference strain rate (1/s)", fit.get("ref_strain_rate_per_s")),
        ("reference temperature (°C)", fit.get("ref_temperature_C")),
        ("melting temperature (°C)", fit.get("melt_temperature_C")),
        ("identified on: plastic strain", span("plastic_strain")),
        ("identified on: strain rate", span("strain_rate_per_s", " 1/s")),
        ("identified on: temperature", span("temperature_C", " °C")),
        ("max / rms error (%)", f"{_fmt(fit.get('fit_error_pct'))} / {_fmt(fit.get('rms_error_pct'))}"),
        ("friction μ (mean of compression tests)", fit.get("friction_mu")),
    ]
    facts_html = "<table><tbody>" + "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(_fmt(v))}</td></tr>"
                                            for k, v in facts) + "</tbody></table>"
    per_record = [(r.get("name", "?"), r) for r in fit.get("records") or [] if isinstance(r, dict)]
    rec_cols = (("record", lambda n, r: n), ("temperature (°C)", lambda n, r: r.get("temperature_C")),
                ("strain rate (1/s)", lambda n, r: r.get("strain_rate_per_s")),
                ("max error (%)", lambda n, r: r.get("fit_error_pct")), ("rms error (%)", lambda n, r: r.get("rms_error_pct")))
    warnings = "".join(f"<li>{html.escape(str(w))}</li>" for w in fit.get("warnings") or [])
    plots = "".join(png_tag(p, f"fit: {p.stem.replace('_', ' ')}") for p in sorted((fit_path.parent / "plots").glob("*.png")))
    return (f"<h2>Johnson–Cook fit of the series</h2><p class='eq'>{html.escape(str(fit.get('equation', '')))}</p>"
            f"<p>fit file: <code>{html.escape(str(fit_path))}</code></p>{constants}{facts_html}"
            + (f"<h3>Fit warnings</h3><ul>{warnings}</ul>" if warnings else "")
            + (f"<h3>Error per record</h3>{table(rec_cols, per_record)}" if per_record else "")
            + (f"<h3>Curves and fit</h3>{plots}" if plots else "")
            + "<p class='warn'>The constants are valid on the range above only; extrapolation beyond it is the user's risk.</p>")


def card_section(fit_path: Path, units: str, material: str | None, overrides: dict) -> str:
    """The LS-DYNA card, or why it could not be written (e.g. a constant missing)."""
    try:
        data: CardData = load_card_data(fit_path, **overrides)
        if material and data.material == "material":
            data.material = material
        text = write_card(data, "lsdyna", units)
    except FlowcurveError as exc:
        return (f"<h2>LS-DYNA material card</h2><p class='warn'>No card in this report: {html.escape(str(exc))}. "
                "Give the missing constant to 'flowcurve report' (e.g. --density) or write it into fit.json.</p>")
    return (f"<h2>LS-DYNA material card ({html.escape(units)})</h2>"
            f"<pre class='card'>{html.escape(text)}</pre>")


STYLE = """body{font-family:sans-serif;max-width:1200px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:90%}th,td{border:1px solid #bbb;padding:3px 8px;text-align:left}
thead th{background:#eee}figure{display:inline-block;margin:0.5em}img{max-width:560px}
pre.card{background:#f6f6f6;padding:1em;font-size:80%;overflow-x:auto}.warn{color:#a00}.eq{font-family:monospace}"""


def build_report(root, *, units: str = DEFAULT_UNIT_SYSTEM, title: str | None = None, **overrides) -> str:
    """The report of the series under ``root`` as HTML text."""
    root = Path(root)
    if not root.is_dir():
        raise ReportError(f"{root}: no such folder")
    fit_path = find_fit(root)
    results = [(n, folder, r) for n, folder, r in find_results(root)
               if fit_path is None or fit_path.parent not in folder.parents]
    if not results and fit_path is None:
        raise ReportError(f"{root}: no result folders (result.json) and no fit.json to report")
    materials = Counter(str(_rec(r).get("material")) for _, _, r in results if _rec(r).get("material"))
    material = materials.most_common(1)[0][0] if materials else None
    title = title or f"Material test report{': ' + material if material else ''}"
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{STYLE}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p>flowcurve {__version__}, {_dt.date.today().isoformat()}; series folder <code>{html.escape(str(root))}</code>; "
             f"{len(results)} specimen(s).</p>"]
    if results:
        rows = [(n, r) for n, _, r in results]
        parts.append(f"<h2>Specimens</h2>{table(SPECIMEN_COLUMNS, rows)}")
        parts.append(f"<h2>Results</h2>{table(RESULT_COLUMNS, rows)}")
        for name, folder, result in results:
            figures = "".join(png_tag(p, f"{name}: {p.stem.replace('_', ' ')}") for p in sorted(folder.glob("*.png")))
            warnings = "".join(f"<li>{html.escape(str(w))}</li>" for w in result.get("warnings") or [])
            if figures or warnings:
                parts.append(f"<h3>{html.escape(name)}</h3>" + (f"<ul>{warnings}</ul>" if warnings else "") + figures)
    if fit_path is not None:
        parts.append(fit_section(fit_path, _read_json(fit_path)))
        parts.append(card_section(fit_path, units, material, overrides))
    else:
        parts.append("<h2>Johnson–Cook fit</h2><p>No fit.json in this folder: run 'flowcurve fit' on the series first.</p>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_report(root, output=None, *, units: str = DEFAULT_UNIT_SYSTEM, title: str | None = None, **overrides) -> Path:
    """Write the report (default ``root/report.html``) and return its path."""
    text = build_report(root, units=units, title=title, **overrides)
    out = Path(output) if output else Path(root) / "report.html"
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ReportError(f"{out}: cannot write the report: {exc}") from None
    return out

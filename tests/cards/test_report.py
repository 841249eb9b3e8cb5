"""``flowcurve report``: the test report (HTML and PDF) of a synthetic series and of a real record."""

import base64
import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from flowcurve.cli import main  # noqa: E402
from flowcurve.reports.report import ReportError, build_report  # noqa: E402
from flowcurve.reports.rounding import format_step, format_uncertainty, round_step, value_with_U  # noqa: E402

from .conftest import jc_MPa, make_fit  # noqa: E402

SPECIMENS = [("C_T20_r0.001", 20.0, 1e-3), ("C_T20_r0.01", 20.0, 1e-2), ("C_T400_r0.001", 400.0, 1e-3),
             ("C_T400_r0.01", 400.0, 1e-2)]


def make_series(root, fit="synthetic"):
    """Result folders as 'flowcurve identify' writes them, from a known Johnson–Cook law."""
    for name, T, rate in SPECIMENS:
        folder = root / "results" / name
        folder.mkdir(parents=True)
        eps = np.linspace(0.0, 0.3, 120)
        pd.DataFrame({"true_plastic_strain": eps, "true_stress_MPa": jc_MPa(eps, rate, T)}).to_csv(folder / "true_curve.csv", index=False)
        result = {"test": "compression", "E_MPa": 194000.0, "Rp02_MPa": float(jc_MPa(0.002, rate, T)), "friction_mu": 0.11,
                  "hardening": {"law": "johnson_cook", "A_MPa": 105.0, "B_MPa": 1392.0, "n": 0.642, "fit_error_pct": 0.4},
                  "record": {"path": f"/lab/{name}.csv", "material": "12Kh18N12M3TL", "nominal_temperature_C": T,
                             "crosshead_speed_mm_per_s": rate * 7.0, "strain_rate_per_s": rate,
                             "specimen": {"d0_mm": 6.0, "h0_mm": 7.0}}}
        (folder / "result.json").write_text(json.dumps(result))
        fig, ax = plt.subplots(figsize=(2, 2))
        ax.plot(eps, jc_MPa(eps, rate, T))
        fig.savefig(folder / "stress_strain.png")
        plt.close(fig)
    if fit == "synthetic":
        (root / "fit").mkdir()
        (root / "fit" / "fit.json").write_text(json.dumps(make_fit(root / "fit", density_kg_per_m3=None)))
    elif fit == "real":
        assert main(["fit", str(root / "results"), "--out", str(root / "fit"), "--melt-temp", "1400"]) == 0
    return root


def images(text):
    return re.findall(r"src='data:image/png;base64,([A-Za-z0-9+/=]+)'", text)


def test_report_holds_specimens_results_constants_plots_and_a_linked_card(tmp_path, capsys):
    root = make_series(tmp_path / "series")
    out = tmp_path / "out" / "report.html"
    out.parent.mkdir()
    assert main(["report", str(root), "-o", str(out), "--density", "7820"]) == 0
    text = out.read_text(encoding="utf-8")
    for name, _, _ in SPECIMENS:
        assert text.count(name) >= 2  # in the specimens and the results tables
    assert "12Kh18N12M3TL" in text
    assert "C_T400_r0.01.csv" in text and "/lab/" not in text  # the record's file name, not its absolute path
    assert str(tmp_path) not in text
    # the fit's constants rounded, with U = 2 × standard error beside them
    assert "<td class='num'>105.0 ± 4.2</td>" in text and "<td class='num'>1392 ± 70</td>" in text  # never coarser than U
    assert "<td class='num'>0.642 ± 0.020</td>" in text
    # self-contained: every image is inline, and a real PNG
    assert not re.search(r"src='(?!data:)", text)
    pngs = images(text)
    assert len(pngs) == len(SPECIMENS)
    assert all(base64.b64decode(p).startswith(b"\x89PNG") for p in pngs)
    # the card is linked, not pasted, and readable by the independent LS-DYNA reader
    assert "<pre" not in text and "*KEYWORD" not in text
    href = re.search(r"<a href='(cards/[^']+\.k)'>", text).group(1)
    card = (out.parent / href).read_text(encoding="utf-8")
    dyna = pytest.importorskip("ansys.dyna.core")
    deck = dyna.Deck()
    deck.loads(card)
    jc = [k for k in deck.keywords if type(k).__name__ == "MatJohnsonCook"][0]
    assert jc.a == pytest.approx(105.0) and jc.ro == pytest.approx(7.82e-9)
    assert "user&#x27;s risk" in text
    pdf = out.with_suffix(".pdf").read_bytes()
    assert pdf.startswith(b"%PDF") and len(re.findall(rb"/Type /Page\b", pdf)) >= 2
    assert "report.pdf" in capsys.readouterr().err


def test_report_without_a_constant_still_written_and_says_why(tmp_path):
    root = make_series(tmp_path / "series")
    text = build_report(root)  # the synthetic fit.json has no density
    assert "LS-DYNA card not written" in text and "--density" in text
    assert "<h2>Specimens</h2>" in text
    # the synthetic results carry no budgets: the report says so instead of showing values as exact
    assert "no uncertainty budget in the result" in text


def test_report_of_a_real_series_fit(tmp_path):
    """End to end with the series engineer's 'flowcurve fit' writing fit.json and its plots."""
    root = make_series(tmp_path / "series", fit="real")
    text = build_report(root, units="mm-ms-kg-kN-GPa", density_kg_per_m3=7820.0, poisson=0.25, specific_heat_J_per_kgK=462.0,
                        cards_dir=tmp_path / "cards", link_base=tmp_path)
    fit = json.loads((root / "fit" / "fit.json").read_text())
    assert fit["A_MPa"] == pytest.approx(105.0, rel=1e-3)  # the law the series was made from
    # U = 2 × the total standard uncertainty (the fit's standard error and the curves' shape band), not the standard error alone
    assert fit["total_uncertainty"]["A_MPa"] > fit["A_MPa_stderr"]
    assert f"<td class='num'>{value_with_U(fit['A_MPa'], 2 * fit['total_uncertainty']['A_MPa'], 1.0)}</td>" in text
    assert "Johnson–Cook fit of the series" in text
    assert len(images(text)) > len(SPECIMENS)  # the fit's plots too
    card = next((tmp_path / "cards").glob("*.k")).read_text()
    assert "*MAT_JOHNSON_COOK" in card and "mm-ms-kg-kN-GPa" in text


def test_report_of_a_real_record_rounds_and_states_U_and_conformity(tmp_path):
    """46NT71 (INSTRON, extensometer): §22 rounding, U beside each value, E measured, method B."""
    rec = Path(__file__).resolve().parents[2] / "examples" / "data" / "46NT71.csv"
    assert main(["identify", str(rec), "--out", str(tmp_path / "series"), "--no-plots"]) == 0
    result = json.loads((tmp_path / "series" / "46NT71" / "result.json").read_text())
    lab = tmp_path / "lab.toml"
    lab.write_text('[lab]\nname = "Prüflabor Nord"\naccreditation = "ISO/IEC 17025, D-PL-00000-01-00"\nreport_number = "2026-0147"\n')
    assert main(["report", str(tmp_path / "series"), "--lab", str(lab)]) == 0
    text = (tmp_path / "series" / "report.html").read_text(encoding="utf-8")
    unc = result["uncertainty"]
    for key, step in (("Rp02_MPa", 1.0), ("Rm_MPa", 1.0), ("Ag_pct", 0.5), ("A_pct", 0.5), ("Z_pct", 1.0)):
        assert f"<td class='num'>{value_with_U(result[key], unc[key]['U'], step)}</td>" in text, key
    assert "<td class='num'>1132 ± 19</td>" in text and "<td class='num'>14.60 ± " in text  # 1132.36 MPa (U with the rate's term, issue 43), 14.60 %
    assert "measured (extensometer)" in text
    assert "<td>2 warning(s) below</td>" in text and "taken as 23 °C" in text  # the row points at its warnings (RT, the yield point)
    rate = result["methods"]["conformity"]["testing_rate"]
    assert 30 <= rate["stress_rate_MPa_per_s"] <= 50  # the elastic stress rate of this record (39–41 MPa/s by the modulus window)
    assert rate["designation"] == f"ISO 6892-1:2019 B{rate['stress_rate_MPa_per_s']:.0f}"
    assert rate["designation"] in text and "conforms" in text
    assert "Prüflabor Nord" in text and "2026-0147" in text and "Lab header: defaults" not in text
    assert "46NT71.csv" in text and str(rec.parent) not in text


@pytest.mark.parametrize("value, step, text", [(1132.358, 1.0, "1132"), (1132.5, 1.0, "1132"), (1133.5, 1.0, "1134"),
                                               (14.6028, 0.5, "14.5"), (14.75, 0.5, "15.0"), (14.25, 0.5, "14.0"),
                                               (55.4178, 1.0, "55"), (0.35, 0.1, "0.4"), (0.45, 0.1, "0.4")])
def test_iso_6892_1_rounding_ties_go_to_the_even_multiple(value, step, text):
    assert format_step(value, step) == text
    assert round_step(value, step) == pytest.approx(float(text))


@pytest.mark.parametrize("U, text", [(13.337, "14"), (0.2385, "0.24"), (0.0105, "0.011"), (4.0, "4.0"), (100.0, "100"),
                                     (0.02, "0.020")])
def test_expanded_uncertainty_two_significant_digits_rounded_up(U, text):
    assert format_uncertainty(U) == text


def test_lab_file_with_an_unknown_key_is_a_one_line_error(tmp_path, capsys):
    root = make_series(tmp_path / "series")
    lab = tmp_path / "lab.toml"
    lab.write_text('[lab]\nnmae = "typo"\n')
    assert main(["report", str(root), "--lab", str(lab)]) == 2
    err = capsys.readouterr().err
    assert "lab.toml: [lab] nmae: unknown key" in err and "Traceback" not in err


def test_empty_folder_is_a_one_line_error(tmp_path, capsys):
    with pytest.raises(ReportError, match="no result folders"):
        build_report(tmp_path)
    assert main(["report", str(tmp_path / "missing")]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_report_of_another_laws_series_fit_names_that_law_and_its_constants(tmp_path):
    """A Hensel–Spittel series fit (fit.json v2's law block) is reported as Hensel–Spittel with its own
    constants ± 2 × their total uncertainty — not under Johnson–Cook's heading with JC's empty columns."""
    from flowcurve.identification.laws.base import get_law
    from flowcurve.reports.report import fit_law_rows

    law = get_law("hensel_spittel")
    params = {p.key: v for p, v in zip(law.parameters, (1500.0, -0.0028, 0.16, 0.13, 0.0005, 4e-5, -0.33, 1e-7, -0.002))}
    total = {k: abs(v) * 0.1 for k, v in params.items()}
    total["m8_per_C"] = None
    fit = {"schema": "flowcurve-fit/2", "law": {"name": "hensel_spittel", "parameters": params, "stderr": {}, "conditions": {}},
           "total_uncertainty": total, "fixed": {}, "at_bound": {"m8": "lower"}}
    name, equation, rows = fit_law_rows(fit)
    assert name == "hensel_spittel" and equation.startswith("Hensel–Spittel: ")
    by_label = {r[0]: r for r in rows}
    assert by_label["A, MPa"][1] == value_with_U(1500.0, 300.0, None) and by_label["A, MPa"][2] == "fitted"
    assert by_label["m8, 1/°C"][2] == "on its lower bound: not identified" and "±" not in by_label["m8, 1/°C"][1]
    assert [r[0].split(",")[0] for r in rows] == [p.name for p in law.parameters]


def test_a_constant_on_its_bound_prints_its_one_sided_interval_as_a_range():
    """A one-sided budget (docs/methods.md §2.12) prints [bound, bound + U] outward to the step, never '0 ± U'."""
    from flowcurve.reports.report_content import constant_text

    on = {"value": 0.0, "U": 0.4, "interval": [0.0, 0.4], "one_sided": "lower"}
    assert constant_text(0.0, on, 1.0) == "0–1 (on its lower bound)"
    assert constant_text(812.3, {"value": 812.3, "U": 13.2}, 1.0) == value_with_U(812.3, 13.2, 1.0) == "812 ± 14"
    assert constant_text(812.3, None, 1.0) == "812"

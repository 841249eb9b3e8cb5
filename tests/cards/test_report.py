"""``flowcurve report``: a self-contained HTML document of a synthetic series."""

import base64
import html
import json
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from flowcurve.cli import main  # noqa: E402
from flowcurve.reports.report import ReportError, build_report  # noqa: E402

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
    return re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', text)


def test_report_holds_specimens_results_constants_plots_and_card(tmp_path, capsys):
    root = make_series(tmp_path / "series")
    out = tmp_path / "report.html"
    assert main(["report", str(root), "-o", str(out), "--density", "7820"]) == 0
    text = out.read_text(encoding="utf-8")
    for name, _, _ in SPECIMENS:
        assert text.count(name) >= 2  # in the specimens and the results tables
    assert "12Kh18N12M3TL" in text and "/lab/C_T400_r0.01.csv" in text
    for constant in ("105", "1392", "0.642", "0.01", "0.517"):
        assert f"<td>{constant}</td>" in text
    assert "<td>2.1</td>" in text  # the standard error of A
    # self-contained: every image is inline, and a real PNG
    assert not re.search(r'src="(?!data:)', text)
    pngs = images(text)
    assert len(pngs) == len(SPECIMENS)
    assert all(base64.b64decode(p).startswith(b"\x89PNG") for p in pngs)
    # the card is there, complete, and readable by the independent LS-DYNA reader
    card = html.unescape(re.search(r"<pre class='card'>(.*?)</pre>", text, re.S).group(1))
    dyna = pytest.importorskip("ansys.dyna.core")
    deck = dyna.Deck()
    deck.loads(card)
    jc = [k for k in deck.keywords if type(k).__name__ == "MatJohnsonCook"][0]
    assert jc.a == pytest.approx(105.0) and jc.ro == pytest.approx(7.82e-9)
    assert "user's risk" in text


def test_report_without_a_constant_still_written_and_says_why(tmp_path):
    root = make_series(tmp_path / "series")
    text = build_report(root)  # the synthetic fit.json has no density
    assert "No card in this report" in text and "--density" in text
    assert "<h2>Specimens</h2>" in text


def test_report_of_a_real_series_fit(tmp_path):
    """End to end with the series engineer's 'flowcurve fit' writing fit.json and its plots."""
    root = make_series(tmp_path / "series", fit="real")
    text = build_report(root, units="mm-ms-kg-kN-GPa", density_kg_per_m3=7820.0, poisson=0.25, specific_heat_J_per_kgK=462.0)
    fit = json.loads((root / "fit" / "fit.json").read_text())
    assert fit["A_MPa"] == pytest.approx(105.0, rel=1e-3)  # the law the series was made from
    assert f"<td>{fit['A_MPa']:.6g}</td>" in text and f"<td>{fit['m']:.6g}</td>" in text
    assert len(images(text)) > len(SPECIMENS)  # the fit's plots too
    assert "*MAT_JOHNSON_COOK" in text and "mm-ms-kg-kN-GPa" in text


def test_empty_folder_is_a_one_line_error(tmp_path, capsys):
    with pytest.raises(ReportError, match="no result folders"):
        build_report(tmp_path)
    assert main(["report", str(tmp_path / "missing")]) == 2
    assert "no such folder" in capsys.readouterr().err

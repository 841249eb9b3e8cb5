"""'flowcurve fit' end to end on result folders written in the documented format."""

import json

import numpy as np
import pandas as pd
import pytest

from flowcurve.cli import main
from flowcurve.errors import RecordError
from flowcurve.identification.series.series import member_from_result


def _series_folders(tmp_path, syn, **kw):
    root = tmp_path / "results"
    for m in syn.members():
        syn.write_result_folder(root / m.name, m, **kw)
    return root


def _run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_fit_command_writes_fit_json_curves_and_plots(tmp_path, syn, capsys):
    root = _series_folders(tmp_path, syn, E_MPa=205000.0)
    out = tmp_path / "fit"
    code, text, err = _run(["fit", str(root), "--out", str(out), "--ref-rate", "1", "--ref-temp", "24.85",
                            "--melt-temp", "1519.85"], capsys)
    assert code == 0, err
    assert "A = " in text and "identified on:" in text and "stepwise for comparison" in text
    d = json.loads((out / "fit.json").read_text())
    for key, p in (("A_MPa", "A"), ("B_MPa", "B"), ("n", "n"), ("C", "C"), ("m", "m")):
        assert abs(d[key] - syn.TRUE[p]) <= 3 * d[f"{key}_stderr"], key
    assert d["ref_strain_rate_per_s"] == 1.0 and d["melt_temperature_C"] == 1519.85 and d["method"] == "global"
    assert d["range"]["strain_rate_per_s"] == [1.0, 100.0] and d["range"]["temperature_C"][1] == 600.0
    assert d["E_MPa"] == 205000.0 and d["friction_mu"] is None and d["material"] == "4340"
    assert d["stepwise"]["C"] == pytest.approx(syn.TRUE["C"], rel=0.05)
    assert len(d["records"]) == 6 and len(d["curves"]) == 6
    for rec in d["records"]:
        assert rec["kind"] == "result" and rec["strain_rate_source"] == "result.json"
        png = (out / rec["plot"]).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        table = pd.read_csv(out / rec["curve"])
        assert list(table.columns) == ["true_plastic_strain", "true_stress_MPa"]
        # one record per condition: the table is the record's own curve
        source = pd.read_csv(root / rec["name"] / "true_curve.csv")
        np.testing.assert_allclose(table.to_numpy(), source.to_numpy(), rtol=1e-5)
    assert (out / "plots" / "all_records.png").stat().st_size > 1000


def test_rate_from_crosshead_speed_when_the_result_has_none(tmp_path, syn):
    m = syn.members()[1]
    folder = syn.write_result_folder(tmp_path / "r", m, with_rate=False, l0_mm=25.0)
    got = member_from_result(folder)
    assert got.strain_rate_source == "crosshead speed / gauge length"
    assert got.strain_rate_per_s == pytest.approx(m.strain_rate_per_s)  # speed was written as rate·l0
    folder_c = syn.write_result_folder(tmp_path / "c", m, with_rate=False, test="compression", l0_mm=8.0, friction_mu=0.12)
    got_c = member_from_result(folder_c)
    assert got_c.test == "compression" and got_c.friction_mu == 0.12
    assert got_c.strain_rate_per_s == pytest.approx(m.strain_rate_per_s)


def test_friction_mean_of_compression_records_and_fixed_m(tmp_path, syn, capsys):
    root = tmp_path / "results"
    mus = iter([0.10, 0.14])
    for m in syn.members(temperatures=(300.0,)):
        syn.write_result_folder(root / m.name, m, test="compression", l0_mm=9.0, friction_mu=next(mus))
    out = tmp_path / "fit"
    code, text, err = _run(["fit", str(root), "--out", str(out), "--ref-rate", "1", "--ref-temp", "24.85",
                            "--melt-temp", "1519.85", "--fix-m", "1.03"], capsys)
    assert code == 0, err
    d = json.loads((out / "fit.json").read_text())
    assert d["friction_mu"] == pytest.approx(0.12) and d["friction_mu_records"] == 2
    assert d["fixed"] == {"m": 1.03} and d["m"] == 1.03 and d["m_stderr"] is None
    assert "m was not identified" in d["warnings"][0] and "fixed, not identified" in text
    assert d["stepwise"] is None and d["stepwise_note"].startswith("no stepwise comparison")


@pytest.mark.parametrize("case,pattern", [
    ("one_temperature", r"m \(--fix-m\): the series has one temperature"),
    ("no_temperature", r"result\.json: record\.nominal_temperature_C is missing"),
    ("no_melt", r"melting temperature, °C \(--melt-temp\)"),
    ("missing_path", r"nothing_here: no such file or folder"),
    ("empty_folder", r"without result\.json"),
])
def test_bad_input_is_one_line_naming_the_problem(tmp_path, syn, capsys, case, pattern):
    root = tmp_path / "results"
    opts = ["--melt-temp", "1519.85"]
    if case == "one_temperature":
        for m in syn.members(temperatures=(300.0,)):
            syn.write_result_folder(root / m.name, m)
    elif case == "no_temperature":
        for i, m in enumerate(syn.members()):
            syn.write_result_folder(root / m.name, m, temperature=i != 3)
    elif case == "no_melt":
        root = _series_folders(tmp_path, syn)
        opts = []
    elif case == "missing_path":
        root = tmp_path / "nothing_here"
    else:
        root.mkdir()
    code, _, err = _run(["fit", str(root), "--out", str(tmp_path / "fit"), *opts], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flowcurve: error: "), err
    import re
    assert re.search(pattern, lines[0]), lines[0]
    if case == "no_temperature":
        assert syn.members()[3].name in lines[0]  # names the record


def test_fit_with_nothing_optional_names_every_missing_input_at_once(tmp_path, syn, capsys):
    """A series at one temperature and one rate, no option given: the melting temperature, C and m
    in one message (they were asked for one refused run at a time), and no output folder."""
    root = tmp_path / "results"
    for m in syn.members(temperatures=(300.0,), rates=(1.0,)):
        syn.write_result_folder(root / m.name, m)
    out = tmp_path / "fit"
    code, _, err = _run(["fit", str(root), "--out", str(out)], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "needs 3 input(s)" in lines[0], err
    for option in ("--melt-temp", "--fix-C", "--fix-m"):
        assert option in lines[0]
    assert not out.exists()
    # with the melting temperature and C given, m alone is named
    code, _, err = _run(["fit", str(root), "--out", str(out), "--melt-temp", "1519.85", "--fix-C", "0.014"], capsys)
    assert code == 2 and "needs 1 input(s)" in err and "--fix-m" in err and "--fix-C" not in err and not out.exists()


def test_unreadable_true_curve_names_the_file(tmp_path, syn):
    m = syn.members()[0]
    folder = syn.write_result_folder(tmp_path / "r", m)
    (folder / "true_curve.csv").write_text("strain,stress\n0.1,500\n", encoding="utf-8")
    with pytest.raises(RecordError, match=r"true_curve\.csv: missing column\(s\) true_plastic_strain"):
        member_from_result(folder)


@pytest.mark.parametrize("result_json,curve,pattern", [
    ('{"test": "tension", "record": [1, 2]}', None, r"result\.json: 'record' is not a JSON object"),
    ("{not json", None, r"result\.json: is not valid JSON"),
    (None, "true_plastic_strain,true_stress_MPa\n0.01,abc\n0.02,510\n", r"true_curve\.csv: the curve holds cells that are not numbers"),
    (None, "", r"true_curve\.csv: cannot be read as CSV"),
])
def test_broken_result_folders_name_the_file(tmp_path, syn, result_json, curve, pattern):
    folder = syn.write_result_folder(tmp_path / "r", syn.members()[0])
    if result_json is not None:
        (folder / "result.json").write_text(result_json, encoding="utf-8")
    if curve is not None:
        (folder / "true_curve.csv").write_text(curve, encoding="utf-8")
    with pytest.raises(RecordError, match=pattern):
        member_from_result(folder)

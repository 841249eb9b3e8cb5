"""Johnson-Cook fracture constants D1-D5 (2.22): the fit recovers known constants from a noisy
fracture table; Bridgman triaxiality and the fracture table reader."""

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification.series.damage import (FracturePoint, bridgman_triaxiality, fit_damage, fracture_strain_from_diameters,
                                             read_fracture_points)

# docs/methods.md §5, table 3.2, steel 45 (140 HB): D1..D5 = 0, 1.3, -0.17, 0.063, 2.8
STEEL45 = dict(D1=0.0, D2=1.3, D3=-0.17, D4=0.063, D5=2.8)
REF = dict(ref_strain_rate_per_s=1e-3, ref_temperature_C=20.0, melt_temperature_C=1500.0)


def true_locus(tri, rate, temp, d=STEEL45):
    """(2.22) written out here, independently of the package."""
    lr = np.maximum(np.log(np.asarray(rate, float) / REF["ref_strain_rate_per_s"]), 0.0)
    ts = np.clip((np.asarray(temp, float) - REF["ref_temperature_C"]) / (REF["melt_temperature_C"] - REF["ref_temperature_C"]), 0, 1)
    return (d["D1"] + d["D2"] * np.exp(d["D3"] * np.asarray(tri, float))) * (1 + d["D4"] * lr) * (1 + d["D5"] * ts)


def table(noise=0.02, seed=3, d=STEEL45):
    """Smooth and notched bars (Bridgman 1/3 .. 1.72), three rates, three temperatures, 2 % noise."""
    rng = np.random.default_rng(seed)
    tris = [1 / 3, *bridgman_triaxiality(3.0, [6.0, 2.0, 1.0, 0.5])]
    rows = [(t, r, T) for t in tris for r in (1e-3, 1.0, 1e3) for T in (20.0, 300.0, 600.0)]
    return [FracturePoint(t, r, T, float(true_locus(t, r, T, d) * (1 + noise * rng.standard_normal())), "synthetic")
            for t, r, T in rows]


def test_fit_recovers_the_steel45_locus_and_constants():
    pts = table()
    fit = fit_damage(pts, **REF)
    tri = np.linspace(min(p.triaxiality for p in pts), max(p.triaxiality for p in pts), 15)
    grid = np.array(np.meshgrid(tri, np.geomspace(1e-3, 1e3, 7), np.linspace(20, 600, 7))).reshape(3, -1)
    dev = fit(*grid) / true_locus(*grid) - 1.0
    assert np.max(np.abs(dev)) < 0.03  # the locus within 3 % over the table's range
    for name in ("D2", "D3", "D4", "D5"):  # within two reported standard errors (95 %)
        assert fit.stderr[name] is not None and fit.stderr[name] > 0
        assert abs(fit.params[name] - STEEL45[name]) < 2 * fit.stderr[name], (name, fit.params[name], fit.stderr[name])
    # steel 45's weak triaxiality effect (D3 = -0.17) makes exp(D3 s) nearly linear over the
    # table: D1 and D2 cannot be told apart, so D1 is fixed at table 3.2's 0, and said so
    assert fit.fixed == {"D1": 0.0} and fit.stderr["D1"] is None
    assert any("cannot be told apart" in w for w in fit.warnings)
    d = fit.as_dict()
    assert set(d) >= {"D1", "D2", "D3", "D4", "D5", "D1_stderr", "damage"}
    assert d["damage"]["triaxiality_range"] == pytest.approx([1 / 3, float(bridgman_triaxiality(3.0, 0.5))])
    assert "positive in tension" in d["damage"]["conventions"]["triaxiality"]
    assert set(d["damage"]["correlations"]) == {"D2", "D3", "D4", "D5"}  # between identified constants only
    assert d["damage"]["fixed"] == {"D1": 0.0}


def test_a_strong_triaxiality_effect_separates_d1_to_d3():
    d4340 = dict(D1=0.05, D2=3.44, D3=-2.12, D4=0.002, D5=0.61)  # Johnson and Cook (1985), 4340 steel
    fit = fit_damage(table(noise=0.01, d=d4340), **REF)
    assert fit.fixed == {}
    for name in ("D1", "D2", "D3"):  # three standard errors: 99.7 % (the errors are calibrated: z-spread ~1 over 30 seeds)
        assert abs(fit.params[name] - d4340[name]) < 3 * fit.stderr[name], (name, fit.params[name], fit.stderr[name])


def test_narrow_triaxiality_range_warns_that_d1_d3_trade_off():
    pts = [p for p in table() if p.triaxiality < 0.6]  # smooth bar and the mildest notch only
    fit = fit_damage(pts, **REF)
    assert fit.fixed == {"D1": 0.0}  # two triaxialities: D1 cannot be separated
    assert any("trade off" in w for w in fit.warnings)
    assert any("D1 fixed at 0" in w for w in fit.warnings)


def test_one_triaxiality_is_refused_and_one_rate_fixes_d4():
    smooth = [p for p in table() if p.triaxiality == 1 / 3]
    with pytest.raises(IdentificationError, match="triaxiality"):
        fit_damage(smooth, **REF)
    slow = [p for p in table() if p.strain_rate_per_s == 1e-3]
    fit = fit_damage(slow, **REF)
    assert fit.fixed["D4"] == 0.0 and fit.stderr["D4"] is None


def test_bar_formulas():
    # Bridgman: a notch as sharp as the section radius (a/2R = 1/2) gives 1/3 + ln 1.5
    assert float(bridgman_triaxiality(3.0, 3.0)) == pytest.approx(1 / 3 + math.log(1.5))
    assert float(fracture_strain_from_diameters(6.0, 3.0)) == pytest.approx(math.log(4.0))  # area ratio 4


def test_fracture_table_reader(tmp_path):
    path = tmp_path / "fracture.csv"
    path.write_text("# notched bars, lab B\ntriaxiality,strain_rate_per_s,temperature_C,fracture_strain\n"
                    "0.333,0.001,20,1.21\n\n0.9,0.001,20,1.05\n")
    pts = read_fracture_points(path)
    assert [(p.triaxiality, p.fracture_strain) for p in pts] == [(0.333, 1.21), (0.9, 1.05)]
    assert pts[1].source.endswith(":5")
    path.write_text("triaxiality,strain_rate_per_s,temperature_C,fracture_strain\n0.3,0.001,20,1.2\n0.9,fast,20,1.0\n")
    with pytest.raises(RecordError, match="line 3, column strain_rate_per_s"):
        read_fracture_points(path)
    path.write_text("triaxiality,rate,temperature_C,fracture_strain\n0.3,0.001,20,1.2\n")
    with pytest.raises(RecordError, match="missing column.*strain_rate_per_s"):
        read_fracture_points(path)


# -- through 'flowcurve fit' ------------------------------------------------------------------------------------
SERIES_REF = dict(ref_strain_rate_per_s=1.0, ref_temperature_C=24.85, melt_temperature_C=1519.85)  # the syn series


def write_fracture_table(path, ref=SERIES_REF, seed=5):
    rng = np.random.default_rng(seed)
    rows = ["# steel 45 constants (table 3.2), 2 % noise", "triaxiality,strain_rate_per_s,temperature_C,fracture_strain"]
    for t in (1 / 3, *bridgman_triaxiality(3.0, [2.0, 1.0, 0.5])):
        for r in (1.0, 1e2, 1e4):
            for T in (24.85, 300.0, 600.0):
                lr = max(math.log(r / ref["ref_strain_rate_per_s"]), 0.0)
                ts = (T - ref["ref_temperature_C"]) / (ref["melt_temperature_C"] - ref["ref_temperature_C"])
                e = (STEEL45["D2"] * math.exp(STEEL45["D3"] * t)) * (1 + STEEL45["D4"] * lr) * (1 + STEEL45["D5"] * ts)
                rows.append(f"{t:.6f},{r:g},{T:g},{e * (1 + 0.02 * rng.standard_normal()):.5f}")
    path.write_text("\n".join(rows) + "\n")
    return path


def test_fit_command_adds_d1_to_d5_from_a_fracture_table(tmp_path, syn, capsys):
    import json

    from flowcurve.cli import main

    root = tmp_path / "results"
    for m in syn.members():
        syn.write_result_folder(root / m.name, m)
    table_path = write_fracture_table(tmp_path / "fracture.csv")
    out = tmp_path / "fit"
    assert main(["fit", str(root), "--out", str(out), "--ref-rate", "1", "--ref-temp", "24.85", "--melt-temp", "1519.85",
                 "--fracture-points", str(table_path)]) == 0
    text = capsys.readouterr().out
    assert "fracture (2.22) over 36 points" in text
    d = json.loads((out / "fit.json").read_text())
    for k in ("D4", "D5"):
        assert abs(d[k] - STEEL45[k]) < 2 * d[f"{k}_stderr"], k
    assert d["damage"]["triaxiality_range"] == pytest.approx([1 / 3, float(bridgman_triaxiality(3.0, 0.5))])
    assert d["damage"]["points"] == 36 and "positive in tension" in d["damage"]["conventions"]["triaxiality"]
    assert any(w.startswith("fracture:") for w in d["warnings"])  # D1 fixed at 0, said so
    # and on into the three solvers' cards
    constants = ["--E", "205000", "--poisson", "0.29", "--density", "7850", "--cp", "477"]
    for fmt, needle in (("lsdyna", "*MAT_JOHNSON_COOK"), ("abaqus", "*DAMAGE INITIATION, CRITERION=JOHNSON COOK"),
                        ("radioss", "/FAIL/JOHNSON/1")):
        card = tmp_path / f"card.{fmt}"
        assert main(["card", str(out / "fit.json"), "-f", fmt, "-o", str(card), *constants]) == 0, capsys.readouterr().err
        text = card.read_text()
        assert needle in text and f"D5 = {d['D5']:.6g}" in text


def test_bad_fracture_table_is_a_one_line_error(tmp_path, syn, capsys):
    from flowcurve.cli import main

    root = tmp_path / "results"
    for m in syn.members():
        syn.write_result_folder(root / m.name, m)
    bad = tmp_path / "bad.csv"
    bad.write_text("triaxiality,strain_rate_per_s,temperature_C,fracture_strain\n0.33,1,20,-1\n")
    assert main(["fit", str(root), "--out", str(tmp_path / "fit"), "--melt-temp", "1519.85", "--fracture-points", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "bad.csv" in err and "line 2" in err and "fracture_strain" in err and "\n" not in err


def test_notched_result_folder_carries_its_bridgman_triaxiality(tmp_path, syn):
    import json

    from flowcurve.identification.series.series import member_from_result

    m = syn.members()[0]
    folder = syn.write_result_folder(tmp_path / "notched", m)
    result = json.loads((folder / "result.json").read_text())
    result["fracture_true_strain"] = 0.8
    result["record"]["specimen"]["notch_radius_mm"] = 1.5
    (folder / "result.json").write_text(json.dumps(result))
    member = member_from_result(folder)
    # d0 6 mm: a = 3 mm, R = 1.5 mm: 1/3 + ln 2
    assert member.fracture.triaxiality == pytest.approx(1 / 3 + math.log(2.0))
    assert member.fracture.fracture_strain == 0.8
    assert member.fracture.strain_rate_per_s == member.strain_rate_per_s


def test_record_with_a_section_after_fracture_and_a_notch_gives_its_fracture_point(syn):
    from flowcurve.identification.series.series import member_from_record

    record, _ = syn.tension_record(24.85, 0.03, 1e-3)
    assert member_from_record(record).fracture is None  # no section after fracture: no point, no guess
    record.meta.update({"post.dk_mm": "4.0", "specimen.notch_radius_mm": "2.0"})
    point = member_from_record(record).fracture
    assert point.fracture_strain == pytest.approx(2 * math.log(6.0 / 4.0), rel=1e-9)  # ln(A0/Af)
    assert point.triaxiality == pytest.approx(1 / 3 + math.log(1 + 3.0 / 4.0))  # a = 3 mm, R = 2 mm
    assert point.temperature_C == pytest.approx(24.85, abs=0.2)

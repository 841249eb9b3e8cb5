"""`flowcurve friction` end to end: table → friction.json, tests.csv, plots, cards; bad input is one line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from flowcurve.cli import main

from .synthetic import TRUTH

KEYS = ("tau0_MPa", "beta0", "k_b_per_C", "theta_k_C", "sigma_S_MPa", "mu_d")


def test_friction_refined_writes_json_plots_and_cards(make_table, tmp_path, capsys):
    table, device = make_table(contact="bowden_tabor", moment_noise_rel=0.002, radius_noise_um=0.2, hot=True, flow_stress_for_hot=True)
    out = tmp_path / "out"
    assert main(["friction", table.sources[0], "--method", "refined", "--mu-d", str(TRUTH.mu_d), "--out", str(out),
                 "--card", "abaqus", "--card", "lsdyna"]) == 0
    text = (out / "friction.json").read_text(encoding="utf-8")
    assert text.isascii()
    data = json.loads(text)
    for key in KEYS:
        assert isinstance(data[key], float), key
        assert f"{key}_stderr" in data
    assert data["sigma_S_MPa"] == pytest.approx(device.surface_flow_stress_MPa(20.0), rel=0.05)
    assert data["range"]["temperature_C"] == [20.0, 800.0]
    assert data["range"]["nominal_mean_pressure_MPa"][0] < data["range"]["nominal_mean_pressure_MPa"][1]
    assert data["mu_d_source"] == "given (--mu-d)"
    for name in data["plots"] + list(data["cards"].values()):
        assert (out / name).stat().st_size > 1000
    tests = pd.read_csv(out / "tests.csv")
    assert len(tests) == 33 and {"moment_N_m", "model_moment_N_m", "residual_pct"} <= set(tests.columns)
    assert "sigma_S" in capsys.readouterr().out


def test_foreign_csv_through_column_options(make_table, tmp_path):
    """The same tests written in kN, N*mm, um and K with other column names give the same constants."""
    table, _ = make_table(contact="full", moment_noise_rel=0.005, radius_noise_um=0.5)
    d = table.data
    foreign = pd.DataFrame({"Fz": d["normal_force_N"] / 1e3, "Mz": d["moment_N_m"] * 1e3,
                            "r": d["imprint_radius_mm"] * 1e3, "T": d["temperature_C"] + 273.15})
    path = tmp_path / "lab.csv"
    foreign.to_csv(path, index=False, float_format="%.12g")
    out_native, out_foreign = tmp_path / "n", tmp_path / "f"
    assert main(["friction", table.sources[0], "--mu-d", "0.02", "--out", str(out_native)]) == 0
    assert main(["friction", str(path), "--mu-d", "0.02", "--out", str(out_foreign), "--column", "normal_force=Fz:kN",
                 "--column", "moment=Mz:N*mm", "--column", "imprint_radius=r:um", "--column", "temperature=T:K"]) == 0
    a = json.loads((out_native / "friction.json").read_text())
    b = json.loads((out_foreign / "friction.json").read_text())
    for key in ("tau0_MPa", "beta0"):
        assert b[key] == pytest.approx(a[key], rel=1e-8)


@pytest.mark.parametrize("row, words", [
    ("X,800,0.07,0,20", "line 4, column 'imprint_radius_mm': imprint radius r must be > 0"),
    ("X,800,-0.07,0.45,20", "line 4, column 'moment_N_m': moment M_z must be >= 0"),
    ("X,800,0.07,0.45,", "line 4, column 'temperature_C': missing temperature"),
])
def test_bad_rows_exit_2_with_one_line(tmp_path, capsys, row, words):
    path = tmp_path / "bad.csv"
    path.write_text("# flowcurve-adhesion: 1\ntest_id,normal_force_N,moment_N_m,imprint_radius_mm,temperature_C\n"
                    "A,500,0.05,0.4,20\n" + row + "\n", encoding="utf-8")
    assert main(["friction", str(path), "--mu-d", "0.02", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert err.startswith(f"flowcurve: error: {path}, {words}")


def test_without_mu_d_or_microrelief_the_error_says_what_to_give(make_table, tmp_path, capsys):
    table, _ = make_table(contact="full", moment_noise_rel=0.005, radius_noise_um=0.5)
    assert main(["friction", table.sources[0], "--out", str(tmp_path / "o")]) == 2
    assert "give it (--mu-d VALUE)" in capsys.readouterr().err


def test_mu_d_from_the_microrelief(make_table, tmp_path):
    """R_p, t_m from the table header and --asperity-radius: μ_d by Kragelsky's formula, named in the result."""
    table, _ = make_table(contact="full", moment_noise_rel=0.005, radius_noise_um=0.5)
    out = tmp_path / "o"
    assert main(["friction", table.sources[0], "--asperity-radius", "50", "--out", str(out)]) == 0
    data = json.loads((out / "friction.json").read_text())
    # K_r = 1 > t_m = 0.5: the bearing curve is full, h = R_p (1/t_m)^(1/2); μ_d = 0.55 √(h/r_a)
    assert data["mu_d"] == pytest.approx(0.55 * np.sqrt(0.2 * np.sqrt(2.0) / 50.0))
    assert "Kragelsky" in data["mu_d_source"]


def test_friction_demo_runs(tmp_path, capsys):
    assert main(["friction-demo", "--out", str(tmp_path / "demo"), "--card", "abaqus"]) == 0
    out = capsys.readouterr().out
    assert "virtual adhesiometer: 24 tests" in out and "tau0 =" in out
    assert (tmp_path / "demo" / "friction_abaqus.inp").exists()
    assert len(list((tmp_path / "demo" / "traces").glob("*.csv"))) == 24
    # mu_d was not given: the demo's default says so, on screen, in friction.json and in the card
    data = json.loads((tmp_path / "demo" / "friction.json").read_text())
    assert data["mu_d_source"].startswith("default") and "given (--mu-d)" not in out
    assert "mu_d = 0.02 (default" in out
    assert "default: the virtual" in (tmp_path / "demo" / "friction_abaqus.inp").read_text()


def test_friction_demo_refined_flags_the_undetermined_sigma_S(tmp_path, capsys):
    """The demo's tests have full contact: σ_S = 0.63 ± 3.6 MPa came out with no word; now flagged on screen, in
    friction.json, and kept out of the LS-DYNA card's friction stress limit."""
    out_dir = tmp_path / "demo"
    assert main(["friction-demo", "--method", "refined", "--out", str(out_dir), "--card", "lsdyna"]) == 0
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if "sigma_S =" in x)
    assert "UNDETERMINED" in line
    data = json.loads((out_dir / "friction.json").read_text())
    assert abs(data["sigma_S_MPa"]) < data["sigma_S_MPa_stderr"] and data["undetermined"] == ["sigma_S_MPa"]
    assert "VC = 0 (sigma_S not identified" in (out_dir / "friction_lsdyna.k").read_text()


def test_friction_without_out_writes_to_the_default_folder(make_table, tmp_path, monkeypatch):
    """Like fit and friction-demo, friction needs no --out: it writes ./friction (it used to refuse)."""
    table, _ = make_table(contact="full", moment_noise_rel=0.002, radius_noise_um=0.2)
    monkeypatch.chdir(tmp_path)
    assert main(["friction", table.sources[0], "--mu-d", str(TRUTH.mu_d)]) == 0
    assert (tmp_path / "friction" / "friction.json").is_file()

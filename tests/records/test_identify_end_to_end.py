"""The identify command end to end on a real 42CrMoS4 INSTRON export: the lab's own numbers."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from flowcurve.cli import main
from identification.importers import load_record


def test_identify_instron_file_matches_published_values(tmp_path, instron_file, capsys):
    code = main(["identify", str(instron_file), "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    assert code == 0, err
    folder = tmp_path / instron_file.stem
    result = json.loads((folder / "result.json").read_text())
    published = load_record(instron_file).meta
    assert result["test"] == "tension"
    # the lab's Rm from the same raw force channel (independent processing, their software)
    assert result["Rm_MPa"] == pytest.approx(float(published["published.Rm_MPa"]), rel=0.005)
    rec = result["record"]
    assert rec["material"] == "42CrMoS4" and rec["nominal_temperature_C"] == 23.0
    assert rec["strain_rate_per_s"] == pytest.approx(float(published["crosshead_speed_mm_per_s"]) / 25.0)
    curve = pd.read_csv(folder / "true_curve.csv")
    assert list(curve.columns)[:2] == ["true_plastic_strain", "true_stress_MPa"] and len(curve) > 10
    assert any(p.suffix == ".png" for p in folder.iterdir())
    assert "Rm" in out and "hardening" in out

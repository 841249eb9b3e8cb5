"""The identify command end to end on a real 42CrMoS4 INSTRON export: the lab's own numbers."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from flowcurve.cli import main
from flowcurve.record.importers import load_record


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


def _frictionless_compression(tmp_path):
    """A compression record from the seed's law (3.34) with no friction: no barrel, dmax = d_n(hk)."""
    import numpy as np

    from flowcurve.record.format import Record, write_record

    A, B, n, E = 105.0, 1392.0, 0.642, 194e3
    d0, h0 = 5.989, 6.982
    eps_p = np.concatenate([np.zeros(200), np.linspace(0.0, 0.6, 1800)])
    sig = A + B * eps_p**n
    sig[:200] = A * np.linspace(0.0, 1.0, 200, endpoint=False)  # elastic loading
    h = h0 * np.exp(-(eps_p + sig / E))
    force = sig * np.pi * (d0**2 * h0 / h) / 4.0  # uniform section by volume constancy, no friction
    crosshead = (h0 - h) + force / 136e3  # plus the frame's 136 N/µm
    hk = float(h0 * np.exp(-0.6))
    meta = {"flowcurve-record": "1", "status": "complete", "test": "compression", "material": "12Kh18N12M3TL",
            "specimen.d0_mm": repr(d0), "specimen.h0_mm": repr(h0), "crosshead_speed_mm_per_s": "0.01",
            "rig.frame_stiffness_N_per_um": "136", "post.hk_mm": repr(hk), "post.dmax_mm": repr(float(d0 * np.sqrt(h0 / hk)))}
    data = pd.DataFrame({"time_s": np.arange(2000) * 0.1, "force_N": force, "crosshead_mm": crosshead})
    return write_record(tmp_path / "C1.csv", Record(meta=meta, data=data, source="C1")), (A, B, n)


def test_identify_frictionless_compression_recovers_the_law(tmp_path, capsys):
    path, (A, B, n) = _frictionless_compression(tmp_path)
    code = main(["identify", str(path), "--out", str(tmp_path / "out")])
    out, err = capsys.readouterr()
    assert code == 0, err
    folder = tmp_path / "out" / "C1"
    result = json.loads((folder / "result.json").read_text())
    assert result["test"] == "compression"
    # no barrel → μ = 0 by both friction methods (closed form: ΔR = 0)
    assert result["friction_mu"] == pytest.approx(0.0, abs=0.01)
    assert all(abs(v) < 0.01 for v in result["friction"].values())
    # with μ = 0 the true curve is the law itself, point by point
    curve = pd.read_csv(folder / "true_curve.csv")
    plastic = curve[curve["true_plastic_strain"] > 0.01]
    law = A + B * plastic["true_plastic_strain"] ** n
    assert (plastic["true_stress_MPa"] / law - 1).abs().max() < 0.03
    h = result["hardening"]
    assert (h["A_MPa"], h["B_MPa"], h["n"]) == (pytest.approx(A, rel=0.05), pytest.approx(B, rel=0.05), pytest.approx(n, rel=0.05))
    assert (folder / "corrections.png").exists() and "friction μ" in out


def test_record_cut_short_is_identified_with_a_warning(tmp_path, instron_file, capsys):
    from flowcurve.record.format import write_record

    rec = load_record(instron_file)
    rec.meta = {"flowcurve-record": "1", **rec.meta, "status": "recording"}  # as after a power cut
    path = write_record(tmp_path / "cut.csv", rec)
    text = path.read_text()
    path.write_text(text + "160.1,0.2")  # and a half-written last line
    code = main(["identify", str(path), "--out", str(tmp_path / "out"), "--no-plots"])
    out, err = capsys.readouterr()
    assert code == 0, err
    result = json.loads((tmp_path / "out" / "cut" / "result.json").read_text())
    assert any("cut short" in w for w in result["warnings"]) and "warning:" in out
    assert result["record"]["truncated"] is True
    assert result["Rm_MPa"] == pytest.approx(float(rec.meta["published.Rm_MPa"]), rel=0.005)

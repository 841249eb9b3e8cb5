"""`flowcurve verify` reports the force deviation before the band where the model's force error
grows (FOLD_OVER_BAND of strain before its side folds onto the platen) apart from the whole
stroke's (identification/fe/verify.py): a model force that is the record's own up to that band and
5 % off beyond it reads 5 % over the stroke and 0 before it. The check runs a finer discretisation
than the fit's and the fit's beside it; their gap is reported as the check's own model error."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.identification.fe import verify
from flowcurve.identification.fe.model.model_form import FOLD_OVER_BAND

RECORD = Path(__file__).parent / "data" / "other_settings_C1.csv"
CARD = "*MATERIAL,NAME=M\n*ELASTIC\n194000.,0.3\n*PLASTIC\n105.,0.\n500.,0.1\n900.,0.5\n1200.,2.\n"


def _fake_runs(stroke, force, factors, fold_over):
    """A stand-in for the solver: the k-th run's force is the record's loading branch × factors[k]."""
    calls = []

    def fake(model_with, timeout_s):
        k = np.argmax(stroke)
        f = factors[len(calls)]
        calls.append(f)
        return SimpleNamespace(stroke_mm=stroke[1:k + 1], force_N=(force * f)[1:k + 1], dmax_mm=np.array([8.66]), wall_s=0.0,
                               cached=True, fold_over_strain=fold_over), {}
    return fake


@pytest.mark.parametrize("fold_over", [0.5, None], ids=["folds", "does not fold"])
def test_the_deviation_before_the_fold_over_is_reported_apart(tmp_path, monkeypatch, fold_over):
    from flowcurve.record.format import read_record

    stroke, force, _ = verify.record_force_stroke(read_record(RECORD))
    h0 = 9.0
    strain = -np.log(1.0 - stroke / h0)
    bump = 1.0 + 0.05 * (strain >= (fold_over - FOLD_OVER_BAND if fold_over is not None else 0.6))  # the model 5 % above from there

    monkeypatch.setattr(verify, "_simulate_with_retries", _fake_runs(stroke, force, [bump, bump], fold_over))
    card = tmp_path / "card.inp"
    card.write_text(CARD)
    assert main(["verify", str(card), str(RECORD), "--mu", "0.15", "--out", str(tmp_path / "v"), "--no-plots"]) == 0
    report = json.loads((tmp_path / "v" / "verify.json").read_text())
    assert report["max_force_deviation_pct"] == pytest.approx(100.0 * (1.0 / 1.05 - 1.0) * -1.0, rel=0.02)
    assert report["fold_over_strain"] == fold_over
    before = report["max_force_deviation_before_fold_over_pct"]
    assert before < 0.01 if fold_over is not None else before == pytest.approx(report["max_force_deviation_pct"])


@pytest.mark.parametrize("options, runs", [([], 2), (["--layers", "2", "--increments", "50"], 1)], ids=["finer check", "the fit's model"])
def test_the_check_runs_a_finer_model_and_reports_the_fits_gap(tmp_path, monkeypatch, options, runs):
    from flowcurve.record.format import read_record

    stroke, force, _ = verify.record_force_stroke(read_record(RECORD))
    monkeypatch.setattr(verify, "_simulate_with_retries", _fake_runs(stroke, force, [1.0, 1.03], 0.5))
    card = tmp_path / "card.inp"
    card.write_text(CARD)
    assert main(["verify", str(card), str(RECORD), "--mu", "0.15", "--out", str(tmp_path / "v"), "--no-plots", *options]) == 0
    report = json.loads((tmp_path / "v" / "verify.json").read_text())
    assert report["max_force_deviation_pct"] < 0.01  # the first run is the check: the record's own force
    if runs == 1:
        assert report["discretisation"] is None and report["model"] == {"layers": 2, "increments": 50}
    else:
        assert report["model"] == {"layers": verify.VERIFY_LAYERS, "increments": verify.VERIFY_INCREMENTS}
        disc = report["discretisation"]
        assert (disc["layers"], disc["increments"]) == (2, 50)
        assert disc["max_force_gap_pct"] == pytest.approx(3.0, rel=1e-6)
        assert disc["max_force_deviation_pct"] == pytest.approx(100.0 * (1.0 - 1.0 / 1.03), rel=1e-3)

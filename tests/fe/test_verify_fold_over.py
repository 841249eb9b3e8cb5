"""`flowcurve verify` reports the force deviation before the band where the model's force error
grows (FOLD_OVER_BAND of strain before its side folds onto the platen) apart from the whole
stroke's (identification/fe/verify.py): a model force that is the record's own up to that band and
5 % off beyond it reads 5 % over the stroke and 0 before it."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.identification.fe import verify
from flowcurve.identification.fe.inverse import FOLD_OVER_BAND

RECORD = Path(__file__).parent / "data" / "other_settings_C1.csv"
CARD = "*MATERIAL,NAME=M\n*ELASTIC\n194000.,0.3\n*PLASTIC\n105.,0.\n500.,0.1\n900.,0.5\n1200.,2.\n"


@pytest.mark.parametrize("fold_over", [0.5, None], ids=["folds", "does not fold"])
def test_the_deviation_before_the_fold_over_is_reported_apart(tmp_path, monkeypatch, fold_over):
    from flowcurve.record.format import read_record

    stroke, force, _ = verify.record_force_stroke(read_record(RECORD))
    h0 = 9.0
    strain = -np.log(1.0 - stroke / h0)
    bump = 1.0 + 0.05 * (strain >= (fold_over - FOLD_OVER_BAND if fold_over is not None else 0.6))  # the model 5 % above from there

    def fake(model_with, timeout_s):  # the record's own loading branch as the model's force
        k = np.argmax(stroke)
        run = SimpleNamespace(stroke_mm=stroke[1:k + 1], force_N=(force * bump)[1:k + 1], dmax_mm=np.array([8.66]), wall_s=0.0,
                              cached=True, fold_over_strain=fold_over)
        return run, {}

    monkeypatch.setattr(verify, "_simulate_with_retries", fake)
    card = tmp_path / "card.inp"
    card.write_text(CARD)
    assert main(["verify", str(card), str(RECORD), "--mu", "0.15", "--out", str(tmp_path / "v"), "--no-plots"]) == 0
    report = json.loads((tmp_path / "v" / "verify.json").read_text())
    assert report["max_force_deviation_pct"] == pytest.approx(100.0 * (1.0 / 1.05 - 1.0) * -1.0, rel=0.02)
    assert report["fold_over_strain"] == fold_over
    before = report["max_force_deviation_before_fold_over_pct"]
    assert before < 0.01 if fold_over is not None else before == pytest.approx(report["max_force_deviation_pct"])

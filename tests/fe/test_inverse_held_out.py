"""The compression inverse on records it has never seen (issue 37), each from an empty solver cache:

* records of the issue's own kind (tests/fe/other_settings.py: the product's kind of model with stick
  slope 1e5, 4 boundary-layer elements, 200 increments; the rig's compliance, toe, noise, counts):
  μ within ± 0.01, the curve within 1 % over ε_p 0.05–0.6, `flowcurve verify` within 2 % over the
  whole stroke (its check runs a finer discretisation than the fit's; the fit's own model reads up
  to 2.9 % there, 1.7–1.9 % of it its discretisation where the side folds over);
* the stricter second model's records (tests/fe/second_model.py: CAX8R graded mesh, node-to-surface
  contact): μ within ± 0.01 on C2 and ± 0.02 on C3, whose end face and force the two models place
  differently (model form, docs/methods.md §4a.7), the same curve bound; verify within 2 % on C2
  and, on C3, 2.5 % (the two discretisations' own gap there is 2 %, and this model's 10-element mesh
  folds over later than either: at the true law and μ the check reads 3.1 %, the fit's model 3.3 %);
* on all, the truth within 2 of the reported standard errors, the model's E the record's handbook
  one (never the apparent slope) and the frame's stiffness the header's.

The time limit is lifted so that the answer does not depend on the machine's load
(bench/inverse_held_out.py measures the times: 114–148 s each on a quiet 2-core machine)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flowcurve.cli import main

from .second_model import HELD_OUT, curve_error

pytestmark = [pytest.mark.slow, pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]
DATA = Path(__file__).parent / "data"
CASES = {c.name: c for c in HELD_OUT}
# what holds for μ: ± 0.01 on the kind; on the second model's C3 (μ 0.2, h0/d0 1) 0.185 ± 0.017 — its end face and
# force read μ low against the product's model (model-form error, docs/methods.md §4a.7), within its standard error
# verify's largest force deviation over the stroke (its check's own discretisation gap is reported beside it)
VERIFY_HOLDS = {("second_model", "C3"): 2.5}
MU_HOLDS = {("other_settings", "C1"): 0.01, ("other_settings", "C2"): 0.01, ("other_settings", "C3"): 0.01,
            ("second_model", "C2"): 0.01, ("second_model", "C3"): 0.02}


@pytest.mark.parametrize("family, name", list(MU_HOLDS), ids=[f"{f}-{n}" for f, n in MU_HOLDS])
def test_inverse_reads_records_it_has_never_seen(tmp_path, monkeypatch, family, name):
    case = CASES[name]
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path / "cache"))
    record = DATA / f"{family}_{name}.csv"
    out = tmp_path / "out"
    assert main(["identify", str(record), "--method", "inverse-fe", "--workers", "2", "--no-plots", "--out", str(out), "--time-limit", "3600"]) == 0
    folder = out / record.stem
    result = json.loads((folder / "result.json").read_text())
    inverse = result["inverse_fe"]
    assert inverse["model"]["E_MPa"] == case.E_MPa and inverse["model"]["E_source"] == "handbook"
    assert inverse["model"]["frame_compliance_source"].startswith("record header") and not inverse["budget"]["cut"]
    assert curve_error(pd.read_csv(folder / "true_curve.csv", comment="#"), case) < 0.01
    assert main(["verify", str(folder), str(record), "--out", str(tmp_path / "v"), "--no-plots"]) == 0
    verified = json.loads((tmp_path / "v" / "verify.json").read_text())
    assert verified["max_force_deviation_pct"] < VERIFY_HOLDS.get((family, name), 2.0)
    assert verified["model"] == {"layers": 4, "increments": 200} and verified["discretisation"]["max_force_gap_pct"] < 2.5
    assert result["friction_mu"] == pytest.approx(case.mu, abs=MU_HOLDS[family, name])
    assert np.isfinite(inverse["mu_stderr"]) and abs(result["friction_mu"] - case.mu) <= 2.0 * inverse["mu_stderr"]

"""Records from a second upsetting model (tests/fe/second_model.py: its own deck, CAX8R graded
mesh, node-to-surface contact, stick slope 1e5, 200 increments) read by the product's default
identification (`flowcurve identify`, fe_table): μ within ±0.02 and the flow curve within 2 %
over ε_p 0.05–0.6 (issue 37). The fast tests read the vendored records (tests/fe/data); the slow
one regenerates them with CalculiX and checks they are the vendored ones.

Measured (this model, CAX8R 10 radial): C2 (μ 0.05, h0/d0 1.5) reads μ 0.046, curve 0.34 % from
the bulge; μ 0.042 from the end face. C3 (μ 0.2, h0/d0 1.0) reads μ 0.2025 but the curve 2.30 %
off (flagged: Swift ε0 beyond the table), and from the end face μ 0.176 with a range 0.170–0.183
that excluded the truth while the range counted only the product's mesh (± 0.005 d/d_n): this
model's rim node sits 0.1–0.2 mm wider than the product's table expects at μ 0.2 (and moves
0.09 mm between 8 and 12 radial elements). With the model form's share (± 0.02 of d/d_n,
identification/fe/model/model_form.py) the range is 0.152–0.204; the coverage test below counts it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest


from .second_model import C3, HELD_OUT, assert_regenerated, coverage_row, identify_default, simulate, write_record

DATA = Path(__file__).parent / "data"
CASES = {c.name: c for c in HELD_OUT}
C3_CURVE = "C3 from the bulge: μ 0.2025 but the curve +2.30 % off at ε_p 0.44 (flagged 'Swift ε0 beyond the table')"
C3_FACE = ("C3 from the end face: μ 0.176 (the curve 1.94 % off) — the second model's rim node sits 0.017 of d/d_n wider than the "
           "product's: its range 0.152–0.204 now counts that model form (± 0.02, fe/model/model_form.py) and holds the truth 0.2")


@pytest.mark.parametrize("name", ["C2", pytest.param("C3", marks=pytest.mark.xfail(strict=True, reason=C3_CURVE))])
def test_default_reads_second_model_records_from_the_bulge(tmp_path, name):
    result, err = identify_default(DATA / f"second_model_{name}.csv", tmp_path, end_face=False)
    assert result["friction_method"] == "fe_table"
    assert result["friction_mu"] == pytest.approx(CASES[name].mu, abs=0.02)
    assert err < 0.02, err


def test_default_mu_from_the_bulge_of_c3(tmp_path):
    """C3's μ is read within ±0.02 even though its curve misses 2 % (above): the miss is flagged."""
    result, err = identify_default(DATA / "second_model_C3.csv", tmp_path, end_face=False)
    assert result["friction_mu"] == pytest.approx(C3.mu, abs=0.02)
    assert err < 0.02 or any(w.startswith("FE table:") for w in result["warnings"])


@pytest.mark.parametrize("name", ["C2", pytest.param("C3", marks=pytest.mark.xfail(strict=True, reason=C3_FACE))])
def test_default_reads_second_model_records_from_the_end_face(tmp_path, name):
    result, err = identify_default(DATA / f"second_model_{name}.csv", tmp_path, end_face=True)
    assert result["friction_details"]["fe_table"]["mu_basis"] == "original end face (dface)"
    assert result["friction_mu"] == pytest.approx(CASES[name].mu, abs=0.02)
    assert err < 0.02, err


@pytest.mark.parametrize("end_face", [False, True], ids=["bulge", "end face"])
def test_the_truth_is_within_the_reported_standard_errors_on_the_held_out_records(tmp_path, end_face):
    """Coverage on the vendored second-model records (h0/d0 1.0–2.0, μ 0.05–0.3): the default's μ
    within 2 of its reported standard errors (fe_table's mu_stderr, with the model form's share)
    of the truth on all but one, within 3 on all — from the bulge and from the end face."""
    rows = [coverage_row(DATA / f"second_model_{name}.csv", tmp_path / name, end_face=end_face) for name in CASES]
    z = {r["record"]: round(r["z"], 2) for r in rows}
    assert len(rows) >= 6 and {r["h0_d0"] for r in rows} >= {1.0, 2.0} and {r["truth_mu"] for r in rows} >= {0.05, 0.3}
    assert sum(v <= 2.0 for v in z.values()) >= len(z) - 1 and all(v <= 3.0 for v in z.values()), z


@pytest.mark.slow
@pytest.mark.solver
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
@pytest.mark.parametrize("name", list(CASES))
def test_second_model_regenerates_the_vendored_records(tmp_path, name):
    """CalculiX makes the vendored record again (post-test shape to 0.1 µm, forces to 0.5 N); 15–120 s each."""
    made = write_record(simulate(CASES[name]), tmp_path / f"{name}.csv")
    assert_regenerated(made, DATA / f"second_model_{name}.csv")
    if name in ("C2", "C3"):
        result, _ = identify_default(made, tmp_path / "id", end_face=False)
        assert result["friction_mu"] == pytest.approx(CASES[name].mu, abs=0.02)

"""The fold-over's onset the inverse fits the force up to (`UpsettingResult.fold_over_strain`):
without friction the compression is homogeneous, so the first side node's gap to the platen
shrinks as h/h0 (closed form; within 0.04 on the model's mesh) and the side never folds; with μ 0.15 on the C1 specimen (d0 6,
h0 9 → 4.5) it folds before the end (measured at ε 0.60 of 0.69), with μ 0.3 sooner."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

pytestmark = [pytest.mark.slow, pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]


def _run(mu: float):
    law = lambda e: 105.0 + 1392.0 * np.asarray(e) ** 0.642  # noqa: E731  C1's Johnson–Cook
    return simulate_upsetting(UpsettingModel.from_law(6.0, 9.0, 4.5, mu, law, E_MPa=194_000.0), require_complete=False)


def test_without_friction_the_side_does_not_fold(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path))
    run = _run(0.0)
    # within 0.04 (measured 0.038 at the end: the node sits 14 µm low of homogeneous, the rim held by the contact)
    np.testing.assert_allclose(run.side_gap, run.height_mm / run.model.h0_mm, atol=0.04)
    assert run.fold_over_strain is None


def test_with_friction_the_side_folds_before_the_end_and_sooner_with_more(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOWCURVE_FE_CACHE", str(tmp_path))
    mid, high = _run(0.15), _run(0.3)
    assert 0.45 < mid.fold_over_strain < mid.strain[-1]
    assert high.fold_over_strain < mid.fold_over_strain

"""How the FE table continues a run that stopped where the side folds onto the platen, checked on
the runs that did not stop: the package table's complete runs are cut at ε 0.3, 0.4 and 0.5, continued
with each rule, and compared with what CalculiX computed at ε 0.7. The rule the table uses for each
array must read its runs back without a bias and better than holding the difference to the run one
μ step lower (the first rule, which read the bulge low and the end face high)."""

from __future__ import annotations

import numpy as np
import pytest

from flowcurve.identification.fe.model import table as table_module
from flowcurve.identification.fe.model.table import continue_stopped_runs

CUTS = (0.3, 0.4, 0.5)


@pytest.fixture(scope="module")
def raw_table():
    """The package table as read, less the continuation (its stopped runs keep their NaN tails)."""
    keep = table_module.continue_stopped_runs
    table_module.continue_stopped_runs = lambda values, rule="difference": values.copy()
    try:
        return table_module._load.__wrapped__(str(table_module.PACKAGE_TABLE))  # past the cache: the table others read stays continued
    finally:
        table_module.continue_stopped_runs = keep


def _continued_errors(values, strain, rule, at=0.7):
    """(continued − computed) at ε ``at`` of every complete run whose two lower-μ runs are complete, cut at each of CUTS."""
    j = int(np.searchsorted(strain, at - 1e-9))
    errors = []
    for k in range(2, values.shape[0]):
        for idx in np.ndindex(values.shape[1:-1]):
            trio = values[k - 2:k + 1, idx[0], idx[1], idx[2]]
            if np.isnan(trio).any():
                continue
            for cut in CUTS:
                stopped = trio.copy()
                stopped[2, int(np.searchsorted(strain, cut)):] = np.nan
                filled = continue_stopped_runs(stopped[:, None, None, None], rule)  # row 0 (μ_k−2) anchors as μ = 0 does
                errors.append(filled[2, 0, 0, 0, j] - trio[2, j])
    return np.array(errors)


def test_the_bulge_is_continued_without_a_bias(raw_table):
    t = raw_table
    used = _continued_errors(t.bulge, t.strain, "mean")
    held = _continued_errors(t.bulge, t.strain, "difference")
    assert used.size > 300
    assert abs(used.mean()) < 0.001 and np.abs(used).max() < 0.007  # ΔR/h
    assert held.mean() < -0.0015  # holding the difference reads the bulge low
    assert np.sqrt(np.mean(used**2)) < np.sqrt(np.mean(held**2))


def test_the_end_face_is_continued_along_the_mu_steps(raw_table):
    t = raw_table
    used = _continued_errors(t.face, t.strain, "mu_scaled")
    held = _continued_errors(t.face, t.strain, "difference")
    assert abs(used.mean()) < 0.006 and np.sqrt(np.mean(used**2)) < 0.015  # d/d_n
    assert held.mean() > 0.015  # holding the difference reads the face high (μ low)
    assert np.sqrt(np.mean(used**2)) < 0.5 * np.sqrt(np.mean(held**2))


def test_the_rules_in_closed_form():
    """Three μ rows; the top one stopped after ε index 2."""
    mu0 = np.array([0.0, 0.01, 0.02, 0.03, 0.04])
    mu1 = np.array([0.0, 0.02, 0.04, 0.07, 0.10])
    mu2 = np.array([0.0, 0.03, 0.08, np.nan, np.nan])
    v = np.stack([mu0, mu1, mu2]).reshape(3, 1, 1, 1, 5)
    diff = continue_stopped_runs(v, "difference")[2, 0, 0, 0]
    np.testing.assert_allclose(diff[3:], [0.08 + 0.03, 0.08 + 0.03 + 0.03])
    ratio3 = 0.08 * 0.07 / 0.04
    mean3 = 0.5 * (0.11 + ratio3)
    mean4 = 0.5 * (mean3 + 0.03 + mean3 * 0.10 / 0.07)
    np.testing.assert_allclose(continue_stopped_runs(v, "mean")[2, 0, 0, 0, 3:], [mean3, mean4])
    # mu_scaled: (v2 − v1) = c·(v1 − v0), c from ε index 2: (0.08 − 0.04)/(0.04 − 0.02) = 2
    np.testing.assert_allclose(continue_stopped_runs(v, "mu_scaled")[2, 0, 0, 0, 3:], [0.07 + 2 * 0.04, 0.10 + 2 * 0.06])
    with pytest.raises(ValueError, match="unknown continuation rule"):
        continue_stopped_runs(v, "spline")

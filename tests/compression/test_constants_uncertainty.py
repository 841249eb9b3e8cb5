"""The hardening constants' stated standard errors cover the truth on closed-form records.

The records (tests/compression/toe_records.py) are made from a known Johnson–Cook law with the slab
Coulomb pressure integrated over the face and the seed's bulge (3.18); the default identification
reads μ and corrects the curve with the CalculiX table, a different model of the same friction. Its
curve is within a few % of the law, but the shape of that difference (it grows towards the end of
the stroke) used to go into A and n, which trade off: A read 121–134 for 105 with a stated standard
error of 4–6 MPa (4.6–4.8 standard errors off). The constants' standard errors now include the
model form's force error as a shape (growing with strain) and the fit range's (docs/methods.md §4.8).

The non-default friction methods (bulge_regression, ebrahimi_najafizadeh) with the slab correction: their
μ had no standard error, so μ's share was empty and linear hardening at μ 0.11 read B 251.5 ± 0.09 for
250 (17 standard errors). μ's standard error now holds the readings' resolution through the method's
formula and its model form against the CalculiX table (bench/friction_model_form.py).
"""

import itertools
import math
import runpy
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from flowcurve.identification.compression import friction as fr
from flowcurve.identification.compression.identify import identify_compression

from .toe_records import make_toe_compression

STEEP = {"A": 105.0, "B": 1392.0, "n": 0.642}  # 12Kh18N12M3TL (seed)
STEEL45 = {"A": 410.0, "B": 280.0, "n": 0.47}  # steel 45, table 3.2
LINEAR = {"A": 300.0, "B": 250.0, "n": 1.0}  # linear hardening
MUS = (0.05, 0.11, 0.2)
SHAPES = ((8.0, 6.0), (6.0, 9.0))  # (d0, h0): h0/d0 0.75 and 1.5
WITHIN = 2.5  # standard errors


def _hardening(law, mu, d0, h0, **options):
    record, _ = make_toe_compression(law=law, mu=mu, d0=d0, h0=h0, rate_hz=2.0, toe_mm=0.05, speed=0.005, handbook_E=True, noise_N=5.0)
    return identify_compression(record, **options).result


def _z(h, law, key, name):
    return (h[key] - law[name]) / h[f"{key}_stderr"]


# the slab-made record's (3.18) barrel at μ 0.05 reads μ 0.033 ± 0.005 on the CalculiX table (3.4 standard errors; bulge_regression
# reads 0.050): B 291.6 for 280, and μ's share holds 10 of the 11.6 MPa. It held at 2.4998 se only on the strain zero's sample
# spacing term, δε0's 1e-4 of an actual ε0 error of 2e-5 (docs/methods.md §2.11): with δε0 the estimator's own, B is 2.502 se
SLAB_BARREL_MISREAD = {"steel45-mu0.05-h0d0_0.75": "slab barrel at μ 0.05 read 0.033 ± 0.005 by the CalculiX table: B 2.502 se"}
CASES = [pytest.param(law, mu, d0, h0, id=(case := f"{name}-mu{mu}-h0d0_{h0 / d0:.2f}"),
                      marks=[pytest.mark.xfail(strict=True, reason=SLAB_BARREL_MISREAD[case])] if case in SLAB_BARREL_MISREAD else [])
         for (name, law), mu, (d0, h0) in itertools.product((("seed", STEEP), ("steel45", STEEL45)), MUS, SHAPES)]


@pytest.mark.parametrize("law,mu,d0,h0", CASES)
def test_the_truth_is_within_the_stated_standard_errors(law, mu, d0, h0):
    result = _hardening(law, mu, d0, h0)
    h = result["hardening"]
    z = {name: _z(h, law, key, name) for name, key in (("A", "A_MPa"), ("B", "B_MPa"), ("n", "n"))}
    assert all(abs(v) <= WITHIN for v in z.values()), (z, h, result["methods"]["hardening_stderr"])
    assert "fit range" in result["methods"]["hardening_stderr"]


@pytest.mark.parametrize("mu", MUS)
def test_a_linear_hardening_law_keeps_its_A_within_the_stated_standard_error(mu):
    """n = 1: A is covered; B and n are not everywhere (the FE table's curve departs from the slab
    record by up to 8 % at μ 0.2, more than the model form it states; see the xfail below)."""
    h = _hardening(LINEAR, mu, 6.0, 9.0)["hardening"]
    assert abs(_z(h, LINEAR, "A_MPa", "A")) <= WITHIN, h


@pytest.mark.xfail(strict=True, reason="linear hardening, h0/d0 1.5, μ 0.11: n 1.22 ± 0.04 for 1.00 (5.5 se): the FE table's curve departs "
                                       "from the slab record's by more than the force model form it states")
def test_a_linear_hardening_law_keeps_n_within_the_stated_standard_error():
    h = _hardening(LINEAR, 0.11, 6.0, 9.0)["hardening"]
    assert abs(_z(h, LINEAR, "n", "n")) <= WITHIN, h


def test_a_and_n_trade_off_is_reported():
    result = _hardening(STEEP, 0.11, 5.989, 6.982)
    h = result["hardening"]
    assert h["correlations"]["A"]["n"] > 0.9
    assert "A and n trade off" in result["methods"]["hardening_stderr"]


BARREL_METHODS = ("bulge_regression", "ebrahimi_najafizadeh")
BARREL_CASES = [pytest.param(method, law, mu, id=f"{method}-{name}-mu{mu}")
                for method, (name, law), mu in itertools.product(BARREL_METHODS, (("seed", STEEP), ("steel45", STEEL45), ("linear", LINEAR)), MUS)]


@pytest.mark.parametrize("method,law,mu", BARREL_CASES)
def test_the_barrel_methods_constants_cover_the_truth(method, law, mu):
    """The record's own model path (slab correction, the slab record): B read 251.5 ± 0.09 for 250 at
    μ 0.11 (bulge_regression), 255.3 ± 0.83 (ebrahimi_najafizadeh) before μ had a standard error."""
    result = _hardening(law, mu, 5.989, 6.982, friction_method=method, friction_correction="slab")
    h = result["hardening"]
    z = {name: _z(h, law, key, name) for name, key in (("A", "A_MPa"), ("B", "B_MPa"), ("n", "n"))}
    assert all(abs(v) <= WITHIN for v in z.values()), (z, h, result["friction_details"][method])
    assert "friction μ" in result["methods"]["hardening_stderr"]
    assert "resolution" in result["methods"]["friction_mu_stderr"] and "model form" in result["methods"]["friction_mu_stderr"]


@pytest.mark.parametrize("method", BARREL_METHODS)
def test_the_resolution_share_is_the_scatter_of_mu_over_the_readings(method):
    """Central differences at ± 0.01 mm against μ's scatter when every reading is off by a normal
    0.01 mm (σ), sampled: the same to the sampling's and the linearisation's error."""
    d0, h0, hk, dmax = 8.0, 6.0, 3.1, 11.3
    rng = np.random.default_rng(7)
    noise = rng.normal(0.0, fr.DIAMETER_RESOLUTION_MM, (4000, 4))
    mus = [fr.identify_friction(method, d0 + a, h0 + b, hk + c, d_max_mm=dmax + d).mu for a, b, c, d in noise]
    stated = fr.identify_friction(method, d0, h0, hk, d_max_mm=dmax).extra["mu_stderr_resolution"]
    assert stated == pytest.approx(float(np.std(mus)), rel=0.08)


@pytest.fixture(scope="module")
def model_form_bench():
    return SimpleNamespace(**runpy.run_path(str(Path(__file__).resolve().parents[2] / "bench" / "friction_model_form.py")))


@pytest.mark.parametrize("method", BARREL_METHODS)
def test_the_model_form_share_is_what_the_calculix_table_measures(model_form_bench, method):
    """MU_MODEL_FORM against the method fed the CalculiX table's barrels (μ 0.05–0.2, the table's h0/d0 × n × ε0)."""
    rows = model_form_bench.relative_errors(method)
    assert np.isfinite(rows[:, 5]).sum() >= 0.95 * len(rows)
    assert fr.MU_MODEL_FORM[method] == pytest.approx(model_form_bench.rms(rows[:, 5]), abs=0.01)
    result = fr.identify_friction(method, 8.0, 6.0, 3.1, d_max_mm=11.3)
    assert result.extra["mu_stderr"] == pytest.approx(math.hypot(result.extra["mu_stderr_resolution"], fr.MU_MODEL_FORM[method] * result.mu))

"""SDAR (ASTM E3076-18) against records whose linear region is known in closed form, and against
the 42CrMoS4 lab's published moduli."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.indicator import elastic_modulus, sdar_modulus
from flowcurve.identification.sdar import sdar

DATA = Path(__file__).resolve().parents[1] / "data" / "42CrMoS4" / "original_data"  # vendored, CC BY 4.0


def toe_line_knee(E=70_000.0, toe_stress=60.0, yield_MPa=300.0, offset_MPa=10.0, n=600, noise_MPa=0.3, seed=0):
    """A soft toe (σ = E·ε²/(2ε_t): its slope grows to E at σ_t), the line of slope E, then a
    Ramberg–Osgood knee ε = σ/E + 0.002·(σ/σy)^12 on the line's own strain, all lifted by an
    offset, and load-cell noise (SDAR ranks windows by their residual: a record without any noise
    leaves every window on the line a residual of rounding only). Returns strain, stress and the
    straight part's stress range."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.15 * yield_MPa, n)
    e_t = 2.0 * toe_stress / E
    e = np.where(s <= toe_stress, np.sqrt(2.0 * e_t * s / E), e_t + (s - toe_stress) / E + 0.002 * (s / yield_MPa) ** 12)
    s = s + offset_MPa + rng.normal(0.0, noise_MPa, s.size)
    return e, s, (toe_stress + offset_MPa, 0.6 * yield_MPa)


def test_the_slope_of_a_record_with_toe_and_knee_is_its_line():
    e, s, (straight_from, _) = toe_line_knee()
    fit = sdar(e, s)
    assert fit.slope == pytest.approx(70_000.0, rel=0.005)
    assert fit.passed, fit.quality
    # the window starts where the toe's slope E·√(σ/σ_t) is within 17 % of E (σ ≥ 0.7·σ_t) and ends below the knee (0.2 % offset at σy)
    assert s[fit.indices[0]] >= straight_from - 0.3 * 60.0 and s[fit.indices[-1]] <= 300.0
    # the least residual window from the start of the record (the toe) would be flatter: the toe is what SDAR leaves out
    assert np.polyfit(e[:150], s[:150], 1)[0] < 0.9 * fit.slope


def test_noise_is_measured_and_flagged():
    e, s, _ = toe_line_knee(noise_MPa=8.0, seed=3)
    fit = sdar(e, s)
    assert fit.slope == pytest.approx(70_000.0, rel=0.05)  # noise of 2.3 % of the range
    assert not fit.quality["noise"]["passed"] and fit.quality["noise"]["relative_noise_y"] > 1.0
    quiet = sdar(*toe_line_knee(noise_MPa=0.3)[:2])
    assert quiet.quality["noise"]["relative_noise_y"] < 1.0


def test_a_coarse_record_is_refused_in_one_line():
    e, s, _ = toe_line_knee(n=12)
    with pytest.raises(IdentificationError, match=r"SDAR: only \d+ samples up to the tangency point"):
        sdar(e, s)


def test_a_straight_record_has_no_tangency_point():
    e = np.linspace(0.0, 0.004, 200)
    with pytest.raises(IdentificationError, match="SDAR"):
        sdar(e, 200_000.0 * e)


def test_the_modulus_block_carries_the_metrics_and_the_method():
    e, s, _ = toe_line_knee()
    mod = sdar_modulus(e, s)
    assert mod.E_MPa == pytest.approx(70_000.0, rel=0.005)
    assert mod.source.startswith("SDAR (ASTM E3076-18)") and "all quality checks passed" in mod.source
    assert set(mod.as_dict()["quality"]) == {"noise", "resolution", "curvature", "fit_range"}
    # strain regressed on stress gives the same line on a clean record
    assert elastic_modulus("sdar", e, s, 0.0, strain_on_stress=True).E_MPa == pytest.approx(70_000.0, rel=0.005)
    with pytest.raises(IdentificationError, match="unknown modulus method 'tangent'"):
        elastic_modulus("tangent", e, s, 300.0)


def test_sdar_on_the_published_42CrMoS4_moduli():
    """SDAR on the extensometer curve up to Fm against the lab's slope of the linear-elastic
    region: an independent regression by the lab's own software."""
    from flowcurve.record.importers import load_record

    files = sorted(DATA.glob("*.csv"))
    dev = []
    for f in files:
        rec = load_record(f)
        force, ext = rec.column("force_N"), rec.column("extensometer_mm")
        i_m = int(np.argmax(force))
        gauge = rec.positive("specimen.extensometer_gauge_mm") or rec.positive("specimen.l0_mm")
        fit = sdar((ext[: i_m + 1] - ext[0]) / gauge, force[: i_m + 1] / rec.positive("specimen.s0_mm2", required=True))
        dev.append(fit.slope / rec.number("published.E_MPa", required=True) - 1.0)
    dev = np.abs(np.array(dev))
    assert len(dev) == 67
    assert np.median(dev) < 0.015 and np.mean(dev <= 0.03) >= 0.9, (np.median(dev), np.sort(dev)[-5:])
    assert math.isfinite(dev.max())


def exhaustive_least_residual(xn, yn):
    """The reference: every start, every end (the scan the product prunes), least 1 − R² first."""
    n = xn.size
    n_min = max(int(math.floor(0.2 * n)), 10)
    c = [np.concatenate([[0.0], np.cumsum(v)]) for v in (np.ones(n), xn, yn, xn * xn, xn * yn, yn * yn)]
    best = (np.inf, -1, -1)
    for i in range(0, n - n_min + 1):
        j = np.arange(i + n_min, n + 1)
        k, sx, sy, sxx, sxy, syy = (cj[j] - cj[i] for cj in c)
        vxx, vxy, vyy = sxx - sx * sx / k, sxy - sx * sy / k, syy - sy * sy / k
        with np.errstate(divide="ignore", invalid="ignore"):
            res = np.where((vxx > 0) & (vyy > 0), 1.0 - vxy * vxy / (vxx * vyy), np.inf)
        m = int(np.argmin(res))
        if res[m] < best[0]:
            best = (float(res[m]), i, int(j[m]) - 1)
    return best


def normalized_to_tangency(e, s):
    """The normalized record SDAR searches (up to its tangency point), as :func:`sdar` makes it."""
    from flowcurve.identification.sdar import tangency_index

    x, y = e - e[0], s - s[0]
    t = tangency_index(x, y)
    keep = np.flatnonzero((y <= y[t]) & (x <= x[t]))
    return x[keep] / x[t], y[keep] / y[t]


def nt75_extensometer():
    return _extensometer(DATA / "46NT75.csv")


def test_46NT75_keeps_the_least_residual_window_and_reports_its_failed_check():
    """E3076 §6.6: the window of least residual is the linear region, whatever its fit quality; the
    old code took the 59th window (E 214.2 GPa, 'all quality checks passed')."""
    e, s = nt75_extensometer()
    fit = sdar(e, s)
    xn, yn = normalized_to_tangency(e, s)
    _, i, j = exhaustive_least_residual(xn, yn)
    assert (fit.indices[0], fit.indices[-1]) == (i, j)  # no offset raise on this record: the same samples
    assert fit.failed_checks() == ["fit_range"] and fit.quality["fit_range"]["normalized_y_range"] < 0.4
    assert fit.slope == pytest.approx(np.polyfit(e[i: j + 1], s[i: j + 1], 1)[0], rel=1e-9)
    assert fit.slope == pytest.approx(201_200.0, rel=0.005)
    mod = sdar_modulus(e, s)
    assert "failed quality checks: fit_range" in mod.source and "all quality checks passed" not in mod.source


def test_auto_names_the_failed_sdar_window_it_did_not_use():
    """On a crosshead the default tries SDAR; where its least-residual window fails, the project's own
    window gives E and says so (never an E3076 label on it)."""
    e, s = nt75_extensometer()
    mod = elastic_modulus("auto", e, s, 0.5 * float(np.max(s)), crosshead=True)
    assert mod.sdar_failed == ["fit_range"] and "ASTM E3076-18, not used" in mod.source
    assert "flowcurve's own method, not ASTM E3076" in mod.source and mod.quality is None
    assert mod.as_dict()["sdar_failed_checks"] == ["fit_range"]


@pytest.mark.parametrize("n, seed", [(3000, 0), (5000, 1), (8000, 2)])
def test_the_pruned_search_finds_the_exhaustive_window(n, seed):
    """Above 2000 points the window search is coarse to fine: the same window as every start and end scanned."""
    from flowcurve.identification.sdar import EXHAUSTIVE_POINTS, least_residual_window

    e, s, _ = toe_line_knee(n=n, seed=seed)
    xn, yn = normalized_to_tangency(e, s)
    assert xn.size > EXHAUSTIVE_POINTS  # the pruned path
    ref = exhaustive_least_residual(xn, yn)
    got = least_residual_window(xn, yn)
    assert got[1:] == ref[1:] and got[0] == pytest.approx(ref[0], rel=1e-9)


@pytest.mark.parametrize("stride", [4, 8])
def test_a_coarse_grid_on_the_short_records_keeps_the_window(stride):
    """The coarse-to-fine search forced onto the 67 vendored extensometer records (about 100 points
    up to the tangency point, a grid of 4 or 8 samples): the window of the exhaustive scan on every one."""
    from flowcurve.identification.sdar import least_residual_window

    files = sorted(DATA.glob("*.csv"))
    assert len(files) == 67
    for f in files:
        xn, yn = normalized_to_tangency(*_extensometer(f))
        assert least_residual_window(xn, yn, stride=stride)[1:] == exhaustive_least_residual(xn, yn)[1:], f.name


def _extensometer(path):
    from flowcurve.record.importers import load_record

    rec = load_record(path)
    force, ext = rec.column("force_N"), rec.column("extensometer_mm")
    i_m = int(np.argmax(force))
    gauge = rec.positive("specimen.extensometer_gauge_mm") or rec.positive("specimen.l0_mm")
    return (ext[: i_m + 1] - ext[0]) / gauge, force[: i_m + 1] / rec.positive("specimen.s0_mm2", required=True)


def test_identify_reports_the_failed_check_in_result_json_and_warnings():
    """46NT75 with --modulus-method sdar: E from the least-residual window (201.2 GPa), its failed
    check in the modulus block and a warning. 46NT85 crosshead-only (default auto): SDAR's window
    fails the fit range, the project's own window gives E, and both say so."""
    from flowcurve.identification.identify import identify
    from flowcurve.record.importers import load_record

    r = identify(load_record(DATA / "46NT75.csv"), modulus_method="sdar").result
    assert r["E_MPa"] == pytest.approx(201_200.0, rel=0.005)
    assert not r["modulus"]["quality"]["fit_range"]["passed"] and "failed quality checks: fit_range" in r["modulus"]["source"]
    assert any(w.startswith("SDAR (ASTM E3076-18): the least-residual window failed fit_range; E is reported from it") for w in r["warnings"])
    x = identify(load_record(DATA / "46NT85.csv"), use_extensometer=False, frame_stiffness_N_per_um=40.0).result
    assert x["modulus"]["sdar_failed_checks"] == ["fit_range"] and "(ASTM E3076-18, not used)" in x["modulus"]["source"]
    assert any("E is from flowcurve's own automatic window instead (not an E3076 result)" in w for w in x["warnings"])
    assert "all quality checks passed" not in x["modulus"]["source"]


def test_the_memo_gives_the_line_a_fresh_search_gives_and_keeps_it_from_relabels():
    """The modulus's fixed-point loop asks again of the same curve with another reference: SDAR's line is
    found once (its line does not depend on the reference), the same as a fresh search, and a caller
    relabelling one answer leaves the next untouched."""
    e, s, _ = toe_line_knee(n=3000, seed=4)
    memo: dict = {}
    first = elastic_modulus("auto", e, s, 0.5 * float(np.max(s)), crosshead=True, sdar_memo=memo)
    first.source = "relabelled by the caller"
    again = elastic_modulus("auto", e, s, 0.4 * float(np.max(s)), crosshead=True, sdar_memo=memo)
    fresh = elastic_modulus("auto", e, s, 0.4 * float(np.max(s)), crosshead=True)
    assert len(memo) == 1 and again.source == fresh.source != first.source
    assert (again.E_MPa, again.window_MPa, again.n_points) == (fresh.E_MPa, fresh.window_MPa, fresh.n_points)


def test_a_record_with_every_sample_finite_gives_what_its_finite_samples_give():
    """Every sample finite (no copy of the record is taken) or a blank cell left out: the same fit, index for index."""
    e, s, _ = toe_line_knee()
    whole = sdar(e, s)
    blank = sdar(np.r_[np.nan, e], np.r_[1.0, s])  # a leading sample without a strain: left out, indices shift by one
    assert (whole.slope, whole.intercept, whole.normalized_residual) == (blank.slope, blank.intercept, blank.normalized_residual)
    assert np.array_equal(whole.indices + 1, blank.indices) and whole.quality == blank.quality

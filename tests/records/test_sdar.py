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

"""Compression records with a soft start (toe) and no handbook modulus: the elastic line is
extended to zero force (ISO 6892-1), so Rp0.2 and the true curve start where the material yields."""

import numpy as np
import pytest

from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.indicator import yield_onset_from_rate

from .toe_records import make_toe_compression


@pytest.mark.parametrize("rate_hz", [10.0, 50.0])
@pytest.mark.parametrize("toe_mm", [0.0, 0.05])
@pytest.mark.parametrize("handbook_E", [False, True])
def test_rp02_within_3_percent_with_a_toe_and_without_handbook_E(rate_hz, toe_mm, handbook_E):
    record, truth = make_toe_compression(rate_hz=rate_hz, toe_mm=toe_mm, handbook_E=handbook_E)
    ident = identify_compression(record)
    r = ident.result
    # the model's mean pressure at εp = 0.002 (flow stress × the Coulomb slab factor)
    assert r["Rp02_MPa"] == pytest.approx(truth["rp02_pressure_MPa"], rel=0.03)
    # the toe found is the seating travel, within one encoder step; with the handbook E the line's
    # offset is read on its known slope, within 1 µm, and Rp0.2 within 1.5 % (10 noise seeds: 1.3 % at most)
    assert r["indicator"]["toe_compensation_mm"] == pytest.approx(toe_mm, abs=0.001 if handbook_E else 0.01)
    if handbook_E:
        assert r["Rp02_MPa"] == pytest.approx(truth["rp02_pressure_MPa"], rel=0.015)
    # the true curve starts at the yield, not near zero stress
    first = ident.true_curve["true_stress_MPa"].iloc[0]
    assert first >= 0.9 * r["Rp02_MPa"]
    assert r["modulus"]["source"] and (handbook_E == ("material.E_MPa" in r["E_source"]))
    # the record's force is the slab solution's: corrected by it, the curve is Johnson–Cook again. The
    # FE-consistent default reads this record's bulge, made with (3.18), as μ ≈ 0.18 for 0.11, and its
    # fit may be poor — then it says so
    assert identify_compression(record, friction_correction="slab").result["hardening"]["quality"] == "good"
    assert r["hardening"]["quality"] == "good" or r["hardening"]["warnings"]


def test_yield_onset_from_the_force_rate_ignores_displacement():
    # elastic at 1000 N/s up to 3000 N, then 100 N/s; a toe at 200 N/s below 500 N; noise 20 N at 50 Hz
    t = np.arange(0, 40, 0.02)
    f = np.where(t < 2.5, 200 * t, 500 + 1000 * (t - 2.5))
    t_y = 2.5 + 2.5
    f = np.where(t < t_y, f, 3000 + 100 * (t - t_y))
    f = f + np.random.default_rng(0).normal(0, 20, t.size)
    onset = yield_onset_from_rate(t, f)
    assert 2600 < onset < 3300  # within the three force levels (3 × 100 N) the rate is taken over


def test_the_modulus_window_option_reaches_compression():
    record, truth = make_toe_compression(rate_hz=50.0, toe_mm=0.05)
    r = identify_compression(record, modulus_window_MPa=(15.0, 110.0)).result
    assert r["modulus"]["window_MPa"] == [15.0, 110.0] and r["modulus"]["source"] == "given window (MPa)"
    assert r["Rp02_MPa"] == pytest.approx(truth["rp02_pressure_MPa"], rel=0.03)
    r = identify_compression(record, modulus_window=(0.1, 0.6)).result
    assert r["modulus"]["source"].startswith("given window 0.1–0.6 × the yield stress")


def test_the_next_window_is_set_on_the_lines_rise_not_in_the_noise_before_it():
    """The yield estimate that sets the next modulus window is the first sample past the 0.2 %
    offset *on the line's rise*: a line whose zero force lies at negative strain (here −0.3 %)
    puts the samples at zero force past the offset too, and one of them with a noise of
    −0.007 MPa once made the window's reference negative ("no elastic line" on the demo's own
    compression record)."""
    from flowcurve.identification.compression.identify import _offset_onset_MPa
    from flowcurve.identification.indicator import ModulusFit

    E = 200_000.0
    line = ModulusFit(E_MPa=E, E_stderr_MPa=100.0, intercept_MPa=0.003 * E, r2=0.9999, n_points=6, window_MPa=(100.0, 250.0))
    stress = np.array([-0.007, 0.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0, 330.0, 340.0])
    strain = (stress - line.intercept_MPa) / E  # on the line ...
    strain[:2] = 0.0  # ... but at zero force the specimen has not moved: 0.3 % "past" the line
    strain[-2:] += [0.0025, 0.006]  # ... until it yields
    assert _offset_onset_MPa(strain, stress, line) == 330.0


def _onset_with_the_median_period(time_s, force_N, levels: int = 400) -> float:
    """yield_onset_from_rate as written before issue 43: the median sampling period always taken."""
    from flowcurve.identification.iso6892 import mad_sigma

    t, f = np.asarray(time_s, dtype=float), np.asarray(force_N, dtype=float)
    noise = mad_sigma(np.diff(f)) / np.sqrt(2.0)
    envelope = np.maximum.accumulate(f)
    step = max(envelope[-1] / levels, 5.0 * noise)
    level = np.arange(step, envelope[-1], step)
    times = t[np.searchsorted(envelope, level)]
    rate = 3.0 * step / np.maximum(times[3:] - times[:-3], float(np.median(np.diff(t))))
    peak = int(np.argmax(rate))
    below = np.nonzero(rate[peak:] < 0.5 * rate[peak])[0]
    return float(level[peak + int(below[0])]) if below.size else float(level[-1])


@pytest.mark.parametrize("samples", [60, 400, 5000])
def test_the_force_rate_onset_is_the_same_whether_the_period_floors_a_span_or_not(samples):
    """Sparse sampling (a span of three levels within one period: the median period floors it) or dense (it floors none)."""
    t = np.linspace(0.0, 100.0, samples)
    f = np.where(t < 40.0, 250.0 * t, 10_000.0 + 20.0 * (t - 40.0)) + np.random.default_rng(samples).normal(0.0, 2.0, samples)
    assert yield_onset_from_rate(t, f) == _onset_with_the_median_period(t, f)

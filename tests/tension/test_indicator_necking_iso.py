"""Indicator-diagram steps, neck corrections and ISO 6892-1 results against closed forms."""

import math

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification import iso6892
from flowcurve.identification.indicator import (
    compensate_toe, fit_modulus, frame_stiffness_from_known_modulus, remove_frame_compliance, scale_to_measured,
)
from flowcurve.identification.tension.necking import (
    bridgman_factor, davidenkov_factor, le_roy_a_over_R, mirone_factor, neck_corrections,
)


# -- indicator ---------------------------------------------------------------------------------

def test_frame_compliance_closed_form():
    # 13.6 kN on a 136 N/µm frame = 100 µm of frame travel
    assert remove_frame_compliance([0.5], [13_600.0], 136.0)[0] == pytest.approx(0.4)
    with pytest.raises(IdentificationError, match="stiffness"):
        remove_frame_compliance([0.5], [1.0], 0.0)


def test_scaling_factor_is_the_seed_worked_example():
    # compression worked example: K_l = (h0 − hk)/max Δl = 0.96
    disp = np.linspace(0, 2.5, 11)
    scaled, k = scale_to_measured(disp, 2.4)
    assert k == pytest.approx(0.96)
    assert scaled.max() == pytest.approx(2.4)
    with pytest.raises(IdentificationError):
        scale_to_measured(np.zeros(5), 1.0)


def test_toe_compensation_removes_slack_and_replaces_the_toe():
    k = 50.0  # N/mm
    force = np.linspace(0, 1000, 201)
    slack = 0.3 * (1 - np.clip(1 - force / 200, 0, 1) ** 2)  # taken up below 200 N
    disp = force / k + slack
    out, toe = compensate_toe(disp, force, window_N=(300, 900))
    assert toe == pytest.approx(0.3)
    assert np.allclose(out, force / k, atol=1e-12)


def test_modulus_regression_on_a_known_line_and_window_limits():
    e = np.linspace(0, 0.004, 81)
    s = np.minimum(210_000 * e, 600 + 1000 * (e - 600 / 210_000))  # bilinear
    m = fit_modulus(e, s, (60, 480))
    assert m.E_MPa == pytest.approx(210_000)
    assert m.window_MPa == (60, 480)
    with pytest.raises(IdentificationError, match="samples"):
        fit_modulus(e[::40], s[::40], (60, 480))
    with pytest.raises(IdentificationError, match="never reaches 700 MPa"):
        fit_modulus(e, s, (60, 700))


def test_frame_stiffness_from_a_specimen_of_known_modulus():
    E, S, L, C = 200_000.0, 28.27, 30.0, 136.0  # MPa, mm², mm, N/µm
    force = np.linspace(0, 5000, 101)
    cross = force * L / (E * S) + force / (C * 1000)
    assert frame_stiffness_from_known_modulus(cross, force, E_MPa=E, area_mm2=S, length_mm=L, window_N=(500, 4000)) == pytest.approx(C)
    with pytest.raises(IdentificationError, match="stiffer"):
        frame_stiffness_from_known_modulus(cross, force, E_MPa=E / 10, area_mm2=S, length_mm=L, window_N=(500, 4000))


# -- neck corrections -------------------------------------------------------------------------

def test_no_neck_means_no_correction():
    assert davidenkov_factor(0.0) == 1.0
    assert bridgman_factor(0.0) == 1.0
    assert mirone_factor(0.1, 0.1) == 1.0
    assert le_roy_a_over_R(0.05, 0.1) == 0.0


def test_davidenkov_and_bridgman_closed_forms():
    # d_k = 4 mm, R = 2 mm: a/R = 1; η = 1/(1 + 4/16) = 0.8
    assert davidenkov_factor(1.0) == pytest.approx(0.8)
    # Bridgman at a/R = 1: 1/(3·ln 1.5); at a/R = 0.5: 1/(5·ln 1.25)
    assert bridgman_factor(1.0) == pytest.approx(1 / (3 * math.log(1.5)))
    assert bridgman_factor(0.5) == pytest.approx(1 / (5 * math.log(1.25)))
    # small a/R: both ≈ 1 − a/(4R), so they agree with each other there
    assert bridgman_factor(1e-3) == pytest.approx(davidenkov_factor(1e-3), rel=1e-6)
    assert bridgman_factor(1e-9) == pytest.approx(1 - 1e-9 / 4)


def test_mirone_and_le_roy_closed_forms():
    x = 0.5
    assert mirone_factor(0.6, 0.1) == pytest.approx(1 - 0.6058 * x**2 + 0.6317 * x**3 - 0.2107 * x**4)
    assert le_roy_a_over_R(0.6, 0.1) == pytest.approx(0.55)


def test_neck_corrections_side_by_side():
    out = neck_corrections(1500.0, 0.9, 0.1, d_k_mm=4.0, neck_radius_mm=2.0)
    assert out["a_over_R"] == pytest.approx(1.0)
    assert out["davidenkov"]["stress_MPa"] == pytest.approx(1200.0)
    assert out["bridgman"]["stress_MPa"] == pytest.approx(1500 / (3 * math.log(1.5)))
    est = neck_corrections(1500.0, 0.9, 0.1)
    assert est["a_over_R"] == pytest.approx(0.88) and "Le Roy" in est["a_over_R_source"]
    with pytest.raises(IdentificationError, match="post.dk_mm"):
        neck_corrections(1500.0, 0.05, 0.1)


# -- ISO 6892-1 -------------------------------------------------------------------------------

def test_offset_yield_on_a_ramberg_osgood_curve():
    # e = σ/E + 0.002·(σ/σ0)^N: the plastic extension is 0.2 % exactly at σ = σ0
    E, s0, N = 200_000.0, 500.0, 12.0
    s = np.linspace(0, 620, 6000)
    e = s / E + 0.002 * (s / s0) ** N
    rp, idx = iso6892.offset_yield_strength(e, s, E, 0.002, start_MPa=50)
    assert rp == pytest.approx(s0, rel=1e-4)
    rp1, _ = iso6892.offset_yield_strength(e, s, E, 0.01)
    assert rp1 == pytest.approx(s0 * 5 ** (1 / N), rel=1e-4)


def test_fracture_index_and_results():
    force = np.array([0, 5, 10, 12, 11, 9, 8.5, 0.2, 0.1])
    assert iso6892.max_force_index(force) == 3
    assert iso6892.fracture_index(force) == 6
    assert iso6892.fracture_index(force[:7]) == 6
    assert iso6892.elongation_after_fracture_pct(50, 61) == pytest.approx(22.0)
    assert iso6892.reduction_of_area_pct(28.0, 7.0) == pytest.approx(75.0)
    with pytest.raises(IdentificationError, match="post.dk_mm"):
        iso6892.reduction_of_area_pct(28.0, 30.0)


def test_the_noise_of_a_long_series_is_read_at_a_stride_and_stays_the_noise():
    """Above iso6892.MAD_SAMPLES values the MAD reads every m-th: on 540 000 second differences of white
    noise σ = 3 it gives σ·√6 within 2 % (its own scatter ~0.5 %), and within 2 % of the full series' MAD;
    a series at the limit is read whole (the same number as the plain formula)."""
    from flowcurve.identification.iso6892 import MAD_SAMPLES, mad_sigma

    noise = np.random.default_rng(7).normal(0.0, 3.0, 540_002)
    d2 = np.diff(noise, 2)
    full = 1.4826 * float(np.median(np.abs(d2 - np.median(d2))))
    assert mad_sigma(d2) / math.sqrt(6.0) == pytest.approx(3.0, rel=0.02)
    assert mad_sigma(d2) == pytest.approx(full, rel=0.02)
    head = d2[:MAD_SAMPLES]
    assert mad_sigma(head) == 1.4826 * float(np.median(np.abs(head - np.median(head))))


@pytest.mark.parametrize("size", [5, 50_001, 50_002, 540_003])
@pytest.mark.parametrize("order", [1, 2, 3])
def test_mad_sigma_of_differences_is_mad_sigma_of_np_diff_to_the_bit(order, size):
    """The k-th differences evaluated only where mad_sigma reads them give the very same number."""
    from flowcurve.identification.iso6892 import mad_sigma, mad_sigma_of_differences

    x = np.cumsum(np.random.default_rng(order).normal(1.0, 3.0, size))  # a trend and its noise
    assert mad_sigma_of_differences(x, order) == mad_sigma(np.diff(x, order))


@pytest.mark.parametrize("where", [None, 0, 1, 4095, 4096, 12_287, 12_288, 99_999])
def test_first_index_reads_in_chunks_what_flatnonzero_reads_whole(where):
    from flowcurve.identification.iso6892 import first_index

    y = np.zeros(100_000)
    if where is not None:
        y[where:] = 1.0
    whole = np.flatnonzero(y >= 0.5)
    assert first_index(lambda at: y[at] >= 0.5, 0, y.size) == (int(whole[0]) if whole.size else None)
    assert first_index(lambda at: y[at] >= 0.5, 50_000, 60_000) == (min(max(where, 50_000), 60_000) if where is not None and where < 60_000 else None)
    read = []
    first_index(lambda at: read.append(at.stop - at.start) or y[at] >= 0.5, 0, y.size)
    assert sum(read) <= max(2 * (where or y.size) + 4096, 4096) or where is None  # never much past the hit


def test_the_fracture_index_from_a_known_maximum_is_the_one_found_anew():
    """Fm's and the fracture's indices handed on (read once per record) give what each call would find."""
    from flowcurve.identification.tension.values import fracture_index, reaches_fracture

    rising = np.linspace(0.0, 10_000.0, 400)
    for force in (np.r_[rising, 9_000.0, 8_000.0, 1_000.0], np.r_[rising, np.linspace(9_990.0, 9_000.0, 50)], rising):
        i_m = iso6892.max_force_index(force)
        assert iso6892.fracture_index(force, i_m) == iso6892.fracture_index(force)
        i_k = fracture_index(force)
        assert reaches_fracture(force, i_k) == reaches_fracture(force)


def test_the_strain_quantum_is_the_smallest_real_step():
    """q/√12 of the smallest finite non-zero step; none (0) for a reading that never moves."""
    from flowcurve.identification.indicator import strain_quantum_noise

    x = np.r_[0.0, 0.0, 0.003, np.nan, 0.004, 0.010, 0.010, 0.0095]
    assert strain_quantum_noise(x) == pytest.approx(0.0005 / math.sqrt(12.0), rel=1e-9)
    d = np.abs(np.diff(x))
    assert strain_quantum_noise(x) == float(np.min(d[np.isfinite(d) & (d > 0)])) / math.sqrt(12.0)
    assert strain_quantum_noise(np.full(5, 0.002)) == 0.0 and strain_quantum_noise([np.nan, 1.0]) == 0.0

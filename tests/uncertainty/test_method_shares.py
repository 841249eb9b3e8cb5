"""The budget's new terms (issue 43): dimensions with the instruments' MPE and ISO 6892-1's bound on du,
read from the record's instruments.* keys; what U covers (near-rectangular, Student's t at ν_eff);
the testing rate within the method's range; an offset yield's E, lines and strain zero."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.identification.quality import uncertainty as un
from flowcurve.identification.quality.assurance import instruments_from_meta

INST = dict(un.INSTRUMENT_DEFAULTS) | dict(un.DIMENSION_DEFAULTS)


def test_z_holds_the_micrometers_mpe_and_the_fracture_bound():
    """46NT71's dimensions (d0 5.003, du 3.34 mm): Z's U was the resolution alone (0.19 %); with the
    micrometer's MPE and ISO 6892-1's ±2 % on Su it is about five times that, by hand."""
    d0, du = 5.003, 3.34
    old = un.reduction_of_area_budget(d0, du, 0.01)
    new = un.reduction_of_area_budget(d0, du, 0.01, mpe_mm=0.004, fracture_rel=un.FRACTURE_DIAMETER_REL)
    u_du = math.sqrt((0.01 / math.sqrt(12)) ** 2 + (0.004 / math.sqrt(3)) ** 2 + (0.01 * du / math.sqrt(3)) ** 2)
    u_d0 = math.sqrt((0.01 / math.sqrt(12)) ** 2 + (0.004 / math.sqrt(3)) ** 2)
    assert new["U"] == pytest.approx(2 * math.hypot(200 * du / d0 ** 2 * u_du, 200 * du ** 2 / d0 ** 3 * u_d0), rel=1e-9)
    assert 4 < new["U"] / old["U"] < 7


def test_the_dimension_instruments_are_read_from_the_record():
    inst = instruments_from_meta({"instruments.micrometer_mpe_mm": "0.002", "instruments.caliper_mpe_mm": "0.02"})
    assert (inst["micrometer_mpe_mm"], inst["caliper_mpe_mm"]) == (0.002, 0.02)
    assert "defaults for force_class" in inst["source"]
    assert instruments_from_meta({})["micrometer_mpe_mm"] == un.DIMENSION_DEFAULTS["micrometer_mpe_mm"]


def test_a_dominant_rectangular_term_is_said_and_its_U_covers_it_entirely():
    comps = [un.Component("big", 1.0, "1", 1.0, 1.0, "rectangular"), un.Component("small", 1.0, "1", 0.1, 1.0, "normal")]
    b = un.budget(0.0, "1", comps)
    assert b["k"] == 2 and "near-rectangular" in b["coverage"]
    _, sd, (lo, hi) = un.monte_carlo(lambda a, b: a + b, {"a": (0.0, 1.0, "rectangular"), "b": (0.0, 0.1, "normal")}, n=200_000)
    assert (hi - lo) / 2 < 0.85 * b["U"]  # the 95 % interval is well inside ±2u: "≈ 95 %" would be wrong


def test_a_type_a_term_with_few_repeats_takes_students_t():
    comps = [un.Component("repeats", 0.0, "1", 1.0, 1.0, "Type A, 3 repeats", dof=2.0), un.Component("class", 0.0, "1", 0.3, 1.0, "normal")]
    b = un.budget(0.0, "1", comps)
    nu = b["u"] ** 4 / (1.0 / 2.0)
    from scipy.stats import t
    assert b["k"] == pytest.approx(t.ppf(0.975, nu)) and "ν_eff" in b["coverage"]


@pytest.mark.parametrize("method, ratio", [("A2", 1.5), ("B", 10.0), (None, 10.0)])
def test_the_rate_term_spans_the_methods_range(method, ratio):
    c = un.rate_component(500.0, method, "steel")
    half = 500.0 * un.RATE_SENSITIVITY["steel"] * math.log(ratio) / 2.0
    assert c.contribution == pytest.approx(half / math.sqrt(3))
    assert 5.0 <= 2 * half <= 15.0 or method == "A2"  # method B: 5–15 MPa on a ferritic Rp of 500 MPa (the review's figure)


def test_the_offset_method_terms_on_a_closed_form_curve():
    """σ = E·e to 300 MPa, then 300 + 20000·e_p: Rp0.2 = 340 MPa; ∂Rp/∂E and ∂Rp/∂ε0 by hand."""
    E = 200_000.0
    ep = np.linspace(0, 0.01, 2001)
    sig = np.concatenate([np.linspace(0, 300, 301), 300 + 20_000 * ep[1:]])
    eps = np.concatenate([np.linspace(0, 300, 301) / E, (300 + 20_000 * ep[1:]) / E + ep[1:]])
    assert un.offset_yield_MPa(eps, sig, E) == pytest.approx(340.0, abs=0.01)
    comps = {c.name: c for c in un.offset_method_components(eps, sig, E, 2000.0, {"a": E, "b": 0.9 * E}, 1e-4)}
    # e(σ) − σ/E = 0.002 at Rp: ∂Rp/∂E = −θ·Rp/E² (a steeper line reads more plastic strain, so yields lower); ∂Rp/∂ε0 = θ
    assert comps["method: E of the offset line"].sensitivity == pytest.approx(-20_000 * 340 / E ** 2, rel=0.02)
    assert comps["method: strain zero and toe ε0"].sensitivity == pytest.approx(20_000, rel=0.01)
    spread = comps["method: spread over the defensible elastic lines"]
    rp_b = un.offset_yield_MPa(eps, sig, 0.9 * E)
    assert spread.value == pytest.approx(abs(340.0 - rp_b) / 2) and spread.u == pytest.approx(spread.value / math.sqrt(3))


def test_the_interpolation_term_is_the_linear_error_on_a_quadratic_curve():
    """σ(εp) = 300 + 40 000·εp − 2·10⁶·εp² sampled every 0.003 of εp: the quadratic through the three samples
    about the 0.2 % crossing is the curve itself, so the stated half-width equals the linear
    interpolant's true error at εp = 0.002 (by hand: the chord's sag there)."""
    E = 200_000.0
    ep = np.array([0.0, 0.0011, 0.0041, 0.0071, 0.0101])
    sig = 300.0 + 40_000.0 * ep - 2e6 * ep**2
    strain = ep + sig / E
    true = 300.0 + 40_000.0 * 0.002 - 2e6 * 0.002**2
    lin = un.offset_yield_MPa(strain, sig, E)
    half = un.offset_interpolation_halfwidth_MPa(strain, sig, E)
    assert abs(true - lin) > 1.0  # the sag is real: about 2 MPa
    assert half == pytest.approx(abs(true - lin), rel=1e-9)
    dense = np.linspace(0.0, 0.01, 2001)
    s_dense = 300.0 + 40_000.0 * dense - 2e6 * dense**2
    assert un.offset_interpolation_halfwidth_MPa(dense + s_dense / E, s_dense, E) < 1e-6  # dense samples: nothing to add


def test_the_offset_lines_zero_leaves_the_spacing_out_only_where_a_regressed_line_places_it():
    """A regressed line: δε0 of the offset line is √(line² + toe²); a handbook E through sparse first
    samples: the spacing counts too (a compression record at 10× the rate showed a −2.6 % Rp0.2 that
    only the spacing covered)."""
    from flowcurve.identification.quality.assurance import _offset_line_zero

    def result(**parts):
        return {"hardening": {"start_uncertainty": {"delta_eps0": math.sqrt(sum(v**2 for v in parts.values())), "components": parts}}}

    assert _offset_line_zero(result(line_fit=3e-5, line_curvature=0.0, toe=4e-5, sample_spacing=1e-3, handbook_E=0.0)) == pytest.approx(5e-5)
    assert _offset_line_zero(result(line_fit=0.0, toe=1e-4, sample_spacing=2e-3, handbook_E=6e-5)) == pytest.approx(
        math.sqrt(1e-8 + 4e-6 + 3.6e-9))


def test_the_band_of_a_flat_maximum_is_where_the_noise_hides_it():
    """σ = 500 − c·(e − 0.12)² sampled every 0.0005 with Gaussian noise s: the samples within 2√2·s of the
    highest one reach about e0 ± √(2√2·s/c) (by hand); noise-free, the band is the maximum itself.
    Ag's budget states half the band (rectangular) and its value is the band's mid-point (ISO 6892-1 §13)."""
    from flowcurve.identification.iso6892 import max_force_band

    c, e0, s = 20_000.0, 0.12, 0.5
    e = np.arange(0.05, 0.2, 0.0005)
    clean = 500.0 - c * (e - e0) ** 2
    i = int(np.argmax(clean))
    assert max_force_band(e, clean) == (e[i], e[i])
    half = math.sqrt(2.0 * math.sqrt(2.0) * s / c)  # 0.0084
    mids, widths = [], []
    for seed in range(40):
        lo, hi = max_force_band(e, clean + np.random.default_rng(seed).normal(0.0, s, e.size))
        mids.append((lo + hi) / 2), widths.append((hi - lo) / 2)
    assert np.median(widths) == pytest.approx(half, rel=0.35)
    assert abs(np.median(mids) - e0) < 0.25 * half  # the mid-point is unbiased on a symmetric maximum

"""GUM budgets of identification.uncertainty against hand-written closed forms and Monte Carlo."""

import math

import numpy as np
import pytest

from flowcurve.identification.quality import uncertainty as un

INST = dict(un.INSTRUMENT_DEFAULTS)


def test_rm_budget_is_the_gum_formula_written_out():
    """Rm = 4F/(π d0²): u² = (∂Rm/∂F·u_F)² + (∂Rm/∂d0·u_d)², written independently here."""
    F, d0, cls, res = 23565.3, 5.003, 0.5, 0.002
    inst = INST | {"force_class": cls, "diameter_resolution_mm": res}
    Rm = 4 * F / (math.pi * d0 ** 2)
    u_F = F * cls / 100 / math.sqrt(3)  # class bound ±0.5 % rectangular
    u_d = res / 2 / math.sqrt(3)  # half the resolution step, rectangular
    dRm_dF = 4 / (math.pi * d0 ** 2)
    dRm_dd = -8 * F / (math.pi * d0 ** 3)
    U_hand = 2 * math.sqrt((dRm_dF * u_F) ** 2 + (dRm_dd * u_d) ** 2)
    b = un.strength_budget(Rm, d0, inst)
    assert b["value"] == pytest.approx(Rm)
    assert b["U"] == pytest.approx(U_hand, rel=1e-12)
    assert b["k"] == 2
    force, diam = b["components"]
    assert force["u"] == pytest.approx(u_F) and force["sensitivity"] == pytest.approx(dRm_dF)
    assert diam["contribution"] == pytest.approx(abs(dRm_dd) * u_d)


def test_rm_budget_agrees_with_monte_carlo():
    """GUM Supplement 1: propagate the rectangular F and d0 through Rm = 4F/(πd0²) by sampling."""
    F, d0 = 12962.0, 6.0
    inst = INST | {"force_class": 2.0, "diameter_resolution_mm": 0.05}  # coarse, so the non-linearity would show
    Rm = 4 * F / (math.pi * d0 ** 2)
    b = un.strength_budget(Rm, d0, inst)
    mean, sd, (lo, hi) = un.monte_carlo(lambda F, d: 4 * F / (math.pi * d ** 2),
                                        {"F": (F, F * 0.02 / math.sqrt(3), "rectangular"),
                                         "d": (d0, 0.05 / math.sqrt(12), "rectangular")}, n=400_000)
    assert sd == pytest.approx(b["u"], rel=0.01)
    assert mean == pytest.approx(Rm, rel=1e-3)
    # the 95 % interval of the sampled Rm is about ±U (the sum of two rectangles is not normal: within 10 %)
    assert (hi - lo) / 2 == pytest.approx(b["U"], rel=0.10)


def test_z_budget_against_finite_differences():
    """Z = 100(1 − du²/d0²): the budget's sensitivities match central differences of the formula."""
    d0, du, res = 6.0, 4.6095, 0.01
    b = un.reduction_of_area_budget(d0, du, res)
    Z = lambda d0_, du_: 100 * (1 - du_ ** 2 / d0_ ** 2)  # noqa: E731
    h = 1e-6
    assert b["value"] == pytest.approx(Z(d0, du))
    c_du = (Z(d0, du + h) - Z(d0, du - h)) / (2 * h)
    c_d0 = (Z(d0 + h, du) - Z(d0 - h, du)) / (2 * h)
    assert [c["sensitivity"] for c in b["components"]] == pytest.approx([c_du, c_d0], rel=1e-6)
    assert b["U"] == pytest.approx(2 * res / math.sqrt(12) * math.hypot(c_du, c_d0), rel=1e-6)


def test_elongation_from_lengths():
    """A = 100(Lu − L0)/L0 with both lengths at 0.01 mm: U by hand."""
    b = un.elongation_from_lengths_budget(30.0, 34.9018, 0.01)
    assert b["value"] == pytest.approx(100 * 4.9018 / 30)
    u = 0.01 / math.sqrt(12)
    assert b["U"] == pytest.approx(2 * u * math.hypot(100 / 30, 100 * 34.9018 / 30 ** 2))


def test_extensometer_floor_dominates_small_extensions():
    """ISO 9513 class 1: ±1 % of the extension, but never below ±3 µm."""
    assert un.extension_u_mm(0.1, 1.0) == pytest.approx(0.003 / math.sqrt(3))
    assert un.extension_u_mm(2.0, 1.0) == pytest.approx(0.02 / math.sqrt(3))
    assert un.extension_u_mm(2.0, 0.5) == pytest.approx(0.01 / math.sqrt(3))


def test_proof_strength_strain_term_by_perturbing_a_curve():
    """The strain-scale sensitivity of Rp0.2 (−θ·0.002 with E regressed) against the offset
    method run on a curve whose strains are scaled by (1 + δ) and E regressed again."""
    from flowcurve.identification.iso6892 import offset_yield_strength

    E, A, B, n = 200_000.0, 400.0, 500.0, 0.3
    sig = np.linspace(1.0, 399.0, 400)
    ep = np.linspace(1e-5, 0.02, 4000)
    s_pl = A + B * ep ** n
    strain = np.concatenate([sig / E, ep + s_pl / E])
    stress = np.concatenate([sig, s_pl])
    Rp, _ = offset_yield_strength(strain, stress, E)
    delta = 1e-3
    Rp_scaled, _ = offset_yield_strength(strain * (1 + delta), stress, E / (1 + delta))  # E regressed on the scaled strain
    theta = B * n * 0.002 ** (n - 1)
    b = un.proof_strength_budget(Rp, 6.0, INST, plastic_slope_MPa=theta, strain_rel_u=1.0, E_MPa=E, u_E_MPa=0.0, E_measured=True)
    strain_term = next(c for c in b["components"] if c["name"] == "strain scale")
    assert strain_term["sensitivity"] * delta == pytest.approx(Rp_scaled - Rp, rel=0.05)
    # with E given (not rescaled), the lever is 0.002 + Rp/E
    Rp_given, _ = offset_yield_strength(strain * (1 + delta), stress, E)
    b = un.proof_strength_budget(Rp, 6.0, INST, plastic_slope_MPa=theta, strain_rel_u=1.0, E_MPa=E, u_E_MPa=0.0, E_measured=False)
    strain_term = next(c for c in b["components"] if c["name"] == "strain scale")
    assert strain_term["sensitivity"] * delta == pytest.approx(Rp_given - Rp, rel=0.05)


def test_flow_stress_sensitivities_against_the_model():
    """Central differences of models written here: the mean pressure p = F·h/(S0·h0) for the
    force, d0, h0 and Δh terms; Siebel's σ = p/(1 + μ·d/3h) at fixed geometry for μ."""
    d0, h0, hk, eps, mu, F = 6.0, 7.0, 3.5, 0.3, 0.1, 40_000.0

    def pressure(F, d0_, h0_, dh):
        return F * (h0_ - dh) / (math.pi * d0_ ** 2 / 4 * h0_)

    h = h0 * math.exp(-eps)
    p0 = (F, d0, h0, h0 - h)
    sigma = pressure(*p0)
    b = un.flow_stress_budget(sigma, eps, d0, h0, hk, INST, mu=mu, u_mu=0.01)
    sens = [c["sensitivity"] for c in b["components"]]
    for i in range(4):
        lo, hi = list(p0), list(p0)
        step = 1e-6 * abs(p0[i])
        lo[i] -= step
        hi[i] += step
        assert sens[i] == pytest.approx((pressure(*hi) - pressure(*lo)) / (2 * step), rel=1e-5)
    siebel = lambda m: sigma / (1 + m * d0 * math.sqrt(h0 / h) / (3 * h))  # noqa: E731
    # the μ sensitivity, at the corrected σ = siebel(μ), is dσ/dμ of Siebel's law at fixed geometry
    b = un.flow_stress_budget(siebel(mu), eps, d0, h0, hk, INST, mu=mu, u_mu=0.01)
    assert b["components"][4]["sensitivity"] == pytest.approx((siebel(mu + 1e-7) - siebel(mu - 1e-7)) / 2e-7, rel=1e-5)


def test_friction_budget_flags_disagreeing_methods():
    b = un.friction_budget(0.097, [0.0886, 0.1069], others={"bulge_regression": 0.118, "ebrahimi_najafizadeh": 0.106})
    assert b["u"] == pytest.approx((0.1069 - 0.0886) / 2)  # the range is μ ± its standard error
    assert b["methods_disagree"] and "bulge_regression 0.118" in b["note"] and "ebrahimi" not in b["note"]
    assert un.friction_budget(0.1, None) is None


def test_defaults_match_the_rig_configuration():
    """identification cannot import rig (layers): the two copies of the defaults stay equal."""
    from dataclasses import asdict

    from flowcurve.rig.config import InstrumentsConfig

    defaults = {k: v for k, v in asdict(InstrumentsConfig()).items() if v is not None}  # calibration keys have no default
    assert defaults == un.INSTRUMENT_DEFAULTS


def test_rig_configuration_instruments_section(tmp_path):
    """[instruments] is optional, validated, and written back by to_toml."""
    from flowcurve.errors import ConfigError
    from flowcurve.rig.config import load_config, parse_config, to_toml

    base = {"loadcell": {"port": "loop://a", "nominal_load_N": 1e5}, "encoder": {"port": "loop://b"}, "frame": {}}
    assert parse_config(base).instruments.force_class == 1.0
    cfg = parse_config(base | {"instruments": {"force_class": 0.5, "extensometer_class": 0.2}})
    assert cfg.instruments.meta()["instruments.force_class"] == 0.5
    (tmp_path / "rig.toml").write_text(to_toml(cfg))
    assert load_config(tmp_path / "rig.toml").instruments == cfg.instruments
    with pytest.raises(ConfigError, match=r"\[instruments\] force_class: must be one of"):
        parse_config(base | {"instruments": {"force_class": 0.7}})

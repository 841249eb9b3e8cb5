"""The virtual rig's FE compression response (issue 11): its interpolation against the npz read
here directly, and the rig's force and bulge against those values rather than the slab formula."""

import math

import numpy as np
import pytest

from flowcurve.rig.virtual.fe_response import DATA, UpsettingResponse, effective_hardening_exponent  # DATA: the conftest raw fixture reads it
from flowcurve.rig.virtual.physics import RigModel, Specimen


@pytest.fixture(scope="module")
def table():
    return UpsettingResponse.load()


def complete_nodes(raw, strain_from=1):
    """Indices (i, j, k, s) of computed (not padded, not NaN) table points."""
    ff = raw["force_factor"]
    ok = np.isfinite(ff)
    ok[..., :strain_from] = False
    return np.argwhere(ok)


def test_interpolation_reproduces_every_computed_node(raw, table):
    nodes = complete_nodes(raw)
    assert len(nodes) > 0.8 * raw["force_factor"][..., 1:].size  # 18 of 112 runs stopped early, not most
    i, j, k, s = nodes.T
    args = raw["mu"][i], raw["h0_d0"][j], raw["n"][k], raw["strain"][s]
    np.testing.assert_allclose(table.force_factor_at(*args), raw["force_factor"][i, j, k, s], rtol=0, atol=1e-12)
    np.testing.assert_allclose(table.bulge_at(*args), raw["bulge_dR_over_h"][i, j, k, s], rtol=0, atol=1e-12)


def test_interpolation_lies_between_neighbouring_nodes(raw, table):
    # mid-cell along each axis in turn, at complete runs: between the two nodes' values
    mu, h, n, eps = raw["mu"], raw["h0_d0"], raw["n"], raw["strain"]
    ff = raw["force_factor"]
    checked = 0
    for i in range(mu.size - 1):
        for j in range(h.size):
            for k in range(n.size):
                for s in (5, 20, 34):
                    a, b = ff[i, j, k, s], ff[i + 1, j, k, s]
                    if not (np.isfinite(a) and np.isfinite(b)):
                        continue
                    v = float(table.force_factor_at(0.5 * (mu[i] + mu[i + 1]), h[j], n[k], eps[s]))
                    assert min(a, b) - 1e-12 <= v <= max(a, b) + 1e-12
                    checked += 1
    j, k, s = 1, 2, 30
    for jj in range(h.size - 1):  # along h0/d0 (interpolated in ln h0/d0)
        a, b = ff[2, jj, k, s], ff[2, jj + 1, k, s]
        v = float(table.force_factor_at(mu[2], math.sqrt(h[jj] * h[jj + 1]), n[k], eps[s]))
        assert v == pytest.approx(0.5 * (a + b), abs=1e-12)
    assert checked > 100


def test_no_friction_means_factor_one_and_no_bulge(table):
    eps = np.linspace(0.0, 1.2, 61)
    for h0_d0 in (0.6, 1.166, 2.5):
        for n in (0.05, 0.13, 0.65):
            assert np.all(table.force_factor_at(0.0, h0_d0, n, eps) == 1.0)
            assert np.all(table.bulge_at(0.0, h0_d0, n, eps) == 0.0)


def test_stopped_runs_are_filled_and_said_so(raw, table):
    stopped = np.isnan(raw["force_factor"]).any(axis=3)
    assert len(table.filled_runs) == int(stopped.sum()) > 0
    assert np.all(np.isfinite(table.force_factor)) and np.all(np.isfinite(table.bulge_dR_over_h))
    # continuous where a run stopped: the first filled step is the lower-μ neighbour's step
    i, j, k = np.argwhere(stopped)[0]
    s = int(np.argmax(np.isnan(raw["force_factor"][i, j, k])))
    step = table.force_factor[i, j, k, s] - table.force_factor[i, j, k, s - 1]
    assert step == pytest.approx(table.force_factor[i - 1, j, k, s] - table.force_factor[i - 1, j, k, s - 1], abs=1e-12)


def test_edges_are_clamped_and_the_bulge_keeps_growing_beyond_the_table(table):
    end = float(table.strain[-1])
    assert table.force_factor_at(0.1, 1.2, 0.2, end + 0.5) == pytest.approx(table.force_factor_at(0.1, 1.2, 0.2, end))
    assert table.bulge_at(0.1, 1.2, 0.2, end + 0.2) > table.bulge_at(0.1, 1.2, 0.2, end)
    assert table.force_factor_at(0.5, 1.2, 0.2, 0.4) == table.force_factor_at(0.35, 1.2, 0.2, 0.4)
    assert table.in_range(0.5, 3.0, 0.2) and not table.in_range(0.1, 1.2, 0.2)


def test_effective_exponent_of_a_power_law_is_its_exponent():
    assert effective_hardening_exponent(lambda e: 700.0 * e**0.31) == pytest.approx(0.31, abs=1e-12)


def run_to_stroke_limit(model, dt=20.0):
    model.start_crosshead()
    forces = []
    while model.moving:
        model.step(dt)
        forces.append(model.force_N)
    return np.array(forces)


@pytest.mark.parametrize("mu", [0.1])  # a grid μ whose runs reach the rig's ε 0.68 here (at 0.15 and 0.2 they stop: filled)
def test_rig_force_and_bulge_come_from_the_fe_runs_not_the_slab_formula(raw, mu):
    m = RigModel("steel45", "compression", speed_mm_per_s=0.01, friction_mu=mu, force_noise_N=0.0)
    forces = run_to_stroke_limit(m)
    assert np.all(np.diff(forces[forces > 0.5 * forces.max()]) > 0)  # steel 45 hardens: the force only rises
    s, st = m.specimen, m.state
    _, h0_d0, n = m.mechanics.fe_lookup()
    # the FE force factor at the rig's (μ, h0/d0, n, ε), interpolated here straight from the npz
    mu_i = int(np.searchsorted(raw["mu"], mu))
    assert raw["mu"][mu_i] == mu  # a grid μ: no interpolation along μ
    lh = np.log(raw["h0_d0"])
    j = int(np.searchsorted(lh, math.log(h0_d0))) - 1
    wj = (math.log(h0_d0) - lh[j]) / (lh[j + 1] - lh[j])
    k = int(np.searchsorted(raw["n"], n)) - 1
    wk = (n - raw["n"][k]) / (raw["n"][k + 1] - raw["n"][k])

    def from_npz(name, eps):
        v = raw[name][mu_i]
        block = ((1 - wj) * (1 - wk) * v[j, k] + wj * (1 - wk) * v[j + 1, k]
                 + (1 - wj) * wk * v[j, k + 1] + wj * wk * v[j + 1, k + 1])
        return float(np.interp(eps, raw["strain"], block))

    eps = st.eps_p
    assert eps == pytest.approx(0.68, abs=1e-6)
    sigma = float(m.material.flow_stress(eps, 0.01 / s.h0_mm))
    r = s.d0_mm / 2 * math.exp(eps / 2 + m.material.nu * sigma / m.material.E_MPa)  # loaded: the elastic lateral strain νσ/E
    h = s.h0_mm * math.exp(-eps)
    assert st.force_N == pytest.approx(sigma * math.pi * r * r * from_npz("force_factor", eps), rel=1e-9)
    c = 2 * mu * r / h
    slab = sigma * math.pi * r * r * 2 * (math.exp(c) - c - 1) / c**2
    assert abs(st.force_N / slab - 1) > 0.01  # the FE says the slab over-estimates the friction force
    post = {k: float(v) for k, v in m.post_test_measurements().items()}
    hk, dmax = post["post.hk_mm"], post["post.dmax_mm"]
    dn = s.d0_mm * math.sqrt(s.h0_mm / hk)
    assert (dmax - dn) / 2 / hk == pytest.approx(from_npz("bulge_dR_over_h", -math.log(hk / s.h0_mm)), abs=2e-5)  # dmax to 0.1 µm
    seed = 0.0683 * eps**0.83 * (1 - math.exp(-26.7 * mu**1.53))  # (3.18)
    assert abs((dmax - dn) / 2 / hk - seed) > 0.002  # and the barrel is not the seed's regression


@pytest.mark.parametrize("mu", [0.0, 0.05, 0.15, 0.3, 0.35, 0.5])
@pytest.mark.parametrize("material", ["steel45", "12Kh18N10T", "12Kh18N12M3TL"])
@pytest.mark.parametrize("h0_mm", [3.6, 6.982, 15.0])
def test_crosshead_rises_with_strain_for_every_friction(material, mu, h0_mm):
    # the force–stroke solve needs the crosshead monotone in the plastic strain, also past
    # the table's last strain (the bracket search goes far beyond it)
    m = RigModel(material, "compression", Specimen.compression(6.0, h0_mm), friction_mu=mu, force_noise_N=0.0)
    eps = np.concatenate([np.linspace(1e-4, 1.0, 400), [1.5, 3.0, 10.0]])
    x = np.array([m.mechanics.compression_crosshead(e) for e in eps])
    assert np.all(np.diff(x) > 0)


def test_slab_option_and_fe_default_agree_without_friction():
    kw = dict(speed_mm_per_s=0.01, friction_mu=0.0, force_noise_N=0.0)
    fe, slab = RigModel("steel45", "compression", **kw), RigModel("steel45", "compression", compression_response="slab", **kw)
    assert fe.stroke_limit_mm == pytest.approx(slab.stroke_limit_mm, rel=1e-12)
    assert run_to_stroke_limit(fe)[-1] == pytest.approx(run_to_stroke_limit(slab)[-1], rel=1e-12)
    assert fe.post_test_measurements() == slab.post_test_measurements()


def test_unknown_compression_response_is_a_config_error():
    from flowcurve.errors import ConfigError

    with pytest.raises(ConfigError, match="compression_response"):
        RigModel("steel45", "compression", compression_response="magic")

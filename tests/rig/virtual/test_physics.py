"""The physical model against closed forms obtained independently of its own solver."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.materials import get_material
from flowcurve.rig.virtual.physics import (FurnaceParams, Furnace, RigModel, Specimen, furnace_steady_state_C,
                         slab_friction_factor)


def run(model, dt, n_max=100000):
    model.start_crosshead()
    out = []
    for _ in range(n_max):
        if not model.moving:
            break
        model.step(dt)
        st = model.state
        out.append((model.crosshead_mm, st.force_N, st.eps_p, st.eps_neck))
    return np.array(out)


@pytest.mark.parametrize("test", ["tension", "compression"])
def test_elastic_slope_is_series_stiffness_of_specimen_and_frame(test):
    # (compression without friction: the slab factor also multiplies the elastic force)
    m = RigModel("steel45", test, speed_mm_per_s=0.001, force_noise_N=0.0, frame_stiffness_N_per_um=136.0,
                 friction_mu=0.0)
    s, mat = m.specimen, m.material
    k_specimen = mat.E_MPa * s.area0_mm2 / s.length0_mm  # N/mm
    k_frame = 136.0e3
    k_series = 1.0 / (1.0 / k_specimen + 1.0 / k_frame)
    m.start_crosshead()
    m.step(2.0)  # 2 µm: far below yield
    assert m.state.eps_p == 0.0
    assert m.force_N / m.crosshead_mm == pytest.approx(k_series, rel=2e-3)


@pytest.mark.parametrize("material", ["steel45", "12Kh18N10T", "12Kh18N12M3TL"])
def test_uniform_tension_force_and_crosshead_follow_volume_constancy(material):
    m = RigModel(material, "tension", speed_mm_per_s=0.01, force_noise_N=0.0)
    rec = run(m, 20.0)
    mat, s = m.material, m.specimen
    rate = 0.01 / s.l0_mm
    uniform = (rec[:, 2] > 0.01) & (rec[:, 3] == rec[:, 2]) & (rec[:, 1] > 0)
    x, force, eps = rec[uniform, 0], rec[uniform, 1], rec[uniform, 2]
    sigma = mat.flow_stress(eps, rate, 20.0)
    np.testing.assert_allclose(force, sigma * s.area0_mm2 * np.exp(-eps), rtol=1e-9)
    # crosshead = gauge elongation (plastic + elastic true strain) + frame deflection
    expected_x = s.l0_mm * (np.exp(eps + sigma / mat.E_MPa) - 1) + force / 136e3
    np.testing.assert_allclose(x, expected_x, rtol=1e-6)


@pytest.mark.parametrize("response", ["fe", "bridgman"])
@pytest.mark.parametrize("material", ["steel45", "12Kh18N10T"])
def test_force_maximum_at_considere_point(material, response):
    m = RigModel(material, "tension", speed_mm_per_s=0.01, force_noise_N=0.0, tension_response=response)
    mat = m.material
    rate = 0.01 / m.specimen.l0_mm
    # Considère dσ/dε = σ solved independently with a finite-difference slope.
    h = 1e-6
    g = lambda e: (mat.flow_stress(e + h, rate) - mat.flow_stress(e - h, rate)) / (2 * h) - mat.flow_stress(e, rate)
    eps_u = brentq(g, 1e-4, 2.0)
    rec = run(m, 2.0)
    i = int(np.argmax(rec[:, 1]))
    assert rec[i, 2] == pytest.approx(eps_u, abs=2e-3)
    f_max = mat.flow_stress(eps_u, rate) * m.specimen.area0_mm2 * math.exp(-eps_u)
    if response == "bridgman":  # Le Roy's smooth onset: the neck carries the Considère force at first
        assert rec[i, 1] == pytest.approx(f_max, rel=1e-5)
    else:  # the FE neck curves a little at once: its maximum comes just past Considère, as in the
        # CalculiX runs (0.004–0.027 of neck strain later, forces 5e-5–2e-4 above, tests/rig/virtual/test_neck_response.py)
        assert rec[i, 3] - eps_u < 0.03 and 0.0 <= rec[i, 1] / f_max - 1.0 < 5e-4
    # after the maximum the force only falls, the neck strains, and the specimen breaks
    assert np.all(np.diff(rec[i:-1, 1]) <= 1e-9)
    assert rec[-1, 1] == 0.0 and m.fractured
    assert rec[i + 5:, 3].max() > rec[i + 5:, 2].max()


@pytest.mark.parametrize("material", ["steel45", "12Kh18N10T"])
def test_bridgman_with_the_measured_neck_radius_recovers_flow_stress_at_fracture(material):
    # the analytic mirror, kept as an option: Bridgman's factor with Le Roy's a/R
    m = RigModel(material, "tension", speed_mm_per_s=0.01, force_noise_N=0.0, tension_response="bridgman")
    rec = run(m, 0.5)
    post = {k: float(v) for k, v in m.post_test_measurements().items()}
    p_k = rec[rec[:, 1] > 0, 1][-1]  # last force before the break
    a = post["post.dk_mm"] / 2
    s_avg = p_k / (math.pi * a * a)
    x = a / post["post.neck_radius_mm"]
    s_eq = s_avg / ((1 + 2 / x) * math.log(1 + x / 2))  # Bridgman, docs/methods.md §3
    eps_f = 2 * math.log(m.specimen.d0_mm / post["post.dk_mm"])
    assert s_eq == pytest.approx(m.material.flow_stress(eps_f, 0.01 / 30), rel=5e-3)


@pytest.mark.parametrize("response", ["fe", "bridgman"])
def test_fracture_post_measurements_are_consistent(response):
    m = RigModel("12Kh18N10T", "tension", speed_mm_per_s=0.02, force_noise_N=0.0, tension_response=response)
    run(m, 10.0)
    post = {k: float(v) for k, v in m.post_test_measurements().items()}
    d0, l0 = m.specimen.d0_mm, m.specimen.l0_mm
    # true fracture strain ln(F0/Fk) equals the material's fracture strain (3.13)
    assert 2 * math.log(d0 / post["post.dk_mm"]) == pytest.approx(m.material.fracture_strain_at(0.02 / l0), rel=1e-3)
    eps_u = 2 * math.log(d0 / post["post.du_mm"])
    assert eps_u == pytest.approx(m.state.eps_p, rel=1e-3)
    a_over_R = (post["post.dk_mm"] / 2) / post["post.neck_radius_mm"]
    eps_f = 2 * math.log(d0 / post["post.dk_mm"])
    d = eps_f - eps_u
    if response == "bridgman":  # Le Roy a/R = 1.1 (eps_f - eps_u), with the model's smooth onset δ/(δ + eps_u)
        assert a_over_R == pytest.approx(1.1 * d * d / (d + eps_u), rel=2e-3)
    else:  # a curved neck, blunter than Le Roy's (tests/rig/virtual/test_neck_response.py has the FE's values)
        assert 0.05 < a_over_R < 1.1 * d
    assert l0 * math.exp(eps_u) < post["post.lu_mm"] < l0 * math.exp(eps_f)
    assert not m.moving  # the crosshead stopped at fracture


@pytest.mark.parametrize("response", ["fe", "bridgman"])
def test_a_parallel_length_longer_than_l0_stretches_the_crosshead_not_the_gauge_marks(response):
    # Lc = l0 + 2·d0 at the same rate v/Lc (ISO 6892-1's ė over Lc) as a bar of Lc = l0: the same
    # flow, neck and fracture; the crosshead sees Lc's uniform strain, Lu the gauge marks' (the neck within them)
    runs = {}
    for lc in (None, 42.0):
        s = Specimen.tension(6.0, 30.0, parallel_length_mm=lc)
        m = RigModel("12Kh18N10T", "tension", s, speed_mm_per_s=s.parallel_mm * 5e-4, force_noise_N=0.0, tension_response=response)
        runs[lc] = (m, run(m, 4.0))
    (m30, r30), (m42, r42) = runs[None], runs[42.0]
    assert m42.nominal_strain_rate_per_s == pytest.approx(5e-4, rel=1e-12)
    mat = m42.material
    uniform = (r42[:, 2] > 0.01) & (r42[:, 3] == r42[:, 2]) & (r42[:, 1] > 0)
    eps, force = r42[uniform, 2], r42[uniform, 1]
    sigma = mat.flow_stress(eps, 5e-4, 20.0)
    np.testing.assert_allclose(r42[uniform, 0], 42.0 * np.expm1(eps + sigma / mat.E_MPa) + force / 136e3, rtol=1e-6)
    assert m42.state.eps_p == pytest.approx(m30.state.eps_p, rel=1e-9) and m42.fractured and m30.fractured
    lu30, lu42 = (float(m.post_test_measurements()["post.lu_mm"]) for m in (m30, m42))
    assert lu42 == pytest.approx(lu30, abs=1e-4)
    # unloaded, the parallel length is 12 mm of uniform strain longer than the gauge marks
    assert m42.state.elongation_mm - (lu42 - 30.0) == pytest.approx(12.0 * math.expm1(m42.state.eps_p), abs=1e-4)
    with pytest.raises(ConfigError, match="parallel_length_mm"):
        Specimen.tension(6.0, 30.0, parallel_length_mm=29.0)


def test_compression_without_friction_is_flow_stress_times_loaded_area():
    """μ = 0: F = σ·A, A the volume-constant area of the plastic strain widened by the elastic
    lateral strain νσ/E on each side (2νσ/E in area)."""
    m = RigModel("12Kh18N12M3TL", "compression", speed_mm_per_s=0.01, friction_mu=0.0, force_noise_N=0.0)
    rec = run(m, 10.0)
    s, mat = m.specimen, m.material
    plastic = rec[:, 2] > 0.01
    eps = rec[plastic, 2]
    h = s.h0_mm * np.exp(-eps)
    sigma = mat.flow_stress(eps, 0.01 / s.h0_mm)
    lat = mat.nu * sigma / mat.E_MPa  # e^{2·lat} by its series
    expected = sigma * s.area0_mm2 * s.h0_mm / h * (1.0 + 2.0 * lat + 2.0 * lat**2 + 4.0 / 3.0 * lat**3)
    np.testing.assert_allclose(rec[plastic, 1], expected, rtol=1e-9)
    assert rec[-1, 2] == pytest.approx(0.68, abs=1e-6)  # default stroke limit


def test_slab_factor_matches_integrated_coulomb_pressure():
    # Coulomb slab: p(r) = σ exp(2μ(R − r)/h); mean over the disc by numerical integration
    for mu, R, h in [(0.1, 4.2, 3.5), (0.3, 3.0, 6.98), (0.05, 5.0, 2.0)]:
        mean, _ = quad(lambda r: math.exp(2 * mu * (R - r) / h) * 2 * math.pi * r, 0, R)
        assert slab_friction_factor(2 * mu * R / h) == pytest.approx(mean / (math.pi * R * R), rel=1e-9)


@pytest.mark.parametrize("mu", [0.05, 0.1, 0.25])
def test_compression_force_uses_slab_factor_and_bulge_inverts_to_mu(mu):
    # the analytic mirror, kept as an option: slab force and the seed's (3.18) barrel
    m = RigModel("12Kh18N12M3TL", "compression", speed_mm_per_s=0.01, friction_mu=mu, force_noise_N=0.0,
                 compression_response="slab")
    run(m, 20.0)
    s, st = m.specimen, m.state
    eps = st.eps_p
    r = s.d0_mm / 2 * math.exp(eps / 2)
    h = s.h0_mm * math.exp(-eps)
    sigma = m.material.flow_stress(eps, 0.01 / s.h0_mm)
    c = 2 * mu * r / h
    r_loaded = r * math.exp(m.material.nu * sigma / m.material.E_MPa)  # the elastic lateral strain νσ/E
    assert st.force_N == pytest.approx(sigma * math.pi * r_loaded**2 * 2 * (math.exp(c) - c - 1) / c**2, rel=1e-9)
    post = {k: float(v) for k, v in m.post_test_measurements().items()}
    hk, dmax = post["post.hk_mm"], post["post.dmax_mm"]
    dn = s.d0_mm * math.sqrt(s.h0_mm / hk)  # (3.17)
    eps_p = -math.log(hk / s.h0_mm)  # (3.31)
    dR_h = (dmax - dn) / 2 / hk
    mu_back = (math.log(1 - dR_h * eps_p**-0.83 / 0.0683) / -26.7) ** (1 / 1.53)  # (3.19)
    assert mu_back == pytest.approx(mu, rel=2e-3)
    assert post["post.smax_mm2"] == pytest.approx(math.pi * dmax**2 / 4, rel=1e-4)


def test_furnace_reaches_steady_state_of_its_first_order_law():
    p = FurnaceParams()
    f = Furnace(p)
    f.set_heater(True)
    f.step(p.dead_time_s * 0.9)
    assert f.temperature_C == pytest.approx(p.ambient_C, abs=1e-9)  # dead time: nothing yet
    f.step(6000.0)
    theta = furnace_steady_state_C(p.heater_power_W, p.ambient_C, p.loss_W_per_K, p.loss_W_per_K2)
    # steady state of C dT/dt = P − (k1 + k2 θ) θ, solved by hand: k2 θ² + k1 θ = P
    assert (p.loss_W_per_K + p.loss_W_per_K2 * (theta - 20)) * (theta - 20) == pytest.approx(p.heater_power_W)
    assert f.temperature_C == pytest.approx(theta, abs=0.05)
    # near the steady state the relaxation is first order with τ = C / (k1 + 2 k2 θ)
    f.set_heater(False)
    f.step(p.dead_time_s)
    t_start = f.temperature_C
    tau = p.heat_capacity_J_per_K / (p.loss_W_per_K + 2 * p.loss_W_per_K2 * (theta - 20))
    f.step(tau * 0.01)
    slope = (f.temperature_C - t_start) / (tau * 0.01)
    assert slope == pytest.approx(-p.heater_power_W / p.heat_capacity_J_per_K, rel=0.02)


def test_stuck_relay_heats_whatever_the_command():
    m = RigModel("steel45", "tension")
    m.furnace.set_relay_stuck(True)
    m.set_heater(False)
    m.step(60.0)
    assert m.temperature_C > 40.0


def test_temperature_softens_the_flow_stress_by_johnson_cook():
    mat = get_material("12Kh18N12M3TL")
    t_star = (600 - 20) / (mat.T_melt_C - 20)
    assert mat.flow_stress(0.1, 0.0, 600) / mat.flow_stress(0.1, 0.0, 20) == pytest.approx(1 - t_star**mat.m)
    assert mat.flow_stress(0.1, 1e-5) == mat.flow_stress(0.1, 1e-3)  # no rate effect below ε̇0


def test_noise_is_deterministic_given_the_seed_and_encoder_quantised():
    a, b = (RigModel("steel45", force_noise_N=5.0, seed=7) for _ in range(2))
    na = [a.measured_force_N() for _ in range(200)]
    nb = [b.measured_force_N() for _ in range(200)]
    assert na == nb and 3.5 < np.std(na) < 6.5
    a.crosshead_mm = 1.23456
    assert a.encoder_counts() == 123


def test_loading_temperature_is_the_furnaces_while_the_crosshead_moved():
    """The truth a virtual run is judged against: the furnace's temperature while loading, not after
    the test (an 850 C compression judged at the 802 C the furnace had cooled to by the stop read 9 %
    off the virtual material)."""
    m = RigModel("12Kh18N10T", "compression", speed_mm_per_s=0.5, initial_temperature_C=850.0)
    m.step(10.0)  # heater off: the furnace cools from the start
    m.start_crosshead()
    seen = []
    for _ in range(50):
        m.step(0.1)
        seen.append(m.temperature_C)  # the temperature the step's flow stress was made at
    m.stop_crosshead()
    m.step(60.0)
    assert m.temperature_C < min(seen) - 5.0
    assert m.loading_temperature_C == pytest.approx(np.mean(seen), abs=0.05)

"""Compression identification on synthetic records made from a known flow curve and friction.

The records come from ``conftest.make_compression`` (fixtures ``seed_like_record`` and
``make_record``): a known Johnson–Cook law and μ, Coulomb friction integrated numerically,
136 N/µm frame, 10 µm encoder steps, 50 N force noise, unloading branch, hk and dmax.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flowcurve.record.format import Record
from flowcurve.errors import FlowcurveError, IdentificationError, RecordError
from flowcurve.identification.compression.identify import identify_compression
from flowcurve.identification.compression.values import loading_branch_end, offset_yield

E_HANDBOOK = 194_000.0
# the synthetic records make their bulge with the seed's (3.18): they test the seed's method (3.19),
# not the default CalculiX table (tests/fe checks that on CalculiX records)
SEED_METHOD = "bulge_regression"


def law_stress(eps_p, law):
    return law["A"] + law["B"] * np.clip(eps_p, 0, None) ** law["n"]


def binned_deviation(eps_p, stress, law, lo=0.02, width=0.04):
    """Relative deviation of the bin means of the curve from the law, bins of ``width`` in strain."""
    edges = np.arange(lo, eps_p.max() + width, width)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (eps_p >= a) & (eps_p < b)
        if sel.sum() >= 5:
            out.append(np.mean(stress[sel]) / np.mean(law_stress(eps_p[sel], law)) - 1)
    return np.array(out)


@pytest.fixture(scope="module")
def seed_like_results(seed_like_record):
    record, truth = seed_like_record
    return truth, {c: identify_compression(record, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD, friction_correction=c) for c in ("k_sigma", "siebel", "slab")}


def test_friction_recovered_from_the_post_test_shape(seed_like_results):
    truth, results = seed_like_results
    res = results["slab"].result
    assert res["friction_mu"] == pytest.approx(truth["mu"], abs=1e-3)  # hk/dmax rounded to 0.1 µm
    assert res["friction"]["bulge_regression"] == res["friction_mu"]
    assert set(res["friction"]) == {"fe_table", "bulge_regression", "ebrahimi_najafizadeh"}
    assert res["friction_details"]["bulge_regression"]["inputs"]["hk_mm"] == pytest.approx(truth["hk"], abs=1e-4)


def test_slab_correction_recovers_the_flow_curve_within_1pct(seed_like_results):
    truth, results = seed_like_results
    law = truth["law"]
    ident = results["slab"]
    curve = ident.curves["true_slab"]
    eps, sig = curve["true_plastic_strain"].to_numpy(), curve["true_stress_MPa"].to_numpy()
    assert eps.max() == pytest.approx(truth["eps_p_end"], abs=0.005)
    dev = binned_deviation(eps, sig, law)
    assert dev.size >= 10
    assert np.max(np.abs(dev)) < 0.01, dev
    # the fitted law, over the whole fitted range from 0.2 % plastic strain to the end
    h = ident.result["hardening"]
    assert h["correction"] == "slab" and h["law"] == "johnson_cook"
    grid = np.linspace(0.002, truth["eps_p_end"], 400)
    fitted = h["A_MPa"] + h["B_MPa"] * grid ** h["n"]
    assert np.max(np.abs(fitted / law_stress(grid, law) - 1)) < 0.01
    assert h["A_MPa"] == pytest.approx(law["A"], rel=0.03)
    assert h["B_MPa"] == pytest.approx(law["B"], rel=0.02)
    assert h["n"] == pytest.approx(law["n"], rel=0.02)


def test_deviation_of_every_correction_is_reported(seed_like_results, capsys):
    truth, results = seed_like_results
    law = truth["law"]
    rows = {}
    for name in ("k_sigma", "siebel", "slab"):
        curve = results["slab"].curves[f"true_{name}"]
        dev = binned_deviation(curve["true_plastic_strain"].to_numpy(), curve["true_stress_MPa"].to_numpy(), law)
        h = results[name].result["hardening"]
        rows[name] = (100 * np.max(np.abs(dev)), 100 * dev[-1], h["A_MPa"], h["B_MPa"], h["n"])
    with capsys.disabled():
        print("\n  correction  max|dev| %  dev at end %   A_MPa    B_MPa     n   (truth 105 / 1392 / 0.642, mu 0.11, slab forward model)")
        for name, r in rows.items():
            print(f"  {name:9s}   {r[0]:8.2f}    {r[1]:8.2f}    {r[2]:7.1f}  {r[3]:7.1f}  {r[4]:.3f}")
    # Siebel drops the c²/12 term of the slab factor: at the end it reads higher by ≈ c²/12
    slab = results["slab"]
    h_end = slab.curves["nominal"]["height_mm"].iloc[-1]
    r_end = 5.989 / 2 * math.sqrt(6.982 / h_end)
    c_end = 2 * slab.result["friction_mu"] * r_end / h_end
    assert rows["siebel"][1] - rows["slab"][1] == pytest.approx(100 * c_end**2 / 12, rel=0.1)
    assert rows["slab"][0] < 1.0


def test_without_friction_all_corrections_agree_and_recover_the_law(make_record):
    record, truth = make_record(mu=0.0, noise_N=20.0, seed=3)
    ident = identify_compression(record, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD)
    assert ident.result["friction_mu"] == pytest.approx(0.0, abs=1e-3)
    curves = [ident.curves[f"true_{c}"] for c in ("k_sigma", "siebel", "slab")]
    for c in curves[1:]:
        np.testing.assert_allclose(c["true_stress_MPa"], curves[0]["true_stress_MPa"], rtol=2e-3)
    eps, sig = curves[0]["true_plastic_strain"].to_numpy(), curves[0]["true_stress_MPa"].to_numpy()
    assert np.max(np.abs(binned_deviation(eps, sig, truth["law"]))) < 0.01


def test_the_fe_table_curve_is_on_the_loaded_area(make_record):
    """The FE table's factor is relative to a μ = 0 run on the loaded area A·J, J = exp(−(1 − 2ν)σ/E):
    an incompressible specimen (ν → 0.5) reads the volume-constant area, ν = 0 the most shrunk."""
    curves = {}
    for nu in ("0.4999999", "0"):
        record, _ = make_record(mu=0.0, noise_N=20.0, seed=3, meta_extra={"material.nu": nu})
        ident = identify_compression(record, E_MPa=E_HANDBOOK)
        assert f"nu {float(nu):g} (record (material.nu))" in ident.result["methods"]["elastic_volume"]
        curves[nu] = ident.curves["true_fe_table"]["true_stress_MPa"].to_numpy()
    incompressible, shrunk = curves["0.4999999"], curves["0"]
    np.testing.assert_allclose(shrunk / incompressible, np.exp(incompressible / E_HANDBOOK), rtol=2e-5)


def test_other_law_and_friction(make_record):
    # a different material and a higher friction: steel 45 of table 3.2, μ = 0.2
    law = {"A": 410.0, "B": 280.0, "n": 0.47}
    record, truth = make_record(mu=0.2, law=law, hk_target=4.2, seed=5)
    ident = identify_compression(record, E_MPa=210_000.0, friction_method=SEED_METHOD, friction_correction="slab")
    assert ident.result["friction_mu"] == pytest.approx(0.2, abs=2e-3)
    c = ident.curves["true_slab"]
    dev = binned_deviation(c["true_plastic_strain"].to_numpy(), c["true_stress_MPa"].to_numpy(), law)
    assert np.max(np.abs(dev)) < 0.01


def test_largest_area_gives_the_same_friction(make_record):
    record, truth = make_record()
    by_d = identify_compression(record, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD).result["friction_mu"]
    meta = dict(record.meta)
    dmax = float(meta.pop("post.dmax_mm"))
    meta["post.smax_mm2"] = repr(math.pi * dmax**2 / 4)
    by_s = identify_compression(Record(meta=meta, data=record.data, source="s"), E_MPa=E_HANDBOOK, friction_method=SEED_METHOD).result["friction_mu"]
    assert by_s == pytest.approx(by_d, rel=1e-9)


def test_friction_method_option_selects_the_value(seed_like_record):
    record, _ = seed_like_record
    res = identify_compression(record, E_MPa=E_HANDBOOK, friction_method="ebrahimi_najafizadeh").result
    assert res["friction_method"] == "ebrahimi_najafizadeh"
    assert res["friction_mu"] == res["friction"]["ebrahimi_najafizadeh"]
    m = res["friction_details"]["ebrahimi_najafizadeh"]["m"]
    assert res["friction_mu"] == pytest.approx(m / math.sqrt(3))


def test_sign_convention_does_not_matter(make_record):
    record, _ = make_record(seed=7)
    flipped = Record(meta=record.meta, data=record.data.assign(force_N=-record.data["force_N"], crosshead_mm=-record.data["crosshead_mm"]), source="f")
    a = identify_compression(record, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD).result["hardening"]
    b = identify_compression(flipped, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD).result["hardening"]
    assert a["A_MPa"] == pytest.approx(b["A_MPa"]) and a["n"] == pytest.approx(b["n"])


def test_scaling_factor_near_one_with_the_frame_compliance_removed(seed_like_results):
    _, results = seed_like_results
    ind = results["slab"].result["indicator"]
    assert ind["frame_stiffness_N_per_um"] == 136.0
    assert ind["K_l"] == pytest.approx(1.0, abs=0.005)


def test_missing_stiffness_is_absorbed_by_the_scaling_with_a_warning(make_record):
    record, _ = make_record(drop=("rig.frame_stiffness_N_per_um",))
    res = identify_compression(record, E_MPa=E_HANDBOOK, friction_method=SEED_METHOD).result
    assert any("frame stiffness" in w for w in res["warnings"])
    # the crosshead travel includes the frame: K_l < 1 by about the frame travel at peak load
    frame_mm = res["max_force_N"] / 136e3
    assert res["indicator"]["K_l"] == pytest.approx(1 - frame_mm / (frame_mm + 3.45), abs=0.01)


def test_loading_branch_end_picks_the_last_loaded_sample():
    travel = np.array([0, 1, 2, 3, 3, 3, 2.6, 2.1])
    force = np.array([0, 10, 20, 30, 31, 29.5, 5, 0])
    assert loading_branch_end(travel, force) == 4


def test_offset_yield_by_hand():
    eps_p = np.array([0.0, 0.001, 0.0015, 0.0025, 0.004])
    stress = np.array([50.0, 90.0, 100.0, 120.0, 130.0])
    assert offset_yield(eps_p, stress) == pytest.approx(110.0)


# -- bad input: one clear line naming the key ------------------------------------------------


@pytest.mark.parametrize("key", ["specimen.h0_mm", "specimen.d0_mm", "post.hk_mm"])
def test_missing_geometry_names_the_key(make_record, key):
    record, _ = make_record(drop=(key,))
    with pytest.raises(RecordError) as exc:
        identify_compression(record)
    assert key in str(exc.value) and "\n" not in str(exc.value)


def test_missing_bulge_names_both_keys(make_record):
    record, _ = make_record(drop=("post.dmax_mm",))
    with pytest.raises(RecordError) as exc:
        identify_compression(record)
    msg = str(exc.value)
    assert "post.dmax_mm" in msg and "post.smax_mm2" in msg and "\n" not in msg


@pytest.mark.parametrize(
    "meta, words",
    [
        ({"post.hk_mm": "7.5"}, "must be below"),
        ({"post.dmax_mm": "9.9"}, "logarithm argument"),
        ({"post.dmax_mm": "7.9"}, "negative bulge"),
        ({"post.dmax_mm": "abc"}, "not a number"),
        ({"material.nu": "0.6"}, "Poisson's ratio"),
    ],
)
def test_out_of_range_post_measurements(make_record, meta, words):
    record, _ = make_record(meta_extra=meta)
    with pytest.raises(FlowcurveError) as exc:
        identify_compression(record, friction_method=SEED_METHOD)
    assert words in str(exc.value) and "\n" not in str(exc.value)


def test_unknown_options_are_clear(seed_like_record):
    record, _ = seed_like_record
    with pytest.raises(IdentificationError, match="choose from"):
        identify_compression(record, friction_method="guess")
    with pytest.raises(IdentificationError, match="choose from"):
        identify_compression(record, friction_correction="bridgman")

"""(3.1) on a broken tension specimen against the virtual rig, whose Lu is the pieces' plastic length
(its uniform plastic strain and neck, not a recovery formula): the seed's K_l = (Lu − L0)/max Δl set
the loaded elongation at the break (and the frame's give-back recorded after it) against the
unloaded Lu, K_l 0.975 and the plastic strain 1.7 % short on 12Kh18N10T (steel 45: 0.969, 2.5 %,
beyond the stated U); like with like K_l is 1 within 0.2 % and the stated U holds the strain."""

import numpy as np
import pytest

from flowcurve.acquisition.session import run_virtual_test
from flowcurve.clock import ModelClock
from flowcurve.demo import demo_specs
from flowcurve.identification.quality.assurance import attach
from flowcurve.identification.tension.identify import identify_tension
from flowcurve.record.format import Record, read_record


@pytest.fixture(scope="module")
def rig_record(tmp_path_factory):
    spec = next(s for s in demo_specs("12Kh18N10T") if s.test == "tension")
    path = tmp_path_factory.mktemp("kl") / "12Kh18N10T-tension.csv"
    run_virtual_test(spec, path, material="12Kh18N10T", time_scale=15.0, clock=ModelClock(), link="inprocess")
    return read_record(path)


def rig_plastic_elongation(rec: Record, i_m: int) -> np.ndarray:
    """The rig's engineering plastic strain to Fm: its specimen elongation crosshead − F/C (the
    rig's frame is exactly that), e = expm1(εp + σ_t/E), σ_t = F·e^εp/S0 (its convention), solved for εp."""
    f, c = rec.data["force_N"].to_numpy()[: i_m + 1], rec.data["crosshead_mm"].to_numpy()[: i_m + 1]
    e = (c - f / (1000.0 * float(rec.meta["rig.frame_stiffness_N_per_um"]))) / float(rec.meta["specimen.l0_mm"])
    s0, E = np.pi * float(rec.meta["specimen.d0_mm"]) ** 2 / 4.0, float(rec.meta["material.E_MPa"])
    eps_p = np.log1p(e)
    for _ in range(4):
        eps_p = np.log1p(e) - f / s0 * np.exp(eps_p) / E
    return np.expm1(eps_p)


@pytest.mark.parametrize("drop", [(), ("rig.frame_stiffness_N_per_um",), ("material.E_MPa",)])
def test_scale_meets_the_rigs_plastic_elongation(rig_record, drop):
    meta = {k: v for k, v in rig_record.meta.items() if k not in drop}
    rec = Record(meta=meta, data=rig_record.data, source="12Kh18N10T virtual")
    ident = identify_tension(rec)
    r = ident.result
    attach(r, ident.curves, rec)
    assert r["methods"]["scale_factor_Kl"] == pytest.approx(1.0, abs=2e-3)  # the seed's: 0.9747
    i_m = int(np.argmax(rig_record.data["force_N"].to_numpy()))
    truth = rig_plastic_elongation(rig_record, i_m)
    eng = ident.curves["engineering"]
    strain = eng[[k for k in eng.columns if "strain" in k][0]].to_numpy()[: i_m + 1]
    force, s0 = rec.data["force_N"].to_numpy()[: i_m + 1], np.pi * float(rec.meta["specimen.d0_mm"]) ** 2 / 4.0
    plastic = strain - force / s0 / r["E_MPa"]  # e − σ_e/E of the line (the frame's slope in it where it stays in)
    err = float(np.median(plastic[truth > 0.02] / truth[truth > 0.02] - 1.0))
    assert abs(err) < 0.012  # the seed's: −1.65 %
    assert abs(err) <= 2.0 * r["uncertainty"]["strain_scale"]["u_rel"]

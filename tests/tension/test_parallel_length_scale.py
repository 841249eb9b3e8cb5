"""(3.1) with a parallel length Lc ≠ L0 against the virtual rig's physics (rig/virtual/physics.py,
driven here sample by sample without the session: a few seconds a record), whose crosshead
stretches Lc uniformly and whose neck and gauge marks lie within L0: Lu is what a caliper reads on
the unloaded pieces, l0·e^εu plus the neck's plastic length. Lc = L0 (reference), L0 + 2·d0 (ISO
6892-1's usual proportional bar) and 1.5·L0, each at ė = v/Lc = 2.5e-4 /s (one flow curve for all).
The truth is the rig's material: its flow law, its Considère strain, its pieces' Lu; the scale
(3.1) should find is 1 (the crosshead less F/C is exactly the specimen's Lc elongation). With
post.du_mm the uniform elongation a_u is the pieces'; without it, the diagram's at Fm (before it
was the argmax sample less F·L/(E·S0): a_u +0.009 and K_l 1.0064 at Lc = 42 mm, 1.0077 at 45 mm; the
flat maximum's mid-point less the same F·L(1 + a)²/(E·S0) as at the break: −0.001, 0.9994 / 0.9989)."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

from flowcurve.identification.quality.assurance import attach
from flowcurve.identification.tension.identify import identify_tension
from flowcurve.record.format import Record
from flowcurve.rig.virtual.physics import RigModel, Specimen

D0_MM, L0_MM, RATE_PER_S, HZ, FRAME_N_PER_UM = 6.0, 30.0, 2.5e-4, 4.0, 136.0
PARALLEL_MM = (None, L0_MM + 2.0 * D0_MM, 1.5 * L0_MM)
FLOW_AT = (0.02, 0.05, 0.1, 0.2, 0.3)  # true plastic strains on the uniform curve (the rig's εu is 0.311)


def rig_record(parallel_mm):
    """A crosshead-only record of the rig's 12Kh18N10T bar (3 N force noise, 1 µm counts, 4 Hz),
    broken, with the operator's post.* measurements, and the rig model that made it."""
    spec = Specimen.tension(D0_MM, L0_MM, parallel_length_mm=parallel_mm)
    v = RATE_PER_S * spec.parallel_mm
    m = RigModel("12Kh18N10T", "tension", spec, speed_mm_per_s=v, frame_stiffness_N_per_um=FRAME_N_PER_UM,
                 force_noise_N=3.0, counts_per_mm=1000.0, seed=1)
    m.start_crosshead()
    rows, after = [], 0
    while after < 5:  # five samples past the break, the crosshead running on
        m.step(1.0 / HZ)
        rows.append((m.time_s, m.measured_force_N(), m.encoder_counts() / 1000.0))
        if m.fractured:
            after += 1
            m.crosshead_mm += v / HZ
    meta = {"test": "tension", "material": "12Kh18N10T", "specimen.d0_mm": f"{D0_MM:g}", "specimen.l0_mm": f"{L0_MM:g}",
            "rig.frame_stiffness_N_per_um": f"{FRAME_N_PER_UM:g}", "material.E_MPa": f"{m.material.E_MPa:g}",
            "crosshead_speed_mm_per_s": f"{v:g}", "nominal_temperature_C": "20", **m.post_test_measurements()}
    if parallel_mm is not None:
        meta["specimen.parallel_length_mm"] = f"{parallel_mm:g}"
    data = pd.DataFrame(rows, columns=["time_s", "force_N", "crosshead_mm"])
    return Record(meta=meta, data=data, source=f"rig Lc {spec.parallel_mm:g} mm"), m


def rig_truth(m) -> dict:
    """The rig's own values: Rp0.2, Rm, Ag on its uniform curve (e = exp(εp + σ/E) − 1, s = σ·e^−εp,
    its convention), A from the pieces' plastic length, the flow law and its slope."""
    mech, E = m.mechanics, m.material.E_MPa
    eng = lambda ep: (math.expm1(ep + mech.flow(ep) / E), mech.flow(ep) * math.exp(-ep))  # noqa: E731
    ep02 = brentq(lambda ep: eng(ep)[0] - eng(ep)[1] / E - 0.002, 1e-9, 0.1)  # offset 0.2 % plastic
    e_m, s_m = eng(mech.considere_strain())
    st = mech.state
    lu = L0_MM * math.exp(st.eps_p) + mech.neck_extension_mm(st.eps_p, st.eps_neck)
    slope = lambda ep: float(m.material.hardening_slope(ep, mech.strain_rate_per_s, mech.temperature_C))  # noqa: E731
    return {"Rp02_MPa": eng(ep02)[1], "Rm_MPa": s_m, "Ag_pct": 100.0 * (e_m - s_m / E), "A_pct": 100.0 * (lu - L0_MM) / L0_MM,
            "flow": mech.flow, "slope": slope}


@pytest.fixture(scope="module")
def records():
    return {lc: rig_record(lc) for lc in PARALLEL_MM}


def identified(rec: Record, drop=()):
    rec = Record(meta={k: v for k, v in rec.meta.items() if k not in drop}, data=rec.data, source=rec.source)
    ident = identify_tension(rec)
    attach(ident.result, ident.curves, rec)
    return ident


def flow_at(ident, at) -> np.ndarray:
    """The identified true stress at true plastic strains ``at`` on the uniform curve (to Fm)."""
    true = ident.curves["true"]
    i_m = int(np.argmax(ident.curves["engineering"]["engineering_stress_MPa"].to_numpy()))
    return np.interp(at, true["true_plastic_strain"].to_numpy()[: i_m + 1], true["true_stress_MPa"].to_numpy()[: i_m + 1])


def flow_U(r: dict, sigma, slope, at) -> np.ndarray:
    """U (k = 2) of a flow point, composed from the stated budgets (tension states none of its own):
    the stress scale's relative u (Rm's: force, d0) and the strain scale's u_rel through σ_t = s(1 + e)
    and the slope θ, δσ ≈ (θ + σ)·εp·u_rel."""
    u = r["uncertainty"]
    rel_s = u["Rm_MPa"]["u"] / u["Rm_MPa"]["value"]
    return 2.0 * np.hypot(sigma * rel_s, (slope + sigma) * np.asarray(at) * u["strain_scale"]["u_rel"])


@pytest.mark.parametrize("drop", [(), ("post.du_mm",), ("post.du_mm", "rig.frame_stiffness_N_per_um")])
@pytest.mark.parametrize("parallel_mm", PARALLEL_MM)
def test_scale_and_results_meet_the_rig_with_a_parallel_length(records, parallel_mm, drop):
    rec, m = records[parallel_mm]
    truth = rig_truth(m)
    ident = identified(rec, drop)
    r = ident.result
    u = r["uncertainty"]
    terms = r["methods"]["scale_Kl"]
    assert terms["length_mm"] == pytest.approx(m.specimen.parallel_mm)  # the strain refers to Lc
    K_l = r["methods"]["scale_factor_Kl"]
    assert abs(K_l - 1.0) <= 2.0 * u["strain_scale"]["u_rel"]
    assert K_l == pytest.approx(1.0, abs=1e-3 if not drop else 3e-3)  # without du, before: 1.0053 at Lc 42 mm
    a_true = math.expm1(m.state.eps_p)
    assert terms["uniform_plastic_elongation"] == pytest.approx(a_true, abs=1e-4 if not drop else 5e-3)
    for key in ("Rp02_MPa", "Rm_MPa", "Ag_pct", "A_pct"):
        assert abs(r[key] - truth[key]) <= u[key]["U"], key
    at = np.array(FLOW_AT)
    sigma = np.array([truth["flow"](x) for x in at])
    slope = np.array([truth["slope"](x) for x in at])
    err = flow_at(ident, at) - sigma
    assert np.all(np.abs(err) <= flow_U(r, sigma, slope, at)), err
    assert np.all(np.abs(err / sigma) < 0.008)  # the rig's convention σ·e^(σ/E): +0.2–0.6 %


def test_a_parallel_length_agrees_with_the_bar_of_lc_l0(records):
    """The same material at the same rate: Lc > L0 and Lc = L0 read the same, within their U."""
    ref = identified(records[None][0])
    at = np.array(FLOW_AT)
    for lc in PARALLEL_MM[1:]:
        ident = identified(records[lc][0])
        r, q = ident.result, ref.result
        for key in ("Rp02_MPa", "Rm_MPa", "Ag_pct", "A_pct"):
            assert abs(r[key] - q[key]) <= math.hypot(r["uncertainty"][key]["U"], q["uncertainty"][key]["U"]), key
        s, s_ref = flow_at(ident, at), flow_at(ref, at)
        assert np.all(np.abs(s / s_ref - 1.0) < 2e-3)


@pytest.mark.parametrize("parallel_mm", PARALLEL_MM[1:])
def test_at_and_a_from_the_curve_refer_to_the_gauge_marks(records, parallel_mm):
    """At (and A without post.lu_mm) are the gauge marks' extensions (ISO 6892-1 3.4.3, 3.4.2), not the
    crosshead's over Lc, and A states a U: the bar of Lc > L0 reads what the bar of Lc = L0 reads, whose crosshead strain is the
    marks' own, and A the pieces' within half a point (before: over Lc, At 43.6 / 43.2 % and A 43.2 / 42.8 % for
    the pieces' 45.4 % at Lc 42 / 45 mm)."""
    drop = ("post.lu_mm",)
    ref = identified(records[None][0], drop).result
    r = identified(records[parallel_mm][0], drop).result
    assert r["At_pct"] == pytest.approx(ref["At_pct"], abs=0.05)
    assert r["A_pct"] == pytest.approx(ref["A_pct"], abs=0.05)
    assert abs(r["A_pct"] - rig_truth(records[parallel_mm][1])["A_pct"]) < 0.5
    assert abs(r["A_pct"] - rig_truth(records[parallel_mm][1])["A_pct"]) <= r["uncertainty"]["A_pct"]["U"]  # before: no U at all
    assert "over L0" in r["A_method"]


@pytest.mark.parametrize("lu", [True, False])
def test_an_unstated_parallel_length_is_in_the_strain_scale(records, lu):
    """The bar of Lc = 42 mm without specimen.parallel_length_mm: its crosshead strain is taken over l0 (too short) and
    read high. Before, value ± U missed (with post.lu_mm: Ag 38.8 ± 1.6 % for 36.9; without: Ag 51.5 ± 2.2, A 60.5 ± 1.4
    for 45.4); the strain scale now holds L up to L0 + 2·d0 (ISO 6892-1's Lc in dispute), and the record is warned."""
    rec, m = records[L0_MM + 2.0 * D0_MM]
    truth = rig_truth(m)
    r = identified(rec, ("specimen.parallel_length_mm",) + (() if lu else ("post.lu_mm",))).result
    assert r["methods"]["strain_length_stated"] is False and r["methods"]["strain_length_mm"] == L0_MM
    assert any("parallel length is not stated" in w for w in r["warnings"])
    for key in ("Rp02_MPa", "Ag_pct", "A_pct"):
        assert abs(r[key] - truth[key]) <= r["uncertainty"][key]["U"], (key, r[key], truth[key], r["uncertainty"][key]["U"])
    stated = identified(rec, () if lu else ("post.lu_mm",)).result
    assert stated["methods"]["strain_length_stated"] is True
    assert not any("parallel length is not stated" in w for w in stated["warnings"])
    assert r["uncertainty"]["strain_scale"]["u_rel"] > 2.0 * stated["uncertainty"]["strain_scale"]["u_rel"]

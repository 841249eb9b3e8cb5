"""A six-record compression series made with CalculiX, identified without a handbook E.

Six upsetting runs of one Johnson–Cook material at three temperatures and two strain rates
(the flow curve of each run is the law at that temperature and at the plastic strain rate the
series will read off the record's data, so the truth is exact), each made a 10 Hz record with
a seating toe, 10 µm encoder steps, force noise and frame compliance, and no ``material.E_MPa``.
``flowcurve fit`` of the six records (each identified by the default method, E from its own
elastic line) gave A = 0 with 709 % error before the elastic line, toe and hardening fits were
made robust (issue 10); now the fitted law is within 1 % of the input at every condition and A,
B, n, C, m within 3 %.
"""

from __future__ import annotations

import json
import math
import shutil
from functools import partial

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.identification.fe.synthetic import upsetting_record
from flowcurve.identification.laws.johnson_cook import johnson_cook
from flowcurve.record.format import write_record

pytestmark = [pytest.mark.slow, pytest.mark.solver, pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")]

TRUE = {"A": 350.0, "B": 600.0, "n": 0.35, "C": 0.02, "m": 1.0}
REF = {"ref_strain_rate_per_s": 0.002, "ref_temperature_C": 20.0, "melt_temperature_C": 1500.0}
D0, H0, EPS_END, MU, RATE_HZ = 6.0, 9.0, 0.7, 0.1, 10.0
CONDITIONS = [(T, rate, E) for T, E in ((20.0, 200_000.0), (300.0, 185_000.0), (600.0, 165_000.0)) for rate in (0.002, 0.02)]


def plastic_rate(nominal_rate: float) -> float:
    """The least-squares slope of ε = ln(h0/(h0 − v·t)) over the loading at v = rate·h0: the
    strain rate the series reads off a constant-speed upsetting record (the law is evaluated at it)."""
    v = nominal_rate * H0
    t = np.linspace(0.0, H0 * (1.0 - math.exp(-EPS_END)) / v, 2001)
    return float(np.polyfit(t, np.log(H0 / (H0 - v * t)), 1)[0])


def record_of(T: float, rate: float, E: float, seed: int):
    from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

    law = partial(johnson_cook, strain_rate_per_s=plastic_rate(rate), temperature_C=T, **TRUE, **REF)
    # a small first increment resolves the elastic line and the yield (1/70 of the stroke steps over both)
    model = UpsettingModel.from_law(D0, H0, H0 * math.exp(-EPS_END), MU, law, E_MPa=E, increments=70, first_increment=1.0 / 3000)
    record = upsetting_record(simulate_upsetting(model), speed_mm_per_s=rate * H0, rate_hz=RATE_HZ, seed=seed,
                              specimen_id=f"T{T:.0f}_r{rate:g}")
    record.meta["nominal_temperature_C"] = repr(T)
    del record.meta["material.E_MPa"]  # no handbook modulus: each record's own elastic line
    return record


@pytest.fixture(scope="module")
def series_fit(tmp_path_factory):
    """``flowcurve fit --strict`` of the six records (no handbook E): (exit code, fit.json, stderr)."""
    import contextlib
    import io

    tmp = tmp_path_factory.mktemp("fe_series")
    paths = [write_record(tmp / f"C{k}.csv", record_of(T, rate, E, seed=10 + k)) for k, (T, rate, E) in enumerate(CONDITIONS)]
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["fit", *map(str, paths), "--out", str(tmp / "fit"), "--strict", "--rate-per-record", "--ref-rate", str(REF["ref_strain_rate_per_s"]),
                     "--ref-temp", str(REF["ref_temperature_C"]), "--melt-temp", str(REF["melt_temperature_C"])])
    fit = json.loads((tmp / "fit" / "fit.json").read_text()) if code == 0 else {}
    return code, fit, err.getvalue()


def _constants(fit):
    return {"A": fit["A_MPa"], "B": fit["B_MPa"], "n": fit["n"], "C": fit["C"], "m": fit["m"]}


def test_six_fe_records_give_the_law_without_handbook_E(series_fit):
    """Each record's own (apparent) E for its strain split; the fitted law reproduces the input law within 1 % at every
    condition over ε_p 0.01–0.6, with B, C and m within 3 %, quality good."""
    code, fit, err = series_fit
    assert code == 0, err
    # the records' moduli are crosshead slopes: apparent, so fit.json hands on no E (the card asks for --E)
    assert fit["quality"] == "good" and fit["E_MPa"] is None and fit["E_MPa_source"].startswith("undetermined")
    got = _constants(fit)
    for key in ("B", "C", "m"):
        assert got[key] == pytest.approx(TRUE[key], rel=0.03), (key, got[key])
    eps = np.linspace(0.01, 0.6, 60)
    for T, rate, _ in CONDITIONS:
        fitted = johnson_cook(eps, plastic_rate(rate), T, **got, **REF)
        true = johnson_cook(eps, plastic_rate(rate), T, **TRUE, **REF)
        assert np.max(np.abs(fitted / true - 1.0)) < 0.01, (T, rate)


def test_six_fe_records_recover_A_and_n_within_3_percent(series_fit):
    """The last of the constants to come in: A 367 → 360.5 (+3.0 %) and n 0.374 → 0.364 (+4.0 %)
    as the encoder counts were re-read and the spring-back measured, then 354 and 0.358 once the
    FE table had its start (each curve had been 0.5–1.1 % high over ε_p 0.002–0.01)."""
    code, fit, err = series_fit
    assert code == 0, err
    got = _constants(fit)
    for key in ("A", "n"):
        assert got[key] == pytest.approx(TRUE[key], rel=0.03), (key, got[key])


def test_the_constants_the_curves_cannot_tell_apart_are_said_and_their_band_holds_the_truth(series_fit):
    """A and n correlate at 0.95: fit.json's shape_uncertainty (the move a 0.4 % RMS shape error
    of the curves can make, the error measured on these records) holds the true A, B and n, and a
    warning names A and n."""
    code, fit, err = series_fit
    assert code == 0, err
    band = fit["shape_uncertainty"]
    for key, name in (("A", "A_MPa"), ("B", "B_MPa"), ("n", "n")):
        assert abs(fit[name] - TRUE[key]) <= band[name], (key, fit[name], band[name])
    told = [w for w in fit["warnings"] if w.startswith("the curves do not tell")]
    assert told and "A by up to" in told[0] and "n by up to" in told[0], fit["warnings"]


def test_the_curve_starts_on_the_input_law():
    """The first record without a toe, noise, encoder counts or frame (E given): the true curve
    over ε_p 0.002–0.01 is off the input law by what it is off over 0.05–0.6 (the mesh's own
    −0.2 % and μ read 0.107 for 0.1), within 0.3 %. It was 1.1 % higher at the start while the
    FE table's factor below ε 0.02 was read between a padded 1 at ε 0 and its value at 0.02;
    the table's start (short runs on ε_p) holds the factor the friction has from the first yield."""
    from flowcurve.identification.compression.identify import identify_compression
    from flowcurve.identification.fe.model.upsetting import UpsettingModel, simulate_upsetting

    T, rate, E = CONDITIONS[0]
    law = partial(johnson_cook, strain_rate_per_s=plastic_rate(rate), temperature_C=T, **TRUE, **REF)
    model = UpsettingModel.from_law(D0, H0, H0 * math.exp(-EPS_END), MU, law, E_MPa=E, increments=70, first_increment=1.0 / 3000)
    record = upsetting_record(simulate_upsetting(model), speed_mm_per_s=rate * H0, rate_hz=RATE_HZ, toe_mm=0.0, noise_N=0.0,
                              step_mm=1e-7, stiffness_N_per_um=1e9)
    curve = identify_compression(record).true_curve
    eps, sigma = curve["true_plastic_strain"].to_numpy(), curve["true_stress_MPa"].to_numpy()
    off = sigma / law(eps) - 1.0
    start, rest = off[(eps >= 0.002) & (eps <= 0.01)], off[(eps >= 0.05) & (eps <= 0.6)]
    assert start.size >= 3 and abs(start.mean() - rest.mean()) < 0.003, (start.mean(), rest.mean())

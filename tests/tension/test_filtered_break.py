"""A break the load cell's low-pass filter spreads over several samples (issue 31's scenario
matrix: the virtual rig at 0.5 mm/s, 100 values/s and the amplifier's ASF2 filter in real time):
the fracture force is the force before the break, not the tail of the filter's decay."""

import math

import numpy as np
import pandas as pd
import pytest

from flowcurve.identification.laws.hardening import johnson_cook_static
from flowcurve.identification.identify import identify
from flowcurve.identification.tension.values import fracture_index
from flowcurve.record.format import Record

from .conftest import TRUTH, make_record

ALPHA_100HZ_ASF2 = 1.0 - math.exp(-2.0 * math.pi * 3.5 / 100.0)  # first-order 3.5 Hz lag, one 10 ms step


def with_filtered_break(record, steps=25):
    """The record run on past its break: the force decays to zero through a first-order filter
    (each sample keeps 1 − α of the last), the crosshead and extensometer stand."""
    data = record.data
    pk = float(data["force_N"].iloc[-1])
    tail = pk * (1.0 - ALPHA_100HZ_ASF2) ** np.arange(1, steps + 1)
    last = data.iloc[-1]
    step = float(data["time_s"].iloc[1] - data["time_s"].iloc[0])
    extra = pd.DataFrame({c: np.full(steps, float(last[c])) for c in data.columns})
    extra["time_s"] = float(last["time_s"]) + step * np.arange(1, steps + 1)
    extra["force_N"] = tail
    return Record(meta=dict(record.meta), data=pd.concat([data, extra], ignore_index=True), source=record.source)


def test_the_filtered_break_is_found_before_its_first_step():
    rec, info = make_record()
    n = len(rec.data)
    force = with_filtered_break(rec).data["force_N"].to_numpy()
    assert np.max(-np.diff(force)) < 0.2 * info["Fm_N"]  # no single step is a break by the 20 %-of-Fm rule
    assert fracture_index(force) == n - 1  # the last sample before the decay
    assert fracture_index(rec.data["force_N"].to_numpy()) == n - 1  # a record cut at the break: unchanged


def test_a_record_stopped_before_fracture_is_not_given_a_break():
    rec, _ = make_record()
    force = rec.data["force_N"].to_numpy()
    i_m = int(np.argmax(force))
    stopped = force[: i_m + 50]  # still necking at 0.9+ Fm: no fracture
    assert fracture_index(stopped) == stopped.size - 1


@pytest.mark.parametrize("extensometer", [True, False])
def test_identification_reads_the_fracture_point_through_a_filtered_break(extensometer):
    rec, info = make_record(extensometer=extensometer)
    res = identify(with_filtered_break(rec)).result
    s_k = math.pi / 4 * float(rec.meta["post.dk_mm"]) ** 2
    assert res["fracture_avg_stress_MPa"] == pytest.approx(info["Pk_N"] / s_k, rel=1e-9)
    truth = float(johnson_cook_static(TRUTH["eps_f"], TRUTH["A"], TRUTH["B"], TRUTH["n"]))  # the record was made to give it back
    assert res["neck_corrections"]["davidenkov"]["stress_MPa"] == pytest.approx(truth, rel=0.01)
    assert res["hardening"]["fracture_point"] == "included"


def test_a_fracture_point_no_law_passes_through_leaves_the_uniform_range_fit():
    # a fracture point far below the curve (a force read off a decay's tail): the fit with it
    # fails, the one without it stays and says so — the uniform range is not lost with it
    from flowcurve.identification.tension.identify import _fit_laws

    eps = np.linspace(0.002, 0.08, 40)
    sig = johnson_cook_static(eps, 400.0, 600.0, 0.3)
    fits, _, choices, warnings = _fit_laws(eps, sig, [(1.5, 5.0, 5.5)], None, "auto")
    jc = fits["least_squares_johnson_cook"]
    assert (jc.params["A"], jc.params["B"], jc.params["n"]) == pytest.approx((400.0, 600.0, 0.3), rel=1e-3)
    assert choices["johnson_cook"] == ("without", "excluded: the fit through the fracture point failed")
    assert any("johnson_cook fit with the fracture point failed" in w for w in warnings)

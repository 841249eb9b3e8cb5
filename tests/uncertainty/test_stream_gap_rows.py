"""The true curve's rows after a load-cell stream gap the acquisition could not tell latency or loss of
(identification/quality/stream_gap.py, true_curve.csv ``stream_gap_u_MPa``): the closed form of the row doubt, and a
synthetic tension (known truth: the same record without the fault) whose gap was latency, or was loss, named
undecided — each row's truth within σ_row ± 2·u, the rows before the gap at 0."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from flowcurve.identification.identify import identify
from flowcurve.identification.outcome import TRUE_CURVE_COLUMNS
from flowcurve.identification.quality import stream_gap
from flowcurve.record.format import Event
from tests.tension.conftest import TRUTH, make_record
from tests.uncertainty.test_stream_gap import UNDECIDED

AFTER_S, DOUBT_S = 20.0, 0.45  # the gap in the hardening's steep part; δ not a whole number of 0.1 s rows (the realignment interpolates)


def test_row_doubt_of_a_line_is_the_offset_and_nan_where_the_alternative_ends():
    """σ = 300 + 1000·x, σ_alt = σ + 7 from x = 0.05 and only up to x = 0.08: u = 0 before, 7 after, NaN past 0.08 (closed form)."""
    x = np.linspace(0.0, 0.1, 101)
    alt_x = x[x <= 0.08 + 1e-12]
    alt = 300.0 + 1000.0 * alt_x + np.where(alt_x >= 0.05 - 1e-12, 7.0, 0.0)
    u = stream_gap.row_doubt(x, 300.0 + 1000.0 * x, alt_x[::-1], alt[::-1])  # the alternative's order does not matter
    np.testing.assert_array_equal(u[x < 0.049], 0.0)
    np.testing.assert_allclose(u[(x > 0.0505) & (x <= 0.08)], 7.0, rtol=0, atol=1e-9)
    assert np.isnan(u[x > 0.0805]).all() and np.isfinite(u[x <= 0.08]).all()
    note = stream_gap.rows_note(x, u)
    assert note["rows_without_u"] == int((x > 0.0805).sum()) and "does not reach" in note["why_without_u"]
    assert note["from_plastic_strain"] == pytest.approx(0.05, abs=0.0011) and note["max_u_MPa"] == pytest.approx(7.0)


def _named(rec, *, latency: bool):
    """``rec`` with an undecided gap after AFTER_S named; its later forces a latency of DOUBT_S stamped as lost frames
    leaves (F_rec(t) = F(t − δ)) when ``latency``, as they were (the frames really were lost) when not."""
    data = rec.data.copy()
    if latency:
        t, f = data["time_s"].to_numpy(dtype=float), data["force_N"].to_numpy(dtype=float)
        data["force_N"] = np.where(t > AFTER_S, np.interp(t - DOUBT_S, t, f), f)  # F(t − δ)
    text = UNDECIDED.replace("21.104", f"{AFTER_S:.3f}").replace("10.000", f"{DOUBT_S:.3f}")
    return dataclasses.replace(rec, data=data, events=[*rec.events, Event(AFTER_S + DOUBT_S, "stream_gap_undecided", text)])


@pytest.fixture(scope="module")
def runs():
    rec, info = make_record()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {"free": identify(rec), "latency": identify(_named(rec, latency=True)), "loss": identify(_named(rec, latency=False)),
                "record": rec, "info": info}


def _gap_strain(rec) -> float:
    """The plastic strain the specimen had at the gap's time, from the record's extensometer and force (closed form,
    not the identification): εp = ln(1 + e) − σ_t/E, σ_t = F(1 + e)/S0."""
    t = rec.data["time_s"].to_numpy(dtype=float)
    e = float(np.interp(AFTER_S, t, rec.data["extensometer_mm"].to_numpy(dtype=float))) / TRUTH["l0_mm"]
    sig = float(np.interp(AFTER_S, t, rec.data["force_N"].to_numpy(dtype=float))) * (1 + e) / (math.pi * TRUTH["d0_mm"] ** 2 / 4)
    return math.log1p(e) - sig / TRUTH["E_MPa"]


def test_a_record_without_a_gap_keeps_its_columns(runs):
    assert list(runs["free"].true_curve.columns) == list(TRUE_CURVE_COLUMNS)
    assert "stream_gap_rows" not in runs["free"].result["methods"]


@pytest.mark.parametrize("kind", ["latency", "loss"])
def test_the_rows_after_the_gap_carry_its_doubt_and_the_truth_lies_within_2u(runs, kind):
    curve, free = runs[kind].true_curve, runs["free"].true_curve
    x, s = (curve[c].to_numpy(dtype=float) for c in TRUE_CURVE_COLUMNS)
    u = curve[stream_gap.ROW_COLUMN].to_numpy(dtype=float)
    # (a) 0 before the gap, > 0 after it (2e-3 either side: E and the strain's zero are identified, not given)
    x_gap = _gap_strain(runs["record"])
    assert (x < x_gap - 2e-3).sum() > 20 and np.all(u[x < x_gap - 2e-3] == 0.0)
    after = (x > x_gap + 2e-3) & np.isfinite(u)
    assert after.sum() > 100 and np.all(u[after] > 0.0)
    note = runs[kind].result["methods"]["stream_gap_rows"]
    assert note["column"] == stream_gap.ROW_COLUMN and abs(note["from_plastic_strain"] - x_gap) < 2e-3
    # the rows without u: only past the alternative's end (its Fm a period's travel away), said so
    assert note["rows_without_u"] == int(np.isnan(u).sum()) <= 10 and np.all(x[np.isnan(u)] > 0.9 * x.max())
    # (b, c) the truth — the record without the fault, identified — within σ_row ± 2·u on every row both reach
    fx, fs = (free[c].to_numpy(dtype=float) for c in TRUE_CURVE_COLUMNS)
    both = np.isfinite(u) & (x >= fx[0]) & (x <= fx[-1])
    truth = np.interp(x[both], fx, fs)
    own = float(np.max(np.abs(np.diff(fs, 2))))  # the truth's own linear-interpolation error between its rows, at most
    assert both.sum() > 0.9 * x.size
    assert np.all(np.abs(s[both] - truth) <= 2.0 * u[both] + own)
    if kind == "latency":  # the fault's error is the gap's: as large as the term, not far under it (u tight, not inflated)
        err = np.abs(s[both] - truth)
        late = u[both] > 0
        assert np.max(err[late]) > 1.0 and np.all(err[late] >= 0.9 * u[both][late])


def test_the_written_rows_the_series_fit_and_the_report_name_where_the_doubt_starts(runs, tmp_path):
    """true_curve.csv holds the column (NaN as an empty cell, read back as NaN); a series member read from it knows the
    strain from which its rows carry the doubt, the series fit's warnings name it (cards are made from its curves),
    and the report's budget notes say it in words without the file's names."""
    import pandas as pd

    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.identification.series.members import stated_uncertainties, stream_gap_warnings
    from flowcurve.reports.report_content import customer_text, stream_gap_rows_note

    ident = runs["latency"]
    ident.write(tmp_path)
    back = pd.read_csv(tmp_path / "true_curve.csv")
    u = ident.true_curve[stream_gap.ROW_COLUMN].to_numpy(dtype=float)
    np.testing.assert_allclose(back[stream_gap.ROW_COLUMN].to_numpy(dtype=float), u, rtol=1e-5, atol=1e-9, equal_nan=True)
    start = ident.result["methods"]["stream_gap_rows"]["from_plastic_strain"]
    stated = stated_uncertainties(ident.result, back)
    assert stated["stream_gap_from_strain"] == pytest.approx(start, rel=1e-5)
    assert stated["stream_gap_u_max_MPa"] == pytest.approx(np.nanmax(u), rel=1e-5)
    assert "stream_gap_from_strain" not in stated_uncertainties(runs["free"].result, runs["free"].true_curve)
    member = dataclasses.make_dataclass("M", ["name", "stream_gap_from_strain", "stream_gap_u_max_MPa"])("s1", start, 4.2)
    (line,) = stream_gap_warnings([member])
    assert line.startswith("s1:") and f"{start:.4g}" in line
    (note,) = stream_gap_rows_note(to_jsonable(ident.result))
    words = customer_text(note)
    assert f"{start:.3g}"[:5] in words and "csv" not in words and "stream_gap_u_MPa" not in words
    assert stream_gap_rows_note(to_jsonable(runs["free"].result)) == []

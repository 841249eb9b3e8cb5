"""A tension record with no elastic line to speak of (one sample before the yield: 12 values/s
at 0.05 mm/s on the virtual rig, issue 31's scenario matrix): with the handbook E in the record
(or given) the elastic strain is stripped with it and the result says the line was missing;
without one it stays a one-line error asking for it."""

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import johnson_cook_static
from flowcurve.identification.identify import identify
from flowcurve.record.format import Record

from .conftest import TRUTH, make_record


def sparse_elastic(record, step=10, **meta):
    """The record sampled as a slow amplifier would: one sample on the elastic rise, then every
    ``step``-th sample of the plastic part."""
    data = record.data
    elastic = np.flatnonzero(data["force_N"].to_numpy() < 0.99 * TRUTH["A"] * np.pi * TRUTH["d0_mm"] ** 2 / 4)
    keep = [0, int(elastic[elastic.size // 2])] + list(range(int(elastic[-1]) + 1, len(data), step))
    return Record(meta={**record.meta, **meta}, data=data.iloc[keep].reset_index(drop=True), source=record.source)


def test_the_handbook_E_stands_in_for_a_missing_elastic_line():
    rec, _ = make_record(extensometer=True)
    ident = identify(sparse_elastic(rec, **{"material.E_MPa": repr(TRUTH["E_MPa"])}))
    res = ident.result
    assert res["E_MPa"] == TRUTH["E_MPa"] and any(w.startswith("no elastic line (") for w in res["warnings"])
    assert TRUTH["A"] < res["Rp02_MPa"] < 1.2 * TRUTH["A"]  # read between the one elastic sample and the next: high
    curve = ident.true_curve
    eps, sig = curve["true_plastic_strain"].to_numpy(), curve["true_stress_MPa"].to_numpy()
    assert np.max(np.abs(sig / johnson_cook_static(eps, TRUTH["A"], TRUTH["B"], TRUTH["n"]) - 1)) < 0.01


def test_without_a_handbook_E_a_missing_elastic_line_is_still_an_error():
    rec, _ = make_record(extensometer=True)
    with pytest.raises(IdentificationError, match="give the handbook modulus"):
        identify(sparse_elastic(rec))

"""verify's model E by the one rule (issue 43): never a silent 200 GPa — the curve's own E, else the
record's material.E_MPa, else its named class's handbook E, each said; else a one-line error."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.verify import FlowCurveSource, curve_from_card, curve_from_result, verify_modulus
from flowcurve.record.format import amend_record, read_record

DATA = Path(__file__).parent / "data"


def _record(tmp_path, **changes):
    path = tmp_path / "c.csv"
    shutil.copyfile(DATA / "other_settings_C1.csv", path)
    amend_record(path, changes)
    return read_record(path)


def _curve(E=None):
    return FlowCurveSource(np.array([0.0, 0.5]), np.array([100.0, 900.0]), E, None, "test curve")


def test_no_E_anywhere_is_refused_not_200_GPa(tmp_path):
    rec = _record(tmp_path, **{"material.E_MPa": None})  # "other-settings FE model C1": no class named
    with pytest.raises(IdentificationError, match=r"elastic modulus.*material\.E_MPa"):
        verify_modulus(_curve(), rec)


def test_the_class_the_grade_names_is_taken_and_said(tmp_path):
    E, source = verify_modulus(_curve(), _record(tmp_path, **{"material.E_MPa": None, "material": "12Kh18N12M3TL"}))
    assert E == 200_000.0 and "steel" in source and "GOST" in source


def test_the_records_handbook_E_and_the_curves_own_come_first(tmp_path):
    rec = _record(tmp_path, material="12Kh18N12M3TL")  # material.E_MPa 194000 in the header
    assert verify_modulus(_curve(), rec) == (194_000.0, f"{rec.source}: the record's material.E_MPa, ±5 % rectangular")
    card = curve_from_card("*ELASTIC\n190000, 0.3\n*PLASTIC\n100, 0\n900, 0.5\n")
    assert verify_modulus(card, rec) == (190_000.0, "card: *ELASTIC")


def test_an_apparent_E_of_a_result_is_not_the_models():
    result = {"hardening": {"law": "johnson_cook", "A_MPa": 100.0, "B_MPa": 800.0, "n": 0.5}, "E_MPa": 25_000.0, "E_source": "apparent"}
    assert curve_from_result(result).E_MPa is None
    result["E_source"] = "class (handbook E of steel ...)"
    result["E_MPa"] = 200_000.0
    assert curve_from_result(result).E_MPa == 200_000.0

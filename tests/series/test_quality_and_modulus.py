"""'flowcurve fit' says when its fit is poor (and fails under --strict), and refuses records
whose plastic strain would be the total strain (no modulus), naming them."""

import json

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.errors import IdentificationError
from flowcurve.identification.series.series import SeriesMember, load_members
from flowcurve.record.format import write_record

from ..compression.conftest import make_compression

ARGS = ["--ref-rate", "1", "--ref-temp", "24.85", "--melt-temp", "1519.85"]


def _folders(tmp_path, syn, distort=None):
    root = tmp_path / "results"
    for m in syn.members():
        if distort and m.name == distort:
            # a curve Johnson–Cook cannot follow together with the others: saturating at 1.3×
            sig = m.stress_MPa * (1.3 - 0.6 * np.exp(-m.plastic_strain / 0.01))
            m = SeriesMember(m.name, m.plastic_strain, sig, m.strain_rate_per_s, m.temperature_C)
        syn.write_result_folder(root / m.name, m, E_MPa=205000.0)
    return root


def test_good_fit_is_marked_good(tmp_path, syn, capsys):
    out = tmp_path / "fit"
    assert main(["fit", str(_folders(tmp_path, syn)), "--out", str(out), "--strict", *ARGS]) == 0
    assert json.loads((out / "fit.json").read_text())["quality"] == "good"
    assert "quality good" in capsys.readouterr().out


def test_poor_fit_is_marked_and_strict_fails(tmp_path, syn, capsys):
    root = _folders(tmp_path, syn, distort="T300C_100per_s")
    out = tmp_path / "fit"
    assert main(["fit", str(root), "--out", str(out), *ARGS]) == 0
    d = json.loads((out / "fit.json").read_text())
    assert d["quality"] == "poor" and d["fit_error_pct"] > 10
    assert any("poor" in w and "T300C_100per_s" in w for w in d["warnings"])
    text = capsys.readouterr().out
    assert "quality poor" in text and "warning: the global fit is poor" in text
    code = main(["fit", str(root), "--out", str(tmp_path / "strict"), "--strict", *ARGS])
    err = capsys.readouterr().err
    assert code == 2 and "poor" in err and "--strict" in err
    assert json.loads((tmp_path / "strict" / "fit.json").read_text())["quality"] == "poor"


def test_records_without_a_modulus_are_named(tmp_path):
    # 5 Hz on a stiff specimen: one sample on the elastic line, no handbook E and no material class named → no modulus
    paths = []
    for i, temperature in enumerate(("20", "300")):
        record, _ = make_compression(seed=30 + i, meta_extra={"nominal_temperature_C": temperature, "material": "synthetic"})
        paths.append(write_record(tmp_path / f"C{i}.csv", record))
    with pytest.raises(IdentificationError, match=r"C0, C1 have no elastic modulus.*--E"):
        load_members(paths)
    members = load_members(paths, E_MPa=194_000.0)
    assert all(m.E_MPa == 194_000.0 for m in members)


def test_records_naming_a_grade_take_its_class_modulus(tmp_path):
    """The same records under a GOST grade name: the steel class's handbook 200 GPa by the rule (issue 43)."""
    paths = [write_record(tmp_path / f"C{i}.csv", make_compression(seed=30 + i, meta_extra={"material": "12Kh18N12M3TL"})[0]) for i in range(2)]
    assert all(m.E_MPa == 200_000.0 for m in load_members(paths))

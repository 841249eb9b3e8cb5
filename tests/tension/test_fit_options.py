"""Tension hardening options: the fracture point's choice, the fit range, the fit's quality."""

import numpy as np
import pytest

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import johnson_cook_static
from flowcurve.identification.tension.identify import identify_tension

from .conftest import TRUTH as T


def law(eps_p):
    return johnson_cook_static(eps_p, T["A"], T["B"], T["n"])


def _fracture_force_scaled(rec, factor):
    """The same record with the force at fracture (its last sample) scaled: a fracture stress
    the law does not reach, as when the neck correction does not suit the material."""
    data = rec.data.copy()
    data.loc[data.index[-1], "force_N"] *= factor
    return type(rec)(meta=rec.meta, data=data, source=rec.source)


def test_consistent_fracture_point_is_included_by_default(synthetic):
    rec, _ = synthetic()
    h = identify_tension(rec).result["hardening"]
    assert h["fracture_point"] == "included"
    assert h["quality"] == "good" and h["warnings"] == []


def test_a_fracture_point_off_the_law_does_not_sacrifice_the_uniform_range(synthetic):
    rec, _ = synthetic()
    off = _fracture_force_scaled(rec, 1.15)  # 15 % above the law at eps_f = 0.8, still below Fm
    res = identify_tension(off, true_stress="constant_volume")
    r = res.result
    h = r["hardening"]
    assert h["fracture_point"] == "excluded" and "excluded" in h["fracture_point_choice"]
    # the reported law follows the input curve over the uniform range (the closed form)
    eps = np.linspace(0.002, r["uniform_true_plastic_strain"], 50)
    fit = johnson_cook_static(eps, h["A_MPa"], h["B_MPa"], h["n"])
    assert np.max(np.abs(fit / law(eps) - 1)) < 0.005
    alt = r["hardening_alternatives"]
    assert {"least_squares_johnson_cook_with_fracture_point", "least_squares_johnson_cook_without_fracture_point"} <= set(alt)
    forced = identify_tension(off, true_stress="constant_volume", fracture_point="include").result["hardening"]
    assert forced["fracture_point"] == "included"
    assert forced["uniform_range_error_pct"] > h["uniform_range_error_pct"] + 2.0


def test_fit_range_limits_the_fitted_points(synthetic):
    rec, _ = synthetic()
    h = identify_tension(rec, fit_range=(0.01, 0.1), fracture_point="exclude", true_stress="constant_volume").result["hardening"]
    assert h["fit_range"][0] >= 0.01 and h["fit_range"][1] <= 0.1
    assert h["fracture_point"] == "excluded"
    assert (h["A_MPa"], h["B_MPa"], h["n"]) == pytest.approx((T["A"], T["B"], T["n"]), rel=5e-3)


@pytest.mark.parametrize("options, words", [
    ({"fit_range": (0.1, 0.05)}, "LO < HI"),
    ({"fit_range": ("a", 1)}, "two plastic strains"),
    ({"fracture_point": "maybe"}, "fracture_point must be one of"),
    ({"fit_range": (0.5, 0.6)}, "fewer than 4 points"),
])
def test_bad_fit_options_are_clear(synthetic, options, words):
    rec, _ = synthetic()
    with pytest.raises(IdentificationError, match=words):
        identify_tension(rec, **options)


def test_identify_command_prints_quality_and_applies_the_options(synthetic, tmp_path, capsys):
    import json

    from flowcurve.cli import main
    from flowcurve.record.format import write_record

    rec, _ = synthetic()
    path = write_record(tmp_path / "T1.csv", _fracture_force_scaled(rec, 1.15))
    code = main(["identify", str(path), "--out", str(tmp_path / "out"), "--no-plots", "--fit-range", "0.005,0.12",
                 "--fracture-point", "include"])
    out = capsys.readouterr().out
    assert code == 0
    h = json.loads((tmp_path / "out" / "T1" / "result.json").read_text())["hardening"]
    assert h["fracture_point"] == "included" and h["fit_range"][0] >= 0.005 and h["fit_range"][1] <= 0.12
    assert f"quality {h['quality']}" in out
    for w in h["warnings"]:
        assert w in out  # every warning of the fit reaches the screen


def test_identify_command_rejects_a_malformed_fit_range(synthetic, tmp_path, capsys):
    from flowcurve.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["identify", "x.csv", "--fit-range", "0.1"])
    assert exc.value.code == 2
    assert "--fit-range" in capsys.readouterr().err

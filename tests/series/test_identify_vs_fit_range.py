"""The same record, two laws (issue 32): 'flowcurve identify' fits the uniform range and the neck-corrected
fracture point, 'flowcurve fit' the true curve up to maximum force. Both say which strain range they used, side by
side on screen and in json, with the reason — checked on the real 42CrMoS4 record examples/data/46NT71.csv."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from flowcurve.cli import main

RECORD = Path(__file__).resolve().parents[2] / "examples" / "data" / "46NT71.csv"


def jc(eps, A_MPa, B_MPa, n, **_):
    return A_MPa + B_MPa * np.power(eps, n)


def test_identify_and_fit_on_46NT71_print_the_strain_range_each_used(tmp_path, capsys):
    assert main(["identify", str(RECORD), "--out", str(tmp_path / "id"), "--no-plots"]) == 0
    id_screen = capsys.readouterr().out
    hard = json.loads((tmp_path / "id" / "46NT71" / "result.json").read_text())["hardening"]
    lo, hi = hard["strain_range"]
    uniform_end = hard["fit_range"][1]
    assert hard["fracture_point"] == "included" and hi > 10 * uniform_end  # the fracture point at εp 0.81, Fm at 0.05
    assert f"over εp {lo:.3g}–{hi:.3g} (uniform range to {uniform_end:.3g} + the fracture point)" in id_screen

    assert main(["fit", str(RECORD), "--melt-temp", "1500", "--fix-C", "0", "--fix-m", "1", "--out", str(tmp_path / "fit")]) == 0
    fit_screen = capsys.readouterr().out
    fit = json.loads((tmp_path / "fit" / "fit.json").read_text())
    rec = fit["records"][0]
    side = rec["identify_law"]
    assert side["plastic_strain"] == [lo, hi] and side["fit_plastic_strain"] == rec["plastic_strain"]
    assert rec["plastic_strain"][1] == uniform_end  # the fit has the uniform range only
    reason = side["why_different"]
    assert reason in fit["warnings"] and f"warning: {reason}" in fit_screen
    assert f"{hi:.3g}" in reason and f"{uniform_end:.3g}" in reason and "fracture point" in reason
    # the reason is true: the two laws agree where both have points and part beyond
    shared = np.linspace(max(lo, 0.005), uniform_end, 50)
    assert np.max(np.abs(jc(shared, **fit) / jc(shared, **side) - 1)) < 0.03
    assert abs(jc(hi, **fit) / jc(hi, **side) - 1) > 0.2

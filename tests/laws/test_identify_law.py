"""``flowcurve identify --law``: any static law of the registry, ``best`` by AIC with its margin
in result.json and the summary, and a rate/temperature law refused in one line naming ``fit``."""

import json
from pathlib import Path

import pytest

from flowcurve.cli import main
from flowcurve.errors import IdentificationError
from flowcurve.identification.identify import identify
from flowcurve.identification.laws.base import get_law
from flowcurve.record.format import write_record
from flowcurve.record.importers import load_record
from tests.compression.conftest import make_compression

TENSION = Path(__file__).resolve().parents[1] / "data" / "42CrMoS4" / "original_data" / "46NT71.csv"


def test_best_on_a_tension_record_says_which_law_won_and_by_how_much(tmp_path, capsys):
    assert main(["identify", str(TENSION), "--law", "best", "--out", str(tmp_path), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    h = json.loads((tmp_path / "46NT71" / "result.json").read_text())["hardening"]
    choice = h["law_choice"]
    assert h["law"] == choice["chosen"] and choice["next"] != choice["chosen"]
    assert choice["delta_aic_to_next"] == pytest.approx(choice["aic"][choice["next"]] - choice["aic"][choice["chosen"]])
    assert all(p.key in h for p in get_law(choice["chosen"]).parameters)  # the winner's own constants
    assert f"--law best: {choice['chosen']} by AIC" in printed and f"({choice['next']})" in printed


def test_a_named_law_is_fitted_and_never_replaced(tmp_path):
    record = load_record(TENSION)
    for name in ("hollomon", "johnson_cook"):
        h = identify(record, law=name).result["hardening"]
        assert h["law"] == name and "law_choice" not in h
        assert all(p.key in h for p in get_law("hollomon" if name == "hollomon" else "johnson_cook").parameters[:2])


def test_a_compression_record_takes_any_static_law():
    record, _ = make_compression(seed=11)
    h = identify(record, law="hollomon").result["hardening"]
    assert h["law"] == "hollomon" and {"K_MPa", "n", "K_MPa_stderr"} <= set(h) and "law_choice" not in h


@pytest.mark.slow  # ~20–30 s: the four-constant laws' refits (range and pattern shifts) crawl along their valleys
def test_best_on_a_compression_record_says_which_law_won():
    record, _ = make_compression(seed=11)
    best = identify(record, law="best").result["hardening"]
    assert best["law"] == best["law_choice"]["chosen"] and best["law_choice"]["delta_aic_to_next"] is not None


def test_a_rate_law_or_an_unknown_name_is_one_line_before_any_work(tmp_path, capsys):
    record = load_record(TENSION)
    with pytest.raises(IdentificationError, match="fit it over a series of records with `flowcurve fit --law hyperbolic_sine`"):
        identify(record, law="hyperbolic_sine")
    path = write_record(tmp_path / "T.csv", record)
    assert main(["identify", str(path), "--law", "zerilli_armstrong_bc", "--out", str(tmp_path / "o"), "--no-plots"]) != 0
    err = capsys.readouterr().err
    assert "unknown law 'zerilli_armstrong_bc' (did you mean 'zerilli_armstrong_bcc'?)" in err and "Traceback" not in err


COMPRESSION_EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "data" / "compression-steel45.csv"


def test_best_never_chooses_a_law_whose_constants_the_curve_does_not_determine(tmp_path, capsys):
    """The virtual rig's compression record: Swift–Voce's seven constants fit closest (lowest AIC) but
    trade off without bound (σ0 0.001 ± 2·10⁷ MPa before this rule); best takes the lowest AIC among
    the determined laws, every constant of the winner within its own value (|v| > se), and says so."""
    assert main(["identify", str(COMPRESSION_EXAMPLE), "--law", "best", "--out", str(tmp_path), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    h = json.loads((tmp_path / "compression-steel45" / "result.json").read_text())["hardening"]
    choice = h["law_choice"]
    assert h["law"] == choice["chosen"] and choice["chosen"] not in choice["undetermined"]
    for p in get_law(choice["chosen"]).parameters:
        if p.key in h:
            assert h[f"{p.key}_stderr"] is not None and h[f"{p.key}_stderr"] < abs(h[p.key]), (p.key, h)
    assert choice["lowest_aic"] in choice["undetermined"] and choice["lowest_aic"] != choice["chosen"]
    assert f"{choice['lowest_aic']} fits closer but the curve does not determine" in printed


def test_a_named_law_whose_constants_trade_off_says_so(tmp_path):
    record = load_record(COMPRESSION_EXAMPLE)
    h = identify(record, law="swift_voce").result["hardening"]
    assert h["law"] == "swift_voce"  # the law asked for is kept, with the warning
    assert any("not determined by this curve" in w for w in h["warnings"]), h["warnings"]


def test_flowcurve_laws_lists_every_registered_law_a_new_file_included(capsys):
    """`flowcurve laws` reads the registry: every law, and a law registered now (as its own file would
    register it) with no list to edit; the help texts of identify and fit point to it."""
    import numpy as np

    from flowcurve.identification.laws import base
    from flowcurve.identification.laws.base import Parameter, register, registered_laws
    from flowcurve.identification.laws.static import StaticLaw

    @register
    class Linear(StaticLaw):
        """A test law: σ = σ0 + H·εp."""

        name = "test_linear"
        display_name = "Linear (test)"
        parameters = (Parameter("sigma0", "sigma0_MPa", "MPa", 0.0, np.inf, "yield stress"),
                      Parameter("H", "H_MPa", "MPa", 0.0, np.inf, "hardening modulus"))
        equation = "sigma_MPa = sigma0 + H*eps_p"
        latex = r"\sigma = \sigma_0 + H\varepsilon_p"
        function = staticmethod(lambda eps_p, sigma0, H: sigma0 + H * np.asarray(eps_p, dtype=float))

    try:
        assert main(["laws"]) == 0
        printed = capsys.readouterr().out
        for name, law in registered_laws().items():
            assert f"{name}: {law.display_name} [" in printed, name
        assert "test_linear: Linear (test) [identify --law]" in printed and "constants: sigma0 (MPa), H (MPa)" in printed
        assert "hensel_spittel: Hensel–Spittel [fit --law]" in printed
    finally:
        base._REGISTRY.pop("test_linear", None)
    with pytest.raises(SystemExit):
        main(["identify", "--help"])
    assert "'flowcurve laws' lists them" in capsys.readouterr().out

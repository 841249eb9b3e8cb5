"""``flowcurve card``: files, options for missing constants, one-line errors."""

import json

import pytest

from flowcurve.cli import main

from .readers import floats, read_inp


def test_card_to_file_for_every_format(fit_file, tmp_path, capsys):
    path = fit_file()
    for fmt, first in (("lsdyna", "*KEYWORD"), ("abaqus", "**"), ("radioss", "#"), ("calculix", "**")):
        out = tmp_path / f"card.{fmt}"
        assert main(["card", str(path), "--format", fmt, "--units", "mm-ms-kg-kN-GPa", "-o", str(out)]) == 0
        text = out.read_text()
        assert text.startswith(first)
        assert "mm-ms-kg-kN-GPa" in text and "user's risk" in text


def test_card_to_stdout_with_constants_from_options(fit_file, capsys):
    path = fit_file(E_MPa=None, poisson_ratio=None, density_kg_per_m3=None)
    code = main(["card", str(path), "-f", "calculix", "--E", "200000", "--poisson", "0.3", "--density", "7850"])
    assert code == 0
    blocks = read_inp(capsys.readouterr().out)
    by_key = {k: rows for k, _, rows in blocks}
    assert floats(by_key["ELASTIC"]).tolist() == [[200000.0, 0.3]]
    assert floats(by_key["DENSITY"])[0, 0] == pytest.approx(7.85e-9)


@pytest.mark.parametrize("missing, option", [("E_MPa", "--E"), ("poisson_ratio", "--poisson"),
                                             ("specific_heat_J_per_kgK", "--cp"), ("melt_temperature_C", "--melt-temp")])
def test_missing_constant_is_one_line_naming_the_option(fit_file, capsys, missing, option):
    path = fit_file(**{missing: None})
    assert main(["card", str(path), "-f", "lsdyna"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("flowcurve: error:") and option in err and "\n" not in err


@pytest.mark.parametrize("fmt, options", [
    ("lsdyna", ("--E", "--poisson", "--density", "--cp", "--melt-temp")),
    ("abaqus", ("--E", "--poisson", "--density", "--melt-temp")),
    ("radioss", ("--E", "--poisson", "--density", "--cp", "--melt-temp")),
])
def test_card_with_nothing_optional_names_every_missing_constant_at_once(fit_file, tmp_path, capsys, fmt, options):
    """A fit file without the elastic and thermal constants: one message lists every one the card
    needs (they were asked for one refused run at a time), and no card file is written."""
    path = fit_file(E_MPa=None, poisson_ratio=None, density_kg_per_m3=None, specific_heat_J_per_kgK=None, melt_temperature_C=None)
    out = tmp_path / "card.txt"
    assert main(["card", str(path), "-f", fmt, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and f"needs {len(options)} value(s)" in err, err
    for option in options:
        assert f"({option})" in err, (option, err)
    assert "Poisson's ratio" in err and not out.exists()


def test_bad_fit_files_are_one_line_errors(tmp_path, capsys):
    bad = tmp_path / "fit.json"
    bad.write_text("{\"A_MPa\": 100,\n oops}")
    assert main(["card", str(bad), "-f", "lsdyna"]) == 2
    err = capsys.readouterr().err.strip()
    assert "line 2" in err and "\n" not in err
    assert main(["card", str(tmp_path / "nope.json"), "-f", "lsdyna"]) == 2
    assert "no such fit file" in capsys.readouterr().err
    bad.write_text(json.dumps({"A_MPa": 100, "B_MPa": 500}))
    assert main(["card", str(bad), "-f", "lsdyna"]) == 2
    assert "'n'" in capsys.readouterr().err
    bad.write_text(json.dumps({"A_MPa": "abc", "B_MPa": 500, "n": 0.3}))
    assert main(["card", str(bad), "-f", "lsdyna"]) == 2
    assert "'A_MPa' is not a number" in capsys.readouterr().err


def test_missing_curve_file_is_named(fit_file, capsys):
    path = fit_file()
    next((path.parent / "curves").iterdir()).unlink()
    assert main(["card", str(path), "-f", "calculix"]) == 2
    assert "is missing" in capsys.readouterr().err


def test_unknown_units_refused_by_the_parser(fit_file, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["card", str(fit_file()), "-f", "lsdyna", "--units", "mm-s-kg-kN-GPa"])
    assert exc.value.code == 2


def test_lsdyna_curves_at_a_chosen_temperature(fit_file, capsys):
    from .conftest import jc_MPa
    import numpy as np

    assert main(["card", str(fit_file(rates=(1e-3,))), "-f", "lsdyna", "--temperature", "400"]) == 0
    text = capsys.readouterr().out
    rows = text.split("*DEFINE_CURVE")[1].split("*END")[0].splitlines()[4:]
    pts = np.array([[float(v) for v in r.split()] for r in rows if r.strip() and not r.startswith("$")])
    np.testing.assert_allclose(pts[1:, 1], jc_MPa(pts[1:, 0], 1e-3, 400.0), rtol=2e-3)
    assert "at 400 C" in " ".join(line[2:] for line in text.splitlines() if line.startswith("$ "))


def test_untested_temperature_for_measured_curves_is_refused(fit_file, capsys):
    assert main(["card", str(fit_file()), "-f", "lsdyna", "--temperature", "300"]) == 2
    err = capsys.readouterr().err
    assert "no measured curves at 300 C" in err and "--curves law" in err
    assert main(["card", str(fit_file()), "-f", "lsdyna", "--temperature", "300", "--curves", "law"]) == 0


def test_card_options_reach_the_card(fit_file, capsys):
    from .readers import read_radioss, read_radioss_block

    path = fit_file()
    assert main(["card", str(path), "-f", "radioss", "--radioss-version", "2023", "--id-offset", "40", "--fcut", "500"]) == 0
    blocks = dict(read_radioss(capsys.readouterr().out))
    v = read_radioss_block(blocks["/MAT/PLAS_JOHNS/41"][1:], "PLAS_JOHNS", "2023")
    assert v["F_cut"] == 500.0 and v["T_r"] == pytest.approx(293.15)
    assert main(["card", str(path), "-f", "calculix", "--extend-to", "0.6", "--temperature-tolerance", "500"]) == 0
    rows = floats([r for k, _, r in read_inp(capsys.readouterr().out) if k == "PLASTIC"][0])
    assert len(set(rows[:, 2])) == 1 and rows[-1, 1] == pytest.approx(0.6)  # 20 and 400 C made one by the tolerance


@pytest.mark.parametrize("option, value", [("--extend-to", "0"), ("--id-offset", "-3"), ("--temperature-tolerance", "-1"),
                                           ("--max-rows", "2"), ("--damage-displacement", "0")])
def test_bad_card_option_is_one_line_naming_it(fit_file, capsys, option, value):
    assert main(["card", str(fit_file()), "-f", "lsdyna", option, value]) == 2
    err = capsys.readouterr().err.strip()
    assert option in err and "\n" not in err

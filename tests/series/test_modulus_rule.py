"""One rule for E (issue 32): given (--E), else the record's material.E_MPa, else measured with an extensometer.
A crosshead slope is reported as apparent and never reaches a card; without a defensible E the card asks for --E."""

from __future__ import annotations

import json

import pytest

from flowcurve.cli import main
from flowcurve.errors import IdentificationError
from flowcurve.identification.elastic_modulus import modulus_for_model, result_E_source, series_modulus
from flowcurve.record.format import write_record

TRUE_E = 205_000.0  # the synthetic records' material
MATERIAL = ("--poisson", "0.3", "--density", "7850", "--cp", "470")  # what else a card needs and these fit files lack


def _fit_from_crosshead_records(tmp_path, syn, capsys, *, handbook_E=None, known_frame=False, material="synthetic"):
    """identify + fit on four crosshead-only tension records (no extensometer); the fit folder. ``material``: the
    records' name ("synthetic": no class named, so no class E either; "4340 (synthetic)": the steels')."""
    paths = []
    for T in (25.0, 600.0):
        for speed in (0.03, 3.0):
            rec, _ = syn.tension_record(T, speed, speed / 30.0, noise_N=2.0, seed=len(paths), ref_rate_per_s=1e-3)
            rec.meta["material"] = material
            if handbook_E is not None:
                rec.meta["material.E_MPa"] = repr(handbook_E)
            if not known_frame:  # the frame stiffness unknown: the slope is the frame's and the specimen's together
                del rec.meta["rig.frame_stiffness_N_per_um"]
            paths.append(write_record(tmp_path / f"T{T:g}_v{speed:g}.csv", rec))
    results, out = tmp_path / "results", tmp_path / "fit"
    assert main(["identify", *map(str, paths), "--out", str(results), "--no-plots"]) == 0
    screen = capsys.readouterr().out
    assert main(["fit", str(results), "--out", str(out), "--ref-temp", "24.85", "--melt-temp", "1519.85"]) == 0
    capsys.readouterr()
    return out / "fit.json", results, screen


def _elastic(card_text: str) -> float:
    lines = card_text.splitlines()
    return float(lines[lines.index("*ELASTIC") + 1].split(",")[0])


def test_crosshead_records_card_asks_for_E_then_carries_exactly_the_given_one(tmp_path, syn, capsys):
    fit, results, screen = _fit_from_crosshead_records(tmp_path, syn, capsys)
    result = json.loads(next(results.glob("*/result.json")).read_text())
    assert result["modulus"]["E_source"] == "apparent" and result_E_source(result) == "apparent"
    assert screen.count("(apparent: the diagram's slope, not the material's E)") == 4  # said on screen, per record
    d = json.loads(fit.read_text())
    assert d["E_MPa"] is None and d["E_MPa_source"].startswith("undetermined")
    apparent = list(d["E_apparent_MPa"].values())
    assert max(apparent) < 0.8 * TRUE_E  # the frame's compliance is in them: far from the material's E
    # no defensible E: the card asks for --E in one line, exit code 2
    assert main(["card", str(fit), "-f", "abaqus", *MATERIAL]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--E" in err and "apparent" in err
    # with --E: exactly that, and the comment names the source
    assert main(["card", str(fit), "-f", "abaqus", "--E", "196500", *MATERIAL, "-o", str(tmp_path / "m.inp")]) == 0
    text = (tmp_path / "m.inp").read_text()
    assert _elastic(text) == 196500.0
    assert "** elastic modulus E = 196500 MPa: given (--E)" in text
    comments = " ".join(line[2:].strip() for line in text.splitlines() if line.startswith("**"))
    assert "given on the command line, not identified: --E 196500, --poisson 0.3, --density 7850, --cp 470" in comments


def test_a_named_grade_gives_the_card_its_class_E_and_says_so(tmp_path, syn, capsys):
    """The same records named by their grade (4340, AISI/SAE): the rule's last step, the steels' handbook
    200 GPa, reaches the fit and the card, labelled as the class's (issue 43)."""
    fit, _, screen = _fit_from_crosshead_records(tmp_path, syn, capsys, material="4340 (synthetic)")
    assert screen.count("the material's E 200000 MPa is class") == 4
    d = json.loads(fit.read_text())
    assert d["E_MPa"] == 200_000.0 and d["E_MPa_source"].startswith("handbook value of the material class")


def test_a_handbook_E_in_the_records_reaches_the_card_and_says_so(tmp_path, syn, capsys):
    fit, _, _ = _fit_from_crosshead_records(tmp_path, syn, capsys, handbook_E=TRUE_E)
    d = json.loads(fit.read_text())
    assert d["E_MPa"] == TRUE_E and d["E_MPa_source"].startswith("handbook")
    assert main(["card", str(fit), "-f", "lsdyna", *MATERIAL, "-o", str(tmp_path / "m.k")]) == 0
    text = (tmp_path / "m.k").read_text()
    assert "elastic modulus E = 205000 MPa: handbook (the record's material.E_MPa)" in " ".join(
        line[2:].strip() for line in text.splitlines() if line.startswith("$ "))


def test_the_series_E_is_the_first_defensible_class_never_a_mean_with_an_apparent_one():
    # the demo run of issue 32: a tension record's apparent 239 GPa and a compression record's handbook 200 GPa
    got = series_modulus([("t1", 239_000.0, "apparent"), ("c1", 200_000.0, "handbook")])
    assert got["E_MPa"] == 200_000.0 and got["E_MPa_source"].startswith("handbook")
    got = series_modulus([("t1", 210_000.0, "measured"), ("c1", 200_000.0, "handbook"), ("c2", 190_000.0, "given")])
    assert got["E_MPa"] == 190_000.0 and got["E_MPa_source"].startswith("given")
    got = series_modulus([("t1", 185_000.0, "apparent"), ("t2", 239_000.0, "apparent")])
    assert got["E_MPa"] is None and "apparent (185000–239000 MPa" in got["E_MPa_source"]


def test_an_fe_model_never_takes_an_apparent_slope(syn):
    rec, _ = syn.tension_record(25.0, 0.03, 1e-3)
    apparent = {"E_MPa": 239_000.0, "modulus": {"source": "most linear stretch", "E_source": "apparent"}}
    with pytest.raises(IdentificationError, match=r"needs the material's elastic modulus.*239000 MPa is apparent.*--E"):
        modulus_for_model(rec, apparent)
    assert modulus_for_model(rec, apparent, 201_000.0) == (201_000.0, "given")
    rec.meta["material.E_MPa"] = "200000"
    assert modulus_for_model(rec, apparent) == (200_000.0, "handbook")
    del rec.meta["material.E_MPa"]
    measured = {"E_MPa": 198_000.0, "modulus": {"source": "most linear stretch", "E_source": "measured"}}
    assert modulus_for_model(rec, measured) == (198_000.0, "measured")


@pytest.mark.parametrize("written, cls", [("option", "given"), ("record (material.E_MPa)", "handbook"), ("apparent", "apparent"),
                                          ("none", "none")])
def test_compression_results_E_source_as_compression_writes_it(written, cls):
    assert result_E_source({"test": "compression", "E_MPa": 200_000.0, "E_source": written}) == cls


def test_a_compression_result_with_a_modulus_block_keeps_its_E_source():
    """Compression results carry a ``modulus`` block (the line's fit and its quality) beside ``E_source``:
    the handbook E of ``run --E`` was read as a tension's apparent slope and every console card asked for --E."""
    line = {"E_MPa": 200000.0, "source": "record (material.E_MPa)", "E_line_MPa": 206290.0}
    assert result_E_source({"E_MPa": 200000.0, "E_source": "record (material.E_MPa)", "modulus": line}) == "handbook"
    assert result_E_source({"E_MPa": 200000.0, "E_source": "option (--E)", "modulus": line}) == "given"
    assert result_E_source({"E_MPa": 180000.0, "E_source": "apparent (crosshead slope)", "modulus": line}) == "apparent"

"""``flowcurve identify --lc``: the crosshead's strain refers to the parallel length given.

The record is the Ramberg–Osgood test of tests/identify/lab_exports.py written natively with the
crosshead alone: its crosshead is e·36 mm + F/(60 N/µm), a bar whose parallel length is 36 mm
with gauge marks 30 mm apart. Ag's truth is the construction's e_m − Rm/E, obtained without
flowcurve; with --lc 36 the identified Ag meets it within its U, without it Ag is 36/30 too large.
"""

import json

import numpy as np
import pandas as pd
import pytest

from flowcurve.cli import main
from flowcurve.record.format import Record, write_record
from tests.identify.lab_exports import tension_truth

LC_MM = 36.0  # the parallel length lab_exports' crosshead stretches


@pytest.fixture(scope="module")
def crosshead_record(tmp_path_factory):
    """A native tension record (time, force, crosshead; no parallel length stated) and its truth."""
    truth = tension_truth()
    data = pd.DataFrame({"time_s": truth.time_s, "force_N": truth.force_N, "crosshead_mm": truth.crosshead_mm})
    header = {"flowcurve-record": "1", "status": "complete", "test": "tension", "material": "synthetic",
              "specimen.d0_mm": f"{truth.d0_mm:g}", "specimen.l0_mm": f"{truth.l0_mm:g}",
              "rig.frame_stiffness_N_per_um": "60", "material.E_MPa": f"{truth.E_MPa:g}"}
    path = write_record(tmp_path_factory.mktemp("lc") / "ro.csv", Record(meta=header, data=data, source="ro"))
    return path, truth


def identified(path, out, *options) -> dict:
    assert main(["identify", str(path), "--out", str(out), "--no-plots", *options]) == 0
    return json.loads((out / path.stem / "result.json").read_text(encoding="utf-8"))


def test_identify_lc_sets_the_strain_length_and_ag_meets_the_truth(crosshead_record, tmp_path):
    path, truth = crosshead_record
    ag_truth = 100.0 * (float(truth.strain[np.argmax(truth.force_N)]) - truth.Rm_MPa / truth.E_MPa)  # 3.28 %
    stated = identified(path, tmp_path / "lc", "--lc", f"{LC_MM:g}")
    assert stated["methods"]["strain_length_mm"] == LC_MM
    assert stated["provenance"]["options"]["metadata"]["specimen.parallel_length_mm"] == repr(LC_MM)
    assert abs(stated["Ag_pct"] - ag_truth) <= stated["uncertainty"]["Ag_pct"]["U"], (stated["Ag_pct"], ag_truth)
    # the same record without it: the strain over l0 30 mm, Ag 3.93 % for 3.28 — the error --lc is there to remove; the
    # unstated length is warned and in the strain scale's U (up to L0 + 2·d0), which --lc takes out again
    unstated = identified(path, tmp_path / "nolc")
    assert unstated["methods"]["strain_length_mm"] == truth.l0_mm and unstated["methods"]["strain_length_stated"] is False
    assert unstated["Ag_pct"] - ag_truth > 3 * stated["uncertainty"]["Ag_pct"]["U"]
    assert abs(unstated["Ag_pct"] - ag_truth) <= unstated["uncertainty"]["Ag_pct"]["U"]
    assert unstated["uncertainty"]["Ag_pct"]["U"] > 5 * stated["uncertainty"]["Ag_pct"]["U"]
    assert any("parallel length is not stated" in w for w in unstated["warnings"])


def test_a_specimens_table_gives_lc_as_the_option_does(crosshead_record, tmp_path):
    path, truth = crosshead_record
    table = tmp_path / "specimens.csv"
    table.write_text(f"file;lc (mm)\n{path.name};{LC_MM:g}\n", encoding="utf-8")
    given = identified(path, tmp_path / "table", "--specimens", str(table))
    assert given["methods"]["strain_length_mm"] == LC_MM

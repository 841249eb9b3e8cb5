"""README's fault table against what really happens (issue 31): every row's drills run as an
operator would give them (``flowcurve run tension --fault …``, the run's defaults) on the
in-process virtual rig on model time; each must end with the exit code the row states, the
device named to the operator and in the record, and the heater's output off.

The rows are read from README.md: a row added, removed or reworded there without its drills here
fails :func:`test_every_row_of_the_table_is_drilled`, so the table and this test cannot drift apart.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

from flowcurve.record.format import read_record

README = Path(__file__).resolve().parents[2] / "README.md"
DEVICE_NAMES = {"loadcell": "load cell", "encoder": "crosshead encoder", "furnace": "furnace"}

# README row (its first cell) → the drills that row speaks for; "@5": five model seconds after the crosshead starts
DRILLS: dict[str, tuple[str, ...]] = {
    "`loadcell:garble:0.05`, `loadcell:drop:0.05`": ("loadcell:garble:0.05", "loadcell:drop:0.05"),
    "`…:corrupt` (one wrong but well-formed reading)": ("loadcell:corrupt@5", "encoder:corrupt@5", "furnace:corrupt@5"),
    "`loadcell:spike:900@40` (one frame 900 N high, under the 1 % of a 100 kN frame the rate rules tolerate)": ("loadcell:spike@40",),
    "`encoder:garble:0.05`, `encoder:drop:0.05`, `furnace:garble:0.05`, `furnace:drop:0.05`":
        ("encoder:garble:0.05", "encoder:drop:0.05", "furnace:garble:0.05", "furnace:drop:0.05"),
    "`encoder:jump`": ("encoder:jump@5",),
    "`encoder:delay`, `furnace:delay` (beyond the time-out)": ("encoder:delay@5", "furnace:delay@5"),
    "`loadcell:delay@SECONDS` (it begins mid-test)": ("loadcell:delay@5",),
    "`loadcell:delay` from the start (the default 0.5 s, beyond the driver's 0.2 s time-out)": ("loadcell:delay",),
    "`loadcell:delay:0.1` from the start (within the time-out)": ("loadcell:delay:0.1",),
    "`…:silence`, `…:drop:1`, `…:garble:1`, `…:unplug`":
        tuple(f"{d}:{k}@5" for k in ("silence", "drop:1", "garble:1", "unplug") for d in DEVICE_NAMES),
    "`furnace:wrong_address`": ("furnace:wrong_address@5",),
    "`furnace:open_thermocouple`, a reading above the maximum": ("furnace:open_thermocouple@5",),
    "`furnace:relay_stuck`": ("furnace:relay_stuck@5",),
}
NOT_FAULT_DRILLS = {  # rows that are no --fault (tests/acquisition/test_fault_drills.py and test_storage cover them)
    "disk full / read-only record folder", "a second run on the same ports"}
UNDETECTABLE = {"loadcell:delay:0.1"}  # the table says so: nothing to name


def fault_table() -> dict[str, str]:
    """README's fault table: first cell → how the run ends."""
    text = README.read_text(encoding="utf-8")
    block = text[text.index("| fault (`--fault`) | how the run ends |"):]
    rows = {}
    for line in block.splitlines()[2:]:
        if not line.startswith("|"):
            break
        first, rest = line.strip("|").split(" | ", 1)
        rows[first.strip()] = rest.strip()
    return rows


def exit_codes(ending: str) -> set[int]:
    """The exit codes a row allows: ``exit 5`` and ``(0 below …)`` alternatives."""
    codes = {int(n) for n in re.findall(r"exit (\d+)", ending)}
    codes |= {int(n) for n in re.findall(r"\((\d+) below", ending)}
    return codes


def test_every_row_of_the_table_is_drilled():
    rows = set(fault_table())
    assert rows - NOT_FAULT_DRILLS == set(DRILLS), "README's fault table and this test's drills differ"


def _drill(tmp_path: Path, fault: str, *extra: str) -> dict:
    """``flowcurve run tension --quiet --fault FAULT`` in this process, the virtual rig on model time."""
    import flowcurve.acquisition.session as session
    from flowcurve.cli import main
    from flowcurve.clock import ModelClock

    rigs = []
    real = session.run_virtual_test

    def on_model_time(*args, **kwargs):
        return real(*args, clock=ModelClock(), link="inprocess", rig_setup=rigs.append, **kwargs)

    out, err = io.StringIO(), io.StringIO()
    record = tmp_path / "r.csv"
    session.run_virtual_test = on_model_time
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(["run", "tension", "--quiet", "--out", str(record), "--tension-response", "bridgman", "--fault", fault, *extra])
    finally:
        session.run_virtual_test = real
    return {"code": code, "said": out.getvalue() + err.getvalue(), "record": record, "rig": rigs[0] if rigs else None}


CASES = [pytest.param(row, fault, id=fault) for row, faults in DRILLS.items() for fault in faults]


@pytest.mark.parametrize("row, fault", CASES)
def test_each_fault_ends_as_the_readme_table_says(tmp_path, row, fault):
    ending = fault_table()[row]
    got = _drill(tmp_path, fault)
    assert got["code"] in exit_codes(ending), f"{fault}: exit {got['code']}, README says {ending!r}\n{got['said'][-600:]}"
    assert "internal error" not in got["said"] and "Traceback" not in got["said"]
    device = DEVICE_NAMES[fault.split(":")[0]]
    if fault not in UNDETECTABLE:
        assert device in got["said"], f"{fault}: the operator was not told of the {device}: {got['said'][-400:]}"
        if got["record"].exists():
            rec = read_record(got["record"])
            named = " ".join(f"{e.name} {e.text}" for e in rec.events)
            assert device in named, f"{fault}: the record's events do not name the {device}: {named[-400:]}"
    vr = got["rig"]
    if vr is not None:
        assert vr.devices["furnace"].do == 0, "the furnace module's heater output is on at the end"


def test_a_garbled_load_cell_is_named_in_the_record_and_in_identifys_warnings(tmp_path):
    """Must-show: ``run tension --fault loadcell:garble:0.05`` names the loss in the record's
    events and in identify's warnings."""
    import json

    from flowcurve.cli import main

    got = _drill(tmp_path, "loadcell:garble:0.05")
    rec = read_record(got["record"])
    losses = [e for e in rec.events if e.name in ("stream_restart", "frames_missing", "data_loss")]
    assert losses and all("load cell" in e.text for e in losses if e.name != "data_loss")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["identify", str(got["record"]), "--out", str(tmp_path / "res"), "--no-plots"]) == 0
    result = json.loads((tmp_path / "res" / got["record"].stem / "result.json").read_text())
    warnings = result.get("warnings") or []
    assert any("declares rig faults" in w and "load cell" in w for w in warnings), warnings


def test_one_corrupt_load_cell_reading_does_not_end_the_test_as_a_fracture(tmp_path):
    """Must-show: ``run tension --fault loadcell:corrupt@5`` (a well-formed +20 kN reading): the
    reading rejected and named; the test ends at the specimen's own fracture, its maximum force
    the specimen's, not the corrupt value."""
    got = _drill(tmp_path, "loadcell:corrupt@5")
    rec = read_record(got["record"])
    corrupt = [e.text for e in rec.events if e.name == "corrupt"]
    assert len(corrupt) == 1 and corrupt[0].startswith("load cell: reading")
    f_max = float(rec.column("force_N").max())
    assert f_max < 20000.0, f"the corrupt reading reached the record: Fmax {f_max:.0f} N"
    stop = rec.meta["stop_reason"]
    assert stop.startswith("fracture") and f"{f_max / 1000:.2f} kN" in stop, (stop, f_max)

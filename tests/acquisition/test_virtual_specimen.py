"""``flowcurve rig virtual --d0/--l0/--lc/--h0``: the virtual rig in its own process simulates the
bar it is told, made as ``flowcurve run`` makes it on the virtual rig in its own process (same
options, checks and defaults), states it in its configuration's ``[virtual]``, and ``run --config``
warns (and records a ``geometry_mismatch`` event) when the test states another geometry.

The CLI's parsing and refusals, the configuration's table and the warning are fast; that the
geometry reaches the simulated bar of a real ``rig virtual`` process is ``-m pty``: its record is
compared with the in-process virtual rig's run of the same geometry (the truth, independent of the
process path) and with the default bar's.
"""

from __future__ import annotations

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.clock import ModelClock
from flowcurve.rig.config import load_config, to_toml
from flowcurve.rig.virtual.physics import Specimen
from flowcurve.services.run import RunRequest, prepare

from .test_fault_drills import RigProcess, env, rig_process, run_test  # noqa: F401 - env and rig_process are fixtures


class Built(Exception):
    pass


@pytest.fixture
def built(monkeypatch):
    """What 'rig virtual' builds its VirtualRig with (nothing started: the rig raises Built)."""
    import flowcurve.rig.virtual.rig as virtual_rig

    seen: dict = {}

    def fake_rig(*args, **kwargs):
        seen.update(kwargs)
        raise Built

    monkeypatch.setattr(virtual_rig, "VirtualRig", fake_rig)
    return seen


def in_process_geometry(test, **options) -> dict:
    """The geometry 'run' on the virtual rig in its own process makes of the same options."""
    return prepare(RunRequest(test, **options)).spec.geometry_mm


@pytest.mark.parametrize("argv, test, options", [
    ([], "tension", {}),
    (["--lc", "42"], "tension", {"lc": 42.0}),
    (["--d0", "8", "--l0", "40", "--lc", "56"], "tension", {"d0": 8.0, "l0": 40.0, "lc": 56.0}),
    (["--test", "compression", "--d0", "5", "--h0", "7.5"], "compression", {"d0": 5.0, "h0": 7.5}),
    (["--test", "compression"], "compression", {}),
])
def test_rig_virtual_builds_the_bar_run_would_build_in_process(tmp_path, built, argv, test, options):
    with pytest.raises(Built):
        main(["rig", "virtual", "--config", str(tmp_path / "v.toml"), *argv])
    specimen = built["specimen"]
    assert specimen == Specimen.from_geometry(test, in_process_geometry(test, **options))
    if "lc" in options:
        assert specimen.parallel_mm == options["lc"]


@pytest.mark.parametrize("argv, message", [
    (["--lc", "25"], "--lc 25 mm is shorter than the gauge length l0 30 mm"),  # the default bar's l0
    (["--l0", "40", "--lc", "35"], "--lc 35 mm is shorter than the gauge length l0 40 mm"),
    (["--d0", "-6"], "--d0 must be more than 0 and at most 30 mm"),
    (["--lc", "1e4"], "--lc must be more than 0 and at most 200 mm"),
    (["--h0", "nan", "--test", "compression"], "--h0 must be a positive number"),
])
def test_rig_virtual_refuses_a_bad_geometry_in_one_line_before_starting(tmp_path, capsys, built, argv, message):
    code = main(["rig", "virtual", "--config", str(tmp_path / "v.toml"), *argv])
    out, err = capsys.readouterr()
    assert code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err, err
    assert not built and not (tmp_path / "v.toml").exists()  # refused before any rig or file


def test_rig_virtual_notes_a_length_the_test_has_not(tmp_path, capsys, built):
    with pytest.raises(Built):
        main(["rig", "virtual", "--config", str(tmp_path / "v.toml"), "--test", "compression", "--lc", "40"])
    assert "--lc ignored: a compression specimen has no such length" in capsys.readouterr().err
    assert built["specimen"] == Specimen.compression()


def virtual_rig_config(tmp_path, specimen: Specimen):
    """The configuration file 'rig virtual' writes for a rig simulating ``specimen`` (in process)."""
    from flowcurve.rig.virtual.rig import VirtualRig

    with VirtualRig("steel45", test=specimen.test, specimen=specimen, clock=ModelClock(), link="inprocess",
                    tension_response="bridgman") as vr:
        path = tmp_path / "v.toml"
        path.write_text(to_toml(vr.config()))
    return path


def test_the_configuration_states_the_simulated_bar(tmp_path):
    path = virtual_rig_config(tmp_path, Specimen.tension(6.0, 30.0, parallel_length_mm=42.0))
    virtual = load_config(path).virtual
    assert virtual.test == "tension" and virtual.geometry_mm == {"d0_mm": 6.0, "l0_mm": 30.0, "parallel_length_mm": 42.0}
    path = virtual_rig_config(tmp_path, Specimen.compression())
    assert load_config(path).virtual.geometry_mm == {"d0_mm": 5.989, "h0_mm": 6.982}


@pytest.mark.parametrize("given, words", [
    ({"d0": 6.0, "l0": 30.0}, "Lc 30 mm here, 42 mm on the rig"),  # no --lc: the header's Lc is l0
    ({"d0": 6.0, "l0": 30.0, "lc": 36.0}, "Lc 36 mm here, 42 mm on the rig"),
    ({"d0": 8.0, "l0": 30.0, "lc": 42.0}, "d0 8 mm here, 6 mm on the rig"),
])
def test_run_config_warns_of_another_geometry_and_records_it(tmp_path, given, words):
    path = virtual_rig_config(tmp_path, Specimen.tension(6.0, 30.0, parallel_length_mm=42.0))
    setup = prepare(RunRequest("tension", target=0.5, **given), config=load_config(path))
    assert len(setup.warnings) == 1 and words in setup.warnings[0] and f"({path} [virtual])" in setup.warnings[0]
    assert setup.spec.opening_events == [("geometry_mismatch", setup.warnings[0])]


def test_run_config_with_the_rigs_geometry_says_nothing(tmp_path):
    path = virtual_rig_config(tmp_path, Specimen.tension(6.0, 30.0, parallel_length_mm=42.0))
    assert prepare(RunRequest("tension", d0=6.0, l0=30.0, lc=42.0), config=load_config(path)).warnings == ()
    path = virtual_rig_config(tmp_path, Specimen.tension())
    assert prepare(RunRequest("tension", d0=6.0, l0=30.0), config=load_config(path)).warnings == ()  # Lc = l0 on both
    warned = prepare(RunRequest("compression", d0=5.989, h0=6.982), config=load_config(path)).warnings
    assert warned and "simulates a tension specimen, not a compression one (d0 6 mm, l0 30 mm, Lc 30 mm)" in warned[0]


def test_a_real_rigs_configuration_has_no_virtual_table(tmp_path):
    from flowcurve.rig.config import virtual_config

    path = tmp_path / "rig.toml"
    path.write_text(to_toml(virtual_config({"loadcell": "/dev/null-a", "encoder": "/dev/null-b"})))
    config = load_config(path)
    assert config.virtual is None and "[virtual]" not in path.read_text()
    assert prepare(RunRequest("tension", d0=9.0, l0=45.0), config=config).warnings == ()


def test_the_opening_events_reach_the_record(tmp_path):
    """The procedure writes a spec's opening events (the mismatch) as the record opens."""
    from flowcurve.acquisition.session import run_virtual_test
    from flowcurve.record.format import read_record

    setup = prepare(RunRequest("tension", d0=6.0, l0=30.0, target=0.3, time_scale=20.0, tension_response="bridgman"))
    setup.spec.opening_events.append(("geometry_mismatch", "Lc 30 mm here, 42 mm on the rig"))
    run = run_virtual_test(setup.spec, tmp_path / "t.csv", material=setup.virtual_material, time_scale=20.0, clock=ModelClock(),
                           link="inprocess", tension_response="bridgman")
    events = read_record(run.outcome.path).events
    assert [(e.name, e.text) for e in events if e.name == "geometry_mismatch"] == [("geometry_mismatch", "Lc 30 mm here, 42 mm on the rig")]
    assert events[0].name == "geometry_mismatch"


# -- the process path: 'rig virtual' simulates the bar it was told --------------------------------

SPEED, TARGET, SCALE = "0.05", 1.0, 10.0


def truth(tmp_path, lc: float):
    """The in-process virtual rig's record of the same test on a bar of parallel length ``lc``."""
    from flowcurve.acquisition.session import run_virtual_test
    from flowcurve.record.format import read_record

    setup = prepare(RunRequest("tension", material="steel45", d0=6.0, l0=30.0, lc=lc, speed=float(SPEED), target=TARGET,
                               time_scale=SCALE, tension_response="bridgman"))
    run = run_virtual_test(setup.spec, tmp_path / f"truth-{lc:g}.csv", material="steel45", time_scale=SCALE, clock=ModelClock(),
                           link="inprocess", tension_response="bridgman")
    return read_record(run.outcome.path)


def crosshead_at(record, forces_N) -> np.ndarray:
    """Where the crosshead first was when the rising force reached ``forces_N`` (its running maximum)."""
    force, cross = np.asarray(record.column("force_N"), float), np.asarray(record.column("crosshead_mm"), float)
    top = int(np.argmax(force))
    rising = np.maximum.accumulate(force[: top + 1])
    return np.array([np.interp(f, rising, cross[: top + 1]) for f in forces_N])


def elastic_compliance(record) -> float:
    """mm/N: the crosshead against the force over the straight part (2 to 8 kN) — the frame's 1/C
    and the bar's Lc/(E·A)."""
    force, cross = np.asarray(record.column("force_N"), float), np.asarray(record.column("crosshead_mm"), float)
    top = int(np.argmax(force))
    keep = (force[:top] > 2000.0) & (force[:top] < 8000.0)
    return float(np.polyfit(force[:top][keep], cross[:top][keep], 1)[0])


@pytest.mark.pty
def test_rig_virtual_simulates_the_parallel_length_it_is_given(tmp_path, env, rig_process):
    """A 42 mm Lc bar in 'rig virtual', a test of the same geometry through 'run --config': the
    record is the in-process rig's 42 mm bar's (the truth), not the default 30 mm one's — the
    elastic line's compliance 1/C + Lc/(E·A) and, past yield, the crosshead at a force (plastic
    strain over Lc). Failed before: 'rig virtual' took no geometry and simulated its 30 mm bar."""
    rig = rig_process(time_scale=SCALE, options=("--material", "steel45", "--speed", SPEED, "--lc", "42"))
    assert any(line.startswith("specimen: tension bar d0 6 mm, l0 30 mm, Lc 42 mm") for line in rig.lines), rig.lines
    assert load_config(rig.config).virtual.parallel_length_mm == 42.0
    run = run_test(tmp_path, env, rig, "--lc", "42", "--speed", SPEED, "--target", TARGET)
    assert run.code in (0, 5), run.err
    assert "geometry_mismatch" not in [e.name for e in run.record.events] and "simulates another" not in run.err
    assert run.record.meta["specimen.parallel_length_mm"] == "42.0"
    t42, t30 = truth(tmp_path, 42.0), truth(tmp_path, 30.0)
    c, c42, c30 = elastic_compliance(run.record), elastic_compliance(t42), elastic_compliance(t30)
    assert abs(c - c42) < 0.3 * abs(c30 - c42), (c, c42, c30)
    levels = np.array([0.985, 0.995]) * float(np.max(t42.column("force_N")))  # past yield, below the target's force
    x, x42, x30 = crosshead_at(run.record, levels), crosshead_at(t42, levels), crosshead_at(t30, levels)
    assert np.all(np.abs(x - x42) < 0.3 * np.abs(x30 - x42)), (x, x42, x30)


@pytest.mark.pty
def test_run_config_against_another_bar_warns_and_records_it(tmp_path, env, rig_process):
    """The same 42 mm bar, a test stating Lc 30 (no --lc): one warning line naming both, the
    ``geometry_mismatch`` event in the record — and the numbers are the rig's bar's."""
    rig = rig_process(time_scale=SCALE, options=("--material", "steel45", "--speed", SPEED, "--lc", "42"))
    run = run_test(tmp_path, env, rig, "--speed", SPEED, "--target", "0.3")
    assert run.code in (0, 5), run.err
    warned = [line for line in run.err.splitlines() if line.startswith("flowcurve: warning: the virtual rig")]
    assert len(warned) == 1 and "Lc 30 mm here, 42 mm on the rig" in warned[0], run.err
    assert [e.name for e in run.record.events if e.name == "geometry_mismatch"] == ["geometry_mismatch"]

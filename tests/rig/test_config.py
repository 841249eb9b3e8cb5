"""Rig configuration: the example file loads; every kind of mistake names file and key."""

import tomllib
from pathlib import Path

import pytest

import flowcurve.rig as rig
from flowcurve.errors import ConfigError
from flowcurve.rig.config import load_config, parse_config, to_toml, virtual_config

EXAMPLE = Path(rig.__file__).with_name("example-rig.toml")


def write(tmp_path, text):
    path = tmp_path / "rig.toml"
    path.write_text(text)
    return path


MINIMAL = """
[loadcell]
port = "/dev/ttyUSB0"
nominal_load_N = 50000
[encoder]
port = "/dev/ttyUSB1"
[frame]
"""


def test_example_loads_with_documented_values():
    c = load_config(EXAMPLE)
    assert c.loadcell.parity == "E" and c.loadcell.address == 31
    assert c.encoder.counts_per_rev == 10_000 and c.frame.stiffness_N_per_um == 136.0
    assert c.furnace.max_temperature_C == 900.0 and c.furnace.watchdog_timeout_s == 10.0


def test_round_trip_through_toml():
    c = load_config(EXAMPLE)
    assert parse_config(tomllib.loads(to_toml(c)), str(EXAMPLE)) == c


def test_minimal_file_takes_defaults_and_no_furnace(tmp_path):
    c = load_config(write(tmp_path, MINIMAL))
    assert c.furnace is None
    assert c.loadcell.nominal_load_N == 50000.0 and isinstance(c.loadcell.nominal_load_N, float)
    assert c.encoder.address == 2 and c.encoder.screw_lead_mm == 100.0


@pytest.mark.parametrize("edit, message", [
    ("[loadcell]\nbogus = 1", r"\[loadcell\] bogus: unknown key"),
    ("[encoder]\ngear_ratio = \"2\"", r"\[encoder\] gear_ratio: must be a number, got str"),
    ("[encoder]\naddress = true", r"\[encoder\] address: must be an integer, got bool"),
    ("[encoder]\nchecksum = 1", r"\[encoder\] checksum: must be true or false"),
    ("[encoder]\nscrew_lead_mm = -5", r"\[encoder\] screw_lead_mm: must be in 0.0 < x <= 1000.0, got -5.0"),
    ("[loadcell]\nparity = \"X\"", r"\[loadcell\] parity: must be one of N, E, O, got 'X'"),
    ("[loadcell]\nbaud = 9601", r"\[loadcell\] baud: must be one of"),
    ("[loadcell]\noutput_format = 13", r"\[loadcell\] output_format: unknown COF output format 13"),
    ("[furnace]\nport = \"/dev/ttyUSB2\"\nmax_temperature_C = 2000", r"\[furnace\] max_temperature_C: must be in"),
    ("[furnace]\nport = \"/dev/ttyUSB2\"\nwatchdog_timeout_s = 60", r"\[furnace\] watchdog_timeout_s"),
    ("[furnace]\nport = \"/dev/ttyUSB0\"", r"two devices share one port"),
    ("[furnace]\nmax_temperature_C = 800", r"\[furnace\] port: missing"),
    ("[loadcell]\ncalibration_N_per_count = 0.01", r"give exactly one of nominal_load_N and calibration"),
    ("[heater]\nx = 1", r"\[heater\]: unknown section"),
    # [virtual]: 'rig virtual' states the bar it simulates; a hand-edited one is checked too
    ("[virtual]\nd0_mm = 6", r"\[virtual\] l0_mm: missing \(a tension specimen's\)"),
    ("[virtual]\ntest = \"compression\"\nd0_mm = 6\nh0_mm = 9\nl0_mm = 30", r"\[virtual\] l0_mm: not a compression specimen's length"),
    ("[virtual]\nd0_mm = 6\nl0_mm = 30\nparallel_length_mm = 25", r"\[virtual\] parallel_length_mm: must be at least l0_mm"),
    ("[virtual]\ntest = \"torsion\"\nd0_mm = 6", r"\[virtual\] test: must be one of tension, compression"),
    ("[virtual]\nd0_mm = 0\nl0_mm = 30", r"\[virtual\] d0_mm: must be in 0.0 < x"),
])
def test_mistakes_name_file_and_key(tmp_path, edit, message):
    # merge the edit into the minimal file, section by section
    doc = tomllib.loads(MINIMAL)
    for section, table in tomllib.loads(edit).items():
        doc.setdefault(section, {}).update(table)
    text = to_toml_like(doc)
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=rf"^{path}: .*{message}"):
        load_config(path)


def to_toml_like(doc):
    out = []
    for section, table in doc.items():
        out.append(f"[{section}]")
        for k, v in table.items():
            out.append(f"{k} = " + (f'"{v}"' if isinstance(v, str) else str(v).lower() if isinstance(v, bool) else repr(v)))
    return "\n".join(out) + "\n"


def test_the_virtual_table_round_trips_and_a_real_rig_has_none(tmp_path):
    doc = tomllib.loads(MINIMAL + "[virtual]\ntest = \"tension\"\nd0_mm = 6\nl0_mm = 30\nparallel_length_mm = 42\n")
    c = parse_config(doc, "v.toml")
    assert c.virtual.geometry_mm == {"d0_mm": 6.0, "l0_mm": 30.0, "parallel_length_mm": 42.0}
    assert parse_config(tomllib.loads(to_toml(c)), "v.toml") == c
    assert load_config(EXAMPLE).virtual is None and "[virtual]" not in to_toml(load_config(EXAMPLE))


def test_missing_section_and_file_and_bad_toml(tmp_path):
    with pytest.raises(ConfigError, match=r"\[encoder\]: missing section"):
        load_config(write(tmp_path, '[loadcell]\nport="a"\nnominal_load_N=1\n[frame]\n'))
    with pytest.raises(ConfigError, match="no such rig configuration file"):
        load_config(tmp_path / "nope.toml")
    with pytest.raises(ConfigError, match=r"not valid TOML: .*line 2"):
        load_config(write(tmp_path, "[loadcell]\nport = \n"))


def test_virtual_config_takes_the_virtual_rigs_keywords():
    ports = {"loadcell": "/dev/pts/7", "encoder": "/dev/pts/8", "furnace": "/dev/pts/9"}
    c = virtual_config(ports=ports, frame_stiffness_N_per_um=120.0, nominal_load_N=50e3,
                       loadcell_address=5, furnace_address=3, encoder_address=4, checksum=True,
                       furnace_max_temperature_C=500.0)
    assert (c.loadcell.port, c.encoder.port, c.furnace.port) == ("/dev/pts/7", "/dev/pts/8", "/dev/pts/9")
    assert c.frame.stiffness_N_per_um == 120.0 and c.loadcell.nominal_load_N == 50e3
    assert (c.loadcell.address, c.furnace.address, c.encoder.address) == (5, 3, 4)
    assert c.encoder.checksum and c.furnace.checksum and c.furnace.max_temperature_C == 500.0
    with pytest.raises(ConfigError, match=r"^<virtual>: \[furnace\] max_temperature_C: must be in"):
        virtual_config(ports, furnace_max_temperature_C=-1)
    with pytest.raises(ConfigError, match="unknown override"):
        virtual_config(ports, speed=3)


def test_devices_built_from_config_carry_its_settings():
    c = load_config(EXAMPLE)
    lc, enc, fur = c.loadcell.create(), c.encoder.create(), c.furnace.create()
    assert lc.transport.settings["parity"] == "E" and lc.nominal_load_N == 100000.0
    assert enc.screw_lead_mm == 100.0 and enc.transport.url == "/dev/ttyUSB1"
    assert fur.max_temperature_C == 900.0 and fur.transport.timeout_s == 0.3
    ctl = c.furnace.controller(fur, 600.0)
    assert ctl.max_rate_C_per_s == pytest.approx(0.5)

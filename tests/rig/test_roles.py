"""Device roles (rig.roles): the drivers fill their role's Protocol, the acquisition types against
the roles, and the rig file names each device's model from a registry (default: today's drivers)."""

from __future__ import annotations

import tomllib
import typing

import pytest

from flowcurve.acquisition.session import DriverRig
from flowcurve.errors import ConfigError
from flowcurve.rig import roles
from flowcurve.rig.config import load_config, parse_config, to_toml, virtual_config
from flowcurve.rig.encoder import CrossheadEncoder
from flowcurve.rig.furnace import Furnace, TemperatureController
from flowcurve.rig.loadcell import LoadCell
from flowcurve.rig.roles import ForceDevice, PositionDevice, TemperatureDevice

from .test_config import EXAMPLE

PORTS = {"loadcell": "loop://a", "encoder": "loop://b", "furnace": "loop://c"}


def test_each_driver_fills_its_role_and_no_other():
    devices = {"force": LoadCell("loop://", nominal_load_N=1e5), "position": CrossheadEncoder("loop://"),
               "temperature": Furnace("loop://")}
    for role, device in devices.items():
        for other, protocol in roles.ROLES.items():
            assert isinstance(device, protocol) == (other == role), (role, other)


def test_the_virtual_rigs_devices_through_the_configured_drivers_fill_their_roles(rig_factory):
    """The virtual twins are read through the drivers the rig file names: each answers through its
    role's methods alone."""
    vr = rig_factory(time_scale=1.0)
    rig = DriverRig(vr.config(), virtual=vr)
    assert isinstance(rig.loadcell, ForceDevice) and isinstance(rig.encoder, PositionDevice)
    with rig.loadcell as force, rig.encoder as position:
        force.configure(**vr.config().loadcell.settings)
        assert abs(force.read().force_N) < 100.0  # idle machine: noise around zero
        position.zero()
        assert position.position_mm() == pytest.approx(0.0, abs=0.02)
    assert isinstance(rig.furnace, TemperatureDevice)
    with rig.furnace as furnace:
        assert 0.0 < furnace.temperature_C() < furnace.max_temperature_C and furnace.heater_off()


def test_the_acquisition_types_against_the_roles():
    hints = typing.get_type_hints(DriverRig)
    assert hints["loadcell"] is ForceDevice and hints["encoder"] is PositionDevice
    assert hints["furnace"] == typing.Optional[TemperatureDevice]
    assert typing.get_type_hints(TemperatureController.__init__)["furnace"] is TemperatureDevice


def test_existing_rig_files_name_no_model_and_get_todays_drivers():
    config = load_config(EXAMPLE)
    assert (config.loadcell.model, config.encoder.model, config.furnace.model) == ("hbm-aed", "dcon-encoder", "dcon-i7011")
    assert parse_config({**_data(), "loadcell": {"port": "loop://a", "nominal_load_N": 1e5, "model": "hbm-aed"}}) \
        == parse_config(_data())  # naming the default is the same rig
    rig = DriverRig(config)
    assert (type(rig.loadcell), type(rig.encoder), type(rig.furnace)) == (LoadCell, CrossheadEncoder, Furnace)
    assert rig.loadcell_period_s == pytest.approx(1 / 100.0)  # rate_code 0: 100 values/s
    assert parse_config(tomllib.loads(to_toml(config)), str(EXAMPLE)) == config


class ToyAmplifier(LoadCell):
    """A force model with another rate table (what the session must ask the device for)."""

    @staticmethod
    def supported_rates_Hz():
        return (400.0, 200.0)


def _data():
    return {"loadcell": {"port": "loop://a", "nominal_load_N": 1e5}, "encoder": {"port": "loop://b"}, "frame": {}}


def test_a_registered_model_is_named_in_the_rig_file_and_sets_the_force_period(monkeypatch):
    monkeypatch.setitem(roles.MODELS["force"], "toy-amp", ToyAmplifier)
    data = _data()
    data["loadcell"].update(model="toy-amp", rate_code=1)
    rig = DriverRig(parse_config(data, "toy.toml"))
    assert type(rig.loadcell) is ToyAmplifier
    assert rig.loadcell_period_s == pytest.approx(1 / 200.0)  # the device's table, not the AED's (50 values/s)


def test_an_unknown_model_is_one_line_naming_the_file_section_and_the_known_models():
    data = _data()
    data["encoder"]["model"] = "laser"
    with pytest.raises(ConfigError, match=r"^rig\.toml: \[encoder\] model: must be one of dcon-encoder, got 'laser'$"):
        parse_config(data, "rig.toml")


def test_the_virtual_configuration_takes_a_model_override(monkeypatch):
    monkeypatch.setitem(roles.MODELS["force"], "toy-amp", ToyAmplifier)
    config = virtual_config(PORTS, loadcell_model="toy-amp")
    assert config.loadcell.model == "toy-amp" and config.furnace.model == "dcon-i7011"


@pytest.mark.parametrize("cof, nominal_N, nov, expected_N", [
    (3, 100_000.0, 0, 0.1),          # ASCII: nominal load reads 1 000 000 (the manual's COF3 range)
    (3, 100_000.0, 50_000, 2.0),     # ASCII with NOV set: the nominal load reads NOV counts
    (4, 10_000.0, 0, 10_000.0 / 5_120_000),  # binary 4-byte: 5 120 000 counts at the nominal load
])
def test_the_force_devices_resolution_is_one_count_of_its_output(cof, nominal_N, nov, expected_N):
    """The procedure's noise floor asks the force device (``resolution_N``), not the AED driver's
    internals: one count of the output format, by hand from the manual's nominal counts."""
    cell = LoadCell("loop://", nominal_load_N=nominal_N, output_format=cof)
    cell.nov = nov
    assert cell.resolution_N() == pytest.approx(expected_N, rel=1e-12)


def test_rig_check_knows_no_device_model():
    """`flowcurve rig check` prints what each driver says of itself (check_lines) and probes through
    answers/probe_parities: the CLI's module names no codec, so a new device is its driver and its
    registry line (docs/extending.md)."""
    import ast
    from pathlib import Path

    import flowcurve.cli.rig as cli_rig

    tree = ast.parse(Path(cli_rig.__file__).read_text(encoding="utf-8"))
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module}
    imported |= {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    assert not [m for m in imported if ".codecs" in m or m.endswith((".loadcell", ".encoder", ".furnace"))], imported
    for cls in (LoadCell, CrossheadEncoder, Furnace):
        assert callable(getattr(cls, "check_lines")) and callable(getattr(cls, "answers")) and cls.probe_parities

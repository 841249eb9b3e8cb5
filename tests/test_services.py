"""The application services (issue 44): a refused value names its request field, in the words
``flowcurve`` prints for the same option, so the console ties it to its form field."""

from __future__ import annotations

import pytest

from flowcurve.cli import main
from flowcurve.services import FieldError
from flowcurve.services.card import CardRequest
from flowcurve.services.fit import FitRequest
from flowcurve.services.run import RunRequest, field_errors, prepare


def _cli_error(argv: list[str], capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("flowcurve: error: ")
    return err[len("flowcurve: error: "):]


@pytest.mark.parametrize("field, option, value", [
    ("d0", "--d0", -2.0), ("h0", "--h0", 0.0), ("speed", "--speed", 1e9), ("target", "--target", -1.0),
    ("force_limit", "--force-limit", 2e5), ("soak", "--soak", 1e12), ("E_MPa", "--E", -5.0), ("temperature", "--temperature", 5000.0),
    ("time_scale", "--time-scale", -1.0),
])
def test_a_refused_run_value_names_its_field_with_runs_words(field, option, value, capsys, tmp_path):
    request = RunRequest("compression", **{field: value})
    with pytest.raises(FieldError) as caught:
        prepare(request)
    assert caught.value.field == field and set(caught.value.errors) == {field}
    assert str(caught.value) == _cli_error(["run", "compression", "--quiet", option, str(value), "--out", str(tmp_path / "r.csv")], capsys)
    assert not (tmp_path / "r.csv").exists()


def test_field_errors_lists_every_refused_value_at_once_and_a_good_request_none():
    bad = RunRequest("compression", d0=-2.0, speed=1e9, fault=["loadcell:nonsense"])
    assert set(field_errors(bad, virtual=True)) == {"d0", "speed", "fault"}
    assert field_errors(RunRequest("compression", d0=6.0, h0=9.0, speed=0.05), virtual=True) == {}
    setup = prepare(RunRequest("compression", d0=6.0, h0=9.0, speed=0.05, post=["post.hk_mm=7"]))
    assert setup.spec.geometry_mm == {"d0_mm": 6.0, "h0_mm": 9.0} and setup.spec.post == {"post.hk_mm": 7.0}
    assert setup.virtual_material == "steel45" and setup.time_scale == 15.0


def test_a_missing_geometry_and_a_bad_post_value_name_their_fields():
    from flowcurve.rig.config import virtual_config

    config = virtual_config({"loadcell": "/dev/null-a", "encoder": "/dev/null-b", "furnace": "/dev/null-c"})
    with pytest.raises(FieldError) as caught:
        prepare(RunRequest("tension", l0=30.0), config=config)
    assert caught.value.field == "d0" and "give --d0" in caught.value.message
    with pytest.raises(FieldError) as caught:
        prepare(RunRequest("tension", post=["post.lu_mm=-1"]))
    assert caught.value.field == "post"


@pytest.mark.parametrize("request_, field", [
    (FitRequest(["x.csv"], method="best"), "method"),
    (CardRequest("fit.json", "nastran"), "format"),
    (CardRequest("fit.json", "lsdyna", units="furlongs"), "units"),
])
def test_fit_and_card_requests_refuse_unknown_choices_by_field(request_, field):
    with pytest.raises(FieldError) as caught:
        request_.check()
    assert caught.value.field == field and "invalid choice" in caught.value.message

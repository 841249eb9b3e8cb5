"""The specimen options (flowcurve/cli/specimen.py) mean the same in `run` and `identify`."""

import pytest

from flowcurve.cli import build_parser, main


def _option(parser, command, flag):
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return next(a for a in sub._actions if flag in a.option_strings)


@pytest.mark.parametrize("flag", ["--d0", "--l0", "--h0", "--E"])
def test_run_and_identify_declare_the_option_alike(flag):
    parser = build_parser()
    run, identify = _option(parser, "run", flag), _option(parser, "identify", flag)
    assert (run.dest, run.type, run.metavar) == (identify.dest, identify.type, identify.metavar)
    assert run.metavar == ("MPA" if flag == "--E" else "MM")


@pytest.mark.parametrize("flag, value", [("--d0", "-6"), ("--l0", "0"), ("--E", "nan")])
def test_identify_refuses_a_non_positive_value_naming_the_option(flag, value, capsys, tmp_path):
    record = tmp_path / "r.csv"
    record.write_text("time_s,force_N\n0,0\n")
    code = main(["identify", str(record), "--out", str(tmp_path / "out"), flag, value])
    err = capsys.readouterr().err
    assert code != 0 and f"{flag} must be a positive number" in err and err.count("\n") == 1

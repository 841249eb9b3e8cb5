"""The specimen options (flowcurve/cli/specimen.py) mean the same in `run` and `identify`."""

import pytest

from flowcurve.cli import build_parser, main


def _option(parser, command, flag):
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return next(a for a in sub._actions if flag in a.option_strings)


@pytest.mark.parametrize("flag", ["--d0", "--l0", "--lc", "--h0", "--E"])
def test_run_and_identify_declare_the_option_alike(flag):
    parser = build_parser()
    run, identify = _option(parser, "run", flag), _option(parser, "identify", flag)
    assert (run.dest, run.type, run.metavar) == (identify.dest, identify.type, identify.metavar)
    assert run.metavar == ("MPA" if flag == "--E" else "MM")


@pytest.mark.parametrize("flag, value", [("--d0", "-6"), ("--l0", "0"), ("--lc", "-42"), ("--E", "nan")])
def test_identify_refuses_a_non_positive_value_naming_the_option(flag, value, capsys, tmp_path):
    record = tmp_path / "r.csv"
    record.write_text("time_s,force_N\n0,0\n")
    code = main(["identify", str(record), "--out", str(tmp_path / "out"), flag, value])
    err = capsys.readouterr().err
    assert code != 0 and f"{flag} must be a positive number" in err and err.count("\n") == 1


def test_identify_refuses_a_parallel_length_shorter_than_the_given_l0_naming_lc(capsys, tmp_path):
    record = tmp_path / "r.csv"
    record.write_text("time_s,force_N\n0,0\n")
    code = main(["identify", str(record), "--out", str(tmp_path / "out"), "--l0", "30", "--lc", "25"])
    err = capsys.readouterr().err
    assert code != 0 and "--lc 25 mm is shorter than the gauge length l0 30 mm" in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()  # refused before any record was read


def test_identify_refuses_a_parallel_length_shorter_than_the_records_l0(capsys, tmp_path):
    """The INSTRON export states L0 25 mm (and Lc 30): --lc 20 would refer the crosshead's strain to
    20 mm, the gauge marks lying beyond the parallel length; the record's L0 is read, so it is refused."""
    from tests.identify.conftest import INSTRON_FILE

    code = main(["identify", str(INSTRON_FILE), "--out", str(tmp_path / "out"), "--no-plots", "--lc", "20"])
    first = capsys.readouterr().err.splitlines()[0]
    assert code != 0 and "'specimen.parallel_length_mm' = 20 mm is shorter than 'specimen.l0_mm' = 25 mm" in first, first
    assert "--lc" in first and "Traceback" not in first

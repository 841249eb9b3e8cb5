"""Diagnostics go through the logging module: record events are logged, the command line
sets the level, device failures on the way out are logged instead of swallowed, and no
`except ...: pass` is left in the package."""

import ast
import logging
from pathlib import Path

import numpy as np
import pytest

from flowcurve.cli import main
from flowcurve.errors import DeviceError
from flowcurve.log import configure, level_name
from flowcurve.record.format import RecordWriter, read_record
from flowcurve.rig.furnace import HEATER_OFF_ATTEMPTS, Furnace

ROOT = Path(__file__).resolve().parents[1]
PACKAGE_FOLDERS = ["flowcurve", "rig", "acquisition", "record", "identification", "reports"]


def test_record_events_are_logged_as_written(tmp_path, caplog):
    caplog.set_level(logging.INFO, logger="flowcurve.record.format")
    with RecordWriter(tmp_path / "r.csv", {"test": "tension"}, ["time_s", "force_N", "crosshead_mm"]) as writer:
        writer.append_rows(np.zeros((3, 3)))
        writer.event(1.25, "heater_on", "set-point 600 C")
    written = read_record(tmp_path / "r.csv").events
    logged = [r.getMessage() for r in caplog.records if r.name == "flowcurve.record.format"]
    assert [(e.time_s, e.name, e.text) for e in written] == [(1.25, "heater_on", "set-point 600 C")]
    assert any("1.250 s heater_on set-point 600 C" in m for m in logged)
    assert any("complete, 3 samples" in m for m in logged)


@pytest.mark.parametrize("verbose, option, level", [(0, None, "WARNING"), (1, None, "INFO"), (2, None, "DEBUG"),
                                                    (5, None, "DEBUG"), (2, "error", "ERROR")])
def test_verbosity_to_level(verbose, option, level):
    assert level_name(verbose, option) == level


def test_the_command_line_sends_log_messages_to_stderr(tmp_path, capsys):
    path = tmp_path / "r.csv"
    with RecordWriter(path, {"test": "tension"}, ["time_s", "force_N", "crosshead_mm"]) as writer:
        writer.append_rows(np.zeros((2, 3)))
    try:
        assert main(["annotate", str(path), "--set", "operator=Ivanov", "-v"]) == 0
        assert logging.getLogger("flowcurve").getEffectiveLevel() == logging.INFO
        logging.getLogger("flowcurve.rig.furnace").info("seen on stderr")
        assert "INFO flowcurve.rig.furnace: seen on stderr" in capsys.readouterr().err
        assert main(["--log-level", "error", "annotate", str(path), "--set", "operator=Petrov"]) == 0
        logging.getLogger("flowcurve.rig.furnace").warning("not shown")
        assert "not shown" not in capsys.readouterr().err
    finally:
        configure("WARNING")


class _DeadFurnace(Furnace):
    """A furnace whose output writes fail like a module that went silent."""

    def __init__(self, error):
        super().__init__("loop://")
        self.error = error

    def _write_outputs(self, mask):
        raise self.error


def test_heater_off_logs_each_failed_attempt_and_returns_false(caplog):
    caplog.set_level(logging.WARNING, logger="flowcurve.rig.furnace")
    assert _DeadFurnace(DeviceError("furnace", "no reply to '@01DO00'")).heater_off() is False
    attempts = [r for r in caplog.records if "heater off, attempt" in r.getMessage()]
    assert len(attempts) == HEATER_OFF_ATTEMPTS and "no reply" in attempts[0].getMessage()


def test_heater_off_does_not_swallow_a_bug():
    with pytest.raises(TypeError):
        _DeadFurnace(TypeError("unsupported operand")).heater_off()


def _silent_handlers(path: Path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ExceptHandler) and all(isinstance(s, ast.Pass) for s in node.body):
            names = [] if node.type is None else [n.id for n in ast.walk(node.type) if isinstance(n, ast.Name)]
            if node.type is None or {"Exception", "BaseException"} & set(names):
                yield node.lineno


def test_no_broad_exception_is_silently_passed():
    bad = [f"{p.relative_to(ROOT)}:{line}" for folder in PACKAGE_FOLDERS for p in sorted((ROOT / folder).rglob("*.py"))
           for line in _silent_handlers(p)]
    assert not bad, "except Exception: pass (catch what can happen and log it): " + ", ".join(bad)


def test_the_silent_handler_check_can_fail(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text("try:\n    x = 1\nexcept Exception:\n    pass\ntry:\n    y = 2\nexcept KeyError:\n    pass\n")
    assert list(_silent_handlers(sample)) == [3]

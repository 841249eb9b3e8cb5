"""Running the real command in-process for the records tests: exit code, stdout, stderr."""

from __future__ import annotations

from flowcurve.cli import main


def run_cli(capsys, argv: list[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def one_error(code: int, out: str, err: str) -> str:
    """The single 'flowcurve: error:' line of a failed run (no traceback, no internal error)."""
    assert code != 0
    lines = [line for line in err.splitlines() if line.startswith("flowcurve: error:")]
    assert len(lines) == 1 and "Traceback" not in err + out and "internal error" not in err, err
    return lines[0]

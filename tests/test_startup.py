"""`flowcurve --help` stays fast: building the command's parser imports none of the heavy
libraries (they are imported inside the code that uses them). Timing is in
bench/cli_startup.py; here only what is imported is checked."""

import subprocess
import sys

HEAVY = ("pandas", "scipy", "lmfit", "matplotlib", "serial")


def test_the_parser_imports_no_heavy_library():
    code = ("import sys; from flowcurve.cli import build_parser; build_parser(); "
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == []


def test_a_heavy_import_is_seen():
    """The check above can fail: a module that imports pandas shows in sys.modules."""
    code = ("import sys; import flowcurve.identification.tension; "
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pandas" in out.stdout.split()


def test_the_fit_command_states_the_series_fits_default():
    """`flowcurve fit --help` names the default without importing the fit; the two agree."""
    from flowcurve.cli.series import DEFAULT_MAX_POINTS, DEFAULT_SHAPE_ERROR_PCT
    from flowcurve.identification.series import MAX_POINTS
    from flowcurve.identification.series_fit import SHAPE_ERROR_PCT

    assert DEFAULT_MAX_POINTS == MAX_POINTS and DEFAULT_SHAPE_ERROR_PCT == SHAPE_ERROR_PCT

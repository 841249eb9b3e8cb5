"""`flowcurve --help` stays fast: building the command's parser, and the help of the command and
of every sub-command, import none of the heavy libraries (numpy included: they are imported
inside the code that uses them). Timing is in bench/cli_startup.py; here only what is imported
is checked."""

import importlib
import json
import subprocess
import sys

import pytest

from flowcurve.cli import choices

HEAVY = ("numpy", "pandas", "scipy", "lmfit", "matplotlib", "serial")

# in a fresh process: the help of the command and of every (sub-)sub-command, one after the
# other; prints {command: heavy libraries it imported first} as JSON
HELP_RUNNER = f"""
import argparse, contextlib, io, json, sys
from flowcurve.cli import build_parser, main

def commands(parser, words=()):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*words, name)
                yield from commands(sub, (*words, name))

seen = {{}}
for words in [(), *commands(build_parser())]:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):
        main([*words, "--help"])
    seen[" ".join(("flowcurve", *words))] = [m for m in {HEAVY!r} if m in sys.modules]
print(json.dumps(seen))
"""


def _heavy_after(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout


def test_the_parser_imports_no_heavy_library():
    code = ("import sys; from flowcurve.cli import build_parser; build_parser(); "
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))")
    assert _heavy_after(code).strip() == "[]"


def test_the_help_of_every_command_imports_no_heavy_library():
    seen = json.loads(_heavy_after(HELP_RUNNER))
    assert {"flowcurve", "flowcurve identify", "flowcurve run", "flowcurve rig check", "flowcurve friction"} <= set(seen)
    assert {command: heavy for command, heavy in seen.items() if heavy} == {}


def test_a_heavy_import_is_seen():
    """The checks above can fail: a module that imports numpy and pandas shows in sys.modules."""
    code = ("import sys; import flowcurve.identification.tension.identify; "
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    assert {"numpy", "pandas"} <= set(_heavy_after(code).split())


@pytest.mark.parametrize("name", sorted(choices.SOURCES))
def test_the_parser_shows_what_the_packages_publish(name):
    """The choices and defaults written in flowcurve/cli/choices.py (so that --help need not
    import their packages) are those the packages publish."""
    module, attribute = choices.SOURCES[name]
    published = getattr(importlib.import_module(module), attribute)
    shown = getattr(choices, name)
    assert shown == (published if isinstance(published, float) else tuple(published)), \
        f"flowcurve/cli/choices.py {name} differs from {module}.{attribute}: write the new value there"


def test_the_fit_command_states_the_series_fits_default():
    """`flowcurve fit --help` names the default without importing the fit; the two agree."""
    from flowcurve.cli.series import DEFAULT_MAX_POINTS, DEFAULT_SHAPE_ERROR_PCT
    from flowcurve.identification.series.series import MAX_POINTS
    from flowcurve.identification.series.fit import SHAPE_ERROR_PCT

    assert DEFAULT_MAX_POINTS == MAX_POINTS and DEFAULT_SHAPE_ERROR_PCT == SHAPE_ERROR_PCT

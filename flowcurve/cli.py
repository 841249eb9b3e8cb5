"""The ``flowcurve`` command: a thin dispatcher over the packages' own sub-commands.

Each package contributes its sub-commands through a module ``<package>/cli.py`` with a
function ``register(subparsers)`` that adds parsers and sets ``func`` on them. ``func(args)``
returns the exit code. Errors derived from :class:`~flowcurve.errors.FlowcurveError` are
printed as one line; an operator never sees a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from flowcurve import __version__
from flowcurve.errors import FlowcurveError

# Packages that contribute sub-commands, in the order they appear in --help.
COMMAND_MODULES = (
    "acquisition.cli",  # run, demo, recover, annotate
    "identification.cli",  # identify
    "identification.series_cli",  # fit
    "reports.cli",  # card, report
    "rig.cli",  # rig check, rig virtual
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="flowcurve",
        description=(
            "Tension and compression tests on a screw-driven testing machine: run them on the "
            "rig (or the virtual rig), record them, identify true stress-strain curves, "
            "Johnson-Cook and friction constants, and write material cards for FE solvers."
        ),
        epilog="Start with 'flowcurve demo': a virtual tension and compression test, identified.",
    )
    parser.add_argument("--version", action="version", version=f"flowcurve {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # that package has no commands yet
                continue
            raise
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except FlowcurveError as exc:
        print(f"flowcurve: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("flowcurve: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    raise SystemExit(main())

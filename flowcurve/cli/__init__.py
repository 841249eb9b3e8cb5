"""The ``flowcurve`` command: a thin dispatcher over the packages' own sub-commands.

This is the application layer: the only place where the layers (rig, acquisition, record,
identification, reports) meet. Each module ``flowcurve/cli/<layer>.py`` has a function
``register(subparsers)`` that adds parsers and sets ``func`` on them; a module that fails to
import is an error, never a silently missing command. ``func(args)``
returns the exit code. Errors derived from :class:`~flowcurve.errors.FlowcurveError` are
printed as one line; an operator never sees a traceback. ``-v``/``-vv``/``--log-level``
(before or after the sub-command) show the modules' log messages on standard error.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from flowcurve import __version__
from flowcurve.errors import FlowcurveError
from flowcurve.log import LOG_LEVELS, configure, level_name

# Packages that contribute sub-commands, in the order they appear in --help.
COMMAND_MODULES = (
    "flowcurve.cli.acquisition",  # run, demo, recover, annotate
    "flowcurve.cli.identification",  # identify
    "flowcurve.cli.series",  # fit
    "flowcurve.cli.reports",  # card, report
    "flowcurve.cli.rig",  # rig check, rig virtual
    "flowcurve.cli.friction",  # friction, friction-demo
    "flowcurve.cli.console",  # console
    "flowcurve.cli.fe",  # verify
)


def build_parser() -> argparse.ArgumentParser:
    """The ``flowcurve`` argument parser with every subcommand registered."""
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
        importlib.import_module(name).register(subparsers)
    _add_logging_options(parser, top=True)
    return parser


def _add_logging_options(parser: argparse.ArgumentParser, *, top: bool) -> None:
    """-v and --log-level on the command and on every sub-command; a sub-command's defaults
    are SUPPRESS, so an option given before the sub-command is kept."""
    parser.add_argument("-v", "--verbose", action="count", default=0 if top else argparse.SUPPRESS,
                        help="show what the modules log: -v steps and record events, -vv details")
    parser.add_argument("--log-level", type=str.upper, choices=LOG_LEVELS, default=None if top else argparse.SUPPRESS,
                        help="log level (overrides -v; default WARNING)")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                _add_logging_options(sub, top=False)


def main(argv: list[str] | None = None) -> int:
    """Run ``flowcurve`` with ``argv`` (None: sys.argv); the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    configure(level_name(args.verbose, args.log_level))
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

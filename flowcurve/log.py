"""Diagnostics through the standard :mod:`logging` module.

Every module logs to its own ``logging.getLogger(__name__)`` (all under ``flowcurve``); the
record writer also logs each ``# event:`` line it writes. Nothing is configured on import: a
program that uses flowcurve as a library decides where the messages go. The command line
calls :func:`configure` (``--log-level``, ``-v``/``-vv``): messages to the standard error
stream, warnings and errors by default.
"""

from __future__ import annotations

import logging
import sys

LOG_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")
FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


class _CurrentStderr(logging.StreamHandler):
    """Writes to whatever ``sys.stderr`` is when a message comes (a test may swap it)."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)

    @property
    def stream(self):
        """The current sys.stderr (so a redirected stderr is followed)."""
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:  # StreamHandler.__init__ sets it; the property decides
        """Ignore the stream StreamHandler sets: the property reads sys.stderr."""
        pass


def level_name(verbose: int = 0, log_level: str | None = None) -> str:
    """``--log-level`` wins; else WARNING, INFO with ``-v``, DEBUG with ``-vv``."""
    if log_level:
        return log_level.upper()
    return LOG_LEVELS[max(0, 2 - min(verbose, 2))]


def configure(level: str = "WARNING") -> logging.Logger:
    """Send the ``flowcurve`` loggers' messages at ``level`` and above to standard error
    (once; a second call only changes the level)."""
    root = logging.getLogger("flowcurve")
    root.setLevel(level)
    if not any(isinstance(h, _CurrentStderr) for h in root.handlers):
        handler = _CurrentStderr()
        handler.setFormatter(logging.Formatter(FORMAT, datefmt="%H:%M:%S"))
        root.addHandler(handler)
    return root

"""Errors a user can act on.

Every error the suite raises on purpose derives from :class:`FlowcurveError`; the command
line prints it as one line (``flowcurve: error: ...``) and exits non-zero, never with a
traceback. The message must name what is wrong and where: the file (line, column), the
device, the configuration key.
"""

from __future__ import annotations


class FlowcurveError(Exception):
    """An error reported to the user as one line, with exit code 2."""

    exit_code = 2


class RecordError(FlowcurveError):
    """A record file that cannot be read or lacks what is needed.

    The message names the file and, where it applies, the line (1-based) and the column.
    """

    def __init__(self, path, message: str, line: int | None = None, column: str | None = None):
        self.path = str(path)
        self.line = line
        self.column = column
        where = self.path
        if line is not None:
            where += f", line {line}"
        if column is not None:
            where += f", column '{column}'"
        super().__init__(f"{where}: {message}")


class IdentificationError(FlowcurveError):
    """The data cannot give the requested result (e.g. inputs outside a method's range)."""


class ConfigError(FlowcurveError):
    """A rig configuration that is missing, malformed or out of range (names the key)."""


class DeviceError(FlowcurveError):
    """A device that does not answer, answers wrongly or reports a fault (names the device)."""

    exit_code = 3

    def __init__(self, device: str, message: str):
        self.device = device
        super().__init__(f"{device}: {message}")


class SafetyError(DeviceError):
    """Over-temperature, open thermocouple, stuck heater: the heating was stopped."""

    exit_code = 4  # set apart from device faults (README "Exit codes")


class InternalError(FlowcurveError):
    """A bug in flowcurve (a TypeError in a driver, say), not a device or input failure:
    the test stops safely and the message says to report it."""

    exit_code = 70  # EX_SOFTWARE


class MissingValueError(RecordError):
    """A value a record lacks (one of the metadata ``keys``); the message says how to give it.

    The command line, which knows its options, rephrases it with :meth:`message_with` so that
    the option (``--d0``) is named as well as the header key.
    """

    def __init__(self, path, keys, what: str | None = None, line: int | None = None, column: str | None = None):
        self.keys = tuple(keys)
        self.what = what
        super().__init__(path, self.explain(), line=line, column=column)

    def explain(self, givers: list[str] | None = None) -> str:
        """The message without the file: what is missing, and every way to give it."""
        keys = " or ".join(f"'{k}'" for k in self.keys)
        text = f"required metadata {keys} is missing"
        if self.what:
            text = f"{self.what}: {text}"
        how = " or ".join(givers) if givers else "give it as an option"
        return f"{text} (add '# {self.keys[0]}: <value>' to the header or {how})"

    def message_with(self, givers: list[str]) -> str:
        """The whole one-line message (file, line, column) naming ``givers`` (e.g. ``['give --d0']``)."""
        return str(self).removesuffix(self.explain()) + self.explain(givers)


# -- how a test run ends: the exit codes of ``flowcurve run`` / ``demo`` (README "Exit codes") --
EXIT_COMPLETE = 0  # complete; nothing lost beyond what the record format allows
EXIT_DATA_LOST = 5  # complete, but samples were lost or rejected: the record's events declare how many
EXIT_STOPPED = 130  # the operator (Ctrl-C, q, stop button) or the system (SIGTERM) stopped it

class RecordWriteError(FlowcurveError):
    """The record cannot be created or written (read-only folder, disk full): names the file
    and what to do; a test that cannot be recorded is not started, or is stopped."""

    exit_code = 6


class PortBusyError(DeviceError):
    """A serial port another process owns (its lock file names the holder)."""

    exit_code = 7

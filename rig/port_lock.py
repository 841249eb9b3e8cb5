"""One owner per serial port across processes: a UUCP-style lock file, as serial tools keep.

``LCK..ttyUSB0`` (``/dev/pts/3`` → ``LCK..pts_3``) in the lock folder holds the owner's PID
(ten characters and a newline, the UUCP convention minicom and picocom read) and a second
line saying who holds it. A lock whose process is gone is stale and taken over. The folder
is ``$FLOWCURVE_LOCK_DIR``, else ``/var/lock`` or ``/run/lock`` when writable, else the
temporary folder.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from flowcurve.errors import PortBusyError

LOCK_DIR_ENV = "FLOWCURVE_LOCK_DIR"


def lock_dir() -> Path:
    """Where the lock files live (see the module docstring)."""
    env = os.environ.get(LOCK_DIR_ENV)
    if env:
        return Path(env)
    for folder in ("/var/lock", "/run/lock"):
        if os.path.isdir(folder) and os.access(folder, os.W_OK):
            return Path(folder)
    return Path(tempfile.gettempdir())


def lock_path(port: str) -> Path | None:
    """The lock file of a device path; None for URLs (``loop://``, ``socket://``, ``virtual://``)."""
    if "://" in port or not port.startswith("/"):
        return None
    name = port[len("/dev/"):] if port.startswith("/dev/") else port.lstrip("/")
    return lock_dir() / ("LCK.." + name.replace("/", "_"))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _read(path: Path) -> tuple[int | None, str]:
    try:
        lines = path.read_text(errors="replace").splitlines()
    except FileNotFoundError:
        return None, ""
    try:
        pid = int(lines[0].strip()) if lines else None
    except ValueError:
        pid = None
    return pid, (lines[1].strip() if len(lines) > 1 else "")


class PortLock:
    """The lock of one port, held by this process from :meth:`acquire` to :meth:`release`."""

    def __init__(self, port: str, device: str):
        self.port = port
        self.device = device
        self.path = lock_path(port)
        self.held = False

    def acquire(self) -> "PortLock":
        """Take the port's lock file (DeviceError naming the holder when taken); the lock."""
        if self.path is None or self.held:
            return self
        holder = f"flowcurve {' '.join(sys.argv[1:3])}".strip() + f" ({self.device})"
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid, who = _read(self.path)
                if pid is not None and pid != os.getpid() and _alive(pid):
                    raise PortBusyError(self.device, f"port {self.port} is in use by process {pid}"
                                                     f"{f' ({who})' if who else ''} — stop that program first "
                                                     f"(lock file {self.path})") from None
                try:  # stale (its process is gone) or our own: take it over
                    self.path.unlink()
                except FileNotFoundError:
                    pass
                continue
            except OSError:  # no lock folder we may write: go on without (as serial tools do)
                return self
            with os.fdopen(fd, "w") as fh:
                fh.write(f"{os.getpid():10d}\n{holder}\n")
            self.held = True
            return self
        raise PortBusyError(self.device, f"port {self.port}: cannot take its lock file {self.path}")

    def release(self) -> None:
        """Release the lock file."""
        if not self.held:
            return
        self.held = False
        pid, _ = _read(self.path)
        if pid == os.getpid():
            try:
                self.path.unlink()
            except FileNotFoundError:
                pass

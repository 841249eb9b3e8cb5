"""rig.port_lock: one owner per serial port across processes (UUCP lock files)."""

import os
import subprocess
import sys

import pytest

from flowcurve.errors import PortBusyError
from flowcurve.rig.port_lock import PortLock, lock_path


@pytest.fixture(autouse=True)
def lock_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOWCURVE_LOCK_DIR", str(tmp_path))
    return tmp_path


def test_lock_file_names_follow_the_uucp_convention(lock_dir):
    assert lock_path("/dev/ttyUSB0") == lock_dir / "LCK..ttyUSB0"
    assert lock_path("/dev/pts/3") == lock_dir / "LCK..pts_3"
    assert lock_path("loop://") is None and lock_path("virtual://loadcell-1") is None


def test_a_held_port_is_refused_to_another_process_naming_the_holder(lock_dir):
    lock = PortLock("/dev/ttyUSB0", "load cell").acquire()
    assert (lock_dir / "LCK..ttyUSB0").read_text().splitlines()[0].strip() == str(os.getpid())
    code = ("from flowcurve.rig.port_lock import PortLock\n"
            "PortLock('/dev/ttyUSB0', 'load cell').acquire()")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=os.environ)
    assert done.returncode != 0 and f"in use by process {os.getpid()}" in done.stderr and "PortBusyError" in done.stderr
    lock.release()
    assert not (lock_dir / "LCK..ttyUSB0").exists()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=os.environ)
    assert done.returncode == 0, done.stderr


def test_a_stale_lock_of_a_dead_process_is_taken_over(lock_dir):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (lock_dir / "LCK..ttyS0").write_text(f"{int(dead.stdout):10d}\nflowcurve run tension (load cell)\n")
    lock = PortLock("/dev/ttyS0", "load cell").acquire()
    assert lock.held
    lock.release()


def test_busy_is_its_own_exit_code():
    assert PortBusyError("load cell", "x").exit_code == 7

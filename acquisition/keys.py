"""The operator's quit key on an interactive terminal."""

from __future__ import annotations

import os
import select
import sys


class KeyWatcher:
    """Reports a 'q' typed on an interactive terminal (cbreak mode, restored on exit)."""

    def __init__(self, enabled: bool):
        self.enabled = enabled and sys.stdin.isatty()
        self._saved = None

    def __enter__(self) -> "KeyWatcher":
        if self.enabled:
            import termios
            import tty

            self._saved = termios.tcgetattr(sys.stdin)
            tty.setcbreak(sys.stdin.fileno())
        return self

    def quit_pressed(self) -> bool:
        """Whether 'q' was typed since the last look."""
        if not self.enabled:
            return False
        while select.select([sys.stdin], [], [], 0)[0]:
            if os.read(sys.stdin.fileno(), 1) in (b"q", b"Q"):
                return True
        return False

    def __exit__(self, *exc) -> None:
        if self._saved is not None:
            import termios

            termios.tcsetattr(sys.stdin, termios.TCSADRAIN, self._saved)

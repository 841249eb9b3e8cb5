"""A plain-text progress bar on standard error for commands that work through many records.

On a terminal the bar is redrawn in place (carriage return); into a file or pipe it writes one
line at most every ``every_s`` seconds and the last one, so a log stays short.
"""

from __future__ import annotations

import sys
import time

WIDTH = 30


def bar_text(done: int, total: int, elapsed_s: float, what: str = "records", note: str = "") -> str:
    """``[#########.....] 12/40 records, 45 s, about 105 s left`` (the time left at the rate so far)."""
    filled = int(WIDTH * done / total) if total else WIDTH
    left = f", about {elapsed_s / done * (total - done):.0f} s left" if 0 < done < total else ""
    return f"[{'#' * filled}{'.' * (WIDTH - filled)}] {done}/{total} {what}{note}, {elapsed_s:.0f} s{left}"


def budget_text(done: int, elapsed_s: float, left_s: float | None, what: str = "solver runs", limit_s: float | None = None) -> str:
    """``[######........] 12 solver runs, 45 s, about 105 s left (time limit 270 s)``: a bar of the
    time spent over the time spent and left, for work whose total is estimated as it goes."""
    total = elapsed_s + (left_s or 0.0)
    filled = int(WIDTH * elapsed_s / total) if left_s is not None and total > 0 else 0
    left = f", about {left_s:.0f} s left" if left_s is not None else ""
    limit = f" (time limit {limit_s:.0f} s)" if limit_s is not None else ""
    return f"[{'#' * filled}{'.' * (WIDTH - filled)}] {done} {what}, {elapsed_s:.0f} s{left}{limit}"


class ProgressBar:
    """``update(done, note="")`` after each item; ``close()`` ends the line."""

    def __init__(self, total: int, what: str = "records", stream=None, every_s: float = 5.0):
        self.total, self.what, self.every_s = total, what, every_s
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self._last = -float("inf")
        self._drawn = False

    def update(self, done: int, note: str = "") -> None:
        """Show ``done`` of the total (and ``note``): in place on a terminal, a line every ``every_s`` s elsewhere."""
        now = time.perf_counter()
        if not self.tty and done < self.total and now - self._last < self.every_s:
            return
        self._last = now
        text = bar_text(done, self.total, now - self.t0, self.what, note)
        self.stream.write(f"\r{text}" if self.tty else f"{text}\n")
        self.stream.flush()
        self._drawn = True

    def close(self) -> None:
        """End the bar's line on a terminal."""
        if self.tty and self._drawn:
            self.stream.write("\n")
            self.stream.flush()

"""Live terminal view of a running test.

On a terminal the view redraws in place about four times a second: a state line (heating,
soaking, recording, stopping), force, displacement, temperature, time, sample rate, a
progress bar while heating and a small force-displacement plot in braille characters.
When stdout is not a terminal it prints one plain line every few seconds (and on every
state change); ``quiet`` prints nothing.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field
from typing import TextIO

import numpy as np

# Braille cell: 2 columns × 4 rows of dots; bit of each dot (column, row)
_BRAILLE_BITS = np.array([[0x01, 0x02, 0x04, 0x40], [0x08, 0x10, 0x20, 0x80]])


def braille_plot(x: np.ndarray, y: np.ndarray, width: int = 40, height: int = 8) -> list[str]:
    """Scatter (x, y) into ``height`` lines of ``width`` braille characters (2×4 dots each)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    cells = np.zeros((height, width), dtype=int)
    if x.size:
        nx, ny = 2 * width, 4 * height
        x0, x1 = float(x.min()), float(x.max())
        y0, y1 = min(0.0, float(y.min())), float(y.max())
        px = np.zeros(x.size, dtype=int) if x1 <= x0 else np.clip(((x - x0) / (x1 - x0) * (nx - 1)).round().astype(int), 0, nx - 1)
        py = np.zeros(y.size, dtype=int) if y1 <= y0 else np.clip(((y - y0) / (y1 - y0) * (ny - 1)).round().astype(int), 0, ny - 1)
        row_dot = (ny - 1) - py  # row 0 at the top
        np.bitwise_or.at(cells, (row_dot // 4, px // 2), _BRAILLE_BITS[px % 2, row_dot % 4])
    return ["".join(chr(0x2800 + int(c)) for c in line) for line in cells]


def progress_bar(fraction: float, width: int = 30) -> str:
    """``[██████░░░░]  60 %`` for a fraction in [0, 1] (clipped)."""
    f = 0.0 if not math.isfinite(fraction) else min(max(fraction, 0.0), 1.0)
    full = int(round(f * width))
    return "[" + "█" * full + "░" * (width - full) + f"] {100 * f:3.0f} %"


@dataclass
class Snapshot:
    """What the view shows at one moment."""

    state: str  # heating, soaking, tare, waiting, recording, stopping, done
    time_s: float = 0.0
    force_N: float = math.nan
    crosshead_mm: float = math.nan
    temperature_C: float = math.nan
    rate_per_s: float = math.nan
    samples: int = 0
    progress: float | None = None  # heating progress 0..1
    message: str = ""
    curve_mm: np.ndarray | None = None
    curve_N: np.ndarray | None = None
    rows: np.ndarray | None = None  # the record rows taken since the last snapshot (for live plots elsewhere)


def _num(value: float, fmt: str) -> str:
    return "—" if value is None or not math.isfinite(value) else format(value, fmt)


def status_line(s: Snapshot) -> str:
    """One plain line: state, time, force, displacement, temperature, rate, samples."""
    parts = [
        f"{s.state:<9}",
        f"t {_num(s.time_s, '8.1f')} s",
        f"F {_num(s.force_N / 1000 if math.isfinite(s.force_N) else math.nan, '8.3f')} kN",
        f"x {_num(s.crosshead_mm, '7.3f')} mm",
        f"T {_num(s.temperature_C, '6.1f')} C",
        f"{_num(s.rate_per_s, '5.0f')} samples/s",
        f"n {s.samples}",
    ]
    line = "  ".join(parts)
    if s.message:
        line += f"  | {s.message}"
    return line


def render(s: Snapshot, width: int = 48, height: int = 8) -> list[str]:
    """The full terminal view as lines."""
    lines = [f"flowcurve — {s.state.upper()}" + (f": {s.message}" if s.message else ""), status_line(Snapshot(**{**s.__dict__, "message": ""}))]
    if s.progress is not None:
        lines.append("heating " + progress_bar(s.progress))
    if s.curve_mm is not None and s.curve_N is not None and len(s.curve_mm):
        fmax = np.nanmax(np.abs(s.curve_N)) / 1000 if len(s.curve_N) else 0.0
        lines.append(f"force–displacement (max {fmax:.2f} kN, {_num(float(np.nanmax(s.curve_mm)), '.2f')} mm)")
        lines.extend("│" + row for row in braille_plot(s.curve_mm, np.abs(s.curve_N), width, height))
        lines.append("└" + "─" * width)
    lines.append("stop: Ctrl-C or q")
    return lines


@dataclass
class LiveView:
    """Shows snapshots at most ``refresh_hz`` times a second (state changes always)."""

    stream: TextIO = field(default_factory=lambda: sys.stdout)
    quiet: bool = False
    refresh_hz: float = 4.0
    plain_every_s: float = 5.0
    tty: bool | None = None
    _last_draw: float = -math.inf
    _last_state: str = ""
    _drawn_lines: int = 0

    def __post_init__(self) -> None:
        if self.tty is None:
            isatty = getattr(self.stream, "isatty", None)
            self.tty = bool(isatty and isatty())

    def show(self, s: Snapshot, force: bool = False) -> None:
        """Draw snapshot ``s`` at the refresh rate, on a change of state, or at once when ``force``."""
        if self.quiet:
            return
        now = time.monotonic()
        changed = s.state != self._last_state
        interval = 1.0 / self.refresh_hz if self.tty else self.plain_every_s
        if not (force or changed or now - self._last_draw >= interval):
            return
        self._last_draw, self._last_state = now, s.state
        if self.tty:
            lines = render(s)
            out = f"\x1b[{self._drawn_lines}F" if self._drawn_lines else ""
            out += "".join(f"\x1b[2K{line}\n" for line in lines) + "\x1b[J"  # clear what a longer frame left
            self.stream.write(out)
            self._drawn_lines = len(lines)
        else:
            self.stream.write(status_line(s) + "\n")
        self.stream.flush()

    def alert(self, text: str) -> None:
        """A line the operator must see whatever the view (safety: stop the motor, cut the
        furnace's power): on the view's stream, or on stderr when quiet."""
        stream = sys.stderr if self.quiet else self.stream
        stream.write(text + "\n")
        stream.flush()
        self._drawn_lines = 0

    def say(self, text: str) -> None:
        """A message line that stays (instructions, results)."""
        if self.quiet:
            return
        self.stream.write(text + "\n")
        self.stream.flush()
        self._drawn_lines = 0

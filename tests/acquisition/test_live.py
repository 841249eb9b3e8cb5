"""Live view rendering: braille plot geometry, progress bar, TTY/plain/quiet modes."""

import io

import numpy as np

from flowcurve.acquisition.live import LiveView, Snapshot, braille_plot, progress_bar, render, status_line


def dots(lines):
    """Set of lit (x, y) dot coordinates decoded from braille lines, y from the top."""
    bits = {0x01: (0, 0), 0x02: (0, 1), 0x04: (0, 2), 0x40: (0, 3), 0x08: (1, 0), 0x10: (1, 1), 0x20: (1, 2), 0x80: (1, 3)}
    out = set()
    for r, line in enumerate(lines):
        for c, ch in enumerate(line):
            code = ord(ch) - 0x2800
            for b, (dx, dy) in bits.items():
                if code & b:
                    out.add((2 * c + dx, 4 * r + dy))
    return out


def test_braille_corners_and_diagonal():
    w, h = 10, 3
    lines = braille_plot(np.array([0.0, 1.0]), np.array([0.0, 1.0]), w, h)
    assert len(lines) == h and all(len(l) == w for l in lines)
    assert dots(lines) == {(0, 4 * h - 1), (2 * w - 1, 0)}  # bottom-left and top-right
    x = np.linspace(0, 1, 200)
    lit = dots(braille_plot(x, x, w, h))
    for px, py in lit:  # every dot lies on the diagonal of the dot grid
        assert abs((4 * h - 1 - py) / (4 * h - 1) - px / (2 * w - 1)) < 0.1
    assert len({px for px, _ in lit}) == 2 * w  # every dot column lit


def test_braille_empty_and_nan():
    lines = braille_plot(np.array([np.nan]), np.array([1.0]), 4, 2)
    assert lines == ["\u2800" * 4] * 2


def test_progress_bar():
    assert progress_bar(0.5, 10) == "[█████░░░░░]  50 %"
    assert progress_bar(2.0, 4).startswith("[████]")
    assert progress_bar(float("nan"), 4).startswith("[░░░░]")


def test_status_line_units_and_missing_values():
    line = status_line(Snapshot("recording", time_s=1.5, force_N=12345.0, crosshead_mm=0.25))
    assert "12.345 kN" in line and "0.250 mm" in line and "— C" in line


def test_modes():
    s = Snapshot("recording", curve_mm=np.linspace(0, 1, 50), curve_N=np.linspace(0, 1e4, 50))
    quiet = io.StringIO()
    LiveView(stream=quiet, quiet=True).show(s)
    assert quiet.getvalue() == ""
    plain = io.StringIO()
    v = LiveView(stream=plain, tty=False)
    v.show(s)
    v.show(Snapshot("stopping"))
    out = plain.getvalue().splitlines()
    assert len(out) == 2 and out[0].startswith("recording") and "\x1b" not in plain.getvalue()
    tty = io.StringIO()
    v = LiveView(stream=tty, tty=True)
    v.show(s)
    v.show(Snapshot("stopping"))
    text = tty.getvalue()
    assert f"\x1b[{len(render(s))}F" in text  # second frame redraws over the first
    assert "force–displacement" in text

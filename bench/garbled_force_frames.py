"""Garbled load-cell frames that decode to another number, against the force guard (acquisition/plausibility.py).

An AED ASCII frame (COF 3: sign and seven digits, 0.1 N a count at 100 kN) carries no checksum: a
garbled byte that lands on another digit (or flips the sign) decodes to a plausible number. The
force guard must reject those that would move a result — above all the maximum force — and must
not reject the physics (yield drops, serrations, fractures) of a fault-free stream.

Force histories: the stream-gap bench's (bench/stream_gap_rule.py ``histories``: the virtual rig's
physics frame by frame, every test × temperature × speed × material, the AED's low-pass). The
guard is the one a test gets (acquisition/channel_guards.py: frame 136 N/µm, 100 kN capacity, the matrix's
time scale). For each history:

* the fault-free stream through the guard: its rejections are false ones;
* drawn frames (seeded, ``--positions`` per history, plus the last two and the maximum's
  neighbourhood), each digit of the frame replaced by every other digit, and the sign flipped:
  counted as rejected, or passed with the reading off by more than 0.3 % of Fm (rises and falls
  apart), and whether the stream's maximum (Fm) moved by more than 0.3 %.

``--module PATH`` judges with another plausibility module (e.g. an older revision's, written out
with ``git show REV:acquisition/plausibility.py``) in the product's place. Deterministic.

Usage: PYTHONPATH=. python bench/garbled_force_frames.py [--rates 12,50] [--positions 20] [--module PATH]
"""

from __future__ import annotations

import argparse
import importlib.util
import random
from collections import Counter

import numpy as np

from bench.stream_gap_rule import histories
from flowcurve.acquisition import channel_guards

STIFFNESS_N_PER_UM = 136.0
CAPACITY_N = 100e3
COUNT_N = 0.1  # COF 3 at 100 kN nominal: 1 000 000 counts
WINDOW_BEFORE = 260  # the guard's noise window (200) and its approach, filled before the garbled frame
MOVED = 0.003  # a reading or Fm off by more than this fraction of Fm counts as moved


def guard_module(path: str | None):
    if path is None:
        import flowcurve.acquisition.plausibility as module

        return module
    spec = importlib.util.spec_from_file_location("plausibility_variant", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def label_parts(label: str) -> tuple[float, float, float]:
    """(temperature °C, speed mm/s, rate Hz) from a history's label 'tension-20C-0.05mmps-12Hz-steel45'."""
    _, temp, speed, rate, _ = label.split("-", 4)
    return float(temp[:-1]), float(speed[:-4]), float(rate[:-2])


def make_guard(module, label: str):
    """The force guard a test gets (acquisition/channel_guards.py) for this history's speed, rate and time scale,
    of ``module``'s RateGuard; and the frames' spacing in test seconds."""
    temp, speed, rate = label_parts(label)
    scale = min(1.0 / speed, 50.0) if temp > 20.0 else 1.0 / speed
    product = channel_guards.RateGuard
    channel_guards.RateGuard = module.RateGuard
    try:
        guard = channel_guards.force_guard("load cell", speed_mm_per_s=speed, frame_stiffness_N_per_um=STIFFNESS_N_PER_UM,
                                           capacity_N=CAPACITY_N, time_scale=scale, period_s=1.0 / rate, resolution_N=COUNT_N)
    finally:
        channel_guards.RateGuard = product
    return guard, scale / rate


def garbled(value_N: float) -> list[float]:
    """Every reading one garbled byte of the frame can decode to: each digit replaced, the sign flipped."""
    counts = int(round(value_N / COUNT_N))
    text = ("-" if counts < 0 else "+") + f"{abs(counts):07d}"
    out = [int(("-" if text[0] == "+" else "+") + text[1:]) * COUNT_N]
    for pos in range(1, 8):
        out += [int(text[:pos] + d + text[pos + 1:]) * COUNT_N for d in "0123456789" if d != text[pos]]
    return out


def judge(module, label, t, f):
    guard, _ = make_guard(module, label)
    kept = guard.feed(list(zip(t, f))) + guard.flush()
    return guard.rejected, kept


def measure(module, rates, positions, seed=0):
    counts = Counter()
    false = []
    for rate in rates:
        for label, force in histories(rate):
            _, dt = make_guard(module, label)
            t = np.arange(force.size) * dt
            rejected, _ = judge(module, label, t, force)
            counts["fault-free samples"] += force.size
            counts["false rejections"] += len(rejected)
            false += [(label, round(float(v), 1), why[:60]) for _, v, why in rejected[:2]]
            fm = float(np.max(force))
            rng = random.Random(f"{seed}-{label}")
            top = int(np.argmax(force))
            chosen = {force.size - 1, force.size - 2, *range(max(top - 3, 30), min(top + 4, force.size))}
            chosen |= set(rng.sample(range(30, force.size), min(positions, force.size - 30)))
            for k in sorted(chosen):
                lo = max(0, k - WINDOW_BEFORE)
                for v in garbled(float(force[k])):
                    off = v - float(force[k])
                    if abs(off) <= MOVED * fm:
                        continue  # a reading within 0.3 % of Fm moves nothing that counts here
                    g = force.copy()
                    g[k] = v
                    rej, kept = judge(module, label, t[lo:], g[lo:])
                    side = "rise" if abs(v) > abs(float(force[k])) else "fall"
                    counts[f"garbled, {side}"] += 1
                    if any(r[0] == t[k] for r in rej):
                        continue
                    counts[f"passed, {side}"] += 1
                    if max(val for _, val in kept) > fm * (1 + MOVED):
                        counts[f"passed, Fm moved > 0.3 %, {label.split('-')[0]}"] += 1
    return counts, false


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rates", default="12,50", help="load-cell rates, Hz (comma-separated)")
    ap.add_argument("--positions", type=int, default=20, help="frames drawn per history (besides the end and Fm's)")
    ap.add_argument("--module", default=None, help="a plausibility module to judge with instead of the product's")
    args = ap.parse_args(argv)
    module = guard_module(args.module)
    counts, false = measure(module, [float(r) for r in args.rates.split(",")], args.positions)
    print(f"guard: {args.module or 'flowcurve.acquisition.plausibility'}")
    for key in ("fault-free samples", "false rejections", "garbled, rise", "passed, rise", "garbled, fall", "passed, fall",
                "passed, Fm moved > 0.3 %, tension", "passed, Fm moved > 0.3 %, compression"):
        print(f"  {key:40s} {counts[key]:8d}")
    for row in false[:10]:
        print("  false:", *row)


if __name__ == "__main__":
    main()

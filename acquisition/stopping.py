"""When recording ends: the stop criteria (fracture, force limit, displacement target, duration, a
stalled crosshead), the target judged on the crosshead's own reading (carried on at the speed when
the encoder retries), the main loop's tick near the target, and the crosshead's measured speed."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


MOTION_MM = 0.005  # the crosshead has moved once it is this far from where recording began


@dataclass
class StopCriteria:
    """When recording ends (whichever comes first). Forces in N, displacements in mm."""

    fracture_drop_fraction: float = 0.2  # |F| below this fraction of the max after the max
    fracture_min_force_N: float = 500.0  # ... once the max exceeded this (ignores the toe)
    target_displacement_mm: float | None = None
    force_limit_N: float | None = None
    max_duration_s: float | None = None
    stall_s: float | None = 10.0  # crosshead still (< stall_mm) this long after it moved: stopped
    stall_mm: float = 0.005


@dataclass
class StopState:
    """Running maximum for the fracture rule, updated block by block."""

    max_force_N: float = 0.0
    last_crosshead_mm: float = 0.0
    start_crosshead_mm: float | None = None
    moved: bool = False
    still_since_s: float = 0.0
    still_at_mm: float = 0.0


def stop_reason(rows: np.ndarray, state: StopState, crit: StopCriteria) -> str | None:
    """The first stop criterion a block of rows [time_s, force_N, crosshead_mm, ...] meets."""
    if rows.size == 0:
        return None
    f = np.abs(rows[:, 1])
    x = np.abs(rows[:, 2])
    running_max = np.maximum.accumulate(np.concatenate([[state.max_force_N], f]))[1:]
    state.max_force_N = float(running_max[-1])
    state.last_crosshead_mm = float(rows[-1, 2])
    stalled = _update_stall(rows, state, crit)
    if crit.force_limit_N is not None and np.any(f >= crit.force_limit_N):
        return f"force limit {crit.force_limit_N:.0f} N reached"
    if crit.target_displacement_mm is not None and np.any(x >= crit.target_displacement_mm):
        return f"target displacement {crit.target_displacement_mm:g} mm reached"
    broken = (running_max >= crit.fracture_min_force_N) & (f < crit.fracture_drop_fraction * running_max)
    if np.any(broken):
        return f"fracture (force fell below {100 * crit.fracture_drop_fraction:.0f} % of the maximum {state.max_force_N / 1000:.2f} kN)"
    if crit.max_duration_s is not None and rows[-1, 0] >= crit.max_duration_s:
        return f"maximum duration {crit.max_duration_s:g} s reached"
    if stalled:
        return f"the crosshead stopped (still for {crit.stall_s:g} s)"
    return None


def target_reached(crosshead_mm: tuple[float, float] | None, crit: StopCriteria, *, now_s: float | None = None,
                   speed_mm_per_s: float = 0.0, stale_s: float = math.inf, carry_max_s: float = math.inf) -> str | None:
    """The displacement target judged on the crosshead reading itself (the encoder stream's latest,
    ``(time_s, mm)``), not on record rows: a row waits for every stream to bracket its force sample,
    so rows come later than the reading that reached the target. A reading older than ``stale_s``
    at ``now_s`` (test s: the encoder retrying a lost reply) is carried on at the crosshead's
    speed, |x| + v·(now − t), so the stop does not wait for the next reading — up to ``carry_max_s``
    old (longer than a retried exchange takes: the encoder has gone silent, and its silence fault ends
    the test instead)."""
    target = crit.target_displacement_mm
    if target is None or crosshead_mm is None:
        return None
    t_s, x_mm = crosshead_mm
    if abs(x_mm) >= target:
        return f"target displacement {target:g} mm reached"
    age_s = (now_s - t_s) if now_s is not None else 0.0
    if stale_s < age_s <= carry_max_s and speed_mm_per_s > 0 and abs(x_mm) + speed_mm_per_s * age_s >= target:
        return (f"target displacement {target:g} mm reached (carried on at {speed_mm_per_s:g} mm/s from the crosshead's "
                f"{abs(x_mm):.3f} mm read {age_s:.2f} s before: the encoder was retrying)")
    return None


STALE_CROSSHEAD_S = 0.1  # host seconds: an encoder reading older than this near the target is carried on at the speed
CARRY_MAX_S = 1.0  # host seconds: ... carried on at most this long (a retried encoder read takes under 0.6 s)
CARRY_AGREE_MM = 0.02  # the reading after such a stop must agree this well with the carried-on stop position
STALE_WAIT_S = 2.0  # host seconds: after such a stop, the longest wait for the encoder's next reading
TARGET_TICK_MIN_S = 0.005  # host seconds: the main loop's shortest tick, near a displacement target


def loop_tick_s(crosshead_mm: tuple[float, float] | None, crit: StopCriteria, speed_mm_per_s: float,
                time_scale: float, tick_s: float) -> float:
    """The main loop's next sleep (host s): ``tick_s``, shortened near a displacement target to
    half the host time the crosshead needs to reach it, t = (target − |x|) / (v · time_scale),
    at least TARGET_TICK_MIN_S — the stop then runs past the target by about one encoder poll,
    not one tick (0.05 s host is 0.0375 mm at 0.05 mm/s and time scale 15)."""
    if crit.target_displacement_mm is None or crosshead_mm is None or not speed_mm_per_s > 0:
        return tick_s
    left_s = (crit.target_displacement_mm - abs(crosshead_mm[1])) / (speed_mm_per_s * time_scale)
    return min(tick_s, max(TARGET_TICK_MIN_S, 0.5 * left_s))


def _update_stall(rows: np.ndarray, state: StopState, crit: StopCriteria) -> bool:
    """Track crosshead motion; True once it has moved and then stood still for stall_s."""
    if crit.stall_s is None:
        return False
    t, x = rows[:, 0], rows[:, 2]
    if state.start_crosshead_mm is None:
        state.start_crosshead_mm = state.still_at_mm = float(x[0])
        state.still_since_s = float(t[0])
    moved = np.abs(x - state.still_at_mm) > crit.stall_mm
    if np.any(moved):
        last = int(np.flatnonzero(moved)[-1])
        state.moved = True
        state.still_at_mm, state.still_since_s = float(x[last]), float(t[last])
        # a later sample can be within stall_mm of the new rest point: that is fine
    return state.moved and float(t[-1]) - state.still_since_s >= crit.stall_s


SPEED_MIN_TRAVEL_MM = 1.0  # the crosshead's speed is measured over at least this travel: a count (10 µm) at each end is ≤ 2 %


@dataclass
class SpeedMeter:
    """The crosshead's speed from its own readings: travel / time from the first reading away from
    rest (MOTION_MM) to the last reading that changed — the still tail after a stop left out."""

    rest_mm: float | None = None
    first: tuple[float, float] | None = None  # (time_s, crosshead_mm) of the first reading away from rest
    last: tuple[float, float] | None = None  # ... of the last reading that changed
    previous_mm: float | None = None

    def update(self, rows: np.ndarray) -> None:
        """Take a block of rows [time_s, force_N, crosshead_mm, ...]."""
        if rows.size == 0:
            return
        t, x = rows[:, 0], rows[:, 2]
        if self.rest_mm is None:
            self.rest_mm = self.previous_mm = float(x[0])
        if self.first is None:
            away = np.flatnonzero(np.abs(x - self.rest_mm) > MOTION_MM)
            if away.size == 0:
                self.previous_mm = float(x[-1])
                return
            self.first = self.last = (float(t[away[0]]), float(x[away[0]]))
        changed = np.flatnonzero(x != np.concatenate([[self.previous_mm], x[:-1]]))
        if changed.size and float(t[changed[-1]]) > self.first[0]:
            self.last = (float(t[changed[-1]]), float(x[changed[-1]]))
        self.previous_mm = float(x[-1])

    def speed_mm_per_s(self) -> float | None:
        """|Δx| / Δt over the motion (None below SPEED_MIN_TRAVEL_MM of travel)."""
        if self.first is None or self.last is None:
            return None
        travel, span = abs(self.last[1] - self.first[1]), self.last[0] - self.first[0]
        return travel / span if travel >= SPEED_MIN_TRAVEL_MM and span > 0 else None

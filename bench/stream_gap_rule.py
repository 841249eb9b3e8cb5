"""The load cell's stream-gap rules against known truth: a lost frame or the line's latency growing.

A gap in the stream's arrivals is lost frames (every later stamp keeps the gap) or the line's latency
grown (no frame lost: every later stamp shifts back by the gap's extra time). The driver tells them
by the force (rig/loadcell.py: the step rule ``step_rule_verdict``/``gap_is_latency``, and the deferred
rule ``gap_after_verdict`` where the step rule cannot tell). Here a :class:`LoadCell` stamps the
frames exactly as ``read_stream`` does (``_hold_or_stamp``, then ``flush_held``, as
tests/rig/test_stream_latency.py's ``stream_at_2hz``), and every verdict is judged by the stamps
against the frames' known send times — never by the rules' own output.

Force histories: the virtual rig's physics (rig/virtual/physics.py ``RigModel``) driven frame by frame
as the scenario matrix's fault-free cells run it (tests/scenarios/matrix.py: time scale 1/v, at most
50 when heated; the furnace held at the set-point; 3 N sensor noise; the AED's ASF2 3.5 Hz low-pass
at the frames; three standstill frames before the crosshead starts; tension to the fracture,
compression to 3 mm): every test × temperature × speed × material at each rate. Cached as .npz in
``$TMPDIR/flowcurve-stream-gap-bench`` (``--fresh`` rebuilds them).

Injected at frame k (the gap before frame k; every k at 2 Hz, ``--positions`` drawn per history
at the higher rates, seeded): (a) j − 1 frames lost from k, (b) the line's latency grown by
j − 1 periods from frame k on; j = 2 and 3 at 2 Hz (0.5 s, 1 s), 7 at 12 Hz (0.5 s), 26 at 50 Hz.
Counted per outcome:

* right — every stamp within T/4 of its send time, no gap named;
* named — the gap named undecided or in doubt (stamped as lost; the record and identify say so);
* loss→latency — a loss stamped as latency, nothing named (every later force a gap early): confident, wrong;
* latency→loss — a latency stamped as lost frames, nothing named: confident, wrong.

``--variant NAME`` runs a rule variant (:data:`VARIANTS`) in the driver's place (patched into
``flowcurve.rig.loadcell``); ``--variant all`` runs each. Deterministic (seeded).

Usage: PYTHONPATH=. python bench/stream_gap_rule.py [--rates 2,12] [--variant all] [--positions 40]
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import itertools
import logging
import math
import os
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

import flowcurve.rig.loadcell as lc
from flowcurve.rig.codecs.aed import ASF_CUTOFF_HZ, MeasuredValue

LINE_S = 0.0012  # the line's time for a frame
TESTS, TEMPERATURES_C, SPEEDS = ("tension", "compression"), (20.0, 300.0, 600.0, 850.0), (0.005, 0.05, 0.5)
MATERIALS = ("steel45", "12Kh18N10T", "12Kh18N12M3TL")
GAPS = {2.0: (2, 3), 12.0: (7,), 50.0: (26,)}  # j: the gap's periods (0.5 s and 1 s at 2 Hz, 0.5 s above)
FILTER_HZ = ASF_CUTOFF_HZ[2]  # the rig configuration's [loadcell] filter (ASF2)
STANDSTILL_FRAMES = 3
WINDOW_BEFORE = 20  # frames fed before the gap (the rules look at 8; the stream starts here when k is larger)
WINDOW_AFTER = 8
CACHE = Path(os.environ.get("FLOWCURVE_BENCH_CACHE", Path(tempfile.gettempdir()) / "flowcurve-stream-gap-bench"))
VERSION = "1"  # bump when the histories' making changes


def _history(test, temperature_C, speed, material, rate_Hz, seed) -> np.ndarray:
    from flowcurve.rig.virtual.physics import RigModel

    heated = temperature_C > 20.0
    scale = min(1.0 / speed, 50.0) if heated else 1.0 / speed  # tests/scenarios/matrix.py Cell.time_scale
    m = RigModel(material, test, speed_mm_per_s=speed, initial_temperature_C=temperature_C if heated else None, seed=seed)
    dt = scale / rate_Hz  # model seconds per frame
    alpha = 1.0 - math.exp(-2.0 * math.pi * FILTER_HZ / rate_Hz)  # the AED's first-order low-pass, per frame
    out, y, after = [], None, 0
    for i in itertools.count():
        if i == STANDSTILL_FRAMES:
            m.start_crosshead()
        if heated:
            m.furnace.temperature_C = temperature_C  # the furnace controller holds the set-point
        m.step(dt)
        f = m.measured_force_N()
        y = f if y is None else y + alpha * (f - y)
        out.append(y)
        if (test == "tension" and m.fractured) or (test == "compression" and m.crosshead_mm >= 3.0):
            after += 1
        if after >= 2 or i > 20000:
            break
    return np.array(out)


def histories(rate_Hz: float, fresh: bool = False) -> list[tuple[str, np.ndarray]]:
    CACHE.mkdir(parents=True, exist_ok=True)
    out = []
    for n, (test, temp, speed, mat) in enumerate(itertools.product(TESTS, TEMPERATURES_C, SPEEDS, MATERIALS)):
        label = f"{test}-{temp:g}C-{speed:g}mmps-{rate_Hz:g}Hz-{mat}"
        path = CACHE / f"{hashlib.sha1((VERSION + label).encode()).hexdigest()[:16]}.npz"
        if path.exists() and not fresh:
            f = np.load(path)["force"]
        else:
            f = _history(test, temp, speed, mat, rate_Hz, seed=1000 + n)
            np.savez(path, force=f)
        out.append((label, f))
    return out


def stamp(force, sent, arrival, rate_Hz):
    """The driver's stamping of these frames (read_stream's _hold_or_stamp, then flush_held)."""
    cell = lc.LoadCell("loop://", nominal_load_N=100e3, output_rate_per_s=rate_Hz)
    for a, f in zip(arrival, force):
        cell.frames_received += 1
        cell._hold_or_stamp(a, MeasuredValue(int(f), 0), f)
    return cell, np.array([s.t_monotonic_s for s in cell.flush_held()])


def outcome(truth, cell, stamps, sent, T) -> str:
    if stamps.size != sent.size:
        return "other"
    off = np.abs(stamps - sent) > 0.25 * T
    named = bool(cell.gaps_undecided or cell.gaps_in_doubt)
    if named:
        return "named"
    if not off.any():
        return "right"
    return "loss→latency" if truth == "loss" else "latency→loss"


def run_case(force, k, j, truth, rate_Hz):
    T = 1.0 / rate_Hz
    lo, hi = max(0, k - WINDOW_BEFORE), min(force.size, k + j - 1 + WINDOW_AFTER)
    idx = np.arange(lo, hi)
    if truth == "loss":
        idx = idx[(idx < k) | (idx >= k + j - 1)]
        sent = idx * T
        arrival = sent + LINE_S
    else:
        sent = idx * T
        arrival = sent + LINE_S + np.where(idx >= k, (j - 1) * T, 0.0)
    cell, stamps = stamp(force[idx], sent, arrival, rate_Hz)
    return outcome(truth, cell, stamps, sent, T)


def positions(n, j, rate_Hz, count, rng):
    ks = np.arange(1, n - j - 2)
    if rate_Hz > 2.0 and ks.size > count:
        ks = np.sort(rng.choice(ks, count, replace=False))
    return ks


def measure(rates, count, fresh=False, detail=False):
    table = Counter()
    wrong = []
    for rate in rates:
        rng = np.random.default_rng(int(rate * 1000) + 7)
        for label, force in histories(rate, fresh):
            for j in GAPS[rate]:
                for k in positions(force.size, j, rate, count, rng):
                    for truth in ("loss", "latency"):
                        o = run_case(force, int(k), j, truth, rate)
                        table[(rate, j, truth, o)] += 1
                        if o in ("loss→latency", "latency→loss"):
                            wrong.append((label, int(k), j, o))
    return table, wrong


def print_table(name, table, rates):
    cols = ("right", "named", "loss→latency", "latency→loss", "other")
    print(f"\n== {name}")
    print(f"{'rate':>5} {'j':>3} {'truth':>8} " + " ".join(f"{c:>13}" for c in cols))
    for rate in rates:
        for j in GAPS[rate]:
            for truth in ("loss", "latency"):
                print(f"{rate:>5g} {j:>3} {truth:>8} " + " ".join(f"{table[(rate, j, truth, c)]:>13}" for c in cols))
    tot = {c: sum(v for key, v in table.items() if key[3] == c) for c in cols}
    print("total          " + " ".join(f"{tot[c]:>13}" for c in cols))


# -- rule variants (each replaces step_rule_verdict; gap_is_latency follows it) ----------------------------


def _line(x, f):
    x = np.asarray(x, dtype=float)
    f = np.asarray(f, dtype=float)
    x = x - x[-1]
    b, a = np.polyfit(x, f, 1)
    sigma = float(np.sqrt(np.sum((f - a - b * x) ** 2) / (f.size - 2)))
    return x, f, a, b, sigma


def _exclude_se(x, f, nxt, periods, min_periods=2, k_se=2.0, both=True, exclude=True, at_j=True):
    v = ORIGINAL(x, f, nxt, periods, min_periods)
    if v is None or (v == "loss" and not both):
        return v
    x, f, a, b, s = _line(x, f)
    apart = abs((periods - 1) * b)
    sxx = float(np.sum((x - x.mean()) ** 2))
    se = max(s * math.sqrt(1.0 / x.size + (at - x.mean()) ** 2 / sxx) for at in ((1.0, float(periods)) if at_j else (1.0,)))
    near, other = (a + b, a + b * periods) if v == "latency" else (a + b * periods, a + b)
    ok = (not exclude or abs(nxt - other) > (1 - lc.LATENCY_FIT) * apart) and abs(nxt - near) + k_se * se < lc.LATENCY_FIT * apart
    return v if ok else None


def v_exclude_se(x, f, nxt, periods, min_periods=2):
    """Latency also needs the loss excluded, |next − (a + b·j)| > (1 − FIT)·apart, and the line's own
    extrapolation error at x = 1 and x = j inside the window: |next − (a+b)| + 2·se(1) < FIT·apart,
    se(x) = σ·√(1/n + (x − x̄)²/Sxx); loss symmetric."""
    v = ORIGINAL(x, f, nxt, periods, min_periods)
    if v is None:
        return None
    x, f, a, b, s = _line(x, f)
    apart = abs((periods - 1) * b)
    sxx = float(np.sum((x - x.mean()) ** 2))
    se = lambda at: s * math.sqrt(1.0 / x.size + (at - x.mean()) ** 2 / sxx)  # noqa: E731
    lat, los = a + b, a + b * periods
    if v == "latency":
        ok = abs(nxt - los) > (1 - lc.LATENCY_FIT) * apart and abs(nxt - lat) + 2 * max(se(1), se(periods)) < lc.LATENCY_FIT * apart
    else:
        ok = abs(nxt - lat) > (1 - lc.LATENCY_FIT) * apart and abs(nxt - los) + 2 * max(se(1), se(periods)) < lc.LATENCY_FIT * apart
    return v if ok else None


def v_noise_floor(x, f, nxt, periods, min_periods=2):
    """σ = max(line's σ, the third differences' σ over the kept history) in the 6σ test."""
    x, f = np.asarray(x, dtype=float), np.asarray(f, dtype=float)
    floor = lc._noise_from_third_differences(f) if f.size >= 6 else 0.0
    v = ORIGINAL(x[-8:], f[-8:], nxt, periods, min_periods)
    if v is None:
        return None
    _, _, a, b, s = _line(x[-8:], f[-8:])
    return v if abs((periods - 1) * b) > lc.LATENCY_NOISE_SIGMAS * max(s, floor) else None


def v_local_slope(x, f, nxt, periods, min_periods=2):
    """The verdict must be the same with the line through the last 4 frames (the local slope)."""
    v = ORIGINAL(x, f, nxt, periods, min_periods)
    if v is None:
        return None
    x, f = np.asarray(x, dtype=float), np.asarray(f, dtype=float)
    x4, f4 = x[-4:] - x[-1], f[-4:]
    b4, a4 = np.polyfit(x4, f4, 1)
    apart = abs((periods - 1) * b4)
    near = "latency" if abs(nxt - a4 - b4) < abs(nxt - a4 - b4 * periods) else "loss"
    return v if near == v else None


def v_quadratic(x, f, nxt, periods, min_periods=2):
    """The verdict must hold with a quadratic through the same frames too (a bending force: the line's
    mean slope is not the slope at the gap): the quadratic's predictions q(1), q(j) apart by > k·σ_q and
    the frame within FIT of the same one."""
    v = ORIGINAL(x, f, nxt, periods, min_periods)
    if v is None:
        return None
    x, f = np.asarray(x, dtype=float), np.asarray(f, dtype=float)
    x = x - x[-1]
    if f.size < 5:
        return v
    c = np.polyfit(x, f, 2)
    sq = float(np.sqrt(np.sum((f - np.polyval(c, x)) ** 2) / (f.size - 3)))
    lat, los = np.polyval(c, 1.0), np.polyval(c, float(periods))
    apart = abs(los - lat)
    if apart <= lc.LATENCY_NOISE_SIGMAS * sq:
        return None
    near = lat if v == "latency" else los
    return v if abs(nxt - near) < lc.LATENCY_FIT * apart else None


def v_quadratic_latency(x, f, nxt, periods, min_periods=2):
    """v_quadratic for a latency verdict only (a loss verdict as the line gives it)."""
    v = ORIGINAL(x, f, nxt, periods, min_periods)
    return v_quadratic(x, f, nxt, periods, min_periods) if v == "latency" else v


def v_combined(x, f, nxt, periods, min_periods=2):
    v = _exclude_se(x, f, nxt, periods, min_periods, 2.0, False)
    return v_quadratic(x, f, nxt, periods, min_periods) if v == "latency" else v


def _told_apart(x, f, periods, min_periods):
    """(x, f, a, b, σ, apart) of the line through the frames before the gap where the two hypotheses'
    predictions lie apart by more than LATENCY_NOISE_SIGMAS·σ (the step rule's first test), else None."""
    x, f = np.asarray(x, dtype=float), np.asarray(f, dtype=float)
    if periods < max(2, min_periods) or f.size < 4:
        return None
    x, f, a, b, sigma = _line(x, f)
    apart = abs((periods - 1) * b)
    return None if apart <= lc.LATENCY_NOISE_SIGMAS * sigma else (x, f, a, b, sigma, apart)


def v_before(x, f, nxt, periods, min_periods=2):
    """The step rule before bench/stream_gap_rule.py (main eac9177): no extrapolation margin on "latency"."""
    told = _told_apart(x, f, periods, min_periods)
    if told is None:
        return None
    x, f, a, b, sigma, apart = told
    if abs(nxt - a - b) < lc.LATENCY_FIT * apart:
        return "latency"
    if abs(nxt - a - b * periods) < lc.LATENCY_FIT * apart:
        return "loss"
    return None


# -- does the line hold? (the step rule decides only where its frames lie on a line within the force's noise) --

_STEP_RULE = lc.step_rule_verdict  # rig/loadcell.py's rule, taken before any variant patches it


def v_se_margin(x, f, nxt, periods, min_periods=2):
    """The driver's rule before its bend gate (main 9e93273: the 2·se margin, no LATENCY_BEND_CHI2)."""
    old, lc.LATENCY_BEND_CHI2 = lc.LATENCY_BEND_CHI2, math.inf
    try:
        return _STEP_RULE(x, f, nxt, periods, min_periods)
    finally:
        lc.LATENCY_BEND_CHI2 = old


DRIVER = v_se_margin  # the gates below are measured against it (chi2_far_16 is the driver's rule now)


def _curvature(x, f, noise="third"):
    """How far the frames bend off their line: χ²/dof of the line against the force's noise σ_n
    (σ_line²/σ_n², σ_n from the third differences: ``noise="third"``), or the F statistic of a quadratic
    term, (RSS_line − RSS_quad)/(RSS_quad/(n − 3)) (``noise="ftest"``: no outside σ needed)."""
    x, f, a, b, s = _line(x, f)
    if noise == "third":
        sn = lc._noise_from_third_differences(f)
        return s * s / max(sn * sn, 1e-12)
    rss2 = float(np.sum((f - np.polyval(np.polyfit(x, f, 2), x)) ** 2))
    return (s * s * (f.size - 2) - rss2) / max(rss2 / (f.size - 3), 1e-12)


_GATED = [False]  # the last step-rule call withheld the driver's verdict (a bent line): read by _named_directly


def _line_gate(x, f, nxt, periods, min_periods=2, limit=4.0, noise="third", latency_only=False):
    """The driver's verdict only where the frames lie on their line (:func:`_curvature` < ``limit``);
    else None (the driver defers the gap to the frames after it, or — :func:`_named_directly` — names it)."""
    _GATED[0] = False
    v = DRIVER(x, f, nxt, periods, min_periods)
    if v is None or (latency_only and v == "loss") or np.asarray(f).size < 6:
        return v
    if _curvature(x, f, noise) < limit:
        return v
    _GATED[0] = True
    return None


def _named_directly(rule):
    """A gap whose line the gate rejected is named undecided at once (stamped as lost), not handed to the
    deferred rule: ``variant()`` patches ``gap_after_verdict`` to answer None for it."""
    rule.names_directly = True
    return rule


def _quad_se(x, f, nxt, periods, min_periods=2, at_j=True, k_se=2.0):
    """The driver's rule with the quadratic's departure from the line at the extrapolation points added
    to se: se(x)² = σ²·(1/n + (x − x̄)²/Sxx) + (q(x) − a − b·x)², max over x ∈ {1, j} (``at_j``) or x = 1."""
    told = _told_apart(x, f, periods, min_periods)
    if told is None:
        return None
    x, f, a, b, s, apart = told
    sxx = float(np.sum((x - x.mean()) ** 2))
    q = np.polyfit(x, f, 2) if f.size >= 5 else None
    def se(at):  # noqa: E306
        bend = float(np.polyval(q, at) - a - b * at) if q is not None else 0.0
        return math.sqrt(s * s * (1.0 / f.size + (at - x.mean()) ** 2 / sxx) + bend * bend)
    e = max(se(at) for at in ((1.0, float(periods)) if at_j else (1.0,)))
    if abs(nxt - a - b) + k_se * e < lc.LATENCY_FIT * apart:
        return "latency"
    if abs(nxt - a - b * periods) < lc.LATENCY_FIT * apart:
        return "loss"
    return None


GATES = {f"chi2_{lim:g}": (lambda lim: lambda *a: _line_gate(*a, limit=lim))(lim) for lim in (2, 4, 8, 16)}
GATES.update({f"chi2_lat_{lim:g}": (lambda lim: lambda *a: _line_gate(*a, limit=lim, latency_only=True))(lim) for lim in (2, 4, 8, 16)})
GATES.update({f"ftest_{lim:g}": (lambda lim: lambda *a: _line_gate(*a, limit=lim, noise="ftest"))(lim) for lim in (6.61, 16.3, 47.2)})
GATES.update({f"ftest_lat_{lim:g}": (lambda lim: lambda *a: _line_gate(*a, limit=lim, noise="ftest", latency_only=True))(lim)
              for lim in (6.61, 16.3, 47.2)})
GATES.update({f"chi2_named_{lim:g}": _named_directly((lambda lim: lambda *a: _line_gate(*a, limit=lim))(lim)) for lim in (4, 16, 32)})
GATES.update({f"chi2_lat_named_{lim:g}": _named_directly((lambda lim: lambda *a: _line_gate(*a, limit=lim, latency_only=True))(lim))
              for lim in (4, 16, 32)})
GATES.update({f"chi2_far_{lim:g}": (lambda lim: lambda x, f, n, j, mp=2: _line_gate(x, f, n, j, mp, limit=lim, latency_only=True)
                                       if j - 1 > np.ptp(np.asarray(x, dtype=float)) else DRIVER(x, f, n, j, mp))(lim) for lim in (16,)})
GATES.update({"se_margin": v_se_margin, "quad_se": _quad_se, "quad_se_at1": lambda *a: _quad_se(*a, at_j=False),
              "quad_se1_at1": lambda *a: _quad_se(*a, at_j=False, k_se=1.0)})


ORIGINAL = v_before
MORE = {"se_latency_only": lambda *a: _exclude_se(*a, k_se=2.0, both=False),
        "se1_latency_only": lambda *a: _exclude_se(*a, k_se=1.0, both=False),
        "se_at1_latency_only": lambda *a: _exclude_se(*a, k_se=2.0, both=False, at_j=False),
        "se1.5_latency_only": lambda *a: _exclude_se(*a, k_se=1.5, both=False),
        "se3_latency_only": lambda *a: _exclude_se(*a, k_se=3.0, both=False),
        "se_no_exclude_latency_only": lambda *a: _exclude_se(*a, k_se=2.0, both=False, exclude=False),
        "exclude_only_latency": lambda *a: _exclude_se(*a, k_se=0.0, both=False),
        "se_latency_and_quadratic": v_combined}
VARIANTS = {"before": v_before, "exclude_se": v_exclude_se, "noise_floor": v_noise_floor, "local_slope": v_local_slope,
            "quadratic": v_quadratic, "quadratic_latency": v_quadratic_latency, **MORE, **GATES}


@contextlib.contextmanager
def variant(rule):
    old = lc.step_rule_verdict, lc.gap_is_latency, lc.gap_after_verdict
    lc.step_rule_verdict = rule
    lc.gap_is_latency = lambda *a, **kw: rule(*a, **kw) == "latency"
    if getattr(rule, "names_directly", False):
        lc.gap_after_verdict = lambda *a, **kw: None if _GATED[0] else old[2](*a, **kw)
    try:
        yield
    finally:
        lc.step_rule_verdict, lc.gap_is_latency, lc.gap_after_verdict = old


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rates", default="2,12")
    p.add_argument("--variant", default="driver", help="driver (rig/loadcell.py as it is), all, or one of " + ", ".join(VARIANTS))
    p.add_argument("--positions", type=int, default=40, help="gap positions drawn per history above 2 Hz")
    p.add_argument("--fresh", action="store_true")
    p.add_argument("--wrong", action="store_true", help="list the confident wrong cases")
    args = p.parse_args(argv)
    logging.getLogger("flowcurve.rig.loadcell").setLevel(logging.ERROR)  # the driver's per-gap warnings
    rates = [float(r) for r in args.rates.split(",")]
    names = ["driver"] if args.variant == "driver" else list(VARIANTS) if args.variant == "all" else args.variant.split(",")
    for name in names:
        ctx = contextlib.nullcontext() if name == "driver" else variant(VARIANTS[name])
        with ctx:
            table, wrong = measure(rates, args.positions, args.fresh)
        print_table(name, table, rates)
        if args.wrong:
            for w in wrong:
                print("   ", *w)


if __name__ == "__main__":
    main()

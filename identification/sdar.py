"""The slope of the linear region of a test record by SDAR (Slope Determination by Analysis of
Residuals, ASTM E3076-18; NIST Technical Note 2050; Graham & Adler, J. Test. Eval. 39 (2011)).

1. Shift the record to its first point; the offset point (x at the first y above 5 % of the
   largest y, that y + 15 % of the largest y) lies above the curve; the tangent from it touches
   the curve where the linear region has surely ended (the tangency point). The record up to
   it is normalized by the tangency point's x and y (§6.3).
2. Data quality (§6.4, §6.5): the noise of the normalized increments (≤ 0.5 % of the range) and
   the digital resolution (the commonest non-zero second difference ≤ 3 bins of 2⁻¹²).
3. Every contiguous window of at least max(20 %, 10) of the points gets a regression line; the
   one with the least normalized residual 1 − R² is the linear region. When it reaches the
   tangency point the offset is raised by 5 % of the largest y and the search repeated (§6.6).
4. Fit quality (§6.7, §6.8): the residuals in the first and last quarter of the window must not
   trend by more than 5 % of the slope (curvature), and the window must span ≥ 40 % of the
   normalized y range. The least-residual window stays the linear region when it fails them, as
   the standard has it; the failed checks are reported (:meth:`SdarFit.failed_checks`).

The window search is coarse to fine (:func:`least_residual_window`): every window's regression
is O(1) from cumulative sums, starts and ends on a grid first, then refined around the best.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.iso6892 import first_index

OFFSET_START = 0.05  # the offset point's x: the first y above this fraction of the largest y
OFFSET_RISE = 0.15  # ... its y: that y plus this fraction (raised by OFFSET_STEP on a retry)
OFFSET_STEP = 0.05
MAX_OFFSET_RAISES = 17
MIN_WINDOW_FRACTION = 0.2  # the shortest regression window, a fraction of the normalized points
MIN_WINDOW_POINTS = 10
NOISE_LIMIT = 0.005  # normalized increment noise allowed (standard deviation)
RESOLUTION_BIN = 2.0**-12  # the optimum digital resolution of normalized data
RESOLUTION_LIMIT_BINS = 3
CROWDED_BIN = 0.25  # a resolution bin holding more than this share of the samples fails the check
CURVATURE_LIMIT = 0.05  # residual slope in the outer quarters, a fraction of the slope
MIN_QUARTER_POINTS = 5
MIN_FIT_RANGE = 0.4  # normalized y range of the window
MIN_SLOPE_OVER_SECANT = 0.5  # a window flatter than half the secant to its top lies past yield (hardening slopes are a few % of E)


@dataclass
class SdarFit:
    """The linear region found by SDAR: y ≈ slope·x + intercept over ``indices`` (of the input),
    with the quality metrics of ASTM E3076-18 and whether each passed."""

    slope: float
    intercept: float
    indices: np.ndarray
    normalized_residual: float
    offset_raises: int
    quality: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        """All data and fit quality checks passed."""
        return all(v["passed"] for v in self.quality.values())

    def failed_checks(self) -> list[str]:
        """The names of the quality checks that failed."""
        return [k for k, v in self.quality.items() if not v["passed"]]


def tangency_index(x: np.ndarray, y: np.ndarray, raises: int = 0) -> int:
    """Index of the tangency point of the line from the offset point to the curve (§6.3): the
    highest local maximum of the tangent slope (2 rises before and 2 falls after, else 1)."""
    y_max = float(np.max(y))
    start = first_index(lambda at: y[at] > OFFSET_START * y_max, 0, y.size)
    if start is None or not y_max > 0:
        raise IdentificationError("SDAR: the record does not rise; no linear region")
    x_off, y_off = x[start], y[start] + (OFFSET_RISE + OFFSET_STEP * raises) * y_max
    above = np.flatnonzero((y > y_off) & (x > x_off))
    if above.size < 3:
        raise IdentificationError(f"SDAR: the record never rises {100 * (OFFSET_RISE + OFFSET_STEP * raises):.0f} % of its range above the offset point: no tangency point")
    slope = (y[above] - y_off) / (x[above] - x_off)
    up = np.diff(slope) > 0
    m = slope.size
    for need in (2, 1):
        is_peak = np.ones(max(m - 2 * need, 0), dtype=bool)  # the candidates k = need … m − need − 1
        for j in range(need):
            is_peak &= up[need - j - 1: m - need - j - 1] & ~up[need + j: m - need + j]  # rising into k, falling out of it
        if is_peak.any():
            peaks = need + np.flatnonzero(is_peak)
            return int(above[peaks[np.argmax(slope[peaks])]])
    raise IdentificationError("SDAR: the tangent from the offset point touches the curve nowhere (no tangency point): the record has no curved end")


def noise_metrics(xn: np.ndarray, yn: np.ndarray) -> dict:
    """§6.4: standard deviation of the normalized increments about their mean, relative to 0.5 %."""
    out = {}
    for name, v in (("x", xn), ("y", yn)):
        d = np.diff(v)
        rel = float(np.std(d - d.mean(), ddof=1) / NOISE_LIMIT) if d.size > 1 else float("nan")
        out[name] = rel
    return {"relative_noise_x": out["x"], "relative_noise_y": out["y"], "passed": bool(out["x"] <= 1.0 and out["y"] <= 1.0)}


def resolution_metrics(xn: np.ndarray, yn: np.ndarray) -> dict:
    """§6.5: the commonest non-zero bin (width 2⁻¹²) of |second differences|, relative to 3 bins;
    failing that, neither that bin nor the zeroth may hold more than 25 % of the samples."""
    out: dict = {}
    ok = True
    for name, v in (("x", xn), ("y", yn)):
        dd = np.abs(np.diff(np.diff(v)))
        if dd.size == 0:
            out[f"relative_resolution_{name}"], ok = float("nan"), False
            continue
        bins = np.floor(dd / RESOLUTION_BIN + 0.5).astype(np.int64)
        counts = np.bincount(bins)
        z = int(np.argmax(counts[1:]) + 1) if counts.size > 1 else 1
        rel = z / RESOLUTION_LIMIT_BINS
        share_z = float(counts[z] / dd.size) if z < counts.size else 0.0
        share_0 = float(counts[0] / dd.size)
        passed = rel <= 1.0 or (share_z <= CROWDED_BIN and share_0 <= CROWDED_BIN)
        out[f"relative_resolution_{name}"] = float(rel)
        out[f"zeroth_bin_share_{name}"] = share_0
        ok = ok and passed
    out["passed"] = bool(ok)
    return out


def _window_residuals(k, sx, sy, sxx, sxy, syy) -> np.ndarray:
    """Normalized residual 1 − R² of the regression over windows given by their sums of
    (1, x, y, x², xy, y²); inf where x or y does not vary. Equation: R² = Sxy²/(Sxx·Syy), S·· the centred sums."""
    with np.errstate(divide="ignore", invalid="ignore"):
        vxx, vxy, vyy = sxx - sx * sx / k, sxy - sx * sy / k, syy - sy * sy / k
        return np.where((vxx > 0) & (vyy > 0), 1.0 - vxy * vxy / (vxx * vyy), np.inf)


def _grid_best(c: list[np.ndarray], starts: np.ndarray, ends: np.ndarray, n_min: int, keep: int = 1) -> list[tuple[float, int, int]]:
    """The ``keep`` least residual windows (residual, start, exclusive end) over every pair of the
    two grids with at least ``n_min`` samples, in blocks of rows to bound the memory."""
    found: list[tuple[float, int, int]] = []
    at_end = [cj[ends][None, :] for cj in c]
    rows = max(1, 2_000_000 // max(ends.size, 1))
    for b in range(0, starts.size, rows):
        i = starts[b: b + rows]
        res = _window_residuals(*(e - cj[i][:, None] for e, cj in zip(at_end, c)))
        res[ends[None, :] - i[:, None] < n_min] = np.inf
        res = res.ravel()
        top = np.argpartition(res, keep - 1)[:keep] if res.size > keep else np.arange(res.size)
        found += [(float(res[m]), int(i[m // ends.size]), int(ends[m % ends.size])) for m in top if np.isfinite(res[m])]
    return sorted(found)[:keep]


EXHAUSTIVE_POINTS = 2000  # up to this many points every window is scanned (about 1.3 million)
COARSE_POINTS = 300  # above it, the coarse grid of starts and ends (stride n/300)
COARSE_CANDIDATES = 8  # the coarse grid's best windows refined on the finer grids
MIN_REFINE_SPAN = 16  # samples either side of a candidate's start and end searched on the next grid


def least_residual_window(xn: np.ndarray, yn: np.ndarray, *, stride: int | None = None) -> tuple[float, int, int]:
    """(1 − R², first, last) of the contiguous window of at least max(20 %, 10) points with the
    least normalized residual (§6.6); every window regressed from cumulative sums.

    Every window up to 2000 points; on a longer record coarse to fine: starts and ends on a grid
    of ``stride`` samples (default n/300), then every start and end within two grid steps (at
    least 16 samples) of the 8 best, on finer grids down to single samples. Each window's residual is exact (the
    full-resolution sums); only the windows scanned are fewer."""
    n = xn.size
    n_min = max(int(math.floor(MIN_WINDOW_FRACTION * n)), MIN_WINDOW_POINTS)
    if n < n_min:
        raise IdentificationError(f"SDAR: only {n} samples up to the tangency point; the linear region needs at least {MIN_WINDOW_POINTS}")
    c = [np.concatenate([[0.0], np.cumsum(v)]) for v in (np.ones(n), xn, yn, xn * xn, xn * yn, yn * yn)]
    if stride is None:
        stride = 1 if n <= EXHAUSTIVE_POINTS else n // COARSE_POINTS
    step = max(1, int(stride))
    best = _grid_best(c, np.arange(0, n - n_min + 1, step), np.arange(n_min, n + 1, step), n_min, COARSE_CANDIDATES if step > 1 else 1)
    while step > 1 and best:
        span, step = max(2 * step, MIN_REFINE_SPAN), max(1, step // 8)
        refined = []
        for _, i0, j0 in best:
            starts = np.arange(max(0, i0 - span), min(n - n_min, i0 + span) + 1, step)
            ends = np.arange(max(n_min, j0 - span), min(n, j0 + span) + 1, step)
            refined += _grid_best(c, starts, ends, n_min, 1 if step == 1 else 2)
        best = sorted(set(refined + best))[:COARSE_CANDIDATES]
    if not best:
        raise IdentificationError("SDAR: no window of the record varies in both x and y")
    resid, i, j = best[0]
    return resid, i, j - 1


def curvature_metrics(xn: np.ndarray, yn: np.ndarray, slope: float, intercept: float) -> dict:
    """§6.7 and §6.8 on the window: the residual slope in the first and the last quarter of its
    x range, relative to 5 % of the slope (≥ 5 points each), and the normalized y range (≥ 0.4)."""
    r = yn - (slope * xn + intercept)
    lo, hi = float(xn.min()), float(xn.max())
    out: dict = {}
    ok = True
    for name, sel in (("first_quarter", xn <= lo + 0.25 * (hi - lo)), ("fourth_quarter", xn >= lo + 0.75 * (hi - lo))):
        count = int(sel.sum())
        if count >= 2 and np.ptp(xn[sel]) > 0:
            rel = float(np.polyfit(xn[sel], r[sel], 1)[0] / (CURVATURE_LIMIT * slope))
        else:
            rel = float("nan")
        out[f"relative_residual_slope_{name}"] = rel
        out[f"points_{name}"] = count
        ok = ok and count >= MIN_QUARTER_POINTS and abs(rel) <= 1.0
    fit_range = float(np.ptp(yn))
    out["normalized_y_range"] = fit_range
    return {"curvature": {**{k: v for k, v in out.items() if k != "normalized_y_range"}, "passed": bool(ok)},
            "fit_range": {"normalized_y_range": fit_range, "passed": bool(fit_range >= MIN_FIT_RANGE)}}


def sdar(x, y) -> SdarFit:
    """The linear region of the record (x, y) by SDAR (ASTM E3076-18): slope and intercept of
    the regression over it (in the record's units), its indices, and the quality metrics.

    The record should run from the start of loading past the end of the linear region (a
    tension curve up to its maximum force, a compression curve past yield). One-line errors
    when there is no tangency point or fewer than 10 samples before it."""
    x0 = np.asarray(x, dtype=float)
    y0 = np.asarray(y, dtype=float)
    finite = np.isfinite(x0) & np.isfinite(y0)
    ok = np.arange(x0.size) if finite.all() else np.flatnonzero(finite)
    if ok.size < MIN_WINDOW_POINTS:
        raise IdentificationError(f"SDAR: only {ok.size} finite samples; at least {MIN_WINDOW_POINTS} are needed")
    x_ok, y_ok = (x0, y0) if ok.size == x0.size else (x0[ok], y0[ok])  # every sample finite: no copy of a long record
    xs, ys = x_ok - x_ok[0], y_ok - y_ok[0]
    for raises in range(MAX_OFFSET_RAISES + 1):
        t = tangency_index(xs, ys, raises)
        x_t, y_t = xs[t], ys[t]
        if not (x_t > 0 and y_t > 0):
            raise IdentificationError("SDAR: the tangency point is not up and to the right of the start")
        keep = np.flatnonzero((ys <= y_t) & (xs <= x_t))
        xn, yn = xs[keep] / x_t, ys[keep] / y_t
        resid, i, j = least_residual_window(xn, yn)
        if j < keep.size - 1:
            break
    else:
        raise IdentificationError("SDAR: the linear region runs up to the tangency point however high the offset is raised: no end of the linear part")
    # the least residual window is the linear region (§6.6) whatever its fit quality: a failed
    # check is reported (§6.7, §6.8), never replaced by a lower-ranked window
    m_n, b_n = np.polyfit(xn[i: j + 1], yn[i: j + 1], 1)
    fit_quality = curvature_metrics(xn[i: j + 1], yn[i: j + 1], float(m_n), float(b_n))
    window = keep[i: j + 1]
    if xn[j] > 0 and m_n < MIN_SLOPE_OVER_SECANT * yn[j] / xn[j]:
        raise IdentificationError(f"SDAR: its linear region ({j - i + 1} samples) is flatter than the secant from the start to its top: a stretch "
                                  "past yield, not the elastic line, which has too few samples (sample faster or give the modulus)")
    quality = {"noise": noise_metrics(xn, yn), "resolution": resolution_metrics(xn, yn), **fit_quality}
    slope, intercept = np.polyfit(x_ok[window], y_ok[window], 1)
    return SdarFit(slope=float(slope), intercept=float(intercept), indices=ok[window], normalized_residual=resid,
                   offset_raises=raises, quality=quality)

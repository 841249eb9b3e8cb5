"""Indicator-diagram (P–Δl) processing: what turns a crosshead reading into specimen elongation.

docs/methods.md §2: frame compliance (§2.1), scaling to the elongation measured on the specimen
((3.1), §2.2), toe/slack compensation, the apparent modulus of the initial linear part (§2.3),
and the frame stiffness identified from a specimen of known modulus (§2.4).

Units: displacements in mm, forces in N, stiffness in N/µm, stresses in MPa.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.iso6892 import first_index, mad_sigma_of_differences

UM_PER_MM = 1000.0


def remove_frame_compliance(crosshead_mm, force_N, stiffness_N_per_um: float) -> np.ndarray:
    """Specimen elongation from the crosshead travel: Δl = Δl_crosshead − P/C (§2.1), in mm."""
    if not stiffness_N_per_um > 0:
        raise IdentificationError(f"frame stiffness must be > 0 N/µm, got {stiffness_N_per_um!r}")
    # (§2.1) Δl_specimen = Δl_crosshead − P / C_frame   (P/C in µm → mm)
    return np.asarray(crosshead_mm, dtype=float) - np.asarray(force_N, dtype=float) / (stiffness_N_per_um * UM_PER_MM)


def scale_to_measured(displacement_mm, measured_final_mm: float, reference_mm: float | None = None) -> tuple[np.ndarray, float]:
    """Scale a displacement so that ``reference_mm`` (default: its largest value) becomes the measured one (3.1).

    Returns the scaled array and the factor K_l = Δl_p / reference (the seed's: Δl_p / max Δl).
    """
    disp = np.asarray(displacement_mm, dtype=float)
    peak = (float(np.nanmax(np.abs(disp))) if disp.size else 0.0) if reference_mm is None else float(reference_mm)
    if not peak > 0:
        raise IdentificationError("cannot scale to the measured elongation: the displacement never leaves zero")
    if not measured_final_mm > 0:
        raise IdentificationError(f"the measured elongation must be > 0 mm, got {measured_final_mm!r}")
    k = measured_final_mm / peak  # (3.1) K_l = Δl_p / max Δl (or the given reference)
    return disp * k, k


def broken_specimen_recovery_mm(force_N: float, length_mm: float, s0_mm2: float, E_MPa: float, uniform_elongation: float = 0.0) -> float:
    """Elastic extension a tension specimen gives back when the force F leaves it: its length and
    section at the uniform elongation e_u (constant volume), F·L·(1 + e_u)²/(E·S0)."""
    # ΔL_el = F·L(1 + e_u) / (E·S0/(1 + e_u))
    return force_N * length_mm * (1.0 + uniform_elongation) ** 2 / (E_MPa * s0_mm2)


def first_loading(y, up_to: float, unit: str = "N") -> int:
    """Index of the first sample at or above ``up_to`` (the end of the first loading branch)."""
    y = np.asarray(y, dtype=float)
    above = first_index(lambda at: y[at] >= up_to, 0, y.size)
    if above is None:
        raise IdentificationError(f"the loading curve never reaches {up_to:.4g} {unit}, the top of the fit window")
    return above


@dataclass
class LineFit:
    """y ≈ slope·x + intercept fitted over a window of the first loading branch."""

    slope: float
    intercept: float
    slope_stderr: float
    r2: float
    n_points: int
    window: tuple[float, float]  # in the units of y
    indices: np.ndarray

    @property
    def x_at_zero(self) -> float:
        """Where the line crosses y = 0 (the toe offset when y is force)."""
        return -self.intercept / self.slope


def strain_quantum_noise(strain) -> float:
    """Standard deviation of the reading error of a quantized strain signal: q/√12, q its
    smallest non-zero step (negligible for a signal that is not quantized)."""
    d = np.abs(np.diff(np.asarray(strain, dtype=float)))
    real = np.isfinite(d) & (d > 0)  # the smallest of these, without gathering them into a copy
    return float(np.min(d, where=real, initial=np.inf)) / math.sqrt(12.0) if real.any() else 0.0


def stepped_fraction(reading) -> float:
    """The share of consecutive samples with the same reading: near 1 for an encoder whose step
    spans many samples, 0 for a signal that changes at every sample."""
    d = np.diff(np.asarray(reading, dtype=float))
    finite = np.isfinite(d)
    d = d if finite.all() else d[finite]  # (every step finite: no copy)
    return float(np.mean(d == 0.0)) if d.size else 0.0


def interpolate_steps(time_s, reading) -> np.ndarray:
    """A stepped (quantized) reading re-read between its steps.

    A change of the reading between samples i and i+1 is taken as the moment the position crossed
    the middle of the two levels, halfway between the two sample times; between two crossings of
    the same direction the position is interpolated linearly in time. Each value stays inside its
    reading's cell (b ± q/2). Samples before the first crossing, after the last, and between
    crossings of opposite directions (a turn, or an encoder dithering at rest) keep the reading.
    """
    t, x = np.asarray(time_s, dtype=float), np.asarray(reading, dtype=float)
    out = x.copy()
    change = np.flatnonzero(np.diff(x) != 0.0)
    if change.size < 2:
        return out
    tc = 0.5 * (t[change] + t[change + 1])  # crossing times
    xc = 0.5 * (x[change] + x[change + 1])  # mid-levels crossed
    way = np.sign(x[change + 1] - x[change])
    k = np.searchsorted(tc, t, side="right") - 1  # the crossing before each sample
    inside = np.flatnonzero((k >= 0) & (k < tc.size - 1))
    k = k[inside]
    ok = (way[k] == way[k + 1]) & (tc[k + 1] > tc[k])
    i, k = inside[ok], k[ok]
    out[i] = xc[k] + (xc[k + 1] - xc[k]) * (t[i] - tc[k]) / (tc[k + 1] - tc[k])
    return out


STEPPED_FRACTION = 0.2  # a counted reading unchanged between more than this part of its samples is re-read between its counts


def reread_if_stepped(time_s, reading) -> tuple[np.ndarray, float | None]:
    """(reading, step): a counted reading — every change a whole number of its smallest step, and
    unchanged between more than :data:`STEPPED_FRACTION` of the samples (a count spans several) —
    interpolated between its counts on its finite samples (:func:`interpolate_steps`), with that
    step; any other reading (a noisy analogue one, a count finer than the motion) as it is, with None."""
    t, x = np.asarray(time_s, dtype=float), np.asarray(reading, dtype=float)
    finite = np.isfinite(t) & np.isfinite(x)
    ok = slice(None) if finite.all() else np.flatnonzero(finite)  # every sample finite: read in place, no copy
    if x[ok].size < 3 or stepped_fraction(x[ok]) <= STEPPED_FRACTION:
        return x, None
    steps = np.abs(np.diff(x[ok]))
    if not np.any(steps > 0):
        return x, None  # a reading that never changes (a dead channel): no counts to read between
    step = float(np.min(steps[steps > 0]))
    counts = steps[steps > 0] / step
    if np.mean(np.abs(counts - np.round(counts)) < 0.01) < 0.99:  # changes that are not whole counts: not an encoder
        return x, None
    out = x.copy()
    out[ok] = interpolate_steps(t[ok], x[ok])
    return out, step


def fit_line_in_window(x, y, lo: float, hi: float, *, min_points: int = 5, unit: str = "N") -> LineFit:
    """Least-squares line through the points of the first rise of ``y`` with lo ≤ y ≤ hi.

    Only the samples before ``y`` first exceeds ``hi`` are used, so unloading loops and the
    plastic part never enter the fit.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if not hi > lo:
        raise IdentificationError(f"fit window must have hi > lo, got ({lo:.4g}, {hi:.4g})")
    end = first_loading(y, hi, unit)
    idx = np.arange(end + 1)
    idx = idx[(y[idx] >= lo) & (y[idx] <= hi) & np.isfinite(x[idx])]
    if idx.size < min_points:
        raise IdentificationError(f"only {idx.size} samples between {lo:.4g} and {hi:.4g} {unit} on the first loading; need {min_points} for a line (sample faster or widen the window)")
    xs, ys = x[idx], y[idx]
    A = np.column_stack([xs, np.ones_like(xs)])
    coef, *_ = np.linalg.lstsq(A, ys, rcond=None)
    resid = ys - A @ coef
    dof = max(idx.size - 2, 1)
    sxx = np.sum((xs - xs.mean()) ** 2)
    if sxx <= 0:
        raise IdentificationError("the displacement does not change over the fit window")
    stderr = float(np.sqrt(np.sum(resid**2) / dof / sxx))
    sst = np.sum((ys - ys.mean()) ** 2)
    r2 = float(1 - np.sum(resid**2) / sst) if sst > 0 else float("nan")
    return LineFit(float(coef[0]), float(coef[1]), stderr, r2, int(idx.size), (float(lo), float(hi)), idx)


def compensate_toe(displacement_mm, force_N, *, window_N: tuple[float, float], min_points: int = 5) -> tuple[np.ndarray, float]:
    """Toe (slack) compensation: shift the displacement so that the linear part of the loading
    curve, extrapolated to zero force, passes through zero; the toe itself (before the window)
    is replaced by that line.

    Returns the compensated displacement (mm) and the toe offset removed (mm).
    """
    disp = np.asarray(displacement_mm, dtype=float)
    force = np.asarray(force_N, dtype=float)
    line = fit_line_in_window(disp, force, *window_N, min_points=min_points)
    if line.slope <= 0:
        raise IdentificationError("the loading curve does not rise over the toe window: cannot compensate the toe")
    toe = line.x_at_zero  # F = k·(Δl − Δl0) → Δl0
    out = disp - toe
    head = np.arange(line.indices[0])
    out[head] = np.clip(force[head], 0.0, None) / line.slope  # the toe replaced by the line
    return out, float(toe)


@dataclass
class ModulusFit:
    """Apparent modulus: σ = E·e + c by linear regression over a stress window."""

    E_MPa: float
    E_stderr_MPa: float
    intercept_MPa: float
    r2: float
    n_points: int
    window_MPa: tuple[float, float]
    source: str = "given window"
    quality: dict | None = None  # SDAR's data and fit quality metrics (ASTM E3076-18), when it found the line
    sdar_failed: list[str] | None = None  # the checks SDAR's least-residual window failed, when SDAR was tried and this line replaced it

    def as_dict(self) -> dict:
        """The result's ``modulus`` block (keys with units)."""
        out = {"E_MPa": self.E_MPa, "E_stderr_MPa": self.E_stderr_MPa, "r2": self.r2, "n_points": self.n_points,
               "window_MPa": list(self.window_MPa), "source": self.source}
        if self.quality is not None:
            out["quality"] = self.quality
        if self.sdar_failed is not None:
            out["sdar_failed_checks"] = self.sdar_failed
        return out


# the automatic window: lower edges and the smallest span, fractions of the reference stress
AUTO_WINDOW_LOWS = (0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.40)
AUTO_WINDOW_MIN_SPAN = 0.25
AUTO_WINDOW_TOP = 0.80  # the elastic line ends before the onset of yield
AUTO_WINDOW_R2 = 0.9995  # a window this linear counts as linear (the Annex G quality criterion)
CONVENTIONAL_WINDOW = (0.10, 0.80)  # used when no stretch is linear (the 42CrMoS4 lab's window)
FEW_POINTS_TOP = 0.90  # with few samples, all of them up to this fraction of the yield stress
MIN_LINE_POINTS = 5  # a window with fewer samples is not a candidate of the automatic choice
MIN_FEW_POINTS = 2  # with fewer samples on the whole elastic line there is no modulus
FEW_SAMPLES = 10  # an elastic line with fewer samples is used whole, not searched for a window
GIVEN_WINDOW_POINTS = 5  # a window the caller gives needs this many samples for its line
SDAR_REACH = 2.0  # SDAR reads the first loading up to this many times the reference (yield) stress


def _slope_stats(n, sx, sy, vxx, vxy, vyy, strain_on_stress: bool) -> tuple[float, float, float]:
    """E, its standard error and the stress intercept of a line from the centred sums of
    strain x and stress y: σ regressed on ε (E = vxy/vxx), or ε on σ (1/E = vxy/vyy)."""
    if strain_on_stress:
        compliance = vxy / vyy
        se_c = math.sqrt(max(vxx - compliance * vxy, 0.0) / (n - 2) / vyy) if n > 2 else float("nan")
        slope = 1.0 / compliance if compliance != 0 else float("nan")
        se = se_c / compliance**2 if compliance != 0 else float("inf")
    else:
        slope = vxy / vxx
        se = math.sqrt(max(vyy - slope * vxy, 0.0) / (n - 2) / vxx) if n > 2 else float("nan")
    return slope, se, (sy - slope * sx) / n


def _line_stats(x: np.ndarray, y: np.ndarray, strain_on_stress: bool = False) -> tuple[float, float, float, float]:
    """Least-squares line y = a·x + b (strain x, stress y): slope, intercept, slope standard error and R²."""
    n = x.size
    vxx, vyy = float(np.sum((x - x.mean()) ** 2)), float(np.sum((y - y.mean()) ** 2))
    if vxx <= 0 or vyy <= 0:
        return float("nan"), float("nan"), float("inf"), float("nan")
    vxy = float(np.sum((x - x.mean()) * (y - y.mean())))
    slope, se, intercept = _slope_stats(n, float(x.sum()), float(y.sum()), vxx, vxy, vyy, strain_on_stress)
    return slope, intercept, se, vxy * vxy / (vxx * vyy)


def yield_onset_from_rate(time_s, force_N, levels: int = 400) -> float:
    """A first estimate of the force at the onset of yield, from the force rate alone.

    Under constant crosshead speed the force rises fastest on the elastic line (the stiffness
    of frame and specimen) and slower in the toe and after yield. The rate is taken between
    force levels (ΔF = the largest force / ``levels``, at least 5 noise standard deviations),
    as 3ΔF over the time the force envelope needs to climb 3 levels, so noise does not make
    it; the onset is the first level after the fastest climb where the rate is below half of
    it. Needs no displacement, so a coarse encoder does not matter."""
    t = np.asarray(time_s, dtype=float)
    f = np.asarray(force_N, dtype=float)
    if f.size < 8:
        raise IdentificationError(f"only {f.size} samples of the first loading: no yield estimate")
    noise = mad_sigma_of_differences(f, 1) / math.sqrt(2.0)  # of the successive differences: σ√2
    envelope = np.maximum.accumulate(f)
    step = max(envelope[-1] / levels, 5.0 * noise)
    level = np.arange(step, envelope[-1], step)
    if level.size < 8:
        raise IdentificationError("the force rises too little above its noise for a yield estimate")
    times = t[np.searchsorted(envelope, level)]
    spans = times[3:] - times[:-3]
    steps = np.diff(t)
    # the sampling period floors each span; when every span is longer than the longest step it floors none (its median not needed)
    rate = 3.0 * step / (spans if np.min(spans) > np.max(steps) else np.maximum(spans, float(np.median(steps))))
    peak = int(np.argmax(rate))
    below = np.nonzero(rate[peak:] < 0.5 * rate[peak])[0]
    return float(level[peak + int(below[0])]) if below.size else float(level[-1])


CURVED_CHECK_POINTS = 20  # windows with this many samples are also checked for curvature at their ends


def _curved(x: np.ndarray, y: np.ndarray) -> bool:
    """The residuals of the window's line trend in its first or last quarter by more than 5 % of
    its slope (the curvature check of ASTM E3076-18 §6.7, :func:`identification.sdar.curvature_metrics`)."""
    from flowcurve.identification.sdar import curvature_metrics

    slope, intercept = np.polyfit(x, y, 1)
    return not curvature_metrics(x, y, float(slope), float(intercept))["curvature"]["passed"]


def auto_modulus(strain, stress_MPa, reference_MPa: float, *, strain_on_stress: bool = False, noise_MPa: float = 0.0,
                 strain_noise: float = 0.0) -> ModulusFit:
    """The modulus over the most linear stretch of the first loading (in the manner of
    ISO 6892-1 Annex G / ASTM E111), not over a fixed fraction of the yield stress.

    Candidate windows run from lo to hi × ``reference_MPa`` (the yield stress, iterated by the
    caller), lo in AUTO_WINDOW_LOWS, hi − lo ≥ 0.25, hi ≤ 0.8; each gets a regression line. The
    widest window whose line is linear (R² ≥ 0.9995, the Annex G quality criterion, and with 20
    samples or more no residual trend at either end, the curvature check of ASTM E3076-18) wins,
    so noise is averaged over as much of the line as stays straight; a toe or early yielding bends
    the windows that reach into it (§2.3). When no window is that linear (a crosshead curve whose
    seating lasts past 0.4 × the yield stress), the linear region SDAR finds
    (:func:`sdar_modulus`) when it passes its fit quality checks, else the conventional
    0.10–0.80 × the yield stress; ``source`` says which.

    noise_MPa: the stress noise (standard deviation); with few samples the standard error of E
    is at least what that noise and the strain noise (e.g. an encoder quantum q: q/√12) give,
    √(σn² + E²·σε²)/√Σ(ε − ε̄)², so two samples still state one.
    strain_on_stress: regress strain on stress (compliance 1/E) instead of stress on strain:
    unbiased when the strain is the coarse signal (a crosshead with 10 µm steps against a
    specimen that shortens a few µm elastically, where the usual direction dilutes E).

    With fewer than 10 samples on the whole elastic line (a sparsely sampled one, e.g. 10 Hz
    on a stiff specimen) all samples of the first loading between the toe (5 %) and the onset
    of yield (90 %) are used, if there are at least 3; otherwise a one-line error.
    """
    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    if not reference_MPa > 0:
        raise IdentificationError(f"the reference stress of the modulus window must be > 0 MPa, got {reference_MPa!r}")
    top = FEW_POINTS_TOP * reference_MPa
    above = np.nonzero(s >= top)[0]
    end = int(above[0]) if above.size else s.size - 1
    e1, s1 = e[: end + 1], s[: end + 1]
    ok = np.isfinite(e1) & np.isfinite(s1)
    e1, s1 = e1[ok], s1[ok]
    line_samples = int(np.sum((s1 >= 0.05 * reference_MPa) & (s1 <= FEW_POINTS_TOP * reference_MPa)))
    best, best_r2 = _widest_linear_window(e1, s1, reference_MPa, line_samples, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                                          strain_noise=strain_noise)
    if best is not None:
        _, slope, intercept, se, r2, n, window = best
        return ModulusFit(slope, se, intercept, r2, n, (float(window[0]), float(window[1])),
                          source=f"automatic window {window[0] / reference_MPa:.2f}–{window[1] / reference_MPa:.2f} × {reference_MPa:.4g} MPa "
                                 f"(flowcurve's own method, not ASTM E3076: widest linear stretch, R² ≥ {AUTO_WINDOW_R2})")
    if np.isfinite(best_r2):  # enough samples, but no stretch is straight: SDAR's linear region, else the conventional window
        fallback = _no_linear_stretch(e, s, e1, s1, reference_MPa, best_r2, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                                      strain_noise=strain_noise)
        if fallback is not None:
            return fallback
    return _all_line_samples(e1, s1, reference_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa, strain_noise=strain_noise)


def _widest_linear_window(e1, s1, reference_MPa: float, line_samples: int, *, strain_on_stress: bool, noise_MPa: float,
                          strain_noise: float) -> tuple[tuple | None, float]:
    """The widest window lo–hi × the reference whose line is linear (R² ≥ AUTO_WINDOW_R2, no end
    trend), of equal ones the surest slope: ((score, slope, intercept, se, r2, n, window_MPa) or
    None, the best R² of the windows that were not linear). Windows are contiguous runs of the
    samples sorted by stress, their sums read off cumulative sums."""
    best, best_r2 = None, -np.inf
    order = np.argsort(s1, kind="stable")
    xs, ys = e1[order], s1[order]
    # cumulative sums over the samples sorted by stress: every window is a contiguous run
    cums = [np.concatenate([[0.0], np.cumsum(v)]) for v in (np.ones_like(xs), xs, ys, xs * xs, xs * ys, ys * ys)]
    for lo in AUTO_WINDOW_LOWS:
        for hi in np.arange(lo + AUTO_WINDOW_MIN_SPAN, AUTO_WINDOW_TOP + 1e-9, 0.05):
            i = int(np.searchsorted(ys, lo * reference_MPa, side="left"))
            j = int(np.searchsorted(ys, hi * reference_MPa, side="right"))
            n, sx, sy, sxx, sxy, syy = (c[j] - c[i] for c in cums)
            if n < MIN_LINE_POINTS or line_samples < FEW_SAMPLES:
                continue
            vxx, vxy, vyy = sxx - sx * sx / n, sxy - sx * sy / n, syy - sy * sy / n
            if not (vxx > 0 and vyy > 0):
                continue
            slope, se, intercept = _slope_stats(n, sx, sy, vxx, vxy, vyy, strain_on_stress)
            r2 = vxy * vxy / (vxx * vyy)
            if not slope > 0:
                continue
            se = max(se, math.sqrt(noise_MPa**2 + (slope * strain_noise) ** 2) / math.sqrt(vxx))  # the readings' own noise
            if r2 < AUTO_WINDOW_R2:
                best_r2 = max(best_r2, r2)
                continue
            if n >= CURVED_CHECK_POINTS and _curved(xs[i:j], ys[i:j]):
                continue  # straight by R², yet its residuals trend at an end: a toe or the knee bends it
            score = (-(hi - lo), se / slope)  # the widest linear window; of equal ones, the surest slope
            if best is None or score < best[0]:
                best = (score, slope, intercept, se, r2, int(n), (lo * reference_MPa, hi * reference_MPa))
    return best, best_r2


def _no_linear_stretch(e, s, e1, s1, reference_MPa: float, best_r2: float, *, strain_on_stress: bool, noise_MPa: float,
                       strain_noise: float) -> ModulusFit | None:
    """No window is linear: SDAR's linear region when it passes its curvature and fit-range checks,
    else the conventional CONVENTIONAL_WINDOW × the reference; None when neither gives a rising line."""
    try:
        by_sdar = sdar_modulus(e, s, upto_MPa=SDAR_REACH * reference_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                               strain_noise=strain_noise)
    except IdentificationError:
        by_sdar = None
    if by_sdar is not None and by_sdar.quality["curvature"]["passed"] and by_sdar.quality["fit_range"]["passed"]:
        by_sdar.source = f"no stretch below {AUTO_WINDOW_TOP:g} × {reference_MPa:.4g} MPa is linear (best R² {best_r2:.5f}): {by_sdar.source}"
        return by_sdar
    lo, hi = CONVENTIONAL_WINDOW
    sel = (s1 >= lo * reference_MPa) & (s1 <= hi * reference_MPa)
    if sel.sum() >= MIN_LINE_POINTS:
        slope, intercept, se, r2 = _line_stats(e1[sel], s1[sel], strain_on_stress)
        if slope > 0:
            return ModulusFit(slope, se, intercept, r2, int(sel.sum()), (lo * reference_MPa, hi * reference_MPa),
                              source=f"conventional window {lo:g}–{hi:g} × {reference_MPa:.4g} MPa: no stretch of the first loading is linear "
                                     f"(best R² {best_r2:.5f} < {AUTO_WINDOW_R2})")
    return None


def _all_line_samples(e1, s1, reference_MPa: float, *, strain_on_stress: bool, noise_MPa: float, strain_noise: float) -> ModulusFit:
    """Too few samples for a window: the line through all of the first loading's samples between
    the toe (5 %) and FEW_POINTS_TOP of the reference, at least MIN_FEW_POINTS of them; its standard
    error at least what the readings' noise gives, √(σn² + E²·σε²)/√Σ(ε − ε̄)²."""
    window = (0.05 * reference_MPa, FEW_POINTS_TOP * reference_MPa)
    sel = (s1 >= window[0]) & (s1 <= window[1])
    if sel.sum() < MIN_FEW_POINTS:
        raise IdentificationError(f"only {int(sel.sum())} samples on the elastic line (between {window[0]:.4g} and {window[1]:.4g} MPa of the first loading); "
                                  f"need {MIN_FEW_POINTS} for a modulus: sample faster or give the handbook modulus (--E or material.E_MPa)")
    slope, intercept, se, r2 = _line_stats(e1[sel], s1[sel], strain_on_stress)
    if not slope > 0:
        raise IdentificationError(f"the stress does not rise with strain on the elastic line ({int(sel.sum())} samples): no modulus")
    count = int(sel.sum())
    x = e1[sel]
    sxx = float(np.sum((x - x.mean()) ** 2))
    from_noise = math.sqrt(noise_MPa**2 + (slope * strain_noise) ** 2) / math.sqrt(sxx) if sxx > 0 else float("inf")
    se = max(se, from_noise) if np.isfinite(se) else from_noise
    return ModulusFit(slope, se, intercept, r2, count, (float(window[0]), float(window[1])),
                      source=f"all {count} samples of the elastic line (too few for a window"
                             + ("; two samples: uncertainty from the force noise only" if count == 2 else "") + ")")


MODULUS_METHODS = ("auto", "window", "sdar")
DEFAULT_MODULUS_METHOD = "auto"  # SDAR on a crosshead (it leaves a seating toe out), the window on an extensometer: bench/modulus_methods.py


def sdar_modulus(strain, stress_MPa, *, upto_MPa: float | None = None, strain_on_stress: bool = False, noise_MPa: float = 0.0,
                 strain_noise: float = 0.0) -> ModulusFit:
    """The modulus over the linear region SDAR finds (ASTM E3076-18, :mod:`identification.sdar`)
    on the first loading up to its largest stress, or up to ``upto_MPa`` for a curve that keeps
    rising (compression). The window's stress range, the regression over it (strain on stress
    with ``strain_on_stress``, see :func:`auto_modulus`) and SDAR's quality metrics; a failed
    metric is named in ``source``."""
    from flowcurve.identification.sdar import sdar

    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    top = float(np.nanmax(s)) if upto_MPa is None else min(float(upto_MPa), float(np.nanmax(s)))
    end = int(np.argmax(s >= top))
    fit = sdar(e[: end + 1], s[: end + 1])
    idx = fit.indices
    slope, intercept, se, r2 = _line_stats(e[idx], s[idx], strain_on_stress)
    if not slope > 0:
        raise IdentificationError(f"SDAR: the stress does not rise with strain over its linear region ({idx.size} samples): no modulus")
    sxx = float(np.sum((e[idx] - e[idx].mean()) ** 2))
    from_noise = math.sqrt(noise_MPa**2 + (slope * strain_noise) ** 2) / math.sqrt(sxx) if sxx > 0 else float("inf")
    se = max(se, from_noise) if np.isfinite(se) else from_noise
    window = (float(np.min(s[idx])), float(np.max(s[idx])))
    failed = fit.failed_checks()
    return ModulusFit(slope, se, intercept, r2, int(idx.size), window,
                      source=f"SDAR (ASTM E3076-18) {window[0]:.4g}–{window[1]:.4g} MPa, {idx.size} samples"
                             + (f"; failed quality checks: {', '.join(failed)}" if failed else "; all quality checks passed"),
                      quality={k: dict(v) for k, v in fit.quality.items()})


def _sdar_once(memo: dict | None, strain, stress_MPa, **options) -> ModulusFit:
    """:func:`sdar_modulus` of the curve, computed once per ``options`` while the caller keeps ``memo``
    (a dict it passes with the same curve every time); a copy, so the caller may relabel it."""
    if memo is None:
        return sdar_modulus(strain, stress_MPa, **options)
    key = tuple(sorted(options.items()))
    if key not in memo:
        try:
            memo[key] = sdar_modulus(strain, stress_MPa, **options)
        except IdentificationError as exc:
            memo[key] = exc
    if isinstance(memo[key], IdentificationError):
        raise memo[key]
    return copy.deepcopy(memo[key])


def elastic_modulus(method: str, strain, stress_MPa, reference_MPa: float, *, upto_MPa: float | None = None, strain_on_stress: bool = False,
                    noise_MPa: float = 0.0, strain_noise: float = 0.0, crosshead: bool = False, sdar_memo: dict | None = None) -> ModulusFit:
    """The modulus of the first loading by ``method``: "window" (:func:`auto_modulus`, the widest
    linear stretch below ``reference_MPa``), "sdar" (:func:`sdar_modulus`), or "auto": on a
    ``crosshead`` strain SDAR's line when it passes its fit quality checks, else (and on an
    extensometer) the window. ``sdar_memo``: a dict kept by a caller that asks again of the same
    curve with another reference (SDAR's line does not depend on it: computed once)."""
    if method == "auto":
        sdar_failed = None
        if crosshead:
            try:
                fit = _sdar_once(sdar_memo, strain, stress_MPa, upto_MPa=upto_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                                 strain_noise=strain_noise)
                if fit.quality["curvature"]["passed"] and fit.quality["fit_range"]["passed"]:
                    return fit
                sdar_failed = [k for k, v in fit.quality.items() if not v["passed"]]
                why = f"SDAR's least-residual window failed {', '.join(sdar_failed)}"
            except IdentificationError as exc:
                sdar_failed, why = ["no linear region"], str(exc)
        window_fit = auto_modulus(strain, stress_MPa, reference_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                                  strain_noise=strain_noise)
        if sdar_failed is not None:  # the standard's method was tried and is named with its failure, not replaced silently
            window_fit.source = f"{why} (ASTM E3076-18, not used): {window_fit.source}"
            window_fit.sdar_failed = sdar_failed
        return window_fit
    if method == "sdar":
        return _sdar_once(sdar_memo, strain, stress_MPa, upto_MPa=upto_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa,
                          strain_noise=strain_noise)
    if method != "window":
        raise IdentificationError(f"unknown modulus method {method!r} (choose from {', '.join(MODULUS_METHODS)})")
    return auto_modulus(strain, stress_MPa, reference_MPa, strain_on_stress=strain_on_stress, noise_MPa=noise_MPa, strain_noise=strain_noise)


def fit_modulus(strain, stress_MPa, window_MPa: tuple[float, float], *, min_points: int = 5,
                strain_on_stress: bool = False) -> ModulusFit:
    """Apparent modulus by linear regression of stress on strain over ``window_MPa`` (§2.3)
    (of strain on stress with ``strain_on_stress``, see :func:`auto_modulus`)."""
    line = fit_line_in_window(strain, stress_MPa, *window_MPa, unit="MPa", min_points=min_points)
    slope, intercept, se, r2 = line.slope, line.intercept, line.slope_stderr, line.r2
    if strain_on_stress:
        idx = line.indices
        slope, intercept, se, r2 = _line_stats(np.asarray(strain, dtype=float)[idx], np.asarray(stress_MPa, dtype=float)[idx], True)
    if not slope > 0:
        raise IdentificationError(f"the stress does not rise with strain between {window_MPa[0]:.4g} and {window_MPa[1]:.4g} MPa: no modulus")
    return ModulusFit(slope, se, intercept, r2, line.n_points, line.window, source="given window")


def frame_stiffness_from_known_modulus(crosshead_mm, force_N, *, E_MPa: float, area_mm2: float, length_mm: float,
                                       window_N: tuple[float, float]) -> float:
    """Frame stiffness (N/µm) from a specimen of known modulus (§2.4).

    The elastic crosshead compliance is the sum of specimen and frame: dΔl/dP = L/(E·S) + 1/C,
    so 1/C = dΔl/dP − L/(E·S), with dΔl/dP regressed over ``window_N`` of the first loading.
    """
    for name, value in (("E_MPa", E_MPa), ("area_mm2", area_mm2), ("length_mm", length_mm)):
        if not value > 0:
            raise IdentificationError(f"{name} must be > 0, got {value!r}")
    line = fit_line_in_window(crosshead_mm, force_N, *window_N)  # P = k·Δl + c
    total_mm_per_N = 1.0 / line.slope
    specimen_mm_per_N = length_mm / (E_MPa * area_mm2)
    frame_mm_per_N = total_mm_per_N - specimen_mm_per_N  # 1/C = dΔl/dP − L/(E S)
    if frame_mm_per_N <= 0:
        raise IdentificationError(
            f"the crosshead is stiffer ({line.slope * 1e-3:.4g} N/µm) than the specimen alone "
            f"({E_MPa * area_mm2 / length_mm * 1e-3:.4g} N/µm): check E, area and length")
    return 1.0 / (frame_mm_per_N * UM_PER_MM)

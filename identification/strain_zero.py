"""The strain zero of a true curve and how sure it is (docs/methods.md §2.11).

The plastic strain of every point is measured from the foot of the elastic line (ISO 6892-1 toe
compensation): an error δε0 there shifts the whole curve along εp, which moves σ by
|dσ/dεp|·δε0 — a few MPa where the curve is flat, several per cent at the start of a steeply
hardening one. This module says how large δε0 is and what it does to the curve's start.
"""

from __future__ import annotations

import math

import numpy as np

from flowcurve.identification.iso6892 import nan_argmax

START_LIMIT = 0.01  # u_σ/σ below which the curve's start is counted as resting on more than the strain zero
WARN_LIMIT = 0.02  # u_σ/σ at the fit range's start above which the result warns
HANDBOOK_E_REL_U = 0.05  # a handbook modulus (or a given one) taken as ±5 % (1 σ) of the specimen's


def line_zero_u(E_MPa: float, E_stderr_MPa: float, window_MPa) -> float:
    """Standard error of the strain zero ε0 = −c/E of a least-squares elastic line.

    E_MPa, E_stderr_MPa: the line's slope and its standard error; window_MPa: (lo, hi) stress
    window the line was regressed over (samples taken as evenly spread in it).
    Equation: x-intercept error of a line, δε0 = (s_E/E)·√(σ̄² + Δσ²/12)/E, σ̄ and Δσ the window's
    centre and span (the intercept at the centroid and the slope's error, uncorrelated)."""
    if not (np.isfinite(E_MPa) and np.isfinite(E_stderr_MPa) and E_MPa > 0):
        return 0.0
    lo, hi = float(window_MPa[0]), float(window_MPa[1])
    centre, span = 0.5 * (lo + hi), hi - lo
    return float(abs(E_stderr_MPa) / E_MPa * math.sqrt(centre**2 + span**2 / 12.0) / E_MPa)


def _zero_of_line(strain: np.ndarray, stress: np.ndarray) -> float | None:
    if strain.size < 2 or np.ptp(strain) <= 0:
        return None
    slope, intercept = np.polyfit(strain, stress, 1)
    return None if not slope > 0 else float(-intercept / slope)


def line_curvature_u(strain, stress_MPa, window_MPa) -> float:
    """The strain zero's spread from a line that is not straight (a toe, plasticity at its top).

    strain, stress_MPa: the first loading (engineering strain, MPa); window_MPa: the line's window.
    Equation: half the difference of the zeros (−c/E) of lines through the window's lower and
    upper halves, |ε0,low − ε0,high|/2; 0 when either half has fewer than 2 samples."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    lo, hi = float(window_MPa[0]), float(window_MPa[1])
    top = nan_argmax(stress) if stress.size else 0
    on = np.flatnonzero((stress[: top + 1] >= lo) & (stress[: top + 1] <= hi) & np.isfinite(strain[: top + 1]))
    if on.size < 4:
        return 0.0
    halves = np.array_split(on, 2)
    zeros = [_zero_of_line(strain[h], stress[h]) for h in halves]
    if any(z is None for z in zeros):
        return 0.0
    return float(abs(zeros[0] - zeros[1]) / 2.0)


def _zero_of_known_slope(strain: np.ndarray, stress: np.ndarray, E_MPa: float) -> float:
    """The zero of a line of known slope E through the samples: the median of their offsets ε − σ/E
    (compression's toe of a handbook E, :func:`.compression.identify.toe_offsets`)."""
    return float(np.median(strain - stress / E_MPa))


def top_step_u(strain, stress_MPa, window_MPa) -> float:
    """Where the curve's plastic part starts, from the sample spacing at the line's top: the yield
    anywhere within the step after the line's last sample, rectangular, u = Δε/√3 (what an offset
    crossing read between those samples carries; the line's foot: :func:`top_spacing_u`)."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    top = nan_argmax(stress) if stress.size else 0
    on = np.flatnonzero(stress[: top + 1] <= float(window_MPa[1]))
    if on.size == 0 or on[-1] + 1 >= strain.size:
        return 0.0
    step = abs(strain[on[-1] + 1] - strain[on[-1]])
    return float(step / math.sqrt(3.0)) if np.isfinite(step) else 0.0


def _top_plastic_part(strain: np.ndarray, stress: np.ndarray, window_MPa, E_MPa: float):
    """(the window's sample indices, their offsets ε − σ/E, the last one's plastic part p) on a line of known
    slope E, p = the last offset above the others' median, at most the step Δε to the next sample; None where
    no step follows the window, it holds under 2 samples, or its samples up to the median lie off one line of
    slope E by more than it spans (the zero not resolved)."""
    lo, hi = float(window_MPa[0]), float(window_MPa[1])
    step = top_step_u(strain, stress, window_MPa) * math.sqrt(3.0)
    top = nan_argmax(stress) if stress.size else 0
    below = np.flatnonzero(stress[: top + 1] <= hi)
    if step == 0.0 or not (np.isfinite(E_MPa) and E_MPa > 0) or below.size == 0:
        return None
    last = below[-1]
    on = np.flatnonzero((stress[: last + 1] >= lo) & np.isfinite(strain[: last + 1]))
    if on.size < 2 or on[-1] != last:
        return None
    offsets = strain[on] - stress[on] / E_MPa  # ε − σ/E: one value, the zero, on a line of slope E
    low = slice(0, on.size // 2 + 1)  # the samples up to the median: they place it
    if np.ptp(offsets[low]) > np.ptp(stress[on][low]) / E_MPa:
        return None
    return on, offsets, min(step, max(float(offsets[-1] - np.median(offsets[:-1])), 0.0))


def known_slope_offsets(strain, stress_MPa, window_MPa, E_MPa: float) -> np.ndarray:
    """The offsets ε − σ/E of the window's samples on a line of known slope E (compression's toe: their median
    places the zero), the last sample's plastic part (:func:`_top_plastic_part`, :func:`top_spacing_u`'s share)
    taken out of it where 3 samples or more tell it from their spread (two: kept whole, the spread is the top's
    plastic part or not). Equation: ε − σ/E, the last one less p."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    lo, hi = float(window_MPa[0]), float(window_MPa[1])
    top = nan_argmax(stress) if stress.size else 0
    on = np.flatnonzero((stress[: top + 1] >= lo) & (stress[: top + 1] <= hi) & np.isfinite(strain[: top + 1]))
    offsets = strain[on] - stress[on] / E_MPa
    placed = _top_plastic_part(strain, stress, window_MPa, E_MPa) if on.size >= 3 else None
    if placed is not None:
        offsets = placed[1].copy()
        offsets[-1] -= placed[2]
    return offsets


def known_slope_spread_u(strain, stress_MPa, window_MPa, E_MPa: float) -> float:
    """The strain zero's spread on a line of known slope E: half the spread of :func:`known_slope_offsets`
    (0 under 2 samples). Equation: u = (max − min)/2."""
    offsets = known_slope_offsets(strain, stress_MPa, window_MPa, E_MPa)
    return float(np.ptp(offsets) / 2.0) if offsets.size >= 2 else 0.0


def top_spacing_u(strain, stress_MPa, window_MPa, *, E_MPa: float | None = None) -> float:
    """The strain zero's uncertainty from the sample spacing where the line ends.

    The line's last sample may already hold plastic strain, up to one step (the yield anywhere
    within that step, rectangular). A line of known slope E (``E_MPa``: compression's toe, the
    median of the offsets ε − σ/E) shows that plastic part in the last sample's offset, and the
    median takes in what it does: u = |ε0(ε_top − p) − ε0(ε_top)|/√3, p the last offset above the
    others' median (at most the step Δε), ε0 the median. Otherwise (a regressed line, a single
    sample, or samples up to the median that lie off one line of slope E by more than it spans:
    the zero not resolved) u = Δε/√3 (:func:`top_step_u`), Δε the strain between the last sample
    in the window and the next one: on the virtual rig's regressed lines the step holds what their
    few top samples carry beyond the model (taken through the regression instead, its A, B, n
    coverage fell 97/94/92 → 92/92/86 %)."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    whole = top_step_u(strain, stress, window_MPa)
    placed = None if whole == 0.0 or E_MPa is None else _top_plastic_part(strain, stress, window_MPa, E_MPa)
    if placed is None:  # a regressed line, or samples off one line of slope E (compression's toe_spread_warning): the step as it is
        return whole
    on, _, plastic = placed
    moved = strain.copy()
    moved[on[-1]] -= plastic  # its plastic part taken out
    return float(abs(_zero_of_known_slope(moved[on], stress[on], E_MPa) - _zero_of_known_slope(strain[on], stress[on], E_MPa)) / math.sqrt(3.0))


def handbook_line_u(E_MPa: float, top_MPa: float, E_rel_u: float = HANDBOOK_E_REL_U) -> float:
    """The strain zero's uncertainty when a given or handbook E, not a regressed line, places it.

    Equation: the elastic strain at the line's top is uncertain by its relative share,
    u = σ_top/E·u_E,rel (σ_top the highest stress the zero was read from)."""
    if not (np.isfinite(E_MPa) and E_MPa > 0 and np.isfinite(top_MPa)):
        return 0.0
    return float(abs(top_MPa) / E_MPa * E_rel_u)


def strain_zero_uncertainty(*, line: float = 0.0, curvature: float = 0.0, toe: float = 0.0, spacing: float = 0.0,
                            handbook: float = 0.0) -> dict:
    """δε0 of a true curve from what places its strain zero, each a standard uncertainty (strain).

    line: the elastic line's fit (:func:`line_zero_u`); curvature: its lack of straightness
    (:func:`line_curvature_u`); toe: the toe compensation's spread; spacing: the sample spacing at
    the line's top (:func:`top_spacing_u`); handbook: a given/handbook E placing the zero
    (:func:`handbook_line_u`). Equation: root sum of squares. Returns {"delta_eps0", "components"}."""
    parts = {"line_fit": line, "line_curvature": curvature, "toe": toe, "sample_spacing": spacing, "handbook_E": handbook}
    parts = {k: float(abs(v)) for k, v in parts.items() if np.isfinite(v)}
    return {"delta_eps0": float(math.sqrt(sum(v**2 for v in parts.values()))), "components": parts}


def stress_u_from_zero(slope_MPa, delta_eps0: float):
    """σ's standard uncertainty from the strain zero: u_σ = |dσ/dεp|·δε0 (MPa)."""
    return np.abs(np.asarray(slope_MPa, dtype=float)) * float(delta_eps0)


def curve_slope(law_fit, eps_p) -> np.ndarray:
    """dσ/dεp of a fitted law (callable σ(εp)) by a central difference (MPa per unit strain)."""
    eps = np.asarray(eps_p, dtype=float)
    h = np.maximum(1e-6, 1e-3 * eps)
    lo = np.maximum(eps - h, 0.0)
    return (law_fit(eps + h) - law_fit(lo)) / (eps + h - lo)


def start_uncertainty(law_fit, eps_range, delta_eps0: float, *, limit: float = START_LIMIT) -> dict:
    """The curve's start as far as it rests on the strain zero.

    law_fit: the fitted law σ(εp); eps_range: the fit's (start, end) in εp; delta_eps0: δε0.
    Returns u_σ/σ at the start (``stress_rel_u_at_start``), u_σ there in MPa and the εp from
    which u_σ/σ = |dσ/dεp|·δε0/σ stays below ``limit`` (``below_limit_from_eps_p``; the start
    when it is below there already, None when it never is within the range)."""
    lo, hi = float(eps_range[0]), float(eps_range[1])
    grid = np.linspace(lo, hi, 400)
    rel = stress_u_from_zero(curve_slope(law_fit, grid), delta_eps0) / np.abs(law_fit(grid))
    above = np.flatnonzero(rel >= limit)
    if above.size == 0:
        from_eps = lo
    elif above[-1] + 1 < grid.size:
        from_eps = float(grid[above[-1] + 1])
    else:
        from_eps = None
    u0 = float(stress_u_from_zero(curve_slope(law_fit, np.array([lo])), delta_eps0)[0])
    return {"delta_eps0": float(delta_eps0), "eps_p_start": lo, "stress_u_at_start_MPa": u0,
            "stress_rel_u_at_start": float(rel[0]), "limit_rel": limit, "below_limit_from_eps_p": from_eps}


def start_warning(start: dict, *, limit: float = WARN_LIMIT) -> str | None:
    """The warning when σ at the reported range's start is uncertain by more than ``limit`` from the strain zero alone."""
    if not start["stress_rel_u_at_start"] > limit:
        return None
    upto = start["below_limit_from_eps_p"]
    where = f"εp < {upto:.3g}" if upto is not None else f"εp {start['eps_p_start']:.3g} on"
    return (f"the curve's start ({where}) rests on the strain zero ± {start['delta_eps0']:.2g}: σ there ± "
            f"{100 * start['stress_rel_u_at_start']:.1f} % (u_σ = |dσ/dεp|·δε0 at εp {start['eps_p_start']:.3g}); "
            f"a hardening constant read from it (A, σ0) carries that")


def constants_shift(refit, base, eps_p, stress_MPa, delta_eps0: float) -> dict[str, float]:
    """The hardening constants' change when the curve is moved by the strain zero's uncertainty.

    refit: eps, σ → HardeningFit; base: the fit of the curve as measured; the curve refitted with εp + δε0 (the lmfit way: a systematic
    input's effect on each constant, added in quadrature to its standard error). Returns
    {name: |Δ|} per constant, {} when the refit fails."""
    from flowcurve.errors import IdentificationError

    eps = np.asarray(eps_p, dtype=float)
    try:
        moved = refit(eps + float(delta_eps0), stress_MPa)
    except IdentificationError:
        return {}
    return {k: float(abs(moved.params[k] - base.params[k])) for k in base.params}


def tension_or_compression_zero(strain, stress_MPa, *, window_MPa, E_line_MPa: float, E_line_stderr_MPa: float,
                                E_used_MPa: float, line_resolved: bool, zero_E_MPa: float | None = None) -> dict:
    """δε0 of a first loading (:func:`strain_zero_uncertainty`) from its arrays and its elastic line.

    strain, stress_MPa: the toe-compensated first loading; window_MPa: the line's window ((0, top)
    when no line was found); E_line_MPa, E_line_stderr_MPa: the regressed line (nan: none);
    E_used_MPa: the E that strips the elastic strain; line_resolved: False when a given/handbook E
    took the line's place; zero_E_MPa: the slope of a line of known slope whose offsets' median places
    the zero (None: the regressed line's intercept). The zero's parts are those of the estimator that
    places it: the regressed line's fit and curvature (:func:`line_zero_u`, :func:`line_curvature_u`), or
    the known slope's offsets' spread (:func:`known_slope_spread_u`); the spacing at the top through it.
    Also ``plastic_start_step`` (:func:`top_step_u`): where the plastic part starts, for an offset read between samples,
    and, where a known slope places the zero, ``regressed_line``: whether a line with a standard error (3 samples or more)
    was regressed on the window (elsewhere its ``line_fit`` part says so)."""
    has_line = np.isfinite(E_line_MPa) and np.isfinite(E_line_stderr_MPa) and window_MPa[1] > window_MPa[0]
    known = zero_E_MPa is not None and np.isfinite(zero_E_MPa) and zero_E_MPa > 0
    regressed = has_line and not known
    line_u = line_zero_u(E_line_MPa, E_line_stderr_MPa, window_MPa) if has_line else 0.0
    zero = strain_zero_uncertainty(
        line=line_u if regressed else 0.0,
        curvature=line_curvature_u(strain, stress_MPa, window_MPa) if regressed else 0.0,
        toe=known_slope_spread_u(strain, stress_MPa, window_MPa, zero_E_MPa) if known else 0.0,
        spacing=top_spacing_u(strain, stress_MPa, window_MPa, E_MPa=zero_E_MPa),
        handbook=0.0 if line_resolved else handbook_line_u(E_used_MPa, window_MPa[1]))
    out = {**zero, "plastic_start_step": top_step_u(strain, stress_MPa, window_MPa)}
    if known:  # its line_fit part no longer says whether a line was regressed on the window
        out["regressed_line"] = line_u > 0.0
    return out


def apply_to_fit(fit, eps_p, stress_MPa, zero: dict, refit) -> tuple[object, dict, list[str]]:
    """The strain zero's effect on a hardening fit: its constants' standard errors widened by
    their shift under εp + δε0 (in quadrature), the curve's start (:func:`start_uncertainty`) and
    its warning; the constants over the fit range (``constants_lack_of_fit``,
    :func:`.uncertainty.correlated_fit_u`: residuals correlated along the range, a constant on its bound). fit: HardeningFit; eps_p, stress_MPa: the points it was fitted to; zero: from
    :func:`strain_zero_uncertainty`; refit: eps, σ → HardeningFit. Returns (fit, block, warnings)."""
    from dataclasses import replace

    from flowcurve.identification.laws.hardening import static_form
    from flowcurve.identification.laws.bounds import constant_scales, constants_on_bound, sides
    from flowcurve.identification.quality.uncertainty import correlated_fit_u

    delta = zero["delta_eps0"]
    start = {**start_uncertainty(fit, fit.strain_range, delta), "components": zero["components"]}
    for key in ("plastic_start_step", "regressed_line"):
        if key in zero:
            start[key] = zero[key]
    shift = constants_shift(refit, refit(np.asarray(eps_p, dtype=float), stress_MPa), eps_p, stress_MPa, delta) if delta > 0 else {}
    start["constants_shift"] = shift
    law = static_form(fit.law)
    on_bound = constants_on_bound(law.func, fit.params, law.bounds, eps_p) if law else {}
    if on_bound:  # named only where there is one (result.json of every other fit as before), with each one's own scale
        start["constants_on_bound"] = sides(on_bound)
        scales = constant_scales(law.func, fit.params, eps_p)
        start["constants_on_bound_scale"] = {k: scales.get(k, 0.0) for k in on_bound}
    start["constants_lack_of_fit"] = correlated_fit_u(law.func, fit.params, eps_p, stress_MPa, on_bound) if law else {}
    # with a constant on its bound the fit's own covariance is not the bounded fit's (lmfit's at a bound, or none):
    # the free constants' statistics are constants_lack_of_fit's, the bound one fixed
    own = {k: None for k in fit.stderr} if on_bound else fit.stderr
    stderr = {k: (math.hypot(se, shift[k]) if se is not None and np.isfinite(se) else shift[k]) if k in shift else se
              for k, se in own.items()}
    warning = start_warning(start)
    return replace(fit, stderr=stderr), start, [warning] if warning else []

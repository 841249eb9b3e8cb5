"""Compression (upsetting) identification with barrelling friction — seed 004, section 3.1.3.

From a compression record (force, crosshead travel) and the post-test measurements (final
height hk, bulge diameter dmax or largest cross-section smax):

1. the indicator diagram: frame compliance removed (§2.1) and the shortening scaled to the
   measured height change, K_l = (h0 − hk)/max Δl ((3.1), worked example 0.96);
2. current height h = h0 − Δl, strain ε = −ln(h/h0) (3.31), volume-constant diameter
   d_n = d0·√(h0/h) (3.28), mean pressure σ_n = P/S, S = π·d_n²/4 ((3.30)/(3.32));
3. the friction coefficient by every method of :mod:`identification.friction` (default: the
   CalculiX table ``fe_table``; the seed's bulge regression (3.19) and Ebrahimi–Najafizadeh
   side by side);
4. the flow curve corrected by every correction (the CalculiX force factor ``fe_table``
   (default), K_σ/K_ε, Siebel, exact slab), each
   kept as the curve ``true_<method>``;
5. the hardening law fitted (:func:`identification.hardening.fit_hardening`) to the default
   corrected curve.

The elastic modulus used to strip elastic strain is the ``E_MPa`` option (a handbook value)
when given, else the record's ``material.E_MPa`` (entered at the test), otherwise the apparent modulus of the initial linear part (§2.3). When ``E_MPa`` is
given, the measured hk (after unloading) is also corrected for the specimen's elastic
spring-back before the shortening is scaled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, MissingValueError, RecordError
from flowcurve.identification import friction as fr
from flowcurve.identification.fe.model import model_form as mf
from flowcurve.identification.elastic_modulus import METAL_E_RANGE_MPa, ModulusChoice, apparent_modulus_warning, choose_modulus
from flowcurve.identification.hardening import RANGE_SHARE_PART, HardeningFit, fit_hardening, pattern_shift, range_shift
from flowcurve.identification.indicator import (DEFAULT_MODULUS_METHOD, FEW_POINTS_TOP, SDAR_REACH, ModulusFit, auto_modulus, elastic_modulus, fit_modulus, remove_frame_compliance, scale_to_measured,
                                                reread_if_stepped, yield_onset_from_rate)
from flowcurve.identification.outcome import Identification
from flowcurve.identification.results import CompressionHardening, CompressionResult
from flowcurve.identification.strain_zero import apply_to_fit, tension_or_compression_zero
from flowcurve.identification.tension import check_fit_range, true_plastic_strain

UNLOADING_BAND = (0.1, 0.9)  # the part of the unloading (× the largest force) the spring-back is read on
MIN_UNLOADING_SAMPLES = 10
YIELD_OFFSET = 0.002  # 0.2 % offset for the compression yield and the start of the fit
LOADED_FRACTION = 0.05  # samples above this fraction of the peak force belong to the test
MAX_FIT_POINTS = 600  # the hardening fit uses at most this many points, evenly spread in strain
FIT_CURVE_POINTS = 200


def compression_sign(values: np.ndarray) -> float:
    """+1 or −1: the sign that makes the larger excursion of a signal positive."""
    return -1.0 if abs(np.nanmin(values)) > abs(np.nanmax(values)) else 1.0


def loading_branch_end(travel_mm: np.ndarray, force_N: np.ndarray, near: float = 0.005) -> int:
    """Index of the end of loading: the largest force among the samples at the top of travel.

    The crosshead reverses at the end of loading; near the top, encoder steps make the travel
    flat over several samples, and the unloading samples there carry a clearly lower force.
    ``near`` is the part of the largest travel counted as "the top".
    """
    top = np.nanmax(travel_mm)
    candidates = np.nonzero(travel_mm >= top * (1.0 - near))[0]
    return int(candidates[np.nanargmax(force_N[candidates])])


def springback_from_unloading(force_N: np.ndarray, specimen_mm: np.ndarray, end: int, *, band=UNLOADING_BAND) -> tuple[float, int] | None:
    """(spring-back in mm, samples) the unloading branch shows, or None when it has too few samples.

    The specimen's displacement (frame compliance removed) against the force over the first
    unloading from ``band`` × the largest force (the turn and a seat re-opening at low force left
    out): Δl = Δl_k + F·c, so the elastic spring-back from the largest force to none is F_max·c."""
    f, d = np.asarray(force_N[end:], dtype=float), np.asarray(specimen_mm[end:], dtype=float)
    if f.size < 2:
        return None
    f_max = float(force_N[end])
    below = np.flatnonzero(f < band[0] * f_max)  # the first unloading ends where the force first leaves the band
    stop = int(below[0]) if below.size else f.size
    on = np.flatnonzero(f[:stop] <= band[1] * f_max)
    if on.size < MIN_UNLOADING_SAMPLES:
        return None
    slope = float(np.polyfit(f[on], d[on], 1)[0])  # Δl = Δl_k + c·F → c (mm/N)
    return (f_max * slope, int(on.size)) if slope > 0 else None


def offset_yield(eps_p, stress_MPa, offset: float = YIELD_OFFSET) -> float | None:
    """Stress where the plastic strain first reaches ``offset`` (running maximum, interpolated)."""
    eps_run = np.maximum.accumulate(np.asarray(eps_p, dtype=float))
    if eps_run[-1] < offset:
        return None
    i = int(np.argmax(eps_run >= offset))
    if i == 0:
        return float(stress_MPa[0])
    e0, e1 = eps_run[i - 1], eps_run[i]
    w = 0.0 if e1 == e0 else (offset - e0) / (e1 - e0)
    return float(stress_MPa[i - 1] + w * (stress_MPa[i] - stress_MPa[i - 1]))


def plastic_strain(strain, stress_MPa, E_MPa: float | None):
    """Plastic part of a (compressive, positive) true strain; the total strain when E is unknown."""
    if E_MPa is None:
        return np.asarray(strain, dtype=float).copy()
    return true_plastic_strain(strain, stress_MPa, E_MPa)  # (3.7) ε_p = ε − σ/E


def _fit_subset(eps_p: np.ndarray, start: float, first: int = 0) -> np.ndarray:
    """Indices of the plastic range (ε_p ≥ start, after the running maximum passed it, from
    sample ``first`` on — the yield sample, so encoder jitter on the elastic line stays out), thinned."""
    past = np.maximum.accumulate(eps_p) >= start
    past[:first] = False
    idx = np.nonzero(past & (eps_p >= start))[0]
    if idx.size > MAX_FIT_POINTS:
        # evenly in strain, so the long end of the curve does not outweigh the start
        targets = np.linspace(eps_p[idx[0]], eps_p[idx[-1]], MAX_FIT_POINTS)
        order = np.argsort(eps_p[idx], kind="stable")
        pos = np.searchsorted(eps_p[idx][order], targets).clip(0, idx.size - 1)
        idx = np.unique(idx[order][pos])
    return idx


def _fit_points(eps_p: np.ndarray, i_yield: int, fit_range) -> np.ndarray:
    """Indices of the points the hardening fit uses: the plastic range from the yield sample on
    (:func:`_fit_subset`), within ``fit_range`` (LO, HI) when given."""
    idx = _fit_subset(eps_p, YIELD_OFFSET, i_yield)
    checked = check_fit_range(fit_range)
    if checked is not None:
        idx = idx[(eps_p[idx] >= checked[0]) & (eps_p[idx] <= checked[1])]
    return idx


def _meta_geometry(record: Record) -> dict:
    src = record.source
    d0 = record.positive("specimen.d0_mm", required=True)
    h0 = record.positive("specimen.h0_mm", required=True)
    hk = record.positive("post.hk_mm", required=True)
    if hk >= h0:
        raise RecordError(src, f"'post.hk_mm' = {hk:g} mm must be below 'specimen.h0_mm' = {h0:g} mm (the specimen is shorter after compression)")
    dmax = record.positive("post.dmax_mm")
    smax = record.positive("post.smax_mm2")
    if dmax is None and smax is None:
        raise MissingValueError(src, ("post.dmax_mm", "post.smax_mm2"), what="the friction needs the bulge diameter dmax or the largest cross-section smax")
    dtop = record.positive("post.dtop_mm")
    dface = record.positive("post.dface_mm")  # the original end face (fe_table reads μ from it when given)
    nu = record.number("material.nu")
    if nu is not None and not (0.0 <= nu < 0.5):
        raise RecordError(src, f"'material.nu' = {nu:g}: Poisson's ratio must be within [0, 0.5)")
    return {"d0": d0, "h0": h0, "hk": hk, "dmax": dmax, "smax": smax, "dtop": dtop, "dface": dface,
            "nu": fr.DEFAULT_POISSON if nu is None else nu, "nu_source": "assumed (metals)" if nu is None else "record (material.nu)"}


def _check_crosshead_gaps(src: str, force: np.ndarray, cross: np.ndarray) -> None:
    """A crosshead without values while the specimen carries load cannot be scaled to hk: stop."""
    loaded = np.abs(np.nan_to_num(force)) > LOADED_FRACTION * np.nanmax(np.abs(force))
    gaps = np.nonzero(loaded & ~np.isfinite(cross))[0]
    if gaps.size:
        raise RecordError(src, f"the crosshead channel has no value at sample {gaps[0] + 1} (and {gaps.size - 1} more) while the specimen is loaded; the shortening cannot be followed through the gap", column="crosshead_mm")


def _friction_all(geo: dict, chosen: str, warnings: list[str], curve=None) -> tuple[fr.FrictionResult, dict[str, fr.FrictionResult | str]]:
    if chosen not in fr.FRICTION_METHODS:
        raise IdentificationError(f"unknown friction method {chosen!r} (choose from {', '.join(fr.FRICTION_METHODS)})")
    results: dict[str, fr.FrictionResult | str] = {}
    for method in fr.FRICTION_METHODS:
        try:
            results[method] = fr.identify_friction(method, geo["d0"], geo["h0"], geo["hk"], d_max_mm=geo["dmax"], s_max_mm2=geo["smax"], d_top_mm=geo["dtop"], curve=curve,
                                                     d_face_mm=geo.get("dface"))
        except IdentificationError as exc:
            if method == chosen:
                raise
            results[method] = str(exc)
            warnings.append(f"friction method {method} not applicable: {exc}")
    return results[chosen], results


def _offset_onset_MPa(strain0, stress0, line: ModulusFit, offset: float = YIELD_OFFSET) -> float | None:
    """Stress where the strain first exceeds the elastic line by ``offset`` (the line's zero at
    zero stress, i.e. toe-compensated): the yield estimate that sets the next window."""
    beyond = strain0 - (stress0 - line.intercept_MPa) / line.E_MPa
    past = np.nonzero((beyond >= offset) & (stress0 >= line.window_MPa[0]))[0]  # on the line's rise, not in the toe's noise
    return float(stress0[past[0]]) if past.size and stress0[past[0]] > 0 else None


def elastic_line(t, specimen_mm, force_N, *, area0_mm2: float, h0_mm: float, window_MPa=None, window=None,
                 modulus_reference: str = "Rp02", method: str = DEFAULT_MODULUS_METHOD) -> tuple[ModulusFit, float]:
    """The elastic line of the first loading and the toe it reveals (§2.3, ISO 6892-1 toe).

    Strain regressed on stress over the widest linear window (:func:`auto_modulus`, iterated
    on the 0.2 % offset yield from a first estimate off the force rate), or over ``window_MPa``
    (MPa) / ``window`` (fractions of the yield estimate, or of the largest stress with
    ``modulus_reference`` "Rm"). Returns the line in (specimen displacement/h0, P/S0) and the
    toe offset (mm): where the line meets zero force. ``method`` "sdar": the line SDAR finds
    (ASTM E3076-18) on the loading up to twice the force rate's yield estimate."""
    strain0 = np.asarray(specimen_mm, dtype=float) / h0_mm
    stress0 = np.asarray(force_N, dtype=float) / area0_mm2
    if window_MPa is None and window is None and method == "sdar":
        line = elastic_modulus(method, strain0, stress0, 0.0, upto_MPa=SDAR_REACH * yield_onset_from_rate(t, force_N) / area0_mm2,
                               strain_on_stress=True)
    elif window_MPa is not None:
        line = fit_modulus(strain0, stress0, tuple(window_MPa), strain_on_stress=True)
        line.source = "given window (MPa)"
    else:
        ref = float(np.max(stress0)) if modulus_reference == "Rm" and window is not None else yield_onset_from_rate(t, force_N) / area0_mm2
        for _ in range(4):
            if window is not None:
                line = fit_modulus(strain0, stress0, (window[0] * ref, window[1] * ref), strain_on_stress=True)
                line.source = f"given window {window[0]:g}–{window[1]:g} × {'largest stress' if modulus_reference == 'Rm' else 'the yield stress'}"
            else:
                line = auto_modulus(strain0, stress0, ref, strain_on_stress=True)
            if modulus_reference == "Rm" and window is not None:
                break
            new_ref = _offset_onset_MPa(strain0, stress0, line)
            if new_ref is None or abs(new_ref - ref) <= 1e-3 * ref:
                break
            ref = new_ref
    if not line.E_MPa > 0:
        raise IdentificationError("the elastic line does not rise: no modulus")
    toe_mm = -line.intercept_MPa / line.E_MPa * h0_mm  # ε = c0 + σ/E → Δl0 = c0·h0
    return line, float(toe_mm)


def toe_offsets(specimen_mm, force_N, window_MPa, *, E_MPa: float, area0_mm2: float, h0_mm: float) -> np.ndarray:
    """The offsets Δl − h0·σ/E (mm) of the first loading's samples in the window: one value, the
    toe, for samples on an elastic line of slope E."""
    stress = np.asarray(force_N, dtype=float) / area0_mm2
    disp = np.asarray(specimen_mm, dtype=float)
    top = int(np.argmax(stress >= window_MPa[1])) if np.any(stress >= window_MPa[1]) else stress.size
    on = np.flatnonzero(stress[:top] >= window_MPa[0])
    if on.size == 0:
        raise IdentificationError("no sample of the first loading in the elastic window")
    return disp[on] - h0_mm * stress[on] / E_MPa  # Δl = Δl0 + h0·σ/E


def toe_spread_warning(offsets_mm: np.ndarray, window_MPa, *, E_MPa: float, h0_mm: float) -> str | None:
    """A warning when the window's samples are not on one line of slope E: their offsets spread
    wider than the line's own length h0·Δσ/E (a sparse record whose first loaded samples are
    already plastic, a force lagging the travel). The strain zero is then uncertain by half the spread."""
    spread = float(np.ptp(offsets_mm)) if offsets_mm.size else 0.0
    span = h0_mm * (window_MPa[1] - window_MPa[0]) / E_MPa
    if not spread > span:
        return None
    return (f"the strain zero is not resolved: the {offsets_mm.size} samples taken for the elastic line lie off one line of "
            f"E = {E_MPa:.4g} MPa by {1000 * spread:.0f} µm (the line itself spans {1000 * span:.0f} µm), so the start of the "
            f"flow curve is uncertain by ±{spread / 2 / h0_mm:.4f} in strain (sample faster near the yield)")


def compensate_toe_line(specimen_mm, force_N, line: ModulusFit, toe_mm: float, *, area0_mm2: float, h0_mm: float) -> np.ndarray:
    """ISO 6892-1 toe compensation: the displacement shifted so that the elastic line passes
    through zero force, and the samples before the line (the toe) replaced by the line."""
    out = np.asarray(specimen_mm, dtype=float) - toe_mm
    force = np.asarray(force_N, dtype=float)
    on_line = np.nonzero(force / area0_mm2 >= line.window_MPa[0])[0]
    head = np.arange(on_line[0]) if on_line.size else np.arange(0)
    out[head] = np.clip(force[head], 0.0, None) / area0_mm2 / line.E_MPa * h0_mm  # the toe replaced by the line
    return out


@dataclass
class _Diagram:
    """The loading branch of the indicator diagram: time, force and travel made positive, the
    specimen's displacement (frame compliance removed when the stiffness is known)."""

    t: np.ndarray
    force: np.ndarray
    travel: np.ndarray
    specimen: np.ndarray
    stiffness: float | None
    warnings: list[str]
    step_mm: float | None = None  # the crosshead's reading step, when it was interpolated between steps
    springback: tuple[float, int] | None = None  # (mm, samples) the unloading branch shows


@dataclass
class _Line:
    """The elastic line (None when there is none), its toe, and the toe-compensated displacement."""

    line: ModulusFit | None
    toe_mm: float
    specimen: np.ndarray
    warnings: list[str]
    apparent_MPa: float | None = None  # the slope regressed on the first loading (frame removed), when there is one


@dataclass
class _Nominal:
    """The shortening scaled to the measured height change, and the nominal curve it gives."""

    springback: float
    springback_source: str | None
    measured: float  # the shortening the scaling aims at, mm
    shortening: np.ndarray
    K_l: float
    h: np.ndarray
    strain: np.ndarray
    d_n: np.ndarray
    pressure: np.ndarray
    warnings: list[str]


@dataclass
class _Yield:
    """The modulus that strips elastic strain, where it came from, and the compression yield."""

    E_used: float | None
    E_fit: ModulusFit | None  # the elastic line when E is its apparent modulus
    E_source: str
    rp02: float | None
    i_yield: int  # the first sample at Rp0.2 (0 without one)


@dataclass
class _Friction:
    """μ by every method, the chosen one, and the curve by every friction correction."""

    chosen: fr.FrictionResult
    frictions: dict
    corrected: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]  # method → (εp, σ, ε)
    warnings: list[str]


def _check_options(friction_correction: str, E_MPa: float | None) -> None:
    """The friction correction and the handbook modulus, checked."""
    if friction_correction not in fr.CORRECTIONS:
        raise IdentificationError(f"unknown friction correction {friction_correction!r} (choose from {', '.join(fr.CORRECTIONS)})")
    if E_MPa is not None and not (math.isfinite(E_MPa) and E_MPa > 0):
        raise IdentificationError(f"E_MPa must be > 0, got {E_MPa!r}")


def _handbook_modulus(record: Record, E_MPa: float | None) -> tuple[float | None, str, ModulusChoice]:
    """The modulus that strips elastic strain by the one rule (:func:`.elastic_modulus.choose_modulus`:
    the option, else the record's material.E_MPa, else the handbook E of the class its material
    names; a compression record has no extensometer) and its source; (None, "apparent") without one."""
    choice = choose_modulus(given=E_MPa, handbook=record.positive("material.E_MPa"), material=record.meta.get("material"))
    # a short stiff specimen's elastic line is about one encoder count: a handbook modulus strips elastic
    # strain better than a regression on it (and a crosshead's slope carries the frame and the toe)
    source = {"given": "option", "handbook": "record (material.E_MPa)", "class": f"class ({choice.basis})"}.get(choice.source, "apparent")
    return choice.E_MPa, source, choice


def _inputs(record: Record, frame_stiffness_N_per_um: float | None) -> _Diagram:
    """The indicator diagram's loading branch, the frame compliance removed (§2.1)."""
    src = record.source
    warnings: list[str] = []
    t = record.column("time_s")
    force_raw = record.column("force_N")
    cross_raw = record.column("crosshead_mm")
    _check_crosshead_gaps(src, force_raw, cross_raw)
    ok = np.isfinite(t) & np.isfinite(force_raw) & np.isfinite(cross_raw)
    t, force_raw, cross_raw = t[ok], force_raw[ok], cross_raw[ok]
    if t.size < 10:
        raise RecordError(src, f"only {t.size} complete samples (time, force, crosshead); a compression identification needs more")
    force = force_raw * compression_sign(force_raw)
    # an encoder count spanning several samples (10 µm is 0.15 % of a 7 mm specimen): its sawtooth
    # against the rising force would run the plastic strain backwards within each count
    cross_raw, step = reread_if_stepped(t, cross_raw)
    travel = cross_raw - cross_raw[0]
    travel = travel * compression_sign(travel)

    stiffness = frame_stiffness_N_per_um if frame_stiffness_N_per_um is not None else record.positive("rig.frame_stiffness_N_per_um")
    if stiffness is not None:
        specimen = remove_frame_compliance(travel, force, stiffness)
    else:
        specimen = travel.copy()
        warnings.append("no frame stiffness ('rig.frame_stiffness_N_per_um'): the frame compliance is left to the scaling K_l")
    end = loading_branch_end(travel, force)
    springback = springback_from_unloading(force, specimen, end)
    t, force, travel, specimen = t[: end + 1], force[: end + 1], travel[: end + 1], specimen[: end + 1]
    if end < 10:
        raise IdentificationError(f"{src}: the loading branch has only {end + 1} samples")
    return _Diagram(t=t, force=force, travel=travel, specimen=specimen, stiffness=stiffness, warnings=warnings, step_mm=step, springback=springback)


MIN_LINE_SLOPE_FRACTION = 0.2  # a regressed line flatter than this part of the handbook E reaches past yield


def _yield_estimate_MPa(diagram: _Diagram, area0_mm2: float) -> float | None:
    """The force rate's estimate of the yield stress (:func:`yield_onset_from_rate`), None without one."""
    try:
        return yield_onset_from_rate(diagram.t, diagram.force) / area0_mm2
    except IdentificationError:
        return None


def toe_on_flattest_offsets(specimen_mm, force_N, *, E_MPa: float, area0_mm2: float, h0_mm: float, upto_MPa: float,
                            run: int = 3) -> tuple[float, tuple[float, float]]:
    """The toe (mm) of an elastic line of known slope E from a few coarse samples: the offset
    Δl − h0·σ/E grows while the toe closes, stays put on the elastic line and grows again past
    yield, so the line is the run of ``run`` consecutive samples of the first loading (up to
    ``upto_MPa``) whose offsets spread least; returns their median offset and their stress range."""
    stress = np.asarray(force_N, dtype=float) / area0_mm2
    disp = np.asarray(specimen_mm, dtype=float)
    top = int(np.argmax(stress >= upto_MPa)) if np.any(stress >= upto_MPa) else stress.size
    on = np.flatnonzero(stress[:top] > 0.02 * upto_MPa)
    if on.size < run:
        raise IdentificationError(f"only {on.size} samples of the first loading below {upto_MPa:.4g} MPa: no elastic line to place")
    offset = disp[on] - h0_mm * stress[on] / E_MPa  # Δl = Δl0 + h0·σ/E on the line
    runs = np.lib.stride_tricks.sliding_window_view(offset, run)
    k = int(np.argmin(np.ptp(runs, axis=1)))
    return float(np.median(runs[k])), (float(stress[on[k]]), float(stress[on[k + run - 1]]))


def _line_of_known_slope(diagram: _Diagram, area0_mm2: float, h0_mm: float, E_MPa: float) -> tuple[ModulusFit, float] | None:
    """(line, toe mm) when the line's own slope cannot be regressed (a few samples, an encoder count
    longer than the line, a toe that lasts into it) but E is known: slope E placed on the flattest
    offsets of the first loading up to 0.9 × the force rate's yield estimate
    (:func:`toe_on_flattest_offsets`; less than one count of a stepped crosshead is no toe); None
    without such samples."""
    ref = _yield_estimate_MPa(diagram, area0_mm2)
    if ref is None:
        return None
    try:
        toe_mm, window = toe_on_flattest_offsets(diagram.specimen, diagram.force, E_MPa=E_MPa, area0_mm2=area0_mm2, h0_mm=h0_mm,
                                                 upto_MPa=FEW_POINTS_TOP * ref)
    except IdentificationError:
        return None
    if diagram.step_mm is not None and abs(toe_mm) < diagram.step_mm:
        toe_mm = 0.0  # less than one count of a stepped crosshead: not told from the count's rounding
    line = ModulusFit(E_MPa, float("nan"), -E_MPa * toe_mm / h0_mm, float("nan"), 3, window,
                      source=f"handbook E = {E_MPa:g} MPa placed on the flattest offsets of the first loading ({window[0]:.4g}–{window[1]:.4g} MPa; "
                             "too few or too coarse samples for a slope of their own)")
    return line, toe_mm


def _elastic_line(diagram: _Diagram, geo: dict, *, E_MPa: float | None, modulus_window_MPa, modulus_window,
                  modulus_reference: str, toe: bool, modulus_method: str = DEFAULT_MODULUS_METHOD) -> _Line:
    """The elastic line and the toe: the linear part extended to zero force (ISO 6892-1)."""
    warnings: list[str] = []
    apparent = None
    area0 = math.pi * geo["d0"] ** 2 / 4.0
    specimen = diagram.specimen
    try:
        line, toe_mm = elastic_line(diagram.t, specimen, diagram.force, area0_mm2=area0, h0_mm=geo["h0"], window_MPa=modulus_window_MPa,
                                    window=modulus_window, modulus_reference=modulus_reference, method=modulus_method)
    except IdentificationError as exc:
        known = None if E_MPa is None else _line_of_known_slope(diagram, area0, geo["h0"], E_MPa)
        line, toe_mm = known if known is not None else (None, 0.0)
        if line is None:
            warnings.append(f"no elastic line ({exc}): the toe is not compensated; "
                            + (f"the handbook E = {E_MPa:g} MPa strips the elastic strain; Rp0.2 is not reported (no strain zero "
                               "to read its offset from: sample faster)" if E_MPa is not None
                               else "no modulus, so the elastic strain is not removed and there is no Rp0.2 — give E_MPa"))
    else:
        apparent = line.E_MPa
        onset = _yield_estimate_MPa(diagram, area0)
        if E_MPa is not None and onset is not None and (line.window_MPa[0] > onset or line.E_MPa < MIN_LINE_SLOPE_FRACTION * E_MPa):
            known = _line_of_known_slope(diagram, area0, geo["h0"], E_MPa)
            warnings.append(f"the line regressed on the first loading ({line.E_MPa:.4g} MPa over {line.window_MPa[0]:.4g}–{line.window_MPa[1]:.4g} MPa) "
                            f"starts above the force rate's yield estimate {onset:.4g} MPa or is flatter than {MIN_LINE_SLOPE_FRACTION:g} × E: not the elastic line; "
                            + (f"the handbook E = {E_MPa:g} MPa is placed on the first loading instead" if known is not None else "the toe is not compensated"))
            line, toe_mm = known if known is not None else (None, 0.0)
        elif E_MPa is not None:
            offsets = toe_offsets(specimen, diagram.force, line.window_MPa, E_MPa=E_MPa, area0_mm2=area0, h0_mm=geo["h0"])
            toe_mm = float(np.median(offsets))  # the toe of a line of known slope E; its offsets' spread judged
            warnings += [w for w in [toe_spread_warning(offsets, line.window_MPa, E_MPa=E_MPa, h0_mm=geo["h0"])] if w]
        elif line.E_MPa < METAL_E_RANGE_MPa[0]:
            warnings.append(f"apparent modulus {line.E_MPa:.4g} MPa over {line.window_MPa[0]:.4g}–{line.window_MPa[1]:.4g} MPa is far below any metal's: "
                            "the line found may be a toe or a stretch past yield, and Rp0.2 with it — give the handbook E (--E or material.E_MPa) "
                            "or name the material's grade")
    if line is not None and toe:
        on_line = line if E_MPa is None else replace(line, E_MPa=E_MPa)  # the toe replaced by the line the offset was read on
        specimen = compensate_toe_line(specimen, diagram.force, on_line, toe_mm, area0_mm2=area0, h0_mm=geo["h0"])
    return _Line(line=line, toe_mm=toe_mm, specimen=specimen, warnings=warnings, apparent_MPa=apparent)


def _nominal_curve(diagram: _Diagram, geo: dict, specimen: np.ndarray, E_MPa: float | None) -> _Nominal:
    """The shortening scaled to the measured one (3.1) and the nominal curve: strain (3.31), mean pressure (3.28)–(3.32)."""
    warnings: list[str] = []
    d0, h0, hk, force = geo["d0"], geo["h0"], geo["hk"], diagram.force
    # measured shortening at the largest load: h0 − hk plus the elastic spring-back — from the handbook E,
    # else as the unloading branch shows it (the frame compliance removed), else none (K_l then scales
    # the loaded shortening to the unloaded one: 0.5 % short for a 9 mm specimen at 1000 MPa)
    d_k = float(fr.nominal_diameter(d0, h0, hk))
    springback, source = 0.0, None
    if E_MPa is not None:
        springback, source = hk * (force[-1] / (math.pi * d_k**2 / 4.0)) / E_MPa, "handbook E"  # elastic strain σ/E over hk
    elif diagram.springback is not None and diagram.stiffness is not None:
        springback, source = diagram.springback[0], f"unloading branch ({diagram.springback[1]} samples)"
    measured = h0 - hk + springback
    shortening, K_l = scale_to_measured(np.clip(specimen, 0.0, None), measured)  # (3.1) K_l = (h0 − hk)/max Δl
    if abs(K_l - 1.0) > 0.1:
        warnings.append(f"scaling factor K_l = {K_l:.3f} differs from 1 by more than 10 %: check the frame stiffness, hk and the crosshead channel")
    h = h0 - shortening
    strain = fr.height_strain(h, h0)  # (3.31)
    d_n = fr.nominal_diameter(d0, h0, h)  # (3.28)
    area = math.pi * d_n**2 / 4.0  # (3.30)
    pressure = force / area  # (3.32) σ_n = P/S_i
    return _Nominal(springback=springback, springback_source=source, measured=measured, shortening=shortening, K_l=K_l, h=h, strain=strain, d_n=d_n,
                    pressure=pressure, warnings=warnings)


def _modulus_and_yield(nominal: _Nominal, line: ModulusFit | None, E_MPa: float | None, E_source: str) -> _Yield:
    """E (handbook, else the elastic line's slope on the scaled strain) and Rp0.2 on the nominal curve."""
    E_used, E_fit = E_MPa, None
    if E_MPa is None and line is not None:
        E_fit = line
        E_used, E_source = line.E_MPa / nominal.K_l, "apparent"  # the line's slope on the scaled strain
    elif E_MPa is None:
        E_source = "none"
    pressure = nominal.pressure
    rp02 = offset_yield(plastic_strain(nominal.strain, pressure, E_used), pressure) if E_used is not None else None
    i_yield = int(np.argmax(pressure >= rp02)) if rp02 is not None else 0
    if line is None:  # no line to place the strain zero on: the offset would be read on an uncompensated toe
        rp02 = None
    return _Yield(E_used=E_used, E_fit=E_fit, E_source=E_source, rp02=rp02, i_yield=i_yield)


MU_RESOLUTION_WARN = 0.02  # μ moved by more than this by one dmax resolution step: say so
MEASURE_THE_FACE = ", or measure the original end face's diameter (post.dface_mm), which still shrinks with μ there"


def _fe_table_warnings(chosen: fr.FrictionResult) -> list[str]:
    """What the FE table's μ cannot promise: a hardening beyond its axes, a barrel that no
    longer grows with μ (near sticking: μ is then a lower bound; the force factor is as flat)."""
    if chosen.method != "fe_table":
        return []
    out = [f"FE table: {w}; read at the table's edge (--method inverse-fe runs the record's own law)" for w in chosen.extra.get("outside_table", [])]
    continued = chosen.extra.get("continued_runs_from_strain")
    if continued is not None:
        out.append(f"FE table: μ and the correction beyond ε {continued:.2f} rest on runs that stopped there (the side folding onto the "
                   "platen) and were continued along the next lower μ: an estimate (--method inverse-fe runs the record itself)")
    sensitivity = chosen.extra.get("sensitivity", {})
    by_face = "mu_per_dface_resolution" in sensitivity
    dmu = sensitivity.get("mu_per_dface_resolution" if by_face else "mu_per_dmax_resolution")
    told_by = "the end face (a dface" if by_face else "the bulge (a dmax"
    if sensitivity and dmu is None:
        out.append(f"FE table: the bulge does not grow with μ near {chosen.mu:.3f} (the faces stick): take μ as a lower bound{MEASURE_THE_FACE}")
    elif dmu is not None and dmu > MU_RESOLUTION_WARN:
        out.append(f"FE table: μ {chosen.mu:.3f} is poorly told by {told_by} reading off by {fr.DIAMETER_RESOLUTION_MM} mm moves it by "
                   f"{dmu:.2g}; the faces nearly stick): take μ as a lower bound"
                   + ("" if by_face else MEASURE_THE_FACE))
    return out


def _friction_disagreement(chosen: fr.FrictionResult) -> str | None:
    """A warning when the end face's μ and the bulge's differ beyond their combined standard
    errors (:data:`.fe.model_form.DISAGREE_SIGMAS`), else None: the shape pulls μ two ways."""
    z = chosen.extra.get("face_bulge_disagreement_sigmas")
    if z is None or not z > mf.DISAGREE_SIGMAS:
        return None
    return (f"friction: μ from the end face {chosen.mu:.3f} ± {chosen.extra['mu_stderr']:.3f} and from the bulge "
            f"{chosen.extra['mu_from_bulge']:.3f} ± {chosen.extra['mu_from_bulge_stderr']:.3f} disagree ({z:.1f} combined standard "
            "errors): the upsetting model does not describe this specimen's shape; the hardening is poor")


def _mu_share(src: str, geo: dict, nominal: _Nominal, friction: _Friction, i_yield: int, fit_range, law: str,
              friction_correction: str, E_used: float | None) -> dict[str, float]:
    """μ's share of the constants' standard errors: the curve corrected and fitted again at μ ∓ its
    standard error ({} when μ has none or a refit fails)."""
    se_mu = friction.chosen.extra.get("mu_stderr")
    if not (se_mu and math.isfinite(se_mu) and friction_correction in fr.CORRECTIONS):
        return {}
    eps_p = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    elastic = None if E_used is None else (E_used, geo["nu"])
    params = []
    for mu in (max(friction.chosen.mu - se_mu, 0.0), friction.chosen.mu + se_mu):
        eps_t, sig_t = fr.correct(friction_correction, nominal.strain, nominal.pressure, mu, nominal.d_n / 2.0, nominal.h, eps_p=eps_p, elastic=elastic)
        try:
            fits, _ = _hardening_fits(src, {friction_correction: (plastic_strain(eps_t, sig_t, E_used), sig_t, eps_t)}, i_yield, fit_range, law,
                                      friction_correction)
        except IdentificationError:
            return {}
        params.append(fits[friction_correction].params)
    return mf.through_mu(*params)


def _constants_stderr(src: str, geo: dict, nominal: _Nominal, friction: _Friction, fit: HardeningFit, i_yield: int, fit_range, law: str,
                      friction_correction: str, E_used: float | None) -> dict[str, dict[str, float]]:
    """The shares of the hardening constants' standard errors beyond the fit's: μ's (:func:`_mu_share`);
    on the FE table's correction, the model form's force error (:func:`.fe.model_form.force_model_form`)
    as a uniform offset and as one growing with strain, each refitted; and the fit range's (the
    constants fitted again over the first half of the range, :func:`.hardening.range_shift`): a
    curve whose shape departs from the law moves correlated constants (A and n) far more than the
    curve itself moves."""
    shares: dict[str, dict[str, float]] = {}
    by_mu = _mu_share(src, geo, nominal, friction, i_yield, fit_range, law, friction_correction, E_used)
    if by_mu:
        shares["friction μ (fits at μ ∓ its standard error)"] = by_mu
    eps_tp, sig_t, _ = friction.corrected[friction_correction]
    idx = _fit_points(eps_tp, i_yield, fit_range)
    eps_fit, sig_fit = eps_tp[idx], sig_t[idx]
    if friction_correction == "fe_table":
        u_force = mf.force_model_form(friction.chosen.mu)
        by_pattern = [pattern_shift(eps_fit, sig_fit, u_force, g, law) for g in mf.force_patterns(eps_fit)]
        shares[f"FE model form ({u_force:.1%} of the force at μ {friction.chosen.mu:.3f}, uniform and growing with strain)"] = {
            k: mf.quadrature(*(b.get(k, 0.0) for b in by_pattern)) for k in fit.params}
    by_range = range_shift(eps_fit, sig_fit, law)
    if by_range:
        shares[f"the fit range (fitted again over its first {RANGE_SHARE_PART:.0%})"] = by_range
    return shares


def trade_off_note(fit: HardeningFit, limit: float = 0.9) -> str | None:
    """A note when two constants' correlation exceeds ``limit``: the curve is known better than either."""
    pairs = [(abs(r), a, b, r) for a, row in fit.correlations.items() for b, r in row.items() if a < b and abs(r) > limit]
    if not pairs:
        return None
    _, a, b, r = max(pairs)
    return (f"{a} and {b} trade off (correlation {r:+.2f}): the curve is known better than either constant; "
            "compare fits through the curve, not constant by constant")


def _model_form_shares(src: str, geo: dict, nominal: _Nominal, yld: _Yield, friction: _Friction, fit: HardeningFit, result: CompressionResult,
                       fit_range, law: str, friction_correction: str) -> None:
    """The main fit's standard errors with μ's and the model form's shares (:func:`_constants_stderr`),
    said in ``methods.hardening_stderr``; a face and bulge that disagree make it poor, with a warning."""
    shares = _constants_stderr(src, geo, nominal, friction, fit, yld.i_yield, fit_range, law, friction_correction, yld.E_used)
    fit.stderr = mf.combined_stderr(fit.stderr, *shares.values())
    note = trade_off_note(fit)
    result.methods["hardening_stderr"] = "; ".join(["the fit's standard errors", *shares]) + " (in quadrature)" + (f". {note}" if note else "")
    disagreement = _friction_disagreement(friction.chosen)
    if disagreement:
        fit.doubt = disagreement
        result.warnings.append(disagreement)


def _dface_advice(chosen: fr.FrictionResult) -> str | None:
    """The advice to measure dface when the FE table's μ rests on a bulge that hardly tells it, else None."""
    sensitivity = chosen.extra.get("sensitivity", {})
    if chosen.method != "fe_table" or "mu_per_dface_resolution" in sensitivity or not sensitivity:
        return None
    dmu = sensitivity.get("mu_per_dmax_resolution")
    return fr.DFACE_ADVICE if dmu is None or dmu > MU_RESOLUTION_WARN else None


def _friction_correction(geo: dict, nominal: _Nominal, friction_method: str, E_used: float | None) -> _Friction:
    """μ (again, now with the curve: the FE table's μ depends on the hardening) and the curve by every correction."""
    warnings: list[str] = []
    eps_p = plastic_strain(nominal.strain, nominal.pressure, E_used) if E_used is not None else None
    curve = (nominal.strain, nominal.pressure) if eps_p is None else (nominal.strain, nominal.pressure, eps_p)
    chosen, frictions = _friction_all(geo, friction_method, warnings, curve=curve)
    warnings += _fe_table_warnings(chosen)
    corrected = {}
    elastic = None if E_used is None else (E_used, geo["nu"])  # fe_table: the pressure on the loaded area
    for method in fr.CORRECTIONS:
        eps_t, sig_t = fr.correct(method, nominal.strain, nominal.pressure, chosen.mu, nominal.d_n / 2.0, nominal.h, eps_p=eps_p, elastic=elastic)
        corrected[method] = (plastic_strain(eps_t, sig_t, E_used), sig_t, eps_t)
    return _Friction(chosen=chosen, frictions=frictions, corrected=corrected, warnings=warnings)


def _hardening_fits(src: str, corrected: dict, i_yield: int, fit_range, law: str, friction_correction: str) -> tuple[dict, list[str]]:
    """The hardening law fitted to every corrected curve from the yield sample on: (fits, warnings)."""
    warnings: list[str] = []
    fits = {}
    for method, (eps_tp, sig_t, _) in corrected.items():
        idx = _fit_points(eps_tp, i_yield, fit_range)
        if idx.size < 4:
            if method == friction_correction:
                raise IdentificationError(f"{src}: the plastic range has only {idx.size} points; nothing to fit (did the specimen yield?)")
            continue
        try:
            fits[method] = fit_hardening(eps_tp[idx], sig_t[idx], law)
        except IdentificationError as exc:
            if method == friction_correction:
                raise
            warnings.append(f"hardening fit on the {method} curve failed: {exc}")
    warnings += [f"hardening: {w}" for w in fits[friction_correction].warnings]
    return fits, warnings


def _strain_zero(diagram: _Diagram, geo: dict, line: _Line, nominal: _Nominal, yld: _Yield, friction: _Friction, fits: dict,
                 fit_range, law: str, friction_correction: str) -> tuple[dict, list[str]]:
    """The strain zero's uncertainty δε0 and its effect on the main fit's start and constants (§2.11);
    the main fit in ``fits`` gets the widened standard errors."""
    stress = diagram.force / (math.pi * geo["d0"] ** 2 / 4.0)
    strain = line.specimen / geo["h0"]
    top = int(np.nanargmax(stress))
    el = line.line
    if el is None:
        window, E_line, E_se = (0.0, float(nominal.pressure[yld.i_yield])), math.nan, math.nan
    else:
        window, E_line, E_se = el.window_MPa, el.E_MPa, el.E_stderr_MPa
    E_used = yld.E_used if yld.E_used is not None else E_line
    toe_spread = 0.0  # a line of known slope E: its samples' offsets Δl − h0·σ/E spread by what is not on the line
    if el is not None and yld.E_source != "apparent" and E_used is not None:
        offsets = toe_offsets(diagram.specimen, diagram.force, window, E_MPa=E_used, area0_mm2=math.pi * geo["d0"] ** 2 / 4.0, h0_mm=geo["h0"])
        toe_spread = float(np.ptp(offsets)) / 2.0 / geo["h0"]  # half the spread, as toe_spread_warning states it
    zero = tension_or_compression_zero(strain[: top + 1], stress[: top + 1], window_MPa=window, E_line_MPa=E_line, E_line_stderr_MPa=E_se,
                                       E_used_MPa=E_used, line_resolved=yld.E_source == "apparent" and np.isfinite(E_se), toe_spread=toe_spread)
    eps_tp, sig_t, _ = friction.corrected[friction_correction]
    idx = _fit_points(eps_tp, yld.i_yield, fit_range)
    fits[friction_correction], start, warnings = apply_to_fit(fits[friction_correction], eps_tp[idx], sig_t[idx], zero,
                                                              lambda e, s: fit_hardening(e, s, law))
    return start, warnings


def _flow_curve(eps_p: np.ndarray, stress_MPa: np.ndarray, i_yield: int, uncertainty_pct: np.ndarray | None = None) -> pd.DataFrame:
    """The curve a card starts from: where the plastic strain has passed the 0.2 % offset (with the
    correction's per-point uncertainty, %, where it has one)."""
    plastic = np.nonzero((np.maximum.accumulate(eps_p) >= YIELD_OFFSET) & (eps_p >= 0) & (np.arange(eps_p.size) >= i_yield))[0]
    curve = {"true_plastic_strain": eps_p[plastic], "true_stress_MPa": stress_MPa[plastic]}
    if uncertainty_pct is not None:
        curve["correction_uncertainty_pct"] = uncertainty_pct[plastic]
    return pd.DataFrame(curve)


def _fe_correction_uncertainty(geo: dict, friction: _Friction, E_used: float | None) -> tuple[np.ndarray, str, list[str]]:
    """Per point of the fe_table-corrected curve: its stress's σ, % (:func:`.fe.model_form.corrected_stress_uncertainty_pct`:
    the model form's force share at μ, growing to the inverse's 3 % over the band before the table's
    fold-over onset, :func:`.friction.fe_fold_over_onset`), what it holds, and a warning when the
    curve reaches that band."""
    eps_tp, sig_t, eps_t = friction.corrected["fe_table"]
    mu, h0_d0 = friction.chosen.mu, geo["h0"] / geo["d0"]
    ok = np.isfinite(sig_t) & (eps_t > 0)
    onset = fr.fe_fold_over_onset(mu, h0_d0, eps_t[ok], sig_t[ok], eps_tp[ok] if E_used is not None else None)
    u = mf.corrected_stress_uncertainty_pct(eps_t, mu, onset)
    u_mf = 100.0 * mf.force_model_form(mu)
    basis = (f"fe_table: per point (true_curve.csv correction_uncertainty_pct) the model form's {u_mf:.1f} % of the force at μ {mu:.3f}"
             + (f", growing to {float(u.max()):.1f} % over ε {onset - mf.FOLD_OVER_BAND:.2f}–{onset:.2f} before the table's fold-over onset"
                if onset is not None else "; no fold-over in the table's runs at this μ, h0/d0 and hardening"))
    warnings = []
    band = None if onset is None else onset - mf.FOLD_OVER_BAND
    if band is not None and np.nanmax(eps_t) > band and float(u.max()) > u_mf + 0.05:
        order = np.argsort(eps_t[ok])
        eps_p_band = float(np.interp(band, eps_t[ok][order], eps_tp[ok][order]))
        warnings.append(f"fe_table correction: the points from ε {band:.2f} (ε_p {eps_p_band:.2f}) on carry the side folding onto the platen "
                        f"(the table's runs fold over from ε {onset:.2f} at μ {mu:.3f}, h0/d0 {h0_d0:.2g}; a finer model folds over earlier "
                        f"and differs by up to 2 % in force there): their uncertainty grows from {u_mf:.1f} % to {float(u.max()):.1f} % "
                        "(true_curve.csv correction_uncertainty_pct)")
    return u, basis, warnings


def _curves(diagram: _Diagram, nominal: _Nominal, friction: _Friction, fit: HardeningFit) -> dict[str, pd.DataFrame]:
    """The intermediate curves for plots: raw and corrected diagram, nominal, one per correction, the fit."""
    curves: dict[str, pd.DataFrame] = {
        "raw_diagram": pd.DataFrame({"crosshead_displacement_mm": diagram.travel, "force_N": diagram.force}),
        "corrected_diagram": pd.DataFrame({"specimen_displacement_mm": nominal.shortening, "force_N": diagram.force}),
        "nominal": pd.DataFrame({"true_strain": nominal.strain, "mean_pressure_MPa": nominal.pressure, "height_mm": nominal.h}),
    }
    for method, (eps_tp, sig_t, eps_t) in friction.corrected.items():
        curves[f"true_{method}"] = pd.DataFrame({"true_plastic_strain": eps_tp, "true_stress_MPa": sig_t, "true_strain": eps_t})
    grid = np.linspace(fit.strain_range[0], fit.strain_range[1], FIT_CURVE_POINTS)
    curves["fit"] = pd.DataFrame({"true_plastic_strain": grid, "true_stress_MPa": fit(grid)})
    return curves


def _result(record: Record, geo: dict, diagram: _Diagram, line: _Line, nominal: _Nominal, yld: _Yield, friction: _Friction,
            fits: dict, warnings: list[str], *, start: dict | None = None, E_MPa: float | None, law: str, friction_correction: str, toe: bool) -> CompressionResult:
    """The typed result (result.json) of a compression identification."""
    t, strain, chosen, frictions, fit = diagram.t, nominal.strain, friction.chosen, friction.frictions, fits[friction_correction]
    duration = float(t[-1] - t[0])
    strain_rate = float(strain[-1] / duration) if duration > 0 else None
    K_l, el = nominal.K_l, line.line
    return CompressionResult(
        E_MPa=yld.E_used,
        E_source=yld.E_source,  # option (handbook) / apparent (initial slope, §2.3) / none
        Rp02_MPa=yld.rp02,  # compression yield: mean pressure at 0.2 % plastic strain
        max_force_N=float(np.max(diagram.force)),
        final_true_strain=float(strain[-1]),
        friction_mu=chosen.mu,
        friction_mu_range=chosen.extra.get("mu_range"),
        friction_method=chosen.method,
        friction={m: (r.mu if isinstance(r, fr.FrictionResult) else None) for m, r in frictions.items()},
        friction_details={m: (r.as_dict() if isinstance(r, fr.FrictionResult) else {"method": m, "error": r}) for m, r in frictions.items()},
        friction_correction=friction_correction,
        hardening=CompressionHardening(fit=fit, correction=friction_correction, start_uncertainty=start),
        hardening_by_correction={m: f.as_dict() for m, f in fits.items()},
        indicator={
            "frame_stiffness_N_per_um": diagram.stiffness,
            "K_l": K_l,
            "measured_shortening_mm": nominal.measured,
            "springback_mm": nominal.springback,
            "springback_source": nominal.springback_source,  # handbook E / unloading branch / None (not added)
            "max_specimen_displacement_mm": float(np.max(line.specimen)),
            "crosshead_step_interpolated_mm": diagram.step_mm,  # a stepped reading re-read between its steps (None: as read)
            **({"toe_compensation_mm": line.toe_mm if toe else None} if el is not None else {}),
        },
        methods={
            "friction": f"{chosen.method} (all: {', '.join(fr.FRICTION_METHODS)})",
            "friction_mu_stderr": _mu_stderr_basis(chosen),
            "correction": f"{friction_correction} (all: {', '.join(fr.CORRECTIONS)})",
            "stress": "mean pressure P/S, S = pi*d_n^2/4, d_n = d0*sqrt(h0/h) (3.28)-(3.32)",
            "scaling": "K_l = (h0 - hk [+ spring-back]) / max(specimen displacement) (3.1)",
            "elastic_volume": (f"fe_table: sigma_f = p / (factor * J), J = exp(-(1 - 2 nu) sigma_f / E), nu {geo['nu']:g} ({geo['nu_source']})"
                               if yld.E_used is not None else "fe_table: volume-constant area (no modulus)"),
            "hardening": f"{law} least squares on the {friction_correction} curve, eps_p >= {YIELD_OFFSET}",
        },
        warnings=warnings,
        dface_advice=_dface_advice(chosen),
        record={
            "path": record.source,
            "material": record.meta.get("material"),
            "nominal_temperature_C": record.number("nominal_temperature_C"),
            "crosshead_speed_mm_per_s": record.number("crosshead_speed_mm_per_s"),
            "strain_rate_per_s": strain_rate,  # mean true strain rate of the loading branch
            "specimen": {"d0_mm": geo["d0"], "h0_mm": geo["h0"]},
            "post": {"hk_mm": geo["hk"], "dmax_mm": geo["dmax"], "smax_mm2": geo["smax"]},
        },
        E_apparent_stderr_MPa=yld.E_fit.E_stderr_MPa / K_l if yld.E_fit is not None else None,
        modulus=None if el is None else {**el.as_dict(), "E_MPa": yld.E_used, "E_line_MPa": el.E_MPa / K_l,
                                         "E_stderr_MPa": el.E_stderr_MPa / K_l, "source": yld.E_source if E_MPa is not None else el.source},
    )


def _modulus_method(choice: ModulusChoice, yld: _Yield, line: _Line) -> dict:
    """result.json's methods.elastic_modulus: the E that stripped the elastic strain, its standard
    uncertainty and where it came from (the rule's class), and the first loading's apparent slope."""
    if yld.E_source == "apparent" and yld.E_used is not None:
        scale = yld.E_used / yld.E_fit.E_MPa if yld.E_fit is not None else math.nan  # 1/K_l: the slope on the scaled strain
        u = yld.E_fit.E_stderr_MPa * scale if yld.E_fit is not None else math.nan
        out = {"E_MPa": yld.E_used, "u_MPa": u if math.isfinite(u) else None, "source": "apparent",
               "basis": "the first loading's slope (frame removed, toe and grips in it): no defensible E (no --E, material.E_MPa or class)"}
    else:
        out = {"E_MPa": choice.E_MPa, "u_MPa": choice.u_MPa if choice.E_MPa is not None else None, "source": choice.source, "basis": choice.basis}
    out["apparent_MPa"] = line.apparent_MPa
    return out


def _mu_stderr_basis(chosen: fr.FrictionResult) -> str:
    """What μ's standard error (``friction_details[method].mu_stderr``) holds, for result.json's methods."""
    if chosen.extra.get("mu_stderr") is None:
        return "none: mu has no standard error"
    basis = chosen.extra.get("mu_stderr_basis")
    return basis if basis else f"half mu_range ({chosen.extra.get('mu_range_basis')})"


def identify_compression(
    record: Record,
    *,
    friction_method: str = fr.DEFAULT_FRICTION_METHOD,
    friction_correction: str = fr.DEFAULT_CORRECTION,
    law: str = "johnson_cook",
    E_MPa: float | None = None,
    frame_stiffness_N_per_um: float | None = None,
    modulus_window_MPa: tuple[float, float] | None = None,
    modulus_window: tuple[float, float] | None = None,
    modulus_reference: str = "Rp02",
    toe: bool = True,
    fit_range: tuple[float, float] | None = None,
    modulus_method: str = DEFAULT_MODULUS_METHOD,
) -> Identification:
    """Identify a compression record: friction, friction-corrected true curves and hardening.

    Options: ``friction_method`` (one of ``fe_table`` (default), ``bulge_regression``,
    ``ebrahimi_najafizadeh``), ``friction_correction`` (``fe_table`` (default), ``k_sigma``,
    ``siebel``, ``slab``), ``law`` of the hardening fit, ``E_MPa`` (handbook modulus for elastic strain and
    spring-back; otherwise the apparent modulus), ``frame_stiffness_N_per_um`` (otherwise the
    record's ``rig.frame_stiffness_N_per_um``), ``modulus_window_MPa`` / ``modulus_window``
    (fractions of the yield stress, or of the largest stress with ``modulus_reference`` "Rm";
    default: the widest linear stretch, :func:`elastic_line`), ``toe`` (compensate a soft
    start, default on), ``fit_range`` (LO, HI true plastic strain of the hardening fit),
    ``modulus_method`` ("window", "sdar", or "auto": the window, see :func:`elastic_line`).
    """
    _check_options(friction_correction, E_MPa)
    E_MPa, E_source, E_choice = _handbook_modulus(record, E_MPa)
    geo = _meta_geometry(record)
    _friction_all(geo, friction_method, [])  # friction first: it needs only the post-test measurements, and bad ones should stop early
    diagram = _inputs(record, frame_stiffness_N_per_um)
    line = _elastic_line(diagram, geo, E_MPa=E_MPa, modulus_window_MPa=modulus_window_MPa, modulus_window=modulus_window,
                         modulus_reference=modulus_reference, toe=toe, modulus_method=modulus_method)
    if E_choice.source == "class":
        line.warnings += [w for w in [apparent_modulus_warning(line.apparent_MPa, record.meta.get("material"))] if w]
    nominal = _nominal_curve(diagram, geo, line.specimen, E_MPa)
    yld = _modulus_and_yield(nominal, line.line, E_MPa, E_source)
    friction = _friction_correction(geo, nominal, friction_method, yld.E_used)
    fits, fit_warnings = _hardening_fits(record.source, friction.corrected, yld.i_yield, fit_range, law, friction_correction)
    start, start_warnings = _strain_zero(diagram, geo, line, nominal, yld, friction, fits, fit_range, law, friction_correction)
    warnings = diagram.warnings + line.warnings + nominal.warnings + friction.warnings + fit_warnings + start_warnings
    result = _result(record, geo, diagram, line, nominal, yld, friction, fits, warnings, start=start, E_MPa=E_MPa, law=law,
                     friction_correction=friction_correction, toe=toe)
    result.methods["elastic_modulus"] = _modulus_method(E_choice, yld, line)
    eps_def, sig_def, _ = friction.corrected[friction_correction]
    _model_form_shares(record.source, geo, nominal, yld, friction, fits[friction_correction], result, fit_range, law, friction_correction)
    uncertainty = None
    if friction_correction == "fe_table":
        uncertainty, result.methods["correction_uncertainty"], fold_warnings = _fe_correction_uncertainty(geo, friction, yld.E_used)
        result.warnings.extend(fold_warnings)
    return Identification(result=result, true_curve=_flow_curve(eps_def, sig_def, yld.i_yield, uncertainty),
                          curves=_curves(diagram, nominal, friction, fits[friction_correction]))

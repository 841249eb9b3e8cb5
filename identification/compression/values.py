"""Compression's record and stages (docs/methods.md §2, seed 3.1.3): the options, the geometry and
the indicator diagram's loading branch (frame compliance removed, spring-back read on the unloading),
the compression yield and plastic strain, the hardening fits' points and fits, and the values each
stage hands on."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, MissingValueError, RecordError
from flowcurve.identification.compression import friction as fr
from flowcurve.identification.elastic_modulus import ModulusChoice, choose_modulus
from flowcurve.identification.laws.hardening import fit_hardening
from flowcurve.identification.indicator import ModulusFit, remove_frame_compliance, reread_if_stepped
from flowcurve.identification.tension.values import check_fit_range, true_plastic_strain


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
    src, spec = record.source, record.specimen
    d0, h0, hk = spec.d0_mm, spec.h0_mm, spec.required("hk_mm")
    if hk >= h0:
        raise RecordError(src, f"'post.hk_mm' = {hk:g} mm must be below 'specimen.h0_mm' = {h0:g} mm (the specimen is shorter after compression)")
    dmax, smax = spec.dmax_mm, spec.smax_mm2
    if dmax is None and smax is None:
        raise MissingValueError(src, ("post.dmax_mm", "post.smax_mm2"), what="the friction needs the bulge diameter dmax or the largest cross-section smax")
    dtop, dface = spec.dtop_mm, spec.dface_mm  # dface: the original end face (fe_table reads μ from it when given)
    nu = record.number("material.nu")
    if nu is not None and not (0.0 <= nu < 0.5):
        raise RecordError(src, f"'material.nu' = {nu:g}: Poisson's ratio must be within [0, 0.5)")
    return {"d0": d0, "h0": h0, "area0": spec.area0_mm2, "hk": hk, "dmax": dmax, "smax": smax, "dtop": dtop, "dface": dface,
            "nu": fr.DEFAULT_POISSON if nu is None else nu, "nu_source": "assumed (metals)" if nu is None else "record (material.nu)"}


def _check_crosshead_gaps(src: str, force: np.ndarray, cross: np.ndarray) -> None:
    """A crosshead without values while the specimen carries load cannot be scaled to hk: stop."""
    loaded = np.abs(np.nan_to_num(force)) > LOADED_FRACTION * np.nanmax(np.abs(force))
    gaps = np.nonzero(loaded & ~np.isfinite(cross))[0]
    if gaps.size:
        raise RecordError(src, f"the crosshead channel has no value at sample {gaps[0] + 1} (and {gaps.size - 1} more) while the specimen is loaded; the shortening cannot be followed through the gap", column="crosshead_mm")


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

"""The elastic line of a tension record (docs/methods.md §2.2): E, the toe and Rp0.2, iterated to a
fixed point over the modulus window; the handbook E where the line is not resolved."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification import iso6892
from flowcurve.identification.laws.hardening import MAX_STRAIN
from flowcurve.identification.elastic_modulus import choose_modulus
from flowcurve.identification.indicator import DEFAULT_MODULUS_METHOD, FEW_SAMPLES, GIVEN_WINDOW_POINTS, ModulusFit, broken_specimen_recovery_mm, elastic_modulus, strain_quantum_noise, yield_onset_from_rate, compensate_toe, fit_modulus, scale_to_measured
from flowcurve.identification.tension.values import MAX_E_UNCERTAINTY, MIN_YIELD_OFFSET
from flowcurve.identification.tension.inputs import _Inputs, _stress_noise_MPa

logger = logging.getLogger(__name__)


@dataclass
class _ElasticLine:
    """E, Rp0.2 and the strain they define (toe-compensated, scaled)."""

    E: float
    mod: ModulusFit
    Rp02: float
    window_MPa: tuple[float, float]
    disp: np.ndarray  # corrected elongation, mm
    strain: np.ndarray  # engineering strain
    toe_mm: float
    scale_factor: float | None
    noise_MPa: float
    warnings: list[str]
    scale: dict | None = None  # :func:`_fracture_scale`'s terms (result.json methods.scale_Kl)


def _fracture_scale(inp: _Inputs, disp, line_E_MPa: float | None, E_option_MPa: float | None) -> tuple[float, float, dict]:
    """(measured, reference, terms) of (3.1) on a broken tension specimen, like with like: the
    crosshead's plastic elongation at the fracture — the displacement at the last sample before it
    (``inp.i_k``: later samples hold the travel after the break) less the elastic extension the
    pieces gave back, the specimen's F_f·L(1 + e_u)²/(E·S0) with the one rule's E (the diagram's
    slope where there is none) and a frame's F_f·(c_line − L/(E·S0)) where its compliance is still in
    ``disp`` — against Lu − L0 plus the uniform plastic elongation of the length the crosshead sees
    beyond L0, (L − L0)·a_u. ``line_E_MPa``: the line's slope on disp/L (unscaled), or None."""
    src, length, s0, i_k, force = inp.src, inp.length, inp.s0, inp.i_k, inp.force
    choice = choose_modulus(given=E_option_MPa, handbook=inp.record.positive("material.E_MPa"), material=inp.record.meta.get("material"))
    frame_in = src["source"] == "crosshead" and src["stiffness"] is None
    E_line = line_E_MPa if line_E_MPa is not None and np.isfinite(line_E_MPa) and line_E_MPa > 0 else None
    c_line = length / (E_line * s0) if E_line is not None else None  # mm/N: the diagram's elastic compliance
    if choice.E_MPa is not None:
        E_s, u_E, E_from = choice.E_MPa, choice.u_MPa, choice.source
    elif E_line is not None and not frame_in:
        E_s, u_E, E_from = E_line, E_line * 0.05, "the diagram's slope (frame removed; ±5 %)"
    else:
        E_s, u_E, E_from = None, 0.0, "none"

    def elastic_mm(F: float, a: float) -> tuple[float, float]:
        """(specimen, frame) elastic extension in ``disp`` at force F and uniform plastic elongation a."""
        if E_s is None:  # no E to split the diagram's slope: specimen and frame together, small strain
            return (F * c_line if c_line is not None else 0.0), 0.0
        frame_mm = F * max(c_line - length / (E_s * s0), 0.0) if frame_in and c_line is not None else 0.0
        return broken_specimen_recovery_mm(F, length, s0, E_s, a), frame_mm

    a_u = inp.record.specimen.uniform_plastic_elongation  # constant volume: (d0/du)² − 1 (du ≤ d0: checked with the inputs)
    if a_u is not None:
        a_u_from = "post.du_mm"
    else:  # the flat maximum's mid-point (ISO 6892-1 §13, as Ag) less the elastic extension there (the same as at the break)
        d_m = float(np.mean(iso6892.max_force_band(disp, inp.eng_stress)))
        a_u = max(d_m - sum(elastic_mm(inp.Fm, 0.0)), 0.0) / length
        a_u, a_u_from = max(d_m - sum(elastic_mm(inp.Fm, a_u)), 0.0) / length, "the diagram at Fm"  # one step: (1 + a)² moves a by < 1e-4
    F_f = max(float(force[i_k]), 0.0)
    specimen, frame = elastic_mm(F_f, a_u)
    step = float(disp[i_k] - disp[i_k - 1]) if i_k > 0 else 0.0  # the break lies within a sample's travel after i_k
    reference = float(disp[i_k]) - specimen - frame
    measured = (inp.lu - inp.l0) + (length - inp.l0) * a_u
    terms = {"measured_mm": measured, "lu_minus_l0_mm": inp.lu - inp.l0, "uniform_plastic_elongation": a_u, "uniform_from": a_u_from,
             "length_mm": length, "fracture_index": int(i_k), "fracture_force_N": F_f, "fracture_displacement_mm": float(disp[i_k]),
             "specimen_recovery_mm": specimen, "frame_recovery_mm": frame, "recovery_E_MPa": E_s, "recovery_E_u_MPa": u_E,
             "recovery_E_source": E_from, "sample_step_mm": max(step, 0.0), "reference_mm": reference,
             "seed_max_displacement_mm": float(np.nanmax(np.abs(disp)))}
    return measured, reference, terms


def _first_guesses(inp: _Inputs, automatic: bool) -> list[float]:
    """Yield stresses to start the automatic window from: the force rate's onset (if any), then Rm."""
    first_guesses = [inp.Rm]  # when the first guess leaves too few samples on the elastic line
    if automatic and inp.record.has("time_s"):
        try:  # a yield guess from the force rate (constant speed): a sparse elastic line needs a good one
            onset = yield_onset_from_rate(inp.data["time_s"].to_numpy(float)[: inp.i_m + 1], inp.force[: inp.i_m + 1]) / inp.s0
            if 0 < onset <= inp.Rm:
                first_guesses.insert(0, onset)
        except IdentificationError as exc:
            logger.debug("no yield estimate from the force rate: %s", exc)
    return first_guesses


def _modulus_window(step: int, ref: float, first_guesses: list[float], strain0, eng_stress, *, fractions, window_fixed_MPa,
                    modulus_reference: str, noise_MPa: float, strain_noise: float, method: str = DEFAULT_MODULUS_METHOD,
                    crosshead: bool = False, sdar_memo: dict | None = None):
    """The stress window of the elastic line at one step: given (MPa, or × the reference stress) or
    the most linear stretch; returns (window_MPa, line_points, how, auto fit or None, reference).
    ``sdar_memo``: kept across the steps (SDAR's line does not depend on the reference)."""
    if window_fixed_MPa is not None:
        return window_fixed_MPa, GIVEN_WINDOW_POINTS, "given window (MPa)", None, ref
    if fractions is not None:
        return (fractions[0] * ref, fractions[1] * ref), 5, f"given window {fractions[0]:g}–{fractions[1]:g} × {modulus_reference}", None, ref
    try:
        auto = elastic_modulus(method, strain0, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise, crosshead=crosshead,
                              sdar_memo=sdar_memo)  # the window is the same before toe and scaling
    except IdentificationError:
        if step > 0 or not first_guesses:
            raise
        while True:  # a sparse elastic line may hold too few samples below the first guess
            ref = first_guesses.pop(0)
            try:
                auto = elastic_modulus(method, strain0, eng_stress, ref, noise_MPa=noise_MPa, strain_noise=strain_noise, crosshead=crosshead,
                              sdar_memo=sdar_memo)
                break
            except IdentificationError:
                if not first_guesses:
                    raise
    return auto.window_MPa, min(auto.n_points, 5), auto.source, auto, ref


def _resolved(mod: ModulusFit) -> bool:
    """A regressed E known to within :data:`MAX_E_UNCERTAINTY` (relative standard error)."""
    return bool(mod.E_stderr_MPa <= MAX_E_UNCERTAINTY * mod.E_MPa)


def _chosen_modulus(mod: ModulusFit, E_MPa: float | None, handbook_E: float | None, given_window: bool) -> float:
    """The E used: the option, else the handbook's when the line has few samples, else the regressed
    one; ``mod.source`` says which."""
    if E_MPa is not None:
        E, mod.source = float(E_MPa), "option E_MPa"
    elif handbook_E is not None and not given_window and mod.n_points < FEW_SAMPLES:
        E, mod.source = handbook_E, f"handbook material.E_MPa (only {mod.n_points} samples on the elastic line)"
    else:
        E = mod.E_MPa
    return E


def _line_without_samples(inp: _Inputs, E: float, why: str, *, scale: bool, noise_MPa: float) -> _ElasticLine:
    """No elastic line in the record (too few samples before the yield): the given or handbook E
    strips the elastic strain, the toe is not compensated (there is no line to find it on)."""
    disp, scale_factor, terms = inp.src["disp"], None, None
    if inp.src["scalable"] and scale and inp.lu is not None:
        measured, reference, terms = _fracture_scale(inp, disp, E if inp.src["stiffness"] is not None or inp.src["source"] != "crosshead" else None, E)
        disp, scale_factor = scale_to_measured(disp, measured, reference)  # (3.1) K_l = Δl_p / Δl_p at the fracture
    strain = disp / inp.length
    if np.nanmax(np.abs(strain)) > MAX_STRAIN:
        raise IdentificationError(f"{inp.record.source}: engineering strain up to {np.nanmax(strain):.4g} is implausible - check units of the displacement (mm) and l0 (mm)")
    mod = ModulusFit(math.nan, math.nan, math.nan, math.nan, 0, (0.0, 0.0), source=f"given or handbook E (no elastic line: {why})")
    Rp02, _ = iso6892.offset_yield_strength(strain, inp.eng_stress, E, MIN_YIELD_OFFSET)
    warnings = [f"no elastic line ({why}): the toe is not compensated and Rp0.2 and the start of the flow curve rest on "
                f"the given E = {E:.4g} MPa alone"]
    return _ElasticLine(E=E, mod=mod, Rp02=Rp02, window_MPa=(0.0, 0.0), disp=disp, strain=strain, toe_mm=0.0,
                        scale_factor=scale_factor, noise_MPa=noise_MPa, warnings=warnings, scale=terms)


def _line_in_window(strain, eng_stress, window_MPa, line_points: int, how: str, auto: ModulusFit | None) -> ModulusFit:
    """The line regressed over a step's window, named by how the window was found (``how``); an
    automatic fit's quality checks carried over and its relative standard error where larger."""
    mod = fit_modulus(strain, eng_stress, window_MPa, min_points=line_points)
    mod.source = how
    if auto is not None:
        mod.quality = auto.quality
        mod.sdar_failed = auto.sdar_failed
        mod.E_stderr_MPa = max(mod.E_stderr_MPa, auto.E_stderr_MPa * mod.E_MPa / auto.E_MPa) if np.isfinite(mod.E_stderr_MPa) else auto.E_stderr_MPa
    return mod


def _elastic_line(inp: _Inputs, *, fractions, window_fixed_MPa, modulus_reference: str, E_MPa: float | None,
                  toe: bool, scale: bool, modulus_method: str = DEFAULT_MODULUS_METHOD) -> _ElasticLine:
    """E, the toe and Rp0.2, which depend on each other through the window: iterated to a fixed point."""
    record, force, eng_stress, i_m, length, src = inp.record, inp.force, inp.eng_stress, inp.i_m, inp.length, inp.src
    automatic = fractions is None and window_fixed_MPa is None
    ref = 0.5 * inp.Rm if modulus_reference == "Rp02" else inp.Rm
    first_guesses = _first_guesses(inp, automatic)
    noise_MPa = _stress_noise_MPa(eng_stress[: i_m + 1])
    raw_channel = "extensometer_mm" if src["source"] == "extensometer" else "crosshead_mm"
    strain_noise = strain_quantum_noise(inp.sub.column(raw_channel)[: i_m + 1] / length)  # the encoder's quantum, before the compliance
    # the handbook E is the material's; a crosshead diagram without the frame's stiffness has the frame's compliance in its slope
    apparent = src["source"] == "crosshead" and src["stiffness"] is None
    handbook_E = record.positive("material.E_MPa") if E_MPa is None and not apparent else None
    disp0 = src["disp"]
    toe_mm, scale_factor, terms = 0.0, None, None
    unresolved = None  # the line's fit when it was not resolved and the handbook E took its place (kept from then on)
    strain0, sdar_memo, previous = disp0 / length, {}, None
    for step in range(6):
        try:
            window_MPa, line_points, how, auto, ref = _modulus_window(
                step, ref, first_guesses, strain0, eng_stress, fractions=fractions, window_fixed_MPa=window_fixed_MPa,
                modulus_reference=modulus_reference, noise_MPa=noise_MPa, strain_noise=strain_noise, method=modulus_method,
                crosshead=src["source"] != "extensometer", sdar_memo=sdar_memo)
        except IdentificationError as exc:
            if unresolved is None:
                if automatic and (E_MPa is not None or handbook_E is not None):  # no line to be found: the E given
                    return _line_without_samples(inp, E_MPa if E_MPa is not None else handbook_E, str(exc), scale=scale, noise_MPa=noise_MPa)
                raise
            break  # no line below the handbook E's Rp0.2 either: the last step's window and Rp0.2 stand
        if previous == (window_MPa, line_points, how, auto):
            break  # the last step's window, method and automatic fit (SDAR's do not depend on the reference): its toe, line and Rp0.2 again
        previous = (window_MPa, line_points, how, auto)
        disp = disp0
        if toe:
            disp, toe_mm = compensate_toe(disp0, force, window_N=(window_MPa[0] * inp.s0, window_MPa[1] * inp.s0), min_points=line_points)
        if src["scalable"] and scale and inp.lu is not None:
            unscaled = fit_modulus(disp / length, eng_stress, window_MPa, min_points=line_points).E_MPa  # the line on disp/L
            measured, reference, terms = _fracture_scale(inp, disp, unscaled, E_MPa)
            disp, scale_factor = scale_to_measured(disp, measured, reference)  # (3.1) K_l = Δl_p / Δl_p at the fracture
        strain = disp / length
        mod = _line_in_window(strain, eng_stress, window_MPa, line_points, how, auto)
        E = _chosen_modulus(mod, E_MPa, handbook_E, given_window=not automatic)
        if unresolved is None and handbook_E is not None and E == mod.E_MPa and not _resolved(mod):
            unresolved = replace(mod)
        if unresolved is not None:
            E, mod.source = handbook_E, (f"handbook material.E_MPa (the elastic line is not resolved: E = {unresolved.E_MPa:.4g} ± "
                                         f"{unresolved.E_stderr_MPa:.2g} MPa from {unresolved.n_points} samples, {unresolved.source})")
        if E == mod.E_MPa and not _resolved(mod):
            raise IdentificationError(
                f"{record.source}: the elastic line is not resolved: E = {E:.4g} ± {mod.E_stderr_MPa:.2g} MPa from {mod.n_points} samples "
                f"({mod.source}); " + ("give the frame stiffness (rig.frame_stiffness_N_per_um), use an extensometer or sample faster "
                                       "(the handbook E is not this diagram's slope: the frame is in it)" if apparent
                                       else "give the handbook modulus (--E or material.E_MPa) or sample faster"))
        Rp02, _ = iso6892.offset_yield_strength(strain, eng_stress, E, MIN_YIELD_OFFSET, start_MPa=window_MPa[0])
        if window_fixed_MPa is not None or modulus_reference == "Rm" or abs(Rp02 - ref) <= 1e-6 * Rp02:
            break
        ref = Rp02
    warnings = _line_checks(record.source, strain, E, unresolved)
    return _ElasticLine(E=E, mod=mod, Rp02=Rp02, window_MPa=window_MPa, disp=disp, strain=strain, toe_mm=toe_mm,
                        scale_factor=scale_factor, noise_MPa=noise_MPa, warnings=warnings, scale=terms)


def _line_checks(source: str, strain, E: float, unresolved: ModulusFit | None) -> list[str]:
    """The line's strain checked for units (an error past MAX_STRAIN); warnings for an unresolved
    line (the handbook E took its place) and for an E far from any metal's."""
    if max(np.nanmax(strain), -np.nanmin(strain)) > MAX_STRAIN:  # max |e| from the extremes: no |e| array of the record
        raise IdentificationError(f"{source}: engineering strain up to {np.nanmax(strain):.4g} is implausible - check units of the displacement (mm) and l0 (mm)")
    warnings: list[str] = []
    if unresolved is not None:
        warnings.append(f"the elastic line is not resolved (E = {unresolved.E_MPa:.4g} ± {unresolved.E_stderr_MPa:.2g} MPa from "
                        f"{unresolved.n_points} samples): the handbook E = {E:.4g} MPa is used instead (sample faster to measure E)")
    if E > 1e6 or E < 1e3:
        warnings.append(f"apparent modulus {E:.4g} MPa is far from any metal's: check units, the frame stiffness or the window")
    return warnings


def sdar_warnings(mod: ModulusFit) -> list[str]:
    """The checks of ASTM E3076-18 that SDAR's least-residual window failed, as a warning: when
    its line gives E (the failure stands beside it) or when the project's window replaced it."""
    if mod.sdar_failed:
        return [f"SDAR (ASTM E3076-18): the least-residual window failed {', '.join(mod.sdar_failed)}; E is from flowcurve's own "
                "automatic window instead (not an E3076 result)"]
    failed = [k for k, v in (mod.quality or {}).items() if not v.get("passed", True)]
    return [f"SDAR (ASTM E3076-18): the least-residual window failed {', '.join(failed)}; E is reported from it"] if failed else []

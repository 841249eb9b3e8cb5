"""What a tension record gives (docs/methods.md §2.1): geometry, the force (corrupt samples left out),
the engineering stress and the strain source (extensometer, or the crosshead less the frame)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification import iso6892
from flowcurve.identification.laws.hardening import MAX_STRESS_MPa
from flowcurve.identification.indicator import reread_if_stepped, remove_frame_compliance
from flowcurve.identification.tension.values import fracture_index


def _check_post_dimensions(record: Record, d0: float, l0: float, lu: float | None) -> None:
    """Measurements after fracture that no tension test can give: Lu < L0, du or dk > d0."""
    if lu is not None and lu < l0:
        raise RecordError(record.source, f"Lu = {lu:g} mm (post.lu_mm, --lu) is shorter than L0 = {l0:g} mm (specimen.l0_mm, --l0): a specimen does not shorten in tension")
    for name in ("du", "dk"):
        d = getattr(record.specimen, f"{name}_mm")
        if d is not None and d > d0:
            raise RecordError(record.source, f"{name} = {d:g} mm (post.{name}_mm{', --dk' if name == 'dk' else ''}) is larger than d0 = {d0:g} mm (specimen.d0_mm, --d0): a specimen does not thicken in tension")


def _strain_source(record: Record, use_extensometer: bool | None, force: np.ndarray, l0: float, options: dict, i_k: int) -> dict:
    """Displacement (mm), the length it refers to (mm) and how it was obtained; ``i_k``: the
    fracture's index (:func:`.values.fracture_index` of ``force``), up to which a channel must have values."""
    has_ext = record.has("extensometer_mm")
    if use_extensometer and not has_ext:
        raise RecordError(record.source, "use_extensometer was requested but the record has no extensometer channel", column="extensometer_mm")
    warnings: list[str] = []
    if has_ext and use_extensometer is not False:
        ext = record.column("extensometer_mm")
        gaps = np.nonzero(~np.isfinite(ext[: i_k + 1]))[0]
        if gaps.size:
            message = f"the extensometer channel has no value from sample {gaps[0] + 1} on (removed before fracture?)"
            if not record.has("crosshead_mm"):
                raise RecordError(record.source, message + "; the record has no crosshead column to identify from instead", column="extensometer_mm")
            if use_extensometer:
                raise RecordError(record.source, message + "; identify from the crosshead instead (use_extensometer=False)", column="extensometer_mm")
            fallback = _strain_source(record, False, force, l0, options, i_k)
            fallback["warnings"].insert(0, message + ": the crosshead is used instead")
            return fallback
        gauge = record.specimen.extensometer_gauge_mm or l0
        if "specimen.extensometer_gauge_mm" not in record.meta:
            warnings.append(f"specimen.extensometer_gauge_mm missing: the extensometer gauge length is taken as l0 = {l0:g} mm")
        return {"disp": ext - ext[0], "length": gauge, "source": "extensometer", "stiffness": None, "scalable": False, "warnings": warnings}
    if not record.has("crosshead_mm"):
        raise RecordError(record.source, "the record has no crosshead column: its strain can only come from the extensometer (leave out --no-extensometer)", column="crosshead_mm")
    cross = record.column("crosshead_mm")
    gaps = np.nonzero(~np.isfinite(cross[: i_k + 1]))[0]
    if gaps.size:
        raise RecordError(record.source, f"the crosshead channel has no value at sample {gaps[0] + 1} (of {gaps.size} before fracture); the strain cannot be followed through the gap", column="crosshead_mm")
    step = None
    if record.has("time_s"):  # a 10 µm count is 3e-4 of a 30 mm length: re-read between counts
        cross, step = reread_if_stepped(record.column("time_s"), cross)
    disp = cross - cross[0]
    stiffness = options.get("frame_stiffness_N_per_um")
    if stiffness is None:
        stiffness = record.positive("rig.frame_stiffness_N_per_um")
    if stiffness is not None:
        disp = remove_frame_compliance(disp, force - force[0], stiffness)
    else:
        warnings.append("no frame stiffness (rig.frame_stiffness_N_per_um): the crosshead displacement still includes the frame; strains and E are not the specimen's")
    stated = options.get("crosshead_length_mm") or record.specimen.parallel_length_mm
    if stated is None:
        warnings.append(f"the parallel length is not stated (specimen.parallel_length_mm, --lc): the crosshead's strain is taken over "
                        f"l0 = {l0:g} mm, but an ISO 6892-1 machined bar's Lc is at least L0 + d0/2 (L0 + 2·d0 in case of dispute), "
                        "over which every strain would read lower: the strain scale's U holds up to L0 + 2·d0")
    return {"disp": disp, "length": float(stated or l0), "source": "crosshead", "stiffness": stiffness, "scalable": True, "warnings": warnings,
            "step_mm": step, "length_stated": stated is not None}


@dataclass
class _Inputs:
    """What the record gives: geometry, the force (finite samples only), stress, strain source."""

    record: Record
    d0: float
    l0: float
    s0: float
    data: pd.DataFrame  # the samples with a force value
    sub: Record  # the record of those samples
    force: np.ndarray
    eng_stress: np.ndarray
    i_m: int  # index of the maximum force
    i_k: int  # index of the last sample before fracture (:func:`.values.fracture_index`)
    Fm: float
    Rm: float
    src: dict  # :func:`_strain_source`: displacement, its length, how it was obtained
    lu: float | None
    length: float  # the length the strain refers to: the crosshead's (parallel length, else l0) or the extensometer's gauge
    warnings: list[str]
    unbroken: bool = False  # the record says the specimen did not break (:func:`.tension_values.unbroken_statement`)


SPIKE_NOISE_FACTOR, SPIKE_FRACTION = 12.0, 0.25  # a lone force sample this far (× noise σ, × peak force) from its agreeing neighbours is corrupt: farther than an upper yield point stands


def _median_of_three_at_extreme(f: np.ndarray) -> float:
    """|median of three| about the sample of largest |F| (inner samples): one of the values whose peak
    :func:`isolated_force_spikes` takes, so a lower bound of that peak, found without a pass over them all."""
    inner = f[1:-1]
    k = int(np.argmax(inner)) if np.max(inner) >= -np.min(inner) else int(np.argmin(inner))
    a, b, c = f[k], f[k + 1], f[k + 2]
    return float(abs(max(min(a, b), min(max(a, b), c))))


def isolated_force_spikes(force_N) -> np.ndarray:
    """Indices of lone corrupt force samples: unlike both neighbours, which agree with each other
    (no specimen's force jumps and comes back within one sample; a fracture does not come back).
    |F_k − (F_k−1 + F_k+1)/2| > max(12 σ, 25 % of the peak of the 3-sample median) and
    |F_k+1 − F_k−1| < a quarter of that; σ from second differences (robust)."""
    f = np.asarray(force_N, dtype=float)
    if f.size < 5:
        return np.zeros(0, dtype=int)
    deviation = np.abs(f[1:-1] - 0.5 * (f[:-2] + f[2:]))
    if not np.any(deviation > SPIKE_FRACTION * _median_of_three_at_extreme(f)):
        return np.zeros(0, dtype=int)  # none beyond a quarter of one median of three (≤ their peak): none beyond the thresholds below
    gap = np.abs(f[2:] - f[:-2])
    a, b, c = f[:-2], f[1:-1], f[2:]
    peak = float(np.max(np.abs(np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c)))))  # median of three, in closed form
    if not np.any((deviation > SPIKE_FRACTION * peak) & (gap < 0.25 * deviation)):
        return np.zeros(0, dtype=int)  # none beyond the peak share: none beyond the larger threshold either (the noise median is not needed)
    threshold = max(SPIKE_NOISE_FACTOR * _stress_noise_MPa(f), SPIKE_FRACTION * peak)
    return np.flatnonzero((deviation > threshold) & (gap < 0.25 * deviation)) + 1


def _inputs(record: Record, *, use_extensometer, frame_stiffness_N_per_um, crosshead_length_mm, scale: bool) -> _Inputs:
    """Geometry, force and engineering stress, and the strain source of a tension record."""
    warnings: list[str] = []
    spec = record.specimen
    d0, l0, s0 = spec.d0_mm, spec.l0_mm, spec.s0_mm2  # F0: the stated S0, else π d0²/4
    force = record.column("force_N")
    ok = np.isfinite(force)
    every = bool(ok.all())  # every force finite: the positions are the samples, no copies (a one-hour record)
    if not every:
        warnings.append(f"{int((~ok).sum())} samples without a force value were left out")
    spikes = isolated_force_spikes(force) if every else np.flatnonzero(ok)[isolated_force_spikes(force[ok])]
    if spikes.size:
        ok[spikes], every = False, False
        warnings.append(f"{spikes.size} force sample(s) unlike both neighbours (a corrupt load-cell frame) left out: "
                        + ", ".join(f"sample {k + 1} ({force[k]:.6g} N)" for k in spikes[:5]) + (" …" if spikes.size > 5 else ""))
    data = (record.data if every else record.data[ok]).reset_index(drop=True)  # all kept: no copy (copy-on-write)
    force = force if every else force[ok]
    sub = Record(meta=record.meta, data=data, source=record.source)
    i_m = iso6892.max_force_index(force)
    Fm = float(force[i_m])
    if Fm <= 0 or i_m == 0 or Fm - force[0] <= 0.05 * abs(Fm):
        raise RecordError(record.source, "the force never rises: no tension test in this record (check the force column and its sign)", column="force_N")
    eng_stress = force / s0
    Rm = Fm / s0
    if Rm > MAX_STRESS_MPa:
        raise IdentificationError(f"{record.source}: Rm = {Rm:.4g} MPa is implausible - check units of force (N) and diameter (mm)")

    i_k = fracture_index(force)
    src = _strain_source(sub, use_extensometer, force, l0, {"frame_stiffness_N_per_um": frame_stiffness_N_per_um, "crosshead_length_mm": crosshead_length_mm}, i_k)
    warnings += src["warnings"]
    lu = spec.lu_mm
    _check_post_dimensions(record, d0, l0, lu)
    length = src["length"]
    if src["scalable"] and scale and lu is not None:
        if lu <= l0:
            raise IdentificationError(f"{record.source}: post.lu_mm = {lu:g} mm is not longer than l0 = {l0:g} mm")
    return _Inputs(record=record, d0=d0, l0=l0, s0=s0, data=data, sub=sub, force=force, eng_stress=eng_stress, i_m=i_m, i_k=i_k,
                   Fm=Fm, Rm=Rm, src=src, lu=lu, length=length, warnings=warnings)


def _stress_noise_MPa(stress_MPa: np.ndarray) -> float:
    """Noise standard deviation of a stress signal from its second differences (robust MAD)."""
    # second differences: a linear trend leaves none, white noise σ leaves σ√6
    return iso6892.mad_sigma_of_differences(stress_MPa, 2) / math.sqrt(6.0) if np.size(stress_MPa) > 2 else 0.0

"""ISO 6892-1 tensile results from an engineering stress–strain curve.

Rp0.2 by the offset method (intersection with the line of slope E through e = 0.2 %),
Rm (maximum force), Ag (plastic extension at maximum force, %), A (after fracture, %),
Z (reduction of area, standard (S0 − Su)/S0, %). Strains are engineering strains (ΔL/L),
stresses in MPa.
"""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError

# a single-step force drop larger than this fraction of Fm is the fracture
FRACTURE_DROP = 0.2


def max_force_index(force_N) -> int:
    """Index of the maximum force Fm (the first one on a flat top)."""
    force = np.asarray(force_N, dtype=float)
    return int(np.nanargmax(force))


def fracture_index(force_N) -> int:
    """Index of the last sample before fracture: the sample before the largest single-step
    force drop after Fm when that drop exceeds 20 % of Fm, else the last sample."""
    force = np.asarray(force_N, dtype=float)
    i_m = max_force_index(force)
    tail = force[i_m:]
    if tail.size < 2:
        return force.size - 1
    drops = tail[:-1] - tail[1:]
    j = int(np.nanargmax(drops))
    if drops[j] > FRACTURE_DROP * force[i_m]:
        return i_m + j
    return force.size - 1


def offset_yield_strength(strain, stress_MPa, E_MPa: float, offset: float = 0.002, *, start_MPa: float = 0.0) -> tuple[float, float]:
    """Proof strength Rp (offset method, ISO 6892-1 §13.1): the first point after ``start_MPa``
    where the curve crosses the line σ = E·(e − offset). Returns (Rp_MPa, fractional index)."""
    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    i_m = int(np.nanargmax(s))
    g = s[: i_m + 1] - E_MPa * (e[: i_m + 1] - offset)  # > 0 left of the offset line
    begin = int(np.argmax(s >= start_MPa)) if start_MPa > 0 else 0
    below = np.nonzero(g[begin:] <= 0)[0]
    if below.size == 0:
        raise IdentificationError(f"the curve never reaches {100 * offset:g} % plastic extension before maximum force: no Rp{100 * offset:g}")
    k = begin + int(below[0])
    if k == 0:
        raise IdentificationError("the curve starts beyond the offset line: check the strain zero (toe)")
    x = g[k - 1] / (g[k - 1] - g[k])  # linear interpolation between k−1 and k
    return float(s[k - 1] + x * (s[k] - s[k - 1])), float(k - 1 + x)


def plastic_extension_pct(strain, stress_MPa, E_MPa: float):
    """Plastic extension in %: 100·(e − σ/E)."""
    return 100.0 * (np.asarray(strain, dtype=float) - np.asarray(stress_MPa, dtype=float) / E_MPa)


def elongation_after_fracture_pct(l0_mm: float, lu_mm: float) -> float:
    """A = (Lu − L0)/L0 · 100 (3.8), from the gauge length measured after fracture."""
    if not lu_mm > 0 or not l0_mm > 0:
        raise IdentificationError(f"gauge lengths must be > 0 mm (L0 {l0_mm!r}, Lu {lu_mm!r})")
    return 100.0 * (lu_mm - l0_mm) / l0_mm


def reduction_of_area_pct(s0_mm2: float, su_mm2: float) -> float:
    """Z = (S0 − Su)/S0 · 100 — the standard form ((3.9) prints /Su, a misprint)."""
    if not 0 < su_mm2 <= s0_mm2:
        raise IdentificationError(f"the area after fracture {su_mm2!r} mm² must be > 0 and not larger than the original {s0_mm2!r} mm²: check post.dk_mm")
    return 100.0 * (s0_mm2 - su_mm2) / s0_mm2

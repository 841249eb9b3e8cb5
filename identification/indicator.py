"""Indicator-diagram (P–Δl) processing: what turns a crosshead reading into specimen elongation.

docs/methods.md §2: frame compliance (§2.1), scaling to the elongation measured on the specimen
((3.1), §2.2), toe/slack compensation, the apparent modulus of the initial linear part (§2.3),
and the frame stiffness identified from a specimen of known modulus (§2.4).

Units: displacements in mm, forces in N, stiffness in N/µm, stresses in MPa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flowcurve.errors import IdentificationError

UM_PER_MM = 1000.0


def remove_frame_compliance(crosshead_mm, force_N, stiffness_N_per_um: float) -> np.ndarray:
    """Specimen elongation from the crosshead travel: Δl = Δl_crosshead − P/C (§2.1), in mm."""
    if not stiffness_N_per_um > 0:
        raise IdentificationError(f"frame stiffness must be > 0 N/µm, got {stiffness_N_per_um!r}")
    # (§2.1) Δl_specimen = Δl_crosshead − P / C_frame   (P/C in µm → mm)
    return np.asarray(crosshead_mm, dtype=float) - np.asarray(force_N, dtype=float) / (stiffness_N_per_um * UM_PER_MM)


def scale_to_measured(displacement_mm, measured_final_mm: float) -> tuple[np.ndarray, float]:
    """Scale a displacement so that its largest value equals the measured one (3.1).

    Returns the scaled array and the factor K_l = Δl_p / max(Δl).
    """
    disp = np.asarray(displacement_mm, dtype=float)
    peak = float(np.nanmax(np.abs(disp))) if disp.size else 0.0
    if peak <= 0:
        raise IdentificationError("cannot scale to the measured elongation: the displacement never leaves zero")
    if not measured_final_mm > 0:
        raise IdentificationError(f"the measured elongation must be > 0 mm, got {measured_final_mm!r}")
    k = measured_final_mm / peak  # (3.1) K_l = Δl_p / max Δl
    return disp * k, k


def first_loading(y, up_to: float, unit: str = "N") -> int:
    """Index of the first sample at or above ``up_to`` (the end of the first loading branch)."""
    y = np.asarray(y, dtype=float)
    above = np.nonzero(y >= up_to)[0]
    if above.size == 0:
        raise IdentificationError(f"the loading curve never reaches {up_to:.4g} {unit}, the top of the fit window")
    return int(above[0])


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


def compensate_toe(displacement_mm, force_N, *, window_N: tuple[float, float]) -> tuple[np.ndarray, float]:
    """Toe (slack) compensation: shift the displacement so that the linear part of the loading
    curve, extrapolated to zero force, passes through zero; the toe itself (before the window)
    is replaced by that line.

    Returns the compensated displacement (mm) and the toe offset removed (mm).
    """
    disp = np.asarray(displacement_mm, dtype=float)
    force = np.asarray(force_N, dtype=float)
    line = fit_line_in_window(disp, force, *window_N)
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


def fit_modulus(strain, stress_MPa, window_MPa: tuple[float, float]) -> ModulusFit:
    """Apparent modulus by linear regression of stress on strain over ``window_MPa`` (§2.3)."""
    line = fit_line_in_window(strain, stress_MPa, *window_MPa, unit="MPa")
    if line.slope <= 0:
        raise IdentificationError(f"the stress does not rise with strain between {window_MPa[0]:.4g} and {window_MPa[1]:.4g} MPa: no modulus")
    return ModulusFit(line.slope, line.slope_stderr, line.intercept, line.r2, line.n_points, line.window)


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

"""PNG plots of an identification, drawn from its named curves (matplotlib, Agg).

:func:`add_plots` fills ``Identification.plots`` with drawing functions; the identification
writes them next to ``result.json``. Curves are DataFrames with unit-named columns
(``displacement_mm``, ``force_kN``, ``strain``, ``stress_MPa``, ``true_plastic_strain``,
``true_stress_MPa``); the first column is the abscissa.

* ``diagram.png`` — the raw and the corrected indicator diagram, force (kN) vs displacement (mm);
* ``stress_strain.png`` — the engineering and true curves with the hardening fit;
* ``corrections.png`` (compression) — the true curve of every friction correction side by side.
"""

from __future__ import annotations

import re
from functools import partial
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from flowcurve.identification.laws.base import display_name_of  # noqa: E402
from flowcurve.identification.outcome import Identification  # noqa: E402

# column-name unit suffix → how the axis label writes it
UNIT_LABELS = {
    "mm": "mm", "kN": "kN", "N": "N", "MPa": "MPa", "GPa": "GPa", "s": "s", "pct": "%",
    "C": "°C", "mm2": "mm²", "per_s": "1/s", "um": "µm",
}
MAX_POINTS = 2000  # points drawn per line; longer curves are thinned evenly


def axis_label(column: str) -> str:
    """``'true_stress_MPa'`` → ``'true stress, MPa'`` (the report's style); dimensionless names bare."""
    for suffix in sorted(UNIT_LABELS, key=len, reverse=True):
        if column.endswith("_" + suffix):
            return f"{column[: -len(suffix) - 1].replace('_', ' ')}, {UNIT_LABELS[suffix]}"
    return column.replace("_", " ")


CORRECTION_NAMES = {"fe_table": "CalculiX force-factor table", "k_sigma": "K_σ/K_ε factors", "siebel": "Siebel",
                    "slab": "slab method"}
NECK_NAMES = {"davidenkov": "Davidenkov", "bridgman": "Bridgman", "mirone": "Mirone"}


def words(name: str) -> str:
    """A curve's code name in words for a legend (``true_fe_table`` → ``CalculiX force-factor table``)."""
    key = name.removeprefix("true_")
    return CORRECTION_NAMES.get(key) or display_name_of(key)


def _thin(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(x) <= MAX_POINTS:
        return x, y
    idx = np.linspace(0, len(x) - 1, MAX_POINTS).astype(int)
    return x[idx], y[idx]


def _column(df: pd.DataFrame, patterns: tuple[str, ...], exclude: tuple[str, ...] = ()) -> str | None:
    for pattern in patterns:
        for name in df.columns:
            if re.search(pattern, name) and not any(re.search(e, name) for e in exclude):
                return name
    return None


def _force_kN(df: pd.DataFrame) -> tuple[np.ndarray, str] | None:
    """The force of a diagram in kN (converted from N where needed)."""
    if "force_kN" in df.columns:
        return df["force_kN"].to_numpy(dtype=float), "force, kN"
    name = _column(df, (r"force_N$",))
    if name is not None:
        return df[name].to_numpy(dtype=float) / 1e3, "force, kN"
    return None


def _displacement(df: pd.DataFrame) -> str | None:
    return _column(df, (r"displacement.*_mm$", r"_mm$"))


def _stress_pair(df: pd.DataFrame) -> tuple[str, str] | None:
    """(strain column, stress column) of a stress-strain curve; the first column is x."""
    y = _column(df, (r"stress.*_MPa$", r"_MPa$"))
    x = _column(df, (r"strain",), exclude=(r"rate",))
    if x is None:
        x = df.columns[0]
    if y is None or y == x:
        return None
    return x, y


def draw_diagram(ident: Identification, path: Path) -> None:
    """Raw and corrected indicator diagram, force (kN) against displacement (mm)."""
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    try:
        for name, style in (("raw_diagram", dict(color="0.55", lw=1.0, label="as recorded (crosshead)")),
                            ("corrected_diagram", dict(color="C0", lw=1.4, label="corrected (frame compliance, toe)"))):
            df = ident.curves.get(name)
            if df is None or df.empty:
                continue
            disp, force = _displacement(df), _force_kN(df)
            if disp is None or force is None:
                continue
            x, y = _thin(df[disp].to_numpy(dtype=float), force[0])
            ax.plot(x, y, **style)
            ax.set_ylabel(force[1])
        ax.set_xlabel("displacement, mm")
        ax.set_title(_title(ident, "indicator diagram"))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def _plot(ax, df: pd.DataFrame, x: str, y: str, **style) -> None:
    xs, ys = _thin(df[x].to_numpy(dtype=float), df[y].to_numpy(dtype=float))
    ax.plot(xs, ys, **style)


def _selected_name(ident: Identification) -> str | None:
    """The true curve the result stands on: ``true`` (tension) or ``true_<friction correction>``."""
    correction = ident.result.get("friction_correction")
    if correction and f"true_{correction}" in ident.curves:
        return f"true_{correction}"
    return "true" if "true" in ident.curves else None


def _fitted_range(ident: Identification) -> tuple[float, float] | None:
    """The plastic strain range of the measured points the law was fitted to (a tension fit's
    uniform range, without the single fracture point)."""
    h = ident.result.get("hardening") or {}
    r = h.get("fit_range") or h.get("strain_range")
    if isinstance(r, (list, tuple)) and len(r) == 2 and all(isinstance(v, (int, float)) for v in r):
        return float(r[0]), float(r[1])
    return None


def _draw_fit(ax, ident: Identification, fit: pd.DataFrame) -> None:
    """The hardening fit: solid over the fitted range, dashed and labelled where it is extrapolated."""
    y = _column(fit, (r"_MPa$",))
    x = fit["true_plastic_strain"].to_numpy(dtype=float)
    f = fit[y].to_numpy(dtype=float)
    rng = _fitted_range(ident)
    lo, hi = rng if rng is not None else (-np.inf, np.inf)
    inside = (x >= lo - 1e-12) & (x <= hi + 1e-12)
    beyond = x > hi + 1e-12  # not drawn below the fitted range (the elastic–plastic transition)
    ax.plot(np.where(inside, x, np.nan), np.where(inside, f, np.nan), color="k", lw=1.0, zorder=4, label=_fit_label(ident))
    if beyond.any():
        through = (ident.result.get("hardening") or {}).get("fracture_point") == "included"
        what = (f"fit beyond the measured εp {hi:.3g}, to the fracture point" if through
                else f"fit extrapolated beyond the fitted εp {lo:.3g}–{hi:.3g}")
        ax.plot(np.where(beyond, x, np.nan), np.where(beyond, f, np.nan), color="k", lw=1.0, ls="--", zorder=4, label=what)


def draw_stress_strain(ident: Identification, path: Path) -> None:
    """Left: engineering and true curves against total strain. Right: the selected true curve
    against true plastic strain, drawn over the hardening fit (solid where fitted, dashed where
    extrapolated), the other corrections thin, and the neck-corrected fracture point."""
    curves = ident.curves
    total = [n for n in ("engineering", "true") if n in curves and _stress_pair(curves[n])]
    fig, axes = plt.subplots(1, 2 if total else 1, figsize=(10 if total else 7, 4.5), squeeze=False, layout="constrained",
                             width_ratios=[1, 1.4] if total else None)
    try:
        if total:
            ax = axes[0][0]
            for i, name in enumerate(total):
                x, y = _stress_pair(curves[name])
                _plot(ax, curves[name], x, y, lw=1.3, color=f"C{i}", label=f"{name} curve")
            ax.set_xlabel("strain")
            ax.set_ylabel("stress, MPa")
            ax.set_title("engineering and true curves")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best")
        ax = axes[0][-1]
        selected = _selected_name(ident)
        others = [n for n in sorted(curves) if n.startswith("true_") and n != selected]
        for name in others:
            df = curves[name]
            if "true_plastic_strain" in df.columns and _column(df, (r"stress.*_MPa$",)):
                _plot(ax, df, "true_plastic_strain", _column(df, (r"stress.*_MPa$",)), lw=0.8, alpha=0.7,
                      label=f"other correction: {words(name)}")
        fit = curves.get("fit")
        if fit is not None and "true_plastic_strain" in fit.columns:
            _draw_fit(ax, ident, fit)
        if selected is not None and "true_plastic_strain" in curves[selected].columns:
            df = curves[selected]
            how = f" ({words(selected)})" if selected != "true" else ""
            _plot(ax, df, "true_plastic_strain", _column(df, (r"stress.*_MPa$",)), lw=3.0, color="C3", alpha=0.55, zorder=3,
                  label=f"selected true curve{how}")
        point = curves.get("fracture_point")
        if point is not None and "true_plastic_strain" in point.columns:
            neck = NECK_NAMES.get(str((ident.result.get("methods") or {}).get("neck_correction")), "")
            ax.plot(point["true_plastic_strain"], point[_column(point, (r"_MPa$",))], "s", color="C2", zorder=5,
                    label=f"fracture, neck-corrected{' (' + neck + ')' if neck else ''}")
        ax.set_xlabel(axis_label("true_plastic_strain"))
        ax.set_ylabel(axis_label("true_stress_MPa"))
        ax.set_title("flow curve and hardening fit")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="lower right", fontsize="small")
        fig.suptitle(_title(ident, "stress–strain curves"))
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def draw_corrections(ident: Identification, path: Path) -> None:
    """The true curve of every friction correction, one panel each, same axes, fit overlaid."""
    names = sorted(n for n in ident.curves if n.startswith("true_") and _stress_pair(ident.curves[n]))
    cols = min(2, max(1, len(names)))  # two panels a row: legible at the report's page width
    rows = -(-max(1, len(names)) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.6 * rows), sharex=True, sharey=True, squeeze=False, layout="constrained")
    try:
        fit = ident.curves.get("fit")
        selected = _selected_name(ident)
        for ax in axes.flat[len(names):]:
            ax.set_visible(False)
        for ax, name in zip(axes.flat, names):
            df = ident.curves[name]
            xc, yc = _stress_pair(df)
            x, y = _thin(df[xc].to_numpy(dtype=float), df[yc].to_numpy(dtype=float))
            ax.plot(x, y, lw=1.8, color="C3" if name == selected else "C0", zorder=3,
                    label="selected true curve" if name == selected else "true curve")
            if fit is not None and _stress_pair(fit) is not None:
                fx, fy = _stress_pair(fit)
                ax.plot(fit[fx], fit[fy], "k--", lw=0.9, label=f"{_law_name(ident)} fit (of the selected curve)")
            ax.set_title(words(name) + (" (selected)" if name == selected else ""), fontsize="medium")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="lower right", fontsize="small")
        for ax in axes[-1]:
            ax.set_xlabel(axis_label("true_plastic_strain"))
        for ax in axes[:, 0]:
            ax.set_ylabel(axis_label("true_stress_MPa"))
        fig.suptitle(_title(ident, "true curves by friction correction"))
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def _title(ident: Identification, what: str) -> str:
    rec = ident.result.get("record") or {}
    parts = [str(p) for p in (rec.get("name"), rec.get("material")) if p]
    temp = rec.get("nominal_temperature_C")
    if isinstance(temp, (int, float)):
        parts.append(f"{temp:g} °C")
    return f"{what} — {', '.join(parts)}" if parts else what


def _law_name(ident: Identification) -> str:
    law = str((ident.result.get("hardening") or {}).get("law", ""))
    return display_name_of(law) or "hardening"


def _fit_label(ident: Identification) -> str:
    h = ident.result.get("hardening") or {}
    if all(isinstance(h.get(k), (int, float)) for k in ("A_MPa", "B_MPa", "n")):
        return f"{_law_name(ident)} fit: A = {h['A_MPa']:.0f} MPa, B = {h['B_MPa']:.0f} MPa, n = {h['n']:.3f}"
    return f"{_law_name(ident)} fit"


def add_plots(ident: Identification) -> Identification:
    """Fill ``ident.plots`` (name → draw(path)) from the curves it has; returns ``ident``."""
    curves = ident.curves
    if "raw_diagram" in curves or "corrected_diagram" in curves:
        ident.plots["diagram"] = partial(draw_diagram, ident)
    if any(n in curves for n in ("engineering", "true", "fit")) or any(n.startswith("true_") for n in curves):
        ident.plots["stress_strain"] = partial(draw_stress_strain, ident)
    if ident.result.get("test") == "compression" and any(n.startswith("true_") for n in curves):
        ident.plots["corrections"] = partial(draw_corrections, ident)
    return ident

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

from flowcurve.identification.outcome import Identification  # noqa: E402

# column-name unit suffix → how the axis label writes it
UNIT_LABELS = {
    "mm": "mm", "kN": "kN", "N": "N", "MPa": "MPa", "GPa": "GPa", "s": "s", "pct": "%",
    "C": "°C", "mm2": "mm²", "per_s": "1/s", "um": "µm",
}
DIMENSIONLESS = ("strain", "ratio", "mu", "factor")
MAX_POINTS = 2000  # points drawn per line; longer curves are thinned evenly


def axis_label(column: str) -> str:
    """``'true_stress_MPa'`` → ``'true stress (MPa)'``; strains are marked dimensionless."""
    for suffix in sorted(UNIT_LABELS, key=len, reverse=True):
        if column.endswith("_" + suffix):
            return f"{column[: -len(suffix) - 1].replace('_', ' ')} ({UNIT_LABELS[suffix]})"
    label = column.replace("_", " ")
    return f"{label} (–)" if any(word in column for word in DIMENSIONLESS) else label


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
        return df["force_kN"].to_numpy(dtype=float), "force (kN)"
    name = _column(df, (r"force_N$",))
    if name is not None:
        return df[name].to_numpy(dtype=float) / 1e3, "force (kN)"
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
        for name, style in (("raw_diagram", dict(color="0.55", lw=1.0)), ("corrected_diagram", dict(color="C0", lw=1.4))):
            df = ident.curves.get(name)
            if df is None or df.empty:
                continue
            disp, force = _displacement(df), _force_kN(df)
            if disp is None or force is None:
                continue
            x, y = _thin(df[disp].to_numpy(dtype=float), force[0])
            ax.plot(x, y, label=f"{name.replace('_', ' ')}: {axis_label(disp).split(' (')[0]}", **style)
            ax.set_ylabel(force[1])
        ax.set_xlabel("displacement (mm)")
        ax.set_title(_title(ident, "indicator diagram"))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def _plot(ax, df: pd.DataFrame, x: str, y: str, **style) -> None:
    xs, ys = _thin(df[x].to_numpy(dtype=float), df[y].to_numpy(dtype=float))
    ax.plot(xs, ys, **style)


def draw_stress_strain(ident: Identification, path: Path) -> None:
    """Left: engineering and true curves against total strain. Right: true stress against
    true plastic strain with the hardening fit (and the neck-corrected fracture point)."""
    curves = ident.curves
    total = [n for n in ("engineering", "true") if n in curves and _stress_pair(curves[n])]
    fig, axes = plt.subplots(1, 2 if total else 1, figsize=(12 if total else 7, 4.5), squeeze=False, layout="constrained")
    try:
        if total:
            ax = axes[0][0]
            for i, name in enumerate(total):
                x, y = _stress_pair(curves[name])
                _plot(ax, curves[name], x, y, lw=1.3, color=f"C{i}", label=f"{name} ({axis_label(x).split(' (')[0]})")
            ax.set_xlabel("strain (–)")
            ax.set_ylabel("stress (MPa)")
            ax.set_title("engineering and true curves")
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best")
        ax = axes[0][-1]
        plastic = [n for n in ("true", *sorted(n for n in curves if n.startswith("true_"))) if n in curves]
        for i, name in enumerate(plastic):
            df = curves[name]
            y = _column(df, (r"stress.*_MPa$",))
            if "true_plastic_strain" in df.columns and y:
                _plot(ax, df, "true_plastic_strain", y, lw=1.3, color=f"C{i + 1}", label=name.replace("_", " "))
        fit = curves.get("fit")
        if fit is not None and "true_plastic_strain" in fit.columns:
            _plot(ax, fit, "true_plastic_strain", _column(fit, (r"_MPa$",)), color="k", ls="--", lw=1.2, label=_fit_label(ident))
        point = curves.get("fracture_point")
        if point is not None and "true_plastic_strain" in point.columns:
            ax.plot(point["true_plastic_strain"], point[_column(point, (r"_MPa$",))], "rs", label="fracture (neck-corrected)")
        ax.set_xlabel(axis_label("true_plastic_strain"))
        ax.set_ylabel(axis_label("true_stress_MPa"))
        ax.set_title("flow curve and hardening fit")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best")
        fig.suptitle(_title(ident, "stress-strain curves"))
        fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def draw_corrections(ident: Identification, path: Path) -> None:
    """The true curve of every friction correction, one panel each, same axes, fit overlaid."""
    names = sorted(n for n in ident.curves if n.startswith("true_") and _stress_pair(ident.curves[n]))
    fig, axes = plt.subplots(1, max(1, len(names)), figsize=(3.6 * max(1, len(names)), 4), sharey=True, squeeze=False, layout="constrained")
    try:
        fit = ident.curves.get("fit")
        for ax, name in zip(axes[0], names):
            df = ident.curves[name]
            xc, yc = _stress_pair(df)
            x, y = _thin(df[xc].to_numpy(dtype=float), df[yc].to_numpy(dtype=float))
            ax.plot(x, y, lw=1.3, label=name.removeprefix("true_").replace("_", " "))
            if fit is not None and _stress_pair(fit) is not None:
                fx, fy = _stress_pair(fit)
                ax.plot(fit[fx], fit[fy], "k--", lw=1.0, label="fit")
            ax.set_xlabel(axis_label(xc))
            ax.set_title(name.removeprefix("true_").replace("_", " "))
            ax.grid(True, alpha=0.3)
            ax.legend(loc="lower right", fontsize="small")
        axes[0][0].set_ylabel("true stress (MPa)")
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


def _fit_label(ident: Identification) -> str:
    h = ident.result.get("hardening") or {}
    law = h.get("law", "fit")
    if all(isinstance(h.get(k), (int, float)) for k in ("A_MPa", "B_MPa", "n")):
        return f"{law}: A={h['A_MPa']:.0f} MPa, B={h['B_MPa']:.0f} MPa, n={h['n']:.3f}"
    return f"{law} fit"


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

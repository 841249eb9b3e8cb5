"""A series fit: the typed request and the fit, for ``flowcurve fit`` and the console.

:func:`fit` fits Johnson–Cook to a series' members and writes ``fit.json`` (schema in
``docs/fit-json.md``), the tabulated true curves per (temperature, rate) in ``curves/`` and one
plot per record (plus an overview) in ``plots/``; :func:`summary` is what a terminal shows.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from flowcurve.services import choice

if TYPE_CHECKING:  # the series fit (lmfit, pandas) is imported when a fit runs, not for --help
    from flowcurve.identification.series.series import SeriesFit

METHODS = ("global", "stepwise")
MAX_POINTS = 60  # the series fit's MAX_POINTS (tests/test_startup.py keeps them equal)
SHAPE_ERROR_PCT = 0.4  # series_fit.SHAPE_ERROR_PCT, likewise


@dataclass
class FitRequest:
    """A series fit as ``flowcurve fit`` and the console ask for it (Johnson–Cook unless ``law``).

    Attributes
    ----------
    inputs : list of str
        Record files or result folders (or folders of them).
    out : str or Path
        The fit folder written.
    ref_rate, ref_temp, melt_temp : float, optional
        Reference strain rate, 1/s; reference and melting temperature, °C.
    method : str
        "global" (one least squares) or "stepwise" (Johnson–Cook only).
    fix_C, fix_m : float, optional
        Johnson–Cook's C and m held at these values, not identified.
    E_MPa : float, optional
        Young's modulus for records without a handbook one, MPa.
    rate_per_record, max_points : bool, int
        One strain rate per record instead of per point; points taken from each curve.
    shape_error : float
        The law's model-form error added to each point's uncertainty, %.
    fracture_points : str, optional
        A CSV of fracture points measured elsewhere (Johnson–Cook damage D1–D5).
    law : str
        A registered law's name (:func:`flowcurve.identification.laws.base.registered_laws`).
    adiabatic, taylor_quinney, density_kg_per_m3, heat_capacity_J_per_kg_K, adiabatic_min_rate : optional
        Put the points at or above ``adiabatic_min_rate`` (1/s) at their adiabatic temperature:
        ΔT = β/(ρ c) ∫σ dεp with β, ρ (kg/m³) and c (J/(kg K)).
    warnings, options : list, dict
        Warnings gathered while checking; the options as given (fit.json's provenance).
    """

    inputs: list[str]
    out: str | Path = "fit"
    ref_rate: float | None = None
    ref_temp: float | None = None
    melt_temp: float | None = None
    method: str = "global"
    fix_C: float | None = None
    fix_m: float | None = None
    E_MPa: float | None = None
    rate_per_record: bool = False
    max_points: int = MAX_POINTS
    shape_error: float = SHAPE_ERROR_PCT
    fracture_points: str | None = None
    law: str = "johnson_cook"  # a registered law with rate and temperature (validated when the fit runs)
    adiabatic: bool = False  # each point at T0 + β∫σ dεp/(ρ c_p) (records at ≥ adiabatic_min_rate 1/s)
    taylor_quinney: float = 0.9
    density_kg_per_m3: float | None = None
    heat_capacity_J_per_kg_K: float | None = None
    adiabatic_min_rate: float = 0.0
    warnings: list[str] = field(default_factory=list)  # found before the fit (records skipped), written first in fit.json
    options: dict = field(default_factory=dict)  # as given, for fit.json's provenance

    def check(self) -> FitRequest:
        """The request, or FieldError naming its first refused field (method, law)."""
        from flowcurve.errors import FlowcurveError
        from flowcurve.identification.laws.base import get_law
        from flowcurve.services import FieldError

        choice("method", "--method", self.method, METHODS)
        try:
            get_law(self.law)
        except FlowcurveError as exc:  # an unknown law, with the nearest name
            raise FieldError("law", str(exc)) from None
        return self

    def fixed(self) -> dict[str, float]:
        """The constants fixed, not identified."""
        return {k: v for k, v in (("C", self.fix_C), ("m", self.fix_m)) if v is not None}


def fit(req: FitRequest, members):
    """Fit a series as ``req`` asks and write the fit folder (fit.json, curves, plots).

    Parameters
    ----------
    req : FitRequest
        The law, method, reference conditions and output folder.
    members : list of SeriesMember
        The series (:func:`flowcurve.identification.series.members.load_members`).

    Returns
    -------
    (SeriesFit, Path)
        The fit and the path of the fit.json written.

    Raises
    ------
    IdentificationError
        Naming every input the fit lacks (melting temperature, a fixed C or m …), at once.
    """
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.series.damage import read_fracture_points
    from flowcurve.identification.series.series import fit_series

    req.check()
    if req.rate_per_record:
        from flowcurve.identification.series.members import with_one_rate

        for m in members:
            with_one_rate(m)  # the record's one rate; the points' spread about it weighs them (docs/methods.md §5.10)
    heating = adiabatic_heating(req, members) if req.adiabatic else []
    missing = missing_inputs(members, ref_strain_rate_per_s=req.ref_rate, ref_temperature_C=req.ref_temp,
                             melt_temperature_C=req.melt_temp, fixed=req.fixed()) if req.law == "johnson_cook" else []
    if missing:
        raise IdentificationError(missing_message(missing))
    extra = read_fracture_points(req.fracture_points) if req.fracture_points else ()
    series = fit_series(members, method=req.method, ref_strain_rate_per_s=req.ref_rate, ref_temperature_C=req.ref_temp,
                        melt_temperature_C=req.melt_temp, fixed=req.fixed(), max_points=req.max_points, fracture_points=extra,
                        shape_error_pct=req.shape_error, law=req.law)
    series.warnings[:0] = [*req.warnings, *heating]
    return series, write_fit(series, req.out, options=req.options)


def adiabatic_heating(req: FitRequest, members) -> list[str]:
    """Put each point of the members at or above ``req.adiabatic_min_rate`` at its own temperature
    T0 + ΔT, ΔT = β∫σ dεp/(ρ c_p) (identification.series.members.with_adiabatic_heating), so the
    fit gives the isothermal law; returns the line fit.json's warnings state it in."""
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.series.members import with_adiabatic_heating

    hot = [m for m in members if m.strain_rate_per_s >= req.adiabatic_min_rate]
    props = {m.name: (req.density_kg_per_m3 or m.density_kg_per_m3, req.heat_capacity_J_per_kg_K or m.heat_capacity_J_per_kg_K) for m in hot}
    lacking = [name for name, (rho, cp) in props.items() if rho is None or cp is None]
    if lacking:
        raise IdentificationError(f"the adiabatic correction needs the material's density and heat capacity (--density kg/m³, "
                                  f"--heat-capacity J/(kg·K), or the records' material.density_kg_per_m3 and "
                                  f"material.heat_capacity_J_per_kg_K): record(s) {', '.join(lacking)} lack them")
    for m in hot:
        with_adiabatic_heating(m, density_kg_per_m3=props[m.name][0], heat_capacity_J_per_kg_K=props[m.name][1], beta=req.taylor_quinney)
    if not hot:
        return [f"adiabatic correction: no record at or above {req.adiabatic_min_rate:g} 1/s, none corrected"]
    worst = max(hot, key=lambda m: m.temperature_rise_max_K)
    used = ", ".join(sorted({f"ρ {rho:g} kg/m³, c_p {cp:g} J/(kg·K)" for rho, cp in props.values()}))
    return [f"adiabatic correction on {len(hot)} of {len(members)} records (rate ≥ {req.adiabatic_min_rate:g} 1/s): each point at "
            f"T0 + β∫σ dεp/(ρ c_p) with β {req.taylor_quinney:g}, {used}; the law is the isothermal one; largest rise "
            f"{worst.temperature_rise_max_K:.3g} K ({worst.name})"]


# each input the fit may lack: (option, what it is, why the fit needs it)
FIT_INPUTS = {
    "melt_temp": ("--melt-temp", "melting temperature, °C", "T* = (T - T_ref)/(T_melt - T_ref) needs it"),
    "fix_C": ("--fix-C", "C", "the series has one strain rate as the model sees it: fix C, or add records at other rates"),
    "fix_m": ("--fix-m", "m", "the series has one temperature as the model sees it: fix m, or add records at other temperatures"),
}


def missing_inputs(members, *, ref_strain_rate_per_s=None, ref_temperature_C=None, melt_temperature_C=None,
                   fixed=None) -> list[str]:
    """Every input (a key of FIT_INPUTS) the fit of ``members`` lacks, found at once: the melting
    temperature when not given, and C or m when the series cannot identify it and it is not fixed."""
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.series.series import BOUNDS, check_identifiable, make_reference

    fixed, missing = dict(fixed or {}), []
    melt = melt_temperature_C
    if melt is None:
        missing.append("melt_temp")
        # a stand-in above every record, only to see which of C and m the series can give
        melt = max([m.temperature_C for m in members] + [ref_temperature_C or 0.0]) + 1000.0
    try:
        ref = make_reference(members, ref_strain_rate_per_s=ref_strain_rate_per_s, ref_temperature_C=ref_temperature_C,
                             melt_temperature_C=melt)
    except IdentificationError:
        return missing  # the fit's own checks name what is wrong with the given values
    for name, other in (("C", "m"), ("m", "C")):
        if name in fixed:
            continue
        try:
            check_identifiable(members, ref, {other: BOUNDS[other][0]})  # the other one fixed: this one alone is checked
        except IdentificationError:
            missing.append(f"fix_{name}")
    return missing


def missing_message(missing: list[str], labels: dict[str, str] | None = None) -> str:
    """One line naming every input the fit lacks, as ``labels`` name them (the console's form)
    or by option."""
    labels = labels or {}
    parts = [f"{labels.get(k) or FIT_INPUTS[k][1] + ' (' + FIT_INPUTS[k][0] + ')'}: {FIT_INPUTS[k][2]}" for k in missing]
    return f"the fit needs {len(missing)} input(s) not given: " + "; ".join(parts)


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name) or "record"


POINT_RATES_FILE = "point_rates.csv"


def write_fit(series: SeriesFit, outdir: str | Path, options: dict | None = None) -> Path:
    """Write fit.json, curves/*.csv, point_rates.csv and plots/*.png into ``outdir``; returns the fit.json path.

    fit.json's ``provenance`` (identification.provenance) names every record's SHA-256 and the
    ``options`` as given."""
    from flowcurve.identification.outcome import to_jsonable
    from flowcurve.identification.provenance import member_record_sha256, provenance

    outdir = Path(outdir)
    (outdir / "curves").mkdir(parents=True, exist_ok=True)
    (outdir / "plots").mkdir(parents=True, exist_ok=True)
    data = series.as_dict()
    for c in series.curves:
        c.table.to_csv(outdir / "curves" / c.filename, index=False, float_format="%.6g", lineterminator="\n")
    series.point_rates().to_csv(outdir / POINT_RATES_FILE, index=False, float_format="%.6g", lineterminator="\n")
    data["point_rates_file"] = POINT_RATES_FILE  # each fitted point's own strain rate (docs/fit-json.md)
    plots = _plots(series, outdir / "plots")
    curve_of = {name: f"curves/{c.filename}" for c in series.curves for name in c.records}
    for rec in data["records"]:
        rec["curve"] = curve_of.get(rec["name"])
        rec["plot"] = plots.get(rec["name"])
        rec["temperature_rise_max_K"] = next(m.temperature_rise_max_K for m in series.members if m.name == rec["name"])
    data["provenance"] = provenance({m.name: member_record_sha256(m.kind, m.source) for m in series.members}, options or {})
    path = outdir / "fit.json"
    path.write_text(json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


def _plots(series: SeriesFit, folder: Path) -> dict[str, str]:
    """One PNG per record (measured curve, the chosen fit, the other method dashed) and an overview."""
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    other = series.stepwise_fit if series.method == "global" else series.global_fit
    written: dict[str, str] = {}
    fig_all, ax_all = plt.subplots(figsize=(7, 5))
    for i, m in enumerate(series.members):
        eps = m.plastic_strain
        grid = np.linspace(0.0, eps[-1], 200)
        label = f"{m.temperature_C:.0f} °C, {m.strain_rate_per_s:.3g} 1/s"
        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax.plot(eps, m.stress_MPa, ".", ms=3, color="0.3", label=f"{m.name} (measured)")
        ax.plot(grid, series.fit(grid, m.strain_rate_per_s, m.temperature_C), "-", color="C0",
                label=f"{series.fit.method} fit (max error {series.fit.record_errors[m.name]['fit_error_pct']:.2g} %)")
        if other is not None:
            ax.plot(grid, other(grid, m.strain_rate_per_s, m.temperature_C), "--", color="C1", label=f"{other.method} fit")
        ax.set(xlabel="true plastic strain", ylabel="true stress, MPa", title=label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        name = f"plots/{_safe(m.name)}.png"
        fig.tight_layout()
        fig.savefig(folder / Path(name).name, dpi=110)
        plt.close(fig)
        written[m.name] = name
        color = f"C{i % 10}"
        ax_all.plot(eps, m.stress_MPa, ".", ms=2, color=color)
        ax_all.plot(grid, series.fit(grid, m.strain_rate_per_s, m.temperature_C), "-", color=color, label=f"{m.name}: {label}")
    ax_all.set(xlabel="true plastic strain", ylabel="true stress, MPa", title=f"{series.fit.law.display_name}, {series.method} fit (lines) and records (dots)")
    ax_all.grid(alpha=0.3)
    ax_all.legend(fontsize=7)
    fig_all.tight_layout()
    fig_all.savefig(folder / "all_records.png", dpi=110)
    plt.close(fig_all)
    return written


def summary(series: SeriesFit, path: Path) -> str:
    """What the terminal shows after a fit: constants ± their total standard uncertainty (the fit's
    standard error and the curve-shape band in quadrature, both stated), range, errors."""
    from flowcurve.identification.series.law_fit import total_uncertainty

    f = series.fit
    band = series.shape_uncertainty or {}
    total = total_uncertainty(f, band)
    ref, law = f.reference, f.law
    head = f"{law.display_name}, {series.method} fit over {len(series.members)} records"
    if ref is not None:
        head += (f" (ref. rate {ref.strain_rate_per_s:g} 1/s [{ref.strain_rate_source}], ref. temperature {ref.temperature_C:g} °C "
                 f"[{ref.temperature_source}], melting {ref.melt_temperature_C:g} °C)")
    lines = [head]
    for p, v in f.params.items():
        se, unit, key = f.stderr.get(p), law.parameter(p).unit, law.parameter(p).key
        u, shape = total.get(key), band.get(key)
        parts = ", ".join(x for x in (f"fit {se:.2g}" if se is not None else "", f"curve shape {shape:.2g}" if shape is not None else "") if x)
        tag = (f" (fixed, not identified: {f.fixed_why.get(p, 'by the user')})" if p in f.fixed
               else f" (on its {f.at_bound[p]} bound: not identified)" if p in f.at_bound
               else f" ± {u:.3g} ({parts}; standard uncertainty)" if u is not None else " (no uncertainty)")
        lines.append(f"  {p} = {v:.5g}{' ' + unit if unit else ''}{tag}")
    d = series.covered_range()
    lines.append(f"  identified on: plastic strain {d['plastic_strain'][0]:.3g}–{d['plastic_strain'][1]:.3g}, "
                 f"rate {d['strain_rate_per_s'][0]:.3g}–{d['strain_rate_per_s'][1]:.3g} 1/s, "
                 f"temperature {d['temperature_C'][0]:.4g}–{d['temperature_C'][1]:.4g} °C")
    lines.append(f"  error: max {f.fit_error_pct:.2f} %, rms {f.rms_error_pct:.2f} %, quality {series.quality}")
    for m in series.members:
        e = f.record_errors[m.name]
        lines.append(f"    {m.name}: {m.temperature_C:.4g} °C, {m.strain_rate_per_s:.3g} 1/s ({m.strain_rate_source}): "
                     f"max {e['fit_error_pct']:.2f} %, rms {e['rms_error_pct']:.2f} %")
    other = series.stepwise_fit if series.method == "global" else series.global_fit
    if other is not None:
        lines.append(f"  {other.method} for comparison: " + ", ".join(f"{p} = {v:.4g}" for p, v in other.params.items())
                     + f" (max error {other.fit_error_pct:.2f} %)")
    elif series.stepwise_note:
        lines.append(f"  {series.stepwise_note}")
    if series.damage is not None:
        d = series.damage
        lines.append(f"  fracture (2.22) over {len(d.points)} points, triaxiality {d.covered()['triaxiality_range'][0]:.3g}-"
                     f"{d.covered()['triaxiality_range'][1]:.3g} (positive in tension): "
                     + ", ".join(f"{k} = {v:.4g}" + (" (fixed)" if k in d.fixed else f" ± {d.stderr[k]:.2g}" if d.stderr[k] else "")
                                 for k, v in d.params.items()))
    lines += [f"  warning: {w}" for w in series.warnings]
    lines.append(f"wrote {path}")
    return "\n".join(lines)

"""The members of a test series: one true curve σ(εp) with the strain rate and temperature it
was run at (:class:`SeriesMember`), built from a record (identified on the way) or from a
result folder of ``flowcurve identify``; :func:`load_members` takes either.

Part of :mod:`identification.series` (which re-exports these names); the fits are in
:mod:`identification.series_fit`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np
import pandas as pd

from flowcurve.record.format import Record
from flowcurve.errors import IdentificationError, RecordError
from flowcurve.identification.outcome import TRUE_CURVE_COLUMNS
from flowcurve.identification.series.damage import FracturePoint, fracture_point_from_result
from flowcurve.identification.elastic_modulus import result_material_E

PLASTIC_START = 0.002  # εp where the plastic range starts (the 0.2 % offset)
MAX_POINTS = 60  # points per record in a fit, so that every record weighs the same


@dataclass
class SeriesMember:
    """One test of a series: its true curve and the conditions it was run at."""

    name: str
    plastic_strain: np.ndarray
    stress_MPa: np.ndarray
    strain_rate_per_s: float
    temperature_C: float
    source: str = "<memory>"
    kind: str = "given"  # "record", "result" (folder of flowcurve identify) or "given"
    test: str | None = None
    strain_rate_source: str = "given"
    temperature_source: str = "given"
    friction_mu: float | None = None
    E_MPa: float | None = None
    E_material_MPa: float | None = None  # the E the test hands on, and its class (identification.elastic_modulus):
    E_source: str = "none"  # given / handbook / measured, or apparent / none (then E_material_MPa is the apparent slope)
    poisson_ratio: float | None = None
    material: str | None = None
    fracture: FracturePoint | None = None  # the test's fracture (tension with a section after fracture)
    identified_law: dict | None = None  # result.json's hardening: the law 'flowcurve identify' fitted and its strain range
    point_rates_per_s: np.ndarray | None = None  # each curve point's own plastic strain rate (1/s), when the record gives it
    point_temperatures_C: np.ndarray | None = None  # each point's own temperature (°C): the adiabatic rise added (with_adiabatic_heating)
    density_kg_per_m3: float | None = None  # the record's material.density_kg_per_m3 (for the adiabatic correction)
    heat_capacity_J_per_kg_K: float | None = None  # the record's material.heat_capacity_J_per_kg_K
    # what each point's uncertainty in the series fit is built from (identification.series.point_uncertainty, §5.10)
    delta_eps0: float | None = None  # the strain zero's stated uncertainty (identify's hardening.start_uncertainty.delta_eps0)
    friction_mu_u: float | None = None  # u(μ): half the friction method's μ range (result.json friction_mu_range)
    dsigma_dmu_MPa: np.ndarray | None = None  # each point's ∂σ/∂μ of the applied friction correction (true_curve.csv)
    correction_u_pct: np.ndarray | None = None  # each point's correction uncertainty, % (true_curve.csv correction_uncertainty_pct)
    strain_rate_u_ln: float | None = None  # a stated standard uncertainty of ln ε̇ of every point
    strain_rate_u_source: str | None = None  # what strain_rate_u_ln holds
    nominal_strain_rate_per_s: float | None = None  # the commanded rate: crosshead speed / gauge length (h0 or l0)
    temperature_u_C: float | None = None  # a stated standard uncertainty of each point's T: the measured T's spread over the plastic range
    stream_gap_from_strain: float | None = None  # a load-cell stream gap's doubt: the first plastic strain whose row carries it (true_curve.csv stream_gap_u_MPa)
    stream_gap_u_max_MPa: float | None = None  # ... and the largest it states

    def __post_init__(self):
        where = self.source if self.source != "<memory>" else self.name
        eps = np.asarray(self.plastic_strain, dtype=float).ravel()
        sig = np.asarray(self.stress_MPa, dtype=float).ravel()
        if eps.shape != sig.shape:
            raise RecordError(where, f"true curve: {eps.size} strains but {sig.size} stresses")
        rates = None if self.point_rates_per_s is None else np.asarray(self.point_rates_per_s, dtype=float).ravel()
        if rates is not None and rates.shape != eps.shape:
            raise RecordError(where, f"true curve: {eps.size} strains but {rates.size} point strain rates")
        temps = None if self.point_temperatures_C is None else np.asarray(self.point_temperatures_C, dtype=float).ravel()
        if temps is not None and temps.shape != eps.shape:
            raise RecordError(where, f"true curve: {eps.size} strains but {temps.size} point temperatures")
        ok = np.isfinite(eps) & np.isfinite(sig) & (np.isfinite(rates) & (rates > 0) if rates is not None else True)
        ok &= np.isfinite(temps) if temps is not None else True
        eps, sig = eps[ok], sig[ok]
        order = np.argsort(eps, kind="stable")
        eps, sig = eps[order], sig[order]
        self.point_rates_per_s = None if rates is None else rates[ok][order]
        self.point_temperatures_C = None if temps is None else temps[ok][order]
        for name in ("dsigma_dmu_MPa", "correction_u_pct"):  # a cell that is not a number states nothing: 0
            values = getattr(self, name)
            if values is not None:
                values = np.nan_to_num(np.asarray(values, dtype=float).ravel(), nan=0.0, posinf=0.0, neginf=0.0)
                if values.shape != ok.shape:
                    raise RecordError(where, f"true curve: {ok.size} strains but {values.size} values of {name}")
                setattr(self, name, values[ok][order])
        if eps.size < 4 or np.ptp(eps) <= 0:
            raise RecordError(where, f"true curve has {eps.size} usable points; a series fit needs at least 4 over a strain range")
        if np.min(eps) < 0 or np.min(sig) <= 0:
            raise RecordError(where, "true curve must have εp ≥ 0 and stress > 0 (MPa)")
        self.plastic_strain, self.stress_MPa = eps, sig
        for value, what, hint in ((self.strain_rate_per_s, "strain rate", "strain_rate_per_s"),
                                  (self.temperature_C, "temperature", "nominal_temperature_C")):
            if value is None or not math.isfinite(float(value)):
                raise RecordError(where, f"the {what} of this test is unknown (give {hint})")
        self.strain_rate_per_s = float(self.strain_rate_per_s)
        self.temperature_C = float(self.temperature_C)
        if self.strain_rate_per_s <= 0:
            raise RecordError(where, f"strain rate must be > 0, got {self.strain_rate_per_s:g} 1/s")

    def fit_points(self, max_points: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
        """The curve on at most ``max_points`` points evenly spaced in εp (all points if fewer)."""
        eps, sig = self.plastic_strain, self.stress_MPa
        if eps.size <= max_points:
            return eps, sig
        grid = np.linspace(eps[0], eps[-1], max_points)
        return grid, np.interp(grid, eps, sig)

    def rates_at(self, eps_p) -> np.ndarray:
        """The strain rate (1/s) at plastic strains ``eps_p``: each point's own (interpolated in ln ε̇)
        when the member has them, else the record's one rate."""
        eps_p = np.asarray(eps_p, dtype=float)
        if self.point_rates_per_s is None:
            return np.full(eps_p.shape, self.strain_rate_per_s)
        return np.exp(np.interp(eps_p, self.plastic_strain, np.log(self.point_rates_per_s)))

    def temperatures_at(self, eps_p) -> np.ndarray:
        """The temperature (°C) at plastic strains ``eps_p``: each point's own (the adiabatic rise
        added, interpolated) when the member has them, else the test's one temperature."""
        eps_p = np.asarray(eps_p, dtype=float)
        if self.point_temperatures_C is None:
            return np.full(eps_p.shape, self.temperature_C)
        return np.interp(eps_p, self.plastic_strain, self.point_temperatures_C)

    def along_curve(self, name: str, eps_p) -> np.ndarray | None:
        """A per-point column of the member (``dsigma_dmu_MPa``, ``correction_u_pct``) at plastic strains
        ``eps_p`` (linear), None when the member has none."""
        values = getattr(self, name)
        if values is None:
            return None
        return np.interp(np.asarray(eps_p, dtype=float), self.plastic_strain, values)

    @property
    def temperature_rise_max_K(self) -> float | None:
        """The largest adiabatic temperature rise over the curve (K), None when not corrected."""
        if self.point_temperatures_C is None:
            return None
        return float(np.max(self.point_temperatures_C) - self.temperature_C)


TAYLOR_QUINNEY = 0.9  # β: the part of the plastic work that turns into heat (Taylor & Quinney 1934)


def adiabatic_temperature_rise_K(plastic_strain, stress_MPa, *, density_kg_per_m3: float, heat_capacity_J_per_kg_K: float,
                                 beta: float = TAYLOR_QUINNEY) -> np.ndarray:
    """The adiabatic temperature rise (K) at each point of a true curve (εp ascending, from 0):
    ΔT = β·∫₀^εp σ dεp/(ρ·c_p), σ in MPa = 10⁶ J/m³; the integral from εp = 0 to the first point
    at the first point's stress, then trapezoids."""
    eps = np.asarray(plastic_strain, dtype=float)
    sig = np.asarray(stress_MPa, dtype=float)
    work_MJ_per_m3 = sig[0] * eps[0] + np.concatenate([[0.0], np.cumsum(0.5 * (sig[1:] + sig[:-1]) * np.diff(eps))])
    return beta * work_MJ_per_m3 * 1e6 / (density_kg_per_m3 * heat_capacity_J_per_kg_K)  # ΔT = β∫σ dεp/(ρ c_p)


def with_adiabatic_heating(member: SeriesMember, *, density_kg_per_m3: float, heat_capacity_J_per_kg_K: float,
                           beta: float = TAYLOR_QUINNEY) -> SeriesMember:
    """The member with each point's own temperature T0 + ΔT (:func:`adiabatic_temperature_rise_K`):
    a fit over these temperatures gives the isothermal law. Refuses a non-physical β, ρ or c_p."""
    for value, what, option in ((beta, "Taylor-Quinney coefficient β", "--taylor-quinney"),
                                (density_kg_per_m3, "density (kg/m³)", "--density"),
                                (heat_capacity_J_per_kg_K, "specific heat capacity (J/(kg·K))", "--heat-capacity")):
        if value is None or not math.isfinite(float(value)) or float(value) <= 0:
            raise IdentificationError(f"the adiabatic correction needs a {what} > 0 ({option}), got {value}")
    if beta > 1:
        raise IdentificationError(f"the Taylor-Quinney coefficient β is the part of the plastic work turned into heat: ≤ 1, got {beta:g}")
    rise = adiabatic_temperature_rise_K(member.plastic_strain, member.stress_MPa, density_kg_per_m3=density_kg_per_m3,
                                        heat_capacity_J_per_kg_K=heat_capacity_J_per_kg_K, beta=beta)
    member.point_temperatures_C = member.temperature_C + rise
    return member


def with_one_rate(member: SeriesMember) -> SeriesMember:
    """The member fitted at its one rate (``fit --rate-per-record``): its points' own rates dropped, their
    spread about that rate kept as each point's u(ln ε̇) unless the member states one (docs/methods.md §5.10)."""
    rates = member.point_rates_per_s
    if rates is not None and member.strain_rate_u_ln is None:
        member.strain_rate_u_ln = float(np.sqrt(np.mean(np.log(rates / member.strain_rate_per_s) ** 2)))  # RMS of ln(ε̇_i/ε̇)
        member.strain_rate_u_source = "the spread of the points' own rates about the record's rate"
    member.point_rates_per_s = None  # rates_at then gives the record's one rate
    return member


def strain_rate_from_record(record: Record, E_MPa: float | None, plastic_start: float = PLASTIC_START) -> tuple[float, np.ndarray]:
    """Plastic strain rate (1/s) of a record from its data, and the plastic-range sample mask.

    The specimen's true strain from the extensometer (tension records that have one) or the
    crosshead (frame compliance removed when the record states the frame stiffness),
    εp = ε − σ/E, and the least-squares slope of εp against time over the plastic range: from
    the first sample with εp ≥ ``plastic_start`` to the force maximum (tension) or the end of
    loading (compression). Without a modulus (``E_MPa`` None) the total strain stands for εp.
    """
    t, eps_p = _plastic_strain_history(record, E_MPa)
    force = np.abs(record.column("force_N"))
    d = np.abs(record.column("crosshead_mm") - record.column("crosshead_mm")[0])
    end = int(np.nanargmax(force)) if record.test == "tension" else int(np.nanargmax(d))
    mask = np.zeros(t.size, dtype=bool)
    mask[: end + 1] = True
    mask &= np.isfinite(eps_p) & np.isfinite(t)
    started = np.maximum.accumulate(np.where(mask, eps_p, -np.inf)) >= plastic_start
    mask &= started
    if mask.sum() < 3 or np.ptp(t[mask]) <= 0:
        raise IdentificationError(f"{record.source}: fewer than 3 samples in the plastic range (εp ≥ {plastic_start:g}); the strain rate cannot be computed from the data")
    slope = float(np.polyfit(t[mask], eps_p[mask], 1)[0])
    if not slope > 0:
        raise IdentificationError(f"{record.source}: the plastic strain does not grow with time ({slope:.3g} 1/s); check the time_s and crosshead_mm columns")
    return slope, mask


def _plastic_strain_history(record: Record, E_MPa: float | None) -> tuple[np.ndarray, np.ndarray]:
    """(time s, true plastic strain) of every sample: extensometer (tension) or crosshead (frame
    compliance removed when the record states the stiffness), εp = ε − σ/E (ε without a modulus)."""
    test = record.test
    t = record.column("time_s")
    force = np.abs(record.column("force_N"))
    spec = record.specimen
    area0 = spec.area0_mm2
    if test == "tension" and record.has("extensometer_mm"):
        ext = record.column("extensometer_mm")
        d, length = np.abs(ext - ext[0]), spec.extensometer_gauge_mm or spec.l0_mm
    else:
        d = np.abs(record.column("crosshead_mm") - record.column("crosshead_mm")[0])
        stiffness = record.positive("rig.frame_stiffness_N_per_um")
        if stiffness:
            from flowcurve.identification.indicator import remove_frame_compliance

            d = np.abs(remove_frame_compliance(d, force - force[0], stiffness))
        length = spec.gauge_mm
    if test == "tension":
        eps = np.log1p(d / length)  # (3.2)
        sigma = force / area0 * np.exp(eps)  # volume constancy: F0/F = l/l0
    else:
        eps = -np.log(np.clip(1.0 - d / length, 1e-9, None))  # (3.31)
        sigma = force / area0 * np.exp(-eps)  # (3.30) S = F0·h0/h
    if E_MPa is not None and math.isfinite(E_MPa) and E_MPa > 0:
        from flowcurve.identification.tension.values import true_plastic_strain

        return t, true_plastic_strain(eps, sigma, E_MPa)  # (3.7)
    return t, eps  # no modulus: the total strain's rate (the elastic part is small past yield)


RATE_WINDOW_STRAIN = 0.02  # the local plastic strain rate is the slope of εp(t) over this much plastic strain (at least 5 samples)


def point_strain_rates(record: Record, E_MPa: float | None, plastic_strain) -> np.ndarray:
    """Each plastic strain's own strain rate (1/s) from the record's time and specimen height
    (or length): the least-squares slope of εp(t) (as in :func:`strain_rate_from_record`) over
    the samples within ±½·0.02 plastic strain of it (at least 5), read at ``plastic_strain``.
    At constant crosshead speed a compression specimen's ε̇ = v/h doubles by ε = 0.7."""
    slope, mask = strain_rate_from_record(record, E_MPa)
    t, eps_p = _plastic_strain_history(record, E_MPa)
    idx = np.flatnonzero(mask)
    t, e = t[idx], np.maximum.accumulate(eps_p[idx])  # εp never runs back in a monotonic test
    half = 0.5 * RATE_WINDOW_STRAIN
    lo = np.searchsorted(e, e - half, side="left")
    hi = np.searchsorted(e, e + half, side="right")
    rates = np.empty(e.size)
    for k in range(e.size):
        a, b = int(lo[k]), int(hi[k])
        if b - a < 5:  # too coarse for the strain window: the 5 nearest samples
            a = max(0, min(k - 2, e.size - 5))
            b = min(e.size, a + 5)
        tt, ee = t[a:b], e[a:b]
        rates[k] = np.polyfit(tt, ee, 1)[0] if np.ptp(tt) > 0 and np.ptp(ee) > 0 else slope
    rates = np.where(rates > 0, rates, slope)
    _, first = np.unique(e, return_index=True)
    return np.exp(np.interp(np.asarray(plastic_strain, dtype=float), e[first], np.log(rates[first])))


def plastic_part(plastic_strain, stress_MPa, plastic_start: float = PLASTIC_START) -> tuple[np.ndarray, np.ndarray]:
    """The points of a true curve with εp ≥ ``plastic_start``: below the 0.2 % offset a true curve
    of ``flowcurve identify`` still holds the elastic-plastic transition, which no hardening law
    describes."""
    eps = np.asarray(plastic_strain, dtype=float)
    keep = eps >= plastic_start
    return eps[keep], np.asarray(stress_MPa, dtype=float)[keep]


def member_from_record(record: Record, **identify_options) -> SeriesMember:
    """Identify a record (tension or compression) and make it a series member.

    Strain rate from the data (:func:`strain_rate_from_record`, and each point's own,
    :func:`point_strain_rates`); temperature the mean of the
    ``temperature_C`` column over the plastic range, else ``nominal_temperature_C``.
    """
    from flowcurve.identification.identify import identify

    ident = identify(record, **identify_options)
    result = ident.result
    rate, mask = strain_rate_from_record(record, result.get("E_MPa"))
    temperature_u = None
    if record.has("temperature_C") and np.isfinite(record.column("temperature_C")[mask]).any():
        temperature, t_source = float(np.nanmean(record.column("temperature_C")[mask])), "data"
        temperature_u = float(np.nanstd(record.column("temperature_C")[mask]))  # the readings' spread over the plastic range
    else:
        temperature = record.number("nominal_temperature_C")
        t_source = "nominal"
        if temperature is None:
            raise RecordError(record.source, "the test temperature is unknown: add '# nominal_temperature_C: <value>' to the header or a temperature_C column")
    eps, sig = plastic_part(ident.true_curve[TRUE_CURVE_COLUMNS[0]], ident.true_curve[TRUE_CURVE_COLUMNS[1]])
    stated = stated_uncertainties(result, ident.true_curve)
    speed, gauge = record.number("crosshead_speed_mm_per_s"), _gauge_of(record)
    E_material, E_source = result_material_E(result)
    point_rates = point_strain_rates(record, result.get("E_MPa"), eps) if eps.size else None
    return SeriesMember(name=record.name, plastic_strain=eps, stress_MPa=sig, strain_rate_per_s=rate, point_rates_per_s=point_rates,
                        temperature_C=temperature, source=record.source, kind="record", test=record.test,
                        strain_rate_source="data" if _number(result.get("E_MPa")) else "data (total strain: no E_MPa)",
                        temperature_source=t_source,
                        friction_mu=_number(result.get("friction_mu")), E_MPa=_number(result.get("E_MPa")),
                        E_material_MPa=E_material, E_source=E_source, identified_law=_law_of(result),
                        poisson_ratio=_number(result.get("poisson_ratio")), material=record.meta.get("material"),
                        density_kg_per_m3=record.positive("material.density_kg_per_m3"),
                        heat_capacity_J_per_kg_K=record.positive("material.heat_capacity_J_per_kg_K"),
                        temperature_u_C=temperature_u, nominal_strain_rate_per_s=speed / gauge if speed and gauge else None, **stated,
                        fracture=fracture_point_from_result(dict(result, test=record.test), record.meta, rate, temperature,
                                                            record.source))


def member_from_result(folder: str | Path) -> SeriesMember:
    """A series member from a result folder of ``flowcurve identify`` (result.json + true_curve.csv).

    Strain rate: ``record.strain_rate_per_s`` of result.json, else crosshead speed / gauge
    length (l0 in tension, h0 in compression); temperature ``record.nominal_temperature_C``.
    """
    folder = Path(folder)
    path = folder / "result.json"
    try:
        result = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise RecordError(folder, "no result.json: not a result folder of 'flowcurve identify'") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise RecordError(path, f"is not valid JSON ({exc})") from None
    if not isinstance(result, dict):
        raise RecordError(path, "is not a JSON object")
    block = result.get("record") or {}
    if not isinstance(block, dict):
        raise RecordError(path, "'record' is not a JSON object")
    test = result.get("test") or block.get("test")
    temperature = _number(block.get("nominal_temperature_C"))
    if temperature is None:
        raise RecordError(path, "record.nominal_temperature_C is missing: the temperature of this test is unknown")
    rate, rate_source, nominal_rate = _result_rates(block, test, path)
    curve_path = folder / "true_curve.csv"
    try:
        curve = pd.read_csv(curve_path)
    except FileNotFoundError:
        raise RecordError(folder, "no true_curve.csv in the result folder") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise RecordError(curve_path, f"cannot be read as CSV ({exc})") from None
    missing = [c for c in TRUE_CURVE_COLUMNS if c not in curve.columns]
    if missing:
        raise RecordError(curve_path, f"missing column(s) {', '.join(missing)}")
    try:
        eps = curve[TRUE_CURVE_COLUMNS[0]].to_numpy(float)
        sig = curve[TRUE_CURVE_COLUMNS[1]].to_numpy(float)
    except ValueError:
        raise RecordError(curve_path, "the curve holds cells that are not numbers") from None
    eps, sig = plastic_part(eps, sig)
    try:
        stated = stated_uncertainties(result, curve)
    except (TypeError, ValueError):
        raise RecordError(curve_path, "the curve holds cells that are not numbers") from None
    E_material, E_source = result_material_E(result)
    return SeriesMember(name=str(block.get("name") or folder.name), plastic_strain=eps, stress_MPa=sig, **stated,
                        nominal_strain_rate_per_s=nominal_rate,
                        strain_rate_per_s=rate, temperature_C=temperature, source=str(folder), kind="result",
                        test=test, strain_rate_source=rate_source, temperature_source="nominal",
                        friction_mu=_number(result.get("friction_mu")), E_MPa=_number(result.get("E_MPa")),
                        E_material_MPa=E_material, E_source=E_source, identified_law=_law_of(result),
                        poisson_ratio=_number(result.get("poisson_ratio")), material=block.get("material"),
                        fracture=fracture_point_from_result(dict(result, test=test), _flat_specimen(block), rate,
                                                            temperature, str(folder)))


def _result_rates(block: dict, test: str | None, path: Path) -> tuple[float, str, float | None]:
    """(strain rate 1/s, its source, the commanded rate 1/s or None) of result.json's record block: its
    ``strain_rate_per_s``, else the crosshead speed / gauge length (h0 or l0), which is the commanded rate."""
    rate = _number(block.get("strain_rate_per_s"))
    speed = _number(block.get("crosshead_speed_mm_per_s"))
    specimen = block.get("specimen") or {}
    gauge_key = "h0_mm" if test == "compression" else "l0_mm"
    gauge = _number(specimen.get(gauge_key) if isinstance(specimen, dict) else None)
    if gauge is None:
        gauge = _number(block.get(f"specimen.{gauge_key}"))
    nominal_rate = speed / gauge if speed is not None and gauge else None
    if rate is not None:
        return rate, "result.json", nominal_rate
    if nominal_rate is None:
        raise RecordError(path, f"the strain rate is unknown: record.strain_rate_per_s is missing and so is record.crosshead_speed_mm_per_s or the specimen {gauge_key}")
    return nominal_rate, "crosshead speed / gauge length", nominal_rate


def stated_uncertainties(result, curve) -> dict:
    """What an identification states about its curve's points, as :class:`SeriesMember` fields: the strain
    zero's δε0 (hardening.start_uncertainty.delta_eps0), u(μ) = half the friction method's μ range
    (friction_mu_range, ±1σ: quality.uncertainty.friction_budget), and the plastic part's (εp ≥ 0.2 %)
    per-point ∂σ/∂μ and correction uncertainty % (true_curve columns ``dsigma_dmu_MPa``,
    ``correction_uncertainty_pct``). Absent ones are None."""
    start = ((_law_of(result) or {}).get("start_uncertainty") or {})
    mu_range = result.get("friction_mu_range")
    u_mu = None
    if isinstance(mu_range, (list, tuple)) and len(mu_range) == 2 and all(_number(v) is not None for v in mu_range):
        u_mu = abs(float(mu_range[1]) - float(mu_range[0])) / 2.0  # u(μ) = (μ_hi − μ_lo)/2
    eps = np.asarray(curve[TRUE_CURVE_COLUMNS[0]], dtype=float)
    keep = eps >= PLASTIC_START  # as plastic_part
    columns = {name: (np.asarray(curve[column], dtype=float)[keep] if column in curve.columns else None)
               for name, column in (("dsigma_dmu_MPa", "dsigma_dmu_MPa"), ("correction_u_pct", "correction_uncertainty_pct"))}
    return {"delta_eps0": _number(start.get("delta_eps0") if isinstance(start, dict) else None), "friction_mu_u": u_mu, **columns,
            **_stream_gap_rows(eps[keep], curve, keep)}


def _stream_gap_rows(eps: np.ndarray, curve, keep: np.ndarray) -> dict:
    """The first plastic strain whose row carries a load-cell stream gap's doubt (true_curve column
    ``stream_gap_u_MPa`` > 0) and the largest it states; empty without such rows."""
    from flowcurve.identification.quality.stream_gap import ROW_COLUMN

    if ROW_COLUMN not in curve.columns:
        return {}
    u = np.asarray(curve[ROW_COLUMN], dtype=float)[keep]
    carried = ~(u <= 0)  # > 0, or NaN: a doubt not known is not none
    if not carried.any():
        return {}
    return {"stream_gap_from_strain": float(eps[carried][0]), "stream_gap_u_max_MPa": float(np.nanmax(u)) if np.isfinite(u).any() else None}


def stream_gap_warnings(members) -> list[str]:
    """The series fit's word on members whose curve rows carry a load-cell stream gap's doubt: the tabulated curves
    (and the cards made from them) carry it from that strain on, unstated in their own rows."""
    return [f"{m.name}: its true curve's rows from plastic strain {m.stream_gap_from_strain:.4g} on carry a load-cell stream "
            f"gap's doubt (latency or loss undecided: up to {m.stream_gap_u_max_MPa:.3g} MPa, true_curve.csv stream_gap_u_MPa); "
            "the tabulated curve and the constants fitted to it include it there"
            if m.stream_gap_u_max_MPa is not None else
            f"{m.name}: its true curve's rows from plastic strain {m.stream_gap_from_strain:.4g} on carry a load-cell stream gap's "
            "doubt of unknown size (true_curve.csv stream_gap_u_MPa empty); the tabulated curve and the constants include it there"
            for m in members if m.stream_gap_from_strain is not None]


def _gauge_of(record: Record) -> float | None:
    """The length the nominal strain refers to (l0 or h0, mm), None when the record does not state it."""
    return _number(getattr(record.specimen, "gauge_mm", None))  # parsed already: the identification read it


def _law_of(result: dict) -> dict | None:
    """result.json's hardening block (a dict), or None."""
    law = result.get("hardening")
    return dict(law) if isinstance(law, dict) else None


def _flat_specimen(block: dict) -> dict:
    """result.json's record block with its specimen keys as in a record header (specimen.d0_mm)."""
    specimen = block.get("specimen") if isinstance(block.get("specimen"), dict) else {}
    return {**block, **{f"specimen.{k}": v for k, v in specimen.items()}}


def load_members(paths: Iterable[str | Path], **identify_options) -> list[SeriesMember]:
    """Series members from record files, result folders, or folders of result folders.

    Parameters
    ----------
    paths : iterable of str or Path
        The inputs.
    **identify_options
        Options of :func:`flowcurve.identification.identify.identify` for the records.

    Returns
    -------
    list of SeriesMember
        One per record or result (its plastic curve, strain rate and temperature).

    Raises
    ------
    RecordError
        Naming the file or folder an error comes from (:func:`member_of_path`).
    """
    members: list[SeriesMember] = []
    for p in paths:
        members.extend(member_of_path(p, **identify_options))
    no_modulus = [m.name for m in members if m.kind == "record" and m.E_MPa is None]
    if no_modulus:
        raise IdentificationError(
            f"record(s) {', '.join(no_modulus)} have no elastic modulus (no elastic line was found and no handbook E given), so their "
            "plastic strain would be the total strain: add material.E_MPa to the records or give the modulus (--E)")
    names = [m.name for m in members]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise IdentificationError(f"two series members have the same name {', '.join(dup)}; rename one (names label the per-record errors and plots)")
    return members


def member_of_path(path: str | Path, **identify_options) -> list[SeriesMember]:
    """The members one input gives (a record, a result folder, a folder of them), or a
    RecordError naming the file when it cannot give them."""
    from flowcurve.errors import FlowcurveError
    from flowcurve.record.importers import load_record

    p = Path(path)
    if p.is_dir():
        if (p / "result.json").exists():
            return [member_from_result(p)]
        subs = sorted(d for d in p.iterdir() if d.is_dir() and (d / "result.json").exists())
        if not subs:
            raise RecordError(p, "is a folder without result.json and without result folders of 'flowcurve identify'")
        return [member_from_result(d) for d in subs]
    if not p.exists():
        raise RecordError(p, "no such file or folder")
    try:
        member = member_from_record(load_record(p), **identify_options)
    except FlowcurveError as exc:  # an identification's own message may not name the record
        if isinstance(exc, RecordError) or p.name in str(exc) or p.stem in str(exc):
            raise
        raise RecordError(p, str(exc)) from None
    return [member]


def _number(value) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None

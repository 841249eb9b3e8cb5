"""Tabulated flow curves for the cards: grouped by temperature, at a chosen strain rate,
from zero plastic strain to the extension strain, with at most ``max_rows`` rows.

The rules every format shares (so that three solvers see one material):

* **Temperatures** closer than ``temperature_tolerance_C`` (default 1 C, the series fit's own
  tolerance, docs/fit-json.md) are one temperature, the mean of its curves.
* **A rate without a measured curve** takes the measured curve at the nearest rate (in
  ln rate) scaled point by point by the fitted law's ratio sigma(eps, rate)/sigma(eps, rate_near)
  (for Johnson-Cook the rate factor 1 + C ln eps_dot*, clamped below eps_dot0).
* **Zero plastic strain**: a measured curve starts at about 0.002; its first point is the
  fitted model at zero plastic strain for its condition (docs/methods.md §7).
* **Beyond the last measured point** the curve continues with the fitted law's hardening at
  the curve's rate and temperature, scaled to meet that point,
  sigma(eps) = sigma_last law(eps)/law(eps_last) (for Johnson-Cook (A + B eps^n)/(A + B eps_last^n):
  the rate and temperature factors of (2.19) cancel), up to ``extend_to`` (default 2).
* **Any registered law** tabulates (identification/laws/); the rows of a law table are its
  tested rates and temperatures, and a solver holds the end curve beyond them (no softening
  or rate effect the data did not show).
"""

from __future__ import annotations

import math

import numpy as np

from flowcurve.reports.cards.data import CardData, CardOptions, FlowCurve
from flowcurve.reports.cards.fields import CardError

SAME_RATE_REL = 0.02  # the series fit's rate tolerance (docs/fit-json.md)
EXTENSION_ROWS = 10  # rows of the law beyond the last measured point
LAW_ROWS = 60  # rows of a curve tabulated from the law


def group_by_temperature(curves: list[FlowCurve], tolerance_C: float) -> list[tuple[float, list[FlowCurve]]]:
    """Curves in groups whose temperatures lie within ``tolerance_C`` of the group's first
    (coldest) member; each group at the mean temperature of its curves, coldest first."""
    groups: list[list[FlowCurve]] = []
    for curve in sorted(curves, key=lambda c: c.temperature_C):
        if groups and curve.temperature_C - groups[-1][0].temperature_C <= tolerance_C:
            groups[-1].append(curve)
        else:
            groups.append([curve])
    return [(float(np.mean([c.temperature_C for c in g])), g) for g in groups]


def distinct_rates(rates, rel: float = SAME_RATE_REL) -> list[float]:
    """Rates in increasing order, one of each within ``rel`` of each other."""
    out: list[float] = []
    for r in sorted(rates):
        if not out or not math.isclose(out[-1], r, rel_tol=rel):
            out.append(float(r))
    return out


def resample(eps, sig, max_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """A curve reduced to <= max_rows points (linear interpolation of the data), strictly
    increasing in strain; the first two points kept, the rest crowded towards small strains
    where hardening curves bend most."""
    order = np.argsort(eps, kind="stable")
    eps, sig = np.asarray(eps, float)[order], np.asarray(sig, float)[order]
    keep = np.concatenate([[True], np.diff(eps) > 0])
    eps, sig = eps[keep], sig[keep]
    if eps.size <= max_rows:
        return eps, sig
    start = 1 if eps.size > 2 else 0
    targets = eps[start] + (eps[-1] - eps[start]) * np.linspace(0.0, 1.0, max_rows - start) ** 2
    targets = np.concatenate([eps[:start], targets])
    return targets, np.interp(targets, eps, sig)


def start_at_zero(card: CardData, curve: FlowCurve) -> FlowCurve:
    """The curve beginning at zero plastic strain: the missing first point is the fitted model
    at zero for the curve's condition (fit.json's ``model_stress_at_zero_strain_MPa``, else the
    law), never above the first measured stress."""
    eps, sig = curve.plastic_strain, curve.stress_MPa
    if eps[0] <= 0.0:
        eps = eps.copy()
        eps[0] = 0.0
        return FlowCurve(curve.temperature_C, curve.strain_rate_per_s, eps, sig, curve.origin)
    s0 = curve.model_stress_at_zero_MPa
    if s0 is None:
        s0 = float(card.flow_stress_MPa(0.0, curve.strain_rate_per_s, curve.temperature_C))
    s0 = min(s0, float(sig[0]))
    return FlowCurve(curve.temperature_C, curve.strain_rate_per_s, np.concatenate([[0.0], eps]),
                     np.concatenate([[s0], sig]), curve.origin, curve.model_stress_at_zero_MPa)


def law_ratio(card: CardData, eps_p, rate_num: float, temp_num: float, eps_den, rate_den: float, temp_den: float):
    """sigma(eps_p, rate_num, T_num)/sigma(eps_den, rate_den, T_den) of the fit's law (1 where the denominator is 0)."""
    num = np.asarray(card.flow_stress_MPa(eps_p, rate_num, temp_num), float)
    den = np.asarray(card.flow_stress_MPa(eps_den, rate_den, temp_den), float)
    return np.divide(num, den, out=np.ones(np.broadcast(num, den).shape), where=den > 0)


def extension(card: CardData, eps_last: float, sig_last: float, extend_to: float, rows: int = EXTENSION_ROWS,
              strain_rate_per_s: float | None = None, temperature_C: float | None = None):
    """The law's hardening scaled through the last point: sigma_last law(eps)/law(eps_last) at the
    curve's rate and temperature (Johnson-Cook: (A + B eps^n)/(A + B eps_last^n)), on ``rows``
    points spaced evenly in ln(eps) up to ``extend_to`` (none if already there)."""
    if eps_last >= extend_to or rows < 1:
        return np.empty(0), np.empty(0)
    rate = card.ref_strain_rate_per_s if strain_rate_per_s is None else strain_rate_per_s
    temp = card.ref_temperature_C if temperature_C is None else temperature_C
    eps = np.geomspace(max(eps_last, 1e-6), extend_to, rows + 1)[1:]
    return eps, sig_last * law_ratio(card, eps, rate, temp, max(eps_last, 0.0), rate, temp)


def finished(card: CardData, curve: FlowCurve, options: CardOptions) -> FlowCurve:
    """A measured curve as a card carries it: from zero, resampled, extended by the law."""
    zero = start_at_zero(card, curve)
    ext_rows = min(EXTENSION_ROWS, max(1, options.max_rows // 4)) if zero.plastic_strain[-1] < options.extend_to else 0
    eps, sig = resample(zero.plastic_strain, zero.stress_MPa, options.max_rows - ext_rows)
    e_ext, s_ext = extension(card, float(eps[-1]), float(sig[-1]), options.extend_to, ext_rows,
                             curve.strain_rate_per_s, curve.temperature_C)
    return FlowCurve(curve.temperature_C, curve.strain_rate_per_s, np.concatenate([eps, e_ext]),
                     np.concatenate([sig, s_ext]), curve.origin)


def law_curve(card: CardData, temperature_C: float, strain_rate_per_s: float, options: CardOptions) -> FlowCurve:
    """The fitted law tabulated from zero plastic strain to ``extend_to``, points crowded
    near zero where hardening laws are steep."""
    rows = min(LAW_ROWS, options.max_rows)
    eps = options.extend_to * np.linspace(0.0, 1.0, rows) ** 2
    sig = card.flow_stress_MPa(eps, strain_rate_per_s, temperature_C)
    return FlowCurve(temperature_C, strain_rate_per_s, eps, np.asarray(sig, float), "law")


def curve_at_rate(card: CardData, group: list[FlowCurve], temperature_C: float, strain_rate_per_s: float) -> FlowCurve:
    """The measured curve of ``group`` at this rate, or the nearest one (in ln rate) scaled by
    the law's rate factor; at the group's temperature."""
    near = min(group, key=lambda c: abs(math.log(c.strain_rate_per_s / strain_rate_per_s)))
    if math.isclose(near.strain_rate_per_s, strain_rate_per_s, rel_tol=SAME_RATE_REL):
        return FlowCurve(temperature_C, near.strain_rate_per_s, near.plastic_strain, near.stress_MPa, "measured",
                         near.model_stress_at_zero_MPa)
    # the law's own rate ratio at each strain (Johnson-Cook: (1 + C ln eps_dot*)/(1 + C ln eps_dot*_near))
    scale = law_ratio(card, near.plastic_strain, strain_rate_per_s, temperature_C, near.plastic_strain, near.strain_rate_per_s,
                      temperature_C)
    zero = None if near.model_stress_at_zero_MPa is None else near.model_stress_at_zero_MPa * float(
        law_ratio(card, 0.0, strain_rate_per_s, temperature_C, 0.0, near.strain_rate_per_s, temperature_C))
    return FlowCurve(temperature_C, strain_rate_per_s, near.plastic_strain, near.stress_MPa * scale,
                     "measured, rate-scaled by the law", zero)


def origin_text(curves: list[FlowCurve], card: CardData | None = None) -> str:
    """What the tabulated curves are, for the card's comment."""
    if curves[0].origin == "law":
        return f"the {card.law.display_name if card else 'fitted'} law tabulated"
    if any("scaled" in c.origin for c in curves):
        return "identified true curves (at an untested rate: the nearest one scaled by the law's rate factor)"
    return "identified true curves"


def source_of(card: CardData, options: CardOptions) -> str:
    """'measured' or 'law' (auto: measured when the fit file has curves)."""
    source = options.curves
    if source == "auto":
        source = "measured" if card.curves else "law"
    if source == "measured" and not card.curves:
        raise CardError(f"{card.source_path}: the fit file has no tabulated curves; use the law (--curves law)")
    return source


def law_temperatures(card: CardData, options: CardOptions) -> list[float]:
    """Temperatures to tabulate the law at: those tested (grouped), else the ends of the range."""
    if card.curves:
        return [t for t, _ in group_by_temperature(card.curves, options.temperature_tolerance_C)]
    temps = sorted(set(card.temperature_range_C or ()))
    return temps or [card.ref_temperature_C]


def flow_tables(card: CardData, options: CardOptions) -> list[FlowCurve]:
    """One curve per temperature at one strain rate (the reference rate by default)."""
    rate = card.ref_strain_rate_per_s if options.strain_rate_per_s is None else options.strain_rate_per_s
    wanted = options.temperatures_C
    tol = options.temperature_tolerance_C

    def asked(temp):
        """Whether the card asked for temperature ``temp`` (all when none were asked)."""
        return wanted is None or any(abs(temp - t) <= tol for t in wanted)

    if source_of(card, options) == "law":
        temps = law_temperatures(card, options) if wanted is None else sorted(wanted)
        return [law_curve(card, t, rate, options) for t in temps]
    out = [finished(card, curve_at_rate(card, group, temp, rate), options)
           for temp, group in group_by_temperature(card.curves, tol) if asked(temp)]
    if not out:
        raise CardError(f"{card.source_path}: no tabulated curve at the temperatures asked for")
    return out


def table_rates(card: CardData, tested) -> list[float]:
    """The rates of a rate table: Johnson-Cook's reference rate eps_dot0 (where the law bends) and
    the tested rates above it; another law's tested rates; one of each within 2 %."""
    if not card.is_johnson_cook:
        return distinct_rates(list(tested) or [card.ref_strain_rate_per_s])
    above = [r for r in tested if r > card.ref_strain_rate_per_s * (1.0 + SAME_RATE_REL)]
    return distinct_rates([card.ref_strain_rate_per_s, *above])


def rate_tables(card: CardData, options: CardOptions) -> list[FlowCurve]:
    """Curves at one temperature (the reference one by default), one per rate of
    :func:`table_rates`, slowest first."""
    temp = card.ref_temperature_C if options.temperature_C is None else options.temperature_C
    if source_of(card, options) == "law":
        tested = [c.strain_rate_per_s for c in card.curves] or list(card.strain_rate_range_per_s or ())
        rates = law_grid(card, table_rates(card, tested), options, temperature_C=temp)
        return [law_curve(card, temp, r, options) for r in rates]
    groups = group_by_temperature(card.curves, options.temperature_tolerance_C)
    nearest, group = min(groups, key=lambda g: abs(g[0] - temp))
    if options.temperature_C is not None and abs(nearest - temp) > options.temperature_tolerance_C:
        raise CardError(f"{card.source_path}: no measured curves at {temp:g} C (tested: "
                        f"{', '.join(f'{t:g}' for t, _ in groups)} C); choose one of those or use the law (--curves law)")
    rates = table_rates(card, [c.strain_rate_per_s for c in group])
    return [finished(card, curve_at_rate(card, group, nearest, r), options) for r in rates]


REFINE_REL = 2e-3  # a law table's nodes are added until linear interpolation between them is this close
REFINE_MAX_NODES = 16


def refine_nodes(nodes, stress_at, log: bool = False, rel: float = REFINE_REL, max_nodes: int = REFINE_MAX_NODES) -> list[float]:
    """Nodes (rates or temperatures) between ``nodes``' ends at which a solver's linear
    interpolation (in ln x when ``log``) between neighbouring curves ``stress_at(x)`` (MPa arrays
    on one strain grid) stays within ``rel`` of the law: in passes, every interval whose midpoint
    misses by more is halved (in ln x or x), until none does or ``max_nodes`` are reached."""
    out = sorted(set(float(x) for x in nodes))
    fwd, back = (np.log, np.exp) if log else (float, float)
    while len(out) < max_nodes:
        mids = []
        for lo, hi in zip(out[:-1], out[1:]):
            mid = float(back(0.5 * (fwd(lo) + fwd(hi))))
            truth = stress_at(mid)
            miss = np.abs(0.5 * (stress_at(lo) + stress_at(hi)) - truth) / np.maximum(np.abs(truth), 1e-12)
            if np.max(miss) > rel:
                mids.append(mid)
        if not mids:
            break
        out = sorted(out + mids[: max_nodes - len(out)])
    return out


def law_grid(card: CardData, nodes, options: CardOptions, *, rate: float | None = None, temperature_C: float | None = None) -> list[float]:
    """The tested rates (``temperature_C`` given) or temperatures (``rate`` given) with nodes added
    where the fitted law bends between them (:func:`refine_nodes`); never beyond the tested ends."""
    eps = options.extend_to * np.linspace(0.0, 1.0, 25) ** 2
    if rate is None:
        return refine_nodes(nodes, lambda r: np.asarray(card.flow_stress_MPa(eps, r, temperature_C), float), log=True)
    return refine_nodes(nodes, lambda t: np.asarray(card.flow_stress_MPa(eps, rate, t), float))

"""The flow-stress table forming codes import: a plain CSV
``eps_p,strain_rate_per_s,temperature_C,stress_MPa`` on every tested temperature × every tested
rate (so every measured condition is a row block) and a stated plastic-strain grid, with ``#``
header lines naming the law, its constants by their fit.json keys, the temperature unit, the
range identified on and the interpolation/extrapolation rule. Lab units whatever ``--units``.

From the fitted law (``--curves law``) or the measured curves (measured; at a tested
temperature's untested rate the nearest curve scaled by the law's rate ratio, beyond the last
measured strain the law scaled through that point — the rules of :mod:`.tables`).
"""

from __future__ import annotations

import numpy as np

from flowcurve import __version__
from flowcurve.identification.provenance import comment_lines
from flowcurve.reports.cards.data import CardData, CardOptions
from flowcurve.reports.cards.fields import comment_block
from flowcurve.reports.cards.tables import curve_at_rate, distinct_rates, group_by_temperature, law_ratio, source_of, start_at_zero
from flowcurve.reports.units import UnitSystem

COLUMNS = ("eps_p", "strain_rate_per_s", "temperature_C", "stress_MPa")
SMALL_STRAINS = (0.0, 0.002, 0.005, 0.01, 0.02, 0.03, 0.05, 0.075)  # dense where hardening bends
STRAIN_STEP = 0.05  # from 0.1 to --extend-to


def strain_grid(extend_to: float) -> np.ndarray:
    """The stated plastic-strain grid: :data:`SMALL_STRAINS`, then every 0.05 from 0.1 to ``extend_to``."""
    big = np.arange(0.1, extend_to + 1e-9, STRAIN_STEP)
    return np.unique(np.concatenate([[e for e in SMALL_STRAINS if e <= extend_to], big, [extend_to]]))


def conditions(card: CardData, options: CardOptions) -> list[tuple[float, float]]:
    """(temperature C, rate 1/s): every tested temperature with every tested rate (the range's
    ends when the fit file has no curves)."""
    if card.curves:
        temps = [t for t, _ in group_by_temperature(card.curves, options.temperature_tolerance_C)]
        rates = distinct_rates(c.strain_rate_per_s for c in card.curves)
    else:
        temps = sorted(set(card.temperature_range_C or (card.ref_temperature_C,)))
        rates = sorted(set(card.strain_rate_range_per_s or (card.ref_strain_rate_per_s,)))
    return [(t, r) for t in temps for r in rates]


def measured_stress(card: CardData, group, temperature_C: float, rate: float, eps: np.ndarray) -> np.ndarray:
    """A measured curve (from zero plastic strain) on the grid: linear within its points, the law
    scaled through its last point beyond them."""
    curve = start_at_zero(card, curve_at_rate(card, group, temperature_C, rate))
    e, s = curve.plastic_strain, curve.stress_MPa
    beyond = s[-1] * law_ratio(card, eps, rate, temperature_C, e[-1], rate, temperature_C)
    return np.where(eps <= e[-1], np.interp(eps, e, s), beyond)


def header(card: CardData, options: CardOptions, source: str, eps: np.ndarray) -> list[str]:
    """The ``#`` lines: law, constants by key, units, range, grid and rules."""
    law = card.law
    values = card.values()
    lines = [
        f"flowcurve {__version__} flow-stress table: {card.material}",
        f"fit file: {card.source_path}; identification method: {card.method}",
        *comment_lines(card.provenance, "fit file"),
        f"law: {law.name} ({law.display_name}): {law.equation}",
        *[f"constant {p.key} = {values[p.name]:.8g}" + (f" {p.unit}" if p.unit else "")
          + (f" +/- {card.stderr[p.key]:.3g}" if isinstance(card.stderr.get(p.key), (int, float)) else "")
          for p in law.parameters if p.name in values],
        *[f"condition {p.key} = {values[p.name]:.8g} (stated, not fitted)" for p in law.conditions if p.name in values],
        "temperature unit: C, in the table and in the law's constants (the law converts to K inside where its "
        "equation is written in K; a code that writes this law in K takes T_K = T_C + 273.15)",
        "units: plastic strain (true), strain rate 1/s, temperature C, stress MPa (true), whatever --units says",
        "identified on: " + "; ".join(card.valid_range_text()),
        "stress from: " + ("the fitted law" if source == "law" else "the measured true curves (an untested rate at a "
                           "tested temperature: the nearest curve scaled by the law's rate ratio)"),
        "grid: every tested temperature x every tested rate; plastic strain " + ", ".join(f"{e:g}" for e in eps[:len(SMALL_STRAINS)])
        + f", then every {STRAIN_STEP:g} to {options.extend_to:g}",
        "rule: interpolate linearly in strain, in ln(strain rate) and in temperature between rows; beyond the last measured "
        f"strain the rows carry the fitted law scaled through that point (to {options.extend_to:g}); beyond the tested "
        "rates and temperatures hold the end rows (clamp): never below the slowest-rate curve, no softening the data "
        "did not show",
        "WARNING: valid only on the range above; extrapolation beyond it is the user's risk.",
    ]
    return lines


def flow_table_card(data: CardData, units: UnitSystem, options: CardOptions) -> str:
    """The CSV text (``units`` is not used: the table is in lab units, and says so)."""
    source = source_of(data, options)
    eps = strain_grid(options.extend_to)
    groups = group_by_temperature(data.curves, options.temperature_tolerance_C) if data.curves else []
    rows = []
    for temp, rate in conditions(data, options):
        if source == "law":
            sig = np.asarray(data.flow_stress_MPa(eps, rate, temp), float)
        else:
            group = next(g for t, g in groups if t == temp)
            sig = measured_stress(data, group, temp, rate, eps)
        rows += [f"{e:.8g},{rate:.8g},{temp:.8g},{s:.8g}" for e, s in zip(eps, sig)]
    return comment_block(header(data, options, source, eps), "# ") + ",".join(COLUMNS) + "\n" + "\n".join(rows) + "\n"

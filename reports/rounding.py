"""Rounding of reported results (ISO 6892-1:2019 §22) and of their expanded uncertainties.

ISO 6892-1 §22, unless a product standard says otherwise: strength values to the nearest
1 MPa; the yield point extension Ae to 0.1 %; every other percentage extension and elongation
(Ag, Agt, A, At) to 0.5 %; the reduction of area Z to 1 %. Rounding is to the nearest multiple,
a tie to the even multiple (ISO 80000-1 Annex B, rule A). Quantities §22 does not name are
given to the steps of :data:`STEPS` (a lab convention, stated in the report). An expanded
uncertainty is given with two significant digits, rounded up (GUM 7.2.6: never understate it).
A value with a U is given to its §22 step or finer ("or better"): never coarser than U's last
digit, so value ± U always holds the unrounded value.
"""

from __future__ import annotations

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, ROUND_HALF_EVEN, Decimal

# result key → rounding step, in the unit the report shows
STEPS = {
    "Rp02_MPa": 1.0, "Rm_MPa": 1.0, "ReH_MPa": 1.0, "ReL_MPa": 1.0, "flow_stress_MPa": 1.0,  # §22: strength, 1 MPa
    "Ae_pct": 0.1,  # §22: yield point extension, 0.1 %
    "Ag_pct": 0.5, "Agt_pct": 0.5, "A_pct": 0.5,  # §22: other extensions and elongations, 0.5 %
    "Z_pct": 1.0,  # §22: reduction of area, 1 %
    # not in §22 (lab convention)
    "E_GPa": 0.1, "friction_mu": 0.001, "fracture_true_strain": 0.01, "fracture_true_stress_MPa": 1.0,
    "A_MPa": 1.0, "B_MPa": 1.0, "K_MPa": 1.0, "sigma0_MPa": 1.0, "Q_MPa": 1.0, "n": 0.001, "eps0": 0.0001, "b": 0.01,
    "C": 0.0001, "m": 0.01, "error_pct": 0.1, "strain_rate_per_s": None, "temperature_C": 1.0,
}
ISO_6892_1_RULES = (("strength values (Rp0.2, Rm, ReH, ReL)", "1 MPa"), ("yield point extension Ae", "0.1 %"),
                    ("other extensions and elongations (Ag, Agt, A)", "0.5 %"), ("reduction of area Z", "1 %"))


def _decimals(step: float) -> int:
    return max(0, -Decimal(repr(step)).normalize().as_tuple().exponent)


def round_step(value: float, step: float) -> float:
    """``value`` to the nearest multiple of ``step``; a tie goes to the even multiple (ISO 80000-1 B, rule A)."""
    q = (Decimal(repr(float(value))) / Decimal(repr(step))).quantize(Decimal(1), rounding=ROUND_HALF_EVEN)
    return float(q * Decimal(repr(step)))


def format_step(value, step: float | None) -> str:
    """The rounded value as text with the step's decimals (``format_step(14.60, 0.5)`` → ``'14.5'``)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    if step is None:
        return f"{value:.3g}"
    return f"{round_step(value, step):.{_decimals(step)}f}"


def format_uncertainty(U) -> str:
    """U with two significant digits, rounded up (``0.2385`` → ``'0.24'``, ``13.34`` → ``'14'``)."""
    if U is None or not math.isfinite(U) or U < 0:
        return "–"
    if U == 0:
        return "0"
    exponent = math.floor(math.log10(U)) - 1  # the second significant digit's place
    step = Decimal(1).scaleb(exponent)
    rounded = (Decimal(repr(float(U))) / step).to_integral_value(rounding=ROUND_CEILING) * step
    return f"{rounded:.{max(0, -exponent)}f}"


def uncertainty_step(U) -> float | None:
    """The place of U's second significant digit (``0.1853`` → ``0.01``), None when U is unknown or 0."""
    if U is None or not math.isfinite(U) or U <= 0:
        return None
    return float(Decimal(1).scaleb(math.floor(math.log10(U)) - 1))


def value_step(step: float | None, U) -> float | None:
    """The step a value is printed to: its §22 step, or U's last digit where that is finer."""
    finer = uncertainty_step(U)
    if finer is None:
        return step
    return finer if step is None else min(step, finer)


def value_with_U(value, U, step: float | None) -> str:
    """``'1132 ± 14'``, ``'55.42 ± 0.19'``: the value at :func:`value_step` and U beside it (``'1132'`` when U is unknown)."""
    text = format_step(value, value_step(step, U))
    return f"{text} ± {format_uncertainty(U)}" if U is not None and text != "–" else text


def format_range(low, high, step: float | None) -> str:
    """An asymmetric interval as a range, ``'0.076–0.092'``, outward to ``step`` so it never narrows."""
    if low is None or high is None:
        return "–"
    if step is None:
        return f"{low:.3g}–{high:.3g}"
    lo = float((Decimal(repr(float(low))) / Decimal(repr(step))).to_integral_value(rounding=ROUND_FLOOR) * Decimal(repr(step)))
    hi = float((Decimal(repr(float(high))) / Decimal(repr(step))).to_integral_value(rounding=ROUND_CEILING) * Decimal(repr(step)))
    return f"{lo:.{_decimals(step)}f}–{hi:.{_decimals(step)}f}"

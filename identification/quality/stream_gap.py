"""A load-cell stream gap the acquisition could not tell lost frames or latency of: what it leaves in the budgets.

The acquisition names such a gap (``stream_gap_undecided``, ``stream_gap_in_doubt``: "after T s … up to δ s
late") and stamps it as lost frames. Had it been the line's latency growing, every force after T was sent δ
earlier than its stamp: F_true(t) = F_rec(t + δ), and the force at a given crosshead position is off by
F(t) − F(t + δ). The result is identified again on that reading (:func:`realigned`), and the difference of each
quantity that pairs the force with the crosshead after the gap — Rp0.2, Ag (the strain at Fm moves by the
crosshead's travel over δ), each flow-curve point, each hardening constant — enters its budget as a component.
Fm/Rm are maxima of the force values, not of their stamps: no term.

The error is one of two values, 0 (a loss, as stamped) or Δ (a latency), with no evidence for either (the rule
could not decide): not spread between them, so not rectangular (|Δ|/√3 would leave U = 1.15·|Δ| to cover Δ and the
realignment's own error: forces linear between 2 Hz frames). It is stated as its size, u = |Δ| (an uncorrected
systematic effect, as the filter lag's): U ≥ 2·|Δ|. A quantity the realigned record does not state is refused.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping

import numpy as np

from flowcurve.identification.quality import filter_lag

EVENTS = ("stream_gap_undecided", "stream_gap_in_doubt")
GAP = re.compile(r"gap in its stream after (-?[\d.]+) s.*?up to ([\d.]+) s late")  # the gap's test time and doubt
COMPONENT = "load-cell stream gap (latency or loss undecided)"
BASIS = ("the record names a gap it stamped as lost frames that may have been the line's latency (every later force sent "
         "δ before its stamp): identified again with F(t) = F_rec(t + δ) after the gap; the error is 0 or Δ, u = |Δ| (uncorrected)")
WIDENED_VALUES = ("Rp02_MPa", "Ag_pct")  # single budgets the pairing moves (not Rm: a maximum of the force values)
WIDENED_BLOCKS = ("hardening", "flow_stress_MPa")


def gaps(record, names: tuple[str, ...] = EVENTS) -> list[tuple[float, float]]:
    """(T, δ) in the record's seconds of each stream gap it names in events ``names`` (undecided or in doubt), in time order."""
    found = (GAP.search(" ".join(str(e.text).split())) for e in record.events if e.name in names)
    return sorted((float(m.group(1)), float(m.group(2))) for m in found if m)


def realigned_force(time_s, force_N, found: list[tuple[float, float]]) -> np.ndarray:
    """The force had every gap in ``found`` been latency: F(t) = F_rec(t + s(t)), s(t) = Σ δ_j over the gaps
    before t, F_rec linear between the record's rows (held at its last row: the frames the line had not delivered)."""
    t, f = np.asarray(time_s, dtype=float), np.asarray(force_N, dtype=float)
    out = f.copy()
    ok = np.isfinite(t) & np.isfinite(f)
    if ok.sum() < 2 or not found:
        return out
    shift = sum(np.where(t > after, doubt, 0.0) for after, doubt in found)  # s(t) = Σ δ_j·[t > T_j]
    moved = ok & (shift > 0)
    out[moved] = np.interp(t[moved] + shift[moved], t[ok], f[ok])  # F_rec(t + s(t))
    return out


def realigned(record, found: list[tuple[float, float]]):
    """A copy of ``record`` with its force :func:`realigned_force` (its events kept: they name the faults)."""
    data = record.data.copy()
    data["force_N"] = realigned_force(data["time_s"].to_numpy(dtype=float), data["force_N"].to_numpy(dtype=float), found)
    return dataclasses.replace(record, data=data)


def widen(uncertainty: Mapping, alternative: Mapping) -> list[str]:
    """:data:`COMPONENT` added to each budget of ``uncertainty`` the pairing moves, u = |Δ| against ``alternative``
    (the realigned record's budgets); returns the keys ("block key" in a flow-curve block) ``alternative`` lacks."""
    return filter_lag.widen(uncertainty, alternative, component=COMPONENT, basis=BASIS, values=WIDENED_VALUES, blocks=WIDENED_BLOCKS)


def refuse(uncertainty: dict, missing: list[str], why: str) -> None:
    """Each budget named in ``missing`` (as :func:`widen` names them) stated not certifiable, ``why``; one that is
    already not certifiable is left as it says."""
    from flowcurve.identification.quality.assurance import not_certifiable

    for name in missing:
        if name in WIDENED_VALUES:
            holder, key = uncertainty, name
        elif name.startswith("flow_stress_MPa "):
            holder, key = uncertainty.get("flow_stress_MPa"), name.split(" ", 1)[1]
        else:
            holder, key = uncertainty.get("hardening"), name
        b = holder.get(key) if isinstance(holder, dict) else None
        if isinstance(b, dict) and "components" in b and b.get("certifiable") is not False:
            holder[key] = not_certifiable(b, why)


ROW_COLUMN = "stream_gap_u_MPa"  # true_curve.csv: each row's share of the gap's doubt, MPa
ROWS_BASIS = ("u = |σ_alt(x) − σ(x)|, σ_alt the curve of the record identified again as if the gap had been latency "
              "(every later force sent δ before its stamp, every choice pinned), interpolated at the row's own "
              "true_plastic_strain x; the row's error is 0 (a loss, as stamped) or that difference (a latency), "
              "uncorrected: σ ± 2·u holds either reading")


def row_doubt(strain, stress_MPa, alt_strain, alt_stress_MPa) -> np.ndarray:
    """Each curve row's share of the gap's doubt, MPa: u = |σ_alt(x) − σ(x)| at the row's strain x, σ_alt linear
    between the alternative curve's rows (sorted by strain); NaN where x lies outside them (not reached)."""
    x, s = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    ax, asig = np.asarray(alt_strain, dtype=float), np.asarray(alt_stress_MPa, dtype=float)
    ok = np.isfinite(ax) & np.isfinite(asig)
    ax, asig = ax[ok], asig[ok]
    if ax.size < 2:
        return np.full(x.shape, np.nan)
    order = np.argsort(ax, kind="stable")
    ax, asig = ax[order], asig[order]
    alt = np.interp(x, ax, asig)  # σ_alt(x)
    return np.where((x >= ax[0]) & (x <= ax[-1]), np.abs(alt - s), np.nan)  # u = |Δ|, NaN outside the alternative


def rows_note(strain, u_MPa, why_missing: str | None = None) -> dict:
    """result.json methods' word on :data:`ROW_COLUMN`: what it holds, the strain from which the rows carry a
    doubt (the first row with u > 0; the rows before it agree in both readings), its largest value, and the rows
    without one (NaN) and why."""
    x, u = np.asarray(strain, dtype=float), np.asarray(u_MPa, dtype=float)
    carried = np.isfinite(u) & (u > 0)
    unread = ~np.isfinite(u)
    note = {"column": ROW_COLUMN, "holds": ROWS_BASIS,
            "from_plastic_strain": float(x[carried][0]) if carried.any() else None,
            "max_u_MPa": float(np.max(u[carried])) if carried.any() else 0.0,
            "rows_without_u": int(unread.sum())}
    if unread.any():
        note["why_without_u"] = why_missing or ("the curve of the record read as latency does not reach these rows' strain "
                                                f"({float(np.min(x[unread])):.4g}–{float(np.max(x[unread])):.4g}): their doubt is unknown, not 0")
    return note

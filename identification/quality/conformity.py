"""Did the test meet the standard's testing conditions? ISO 6892-1/-2 rates, temperatures.

Testing rate, measured per phase from the record itself (docs/methods.md §3.3c): the elastic
line, the yield phase (to Rp, or ReH to the end of the yield point extension) and the plastic
range to Rm. The strain rate is the estimate over the parallel length ė_Lc = v_c/L_c from the
crosshead (v_c: the least-squares slope of the crosshead over time in the phase), or ė_Le from
the extensometer on a record without a crosshead; the elastic stress rate is the slope of σ(t).
Each rate carries its u (:func:`slope_u`: residual scatter, reading quantum, stamp jitter; at least the
spread over windows of its crosshead command, :func:`window_scatter_u`) and is judged by a guard band
w = U (k = 2, :func:`band_verdict`): conforms, does not conform, or "not resolved"; a phase whose U
exceeds 20 % is measured over a wider window of the same command when the record states its speed.

ISO 6892-1:2019 §10.3 method A: ranges 1 0.00007, 2 0.00025, 3 0.002, 4 0.0067 s⁻¹, each
±20 %: Rp/ReH (the elastic and yield phases) in 1 or 2, ReL/Ae in 2 or 3, Rm/Ag/A/Z in 2, 3
or 4; designation ``A`` + the three phases' ranges. §10.4 method B: elastic stress rate by E
(Table 4: 2–20 MPa/s below 150 GPa, 6–60 MPa/s from it), for Rp a strain rate ≤ 0.0025 s⁻¹ up
to Rp, for ReL 0.00025–0.0025 s⁻¹ during yield, ≤ 0.008 s⁻¹ for Rm.
ISO 6892-2:2018 (heated, above 35 °C) §10.3 method A: ranges 1 0.00007, 2 0.00025 (Rp/ReH),
2 or 3 0.0014 s⁻¹ (ReL/Ae, Rm), ±20 %; §10.4 method B: 0.0000167–0.0000833 s⁻¹ from the
start to the yield strength, 0.00033–0.0033 s⁻¹ for Rm.

Temperature: ISO 6892-1 tests at 10–35 °C; ISO 6892-2 allows the indicated temperature to
deviate from T by ±3 °C up to 600 °C, ±4 °C up to 800 °C and ±5 °C up to 1000 °C. A record
that states no temperature, or "RT" (a word, not a temperature), is "not stated".
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from flowcurve.identification.iso6892 import first_index, nan_argmax

STANDARD_TENSION = "ISO 6892-1:2019"
STANDARD_HEATED = "ISO 6892-2:2018"
RANGE_TOLERANCE = 0.20  # ±20 % about each method A range
# per standard: method A ranges (s⁻¹); the ranges allowed per result; method B limits
RULES = {
    STANDARD_TENSION: {
        "ranges": {1: 0.00007, 2: 0.00025, 3: 0.002, 4: 0.0067},
        "allowed": {"Rp/ReH": (1, 2), "ReL/Ae": (2, 3), "Rm/Ag/A/Z": (2, 3, 4)},
    },
    STANDARD_HEATED: {
        "ranges": {1: 0.00007, 2: 0.00025, 3: 0.0014},
        "allowed": {"Rp/ReH": (1, 2), "ReL/Ae": (2, 3), "Rm/Ag/A/Z": (2, 3)},
    },
}
RANGES_PER_S = RULES[STANDARD_TENSION]["ranges"]
B_STRESS_RATE_MPa_PER_S = {"E < 150 GPa": (2.0, 20.0), "E ≥ 150 GPa": (6.0, 60.0)}  # ISO 6892-1 method B, Table 4
B_RP_MAX_RATE_PER_S = 0.0025  # ISO 6892-1 method B: plastic range up to Rp
B_REL_RATE_PER_S = (0.00025, 0.0025)  # ISO 6892-1 method B: during yield, for ReL
B_RM_MAX_RATE_PER_S = 0.008  # ISO 6892-1 method B: for Rm
B2_YIELD_RATE_PER_S = (0.0000167, 0.0000833)  # ISO 6892-2 method B: from the start to the yield strength
B2_RM_RATE_PER_S = (0.00033, 0.0033)  # ISO 6892-2 method B: for Rm
ROOM_RANGE_C = (10.0, 35.0)  # ISO 6892-1 §10.1
HEATED_TOLERANCE_C = ((600.0, 3.0), (800.0, 4.0), (1000.0, 5.0))  # ISO 6892-2: up to T, ± tolerance
PHASE_NAMES = ("elastic", "yield", "to_Rm")
MIN_PHASE_SAMPLES = 3
K_RATE = 2.0  # coverage factor of a rate's U
COVERAGE_P = 0.95  # the coverage probability U stands for
UNRESOLVED_U_REL = RANGE_TOLERANCE  # a phase's rate whose U exceeds ±20 % of it cannot be judged against a ±20 % band
WIDE_TARGET_U_REL = 0.05  # a wider window grows until its U is this small (a quarter of the band)
CONFORMS, FAILS, UNRESOLVED, UNMEASURED = "conforms", "does not conform", "not resolved", "not measured"


def method_a_range(strain_rate_per_s: float | None, standard: str = STANDARD_TENSION) -> int | None:
    """The method A range whose ±20 % band holds this strain rate, or None."""
    if strain_rate_per_s is None:
        return None
    for number, centre in RULES[standard]["ranges"].items():
        if abs(strain_rate_per_s - centre) <= RANGE_TOLERANCE * centre:
            return number
    return None


def _results_of(phase: str, yield_point: bool) -> str:
    """The results a phase's rate governs: the elastic phase and (without a yield point) the yield phase Rp/ReH."""
    if phase == "to_Rm":
        return "Rm/Ag/A/Z"
    return "ReL/Ae" if phase == "yield" and yield_point else "Rp/ReH"


def band_verdict(value: float, U: float, lo: float | None, hi: float | None) -> str:
    """Guard-band decision (ILAC-G8, ISO 14253-1; w = U): CONFORMS when value ± U lies inside [lo, hi],
    FAILS when it lies wholly outside, UNRESOLVED when it straddles an edge (None: no limit on that side)."""
    inside = (lo is None or value - U >= lo) and (hi is None or value + U <= hi)
    outside = (lo is not None and value + U < lo) or (hi is not None and value - U > hi)
    return CONFORMS if inside else (FAILS if outside else UNRESOLVED)


def _a_verdict(rate: float | None, U: float, allowed: Sequence[int], standard: str) -> str:
    """Method A for one phase: CONFORMS when rate ± U lies in one allowed range's ±20 % band, FAILS when it meets none."""
    if rate is None:
        return UNMEASURED
    centres = RULES[standard]["ranges"]
    verdicts = [band_verdict(rate, U, (1 - RANGE_TOLERANCE) * centres[r], (1 + RANGE_TOLERANCE) * centres[r]) for r in allowed]
    return CONFORMS if CONFORMS in verdicts else (UNRESOLVED if UNRESOLVED in verdicts else FAILS)


def _combine(verdicts: Sequence[str]) -> str:
    """All limits of a method: one failed → FAILS; one not measured → UNMEASURED; one straddling → UNRESOLVED."""
    for v in (FAILS, UNMEASURED, UNRESOLVED):
        if v in verdicts:
            return v
    return CONFORMS


def _fmt(rate: float | None, U: float | None = None, unit: str = "s⁻¹") -> str:
    if rate is None:
        return "not measured"
    if not U:
        return f"{rate:.3g} {unit}"
    return f"{rate:.3g} ± {U:.2g} {unit} (U, k = 2: {100 * U / abs(rate):.0f} %)" if rate else f"{rate:.3g} ± {U:.2g} {unit}"


def _U(phase: Mapping | None, key: str = "strain_rate_u_per_s") -> float:
    u = (phase or {}).get(key)
    return K_RATE * u if u is not None and math.isfinite(u) else 0.0


def testing_rate(phases: Mapping[str, Mapping], *, E_MPa: float | None, yield_point: bool = False, heated: bool = False) -> dict:
    """Conformity of the measured rates with method A, else method B, of ISO 6892-1 (or ISO 6892-2 when ``heated``),
    each phase's rate ± U (k = 2, ``strain_rate_u_per_s``) against the band (:func:`band_verdict`): ``conforms`` True
    (method A or B holds), False (rate ± U outside in both), None: "not resolved" (a rate ± U straddles a band's edge)
    or "not stated" (a rate the verdict needs was not measured)."""
    standard = STANDARD_HEATED if heated else STANDARD_TENSION
    rates = {p: (phases.get(p) or {}).get("strain_rate_per_s") for p in PHASE_NAMES}
    Us = {p: _U(phases.get(p)) for p in PHASE_NAMES}
    ranges = {p: method_a_range(rates[p], standard) for p in PHASE_NAMES}
    a = {p: _a_verdict(rates[p], Us[p], RULES[standard]["allowed"][_results_of(p, yield_point)], standard) for p in PHASE_NAMES}
    findings = [f"{p}: ė {_fmt(rates[p], Us[p])}" + (f" (method A range {ranges[p]}: {a[p]})" if ranges[p] else "")
                + (f" — {(phases.get(p) or {}).get('window_note')}" if (phases.get(p) or {}).get("window_note") else "") for p in PHASE_NAMES]
    elastic = phases.get("elastic") or {}
    out: dict = {"standard": standard, "decision_rule": "guard band w = U (k = 2) of each measured rate",
                 "phases": {p: dict(phases.get(p) or {}, method_a_range=ranges[p], method_a_verdict=a[p]) for p in PHASE_NAMES},
                 "strain_rate_per_s": rates["yield"], "method_a_range": ranges["yield"],
                 "stress_rate_MPa_per_s": elastic.get("stress_rate_MPa_per_s"),
                 "stress_rate_u_MPa_per_s": elastic.get("stress_rate_u_MPa_per_s")}
    a_all = _combine(list(a.values()))
    if a_all == CONFORMS:
        first = ranges["yield"] if not yield_point else ranges["elastic"]
        out.update(method="A", conforms=True, designation=f"{standard} A{first}{ranges['yield']}{ranges['to_Rm']}")
        findings.append("method A: every phase's rate ± U in an allowed range (±20 %)")
        out["findings"] = findings
        return out
    bad, open_ = [p for p in PHASE_NAMES if a[p] == FAILS], [p for p in PHASE_NAMES if a[p] == UNRESOLVED]
    findings.append("method A: " + "; ".join(([f"not met in {', '.join(bad)}"] if bad else [])
                                            + ([f"not resolved in {', '.join(open_)} (rate ± U straddles a band's edge)"] if open_ else [])
                                            + (["not every phase measured"] if UNMEASURED in a.values() else [])))
    b_all, b_why = (_method_b_heated(rates, Us) if heated else
                    _method_b(rates, Us, out["stress_rate_MPa_per_s"], _U(elastic, "stress_rate_u_MPa_per_s"), E_MPa, yield_point))
    findings.extend(b_why)
    if b_all == CONFORMS:
        tag = "B" if heated or out["stress_rate_MPa_per_s"] is None else f"B{out['stress_rate_MPa_per_s']:.0f}"
        out.update(method="B", conforms=True, designation=f"{standard} {tag}")
    elif a_all == FAILS and b_all == FAILS:
        out.update(method=None, conforms=False, designation=f"{standard} (testing rate not conforming)")
    elif UNRESOLVED in (a_all, b_all):  # rate ± U straddles a band's edge: neither verdict can be given, never a guess
        out.update(method=None, conforms=None, designation=f"{standard} (testing rate not resolved)")
        findings.append("testing rate not resolved: a rate ± U straddles its band's edge")
    else:  # neither method can be judged on what was measured: not stated, never a guess
        out.update(method=None, conforms=None, designation=f"{standard} (testing rate not stated)")
    out["findings"] = findings
    return out


def _limit(ok: list, why: list, name: str, value: float | None, U: float, lo: float | None, hi: float | None, unit: str, what: str) -> None:
    """One method B limit: appends its verdict (:func:`band_verdict`, or UNMEASURED) and the finding."""
    if value is None:
        ok.append(UNMEASURED)
        why.append(f"method B: {name} not measured ({what})")
        return
    verdict = band_verdict(value, U, lo, hi)
    ok.append(verdict)
    band = f"{lo:g}–{hi:g}" if lo is not None and hi is not None else (f"≤ {hi:g}" if hi is not None else f"≥ {lo:g}")
    where = {CONFORMS: "within", FAILS: "outside", UNRESOLVED: "straddles the edge of"}[verdict]
    why.append(f"method B: {name} {_fmt(value, U, unit)} {where} {band} {unit} ({what})")


def _method_b(rates: Mapping, Us: Mapping, stress_rate: float | None, stress_U: float, E_MPa: float | None,
              yield_point: bool) -> tuple[str, list[str]]:
    """ISO 6892-1 method B (§10.4): elastic stress rate by E class, the yield phase's strain rate, ≤ 0.008 s⁻¹ to Rm."""
    ok: list = []
    why: list[str] = []
    if E_MPa is None:
        ok.append(UNMEASURED)
        why.append("method B: no E, so no stress-rate class")
    else:
        band = "E < 150 GPa" if E_MPa < 150_000.0 else "E ≥ 150 GPa"
        _limit(ok, why, "elastic stress rate", stress_rate, stress_U, *B_STRESS_RATE_MPa_PER_S[band], "MPa/s", f"Table 4, {band}")
    if yield_point:
        _limit(ok, why, "strain rate during yield", rates["yield"], Us["yield"], *B_REL_RATE_PER_S, "s⁻¹", "ReL")
    else:
        _limit(ok, why, "strain rate up to Rp", rates["yield"], Us["yield"], None, B_RP_MAX_RATE_PER_S, "s⁻¹", "Rp")
    _limit(ok, why, "strain rate to Rm", rates["to_Rm"], Us["to_Rm"], None, B_RM_MAX_RATE_PER_S, "s⁻¹", "Rm")
    return _combine(ok), why


def _method_b_heated(rates: Mapping, Us: Mapping) -> tuple[str, list[str]]:
    """ISO 6892-2 method B (§10.4): the strain rate from the start to the yield strength and for Rm."""
    ok: list = []
    why: list[str] = []
    for phase in ("elastic", "yield"):
        _limit(ok, why, f"strain rate ({phase})", rates[phase], Us[phase], *B2_YIELD_RATE_PER_S, "s⁻¹", "ISO 6892-2, to the yield strength")
    _limit(ok, why, "strain rate to Rm", rates["to_Rm"], Us["to_Rm"], *B2_RM_RATE_PER_S, "s⁻¹", "ISO 6892-2, Rm")
    return _combine(ok), why


def heated_tolerance_C(temperature_C: float) -> float | None:
    """ISO 6892-2's permitted deviation of the indicated temperature at this T (None above 1000 °C)."""
    for upto, tol in HEATED_TOLERANCE_C:
        if temperature_C <= upto:
            return tol
    return None


def temperature(nominal_C: float | None, measured_C: Sequence[float] | None, *, as_written: str | None = None) -> dict:
    """Conformity of the test temperature: room (ISO 6892-1, 10–35 °C) or heated (ISO 6892-2
    tolerance); "not stated" (conforms None) when the record gives no number for it (``as_written``:
    the header's own word, e.g. "RT", which the reader stood in for with a number)."""
    meas = np.asarray(measured_C if measured_C is not None else [], dtype=float)
    meas = meas[np.isfinite(meas)]
    if as_written is not None and not _is_number(as_written):
        return {"conforms": None, "nominal_C": None, "stated_as": as_written,
                "findings": [f"test temperature not stated (the record says {as_written!r}, not a temperature)"]}
    if nominal_C is None:
        return {"conforms": None, "nominal_C": None, "findings": ["test temperature not stated in the record"]}
    if nominal_C <= ROOM_RANGE_C[1]:
        lo, hi = ROOM_RANGE_C
        values = meas if meas.size else np.array([nominal_C])
        ok = bool(lo <= values.min() and values.max() <= hi)
        source = f"measured {values.min():.1f}–{values.max():.1f} °C" if meas.size else f"nominal {nominal_C:g} °C (not measured)"
        return {"standard": STANDARD_TENSION, "nominal_C": nominal_C, "range_C": [lo, hi], "conforms": ok,
                "findings": [f"room temperature: {source}, {'within' if ok else 'outside'} {lo:g}–{hi:g} °C"]}
    tol = heated_tolerance_C(nominal_C)
    out = {"standard": STANDARD_HEATED, "nominal_C": nominal_C, "tolerance_C": tol}
    if tol is None:
        out.update(conforms=None, findings=[f"{nominal_C:g} °C: above ISO 6892-2's table (≤ 1000 °C); tolerance by agreement"])
    elif not meas.size:
        out.update(conforms=None, findings=["no temperature measured during the test: conformity cannot be stated"])
    else:
        dev = float(np.max(np.abs(meas - nominal_C)))
        ok = dev <= tol
        out.update(conforms=ok, max_deviation_C=dev,
                   findings=[f"indicated temperature within {dev:.1f} °C of {nominal_C:g} °C ({'within' if ok else 'outside'} ±{tol:g} °C); "
                             "gradient along the gauge length not measured (one thermocouple)"])
    return out


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(str(text).strip()))
    except ValueError:
        return False


def _elastic_stretch(stress_MPa: np.ndarray, window_MPa: Sequence[float], i_m: int) -> np.ndarray:
    """Indices of the first contiguous stretch before the maximum whose stress lies in the window."""
    lo, hi = window_MPa
    first = first_index(lambda at: (stress_MPa[at] >= lo) & (stress_MPa[at] <= hi), 0, i_m + 1)
    if first is None:
        return np.zeros(0, dtype=np.intp)
    after = first_index(lambda at: ~((stress_MPa[at] >= lo) & (stress_MPa[at] <= hi)), first, i_m + 1)  # the stretch's end: read no further
    return np.arange(first, i_m + 1 if after is None else after)


def _slope(t: np.ndarray, y: np.ndarray) -> float | None:
    """Least-squares slope dy/dt over finite samples; None with fewer than 3 or no time span."""
    fit = slope_u(t, y)
    return fit[0] if fit else None


def slope_u(t, y, *, quantum: float = 0.0, time_u_s: float = 0.0) -> tuple[float, float] | None:
    """Least-squares slope b = dy/dt of finite samples and its standard uncertainty u(b) (k = 1); None with
    fewer than 3 samples or no time span. u(b) = max(u_res, u_read): u_res = s/√Sxx, s² = Σr²/(n − 2) (the
    residual scatter); u_read = max(σ_r/√Sxx, q²/(√6·|b|·T²)), σ_r² = q²/12 + (b·u_t)² (each reading's quantum
    q and stamp jitter u_t), the second term the sawtooth of a ramp quantised to q over T that the residuals
    do not show when it crosses few quanta (Monte Carlo of quantised ramps: tests/uncertainty/test_conformity_rate_u.py)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    if not ok.all():
        t, y = t[ok], y[ok]
    if t.size < MIN_PHASE_SAMPLES or np.ptp(t) <= 0:
        return None
    dt = t - t.mean()
    dy = y - y.mean()
    sxx = np.einsum("i,i->", dt, dt)  # einsum, not np.dot: BLAS threads on a busy machine cost 50× a plain loop
    b = float(np.einsum("i,i->", dt, dy) / sxx)  # least squares: Σ(t − t̄)(y − ȳ) / Σ(t − t̄)²
    r = dy - b * dt
    u_res = math.sqrt(np.einsum("i,i->", r, r) / (t.size - 2) / sxx)
    u_read = math.sqrt((quantum ** 2 / 12.0 + (b * time_u_s) ** 2) / sxx)
    if quantum > 0:  # q²/(√6·|b|·T²): q/(√6·T) per quantum crossed
        u_read = max(u_read, quantum ** 2 / (math.sqrt(6.0) * abs(b) * np.ptp(t) ** 2) if b else math.inf)
    return b, max(u_res, u_read)


def reading_quantum(values) -> float:
    """A channel's reading quantum estimated from the data: its smallest non-zero step (steps below float
    noise, 1e-9 of the values' span, left out); 0 with fewer than two distinct values."""
    v = np.asarray(values, dtype=float)
    finite = np.isfinite(v)
    v = v if finite.all() else v[finite]  # (every value finite: no copy)
    steps = np.abs(np.diff(v))
    real = steps > 1e-9 * (np.ptp(v) if v.size else 0.0)  # the steps above float noise
    return float(np.min(steps, where=real, initial=np.inf)) if real.any() else 0.0


def elastic_stress_rate(time_s, stress_MPa, window_MPa: Sequence[float]) -> float | None:
    """The stress rate on the elastic line: slope of σ(t) over the samples before the maximum
    whose stress lies in ``window_MPa`` (least squares), MPa/s; None with fewer than 3 samples.
    Samples whose time or stress is not a number (a blank or junk cell) are left out."""
    t = np.asarray(time_s, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    finite = np.isfinite(t) & np.isfinite(s)
    t, s = t[finite], s[finite]
    if t.size < 3:
        return None
    sel = _elastic_stretch(s, window_MPa, nan_argmax(s))
    return _slope(t[sel], s[sel]) if sel.size >= MIN_PHASE_SAMPLES else None


def phase_bounds(strain, stress_MPa, *, window_MPa: Sequence[float], Rp_MPa: float | None, yield_point: Mapping | None) -> dict:
    """Sample ranges [first, last] of the three phases of a tension curve: the elastic line (the
    modulus window's first stretch), the yield phase (to the Rp crossing after it, or with a yield
    point from ReH to the end of the yield point extension Ae) and the plastic range to Fm."""
    e = np.asarray(strain, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    i_m = nan_argmax(s)
    stretch = _elastic_stretch(s, window_MPa, i_m)
    out: dict = {"elastic": [int(stretch[0]), int(stretch[-1])] if stretch.size else None}
    start = int(stretch[-1]) if stretch.size else 0
    if yield_point and yield_point.get("ReH_MPa") is not None:
        i_h = int(np.argmax(s[: i_m + 1] >= yield_point["ReH_MPa"] - 1e-9 * abs(yield_point["ReH_MPa"])))
        past = np.flatnonzero(e[i_h: i_m + 1] >= e[i_h] + (yield_point.get("Ae_pct") or 0.0) / 100.0)
        end = i_h + int(past[0]) if past.size else i_m
        out["yield"] = [i_h, end]
    elif Rp_MPa is not None:
        reach = first_index(lambda at: s[at] >= Rp_MPa, start, i_m + 1)
        end = i_m if reach is None else reach
        out["yield"] = [start, max(end, start + MIN_PHASE_SAMPLES - 1)]
    else:
        out["yield"] = None
    out["to_Rm"] = [out["yield"][1], i_m] if out["yield"] else None
    return out


def measured_phases(time_s, elongation_mm, length_mm: float, stress_MPa, bounds: Mapping, *, quantum_mm: float = 0.0,
                    time_u_s: float = 0.0, commanded_mm_per_s: float | None = None, segment: Sequence[int] | None = None,
                    one_command: bool = False) -> dict:
    """Per phase: the strain rate ė = v/L (v: the least-squares slope of the elongation over time,
    L: the length it refers to) with its u (k = 1, :func:`slope_u`) and, on the elastic line, the stress
    rate dσ/dt with its u; None where a phase has fewer than 3 samples or no time span. A phase whose U
    exceeds UNRESOLVED_U_REL is, when the crosshead's ``commanded_mm_per_s`` is stated, measured over a
    wider window of the same command (``segment``: its samples) — :func:`_widened`. When the record's events
    show the ``segment`` ran under ``one_command`` (a constant crosshead speed), u is at least the spread of
    this slope over every window as long in that segment (:func:`window_scatter_u`): the readings' own errors,
    correlated ones (a host's stall, an interpolated reading) too."""
    t = np.asarray(time_s, dtype=float)
    x = np.asarray(elongation_mm, dtype=float)
    s = np.asarray(stress_MPa, dtype=float)
    out = {}
    for phase in PHASE_NAMES:
        span = bounds.get(phase)
        sel = slice(span[0], span[1] + 1) if span else slice(0, 0)
        fit = slope_u(t[sel], x[sel], quantum=quantum_mm, time_u_s=time_u_s)
        if fit and one_command and segment is not None:
            fit = (fit[0], max(fit[1], window_scatter_u(t, x, segment, span[1] - span[0] + 1)))
        out[phase] = {"samples": span, "time_s": [float(t[span[0]]), float(t[span[1]])] if span else None,
                      "strain_rate_per_s": fit[0] / length_mm if fit else None,
                      "strain_rate_u_per_s": fit[1] / length_mm if fit else None,
                      "strain_rate_U_rel_pct": _U_pct(fit)}
        if fit and not K_RATE * fit[1] <= UNRESOLVED_U_REL * abs(fit[0]):
            out[phase].update(_widened(t, x, length_mm, span, fit, quantum_mm, time_u_s, commanded_mm_per_s, segment, one_command))
        if phase == "elastic":
            stress_fit = slope_u(t[sel], s[sel], time_u_s=time_u_s)
            out[phase]["stress_rate_MPa_per_s"] = stress_fit[0] if stress_fit else None
            out[phase]["stress_rate_u_MPa_per_s"] = stress_fit[1] if stress_fit else None
    return out


def _U_pct(fit: tuple[float, float] | None) -> float | None:
    """U (k = 2) relative to the slope, %."""
    return 100.0 * K_RATE * fit[1] / abs(fit[0]) if fit and fit[0] else None


def window_scatter_u(t, x, segment: Sequence[int], n: int) -> float:
    """The u of a least-squares slope over n consecutive samples of a constant-speed ``segment`` from the
    readings' own errors: the slopes, over every window of n samples, of the residuals about the segment's
    line (windows' sums from cumulative sums); u = their 95 % quantile of |slope| / k, so that U holds 95 % of
    them whatever their distribution; 0 where the segment holds no such window."""
    lo, hi = int(segment[0]), int(segment[1])
    tt, xx = np.asarray(t[lo: hi + 1], dtype=float), np.asarray(x[lo: hi + 1], dtype=float)
    ok = np.isfinite(tt) & np.isfinite(xx)
    tt, xx = tt[ok], xx[ok]
    line = slope_u(tt, xx)
    if line is None or n < MIN_PHASE_SAMPLES or tt.size < n + 1:
        return 0.0
    r = xx - xx.mean() - line[0] * (tt - tt.mean())
    chunk = max(2 * n, 2048)  # cumulative sums per chunk, its time centred: no cancellation on a long record
    slopes = np.concatenate([_window_slopes(tt[i: i + chunk], r[i: i + chunk], n) for i in range(0, tt.size - n + 1, chunk - n + 1)])
    return float(np.quantile(np.abs(slopes), COVERAGE_P) / K_RATE)  # U = the 95 % quantile: heavy tails (stalls) held


def _window_slopes(t: np.ndarray, r: np.ndarray, n: int) -> np.ndarray:
    """Least-squares slopes of r(t) over every window of n consecutive samples: (nΣtr − ΣtΣr)/(nΣt² − (Σt)²)."""
    t = t - t.mean()

    def window_sums(v):  # Σ over every window of n samples
        """Σ over every window of n samples."""
        c = np.concatenate([[0.0], np.cumsum(v)])
        return c[n:] - c[:-n]

    st, sr = window_sums(t), window_sums(r)
    return (n * window_sums(t * r) - st * sr) / (n * window_sums(t * t) - st * st)


def _widened(t, x, length_mm, span, fit, quantum_mm, time_u_s, commanded_mm_per_s, segment, one_command) -> dict:
    """The phase's rate over a wider window of the same crosshead command: the phase's samples grown on
    both sides (doubling, within ``segment``) until U ≤ WIDE_TARGET_U_REL; taken only when it agrees
    with the commanded speed (SPEED_TOLERANCE + its U). Else the phase keeps its own rate, said not resolved."""
    from flowcurve.record.summary import SPEED_TOLERANCE

    own = {"phase_window": {"samples": span, "strain_rate_per_s": fit[0] / length_mm, "strain_rate_u_per_s": fit[1] / length_mm,
                            "strain_rate_U_rel_pct": _U_pct(fit)}}
    why = f"not resolved over its {span[1] - span[0] + 1} samples (U {_U_pct(fit):.0f} % > {100 * UNRESOLVED_U_REL:g} %)"
    if not commanded_mm_per_s or segment is None:
        return own | {"window_note": why + "; no wider window of one crosshead command (no commanded speed stated, or the rate is not the crosshead's)"}
    lo_seg, hi_seg = segment
    half = max(1, (span[1] - span[0]) // 2)
    wide = None
    while True:
        lo, hi = max(lo_seg, span[0] - half), min(hi_seg, span[1] + half)
        wide = slope_u(t[lo: hi + 1], x[lo: hi + 1], quantum=quantum_mm, time_u_s=time_u_s)
        if wide and one_command:
            wide = (wide[0], max(wide[1], window_scatter_u(t, x, segment, hi - lo + 1)))
        if wide is None or K_RATE * wide[1] <= WIDE_TARGET_U_REL * abs(wide[0]) or (lo == lo_seg and hi == hi_seg):
            break
        half *= 2
    if wide is None or not abs(wide[0] / commanded_mm_per_s - 1.0) <= SPEED_TOLERANCE + K_RATE * wide[1] / abs(wide[0]):
        got = "no slope" if wide is None else f"{wide[0]:.4g} mm/s"
        return own | {"window_note": why + f"; the wider window's crosshead rate ({got}) is not the commanded {commanded_mm_per_s:g} mm/s"}
    return own | {"samples_widened": [int(lo), int(hi)], "time_s_widened": [float(t[lo]), float(t[hi])],
                  "strain_rate_per_s": wide[0] / length_mm, "strain_rate_u_per_s": wide[1] / length_mm, "strain_rate_U_rel_pct": _U_pct(wide),
                  "window_note": why + f"; measured over samples {lo}–{hi} of the same crosshead command ({commanded_mm_per_s:g} mm/s)"}


def command_segment(time_s, events, i_max: int) -> tuple[int, int, bool]:
    """The samples [first, last] (to Fm, ``i_max``) run under one crosshead command: from the record's last
    ``start`` event before Fm to its next ``start``/``stop`` event, and True; the whole record to Fm without
    a ``start`` event, and False (one command not shown)."""
    t = np.asarray(time_s, dtype=float)
    t_m = t[i_max]
    starts = [e.time_s for e in events or () if e.name == "start" and e.time_s <= t_m]
    t0 = max(starts) if starts else -math.inf
    ends = [e.time_s for e in events or () if e.name in ("start", "stop") and e.time_s > t0]
    t1 = min(ends) if ends else math.inf
    inside = (t[: i_max + 1] >= t0) & (t[: i_max + 1] <= t1)  # (the samples after Fm never count: not read)
    if not inside.any():
        return 0, int(i_max), False
    return int(np.argmax(inside)), int(inside.size - 1 - np.argmax(inside[::-1])), bool(starts)


def _num(value) -> float | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


QUANTUM_KEYS = {"crosshead_mm": "crosshead_resolution_mm", "extensometer_mm": "extensometer_resolution_mm"}  # instruments.<key>
STAMP_U_KEYS = {"crosshead_mm": "crosshead_stamp_u_s", "extensometer_mm": "extensometer_stamp_u_s"}  # instruments.<key>: a reading's time stamp's u, if stated


def tension_testing_rate(result: Mapping, curves: Mapping, events=None) -> dict:
    """The testing-rate verdict of a tension identification from its own record (``curves``:
    ``raw_diagram`` with time and crosshead or extensometer, ``engineering`` strain and stress;
    ``events``: the record's, for the crosshead command a phase ran under)."""
    spec = (result.get("record") or {}).get("specimen") or {}
    instruments = (result.get("record") or {}).get("instruments") or {}
    raw, eng = curves.get("raw_diagram"), curves.get("engineering")
    heated = (_num((result.get("record") or {}).get("nominal_temperature_C")) or 0.0) > ROOM_RANGE_C[1]
    E = _num(result.get("E_MPa"))
    yp = {"ReH_MPa": result.get("ReH_MPa"), "Ae_pct": result.get("Ae_pct")} if result.get("yield_point") else None
    if raw is None or eng is None or "time_s" not in raw.columns:
        out = testing_rate({}, E_MPa=E, yield_point=bool(yp), heated=heated)
        out["findings"].insert(0, "the record has no time column: the testing rate is not stated")
        return out
    if "crosshead_mm" in raw.columns:
        channel, length = "crosshead_mm", _num(spec.get("parallel_length_mm"))
        basis = f"ė_Lc = v_c/L_c: crosshead rate over the parallel length L_c {length:g} mm" if length else None
        if not length:
            length = _num(spec.get("l0_mm"))
            basis = f"ė_Lc = v_c/L_c: crosshead rate over L0 {length:g} mm (the record gives no parallel length L_c)" if length else None
    else:
        channel, length = "extensometer_mm", _num(spec.get("extensometer_gauge_mm")) or _num(spec.get("l0_mm"))
        basis = f"ė_Le: extensometer rate over its gauge length {length:g} mm (no crosshead channel)" if length else None
    window = result.get("modulus_window_MPa") or (result.get("modulus") or {}).get("window_MPa")
    if not length or not window or channel not in raw.columns:
        out = testing_rate({}, E_MPa=E, yield_point=bool(yp), heated=heated)
        out["findings"].insert(0, "no elongation channel, length or elastic line: the testing rate is not stated")
        return out
    stress = eng["engineering_stress_MPa"].to_numpy(dtype=float)
    bounds = phase_bounds(eng["engineering_strain"].to_numpy(dtype=float), stress, window_MPa=window,
                          Rp_MPa=_num(result.get("Rp02_MPa")), yield_point=yp)
    time, elongation = raw["time_s"].to_numpy(dtype=float), raw[channel].to_numpy(dtype=float)
    quantum = _num(instruments.get(QUANTUM_KEYS[channel]))
    q_how = f"{channel} reading quantum {quantum:g} mm (stated)" if quantum else None
    if not quantum:
        quantum = reading_quantum(elongation)
        q_how = f"{channel} reading quantum {quantum:.3g} mm (its smallest step: the record states none)"
    stamp_u = _num(instruments.get(STAMP_U_KEYS[channel])) or 0.0
    if stamp_u:
        q_how += f" and its time stamps' u {stamp_u:g} s (stated)"
    crosshead = channel == "crosshead_mm"
    commanded = _num((result.get("record") or {}).get("crosshead_speed_mm_per_s")) if crosshead else None
    segment = command_segment(time, events, min(nan_argmax(stress), time.size - 1))
    phases = measured_phases(time, elongation, length, stress, bounds, quantum_mm=quantum, time_u_s=stamp_u,
                             commanded_mm_per_s=commanded, segment=segment[:2], one_command=segment[2] and crosshead)
    out = testing_rate(phases, E_MPa=E, yield_point=bool(yp), heated=heated)
    out["strain_rate_definition"] = basis
    out["reading_quantum_mm"] = quantum
    out["findings"][:0] = [basis, f"each rate ± U (k = 2): least squares, from the residual scatter and the {q_how}"]
    return out


def assess(result: Mapping, curves: Mapping, data=None, meta: Mapping | None = None, events=None) -> dict:
    """``methods.conformity`` of a finished identification: temperature (ISO 6892-1 room / ISO
    6892-2 heated, "not stated" without a number) and, for tension, the testing rate measured per
    phase (:func:`tension_testing_rate`); a compression's rate is stated, not judged."""
    rec = result.get("record") or {}
    temps = data["temperature_C"].to_numpy(dtype=float) if data is not None and "temperature_C" in data.columns else None
    as_written = (meta or {}).get("nominal_temperature_as_written")
    out = {"temperature": temperature(_num(rec.get("nominal_temperature_C")), temps, as_written=as_written)}
    if result.get("test") != "tension":
        out["testing_rate"] = {"conforms": None, "strain_rate_per_s": _num(rec.get("strain_rate_per_s")),
                               "findings": ["ISO 6892-1 rates apply to tension; the compression strain rate is stated, not checked"]}
        return out
    out["testing_rate"] = tension_testing_rate(result, curves or {}, events)
    return out

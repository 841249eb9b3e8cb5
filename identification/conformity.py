"""Did the test meet the standard's testing conditions? ISO 6892-1 rates, ISO 6892-2 temperatures.

Testing rate (ISO 6892-1:2019 §10): method A prescribes strain-rate ranges per result
(range 1 0.00007 s⁻¹, 2 0.00025 s⁻¹, 3 0.002 s⁻¹, 4 0.0067 s⁻¹, each ±20 %): Rp/ReH in range
1 or 2, ReL/Ae in 2 or 3, Rm/Ag/A/Z in 2, 3 or 4; a constant crosshead rate is method A2 (open
loop) with the estimated strain rate over the parallel length ė_Lc = v_c/L_c. Method B prescribes
the elastic stress rate (2–20 MPa/s for E < 150 GPa, 6–60 MPa/s otherwise), a plastic strain
rate of 0.00025–0.0025 s⁻¹ while Rp is determined and at most 0.008 s⁻¹ for Rm. The designation
is ``ISO 6892-1:2019 A222`` (the range of each of the three phases) or ``… B30`` (the stress rate,
MPa/s).

Temperature: ISO 6892-1 tests at 10–35 °C; ISO 6892-2:2018 (heated) allows the indicated
temperature to deviate from the specified T by ±3 °C up to 600 °C, ±4 °C up to 800 °C and ±5 °C
up to 1000 °C.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

STANDARD_TENSION = "ISO 6892-1:2019"
STANDARD_HEATED = "ISO 6892-2:2018"
RANGES_PER_S = {1: 0.00007, 2: 0.00025, 3: 0.002, 4: 0.0067}  # method A strain-rate ranges, §10.3.3
RANGE_TOLERANCE = 0.20  # ±20 % about each range
PHASES = (("Rp/ReH", (1, 2)), ("ReL/Ae", (2, 3)), ("Rm/Ag/A/Z", (2, 3, 4)))
B_STRESS_RATE_MPa_PER_S = {"E < 150 GPa": (2.0, 20.0), "E ≥ 150 GPa": (6.0, 60.0)}  # method B, Table 3
B_PLASTIC_RATE_PER_S = (0.00025, 0.0025)  # method B while Rp is determined
B_RM_MAX_RATE_PER_S = 0.008  # method B for Rm
ROOM_RANGE_C = (10.0, 35.0)  # ISO 6892-1 §10.1
HEATED_TOLERANCE_C = ((600.0, 3.0), (800.0, 4.0), (1000.0, 5.0))  # ISO 6892-2: up to T, ± tolerance


def method_a_range(strain_rate_per_s: float) -> int | None:
    """The method A range (1–4) whose ±20 % band holds this strain rate, or None."""
    for number, centre in RANGES_PER_S.items():
        if abs(strain_rate_per_s - centre) <= RANGE_TOLERANCE * centre:
            return number
    return None


def testing_rate(strain_rate_per_s: float, *, stress_rate_MPa_per_s: float | None, E_MPa: float | None) -> dict:
    """Conformity of a constant-crosshead tension test with ISO 6892-1 methods A2 and B, and its designation."""
    rng = method_a_range(strain_rate_per_s)
    phases = {name: (rng is not None and rng in allowed) for name, allowed in PHASES}
    findings = [f"estimated strain rate over the parallel length ė_Lc = {strain_rate_per_s:.3g} s⁻¹ "
                + (f"(method A range {rng})" if rng else "(in no method A range ±20 %)")]
    out: dict = {"standard": STANDARD_TENSION, "strain_rate_per_s": strain_rate_per_s, "method_a_range": rng,
                 "stress_rate_MPa_per_s": stress_rate_MPa_per_s}
    if all(phases.values()):
        out.update(method="A2", conforms=True, designation=f"{STANDARD_TENSION} A{rng}{rng}{rng}")
        findings.append("method A2 (open loop, constant crosshead rate): every phase in an allowed range")
    else:
        bad = ", ".join(name for name, ok in phases.items() if not ok)
        findings.append(f"method A: not met for {bad}")
        b_ok, b_why = _method_b(strain_rate_per_s, stress_rate_MPa_per_s, E_MPa)
        findings.extend(b_why)
        if b_ok:
            out.update(method="B", conforms=True, designation=f"{STANDARD_TENSION} B{stress_rate_MPa_per_s:.0f}")
        else:
            out.update(method=None, conforms=False, designation=f"{STANDARD_TENSION} (testing rate not conforming)")
    out["findings"] = findings
    return out


def _method_b(rate: float, stress_rate: float | None, E_MPa: float | None) -> tuple[bool, list[str]]:
    ok, why = True, []
    if stress_rate is None or E_MPa is None:
        return False, ["method B: the elastic stress rate could not be measured"]
    band_name = "E < 150 GPa" if E_MPa < 150_000.0 else "E ≥ 150 GPa"
    lo, hi = B_STRESS_RATE_MPa_PER_S[band_name]
    if not lo <= stress_rate <= hi:
        ok = False
        why.append(f"method B: elastic stress rate {stress_rate:.3g} MPa/s outside {lo:g}–{hi:g} MPa/s ({band_name})")
    plo, phi = B_PLASTIC_RATE_PER_S
    if not plo <= rate <= phi:
        ok = False
        why.append(f"method B: plastic strain rate {rate:.3g} s⁻¹ outside {plo:g}–{phi:g} s⁻¹ for Rp")
    if rate > B_RM_MAX_RATE_PER_S:
        ok = False
        why.append(f"method B: strain rate {rate:.3g} s⁻¹ above {B_RM_MAX_RATE_PER_S:g} s⁻¹ for Rm")
    if ok:
        why.append(f"method B: stress rate {stress_rate:.3g} MPa/s and strain rate {rate:.3g} s⁻¹ within the limits")
    return ok, why


def heated_tolerance_C(temperature_C: float) -> float | None:
    """ISO 6892-2's permitted deviation of the indicated temperature at this T (None above 1000 °C)."""
    for upto, tol in HEATED_TOLERANCE_C:
        if temperature_C <= upto:
            return tol
    return None


def temperature(nominal_C: float | None, measured_C: Sequence[float] | None) -> dict:
    """Conformity of the test temperature: room (ISO 6892-1, 10–35 °C) or heated (ISO 6892-2 tolerance)."""
    meas = np.asarray(measured_C if measured_C is not None else [], dtype=float)
    meas = meas[np.isfinite(meas)]
    if nominal_C is None:
        return {"conforms": None, "findings": ["no nominal test temperature in the record"]}
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
    i_m = int(np.nanargmax(s))
    lo, hi = window_MPa
    sel = np.nonzero((s[: i_m + 1] >= lo) & (s[: i_m + 1] <= hi))[0]
    if sel.size < 3:
        return None
    first_exit = np.nonzero(np.diff(sel) > 1)[0]  # the first contiguous stretch only
    if first_exit.size:
        sel = sel[: first_exit[0] + 1]
    if sel.size < 3 or np.ptp(t[sel]) <= 0:
        return None
    return float(np.polyfit(t[sel], s[sel], 1)[0])

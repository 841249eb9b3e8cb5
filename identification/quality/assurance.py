"""What an accredited lab states beside each result: its uncertainty budget and the test's conformity.

:func:`attach` fills ``result["uncertainty"]`` (one GUM budget per result, from
:mod:`identification.uncertainty`, with the instruments it assumed) and
``result["methods"]["conformity"]`` (testing rate and temperature, from
:mod:`identification.conformity`) of a finished tension or compression identification. A
budget whose inputs the result lacks is left out, never guessed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from flowcurve.identification.iso6892 import mad_sigma, max_force_band, nan_argmax
from flowcurve.identification.quality import conformity as cf
from flowcurve.identification.quality import uncertainty as un
from flowcurve.identification.elastic_modulus import apparent_modulus_warning, class_modulus

FLOW_STRAINS = (0.05, 0.1, 0.2, 0.3, 0.5)  # compression flow stress budgets at these true plastic strains
CONSTANTS = (("A_MPa", "MPa"), ("B_MPa", "MPa"), ("n", "1"), ("K_MPa", "MPa"), ("eps0", "1"), ("sigma0_MPa", "MPa"), ("Q_MPa", "MPa"), ("b", "1"))


def instruments_from_meta(meta: Mapping[str, str]) -> dict:
    """The instrument classes of a record (``instruments.<key>`` metadata) with the defaults for
    the keys it lacks; ``source`` says which were defaults."""
    inst: dict = {}
    defaulted, unreadable = [], []
    defaults = {**un.INSTRUMENT_DEFAULTS, **un.DIMENSION_DEFAULTS}
    for key, default in defaults.items():
        raw = meta.get(f"instruments.{key}")
        try:
            value = float(raw) if raw is not None and str(raw).strip() else None
        except ValueError:
            value = math.nan
        if value is None or not math.isfinite(value) or value <= 0:
            if value is not None:
                unreadable.append(f"{key} {raw!r}")
            value = default
            defaulted.append(key)
        inst[key] = value
    if not defaulted:
        inst["source"] = "record (instruments.*)"
    elif len(defaulted) == len(defaults) and not unreadable:
        inst["source"] = ("defaults: the record states no instrument classes (set [instruments] in the rig configuration, "
                          "or --set instruments.force_class=… when identifying)")
    else:
        inst["source"] = f"record, defaults for {', '.join(defaulted)}"
    if unreadable:
        inst["source"] += f"; not a positive number, default used: {', '.join(unreadable)}"
    return inst


def _num(value) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) else None


def _block(result: Mapping, name: str) -> dict:
    rec = result.get("record") or {}
    block = rec.get(name) if isinstance(rec, Mapping) else None
    return block if isinstance(block, Mapping) else {}


def plastic_slope_MPa(curve, E_MPa: float, at: float = un.OFFSET, half_width: float = 0.001) -> float | None:
    """θ = dσ/de_p of an engineering curve at plastic strain ``at`` (least-squares slope over ±half_width before Fm)."""
    if curve is None or "engineering_strain" not in curve.columns or "engineering_stress_MPa" not in curve.columns:
        return None
    e = curve["engineering_strain"].to_numpy(dtype=float)
    s = curve["engineering_stress_MPa"].to_numpy(dtype=float)
    i_m = nan_argmax(s)
    ep = e[: i_m + 1] - s[: i_m + 1] / E_MPa
    sel = (ep >= at - half_width) & (ep <= at + half_width)
    if sel.sum() < 3 or np.ptp(ep[sel]) <= 0:
        return None
    return float(np.polyfit(ep[sel], s[: i_m + 1][sel], 1)[0])


def _curve_slope(eps_p: np.ndarray, stress_MPa: np.ndarray, at: float, half_width: float = 0.01) -> float:
    """dσ/dε_p of a curve at ``at``: the chord over ±half_width (within the curve)."""
    lo, hi = max(at - half_width, float(np.nanmin(eps_p))), min(at + half_width, float(np.nanmax(eps_p)))
    order = np.argsort(eps_p)
    s_lo, s_hi = np.interp([lo, hi], eps_p[order], stress_MPa[order])
    return float((s_hi - s_lo) / (hi - lo)) if hi > lo else 0.0


def _hardening_slope(hard: Mapping, at: float) -> float | None:
    A, B, n = (_num(hard.get(k)) for k in ("A_MPa", "B_MPa", "n"))
    if hard.get("law") == "johnson_cook" and None not in (B, n):
        return B * n * at ** (n - 1.0)  # d/dε (A + B·εⁿ)
    return None


def _constants(hard: Mapping, stress_rel_u: float) -> dict:
    out = {}
    shifts = ((hard.get("start_uncertainty") or {}).get("constants_shift") or {})
    lack = ((hard.get("start_uncertainty") or {}).get("constants_lack_of_fit") or {})
    sides = ((hard.get("start_uncertainty") or {}).get("constants_on_bound") or {})
    scales = ((hard.get("start_uncertainty") or {}).get("constants_on_bound_scale") or {})
    shares = hard.get("stderr_shares") or {}  # compression: name → {key: u}, inside the stated standard error
    for key, unit in CONSTANTS:
        value = _num(hard.get(key))
        if value is None:
            continue
        shift = _num(shifts.get(key.removesuffix("_MPa")))
        b = un.constant_budget(value, _num(hard.get(f"{key}_stderr")), stress_rel_u, unit, zero_shift=shift,
                               lack_of_fit=_num(lack.get(key.removesuffix("_MPa"))), on_bound=sides.get(key.removesuffix("_MPa")),
                               scale=_num(scales.get(key.removesuffix("_MPa"))),
                               shares={name: u for name, per in shares.items() if (u := _num((per or {}).get(key))) is not None})
        if b is not None:
            out[key] = b
    return out


def _strain_rel_u(result: Mapping, inst: Mapping) -> tuple[float, str]:
    methods = result.get("methods") or {}
    if methods.get("strain_source") == "extensometer":
        return un.extensometer_scale_rel_u(inst["extensometer_class"]), f"extensometer, ISO 9513 class {inst['extensometer_class']:g}"
    # a crosshead strain: compliance and toe corrections within ±crosshead_strain_error_pct; the scale
    # pinned to the measured Lu − L0 (K_l) adds that measurement's own uncertainty
    spec, post = _block(result, "specimen"), _block(result, "post")
    l0, lu = _num(spec.get("l0_mm")), _num(post.get("lu_mm"))
    shape = un.rectangular(inst["crosshead_strain_error_pct"] / 100.0)
    basis = f"crosshead travel, ±{inst['crosshead_strain_error_pct']:g} % assumed"
    d0 = _num(spec.get("d0_mm"))
    if methods.get("strain_length_stated") is False and l0 and d0:  # Lc not stated: l0 taken, up to L0 + 2·d0 (one-sided, u = r/2)
        scaled = methods.get("scale_factor_Kl") is not None and lu and lu != l0
        a_u = _num((methods.get("scale_Kl") or {}).get("uniform_plastic_elongation")) if scaled else None
        r = un.unstated_length_rel(l0, d0, lu_mm=lu if scaled else None, a_u=a_u)
        shape = math.hypot(shape, r / 2.0)
        basis += f"; Lc not stated, l0 taken: over L0 + 2·d0 the strains would read {100.0 * r:.2g} % lower (u = half of it)"
    if methods.get("scale_factor_Kl") is not None and l0 and lu and lu != l0:
        terms = methods.get("scale_Kl") or {}  # (3.1)'s terms: the recovery at the fracture, its E, the last sample's travel
        recovery = (_num(terms.get("specimen_recovery_mm")) or 0.0) + (_num(terms.get("frame_recovery_mm")) or 0.0)
        E_rec, u_E_rec = _num(terms.get("recovery_E_MPa")), _num(terms.get("recovery_E_u_MPa")) or 0.0
        scale = un.measured_length_scale_rel_u(l0, lu, inst["length_resolution_mm"], mpe_mm=inst["caliper_mpe_mm"], recovery_mm=recovery,
                                               recovery_E_rel_u=u_E_rec / E_rec if E_rec else un.rectangular(un.HANDBOOK_E_BOUND),
                                               sample_step_mm=_num(terms.get("sample_step_mm")) or 0.0)
        return (math.hypot(shape, scale), basis + f", scaled to the measured Lu − L0 (resolution {inst['length_resolution_mm']:g} mm, "
                f"MPE ±{inst['caliper_mpe_mm']:g} mm) less the elastic recovery at the fracture ({recovery:.3g} mm)")
    return shape, basis


def tension_uncertainty(result: Mapping, curves: Mapping, inst: Mapping) -> dict:
    """The budgets of a tension result: E, Rp0.2, Rm, Ag, A, Z and the hardening constants."""
    out: dict = {}
    spec, post = _block(result, "specimen"), _block(result, "post")
    d0 = _num(spec.get("d0_mm"))
    E = _num(result.get("E_MPa"))
    Rm, Rp = _num(result.get("Rm_MPa")), _num(result.get("Rp02_MPa"))
    if d0 is None or E is None:
        return out
    strain_u, strain_basis = _strain_rel_u(result, inst)
    out["strain_scale"] = {"u_rel": strain_u, "basis": strain_basis}
    stderr = _num(result.get("E_stderr_MPa"))
    E_measured = stderr is not None
    if E_measured:  # a force or strain scale error moves E with the stresses and strains: only the regression is E's own
        out["E_MPa"] = un.modulus_budget(E, d0, inst, strain_rel_u=strain_u, stderr_MPa=stderr)
        u_E = stderr
    else:
        u_E = E * un.rectangular(un.HANDBOOK_E_BOUND)
        out["E_MPa"] = {"value": E, "unit": "MPa", "given": True, "u": u_E, "U": un.K_COVERAGE * u_E, "k": un.K_COVERAGE, "components": [],
                        "note": f"given, not measured: ±{100 * un.HANDBOOK_E_BOUND:g} % assumed"}
    if Rm is not None:
        out["Rm_MPa"] = un.strength_budget(Rm, d0, inst)
    if Rp is not None:
        theta = plastic_slope_MPa(curves.get("engineering"), E) or _hardening_slope(result.get("hardening") or {}, un.OFFSET)
        if theta is not None:
            out["Rp02_MPa"] = un.proof_strength_budget(Rp, d0, inst, plastic_slope_MPa=theta, strain_rel_u=strain_u,
                                                       E_MPa=E, u_E_MPa=u_E, E_measured=E_measured)
            method = _tension_rp_method(result, curves.get("engineering"), Rp, E)
            extend_budget(out["Rp02_MPa"], method)
    Ag = _num(result.get("Ag_pct"))
    if Ag is not None and Rm is not None:
        out["Ag_pct"] = _uniform_elongation(result, curves, inst, Ag, Rm, E, E_measured=E_measured, strain_u=strain_u, u_E=u_E,
                                            u_Rm=None if E_measured else out["Rm_MPa"]["u"])
    A = _num(result.get("A_pct"))
    l0, lu = _num(spec.get("l0_mm")), _num(post.get("lu_mm"))
    method = str(result.get("A_method") or "")
    if A is not None and l0 and lu and "lu_mm" in method:
        out["A_pct"] = un.elongation_from_lengths_budget(l0, lu, inst["length_resolution_mm"], mpe_mm=inst["caliper_mpe_mm"])
    elif A is not None and "extensometer" in method:
        gauge = _num((result.get("methods") or {}).get("strain_length_mm")) or _num(spec.get("extensometer_gauge_mm")) or l0
        if gauge:
            out["A_pct"] = un.elongation_from_extension_budget(A, gauge, inst["extensometer_class"])
    elif A is not None and isinstance((result.get("methods") or {}).get("A_from_curve"), Mapping):
        u_a = out["Ag_pct"]["u"] / 100.0 if "Ag_pct" in out else 0.0
        out["A_pct"] = un.elongation_from_curve_budget(A, result["methods"]["A_from_curve"], strain_u, u_E or 0.0, u_a, strain_basis)
    Z = _num(result.get("Z_pct"))
    du = _num(post.get("dk_mm")) or _num(post.get("du_mm"))
    if du is None and _num(post.get("sk_mm2")):
        du = math.sqrt(4.0 * post["sk_mm2"] / math.pi)
    if Z is not None and du:
        out["Z_pct"] = un.reduction_of_area_budget(d0, du, inst["diameter_resolution_mm"], mpe_mm=inst["micrometer_mpe_mm"],
                                                   fracture_rel=un.FRACTURE_DIAMETER_REL)
    stress_rel_u = math.hypot(un.force_rel_u(inst["force_class"]), 2.0 * un.dimension_u(d0, inst["diameter_resolution_mm"], inst["micrometer_mpe_mm"]) / d0)
    out["hardening"] = _constants(result.get("hardening") or {}, stress_rel_u)
    return out


def _uniform_elongation(result: Mapping, curves: Mapping, inst: Mapping, Ag: float, Rm: float, E: float, *, E_measured: bool,
                        strain_u: float, u_E: float, u_Rm: float | None) -> dict:
    """Ag's budget: the strain at Fm, e_m = Ag/100 + Rm/E, with the extensometer's class or the
    strain scale's u; Rm's u only with a given E (a measured one moves with the force scale); half
    the band of a flat maximum (:func:`.iso6892.max_force_band`)."""
    e_m = Ag / 100.0 + Rm / E
    gauge = _num((result.get("methods") or {}).get("strain_length_mm"))
    # measured E: the scales cancel in Rm/E and scale the plastic extension e_m − Rm/E; given E: e_m, E and Rm apart
    scaled = Ag / 100.0 if E_measured else e_m
    if (result.get("methods") or {}).get("strain_source") == "extensometer" and gauge:
        cls = inst["extensometer_class"]
        u_em = math.hypot(un.extension_u_mm(scaled * gauge, cls) / gauge, scaled * un.rectangular(cls / 100.0))
    else:
        u_em = scaled * strain_u
    eng = curves.get("engineering")
    band = (max_force_band(eng["engineering_strain"].to_numpy(dtype=float), eng["engineering_stress_MPa"].to_numpy(dtype=float))
            if eng is not None and "engineering_strain" in eng.columns else (0.0, 0.0))
    return un.uniform_elongation_budget(Ag, Rm, E, strain_at_Fm_u=u_em, u_E_MPa=u_E, u_Rm_MPa=u_Rm, flat_halfwidth=(band[1] - band[0]) / 2.0)


def compression_uncertainty(result: Mapping, curves: Mapping, inst: Mapping) -> dict:
    """The budgets of a compression result: μ, the flow stress at :data:`FLOW_STRAINS`, Rp0.2, constants."""
    out: dict = {}
    spec, post = _block(result, "specimen"), _block(result, "post")
    d0, h0, hk = _num(spec.get("d0_mm")), _num(spec.get("h0_mm")), _num(post.get("hk_mm"))
    mu = _num(result.get("friction_mu"))
    friction = result.get("friction")
    others = {k: _num(v) for k, v in friction.items() if k != result.get("friction_method")} if isinstance(friction, Mapping) else {}
    mu_b = un.friction_budget(mu, result.get("friction_mu_range"), others=others) if mu is not None else None
    if mu_b is not None:
        out["friction_mu"] = mu_b
    if d0 is None:
        return out
    Rp = _num(result.get("Rp02_MPa"))
    if Rp is not None:
        method = _compression_rp_method(result, curves.get("nominal"))
        out["Rp02_MPa"] = un.strength_budget(Rp, d0, inst, extra=method,
                                             note="mean pressure at 0.2 % plastic strain: force and d0, and the method's own share "
                                                  "(the elastic line's E and the defensible lines' spread, the strain zero and toe)")
        out["Rp02_MPa"]["u_method"] = un.combined(method)
    curve = curves.get(f"true_{result.get('friction_correction')}")
    if curve is not None and h0 and hk and h0 > hk and mu is not None:
        eps = curve["true_plastic_strain"].to_numpy(dtype=float)
        sig = curve["true_stress_MPa"].to_numpy(dtype=float)
        u_mu = mu_b["u"] if mu_b else 0.0
        E_method = (result.get("methods") or {}).get("elastic_modulus") or {}
        zero = _num(((result.get("hardening") or {}).get("start_uncertainty") or {}).get("delta_eps0")) or 0.0
        flow = {}
        for at in FLOW_STRAINS:
            if eps.size and eps.min() <= at <= eps.max():
                sigma = float(np.interp(at, eps, sig))
                method = un.flow_point_method_components(sigma, _curve_slope(eps, sig, at), _num(E_method.get("E_MPa")),
                                                         _num(E_method.get("u_MPa")) or 0.0, zero)
                method += un.correction_form_components(sigma, _at_strain(curve, "correction_uncertainty_pct", eps, at))
                flow[f"{at:g}"] = un.flow_stress_budget(sigma, at, d0, h0, hk, inst, mu=mu, u_mu=u_mu, method=method,
                                                        mu_sensitivity=_at_strain(curve, "dsigma_dmu_MPa", eps, at))
        if flow:
            out["flow_stress_MPa"] = flow
    stress_rel_u = math.hypot(un.force_rel_u(inst["force_class"]), 2.0 * un.dimension_u(d0, inst["diameter_resolution_mm"], inst["micrometer_mpe_mm"]) / d0)
    out["hardening"] = _constants(result.get("hardening") or {}, stress_rel_u)
    return out


def _at_strain(curve, column: str, eps: np.ndarray, at: float) -> float | None:
    """The curve's ``column`` at plastic strain ``at`` (linear), None where the curve has no such column."""
    if column not in curve.columns:
        return None
    values = curve[column].to_numpy(dtype=float)
    ok = np.isfinite(values) & np.isfinite(eps)
    return float(np.interp(at, eps[ok], values[ok])) if ok.any() else None


def extend_budget(b: dict, method: list) -> None:
    """A budget with the method's own components added: u, U again; ``u_method`` (the method's share,
    stated apart) grown by them; the budget's other keys kept."""
    old = [un.Component(**{k: c[k] for k in ("name", "value", "unit", "u", "sensitivity", "basis", "dof") if k in c}) for c in b["components"]]
    out = un.budget(b["value"], b["unit"], old + method, note=b.get("note", ""))
    u_method = math.hypot(_num(b.get("u_method")) or 0.0, un.combined(method))
    b.update(out, u_method=u_method)


def _tension_rp_method(result: Mapping, curve, Rp: float, E: float) -> list:
    """The method's share of a tension Rp0.2 beyond E's own uncertainty: the spread over the
    defensible lines (the line, its window's halves, the class's handbook E where the strain is the
    specimen's), the strain zero δε0, the crosshead compliance model (no extensometer) and the
    testing rate within the method's range."""
    methods = result.get("methods") or {}
    record = result.get("record") or {}
    material = record.get("material") if isinstance(record, Mapping) else None
    named = class_modulus(material)
    comps: list = []
    window = (result.get("modulus") or {}).get("window_MPa")
    if curve is not None and "engineering_strain" in curve.columns:
        strain = curve["engineering_strain"].to_numpy(dtype=float)
        stress = curve["engineering_stress_MPa"].to_numpy(dtype=float)
        lines = {"the line": E}
        if window and window[1] > window[0]:
            lines.update(un.line_windows_E(strain, stress, window))
        specimen_strain = methods.get("strain_source") == "extensometer" or methods.get("frame_stiffness_N_per_um") is not None
        if named is not None and specimen_strain:
            lines[f"{named[0]} class handbook"] = named[1]
        comps += un.offset_method_components(strain, stress, E, 0.0, lines, _offset_line_zero(result))
    if methods.get("strain_source") == "crosshead":
        comps.append(un.crosshead_compliance_component(Rp))
    rate = ((methods.get("conformity") or {}).get("testing_rate") or {}).get("method")
    comps.append(un.rate_component(Rp, rate, named[0] if named else None))
    return comps


def _compression_rp_method(result: Mapping, nominal) -> list:
    """The method's share of a compression Rp0.2 (:func:`.uncertainty.offset_method_components`) on
    the nominal curve (true strain, mean pressure): the E that stripped the elastic strain, the
    spread over the defensible lines (this E, the class's handbook E, a plausible apparent slope)
    and the strain zero δε0 (hardening.start_uncertainty)."""
    if nominal is None or "true_strain" not in nominal.columns:
        return []
    E_method = (result.get("methods") or {}).get("elastic_modulus") or {}
    E, u_E = _num(E_method.get("E_MPa")), _num(E_method.get("u_MPa"))
    if E is None:
        return []
    strain = nominal["true_strain"].to_numpy(dtype=float)
    stress = nominal["mean_pressure_MPa"].to_numpy(dtype=float)
    lines = {E_method.get("source", "used"): E}
    named = class_modulus((result.get("record") or {}).get("material"))
    if named is not None:
        lines[f"{named[0]} class handbook"] = named[1]
    apparent = _num(E_method.get("apparent_MPa"))
    if apparent is not None and apparent_modulus_warning(apparent, (result.get("record") or {}).get("material")) is None:
        lines["apparent slope"] = apparent
    return un.offset_method_components(strain, stress, E, u_E or 0.0, lines, _offset_line_zero(result), basis=E_method.get("basis", ""))


def _offset_line_zero(result: Mapping) -> float:
    """δε0 of the offset line's foot. Where a line was regressed on the window (``regressed_line``; before
    that key, a line fit term), the sample spacing at the line's top is left out (it places where the
    curve's plastic part starts, not the line's foot);
    where a given or handbook E does, the step itself counts (``plastic_start_step``, Δε/√3: the
    offset crossing read between sparse samples) in place of the zero's own spacing term. Equation:
    root sum of squares of the parts (hardening.start_uncertainty.components)."""
    start = (result.get("hardening") or {}).get("start_uncertainty") or {}
    parts = start.get("components")
    if not isinstance(parts, Mapping):
        return _num(start.get("delta_eps0")) or 0.0
    regressed = start["regressed_line"] if "regressed_line" in start else (_num(parts.get("line_fit")) or 0.0) > 0.0
    step = _num(start.get("plastic_start_step"))
    spacing = 0.0 if regressed else (step if step is not None else _num(parts.get("sample_spacing")) or 0.0)
    return math.sqrt(sum((_num(v) or 0.0) ** 2 for k, v in parts.items() if k != "sample_spacing") + spacing ** 2)


MAX_PASSED_IN_NOISE = 10.0  # a fall of this many noise σ after the maximum: the noise's own extremes over a record reach ±3.5σ


def force_maximum_not_reached(record) -> str | None:
    """Why the record's largest force is not Fm, or None: a test that ended on something other than a fracture (the
    record's ``stop_reason``) while its force had not fallen from its maximum by :data:`MAX_PASSED_IN_NOISE` × its
    noise σ (a test stopped on the rise, e.g. by a fault drill). A broken specimen's force falls: its maximum stands."""
    reason = " ".join(str(record.meta.get("stop_reason") or "").split())
    if not reason or "fracture" in reason.lower() or not record.has("force_N"):
        return None
    force = np.abs(record.column("force_N"))
    force = force[np.isfinite(force)]
    if force.size < 3:
        return None
    i = int(np.argmax(force))
    drop = float(force[i] - np.min(force[i:]))  # how far the force fell after its maximum
    noise = mad_sigma(np.diff(force, 2)) / math.sqrt(6.0)  # σ of white noise from its second differences (trend-free)
    if drop > MAX_PASSED_IN_NOISE * noise:
        return None
    return f"the test stopped before the force maximum (it ended on: {reason[:80]}; the force had not fallen from its largest value)"


def not_certifiable(budget: Mapping, why: str) -> dict:
    """A budget replaced by the statement that its value is not certifiable: no U, the reason."""
    return {"value": budget.get("value"), "unit": budget.get("unit"), "u": None, "U": None, "k": budget.get("k"), "components": [],
            "certifiable": False, "note": why}


def attach(result, curves: Mapping, record) -> None:
    """Fill ``result['uncertainty']`` and ``result['methods']['conformity']`` (tension or compression)."""
    inst = instruments_from_meta(record.meta)
    test = result.get("test")
    methods = result.get("methods")
    if isinstance(methods, dict):  # first: the Rp budget's rate term takes the testing method it found
        methods["conformity"] = cf.assess(result, curves, record.data, record.meta, getattr(record, "events", None))
    budgets = (tension_uncertainty if test == "tension" else compression_uncertainty)(result, curves, inst)
    why = force_maximum_not_reached(record) if test == "tension" else None
    if why:  # Rm and Ag are the maximum force's: a test stopped on the rise has neither, only a lower bound of Rm
        for key in ("Rm_MPa", "Ag_pct"):
            if key in budgets:
                budgets[key] = not_certifiable(budgets[key], why)
        if isinstance(result.get("warnings"), list):
            result["warnings"].append(f"Rm is not certifiable: {why}; the value is a lower bound (Rm ≥ it) and states no U")
    result["uncertainty"] = {"instruments": inst, **budgets}

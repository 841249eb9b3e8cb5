"""Measurement uncertainty of the identified results (GUM, JCGM 100:2008), per result.

Every result gets a budget: its input quantities, each with a standard uncertainty ``u``, a
sensitivity coefficient ``c`` (∂result/∂input) and a contribution ``|c|·u``; the combined
standard uncertainty is the root sum of squares of the contributions (GUM (10), inputs
uncorrelated) and the expanded uncertainty ``U = k·u_c`` with k = 2 (about 95 %).

The inputs come from the instruments' classes — force per ISO 7500-1 class, extensometer per
ISO 9513 class, dimensions from the resolution of the measuring tool — read from the record's
``instruments.*`` metadata (written from the rig configuration's ``[instruments]``), or the
defaults of :data:`INSTRUMENT_DEFAULTS` with a note saying so; and from the fits' own
statistics (standard errors). A class ``c`` is a bound ±c % on the relative indication error
and is taken as rectangular (u = c %/√3); a resolution ``r`` as rectangular of width r
(u = r/√12). docs/test-report.md states every model.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flowcurve.identification.iso6892 import nan_argmax
from flowcurve.identification.laws.bounds import BOUND_REL_TOL, constant_scales
from flowcurve.identification.laws.bounds import central_jacobian as _jacobian
from flowcurve.record.specimen import circle_area_mm2 as _area_mm2  # S0 = π·d0²/4

K_COVERAGE = 2.0  # expanded uncertainty U = k·u_c, k = 2 (≈ 95 % for a normal output)

# The defaults when a record does not state its instruments (the same values as
# rig.config.InstrumentsConfig; a test keeps them equal).
INSTRUMENT_DEFAULTS = {
    "force_class": 1.0,  # ISO 7500-1 class of the force-measuring system, %
    "extensometer_class": 1.0,  # ISO 9513 class of the extensometer
    "diameter_resolution_mm": 0.01,  # resolution of the diameter measurement (micrometer)
    "length_resolution_mm": 0.01,  # resolution of lengths and heights (L0, Lu, h0, hk)
    "crosshead_strain_error_pct": 2.0,  # bound on a strain from crosshead travel (no extensometer)
}
# the dimensions' instruments, read from the record's instruments.<key> like the classes above (defaults said so): the
# maximum permissible error of the micrometer (d0, du; DIN 863-1 0–25 mm: 4 µm) and of the caliper (L0, Lu, h0, hk; ISO 13385-1
# to 150 mm: 30 µm), each a bound, rectangular
DIMENSION_DEFAULTS = {"micrometer_mpe_mm": 0.004, "caliper_mpe_mm": 0.03}
FRACTURE_DIAMETER_REL = 0.01  # ISO 6892-1 20.1: Su to ±2 % (the pieces fitted together), so du to ±1 %, rectangular
# ISO 9513 Table 2: per class, the bound on the relative extension error (%) and its absolute floor (µm)
EXTENSOMETER_LIMITS = {0.2: (0.2, 0.6), 0.5: (0.5, 1.5), 1.0: (1.0, 3.0), 2.0: (2.0, 6.0)}
HANDBOOK_E_BOUND = 0.05  # a handbook E (not measured) is taken as within ±5 %
OFFSET = 0.002  # the 0.2 % offset of Rp0.2
# a crosshead-only Rp0.2 against the same specimen's extensometer: rms of the relative differences over the 67 pairs of
# the 42CrMoS4 set (Machine Displacement alone, no frame stiffness; bench/crosshead_pairs_42CrMoS4.py, docs/methods.md §2.12)
CROSSHEAD_RP_REL_U = 0.0037
# strain-rate sensitivity m = d ln R / d ln ė of a proof strength at room temperature, per material class (ferritic steels
# 5–15 MPa a decade on Rp 300–700 MPa; docs/methods.md §2.12); the default for a class not named: the steels'
RATE_SENSITIVITY = {"steel": 0.008, "aluminium": 0.003, "titanium": 0.012, "copper": 0.005, "nickel": 0.005}
# the rate range a testing method allows, as the ratio of its ends: method A ±20 % (ISO 6892-1 10.3), method B a decade (10.4)
RATE_RANGE = {"A": 1.2 / 0.8, "B": 10.0}


def rectangular(half_width: float) -> float:
    """Standard uncertainty of a quantity known to lie within ±half_width: a/√3 (GUM 4.3.7)."""
    return abs(half_width) / math.sqrt(3.0)


def resolution(step: float) -> float:
    """Standard uncertainty of a reading with resolution ``step``: step/√12 (GUM F.2.2.1)."""
    return abs(step) / math.sqrt(12.0)


@dataclass(frozen=True)
class Component:
    """One input of a budget: its value, standard uncertainty u and sensitivity c = ∂y/∂x."""

    name: str
    value: float
    unit: str
    u: float
    sensitivity: float
    basis: str
    dof: float = math.inf  # degrees of freedom: a Type A term's n − 1; ∞ for a Type B bound

    @property
    def contribution(self) -> float:
        """|c|·u, in the result's unit."""
        return abs(self.sensitivity * self.u)

    def as_dict(self) -> dict:
        """The component as the budget's JSON row."""
        out = {"name": self.name, "value": self.value, "unit": self.unit, "u": self.u, "sensitivity": self.sensitivity,
               "contribution": self.contribution, "basis": self.basis}
        return out if math.isinf(self.dof) else {**out, "dof": self.dof}


def combined(components: Sequence[Component]) -> float:
    """u_c = √Σ(c_i·u_i)² (GUM (10), uncorrelated inputs)."""
    return math.sqrt(sum(c.contribution ** 2 for c in components))


RECTANGULAR_DOMINANT = 0.9  # one rectangular share at least this part of u²: the output is near-rectangular


def effective_dof(components: Sequence[Component]) -> float:
    """ν_eff = u_c⁴ / Σ (c_i·u_i)⁴/ν_i (Welch–Satterthwaite, GUM G.4.1); ∞ when every term is Type B."""
    u = combined(components)
    tail = sum(c.contribution ** 4 / c.dof for c in components if math.isfinite(c.dof) and c.dof > 0)
    return u ** 4 / tail if tail > 0 else math.inf


def coverage(components: Sequence[Component]) -> tuple[float, str]:
    """(k, what U covers): k = 2 for ≈ 95 % of a normal output; Student's t at ν_eff when a Type A
    term has few degrees of freedom (GUM G.3); and where one rectangular share dominates u² the output
    is near-rectangular, k = 2 covers all of it (its 95 % lies at 1.65·u, GUM G.6.5) — said, not claimed as 95 %."""
    u2 = combined(components) ** 2
    rect = max((c.contribution ** 2 for c in components if "rectangular" in c.basis), default=0.0)
    if u2 > 0 and rect >= RECTANGULAR_DOMINANT * u2:
        return K_COVERAGE, (f"k = 2 on a near-rectangular output (one rectangular term is {100 * rect / u2:.0f} % of u²): U covers it "
                            "entirely (its 95 % interval is ±1.65·u)")
    nu = effective_dof(components)
    if math.isfinite(nu):
        from scipy.stats import t

        k = float(t.ppf(0.975, max(nu, 1.0)))
        return k, f"k = {k:.2f}: Student's t at ν_eff = {nu:.1f} (Welch–Satterthwaite), ≈ 95 %"
    return K_COVERAGE, "k = 2: ≈ 95 % for a normal output"


def budget(value: float, unit: str, components: Sequence[Component], *, note: str = "", k: float | None = None) -> dict:
    """A result's budget as written to result.json: value, u, U = k·u, k (:func:`coverage`, unless
    given), what U covers and the components."""
    u = combined(components)
    k_rule, covers = coverage(components)
    k = k_rule if k is None else k
    out = {"value": value, "unit": unit, "u": u, "U": k * u, "k": k, "coverage": covers if k == k_rule else f"k = {k:g} (given)",
           "components": [c.as_dict() for c in components]}
    if note:
        out["note"] = note
    return out


def force_rel_u(force_class: float) -> float:
    """Relative standard uncertainty of a force from its ISO 7500-1 class: (class %)/√3."""
    return rectangular(force_class / 100.0)


def extension_u_mm(extension_mm: float, extensometer_class: float) -> float:
    """Standard uncertainty of an extension read by an ISO 9513 extensometer of this class: the
    larger of the relative bound and the absolute floor, rectangular."""
    rel_pct, floor_um = EXTENSOMETER_LIMITS.get(float(extensometer_class), (extensometer_class, 3.0 * extensometer_class))
    return rectangular(max(rel_pct / 100.0 * abs(extension_mm), floor_um / 1000.0))


def extensometer_scale_rel_u(extensometer_class: float) -> float:
    """Relative standard uncertainty of strain = ΔL/Le from an ISO 9513 class: the extension and
    the gauge length Le each within ±class % (rectangular), combined."""
    return math.hypot(rectangular(extensometer_class / 100.0), rectangular(extensometer_class / 100.0))


def measured_length_scale_rel_u(l0_mm: float, lu_mm: float, length_resolution_mm: float, *, mpe_mm: float = 0.0,
                                recovery_mm: float = 0.0, recovery_E_rel_u: float = 0.0, sample_step_mm: float = 0.0) -> float:
    """Relative standard uncertainty of a crosshead strain scaled to the measured Lu − L0 (K_l, (3.1)):
    both lengths read with the caliper's resolution and MPE; the elastic recovery at the fracture
    taken off the displacement, through its E (u(R)/R = u(E)/E); the break somewhere within the
    last sample's travel (rectangular over it). K = M/(D − R): u(K)/K = √(u(M)²/M² + u(R)² + δ²/3)/(D − R), D − R ≈ M."""
    m = abs(lu_mm - l0_mm)
    length_u = math.sqrt(2.0) * dimension_u(lu_mm, length_resolution_mm, mpe_mm)
    return math.sqrt(length_u ** 2 + (recovery_mm * recovery_E_rel_u) ** 2 + sample_step_mm ** 2 / 3.0) / m


# ---- budgets of the tension results (ISO 6892-1) -------------------------------------------------

def _force_component(force_N: float, force_class: float, per_N: float, name: str = "force") -> Component:
    return Component(f"{name} F (ISO 7500-1 class {force_class:g})", force_N, "N", force_N * force_rel_u(force_class), per_N,
                     f"±{force_class:g} % of reading, rectangular")


def dimension_u(value_mm: float, res_mm: float, mpe_mm: float = 0.0, rel_bound: float = 0.0) -> float:
    """Standard uncertainty of a measured dimension: the reading's resolution (r/√12), the
    instrument's MPE and a relative bound of the method (each ±a, rectangular), combined."""
    return math.sqrt(resolution(res_mm) ** 2 + rectangular(mpe_mm) ** 2 + rectangular(rel_bound * value_mm) ** 2)


def _dimension_basis(res_mm: float, mpe_mm: float, rel_bound: float = 0.0) -> str:
    return (f"resolution {res_mm:g} mm" + (f", MPE ±{mpe_mm:g} mm" if mpe_mm else "")
            + (f", ISO 6892-1 ±{100 * rel_bound:g} %" if rel_bound else "") + ", rectangular")


def _diameter_component(d0_mm: float, res_mm: float, sensitivity: float, name: str = "diameter d0", *, mpe_mm: float = 0.0,
                        rel_bound: float = 0.0) -> Component:
    return Component(name, d0_mm, "mm", dimension_u(d0_mm, res_mm, mpe_mm, rel_bound), sensitivity, _dimension_basis(res_mm, mpe_mm, rel_bound))


def strength_budget(strength_MPa: float, d0_mm: float, inst: Mapping, *, extra: Sequence[Component] = (), note: str = "") -> dict:
    """R = F/S0, S0 = π·d0²/4 (Rm, and the force part of Rp0.2): ∂R/∂F = 1/S0, ∂R/∂d0 = −2R/d0."""
    s0 = _area_mm2(d0_mm)
    comps = [_force_component(strength_MPa * s0, inst["force_class"], 1.0 / s0),
             _diameter_component(d0_mm, inst["diameter_resolution_mm"], -2.0 * strength_MPa / d0_mm, mpe_mm=inst.get("micrometer_mpe_mm", 0.0)),
             *extra]
    return budget(strength_MPa, "MPa", comps, note=note)


def proof_strength_budget(Rp_MPa: float, d0_mm: float, inst: Mapping, *, plastic_slope_MPa: float, strain_rel_u: float,
                          E_MPa: float, u_E_MPa: float, E_measured: bool) -> dict:
    """Rp0.2: the force and d0 as for Rm, plus the strain scale and the slope E of the offset line.

    θ = dσ/de_p at Rp0.2. A strain scale error δ moves the intersection by −θ·0.002·δ when E is
    regressed on the same strain (the elastic line scales with it), by −θ·(0.002 + Rp/E)·δ when
    E is given; an error of E moves it by θ·Rp/E²·ΔE.
    """
    lever = OFFSET if E_measured else OFFSET + Rp_MPa / E_MPa
    extra = [Component("strain scale", 1.0, "1", strain_rel_u, -plastic_slope_MPa * lever,
                       "relative; extensometer class or crosshead scale"),
             Component("E of the offset line" + (" (regression)" if E_measured else " (given)"), E_MPa, "MPa", u_E_MPa,
                       plastic_slope_MPa * Rp_MPa / E_MPa ** 2,
                       "standard error of the elastic line (its scale errors are in the terms above)" if E_measured
                       else f"given, ±{100 * HANDBOOK_E_BOUND:g} % rectangular")]
    return strength_budget(Rp_MPa, d0_mm, inst, extra=extra, note=f"plastic slope at Rp0.2 θ = {plastic_slope_MPa:.4g} MPa")


def modulus_budget(E_MPa: float, d0_mm: float, inst: Mapping, *, strain_rel_u: float, stderr_MPa: float | None) -> dict:
    """E = slope of σ = F/S0 against e: relative force scale, d0 (−2E/d0), strain scale (−E), regression."""
    comps = [Component(f"force scale (ISO 7500-1 class {inst['force_class']:g})", 1.0, "1", force_rel_u(inst["force_class"]), E_MPa,
                       "relative, rectangular"),
             _diameter_component(d0_mm, inst["diameter_resolution_mm"], -2.0 * E_MPa / d0_mm, mpe_mm=inst.get("micrometer_mpe_mm", 0.0)),
             Component("strain scale", 1.0, "1", strain_rel_u, -E_MPa, "relative; extensometer class or crosshead scale")]
    if stderr_MPa is not None:
        comps.append(Component("regression of the elastic line", E_MPa, "MPa", stderr_MPa, 1.0, "standard error of the slope"))
    return budget(E_MPa, "MPa", comps)


def uniform_elongation_budget(Ag_pct: float, Rm_MPa: float, E_MPa: float, *, strain_at_Fm_u: float, u_E_MPa: float,
                              u_Rm_MPa: float | None, flat_halfwidth: float = 0.0) -> dict:
    """Ag = 100·(e_m − Rm/E): ∂/∂e_m = 100, ∂/∂E = 100·Rm/E², ∂/∂Rm = −100/E (Rm left out, ``None``,
    when E was measured on the same force and strain: their scales cancel in Rm/E); on a flat
    maximum e_m anywhere within ±``flat_halfwidth`` (half of :func:`.iso6892.max_force_band`), rectangular."""
    e_m = Ag_pct / 100.0 + Rm_MPa / E_MPa
    comps = [Component("strain at maximum force e_m", e_m, "1", strain_at_Fm_u, 100.0, "strain measurement"),
             Component("E (elastic part removed)", E_MPa, "MPa", u_E_MPa, 100.0 * Rm_MPa / E_MPa ** 2, "E's own uncertainty")]
    if flat_halfwidth > 0:
        comps.append(Component("method: strain at Fm on a flat maximum", e_m, "1", rectangular(flat_halfwidth), 100.0,
                               f"the samples within the noise of Fm span ±{flat_halfwidth:.3g} of strain about its mid-point, rectangular"))
    if u_Rm_MPa is not None:
        comps.append(Component("Rm", Rm_MPa, "MPa", u_Rm_MPa, -100.0 / E_MPa, "budget of Rm"))
    return budget(Ag_pct, "%", comps)


def elongation_from_lengths_budget(l0_mm: float, lu_mm: float, length_resolution_mm: float, *, mpe_mm: float = 0.0) -> dict:
    """A = 100·(Lu − L0)/L0 (3.8): ∂A/∂Lu = 100/L0, ∂A/∂L0 = −100·Lu/L0² (each length read with the
    caliper's resolution and MPE)."""
    A = 100.0 * (lu_mm - l0_mm) / l0_mm
    basis = _dimension_basis(length_resolution_mm, mpe_mm)
    u = dimension_u(l0_mm, length_resolution_mm, mpe_mm)
    comps = [Component("gauge length after fracture Lu", lu_mm, "mm", u, 100.0 / l0_mm, basis),
             Component("original gauge length L0", l0_mm, "mm", u, -100.0 * lu_mm / l0_mm ** 2, basis)]
    return budget(A, "%", comps)


def elongation_from_extension_budget(A_pct: float, gauge_mm: float, extensometer_class: float) -> dict:
    """A = 100·ΔL/Le read by the extensometer: the extension (ISO 9513 bound) and Le (±class %)."""
    extension = A_pct / 100.0 * gauge_mm
    comps = [Component(f"extension ΔL (ISO 9513 class {extensometer_class:g})", extension, "mm",
                       extension_u_mm(extension, extensometer_class), 100.0 / gauge_mm, "larger of ±class % and the absolute floor, rectangular"),
             Component("extensometer gauge length Le", gauge_mm, "mm", gauge_mm * rectangular(extensometer_class / 100.0),
                       -A_pct / gauge_mm, f"±{extensometer_class:g} %, rectangular")]
    return budget(A_pct, "%", comps)


def unstated_length_rel(l0_mm: float, d0_mm: float, *, lu_mm: float | None = None, a_u: float | None = None) -> float:
    """How much lower a crosshead's strains read had its length been ISO 6892-1's L1 = L0 + 2·d0 (the dispute value
    of a machined bar's Lc) instead of the l0 taken for an unstated Lc: 1 − L0/L1 (e = Δl/L); scaled to the
    measured Lu by (3.1), whose K_l ∝ (Lu − L0 + (L − L0)·a_u)/L over L, 1 − [(Lu − L0 + 2·d0·a_u)/L1]/[(Lu − L0)/L0]."""
    L1 = l0_mm + 2.0 * d0_mm
    if lu_mm is None or a_u is None or not lu_mm > l0_mm:
        return 1.0 - l0_mm / L1
    return max(1.0 - ((lu_mm - l0_mm + 2.0 * d0_mm * a_u) / L1) / ((lu_mm - l0_mm) / l0_mm), 0.0)


def elongation_from_curve_budget(A_pct: float, terms: Mapping, strain_rel_u: float, u_E_MPa: float, u_a_u: float = 0.0,
                                 strain_basis: str = "") -> dict:
    """A read off the curve at the break (no Lu): A = 100·(e_g − s_k/E), e_g the gauge's strain at fracture
    (``terms``: identify's methods.A_from_curve). Components: the strain scale (e_L·u_rel, the crosshead's or
    extensometer's scale over its length L, carried to the gauge by L/L0), E of the elastic part (100·s_k/E²),
    the break within one sample's travel (rectangular over Δe, 100·L/L0), and over L > L0 the uniform part's a_u
    (∂e_g/∂a_u ≈ −(L − L0)/L0)."""
    e_L, s_k, E = float(terms["strain_at_fracture"]), float(terms["stress_at_fracture_MPa"]), float(terms["E_MPa"])
    L, L0 = float(terms["length_mm"]), float(terms["l0_mm"])
    a_u = terms.get("uniform_plastic_elongation")
    beyond = (L - L0) / L0 if a_u is not None and L > L0 else 0.0  # e_out's share: e_g = (e_L·L − (L − L0)·e_out)/L0
    a = float(a_u) if beyond else 0.0
    comps = [Component("strain scale at the break", e_L, "1", abs(e_L) * strain_rel_u, 100.0 * L / L0, strain_basis or "the strain source's scale"),
             # ∂A/∂E = 100·s_k/E²·(1 + (L − L0)/L0·(1 + a_u)²): the gauge's elastic part and the uniform part's
             Component("E of the elastic part removed", E, "MPa", u_E_MPa, 100.0 * s_k / E ** 2 * (1.0 + beyond * (1.0 + a) ** 2), "the rule's E"),
             Component("the break within one sample's travel", e_L, "1", abs(float(terms.get("sample_step_strain") or 0.0)) / math.sqrt(12.0),
                       100.0 * L / L0, "rectangular over the last sample's strain step")]
    if beyond:  # ∂A/∂a_u = −100·(L − L0)/L0·(1 + 2·s_k(1 + a_u)/E)
        comps.append(Component("uniform elongation beyond the marks a_u", a, "1", u_a_u, -100.0 * beyond * (1.0 + 2.0 * s_k * (1.0 + a) / E),
                               "Ag's (or du's) standard uncertainty"))
    return budget(A_pct, "%", comps)


def reduction_of_area_budget(d0_mm: float, du_mm: float, diameter_resolution_mm: float, *, mpe_mm: float = 0.0,
                             fracture_rel: float = 0.0) -> dict:
    """Z = 100·(1 − du²/d0²): ∂Z/∂du = −200·du/d0², ∂Z/∂d0 = 200·du²/d0³ (micrometer resolution and
    MPE; du also within ISO 6892-1's ±``fracture_rel`` of the pieces fitted together)."""
    Z = 100.0 * (1.0 - (du_mm / d0_mm) ** 2)
    comps = [_diameter_component(du_mm, diameter_resolution_mm, -200.0 * du_mm / d0_mm ** 2, "smallest diameter after fracture du",
                                 mpe_mm=mpe_mm, rel_bound=fracture_rel),
             _diameter_component(d0_mm, diameter_resolution_mm, 200.0 * du_mm ** 2 / d0_mm ** 3, mpe_mm=mpe_mm)]
    return budget(Z, "%", comps)


# ---- the method's own share (the elastic line, the strain zero) ---------------------------------

def offset_yield_MPa(strain, stress_MPa, E_MPa: float, offset: float = OFFSET) -> float | None:
    """Stress where ε − σ/E (the running maximum) first reaches ``offset``, interpolated; None when never."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    i = _first_at_least(strain, stress, E_MPa, offset)  # the running maximum of ε_p first reaches the offset where ε_p itself does
    if i is None:
        return None
    if i == 0:
        return float(stress[0])
    before = float(np.max(strain[:i] - stress[:i] / E_MPa))  # the running maximum at i − 1
    at = float(strain[i] - stress[i] / E_MPa)
    w = 0.0 if at == before else (offset - before) / (at - before)
    return float(stress[i - 1] + w * (stress[i] - stress[i - 1]))


def offset_interpolation_halfwidth_MPa(strain, stress_MPa, E_MPa: float, offset: float = OFFSET) -> float:
    """How far the linear interpolation of :func:`offset_yield_MPa` may be off between sparse samples:
    |σ_quad − σ_lin| at the crossing, σ_quad through the three samples about it (the next order's
    difference estimates the interpolant's error); 0 where fewer than three samples bracket it."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    i = _first_at_least(strain, stress, E_MPa, offset)
    if i is None or i < 1 or i + 1 >= strain.size:
        return 0.0
    ep = strain[i - 1: i + 2] - stress[i - 1: i + 2] / E_MPa
    sig = stress[i - 1: i + 2]
    if not (np.all(np.isfinite(ep)) and np.all(np.isfinite(sig)) and ep[0] < ep[1] < ep[2]):
        return 0.0
    lin = sig[0] + (offset - ep[0]) * (sig[1] - sig[0]) / (ep[1] - ep[0])
    # Lagrange's quadratic through the three samples, at ε_p = offset
    w = [np.prod([(offset - ep[m]) / (ep[j] - ep[m]) for m in range(3) if m != j]) for j in range(3)]
    return float(abs(float(np.dot(w, sig)) - lin))


def _first_at_least(strain: np.ndarray, stress_MPa: np.ndarray, E_MPa: float, offset: float, chunk: int = 4096) -> int | None:
    """First index where ε_p = ε − σ/E ≥ ``offset`` (None when never), read in doubling chunks:
    Rp0.2 lies early in a long record, so most of it is never computed."""
    start = 0
    while start < strain.size:
        stop = min(strain.size, start + chunk)
        hits = np.flatnonzero(strain[start:stop] - stress_MPa[start:stop] / E_MPa >= offset)
        if hits.size:
            return start + int(hits[0])
        start, chunk = stop, 2 * chunk
    return None


def offset_method_components(strain, stress_MPa, E_MPa: float, u_E_MPa: float, lines: Mapping[str, float], delta_eps0: float,
                             *, basis: str = "") -> list[Component]:
    """The method's share of an offset yield Rp0.2 read on (strain, stress): E of the offset line
    (∂Rp/∂E by central difference at E ± u), the spread of Rp over the defensible elastic lines
    (``lines``: name → E; half their range, rectangular) and the strain zero δε0 (∂Rp/∂ε0 by central
    difference of the offset at 0.002 ± δε0). Terms that cannot be read (no yield) are left out."""
    out = []
    if u_E_MPa > 0:
        hi, lo = offset_yield_MPa(strain, stress_MPa, E_MPa + u_E_MPa), offset_yield_MPa(strain, stress_MPa, E_MPa - u_E_MPa)
        if hi is not None and lo is not None:
            out.append(Component("method: E of the offset line", E_MPa, "MPa", u_E_MPa, (hi - lo) / (2.0 * u_E_MPa), basis or "the rule's E"))
    rps = {name: offset_yield_MPa(strain, stress_MPa, E) for name, E in lines.items() if E and E > 0}
    rps = {k: v for k, v in rps.items() if v is not None}
    half = (max(rps.values()) - min(rps.values())) / 2.0 if len(rps) > 1 else 0.0
    if half > 0:
        out.append(Component("method: spread over the defensible elastic lines", half, "MPa", rectangular(half), 1.0,
                             "Rp0.2 on " + ", ".join(f"{k} ({lines[k]:.0f} MPa): {v:.4g}" for k, v in rps.items()) + "; half the range, rectangular"))
    half = offset_interpolation_halfwidth_MPa(strain, stress_MPa, E_MPa)
    if half > 0:
        out.append(Component("method: interpolation between samples at the offset", half, "MPa", rectangular(half), 1.0,
                             "|quadratic − linear| through the three samples about the 0.2 % crossing, rectangular"))
    if delta_eps0 > 0:
        hi = offset_yield_MPa(strain, stress_MPa, E_MPa, OFFSET + delta_eps0)
        lo = offset_yield_MPa(strain, stress_MPa, E_MPa, max(OFFSET - delta_eps0, 0.0))
        if hi is not None and lo is not None:
            step = OFFSET + delta_eps0 - max(OFFSET - delta_eps0, 0.0)
            out.append(Component("method: strain zero and toe ε0", 0.0, "1", delta_eps0, (hi - lo) / step,
                                 "δε0 of the foot of the elastic line (line fit, curvature, toe, sample spacing; docs/methods.md §2.11)"))
    return out


def rate_component(value_MPa: float, method: str | None, material_class: str | None) -> Component:
    """The testing rate within the method's allowed range: R ∝ ė^m, the rate anywhere in the range
    (ratio r of its ends) → R within ±R·m·ln(r)/2, rectangular. ``method`` "A1"/"A2" (±20 %) or
    "B"/unknown (a decade)."""
    m = RATE_SENSITIVITY.get(material_class or "", RATE_SENSITIVITY["steel"])
    kind = "A" if method and str(method).startswith("A") else "B"
    half = value_MPa * m * math.log(RATE_RANGE[kind]) / 2.0  # ΔR = R·m·Δln ė
    return Component(f"method: testing rate within method {kind}'s range", half, "MPa", rectangular(half), 1.0,
                     f"m = {m:g} ({material_class or 'class not named: the steels'}), the rate anywhere in a ×{RATE_RANGE[kind]:.3g} range, rectangular")


def crosshead_compliance_component(Rp_MPa: float) -> Component:
    """A crosshead-only Rp0.2: the compliance model's own share, the rms relative difference from the
    extensometer's over :data:`CROSSHEAD_RP_REL_U`'s pairs."""
    return Component("method: crosshead compliance model", Rp_MPa, "MPa", Rp_MPa * CROSSHEAD_RP_REL_U, 1.0,
                     f"rms {100 * CROSSHEAD_RP_REL_U:.2g} % crosshead − extensometer over 67 pairs (42CrMoS4, docs/methods.md §2.12)")


def line_windows_E(strain, stress_MPa, window_MPa) -> dict[str, float]:
    """The slopes of the elastic line over its window's lower and upper halves (strain regressed on
    stress up to the largest stress): where the first loading is not linear they differ."""
    strain, stress = np.asarray(strain, dtype=float), np.asarray(stress_MPa, dtype=float)
    top = nan_argmax(stress) + 1
    lo, hi = float(window_MPa[0]), float(window_MPa[1])
    mid = 0.5 * (lo + hi)
    out = {}
    inside = np.flatnonzero((stress[:top] >= lo) & (stress[:top] <= hi) & np.isfinite(strain[:top]))  # one pass; each half from it
    for name, (a, b) in (("the window's lower half", (lo, mid)), ("the window's upper half", (mid, hi))):
        on = inside[(stress[inside] >= a) & (stress[inside] <= b)]
        if on.size >= 4 and np.ptp(stress[on]) > 0:
            slope = np.polyfit(stress[on], strain[on], 1)[0]  # ε = c + σ/E
            if slope > 0:
                out[name] = float(1.0 / slope)
    return out


# ---- compression ------------------------------------------------------------------------------

def friction_budget(mu: float, mu_range: Sequence[float] | None, *, others: Mapping[str, float] | None = None) -> dict | None:
    """μ: the friction method's range [lo, hi] is μ ± its standard error (the shape read ± its
    resolution and the model form's σ: ``friction_details`` mu_stderr is half of it), so u(μ) is
    half the range, normal; a note when other friction methods read μ outside μ ± U (the evidence disagrees)."""
    if not mu_range or len(mu_range) != 2 or mu_range[0] is None or mu_range[1] is None:
        return None
    lo, hi = float(mu_range[0]), float(mu_range[1])
    # u(μ) = (μ_hi − μ_lo)/2: a ±1σ interval (fe.model_form.stderr_of_range), not a pair of bounds (that was u/√3)
    comps = [Component("friction method's μ range (±1σ)", mu, "1", (hi - lo) / 2.0, 1.0,
                       f"[{lo:.4g}, {hi:.4g}]: the shape ± its resolution and the model form's σ, ±1σ")]
    out = budget(mu, "1", comps)
    outside = {k: v for k, v in (others or {}).items() if v is not None and abs(v - mu) > out["U"]}
    if outside:
        out["note"] = ("other friction methods read μ outside μ ± U: "
                       + ", ".join(f"{k} {v:.3f}" for k, v in outside.items()) + " — the methods disagree")
        out["methods_disagree"] = True
    return out


def flow_stress_budget(sigma_MPa: float, eps: float, d0_mm: float, h0_mm: float, hk_mm: float, inst: Mapping, *,
                       mu: float, u_mu: float, method: Sequence[Component] = (), mu_sensitivity: float | None = None) -> dict:
    """Compression flow stress σ at true strain ε: σ = F·h/(S0·h0) corrected for friction.

    With h = h0 − Δh = h0·e^−ε: ∂σ/∂F = h/(S0·h0), ∂σ/∂d0 = −2σ/d0, ∂σ/∂h0 = σ·Δh/(h0·h),
    ∂σ/∂Δh = −σ/h, where Δh is scaled to the measured h0 − hk (K_l), so u(Δh) = Δh·u(h0 − hk)/(h0 − hk);
    μ with ``mu_sensitivity``, ∂σ/∂μ of the correction applied (the identification's secant), else
    Siebel's ∂σ/∂μ = −σ·(d/3h)/(1 + μ·d/3h), d = d0·√(h0/h).
    """
    h = h0_mm * math.exp(-eps)
    dh = h0_mm - h
    s0 = _area_mm2(d0_mm)
    force = sigma_MPa * s0 * h0_mm / h
    siebel = d0_mm * math.sqrt(h0_mm / h) / (3.0 * h)
    res, mpe = inst["length_resolution_mm"], inst.get("caliper_mpe_mm", 0.0)
    u_len = dimension_u(h0_mm, res, mpe)
    scale_u = dh * math.sqrt(2.0) * u_len / abs(h0_mm - hk_mm)  # shortening scaled to h0 − hk (K_l)
    comps = [_force_component(force, inst["force_class"], h / (s0 * h0_mm)),
             _diameter_component(d0_mm, inst["diameter_resolution_mm"], -2.0 * sigma_MPa / d0_mm, mpe_mm=inst.get("micrometer_mpe_mm", 0.0)),
             Component("initial height h0", h0_mm, "mm", u_len, sigma_MPa * dh / (h0_mm * h), _dimension_basis(res, mpe)),
             Component("shortening Δh (scaled to h0 − hk)", dh, "mm", scale_u, -sigma_MPa / h, f"h0 and hk: {_dimension_basis(res, mpe)}"),
             (Component("friction μ", mu, "1", u_mu, mu_sensitivity, "budget of μ; the applied correction's sensitivity") if mu_sensitivity is not None
              else Component("friction μ", mu, "1", u_mu, -sigma_MPa * siebel / (1.0 + mu * siebel), "budget of μ; Siebel's sensitivity")),
             *method]
    out = budget(sigma_MPa, "MPa", comps, note=f"at true plastic strain {eps:g}")
    out["u_method"] = combined(method)  # the method's own share (E, strain zero), stated apart
    return out


def flow_point_method_components(sigma_MPa: float, slope_MPa: float, E_MPa: float | None, u_E_MPa: float, delta_eps0: float) -> list[Component]:
    """The method's share of a flow-curve point σ at a plastic strain: the E that stripped the
    elastic strain (ε_p = ε − σ/E moves by σ·δE/E², so σ by θ·σ/E²·δE) and the strain zero
    (σ by θ·δε0), θ = dσ/dε_p there."""
    out = []
    if E_MPa and u_E_MPa > 0:
        out.append(Component("method: E stripping the elastic strain", E_MPa, "MPa", u_E_MPa, slope_MPa * sigma_MPa / E_MPa ** 2, "the rule's E"))
    if delta_eps0 > 0:
        out.append(Component("method: strain zero ε0", 0.0, "1", delta_eps0, slope_MPa, "δε0 of the foot of the elastic line (§2.11)"))
    return out


CORRECTION_FORM = "method: FE model form of the friction correction"


def correction_form_components(sigma_MPa: float, correction_u_pct: float | None) -> list[Component]:
    """The friction correction's own σ at a flow-curve point (the fe_table correction's stated per-point
    uncertainty, true_curve.csv ``correction_uncertainty_pct``: the model form's share of the force, grown
    over the band before the fold-over): u = σ·u_corr/100, sensitivity 1; none where the correction states none."""
    if correction_u_pct is None or not math.isfinite(correction_u_pct) or correction_u_pct <= 0:
        return []
    return [Component(CORRECTION_FORM, sigma_MPa, "MPa", sigma_MPa * correction_u_pct / 100.0, 1.0,
                      f"the correction's stated σ at this point, {correction_u_pct:.2f} % of the stress (correction_uncertainty_pct)")]


def on_bound_reach(m: float, se: float, k: float = K_COVERAGE) -> float:
    """How far inward the constant's value (as the law fitted with its bounds, noise-free, would give it)
    can lie from its bound: the bounded fit's constant is max(bound, p) of the unbounded one p ~ N(m, se²),
    m the unbounded optimum's distance inward (≤ 0 when the bound holds it), se its standard error;
    the k-interval of p mapped through max: [bound, bound + max(0, m + k·se)] (exact for a linear model;
    0 when the noise cannot take it off its bound)."""
    return max(0.0, m + k * se)


def correlated_fit_u(func: Callable, params: Mapping[str, float], eps, stress_MPa, on_bound: Mapping[str, float] | None = None) -> dict[str, float]:
    """Standard uncertainties of a least-squares fit's constants when its residuals are correlated
    along the range (a lack of fit is a smooth residual, not independent noise).

    func(eps, **params): the law; eps, stress_MPa: the fitted points; on_bound: constant → +1
    (on its lower bound) or −1 (upper). The free constants: (JᵀJ)⁻¹·SSR/(N_eff − p) (J by central
    differences; the white s²·(JᵀJ)⁻¹ widened by N/N_eff), N_eff = N·(1 − ρ)/(1 + ρ) ≥ p + 1 from
    the residuals' lag-1 autocorrelation ρ (an AR(1) residual). A constant on its bound, the free ones
    refitted (linearised, a⊥ its inward column less its projection on the free ones'): its unbounded
    optimum lies m = a⊥·r/|a⊥|² inward (≤ 0), with se = σ_n/|a⊥|, σ²_n = Σ(Δr)²/(2(N − 1)) the noise
    alone (first differences); stated u = R/k, R = :func:`on_bound_reach` (U = R: the one-sided interval
    [bound, bound + R]), at least :data:`BOUND_REL_TOL` × its scale (the bound as the optimisers reach it).
    {} when it cannot be formed."""
    on_bound = dict(on_bound or {})
    eps, sig = np.asarray(eps, dtype=float).ravel(), np.asarray(stress_MPa, dtype=float).ravel()
    ok = np.isfinite(eps) & np.isfinite(sig)
    order = np.argsort(eps[ok])
    eps, sig = eps[ok][order], sig[ok][order]
    names = list(params)
    free = [k for k in names if k not in on_bound]
    n = eps.size
    if n < len(names) + 2:
        return {}
    with np.errstate(all="ignore"):
        r = sig - func(eps, **params)
        J = _jacobian(func, params, eps)
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        return {}
    rc = r - r.mean()
    rho = float(np.clip(np.dot(rc[:-1], rc[1:]) / np.dot(rc, rc), 0.0, 1.0)) if np.dot(rc, rc) > 0 else 0.0
    n_eff = max(n * (1.0 - rho) / (1.0 + rho), len(free) + 1.0)
    threshold = float(np.dot(r, r)) / (n_eff - len(free))  # s²·N/N_eff, s² = SSR·N_eff/(N·(N_eff − p)): N/N_eff points per piece
    Jf = J[:, [names.index(k) for k in free]]
    cov = np.linalg.pinv(Jf.T @ Jf) * threshold
    out = {k: float(math.sqrt(max(cov[i, i], 0.0))) for i, k in enumerate(free)}
    noise = float(np.sum(np.diff(r) ** 2)) / (2.0 * (n - 1))  # σ² of the noise alone: first differences cancel a smooth lack of fit (Rice 1984)
    scales = constant_scales(func, params, eps) if on_bound else {}
    for k, inward in on_bound.items():
        a = inward * J[:, names.index(k)]
        if free:
            a = a - Jf @ np.linalg.lstsq(Jf, a, rcond=None)[0]  # a⊥: the free constants absorb what they can
        aa, ar = float(np.dot(a, a)), float(np.dot(a, r))
        if aa > 0:
            reach = on_bound_reach(ar / aa, math.sqrt(noise / aa))
            out[k] = max(reach, BOUND_REL_TOL * scales.get(k, 0.0)) / K_COVERAGE
    return out


def constant_budget(value: float, stderr: float | None, stress_rel_u: float, unit: str, *, zero_shift: float | None = None,
                    lack_of_fit: float | None = None, on_bound: str | None = None, shares: Mapping[str, float] | None = None,
                    scale: float | None = None) -> dict | None:
    """A fitted constant: the fit's standard error and, for a stress (MPa), the stress scale. With
    ``zero_shift`` (the constant's move when the strain zero moves by δε0, already inside the
    widened standard error) the method's share is stated apart: fit √(se² − shift²) and the shift.
    ``shares`` (component name → u, each already inside the widened standard error in quadrature:
    compression's μ, FE model form and fit range) are stated apart the same way, one component each,
    the fit's own √(se² − shift² − Σu²). With ``lack_of_fit`` (:func:`correlated_fit_u`) where it
    exceeds the standard error (with its shares), the difference √(u_lof² − se²) is a method term:
    the standard error then reads as u_lof. ``on_bound`` ("lower"/"upper"): the constant sits on that
    bound, its fit's standard error is not its own (a covariance at a bound) and ``lack_of_fit`` is its
    reach inward over k (:func:`on_bound_reach`): the budget states it with the shift and the stress
    scale, and ``interval`` one-sided, [value, value + U]; where U passes the constant's own ``scale``
    (:func:`.laws.bounds.constant_scales`) the bound holds it and the curve does not, which a note says."""
    if on_bound:
        return _on_bound_budget(value, lack_of_fit or 0.0, stress_rel_u, unit, on_bound, zero_shift, scale)
    if (stderr is None or not math.isfinite(stderr)) and lack_of_fit is None:
        return None
    given = stderr is not None and math.isfinite(stderr)
    stderr = stderr if given else 0.0
    method = []
    if zero_shift is not None and math.isfinite(zero_shift) and 0.0 < zero_shift <= stderr:
        method = [Component("method: strain zero ε0", value, unit, zero_shift, 1.0, "the constant refitted with the strain zero moved by δε0 (§2.11)")]
        stderr = math.sqrt(stderr ** 2 - zero_shift ** 2)
    inside = [Component(name, value, unit, float(u), 1.0, "the constant refitted (docs/methods.md §4.8)")
              for name, u in (shares or {}).items() if given and u is not None and math.isfinite(u) and u > 0]
    own = math.sqrt(max(stderr ** 2 - combined(inside) ** 2, 0.0))  # se² = own² + Σ share²
    method += inside
    if lack_of_fit is not None and math.isfinite(lack_of_fit) and lack_of_fit > stderr:
        method.append(Component("method: constants over the fit range", value, unit, math.sqrt(lack_of_fit ** 2 - stderr ** 2), 1.0,
                                "the fit's covariance with its residuals correlated along the range (lack of fit; a constant on "
                                "its bound as far as it could move), beyond the standard error (§2.12)"))
    comps = [Component("fit (standard error)", value, unit, own, 1.0, "least squares"), *method]
    if unit == "MPa":
        comps.append(Component("stress scale (force class, d0)", 1.0, "1", stress_rel_u, value, "relative"))
    out = budget(value, unit, comps)
    out["u_method"] = combined(method)
    if method and method[-1].name == "method: constants over the fit range" and out["U"] >= abs(value):
        out["note"] = ("over this fit range the law's constants trade off (their correlations): this one alone is not determined, "
                       "the set of them is")
    return out


def _on_bound_budget(value: float, u_bound: float, stress_rel_u: float, unit: str, side: str, zero_shift: float | None,
                     scale: float | None = None) -> dict:
    """The budget of a constant on its ``side`` bound: its reach inward (u = reach/k), the strain zero's
    shift (its move under εp + δε0) and, for a stress, the stress scale; ``interval`` is one-sided:
    [value, value + U] on a lower bound, [value − U, value] on an upper one (``one_sided``: the side)."""
    method = [Component(f"method: constant on its {side} bound", value, unit, u_bound, 1.0,
                        "how far inward the law fitted with its bounds could place it: the unbounded optimum (the free "
                        "constants refitted) + k·its standard error, at least the bound's tolerance; one-sided (§2.12)")]
    if zero_shift is not None and math.isfinite(zero_shift) and zero_shift > 0.0:
        method.append(Component("method: strain zero ε0", value, unit, zero_shift, 1.0, "the constant refitted with the strain zero moved by δε0 (§2.11)"))
    comps = [*method]
    if unit == "MPa":
        comps.append(Component("stress scale (force class, d0)", 1.0, "1", stress_rel_u, value, "relative"))
    note = f"on its {side} bound: the value lies on the bound's inward side only, within U of it"
    if scale is not None and scale > 0 and K_COVERAGE * combined(method) > scale:  # reaches past the law's own size for it
        note += ("; over this fit range the law's constants trade off (their correlations): the bound holds this one, the curve "
                 "does not determine it, the set of them is")
    out = budget(value, unit, comps, note=note)
    out["u_method"] = combined(method)
    out["interval"] = [value, value + out["U"]] if side == "lower" else [value - out["U"], value]
    out["one_sided"] = side
    return out


# ---- Monte Carlo propagation (GUM Supplement 1) -------------------------------------------------

def monte_carlo(model: Callable[..., np.ndarray], inputs: Mapping[str, tuple[float, float, str]], *, n: int = 200_000,
                seed: int = 1) -> tuple[float, float, tuple[float, float]]:
    """Propagate distributions through ``model(**samples)`` (JCGM 101:2008): inputs name →
    (value, standard uncertainty, 'normal' | 'rectangular'). Returns (mean, standard deviation,
    the probabilistically symmetric 95 % coverage interval)."""
    rng = np.random.default_rng(seed)
    draws = {}
    for name, (value, u, kind) in inputs.items():
        if kind == "rectangular":
            half = u * math.sqrt(3.0)
            draws[name] = rng.uniform(value - half, value + half, n)
        elif kind == "normal":
            draws[name] = rng.normal(value, u, n)
        else:
            raise ValueError(f"{name}: distribution must be normal or rectangular, not {kind!r}")
    y = np.asarray(model(**draws), dtype=float)
    lo, hi = np.quantile(y, [0.025, 0.975])
    return float(y.mean()), float(y.std(ddof=1)), (float(lo), float(hi))

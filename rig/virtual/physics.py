"""Physical model of the virtual rig: specimen, frame, crosshead, furnace (docs/methods.md §1–§5).

Pure and deterministic given a seed: :class:`RigModel` is advanced in model time by
:meth:`RigModel.step` / :meth:`RigModel.advance_to`; the devices of :mod:`rig.virtual` only
read it. Conventions:

* Forces and displacements are positive in the loading direction for both tests (the
  compression test runs in a reversing cage, so the load cell sees the same sign).
* Quasi-static mechanics: the specimen state is a function of the crosshead position and
  the plastic history (largest plastic strain reached), solved exactly at each step.
* Flow stress is Johnson–Cook (:mod:`flowcurve.rig.virtual.materials`) at the *nominal* strain rate of the
  test, v/Lc (tension: the parallel length, l0 unless given) or v/h0 (compression), and at the furnace's true temperature.
* Tension: uniform deformation with plastic incompressibility, F = F0·exp(−εp) (elastic
  volume change neglected), until the force maximum (Considère, dσ/dεp = σ); then a neck
  strains alone while the rest unloads elastically; fracture when the neck strain reaches the
  material's fracture strain (force drops to zero). With the default
  ``tension_response="fe"`` the neck is that of CalculiX necking runs
  (:mod:`flowcurve.rig.virtual.neck_response`, the rig's own copy and interpolation, read
  from the material's Considère strain on with its hardening ratio θ/σ): the neck's mean axial
  stress is the flow stress times the FE's factor β(ε_n − ε_u), the elongation is the rest's
  Lc·(e^(ε_u + σ/E) − 1) (Lc the parallel length) plus the FE neck's d0·λ(ε_n − ε_u) (runs of l0/d0 = 5;
  the neck within the gauge marks, whose Lu is l0·e^ε_u plus it), and the
  neck's dk and profile radius measured after the test are the FE's. These are not the
  formulas the identification's neck corrections invert, so the demo shows their real error.
  The specimen itself stays ideal up to Considère (an FE run's imperfection ends the uniform
  elongation earlier: the rig's Ag is the perfect specimen's). ``tension_response="bridgman"`` keeps the analytic mirror:
  a neck zone of initial length ``neck_length_mm`` (default d0), Bridgman's factor
  (1 + 2R/a)·ln(1 + a/(2R)) with Le Roy's curvature a/R = 1.1·(ε − ε_u) (Le Roy et al. 1981)
  given a smooth onset a/R = 1.1·δ²/(δ + ε_u), δ = ε − ε_u (a neck that curves at once,
  linear in δ, would make the force rise past Considère), and the reported neck radius from
  the same law, so a Bridgman correction with the measured radius recovers the flow stress at
  fracture exactly.
* Compression (default ``compression_response="fe"``): flow stress × volume-constant area ×
  the force factor F/(σ_f·A) of CalculiX upsetting runs, and the bulge measured after the test
  from the same runs' ΔR/h (:mod:`flowcurve.rig.virtual.fe_response`, the rig's own copy and
  interpolation), at the rig's μ, h0/d0 and the material's effective hardening exponent. These
  are not the formulas the identification's seed and slab methods invert, so the demo shows
  their real error. ``compression_response="slab"`` keeps the analytic mirror: the exact
  Coulomb slab factor 2(e^c − c − 1)/c², c = 2μr/h, and the seed's bulge regression (3.18).
* Frame: crosshead = specimen Δl + P/C_frame.
* Furnace: C·dT/dt = P_heater·u(t − τ_dead) − (k1 + k2·(T − T_amb))·(T − T_amb).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from flowcurve.errors import ConfigError
from flowcurve.rig.virtual.materials import Material, get_material
from flowcurve.rig.virtual.responses import COMPRESSION_RESPONSES, TENSION_RESPONSES

log = logging.getLogger(__name__)

LE_ROY_SLOPE = 1.1  # a/R = 1.1·(ε − ε_u), Le Roy et al. (1981)
NECK_REUSE_STRAIN = 1e-6  # the FE neck is made again only when the Considère strain moves more


def neck_a_over_R(eps_u, eps):
    """# Le Roy a/R = 1.1·(ε − ε_u) with a smooth onset: 1.1·δ²/(δ + ε_u), δ = ε − ε_u ≥ 0."""
    d = np.maximum(np.asarray(eps, float) - eps_u, 0.0)
    return LE_ROY_SLOPE * d * d / (d + max(eps_u, 1e-6))


# ----------------------------------------------------------------------------- closed forms
def slab_friction_factor(c):
    """# exact Coulomb slab solution p_avg/σ_f = 2(e^c − c − 1)/c², c = 2μr/h (→ 1 at c = 0)."""
    c = np.asarray(c, dtype=float)
    small = np.abs(c) < 1e-6
    cs = np.where(small, 1.0, c)
    exact = 2.0 * (np.expm1(cs) - cs) / cs**2
    return np.where(small, 1.0 + c / 3.0, exact)


def bridgman_factor(a_over_R):
    """# Bridgman σ_avg/σ_eq = (1 + 2R/a)·ln(1 + a/(2R)) (→ 1 for a flat neck)."""
    x = np.asarray(a_over_R, dtype=float)
    small = x < 1e-8
    xs = np.where(small, 1.0, x)
    exact = (1.0 + 2.0 / xs) * np.log1p(xs / 2.0)
    return np.where(small, 1.0 + x / 4.0, exact)


def bulge_delta_R_over_h(eps_p, mu):
    """# (3.18) ΔR/h = 0.0683·εp^0.83·(1 − exp(−26.7·μ^1.53))."""
    return 0.0683 * np.asarray(eps_p, float) ** 0.83 * (1.0 - np.exp(-26.7 * np.asarray(mu, float) ** 1.53))


def furnace_steady_state_C(power_W, ambient_C, k1_W_per_K, k2_W_per_K2):
    """Steady state of C·dT/dt = P − (k1 + k2·θ)·θ, θ = T − T_amb: k2θ² + k1θ − P = 0."""
    if k2_W_per_K2 == 0:
        return ambient_C + power_W / k1_W_per_K
    theta = (-k1_W_per_K + math.sqrt(k1_W_per_K**2 + 4.0 * k2_W_per_K2 * power_W)) / (2.0 * k2_W_per_K2)
    return ambient_C + theta


# ----------------------------------------------------------------------------- specimen
@dataclass(frozen=True)
class Specimen:
    """Specimen geometry in mm. Tension uses d0, l0 (gauge), the parallel length (l0 unless
    given: the crosshead sees it all, the neck lies within the gauge marks) and, with the
    ``bridgman`` tension response, the neck-zone length; compression uses d0, h0."""

    test: str = "tension"
    d0_mm: float = 6.0
    l0_mm: float = 30.0
    h0_mm: float = 6.982
    neck_length_mm: float | None = None
    parallel_length_mm: float | None = None

    def __post_init__(self):
        if self.test not in ("tension", "compression"):
            raise ConfigError(f"specimen.test: must be 'tension' or 'compression', got '{self.test}'")
        for key in ("d0_mm", "l0_mm", "h0_mm"):
            if not getattr(self, key) > 0:
                raise ConfigError(f"specimen.{key}: must be positive, got {getattr(self, key)}")
        if self.parallel_length_mm is not None and not self.parallel_length_mm >= self.l0_mm:
            raise ConfigError(f"specimen.parallel_length_mm: must be at least l0 = {self.l0_mm:g} mm (the gauge marks lie on it), "
                              f"got {self.parallel_length_mm}")

    @property
    def area0_mm2(self) -> float:
        """The initial cross-section, mm²."""
        return math.pi * self.d0_mm**2 / 4.0

    @property
    def neck_mm(self) -> float:
        """The neck's length, mm (d0 unless given, at most l0)."""
        ln = self.d0_mm if self.neck_length_mm is None else self.neck_length_mm
        return min(ln, self.l0_mm)

    @property
    def length0_mm(self) -> float:
        """The initial gauge length (tension) or height (compression), mm."""
        return self.l0_mm if self.test == "tension" else self.h0_mm

    @property
    def parallel_mm(self) -> float:
        """The parallel length the crosshead stretches (tension), mm: l0 unless given."""
        return self.l0_mm if self.parallel_length_mm is None else self.parallel_length_mm

    @classmethod
    def tension(cls, d0_mm=6.0, l0_mm=30.0, neck_length_mm=None, parallel_length_mm=None) -> "Specimen":
        """GOST 1497 type IV (docs/methods.md §3): d0 6 mm, l0 30 mm (parallel length l0 unless given)."""
        return cls("tension", d0_mm=d0_mm, l0_mm=l0_mm, neck_length_mm=neck_length_mm, parallel_length_mm=parallel_length_mm)

    @classmethod
    def compression(cls, d0_mm=5.989, h0_mm=6.982) -> "Specimen":
        """GOST 25.503 type III cylinder of the seed's worked example."""
        return cls("compression", d0_mm=d0_mm, h0_mm=h0_mm)

    @classmethod
    def from_geometry(cls, test: str, geometry_mm: dict[str, float]) -> "Specimen":
        """The bar of a test's geometry (mm, the record's keys: ``d0_mm`` with ``l0_mm`` and
        optionally ``parallel_length_mm``, or ``h0_mm``): what the virtual rig simulates, in the
        host's process (``flowcurve run``) and in its own (``flowcurve rig virtual``)."""
        g = geometry_mm
        if test == "tension":
            return cls.tension(g["d0_mm"], g["l0_mm"], parallel_length_mm=g.get("parallel_length_mm"))
        return cls.compression(g["d0_mm"], g["h0_mm"])

    @property
    def geometry_mm(self) -> dict[str, float]:
        """The bar's geometry (mm, the record's keys), the parallel length always stated in tension."""
        if self.test == "tension":
            return {"d0_mm": self.d0_mm, "l0_mm": self.l0_mm, "parallel_length_mm": self.parallel_mm}
        return {"d0_mm": self.d0_mm, "h0_mm": self.h0_mm}


@dataclass
class SpecimenState:
    """Mechanical state: force, plastic strains, phase."""

    force_N: float = 0.0
    eps_p: float = 0.0  # plastic strain of the uniform part (tension) / of the cylinder
    eps_neck: float = 0.0  # plastic strain in the neck zone (tension)
    necked: bool = False
    fractured: bool = False
    elongation_mm: float = 0.0  # specimen Δl over its parallel length (tension) or shortening h0 − h (compression)


class Mechanics:
    """Quasi-static specimen + frame: solves the state for a crosshead position.

    ``flow(eps_p)`` is the flow stress at the test's rate and temperature, which the caller
    sets through :meth:`set_conditions`.
    """

    def __init__(self, material: Material, specimen: Specimen, frame_stiffness_N_per_um: float,
                 friction_mu: float = 0.1, compression_response: str = "fe", tension_response: str = "fe"):
        if not frame_stiffness_N_per_um > 0:
            raise ConfigError(f"rig.frame_stiffness_N_per_um: must be positive, got {frame_stiffness_N_per_um}")
        if friction_mu < 0:
            raise ConfigError(f"friction_mu: must be ≥ 0, got {friction_mu}")
        if compression_response not in COMPRESSION_RESPONSES:
            raise ConfigError(f"compression_response: must be one of {', '.join(COMPRESSION_RESPONSES)}, got '{compression_response}'")
        if tension_response not in TENSION_RESPONSES:
            raise ConfigError(f"tension_response: must be one of {', '.join(TENSION_RESPONSES)}, got '{tension_response}'")
        self.compression_response = compression_response
        self.tension_response = tension_response
        self.material = material
        self.specimen = specimen
        self.C_N_per_mm = frame_stiffness_N_per_um * 1000.0
        self.mu = friction_mu
        self.state = SpecimenState()
        self.strain_rate_per_s = 0.0
        self.temperature_C = material.T_ref_C
        self._considere: tuple[tuple[float, float], float] | None = None
        self._fe_curve: tuple[np.ndarray, np.ndarray] | None = None  # (ε grid, force factor) at this μ, h0/d0, n
        self._neck = None  # the FE neck (neck_response.NeckCurve) at the material's Considère strain

    # -- FE compression response ------------------------------------------------------------
    def fe_lookup(self) -> tuple[float, float, float]:
        """(μ, h0/d0, n) at which the FE response is read: the rig's friction, the specimen's
        slenderness and the material's effective Swift exponent (rate and temperature enter the
        Johnson–Cook law as a factor, so they do not change it)."""
        from flowcurve.rig.virtual.fe_response import effective_hardening_exponent

        m = self.material
        n = effective_hardening_exponent(lambda e: m.flow_stress(e, 0.0, m.T_ref_C))
        return self.mu, self.specimen.h0_mm / self.specimen.d0_mm, n

    def _fe_factor_curve(self) -> tuple[np.ndarray, np.ndarray]:
        """The force factor along the table's strain grid at :meth:`fe_lookup` (computed once;
        linear between grid strains, as the table's interpolation is)."""
        if self._fe_curve is None:
            from flowcurve.rig.virtual.fe_response import UpsettingResponse

            table = UpsettingResponse.load()
            mu, h0_d0, n = self.fe_lookup()
            for message in table.in_range(mu, h0_d0, n):
                log.warning("virtual rig: %s", message)
            self._fe_curve = (table.strain, table.force_factor_at(mu, h0_d0, n, table.strain))
        return self._fe_curve

    def friction_force_factor(self, eps_p: float) -> float:
        """F/(σ_f·π r²) at plastic strain eps_p: the FE force factor, or the slab factor."""
        s = self.specimen
        if self.compression_response == "slab":
            r = s.d0_mm / 2.0 * math.exp(eps_p / 2.0)
            h = s.h0_mm * math.exp(-eps_p)
            return float(slab_friction_factor(2.0 * self.mu * r / h))
        strain, factor = self._fe_factor_curve()
        return float(np.interp(eps_p, strain, factor))  # held beyond the table's last strain

    def bulge_dR_over_h(self, eps_p: float) -> float:
        """ΔR/h of the barrel at plastic strain eps_p: the FE runs', or the seed's (3.18)."""
        if self.compression_response == "slab":
            return float(bulge_delta_R_over_h(eps_p, self.mu))
        from flowcurve.rig.virtual.fe_response import UpsettingResponse

        return float(UpsettingResponse.load().bulge_at(*self.fe_lookup(), eps_p))

    # -- conditions -----------------------------------------------------------------
    def set_conditions(self, strain_rate_per_s: float, temperature_C: float) -> None:
        """Set the strain rate (1/s) and temperature (°C) the flow stress is taken at."""
        self.strain_rate_per_s = strain_rate_per_s
        self.temperature_C = temperature_C

    def flow(self, eps_p):
        """The flow stress at ``eps_p`` under the current conditions, MPa."""
        return float(self.material.flow_stress(eps_p, self.strain_rate_per_s, self.temperature_C))

    @property
    def fracture_strain(self) -> float:
        """The fracture strain under the current conditions."""
        return self.material.fracture_strain_at(self.strain_rate_per_s, self.temperature_C)

    def considere_strain(self) -> float:
        """Plastic strain at the force maximum of uniform tension: dσ/dεp = σ.

        Remembered for the last (rate, temperature): every step of a test at constant
        conditions asks again, and the root search is most of a step's cost.
        """
        key = (self.strain_rate_per_s, self.temperature_C)
        if self._considere is None or self._considere[0] != key:
            self._considere = (key, self._solve_considere())
        return self._considere[1]

    def _solve_considere(self) -> float:
        m = self.material
        g = lambda e: float(m.hardening_slope(e, self.strain_rate_per_s, self.temperature_C)) - self.flow(e)
        lo, hi = 1e-9, 1e-3
        while g(hi) > 0:
            lo, hi = hi, hi * 2.0
            if hi > 50:
                return math.inf
        return brentq(g, lo, hi, xtol=1e-12)

    # -- tension --------------------------------------------------------------------
    def _tension_uniform(self, eps_p: float, sigma: float) -> tuple[float, float]:
        """(force, crosshead) of a uniform specimen at plastic strain eps_p, true stress sigma."""
        s, E = self.specimen, self.material.E_MPa
        force = sigma * s.area0_mm2 * math.exp(-eps_p)  # F = F0·exp(−εp)
        dl = s.parallel_mm * math.expm1(eps_p + sigma / E)
        return force, dl + force / self.C_N_per_mm

    # -- FE tension response ------------------------------------------------------------
    def fe_neck(self):
        """The FE neck (:class:`~flowcurve.rig.virtual.neck_response.NeckCurve`) at the material's
        Considère strain (made once per strain, to 1e-6: rate and temperature scale the
        Johnson–Cook law and leave it unchanged, but the root search moves in its last digits)."""
        eps_u = self.considere_strain()
        if self._neck is None or abs(self._neck.considere_strain - eps_u) > NECK_REUSE_STRAIN:
            from flowcurve.rig.virtual.neck_response import TensionResponse

            m, rate, T = self.material, self.strain_rate_per_s, self.temperature_C
            ratio = lambda e: m.hardening_slope(e, rate, T) / m.flow_stress(e, rate, T)  # noqa: E731  θ/σ
            self._neck = TensionResponse.load().curve(eps_u, ratio, fracture_delta=self.fracture_strain - eps_u)
            if self.fracture_strain - eps_u > self._neck.table_end:
                log.warning("virtual rig: the fracture strain %.3g lies %.2f beyond the FE necking runs' last neck strain: "
                            "the neck is continued with their slope", self.fracture_strain, self.fracture_strain - eps_u - self._neck.table_end)
        return self._neck

    def neck_profile_a_over_R(self, eps_u: float, eps_n: float) -> float:
        """a/R of the neck profile: the FE runs', or Le Roy's with the smooth onset."""
        if self.tension_response == "bridgman":
            return float(neck_a_over_R(eps_u, eps_n))
        return float(self.fe_neck().a_over_R_at(eps_n - eps_u))

    def neck_extension_mm(self, eps_u: float, eps_n: float) -> float:
        """Plastic elongation the neck adds beyond the uniform Lc·(e^ε_u − 1): the FE neck's
        d0·λ(ε_n − ε_u), or the neck zone's L_n·(e^ε_n − e^ε_u)."""
        s = self.specimen
        if self.tension_response == "bridgman":
            return s.neck_mm * (math.exp(eps_n) - math.exp(eps_u))
        return s.d0_mm * float(self.fe_neck().elongation_over_d0_at(eps_n - eps_u))

    def _tension_necked(self, eps_u: float, eps_n: float, force: float) -> float:
        """Crosshead of a necked specimen carrying ``force``."""
        s, E = self.specimen, self.material.E_MPa
        sig_u = force / (s.area0_mm2 * math.exp(-eps_u))
        if self.tension_response == "bridgman":
            sig_n = force / (s.area0_mm2 * math.exp(-eps_n))
            dl = (s.parallel_mm - s.neck_mm) * math.expm1(eps_u + sig_u / E) + s.neck_mm * math.expm1(eps_n + sig_n / E)
        else:  # the FE's λ was taken under load: the neck's own elastic stretch is in it
            dl = s.parallel_mm * math.expm1(eps_u + sig_u / E) + self.neck_extension_mm(eps_u, eps_n)
        return dl + force / self.C_N_per_mm

    def _tension_unloaded(self, eps_u: float, eps_n: float) -> float:
        """Elongation of the necked specimen's parallel length without load (plastic only)."""
        return self.specimen.parallel_mm * math.expm1(eps_u) + self.neck_extension_mm(eps_u, eps_n)

    def neck_force(self, eps_u: float, eps_n: float) -> float:
        """Force carried by the neck at strain eps_n: σ_flow·β·F0·exp(−εn), β the FE factor or Bridgman's at Le Roy's a/R."""
        if self.tension_response == "bridgman":
            beta = float(bridgman_factor(neck_a_over_R(eps_u, eps_n)))
        else:
            beta = float(self.fe_neck().factor_at(eps_n - eps_u))
        return self.flow(eps_n) * beta * self.specimen.area0_mm2 * math.exp(-eps_n)

    def _tension_solve(self, x: float) -> SpecimenState:
        st = self.state
        s = self.specimen
        if st.fractured:
            return st
        eps_f = self.fracture_strain
        if not st.necked:
            eps_hist = st.eps_p
            slack = s.parallel_mm * math.expm1(eps_hist)
            if x <= slack:
                return SpecimenState(0.0, eps_hist, eps_hist, False, False, slack)
            sig_y = self.flow(eps_hist)
            if self._tension_uniform(eps_hist, sig_y)[1] >= x:  # elastic
                sig = brentq(lambda q: self._tension_uniform(eps_hist, q)[1] - x, 0.0, sig_y, xtol=1e-10)
                f, xc = self._tension_uniform(eps_hist, sig)
                return SpecimenState(f, eps_hist, eps_hist, False, False, xc - f / self.C_N_per_mm)
            eps_u_c = self.considere_strain()  # (only past yield: it is a root search)
            eps_end = min(eps_u_c, eps_f)
            x_end = self._tension_uniform(eps_end, self.flow(eps_end))[1]
            if x < x_end:
                e = brentq(lambda q: self._tension_uniform(q, self.flow(q))[1] - x, eps_hist, eps_end, xtol=1e-13)
                f, xc = self._tension_uniform(e, self.flow(e))
                return SpecimenState(f, e, e, False, False, xc - f / self.C_N_per_mm)
            if eps_f <= eps_u_c:  # fracture before necking
                return SpecimenState(0.0, eps_f, eps_f, False, True, s.parallel_mm * math.expm1(eps_f))
            st = SpecimenState(self.neck_force(eps_u_c, eps_u_c), eps_u_c, eps_u_c, True, False)
        # necked
        eps_u, eps_hist = st.eps_p, st.eps_neck
        p_y = self.neck_force(eps_u, eps_hist)
        unloaded = self._tension_unloaded(eps_u, eps_hist)
        if x <= unloaded:
            return SpecimenState(0.0, eps_u, eps_hist, True, False, unloaded)
        if self._tension_necked(eps_u, eps_hist, p_y) >= x:  # elastic
            f = brentq(lambda p: self._tension_necked(eps_u, eps_hist, p) - x, 0.0, p_y, xtol=1e-9)
            return SpecimenState(f, eps_u, eps_hist, True, False, x - f / self.C_N_per_mm)
        xn = lambda e: self._tension_necked(eps_u, e, self.neck_force(eps_u, e)) - x
        if xn(eps_f) <= 0:
            return SpecimenState(0.0, eps_u, eps_f, True, True, self._tension_unloaded(eps_u, eps_f))
        e = brentq(xn, eps_hist, eps_f, xtol=1e-13)
        f = self.neck_force(eps_u, e)
        return SpecimenState(f, eps_u, e, True, False, x - f / self.C_N_per_mm)

    def tension_fracture_crosshead(self) -> float:
        """Crosshead position at which the specimen breaks (at the present conditions)."""
        eps_f, eps_u = self.fracture_strain, self.considere_strain()
        if eps_f <= eps_u:
            return self._tension_uniform(eps_f, self.flow(eps_f))[1]
        eps_u = self.state.eps_p if self.state.necked else eps_u
        return self._tension_necked(eps_u, eps_f, self.neck_force(eps_u, eps_f))

    # -- compression ----------------------------------------------------------------
    def compression_force(self, eps_p: float, sigma: float) -> float:
        """P = σ·π r²·f(εp), r = r0·e^{εp/2 + νσ/E} (the plastic flow keeps the volume, the elastic
        lateral strain νσ/E widens it): f the FE force factor or the slab 2(e^c − c − 1)/c², c = 2μr/h."""
        m = self.material
        r = self.specimen.d0_mm / 2.0 * math.exp(eps_p / 2.0 + m.nu * sigma / m.E_MPa)
        return sigma * math.pi * r * r * self.friction_force_factor(eps_p)

    def _compression_x(self, eps_p: float, sigma: float) -> tuple[float, float]:
        s = self.specimen
        force = self.compression_force(eps_p, sigma)
        shortening = -s.h0_mm * math.expm1(-(eps_p + sigma / self.material.E_MPa))
        return force, shortening + force / self.C_N_per_mm

    def compression_crosshead(self, eps_p: float) -> float:
        """Crosshead position at which plastic strain eps_p is reached under load."""
        return self._compression_x(eps_p, self.flow(eps_p))[1]

    def _compression_solve(self, x: float) -> SpecimenState:
        s = self.specimen
        eps_hist = self.state.eps_p
        slack = -s.h0_mm * math.expm1(-eps_hist)
        if x <= slack:
            return SpecimenState(0.0, eps_hist, 0.0, False, False, slack)
        sig_y = self.flow(eps_hist)
        if self._compression_x(eps_hist, sig_y)[1] >= x:
            sig = brentq(lambda q: self._compression_x(eps_hist, q)[1] - x, 0.0, sig_y, xtol=1e-10)
        else:
            hi = max(eps_hist, 1e-3)
            while self.compression_crosshead(hi) < x:
                hi *= 2.0
                if hi > 20:
                    raise ConfigError("compression: crosshead beyond any reachable specimen strain")
            eps_hist = brentq(lambda q: self.compression_crosshead(q) - x, eps_hist, hi, xtol=1e-13)
            sig = self.flow(eps_hist)
        f, xc = self._compression_x(eps_hist, sig)
        return SpecimenState(f, eps_hist, 0.0, False, False, xc - f / self.C_N_per_mm)

    # -- common ---------------------------------------------------------------------
    def solve(self, crosshead_mm: float) -> SpecimenState:
        """Update and return the state for the crosshead position (history kept)."""
        if self.specimen.test == "tension":
            self.state = self._tension_solve(crosshead_mm)
        else:
            self.state = self._compression_solve(crosshead_mm)
        return self.state

    def post_test_measurements(self) -> dict[str, str]:
        """What the operator measures on the unloaded specimen, as ``post.*`` record keys."""
        s, st = self.specimen, self.state
        out: dict[str, str] = {}
        if s.test == "tension":
            eps_u, eps_n = st.eps_p, st.eps_neck
            out["post.du_mm"] = f"{s.d0_mm * math.exp(-eps_u / 2.0):.4f}"
            if not st.fractured:  # an unbroken bar has no fracture values (Lu, dk, the neck's radius at fracture)
                return out
            lu = s.l0_mm * math.exp(eps_u) + (self.neck_extension_mm(eps_u, eps_n) if st.necked else 0.0)  # the gauge marks: the neck within them
            dk = s.d0_mm * math.exp(-eps_n / 2.0)
            out["post.lu_mm"] = f"{lu:.4f}"
            out["post.dk_mm"] = f"{dk:.4f}"
            if eps_n - eps_u > 1e-6:
                out["post.neck_radius_mm"] = f"{(dk / 2.0) / self.neck_profile_a_over_R(eps_u, eps_n):.4f}"
        else:
            eps = st.eps_p
            hk = s.h0_mm * math.exp(-eps)
            dn = s.d0_mm * math.sqrt(s.h0_mm / hk)  # (3.17) volume constancy
            dmax = dn + 2.0 * hk * self.bulge_dR_over_h(eps)  # FE ΔR/h, or (3.18)
            out["post.hk_mm"] = f"{hk:.4f}"
            out["post.dmax_mm"] = f"{dmax:.4f}"
            out["post.smax_mm2"] = f"{math.pi * dmax**2 / 4.0:.4f}"
        return out


# ----------------------------------------------------------------------------- furnace
@dataclass(frozen=True)
class FurnaceParams:
    """First-order furnace with dead time and temperature-dependent losses."""

    ambient_C: float = 20.0
    heater_power_W: float = 6000.0  # 24 V × 250 A transformer
    heat_capacity_J_per_K: float = 3000.0
    loss_W_per_K: float = 1.0
    loss_W_per_K2: float = 0.0038  # losses grow with temperature (radiation, convection)
    dead_time_s: float = 5.0
    thermocouple_noise_C: float = 0.1
    max_step_s: float = 0.5

    def steady_state_C(self, power_fraction: float = 1.0) -> float:
        """The furnace's steady temperature at ``power_fraction`` of the heater power, °C."""
        return furnace_steady_state_C(self.heater_power_W * power_fraction, self.ambient_C,
                                      self.loss_W_per_K, self.loss_W_per_K2)


class Furnace:
    """Furnace temperature driven by the heater relay (the DCON module's DO0)."""

    def __init__(self, params: FurnaceParams = FurnaceParams(), initial_C: float | None = None):
        self.p = params
        self.temperature_C = params.ambient_C if initial_C is None else float(initial_C)
        self.time_s = 0.0
        self.commanded_on = False
        self.relay_stuck_on = False
        self._switches: list[tuple[float, bool]] = [(-math.inf, False)]  # relay state history

    @property
    def relay_on(self) -> bool:
        """Whether the relay conducts (commanded on or stuck on)."""
        return self.commanded_on or self.relay_stuck_on

    def set_heater(self, on: bool) -> None:
        """Command the relay (takes effect after the dead time)."""
        self.commanded_on = bool(on)
        self._record()

    def set_relay_stuck(self, stuck: bool) -> None:
        """Set the relay's stuck-on fault."""
        self.relay_stuck_on = bool(stuck)
        self._record()

    def _record(self) -> None:
        if self._switches[-1][1] != self.relay_on:
            self._switches.append((self.time_s, self.relay_on))

    def _power_at(self, t: float) -> float:
        """Heater power acting at time t: relay state at t − dead time."""
        td = t - self.p.dead_time_s
        on = False
        for ts, state in self._switches:
            if ts <= td:
                on = state
            else:
                break
        return self.p.heater_power_W if on else 0.0

    def _rate(self, T: float, power: float) -> float:
        theta = T - self.p.ambient_C
        return (power - (self.p.loss_W_per_K + self.p.loss_W_per_K2 * theta) * theta) / self.p.heat_capacity_J_per_K

    def step(self, dt: float) -> None:
        """Advance by dt seconds (RK4, input piecewise constant over sub-steps ≤ max_step_s)."""
        remaining = dt
        while remaining > 1e-12:
            h = min(remaining, self.p.max_step_s)
            power = self._power_at(self.time_s + h / 2.0)
            T = self.temperature_C
            k1 = self._rate(T, power)
            k2 = self._rate(T + h * k1 / 2, power)
            k3 = self._rate(T + h * k2 / 2, power)
            k4 = self._rate(T + h * k3, power)
            self.temperature_C = T + h * (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
            self.time_s += h
            remaining -= h
        # forget switches older than the dead time (keep the last one before it)
        cut = self.time_s - self.p.dead_time_s
        while len(self._switches) > 1 and self._switches[1][0] <= cut:
            self._switches.pop(0)


# ----------------------------------------------------------------------------- rig model
class RigModel:
    """Specimen + frame + crosshead + furnace + sensor noise, advanced in model time.

    ``speed_mm_per_s`` is the crosshead speed; the crosshead moves only between
    :meth:`start_crosshead` and :meth:`stop_crosshead`, and stops by itself at fracture or
    at ``stroke_limit_mm`` (default: none for tension, the crosshead at εp = 0.68 for
    compression, the seed's worked example). ``compression_response`` is ``"fe"`` (default:
    force factor and bulge from CalculiX runs) or ``"slab"`` (the slab factor and the seed's
    (3.18): the analytic mirror of the identification's slab and seed methods);
    ``tension_response`` is ``"fe"`` (default: the neck of CalculiX necking runs) or
    ``"bridgman"`` (Bridgman's factor with Le Roy's a/R: the mirror of the neck corrections).
    """

    def __init__(self, material: str | Material = "12Kh18N12M3TL", test: str = "tension",
                 specimen: Specimen | None = None, *, speed_mm_per_s: float = 0.01,
                 frame_stiffness_N_per_um: float = 136.0, friction_mu: float = 0.1,
                 furnace: FurnaceParams = FurnaceParams(), initial_temperature_C: float | None = None,
                 force_noise_N: float = 3.0, counts_per_mm: float = 100.0,
                 stroke_limit_mm: float | None = None, seed: int = 0, compression_response: str = "fe",
                 tension_response: str = "fe"):
        self.material = get_material(material)
        if specimen is None:
            specimen = Specimen.tension() if test == "tension" else Specimen.compression()
        if specimen.test != test:
            raise ConfigError(f"specimen: a {specimen.test} specimen given for a {test} test")
        if not speed_mm_per_s > 0:
            raise ConfigError(f"speed_mm_per_s: must be positive, got {speed_mm_per_s}")
        self.test = test
        self.specimen = specimen
        self.speed_mm_per_s = float(speed_mm_per_s)
        self.frame_stiffness_N_per_um = float(frame_stiffness_N_per_um)
        self.mechanics = Mechanics(self.material, specimen, frame_stiffness_N_per_um, friction_mu, compression_response,
                                   tension_response)
        self.furnace = Furnace(furnace, initial_temperature_C)
        self.force_noise_N = float(force_noise_N)
        self.counts_per_mm = float(counts_per_mm)
        self.rng = np.random.default_rng(seed)
        self.time_s = 0.0
        self.crosshead_mm = 0.0
        self.moving = False
        self.thermocouple_open = False
        self.events: list[tuple[float, str]] = []
        self._loading_C_s, self._loading_s = 0.0, 0.0  # ∫T dt and ∫dt while the crosshead moves
        self._update_conditions()
        if test == "tension" and tension_response == "fe":
            self.mechanics.fe_neck()  # made now, not in the model step that starts the test (the devices wait on it)
        if stroke_limit_mm is None and test == "compression":
            stroke_limit_mm = self.mechanics.compression_crosshead(0.68)
        self.stroke_limit_mm = math.inf if stroke_limit_mm is None else float(stroke_limit_mm)

    # -- derived ----------------------------------------------------------------------
    @property
    def nominal_strain_rate_per_s(self) -> float:
        """v/Lc (tension: the parallel length, l0 unless given; ISO 6892-1 ė_Lc) or v/h0
        (compression): the rate of the Johnson–Cook rate term."""
        return self.speed_mm_per_s / (self.specimen.parallel_mm if self.test == "tension" else self.specimen.h0_mm)

    @property
    def state(self) -> SpecimenState:
        """The specimen's state."""
        return self.mechanics.state

    @property
    def force_N(self) -> float:
        """True (noise-free) force in N."""
        return self.mechanics.state.force_N

    @property
    def temperature_C(self) -> float:
        """The furnace's temperature, °C."""
        return self.furnace.temperature_C

    @property
    def loading_temperature_C(self) -> float:
        """The furnace's mean temperature while the crosshead moved (the temperature the flow
        stress was made at; the furnace cools after the heater goes off); now, before it moved."""
        return self._loading_C_s / self._loading_s if self._loading_s > 0 else self.furnace.temperature_C

    @property
    def fractured(self) -> bool:
        """Whether the specimen has fractured."""
        return self.mechanics.state.fractured

    def _update_conditions(self) -> None:
        self.mechanics.set_conditions(self.nominal_strain_rate_per_s, self.furnace.temperature_C)

    # -- commands ---------------------------------------------------------------------
    def start_crosshead(self) -> None:
        """Start the crosshead (unless fractured or at the stroke limit)."""
        if not self.fractured and self.crosshead_mm < self.stroke_limit_mm:
            self.moving = True
            self.events.append((self.time_s, "crosshead_start"))

    def set_speed(self, speed_mm_per_s: float) -> None:
        """The crosshead's speed from now on, mm/s (the rate term follows: v / Lc or v / h0)."""
        if not (speed_mm_per_s > 0 and math.isfinite(speed_mm_per_s)):
            raise ConfigError(f"speed_mm_per_s: must be positive, got {speed_mm_per_s}")
        self.speed_mm_per_s = float(speed_mm_per_s)
        self._update_conditions()

    def stop_crosshead(self) -> None:
        """Stop the crosshead."""
        if self.moving:
            self.moving = False
            self.events.append((self.time_s, "crosshead_stop"))

    def set_heater(self, on: bool) -> None:
        """Switch the heater ``on`` or off."""
        self.furnace.set_heater(on)

    # -- time -------------------------------------------------------------------------
    def step(self, dt: float) -> None:
        """Advance the model by dt seconds of model time."""
        if dt < 0:
            raise ValueError("time runs forward only")
        self.furnace.step(dt)
        self._update_conditions()
        if self.moving:
            self._loading_C_s += self.furnace.temperature_C * dt
            self._loading_s += dt
            target = self.crosshead_mm + self.speed_mm_per_s * dt
            limit = self.stroke_limit_mm
            if self.test == "tension" and not self.fractured:
                limit = min(limit, self.mechanics.tension_fracture_crosshead())
            if target >= limit:
                target = limit
                self.moving = False
                self.crosshead_mm = target
                self.mechanics.solve(target + (1e-9 if limit < self.stroke_limit_mm else 0.0))
                self.events.append((self.time_s + dt, "fracture" if self.fractured else "stroke_limit"))
            else:
                self.crosshead_mm = target
                self.mechanics.solve(target)
        else:
            self.mechanics.solve(self.crosshead_mm)
        self.time_s += dt

    def advance_to(self, t: float) -> None:
        """Advance to model time t (no-op if t is not later than the present)."""
        if t > self.time_s:
            self.step(t - self.time_s)

    # -- sensors ----------------------------------------------------------------------
    def measured_force_N(self) -> float:
        """Load-cell force: true force plus Gaussian noise of ``force_noise_N``."""
        return self.force_N + (self.rng.normal(0.0, self.force_noise_N) if self.force_noise_N > 0 else 0.0)

    def encoder_counts(self) -> int:
        """Quantised crosshead position (incremental encoder: whole counts passed)."""
        return int(math.floor(self.crosshead_mm * self.counts_per_mm + 1e-9))

    def thermocouple_C(self) -> float:
        """Thermocouple reading (°C) with noise; +inf when the thermocouple is open."""
        if self.thermocouple_open:
            return math.inf
        noise = self.furnace.p.thermocouple_noise_C
        return self.furnace.temperature_C + (self.rng.normal(0.0, noise) if noise > 0 else 0.0)

    def post_test_measurements(self) -> dict[str, str]:
        """The specimen's post-test measurements, as the record writes them."""
        return self.mechanics.post_test_measurements()

"""A virtual rotating-sphere adhesiometer: the friction law (2.25) run forward (docs/methods.md §6).

A polished sphere of tool material is pressed into the work material with the normal force
N_z and turned slowly (31.5 rpm); the dynamometer reads N_z and the moment M_z, and the
imprint radius r is measured afterwards (seed 004 section 3.2.2). This device produces those
readings from known friction constants, so that the identification can be checked against
the truth. It is written independently of :mod:`flowcurve.identification.compression.adhesion` (the rig
layer does not import it):

* the imprint radius comes from the indentation of an elastic–plastic half-space by a sphere:
  Hertz up to first yield (p_m = 1.1·Y), then the expanding-cavity form p_m ∝ ln a up to
  Tabor's fully plastic p_m = 3·Y
  (K. L. Johnson, *Contact Mechanics*, 1985, §6.3; D. Tabor, *The Hardness of Metals*, 1951),
  solved for a by root finding; Y is the surface flow stress of the work material at the
  test temperature (the virtual material's Johnson–Cook flow stress at an assumed surface
  strain);
* the moment is the shear stress of (2.25) integrated numerically (adaptive quadrature) over
  the imprint under the Hertz pressure σ_n(ρ) = p0·√(1 − ρ²/a²) (the seed's (3.43)), with the
  real contact ratio of plastic contact K_r = min(1, σ_n/(3Y)) (Bowden & Tabor) or full
  contact (K_r = 1): τ(ρ) = μ_d·σ_n + K_r·(τ0 + β(T)·σ_n/K_r), M_z = ∫∫ ρ·τ dA;
* the readings carry the instrument's scatter: relative noise on N_z and M_z, absolute noise
  on the measured imprint radius; the M_z(t) trace has a run-in and a ripple at the
  spindle frequency.

Units: N, mm, MPa, °C; the readings are returned in the adhesion table's units (N, N·m, mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from flowcurve.errors import DeviceError
from flowcurve.rig.virtual.materials import Material, get_material

DEVICE = "virtual adhesiometer"
SPINDLE_RPM = 31.5  # seed 3.2.2
FIRST_YIELD_X = 3.0  # E*a/(YR) at first yield under a sphere, p_m = 1.1Y (Johnson 1985, §6.3)
FULLY_PLASTIC_X = 40.0  # E*a/(YR) of a fully plastic imprint, p_m = 3Y (Johnson 1985, fig. 6.15)


@dataclass(frozen=True)
class FrictionTruth:
    """The constants of (2.25) the virtual work material really has."""

    tau0_MPa: float = 80.0
    beta0: float = 0.05
    k_b_per_C: float = 0.05 / 300.0
    theta_k_C: float = 700.0
    mu_d: float = 0.02

    def beta(self, temperature_C: float) -> float:
        """β(T) = β0 − k_b·max(0, T − θ_k) of (2.25)."""
        return self.beta0 - self.k_b_per_C * max(0.0, temperature_C - self.theta_k_C)


@dataclass
class VirtualAdhesiometer:
    """Sphere, work material, friction truth and instrument scatter of one virtual adhesiometer.

    contact: ``"bowden_tabor"`` (real contact ratio min(1, σ_n/(3Y))) or ``"full"`` (K_r = 1).
    surface_strain: the plastic strain of the work-hardened surface layer (assumed) at which the
        material's flow stress is taken as the surface flow stress Y.
    """

    material: Material | str = "steel45"
    truth: FrictionTruth = field(default_factory=FrictionTruth)
    sphere_diameter_mm: float = 8.0
    sphere_E_MPa: float = 510e3  # WC–Co hard alloy (assumed)
    sphere_nu: float = 0.22
    sphere_Rp_um: float = 0.20
    sphere_tm: float = 0.50
    contact: str = "bowden_tabor"
    surface_strain: float = 0.1
    force_noise_rel: float = 0.0
    moment_noise_rel: float = 0.0
    radius_noise_um: float = 0.0
    seed: int | None = 0

    def __post_init__(self):
        self.material = get_material(self.material)
        if self.contact not in ("bowden_tabor", "full"):
            raise DeviceError(DEVICE, f"contact must be 'bowden_tabor' or 'full', not {self.contact!r}")
        self._rng = np.random.default_rng(self.seed)

    # -- physics ---------------------------------------------------------------------------------
    @property
    def sphere_radius_mm(self) -> float:
        """The sphere's radius, mm."""
        return self.sphere_diameter_mm / 2.0

    @property
    def contact_modulus_MPa(self) -> float:
        """E* = 1/((1 − ν1²)/E1 + (1 − ν2²)/E2) (Hertz)."""
        m = self.material
        return 1.0 / ((1.0 - self.sphere_nu**2) / self.sphere_E_MPa + (1.0 - m.nu**2) / m.E_MPa)

    def surface_flow_stress_MPa(self, temperature_C: float) -> float:
        """Y of the work-hardened surface at the test temperature (quasi-static)."""
        return float(self.material.flow_stress(self.surface_strain, 0.0, temperature_C))

    def mean_pressure_MPa(self, a_mm: float, temperature_C: float) -> float:
        """p_m(a): Hertz up to first yield, then logarithmic in a to the fully plastic 3Y.

        x = E*·a/(Y·R): elastic (p_m = 4E*a/(3πR)) up to x = 3 where p_m = 1.1Y; fully plastic
        p_m = 3Y from x = 40; between, p_m/Y = 1.1 + 1.9·ln(x/3)/ln(40/3), the expanding-cavity
        form (slope 0.73 against the cavity model's 2/3) pinned to those two limits (Johnson,
        Contact Mechanics, 1985, §6.3 and fig. 6.15).
        """
        Y = self.surface_flow_stress_MPa(temperature_C)
        R, E = self.sphere_radius_mm, self.contact_modulus_MPa
        x = E * a_mm / (Y * R)
        if x <= FIRST_YIELD_X:
            return 4.0 * E * a_mm / (3.0 * math.pi * R)
        if x >= FULLY_PLASTIC_X:
            return 3.0 * Y
        return Y * (1.1 + 1.9 * math.log(x / FIRST_YIELD_X) / math.log(FULLY_PLASTIC_X / FIRST_YIELD_X))

    def imprint_radius_mm(self, force_N: float, temperature_C: float) -> float:
        """The contact radius a at which π a²·p_m(a) = N_z (a permanent imprint needs first yield passed)."""
        from scipy.optimize import brentq

        Y = self.surface_flow_stress_MPa(temperature_C)
        a = brentq(lambda x: math.pi * x * x * self.mean_pressure_MPa(x, temperature_C) - force_N, 1e-6, 50.0, xtol=1e-12)
        if self.contact_modulus_MPa * a / (Y * self.sphere_radius_mm) <= FIRST_YIELD_X:
            raise DeviceError(DEVICE, f"{force_N:g} N leaves no permanent imprint at {temperature_C:g} C (the contact stays elastic)")
        return a

    def shear_stress_MPa(self, normal_MPa, temperature_C: float):
        """τ of (2.25) on the nominal area: μ_d·σ_n + K_r·(τ0 + β(T)·σ_nr), σ_nr = σ_n/K_r."""
        t = self.truth
        sn = np.asarray(normal_MPa, dtype=float)
        if self.contact == "full":
            ratio = np.ones_like(sn)
        else:
            ratio = np.minimum(1.0, sn / (3.0 * self.surface_flow_stress_MPa(temperature_C)))
        real = np.divide(sn, ratio, out=np.zeros_like(sn), where=ratio > 0)
        return t.mu_d * sn + ratio * (t.tau0_MPa + t.beta(temperature_C) * real)

    def moment_N_mm(self, force_N: float, a_mm: float, temperature_C: float) -> float:
        """M_z = 2π∫₀ᵃ ρ²·τ(σ_n(ρ)) dρ under the Hertz pressure, by adaptive quadrature."""
        from scipy.integrate import quad

        p0 = 3.0 * force_N / (2.0 * math.pi * a_mm**2)

        def integrand(rho):
            """The moment's integrand at radius ``rho`` (mm), N."""
            normal = p0 * math.sqrt(max(1.0 - (rho / a_mm) ** 2, 0.0))
            return 2.0 * math.pi * rho**2 * float(self.shear_stress_MPa(normal, temperature_C))

        kinks = None  # where the real contact ratio reaches 1 (σ_n = 3Y), the integrand has a kink
        if self.contact == "bowden_tabor":
            flow_pressure = 3.0 * self.surface_flow_stress_MPa(temperature_C)
            if p0 > flow_pressure:
                kinks = [a_mm * math.sqrt(1.0 - (flow_pressure / p0) ** 2)]
        value, _ = quad(integrand, 0.0, a_mm, points=kinks, limit=200, epsabs=0.0, epsrel=1e-11)
        return value

    # -- a test ----------------------------------------------------------------------------------
    def run_test(self, force_N: float, temperature_C: float, test_id: str, *, trace_seconds: float = 0.0,
                 sample_rate_hz: float = 50.0) -> tuple[dict, pd.DataFrame | None]:
        """One test: the table row (N, N·m, mm, °C, sphere) and, if asked, its M_z(t) trace."""
        a = self.imprint_radius_mm(force_N, temperature_C)
        moment = self.moment_N_mm(force_N, a, temperature_C) * 1e-3  # N·m
        rng = self._rng
        row = {"test_id": test_id,
               "normal_force_N": force_N * (1.0 + self.force_noise_rel * rng.standard_normal()),
               "moment_N_m": moment * (1.0 + self.moment_noise_rel * rng.standard_normal()),
               "imprint_radius_mm": a + 1e-3 * self.radius_noise_um * rng.standard_normal(),
               "temperature_C": float(temperature_C),
               "sphere_diameter_mm": self.sphere_diameter_mm, "sphere_Rp_um": self.sphere_Rp_um, "sphere_tm": self.sphere_tm}
        trace = None
        if trace_seconds > 0:
            t = np.arange(0.0, trace_seconds, 1.0 / sample_rate_hz)
            run_in = 1.0 - np.exp(-t / (0.05 * trace_seconds))
            ripple = 0.01 * np.sin(2.0 * math.pi * SPINDLE_RPM / 60.0 * t)
            trace = pd.DataFrame({"time_s": t, "moment_N_m": row["moment_N_m"] * run_in * (1.0 + ripple)
                                  + 0.002 * moment * rng.standard_normal(t.size)})
        return row, trace

    def run_series(self, forces_N, temperatures_C, *, prefix: str = "A", trace_seconds: float = 0.0
                   ) -> tuple[pd.DataFrame, dict[str, pd.DataFrame]]:
        """Tests at every (force, temperature) pair given (two sequences of equal length)."""
        rows, traces = [], {}
        for i, (force, temp) in enumerate(zip(forces_N, temperatures_C, strict=True), start=1):
            row, trace = self.run_test(float(force), float(temp), f"{prefix}{i:02d}", trace_seconds=trace_seconds)
            rows.append(row)
            if trace is not None:
                traces[row["test_id"]] = trace
        return pd.DataFrame(rows), traces

    def table_meta(self) -> dict[str, object]:
        """Header of the adhesion table these tests make."""
        return {"material": self.material.name, "instrument": DEVICE, "sphere.diameter_mm": self.sphere_diameter_mm,
                "sphere.Rp_um": self.sphere_Rp_um, "sphere.tm": self.sphere_tm}

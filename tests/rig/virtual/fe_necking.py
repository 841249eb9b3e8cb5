"""Independent CalculiX necking runs of the virtual materials, for tests/rig/virtual/test_neck_response.py.

The same CAX8R model as the rig's table (12×40, imperfection 0.005, d0 6, l0 30, ≈ 0.05 mm
increments) but the material's own Johnson–Cook law, E and ν — laws the table was not made
from (it holds Swift laws, K 1000, ε0 0.002, E 200 GPa, ν 0.3).
"""

from __future__ import annotations

import math

import numpy as np

D0_MM, L0_MM = 6.0, 30.0
IMPERFECTION = 0.005
NECK_ELONGATION_MM = 4.0  # beyond the uniform elongation: past the virtual materials' fracture strains


def fe_necking_run(material, strain_rate_per_s: float, considere_strain: float, temperature_C: float = 20.0):
    """(run, ε_n per increment) of ``material`` at the rig's rate and temperature."""
    from flowcurve.identification.fe.model.tension import TensionModel, simulate_tension

    flow = lambda e: material.flow_stress(e, strain_rate_per_s, temperature_C)  # noqa: E731
    elongation = L0_MM * math.expm1(considere_strain) + NECK_ELONGATION_MM
    m = TensionModel.from_law(D0_MM, L0_MM, elongation, flow, E_MPa=material.E_MPa, nu=material.nu, nr=12, nz=40,
                              imperfection=IMPERFECTION, increments=int(math.ceil(elongation / 0.05)), surface=True)
    run = simulate_tension(m, require_complete=False, timeout_s=1800.0)
    a = run.neck_radius_mm
    a0 = D0_MM / 2.0 * (1.0 - IMPERFECTION)
    eps_n = 2.0 * np.log(a0 / a) - 2.0 * material.nu * run.force_N / (math.pi * a * a) / material.E_MPa  # plastic: elastic contraction out
    return run, eps_n

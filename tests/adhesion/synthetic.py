"""Synthetic adhesiometer series: the virtual adhesiometer's tests written as tables."""

from __future__ import annotations

import numpy as np

from flowcurve.record.adhesion import read_adhesion_table, write_adhesion_table
from flowcurve.rig.virtual.adhesiometer import FrictionTruth, VirtualAdhesiometer

TRUTH = FrictionTruth(tau0_MPa=80.0, beta0=0.05, k_b_per_C=1.0e-4, theta_k_C=650.0, mu_d=0.02)
COLD_LOADS_N = np.geomspace(5.0, 1300.0, 24)  # first yield to fully plastic on an 8 mm sphere in steel 45
HOT_LOADS_N = np.array([200.0, 400.0, 800.0])


def virtual_table(path, *, contact: str, moment_noise_rel: float, radius_noise_um: float, hot: bool = False,
                  seed: int = 3, flow_stress_for_hot: bool = False, truth: FrictionTruth = TRUTH):
    """A table of 24 room-temperature tests (and 3 loads at each of 600, 700, 800 °C if ``hot``)."""
    device = VirtualAdhesiometer(truth=truth, contact=contact, moment_noise_rel=moment_noise_rel,
                                 radius_noise_um=radius_noise_um, seed=seed)
    forces = list(COLD_LOADS_N)
    temps = [20.0] * len(forces)
    if hot:
        for t in (600.0, 700.0, 800.0):
            forces += list(HOT_LOADS_N)
            temps += [t] * len(HOT_LOADS_N)
    data, traces = device.run_series(forces, temps)
    if flow_stress_for_hot:
        data["flow_stress_MPa"] = [device.surface_flow_stress_MPa(t) if t >= 600.0 else np.nan for t in temps]
    write_adhesion_table(path, data, device.table_meta(), traces)
    return read_adhesion_table(path), device


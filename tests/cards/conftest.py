"""Synthetic series fits for the card tests: curves generated from a known Johnson–Cook law
(table 3.2, 12Kh18N12M3TL; table 1.1 elastic and thermal constants)."""

import json

import numpy as np
import pytest

LAW = dict(A=105.0, B=1392.0, n=0.642, C=0.01, m=0.517, rate0=1e-3, T_ref=20.0, T_melt=1400.0)


def jc_MPa(eps_p, rate, T, law=LAW):
    """Johnson–Cook written out independently of the package under test."""
    eps_p = np.asarray(eps_p, dtype=float)
    t_star = min(max((T - law["T_ref"]) / (law["T_melt"] - law["T_ref"]), 0.0), 1.0)
    rate_term = 1.0 + law["C"] * max(np.log(rate / law["rate0"]), 0.0)
    return (law["A"] + law["B"] * eps_p ** law["n"]) * rate_term * (1.0 - t_star ** law["m"])


def make_fit(temperatures=(20.0, 400.0), rates=(1e-3, 1e-2), points=300, friction=0.11, **extra):
    curves = []
    for T in temperatures:
        for r in rates:
            e = np.linspace(0.002, 0.25, points)
            curves.append({"temperature_C": T, "strain_rate_per_s": r, "true_plastic_strain": e.tolist(),
                           "true_stress_MPa": jc_MPa(e, r, T).tolist()})
    fit = {
        "material": "12Kh18N12M3TL", "A_MPa": LAW["A"], "B_MPa": LAW["B"], "n": LAW["n"], "C": LAW["C"],
        "m": LAW["m"], "ref_strain_rate_per_s": LAW["rate0"], "ref_temperature_C": LAW["T_ref"],
        "melt_temperature_C": LAW["T_melt"], "A_MPa_stderr": 2.1, "B_MPa_stderr": 35.0, "n_stderr": 0.01,
        "range": {"plastic_strain": [0.002, 0.25], "strain_rate_per_s": [min(rates), max(rates)],
                  "temperature_C": [min(temperatures), max(temperatures)]},
        "source_records": ["c20_v1.csv", "c20_v2.csv", "c400_v1.csv"], "method": "least squares (series)",
        "E_MPa": 194000.0, "poisson": 0.25, "density_kg_per_m3": 7820.0, "specific_heat_J_per_kgK": 462.0,
        "curves": curves,
    }
    if friction is not None:
        fit["friction_mu"] = friction
    fit.update(extra)
    return fit


@pytest.fixture
def fit_file(tmp_path):
    def write(**kwargs):
        path = tmp_path / "fit.json"
        path.write_text(json.dumps(make_fit(**kwargs)), encoding="utf-8")
        return path

    return write

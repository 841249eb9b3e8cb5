"""Synthetic series fits for the card tests: curves generated from a known Johnson–Cook law
(table 3.2, 12Kh18N12M3TL; table 1.1 elastic and thermal constants)."""

import json

import numpy as np
import pandas as pd
import pytest

LAW = dict(A=105.0, B=1392.0, n=0.642, C=0.01, m=0.517, rate0=1e-3, T_ref=20.0, T_melt=1400.0)


def jc_MPa(eps_p, rate, T, law=LAW):
    """Johnson–Cook written out independently of the package under test."""
    eps_p = np.asarray(eps_p, dtype=float)
    t_star = min(max((T - law["T_ref"]) / (law["T_melt"] - law["T_ref"]), 0.0), 1.0)
    rate_term = 1.0 + law["C"] * max(np.log(rate / law["rate0"]), 0.0)
    return (law["A"] + law["B"] * eps_p ** law["n"]) * rate_term * (1.0 - t_star ** law["m"])


def make_fit(folder, temperatures=(20.0, 400.0), rates=(1e-3, 1e-2), points=300, friction=0.11, law=LAW,
             conditions=None, curve=None, last_strain=0.25, **extra):
    """A fit.json following docs/fit-json.md, its curve tables written under ``folder``/curves.
    ``conditions``: (temperature, rate) pairs instead of every temperature with every rate;
    ``curve(eps, rate, T)``: the measured stress (default the law itself)."""
    curve = curve or (lambda e, r, T: jc_MPa(e, r, T, law))
    conditions = conditions or [(T, r) for T in temperatures for r in rates]
    temperatures = sorted({T for T, _ in conditions})
    rates = sorted({r for _, r in conditions})
    curves = []
    (folder / "curves").mkdir(parents=True, exist_ok=True)
    for T, r in conditions:
        e = np.linspace(0.002, last_strain, points)
        name = f"curves/T{T:g}C_rate{r:.0e}.csv"
        pd.DataFrame({"true_plastic_strain": e, "true_stress_MPa": curve(e, r, T)}).to_csv(folder / name, index=False)
        curves.append({"temperature_C": T, "strain_rate_per_s": r, "file": name, "records": [f"T{T:g}_r{r:g}"],
                       "plastic_strain": [0.002, last_strain], "model_stress_at_zero_strain_MPa": float(jc_MPa(0.0, r, T, law))})
    fit = {"schema": "flowcurve-fit/1", "model": "johnson_cook",
        "material": "12Kh18N12M3TL", "A_MPa": law["A"], "B_MPa": law["B"], "n": law["n"], "C": law["C"],
        "m": law["m"], "ref_strain_rate_per_s": law["rate0"], "ref_temperature_C": law["T_ref"],
        "melt_temperature_C": law["T_melt"], "A_MPa_stderr": 2.1, "B_MPa_stderr": 35.0, "n_stderr": 0.01,
        "range": {"plastic_strain": [0.002, last_strain], "strain_rate_per_s": [min(rates), max(rates)],
                  "temperature_C": [min(temperatures), max(temperatures)]},
        "records": [{"name": "c20_v1", "source": "/lab/c20_v1.csv"}, {"name": "c20_v2", "source": "/lab/c20_v2.csv"},
                    {"name": "c400_v1", "source": "/lab/c400_v1.csv"}],
        "method": "global", "fixed": {},
        "E_MPa": 194000.0, "poisson_ratio": 0.25, "density_kg_per_m3": 7820.0, "specific_heat_J_per_kgK": 462.0,
        "curves": curves,
    }
    if friction is not None:
        fit["friction_mu"] = friction
    fit.update(extra)
    return fit


@pytest.fixture
def fit_file(tmp_path):
    def write(**kwargs):
        path = tmp_path / "fit" / "fit.json"
        path.parent.mkdir(exist_ok=True)
        path.write_text(json.dumps(make_fit(path.parent, **kwargs)), encoding="utf-8")
        return path

    return write

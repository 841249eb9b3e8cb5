"""The two true-stress forms of tension against the input law, on CalculiX records of an austenitic steel.

    python bench/tension_true_stress_forms.py

A 12Kh18N10T-like Johnson–Cook law (A 250, B 1300 MPa, n 0.55: uniform to e ≈ 0.48) is pulled 18 mm on
l0 30 in the product's own necking model (10×40 CAX8R, a 0.4 % cosine taper; :func:`tension_case_model`
with a longer pull) and written as a crosshead record with frame compliance, encoder steps and force noise
(:func:`tension_record`). The record is identified with ``true_stress="constant_volume"`` (the default) and
``"gost_3_6"`` (the seed's (3.4)–(3.6)); printed: each form's true stress over the input law, in %, at
engineering strains 0.1–0.4 (within the uniform range), and the largest deviation over the uniform range.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from flowcurve.identification.fe.synthetic import RECORD_FIRST_INCREMENT, johnson_cook_flow, tension_record
from flowcurve.identification.fe.model.tension import TensionModel, simulate_tension
from flowcurve.identification.tension.identify import identify_tension

AUSTENITIC = partial(johnson_cook_flow, A=250.0, B=1300.0, n=0.55)  # 12Kh18N10T-like, E 200 GPa
ELONGATION_MM = 18.0  # of the 30 mm gauge length: past Fm (Considère: e 0.52) into the neck
E_POINTS = (0.1, 0.2, 0.3, 0.35, 0.4)


def austenitic_record():
    """The CalculiX record (cached by the solver cache after the first run)."""
    model = TensionModel.from_law(6.0, 30.0, ELONGATION_MM, AUSTENITIC, nr=10, nz=40, imperfection=0.004, increments=180,
                                  first_increment=RECORD_FIRST_INCREMENT)
    return tension_record(simulate_tension(model, timeout_s=3600.0), material="12Kh18N10T (CalculiX)")


def deviation_table(record) -> dict:
    """For each form: engineering strain → true stress / input law − 1 (%), and the uniform-range maximum."""
    out = {}
    for form in ("constant_volume", "gost_3_6"):
        curves = identify_tension(record, true_stress=form).curves["true"]
        eps_t = curves["true_strain"].to_numpy()
        eps_p, sig = curves["true_plastic_strain"].to_numpy(), curves["true_stress_MPa"].to_numpy()
        dev = 100.0 * (sig / AUSTENITIC(eps_p) - 1.0)
        e = np.expm1(eps_t)
        plastic = eps_p > 0.01
        out[form] = {"at": {x: float(np.interp(x, e, dev)) if x <= e[-1] else None for x in E_POINTS},
                     "max_pct": float(np.max(np.abs(dev[plastic]))), "e_uniform": float(e[-1])}
    return out


def main() -> None:
    table = deviation_table(austenitic_record())
    print(f"uniform range up to e = {table['constant_volume']['e_uniform']:.3f}")
    print("| e | " + " | ".join(f"{x:g}" for x in E_POINTS) + " | max over εp > 0.01 |")
    print("|---|" + "---|" * (len(E_POINTS) + 1))
    for form, row in table.items():
        cells = [f"{row['at'][x]:+.2f} %" if row["at"][x] is not None else "past Fm" for x in E_POINTS]
        print(f"| {form} | " + " | ".join(cells) + f" | {row['max_pct']:.2f} % |")


if __name__ == "__main__":
    main()

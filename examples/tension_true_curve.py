"""From the engineering curve to the true stress–strain curve and a hardening law.

Up to the force maximum the specimen deforms uniformly, so the true stress is the
engineering stress times (1 + e) (constant volume; docs/methods.md §3.2); past it a neck
forms and the fracture point is corrected for the neck's triaxiality (Davidenkov, §3.4). The
Johnson–Cook static law σ = A + B·εp^n is fitted to the true curve over the uniform range
plus the corrected fracture point (docs/methods.md §3.5, §5.1).

Run: python examples/tension_true_curve.py
"""

from pathlib import Path

import numpy as np

from flowcurve.identification.identify import identify
from flowcurve.record.importers import load_record

RECORD = Path(__file__).parent / "data" / "46NT71.csv"


def main() -> None:
    ident = identify(load_record(RECORD), true_stress="constant_volume")
    result, curve = ident.result, ident.true_curve
    law = result["hardening"]
    eps_p, stress = curve["true_plastic_strain"].to_numpy(), curve["true_stress_MPa"].to_numpy()
    uniform = eps_p <= np.log(1 + result["Ag_pct"] / 100)
    print(f"true curve: {len(curve)} points, true plastic strain 0 … {eps_p.max():.4f}")
    print(f"true stress at the force maximum: {stress[uniform].max():.1f} MPa (Rm {result['Rm_MPa']:.1f} MPa, Ag {result['Ag_pct']:.2f} %)")
    print(f"fracture: true strain {result['fracture_true_strain']:.4f}, true stress {result['fracture_true_stress_MPa']:.1f} MPa (neck-corrected)")
    print(f"Johnson-Cook static: A {law['A_MPa']:.1f} MPa, B {law['B_MPa']:.1f} MPa, n {law['n']:.4f} "
          f"(fit error max {law['fit_error_pct']:.2f} %, rms {law['rms_error_pct']:.2f} %)")
    for e in (0.01, 0.03, 0.05):
        sigma = law["A_MPa"] + law["B_MPa"] * e ** law["n"]  # the fitted law
        print(f"at true plastic strain {e:.2f}: law {sigma:.1f} MPa, curve {np.interp(e, eps_p, stress):.1f} MPa")


if __name__ == "__main__":
    main()

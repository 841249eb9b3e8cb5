"""The model form of the friction methods that read μ from the barrel alone (issue: the non-default
methods' μ says how sure it is): each method fed the barrels of the CalculiX upsetting table
(identification/fe/model/data, the project's own ccx runs) and its μ compared with the run's.

    python bench/friction_model_form.py

Per run of the table (μ 0.05–0.2, every h0/d0, n, ε0, at ε 0.3/0.5/0.7 where the run reached it):
the bulge ΔR/h at ε made into a specimen (d0 10 mm, dmax = d_n + 2ΔR, no top face measured) and
read by ``bulge_regression`` (3.19) and ``ebrahimi_najafizadeh``. Printed: (μ_method − μ)/μ, mean and
rms per h0/d0 × n and over all; the rms over all is :data:`identification.friction.MU_MODEL_FORM`.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from flowcurve.errors import IdentificationError  # noqa: E402
from flowcurve.identification.compression import friction as fr  # noqa: E402
from flowcurve.identification.fe.model.table import UpsettingTable  # noqa: E402

MUS = (0.05, 0.2)  # the μ range measured (the table's runs within it)
STRAINS = (0.3, 0.5, 0.7)
D0_MM = 10.0


def relative_errors(method: str, table: UpsettingTable | None = None) -> np.ndarray:
    """Rows (μ, h0/d0, n, ε0, ε, (μ_method − μ)/μ) over the table's runs in :data:`MUS` (nan: the method cannot read it)."""
    # dmax = d_n + 2·ΔR, ΔR = (ΔR/h)·hk, hk = h0·e^(−ε) (3.29), (3.31)
    table = table or UpsettingTable.load()
    rows = []
    for i, mu in enumerate(table.mu):
        if not MUS[0] <= mu <= MUS[1]:
            continue
        for (j, h0_d0), (k, n), (m, eps0) in ((a, b, c) for a in enumerate(table.h0_d0) for b in enumerate(table.n) for c in enumerate(table.eps0)):
            for eps in STRAINS:
                if table.reached[i, j, k, m] < eps:
                    continue
                h0 = h0_d0 * D0_MM
                hk = h0 * math.exp(-eps)
                dmax = D0_MM * math.sqrt(h0 / hk) + 2.0 * float(np.interp(eps, table.strain, table.bulge[i, j, k, m])) * hk
                try:
                    read = fr.identify_friction(method, D0_MM, h0, hk, d_max_mm=dmax).mu
                except IdentificationError:
                    read = math.nan
                rows.append((mu, h0_d0, n, eps0, eps, (read - mu) / mu))
    return np.array(rows)


def rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.nanmean(np.asarray(values) ** 2)))


def main() -> None:
    table = UpsettingTable.load()
    for method in ("bulge_regression", "ebrahimi_najafizadeh"):
        rows = relative_errors(method, table)
        print(f"{method}: (μ_method − μ)/μ, mean/rms, rows h0/d0, columns n {', '.join(f'{n:g}' for n in table.n)}")
        for h0_d0 in table.h0_d0:
            cells = [rows[(rows[:, 1] == h0_d0) & (rows[:, 2] == n), 5] for n in table.n]
            print(f"  h0/d0 {h0_d0:<4g}" + "".join(f"  {np.nanmean(c):+.2f}/{rms(c):.2f}" for c in cells))
        print(f"  all {np.isfinite(rows[:, 5]).sum()} of {len(rows)} read: mean {np.nanmean(rows[:, 5]):+.3f}, rms {rms(rows[:, 5]):.3f}"
              f" (MU_MODEL_FORM {fr.MU_MODEL_FORM[method]})")


if __name__ == "__main__":
    main()

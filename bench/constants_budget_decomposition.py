"""What makes a hardening constant's U on the coverage campaign's drawn tension records (issue 43)?

Runs tests/coverage/campaign.py's drawn tension cases (150 drawn with numpy's generator, seed 43) through
identify and the campaign's judge; for every judged Johnson–Cook constant prints its value, the truth, the
error, U, U's method share and each budget component's contribution (fit, strain zero, constants over the
range, constant on its bound), whether A sits on its bound, δε0 and the fit range; then per constant the
cell's medians, and those of the records off the bound apart.
Run: nice python bench/constants_budget_decomposition.py [A_MPa,B_MPa,n]  (~15 s)
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from flowcurve.errors import FlowcurveError  # noqa: E402
from tests.coverage import campaign as cp  # noqa: E402

SHORT = {"fit (standard error)": "fit", "method: strain zero ε0": "zero", "method: constants over the fit range": "range",
         "method: constant on its lower bound": "bound", "method: constant on its upper bound": "bound"}


def judged_records() -> list[tuple[str, dict, list[dict]]]:
    """(name, result, judged rows) of every drawn record identify does not refuse."""
    out = []
    for case in cp.drawn_cases(150, 43):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result, truth = case.run()
        except FlowcurveError:
            continue
        out.append((case.name, result, cp.judge(case, result, truth)))
    return out


def row_text(name: str, result: dict, row: dict, key: str) -> str:
    """One judged constant: value, truth, error, U, method share, the components' contributions, A on its bound, δε0, range."""
    hard = result["hardening"]
    comps = {SHORT.get(c["name"], c["name"]): c["contribution"] for c in result["uncertainty"]["hardening"][key]["components"]}
    start = hard.get("start_uncertainty") or {}
    rng = hard.get("fit_range") or hard.get("strain_range")
    bound = " A on its bound" if "A" in (start.get("constants_on_bound") or {}) else ""
    parts = " ".join(f"{k}={v:.3g}" for k, v in comps.items() if k != "stress scale (force class, d0)")
    return (f"{name}: value {row['value']:.4g} truth {row['truth']:.4g} |error| {row['error']:.3g} U {row['U']:.3g} "
            f"method {row['U_method']:.3g} held {row['held']} [{parts}] δε0 {start.get('delta_eps0', 0):.2g} "
            f"range {rng[0]:.3g}–{rng[1]:.3g}{bound}")


def main(keys=("A_MPa", "B_MPa", "n")) -> None:
    records = judged_records()
    for key in keys:
        print(f"\n== johnson_cook {key}")
        cell, off = [], []
        for name, result, rows in records:
            for row in (r for r in rows if r["quantity"] == f"johnson_cook {key}"):
                print(row_text(name, result, row, key))
                cell.append(row)
                if "A" not in (((result["hardening"].get("start_uncertainty") or {}).get("constants_on_bound")) or {}):
                    off.append(row)
        for label, rows in (("cell", cell), ("A off its bound", off)):
            if rows:
                m, e = (float(np.median([r[k] for r in rows])) for k in ("U_method", "error"))
                print(f"{label}: {len(rows)} judged, {100 * np.mean([r['held'] for r in rows]):.0f} % held, "
                      f"median method share {m:.3g}, median |error| {e:.3g}, ratio {m / e if e else float('inf'):.3g}")


if __name__ == "__main__":
    main(tuple(sys.argv[1].split(",")) if len(sys.argv) > 1 else ("A_MPa", "B_MPa", "n"))

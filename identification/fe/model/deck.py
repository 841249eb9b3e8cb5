"""The pieces every CalculiX deck of the FE model shares: the sector factor, the ``*PLASTIC``
table and its data lines, the ``*STATIC`` step line, lists of numbers on data lines.

:mod:`.upsetting`, :mod:`.tension` and :mod:`.realised_law` write their decks with these, so none
of the three imports another for them.
"""

from __future__ import annotations

import numpy as np

from flowcurve.errors import IdentificationError

SECTOR = 180.0  # CAX reaction totals are for a 2° sector (docs/calculix.md)
PLASTIC_ROWS = 70  # *PLASTIC tables over ~150 rows read ~8 % low at small strain (docs/calculix.md)


def plastic_table(flow_stress, eps_max: float = 2.0, rows: int = PLASTIC_ROWS) -> tuple[np.ndarray, np.ndarray]:
    """(ε_p, σ) rows for ``*PLASTIC`` from a flow-curve function: 0 then a geometric spacing."""
    eps = np.concatenate([[0.0], np.geomspace(1e-4, eps_max, rows)])
    return eps, np.asarray(flow_stress(eps), dtype=float)


def check_plastic_table(eps_p, stress_MPa, what: str) -> None:
    """A *PLASTIC table ccx reads right: ≥ 2 rows, the first at ε_p = 0, at most ~150 rows."""
    if len(eps_p) != len(stress_MPa) or len(eps_p) < 2 or eps_p[0] != 0.0:
        raise IdentificationError(f"{what}: the plastic table needs ≥ 2 rows, the first at zero plastic strain")
    if len(eps_p) > 150:
        raise IdentificationError(f"{what}: {len(eps_p)} plastic rows; keep the table to ~100 rows (over ~150 ccx reads stresses low, docs/calculix.md)")


def number_lines(values, per_line: int = 12) -> list[str]:
    """Values as comma-separated data lines of at most ``per_line`` each (node and element sets)."""
    values = [str(v) for v in values]
    return [",".join(values[i:i + per_line]) for i in range(0, len(values), per_line)]


def static_step(increments: int, first_increment: float = 0.0) -> str:
    """The ``*STATIC`` data line: first increment (1/increments unless a smaller one is given),
    step 1, the smallest increment, the largest 1/increments."""
    dt = 1.0 / increments
    dt0 = first_increment if 0.0 < first_increment < dt else dt
    return f"{dt0:.9g},1.,{min(dt0, dt * 1e-3):.9g},{dt:.9g}"


def plastic_lines(eps_p, stress_MPa) -> list[str]:
    """``*PLASTIC`` data lines (stress, plastic strain)."""
    return [f"{sig:.9g},{e:.9g}" for e, sig in zip(eps_p, stress_MPa)]

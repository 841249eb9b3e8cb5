"""The flow curve CalculiX realises from a ``*PLASTIC`` table, and the table that realises a law.

In homogeneous compression (one CAX4R element, no contact) the Cauchy stress F/A — A the
loaded area, measured — at the plastic strain ε_p = ln(h0/h) − σ/E falls below the table's
rows: by an increment-size error, by about 0.3·σ/E, and by the rows' chords. For the seed's law
(E 194 GPa, 70 rows, ε 0 → 0.7) at ε 0.6: −0.53 % with 70 increments, −0.28 % with 700, −0.11 %
with 700 and E ten times higher (tests/fe/test_realised_law.py). That is the solver's, not the
specimen's. The FE table cancels it (its factor is a ratio to its own μ = 0 run, same mesh and
increments); runs whose force *is* the result — the records made from a law, the inverse FE's
fits, ``flowcurve verify`` — write the rows :func:`realising_rows` gives instead: the law divided
by the ratio a one-element run of it shows on the same strain path and increments (one ccx run,
~0.1 s). The corrected rows' realisation is within 0.05 % of the law, and the upsetting model at
μ = 0 on the records' mesh within 0.15 % (it was 0.5 % low).
"""

from __future__ import annotations

import math

import numpy as np

from flowcurve.identification.fe.model.ccx import run_deck
from flowcurve.identification.fe.model.deck import SECTOR, plastic_lines, static_step


def one_element_deck(eps_p, stress_MPa, *, radius_mm: float, height_mm: float, h_end_mm: float, E_MPa: float, nu: float,
                     increments: int, first_increment: float = 0.0) -> str:
    """One CAX4R element radius × height, its top pushed to h_end with no contact (a homogeneous
    cylinder), with the step control of an upsetting run of ``increments``."""
    r, h = radius_mm, height_mm
    return "\n".join([
        "*HEADING", "flowcurve one-element compression", "*NODE", "1,0,0", f"2,{r:.9g},0", f"3,{r:.9g},{h:.9g}", f"4,0,{h:.9g}",
        "*ELEMENT,TYPE=CAX4R,ELSET=SPEC", "1,1,2,3,4",
        "*NSET,NSET=AXIS", "1,4", "*NSET,NSET=BOT", "1,2", "*NSET,NSET=TOP", "3,4", "*NSET,NSET=OUTER", "2,3",
        "*MATERIAL,NAME=S", "*ELASTIC", f"{E_MPa:.9g},{nu:.9g}", "*PLASTIC", *plastic_lines(eps_p, stress_MPa),
        "*SOLID SECTION,ELSET=SPEC,MATERIAL=S", "*BOUNDARY", "AXIS,1,1,0.", "BOT,2,2,0.",
        "*STEP,NLGEOM,INC=10000", "*STATIC", static_step(increments, first_increment),
        "*BOUNDARY", f"TOP,2,2,{h_end_mm - h:.9g}", "*NODE PRINT,NSET=TOP,TOTALS=ONLY", "RF", "*NODE PRINT,NSET=OUTER", "U",
        "*END STEP"]) + "\n"


def realised_curve(eps_p, stress_MPa, *, E_MPa: float, nu: float, h0_mm: float, h_end_mm: float, increments: int,
                   first_increment: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(ε_p, σ) CalculiX gives for the rows in homogeneous compression h0 → h_end: σ = F/A on the
    loaded area, ε_p = ln(h0/h) − σ/E (the identification's definitions)."""
    deck = one_element_deck(eps_p, stress_MPa, radius_mm=h0_mm / 2.0, height_mm=h0_mm / 2.0, h_end_mm=h_end_mm / 2.0,
                            E_MPa=E_MPa, nu=nu, increments=increments, first_increment=first_increment)
    out = run_deck(deck, name="one-element compression", timeout_s=120.0)
    h = h0_mm + (h_end_mm - h0_mm) * out.time  # full height (the element is the half model)
    radius = h0_mm / 2.0 + out.displacements["OUTER"][:, -1, 0]
    sigma = -out.totals["TOP"][:, 1] * SECTOR / (math.pi * radius**2)
    # (3.7) ε_p = ε − σ/E
    return np.log(h0_mm / h) - sigma / E_MPa, sigma


def realising_rows(eps_p, stress_MPa, *, E_MPa: float, nu: float, h0_mm: float, h_end_mm: float, increments: int,
                   first_increment: float = 0.0) -> np.ndarray:
    """The ``*PLASTIC`` stresses whose CalculiX realisation on this strain path is ``stress_MPa``:
    each row divided by the realised-over-input ratio of one run at its ε_p (held beyond the run)."""
    eps_p, stress = np.asarray(eps_p, dtype=float), np.asarray(stress_MPa, dtype=float)
    e_run, s_run = realised_curve(eps_p, stress, E_MPa=E_MPa, nu=nu, h0_mm=h0_mm, h_end_mm=h_end_mm, increments=increments,
                                  first_increment=first_increment)
    plastic = e_run > 1e-5  # past the yield (elastic increments carry no ratio)
    if plastic.sum() < 2:
        return stress.copy()
    e_run, s_run = e_run[plastic], s_run[plastic]
    ratio = s_run / np.interp(e_run, eps_p, stress)  # the rows' own (linear) reading, as ccx interpolates them
    keep = np.concatenate([[True], np.diff(e_run) > 0])
    return stress / np.interp(eps_p, e_run[keep], ratio[keep])

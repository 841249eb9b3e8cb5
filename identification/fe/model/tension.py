"""Tension with necking in CalculiX: CAX8R quarter model (docs/calculix.md, "Tension with necking").

Axis and mid-length symmetry; the gauge radius carries a small cosine imperfection
r(z) = R·(1 − δ·cos(π·z/l0)) (δ = ``imperfection``, deepest at mid-length) so the neck forms
there. CAX4R stalls at the load maximum and CAX4 locks, hence CAX8R; 8×30 elements and an
increment of 0.01 reach a/a0 = 0.56 with force and neck radius within 0.35 % of converged.
The end of the gauge length is pulled by half the elongation. :func:`simulate_tension` returns
the full-ring force (RF × 180), the elongation of the gauge length and the neck radius.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.model.ccx import run_deck
from flowcurve.identification.fe.model.deck import SECTOR, check_plastic_table, number_lines, plastic_lines, plastic_table, static_step


@dataclass(frozen=True)
class TensionModel:
    d0_mm: float
    l0_mm: float  # gauge length (the model is half of it)
    elongation_mm: float  # imposed elongation of the whole gauge length
    eps_p: tuple
    stress_MPa: tuple
    E_MPa: float = 200_000.0
    nu: float = 0.3
    nr: int = 8
    nz: int = 30
    imperfection: float = 0.005
    increments: int = 100
    # initial increment as a fraction of the step (0: 1/increments); ccx grows it while it converges easily, so a small
    # one resolves the elastic line that a first increment of 1/increments steps over (records: the modulus read right)
    first_increment: float = 0.0
    surface: bool = False  # also print the outer surface's nodes (the neck profile); the default deck is unchanged

    def __post_init__(self):
        if not (self.d0_mm > 0 and self.l0_mm > 0 and self.elongation_mm > 0):
            raise IdentificationError(f"tension model: d0, l0 and the elongation must be > 0 (got {self.d0_mm}, {self.l0_mm}, {self.elongation_mm} mm)")
        check_plastic_table(self.eps_p, self.stress_MPa, "tension model")

    @classmethod
    def from_law(cls, d0_mm, l0_mm, elongation_mm, flow_stress, **kw) -> "TensionModel":
        """The model with the plastic table of ``flow_stress`` (a function of εp, MPa)."""
        eps, sig = plastic_table(flow_stress)
        return cls(d0_mm, l0_mm, elongation_mm, tuple(float(x) for x in eps), tuple(float(x) for x in sig), **kw)


def tension_deck(m: TensionModel) -> str:
    """The CalculiX deck of tension model ``m`` (axisymmetric half specimen)."""
    R, L = m.d0_mm / 2.0, m.l0_mm / 2.0
    nr2, nz2 = 2 * m.nr, 2 * m.nz
    ids, nodes = {}, []
    for j in range(nz2 + 1):
        z = L * j / nz2
        rz = R * (1.0 - m.imperfection * math.cos(math.pi * z / m.l0_mm))  # cosine imperfection, deepest at z = 0
        for i in range(nr2 + 1):
            if i % 2 and j % 2:
                continue  # element centres: CAX8R has no centre node
            nodes.append((rz * i / nr2, z))
            ids[i, j] = len(nodes)
    elems = []
    for j in range(0, nz2, 2):
        for i in range(0, nr2, 2):
            c = [ids[i, j], ids[i + 2, j], ids[i + 2, j + 2], ids[i, j + 2]]
            mid = [ids[i + 1, j], ids[i + 2, j + 1], ids[i + 1, j + 2], ids[i, j + 1]]
            elems.append(c + mid)
    axis = [ids[0, j] for j in range(nz2 + 1)]
    mid_plane = [ids[i, 0] for i in range(nr2 + 1)]
    top = [ids[i, nz2] for i in range(nr2 + 1)]
    eps, sig = m.eps_p, m.stress_MPa
    lines = ["*HEADING", f"flowcurve tension d0={m.d0_mm:g} l0={m.l0_mm:g} dl={m.elongation_mm:g}", "*NODE"]
    lines += [f"{k},{r:.9g},{z:.9g}" for k, (r, z) in enumerate(nodes, start=1)]
    lines += ["*ELEMENT,TYPE=CAX8R,ELSET=SPEC"] + [f"{k}," + ",".join(map(str, e)) for k, e in enumerate(elems, start=1)]
    lines += ["*NSET,NSET=AXIS", *number_lines(axis), "*NSET,NSET=MID", *number_lines(mid_plane), "*NSET,NSET=TOP", *number_lines(top),
              "*NSET,NSET=NECK", str(ids[nr2, 0]),
              "*MATERIAL,NAME=SPECIMEN", "*ELASTIC", f"{m.E_MPa:.9g},{m.nu:.9g}", "*PLASTIC",
              *plastic_lines(eps, sig),
              "*SOLID SECTION,ELSET=SPEC,MATERIAL=SPECIMEN",
              "*BOUNDARY", "AXIS,1,1,0.", "MID,2,2,0.",
              "*STEP,NLGEOM,INC=10000", "*STATIC", static_step(m.increments, m.first_increment),
              "*BOUNDARY", f"TOP,2,2,{m.elongation_mm / 2.0:.9g}",
              "*NODE PRINT,NSET=TOP,TOTALS=ONLY", "RF", "*NODE PRINT,NSET=NECK", "U", "*END STEP"]
    if m.surface:  # the outer surface from the neck (z = 0) to the end, corner and mid-side nodes
        surf = [ids[nr2, j] for j in range(nz2 + 1)]
        at = lines.index("*MATERIAL,NAME=SPECIMEN")
        lines[at:at] = ["*NSET,NSET=SURF", *number_lines(surf)]
        lines[-1:-1] = ["*NODE PRINT,NSET=SURF", "U"]
    return "\n".join(lines) + "\n"


@dataclass
class TensionResult:
    model: TensionModel
    time: np.ndarray
    elongation_mm: np.ndarray
    force_N: np.ndarray
    neck_radius_mm: np.ndarray
    completed: bool
    wall_s: float
    message: str = ""
    cached: bool = False  # read from the run cache, not solved now
    surface_r_mm: np.ndarray | None = None  # (increment, node) outer radius from z = 0 to l0/2 (model.surface)
    surface_z_mm: np.ndarray | None = None  # (increment, node) axial position of the same nodes


def simulate_tension(m: TensionModel, *, require_complete: bool = True, timeout_s: float = 600.0, use_cache: bool = True) -> TensionResult:
    """Run tension model ``m`` in CalculiX; its force–elongation and neck history."""
    out = run_deck(tension_deck(m), name=f"tension d0={m.d0_mm:g}", timeout_s=timeout_s, use_cache=use_cache, require_complete=require_complete)
    r_neck0 = m.d0_mm / 2.0 * (1.0 - m.imperfection)
    res = TensionResult(m, out.time, m.elongation_mm * out.time, out.totals["TOP"][:, 1] * SECTOR,
                        r_neck0 + out.displacements["NECK"][:, 0, 0], out.completed, out.wall_s, out.message, out.cached)
    if m.surface:
        r0, z0 = surface_nodes(m)
        res.surface_r_mm = r0[None, :] + out.displacements["SURF"][:, :, 0]
        res.surface_z_mm = z0[None, :] + out.displacements["SURF"][:, :, 1]
    return res


def surface_nodes(m: TensionModel) -> tuple[np.ndarray, np.ndarray]:
    """Initial (r, z) of the outer surface's nodes, z = 0 (the neck) to l0/2, as the deck places them."""
    z = (m.l0_mm / 2.0) * np.arange(2 * m.nz + 1) / (2 * m.nz)
    return m.d0_mm / 2.0 * (1.0 - m.imperfection * np.cos(np.pi * z / m.l0_mm)), z

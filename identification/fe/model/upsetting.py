"""Axisymmetric upsetting (compression between flat platens with Coulomb friction) in CalculiX.

Half model (symmetry at mid-height) of a cylinder d0 × h0 (docs/calculix.md, "Upsetting"):

* specimen: CAX4R, an O-grid — a structured core [0, R − t] × [0, H − t] and a boundary layer
  of ``layers`` elements and thickness t wrapped around its top and side, the layer split
  along the diagonal at the rim corner (a plain rectangular mesh fails near μ = 0.3 where the
  side face folds onto the platen); the core's element aspect is kept near 1 (nz scales with h0);
* platen: a meshed carbide block whose nodes are all driven (rigid), node numbers contiguous
  after the specimen's;
* contact: ``*CONTACT PAIR, TYPE=SURFACE TO SURFACE``, linear pressure-overclosure 1e8 MPa/mm,
  ``*FRICTION`` μ with stick slope 1e7 (left out for μ = 0: a tiny value made ccx abort);
* loading: the platen and the top-face node on the axis driven down by (h0 − h_end)/2.

The default mesh (24 core elements, a 2-element rim layer of d0/24) is the coarsest whose force
and barrel hold under refinement at μ 0.25, ε 0.7 (0.6 % in force, a few % in bulge;
``bench/fe_mesh.py``); the first one (12, d0/12) read the barrel up to 40 % large.

:func:`simulate_upsetting` returns the full-ring force (RF × 180 for the 2° sector), the
height, the stroke and the bulge (largest outer diameter) at every increment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from flowcurve.errors import IdentificationError
from flowcurve.identification.fe.model.ccx import CcxOutput, run_deck
from flowcurve.identification.fe.model.deck import SECTOR, check_plastic_table, number_lines, plastic_lines, plastic_table, static_step
from flowcurve.identification.fe.model.realised_law import realising_rows

CARBIDE_E_MPa, CARBIDE_NU = 560_000.0, 0.22
CONTACT_SLOPE_MPa_per_mm = 1.0e8  # 1e7 left a force deficit up to 1.1 % (docs/calculix.md)
STICK_SLOPE_MPa_per_mm = 1.0e7
# What the default mesh (24 core elements) leaves uncertain in the final shape: against 30 elements, on the six FE
# validation cases at ε 0.3–0.7, the bulge ΔR moved by up to 3.5 % (steel 45 at μ 0.25, h0/d0 1; ≤ 1.6 % on the
# others) and the original end face's d/d_n by up to 0.0038 (tests/fe/test_mesh_shape_uncertainty.py). Finer meshes
# stop where the side folds onto the platen, so these are lower bounds on the discretisation error, kept a little
# above the measured changes. The table's μ range and the inverse FE's μ uncertainty count them.
MESH_BULGE_UNCERTAINTY = 0.04  # relative, of ΔR
MESH_FACE_UNCERTAINTY = 0.005  # of the end face's d/d_n


@dataclass(frozen=True)
class UpsettingModel:
    """One upsetting run: geometry (mm), friction, material, end height and discretisation."""

    d0_mm: float
    h0_mm: float
    h_end_mm: float  # full height at the end of loading
    mu: float
    eps_p: tuple  # *PLASTIC plastic strains (first 0)
    stress_MPa: tuple  # *PLASTIC von Mises stresses
    E_MPa: float = 200_000.0
    nu: float = 0.3
    # 24 core elements, a d0/24 rim layer: 12 with a d0/12 layer read +3 % (μ 0.1) to +6 % (μ 0.25) in force
    # and +16–40 % in bulge at ε 0.7, with a barrel that moved 10 % with σ/E (bench/fe_mesh.py)
    nr: int = 24  # core elements across R − t
    layers: int = 2  # boundary-layer elements
    layer_fraction: float = 1.0 / 24.0  # layer thickness t as a part of d0 (0.25 mm at d0 = 6)
    increments: int = 50  # largest (and by default initial) increment: 1/increments of the step
    first_increment: float = 0.0  # initial increment as a fraction of the step (0: 1/increments); ccx grows it when
    # it converges easily, so a small one resolves the elastic line and the yield that 1/increments steps over
    platen_radius_factor: float = 2.5  # platen radius / R0 (the top face spreads with friction)
    # tangential (stick) stiffness of the contact: 1e6 gives the same force (0.02 %; up to 1 % while a side node folds
    # over, the fold-over sawtooth shifted in time) and dmax (0.5 µm) as 1e7 where
    # both converge, and carries runs past the fold-over where 1e7 stops with "too many cutbacks" (make_table)
    stick_slope_MPa_per_mm: float = STICK_SLOPE_MPa_per_mm

    def __post_init__(self):
        if not (self.d0_mm > 0 and self.h0_mm > 0 and 0 < self.h_end_mm < self.h0_mm):
            raise IdentificationError(f"upsetting model: need d0, h0 > 0 and 0 < h_end < h0 (got d0 {self.d0_mm}, h0 {self.h0_mm}, h_end {self.h_end_mm} mm)")
        if not (0.0 <= self.mu <= 1.0):
            raise IdentificationError(f"upsetting model: friction μ = {self.mu} must be within [0, 1]")
        check_plastic_table(self.eps_p, self.stress_MPa, "upsetting model")

    @classmethod
    def from_law(cls, d0_mm, h0_mm, h_end_mm, mu, flow_stress, **kw) -> "UpsettingModel":
        """The model with the plastic table of ``flow_stress`` (a function of εp, MPa)."""
        eps, sig = plastic_table(flow_stress)
        return cls(d0_mm, h0_mm, h_end_mm, mu, tuple(float(x) for x in eps), tuple(float(x) for x in sig), **kw)

    @property
    def stroke_mm(self) -> float:
        """The stroke h0 − h_end, mm."""
        return self.h0_mm - self.h_end_mm

    def realising(self) -> "UpsettingModel":
        """This model with the ``*PLASTIC`` stresses CalculiX realises as the given ones in
        homogeneous compression on the same strain path (:mod:`.realised_law`): for runs whose
        force is the result (records from a law, the inverse FE, verify), not for the table."""
        rows = realising_rows(self.eps_p, self.stress_MPa, E_MPa=self.E_MPa, nu=self.nu, h0_mm=self.h0_mm, h_end_mm=self.h_end_mm,
                              increments=self.increments, first_increment=self.first_increment)
        return replace(self, stress_MPa=tuple(float(v) for v in rows))


@dataclass
class Mesh:
    nodes: list = field(default_factory=list)  # (r, z)
    elements: list = field(default_factory=list)  # 4 node numbers (1-based), counter-clockwise

    def add_node(self, r: float, z: float) -> int:
        """Add node (r, z) in mm; its 1-based number."""
        self.nodes.append((r, z))
        return len(self.nodes)

    def add_quad(self, a: int, b: int, c: int, d: int) -> int:
        """Add a quadrilateral of nodes a–d (counter-clockwise); its 1-based number."""
        quad = [a, b, c, d]
        pts = np.array([self.nodes[k - 1] for k in quad])
        area2 = np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1])
        if area2 < 0:  # clockwise → reverse (CAX4 wants counter-clockwise in r–z)
            quad = [a, d, c, b]
        self.elements.append(quad)
        return len(self.elements)


def _face(quad: list, a: int, b: int) -> int:
    """Face number (1..4) of a CAX4 element whose edge joins nodes a and b."""
    for f in range(4):
        if {quad[f], quad[(f + 1) % 4]} == {a, b}:
            return f + 1
    raise ValueError("edge not on the element")


def build_mesh(m: UpsettingModel):
    """Specimen O-grid and platen; returns the mesh and the node/element sets."""
    R, H = m.d0_mm / 2.0, m.h0_mm / 2.0
    t = min(m.layer_fraction * m.d0_mm, 0.25 * H)
    rc, hc = R - t, H - t
    nr = m.nr
    nz = max(2, int(round(nr * hc / rc)))  # core element aspect near 1
    mesh = Mesh()
    core = {}
    for j in range(nz + 1):
        for i in range(nr + 1):
            core[i, j] = mesh.add_node(rc * i / nr, hc * j / nz)
    for j in range(nz):
        for i in range(nr):
            mesh.add_quad(core[i, j], core[i + 1, j], core[i + 1, j + 1], core[i, j + 1])
    # the core's top edge (axis → corner) then its side edge (corner → bottom)
    inner = [core[i, nz] for i in range(nr + 1)] + [core[nr, j] for j in range(nz - 1, -1, -1)]
    outer_xy = [(rc * i / nr, H) for i in range(nr)] + [(R, H)] + [(R, hc * j / nz) for j in range(nz - 1, -1, -1)]
    rows = [inner]
    for level in range(1, m.layers + 1):
        w = level / m.layers
        row = []
        for k, (ro, zo) in enumerate(outer_xy):
            ri, zi = mesh.nodes[inner[k] - 1]
            row.append(mesh.add_node(ri + w * (ro - ri), zi + w * (zo - zi)))
        rows.append(row)
    outer = rows[-1]
    outer_elems = []
    for level in range(m.layers):
        for k in range(len(inner) - 1):
            e = mesh.add_quad(rows[level][k], rows[level][k + 1], rows[level + 1][k + 1], rows[level + 1][k])
            if level == m.layers - 1:
                outer_elems.append((e, outer[k], outer[k + 1]))
    n_spec_nodes, n_spec_elems = len(mesh.nodes), len(mesh.elements)
    # platen: one element thick, element width about the core's
    rp = m.platen_radius_factor * R
    npl = int(math.ceil(rp / (rc / nr)))
    tp = max(0.5, 0.1 * m.d0_mm)
    bottom = [mesh.add_node(rp * i / npl, H) for i in range(npl + 1)]
    top = [mesh.add_node(rp * i / npl, H + tp) for i in range(npl + 1)]
    platen_elems = [mesh.add_quad(bottom[i], bottom[i + 1], top[i + 1], top[i]) for i in range(npl)]
    sets = {
        "axis": [core[0, j] for j in range(nz + 1)] + [r[0] for r in rows[1:]],
        "bottom": [core[i, 0] for i in range(nr + 1)] + [r[-1] for r in rows[1:]],
        "outer": outer,  # top face then side, for the bulge
        "topaxis": [outer[0]],
        "platen": bottom + top,
        "n_spec_nodes": n_spec_nodes,
        "n_spec_elems": n_spec_elems,
        "slave": [(e, _face(mesh.elements[e - 1], a, b)) for e, a, b in outer_elems],
        "master": [(e, _face(mesh.elements[e - 1], bottom[i], bottom[i + 1])) for i, e in enumerate(platen_elems)],
        "nz": nz,
    }
    return mesh, sets


def upsetting_deck(m: UpsettingModel) -> str:
    """The ccx input deck of one upsetting run."""
    mesh, s = build_mesh(m)
    dz = m.stroke_mm / 2.0
    es = s["n_spec_elems"]
    lines = ["*HEADING", f"flowcurve upsetting d0={m.d0_mm:g} h0={m.h0_mm:g} h_end={m.h_end_mm:g} mu={m.mu:g}", "*NODE"]
    lines += [f"{k},{r:.9g},{z:.9g}" for k, (r, z) in enumerate(mesh.nodes, start=1)]
    lines += ["*ELEMENT,TYPE=CAX4R,ELSET=SPEC"] + [f"{k},{a},{b},{c},{d}" for k, (a, b, c, d) in enumerate(mesh.elements[:es], start=1)]
    lines += ["*ELEMENT,TYPE=CAX4R,ELSET=PLAT"] + [f"{k},{a},{b},{c},{d}" for k, (a, b, c, d) in enumerate(mesh.elements[es:], start=es + 1)]
    lines += ["*NSET,NSET=AXIS", *number_lines(s["axis"]), "*NSET,NSET=BOT", *number_lines(s["bottom"]),
              "*NSET,NSET=PLN", *number_lines(s["platen"]), "*NSET,NSET=OUTER", *number_lines(s["outer"]),
              "*NSET,NSET=TOPAX", *number_lines(s["topaxis"])]
    lines += ["*SURFACE,NAME=SSLAVE,TYPE=ELEMENT", *[f"{e},S{f}" for e, f in s["slave"]],
              "*SURFACE,NAME=SMASTER,TYPE=ELEMENT", *[f"{e},S{f}" for e, f in s["master"]]]
    lines += ["*MATERIAL,NAME=SPECIMEN", "*ELASTIC", f"{m.E_MPa:.9g},{m.nu:.9g}", "*PLASTIC",
              *plastic_lines(m.eps_p, m.stress_MPa),
              "*MATERIAL,NAME=CARBIDE", "*ELASTIC", f"{CARBIDE_E_MPa:.9g},{CARBIDE_NU}",
              "*SOLID SECTION,ELSET=SPEC,MATERIAL=SPECIMEN", "*SOLID SECTION,ELSET=PLAT,MATERIAL=CARBIDE",
              "*SURFACE INTERACTION,NAME=SI", "*SURFACE BEHAVIOR,PRESSURE-OVERCLOSURE=LINEAR", f"{CONTACT_SLOPE_MPa_per_mm:.3g},1.0"]
    if m.mu > 0:  # μ = 0: no *FRICTION at all (docs/calculix.md)
        lines += ["*FRICTION", f"{m.mu:.9g},{m.stick_slope_MPa_per_mm:.3g}"]
    lines += ["*CONTACT PAIR,INTERACTION=SI,TYPE=SURFACE TO SURFACE", "SSLAVE,SMASTER",
              "*BOUNDARY", "AXIS,1,1,0.", "BOT,2,2,0.",
              "*STEP,NLGEOM,INC=10000", "*STATIC", static_step(m.increments, m.first_increment),
              "*BOUNDARY", "PLN,1,1,0.", f"PLN,2,2,{-dz:.9g}", f"TOPAX,2,2,{-dz:.9g}",
              "*NODE PRINT,NSET=PLN,TOTALS=ONLY", "RF", "*NODE PRINT,NSET=OUTER", "U", "*END STEP"]
    return "\n".join(lines) + "\n"


@dataclass
class UpsettingResult:
    """Force–stroke history of one run (full specimen, compression positive)."""

    model: UpsettingModel
    time: np.ndarray
    stroke_mm: np.ndarray  # platen travel × 2 (full specimen shortening)
    height_mm: np.ndarray
    force_N: np.ndarray  # full ring
    dmax_mm: np.ndarray  # largest outer diameter (bulge)
    dtop_mm: np.ndarray  # diameter of the top face's rim node (initially d0)
    completed: bool
    wall_s: float
    cached: bool
    message: str = ""
    side_gap: np.ndarray | None = None  # the first side node below the rim: its height under the platen face over the first

    @property
    def strain(self) -> np.ndarray:
        """Logarithmic height strain ε = ln(h0/h) (3.31)."""
        return np.log(self.model.h0_mm / self.height_mm)

    @property
    def fold_over_strain(self) -> float | None:
        """The strain at which the side begins to fold onto the platen: the first side node below
        the rim comes within :data:`FOLD_OVER_GAP` of its first distance to the platen face (None: it never does)."""
        if self.side_gap is None or self.side_gap.size == 0:
            return None
        on = np.nonzero(self.side_gap <= FOLD_OVER_GAP)[0]
        return float(self.strain[on[0]]) if on.size else None


FOLD_OVER_GAP = 0.05  # a side node this part of its first distance from the platen face has folded onto it


def simulate_upsetting(m: UpsettingModel, *, require_complete: bool = True, timeout_s: float = 600.0, use_cache: bool = True) -> UpsettingResult:
    """Run upsetting model ``m`` in CalculiX; its force–stroke and bulge history."""
    out: CcxOutput = run_deck(upsetting_deck(m), name=f"upsetting mu={m.mu:g} h0/d0={m.h0_mm / m.d0_mm:.3g}",
                              timeout_s=timeout_s, use_cache=use_cache, require_complete=require_complete)
    return upsetting_result(m, out)


def upsetting_result(m: UpsettingModel, out: CcxOutput) -> UpsettingResult:
    """The UpsettingResult of model ``m`` from CalculiX's output ``out``."""
    mesh, s = build_mesh(m)
    t = out.time
    rf = out.totals["PLN"]
    u = out.displacements["OUTER"]  # (n_inc, n_outer, 3)
    r0 = np.array([mesh.nodes[k - 1][0] for k in out.nodes["OUTER"]])
    radius = r0[None, :] + u[:, :, 0]
    corner = list(out.nodes["OUTER"]).index(s["outer"][m.nr])  # the rim-corner node
    stroke = m.stroke_mm * t
    below = list(out.nodes["OUTER"]).index(s["outer"][m.nr + 1])  # the first side node under the rim
    platen_z = m.h0_mm / 2.0 - stroke / 2.0  # the platen face (half model, symmetry at mid-height)
    z0 = mesh.nodes[s["outer"][m.nr + 1] - 1][1]
    side_gap = (platen_z - (z0 + u[:, below, 1])) / (m.h0_mm / 2.0 - z0)
    return UpsettingResult(
        model=m, time=t, stroke_mm=stroke, height_mm=m.h0_mm - stroke, force_N=-rf[:, 1] * SECTOR,
        dmax_mm=2.0 * radius.max(axis=1), dtop_mm=2.0 * radius[:, corner], completed=out.completed,
        wall_s=out.wall_s, cached=out.cached, message=out.message,
        side_gap=side_gap)

"""Regenerate the virtual rig's tension (necking) response: CalculiX necking runs over Swift n.

    python -m flowcurve.identification.fe.make_tension_response [--out FILE.npz] [--workers 2] [--scheduler ADDR] [--n 0.05 0.1 ...]

Each run (:mod:`.tension`: CAX8R quarter model, 12×40 elements, cosine imperfection 0.005, the
rig's default specimen d0 6, l0 30) of a Swift law σ = K·(ε0 + ε_p)^n is pulled to
l0·(e^n − 1) + ``NECK_ELONGATION_MM``, well past the force maximum, in increments of about
``INCREMENT_MM``. Its history is sampled on the neck's plastic strain
ε_n = 2·ln(a0/a) − 2ν·σ_avg/E (a the minimum-section radius, a0 its initial value; the elastic
radial contraction removed, as the operator measures dk on the unloaded specimen):

* ``force_factor`` β = F/(σ_f(ε_n)·π·a²): the mean axial stress in the minimum section over
  the flow stress at the neck strain — the FE's "Bridgman factor", 1 before the neck curves;
* ``neck_elongation_over_d0`` λ = (Δl − l0·(e^ε_end − 1))/d0: the elongation beyond what the
  gauge length would have at the strain ε_end of its thick end (z = l0/2, from that
  section's radius and stress), in units of d0 — after the force maximum the end unloads
  elastically and λ grows with the neck alone;
* ``neck_a_over_R`` a/R of the neck profile: r = c0 + c1·z² + c2·z⁴ fitted to the outer
  surface's nodes within |z| ≤ ``PROFILE_WINDOW``·a, R = 1/(2·c1) (the curvature at z = 0).

Mesh and increment checks (n 0.2, measured with this model): 12×40 against 16×54 and an
increment of 0.025 mm against 0.05–0.07 mm moved β by ≤ 0.25 % and λ by ≤ 0.6 % up to
ε_n 1.4, a/R by 3–5 % (the fit's own scatter); 8×30 and 12×40 part by 4 % in force beyond
ε_n 1.7, so the table stops at ``NECK_STRAIN_END``.

The .npz goes to the rig's data folder (``rig/virtual/data/tension_response.npz``, read by
``flowcurve.rig.virtual.neck_response``, which may not import this layer) with a .json of
the provenance beside it (ccx version, mesh, increments, imperfection, date, command, run times).
"""

from __future__ import annotations

import json
import logging
import math
from functools import partial
from pathlib import Path

import numpy as np

from flowcurve.identification.fe import generator
from flowcurve.identification.fe.synthetic import swift_flow
from flowcurve.identification.fe.model.tension import TensionModel, simulate_tension

log = logging.getLogger(__name__)

MODULE = "flowcurve.identification.fe.make_tension_response"

# the source tree's rig/virtual/data (the response is regenerated in a checkout, never in a wheel)
DEFAULT_OUT = Path(__file__).resolve().parents[2] / "rig" / "virtual" / "data" / "tension_response.npz"
N = (0.05, 0.1, 0.2, 0.3, 0.45)  # Considère strains n − ε0 from 0.048 to 0.448
D0_MM, L0_MM = 6.0, 30.0  # the rig's default specimen (GOST 1497 type IV)
SWIFT_K_MPa, SWIFT_EPS0 = 1000.0, 0.002
E_MPa, NU = 200_000.0, 0.3
MESH = {"nr": 12, "nz": 40}  # docs/calculix.md: 12×40 when the neck's curvature is needed
IMPERFECTION = 0.005
INCREMENT_MM = 0.05
NECK_ELONGATION_MM = 5.0  # beyond the uniform elongation: reaches ε_n ≈ 1.6 and more
NECK_STRAIN_END = 1.5
NECK_STRAIN = np.round(np.arange(0.01, NECK_STRAIN_END + 1e-9, 0.01), 4)
PROFILE_WINDOW = 1.5  # the profile fit's half-length in units of the current neck radius a
PROFILE_MIN_NODES = 4


def neck_plastic_strain(a_mm, a0_mm, force_N, E=E_MPa, nu=NU):
    """# ε_n = 2 ln(a0/a) − 2ν·σ_avg/E, σ_avg = F/(π a²): the section's plastic strain."""
    a = np.asarray(a_mm, float)
    return 2.0 * np.log(a0_mm / a) - 2.0 * nu * np.asarray(force_N, float) / (math.pi * a * a) / E


def neck_force_factor(force_N, a_mm, flow_MPa):
    """# β = F/(σ_f·π a²): mean axial stress in the minimum section over the flow stress."""
    a = np.asarray(a_mm, float)
    return np.asarray(force_N, float) / (np.asarray(flow_MPa, float) * math.pi * a * a)


def end_axial_strain(r_mm, r0_mm, force_N, E=E_MPa, nu=NU):
    """# ε_z = ε_p + σ/E, ε_p = 2 ln(r0/r) − 2ν σ/E, σ = F/(π r²): total axial strain of a uniform section."""
    r = np.asarray(r_mm, float)
    sigma = np.asarray(force_N, float) / (math.pi * r * r)
    return 2.0 * np.log(r0_mm / r) - 2.0 * nu * sigma / E + sigma / E


def neck_elongation_over_d0(elongation_mm, eps_end, l0_mm=L0_MM, d0_mm=D0_MM):
    """# λ = (Δl − l0·(e^ε_end − 1))/d0: the elongation the neck adds, in units of d0."""
    return (np.asarray(elongation_mm, float) - l0_mm * np.expm1(np.asarray(eps_end, float))) / d0_mm


def profile_a_over_R(z_mm, r_mm, a_mm: float, window: float = PROFILE_WINDOW) -> float:
    """a/R of a neck profile: r = c0 + c1 z² + c2 z⁴ fitted within |z| ≤ window·a, 1/R = 2 c1 (NaN on too few nodes)."""
    z, r = np.asarray(z_mm, float), np.asarray(r_mm, float)
    inside = np.abs(z) <= window * a_mm
    if inside.sum() < PROFILE_MIN_NODES:
        return math.nan
    z2 = z[inside] ** 2
    c = np.linalg.lstsq(np.column_stack([np.ones_like(z2), z2, z2 * z2]), r[inside], rcond=None)[0]
    return float(2.0 * c[1] * a_mm)  # a/R = a·r''(0) = 2 c1·a


def grid_model(n: float, *, increment_mm: float = INCREMENT_MM, neck_elongation_mm: float = NECK_ELONGATION_MM) -> TensionModel:
    """The tension model of one Swift exponent ``n``."""
    elongation = L0_MM * math.expm1(n) + neck_elongation_mm
    return TensionModel.from_law(D0_MM, L0_MM, elongation, partial(swift_flow, K=SWIFT_K_MPa, eps0=SWIFT_EPS0, n=n),
                                 E_MPa=E_MPa, nu=NU, imperfection=IMPERFECTION, surface=True,
                                 increments=int(math.ceil(elongation / increment_mm)), **MESH)


def increasing(x) -> np.ndarray:
    """Mask of the points where ``x`` exceeds every earlier value (np.interp needs rising abscissae)."""
    x = np.asarray(x, float)
    prev = np.concatenate([[-np.inf], np.maximum.accumulate(x)[:-1]])
    return x > prev


def sample_run(n: float, strain=NECK_STRAIN) -> dict:
    """One CalculiX necking run sampled on the neck-strain grid (NaN beyond the strain reached)."""
    m = grid_model(n)
    r = simulate_tension(m, require_complete=False, timeout_s=1800.0)
    a0 = m.d0_mm / 2.0 * (1.0 - m.imperfection)
    eps_n = neck_plastic_strain(r.neck_radius_mm, a0, r.force_N, m.E_MPa, m.nu)
    flow = swift_flow(eps_n, SWIFT_K_MPa, SWIFT_EPS0, n)
    beta = neck_force_factor(r.force_N, r.neck_radius_mm, flow)
    eps_end = end_axial_strain(r.surface_r_mm[:, -1], m.d0_mm / 2.0, r.force_N, m.E_MPa, m.nu)
    lam = neck_elongation_over_d0(r.elongation_mm, eps_end, m.l0_mm, m.d0_mm)
    a_over_R = np.array([profile_a_over_R(z, rr, a) for z, rr, a in zip(r.surface_z_mm, r.surface_r_mm, r.neck_radius_mm)])
    keep = increasing(eps_n)
    reached = float(eps_n[keep][-1])
    inside = np.asarray(strain) <= reached + 1e-12

    def on_grid(values):
        """``values`` on the strain grid (NaN outside the run's range)."""
        ok = keep & np.isfinite(values)
        return np.where(inside, np.interp(strain, eps_n[ok], values[ok]), np.nan)

    i_m = int(np.argmax(r.force_N))
    return {"force_factor": on_grid(beta), "neck_elongation_over_d0": on_grid(lam), "neck_a_over_R": on_grid(a_over_R),
            "fm_neck_strain": float(eps_n[i_m]), "fm_end_strain": float(eps_end[i_m]), "fm_elongation_mm": float(r.elongation_mm[i_m]),
            "fm_force_N": float(r.force_N[i_m]), "reached_neck_strain": reached, "completed": r.completed, "wall_s": r.wall_s,
            "cached": r.cached, "increments": int(r.time.size), "model_increments": m.increments,
            "elongation_mm": m.elongation_mm, "message": r.message}


def build_response(n=N, *, workers: int = 2, scheduler=None, out: Path = DEFAULT_OUT, command: str = "") -> dict:
    """Run the tension grid in CalculiX and write the virtual rig's response to ``out``; its dict."""
    n = tuple(sorted(float(v) for v in n))

    runs, wall = generator.run_timed(sample_run, n, workers=workers, scheduler=scheduler)
    rows = lambda key: np.array([r[key] for r in runs])  # noqa: E731
    meta = {
        "what": "the virtual rig's tension response after the force maximum: CalculiX necking runs of Swift laws, "
                "sampled on the neck's plastic strain eps_n = 2 ln(a0/a) - 2 nu sigma_avg/E",
        "arrays": {
            "n": "Swift hardening exponent of each run",
            "considere_strain": "n - eps0: the plastic strain at the force maximum of uniform tension (Considere)",
            "neck_strain": "the neck's plastic strain eps_n (grid)",
            "force_factor": "F/(sigma_f(eps_n) * pi a^2): mean axial stress in the minimum section over the flow stress",
            "neck_elongation_over_d0": "(elongation - l0 (exp(eps_end) - 1))/d0, eps_end the axial strain at the gauge's end",
            "neck_a_over_R": f"a/R of the neck profile, r = c0 + c1 z^2 + c2 z^4 fitted within |z| <= {PROFILE_WINDOW:g} a",
            "fm_neck_strain, fm_end_strain, fm_elongation_mm, fm_force_N": "at the run's force maximum",
            "reached_neck_strain, run_wall_s": "per run",
        },
        "nan": "neck strains a run did not reach",
        "model": "CAX8R axisymmetric quarter model (axis and mid-length symmetry), NLGEOM, gauge end pulled axially "
                 "(radially free), cosine imperfection r(z) = R (1 - imperfection cos(pi z/l0))",
        "mesh": MESH, "imperfection": IMPERFECTION, "increment_mm": INCREMENT_MM,
        "increments": {str(v): r["model_increments"] for v, r in zip(n, runs)},
        "elongation_mm": {str(v): round(r["elongation_mm"], 4) for v, r in zip(n, runs)},
        "d0_mm": D0_MM, "l0_mm": L0_MM,
        "material": {"law": "swift", "K_MPa": SWIFT_K_MPa, "eps0": SWIFT_EPS0, "E_MPa": E_MPa, "nu": NU},
        **generator.provenance(command or f"python -m {MODULE}", runs, wall),
        "run_wall_s": {str(v): round(r["wall_s"], 1) for v, r in zip(n, runs)},
        "cached_runs": [v for v, r in zip(n, runs) if r["cached"]],
        "incomplete_runs": [{"n": v, "reached_neck_strain": r["reached_neck_strain"], "message": r["message"]}
                            for v, r in zip(n, runs) if not r["completed"]],
    }
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, n=np.array(n), considere_strain=np.array(n) - SWIFT_EPS0, neck_strain=NECK_STRAIN,
                        force_factor=rows("force_factor"), neck_elongation_over_d0=rows("neck_elongation_over_d0"),
                        neck_a_over_R=rows("neck_a_over_R"), fm_neck_strain=rows("fm_neck_strain"), fm_end_strain=rows("fm_end_strain"),
                        fm_elongation_mm=rows("fm_elongation_mm"), fm_force_N=rows("fm_force_N"),
                        reached_neck_strain=rows("reached_neck_strain"), run_wall_s=rows("wall_s"))
    out.with_suffix(".json").write_text(json.dumps(meta, indent=2) + "\n")
    return meta


def main(argv=None) -> int:
    """``python -m`` entry: build the tension response; the exit status."""
    p = generator.parser(MODULE, __doc__, DEFAULT_OUT)
    p.add_argument("--n", type=float, nargs="+", default=list(N), help="Swift exponents of the runs")
    a = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    meta = build_response(a.n, workers=a.workers, scheduler=a.scheduler, out=a.out, command=generator.command_line(MODULE, argv))
    print(generator.summary(meta))
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Upsetting with a friction law that is not one uniform Coulomb μ: the second model's deck
(tests/fe/second_model.py) with its end face split into a central zone (initial radius below
``r_split``·r0) and an outer zone (the rest of the face and the side that folds onto the
platen), each its own Coulomb μ — two node sets, two *SURFACE INTERACTION / *FRICTION and two
*CONTACT PAIR blocks against the one platen face.

Lubricant trapped in the middle and squeezed out at the rim: μ_center < μ_rim ("lubricated
centre"); the opposite, a dry centre: μ_center > μ_rim. The header's truth (``fe2.mu``) is the
mean μ of the initial end face weighed by each node's consistent area ∫N_i·2πr dr (the contact's
own discretisation of the face), ``fe2.mu_center``/``fe2.mu_rim`` the zones' μ.

Use: ``run = sm.simulate(zoned(C3, 0.1, 0.3)); write_zoned_record(run, path)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from . import second_model as sm

R_SPLIT = 0.7  # the centre zone's outer initial radius as a fraction of r0: about half the face's area


@dataclass(frozen=True)
class ZonedCase(sm.Case):
    """A second-model case whose end face has two Coulomb zones; ``mu`` is their area-weighted mean."""

    mu_center: float = 0.0
    mu_rim: float = 0.0
    r_split: float = R_SPLIT

    def zones(self, r, top, side):
        """(suffix, slave nodes, μ) of the two zones: centre (0 < r < r_split·r0) and rim (the rest of the face and the side)."""
        R = float(r[-1])
        center = [n for n, ri in zip(top[1:], r[1:]) if ri < self.r_split * R]  # the axis node is driven with the platen
        rim = sorted(set(top[1:] + side) - set(center))
        return [("C", center, self.mu_center), ("R", rim, self.mu_rim)]


def face_radii(case: sm.Case) -> np.ndarray:
    """The end face's initial node radii as the second model meshes them (graded, with mid-side nodes for CAX8R)."""
    r = sm._graded(case.d0_mm / 2.0, case.nr, sm.GRADING)
    if case.element == "CAX8R":
        r = np.insert(r, np.arange(1, r.size), (r[1:] + r[:-1]) / 2.0)
    return r


def nodal_areas(r: np.ndarray, quadratic: bool = True) -> np.ndarray:
    """Each face node's consistent area ∫ N_i · 2πr dr over its edges (3-node quadratic or 2-node linear edges)."""
    # A_i = Σ_edges ∫_{-1}^{1} N_i(ξ) · 2π r(ξ) · r'(ξ) dξ, Gauss–Legendre with 4 points (exact for the cubic integrand)
    xi, wq = np.polynomial.legendre.leggauss(4)
    k = 2 if quadratic else 1
    shape = ([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2] if quadratic else [(1 - xi) / 2, (1 + xi) / 2])
    A = np.zeros(r.size)
    for a in range(0, r.size - 1, k):
        ra, rb = r[a], r[a + k]
        rr, jac = (ra + rb) / 2 + xi * (rb - ra) / 2, (rb - ra) / 2
        for j, N in enumerate(shape):
            A[a + j] += np.sum(wq * N * 2 * np.pi * rr * jac)
    return A


def center_share(case: sm.Case, r_split: float) -> float:
    """The central zone's share of the initial face (its nodes' consistent areas, the axis node's with them)."""
    r = face_radii(case)
    A = nodal_areas(r, case.element == "CAX8R")
    return float(A[r < r_split * r[-1]].sum() / A.sum())


def zoned(base: sm.Case, mu_center: float, mu_rim: float, r_split: float = R_SPLIT, name: str | None = None) -> ZonedCase:
    """``base``'s specimen and law with a two-zone face; ``mu`` the area-weighted mean of the zones' μ."""
    f = center_share(base, r_split)
    fields = {k: getattr(base, k) for k in base.__dataclass_fields__}
    fields.update(name=name or base.name, mu=round(f * mu_center + (1 - f) * mu_rim, 6))
    return ZonedCase(**fields, mu_center=mu_center, mu_rim=mu_rim, r_split=r_split)


def _held(name: str) -> sm.Case:
    return next(c for c in sm.HELD_OUT if c.name == name)


# the laws and specimens of C1, C3 and S4; their μ as the zones' mean, 0.5·μ / 1.5·μ centre / rim (L, a lubricated
# centre) and the opposite (D, a dry centre). S4D to h 5.6 mm: to 5.0 mm its side folded at 0.917 of the stroke
CASES = {f"{b}{tag}": zoned(_held(b), round(lo_hi[0] * _held(b).mu, 6), round(lo_hi[1] * _held(b).mu, 6), name=f"{b}{tag}")
         for b in ("C1", "C3", "S4") for tag, lo_hi in (("L", (0.5, 1.5)), ("D", (1.5, 0.5)))}
CASES["S4D"] = replace(CASES["S4D"], h_end_mm=5.6)


def uniform_twin(case: ZonedCase) -> ZonedCase:
    """The same deck with both zones at the case's mean μ (the split's own check against the one-zone deck)."""
    return replace(case, mu_center=case.mu, mu_rim=case.mu)


def write_zoned_record(run: sm.SecondRun, path: Path, **rig) -> Path:
    """The second model's record (the same rig) with the zones' truth added to the header (``fe2.*``, not read by identification)."""
    from flowcurve.record.format import amend_record

    c = run.case
    sm.write_record(run, path, **rig)
    return amend_record(path, {
        "material": f"zoned-friction FE model {c.name}",
        "fe2.friction": f"Coulomb in two zones: mu_center for initial r < {c.r_split:g}·r0, mu_rim beyond and on the side; "
                        "fe2.mu the face's area-weighted mean",
        "fe2.mu_center": repr(c.mu_center), "fe2.mu_rim": repr(c.mu_rim), "fe2.r_split": repr(c.r_split),
        "fe2.center_area_share": f"{center_share(c, c.r_split):.4f}",
    })


FLOW_AT = (0.05, 0.1, 0.2, 0.3, 0.5)


def measure(path: Path) -> dict:
    """The product's default identification of a zoned record (or a uniform one: both zones its fe2.mu) against its header's truth: μ read (bulge and end
    face) and their standard errors, per flow-stress budget point the error % of A + B·εpⁿ, the stated correction σ %
    (true_curve.csv ``correction_uncertainty_pct``), the model-form component and |error|/U, and per hardening
    constant |error| against the law fitted over the result's fit range (tests/coverage/campaign.py ``fit_constants``) in U."""
    import warnings

    from flowcurve.identification.identify import identify
    from flowcurve.record.importers import load_record
    from tests.coverage.campaign import fit_constants

    record = load_record(path)
    meta = record.meta
    A, B, n = (float(meta[f"fe2.{k}"]) for k in ("A_MPa", "B_MPa", "n"))
    flow = lambda ep: A + B * np.asarray(ep, float) ** n  # noqa: E731  σ = A + B·εpⁿ, the law the record was made with
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ident = identify(record)
    res, curve = ident.result, ident.true_curve
    fe = res["friction_details"]["fe_table"]
    unc = res["uncertainty"]
    eps = curve["true_plastic_strain"].to_numpy(float)
    u_corr = curve["correction_uncertainty_pct"].to_numpy(float) if "correction_uncertainty_pct" in curve else None
    points = []
    for at, b in (unc.get("flow_stress_MPa") or {}).items():
        truth = float(flow(float(at)))
        form = [c for c in b.get("components") or [] if str(c.get("name", "")).lower().startswith("method: fe model form")]
        points.append({"eps_p": float(at), "value": float(b["value"]), "truth": truth, "U": float(b["U"]),
                       "error_pct": 100.0 * (float(b["value"]) / truth - 1.0),
                       "u_corr_pct": float(np.interp(float(at), eps, u_corr)) if u_corr is not None else math.nan,
                       "u_form_MPa": float(form[0]["contribution"]) if form else 0.0,
                       "z": abs(float(b["value"]) - truth) / float(b["U"])})
    hard = res.get("hardening") or {}
    lo_hi = hard.get("fit_range") or hard.get("strain_range")
    fitted = fit_constants(flow, str(hard.get("law")), max(float(lo_hi[0]), 1e-4), float(lo_hi[1])) if lo_hi else None
    constants = [{"name": k, "value": float(b["value"]), "truth": fitted[k], "U": float(b["U"]),
                  "z": abs(float(b["value"]) - fitted[k]) / float(b["U"])}
                 for k, b in (unc.get("hardening") or {}).items() if fitted and k in fitted and b.get("U")]
    mu_b = unc.get("friction_mu") or {}
    return {"record": meta["specimen.id"], "mu_true": float(meta["fe2.mu"]), "mu_center": float(meta.get("fe2.mu_center", meta["fe2.mu"])),
            "mu_rim": float(meta.get("fe2.mu_rim", meta["fe2.mu"])), "mu": float(res["friction_mu"]), "mu_U": float(mu_b.get("U", math.nan)),
            "mu_face": fe.get("mu") if fe.get("mu_basis", "").startswith("original end face") else None,
            "mu_face_se": fe.get("mu_stderr"), "mu_bulge": fe.get("mu_from_bulge", fe.get("mu")),
            "mu_bulge_se": fe.get("mu_from_bulge_stderr", fe.get("mu_stderr")), "mu_basis": fe.get("mu_basis"),
            "law": hard.get("law"), "fit_range": lo_hi, "points": points, "constants": constants,
            "curve_error": sm.curve_error(curve, sm.Case("truth", A, B, n, 1.0, 0.0, 1.0, 1.0, 1.0)),  # max |σ/σ_true − 1|, εp 0.05–0.6
            "disagree_warning": any(w.startswith("friction: μ from the end face") for w in res.get("warnings", [])),
            "warnings": list(res.get("warnings", []))}

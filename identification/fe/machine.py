"""The compression inverse's elastic inputs: the specimen's E and the machine frame's compliance.

The crosshead's elastic part is the frame's F/k, the specimen's h·σ/E and the seating toe; one
record's slope cannot split them (a low yield, a toe and 1 µm counts read "E 62 GPa" for 194). So:

* E by the product's one rule (:func:`..elastic_modulus.modulus_for_model`): given (``--E``),
  the record's ``material.E_MPa``, an extensometer's; else the handbook value of the material
  class the record's ``material`` names (:data:`..elastic_modulus.CLASS_MODULI`, its spread over
  the class as its standard error); never an apparent slope.
* k: the record header's ``rig.frame_stiffness_N_per_um`` when the rig states it; else fitted by
  closure — the k at which the frame-corrected, toe-compensated shortening at the largest force
  meets the measured one, h0 − hk + hk·σ/E (the scaling (3.1) K_l(k) = 1). The shortening is
  linear in the compliance u = 1/k, Δl(u) = c − toe − F·u, so a secant on u converges in a few
  fast identifications. Its standard error: δk = k²·δΔh/F, δΔh from hk's resolution and E's
  share of the spring-back in quadrature.
"""

from __future__ import annotations

from dataclasses import dataclass

from flowcurve.errors import IdentificationError

HK_RESOLUTION_MM = 0.01  # a caliper's reading of the final height
CLOSURE_TOLERANCE = 1e-5  # |K_l − 1| at which the closure stops
CLOSURE_STEPS = 8


@dataclass(frozen=True)
class ModelElastics:
    """E (MPa) and the frame stiffness (N/µm) of an inverse's model, each with its source and standard error."""

    E_MPa: float
    E_stderr_MPa: float
    E_source: str  # given / handbook / measured (the class of :mod:`..elastic_modulus`)
    E_basis: str  # in words: which input
    frame_stiffness_N_per_um: float
    frame_stiffness_stderr_N_per_um: float | None  # None: stated by the rig, no uncertainty given
    frame_compliance_source: str  # "record header" or "fitted (closure on the measured height change)"

    def as_dict(self) -> dict:
        """The elastics as result.json's block."""
        return {"E_MPa": self.E_MPa, "E_stderr_MPa": self.E_stderr_MPa, "E_source": self.E_source, "E_basis": self.E_basis,
                "frame_stiffness_N_per_um": self.frame_stiffness_N_per_um,
                "frame_stiffness_stderr_N_per_um": self.frame_stiffness_stderr_N_per_um,
                "frame_compliance_source": self.frame_compliance_source}


def model_modulus(record, fast_result: dict, E_MPa: float | None, what: str) -> tuple[float, float, str, str]:
    """(E, its standard error, class, basis) by the rule above; a one-line error naming the inputs
    to give when the record tells nothing defensible."""
    from flowcurve.identification.elastic_modulus import class_modulus, modulus_for_model

    try:
        E, source = modulus_for_model(record, fast_result, E_MPa, what=what)
    except IdentificationError as exc:
        named = class_modulus(record.meta.get("material"))
        if named is None:
            raise IdentificationError(f"{exc}, or name the material's class (steel, aluminium, titanium, copper, nickel) in the "
                                      "record's 'material'; the crosshead's slope mixes the frame's and the specimen's compliance") from None
        cls, E, se = named
        return E, se, "handbook", f"handbook value of the class '{cls}' named by material {record.meta.get('material')!r}: {E:.0f} ± {se:.0f} MPa"
    basis = {"given": "given (--E)", "handbook": "the record's material.E_MPa", "measured": "an extensometer's"}.get(source, source)
    return E, 0.0, source, basis  # a value given or written for this material: no spread taken


def fit_frame_stiffness(record, E_MPa: float, E_stderr_MPa: float) -> tuple[float, float]:
    """(k N/µm, its standard error) by closure on the measured height change (see the module)."""
    from flowcurve.identification.compression.identify import identify_compression

    def shortening(u_um_per_N: float) -> tuple[float, float, float]:  # (K_l, max specimen displacement mm, force there N)
        """(K_l, max specimen displacement mm, force there N) at compliance ``u_um_per_N``."""
        ident = identify_compression(record, E_MPa=E_MPa, frame_stiffness_N_per_um=1.0 / u_um_per_N if u_um_per_N > 0 else 1e12)
        ind = ident.result["indicator"]
        return float(ind["K_l"]), float(ind["max_specimen_displacement_mm"]), float(ident.curves["corrected_diagram"]["force_N"].max())

    # Δl(u) = c − toe − F·u meets the measured m: 1/K_l = Δl/m is linear in u (secant)
    u0, (K0, d0, force) = 0.0, shortening(0.0)
    measured = K0 * d0
    if K0 >= 1.0:
        raise IdentificationError(f"{record.source}: the crosshead's travel ({d0:.3f} mm) is no longer than the measured shortening "
                                  f"({measured:.3f} mm) even with a rigid frame: the frame compliance cannot be fitted; check hk "
                                  "(post.hk_mm) or give the rig's stiffness (rig.frame_stiffness_N_per_um, --frame-stiffness)")
    u1 = (d0 - measured) / force * 1000.0  # µm/N, the toe as at u0
    K1 = shortening(u1)[0]
    for _ in range(CLOSURE_STEPS):
        if abs(K1 - 1.0) < CLOSURE_TOLERANCE or K1 == K0:
            break
        u0, K0, u1 = u1, K1, u1 - (1.0 / K1 - 1.0) * (u1 - u0) / (1.0 / K1 - 1.0 / K0)
        K1 = shortening(u1)[0]
    if not (u1 > 0 and abs(K1 - 1.0) < 1e-3):
        raise IdentificationError(f"{record.source}: the frame compliance's closure did not converge (K_l {K1:.4f} at "
                                  f"{1.0 / u1 if u1 > 0 else float('inf'):.4g} N/µm); give rig.frame_stiffness_N_per_um")
    k = 1.0 / u1
    # δΔh: hk's resolution and the spring-back's share of E's uncertainty, hk·σ/E·δE/E = (measured − (h0 − hk))·δE/E
    h0, hk = record.specimen.h0_mm, record.specimen.required("hk_mm")
    springback = measured - (h0 - hk)
    d_short = (HK_RESOLUTION_MM**2 + (springback * E_stderr_MPa / E_MPa) ** 2) ** 0.5
    return k, k**2 * d_short / force * 1000.0  # δk = k²·δu, δu = δΔh/F


def model_elastics(record, fast_result: dict, E_MPa: float | None = None, *, what: str = "the inverse FE model") -> ModelElastics:
    """E and k for ``record``'s inverse model (the module's rule), ``fast_result`` the fast identification's."""
    E, E_se, E_source, basis = model_modulus(record, fast_result, E_MPa, what)
    stated = record.positive("rig.frame_stiffness_N_per_um")
    if stated is not None:
        return ModelElastics(E, E_se, E_source, basis, float(stated), None, "record header (rig.frame_stiffness_N_per_um)")
    k, k_se = fit_frame_stiffness(record, E, E_se)
    return ModelElastics(E, E_se, E_source, basis, k, k_se,
                         "fitted: closure of the frame-corrected shortening on the measured height change (K_l = 1)")

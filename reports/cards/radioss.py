"""OpenRadioss block-format card: /MAT/PLAS_JOHNS (law 2, Johnson-Cook) and /FAIL/JOHNSON.

Layouts from OpenRadioss' own input definitions (hm_cfg_files/config/CFG/radioss2025/MAT/
matl2_plas_johns.cfg and .../FAIL/fail_johnson.cfg), fields of 20 characters (10 for the
integer flags):

    line 1  RHO_I
    line 2  E | Nu | Iflag(10) | flagVP(10) [| Pmin: 2025 only]
    line 3  a | b | n | EPS_p_max | SIG_max0
    line 4  c | EPS_DOT_0 | ICC(10) | Fsmooth(10) | F_cut | Chard
    line 5  m | T_melt | rhoC_p | T_r [| T_max: 2025 only]

The 2023 layout (OpenRadioss before 2025) has four fields on line 5. Radioss wants absolute
temperatures (T_r <= 0 reads as 298 K) and the volumetric heat capacity rho*Cp; eps_dot0 and
F_cut are per the deck's time unit. The strain-rate filter is on (Fsmooth = 1, F_cut given):
without it OpenRadioss warns and uses the raw, noisy strain rate.

/FAIL/JOHNSON: OpenRadioss evaluates eps_f = D1 + D2 exp(D3 P/SVM) with P the mean stress
(sigma_xx + sigma_yy + sigma_zz)/3, positive in tension, times (1 + D4 ln(max(1, eps_dot/eps_dot0)))
(1 + D5 T*) (engine/source/materials/fail/johnson_cook/fail_johnson.F): the conventions of
identification.damage, so the fitted constants go in unchanged.
"""

from __future__ import annotations

from flowcurve.reports.cards.data import DAMAGE_KEYS, CardData, CardOptions, header_lines
from flowcurve.reports.cards.fields import ascii_text, comment_block, mixed_line
from flowcurve.reports.units import UnitSystem

MAT_ID = 1


def plas_johns(data: CardData, units: UnitSystem, options: CardOptions, mat_id: int) -> list[str]:
    """The /MAT/PLAS_JOHNS block in the layout of ``options.radioss_version``."""
    E = units.to_system(data.require("E_MPa") * 1e6, "stress")
    nu = data.require("poisson")
    rho = units.to_system(data.require("density_kg_per_m3"), "density")
    cp = units.to_system(data.require("specific_heat_J_per_kgK"), "specific_heat")
    rho_cp = rho * cp  # volumetric heat capacity, the unit system's own rho*Cp
    A, B = (units.to_system(v * 1e6, "stress") for v in (data.A_MPa, data.B_MPa))
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    fcut = units.to_system(options.fcut_hz, "frequency")
    t_melt = units.temperature(data.require("melt_temperature_C"), absolute=True)
    t_ref = units.temperature(data.ref_temperature_C, absolute=True)
    current = options.radioss_version == "2025"
    out = [
        f"/MAT/PLAS_JOHNS/{mat_id}",
        ascii_text(data.material)[:100],
        "#              RHO_I",
        mixed_line((rho, 20)),
    ]
    if current:
        out += ["#                  E                  Nu     Iflag    flagVP                Pmin",
                mixed_line((E, 20), (nu, 20), (0, 10), (0, 10), (None, 20))]
    else:
        out += ["#                  E                  Nu     Iflag    flagVP",
                mixed_line((E, 20), (nu, 20), (0, 10), (0, 10))]
    out += [
        "#                  a                   b                   n           EPS_p_max            SIG_max0",
        mixed_line((A, 20), (B, 20), (data.n, 20), (None, 20), (None, 20)),
        "#                  c           EPS_DOT_0       ICC   Fsmooth               F_cut               Chard",
        mixed_line((data.C, 20), (eps0, 20), (1, 10), (1, 10), (fcut, 20), (0.0, 20)),
    ]
    if current:
        out += ["#                  m              T_melt              rhoC_p                 T_r               T_max",
                mixed_line((data.m, 20), (t_melt, 20), (rho_cp, 20), (t_ref, 20), (None, 20))]
    else:
        out += ["#                  m              T_melt              rhoC_p                 T_r",
                mixed_line((data.m, 20), (t_melt, 20), (rho_cp, 20), (t_ref, 20))]
    return out


def fail_johnson(data: CardData, units: UnitSystem, options: CardOptions, mat_id: int) -> list[str]:
    """/FAIL/JOHNSON/mat_ID: D1-D5 and eps_dot0 (solids: element deleted at one point, Ifail_so = 1)."""
    eps0 = units.to_system(data.ref_strain_rate_per_s, "strain_rate")
    out = [
        f"/FAIL/JOHNSON/{mat_id}",
        "#                 D1                  D2                  D3                  D4                  D5",
        mixed_line(*((data.fracture[k], 20) for k in DAMAGE_KEYS)),
        "#      EPSILON_DOT_0  IFAIL_SH  IFAIL_SO            EPSF_MIN                DADV               IXFEM",
        mixed_line((eps0, 20), (1, 10), (1, 10), (None, 20), (None, 20), (None, 10), (0, 10)),
    ]
    if options.radioss_version == "2025":
        out += ["#FAILIP", mixed_line((1, 10))]
    return out


def radioss_card(data: CardData, units: UnitSystem, options: CardOptions) -> str:
    """/MAT/PLAS_JOHNS (rate and temperature dependent), and /FAIL/JOHNSON when D1-D5 are known."""
    data.require_johnson_cook("Radioss' /MAT/PLAS_JOHNS")
    time_unit = units.name.split("-")[1]
    mat_id = MAT_ID + options.id_offset
    notes = [f"OpenRadioss {options.radioss_version} input layout (--radioss-version 2023 for the layout before 2025).",
             "EPS_p_max, SIG_max0 and T_max left blank (Radioss default: no failure strain, no stress cap).",
             f"Strain-rate filter on: Fsmooth = 1, F_cut = {options.fcut_hz:g} Hz (in 1/{time_unit} below)."]
    if data.fracture:
        notes.append("/FAIL/JOHNSON: the identified D1-D5 (triaxiality positive in tension, as Radioss'); "
                     "T* from T_r and T_melt of the material.")
    out = [comment_block(header_lines(data, units, "OpenRadioss", f"temperatures in K, strain rates per {time_unit}", options)
                         + notes, "# ").rstrip("\n")]
    out += plas_johns(data, units, options, mat_id)
    if data.fracture:
        out += fail_johnson(data, units, options, mat_id)
    if data.friction_mu is not None:
        out.append(f"# friction mu = {data.friction_mu:.4g} (specimen-platen, from barrelling): Fric of the contact interface (/INTER/TYPE7)")
    return "\n".join(out) + "\n"

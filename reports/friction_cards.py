"""The identified friction law (2.25) in the forms FE solvers take.

Input: the ``friction.json`` written by ``flowcurve friction`` (its dict). At the tool–chip
contact of a cutting simulation the contact is taken as full (K_r = 1: the real pressure is
the solver's contact pressure p), so the law is

    τ(p, T) = τ0 + (β0 − k_b·max(0, T − θ_k))·p + μ_d·p,     μ(p, T) = τ(p, T)/p

* Abaqus: ``*FRICTION`` with a pressure- and temperature-dependent table. Isotropic data lines
  are ``μ, slip rate, contact pressure, temperature`` (Abaqus Keywords Reference, *FRICTION;
  the CAE table of ContactTangentialBehavior lists the same order); slip rate is left 0 (no
  rate dependence), pressure varies fastest within each temperature. Abaqus interpolates
  linearly and holds the end values outside the table: below the lowest pressure the card's
  μ is that of the lowest pressure.
* LS-DYNA: ``*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE`` with FS = FD = μ(p*, T*) at a stated
  pressure and temperature (card 2: FS FD DC VC VDC PENCHK BT DT), VC = σ_S/√3 (the shear
  flow stress limit) when σ_S is known; and the whole law as ``*DEFINE_TABLE`` (temperatures,
  one 20-character VALUE per line) with its ``*DEFINE_CURVE`` (μ against contact pressure)
  immediately after it in the same order, for a user friction routine; constants in the comments.

Every card states its unit system, the range of pressure and temperature the constants were
identified on, and what lies outside it.
"""

from __future__ import annotations

import math
import textwrap

import numpy as np

from flowcurve import __version__
from flowcurve.identification.provenance import comment_lines
from flowcurve.errors import FlowcurveError
from flowcurve.reports.units import DEFAULT_UNIT_SYSTEM, UNIT_SYSTEMS, UnitSystem

FRICTION_CARD_FORMATS = ("abaqus", "lsdyna")
PRESSURE_ROWS = 16
FRICTION_CURVE_ID = 9001
FRICTION_TABLE_ID = 9000


class FrictionCardError(FlowcurveError):
    """A friction.json that cannot give a card, or a card option out of range."""


def friction_shear_MPa(law: dict, pressure_MPa, temperature_C):
    """# (2.25) with K_r = 1: τ = τ0 + (β0 − k_b·max(0, T − θ_k))·p + μ_d·p (MPa)."""
    p = np.asarray(pressure_MPa, dtype=float)
    beta = law["beta0"] - law["k_b_per_C"] * np.maximum(0.0, np.asarray(temperature_C, dtype=float) - law["theta_k_C"])
    return law["tau0_MPa"] + (beta + law["mu_d"]) * p


def friction_coefficient(law: dict, pressure_MPa, temperature_C):
    """μ = τ/p of (2.25) at contact pressure p > 0."""
    return friction_shear_MPa(law, pressure_MPa, temperature_C) / np.asarray(pressure_MPa, dtype=float)


def _check_law(law: dict) -> None:
    missing = [k for k in ("tau0_MPa", "beta0", "k_b_per_C", "theta_k_C", "mu_d") if not isinstance(law.get(k), (int, float))]
    if missing:
        raise FrictionCardError(f"friction.json lacks {', '.join(missing)}")


def table_grid(law: dict, pressure_range_MPa=None, temperature_range_C=None, rows: int = PRESSURE_ROWS):
    """Pressures (geometric steps) and temperatures (ends, θ_k, 100 °C steps) of the card tables."""
    covered = law.get("range", {})
    lo, hi = pressure_range_MPa or covered.get("nominal_mean_pressure_MPa") or (None, None)
    if lo is None or not (0 < lo < hi):
        raise FrictionCardError(f"the pressure range must be 0 < min < max, got {lo}, {hi}")
    t_lo, t_hi = temperature_range_C or covered.get("temperature_C") or (20.0, 20.0)
    temps = {float(t_lo), float(t_hi)}
    temps.update(float(t) for t in np.arange(math.ceil(t_lo / 100.0) * 100.0, t_hi, 100.0))
    if t_lo < law["theta_k_C"] < t_hi:
        temps.add(float(law["theta_k_C"]))  # the kink of max(0, T − θ_k): linear interpolation is exact between
    return np.geomspace(lo, hi, rows), np.array(sorted(temps))


def _range_lines(law: dict, pressures, temperatures, units: UnitSystem) -> list[str]:
    covered = law.get("range", {})
    p_cov = covered.get("nominal_mean_pressure_MPa")
    t_cov = covered.get("temperature_C")

    def se(key, fmt="{:.3g}"):
        """A constant's error as " +/- error", or "" without one."""
        err = law.get(f"{key}_stderr")
        return "" if not isinstance(err, (int, float)) else " +/- " + fmt.format(err)

    sigma_S = law.get("sigma_S_MPa") if "sigma_S_MPa" not in law.get("undetermined", ()) else None  # not a limit to write
    return [
        f"flowcurve {__version__}: friction law (2.25) from {law.get('tests_used', '?')} adhesiometer tests, method {law.get('method')}",
        "tau = tau0 + (beta0 - k_b*max(0, T - theta_k))*p + mu_d*p, mu = tau/p; full contact (K_r = 1, real pressure = p)",
        f"tau0 = {law['tau0_MPa']:.6g}{se('tau0_MPa')} MPa, beta0 = {law['beta0']:.6g}{se('beta0')}, "
        f"k_b = {law['k_b_per_C']:.4g}{se('k_b_per_C')} 1/C, theta_k = {law['theta_k_C']:.5g}{se('theta_k_C', '{:.3g}')} C, "
        f"mu_d = {law['mu_d']:.4g} ({law.get('mu_d_source', 'source not stated')})"
        + (f", sigma_S = {sigma_S:.5g} MPa" if isinstance(sigma_S, (int, float)) else ""),
        f"hot constants: {law.get('hot_constants_source', 'not stated')}",
        f"unit system {units.name}: pressure and stress in {units.stress_name}, temperature in C",
        (f"identified on nominal mean pressure {p_cov[0]:.4g}..{p_cov[1]:.4g} MPa and temperature {t_cov[0]:.4g}..{t_cov[1]:.4g} C"
         if p_cov and t_cov else "identified range not stated in friction.json"),
        f"tabulated for pressure {pressures[0]:.4g}..{pressures[-1]:.4g} MPa, temperature {temperatures[0]:.4g}..{temperatures[-1]:.4g} C; "
        "outside it the solver holds the end values (extrapolation is not identified)",
        *comment_lines(law.get("provenance"), "friction fit"),
    ]


def _comment(lines, prefix: str) -> list[str]:
    out = []
    for line in lines:
        out += [prefix + part for part in (textwrap.wrap(line, 78 - len(prefix), subsequent_indent="  ") or [""])]
    return out


def _num(value) -> str:
    return f"{float(value):.8g}"


def abaqus_friction_card(law: dict, units: UnitSystem, *, pressure_range_MPa=None, temperature_range_C=None,
                         rows: int = PRESSURE_ROWS, name: str = "ADHESION_FRICTION") -> str:
    """``*SURFACE INTERACTION`` + ``*FRICTION`` table μ(p, T) (data lines μ, slip rate, p, T)."""
    _check_law(law)
    pressures, temperatures = table_grid(law, pressure_range_MPa, temperature_range_C, rows)
    out = _comment(_range_lines(law, pressures, temperatures, units), "** ")
    out += _comment(["data lines: friction coefficient, slip rate (0: no rate dependence), contact pressure, temperature"], "** ")
    out += [f"*SURFACE INTERACTION, NAME={name}", "*FRICTION"]
    for T in temperatures:
        for p in pressures:
            mu = float(friction_coefficient(law, p, T))
            out.append(f"{_num(mu)}, 0., {_num(units.to_system(p * 1e6, 'stress'))}, {_num(T)}")
    return "\n".join(out) + "\n"


def _fields(values, width: int = 10) -> str:
    """LS-DYNA fixed 10-character fields (blank for None)."""
    cells = []
    for v in values:
        if v is None:
            cells.append(" " * width)
        elif isinstance(v, int):
            cells.append(f"{v:>{width}d}")
        else:
            text = f"{float(v):.6g}"
            if len(text) > width:
                text = f"{float(v):.3e}"
            cells.append(f"{text:>{width}}")
    return "".join(cells)


def lsdyna_friction_card(law: dict, units: UnitSystem, *, at_pressure_MPa: float | None = None, at_temperature_C: float | None = None,
                         pressure_range_MPa=None, temperature_range_C=None, rows: int = PRESSURE_ROWS) -> str:
    """*CONTACT with FS = FD at (p*, T*), and *DEFINE_TABLE/*DEFINE_CURVE of μ(p) per temperature."""
    _check_law(law)
    pressures, temperatures = table_grid(law, pressure_range_MPa, temperature_range_C, rows)
    p_star = at_pressure_MPa if at_pressure_MPa is not None else float(np.sqrt(pressures[0] * pressures[-1]))
    T_star = at_temperature_C if at_temperature_C is not None else float(temperatures[0])
    if p_star <= 0:
        raise FrictionCardError(f"--at-pressure must be > 0 MPa, got {p_star:g}")
    mu_star = float(friction_coefficient(law, p_star, T_star))
    sigma_S = law.get("sigma_S_MPa") if "sigma_S_MPa" not in law.get("undetermined", ()) else None  # not a limit to write
    vc = units.to_system(sigma_S / math.sqrt(3.0) * 1e6, "stress") if isinstance(sigma_S, (int, float)) else 0.0
    out = ["*KEYWORD"]
    out += _comment(_range_lines(law, pressures, temperatures, units), "$ ")
    out += _comment([f"FS = FD = mu({p_star:.4g} MPa, {T_star:.4g} C) = {mu_star:.4g}; "
                     + (f"VC = sigma_S/sqrt(3) = {sigma_S / math.sqrt(3.0):.4g} MPa limits the friction stress" if vc else
                        "VC = 0 (sigma_S not identified: no friction stress limit)"),
                     "set SURFA/SURFB (card 1) to the chip and tool parts"], "$ ")
    out += ["*CONTACT_AUTOMATIC_SURFACE_TO_SURFACE",
            "$#   surfa     surfb  surfatyp  surfbtyp   saboxid   sbboxid      sapr      sbpr",
            _fields([0, 0, 3, 3, None, None, 0, 0]),
            "$#      fs        fd        dc        vc       vdc    penchk        bt        dt",
            _fields([mu_star, mu_star, 0.0, vc, 0.0, None, 0.0, 1.0e20]),
            "$#    sfsa      sfsb      sast      sbst     sfsat     sfsbt       fsf       vsf",
            _fields([1.0, 1.0, None, None, 1.0, 1.0, 1.0, 1.0])]
    out += _comment([f"the whole law for a user friction routine: table {FRICTION_TABLE_ID} over temperature (C); the curves "
                     f"that follow it, in the same order, give mu against contact pressure ({units.stress_name})"], "$ ")
    out += ["*DEFINE_TABLE", "$#    tbid       sfa      offa", _fields([FRICTION_TABLE_ID, 1.0, 0.0])]
    out += [_fields([float(T)], width=20) for T in temperatures]
    for i, T in enumerate(temperatures):
        out += [f"$ mu(p) at {T:g} C", "*DEFINE_CURVE",
                "$#    lcid      sidr       sfa       sfo      offa      offo    dattyp",
                _fields([FRICTION_CURVE_ID + i, 0, 1.0, 1.0, 0.0, 0.0, 0])]
        for p in pressures:
            out.append(_fields([units.to_system(p * 1e6, "stress"), float(friction_coefficient(law, p, T))], width=20))
    out.append("*END")
    return "\n".join(out) + "\n"


def friction_card(law: dict, fmt: str, units: str | UnitSystem = DEFAULT_UNIT_SYSTEM, **options) -> str:
    """The card text in ``fmt`` (``abaqus`` or ``lsdyna``)."""
    system = units if isinstance(units, UnitSystem) else UNIT_SYSTEMS.get(units)
    if system is None:
        raise FrictionCardError(f"unknown unit system {units!r} (known: {', '.join(sorted(UNIT_SYSTEMS))})")
    if fmt == "abaqus":
        options.pop("at_pressure_MPa", None)
        options.pop("at_temperature_C", None)
        return abaqus_friction_card(law, system, **options)
    if fmt == "lsdyna":
        return lsdyna_friction_card(law, system, **options)
    raise FrictionCardError(f"unknown friction card format {fmt!r} (use: {', '.join(FRICTION_CARD_FORMATS)})")

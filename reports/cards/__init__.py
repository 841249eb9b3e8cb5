"""Material cards for FE solvers, written from a series fit (``fit.json``).

:func:`load_card_data` reads ``fit.json`` (schema: ``docs/fit-json.md``) plus the elastic and
thermal constants given as options into a :class:`CardData`; each solver module
(:mod:`.lsdyna`, :mod:`.abaqus`, :mod:`.radioss`, :mod:`.calculix`) turns that into deck text
in a chosen unit system (:mod:`reports.units`). Every card opens with a comment block: the
source records, the identification method, the unit system, and the range the constants
were identified on, with the warning that extrapolation beyond it is the user's risk.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flowcurve import __version__
from flowcurve.errors import FlowcurveError
from flowcurve.identification.johnson_cook import johnson_cook
from flowcurve.reports.units import UnitSystem, get_unit_system
from flowcurve.identification.outcome import read_json_object

FORMATS = ("lsdyna", "abaqus", "radioss", "calculix")
MAX_TABLE_ROWS = 100  # CALCULIX.md: tables over ~150 rows gave stresses ~8 % too low


class CardError(FlowcurveError):
    """A fit file or option that cannot make the requested card (names the key or option)."""


# Constants a card may need: attribute → (fit.json key, command-line option, what it is).
CONSTANTS = {
    "E_MPa": ("E_MPa", "--E", "Young's modulus in MPa"),
    "poisson": ("poisson_ratio", "--poisson", "Poisson's ratio"),
    "density_kg_per_m3": ("density_kg_per_m3", "--density", "density in kg/m3"),
    "specific_heat_J_per_kgK": ("specific_heat_J_per_kgK", "--cp", "specific heat in J/(kg K)"),
    "melt_temperature_C": ("melt_temperature_C", "--melt-temp", "melting temperature in °C"),
    "conductivity_W_per_mK": ("conductivity_W_per_mK", "--conductivity", "thermal conductivity in W/(m K)"),
    "expansion_per_K": ("expansion_per_K", "--expansion", "thermal expansion coefficient in 1/K"),
}


@dataclass
class FlowCurve:
    """One tabulated flow curve σ(εp) at a temperature and strain rate (lab units)."""

    temperature_C: float
    strain_rate_per_s: float
    plastic_strain: np.ndarray
    stress_MPa: np.ndarray
    origin: str = "measured"  # "measured" (identified true curve) or "Johnson-Cook"
    model_stress_at_zero_MPa: float | None = None  # fit.json's value for this condition


@dataclass
class CardData:
    """Everything a card carries, in lab units (MPa, kg/m3, J/(kg K), °C, 1/s)."""

    A_MPa: float
    B_MPa: float
    n: float
    C: float = 0.0
    m: float = 1.0
    ref_strain_rate_per_s: float = 1.0
    ref_temperature_C: float = 20.0
    melt_temperature_C: float | None = None
    stderr: dict[str, float | None] = field(default_factory=dict)
    plastic_strain_range: tuple[float, float] | None = None
    strain_rate_range_per_s: tuple[float, float] | None = None
    temperature_range_C: tuple[float, float] | None = None
    sources: list[str] = field(default_factory=list)
    method: str = "unknown"
    material: str = "material"
    friction_mu: float | None = None
    E_MPa: float | None = None
    poisson: float | None = None
    density_kg_per_m3: float | None = None
    specific_heat_J_per_kgK: float | None = None
    conductivity_W_per_mK: float | None = None
    expansion_per_K: float | None = None
    fracture: dict[str, float] = field(default_factory=dict)  # D1..D5 if identified
    fixed: dict[str, float] = field(default_factory=dict)  # constants given, not identified
    warnings: list[str] = field(default_factory=list)
    curves: list[FlowCurve] = field(default_factory=list)
    source_path: str = "<memory>"

    # -- the law ---------------------------------------------------------------------------
    def flow_stress_MPa(self, eps_p, strain_rate_per_s=None, temperature_C=None):
        """(2.19) Johnson–Cook flow stress in MPa, with the conventions of docs/methods.md §5."""
        rate = self.ref_strain_rate_per_s if strain_rate_per_s is None else strain_rate_per_s
        temp = self.ref_temperature_C if temperature_C is None else temperature_C
        melt = self.melt_temperature_C
        if melt is None:
            if temp > self.ref_temperature_C:
                self.require("melt_temperature_C")
            melt = self.ref_temperature_C + 1.0  # T* is clamped to 0 at or below T_ref anyway
        return johnson_cook(eps_p, rate, temp, A=self.A_MPa, B=self.B_MPa, n=self.n, C=self.C, m=self.m,
                            ref_strain_rate_per_s=self.ref_strain_rate_per_s,
                            ref_temperature_C=self.ref_temperature_C, melt_temperature_C=melt)

    def require(self, name: str) -> float:
        """A constant the card needs; a one-line error naming the option that supplies it."""
        value = getattr(self, name)
        if value is None:
            key, option, what = CONSTANTS[name]
            raise CardError(f"{self.source_path}: the card needs the {what}: give it with {option} or as '{key}' in the fit file")
        return value

    # -- what the card is valid for --------------------------------------------------------
    def valid_range_text(self) -> list[str]:
        def rng(r, fmt, unit):
            return "not stated in the fit file" if r is None else f"{fmt(r[0])} to {fmt(r[1])}{unit}"

        return [
            f"plastic strain {rng(self.plastic_strain_range, lambda v: f'{v:.4g}', '')}",
            f"strain rate {rng(self.strain_rate_range_per_s, lambda v: f'{v:.3g}', ' 1/s')}",
            f"temperature {rng(self.temperature_range_C, lambda v: f'{v:.4g}', ' °C')}",
        ]


def _pair(value, key: str, path) -> tuple[float, float] | None:
    if value is None:
        return None
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise CardError(f"{path}: '{key}' must be a pair [low, high] of numbers, got {value!r}") from None
    return (lo, hi)


def _number(fit: dict, key: str, path, default=None, *, required=False, positive=False):
    value = fit.get(key, default)
    if value is None:
        if required:
            raise CardError(f"{path}: the fit file has no '{key}'")
        return None
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise CardError(f"{path}: '{key}' is not a number: {value!r}") from None
    if not math.isfinite(value) or (positive and value <= 0):
        raise CardError(f"{path}: '{key}' must be a {'positive' if positive else 'finite'} number, got {value!r}")
    return value


def _curves(fit: dict, path) -> list[FlowCurve]:
    """The tabulated true curves of ``fit.json`` (``curves[].file``, relative to its folder)."""
    folder = Path(path).parent
    curves = []
    for i, c in enumerate(fit.get("curves") or []):
        where = f"curves[{i}]"
        try:
            temp = float(c["temperature_C"])
            rate = float(c["strain_rate_per_s"])
            file = folder / c["file"]
        except KeyError as exc:
            raise CardError(f"{path}: {where} lacks '{exc.args[0]}'") from None
        except (TypeError, ValueError):
            raise CardError(f"{path}: {where} holds values that are not numbers") from None
        import pandas as pd  # here, so `flowcurve --help` stays fast

        try:
            table = pd.read_csv(file, comment="#")
            eps = table["true_plastic_strain"].to_numpy(dtype=float)
            sig = table["true_stress_MPa"].to_numpy(dtype=float)
        except FileNotFoundError:
            raise CardError(f"{path}: {where}: curve file {file} is missing") from None
        except KeyError as exc:
            raise CardError(f"{file}: no column {exc.args[0]!r} (expected true_plastic_strain,true_stress_MPa)") from None
        except (ValueError, pd.errors.ParserError) as exc:
            raise CardError(f"{file}: not a readable curve table: {exc}") from None
        if eps.size < 2 or not (np.all(np.isfinite(eps)) and np.all(np.isfinite(sig))):
            raise CardError(f"{file}: a curve needs at least 2 finite points")
        zero = c.get("model_stress_at_zero_strain_MPa")
        curves.append(FlowCurve(temp, rate, eps, sig, "measured", None if zero is None else float(zero)))
    return curves


def _sources(fit: dict) -> list[str]:
    out = []
    for r in fit.get("records") or []:
        if isinstance(r, dict):
            name, source = r.get("name"), r.get("source")
            out.append(f"{name} ({source})" if name and source and str(source) != name else str(name or source))
        else:
            out.append(str(r))
    return out


def card_data_from_fit(fit: dict, path="<memory>", **overrides) -> CardData:
    """A :class:`CardData` from a parsed ``fit.json``; ``overrides`` (e.g. ``E_MPa=2.1e5``) win."""
    rng = fit.get("range") or {}
    stderr = {k[: -len("_stderr")]: fit[k] for k in fit if k.endswith("_stderr")}
    data = CardData(
        A_MPa=_number(fit, "A_MPa", path, required=True),
        B_MPa=_number(fit, "B_MPa", path, required=True),
        n=_number(fit, "n", path, required=True, positive=True),
        C=_number(fit, "C", path, 0.0),
        m=_number(fit, "m", path, 1.0, positive=True),
        ref_strain_rate_per_s=_number(fit, "ref_strain_rate_per_s", path, 1.0, positive=True),
        ref_temperature_C=_number(fit, "ref_temperature_C", path, 20.0),
        melt_temperature_C=_number(fit, "melt_temperature_C", path),
        stderr=stderr,
        plastic_strain_range=_pair(rng.get("plastic_strain"), "range.plastic_strain", path),
        strain_rate_range_per_s=_pair(rng.get("strain_rate_per_s"), "range.strain_rate_per_s", path),
        temperature_range_C=_pair(rng.get("temperature_C"), "range.temperature_C", path),
        sources=_sources(fit),
        method=str(fit.get("method", "unknown")),
        material=str(fit.get("material", "material")),
        friction_mu=_number(fit, "friction_mu", path),
        E_MPa=_number(fit, "E_MPa", path, positive=True),
        poisson=_number(fit, "poisson_ratio", path),
        density_kg_per_m3=_number(fit, "density_kg_per_m3", path, positive=True),
        specific_heat_J_per_kgK=_number(fit, "specific_heat_J_per_kgK", path, positive=True),
        conductivity_W_per_mK=_number(fit, "conductivity_W_per_mK", path, positive=True),
        expansion_per_K=_number(fit, "expansion_per_K", path),
        fracture={k: float(fit[k]) for k in ("D1", "D2", "D3", "D4", "D5") if fit.get(k) is not None},
        fixed={str(k): float(v) for k, v in (fit.get("fixed") or {}).items()},
        warnings=[str(w) for w in fit.get("warnings") or []],
        curves=_curves(fit, path),
        source_path=str(path),
    )
    for name, value in overrides.items():
        if value is None:
            continue
        if not hasattr(data, name):
            raise CardError(f"unknown card constant {name!r}")
        setattr(data, name, float(value) if isinstance(value, (int, float)) else value)
    if data.poisson is not None and not (0.0 <= data.poisson < 0.5):
        raise CardError(f"{path}: Poisson's ratio must lie in [0, 0.5), got {data.poisson:g}")
    if data.melt_temperature_C is not None and data.melt_temperature_C <= data.ref_temperature_C:
        raise CardError(f"{path}: melting temperature {data.melt_temperature_C:g} °C is not above the reference {data.ref_temperature_C:g} °C")
    return data


def load_card_data(path, **overrides) -> CardData:
    """Read ``fit.json`` at ``path``; a one-line error if it is missing or not JSON."""
    path = Path(path)
    fit = read_json_object(path, CardError, "fit file")
    return card_data_from_fit(fit, path, **overrides)


# -- flow tables -----------------------------------------------------------------------------
def resample(eps, sig, max_rows: int = MAX_TABLE_ROWS) -> tuple[np.ndarray, np.ndarray]:
    """A curve reduced to ≤ max_rows points (linear interpolation of the data), strictly
    increasing in strain."""
    order = np.argsort(eps, kind="stable")
    eps, sig = np.asarray(eps, float)[order], np.asarray(sig, float)[order]
    keep = np.concatenate([[True], np.diff(eps) > 0])
    eps, sig = eps[keep], sig[keep]
    if eps.size <= max_rows:
        return eps, sig
    # keep the first two points (zero and the first measured one), then crowd the rest
    # towards small strains, where hardening curves bend most
    start = 1 if eps.size > 2 else 0
    targets = eps[start] + (eps[-1] - eps[start]) * np.linspace(0.0, 1.0, max_rows - start) ** 2
    targets = np.concatenate([eps[:start], targets])
    return targets, np.interp(targets, eps, sig)


def start_at_zero(card: CardData, curve: FlowCurve) -> FlowCurve:
    """The curve beginning at zero plastic strain (solvers require it, docs/methods.md §7).

    A measured curve starts at εp ≈ 0.002 (Rp0.2): the missing first point is the fitted
    model at εp = 0 for the curve's condition (fit.json's ``model_stress_at_zero_strain_MPa``,
    else the law), not above the first measured stress. The cards say so.
    """
    eps, sig = curve.plastic_strain, curve.stress_MPa
    if eps[0] <= 0.0:
        eps = eps.copy()
        eps[0] = 0.0
        return FlowCurve(curve.temperature_C, curve.strain_rate_per_s, eps, sig, curve.origin)
    s0 = curve.model_stress_at_zero_MPa
    if s0 is None:
        s0 = float(card.flow_stress_MPa(0.0, curve.strain_rate_per_s, curve.temperature_C))
    s0 = min(s0, float(sig[0]))
    return FlowCurve(curve.temperature_C, curve.strain_rate_per_s, np.concatenate([[0.0], eps]),
                     np.concatenate([[s0], sig]), curve.origin, curve.model_stress_at_zero_MPa)


def law_curve(card: CardData, temperature_C: float, strain_rate_per_s: float, rows: int = 60) -> FlowCurve:
    """The Johnson–Cook law tabulated from εp = 0 to the top of the identified strain range,
    with points crowded near zero where εp^n is steep."""
    hi = card.plastic_strain_range[1] if card.plastic_strain_range else 0.3
    eps = hi * np.linspace(0.0, 1.0, rows) ** 2
    sig = card.flow_stress_MPa(eps, strain_rate_per_s, temperature_C)
    return FlowCurve(temperature_C, strain_rate_per_s, eps, np.asarray(sig, float), "Johnson-Cook")


def table_temperatures(card: CardData) -> list[float]:
    """Temperatures to tabulate: those tested (from the curves), else the ends of the range."""
    temps = sorted({c.temperature_C for c in card.curves})
    if not temps and card.temperature_range_C:
        temps = sorted(set(card.temperature_range_C))
    return temps or [card.ref_temperature_C]


def flow_tables(card: CardData, source: str = "auto", strain_rate_per_s: float | None = None,
                temperatures_C=None, max_rows: int = MAX_TABLE_ROWS) -> list[FlowCurve]:
    """One curve per temperature at one strain rate, each starting at εp = 0, ≤ max_rows rows.

    source "measured": the identified true curves at the tested rate closest (in log) to
    ``strain_rate_per_s``; "law": the fitted Johnson–Cook law; "auto": measured when the fit
    file has curves, else the law.
    """
    rate = card.ref_strain_rate_per_s if strain_rate_per_s is None else strain_rate_per_s
    if source == "auto":
        source = "measured" if card.curves else "law"
    if source == "law":
        temps = table_temperatures(card) if temperatures_C is None else sorted(temperatures_C)
        return [law_curve(card, t, rate, min(60, max_rows)) for t in temps]
    if source != "measured":
        raise CardError(f"unknown table source {source!r} (measured, law)")
    if not card.curves:
        raise CardError(f"{card.source_path}: the fit file has no tabulated curves; use the law (--curves law)")
    out = []
    for temp in sorted({c.temperature_C for c in card.curves}):
        if temperatures_C is not None and not any(math.isclose(temp, t) for t in temperatures_C):
            continue
        at_t = [c for c in card.curves if c.temperature_C == temp]
        best = min(at_t, key=lambda c: abs(math.log(c.strain_rate_per_s / rate)))
        curve = start_at_zero(card, best)
        eps, sig = resample(curve.plastic_strain, curve.stress_MPa, max_rows)
        out.append(FlowCurve(temp, best.strain_rate_per_s, eps, sig, "measured"))
    if not out:
        raise CardError(f"{card.source_path}: no tabulated curve at the temperatures asked for")
    return out


def rate_tables(card: CardData, temperature_C: float | None = None, source: str = "auto",
                max_rows: int = MAX_TABLE_ROWS) -> list[FlowCurve]:
    """Curves at one temperature (the reference one by default), one per strain rate."""
    temp = card.ref_temperature_C if temperature_C is None else temperature_C
    if source == "auto":
        source = "measured" if card.curves else "law"
    if source == "measured":
        if not card.curves:
            raise CardError(f"{card.source_path}: the fit file has no tabulated curves; use the law (--curves law)")
        tested = sorted({c.temperature_C for c in card.curves})
        nearest = min(tested, key=lambda t: abs(t - temp))
        if temperature_C is not None and abs(nearest - temp) > 1.0:
            raise CardError(f"{card.source_path}: no measured curves at {temp:g} °C (tested: "
                            f"{', '.join(f'{t:g}' for t in tested)} °C); choose one of those or use the law (--curves law)")
        out = []
        for c in sorted((c for c in card.curves if c.temperature_C == nearest), key=lambda c: c.strain_rate_per_s):
            if out and math.isclose(out[-1].strain_rate_per_s, c.strain_rate_per_s, rel_tol=0.02):
                continue  # one curve per rate: the first specimen's
            z = start_at_zero(card, c)
            eps, sig = resample(z.plastic_strain, z.stress_MPa, max_rows)
            out.append(FlowCurve(nearest, c.strain_rate_per_s, eps, sig, "measured"))
        return out
    if source != "law":
        raise CardError(f"unknown table source {source!r} (measured, law)")
    candidates = sorted({c.strain_rate_per_s for c in card.curves}) or sorted(set(card.strain_rate_range_per_s or ()))
    rates = []
    for r in candidates or [card.ref_strain_rate_per_s]:
        if not rates or not math.isclose(rates[-1], r, rel_tol=0.02):  # the series' 2 % rate tolerance
            rates.append(r)
    return [law_curve(card, temp, r, min(60, max_rows)) for r in rates]


# -- the comment block ------------------------------------------------------------------------
def header_lines(card: CardData, units: UnitSystem, solver: str, temperature_note: str) -> list[str]:
    """The comment block every card opens with (without the solver's comment prefix)."""
    def pm(key, value, unit=""):
        err = card.stderr.get(key)
        return f"{value:.6g}{unit}" + (f" ± {err:.2g}" if isinstance(err, (int, float)) else "")

    lines = [
        f"flowcurve {__version__} material card for {solver}: {card.material}",
        f"fit file: {card.source_path}",
        f"identification method: {card.method}",
        "source records: " + (", ".join(card.sources) if card.sources else "not stated in the fit file"),
        f"unit system: {units.name} (length {units.name.split('-')[0]}, time {units.name.split('-')[1]}, "
        f"mass {units.name.split('-')[2]}, force {units.force_name}, stress {units.stress_name}); {temperature_note}",
        f"Johnson-Cook (lab units): A = {pm('A_MPa', card.A_MPa)} MPa, B = {pm('B_MPa', card.B_MPa)} MPa, "
        f"n = {pm('n', card.n)}, C = {pm('C', card.C)}, m = {pm('m', card.m)}, "
        f"reference strain rate {card.ref_strain_rate_per_s:.6g} 1/s, reference temperature "
        f"{card.ref_temperature_C:.6g} °C, melting temperature "
        + (f"{card.melt_temperature_C:.6g} °C" if card.melt_temperature_C is not None else "not given"),
        "identified on: " + "; ".join(card.valid_range_text()),
        "WARNING: valid only on the range above. Extrapolation beyond it (larger strains, the "
        "high strain rates and temperatures of machining) is the user's risk.",
    ]
    if card.fixed:
        lines.append("NOT identified but given by the user: " + ", ".join(f"{k} = {v:g}" for k, v in card.fixed.items()))
    for warning in card.warnings:
        lines.append(f"fit warning: {warning}")
    if card.curves:
        lines.append("tabulated curves: measured true curves; their first point (zero plastic strain) is the fitted model's")
    if card.friction_mu is not None:
        lines.append(f"friction coefficient mu = {card.friction_mu:.4g} (specimen-platen, identified from barrelling)")
    return lines


def comment_block(lines, prefix: str, width: int = 78) -> str:
    """Comment lines, wrapped to ``width`` columns (fixed-format readers stop at 80)."""
    out = []
    for line in lines:
        out += textwrap.wrap(line, width - len(prefix), subsequent_indent="  ", break_on_hyphens=False) or [""]
    return "\n".join(f"{prefix}{line}".rstrip() for line in out) + "\n"


def write_card(card: CardData, fmt: str, units: str | UnitSystem, **options) -> str:
    """The card text in solver format ``fmt`` and unit system ``units``."""
    system = get_unit_system(units) if isinstance(units, str) else units
    if fmt == "lsdyna":
        from flowcurve.reports.cards.lsdyna import lsdyna_card as writer
    elif fmt == "abaqus":
        from flowcurve.reports.cards.abaqus import abaqus_card as writer
    elif fmt == "radioss":
        from flowcurve.reports.cards.radioss import radioss_card as writer
    elif fmt == "calculix":
        from flowcurve.reports.cards.calculix import calculix_card as writer
    else:
        raise CardError(f"unknown card format {fmt!r} (choose one of: {', '.join(FORMATS)})")
    return writer(card, system, **options)


# -- fixed-width fields -----------------------------------------------------------------------
def fixed(value, width: int = 10, digits: int | None = None) -> str:
    """``value`` right-aligned in a field of ``width`` characters: within 1e-7 with one blank
    to spare when possible (fields stay apart for the eye), else the most significant digits
    the field holds; never truncated (a value that cannot fit is an error, not a wrong
    number). ``digits`` caps the significant digits (curve points need no more than 8)."""
    if value is None:
        return " " * width
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        text = str(int(value))
        if len(text) > width - 1:
            raise CardError(f"integer {value} does not fit a {width}-character field")
        return text.rjust(width)
    value = float(value)
    if not math.isfinite(value):
        raise CardError(f"cannot write {value} into a card field")
    if value == 0.0:
        return "0.0".rjust(width)
    if digits is not None:
        value = float(f"{value:.{digits}g}")
    candidates = {_compact(repr(value))}
    candidates |= {_compact(f"{value:.{d}g}") for d in range(1, 16)}
    candidates |= {_compact(f"{value:.{d}e}") for d in range(0, 15)}
    candidates = {t + ".0" if "e" not in t and "." not in t else t for t in candidates}
    def best(room):
        fitting = [t for t in candidates if len(t) <= room]
        return min(fitting, key=lambda t: (abs(float(t) - value), "e" in t, len(t))) if fitting else None

    spaced = best(width - 1)  # one blank keeps the field apart from the one before
    if spaced is not None and abs(float(spaced) - value) <= 1e-7 * abs(value):
        return spaced.rjust(width)
    full = best(width)  # else the most precise the field holds
    if full is not None:
        return full.rjust(width)
    raise CardError(f"{value!r} does not fit a {width}-character field")


def _compact(text: str) -> str:
    """'1.5e-09' → '1.5e-9', '2e+05' → '2e5'."""
    if "e" in text:
        mantissa, exponent = text.split("e")
        sign = "-" if exponent.startswith("-") else ""
        return f"{mantissa}e{sign}{exponent.lstrip('+-').lstrip('0') or '0'}"
    return text

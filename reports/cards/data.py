"""What a card carries: the constants of a series fit (``fit.json``, schema
``docs/fit-json.md``) plus the elastic and thermal constants given as options, in lab units,
and the options that shape the deck (:class:`CardOptions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from flowcurve import __version__
from flowcurve.identification.outcome import read_json_object
from flowcurve.identification.provenance import comment_lines
from flowcurve.reports.cards.fields import CardError
from flowcurve.reports.units import UnitSystem

MAX_TABLE_ROWS = 100  # docs/calculix.md: tables over ~150 rows gave stresses ~8 % too low
DAMAGE_KEYS = ("D1", "D2", "D3", "D4", "D5")
LSDYNA_MATERIALS = ("15", "24", "224")  # *MAT_JOHNSON_COOK, *MAT_PIECEWISE_LINEAR_PLASTICITY, *MAT_TABULATED_JOHNSON_COOK
LSDYNA_MATERIAL_NAMES = {"15": "*MAT_JOHNSON_COOK", "24": "*MAT_PIECEWISE_LINEAR_PLASTICITY", "224": "*MAT_TABULATED_JOHNSON_COOK"}


@dataclass
class CardOptions:
    """How a deck is written; the same meaning in every format that uses an option.

    curves: tabulated curves from the 'measured' true curves, the fitted 'law', or 'auto'
    (measured when the fit file has them). temperature_C: the temperature of LS-DYNA's MAT_024
    (default the reference). strain_rate_per_s: the rate of the temperature tables (Abaqus,
    CalculiX; default the reference). extend_to: every tabulated curve continues beyond its
    last measured point with the fitted law up to this plastic strain. temperature_tolerance_C:
    curves closer than this in temperature are one temperature. id_offset: added to every
    numeric ID (materials, EOS, curves, tables). radioss_version: the /MAT/PLAS_JOHNS layout
    (2025: the current one; 2023: the layout before 2025). fcut_hz: Radioss' strain-rate
    filter cut-off. erosion_strain: LS-DYNA *MAT_ADD_EROSION, EFFEPS (the user's failure strain) on
    both materials.
    damage_displacement_mm: Abaqus *DAMAGE EVOLUTION, TYPE=DISPLACEMENT (linear softening).
    lsdyna_material: the LS-DYNA material(s): None both *MAT_015 and *MAT_024; "15", "24" or "224" one.
    """

    curves: str = "auto"
    temperature_C: float | None = None
    strain_rate_per_s: float | None = None
    temperatures_C: list[float] | None = None
    max_rows: int = MAX_TABLE_ROWS
    extend_to: float = 2.0
    temperature_tolerance_C: float = 1.0
    id_offset: int = 0
    radioss_version: str = "2025"
    fcut_hz: float = 1.0e4
    erosion_strain: float | None = None
    damage_displacement_mm: float | None = None
    lsdyna_material: str | None = None  # None: *MAT_015 and *MAT_024 (Johnson-Cook only); "15", "24" or "224": that one

    @classmethod
    def from_keywords(cls, **options) -> "CardOptions":
        """Options by name; a one-line error for an unknown one; None keeps the default."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(options) - known)
        if unknown:
            raise CardError(f"unknown card option(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
        out = cls(**{k: v for k, v in options.items() if v is not None})
        out.check()
        return out

    def check(self) -> None:
        """CardError for an unknown table source or too few table rows."""
        if self.curves not in ("auto", "measured", "law"):
            raise CardError(f"unknown table source {self.curves!r} (auto, measured, law)")
        if self.max_rows < 3:
            raise CardError(f"--max-rows must be at least 3, got {self.max_rows}")
        if not self.extend_to > 0:
            raise CardError(f"--extend-to must be a plastic strain > 0, got {self.extend_to:g}")
        if not self.temperature_tolerance_C >= 0:
            raise CardError(f"--temperature-tolerance must be >= 0 C, got {self.temperature_tolerance_C:g}")
        if int(self.id_offset) != self.id_offset or self.id_offset < 0:
            raise CardError(f"--id-offset must be a whole number >= 0, got {self.id_offset}")
        if self.radioss_version not in ("2025", "2023"):
            raise CardError(f"--radioss-version must be 2025 (current layout) or 2023 (before 2025), got {self.radioss_version!r}")
        if not self.fcut_hz > 0:
            raise CardError(f"--fcut must be a frequency > 0 Hz, got {self.fcut_hz:g}")
        if self.erosion_strain is not None and not self.erosion_strain > 0:
            raise CardError(f"--erosion-strain must be > 0, got {self.erosion_strain:g}")
        if self.lsdyna_material is not None and str(self.lsdyna_material) not in LSDYNA_MATERIALS:
            raise CardError(f"--lsdyna-material must be one of {', '.join(LSDYNA_MATERIALS)}, got {self.lsdyna_material!r}")
        if self.damage_displacement_mm is not None and not self.damage_displacement_mm > 0:
            raise CardError(f"--damage-displacement must be > 0 mm, got {self.damage_displacement_mm:g}")


# the formats that carry any law as tables (named when a Johnson-Cook-only format refuses another law)
TABLE_FORMATS = ("--format lsdyna --lsdyna-material 24 or 224, --format abaqus (its table material), "
                 "--format calculix or --format flow-table")

# fit.json's E before the one rule for E (issue 32): a mean with apparent crosshead slopes in it, never put on a card
OLD_APPARENT_MEAN = "mean of the records' E_MPa (apparent"

# Constants a card may need: attribute → (fit.json key, command-line option, what it is).
CONSTANTS = {
    "E_MPa": ("E_MPa", "--E", "Young's modulus in MPa"),
    "poisson": ("poisson_ratio", "--poisson", "Poisson's ratio"),
    "density_kg_per_m3": ("density_kg_per_m3", "--density", "density in kg/m3"),
    "specific_heat_J_per_kgK": ("specific_heat_J_per_kgK", "--cp", "specific heat in J/(kg K)"),
    "melt_temperature_C": ("melt_temperature_C", "--melt-temp", "melting temperature in C"),
    "conductivity_W_per_mK": ("conductivity_W_per_mK", "--conductivity", "thermal conductivity in W/(m K)"),
    "expansion_per_K": ("expansion_per_K", "--expansion", "thermal expansion coefficient in 1/K"),
}


class MissingConstant(CardError):
    """A constant the card needs and was not given; ``name`` is its CardData attribute."""

    def __init__(self, name: str, message: str):
        super().__init__(message)
        self.name = name


@dataclass
class FlowCurve:
    """One tabulated flow curve σ(εp) at a temperature and strain rate (lab units)."""

    temperature_C: float
    strain_rate_per_s: float
    plastic_strain: np.ndarray
    stress_MPa: np.ndarray
    origin: str = "measured"  # "measured" (identified true curve) or "law" (tabulated from the fitted law)
    model_stress_at_zero_MPa: float | None = None  # fit.json's value for this condition


@dataclass
class CardData:
    """Everything a card carries, in lab units (MPa, kg/m3, J/(kg K), C, 1/s)."""

    A_MPa: float | None = None  # Johnson-Cook's constants (fit.json's top level); None for another law
    B_MPa: float | None = None
    n: float | None = None
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
    E_source: str | None = None  # where E came from (fit.json E_MPa_source, or "given (--E)")
    given: dict[str, float] = field(default_factory=dict)  # constants given on the command line (option → value)
    poisson: float | None = None
    density_kg_per_m3: float | None = None
    specific_heat_J_per_kgK: float | None = None
    conductivity_W_per_mK: float | None = None
    expansion_per_K: float | None = None
    fracture: dict[str, float] = field(default_factory=dict)  # D1..D5 if identified
    fracture_stderr: dict[str, float | None] = field(default_factory=dict)
    fracture_triaxiality_range: tuple[float, float] | None = None
    fixed: dict[str, float] = field(default_factory=dict)  # constants given, not identified
    warnings: list[str] = field(default_factory=list)
    curves: list[FlowCurve] = field(default_factory=list)
    source_path: str = "<memory>"
    provenance: dict | None = None  # fit.json's: versions, every record's SHA-256, options, date
    law_name: str = "johnson_cook"  # the registered law of the fit (fit.json v2's law.name; v1: Johnson-Cook)
    law_values: dict[str, float] = field(default_factory=dict)  # another law's parameters and conditions by name

    # -- the law ---------------------------------------------------------------------------
    @property
    def law(self):
        """The fit's registered :class:`~flowcurve.identification.laws.base.Law`."""
        from flowcurve.identification.laws.base import get_law
        return get_law(self.law_name)

    @property
    def is_johnson_cook(self) -> bool:
        """Whether the law is Johnson–Cook."""
        return self.law_name == "johnson_cook"

    def values(self, temperature_C=None) -> dict[str, float]:
        """The law's values by name; Johnson-Cook's from the card's constants (a missing melting
        temperature asked for only above the reference temperature, where T* needs it)."""
        if not self.is_johnson_cook:
            return dict(self.law_values)
        melt = self.melt_temperature_C
        if melt is None:
            if temperature_C is not None and np.max(temperature_C) > self.ref_temperature_C:
                self.require("melt_temperature_C")
            melt = self.ref_temperature_C + 1.0  # T* is clamped to 0 at or below T_ref anyway
        return dict(A=self.A_MPa, B=self.B_MPa, n=self.n, C=self.C, m=self.m, ref_strain_rate_per_s=self.ref_strain_rate_per_s,
                    ref_temperature_C=self.ref_temperature_C, melt_temperature_C=melt)

    def flow_stress_MPa(self, eps_p, strain_rate_per_s=None, temperature_C=None):
        """σ (MPa) of the fit's law at εp, ε̇ (1/s), T (°C); rate and temperature default to the reference."""
        rate = self.ref_strain_rate_per_s if strain_rate_per_s is None else strain_rate_per_s
        temp = self.ref_temperature_C if temperature_C is None else temperature_C
        return self.law.stress(eps_p, rate, temp, **self.values(temp))

    def require_johnson_cook(self, what: str) -> None:
        """A one-line CardError when the fit's law is not Johnson-Cook: ``what`` carries JC constants only."""
        if not self.is_johnson_cook:
            raise CardError(f"{self.source_path}: {what} carries only Johnson-Cook constants and the fit's law is "
                            f"{self.law.display_name}: use {TABLE_FORMATS}")

    def require(self, name: str) -> float:
        """A constant the card needs; a one-line error naming the option that supplies it."""
        value = getattr(self, name)
        if value is None:
            key, option, what = CONSTANTS[name]
            if name == "E_MPa" and self.E_source:  # the fit file says why it has none (apparent moduli only)
                raise MissingConstant(name, f"{self.source_path}: the card needs the material's {what}: give it with {option} "
                                f"(the fit file's E is {self.E_source})")
            raise MissingConstant(name, f"{self.source_path}: the card needs the {what}: give it with {option} or as '{key}' in the fit file")
        return value

    # -- what the card is valid for --------------------------------------------------------
    def valid_range_text(self) -> list[str]:
        """The fit's valid strain, rate and temperature ranges as lines of text."""
        def rng(r, fmt, unit):
            """A range as "lo to hi unit", or that the fit file does not state it."""
            return "not stated in the fit file" if r is None else f"{fmt(r[0])} to {fmt(r[1])}{unit}"

        return [
            f"plastic strain {rng(self.plastic_strain_range, lambda v: f'{v:.4g}', '')}",
            f"strain rate {rng(self.strain_rate_range_per_s, lambda v: f'{v:.3g}', ' 1/s')}",
            f"temperature {rng(self.temperature_range_C, lambda v: f'{v:.4g}', ' C')}",
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


def _law(fit: dict, path) -> tuple[str, dict[str, float], dict[str, float | None]]:
    """(law name, values by name, stderr by key): a v2 fit's "law" block read by
    :func:`~flowcurve.identification.laws.fit_file.law_of_fit`; a v1 fit is Johnson-Cook from its
    top-level keys (read by the card's own fields, so a missing melting temperature is asked
    for only where a card needs it)."""
    top_stderr = {k[: -len("_stderr")]: fit[k] for k in fit if k.endswith("_stderr")}
    block = fit.get("law")
    if block is None:
        return "johnson_cook", {}, top_stderr
    from flowcurve.errors import IdentificationError
    from flowcurve.identification.laws.fit_file import law_of_fit

    if not isinstance(block, dict):
        raise CardError(f"{path}: 'law' must be an object (docs/fit-json.md)")
    try:
        law, values = law_of_fit(fit)
    except IdentificationError as exc:
        raise CardError(f"{path}: {exc}") from None
    return law.name, values, {**top_stderr, **{str(k): v for k, v in (block.get("stderr") or {}).items()}}


def card_data_from_fit(fit: dict, path="<memory>", **overrides) -> CardData:
    """The CardData of a parsed fit.json.

    Parameters
    ----------
    fit : dict
        fit.json's content.
    path : str
        Where it was read (for messages).
    **overrides
        Constants that win over the fit's (``E_MPa=2.1e5``).

    Returns
    -------
    CardData
        The law, constants, curves and ranges.
    """
    rng = fit.get("range") or {}
    law_name, law_values, stderr = _law(fit, path)
    total = fit.get("total_uncertainty")  # the fit's standard error and the curve-shape band in quadrature, where the fit states it
    if isinstance(total, dict):
        stderr = {**stderr, **{str(k): v for k, v in total.items() if isinstance(v, (int, float))}}
    jc = law_name == "johnson_cook"
    rates = _pair(rng.get("strain_rate_per_s"), "range.strain_rate_per_s", path)
    temps = _pair(rng.get("temperature_C"), "range.temperature_C", path)
    data = CardData(
        A_MPa=_number(fit, "A_MPa", path, required=jc),
        B_MPa=_number(fit, "B_MPa", path, required=jc),
        n=_number(fit, "n", path, required=jc, positive=True),
        C=_number(fit, "C", path, 0.0),
        m=_number(fit, "m", path, 1.0, positive=True),
        # another law's reference (a table's quasi-static rate, MAT_224's TR): its own condition, else the slowest and
        # coldest tested condition (never Johnson-Cook's top-level keys, which a v2 file may carry for another law)
        ref_strain_rate_per_s=(_number(fit, "ref_strain_rate_per_s", path, 1.0, positive=True) if jc
                               else law_values.get("ref_strain_rate_per_s", rates[0] if rates else 1.0)),
        ref_temperature_C=(_number(fit, "ref_temperature_C", path, 20.0) if jc
                           else law_values.get("ref_temperature_C", temps[0] if temps else 20.0)),
        melt_temperature_C=_number(fit, "melt_temperature_C", path),
        stderr=stderr,
        law_name=law_name,
        law_values={} if jc else law_values,
        plastic_strain_range=_pair(rng.get("plastic_strain"), "range.plastic_strain", path),
        strain_rate_range_per_s=rates,
        temperature_range_C=temps,
        sources=_sources(fit),
        method=str(fit.get("method", "unknown")),
        material=str(fit.get("material", "material")),
        friction_mu=_number(fit, "friction_mu", path),
        E_MPa=_number(fit, "E_MPa", path, positive=True),
        E_source=str(fit["E_MPa_source"]) if fit.get("E_MPa_source") else None,
        poisson=_number(fit, "poisson_ratio", path),
        density_kg_per_m3=_number(fit, "density_kg_per_m3", path, positive=True),
        specific_heat_J_per_kgK=_number(fit, "specific_heat_J_per_kgK", path, positive=True),
        conductivity_W_per_mK=_number(fit, "conductivity_W_per_mK", path, positive=True),
        expansion_per_K=_number(fit, "expansion_per_K", path),
        fracture={k: _number(fit, k, path) for k in DAMAGE_KEYS if fit.get(k) is not None},
        fracture_stderr={k: _number(fit, f"{k}_stderr", path) for k in DAMAGE_KEYS if fit.get(k) is not None},
        fracture_triaxiality_range=_pair((fit.get("damage") or {}).get("triaxiality_range"), "damage.triaxiality_range", path),
        fixed={str(k): float(v) for k, v in (fit.get("fixed") or {}).items()},
        warnings=[str(w) for w in fit.get("warnings") or []],
        curves=_curves(fit, path),
        source_path=str(path),
        provenance=fit.get("provenance") if isinstance(fit.get("provenance"), dict) else None,
    )
    if data.E_MPa is not None and (data.E_source or "").startswith(OLD_APPARENT_MEAN):  # a fit.json from before issue 32
        data.E_MPa, data.E_source = None, f"{data.E_MPa:.4g} MPa, a mean over apparent moduli (crosshead slopes), not the material's"
    for name, value in overrides.items():
        if value is None:
            continue
        if name == "E_MPa":
            data.E_source = "given (--E)"
        if name in CONSTANTS or name == "friction_mu":
            data.given[CONSTANTS[name][1] if name in CONSTANTS else "--friction"] = float(value)
        if not hasattr(data, name):
            raise CardError(f"unknown card constant {name!r}")
        setattr(data, name, float(value) if isinstance(value, (int, float)) else value)
    if data.poisson is not None and not (0.0 <= data.poisson < 0.5):
        raise CardError(f"{path}: Poisson's ratio must lie in [0, 0.5), got {data.poisson:g}")
    if data.fracture and set(data.fracture) != set(DAMAGE_KEYS):
        raise CardError(f"{path}: the fit file has only {', '.join(sorted(data.fracture))} of the fracture constants D1-D5")
    if data.melt_temperature_C is not None and data.melt_temperature_C <= data.ref_temperature_C:
        raise CardError(f"{path}: melting temperature {data.melt_temperature_C:g} C is not above the reference {data.ref_temperature_C:g} C")
    return data


def load_card_data(path, **overrides) -> CardData:
    """Read ``fit.json`` at ``path``; a one-line error if it is missing or not JSON."""
    path = Path(path)
    fit = read_json_object(path, CardError, "fit file")
    return card_data_from_fit(fit, path, **overrides)



def law_line(card: CardData, pm) -> str:
    """The fitted law and its constants (lab units) for the comment block; ``pm(key, value)`` adds ± stderr."""
    if card.is_johnson_cook:
        return (f"Johnson-Cook (lab units): A = {pm('A_MPa', card.A_MPa)} MPa, B = {pm('B_MPa', card.B_MPa)} MPa, "
                f"n = {pm('n', card.n)}, C = {pm('C', card.C)}, m = {pm('m', card.m)}, "
                f"reference strain rate {card.ref_strain_rate_per_s:.6g} 1/s, reference temperature "
                f"{card.ref_temperature_C:.6g} C, melting temperature "
                + (f"{card.melt_temperature_C:.6g} C" if card.melt_temperature_C is not None else "not given"))
    law = card.law
    params = ", ".join(f"{p.key} = {pm(p.key, card.law_values[p.name])}" for p in law.parameters if p.name in card.law_values)
    conds = ", ".join(f"{p.key} = {card.law_values[p.name]:.6g}" for p in law.conditions if p.name in card.law_values)
    return (f"{law.display_name} ({law.name}; lab units, temperature in C at the law's interface): {law.equation}; "
            f"{params}" + (f"; stated conditions: {conds}" if conds else ""))


# -- the comment block ------------------------------------------------------------------------
def header_lines(card: CardData, units: UnitSystem, solver: str, temperature_note: str,
                 options: CardOptions | None = None) -> list[str]:
    """The comment block every card opens with (without the solver's comment prefix)."""
    options = options or CardOptions()

    def pm(key, value, unit="", errors=card.stderr):
        """A constant as "value +/- error unit"."""
        err = errors.get(key)
        return f"{value:.6g}{unit}" + (f" +/- {err:.2g}" if isinstance(err, (int, float)) else "")

    lines = [
        f"flowcurve {__version__} material card for {solver}: {card.material}",
        f"fit file: {card.source_path}",
        f"identification method: {card.method}",
        "source records: " + (", ".join(card.sources) if card.sources else "not stated in the fit file"),
        *comment_lines(card.provenance, "fit file"),
        f"unit system: {units.name} (length {units.name.split('-')[0]}, time {units.name.split('-')[1]}, "
        f"mass {units.name.split('-')[2]}, force {units.force_name}, stress {units.stress_name}); {temperature_note}",
        law_line(card, pm),
        "+/-: standard uncertainty (k = 1) of each constant, the fit's standard error and the curve-shape band in "
        "quadrature where the fit file states both (total_uncertainty), else the standard error alone",
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
    lines.append(f"beyond the last measured point every tabulated curve continues with the fitted {card.law.display_name} law's "
                 f"hardening at its rate and temperature, scaled to meet that point, up to plastic strain {options.extend_to:g} "
                 "(the same rule in every format)")
    if card.fracture:
        tri = card.fracture_triaxiality_range
        lines.append("Johnson-Cook fracture: " + ", ".join(pm(k, card.fracture[k], errors=card.fracture_stderr).join((f"{k} = ", ""))
                                                          for k in DAMAGE_KEYS)
                     + "; triaxiality sigma_m/sigma_eq positive in tension (the seed's p/sigma_s with p positive in "
                     "compression is its negative); identified on triaxiality "
                     + (f"{tri[0]:.3g} to {tri[1]:.3g}" if tri else "not stated in the fit file"))
    if card.friction_mu is not None:
        lines.append(f"friction coefficient mu = {card.friction_mu:.4g} "
                     + ("(given: --friction)" if "--friction" in card.given else "(specimen-platen, identified from barrelling)"))
    if card.E_MPa is not None:
        lines.append(f"elastic modulus E = {card.E_MPa:.6g} MPa: {card.E_source or 'source not stated in the fit file'}")
    if card.given:
        lines.append("given on the command line, not identified: " + ", ".join(f"{k} {v:g}" for k, v in card.given.items()))
    return lines



"""The typed results of the tension and compression identifications (``result.json``).

:class:`TensionResult` and :class:`CompressionResult` hold what the pipelines of
:mod:`identification.tension` and :mod:`identification.compression` produce, one field per
top-level key of ``result.json`` (the keys carry units: ``Rm_MPa``), in the order the file
lists them. :meth:`as_dict` is the ``result.json`` object, :meth:`to_json` its text; the main
hardening fit is a small dataclass of its own that keeps the fitted law callable
(``result.hardening.fit(eps_p)``). The inverse FE identifications (``--method inverse-fe``)
return the same two results with an ``inverse_fe`` block (:class:`CompressionInverseFE`,
:class:`TensionInverseFE`) and their own hardening (:class:`InverseHardening`,
:class:`TensionInverseHardening`).

Transition aid: both results also read like the dict they replace (``result["E_MPa"]``,
``.get``, ``.keys()``, ``in``, ``dict(result)``) and accept assignment to their own keys
(``result["warnings"] = ...``, ``result.setdefault("record", {})``), so callers written for the
dict keep working; a key that is not a field is a ``KeyError`` and keys cannot be deleted.
New code should use the attributes.
"""

from __future__ import annotations

import json
from collections.abc import MutableMapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any

from flowcurve.identification.outcome import to_jsonable

if TYPE_CHECKING:
    from flowcurve.identification.laws.hardening import HardeningFit


class _ResultMapping(MutableMapping):
    """Mapping access to a result dataclass's fields, as the keys of ``result.json``."""

    _optional: tuple[str, ...] = ()  # keys left out of result.json while their value is None

    def _names(self):
        """The keys present, in field order."""
        return [f.name for f in fields(self) if not (f.name in self._optional and getattr(self, f.name) is None)]

    def __getitem__(self, key: str) -> Any:
        if key not in self._names():
            raise KeyError(key)
        value = getattr(self, key)
        return value.as_dict() if hasattr(value, "as_dict") else value  # nested parts as their JSON object

    def __setitem__(self, key: str, value: Any) -> None:
        if key not in {f.name for f in fields(self)}:
            raise KeyError(f"{type(self).__name__} has no key {key!r}")
        setattr(self, key, value)

    def __delitem__(self, key: str) -> None:
        raise TypeError(f"{type(self).__name__}: keys of result.json cannot be removed")

    def __iter__(self):
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def as_dict(self) -> dict:
        """The ``result.json`` object (nested parts as dicts; numbers not yet made JSON-able)."""
        return {key: self[key] for key in self}

    def to_json(self) -> str:
        """The text of ``result.json``: numpy values as Python, NaN and inf as null."""
        return json.dumps(to_jsonable(self.as_dict()), indent=2, allow_nan=False) + "\n"


@dataclass
class TensionHardening:
    """The main hardening fit of a tension identification and how the fracture point entered it."""

    fit: HardeningFit
    fracture_point_weight: float | None  # its weight in the least squares, when it was included
    fracture_point: str  # "included", "excluded" or "none"
    fracture_point_choice: str | None  # why
    uniform_range_error_pct: float  # max |σ_fit/σ − 1| over the uniform range, %
    fit_range: list[float]  # true plastic strain of the fitted uniform range
    start_uncertainty: dict | None = None  # the curve's start as far as it rests on the strain zero (methods §2.11)

    def as_dict(self) -> dict:
        """The tension hardening block of result.json."""
        return {**self.fit.as_dict(), "fracture_point_weight": self.fracture_point_weight, "fracture_point": self.fracture_point,
                "fracture_point_choice": self.fracture_point_choice, "uniform_range_error_pct": self.uniform_range_error_pct,
                "fit_range": self.fit_range, "start_uncertainty": self.start_uncertainty}


@dataclass
class CompressionHardening:
    """The main hardening fit of a compression identification and the friction correction it was fitted on."""

    fit: HardeningFit
    correction: str
    start_uncertainty: dict | None = None  # the curve's start as far as it rests on the strain zero (methods §2.11)
    # the method's shares inside the stated standard errors (μ, FE model form, fit range): name → {result key: u} (methods §4.8)
    stderr_shares: dict | None = None

    def as_dict(self) -> dict:
        """The compression hardening block of result.json."""
        correlations = {a: {b: round(r, 3) for b, r in row.items()} for a, row in self.fit.correlations.items()}  # A and n trade off
        return {**self.fit.as_dict(), "correlations": correlations, "correction": self.correction, "start_uncertainty": self.start_uncertainty,
                "stderr_shares": self.stderr_shares}


class _Block:
    """A block of result.json as a dataclass: :meth:`as_dict` gives its fields as the keys, in field order."""

    _optional: tuple[str, ...] = ()  # keys left out while their value is None
    _spread: tuple[str, ...] = ()  # fields whose own keys stand in the block in their place

    def as_dict(self) -> dict:
        """The block's JSON object (nested blocks as dicts; numbers not yet made JSON-able)."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in self._optional:
                continue
            if f.name in self._spread:
                out.update(value.as_dict())
            else:
                out[f.name] = value.as_dict() if hasattr(value, "as_dict") else value
        return out


@dataclass
class InverseHardening:
    """The law an inverse FE fit of compression identified (constants fitted with CalculiX in the loop).

    ``params`` and ``stderr`` by the law's parameter names; result.json names them by its keys
    (``A_MPa``, ``A_MPa_stderr``); ``fit_error_pct`` and ``rms_error_pct`` are the fitted model's
    force misfit (max and RMS, %); ``quality`` is "poor" when the fit warned, else not written.
    """

    law: str
    params: dict[str, float]
    stderr: dict[str, float]  # NaN where the record does not determine a constant (null in result.json)
    fit_error_pct: float
    rms_error_pct: float
    strain_range: list[float]  # true plastic strain of the law's curve
    quality: str | None = None
    method: str = "inverse_fe"

    def __call__(self, eps_p):
        """σ_true(ε_p), MPa, of the identified law."""
        from flowcurve.identification.laws.hardening import static_form

        return static_form(self.law).func(eps_p, **self.params)

    def as_dict(self) -> dict:
        """result.json's ``hardening`` object: the law, its constants by their keys, their standard errors and the errors."""
        from flowcurve.identification.laws.hardening import static_form

        law = static_form(self.law)
        return {"law": self.law, "method": self.method, **{k: self.params[n] for n, k in zip(law.names, law.keys)},
                **{f"{k}_stderr": self.stderr[n] for n, k in zip(law.names, law.keys)}, "fit_error_pct": self.fit_error_pct,
                "rms_error_pct": self.rms_error_pct, "strain_range": self.strain_range, **({"quality": self.quality} if self.quality else {})}


@dataclass
class TensionInverseHardening:
    """A law refitted to the FE-consistent flow curve of an inverse FE fit of tension (measured to ε_a, CalculiX beyond)."""

    fit: HardeningFit
    strain_range: list[float]  # [0.002, the fracture strain]
    fit_poor: bool = False  # the inverse fit itself warned: quality "poor", whatever the refit's own
    fitted_to: str = "the FE-consistent flow curve (measured to ε_a, CalculiX beyond)"
    method: str = "inverse_fe"

    def as_dict(self) -> dict:
        """result.json's ``hardening`` object: the refit's, with the method, what it was fitted to and its range."""
        out = {**self.fit.as_dict(), "method": self.method, "fitted_to": self.fitted_to, "strain_range": self.strain_range}
        if self.fit_poor:
            out["quality"] = "poor"
        return out


@dataclass
class InverseBudget(_Block):
    """``inverse_fe.budget`` of tension: the wall-time limit, whether it cut the fit, what was fitted (in words)."""

    time_limit_s: float | None  # None: no limit
    cut: bool
    solver_runs: int
    wall_s: float
    done: str


@dataclass
class CompressionBudget(_Block):
    """``inverse_fe.budget`` of compression: the tension's, and how far the force was fitted (the fold-over's onset)."""

    time_limit_s: float | None
    cut: bool
    solver_runs: int
    wall_s: float
    fold_over_strain: float | None  # where the side folds onto the platen in the warm start's run (None: it does not)
    force_fitted_to_strain: float
    record_strain: float
    done: str


@dataclass
class CompressionInverseFE(_Block):
    """result.json's ``inverse_fe`` block of compression: μ and its standard errors, the misfits, the runs, the budget,
    the warm start and the model; what the force and the shape alone tell of μ (``by_side``) where the fit has a Jacobian."""

    _optional = ("dface_residual_mm", "by_side", "force_shape_check")
    _spread = ("by_side",)

    law: dict  # the law given, or chosen and why
    mu: float
    mu_stderr: float  # NaN: undetermined
    mu_stderr_shape_alone: float | None
    force_residual_serial_correlation: float
    shape_sigma_mm: dict  # dmax (and dface): the σ each diameter row is weighed by
    solver_runs: int
    failed_solver_runs: int
    retried_solver_runs: int
    solver_s: float
    wall_s: float
    force_rms_residual_pct: float
    force_max_residual_pct: float
    dmax_residual_mm: float
    dface_residual_mm: float | None  # not written without a measured end face
    shape_measured: list[str]
    optimizer: dict  # status, message, nfev
    budget: CompressionBudget
    warm_start: dict  # μ and the law's constants the fit started from
    model: dict  # increments, the model's elastics, the diagram's options, the force rows' settings
    by_side: Any = None  # a .fe.force_shape.MuBySide: written as mu_force_alone, mu_shape_alone, force_shape_disagreement_sigmas
    force_shape_check: str | None = None  # what comparing the two sides found


@dataclass
class TensionInverseFE(_Block):
    """result.json's ``inverse_fe`` block of tension: the family beyond ε_a (H, β, c; :func:`.fe.inverse_tension.hardening_beyond`)
    and the taper δ with their standard errors, the FE fracture stress, the neck corrections against it, the runs, the
    budget, the misfits, the warm starts and the model."""

    H_MPa: float
    H_MPa_stderr: float
    beta: float
    beta_stderr: float
    c: float
    c_stderr: float
    taper: float
    taper_stderr: float
    sigma_a_MPa: float  # the measured curve's stress at ε_a
    measured_to_true_plastic_strain: float  # ε_a
    sigma_u_MPa: float
    uniform_rows: dict  # the measured curve's *PLASTIC rows up to ε_a
    uniform_true_plastic_strain: float
    fracture_true_stress_MPa: float | None  # the FE-consistent curve's at the fracture strain (None: no fracture)
    fracture_true_stress_MPa_stderr: float | None
    neck_corrections_vs_fe: dict  # method → its stress and how far it is from the FE one, %
    solver_runs: int
    failed_solver_runs: int
    solver_s: float
    wall_s: float
    budget: InverseBudget
    force_rms_residual_pct: float
    force_max_residual_pct: float
    force_residual_serial_correlation: float
    neck_radius_residual_mm: float | None  # None: no neck diameter measured
    law_rms_error_pct: dict  # law → its RMS error against the FE-consistent curve, %
    optimizer: dict
    warm_starts: dict  # law → the family's H, β, c and the taper it started from
    model: dict


@dataclass(kw_only=True)
class TensionResult(_ResultMapping):
    """A tension identification: ISO 6892-1 results, true curve points, neck corrections, hardening."""

    _optional = ("uncertainty", "inverse_fe", "provenance")

    test: str = "tension"
    E_MPa: float
    E_stderr_MPa: float | None  # None when E was not regressed (option or handbook)
    modulus: dict  # the elastic line: window, samples, r², source; E used and regressed
    Rp02_MPa: float
    yield_point: bool  # ISO 6892-1: with a yield point ReH/ReL are the yield strengths
    ReH_MPa: float | None
    ReL_MPa: float | None
    Ae_pct: float | None
    Rm_MPa: float
    Fm_N: float
    Ag_pct: float
    Agt_pct: float  # percentage total extension at maximum force (ISO 6892-1 3.6.5)
    At_pct: float | None  # percentage total extension at fracture (3.6.6); None when the record does not reach it
    A_pct: float | None
    A_method: str | None  # how A was obtained: Lu − L0 measured after fracture, or the extension at fracture less its elastic part
    Z_pct: float | None
    uniform_true_strain: float
    uniform_true_plastic_strain: float
    fracture_true_strain: float | None
    fracture_true_stress_MPa: float | None
    fracture_avg_stress_MPa: float | None
    neck_corrections: dict
    hardening: TensionHardening | TensionInverseHardening
    hardening_alternatives: dict  # name → the other fits' dicts
    three_points: list | None
    modulus_window_MPa: list[float]
    methods: dict
    warnings: list[str]
    uncertainty: dict | None = None  # GUM budget per result (identification.assurance)
    record: dict = field(default_factory=dict)  # where the record came from (record.summary)
    inverse_fe: TensionInverseFE | None = None  # only from the inverse FE identification
    provenance: dict | None = None  # version, record_sha256, options, date (identification.provenance); set by the writer


@dataclass(kw_only=True)
class CompressionResult(_ResultMapping):
    """A compression identification: friction by every method, corrected curves, hardening."""

    _optional = ("E_apparent_stderr_MPa", "modulus", "friction_mu_range", "uncertainty", "inverse_fe", "dface_advice", "provenance")

    test: str = "compression"
    E_MPa: float | None
    E_source: str  # option (handbook) / record (material.E_MPa) / apparent (initial slope, §2.3) / none
    Rp02_MPa: float | None  # compression yield: mean pressure at 0.2 % plastic strain
    Rm_MPa: None = None
    Ag_pct: None = None
    A_pct: None = None
    Z_pct: None = None
    fracture_true_strain: None = None
    fracture_true_stress_MPa: None = None
    max_force_N: float
    final_true_strain: float
    friction_mu: float
    friction_mu_range: list | None = None  # [lo, hi] the friction method's μ for the measured shape ± its resolution and the FE mesh's share (fe_table only)
    friction_method: str
    friction: dict  # method → μ (None where not applicable)
    friction_details: dict
    friction_correction: str
    hardening: CompressionHardening | InverseHardening
    hardening_by_correction: dict  # correction → fit dict
    indicator: dict  # frame stiffness, K_l, shortening, spring-back, toe
    methods: dict
    warnings: list[str]
    uncertainty: dict | None = None  # GUM budget per result (identification.assurance)
    record: dict = field(default_factory=dict)
    E_apparent_stderr_MPa: float | None = None  # only with the apparent modulus
    modulus: dict | None = None  # only with an elastic line
    inverse_fe: CompressionInverseFE | None = None  # only from the inverse FE identification
    dface_advice: str | None = None  # μ poorly told by dmax and no end face measured: measuring post.dface_mm would settle it
    provenance: dict | None = None  # version, record_sha256, options, date (identification.provenance); set by the writer

"""The typed results of the tension and compression identifications (``result.json``).

:class:`TensionResult` and :class:`CompressionResult` hold what the pipelines of
:mod:`identification.tension` and :mod:`identification.compression` produce, one field per
top-level key of ``result.json`` (the keys carry units: ``Rm_MPa``), in the order the file
lists them. :meth:`as_dict` is the ``result.json`` object, :meth:`to_json` its text; the main
hardening fit is a small dataclass of its own that keeps the fitted law callable
(``result.hardening.fit(eps_p)``).

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

    def as_dict(self) -> dict:
        """The compression hardening block of result.json."""
        correlations = {a: {b: round(r, 3) for b, r in row.items()} for a, row in self.fit.correlations.items()}  # A and n trade off
        return {**self.fit.as_dict(), "correlations": correlations, "correction": self.correction, "start_uncertainty": self.start_uncertainty}


@dataclass(kw_only=True)
class TensionResult(_ResultMapping):
    """A tension identification: ISO 6892-1 results, true curve points, neck corrections, hardening."""

    _optional = ("uncertainty", "provenance")

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
    hardening: TensionHardening
    hardening_alternatives: dict  # name → the other fits' dicts
    three_points: list | None
    modulus_window_MPa: list[float]
    methods: dict
    warnings: list[str]
    uncertainty: dict | None = None  # GUM budget per result (identification.assurance)
    record: dict = field(default_factory=dict)  # where the record came from (record.summary)
    provenance: dict | None = None  # version, record_sha256, options, date (identification.provenance); set by the writer


@dataclass(kw_only=True)
class CompressionResult(_ResultMapping):
    """A compression identification: friction by every method, corrected curves, hardening."""

    _optional = ("E_apparent_stderr_MPa", "modulus", "friction_mu_range", "uncertainty", "dface_advice", "provenance")

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
    hardening: CompressionHardening
    hardening_by_correction: dict  # correction → fit dict
    indicator: dict  # frame stiffness, K_l, shortening, spring-back, toe
    methods: dict
    warnings: list[str]
    uncertainty: dict | None = None  # GUM budget per result (identification.assurance)
    record: dict = field(default_factory=dict)
    E_apparent_stderr_MPa: float | None = None  # only with the apparent modulus
    modulus: dict | None = None  # only with an elastic line
    dface_advice: str | None = None  # μ poorly told by dmax and no end face measured: measuring post.dface_mm would settle it
    provenance: dict | None = None  # version, record_sha256, options, date (identification.provenance); set by the writer

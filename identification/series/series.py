"""Johnson–Cook constants from a test series: one global least-squares fit, or stepwise.

A series is a list of :class:`SeriesMember` — the true curve σ(εp) of one test with the strain
rate and temperature it was run at — built from records (identified with
:func:`identification.identify.identify`) or from the result folders of ``flowcurve identify``.

* :func:`fit_global` — A, B, n, C, m in one least-squares problem over all curves (lmfit, the
  default);
* :func:`fit_stepwise` — the classic procedure: A, B, n at the reference condition (with
  :func:`identification.hardening.fit_hardening`), then C from the reference-temperature
  records at higher rates, then m from the records above the reference temperature;
* :func:`fit_series` — both, plus the covered range and the tabulated curves per condition:
  everything ``fit.json`` holds (schema in ``docs/fit-json.md``).

The model and its conventions (T* clamped to [0, 1], no rate effect below ε̇0) are those of
:mod:`identification.johnson_cook`.

The series is split by concern: :mod:`identification.series_members` (the members, loaded from
records or result folders, and the strain rate of a record) and :mod:`identification.series_fit`
(the reference, the fits, :func:`fit_series`). This module is the public facade: it re-exports
their names, so ``from flowcurve.identification.series.series import fit_series`` keeps working.
"""

from __future__ import annotations

from flowcurve.identification.series.fit import (BOUNDS, DISTINCT_LOG_RATE, DISTINCT_T_STAR, KEYS, MAX_POINTS, PARAMS,
                                                 REF_RATE_FACTOR, REF_TEMPERATURE_TOL_C, SAME_RATE_REL, SAME_TEMPERATURE_C,
                                                 ConditionCurve, JohnsonCookFit, Reference, SeriesFit, check_identifiable,
                                                 condition_curves, fit_global, fit_series, fit_stepwise, make_reference)
from flowcurve.identification.series.members import (PLASTIC_START, SeriesMember, load_members, member_from_record,
                                                     member_from_result, plastic_part, strain_rate_from_record)

__all__ = [
    "BOUNDS", "DISTINCT_LOG_RATE", "DISTINCT_T_STAR", "KEYS", "MAX_POINTS", "PARAMS", "PLASTIC_START", "REF_RATE_FACTOR",
    "REF_TEMPERATURE_TOL_C", "SAME_RATE_REL", "SAME_TEMPERATURE_C",
    "ConditionCurve", "JohnsonCookFit", "Reference", "SeriesFit", "SeriesMember",
    "check_identifiable", "condition_curves", "fit_global", "fit_series", "fit_stepwise", "load_members", "make_reference",
    "member_from_record", "member_from_result", "plastic_part", "strain_rate_from_record",
]

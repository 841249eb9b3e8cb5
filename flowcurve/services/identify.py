"""Identification of one record: the typed request and the service ``flowcurve identify`` and the console call.

:func:`identify` loads a record (native, INSTRON export or any CSV through ``columns``),
identifies it (fast, or the inverse FE with ``method="inverse-fe"``) and writes its result
folder ``out/<record name>/`` with result.json (its provenance block), true_curve.csv and plots.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from flowcurve.errors import RecordError


@dataclass
class IdentifyRequest:
    """One record to identify, as ``flowcurve identify`` and the console ask for it.

    Attributes
    ----------
    record : str or Path
        The record file (native, or a foreign export: CSV, INSTRON, text).
    out : Path
        The folder the record's result folder is written under.
    columns : dict, optional
        A plain CSV's quantity → (column, unit); None: recognised from the column names.
    meta : dict
        Header values given (geometry in mm, material …), overriding the file's.
    options : dict
        The identification's options (neck, hardening, law, E_MPa, method, workers, time_limit …; None: default).
    plots : bool
        Draw the result's PNG plots.
    record_sha256 : str, optional
        The record file's SHA-256 when the caller has it (else computed).
    """

    record: str | Path
    out: Path
    columns: dict | None = None
    meta: dict[str, str] = field(default_factory=dict)
    options: dict = field(default_factory=dict)
    plots: bool = True
    record_sha256: str | None = None


def given_options(options: dict, meta: dict, columns) -> dict:
    """The options as given that decide a record's result (result.json's provenance.options):
    the identification options set, the metadata given (options, --set, --specimens row) and
    the --column mapping; not --workers/--jobs/--scheduler, which change only the speed."""
    given = {k: v for k, v in options.items() if v is not None and k != "workers"}
    return {**given, **({"metadata": dict(meta)} if meta else {}), **({"columns": dict(columns)} if columns else {})}


def identify(req: IdentifyRequest, progress: Callable | None = None):
    """Load, identify and write one record; returns (identification, result folder).

    result.json carries a ``provenance`` block (:mod:`identification.provenance`): the record
    file's SHA-256 (``record_sha256`` when the caller has it), the options as given, the date,
    and ccx's version when the inverse FE ran the solver.

    A numerical warning (numpy's RuntimeWarning) is not printed raw: it joins the result's
    warnings, so it is written to result.json and shown in one line under the record.

    Parameters
    ----------
    req : IdentifyRequest
        The record's path, the output folder, column mapping and header values for a foreign
        export, the identification's options, whether to plot.
    progress : callable, optional
        ``progress(runs, elapsed_s, left_s, limit_s)`` while the inverse FE runs CalculiX.

    Returns
    -------
    (Identification, Path)
        The identification and the folder its result.json, curves and plots were written to.
    """
    from flowcurve.identification.identify import identify as identify_record
    from flowcurve.identification.provenance import file_sha256, provenance
    from flowcurve.record.importers import load_record

    path, columns, meta, out = str(req.record), req.columns, req.meta, Path(req.out)
    given = given_options(req.options, meta, columns)
    options = dict(req.options)
    method, workers, time_limit = options.pop("method", "fast"), options.pop("workers", None), options.pop("time_limit", None)
    raise_runtime = _runtime_warnings_raise()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if raise_runtime:  # '-W error::RuntimeWarning' from outside still raises (tests find the source)
            warnings.simplefilter("error", RuntimeWarning)
        record = load_record(path, columns=columns, meta=meta)
        if method == "inverse-fe":
            from flowcurve.identification.identify import identify_inverse_fe, inverse_time_limit_s

            limit = time_limit or inverse_time_limit_s(record.test)

            def told(runs, elapsed, left_s=None):  # progress(runs, elapsed_s, left_s, limit_s), e.g. a terminal line
                """Tell ``progress`` (runs, elapsed s, left s, limit s) when given."""
                if progress is not None:
                    progress(runs, elapsed, left_s, limit)

            ident = identify_inverse_fe(record, law=options.get("law") or "auto", workers=workers, progress=told,
                                        E_MPa=options.get("E_MPa"), **({"time_limit_s": time_limit} if time_limit is not None else {}))
        else:
            ident = identify_record(record, **options)
    caught_lines = [f"{'numerical warning' if issubclass(w.category, RuntimeWarning) else w.category.__name__}: {w.message}" for w in caught]
    if caught_lines:
        old = ident.result.setdefault("warnings", [])
        old.extend(m for m in dict.fromkeys(caught_lines) if m not in old)
    solver = None
    if method == "inverse-fe":
        from flowcurve.identification.fe.model.ccx import ccx_version

        solver = ccx_version()
    ident.result["provenance"] = provenance(req.record_sha256 or file_sha256(path), given, ccx_version=solver)
    if req.plots:
        from flowcurve.reports.plots import add_plots

        add_plots(ident)
    folder = out / record.name
    try:
        ident.write(folder)
    except OSError as exc:
        raise RecordError(folder, f"cannot write the results ({exc.strerror or exc}); choose another --out") from None
    return ident, folder


def _runtime_warnings_raise() -> bool:
    """Did the caller make RuntimeWarnings errors ('-W error::RuntimeWarning')? The first filter
    that applies to them decides, as in the warnings module."""
    for action, _message, category, _module, _line in warnings.filters:
        if issubclass(RuntimeWarning, category):
            return action == "error"
    return False



"""``flowcurve fit``: Johnson–Cook constants from a series of records or result folders.

Parses the options into a :class:`~flowcurve.services.fit.FitRequest`, loads the members (side
by side with ``--jobs``) and calls :func:`flowcurve.services.fit.fit`, which writes ``fit.json``,
``curves/`` and ``plots/``.
"""

from __future__ import annotations

import sys

from flowcurve.services.fit import MAX_POINTS as DEFAULT_MAX_POINTS  # the series fit's, without importing it (lmfit) for --help
from flowcurve.services.fit import SHAPE_ERROR_PCT as DEFAULT_SHAPE_ERROR_PCT


def register(subparsers) -> None:
    """Add ``fit`` and ``laws`` to the subcommands."""
    register_laws(subparsers)
    p = subparsers.add_parser(
        "fit",
        help="Johnson-Cook constants (A, B, n, C, m), or another registered law's (--law), from a series of tests",
        description=(
            "Fit the Johnson-Cook flow stress sigma = (A + B*eps_p^n)(1 + C ln(rate/ref_rate))(1 - T*^m) "
            "to the true curves of a series of tests (records, result folders of 'flowcurve identify', "
            "or folders of them). T* is clamped to [0, 1] and there is no rate effect below the "
            "reference rate. Writes fit.json, curves/*.csv and plots/*.png."
        ),
    )
    p.add_argument("inputs", nargs="+", metavar="RECORD_OR_DIR", help="record files, result folders, or folders of result folders")
    p.add_argument("--out", default="fit", metavar="DIR", help="output folder (default: ./fit)")
    p.add_argument("--ref-rate", type=float, metavar="1/s", help="reference strain rate (default: the lowest rate of the series)")
    p.add_argument("--ref-temp", type=float, metavar="C", help="reference temperature, °C (default: the lowest of the series)")
    p.add_argument("--melt-temp", type=float, metavar="C", help="melting temperature of the material, °C (required)")
    p.add_argument("--law", default="johnson_cook", metavar="NAME",
                   help="a registered law with strain rate and temperature (default johnson_cook; e.g. hensel_spittel, T in °C; "
                        "'flowcurve laws' lists them); checked when the fit runs")
    p.add_argument("--method", choices=("global", "stepwise"), default="global",
                   help="global least squares over all curves (default) or the classic stepwise procedure; the other is reported for comparison")
    p.add_argument("--fix-C", type=float, metavar="VALUE", help="do not identify C, use this value (e.g. for a series at one rate)")
    p.add_argument("--fix-m", type=float, metavar="VALUE", help="do not identify m, use this value (e.g. for a series at one temperature)")
    p.add_argument("--E", dest="E_MPa", type=float, metavar="MPA", help="elastic modulus for records that have no handbook material.E_MPa (default: each record's identified modulus)")
    p.add_argument("--rate-per-record", action="store_true",
                   help="one strain rate per record (its mean) instead of each point's own v/h: for records whose material "
                        "has no rate dependence within the record, e.g. FE records made with the law at one rate")
    p.add_argument("--strict", action="store_true", help="exit non-zero when the fit is poor (max error above 10 %%); fit.json is still written, marked poor")
    p.add_argument("--max-points", type=int, default=DEFAULT_MAX_POINTS, metavar="N", help=f"points per record in the fit, the same for every record (default {DEFAULT_MAX_POINTS})")
    p.add_argument("--shape-error", type=float, default=DEFAULT_SHAPE_ERROR_PCT, metavar="PCT",
                   help="RMS shape error assumed for the true curves, %% (default %(default)s: what the friction correction leaves on "
                        "FE compression records); fit.json's shape_uncertainty says how far it can move each constant")
    p.add_argument("--fracture-points", metavar="FILE.csv",
                   help="fracture points measured elsewhere for the Johnson-Cook fracture constants D1-D5 (columns triaxiality "
                        "[sigma_m/sigma_eq, positive in tension], strain_rate_per_s, temperature_C, fracture_strain); "
                        "added to the fractures of the series' tension records")
    p.add_argument("--strict-records", action="store_true",
                   help="refuse the series when any record cannot be read (default: skip it with a warning naming it, fit the rest "
                        "and say how many were used)")
    p.add_argument("--adiabatic", action="store_true",
                   help="correct for adiabatic heating: each point at T0 + beta*int(sigma d eps_p)/(rho*c_p), so the fitted law is "
                        "the isothermal one (needs --density and --heat-capacity, or the records' material.density_kg_per_m3 and material.heat_capacity_J_per_kg_K); fit.json gives each record's largest rise")
    p.add_argument("--taylor-quinney", type=float, default=0.9, metavar="BETA",
                   help="part of the plastic work turned into heat, for --adiabatic (default %(default)s)")
    p.add_argument("--density", dest="density_kg_per_m3", type=float, metavar="KG/M3", help="material density for --adiabatic, kg/m³")
    p.add_argument("--heat-capacity", dest="heat_capacity_J_per_kg_K", type=float, metavar="J/(KG.K)",
                   help="specific heat capacity for --adiabatic, J/(kg·K)")
    p.add_argument("--adiabatic-min-rate", type=float, default=0.0, metavar="1/s",
                   help="correct only the records at or above this strain rate (default 0: every record; slow tests lose their heat "
                        "to the platens)")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="identify N records side by side in separate processes (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="identify the records as tasks on this Dask distributed scheduler (needs the 'fe' extra)")
    p.set_defaults(func=run)


# options that change only where and how fast the fit runs, not fit.json's numbers
NOT_RESULT_OPTIONS = {"command", "func", "inputs", "out", "jobs", "scheduler", "verbose", "log_level"}


def _members_of(item: tuple[str, dict]):
    """The series members of one input (a worker's task): ("ok", members) or ("error", message)
    — a FlowcurveError's own arguments do not survive pickling, its message does."""
    from flowcurve.errors import FlowcurveError
    from flowcurve.identification.series.series import load_members

    try:
        return "ok", load_members([item[0]], **item[1])
    except FlowcurveError as exc:
        return "error", str(exc)


def load_members_in_parallel(inputs, identify_options: dict, jobs: int = 1, scheduler: str | None = None,
                             skipped: list[str] | None = None):
    """load_members over the inputs, ``jobs`` at a time or as Dask tasks, with a progress bar on
    standard error. Each input that fails names itself; with a list ``skipped`` the failing inputs
    are left out and their errors appended to it (all failing, or ``skipped`` None: the error
    names every failing input)."""
    from flowcurve.cli.progress import ProgressBar
    from flowcurve.errors import FlowcurveError, IdentificationError
    from flowcurve.identification.fe.pool import run_many

    if jobs < 1:
        raise FlowcurveError(f"--jobs must be ≥ 1, got {jobs}")
    bar = ProgressBar(len(inputs), "inputs") if len(inputs) > 1 else None
    if jobs > 1 and scheduler is None:
        from flowcurve.cli.identification import preload_identification

        preload_identification()
    try:
        outcomes = run_many(_members_of, [(str(p), identify_options) for p in inputs], workers=jobs, scheduler=scheduler,
                            progress=(lambda done, _total, _elapsed: bar.update(done)) if bar else (lambda *_: None))
    finally:
        if bar:
            bar.close()
    errors = [message for status, message in outcomes if status == "error"]
    if errors and (skipped is None or len(errors) == len(outcomes)):
        raise FlowcurveError(errors[0] if len(errors) == 1 else f"{len(errors)} of {len(outcomes)} inputs cannot be read: " + "; ".join(errors))
    if errors:
        skipped += [f"skipped (cannot be read): {message}" for message in errors]
        skipped.append(f"fitted on {len(outcomes) - len(errors)} of {len(outcomes)} inputs ({len(errors)} skipped; --strict-records refuses the series instead)")
    members = [m for status, found in outcomes if status == "ok" for m in found]
    names = [m.name for m in members]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise IdentificationError(f"two series members have the same name {', '.join(dup)}; rename one (names label the per-record errors and plots)")
    return members


def register_laws(subparsers) -> None:
    """Add ``laws``: the registered laws, read from the registry (a law's file is enough to list it)."""
    p = subparsers.add_parser("laws", help="the registered hardening laws: names for identify --law and fit --law, equations, constants",
                              description="List every registered law (identification/laws/, one file each): its name for "
                                          "'flowcurve identify --law' (static laws) or 'flowcurve fit --law' (laws with strain "
                                          "rate and temperature), its equation and its constants with their units.")
    p.set_defaults(func=run_laws)


def law_lines() -> list[str]:
    """One block per registered law: name, display name, where it is used, equation, constants (unit)."""
    from flowcurve.identification.laws.base import registered_laws
    from flowcurve.identification.laws.hardening import static_law_names

    static = set(static_law_names())
    lines = []
    for name, law in registered_laws().items():
        use = ("identify --law, fit --law" if name in static and law.rate_dependent and law.temperature_dependent
               else "identify --law" if name in static else "fit --law" if law.rate_dependent and law.temperature_dependent
               else "neither (a static part of another law)")
        constants = ", ".join(f"{p.name}{f' ({p.unit})' if p.unit else ''}" for p in law.parameters)
        lines += [f"{name}: {law.display_name} [{use}]", f"  {law.equation}", f"  constants: {constants}"]
    lines.append("identify --law best: every static law fitted, the lowest AIC among the laws whose constants the curve determines "
                 "and whose least-squares minimum is not flat (a refit that does not settle is not reproducible)")
    return lines


def run_laws(args) -> int:
    """``flowcurve laws``: print the registry; exit 0."""
    print("\n".join(law_lines()))
    return 0


def run(args) -> int:
    """``flowcurve fit``: fit a law to a series of records or result folders; the exit status."""
    from flowcurve.identification.laws.base import get_law
    from flowcurve.services.fit import FitRequest, fit, summary

    get_law(args.law)  # an unknown law is refused before any record is read

    request = FitRequest(args.inputs, args.out, ref_rate=args.ref_rate, ref_temp=args.ref_temp, melt_temp=args.melt_temp,
                         method=args.method, fix_C=args.fix_C, fix_m=args.fix_m, E_MPa=args.E_MPa,
                         rate_per_record=getattr(args, "rate_per_record", False), max_points=args.max_points,
                         shape_error=args.shape_error, fracture_points=args.fracture_points, law=args.law,
                         adiabatic=getattr(args, "adiabatic", False), taylor_quinney=getattr(args, "taylor_quinney", 0.9),
                         density_kg_per_m3=getattr(args, "density_kg_per_m3", None),
                         heat_capacity_J_per_kg_K=getattr(args, "heat_capacity_J_per_kg_K", None),
                         adiabatic_min_rate=getattr(args, "adiabatic_min_rate", 0.0),
                         options={k: v for k, v in vars(args).items() if k not in NOT_RESULT_OPTIONS and v is not None})
    skipped = None if getattr(args, "strict_records", False) else []
    members = load_members_in_parallel(args.inputs, {"E_MPa": args.E_MPa} if args.E_MPa is not None else {}, args.jobs, args.scheduler,
                                       skipped=skipped)
    for line in skipped or []:
        print(f"flowcurve: warning: {line}", file=sys.stderr)
    request.warnings = list(skipped or [])
    series, out = fit(request, members)
    print(summary(series, out))
    if series.quality == "poor" and args.strict:
        print(f"flowcurve: error: the fit is poor (max error {series.fit.fit_error_pct:.3g} % > 10 %); {out} is marked poor (--strict)", file=sys.stderr)
        return 2
    return 0

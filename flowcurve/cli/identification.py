"""``flowcurve identify``: records in, true curves, results, hardening constants and plots out."""

from __future__ import annotations

import argparse
import logging
import math
import os
import sys
from pathlib import Path

from flowcurve.cli.choices import FRICTION_CORRECTIONS, FRICTION_METHODS, NECK_METHODS, TEST_TYPES
from flowcurve.cli.specimen import GEOMETRY_OPTIONS, add_geometry_options, add_modulus_option, check_specimen_options, measurement
from flowcurve.errors import FlowcurveError, MissingValueError, RecordError
from flowcurve.services.identify import IdentifyRequest, given_options, identify

logger = logging.getLogger(__name__)

DEFAULT_OUT = "flowcurve-results"

# --hardening value → the identification's method name
HARDENING_CHOICES = {"lsq": "least_squares", "three-point": "three_point"}

# command-line option → metadata key it sets (geometry and post-test measurements, in mm)
META_OPTIONS = {
    "test": "test",
    **{option: key for option, (key, _) in GEOMETRY_OPTIONS.items()},
    "le": "specimen.extensometer_gauge_mm",
    "lu": "post.lu_mm",
    "dk": "post.dk_mm",
    "hk": "post.hk_mm",
    "dmax": "post.dmax_mm",
    "smax": "post.smax_mm2",
    "dface": "post.dface_mm",
    "neck_radius": "post.neck_radius_mm",
    "frame_stiffness": "rig.frame_stiffness_N_per_um",
    "speed": "crosshead_speed_mm_per_s",
}

EPILOG = """\
examples:
  flowcurve identify runs/T600-01.csv
      a native record: geometry and post-test measurements come from its header
  flowcurve identify 46NT71.csv --out results
      an INSTRON export (tab-separated key/value header, force in kN) is recognised
  flowcurve identify export.csv --column force=Load:kN --column crosshead=Extension:mm \\
      --column time=Time:s --test tension --d0 6 --l0 30 --lu 34.1 --dk 3.9
      any CSV: name its columns and units; give the geometry the file lacks
  flowcurve identify bluehill/*.csv --test tension --le 25 --specimens specimens.csv
      other labs' exports (Bluehill, testXpert, MTS): columns named 'Load [kN]', 'Time (s)'
      or with a units row are recognised; a strain column needs the extensometer length
      --le; each specimen's d0, l0, lu, dk ... come from a table with a 'file' column
  flowcurve identify C1.csv --friction-correction siebel --hardening three-point

  flowcurve identify archive/*.csv --jobs 2 --no-plots
      an archive: two records at a time, a progress bar on standard error; run it again and
      the records whose result.json is current are skipped

Options override what a record's header says. Each record gets DIR/<record name>/ with
result.json (its 'provenance': flowcurve version, the record's SHA-256, the options, the
date), true_curve.csv and PNG plots; DIR/summary.csv tables all results. With several
records, one that fails is reported in one line and the others are still identified; the
exit code is then non-zero.
"""


def register(subparsers) -> None:
    """Add ``identify`` to the subcommands."""
    p = subparsers.add_parser(
        "identify",
        help="identify true stress-strain curves, ISO 6892-1 results and hardening constants from records",
        description=(
            "Turn test records into results: the corrected indicator diagram (frame compliance, "
            "toe), engineering and true curves, E, Rp0.2, Rm, Ag, A, Z, neck (tension) or "
            "friction (compression) corrections, and a hardening law fitted to the true curve. "
            "Reads native flowcurve records, INSTRON exports, and any CSV through --column."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("records", nargs="+", metavar="RECORD", help="record file(s) to identify")
    p.add_argument("--out", metavar="DIR", default=DEFAULT_OUT, help=f"folder for the results, one sub-folder per record (default: ./{DEFAULT_OUT})")
    p.add_argument("--column", action="append", default=[], metavar="QUANTITY=COLUMN[:UNIT]",
                   help="for a plain CSV: which column holds time, force, crosshead, extensometer or temperature, "
                        "and its unit (e.g. force=Load:kN, crosshead=Extension:in, temperature=T:K); without a unit "
                        "the file's units row is used. Repeat per column. Units are converted, never guessed.")
    p.add_argument("--specimens", metavar="TABLE.csv",
                   help="per-specimen dimensions for several records: a table with a 'file' column naming each record and "
                        "columns d0, l0, lc, h0, le, lu, dk, du, hk, dmax, smax, dface, neck_radius, speed, temperature, test, material, "
                        "each with its unit in the name ('d0 (mm)', 'd0_mm') or in a units row")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots (faster for long series)")
    b = p.add_argument_group("many records (an archive)")
    b.add_argument("--jobs", type=int, default=1, metavar="N", help="identify N records side by side in separate processes (default 1)")
    b.add_argument("--force", action="store_true", help="identify every record again, even one whose result.json is current "
                   "(same flowcurve version and code, record SHA-256 and options; such a record is skipped by default)")
    g = p.add_argument_group("specimen and test (override the record's header)")
    g.add_argument("--test", choices=TEST_TYPES, help="kind of test, for files that do not say")
    add_geometry_options(g)
    g.add_argument("--le", type=float, metavar="MM", help="extensometer gauge length Le (ISO 6892-1), mm; needed to turn a strain column (%%, mm/mm, -) into elongation")
    g.add_argument("--lu", type=float, metavar="MM", help="gauge length measured after fracture (tension), mm")
    g.add_argument("--dk", type=float, metavar="MM", help="smallest diameter at the fracture (tension), mm")
    g.add_argument("--neck-radius", type=float, metavar="MM", help="profile radius of the neck at fracture (tension), mm; without it a/R is estimated (Le Roy)")
    g.add_argument("--hk", type=float, metavar="MM", help="specimen height after the test (compression), mm")
    g.add_argument("--dmax", type=float, metavar="MM", help="largest (bulge) diameter after the test (compression), mm")
    g.add_argument("--smax", type=float, metavar="MM2", help="largest cross-section area after the test (compression), mm², instead of --dmax")
    g.add_argument("--dface", type=float, metavar="MM", help="diameter of the original end face after the test (compression; its machined "
                   "area, not the side folded onto the platen), mm: the FE table reads μ from it, which near sticking the bulge cannot tell")
    g.add_argument("--speed", type=float, metavar="MM_PER_S", help="crosshead speed, mm/s (needed when a CSV has no time column)")
    g.add_argument("--frame-stiffness", type=float, metavar="N_PER_UM", help="stiffness of the machine frame and grips, N/µm, subtracted from the crosshead travel (rig figure: 136)")
    g.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="any other metadata key, e.g. --set nominal_temperature_C=600")
    m = p.add_argument_group("methods")
    m.add_argument("--no-extensometer", action="store_true", help="use the corrected crosshead travel even when the record has an extensometer channel")
    m.add_argument("--neck-correction", choices=NECK_METHODS, help="neck correction of the fracture stress (tension; default davidenkov; all are reported)")
    m.add_argument("--hardening", choices=tuple(HARDENING_CHOICES), help="hardening identification: least squares over the uniform range plus the fracture point (lsq, default) or exactly through three characteristic points (three-point)")
    add_modulus_option(m, "strips elastic strain with it (e.g. the handbook 194000 for 12Kh18N12M3TL); default: the apparent modulus regressed on the record (§2.3) — for compression records with few elastic samples give it")
    m.add_argument("--true-stress", choices=("constant_volume", "gost_3_6"), help="true stress in the uniform part of a tension test: σ·(1 + e) at constant volume (default) or the seed's corrected (3.6) with bulk modulus, for comparison (it reads up to ~7 %% high at e = 0.4)")
    m.add_argument("--law", metavar="LAW", help="hardening law: any static law of the registry ('flowcurve laws' lists them; default johnson_cook: "
                   "A + B·εp^n; checked when run, with the nearest name) — or best (every one fitted, the lowest AIC among the laws whose "
                   "constants the curve determines and whose least-squares minimum is not flat kept, and by how much it won); with --method inverse-fe on compression the default is the "
                   "law that best fits the fast curve")
    m.add_argument("--modulus-window", type=_pair, metavar="LO,HI", help="stress window of the elastic-modulus regression: MPa (e.g. 50,300), or fractions of Rm when both are ≤ 1 (e.g. 0.1,0.4); default: the widest linear stretch of the first loading, chosen automatically (all of it when it has few samples)")
    m.add_argument("--modulus-method", choices=("auto", "window", "sdar"), help="how the elastic line is found when no --modulus-window is given: window (the widest linear stretch), sdar (ASTM E3076-18, slope determination by analysis of residuals, with its quality metrics) or auto (default: sdar on a crosshead-only tension record, else window)")
    m.add_argument("--fit-range", type=_pair, metavar="LO,HI", help="true plastic strain range of the hardening fit, e.g. 0.01,0.15 (default: from 0.2 %% offset, past a yield plateau, to the end of the uniform range)")
    m.add_argument("--fracture-point", choices=("auto", "include", "exclude"), help="the neck-corrected fracture point in the least-squares hardening fit (tension): include, exclude, or auto (default: included unless it costs the uniform range more than 2 %% max error); both variants are reported")
    m.add_argument("--friction-method", choices=FRICTION_METHODS, help="how μ is identified from the barrel (compression; default fe_table: the CalculiX table; all are reported)")
    m.add_argument("--method", choices=("fast", "inverse-fe"), default="fast", help="fast (default; compression: FE tables, no solver at identification time) or inverse-fe (CalculiX in the loop: compression, the hardening law and μ fitted to the force-stroke curve and dmax; tension, the hardening beyond Fm fitted to the force-elongation curve and the neck diameter dk)")
    m.add_argument("--workers", type=int, metavar="N", help="inverse-fe: solver runs side by side (default: the cores)")
    m.add_argument("--time-limit", type=float, metavar="S", help="inverse-fe (compression and tension): wall-time budget, s; the fit ends by it with its "
                   "best answer so far, marked cut in result.json (default: compression 270, the held-out records end within 5 min on 2 cores; "
                   "tension 900, its bench records' longest run count at a loaded machine's rate)")
    m.add_argument("--scheduler", metavar="ADDRESS", help="send the records as tasks to this Dask distributed scheduler (needs the 'fe' extra); "
                   "inverse-fe solver runs stay with their record's task (--workers)")
    m.add_argument("--friction-correction", choices=FRICTION_CORRECTIONS, help="friction correction giving the reported true curve (compression; default fe_table: the CalculiX force factor; all are computed)")
    p.set_defaults(func=run)


def _pair(text: str) -> tuple[float, float]:
    """'LO,HI' → (lo, hi) for argparse (its error names the option)."""
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        return float(parts[0]), float(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not LO,HI (two numbers separated by a comma)") from None


def _modulus_window_options(window) -> dict:
    """--modulus-window LO,HI: fractions of Rm when both are ≤ 1, else MPa."""
    if window is None:
        return {}
    if max(window) <= 1.0:
        return {"modulus_window": window, "modulus_reference": "Rm"}
    return {"modulus_window_MPa": window}


def _meta_from_args(args) -> dict[str, str]:
    meta = {}
    for attr, key in META_OPTIONS.items():
        value = getattr(args, attr, None)
        if value is not None:
            meta[key] = repr(measurement(attr, value)) if isinstance(value, float) else str(value)
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or " " in key.strip():
            raise RecordError("--set", f"{item!r} is not KEY=VALUE (e.g. nominal_temperature_C=600)")
        meta[key.strip()] = value.strip()
    return meta


def _options_from_args(args) -> dict:
    return {
        "use_extensometer": False if args.no_extensometer else None,
        "neck": args.neck_correction,
        "hardening": HARDENING_CHOICES.get(args.hardening),
        "law": args.law,
        "friction_method": args.friction_method,
        "friction_correction": args.friction_correction,
        "E_MPa": None if args.E_MPa is None else measurement("E", args.E_MPa),
        "true_stress": args.true_stress,
        **_modulus_window_options(args.modulus_window),
        "modulus_method": args.modulus_method,
        "fit_range": args.fit_range,
        "fracture_point": args.fracture_point,
        "method": getattr(args, "method", "fast"),
        "workers": getattr(args, "workers", None),
        "time_limit": getattr(args, "time_limit", None),
    }


def _inverse_progress(runs, elapsed, left_s, limit_s) -> None:
    """The inverse FE's budget, one line on standard error."""
    from flowcurve.cli.progress import budget_text

    print(f"  inverse FE: {budget_text(runs, elapsed, left_s, limit_s=limit_s)}", file=sys.stderr, flush=True)


def _fmt(value, spec: str = ".4g") -> str:
    """A number as ``spec``; "—" for a missing or undetermined one (None, NaN)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return format(value, spec)
    return "—"


def _law_range_text(h: dict) -> str:
    """Where the law was fitted: εp lo–hi, and the fracture point when it lies beyond the uniform range
    (why 'flowcurve fit' on the same record, which has the uniform range only, gives another law)."""
    span, uniform = h.get("strain_range"), h.get("fit_range")
    if not (isinstance(span, list) and len(span) == 2):
        return ""
    text = f"; over εp {_fmt(span[0], '.3g')}–{_fmt(span[1], '.3g')}"
    if h.get("fracture_point") == "included" and isinstance(uniform, list) and len(uniform) == 2:
        text += f" (uniform range to {_fmt(uniform[1], '.3g')} + the fracture point)"
    return text


def summary_lines(result: dict) -> list[str]:
    """A short table of one result: strength figures, hardening constants, friction."""
    h = result.get("hardening") or {}
    from flowcurve.identification.elastic_modulus import result_E_source, result_material_E

    E_source = result_E_source(result)  # apparent: the diagram's slope, never handed to a card or an FE model
    E_note = E_source + (": the diagram's slope, not the material's E" if E_source == "apparent" else "")
    if E_source == "class":  # the rule's last step: say which class and how it was told
        E_note += f": {((result.get('methods') or {}).get('elastic_modulus') or {}).get('basis', 'the material class handbook value')}"
    E_material, material_source = result_material_E(result)
    if material_source != E_source and E_material is not None:
        E_note += f"; the material's E {_fmt(E_material, '.0f')} MPa is {material_source}"
    strength = f"  E {_fmt(result.get('E_MPa'), '.0f')} MPa ({E_note})   Rp0.2 {_fmt(result.get('Rp02_MPa'), '.1f')} MPa"
    if result.get("test") != "compression":  # Rm, Ag, A, Z are tension results
        strength += (f"   Rm {_fmt(result.get('Rm_MPa'), '.1f')} MPa   Ag {_fmt(result.get('Ag_pct'), '.2f')} %   "
                     f"A {_fmt(result.get('A_pct'), '.2f')} %   Z {_fmt(result.get('Z_pct'), '.1f')} %")
    lines = [strength]
    if result.get("ReH_MPa") is not None:
        lines.append(f"  yield point: ReH {_fmt(result['ReH_MPa'], '.1f')} MPa   ReL {_fmt(result.get('ReL_MPa'), '.1f')} MPa   "
                     f"Ae {_fmt(result.get('Ae_pct'), '.2f')} %")
    if h:
        consts = "   ".join(f"{k.removesuffix('_MPa')} {_fmt(h[k])}{' MPa' if k.endswith('_MPa') else ''}"
                           for k in h if f"{k}_stderr" in h)  # the law's constants, whichever law
        lines.append(f"  hardening {h.get('law', '?')} ({h.get('method', '?')}): {consts}   fit error {_fmt(h.get('fit_error_pct'), '.2f')} %"
                     + (f", quality {h['quality']}" if h.get("quality") else "") + _law_range_text(h))
        if h.get("law_choice"):
            from flowcurve.identification.laws.hardening import law_choice_text

            lines.append(f"  {law_choice_text(h['law_choice'])}")
    if result.get("test") == "compression":
        methods = result.get("friction") or {}
        extra = "   ".join(f"{k} {_fmt(v, '.3f')}" for k, v in methods.items() if isinstance(v, (int, float)))
        span = result.get("friction_mu_range")
        basis = (result.get("friction_details") or {}).get(result.get("friction_method"), {}).get("mu_range_basis", "dmax ± 0.01 mm")
        span = f" [{_fmt(span[0], '.3f')}–{_fmt(span[1], '.3f')} for {basis}]" if span else ""
        lines.append(f"  friction μ {_fmt(result.get('friction_mu'), '.3f')}{span}" + (f"   ({extra})" if extra else ""))
    inv = result.get("inverse_fe")
    if inv and result.get("test") == "tension":
        necks = ", ".join(f"{k} {v['vs_fe_pct']:+.1f} %" for k, v in inv["neck_corrections_vs_fe"].items())
        taper = inv.get("taper")
        lines.append(f"  inverse FE beyond ε_p {_fmt(inv.get('measured_to_true_plastic_strain'), '.3f')}: fracture stress "
                     f"{_fmt(inv['fracture_true_stress_MPa'], '.1f')} ± {_fmt(inv.get('fracture_true_stress_MPa_stderr'), '.1f')} MPa "
                     f"(closed-form neck corrections against it: {necks}), taper {_fmt(100.0 * taper if taper is not None else None, '.2f')} ± "
                     f"{_fmt(100.0 * inv['taper_stderr'] if inv.get('taper_stderr') is not None else None, '.2f')} %, "
                     f"{solver_runs_text(inv)}, {_fmt(inv['wall_s'], '.0f')} s, force residual rms {_fmt(inv['force_rms_residual_pct'], '.2f')} %, "
                     f"neck radius residual {_fmt(inv.get('neck_radius_residual_mm'), '+.4f')} mm")
    elif inv:
        lines.append(f"  inverse FE: μ {_fmt(inv['mu'], '.4f')} ± {_fmt(inv['mu_stderr'], '.4f')}, {solver_runs_text(inv)}, {_fmt(inv['wall_s'], '.0f')} s, "
                     f"force residual rms {_fmt(inv['force_rms_residual_pct'], '.2f')} %, dmax residual {_fmt(inv['dmax_residual_mm'], '+.4f')} mm")
    return lines


def solver_runs_text(inv: dict, noun: str = " solver runs") -> str:
    """"27 solver runs", how many of them did not converge and how many converged only when run again
    with a retry's settings (a result.json from before these counts: none said)."""
    failed, retried = inv.get("failed_solver_runs") or 0, inv.get("retried_solver_runs") or 0
    said = [f"{failed} did not converge"] * bool(failed) + [f"{retried} converged only when retried"] * bool(retried)
    said += ["cut by the time limit"] * bool((inv.get("budget") or {}).get("cut"))
    return f"{inv['solver_runs']}{noun}" + (f" ({', '.join(said)})" if said else "")


def _check_out(out: Path) -> None:
    """--out must be a folder (or not exist yet): a file there is a one-line error, before any work."""
    for folder in (out, *out.parents):
        if folder.exists():
            if not folder.is_dir():
                raise FlowcurveError(f"--out {out}: {'is' if folder == out else f'{folder} is'} a file, not a folder; choose another --out")
            if not os.access(folder, os.W_OK | os.X_OK):
                raise FlowcurveError(f"--out {out}: {folder} is not writable; choose another --out")
            return


def _givers(keys, table) -> list[str]:
    """The ways to give missing metadata ``keys`` on the command line: options and table columns."""
    options = {key: f"--{opt.replace('_', '-')}" for opt, key in META_OPTIONS.items()}
    named = [options[k] for k in keys if k in options]
    givers = [f"give {' or '.join(named)}"] if named else []
    if table is not None:
        from flowcurve.record.specimens import TABLE_COLUMNS

        columns = {key: name for name, (key, _) in TABLE_COLUMNS.items()}
        givers += [f"a column '{columns[k]}' in {table.source}" for k in keys if k in columns]
    return givers or ["give it with --set KEY=VALUE"]


def _check_table_against_options(table, meta: dict[str, str]) -> None:
    """A value given both by an option and by a --specimens column is an error: which is meant?"""
    options = {key: f"--{opt.replace('_', '-')}" for opt, key in META_OPTIONS.items()}
    for key in meta:
        if key in table.columns and any(key in row.meta for row in table.rows):
            raise RecordError(table.source, f"{options.get(key, '--set ' + key)} and this column both give '{key}'; keep one", column=table.columns[key])


def _record_meta(path: str, meta: dict[str, str], table) -> dict[str, str]:
    """The metadata of one record: its row of the --specimens table, and the options."""
    return meta if table is None else {**table.row_for(path).meta, **meta}


def run(args) -> int:
    """``flowcurve identify``: identify each record into a result folder; the exit status."""
    check_specimen_options(args)
    columns = None
    if args.column:  # the importers (numpy, pandas) only for a plain CSV: records that are current need neither
        from flowcurve.record.importers import parse_column_option

        columns = dict(parse_column_option(c) for c in args.column)
    meta = _meta_from_args(args)
    options = _options_from_args(args)
    out = Path(args.out)
    _check_out(out)
    table = None
    if args.specimens:
        from flowcurve.record.specimens import read_specimen_table

        table = read_specimen_table(args.specimens)
        _check_table_against_options(table, meta)
        for row in table.unused(args.records):
            print(f"flowcurve: warning: {table.source}, line {row.line}: '{row.file}' names none of the records given", file=sys.stderr)
    if args.jobs < 1:
        raise FlowcurveError(f"--jobs must be ≥ 1, got {args.jobs}")
    tasks = [{"path": path, "columns": columns, "meta": meta, "options": options, "out": str(out),
              "plots": not args.no_plots, "resume": not args.force, "table": table} for path in args.records]
    outcomes = []
    for outcome in _outcomes(tasks, args.jobs, args.scheduler):
        outcomes.append(outcome)
        _print_outcome(outcome)
    summary = write_summary_table(outcomes, out)
    failed = sum(o["status"] == "failed" for o in outcomes)
    skipped = sum(o["status"] == "skipped" for o in outcomes)
    if len(outcomes) > 1:
        print(f"{len(outcomes) - failed - skipped} identified, {skipped} skipped (current), {failed} failed; all results in {summary}")
    if failed:
        print(f"flowcurve: {failed} of {len(args.records)} record(s) failed", file=sys.stderr)
        return 2
    return 0


def _outcomes(tasks: list[dict], jobs: int, scheduler: str | None):
    """The outcome of every task (:func:`identify_task`) in the tasks' order: one after another
    here, or side by side in ``jobs`` processes or as tasks on the Dask ``scheduler``; a
    progress bar on standard error when there are several. Before any pool or cluster, the
    tasks that need no identification (:func:`outcome_without_work`) are decided here: only
    the others go there, and none → no pool."""
    from flowcurve.cli.progress import ProgressBar

    bar = ProgressBar(len(tasks)) if len(tasks) > 1 else None
    try:
        if scheduler is None and jobs == 1:
            for done, task in enumerate(tasks, start=1):
                outcome = identify_task(task)
                if bar:
                    bar.update(done)
                yield outcome
            return
        decided = [outcome_without_work(task) for task in tasks]
        work = [task for task, outcome in zip(tasks, decided) if outcome is None]
        if bar and len(work) < len(tasks):
            bar.update(len(tasks) - len(work))
        identified = iter(_run_in_parallel(work, jobs, scheduler, bar, len(tasks) - len(work)) if work else ())
        for outcome in decided:
            yield outcome if outcome is not None else next(identified)
    finally:
        if bar:
            bar.close()


def _run_in_parallel(tasks: list[dict], jobs: int, scheduler: str | None, bar, done_before: int) -> list[dict]:
    """identify_task over ``tasks`` in ``jobs`` processes or on the Dask ``scheduler``; the bar
    counts on from the ``done_before`` tasks decided without work."""
    from flowcurve.identification.fe.pool import run_many

    if scheduler is None:
        preload_identification(plots=any(task["plots"] for task in tasks))
    return run_many(identify_task, tasks, workers=jobs, scheduler=scheduler,
                    progress=(lambda done, _total, _elapsed: bar.update(done_before + done)) if bar else (lambda *_: None))


def preload_identification(plots: bool = False) -> None:
    """Import the identification and the libraries it imports on first use (lmfit alone takes
    3-5 s) before worker processes are forked: they inherit them instead of each importing them."""
    import lmfit  # noqa: F401

    import flowcurve.identification.identify  # noqa: F401

    if plots:
        import flowcurve.reports.plots  # noqa: F401


def identify_task(task: dict) -> dict:
    """One record of a batch, in this process, a worker process or a Dask worker: skipped when
    its result.json is current (:func:`identification.provenance.same_run`), else identified and
    written. Returns a picklable outcome (path, folder, status identified/skipped/failed, the
    result as JSON, the one-line error); bad input never raises."""
    return _task_outcome(task, work=True)


def outcome_without_work(task: dict) -> dict | None:
    """The outcome of a task decided without identifying its record: skipped (its result.json is
    current) or failed on its metadata; None when the record is to be identified."""
    return _task_outcome(task, work=False)


def _task_outcome(task: dict, *, work: bool) -> dict | None:
    """:func:`identify_task`; with ``work`` False, None where it would identify the record."""
    from flowcurve.identification.provenance import file_sha256

    path, out = task["path"], Path(task["out"])
    outcome = {"path": str(path), "folder": str(out / Path(path).stem), "status": "failed", "result": None, "error": None}
    try:
        sha = file_sha256(path)
    except OSError:
        sha = None  # load_record names what is wrong with the file
    try:
        meta = _record_meta(path, task["meta"], task["table"])
        if sha and task["resume"]:
            current = _current_result(Path(outcome["folder"]), sha, given_options(task["options"], meta, task["columns"]))
            if current is not None:
                return {**outcome, "status": "skipped", "result": current}
        if not work:
            return None
        ident, folder = identify(IdentifyRequest(path, out, columns=task["columns"], meta=meta, options=task["options"],
                                                 plots=task["plots"], record_sha256=sha), progress=_inverse_progress)
    except FlowcurveError as exc:
        message = exc.message_with(_givers(exc.keys, task["table"])) if isinstance(exc, MissingValueError) else str(exc)
        return {**outcome, "error": message if str(path) in message else f"{path}: {message}"}  # always name the file
    except Exception as exc:  # a bug, not bad input: one line per record, the others still run
        if os.environ.get("FLOWCURVE_DEBUG"):
            raise
        logger.debug("internal error on %s", path, exc_info=exc)
        return {**outcome, "error": f"internal error on {path}: {type(exc).__name__}: {exc} (-vv or FLOWCURVE_DEBUG=1 shows the "
                                    "traceback; please report it)"}
    from flowcurve.identification.outcome import to_jsonable  # numpy: not needed to skip a current record

    return {**outcome, "folder": str(folder), "status": "identified", "result": to_jsonable(ident.result)}


def _current_result(folder: Path, record_sha256: str, given: dict) -> dict | None:
    """result.json of ``folder`` when it was made by this flowcurve from the same record bytes
    with the same options (and its true curve is there), else None."""
    import json

    from flowcurve.identification.provenance import same_run

    try:
        result = json.loads((folder / "result.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(result, dict) or not (folder / "true_curve.csv").exists():
        return None
    return result if same_run(result.get("provenance"), record_sha256, given) else None


def _print_outcome(outcome: dict) -> None:
    path, result = outcome["path"], outcome["result"]
    if outcome["status"] == "failed":
        prefix = "flowcurve: " if outcome["error"].startswith("internal error") else "flowcurve: error: "
        print(prefix + outcome["error"], file=sys.stderr)
        return
    if outcome["status"] == "skipped":
        print(f"{path}: skipped, {outcome['folder']}/result.json is current (same flowcurve version and code, record SHA-256 and options)")
        return
    print(f"{path}: {result.get('test', '?')} → {outcome['folder']}")
    for line in summary_lines(result):
        print(line)
    for warning in result.get("warnings") or []:
        print(f"  warning: {warning}")


# the summary table: column (unit in its name) → where it is in result.json
SUMMARY_COLUMNS = {
    "test": ("test",), "E_MPa": ("E_MPa",), "Rp02_MPa": ("Rp02_MPa",), "ReH_MPa": ("ReH_MPa",), "ReL_MPa": ("ReL_MPa",),
    "Rm_MPa": ("Rm_MPa",), "Ag_pct": ("Ag_pct",), "A_pct": ("A_pct",), "Z_pct": ("Z_pct",),
    "fracture_true_stress_MPa": ("fracture_true_stress_MPa",), "friction_mu": ("friction_mu",),
    "friction_method": ("friction_method",), "hardening_law": ("hardening", "law"), "hardening_method": ("hardening", "method"),
    **{f"hardening_{k}": ("hardening", k) for k in ("A_MPa", "B_MPa", "n", "K_MPa", "eps0", "sigma0_MPa", "Q_MPa", "b",
                                                   "fit_error_pct", "quality")},
    "warnings": ("warnings",), "record_sha256": ("provenance", "record_sha256"),
    "flowcurve_version": ("provenance", "flowcurve_version"), "identified_utc": ("provenance", "date_utc"),
}


def write_summary_table(outcomes: list[dict], out: Path) -> Path:
    """DIR/summary.csv: one row per record (identified, skipped as current, or failed with its
    error), the main results with units in the column names."""
    import csv

    out.mkdir(parents=True, exist_ok=True)
    path = out / "summary.csv"
    with open(path, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(["record", "status", *SUMMARY_COLUMNS, "folder", "error"])
        for o in outcomes:
            values = []
            for keys in SUMMARY_COLUMNS.values():
                value = o["result"] or {}
                for key in keys:
                    value = value.get(key) if isinstance(value, dict) else None
                values.append(" | ".join(value) if isinstance(value, list) else "" if value is None else value)
            writer.writerow([o["path"], o["status"], *values, o["folder"] if o["status"] != "failed" else "", o["error"] or ""])
    return path
